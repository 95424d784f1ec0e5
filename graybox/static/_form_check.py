"""The static curve's form, and the terms a structure needs to carry it.

A gray-box model must be able to *represent* the static information before any estimator can
impose it. At a constant input the clusters Σ_{u^m} (terms in u only) make the numerator of the
static function and Σ_y its denominator (eq. (6)); a rational structure reproduces a polynomial
curve of degree d exactly (eq. (22)) only when it has every cluster Σ_{u^0} … Σ_{u^d} and Σ_y (candidates
without output terms, an NFIR structure, have no denominator: Σ_{u^0} … Σ_{u^d} carry the curve).
Notebooks 02 and 04 added "the simplest term per missing cluster" by hand; this module does it:

- :func:`static_degree` — the degree of the curve the static information asks for: a
  :class:`~graybox.StaticCurve`'s own degree, or for static points the smallest polynomial degree
  whose least-squares fit lies within the band B (mean squared error ≤ B, the band of D_SF);
- :func:`static_terms` — for each cluster that degree needs and the structure lacks, the simplest
  candidate of that cluster (smallest largest lag, then fewest factors, then candidate order).

With several inputs the static information is a surface: the degree is the total degree of the
polynomial surface (every monomial ū₁^a₁ ⋯ ū_m^a_m with a₁ + … + a_m ≤ d), and the clusters
needed are every Σ_{u₁^a₁ ⋯ u_m^a_m} of those monomials and Σ_y. An input that the static
points hold at one value (a transient input, zero at every steady state; a second input kept
fixed during the static test) says nothing about the form: the degree is judged, and the
clusters asked, over the inputs the points vary (:func:`varied_inputs`).
"""

from __future__ import annotations

import numpy as np

from ._curves import StaticCurve
from ..core._records import StaticPoints
from ._analysis import cluster_name
from ._surface_analysis import surface_cluster_key, surface_cluster_name
from ..core._least_squares import free_directions, scaled_lstsq
from ._surfaces import StaticSurface, _monomials, monomial_exponents
from ..core._terms import Structure, Term
from ..core._validation import check_int, check_real

__all__ = ["carried_degree", "static_degree", "static_fit_mse", "static_terms", "varied_inputs"]


def varied_inputs(static: StaticPoints | StaticCurve | StaticSurface) -> tuple[str, ...]:
    """The inputs the static information varies: every input of a curve or a surface; for points, those
    whose ū differs between points (one held at a single value, e.g. a transient input's z̄ = 0,
    carries no information on the static form)."""
    if isinstance(static, StaticPoints):
        u = np.asarray(static.ubar, float).reshape(len(static), static.n_inputs)
        return tuple(n for n, col in zip(static.input_names, u.T) if np.ptp(col) > 0)
    return tuple(static.input_names)


def static_degree(static: StaticPoints | StaticCurve | StaticSurface, *, band: float, max_degree: int = 3) -> int:
    """Degree of the polynomial static curve (total degree of the surface, several inputs) the
    static information asks for.

    Parameters
    ----------
    static : StaticPoints, StaticCurve or StaticSurface
        The static information. A curve or a surface gives its own degree.
    band : float
        B (output units²): points ask for the smallest degree whose least-squares polynomial fit
        has a mean squared error at most B (a fit closer than the points' uncertainty is noise).
    max_degree : int
        Largest degree considered (also limited to the degrees the points can determine: see
        :func:`static_fit_mse`).

    Returns
    -------
    int
        The degree d; when no degree up to the limit fits within B, the limit (the best that
        can be asked of the points).
    """
    if isinstance(static, (StaticCurve, StaticSurface)):
        return static.degree
    if not isinstance(static, StaticPoints):
        raise TypeError(f"static must be StaticPoints, a StaticCurve or a StaticSurface, got {type(static).__name__}")
    band = check_real(band, "band", low=0, low_open=True)
    top = check_int(max_degree, "max_degree", low=0)
    best = 0
    for d in range(top + 1):
        mse = static_fit_mse(static, d)
        if mse is None:  # too few points for this degree's monomials
            break
        best = d
        if mse <= band:
            return d
    return best


def static_fit_mse(static: StaticPoints, degree: int) -> float | None:
    """Mean squared error (output units²) of the least-squares polynomial of ``degree`` through the
    points (a surface of that total degree with several inputs); None when the points cannot
    determine it (fewer points than coefficients, or points that leave a direction unvaried, as
    when two inputs always move together). One point is fitted exactly by a constant. With several
    inputs, an input at k levels enters with powers below k only (its higher powers are a combination
    of those at these points): 4 speeds × 2 valve positions determine a surface of degree 2 in
    1, s, v, s², sv, not v²."""
    u = np.asarray(static.ubar, float).reshape(len(static), static.n_inputs)
    # a held input is a constant: the constant monomial carries it
    u = u[:, [static.input_names.index(n) for n in varied_inputs(static)]]
    if u.shape[1] == 0:
        ex: tuple = ((),)
        if degree > 0:
            return None  # no input varies: only degree 0 is determined
    else:
        # each input centred and scaled: the polynomials of a degree are the same, their fit's conditioning is not
        # (ū = 1e5 ± 1 made the cubic's columns collinear, and the degree asked depended on where the input's units
        # put their zero)
        u = (u - u.mean(axis=0)) / np.ptp(u, axis=0)
        levels = [_levels(col, degree) for col in u.T]
        ex = tuple(e for e in monomial_exponents(u.shape[1], degree) if all(p < k for p, k in zip(e, levels)))
        if not any(sum(e) == degree for e in ex):
            return None  # nothing of this degree is determined: it is the degree below's fit
    if len(static) < len(ex):
        return None
    # plain least squares on the monomials (no curve object: its domain would refuse one point,
    # or points that do not vary every input)
    V = _monomials(u, ex)
    try:
        c = scaled_lstsq(V, static.ybar)
    except ValueError:  # rank deficient: the points do not pin the polynomial down (e.g. one input held)
        return None
    return float(np.mean((V @ c - static.ybar) ** 2))


