"""The settling cost of select_graybox on a small first-order plant (the settle42c pathology).

SE iterates near an integrator (y coefficients summing to 1 − 1e-6) put the physical equilibrium just on its
unstable side and the only stable one far away, so settling runs creep for millions of steps. Prints the
wall and CPU (thread) time spent in ``settle_runs``, the whole call's, and the selection table (which must
not change). Run from the repository root with the project's environment:

    PYTHONPATH=. .venv/bin/python benchmarks/bench_settle_first_order.py
"""
import time
import warnings

import numpy as np

import graybox as gb
import graybox.static._analysis as A
from graybox.static._form_check import static_fit_mse


def first_order(seed: int, n: int = 600) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.5, 2.0, n // 20 + 1), 20)[:n]
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.7 * y[k - 1] + 0.2 * u[k - 1] + 0.05 * u[k - 1] ** 2
    return gb.Record(u, y + 0.002 * rng.standard_normal(n), name=f"first order {seed}")


def main() -> None:
    spent = [0.0, 0.0, 0]
    orig = A.settle_runs

    def timed(*a):
        t, c = time.perf_counter(), time.thread_time()
        out = orig(*a)
        spent[0] += time.perf_counter() - t
        spent[1] += time.thread_time() - c
        spent[2] += 1
        return out

    A.settle_runs = timed
    ub = np.linspace(0.5, 2.0, 8)
    yb = (0.2 * ub + 0.05 * ub ** 2) / 0.3 + 0.01 * ub ** 3
    static = gb.StaticPoints(ub, yb)
    band = static_fit_mse(static, 2) / 10
    data = gb.Dataset(first_order(1), first_order(2), static)
    warnings.simplefilter("ignore")
    t, c = time.perf_counter(), time.process_time()
    res = gb.select_graybox(gb.Candidates(ny=2, nu=2, degree=2), data, band=band, fallback="min_jsf")
    print(f"total {time.perf_counter() - t:.1f} s wall, {time.process_time() - c:.1f} s CPU; settle_runs "
          f"{spent[0]:.1f} s wall, {spent[1]:.1f} s CPU in {spent[2]} calls")
    print(res.table[["n_terms", "estimator", "JS_valid", "JSF", "in_band"]].to_string())


if __name__ == "__main__":
    main()
