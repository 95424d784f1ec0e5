"""Decision makers: pick one model from a Pareto set.

:func:`decide_dsf` is the paper's D_SF (eq. (14)): the member with the smallest free-run
error J_S among those whose static error J_SF lies in the uncertainty interval
B = [0, band] of the pressure transmitter (0.031 mlc² = 0.175²).
"""

from __future__ import annotations

import numpy as np

from .model import Model
from .pareto import ParetoSet
from .records import Record

__all__ = ["decide_dsf", "FALLBACKS"]

#: What :func:`decide_dsf` may do when no member lies in the band, if the user says so.
FALLBACKS = ("min_jsf",)


def decide_dsf(
    pareto: ParetoSet,
    band: float | tuple[float, float] = 0.031,
    fallback: str | None = None,
    return_index: bool = False,
) -> Model | tuple[Model, int]:
    """Eq. (14): argmin J_S subject to J_SF ∈ B.

    Parameters
    ----------
    pareto : ParetoSet
        Members with J_S and J_SF (output units²).
    band : float or (float, float)
        B = [0, band] (default 0.031 mlc² = 0.175², the transmitter's error), or (low, high).
    fallback : {None, "min_jsf"}
        When no member has J_SF in B (with a finite J_S): None (default) raises ``ValueError``;
        ``"min_jsf"`` picks the member with the smallest J_SF (ties: smaller J_S) instead. The
        choice must be explicit because the result then is *not* a D_SF decision.
    return_index : bool
        Also return the member's index in ``pareto``.

    Returns
    -------
    Model, or (Model, int) with ``return_index``
        Ties in J_S are broken by the smaller J_SF, then the lower index.
    """
    if not isinstance(pareto, ParetoSet):
        raise ValueError(f"decide_dsf needs a ParetoSet, got {type(pareto).__name__}")
    if len(pareto) == 0:
        raise ValueError("the Pareto set is empty")
    lo, hi = (0.0, band) if np.ndim(band) == 0 else band
    lo, hi = float(lo), float(hi)
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo <= hi):
        raise ValueError(f"band must be >= 0 (or (low, high) with 0 <= low <= high), got {band!r}")
    if fallback is not None and fallback not in FALLBACKS:
        raise ValueError(f"fallback must be None or one of {FALLBACKS}, got {fallback!r}")
    js, jsf = pareto.JS, pareto.JSF
    inside = (jsf >= lo) & (jsf <= hi) & np.isfinite(js)
    if inside.any():
        cand = np.flatnonzero(inside)
        i = int(cand[np.lexsort((cand, jsf[cand], js[cand]))[0]])
        label = f"{pareto.method} D_SF"
    else:
        finite = jsf[np.isfinite(jsf)]
        best = f"{finite.min():.4g}" if finite.size else "inf for every member"
        if fallback is None:
            raise ValueError(
                f"no member of the Pareto set ({len(pareto)} members, method {pareto.method!r}) has J_SF in "
                f"B = [{lo:g}, {hi:g}] with a finite J_S; the smallest J_SF is {best}. Widen the band, extend "
                "the λ sweep, or pass fallback='min_jsf' to take the member with the smallest J_SF"
            )
        ok = np.flatnonzero(np.isfinite(jsf))
        if ok.size == 0:
            raise ValueError("fallback 'min_jsf': every member has an undefined static curve (J_SF = inf)")
        i = int(ok[np.lexsort((ok, pareto.JS[ok], jsf[ok]))[0]])
        label = f"{pareto.method} min J_SF (no member in B)"
    model = pareto.model(i, name=label)
    return (model, i) if return_index else model


def decide_min_correlation(
    pareto: ParetoSet,
    record: Record,
    output: str = "free-run",
    return_index: bool = False,
) -> Model | tuple[Model, int]:
    """The minimal-correlation decision maker (Barroso, Takahashi & Aguirre, J. Process Control, 2007).

    As we read that paper: the chosen member is the one whose one-step residuals
    ξ(k) = y(k) − ŷ₁(k) are least correlated with the model's output, ρ = |corr(ξ, ŷ)|, on the
    identification data. With ``output="free-run"`` (default) ŷ is the free-run simulation; with
    ``"one-step"`` it is ŷ₁ itself (then plain least squares, whose residuals are orthogonal to
    its predictions when the structure has a constant term, is always a minimiser: that variant
    is useful only for constrained sets). Members whose free run diverges are never chosen.

    Parameters
    ----------
    pareto : ParetoSet
    record : Record
        Identification data, shape (N,) each; counted from sample max_lag on.
    output : {"free-run", "one-step"}
    return_index : bool
        Also return the member's index.

    Returns
    -------
    Model, or (Model, int) with ``return_index``
    """
    from .regressors import regressor_matrix
    from .simulation import simulate_many

    if not isinstance(pareto, ParetoSet):
        raise ValueError(f"decide_min_correlation needs a ParetoSet, got {type(pareto).__name__}")
    if output not in ("free-run", "one-step"):
        raise ValueError(f"output must be 'free-run' or 'one-step', got {output!r}")
    if len(pareto) == 0:
        raise ValueError("the Pareto set is empty")
    st = pareto.structure
    L = st.max_lag
    record.require_length(L)
    y = record.y[L:]
    Y1 = regressor_matrix(st, record.u, record.y, start=L) @ pareto.thetas.T  # (N-L, K)
    xi = y[:, None] - Y1
    Yo = Y1 if output == "one-step" else np.asarray(simulate_many(st, pareto.thetas, record)).T[L:]
    with np.errstate(all="ignore"):
        xc = xi - xi.mean(axis=0)
        oc = Yo - Yo.mean(axis=0)
        rho = np.abs(np.sum(xc * oc, axis=0)) / np.sqrt(np.sum(xc**2, axis=0) * np.sum(oc**2, axis=0))
    rho = np.where(np.isfinite(rho) & np.all(np.isfinite(Yo), axis=0), rho, np.inf)
    if not np.isfinite(rho).any():
        raise ValueError("no member has a defined residual/output correlation (every free run diverged?)")
    i = int(np.argmin(rho))
    model = pareto.model(i, name=f"{pareto.method} min-corr (ρ = {rho[i]:.3g})")
    return (model, i) if return_index else model


__all__.append("decide_min_correlation")
