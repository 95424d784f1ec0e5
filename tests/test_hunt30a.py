"""Bugs found by a bug hunt in static analysis (graybox.static and the models' static curves,
surfaces, equilibria and gains) on one's own models: inputs not named "u", units far from 1, cross
and cubic terms, several or no equilibria, one and two inputs. Each test fails without its fix."""

import numpy as np
import pytest

import graybox as gb


def test_the_static_gain_is_nan_where_the_static_curve_is():
    # y(k) = 1.5 y(k-1) + s(k-1) (+ s(k-1)²): its one equilibrium is unstable, so the static curve
    # is NaN with strict=False; the gain read NaN⁰ = 1 in −F_ū/F_ȳ and gave a finite slope (−2, −6)
    # of a curve that does not exist there.
    st = gb.Structure(["y(k-1)", "s(k-1)", "s(k-1)^2"])
    th = [1.5, 1.0, 1.0]
    assert np.isnan(gb.static_curve(st, th, [1.0, 2.0], strict=False)).all()
    assert np.isnan(gb.static_gain(st, th, [1.0, 2.0], strict=False)).all()
    two = gb.Structure(["y(k-1)", "a(k-1)", "b(k-1)"])
    assert np.isnan(gb.static_surface_gain(two, [1.5, 1.0, 2.0], [[1.0, 2.0]], strict=False)).all()


#: y(k) = 1.5 y(k-1) − 0.5 y(k-1)³/s² + 0.1 s v(k-1): bistable, its equilibria near ±s (s the output's unit)
def bistable(s: float) -> gb.Model:
    return gb.Model(["y(k-1)", "y(k-1)^3", "v(k-1)"], [1.5, -0.5 / s**2, 0.1 * s], input_names=("v",))


def test_the_equilibria_a_static_curve_cannot_choose_between_are_named_in_any_units():
    # two stable equilibria near ±1e-7 V: the message rounded them to 6 decimals, "[-0.0, 0.0]"
    s = 1e-7
    ys = [e.ybar for e in bistable(s).equilibria(0.5) if e.stable]
    with pytest.raises(ValueError, match="pass y0") as info:
        bistable(s).static_curve([0.5])
    assert all(f"{y:.6g}" in str(info.value) for y in ys)
    two = gb.Model(["y(k-1)", "y(k-1)^3", "a(k-1)", "b(k-1)"], [1.5, -0.5 / s**2, 0.1 * s, 0.0])
    with pytest.raises(ValueError, match="pass y0") as info:
        two.static_curve([[0.5, 1.0]])
    assert all(f"{y:.6g}" in str(info.value) for y in ys)


def test_the_gain_of_an_integrator_is_nan_without_a_numpy_warning():
    # y(k) = y(k-1) + 2 q(k-1) has no equilibrium at q̄ ≠ 0 (F_ȳ = 0): with strict=False the gain is
    # NaN, but dividing by F_ȳ = 0 let numpy's "divide by zero" RuntimeWarning out (an error here)
    st = gb.Structure(["y(k-1)", "q(k-1)"])
    assert np.isnan(gb.static_gain(st, [1.0, 2.0], [1.0, 3.0], strict=False)).all()


def test_a_static_curve_without_y0_names_every_level_it_fails_at_and_why():
    # y(k) = y(k-1)² + 1 + u(k-1): no real equilibrium at ū = 1 and 2, two unstable ones at ū = −3.
    # The docstring promises every such ū named; the one-input curve stopped at the first, and both
    # it and the surface said "no stable equilibrium" where there is no equilibrium at all.
    one = gb.Model(["y(k-1)^2", "1", "u(k-1)"], [1.0, 1.0, 1.0])
    with pytest.raises(ValueError) as info:
        one.static_curve([1.0, 2.0, -3.0])
    msg = str(info.value)
    assert "no equilibrium at ū = 1 " in msg and "no equilibrium at ū = 2 " in msg
    assert "no stable equilibrium at ū = -3" in msg
    two = gb.Model(["y(k-1)^2", "1", "a(k-1)", "b(k-1)"], [1.0, 1.0, 1.0, 0.0])
    with pytest.raises(ValueError) as info:
        two.static_curve([[1.0, 0.0], [2.0, 5.0], [-3.0, 0.0]])
    msg = str(info.value)
    assert "no equilibrium at ū = (1, 0)" in msg and "no equilibrium at ū = (2, 5)" in msg
    assert "no stable equilibrium at ū = (-3, 0)" in msg


