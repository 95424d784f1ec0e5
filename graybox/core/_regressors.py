"""The regressor matrix Ψ of a structure over one or more records (vectorised).

Row ``r`` of Ψ holds the terms evaluated at sample ``k = start + r`` of a record,
from measured data (one-step-ahead form, eq. (10)). Rows never straddle two
records: with several records the blocks are stacked.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ._records import Record, as_input_array, as_records, require_lengths
from ._terms import Structure, check_input_names, missing_input_hint, structure_of
from ._validation import as_1d_finite, check_int, check_sequence

__all__ = ["record_signals", "check_structure_inputs", "check_record_inputs", "refuse_non_finite_columns",
           "input_signals", "regressor_matrix", "regressor_columns", "stacked_regressors"]


def record_signals(record: Record) -> dict[str, np.ndarray]:
    """The measured signals of a record by the names terms use for them, each shape (N,).

    The one place that maps a record onto term signal names; every builder of regressor
    columns takes its signals from here. Each input appears under its name (``"u"`` for a
    single unnamed input, ``"u1"``, ``"u2"``, … or the record's ``input_names``).
    """
    if record.u.ndim == 1:
        out = {record.input_names[0]: record.u}
    else:
        out = {n: record.u[:, i] for i, n in enumerate(record.input_names)}
    out["y"] = record.y
    return out


def check_structure_inputs(structure: Structure, records: Sequence[Record]) -> None:
    """``ValueError`` naming an input a term of ``structure`` uses that a record lacks, or a record too short.

    Too short: not more samples than the structure's largest lag (e.g. an input delay beyond the record).
    """
    require_lengths(records, structure.max_lag)
    check_record_inputs(structure.input_names, records)


def check_record_inputs(inputs: Sequence[str], records: Sequence) -> None:
    """``ValueError`` naming an input of ``inputs`` (the ones the terms use) that a record (a Record or a DaskRecord,
    anything with ``name`` and ``input_names``) lacks, with how to give them it (:func:`missing_input_hint`)."""
    for r in records:
        missing = [n for n in inputs if n not in r.input_names]
        if missing and type(r).__name__ == "DaskRecord":  # by name: core._gram imports this module
            # the hint for a Record (Record(..., input_names=[...])) is no way to name a DaskRecord's input
            raise ValueError(f"{r.name}: the terms use input {missing[0]!r}, but the record's inputs are ('u',): a "
                             "DaskRecord holds one input, named 'u' (it takes no input_names): write the terms with u, "
                             "e.g. Candidates(ny, nu) without input names, or reduce a Record of the named inputs in "
                             "memory")
        if missing:
            raise ValueError(f"{r.name}: the terms use input {missing[0]!r}, but the record's inputs are "
                             f"{r.input_names}{missing_input_hint(tuple(inputs), r.input_names)}")


def refuse_non_finite_columns(columns: np.ndarray, terms: Sequence, what: str = "") -> None:
    """``ValueError`` naming the terms whose columns (regressors, shape (N, n)) hold non-finite values: on finite
    data, an overflow of a high power of a large u or y. Build the columns under ``np.errstate(over="ignore",
    invalid="ignore")``: this names the terms where numpy's RuntimeWarning would not."""
    bad = np.flatnonzero(~np.all(np.isfinite(columns), axis=0))
    if bad.size:
        raise ValueError(f"{what}regressors overflow to non-finite values on these data (e.g. "
                         f"{', '.join(str(terms[j]) for j in bad[:5])}): a high power of u or y beyond the floating "
                         "point range; rescale the signals (other units) and estimate again")


def input_signals(u: np.ndarray, input_names: tuple[str, ...] | None = None) -> dict[str, np.ndarray]:
    """Input columns by name: ``u`` of shape (N,) (one input, default name ``"u"``) or (N, m)."""
    if u.ndim == 1:
        if input_names is not None and len(input_names) != 1:  # else u was silently taken as the first of them
            raise ValueError(f"u has one input column (shape {u.shape}) but {len(input_names)} input names "
                             f"{tuple(input_names)} were given: give u one column per input, shape ({u.shape[0]}, "
                             f"{len(input_names)})")
        return {"u" if input_names is None else input_names[0]: u}
    names = tuple(f"u{i}" for i in range(1, u.shape[1] + 1)) if input_names is None else tuple(input_names)
    if len(names) != u.shape[1]:
        raise ValueError(f"u has {u.shape[1]} input columns but {len(names)} input names {names} were given")
    return {n: u[:, i] for i, n in enumerate(names)}


def regressor_matrix(
    structure: Structure,
    u: np.ndarray,
    y: np.ndarray,
    *,
    e: np.ndarray | None = None,
    start: int | None = None,
    input_names: tuple[str, ...] | None = None,
) -> np.ndarray:
    """Evaluate every term of ``structure`` at samples ``k = start … N-1``.

    Parameters
    ----------
    structure : Structure, sequence of str, or a model
        The terms, in column order (a Model, a Selection … gives its ``.structure``).
    u : ndarray, shape (N,) or (N, m)
        Input samples, one column per input (a list or a DataFrame too, converted as a :class:`Record`'s).
    y : ndarray, shape (N,)
        Output samples, finite.
    e : ndarray, shape (N,), optional
        Residuals for noise terms ``e(k-l)``; required when the structure has any.
    start : int, optional
        First sample to evaluate; defaults to ``structure.max_lag`` and must not be smaller.
    input_names : tuple of str, optional
        Names of the columns of ``u`` (default ``"u"`` for 1-D ``u``, else ``u1 … um``).

    Returns
    -------
    ndarray, shape (N - start, len(structure))
        Ψ, float64, C-contiguous, finite.

    Raises
    ------
    ValueError
        Data that are no record (a bad shape, non-finite samples, too few samples for ``start``), a term whose
        signal the data lack, or a term whose product leaves the float range on these data (``y(k-1)^2`` of y
        near 1e200), named.
    """
    structure = structure_of(structure)  # terms, or what carries a structure (a Model, a Selection)
    psi = regressor_columns(structure, u, y, e=e, start=start, input_names=input_names)
    # a term's product beyond the float range (y ~ 1e200, y(k-1)^2) was an inf column with numpy's overflow warning
    refuse_non_finite_columns(psi, structure)
    return psi


def regressor_columns(
    structure: Structure,
    u: np.ndarray,
    y: np.ndarray,
    *,
    e: np.ndarray | None = None,
    start: int | None = None,
    input_names: tuple[str, ...] | None = None,
) -> np.ndarray:
    """:func:`regressor_matrix` with a term beyond the float range left as it comes (±inf or NaN in its column, no
    numpy warning): for one-step predictions, where such a prediction is NaN, and scores, where it is inf."""
    structure = structure_of(structure)  # terms, or what carries a structure (a Model, a Selection)
    names = None if input_names is None else check_input_names(input_names)
    # a public entry: lists, text or None were an AttributeError ('list' object has no attribute 'shape'), a u
    # shorter than y numpy's broadcast error, NaN a silent NaN column. A Record's arrays pass the checks as they are
    if not (isinstance(y, np.ndarray) and y.dtype == np.float64 and y.ndim == 1 and np.isfinite(y).all()):
        y = as_1d_finite(y, "y")
    # one input as a column (N, 1) goes through the coercion, which reads it as a Record does (the one input, 1-D):
    # taken as it is it was input 'u1', and the same samples as a list input 'u'
    if not (isinstance(u, np.ndarray) and u.dtype == np.float64 and (u.ndim == 1 or (u.ndim == 2 and u.shape[1] != 1
                                                                                    and u.shape[0] >= u.shape[1]))
            and np.isfinite(u).all()):  # fewer samples than inputs: inputs as rows, said by the coercion
        # shown the output, as Record's is: y's samples settle which of u's axes are the samples
        u = as_input_array(u, "u", names, output=y)
    n = y.shape[0]
    if u.shape[0] != n:
        raise ValueError(f"u has {u.shape[0]} samples but y has {n}: one input sample per output sample")
    s = structure.max_lag if start is None else check_int(start, "start", low=0)
    if s < structure.max_lag:
        raise ValueError(f"start ({s}) is smaller than the structure's max lag ({structure.max_lag})")
    if n < s + 1:
        first = "max lag + 1" if start is None else f"start + 1 (start = {s}, the structure's max lag {structure.max_lag})"
        raise ValueError(f"record has {n} samples, fewer than {first} = {s + 1}")
    signals = input_signals(u, names)
    signals["y"] = y
    if e is not None:
        signals["e"] = as_1d_finite(e, "e")
        if signals["e"].size != n:
            raise ValueError(f"e has {signals['e'].size} samples, y has {n}")
    rows = n - s
    psi = np.empty((rows, len(structure)))
    with np.errstate(over="ignore", invalid="ignore"):  # a product beyond the float range: the caller names it
        _fill_columns(psi, structure, signals, s, n)
    return psi


def _fill_columns(psi: np.ndarray, structure: Structure, signals: dict[str, np.ndarray], s: int, n: int) -> None:
    """Ψ's columns, in place: each term's product of lagged signals at k = s … n−1."""
    rows = n - s
    for j, term in enumerate(structure):
        col = np.ones(rows)
        for sig, lag, power in term.factors:
            if sig not in signals:
                what = "input" if sig not in ("y", "e") else "signal"
                have = tuple(k for k in signals if k not in ("y", "e"))
                used = structure.input_names
                raise ValueError(f"term {term} needs {what} {sig!r}, which the data do not have (inputs: {have})"
                                 f"{missing_input_hint(used, have) if what == 'input' else ''}")
            x = signals[sig][s - lag : n - lag]
            col *= x if power == 1 else x**power
        psi[:, j] = col


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
    structure : Structure, sequence of str, or a model
        The terms, in column order (a Model, a Selection … gives its ``.structure``).
    records : Record or sequence of Record
    start : int, optional
        First sample of each record (default: the structure's max lag).
    residuals : sequence of ndarray, each of shape (N_r,), optional
        One residual series per record (output units), for noise terms.

    Returns
    -------
    psi : ndarray, shape (sum(N_r - start), n_terms)
    target : ndarray, shape (sum(N_r - start),)
        The measured ``y(k)`` matching each row.
    """
    structure = structure_of(structure)  # terms, or what carries a structure (a Model, a Selection)
    recs = as_records(records, name="records")  # the argument's own name in the message
    s = structure.max_lag if start is None else check_int(start, "start", low=0)
    if residuals is not None:
        residuals = check_sequence(residuals, "residuals", "a sequence of residual series, one per record")
        if len(residuals) != len(recs):
            raise ValueError(f"residuals has {len(residuals)} series for {len(recs)} record(s): give one per record")
    blocks, targets = [], []
    require_lengths(recs, s)
    for i, r in enumerate(recs):
        e = None if residuals is None else residuals[i]
        blocks.append(regressor_matrix(structure, r.u, r.y, e=e, start=s, input_names=r.input_names))
        targets.append(r.y[s:])
    return np.vstack(blocks), np.concatenate(targets)
