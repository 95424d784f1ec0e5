"""Compiled kernels of the static analysis (numba): real roots, the stability test, settling runs.

- :func:`schur_stable_rows` — the one stability test: the Schur–Cohn step-down recursion on the
  characteristic polynomial of a linearised recursion (no eigenvalues are computed, which keeps it
  cheap enough for every generation of a GA); the coefficients come from
  :mod:`graybox.static._linearisation`.
- :func:`entry_sums` — the coefficients a_l of a linearised recursion from the term structure's
  entries (the arithmetic of :mod:`graybox.static._linearisation`, compiled: it runs at every trial
  point of a fit).
- :func:`real_roots_upto_cubic` — real roots of the static equation (degree ≤ 3) for every
  (member, point) pair, with the variable scaled by a power of two so that the extreme
  coefficients are balanced (the decisions do not depend on the units of y), then Kahan's cubic
  solver (one real root by a monotone Newton iteration, deflation, a stable quadratic formula).
- :func:`merge_multiple_roots` — one root for each multiple root (a fold of the static curve) and which
  roots are multiple, from the polynomial's conditioning at and between them.
- :func:`settle_runs` — the one "run until settled" routine: a free run at constant input from a
  constant initial output, stopped and classified (reached a given stable equilibrium / diverged /
  did not settle within the step budget). Two recursions share it: a polynomial model with its
  input folded into the coefficients, and a one-hidden-layer tanh network.

Nothing here validates input: :mod:`graybox.static._analysis` and :mod:`graybox.estimation._neural` do.
"""

from __future__ import annotations

import math

from ..core._jit import nb
import numpy as np

__all__ = [
    "schur_stable_rows", "unit_pole", "entry_sums", "real_roots_upto_cubic", "real_roots_upto_cubic_sized", "merge_multiple_roots", "settle_candidates", "settle_runs",
    "candidate_linearisations",
    "POLY", "NET", "REACHED", "DIVERGED", "NOT_SETTLED", "SKIPPED",
]

#: Kinds of recursion understood by :func:`settle_runs`.
POLY, NET = 0, 1
#: Outcomes of :func:`settle_runs` (codes shared with :class:`graybox.static._analysis.Reached`).
REACHED, DIVERGED, NOT_SETTLED = 0, 3, 4
#: A pair not followed to its end: another pair of its group ended not reached (``group`` of :func:`settle_runs`).
SKIPPED = 6


# -- the stability test ------------------------------------------------------------------------
@nb.njit(cache=True, nogil=True)
def _schur_cohn(c, n, nxt):  # pragma: no cover - compiled
    """Are all roots of z^n + c[1] z^(n-1) + … + c[n] (c[0] = 1) strictly inside the unit circle?

    The step-down recursion: every reflection coefficient must lie strictly inside (−1, 1).
    ``c`` is overwritten; ``nxt`` is work space of the same length. Non-finite → False.
    """
    for i in range(n + 1):
        if not np.isfinite(c[i]):
            return False
    while n > 0:
        k = c[n]
        if not (abs(k) < 1.0):
            return False
        den = 1.0 - k * k
        for i in range(n):
            nxt[i] = (c[i] - k * c[n - i]) / den
        for i in range(n):
            c[i] = nxt[i]
        n -= 1
    return True


@nb.njit(cache=True, nogil=True)
def unit_pole(a):  # pragma: no cover - compiled
    """Is z = 1 a root of z^L − a_1 z^(L−1) − … − a_L to rounding: 1 − Σ a_l within the sum's rounding error,
    4 (L + 1) eps (1 + Σ |a_l|)? So at a fold of the static curve (1 − Σ a_l = −∂F/∂ȳ = 0), whatever rounding made of
    the a_l (Σ a_l = 1 − 2⁻⁵² passes the step-down recursion). ``a`` shape (L,); False for L = 0."""
    L = a.shape[0]
    s = 0.0
    m = 0.0
    for i in range(L):
        s += a[i]
        m += abs(a[i])
    return L > 0 and abs(1.0 - s) <= 4.0 * (L + 1) * 2.220446049250313e-16 * (1.0 + m)


@nb.njit(cache=True, nogil=True)
def schur_stable_rows(a):  # pragma: no cover - compiled
    """(K,) mask: is y(k) = Σ_l a[r, l-1] y(k-l) asymptotically stable, row by row?

    ``a`` has shape (K, L): the coefficients a_1 … a_L of a linearised recursion. A pole at z = 1 to rounding
    (:func:`unit_pole`) is not inside: the one test says so, for the static analysis and the local models alike.
    """
    K, L = a.shape
    out = np.zeros(K, dtype=np.bool_)
    c = np.empty(L + 1)
    nxt = np.empty(L + 1)
    for r in range(K):
        c[0] = 1.0
        for i in range(L):
            c[i + 1] = -a[r, i]
        out[r] = _schur_cohn(c, L, nxt) and not unit_pole(a[r])
    return out


