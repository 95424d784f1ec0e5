"""An output-only model (no input terms) reads no input: the names of a record's inputs never matter to it."""

import numpy as np
import pytest

import graybox as gb

AR = gb.Structure(["1", "y(k-1)", "y(k-2)", "y(k-1)^2"])
THETA = np.array([0.3, 0.6, -0.2, 0.01])


def _records(seed=0, n=300):
    """The same output with one input named 'u', one named 'speed', and two inputs named 'a', 'b'."""
    rng = np.random.default_rng(seed)
    y = gb.simulate(AR, THETA, np.zeros(n), np.zeros(2)) + 0.05 * rng.standard_normal(n)
    u = rng.uniform(0.0, 1.0, (n, 2))
    return (gb.Record(u[:, 0], y, Ts=1.0, name="u"),
            gb.Record(u[:, 0], y, Ts=1.0, input_names=("speed",), name="speed"),
            gb.Record(u, y, Ts=1.0, input_names=("a", "b"), name="two"))


@pytest.mark.parametrize("call", [
    lambda r: gb.simulate(AR, THETA, r),
    lambda r: gb.Model(AR, THETA).simulate(r),
    lambda r: gb.predict(AR, THETA, r),
    lambda r: gb.predict(AR, THETA, r, horizon=5),
    lambda r: gb.simulate_many(AR, np.vstack([THETA, 0.9 * THETA]), r),
    lambda r: gb.output_error(AR, r, n_starts=2, seed=1).model.theta,
    lambda r: gb.output_error(AR, r, n_starts=2, seed=1, margin=0.05).model.theta,
    lambda r: gb.els(AR, r).model.theta,
], ids=["simulate", "Model.simulate", "predict", "predict-5", "simulate_many", "output_error",
        "output_error-margin", "els"])
def test_an_output_only_model_gives_the_same_result_whatever_the_inputs_are_named(call):
    ref, *others = (call(r) for r in _records())
    assert np.all(np.isfinite(ref))
    for got in others:
        np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12)


def test_a_model_that_uses_u_still_needs_an_input_named_u():
    _, speed, _ = _records()
    model = gb.Model(gb.Structure(["y(k-1)", "u(k-1)"]), np.array([0.5, 0.3]))
    with pytest.raises(ValueError, match="uses input 'u'.*'speed'"):
        model.simulate(speed)


def test_model_simulate_takes_a_divergence_bound_for_large_outputs():
    # a stable plant whose output is near 2e7 (a pressure in Pa) run from rest: the default bound is in the
    # output's units (it was 1e6 · (1 + 0) and read the rise as divergence); a given bound still guards
    model = gb.Model(gb.Structure(["y(k-1)", "u(k-1)"]), np.array([0.5, 1e7]))
    u = np.ones(50)
    assert model.simulate(u, np.zeros(1))[-1] == pytest.approx(2e7)
    y = model.simulate(u, np.zeros(1), bound=1e9)
    assert y[-1] == pytest.approx(2e7)
    assert np.isnan(model.simulate(u, np.zeros(1), bound=1e7, on_diverge="nan")[-1])
