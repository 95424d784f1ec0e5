"""graybox against its peers by CPU time, for a machine other jobs share.

    python3 -m venv /tmp/peers && /tmp/peers/bin/pip install -e . sysidentpy   # never graybox's environment
    /tmp/peers/bin/python benchmarks/bench_peers_cpu.py [--rounds 15]

Wall-clock medians (``bench_simulate.py``, ``bench_frols.py``, ``bench_convex.py``) follow the machine's load: at
load 10–20 on 2 vCPUs they moved 3–30x between runs minutes apart, and a peer using BLAS threads suffered more than
graybox's single-threaded kernels, so their ratios were not comparable either. Here every case runs on one BLAS
thread and is timed by this thread's CPU time (``time.thread_time``), the best of ``--rounds`` rounds with the cases
alternated, so both sides of a ratio meet the same load. The same cases as those scripts: model (15)'s free run
(3200 samples) and a batch of 200 against SysIdentPy's ``SimulateNARMAX``; FROLS at degrees 2 and 3 against
SysIdentPy's ``FROLS``; the 100-λ PE sweep in closed form and ``pe_pareto`` against SysIdentPy's AILS.
(Threads are not measured here: CPU time says nothing of a parallel speed-up.)
"""

from __future__ import annotations

import argparse
import datetime
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine, sysidentpy_code  # noqa: E402

from graybox import Candidates, Record, reference, simulate_many  # noqa: E402
from graybox.datasets import load_pumping  # noqa: E402
from graybox.estimation._prediction_error import pe_pareto, pe_thetas  # noqa: E402
from graybox.selection._forward_regression import frols  # noqa: E402

N, P = 3200, 200


def cases() -> dict[str, tuple]:
    """name → (graybox's call, the peer's call, calls per timing); the peer's None where it has none."""
    from sysidentpy.basis_function import Polynomial
    from sysidentpy.model_structure_selection import FROLS
    from sysidentpy.parameter_estimation import LeastSquares
    from sysidentpy.simulation import SimulateNARMAX

    import bench_convex

    rng = np.random.default_rng(0)
    m = reference.paper_model(15)
    u = np.repeat(rng.uniform(750, 1650, N // 80 + 1), 80)[:N]
    rec = Record(u, m.simulate(u, np.full(m.max_lag, float(m.static_curve([u[0]])[0]))), Ts=0.05)
    thetas = m.theta * (1 + 0.002 * rng.standard_normal((P, m.n_params)))
    code = sysidentpy_code(m.structure)
    sim = SimulateNARMAX(basis_function=Polynomial(degree=2), estimate_parameter=False, model_type="NARMAX")
    X, Y = u.reshape(-1, 1), rec.y.reshape(-1, 1)
    sim.simulate(X_test=X, y_test=Y, model_code=code, theta=np.zeros((m.n_params, 1)))
    order = [next(i for i, c in enumerate(code) if sorted(c) == sorted(f)) for f in sim.final_model]
    theta_s = m.theta[order].reshape(-1, 1)
    out = {
        "free run, model (15)": (lambda: m.simulate(rec),
                                 lambda: sim.simulate(X_test=X, y_test=Y, model_code=code, theta=theta_s), 20),
        f"batch of {P} free runs (simulate_many, 1 thread)": (
            lambda: simulate_many(m.structure, thetas, rec, threads=1), None, 3),
    }
    data = load_pumping()
    ident = data.ident
    Xi, Yi = ident.u.reshape(-1, 1), ident.y.reshape(-1, 1)
    for degree, k in ((2, 17), (3, 23)):
        cand = Candidates(6, 6, ne=0, degree=degree)

        def theirs(degree=degree, k=k):
            FROLS(order_selection=False, n_terms=k, ylag=6, xlag=6, estimator=LeastSquares(),
                  basis_function=Polynomial(degree=degree)).fit(X=Xi, y=Yi)

        out[f"FROLS degree {degree}, {k} terms"] = (lambda cand=cand, k=k: frols(cand, ident, n_terms=k), theirs, 1)
    st, pts, lam = reference.STRUCTURE_15, data.static, bench_convex.LAMBDAS
    ails = lambda: bench_convex.ails_sweep(st, ident, pts, lam)  # noqa: E731
    out["100-λ PE sweep, closed form"] = (lambda: pe_thetas(st, ident, pts, lambdas=lam, solver="closed"), ails, 1)
    out["100-λ PE sweep, pe_pareto (J's included)"] = (
        lambda: pe_pareto(st, ident, pts, lambdas=lam, solver="closed"), ails, 1)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=15, help="alternated rounds; the least CPU time is kept")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    load = os.getloadavg()
    print(f"# bench_peers_cpu  {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC  git {git_rev()}  "
          f"{machine()}  load {load[0]:.1f} {load[1]:.1f} {load[2]:.1f}")
    with threadpool_limits(limits=1, user_api="blas"):
        cs = cases()
        fns = {(name, side): (f, n) for name, (g, p, n) in cs.items() for side, f in (("graybox", g), ("peer", p))
               if f is not None}
        best = {key: np.inf for key in fns}
        for _ in range(args.rounds):
            for key, (f, n) in fns.items():
                f()  # warm-up in every round: the caches as the other cases left them
                t0 = time.thread_time()
                for _ in range(n):
                    f()
                best[key] = min(best[key], (time.thread_time() - t0) / n)
    print("| case | graybox (CPU ms) | peer (CPU ms) | ratio |")
    print("| --- | --- | --- | --- |")
    for name, (_, p, _) in cs.items():
        g = best[(name, "graybox")]
        if p is None:
            print(f"| {name} | {g * 1e3:.3f} | — | — |")
        else:
            q = best[(name, "peer")]
            print(f"| {name} | {g * 1e3:.3f} | {q * 1e3:.3f} | {q / g:.1f}x |")
    load = os.getloadavg()
    print(f"# load after {load[0]:.1f} {load[1]:.1f} {load[2]:.1f}")


if __name__ == "__main__":
    main()