@nb.njit(cache=True, nogil=True)
def entry_sums(th, yb, U, t, l, g, yexp, Ly):  # pragma: no cover - compiled
    """a[r, l_e] = Σ_e θ[r, t_e] g_e ȳ_r^(yexp_e) U[r, e], summed entry by entry in order, shape (R, Ly).

    One row r per (θ, steady state) pair: ``th`` (R, T), ``yb`` (R,), ``U`` (R, E) the entries'
    input parts; entry e is (term t_e, lag l_e, lag count g_e, output exponent yexp_e ≥ 0). An
    entry whose θ is 0 adds nothing (an overflowing weight of a zero term is no NaN). The product
    is formed as ((θ g) Y) U, Y = ȳ^yexp with ȳ¹ = ȳ and ȳ² = ȳ·ȳ, as numpy forms it.
    """
    R = th.shape[0]
    E = t.shape[0]
    a = np.zeros((R, Ly))
    for r in range(R):
        y = yb[r]
        for e in range(E):
            v = th[r, t[e]]
            if v == 0.0:
                continue
            x = yexp[e]
            if x == 0.0:
                Y = 1.0
            elif x == 1.0:
                Y = y
            elif x == 2.0:
                Y = y * y
            else:
                Y = y ** x
            a[r, l[e]] += v * g[e] * Y * U[r, e]
    return a


# -- real roots of the static equation -----------------------------------------------------------
@nb.njit(cache=True, nogil=True)
def _pow2_scale(c, deg):  # pragma: no cover - compiled
    """Power of two s balancing |c_lo| s^lo and |c_hi| s^hi (lo, hi: first and last non-zero)."""
    lo = -1
    hi = -1
    for k in range(deg + 1):
        if c[k] != 0.0:
            if lo < 0:
                lo = k
            hi = k
    if lo < 0 or hi == lo:
        return 1.0
    e = (np.log2(abs(c[lo])) - np.log2(abs(c[hi]))) / (hi - lo)
    return 2.0 ** np.round(e)


@nb.njit(cache=True, nogil=True)
def _eval3(X, A, B, C, D):  # pragma: no cover - compiled
    # A X³ + B X² + C X + D by Horner, its derivative, and the quotient's coefficients b1, c2
    q0 = A * X
    b1 = q0 + B
    c2 = b1 * X + C
    dq = (q0 + b1) * X + c2
    q = c2 * X + D
    return q, dq, b1, c2


@nb.njit(cache=True, nogil=True)
def _disc_slack(a, b1, r, n, sizes):  # pragma: no cover - compiled
    """How far below 0 the discriminant of the quadratic factor a x² + b1 x + c2 of F (F itself, or F / (x − r[0])
    after a real root r[0] of a cubic, n = 1) may be for coefficients known to ``ROOT_EPS`` eps of their sizes: F
    uncertain by η = ROOT_EPS eps Σ sizes_p |x|^p at the would-be double root x = −b1 / (2a) leaves the factor
    uncertain by η / |x − r[0]|, and its discriminant by 4 |a| that."""
    x = -b1 / (2.0 * a)
    eta = 0.0
    pw = 1.0
    for p in range(4):
        eta += sizes[p] * pw
        pw *= abs(x)
    eta *= ROOT_EPS * 2.220446049250313e-16
    if n == 1:
        if x == r[0]:
            return 0.0
        eta /= abs(x - r[0])
    out = 4.0 * abs(a) * eta
    return out if np.isfinite(out) else 0.0


@nb.njit(cache=True, nogil=True)
def _horner_slack(x, A, B, C, D):  # pragma: no cover - compiled
    """The rounding error bound of the cubic A x³ + B x² + C x + D evaluated at ``x`` by Horner's rule (:func:`_eval3`):
    2 · 3 eps of Σ |coefficient| |x|^p. Within it the computed value's sign is rounding's."""
    ax = abs(x)
    return 6.0 * 2.220446049250313e-16 * (((abs(A) * ax + abs(B)) * ax + abs(C)) * ax + abs(D))


@nb.njit(cache=True, nogil=True)
def _real_roots3(A, B, C, D, r, sizes):  # pragma: no cover - compiled
    """Real roots of A x³ + B x² + C x + D into r (unsorted); returns their number. ``sizes`` (ascending, 4): the
    sizes of the terms each coefficient sums (:func:`real_roots_upto_cubic_sized`): the quadratic's discriminant
    may be below 0 by its own rounding and by what those leave uncertain, and still be a double root.

    W. Kahan, "To solve a real cubic equation" (1986): one real root by Newton's iteration from
    a start that makes it monotone, deflation (from the end that keeps it accurate), and the
    stable quadratic formula. Exact zeros of A (or B) lower the degree; nothing else does.
    """
    n = 0
    if A == 0.0:
        a, b1, c2 = B, C, D
    elif D == 0.0:
        r[n] = 0.0
        n += 1
        a, b1, c2 = A, B, C
    else:
        X = -(B / A) / 3.0
        q, dq, b1, c2 = _eval3(X, A, B, C, D)
        t = q / A
        rr = np.cbrt(abs(t))
        s = 1.0 if t > 0.0 else (-1.0 if t < 0.0 else 0.0)
        t = -dq / A
        if t > 0.0:
            rr = 1.324718 * max(rr, np.sqrt(t))
        x0 = X - s * rr
        # F at the inflection X within its own rounding (_horner_slack): X is a root as far as F can be evaluated,
        # and with F'(X) ~ 0 too (a triple root) the start Kahan's iteration takes from F's computed sign there is
        # rounding's: its Newton steps went far past the root, so that the cubic's one real root came out 1.6 % off,
        # not a root at all, where a change of y's units (× 3.7) or of u's (× 1e4) rounded the coefficients
        # otherwise, and the fold (a triple root, not stable) was called a stable equilibrium there
        if x0 != X and abs(q) > _horner_slack(X, A, B, C, D):
            for _ in range(200):
                X = x0
                q, dq, b1, c2 = _eval3(X, A, B, C, D)
                x0 = X if dq == 0.0 else X - (q / dq) / 1.000000000000001
                if not (s * x0 > s * X):
                    break
            if abs(A) * X * X > abs(D / X):
                c2 = -D / X
                b1 = (c2 - C) / X
        if not np.isfinite(X):
            return 0
        r[n] = X
        n += 1
        a = A
    # a x² + b1 x + c2
    if a == 0.0:
        if b1 != 0.0:
            r[n] = -c2 / b1
            n += 1
        return n
    disc = b1 * b1 - 4.0 * a * c2
    if disc < 0.0:
        # within its own rounding error (a few eps of the terms it is the difference of) a negative discriminant is
        # a double root that rounding pushed into the complex plane, as often as it splits one into two reals: it is
        # the double root (merge_multiple_roots reads it as such), in any units
        if -disc > 8.0 * 2.220446049250313e-16 * (b1 * b1 + 4.0 * abs(a * c2)) + _disc_slack(a, b1, r, n, sizes):
            return n
        disc = 0.0
    qq = -0.5 * (b1 + (np.sqrt(disc) if b1 >= 0.0 else -np.sqrt(disc)))
    if qq == 0.0:  # b1 = 0 and a c2 = 0: a double root at 0
        r[n] = 0.0
        r[n + 1] = 0.0
        return n + 2
    r[n] = qq / a
    r[n + 1] = c2 / qq
    return n + 2


