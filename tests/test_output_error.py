"""Output error (pure simulation-error fit), the stability margin, and D_SF on a choosing record."""

from fractions import Fraction

import numpy as np
import pytest

import graybox as gb
from graybox.estimation._decisions import decide_dsf
from graybox.estimation._local_models import LocalModels, record_points
from graybox.estimation._output_error import OEResult, output_error
from graybox.estimation._pareto import ParetoSet
from graybox.estimation._simulation_error import SEProblem, se_pareto

#: A nonlinear output-error system: x(k) = 0.7 x(k-1) + 0.25 u(k-1) + 0.1 u(k-2)^2 - 0.05 x(k-1) u(k-1),
#: measured as y = x + v with white v (noise on the output only).
OE_STRUCT = gb.Structure(["y(k-1)", "u(k-1)", "u(k-2)^2", "u(k-1)y(k-1)"])
OE_THETA = np.array([0.7, 0.25, 0.1, -0.05])


def oe_record(seed, N=1500, noise=0.15, name="oe"):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1.0, 1.0, N // 8 + 1), 8)[:N]
    x = gb.Model(OE_STRUCT, OE_THETA).simulate(u, np.zeros(2))
    return gb.Record(u, x + noise * rng.standard_normal(N), name=name), x


@pytest.fixture(scope="module")
def oe_data():
    fit, _ = oe_record(1)
    test, clean = oe_record(2, noise=0.0, name="test")
    return fit, test


def test_recovers_an_output_error_system_better_than_least_squares(oe_data):
    fit, test = oe_data
    r = output_error(OE_STRUCT, fit, n_starts=3, seed=0, ridge=0.0)  # pure output error
    assert isinstance(r, OEResult)
    ls = SEProblem(OE_STRUCT, fit, None).ls_theta()
    err_oe = np.linalg.norm(r.model.theta - OE_THETA)
    err_ls = np.linalg.norm(ls - OE_THETA)
    # noise on the output biases least squares (its regressors hold the noisy past output)
    assert err_oe < 0.5 * err_ls
    assert abs(r.model.theta[0] - OE_THETA[0]) < abs(ls[0] - OE_THETA[0])
    # and the free run on noise-free data follows the system more closely
    assert gb.js(r.model, test) < gb.js(gb.Model(OE_STRUCT, ls), test)
    assert r.JS == pytest.approx(gb.js(r.model, fit), rel=1e-9)
    assert np.isnan(r.JS_choose) and r.chosen_on == "" and np.isnan(r.margin)
    # the default (a ridge towards least squares) pays some bias for robustness, and still beats least squares
    d = output_error(OE_STRUCT, fit, n_starts=3, seed=0)
    err_d = np.linalg.norm(d.model.theta - OE_THETA)
    assert err_oe < err_d < err_ls
    assert gb.js(d.model, test) < gb.js(gb.Model(OE_STRUCT, ls), test)


def test_reproducible_with_a_seed(oe_data):
    fit, _ = oe_data
    a = output_error(OE_STRUCT, fit, n_starts=2, seed=5, max_nfev=20)
    b = output_error(OE_STRUCT, fit, n_starts=2, seed=5, max_nfev=20)
    np.testing.assert_array_equal(a.model.theta, b.model.theta)
    assert a.starts.equals(b.starts)
    c = output_error(OE_STRUCT, fit, n_starts=2, seed=6, max_nfev=20)
    # another seed draws other subsample starts
    assert not np.array_equal(a.starts["JS_start"].to_numpy()[-2:], c.starts["JS_start"].to_numpy()[-2:])


def test_reports_failed_starts(oe_data):
    fit, _ = oe_data
    r = output_error(OE_STRUCT, fit, n_starts=1, theta0=np.array([3.0, 0.0, 0.0, 0.0]), max_nfev=20)
    row = r.starts[r.starts["start"] == "theta0"]
    assert list(row["status"]) == ["infeasible"] and "diverges" in row["message"].iloc[0]
    assert "theta0" in r.failures and "diverges" in r.failures["theta0"]
    assert set(r.starts["status"]) <= {"fitted", "infeasible", "failed"}
    assert (r.starts["status"] == "fitted").sum() >= 2  # least squares and ELS at least, with both solvers
    assert "theta0" not in r.start


