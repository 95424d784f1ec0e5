"""Honest selection, variants of the choice (issue 26: the bundled plant's gap).

    .venv/bin/python benchmarks/bench_honest_variants.py [--cases plant,buck,...] [--folds] [--seeds]

Every job (structure × estimator) of ``select_graybox``'s default search on bench_honest's six
cases is fitted and scored once (fit on the identification record, 5 blocks of the validation
record, the untouched test record), then each variant of the choice is applied to the same scores.
Nothing a variant chooses with reads the test record. Variants:

- (a) more estimators per structure: SE with a stability margin 0.01 (``se_pareto(margin=0.01)``)
  and SE with a ridge towards least squares (``ridge=1``), beside PE and SE;
- (b) the choosing statistic: median or geometric mean over the blocks instead of the mean, a
  rule at 2 or 0.5 standard errors, ties of one size broken by the smaller J_SF (the default
  since this study) or by SE over PE;
- (c) ``--folds``: the validation blocks joined by 3 refitted folds of the identification record;
- (d) the chosen member refitted on identification + validation records (same λ1; the nearest
  in-band λ1 when the refit leaves the band), every row likewise for the regret;
- (e) the member of each front chosen by a one-standard-error rule towards the smaller J_SF.

``--dsf``: instead of the variants, each structure's D_SF model solved directly (``se_dsf`` on the
identification record, the case's band), scored on the validation and test records.

``--synthetic``: the tie-breaks of (b) on synthetic systems with a known answer (bench_honest's
system; identification 400 and validation 300 samples with inputs in [0, 1.5], test 3000 samples in
[0, 3], static points over [0, 3]: family A from the true curve, band 1e-2; family B 0.15 above it,
band 0.03, so that J_SF lies near the band as on the plant), 40 seeds each.

``--seeds``: the plant's rows on five fresh simulator runs (seeds + 1 … + 5), a diagnosis of the
gap (the first run is bench_honest's test record).

Per variant and case: gray test J_S / black-box test J_S (the black box chosen by the same variant
of the rule), the gray choice's regret, and whether issue 26's goal holds (≤ 1.1, regret ≤ 1.2,
J_SF of the test-scored model in the band).
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
import pandas as pd

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402
import bench_honest  # noqa: E402

import graybox as gb  # noqa: E402
from graybox.experiments import _select as S  # noqa: E402

SE_LAMBDAS = np.logspace(-2, 0, 8)  # select_graybox's SE front
EXTRA = {"se-margin": dict(margin=0.01), "se-ridge": dict(ridge=1.0)}
_plain_fit = S._fit


def _fit(job, st, rec):
    """select_graybox's fit, with the extra SE estimators of variant (a)."""
    if job.estimator not in EXTRA:
        return _plain_fit(job, st, rec)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            f = gb.se_pareto(st, rec, job.plan.static, lambdas=SE_LAMBDAS, progress=False, method="gradient",
                             **EXTRA[job.estimator])
        except ValueError:  # every member failed: a row without a model
            return np.full((len(SE_LAMBDAS), len(st)), np.nan), SE_LAMBDAS[::-1]
    th = np.array(f.thetas, float)
    th[list(f.failures)] = np.nan
    return th, np.asarray(f.lambdas, float)


S._fit = _fit  # the worker processes are forked after this line: they see it too


def _refit(args):
    """(d): the job's front refitted on identification + validation records; J_SF and test J_S per member."""
    terms, est, recs, static, test, L = args
    warnings.simplefilter("ignore")
    st = gb.Structure(terms.split(" + "))
    try:
        if est == "ls":
            th = np.asarray(gb.els(st, recs, noise=0).model.theta, float)[None]
        elif est == "els":
            m = gb.els(st, recs).model
            th = np.array([t for s, t in zip(m.structure, m.theta) if not s.is_noise], float)[None]
        elif est == "pe":
            th = gb.pe_thetas(st, recs, static, lambdas=np.logspace(-6, 0, 40), solver="closed")
        else:
            f = gb.se_pareto(st, recs, static, lambdas=SE_LAMBDAS, progress=False, method="gradient",
                             **EXTRA.get(est, {}))
            th = np.array(f.thetas, float)
            th[list(f.failures)] = np.nan
    except ValueError:
        return None
    return dict(jsf=S._jsf(st, th, static), test=S._block_mse(st, th, test, np.array([L, len(test)]))[:, 0])


