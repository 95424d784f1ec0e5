"""Free-run simulation speed: graybox's compiled kernels vs SysIdentPy.

Run with the benchmark environment (SysIdentPy is not a project dependency):

    python3 -m venv benchmarks/.env && benchmarks/.env/bin/pip install -e . sysidentpy
    benchmarks/.env/bin/python benchmarks/bench_simulate.py

Model (15) of the paper (Table II, ELS column), 3200 samples of a step input in rpm.
Throughput counts term-evaluations: one term of one model at one sample.
"""

from __future__ import annotations

import datetime
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import machine, sysidentpy_code, timeit  # noqa: E402

from graybox import Record, reference, simulate_many  # noqa: E402

N = 3200
P = 200


def main() -> None:
    rng = np.random.default_rng(0)
    m = reference.paper_model(15)
    u = np.repeat(rng.uniform(750, 1650, N // 80 + 1), 80)[:N]
    y0 = np.full(m.max_lag, float(m.static_curve([u[0]])[0]))
    rec = Record(u, m.simulate(u, y0), Ts=0.05)
    thetas = m.theta * (1 + 0.002 * rng.standard_normal((P, m.n_params)))
    T = m.n_params
    print(f"# bench_simulate  {datetime.date.today()}  {machine()}")

    t_one = timeit(lambda: m.simulate(rec), repeat=15, number=20)
    t_b1 = timeit(lambda: simulate_many(m.structure, thetas, rec, threads=1), repeat=9, number=3)
    t_b2 = timeit(lambda: simulate_many(m.structure, thetas, rec, threads=2), repeat=9, number=3)
    evals = (N - m.max_lag) * T
    rows = [
        ("graybox single free run", t_one, evals / t_one),
        (f"graybox batch of {P}, 1 thread", t_b1, P * evals / t_b1),
        (f"graybox batch of {P}, 2 threads", t_b2, P * evals / t_b2),
    ]
    try:
        from sysidentpy.basis_function import Polynomial
        from sysidentpy.simulation import SimulateNARMAX

        code = sysidentpy_code(m.structure)
        sim = SimulateNARMAX(basis_function=Polynomial(degree=2), estimate_parameter=False, model_type="NARMAX")
        X, Y = u.reshape(-1, 1), rec.y.reshape(-1, 1)
        # SysIdentPy reorders the terms; map our θ onto its final_model order
        sim.simulate(X_test=X, y_test=Y, model_code=code, theta=np.zeros((T, 1)))
        order = [next(i for i, c in enumerate(code) if sorted(c) == sorted(f)) for f in sim.final_model]
        theta_s = m.theta[order].reshape(-1, 1)
        ys = sim.simulate(X_test=X, y_test=Y, model_code=code, theta=theta_s).ravel()
        err = np.max(np.abs(ys[m.max_lag:] - rec.y[m.max_lag:]))
        t_s = timeit(lambda: sim.simulate(X_test=X, y_test=Y, model_code=code, theta=theta_s), repeat=5)
        import sysidentpy

        rows.append((f"SysIdentPy {sysidentpy.__version__} SimulateNARMAX (max |Δy| vs graybox {err:.1e})", t_s, evals / t_s))
    except ImportError as exc:
        print(f"SysIdentPy not available ({exc}); install it in the benchmark environment")
        t_s = None
    print(f"{'case':60s} {'time':>12s} {'term-evals/s':>14s}")
    for name, t, r in rows:
        print(f"{name:60s} {t * 1e3:9.3f} ms {r:14.3e}")
    if t_s is not None:
        print(f"single free run speed-up over SysIdentPy: {t_s / t_one:.0f}x")


if __name__ == "__main__":
    main()
