"""FROLS (ERR structure selection) speed: graybox vs SysIdentPy on the same data and task.

Run with the benchmark environment (SysIdentPy is not a project dependency):

    python3 -m venv benchmarks/.env && benchmarks/.env/bin/pip install -e . sysidentpy
    benchmarks/.env/bin/python benchmarks/bench_frols.py [--repeat 5]

Task (the paper's Section IV-A): the bundled plant's identification record (3200 samples,
u in rpm, y in mlc), ny = nu = 6, degree 2 (91 candidates, 17 terms) and degree 3 (455
candidates, 23 terms), a fixed number of terms. Both sides do the whole job from the raw
signals: candidate matrix, ERR selection and least-squares parameters. SysIdentPy runs
``FROLS(order_selection=False, n_terms=k, estimator=LeastSquares())``. Times are medians
after one warm-up call (graybox's compiled kernel is cached on disk after its first use).
The script also reports whether both select the same terms in the same order.
"""

from __future__ import annotations

import argparse
import datetime
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine, timeit  # noqa: E402

from graybox import Candidates, Record, Structure, Term  # noqa: E402
from graybox.selection._forward_regression import frols  # noqa: E402

TASKS = ((2, 17), (3, 23))
NY = NU = 6


def load_record() -> tuple[Record, str]:
    """The bundled plant's identification record, or a deterministic synthetic stand-in."""
    try:
        from graybox.datasets import load_pumping

        return load_pumping().ident, "bundled plant data (load_pumping().ident)"
    except ImportError:  # pragma: no cover - only before the data module exists
        from graybox import reference

        rng = np.random.default_rng(0)
        m = reference.paper_model(15)
        u = np.repeat(rng.uniform(750, 1650, 3200 // 60 + 1), 60)[:3200]
        y = m.simulate(u, np.full(m.max_lag, float(m.static_curve([u[0]])[0])))
        return Record(u, y + 0.1 * rng.standard_normal(3200), Ts=0.05), "model (15) under steps + noise"


def from_sysidentpy_code(row) -> Term:
    """SysIdentPy's code row (1000+j = y(k-j), 2000+j = u(k-j), 0 = none) as a Term."""
    return Term(tuple(("y" if c < 2000 else "u", int(c) % 1000, 1) for c in row if c != 0))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="timed repetitions per case (median reported)")
    args = ap.parse_args()
    rec, source = load_record()
    print(f"# bench_frols  {datetime.date.today()}  git {git_rev()}  {machine()}")
    print(f"# data: {source}, N = {len(rec)}, ny = nu = {NY}")
    try:
        import sysidentpy
        from sysidentpy.basis_function import Polynomial
        from sysidentpy.model_structure_selection import FROLS
        from sysidentpy.parameter_estimation import LeastSquares
    except ImportError as exc:
        print(f"SysIdentPy not available ({exc}); install it in the benchmark environment")
        sysidentpy = None
    X, Y = rec.u.reshape(-1, 1), rec.y.reshape(-1, 1)
    rows = []
    for degree, k in TASKS:
        cand = Candidates(NY, NU, ne=0, degree=degree)
        sel = frols(cand, rec, n_terms=k)
        t_g = timeit(lambda: frols(cand, rec, n_terms=k), repeat=args.repeat)
        t_s, same = float("nan"), "-"
        if sysidentpy is not None:

            def fit():
                model = FROLS(
                    order_selection=False,
                    n_terms=k,
                    ylag=NY,
                    xlag=NU,
                    estimator=LeastSquares(),
                    basis_function=Polynomial(degree=degree),
                )
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    model.fit(X=X, y=Y)
                return model

            model = fit()
            theirs = Structure(from_sysidentpy_code(r) for r in model.final_model)
            n_same = sum(a == b for a, b in zip(theirs, sel.structure))
            same = f"{n_same}/{k} in order" if n_same == k else f"{len(set(theirs) & set(sel.structure))}/{k} as sets, {n_same} in order"
            t_s = timeit(fit, repeat=max(3, args.repeat // 2))
        rows.append((degree, len(cand), k, t_g, t_s, same))
    print(f"{'degree':>6} {'candidates':>10} {'terms':>5} {'graybox':>11} {'SysIdentPy':>12} {'speed-up':>9}  same terms")
    for degree, n, k, t_g, t_s, same in rows:
        print(f"{degree:>6} {n:>10} {k:>5} {t_g * 1e3:8.1f} ms {t_s * 1e3:9.1f} ms {t_s / t_g:8.1f}x  {same}")
    if sysidentpy is not None:
        print(f"# SysIdentPy {sysidentpy.__version__}: FROLS(order_selection=False, n_terms=k, LeastSquares())")


if __name__ == "__main__":
    main()
