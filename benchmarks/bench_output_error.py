"""Output error against LS and ELS, and SE D_SF with a stability margin, scored on records not used for fitting.

    python benchmarks/bench_output_error.py [--quick] [--se] [--ga]

Three records per data set: **fit** (the estimators see it), **choose** (only the ``choose_on``
variants see it: early stopping and the choice of start for output error, D_SF's choice for the
SE fronts) and **test** (nothing sees it; the figure to judge by).

- Bundled plant (simulated stand-in): fit = ``ident`` (3200 samples), choose = ``valid`` (800),
  test = three new 4000-sample runs of the same plant (``PumpingPlant().simulate`` on
  ``speed_reference(seed=s)``, s = 7, 8, 9), mean (and worst) J_S over the three. Structures: the
  ℓ = 2 (17 terms) and ℓ = 3 (23 terms) FROLS selections of ``graybox reproduce``, and the paper's
  structure (15).
- Buck converter (real, ``GRAYBOX_BUCK_DIR`` or /work/shared/data/buck): fit = ``ident`` (1001),
  choose = first half of ``valid``, test = its second half. Structures: FROLS on the fit record,
  ny = nu = 2, degree 2, 6 terms; ny = nu = 3, degree 3, 8 terms.
- Synthetic output-error system (known θ): x(k) = 0.7 x(k−1) + 0.25 u(k−1) + 0.1 u(k−2)² −
  0.05 x(k−1)u(k−1), y = x + v (white v, std 0.15: noise on the output only); fit 1500 samples,
  choose 600, test 1500 noise-free; also ‖θ − θ_true‖.

Estimators on the same structure: LS, ELS (process part), and :func:`graybox.output_error`
without and with a margin (0.01 and 0.05) or a ridge towards least squares (0.01 and 1), without
and with ``choose_on``. ``--se`` adds the SE
fronts of Table I (10 λ1, gradient; ``--ga`` the paper's GA too) with margins None, 0.01, 0.02,
0.05, D_SF on the identification record and on the choosing record, and (margin 0.01) a front fitted
on fit + choose together: what members inside the band reach on the choosing record when they have
seen it, a floor for the honest fits.
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

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402

import graybox as gb  # noqa: E402
from graybox.datasets.pumping import PumpingPlant, speed_reference  # noqa: E402

OE_STRUCT = gb.Structure(["y(k-1)", "u(k-1)", "u(k-2)^2", "u(k-1)y(k-1)"])
OE_THETA = np.array([0.7, 0.25, 0.1, -0.05])


#: Output-error variants: (margin, ridge, choose on the choosing record).
VARIANTS = ((None, 0.0, False), (None, 0.0, True), (0.01, 0.0, False), (0.01, 0.0, True), (0.05, 0.0, False),
            (0.05, 0.0, True), (None, 0.01, False), (None, 1.0, False), (None, 0.01, True))


def synthetic():
    def rec(seed, N, noise, name):
        rng = np.random.default_rng(seed)
        u = np.repeat(rng.uniform(-1.0, 1.0, N // 8 + 1), 8)[:N]
        x = gb.Model(OE_STRUCT, OE_THETA).simulate(u, np.zeros(2))
        return gb.Record(u, x + noise * rng.standard_normal(N), name=name)

    return rec(1, 1500, 0.15, "fit"), rec(3, 600, 0.15, "choose"), [rec(2, 1500, 0.0, "test")]


def plant_tests(Ts):
    """Three new 4000-sample runs of the simulated plant (seeds 7, 8, 9): records nothing is fitted or chosen on."""
    tests = []
    for s in (7, 8, 9):
        run = PumpingPlant().simulate(speed_reference(seed=s), seed=np.random.default_rng([s, 2]))
        tests.append(gb.Record(run.u, run.y, Ts=Ts, name=f"plant run {s}"))
    return tests


def pumping_sets(quick):
    data = gb.load_pumping()
    tests = plant_tests(data.ident.Ts)
    out = []
    for degree, n_terms in ((2, 17),) if quick else ((2, 17), (3, 23)):
        cand = gb.Candidates(6, 6, ne=2, degree=degree, max_y_power=1 if degree == 2 else None)
        st = gb.frols(cand, data.ident, n_terms=n_terms, include=["1"]).structure
        out.append((f"plant ℓ={degree} ({n_terms} terms)", st, data.ident, data.valid, tests, data))
    if not quick:
        out.append(("plant, the paper's (15)", gb.reference.STRUCTURE_15, data.ident, data.valid, tests, data))
    return out


def buck_sets(quick):
    folder = os.environ.get("GRAYBOX_BUCK_DIR", "/work/shared/data/buck")
    try:
        data = gb.load_buck(folder)
    except (OSError, ValueError) as exc:
        print(f"buck converter skipped: {exc}")
        return []
    n = len(data.valid) // 2
    choose, test = data.valid.slice(0, n, name="buck choose"), data.valid.slice(n, None, name="buck test")
    out = []
    for ny, deg, nt in ((2, 2, 6),) if quick else ((2, 2, 6), (3, 3, 8)):
        st = gb.frols(gb.Candidates(ny=ny, nu=ny, ne=2, degree=deg), data.ident, n_terms=nt).structure
        out.append((f"buck ny=nu={ny} ℓ={deg} ({nt} terms)", st, data.ident, choose, [test], data))
    return out


def js(st, th, rec):
    return float(gb.evaluate_thetas(st, np.asarray(th)[None], rec, None, one_step=False)["JS"][0])


def fmt(v):
    return "inf" if not np.isfinite(v) else (f"{v:.3g}" if v < 1e4 else f"{v:.2e}")


def black_boxes(sets, true_theta=None):
    print("| data, structure | estimator | J_S fit | J_S choose | J_S test (mean, worst) | ρ max | s |"
          + (" ‖θ − θ_true‖ |" if true_theta is not None else ""))
    print("| --- | --- | --- | --- | --- | --- | --- |" + (" --- |" if true_theta is not None else ""))
    for label, st, fit, choose, tests, _ in sets:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            e = gb.els(st, fit)
        st = e.model.structure
        fits = {"LS": (e.theta_ls, 0.0, np.nan), "ELS": (e.model.theta, 0.0, np.nan)}
        for m, g, on in VARIANTS:
            t0 = time.perf_counter()
            r = gb.output_error(st, fit, margin=m, ridge=g, choose_on=choose if on else None, seed=0)
            name = "OE" + (f" margin={m:g}" if m is not None else "") + (f" ridge={g:g}" if g else "") \
                + (" choose" if on else "")
            fits[name] = (r.model.theta, time.perf_counter() - t0, r.radius)
        for name, (th, sec, rho) in fits.items():
            tj = [js(st, th, t) for t in tests]
            test = f"{fmt(np.mean(tj))}" + (f", {fmt(max(tj))}" if len(tj) > 1 else "")
            if not np.isfinite(rho):
                from graybox.estimation._local_models import LocalModels, record_points
                rho = float(LocalModels(st, *record_points(st, [fit])).radius(th).max())
            row = (f"| {label} | {name} | {fmt(js(st, th, fit))} | {fmt(js(st, th, choose))} | {test} | {rho:.4f} | "
                   f"{sec:.1f} |")
            if true_theta is not None:
                row += f" {np.linalg.norm(th - true_theta):.4f} |"
            print(row, flush=True)


def se_fronts(sets, methods):
    print("| data, structure | method | margin | D_SF on | λ1 | J_S ident | J_SF | J_S choose | J_S test (mean, worst) "
          "| front s |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for label, st, fit, choose, tests, data in sets:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            e = gb.els(st, fit)
        tj = [js(e.model.structure, e.model.theta, t) for t in tests]
        print(f"| {label} | ELS | | | | {fmt(js(e.model.structure, e.model.theta, fit))} | "
              f"{fmt(gb.jsf(e.model, data.static))} | {fmt(js(e.model.structure, e.model.theta, choose))} | "
              f"{fmt(np.mean(tj))}, {fmt(max(tj))} | |", flush=True)
        for method in methods:
            for m in (None, 0.01, 0.02, 0.05):
                t0 = time.perf_counter()
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        se = gb.se_pareto(st, data, lambdas=np.logspace(-2, 0, 10), method=method, seed=0, margin=m)
                except ValueError as exc:
                    print(f"| {label} | SE ({method}) | {m} | | failed: {str(exc)[:80]}… | | | | | |")
                    continue
                sec = time.perf_counter() - t0
                if m == 0.01 and method == "gradient":  # the floor: band-respecting members that saw the choosing record
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        both = gb.se_pareto(st, [fit, choose], data.static, lambdas=np.logspace(-2, 0, 10),
                                            method=method, seed=0, margin=m)
                    d = gb.decide_dsf(both, band=0.031, fallback="min_jsf")
                    tj = [js(st, d.model.theta, t) for t in tests]
                    print(f"| {label} | SE ({method}) fitted on fit + choose | {m} | fit + choose | {d.lambda1:.3g} | "
                          f"{fmt(js(st, d.model.theta, fit))} | {fmt(d.JSF)} | {fmt(js(st, d.model.theta, choose))} | "
                          f"{fmt(np.mean(tj))}, {fmt(max(tj))} | |", flush=True)
                for on in (None, choose):
                    d = gb.decide_dsf(se, band=0.031, fallback="min_jsf", choose_on=on)
                    th = d.model.theta
                    tj = [js(se.structure, th, t) for t in tests]
                    print(f"| {label} | SE ({method}) | {m} | {'choose' if on is not None else 'ident'} | "
                          f"{d.lambda1:.3g}{'' if d.in_band else ' (min J_SF)'} | {fmt(d.JS)} | {fmt(d.JSF)} | "
                          f"{fmt(js(se.structure, th, choose))} | {fmt(np.mean(tj))}, {fmt(max(tj))} | {sec:.0f} |",
                          flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one structure per data set")
    ap.add_argument("--se", action="store_true", help="also the SE fronts with margins (bundled plant)")
    ap.add_argument("--ga", action="store_true", help="with --se: the paper's GA too")
    args = ap.parse_args(argv)
    print(f"# bench_output_error.py{' --quick' if args.quick else ''}{' --se' if args.se else ''}"
          f"{' --ga' if args.ga else ''}: {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, "
          f"git {git_rev()}, {machine()}")
    plant = pumping_sets(args.quick)
    print("\n## synthetic output-error system\n")
    fit, choose, tests = synthetic()
    black_boxes([("synthetic OE", OE_STRUCT, fit, choose, tests, None)], OE_THETA)
    print("\n## bundled plant and buck converter\n")
    black_boxes(plant + buck_sets(args.quick))
    if args.se:
        print("\n## SE fronts (10 λ1) and D_SF, bundled plant\n")
        se_fronts(plant, ("gradient", "ga") if args.ga else ("gradient",))


if __name__ == "__main__":
    main()
