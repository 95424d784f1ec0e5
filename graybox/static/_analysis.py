"""Static analysis of polynomial NARX models: clusters, equilibria, the equilibrium reached, curve and gain.

At a constant input ū a term with output power p and input power m becomes ȳ^p ū^m, so the
steady states solve the polynomial equation (eq. (5))

    F(ȳ) = Σ_{p,m} Σ_{y^p u^m} ȳ^p ū^m − ȳ = 0,

whose coefficients are the *cluster coefficients* Σ = R θ (R is a 0/1 matrix). When no term has
y to a power above 1 the solution is the rational function of eq. (6). Every real root is an
equilibrium; its local stability follows from the linearised recursion y(k) = Σ_i a_i y(k-i),
a_i = ∂f/∂y(k-i) at (ȳ, ū), decided by one test, the compiled Schur–Cohn recursion
(:func:`stable_mask`, :func:`schur_stable`). A multiple root (a fold of the static curve, where
∂F/∂ȳ = Σ a_i − 1 = 0: a pole at z = 1) is one equilibrium, and not stable, whatever rounding made of it
(:func:`~graybox.static._equilibrium_kernels.merge_multiple_roots`).

The equilibrium a model reaches
-------------------------------
J_SF and every static path of the package use one definition. At a static point (ū_i, ȳ_i) the
model's static output is **the equilibrium a free run at constant input ū_i, started with every
initial condition equal to the measured ȳ_i, settles on** (:func:`reached_equilibria`). When the
run settles on none — it diverges, oscillates, or creeps on beyond the step budget — the point is
undefined: J_SF is infinite and the point is named (NaN in batched outputs). A locally stable
equilibrium whose basin does not hold ȳ_i does not count; nor does an unstable one, even for a run
started exactly on it.

- Rational structures (no y power above 1): at constant ū the dynamics are linear in y, so the
  unique equilibrium of eq. (6) is reached from every start exactly when the linearised recursion
  is Schur-stable. This is decided in closed form; no simulation is needed.
- Other structures: every real root of eq. (5) is found and tested; then the model is run from
  ȳ_i (:func:`settle`, compiled, all (member, point) pairs at once) until its last L outputs lie
  within ``SETTLE_RTOL`` (relative) of one stable root, or its increments vanish and Newton's
  method on eq. (5) lands on one; it is stopped as diverged when |y| exceeds 10⁶ times the scale of
  the point, and as not settled after ``SETTLE_STEPS`` steps, or, when a stable root it may be
  heading for is slow, after ``SETTLE_TAUS`` time constants of the slowest (a slow plant sampled
  fast is judged as it is sampled slowly), unless that exceeds ``SETTLE_MAX_STEPS`` steps. A run left
  unsettled by ``SETTLE_STEPS`` and proven to contract onto its nearest root within its budget is not run on: its
  end is known (:func:`_contracting_runs`), the same as running it on gives.

Units do not matter: the roots are computed with the variable ȳ scaled by a power of two that
balances the polynomial's extreme coefficients (degree >= 4: each group of roots of similar size in
its own scale, read off the Newton polygon), so no degree is dropped and no root is judged by an
absolute threshold; every tolerance is relative, and a rational denominator counts as vanishing
below one relative threshold (``DENOMINATOR_RTOL``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache
from typing import ClassVar, Sequence

import numpy as np

from ..core._simulation_kernels import encode, kernel_array
from ._equilibrium_kernels import (
    DIVERGED,
    NET,
    NOT_SETTLED,
    POLY,
    REACHED,
    SKIPPED,
    ROOT_EPS,
    candidate_linearisations,
    merge_multiple_roots,
    real_roots_upto_cubic_sized,
    schur_stable_rows,
    settle_candidates,
    settle_runs,
)
from ..core._terms import Structure, Term, structure_of
from ..core._validation import (Relocked, as_1d_finite, check_bool, check_fields, check_per_point, check_real,
                                check_theta, locked, real_array)
from ..core._reprs import LISTED, exact_text, point_texts, short_repr
from ._linearisation import (characteristic_roots, derivative_map, grid_coefficients, static_gains, static_powers,
                             split_power, static_theta_gradient_of)

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
    "denominator_vanishes",
    "vanishing_denominator",
    "static_coefficients",
    "real_roots",
    "stable_mask",
    "schur_stable",
    "spectral_radius",
    "Reached",
    "reached_equilibria",
    "settle",
    "static_theta_gradient",
    "checked_model",
    "several_stable",
    "folded_equilibria",
    "equilibria_at_levels",
    "multiple_root",
    "continuum",
    "CONTINUUM_WHY",
    "point_phrases",
    "DENOMINATOR_RTOL",
    "SETTLE_STEPS",
    "SETTLE_TAUS",
    "SETTLE_MAX_STEPS",
    "SETTLE_RTOL",
    "POLY",
    "NET",
]

#: A rational static function's denominator 1 − Σy − Σyu ū − … (dimensionless) counts as vanishing
#: when its magnitude is at most this fraction of the sum of the magnitudes of its terms (the
#: static gain would exceed 10⁹ times the numerator's): the static function does not exist there.
DENOMINATOR_RTOL = 1e-9
#: Step budget of a settling run (:func:`settle`) ...
SETTLE_STEPS = 20000
#: ... raised, for a run still unsettled after it, to SETTLE_TAUS time constants −1/ln ρ of the
#: slowest stable candidate it may be heading for (ρ the spectral radius of the recursion
#: linearised there), so that a slow plant sampled fast is judged as it is sampled slowly ...
SETTLE_TAUS = 50
#: ... when that is at most this many steps: a run heading for a time constant beyond
#: SETTLE_MAX_STEPS / SETTLE_TAUS = 2·10⁵ samples cannot be judged at a bearable cost (a run's cost
#: grows with its budget; near-integrators a fit tries would pay it), and counts as not settled.
SETTLE_MAX_STEPS = 10_000_000
#: A settling run has reached a stable equilibrium ȳ_e once its last L outputs lie within
#: SETTLE_RTOL · min(max(|ȳ_e|, |y0|), distance to the nearest other equilibrium) of it ...
SETTLE_RTOL = 1e-6
#: ... or once it lies within 1000 times that distance of it, its last L increments are below
#: STALL_RTOL · max(|y|, |y0|), and Newton's method on eq. (5) from there lands on it (a slow approach);
#: a run given the longer budget also once its distance to it shrinks at its own rate (the geometric
#: test of :func:`graybox.static._equilibrium_kernels.settle_runs`: a slow mode near −1, whose
#: increments never vanish, is otherwise run until it has decayed to the tolerance).
STALL_RTOL = 1e-7
#: A root of a static polynomial of degree >= 4 (companion eigenvalues) counts as real when its
#: imaginary part is at most this fraction of its modulus.
IMAG_RTOL = 1e-7

_SUP = str.maketrans("0123456789", "⁰¹²³⁴⁵⁶⁷⁸⁹")


def cluster_key(term: Term) -> tuple[int, int]:
    """(power of y, power of the input) of a process term of a single-input model: its cluster Ω_{y^p u^m}.

    The input may have any name; for several inputs see :func:`graybox.static._surface_analysis.surface_cluster_map`.
    """
    if term.is_noise:
        raise ValueError(f"noise term {term} has no cluster")
    return term.power_of("y"), term.input_power


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


def ascii_cluster_name(name: object, *, single_input: bool) -> object:
    """A cluster name written in ASCII (``"Syu^2"``, ``"S0"``) in the paper's form (``"Σyu²"``, ``"Σ0"``).

    With one input a digit after ``y`` or ``u`` is a power (``"Su2"`` is Σu²); with several the
    inputs' names may end in digits (u1), so only ``^k`` is a power. The constant cluster ``Σ0``
    keeps its digit. Anything that is not such a string is returned as it is.
    """
    if not isinstance(name, str) or not name.startswith(("S", "Σ")):
        return name
    body = name[1:]
    if body == "0":
        return "Σ0"
    sup = (lambda m: m.group(1) + m.group(2).translate(_SUP))
    body = re.sub(r"([yu])\^?(\d+)", sup, body) if single_input else re.sub(r"()\^(\d+)", sup, body)
    return "Σ" + body


@dataclass(frozen=True, eq=False)
class ClusterMap(Relocked):
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
            return key_index(self.keys, self.names, name_or_key, "(p, m)")
        names = self.names
        # every printed name is accepted as it is; ASCII ("Syu^2", "Su2") is read as the paper's form
        name = name_or_key if name_or_key in names else ascii_cluster_name(name_or_key, single_input=True)
        if name not in names:
            raise ValueError(f"no cluster {name_or_key!r} in this structure; it has {names}")
        return names.index(name)

    @property
    def max_y_power(self) -> int:
        """Largest output power over the clusters."""
        return max((p for p, _ in self.keys), default=0)

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape


def key_index(keys: tuple, names: list[str], key: tuple, form: str) -> int:
    """Row of the cluster ``key`` among ``keys``, or ``ValueError`` naming it and the clusters there are."""
    if key not in keys:
        raise ValueError(f"no cluster with key {key!r} (powers {form}) in this structure; it has "
                         + ", ".join(f"{n} {k}" for n, k in zip(names, keys)))
    return keys.index(key)


def cluster_map(structure: Structure) -> ClusterMap:
    """Build the ``ClusterMap`` of the process terms of ``structure`` (cached: it is immutable).

    Single-input structures only (a structure with several inputs has a static *surface*:
    :func:`graybox.surface_cluster_map`); ``ValueError`` otherwise. A
    sequence of terms is read as a Structure.

    Parameters
    ----------
    structure : Structure or sequence of terms
        Process terms, grouped into clusters Σ_{y^p u^q} (a noise term has none: ``ValueError``; a Model's
        :meth:`~graybox.Model.clusters` passes its process part).

    Returns
    -------
    ClusterMap
    """
    return _cluster_map(structure_of(structure))


@lru_cache(maxsize=256)
def _cluster_map(structure: Structure) -> ClusterMap:
    if len(structure.input_names) > 1:
        raise ValueError(f"the structure has {len(structure.input_names)} inputs {structure.input_names}: its static function "
                         "is a surface (use the surface functions, e.g. Model.static_curve with ū of shape (M, m))")
    return ClusterMap(*cluster_membership([cluster_key(t) for t in structure]))


def cluster_membership(keys: list[tuple[int, ...]]) -> tuple[tuple[tuple[int, ...], ...], np.ndarray]:
    """The distinct cluster keys, sorted, and the read-only 0/1 map R (clusters × terms) with
    R[i, j] = 1 when term j (of key ``keys[j]``) belongs to cluster i."""
    uniq = tuple(sorted(set(keys)))
    R = np.zeros((len(uniq), len(keys)))
    for j, k in enumerate(keys):
        R[uniq.index(k), j] = 1.0
    return uniq, locked(R)  # shared by every caller (lru_cache): nobody may make it writeable


# -- the static polynomial and its real roots ----------------------------------------------------
def static_coefficients(structure: Structure, thetas: np.ndarray, ubar: np.ndarray) -> np.ndarray:
    """Ascending coefficients of F(ȳ) = Σ_p c_p ȳ^p of eq. (5) for many members and points.

    Parameters
    ----------
    structure : Structure
    thetas : ndarray, shape (P, n_terms)
    ubar : ndarray, shape (M,)

    Returns
    -------
    ndarray, shape (D + 1, P, M)
        D = max(largest power of y, 1); c_1 includes the −ȳ of eq. (5).
    """
    return _static_terms(structure, thetas, ubar)[0]


def _static_terms(structure: Structure, thetas: np.ndarray, ubar: np.ndarray, *, common: bool = False
                  ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`static_coefficients` and, alike, the sum of the magnitudes of the terms each is the sum of.

    ``common``: each (member, level)'s coefficients over one power of two where one would leave the float range
    (:func:`_cluster_terms`), which moves no root; the coefficients as they are otherwise."""
    cm = cluster_map(structure)
    th = np.atleast_2d(np.asarray(thetas, float))
    ub = np.asarray(ubar, float)
    with np.errstate(all="ignore"):  # a surface's folded θ_t ū^a beyond the float range (inf · 0 in the sums): no root
        sig = th @ cm.R.T
    D = max(cm.max_y_power, 1)
    coef = np.zeros((D + 1, th.shape[0], ub.size))
    size = np.zeros_like(coef)
    terms, shift = _cluster_terms(cm.keys, sig, ub[None, :], common)
    with np.errstate(all="ignore"):
        for p, term in terms:
            coef[p] += term
            size[p] += np.abs(term)
    one = np.ldexp(1.0, -shift)  # the −ȳ of eq. (5), over the same power of two
    coef[1] -= one
    size[1] += one
    return coef, size