def _levels(x: np.ndarray, degree: int) -> int:
    """How many of one input's powers x⁰ … x^degree the points determine: its number of levels (at most
    degree + 1), judged by the one rank rule, so that levels apart by round-off (0.3 and 0.1 * 3) are one level,
    as they are to the fit (np.unique took them for two, asked a power they cannot determine, and the fit,
    rank deficient, stopped the degree)."""
    V = x[:, None] ** np.arange(degree + 1)
    return V.shape[1] - free_directions([(V, len(x))]).shape[1]


def _simplicity(term: Term) -> tuple[int, int, int]:
    return (term.max_lag, len(term.factors), sum(l for _, l, _ in term.factors))


def static_terms(structure: Structure, candidates: Structure, degree: int,
                 inputs: tuple[str, ...] | None = None) -> list[Term]:
    """The simplest candidates that give ``structure`` every cluster a degree-``degree`` curve needs.

    Parameters
    ----------
    structure : Structure
        The structure to complete (process terms).
    candidates : Structure
        Where the missing terms are taken from.
    degree : int
        Degree d of the static curve: clusters Σ_{u^0} … Σ_{u^d} and Σ_y are needed (several
        inputs: every Σ_{u1^a1 ⋯ um^am} with a1 + … + am ≤ d, and Σ_y); Σ_y only when the candidates or
        the structure hold output terms (without, the static function is its numerator alone).
    inputs : tuple of str, optional
        The inputs the form is a polynomial in (default: every input of the candidates and the
        structure); the others are held by the static information (:func:`varied_inputs`), and
        no cluster in them is asked.

    Returns
    -------
    list of Term
        Terms to add (empty when nothing is missing), in cluster order.

    Raises
    ------
    ValueError
        When the candidates hold no term of a needed cluster (they cannot represent the static
        curve's form: e.g. a degree-2 curve and candidates of degree 1), naming the clusters.
    """
    degree = check_int(degree, "degree", low=0)
    out, missing, inputs = _complete(structure, candidates, degree, inputs)
    if missing:
        m = len(inputs)
        names = [cluster_name(*k) if m == 1 else surface_cluster_name(k[0], k[1:], inputs) for k in missing]
        # name the remedy for what is missing: a constant for Σ0, a higher degree for the input powers
        fixes = ([f"candidates of degree >= {max(sum(k[1:]) for k in missing)}"] if any(sum(k[1:]) for k in missing)
                 else []) + (["a constant term"] if (0,) * (m + 1) in missing else []) + \
            (["output terms (Σy)"] if (1,) + (0,) * m in missing else [])
        raise ValueError(
            f"the candidates cannot represent a degree-{degree} static {'curve' if m == 1 else 'surface'}: they hold "
            f"no term of the cluster(s) {names}; they need {' and '.join(fixes)}")
    return out


def _complete(structure: Structure, candidates: Structure, degree: int,
              varied: tuple[str, ...] | None = None) -> tuple[list[Term], list[tuple], tuple]:
    """(terms to add, cluster keys no candidate holds, input names) for a degree-``degree`` form in the
    ``varied`` inputs (default: all)."""
    inputs = tuple(dict.fromkeys(candidates.input_names + structure.input_names)) or ("u",)
    # an input the static information varies but no candidate has: its clusters are asked, and missing
    inputs += tuple(n for n in (varied or ()) if n not in inputs)
    m = len(inputs)
    pos = [i for i, n in enumerate(inputs) if varied is None or n in varied]
    need = [(0,) + e for e in _embedded(monomial_exponents(len(pos), degree) if pos else ((),), pos, m)]
    # Σy is the static function's denominator: a structure with output terms needs it; one of candidates without
    # any (NFIR) has the numerator alone (Σy = 0), which carries the curve
    if any(t.power_of("y") for t in (*candidates, *structure) if not t.is_noise):
        need += [(1,) + (0,) * m]
    have = {surface_cluster_key(t, inputs) for t in structure if not t.is_noise}
    out, missing = [], []
    for key in need:
        if key in have:
            continue
        pool = [t for t in candidates if not t.is_noise and surface_cluster_key(t, inputs) == key]
        if not pool:
            missing.append(key)
            continue
        out.append(min(pool, key=_simplicity))
    return out, missing, inputs


def _embedded(exponents, pos: list[int], m: int) -> list[tuple[int, ...]]:
    """Exponent vectors over the inputs at ``pos``, written over all ``m`` inputs (zero elsewhere)."""
    out = []
    for e in exponents:
        full = [0] * m
        for i, k in zip(pos, e):
            full[i] = k
        out.append(tuple(full))
    return out


def carried_degree(candidates: Structure, degree: int, inputs: tuple[str, ...] | None = None) -> int | None:
    """The largest degree d <= ``degree`` whose static form (clusters Σ_{u^0} … Σ_{u^d}, Σ_y; every
    monomial of total degree <= d with several inputs) the candidates can complete; None when they
    cannot complete even degree 0 (no constant, or output terms but no Σ_y term).

    Parameters
    ----------
    candidates : Structure
        Candidate terms (noise terms are ignored).
    degree : int
        The degree the static information asks for.
    inputs : tuple of str, optional
        The inputs the form is a polynomial in (default: all; see :func:`static_terms`).

    Returns
    -------
    int or None
    """
    degree = check_int(degree, "degree", low=0)
    for d in range(degree, -1, -1):
        if not _complete(Structure([]), candidates, d, inputs)[1]:
            return d
    return None