def test_a_curve_or_surface_refuses_a_level_outside_its_domain_in_any_units():
    # known over [1, 2] pA (1e-12 A): the tolerance at the domain's ends was 1e-9 absolute (at least
    # 1e-9 × 1), so 5 pA, 2.5 times the upper end, was accepted as inside the domain in amperes
    curve = gb.StaticCurve.polynomial([1.0, 2.0], domain=(1e-12, 2e-12))
    assert curve(2e-12) == pytest.approx(1.0 + 4e-12)
    with pytest.raises(ValueError, match="outside the domain"):
        curve(5e-12)
    surface = gb.StaticSurface.polynomial({(0, 0): 1.0, (1, 0): 2.0}, domain=[(1e-12, 2e-12), (0.0, 1.0)])
    with pytest.raises(ValueError, match="outside the domain"):
        surface([[5e-12, 0.5]])


@pytest.mark.parametrize("offset", [0.0, 1e3, 1e9, -1e9])
def test_a_domain_narrow_beside_its_offset_refuses_what_lies_beyond_its_width(offset):
    # the tolerance at the ends was 1e-9 of the ends' size, not of the domain's width: [1e9, 1e9 + 0.04] took
    # 1e9 + 0.5 (12 widths past its upper end) as inside; the same domain at 0 refused 0.5
    lo, hi = offset, offset + 0.04
    curve = gb.StaticCurve.polynomial([1.0, 2.0], domain=(lo, hi))
    surface = gb.StaticSurface.polynomial({(0, 0): 1.0, (1, 0): 2.0}, domain=[(lo, hi), (0.0, 1.0)])
    for beyond in (hi + 0.5, hi + 0.001, lo - 0.001):
        with pytest.raises(ValueError, match="outside the domain"):
            curve(beyond)
        with pytest.raises(ValueError, match="outside the domain"):
            surface([[beyond, 0.5]])
    # the ends, and ends off by the round-off of a conversion (two units in their last place), are inside
    back = np.array([lo, hi]) + 2 * np.spacing(np.array([lo, hi])) * [-1, 1]
    assert np.isfinite(curve(np.array([lo, hi, *back]))).all()
    assert np.isfinite(surface(np.column_stack([[lo, hi, *back], [0.5] * 4]))).all()


@pytest.mark.parametrize("points", [[1.0, 2.0, 3.0], np.array([1.0, 2.0, 3.0])])
def test_a_curve_or_surface_refuses_points_that_are_not_static_points_as_a_type_error(points):
    # StaticCurve.fit read points.ubar and failed with AttributeError; StaticSurface.fit with a ValueError
    with pytest.raises(TypeError, match="points must be StaticPoints"):
        gb.StaticCurve.fit(points)
    with pytest.raises(TypeError, match="points must be StaticPoints"):
        gb.StaticSurface.fit(points)


def test_a_curve_fitted_to_points_of_two_inputs_says_to_fit_a_surface():
    # numpy's "x must be a one-dimensional array or sequence." came out of np.vander
    pts = gb.StaticPoints([[1.0, 2.0], [2.0, 3.0], [3.0, 1.0]], [1.0, 2.0, 3.0], input_names=("valve", "speed"))
    with pytest.raises(ValueError, match=r"2 inputs \('valve', 'speed'\).*StaticSurface.fit"):
        gb.StaticCurve.fit(pts, degree=1)


def test_a_curve_fitted_to_a_single_static_point_says_why_it_cannot():
    # the domain check's "domain high must lie in (2000, inf), got 2000.0" came out: true but not the reason
    one = gb.StaticPoints([2000.0], [2e5], input_names=("speed",))
    with pytest.raises(ValueError, match="one level.*two levels or more"):
        gb.StaticCurve.fit(one, degree=0)


