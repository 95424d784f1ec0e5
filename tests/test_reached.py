"""J_SF's definition: the equilibrium a free run at constant ū, started at the measured ȳ, settles on.

Each case is checked against a long constant-input free run from ȳ (graybox's own simulator, which
the settling routine does not use: it runs its own compiled recursion with the input folded in).
"""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from graybox import Model, Record, StaticPoints, Structure, evaluate_thetas, jsf, reference
from graybox.estimation._simulation_error import SEProblem
from graybox.static._analysis import (
    NO_EQUILIBRIUM, NONE_STABLE, SETTLE_STEPS, reached_equilibria, static_theta_gradient,
)
from graybox.static._equilibrium_kernels import DIVERGED, NOT_SETTLED, REACHED

CUBIC = Structure(["y(k-1)", "y(k-2)", "y(k-1)^3", "u(k-1)"])
#: y = 0.3 y1 + 0.2 y2 + 0.5 y1³ + 1e-3 u: three equilibria at ū = 100 (−1.088, 0.209, 0.879),
#: only the middle one stable, and its basin ends at the upper one.
ONE_STABLE = Model(CUBIC, [0.3, 0.2, 0.5, 1e-3], name="one stable")
#: y = 1.2 y1 + 0.3 y2 − 0.5 y1³ + 1e-3 u: at ū = 100 two stable equilibria (−0.879, 1.088) around
#: an unstable one (−0.209).
TWO_STABLE = Model(CUBIC, [1.2, 0.3, -0.5, 1e-3], name="two stable")


def long_run(model: Model, ubar: float, y0: float, n: int = 3 * SETTLE_STEPS) -> np.ndarray:
    return model.simulate(np.full(n, ubar), np.full(model.max_lag, y0), on_diverge="nan")


def test_the_models_have_the_equilibria_the_tests_rely_on():
    a = ONE_STABLE.equilibria(100.0)
    assert [e.stable for e in a] == [False, True, False]
    np.testing.assert_allclose([e.ybar for e in a], [-1.0880, 0.2091, 0.8789], atol=1e-4)
    b = TWO_STABLE.equilibria(100.0)
    assert [e.stable for e in b] == [True, False, True]
    np.testing.assert_allclose([e.ybar for e in b], [-0.8789, -0.2091, 1.0880], atol=1e-4)


def test_a_stable_equilibrium_whose_basin_does_not_hold_ybar_does_not_count():
    # from ȳ = 1.5 at ū = 100 (beyond the unstable 0.879) the run diverges, though 0.209 is locally
    # stable; from 0.5 at ū = 120 it settles on that branch
    assert not np.isfinite(long_run(ONE_STABLE, 100.0, 1.5)[-1])
    res = reached_equilibria(CUBIC, ONE_STABLE.theta[None], [100.0, 120.0], [1.5, 0.5])
    assert res.status[0].tolist() == [DIVERGED, REACHED]
    assert np.isnan(res.ybar[0, 0])
    assert res.ybar[0, 1] == pytest.approx(long_run(ONE_STABLE, 120.0, 0.5)[-1], rel=1e-12)
    pts = StaticPoints([100.0, 120.0], [1.5, 0.5])
    with pytest.warns(RuntimeWarning, match=r"ū = 100: the free run from y0 = 1.5 diverged"):
        assert jsf(ONE_STABLE, pts) == np.inf
    assert evaluate_thetas(CUBIC, ONE_STABLE.theta, static=pts)["JSF"][0] == np.inf
    with pytest.raises(ValueError, match="diverged"):
        ONE_STABLE.static_curve([100.0], y0=1.5)
    assert np.isnan(ONE_STABLE.static_curve([100.0], y0=1.5, strict=False)[0])
    # the rest of the package agrees: the SE objective counts the point as undefined too
    rec = Record(np.full(50, 100.0), np.full(50, 0.5))
    assert SEProblem(CUBIC, rec, pts).jsf(ONE_STABLE.theta[None])[0] == np.inf


def test_two_stable_equilibria_the_one_reached_from_ybar():
    lo, _, hi = (e.ybar for e in TWO_STABLE.equilibria(100.0))
    y0 = np.array([0.5, -0.6, 3.0, -3.0])
    res = reached_equilibria(CUBIC, TWO_STABLE.theta[None], np.full(4, 100.0), y0)
    for j, start in enumerate(y0):
        end = long_run(TWO_STABLE, 100.0, start)[-1]
        if res.status[0, j] == REACHED:
            assert res.ybar[0, j] == pytest.approx(end, rel=1e-9)
        else:
            assert res.status[0, j] == DIVERGED and not np.isfinite(end)
    assert res.ybar[0, 0] == pytest.approx(hi) and res.ybar[0, 1] == pytest.approx(lo)
    # without y0 the model has no single static curve here, and says so
    with pytest.raises(ValueError, match="2 stable equilibria at ū = 100.*pass y0"):
        TWO_STABLE.static_curve([100.0])
    np.testing.assert_allclose(TWO_STABLE.static_curve([100.0, 100.0], y0=[0.5, -0.6]), [hi, lo], rtol=1e-12)


