"""Static analysis of polynomial NARX models: clusters, equilibria, static curve and gain.

At a constant input ū a term with output power p and input power m becomes
ȳ^p ū^m, so the steady state solves the polynomial equation (eq. (5))

    ȳ = Σ_{p,m} Σ_{y^p u^m} ȳ^p ū^m,

whose coefficients are the *cluster coefficients* Σ = R θ (R is a 0/1 matrix).
When no term has y to a power above 1 the solution is the rational function of
eq. (6). Every real root is an equilibrium; its local stability follows from the
linearised recursion y(k) = Σ_i a_i y(k-i) with a_i = ∂f/∂y(k-i) at (ȳ, ū).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ._validation import as_1d_finite
from ._terms import Structure, Term

__all__ = [
    "cluster_key",
    "cluster_name",
    "ClusterMap",
    "cluster_map",
    "Equilibrium",
    "equilibria",
    "static_curve",
    "static_gain",
    "is_rational",
    "rational_static_curve",
    "rational_parts",
    "stable_mask",
    "rational_equilibria",
]

_SUP = str.maketrans("0123456789", "⁰¹²³⁴⁵⁶⁷⁸⁹")


def cluster_key(term: Term) -> tuple[int, int]:
    """(power of y, power of u) of a process term: its cluster Ω_{y^p u^m}."""
    if term.is_noise:
        raise ValueError(f"noise term {term} has no cluster")
    return term.power_of("y"), term.power_of("u")


def cluster_name(p: int, m: int) -> str:
    """Paper-style cluster name: ``Σ0``, ``Σy``, ``Σu²``, ``Σyu``, ``Σy²u`` …"""
    if p == 0 and m == 0:
        return "Σ0"
    s = "Σ"
    if p:
        s += "y" + (str(p).translate(_SUP) if p > 1 else "")
    if m:
        s += "u" + (str(m).translate(_SUP) if m > 1 else "")
    return s


@dataclass(frozen=True)
class ClusterMap:
    """The clusters of a structure and the 0/1 map R with Σ = R θ.

    Attributes
    ----------
    keys : tuple of (p, m)
        Output and input powers of each cluster, sorted by (p, m).
    R : ndarray, shape (n_clusters, n_terms)
    """

    keys: tuple[tuple[int, int], ...]
    R: np.ndarray

    @property
    def names(self) -> list[str]:
        """Cluster names in the order of ``keys``."""
        return [cluster_name(p, m) for p, m in self.keys]

    def index(self, name_or_key: str | tuple[int, int]) -> int:
        """Row of R for a cluster given by name (``"Σyu"``, or ASCII ``"Syu"``) or (p, m)."""
        if isinstance(name_or_key, tuple):
            return self.keys.index(name_or_key)
        name = name_or_key.replace("S", "Σ", 1) if name_or_key.startswith("S") else name_or_key
        name = name.replace("^", "").translate(_SUP) if "Σ" in name else name
        names = self.names
        if name not in names:
            raise ValueError(f"no cluster {name_or_key!r} in this structure; it has {names}")
        return names.index(name)

    @property
    def max_y_power(self) -> int:
        """Largest output power over the clusters."""
        return max((p for p, _ in self.keys), default=0)


@lru_cache(maxsize=256)
def cluster_map(structure: Structure) -> ClusterMap:
    """Build the :class:`ClusterMap` of the process terms of ``structure`` (cached: it is immutable)."""
    keys = [cluster_key(t) for t in structure]
    uniq = tuple(sorted(set(keys)))
    R = np.zeros((len(uniq), len(structure)))
    for j, k in enumerate(keys):
        R[uniq.index(k), j] = 1.0
    R.setflags(write=False)
    return ClusterMap(uniq, R)


def _poly_in_y(cm: ClusterMap, sigma: np.ndarray, ubar: float) -> np.ndarray:
    """Coefficients c_p (p = 0..P) of F(ȳ) = Σ_p c_p ȳ^p - ȳ, highest power first (np.roots order)."""
    P = max(cm.max_y_power, 1)
    c = np.zeros(P + 1)
    for (p, m), s in zip(cm.keys, sigma):
        c[p] += s * ubar**m
    c[1] -= 1.0
    return c[::-1]


def _linear_coefficients(structure: Structure, theta: np.ndarray, ybar: float, ubar: float) -> np.ndarray:
    """a_i = ∂f/∂y(k-i) at the equilibrium, i = 1..L (L = largest output lag)."""
    L = max((l for t in structure for s, l, _ in t.factors if s == "y"), default=0)
    a = np.zeros(L)
    for th, term in zip(theta, structure):
        if th == 0.0:
            continue
        p, m = cluster_key(term)
        for s, l, pw in term.factors:
            if s == "y":
                # d/dy(k-l) of y(k-l)^pw * (rest) at steady state = pw * ybar^(p-1) * ubar^m
                a[l - 1] += th * pw * ybar ** (p - 1) * ubar**m
    return a


@dataclass(frozen=True)
class Equilibrium:
    """A real steady state of a model at constant input.

    Attributes
    ----------
    ubar, ybar : float
        Input and output levels.
    stable : bool
        True when every root of the linearised recursion lies strictly inside the unit circle.
    spectral_radius : float
        Largest modulus of those roots (0 for a static model).
    """

    ubar: float
    ybar: float
    stable: bool
    spectral_radius: float


def _spectral_radius(a: np.ndarray) -> float:
    if a.size == 0 or not np.any(a):
        return 0.0
    # characteristic polynomial z^L - a1 z^(L-1) - ... - aL
    return float(np.max(np.abs(np.roots(np.concatenate(([1.0], -a))))))


def equilibria(structure: Structure, theta: np.ndarray, ubar: float, imag_tol: float = 1e-9) -> list[Equilibrium]:
    """Every real equilibrium at constant input ``ubar``, sorted by ȳ, with its local stability.

    Parameters
    ----------
    structure : Structure
        Process terms.
    theta : ndarray, shape (n_terms,)
    ubar : float
        Constant input level (engineering units).
    imag_tol : float
        A root counts as real when |Im| <= imag_tol * max(1, |root|).
    """
    cm = cluster_map(structure)
    sigma = cm.R @ theta
    c = np.trim_zeros(_poly_in_y(cm, sigma, float(ubar)), "f")
    if c.size <= 1:
        return []  # no dependence on ȳ left: no (or infinitely many) solutions
    roots = np.roots(c)
    real = sorted(float(r.real) for r in roots if abs(r.imag) <= imag_tol * max(1.0, abs(r)))
    out = []
    for yb in real:
        rho = _spectral_radius(_linear_coefficients(structure, theta, yb, float(ubar)))
        out.append(Equilibrium(float(ubar), yb, rho < 1.0, rho))
    return out


@lru_cache(maxsize=256)
def is_rational(structure: Structure) -> bool:
    """True when no term has y to a power above 1 (static function of eq. (6))."""
    return all(t.power_of("y") <= 1 for t in structure if not t.is_noise)


def rational_parts(structure: Structure, thetas: np.ndarray, ubar: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Numerator Σ0 + Σu ū + … and denominator 1 − Σy − Σyu ū − … of eq. (6).

    Parameters
    ----------
    structure : Structure
        A rational structure (no term with y to a power above 1).
    thetas : ndarray, shape (n_terms,) or (P, n_terms)
    ubar : ndarray, shape (M,)

    Returns
    -------
    num, den : ndarray, shape (M,) or (P, M)
    """
    if not is_rational(structure):
        raise ValueError("structure has a term with y to a power above 1: its static function is not rational")
    cm = cluster_map(structure)
    th = np.asarray(thetas, dtype=float)
    sig = th @ cm.R.T  # (C,) or (P, C)
    ub = np.asarray(ubar, dtype=float)
    num = np.zeros(sig.shape[:-1] + ub.shape)
    den = np.ones_like(num)
    for c, (p, m) in enumerate(cm.keys):
        term = sig[..., c, None] * ub**m
        if p == 0:
            num += term
        else:
            den -= term
    return num, den


