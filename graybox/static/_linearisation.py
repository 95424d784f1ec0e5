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

At an equilibrium the lags sum away: F(ȳ, ū) = Σ_t θ_t ȳ^p_t ∏_i ū_i^A_ti − ȳ = 0, whose partials
F_ȳ = Σ_l a_l − 1 and F_ūi = Σ_l b_il give every static gain ∂ȳ/∂ū_i = −F_ūi / F_ȳ, every sensitivity
∂ȳ/∂θ_t = −ȳ^p_t ∏ ū^A_t / F_ȳ and the gains' own θ-gradient (:func:`static_partials`,
:func:`static_gains`, :func:`static_theta_gradient_of`, :func:`static_gain_gradient`): the static curve's
and surface's gains, the SE fits' static Jacobian and the delta and Monte Carlo bands all read them here.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

from ..core._simulation_kernels import Code, encode, kernel_array
from ..core._terms import Structure
from ._equilibrium_kernels import entry_sums

__all__ = ["DerivativeMap", "derivative_map", "local_coefficients", "grid_coefficients", "characteristic_roots",
           "input_monomials_of", "split_power", "times_monomials", "static_powers", "static_partials", "static_gains",
           "static_theta_gradient_of", "static_gain_gradient"]


#: Bytes of point sets (ū and their entries' input parts) a map remembers: a fit's static points take a few
#: kB; the maps live as long as the process (derivative_map's cache), so large sets are not kept.
_POINT_CACHE_BYTES = 1 << 18


@lru_cache(maxsize=1024)
def _power_plan(exponents: tuple[float, ...]) -> tuple[tuple[float, ...], np.ndarray]:
    """The distinct exponents, in order of appearance, and each exponent's index among them."""
    distinct = tuple(dict.fromkeys(exponents))
    index = np.array([distinct.index(k) for k in exponents], dtype=np.intp)
    index.setflags(write=False)
    return distinct, index


def _powers(x: np.ndarray, exponents: np.ndarray) -> np.ndarray:
    """x ** e_t for each exponent, shape x.shape + (n,): one scalar power per distinct exponent (an array of
    exponents rounds otherwise, and a single-input result stays bit for bit ``x ** e``); x⁰ = 1, NaN⁰ too."""
    x = np.asarray(x, float)
    distinct, index = _power_plan(tuple(np.asarray(exponents, float).ravel().tolist()))
    if not distinct:
        return np.ones(x.shape + (0,))
    with np.errstate(all="ignore"):
        cols = [np.ones_like(x) if k == 0 else x ** k for k in distinct]
    return np.stack(cols, axis=-1)[..., index]


def input_monomials_of(A: np.ndarray, ubar: np.ndarray) -> np.ndarray:
    """∏_i ū_i^A_ti of each term t at each point, shape (M, n): ``A`` (n, m) the terms' input powers, ``ubar``
    (M, m); the factors multiplied input by input."""
    ub = np.asarray(ubar, float)
    A = np.asarray(A, float)
    out = np.ones((ub.shape[0], A.shape[0]))
    with np.errstate(all="ignore"):
        for i in np.flatnonzero(A.any(axis=0)):
            out = out * _powers(ub[:, i], A[:, i])
    return out


