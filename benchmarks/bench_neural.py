"""The neural NARMAX row of Table I: why the paper's training fails on the bundled plant, how the
default is chosen, and the optimiser it uses.

    benchmarks/.env/bin/python benchmarks/bench_neural.py [--part evidence|cv|optimiser|all] [--seeds 5]

Bundled pumping-plant data, the paper's network (ny = nu = 6, ne = 2, 7 tanh nodes, N_p = 99).
J in mlc² (J_S ident / J_S valid: free-run MSE on the identification / validation record; J_SF:
static error at the 10 static points). The validation record is only ever evaluated, never
trained on, early-stopped on or used to choose an option.

- ``evidence``: training variants over seeds (min / median / max), how well early stopping's
  held-out cost ranks the validation J_S, and the paper's training epoch by epoch (one-step J_1
  against free-run J_S);
- ``cv``: the weight decay D chosen by 5-fold cross-validation over contiguous blocks of the
  identification record (train on four blocks as separate records, free-run MSE on the fifth);
- ``optimiser``: the library's Levenberg–Marquardt (Norgaard's ``marq``, numba normal equations
  and Cholesky) against ``scipy.optimize.least_squares`` with the same analytic Jacobians and the
  same trial-step budgets, plugged into the same default training.
"""

from __future__ import annotations

import argparse
import datetime
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import spearmanr
from threadpoolctl import threadpool_limits

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402

import graybox.estimation._neural as gn  # noqa: E402
from graybox import neural_narx  # noqa: E402
from graybox.models._evaluate import evaluate, mse  # noqa: E402
from graybox.datasets import load_pumping  # noqa: E402


def row(model, data) -> tuple[float, float, float, float]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = evaluate({"n": model}, data).loc["n"]
    return r["JS_ident"], r["JS_valid"], r["JSF"], r["J1_ident"]


def spread(rows) -> str:
    a = np.array(rows, dtype=float)
    return "  ".join(f"{np.median(a[:, i]):7.3f} [{np.min(a[:, i]):.3f}–{np.max(a[:, i]):.3f}]" for i in range(3))


VARIANTS = {
    "paper: PE 60 epochs, D = 0": dict(epochs=60, sim_epochs=0, weight_decay=0.0),
    "paper + early stopping (last 20 %)": dict(epochs=60, sim_epochs=0, weight_decay=0.0, holdout=0.2),
    "paper + weight decay D = 0.01": dict(epochs=60, sim_epochs=0, weight_decay=0.01),
    "paper + weight decay D = 1": dict(epochs=60, sim_epochs=0, weight_decay=1.0),
    "PE 10 + SE 60, D = 0": dict(sim_epochs=60, weight_decay=0.0),
    "PE 10 + SE 60, D = 0, early stopping (last 20 %)": dict(sim_epochs=60, weight_decay=0.0, holdout=0.2),
    "PE 10 + SE 200, D = 0": dict(sim_epochs=200, weight_decay=0.0),
    "default: PE 10 + SE 60, D = 30": dict(),
    "default + early stopping (last 20 %)": dict(holdout=0.2),
    "PE 10 + SE 200, D = 30": dict(sim_epochs=200),
}


def part_evidence(data, seeds) -> None:
    print("## training variants: median [min–max] over seeds", list(seeds))
    print(f"{'variant':52s} {'JS_ident':>22s}  {'JS_valid':>22s}  {'JSF':>22s}")
    for label, kw in VARIANTS.items():
        rows = [row(neural_narx(data.ident, seed=sd, **kw).model, data) for sd in seeds]
        print(f"{label:52s} {spread(rows)}", flush=True)
    print("\n## does the held-out cost of early stopping rank the networks' validation J_S? (paper's training "
          "+ early stopping on the last 20 %, seeds 0–19)")
    held, valid = [], []
    for sd in range(20):
        fit = neural_narx(data.ident, seed=sd, holdout=0.2, **VARIANTS["paper: PE 60 epochs, D = 0"])
        held.append(fit.holdout_cost[fit.best_step])
        valid.append(row(fit.model, data)[1])
    print(f"Spearman rank correlation of held-out MSE and J_S valid: {spearmanr(held, valid).statistic:.2f}; "
          f"J_S valid median {np.median(valid):.3f} [{min(valid):.3f}–{max(valid):.3f}]", flush=True)
    print("\n## the paper's training epoch by epoch (seed 0; the first k epochs of one run)")
    print(" epochs   J_1 ident  J_S ident  J_S valid   J_SF")
    for k in (5, 10, 15, 20, 30, 40, 60):
        fit = neural_narx(data.ident, seed=0, epochs=k, sim_epochs=0, weight_decay=0.0)
        js_i, js_v, jsf, j1 = row(fit.model, data)
        print(f"{k:7d} {j1:10.4f} {js_i:10.3f} {js_v:10.3f} {jsf:7.3f}", flush=True)


