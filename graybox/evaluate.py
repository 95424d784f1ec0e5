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

from .model import Model
from .records import Dataset, Record, StaticPoints
from .simulation import DivergenceError

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
    """J_1: one-step-ahead prediction MSE over ``record`` (samples max_lag … N-1)."""
    return mse(record.y, model.predict(record), model.max_lag)


def js(model: Model, record: Record) -> float:
    """J_S: free-run simulation MSE over ``record`` (inf when the run diverges)."""
    return mse(record.y, model.simulate(record, on_diverge="nan"), model.max_lag)


def jsf(model: Model, static: StaticPoints, y0: float | None = None) -> float:
    """J_SF: MSE of the model's static curve at the static points (inf with a warning if undefined)."""
    try:
        yb = model.static_curve(static.ubar, y0=y0, strict=True)
    except (ValueError, DivergenceError) as exc:
        warnings.warn(f"J_SF of {model.name or 'model'} is infinite: {exc}", RuntimeWarning, stacklevel=2)
        return float("inf")
    return mse(static.ybar, yb)


def rrse(y: np.ndarray, yhat: np.ndarray, start: int = 0) -> float:
    """Root relative squared error ‖y − ŷ‖ / ‖y − mean(y)‖ over samples ``start …``."""
    y = np.asarray(y)[start:]
    yhat = np.asarray(yhat)[start:]
    if not np.all(np.isfinite(yhat)):
        return float("inf")
    den = np.linalg.norm(y - y.mean())
    if den == 0:
        raise ValueError("RRSE undefined: the measured output is constant")
    return float(np.linalg.norm(y - yhat) / den)


def fit_percent(y: np.ndarray, yhat: np.ndarray, start: int = 0) -> float:
    """MATLAB ``compare`` fit: 100 (1 − ‖y − ŷ‖ / ‖y − mean(y)‖), in percent."""
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
    y0 : float, optional
        Initial output used to pick among several stable equilibria.

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
