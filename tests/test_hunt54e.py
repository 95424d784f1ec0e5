"""hunt54e: statics and free runs (what hunt48b did not try)."""

import numpy as np
import pytest

import graybox as gb


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_simulate_many_refuses_a_non_finite_theta_row_naming_it(bad):
    # simulate_many ran a NaN (or inf) θ and returned its run as NaN from the first sample on, as if the member had
    # diverged, where evaluate_thetas refuses the same row as no model: one rule, the rows named
    rec = gb.Record(np.linspace(0.0, 1.0, 20), np.linspace(0.0, 2.0, 20))
    st = ["y(k-1)", "u(k-1)"]
    with pytest.raises(ValueError, match=r"thetas: row \[1\] \(1 of 2\) not finite"):
        gb.simulate_many(st, [[0.5, 1.0], [bad, 1.0]], rec)
    assert np.isfinite(gb.simulate_many(st, [[0.5, 1.0], [0.4, 1.0]], rec)).all()


@pytest.mark.parametrize("box, kind, match", [
    ([("0", "10"), (1.0, 2.0)], TypeError, r"ubar_range of input 1 must be a real number, got '0'"),
    ([(0.0, 10.0), (False, True)], TypeError, r"ubar_range of input 2 must be a real number, got False"),
    ([(0.0, 10.0), 5.0], TypeError, r"ubar_range of input 2 must be \(low, high\)"),
    ([(0.0, 10.0), (1.0, 2.0, 3.0)], ValueError, r"one \(low, high\) per input"),
])
def test_gain_bounds_box_refuses_ends_that_are_no_numbers(box, kind, match):
    # a range per input read each end with float(): "10" was parsed and True read as 1 (the box ((0, 10), (0, 1))
    # built), where the one-input pair and the ranges by name refuse them naming the input
    with pytest.raises(kind, match=match):
        gb.GainBounds(lower=0.0, ubar_range=box)
    assert gb.GainBounds(lower=0.0, ubar_range=[(0, 10), (1.0, 2.0)]).ubar_range == ((0.0, 10.0), (1.0, 2.0))


def test_static_messages_tell_offset_input_levels_apart():
    # the static surface's "several stable equilibria" named both points ū = (10000, 10000), and equilibria's
    # continuum refusal said ū = 10000 of the level 10000.01 (%g's six digits): the static curve tells them apart
    bistable = gb.Model(["y(k-1)", "y(k-1)^3", "a(k-1)", "b(k-1)"], [1.5, -0.5, 1e-9, -1e-9], input_names=("a", "b"))
    U = np.array([[10000.01, 10000.0], [10000.02, 10000.0]])
    with pytest.raises(ValueError, match=r"ū = \(10000\.01, 10000\) .*ū = \(10000\.02, 10000\) "):
        bistable.static_curve(U)
    integrator = gb.Model(["y(k-1)", "a(k-1)", "b(k-1)"], [1.0, 1.0, -1.0], input_names=("a", "b"))
    with pytest.raises(ValueError, match=r"^ū = \(10000\.01, 10000\.01\): a continuum"):
        integrator.equilibria([10000.01, 10000.01])
    with pytest.raises(ValueError, match=r"^ū = 10000\.01: a continuum"):
        gb.equilibria(["y(k-1)", "u(k-1)"], [1.0, 0.0], 10000.01)


def test_domain_refusals_tell_the_domain_ends_apart():
    # "ū = [10000.0] outside the domain [10000, 10000]": the ends of a narrow domain far from zero printed alike
    # (%g), and the refused level seemed to lie on them; a fit to one level said ū = 10000 of 10000.01
    c = gb.StaticCurve.fit(gb.StaticPoints([10000.01, 10000.03, 10000.05], [1.0, 2.0, 3.5]), 2)
    with pytest.raises(ValueError, match=r"ū = \[10000\.0\] outside the domain \[10000\.01, 10000\.05\]"):
        c(10000.0)
    U = np.array([[10000.01, 1.0], [10000.03, 2.0], [10000.05, 1.0], [10000.02, 2.0]])
    s = gb.StaticSurface.fit(gb.StaticPoints(U, [1.0, 2.0, 3.0, 4.0], input_names=("a", "b")), 1)
    with pytest.raises(ValueError, match=r"a = \[10000\.06\] outside the domain \[10000\.01, 10000\.05\]"):
        s([[10000.06, 1.5]])
    with pytest.raises(ValueError, match=r"one level \(ū = 10000\.01\)"):
        gb.StaticCurve.fit(gb.StaticPoints([10000.01], [1.0]), 1)
    with pytest.raises(ValueError, match=r"outside the domain \[0\.6, 1\.8\]"):  # as before where %g tells them
        gb.StaticCurve.polynomial([1.0], domain=(0.6, 1.8))(2.0)


