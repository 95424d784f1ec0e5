"""The stopping rule shared by FROLS and SEMP: a term count, a tolerance or an information criterion.

A selector walks through models of growing size (FROLS: the nested models of its path; SEMP:
every structure its forward and pruning steps accept). Each model is described by its size, the
value of the information criterion and the unexplained fraction the tolerance is read on
(FROLS: 1 − ΣERR = RSS / yᵀy; SEMP: free-run MSE / var(y)). :func:`choose_model` picks one of
them by the same rule for both selectors, and warns in the same words when the rule was cut
short by the largest size looked at.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..core._validation import warn

__all__ = ["StopRule", "stop_rule", "choose_model", "FewerTermsError"]

Mode = Literal["n_terms", "tol", "criterion"]


class FewerTermsError(ValueError):
    """A search cannot give the size asked for on these data (fewer usable or independent candidates).

    ``reached``: the most terms it can give, when known (None otherwise), so that a caller that asks
    for several sizes (``select_graybox``) takes the ones reached instead of reading the message.
    """

    def __init__(self, message: str, reached: int | None = None):
        super().__init__(message)
        self.reached = reached


@dataclass(frozen=True)
class StopRule:
    """Which rule ends a selection: exactly one of a count, a tolerance, a criterion minimum.

    Attributes
    ----------
    mode : {"n_terms", "tol", "criterion"}
    n_terms : int or None
        The count (mode ``"n_terms"``).
    tol : float or None
        The tolerance on the unexplained fraction (mode ``"tol"``).
    criterion : str
        The information criterion: the rule's own in mode ``"criterion"``, otherwise only the
        name of the curve a result stores.
    """

    mode: Mode
    n_terms: int | None
    tol: float | None
    criterion: str


def stop_rule(n_terms: int | None, tol: float | None, criterion: str | None, *, curve_default: str) -> StopRule:
    """The rule given by already checked arguments: a count, else a tolerance, else a criterion (BIC by default).

    ``curve_default`` names the stored curve when a count or a tolerance stops the selection.
    """
    if n_terms is not None:
        return StopRule("n_terms", n_terms, None, criterion or curve_default)
    if tol is not None:
        return StopRule("tol", None, tol, criterion or curve_default)
    return StopRule("criterion", None, None, criterion or "bic")


def choose_model(
    rule: StopRule,
    sizes: np.ndarray,
    crit: np.ndarray,
    unexplained: np.ndarray,
    *,
    can_grow: bool,
    fraction: str,
    rows_cap: int | None = None,
    round_off: float | np.ndarray = 0.0,
) -> tuple[int, str]:
    """Index of the model the rule picks among those looked at, and why, in words.

    ``n_terms``: the model of that size with the smallest criterion (the last one met among
    ties); ``tol``: the fewest terms whose unexplained fraction is at most the tolerance (then
    the smallest criterion, the last met), else the last model, with a warning; ``criterion``:
    the smallest criterion (the first met among ties; where that model is at its round-off floor, the fewest terms at
    theirs), with a warning when it is at the largest size looked at and ``can_grow``.

    Parameters
    ----------
    rule : StopRule
    sizes : ndarray of int, shape (M,)
        Number of terms of each model, in the order the selector met them.
    crit : ndarray, shape (M,)
        The criterion of each model (smaller is better).
    unexplained : ndarray, shape (M,)
        The fraction the tolerance is read on (dimensionless).
    can_grow : bool
        Whether a larger model could have been looked at (candidates were left): only then is a
        rule cut short by the largest size worth a warning.
    fraction : str
        How the unexplained fraction is written in messages (e.g. ``"1 - ΣERR"``).
    rows_cap : int, optional
        The regression rows, when they alone kept larger models from being looked at (the largest
        size is rows − 1 and candidates were left): a criterion smallest there has only met the
        record's end, an interpolation rather than a choice, and gets a warning saying so; a
        tolerance not reached there is said to need a longer record.
    round_off : float or ndarray of shape (M,), optional
        The unexplained fraction's floor (the selector's residual floored at round-off), one for all
        models or one each: a model at it fits exactly, and meets any tolerance, however far below the
        floor (default 0).

    Returns
    -------
    (int, str)
        The index into the arrays and the reason (e.g. ``"bic minimum at 6 of 12 sizes"``).

    Warns
    -----
    RuntimeWarning
        When the tolerance is not reached by any model (the last one is returned), or the
        criterion is smallest at the largest size looked at while candidates were left (or at the
        largest the record's rows allow, ``rows_cap``).
    """
    sizes = np.asarray(sizes, dtype=int)
    crit = np.asarray(crit, dtype=float)
    unexplained = np.asarray(unexplained, dtype=float)
    if rule.mode == "n_terms":
        same = np.flatnonzero(sizes == rule.n_terms)
        if same.size == 0:
            raise ValueError(f"no model of {rule.n_terms} terms was reached")
        # the best of that size; among ties (exact fits on noise-free data) the last one met
        best = same[crit[same] == crit[same].min()]
        return int(best[-1]), f"n_terms = {rule.n_terms}"
    if rule.mode == "tol":
        # at the floor (to its rounding) the fit is exact: no tolerance asks more (1e-30 of noise-free data)
        exact = _exact(unexplained, round_off)
        reached = np.flatnonzero((unexplained <= rule.tol) | exact)
        if reached.size:
            # the fewest terms within the tolerance (SEMP's pruning may reach it with fewer after more)
            few = reached[sizes[reached] == sizes[reached].min()]
            i = int(few[crit[few] == crit[few].min()][-1])
            floor = float(np.broadcast_to(np.asarray(round_off, dtype=float), unexplained.shape)[i])
            return i, (f"{fraction} ≤ {rule.tol:g}" if unexplained[i] <= rule.tol else
                       f"{fraction} at its round-off floor {floor:.0e} (an exact fit; tol {rule.tol:g} is below it)")
        last = sizes.size - 1
        # every candidate looked at, or every term the rows allow: a larger max_terms looks at nothing more
        advice = ("raise max_terms or tol" if can_grow else
                  f"{rows_cap} regression rows allow no more terms: use a longer record, fewer candidates, or raise tol"
                  if rows_cap is not None else "every candidate was looked at: raise tol, or add candidates")
        warn(f"tolerance {rule.tol:g} not reached: {fraction} = {unexplained[last]:.3e} after {sizes[last]} terms "
             f"({advice})", RuntimeWarning)
        return last, f"tol {rule.tol:g} not reached in {sizes[last]} terms"
    i = int(np.argmin(crit))
    exact = _exact(unexplained, round_off)
    if exact[i]:
        # among exact fits the residual is round-off: the criteria's penalties then compare nothing the data say
        # (EBIC's ln C(p, k) falls as k nears p), so the fewest terms, then the smallest criterion
        few = np.flatnonzero(exact & (sizes == sizes[exact].min()))
        i = int(few[np.argmin(crit[few])])
    largest = int(sizes.max())
    if sizes[i] == largest and can_grow:
        warn(f"{rule.criterion} is smallest at the largest size looked at ({largest} terms): the curve may still be "
             "falling; raise max_terms", RuntimeWarning)
    elif sizes[i] == largest and rows_cap is not None:
        warn(f"{rule.criterion} is smallest at the largest size the data allow ({largest} terms: {rows_cap} regression "
             "rows): the model interpolates the record rather than being chosen by the criterion; use a longer "
             "record, fewer candidates, or give n_terms", RuntimeWarning)
    return i, f"{rule.criterion} minimum at {sizes[i]} of {largest} sizes"


def _exact(unexplained: np.ndarray, round_off: float | np.ndarray) -> np.ndarray:
    """(M,) whether each model is at its round-off floor (to its rounding): an exact fit. A floor of 1 (rss_floor's
    yᵀy: parameters too large for any digit of y to survive) is no exact fit: that model explains nothing."""
    floor = np.broadcast_to(np.asarray(round_off, dtype=float), unexplained.shape)
    return (unexplained <= floor * (1.0 + 1e-9)) & (floor < 1.0)
