"""The regressor matrix Ψ of a structure over one or more records (vectorised).

Row ``r`` of Ψ holds the terms evaluated at sample ``k = start + r`` of a record,
from measured data (one-step-ahead form, eq. (10)). Rows never straddle two
records: with several records the blocks are stacked.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ._records import Record, as_records
from ._terms import Structure

__all__ = ["record_signals", "regressor_matrix", "stacked_regressors"]


def record_signals(record: Record) -> dict[str, np.ndarray]:
    """The measured signals of a record by the names terms use for them, each shape (N,).

    The one place that maps a record onto term signal names; every builder of regressor
    columns takes its signals from here.
    """
    return {"u": record.u, "y": record.y}


def regressor_matrix(
    structure: Structure,
    u: np.ndarray,
    y: np.ndarray,
    *,
    e: np.ndarray | None = None,
    start: int | None = None,
) -> np.ndarray:
    """Evaluate every term of ``structure`` at samples ``k = start … N-1``.

    Parameters
    ----------
    structure : Structure
        The terms, in column order.
    u, y : ndarray, shape (N,)
        Input and output samples (assumed validated, e.g. from a :class:`Record`).
    e : ndarray, shape (N,), optional
        Residuals for noise terms ``e(k-l)``; required when the structure has any.
    start : int, optional
        First sample to evaluate; defaults to ``structure.max_lag`` and must not be smaller.

    Returns
    -------
    ndarray, shape (N - start, len(structure))
        Ψ, float64, C-contiguous.
    """
    n = u.shape[0]
    s = structure.max_lag if start is None else int(start)
    if s < structure.max_lag:
        raise ValueError(f"start ({s}) is smaller than the structure's max lag ({structure.max_lag})")
    if n < s + 1:
        raise ValueError(f"record has {n} samples, fewer than max lag + 1 = {s + 1}")
    signals = {"u": u, "y": y}
    if e is not None:
        signals["e"] = e
    rows = n - s
    psi = np.empty((rows, len(structure)))
    for j, term in enumerate(structure):
        col = np.ones(rows)
        for sig, lag, power in term.factors:
            if sig not in signals:
                raise ValueError(f"term {term} needs signal {sig!r}, which was not given")
            x = signals[sig][s - lag : n - lag]
            col *= x if power == 1 else x**power
        psi[:, j] = col
    return psi


def stacked_regressors(
    structure: Structure,
    records: Record | Sequence[Record],
    *,
    start: int | None = None,
    residuals: Sequence[np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Ψ and the target vector over one or several records, stacked per record.

    Parameters
    ----------
    structure : Structure
    records : Record or sequence of Record
    start : int, optional
        First sample of each record (default: the structure's max lag).
    residuals : sequence of ndarray, optional
        One residual series per record, for noise terms.

    Returns
    -------
    psi : ndarray, shape (sum(N_r - start), n_terms)
    target : ndarray, shape (sum(N_r - start),)
        The measured ``y(k)`` matching each row.
    """
    recs = as_records(records)
    s = structure.max_lag if start is None else int(start)
    blocks, targets = [], []
    for i, r in enumerate(recs):
        r.require_length(s)
        e = None if residuals is None else residuals[i]
        blocks.append(regressor_matrix(structure, r.u, r.y, e=e, start=s))
        targets.append(r.y[s:])
    return np.vstack(blocks), np.concatenate(targets)
