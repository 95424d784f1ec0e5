"""Honest selection: fit / choose / untouched test (issue 26).

    .venv/bin/python benchmarks/bench_honest.py [--part speed|protocol|transient|blackbox|sources|all] [--cases plant,buck,...]
        [--no-old] [--record-only]

- protocol: on each case, ``select_graybox`` fits on the identification record, chooses on the
  validation record and reports on a test record nothing was fitted or chosen on. Per case: the
  chosen gray box (rule "one-se", the default; and rule "min", the smallest validation J_S) and the
  black box chosen the same way (no band: LS / ELS), with the old select_graybox (main before
  issue 26: smallest validation J_S over sizes 4…20) beside them. Figures: test J_S and its ratio
  to the black box's, J_SF of the test-scored model against the band, optimism (choosing J_S /
  test J_S) and regret (test J_S of the choice / the best test J_S among the rows it compared).
- speed: the README's call ``select_graybox(Candidates(ny=6, nu=6, degree=2), data, band=0.031)``
  on the bundled plant, in the driver and on 2 worker processes, with the load average.
- transient: the gray and the black box chosen as in protocol from the case's candidates, and from
  the same candidates plus transient inputs (``gb.transient_inputs``, one lag each) on two τ grids
  given in samples (60, 200, 600, 2000 and 100, 300, 900, 2700: 3–100 s and 5–135 s on the plant),
  scored on the test record and, for the simulated plants, on five fresh runs (seed + 1 … + 5).
- sources: the default sources of structures (SEMP, FROLS) against the swap search's best subsets
  added or in FROLS's place, on the cases and on bench_search's staircase systems.
- blackbox: the black box chosen among LS and ELS, among LS, ELS and output error (the default),
  and by output error alone; the gray box's test J_S against each.

Cases: the bundled plant (test: a fresh simulator run, another seed), the two-speed rig (same),
the buck converter (choose on the first half of its validation file, test on the second), and
synthetic systems with a known answer that expose the old failure: short records with many
candidates, a slow output disturbance, and static points that conflict with the records.
"""

from __future__ import annotations

import argparse
import datetime
import os
import subprocess
import sys
import time
import types
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402

import graybox as gb  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
TRUE = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2", "1"])
THETA = np.array([0.6, 0.2, 0.3, 0.05, 0.4])
OLD = "64f2d27"  # main before issue 26's selection protocol


def old_select():
    """select_graybox as it was before issue 26 (its source at 64f2d27, loaded beside ours; it reads the
    package's names of that commit, so later renames may stop it: the figures in BENCHMARKS.md were taken
    at 30dda9f, where it ran)."""
    src = subprocess.run(["git", "-C", str(ROOT), "show", f"{OLD}:graybox/experiments/_select.py"], check=True,
                         capture_output=True, text=True).stdout
    src = src.replace('register_type("GrayboxSelection"', '(lambda *a: None)("GrayboxSelection"')
    mod = types.ModuleType("graybox.experiments._select_old")
    mod.__package__ = "graybox.experiments"
    sys.modules[mod.__name__] = mod  # dataclasses look their module up
    exec(compile(src, "main:_select.py", "exec"), mod.__dict__)
    return mod.select_graybox


def _synthetic(seed, n, noise=0.02, drift=0.0):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.0, 3.0, n // 25 + 1), 25)[:n]
    y = gb.Model(TRUE, THETA).simulate(u, np.zeros(2)) + noise * rng.standard_normal(n)
    if drift:  # a slow disturbance: a random walk smoothed over ~200 samples, the size of `drift`
        w = np.cumsum(rng.standard_normal(n + 400))
        w = np.convolve(w, np.ones(200) / 200, mode="same")[200:200 + n]
        y = y + drift * (w - w.mean()) / (w.std() + 1e-12)
    return gb.Record(u, y, name=f"synthetic {seed}")


def _true_points(bias=0.0):
    ub = np.linspace(-0.5, 3.5, 7)
    return gb.StaticPoints(ub, gb.Model(TRUE, THETA).static_curve(ub) + bias)


def _tank_pump(u):
    """The cascaded tanks' pump: flow (cm³/s per cm² of tank) against its voltage u (V), a dead zone below 1 V."""
    return 3.2 * np.maximum(u - 1.0, 0.0) ** 1.3


#: The cascaded tanks' Torricelli outflow coefficients (upper, lower tank) and their cross-section.
_TANK_OUT, _TANK_AREA = (0.45, 0.38), 0.6