def test_needs_no_static_points(oe_data):
    fit, _ = oe_data
    ds = gb.Dataset(ident=fit, valid=oe_data[1], static=None)
    r = output_error(OE_STRUCT, ds, n_starts=0, max_nfev=10)
    assert np.all(np.isfinite(r.model.theta))
    # the SE front still needs them: its λ < 1 members weigh the static points
    with pytest.raises(ValueError, match="static points"):
        se_pareto(OE_STRUCT, fit, lambdas=[1.0, 0.5], method="gradient")


def test_choosing_record_picks_the_iterate_with_the_smallest_js_there(oe_data):
    fit, test = oe_data
    choose, _ = oe_record(3, N=600, name="choose")
    r = output_error(OE_STRUCT, fit, n_starts=2, choose_on=choose, max_nfev=30)
    assert r.chosen_on == "choose"
    assert r.JS_choose == pytest.approx(gb.js(r.model, choose), rel=1e-9)
    fitted = r.starts[r.starts["status"] == "fitted"]
    assert r.JS_choose <= fitted["JS_choose"].min() * (1 + 1e-12)
    # no fitted end point nor start has a lower J_S on the choosing record than the returned iterate
    assert r.JS_choose <= gb.js(gb.Model(OE_STRUCT, SEProblem(OE_STRUCT, fit, None).ls_theta()), choose)


@pytest.mark.parametrize("margin", [0.2, 0.4])
def test_the_margin_holds_on_the_fitted_model(oe_data, margin):
    fit, _ = oe_data
    r = output_error(OE_STRUCT, fit, n_starts=2, margin=margin, max_nfev=30)
    assert r.margin == margin
    assert r.radius <= 1 - margin + 1e-9
    pts = LocalModels(OE_STRUCT, *record_points(OE_STRUCT, [fit]))
    assert pts.radius(r.model.theta).max() <= 1 - margin + 1e-9
    # the local models at the model's own equilibria inside the record's input range keep it too
    for ub in np.quantile(fit.u, [0.05, 0.5, 0.95]):
        for eq in r.model.equilibria(float(ub)):
            assert eq.spectral_radius <= 1 - margin + 1e-9
    # the margin binds here: the unconstrained fit's feedback 0.7 - 0.05 u reaches 0.75 > 1 - 0.4
    if margin == 0.4:
        assert output_error(OE_STRUCT, fit, n_starts=0, max_nfev=30, ridge=0.0).radius > 1 - margin


def test_a_start_outside_the_margin_is_pulled_inside(oe_data):
    fit, _ = oe_data
    r = output_error(OE_STRUCT, fit, n_starts=0, margin=0.4, theta0=np.array([0.95, 0.25, 0.1, 0.0]), max_nfev=10)
    pulled = [s for s in r.starts["start"] if s.startswith("theta0")]
    assert pulled and all("feedback ×" in s for s in pulled)
    assert r.radius <= 0.6 + 1e-9


@pytest.mark.parametrize("method", ["gradient", "ga"])
@pytest.mark.parametrize("margin", [0.35, 0.45])
def test_se_front_members_keep_the_margin(method, margin):
    fit, _ = oe_record(4, N=800)
    x_static = np.array([-0.8, 0.0, 0.8])
    m = gb.Model(OE_STRUCT, OE_THETA)
    static = gb.StaticPoints(x_static, m.static_curve(x_static))
    kw = {"options": gb.GAOptions(population=30, generations=5)} if method == "ga" else {"max_nfev": 20}
    ps = se_pareto(OE_STRUCT, fit, static, lambdas=[1.0, 0.3], method=method, margin=margin, seed=0, **kw)
    pts = LocalModels(OE_STRUCT, *record_points(OE_STRUCT, [fit]))
    problem = SEProblem(OE_STRUCT, fit, static, margin=margin)
    if margin == 0.45:  # least squares (and the PE starts) lie outside: the sweep pulls them in, nothing fails
        assert not problem.within_margin(problem.ls_theta())[0]
        assert not ps.failures
    for i in range(len(ps)):
        if i in ps.failures:
            continue
        assert pts.radius(ps.thetas[i]).max() <= 1 - margin + 1e-9
        for ub in x_static:
            for eq in gb.Model(OE_STRUCT, ps.thetas[i]).equilibria(float(ub)):
                if eq.stable:
                    assert eq.spectral_radius <= 1 - margin + 1e-9