def test_a_diverging_settling_run_names_its_start_as_given():
    # "the free run from y0 = 10005 diverged" of the run started at 10005.01 (%g), an output 1e4 from its zero:
    # y(k) = 0.5 y + 0.1 y² + u written in y' = y + 1e4, whose unstable equilibrium at ū = 0 is y' = 10005
    c = 1e4
    m = gb.Model(["1", "y(k-1)", "y(k-1)^2", "u(k-1)"], [c - 0.5 * c + 0.1 * c * c, 0.5 - 0.2 * c, 0.1, 1.0])
    with pytest.raises(ValueError, match=r"ū = 0: the free run from y0 = 10005\.01 diverged"):
        m.static_curve([0.0], y0=c + 5.01)
    assert m.static_curve([0.0], y0=c + 4.9)[0] == pytest.approx(c, abs=1e-6)  # the stable one, y' = 1e4


def _heater():
    """Two time constants, 1 h and 30 min, sampled at 1 s; static gain 0.5 °C per %: D = 1 − a1 − a2 = 1.5e-7, so
    the steady output (25 °C at 50 %) is 6.5e6 times the input's direct push b u."""
    a1, a2 = np.exp(-1 / 3600), np.exp(-1 / 1800)
    d = (1 - a1) * (1 - a2)
    return gb.Model(["y(k-1)", "y(k-2)", "u(k-1)"], [a1 + a2, -a1 * a2, 0.5 * d])


@pytest.mark.parametrize("threads", [1, 2])
def test_a_stable_slow_plant_run_from_rest_is_not_divergence(threads):
    # the default bound was 1e6 × the push b u: the heater's free run from 0 °C passed it at sample 1797 (3.9 °C)
    # on its way to 25 °C: DivergenceError, J_S = inf for the exact model, NaN in simulate_many; the push now
    # counts at the level it holds the output at through the linear feedback (b u / D)
    m = _heater()
    u = np.full(3000, 50.0)
    y = m.simulate(u, [0.0, 0.0])
    assert np.isfinite(y).all() and 4.0 < y[-1] < m.static_curve([50.0])[0] == pytest.approx(25.0)
    rec = gb.Record(u, y)
    assert gb.js(m, rec) == 0.0
    assert np.array_equal(m.predict(rec, horizon=len(rec)), y)
    thetas = np.vstack([m.theta] * 4)
    np.testing.assert_allclose(gb.simulate_many(m, thetas, rec, threads=threads), np.vstack([y] * 4), rtol=1e-9)
    assert np.all(gb.evaluate_thetas(m, thetas, rec, threads=threads)["JS"] < 1e-12)
    # made unstable (a pole at 1.0005), the same plant from rest is still caught running off
    with pytest.raises(gb.DivergenceError):
        gb.Model(m.structure, [m.theta[0] + 1e-3, m.theta[1], m.theta[2]]).simulate(np.full(20000, 50.0), [0.0, 0.0])


def test_static_points_holding_an_input_the_model_does_not_use_are_read_by_name():
    # a model of one input ('speed') on data of two ('speed', 'valve'): j1 and js take the records' speed by name,
    # evaluate_thetas scored J_SF at the points' speed, but jsf (and so evaluate's table) refused the points:
    # "2 input columns ('speed', 'valve'), but the model has one input ('speed',)"
    m = gb.Model(["y(k-1)", "speed(k-1)"], [0.5, 1.0])
    u = np.c_[np.linspace(1.0, 2.0, 30), np.linspace(0.0, 3.0, 30)]
    rec = gb.Record(u, np.linspace(1.0, 4.0, 30), input_names=("speed", "valve"))
    sp = gb.StaticPoints([[1.0, 0.0], [2.0, 3.0]], [2.0, 4.1], input_names=("speed", "valve"))
    assert gb.jsf(m, sp) == pytest.approx(0.005)
    assert gb.evaluate_thetas(m, m.theta, rec, sp)["JSF"][0] == pytest.approx(0.005)
    table = gb.evaluate({"m": m}, gb.Dataset(rec, rec, sp))
    assert table.loc["m", "JSF"] == pytest.approx(0.005) and table.loc["m", "JS_valid"] == gb.js(m, rec)
    other = gb.Model(["y(k-1)", "flow(k-1)"], [0.5, 1.0])  # an input the points do not have: still refused
    with pytest.raises(ValueError, match="2 input columns"):
        gb.jsf(other, sp)


