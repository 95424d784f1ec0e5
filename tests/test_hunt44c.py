"""Bug hunt 44c: several inputs and transient-input channels end to end."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import graybox as gb
from graybox import plots


def _grid(order=(0, 1), names=("speed", "valve")):
    """Static points of a surface in (speed rpm, valve %), columns in ``order``."""
    A, B = np.meshgrid(np.linspace(600.0, 1400.0, 4), np.linspace(20.0, 80.0, 4))
    A, B = A.ravel(), B.ravel()
    ybar = 0.002 * A - 0.01 * B + 1e-5 * A * B
    U = np.c_[A, B][:, list(order)]
    return gb.StaticPoints(U, ybar, input_names=tuple(names[i] for i in order), uncertainty=0.01)


# --- plots of surfaces: a surface and points that name their inputs in different orders --------------------------
def test_surface_contours_match_a_surface_to_points_by_input_name():
    pts = _grid()
    swapped = _grid(order=(1, 0))  # the same points, columns (valve, speed)
    surf = gb.StaticSurface.fit(pts, 2)  # in (speed, valve)
    fig = plots.plot_surface_contours(surf, swapped, n_grid=9)
    ax = fig.axes[0]
    # the axes are the points' inputs (valve across, speed up), and the map is the surface read by name there
    assert ax.get_xlim()[0] == pytest.approx(20.0) and ax.get_ylim()[1] == pytest.approx(1400.0)
    same = plots.plot_surface_contours(surf, pts, n_grid=9).axes[0]
    # the same surface over the same box: the same contour levels (a surface read with its columns swapped
    # would span other values, or leave its domain)
    assert np.allclose(ax.collections[0].levels, same.collections[0].levels)


def test_surface_slices_match_a_surface_to_points_by_input_name():
    pts = _grid()
    swapped = _grid(order=(1, 0))
    surf = gb.StaticSurface.fit(pts, 2)
    fig = plots.plot_surface_slices(surf, swapped, against=1, n_grid=5)  # ȳ against speed, valve held
    ax = fig.axes[0]
    line = ax.get_lines()[0]  # the surface at the first held level of valve (20 %)
    x = np.asarray(line.get_xdata())
    assert np.allclose(line.get_ydata(), surf(np.c_[x, np.full_like(x, 20.0)]))


def test_surface_plots_refuse_a_surface_of_other_inputs():
    pts = _grid()
    other = gb.StaticSurface.fit(_grid(names=("n1", "n2")), 2)
    for draw in (plots.plot_surface_slices, plots.plot_surface_contours):
        with pytest.raises(ValueError, match="inputs"):
            draw(other, pts)


# --- select_graybox: a surface beside records of more inputs, or of its inputs in another order -------------------
def _rig(n, seed, order=(0, 1)):
    rng = np.random.default_rng(seed)
    a = np.repeat(rng.uniform(-1, 1, n // 20 + 1), 20)[:n]
    b = np.repeat(rng.uniform(-1, 1, n // 30 + 1), 30)[:n]
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = 0.6 * y[k - 1] + 0.5 * a[k - 1] - 0.3 * b[k - 2] + 0.2 * a[k - 1] * b[k - 1] + 0.1
    U = np.c_[1000 + 500 * a, 50 + 40 * b][:, list(order)]
    return gb.Record(U, y, Ts=0.1, input_names=tuple(("speed", "valve")[i] for i in order))


def test_select_graybox_says_how_a_surface_meets_records_with_transient_inputs():
    data = gb.transient_inputs(gb.Dataset(_rig(300, 0), _rig(200, 1), _grid()), taus=[3])
    surface = gb.StaticSurface.fit(_grid(), 1)  # in (speed, valve), the records' first two inputs
    cand = gb.Candidates(1, {"speed": 1, "valve": 1, "speed_tau3": 1, "valve_tau3": 1}, degree=1)
    with pytest.raises(ValueError) as info:
        gb.select_graybox(cand, data, surface, band=1e-3, progress=False)
    said = str(info.value)
    assert "first input" not in said and "('speed', 'valve')" in said and ".points(ubar)" in said
    assert ".points(ubar, name)" not in said
    # the way it gives: the surface's points, given the transient channels
    pts = gb.transient_inputs(surface.points(_grid().ubar), taus=[3])
    assert pts.input_names == data.input_names


def test_select_graybox_says_a_surface_of_the_records_inputs_in_another_order_is_to_be_reordered():
    surface = gb.StaticSurface.fit(_grid(order=(1, 0)), 1)  # (valve, speed)
    cand = gb.Candidates(1, {"speed": 1, "valve": 1}, degree=1)
    with pytest.raises(ValueError) as info:
        gb.select_graybox(cand, gb.Dataset(_rig(300, 0), _rig(200, 1), _grid()), surface, band=1e-3, progress=False)
    said = str(info.value)
    assert "first input" not in said and "transient" not in said and "order" in said


# --- plot_operating_curve: a model of several inputs whose operating points vary one -------------------------------
def _transient_model():
    """A one-input plant's model with a transient input u_tau3 (zero at every operating point)."""
    st = gb.parse_structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "u_tau3(k-1)"])
    return gb.Model(st, np.array([0.1, 0.6, 0.002, 1e-6, -0.5]), input_names=("u", "u_tau3"), Ts=0.5)


