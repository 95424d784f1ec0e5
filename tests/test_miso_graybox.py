"""Gray-box estimation with static surfaces: several inputs in CLS, PE and SE (issue 15)."""

from __future__ import annotations

import dataclasses

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import graybox as gb
from graybox.estimation._prediction_error import qr_static_error
from graybox.models._coerce import SURFACE_LEVELS
from graybox.static._constraints import (
    StaticContext, cluster_powers, n_static_inputs, static_rows,
)
from graybox.static._surfaces import StaticSurface

# A rational two-input structure (no y power above 1) for the bundled two-input rig: its
# numerator carries 1, u1, u2, u1², u1·u2, u2²; its denominator 1 − Σy − Σyu1 ū1 − Σyu2 ū2.
TERMS = ["1", "y(k-1)", "y(k-2)", "u1(k-2)", "u2(k-2)", "u1(k-3)^2", "u1(k-2)u2(k-3)", "u2(k-3)^2",
         "u1(k-2)y(k-1)", "u2(k-2)y(k-2)"]
ST = gb.parse_structure(TERMS)


@pytest.fixture(scope="module")
def ds():
    return gb.load_pumping_miso()


def rational_surface(structure, theta, U):
    """ȳ = N(ū)/D(ū) from the cluster coefficients (eq. (6) in several inputs), shape (K,)."""
    cm = gb.surface_cluster_map(structure)
    sig = cm.R @ np.asarray(theta, float)
    U = np.atleast_2d(np.asarray(U, float))
    num = np.zeros(U.shape[0])
    den = np.ones(U.shape[0])
    for s, key in zip(sig, cm.keys):
        p, e = cluster_powers(key)
        mono = np.prod(U ** np.array(e, float)[None, :], axis=1)
        if p == 0:
            num += s * mono
        else:
            assert p == 1
            den -= s * mono
    return num / den


def rational_gradient(structure, theta, U, h=1e-4):
    U = np.atleast_2d(np.asarray(U, float))
    out = np.empty(U.shape)
    for j in range(U.shape[1]):
        d = np.zeros(U.shape[1])
        d[j] = h * np.abs(U[:, j]).max()
        out[:, j] = (rational_surface(structure, theta, U + d) - rational_surface(structure, theta, U - d)) / (2 * d[j])
    return out


def grid(n=7, lo=1150.0, hi=1650.0):
    g = np.linspace(lo, hi, n)
    return np.array([(a, b) for a in g for b in g])


# -- static rows -------------------------------------------------------------------

def test_clusters_speak_of_both_inputs():
    cm = gb.surface_cluster_map(ST)
    assert n_static_inputs(cm) == 2
    powers = {cluster_powers(k) for k in cm.keys}
    assert powers == {(0, (0, 0)), (1, (0, 0)), (0, (1, 0)), (0, (0, 1)), (0, (2, 0)), (0, (1, 1)), (0, (0, 2)),
                      (1, (1, 0)), (1, (0, 1))}


def test_static_rows_are_the_monomials_and_their_derivatives():
    cm = gb.surface_cluster_map(ST)
    rng = np.random.default_rng(0)
    U = rng.uniform(1000, 1700, (5, 2))
    yb = rng.uniform(8, 20, 5)
    Q = static_rows(cm, U, yb)
    for c, key in enumerate(cm.keys):
        p, e = cluster_powers(key)
        np.testing.assert_allclose(Q[:, c], yb**p * U[:, 0] ** e[0] * U[:, 1] ** e[1], rtol=1e-14)
    theta = rng.standard_normal(len(ST))
    for j in (0, 1):
        h = np.zeros(2)
        h[j] = 1e-3
        fd = (static_rows(cm, U + h, yb) - static_rows(cm, U - h, yb)) / 2e-3
        np.testing.assert_allclose(static_rows(cm, U, yb, wrt="u", input=j) @ cm.R @ theta, fd @ cm.R @ theta,
                                   rtol=1e-6)
    fd = (static_rows(cm, U, yb + 1e-4) - static_rows(cm, U, yb - 1e-4)) / 2e-4
    np.testing.assert_allclose(static_rows(cm, U, yb, wrt="y"), fd, rtol=1e-6, atol=1e-9)
    with pytest.raises(ValueError, match="needs input = 0 … 1"):
        static_rows(cm, U, yb, wrt="u")
    with pytest.raises(ValueError, match="the structure has 2 inputs but ū has shape"):
        static_rows(cm, U[:, 0], yb)


