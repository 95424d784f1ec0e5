"""A store that grows (issue 24): what growing costs against running the grid again, and what the
bookkeeping of a growing store (registering a spec, reading its cells, status, the HTML report) adds.

    .venv/bin/python benchmarks/bench_grid_growth.py [--structures 12] [--repeat 3]

Bundled pumping plant; S given structures (first to third order, 4–9 terms) × 4 cheap variants (LS,
CLS eq. (22), PE closed form with 8 λ, PE with a static band): 4·S cells in-process. Then one
variant more (PE with 16 λ) is added: the grown spec run on a copy of the finished store runs only its S
cells; the same grown grid into a new store runs all 5·S. Reported: wall times (median of R) of
the first run, the growth, the full rerun; the same spec run again on the finished store (nothing
runs: open, key, register, count); load_results of one spec and of all; grid_status; write_report
with and without html.
"""

from __future__ import annotations

import argparse
import datetime
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import git_rev, machine  # noqa: E402

from graybox import experiments as gx  # noqa: E402

TERMS = ["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "1", "y(k-2)", "u(k-2)", "u(k-1)^2", "u(k-2)y(k-1)", "y(k-3)"]


def grids(n_structures: int) -> tuple[gx.Grid, gx.Grid]:
    structures = []
    for i in range(n_structures):
        k = 4 + i % 6  # 4…9 terms
        terms = TERMS[:k] if i < 6 else [t for t in TERMS[:k] if t != "u(k-1)y(k-1)"] + ["u(k-2)^2"]
        structures.append(gx.StructureSpec(f"s{i}", terms=terms))
    variants = [gx.Variant("LS", "ls"), gx.Variant("CLS", "cls", constraints=[{"type": "equality"}]),
                gx.Variant("PE", "pe", lambdas={"logspace": [-4, 0, 8]}, options={"solver": "closed"}),
                gx.Variant("PE band", "pe", lambdas={"logspace": [-3, 0, 4]}, constraints=[{"type": "band", "b": 0.175}])]
    data = [gx.DataSpec("pumping", bundled="pumping")]
    base = gx.Grid(data, structures, variants, name="growth")
    more = gx.Variant("PE 16", "pe", lambdas={"logspace": [-4, 0, 16]}, options={"solver": "closed"})
    return base, gx.Grid(data, structures, variants + [more], name="growth")


def timed(fn) -> tuple[float, object]:
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--structures", type=int, default=12)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    base, grown = grids(args.structures)
    results: dict[str, list[float]] = {}
    counts: dict[str, int] = {}
    tmp = Path(tempfile.mkdtemp(prefix="bench-growth-"))
    gx.run_grid(grids(2)[0], tmp / "warm.sqlite")  # JIT, imports
    try:
        for r in range(args.repeat):
            d = tmp / f"r{r}"
            d.mkdir()
            for label, g, store, start in (("first run (base spec, new store)", base, "base", None),
                                           ("same spec again (nothing runs)", base, "base", None),
                                           ("grown spec on the finished store", grown, "grown", "base"),
                                           ("grown spec into a new store", grown, "fresh", None)):
                if start is not None:
                    shutil.copy(d / f"{start}.sqlite", d / f"{store}.sqlite")
                t, run = timed(lambda: gx.run_grid(g, d / f"{store}.sqlite"))
                results.setdefault(label, []).append(t)
                counts[label] = run.ran
            for label, fn in (("load_results (latest spec)", lambda: gx.load_results(d / "grown.sqlite")),
                              ("load_results (spec='all')", lambda: gx.load_results(d / "grown.sqlite", spec="all")),
                              ("grid_status", lambda: gx.grid_status(d / "grown.sqlite")),
                              ("write_report (CSV, PNG)", lambda: gx.write_report(d / "grown.sqlite", d / "rep")),
                              ("write_report (… and html)",
                               lambda: gx.write_report(d / "grown.sqlite", d / "rep_html", html=True))):
                results.setdefault(label, []).append(timed(fn)[0])
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print(f"## A store that grows (`bench_grid_growth.py --structures {args.structures} --repeat {args.repeat}`, "
          f"git {git_rev()}, {datetime.date.today()})\n")
    print(f"{machine()}; {4 * args.structures} cells in the base spec, {5 * args.structures} in the grown one; "
          "in-process; median of the repeats (a shared machine: noisy)\n")
    print("| step | cells run | wall (s) |\n|---|---:|---:|")
    for label, ts in results.items():
        print(f"| {label} | {counts.get(label, '')} | {statistics.median(ts):.3f} |")


if __name__ == "__main__":
    main()
