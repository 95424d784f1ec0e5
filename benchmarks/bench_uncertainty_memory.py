"""Peak memory and time of the parameter uncertainties on a long record (hunt45b's changes).

    .venv/bin/python benchmarks/bench_uncertainty_memory.py [--n 200000]

Peak memory is tracemalloc's (numpy's arrays are traced), in multiples of the regressor matrix Ψ (N × n float64):
a figure the machine's load does not move. Times are one call each, after a warm-up (noisy on a shared machine).
Run it with PYTHONPATH on another checkout to compare.
"""

from __future__ import annotations

import argparse
import sys
import time
import tracemalloc
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402

import graybox as gb  # noqa: E402


def plant(n: int, seed: int = 0) -> tuple[gb.Record, gb.StaticPoints]:
    """A first-order rational plant with a staircase input and 2 % output noise; static points at 7 levels."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.5, 2.0, n // 50 + 1), 50)[:n]
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.6 * y[k - 1] + 0.3 * u[k - 1] + 0.05 * u[k - 1] ** 2 + 0.1
    y += 0.02 * np.std(y) * rng.standard_normal(n)
    ub = np.linspace(0.5, 2.0, 7)
    return gb.Record(u, y, name="plant"), gb.StaticPoints(ub, (0.3 * ub + 0.05 * ub ** 2 + 0.1) / 0.4,
                                                          uncertainty=0.01)


def measure(fn) -> tuple[float, float]:
    fn()  # warm-up: compilation, caches
    tracemalloc.start()
    t = time.perf_counter()
    fn()
    wall = time.perf_counter() - t
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak, wall


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=200_000)
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    rec, sp = plant(args.n)
    st = gb.parse_structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "y(k-2)", "u(k-2)"])
    psi = args.n * len(st) * 8
    print(f"# bench_uncertainty_memory (git {git_rev()}, graybox from {Path(gb.__file__).parent}): {machine()}")
    print(f"N = {args.n}, n = {len(st)} terms, Ψ = {psi / 2**20:.1f} MiB")
    model = gb.cls(st, rec).model  # no constraint: least squares
    front = gb.se_pareto(st, rec, sp, lambdas=[0.5], method="gradient", progress=False)
    se_model = gb.Model(st, front.thetas[0])
    rows = {
        "ls_uncertainty (LS)": lambda: gb.ls_uncertainty(model, rec),
        "se_uncertainty (λ1 = 0.5)": lambda: gb.se_uncertainty(se_model, rec, sp, lambda1=0.5),
    }
    print("| call | peak traced memory | in Ψ | wall |")
    print("|:--|--:|--:|--:|")
    for name, fn in rows.items():
        try:
            peak, wall = measure(fn)
            print(f"| {name} | {peak / 2**20:.0f} MiB | {peak / psi:.2f} | {wall:.2f} s |", flush=True)
        except Exception as exc:  # an older checkout without a function or option
            print(f"| {name} | {type(exc).__name__}: {str(exc)[:80]} | | |", flush=True)


if __name__ == "__main__":
    main()
