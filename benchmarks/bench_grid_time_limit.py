"""What a cell time limit costs on Dask: the same grid on one LocalCluster without and with ``cell_time_limit``.

    .venv/bin/python benchmarks/bench_grid_time_limit.py [--workers 2] [--quick]

With a limit each Dask task runs its cells in a child process of its worker (stopped past the limit), so a task
pays that process's start-up (a Python and graybox's imports) on top of its cells. The grid is
``bench_grid.py``'s (200 cells of the bundled plant, 24 with ``--quick``); both runs on one cluster, after a
warm-up run of each kind; the figures of the two runs are compared cell by cell.
"""

from __future__ import annotations

import argparse
import datetime
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402
from bench_grid import grid, warm_up  # noqa: E402

from graybox import experiments as gx  # noqa: E402
from graybox.experiments._executors import local_cluster  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--quick", action="store_true", help="24 cells instead of 200")
    args = ap.parse_args()
    g = grid(args.quick)
    n = len(g.cells())
    print(f"# bench_grid_time_limit: {n} cells; {machine()}; git {git_rev()}; {datetime.datetime.now():%Y-%m-%d %H:%M}")
    from distributed import Client

    walls, frames = {}, {}
    with tempfile.TemporaryDirectory() as tmp, local_cluster(args.workers) as cluster, Client(cluster) as client:
        tmp = Path(tmp)
        for name, limit in (("no limit", None), ("cell_time_limit=600", 600.0)):
            gx.run_grid(warm_up(), tmp / f"warm-{limit}.sqlite", client=client, cell_time_limit=limit)
            t = time.perf_counter()
            run = gx.run_grid(g, tmp / f"{limit}.sqlite", client=client, cell_time_limit=limit)
            walls[name] = time.perf_counter() - t
            assert run.ran == n
            frames[name] = gx.load_results(tmp / f"{limit}.sqlite").set_index("key").sort_index()
    a, b = frames.values()
    same = all(np.array_equal(a[c].to_numpy(float), b[c].to_numpy(float), equal_nan=True)
               for c in ("JS_valid", "JSF", "J1_ident"))
    tasks = "tasks of several cells each (IN_FLIGHT batches)"
    for name, w in walls.items():
        print(f"{name}: {w:.2f} s for {n} cells on {args.workers} Dask workers ({tasks})")
    print(f"the limit's cost: {walls['cell_time_limit=600'] - walls['no limit']:+.2f} s; identical figures: {same}")


if __name__ == "__main__":
    main()
