"""One-step-ahead prediction and free-run simulation with validation at the boundary.

Conventions (shared by the evaluator): a structure with largest lag L uses the
first L measured samples as initial conditions; outputs are returned at full
length N with those L samples copied from the data, and every error measure counts
samples L … N-1 only.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from ._simulation_kernels import (BOUND_FACTOR, encode, predict_ahead, record_inputs, scaled_bound, simulate_batch,
                                 simulate_one)
from ._records import Dataset, Record, as_input_array, is_frame, record_hint, require_record
from ._terms import carried_input_names, check_input_names, default_input_names, require_inputs
from ._validation import as_1d_finite, check_choice, check_finite_rows, check_int, check_real, check_theta, real_array
from ._regressors import regressor_columns
from ._least_squares import binary_scaled, scaled_theta
from ._terms import Structure, structure_of

__all__ = ["predict", "simulate", "simulate_many", "DivergenceError", "free_run_inputs", "default_bound",
           "check_fitted_record"]


class DivergenceError(ValueError):
    """A free run left every reasonable bound (the model is unstable along this input)."""


def check_fitted_record(given: object, record: object) -> None:
    """``ValueError`` when ``given`` (the structure argument) is a model, or a set or result that carries one, that
    knows the period and units its θ hold in (its ``check_record``) and ``record`` is at another period or in other
    units: refused as the model's own methods, js and evaluate_thetas refuse it, not run with parameters that do not
    hold there. Anything else (a Structure, terms; an array of inputs) is not checked."""
    fitted = given if callable(getattr(given, "check_record", None)) else getattr(given, "model", None)
    if isinstance(record, Record) and callable(getattr(fitted, "check_record", None)):
        fitted.check_record(record)


def predict(structure: Structure, theta: np.ndarray, record: Record, *, horizon: int = 1) -> np.ndarray:
    """Prediction ``horizon`` steps ahead from measured data (one step: ŷ(k) = ψ(k)ᵀθ).

    Parameters
    ----------
    structure : Structure, sequence of str, or a model
        Process terms (a model, or a result with ``.structure``, gives its own, and refuses a record
        sampled at another period or in other units than its own).
    theta : ndarray, shape (n_terms,)
    record : Record
        Measured input(s) and output; every input the structure uses must be among the
        record's ``input_names``.
    horizon : int >= 1, keyword-only
        Samples ahead. ŷ(k) is the model run freely from the outputs measured up to
        k − horizon (never before the record's first ``max_lag`` samples) and driven by the
        measured inputs: 1 (default) is the one-step prediction J_1 scores; a horizon of the
        record's length is the free run J_S scores. Between them it shows how fast a model's
        error grows from a measured state, e.g. a start-up transient a free run from rest
        never meets.

    Returns
    -------
    ndarray, shape (N,)
        ŷ in the output's units; the first ``max_lag`` samples are the measured ones. From
        horizon 2 on, NaN where the run behind a prediction leaves :func:`simulate`'s default
        bound (from the measured outputs that run starts from and the record's inputs); one step
        ahead, NaN only where the prediction itself leaves the float range.
    """
    require_record(record, call="model.predict(r)")  # a Dataset: told to pass data.ident or data.valid
    check_fitted_record(structure, record)
    structure = structure_of(structure)
    th = check_theta(len(structure), theta)
    horizon = check_int(horizon, "horizon", low=1)
    L = structure.max_lag
    record.require_length(L)
    if horizon == 1:
        yhat = record.y.copy()
        # on u and y times powers of two where a term's column nears the float range's ends (exact, as the estimators
        # fit): y(k-1)² of y ≈ 1e-200 (1e-400, no float) was dropped, 17% of the output off, and of y ≈ 1e200 NaN
        (scaled,), exps = binary_scaled([record], structure)
        ths = scaled_theta(th, structure, exps) if exps else th
        # a prediction beyond the float range was inf − inf with numpy's warnings: NaN
        with np.errstate(over="ignore", invalid="ignore"):
            one = regressor_columns(structure, scaled.u, scaled.y, start=L, input_names=scaled.input_names) @ ths
            one = np.ldexp(one, exps["y"]) if exps else one
        yhat[L:] = np.where(np.isfinite(one), one, np.nan)
        return yhat
    code = encode(structure, record.input_names)
    # simulate's bound, each run's from the measured outputs it starts from: a horizon of the record's length is
    # the free run from the first max_lag samples
    return predict_ahead(code, th, record_inputs(record, code.input_names), record.y, L, min(horizon, len(record)),
                         None)


def default_bound(y0: np.ndarray, scale: float = 0.0) -> float:
    """A divergence bound on |y| in output units: :data:`BOUND_FACTOR` × max(max|y0|, ``scale``).

    ``scale`` is what the model says of its output's size (a network's output range); where both
    are 0 only an overflow counts (the largest float). A polynomial model's free run applies the
    same rule sample by sample in its kernel (:func:`~graybox.core._simulation_kernels.simulate_one`),
    its scale the larger of its feedback scale and the level its inputs' push so far holds the output at
    (:func:`~graybox.core._simulation_kernels.push_gain`).
    """
    return float(scaled_bound(max(float(np.max(np.abs(y0), initial=0.0)), float(scale))))


def free_run_inputs(
    u: np.ndarray | Record, y0: np.ndarray | None, L: int, bound: float | None, what: str = "structure",
    names: tuple[str, ...] | None = None,
) -> tuple[np.ndarray, np.ndarray, float | None]:
    """Validate a free run's input and initial conditions (shared by every model kind).

    Parameters
    ----------
    u : ndarray, shape (N,) or (N, m), or Record
        Input(s); with a Record, ``y0`` defaults to its first ``L`` outputs.
    y0 : ndarray, shape (>= L,), optional
        Initial outputs; only the first ``L`` are used.
    L : int
        Number of initial conditions (the model's max lag).
    bound : float or None
        Divergence bound on |y|, checked; None (the model's default) is returned as None.
    what : str
        What needs the lags, for messages ("structure", "network").
    names : tuple of str, optional
        The inputs' names in the order of an array's columns: a DataFrame ``u`` is read by them
        (:func:`~graybox.core._records.frame_inputs`).

    Returns
    -------
    u : ndarray, shape (N,) or (N, m), contiguous
    y0 : ndarray, shape (L,), contiguous
    bound : float or None
    """
    if isinstance(u, Record):  # already validated
        if len(u) < L + 1:  # named as the record it is: "y0 has 1 samples" spoke of an argument never passed
            raise ValueError(f"{u.name}: record has {len(u)} samples, fewer than max lag + 1 = {L + 1} (the {what} "
                             f"needs max lag = {L})")
        if y0 is None:  # a record's outputs are finite, 1-D, read-only and contiguous already: no copy, no check
            b = None if bound is None else check_real(bound, "bound", low=0, low_open=True)
            return np.ascontiguousarray(u.u), np.ascontiguousarray(u.y[:L]), b
        u = u.u
    else:
        # "u must be an array of numbers" said nothing of which record to pass, nor where a DaskRecord is taken
        several = isinstance(u, (tuple, list)) and bool(u) and all(isinstance(r, Record) for r in u)
        if isinstance(u, Dataset) or type(u).__name__ == "DaskRecord" or several:  # by name: core._gram imports this
            raise TypeError(f"u must be a Record or an array of inputs, got {type(u).__name__}"
                            f"{record_hint(u, 'model.simulate(r)')}"
                            # graybox.simulate shares this path and its caller may hold no model
                            + (" (graybox.simulate: simulate(structure, theta, r) for each)"
                               if several and what == "structure" else ""))
        u = as_input_array(u, "u", names)
        if y0 is None:
            if L > 0:
                raise ValueError("y0 (the first max-lag outputs) is required when u is an array")
            y0 = np.zeros(0)  # no lags: no initial outputs
    y0 = real_array(y0, "y0", "an array of the first max-lag outputs (numbers)")  # text, None, booleans: TypeError
    if y0.ndim != 1:
        raise ValueError(f"y0 must be 1-D (the first max-lag outputs), got shape {y0.shape}")
    if y0.size < L:
        raise ValueError(f"y0 has {y0.size} samples, the {what} needs max lag = {L}")
    y0 = as_1d_finite(y0[:L], "y0")
    if u.shape[0] < L + 1:
        raise ValueError(f"input has {u.shape[0]} samples, fewer than max lag + 1 = {L + 1}")
    b = None if bound is None else check_real(bound, "bound", low=0, low_open=True)
    return np.ascontiguousarray(u), np.ascontiguousarray(y0), b


def simulate(
    structure: Structure,
    theta: np.ndarray,
    u: np.ndarray | Record,
    y0: np.ndarray | None = None,
    *,
    on_diverge: Literal["raise", "nan"] = "raise",
    bound: float | None = None,
    input_names: tuple[str, ...] | None = None,
) -> np.ndarray:
    """Free-run simulation: the model feeds back its own past outputs.

    Parameters
    ----------
    structure : Structure, sequence of str, or a model
        Process terms (noise terms are not simulated; a model, or a result with ``.structure``,
        gives its own, its input order for an array ``u``, and refuses a Record sampled at another period
        or in other units than its own).
    theta : ndarray, shape (n_terms,)
    u : ndarray or pandas.DataFrame, shape (N,) or (N, m), or Record
        Input(s). With a Record, ``y0`` defaults to its first ``max_lag`` outputs and the
        inputs are taken by name. A DataFrame whose columns are the inputs (``input_names``, else
        the structure's inputs when a column names one of them, else ``u1 … um``) is read by name
        in any column order; one whose columns name none of them, by position; one whose columns
        name some of them is refused (``ValueError`` naming the columns).
    y0 : ndarray, shape (>= max_lag,), optional
        Initial outputs y(0) … y(L-1); only the first L = max_lag are used.
    on_diverge : {"raise", "nan"}
        When the output leaves ``bound``: raise :class:`DivergenceError` naming the sample,
        or return NaN from that sample on.
    bound : float, optional
        Divergence bound on |y|, output units. Default: at each sample k, 1e6 × the largest of
        max|y0|, max_j≤k G(j) |X(j)|, X the sum of the terms without y (the inputs' direct push on
        the output, and the constant) and G(j) the steady gain of the linear output feedback at
        sample j's inputs (1 / (1 − c(j)), c(j) the sum of the coefficients of the single past
        outputs y(j−l), input-dependent terms θ y(j−l) u(j−i) included, where that lies in (0, 1),
        else 1: the level a constant push holds a stable slow plant at; and at least Π 1 / (1 − |p|)
        over the poles p of the stable linear feedback, the level any push holds it within, a
        resonance driven at its frequency too: of the constant feedback, or, where input-dependent
        terms feed back and no single past output lies beyond lag 2, of the feedback at sample j's
        inputs, to within a factor 4; 1 where that has a pole on or outside the unit circle), and
        the size at which the model's nonlinear output feedback matters (a limit cycle's scale), so
        it does not depend on the output's units, also for a run from rest (y0 = 0).
    input_names : tuple of str, optional
        Names of the columns of an array ``u`` (default: a model's own ``input_names``, else ``"u"``
        for 1-D, ``u1 … um`` for (N, m)); ignored for a Record, which names its inputs.

    Returns
    -------
    ndarray, shape (N,)
    """
    check_fitted_record(structure, u)  # a model's θ hold at its period, in its units
    carried = carried_input_names(structure)
    if input_names is None and carried is not None and len(carried) > 1:
        input_names = carried  # a model's array is read in its own column order, as Model.simulate reads it
    structure = structure_of(structure)
    th = _checked_theta(len(structure), theta)
    check_choice(on_diverge, "on_diverge", ("raise", "nan"))
    L = structure.max_lag
    if isinstance(u, Record):  # validated already: no copy
        code = encode(structure)
        _, y0, b = free_run_inputs(u, y0, L, bound)
        uu = record_inputs(u, code.input_names)
    else:
        cols = [str(c) for c in u.columns] if input_names is None and is_frame(u) else []
        if cols and sorted(cols) != sorted(default_input_names(len(cols))) and any(c in structure.input_names for c in cols):
            # a DataFrame naming the structure's inputs is read by those names (refused, naming its columns, where it
            # names some and not others): by position its named columns were said to be u1 … um. Columns with the
            # default names (any order) are read by them, as before (a structure in u2 alone reads the frame's u2)
            input_names = structure.input_names
        uu, y0, b = free_run_inputs(u, y0, L, bound, names=input_names)
        code, uu = _inputs_for(structure, uu, input_names)
    y = simulate_one(code, th, uu, y0, L, b)
    if on_diverge == "raise" and not np.isfinite(y[-1]):
        k = int(np.flatnonzero(~np.isfinite(y))[0])
        limit = f"{b:g}" if b is not None else (f"{BOUND_FACTOR:g} × the run's own scale: its initial outputs, the level "
                                                 "the inputs' direct push so far holds it at and the model's output "
                                                 "feedback")
        raise DivergenceError(f"free run diverged at sample {k} (|y| > {limit}): the model is unstable along this input")
    return y


def simulate_many(
    structure: Structure,
    thetas: np.ndarray,
    record: Record,
    *,
    threads: int = 1,
) -> np.ndarray:
    """Free runs of many parameter vectors of one structure over one record.

    Parameters
    ----------
    structure : Structure, sequence of str, or a model
        Process terms (a model, or a result with ``.structure``, gives its own, and refuses a record
        sampled at another period or in other units than its own).
    thetas : ndarray, shape (P, n_terms)
        Finite: a row with a NaN or inf is no model, and is refused naming it (``ValueError``).
    record : Record
        Input and initial outputs (its first ``max_lag`` samples).
    threads : int
        Parallel blocks of the population (numba threads).

    Returns
    -------
    ndarray, shape (P, N)
        A diverging member has non-finite samples; this never raises for divergence.
    """
    threads = check_int(threads, "threads", low=1)
    require_record(record)  # a Dataset: told to pass data.ident or data.valid
    check_fitted_record(structure, record)
    structure = structure_of(structure)
    # the one conversion of numbers (text, booleans, None: TypeError; beyond the float range: ValueError)
    th = real_array(thetas, "thetas", "parameter vectors (numbers), shape (P, n_terms)")
    if th.ndim != 2 or th.shape[1] != len(structure):
        raise ValueError(f"thetas must have shape (P, {len(structure)}), got {th.shape}")
    check_finite_rows(th, "thetas")  # a NaN θ is no model: its run was all NaN, as if it diverged
    L = structure.max_lag
    record.require_length(L)
    code = encode(structure)
    return simulate_batch(code, th, record_inputs(record, code.input_names), record.y[:L], L, threads, bounded=True)


def _checked_theta(n_terms: int, theta: object) -> np.ndarray:
    """θ as :func:`check_theta` gives it, without its conversions where ``theta`` already is a finite float64 vector
    of ``n_terms`` values (a model's own, 6 µs of a 50 µs free run); anything else goes through check_theta."""
    if (type(theta) is np.ndarray and theta.dtype == np.float64 and theta.shape == (n_terms,)
            and np.isfinite(theta).all()):
        return theta
    return check_theta(n_terms, theta)


def _inputs_for(structure: Structure, u: np.ndarray, input_names: object):
    """The kernel code of ``structure`` and the validated input array ``u`` (N,) or (N, m) it reads."""
    a = u
    m = 1 if a.ndim == 1 else a.shape[1]
    names = default_input_names(m) if input_names is None else check_input_names(input_names, m, "input_names")
    if m == 1:
        # one column feeds the structure's one input whatever its name, unless named otherwise
        if len(structure.input_names) > 1 or (input_names is not None and structure.input_names
                                         and structure.input_names[0] != names[0]):
            raise ValueError(f"u has one input column ({names[0]!r}) but the structure uses the inputs "
                             f"{structure.input_names}; pass u of shape (N, m) and its input_names")
        return encode(structure), a
    require_inputs(structure.input_names, names, f"but u's {m} columns are the inputs")
    return encode(structure, names), a
