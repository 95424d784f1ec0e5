"""Bugs found by a bug hunt in the static analysis (equilibria, static curves, surfaces and gains, the
static constraints), the diagnostics (residual tests, parameter uncertainty, static-curve bands) and
the local models that read the statics, used as a control engineer would on their own data: models
with cross and cubic terms, several or no equilibria, two inputs not named "u", MA terms, units far
from 1 (Pa near 2e5, rpm near 3000), integrators and models unstable at some operating points,
compared with independent references. Each test fails without its fix."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import graybox as gb


def _bistable_fit():
    """Least squares of y(k) = 1.5 y(k-1) − 0.5 y(k-1)³ + 0.1 u(k-1) + noise: stable equilibria near ±1,
    an unstable one between them."""
    rng = np.random.default_rng(0)
    n = 400
    u = rng.uniform(-0.2, 0.2, n)
    y = np.zeros(n)
    y[0] = 0.9
    for k in range(1, n):
        y[k] = 1.5 * y[k - 1] - 0.5 * y[k - 1] ** 3 + 0.1 * u[k - 1] + 0.01 * rng.standard_normal()
    rec = gb.Record(u, y, Ts=1.0)
    model = gb.els(["y(k-1)", "y(k-1)^3", "u(k-1)"], rec, noise=0).model
    return model, gb.ls_uncertainty(model, rec)


def test_operating_curve_band_is_nan_where_the_model_reaches_no_equilibrium():
    # operating_curve's Monte Carlo band started every draw from the local model's ȳ, which exists where
    # the estimate's equilibrium is unstable too (linearised there): from the unstable middle equilibrium
    # of a bistable model the draws ran off to the stable ones at ±1, and the "95 %" band of the gain
    # at that point was [0.086, 0.104] around a gain of −0.19, the time constant's [0.16, 0.43] s
    # around τ = inf, with no draw counted as undefined
    model, unc = _bistable_fit()
    middle = sorted(e.ybar for e in model.equilibria(0.05))[1]
    oc = gb.operating_curve(model, [0.05, 0.05], y0=[middle, 0.9], uncertainty=unc, n_samples=200)
    assert oc.status == ("did not settle", "reached")
    for band in (oc.gain_low, oc.gain_high, oc.time_constant_low, oc.time_constant_high, oc.undefined):
        assert np.isnan(band[0])
    assert oc.gain_low[1] <= oc.gain[1] <= oc.gain_high[1] and oc.undefined[1] == 0.0


@pytest.mark.parametrize("bad", ["1", ["1", "-1"], [True, False], np.array([1 + 0j, 1])])
@pytest.mark.parametrize("call", [
    lambda y0: gb.Model(["y(k-1)", "y(k-1)^3", "q(k-1)"], [1.5, -0.5, 1e-3]).static_curve([0.0, 0.0], y0=y0),
    lambda y0: gb.Model(["y(k-1)", "y(k-1)^3", "q(k-1)"], [1.5, -0.5, 1e-3]).static_gain([0.0, 0.0], y0=y0),
    lambda y0: gb.Model(["y(k-1)", "y(k-1)^3", "a(k-1)", "b(k-1)"], [1.5, -0.5, 1e-3, 1.0]).static_curve(
        [[0.0, 0.0], [0.0, 0.0]], y0=y0),
    lambda y0: gb.StaticPoints([1.0, 2.0], [1.0, 2.0], uncertainty=y0),
    lambda y0: gb.operating_curve(gb.Model(["y(k-1)", "y(k-1)^3", "q(k-1)"], [1.5, -0.5, 1e-3]), [0.0, 0.0],
                                  y0=y0, Ts=1.0),
])
def test_a_per_point_value_that_is_not_numbers_is_a_type_error(call, bad):
    # y0 (and a static point's uncertainty) were converted by numpy: the text "1" was read as ȳ = 1 and a
    # mask [True, False] as y0 = [1, 0] (the run from 0 settles on nothing: NaN with strict=False), a
    # complex y0 lost its imaginary part with numpy's warning;
    # operating_curve refused a text y0 but read a list of texts
    with pytest.raises(TypeError, match="y0|uncertainty"):
        call(bad)


def test_a_surface_fitted_with_its_inputs_in_another_order_takes_the_points_by_name():
    # StaticSurface.fit(points, input_names=...) renamed the points' columns by position: points in
    # (speed, valve) fitted with input_names=("valve", "speed") gave "2e5 + 10 valve + 1e7 speed" for the
    # plane 2e5 + 10 speed + 1e7 valve, which every estimator then imposed, matched by name, without a word
    U = np.array([[2900.0, 1e-3], [3100.0, 1e-3], [2900.0, 2e-3], [3100.0, 2e-3], [3000.0, 1.5e-3]])
    points = gb.StaticPoints(U, 2e5 + 10.0 * U[:, 0] + 1e7 * U[:, 1], input_names=("speed", "valve"))
    surface = gb.StaticSurface.fit(points, 1, input_names=("valve", "speed"))
    assert surface.input_names == ("valve", "speed")
    np.testing.assert_allclose(surface(U[:, ::-1]), points.ybar, rtol=1e-12)
    np.testing.assert_allclose(surface.coefficient((1, 0)), 1e7, rtol=1e-9)  # valve's
    assert surface.domain == ((1e-3, 2e-3), (2900.0, 3100.0))
    renamed = gb.StaticSurface.fit(points, 1, input_names=("n", "v"))  # new names: the points' order
    np.testing.assert_allclose(renamed(U), points.ybar, rtol=1e-12)
    with pytest.raises(ValueError, match="rename some"):
        gb.StaticSurface.fit(points, 1, input_names=("valve", "n"))
    with pytest.raises(ValueError, match="2 distinct names"):
        gb.StaticSurface.fit(points, 1, input_names=("valve",))


@pytest.mark.parametrize("terms, inputs, key", [
    (["1", "y(k-1)", "speed(k-1)"], ("speed",), (2, 0)),
    (["1", "y(k-1)", "speed(k-1)", "valve(k-1)"], ("speed", "valve"), (1, 0)),
])
def test_a_cluster_key_the_structure_lacks_is_named_with_the_keys_it_has(terms, inputs, key):
    # ClusterBounds({(2, 0): ...}) on a structure without y², or a one-input key (1, 0) for two inputs
    # (whose keys are (p, a_speed, a_valve)), failed with Python's "tuple.index(x): x not in tuple"
    rng = np.random.default_rng(0)
    u = rng.uniform(2900.0, 3100.0, (200, len(inputs)))
    y = 2e5 + 0.01 * rng.standard_normal(200)
    rec = gb.Record(u[:, 0] if len(inputs) == 1 else u, y, input_names=inputs)
    model = gb.Model(terms, np.ones(len(terms)), input_names=inputs)
    with pytest.raises(ValueError, match=r"no cluster with key .*Σy \(1, 0"):
        model.cluster_map().index(key)
    with pytest.raises(ValueError, match=r"no cluster with key"):
        gb.cls(terms, rec, constraints=gb.ClusterBounds({key: (0.0, 0.5)}))


def _pressure_record(rng, n=500, c=(0.5,)):
    """Pressure (Pa, near 2e5) from a speed (rpm, near 3000) with MA equation noise 1 + Σ c_l q⁻ˡ."""
    s = np.repeat(rng.uniform(2800.0, 3200.0, n // 10 + 1), 10)[:n]
    e = 40.0 * rng.standard_normal(n)
    y = np.full(n, 2.0e5)
    for k in range(2, n):
        y[k] = (1e4 + 0.8 * y[k - 1] + 6.0 * s[k - 1] + 2e-3 * s[k - 1] ** 2 + e[k]
                + sum(cl * e[k - 1 - i] for i, cl in enumerate(c)))
    return gb.Record(s, y, input_names=("speed",), units=("rpm", "Pa"), Ts=0.1)


@pytest.mark.parametrize("ne", [1, 2])
def test_ls_uncertainty_refuses_an_els_model_of_other_data(ne):
    # ls_uncertainty checks that a plain LS model is the estimate on the data it is given, but took an ELS
    # model of another record of the same plant without a word and gave it a covariance (the share of its
    # residuals along its extended regressors was 0.1-0.16 there, ~1e-8-1e-7 on its own record)
    rng = np.random.default_rng(3)
    a, b = _pressure_record(rng), _pressure_record(rng)
    terms = ["1", "y(k-1)", "speed(k-1)", "speed(k-1)^2"]
    own = gb.els(terms, a, noise=ne).model
    assert np.all(gb.ls_uncertainty(own, a).std > 0)
    with pytest.raises(ValueError, match="not the optimum.*ELS estimate on these data"):
        gb.ls_uncertainty(own, b)


def test_operating_curve_refuses_the_uncertainty_of_another_estimate_of_the_structure():
    # the band checked only that the uncertainty's model had the same structure: the least-squares
    # covariance given with the CLS model of that structure (eq. (22) fixes its static curve, so its gain
    # has no spread) drew a gain band around the CLS gain as wide as least squares', without a word
    rng = np.random.default_rng(4)
    rec = _pressure_record(rng, c=())
    terms = ["1", "y(k-1)", "speed(k-1)", "speed(k-1)^2"]
    ls = gb.els(terms, rec, noise=0).model
    curve = gb.StaticCurve.polynomial(np.array([1e4, 6.0, 2e-3]) / 0.2, domain=(2850.0, 3150.0))
    gray = gb.cls(terms, rec, curve, reference=0.8).model
    with pytest.raises(ValueError, match="whose θ differs"):
        gb.operating_curve(gray, [2900.0, 3100.0], uncertainty=gb.ls_uncertainty(ls, rec), n_samples=50)
    own = gb.operating_curve(gray, [2900.0, 3100.0], uncertainty=gb.cls_uncertainty(gray, rec, curve, reference=0.8),
                             n_samples=50)
    np.testing.assert_allclose(own.gain_high - own.gain_low, 0.0, atol=1e-9 * np.abs(own.gain).max())


def test_bootstrap_on_records_too_short_for_a_block_says_so():
    # with block_length left at its default, records shorter than a block's minimum 2·(L + 1) gave
    # "block_length must be an integer >= 14, got 12", about an argument the user never passed
    rng = np.random.default_rng(0)
    rec = gb.Record(rng.uniform(0.0, 1.0, 12), rng.uniform(0.0, 1.0, 12))
    points = gb.StaticPoints([0.0, 0.5, 1.0], [0.0, 1.0, 2.0], uncertainty=0.1)
    with pytest.raises(ValueError, match=r"records \(\[12\] samples\) are too short .* at least 14"):
        gb.bootstrap_decision(["1", "y(k-6)", "u(k-1)"], rec, points, lambdas=[0.5, 1.0], n_boot=2, progress=False)


_TWO = gb.Model(["1", "y(k-1)", "speed(k-1)", "valve(k-1)"], [1e4, 0.5, 2.0, 1e6], input_names=("speed", "valve"))
_PLANE = gb.StaticSurface.polynomial({(0, 0): 2e5, (1, 0): 10.0, (0, 1): 1e7}, input_names=("speed", "valve"))


@pytest.mark.parametrize("bad", [[["3000", "1e-3"]], [["a", "b"]], [[3000.0 + 0j, 1e-3]], [[True, False]]])
@pytest.mark.parametrize("call", [
    _TWO.static_curve, _TWO.static_gain, _TWO.equilibria, _PLANE, _PLANE.gradient,
    lambda ub: gb.static_surface(_TWO.structure, _TWO.theta, ub),
])
def test_points_of_two_inputs_that_are_not_numbers_are_a_type_error(call, bad):
    # the surface paths converted ū with numpy: text "3000" was read as 3000 rpm, True as 1, a complex
    # level lost its imaginary part, and "a" failed with numpy's "could not convert string to float: 'a'"
    # naming no argument (the one-input paths refuse all of these as a TypeError naming ubar)
    with pytest.raises(TypeError, match="ū|ubar"):
        call(bad)


_ONE = gb.Model(["1", "y(k-1)", "speed(k-1)"], [1.0, 0.5, 2.0], input_names=("speed",))
_LINE = gb.StaticCurve.polynomial([1.0, 2.0], domain=(0.0, 5000.0))


def _one_band(ubar):
    rng = np.random.default_rng(0)
    u = rng.uniform(0.0, 1.0, 100)
    y = np.zeros(100)
    for k in range(1, 100):
        y[k] = 1.0 + 0.5 * y[k - 1] + 2.0 * u[k - 1] + 0.01 * rng.standard_normal()
    rec = gb.Record(u, y, input_names=("speed",))
    return gb.static_curve_band(gb.ls_uncertainty(gb.els(_ONE.structure, rec, noise=0).model, rec), ubar)


@pytest.mark.parametrize("bad", ["3000", ["1", "2"], True, [True, False], [1.0 + 1j]])
@pytest.mark.parametrize("call", [_ONE.static_curve, _ONE.static_gain, _LINE, _LINE.gain, _LINE.points,
                                  lambda ub: gb.static_curve(_ONE.structure, _ONE.theta, ub), _one_band])
def test_levels_of_one_input_that_are_not_numbers_are_a_type_error(call, bad):
    # a StaticCurve read the text "3000" as ū = 3000 (H = 6001) and True as 1; Model.static_curve refused
    # text but took True and [True, False] as the levels 1 and 0 (equilibria and local_model refuse them);
    # static_curve_band drew a band at ū = 0.5 for the text "0.5" and at ū = 1 for True
    with pytest.raises(TypeError, match="ubar"):
        call(bad)


def test_monte_carlo_bands_at_an_output_and_input_offset_match_the_delta_band():
    # The Monte Carlo draws came from the eigenvectors of θ's correlation matrix, which hold its small
    # directions only to eps: with y near 2e5 and u near 3000 those are the directions the static curve
    # is known along, and the "95 %" band of ȳ was 20 times as wide as the delta band (0.2 against
    # 0.009; the same record near 0 gave 0.009 both ways), the gain's and operating_curve's 1.2-1.7
    # times. The draws now come from the covariance's factor, as the delta band's contraction does.
    terms = ["1", "y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)", "u(k-1)^2", "u(k-2)y(k-1)"]
    rng = np.random.default_rng(0)
    n = 600
    u = np.repeat(rng.uniform(-1.0, 1.0, n // 5 + 1), 5)[:n]
    y = gb.Model(terms, [0.1, 0.9, -0.3, 0.5, 0.2, -0.05, 0.05]).simulate(u, [0.0, 0.0])
    rec = gb.Record(u + 3000.0, y + 0.01 * rng.standard_normal(n) + 2e5, Ts=0.1)
    fit = gb.els(terms, rec, noise=0).model
    unc = gb.ls_uncertainty(fit, rec)
    ub = np.array([2999.5, 3000.0, 3000.4])
    delta = gb.static_curve_band(unc, ub)
    mc = gb.static_curve_band(unc, ub, method="monte-carlo", n_samples=2000)
    oc = gb.operating_curve(fit, ub, uncertainty=unc, n_samples=2000)
    np.testing.assert_allclose(mc.ybar_high - mc.ybar_low, delta.ybar_high - delta.ybar_low, rtol=0.15)
    np.testing.assert_allclose(mc.gain_high - mc.gain_low, delta.gain_high - delta.gain_low, rtol=0.15)
    np.testing.assert_allclose(oc.gain_high - oc.gain_low, delta.gain_high - delta.gain_low, rtol=0.15)


def test_narx_initial_state_refuses_a_record_at_another_period():
    # narx_initial_state took the lags of a record sampled every 1 s for a model identified at 0.1 s, whose
    # system then ran at 0.1 s from them; Model.simulate, which its docstring says the run equals, refuses it
    model = gb.Model(["1", "y(k-1)", "speed(k-2)", "valve(k-1)"], [1.0, 0.5, 2.0, 1e3], input_names=("speed", "valve"),
                     Ts=0.1)
    u = np.c_[np.linspace(2900.0, 3100.0, 5), np.linspace(1e-3, 2e-3, 5)]
    slow = gb.Record(u, np.linspace(2e5, 2.1e5, 5), input_names=("speed", "valve"), Ts=1.0)
    with pytest.raises(ValueError, match="sampled"):
        gb.narx_initial_state(model, slow)
    same = gb.Record(u, np.linspace(2e5, 2.1e5, 5), input_names=("speed", "valve"), Ts=0.1)
    np.testing.assert_array_equal(gb.narx_initial_state(model, same), [2.025e5, 2950.0, 2900.0, 1.25e-3])


@pytest.mark.parametrize("estimator", ["pe", "se"])
def test_the_default_static_sigma_counts_what_the_member_absorbs_of_the_points(estimator):
    # The default σ_SF was the member's static misfit √mean(((QRθ − ȳ)/D)²) (PE) or √J_SF (SE), said to
    # err on the safe side; at small λ1 the member meets the points with its free static coefficients, so
    # the misfit holds almost none of their noise: with 3 points (σ_SF = 20 Pa) at λ1 = 0.01 PE read
    # σ_SF ≈ 0.36 Pa and the predicted std of ȳ(3050 rpm) was 0.38 Pa against a spread over replicates of
    # 17 Pa (45 times optimistic; SE 0.26 Pa against 14 Pa). The misfit is now divided by its degrees of
    # freedom (M at λ1 = 1).
    rng = np.random.default_rng(1)
    a1, b1, b2 = 0.8, 10.0, 0.004
    c0 = 2e5 * (1 - a1) - b1 * 3000 - b2 * 3000**2
    terms = ["1", "y(k-1)", "speed(k-1)", "speed(k-1)^2"]
    levels = np.array([2900.0, 3000.0, 3100.0])
    n = 300
    ybar, std = [], []
    for _ in range(30):
        s = np.repeat(rng.uniform(2850.0, 3150.0, n // 5 + 1), 5)[:n]
        y = np.full(n, 2e5)
        for k in range(1, n):
            y[k] = c0 + a1 * y[k - 1] + b1 * s[k - 1] + b2 * s[k - 1] ** 2 + 50.0 * rng.standard_normal()
        rec = gb.Record(s, y, input_names=("speed",), Ts=0.1)
        points = gb.StaticPoints(levels, (c0 + b1 * levels + b2 * levels**2) / (1 - a1) + 20.0 * rng.standard_normal(3),
                                 input_names=("speed",))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", gb.StaticRangeWarning)
            if estimator == "pe":
                member = gb.Model(terms, gb.pe_thetas(terms, rec, points, lambdas=[0.01])[0], input_names=("speed",),
                                  Ts=0.1)
                unc = gb.pe_uncertainty(member, rec, points, lambda1=0.01)
            else:
                member = gb.se_pareto(terms, rec, points, lambdas=[0.01], method="gradient", progress=False).member_model(0)
                unc = gb.se_uncertainty(member, rec, points, lambda1=0.01)
        band = gb.static_curve_band(unc, [3050.0])
        ybar.append(band.ybar[0])
        std.append(band.ybar_std[0])
    spread = np.std(ybar)
    assert 0.6 * spread < np.mean(std) < 3.0 * spread


@pytest.mark.parametrize("noise, theta", [(["e(k-1)"], [1.5]), (["e(k-1)u(k-1)"], [3.0])])
def test_residual_tests_refuse_residuals_that_grow_without_bound(noise, theta):
    # an MA part 1 + 1.5q⁻¹ (a root outside the unit circle) makes the one-step residuals grow as 1.5^k:
    # residual_tests let numpy's overflow warnings out and judged inf and NaN correlations ("failed" on
    # all five tests), or, on a shorter record, correlations of residuals of 1e50; one_step_residuals
    # returned them. ls_uncertainty refused that model already, with the words used now for all three.
    rng = np.random.default_rng(0)
    n = 3000
    u = rng.uniform(1.0, 2.0, n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + u[k - 1] + 0.1 * rng.standard_normal()
    model = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0], noise_structure=noise, noise_theta=theta)
    for call in (gb.residual_tests, gb.one_step_residuals, gb.ls_uncertainty):
        with pytest.raises(ValueError, match="not invertible|overflow"):
            call(model, gb.Record(u, y))


@pytest.mark.parametrize("call", [gb.pe_uncertainty, gb.se_uncertainty])
def test_a_member_that_meets_its_exact_static_points_takes_static_sigma_zero(call):
    # at λ1 near 0 a member meets its static points exactly and its misfit cannot estimate σ_SF, which is
    # then asked for; points known exactly (σ_SF = 0) were refused as "static_sigma must lie in (0, inf)"
    rng = np.random.default_rng(1)
    terms = ["1", "y(k-1)", "speed(k-1)", "speed(k-1)^2"]
    s = np.repeat(rng.uniform(2850.0, 3150.0, 61), 5)[:300]
    y = np.full(300, 2e5)
    for k in range(1, 300):
        y[k] = 2e4 + 0.8 * y[k - 1] + 10.0 * s[k - 1] + 1e-3 * (s[k - 1] - 3000.0) ** 2 + 50.0 * rng.standard_normal()
    rec = gb.Record(s, y, input_names=("speed",), Ts=0.1)
    points = gb.StaticPoints([2900.0, 3100.0], [(2e4 + 10.0 * p + 1e-3 * (p - 3000.0) ** 2) / 0.2 for p in (2900.0, 3100.0)],
                             input_names=("speed",))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        member = gb.Model(terms, gb.pe_thetas(terms, rec, points, lambdas=[1e-4])[0], input_names=("speed",), Ts=0.1)
        with pytest.raises(ValueError, match="meets its 2 static points exactly.*0 for exact points"):
            call(member, rec, points, lambda1=1e-4)
        unc = call(member, rec, points, lambda1=1e-4, static_sigma=0.0)
    assert unc.static_sigma2 == 0.0 and np.all(np.isfinite(unc.std))


def test_a_residual_test_that_was_not_made_says_why_when_asked_for():
    # tests["u2_xi"] of a balanced two-level input (left out: u'² is constant) and tests["u_xi"] of a
    # two-input record (whose keys are "u_xi:speed", "u_xi:valve") were a bare KeyError: 'u2_xi'
    rng = np.random.default_rng(0)
    u = np.r_[2900.0, np.repeat(rng.permutation(np.r_[np.full(20, 2900.0), np.full(20, 3100.0)]), 10)]
    n = u.size  # the residuals start at sample 1: the levels balanced from there
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + 0.01 * u[k - 1] + 0.1 * rng.standard_normal()
    model = gb.Model(["y(k-1)", "speed(k-1)"], [0.5, 0.01], input_names=("speed",))
    with pytest.warns(UserWarning, match="undefined"):
        tests = gb.residual_tests(model, gb.Record(u, y, input_names=("speed",)))
    with pytest.raises(KeyError, match="not made on these data: input 'speed' takes two levels"):
        tests["u2_xi"]
    with pytest.raises(KeyError, match=r"no test 'u_xi:valve'; the tests made are \['xi_xi', 'u_xi'"):
        tests["u_xi:valve"]
    assert tests["u_xi"].name == "u_xi"


def test_a_curve_with_a_zero_top_coefficient_is_of_the_lower_degree_as_a_surface_is():
    # StaticCurve.degree was the number of coefficients less one: [κ, α, 0] (a line written with a zero
    # quadratic term) was of degree 2, so the static-form check asked the structures for a Σu² cluster
    # (and select_graybox warned that degree-1 candidates cannot carry the curve), while a surface with
    # zero quadratic coefficients is of degree 1
    from graybox.static._form_check import static_degree
    line = gb.StaticCurve.polynomial([2e5, 10.0, 0.0], domain=(2900.0, 3100.0))
    plane = gb.StaticSurface.polynomial({(0, 0): 2e5, (1, 0): 10.0, (0, 1): 1e7, (2, 0): 0.0, (1, 1): 0.0})
    assert line.degree == plane.degree == 1
    assert static_degree(line, band=1.0) == 1
    assert gb.StaticCurve.polynomial([0.0]).degree == 0 and gb.StaticCurve.polynomial([1.0, 0.0, 3.0]).degree == 2


def test_clusters_whose_names_would_collide_keep_both():
    # with inputs "pos" and "ypos" the clusters Σ_{y·pos} and Σ_{ypos} were both named "Σypos": Model.clusters()
    # kept one of them (0.01, losing ypos's 2.0) and ClusterBounds({"Σypos": ...}) bounded whichever came first
    model = gb.Model(["1", "y(k-1)", "ypos(k-1)", "pos(k-1)", "y(k-1)pos(k-1)"], [1.0, 0.5, 2.0, 3.0, 0.01],
                     input_names=("pos", "ypos"))
    assert model.clusters() == {"Σ0": 1.0, "Σypos": 2.0, "Σpos": 3.0, "Σy": 0.5, "Σy·pos": 0.01}
    cm = model.cluster_map()
    assert cm.keys[cm.index("Σypos")] == (0, 0, 1) and cm.keys[cm.index("Σy·pos")] == (1, 1, 0)
    plain = gb.Model(["1", "y(k-1)", "speed(k-1)", "y(k-1)valve(k-1)"], [1.0, 0.5, 2.0, 3.0],
                     input_names=("speed", "valve"))
    assert list(plain.clusters()) == ["Σ0", "Σspeed", "Σy", "Σyvalve"]  # names as before where none collide
