"""PE bi-objective sweep (eqs. (9), (11)): closed form, cvxpy + Clarabel, cvxpy + OSQP, SysIdentPy AILS.

Run with the benchmark environment (SysIdentPy is not a project dependency):

    python3 -m venv benchmarks/.env && benchmarks/.env/bin/pip install -e . sysidentpy
    benchmarks/.env/bin/python benchmarks/bench_convex.py

Same structure and data for every method: the paper's structure (15) (17 terms), the bundled
pumping-plant identification record (3200 samples, u in rpm, y in mlc) and its 10 static
points; 100 λ1 in logspace(-6, 0). Each time is the median of a few repetitions of the whole
sweep from (structure, data, static points) to the 100 θ vectors: building Ψ and the static
rows, and for cvxpy building and compiling the problem once.

Accuracy is the largest relative difference of θ from graybox's closed form over the sweep,
measured with every term at its data scale (‖Δθ ⊙ s‖ / ‖θ ⊙ s‖, s = RMS of Ψ's columns).
SysIdentPy's AILS weights the *sums* of squares as eq. (11) is printed, so it is compared with
graybox's ``weights="sum"`` sweep at the same λ.
"""

from __future__ import annotations

import argparse
import datetime
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine, sysidentpy_code, timeit  # noqa: E402

from graybox import reference  # noqa: E402
from graybox.estimation._prediction_error import cls, pe_pareto, pe_thetas, qr_static_error  # noqa: E402
from graybox.static._curves import StaticCurve  # noqa: E402
from graybox.datasets import load_pumping  # noqa: E402
from graybox.core._least_squares import column_scales  # noqa: E402
from graybox.core._regressors import stacked_regressors  # noqa: E402

LAMBDAS = np.logspace(-6, 0, 100)


def rel_err(a: np.ndarray, b: np.ndarray, s: np.ndarray) -> float:
    return float(np.max(np.linalg.norm((a - b) * s, axis=1) / np.linalg.norm(b * s, axis=1)))


def ails_sweep(structure, rec, pts, lambdas):
    """SysIdentPy's AILS on the same problem; θ mapped back to graybox's term order."""
    from sysidentpy.multiobjective_parameter_estimation import AILS

    code = sysidentpy_code(structure)
    w = np.vstack([lambdas, 1.0 - lambdas])
    ails = AILS(final_model=code.copy(), static_function=True, static_gain=False, normalize=False)
    out = ails.estimate(y=rec.y.reshape(-1, 1), X=rec.u.reshape(-1, 1), y_static=pts.ybar.reshape(-1, 1),
                        X_static=pts.ubar.reshape(-1, 1), gain=np.zeros((len(pts), 1)), weighing_matrix=w)
    theta = out[2]
    # AILS reorders the regressors (its final_model after estimate); map its columns to ours
    order = [next(i for i, f in enumerate(ails.final_model) if sorted(f) == sorted(c)) for c in code]
    return theta[:, order]


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="repetitions of each sweep (median reported)")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore", RuntimeWarning)
    data = load_pumping()
    st, rec, pts = reference.STRUCTURE_15, data.ident, data.static
    s = column_scales(stacked_regressors(st, rec)[0])
    print(f"# bench_convex  {datetime.date.today()}  git {git_rev()}  {machine()}")
    print(f"# structure (15), {len(st)} terms; {len(rec)} samples; {len(pts)} static points; "
          f"{LAMBDAS.size} λ1 in logspace(-6, 0); median of {args.repeat}")

    ref = pe_thetas(st, rec, pts, lambdas=LAMBDAS, solver="closed")
    ref_sum = pe_thetas(st, rec, pts, lambdas=LAMBDAS, solver="closed", weights="sum")
    rows = []
    t = timeit(lambda: pe_thetas(st, rec, pts, lambdas=LAMBDAS, solver="closed"), repeat=max(args.repeat, 5))
    rows.append(("graybox closed form (11), batched QR", t, 0.0))
    for solver in ("clarabel", "osqp"):
        th = pe_thetas(st, rec, pts, lambdas=LAMBDAS, solver=solver)
        t = timeit(lambda: pe_thetas(st, rec, pts, lambdas=LAMBDAS, solver=solver), repeat=args.repeat)
        rows.append((f"graybox cvxpy + {solver.capitalize()} (one DPP problem)", t, rel_err(th, ref, s)))
    t = timeit(lambda: pe_pareto(st, rec, pts, lambdas=LAMBDAS, solver="closed"), repeat=args.repeat)
    rows.append(("graybox pe_pareto (closed form + J1/JS/JSF of 100 members)", t, 0.0))
    try:
        import sysidentpy

        th_ails = ails_sweep(st, rec, pts, LAMBDAS)
        t = timeit(lambda: ails_sweep(st, rec, pts, LAMBDAS), repeat=args.repeat)
        rows.append((f"SysIdentPy {sysidentpy.__version__} AILS (normal equations)", t, rel_err(th_ails, ref_sum, s)))
    except ImportError as exc:
        print(f"# SysIdentPy not available ({exc}); install it in the benchmark environment")
        th_ails = None

    print(f"{'100-λ PE sweep':64s} {'time':>11s} {'max rel Δθ':>11s}")
    for name, t, e in rows:
        print(f"{name:64s} {t * 1e3:8.1f} ms {e:11.1e}")

    if th_ails is not None:
        # what the difference means: the two objectives each method trades, at the same λ
        psi, y = stacked_regressors(st, rec)
        j1 = lambda T: np.mean((y[:, None] - psi @ T.T) ** 2, axis=0)  # noqa: E731
        dom = (j1(th_ails) >= j1(ref_sum)) & (qr_static_error(st, th_ails, pts) >= qr_static_error(st, ref_sum, pts))
        print(f"AILS vs graybox (weights='sum', same λ): AILS is dominated in (J_1, J_SF^QR) at {int(dom.sum())} of "
              f"{LAMBDAS.size} λ; at λ1 = 1 (plain LS) J_1 = {j1(th_ails)[-1]:.5f} vs {j1(ref_sum)[-1]:.5f} mlc²")

    curve = StaticCurve.polynomial(reference.EQ1_COEFFICIENTS)
    closed = cls(st, rec, curve, solver="closed").model
    print(f"\n{'CLS (22), one estimate':64s} {'time':>11s} {'max rel Δθ':>11s}")
    for solver in ("closed", "clarabel", "osqp"):
        m = cls(st, rec, curve, solver=solver).model
        t = timeit(lambda: cls(st, rec, curve, solver=solver).model, repeat=args.repeat)
        print(f"{'graybox cls, ' + solver:64s} {t * 1e3:8.1f} ms {rel_err(m.theta[None], closed.theta[None], s):11.1e}")


if __name__ == "__main__":
    main()