def rational_equilibria(
    structure: Structure, thetas: np.ndarray, ubar: np.ndarray, stable_only: bool = True
) -> np.ndarray:
    """Eq. (6) for many parameter vectors, shape (P, M); NaN where the denominator vanishes.

    With ``stable_only`` an equilibrium that is not locally stable is NaN too: the model does
    not settle there (:func:`stable_mask`).

    Parameters
    ----------
    structure : Structure
        A rational structure.
    thetas : ndarray, shape (P, n_terms)
    ubar : ndarray, shape (M,)
    stable_only : bool
    """
    th = np.atleast_2d(np.asarray(thetas, float))
    ub = np.asarray(ubar, float)
    num, den = rational_parts(structure, th, ub)
    with np.errstate(divide="ignore", invalid="ignore"):
        yb = np.where(np.abs(den) > 1e-12, num / den, np.nan)
    if stable_only:
        yb = np.where(stable_mask(structure, th, ub, yb), yb, np.nan)
    return yb


def rational_static_curve(structure: Structure, theta: np.ndarray, ubar: np.ndarray) -> np.ndarray:
    """Eq. (6): ȳ = (Σ0 + Σu ū + Σu² ū² + …) / (1 − Σy − Σyu ū − …).

    Raises ``ValueError`` when the structure is not rational or the denominator vanishes.
    """
    ub = np.atleast_1d(np.asarray(ubar, dtype=float))
    num, den = rational_parts(structure, theta, ub)
    cm = cluster_map(structure)
    sigma = cm.R @ theta
    scale = 1.0 + sum(abs(s) * np.abs(ub) ** m for (p, m), s in zip(cm.keys, sigma) if p == 1)
    bad = np.abs(den) <= 1e-12 * scale
    if bad.any():
        raise ValueError(f"static function undefined: denominator 1 − Σy − … vanishes at ū = {ub[bad].tolist()}")
    return num / den