def test_bad_options(oe_data):
    fit, _ = oe_data
    for kw, match in [({"margin": 1.0}, "margin"), ({"margin": -0.1}, "margin"), ({"n_starts": -1}, "n_starts"),
                      ({"subsample": 0.0}, "subsample"), ({"solver": "bfgs"}, "solver"),
                      ({"theta0": np.ones(3)}, "theta0")]:
        with pytest.raises(ValueError, match=match):
            output_error(OE_STRUCT, fit, **kw)
    with pytest.raises(TypeError, match="choose_on"):  # a Dataset would stand for its ident, the fitting data
        output_error(OE_STRUCT, fit, choose_on=gb.Dataset(ident=fit, valid=fit, static=None))


# -- D_SF on a choosing record ------------------------------------------------------------------------------
def test_dsf_chooses_on_the_choosing_record(oe_data):
    fit, _ = oe_data
    choose, _ = oe_record(3, N=600, name="choose")
    thetas = np.array([OE_THETA, OE_THETA * [1.3, 1, 1, 1], OE_THETA * [1, 0.5, 1, 1], OE_THETA * [0.9, 1, 1, 1]])
    k = len(thetas)
    # the identification J_S stored in the set says member 1 is best; the choosing record is asked instead
    ps = ParetoSet(OE_STRUCT, thetas, np.linspace(1, 0.1, k), np.zeros(k), np.array([0.5, 0.1, 0.2, 0.3]),
                   np.array([0.0, 0.0, 0.0, 1.0]), "test")
    assert decide_dsf(ps, band=0.5).index == 1
    d = decide_dsf(ps, band=0.5, choose_on=choose)
    on_choose = np.array([gb.js(gb.Model(OE_STRUCT, t), choose) for t in thetas])
    in_band = np.flatnonzero(ps.JSF <= 0.5)
    assert d.index == in_band[np.argmin(on_choose[in_band])]
    assert d.score == pytest.approx(on_choose[d.index], rel=1e-9)
    assert d.JS == ps.JS[d.index] and d.chosen_on == "choose" and "on choose" in d.model.name
    assert decide_dsf(ps, band=0.5).chosen_on == ""
    with pytest.raises(ValueError, match="choose_on"):
        decide_dsf(ps, band=0.5, choose_on=[])


# -- regularisation towards least squares -------------------------------------------------------------------
def test_ridge_factor_matches_finite_differences(oe_data):
    from test_se import assert_factor_matches_finite_differences

    fit, _ = oe_data
    x_static = np.array([-0.8, 0.0, 0.8])
    static = gb.StaticPoints(x_static, gb.Model(OE_STRUCT, OE_THETA).static_curve(x_static))
    problem = SEProblem(OE_STRUCT, fit, static, ridge=0.3)
    z = OE_THETA * problem.scale  # away from least squares: the ridge rows are not zero
    for lam1 in (1.0, 0.4):
        assert_factor_matches_finite_differences(problem, z, lam1)
        # the GA's cost is the same regularised objective
        from graybox.estimation._simulation_error import _residuals

        r = _residuals(problem, z, lam1)
        assert problem.cost(OE_THETA[None], lam1)[0] == pytest.approx(r @ r, rel=1e-10)


def test_ridge_pulls_towards_least_squares(oe_data):
    fit, _ = oe_data
    ls = SEProblem(OE_STRUCT, fit, None).ls_theta()
    free = output_error(OE_STRUCT, fit, n_starts=0, max_nfev=40, ridge=0.0).model.theta
    held = output_error(OE_STRUCT, fit, n_starts=0, max_nfev=40, ridge=1e4).model.theta
    mild = output_error(OE_STRUCT, fit, n_starts=0, max_nfev=40, ridge=1e-3).model.theta
    assert np.linalg.norm(held - ls) < 0.05 * np.linalg.norm(free - ls)
    d_mild = np.linalg.norm(mild - ls)
    assert np.linalg.norm(held - ls) < d_mild <= np.linalg.norm(free - ls) * (1 + 1e-9)
    with pytest.raises(ValueError, match="ridge"):
        output_error(OE_STRUCT, fit, ridge=-1.0)


# -- the margin test itself ---------------------------------------------------------------------------------
from hypothesis import assume, given, settings  # noqa: E402
from hypothesis import strategies as hst  # noqa: E402