def score(data, test, cand, band, folds: bool) -> dict:
    """Per kind (gray, black): the jobs and their scores (as select_graybox's), refits (d), folds (c)."""
    from graybox.experiments._map import parallel_map

    out = {}
    for kind, b, ests in (("gray", band, ("pe", "se-gradient", *EXTRA)), ("black", None, ("ls", "els"))):
        plan, degree = S._inputs(cand, data, None, None, test, b, 3, 5)
        rows = S._structures(cand, plan.ident, None, ("semp", "frols"), ("1",), degree)
        jobs = [S._Job(r["structure"], r["terms"], e, plan, None, ()) for r in rows for e in ests]
        run = dict(executor="processes", workers=2, client=None, scheduler=None, progress=False)
        D = dict(jobs=[(j.name, j.terms, j.estimator) for j in jobs], results=S._run_jobs(jobs, **run),
                 band=np.inf if b is None else b,
                 n=(len(data.valid) - plan.lag, len(data.ident) - 3 * plan.lag))  # choosing samples: blocks, folds
        args = [(j.terms, j.estimator, [data.ident, data.valid], data.static, test, plan.lag) for j in jobs]
        with parallel_map(executor="processes", workers=2) as pmap:
            D["refit"] = pmap(_refit, args)
        if folds:
            fplan, _ = S._inputs(cand, data.ident, data.static, None, None, b, 3, 5)
            D["folds"] = S._run_jobs([S._Job(j.name, j.terms, j.estimator, fplan, None, ()) for j in jobs], **run)
        out[kind] = D
    return out


# -- the variants of the choice (the rule of graybox.experiments._select, re-stated with its options) --

def _stat(B: np.ndarray, w: np.ndarray, stat: str) -> np.ndarray:
    if stat == "median":
        return np.median(B, axis=-1)
    if stat == "geo":
        with np.errstate(divide="ignore"):
            return np.exp(np.log(B).mean(axis=-1))
    return B @ w


def _member(r: dict, band: float, stat: str, member_se: bool) -> int:
    B = r["blocks"]
    js = _stat(B, r["weights"], stat)
    inside = np.isfinite(B).all(axis=1) & np.isfinite(js) & (r["jsf"] <= band)
    if not inside.any():
        return -1
    c = np.flatnonzero(inside)
    best = int(c[np.lexsort((c, r["jsf"][c], js[c]))[0]])
    if not member_se:
        return best
    with np.errstate(all="ignore"):
        lr = np.log(B[c] / B[best])
    near = c[(lr.mean(1) <= lr.std(1, ddof=1) / np.sqrt(B.shape[1])) | (c == best)]
    return int(near[np.argmin(r["jsf"][near])])


def _joined(D: dict) -> dict:
    """(c): each job's validation blocks and identification folds side by side, weighted by samples."""
    res = []
    for r, f in zip(D["results"], D["folds"]):
        w = np.concatenate([r["weights"] * D["n"][0], f["weights"] * D["n"][1]])
        res.append(dict(r, blocks=np.concatenate([r["blocks"], f["blocks"]], axis=1), weights=w / w.sum(),
                        jsf=np.maximum(r["jsf"], f["jsf"])))
    return dict(D, results=res)