def _tanks(seed, n):
    """A plant no default or study of graybox was tuned on (added 2026-11-29): two cascaded tanks, pump voltage
    u (V) to the lower tank's level y (cm), Torricelli outflows, sampled every 2 s (Euler steps of 0.1 s), a slow
    random inflow disturbance and 0.05 cm of level noise; APRBS input in [2, 5] V held 15-59 samples, the run
    starting at its first level's steady state."""
    rng = np.random.default_rng(seed)
    levels = []
    while len(levels) < n:
        levels += [rng.uniform(2.0, 5.0)] * int(rng.integers(15, 60))
    u = np.array(levels[:n])
    (a1, a2), area = _TANK_OUT, _TANK_AREA
    q = _tank_pump(u[0])
    h1, h2, d = (q / a1) ** 2, (q / a2) ** 2, 0.0
    y = np.empty(n)
    for k in range(n):
        y[k] = h2
        for _ in range(20):
            d = 0.999 * d + 0.01 * rng.standard_normal()
            h1 += 0.1 / area * (_tank_pump(u[k]) + d - a1 * np.sqrt(max(h1, 0.0)))
            h2 += 0.1 / area * (a1 * np.sqrt(max(h1, 0.0)) - a2 * np.sqrt(max(h2, 0.0)))
    return gb.Record(u, y + 0.05 * rng.standard_normal(n), name=f"tanks {seed}", Ts=2.0, units=("V", "cm"))


def _tank_points():
    """The tanks' static test: 9 levels over [1.5, 5.5] V, beyond the records' range, 0.05 cm of noise."""
    ub = np.linspace(1.5, 5.5, 9)
    yb = (_tank_pump(ub) / _TANK_OUT[1]) ** 2 + 0.05 * np.random.default_rng(0).standard_normal(9)
    return gb.StaticPoints(ub, yb, units=("V", "cm"))


def cases():
    """name -> (Dataset (ident, valid, static), test Record, candidates, band)."""
    from graybox.datasets import pumping
    from graybox.datasets._pumping_miso import generate_miso

    out = {}
    plant = gb.load_pumping()
    test = pumping.generate(seed=plant.extra["seed"] + 1)[0].record("pumping, seed + 1")
    out["plant"] = (plant, test, gb.Candidates(6, 6, degree=2), 0.031)
    miso = gb.load_pumping_miso()
    test = generate_miso(seed=miso.extra["seed"] + 1)[0].record("two-speed, seed + 1")
    out["two-speed rig"] = (miso, test, gb.Candidates(2, 2, degree=2, input_names=("u1", "u2")), 0.031)
    if not os.environ.get("GRAYBOX_BUCK_DIR") and Path("/work/shared/data/buck").is_dir():
        os.environ["GRAYBOX_BUCK_DIR"] = "/work/shared/data/buck"
    buck = gb.load_buck()
    half = len(buck.valid) // 2
    out["buck"] = (gb.Dataset(buck.ident, buck.valid.slice(0, half, "buck valid, first half"), buck.static),
                   buck.valid.slice(half, None, "buck valid, second half"), gb.Candidates(2, 2, degree=2), 0.01)
    out["short records (45 candidates)"] = (gb.Dataset(_synthetic(1, 300), _synthetic(2, 150), _true_points()),
                                           _synthetic(3, 4000), gb.Candidates(4, 4, degree=2), 1e-3)
    out["slow disturbance"] = (gb.Dataset(_synthetic(4, 1200, drift=0.3), _synthetic(5, 600, drift=0.3),
                                          _true_points()), _synthetic(6, 4000, drift=0.3),
                               gb.Candidates(3, 3, degree=2), 1e-3)
    out["static points off the records"] = (gb.Dataset(_synthetic(7, 1200), _synthetic(8, 600), _true_points(0.15)),
                                            _synthetic(9, 4000), gb.Candidates(3, 3, degree=2), 0.03)
    out["cascaded tanks"] = (gb.Dataset(_tanks(1, 1200), _tanks(2, 600), _tank_points()), _tanks(3, 1500),
                             gb.Candidates(3, 3, degree=3), 25.0)
    return out


def _test_js(model, rec):
    sim = model.simulate(rec, on_diverge="nan")
    return gb.mse(rec.y, sim, start=model.max_lag)