@settings(max_examples=200, deadline=None)
@given(a=hst.lists(hst.floats(-1.5, 1.5), min_size=1, max_size=6), margin=hst.floats(0.0, 0.9))
def test_scaled_schur_cohn_agrees_with_the_roots(a, margin):
    """ρ(a) < 1 − margin exactly when the compiled test on the scaled polynomial says so."""
    from graybox.estimation._local_models import _radius, _within

    row = np.array([a])
    rho = _radius(row)[0]
    assume(abs(rho - (1 - margin)) > 1e-9)  # the boundary itself is measure zero and rounding-sensitive
    assert bool(_within(row, margin)[0]) == (rho < 1 - margin)


def test_local_models_are_the_linearisation_of_the_model(oe_data):
    """a_l at a point equals the derivative of the one-step map with respect to y(k-l), by differences."""
    fit, _ = oe_data
    theta = np.array([0.6, 0.3, 0.1, -0.2])
    ub, yb = np.array([0.3, -0.7]), np.array([0.5, 1.2])
    a = LocalModels(OE_STRUCT, ub, yb).coefficients(theta)
    for p in range(2):
        def step(y1):  # y(k) from y(k-1) = y1, every input lag at ū
            return theta[0] * y1 + theta[1] * ub[p] + theta[2] * ub[p] ** 2 + theta[3] * ub[p] * y1
        h = 1e-6
        assert a[p, 0] == pytest.approx((step(yb[p] + h) - step(yb[p] - h)) / (2 * h), rel=1e-8)


def test_checkpoints_tell_margins_and_ridges_apart(oe_data):
    fit, _ = oe_data
    static = gb.StaticPoints(np.array([-0.5, 0.5]), np.array([0.0, 0.5]))
    plain = SEProblem(OE_STRUCT, fit, static).fingerprint()
    assert SEProblem(OE_STRUCT, fit, static, margin=0.1).fingerprint() != plain
    assert SEProblem(OE_STRUCT, fit, static, ridge=0.1).fingerprint() != plain
    assert SEProblem(OE_STRUCT, fit, static, margin=None, ridge=0.0).fingerprint() == plain


def test_structure_carriers_and_a_choosing_record_that_is_the_fitting_one(oe_data):
    fit, _ = oe_data
    sel = gb.frols(gb.Candidates(1, 2, ne=0, degree=2), fit, n_terms=4)
    a = output_error(sel, fit, n_starts=1, max_nfev=5, seed=0)  # a Selection stands for its structure
    b = output_error(sel.structure, fit, n_starts=1, max_nfev=5, seed=0)
    np.testing.assert_array_equal(a.model.theta, b.model.theta)
    with pytest.raises(ValueError, match="choose_on: a choosing record is a fitting record"):
        output_error(OE_STRUCT, fit, choose_on=fit)


def _oe_static_problem():
    fit, _ = oe_record(4, N=800)
    x_static = np.array([-0.8, 0.0, 0.8])
    static = gb.StaticPoints(x_static, gb.Model(OE_STRUCT, OE_THETA).static_curve(x_static))
    return fit, static


@pytest.mark.parametrize("margin", [0.35, 0.45])
def test_se_dsf_keeps_the_margin(margin):
    fit, static = _oe_static_problem()
    res = gb.se_dsf(OE_STRUCT, fit, static, band=0.01, margin=margin, lambdas=[0.5, 0.1], max_iter=30)
    assert res.in_band
    pts = LocalModels(OE_STRUCT, *record_points(OE_STRUCT, [fit]))
    assert pts.radius(res.model.theta).max() <= 1 - margin + 1e-9
    for ub in static.ubar:
        for eq in res.model.equilibria(float(ub)):
            if eq.stable:
                assert eq.spectral_radius <= 1 - margin + 1e-9
    # the margin binds at 0.45: the fit without it leaves the margin
    if margin == 0.45:
        free = gb.se_dsf(OE_STRUCT, fit, static, band=0.01, lambdas=[0.5, 0.1], max_iter=30)
        assert pts.radius(free.model.theta).max() > 1 - margin


def test_se_dsf_pulls_a_start_inside_the_margin():
    fit, static = _oe_static_problem()
    outside = np.array([0.95, 0.25, 0.1, 0.0])
    assert not SEProblem(OE_STRUCT, fit, static, margin=0.4).within_margin(outside)[0]
    res = gb.se_dsf(OE_STRUCT, fit, static, band=0.05, margin=0.4, theta0=outside, max_iter=10)
    assert res.start.startswith("theta0, feedback ×")
    assert LocalModels(OE_STRUCT, *record_points(OE_STRUCT, [fit])).radius(res.model.theta).max() <= 0.6 + 1e-9