@nb.njit(cache=True, nogil=True)
def real_roots_upto_cubic(coef):  # pragma: no cover - compiled
    """:func:`real_roots_upto_cubic_sized` of coefficients known to their own rounding (sizes |coef|)."""
    return real_roots_upto_cubic_sized(coef, np.abs(coef))


@nb.njit(cache=True, nogil=True)
def real_roots_upto_cubic_sized(coef, size):  # pragma: no cover - compiled
    """Real roots of Σ_p coef[p] y^p (degree ≤ 3) for every (member, point), sorted, NaN-padded.

    ``size`` (same shape): the sizes of the terms each coefficient sums (:func:`merge_multiple_roots`'s): a
    quadratic's discriminant below 0 by no more than what the coefficients are known to (``ROOT_EPS`` eps of
    their sizes) is a double root, as one below 0 by its own rounding is (ȳ − θ1 ȳ of a θ1 near 1 leaves the
    ȳ coefficient known to eps, not to eps of itself).

    Parameters
    ----------
    coef : ndarray, shape (D + 1, P, M), D ≤ 3
        Ascending coefficients.

    Returns
    -------
    ndarray, shape (P, M, max(D, 1))
        Real roots, ascending; NaN where fewer exist (or a coefficient is not finite). The
        variable is scaled by a power of two (exact) that balances the extreme coefficients, so
        a change of units of y changes nothing but the scale; every root is then polished by
        Newton steps on the full polynomial that are kept only when they reduce |F|.
    """
    D = coef.shape[0] - 1
    P, M = coef.shape[1], coef.shape[2]
    W = max(D, 1)
    out = np.full((P, M, W), np.nan)
    c = np.zeros(4)
    a = np.zeros(4)
    r = np.empty(4)
    for i in range(P):
        for j in range(M):
            ok = True
            for k in range(4):
                c[k] = coef[k, i, j] if k <= D else 0.0
                a[k] = max(abs(size[k, i, j]), abs(c[k])) if k <= D else 0.0
                if not np.isfinite(c[k]):
                    ok = False
            if not ok:
                continue
            s = _pow2_scale(c, 3)
            big = 0.0
            for k in range(4):
                # c_k s^k by k exact multiplications (s is a power of two), not by s^k: s^3 overflows where
                # the roots span beyond ~1e205 (a y² coefficient ~1e-212 of a unit constant) and 0 · inf
                # made an absent cubic coefficient NaN, losing every root, the sane one too
                for _ in range(k):
                    c[k] *= s
                    a[k] *= s
                big = max(big, abs(c[k]))
            if big == 0.0 or not np.isfinite(big):
                continue
            e = 2.0 ** np.round(np.log2(big))
            for k in range(4):
                c[k] /= e
                a[k] /= e
            n = _real_roots3(c[3], c[2], c[1], c[0], r, a)
            for k in range(n):
                x = r[k]
                f = ((c[3] * x + c[2]) * x + c[1]) * x + c[0]
                for _ in range(2):
                    df = (3.0 * c[3] * x + 2.0 * c[2]) * x + c[1]
                    if df == 0.0:
                        break
                    xn = x - f / df
                    fn = ((c[3] * xn + c[2]) * xn + c[1]) * xn + c[0]
                    if not (abs(fn) < abs(f)):
                        break
                    x, f = xn, fn
                r[k] = x * s
            # sort the (at most three) roots
            for a_ in range(n):
                for b_ in range(a_ + 1, n):
                    if r[b_] < r[a_]:
                        r[a_], r[b_] = r[b_], r[a_]
            for k in range(min(n, W)):
                out[i, j, k] = r[k]
    return out


