"""The leaderboard and grid status of a large store (issue 24's reports, hunt38c's finding).

    .venv/bin/python benchmarks/bench_leaderboard.py [--structures 225] [--repeat 5] [--store PATH]

A grid of S random structures (4–9 terms from Candidates(3, 3, degree=2, max_y_power=1), seed 0, with
the constant, y(k−1) and u(k−1)) × 4 cheap variants (LS, CLS eq. (22), PE closed form with 8 λ, PE with
a static band) on the bundled plant: 4·S cells, run in process into a new SQLite store (or an existing
``--store``). Then the median wall time of R calls of ``leaderboard`` (D_SF with the stored band, the
rule "chosen", and a band no model meets, where every group takes the path that says why) and of
``grid_status``.
"""

from __future__ import annotations

import argparse
import datetime
import statistics
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import git_rev, machine  # noqa: E402

import graybox as gb  # noqa: E402
from graybox import experiments as gx  # noqa: E402


def grid(n_structures: int) -> gx.Grid:
    pool = [str(t) for t in gb.Candidates(3, 3, degree=2, max_y_power=1).terms]
    rng = np.random.default_rng(0)
    seen: set[tuple[str, ...]] = set()
    structures = []
    while len(structures) < n_structures:
        terms = tuple(sorted({"1", "y(k-1)", "u(k-1)", *rng.choice(pool, int(rng.integers(4, 10)), replace=False)}))
        if terms not in seen:
            seen.add(terms)
            structures.append(gx.StructureSpec(f"s{len(structures)}", terms=list(terms)))
    variants = [gx.Variant("LS", "ls"), gx.Variant("CLS", "cls", constraints=[{"type": "equality"}]),
                gx.Variant("PE", "pe", lambdas={"logspace": [-4, 0, 8]}, options={"solver": "closed"}),
                gx.Variant("PE band", "pe", lambdas={"logspace": [-3, 0, 4]},
                           constraints=[{"type": "band", "b": 0.175}])]
    return gx.Grid([gx.DataSpec("pumping", bundled="pumping")], structures, variants, name="leaderboard")


def median_time(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--structures", type=int, default=225)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--store", type=Path, default=None, help="an existing store to time (no grid is run)")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    print(f"bench_leaderboard.py: {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, "
          f"git {git_rev()}, {machine()}")
    with tempfile.TemporaryDirectory() as tmp:
        store = args.store
        if store is None:
            store = Path(tmp) / "leaderboard.sqlite"
            t0 = time.perf_counter()
            gx.run_grid(grid(args.structures), store, progress=False)
            print(f"grid run: {4 * args.structures} cells in {time.perf_counter() - t0:.1f} s")
        df = gb.load_results(store)
        gx.leaderboard(df)  # warm: imports, first pandas paths
        print("| call | cells | median wall (s) |\n| --- | ---: | ---: |")
        for label, fn in (("leaderboard (D_SF, stored band)", lambda: gx.leaderboard(df)),
                          ("leaderboard (rule 'chosen')", lambda: gx.leaderboard(df, rule="chosen")),
                          ("leaderboard (band 1e-4: no model qualifies)", lambda: gx.leaderboard(df, band=1e-4)),
                          ("grid_status", lambda: gx.grid_status(store))):
            print(f"| {label} | {len(df)} | {median_time(fn, args.repeat):.3f} |")


if __name__ == "__main__":
    main()
