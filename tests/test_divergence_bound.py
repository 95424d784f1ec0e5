"""The default divergence bound of a free run is in the output's units (graybox.core._simulation.default_bound):
a run that diverges in one set of units diverges at the same sample in any other, also from rest."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import graybox as gb
from graybox.core._simulation import default_bound
from graybox.core._simulation_kernels import BOUND_FACTOR, encode, feedback_scale

ST = gb.Structure(["1", "u(k-1)", "y(k-1)", "u(k-1)y(k-1)", "y(k-2)^2"])


def scaled(theta: np.ndarray, s: float) -> np.ndarray:
    """θ for the output in units 1/s of the original (y' = s y): y-free terms × s, y-linear × 1, y² × 1/s."""
    return theta * np.array([s, s, 1.0, 1.0, 1.0 / s])


@settings(max_examples=60, deadline=None)
@given(a=st.floats(0.5, 1.3), c=st.floats(-0.5, 0.5), d=st.floats(-0.2, 0.2), e=st.floats(-0.05, 0.05),
       k=st.integers(-40, 40), start=st.sampled_from(["rest", "measured"]), seed=st.integers(0, 50))
def test_the_sample_a_run_is_called_divergent_does_not_depend_on_the_output_units(a, c, d, e, k, start, seed):
    rng = np.random.default_rng(seed)
    u = rng.uniform(0.0, 2.0, 300)
    theta = np.array([c, 0.4, a, d, e])
    y0 = np.zeros(2) if start == "rest" else rng.uniform(0.5, 2.0, 2)
    s = 2.0**k  # a power of two: the scaled run is the same run, bit for bit
    y = gb.simulate(ST, theta, u, y0, on_diverge="nan")
    ys = gb.simulate(ST, scaled(theta, s), u, y0 * s, on_diverge="nan")
    assume(np.all(np.isfinite(y * s)))  # no overflow of the scaled copy
    np.testing.assert_array_equal(np.isnan(ys), np.isnan(y))
    np.testing.assert_allclose(ys[np.isfinite(ys)], s * y[np.isfinite(y)], rtol=1e-12)


def test_a_large_output_from_rest_is_not_divergence_and_a_runaway_still_is():
    # pressure in Pa near 2e7 from rest; the same model made unstable runs off and is caught
    u = np.ones(400)
    stable = gb.Model(gb.Structure(["y(k-1)", "u(k-1)"]), np.array([0.99, 2e5]))
    assert stable.simulate(u, np.zeros(1))[-1] == pytest.approx(2e7 * (1 - 0.99**399), rel=1e-9)
    with pytest.raises(gb.DivergenceError, match="diverged at sample"):
        gb.Model(gb.Structure(["y(k-1)", "u(k-1)"]), np.array([1.2, 2e5])).simulate(u, np.zeros(1))


def test_tiny_units_are_not_given_room_in_the_units_of_one():
    # outputs near 1e-6 V: a runaway is caught within 1e6 times that size, as in any other units
    u = np.ones(400)
    y = gb.simulate(gb.Structure(["y(k-1)", "u(k-1)"]), np.array([1.2, 1e-7]), u, np.zeros(1), on_diverge="nan")
    first = int(np.flatnonzero(np.isnan(y))[0])
    last = np.nanmax(np.abs(y))
    assert last <= BOUND_FACTOR * 1e-7 < 1.2 * last + 1e-7  # stopped at the first step past 1e6 × the push
    assert first < 80  # 5e-7 · 1.2^k passes 0.1 near k = 67 (in units of 1, 1e6 held until k ≈ 140)


def test_the_default_bound_follows_the_largest_push_so_far():
    assert default_bound(np.array([3.0, -5.0])) == BOUND_FACTOR * 5.0
    assert default_bound(np.zeros(2), 0.25) == BOUND_FACTOR * 0.25
    assert default_bound(np.zeros(2)) == np.finfo(float).max  # nothing drives the output: only overflow counts
    # y(k) = 1.5 y(k-1) + c(k-1): the push is 1e-3 for 50 samples, then 1; the run from rest is caught
    # when it passes 1e6 × the push so far, not 1e6 × the record's largest
    u = np.r_[np.full(50, 1e-3), np.ones(50)]
    y = gb.simulate(gb.Structure(["y(k-1)", "u(k-1)"]), np.array([1.5, 1.0]), u, np.zeros(1), on_diverge="nan")
    k = int(np.flatnonzero(np.isnan(y))[0])
    assert k < 50 and abs(y[k - 1]) <= 1e3 < 1.5 * abs(y[k - 1]) + 1e-3
    # nothing drives a run that starts at 0: it stays at 0 and is never divergent
    z = gb.simulate(gb.Structure(["y(k-1)", "u(k-1)y(k-1)"]), np.array([1.5, 2.0]), np.ones(100), np.zeros(1))
    assert np.all(z == 0.0)


def test_predict_ahead_to_the_records_length_is_the_free_run_also_when_it_diverges():
    rng = np.random.default_rng(3)
    u = rng.uniform(0, 2, 300)
    rec = gb.Record(u, np.zeros(300) + 1e-3 * rng.standard_normal(300), 1.0)
    model = gb.Model(gb.Structure(["y(k-1)", "u(k-1)"]), np.array([1.1, 3e4]))
    free = model.simulate(rec, on_diverge="nan")
    ahead = model.predict(rec, horizon=300)
    assert np.isnan(free[-1])
    assert np.array_equal(ahead, free, equal_nan=True)  # bit for bit, the NaN from the same sample


def test_a_limit_cycle_from_a_tiny_start_is_not_divergence():
    # a discretised Van der Pol oscillator (no input, no constant): from y0 = 1e-6 its run grows to the limit
    # cycle (amplitude about 2); the model's feedback scale (|θ of y³|^(-1/2) = 3.2) keeps the bound there
    st = gb.Structure(["y(k-1)", "y(k-2)", "y(k-1)^3", "y(k-1)^2y(k-2)"])
    mu, h = 1.0, 0.1
    theta = np.array([2 + h * mu, -1 - h * mu - h * h, -h * mu, h * mu])
    y = gb.simulate(st, theta, np.zeros(2000), np.array([1e-6, 0.0]))
    assert np.max(np.abs(y[1000:])) == pytest.approx(2.04, abs=0.05)
    assert feedback_scale(encode(st), theta, np.zeros(10)) == pytest.approx(1 / np.sqrt(h * mu))
    # in other units (y' = 4 y) the same run, scaled
    ys = gb.simulate(st, theta * np.array([1, 1, 1 / 16, 1 / 16]), np.zeros(2000), np.array([4e-6, 0.0]))
    np.testing.assert_allclose(ys, 4 * y, rtol=1e-12)


def test_each_run_ahead_is_bounded_from_the_outputs_it_starts_from():
    # an AR(2) record whose first outputs are near 0 and the rest of size 10: the runs k samples ahead start from
    # measured outputs of size 10, and are not cut off by a bound taken from the record's first samples
    rng = np.random.default_rng(0)
    y = np.zeros(400)
    y[1] = 1e-6
    e = rng.standard_normal(400)
    for k in range(2, 400):
        y[k] = 1.5 * y[k - 1] - 0.7 * y[k - 2] + e[k]
    rec = gb.Record(np.zeros(400), y, 1.0)
    model = gb.Model(gb.Structure(["y(k-1)", "y(k-2)"]), np.array([1.5, -0.7]))
    for horizon in (2, 5, 50):
        assert np.all(np.isfinite(model.predict(rec, horizon=horizon)))


def test_a_network_is_never_called_divergent_at_its_default_bound():
    rng = np.random.default_rng(0)
    u = rng.uniform(0, 1, 400)
    y = 2e7 * np.convolve(u, [0.0, 0.3, 0.2], mode="full")[:400] + 1e4 * rng.standard_normal(400)
    net = gb.neural_narx(gb.Record(u, y, 1.0), ny=2, nu=2, ne=0, hidden=3, seed=0, epochs=3, sim_epochs=3)
    out = net.model.simulate(u, np.zeros(2))  # from rest, an output near 1e7 Pa
    assert np.all(np.isfinite(out))


@settings(max_examples=60, deadline=None)
@given(a=st.floats(0.5, 1.3), c=st.floats(-0.5, 0.5), d=st.floats(-0.2, 0.2), e=st.floats(-0.05, 0.05),
       spread=st.floats(0.0, 0.1), seed=st.integers(0, 50), threads=st.sampled_from([1, 2]))
def test_a_population_diverges_where_each_member_does_alone(a, c, d, e, spread, seed, threads):
    # one J_S and one free run per member, whatever computes them: the batch kernels behind
    # evaluate_thetas, simulate_many and ParetoSet stop a run where simulate's default bound does
    rng = np.random.default_rng(seed)
    u = rng.uniform(0.0, 2.0, 300)
    y = rng.uniform(0.5, 2.0, 300)
    rec = gb.Record(u, y)
    base = np.array([c, 0.4, a, d, e])
    thetas = base * (1.0 + spread * rng.standard_normal((6, base.size)))
    runs = gb.simulate_many(ST, thetas, rec, threads=threads)
    alone = np.array([gb.simulate(ST, th, u, y[:2], on_diverge="nan") for th in thetas])
    assume(np.all(np.isfinite(alone) | np.isnan(alone)))
    np.testing.assert_array_equal(np.isnan(runs), np.isnan(alone))
    # the batch kernel sums term by term, the single run by output monomial: round-off of the run's size
    size = np.nanmax(np.abs(alone), initial=1.0)
    np.testing.assert_allclose(runs[np.isfinite(runs)], alone[np.isfinite(alone)], rtol=1e-12, atol=1e-12 * size)
    js = gb.evaluate_thetas(ST, thetas, rec, None, one_step=False, threads=threads)["JS"]
    np.testing.assert_array_equal(np.isinf(js), ~np.all(np.isfinite(alone[:, 2:]), axis=1))


def _slow_divergence():
    """A first-order record and two members of y(k-1) + u(k-1): 1.01 (1.01^3000 ≈ 1e13: no overflow, but far
    past 1e6 × the run's scale) and the system's own 0.9."""
    rng = np.random.default_rng(0)
    u = rng.uniform(0.0, 1.0, 3000)
    y = np.zeros(3000)
    for k in range(1, 3000):
        y[k] = 0.9 * y[k - 1] + u[k - 1]
    return gb.Record(u, y), gb.Structure(["y(k-1)", "u(k-1)"]), np.array([[1.01, 1.0], [0.9, 1.0]])


def test_a_slowly_diverging_member_has_an_infinite_js_in_a_front_as_alone():
    rec, st_, th = _slow_divergence()
    assert gb.js(gb.Model(st_, th[0]), rec) == np.inf
    front = gb.ParetoSet.from_thetas(st_, th, None, rec, None)
    assert front.JS[0] == np.inf and front.JS[1] == pytest.approx(gb.js(gb.Model(st_, th[1]), rec), abs=1e-20)
    assert gb.evaluate_thetas(st_, th, rec, None)["JS"][0] == np.inf


def test_semp_scores_a_slowly_diverging_candidate_as_gb_js_does():
    # SEMP ranks candidates by their free-run J_S: a slowly diverging one scored 4e27 (the batch kernel stopped
    # only at an overflow), so a search where every extension diverges went on instead of saying so
    from graybox.selection._simulation_error_pruning import _Scorer

    rec, st_, th = _slow_divergence()
    scores = _Scorer(st_, [rec], 1).scores(th)
    assert scores[0] == np.inf == gb.js(gb.Model(st_, th[0]), rec)
    assert np.isfinite(scores[1])