#: A polynomial's coefficients are taken as known to this many eps of the sizes of the terms each is the sum of
#: (:func:`merge_multiple_roots`): a θ stored, its products with powers of ū, their sum and the −ȳ of eq. (5).
ROOT_EPS = 2.0


@nb.njit(cache=True, nogil=True)
def _scaled_pair(c, a, x, t, u):  # pragma: no cover - compiled
    """t[p] = c[p] x^p and u[p] = a[p] x^p (a[p] >= |c[p]|: the sizes of the terms c[p] sums), both scaled by one
    power of two (exact) where one leaves the float range (roots near 1e200: inf − inf would say nothing; an underflow
    would drop a term); only ratios of sums of them are used."""
    n = c.shape[0]
    ok = True
    pw = 1.0
    for p in range(n):
        t[p] = c[p] * pw
        u[p] = a[p] * pw
        if not (np.isfinite(u[p]) and np.isfinite(t[p])) or (u[p] == 0.0 and a[p] != 0.0 and x != 0.0):
            ok = False
        pw *= x
    if ok:
        return
    xm, xe = math.frexp(x)
    emax = -(1 << 62)
    for p in range(n):
        if a[p] != 0.0:
            emax = max(emax, math.frexp(a[p])[1] + p * xe)
    pw = 1.0
    for p in range(n):
        t[p] = 0.0
        u[p] = 0.0
        if c[p] != 0.0:
            cm, ce = math.frexp(c[p])
            t[p] = math.ldexp(cm, max(ce + p * xe - emax, -1100)) * pw
        if a[p] != 0.0:
            am, ae = math.frexp(a[p])
            u[p] = math.ldexp(am, max(ae + p * xe - emax, -1100)) * pw
        pw *= xm


@nb.njit(cache=True, nogil=True)
def _curvature(t, u):  # pragma: no cover - compiled
    """x² F''(x) over the size S(x) = Σ a_p |x|^p, from :func:`_scaled_pair`'s terms (0 where S is)."""
    s = 0.0
    for p in range(t.shape[0]):
        s += abs(u[p])
    if s == 0.0:
        return 0.0
    d2 = 0.0
    for p in range(t.shape[0]):
        d2 += p * (p - 1) * (t[p] / s)
    return d2


@nb.njit(cache=True, nogil=True)
def merge_multiple_roots(coef, roots, size):  # pragma: no cover - compiled
    """One root for each multiple root of Σ_p coef[p] y^p, and which roots are multiple (a fold: F'(ȳ) = 0).

    A double root comes out of a solver as two equal roots, or as two a rounding error apart (of
    relative size √eps, a companion matrix's). The coefficients are known to η = ROOT_EPS eps S(x),
    S(x) = Σ_p size[p] |x|^p (``size``: the sum of the magnitudes of the terms each coefficient sums,
    >= |coef|; the polynomial's conditioning). Two distinct roots δ apart leave F''δ²/8 at their
    midpoint: adjacent roots x1 < x2 are one when |F''| δ²/8 <= η there (a change of the coefficients
    within η makes them one double root; true double roots that rounding split are far inside it) and F itself
    is that small there, to η and its own rounding (2 (D + 1) eps S: F'' stands for F only where F is near a
    parabola; where F'' vanishes between two roots, as s (ȳ⁴ − 1)'s at 0 between −1 and 1, it says nothing), and
    the midpoint stands for both; farther apart they are two, however close (1 and 1 + 1.2e-7 at y's scale 1 are).
    A root is multiple when F'(x)² <= 2 η |F''(x)|, the same bound read at the root (F' = ±F''δ/2 at each
    of two roots δ apart; a root of multiplicity m split by rounding into parts δ apart has F' ~ F^(m)
    δ^(m−1), F'' ~ F^(m) δ^(m−2), η ~ F^(m) δ^m): so also a triple root whose companions a solver made
    complex. Units-free: both sides scale alike.

    Parameters
    ----------
    coef : ndarray, shape (D + 1, P, M)
        Ascending coefficients.
    roots : ndarray, shape (P, M, D)
        Real roots, ascending, NaN-padded.
    size : ndarray, shape (D + 1, P, M)
        The sizes of the coefficients' terms (``coef`` itself where the coefficients are given).

    Returns
    -------
    (ndarray, ndarray)
        The roots with each multiple one once (ascending, NaN-padded), shape (P, M, D), and whether each is
        multiple, bool, same shape.
    """
    n = coef.shape[0]
    P, M, D = roots.shape
    out = roots.copy()
    fold = np.zeros(roots.shape, dtype=np.bool_)
    c = np.empty(n)
    a = np.empty(n)
    t = np.empty(n)
    u = np.empty(n)
    eps = np.finfo(np.float64).eps
    eta = ROOT_EPS * eps
    for i in range(P):
        for j in range(M):
            m = 0
            while m < D and np.isfinite(out[i, j, m]):
                m += 1
            if m == 0:
                continue
            for p in range(n):
                c[p] = coef[p, i, j]
                a[p] = max(abs(size[p, i, j]), abs(c[p]))
            k = 0
            while k < m - 1:
                x1 = out[i, j, k]
                x2 = out[i, j, k + 1]
                mid = 0.5 * x1 + 0.5 * x2
                delta = x2 - x1
                same = x1 == x2
                if not same and abs(mid) < delta:  # about 0 (roots of either sign, or one far beyond the other):
                    # F, F'' and S at mid in the variable x / g, g the power of two of the gap, whose terms
                    # c_p g^p _scaled_pair forms (scaled by one power of two): F'' δ² and S(mid) overflowed
                    # unscaled where the far root is beyond ~1e154 (1 and 1e200 read inf <= inf: one 'fold')
                    g = math.ldexp(1.0, math.frexp(delta)[1])
                    _scaled_pair(c, a, g, t, u)
                    xm = mid / g  # |xm| < 1
                    dm = delta / g  # in [1/2, 1)
                    f0 = 0.0
                    f2 = 0.0
                    sz = 0.0
                    pw = 1.0
                    for p in range(n):
                        sz += abs(u[p]) * abs(pw)
                        f0 += t[p] * pw
                        pw *= xm
                    pw = 1.0
                    for p in range(2, n):
                        f2 += p * (p - 1) * t[p] * pw
                        pw *= xm
                    same = abs(f2) * dm * dm / 8.0 <= eta * sz and abs(f0) <= (eta + 2 * n * eps) * sz
                elif not same:
                    _scaled_pair(c, a, mid, t, u)
                    r = delta / mid  # the gap relative to where it is, |r| <= 2
                    f0 = 0.0
                    sz = 0.0
                    for p in range(n):
                        f0 += t[p]
                        sz += abs(u[p])
                    same = abs(_curvature(t, u)) * r * r / 8.0 <= eta and abs(f0) <= (eta + 2 * n * eps) * sz
                if same:  # the pair is one root: the midpoint; the rest move down (and may merge with it in turn)
                    out[i, j, k] = mid
                    for q in range(k + 1, m - 1):
                        out[i, j, q] = out[i, j, q + 1]
                    out[i, j, m - 1] = np.nan
                    m -= 1
                else:
                    k += 1
            for k in range(m):
                x = out[i, j, k]
                if x == 0.0:  # x F' and x² F'' vanish there: F'(0) = c_1
                    fold[i, j, k] = c[1] == 0.0
                    continue
                _scaled_pair(c, a, x, t, u)
                s = 0.0
                for p in range(n):
                    s += abs(u[p])
                if s == 0.0:
                    continue
                d1 = 0.0
                d2 = 0.0
                for p in range(n):  # x F'(x) and x² F''(x), over the size S(x) (no overflow)
                    d1 += p * (t[p] / s)
                    d2 += p * (p - 1) * (t[p] / s)
                fold[i, j, k] = d1 * d1 <= 2.0 * eta * abs(d2)
    return out, fold