def part_cv(data, seeds, decays=(0.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0), folds=5) -> None:
    """Weight decay by K-fold CV over contiguous blocks, chosen by the one-standard-error rule.

    The rule (Hastie, Tibshirani & Friedman, The Elements of Statistical Learning, §7.10): the
    largest D whose CV error is within one standard error of the lowest; the standard error is
    the spread of the per-fold errors (each averaged over the seeds) over √K.
    """
    rec = data.ident
    N = len(rec)
    edges = np.linspace(0, N, folds + 1).astype(int)
    print(f"## weight decay by {folds}-fold CV over contiguous blocks of the identification record "
          f"(free-run MSE of the held-out block, mlc²; seeds {list(seeds)})")
    print(f"{'D':>7s} {'CV error':>9s} {'std err':>8s}   per fold (mean over seeds)")
    cv, se = [], []
    for D in decays:
        per = np.empty((len(seeds), folds))
        for a, sd in enumerate(seeds):
            for f in range(folds):
                lo, hi = edges[f], edges[f + 1]
                train = [r for r in ((rec.slice(0, lo) if lo else None), (rec.slice(hi, N) if hi < N else None)) if r]
                m = neural_narx(train, seed=sd, weight_decay=D).model
                held = rec.slice(lo, hi)
                per[a, f] = mse(held.y, m.simulate(held, on_diverge="nan"), start=m.max_lag)
        fold = per.mean(0)
        cv.append(fold.mean())
        se.append(fold.std(ddof=1) / np.sqrt(folds))
        print(f"{D:7g} {cv[-1]:9.3f} {se[-1]:8.3f}   " + " ".join(f"{v:.3f}" for v in fold), flush=True)
    i = int(np.nanargmin(cv))
    pick = max(D for D, c in zip(decays, cv) if c <= cv[i] + se[i])
    print(f"lowest CV error at D = {decays[i]:g}; one-standard-error rule: D = {pick:g}")


def lsq_stage(residual, jacobian, x0, *, max_epochs, decay, heldout=None, patience=None, **lsq):
    """The same stage as graybox's ``_run_stage`` by ``scipy.optimize.least_squares``."""
    assert heldout is None and patience is None  # the comparison runs the default (no holdout)
    sq = np.sqrt(decay)
    cost = []

    def fun(x):
        r = residual(x)
        return np.concatenate([r, sq * x]) if sq else r

    def jac(x):
        J = jacobian(x)
        return np.vstack([J, sq * np.eye(x.size)]) if sq else J

    with threadpool_limits(limits=1, user_api="blas"):
        res = least_squares(fun, x0, jac=jac, max_nfev=max_epochs, ftol=1e-10, xtol=1e-10, gtol=1e-10, **lsq)
    cost.append(float(res.cost))
    return gn._Stage(res.x, int(res.nfev), cost, [], None, "epochs" if res.status == 0 else "converged")


OPTIMISERS = {
    "graybox LM (numba)": None,
    "least_squares trf, lsmr": dict(method="trf", tr_solver="lsmr", x_scale=1.0),
    "least_squares trf, lsmr, x_scale='jac'": dict(method="trf", tr_solver="lsmr", x_scale="jac"),
    "least_squares trf, exact": dict(method="trf", tr_solver="exact", x_scale=1.0),
    "least_squares lm (MINPACK)": dict(method="lm", x_scale="jac"),
}


def run_with(data, seed, lsq):
    orig = gn._run_stage
    if lsq is not None:
        gn._run_stage = lambda *a, **k: lsq_stage(*a, **k, **lsq)
    try:
        return neural_narx(data.ident, seed=seed)
    finally:
        gn._run_stage = orig


def part_optimiser(data, seeds, repeat) -> None:
    print(f"## optimisers in the default training (wall time: median of {repeat} runs per seed; "
          "final SE cost in normalised units, lower is better)")
    print(f"{'optimiser':40s} {'time s':>16s}  {'final SE cost':>26s}  {'JS_ident':>22s}  {'JS_valid':>22s}  {'JSF':>22s}")
    for label, lsq in OPTIMISERS.items():
        run_with(data, 0, lsq)  # JIT warm-up
        times, costs, rows = [], [], []
        for sd in seeds:
            ts = []
            for _ in range(repeat):
                t0 = time.perf_counter()
                fit = run_with(data, sd, lsq)
                ts.append(time.perf_counter() - t0)
            times.append(statistics.median(ts))
            costs.append(fit.simulation_cost[-1])
            rows.append(row(fit.model, data))
        print(f"{label:40s} {np.median(times):6.2f} [{min(times):.2f}–{max(times):.2f}]  "
              f"{np.median(costs):7.2f} [{min(costs):.2f}–{max(costs):.2f}]  {spread(rows)}  "
              f"(SE cost per seed: {' '.join(f'{c:.1f}' for c in costs)})", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--part", choices=("evidence", "cv", "optimiser", "all"), default="all")
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--cv-seeds", type=int, default=3)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    data = load_pumping()
    print(f"# bench_neural  {datetime.datetime.now():%Y-%m-%d %H:%M}  git {git_rev()}  {machine()}")
    seeds = range(args.seeds)
    if args.part in ("evidence", "all"):
        part_evidence(data, seeds)
    if args.part in ("cv", "all"):
        part_cv(data, range(args.cv_seeds))
    if args.part in ("optimiser", "all"):
        part_optimiser(data, seeds, args.repeat)


if __name__ == "__main__":
    main()
