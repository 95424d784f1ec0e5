"""Compiled free-run kernels (numba).

A structure is encoded once as flat integer arrays (see :func:`encode`): for term
``t`` its factors are ``fsig[fptr[t]:fptr[t+1]]`` (0 = y, 1 + i = input i of the
code's ``inputs``), with lags and powers alongside. Noise terms are never encoded:
free runs ignore the MA part.

Several inputs: the kernels read the inputs as one (m, N) array, one contiguous row per
input (a single input is the (1, N) view of its (N,) samples, so the single-input
arithmetic is exactly what it was). The wrappers take ``u`` of shape (N,) or (N, m) with
the columns in the code's ``inputs`` order; :func:`record_inputs` picks them from a record
by name.

The batch kernel keeps the population on the innermost, contiguous axis of its
work buffer (shape (N, P)) so that every term update is a unit-stride loop that
LLVM vectorises; the input-only part of each term is computed once per sample
and shared by the whole population.

Nothing here validates input: callers in :mod:`graybox.core._simulation` do. The static-analysis kernels
(roots, stability, settling runs) live in :mod:`graybox.static._equilibrium_kernels`.
"""

from __future__ import annotations

import cmath
import math
from functools import lru_cache
from typing import NamedTuple

from ._jit import nb
import numpy as np

from ._terms import Structure, require_inputs

__all__ = ["Code", "encode", "simulate_one", "simulate_batch", "predict_ahead", "input_products", "record_inputs",
           "kernel_inputs", "BOUND_FACTOR", "scaled_bound", "feedback_scale", "feedback_scales", "push_gain",
           "linear_margins", "kernel_array"]


def kernel_array(a, dtype=np.float64) -> np.ndarray:
    """``a`` as every compiled kernel reads an array it does not write: C-contiguous, of ``dtype``, read-only.

    A view when ``a`` already is contiguous of ``dtype`` (a copy otherwise). numba compiles (and caches) one
    version of a kernel per argument type, and a read-only array (a model's θ, a record's samples) is another
    type than a writable one: callers passing both paid two compilations of the same kernel, 0.5–3 s each.
    """
    out = np.ascontiguousarray(a, dtype=dtype)
    if out.flags.writeable:
        out = out.view()
        out.flags.writeable = False
    return out


class Code(NamedTuple):
    """A structure encoded for the kernels.

    ``fptr, fsig, flag, fpow``: the factors of term t are ``fptr[t]:fptr[t+1]`` with signal
    (0 = y, 1 + i = input ``inputs[i]``), lag and power. ``ny[t]`` is the total output power of term t and
    ``ylag[t, :ny[t]]`` its output lags with repetition (y(k-2)^2 → [2, 2]).

    ``mu[t]``: the total input power of term t. ``uptr, ulag, upow, usig``: the input factors
    only (``usig``: the input's index in ``inputs``). ``inputs``: the input names, in the order
    of the columns the kernels expect.
    ``grp[t]`` is the output monomial group of term t (-1 for input-only terms); group g is the
    monomial with lags ``gylag[g, :gny[g]]``.
    Grouping lets the single free run treat y(k) = X(k) + Σ_g C_g(k) · m_g(y) as a recursion
    over a few monomials with coefficients precomputed from the input.
    """

    fptr: np.ndarray
    fsig: np.ndarray
    flag: np.ndarray
    fpow: np.ndarray
    ny: np.ndarray
    ylag: np.ndarray
    uptr: np.ndarray
    ulag: np.ndarray
    upow: np.ndarray
    grp: np.ndarray
    gny: np.ndarray
    gylag: np.ndarray
    mu: np.ndarray
    usig: np.ndarray
    input_names: tuple[str, ...]
    # the structure's facts the default bound reads at every call, as plain ints (numpy scalars read term by term
    # cost 15 µs of a 50 µs free run): ``single``, (term, lag) of the terms of one past output y(k−l) (times inputs
    # or not); ``single_inputs``, whether one of those has input factors; ``nonlinear``, the index and output power
    # of the terms of output power >= 2
    single: tuple[tuple[int, int], ...] = ()
    single_inputs: bool = False
    nonlinear: tuple[tuple[int, int], ...] = ()


def encode(structure: Structure, inputs: tuple[str, ...] | None = None) -> Code:
    """Encode the process terms of ``structure`` for the kernels (cached; arrays read-only).

    Parameters
    ----------
    structure : Structure
    inputs : tuple of str, optional
        The input names in the column order the caller will pass (default: the inputs the
        structure uses, in natural name order; none for an output-only structure, which then
        reads no input by name). Must contain every input the structure uses.
    """
    if inputs is None:
        inputs = structure.input_names
    return _encode(structure, tuple(inputs))


@lru_cache(maxsize=512)
def _encode(structure: Structure, inputs: tuple[str, ...]) -> Code:
    sig = {"y": 0} | {n: 1 + i for i, n in enumerate(inputs)}
    require_inputs(structure.input_names, tuple(inputs), "which is not among the inputs")
    fptr = [0]
    fsig: list[int] = []
    flag: list[int] = []
    fpow: list[int] = []
    ylags: list[list[int]] = []
    for term in structure:
        if term.is_noise:
            raise ValueError(f"noise term {term} cannot be simulated; pass the process structure")
        lags: list[int] = []
        for s, l, p in term.factors:
            fsig.append(sig[s])
            flag.append(l)
            fpow.append(p)
            if s == "y":
                lags += [l] * p
        ylags.append(lags)
        fptr.append(len(fsig))
    D = max((len(l) for l in ylags), default=0)
    ylag = np.zeros((len(ylags), max(D, 1)), dtype=np.int64)
    for t, lags in enumerate(ylags):
        ylag[t, : len(lags)] = lags
    uptr, ulag, upow, usig = [0], [], [], []
    groups: dict[tuple[int, ...], int] = {}
    grp = []
    for term, lags in zip(structure, ylags):
        for s_, l, p in term.factors:
            if s_ != "y":
                ulag.append(l)
                upow.append(p)
                usig.append(sig[s_] - 1)
        uptr.append(len(ulag))
        key = tuple(sorted(lags))
        if key:
            groups.setdefault(key, len(groups))
    # groups in decreasing order of their smallest lag: the monomial that needs y(k-1), the
    # sample just computed, is added last, which keeps the recursion's dependency chain short
    order = sorted(groups, key=lambda key: (-key[0], key))
    groups = {key: g for g, key in enumerate(order)}
    for lags in ylags:
        key = tuple(sorted(lags))
        grp.append(groups[key] if key else -1)
    gylag = np.zeros((len(groups), max(D, 1)), dtype=np.int64)
    for key, g in groups.items():
        gylag[g, : len(key)] = key
    def as_i(a):
        x = np.array(a, dtype=np.int64)
        x.setflags(write=False)  # shared by every caller through the cache
        return x

    return Code(
        as_i(fptr), as_i(fsig), as_i(flag), as_i(fpow), as_i([len(l) for l in ylags]), as_i(ylag),
        as_i(uptr), as_i(ulag), as_i(upow), as_i(grp), as_i([len(k) for k in sorted(groups, key=groups.get)]),
        as_i(gylag), as_i([t.input_power for t in structure]), as_i(usig), tuple(inputs),
        tuple((t, lags[0]) for t, lags in enumerate(ylags) if len(lags) == 1),
        any(uptr[t] != uptr[t + 1] for t, lags in enumerate(ylags) if len(lags) == 1),
        tuple((t, len(lags)) for t, lags in enumerate(ylags) if len(lags) >= 2),
    )


def kernel_inputs(code: Code, u: np.ndarray) -> np.ndarray:
    """The inputs as the kernels read them: shape (m, N), one contiguous row per input.

    ``u`` is (N,) for a single input (a view, no copy) or (N, m) with the columns in
    ``code.input_names`` order; ``ValueError`` when the column count differs.
    """
    if u.ndim == 1:
        if len(code.input_names) > 1:
            raise ValueError(f"u has one input column but the structure's inputs are {code.input_names}")
        return kernel_array(u.reshape(1, u.shape[0]))
    if u.ndim != 2 or u.shape[1] != len(code.input_names):
        raise ValueError(f"u has shape {u.shape}, expected (N, {len(code.input_names)}) for the inputs {code.input_names}")
    return kernel_array(u.T)


