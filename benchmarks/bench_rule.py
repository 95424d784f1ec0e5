"""The choosing rule of select_graybox against alternatives, on the same scores (issue 26).

    .venv/bin/python benchmarks/bench_rule.py [--cases plant,buck,...] [--tank-draws 3]
    .venv/bin/python benchmarks/bench_rule.py --first-draw 8 --tank-draws 8 --synthetic-draws 4   # fresh draws
    .venv/bin/python benchmarks/bench_rule.py ... --dump seen.json; ... --analyse seen.json --taus 0,1,2

Each case of bench_honest (and more draws of its cascaded tanks) runs ``select_graybox`` once for the gray box
(the case's band) and once for the black box (no band), fit on identification, choose on the validation record's
blocks, test untouched; the rule's inputs (each row's per-block J_S of its chosen member) are captured and every
rule below applied to them. Nothing a rule chooses with reads the test record. Rules (eligible rows, then the
fewest terms, ties by the smaller validation J_S):

- ``log``: the mean per-block log ratio to the best row within its standard error (select_graybox's one-se
  before 2026-11-29);
- ``arith``: the mean per-block difference to the best row's J_S within its standard error (J_S's own scale);
- ``log+arith``: both;
- ``ratio``: log(J_S / best J_S) of the whole record within the per-block log ratios' standard error;
- ``ratio-delta``: the same, the standard error of log(J_S / best J_S) by the delta method over the blocks
  (select_graybox's one-se since 2026-11-29; blocks of equal length here: its divisor 1 − Σ w² is n / (n − 1));
- ``best's se``: J_S within one standard error of the best row's own J_S over the blocks (Breiman's);
- ``min``: the smallest validation J_S.
"""

from __future__ import annotations

import argparse
import datetime
import json
import sys
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402
import bench_honest  # noqa: E402

import graybox as gb  # noqa: E402
from graybox.experiments import _select as S  # noqa: E402

CAUGHT: list = []
_table, _choose = S._table, S._choose


def _caught_table(rows, jobs, results, plan):
    out = _table(rows, jobs, results, plan)
    CAUGHT.append(dict(weights=np.asarray(results[0]["weights"], float)))
    return out


def _caught_choose(table, scores, weights, rule):
    CAUGHT[-1].update(scores=[np.asarray(s, float) for s in scores], table=table[["estimator", "n_terms",
                      "JS_valid", "in_band"]].copy())
    return _choose(table, scores, weights, rule)


S._table, S._choose = _caught_table, _caught_choose


