"""Simulation-error fronts: the paper's GA, the gradient method, and fastcan's SE fit.

    benchmarks/.env/bin/python benchmarks/bench_se.py [--quick] [--threads 2]

Bundled pumping-plant data, the degree-2 structure FROLS selects (ny = nu = 6, 17 terms,
rational, constant included: the ℓ = 2 structure of `graybox reproduce`).
Full GA front: 100 λ1 in logspace(-2, 0), population 200, 50 generations per λ.
fastcan (installed for the benchmark only) fits the same structure by simulation error
(J_S only, `coef_init="one_step_ahead"`); we compare one gradient SE fit at λ1 = 1 with it.
"""

from __future__ import annotations

import argparse
import datetime
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import machine  # noqa: E402

from graybox import Candidates, js  # noqa: E402
from graybox.datasets import load_pumping  # noqa: E402
from graybox._model import Model  # noqa: E402
from graybox._se import GAOptions, SEProblem, ga_front, gradient_front  # noqa: E402
from graybox._selection import frols  # noqa: E402


def fastcan_ids(structure):
    """fastcan's feat_ids/delay_ids for a single-input structure (u = feature 0, y = feature 1)."""
    deg = max(t.degree for t in structure)
    feats, delays = [], []
    for t in structure:
        if t.is_constant:
            continue
        f, d = [], []
        for s, lag, p in t.factors:
            f += [0 if s == "u" else 1] * p
            d += [lag] * p
        feats.append([-1] * (deg - len(f)) + f)
        delays.append([-1] * (deg - len(d)) + d)
    return np.array(feats), np.array(delays)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="10 λ instead of 100")
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    data = load_pumping()
    # the ℓ = 2 structure of `graybox reproduce` (rational, constant included)
    sel = frols(Candidates(6, 6, 0, 2, max_y_power=1), data.ident, n_terms=17, include=["1"])
    structure = sel.structure
    prob = SEProblem(structure, data.ident, data.static)
    K = 10 if args.quick else 100
    lam = np.logspace(-2, 0, K)
    print(f"# bench_se  {datetime.date.today()}  {machine()}  threads={args.threads}  λ count={K}")
    print(f"# structure: {structure}")

    # warm-up compiles (not timed)
    ga_front(prob, [1.0], options=GAOptions(population=20, generations=2), progress=False, threads=args.threads)
    gradient_front(prob, [1.0], progress=False, max_nfev=2)

    t0 = time.perf_counter()
    _, th_ga, c_ga = ga_front(prob, lam, options=GAOptions(population=200, generations=50), seed=0, progress=False,
                              threads=args.threads)
    t_ga = time.perf_counter() - t0
    t0 = time.perf_counter()
    _, th_gr, c_gr = gradient_front(prob, lam, progress=False)
    t_gr = time.perf_counter() - t0
    print(f"GA front       : {t_ga:8.2f} s  ({K} λ × 50 generations × 200 individuals)")
    print(f"gradient front : {t_gr:8.2f} s")
    print(f"best weighted cost, GA vs gradient, at λ1 = 1: {c_ga[0]:.5f} vs {c_gr[0]:.5f}; "
          f"at λ1 = 0.01: {c_ga[-1]:.5f} vs {c_gr[-1]:.5f}")

    ones = {}
    for solver in ("trf", "dogbox"):
        t0 = time.perf_counter()
        _, th1, _ = gradient_front(prob, [1.0], progress=False, solver=solver)
        ones[solver] = (time.perf_counter() - t0, js(Model(structure, th1[0]), data.ident))
    t_one, js_g = ones["trf"]
    print("one SE fit (λ1 = 1): " + "; ".join(f"graybox gradient ({k}) {t:.3f} s, J_S {j:.4f}" for k, (t, j) in ones.items()))
    try:
        from fastcan.narx import NARX

        from importlib.metadata import version

        feats, delays = fastcan_ids(structure)
        has_c = any(t.is_constant for t in structure)
        L = structure.max_lag
        # fastcan does not scale internally: fit it in engineering units (as graybox is called)
        # and on data normalised to unit RMS (what a careful fastcan user would do)
        for label, su, sy in (("engineering units", 1.0, 1.0),
                              ("normalised data", float(np.std(data.ident.u)), float(np.std(data.ident.y)))):
            X = (data.ident.u / su).reshape(-1, 1)
            yv = data.ident.y / sy
            t0 = time.perf_counter()
            narx = NARX(feat_ids=feats, delay_ids=delays, fit_intercept=has_c).fit(X, yv, coef_init="one_step_ahead")
            t_fc = time.perf_counter() - t0
            yfc = narx.predict(X, y_init=yv[: narx.max_delay_]) * sy
            js_fc = float(np.mean((yfc[L:] - data.ident.y[L:]) ** 2))
            print(f"fastcan {version('fastcan')} on {label}: {t_fc:.3f} s (J_S {js_fc:.4g}); "
                  f"graybox (trf) is {t_fc / t_one:.1f}x faster")
    except ImportError as exc:
        print(f"fastcan not available ({exc})")
        pass


if __name__ == "__main__":
    main()