def choose(D: dict, *, ests=None, stat="mean", k=1.0, tie="js", member_se=False, refit=False, folds=False):
    """(table of the rows' chosen members, position of the choice)."""
    if folds:
        D = _joined(D)
    band, rows = D["band"], []
    for (name, terms, est), r, rf in zip(D["jobs"], D["results"], D["refit"]):
        if ests is not None and est not in ests:
            continue
        i = _member(r, band, stat, member_se)
        if i < 0:
            continue
        test, jsf_test = r["test"][i], r["jsf"][i]
        if refit:
            test, jsf_test = np.inf, np.inf
            if rf is not None:
                j, ok = i, np.flatnonzero(rf["jsf"] <= band)
                if not rf["jsf"][j] <= band and ok.size:
                    j = int(ok[np.argmin(np.abs(ok - j))])
                test, jsf_test = rf["test"][j], rf["jsf"][j]
        rows.append(dict(row=name, est=est, n=terms.count(" + ") + 1, blocks=r["blocks"][i],
                         js=_stat(r["blocks"][i], r["weights"], stat), jsf=r["jsf"][i], test=test, jsf_test=jsf_test))
    t = pd.DataFrame(rows)
    B = np.stack(t["blocks"].to_numpy())
    js = t["js"].to_numpy(float)
    best = int(np.argmin(js))
    with np.errstate(all="ignore"):
        lr = np.log(B / B[best])
    eligible = (lr.mean(1) <= k * lr.std(1, ddof=1) / np.sqrt(B.shape[1])) | (np.arange(len(t)) == best)
    key = {"js": js, "jsf": t["jsf"].to_numpy(float) if np.isfinite(band) else js,
           "se": np.array([0.0 if e.startswith("se") else 1.0 for e in t["est"]])}[tie]
    c = np.flatnonzero(eligible)
    return t, int(c[np.lexsort((js[c], key[c], t["n"].to_numpy()[c]))[0]])


GRAY = ("pe", "se-gradient")
VARIANTS = {
    "default (select_graybox's rule)": dict(ests=GRAY),
    "(b) tie of one size: smaller J_SF": dict(ests=GRAY, tie="jsf"),
    "(b) tie of one size: SE over PE": dict(ests=GRAY, tie="se"),
    "(b) median over the blocks": dict(ests=GRAY, stat="median"),
    "(b) geometric mean over the blocks": dict(ests=GRAY, stat="geo"),
    "(b) within 2 standard errors": dict(ests=GRAY, k=2.0),
    "(b) within 0.5 standard error": dict(ests=GRAY, k=0.5),
    "(a) + SE with margin 0.01": dict(ests=GRAY + ("se-margin",)),
    "(a) + SE with margin 0.01 and SE with ridge 1": dict(ests=GRAY + tuple(EXTRA)),
    "(a) PE and SE with margin 0.01 (no plain SE)": dict(ests=("pe", "se-margin")),
    "(c) validation blocks + 3 identification folds": dict(ests=GRAY, folds=True),
    "(d) refit on identification + validation": dict(ests=GRAY, refit=True),
    "(e) member: one standard error towards smaller J_SF": dict(ests=GRAY, member_se=True),
}
BLACK_KEYS = ("stat", "k", "refit", "folds")  # the black box is chosen by the same variant of the rule


def evaluate(scores: dict, with_folds: bool) -> pd.DataFrame:
    out = []
    for label, kw in VARIANTS.items():
        if kw.get("folds") and not with_folds:
            continue
        for case, (d, band) in scores.items():
            g, cg = choose(d["gray"], **kw)
            b, cb = choose(d["black"], **{k: v for k, v in kw.items() if k in BLACK_KEYS})
            gt, bt = g["test"].iloc[cg], b["test"].iloc[cb]
            regret = gt / g["test"].min()
            ok = bool(gt / bt <= 1.1 and regret <= 1.2 and g["jsf_test"].iloc[cg] <= band)
            out.append(dict(variant=label, case=case, choice=f"{g['row'].iloc[cg]} {g['est'].iloc[cg]}",
                            JS_test=gt, vs_black=gt / bt, regret=regret, goal=ok))
    return pd.DataFrame(out)


