"""The static curve's form, and the terms a structure needs to carry it.

A gray-box model must be able to *represent* the static information before any estimator can
impose it. At a constant input the clusters Σ_{u^m} (terms in u only) make the numerator of the
static function and Σ_y its denominator (eq. (6)); a rational structure reproduces a polynomial
curve of degree d exactly (eq. (22)) only when it has every cluster Σ_{u^0} … Σ_{u^d} and Σ_y.
Notebooks 02 and 04 added "the simplest term per missing cluster" by hand; this module does it:

- :func:`static_degree` — the degree of the curve the static information asks for: a
  :class:`~graybox.StaticCurve`'s own degree, or for static points the smallest polynomial degree
  whose least-squares fit lies within the band B (mean squared error ≤ B, the band of D_SF);
- :func:`static_terms` — for each cluster that degree needs and the structure lacks, the simplest
  candidate of that cluster (smallest largest lag, then fewest factors, then candidate order).
"""

from __future__ import annotations

import numpy as np

from ._curves import StaticCurve
from ._records import StaticPoints
from ._static import cluster_key, cluster_name
from ._terms import Structure, Term
from ._validation import check_int, check_real

__all__ = ["static_degree", "static_terms"]


def static_degree(static: StaticPoints | StaticCurve, *, band: float, max_degree: int = 3) -> int:
    """Degree of the polynomial static curve the static information asks for.

    Parameters
    ----------
    static : StaticPoints or StaticCurve
        The static information. A curve gives its own degree.
    band : float
        B (output units²): points ask for the smallest degree whose least-squares polynomial fit
        has a mean squared error at most B (a fit closer than the points' uncertainty is noise).
    max_degree : int
        Largest degree considered (also limited by the number of points minus one).

    Returns
    -------
    int
        The degree d; when no degree up to the limit fits within B, the limit (the best that
        can be asked of the points).
    """
    if isinstance(static, StaticCurve):
        return static.degree
    if not isinstance(static, StaticPoints):
        raise ValueError(f"static must be StaticPoints or a StaticCurve, got {type(static).__name__}")
    band = check_real(band, "band", low=0, low_open=True)
    top = min(check_int(max_degree, "max_degree", low=0), len(static) - 1)
    for d in range(top + 1):
        c = StaticCurve.fit(static, d)
        if float(np.mean((c(static.ubar) - static.ybar) ** 2)) <= band:
            return d
    return top


def _simplicity(term: Term) -> tuple[int, int, int]:
    return (term.max_lag, len(term.factors), sum(l for _, l, _ in term.factors))


def static_terms(structure: Structure, candidates: Structure, degree: int) -> list[Term]:
    """The simplest candidates that give ``structure`` every cluster a degree-``degree`` curve needs.

    Parameters
    ----------
    structure : Structure
        The structure to complete (process terms).
    candidates : Structure
        Where the missing terms are taken from.
    degree : int
        Degree d of the static curve: clusters Σ_{u^0} … Σ_{u^d} and Σ_y are needed.

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
    have = {cluster_key(t) for t in structure if not t.is_noise}
    need = [(0, m) for m in range(degree + 1)] + [(1, 0)]
    out, missing = [], []
    for key in need:
        if key in have:
            continue
        pool = [t for t in candidates if not t.is_noise and cluster_key(t) == key]
        if not pool:
            missing.append(key)
            continue
        out.append(min(pool, key=_simplicity))
    if missing:
        raise ValueError(
            f"the candidates cannot represent a degree-{degree} static curve: they hold no term of the cluster(s) "
            f"{[cluster_name(*k) for k in missing]} (raise the candidates' degree, or include a constant)")
    return out