def test_a_surface_imposed_on_two_inputs_is_matched_by_its_input_names():
    # the data's inputs are (valve, speed); a surface written in (speed, valve) was matched by position,
    # so eq. (22) and the gain bounds gave valve the speed coefficient: CLS imposed 2 + 1 valve + 4 speed
    # for the surface 2 + 4 valve + 1 speed, without a word
    st = gb.Structure(["1", "valve(k-1)", "speed(k-1)", "y(k-1)"])
    rng = np.random.default_rng(0)
    u = rng.uniform(0.0, 1.0, (300, 2))
    y = gb.Model(st, [1.0, 2.0, 0.5, 0.5], input_names=("valve", "speed")).simulate(u, np.zeros(1))
    rec = gb.Record(u, y, input_names=("valve", "speed"))
    swapped = gb.StaticSurface.polynomial({(0, 0): 2.0, (0, 1): 4.0, (1, 0): 1.0}, input_names=("speed", "valve"))
    with pytest.raises(ValueError, match=r"\('speed', 'valve'\).*\('valve', 'speed'\)"):
        gb.cls(st, rec, swapped)
    with pytest.raises(ValueError, match=r"\('speed', 'valve'\).*\('valve', 'speed'\)"):
        gb.pe_pareto(st, rec, gb.StaticPoints([[0.0, 0.0], [1.0, 1.0], [0.5, 0.2], [0.2, 0.9]], [2.0, 7.0, 4.2, 3.7],
                                              input_names=("valve", "speed")),
                     constraints=gb.GainBounds(lower=0.0, reference=swapped), lambdas=[0.5])


def test_a_surface_of_one_input_is_still_imposed_whatever_it_calls_its_input():
    # the check of the surface's input names (above) read the cluster map's inputs, which a one-input
    # structure's map does not have: CLS with a one-input StaticSurface raised AttributeError
    st = gb.Structure(["1", "y(k-1)", "speed(k-1)", "speed(k-1)^2"])
    model = gb.Model(st, [0.1, 0.5, 0.2, 0.01], input_names=("speed",))
    u = np.linspace(0.0, 2.0, 200)
    rec = gb.Record(u, model.simulate(u, np.zeros(1)), input_names=("speed",))
    for names in [("speed",), None]:  # None: the default name "u"
        surface = gb.StaticSurface.polynomial({(0,): 0.2, (1,): 0.4, (2,): 0.02}, input_names=names)
        np.testing.assert_allclose(gb.cls(st, rec, surface).model.theta, model.theta, atol=1e-9)


def test_constraints_refuse_an_argument_of_another_type_as_a_type_error():
    # a list for the curve and a number for the function came out as ValueError; a text bound of
    # ClusterBounds as numpy's "ufunc 'isfinite' not supported", and True was taken as the bound 1
    with pytest.raises(TypeError, match="CurveEquality.*list"):
        gb.CurveEquality([1.0, 2.0, 3.0])
    with pytest.raises(TypeError, match="UserConstraint.*int"):
        gb.UserConstraint(3)
    for bad in ("a", True):
        with pytest.raises(TypeError, match="Σy"):
            gb.ClusterBounds({"Σy": (None, bad)})


@pytest.mark.parametrize("call", [
    lambda st, th: gb.static_curve(st, th, [1.0]),
    lambda st, th: gb.static_gain(st, th, [1.0]),
    lambda st, th: gb.equilibria(st, th, 1.0),
])
def test_the_static_functions_name_a_theta_of_the_wrong_length_or_not_finite(call):
    # θ of 2 values for a structure of 3 terms came out as numpy's "matmul: Input operand 1 has a mismatch
    # in its core dimension"; a NaN in θ gave "no equilibrium (the static equation has no real root)", or []
    st = gb.Structure(["y(k-1)", "y(k-1)^2", "p(k-1)"])
    with pytest.raises(ValueError, match="theta has 2 values but the structure has 3 terms"):
        call(st, [0.5, -0.1])
    with pytest.raises(ValueError, match="theta has non-finite values at \\[1\\]"):
        call(st, [0.5, np.nan, 1.0])
    # a structure written as its terms is read as one (it was "unhashable type: 'list'")
    assert str(call(["y(k-1)", "y(k-1)^2", "p(k-1)"], [0.5, -0.1, 1.0])) == str(call(st, [0.5, -0.1, 1.0]))


@pytest.mark.parametrize("call", [
    lambda st, th: gb.static_surface(st, th, [[1.0, 1.0]]),
    lambda st, th: gb.static_surface_gain(st, th, [[1.0, 1.0]]),
    lambda st, th: gb.surface_equilibria(st, th, [1.0, 1.0]),
])
def test_the_surface_functions_name_a_theta_of_the_wrong_length(call):
    # "operands could not be broadcast together with shapes (1,1,2) (1,1,3)"
    st = gb.Structure(["y(k-1)", "a(k-1)", "b(k-1)"])
    with pytest.raises(ValueError, match="theta has 2 values but the structure has 3 terms"):
        call(st, [0.5, 1.0])