def static_curve(
    structure: Structure,
    theta: np.ndarray,
    ubar: np.ndarray,
    y0: float | np.ndarray | None = None,
    strict: bool = True,
) -> np.ndarray:
    """The steady state the model reaches at each constant input ``ubar``.

    At each ū the stable equilibrium is returned. When several are stable the one reached
    by a free run at constant ū from the constant initial output ``y0`` is returned (``y0``
    is then required; the evaluator passes the measured ȳ_i, so J_SF asks "started at the
    plant's measured steady state, where does the model settle?").

    Parameters
    ----------
    structure : Structure
    theta : ndarray, shape (n_terms,)
    ubar : array_like, shape (M,)
    y0 : float or array_like of shape (M,), optional
        Initial output (one for all ū, or one per ū) used to pick among several stable equilibria.
    strict : bool
        When True (default) a ū with no stable equilibrium raises ``ValueError``; when False
        its value is NaN (used inside optimisers, which turn it into an infinite cost).

    Returns
    -------
    ndarray, shape (M,)
    """
    ub = np.atleast_1d(as_1d_finite(np.ravel(ubar), "ubar"))
    y0s = None if y0 is None else np.broadcast_to(np.asarray(y0, dtype=float), ub.shape)
    out = np.empty(ub.size)
    for i, u_ in enumerate(ub):
        stable = [e for e in equilibria(structure, theta, u_) if e.stable]
        if len(stable) == 1:
            out[i] = stable[0].ybar
        elif not stable:
            if strict:
                raise ValueError(f"the model has no stable equilibrium at ū = {u_:g}")
            out[i] = np.nan
        else:
            if y0s is None:
                if strict:
                    raise ValueError(
                        f"the model has {len(stable)} stable equilibria at ū = {u_:g} "
                        f"({[round(e.ybar, 6) for e in stable]}); pass y0 to choose the one reached from it"
                    )
                out[i] = np.nan
                continue
            out[i] = _settle(structure, theta, u_, float(y0s[i]), [e.ybar for e in stable])
    return out


