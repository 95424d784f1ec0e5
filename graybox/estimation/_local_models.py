"""The local linear models of a polynomial NARX model, and a stability margin on them.

At an operating point (ū, ȳ) — every input lag at ū, every output lag at ȳ — the model's
linearisation is the recursion δy(k) = Σ_l a_l δy(k−l) with a_l = Σ_t θ_t ∂φ_t/∂y(k−l). For a term
θ_t ū^μ_t ȳ^(m_t) (input power μ_t, output power m_t) that is θ_t ū^μ_t ȳ^(m_t − 1) times the
number of its output factors at lag l, so a = (W ⊙ θ) G with W the points' weights (one row per
point, one column per term) and G the terms' lag counts: linear in θ, computed once per set of
points. W and G are the package's one derivative map (:mod:`graybox.static._linearisation`); this
module keeps only the many-θ form of it. At an equilibrium this is the local model whose stability
:func:`graybox.static._analysis.stable_mask` decides; away from one it is the frozen-time model of
a sample the record visits.

Why a margin. A free-run (simulation-error) fit can buy identification error with near-unit
roots that follow the record's slow drift: on the bundled plant the gradient SE members reach a
spectral radius of 0.99975 at every static point and wander off on new data. Asking every local
model to keep its spectral radius ρ ≤ 1 − margin (at the static points' equilibria and at samples
along the record) rules those out. The test is the Schur–Cohn recursion of the package's one
stability test applied to the polynomial with its variable scaled by 1 − margin
(ρ(a) ≤ r ⇔ z^L − (a_1/r) z^(L−1) − … − a_L/r^L has no root outside the unit circle), compiled and
cheap enough for every trial point of a fit and every individual of a GA generation.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..core._records import Record
from ..core._simulation_kernels import encode, kernel_array, record_inputs
from ..core._terms import Structure
from ..core._validation import check_choice, check_real
from ..static._equilibrium_kernels import schur_stable_rows
from ..static._linearisation import characteristic_roots, derivative_map, grid_coefficients

__all__ = ["LocalModels", "record_points", "within_at", "check_margin", "slow_margin", "RECORD_POINTS",
           "SLOW_FACTOR", "SlowModeWarning"]

#: Samples of the record(s) at which the margin is checked, at most (evenly spaced).
RECORD_POINTS = 64

#: A mode is slow when its distance to the unit circle, 1 − ρ, is under 1/SLOW_FACTOR of the
#: least-squares model's along the same record (for ρ near 1, a time constant Ts / (1 − ρ) over
#: SLOW_FACTOR times the least-squares model's slowest). Over 19 structures × 10 gradient SE members
#: on six data sets, the members this flags erred 5× to 10⁸× the others on new records and no
#: member it passed did (BENCHMARKS.md, "A slow-mode check").
SLOW_FACTOR = 10.0


class SlowModeWarning(UserWarning):
    """A fit's local models have modes far slower than the least-squares model's (``SLOW_FACTOR``).

    Such near-integrators buy identification error by following the record's slow drift and err on
    new records; ``margin="auto"`` keeps every mode within the factor.
    """


def check_margin(margin: object) -> float | str | None:
    """``margin`` as a float in [0, 1), ``"auto"`` (:func:`slow_margin` of the least-squares fit), or None."""
    if margin is None:
        return None
    if isinstance(margin, str):
        return check_choice(margin, "margin", ("auto",))
    return check_real(margin, "margin", low=0.0, high=1.0, high_open=True)


def slow_margin(rho_ls: float) -> float | None:
    """The margin that keeps every mode within :data:`SLOW_FACTOR` of the least-squares model's slowest.

    ``rho_ls`` is the largest spectral radius of the least-squares model's local models along the
    records; the margin is (1 − ρ_LS) / SLOW_FACTOR, or None when ρ_LS ≥ 1 (a least-squares model
    unstable somewhere along the record is no reference). Dimensionless and independent of the
    sampling period: halve Ts and both 1 − ρ halve.
    """
    return (1.0 - float(rho_ls)) / SLOW_FACTOR if rho_ls < 1.0 else None


def record_points(structure: Structure, records: Sequence[Record], count: int = RECORD_POINTS
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Up to ``count`` operating points (u(k), y(k)) measured along the records, evenly spaced.

    Returns
    -------
    ubar : ndarray, shape (P,) or (P, m)
        The input(s) at those samples, columns in the order of ``encode(structure).input_names``.
    ybar : ndarray, shape (P,)
    """
    code = encode(structure)
    L = structure.max_lag
    total = sum(max(len(r) - L, 0) for r in records)
    stride = max(1, -(-total // count))
    us, ys = [], []
    offset = 0  # the samples are every stride-th of all records' rows in turn: at most count in all (a stride per
    for r in records:  # record took up to one more per record)
        u = record_inputs(r, code.input_names)
        first = L + (-offset) % stride
        us.append(u[first::stride])
        ys.append(r.y[first::stride])
        offset += max(len(r) - L, 0)
    return np.concatenate(us), np.concatenate(ys)


class LocalModels:
    """The local linear models of one structure at fixed operating points, for many θ at once.

    Parameters
    ----------
    structure : Structure
        Process terms.
    ubar : ndarray, shape (P,) or (P, m)
        Input level(s) of each point (columns in the order of ``encode(structure).input_names``).
    ybar : ndarray, shape (P,)
        Output level of each point.
    """

    def __init__(self, structure: Structure, ubar: np.ndarray, ybar: np.ndarray):
        dm = derivative_map(structure)
        self.L = dm.Ly
        T = len(structure)
        self.G = dm.G if self.L else np.zeros((T, 1))
        self.W = dm.output_weights(np.asarray(ybar, float), np.asarray(ubar, float))
        # a(θ) for every point at once is one matrix product: θ (T,) @ WG (T, P·L)
        self.WG = (self.W.T[:, :, None] * self.G[:, None, :]).reshape(T, -1)

    def coefficients(self, theta: np.ndarray) -> np.ndarray:
        """a_1 … a_L of each point's local model, shape (P, L)."""
        return (self.W * np.asarray(theta, float)) @ self.G

    def radius(self, theta: np.ndarray) -> np.ndarray:
        """Spectral radius of each point's local model (dimensionless), shape (P,)."""
        a = self.coefficients(theta)
        P = a.shape[0]
        if self.L == 0 or P == 0:
            return np.zeros(P)
        if not np.all(np.isfinite(a)):
            out = np.full(P, np.inf)
            ok = np.all(np.isfinite(a), axis=1)
            out[ok] = _radius(a[ok])
            return out
        return _radius(a)

    def within(self, thetas: np.ndarray, margin: float) -> np.ndarray:
        """Does every point's local model of each row keep ρ ≤ 1 − margin? Shape (K,).

        ρ < 1 − margin strictly (the Schur–Cohn test is strict); equality has measure zero.
        """
        th = np.atleast_2d(np.asarray(thetas, float))
        K, P = th.shape[0], self.W.shape[0]
        if self.L == 0 or P == 0:
            return np.ones(K, bool)
        a = th @ self.WG  # (K, P·L): row k holds a_1 … a_L of each point in turn
        return _within(a.reshape(K * P, self.L), margin).reshape(K, P).all(axis=1)


def within_at(structure: Structure, thetas: np.ndarray, ubar: np.ndarray, ybar: np.ndarray, margin: float
              ) -> np.ndarray:
    """Does row k keep ρ ≤ 1 − margin at its own points (ū_j, ȳ_kj), every finite ȳ_kj? Shape (K,).

    For equilibria that depend on θ (the static points'): ``thetas`` (K, T), ``ubar`` (M,) or
    (M, m), ``ybar`` (K, M); a non-finite ȳ_kj is skipped.
    """
    yb = np.atleast_2d(np.asarray(ybar, float))
    K, M = yb.shape
    L = derivative_map(structure).Ly
    if L == 0 or M == 0:
        return np.ones(K, bool)
    fin = np.isfinite(yb)
    a = grid_coefficients(structure, thetas, np.asarray(ubar, float), np.where(fin, yb, 0.0))
    ok = _within(a.reshape(K * M, L), margin) | ~fin.ravel()
    return ok.reshape(K, M).all(axis=1)


def _within(a: np.ndarray, margin: float) -> np.ndarray:
    """Row-wise: is every root of z^L − a_1 z^(L−1) − … − a_L of modulus < 1 − margin? (Schur–Cohn, scaled)."""
    r = 1.0 - margin
    if r <= 0.0:
        return np.zeros(a.shape[0], bool)
    return schur_stable_rows(kernel_array(a / r ** np.arange(1, a.shape[1] + 1)))


def _radius(a: np.ndarray) -> np.ndarray:
    """Largest root modulus of z^L − a_1 z^(L−1) − … − a_L, row by row (companion eigenvalues)."""
    return np.abs(characteristic_roots(a)).max(axis=1)