def protocol(names, with_old: bool, record_only: bool = False) -> None:
    old = old_select() if with_old else None
    rows = []
    for name, (data, test, cand, band) in cases().items():
        if names and name not in names:
            continue
        t0 = time.perf_counter()
        res = {"gray one-se": gb.select_graybox(cand, data, band=band, test=test),
               "gray min": gb.select_graybox(cand, data, band=band, test=test, rule="min"),
               "black one-se": gb.select_graybox(cand, data, band=np.inf, test=test)}
        if record_only:  # the identification record alone: the choice on refitted folds of it
            res["gray, folds of ident"] = gb.select_graybox(cand, data.ident, data.static, band=band, test=test)
            res["black, folds of ident"] = gb.select_graybox(cand, data.ident, data.static, band=np.inf, test=test)
        t_new = time.perf_counter() - t0
        black = res["black one-se"].chosen["JS_test"]
        for label, r in res.items():
            ref = res["black, folds of ident"].chosen["JS_test"] if "folds" in label else black
            c = r.chosen
            rows.append({"case": name, "choice": label, "n_terms": len(r.structure), "estimator": c["estimator"],
                         "JS_valid": c["JS_valid"], "JS_test": c["JS_test"], "vs black": c["JS_test"] / ref,
                         "JSF": c["JSF_test"], "in band": bool(c["JSF_test"] <= band) if np.isfinite(r.band) else None,
                         "optimism": r.optimism,
                         "regret": r.regret, "rows": len(r.table)})
        t_old = np.nan
        if old is not None:
            t0 = time.perf_counter()
            try:
                o = old(cand, data, band=band)
                js_t = _test_js(o.model, test)
                v = o.table["JS_valid"].min()
                rows.append({"case": name, "choice": "gray, old (main)", "n_terms": len(o.structure),
                             "estimator": o.table.iloc[0]["estimator"], "JS_valid": v, "JS_test": js_t,
                             "vs black": js_t / black, "JSF": o.decision.JSF, "in band": bool(o.decision.JSF <= band),
                             "optimism": v / js_t, "regret": np.nan, "rows": len(o.table)})
            except ValueError as e:  # the old defaults' refusals are part of the comparison
                rows.append({"case": name, "choice": "gray, old (main)", "estimator": f"error: {str(e)[:60]}"})
            t_old = time.perf_counter() - t0
        print(f"{name}: new (3 selections) {t_new:.0f} s, old {t_old:.0f} s (load {os.getloadavg()[0]:.1f})",
              flush=True)
        df = pd.DataFrame([r for r in rows if r["case"] == name]).drop(columns="case")
        print(df.to_markdown(index=False, floatfmt=".4g"), flush=True)
    df = pd.DataFrame(rows)
    print("\n" + df.to_markdown(index=False, floatfmt=".4g"))


def speed() -> None:
    data = gb.load_pumping()
    cand = gb.Candidates(6, 6, degree=2)
    gb.semp(gb.Candidates(2, 2, degree=2), data, n_terms=3)  # compile
    for label, kw in (("in the driver", {}), ("2 worker processes", dict(executor="processes", workers=2))):
        la = os.getloadavg()[0]
        t0, c0 = time.perf_counter(), time.process_time()
        r = gb.select_graybox(cand, data, band=data.static.band, **kw)
        t, c = time.perf_counter() - t0, time.process_time() - c0
        # on a loaded machine the driver's CPU time is the closer figure for a quiet one (one thread)
        print(f"| select_graybox(Candidates(6, 6, degree=2), plant, band=data.static.band), {label} | wall {t:.1f} s | "
              f"driver CPU {c:.1f} s | {len(r.table)} rows | load average {la:.1f} → {os.getloadavg()[0]:.1f} |",
              flush=True)


# candidate lags per case (ny, nu), for the candidates with transient inputs
_LAGS = {"plant": (6, 6), "two-speed rig": (2, 2), "buck": (2, 2), "short records (45 candidates)": (4, 4),
         "slow disturbance": (3, 3), "static points off the records": (3, 3)}
# τ grids in samples: a 1-3-10 series (the plant: 3, 10, 30, 100 s) and one shifted off it (5, 15, 45, 135 s)
_GRIDS = {"1-3-10": (60, 200, 600, 2000), "off": (100, 300, 900, 2700)}