def _settle(structure: Structure, theta: np.ndarray, ubar: float, y0: float, candidates: list[float]) -> float:
    """Run the model at constant input from y0 and return the candidate equilibrium it approaches."""
    from ._kernels import encode, simulate_one

    L = max(structure.max_lag, 1)
    n = L + 20000
    code = encode(structure)
    y = simulate_one(code, np.asarray(theta, float), np.full(n, ubar), np.full(L, y0), L, 1e300)
    end = y[-1]
    if not np.isfinite(end):
        raise ValueError(f"free run at ū = {ubar:g} from y0 = {y0:g} diverged")
    return min(candidates, key=lambda c: abs(c - end))


def static_gain(
    structure: Structure,
    theta: np.ndarray,
    ubar: np.ndarray,
    y0: float | np.ndarray | None = None,
    strict: bool = True,
) -> np.ndarray:
    """dȳ/dū along the static curve, by implicit differentiation of eq. (5).

    Parameters
    ----------
    structure : Structure
    theta : ndarray, shape (n_terms,)
    ubar : array_like, shape (M,)
        Input levels (engineering units).
    y0, strict
        As for :func:`static_curve`.

    Returns
    -------
    ndarray, shape (M,)
        Gain in output units per input unit.
    """
    ub = np.atleast_1d(np.asarray(ubar, dtype=float))
    yb = static_curve(structure, theta, ub, y0=y0, strict=strict)
    cm = cluster_map(structure)
    sigma = cm.R @ theta
    Fu = np.zeros_like(ub)
    Fy = -np.ones_like(ub)
    for (p, m), s in zip(cm.keys, sigma):
        if m:
            Fu += s * m * yb**p * ub ** (m - 1)
        if p:
            Fy += s * p * yb ** (p - 1) * ub**m
    return -Fu / Fy


def nearest_stable_equilibria(
    structure: Structure, thetas: np.ndarray, ubar: np.ndarray, ytarget: np.ndarray
) -> np.ndarray:
    """For many parameter vectors at once: the stable equilibrium nearest ``ytarget`` at each ū.

    The optimisers' fast path for J_SF. Rational structures have one equilibrium (eq. (6)),
    kept when it is stable. Otherwise every real root of eq. (5) is found at once (batched
    companion-matrix eigenvalues), the unstable ones are dropped (:func:`stable_mask`), and the
    one nearest the measured ȳ_i is kept — where :func:`static_curve` would run the model from
    ȳ_i to see which stable equilibrium it reaches (real roots of degree ≤ 3 by closed forms,
    higher degrees by batched companion eigenvalues). The two agree whenever a single stable
    equilibrium exists (the usual case); the shared evaluator re-scores the final members.

    Parameters
    ----------
    structure : Structure
    thetas : ndarray, shape (P, n_terms)
    ubar : ndarray, shape (M,)
    ytarget : ndarray, shape (M,)
        Usually the measured ȳ_i.

    Returns
    -------
    ndarray, shape (P, M)
        NaN where there is no stable real equilibrium.
    """
    th = np.atleast_2d(np.asarray(thetas, float))
    ub = np.asarray(ubar, float)
    yt = np.broadcast_to(np.asarray(ytarget, float), ub.shape)
    P, M = th.shape[0], ub.size
    with np.errstate(all="ignore"):
        if is_rational(structure):
            return rational_equilibria(structure, th, ub)
        cm = cluster_map(structure)
        sig = th @ cm.R.T
        D = cm.max_y_power
        coef = np.zeros((D + 1, P, M))  # F(ȳ) = Σ_p coef[p] ȳ^p
        for c, (p, m) in enumerate(cm.keys):
            coef[p] += sig[:, c, None] * ub[None, :] ** m
        coef[1] -= 1.0
        if D <= 3:
            # closed forms, compiled: batched eigenvalues cost 5 ms per GA generation here
            from ._kernels import real_roots_upto_cubic

            rr = real_roots_upto_cubic(coef)
            roots = rr.astype(complex)
            real = np.isfinite(rr)
        else:
            lead = coef[D]
            ok = np.isfinite(coef).all(axis=0) & (np.abs(lead) > 1e-300)
            comp = np.zeros((P, M, D, D))
            comp[..., 0, :] = -np.moveaxis(coef[D - 1 :: -1], 0, -1) / np.where(ok, lead, 1.0)[..., None]
            if D > 1:
                idx = np.arange(D - 1)
                comp[..., idx + 1, idx] = 1.0
            comp[~ok] = 0.0
            roots = np.linalg.eigvals(comp)  # (P, M, D)
            real = ok[..., None] & (np.abs(roots.imag) <= 1e-9 * (1.0 + np.abs(roots.real)))
        best = np.full((P, M), np.nan)
        dist = np.full((P, M), np.inf)
        for d in range(roots.shape[-1]):
            r = np.where(real[..., d], roots[..., d].real, np.nan)
            good = real[..., d] & stable_mask(structure, th, ub, r)
            dd = np.where(good, np.abs(r - yt[None, :]), np.inf)
            take = dd < dist
            best = np.where(take, r, best)
            dist = np.where(take, dd, dist)
        return best


