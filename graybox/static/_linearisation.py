"""The local linear model of a polynomial NARX model at a steady state: the one derivative map.

At a steady state every lag of a signal has one value (ȳ, ū_1 … ū_m). The one-step map F is then
linearised exactly from the term structure: a factor s(k−l)^p of a term θ ∏ s^P_s contributes
θ p x̄_s^(P_s − 1) ∏_(s' ≠ s) x̄_s'^P_s' to ∂F/∂s(k−l). So the coefficients

    a_l = ∂F/∂y(k−l) = Σ_t θ_t W_t G_tl,     b_il = ∂F/∂u_i(k−l) = Σ_t θ_t V_it H_itl,

are linear in θ: W, V are the terms' *weights* at the point (ȳ^(P_y − 1) ∏ ū^P, and
ȳ^P_y ū_i^(P_i − 1) ∏_(i' ≠ i) ū_i'^P_i'; 0 for a term without that signal) and G, H the terms'
*lag counts* (the powers of their factors at each lag). Every place that needs a local model reads
it from here: the stability test of equilibria (:func:`graybox.static._analysis.stable_mask`), the
stability margin of the simulation-error fits (weights computed once per set of points, then one
matrix product per θ), and the control bridge (a and b, for poles and gains).

The poles are the roots of z^L − a_1 z^(L−1) − … − a_L (:func:`characteristic_roots`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..core._simulation_kernels import Code, encode
from ..core._terms import Structure

__all__ = ["DerivativeMap", "derivative_map", "local_coefficients", "grid_coefficients", "characteristic_roots"]


@dataclass(frozen=True, eq=False)
class DerivativeMap:
    """The lag counts of a structure's steady-state Jacobian, and its weights at any points.

    Attributes
    ----------
    code : Code
        The structure encoded with the inputs in the caller's column order.
    Ly, Lu : int
        Largest output lag; largest input lag over the inputs (unused lags get zero columns).
    G : ndarray, shape (n_terms, Ly)
        G[t, l−1]: the output power of term t at lag l.
    H : ndarray, shape (m, n_terms, Lu)
        H[i, t, l−1]: the power of input i in term t at lag l.
    powers : ndarray, shape (n_terms, 1 + m)
        Each term's total power of [y, u_1 … u_m].
    """

    code: Code
    Ly: int
    Lu: int
    G: np.ndarray
    H: np.ndarray
    powers: np.ndarray

    def output_weights(self, ybar: np.ndarray, ubar: np.ndarray) -> np.ndarray:
        """ȳ^(P_y − 1) ∏_i ū_i^P_i of each term with an output factor (0 for the others), shape (K, n_terms).

        ``ybar`` (K,) output levels; ``ubar`` (K,) or (K, m) input levels (columns in ``code.inputs`` order).
        """
        code = self.code
        T = code.ny.shape[0]
        W = np.zeros((ybar.size, T))
        with np.errstate(all="ignore"):
            for t in range(T):
                p = int(code.ny[t])
                if p == 0:
                    continue
                w = ybar ** (p - 1) if p > 1 else np.ones(ybar.size)
                for f in range(code.uptr[t], code.uptr[t + 1]):
                    col = ubar if ubar.ndim == 1 else ubar[:, code.usig[f]]
                    w = w * col ** code.upow[f]
                W[:, t] = w
        return W

    def input_weights(self, ybar: np.ndarray, ubar: np.ndarray) -> np.ndarray:
        """ȳ^P_y ū_i^(P_i − 1) ∏_(i' ≠ i) ū_i'^P_i' of each term and input i, shape (K, m, n_terms).

        ``ybar`` (K,); ``ubar`` (K, m). A term without input i has weight 0 for it.
        """
        x = np.column_stack([ybar, ubar.reshape(ybar.size, -1)])  # (K, 1 + m)
        m = x.shape[1] - 1
        V = np.zeros((ybar.size, m, self.powers.shape[0]))
        with np.errstate(all="ignore"):
            for i in range(m):
                has = self.powers[:, 1 + i] > 0
                E = self.powers[has].copy()
                E[:, 1 + i] -= 1.0
                V[:, i, has] = np.prod(x[:, None, :] ** E[None, :, :], axis=2)  # 0**0 = 1
        return V


@lru_cache(maxsize=256)
def derivative_map(structure: Structure, inputs: tuple[str, ...] | None = None) -> DerivativeMap:
    """The :class:`DerivativeMap` of ``structure`` with the inputs in the order ``inputs`` (cached).

    ``inputs`` defaults to ``encode(structure).inputs``; it must hold every input the structure uses.
    """
    code = encode(structure, inputs)
    names = code.inputs
    T = len(structure)
    Ly = int(code.ylag.max(initial=0))
    Lu = max((structure.input_lag(n) for n in names), default=0)
    G = np.zeros((T, Ly))
    H = np.zeros((len(names), T, Lu))
    powers = np.zeros((T, 1 + len(names)))
    for t, term in enumerate(structure):
        for s, l, p in term.factors:
            if s == "y":
                G[t, l - 1] += p
                powers[t, 0] += p
            else:
                i = names.index(s)
                H[i, t, l - 1] += p
                powers[t, 1 + i] += p
    for arr in (G, H, powers):
        arr.setflags(write=False)
    return DerivativeMap(code, Ly, Lu, G, H, powers)


def local_coefficients(structure: Structure, inputs: tuple[str, ...] | None, thetas: np.ndarray, ybar: np.ndarray,
                       ubar: np.ndarray, *, with_b: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
    """a_l and b_il at many steady states (exact: read from the term structure).

    Parameters
    ----------
    structure : Structure
        Process terms.
    inputs : tuple of str or None
        The inputs, in the column order of ``ubar`` (None: ``encode(structure).inputs``).
    thetas : ndarray, shape (K, n_terms)
        One parameter vector per steady state.
    ybar : ndarray, shape (K,)
        Output levels.
    ubar : ndarray, shape (K,) or (K, m)
        Input levels.
    with_b : bool
        False skips the input coefficients (then ``b`` is None).

    Returns
    -------
    a : ndarray, shape (K, Ly)
        ∂F/∂y(k−l), l = 1 … Ly (dimensionless).
    b : ndarray, shape (K, m, Lu) or None
        ∂F/∂u_i(k−l) (output units per unit of input i).
    """
    dm = derivative_map(structure, None if inputs is None else tuple(inputs))
    th = np.atleast_2d(np.asarray(thetas, float))
    yb = np.asarray(ybar, float).reshape(th.shape[0])
    ub = np.asarray(ubar, float).reshape(th.shape[0], -1)
    # einsum, not a BLAS product: these are many short rows, and BLAS threads only contend for them
    a = np.einsum("kt,tl->kl", th * dm.output_weights(yb, ub), dm.G)
    if not with_b:
        return a, None
    b = np.einsum("kit,itl->kil", th[:, None, :] * dm.input_weights(yb, ub), dm.H)
    return a, b


def grid_coefficients(structure: Structure, thetas: np.ndarray, ubar: np.ndarray, ybar: np.ndarray) -> np.ndarray:
    """a_l of member p at its steady state (ū_j, ȳ_pj), every pair at once, shape (P, M, Ly).

    The members × points form (equilibria depend on θ; the input part of the weights does not):
    a[p, j] = Σ_q ȳ_pj^q Σ_(t: P_y,t = q + 1) θ_pt g_jt G_t, with g_jt = ∏ ū_j^P the input part.

    Parameters
    ----------
    structure : Structure
        Process terms.
    thetas : ndarray, shape (P, n_terms)
    ubar : ndarray, shape (M,) or (M, m)
        Input levels (M,): every input at ū_j; (M, m): columns in ``encode(structure).inputs`` order.
    ybar : ndarray, shape (P, M)
        Output levels (a non-finite one gives non-finite or meaningless coefficients: mask it).
    """
    dm = derivative_map(structure)
    th = np.atleast_2d(np.asarray(thetas, float))
    yb = np.atleast_2d(np.asarray(ybar, float))
    ub = np.asarray(ubar, float)
    g = dm.output_weights(np.ones(ub.shape[0]), ub)  # (M, T): ȳ = 1 leaves the input part
    py = dm.powers[:, 0]
    a = np.zeros(yb.shape + (dm.Ly,))
    with np.errstate(all="ignore"):
        for p in np.unique(py[py > 0]):
            sel = py == p
            part = np.einsum("pt,jtl->pjl", th[:, sel], g[:, sel, None] * dm.G[sel])
            a += part if p == 1 else yb[:, :, None] ** (p - 1) * part
    return a


def characteristic_roots(a: np.ndarray) -> np.ndarray:
    """Roots of z^L − a_1 z^(L−1) − … − a_L for many rows: a (K, L) → (K, L) complex (companion eigenvalues)."""
    K, L = a.shape
    if L == 0:
        return np.zeros((K, 0), complex)
    C = np.zeros((K, L, L))
    C[:, 0, :] = a
    C[:, np.arange(1, L), np.arange(L - 1)] = 1.0
    return np.linalg.eigvals(C)