def split_power(c: np.ndarray, x: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """c · x^m, broadcast, as a mantissa and a power of two (``np.ldexp(*split_power(c, x, m))`` is the product), where
    x^m alone may leave the float range and the product not (1e-300 · 1e200², 1e300 · 1e-200²): exact scaling, so an
    in-range product is bit for bit ``c * x ** m``; 0 where c = 0 (no 0 · inf)."""
    fx, ex = np.frexp(np.asarray(x, float))
    fc, ec = np.frexp(np.asarray(c, float))
    return fc * fx ** m, ec + ex * int(m)


def times_monomials(c: np.ndarray, A: np.ndarray, ubar: np.ndarray) -> np.ndarray:
    """c[..., t] · ∏_i ū_i^A_ti at each point, shape (..., M, n): ``c`` (P, 1, n) or (n,), ``A`` (n, m) integer input
    powers, ``ubar`` (M, m); as :func:`input_monomials_of` times c, the powers taken in mantissas and powers of two
    (:func:`split_power`'s reason)."""
    f, e = np.frexp(np.asarray(ubar, float))
    A = np.asarray(A, float)
    return _times_scaled(c, input_monomials_of(A, f), e @ np.rint(A).astype(np.int64).T)


def _times_scaled(c: np.ndarray, mant: np.ndarray, exp: np.ndarray) -> np.ndarray:
    """c · mant · 2^exp without an intermediate leaving the float range (inf only where the product does)."""
    fc, ec = np.frexp(np.asarray(c, float))
    with np.errstate(all="ignore"):  # mant may be NaN⁰-like or inf at a non-finite level: carried, not warned of
        return np.ldexp(fc * mant, ec + exp)


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

        ``ubar`` (K, m): columns in ``code.input_names`` order; (K,): every input at ū (ū^μ, μ the
        term's total input power).
        """
        ub = np.asarray(ubar, float)
        if ub.ndim != 1:
            return input_monomials_of(self.powers[:, 1:], ub)
        U = np.ones((ub.shape[0], self.powers.shape[0]))
        mu = self.powers[:, 1:].sum(axis=1)
        with np.errstate(all="ignore"):
            for t in np.flatnonzero(mu):
                U[:, t] = ub ** mu[t]
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
        return entry_sums(kernel_array(th), kernel_array(yb), kernel_array(U), t, l, g, yexp, self.Ly)

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


#: Largest output lag (samples) the static and local analyses take: they hold the output's L×L companion matrix at
#: each steady state. A hand-edited y(k-99999999999) asked numpy for TiB (MemoryError).
MAX_ANALYSIS_LAG = 10_000
#: Largest input lag: an input's lags take per-lag arrays only (a term's row of that length), so a finely sampled
#: plant's long dead time (u(k-15000): 15 s at 1 kHz) is analysed; u(k-99999999999) is not.
MAX_ANALYSIS_INPUT_LAG = 10_000_000


@lru_cache(maxsize=256)
def derivative_map(structure: Structure, inputs: tuple[str, ...] | None = None) -> DerivativeMap:
    """The :class:`DerivativeMap` of ``structure`` with the inputs in the order ``inputs`` (cached).

    ``inputs`` defaults to ``encode(structure).input_names``; it must hold every input the structure uses.
    """
    code = encode(structure, inputs)
    names = code.input_names
    T = len(structure)
    Ly = int(code.ylag.max(initial=0))
    Lu = max((structure.input_lag(n) for n in names), default=0)
    if Ly > MAX_ANALYSIS_LAG or Lu > MAX_ANALYSIS_INPUT_LAG:
        out = Ly > MAX_ANALYSIS_LAG
        worst = max(structure, key=lambda t: max((l for sg, l, _ in t.factors if (sg == "y") == out), default=0))
        lag = Ly if out else Lu
        raise ValueError(f"term {worst} has a lag of {lag} samples: the static and local analyses (static curves, "
                         f"equilibria, local models) take output lags up to {MAX_ANALYSIS_LAG} (they hold an L×L "
                         f"companion matrix per steady state) and input lags up to {MAX_ANALYSIS_INPUT_LAG}; is the "
                         "lag a typing error?")
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
        The inputs, in the column order of ``ubar`` (None: ``encode(structure).input_names``).
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
        Input levels (M,): every input at ū_j; (M, m): columns in ``encode(structure).input_names`` order.
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


# The static map's partials. p (n,) and A (n, m) are each term's power of y and of each input with the lags
# summed; the forms take many θ at the same points (a Monte Carlo band's draws) and skip θ_t = 0, as the
# coefficients above do, so an overflowing power of a zero term is no NaN.

def static_powers(structure: Structure, inputs: tuple[str, ...] | None = None, *,
                  curve: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Each term's power of y, shape (n,), and of each input, shape (n, m), in the static map (read-only).

    ``inputs``: the columns' order (default: the structure's inputs). ``curve=True``: one column, each
    term's total input power, for the static curve (every input at ū).
    """
    powers = derivative_map(structure, None if inputs is None else tuple(inputs)).powers
    A = powers[:, 1:]
    return powers[:, 0], (A.sum(axis=1, keepdims=True) if curve else A)


def _lowered(A: np.ndarray, ub: np.ndarray) -> np.ndarray:
    """∏ ū^(A_t − e_i): each term's input part differentiated by ū_i without its factor A_ti, shape (M, n, m)
    (0 where A_ti = 0)."""
    out = np.zeros((ub.shape[0],) + A.shape)
    for i in np.flatnonzero(A.any(axis=0)):
        e = A.copy()
        e[:, i] = np.maximum(e[:, i] - 1.0, 0.0)
        out[:, :, i] = np.where(A[:, i] > 0, input_monomials_of(e, ub), 0.0)
    return out


def static_partials(p: np.ndarray, A: np.ndarray, thetas: np.ndarray, ubar: np.ndarray, Y: np.ndarray, *,
                    with_inputs: bool = True, _monomials: np.ndarray | None = None
                    ) -> tuple[np.ndarray, np.ndarray | None]:
    """F_ȳ and F_ū of the static map at (ū_j, Y_kj) for parameter vectors θ_k.

    Parameters
    ----------
    p, A : ndarray, shapes (n,) and (n, m)
        From :func:`static_powers`.
    thetas : ndarray, shape (K, n)
    ubar : ndarray, shape (M, m)
        Points of input space (input units).
    Y : ndarray, shape (K, M)
        Output levels (output units), one row per θ.
    with_inputs : bool
        False skips F_ū (then None).

    Returns
    -------
    Fy : ndarray, shape (K, M)
        Dimensionless; NaN where Y is not finite (no equilibrium there).
    Fu : ndarray, shape (K, M, m) or None
        Output units per unit of each input; NaN where Y is not finite.
    """
    thetas, ub, Y = np.atleast_2d(thetas), np.asarray(ubar, float), np.atleast_2d(Y)
    # _monomials: input_monomials_of(A, ubar), when the caller has it (a caller that needs it too)
    G = input_monomials_of(A, ub) if _monomials is None else _monomials
    Fy = -np.ones(Y.shape)
    Fu = np.zeros(Y.shape + (A.shape[1],)) if with_inputs else None
    # summed term by term in structure order (no pairwise reordering), θ_t = 0 skipped
    with np.errstate(all="ignore"):
        t = np.flatnonzero(p)
        th = thetas[:, None, t]
        C = np.where(th != 0.0, th * p[t] * _powers(Y, p[t] - 1) * G[None, :, t], 0.0)  # (K, M, terms with y)
        for k in range(t.size):
            Fy = Fy + C[..., k]
        if with_inputs:
            t = np.flatnonzero(A.any(axis=1))
            th = thetas[:, None, t, None]
            C = np.where(th != 0.0, th * A[t] * _powers(Y, p[t])[..., None] * _lowered(A, ub)[None, :, t, :], 0.0)
            for k in range(t.size):
                Fu = Fu + C[..., k, :]
    bad = ~np.isfinite(Y)
    if bad.any():  # NaN⁰ = 1: a term without y, or linear in it, leaves a partial finite where no equilibrium is
        Fy = np.where(bad, np.nan, Fy)
        Fu = None if Fu is None else np.where(bad[..., None], np.nan, Fu)
    return Fy, Fu


def static_gains(p: np.ndarray, A: np.ndarray, thetas: np.ndarray, ubar: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """∂ȳ/∂ū_i = −F_ūi / F_ȳ at (ū_j, Y_kj), shape (K, M, m); arguments as for :func:`static_partials`.

    Output units per unit of input i; inf or NaN where F_ȳ = 0 (an integrator) or Y is not finite.
    """
    Fy, Fu = static_partials(p, A, thetas, ubar, Y)
    with np.errstate(all="ignore"):
        return -Fu / Fy[..., None]


def static_theta_gradient_of(p: np.ndarray, A: np.ndarray, theta: np.ndarray, ubar: np.ndarray,
                             ybar: np.ndarray) -> np.ndarray:
    """∂ȳ_j/∂θ_t = −ȳ_j^p_t ∏ ū_j^A_t / F_ȳ at equilibria (ū_j, ȳ_j), shape (M, n).

    ``theta`` (n,), ``ubar`` (M, m), ``ybar`` (M,); ``p``, ``A`` from :func:`static_powers`. At a
    reached equilibrium this is the gradient of the static output (the basin does not change under a
    small step). NaN where ȳ is not finite (no equilibrium there).
    """
    yb = np.asarray(ybar, float)
    # the input monomials once for F_ȳ and the numerator: the SE fits' static Jacobian asks this at every step
    G = input_monomials_of(A, ubar)
    Fy = static_partials(p, A, np.asarray(theta, float)[None, :], ubar, yb[None, :], with_inputs=False,
                         _monomials=G)[0][0]
    with np.errstate(all="ignore"):
        return -(_powers(yb, p) * G) / Fy[:, None]


def static_gain_gradient(p: np.ndarray, A: np.ndarray, theta: np.ndarray, ubar: np.ndarray, ybar: np.ndarray,
                         dy: np.ndarray) -> np.ndarray:
    """∂(∂ȳ/∂ū_i)/∂θ_t along the static map, through ȳ(θ) too, shape (M, m, n).

    ``theta`` (n,), ``ubar`` (M, m), ``ybar`` (M,) equilibria, ``dy`` (M, n) = ∂ȳ/∂θ there
    (:func:`static_theta_gradient_of`); ``p``, ``A`` from :func:`static_powers`. NaN where ȳ is not finite.
    """
    ub, yb, theta = np.asarray(ubar, float), np.asarray(ybar, float), np.asarray(theta, float)
    G, L = input_monomials_of(A, ub), _lowered(A, ub)  # (M, n), (M, n, m)
    with np.errstate(all="ignore"):
        dFy = p * _powers(yb, np.maximum(p - 1, 0)) * G  # ∂F_ȳ/∂θ_t, (M, n)
        dFu = np.moveaxis(A[None] * _powers(yb, p)[..., None] * L, 1, 2)  # ∂F_ū/∂θ, (M, m, n)
        # the sums over the terms skip θ_t = 0, as the forms above do (an overflowing zero term is no NaN); the
        # derivatives by each θ_t keep every term
        live = theta != 0.0
        th, pl = theta[live], p[live]
        Fyy = (pl * (pl - 1) * _powers(yb, np.maximum(pl - 2, 0)) * G[:, live]) @ th  # ∂F_ȳ/∂ȳ, (M,)
        Fuy = np.einsum("t,mti->mi", th, (A[live] * pl[:, None])[None] * _powers(yb, np.maximum(pl - 1, 0))[..., None]
                        * L[:, live])
        Fy, Fu = dFy[:, live] @ th - 1.0, dFu[:, :, live] @ th
        dFu_tot = dFu + Fuy[:, :, None] * dy[:, None, :]
        dFy_tot = (dFy + Fyy[:, None] * dy)[:, None, :]
        out = -(dFu_tot * Fy[:, None, None] - Fu[:, :, None] * dFy_tot) / (Fy**2)[:, None, None]
    # no equilibrium, no gradient (NaN⁰ = 1 leaves the partials of terms without y finite)
    return np.where(np.isfinite(yb)[:, None, None], out, np.nan)