def seeds(d: dict) -> None:
    """The plant's rows (their members chosen on the validation record) on five fresh simulator runs."""
    from graybox.datasets import pumping

    plant = gb.load_pumping()
    runs = [pumping.generate(seed=plant.extra["seed"] + s)[0].record(f"seed + {s}") for s in range(1, 6)]
    def five(st, r, i):
        return [S._block_mse(st, r["thetas"][i:i + 1], rec, np.array([st.max_lag, len(rec)]))[0, 0] for rec in runs]

    rows, near = [], []
    black = min(r["test"][0] for r in d["black"]["results"] if np.isfinite(r["test"][0]))
    for kind in ("gray", "black"):
        D = d[kind]
        for (name, terms, est), r in zip(D["jobs"], D["results"]):
            i = _member(r, D["band"], "mean", False)
            if i < 0:
                continue
            st = gb.Structure(terms.split(" + "))
            t = five(st, r, i)
            rows.append(dict(kind=kind, row=f"{name} {est}", JS_valid=float(r["blocks"][i] @ r["weights"]),
                             **{f"+{s}": v for s, v in enumerate(t, 1)}, mean=float(np.mean(t))))
            if kind == "gray":  # every in-band member within 1.1× of the black box on the first run
                js = r["blocks"] @ r["weights"]
                for j in np.flatnonzero((r["jsf"] <= D["band"]) & (r["test"] <= 1.1 * black)):
                    t = five(st, r, j)
                    near.append(dict(row=f"{name} {est}", member=int(j), lambda1=r["lambdas"][j], JS_valid=js[j],
                                     row_DSF_JS_valid=js[i], **{f"+{s}": v for s, v in enumerate(t, 1)},
                                     mean=float(np.mean(t))))
    n_in = sum(int(np.sum(r["jsf"] <= d["gray"]["band"])) for r in d["gray"]["results"])
    gray_rows = [x for x in rows if x["kind"] == "gray"]
    print(f"\ngray rows with an in-band member: {len(gray_rows)}; their D_SF members' best test J_S (+1): "
          f"{min(x['+1'] for x in gray_rows):.4g}, 1.1 × the black box's best: {1.1 * black:.4g}; in-band members "
          f"of all fronts: {n_in}, within 1.1× on the first run: {len(near)}")
    if near:
        print(pd.DataFrame(near).to_markdown(index=False, floatfmt=".4g"))
    df = pd.DataFrame(rows).sort_values(["kind", "mean"])
    print("\nThe plant's rows on five fresh runs (the D_SF member chosen on the validation record):")
    print(df.to_markdown(index=False, floatfmt=".3f"))
    black = df[df["kind"] == "black"]["mean"].min()
    print(f"best gray mean / best black mean: {df[df['kind'] == 'gray']['mean'].min() / black:.3f}")


def dsf(name, data, test, cand, band) -> None:
    """Each distinct structure of the gray search fitted by se_dsf (min J_S s.t. J_SF ≤ B) on the identification record."""
    plan, degree = S._inputs(cand, data, None, None, test, band, 3, 5)
    rows = []
    for r in S._structures(cand, plan.ident, None, ("semp", "frols"), ("1",), degree):
        st = gb.Structure(r["terms"].split(" + "))
        try:
            m = gb.se_dsf(st, data.ident, data.static, band=band)
        except ValueError as e:
            rows.append(dict(row=r["structure"], n_terms=len(st), note=str(e)[:60]))
            continue
        th = np.asarray(m.model.theta, float)[None]
        rows.append(dict(row=r["structure"], n_terms=len(st), JS_ident=m.JS, JSF=m.JSF,
                         JS_valid=S._block_mse(st, th, data.valid, np.array([plan.lag, len(data.valid)]))[0, 0],
                         JS_test=S._block_mse(st, th, test, np.array([plan.lag, len(test)]))[0, 0]))
    print(f"\n{name}: se_dsf per structure\n")
    print(pd.DataFrame(rows).to_markdown(index=False, floatfmt=".4g"))