def record_inputs(record, inputs: tuple[str, ...]) -> np.ndarray:
    """The columns ``inputs`` of a record's input, by name: shape (N,) for one, (N, k) for several.

    Raises ``ValueError`` naming an input the record does not have.
    """
    names = record.input_names
    if tuple(inputs) == tuple(names):
        return record.u
    require_inputs(inputs, names, "but the record's inputs are", prefix=f"{record.name}: ")
    if len(inputs) == 1:
        return np.ascontiguousarray(record.input(inputs[0]))
    if len(inputs) == 0:
        return record.inputs[:, 0]
    return np.ascontiguousarray(record.inputs[:, [names.index(n) for n in inputs]])


def input_products(fptr, fsig, flag, fpow, u, start):
    """U[k, t] = product of the input factors of term t at sample k (1 for none), shape (N, T).

    ``u`` is (N,) for a single input or (N, m) with the columns in the code's input order
    (signal 1 + i reads column i).
    """
    return _input_products(fptr, fsig, flag, fpow, kernel_array(u.reshape(1, u.shape[0]) if u.ndim == 1 else u.T),
                           start)


@nb.njit(cache=True, nogil=True)
def _input_products(fptr, fsig, flag, fpow, uc, start):  # pragma: no cover - compiled
    n = uc.shape[1]
    nt = fptr.shape[0] - 1
    U = np.ones((n, nt))
    # term by term with the sample loop innermost: branch-free, vectorisable inner loops
    for t in range(nt):
        for f in range(fptr[t], fptr[t + 1]):
            if fsig[f] == 0:
                continue
            u = uc[fsig[f] - 1]
            lag = flag[f]
            pw = fpow[f]
            if pw == 1:
                for k in range(start, n):
                    U[k, t] *= u[k - lag]
            elif pw == 2:
                for k in range(start, n):
                    x = u[k - lag]
                    U[k, t] *= x * x
            else:
                for k in range(start, n):
                    x = u[k - lag]
                    v = x
                    for _ in range(pw - 1):
                        v *= x
                    U[k, t] *= v
    return U


_CHUNK = 512


@nb.njit(cache=True, nogil=True, inline="always")
def _input_parts(uptr, ulag, upow, usig, grp, theta, uflat, n, k0, mm, X, C, tmp):  # pragma: no cover - compiled
    # X[i] and C[g, i] for the samples k0 + i, i < mm: X(k) from the input-only terms and the
    # coefficient C_g(k) of each output monomial. Loops start at 0 over offset views so that
    # LLVM drops numba's negative-index checks and vectorises them.
    for i in range(mm):
        X[i] = 0.0
    for g in range(C.shape[0]):
        for i in range(mm):
            C[g, i] = 0.0
    for t in range(theta.shape[0]):
        th = theta[t]
        for i in range(mm):
            tmp[i] = th
        for f in range(uptr[t], uptr[t + 1]):
            us = uflat[usig[f] * n + k0 - ulag[f]:]
            for _ in range(upow[f]):
                for i in range(mm):
                    tmp[i] *= us[i]
        g = grp[t]
        if g < 0:
            for i in range(mm):
                X[i] += tmp[i]
        else:
            for i in range(mm):
                C[g, i] += tmp[i]


#: The default divergence bound is this many times the run's own output scale: the largest of
#: max|y0|, the model's feedback scale (:func:`feedback_scale`) and the level the inputs' direct push
#: so far holds the output at, max_j≤k G(j) |X(j)| (X: the terms without y; G(j) the gain of the linear
#: feedback at sample j's inputs, :func:`push_gain`, at least that of its constant part for any input,
#: :func:`linear_margins`), all in output units, so that it does not depend
#: on the output's units, also from rest.
BOUND_FACTOR = 1e6
_BIG = np.finfo(np.float64).max  # nothing drives the output yet: only an overflow counts


@nb.njit(cache=True, nogil=True)
def scaled_bound(ref):  # pragma: no cover - compiled
    """``BOUND_FACTOR`` × ``ref``, or the largest float where that is 0 or not finite (only an overflow counts)."""
    b = BOUND_FACTOR * ref
    return b if 0.0 < b < _BIG else _BIG


def feedback_scale(code: Code, theta: np.ndarray, u: np.ndarray) -> float:
    """The output size at which the model's nonlinear output feedback matters (output units).

    For a term θ_t · (input part) · y-monomial of output power p ≥ 2, the amplitude where it
    weighs as much as a linear term, (|θ_t| max|input part|)^(−1/(p−1)) (θ_t is in units of
    y^(1−p) per input units): the largest over such terms, 0 without them. A limit cycle of such a
    model lives at this scale whatever the run's start (e.g. from y0 near 0).
    """
    return float(feedback_scales(code, np.asarray(theta, dtype=float)[None, :], u)[0])


def feedback_scales(code: Code, thetas: np.ndarray, u: np.ndarray) -> np.ndarray:
    """:func:`feedback_scale` of every row of ``thetas`` (P, n_terms) at once, shape (P,)."""
    th = np.atleast_2d(np.asarray(thetas, dtype=float))
    out = np.zeros(th.shape[0])
    if not code.nonlinear:  # no output power >= 2: no input's size to read (a pass over every sample)
        return out
    umax = np.abs(np.asarray(u, dtype=float)).reshape(u.shape[0], -1).max(axis=0) if u.size else np.zeros(0)
    with np.errstate(all="ignore"):
        for t, p in code.nonlinear:
            c = np.abs(th[:, t])
            for f in range(code.uptr[t], code.uptr[t + 1]):
                c = c * umax[code.usig[f]] ** code.upow[f]
            ok = (c > 0.0) & (c < np.inf)
            out = np.where(ok, np.maximum(out, np.where(ok, c, 1.0) ** (-1.0 / (p - 1))), out)
    return out


@nb.njit(cache=True, nogil=True, inline="always")
def pole_margin(a1, a2):  # pragma: no cover - compiled
    """At most Π (1 − |p|) over the poles p of y(k) = a1 y(k−1) + a2 y(k−2), and within a factor 4 of it, where both
    lie inside the unit circle; else 2 (dimensionless): :func:`linear_margins`' rule for a recursion of order two at
    most, without a square root (it runs at every sample of every member of a population)."""
    inside = abs(a1) < 1.0 - a2 and abs(a2) < 1.0  # the step-down test of z² − a1 z − a2 (NaN: not inside)
    b = 1.0 + a2
    # a complex pair, |p|² = −a2: (1 − |p|)² = (1 − |p|²)² / (1 + |p|)²; real poles of one sign: |p1| + |p2| = |a1|,
    # |p1 p2| = −a2, exactly; of both signs: 1 + a2 − √disc = ((1 − a2)² − a1²) / (1 + a2 + √disc), √disc < 1 + a2
    pm = b * b / 4.0 if a1 * a1 + 4.0 * a2 < 0.0 else (
        1.0 - abs(a1) - a2 if a2 <= 0.0 else ((1.0 - a2) * (1.0 - a2) - a1 * a1) / (2.0 * b))
    return max(pm, 2.2250738585072014e-308) if inside else 2.0


