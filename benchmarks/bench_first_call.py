"""The first se_dsf of a fresh process against a warm one: what the numba cache saves.

Each measurement runs in a new Python process (``python -c``), so nothing compiled or imported
by an earlier run is in memory. Three settings:

- ``cold``: an empty numba cache directory (``NUMBA_CACHE_DIR`` pointed at a new folder): every
  kernel compiles, as on the very first run after an install;
- ``cached``: the same folder after the cold run filled it: kernels load from disk;
- ``cached, numba started``: as ``cached``, with one 10-sample free run before the timed call, so
  numba's one-off start-up in a process (its typing and target contexts) is timed apart;
- in each process, after the first call, the same call again: ``warm`` (nothing left to load).

Wall and process CPU time are both printed: on a machine other jobs load, the CPU time ratio is
the steadier figure.

Imports are timed apart: ``import graybox`` (lazy, light) and the first access of ``gb.se_dsf``
(the estimation modules and their numpy, scipy, numba and pandas). The data are made with numpy
alone, so the first call pays for loading (or compiling) every kernel it uses.

The problem is small on purpose (a 6-term structure, 600 + 200 samples, 6 static points, 5 λ1 in
the start sweep) so that compilation and loading, not the optimisation, dominate a first call.
``--case plant`` times instead the README's size of problem: the bundled plant, the paper's
structure (15), the points' own band, the default sweep. The issue's target: first call with a
filled cache within 2x of a warm call.

    python benchmarks/bench_first_call.py [--rounds 3] [--case small|plant]
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402

CHILD = r"""
import json, os, time
t0 = time.perf_counter()
import numpy as np
import graybox as gb
t_import = time.perf_counter() - t0
t0 = time.perf_counter()
se_dsf = gb.se_dsf  # the lazy import of the estimation modules (numpy, scipy, numba, pandas)
t_modules = time.perf_counter() - t0
# data made with numpy alone, so that no graybox kernel is loaded before the timed call
if os.environ.get("GB_BENCH_CASE") == "plant":
    # the bundled plant with the paper's structure (15) and the points' own band: a problem of the
    # size the README runs (loading the data uses no graybox kernel)
    from graybox.reference import STRUCTURE_15 as st
    data = gb.load_pumping()
    band, lam = data.static.band, None
else:
    band, lam, st, data = None, None, None, None
rng = np.random.default_rng(4)
u = np.repeat(rng.uniform(0.0, 3.0, 40), 20)
y = np.zeros(u.size)
for k in range(2, u.size):
    y[k] = 0.6 * y[k-1] + 0.2 * y[k-2] + 0.3 * u[k-1] + 0.05 * u[k-2] ** 2 - 0.02 * u[k-1] * y[k-1] + 0.4
y += 0.05 * rng.standard_normal(u.size)
ub = np.linspace(0.3, 2.8, 6)
yb = (0.4 + 0.3 * ub + 0.05 * ub ** 2) / (0.2 + 0.02 * ub)  # the system's static function
if data is None:
    st = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2", "u(k-1)y(k-1)", "1"])
    data = gb.Dataset(gb.Record(u[:600], y[:600]), gb.Record(u[600:], y[600:]),
                      gb.StaticPoints(ub, yb + 0.3 * np.sin(ub)))
    band, lam = 0.02, np.logspace(-2, 0, 5)
t_start = float("nan")
if os.environ.get("GB_BENCH_START_NUMBA"):
    # one free run of 20 samples first: numba's one-off start-up (typing and target contexts, loading
    # the first kernel), timed apart from se_dsf
    t = time.perf_counter()
    gb.Model(st, np.zeros(len(st))).simulate(u[:20], np.zeros(st.max_lag))
    t_start = time.perf_counter() - t
times, cpu = [], []
for _ in range(3):
    t, c = time.perf_counter(), time.process_time()
    res = se_dsf(st, data, band=band, **({} if lam is None else {"lambdas": lam}))
    times.append(time.perf_counter() - t)
    cpu.append(time.process_time() - c)
print(json.dumps({"import": t_import, "modules": t_modules, "start": t_start, "first": times[0],
                  "warm": min(times[1:]), "first_cpu": cpu[0], "warm_cpu": min(cpu[1:]), "JS": res.JS}))
"""


def child(cache: str, start_numba: bool = False, case: str = "small") -> dict:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache, GB_BENCH_START_NUMBA="1" if start_numba else "", GB_BENCH_CASE=case)
    out = subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=3, help="fresh processes per setting")
    ap.add_argument("--case", choices=("small", "plant"), default="small",
                    help="small: the 6-term synthetic problem; plant: the bundled plant, structure (15)")
    args = ap.parse_args()
    print(f"case: {args.case}")
    print(f"# {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC, {machine()}, git {git_rev()}")
    rows = {"cold": [], "cached": [], "cached, numba started": []}
    for _ in range(args.rounds):
        with tempfile.TemporaryDirectory() as cache:
            rows["cold"].append(child(cache, case=args.case))    # compiles everything into the empty cache
            rows["cached"].append(child(cache, case=args.case))  # a new process: loads what the cold one wrote
            rows["cached, numba started"].append(child(cache, start_numba=True, case=args.case))
    for name, rs in rows.items():
        first = statistics.median(r["first"] for r in rs)
        warm = statistics.median(r["warm"] for r in rs)
        imp = statistics.median(r["import"] for r in rs)
        mods = statistics.median(r["modules"] for r in rs)
        start = statistics.median(r["start"] for r in rs)
        fc, wc = statistics.median(r["first_cpu"] for r in rs), statistics.median(r["warm_cpu"] for r in rs)
        started = "" if start != start else f", numba start-up (20-sample free run) {start:.2f} s"
        print(f"{name}: import graybox {imp:.3f} s, gb.se_dsf (modules) {mods:.2f} s{started}; se_dsf first call "
              f"{first:.3f} s, warm {warm:.3f} s: first/warm {first / warm:.2f}x; CPU time {fc:.3f} s against "
              f"{wc:.3f} s: {fc / wc:.2f}x (median of {len(rs)} processes)")
    assert len({round(r["JS"], 12) for rs in rows.values() for r in rs}) == 1, "every process gives the same J_S"


if __name__ == "__main__":
    main()
