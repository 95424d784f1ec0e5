"""FROLS on long records: time and peak memory against the record length N (issue 14).

    .venv/bin/python benchmarks/bench_frols_long.py [--sizes 1e4 1e5 1e6] [--repeat 3]

Task: records of N samples from the bundled plant simulator
(``PumpingPlant().simulate(speed_reference(n_samples=N, n_ident=N // 2, seed=0), seed=0)``, the
whole record used for identification), ny = nu = 6, degree 2 (91 candidates -> 17 terms) and
degree 3 (455 candidates -> 23 terms), a fixed number of terms, ``method`` as given (default: the
library's default). Each size runs in a fresh subprocess (one process per size, so the peak is
that size's own): the time is the minimum of ``--repeat`` calls below 5 s (one call above) after
a warm-up (and the CPU time of the same calls: with one BLAS thread, the default, it is the
figure least disturbed by other work on the machine); the peak is ``tracemalloc``'s over one extra call (Python and numpy allocations, over
what the record itself holds) and the subprocess's ``ru_maxrss``.

The records are simulated once and cached in ``--cache`` (``.npz``), so a run against another
checkout of graybox (``PYTHONPATH=/path/to/old/checkout``, e.g. ``git archive c6f5ffe``) times
the same data: ``--method ""`` then calls ``frols`` without the ``method`` keyword.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
import tracemalloc
import warnings
from pathlib import Path

import numpy as np

TASKS = ((2, 17), (3, 23))


def record_path(cache: Path, n: int) -> Path:
    return cache / f"plant_{n}.npz"


def make_record(cache: Path, n: int) -> Path:
    p = record_path(cache, n)
    if not p.exists():
        from graybox.datasets.pumping import PumpingPlant, speed_reference

        run = PumpingPlant().simulate(speed_reference(n_samples=n, n_ident=n // 2, seed=0), seed=0)
        cache.mkdir(parents=True, exist_ok=True)
        np.savez(p, u=np.asarray(run.u, float), y=np.asarray(run.y, float))
    return p


def one_size(path: str, degree: int, k: int, repeat: int, method: str, dask_blocks: int = 0) -> dict:
    import graybox
    from graybox import Candidates, Record
    from graybox.selection._forward_regression import frols

    d = np.load(path)
    rec = Record(d["u"], d["y"], Ts=0.05)
    cand = Candidates(6, 6, ne=0, degree=degree)
    if dask_blocks:
        # the record as Dask arrays, reduced on a 2-worker LocalCluster: the driver never holds Ψ
        import dask.array as da
        from distributed import Client, LocalCluster

        cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
        Client(cluster)
        step = -(-len(rec) // dask_blocks)
        rec = graybox.DaskRecord(da.from_array(rec.u, chunks=step), da.from_array(rec.y, chunks=step), Ts=0.05)
    kw = {"n_terms": k} | ({"method": method} if method else {})

    def call():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return frols(cand, rec, **kw)

    sel = call()  # warm-up
    times, cpus = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        call()
        times.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
        if times[-1] > 5.0:
            break
    tracemalloc.start()
    call()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return {
        "N": len(rec), "degree": degree, "dask_blocks": dask_blocks, "candidates": len(cand), "terms": k, "time_s": min(times), "cpu_s": min(cpus),
        "peak_MiB": peak / 2**20, "maxrss_MiB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "matrix_MiB": 8 * sel.n_rows * len(cand) / 2**20, "selected": [str(t) for t in sel.structure],
        "graybox": str(Path(graybox.__file__).parent),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=float, nargs="+", default=[1e4, 1e5, 1e6])
    ap.add_argument("--degrees", type=int, nargs="+", default=[2, 3])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--method", default="auto", help='frols method; "" to omit the keyword (old checkouts)')
    ap.add_argument("--cache", type=Path, default=Path("/tmp/graybox_bench_records"))
    ap.add_argument("--blas-threads", type=int, default=1,
                    help="BLAS/OpenMP threads of each run (1: steady figures on a shared machine)")
    ap.add_argument("--json", type=Path, help="append the rows to this JSON-lines file")
    ap.add_argument("--dask", type=int, default=0, metavar="BLOCKS",
                    help="run on the record as a DaskRecord of BLOCKS blocks on a 2-worker LocalCluster "
                         "(time and driver memory; needs dask[distributed])")
    ap.add_argument("--child", nargs=3, metavar=("PATH", "DEGREE", "K"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        p, deg, k = args.child
        print(json.dumps(one_size(p, int(deg), int(k), args.repeat, args.method, args.dask)))
        return
    sys.path.insert(0, str(Path(__file__).parent))
    from _common import git_rev, machine

    print(f"# bench_frols_long  {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}  git {git_rev()}  {machine()}")
    print(f"# method={args.method!r}, dask blocks {args.dask or '-'}, BLAS threads {args.blas_threads}, PYTHONPATH={os.environ.get('PYTHONPATH', '')!r}")
    print(f"{'N':>9} {'deg':>3} {'cand':>5} {'terms':>5} {'time':>9} {'CPU':>9} {'peak':>11} {'maxrss':>11} "
          f"{'Ψ size':>11}")
    prev: dict[int, dict] = {}
    for n in [int(s) for s in args.sizes]:
        path = make_record(args.cache, n)
        for degree, k in TASKS:
            if degree not in args.degrees:
                continue
            cmd = [sys.executable, __file__, "--child", str(path), str(degree), str(k), "--repeat", str(args.repeat),
                   "--method", args.method, "--dask", str(args.dask)]
            env = os.environ | {v: str(args.blas_threads) for v in
                                ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")}
            out = subprocess.run(cmd, capture_output=True, text=True, env=env)
            if out.returncode:
                print(f"{n:>9} {degree:>3} failed: {out.stderr.strip().splitlines()[-1] if out.stderr else out.returncode}")
                continue
            row = json.loads(out.stdout.strip().splitlines()[-1])
            growth = ""
            if degree in prev:
                a = prev[degree]
                growth = f"  growth N^{np.log(row['time_s'] / a['time_s']) / np.log(row['N'] / a['N']):.2f}"
            prev[degree] = row
            print(f"{row['N']:>9} {degree:>3} {row['candidates']:>5} {k:>5} {row['time_s']:8.3f}s {row['cpu_s']:8.3f}s "
                  f"{row['peak_MiB']:8.1f}MiB {row['maxrss_MiB']:8.1f}MiB {row['matrix_MiB']:8.1f}MiB{growth}")
            if args.json:
                with open(args.json, "a") as fh:
                    fh.write(json.dumps(row | {"method": args.method}) + "\n")


if __name__ == "__main__":
    main()