def _more_tests(name, data, n=5):
    """Fresh simulator runs (seed + 1 … + n) for the simulated plants; the case's own test record otherwise."""
    from graybox.datasets import pumping
    from graybox.datasets._pumping_miso import generate_miso
    if name == "plant":
        return [pumping.generate(seed=data.extra["seed"] + i)[0].record(f"seed + {i}") for i in range(1, n + 1)]
    if name == "two-speed rig":
        return [generate_miso(seed=data.extra["seed"] + i)[0].record(f"seed + {i}") for i in range(1, n + 1)]
    return []


def transient(names) -> None:
    """Gray and black boxes chosen with and without transient inputs (two τ grids), scored on untouched records."""
    rows = []
    for name, (data, test, cand, band) in cases().items():
        if names and name not in names:
            continue
        tests = [test] + _more_tests(name, data)[1:]  # the first fresh run is the case's test record
        ny, nu = _LAGS[name]
        variants = {"plain": (data, cand, tests)}
        for grid, samples in _GRIDS.items():
            taus = tuple(k * data.Ts for k in samples)
            aug = gb.transient_inputs(data, taus=taus)
            lags = {n: (nu if n in data.input_names else 1) for n in aug.input_names}
            c = gb.Candidates(ny, lags, degree=2, input_names=aug.input_names)
            ts = [gb.transient_inputs(t, taus=taus) for t in tests]
            variants[f"transient {grid}"] = (aug, c, ts)
            # the transient inputs alone or times an input, never times y or squared: the model's
            # y-dynamics (its poles) stay those of its other terms whatever the transients do
            new = set(aug.input_names) - set(data.input_names)
            keep = [t for t in c if not new & set(t.input_names)
                    or (t.power_of("y") == 0 and sum(t.power_of(n) for n in new) == 1)]
            variants[f"transient {grid}, z alone or times u"] = (aug, gb.Structure(keep), ts)
        t0 = time.perf_counter()
        for label, (d, c, ts) in variants.items():
            try:
                res = {box: gb.select_graybox(c, d, band=b, test=ts[0], executor="processes", workers=2)
                       for box, b in (("gray", band), ("black", np.inf))}
            except ValueError as e:  # e.g. no structure meets the band: a failed row, the run goes on
                rows.append({"case": name, "candidates": label, "box": "gray", "estimator": f"error: {e}"[:120]})
                continue
            js = {box: [_test_js(r.model, t) for t in ts] for box, r in res.items()}
            for box, r in res.items():
                ch = r.chosen
                z = sorted({n for t in r.structure for n in t.input_names} - set(data.input_names))
                rows.append({"case": name, "candidates": label, "box": box, "n_terms": len(r.structure),
                             "estimator": ch["estimator"], "transient inputs used": ", ".join(z) or "none",
                             "JS_valid": ch["JS_valid"], "JS_test": ch["JS_test"],
                             "vs black": ch["JS_test"] / res["black"].chosen["JS_test"],
                             "regret": r.regret,
                             "JSF": ch["JSF_test"], "in band": bool(ch["JSF_test"] <= band),
                             f"mean test ({len(ts)})": np.mean(js[box]),
                             "mean vs black": np.mean(js[box]) / np.mean(js["black"])})
        print(f"{name}: {time.perf_counter() - t0:.0f} s (load {os.getloadavg()[0]:.1f})", flush=True)
        print(pd.DataFrame([r for r in rows if r["case"] == name]).drop(columns="case").to_markdown(
            index=False, floatfmt=".4g"), flush=True)
    print("\n" + pd.DataFrame(rows).to_markdown(index=False, floatfmt=".4g"))


def blackbox(names) -> None:
    """The black box chosen among LS and ELS (before output error joined), among LS, ELS and output
    error (the default now) and by output error alone, against the gray box chosen the same way."""
    rows = []
    for name, (data, test, cand, band) in cases().items():
        if names and name not in names:
            continue
        gray = gb.select_graybox(cand, data, band=band, test=test).chosen
        for label, est in (("LS, ELS", ("ls", "els")), ("LS, ELS, OE (default)", None), ("OE", "oe")):
            t0 = time.perf_counter()
            c = gb.select_graybox(cand, data, band=np.inf, test=test, estimator=est).chosen
            rows.append({"case": name, "black box among": label, "chosen": f"{c.name} {c['estimator']}",
                         "n_terms": c["n_terms"], "JS_valid": c["JS_valid"], "JS_test": c["JS_test"],
                         "gray JS_test": gray["JS_test"], "gray / black": gray["JS_test"] / c["JS_test"],
                         "s": time.perf_counter() - t0})
        print(pd.DataFrame([r for r in rows if r["case"] == name]).drop(columns="case").to_markdown(
            index=False, floatfmt=".4g"), flush=True)
    print("\n" + pd.DataFrame(rows).to_markdown(index=False, floatfmt=".4g"))