def _cluster_terms(keys: Sequence[tuple[int, int]], sig: np.ndarray, ub: np.ndarray, common: bool
                   ) -> tuple[list[tuple[int, np.ndarray]], np.ndarray]:
    """Each cluster's σ ū^m (power p of y, the term), taken in mantissas and powers of two so that a product in the
    float range stays in it where ū^m alone is not (1e-300 · 1e200²); ``sig`` (..., C), ``ub`` broadcasting against
    ``sig[..., c, None]``. With ``common``, where a term's power of two passes 2^1000 every term of that (member,
    level) is read over 2^(top − 1000), the shift returned (0 elsewhere, the terms bit for bit as without): a
    coefficient beyond the float range (σ_u ū = 1e309) whose equation has its root inside it (over σ_yu ū = 1e298)."""
    with np.errstate(all="ignore"):  # a folded θ of inf at ū = 0: NaN, no float root of that level
        parts = [(p, *split_power(sig[..., c, None], ub, m)) for c, (p, m) in enumerate(keys)]
    shape = np.broadcast_shapes(sig[..., 0, None].shape, np.shape(ub))
    shift = np.zeros(shape, dtype=np.int64)
    if common and parts:
        top = np.max([np.where((mant != 0) & np.isfinite(mant), ex, 0) for _, mant, ex in parts], axis=0)
        shift = np.where(top > 1000, top - 1000, 0).astype(np.int64)
    with np.errstate(all="ignore"):  # a term beyond the float range even so: inf, no float root of that level
        return [(p, np.ldexp(mant, ex - shift)) for p, mant, ex in parts], shift


def continuum(structure: Structure, thetas: np.ndarray, ubar: np.ndarray) -> np.ndarray:
    """Where every ȳ is an equilibrium, shape (P, M): each coefficient of eq. (5) vanishes, to
    :data:`DENOMINATOR_RTOL` of the terms it sums (units-free), so the static equation holds for every output.

    An integrator y(k) = y(k−1) + a (u(k−1) − u0) at ū = u0 is the case: ȳ is not set by ū, the output
    stays where it starts (for a rational structure, numerator and denominator of eq. (6) both vanish).
    ``thetas`` (P, n_terms), ``ubar`` (M,).
    """
    coef, size = _static_terms(structure, thetas, ubar, common=True)
    return np.all(np.abs(coef) <= DENOMINATOR_RTOL * size, axis=0)


def _root_groups(c: np.ndarray) -> list[tuple[int, int, int]]:
    """Groups of roots of Σ c_k x^k of similar magnitude: (log2 of the scale, an integer, k1, k2) for each.

    The upper convex hull of the points (k, log2|c_k|) (the Newton polygon) has one edge per
    group: the edge from k1 to k2 carries k2 − k1 roots of magnitude near 2^(−slope), the roots of
    Σ_{k1 ≤ k ≤ k2} c_k x^(k−k1) up to a relative error of the order of the ratio to the next
    group's scale. Edges whose scales are less than 2^10 apart form one group. One polynomial's own steps, as
    fast as the ones that solve one or two (:func:`_root_groups_rows` takes the same steps on many rows at once).
    """
    pts = [(k, float(np.log2(abs(v)))) for k, v in enumerate(c) if v != 0]
    hull: list[tuple[int, float]] = []
    for p in pts:
        while len(hull) >= 2 and ((hull[-1][1] - hull[-2][1]) * (p[0] - hull[-2][0])
                                  <= (p[1] - hull[-2][1]) * (hull[-1][0] - hull[-2][0])):
            hull.pop()
        hull.append(p)
    groups: list[list[float]] = []  # [log2 scale · count, k1, k2]
    for (k1, v1), (k2, v2) in zip(hull, hull[1:]):
        e = (v1 - v2) / (k2 - k1)
        if groups and e - groups[-1][0] / (groups[-1][2] - groups[-1][1]) < 10:
            groups[-1][0] += e * (k2 - k1)
            groups[-1][2] = k2
        else:
            groups.append([e * (k2 - k1), k1, k2])
    return [(int(np.round(w / (k2 - k1))), int(k1), int(k2)) for w, k1, k2 in groups]


def _roots_one(c: np.ndarray) -> np.ndarray:
    """Every root (complex) of Σ c_k x^k: group by group in each group's scale, then Newton on the whole."""
    z0 = [0.0] * int(np.argmax(c != 0))  # x^lo divides the polynomial
    z = []
    for e, k1, k2 in _root_groups(c):
        tau = np.ldexp(1.0, e)
        if not 0 < tau < np.inf:
            continue  # roots of a scale beyond the float range: no float root to find among them
        cs = np.ldexp(c[k1:k2 + 1], e * np.arange(k2 - k1 + 1))  # exact (tau ** k may leave the range, cs not)
        p = cs[::-1] / np.max(np.abs(cs))
        if np.all(np.isfinite(p)):
            z.extend((tau * np.roots(p)).tolist())
    z = _newton_polish(np.array(z, dtype=complex)[None, :], c[None, :])[0]
    return np.concatenate([np.array(z0, dtype=complex), z])


#: Halvings of a Newton step that does not reduce |F| (:func:`_newton_polish`) before the root is left where it is.
_HALVINGS = 8