def test_ga_starts_join_every_initial_population():
    fit, static = _oe_static_problem()
    opts = gb.GAOptions(population=20, generations=2)
    lam = [1.0, 0.3]
    problem = SEProblem(OE_STRUCT, fit, static)
    plain = se_pareto(OE_STRUCT, fit, static, lambdas=lam, method="ga", seed=0, options=opts, theta0=None)
    seeded = se_pareto(OE_STRUCT, fit, static, lambdas=lam, method="ga", seed=0, options=opts, theta0=None,
                       starts=[OE_THETA])
    # elitism keeps the start: every member's cost is at most the true θ's at its λ
    for i, l1 in enumerate(seeded.lambdas):
        assert seeded.extra["cost"][i] <= problem.cost(OE_THETA[None], l1)[0] * (1 + 1e-12)
    # from random individuals only, two generations do not get there
    assert plain.extra["cost"][0] > seeded.extra["cost"][0]
    with pytest.raises(ValueError, match="starts"):
        se_pareto(OE_STRUCT, fit, static, lambdas=lam, method="ga", options=opts, starts=[OE_THETA] * 20)
    with pytest.raises(ValueError, match="starts"):
        se_pareto(OE_STRUCT, fit, static, lambdas=lam, method="ga", options=opts, starts=[np.zeros(2)])


def test_ga_starts_pe_are_the_pe_solutions():
    from graybox.estimation._simulation_error import _pe_starts
    fit, static = _oe_static_problem()
    opts = gb.GAOptions(population=20, generations=2)
    kw = dict(lambdas=[1.0, 0.3], method="ga", seed=0, options=opts)
    pe = _pe_starts(SEProblem(OE_STRUCT, fit, static))
    assert len(pe) == 4
    named = se_pareto(OE_STRUCT, fit, static, starts="pe", **kw)
    given = se_pareto(OE_STRUCT, fit, static, starts=pe, **kw)
    np.testing.assert_array_equal(named.thetas, given.thetas)
    with pytest.raises(ValueError, match="starts"):
        se_pareto(OE_STRUCT, fit, static, starts="ls", **kw)


def test_a_fit_that_ends_diverging_is_not_reported_fitted():
    # a start whose free run diverges slowly (a huge but finite sum of squares) that the solver cannot bring back
    # within one evaluation: its row says where the run diverges, as simulate would call it, not "fitted" (the
    # fit's cost bounds the run as simulate does, so such a start is refused before it is fitted)
    from graybox.estimation._simulation_error import SEProblem

    rng = np.random.default_rng(0)
    u = rng.uniform(0, 1, 300)
    y = gb.simulate(gb.Structure(["y(k-1)", "u(k-1)"]), np.array([0.5, 1.0]), u, np.zeros(1))
    rec = gb.Record(u, y + 0.01 * rng.standard_normal(300), 1.0)
    st = gb.Structure(["y(k-1)", "u(k-1)"])
    bad = np.array([1.5, 1.0])
    p = SEProblem(st, [rec], None)
    assert np.isfinite(p.js(bad[None], bounded=False)[0]) and not np.isfinite(p.js(bad[None])[0])
    assert p.diverges(bad) and not p.diverges(np.array([0.5, 1.0]))
    res = gb.output_error(st, rec, theta0=bad, n_starts=0, max_nfev=1, ridge=0.0, margin=None)
    row = res.starts[res.starts["start"].str.startswith("theta0")]
    assert set(row["status"]) <= {"failed", "infeasible"} and row["message"].str.contains("diverges").all()


