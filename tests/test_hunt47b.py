"""Bug hunt 47b: constrained estimation (CLS and PE QPs, the closed form, static constraints, Pareto sets and decisions)."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

import graybox as gb

_S = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "y(k-1)u(k-1)", "1"])
_THETA = np.array([0.7, 0.2, 0.01, 0.0, 0.1])
_PLANT = gb.Model(_S, _THETA)


def _record(n: int = 400, seed: int = 0, units: tuple[str, str] = ("", "")) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.0, 3.0, n // 20 + 1), 20)[:n]
    y = _PLANT.simulate(u, np.zeros(1)) + 0.01 * rng.standard_normal(n)
    return gb.Record(u, y, name="ident", units=units)


def _points(units: tuple[str, str] = ("", "")) -> gb.StaticPoints:
    ub = np.linspace(0.2, 2.8, 6)
    return gb.StaticPoints(ub, _PLANT.static_curve(ub) + 0.05, units=units)


# -- static points given to a constraint or as eval_static: in the records' units ----------------------------
_RPM = ("rpm", "mlc")
_OTHER = ("rad/s", "Pa")


@pytest.mark.parametrize("call", [
    lambda r, p: gb.cls(_S, r, None, constraints=gb.StaticBand(b=0.1, points=p)),
    lambda r, p: gb.cls(_S, r, None, constraints=gb.PassesThrough(p)),
    lambda r, p: gb.cls(_S, r, _points(_RPM), how="context", constraints=gb.StaticBand(b=0.1, points=p)),
    lambda r, p: gb.pe_pareto(_S, r, _points(_RPM), lambdas=[0.5], constraints=gb.StaticBand(b=0.1, points=p)),
    lambda r, p: gb.pe_thetas(_S, r, _points(_RPM), lambdas=[0.5], constraints=gb.PassesThrough(p)),
    lambda r, p: gb.pe_pareto(_S, r, _points(_RPM), lambdas=[0.5], eval_static=p),
], ids=["cls band", "cls passes", "cls context band", "pe band", "pe_thetas passes", "pe eval_static"])
def test_static_points_of_a_constraint_or_eval_static_in_other_units_than_the_records_are_refused(call):
    # was: only static= was held to the records' units; a constraint's own points (or eval_static) in Pa beside
    # records in mlc were imposed (or scored) as if they were in mlc, silently
    with pytest.raises(ValueError, match="same units"):
        call(_record(units=_RPM), _points(_OTHER))
    call(_record(units=_RPM), _points(("", "")))  # points that name no unit say nothing against the records


# -- nondominated_mask without objectives -------------------------------------------------------------------
@pytest.mark.parametrize("points", [np.zeros((3, 0)), np.zeros((0, 0)), [[]]])
def test_nondominated_mask_of_points_without_objectives_is_a_value_error_naming_them(points):
    # was: numpy's lexsort TypeError "need sequence of keys with len > 0", naming neither points nor objectives
    with pytest.raises(ValueError, match="at least one objective"):
        gb.nondominated_mask(points)
    assert gb.nondominated_mask(np.zeros((0, 2))).shape == (0,)  # no members, two objectives: nothing to keep


# -- a decision on a set with nothing to choose says why -----------------------------------------------------
def _front(failed: bool, static: bool = True) -> gb.ParetoSet:
    rec, pts = _record(), _points()
    K = 3
    thetas = np.tile(_THETA, (K, 1))
    fails = {k: f"λ1 = {k}: no start was feasible" for k in range(K)} if failed else {}
    return gb.ParetoSet.from_thetas(_S, thetas, [0.1, 0.5, 1.0], rec, pts if static else None, "test", failures=fails)


@pytest.mark.parametrize("decide", [
    lambda f: gb.decide_dsf(f, band=1.0),
    lambda f: gb.decide_dsf(f, band=1.0, fallback="min_jsf"),
    lambda f: gb.decide_dsf(f, band=1.0, choose_on=_record(seed=3)),
    lambda f: gb.decide_min_correlation(f, _record()),
], ids=["dsf", "dsf fallback", "dsf choose_on", "min correlation"])
def test_a_set_whose_members_all_failed_is_said_so_with_a_reason_by_every_decision_rule(decide):
    # was: "the smallest J_SF is inf for every member. Widen the band …", "every member has an undefined static
    # curve (J_SF = inf)", "every member's free run diverged on this record": each a wrong reason
    with pytest.raises(ValueError, match="every member .* failed.*no start was feasible") as info:
        decide(_front(failed=True))
    assert "Widen" not in str(info.value) and "diverged" not in str(info.value)


@pytest.mark.parametrize("fallback", [None, "min_jsf"])
def test_decide_dsf_on_a_set_evaluated_without_static_points_says_that_j_sf_was_not_computed(fallback):
    # was: "the smallest J_SF is inf for every member. Widen the band" (or "undefined static curve (J_SF = inf)"),
    # for a J_SF that is NaN: never computed, which no band and no fallback change
    front = _front(failed=False, static=False)
    assert np.all(np.isnan(front.JSF))
    with pytest.raises(ValueError, match="has a J_SF .*without static points"):
        gb.decide_dsf(front, band=1.0, fallback=fallback)
    assert gb.decide_min_correlation(front, _record()).rule == "min correlation"  # ρ needs no J_SF
    assert gb.decide_dsf(_front(failed=False), band=1.0).rule == "D_SF"


# -- PassesThrough: a model returned passes through its points -----------------------------------------------
def _six_points(dy: float = 0.0, wiggle: float = 1e-4) -> gb.StaticPoints:
    ub = np.linspace(0.2, 2.8, 6)  # as many points as clusters and more: only the degenerate Σy = 1 meets them all
    return gb.StaticPoints(ub, _PLANT.static_curve(ub) + 0.05 + wiggle * np.array([1, -1, 1, -1, 1, -1]) + dy)


def _shifted(rec: gb.Record, dy: float) -> gb.Record:
    return replace(rec, y=rec.y + dy)


def test_passing_through_more_points_than_clusters_is_refused_whatever_the_output_s_zero():
    # was: refused at y (the degenerate Σy = 1), but at y + 1e4 the model with Σy = 1 − 2.5e-9 was returned as passing
    # through the points, its static function 3e-3 off them (the rows D·(ȳ − ȳ_model) met to round-off)
    for dy in (0.0, 1e4):
        with pytest.raises(ValueError, match="static function"):
            gb.cls(_S, _shifted(_record(), dy), _six_points(dy), how="points")


@pytest.mark.parametrize("dy", [0.0, 1e3, 1e4, 2e5])
def test_a_cls_model_through_points_meets_each_to_a_millionth_of_their_spread(dy):
    ub = np.array([0.4, 1.5, 2.6])  # fewer points than clusters: a model passes through them
    pts = gb.StaticPoints(ub, _PLANT.static_curve(ub) + 0.05 + dy)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model = gb.cls(_S, _shifted(_record(), dy), pts, how="points").model
    miss = np.abs(model.static_curve(ub) - pts.ybar)
    assert miss.max() <= 1e-6 * np.ptp(pts.ybar)


# -- PassesThrough with a y power above 1: no integrator returned as passing through every point --------------
_SQ = gb.Structure(["y(k-1)", "y(k-1)^2", "u(k-1)", "1"])
_QUAD = gb.Model(_SQ, [0.5, 0.05, 0.3, 0.1])


def _quad_record() -> gb.Record:
    rng = np.random.default_rng(2)
    u = np.repeat(rng.uniform(0.0, 2.0, 30), 20)
    return gb.Record(u, _QUAD.simulate(u, [0.0]) + 0.01 * rng.standard_normal(u.size), name="quad")


@pytest.mark.parametrize("how", ["auto", "points"])
def test_cls_through_more_points_than_clusters_of_a_non_rational_structure_is_refused(how):
    # was: cls's default (how="auto" takes points for a structure with y²) returned θ = [1, 0, 0, 0], y(k) = y(k−1),
    # whose static equation ȳ = ȳ "passes through" any points; the rational structures' check did not apply
    ub = np.linspace(0.2, 1.8, 6)
    pts = gb.StaticPoints(ub, _QUAD.static_curve(ub) + 0.02 + 1e-3 * np.array([1, -1, 1, -1, 1, -1]))
    with pytest.raises(ValueError, match="no isolated equilibrium"):
        gb.cls(_SQ, _quad_record(), pts, how=how)


def test_cls_through_fewer_points_than_clusters_of_a_non_rational_structure_makes_them_equilibria():
    ub = np.array([0.5, 1.5])
    pts = gb.StaticPoints(ub, _QUAD.static_curve(ub) + 0.02)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model = gb.cls(_SQ, _quad_record(), pts).model
    a, b, c, d = model.theta  # ȳ = a ȳ + b ȳ² + c ū + d at each point, with ∂/∂ȳ of the rest away from 1
    np.testing.assert_allclose(a * pts.ybar + b * pts.ybar**2 + c * ub + d, pts.ybar, rtol=1e-9)
    assert np.all(np.abs(1 - a - 2 * b * pts.ybar) > 1e-3)


# -- reference="els" with a DaskRecord: said of the reference ------------------------------------------------
@pytest.mark.parametrize("call", [
    lambda dr, curve: gb.cls(_S, dr, curve, reference="els"),
    lambda dr, curve: gb.pe_thetas(_S, dr, _points(), lambdas=[0.5], constraints=gb.CurveEquality(curve),
                                   reference="els"),
], ids=["cls", "pe_thetas"])
def test_reference_els_with_a_dask_record_names_the_reference_and_what_to_give(call):
    # was: els's TypeError "data must be a Record, a sequence of Records or a Dataset; got a sequence holding a
    # DaskRecord", for data cls and pe_thetas take, naming neither the reference nor what would do
    da = pytest.importorskip("dask.array")
    rec = _record(n=1000)
    dr = gb.DaskRecord(da.from_array(rec.u, chunks=300), da.from_array(rec.y, chunks=300), Ts=rec.Ts, name="dask")
    curve = gb.StaticCurve.fit(_points(), degree=2)
    with pytest.raises(ValueError, match="reference='els'.*in memory"):
        call(dr, curve)
    free = gb.cls(_S, dr, curve).model.theta  # the default reference takes a DaskRecord
    np.testing.assert_allclose(free, gb.cls(_S, rec, curve).model.theta, rtol=1e-9, atol=1e-12)


# -- se_dsf: a run inside the band but at its aim does not stop short of the band's edge ---------------------
_S4 = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"])
# where a run from the coarse sweep's λ1 = 0.3728 member landed (J_S 1.4129e-3, J_SF 1.899e-4 for a band of 2e-4):
# stationary for the aim a 5 % margin inside the band, not for the band
_STUCK = np.array([0.7017069337121737, 0.20147956730461658, 0.00900881859673418, 0.10919957774053114])


@pytest.mark.parametrize("a, c", [(1.0, 1.0), (1.0, 10.0), (1000.0, 100.0)])
def test_se_dsf_from_a_start_just_inside_its_aim_reaches_the_band_s_edge_in_any_units(a, c):
    # was: every step refused, the run stopped with "no step along which the model improves" at J_S 1.4129e-3 in
    # rpm and mlc, or in u × 10, but went on to 1.3868e-3 in u × 100 and y × 1000, where a 1-ulp gain was accepted
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(0.0, 3.0, 21), 20)[:400]
    y = _PLANT.simulate(u, np.zeros(1)) + 0.01 * rng.standard_normal(400)
    rec = gb.Record(u * c, y * a, name="ident")
    ub = np.linspace(0.2, 2.8, 6)
    pts = gb.StaticPoints(ub * c, (_PLANT.static_curve(ub) + 0.05) * a)
    res = gb.se_dsf(_S4, rec, pts, band=2e-4 * a**2, theta0=_STUCK * np.array([1.0, a / c, a / c**2, a]), margin=None)
    assert res.in_band and res.JS / a**2 < 1.3870e-3 and res.JSF / a**2 > 1.999e-4


# -- cls(how="points" | "curve") with nothing to impose ------------------------------------------------------
@pytest.mark.parametrize("how", ["points", "curve"])
def test_cls_asked_to_impose_static_information_it_does_not_have_says_so(how):
    # was: the unconstrained least-squares model, returned as the CLS estimate with constraints () and no word
    with pytest.raises(ValueError, match=f"how='{how}'.*no static information"):
        gb.cls(_S, _record(), None, how=how)
    assert gb.cls(_S, _record(), None).constraints == ()  # how="auto" without static information: least squares
    assert gb.cls(_S, gb.Dataset(_record(), _record(seed=1), _points()), how=how).constraints  # a Dataset's points


# -- a solver option value the solver refuses is said of the options -----------------------------------------
@pytest.mark.parametrize("options", [{"eps_abs": -1.0}, {"eps_rel": -1.0}, {"max_iter": 0}])
def test_an_osqp_option_value_it_refuses_is_not_reported_as_infeasible_constraints(options, capfd):
    # was: InfeasibleError "solver osqp failed (2) with constraints [...]": a bad tolerance read as constraints
    # that admit no θ
    with pytest.raises(ValueError, match="solver_options") as info:
        gb.cls(_S, _record(), _points(), how="context", constraints=gb.StaticBand(b=0.02), solver="osqp",
               solver_options=options)
    assert not isinstance(info.value, gb.InfeasibleError)
    capfd.readouterr()  # OSQP's own lines on the console


# -- cls(how="curve"): as many points as the numerator's clusters, as the docstring now says -------------------
def test_cls_curve_needs_as_many_points_as_numerator_clusters_as_its_docstring_says():
    # was: the docstring said "at least degree + 1 points"; the curve is fitted on the powers the Σ_{u^m} clusters
    # carry, so Σ0 and Σu² take two points (a degree-2 curve through them), and one point is refused naming two
    st = gb.Structure(["y(k-1)", "u(k-1)^2", "1"])
    plant = gb.Model(st, [0.6, 0.05, 0.2])
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(0.0, 3.0, 21), 20)
    rec = gb.Record(u, plant.simulate(u, [0.0]) + 0.01 * rng.standard_normal(u.size))
    two = gb.StaticPoints([1.0, 2.0], plant.static_curve([1.0, 2.0]))
    model = gb.cls(st, rec, two, how="curve").model
    np.testing.assert_allclose(model.static_curve(two.ubar), two.ybar, atol=1e-12)
    with pytest.raises(ValueError, match="at least 2 points"):
        gb.cls(st, rec, gb.StaticPoints([1.0], plant.static_curve([1.0])), how="curve")
    assert "degree + 1" not in gb.cls.__doc__ and "as many points as there are such clusters" in gb.cls.__doc__


# -- GainBounds along a one-input surface: its domain is the default range, as a curve's ----------------------
@pytest.mark.parametrize("reference", [None, "surface"])
def test_gain_bounds_take_a_one_input_surface_s_domain_as_a_curve_s(reference):
    # was: "give ubar_range (no curve domain or static points to take it from)" for a surface with a domain, which
    # cls takes as the curve of the one input (eq. (22))
    pts = _points()
    surf = gb.StaticSurface.fit(pts, degree=2)
    curve = gb.StaticCurve.fit(pts, degree=2)
    ref = surf if reference else None
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        by_surface = gb.cls(_S, _record(), surf, constraints=gb.GainBounds(lower=0.0, reference=ref)).model.theta
        by_curve = gb.cls(_S, _record(), curve, constraints=gb.GainBounds(lower=0.0, reference=curve if ref else None))
    np.testing.assert_allclose(by_surface, by_curve.model.theta, rtol=1e-9, atol=1e-12)
