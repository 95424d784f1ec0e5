"""One evaluator shared by every estimator, notebook and the CLI.

Error measures (all mean squared errors in output units², as in the paper's Table I):

- ``J_1``: one-step-ahead prediction error,
- ``J_S``: free-run simulation error (initial conditions: the first max-lag measured samples),
- ``J_SF``: static-function error at the static points,
- ``RRSE`` = ‖y − ŷ‖ / ‖y − mean(y)‖ and ``fit %`` = 100 (1 − RRSE) of the free run, as MATLAB's
  ``compare`` defines it.

Dynamic errors are counted from sample ``max_lag`` on (the samples before are initial
conditions copied from the data, so their error is zero by construction). A free run that
diverges has J_S = inf; a static point where the model has no stable equilibrium makes
J_SF = inf (with a warning naming ū). Neither is a made-up number: both errors are unbounded.
"""

from __future__ import annotations

import warnings
from typing import Mapping

import numpy as np
import pandas as pd

from ._model import Model
from ._records import Dataset, Record, StaticPoints
from ._simulation import DivergenceError

__all__ = ["mse", "j1", "js", "jsf", "rrse", "fit_percent", "evaluate"]


def mse(y: np.ndarray, yhat: np.ndarray, start: int = 0) -> float:
    """Mean squared error of ``yhat`` against ``y`` over samples ``start …``; inf if ŷ is not finite."""
    e = np.asarray(y)[start:] - np.asarray(yhat)[start:]
    if e.size == 0:
        raise ValueError("no samples left to evaluate")
    if not np.all(np.isfinite(e)):
        return float("inf")
    return float(np.mean(e**2))


def j1(model: Model, record: Record) -> float:
    """J_1: one-step-ahead prediction MSE of ``model`` over ``record`` (samples max_lag … N-1)."""
    return mse(record.y, model.predict(record), model.max_lag)


def js(model: Model, record: Record) -> float:
    """J_S: free-run simulation MSE of ``model`` over ``record`` (inf when the run diverges)."""
    return mse(record.y, model.simulate(record, on_diverge="nan"), model.max_lag)


def jsf(model: Model, static: StaticPoints, y0: float | np.ndarray | None = None) -> float:
    """J_SF: MSE of the model's static curve at the static points (inf with a warning if undefined).

    Where the model has several stable equilibria at ū_i, the one it settles on when started at
    ``y0`` (default: the measured ȳ_i) counts.
    """
    try:
        yb = model.static_curve(static.ubar, y0=static.ybar if y0 is None else y0, strict=True)
    except (ValueError, DivergenceError) as exc:
        warnings.warn(f"J_SF of {model.name or 'model'} is infinite: {exc}", RuntimeWarning, stacklevel=2)
        return float("inf")
    return mse(static.ybar, yb)


def rrse(y: np.ndarray, yhat: np.ndarray, start: int = 0) -> float:
    """Root relative squared error ‖y − ŷ‖ / ‖y − mean(y)‖ over samples ``start …``.

    ``y`` is measured, ``yhat`` the model's output (inf when ``yhat`` is not finite).
    """
    y = np.asarray(y)[start:]
    yhat = np.asarray(yhat)[start:]
    if not np.all(np.isfinite(yhat)):
        return float("inf")
    den = np.linalg.norm(y - y.mean())
    if den == 0:
        raise ValueError("RRSE undefined: the measured output is constant")
    return float(np.linalg.norm(y - yhat) / den)


def fit_percent(y: np.ndarray, yhat: np.ndarray, start: int = 0) -> float:
    """MATLAB ``compare`` fit: 100 (1 − ‖y − ŷ‖ / ‖y − mean(y)‖), in percent.

    ``y`` is measured, ``yhat`` the model's output, counted from sample ``start`` on.
    """
    return 100.0 * (1.0 - rrse(y, yhat, start))


