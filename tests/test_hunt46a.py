"""hunt46a: from model to controller — local models, equilibria and the python-control bridge."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb
from graybox import Model


def quartic_fold(scale: float) -> Model:
    """ȳ = F(ȳ) + ū with F(ȳ) − ȳ + 1 = scale (ȳ − 1)² (ȳ² + 1): a double root (a fold) at ū = 1, ȳ = 1."""
    c = np.array([1.0, -2.0, 2.0, -2.0, 1.0]) * scale  # ascending
    return Model(["y(k-1)", "y(k-1)^2", "y(k-1)^3", "y(k-1)^4", "u(k-1)"], [c[1] + 1, c[2], c[3], c[4], c[0]],
                 name="quartic fold")


#: ȳ = 0.5 ȳ + 0.25 ȳ² + ū: a double root at the exact fold ū = 0.25, ȳ = 1 (closed-form quadratic path).
QUADRATIC_FOLD = Model(["y(k-1)", "y(k-1)^2", "u(k-1)"], [0.5, 0.25, 1.0], name="quadratic fold")


#: The same fold with y in units 100 times smaller: at ū = 2500 the double root is ȳ = 100.
SCALED_FOLD = Model(["y(k-1)", "y(k-1)^2", "u(k-1)"], [0.5, 0.25e-2, 1.0], name="scaled fold")


@pytest.mark.parametrize("model,ubar,ybar", [(QUADRATIC_FOLD, 0.25, 1.0), (SCALED_FOLD, 25.0, 100.0),
                                             (quartic_fold(1.0), 1.0, 1.0), (quartic_fold(0.1), 1.0, 1.0),
                                             (quartic_fold(1 / 3), 1.0, 1.0), (quartic_fold(0.01), 1.0, 1.0)])
def test_a_double_root_at_a_fold_is_one_equilibrium_and_not_stable(model, ubar, ybar):
    eqs = model.equilibria(ubar)
    assert len(eqs) == 1, eqs
    e = eqs[0]
    assert e.ybar == pytest.approx(ybar, rel=1e-6)
    # at a double root of the static equation Σ a_l = 1: a pole at z = 1, not asymptotically stable
    assert not e.stable
    assert e.spectral_radius >= 1.0


def test_a_fold_is_not_two_stable_equilibria_for_the_static_curve_and_the_local_model():
    m = quartic_fold(1 / 3)
    with pytest.raises(ValueError, match="no stable equilibrium"):
        m.static_curve([1.0])
    lm = gb.local_model(m, 1.0, Ts=1.0)
    assert lm.status == "no stable equilibrium" and lm.ybar == pytest.approx(1.0)


def test_two_close_but_distinct_equilibria_below_a_fold_stay_two():
    eqs = QUADRATIC_FOLD.equilibria(0.2499999)
    assert len(eqs) == 2 and eqs[0].stable and not eqs[1].stable


def test_a_double_root_beside_simple_ones_is_listed_once():
    c = np.polynomial.polynomial.polyfromroots([1.0, 1.0, 2.0, -3.0]) * 0.05
    m = Model(["y(k-1)", "y(k-1)^2", "y(k-1)^3", "y(k-1)^4", "u(k-1)"], [c[1] + 1, c[2], c[3], c[4], c[0]])
    ys = [e.ybar for e in m.equilibria(1.0)]
    np.testing.assert_allclose(ys, [-3.0, 1.0, 2.0], rtol=1e-7)
    c = np.polynomial.polynomial.polyfromroots([1.0, 1.0, -2.0]) * 0.25
    m = Model(["y(k-1)", "y(k-1)^2", "y(k-1)^3", "u(k-1)"], [c[1] + 1, c[2], c[3], c[0]])
    ys = [e.ybar for e in m.equilibria(1.0)]
    np.testing.assert_allclose(ys, [-2.0, 1.0], rtol=1e-12)



def _with_static_roots(roots: list[float], scale: float) -> Model:
    """ȳ = F(ȳ) + ū whose static equation at ū = 1 is scale · ∏ (ȳ − r) = 0."""
    c = np.polynomial.polynomial.polyfromroots(roots) * scale
    terms = ["y(k-1)"] + [f"y(k-1)^{p}" for p in range(2, len(c))] + ["u(k-1)"]
    return Model(terms, [c[1] + 1, *c[2:], c[0]])


@pytest.mark.parametrize("roots,scale", [([1.0, 1.0, 1.0, -1.0], -0.1), ([2.0] * 5, -0.1), ([1.0, 1.0, 1.0], -0.1)])
def test_a_triple_root_is_not_stable_even_where_the_solver_left_it_alone(roots, scale):
    # Σ a_l = 1 at any multiple root; the companion matrix splits a triple root into one real root and a complex
    # pair, so no two real roots are left to merge, and rounding put Σ a_l just below 1: 'stable'
    eqs = _with_static_roots(roots, scale).equilibria(1.0)
    at = [e for e in eqs if abs(e.ybar - roots[0]) < 1e-2]
    assert len(at) == 1 and not at[0].stable and at[0].spectral_radius >= 1.0
    # the simple root beside it keeps its own verdict (−1 here: F' = 0.8, a pole at 1.8)
    assert all(not e.stable for e in eqs if abs(e.ybar + 1.0) < 1e-9)


def test_the_local_model_at_a_fold_has_its_pole_at_one_whatever_rounding_made_of_it():
    lm = gb.local_model(quartic_fold(1 / 3), 1.0, Ts=0.5)  # Σ a_l = 1 − 2⁻⁵² here
    assert not lm.stable and lm.spectral_radius >= 1.0
    assert lm.time_constant == np.inf and np.isinf(lm.dc_gain[0]) and lm.settling_time() == np.inf
    curve = gb.operating_curve(quartic_fold(1 / 3), [0.5, 1.0], Ts=0.5)
    assert curve.status[1] == "no stable equilibrium" and curve.time_constant[1] == np.inf


def _narmax_record(n: int = 80):
    """A NARMAX model whose MA part reaches further back (e(k−3)) than its process terms (lag 1), and a record of it."""
    m = Model(["1", "y(k-1)", "u(k-1)", "y(k-1)u(k-1)"], [0.1, 0.6, 0.3, 0.02], noise_structure=["e(k-1)", "e(k-3)"],
              noise_theta=[0.4, -0.2], Ts=1.0, name="narmax")
    rng = np.random.default_rng(1)
    u, e, y = rng.uniform(0, 1, n), 0.05 * rng.standard_normal(n), np.zeros(n)
    for k in range(3, n):
        y[k] = 0.1 + 0.6 * y[k - 1] + 0.3 * u[k - 1] + 0.02 * y[k - 1] * u[k - 1] + 0.4 * e[k - 1] - 0.2 * e[k - 3] + e[k]
    return m, gb.Record(u, y, Ts=1.0)


@pytest.mark.parametrize("start", [None, 3, 10, 70])
def test_the_system_fed_the_one_step_residuals_reproduces_the_record_when_the_ma_part_reaches_furthest(start):
    ct = pytest.importorskip("control")
    m, rec = _narmax_record()
    xi = gb.one_step_residuals(m, rec)[0]  # ξ(k), k = 3 … N−1 (0 before 3)
    L = len(rec) - xi.size
    x0 = gb.narx_initial_state(m, rec, start=start, noise=True)
    k0 = L if start is None else start
    sysm = gb.narx_iosystem(m, noise=True)
    r = ct.input_output_response(sysm, np.arange(len(rec) - k0), np.vstack([rec.u[k0:], xi[k0 - L:]]), x0)
    np.testing.assert_allclose(r.outputs[0], rec.y[k0:], rtol=0, atol=1e-12)


#: y⁺ = y + 0.2 (u + y − y³): two stable equilibria (±1 at ū = 0) for |ū| < 2 / (3√3), one outside.
BISTABLE = Model(["y(k-1)", "y(k-1)^3", "u(k-1)"], [1.2, -0.2, 0.2], Ts=1.0, name="bistable")


def test_an_operating_curve_through_a_bistable_range_marks_those_points_and_goes_on():
    # a sweep: a point where ū sets no one equilibrium is that point's status, not the whole curve's ValueError
    oc = gb.operating_curve(BISTABLE, [-1.0, 0.0, 1.0])
    assert oc.status == ("reached", "several stable equilibria", "reached")
    assert np.isnan(oc.ybar[1]) and np.isnan(oc.gain[1]) and np.isfinite(oc.ybar[[0, 2]]).all()
    lm = oc.local_models[1]
    assert not lm.exists and "2 stable equilibria" in lm.reason and "y0" in lm.reason
    with pytest.raises(ValueError, match="no local model: .*2 stable equilibria"):
        lm.dc_gain
    assert oc.to_frame()["status"].tolist() == list(oc.status)
    # one point: local_model still says so and asks for y0, as documented
    with pytest.raises(ValueError, match=r"2 stable equilibria at ū = 0 \(\[-1, 1\]\); pass y0"):
        gb.local_model(BISTABLE, 0.0)
    # with y0 every point has its equilibrium, as before
    assert gb.operating_curve(BISTABLE, [-1.0, 0.0, 1.0], y0=0.5).status == ("reached",) * 3


@pytest.mark.parametrize("roots,scale", [([1.0, 1.0, 1.0, -1.0], -0.1), ([2.0] * 5, -0.1)])
def test_the_local_model_at_a_triple_root_is_that_of_a_pole_at_one(roots, scale):
    # the root is found to eps^(1/3) only, so its a_l sum to 1 − 3e-11: Schur–Cohn 'stable', while the static
    # analysis says (rightly) that no equilibrium is: the LocalModel refused its own status, local_model crashed
    m = _with_static_roots(roots, scale)
    for y0 in (None, roots[0]):
        lm = gb.local_model(m, 1.0, Ts=1.0, y0=y0)
        assert lm.exists and lm.ybar == pytest.approx(roots[0], rel=1e-3) and not lm.reached
        assert not lm.stable and lm.time_constant == np.inf and lm.spectral_radius >= 1.0
        assert lm.a.sum() == pytest.approx(1.0, abs=1e-15)
    assert gb.operating_curve(m, [1.0], Ts=1.0).status == ("no stable equilibrium",)


def test_a_record_shorter_than_the_state_is_named_as_such():
    # the message was "start must lie in [3, 2]", an empty interval, whatever start was given
    m = Model(["y(k-1)", "u(k-3)"], [0.5, 1.0], Ts=1.0)
    short = gb.Record(np.ones(2), np.ones(2), Ts=1.0, name="short")
    for start in (None, 2):
        with pytest.raises(ValueError, match="short: the record has 2 samples, fewer than the 3 .*max lag"):
            gb.narx_initial_state(m, short, start=start)
    assert gb.narx_initial_state(m, gb.Record(np.arange(3.0), np.ones(3), Ts=1.0)).tolist() == [1.0, 2.0, 1.0, 0.0]


def _y_in_units(model: Model, s: float) -> Model:
    """The same model with y in units s times smaller (y' = s y): θ of a term in y^p (and u) times s^(1−p)."""
    return Model(model.structure, [th * s ** (1 - t.power_of("y")) for th, t in zip(model.theta, model.structure)])


@pytest.mark.parametrize("roots,scale", [([1.1, -0.1, 1.1], -0.1), ([1.1, -0.1, 1.1], 0.03), ([0.7, 0.7], 0.3)])
def test_a_double_root_is_one_fold_in_any_units_of_y(roots, scale):
    # rounding leaves a double root as two close real roots or as a complex pair with a tiny imaginary part; the
    # closed-form quadratic dropped the pair (no equilibrium there) and kept the reals (a fold), so the fold came
    # and went with the units of y (as ȳ = 1.1 did here in °C against K-sized or 7x units)
    m = _with_static_roots(roots, scale)
    seen = []
    for s in (1.0, 7.0, 1000.0, 1e-3, 3.0):
        eqs = _y_in_units(m, s).equilibria(1.0)
        seen.append([(round(e.ybar / s, 6), e.stable) for e in eqs])
    assert all(v == seen[0] for v in seen), seen
    assert (roots[0], False) in seen[0]  # the double root, a fold: not stable