@lru_cache(maxsize=256)
def _term_keys(structure: Structure) -> tuple[tuple[int, int], ...]:
    return tuple(cluster_key(t) for t in structure)


def static_theta_gradient(structure: Structure, theta: np.ndarray, ubar: np.ndarray, ybar: np.ndarray) -> np.ndarray:
    """∂ȳ_i/∂θ_t at equilibria (ū_i, ȳ_i), by implicit differentiation of eq. (5).

    F(ȳ, θ) = Σ_t θ_t ȳ^{p_t} ū^{m_t} − ȳ = 0 gives ∂ȳ/∂θ_t = −ȳ^{p_t} ū^{m_t} / F_ȳ.

    Returns
    -------
    ndarray, shape (M, n_terms)
    """
    ub = np.asarray(ubar, float)
    yb = np.asarray(ybar, float)
    keys = _term_keys(structure)
    basis = np.stack([yb**p * ub**m for p, m in keys], axis=1)  # (M, n)
    Fy = -np.ones_like(yb)
    for th, (p, m) in zip(theta, keys):
        if p:
            Fy += th * p * yb ** (p - 1) * ub**m
    with np.errstate(all="ignore"):
        return -basis / Fy[:, None]


__all__ += ["nearest_stable_equilibria", "static_theta_gradient"]


def stable_mask(structure: Structure, thetas: np.ndarray, ubar: np.ndarray, ybar: np.ndarray) -> np.ndarray:
    """Is each equilibrium (ū_j, ȳ_pj) of member p locally stable? Shape (P, M), batched.

    The characteristic polynomial z^L − a_1 z^(L−1) − … − a_L of the linearised recursion is
    tested by the Schur–Cohn step-down recursion (all reflection coefficients inside the unit
    interval), compiled (:func:`graybox._kernels.stable_equilibria`): no eigenvalues are
    computed, which makes the test cheap enough for every generation of a GA.

    Parameters
    ----------
    structure : Structure
    thetas : ndarray, shape (P, n_terms)
    ubar : ndarray, shape (M,)
    ybar : ndarray, shape (P, M)
        Equilibrium outputs (non-finite entries count as unstable).
    """
    from ._kernels import encode, stable_equilibria

    code = encode(structure)
    L = int(code.ylag.max(initial=0))
    yb = np.atleast_2d(np.asarray(ybar, float))
    if L == 0:
        return np.isfinite(yb)
    return stable_equilibria(code.ny, code.ylag, code.mu, np.atleast_2d(np.asarray(thetas, float)),
                             np.asarray(ubar, float), yb, L)