def _newton_polish(z: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Roots of whole polynomials from the starts ``z`` (K, D) complex (NaN: none) of the rows of ``c`` (K, n):
    simultaneous steps (:func:`_aberth`), then Newton steps, each kept only where it reduces |F|, halved up to
    :data:`_HALVINGS` times where it does not.

    A start on the convex side of a root far from its group's scale (−c5/c6 ≈ 1.44e5 for the root 1.6e5 of a
    degree-6 F) overshoots with a full step to a larger |F|; refused outright, it left the root unpolished and then
    dropped as no root. Half of it lands nearer, and the steps after it converge.
    """
    dc = c[:, 1:] * np.arange(1, c.shape[1])
    with np.errstate(all="ignore"):
        z = _aberth(z, c, dc)
        f = _polyval_rows(z, c)
        for _ in range(30):
            df = _polyval_rows(z, dc)
            step = np.where(df != 0, f / np.where(df != 0, df, 1.0), 0.0)
            todo = np.isfinite(step) & (step != 0)
            moved = np.zeros(z.shape, bool)
            for h in range(_HALVINGS + 1):
                if h == 1:  # a refused step of the root's own rounding is no overshoot: it is not halved
                    todo &= np.abs(step) > 2 * 4 * np.finfo(float).eps * np.abs(z)
                rows, cols = np.nonzero(todo)
                if rows.size == 0:
                    break
                zn = z[rows, cols] - step[rows, cols]
                fn = _polyval_rows(zn[:, None], c[rows])[:, 0]
                better = np.abs(fn) < np.abs(f[rows, cols])
                z[rows[better], cols[better]] = zn[better]
                f[rows[better], cols[better]] = fn[better]
                moved[rows[better], cols[better]] = True
                todo[rows[better], cols[better]] = False
                step = step / 2
            if not moved.any():
                break
    return z


#: Most simultaneous (Ehrlich–Aberth) steps of :func:`_aberth`.
_ABERTH_STEPS = 50


def _aberth(z: np.ndarray, c: np.ndarray, dc: np.ndarray) -> np.ndarray:
    """Ehrlich–Aberth steps on the starting roots ``z`` (K, D) complex (NaN: none) of the rows of ``c`` (K, n), ``dc``
    their derivatives' coefficients: each root's Newton step corrected by its distance to the others (those of ``z``
    and the x^lo factor's zeros), so two starts of one group cannot both settle on one root and leave another unfound
    (Newton alone did: a degree-6 F with roots near −8.6e5 and −8.1e5 gave −8.1e5 twice). Where the steps leave |F|
    no smaller than at the start (no convergence), the start is kept, for the guarded Newton steps after it.
    """
    lo = np.argmax(c != 0, axis=1).astype(float)[:, None]  # x^lo divides the polynomial: lo roots at 0
    live = np.isfinite(z)
    z0 = z.copy()
    # a real polynomial's steps keep a conjugate pair conjugate, so a pair started off two close real roots could
    # never split onto them: a small turn of every start breaks the symmetry (the steps bring real roots back)
    z = z * (1.0 + 1e-3j)
    D = z.shape[1]
    other = ~np.eye(D, dtype=bool)[None]
    eps = np.finfo(float).eps
    # a row stops once its own steps vanish, whatever the others do: a polynomial solved among many gets the roots
    # it gets alone (an operating curve's levels solved together or one by one)
    rows = np.flatnonzero(live.any(axis=1))
    with np.errstate(all="ignore"):
        for _ in range(_ABERTH_STEPS):
            if rows.size == 0:
                break
            zr, lv = z[rows], live[rows]
            N = _polyval_rows(zr, c[rows]) / _polyval_rows(zr, dc[rows])
            pair = other & lv[:, :, None] & lv[:, None, :]
            S = np.where(pair, 1.0 / np.where(pair, zr[:, :, None] - zr[:, None, :], 1.0), 0.0).sum(axis=2)
            S = S + np.where(lo[rows] > 0, lo[rows] / zr, 0.0)
            w = N / (1.0 - N * S)
            ok = lv & np.isfinite(w)
            zr = np.where(ok, zr - np.where(ok, w, 0.0), zr)
            z[rows] = zr
            rows = rows[np.any(ok & (np.abs(w) > 4 * eps * np.abs(zr)), axis=1)]
        # kept only where |F| fell (an F beyond the float range at both, a start left turned, is no fall)
        better = np.isfinite(z) & (np.abs(_polyval_rows(z, c)) < np.abs(_polyval_rows(z0, c)))
    return np.where(live & better, z, z0)


def _real_roots_companion(coef: np.ndarray, sizes: np.ndarray | None = None) -> np.ndarray:
    """Real roots (sorted, NaN-padded) of ascending polynomials of degree D >= 4, shape (P, M, D).

    Companion-matrix eigenvalues (numpy.roots), computed group by group in the scale of each group
    of roots (the edges of the Newton polygon of the coefficients, scales rounded to powers of
    two), so roots of very different magnitudes all start accurate and a change of units only
    rescales them; Newton steps on the whole polynomial finish them, and a real root is kept
    only if its backward error is small. ``sizes`` (as ``coef``; default |coef|): the sizes of the terms each
    coefficient sums, as :func:`~graybox.static._equilibrium_kernels.real_roots_upto_cubic_sized` takes them: a
    complex pair x ± iy whose F(x) is within what they leave uncertain (``ROOT_EPS`` eps of Σ sizes_p |x|^p) is
    the double root x that rounding pushed off the real axis (listed twice, read as one fold by
    :func:`~graybox.static._equilibrium_kernels.merge_multiple_roots`).

    Every polynomial at once (:func:`_roots_batch`: the companion matrices of each kind of group stacked through
    one ``numpy.linalg.eigvals``, the Newton steps on all of them together); what :func:`_real_roots_row` finds one
    polynomial at a time, which takes the few whose scaled coefficients leave the float range.
    """
    D = coef.shape[0] - 1
    P, M = coef.shape[1:]
    c = np.moveaxis(coef, 0, -1).reshape(-1, D + 1)
    a = c if sizes is None else np.maximum(np.abs(np.moveaxis(sizes, 0, -1).reshape(-1, D + 1)), np.abs(c))
    out = np.full((c.shape[0], D), np.nan)
    rows = np.flatnonzero(np.all(np.isfinite(c), axis=1) & np.any(c != 0, axis=1))
    if rows.size < _BATCH_FROM:  # a point or two (equilibria at one ū): the batch's set-up would cost more
        for k in rows:
            out[k] = _real_roots_row(c[k], a[k], D)
    elif rows.size:
        z, alone = _roots_batch(c[rows])
        out[rows] = _real_of(z, c[rows], a[rows], D)
        for k in rows[alone]:
            out[k] = _real_roots_row(c[k], a[k], D)
    return out.reshape(P, M, D)


#: Polynomials from which :func:`_real_roots_companion` solves them together (fewer: one at a time, as fast).
_BATCH_FROM = 4


def _real_roots_row(ck: np.ndarray, ak: np.ndarray, D: int) -> np.ndarray:
    """:func:`_real_roots_companion` of one polynomial (finite coefficients, not all 0), shape (D,)."""
    with np.errstate(all="ignore"):
        return _real_of(_roots_one(ck)[None, :], ck[None, :], ak[None, :], D)[0]


def _polyval_rows(x: np.ndarray, c: np.ndarray) -> np.ndarray:
    """numpy's ``polyval(x[i], c[i])`` for every row i at once (its Horner steps, so the same numbers)."""
    v = c[:, -1:] + x * 0
    for i in range(2, c.shape[1] + 1):
        v = c[:, -i:c.shape[1] - i + 1] + v * x
    return v


def _real_of(z: np.ndarray, c: np.ndarray, a: np.ndarray, D: int) -> np.ndarray:
    """The real roots among the roots ``z`` (K, n; NaN: none) of the rows of ``c``, sorted, NaN-padded to D: the
    real ones whose backward error is small, and twice the real part of each complex pair that is a double root to
    the coefficients' uncertainty (``a``, their terms' sizes)."""
    powers = np.arange(c.shape[1])
    eps = np.finfo(float).eps
    with np.errstate(all="ignore"):
        live = ~np.isnan(z)
        real = live & (np.abs(z.imag) <= IMAG_RTOL * np.abs(z))
        x = np.where(real, z.real, np.nan)
        f = _polyval_rows(x, c)
        size = np.abs(x)[..., None] ** powers @ np.abs(c)[:, :, None]
        x = np.where(np.isfinite(x) & (np.abs(f) <= 1e-8 * size[..., 0]), x, np.nan)
        # each root of a complex pair: its real part, where F is within the coefficients' uncertainty there (a double
        # root that rounding of a cancelling coefficient split into the pair); the two of a pair are taken one by one,
        # not one of them twice, as the simultaneous steps leave a pair near the axis nearly, not exactly, conjugate
        xp = np.where(live & ~real, z.real, np.nan)
        fp = np.abs(_polyval_rows(xp, c))
        eta = ROOT_EPS * eps * (np.abs(xp)[..., None] ** powers @ np.abs(a)[:, :, None])[..., 0]
        xp = np.where(np.isfinite(xp) & np.isfinite(eta) & (fp <= eta), xp, np.nan)
        x = np.sort(np.concatenate([x, xp], axis=1), axis=1)
    out = np.full((c.shape[0], D), np.nan)
    n = min(D, x.shape[1])
    out[:, :n] = x[:, :n]
    return out


@np.errstate(all="ignore")  # log2(0) = -inf at the zero coefficients, which take no part
def _root_groups_rows(c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_root_groups` of every row of ``c`` (K, D + 1) at once: the scales' log2 (integers, as floats), k1,
    k2, shape (K, D) each (the groups of row i first, in order), and each row's number of groups."""
    K, n = c.shape
    lv = np.log2(np.abs(c))
    # the upper convex hull of (k, log2|c_k|) over the nonzero c_k, by the same steps as _root_groups'
    hk = np.zeros((K, n), int)
    hv = np.zeros((K, n))
    h = np.zeros(K, int)
    r = np.arange(K)
    for k in range(n):
        on = c[:, k] != 0
        while True:
            two = on & (h >= 2)
            i1, i2 = np.maximum(h - 1, 0), np.maximum(h - 2, 0)
            pop = two & ((hv[r, i1] - hv[r, i2]) * (k - hk[r, i2]) <= (lv[:, k] - hv[r, i2]) * (hk[r, i1] - hk[r, i2]))
            if not pop.any():
                break
            h = h - pop
        hk[on, h[on]] = k
        hv[on, h[on]] = lv[on, k]
        h = h + on
    gw = np.zeros((K, n))
    g1 = np.zeros((K, n), int)
    g2 = np.zeros((K, n), int)
    ng = np.zeros(K, int)
    for j in range(n - 1):  # the hull's edge j, where the row has one
        has = h >= j + 2
        k1, k2 = hk[:, j], hk[:, min(j + 1, n - 1)]
        v1, v2 = hv[:, j], hv[:, min(j + 1, n - 1)]
        e = (v1 - v2) / (k2 - k1)
        last = np.maximum(ng - 1, 0)
        join = has & (ng > 0) & (e - gw[r, last] / (g2[r, last] - g1[r, last]) < 10)
        new = has & ~join
        gw[r[join], last[join]] += (e * (k2 - k1))[join]
        g2[r[join], last[join]] = k2[join]
        gw[r[new], ng[new]] = (e * (k2 - k1))[new]
        g1[r[new], ng[new]] = k1[new]
        g2[r[new], ng[new]] = k2[new]
        ng = ng + new
    return np.round(gw / np.where(g2 > g1, g2 - g1, 1)), g1, g2, ng


def _roots_batch(c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_roots_one` of every row of ``c`` (K, D + 1; finite, not all 0): the roots, shape (K, D) complex
    (NaN past a row's own), and the rows left to :func:`_roots_one` (a scaled coefficient outside the float
    range: numpy.roots would drop it)."""
    K, n = c.shape
    D = n - 1
    ex, g1, g2, ng = _root_groups_rows(c)
    z = np.full((K, D), np.nan + 0j)
    fill = np.zeros(K, int)
    alone = np.zeros(K, bool)
    for j in range(int(ng.max(initial=0))):
        for k1, k2 in {(int(p), int(q)) for p, q, g in zip(g1[:, j], g2[:, j], ng) if g > j}:
            rows = np.flatnonzero((ng > j) & (g1[:, j] == k1) & (g2[:, j] == k2))
            e = ex[rows, j]
            with np.errstate(all="ignore"):  # a scale beyond the float range (0 or inf): the row goes alone, below
                t = np.ldexp(1.0, e.astype(int))
                # exact, as in _roots_one (t ** k may leave the float range where the scaled coefficients do not)
                cs = np.ldexp(c[rows, k1:k2 + 1], e.astype(int)[:, None] * np.arange(k2 - k1 + 1))
                p = cs[:, ::-1] / np.max(np.abs(cs), axis=1, keepdims=True)
                top = -p[:, 1:] / p[:, :1]
            ok = (np.all(np.isfinite(p), axis=1) & (p[:, 0] != 0) & (p[:, -1] != 0) & np.isfinite(t) & (t != 0)
                  & np.all(np.isfinite(top), axis=1))
            alone[rows[~ok]] = True
            rows, top, t = rows[ok], top[ok], t[ok]
            m = k2 - k1
            A = np.zeros((rows.size, m, m))
            A[:, 1:, :-1] = np.eye(m - 1)
            A[:, 0, :] = top
            w = np.asarray(np.linalg.eigvals(A), complex)
            with np.errstate(all="ignore"):
                z[rows[:, None], fill[rows, None] + np.arange(m)] = t[:, None] * w
            fill[rows] += m
    z = _newton_polish(z, c)
    lo = np.argmax(c != 0, axis=1)  # x^lo divides the polynomial: lo roots at 0
    for k in np.flatnonzero(lo):
        z[k, fill[k]:fill[k] + lo[k]] = 0.0
    return z, alone


def real_roots(structure: Structure, thetas: np.ndarray, ubar: np.ndarray) -> np.ndarray:
    """Every real root of eq. (5) for many members and points: the candidate equilibria.

    Degree ≤ 3 (every quadratic and cubic structure): closed forms, compiled
    (:func:`graybox.static._equilibrium_kernels.real_roots_upto_cubic`). Degree >= 4: companion-matrix
    eigenvalues. Both balance the variable first, so the result does not depend on units. A multiple
    root (a fold; to rounding: :func:`graybox.static._equilibrium_kernels.merge_multiple_roots`) is listed once.

    Parameters
    ----------
    structure : Structure
    thetas : ndarray, shape (P, n_terms)
    ubar : ndarray, shape (M,)

    Returns
    -------
    ndarray, shape (P, M, D)
        Real roots in ascending order, NaN-padded (D = max(largest power of y, 1)).
    """
    return _roots_and_folds(structure, thetas, ubar)[0]


def _roots_and_folds(structure: Structure, thetas: np.ndarray, ubar: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`real_roots`, and which of them are multiple roots (folds of the static curve), shape (P, M, D) each."""
    coef, size = _static_terms(structure, thetas, ubar, common=True)
    if coef.shape[0] <= 4:
        roots = real_roots_upto_cubic_sized(coef, np.ascontiguousarray(size))
        # the closed forms balance the extreme coefficients by one scale, which leaves the float range where the
        # roots' magnitudes span more than it (−1e11 beside 1e490): every root was lost, the one in range too; those
        # polynomials go by the groups of the companion route, each in its own scale
        wide = _unbalanced(coef)
        if wide.any():
            roots[wide] = _real_roots_companion(coef[:, wide][:, None], size[:, wide][:, None])[0]
    else:
        roots = _real_roots_companion(coef, size)
    if roots.shape[-1] < 2:  # a linear equation: one simple root
        return roots, np.zeros(roots.shape, dtype=bool)
    return merge_multiple_roots(np.ascontiguousarray(coef), np.ascontiguousarray(roots), np.ascontiguousarray(size))


def _unbalanced(coef: np.ndarray) -> np.ndarray:
    """Where one power of two balancing a polynomial's first and last non-zero coefficients (the closed forms'
    scale) takes a coefficient c_k s^k out of the float range (with a margin), shape (P, M); ``coef`` (D + 1, P, M)."""
    k = np.arange(coef.shape[0])[:, None, None]
    with np.errstate(all="ignore"):
        L = np.log2(np.abs(coef))  # −inf at a zero coefficient
        nz = np.isfinite(L)
        lo = np.argmax(nz, axis=0)
        hi = coef.shape[0] - 1 - np.argmax(nz[::-1], axis=0)
        Llo = np.take_along_axis(L, lo[None], axis=0)[0]
        Lhi = np.take_along_axis(L, hi[None], axis=0)[0]
        e = np.where(hi > lo, (Llo - Lhi) / np.where(hi > lo, hi - lo, 1), 0.0)
        span = np.where(nz, L + k * np.round(e), 0.0)
    return (coef.shape[0] > 2) & np.all(np.isfinite(coef), axis=0) & np.any(np.abs(span) > 1000, axis=0)


def _linear_coefficients(structure: Structure, theta: np.ndarray, ybar: float, ubar: float) -> np.ndarray:
    """a_i = ∂f/∂y(k-i) at the equilibrium, i = 1..L (L = largest output lag): one row of the derivative map."""
    return grid_coefficients(structure, np.asarray(theta, float)[None, :], np.array([float(ubar)]),
                             np.array([[float(ybar)]]))[0, 0]


# -- stability: one test ---------------------------------------------------------------------------
def schur_stable(a: np.ndarray) -> np.ndarray:
    """Is the linear recursion y(k) = Σ_l a_l y(k-l) asymptotically stable? The one stability test.

    The Schur–Cohn step-down recursion on z^L − a_1 z^(L−1) − … − a_L (every root strictly inside
    the unit circle), compiled; a root at z = 1 to rounding (1 − Σ a_l within the sum's rounding
    error, as at a fold of the static curve: :func:`~graybox.static._equilibrium_kernels.unit_pole`)
    is not inside. :func:`stable_mask` applies the same test to the linearisation
    of a polynomial model at its equilibria; the neural model uses this entry point.

    Parameters
    ----------
    a : array_like, shape (L,) or (K, L)
        Coefficients a_1 … a_L (dimensionless), one row per recursion.

    Returns
    -------
    bool or ndarray of bool, shape (K,)
    """
    arr = np.asarray(a, float)
    out = schur_stable_rows(kernel_array(np.atleast_2d(arr)))
    return bool(out[0]) if arr.ndim <= 1 else out


def stable_mask(structure: Structure, thetas: np.ndarray, ubar: np.ndarray, ybar: np.ndarray) -> np.ndarray:
    """Is each equilibrium (ū_j, ȳ_pj) of member p locally stable? Shape (P, M), batched.

    The linearised recursion at each equilibrium is tested by the compiled Schur–Cohn recursion
    (the test of :func:`schur_stable`): no eigenvalues are computed, which makes it cheap enough
    for every generation of a GA.

    Parameters
    ----------
    structure : Structure
    thetas : ndarray, shape (P, n_terms)
    ubar : ndarray, shape (M,)
    ybar : ndarray, shape (P, M)
        Equilibrium outputs (non-finite entries count as unstable).

    Returns
    -------
    ndarray of bool, shape (P, M)
    """
    yb = np.atleast_2d(np.asarray(ybar, float))
    if derivative_map(structure).Ly == 0:
        return np.isfinite(yb)
    fin = np.isfinite(yb)
    a = grid_coefficients(structure, thetas, np.asarray(ubar, float), np.where(fin, yb, 0.0))
    return schur_stable_rows(kernel_array(a.reshape(-1, a.shape[2]))).reshape(yb.shape) & fin


def _roots_stable(structure: Structure, thetas: np.ndarray, ubar: np.ndarray, roots: np.ndarray) -> np.ndarray:
    """:func:`stable_mask` of every root: roots (P, M, D) → (P, M, D), in one call."""
    P, M, D = roots.shape
    return stable_mask(structure, thetas, np.repeat(ubar, D), roots.reshape(P, M * D)).reshape(P, M, D)


def roots_and_stability(structure: Structure, thetas: np.ndarray, ubar: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`real_roots` (P, M, D) and their stability (P, M, D). A multiple root (a fold) is not stable: there
    Σ a_l = 1, a pole at z = 1, whatever rounding makes of Σ a_l."""
    roots, fold = _roots_and_folds(structure, thetas, ubar)
    return roots, _roots_stable(structure, thetas, ubar, roots) & ~fold


@dataclass(frozen=True)
class Equilibrium(Relocked):
    """A real steady state of a model at constant input.

    Attributes
    ----------
    ubar : float or tuple of float
        Input level (one per input with several inputs: a point of the static surface).
    ybar : float
        Output level.
    stable : bool
        True when the linearised recursion is asymptotically stable (every root strictly inside
        the unit circle, by the Schur–Cohn test of ``schur_stable``).
    spectral_radius : float
        Largest modulus of those roots (0 for a static model), for information.
    """

    ubar: float | tuple[float, ...]
    ybar: float
    stable: bool
    spectral_radius: float

    def __post_init__(self) -> None:
        check_fields(self)
        # what a hand-edited file could say and no model's equilibria are: a point at NaN, a level beyond the
        # floats (equilibria keeps the finite roots only), a negative or undefined modulus
        points = self.ubar if isinstance(self.ubar, tuple) else (self.ubar,)
        if not points:
            raise ValueError("Equilibrium: ubar needs one input level per input, got ()")
        for i, v in enumerate(points):
            check_real(v, "Equilibrium: ubar" + (f"[{i}]" if isinstance(self.ubar, tuple) else ""))
        check_real(self.ybar, "Equilibrium: ybar")
        if not self.spectral_radius >= 0.0:  # inf is said of a linearisation beyond the float range
            raise ValueError(f"Equilibrium: spectral_radius must be >= 0 (a modulus), got {self.spectral_radius!r}")
        # stable: every root strictly inside the unit circle, so the largest modulus is below 1 (to the rounding by
        # which the stability test and the roots, computed apart, may differ at the circle); a hand-edited file said
        # stable with a root at 1.5 or inf, or unstable with every root inside, and loaded as it said
        if self.stable and not self.spectral_radius <= 1.0 + _RADIUS_ROUNDING:
            raise ValueError(f"Equilibrium: stable, but spectral_radius {self.spectral_radius!r} puts a root outside "
                             "the unit circle")
        if not self.stable and self.spectral_radius < 1.0 - _RADIUS_ROUNDING:
            raise ValueError(f"Equilibrium: not stable, but spectral_radius {self.spectral_radius!r} puts every root "
                             "inside the unit circle")


#: How far the roots' largest modulus may lie across the unit circle from the stability test's verdict: the two are
#: computed apart, and numpy's roots of a root repeated m times are good to about eps^(1/m) (a triple root's 1.2e-5, a
#: fourfold one's 2.4e-4 at worst). Computed equilibria keep the two on one side (``verdict_radius``); files written
#: before that may not, and load.
_RADIUS_ROUNDING = 5e-4


def spectral_radius(a: np.ndarray) -> float:
    """Largest modulus of the roots of z^L − a_1 z^(L−1) − … − a_L (information; stability is
    decided by :func:`schur_stable`)."""
    a = np.asarray(a, float)
    if a.size == 0 or not np.any(a):
        return 0.0
    if not np.all(np.isfinite(a)):  # a derivative beyond the float range (an equilibrium far out): no root solver
        return float("inf")
    # characteristic polynomial z^L - a1 z^(L-1) - ... - aL
    return float(np.max(np.abs(np.roots(np.concatenate(([1.0], -a))))))


def verdict_radius(stable: bool, rho: float) -> float:
    """The spectral radius ``rho`` an :class:`Equilibrium` reports beside its stability verdict, held to the verdict's
    side of the unit circle: numpy's roots of an m-fold root are good to ~eps^(1/m) only (6e-6 for a triple root),
    so near the circle they may cross it where the Schur–Cohn test does not (a triple root at z = -(1 - 1e-5) was
    'not stable' with every root at 0.999993, and its Equilibrium refused). Not stable (a fold, a pole at z = 1 to
    rounding, a root outside): at least 1; stable: at most 1."""
    return min(rho, 1.0) if stable else max(rho, 1.0)


def equilibria(structure: Structure, theta: np.ndarray, ubar: float) -> list[Equilibrium]:
    """Every real equilibrium at constant input ``ubar``, sorted by ȳ, with its local stability.

    Parameters
    ----------
    structure : Structure
        Process terms.
    theta : ndarray, shape (n_terms,)
    ubar : float
        Constant input level (engineering units).

    Returns
    -------
    list of Equilibrium
        Empty when eq. (5) has no real root (or, for a rational structure, its denominator
        vanishes and its numerator does not).

    Raises
    ------
    ValueError
        When every ȳ is an equilibrium at ``ubar`` (``continuum``, e.g. an integrator at its balancing
        input): ȳ is not set by ū there.
    """
    structure, theta = checked_model(structure, theta)
    if len(structure.input_names) > 1:
        raise ValueError(f"the structure has {len(structure.input_names)} inputs {structure.input_names}: its equilibria lie on "
                         "a surface; use graybox.surface_equilibria(structure, theta, ū) with ū of shape (m,)")
    ub = check_real(ubar, "ubar (one input level)")
    refuse_continuum(structure, theta, ub, exact_text(ub))  # the level given: 10000.01 was said '10000'
    return folded_equilibria(structure, theta, ub)


def refuse_continuum(structure: Structure, theta: np.ndarray, ub: float, label: str) -> None:
    """``ValueError`` when every ȳ is an equilibrium at ``ub`` (:func:`continuum`): a list of equilibria cannot
    hold them (``label`` names the point)."""
    if continuum(structure, np.asarray(theta, float)[None, :], np.array([ub]))[0, 0]:
        raise ValueError(f"ū = {label}: {CONTINUUM_WHY}; equilibria lists isolated equilibria (for the local model "
                         "at an output level ȳ of your choice: local_model(model, ū, y0=ȳ))")


def multiple_root(structure: Structure, theta: np.ndarray, ub: float, ybar: float) -> bool:
    """Is ``ybar`` a multiple root of eq. (5) at ``ub`` (a fold: ∂F/∂ȳ = 0, so Σ a_l = 1 there), by the test
    :func:`real_roots` applies to its roots (:func:`~graybox.static._equilibrium_kernels.merge_multiple_roots`)?
    A rational structure's eq. (6) is linear in ȳ: never. ``theta`` (n_terms,), ``ub`` and ``ybar`` scalars."""
    if is_rational(structure) or not np.isfinite(ybar):
        return False
    coef, size = _static_terms(structure, np.asarray(theta, float)[None, :], np.array([float(ub)]), common=True)
    roots = np.full((1, 1, coef.shape[0] - 1), np.nan)
    if roots.shape[-1] < 2:  # a linear equation: one simple root
        return False
    roots[0, 0, 0] = ybar
    return bool(merge_multiple_roots(np.ascontiguousarray(coef), roots, np.ascontiguousarray(size))[1][0, 0, 0])


def folded_equilibria(structure: Structure, theta: np.ndarray, ub: float) -> list[Equilibrium]:
    """:func:`equilibria` of checked arguments (a folded surface model's θ may exceed the float range)."""
    return equilibria_at_levels(structure, theta, np.array([ub]))[0]


def equilibria_at_levels(structure: Structure, theta: np.ndarray, ubar: np.ndarray) -> list[list[Equilibrium]]:
    """:func:`folded_equilibria` at each level of ``ubar`` (M,), the static equations of all of them solved together
    (an operating curve's); the caller refuses a level where every ȳ is an equilibrium (:func:`continuum`)."""
    th = np.asarray(theta, float)[None, :]
    ub = np.asarray(ubar, float)
    if is_rational(structure):
        ys = _rational_roots(structure, th, ub)[0][:, None]
        folds = np.zeros(ys.shape, dtype=bool)  # eq. (6) is linear in ȳ: one simple root
    else:
        ys, folds = (v[0] for v in _roots_and_folds(structure, th, ub))
    return [_level_equilibria(structure, th, float(u), yb, fold) for u, yb, fold in zip(ub, ys, folds)]


def _level_equilibria(structure: Structure, th: np.ndarray, ub: float, yb: np.ndarray, fold: np.ndarray
                      ) -> list[Equilibrium]:
    """The equilibria at one level ``ub`` from the roots ``yb`` of its static equation (NaN-padded) and which are
    multiple (``fold``)."""
    keep = np.isfinite(yb)
    yb, fold = yb[keep], fold[keep]
    if yb.size == 0:
        return []
    stable = stable_mask(structure, th, np.full(yb.size, ub), yb[None, :])[0] & ~fold
    # a fold's pole is at z = 1 (Σ a_l = 1), not stable: its modulus at least 1 whatever rounding made of it; so where
    # the a_l sum to 1 to rounding (unit_pole, the stability test's rule); and every radius on its verdict's side
    a = [_linear_coefficients(structure, th[0], float(y), ub) for y in yb]
    return [Equilibrium(ub, float(y), bool(s), verdict_radius(bool(s), spectral_radius(al)))
            for y, s, al in zip(yb, stable, a)]


# -- rational structures: eq. (6) --------------------------------------------------------------------
@lru_cache(maxsize=256)
def is_rational(structure: Structure) -> bool:
    """True when no term has y to a power above 1 (static function of eq. (6))."""
    return all(t.power_of("y") <= 1 for t in structure if not t.is_noise)


def _rational_terms(structure: Structure, thetas: np.ndarray, ubar: np.ndarray, *, common: bool = False):
    """Eq. (6)'s numerator, denominator and the magnitude of the denominator's terms; ``common``: each (member,
    level)'s three over one power of two where a term would leave the float range (as :func:`_static_terms`)."""
    cm = cluster_map(structure)
    th = np.asarray(thetas, dtype=float)
    with np.errstate(all="ignore"):  # as in _static_terms: a folded θ beyond the float range leaves no equilibrium
        sig = th @ cm.R.T  # (C,) or (P, C)
    ub = np.asarray(ubar, dtype=float)
    terms, shift = _cluster_terms(cm.keys, sig, ub, common)
    one = np.ldexp(1.0, -shift)
    num = np.zeros(sig.shape[:-1] + ub.shape)
    den = np.broadcast_to(one, num.shape).copy()
    size = den.copy()
    with np.errstate(all="ignore"):
        for p, term in terms:
            if p == 0:
                num += term
            else:
                den -= term
                size += np.abs(term)
    return num, den, size


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
    num, den, _ = _rational_terms(structure, thetas, ubar)
    return num, den


def denominator_vanishes(den: np.ndarray, size: np.ndarray) -> np.ndarray:
    """Does a rational static denominator vanish? |den| <= ``DENOMINATOR_RTOL`` · size.

    Parameters
    ----------
    den : ndarray
        1 − Σy − Σyu ū − … (dimensionless).
    size : ndarray
        1 + Σ |Σ_{y u^m} ū^m|: the magnitude of the terms it is the sum of.
    """
    return ~(np.abs(den) > DENOMINATOR_RTOL * size)


def vanishing_denominator(structure: Structure, theta: np.ndarray, ubar: np.ndarray) -> np.ndarray:
    """Where does the denominator of eq. (6) vanish (:func:`denominator_vanishes`)? Shape (M,).

    Parameters
    ----------
    structure : Structure
        A rational structure.
    theta : ndarray, shape (n_terms,)
    ubar : ndarray, shape (M,)
    """
    _, den, size = _rational_terms(structure, theta, np.asarray(ubar, float), common=True)
    return denominator_vanishes(den, size)


def _rational_roots(structure: Structure, thetas: np.ndarray, ubar: np.ndarray) -> np.ndarray:
    """Eq. (6) for many members, shape (P, M); NaN where the denominator vanishes."""
    num, den, size = _rational_terms(structure, np.atleast_2d(thetas), ubar, common=True)
    with np.errstate(all="ignore"):
        return np.where(denominator_vanishes(den, size), np.nan, num / den)


def rational_static_curve(structure: Structure, theta: np.ndarray, ubar: np.ndarray) -> np.ndarray:
    """Eq. (6): ȳ = (Σ0 + Σu ū + Σu² ū² + …) / (1 − Σy − Σyu ū − …), shape (M,).

    Raises ``ValueError`` when the structure is not rational or the denominator vanishes
    (:func:`denominator_vanishes`). Stability is not checked: this is the equilibrium, reached
    or not.
    """
    ub = np.atleast_1d(np.asarray(ubar, dtype=float))
    if not is_rational(structure):
        raise ValueError("structure has a term with y to a power above 1: its static function is not rational")
    num, den, size = _rational_terms(structure, theta, ub, common=True)
    bad = denominator_vanishes(den, size)
    if bad.any():
        # + 0.0: an input of -0.0 is said as the level it is, 0.0
        raise ValueError(f"static function undefined: denominator 1 − Σy − … vanishes at ū = "
                         f"{(ub[bad] + 0.0).tolist()}")
    return num / den


# -- the equilibrium reached -----------------------------------------------------------------------
NO_EQUILIBRIUM, NONE_STABLE, CONTINUUM = 1, 2, 5
#: Why a point has no equilibrium, in words: no real root of eq. (5), or (rational form) a vanishing
#: denominator whose numerator does not vanish (where it does too, every output is one: CONTINUUM). "Vanishing" is
#: the rule of DENOMINATOR_RTOL, not zero: y = (1 − 1e-10) y(k−1) + 1e-9 u(k−1) has ȳ = 10 ū in exact arithmetic,
#: but its denominator 1e-10 is below 1e-9 of its terms' size (2), so the rule counts it as none, and says so.
NO_EQUILIBRIUM_WHY = ("no equilibrium (the static equation has no real root within the float range, or its denominator "
                      f"vanishes: at most DENOMINATOR_RTOL = {DENOMINATOR_RTOL:g} of its terms' size, ȳ over 10⁹ "
                      "times its numerator)")
#: Why a point has every output as an equilibrium (:func:`continuum`), in words.
CONTINUUM_WHY = ("a continuum of equilibria: the static equation holds for every output level, so ȳ is not set by ū "
                 "(an integrator at its balancing input: the output stays where it starts, a marginally stable "
                 "equilibrium)")


@dataclass(frozen=True, eq=False)
class Reached:
    """Where free runs at constant input settle: the static outputs of many members at many points.

    Attributes
    ----------
    ubar : ndarray, shape (M,)
        Input levels.
    y0 : ndarray, shape (M,)
        The constant initial output of each point's run (usually the measured ȳ_i).
    ybar : ndarray, shape (P, M)
        The equilibrium each member's run settles on; NaN where it settles on none.
    status : ndarray of int8, shape (P, M)
        0 reached; 1 no equilibrium (eq. (5) has no real root, or a rational denominator
        vanishes); 2 no locally stable equilibrium; 3 the run diverged; 4 the run did not settle
        within the step budget (an oscillation, a limit cycle, an approach slower than
        ``SETTLE_MAX_STEPS`` / ``SETTLE_TAUS`` samples per time constant); 5 a continuum of
        equilibria (:func:`continuum`: every output is one, so ū sets no ȳ; none is asymptotically stable);
        6 not evaluated (asked with ``until_failure``: another point of the member is not reached).
    start_on : ndarray, shape (P, M), optional
        Where a run did not settle (status 4) because it starts on an unstable equilibrium (y0 one of the
        static equation's roots, to rounding): that equilibrium (output units), which a run begun on it need not
        leave; NaN elsewhere. None when not looked for.
    """

    ubar: np.ndarray
    y0: np.ndarray
    ybar: np.ndarray
    status: np.ndarray
    start_on: np.ndarray | None = None

    STATUS: ClassVar[tuple[str, ...]] = ("reached", "no equilibrium", "no stable equilibrium", "diverged",
                                         "did not settle", "continuum of equilibria", "not evaluated")
    #: The statuses an analysis asked without ``until_failure`` gives (every point evaluated).
    FULL_STATUS: ClassVar[tuple[str, ...]] = STATUS[:-1]

    @property
    def ok(self) -> np.ndarray:
        """(P, M) mask of the points where an equilibrium is reached."""
        return self.status == REACHED

    def explain(self, member: int = 0) -> list[str]:
        """One phrase per point member ``member`` does not reach, naming ū and the reason."""
        out = []
        points = point_texts(self.ubar)  # each point told apart from the others (10000.01 and 10000.02)
        for j in np.flatnonzero(self.status[member] != REACHED):
            y0 = float(self.y0[j])
            s = int(self.status[member, j])
            if s == NO_EQUILIBRIUM:
                why = NO_EQUILIBRIUM_WHY
            elif s == CONTINUUM:
                why = CONTINUUM_WHY
            elif s == NONE_STABLE:
                why = "no stable equilibrium"
            elif s == DIVERGED:
                why = f"the free run from y0 = {exact_text(y0)} diverged"  # as given: 10005.01 read '10005'
            elif s == SKIPPED:
                why = "not evaluated (another point is not reached)"
            elif self.start_on is not None and np.isfinite(self.start_on[member, j]):
                # no time constant is involved: the run sits on an equilibrium that repels, not on a slow approach
                why = (f"the free run from y0 = {exact_text(y0)} did not settle on a stable equilibrium: it starts on "
                       f"the unstable equilibrium ȳ = {exact_text(float(self.start_on[member, j]))} (to rounding), "
                       "which holds a run begun on it")
            else:
                why = (f"the free run from y0 = {exact_text(y0)} did not settle on a stable equilibrium within "
                       f"{SETTLE_STEPS} steps, nor within {SETTLE_TAUS} time constants of the slowest (one over "
                       f"{SETTLE_MAX_STEPS // SETTLE_TAUS} samples is not run)")
            out.append(f"ū = {points[j]}: {why}")
        return out

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape


def settle(kind: int, ip: np.ndarray, fp: np.ndarray, y0: np.ndarray, roots: np.ndarray, stable: np.ndarray,
           L: int, floor: float = 0.0, *, members: np.ndarray | None = None,
           failed: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The one "run until settled" routine: free runs at constant input, checked to have settled.

    Each pair k is run from the constant initial output ``y0[k]`` until its last L outputs lie
    within ``SETTLE_RTOL`` (relative; at most that fraction of the distance to the nearest other
    equilibrium) of one of its stable equilibria, or it creeps towards one so slowly that its
    increments vanish and Newton's method on the static equation lands on it; it is stopped as
    diverged (|y| beyond 10⁶ times the pair's scale) or as not settled after its step budget,
    ``SETTLE_STEPS`` or, for a run still unsettled then, ``SETTLE_TAUS`` time constants of its
    slowest stable equilibrium (:func:`settle_budget`), where it also ends once its distance to an
    equilibrium shrinks at that equilibrium's own rate (the geometric test); see
    :func:`graybox.static._equilibrium_kernels.settle_runs`, whose docstring gives ``kind``, ``ip``
    and ``fp``. Pairs with no stable equilibrium are not run: they settle on none; nor are polynomial runs
    run on past ``SETTLE_STEPS`` where they are proven to reach their nearest candidate within their budget
    (:func:`_contracting_runs`; without ``members``).

    Parameters
    ----------
    kind : {POLY, NET}
        A polynomial model with its input folded in, or a tanh network.
    ip : ndarray of int64
        Integer description of the recursion.
    fp : ndarray, shape (K, nf)
        Each pair's coefficients.
    y0 : ndarray, shape (K,)
        Constant initial outputs.
    roots : ndarray, shape (K, D)
        Each pair's equilibria (every real root of its static equation), NaN-padded.
    stable : ndarray of bool, shape (K, D)
        Which of them are locally stable.
    L : int
        Largest output lag of the recursion.
    floor : float
        Smallest output scale of the tolerances (0 for engineering units; 1 in normalised units).
    members : ndarray of int, shape (K,), optional
        Each pair's member. Given, a member's pairs are followed only until one of them is not reached:
        the others then end, or are not started, as 6 (not evaluated), for a caller to whom a member
        with one point not reached has failed whatever its others reach (J_SF). A member none of whose
        pairs fails gets exactly the runs and results it gets without ``members``.
    failed : ndarray of bool, shape (number of members,), optional
        Members that have failed already (at a point with no stable equilibrium, which is not run);
        with ``members``; updated in place.

    Returns
    -------
    ybar : ndarray, shape (K,)
        The equilibrium reached (NaN where none).
    status : ndarray of int8, shape (K,)
        As in :class:`Reached`: 0, 2 (no stable equilibrium), 3, 4 or (with ``members``) 6.
    """
    y0a = np.ascontiguousarray(y0, dtype=float)
    cand, ncand, tol, ntol = settle_candidates(np.ascontiguousarray(roots, dtype=float),
                                               np.ascontiguousarray(stable, dtype=np.bool_), y0a, float(floor),
                                               SETTLE_RTOL)
    run = ncand > 0
    ybar = np.full(y0a.shape, np.nan)
    status = np.full(y0a.shape, NONE_STABLE, dtype=np.int8)
    groups = None
    if members is not None:
        groups = np.ascontiguousarray(members, dtype=np.int64)
        if failed is None:
            failed = np.zeros(int(groups.max(initial=-1)) + 1, dtype=np.bool_)
        failed[groups[~run]] = True  # a pair with no stable equilibrium is not reached
    if run.any():
        sel = slice(None) if run.all() else run  # every pair runs: views, no copies
        ip = kernel_array(ip, np.int64)
        L = max(int(L), 1)
        grp = () if groups is None else (np.ascontiguousarray(groups[sel]), failed, False)
        with np.errstate(all="ignore"):
            ybar[sel], status[sel], last, left = settle_runs(
                int(kind), ip, np.ascontiguousarray(fp[sel], dtype=float), np.ascontiguousarray(y0a[sel]),
                np.ascontiguousarray(cand[sel]), ncand[sel], np.ascontiguousarray(tol[sel]),
                np.ascontiguousarray(ntol[sel]), L, float(floor), SETTLE_STEPS, _ONE_BUDGET, _NO_HISTORY, STALL_RTOL,
                _NO_RATES, *grp)
        if left:
            _settle_longer(int(kind), ip, fp, y0a, cand, ncand, tol, ntol, L, float(floor), run, ybar, status, last,
                           groups, failed)
    return ybar, status


def _settle_longer(kind: int, ip: np.ndarray, fp: np.ndarray, y0: np.ndarray, cand: np.ndarray, ncand: np.ndarray,
                   tol: np.ndarray, ntol: np.ndarray, L: int, floor: float, run: np.ndarray, ybar: np.ndarray,
                   status: np.ndarray, last: np.ndarray, groups: np.ndarray | None = None,
                   failed: np.ndarray | None = None) -> None:
    """Let the runs :func:`settle`'s first pass left unsettled go on for the budget their slowest candidate
    needs (:func:`settle_budget`), from where they are (``last``: the first pass's, indexed as the pairs
    it ran); one whose candidate is too slow to judge within SETTLE_MAX_STEPS stays not settled.
    These runs also end on the geometric test (an approach at the candidate's own rate; see
    :func:`graybox.static._equilibrium_kernels.settle_runs`). ``ybar`` and ``status`` are updated in place;
    with ``groups`` (each pair's member) the members in ``failed`` are not run on, as in :func:`settle`."""
    again = np.flatnonzero(status == NOT_SETTLED)
    budget, lograte = settle_budget(kind, ip, fp[again], cand[again], ncand[again], L)
    longer = (budget > SETTLE_STEPS) & (budget <= SETTLE_MAX_STEPS)
    grp = ()
    if groups is not None:
        failed[groups[again[~longer]]] = True  # not settled, and not run on: not reached
        skip = longer & failed[groups[again]]
        status[again[skip]] = SKIPPED
        longer &= ~skip
        grp = (np.ascontiguousarray(groups[again[longer]]), failed, True)
    if not longer.any():
        return
    sel = again[longer]
    hist = np.ascontiguousarray(last[np.searchsorted(np.flatnonzero(run), sel)])
    left = budget[longer] - SETTLE_STEPS
    lograte = lograte[longer]
    if kind == POLY and groups is None:
        # a run whose end is proven from where it is (a contraction onto its nearest root) is not run on
        known, root = _contracting_runs(ip, fp[sel], y0[sel], hist, cand[sel], ncand[sel], tol[sel], L, left)
        ybar[sel[known]] = root[known]
        status[sel[known]] = REACHED
        sel, hist, left, lograte = sel[~known], hist[~known], left[~known], lograte[~known]
        if not sel.size:
            return
    with np.errstate(all="ignore"):
        ybar[sel], status[sel], _, _ = settle_runs(
            kind, ip, np.ascontiguousarray(fp[sel], dtype=float), np.ascontiguousarray(y0[sel]),
            np.ascontiguousarray(cand[sel]), ncand[sel], np.ascontiguousarray(tol[sel]),
            np.ascontiguousarray(ntol[sel]), L, floor, 0, np.ascontiguousarray(left), np.ascontiguousarray(hist),
            STALL_RTOL, np.ascontiguousarray(lograte), *grp)


def _contracting_runs(ip: np.ndarray, fp: np.ndarray, y0: np.ndarray, hist: np.ndarray, cand: np.ndarray,
                      ncand: np.ndarray, tol: np.ndarray, L: int, steps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Which polynomial runs :func:`settle`'s first pass left unsettled reach their nearest candidate within
    ``steps`` (K,) more steps from where they are (``hist`` (K, L), their last L outputs, oldest first), proven
    without running them on; and that candidate. Other shapes as :func:`settle`'s; returns bool (K,), float (K,).

    About the candidate r nearest the last output the run's errors e(k) = y(k) − r obey
    e(k) = Σ_l a_l e(k−l) + h(e) + c: a the recursion linearised at r (companion matrix A), h the rest of the
    polynomial, c = F(r) plus one step's rounding (at most δ). In the coordinates z = W e of A's eigenvectors (W ≈
    V⁻¹; ‖W⁻¹‖ bounded through ‖I − W V‖) the state contracts by ρ = ‖W A W⁻¹‖ + ‖W e₁‖ S(R) ‖W⁻¹‖ per step while
    every output lies within R of r, S(R) bounding how far the partials move there. Proven where ρ < 1, the state
    (z₀ = W e of the last L errors) stays within R, its error after k steps, ‖W⁻¹‖ (ρ^k ‖z₀‖ + ‖W e₁‖ |c| / (1 − ρ)),
    is below tol at a step within ``steps`` (or, counted phase by phase as the state halves, each phase at the rate
    of the ball the state has shrunk to), every other candidate lies beyond 2.5 R (none is ever the nearest,
    so no test of the run measures against another), and the run never meets the divergence bound: its own
    checks then end it REACHED at r, as running it on would, only sooner.
    """
    K, C = cand.shape
    r_out = np.full(K, np.nan)
    ip = np.ascontiguousarray(ip, dtype=np.int64)
    G = int(ip[0])
    L = max(int(L), 1)
    pw = np.asarray(ip[2:2 + G], dtype=np.int64)
    if K == 0 or C == 0:
        return np.zeros(K, dtype=bool), r_out
    valid = np.arange(C)[None, :] < ncand[:, None]
    rows = np.arange(K)
    eps = np.finfo(float).eps
    with np.errstate(all="ignore"):
        dist = np.where(valid, np.abs(cand - hist[:, -1:]), np.inf)  # the resumed run's first goal
        j = np.argmin(dist, axis=1)
        r, tl = cand[rows, j], tol[rows, j]
        other = np.where(valid & (np.arange(C)[None, :] != j[:, None]), np.abs(cand - r[:, None]), np.inf).min(axis=1)
        a = candidate_linearisations(POLY, kernel_array(ip, np.int64), np.ascontiguousarray(fp, dtype=float),
                                     np.ascontiguousarray(r[:, None]), np.ones(K, dtype=np.int64), L)[:, 0, :]
        A = np.zeros((K, L, L))
        A[:, 0, :] = np.where(np.isfinite(a), a, 0.0)
        A[:, np.arange(1, L), np.arange(L - 1)] = 1.0
        V, W, fine = _eigenbases(A)
        inf_norm = lambda M: np.abs(M).sum(axis=-1).max(axis=-1)  # noqa: E731 - ‖·‖∞ of a stack
        eta = inf_norm(np.eye(L)[None] - W @ V) + 4 * L * eps * inf_norm(W) * inf_norm(V)
        Vn = inf_norm(V) / (1.0 - eta)  # >= ‖W⁻¹‖∞ where eta < 1
        WAV = W @ A @ V
        rho_A = (inf_norm(WAV) + 4 * L * eps * inf_norm(W) * inf_norm(A) * inf_norm(V)) / (1.0 - eta)
        w1 = np.abs(W[:, :, 0]).max(axis=1)
        e0 = hist[:, ::-1] - r[:, None]  # the state: e(k−1), …, e(k−L)
        z0 = np.abs(np.einsum("kij,kj->ki", W, e0)).max(axis=1)
        R = 1.25 * Vn * z0 + tl
        Y = np.abs(r) + R

        def slope(Yb: np.ndarray) -> np.ndarray:
            # S: how far the partials of the C_g y^m with m >= 2 move within Yb − |r| of r (the linear ones do not)
            out = np.zeros(K)
            for g in range(G):
                m = int(pw[g])
                if m >= 2:
                    out = out + np.abs(fp[:, 1 + g]) * m * ((Yb ** (m - 1) - np.abs(r) ** (m - 1))
                                                            + 2 * m * eps * Yb ** (m - 1))
            return out

        S = slope(Y)
        at_r = np.abs(fp[:, 0]) + np.abs(r)  # Σ |terms| of a step at r
        F = fp[:, 0] - r
        for g in range(G):
            m = int(pw[g])
            at_r = at_r + np.abs(fp[:, 1 + g]) * np.abs(r) ** m
            F = F + fp[:, 1 + g] * r ** m
        n_ops = int(pw.sum()) + G + 2  # products and sums of one step: each rounds by at most eps/2 (γ_n bound × 2)

        def c_of(Yb: np.ndarray) -> np.ndarray:
            # c of the error recursion while the outputs lie within Yb − |r| of r: F(r) as evaluated, its own
            # rounding, and one step's rounding (n_ops eps Σ |terms| there)
            size = np.abs(fp[:, 0]) + sum(np.abs(fp[:, 1 + g]) * Yb ** int(pw[g]) for g in range(G))
            return np.abs(F) + n_ops * eps * (at_r + size)

        c_bound = c_of(Y)
        rho = rho_A + w1 * S * Vn
        gap = 1.0 - rho
        floor_y = Vn * w1 * c_bound / gap  # the error rounding and F(r) keep up
        need = np.ceil(np.log(np.maximum(Vn * z0 / (tl / 2), 1.0)) / -np.log1p(-gap)) + 2 * L + 2
        ref = np.maximum(np.abs(y0), np.where(valid, np.abs(cand), 0.0).max(axis=1))
        base = (fine & (ncand > 0) & (eta < 0.5) & (gap > 0) & (other > 2.5 * R) & (Y < 1e6 * ref)
                & np.all(np.isfinite(e0), axis=1) & np.isfinite(c_bound) & np.isfinite(S))
        whole = base & (floor_y <= tl / 4) & (need <= steps)
        # The same argument restarted as the state shrinks: a phase that starts with ‖z‖ <= Z (up to z0's own
        # rounding, which the 1.25 of R covers) stays in the ball R_Z = 1.25 Vn Z + tl while its floor
        # ‖W e₁‖ c_Z / (1 − ρ_Z) is below Z / 2, c_Z and ρ_Z = ‖W A W⁻¹‖ + ‖W e₁‖ S(R_Z) ‖W⁻¹‖ (<= ρ) those of that
        # ball; ρ_Z^n Z + ‖W e₁‖ c_Z / (1 − ρ_Z) <= Z / 2 after the n steps counted, and the next phase starts there.
        # Once Vn Z <= tl / 2, with the floor of that last ball below tl / 4, every later output lies within tl of r.
        # A slow plant's nonlinear rest and rounding weigh less as its run nears r: the whole ball's rate and floor
        # undercounted it (second order, τ ≈ 1.9e5: 1.8e-6 per step against 5.9e-6) and runs were run on.
        Z = np.where(base, z0, 0.0)
        phased = np.zeros(K)
        todo = base & (Vn * Z > tl / 2)
        while todo.any():
            Y_Z = np.abs(r) + 1.25 * Vn * Z + tl
            g_Z = 1.0 - (rho_A + w1 * slope(Y_Z) * Vn)
            q = w1 * c_of(Y_Z) / (g_Z * np.where(todo, Z, 1.0))  # the phase's floor against its Z
            n = np.where((g_Z > 0) & (q < 0.5), np.ceil(np.log(0.5 - q) / np.log1p(-g_Z)), np.inf)
            phased = phased + np.where(todo, n, 0.0)
            Z = np.where(todo, Z / 2, Z)
            todo = todo & np.isfinite(phased) & (Vn * Z > tl / 2)
        Y_Z = np.abs(r) + 1.25 * Vn * Z + tl
        g_Z = 1.0 - (rho_A + w1 * slope(Y_Z) * Vn)
        last = (g_Z > 0) & (Vn * w1 * c_of(Y_Z) / g_Z <= tl / 4)  # the floor of the last ball
        ok = whole | (base & last & (phased + 2 * L + 2 <= steps))
    r_out[ok] = r[ok]
    return ok, r_out


def _eigenbases(A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eigenvectors V of a stack of matrices A (K, n, n), their computed inverses W, and which rows have both
    finite (a defective or singular basis is no basis: False there, its V and W the identity)."""
    K, n, _ = A.shape
    V = np.broadcast_to(np.eye(n, dtype=complex), (K, n, n)).copy()
    fine = np.all(np.isfinite(A.reshape(K, -1)), axis=1)
    if fine.any():
        _, V[fine] = np.linalg.eig(A[fine])
    W = np.broadcast_to(np.eye(n, dtype=complex), (K, n, n)).copy()
    try:
        W[fine] = np.linalg.inv(V[fine])
    except np.linalg.LinAlgError:
        for k in np.flatnonzero(fine):  # one by one: a singular basis refuses its own row, not the stack's
            try:
                W[k] = np.linalg.inv(V[k])
            except np.linalg.LinAlgError:
                fine[k] = False
    ok = fine & np.all(np.isfinite(W.reshape(K, -1)), axis=1)
    V[~ok] = np.eye(n)
    W[~ok] = np.eye(n)
    return V, W, ok


#: No per-pair budgets, no earlier runs to go on from: the first pass of :func:`settle`.
_ONE_BUDGET = np.zeros(0, dtype=np.int64)
_NO_HISTORY = np.zeros((0, 1))
_NO_RATES = np.zeros((0, 1))


def settle_budget(kind: int, ip: np.ndarray, fp: np.ndarray, cand: np.ndarray, ncand: np.ndarray, L: int
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Each pair's step budget: ``SETTLE_TAUS`` time constants of its slowest stable candidate; and ln ρ
    of each candidate.

    The time constant of a candidate is −1/ln ρ samples, ρ the spectral radius of the recursion
    linearised there; the budget is at least ``SETTLE_STEPS``; one above ``SETTLE_MAX_STEPS`` is
    returned as ``SETTLE_MAX_STEPS + 1`` (the run cannot be judged). Shapes: ``fp`` (K, nf),
    ``cand`` (K, C), ``ncand`` (K,); returns int64 (K,) and ln ρ (K, C), NaN past a pair's candidates.
    """
    a = candidate_linearisations(int(kind), kernel_array(ip, np.int64), np.ascontiguousarray(fp, dtype=float),
                                 np.ascontiguousarray(cand, dtype=float), ncand, int(L))  # (K, C, L)
    K, C, _ = a.shape
    with np.errstate(all="ignore"):
        roots = characteristic_roots(np.where(np.isfinite(a), a, 0.0).reshape(K * C, L))  # of y(t) = Σ_l a_l y(t − l)
        rho = np.abs(roots).max(axis=1).reshape(K, C)
        valid = np.arange(C)[None, :] < ncand[:, None]
        lograte = np.where(valid, np.log(rho), np.nan)
        tau = -1.0 / np.log(np.minimum(np.where(valid, rho, 0.0).max(axis=1), 1.0))  # stable: ρ < 1; rounding may not
    steps = np.where(np.isfinite(tau), np.ceil(SETTLE_TAUS * np.minimum(tau, SETTLE_MAX_STEPS)), np.inf)
    return np.clip(steps, SETTLE_STEPS, SETTLE_MAX_STEPS + 1).astype(np.int64), lograte


@lru_cache(maxsize=256)
def _fold_map(structure: Structure) -> tuple[np.ndarray, np.ndarray, int]:
    """(ip, one-hot term → [X, group 0, …] matrix, L) of a structure for :func:`settle` (POLY)."""
    code = encode(structure)
    G = int(code.gny.size)
    Dg = int(code.gylag.shape[1])
    ip = np.concatenate([[G, Dg], code.gny, code.gylag[:G].ravel()]).astype(np.int64)
    onehot = np.zeros((len(structure), G + 1))
    onehot[np.arange(len(structure)), code.grp + 1] = 1.0  # group −1 (input only) → column 0: X
    ip.setflags(write=False)
    onehot.setflags(write=False)
    return ip, onehot, int(code.ylag.max(initial=0))


def reached_equilibria(structure: Structure, thetas: np.ndarray, ubar: np.ndarray, y0: np.ndarray, *,
                       until_failure: bool = False, members: np.ndarray | None = None) -> Reached:
    """The equilibrium each member reaches at each point from the constant initial output ``y0``.

    The definition behind J_SF (see the module docstring): at (ū_j, y0_j) the equilibrium a free
    run at constant ū_j, started with every initial condition equal to y0_j, settles on. Rational
    structures: the equilibrium of eq. (6) when it is Schur-stable (then it is reached from every
    start). Others: the real roots of eq. (5), their stability, and a checked settling run from
    y0_j (:func:`settle`) for every pair that has a stable root.

    Parameters
    ----------
    structure : Structure
    thetas : ndarray, shape (P, n_terms)
    ubar : ndarray, shape (M,)
        Input levels (input units).
    y0 : float or ndarray, shape (M,) or (P, M)
        Initial output of each point's run (output units), usually the measured ȳ_i; or one
        per member and point.
    until_failure : bool
        Only whether a member reaches every point, and where, is asked (J_SF: infinite once one point
        is not reached): a member's settling runs stop once one of its points is not reached (no stable
        equilibrium; a run diverged or did not settle), the points not run to their end then status 6
        (not evaluated, NaN). A member that reaches every point gets exactly the result it gets without.
    members : ndarray of int, shape (P,), optional
        With ``until_failure``: the member each row belongs to, where one member spans several rows (the
        static surface's folded members, one row per member and point); rows of one member fail together.
        By default each row is its own member.

    Returns
    -------
    Reached
        ``ybar`` (P, M), NaN where nothing is reached, and the reason in ``status``.
    """
    th = np.atleast_2d(np.asarray(thetas, float))
    ub = np.asarray(ubar, float).ravel()
    P, M = th.shape[0], ub.size
    y0a = np.asarray(y0, float)
    # one initial output per point, or per member and point (the static surface's folded members)
    y0s = np.broadcast_to(y0a, (P, M) if y0a.ndim == 2 else ub.shape).copy()
    finite = np.all(np.isfinite(th), axis=1)
    th_ok = np.where(finite[:, None], th, 0.0)
    start_on = None  # a rational structure runs nothing: every point is reached or has no stable equilibrium
    if is_rational(structure):
        yb = _rational_roots(structure, th_ok, ub)
        stable = stable_mask(structure, th_ok, ub, yb)
        status = np.where(np.isfinite(yb), np.where(stable, REACHED, NONE_STABLE), NO_EQUILIBRIUM).astype(np.int8)
        yb = np.where(stable, yb, np.nan)
    else:
        roots, stab = roots_and_stability(structure, th_ok, ub)  # (P, M, D) each
        start_on = None
        has_root = np.any(np.isfinite(roots), axis=-1)
        status = np.where(has_root, NONE_STABLE, NO_EQUILIBRIUM).astype(np.int8)
        yb = np.full((P, M), np.nan)
        runs = np.any(stab, axis=-1) & finite[:, None]
        failed = owner = None
        if until_failure:
            owner = np.arange(P) if members is None else np.asarray(members, dtype=np.int64).ravel()
            failed = np.zeros(int(owner.max(initial=-1)) + 1, dtype=np.bool_)
            failed[owner[~runs.all(axis=1)]] = True  # a point with no stable equilibrium is reached by no run
            status[runs & failed[owner][:, None]] = SKIPPED
            runs &= ~failed[owner][:, None]
        run = np.flatnonzero(runs.ravel())
        if run.size:
            ip, onehot, L = _fold_map(structure)
            mu = encode(structure).mu
            with np.errstate(all="ignore"):
                W = th_ok[:, None, :] * (ub[:, None] ** mu)[None]  # θ_t ū^m_t: the input folded in
            fp = (W.reshape(P * M, -1)[run]) @ onehot
            D = roots.shape[-1]
            y_run, s_run = settle(POLY, ip, fp, np.broadcast_to(y0s, (P, M)).ravel()[run],
                                  roots.reshape(P * M, D)[run], stab.reshape(P * M, D)[run], L,
                                  members=None if failed is None else owner[run // M], failed=failed)
            yb.ravel()[run] = y_run
            status.ravel()[run] = s_run
            start_on = _unstable_starts(roots, stab, np.broadcast_to(y0s, (P, M)), status)
    # every ȳ an equilibrium: none is reached (a run stays at y0, not drawn to any), and it is said as such.
    # Looked for only where nothing was reached: there the y-coefficient 1 − Σ_y… vanishes, so the local
    # pole is 1 and no equilibrium is stable, let alone reached (most calls reach every point, and the
    # check cost a tenth of select_graybox's time)
    todo = (status != REACHED) & (status != SKIPPED) & finite[:, None]
    if todo.any():
        cont = continuum(structure, th_ok, ub) & todo
        status[cont] = CONTINUUM
        yb[cont] = np.nan
    status[~finite] = NO_EQUILIBRIUM
    yb[~finite] = np.nan
    return Reached(ub, y0s, yb, status, start_on)


def _unstable_starts(roots: np.ndarray, stab: np.ndarray, y0: np.ndarray, status: np.ndarray) -> np.ndarray:
    """Where a run did not settle and its start y0 is an unstable root (to a few ulps), that root; NaN elsewhere.
    ``roots``, ``stab`` (P, M, D); ``y0``, ``status`` (P, M). Shape (P, M)."""
    y = y0[..., None]
    with np.errstate(invalid="ignore"):
        near = np.abs(roots - y) <= 8 * np.finfo(float).eps * np.maximum(np.abs(y), np.abs(roots))
    on = ~stab & np.isfinite(roots) & near
    on &= (status == NOT_SETTLED)[..., None]
    first = np.argmax(on, axis=-1)
    hit = np.take_along_axis(roots, first[..., None], axis=-1)[..., 0]
    return np.where(on.any(axis=-1), hit, np.nan)


def point_phrases(phrases: list[str]) -> str:
    """The phrases of the points not reached (one per point, naming ū and why) joined by "; ": the first
    :data:`~graybox.core._reprs.LISTED`, then how many more (a curve over 10⁴ levels where none is reached made a
    message of megabytes)."""
    if len(phrases) <= LISTED:
        return "; ".join(phrases)
    return "; ".join(phrases[:LISTED]) + (f"; … and {len(phrases) - LISTED} more ū ({len(phrases)} in all; "
                                          "strict=False gives NaN there)")


def _describe_failures(res: Reached, what: str = "model") -> str:
    return f"the {what} reaches no equilibrium at " + point_phrases(res.explain(0))


def checked_model(structure: object, theta: object) -> tuple[Structure, np.ndarray]:
    """The arguments of a public static function: a Structure (a sequence of terms is read as one) and θ
    of its length, finite (``TypeError``/``ValueError`` naming the problem)."""
    structure = structure_of(structure)
    return structure, check_theta(len(structure), theta)


def refuse_surface(structure: Structure, twin: str) -> None:
    """``ValueError`` for a structure of several inputs given to a function of one input's static curve, naming
    ``twin``, the surface function that takes it (before ū is read: points of shape (M, m), right for the surface,
    were told to be levels of one input "as a model of several inputs takes (M, m)")."""
    if len(structure.input_names) > 1:
        m = len(structure.input_names)
        raise ValueError(f"the structure has {m} inputs {structure.input_names}: its static function is a surface, "
                         f"which graybox.{twin}(structure, theta, ubar) gives at points ū of shape (M, {m})")


def one_input_levels(ubar: object, name: str = "ubar") -> np.ndarray:
    """Levels of one input, shape (M,): a number, a 1-D array or a column (M, 1); finite.

    Points of several inputs, shape (M, m), are refused rather than flattened into M·m levels.
    """
    shape = np.shape(ubar)
    if len(shape) > 2 or (len(shape) == 2 and shape[1] != 1):
        raise ValueError(f"{name} must be levels of the one input (a number, shape (M,) or (M, 1)), got shape "
                         f"{shape}: a model of several inputs takes points of shape (M, m)")
    return np.atleast_1d(as_1d_finite(np.ravel(real_array(ubar, name, "input levels (numbers)")), name))


def only_stable(roots: np.ndarray, stable: np.ndarray, where: list[str],
                cont: np.ndarray | None = None) -> tuple[np.ndarray, list[str]]:
    """The one locally stable equilibrium at each point, shape (M,), NaN where there is none or there
    are several; and a phrase for each such point, naming it by ``where`` (e.g. "ū = 100").

    ``roots`` (M, D): every real root at each point, NaN-padded; ``stable`` (M, D) their stability;
    ``cont`` (M,): where every output is an equilibrium (:func:`continuum`), NaN too.
    """
    out = np.full(roots.shape[0], np.nan)
    problems = []
    for i in range(roots.shape[0]):
        ys = roots[i][stable[i]]
        if cont is not None and cont[i]:
            problems.append(f"at {where[i]} {CONTINUUM_WHY}")
        elif ys.size == 1:
            out[i] = ys[0]
        elif ys.size:
            problems.append(several_stable(ys, where[i]))
        elif np.isfinite(roots[i]).any():
            problems.append(f"no stable equilibrium at {where[i]}")
        else:
            problems.append(f"no equilibrium at {where[i]} (the static equation has no real root)")
    return out, problems


def several_stable(ybar: np.ndarray, where: str) -> str:
    """The phrase for several stable equilibria ``ybar`` at ``where`` (e.g. "ū = 100"), each to 6 significant
    digits (the same in any units)."""
    return (f"{len(ybar)} stable equilibria at {where} ([{', '.join(f'{e:.6g}' for e in ybar)}]); "
            "pass y0 to choose the one reached from it")


def static_curve(
    structure: Structure,
    theta: np.ndarray,
    ubar: np.ndarray,
    y0: float | np.ndarray | None = None,
    *,
    strict: bool = True,
) -> np.ndarray:
    """The steady state the model reaches at each constant input ``ubar``.

    With ``y0`` (the evaluator passes the measured ȳ_i): the equilibrium a free run at constant
    ū, started with every initial condition equal to ``y0``, settles on (``reached_equilibria``).
    Without it: the locally stable equilibrium when there is exactly one; several need ``y0`` to
    choose. For a rational structure both are the equilibrium of eq. (6) when it is Schur-stable.

    Parameters
    ----------
    structure : Structure
    theta : ndarray, shape (n_terms,)
    ubar : array_like, shape (M,)
        Input levels (input units).
    y0 : float or array_like of shape (M,), optional
        Initial output (one for all ū, or one per ū), output units.
    strict : bool
        When True (default) a ū where no equilibrium is reached (none is stable, the run
        diverges or does not settle; or several are stable and ``y0`` is not given) raises
        ``ValueError`` naming each such ū and why (the first 20, and how many more); when False its value is NaN.

    Returns
    -------
    ndarray, shape (M,)
        Output units.
    """
    strict = check_bool(strict, "strict")
    structure, th = checked_model(structure, theta)
    refuse_surface(structure, "static_surface")
    ub = one_input_levels(ubar)
    if y0 is not None:
        y0s = check_per_point(y0, ub.size, "y0")
        res = reached_equilibria(structure, th[None, :], ub, y0s)
        if strict and not res.ok.all():
            raise ValueError(_describe_failures(res))
        return res.ybar[0].copy()
    if is_rational(structure):
        res = reached_equilibria(structure, th[None, :], ub, np.zeros(ub.size))
        if strict and not res.ok.all():
            raise ValueError(_describe_failures(res))
        return res.ybar[0].copy()
    roots, stab = (v[0] for v in roots_and_stability(structure, th[None, :], ub))  # (M, D) each
    out, problems = only_stable(roots, stab,
                                [f"ū = {u}" for u in point_texts(ub)], continuum(structure, th[None, :], ub)[0])
    if strict and problems:
        raise ValueError("the model has " + point_phrases(problems))
    return out


def static_gain(
    structure: Structure,
    theta: np.ndarray,
    ubar: np.ndarray,
    y0: float | np.ndarray | None = None,
    *,
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
    structure, theta = checked_model(structure, theta)
    refuse_surface(structure, "static_surface_gain")
    ub = one_input_levels(ubar)
    yb = static_curve(structure, theta, ub, y0=y0, strict=strict)
    cm = cluster_map(structure)  # the curve's own form: one coefficient Σ = Rθ per cluster (p, m)
    keys = np.array(cm.keys, float).reshape(-1, 2)
    gain = static_gains(keys[:, 0], keys[:, 1:], (cm.R @ theta)[None, :], ub[:, None], yb[None, :])[0, :, 0]
    # NaN⁰ is 1: where no equilibrium is reached F_ū and F_ȳ may still be finite (F_ȳ = 0 for an
    # integrator), the gain is not
    return np.where(np.isfinite(yb), gain, np.nan)


def static_theta_gradient(structure: Structure, theta: np.ndarray, ubar: np.ndarray, ybar: np.ndarray) -> np.ndarray:
    """∂ȳ_i/∂θ_t at equilibria (ū_i, ȳ_i) of the static curve, by implicit differentiation of eq. (5).

    F(ȳ, θ) = Σ_t θ_t ȳ^{p_t} ū^{m_t} − ȳ = 0 gives ∂ȳ/∂θ_t = −ȳ^{p_t} ū^{m_t} / F_ȳ
    (:func:`graybox.static._linearisation.static_theta_gradient_of`).

    Returns
    -------
    ndarray, shape (M, n_terms)
    """
    p, A = static_powers(structure, curve=True)
    return static_theta_gradient_of(p, A, theta, np.asarray(ubar, float).reshape(-1, 1), ybar)
