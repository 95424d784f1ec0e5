"""One sampling of a static curve or surface into static points, shared by PE, SE, se_dsf and
select_graybox (graybox.models._coerce.static_points)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import graybox as gb
from graybox.models._coerce import CURVE_LEVELS, static_points

#: y(k) = 0.6 y(k-1) + 0.3 s(k-1) + 0.05 s(k-1)² + 0.1, the input named "speed"
ST = gb.Structure(["1", "speed(k-1)", "speed(k-1)^2", "y(k-1)"])
THETA = np.array([0.1, 0.3, 0.05, 0.6])


def true_curve(u):
    return (0.1 + 0.3 * u + 0.05 * u**2) / 0.4


@pytest.fixture(scope="module")
def rec():
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(0.0, 2.0, 40), 10)
    y = gb.Model(ST, THETA, input_names=("speed",)).simulate(u, np.zeros(1)) + 0.01 * rng.standard_normal(400)
    return gb.Record(u, y, 1.0, input_names=("speed",))


@pytest.fixture(scope="module")
def curve():
    ub = np.linspace(0.0, 2.0, 7)
    return gb.StaticCurve.fit(gb.StaticPoints(ub, true_curve(ub), input_names=("speed",)), degree=2)


def test_a_curve_is_sampled_over_its_domain_as_the_records_input(rec, curve):
    pts = static_points(curve, rec)
    assert pts.input_names == ("speed",)
    np.testing.assert_allclose(pts.ubar, np.linspace(*curve.domain, CURVE_LEVELS))
    np.testing.assert_allclose(pts.ybar, true_curve(pts.ubar), rtol=1e-9)
    at = static_points(curve, [rec], ubar=[0.5, 1.5])
    np.testing.assert_allclose(at.ybar, true_curve(np.array([0.5, 1.5])), rtol=1e-9)
    assert at.input_names == ("speed",)


def test_sampling_is_refused_where_it_means_nothing(rec, curve):
    pts = curve.points(np.linspace(0, 2, 5), "speed")
    with pytest.raises(ValueError, match="static points carry their own"):
        static_points(pts, rec, ubar=[1.0])
    bare = gb.StaticCurve.polynomial([0.25, 0.75, 0.125])
    with pytest.raises(ValueError, match="without a domain needs ubar"):
        static_points(bare, rec)
    with pytest.raises(ValueError, match="ubar"):
        static_points(curve, rec, ubar=[1.0, np.nan])
    with pytest.raises(ValueError, match="se_dsf needs static points"):
        static_points(None, rec, needed_by="se_dsf")
    assert static_points(None, rec) is None


def test_se_takes_a_curve_as_pe_does(rec, curve):
    # the same curve, given as a curve or as the points it stands for: the same front, PE and SE alike
    pts = static_points(curve, rec)
    lam = [0.3, 1.0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        se_c = gb.se_pareto(ST, rec, curve, lambdas=lam, method="gradient", progress=False)
        se_p = gb.se_pareto(ST, rec, pts, lambdas=lam, method="gradient", progress=False)
        pe_c = gb.pe_pareto(ST, rec, curve, lambdas=lam)
        pe_p = gb.pe_pareto(ST, rec, pts, lambdas=lam)
    np.testing.assert_array_equal(se_c.thetas, se_p.thetas)
    np.testing.assert_array_equal(pe_c.thetas, pe_p.thetas)
    # the data fit the true curve, so the static member is near the true model
    assert se_c.JSF[0] < 1e-3
    at = gb.se_pareto(ST, rec, curve, lambdas=[0.3], method="gradient", progress=False, ubar=[0.2, 1.0, 1.8])
    assert at.JSF[0] < 1e-3


def test_se_dsf_takes_a_curve_with_a_band(rec, curve):
    with pytest.raises(ValueError, match="band"):  # sampled points carry no uncertainty
        gb.se_dsf(ST, rec, curve)
    res = gb.se_dsf(ST, rec, curve, band=1e-3)
    assert res.in_band and res.JSF <= 1e-3
    np.testing.assert_allclose(res.model.theta, THETA, rtol=0.05, atol=0.01)


def test_select_graybox_samples_a_curve_the_same_way(rec, curve):
    rng = np.random.default_rng(1)
    u = np.repeat(rng.uniform(0.0, 2.0, 30), 10)
    y = gb.Model(ST, THETA, input_names=("speed",)).simulate(u, np.zeros(1)) + 0.01 * rng.standard_normal(300)
    valid = gb.Record(u, y, 1.0, input_names=("speed",))
    cand = gb.Candidates(1, 1, degree=2, input_names=("speed",))
    sel = gb.select_graybox(cand, rec, curve, validation=valid, band=1e-3, progress=False)
    # J_SF in the table is against the curve's points sampled as everywhere else
    pts = static_points(curve, rec)
    assert gb.jsf(sel.model, pts) == pytest.approx(sel.table.iloc[0]["JSF"], rel=1e-6)


def test_the_errors_name_what_to_give(rec, curve):
    bare = gb.StaticCurve.polynomial([0.25, 0.75, 0.125])
    cand = gb.Candidates(1, 1, degree=2, input_names=("speed",))
    # select_graybox has no ubar: it asks for points
    with pytest.raises(ValueError, match=r"without a domain needs static points \(e.g. its .points\(ubar\)\)"):
        gb.select_graybox(cand, rec, bare, validation=rec.slice(0, 100), band=1e-3, progress=False)
    with pytest.raises(ValueError, match="carries no uncertainty .* give band=B"):
        gb.se_dsf(ST, rec, curve)
    surface = gb.StaticSurface.fit(gb.StaticPoints(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]),
                                                   np.array([0.0, 1.0, 2.0, 3.0]), input_names=("a", "b")), 1)
    for bad, said in (("abc", "ubar must be an array of numbers"), ([1.0, 2.0], r"ubar must have shape \(K, 2\)"),
                      ([[0.5, np.nan]], "ubar has NaN or inf at rows")):
        with pytest.raises(ValueError, match=said):
            static_points(surface, None, ubar=bad)
    np.testing.assert_allclose(static_points(surface, None, ubar=[[0.5, 0.5]]).ybar, [1.5])


def test_pe_takes_a_surface_of_one_input(rec):
    # a one-input StaticSurface (a polynomial in one input) is a curve by another name: PE takes it as it takes one
    ub = np.linspace(0.0, 2.0, 7)
    pts = gb.StaticPoints(ub, true_curve(ub), input_names=("speed",))
    surface = gb.StaticSurface.fit(pts, 2)
    curve = gb.StaticCurve.fit(pts, degree=2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        a = gb.pe_pareto(ST, rec, surface, lambdas=[0.5])
        b = gb.pe_pareto(ST, rec, curve, lambdas=[0.5], ubar=static_points(surface, rec).ubar)
    np.testing.assert_allclose(a.thetas, b.thetas, rtol=1e-9)


def test_a_curve_beside_transient_inputs_says_the_way_through():
    data = gb.load_pumping()
    curve = gb.StaticCurve.fit(data.static, degree=2)
    td = gb.transient_inputs(data, taus=[30])
    cand = gb.Candidates(2, {"u": 2, "u_tau30": 1}, degree=2, input_names=td.input_names)
    with pytest.raises(ValueError, match=r"sample it into static points .* gb.transient_inputs\(points"):
        gb.select_graybox(cand, td, curve, band=0.031, progress=False)
    with pytest.raises(TypeError, match=r"sample it into static points first"):
        gb.transient_inputs(curve, taus=[30])
    # the way through: the curve's points, given the transient channels (z̄ = 0 at rest)
    pts = gb.transient_inputs(static_points(curve, data), taus=[30])
    assert pts.input_names == ("u", "u_tau30") and np.all(np.asarray(pts.ubar)[:, 1] == 0.0)


def test_the_diagnostics_take_a_curve_as_the_estimators_do(rec, curve):
    # se_uncertainty and bootstrap_decision score the same points a curve stands for everywhere else
    pts = static_points(curve, rec)
    front = gb.se_pareto(ST, rec, pts, lambdas=[0.3], method="gradient", progress=False)
    member = front.member_model(0)
    a = gb.se_uncertainty(member, rec, curve, lambda1=0.3)
    b = gb.se_uncertainty(member, rec, pts, lambda1=0.3)
    np.testing.assert_array_equal(a.std, b.std)
    kw = dict(estimator="pe", lambdas=[1.0, 0.3], n_boot=2, seed=0, band=1e-3)
    c = gb.bootstrap_decision(ST, rec, curve, **kw)
    d = gb.bootstrap_decision(ST, rec, pts, **kw)
    np.testing.assert_array_equal(c.thetas, d.thetas)
