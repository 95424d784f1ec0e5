"""Bug hunt 44e: static constraints, infeasible sets and the diagnostics of trust."""

import numpy as np
import pytest

import graybox as gb
from graybox.experiments._spec import SpecError, build_constraint, constraint_from_object


# --------------------------------------------------------------------------------------------
# a grid's equality table from a CurveEquality on a StaticSurface
# --------------------------------------------------------------------------------------------
def test_grid_equality_of_a_one_input_surface_keeps_its_powers():
    # 1 + 3ū² as a surface of one input: its coefficients are by exponent, (0,) and (2,); read as an
    # ascending curve they said 1 + 3ū, and the grid imposed that curve instead
    s = gb.StaticSurface(exponents=((0,), (2,)), coefficients=[1.0, 3.0], input_names=("u",))
    (table,) = constraint_from_object(gb.CurveEquality(s))
    curve = build_constraint(table).curve
    ub = np.array([0.5, 2.0, 7.0])
    np.testing.assert_allclose(curve(ub), s(ub[:, None]), rtol=1e-14)


def test_grid_equality_of_a_surface_of_several_inputs_is_refused_by_name():
    pts = gb.StaticPoints(np.array([[0, 0], [1, 0], [0, 1], [1, 1], [2, 1], [1, 2]], float),
                          np.array([1, 2, 3, 4, 5, 6.0]))
    surf = gb.StaticSurface.fit(pts, degree=1)
    with pytest.raises(SpecError, match="surface"):
        constraint_from_object(gb.CurveEquality(surf))


# --------------------------------------------------------------------------------------------
# shared synthetic plant: y(k) = 0.6 y(k-1) + 0.1 y(k-2) + 0.2 u(k-1) + 0.1 u(k-1)² + 0.05 + e(k)
# --------------------------------------------------------------------------------------------
S = ["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)^2", "1"]


def _plant(n=400, noise=0.05, seed=0, u_scale=1.0, u_offset=0.0, y_scale=1.0, y_offset=0.0):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.5, 2.0, n // 20 + 1), 20)[:n]
    y = np.zeros(n)
    e = noise * rng.standard_normal(n)
    for k in range(2, n):
        y[k] = 0.6 * y[k - 1] + 0.1 * y[k - 2] + 0.2 * u[k - 1] + 0.1 * u[k - 1] ** 2 + 0.05 + e[k]
    ub = np.linspace(0.6, 1.8, 6)
    yb = (0.2 * ub + 0.1 * ub**2 + 0.05) / 0.3
    rec = gb.Record(u * u_scale + u_offset, y * y_scale + y_offset, Ts=1.0)
    pts = gb.StaticPoints(ub * u_scale + u_offset, yb * y_scale + y_offset)
    return gb.Dataset(rec, rec, pts)


@pytest.mark.parametrize("solver", ["clarabel", "closed"])
def test_contradictory_cluster_equalities_are_not_blamed_on_static_points(solver):
    # Σy = 0.9 and Σy = 0.5: the message said "generic static points over-determine" the static function
    # and advised fewer points, where no point is imposed at all
    d = _plant()
    cons = gb.ClusterBounds({"Σy": (0.9, 0.9)}) & gb.ClusterBounds({"Σy": (0.5, 0.5)})
    with pytest.raises(gb.InfeasibleError) as info:
        gb.pe_pareto(S, d, constraints=cons, lambdas=[0.5], solver=solver)
    msg = str(info.value)
    assert "Σy <= 0.9" in msg and "Σy <= 0.5" in msg
    assert "static points" not in msg


def test_too_many_points_to_pass_through_still_says_so():
    d = _plant()
    pts = gb.StaticPoints(d.static.ubar, d.static.ybar + 0.01 * np.array([1, -1, 1, -1, 1, -1]))  # off any one curve
    with pytest.raises(gb.InfeasibleError, match="over-determine"):
        gb.cls(["u(k-1)", "u(k-1)^2", "1"], d.ident, constraints=gb.PassesThrough(pts), how="context")


@pytest.mark.parametrize("bad", [3, 2.5, "th <= 1"])
def test_user_constraint_returning_no_constraints_is_named(bad):
    # a number returned by the function failed in list(): "'int' object is not iterable", naming nothing
    d = _plant()
    with pytest.raises(ValueError, match="mine: the function must return cvxpy constraints, got (int|float|str)"):
        gb.cls(S, d.ident, constraints=gb.UserConstraint(lambda th: bad, name="mine"), how="context")


