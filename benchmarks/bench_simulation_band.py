"""The free run's confidence band (``simulation_band``): coverage on systems of known θ, and speed.

    .venv/bin/python benchmarks/bench_simulation_band.py [--reps 300] [--draws 300]

Coverage: for each system and noise level, ``--reps`` fresh identification records (300 samples,
APRBS input from ``design_input``, white equation noise, so least squares is consistent) are fitted
by LS and given a 95 % band on one fixed validation input (150 samples); the figure is the share of
(record, sample) pairs whose true noise-free free run lies inside the band, for the delta method and
for Monte Carlo with ``--draws`` draws. Systems: S1 y(k) = 0.7 y(k-1) + 0.8 u(k-1) − 0.2 u(k-1)² + 0.1
(a free run nearly linear in θ); S2 y(k) = 0.5 y(k-1) + 0.3 u(k-1) y(k-1) + 0.5 u(k-1) (a pole that
moves with u, up to 0.95: the run is far from linear in θ at high noise).
Speed: the bundled plant's ELS ℓ = 2 model (17 terms) on its validation record and on records of
10⁵ and 10⁶ samples (the validation input repeated), median of 3 after a warm-up.
"""

from __future__ import annotations

import argparse
import datetime
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine, timeit  # noqa: E402

import graybox as gb  # noqa: E402

SYSTEMS = {
    "S1": (["y(k-1)", "u(k-1)", "u(k-1)^2", "1"], np.array([0.7, 0.8, -0.2, 0.1]),
           lambda th, y1, u1: th[0] * y1 + th[1] * u1 + th[2] * u1**2 + th[3]),
    "S2": (["y(k-1)", "u(k-1)y(k-1)", "u(k-1)"], np.array([0.5, 0.3, 0.5]),
           lambda th, y1, u1: th[0] * y1 + th[1] * u1 * y1 + th[2] * u1),
}


def _coverage(name: str, noise: float, reps: int, draws: int) -> tuple[float, float, float]:
    terms, theta, step = SYSTEMS[name]
    st = gb.parse_structure(terms)
    truth_model = gb.Model(st, theta)
    uv = gb.design_input("aprbs", 150, low=0.0, high=1.5, hold=(3, 12), seed=999)
    val = gb.Record(uv, np.zeros(150), name="valid")
    truth = truth_model.simulate(val)
    inside_d, inside_m, diverged = [], [], []
    for r in range(reps):
        rng = np.random.default_rng([r, 7])
        u = gb.design_input("aprbs", 300, low=0.0, high=1.5, hold=(3, 12), seed=r)
        e = noise * rng.standard_normal(300)
        y = np.zeros(300)
        for k in range(1, 300):  # the true system with equation noise
            y[k] = step(theta, y[k - 1], u[k - 1]) + e[k]
        rec = gb.Record(u, y)
        unc = gb.ls_uncertainty(gb.els(terms, rec, noise=0).model, rec)
        d = gb.simulation_band(unc, val)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            m = gb.simulation_band(unc, val, method="monte-carlo", n_samples=draws, seed=r)
        inside_d.append((truth[1:] >= d.low[1:]) & (truth[1:] <= d.high[1:]))
        inside_m.append((truth[1:] >= m.low[1:]) & (truth[1:] <= m.high[1:]))
        diverged.append(m.diverged)
    return float(np.mean(inside_d)), float(np.mean(inside_m)), float(np.mean(diverged))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--reps", type=int, default=300)
    ap.add_argument("--draws", type=int, default=300)
    args = ap.parse_args()
    print(f"# {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, {machine()}, git {git_rev()}")
    print(f"\n## coverage of the true free run by the 95 % band ({args.reps} records, {args.draws} draws)\n")
    print("| system | noise σ | delta | Monte Carlo | MC draws diverged |")
    print("| --- | --- | --- | --- | --- |")
    for name in SYSTEMS:
        for noise in (0.02, 0.1, 0.3):
            d, m, dv = _coverage(name, noise, args.reps, args.draws)
            print(f"| {name} | {noise:g} | {d:.3f} | {m:.3f} | {dv:.3%} |", flush=True)
    warnings.simplefilter("ignore")
    data = gb.load_pumping()
    sel = gb.frols(gb.Candidates(ny=6, nu=6, ne=2, degree=2), data.ident, n_terms=17)
    unc = gb.ls_uncertainty(gb.els(sel, data.ident).model, data.ident)
    print("\n## speed (bundled plant, ELS ℓ = 2, 17 terms)\n")
    print("| call | samples | s |")
    print("| --- | --- | --- |")
    for n in (800, 100_000, 1_000_000):
        reps = -(-n // 800)
        rec = gb.Record(np.tile(data.valid.u, reps)[:n], np.tile(data.valid.y, reps)[:n], Ts=data.Ts)
        print(f"| delta | {n} | {timeit(lambda: gb.simulation_band(unc, rec), repeat=3):.3g} |", flush=True)
        if n <= 100_000:
            t = timeit(lambda: gb.simulation_band(unc, rec, method="monte-carlo", n_samples=1000), repeat=3)
            print(f"| Monte Carlo, 1000 draws | {n} | {t:.3g} |", flush=True)


if __name__ == "__main__":
    main()