# -- running until settled ---------------------------------------------------------------------------
#: Pairs run side by side (lanes): independent recursions interleaved hide each one's latency.
LANES = 8
#: The geometric test of :func:`settle_runs` (runs given their candidates' rates): windows of
#: GEOM_TAUS time constants, GEOM_WINDOWS of them in a row each shrinking the distance to the
#: candidate by at least ρ^(GEOM_SLACK · window). The linearised recursion shrinks it by ρ^window
#: once the faster modes have died (faster while they have not); the slack leaves room for the
#: window's maximum to fall between samples of a mode near −1 or of a complex pair. Four windows,
#: 0.2 time constants, against the decay to SETTLE_RTOL that a run close to its candidate otherwise
#: needs (ln(distance / tol) ≈ 2 time constants on the plant's near-integrators).
GEOM_TAUS = 0.05
GEOM_WINDOWS = 3
GEOM_SLACK = 0.9


@nb.njit(cache=True, nogil=True, inline="always")
def _step_lanes(kind, ip, C, ring, t, mask, acc):  # pragma: no cover - compiled
    """acc[b] = next output of lane b's recursion at constant input; outputs in ring[(k & mask)·B + b].

    Every loop over lanes runs over the whole lane axis, contiguous in ``ring`` and ``C``, with a
    compile-time length, so LLVM vectorises it.
    """
    B = LANES
    if kind == POLY:
        # ip = [G, Dg, gny(G), gylag(G·Dg)]; C rows = [X, C_0 … C_{G-1}]
        G = ip[0]
        Dg = ip[1]
        for b in range(B):
            acc[b] = C[0, b]
        for g in range(G):
            m = ip[2 + g]
            lag = 2 + G + g * Dg
            o0 = ((t - ip[lag]) & mask) * B
            if m == 1:
                for b in range(B):
                    acc[b] += C[1 + g, b] * ring[o0 + b]
            elif m == 2:
                o1 = ((t - ip[lag + 1]) & mask) * B
                for b in range(B):
                    acc[b] += C[1 + g, b] * ring[o0 + b] * ring[o1 + b]
            elif m == 3:
                o1 = ((t - ip[lag + 1]) & mask) * B
                o2 = ((t - ip[lag + 2]) & mask) * B
                for b in range(B):
                    acc[b] += C[1 + g, b] * ring[o0 + b] * ring[o1 + b] * ring[o2 + b]
            else:
                for b in range(B):
                    v = C[1 + g, b]
                    for d in range(m):
                        v *= ring[((t - ip[lag + d]) & mask) * B + b]
                    acc[b] += v
        return
    # NET: ip = [H, ny]; C rows = [b2, w2(H), c(H), A(H·ny)]
    H = ip[0]
    ny = ip[1]
    for b in range(B):
        acc[b] = C[0, b]
    for j in range(H):
        for b in range(B):
            a = C[1 + H + j, b]
            for i in range(ny):
                a += C[1 + 2 * H + j * ny + i, b] * ring[((t - 1 - i) & mask) * B + b]
            acc[b] += C[1 + j, b] * np.tanh(a)