def test_equilibria_takes_one_input_level_and_says_so():
    # [1.0, 2.0] gave "ubar must be 1-D, got shape (1, 2)", and "x" "ubar must be an array of numbers, got list"
    with pytest.raises(TypeError, match="ubar \\(one input level\\) must be a real number, got \\[1.0, 2.0\\]"):
        gb.equilibria(gb.Structure(["y(k-1)", "u(k-1)"]), [0.5, 1.0], [1.0, 2.0])


def test_levels_outside_the_records_are_named_in_any_units():
    # a current in units of 1e-8 A: the static points and operating points beyond the records were
    # named rounded to 6 decimals, "ū = [0.0, 0.0]", in the very warning meant to catch a units mix-up;
    # and local_model's absolute 1e-9 tolerance took 1.05e-8 as inside records that end at 1e-8
    s = 1e-8
    st = gb.Structure(["1", "y(k-1)", "i(k-1)"])
    u = np.linspace(0.0, 1.0, 300) * s
    m = gb.Model(st, [1.0, 0.5, 1.0 / s], input_names=("i",), Ts=1.0)
    rec = gb.Record(u, m.simulate(u, np.zeros(1)), input_names=("i",))
    pts = gb.StaticPoints(np.array([0.5, 3.0, 4.0]) * s, [3.0, 8.0, 10.0], input_names=("i",))
    with pytest.warns(gb.StaticRangeWarning, match=r"ū = \[3e-08, 4e-08\]"):
        gb.cls(st, rec, pts)
    with pytest.warns(gb.StaticRangeWarning, match=r"ū = \[1.05e-08\]"):
        gb.local_model(m, 1.05 * s, data=rec)


def test_a_models_gain_curve_over_a_grid_is_nan_where_it_has_no_equilibrium():
    # Model.static_curve takes strict=False (NaN where no equilibrium is reached) but Model.static_gain
    # did not pass it on: a gain curve over a grid crossing a region without equilibrium could not be drawn
    # y(k) = (0.5 + 0.001 s) y(k-1) + s(k-1): stable below s = 500, unstable above
    m = gb.Model(["y(k-1)", "s(k-1)y(k-1)", "s(k-1)"], [0.5, 0.001, 1.0], input_names=("s",))
    g = m.static_gain([100.0, 700.0], strict=False)
    assert g[0] == pytest.approx(0.5 / (0.5 - 0.1) ** 2) and np.isnan(g[1])
    two = gb.Model(["y(k-1)", "a(k-1)y(k-1)", "a(k-1)", "b(k-1)"], [0.5, 0.001, 1.0, 2.0])
    g = two.static_gain([[100.0, 0.0], [700.0, 0.0]], strict=False)
    assert g[0] == pytest.approx([0.5 / (0.5 - 0.1) ** 2, 2.0 / 0.4]) and np.isnan(g[1]).all()


@pytest.mark.parametrize("exponents, match", [
    ([(0, 0, 0), (1, 0, 0)], "2 inputs.*3 entries"),  # was numpy's "operands could not be broadcast together"
    ([(0, 0), (1, 0), (1, 0)], r"\(1, 0\).*given twice"),  # was "regressor matrix has rank 2 < 3 columns"
    ([], "at least one monomial"),  # was IndexError "too many indices for array"
])
def test_a_surface_fitted_on_given_monomials_checks_them_first(exponents, match):
    u = np.array([[0, 0], [1, 0], [0, 1], [1, 1], [2, 1], [1, 2.0]])
    pts = gb.StaticPoints(u, u[:, 0] + 2 * u[:, 1], input_names=("a", "b"))
    with pytest.raises(ValueError, match=match):
        gb.StaticSurface.fit(pts, exponents=exponents)


def test_the_cluster_maps_read_a_structure_given_as_its_terms():
    # "unhashable type: 'list'" and "'list' object has no attribute 'inputs'" came out of the caches
    assert gb.cluster_map(["y(k-1)", "u(k-1)", "u(k-2)"]).names == ["Σu", "Σy"]
    assert gb.surface_cluster_map(["y(k-1)", "a(k-1)", "b(k-1)"]).names == ["Σb", "Σa", "Σy"]
    with pytest.raises(TypeError, match="structure must be a Structure, a sequence of terms or a model"):
        gb.cluster_map(3)


