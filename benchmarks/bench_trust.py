"""Trusting and keeping a model: residual tests, covariances, static bands, the D_SF bootstrap, JSON.

    .venv/bin/python benchmarks/bench_trust.py [--repeat 5] [--boot 20]

Data: the bundled pumping-plant records (3200 identification samples, 800 validation) and static
points; the ℓ = 2 rational structure of notebook 2/3 (17 FROLS terms, max_y_power=1) with its
ELS, CLS (eq. (22)), PE D_SF and SE (gradient) D_SF models. Each figure is the median wall time of
``--repeat`` calls after one warm-up; the bootstrap rows time whole runs of ``--boot`` replicates,
in this process and through a ``ProcessPoolExecutor`` with 2 workers.
"""

from __future__ import annotations

import argparse
import datetime
import sys
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine, timeit  # noqa: E402

import graybox as gb  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--boot", type=int, default=20)
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    data = gb.load_pumping()
    sel = gb.frols(gb.Candidates(ny=6, nu=6, ne=2, degree=2, max_y_power=1), data.ident, n_terms=17)
    st = sel.structure
    fit = gb.els(sel, data.ident)
    els = fit.model
    curve = gb.StaticCurve.fit(data.static, degree=2)
    cls = gb.cls(st, data.ident, curve, reference=els).model
    pe_l = np.logspace(-6, 0, 30)
    pe = gb.pe_pareto(st, data.ident, data.static, lambdas=pe_l, solver="closed")
    pe_d = gb.decide_dsf(pe, band=0.031, fallback="min_jsf")
    se_l = np.logspace(-2, 0, 6)
    se = gb.se_pareto(st, data, lambdas=se_l, method="gradient", progress=False)
    se_d = gb.decide_dsf(se, band=0.031, fallback="min_jsf")
    unc = gb.ls_uncertainty(els, data.ident)
    ub = np.linspace(750, 1650, 50)
    big = gb.pe_pareto(st, data.ident, data.static, lambdas=np.logspace(-6, 0, 100), solver="closed")
    text = gb.to_json(big)
    rows = [
        ("residual_tests (ELS, validation, 5 tests × ≤ 41 lags)", lambda: gb.residual_tests(els, data.valid)),
        ("ls_uncertainty (ELS, MA(2) block)", lambda: gb.ls_uncertainty(els, data.ident)),
        ("cls_uncertainty (eq. (22))", lambda: gb.cls_uncertainty(cls, data.ident, curve, reference=els)),
        ("pe_uncertainty (D_SF member)", lambda: gb.pe_uncertainty(pe_d, data.ident, data.static)),
        ("se_uncertainty (D_SF member, Jacobian of 3200 free-run samples)",
         lambda: gb.se_uncertainty(se_d, data.ident, data.static)),
        ("static_curve_band, delta, 50 ū", lambda: gb.static_curve_band(unc, ub)),
        ("static_curve_band, Monte Carlo 2000 draws, 50 ū",
         lambda: gb.static_curve_band(unc, ub, method="monte-carlo", n_samples=2000)),
        (f"to_json (ParetoSet, 100 × 17; {len(text) / 1024:.0f} KiB)", lambda: gb.to_json(big)),
        ("from_json (same)", lambda: gb.from_json(text)),
    ]
    print(f"# bench_trust: {machine()}, graybox {gb.__version__} ({git_rev()}), {datetime.date.today()}")
    print("| what | median time |\n| --- | --- |")
    for name, fn in rows:
        print(f"| {name} | {1e3 * timeit(fn, repeat=args.repeat):.2f} ms |")

    def boot(method, lambdas, options, mp=None):
        return gb.bootstrap_decision(st, data, estimator=method, lambdas=lambdas, n_boot=args.boot, fallback="min_jsf",
                                     options=options, map=mp, progress=False)

    for label, method, lam, opts in (("PE, 30 λ, closed form", "pe", pe_l, {"solver": "closed"}),
                                     ("SE gradient, 6 λ, max_nfev 20", "se", se_l, {"method": "gradient", "max_nfev": 20})):
        t0 = time.perf_counter()
        a = boot(method, lam, opts)
        t1 = time.perf_counter()
        with ProcessPoolExecutor(2) as ex:
            b = boot(method, lam, opts, ex.map)
        t2 = time.perf_counter()
        assert np.array_equal(a.thetas, b.thetas, equal_nan=True)
        print(f"| bootstrap_decision {label}, {args.boot} replicates + reference: in process | {t1 - t0:.2f} s |")
        print(f"| … same, ProcessPoolExecutor(2) (start-up included; identical result) | {t2 - t1:.2f} s |")


if __name__ == "__main__":
    main()