# --------------------------------------------------------------------------------------------
# the active set of a CLS / PE covariance, in any units
# --------------------------------------------------------------------------------------------
def _band_width(fn, constraint, **units):
    d = _plant(**units)
    ys, yo = units.get("y_scale", 1.0), units.get("y_offset", 0.0)
    us, uo = units.get("u_scale", 1.0), units.get("u_offset", 0.0)
    pts = gb.StaticPoints(d.static.ubar, d.static.ybar + ys * 0.05 * np.array([1, -1, 1, -1, 1, -1]))
    c = constraint(ys)
    if fn == "cls":
        fit = gb.cls(S, d.ident, pts, constraints=c, how="context")
        unc = gb.cls_uncertainty(fit, d.ident, pts, constraints=c, how="context")
    else:
        front = gb.pe_pareto(S, d.ident, pts, constraints=c, lambdas=[0.5])
        unc = gb.pe_uncertainty(front.member_model(0), d.ident, pts, lambda1=0.5, constraints=c)
    frame = gb.static_curve_band(unc, np.array([0.7, 1.2, 1.7]) * us + uo).to_frame()
    return (frame["ybar high"].to_numpy() - frame["ybar low"].to_numpy()) / ys


@pytest.mark.parametrize("fn", ["cls", "pe"])
@pytest.mark.parametrize("units", [dict(u_offset=1e4), dict(y_offset=1e4)])
def test_band_constraint_covariance_does_not_depend_on_offsets(fn, units):
    # an inequality counted as active within 1e-6 ‖θ ⊙ s‖, which grows with the offsets: at u = 1e4 ± 1 every row of
    # a band 0.06 wide was active (the static band collapsed to the constrained model's), at y = 1e4 ± 1 six of them
    band = lambda ys: gb.StaticBand(b=0.06 * ys)  # noqa: E731
    np.testing.assert_allclose(_band_width(fn, band, **units), _band_width(fn, band), rtol=1e-4)


@pytest.mark.parametrize("fn", ["cls", "pe"])
def test_cluster_bound_covariance_does_not_depend_on_the_output_offset(fn):
    bound = lambda ys: gb.ClusterBounds({"Σy": (None, 0.65)})  # noqa: E731
    np.testing.assert_allclose(_band_width(fn, bound, y_offset=1e4), _band_width(fn, bound), rtol=1e-4)


def test_a_grid_table_given_to_an_estimator_is_named_as_a_table():
    # a table such as a grid spec holds was iterated as its keys: "got str"
    d = _plant()
    with pytest.raises(TypeError, match="dict"):
        gb.cls(S, d.ident, constraints={"type": "band", "b": 0.1})


def test_selection_uncertainty_takes_the_tables_the_selection_took():
    # select_graybox takes constraint tables and .uncertainty says it takes "a constraint, a table of them or a
    # sequence", but handed the tables on to pe_uncertainty, which refused them
    import warnings

    d, other = _plant(n=300), _plant(n=300, seed=7)
    pts = gb.StaticPoints(d.static.ubar, d.static.ybar + 0.05 * np.array([1, -1, 1, -1, 1, -1]), uncertainty=0.05)
    data = gb.Dataset(d.ident, other.ident, pts)
    table = {"type": "band", "b": 0.08}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the selection's notes on these small data are not what is tested
        sel = gb.select_graybox(gb.Candidates(ny=2, nu=1, degree=2, max_y_power=1), data, estimator="pe",
                                constraints=[table], lambdas=[0.3, 0.9], sizes=[4, 5], sources=("frols",),
                                progress=False)
    by_object = sel.uncertainty(data, constraints=gb.StaticBand(b=0.08))
    for given in ([table], table):
        np.testing.assert_array_equal(sel.uncertainty(data, constraints=given).cov, by_object.cov)


# --------------------------------------------------------------------------------------------
# solver options: an option error is not an infeasible constraint set
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("solver", ["clarabel", "osqp"])
def test_an_unknown_solver_option_is_a_value_error_naming_it(solver):
    # osqp's refusal came back as InfeasibleError ("solver osqp failed (Unrecognized settings ['foo'])"), which a
    # sweep reads as constraints that admit no θ; clarabel's as its own TypeError
    d = _plant()
    with pytest.raises(ValueError, match="foo") as info:
        gb.pe_pareto(S, d, constraints=gb.StaticBand(b=0.5), lambdas=[0.5], solver=solver,
                     solver_options={"foo": 1})
    assert not isinstance(info.value, gb.InfeasibleError)
    assert "solver_options" in str(info.value)