@nb.njit(cache=True, nogil=True)
def _static_residual(kind, ip, fp, y):  # pragma: no cover - compiled
    """F(y) = g(y, …, y) − y and F'(y) of the scalar static equation (fp: one pair's row)."""
    if kind == POLY:
        G = ip[0]
        F = fp[0] - y
        dF = -1.0
        for g in range(G):
            m = ip[2 + g]
            v = fp[1 + g]
            for _ in range(m - 1):
                v *= y
            F += v * y
            dF += m * v
        return F, dF
    H = ip[0]
    ny = ip[1]
    F = fp[0] - y
    dF = -1.0
    for j in range(H):
        a = 0.0
        for i in range(ny):
            a += fp[1 + 2 * H + j * ny + i]
        th = np.tanh(fp[1 + H + j] + a * y)
        F += fp[1 + j] * th
        dF += fp[1 + j] * a * (1.0 - th * th)
    return F, dF


@nb.njit(cache=True, nogil=True)
def candidate_linearisations(kind, ip, fp, cand, ncand, L):  # pragma: no cover - compiled
    """a[k, c, l − 1] = ∂f/∂y(t − l) of pair k's recursion at the constant output cand[k, c], shape (K, C, L).

    The linearised recursion y(t) = Σ_l a_l y(t − l) at each pair's first ``ncand[k]`` candidates
    (zeros elsewhere); layouts of ``ip`` and ``fp`` as in :func:`_step_lanes`.
    """
    K, C = cand.shape
    a = np.zeros((K, C, L))
    for k in range(K):
        for c in range(ncand[k]):
            y = cand[k, c]
            if kind == POLY:
                G = ip[0]
                Dg = ip[1]
                for g in range(G):
                    m = ip[2 + g]
                    v = fp[k, 1 + g]
                    for _ in range(m - 1):
                        v *= y
                    for d in range(m):  # each factor y(t − lag_d) contributes C_g y^(m−1)
                        a[k, c, ip[2 + G + g * Dg + d] - 1] += v
            else:
                H = ip[0]
                ny = ip[1]
                for j in range(H):
                    s = 0.0
                    for i in range(ny):
                        s += fp[k, 1 + 2 * H + j * ny + i]
                    th = np.tanh(fp[k, 1 + H + j] + s * y)
                    w = fp[k, 1 + j] * (1.0 - th * th)
                    for i in range(ny):
                        a[k, c, i] += w * fp[k, 1 + 2 * H + j * ny + i]
    return a


@nb.njit(cache=True, nogil=True)
def settle_candidates(roots, stable, y0, floor, rtol):  # pragma: no cover - compiled
    """The targets of :func:`settle_runs`: each pair's stable roots first (in their order), and their tolerances.

    ``roots`` (K, D) NaN-padded, ``stable`` (K, D), ``y0`` (K,). A root's scale is
    min(max(|root|, |y0|, floor), its distance to the nearest other finite root); ``tol`` is
    ``rtol`` × scale and ``ntol`` 1000 ``rtol`` × scale. Returns (cand (K, D) NaN-padded,
    ncand (K,), tol (K, D), ntol (K, D)).
    """
    K, D = roots.shape
    cand = np.full((K, D), np.nan)
    tol = np.full((K, D), np.nan)
    ntol = np.full((K, D), np.nan)
    ncand = np.zeros(K, dtype=np.int64)
    big = 1000.0 * rtol
    for k in range(K):
        c = 0
        for i in range(D):
            r = roots[k, i]
            if not (stable[k, i] and np.isfinite(r)):
                continue
            gap = np.inf
            for j in range(D):
                if j != i:
                    d = abs(r - roots[k, j])
                    if np.isfinite(d) and d < gap:
                        gap = d
            scale = min(max(max(abs(r), abs(y0[k])), floor), gap)
            cand[k, c] = r
            tol[k, c] = rtol * scale
            ntol[k, c] = big * scale
            c += 1
        ncand[k] = c
    return cand, ncand, tol, ntol