def test_a_local_model_without_an_equilibrium_or_with_several_says_why_in_any_units():
    # local_model had its own copy of the static curve's phrases: two stable equilibria near ±1e-7 V were
    # named rounded to 6 decimals ("[-0.0, 0.0]"), and an integrator, whose rational static function's
    # denominator vanishes, was said to have a static equation "with no real root" (only)
    s = 1e-7
    ys = [e.ybar for e in bistable(s).equilibria(0.5) if e.stable]
    with pytest.raises(ValueError, match="pass y0") as info:
        gb.local_model(bistable(s), 0.5, Ts=1.0)
    assert all(f"{y:.6g}" in str(info.value) for y in ys)
    integrator = gb.Model(["y(k-1)", "q(k-1)"], [1.0, 2.0], input_names=("q",))
    lm = gb.local_model(integrator, 1.0, Ts=1.0)
    assert lm.status == "no equilibrium" and "denominator vanishes" in lm.reason


def test_a_surface_fitted_to_points_that_hold_an_input_says_which():
    # the points hold z at 2: the fit failed first with the least-squares "rank 2 < 3 columns", so the
    # message meant for this case ("the points do not vary every input") never came out; it names z now
    u = np.column_stack([np.arange(5.0), np.full(5, 2.0)])
    pts = gb.StaticPoints(u, np.arange(5.0), input_names=("a", "z"))
    with pytest.raises(ValueError, match=r"do not vary every input.*\['z'\]"):
        gb.StaticSurface.fit(pts, 1)


def test_a_network_that_cannot_choose_an_equilibrium_names_them_and_every_level_in_any_units():
    # NeuralModel.static_curve had its own copy of the rule: equilibria near ±2e-7 V rounded to 6
    # decimals ("[-0.0, 0.0]"), and only the first failing ū named; it now shares the polynomial model's
    from graybox.estimation._neural import NeuralModel

    W1 = np.array([[2.0, 0.001]])  # y_n(k) = 2 tanh(2 y_n(k-1) + 0.001 u(k-1)): bistable at ū = 0
    net = NeuralModel(W1, [0.0], [2.0], 0.0, ny=1, nu=1, y_scale=1e-7)
    ys = [e.ybar for e in net.equilibria(0.0) if e.stable]
    with pytest.raises(ValueError, match="pass y0") as info:
        net.static_curve([0.0, 1.0])
    msg = str(info.value)
    assert all(f"{y:.6g}" in msg for y in ys) and "ū = 0 " in msg and "ū = 1 " in msg
    assert net.static_curve([]).shape == (0,)


def test_evaluate_thetas_checks_the_shape_of_thetas_and_refuses_a_non_finite_member():
    # θ rows of the wrong length came out as numpy's matmul, einsum or unpacking errors; a member with
    # a NaN had J_S = J_SF = inf but J_1 = NaN (scored inf since, and refused naming its row since mend36a:
    # a NaN θ is no model, and every caller leaves failed members out before scoring)
    st = gb.Structure(["1", "y(k-1)", "speed(k-1)"])
    rec = gb.Record(np.linspace(0.0, 1.0, 50), np.linspace(0.0, 1.0, 50), input_names=("speed",))
    pts = gb.StaticPoints([0.0, 1.0], [0.2, 2.2], input_names=("speed",))
    for bad in (np.zeros((3, 2)), np.zeros((2, 3, 3))):
        with pytest.raises(ValueError, match=r"thetas must have shape \(P, 3\)"):
            gb.evaluate_thetas(st, bad, rec, pts)
    with pytest.raises(TypeError, match="thetas"):
        gb.evaluate_thetas(st, "abc", rec)
    with pytest.raises(ValueError, match=r"thetas: row \[1\]"):
        gb.evaluate_thetas(st, [[0.1, 0.5, 1.0], [np.nan, 0.5, 1.0]], rec, pts)
    out = gb.evaluate_thetas(st, [[0.1, 0.5, 1.0]], rec, pts)
    assert all(np.isfinite(out[k][0]) for k in ("J1", "JS", "JSF"))