def eligible(rule: str, B: np.ndarray, w: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """Eligible rows (bool) among the in-band ``ok`` rows from their (rows, blocks) J_S."""
    js = B @ w
    best = int(np.flatnonzero(ok)[np.argmin(js[ok])])
    n = B.shape[1]
    with np.errstate(all="ignore"):
        lr = np.log(B / B[best])
        log_ok = lr.mean(1) <= np.nan_to_num(lr.std(1, ddof=1) / np.sqrt(n))
        d = B - B[best]
        arith_ok = d @ w <= np.nan_to_num(d.std(1, ddof=1) / np.sqrt(n))
        ratio_ok = np.log(js / js[best]) <= np.nan_to_num(lr.std(1, ddof=1) / np.sqrt(n))
        # the delta method's standard error of log(mean a / mean b) over the blocks
        z = B / js[:, None] - B[best] / js[best]
        delta_ok = np.log(js / js[best]) <= np.nan_to_num(np.sqrt(((w * z) ** 2).sum(1) / (1 - w @ w)))
    e = {"log": log_ok, "arith": arith_ok, "log+arith": log_ok & arith_ok, "ratio": ratio_ok, "ratio-delta": delta_ok,
         "best's se": js <= js[best] + B[best].std(ddof=1) / np.sqrt(n), "min": js == js[best]}[rule]
    e = e & ok & np.isfinite(js)
    e[best] = True
    return e


RULES = ("log", "arith", "log+arith", "ratio", "ratio-delta", "best's se", "min")


def slowest_mode(g: gb.GrayboxSelection, data: gb.Dataset, levels: int = 11) -> np.ndarray:
    """(rows,) each row's slowest settling time constant in samples, −1 / ln ρ, over ``levels`` operating points of
    the identification and validation records' inputs (quantiles, each input alike): at each point the most
    stable equilibrium's spectral radius ρ; inf where ρ ≥ 1 or a point has no equilibrium; NaN: no model."""
    u = np.concatenate([np.asarray(r.u, float).reshape(len(r), -1) for r in (data.ident, data.valid)])
    points = np.quantile(u, np.linspace(0.02, 0.98, levels), axis=0)
    out = []
    for row, est in zip(g.table.index, g.table["estimator"]):
        try:
            m = g.model_of(row, est)
        except ValueError:
            out.append(np.nan)
            continue
        rho = 0.0
        for pt in points:
            try:
                eq = m.equilibria(pt[0] if pt.size == 1 else pt)
            except ValueError:
                eq = []
            rho = max(rho, min((e.spectral_radius for e in eq), default=np.inf))
        out.append(np.inf if rho >= 1 else -1 / np.log(rho) if rho > 0 else 0.0)
    return np.array(out)


def choose(table: pd.DataFrame, cap: dict, rule: str, tau_max: float = np.inf) -> int:
    """The row ``rule`` chooses; rows whose slowest mode is longer than ``tau_max`` samples are left out (unless
    every in-band row is)."""
    B = np.stack(cap["scores"])
    ok = table["in_band"].to_numpy(bool)
    if np.isfinite(tau_max):
        judged = ok & (table["tau"].to_numpy(float) <= tau_max)
        ok = judged if judged.any() else ok
    e = np.flatnonzero(eligible(rule, B, cap["weights"], ok))
    return int(e[np.lexsort((table["JS_valid"].to_numpy(float)[e], table["n_terms"].to_numpy()[e]))[0]])


def synthetic_case(name: str, k: int):
    """Draw k of one of bench_honest's synthetic cases: its seeds + 100 k."""
    h, s = bench_honest, 100 * k
    if name == "short records (45 candidates)":
        return (gb.Dataset(h._synthetic(1 + s, 300), h._synthetic(2 + s, 150), h._true_points()),
                h._synthetic(3 + s, 4000), gb.Candidates(4, 4, degree=2), 1e-3)
    if name == "slow disturbance":
        return (gb.Dataset(h._synthetic(4 + s, 1200, drift=0.3), h._synthetic(5 + s, 600, drift=0.3), h._true_points()),
                h._synthetic(6 + s, 4000, drift=0.3), gb.Candidates(3, 3, degree=2), 1e-3)
    return (gb.Dataset(h._synthetic(7 + s, 1200), h._synthetic(8 + s, 600), h._true_points(0.15)),
            h._synthetic(9 + s, 4000), gb.Candidates(3, 3, degree=2), 0.03)


SYNTHETIC = ("short records (45 candidates)", "slow disturbance", "static points off the records")


def tank_case(k: int):
    s = 10 * k + 1
    data = gb.Dataset(bench_honest._tanks(s, 1200), bench_honest._tanks(s + 1, 600), bench_honest._tank_points())
    return data, bench_honest._tanks(s + 2, 1500), gb.Candidates(3, 3, degree=3), 25.0


def scored(gt: pd.DataFrame, bt: pd.DataFrame, i: int, j: int) -> dict:
    """The test figures of gray row ``i`` and black row ``j`` (positions): each row as text, the gray box's test J_S
    over the black box's, each choice's regret (its test J_S over the best among the rows it was compared with: the
    in-band ones for the gray box), and issue 26's goal."""
    tg, tb = gt["JS_test"].to_numpy(float), bt["JS_test"].to_numpy(float)
    inb = gt["in_band"].to_numpy(bool)
    regret = tg[i] / tg[inb & np.isfinite(tg)].min()
    return dict(gray=f"{gt.iloc[i]['n_terms']} {gt.iloc[i]['estimator']}",
                black=f"{bt.iloc[j]['n_terms']} {bt.iloc[j]['estimator']}",
                vs_black=tg[i] / tb[j], regret=regret, black_regret=tb[j] / tb[np.isfinite(tb)].min(),
                goal=bool(tg[i] / tb[j] <= 1.1 and regret <= 1.2 and inb[i]))


def analyse(paths: list[str], taus: list[float], rule: str = "ratio-delta") -> None:
    """The rule on dumped cases with rows slower than tau validation records left out, for each tau (0: none)."""
    out = []
    for path in paths:
        for name, boxes in json.loads(Path(path).read_text()).items():
            tables = {b: pd.DataFrame(x["table"]) for b, x in boxes.items()}
            caps = {b: dict(scores=list(np.array(x["scores"], float)), weights=np.array(x["weights"], float))
                    for b, x in boxes.items()}
            n_valid = boxes["gray"]["n_valid"]
            for tau in taus:
                tau_max = tau * n_valid if tau else np.inf
                i, j = (choose(tables[b], caps[b], rule, tau_max) for b in ("gray", "black"))
                out.append(dict(case=name, family=name.split(", draw")[0], tau=tau,
                                **scored(tables["gray"], tables["black"], i, j)))
    df = pd.DataFrame(out)
    for col in ("regret", "black_regret", "vs_black"):
        t = np.exp(np.log(df[col]).groupby([df.tau, df.family]).mean()).unstack()
        t.insert(0, "all cases", np.exp(np.log(df[col]).groupby(df.tau).mean()))
        print(f"\nGeometric means, {col}, {rule} with rows slower than tau validation records left out:\n"
              + t.to_markdown(floatfmt=".3f"))
    print("\ngoal met:", df.groupby("tau")["goal"].sum().to_dict(), "of", df.case.nunique())
    moved = df.pivot(index="case", columns="tau", values="gray")
    moved_b = df.pivot(index="case", columns="tau", values="black")
    print("\ncases whose choice moves with tau (gray | black):")
    for c in moved.index:
        if moved.loc[c].nunique() > 1 or moved_b.loc[c].nunique() > 1:
            print(f"  {c}: " + "; ".join(f"{t}: {moved.loc[c, t]} | {moved_b.loc[c, t]}" for t in moved.columns))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", default="", help="comma-separated case names (default: all)")
    ap.add_argument("--tank-draws", type=int, default=3, help="draws of the cascaded tanks (bench_honest's the first)")
    ap.add_argument("--blocks", type=int, default=None, help="select_graybox's blocks= (default: its own, 5)")
    ap.add_argument("--synthetic-draws", type=int, default=1, help="draws of each synthetic case (likewise)")
    ap.add_argument("--first-draw", type=int, default=0,
                    help="0: bench_honest's cases and the draws after them; k > 0: only fresh draws k, k + 1, … of the "
                         "tanks and the synthetic cases (seeds no rule was chosen on: the rule landed on draws < 8)")
    ap.add_argument("--tau", type=float, default=0.0,
                    help="leave out rows whose slowest mode (samples, over the records' operating points) is longer "
                         "than this many validation records (0: keep every row)")
    ap.add_argument("--dump", default="", help="write each case's captured rows, scores and slowest modes (JSON)")
    ap.add_argument("--analyse", default="", help="comma-separated dumps: apply the library's rule to them at each "
                    "--taus value and print the regrets (runs no selection)")
    ap.add_argument("--taus", default="0,0.5,1,2,4", help="with --analyse: the values of --tau to compare")
    args = ap.parse_args()
    if args.analyse:
        analyse(args.analyse.split(","), [float(t) for t in args.taus.split(",")])
        return
    dumped: dict = {}
    names = [c for c in args.cases.split(",") if c]
    print(f"# bench_rule ({datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, git {git_rev()}, "
          f"blocks={args.blocks}, tau={args.tau}): {machine()}", flush=True)
    warnings.simplefilter("ignore")
    first = max(args.first_draw, 1)
    cases = bench_honest.cases() if args.first_draw == 0 else {}
    for k in range(first, first + args.tank_draws - (args.first_draw == 0)):
        cases[f"cascaded tanks, draw {k + 1}"] = tank_case(k)
    for name in SYNTHETIC:
        for k in range(first, first + args.synthetic_draws - (args.first_draw == 0)):
            cases[f"{name}, draw {k + 1}"] = synthetic_case(name, k)
    out = []
    for name, (data, test, cand, band) in cases.items():
        if names and name not in names:
            continue
        sel = {}
        for box, b in (("gray", band), ("black", np.inf)):
            CAUGHT.clear()
            g = gb.select_graybox(cand, data, band=b, test=test, executor="processes", workers=2, blocks=args.blocks)
            cap = CAUGHT[-1]
            cap["library"] = f"{g.chosen['n_terms']} {g.chosen['estimator']}"
            t = cap["table"].set_index("estimator", append=True)
            t["JS_test"] = g.table.set_index("estimator", append=True)["JS_test"].reindex(t.index).to_numpy()
            if args.tau or args.dump:
                t["tau"] = pd.Series(slowest_mode(g, data), index=g.table.set_index("estimator", append=True).index
                                     ).reindex(t.index).to_numpy()
            sel[box] = (t.reset_index(level="estimator"), cap)
        if args.dump:
            dumped[name] = {box: dict(table=t.to_dict(orient="list"), scores=np.stack(c["scores"]).tolist(),
                                      weights=c["weights"].tolist(), n_valid=len(data.valid))
                            for box, (t, c) in sel.items()}
            Path(args.dump).write_text(json.dumps(dumped, allow_nan=True))
        for rule in RULES:
            (gt, gc), (bt, bc) = sel["gray"], sel["black"]
            tau_max = args.tau * len(data.valid) if args.tau else np.inf
            i, j = choose(gt, gc, rule, tau_max), choose(bt, bc, rule, tau_max)
            out.append(dict(case=name, rule=rule, library=gc["library"], **scored(gt, bt, i, j)))
        print(pd.DataFrame(out[-len(RULES):]).to_string(index=False), flush=True)
    df = pd.DataFrame(out)
    df["cell"] = [f"{v:.3g} ({r:.3g}){'' if g else ' ✗'}" for v, r, g in zip(df.vs_black, df.regret, df.goal)]
    wide = df.pivot(index="rule", columns="case", values="cell").reindex(list(RULES))
    wide.insert(0, "goal met", df.groupby("rule")["goal"].sum().reindex(list(RULES)).astype(int))
    gm = df.assign(lv=np.log(df.vs_black), lr=np.log(df.regret)).groupby("rule")[["lv", "lr"]].mean()
    wide.insert(1, "geo. mean vs black", np.exp(gm["lv"]).reindex(list(RULES)).round(3))
    wide.insert(2, "geo. mean regret", np.exp(gm["lr"]).reindex(list(RULES)).round(3))
    print("\n" + wide.to_markdown())
    df["family"] = df["case"].str.split(", draw").str[0]
    fam = df.assign(g=np.log(df.regret), b=np.log(df.black_regret), v=np.log(df.vs_black)).groupby(["rule", "family"])
    for col, what in (("g", "gray regret"), ("b", "black regret"), ("v", "gray / black")):
        t = np.exp(fam[col].mean()).unstack().reindex(list(RULES))
        t.insert(0, "all cases", np.exp(df.assign(x=np.log(df[{"g": "regret", "b": "black_regret",
                                                                 "v": "vs_black"}[col]])).groupby("rule")["x"].mean()))
        print(f"\nGeometric means over the draws, {what}:\n" + t.to_markdown(floatfmt=".3f"))
    print("\n" + df.pivot(index="rule", columns="case", values="gray").reindex(list(RULES)).to_markdown())


if __name__ == "__main__":
    main()
