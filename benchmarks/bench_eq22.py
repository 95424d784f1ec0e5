"""Where Σ*_y of eq. (22) comes from, and where the input's zero is (issue 26, robust defaults).

    .venv/bin/python benchmarks/bench_eq22.py [--seeds 20]

CLS with a static curve (eq. (22)) makes the model's denominator constant (Σ_{yu^m} = 0) and fixes
Σ_y. The paper takes Σ*_y from a reference model (its ELS estimate's Σ_y); graybox took it from the
least-squares estimate. A reference's Σ_y is its denominator's slope at ū = 0, so it moves when the
input's zero moves (rpm against rpm − 1000, °C against K). ``reference="free"`` estimates Σ_y with
the other parameters (Σ_{u^m} + c_m Σ_y = c_m, still affine). Each reference on:

- the bundled plant, Table I's ℓ = 2 structure (15) and curve (eq. (1) fitted to the static points), u
  shifted by 0, −700 and +1000 rpm; scored on the validation record and three fresh simulator runs;
- the buck converter, FROLS structures of 6, 8 and 10 terms from rational candidates, u shifted by 0,
  −2.35 (the records' middle at 0) and +10 V, the curve the structure's numerator carries fitted to the
  static points (``how="curve"``); scored on the validation record;
- a synthetic rational system whose true denominator varies with ū, y(k) = 0.5 y(k−1) + 0.15 y(k−1)u(k−1)
  + 0.3 u(k−1) − 0.05 u(k−1)² + 0.2 + noise 0.02, u in [0, 2] held 20 samples, its true structure
  (closed under shifts of u), the curve fitted to 7 true static points; u shifted by 0, −5, +5; seeds
  1 … N; J_S on a noise-free 3000-sample record of another seed, J_SF against the true points.

Cells: J_S (free run, output units²) and J_SF; "fails" when the estimator refuses (its reason).
"""

from __future__ import annotations

import argparse
import datetime
import sys
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402

import graybox as gb  # noqa: E402

REFERENCES = ("free", "ls", "els")
TRUE = gb.Structure(["y(k-1)", "y(k-1)u(k-1)", "u(k-1)", "u(k-1)^2", "1"])
THETA = np.array([0.5, 0.15, 0.3, -0.05, 0.2])


def _shift(rec: gb.Record, c: float) -> gb.Record:
    return gb.Record(rec.u + c, rec.y, Ts=rec.Ts, name=rec.name)


def _js(model: gb.Model, rec: gb.Record) -> float:
    sim = model.simulate(rec, on_diverge="nan")
    return gb.mse(rec.y, sim, start=model.max_lag)


def _fit(structure, ident, static, reference):
    """CLS with eq. (22): a curve as given, or points with the curve the structure's numerator carries."""
    how = "curve" if isinstance(static, gb.StaticPoints) else "auto"
    try:
        return gb.cls(structure, ident, static, how=how, reference=reference).model, ""
    except ValueError as e:
        return None, str(e).split(";")[0][:80]


def plant() -> pd.DataFrame:
    from graybox.datasets import pumping

    data = gb.load_pumping()
    tests = [pumping.generate(seed=data.extra["seed"] + k)[0].record(f"seed + {k}") for k in (1, 2, 3)]
    cand = gb.Candidates(6, 6, ne=2, degree=2, max_y_power=1)
    st = gb.els(gb.frols(cand, data.ident, n_terms=17, include=["1"]), data.ident).model.structure
    rows = []
    for c in (0.0, -700.0, 1000.0):
        ident, valid = _shift(data.ident, c), _shift(data.valid, c)
        pts = gb.StaticPoints(data.static.ubar + c, data.static.ybar)
        curve = gb.StaticCurve.fit(pts, degree=2)
        for ref in REFERENCES:
            m, why = _fit(st, ident, curve, ref)
            row = {"case": "plant (15)", "u offset": c, "reference": ref}
            if m is None:
                rows.append(row | {"fails": why})
                continue
            row |= {"Σy": m.clusters()["Σy"], "J_S valid": _js(m, valid), "J_SF": gb.jsf(m, pts),
                    "J_S test (mean of 3)": np.mean([_js(m, _shift(t, c)) for t in tests])}
            rows.append(row)
    return pd.DataFrame(rows)


def buck() -> pd.DataFrame:
    data = gb.load_buck()
    cand = gb.Candidates(2, 2, degree=2, max_y_power=1)
    rows = []
    for n in (6, 8, 10):
        st = gb.frols(cand, data.ident, n_terms=n, include=["1"]).model.structure
        for c in (0.0, -2.35, 10.0):
            ident, valid = _shift(data.ident, c), _shift(data.valid, c)
            pts = gb.StaticPoints(data.static.ubar + c, data.static.ybar)
            for ref in REFERENCES:
                m, why = _fit(st, ident, pts, ref)
                row = {"case": f"buck, {n} terms", "u offset": c, "reference": ref}
                if m is None:
                    rows.append(row | {"fails": why})
                    continue
                rows.append(row | {"Σy": m.clusters().get("Σy", 0.0), "J_S valid": _js(m, valid),
                                   "J_SF": gb.jsf(m, pts)})
    return pd.DataFrame(rows)


def _synthetic(seed: int, n: int, noise: float) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.0, 2.0, n // 20 + 1), 20)[:n]
    y = gb.Model(TRUE, THETA).simulate(u, np.zeros(1)) + noise * rng.standard_normal(n)
    return gb.Record(u, y, name=f"synthetic {seed}")


def synthetic(seeds: int) -> pd.DataFrame:
    ub = np.linspace(0.0, 2.0, 7)
    true_pts = gb.StaticPoints(ub, gb.Model(TRUE, THETA).static_curve(ub))
    test = _synthetic(10_000, 3000, 0.0)
    rows = []
    for seed in range(1, seeds + 1):
        ident = _synthetic(seed, 400, 0.02)
        for c in (0.0, -5.0, 5.0):
            pts = gb.StaticPoints(true_pts.ubar + c, true_pts.ybar)
            curve = gb.StaticCurve.fit(pts, degree=2)
            for ref in REFERENCES:
                m, why = _fit(TRUE, _shift(ident, c), curve, ref)
                row = {"case": "synthetic", "seed": seed, "u offset": c, "reference": ref}
                rows.append(row | ({"fails": why} if m is None else
                                   {"J_S test": _js(m, _shift(test, c)), "J_SF": gb.jsf(m, pts)}))
    return pd.DataFrame(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    print(f"bench_eq22.py: {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, git {git_rev()}, "
          f"{machine()}")
    pd.set_option("display.width", 200)
    print(plant().to_markdown(index=False, floatfmt=".4g"))
    print()
    print(buck().to_markdown(index=False, floatfmt=".4g"))
    print()
    syn = synthetic(args.seeds)
    print(syn.groupby(["u offset", "reference"]).agg(
        fails=("J_S test", lambda s: int(s.isna().sum())),
        median_JS_test=("J_S test", "median"), worst_JS_test=("J_S test", "max"),
        median_JSF=("J_SF", "median")).reset_index().to_markdown(index=False, floatfmt=".4g"))
    if "fails" in syn:
        why = syn["fails"].dropna().str.replace(r"[-0-9.]+ > 1", "… > 1", regex=True)
        for reason, n in why.value_counts().items():
            print(f"refused {n}×: {reason}")


if __name__ == "__main__":
    main()
