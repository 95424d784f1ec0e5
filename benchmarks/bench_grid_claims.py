"""Two runs on one store: what the cells' claims cost, and two real drivers sharing a grid.

    .venv/bin/python benchmarks/bench_grid_claims.py [--cells 10000] [--writes 2000]

1. Bookkeeping: a grid of N cells (a GA variant over many seeds, so that keys are cheap to make), its
   store opened; one claim of every key, ``grid status`` (which reads the claims), and W rows written
   (failed rows: no cell is run) with the claims in force against a store no run claimed (before claims,
   every write was the latter); then what a run now does for each cell before it starts it
   (``run_grid``'s take: its row looked for, the key claimed, looked for again), W keys one at a time.
2. bench_grid_growth's 48-cell grid (12 structures × LS, CLS, PE, PE with a band) run by one driver
   (``graybox grid run``, in-process), then by two drivers started together on a fresh store: the cells each
   ran (before claims: each ran all of them; with every cell claimed at a run's start: 0 + 48) and the wall
   time until both end.
"""

from __future__ import annotations

import argparse
import datetime
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import git_rev, machine  # noqa: E402
from bench_grid_growth import grids  # noqa: E402

import graybox as gb  # noqa: E402
from graybox import experiments as gx  # noqa: E402
from graybox.experiments._cell import failed_row  # noqa: E402
from graybox.experiments._run import _Share  # noqa: E402
from graybox.experiments._store import ResultStore  # noqa: E402


class _NoBar:
    def update(self, n: int) -> None:
        pass


def bookkeeping(n_cells: int, writes: int, tmp: Path) -> None:
    g = gx.Grid([gx.DataSpec("pumping", bundled="pumping")],
                [gx.StructureSpec("a", terms=["y(k-1)", "u(k-1)", "1"])],
                [gx.Variant("GA", "se-ga", lambdas=[0.5, 1.0], options={"population": 20, "generations": 2})],
                seeds=list(range(n_cells)), name="claims")
    t0 = time.perf_counter()
    cells = g.cells(g.load_data())
    t_cells = time.perf_counter() - t0
    rows = {}
    for label, claim in (("claimed", True), ("not claimed", False)):
        path = tmp / f"{label.replace(' ', '_')}.sqlite"
        st = ResultStore.open(path, grid_name=g.name, fingerprint=g.fingerprint(cells), spec=g.to_dict(), cells=cells,
                              version=gb.__version__)
        try:
            t_claim = float("nan")
            if claim:
                t0 = time.perf_counter()
                held = st.claim([c.key for c in cells])
                t_claim = time.perf_counter() - t0
                assert held == {}
                t0 = time.perf_counter()
                running = gx.grid_status(path).running
                t_status = time.perf_counter() - t0
                assert sum(running.values()) == len(cells)
            t0 = time.perf_counter()
            for c in cells[:writes]:
                st.write(failed_row(c, "bench"))
            t_write = (time.perf_counter() - t0) / writes
            t_take = float("nan")
            if not claim:  # the unwritten cells, taken one at a time as run_grid now takes them
                share = _Share(st, st.marks(), _NoBar())
                left = cells[writes:2 * writes]
                t0 = time.perf_counter()
                for c in left:
                    assert share.take([c]) == [c]
                t_take = (time.perf_counter() - t0) / len(left)
        finally:
            st.close()
        rows[label] = (t_claim, t_status if claim else float("nan"), t_write, t_take)
    print(f"\n{len(cells)} cells (made in {t_cells:.2f} s); {writes} rows written, {writes} cells taken one by one\n")
    print("| store | claim every key | grid status | one row written | one cell taken (run_grid's take) |")
    print("| --- | --- | --- | --- | --- |")
    for label, (a, b, c, d) in rows.items():
        f = (lambda x: "–" if x != x else f"{x:.3f} s")
        g = (lambda x: "–" if x != x else f"{x * 1e3:.2f} ms")
        print(f"| {label} | {f(a)} | {f(b)} | {g(c)} | {g(d)} |")


def two_drivers(tmp: Path) -> None:
    n = len(grids(12)[0].cells())
    code = (f"import sys; sys.path.insert(0, {str(Path(__file__).resolve().parent)!r})\n"
            "from bench_grid_growth import grids\nfrom graybox import experiments as gx\n"
            "print(gx.run_grid(grids(12)[0], sys.argv[1]).ran, 'run now')\n")
    cmd = [sys.executable, "-c", code]
    t0 = time.perf_counter()
    one = subprocess.run(cmd + [str(tmp / "one.sqlite")], capture_output=True, text=True, check=True)
    t_one = time.perf_counter() - t0
    t0 = time.perf_counter()
    procs = [subprocess.Popen(cmd + [str(tmp / "two.sqlite")], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True) for _ in range(2)]
    outs = [p.communicate() for p in procs]
    t_two = time.perf_counter() - t0
    assert all(p.returncode == 0 for p in procs), outs
    ran = [int(re.search(r"(\d+) run now", o).group(1)) for o, _ in outs]
    ran_one = int(re.search(r"(\d+) run now", one.stdout).group(1))
    assert len(gx.load_results(tmp / "two.sqlite")) == n
    print(f"\n{n} cells, in-process drivers (each process imports graybox and loads the data first)\n")
    print("| drivers | cells each ran | wall time until all end |")
    print("| --- | --- | --- |")
    print(f"| one | {ran_one} | {t_one:.1f} s |")
    print(f"| two, started together | {' + '.join(map(str, ran))} | {t_two:.1f} s |")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cells", type=int, default=10000)
    ap.add_argument("--writes", type=int, default=2000)
    args = ap.parse_args()
    print(f"# bench_grid_claims ({datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, git {git_rev()}): "
          f"{machine()}")
    with tempfile.TemporaryDirectory() as d:
        bookkeeping(args.cells, args.writes, Path(d))
        two_drivers(Path(d))


if __name__ == "__main__":
    main()