def test_a_model_given_as_the_structure_reads_its_points_in_its_own_input_order():
    # gb.static_surface(model, θ, ū) read ū's columns in the structure's order (a, b), not the model's (b, a): 402
    # where model.static_curve says 204 (the levels of a and b swapped, silently); gb.simulate(model, θ, u) refused
    # the model's own array as of inputs ('u1', 'u2')
    m = gb.Model(["y(k-1)", "a(k-1)", "b(k-1)"], [0.5, 1.0, 100.0], input_names=("b", "a"))
    pt = [[1.0, 2.0]]  # b = 1, a = 2
    assert gb.static_surface(m, m.theta, pt).tolist() == m.static_curve(pt).tolist() == [204.0]
    assert gb.static_surface_gain(m, m.theta, pt).tolist() == m.static_gain(pt).tolist() == [[200.0, 2.0]]
    assert [e.ybar for e in gb.surface_equilibria(m, m.theta, pt[0])] == [e.ybar for e in m.equilibria(pt[0])] == [204.0]
    u = np.tile(pt[0], (5, 1))
    assert np.array_equal(gb.simulate(m, m.theta, u, [0.0]), m.simulate(u, [0.0]))
    # a Structure (no order of its own) still reads the structure's inputs' order, and input_names= overrides
    assert gb.static_surface(m.structure, m.theta, pt).tolist() == [402.0]
    assert gb.static_surface(m, m.theta, pt, input_names=("a", "b")).tolist() == [402.0]


@pytest.mark.parametrize("k", [-700, -530, -400, 0, 400, 530, 660])
def test_figures_of_merit_do_not_depend_on_the_output_scale(k):
    # RRSE and fit % of an output near 2^±530 (1e±160): numpy's norms squared the samples, so near 1e200 the output
    # was 'constant' (ValueError) and near 1e-160 RRSE was 0.173176 for 0.173205; mse, j1, js and jsf warned
    # 'overflow encountered in square' (an error under -W error) where the error is beyond the float range
    s = 2.0**k
    y = np.array([0.0, 1.0, 3.0, 2.0, 5.0])
    yh = np.array([0.5, 1.0, 2.5, 2.0, 4.0])
    assert gb.rrse(s * y, s * yh) == pytest.approx(gb.rrse(y, yh), rel=1e-14)
    assert gb.fit_percent(s * y, s * yh) == pytest.approx(gb.fit_percent(y, yh), rel=1e-14)
    expected = np.mean((s * y - s * yh) ** 2) if abs(k) < 500 else None
    with np.errstate(over="raise", invalid="raise"):  # numpy's default ignores underflow: 2^-1400 is 0
        got = gb.mse(s * y, s * yh)
    if expected is not None:
        assert got == pytest.approx(expected, rel=1e-14)
    elif k > 0:
        assert got == np.inf  # beyond the float range, said as inf


def test_scores_of_a_run_beyond_the_float_range_are_inf_without_numpy_warnings():
    m = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0])
    rec = gb.Record(np.full(20, 1e200), np.linspace(0.0, 1.0, 20))
    sp = gb.StaticPoints([1e200, 2e200], [1.0, 2.0])
    with np.errstate(over="raise", invalid="raise"):
        assert gb.j1(m, rec) == gb.js(m, rec) == gb.jsf(m, sp) == np.inf
        assert gb.rrse(rec.y, np.full(20, 1e308)) == np.inf


@pytest.mark.parametrize("other", [dict(units=("rad/s", "mlc")), dict(Ts=0.5)], ids=["units", "period"])
def test_the_free_run_functions_given_a_model_refuse_records_it_does_not_hold_on(other):
    # gb.simulate, gb.predict and gb.simulate_many given a Model ran a record in other units (or at another period)
    # with its θ, silently, where Model.simulate, js, jsf and evaluate_thetas refuse it
    m = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0], Ts=1.0, units=("rpm", "mlc"))
    rec = gb.Record(np.ones(10), np.ones(10), **({"Ts": 1.0, "units": ("rpm", "mlc")} | other))
    for call in (lambda: gb.simulate(m, m.theta, rec), lambda: gb.predict(m, m.theta, rec),
                 lambda: gb.simulate_many(m, m.theta[None], rec), lambda: m.simulate(rec)):
        with pytest.raises(ValueError, match="model '' was identified"):
            call()
    ok = gb.Record(np.ones(10), np.ones(10), Ts=1.0, units=("rpm", "mlc"))
    assert np.array_equal(gb.simulate(m, m.theta, ok), m.simulate(ok))
    assert np.array_equal(gb.simulate(m.structure, m.theta, rec), m.simulate(ok))  # a Structure knows no units


