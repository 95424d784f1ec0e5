"""A run taking over another run's cells: what its executor costs after the wait.

    .venv/bin/python benchmarks/bench_grid_takeover.py [--repeat 3] [--structures 4]

Another run (this process, a store connection of its own) holds half the cells of bench_grid_growth's grid
(``--structures`` structures × LS, CLS, PE, PE with a band) or all of them; the run under test (``run_grid``,
Dask ``LocalCluster`` of 2 workers, or 2 local processes) runs the rest, says it waits, and the other run then
stops without running its cells, so the run under test takes them over. Timed: the run's wall time, and the
seconds from the other run's stop to the run's return (the take-over); counted: the ``LocalCluster``s and worker
processes the run started. Also a ``LocalCluster`` of 2 workers started and closed alone.
"""

from __future__ import annotations

import argparse
import datetime
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import git_rev, machine  # noqa: E402
from bench_grid_growth import grids  # noqa: E402

import graybox as gb  # noqa: E402
from graybox import experiments as gx  # noqa: E402
from graybox.experiments import _executors  # noqa: E402
from graybox.experiments._store import ResultStore  # noqa: E402


def shared_run(g, store: Path, held_share: float, executor: str) -> tuple[float, float, int, int]:
    """(wall time of the run, seconds from the other run's stop to the run's return, LocalClusters started,
    worker processes started)."""
    cells = g.cells(g.load_data())
    other = ResultStore.open(store, grid_name=g.name, fingerprint=g.fingerprint(cells), spec=g.to_dict(),
                             cells=cells, version=gb.__version__)
    held = cells[int(len(cells) * (1 - held_share)):]
    assert other.claim([c.key for c in held]) == {}
    clusters, procs = [], []
    real_cluster, real_start = _executors.local_cluster, _executors.ProcessPool._start

    def counting_cluster(workers, dashboard=False):
        clusters.append(workers)
        return real_cluster(workers, dashboard)

    def counting_start(self):
        procs.append(1)
        return real_start(self)

    _executors.local_cluster, _executors.ProcessPool._start = counting_cluster, counting_start
    lines, out = [], {}

    def target():
        out["run"] = gx.run_grid(g, store, executor=executor, workers=2, log=lines.append)
        out["end"] = time.perf_counter()

    try:
        t = threading.Thread(target=target)
        t.start()
        while not any("waits for them" in x for x in lines):
            if not t.is_alive():
                raise RuntimeError(f"the run ended without waiting: {lines}")
            time.sleep(0.01)
        t_release = time.perf_counter()
        other.close()
        t.join()
    finally:
        _executors.local_cluster, _executors.ProcessPool._start = real_cluster, real_start
    run = out["run"]
    assert run.ran == len(cells), run.summary()
    return run.wall_time, out["end"] - t_release, len(clusters), len(procs)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--structures", type=int, default=4)
    args = ap.parse_args()
    g = grids(args.structures)[0]
    tmp = Path(tempfile.mkdtemp(prefix="bench-takeover-"))
    print(f"# {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, git {git_rev()}, {machine()}")
    print(f"# grid: {len(g.cells(g.load_data()))} cells")
    gx.run_grid(grids(1)[0], tmp / "warm.sqlite")  # JIT, imports
    t = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        with _executors.local_cluster(2):
            pass
        t.append(time.perf_counter() - t0)
    print(f"LocalCluster(2) started and closed alone: median {statistics.median(t):.2f} s "
          f"({', '.join(f'{x:.2f}' for x in t)})")
    n = 0
    for executor, share in (("dask", 0.5), ("dask", 1.0), ("processes", 0.5)):
        rows = []
        for _ in range(args.repeat):
            n += 1
            rows.append(shared_run(g, tmp / f"s{n}.sqlite", share, executor))
        wall, after, clusters, procs = zip(*rows)
        print(f"{executor}, other run holds {share:.0%}: run {statistics.median(wall):.2f} s "
              f"({', '.join(f'{x:.2f}' for x in wall)}), take-over {statistics.median(after):.2f} s "
              f"({', '.join(f'{x:.2f}' for x in after)}); LocalClusters started {clusters}, "
              f"worker processes started {procs}")


if __name__ == "__main__":
    main()
