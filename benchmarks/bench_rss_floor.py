"""The round-off of an exact fit's residual sum of squares, against the floor FROLS and its searches put under it.

    python benchmarks/bench_rss_floor.py

Noise-free y(k) − c = a (y(k-1) − c) + (u(k-1) − ū) + 0.1 (u(k-1) − ū)², fitted in raw monomials (1, y(k-1), u(k-1),
u(k-1)^2) on unit-RMS columns, simulated either in those raw terms (which cancel to a small y when ū is large) or
centred. For N 50 … 1e5, c 0 … 1e8, ū 0 … 1e4, a 0.5 and 0.999 (192 cases), the residual sum of squares of the true
structure by QR of [S, y] and by MGS, in units of eps² (yᵀy + N (Σ|θ_s|)²) (θ_s: the unit-RMS columns' parameters):
the largest is printed; FROLS's floor (``_subset_search.ROUND_OFF``) is 1e4 of those units.
"""

from __future__ import annotations

import warnings

import numpy as np

import graybox as gb
from graybox import stacked_regressors

EPS = np.finfo(float).eps
TRUE = gb.Structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"])


def simulate(u: np.ndarray, c: float, a: float, uc: float, raw: bool) -> np.ndarray:
    y = np.zeros(len(u))
    y[0] = c
    th0, thu = (1 - a) * c + 0.1 * uc * uc - uc, 1 - 0.2 * uc
    for k in range(1, len(u)):
        if raw:
            y[k] = th0 + a * y[k - 1] + thu * u[k - 1] + 0.1 * u[k - 1] ** 2
        else:
            y[k] = a * (y[k - 1] - c) + (u[k - 1] - uc) + 0.1 * (u[k - 1] - uc) ** 2 + c
    return y


def main() -> None:
    warnings.simplefilter("ignore")
    rng = np.random.default_rng(0)
    worst, cases = 0.0, 0
    for N in (50, 300, 10_000, 100_000):
        for c in (0.0, 1e3, 1e6, 1e8):
            for uc in (0.0, 1e3, 1e4):
                for a in (0.5, 0.999):
                    for raw in (True, False):
                        u = rng.uniform(-1, 1, N) + uc
                        X, t = stacked_regressors(TRUE, gb.Record(u, simulate(u, c, a, uc, raw)), start=2)
                        S = X / np.sqrt((X * X).mean(0))
                        R = np.linalg.qr(np.column_stack([S, t]), mode="r")
                        T = np.abs(np.linalg.solve(R[:4, :4], R[:4, 4])).sum()
                        Q = np.linalg.qr(S)[0]
                        r = t - Q @ (Q.T @ t)
                        r -= Q @ (Q.T @ r)
                        unit = EPS**2 * (t @ t + len(t) * T * T)
                        worst = max(worst, R[-1, -1] ** 2 / unit, r @ r / unit)
                        cases += 1
    print(f"{cases} cases: an exact fit's RSS at most {worst:.2f} eps² (yᵀy + N (Σ|θ_s|)²); the floor is 1e4 of that")


if __name__ == "__main__":
    main()