def test_plot_operating_curve_draws_a_curve_over_the_one_input_it_varies():
    model = _transient_model()
    speeds = np.linspace(800.0, 1600.0, 5)
    curve = gb.operating_curve(model, np.c_[speeds, np.zeros(5)])  # u_tau3 rests at 0: its static level
    fig = plots.plot_operating_curve(curve)
    gain_line = fig.axes[0].get_lines()[0]
    np.testing.assert_array_equal(gain_line.get_xdata(), speeds)
    np.testing.assert_allclose(gain_line.get_ydata(), curve.gain[:, 0])  # ∂ȳ/∂u, the input on the axis
    assert "u" in fig.axes[2].get_xlabel()


def test_plot_operating_curve_refuses_points_that_vary_several_inputs_naming_them():
    # two inputs of the plant's own (a transient input's level other than 0 is no operating point: refused by
    # operating_curve itself since mend60g)
    st = gb.parse_structure(["1", "y(k-1)", "u(k-1)", "v(k-1)"])
    model = gb.Model(st, np.array([0.1, 0.6, 0.002, -0.5]), input_names=("u", "v"), Ts=0.5)
    curve = gb.operating_curve(model, [[800.0, 0.0], [1200.0, 1.0]])
    with pytest.raises(ValueError, match=r"'u', 'v'"):
        plots.plot_operating_curve(curve)
    with pytest.raises(ValueError, match="transient input"):
        gb.operating_curve(_transient_model(), [[800.0, 0.0], [1200.0, 1.0]])


# --- a cluster named by its factors, whatever order the data list the inputs in ----------------------------------
ST_MISO = gb.parse_structure(["1", "y(k-1)", "speed(k-1)", "valve(k-2)", "speed(k-1)valve(k-1)", "y(k-1)speed(k-1)"])


@pytest.mark.parametrize("name", ["Σspeedvalve", "Σvalvespeed", "Sspeedvalve", "Σspeed·valve", "Σvalve·speed"])
def test_cluster_bounds_name_a_cluster_by_its_factors_in_any_order(name):
    thetas = []
    for order in ((0, 1), (1, 0)):
        pe = gb.pe_pareto(ST_MISO, _rig(300, 0, order), _grid(order), lambdas=[0.5],
                          constraints=gb.ClusterBounds({name: (None, 1e-6)}))
        thetas.append(pe.thetas[0])
        cl = pe.member_model(0).clusters()
        assert cl["Σspeedvalve" if order == (0, 1) else "Σvalvespeed"] <= 1e-6 * (1 + 1e-6)
    np.testing.assert_allclose(thetas[0], thetas[1], rtol=1e-6, atol=1e-12)  # the terms are the same, by name


def test_a_cluster_name_that_fits_no_cluster_is_still_refused_naming_them():
    from graybox.static._surface_analysis import surface_cluster_map
    cm = surface_cluster_map(ST_MISO, input_names=("speed", "valve"))
    with pytest.raises(ValueError, match="no cluster 'Σspeedvalvey'"):
        cm.index("Σspeedvalvey")
    with pytest.raises(ValueError, match="no cluster"):
        cm.index("Σspeedspeed")