@nb.njit(cache=True, nogil=True)
def lattice_margin(a, w):  # pragma: no cover - compiled
    """1 / a bound on Σ|h| of y(k) = Σ_l a_l y(k−l) + push, l = 1 … L (``a`` a 1-D view of length L), where every pole
    lies inside the unit circle; else 2 (dimensionless): :func:`linear_margins`' rule for a feedback through the
    inputs that reads a lag beyond 2, at the samples of a run the steady gain alone would stop. ``w`` is a work array
    of at least L floats.

    The Schur–Cohn step-down of A(z) = 1 − Σ a_l z^−l gives its reflection coefficients k_L … k_1 (every |k_m| < 1
    exactly when every pole is inside), and on the unit circle |A_m| >= (1 − |k_m|) |A_(m−1)| (the step-up
    A_m(z) = A_(m−1)(z) + k_m z^−m A_(m−1)(1/z), whose two parts have one modulus there), so
    sup_ω 1/|A(e^{jω})| <= 1 / Π (1 − |k_m|); and Σ|h| <= (2L + 1) sup_ω |H| for a system of order L (Boyd and
    Doyle's peak-to-peak bound), hence the margin Π (1 − |k_m|) / (2L + 1), or 1 − Σ|a_l| where that is larger
    (Σ|h| <= 1 / (1 − Σ|a_l|), the small-gain bound: tighter for a plant of real positive poles). A lightly damped
    pair driven at its own frequency builds up to sup |H| ≫ 1/D, which the steady gain 1/D of :func:`push_gain`
    does not cover."""
    L = a.shape[0]
    small = 1.0
    for i in range(L):
        w[i] = -a[i]  # A's coefficients α_1 … α_L of z^−1 … z^−L
        small -= abs(a[i])
    prod = 1.0
    for m in range(L, 0, -1):
        k = w[m - 1]
        if not abs(k) < 1.0:  # a pole on or outside the unit circle (NaN: not inside)
            return 2.0
        prod *= 1.0 - abs(k)
        s = 1.0 - k * k
        for i in range((m - 1) // 2 + 1):  # α_i ← (α_i − k α_(m−i)) / (1 − k²), i = 1 … m − 1, in pairs
            j = m - 2 - i
            if i > j:
                break
            lo, hi = w[i], w[j]
            w[i] = (lo - k * hi) / s
            w[j] = (hi - k * lo) / s
    return max(prod / (2.0 * L + 1.0), small, 2.2250738585072014e-308)


@nb.njit(cache=True, nogil=True)
def _lattice_push_margin(a, w):  # pragma: no cover - compiled
    # 1 / push_gain of a feedback through the inputs that reads a lag beyond 2 (linear_margins' −2), ``a`` that
    # sample's a_1 … a_L: lattice_margin where every pole is inside, else the steady gain's margin (the fast path's,
    # _push_margin at margin 1); never above the latter (lattice_margin <= 1 / Σ|h| <= 1 / |Σh| = D where stable),
    # so a run the fast path lets through, this lets through too, and only runs it stops need this
    s = 0.0
    for i in range(a.shape[0]):
        s += a[i]
    d = _push_margin(s, 0.0, 1.0)
    lm = lattice_margin(a, w)
    return lm if lm < d else d


@nb.njit(cache=True, nogil=True, inline="always")
def push_gain(c1, c2, margin):  # pragma: no cover - compiled
    """How far the linear output feedback at a sample amplifies the push (dimensionless); ``margin`` is
    :func:`linear_margins`' (1: none).

    ``c1 + c2`` is the sum of the coefficients of the single past outputs y(k−l) at that sample, terms θ y(k−l) and
    input-dependent ones θ y(k−l) · (inputs) alike (C_g(k) of the monomials of output power 1), so the gain is the
    one the inputs the run sees give it; ``c1`` those of lag 1. With ``margin`` −1 (the feedback runs through the
    inputs and reads lags 1 and 2 alone) the gain is 1 / :func:`pole_margin` (c1, c2), the gain of that sample's
    feedback for any push (a feedback near −1 through y·u² at u = ±1, driven at its own frequency, builds up to
    1 / (1 − |a|) ≫ 1 / D), and 1 where it has a pole on or outside the unit circle (a growing pair
    1.001 e^{±0.01j}, part of it through y·u: D = 1e-4, and the gain 1e4 let it run to 1.5e9 uncaught).
    Else it is 1 / min(D, ``margin``) with D = 1 − c1 − c2 where 0 < D < 1, else 1: a stable linear
    recursion held by a constant push X settles at X / D (a slow plant sampled fast, two time constants of 1000
    samples: D = 1e-6, rests at 10⁶ times its push, which the bound must not call divergence); D <= 0 is a root at
    z >= 1 (no steady level: the push's own scale is kept, as an unstable recursion's, so a diverging run is caught
    as early as before), and so is a ``margin`` above 1, a constant feedback with a pole on or outside the unit
    circle though 0 < D < 1.
    """
    return 1.0 / _push_margin(c1, c2, margin)


@nb.njit(cache=True, nogil=True, inline="always")
def _push_margin(c1, c2, margin):  # pragma: no cover - compiled
    # 1 / push_gain: a run's scale grows where |X| > scale × this, a product, no division per sample
    if margin > 1.0:  # the constant feedback has a pole on or outside the unit circle: no steady level
        return 1.0
    if margin < 0.0:  # the feedback through the inputs: its poles at this sample
        pm = pole_margin(c1, c2)
        return 1.0 if pm > 1.0 else pm
    return _steady_margin(c1, c2, margin)


@nb.njit(cache=True, nogil=True, inline="always")
def _steady_margin(c1, c2, margin):  # pragma: no cover - compiled
    # _push_margin for a ``margin`` in [0, 1] (a constant feedback's, or none): the steady gain's, at most margin
    d = 1.0 - (c1 + c2)
    d = d if 0.0 < d < 1.0 else 1.0
    return min(d, margin)


def linear_margins(code: Code, thetas: np.ndarray) -> np.ndarray:
    """1 / the gain of the constant linear output feedback for any input, per row of ``thetas`` (P, n_terms):
    Π (1 − |p|) over the poles p of y(k) = Σ_l a_l y(k−l) (a_l the θ of the terms θ y(k−l)) where all lie inside
    the unit circle, 2 where one does not (no steady level, whatever D: :func:`push_gain` then keeps the push's own
    scale), 1 where θ is not finite. Where a term y(k−l) · (inputs) feeds back too, the constant terms are no account
    of the feedback: −1 where no single past output lies beyond lag 2 (:func:`push_gain` reads the poles of the
    feedback at each sample's inputs), else −2: the run is judged by the steady gain at each sample first (the
    margin 1, the fast path), and a run that judgement stops is run again with :func:`lattice_margin` of each
    sample's feedback (a step-down per sample, paid only by the runs that would otherwise be stopped). Shape (P,),
    in (0, 2], −1 or −2.

    A push X bounded by |X| <= x holds a stable linear recursion at |y| <= x Σ_j |h(j)| <= x Π 1 / (1 − |p|): for
    real positive poles that is the steady gain 1 / D of :func:`push_gain`, but a lightly damped pair driven at its
    frequency builds up to 1 / |A(e^{jω})|, up to 1 / (1 − |p|)² ≫ 1 / D (poles 0.9999999 e^{±0.5j}: 10¹⁴ against
    4), which the bound must not call divergence.
    """
    th = np.atleast_2d(np.asarray(thetas, dtype=float))
    out = np.ones(th.shape[0])
    if not code.single:
        return out
    single, lags = [t for t, _ in code.single], [l for _, l in code.single]
    L = max(lags)
    if code.single_inputs:
        m = -1.0 if L <= 2 else -2.0
        if th.shape[0] == 1:  # one run's (simulate, predict): in floats, no array work (4 µs of a 45 µs free run)
            out[0] = m if all(map(math.isfinite, th[0].tolist())) else 1.0
            return out
        return np.where(np.all(np.isfinite(th), axis=1), m, 1.0)
    if th.shape[0] == 1 and L <= 2:  # one run's (simulate, predict): the poles in floats, no array work
        c = [0.0, 0.0]
        for t, l in zip(single, lags):
            c[l - 1] += float(th[0, t])
        if not all(math.isfinite(v) for v in c):
            return out
        disc = cmath.sqrt(c[0] * c[0] + 4.0 * c[1])
        r1, r2 = abs((c[0] + disc) / 2.0), abs((c[0] - disc) / 2.0)
        out[0] = max((1.0 - r1) * (1.0 - r2), np.finfo(float).tiny) if r1 < 1.0 and r2 < 1.0 else 2.0
        return out
    a = np.zeros((th.shape[0], L))
    for t, l in zip(single, lags):
        a[:, l - 1] += th[:, t]
    ok = np.all(np.isfinite(a), axis=1)
    if ok.any():
        with np.errstate(all="ignore"):
            if L <= 2:  # the poles in closed form (a free run's common orders: no eigenvalue solver per call)
                a1, a2 = a[ok, 0], (a[ok, 1] if L == 2 else np.zeros(int(ok.sum())))
                disc = np.sqrt((a1 * a1 + 4.0 * a2).astype(complex))
                rho = np.abs(np.stack([(a1 + disc) / 2.0, (a1 - disc) / 2.0], axis=1))
            else:
                C = np.zeros((int(ok.sum()), L, L))
                C[:, 0, :] = a[ok]
                C[:, np.arange(1, L), np.arange(L - 1)] = 1.0
                rho = np.abs(np.linalg.eigvals(C))
            out[ok] = np.where(np.all(rho < 1.0, axis=1), np.prod(1.0 - rho, axis=1), 2.0)
    return np.clip(out, np.finfo(float).tiny, 2.0)


@nb.njit(cache=True, nogil=True, inline="always")
def _start_ref(y, start):  # pragma: no cover - compiled
    ref = 0.0
    for k in range(start):
        a = abs(y[k])
        if a > ref:
            ref = a
    return ref


@nb.njit(cache=True, nogil=True, inline="always")
def _feedback_margins(C, gny, gylag, mm, D, E, margin):  # pragma: no cover - compiled
    # D[i] = 1 / push_gain at the samples i < mm, from the coefficients C_g of the single past outputs (monomials
    # of output power 1) summed by lag (1 in D, 2 and beyond in E); loops over the samples (vectorised)
    if margin < -1.5:  # the feedback through the inputs reads a lag beyond 2: every lag's sum, sample by sample
        _lattice_margins(C, gny, gylag, mm, D)
        return
    for i in range(mm):
        D[i] = 0.0
        E[i] = 0.0
    for g in range(gny.shape[0]):
        if gny[g] == 1:
            if gylag[g, 0] == 1:
                for i in range(mm):
                    D[i] += C[g, i]
            else:
                for i in range(mm):
                    E[i] += C[g, i]
    for i in range(mm):
        D[i] = _push_margin(D[i], E[i], margin)


@nb.njit(cache=True, nogil=True, inline="always")
def _single_lags(gny, gylag):  # pragma: no cover - compiled (inlined)
    # the largest lag of a single past output y(k−l) among the monomials (gny, gylag) or the terms (ny, ylag); 0: none
    L = 0
    for g in range(gny.shape[0]):
        if gny[g] == 1 and gylag[g, 0] > L:
            L = gylag[g, 0]
    return L


@nb.njit(cache=True, nogil=True)
def _lattice_margins(C, gny, gylag, mm, D):  # pragma: no cover - compiled
    # D[i] = 1 / push_gain at the samples i < mm by _lattice_push_margin of that sample's a_l (every lag's sum of C_g)
    L = _single_lags(gny, gylag)
    a = np.empty(L)
    w = np.empty(L)
    for i in range(mm):
        for l in range(L):
            a[l] = 0.0
        for g in range(gny.shape[0]):
            if gny[g] == 1:
                a[gylag[g, 0] - 1] += C[g, i]
        D[i] = _lattice_push_margin(a, w)


@nb.njit(cache=True, nogil=True)
def _one(uptr, ulag, upow, usig, grp, gny, gylag, theta, uflat, n, y0, start, bound, auto, scale,
         margin):  # pragma: no cover - compiled
    # uflat: the (m, n) inputs flattened, input i at uflat[i*n:(i+1)*n]; 1-D slices of a 1-D
    # array keep the pass-1 loops as the single-input kernel had them (unit stride, vectorised).
    # Returns (y, cut): cut where the bound stopped the run at a finite sample (see _rerun).
    G = gny.shape[0]
    y = np.empty(n)
    for k in range(start):
        y[k] = y0[k]
    ref = max(_start_ref(y0, start), scale)
    if auto:
        bound = scaled_bound(ref)
    # Chunks of samples keep the work buffers in cache (no large allocation per call).
    X = np.empty(_CHUNK)
    C = np.empty((G, _CHUNK))
    tmp = np.empty(_CHUNK)
    tmp2 = np.empty(_CHUNK if auto else 0)
    for k0 in range(start, n, _CHUNK):
        mm = min(_CHUNK, n - k0)
        # pass 1, off the recursion's critical path
        _input_parts(uptr, ulag, upow, usig, grp, theta, uflat, n, k0, mm, X, C, tmp)
        if auto:
            _feedback_margins(C, gny, gylag, mm, tmp, tmp2, margin)
        # pass 2: the recursion over a few output monomials
        for i in range(mm):
            k = k0 + i
            # off the recursion's critical path: the level the push holds the output at, |X| / D, compared as
            # |X| > ref · D (no division per sample)
            if auto and abs(X[i]) > ref * tmp[i]:
                ref = abs(X[i]) / tmp[i]
                bound = scaled_bound(ref)
            acc = _monomials_step(X, C, gny, gylag, y, i, k)
            if not (abs(acc) <= bound):
                for j in range(k, n):
                    y[j] = np.nan
                return y, abs(acc) < np.inf
            y[k] = acc
    return y, False


def _fast(margin: float) -> float:
    """The margin a run is judged by first: :func:`linear_margins`' −2 (a feedback through the inputs reading a lag
    beyond 2) is judged by the steady gain (margin 1) and run again only where that stops it (:func:`_rerun`)."""
    return 1.0 if margin < -1.5 else margin


def _rerun(margin: float, cut: bool) -> bool:
    """Whether a run the fast margin (:func:`_fast`) stopped at a finite sample is to be run again with
    ``margin``: the steady gain 1/D bounds a stable feedback's response to a constant push, not to one at the
    feedback's resonance (poles 0.9999999 e^{±j(π − 0.01)} and 0.5 through y(k−3)·v(k−1), driven at the pair's
    frequency, build up to 10⁸ × the push where 1/D = 0.5); :func:`lattice_margin` bounds it for any push. It is
    never above the steady gain's margin, so a run the fast path lets through it lets through too and the two
    passes are the lattice bound's run exactly; the step-down per sample costs only the runs that would otherwise
    be stopped (a diverging run, stopped again where the lattice bound stops it)."""
    return margin < -1.5 and bool(cut)


def simulate_one(code: Code, theta: np.ndarray, u: np.ndarray, y0: np.ndarray, start: int,
                 bound: float | None) -> np.ndarray:
    """Free run of one model; ``y0`` gives samples ``0 … start-1``; returns y, shape (N,).

    ``u`` is (N,) or (N, m) in ``code.input_names`` order. The run stops at the first sample whose
    magnitude exceeds ``bound`` (or is not finite); that sample and all later ones are NaN.
    ``bound=None``: the default, :data:`BOUND_FACTOR` × the run's own scale at each sample.
    """
    uc = kernel_inputs(code, u)
    scale = feedback_scale(code, theta, u) if bound is None else 0.0
    margin = float(linear_margins(code, theta)[0]) if bound is None else 1.0
    args = (code.uptr, code.ulag, code.upow, code.usig, code.grp, code.gny, code.gylag, kernel_array(theta),
            uc.reshape(-1), uc.shape[1], kernel_array(y0), start, 0.0 if bound is None else float(bound),
            bound is None, scale)
    y, cut = _one(*args, _fast(margin))
    return _one(*args, margin)[0] if _rerun(margin, cut) else y


@nb.njit(cache=True, nogil=True, inline="always")
def _monomials_step(X, C, gny, gylag, buf, i, j):  # pragma: no cover - compiled
    # ŷ from the input parts X[i], C[:, i] and the run's past outputs in buf up to position j - 1
    acc = X[i]
    for g in range(gny.shape[0]):
        v = C[g, i]
        if gny[g] == 1:  # the common monomial, a single lagged output
            v *= buf[j - gylag[g, 0]]
        else:
            for d in range(gny[g]):
                v *= buf[j - gylag[g, d]]
        acc += v
    return acc


@nb.njit(cache=True, nogil=True)
def _ahead(uptr, ulag, upow, usig, grp, gny, gylag, theta, uflat, n, y, start, horizon, bound, auto, scale,
           margin):  # pragma: no cover - compiled
    # The input-only parts X(k), C_g(k) once over the record; the samples before start + horizon - 1
    # by one free run from the record's start; every later sample t by a recursion of ``horizon``
    # steps from the measured outputs before t - horizon + 1: O(N min(horizon, N - horizon)) steps.
    # Returns (ŷ, cut): cut where the bound stopped a run at a finite sample (see _rerun).
    cut = False
    m = n - start
    X = np.empty(m)  # X[k - start], C[:, k - start]: sample k
    C = np.empty((gny.shape[0], m))
    _input_parts(uptr, ulag, upow, usig, grp, theta, uflat, n, start, m, X, C, np.empty(m))
    # the default bound's scale without the run's start: the feedback scale and the push so far
    P = np.full(m, scale)
    ref = scale
    D = np.empty(m)
    _feedback_margins(C, gny, gylag, m, D, np.empty(m), margin)
    for i in range(m):
        lvl = abs(X[i]) / D[i]
        if lvl > ref:
            ref = lvl
        P[i] = ref
    start_ref = _start_ref(y, start)
    out = np.empty(n)
    for k in range(start):
        out[k] = y[k]
    # every t before start + horizon - 1 is predicted from the record's first samples: one free run
    prefix = min(start + horizon - 1, n)
    buf = np.empty(max(prefix, start + horizon))
    for i in range(start):
        buf[i] = y[i]
    gone = False
    for k in range(start, prefix):
        acc = np.nan
        if not gone:
            acc = _monomials_step(X, C, gny, gylag, buf, k - start, k)
            if not (abs(acc) <= (scaled_bound(max(start_ref, P[k - start])) if auto else bound)):
                cut = cut or abs(acc) < np.inf
                acc = np.nan
                gone = True
        buf[k] = acc
        out[k] = acc
    for t in range(prefix, n):
        s = t - horizon + 1
        w = 0.0  # this run's own start: the measured outputs it begins from
        for i in range(start):
            buf[i] = y[s - start + i]
            w = max(w, abs(buf[i]))
        for k in range(s, t + 1):
            j = start + k - s
            acc = _monomials_step(X, C, gny, gylag, buf, k - start, j)
            if not (abs(acc) <= (scaled_bound(max(w, P[k - start])) if auto else bound)):
                cut = cut or abs(acc) < np.inf
                acc = np.nan
                break
            buf[j] = acc
        out[t] = acc
    return out, cut


def predict_ahead(code: Code, theta: np.ndarray, u: np.ndarray, y: np.ndarray, start: int, horizon: int,
                  bound: float | None) -> np.ndarray:
    """``horizon``-step-ahead prediction of one model from measured outputs, shape (N,).

    ŷ(t) is the free run started from the measured y(s − start) … y(s − 1), s = max(t − horizon + 1,
    start), and driven by the measured inputs up to t − 1: the prediction of y(t) from the outputs
    measured up to t − horizon (horizon 1: one step ahead; horizon ≥ N: the free run from the
    record's start). The first ``start`` samples are the measured ones; a prediction whose run leaves
    ``bound`` (or is not finite) is NaN. ``bound=None``: the free run's default (:func:`simulate_one`),
    each run's own start being the measured outputs it begins from (so a horizon of the record's
    length is the free run, bit for bit).
    """
    uc = kernel_inputs(code, u)
    scale = feedback_scale(code, theta, u) if bound is None else 0.0
    margin = float(linear_margins(code, theta)[0]) if bound is None else 1.0
    args = (code.uptr, code.ulag, code.upow, code.usig, code.grp, code.gny, code.gylag, kernel_array(theta),
            uc.reshape(-1), uc.shape[1], kernel_array(y), start, horizon, 0.0 if bound is None else float(bound),
            bound is None, scale)
    out, cut = _ahead(*args, _fast(margin))
    return _ahead(*args, margin)[0] if _rerun(margin, cut) else out


@nb.njit(cache=True, nogil=True, inline="always")
def _advance(thT, U, ny, ylag, Y, k, mask, acc, xacc, cacc, bounded):  # pragma: no cover - compiled
    # acc[p] = ŷ_p(k) for every member p, reading past outputs from rows (k - lag) & mask of Y;
    # when ``bounded`` also xacc[p] = X_p(k), the sum of the terms without y, and cacc[0, p], cacc[1, p] the sums of
    # the coefficients of its single past outputs at sample k of lag 1 and of the others (for the bound:
    # :func:`push_gain`); a cacc of more rows holds one per lag (the lattice pass, linear_margins' −2).
    # The accumulator is a separate array, every access is 2-D indexed and every population
    # loop runs over the whole second axis (range(P) with P = Y.shape[1]): in this form LLVM
    # vectorises each term update, which a loop over a sub-range p0:p1 does not (BENCHMARKS.md).
    P = Y.shape[1]
    nt = thT.shape[0]
    for p in range(P):
        acc[p] = 0.0
    if bounded:
        for p in range(P):
            xacc[p] = 0.0
        for r in range(cacc.shape[0]):  # rows outermost: each a unit-stride loop over the population
            for p in range(P):
                cacc[r, p] = 0.0
    for t in range(nt):
        c = U[k, t]
        m = ny[t]
        if m == 0:
            if bounded:
                for p in range(P):
                    v = thT[t, p] * c
                    acc[p] += v
                    xacc[p] += v
            else:
                for p in range(P):
                    acc[p] += thT[t, p] * c
        elif m == 1:
            a = (k - ylag[t, 0]) & mask
            if bounded:
                r = min(ylag[t, 0], cacc.shape[0]) - 1  # 2 rows: lag 1, the others; more: one per lag
                for p in range(P):
                    v = thT[t, p] * c
                    acc[p] += v * Y[a, p]
                    cacc[r, p] += v
            else:
                for p in range(P):
                    acc[p] += thT[t, p] * c * Y[a, p]
        elif m == 2:
            a = (k - ylag[t, 0]) & mask
            b = (k - ylag[t, 1]) & mask
            for p in range(P):
                acc[p] += thT[t, p] * c * Y[a, p] * Y[b, p]
        elif m == 3:
            a = (k - ylag[t, 0]) & mask
            b = (k - ylag[t, 1]) & mask
            e = (k - ylag[t, 2]) & mask
            for p in range(P):
                acc[p] += thT[t, p] * c * Y[a, p] * Y[b, p] * Y[e, p]
        else:
            for p in range(P):
                v = thT[t, p] * c
                for d in range(m):
                    v *= Y[(k - ylag[t, d]) & mask, p]
                acc[p] += v


@nb.njit(cache=True, nogil=True, inline="always")
def _bound_start(ref):  # pragma: no cover - compiled
    # (bounded, the members' scales (a copy: they grow), their bounds); ``ref`` empty: no bound
    own = ref.copy()
    bnd = np.empty(own.shape[0])
    for p in range(own.shape[0]):
        bnd[p] = scaled_bound(own[p])
    return own.shape[0] > 0, own, bnd


@nb.njit(cache=True, nogil=True, inline="always")
def _bound_members(ref, bnd, xacc, cacc, acc, margin, poles, cut):  # pragma: no cover - compiled
    # The default bound of _one for every member p: its scale ref[p] grows with G_p(k) |X_p(k)| (xacc, the
    # sum of its terms without y; G_p(k) the push_gain of its linear feedback at sample k, cacc[:, p]), and a
    # sample beyond BOUND_FACTOR × that scale is NaN, and so is every later one, as _one stops there: a stopped
    # member's bound is -1 for good (its NaN need not reach a later sample, e.g. y(k) = a y(k-2) reads only every
    # other one). ``poles``: some member's margin is -1 (the structure's feedback runs through the inputs): every
    # member's is then -1 but a padding member's (θ = 0: the poles' margin is 1 too) or a non-finite one's (not
    # inside: the same 1), so one loop serves them all, without a branch per member. cut[p]: the bound stopped
    # member p at a finite sample (linear_margins' −2, judged here by the steady gain: see _rerun).
    P = acc.shape[0]
    for p in range(P):
        x = abs(xacc[p])
        d = pole_margin(cacc[0, p], cacc[1, p]) if poles else _push_margin(cacc[0, p], cacc[1, p], margin[p])
        d = d if d <= 1.0 else 1.0
        if x > ref[p] * d:  # off the common path: a division only where the scale grows
            ref[p] = x / d
            bnd[p] = scaled_bound(ref[p])
        if not (abs(acc[p]) <= bnd[p]):
            if bnd[p] >= 0.0 and abs(acc[p]) < np.inf:
                cut[p] = True
            acc[p] = np.nan
            ref[p] = np.inf
            bnd[p] = -1.0


@nb.njit(cache=True, nogil=True, inline="always")
def _bound_lattice(ref, bnd, xacc, cacc, acc, a, w):  # pragma: no cover - compiled
    # _bound_members in the lattice pass (linear_margins' −2, the members the steady gain stopped: see _rerun):
    # cacc holds a row per lag, each member's a_l, read by _lattice_push_margin (``a``, ``w``: work rows). Kernels
    # of their own: a branch to it in _bound_members' loop, even one never taken, slowed every bounded batch run by
    # 10–20 %.
    for p in range(acc.shape[0]):
        for r in range(cacc.shape[0]):
            a[r] = cacc[r, p]
        d = _lattice_push_margin(a, w)
        x = abs(xacc[p])
        if x > ref[p] * d:
            ref[p] = x / d
            bnd[p] = scaled_bound(ref[p])
        if not (abs(acc[p]) <= bnd[p]):
            acc[p] = np.nan
            ref[p] = np.inf
            bnd[p] = -1.0


@nb.njit(cache=True, nogil=True)
def _batch_block(thT, U, ny, ylag, Y, start, ref, margin):  # pragma: no cover - compiled
    # ``ref`` (P,): each member's starting scale, for the default bound; empty: no bound; ``margin`` (P,):
    # linear_margins (no −2: see _rerun). Returns cut (P,), _bound_members'.
    n, P = Y.shape
    mask = -1  # all ones: (k - lag) & mask == k - lag, the whole record is kept
    acc = np.empty(P)
    bounded, ref, bnd = _bound_start(ref)
    xacc = np.empty(P)
    cacc = np.empty((2, P))
    poles = bounded and margin.shape[0] > 0 and margin.min() < 0.0
    # every margin in [0, 1] (a constant feedback's, or the steady gain's first pass of linear_margins' −2): the
    # bound's test needs no pole test's branches (_bound_hit)
    steady = bounded and margin.shape[0] > 0 and margin.min() >= 0.0 and margin.max() <= 1.0
    cut = np.zeros(P, dtype=np.bool_)
    for k in range(start, n):
        _advance(thT, U, ny, ylag, Y, k, mask, acc, xacc, cacc, bounded)
        if bounded and _bound_hit(ref, bnd, xacc, cacc, acc, margin, poles, steady):
            _bound_members(ref, bnd, xacc, cacc, acc, margin, poles, cut)
        for p in range(P):
            Y[k, p] = acc[p]
    return cut


@nb.njit(cache=True, nogil=True, inline="always")
def _bound_hit(ref, bnd, xacc, cacc, acc, margin, poles, steady):  # pragma: no cover - compiled
    # whether _bound_members has anything to do at this sample for a member still running: its scale grows or its
    # sample leaves its bound. Its own loop's stores on those rare events kept it scalar (the bound doubled a batch
    # run's cost); this loop's one store is unconditional: a stopped member's sample NaN (bound -1), as
    # _bound_members makes it, and where it says no (nearly every sample) _bound_members would have changed nothing
    # else. A stopped member is no hit: one member's divergence made every later sample take the scalar loop
    P = acc.shape[0]
    hit = False
    if poles:
        for p in range(P):
            d = pole_margin(cacc[0, p], cacc[1, p])
            d = d if d <= 1.0 else 1.0
            live = bnd[p] >= 0.0
            hit |= live & ((abs(xacc[p]) > ref[p] * d) | (not (abs(acc[p]) <= bnd[p])))
            acc[p] = acc[p] if live else np.nan
    elif steady:
        for p in range(P):
            d = _steady_margin(cacc[0, p], cacc[1, p], margin[p])
            d = d if d <= 1.0 else 1.0
            live = bnd[p] >= 0.0
            hit |= live & ((abs(xacc[p]) > ref[p] * d) | (not (abs(acc[p]) <= bnd[p])))
            acc[p] = acc[p] if live else np.nan
    else:
        for p in range(P):
            d = _push_margin(cacc[0, p], cacc[1, p], margin[p])
            d = d if d <= 1.0 else 1.0
            live = bnd[p] >= 0.0
            hit |= live & ((abs(xacc[p]) > ref[p] * d) | (not (abs(acc[p]) <= bnd[p])))
            acc[p] = acc[p] if live else np.nan
    return hit


@nb.njit(cache=True, nogil=True)
def _batch_block_lattice(thT, U, ny, ylag, Y, start, ref):  # pragma: no cover - compiled
    # _batch_block's bounded run judged by the lattice margin (see _rerun): a row of cacc per lag
    n, P = Y.shape
    acc = np.empty(P)
    _, ref, bnd = _bound_start(ref)
    xacc = np.empty(P)
    L = _single_lags(ny, ylag)
    cacc = np.empty((L, P))
    a, w = np.empty(L), np.empty(L)
    for k in range(start, n):
        _advance(thT, U, ny, ylag, Y, k, -1, acc, xacc, cacc, True)
        _bound_lattice(ref, bnd, xacc, cacc, acc, a, w)
        for p in range(P):
            Y[k, p] = acc[p]


@nb.njit(cache=True, parallel=True)
def _batch_block_parallel(blocks, U, ny, ylag, Y, start, refs, margins):  # pragma: no cover - compiled
    # blocks: (n_blocks, T, step); Y: (n_blocks, N, step) with the initial rows filled; refs
    # (n_blocks, step) or (n_blocks, 0). An OpenMP team (see _batch_sse_parallel) rather than a
    # Python thread pool. Returns cut (n_blocks, step), as _batch_block's.
    cut = np.zeros((blocks.shape[0], blocks.shape[2]), dtype=np.bool_)
    for b in nb.prange(blocks.shape[0]):
        cut[b] = _batch_block(blocks[b], U, ny, ylag, Y[b], start, refs[b], margins[b])
    return cut


def _blocks(thT: np.ndarray, threads: int) -> np.ndarray:
    """(threads, T, step) contiguous population blocks, zero-padded (a harmless null model)."""
    P = thT.shape[1]
    step = (P + threads - 1) // threads
    blocks = np.zeros((threads, thT.shape[0], step))
    for b in range(threads):
        part = thT[:, b * step : (b + 1) * step]
        blocks[b, :, : part.shape[1]] = part
    return blocks


def simulate_batch(
    code: Code,
    thetas: np.ndarray,
    u: np.ndarray,
    y0: np.ndarray,
    start: int,
    threads: int = 1,
    *,
    bounded: bool = False,
) -> np.ndarray:
    """Free runs of P parameter vectors of one structure.

    Parameters
    ----------
    code : Code
        :func:`encode` of the structure.
    thetas : ndarray, shape (P, n_terms)
    u : ndarray, shape (N,) or (N, m)
        Input(s), columns in ``code.input_names`` order.
    y0 : ndarray, shape (start,)
        Initial outputs shared by the population.
    start : int
        Number of initial samples (>= the structure's max lag).
    threads : int
        Population blocks run in parallel (an OpenMP team); 1 runs in the calling thread.
    bounded : bool
        Stop each member's run where :func:`simulate_one`'s default bound stops it (the samples
        from there on NaN), so that a member diverges here exactly where its own free run does.
        False: only an overflow ends a run (a cost inside an optimiser).

    Returns
    -------
    ndarray, shape (P, N)
        Outputs (a transposed view of an (N, P) buffer); a diverging member has non-finite
        samples (never raises).
    """
    n = u.shape[0]
    thT = kernel_array(thetas.T)
    U = _input_products(code.fptr, code.fsig, code.flag, code.fpow, kernel_inputs(code, u), start)
    ref = _member_scales(code, thetas, u, y0, start, bounded)
    margin = linear_margins(code, thetas) if bounded else np.zeros(0)
    out, cut = _simulate_members(code, thT, U, y0, start, threads, ref, np.where(margin < -1.5, 1.0, margin))
    redo = _redo(margin, cut)
    if redo.size:  # the members the steady gain stopped, by the lattice margin from the start (see _rerun)
        Y = np.empty((n, redo.size))  # a few members: in this thread
        Y[:start, :] = y0[:start, None]
        with np.errstate(all="ignore"):
            _batch_block_lattice(kernel_array(thT[:, redo]), U, code.ny, code.ylag, Y, start, ref[redo])
        out[redo] = Y.T
    return out


def _redo(margin: np.ndarray, cut: np.ndarray) -> np.ndarray:
    """The members to run again with the lattice margin (:func:`_rerun`, for each member): their indices."""
    if margin.size == 0:
        return np.zeros(0, dtype=np.int64)
    return np.flatnonzero((margin < -1.5) & cut)


def _simulate_members(code: Code, thT: np.ndarray, U: np.ndarray, y0: np.ndarray, start: int, threads: int,
                      ref: np.ndarray, margin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`simulate_batch`'s runs of the members ``thT`` (T, P) judged by ``margin``: (outputs (P, N), cut (P,))."""
    n, P = U.shape[0], thT.shape[1]
    with np.errstate(all="ignore"):
        if threads <= 1 or P < 2 * threads:
            Y = np.empty((n, P))
            Y[:start, :] = y0[:start, None]
            cut = _batch_block(thT, U, code.ny, code.ylag, Y, start, ref, margin)
            # a transposed view, not a copy: copying 5 MB cost more than the whole batch run
            return Y.T, cut
        blocks = kernel_array(_blocks(thT, int(threads)))  # read-only, as thT is: one compiled kernel
        Y = np.empty((blocks.shape[0], n, blocks.shape[2]))
        Y[:, :start, :] = y0[None, :start, None]
        cut = _batch_block_parallel(blocks, U, code.ny, code.ylag, Y, start, _ref_blocks(ref, blocks),
                                    _ref_blocks(margin - 1.0, blocks) + 1.0)  # padding members: margin 1
        return np.concatenate([Yb.T for Yb in Y])[:P], cut.ravel()[:P]


def _member_scales(code: Code, thetas: np.ndarray, u: np.ndarray, y0: np.ndarray, start: int, bounded: bool
                   ) -> np.ndarray:
    """Each member's starting scale for the batch kernels' bound, max(max|y0|, :func:`feedback_scales`),
    shape (P,); empty when not ``bounded`` (no bound)."""
    if not bounded:
        return np.zeros(0)
    y_start = float(np.max(np.abs(np.asarray(y0[:start], dtype=float)), initial=0.0))
    return np.maximum(y_start, feedback_scales(code, thetas, u))


def _ref_blocks(ref: np.ndarray, blocks: np.ndarray) -> np.ndarray:
    """``ref`` laid out by :func:`_blocks` as the members are, (n_blocks, step); (n_blocks, 0) when empty
    (the padding members, θ = 0, start from scale 0)."""
    if ref.size == 0:
        return np.zeros((blocks.shape[0], 0))
    return np.ascontiguousarray(_blocks(ref[None, :], blocks.shape[0])[:, 0, :])


@nb.njit(cache=True, nogil=True, inline="always")
def _ring_start(y, start, ring, P):  # pragma: no cover - compiled
    # the ring buffer of the batch SSE kernels: each member's first `start` outputs are the measured ones
    mask = ring - 1
    Y = np.empty((ring, P))
    for k in range(start):
        for p in range(P):
            Y[k & mask, p] = y[k]
    return Y


@nb.njit(cache=True, nogil=True)
def _batch_sse(thT, U, ny, ylag, y, start, ring, ref, margin):  # pragma: no cover - compiled
    # Same update as _batch_block, but the outputs live in a ring buffer of `ring` rows (a
    # power of two > max lag) and only the squared free-run error is kept: the population's
    # working set stays in L1 whatever N is. ``ref`` as for _batch_block. Returns (sse, cut), cut as _batch_block's.
    n = U.shape[0]
    P = thT.shape[1]
    mask = ring - 1
    Y = _ring_start(y, start, ring, P)
    sse = np.zeros(P)
    acc = np.empty(P)
    bounded, ref, bnd = _bound_start(ref)
    xacc = np.empty(P)
    cacc = np.empty((2, P))
    poles = bounded and margin.shape[0] > 0 and margin.min() < 0.0
    # every margin in [0, 1] (a constant feedback's, or the steady gain's first pass of linear_margins' −2): the
    # bound's test needs no pole test's branches (_bound_hit)
    steady = bounded and margin.shape[0] > 0 and margin.min() >= 0.0 and margin.max() <= 1.0
    cut = np.zeros(P, dtype=np.bool_)
    for k in range(start, n):
        _advance(thT, U, ny, ylag, Y, k, mask, acc, xacc, cacc, bounded)
        if bounded and _bound_hit(ref, bnd, xacc, cacc, acc, margin, poles, steady):
            _bound_members(ref, bnd, xacc, cacc, acc, margin, poles, cut)
        kk = k & mask
        yk = y[k]
        for p in range(P):
            Y[kk, p] = acc[p]
            e_ = acc[p] - yk
            sse[p] += e_ * e_
    return sse, cut


@nb.njit(cache=True, nogil=True)
def _batch_sse_lattice(thT, U, ny, ylag, y, start, ring, ref):  # pragma: no cover - compiled
    # _batch_sse's bounded run judged by the lattice margin (see _rerun): a row of cacc per lag
    n = U.shape[0]
    P = thT.shape[1]
    mask = ring - 1
    Y = _ring_start(y, start, ring, P)
    sse = np.zeros(P)
    acc = np.empty(P)
    _, ref, bnd = _bound_start(ref)
    xacc = np.empty(P)
    L = _single_lags(ny, ylag)
    cacc = np.empty((L, P))
    a, w = np.empty(L), np.empty(L)
    for k in range(start, n):
        _advance(thT, U, ny, ylag, Y, k, mask, acc, xacc, cacc, True)
        _bound_lattice(ref, bnd, xacc, cacc, acc, a, w)
        kk = k & mask
        for p in range(P):
            Y[kk, p] = acc[p]
            e_ = acc[p] - y[k]
            sse[p] += e_ * e_
    return sse


@nb.njit(cache=True, parallel=True)
def _batch_sse_parallel(blocks, U, ny, ylag, y, start, ring, refs, margins):  # pragma: no cover - compiled
    # blocks: (n_blocks, T, step) contiguous population blocks. An OpenMP team keeps its workers
    # spinning for a moment between calls, so a GA's millisecond calls do not pay for waking an
    # idle core each time (a Python thread pool did not beat one thread for them: BENCHMARKS.md).
    nb_ = blocks.shape[0]
    out = np.empty((nb_, blocks.shape[2]))
    cut = np.zeros((nb_, blocks.shape[2]), dtype=np.bool_)
    for b in nb.prange(nb_):
        out[b], cut[b] = _batch_sse(blocks[b], U, ny, ylag, y, start, ring, refs[b], margins[b])
    return out, cut


def batch_sse(
    code: Code,
    thetas: np.ndarray,
    u: np.ndarray,
    y: np.ndarray,
    start: int,
    threads: int = 1,
    U: np.ndarray | None = None,
    *,
    bounded: bool = False,
) -> np.ndarray:
    """Sum of squared free-run errors of P parameter vectors, samples ``start … N-1``.

    The free run starts from the measured ``y[:start]``. Non-finite where a member diverges.

    Parameters
    ----------
    code : Code
    thetas : ndarray, shape (P, n_terms)
    u : ndarray, shape (N,) or (N, m)
        Input(s), columns in ``code.input_names`` order.
    y : ndarray, shape (N,)
        Measured output.
    start : int
        Number of initial conditions (>= the structure's max lag).
    threads : int
        Parallel population blocks.
    U : ndarray, shape (N, n_terms), optional
        :func:`input_products` of ``u``, when the caller keeps it across calls (a GA does).
    bounded : bool
        As for :func:`simulate_batch`: a member whose free run leaves :func:`simulate_one`'s
        default bound has a non-finite sum, as its own free run has. False (optimisers' costs):
        only an overflow makes it non-finite.

    Returns
    -------
    ndarray, shape (P,)
    """
    thT = kernel_array(np.asarray(thetas, dtype=np.float64).T)
    if U is None:
        U = _input_products(code.fptr, code.fsig, code.flag, code.fpow, kernel_inputs(code, u), start)
    ref = _member_scales(code, np.atleast_2d(np.asarray(thetas, dtype=np.float64)), u, y, start, bounded)
    margin = linear_margins(code, thetas) if bounded else np.zeros(0)
    y = kernel_array(y)
    ring = 1 << int(np.ceil(np.log2(start + 1)))
    with np.errstate(all="ignore"):
        P = thT.shape[1]
        fast = np.where(margin < -1.5, 1.0, margin)
        if threads <= 1 or P < 2 * threads:
            sse, cut = _batch_sse(thT, U, code.ny, code.ylag, y, start, ring, ref, fast)
        else:
            blocks = kernel_array(_blocks(thT, int(threads)))  # read-only, as thT is: one compiled kernel
            sse, cut = _batch_sse_parallel(blocks, U, code.ny, code.ylag, y, start, ring, _ref_blocks(ref, blocks),
                                           _ref_blocks(fast - 1.0, blocks) + 1.0)  # padding: margin 1
            sse, cut = sse.ravel()[:P], cut.ravel()[:P]
        redo = _redo(margin, cut)
        if redo.size:  # the members the steady gain stopped, by the lattice margin from the start (see _rerun)
            sse[redo] = _batch_sse_lattice(kernel_array(thT[:, redo]), U, code.ny, code.ylag, y, start, ring,
                                           ref[redo])
    return sse


@nb.njit(cache=True, nogil=True)
def _sensitivity_rows(ny, ylag, theta, U, yh, S, k0, k1, off):  # pragma: no cover - compiled
    # Forward sensitivity of the free run: S(k, j) = ∂ŷ(k)/∂θ_j obeys
    #   S(k, :) = φ(k, :) + Σ_t θ_t Σ_{y(k-l) in t} ∂φ_t/∂y(k-l) · S(k-l, :),
    # where φ(k, t) is term t evaluated on the simulated output.
    # The feedback is gathered first into a_l(k) = ∂ŷ(k)/∂ŷ(k-l) (a few lags), so the
    # Jacobian update costs (number of lags) × n_terms per sample, not n_factors × n_terms.
    # Samples k0..k1-1 are computed: ŷ(k) into yh[k] (earlier samples must be there), S(k, :)
    # into S[k - off] (the rows of the output lags before k0 must be there), so a caller can
    # run a long record through a small buffer of rows.
    nt = theta.shape[0]
    Ly = 0
    for t in range(nt):
        for d in range(ny[t]):
            Ly = max(Ly, ylag[t, d])
    a = np.zeros(Ly + 1)
    for k in range(k0, k1):
        row = k - off
        acc = 0.0
        for l in range(Ly + 1):
            a[l] = 0.0
        for t in range(nt):
            m = ny[t]
            v = U[k, t]
            for d in range(m):
                v *= yh[k - ylag[t, d]]
            S[row, t] = v  # φ_t(k): the direct part of ∂ŷ(k)/∂θ_t
            acc += theta[t] * v
            if m == 0 or theta[t] == 0.0:
                continue
            for d in range(m):
                # derivative of the product with respect to its d-th output factor
                g = theta[t] * U[k, t]
                for e in range(m):
                    if e != d:
                        g *= yh[k - ylag[t, e]]
                a[ylag[t, d]] += g
        yh[k] = acc
        for l in range(1, Ly + 1):
            if a[l] != 0.0:
                r = row - l
                for j in range(nt):
                    S[row, j] += a[l] * S[r, j]


@nb.njit(cache=True, nogil=True)
def _sensitivity(ny, ylag, theta, U, y0, start):  # pragma: no cover - compiled
    n = U.shape[0]
    yh = np.empty(n)
    S = np.zeros((n, theta.shape[0]))
    for k in range(start):
        yh[k] = y0[k]
    _sensitivity_rows(ny, ylag, theta, U, yh, S, start, n, np.int64(0))
    return yh, S


def free_run_sensitivity_blocks(
    code: Code, theta: np.ndarray, U: np.ndarray, y0: np.ndarray, start: int, block: int = 4096
):
    """Free run and its Jacobian with respect to θ, streamed in blocks of samples.

    Memory stays at ``block`` rows of the Jacobian whatever the record's length (a long
    record's full N × n_terms Jacobian would not stay in cache, nor, at 10⁶ samples and
    beyond, comfortably in memory).

    Parameters
    ----------
    code : Code
    theta : ndarray, shape (n_terms,)
    U : ndarray, shape (N, n_terms)
        :func:`input_products` of the record's input.
    y0 : ndarray, shape (start,)
        Initial outputs.
    start : int
        First simulated sample (at least the structure's largest output lag).
    block : int
        Samples per block.

    Yields
    ------
    k0, k1 : int
        The block's samples.
    yh : ndarray, shape (N,)
        The free run, valid up to sample k1 (one array, filled as the blocks go).
    S : ndarray, shape (k1 − k0, n_terms)
        ∂ŷ(k)/∂θ_j for k in [k0, k1): a view into a buffer reused by the next block.
    """
    theta = kernel_array(theta)
    n = U.shape[0]
    H = max(int(start), 1)
    block = max(int(block), H)
    yh = np.empty(n)
    yh[:start] = y0[:start]
    buf = np.zeros((H + block, theta.size))
    for k0 in range(start, n, block):
        k1 = min(k0 + block, n)
        with np.errstate(all="ignore"):
            _sensitivity_rows(code.ny, code.ylag, theta, U, yh, buf, k0, k1, np.int64(k0 - H))
        yield k0, k1, yh, buf[H:H + k1 - k0]
        buf[:H] = buf[k1 - k0:k1 - k0 + H]  # the rows the next block's feedback reads


def free_run_sensitivity(
    code: Code, theta: np.ndarray, u: np.ndarray, y0: np.ndarray, start: int, U: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Free run and its Jacobian with respect to θ by forward sensitivity recursion.

    ``U`` is :func:`input_products` of ``u`` when the caller keeps it across calls.

    Returns
    -------
    y : ndarray, shape (N,)
    S : ndarray, shape (N, n_terms)
        ∂y(k)/∂θ_j (zero for the initial samples).
    """
    if U is None:
        U = _input_products(code.fptr, code.fsig, code.flag, code.fpow, kernel_inputs(code, u), start)
    with np.errstate(all="ignore"):
        return _sensitivity(code.ny, code.ylag, kernel_array(theta), U, kernel_array(y0), start)


__all__ += ["batch_sse", "free_run_sensitivity", "free_run_sensitivity_blocks"]


@nb.njit(cache=True, nogil=True)
def _inverse_ma_cols(X, a, bounds, out):  # pragma: no cover - compiled
    # samples outermost, signals innermost (contiguous): the recursions of the m signals
    # run side by side instead of one latency-bound chain at a time
    L = a.shape[0] - 1
    m = X.shape[1]
    for s in range(bounds.shape[0] - 1):
        k0, k1 = bounds[s], bounds[s + 1]
        for k in range(k0, k1):
            for r in range(m):
                out[k, r] = X[k, r]
            for l in range(1, min(L, k - k0) + 1):
                al = a[l]
                for r in range(m):
                    out[k, r] -= al * out[k - l, r]


def inverse_ma_filter(X: np.ndarray, C: np.ndarray, bounds: np.ndarray) -> np.ndarray:
    """Columns of ``X`` filtered by 1/C(q) from rest on each segment: what ``lfilter([1], C, ·, axis=0)`` gives.

    Parameters
    ----------
    X : ndarray, shape (N, m)
        Signals, one per column (C-contiguous is fastest).
    C : ndarray, shape (L + 1,)
        Monic polynomial 1 + c_1 q^-1 + … + c_L q^-L.
    bounds : ndarray of int, shape (S + 1,)
        Segment boundaries along the rows (records): the recursion restarts at each.

    Returns
    -------
    ndarray, shape (N, m)
    """
    X = np.ascontiguousarray(X, dtype=np.float64)
    out = np.empty_like(X)
    _inverse_ma_cols(X, np.ascontiguousarray(C, dtype=np.float64), np.asarray(bounds, dtype=np.int64), out)
    return out


__all__ += ["inverse_ma_filter"]
