"""Prediction k steps ahead (`predict(..., horizon=k)`): between the one-step prediction and the free run."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import graybox as gb
from graybox.core._simulation_kernels import encode, predict_ahead

ARX = gb.Structure(["y(k-1)", "u(k-1)", "1"])


def _record(n=200, seed=0, noise=0.05):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1.0, 1.0, n // 5 + 1), 5)[:n]
    y = gb.simulate(ARX, np.array([0.7, 0.4, 0.2]), u, np.zeros(1)) + noise * rng.standard_normal(n)
    return gb.Record(u, y, Ts=0.1)


@settings(max_examples=60, deadline=None)
@given(a=st.floats(-0.95, 0.95), b=st.floats(-2.0, 2.0), c=st.floats(-1.0, 1.0), h=st.integers(1, 30),
       seed=st.integers(0, 10_000))
def test_first_order_arx_matches_its_closed_form(a, b, c, h, seed):
    # ŷ(t | t − h) = a^h y(t − h) + Σ_{i<h} a^i (b u(t − 1 − i) + c) once t − h ≥ 0 (max lag 1)
    rec = _record(seed=seed)
    yhat = gb.predict(ARX, np.array([a, b, c]), rec, horizon=h)
    u, y = rec.u, rec.y
    for t in range(h, len(rec), 7):
        ref = a**h * y[t - h] + sum(a**i * (b * u[t - 1 - i] + c) for i in range(h))
        assert yhat[t] == pytest.approx(ref, rel=1e-9, abs=1e-9)
    assert yhat[0] == y[0]  # the first max_lag samples are the measured ones


def test_horizon_one_is_the_one_step_prediction_and_a_long_horizon_the_free_run():
    structure = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)y(k-1)", "u(k-1)^2", "1"])
    theta = np.array([0.9, -0.2, 0.5, -0.05, 0.02, 0.1])
    rec = _record(n=300, seed=3)
    one = gb.predict(structure, theta, rec)
    # the compiled recursion at horizon 1 is the regressor matrix times θ
    kernel = predict_ahead(encode(structure), theta, rec.u, rec.y, 2, 1, 1e12)
    np.testing.assert_allclose(kernel, one, rtol=1e-12, atol=1e-12)
    free = gb.simulate(structure, theta, rec)
    np.testing.assert_array_equal(gb.predict(structure, theta, rec, horizon=len(rec)), free)
    np.testing.assert_array_equal(gb.predict(structure, theta, rec, horizon=10 * len(rec)), free)
    # the error grows with the horizon on average (the model is not the data's)
    err = [np.mean((gb.predict(structure, theta, rec, horizon=h)[40:] - rec.y[40:]) ** 2) for h in (1, 5, 40)]
    assert err[0] < err[1] < err[2]


def test_noise_free_data_of_the_model_are_predicted_exactly_at_every_horizon():
    rec = _record(noise=0.0)
    theta = np.array([0.7, 0.4, 0.2])
    for h in (1, 2, 7, 50):
        np.testing.assert_allclose(gb.predict(ARX, theta, rec, horizon=h), rec.y, rtol=0, atol=1e-12)


def test_several_inputs_are_taken_by_name_and_the_model_method_agrees():
    rng = np.random.default_rng(5)
    n = 150
    u = rng.uniform(0.0, 1.0, (n, 3))
    structure = gb.Structure(["y(k-1)", "b(k-1)", "a(k-2)b(k-1)", "1"])
    theta = np.array([0.6, 0.5, -0.3, 0.05])
    ab = gb.Record(u[:, :2], np.zeros(n), Ts=1.0, input_names=("a", "b"))
    y = gb.simulate(structure, theta, ab) + 0.01 * rng.standard_normal(n)
    # the record holds an extra input and the columns in another order
    rec = gb.Record(u[:, [2, 1, 0]], y, Ts=1.0, input_names=("c", "b", "a"))
    model = gb.Model(structure, theta)
    for h in (1, 3):
        ref = gb.predict(structure, theta, gb.Record(u[:, :2], y, Ts=1.0, input_names=("a", "b")), horizon=h)
        np.testing.assert_allclose(model.predict(rec, horizon=h), ref, rtol=1e-12, atol=1e-12)


def test_a_prediction_whose_run_diverges_is_nan_not_a_number_made_up():
    rec = _record(n=120)
    theta = np.array([3.0, 0.4, 0.2])  # unstable: a run of many steps leaves any bound
    assert np.isfinite(gb.predict(ARX, theta, rec, horizon=1)).all()
    far = gb.predict(ARX, theta, rec, horizon=60)
    assert np.isnan(far[80:]).all() and np.isfinite(far[:5]).all()


def test_bad_arguments_are_named():
    rec = _record()
    theta = np.array([0.7, 0.4, 0.2])
    with pytest.raises(TypeError, match="record must be a Record"):
        gb.predict(ARX, theta, rec.u)
    with pytest.raises(TypeError, match="record must be a Record"):
        gb.Model(ARX, theta).predict(rec.u)
    with pytest.raises(ValueError, match="horizon"):
        gb.predict(ARX, theta, rec, horizon=0)
    with pytest.raises(TypeError, match="horizon"):
        gb.predict(ARX, theta, rec, horizon=2.5)
    with pytest.raises(ValueError, match="fewer than max lag"):
        gb.predict(gb.Structure(["y(k-8)"]), np.array([0.5]), rec.slice(0, 5), horizon=3)
