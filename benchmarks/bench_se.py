"""Simulation-error fronts: the paper's GA, the gradient method, fastcan's SE fit, and cost in N.

    benchmarks/.env/bin/python benchmarks/bench_se.py [--quick] [--threads 2] [--no-ga] [--scale]

Bundled pumping-plant data, the degree-2 structure FROLS selects (ny = nu = 6, 17 terms,
rational, constant included: the ℓ = 2 structure of `graybox reproduce`).
Full GA front: 100 λ1 in logspace(-2, 0), population 200, 50 generations per λ.
Gradient fronts: the default (``solver="auto"``: multi-start with "trf" and "dogbox" wherever the
sweep restarts, "trf" along it) and "trf" everywhere; each member's J_S on the identification and
validation records and J_SF from the shared evaluator.
fastcan (installed for the benchmark only: ``python3 -m venv benchmarks/.env &&
benchmarks/.env/bin/pip install -e . fastcan``) fits the same structure by simulation error
(J_S only, ``coef_init="one_step_ahead"``); we compare one gradient SE fit at λ1 = 1 with it.

``--scale`` times the gradient method against the record length N = 10⁴, 10⁵, 10⁶ in one process:
records from the plant simulator (100 000-sample runs of ``PumpingPlant().simulate`` joined end to
end; seeds whose run fails are skipped and named), per objective evaluation (one free run), per
Jacobian (the streamed QR factor; and, for comparison, the former path: the whole N × n Jacobian and
its SVD, which ``least_squares`` computed at every accepted step), and one λ by ``se_pareto``.
"""

from __future__ import annotations

import argparse
import datetime
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import scipy.linalg
from threadpoolctl import threadpool_limits

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402

from graybox import Candidates, Record, StaticRangeWarning, evaluate_thetas, js, se_pareto  # noqa: E402
from graybox.datasets import load_pumping  # noqa: E402
from graybox.datasets.pumping import PumpingPlant, speed_reference  # noqa: E402
from graybox.core._simulation_kernels import free_run_sensitivity  # noqa: E402
from graybox.models._model import Model  # noqa: E402
from graybox.estimation._simulation_error import GAOptions, SEProblem, _Compressed, _pe_starts, ga_front, gradient_front  # noqa: E402
from graybox.selection._forward_regression import frols  # noqa: E402


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


def front_table(name, front, structure, data, seconds):
    """Members of a front at a few λ, J's from the shared evaluator, and a one-line summary."""
    ev = evaluate_thetas(structure, np.nan_to_num(front.thetas), data.ident, data.static)
    val = evaluate_thetas(structure, np.nan_to_num(front.thetas), data.valid, None)["JS"]
    lam = front.lambdas
    print(f"\n{name}: {seconds:.2f} s, {int(front.nfev.sum())} evaluations, {len(front.failures)} failed")
    print("| λ1 | J_S ident | J_S valid | J_SF | weighted cost |")
    print("| --- | --- | --- | --- | --- |")
    for target in (1.0, 0.9, 0.5, 0.1, 0.01):
        i = int(np.argmin(np.abs(np.log(lam) - np.log(target))))
        print(f"| {lam[i]:.3g} | {ev['JS'][i]:.4f} | {val[i]:.4f} | {ev['JSF'][i]:.5f} | {front.costs[i]:.5f} |")
    low = lam < 1
    print(f"summary: J_S ident median {np.median(ev['JS']):.4f}, J_S valid median {np.median(val):.3f}, "
          f"J_SF (λ1 < 1) median {np.median(ev['JSF'][low]):.5f} max {np.max(ev['JSF'][low]):.5f}")
    return front.costs


def fronts(args, data, structure, prob):
    K = 10 if args.quick else 100
    lam = np.logspace(-2, 0, K)
    starts = _pe_starts(prob)  # what se_pareto passes
    # warm-up compiles (not timed)
    ga_front(prob, [1.0], options=GAOptions(population=20, generations=2), progress=False, threads=args.threads)
    gradient_front(prob, [1.0], progress=False, max_nfev=2)
    if not args.no_ga:
        t0 = time.perf_counter()
        ga = ga_front(prob, lam, options=GAOptions(population=200, generations=50), seed=0, progress=False,
                      threads=args.threads)
        print(f"GA front       : {time.perf_counter() - t0:8.2f} s  ({K} λ × 50 generations × 200 individuals)")
        print(f"best weighted cost of the GA at λ1 = 1: {ga.costs[0]:.5f}; at λ1 = 0.01: {ga.costs[-1]:.5f}")
    costs = {}
    for solver in ("auto", "trf"):
        t0 = time.perf_counter()
        front = gradient_front(prob, lam, progress=False, starts=starts, solver=solver)
        costs[solver] = front_table(f"gradient front, solver={solver!r}", front, structure, data,
                                    time.perf_counter() - t0)
    r = costs["auto"] / costs["trf"]
    print(f"\nweighted cost, auto / trf, per λ: median {np.median(r):.3f}, min {np.min(r):.3f}, max {np.max(r):.3f}")


