"""Slow plants sampled fast: whether an equilibrium is reached, and the static band's stability margin,
must not depend on how many samples the plant's time constant spans."""

import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st

import graybox as gb
from graybox.static import _analysis
from graybox.static._analysis import SETTLE_STEPS, reached_equilibria
from graybox.static._equilibrium_kernels import NOT_SETTLED, REACHED

#: A term in y² keeps the settling run in play (a rational structure is decided in closed form).
QUAD = gb.Structure(["y(k-1)", "y(k-1)^2", "u(k-1)"])
QUAD2 = gb.Structure(["y(k-1)", "y(k-1)^2", "u1(k-1)", "u2(k-1)"])
TAUS = [10.0, 100.0, 1e3, 1e4, 1e5]  # samples


def _slow_quad(tau: float) -> tuple[np.ndarray, float]:
    """θ of y = a y1 + c y1² + u1 whose equilibrium ȳ = 1 has the pole ρ = exp(−1/τ), and the ū that puts it there.

    c = (1 − ρ)/10 and a = ρ − 2c (f'(1) = a + 2c = ρ): the other equilibrium is ū/c = 11, far off.
    """
    rho = np.exp(-1.0 / tau)
    c = (1.0 - rho) / 10.0
    a = rho - 2.0 * c
    return np.array([a, c, 1.0]), 1.0 - a - c


def _stable_root(a: float, c: float, u: float) -> float:
    """The root of c ȳ² + (a − 1) ȳ + u = 0 where 1 − a − 2 c ȳ > 0 (the stable one), by the quadratic formula."""
    disc = np.sqrt((a - 1.0) ** 2 - 4.0 * c * u)
    roots = [(1.0 - a + s * disc) / (2.0 * c) for s in (-1.0, 1.0)]
    return next(r for r in roots if abs(a + 2.0 * c * r) < 1.0)


def test_the_reproducer_a_pole_of_0_9999_is_reached():
    a = 0.5
    b = (0.9999 - a) / 2
    u = 1 - a - b
    m = gb.Model(QUAD, [a, b, 1.0])
    end = m.simulate(np.full(200000, u), np.zeros(1))[-1]
    assert end == pytest.approx(1.0, rel=1e-6)
    assert m.static_curve([u], y0=0.0, strict=False)[0] == pytest.approx(end, rel=1e-6)


@pytest.mark.parametrize("tau", TAUS)
def test_one_input_the_equilibrium_is_reached_whatever_the_time_constant(tau):
    th, u = _slow_quad(tau)
    res = reached_equilibria(QUAD, th[None], [u, u], [0.0, 5.0])
    assert res.status[0].tolist() == [REACHED, REACHED]
    np.testing.assert_allclose(res.ybar[0], [1.0, 1.0], rtol=1e-12)
    pts = gb.StaticPoints([u], [1.0])
    assert gb.jsf(gb.Model(QUAD, th), pts) == pytest.approx(0.0, abs=1e-20)


@pytest.mark.parametrize("tau", TAUS[:4])
def test_the_reached_equilibrium_is_where_a_long_free_run_ends(tau):
    th, u = _slow_quad(tau)
    ub = 0.8 * u  # off the constructed point: an equilibrium the test finds by the quadratic formula
    y = gb.Model(QUAD, th).simulate(np.full(int(60 * tau) + 100, ub), np.zeros(1))
    root = _stable_root(th[0], th[1], ub)
    assert y[-1] == pytest.approx(root, rel=1e-9)
    assert gb.Model(QUAD, th).static_curve([ub], y0=0.0)[0] == pytest.approx(root, rel=1e-9)


@pytest.mark.parametrize("tau", TAUS)
def test_two_inputs_the_equilibrium_is_reached_whatever_the_time_constant(tau):
    th1, u = _slow_quad(tau)
    th = np.array([th1[0], th1[1], 1.0, 1.0])  # ū1 + ū2 plays the one input's part
    m = gb.Model(QUAD2, th, input_names=("u1", "u2"))
    ys = m.static_curve(np.array([[u / 2, u / 2], [u, 0.0]]), y0=0.0)
    np.testing.assert_allclose(ys, [1.0, 1.0], rtol=1e-12)