def test_a_stable_run_held_by_feedback_through_the_input_is_not_divergence():
    # the bound's gain counted the terms θ y(k−l) alone: feedback through y·u was not seen, and this plant's run
    # from rest (at u = 1, y(k) = (1 − 1e-7) y(k−1) + 1e-7 = 1 − (1 − 1e-7)^k, on its way to 1) was called divergent
    # at sample 1053606
    m = gb.Model(["y(k-1)", "y(k-1)u(k-1)", "u(k-1)"], [-0.5, 1.5 - 1e-7, 1e-7])
    u = np.ones(1_100_000)
    y = m.simulate(u, [0.0])
    k = np.arange(0, len(u), 1000)
    np.testing.assert_allclose(y[k], -np.expm1(k * np.log1p(-1e-7)), rtol=1e-6, atol=1e-12)
    rec = gb.Record(u, y)
    assert gb.js(m, rec) < 1e-20
    assert np.array_equal(m.predict(rec, horizon=len(rec)), y)
    np.testing.assert_allclose(gb.simulate_many(m, m.theta[None, :], rec)[0], y, rtol=1e-9)


@pytest.mark.parametrize("threads", [1, 2])
def test_a_run_diverging_through_the_input_still_stops_early(threads):
    # feedback 1.1 through y·u at u = 1: y(k) = 1e-6 (1.1^k − 1) passes 1e6 × the push 1e-7 at k = 121
    m = gb.Model(["y(k-1)", "y(k-1)u(k-1)", "u(k-1)"], [-0.5, 1.6, 1e-7])
    u = np.ones(400)
    with pytest.raises(gb.DivergenceError, match=r"at sample 121 "):
        m.simulate(u, [0.0])
    y = m.simulate(u, [0.0], on_diverge="nan")
    runs = gb.simulate_many(m, np.vstack([m.theta] * 3), gb.Record(u, np.zeros(400)), threads=threads)
    for row in runs:
        assert np.isfinite(row[:121]).all() and np.isnan(row[121:]).all()
    np.testing.assert_allclose(runs[0][:121], y[:121], rtol=1e-12)


def test_a_stable_resonance_driven_at_its_frequency_is_not_divergence():
    # poles 0.9999999 e^{±jπ/2}: stable, and a sine at π/2 rad/sample builds the output up to |b| / |A(e^{jπ/2})|
    # ≈ 5e6 |b| over ~10⁷ samples; the bound held it at 1e6 × its steady gain 1 / A(1) ≈ 1 / 2, clipped to 1:
    # DivergenceError near sample 2e6. The linear feedback's gain for any input, Π 1 / (1 − |p|) over its poles,
    # now counts
    r, w = 1 - 1e-7, np.pi / 2
    m = gb.Model(["y(k-1)", "y(k-2)", "u(k-1)"], [2 * r * np.cos(w), -r * r, 1.0])
    k = np.arange(2_400_000)
    u = np.sin(w * k)
    y = m.simulate(u, [0.0, 0.0])
    # by hand: driven at resonance from rest the amplitude grows as (1 − r^k) / ((1 − r) 2 sin w), between
    # e^{−(1−r)k/2} k / (2 sin w) and k / (2 sin w)
    amp = np.abs(y[-1000:]).max()
    assert 0.99 * len(k) / (2 * np.sin(w)) * np.exp(-(1 - r) * len(k) / 2) < amp < len(k) / (2 * np.sin(w))
    assert gb.js(m, gb.Record(u, y)) == 0.0  # the batch runs' bound is the same
    # the same resonator a hair unstable (poles 1 + 1e-4) is still caught, within its first 2e5 samples
    with pytest.raises(gb.DivergenceError):
        gb.Model(m.structure, [2 * 1.0001 * np.cos(w), -1.0001 ** 2, 1.0]).simulate(u[:200_000], [0.0, 0.0])


@pytest.mark.parametrize("threads", [1, 2])
def test_a_growing_pair_whose_steady_gain_looks_large_is_still_caught(threads):
    """Poles 1.001 e^{±0.01j} (unstable) give D = 1 − Σa ≈ 1e-4 in (0, 1): the bound took 1/D = 1e4 as the gain and
    let the run grow to 1.5e9 uncaught (review55a), where it stopped at sample 4668 before 1b0c1fe; a recursion with
    a pole outside the unit circle has no steady level, so the push's own scale holds again."""
    m = gb.Model(["y(k-1)", "y(k-2)", "u(k-1)"], [2 * 1.001 * np.cos(0.01), -1.001**2, 1.0])
    assert 0 < 1 - m.theta[0] - m.theta[1] < 1e-3  # the case: D in (0, 1), small
    u = np.ones(12_000)
    with pytest.raises(gb.DivergenceError, match=r"at sample 4668 "):
        m.simulate(u, [0.0, 0.0])
    runs = gb.simulate_many(m, np.vstack([m.theta] * 3), gb.Record(u, np.zeros(u.size)), threads=threads)
    assert np.isnan(runs[:, 4668:]).all() and np.isfinite(runs[:, :4668]).all()