# -- CLS ----------------------------------------------------------------------------

def test_cls_imposes_a_fitted_surface_to_1e_8(ds):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        model = gb.cls(ST, ds, ds.static, how="curve").model
    cm = gb.surface_cluster_map(ST)
    exps = {cluster_powers(k)[1] for k in cm.keys if cluster_powers(k)[0] == 0}
    surf = StaticSurface.fit(ds.static, exponents=sorted(exps))
    U = grid(11)
    H = surf(U)
    ym = rational_surface(ST, model.theta, U)
    assert np.max(np.abs(ym - H) / np.abs(H)) < 1e-8
    # the model's own static analysis (the equilibrium a free run reaches) agrees
    ys = model.static_curve(U)
    np.testing.assert_allclose(ys, H, rtol=1e-8)
    # and the rows are met as equalities: Σ_{y u^e} = 0 for e ≠ 0
    sig = dict(zip(cm.keys, cm.R @ model.theta))
    for key, v in sig.items():
        p, e = cluster_powers(key)
        if p == 1 and any(e):
            assert abs(v) < 1e-12


def test_cls_surface_equality_in_rad_per_s_gives_the_same_model(ds):
    k = np.pi / 30
    scaled = gb.Dataset(
        gb.Record(ds.ident.u * k, ds.ident.y, Ts=ds.Ts, input_names=ds.input_names),
        gb.Record(ds.valid.u * k, ds.valid.y, Ts=ds.Ts, input_names=ds.input_names),
        gb.StaticPoints(ds.static.ubar * k, ds.static.ybar, input_names=ds.input_names),
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        a = gb.cls(ST, ds, ds.static, how="curve").model
        b = gb.cls(ST, scaled, scaled.static, how="curve").model
    U = grid(5)
    np.testing.assert_allclose(rational_surface(ST, b.theta, U * k), rational_surface(ST, a.theta, U), rtol=1e-7)


def test_cls_through_a_few_static_points_meets_them_to_1e_8(ds):
    pts = gb.StaticPoints(ds.static.ubar[[0, 14, 21, 35]], ds.static.ybar[[0, 14, 21, 35]],
                          input_names=ds.input_names)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        for solver in ("clarabel", "closed"):
            model = gb.cls(ST, ds, pts, solver=solver).model
            ym = rational_surface(ST, model.theta, pts.ubar)
            np.testing.assert_allclose(ym, pts.ybar, rtol=1e-8)


def test_cls_with_a_given_surface_and_per_input_gain_bounds(ds):
    surf = StaticSurface.fit(ds.static, 2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        model = gb.cls(ST, ds, surf, constraints=gb.GainBounds(lower=[0.0, 0.0], n=6)).model
    U = grid(9)
    np.testing.assert_allclose(rational_surface(ST, model.theta, U), surf(U), rtol=1e-8)
    assert np.all(rational_gradient(ST, model.theta, U) > -1e-8)


# -- PE -----------------------------------------------------------------------------

def test_pe_closed_form_and_cvxpy_agree_with_two_inputs(ds):
    lam = np.array([1e-3, 0.1, 0.9])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        closed = gb.pe_thetas(ST, ds, lambdas=lam, solver="closed")
        qp = gb.pe_thetas(ST, ds, lambdas=lam, solver="clarabel")
    U = ds.static.ubar
    for a, b in zip(closed, qp):
        np.testing.assert_allclose(rational_surface(ST, b, U), rational_surface(ST, a, U), rtol=1e-6)
    jsf_qr = qr_static_error(ST, closed, ds.static)
    assert jsf_qr[0] < jsf_qr[-1]  # the static points weigh more at small λ1


def test_pe_band_and_gain_bounds_hold_per_input(ds):
    band = gb.StaticBand(0.2)
    gain = gb.GainBounds(lower=[0.0, 0.0])  # at the static points (no reference surface)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        thetas = gb.pe_thetas(ST, ds, lambdas=[0.5, 1.0], constraints=band & gain)
    for th in thetas:
        err = rational_surface(ST, th, ds.static.ubar) - ds.static.ybar
        assert np.abs(err).max() <= 0.2 + 1e-6
        assert np.all(rational_gradient(ST, th, ds.static.ubar) > -1e-6)


def test_pe_samples_a_surface(ds):
    surf = StaticSurface.fit(ds.static, 2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        th = gb.pe_thetas(ST, ds, surf, lambdas=[1e-4], solver="closed")[0]
    U = grid(SURFACE_LEVELS)  # the default sample: a grid over the surface's domain
    assert np.sqrt(np.mean((rational_surface(ST, th, U) - surf(U)) ** 2)) < 0.05


# -- SE -----------------------------------------------------------------------------

def test_se_gradient_on_two_inputs(ds):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        par = gb.se_pareto(ST, ds, lambdas=[0.3, 1.0], method="gradient", progress=False, max_nfev=5)
    assert len(par) == 2 and np.all(np.isfinite(par.JSF))
    # J_SF is the static error at the 36 points of the equilibrium each member reaches
    th = par.thetas[0]
    ym = rational_surface(ST, th, ds.static.ubar)
    assert par.JSF[0] == pytest.approx(np.mean((ym - ds.static.ybar) ** 2), rel=1e-6)


# -- bad input ------------------------------------------------------------------------

def test_input_count_mismatches_are_named(ds):
    three = gb.StaticPoints(np.c_[ds.static.ubar, ds.static.ubar[:, :1]], ds.static.ybar)
    with pytest.raises(ValueError, match=r"has inputs \('u1', 'u2'\) but .* has inputs \('u1', 'u2', 'u3'\)"):
        gb.cls(ST, ds, three).model
    with pytest.raises(ValueError, match="has inputs"):
        gb.pe_thetas(ST, ds, three, lambdas=[0.5])
    with pytest.raises(ValueError, match="has inputs"):
        gb.cls(ST, ds, constraints=gb.StaticBand(0.2, points=three)).model
    with pytest.raises(ValueError, match="curve in one input but the structure has 2 inputs"):
        gb.cls(ST, ds, gb.StaticCurve.polynomial([1.0, 2.0])).model
    surf3 = StaticSurface.polynomial({(0, 0, 0): 1.0, (1, 0, 0): 1.0})
    with pytest.raises(ValueError, match="surface in 3 input"):
        gb.cls(ST, ds, surf3).model
    surf_y = StaticSurface.polynomial({(0, 0): 1.0, (3, 0): 1.0})
    with pytest.raises(ValueError, match="no cluster of the structure carries"):
        gb.cls(ST, ds, surf_y).model
    with pytest.raises(ValueError, match="lower has 3 entries but the structure has 2 input"):
        gb.pe_thetas(ST, ds, lambdas=[0.5], constraints=gb.GainBounds(lower=[0, 0, 0]))
    ctx = StaticContext(ST, ds.static)
    with pytest.raises(ValueError, match="one \\(low, high\\) per input"):
        gb.GainBounds(lower=0.0, ubar_range=(1200, 1500), reference=StaticSurface.fit(ds.static, 2)).affine(ctx)


def test_se_ga_on_two_inputs(ds):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        par = gb.se_pareto(ST, ds, lambdas=[0.5], method="ga", seed=0, progress=False,
                           options=gb.GAOptions(population=20, generations=2))
    assert len(par) == 1 and np.isfinite(par.JSF[0]) and np.isfinite(par.JS[0])
    ym = rational_surface(ST, par.thetas[0], ds.static.ubar)
    assert par.JSF[0] == pytest.approx(np.mean((ym - ds.static.ybar) ** 2), rel=1e-6)


# -- the experiment layer -------------------------------------------------------------

def test_grid_spec_with_per_input_lags_and_gain_bounds(tmp_path):
    from graybox import experiments as gx

    grid = gx.Grid(
        name="miso",
        data=[gx.DataSpec("rig", bundled="pumping_miso")],
        structures=[gx.StructureSpec("F6", candidates={"ny": 2, "nu": {"u1": 2, "u2": 3}, "delay": {"u1": 2, "u2": 2},
                                                       "degree": 2, "max_y_power": 1}, n_terms=6, include=["1"])],
        variants=[
            gx.Variant("CLS", "cls", constraints=[{"type": "equality", "curve": "fit", "sigma_y": 0.99}]),
            gx.Variant("PE gain", "pe", lambdas=[1e-4, 1.0], decision={"rule": "dsf", "fallback": "min_jsf"},
                       constraints=gb.GainBounds(lower=[0.0, None], ubar_range=((1150, 1650), (1150, 1650)), n=4)),
        ],
    )
    spec = grid.to_dict()
    assert spec["structures"][0]["candidates"]["nu"] == {"u1": 2, "u2": 3}
    gain = spec["variants"][1]["constraints"][0]
    assert gain["lower"] == [0.0, None] and gain["ubar_range"] == [[1150.0, 1650.0], [1150.0, 1650.0]]
    assert gx.Grid.from_dict(spec).to_dict() == spec
    gx.run_grid(grid, tmp_path / "r.sqlite")
    res = gb.load_results(tmp_path / "r.sqlite")
    assert list(res.status) == ["ok", "ok"], res.message.tolist()
    assert res.JSF.iloc[0] < 0.2  # eq. (22) on the fitted surface: the static points are met closely


def test_readme_miso_example_runs():
    import re
    from pathlib import Path

    readme = (Path(__file__).parents[1] / "README.md").read_text(encoding="utf-8")
    section = readme.split("## Several inputs: static surfaces and the two-speed rig", 1)[1]
    block = re.findall(r"```python\n(.*?)```", section, re.S)[0]
    ns: dict = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exec(compile(block, "README.md (several inputs)", "exec"), ns)
    U = ns["data"].static.ubar
    np.testing.assert_allclose(ns["cls"].static_curve(U), ns["surface"](U), rtol=1e-8)


def test_cluster_bounds_by_name_on_two_inputs(ds):
    cm = gb.surface_cluster_map(ST)
    assert "Σu1²" in cm.names and "Σyu2" in cm.names
    cons = gb.ClusterBounds({"Sy": (None, 0.95), "Su1^2": (0.0, None), "Σyu2": (0.0, 0.0)})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        model = gb.cls(ST, ds, constraints=cons, how="context").model
    sig = dict(zip(cm.names, cm.R @ model.theta))
    assert sig["Σy"] <= 0.95 + 1e-9 and sig["Σu1²"] >= -1e-12 and abs(sig["Σyu2"]) < 1e-12
    with pytest.raises(ValueError, match="no cluster 'Σu3'"):
        gb.cls(ST, ds, constraints=gb.ClusterBounds({"Su3": (0.0, None)}), how="context")


@settings(max_examples=10, deadline=None)
@given(st.floats(1150, 1650), st.floats(1150, 1650))
def test_a_models_static_surface_is_its_long_free_run_steady_state(u1, u2):
    # the PE member nearest the static points on the bundled rig: a stable, realistic two-input model
    model = _pe_model()
    U = np.array([[u1, u2]])
    yb = float(model.static_curve(U)[0])
    rec = gb.Record(np.tile(U, (4000, 1)), np.full(4000, yb + 1.0), Ts=0.05, input_names=("u1", "u2"))
    y = model.simulate(rec)
    assert y[-1] == pytest.approx(yb, rel=1e-9, abs=1e-9)


_PE = {}


def _pe_model():
    if "m" not in _PE:
        ds = gb.load_pumping_miso()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", gb.StaticRangeWarning)
            par = gb.pe_pareto(ST, ds.ident, ds.static, lambdas=[0.01], solver="closed")
        _PE["m"] = par.member_model(0)
    return _PE["m"]


def test_se_dsf_on_two_inputs_lands_on_the_band(ds):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        res = gb.se_dsf(ST, ds, band=0.031)
    assert res.in_band and res.JSF <= 0.031 * (1 + 1e-6)
    ym = res.model.static_curve(ds.static.ubar)
    assert np.mean((ym - ds.static.ybar) ** 2) == pytest.approx(res.JSF, rel=1e-6)


def test_pe_on_two_inputs_does_not_depend_on_units(ds):
    # ū in rad/s and ȳ in kPa: the same models (static surfaces scaled by the output's unit)
    ku, ky = np.pi / 30, 9.80665
    scaled = gb.Dataset(
        gb.Record(ds.ident.u * ku, ds.ident.y * ky, Ts=ds.Ts, input_names=ds.input_names),
        gb.Record(ds.valid.u * ku, ds.valid.y * ky, Ts=ds.Ts, input_names=ds.input_names),
        gb.StaticPoints(ds.static.ubar * ku, ds.static.ybar * ky, input_names=ds.input_names),
    )
    lam = [1e-3, 0.5]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        for solver in ("closed", "clarabel"):
            a = gb.pe_thetas(ST, ds, lambdas=lam, solver=solver, constraints=None if solver == "closed" else
                             gb.StaticBand(0.3) & gb.GainBounds(lower=[0.0, 0.0]))
            b = gb.pe_thetas(ST, scaled, lambdas=lam, solver=solver, constraints=None if solver == "closed" else
                             gb.StaticBand(0.3 * ky) & gb.GainBounds(lower=[0.0, 0.0]))
            U = grid(4)
            for ta, tb in zip(a, b):
                np.testing.assert_allclose(rational_surface(ST, tb, U * ku), ky * rational_surface(ST, ta, U),
                                           rtol=1e-6)


def test_gain_bounds_by_input_name_hold_the_input_named_whatever_the_order(ds):
    # positional bounds move to another input when the data list their inputs in another order; bounds by name
    # stay with their input (hunt44c's note)
    by_position = gb.pe_thetas(ST, ds, lambdas=[0.5], constraints=gb.GainBounds(lower=[None, 0.0]))
    by_name = gb.pe_thetas(ST, ds, lambdas=[0.5], constraints=gb.GainBounds(lower={"u2": 0.0}))
    np.testing.assert_allclose(by_name, by_position, rtol=1e-9, atol=1e-12)
    assert np.all(rational_gradient(ST, by_name[0], ds.static.ubar)[:, 1] > -1e-6)
    both = gb.pe_thetas(ST, ds, lambdas=[0.5], constraints=gb.GainBounds(lower={"u1": 0.0, "u2": 0.0}))
    np.testing.assert_allclose(both, gb.pe_thetas(ST, ds, lambdas=[0.5], constraints=gb.GainBounds(lower=0.0)),
                               rtol=1e-9, atol=1e-12)
    assert "lower {u2: 0}, upper none by input" in gb.GainBounds(lower={"u2": 0.0}).describe()

    def swapped(r):
        return dataclasses.replace(r, u=r.u[:, ::-1], input_names=r.input_names[::-1])

    other = gb.Dataset(swapped(ds.ident), swapped(ds.valid),
                       gb.StaticPoints(ds.static.ubar[:, ::-1], ds.static.ybar, input_names=("u2", "u1")))
    np.testing.assert_allclose(gb.pe_thetas(ST, other, lambdas=[0.5], constraints=gb.GainBounds(lower={"u2": 0.0})),
                               by_name, rtol=1e-7, atol=1e-10)
    with pytest.raises(ValueError, match="no input named 'valve'"):
        gb.pe_thetas(ST, ds, lambdas=[0.5], constraints=gb.GainBounds(lower={"valve": 0.0}))
    with pytest.raises(ValueError, match="exceeds upper bound 1.0 of input 'u2'"):
        gb.GainBounds(lower={"u2": 2.0}, upper=1.0)
    with pytest.raises(TypeError, match="take input names"):
        gb.GainBounds(lower={1: 0.0})
    with pytest.raises(ValueError, match="needs a lower or an upper bound"):
        gb.GainBounds(lower={"u1": None})


def test_gain_bounds_by_input_name_in_a_grid_spec_and_a_selection(ds):
    from graybox import experiments as gx

    v = gx.Variant("PE gain", "pe", lambdas=[1e-4, 1.0], constraints=gb.GainBounds(lower={"u2": 0.0}))
    grid = gx.Grid(name="m", data=[gx.DataSpec("rig", bundled="pumping_miso")],
                   structures=[gx.StructureSpec("S", terms=TERMS)], variants=[v])
    spec = grid.to_dict()
    assert spec["variants"][0]["constraints"][0]["lower"] == {"u2": 0.0}
    assert gx.Grid.from_dict(spec).to_dict() == spec
    with pytest.raises(gx.SpecError, match="lower by input name needs at least one input's bound"):
        gx.Variant("x", "pe", constraints=[{"type": "gain", "lower": {}}])
    # a name the data do not have is said before any row is fitted
    with pytest.raises(ValueError, match="constraints: .*no input named 'valve'"):
        gb.select_graybox(gb.Candidates(ny=1, nu=1, degree=1, input_names=["u1", "u2"]), ds, band=1.0,
                          constraints=gb.GainBounds(lower={"valve": 0.0}), progress=False)


def test_gain_ranges_by_input_name_hold_the_input_named_whatever_the_order(ds):
    # ubar_range was positional only: data listing their inputs in another order moved a range to another input
    box = ((1150.0, 1650.0), (1150.0, 1400.0))
    named = gb.GainBounds(upper={"u2": 0.0}, ubar_range={"u2": (1150.0, 1400.0)})
    by_position = gb.pe_thetas(ST, ds, lambdas=[0.5], constraints=gb.GainBounds(upper=[None, 0.0], ubar_range=box))
    by_name = gb.pe_thetas(ST, ds, lambdas=[0.5], constraints=named)
    np.testing.assert_allclose(by_name, by_position, rtol=1e-9, atol=1e-12)
    whole = gb.pe_thetas(ST, ds, lambdas=[0.5], constraints=gb.GainBounds(upper={"u2": 0.0}))
    assert np.max(np.abs(whole - by_name)) > 1e-6  # the range matters here (points outside it are not held)
    assert "over u2 in [1150, 1400]" in named.describe()

    def swapped(r):
        return dataclasses.replace(r, u=r.u[:, ::-1], input_names=r.input_names[::-1])

    other = gb.Dataset(swapped(ds.ident), swapped(ds.valid),
                       gb.StaticPoints(ds.static.ubar[:, ::-1], ds.static.ybar, input_names=("u2", "u1")))
    np.testing.assert_allclose(gb.pe_thetas(ST, other, lambdas=[0.5], constraints=named), by_name,
                               rtol=1e-7, atol=1e-10)
    # on a reference surface's grid: an input not named keeps the surface's domain
    surf = StaticSurface.fit(ds.static, degree=2)
    ref = dict(upper={"u2": 0.0}, reference=surf, n=5)
    np.testing.assert_allclose(
        gb.pe_thetas(ST, ds, lambdas=[0.5], constraints=gb.GainBounds(ubar_range={"u2": (1150.0, 1400.0)}, **ref)),
        gb.pe_thetas(ST, ds, lambdas=[0.5], constraints=gb.GainBounds(ubar_range=(surf.domain[0], (1150.0, 1400.0)),
                                                                      **ref)), rtol=1e-9, atol=1e-12)
    with pytest.raises(ValueError, match="no input named 'valve'"):
        gb.pe_thetas(ST, ds, lambdas=[0.5], constraints=gb.GainBounds(lower=0.0, ubar_range={"valve": (0, 1)}))
    with pytest.raises(ValueError, match="of input 'u2' must be \\(low, high\\) with low <= high"):
        gb.GainBounds(lower=0.0, ubar_range={"u2": (2.0, 1.0)})
    with pytest.raises(TypeError, match="takes input names"):
        gb.GainBounds(lower=0.0, ubar_range={2: (0.0, 1.0)})
    with pytest.raises(ValueError, match="give at least one input"):
        gb.GainBounds(lower=0.0, ubar_range={})


def test_gain_ranges_by_input_name_in_a_grid_spec(ds):
    from graybox import experiments as gx

    v = gx.Variant("PE gain", "pe", lambdas=[1e-4, 1.0],
                   constraints=gb.GainBounds(lower={"u2": 0.0}, ubar_range={"u2": (1150.0, 1400.0)}))
    grid = gx.Grid(name="m", data=[gx.DataSpec("rig", bundled="pumping_miso")],
                   structures=[gx.StructureSpec("S", terms=TERMS)], variants=[v])
    spec = grid.to_dict()
    assert spec["variants"][0]["constraints"][0]["ubar_range"] == {"u2": [1150.0, 1400.0]}
    assert gx.Grid.from_dict(spec).to_dict() == spec
    with pytest.raises(gx.SpecError, match="ubar_range of input 'u2' must be \\[low, high\\]"):
        gx.Variant("x", "pe", constraints=[{"type": "gain", "lower": 0.0, "ubar_range": {"u2": [1.0]}}])
