"""A slow-mode check for simulation-error fits: does a member's slowest local mode, against the least-squares
model's, tell which members err on new records? And does ``margin="auto"`` keep the good ones?

    .venv/bin/python benchmarks/bench_slow_modes.py [--cases plant,buck,...] [--method gradient|ga] [--direct]

On each case of ``bench_honest.py`` (fit on the identification record, D_SF on it, test on a record
nothing saw) and each FROLS structure of 4, 8 and 12 terms (the plant also the paper's structure (15)),
the SE front (10 λ1 in logspace(-2, 0); gradient, or ``--method ga`` the paper's GA with
``starts="pe"``) is fitted without a margin and with ``margin="auto"``.

- check: the members without a margin, split by the rule of :func:`graybox.estimation._local_models.slow_margin`
  (slow: 1 − ρ < (1 − ρ_LS) / 10, ρ the largest spectral radius of a member's local models along the
  identification record, ρ_LS the least-squares model's): how many are slow, and the median test J_S of
  each group, beside the least-squares model's.
- auto: the D_SF member (the case's band) of each front, without a margin and with ``margin="auto"`` (the
  default: the slow members refitted with the margin (1 − ρ_LS) / 10): its λ1, J_SF, validation and test
  J_S; and the front's median test J_S.
- ``--direct``: ``se_dsf`` and ``output_error`` with margin None, "auto" and 0.01 on bench_output_error.py's
  data sets (the plant's ℓ = 2, ℓ = 3 and (15) structures, tested on three fresh runs; the buck converter's
  two, tested on the second half of its validation file).
"""

from __future__ import annotations

import argparse
import datetime
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402
from bench_honest import cases  # noqa: E402

import graybox as gb  # noqa: E402

LAMBDAS = np.logspace(-2, 0, 10)


def js(st, thetas, rec):
    return gb.evaluate_thetas(st, np.atleast_2d(thetas), rec, None, one_step=False)["JS"]


def fmt(v):
    return "inf" if not np.isfinite(v) else (f"{v:.3g}" if v < 1e4 else f"{v:.2e}")


def structures(name, data, cand):
    out = []
    for n in (4, 8, 12):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                out.append((f"frols-{n}", gb.frols(cand, data.ident, n_terms=n, include=["1"]).structure))
        except ValueError as exc:
            print(f"<!-- {name}: frols-{n} skipped: {exc} -->")
    if name == "plant":
        out.append(("paper's (15)", gb.reference.STRUCTURE_15))
    return out


def run(names, method="gradient"):
    from graybox.estimation._simulation_error import SEProblem
    check = ["| case | structure | ρ_LS | slow members | their ρ (max) | median test J_S: slow, others | LS test J_S |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    auto = ["| case | structure | margin | refitted with | D_SF λ1 | J_SF | J_S valid | J_S test | front: median test J_S | s |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for name, (data, test, cand, band) in cases().items():
        if names and name not in names:
            continue
        for label, st in structures(name, data, cand):
            problem = SEProblem(st, [data.ident], data.static)
            th_ls = problem.ls_theta()
            for margin in (None, "auto"):
                t0 = time.perf_counter()
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    try:
                        kw = {"starts": "pe", "threads": 2} if method == "ga" else {}
                        se = gb.se_pareto(st, data, lambdas=LAMBDAS, method=method, seed=0, margin=margin,
                                          progress=False, **kw)
                    except ValueError as exc:
                        auto.append(f"| {name} | {label} | {margin} | failed: {str(exc)[:70]} | | | | | | |")
                        continue
                sec = time.perf_counter() - t0
                tj = js(se.structure, se.thetas, test)
                if margin is None:
                    radii, slow, rho_ls = problem.slow_modes(se.thetas)
                    ok = np.isfinite(radii)
                    med = (lambda m: fmt(np.median(tj[m])) if m.any() else "–")
                    check.append(f"| {name} | {label} | {rho_ls:.4f} | {int(slow.sum())} of {int(ok.sum())} | "
                                 f"{np.nanmax(radii[slow]) if slow.any() else float('nan'):.5f} | "
                                 f"{med(slow & ok)}, {med(~slow & ok)} | {fmt(js(st, th_ls, test)[0])} |")
                    resolved = "none"
                else:
                    refit = np.isfinite(se.extra["margin"])
                    resolved = (f"{np.nanmax(se.extra['margin']):.4g} on {int(refit.sum())} of {len(se)}" if refit.any()
                                else "none needed")
                d = gb.decide_dsf(se, band=band, fallback="min_jsf")
                th = d.model.theta
                auto.append(f"| {name} | {label} | {margin} | {resolved} | {d.lambda1:.3g}"
                            f"{'' if d.in_band else ' (min J_SF)'} | {fmt(d.JSF)} | {fmt(js(st, th, data.valid)[0])} | "
                            f"{fmt(js(st, th, test)[0])} | {fmt(np.median(tj[np.isfinite(se.JS)]))} | {sec:.0f} |")
                print(auto[-1], flush=True)
    print("\n### check: members without a margin\n")
    print("\n".join(check))
    print("\n### auto: the D_SF member without a margin and with margin='auto'\n")
    print("\n".join(auto))


def direct():
    from bench_output_error import buck_sets, pumping_sets
    print("| data, structure | margin | se_dsf: J_SF, J_S valid, J_S test | output_error: J_S valid, J_S test, ρ |")
    print("| --- | --- | --- | --- |")
    for label, st, fit, choose, tests, data in pumping_sets(False) + buck_sets(False):
        band = 0.031 if "plant" in label else 0.01
        for m in (None, "auto", 0.01):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    r = gb.se_dsf(st, data, band=band, margin=m)
                    th = r.model.theta
                    a = f"{fmt(r.JSF)}, {fmt(js(st, th, choose)[0])}, {fmt(np.mean([js(st, th, t)[0] for t in tests]))}"
                except ValueError as exc:
                    a = f"failed: {str(exc)[:60]}…"
                o = gb.output_error(st, fit, margin=m)
                th = o.model.theta
                b = f"{fmt(js(st, th, choose)[0])}, {fmt(np.mean([js(st, th, t)[0] for t in tests]))}, {o.radius:.4f}"
            print(f"| {label} | {m} | {a} | {b} |", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default="", help="comma-separated case names (default: all)")
    ap.add_argument("--method", default="gradient", choices=("gradient", "ga"))
    ap.add_argument("--direct", action="store_true", help="se_dsf and output_error instead of the fronts")
    args = ap.parse_args(argv)
    print(f"# bench_slow_modes.py {'--direct' if args.direct else '--method ' + args.method}: {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, "
          f"git {git_rev()}, {machine()}")
    if args.direct:
        direct()
    else:
        run([c for c in args.cases.split(",") if c], args.method)


if __name__ == "__main__":
    main()