SOURCE_SETS = {"semp, frols (default)": ("semp", "frols"), "semp, frols, swap": ("semp", "frols", "swap"),
               "semp, swap": ("semp", "swap")}


def sources(names, seeds: int) -> None:
    """The structures' sources: the default (SEMP and greedy FROLS paths) against the swap search's
    best subsets added or in FROLS's place. The six cases (gray and black box, test J_S against the
    black box chosen from the same sources, regret), and bench_search's staircase systems (black box
    with LS alone on 1 % equation noise: whether the chosen structure is the true one)."""
    import bench_search as bs

    rows = []
    for name, (data, test, cand, band) in cases().items():
        if names and name not in names:
            continue
        for label, src in SOURCE_SETS.items():
            t0 = time.perf_counter()
            gray = gb.select_graybox(cand, data, band=band, test=test, sources=src)
            t_gray = time.perf_counter() - t0
            black = gb.select_graybox(cand, data, band=np.inf, test=test, sources=src).chosen
            g = gray.chosen
            ok = gray.table[gray.table["in_band"]]
            rows.append({"case": name, "sources": label, "gray": f"{g.name} {g['estimator']}",
                         "gray JS_test": g["JS_test"], "black": f"{black.name} {black['estimator']}",
                         "black JS_test": black["JS_test"], "gray / black": g["JS_test"] / black["JS_test"],
                         "gray regret": g["JS_test"] / ok["JS_test"].min(), "rows": len(gray.table),
                         "gray s": t_gray})
        print(pd.DataFrame([r for r in rows if r["case"] == name]).drop(columns="case").to_markdown(
            index=False, floatfmt=".4g"), flush=True)
    print("\n" + pd.DataFrame(rows).to_markdown(index=False, floatfmt=".4g"))
    rec_rows = []
    for system in bs.SYSTEMS:
        true = frozenset(gb.Structure(bs.SYSTEMS[system][0]))
        cand = bs.candidates(system)
        for seed in range(seeds):
            recs = [bs.record(system, "staircase", 0.01, 1000 * seed + k, n) for k, n in ((1, 1000), (2, 500), (3, 2000))]
            for label, src in SOURCE_SETS.items():
                r = gb.select_graybox(cand, gb.Dataset(recs[0], recs[1], None), band=np.inf, estimator="ls",
                                      test=recs[2], sources=src, include=())
                compared = {frozenset(r.structure_of(n)) for n in set(r.table.index)}
                rec_rows.append({"system": system, "seed": seed, "sources": label,
                                 "true structure compared": true in compared,
                                 "true structure chosen": frozenset(r.structure) == true,
                                 "JS_test": r.chosen["JS_test"]})
    df = pd.DataFrame(rec_rows)
    out = df.groupby(["system", "sources"]).agg(compared=("true structure compared", "sum"),
                                                 chosen=("true structure chosen", "sum"),
                                                 JS_test_median=("JS_test", "median")).reset_index()
    print(f"\nstaircase systems (1 % equation noise, {seeds} seeds; black box, LS):\n"
          + out.to_markdown(index=False, floatfmt=".4g"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--part", default="all", choices=("speed", "protocol", "transient", "blackbox", "sources", "all"))
    ap.add_argument("--cases", default="", help="comma-separated case names (default all)")
    ap.add_argument("--no-old", action="store_true", help="skip main's select_graybox")
    ap.add_argument("--seeds", type=int, default=5, help="seeds per staircase system (--part sources)")
    ap.add_argument("--record-only", action="store_true",
                    help="also choose on refitted folds of the identification record alone (gray and black)")
    args = ap.parse_args()
    print(f"# bench_honest ({datetime.date.today()}, git {git_rev()}): {machine()}")
    warnings.simplefilter("ignore")
    if args.part in ("speed", "all"):
        speed()
    if args.part in ("protocol", "all"):
        protocol([c for c in args.cases.split(",") if c], not args.no_old, args.record_only)
    if args.part in ("transient", "all"):
        transient([c for c in args.cases.split(",") if c])
    if args.part in ("blackbox", "all"):
        blackbox([c for c in args.cases.split(",") if c])
    if args.part in ("sources", "all"):
        sources([c for c in args.cases.split(",") if c], args.seeds)


if __name__ == "__main__":
    main()
