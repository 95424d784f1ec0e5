"""Free-run fits of a structure closed under shifts, at other offsets and scales of u and y (units41b).

For each transform u' = su u + ou, y' = sy y + oy the fit is made on the transformed data and its free run
on the (transformed) validation record is mapped back, (ŷ' − oy) / sy, and compared with the untransformed
fit's: the relative difference of J_S (mapped back by 1/sy²) and the largest difference of the free runs over
the output's spread. Part 2: the Monte Carlo band of the least-squares model's free run (ls_uncertainty, 200 draws, seed 0) at
each transform, mapped back: the largest difference of its quantiles over the output's spread (0 when one
seed draws the same models), and the band's time (median of 5).
Run: PYTHONPATH=. python benchmarks/units41b_offsets.py [--part fits|bands|all]
"""
from __future__ import annotations

import sys
import time
import warnings
from dataclasses import replace

import numpy as np

import graybox as gb

TRANSFORMS = [(1, 0, 1, 0), (1, 1e2, 1, 1e2), (1, 1e4, 1, 1e4), (1, 1e4, 1, 0), (1, 0, 1, 500.0),
              (1000, 0, 1, 0), (1, 0, 1000, 0), (1000, 1e4, 1000, 500.0)]


def shift(data: gb.Dataset, su, ou, sy, oy) -> gb.Dataset:
    def rec(r):
        return replace(r, u=su * r.u + ou, y=sy * r.y + oy)
    sp = data.static
    unc = None if sp.uncertainty is None else sy * sp.uncertainty
    static = gb.StaticPoints(su * sp.ubar + ou, sy * sp.ybar + oy, uncertainty=unc)
    return gb.Dataset(rec(data.ident), rec(data.valid), static)


def synthetic() -> tuple[gb.Dataset, float]:
    true = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "u(k-2)^2"])
    theta = np.array([0.5, 0.3, 0.2, 0.1])

    def record(seed, n=600):
        rng = np.random.default_rng(seed)
        u = np.repeat(rng.uniform(-1.0, 1.0, n // 5 + 1), 5)[:n]
        y = gb.Model(true, theta).simulate(u, np.zeros(2)) + 0.02 * rng.standard_normal(n)
        return gb.Record(u, y, name=f"narx {seed}")
    ub = np.linspace(-0.9, 0.9, 7)
    yb = gb.Model(true, theta).static_curve(ub) + 0.01
    return gb.Dataset(record(0), record(1), gb.StaticPoints(ub, yb, uncertainty=0.05)), 0.05 ** 2


def fits(st, data, band):
    out = {}
    t = time.perf_counter()
    pareto = gb.se_pareto(st, data, lambdas=[1.0, 0.3, 0.1], method="gradient")
    out["se_pareto gradient"] = [pareto.member_model(i) for i in range(len(pareto)) if i not in pareto.failures]
    out["se_dsf"] = [gb.se_dsf(st, data, band=band, lambdas=np.logspace(-2, 0, 6)).model]
    out["output_error"] = [gb.output_error(st, data.ident, n_starts=2).model]
    ga = gb.se_pareto(st, data, lambdas=[1.0, 0.3], method="ga", options=gb.GAOptions(population=40, generations=15))
    out["se_pareto ga"] = [ga.member_model(i) for i in range(len(ga)) if i not in ga.failures]
    return out, time.perf_counter() - t


def transformed(data):
    """Each of TRANSFORMS (u scale, u offset, y scale, y offset) with the data it makes."""
    for tr in TRANSFORMS:
        yield tr, shift(data, *tr)


def bands(cases) -> None:
    for name, data, st, _ in cases:
        print(f"== Monte Carlo simulation_band, {name}", flush=True)
        base = None
        for (su, ou, sy, oy), d in transformed(data):
            unc = gb.ls_uncertainty(gb.els(st, d.ident, noise=0).model, d.ident)
            times = []
            for _ in range(5):
                t = time.perf_counter()
                b = gb.simulation_band(unc, d.valid, method="monte-carlo", n_samples=200, seed=0)
                times.append(time.perf_counter() - t)
            low, high = (b.low - oy) / sy, (b.high - oy) / sy
            if base is None:
                base = low, high
            diff = max(np.max(np.abs(low - base[0])), np.max(np.abs(high - base[1]))) / data.valid.y.std()
            print(f"su={su:g} ou={ou:g} sy={sy:g} oy={oy:g} | band quantiles mapped back: max diff {diff:.1e} of "
                  f"y's spread | {np.median(times) * 1e3:.1f} ms", flush=True)


def main() -> None:
    part = sys.argv[sys.argv.index("--part") + 1] if "--part" in sys.argv else "all"
    pump = gb.load_pumping()
    pst = gb.frols(gb.Candidates(ny=2, nu=2, degree=2), pump, n_terms=6, centre=True).structure
    syn, syn_band = synthetic()
    sst = gb.frols(gb.Candidates(ny=2, nu=2, degree=2), syn, n_terms=4, centre=True).structure
    cases = [("pumping", pump, pst, pump.static.band), ("synthetic", syn, sst, syn_band)]
    if part in ("bands", "all"):
        bands(cases)
    if part == "bands":
        return
    for name, data, st, band in cases:
        print(f"== {name}: {len(st)} terms {st}", flush=True)
        base = None
        for (su, ou, sy, oy), d in transformed(data):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                models, secs = fits(st, d, band * sy * sy)
            runs = {k: [(m.simulate(d.valid, d.valid.y[:m.max_lag]) - oy) / sy for m in ms] for k, ms in models.items()}
            if base is None:
                base = runs
            row = []
            for k in runs:
                L = max(m.max_lag for m in models[k])
                js = [gb.mse(data.valid.y, r, start=L) for r in runs[k]]
                js0 = [gb.mse(data.valid.y, r, start=L) for r in base[k]]
                rel = max(abs(a / b - 1) for a, b in zip(js, js0))
                dy = max(np.max(np.abs(a - b)) for a, b in zip(runs[k], base[k])) / data.valid.y.std()
                row.append(f"{k}: dJS {rel:.1e} dy {dy:.1e}")
            print(f"su={su:g} ou={ou:g} sy={sy:g} oy={oy:g} ({secs:.1f} s) | " + " | ".join(row), flush=True)


if __name__ == "__main__":
    main()