def test_a_solver_option_value_the_solver_refuses_is_a_value_error_naming_the_options():
    # max_iter = -2: OverflowError from clarabel's binding
    d = _plant()
    with pytest.raises(ValueError, match="solver_options") as info:
        gb.cls(S, d, constraints=gb.StaticBand(b=0.5), how="context", solver_options={"max_iter": -2})
    assert not isinstance(info.value, gb.InfeasibleError)


def test_a_cone_constraint_with_osqp_is_refused_as_the_solver_choice_not_as_infeasible():
    # a second-order-cone UserConstraint with solver="osqp" (QPs only) came back as InfeasibleError "solver osqp
    # failed (The solver OSQP cannot solve this problem.)", as if the constraints admitted no θ
    import cvxpy as cp

    d = _plant()
    uc = gb.UserConstraint(lambda th: [cp.norm(th[:2]) <= 0.7], name="norm of the y terms")
    with pytest.raises(ValueError, match="norm of the y terms.*clarabel") as info:
        gb.cls(S, d.ident, constraints=uc, solver="osqp")
    assert not isinstance(info.value, gb.InfeasibleError)
    assert np.all(np.isfinite(gb.cls(S, d.ident, constraints=uc).model.theta))  # clarabel takes cones


@pytest.mark.parametrize("fn", ["cls", "pe"])
@pytest.mark.parametrize("make", [lambda: gb.StaticBand(b=0.06), lambda: gb.ClusterBounds({"Σy": (None, 0.5)}),
                                  lambda: gb.GainBounds(upper=0.5)])
def test_a_covariance_is_refused_for_a_model_that_breaks_the_inequalities_given(fn, make):
    # a model estimated without the constraints, whose θ breaks them, was accepted: the broken rows counted as
    # active equalities, and the covariance was that of another problem, said as the model's
    d = _plant()
    pts = gb.StaticPoints(d.static.ubar, d.static.ybar + 0.05 * np.array([1, -1, 1, -1, 1, -1]))
    c = make()
    with pytest.raises(ValueError, match="does not satisfy"):
        if fn == "cls":
            gb.cls_uncertainty(gb.cls(S, d.ident, pts, how="context"), d.ident, pts, constraints=c, how="context")
        else:
            member = gb.pe_pareto(S, d.ident, pts, lambdas=[0.5]).member_model(0)
            gb.pe_uncertainty(member, d.ident, pts, lambda1=0.5, constraints=c)


def test_gain_bounds_beyond_their_reference_curve_name_the_constraint():
    # the curve's own refusal ("ū = [...] outside the domain [0.6, 1.8] of fit to static points") named no constraint
    d = _plant()
    curve = gb.StaticCurve.fit(d.static, degree=2)
    with pytest.raises(ValueError, match=r"static gain in \[0, inf\] over ū in \[0, 3\].*outside the domain"):
        gb.cls(S, d, constraints=gb.GainBounds(lower=0, ubar_range=(0.0, 3.0), reference=curve))


@pytest.mark.parametrize("fn", ["cls", "pe"])
@pytest.mark.parametrize("kind", ["none", "band"])
def test_covariance_of_an_input_far_from_its_zero(fn, kind):
    # u = −50 ± 0.0015 with a u² term: the terms cancel (‖θ ⊙ s‖ = 6e8 for outputs of order 1), and the estimate,
    # right to its round-off, was refused as "not the optimum" (2e-6 of its residual along the free directions);
    # with the band its active row, 2.4e-6 of the spread off its hyperplane, was taken as inactive
    make = {"none": lambda ys: None, "band": lambda ys: gb.StaticBand(b=0.06 * ys)}[kind]
    far = _band_width(fn, make, u_scale=1e-3, u_offset=-50.0)
    np.testing.assert_allclose(far, _band_width(fn, make), rtol=1e-3)


def test_a_member_passed_with_another_lambda_is_still_refused_far_from_the_inputs_zero():
    d = _plant(u_scale=1e-3, u_offset=-50.0)
    member = gb.pe_pareto(S, d.ident, d.static, lambdas=[0.5]).member_model(0)
    with pytest.raises(ValueError, match="not the optimum"):
        gb.pe_uncertainty(member, d.ident, d.static, lambda1=0.3)