def evaluate(
    models: Mapping[str, Model],
    data: Dataset,
    static: StaticPoints | None = None,
    y0: float | None = None,
) -> pd.DataFrame:
    """A table shaped like the paper's Table I.

    Parameters
    ----------
    models : mapping name -> Model
    data : Dataset
        Identification and validation records (and static points, unless ``static`` is given).
    static : StaticPoints, optional
        Static points for J_SF (default ``data.static``).
    y0 : float or ndarray, optional
        Initial output used to pick among several stable equilibria (default: the measured ȳ_i).

    Returns
    -------
    pandas.DataFrame
        Index: model names. Columns: ``J_S ident``, ``J_S valid``, ``J_SF``, ``N_p``,
        ``J_1 ident``, ``fit % valid`` (MSE in output units²).
    """
    sp = data.static if static is None else static
    rows = {}
    for name, m in models.items():
        sim_v = m.simulate(data.valid, on_diverge="nan")
        rows[name] = {
            "J_S ident": js(m, data.ident),
            "J_S valid": mse(data.valid.y, sim_v, m.max_lag),
            "J_SF": jsf(m, sp, y0) if sp is not None else float("nan"),
            "N_p": m.n_params,
            "J_1 ident": j1(m, data.ident),
            "fit % valid": fit_percent(data.valid.y, sim_v, m.max_lag),
        }
    df = pd.DataFrame.from_dict(rows, orient="index")
    df["N_p"] = df["N_p"].astype(int)
    return df


def static_curves(
    structure,
    thetas: np.ndarray,
    ubar: np.ndarray,
    check_stability: bool = True,
    y0: np.ndarray | None = None,
) -> np.ndarray:
    """Static curves of many parameter vectors, shape (P, M); NaN where undefined.

    Rational structures use eq. (6) vectorised; others solve the polynomial per member (with
    ``y0``, shape (M,), choosing among several stable equilibria as in :func:`jsf`).
    With ``check_stability`` an equilibrium that is not locally stable is NaN too (the model
    does not settle there), matching :meth:`Model.static_curve`.
    """
    from ._static import is_rational, rational_equilibria, static_curve

    th = np.atleast_2d(np.asarray(thetas, float))
    ub = np.asarray(ubar, float)
    if is_rational(structure):
        return rational_equilibria(structure, th, ub, stable_only=check_stability)
    out = np.empty((th.shape[0], ub.size))
    for i, row in enumerate(th):
        out[i] = static_curve(structure, row, ub, y0=y0, strict=False) if np.all(np.isfinite(row)) else np.nan
    return out


def evaluate_thetas(
    structure,
    thetas: np.ndarray,
    record: Record | None = None,
    static: StaticPoints | None = None,
    one_step: bool = True,
    threads: int = 1,
    check_stability: bool = True,
) -> dict[str, np.ndarray]:
    """J_1, J_S and J_SF of many parameter vectors of one structure, vectorised.

    The same definitions as :func:`j1`, :func:`js` and :func:`jsf` (counted from sample
    max_lag on; inf where a free run diverges or the static curve is undefined), computed for a
    whole front or GA population at once.

    Parameters
    ----------
    structure : Structure
    thetas : ndarray, shape (P, n_terms)
    record : Record, optional
        Dynamic data for J_1 and J_S.
    static : StaticPoints, optional
        Static points for J_SF.
    one_step : bool
        Compute J_1 too (needs the regressor matrix).
    threads : int
        Threads for the batch free run.
    check_stability : bool
        Whether J_SF treats an unstable equilibrium as undefined (inf).

    Returns
    -------
    dict with keys among ``"J1"``, ``"JS"``, ``"JSF"``, each ndarray of shape (P,)
    """
    from ._regressors import regressor_matrix
    from ._simulation import simulate_many

    th = np.atleast_2d(np.asarray(thetas, float))
    out: dict[str, np.ndarray] = {}
    if record is not None:
        L = structure.max_lag
        if one_step:
            psi = regressor_matrix(structure, record.u, record.y, start=L)
            out["J1"] = np.mean((record.y[L:, None] - psi @ th.T) ** 2, axis=0)
        Y = simulate_many(structure, th, record, threads=threads)
        with np.errstate(over="ignore", invalid="ignore"):
            e2 = (Y[:, L:] - record.y[None, L:]) ** 2
            js_ = np.mean(e2, axis=1)
        out["JS"] = np.where(np.isfinite(js_), js_, np.inf)
    if static is not None:
        yb = static_curves(structure, th, static.ubar, check_stability, y0=static.ybar)
        with np.errstate(over="ignore", invalid="ignore"):
            jsf_ = np.mean((yb - static.ybar[None, :]) ** 2, axis=1)
        out["JSF"] = np.where(np.isfinite(jsf_), jsf_, np.inf)
    return out


__all__ += ["evaluate_thetas", "static_curves"]