def one_fit(args, data, structure, prob):
    print("\none SE fit at λ1 = 1 (J_S only):")
    print("| fit | time (s) | J_S ident | J_S valid |")
    print("| --- | --- | --- | --- |")
    starts = _pe_starts(prob)
    t_default = None
    for label, kw in (("graybox default (auto: trf + dogbox from LS and 4 PE starts)", {"starts": starts}),
                      ("graybox trf from LS and the PE starts", {"starts": starts, "solver": "trf"}),
                      ("graybox trf from LS only", {"solver": "trf"}),
                      ("graybox dogbox from LS only", {"solver": "dogbox"})):
        t0 = time.perf_counter()
        front = gradient_front(prob, [1.0], progress=False, **kw)
        t = time.perf_counter() - t0
        t_default = t if t_default is None else t_default
        m = Model(structure, front.thetas[0])
        print(f"| {label} | {t:.3f} | {js(m, data.ident):.4f} | {js(m, data.valid):.4f} |")
    try:
        from importlib.metadata import version

        from fastcan.narx import NARX
    except ImportError as exc:
        print(f"fastcan not available ({exc})")
        return
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
        res = []
        for rec in (data.ident, data.valid):
            yfc = narx.predict((rec.u / su).reshape(-1, 1), y_init=rec.y[: narx.max_delay_] / sy) * sy
            res.append(float(np.mean((yfc[L:] - rec.y[L:]) ** 2)))
        print(f"| fastcan {version('fastcan')}, {label} | {t_fc:.3f} | {res[0]:.4g} | {res[1]:.4g} |")
        print(f"  (graybox default is {t_fc / t_default:.1f}x faster)")


def best_of(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def scale(args, data, structure):
    sizes = (10_000, 100_000, 1_000_000)
    runs, failed, seed = [], [], 0
    while sum(r.u.size for r in runs) < sizes[-1]:
        try:
            runs.append(PumpingPlant().simulate(speed_reference(n_samples=100_000, n_ident=50_000, seed=seed),
                                                seed=seed))
        except ValueError as exc:  # the simulator's known failure on some long records
            failed.append((seed, str(exc)))
        seed += 1
    print(f"\ncost in N: plant simulator runs of 100 000 samples, seeds 0–{seed - 1}, joined end to end; "
          f"seeds skipped (simulator failed): {[s for s, _ in failed]}")
    u = np.concatenate([r.u for r in runs])
    y = np.concatenate([r.y for r in runs])
    print("| N | free run (s) | Jacobian factor, streamed QR (s) | former: N × n Jacobian + its SVD (s) | "
          "one λ by se_pareto (s) | evaluations | s per evaluation |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    rows = {}
    for N in sizes:
        rec = Record(u[:N], y[:N], runs[0].Ts)
        prob = SEProblem(structure, rec, data.static)
        th = prob.ls_theta()
        z = th * prob.scale
        cp = _Compressed(prob, 1.0)
        rep = 3 if N < 1_000_000 else 2
        L = prob.L

        def former():
            _, S = free_run_sensitivity(prob.code, th, rec.u, rec.y[:L], L, prob.U[0])
            scipy.linalg.svd(S[L:] / prob.scale, full_matrices=False)

        with threadpool_limits(limits=1, user_api="blas"):  # as inside the sweeps
            t_fun = best_of(lambda: cp.fun(z), rep)
            t_jac = best_of(lambda: cp.jac(z), rep)
            t_old = best_of(former, rep)

        def one_lambda():
            se_pareto(structure, rec, data.static, lambdas=[1.0], method="gradient", progress=False)

        evals = {}

        def counted():
            front = gradient_front(prob, [1.0], progress=False, starts=_pe_starts(prob))
            evals["n"] = int(front.nfev[0])

        t_one = best_of(one_lambda, 1 if N == sizes[-1] else 2)
        t_count = best_of(counted, 1)
        rows[N] = (t_fun, t_jac, t_old, t_one, t_count / evals["n"])
        print(f"| {N:.0e} | {t_fun:.4f} | {t_jac:.4f} | {t_old:.4f} | {t_one:.2f} | {evals['n']} | "
              f"{t_count / evals['n'] * 1e3:.3f} ms |", flush=True)
    a, b = rows[sizes[1]], rows[sizes[2]]
    names = ("free run", "Jacobian factor", "former Jacobian + SVD", "one λ", "per evaluation")
    print("growth exponent 1e5 -> 1e6 (log10 of the time ratio): "
          + ", ".join(f"{nm} {np.log10(y_ / x_):.2f}" for nm, x_, y_ in zip(names, a, b)))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="10 λ instead of 100")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--no-ga", action="store_true", help="skip the GA front")
    ap.add_argument("--scale", action="store_true", help="also time the gradient method against N (minutes)")
    ap.add_argument("--only-scale", action="store_true", help="only the timing against N")
    args = ap.parse_args()
    warnings.simplefilter("ignore", StaticRangeWarning)
    data = load_pumping()
    # the ℓ = 2 structure of `graybox reproduce` (rational, constant included)
    sel = frols(Candidates(6, 6, ne=0, degree=2, max_y_power=1), data.ident, n_terms=17, include=["1"])
    structure = sel.structure
    prob = SEProblem(structure, data.ident, data.static)
    print(f"# bench_se  {datetime.datetime.now():%Y-%m-%d %H:%M}  git {git_rev()}  {machine()}  threads={args.threads}")
    print(f"# structure: {structure}")
    if not args.only_scale:
        fronts(args, data, structure, prob)
        one_fit(args, data, structure, prob)
    if args.scale or args.only_scale:
        scale(args, data, structure)


if __name__ == "__main__":
    main()
