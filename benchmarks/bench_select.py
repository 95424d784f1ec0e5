"""Structure selection for gray-box use: semp and select_graybox against FROLS (issue 12).

    .venv/bin/python benchmarks/bench_select.py [--workers 2] [--part speed|tables|staircase|dsf|all]

- speed: FROLS, ``semp`` (91 candidates: degree 2, lags 6; 3200 samples; to 17 terms) and
  ``select_graybox`` over the same space (in-process and with N Dask workers);
- tables: on the bundled plant and the buck converter, the D_SF model of the selected structure
  against the FROLS + ELS model of the same size (J_S ident / valid, J_SF, N_p);
- staircase: noise-free NARX systems under staircase inputs, FROLS against semp (true structure
  recovered or not);
- dsf: ``se_dsf`` against sweep + D_SF (the GA and the gradient method) on ten structures.
"""

from __future__ import annotations

import argparse
import datetime
import functools
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402

import graybox as gb  # noqa: E402

BANDS = {"pumping": 0.031, "buck": 0.01}


def wall(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def speed(workers: int) -> None:
    data = gb.load_pumping()
    cand = gb.Candidates(6, 6, degree=2)
    gb.frols(cand, data, n_terms=17)
    _, t_frols = wall(lambda: gb.frols(cand, data, n_terms=17))
    gb.semp(gb.Candidates(2, 2, degree=2), data, n_terms=3)  # compile
    _, t_semp = wall(lambda: gb.semp(cand, data, n_terms=17))
    _, t_sel_pe = wall(lambda: gb.select_graybox(cand, data, band=0.031, estimator="pe"))
    _, t_sel = wall(lambda: gb.select_graybox(cand, data, band=0.031))
    _, t_sel_dask = wall(lambda: gb.select_graybox(cand, data, band=0.031, workers=workers))
    print("| step | time |\n| --- | --- |")
    print(f"| FROLS, 91 candidates -> 17 terms | {t_frols:.3f} s |")
    print(f"| semp, 91 candidates -> 17 terms (1 thread) | {t_semp:.2f} s |")
    print(f"| select_graybox (semp + FROLS, sizes 4..20, PE fronts), in-process | {t_sel_pe:.1f} s |")
    print(f"| select_graybox (default: PE and SE-gradient fronts), in-process | {t_sel:.1f} s |")
    print(f"| select_graybox (default), {workers} Dask workers (LocalCluster start included) | {t_sel_dask:.1f} s |")


#: Per data set: loader, candidate lags, structure sizes of the selection tables.
SELECTION_CASES = {"pumping": (gb.load_pumping, dict(ny=6, nu=6), None),
                   "buck": (gb.load_buck, dict(ny=2, nu=2), (2, 3, 4, 5, 6))}


@functools.lru_cache(maxsize=None)
def selection(name: str, est: str | tuple[str, ...]) -> gb.GrayboxSelection:
    """select_graybox on a bundled data set (once per run: the tables and the dsf part share it)."""
    load, cand_kw, sizes = SELECTION_CASES[name]
    return gb.select_graybox(gb.Candidates(**cand_kw, degree=2), load(), band=BANDS[name], estimator=est,
                             sizes=None if sizes is None else list(sizes))


def tables() -> None:
    for name, (load, cand_kw, _) in SELECTION_CASES.items():
        data = load()
        band = BANDS[name]
        for est in ("pe", "se-gradient", ("pe", "se-gradient")):
            res = selection(name, est)
            est = "+".join(est) if isinstance(est, tuple) else est
            k = len(res.structure)
            sel = gb.frols(gb.Candidates(**cand_kw, ne=2, degree=2), data, n_terms=k)
            els = gb.els(sel, data).model
            tab = gb.evaluate({f"select_graybox ({est}) D_SF": res.model, f"FROLS + ELS, {k} terms": els}, data)
            print(f"\n{name}, band {band}, estimator {est}: {res.structure}")
            print(tab[["JS_ident", "JS_valid", "JSF", "n_params"]].to_string(float_format=lambda v: f"{v:.4f}"))


def staircase() -> None:
    systems = {
        "A": (["y(k-1)", "y(k-2)", "u(k-2)", "u(k-1)y(k-1)", "u(k-2)^2", "1"], [0.5, 0.3, 0.4, -0.2, 0.15, 0.1]),
        "C": (["y(k-1)", "u(k-1)", "u(k-2)", "u(k-2)y(k-1)", "1"], [0.6, 0.3, 0.2, -0.1, 0.05]),
        "D": (["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)^2"], [1.2, -0.4, 0.2, 0.1]),
    }
    rows = []
    for name, (terms, th) in systems.items():
        st = gb.Structure(terms)
        for hold in (5, 10, 20):
            for seed in range(3):
                rng = np.random.default_rng(seed)
                u = np.repeat(rng.uniform(-1, 1, 1000 // hold + 1), hold)[:1000]
                rec = gb.Record(u, gb.Model(st, th).simulate(u, np.zeros(st.max_lag)))
                cand = gb.Candidates(3, 3, degree=2)
                f = gb.frols(cand, rec, n_terms=len(st))
                s = gb.semp(cand, rec, n_terms=len(st))
                b = gb.semp(cand, rec)
                rows.append({"system": name, "hold": hold, "seed": seed, "frols": set(f.structure) == set(st),
                             "semp n_terms": set(s.structure) == set(st), "semp BIC": set(b.structure) == set(st)})
    df = pd.DataFrame(rows)
    print(df.groupby("system")[["frols", "semp n_terms", "semp BIC"]].sum().to_string())
    print(f"(of {len(df) // len(systems)} records per system)")


def dsf_cases():
    """(name, data, structure, band): FROLS structures of several sizes on both data sets, and the
    structure select_graybox chooses on the plant."""
    plant = gb.load_pumping()
    for label, cand, sizes in (("6", gb.Candidates(6, 6, ne=2, degree=2, max_y_power=1), (10, 13, 17, 20)),
                               ("3", gb.Candidates(3, 3, degree=2, max_y_power=1), (6, 9))):
        for k in sizes:
            yield f"plant, lags {label}, {k} terms", plant, gb.frols(cand, plant, n_terms=k, include=["1"]).structure, \
                BANDS["pumping"]
    # the structure select_graybox chooses on the plant (the tables above): a case a user meets
    chosen = selection("pumping", ("pe", "se-gradient")).structure
    yield f"plant, chosen by select_graybox, {len(chosen)} terms", plant, chosen, BANDS["pumping"]
    buck = gb.load_buck()
    for k in (4, 6, 8):
        st = gb.frols(gb.Candidates(2, 2, degree=2, max_y_power=1), buck, n_terms=k, include=["1"]).structure
        if gb.parse_term("u(k-1)") not in st:
            st = st + gb.parse_structure(["u(k-1)"])
        yield f"buck, lags 2, {len(st)} terms", buck, st, BANDS["buck"]


def dsf() -> None:
    """se_dsf against sweep + D_SF on the structures of :func:`dsf_cases`.

    The sweeps: the gradient method on 30 and on 100 λ1 (the fast one, same machinery as se_dsf) and
    the paper's GA (``se_pareto``'s default method, 100 λ1, one thread like the others).
    """
    print("| structure | GA sweep (default) + D_SF: J_S, J_SF, time | gradient sweep of 30 λ + D_SF "
          "| gradient sweep of 100 λ + D_SF | se_dsf | se_dsf time / 100-λ gradient sweep's | … / GA sweep's |\n"
          "| --- | --- | --- | --- | --- | --- | --- |")
    ratios = []
    for name, data, st, band in dsf_cases():
        cols = []
        for kw in ({}, dict(lambdas=np.logspace(-2, 0, 30), method="gradient"),
                   dict(lambdas=np.logspace(-2, 0, 100), method="gradient")):
            se, t = wall(lambda: gb.se_pareto(st, data, progress=False, **kw))
            d = gb.decide_dsf(se, band=band, fallback="min_jsf")
            cols.append((d.JS, d.JSF, t))
        r, t = wall(lambda: gb.se_dsf(st, data, band=band))
        best = min(c[0] for c in cols)
        mark = "**" if r.JS <= best * (1 + 1e-6) else ""
        ratios.append((t / cols[2][2], t / cols[0][2]))
        print(f"| {name} | " + " | ".join(f"{a:.4f}, {b:.4f}, {c:.2f} s" for a, b, c in cols)
              + f" | {mark}{r.JS:.4f}{mark}, {r.JSF:.4f}, {t:.2f} s | {ratios[-1][0]:.2f} | {ratios[-1][1]:.3f} |",
              flush=True)
    g, a = np.array(ratios).T
    print(f"\nse_dsf time / 100-λ gradient sweep's: {g.min():.2f}–{g.max():.2f} (median {np.median(g):.2f}); "
          f"/ GA sweep's: {a.min():.3f}–{a.max():.3f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--part", default="all", choices=("speed", "tables", "staircase", "dsf", "all"))
    args = ap.parse_args()
    print(f"# bench_select ({datetime.date.today()}, git {git_rev()}): {machine()}")
    warnings.simplefilter("ignore")
    if args.part in ("staircase", "all"):
        staircase()
    if args.part in ("speed", "all"):
        speed(args.workers)
    if args.part in ("tables", "all"):
        tables()
    if args.part in ("dsf", "all"):
        dsf()


if __name__ == "__main__":
    main()
