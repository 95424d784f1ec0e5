"""review49f: equilibria: two distinct roots about an inflection point, or one beyond 1e154 beside a near one, are not one
fold; a double root of degree 4 and above whose y coefficient cancels is kept."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb


@pytest.mark.parametrize("s", [0.1, -0.1, 0.01, -3.0])
@pytest.mark.parametrize("c0", [0.0, 0.3, -2.0])
@pytest.mark.parametrize("ys", [1.0, 1e-30, 1e40])
def test_two_roots_about_an_inflection_point_are_two_equilibria_not_one_fold(s, c0, ys):
    """060d79e judged adjacent roots one when |F''(mid)| δ²/8 was within the coefficients' uncertainty, F''(mid)
    standing for F(mid): where F'' vanishes at the midpoint (s (ȳ² − 1)(ȳ² + 1) = s (ȳ⁴ − 1): F''(0) = 0) the roots
    −1 and 1 were merged into one 'fold' at 0, an output that is no equilibrium at all (F(0) = −s), and the stable
    one of them was lost: y(k) = y(k−1) + 0.1 y(k−1)⁴ − 0.1 u(k−1) at ū = 1 had the one equilibrium (0.0, unstable)."""
    c = np.real(np.polynomial.polynomial.polyfromroots(np.array([c0 - 1, c0 + 1, c0 + 1j, c0 - 1j]) * ys)) * (s / ys**3)
    model = gb.Model(["y(k-1)", "y(k-1)^2", "y(k-1)^3", "y(k-1)^4", "u(k-1)"], [c[1] + 1, *c[2:], c[0]])
    eqs = model.equilibria(1.0)
    np.testing.assert_allclose([e.ybar / ys for e in eqs], [c0 - 1, c0 + 1], rtol=1e-9, atol=1e-12)
    for e, fprime in zip(eqs, (-4.0 * s, 4.0 * s)):  # F = s ((ȳ − c0)⁴ − 1) in y's units: F' = ∓4s at c0 ∓ 1
        assert e.stable == (-2.0 < fprime < 0.0)


@pytest.mark.parametrize("c", [1e-160, 1e-200, 1e-300, -1e-200])
def test_a_near_root_beside_one_beyond_the_float_square_is_not_merged_with_it(c):
    """060d79e read a pair whose midpoint is below their gap (1 and 1/c: mid = 1/(2c) < δ) unscaled: F'' δ² and
    S(mid) = … + |c| mid² both overflowed, inf <= inf, and y = 1 + c y² had the one equilibrium (1/(2c), a 'fold')
    for c <= ~1e-160 (test_hunt39a failed): the stable ȳ = 1 and the static curve there were lost."""
    m = gb.Model(["1", "y(k-1)^2"], [1.0, c])
    eqs = m.equilibria(0.0)
    want = sorted([2.0 / (1.0 + np.sqrt(1.0 - 4.0 * c)), (1.0 + np.sqrt(1.0 - 4.0 * c)) / (2.0 * c)])
    np.testing.assert_allclose([e.ybar for e in eqs], want, rtol=1e-9)
    assert [e.stable for e in eqs] == [abs(2.0 * c * e.ybar) < 1.0 for e in eqs]
    assert m.static_curve([0.0])[0] == pytest.approx(1.0, rel=1e-12)


def _roots_model(roots, scale: float) -> gb.Model:
    """ȳ = θ1 ȳ + θ2 ȳ² + … + ū whose static equation at ū = 1 is scale · ∏ (ȳ − r) = 0 (θ1 = 1 + c1 near 1)."""
    c = np.polynomial.polynomial.polyfromroots(np.asarray(roots, float)) * scale
    terms = ["y(k-1)"] + [f"y(k-1)^{p}" for p in range(2, len(c))] + ["u(k-1)"]
    return gb.Model(terms, [c[1] + 1, *c[2:], c[0]])


@pytest.mark.parametrize("scale", [-0.5, -0.005, -5e-4, 0.005, 5e-4, 5e-5])
@pytest.mark.parametrize("others", [[-1.0, 2.5], [-1.0, -2.5, 2.5]])
@pytest.mark.parametrize("r", [1.5, -0.6, 0.75, -2.0])
def test_a_double_root_of_a_quartic_or_quintic_whose_y_coefficient_cancels_is_kept(r, scale, others):
    """7bd1e9c kept such a double root for quadratics and cubics only: the companion path (degree >= 4) kept a root
    only where its imaginary part was below 1e-7 of it, and rounding of c1 = θ1 − 1 splits the double root into a
    complex pair farther apart: c (ȳ − 1.5)² (ȳ + 1)(ȳ − 2.5) at c = −5e-4 had the equilibria −1 and 2.5 only."""
    model = _roots_model([r, r, *others], scale)
    eqs = model.equilibria(1.0)
    np.testing.assert_allclose([e.ybar for e in eqs], sorted([r, *others]), rtol=1e-6)
    (fold,) = [e for e in eqs if abs(e.ybar - r) < 1e-6]
    assert not fold.stable


@pytest.mark.parametrize("scale", [-0.5, -0.005, 0.005])
def test_a_complex_pair_of_a_quartic_is_no_equilibrium(scale):
    """A complex pair clear of the real axis (1.5 ± 0.01i) stays out: only the real roots are equilibria."""
    c = np.real(np.polynomial.polynomial.polyfromroots([1.5 + 0.01j, 1.5 - 0.01j, -1.0, 2.5])) * scale
    model = gb.Model(["y(k-1)", "y(k-1)^2", "y(k-1)^3", "y(k-1)^4", "u(k-1)"], [c[1] + 1, *c[2:], c[0]])
    np.testing.assert_allclose([e.ybar for e in model.equilibria(1.0)], [-1.0, 2.5], rtol=1e-9)


# -- 9f2fe7d: PumpingPlant.turbine_head reads its flow as the library reads one number -------------------------------

def test_turbine_head_takes_a_flow_as_a_zero_dimensional_array_as_steady_state_takes_a_speed():
    """9f2fe7d read the flow with isinstance(flow, numbers.Real): a 0-d array (np.array(3.0), as np.asarray or a
    reduction with keepdims=False over an array hands one out) was 'flow must be a number', where float() took it
    before and every other number check of the plant (check_real, _one_speed: steady_state(np.array(1200.0))) takes it."""
    from graybox.datasets.pumping import PumpingPlant

    plant = PumpingPlant()
    assert plant.turbine_head(np.array(3.0)) == plant.turbine_head(3.0)
    assert plant.turbine_head(np.array(30.0)) == plant.turbine_head(30.0)
    assert plant.steady_state(np.array(1200.0)) == plant.steady_state(1200.0)
    with pytest.raises(TypeError, match="flow"):
        plant.turbine_head(np.array([3.0]))


@pytest.mark.parametrize("speed, step", [(1790.0, 20.0), (505.0, -20.0)])
def test_step_time_constant_names_a_step_that_leaves_the_speed_range(speed, step):
    """5744b9b read the speed as simulate does, but a step from it past the range still ended in simulate's words
    about a reference the caller never gave ('speed reference must stay within 500–1800 rpm …; sample 10 is 1810
    rpm'): the stepped speed is read as the speed is, naming speed + step."""
    from graybox.datasets.pumping import PumpingPlant

    with pytest.raises(ValueError, match=r"speed \+ step") as e:
        PumpingPlant().step_time_constant(speed, step=step)
    assert "sample 10" not in str(e.value)
    assert PumpingPlant().step_time_constant(1780.0) > 0  # a step that stays inside is read as before