def test_a_run_slower_than_the_longest_budget_is_not_run_and_named_not_settled(monkeypatch):
    monkeypatch.setattr(_analysis, "SETTLE_MAX_STEPS", 2 * SETTLE_STEPS)
    th, u = _slow_quad(1e4)
    res = reached_equilibria(QUAD, th[None], [u], [0.0])
    assert res.status[0, 0] == NOT_SETTLED
    assert f"time constants of the slowest (one over {40000 // _analysis.SETTLE_TAUS} samples is not run)" in \
        res.explain(0)[0]


def _first_order(a: float, gain: float, k: int) -> np.ndarray:
    """y = a y1 + 0 y1² + b u1 with static gain ``gain``, sampled k times faster under a zero-order hold."""
    ak = a ** (1.0 / k)
    return np.array([ak, 0.0, gain * (1.0 - ak)])


@settings(max_examples=40, deadline=None)
@given(a=st.floats(0.5, 0.999), k=st.integers(1, 200), u=st.floats(-5.0, 5.0), y0=st.floats(-5.0, 5.0),
       gain=st.floats(0.2, 5.0))
def test_reached_does_not_depend_on_the_sampling_rate(a, k, u, y0, gain):
    slow, fast = _first_order(a, gain, 1), _first_order(a, gain, k)
    assume(-k / np.log(a) <= 1e5)  # time constants up to 10⁵ samples (the budget's cap lies beyond)
    res = reached_equilibria(QUAD, np.vstack([slow, fast]), [u], [y0])
    assert res.status[0, 0] == res.status[1, 0] == REACHED
    np.testing.assert_allclose(res.ybar[:, 0], [gain * u, gain * u], rtol=1e-9, atol=1e-9 * (1 + abs(y0)))


# -- the static band's stability margin -------------------------------------------------------------
FIRST = gb.Structure(["y(k-1)", "u(k-1)"])


