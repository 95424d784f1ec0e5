"""Coverage of ls_, cls_, pe_ and se_uncertainty's 95 % intervals on a small known system, by Monte Carlo.

    .venv/bin/python benchmarks/bench_coverage.py [--reps 200] [--only ls,cls,pe,se]

The plant y(k) = 0.5 y(k-1) + 0.3 u(k-1) + 0.2 u(k-1)y(k-1) + 0.1 u(k-2)^2 (a rational static function), 200
samples, u held 5 samples at uniform levels in [−1, 1], fitted with its own four terms. Each replicate draws a new
input, new noise and new static points; the rows:

- **LS**: least squares (``cls`` without static information) on equation noise e ~ N(0, 0.02²).
- **CLS**: ``cls`` through 2 exact static points (how="points"; the true θ meets them), equation noise.
- **PE**: the PE member (closed form) at λ1 with 7 static points ȳ(ū_i) + N(0, 0.02²) and equation noise; the
  default σ_SF (its misfit) and the true one given (``static_sigma=0.02``).
- **SE**: the SE member (gradient) at λ1 on *output* noise y = ŷ_free + N(0, 0.02²) (the white output errors
  its intervals assume), with the same static points.

Columns: the share of replicates whose interval holds the true θ_j (the worst and the mean over the four
terms; ±1.5 % is the Monte Carlo's own standard error at 200 replicates), and the median reported std over the
replicates' spread of θ̂_j (worst and best term); the worst share holding the replicates' mean θ̂ instead (where
the member is on average) and the largest |mean θ̂_j − θ_j| over the spread (the estimator's bias: the measured ȳ_i
sits on both sides of PE's static equation, an errors-in-variables regression). A PE or SE member is a biased estimate of the true θ by design
only where the static points disagree with the dynamic data; here both come from the plant, so the intervals
are judged against the true θ.
"""

from __future__ import annotations

import argparse
import datetime
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402

import graybox as gb  # noqa: E402

TERMS = ["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "u(k-2)^2"]
THETA = np.array([0.5, 0.3, 0.2, 0.1])
TRUE = gb.Model(TERMS, THETA)
UB = np.linspace(-0.9, 0.9, 7)
SIGMA = 0.02


def replicate(rng: np.random.Generator, output_noise: bool = False, n: int = 200) -> tuple[gb.Record, np.ndarray]:
    u = np.repeat(rng.uniform(-1.0, 1.0, n // 5 + 1), 5)[:n]
    if output_noise:
        y = TRUE.simulate(u, np.zeros(2)) + SIGMA * rng.standard_normal(n)
    else:
        e = SIGMA * rng.standard_normal(n)
        y = np.zeros(n)
        for k in range(2, n):
            y[k] = (0.5 * y[k - 1] + 0.3 * u[k - 1] + 0.2 * u[k - 1] * y[k - 1] + 0.1 * u[k - 2] ** 2 + e[k])
    return gb.Record(u, y), TRUE.static_curve(UB) + SIGMA * rng.standard_normal(UB.size)


def fit(method: str, rng: np.random.Generator, lam: float) -> list[gb.ParameterUncertainty]:
    rec, yb = replicate(rng, output_noise=method == "SE")
    pts = gb.StaticPoints(UB, yb)
    if method == "LS":
        return [gb.ls_uncertainty(gb.cls(TERMS, rec).model, rec)]
    if method == "CLS":
        exact = gb.StaticPoints([-0.5, 0.5], TRUE.static_curve([-0.5, 0.5]))
        return [gb.cls_uncertainty(gb.cls(TERMS, rec, exact, how="points").model, rec, exact, how="points")]
    if method == "PE":
        m = gb.Model(TERMS, gb.pe_thetas(TERMS, rec, pts, lambdas=[lam], solver="closed")[0])
        return [gb.pe_uncertainty(m, rec, pts, lambda1=lam), gb.pe_uncertainty(m, rec, pts, lambda1=lam, static_sigma=SIGMA)]
    m = gb.se_pareto(TERMS, rec, pts, lambdas=[lam], method="gradient", margin=None, progress=False).member_model(0)
    return [gb.se_uncertainty(m, rec, pts, lambda1=lam), gb.se_uncertainty(m, rec, pts, lambda1=lam, static_sigma=SIGMA)]


def study(method: str, lam: float, reps: int, seed: int = 1) -> list[dict]:
    rng = np.random.default_rng(seed)
    runs = []
    for _ in range(reps):
        try:
            runs.append(fit(method, rng, lam))
        except ValueError as exc:  # counted, not hidden
            runs.append(str(exc))
    ok = [r for r in runs if not isinstance(r, str)]
    rows = []
    for k, label in enumerate(["default σ_SF", "σ_SF given"][:len(ok[0])]):
        cover = np.mean([u[k].covers(THETA) for u in ok], axis=0)
        spread = np.std([u[k].theta for u in ok], axis=0)
        ratio = np.median([u[k].std for u in ok], axis=0) / spread
        centre = np.mean([u[k].theta for u in ok], axis=0)
        around = np.mean([u[k].covers(centre) for u in ok], axis=0)
        rows.append({"method": method, "λ1": lam, "σ_SF": label if method in ("PE", "SE") else "—",
                     "fits": len(ok), "refused": len(runs) - len(ok), "coverage worst": cover.min(),
                     "coverage mean": cover.mean(), "of mean θ̂ worst": around.min(),
                     "|bias|/spread max": np.max(np.abs(centre - THETA) / spread),
                     "std/spread worst": ratio.min(), "std/spread best": ratio.max()})
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--reps", type=int, default=200)
    ap.add_argument("--only", default="LS,CLS,PE,SE")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    print(f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, {machine()}, git {git_rev()}, "
          f"{args.reps} replicates\n")
    plan = {"LS": [1.0], "CLS": [1.0], "PE": [0.01, 0.5], "SE": [0.5, 1.0]}
    rows = [r for m in args.only.split(",") for lam in plan[m] for r in study(m, lam, args.reps)]
    keys = list(rows[0])
    print("| " + " | ".join(keys) + " |")
    print("|" + "---|" * len(keys))
    for r in rows:
        print("| " + " | ".join(f"{v:.3g}" if isinstance(v, float) else str(v) for v in r.values()) + " |", flush=True)


if __name__ == "__main__":
    main()