def test_started_on_the_unstable_equilibrium_the_run_does_not_settle():
    # at ū = 0 the equilibria are −1, 0, 1 exactly; from 0 the run stays on the unstable one
    res = reached_equilibria(CUBIC, TWO_STABLE.theta[None], [0.0], [0.0])
    assert res.status[0, 0] == NOT_SETTLED
    assert "did not settle" in res.explain(0)[0]
    assert np.all(long_run(TWO_STABLE, 0.0, 0.0) == 0.0)
    # the reason said "... within 50 time constants of the slowest (one over 200000 samples is not run)", where
    # no time constant is involved: it names the equilibrium the run starts on, here and through static_curve
    assert "starts on the unstable equilibrium ȳ = 0" in res.explain(0)[0]
    assert "time constant" not in res.explain(0)[0]
    with pytest.raises(ValueError, match="starts on the unstable equilibrium ȳ = 0"):
        TWO_STABLE.static_curve([0.0], y0=[0.0])
    # started elsewhere, the same model settles: the phrase is for the start on the equilibrium only
    assert reached_equilibria(CUBIC, TWO_STABLE.theta[None], [0.0], [0.5]).status[0, 0] == REACHED


@st.composite
def cubic_models(draw):
    base = draw(st.sampled_from([ONE_STABLE, TWO_STABLE]))
    scale = draw(st.floats(0.9, 1.1))
    return base.with_theta(base.theta * np.array([1.0, 1.0, scale, 1.0]))


@given(cubic_models(), st.floats(-300.0, 300.0), st.floats(-2.5, 2.5))
@settings(max_examples=60, deadline=None)
def test_property_reached_equilibrium_is_where_a_long_free_run_from_ybar_ends(model, ubar, y0):
    res = reached_equilibria(CUBIC, model.theta[None], [ubar], [y0])
    run = long_run(model, ubar, y0)
    end = run[-1]
    if not np.isfinite(end):  # it diverged, or there was nothing stable to settle on
        assert res.status[0, 0] in (DIVERGED, NONE_STABLE, NO_EQUILIBRIUM)
    elif np.ptp(run[-500:]) <= 1e-12 * max(1.0, abs(end)):  # the long run has settled
        if any(e.stable and e.ybar == pytest.approx(end, rel=1e-9, abs=1e-12) for e in model.equilibria(ubar)):
            assert res.status[0, 0] == REACHED
            assert res.ybar[0, 0] == pytest.approx(end, rel=1e-9, abs=1e-12)
        else:  # it sits exactly on an unstable equilibrium (started there): never counted
            assert res.status[0, 0] == NOT_SETTLED
    else:  # bounded and still moving after 3× the budget: an oscillation
        assert res.status[0, 0] in (NOT_SETTLED, NONE_STABLE)


def test_model17_middle_root_from_eq1_and_divergence_from_above():
    m = reference.paper_model(17)
    pts = reference.eq1_points()
    res = reached_equilibria(m.structure, m.theta[None], pts.ubar, pts.ybar)
    assert res.ok.all()
    for u, yb, y0 in zip(pts.ubar, res.ybar[0], pts.ybar):
        mid = [e for e in m.equilibria(u) if e.stable]
        assert len(mid) == 1 and yb == pytest.approx(mid[0].ybar, rel=1e-12)
        assert yb == pytest.approx(long_run(m, u, y0, 6000)[-1], rel=1e-9)
    # above the upper (unstable) equilibrium at 750 rpm (16.47 mlc) the run diverges
    with pytest.warns(RuntimeWarning) as said:
        assert jsf(m, StaticPoints([750.0, 1650.0], [30.0, 20.5])) == np.inf
    assert "ū = 750: the free run from y0 = 30 diverged" in str(said[0].message)
    assert "1650" not in str(said[0].message)  # only the failing point is named
    assert not np.isfinite(long_run(m, 750.0, 30.0, 2000)[-1])


def test_rational_structure_closed_form_needs_no_run():
    m = reference.paper_model(15)
    ub = np.array([750.0, 1200.0, 1650.0])
    for y0 in (-50.0, 0.0, 12.0, 500.0):  # linear in y at constant ū: reached from any start
        yb = m.static_curve(ub, y0=y0)
        for u, v in zip(ub, yb):
            assert v == pytest.approx(long_run(m, u, y0, 20000)[-1], rel=1e-8)
    # made unstable (Σy pushed above 1): the equilibrium exists but is never reached
    th = m.theta.copy()
    th[0] += 0.08
    bad = m.with_theta(th)
    assert all(not e.stable for e in bad.equilibria(1000.0))
    res = reached_equilibria(m.structure, th[None], [1000.0], [10.0])
    assert res.explain(0) == ["ū = 1000: no stable equilibrium"]
    assert not np.isfinite(long_run(bad, 1000.0, 10.0, 5000)[-1])


def test_every_evaluator_path_agrees_on_a_nonrational_population(paper_record):
    m = reference.paper_model(17)
    pts = reference.eq1_points()
    rng = np.random.default_rng(7)
    th = m.theta * (1 + 0.02 * rng.standard_normal((16, len(m.theta))))
    prob = SEProblem(m.structure, paper_record, pts)
    a = prob.jsf(th)
    b = evaluate_thetas(m.structure, th, static=pts)["JSF"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        c = np.array([jsf(m.with_theta(t), pts) for t in th])
    np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(a, c, rtol=1e-12)
    assert 4 <= np.isfinite(a).sum() < 16  # both kinds of member occur


def test_static_gradient_is_the_gradient_of_the_reached_equilibrium():
    m = reference.paper_model(17)
    pts = reference.eq1_points()
    yb = reached_equilibria(m.structure, m.theta[None], pts.ubar, pts.ybar).ybar[0]
    G = static_theta_gradient(m.structure, m.theta, pts.ubar, yb)
    for j in (0, 5, 12, 22):
        h = 1e-6 * abs(m.theta[j])
        tp, tm = m.theta.copy(), m.theta.copy()
        tp[j] += h
        tm[j] -= h
        r = reached_equilibria(m.structure, np.vstack([tp, tm]), pts.ubar, pts.ybar).ybar
        np.testing.assert_allclose((r[0] - r[1]) / (2 * h), G[:, j], rtol=1e-5)
