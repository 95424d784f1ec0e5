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
from functools import cached_property, lru_cache

import numpy as np

from ..core._simulation_kernels import Code, encode
from ..core._terms import Structure
from ._equilibrium_kernels import entry_sums

__all__ = ["DerivativeMap", "derivative_map", "local_coefficients", "grid_coefficients", "characteristic_roots"]


#: Bytes of point sets (ū and their entries' input parts) a map remembers: a fit's static points take a few
#: kB; the maps live as long as the process (derivative_map's cache), so large sets are not kept.
_POINT_CACHE_BYTES = 1 << 18


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

    def input_part(self, ubar: np.ndarray) -> np.ndarray:
        """∏_i ū_i^P_i of each term, shape (K, n_terms).

        ``ubar`` (K, m): columns in ``code.inputs`` order; (K,): every input at ū (ū^μ, μ the
        term's total input power).
        """
        ub = np.asarray(ubar, float)
        with np.errstate(all="ignore"):
            U = np.ones((ub.shape[0], self.powers.shape[0]))
            if ub.ndim == 1:
                mu = self.powers[:, 1:].sum(axis=1)
                for t in np.flatnonzero(mu):
                    U[:, t] = ub ** mu[t]
                return U
            for t in range(U.shape[1]):
                for i in np.flatnonzero(self.powers[t, 1:]):
                    U[:, t] = U[:, t] * ub[:, i] ** self.powers[t, 1 + i]
        return U

    def output_part(self, ybar: np.ndarray) -> np.ndarray:
        """ȳ^(P_y − 1) of each term with an output factor (1 for the others), shape (K, n_terms)."""
        with np.errstate(all="ignore"):
            return np.asarray(ybar, float)[:, None] ** np.maximum(self.powers[:, 0] - 1.0, 0.0)[None, :]

    def output_weights(self, ybar: np.ndarray, ubar: np.ndarray) -> np.ndarray:
        """W = ȳ^(P_y − 1) ∏_i ū_i^P_i of each term with an output factor (0 for the others), shape (K, n_terms).

        a = (θ ⊙ W) G: the form for many θ at the same points. ``ybar`` (K,); ``ubar`` as for
        :meth:`input_part`.
        """
        with np.errstate(all="ignore"):
            return np.where(self.powers[:, 0] > 0, self.output_part(ybar) * self.input_part(ubar), 0.0)

    def coefficients(self, thetas: np.ndarray, ybar: np.ndarray, ubar: np.ndarray) -> np.ndarray:
        """a_l = Σ_t θ_t G_tl ȳ^(P_y − 1) ∏ ū^P, one row per steady state, shape (K, Ly).

        ``thetas`` (K, n_terms), ``ybar`` (K,), ``ubar`` as for :meth:`input_part`. Summed term by
        term in structure order, θ_t = 0 skipped (so an overflowing weight of a zero term is no NaN).
        """
        return self._sum_entries(np.asarray(thetas, float), np.asarray(ybar, float).ravel(),
                                 self.input_part(ubar)[:, self._entries[0]])

    @cached_property
    def _entries(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The nonzero entries of G in structure order: (term t, lag index l, count G_tl, output exponent
        max(P_y − 1, 0) of term t), each shape (entries,)."""
        t, l = np.nonzero(self.G)
        out = (t.astype(np.int64), l.astype(np.int64), self.G[t, l].copy(), np.maximum(self.powers[t, 0] - 1.0, 0.0))
        for arr in out:
            arr.setflags(write=False)
        return out

    def _sum_entries(self, th: np.ndarray, yb: np.ndarray, U: np.ndarray) -> np.ndarray:
        """a from each row's θ (R, T), ȳ (R,) and the entries' input parts U (R, entries): ((θ_t G_tl) ȳ^(P_y − 1)) ∏ ū^P,
        summed per lag entry by entry in order (no pairwise reordering), compiled (:func:`entry_sums`)."""
        t, l, g, yexp = self._entries
        return entry_sums(np.ascontiguousarray(th, dtype=float), np.ascontiguousarray(yb, dtype=float),
                          np.ascontiguousarray(U, dtype=float), t, l, g, yexp, self.Ly)

    def entry_inputs(self, ubar: np.ndarray) -> np.ndarray:
        """The input part ∏ ū^P of each entry of G at fixed points ``ubar`` (as for :meth:`input_part`), shape
        (K, entries), read-only. Remembered for the last few small point sets: a fit asks for the same static
        points at every trial θ."""
        ub = np.ascontiguousarray(ubar, dtype=float)
        if ub.nbytes > _POINT_CACHE_BYTES:  # a fine static curve: not a fit's points, not kept (the map lives on)
            return self.input_part(ub)[:, self._entries[0]]
        key = (ub.shape, ub.tobytes())
        cache = self._point_cache
        U = cache.get(key)
        if U is None:
            U = self.input_part(ub)[:, self._entries[0]]
            U.setflags(write=False)
            size = U.nbytes + ub.nbytes
            if size <= _POINT_CACHE_BYTES:
                if len(cache) >= 16 or size + sum(v.nbytes + len(k[1]) for k, v in cache.items()) > _POINT_CACHE_BYTES:
                    cache.clear()
                cache[key] = U
        return U

    @cached_property
    def _point_cache(self) -> dict:
        return {}

    def input_coefficients(self, thetas: np.ndarray, ybar: np.ndarray, ubar: np.ndarray) -> np.ndarray:
        """b_il = Σ_t θ_t H_itl ȳ^P_y ū_i^(P_i − 1) ∏_(i' ≠ i) ū_i'^P_i', shape (K, m, Lu).

        ``thetas`` (K, n_terms), ``ybar`` (K,), ``ubar`` (K, m).
        """
        th = np.asarray(thetas, float)
        x = np.column_stack([np.asarray(ybar, float), np.asarray(ubar, float).reshape(th.shape[0], -1)])
        m = x.shape[1] - 1
        b = np.zeros((th.shape[0], m, self.Lu))
        with np.errstate(all="ignore"):
            for i in range(m):
                for t in np.flatnonzero(self.powers[:, 1 + i]):
                    e = self.powers[t].copy()
                    e[1 + i] -= 1.0
                    v = th[:, t] * np.prod(x ** e, axis=1)  # 0**0 = 1
                    for l in np.flatnonzero(self.H[i, t]):
                        b[:, i, l] += np.where(th[:, t] == 0.0, 0.0, v * self.H[i, t, l])
        return b


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
    a = dm.coefficients(th, yb, ub)
    return a, (dm.input_coefficients(th, yb, ub) if with_b else None)


def grid_coefficients(structure: Structure, thetas: np.ndarray, ubar: np.ndarray, ybar: np.ndarray) -> np.ndarray:
    """a_l of member p at its steady state (ū_j, ȳ_pj), every pair at once, shape (P, M, Ly).

    The members × points form, for equilibria that depend on θ (the stability test of every root
    of every member, the margin at the static points): :meth:`DerivativeMap.coefficients` of
    every (member, point) pair.

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
    yb = np.atleast_2d(np.asarray(ybar, float))
    P, M = yb.shape
    th = np.broadcast_to(np.atleast_2d(np.asarray(thetas, float)), (P, len(structure)))
    U = dm.entry_inputs(np.asarray(ubar, float))  # the input part depends on the points only
    a = dm._sum_entries(np.repeat(th, M, axis=0), yb.ravel(), np.tile(U, (P, 1)) if P > 1 else U)
    return a.reshape(P, M, dm.Ly)


def characteristic_roots(a: np.ndarray) -> np.ndarray:
    """Roots of z^L − a_1 z^(L−1) − … − a_L for many rows: a (K, L) → (K, L) complex (companion eigenvalues)."""
    K, L = a.shape
    if L == 0:
        return np.zeros((K, 0), complex)
    C = np.zeros((K, L, L))
    C[:, 0, :] = a
    C[:, np.arange(1, L), np.arange(L - 1)] = 1.0
    return np.linalg.eigvals(C)