def test_output_errors_starts_table_reports_the_theta_each_start_offers():
    # with choose_on, a row's JS was its last iterate's and its JS_choose the best watched iterate's: two models in
    # one row, and the winning row's JS differed from the result's (hunt45c's note)
    rng = np.random.default_rng(3)
    n = 600
    u = np.repeat(rng.uniform(0.5, 2.0, n // 5), 5)
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = 0.5 * y[k - 1] + 0.2 * y[k - 2] + 0.3 * u[k - 1] + 0.1 * u[k - 2] ** 2
    y += 0.05 * rng.standard_normal(n) + np.cumsum(0.01 * rng.standard_normal(n))  # a slow disturbance
    fit_rec, choose = gb.Record(u[:400], y[:400], name="fit"), gb.Record(u[400:], y[400:], name="choose")
    st = ["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2", "1"]
    res = gb.output_error(st, fit_rec, n_starts=3, choose_on=choose, progress=False)
    fitted = res.starts[res.starts["status"] == "fitted"]
    win = fitted[fitted["JS_choose"] == fitted["JS_choose"].min()].iloc[0]
    assert win["JS_choose"] == pytest.approx(res.JS_choose, rel=1e-12)
    assert win["JS"] == pytest.approx(res.JS, rel=1e-9)
    assert win["JS"] == pytest.approx(gb.js(res.model, fit_rec), rel=1e-9)


def test_a_least_squares_start_beyond_the_float_range_is_refused_in_words():
    # u about 1e-100 and y about 1e150: u(k-1)²'s parameter, about 1e349, is no float. The centred problem's least
    # squares overflowed in from_z with numpy's bare "overflow encountered in matmul" (an error under -W error;
    # otherwise an inf start reported as "least squares: free run diverges")
    st = gb.Structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "y(k-2)"])
    rng = np.random.default_rng(1)
    u = rng.uniform(-1.0, 1.0, 60)
    y = gb.Model(st, np.array([0.1, 1.2, 0.25, 0.1, -0.4])).simulate(u, np.zeros(2))
    rec = gb.Record(1e-100 * u, 1e150 * y)
    with pytest.raises(ValueError, match=r"least squares: the parameter\(s\) of \['u\(k-1\)\^2'\] are beyond the "
                                         "float range.*rescale the signals"):
        output_error(st, rec, n_starts=1, margin=None)
    with pytest.raises(ValueError, match=r"\['u\(k-1\)\^2'\] are beyond the float range"):
        se_pareto(st, rec, gb.StaticPoints(1e-100 * np.array([-0.5, 0.0, 0.5]), 1e150 * np.ones(3)),
                  lambdas=[0.5], method="gradient")


def test_a_least_squares_start_below_the_float_range_is_refused_in_words():
    # u about 1e100 and y about 1e-150: u(k-1)²'s parameter, about 1e-351, is below the normal floats. It became 0
    # without a word (θ [1.3e-151, 1.197, 2.4e-251, 0, -0.3996]: the term dropped, the others fitted without it), where
    # the overflow side is refused (9210ff7c); cls did the same (its u(k-1)² θ 0), ELS refuses it by name
    st = gb.Structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "y(k-2)"])
    rng = np.random.default_rng(1)
    u = rng.uniform(-1.0, 1.0, 60)
    y = gb.Model(st, np.array([0.1, 1.2, 0.25, 0.1, -0.4])).simulate(u, np.zeros(2))
    rec = gb.Record(1e100 * u, 1e-150 * y)
    far = r"the parameter\(s\) of \['u\(k-1\)\^2'\] are beyond the float range.*rescale the signals"
    with pytest.raises(ValueError, match="least squares: " + far):
        output_error(st, rec, n_starts=1, margin=None)
    with pytest.raises(ValueError, match=far):
        gb.cls(st, rec)