def synthetic(seeds: int = 40) -> None:
    """Among the eligible rows of the fewest terms: the test J_S of the J_SF and SE-over-PE tie-breaks
    against the J_S tie-break (select_graybox's), counted over the seeds where more than one row ties."""
    truth = gb.Model(bench_honest.TRUE, bench_honest.THETA)

    def rec(seed, n, hi):
        rng = np.random.default_rng(seed)
        u = np.repeat(rng.uniform(0.0, hi, n // 25 + 1), 25)[:n]
        return gb.Record(u, truth.simulate(u, np.zeros(2)) + 0.05 * rng.standard_normal(n), name=f"synthetic {seed}")

    ub = np.linspace(0.0, 3.0, 7)
    rows = []
    for family, bias, band in (("A: true static points", 0.0, 1e-2), ("B: static points 0.15 off", 0.15, 0.03)):
        sp = gb.StaticPoints(ub, truth.static_curve(ub) + bias)
        for seed in range(seeds):
            data = gb.Dataset(rec(10 * seed, 400, 1.5), rec(10 * seed + 1, 300, 1.5), sp)
            try:
                t = gb.select_graybox(gb.Candidates(2, 2, degree=2), data, band=band, sizes=[3, 4, 5, 6],
                                      test=rec(10 * seed + 2, 3000, 3.0)).table
            except ValueError:  # no structure in the band
                continue
            el = t[t["eligible"]]
            tied = el[el["n_terms"] == el["n_terms"].min()]
            if len(tied) < 2:
                continue
            by_js = tied.sort_values("JS_valid").iloc[0]["JS_test"]
            by_jsf = tied.sort_values(["JSF", "JS_valid"]).iloc[0]["JS_test"]
            se = tied.assign(pe=tied["estimator"] == "pe").sort_values(["pe", "JS_valid"]).iloc[0]["JS_test"]
            rows.append(dict(family=family, seed=seed, tied=len(tied), JS=by_js, JSF=by_jsf, SE=se))
    df = pd.DataFrame(rows)
    out = []
    for family, g in df.groupby("family"):
        for key in ("JSF", "SE"):
            r = g[key] / g["JS"]
            out.append({"family": family, "tie-break": key, "seeds with a tie": len(g), "better": int((r < 1).sum()),
                        "worse": int((r > 1).sum()), "equal": int((r == 1).sum()),
                        "geometric mean test J_S / J_S tie's": float(np.exp(np.log(r).mean()))})
    print(f"\nsynthetic, {seeds} seeds per family: the tie-breaks against the J_S tie (test J_S)\n")
    print(pd.DataFrame(out).to_markdown(index=False, floatfmt=".3f"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--cases", default="", help="comma-separated case names (default all)")
    ap.add_argument("--folds", action="store_true", help="variant (c): 3 refitted folds per job (4× the fits)")
    ap.add_argument("--seeds", action="store_true", help="the plant's rows on five fresh runs")
    ap.add_argument("--dsf", action="store_true", help="se_dsf per structure instead of the variants")
    ap.add_argument("--synthetic", action="store_true", help="only the tie-breaks on synthetic systems")
    args = ap.parse_args()
    names = [c for c in args.cases.split(",") if c]
    print(f"# bench_honest_variants ({datetime.date.today()}, git {git_rev()}): {machine()}")
    warnings.simplefilter("ignore")
    if args.synthetic:
        synthetic()
        return
    scores = {}
    for name, (data, test, cand, band) in bench_honest.cases().items():
        if names and name not in names:
            continue
        if args.dsf:
            dsf(name, data, test, cand, band)
            continue
        t0 = time.perf_counter()
        scores[name] = (score(data, test, cand, band, args.folds), band)
        print(f"{name}: scored in {time.perf_counter() - t0:.0f} s (load {os.getloadavg()[0]:.1f})", flush=True)
    if args.dsf:
        return
    df = evaluate(scores, args.folds)
    wide = df.assign(cell=[f"{v:.3g} ({r:.3g}){'' if g else ' ✗'}" for v, r, g in
                           zip(df["vs_black"], df["regret"], df["goal"])])
    table = wide.pivot(index="variant", columns="case", values="cell").reindex(
        [v for v in VARIANTS if v in set(df["variant"])])[list(scores)]
    table.insert(0, "goal met", df.groupby("variant")["goal"].sum().reindex(table.index).astype(int))
    print("\ngray test J_S / black box's (regret); ✗: goal missed\n")
    print(table.to_markdown())
    print("\nthe choices\n")
    print(df.pivot(index="variant", columns="case", values="choice").reindex(table.index)[list(scores)].to_markdown())
    if args.seeds and "plant" in scores:
        seeds(scores["plant"][0])


if __name__ == "__main__":
    main()