@nb.njit(cache=True, nogil=True)
def settle_runs(kind, ip, fp, y0, cand, ncand, tol, ntol, L, floor, max_steps, budgets, hist, stall_rtol, lograte,
                group=None, dead=None, final=False):  # pragma: no cover - compiled
    """Run each pair's recursion at constant input from y0 until it settles; classify the end.

    Parameters
    ----------
    kind : int
        :data:`POLY` or :data:`NET` (see :func:`_step_lanes` for the layouts of ``ip`` and ``fp``).
    ip : ndarray of int64
        Integer description of the recursion, shared by all pairs.
    fp : ndarray, shape (K, nf)
        Each pair's coefficients (its input folded in).
    y0 : ndarray, shape (K,)
        Initial output: all L initial conditions equal it.
    cand : ndarray, shape (K, C)
        The pair's locally stable equilibria; the first ``ncand[k]`` of them are valid.
    tol, ntol : ndarray, shape (K, C)
        A pair has reached candidate c once its last L outputs all lie within ``tol`` of c; or
        once its last L increments are all below stall_rtol · max(|y|, |y0|, floor), it lies
        within ``ntol`` of c, and Newton's method on the static equation, started at the current
        output, lands within ``ntol`` of c (a slow approach: there no other root is near, and the run and the
        root finder may place c apart by more than ``tol``, the roundings of two foldings of its terms).
    L : int
        Number of past outputs the recursion reads (its largest output lag, >= 1).
    floor : float
        Smallest output scale (0 where only ratios of outputs are meaningful).
    max_steps : int
        Step budget of every pair ...
    budgets : ndarray of int64, shape (K,) or (0,)
        ... or each pair's own (when not empty).
    hist : ndarray, shape (K, L) or (0, L)
        When not empty, each pair goes on from these last L outputs (oldest first) of an earlier
        call that left it not settled, as one longer run would (``y0`` still sets its scales).
    stall_rtol : float
        Relative size of a vanishing increment.
    lograte : ndarray, shape (K, C) or (0, C)
        When not empty, ln ρ of each candidate (ρ the spectral radius of the recursion linearised
        there, < 1): a run also reaches candidate c once, over :data:`GEOM_WINDOWS` consecutive
        windows of :data:`GEOM_TAUS` time constants −1/ln ρ each, its largest distance to c has
        shrunk window by window at least as fast as ρ^(GEOM_SLACK · window) and lies within
        ``ntol`` of c: the approach is geometric at the candidate's own rate (the linearised
        recursion's), which a run heading elsewhere, cycling or stalling does not show. A slow
        mode near −1 (an oscillation about c that dies out over 10⁵ samples) ends no other way
        short of its decay to ``tol``.
    group : ndarray of int64, shape (K,), optional
        Each pair's group (a member: its points). Given, a group counts as failed once one of its pairs
        ends :data:`DIVERGED`, or :data:`NOT_SETTLED` when ``final`` (a last pass); its other pairs then
        end, or are not started, as :data:`SKIPPED` (NaN): a caller that only asks whether every point
        of a member is reached (J_SF is infinite as soon as one is not) pays no run whose end cannot
        change that answer. The pairs of groups that never fail run exactly as without groups.
    dead : ndarray of bool, shape (number of groups,), optional
        Which groups have failed (read and updated in place; required with ``group``).
    final : bool
        Whether a pair ending :data:`NOT_SETTLED` fails its group (no later pass goes on with it).

    Returns
    -------
    ybar : ndarray, shape (K,)
        The candidate reached (NaN when none is).
    status : ndarray of int8, shape (K,)
        :data:`REACHED`, :data:`DIVERGED` (the output left 10⁶ times the pair's scale or is not
        finite) or :data:`NOT_SETTLED` (neither within the budget: an oscillation, a limit
        cycle, a run too slow); with ``group``, also :data:`SKIPPED`.
    last : ndarray, shape (K, L)
        The last L outputs (oldest first) of each pair left not settled (``hist`` of a call that
        goes on with it); undefined for the others.
    left : int
        How many pairs were left not settled.
    """
    K = y0.shape[0]
    nf = fp.shape[1]
    B = LANES
    ring_n = 1
    while ring_n < L + 1:
        ring_n *= 2
    mask = ring_n - 1
    ybar = np.full(K, np.nan)
    status = np.full(K, NOT_SETTLED, dtype=np.int8)
    last_out = np.empty((K, L))
    left = 0
    resume = hist.shape[0] > 0
    ring = np.zeros(ring_n * B)
    Cl = np.zeros((nf, B))
    acc = np.empty(B)
    pair = np.full(B, -1, dtype=np.int64)
    start = np.zeros(B, dtype=np.int64)
    limit = np.zeros(B, dtype=np.int64)
    own = budgets.shape[0] > 0
    target = np.zeros(B, dtype=np.int64)  # the candidate this lane's window is measured against
    goal = np.zeros(B)
    dev = np.zeros(B)  # largest |y − goal| since the last check
    inc = np.zeros(B)  # largest |y(k) − y(k−1)| since the last check
    bound = np.zeros(B)
    sref = np.zeros(B)
    geo = lograte.shape[0] > 0
    gwin = np.zeros(B, dtype=np.int64)  # steps per geometric window (0: no geometric test for this lane)
    gsteps = np.zeros(B, dtype=np.int64)  # steps into the current window
    gdev = np.zeros(B)  # largest |y − goal| in the current window ...
    gprev = np.zeros(B)  # ... and in the window before (0: none yet)
    gcount = np.zeros(B, dtype=np.int64)  # consecutive windows that shrank at the candidate's rate
    nxt = 0
    active = 0
    t = L
    while True:
        # fill empty lanes with the next pairs (a pair that starts on a candidate needs no run)
        for b in range(B):
            while pair[b] < 0 and nxt < K:
                k = nxt
                nxt += 1
                if group is not None and dead[group[k]]:
                    status[k] = SKIPPED
                    continue
                yk0 = y0[k]
                ycur = hist[k, L - 1] if resume else yk0  # a resumed run is measured from where it is
                ref = max(abs(yk0), floor)
                best = 0
                for c_ in range(ncand[k]):
                    ref = max(ref, abs(cand[k, c_]))
                    if abs(ycur - cand[k, c_]) < abs(ycur - cand[k, best]):
                        best = c_
                if not resume and abs(yk0 - cand[k, best]) <= tol[k, best]:
                    ybar[k] = cand[k, best]
                    status[k] = REACHED
                    continue
                pair[b] = k
                active += 1
                start[b] = t
                limit[b] = budgets[k] if own else max_steps
                target[b] = best
                goal[b] = cand[k, best]
                dev[b] = 0.0
                inc[b] = 0.0
                if geo:
                    gwin[b] = _geom_window(lograte[k, best], L)
                    gsteps[b] = 0
                    gdev[b] = 0.0
                    gprev[b] = 0.0
                    gcount[b] = 0
                bound[b] = 1e6 * ref
                sref[b] = max(abs(yk0), floor)
                for i in range(ring_n):
                    ring[i * B + b] = yk0
                if resume:
                    for i in range(L):
                        ring[((t - L + i) & mask) * B + b] = hist[k, i]
                for f in range(nf):
                    Cl[f, b] = fp[k, f]
        if active == 0:
            break
        # L steps, all lanes at once; each lane tracks its largest deviation from its goal and
        # its largest increment over these L outputs (vectorised, no branches)
        for _ in range(L):
            _step_lanes(kind, ip, Cl, ring, t, mask, acc)
            last = ((t - 1) & mask) * B
            now = (t & mask) * B
            for b in range(B):
                dev[b] = max(dev[b], abs(acc[b] - goal[b]))
                inc[b] = max(inc[b], abs(acc[b] - ring[last + b]))
            for b in range(B):
                ring[now + b] = acc[b]
            t += 1
        # check each lane on the window of its last L outputs
        for b in range(B):
            k = pair[b]
            if k < 0:
                continue
            y = ring[((t - 1) & mask) * B + b]
            c0 = target[b]
            end = -1
            if group is not None and dead[group[k]]:
                end = SKIPPED
            elif not (abs(y) <= bound[b]) or not (dev[b] < np.inf):
                end = DIVERGED
            elif dev[b] <= tol[k, c0]:
                end = REACHED
            elif inc[b] <= stall_rtol * max(abs(y), sref[b]) and abs(y - goal[b]) <= ntol[k, c0]:
                # a slow approach: Newton on the static equation says where it is heading
                x = y
                for _ in range(50):
                    F, dF = _static_residual(kind, ip, fp[k], x)
                    if dF == 0.0 or not np.isfinite(F / dF):
                        break
                    x -= F / dF
                    if abs(F / dF) <= 1e-15 * max(abs(x), floor):
                        break
                # within ntol (at most a thousandth of the way to any other root) Newton has found c itself: the
                # recursion's own static equation puts it where the candidate's root finder did, to their two
                # roundings (far from the signals' zeros, cancelling terms of 1e6 shift a slow equilibrium by
                # more than tol, and a run measured against tol then went on for its whole budget)
                if abs(x - goal[b]) <= ntol[k, c0] and np.isfinite(x):
                    end = REACHED
            if end < 0 and gwin[b] > 0:
                gdev[b] = max(gdev[b], dev[b])
                gsteps[b] += L
                if gsteps[b] >= gwin[b]:
                    # this window against the one before: shrunk at least at the candidate's own rate?
                    if gprev[b] > 0.0 and gdev[b] <= ntol[k, c0] and \
                            gdev[b] <= gprev[b] * np.exp(GEOM_SLACK * gsteps[b] * lograte[k, c0]):
                        gcount[b] += 1
                    else:
                        gcount[b] = 0
                    if gcount[b] >= GEOM_WINDOWS:
                        end = REACHED
                    gprev[b] = gdev[b]
                    gdev[b] = 0.0
                    gsteps[b] = 0
            if end < 0 and t - start[b] >= limit[b]:
                end = NOT_SETTLED
            if end >= 0:
                status[k] = end
                if group is not None and (end == DIVERGED or (end == NOT_SETTLED and final)):
                    dead[group[k]] = True
                if end == NOT_SETTLED:
                    left += 1
                    for i in range(L):
                        last_out[k, i] = ring[((t - L + i) & mask) * B + b]
                if end == REACHED:
                    ybar[k] = goal[b]
                pair[b] = -1
                active -= 1
                for f in range(nf):
                    Cl[f, b] = 0.0  # an idle lane computes zeros
                for i in range(ring_n):
                    ring[i * B + b] = 0.0
                goal[b] = 0.0
                continue
            # measure the next window against the candidate nearest the current output
            best = 0
            for c_ in range(ncand[k]):
                if abs(y - cand[k, c_]) < abs(y - cand[k, best]):
                    best = c_
            if geo and best != target[b]:  # another candidate: its own rate, windows from scratch
                gwin[b] = _geom_window(lograte[k, best], L)
                gsteps[b] = 0
                gdev[b] = 0.0
                gprev[b] = 0.0
                gcount[b] = 0
            target[b] = best
            goal[b] = cand[k, best]
            dev[b] = 0.0
            inc[b] = 0.0
    return ybar, status, last_out, left


@nb.njit(cache=True, nogil=True)
def _geom_window(lr, L):  # pragma: no cover - compiled
    """Steps of one geometric window: GEOM_TAUS time constants −1/ln ρ, a multiple of L (0: no test)."""
    w = GEOM_TAUS / (-lr) / L
    if not (0.0 < w < 1e15):  # ρ >= 1 or NaN: no rate to test against; a window no int holds: none either
        return 0
    return max(int(np.ceil(w)), 1) * L
