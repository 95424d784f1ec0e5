"""One evaluator shared by every estimator, notebook and the CLI.

Error measures (all mean squared errors in output units², as in the paper's Table I):

- ``J_1``: one-step-ahead prediction error,
- ``J_S``: free-run simulation error (initial conditions: the first max-lag measured samples),
- ``J_SF``: static-function error at the static points,
- ``RRSE`` = ‖y − ŷ‖ / ‖y − mean(y)‖ and ``fit %`` = 100 (1 − RRSE) of the free run, as MATLAB's
  ``compare`` defines it.

Dynamic errors are counted from sample ``max_lag`` on (the samples before are initial
conditions copied from the data, so their error is zero by construction). A free run that
diverges has J_S = inf. J_SF counts, at each static point (ū_i, ȳ_i), the equilibrium the model
actually reaches: the one a free run at constant ū_i, started with every initial condition equal
to the measured ȳ_i, settles on (:func:`graybox.static._analysis.reached_equilibria`). A point where it
settles on none (no stable equilibrium, the run diverges or does not settle) makes J_SF = inf,
with a warning naming ū and why. Neither is a made-up number: both errors are unbounded.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Mapping, Sequence

import numpy as np

from ..core._least_squares import CONSTANT_RTOL, mean_square, output_spread, scaled_norm  # noqa: F401 (home: core)
from ..core._least_squares import binary_exponent, binary_scaled, scaled_points, scaled_theta
from ..core._simulation_kernels import batch_sse, encode, record_inputs
from ._model import Model
from ._coerce import as_model, as_record, as_structure, static_info
from ..core._regressors import regressor_columns
from ..core._records import Dataset, Record, StaticPoints, static_point_inputs
from ..core._simulation import DivergenceError
from ..core._validation import (as_1d_finite, check_bool, check_finite_rows, check_int, check_per_point, check_sequence,
                                real_array, warn)
from ..static._analysis import reached_equilibria
from ..static._surface_analysis import reached_surface
from ..core._terms import Structure

if TYPE_CHECKING:  # pandas takes ~0.4 s to import: loaded where a table is made
    import pandas as pd

__all__ = ["mse", "j1", "js", "jsf", "rrse", "fit_percent", "evaluate"]


def _measured_and_model(y: object, yhat: object, start: object) -> tuple[np.ndarray, np.ndarray]:
    """``y[start:]`` (measured: finite) and ``yhat[start:]`` (a model's: inf/NaN where it diverged), 1-D, one length."""
    start = check_int(start, "start", low=0)
    y = as_1d_finite(y, "y")
    # the shared coercion, not numpy's: that parses text, reads True as 1 and None as NaN (a "diverged" run)
    yhat = real_array(yhat, "yhat", "the model's output (numbers; NaN or inf where its free run diverged)")
    if yhat.shape != y.shape:
        raise ValueError(f"y and yhat must have the same length, got shapes {y.shape} and {yhat.shape}")
    if start >= y.size:  # every figure alike (RRSE and fit % took the empty rest for a constant output)
        raise ValueError(f"no samples left to evaluate: start = {start} of a record of {y.size} samples")
    return y[start:], yhat[start:]


#: The Parameters section of the scores of a measured output against a model's (:func:`mse`, :func:`rrse`,
#: :func:`fit_percent`): one text, put in each docstring by :func:`_scores_samples`.
_Y_YHAT_START = """Parameters
    ----------
    y : ndarray, shape (N,)
        The measured output (finite; output units).
    yhat : ndarray, shape (N,)
        The model's output on the same samples (NaN or inf where its free run diverged).
    start : int
        The first sample counted (default 0; a model's largest lag, as :func:`js` counts); ``start < N``."""


def _scores_samples(fn):
    """Put the shared Parameters section into ``fn``'s docstring (its marker line)."""
    fn.__doc__ = fn.__doc__.replace("__Y_YHAT_START__", _Y_YHAT_START)
    return fn


@_scores_samples
def mse(y: np.ndarray, yhat: np.ndarray, *, start: int = 0) -> float:
    """Mean squared error of ``yhat`` against ``y`` over samples ``start …``; inf if ŷ is not finite.

    __Y_YHAT_START__

    Returns
    -------
    float
        mean((y − ŷ)²) over samples start … N − 1, output units²; inf where ŷ is not finite.

    Raises
    ------
    ValueError
        ``y`` and ``yhat`` of different lengths, a ``y`` that is not finite, ``start`` negative or at least N.
    """
    y, yhat = _measured_and_model(y, yhat, start)
    with np.errstate(over="ignore"):  # an error beyond the float range is inf, and says so (numpy's warning did not)
        e = y - yhat
        if not np.all(np.isfinite(e)):
            return float("inf")
    # over the power of two above max|e| (exact): errors about 2^512 overflowed when squared, where their mean square
    # (about 2^1018) is a float
    return float(mean_square(e))


def j1(model: Model, record: Record | Dataset) -> float:
    """J_1: one-step-ahead prediction MSE of ``model`` over ``record`` (samples max_lag … N-1).

    Parameters
    ----------
    model : Model, NeuralModel, or a result that carries one in ``.model``
        The model to score (an ELSResult, CLSResult, Decision, DSFResult … stands for its model).
    record : Record or Dataset
        Measured data; a Dataset stands for its validation record (a model is judged on data it
        was not fitted on).

    Returns
    -------
    float
        mean((y(k) − ŷ(k|k−1))²) over samples max_lag … N − 1, output units²; inf where the prediction is not
        finite.
    """
    model = as_model(model, duck=("predict", "max_lag"))
    record = as_record(record, "valid", "record", call="j1(model, r)")
    return mse(record.y, model.predict(record), start=model.max_lag)


def js(model: Model, record: Record | Dataset) -> float:
    """J_S: free-run simulation MSE of ``model`` over ``record`` (inf when the run diverges).

    Parameters
    ----------
    model : Model, NeuralModel, or a result that carries one in ``.model``
        The model to score.
    record : Record or Dataset
        Measured data; a Dataset stands for its validation record.

    Returns
    -------
    float
        mean((y − ŷ_s)²) over samples max_lag … N − 1 of the free run ŷ_s, output units²; inf when the run
        diverges.
    """
    model = as_model(model, duck=("simulate", "max_lag"))
    record = as_record(record, "valid", "record", call="js(model, r)")
    return mse(record.y, model.simulate(record, on_diverge="nan"), start=model.max_lag)


def jsf(model: Model, static: StaticPoints | Dataset, y0: float | np.ndarray | None = None) -> float:
    """J_SF: MSE of the model's static outputs at the static points, output units².

    At each static point (ū_i, ȳ_i) the model's static output is the equilibrium a free run at
    constant ū_i, started with every initial condition equal to ȳ_i, settles on. A locally stable
    equilibrium whose basin does not hold ȳ_i does not count. For a rational structure (no power
    of y above 1) that is the equilibrium of eq. (6) when it is stable, from any start.

    Parameters
    ----------
    model : Model, NeuralModel, or a result that carries one in ``.model``
        Anything with ``static_curve(ubar, y0=…, strict=True)``.
    static : StaticPoints or Dataset
        The measured static points (a Dataset's ``static``).
    y0 : float or ndarray of shape (M,), optional
        Initial output of the runs (default: the measured ȳ_i).

    Returns
    -------
    float
        inf, with a ``RuntimeWarning`` naming each ū where no equilibrium is reached and why,
        when the model settles on none at some point.
    """
    model = as_model(model, duck="static_curve")
    static = static_info(None if isinstance(static, Dataset) else static, static, needed_by="jsf")
    if hasattr(model, "check_record"):
        model.check_record(static)  # points in other units than the model's are refused, not scored
    names = getattr(model, "input_names", ("u",))
    ub = static_point_inputs(static, names)
    if y0 is not None:  # checked here: a bad y0 must not pass for a model without an equilibrium
        y0 = check_per_point(y0, len(static), "y0")  # several inputs: ū's columns by the model's input names
    try:
        yb = model.static_curve(ub, y0=static.ybar if y0 is None else y0, strict=True)
    except (ValueError, DivergenceError) as exc:
        warn(f"J_SF of {getattr(model, 'name', '') or 'model'} is infinite: {exc}", RuntimeWarning)
        return float("inf")
    return mse(static.ybar, yb)


@_scores_samples
def rrse(y: np.ndarray, yhat: np.ndarray, *, start: int = 0) -> float:
    """Root relative squared error ‖y − ŷ‖ / ‖y − mean(y)‖ over samples ``start …``.

    __Y_YHAT_START__

    Returns
    -------
    float
        Dimensionless (0: a perfect output, 1: no better than the measured mean); inf where ŷ is not finite.

    Raises
    ------
    ValueError
        As :func:`mse`, and for a measured output that is constant over the samples counted (no spread to
        compare with).
    """
    return _relative_error(y, yhat, start, "RRSE")


def _relative_error(y: object, yhat: object, start: object, what: str) -> float:
    """:func:`rrse`, its errors naming ``what`` the user called (fit_percent is 100 (1 − RRSE))."""
    y, yhat = _measured_and_model(y, yhat, start)
    if not np.all(np.isfinite(yhat)):
        return float("inf")
    # both norms over the power of two above max|y| (exact): near the float range's end y − ŷ overflowed (±1e308)
    e = binary_exponent(float(np.max(np.abs(y))))
    with np.errstate(over="ignore"):  # ŷ beyond y's scale by more than the float range: inf, its RRSE's float
        y, yhat = np.ldexp(y, -e), np.ldexp(yhat, -e)
    den = output_spread(y)
    if den == 0:
        raise ValueError(f"{what} undefined: the measured output is constant")
    with np.errstate(over="ignore"):  # ‖y − ŷ‖ beyond the float range: inf, as mse's (numpy warned)
        return float(scaled_norm(y - yhat) / den)  # in the output's own scale, as den is: the same in any units


@_scores_samples
def fit_percent(y: np.ndarray, yhat: np.ndarray, *, start: int = 0) -> float:
    """MATLAB ``compare`` fit: 100 (1 − ‖y − ŷ‖ / ‖y − mean(y)‖), in percent.

    __Y_YHAT_START__

    Returns
    -------
    float
        100 (1 − :func:`rrse`), percent (100: a perfect output; negative: worse than the measured mean); −inf
        where ŷ is not finite.

    Raises
    ------
    ValueError
        As :func:`rrse`.
    """
    return 100.0 * (1.0 - _relative_error(y, yhat, start, "fit_percent"))


def fit_or_nan(y: np.ndarray, yhat: np.ndarray, start: int) -> float:
    """:func:`fit_percent`, NaN where the measured output is held constant (the fit % is undefined there,
    the J_S of the same run is not): what a table of many models' figures keeps for such a record."""
    y = np.asarray(y, float)
    return fit_percent(y, yhat, start=start) if output_spread(y[start:]) > 0 else float("nan")


def evaluate(
    models: Mapping[str, object],
    data: Dataset,
    static: StaticPoints | None = None,
    y0: float | None = None,
    *,
    horizons: Sequence[int] = (),
) -> pd.DataFrame:
    """A table shaped like the paper's Table I.

    Parameters
    ----------
    models : mapping name -> Model
        Each value a Model, a NeuralModel, or a result that carries one in ``.model`` (an
        ELSResult, CLSResult, Decision, DSFResult …).
    data : Dataset
        Identification and validation records (and static points, unless ``static`` is given).
        A single Record is refused (the table has a column per record): score it with
        :func:`j1` and :func:`js`.
    static : StaticPoints, optional
        Static points for J_SF (default ``data.static``).
    y0 : float or ndarray of shape (M,), optional
        Initial output of the constant-input runs that define J_SF, output units: one for every static point or one
        per point (default: the measured ȳ_i).
    horizons : sequence of int >= 1, keyword-only
        Prediction horizons k (samples) to score on the validation record as well: a column
        ``J{k}_valid`` each, the MSE of the prediction k samples ahead (``model.predict(valid,
        horizon=k)``) from sample max_lag on; between J_1 (k = 1) and J_S (k = N). Default none.

    Returns
    -------
    pandas.DataFrame
        Index: model names. Columns: ``JS_ident``, ``JS_valid``, ``JSF``, ``n_params``,
        ``J1_ident`` (MSE in output units²), ``fit_valid`` (%, MATLAB's ``compare`` fit of the free run),
        then ``J{k}_valid`` for each horizon (output units²).
        ``fit_valid`` is NaN, with a ``RuntimeWarning``, when the validation output is constant
        (the fit % is undefined there).
    """
    import pandas as pd

    if not isinstance(data, Dataset):
        raise TypeError(f"data must be a Dataset (the table scores its ident and valid records); got "
                        f"{type(data).__name__}; score a single record with graybox.j1 and graybox.js")
    if not isinstance(models, Mapping):
        raise TypeError(f"models must be a mapping name -> model; got {type(models).__name__}")
    if not models:  # said here: the table of no model failed building its n_params column with a bare KeyError
        raise ValueError("models: an empty mapping; give at least one model to score (name -> model)")
    sp = static_info(static, data)
    horizons = sorted({check_int(k, "horizons", low=1) for k in check_sequence(horizons, "horizons", "a sequence of int")})
    rows = {}
    undefined_fit = []  # models whose fit % is undefined: the validation output is constant after their lags
    for name, m in models.items():
        m = as_model(m, f"models[{name!r}]", duck=("simulate", "predict", "max_lag", "n_params")
                     + (("static_curve",) if sp is not None else ()))
        sim_v = m.simulate(data.valid, on_diverge="nan")
        fit = fit_or_nan(data.valid.y, sim_v, m.max_lag)
        if np.isnan(fit):
            undefined_fit.append(name)
        rows[name] = {
            "JS_ident": js(m, data.ident),
            "JS_valid": mse(data.valid.y, sim_v, start=m.max_lag),
            "JSF": jsf(m, sp, y0) if sp is not None else float("nan"),
            "n_params": m.n_params,
            "J1_ident": j1(m, data.ident),
            "fit_valid": fit,
        } | {f"J{k}_valid": mse(data.valid.y, m.predict(data.valid, horizon=k), start=m.max_lag) for k in horizons}
    if undefined_fit:
        warn(f"fit_valid is NaN for {undefined_fit}: the validation output {data.valid.name!r} is constant, so the "
             "fit % (1 − ‖y − ŷ‖ / ‖y − mean y‖) is undefined; JS_valid scores the run", RuntimeWarning)
    df = pd.DataFrame.from_dict(rows, orient="index")
    df["n_params"] = df["n_params"].astype(int)
    return df


def evaluate_thetas(
    structure: Structure,
    thetas: np.ndarray,
    record: Record | Dataset | None = None,
    static: StaticPoints | None = None,
    *,
    one_step: bool = True,
    threads: int = 1,
) -> dict[str, np.ndarray]:
    """J_1, J_S and J_SF of many parameter vectors of one structure, vectorised.

    The evaluator for whole fronts and GA populations: the same definitions as :func:`j1`,
    :func:`js` and :func:`jsf`, computed for every row of ``thetas`` at once (compiled batch free
    runs; J_SF from the equilibrium each member reaches from each measured ȳ_i). Errors are
    counted from sample max_lag on; a diverging free run gives J_S = inf, a static point where a
    member reaches no equilibrium gives its J_SF = inf. Nothing warns: use :func:`jsf` on a single
    model to learn which point failed and why. A row that is not finite (NaN or inf) is no model
    and is refused: a front's failed members are left out by its caller, not scored here.

    Parameters
    ----------
    structure : Structure, sequence of str, Model, or a result that carries one
        Process terms shared by every member (a ParetoSet, Selection, ELSResult … gives its own). A Model, a
        ParetoSet or a result that carries a model also gives the sampling period and units its θ hold in: a
        record at another period, or data in other units, are refused (as :func:`js` and :func:`jsf` refuse them).
    thetas : ndarray, shape (P, n_terms) or (n_terms,)
        Parameter vectors, engineering units, one per row.
    record : Record or Dataset, optional
        Dynamic data for J_1 and J_S (N samples); omitted: neither is computed. A Dataset
        stands for its validation record and lends its static points when ``static`` is omitted.
    static : StaticPoints, optional
        Static points (M of them) for J_SF; omitted (and no Dataset): J_SF is not computed.
    one_step : bool
        Compute J_1 too (builds the regressor matrix, N × n_terms).
    threads : int
        Threads for the batch free run.

    Returns
    -------
    dict
        Keys among ``"J1"``, ``"JS"`` (with ``record``) and ``"JSF"`` (with ``static``), each an
        ndarray of shape (P,) in output units². Data near the ends of the float range are evaluated on the
        signals times powers of two (exact) and the J's mapped back: a J beyond the range reads inf or 0.

    Raises
    ------
    ValueError
        ``thetas`` of the wrong shape, or with a row that is not finite (the rows are named); data the model or
        set given as ``structure`` was not fitted at (another period, other units).
    """

    # a Model, a ParetoSet or a result carrying a model knows the period and units its θ hold in: data at another
    # period or in other units are refused, as js and jsf refuse them, not scored with parameters that do not hold
    fitted = structure if callable(getattr(structure, "check_record", None)) else getattr(structure, "model", None)
    structure = as_structure(structure)
    static = static_info(static, record)
    record = None if record is None else as_record(record, "valid", "record")
    if callable(getattr(fitted, "check_record", None)):
        for d in (record, static):
            if d is not None:
                fitted.check_record(d)
    one_step = check_bool(one_step, "one_step")
    threads = check_int(threads, "threads", low=1)
    # the one conversion of numbers (text, booleans, None: TypeError; beyond the float range: ValueError)
    th = np.atleast_2d(real_array(thetas, "thetas", "parameter vectors (numbers)"))
    if th.ndim != 2 or th.shape[1] != len(structure):
        raise ValueError(f"thetas must have shape (P, {len(structure)}) (one parameter vector per row, one value per "
                         f"term) or ({len(structure)},), got shape {np.shape(thetas)}")
    check_finite_rows(th, "thetas")
    # signals whose squares (or products of the terms) near the float range's ends: evaluated on the signals times
    # powers of two (exact) and the J's mapped back, so that they do not depend on the units (at y × 2^512 the sums
    # of squares, about 2^1027, read inf; with a y² term the equilibria overflowed)
    exps: dict[str, int] = {}
    if record is not None:
        (record,), exps = binary_scaled([record], structure)
    elif static is not None:  # the static points alone set the exponents
        # one input's points are read whatever their input's name (StaticPoints' default 'u' beside terms of 'a'):
        # the exponent then goes by the structure's name, which scaled_theta reads
        one = static.n_inputs == 1 and len(structure.input_names) == 1
        exps = binary_scaled([Record(np.asarray(static.ubar, float), np.asarray(static.ybar, float),
                                     input_names=structure.input_names if one else static.input_names)],
                             structure)[1]
    if exps:
        th = scaled_theta(th, structure, exps)
        static = None if static is None else scaled_points(static, exps)
    out: dict[str, np.ndarray] = {}
    if record is not None:
        L = structure.max_lag
        record.require_length(L)
        n_rows = len(record) - L
        if one_step:
            # a term beyond the float range on these data: inf (or NaN) in its column, every member's J1 inf
            psi = regressor_columns(structure, record.u, record.y, start=L, input_names=record.input_names)
            # row blocks of at most ~2^20 residuals: no N × P temporary on long records
            step = max(1, (1 << 20) // max(1, th.shape[0]))
            sse1 = np.zeros(th.shape[0])
            with np.errstate(over="ignore", invalid="ignore"):
                for k in range(0, n_rows, step):
                    r = record.y[L + k : L + k + step, None] - psi[k : k + step] @ th.T
                    sse1 += np.einsum("ij,ij->j", r, r)
            out["J1"] = np.where(np.isfinite(sse1), sse1 / n_rows, np.inf)  # as J_S: a non-finite member scores inf
        # the compiled kernel sums squared free-run errors as it simulates: no P × N output
        with np.errstate(over="ignore", invalid="ignore"):
            code = encode(structure)
            js_ = batch_sse(code, th, record_inputs(record, code.input_names), record.y, L, threads, bounded=True) / n_rows
        out["JS"] = np.where(np.isfinite(js_), js_, np.inf)
    if static is not None:
        if static.n_inputs > 1 or len(structure.input_names) > 1:  # a static surface: ū's columns by name
            names = record.input_names if record is not None else static.input_names
            ub = static_point_inputs(static, names)
            yb = reached_surface(structure, th, ub, static.ybar, inputs=names).ybar
        else:
            yb = reached_equilibria(structure, th, static.ubar, static.ybar).ybar
        with np.errstate(over="ignore", invalid="ignore"):
            jsf_ = np.mean((yb - static.ybar[None, :]) ** 2, axis=1)
        out["JSF"] = np.where(np.isfinite(jsf_), jsf_, np.inf)
    if exps:
        with np.errstate(over="ignore", under="ignore"):  # beyond the float range: inf or 0, as y² there
            out = {nm: np.ldexp(v, 2 * exps["y"]) for nm, v in out.items()}
    return out


__all__ += ["evaluate_thetas"]