def _first_order_records(a: float, *, n: int = 5000, R: int = 10, noise: float = 1e-3, seed: int = 0):
    """R records of y = a y1 + (1 − a) u1 (static gain 1) under steps of 500 samples, and 10 static points."""
    rng = np.random.default_rng(seed)
    recs = []
    for _ in range(R):
        u = np.repeat(rng.uniform(0.0, 2.0, n // 500 + 1), 500)[:n]
        y = gb.simulate(FIRST, np.array([a, 1.0 - a]), u, np.array([rng.uniform(0.0, 2.0)]))
        recs.append(gb.Record(u, y + noise * rng.standard_normal(n)))
    ub = np.linspace(0.2, 1.8, 10)
    pts = gb.StaticPoints(ub, ub + 0.01 * rng.standard_normal(10), uncertainty=np.full(10, 0.05))
    return recs, pts


def _fit(recs, pts, constraints):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        return gb.cls(FIRST, recs, pts, how="context", constraints=constraints).model.theta


def test_the_band_does_not_force_a_slow_plant_faster():
    # y = 0.9998 y1 + 0.0002 u1 (τ ≈ 5000 samples): the least-squares estimate meets the band, so the
    # band must leave it alone; a fixed margin D >= 10⁻³ made it θ = [0.999, 9.9e-4]
    recs, pts = _first_order_records(0.9998)
    ls = _fit(recs, pts, [])
    assert ls[0] > 0.9995
    assert np.abs(gb.Model(FIRST, ls).static_curve(pts.ubar) - pts.ybar).max() < 0.05  # inside the band
    np.testing.assert_allclose(_fit(recs, pts, gb.StaticBand()), ls, rtol=1e-6)
    np.testing.assert_allclose(_fit(recs, pts, gb.GainBounds(lower=0.0)), ls, rtol=1e-6)


@settings(max_examples=12, deadline=None)
@given(tau=st.floats(5.0, 1e5), seed=st.integers(0, 100))
def test_the_band_leaves_a_least_squares_estimate_inside_it_alone_whatever_the_sampling_rate(tau, seed):
    a = float(np.exp(-1.0 / tau))
    recs, pts = _first_order_records(a, n=2000, R=6, noise=0.0, seed=seed)
    ls = _fit(recs, pts, [])
    assume(ls[0] < 1.0)
    assume(np.abs(gb.Model(FIRST, ls).static_curve(pts.ubar) - pts.ybar).max() < 0.05)
    th = _fit(recs, pts, gb.StaticBand())
    # the time scale 1 − a and the static gain, to the QP solver's accuracy (a fixed margin of 10⁻³ on
    # 1 − a moved a plant with τ = 10⁴ samples tenfold)
    assert 1.0 - th[0] == pytest.approx(1.0 - ls[0], rel=1e-3)
    assert th[1] / (1.0 - th[0]) == pytest.approx(ls[1] / (1.0 - ls[0]), rel=1e-3)


def test_the_default_margin_still_keeps_the_band_from_going_vacuous():
    # a cluster bound that pushes Σy to within a twentieth of the least-squares estimate's 1 − Σy:
    # the band's margin (a tenth of it) refuses, as 10⁻³ refuses on a fast plant
    recs, pts = _first_order_records(0.9998)
    ls = _fit(recs, pts, [])
    push = gb.ClusterBounds({"Σy": (1.0 - (1.0 - ls[0]) / 20.0, None)})
    with pytest.raises(gb.InfeasibleError):
        _fit(recs, pts, [gb.StaticBand(), push])
    # with the margin given, as small as the push, the band holds it
    th = _fit(recs, pts, [gb.StaticBand(min_denominator=(1.0 - ls[0]) / 40.0), push])
    assert th[0] >= 1.0 - (1.0 - ls[0]) / 20.0 - 1e-12


def test_gain_bounds_do_not_force_a_very_slow_plant_faster():
    # τ = 5·10⁶ samples: 1 − a = 2·10⁻⁷, under GainBounds' former fixed margin of 10⁻⁶ (noise-free data)
    a = 1.0 - 2e-7
    recs, pts = _first_order_records(a, n=2000, R=6, noise=0.0)
    ls = _fit(recs, pts, [])
    assert 1.0 - ls[0] == pytest.approx(2e-7, rel=1e-3)
    th = _fit(recs, pts, gb.GainBounds(lower=0.0, upper=2.0))
    assert 1.0 - th[0] == pytest.approx(1.0 - ls[0], rel=0.05)  # the QP's accuracy here; 10⁻⁶ was 5×


# -- the budget's time constant ---------------------------------------------------------------------
@settings(max_examples=30, deadline=None)
@given(th=st.lists(st.floats(-0.6, 0.6), min_size=5, max_size=5), u=st.floats(0.1, 2.0))
def test_the_budget_reads_the_spectral_radius_the_equilibria_report(th, u):
    # the compiled linearisation of the folded recursion against Model.equilibria's (numpy roots)
    from graybox.core._simulation_kernels import encode
    from graybox.static._analysis import POLY, _fold_map
    from graybox.static._equilibrium_kernels import candidate_linearisations

    structure = gb.Structure(["y(k-1)", "y(k-2)", "y(k-1)y(k-3)", "y(k-2)^2", "u(k-1)"])
    theta = np.array(th)
    eqs = [e for e in gb.Model(structure, theta).equilibria(u) if e.stable]
    assume(eqs)
    ip, onehot, L = _fold_map(structure)
    fp = ((theta * u ** encode(structure).mu)[None, :]) @ onehot
    cand = np.array([[e.ybar for e in eqs]])
    a = candidate_linearisations(POLY, ip, fp, cand, np.array([len(eqs)]), L)[0]
    for e, row in zip(eqs, a):
        rho = np.abs(np.roots(np.concatenate(([1.0], -row)))).max()
        assert rho == pytest.approx(e.spectral_radius, rel=1e-9, abs=1e-12)


@settings(max_examples=25, deadline=None)
@given(r=st.floats(0.99, 0.9999), angle=st.floats(0.0, 0.5), y0=st.floats(-3.0, 3.0), c=st.floats(-0.02, 0.02))
def test_going_on_after_the_first_budget_is_one_longer_run(r, angle, y0, c):
    # two lags (the history handed over has two outputs), a slow pair of poles r e^(±i angle) at ȳ = 0
    # and a y² term: the run that stops at SETTLE_STEPS and goes on ends as one run given the whole budget
    structure = gb.Structure(["y(k-1)", "y(k-2)", "y(k-1)^2", "u(k-1)"])
    theta = np.array([2 * r * np.cos(angle), -r * r, c, 1.0])
    u = [0.0, 1e-4, -1e-4]
    two = reached_equilibria(structure, theta[None], u, [y0] * 3)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(_analysis, "SETTLE_STEPS", _analysis.SETTLE_MAX_STEPS)
        one = reached_equilibria(structure, theta[None], u, [y0] * 3)
    np.testing.assert_array_equal(two.status, one.status)
    np.testing.assert_array_equal(two.ybar, one.ybar)


def test_two_inputs_the_band_does_not_force_a_slow_plant_faster():
    # y = 0.9998 y1 + 10⁻⁴ u1 + 10⁻⁴ u2: static ȳ = (ū1 + ū2) / 2, τ ≈ 5000 samples
    structure = gb.Structure(["y(k-1)", "u1(k-1)", "u2(k-1)"])
    a = 0.9998
    rng = np.random.default_rng(1)
    recs = []
    for _ in range(8):
        u = np.repeat(rng.uniform(0.0, 2.0, (11, 2)), 500, axis=0)[:5000]
        y = gb.simulate(structure, np.array([a, (1 - a) / 2, (1 - a) / 2]), u, np.array([rng.uniform(0.0, 2.0)]))
        recs.append(gb.Record(u, y + 1e-3 * rng.standard_normal(5000), input_names=("u1", "u2")))
    ub = rng.uniform(0.2, 1.8, (10, 2))
    pts = gb.StaticPoints(ub, ub.mean(axis=1) + 0.01 * rng.standard_normal(10), uncertainty=np.full(10, 0.05),
                          input_names=("u1", "u2"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        ls = gb.cls(structure, recs, pts, how="context", constraints=[]).model.theta
        th = gb.cls(structure, recs, pts, how="context", constraints=gb.StaticBand()).model.theta
    assert ls[0] > 0.9995
    assert 1.0 - th[0] == pytest.approx(1.0 - ls[0], rel=1e-3)  # a fixed 10⁻³ made it 0.999


def test_auto_margin_without_a_least_squares_reference_is_the_former_fixed_one():
    from graybox.static._constraints import StaticContext, auto_min_denominator

    ctx = StaticContext(FIRST)  # no ls_theta: e.g. the regressors do not identify θ
    one, dR = np.ones(3), np.full((3, 2), 0.5)
    assert auto_min_denominator("auto", 1e-3, ctx, one, dR) == 1e-3
    assert auto_min_denominator(2e-5, 1e-3, ctx, one, dR) == 2e-5
    # with one whose D_i are 0.02, 0.01 and -0.5 (not a reference there): a tenth of the smallest positive
    ls = StaticContext(FIRST, ls_theta=np.array([0.98, 0.0]))
    dR = np.array([[1.0, 0.0], [0.99 / 0.98, 0.0], [1.5 / 0.98, 0.0]])
    assert auto_min_denominator("auto", 1e-2, ls, one, dR) == pytest.approx(0.001, rel=1e-9)
    assert auto_min_denominator("auto", 1e-4, ls, one, dR) == 1e-4  # never above the ceiling


def test_a_grid_spec_band_takes_auto_by_default():
    from graybox.experiments._spec import build_constraint, canonical_constraint

    d = canonical_constraint({"type": "band"}, ())
    assert d["min_denominator"] == "auto"
    assert build_constraint(d).min_denominator == "auto"
    assert canonical_constraint({"type": "band", "min_denominator": 1e-5}, ())["min_denominator"] == 1e-5
    g = canonical_constraint({"type": "gain", "lower": 0.0}, ())
    assert g["min_denominator"] == "auto"
