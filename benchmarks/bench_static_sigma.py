"""pe_uncertainty's default static σ (σ_SF) against a Monte Carlo of noisy static points.

    .venv/bin/python benchmarks/bench_static_sigma.py [--reps 200] [--sigma 0.02]

Three small plants (200 samples, equation noise 0.02, u held 5 samples at uniform levels in [−1, 1]) and 7
static points at ū = −0.9 … 0.9: a *polynomial* static function (1, y(k-1), u(k-1), u(k-1)^2: ∂s/∂ȳ the same at
every point), a *rational* one (the closure of y(k-1), u(k-1), u(k-1)y(k-1), u(k-2)^2: ∂s/∂ȳ = −D(ū)) and a
*quadratic* one (the closure of y(k-1), u(k-1), y(k-1)^2, u(k-1)y(k-1): ∂s/∂ȳ depends on ȳ, and small-λ1 members
bend towards a fold of their static curve). The dynamic record is fixed; each replicate draws ȳ_i = ȳ(ū_i) +
bias·sin(3ū_i) + σ ε_i, refits the PE member at λ1 (closed form, eq. (11)) and asks pe_uncertainty for its default
σ_SF. Columns: the Monte Carlo E Σ(s_i/g_i)² / σ² less the noise-free points' misfit (the misfit's degrees of
freedom in ȳ-distances, s = QRθ − ȳ, g = ∂s/∂ȳ), the reported σ_SF over the true σ (its 5 % quantile and median, and √mean σ̂²/σ), and the member's ȳ(0.3) std from
static_curve_band with that σ_SF over the Monte Carlo spread of the members' ȳ(0.3) (median). With bias the
reported σ must be at least σ (the systematic misfit counts as noise: the safe side).
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
from graybox.estimation._prediction_error import static_prediction  # noqa: E402
from graybox.selection._centring import closure  # noqa: E402

UB = np.linspace(-0.9, 0.9, 7)
AT = 0.3
PLANTS = {
    "polynomial": (["1", "y(k-1)", "u(k-1)", "u(k-1)^2"], [0.0, 0.5, 0.3, 0.2], False),
    "rational": (["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "u(k-2)^2"], [0.5, 0.3, 0.2, 0.1], True),
    "quadratic": (["y(k-1)", "u(k-1)", "y(k-1)^2", "u(k-1)y(k-1)"], [0.5, 0.3, -0.1, 0.1], True),
}


def misfit(st: gb.Structure, theta: np.ndarray, ybar: np.ndarray) -> float:
    """Σ(s_i/g_i)² of the static equation's residuals s = QRθ − ȳ (g = ∂s/∂ȳ, central differences: exact for a
    static equation at most quadratic in ȳ)."""
    def s(yb):
        return static_prediction(st, theta, gb.StaticPoints(UB, yb)) - yb
    h = 1e-4
    r = s(ybar)
    g = np.array([(s(ybar + h * e) - s(ybar - h * e))[i] / (2 * h) for i, e in enumerate(np.eye(UB.size))])
    return float(np.sum((r / g) ** 2))


def study(name: str, lam: float, sigma: float, bias: float, reps: int, seed: int = 0) -> dict:
    terms, theta, close = PLANTS[name]
    true = gb.Model(terms, theta)
    st = closure(true.structure) if close else true.structure
    rng = np.random.default_rng(seed)
    n = 200
    u = np.repeat(rng.uniform(-1.0, 1.0, n // 5 + 1), 5)[:n]
    rec = gb.Record(u, true.simulate(u, np.zeros(2)) + 0.02 * rng.standard_normal(n))
    yb0 = true.static_curve(UB) + bias * np.sin(3 * UB)

    def member(yb):
        return gb.pe_thetas(st, rec, gb.StaticPoints(UB, yb), lambdas=[lam], solver="closed")[0]
    a0 = misfit(st, member(yb0), yb0)
    A, rep, ystd, yat, failed = [], [], [], [], 0
    for _ in range(reps):
        yb = yb0 + sigma * rng.standard_normal(UB.size)
        th = member(yb)
        A.append(misfit(st, th, yb))
        try:
            unc = gb.pe_uncertainty(gb.Model(st, th), rec, gb.StaticPoints(UB, yb), lambda1=lam)
            band = gb.static_curve_band(unc, [AT])
        except ValueError:
            failed += 1
            continue
        rep.append(np.sqrt(unc.static_sigma2))
        ystd.append(band.ybar_std[0])
        yat.append(band.ybar[0])
    rep = np.array(rep)
    return {"structure": name, "λ1": lam, "bias": bias, "E Σ(s/g)²/σ²": (np.mean(A) - a0) / sigma**2,
            "σ̂/σ 5 %": np.quantile(rep, 0.05) / sigma, "σ̂/σ median": np.median(rep) / sigma, "√E σ̂²/σ": np.sqrt(np.mean(rep**2)) / sigma,
            # at λ1 = 1 the points do not move the member: no spread to compare with
            "ȳ std / spread": np.median(ystd) / np.std(yat) if lam < 1 else float("nan"), "refused": failed}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--reps", type=int, default=200)
    ap.add_argument("--sigma", type=float, default=0.02)
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    print(f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, {machine()}, git {git_rev()}, "
          f"{args.reps} replicates, σ = {args.sigma:g}\n")
    rows = [study(name, lam, args.sigma, bias, args.reps) for name in PLANTS for bias in (0.0, 0.05)
            for lam in (1e-3, 1e-2, 0.1, 0.5, 1.0)]
    keys = list(rows[0])
    print("| " + " | ".join(keys) + " |")
    print("|" + "---|" * len(keys))
    for r in rows:
        print("| " + " | ".join(f"{v:.3g}" if isinstance(v, float) else str(v) for v in r.values()) + " |")


if __name__ == "__main__":
    main()