@pytest.mark.parametrize("ey", [-520, -531, -565, 520])
def test_an_output_near_the_float_ranges_ends_is_fitted_as_in_ordinary_units(ey):
    # y × 2^ey (about 1e-157, 1e-170, 1e157): J_S's squares left the float range. At 2^-520 every start failed
    # ("array must not contain infs or NaNs", LAPACK's DLASCL on stderr), at 2^-565 J_S was 0 and the fits stopped
    # at their starts (θ 0.02 off), at 2^520 every start "diverged". Fitted on the signals times a power of two (as
    # frols, semp and els are), θ is the same model and J_S the same in the data's units (0 or inf beyond the range)
    st = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)y(k-1)", "1"])
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(-1.0, 1.0, 51), 4)[:200]
    y = gb.simulate(st, np.array([1.2, -0.45, 0.5, -0.1, 0.05]), u, np.zeros(2)) + 0.05 * rng.standard_normal(200)
    half = (gb.Record(u[:120], y[:120], name="fit"), gb.Record(u[120:], y[120:], name="choose"))
    kw = dict(n_starts=1, max_nfev=20, progress=False)
    ref = output_error(st, half[0], choose_on=half[1], **kw)
    far = [gb.Record(r.u, np.ldexp(r.y, ey), name=r.name) for r in half]
    res = output_error(st, far[0], choose_on=far[1], **kw)
    # y(k-1), y(k-2), u(k-1)y(k-1) keep their θ; u(k-1) and the constant carry y's unit
    np.testing.assert_allclose(res.model.theta, np.ldexp(ref.model.theta, [0, 0, ey, 0, ey]), rtol=1e-9)
    with np.errstate(over="ignore", under="ignore"):
        for got, want in ((res.JS, ref.JS), (res.JS_choose, ref.JS_choose)):
            assert got == pytest.approx(np.ldexp(want, 2 * ey), rel=1e-6, abs=1e-320)
            # one rule, y²'s: the nearest float to the data's J_S, a subnormal of a few bits below the normal range
            # (at 2^-531, y near 1.5e-160: some 1e-322, not 0, which would read as an exact fit), 0 only below 2.5e-324
            if got < np.finfo(float).tiny:
                assert got == float(Fraction(want) * Fraction(2) ** (2 * ey))
    assert res.start == ref.start and res.radius == pytest.approx(ref.radius, rel=1e-9)
    assert list(res.starts["status"]) == list(ref.starts["status"])


def test_problems_of_other_lengths_or_shapes_over_the_same_numbers_have_other_fingerprints():
    """The arrays' bytes were hashed one after another, without their shapes: one record of 6 samples and two of 3
    over the same numbers, or a record and static points, shared a fingerprint, and a checkpoint of one problem was
    resumed for the other (mend60g)."""
    st = gb.Structure(["y(k-1)", "u(k-1)"])
    x = np.arange(1.0, 13.0)
    one = SEProblem(st, gb.Record(x[:6], x[6:]), None, scored_only=True)
    two = SEProblem(st, [gb.Record(x[:3], x[3:6]), gb.Record(x[6:9], x[9:])], None, scored_only=True)
    assert one.fingerprint() != two.fingerprint()
    wide = SEProblem(["y(k-1)", "u1(k-1)"], gb.Record(x[:8].reshape(4, 2), x[8:]), None, scored_only=True)
    split = SEProblem(["y(k-1)", "u1(k-1)"], [gb.Record(x[:4].reshape(2, 2), x[4:6]),
                                               gb.Record(x[6:10].reshape(2, 2), x[10:])], None, scored_only=True)
    assert wide.fingerprint() != split.fingerprint()
    points = SEProblem(st, gb.Record(x[:3], x[3:6]), gb.StaticPoints(x[6:9], x[9:]), scored_only=True)
    assert points.fingerprint() != two.fingerprint()  # static points are no second record


def test_a_checkpoint_fingerprinted_without_shapes_starts_over_as_one_of_another_version(oe_data, tmp_path):
    """A checkpoint written before the fingerprint held the arrays' shapes is this problem's (as far as that hash
    could tell): started over with the warning of another version's file, not refused as another problem's."""
    import json

    from graybox.estimation._simulation_error import _save_checkpoint, read_npz
    fit = gb.Record(oe_data[0].u[:60], oe_data[0].y[:60])  # short: the sweep is run twice
    static = gb.StaticPoints(np.array([-0.5, 0.5]), np.array([0.0, 0.5]))
    kw = dict(lambdas=[1.0], method="gradient", checkpoint=tmp_path / "old.npz", margin=None)
    ck = kw["checkpoint"]
    first = se_pareto(OE_STRUCT, fit, static, **kw)
    arrays = read_npz(ck)
    meta = json.loads(str(arrays["meta"]))
    assert meta["problem"] == SEProblem(OE_STRUCT, fit, static).fingerprint()
    meta["problem"] = SEProblem(OE_STRUCT, fit, static).fingerprint(shapes=False)
    _save_checkpoint(ck, meta, arrays["thetas"], arrays["costs"], int(arrays["done"]),
                     json.loads(str(arrays["failures"])), arrays["nfev"])
    with pytest.warns(UserWarning, match="left out its arrays' shapes.*starts over"):
        again = se_pareto(OE_STRUCT, fit, static, **kw)
    np.testing.assert_allclose(again.thetas, first.thetas)
    meta["problem"] = "0123456789abcdef"  # any other problem's is refused, as before
    _save_checkpoint(ck, meta, arrays["thetas"], arrays["costs"], int(arrays["done"]),
                     json.loads(str(arrays["failures"])), arrays["nfev"])
    with pytest.raises(ValueError, match="another problem"):
        se_pareto(OE_STRUCT, fit, static, **kw)


