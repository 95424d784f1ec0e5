"""GrayboxSelection.uncertainty: the chosen model's covariance by its estimator's own rule, on a
synthetic plant of known structure, for every estimator select_graybox can choose; and refusals of
data the model was not fitted on."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import graybox as gb


def _plant(u: np.ndarray, e: np.ndarray) -> np.ndarray:
    y = np.zeros(u.size)
    for k in range(1, u.size):
        y[k] = 0.6 * y[k - 1] + 0.5 * u[k - 1] - 0.1 * u[k - 1] ** 2 + 0.2 + e[k]
    return y


@pytest.fixture(scope="module")
def data() -> gb.Dataset:
    rng = np.random.default_rng(0)
    recs = []
    for i, (n, name) in enumerate(((400, "ident"), (300, "valid"))):
        u = gb.design_input("aprbs", n, low=0.0, high=3.0, hold=(3, 15), seed=i)
        recs.append(gb.Record(u, _plant(u, 0.02 * rng.standard_normal(n)), name=name))
    ub = np.linspace(0, 3, 7)
    sp = gb.StaticPoints(ub, (0.5 * ub - 0.1 * ub**2 + 0.2) / 0.4 + 0.01 * rng.standard_normal(7), uncertainty=0.02)
    return gb.Dataset(recs[0], recs[1], sp)


def _select(data: gb.Dataset, est: str) -> gb.GrayboxSelection:
    black = {"band": np.inf} if est in ("ls", "els", "oe") else {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.SelectionWarning)
        return gb.select_graybox(gb.Candidates(2, 2, degree=2), data, estimator=est, sizes=[4], **black)


@pytest.mark.parametrize("est", ["ls", "els", "oe", "pe", "se-gradient"])
def test_the_chosen_models_covariance_by_its_estimators_rule(data, est):
    sel = _select(data, est)
    assert sel.chosen["estimator"] == est
    if est == "oe":  # output_error's own fit is regularised (ridge towards LS): not the plain SE optimum, said
        with pytest.warns(gb.UncertaintyWarning, match="not a stationary point of the SE objective at λ1 = 1"):
            unc = sel.uncertainty(data)
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # a θ that is not the estimator's solution on these data would warn
            unc = sel.uncertainty(data)
    process = [th for t, th in zip(unc.model.structure, unc.model.theta) if not t.is_noise]
    np.testing.assert_allclose(process, sel.model.theta, rtol=1e-8)
    # the right structure on 400 samples of 2 % noise: each interval holds the true value
    truth = {"1": 0.2, "y(k-1)": 0.6, "u(k-1)": 0.5, "u(k-1)^2": -0.1}
    got = dict(zip(map(str, sel.structure), unc.intervals))
    assert set(got) == set(truth)
    assert all(lo <= truth[t] <= hi for t, (lo, hi) in got.items()), (est, got)
    band = gb.simulation_band(unc, data.valid)
    assert np.all(band.std[1:] > 0) and band.model_name == unc.model.name
    expected = {"ls": "LS", "els": "ELS", "oe": "SE λ1=1", "pe": "PE", "se-gradient": "SE"}[est]
    assert unc.method.startswith(expected)


def test_data_the_model_was_not_fitted_on_are_refused(data):
    other = gb.Dataset(data.valid, data.ident, data.static)
    with pytest.raises(ValueError, match="ELS on these data does not give the chosen model's θ"):
        _select(data, "els").uncertainty(other)
    with pytest.raises(ValueError):
        _select(data, "ls").uncertainty(other)
    with pytest.raises(ValueError, match="static applies to a gray box"):
        _select(data, "ls").uncertainty(data, data.static)
    with pytest.raises(ValueError, match="constraints apply to the PE estimator"):
        _select(data, "se-gradient").uncertainty(data, constraints=[gb.PassesThrough()])