# --- GainBounds: one bound for every input leaves a transient input (no static level) free ------------------------
def _transient_rig():
    """A rig whose speed changes cost output for a while (a transient effect of negative sign), as the bundled
    plant's air loss does, with its transient channel and static points at z̄ = 0."""
    rng = np.random.default_rng(4)
    n = 1200
    a = np.repeat(rng.uniform(-1, 1, n // 25 + 1), 25)[:n]
    u = 1000 + 400 * a
    rec = gb.transient_inputs(gb.Record(u, np.zeros(n), Ts=0.1), taus=[1.0])
    z = rec.input("u_tau1")
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.7 * y[k - 1] + 0.003 * u[k - 1] - 1e-5 * z[k - 1] + 0.01 * rng.standard_normal()
    ub = np.linspace(700.0, 1300.0, 5)
    pts = gb.transient_inputs(gb.StaticPoints(ub, 0.01 * ub, uncertainty=0.02), taus=[1.0])
    return gb.Record(rec.u, y, Ts=0.1, input_names=rec.input_names), pts


def test_one_gain_bound_for_every_input_leaves_a_transient_input_free():
    rec, pts = _transient_rig()
    st = gb.parse_structure(["1", "y(k-1)", "u(k-1)", "u_tau1(k-1)"])
    free = gb.pe_pareto(st, rec, pts, lambdas=[0.5]).thetas[0]
    assert free[3] < 0  # the transient effect lowers the output
    monotone = gb.pe_pareto(st, rec, pts, lambdas=[0.5], constraints=gb.GainBounds(lower=0.0)).thetas[0]
    # a monotone static curve in u (met already) does not ban the transient effect's sign: same fit
    np.testing.assert_allclose(monotone, free, rtol=1e-6)
    # a bound given for the transient input itself still holds
    held = gb.pe_pareto(st, rec, pts, lambdas=[0.5], constraints=gb.GainBounds(lower=[0.0, 0.0])).thetas[0]
    assert held[3] >= -1e-12


def test_a_gain_bounds_box_holds_a_flat_range_at_one_level():
    # GainBounds(ubar_range=[(600, 1400), (20, 80), (0, 0), (0, 0)]) over two inputs and their transient channels
    # (z̄ = 0) made 25⁴ = 390 625 grid points, every one repeated 625 times (29 s for one PE member); three inputs
    # would have made 25⁶
    from graybox.static._surfaces import box_grid
    grid = box_grid([(600.0, 1400.0), (20.0, 80.0), (0.0, 0.0), (0.0, 0.0)], 25)
    assert grid.shape == (625, 4)
    assert len(np.unique(grid, axis=0)) == 625 and np.all(grid[:, 2:] == 0.0)


def test_a_non_finite_input_sample_is_said_of_its_input_by_name():
    # "first at sample 2, input 1" for a NaN in the second column: u2 to whoever counts inputs from 1, as every
    # default name does (u1, u2), u1 to whoever reads the name
    u = np.c_[np.ones(5), [1.0, 2.0, np.nan, 4.0, 5.0]]
    with pytest.raises(ValueError, match=r"sample 2, input 'u2'"):
        gb.Record(u, np.arange(5.0))
    with pytest.raises(ValueError, match=r"sample 2, input 'valve'"):
        gb.Record(u, np.arange(5.0), input_names=("speed", "valve"))
    with pytest.raises(ValueError, match=r"point 1, input 'b'"):
        gb.StaticPoints(np.c_[[1.0, 2.0, 3.0], [1.0, np.nan, 3.0]], np.arange(3.0), input_names=("a", "b"))


def test_a_missing_value_in_a_nullable_input_column_is_said_as_one():
    # pandas' nullable columns (Int64, Float64) hold pd.NA: a Series said "non-finite value at index 2", a
    # DataFrame of several inputs "u must be an array of numbers, got DataFrame" (a TypeError, for a bad value)
    frame = pd.DataFrame({"speed": pd.array([1000, 1100, None, 1200, 1300], dtype="Int64"),
                          "valve": pd.array([10.0, 20.0, 30.0, 40.0, 50.0], dtype="Float64")})
    with pytest.raises(ValueError, match=r"non-finite value.*sample 2, input 'speed'"):
        gb.Record(frame, np.arange(5.0), input_names=("speed", "valve"))
    rec = gb.Record(frame.fillna(1150), np.arange(5.0), input_names=("speed", "valve"))
    np.testing.assert_array_equal(rec.input("speed"), [1000.0, 1100.0, 1150.0, 1200.0, 1300.0])


def test_plot_static_curve_draws_points_of_one_input_and_its_transient_channel():
    # the bundled plant's points after transient_inputs: (ū, z̄ = 0); refused as "several inputs" before
    pts = gb.transient_inputs(gb.StaticPoints(np.linspace(700.0, 1300.0, 5), np.arange(5.0), units=("rpm", "mlc")),
                              taus=[30])
    curve = gb.StaticCurve.fit(gb.StaticPoints(np.linspace(700.0, 1300.0, 5), np.arange(5.0)), 1)
    fig = plots.plot_static_curve(pts, curve)
    ax = fig.axes[0]
    marks = ax.get_lines()[-1]
    np.testing.assert_array_equal(marks.get_xdata(), np.linspace(700.0, 1300.0, 5))
    assert "u" in ax.get_xlabel() and "rpm" in ax.get_xlabel()
    two = _grid()  # two inputs that both vary: still a surface's
    with pytest.raises(ValueError, match="plot_surface_slices"):
        plots.plot_static_curve(two)


def test_a_data_sets_surface_is_told_from_another_of_the_same_coefficients():
    # a grid cell's key holds the data set's fingerprint: two surfaces with the same coefficients on other monomials
    # hashed alike, so a store gave the first surface's CLS cells for the second (curve = "dataset")
    from graybox.experiments._spec import data_fingerprint
    rec, box = _rig(100, 0), ((600.0, 1400.0), (20.0, 80.0))
    a = gb.StaticSurface([(0, 0), (1, 0), (0, 1)], [-0.5, 1e-3, -5e-3], domain=box, input_names=("speed", "valve"))
    b = gb.StaticSurface([(0, 0), (0, 1), (1, 0)], [-0.5, 1e-3, -5e-3], domain=box, input_names=("speed", "valve"))
    assert not np.allclose(a(_grid().ubar), b(_grid().ubar))
    prints = {data_fingerprint(gb.Dataset(rec, rec, _grid(), extra={"static_curve": s})) for s in (a, b)}
    assert len(prints) == 2


def test_operating_points_of_a_model_with_transient_inputs_take_them_at_zero():
    # a one-input plant's model with a transient input: ū given as levels of u, as for a one-input model, has
    # z̄ = 0 (its level at every steady state); [800, 1200] was the one point (u = 800, z̄ = 1200), silently
    model = _transient_model()  # inputs (u, u_tau3)
    levels = np.array([800.0, 1000.0, 1200.0])  # two values (m of them) are refused: levels or a point (review44f)
    full = np.c_[levels, np.zeros(3)]
    np.testing.assert_array_equal(gb.operating_curve(model, levels).ubar, full)
    np.testing.assert_allclose(model.static_gain(levels), model.static_gain(full))
    np.testing.assert_allclose(model.static_curve(levels), model.static_curve(full))
    assert gb.local_model(model, 1200.0).ybar == gb.local_model(model, [1200.0, 0.0]).ybar
    assert model.equilibria(1200.0)[0].ubar == (1200.0, 0.0)
    np.testing.assert_array_equal(gb.narx_steady_state(model, 1200.0, 5.0), gb.narx_steady_state(model, [1200.0, 0.0], 5.0))
    # a full point stays one point; several inputs beside their channels: points of those inputs
    assert len(gb.operating_curve(model, [[1200.0, 0.0]]).ubar) == 1
    st = gb.parse_structure(["1", "y(k-1)", "a(k-1)", "b(k-1)", "a_tau3(k-1)"])
    two = gb.Model(st, np.array([0.1, 0.5, 1.0, 2.0, -0.1]), input_names=("a", "b", "a_tau3"), Ts=1.0)
    np.testing.assert_allclose(two.static_curve([[1.0, 2.0], [0.5, 1.0]]),
                               two.static_curve([[1.0, 2.0, 0.0], [0.5, 1.0, 0.0]]))


def test_decimating_transient_inputs_gives_the_channels_of_the_decimated_record():
    # z(k) = ρ z(k−1) + (1 − ρ)(u(k) − u(k−1))² depends on Ts: the fast record's z kept every q-th sample was about
    # half the z that transient_inputs gives the decimated record (or any new record at that rate) a model meets
    rng = np.random.default_rng(2)
    u = np.repeat(rng.uniform(800, 1600, 40), 50)
    rec = gb.Record(u, np.sin(np.arange(u.size) / 30.0), Ts=0.1, units=("rpm", "mlc"))
    fast = gb.transient_inputs(rec, taus=[3, 2.5])
    slow = gb.decimate(fast, 4)
    again = gb.transient_inputs(gb.decimate(rec, 4), taus=[3, 2.5])
    assert slow.input_names == again.input_names
    np.testing.assert_allclose(slow.u, again.u, rtol=1e-12, atol=0)
    np.testing.assert_array_equal(slow.y, again.y)
    data = gb.transient_inputs(gb.Dataset(rec, rec.slice(0, 1000, name="v"), None), taus=[3])
    np.testing.assert_allclose(gb.decimate(data, 4).ident.u, gb.transient_inputs(gb.decimate(rec, 4), taus=[3]).u)