def _random_walk():
    """A record whose least-squares (and ELS) fit of y(k-1), y(k-1)², u(k-1) is unstable (a local spectral radius
    about 1.04 along it) and diverges in free run."""
    rng = np.random.default_rng(3)
    return ["y(k-1)", "y(k-1)^2", "u(k-1)"], gb.Record(rng.standard_normal(120), np.cumsum(rng.standard_normal(120)))


def test_a_start_whose_free_run_diverges_is_pulled_inside_the_margin_by_output_error():
    # a start outside the margin is pulled in by shrinking its output feedback, but only where its free run stayed
    # bounded: least squares and ELS, unstable and diverging, were dropped as 'free run diverges' and margin=0.1
    # (the tool that makes them stable) ended in "no start of the output-error fit gave a model"
    terms, rec = _random_walk()
    p = SEProblem(terms, rec, None, margin=0.1)
    assert not np.isfinite(p.js(p.ls_theta()[None])[0]) and not p.within_margin(p.ls_theta())[0]
    r = output_error(terms, rec, margin=0.1, n_starts=0, solver="trf")
    assert "feedback ×" in r.start and r.radius <= 0.9 + 1e-9 and np.isfinite(r.JS)
    assert np.isfinite(gb.js(r.model, rec))
    assert any(s.startswith("least squares, feedback ×") for s in r.starts["start"])


def test_a_start_whose_free_run_diverges_is_pulled_inside_the_margin_by_the_gradient_sweep():
    # the same in the gradient sweep's restarts (se_pareto, se_dsf's coarse sweep): every member failed with
    # 'free run diverges' though the margin brings least squares inside
    terms, rec = _random_walk()
    ps = se_pareto(terms, rec, gb.StaticPoints([-1.0, 1.0], [-1.0, 1.0]), lambdas=[1.0], method="gradient",
                   margin=0.1, starts=[])
    assert not ps.failures and ps.extra["radius"][0] <= 0.9 + 1e-9 and np.isfinite(ps.JS[0])


def test_when_every_start_diverges_without_a_margin_the_error_offers_one():
    # the message said "a smaller margin" of a fit that had none, where a margin is what brings the starts in
    terms, rec = _random_walk()
    with pytest.raises(ValueError, match=r"free run diverges.*margin=0\.1") as exc:
        output_error(terms, rec, margin=None, n_starts=0, solver="trf")
    assert "smaller margin" not in str(exc.value)


def test_a_start_outside_the_margin_only_at_a_static_point_is_pulled_inside_by_the_gradient_sweep():
    # y(k) = 0.5 y(k-1) + 0.2 u(k-1) y(k-1) + u(k-1): its local radius 0.5 + 0.2 u stays below 1 - 0.2 along a
    # record in u ∈ [0, 1] but not at the static point ū = 2; the sweep pulled a start in only where the records
    # said it was outside, so every start of λ1 < 1 was dropped ("outside the stability margin") and those members
    # failed, while the GA (and se_dsf) pull such starts in
    rng = np.random.default_rng(0)
    terms = ["y(k-1)", "u(k-1)*y(k-1)", "u(k-1)"]
    u = np.repeat(rng.uniform(0.0, 1.0, 40), 8)
    rec = gb.Record(u, gb.Model(terms, [0.5, 0.2, 1.0]).simulate(u, np.zeros(1)) + 0.01 * rng.standard_normal(u.size))
    ub = np.array([0.0, 1.0, 2.0])
    points = gb.StaticPoints(ub, ub / (0.5 - 0.2 * ub))
    with pytest.warns(gb.StaticRangeWarning):
        ps = se_pareto(terms, rec, points, lambdas=[0.5], method="gradient", margin=0.2, starts=[], solver="trf",
                       max_nfev=10)
    assert not ps.failures and np.isfinite(ps.JS[0]) and np.isfinite(ps.JSF[0])
    p = SEProblem(terms, rec, points, margin=0.2)
    assert p.within_margin(ps.thetas, p.static_outputs(ps.thetas)).all()
