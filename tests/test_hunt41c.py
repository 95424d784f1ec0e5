"""hunt41c: bugs found in static_surface_band, plot_static_band, the QP's equality elimination, static settling,
decimation_advice, design_input and gb.save/gb.load; each test failed before its fix."""

from __future__ import annotations

import json

import numpy as np
import pytest

import graybox as gb
from conftest import edited_file


MISO = ["y(k-1)", "y(k-2)", "u1(k-1)", "u2(k-1)", "u1(k-1)y(k-1)", "u1(k-1)u2(k-1)", "u2(k-1)^2", "1"]


@pytest.fixture(scope="module")
def surface_band():
    d = gb.load_pumping_miso()
    unc = gb.ls_uncertainty(gb.els(MISO, d.ident, noise=0).model, d.ident)
    return gb.static_surface_band(unc, np.array([[1250.0, 1300.0], [1400.0, 1400.0]]))


def test_a_surface_band_refuses_an_input_named_twice(surface_band, tmp_path):
    # to_frame's columns 'gain u1 …' of the first input were overwritten by the second's without a word
    b = surface_band
    with pytest.raises(ValueError, match="named twice"):
        type(b)(b.ubar, ("u1", "u1"), b.ybar, b.ybar_low, b.ybar_high, b.ybar_std, b.gain, b.gain_low,
                b.gain_high, b.gain_std, b.level, b.method, b.n_samples, b.undefined)
    p = tmp_path / "band.json"
    gb.save(b, p)
    j = json.loads(p.read_text())
    for bad in (["u1", "u1"], ["", "u2"]):
        j["object"]["input_names"] = bad
        p.write_text(json.dumps(j))
        with pytest.raises(gb.GrayboxFileError, match="input_names"):
            gb.load(p)


def test_plot_static_band_puts_points_on_their_slice_whatever_each_input_unit():
    # the slice tolerance took 1e-9 of the largest held input's size: with u2 in a unit 1e3 smaller and u3 in one
    # 1e6 larger, the tolerance in u3 (levels 5e-7 and 1.5e-6) was 1.5e-6 and every point lay on every slice
    from graybox import plots

    rng = np.random.default_rng(0)
    st, names = ["y(k-1)", "u1(k-1)", "u2(k-1)", "u3(k-1)", "1"], ("u1", "u2", "u3")
    k = np.array([1.0, 1e3, 1e-6])
    U = np.column_stack([np.repeat(rng.uniform(0, 2, 30), 20) for _ in range(3)])
    y = gb.Model(st, [0.5, 0.2, 0.3, 0.1, 1.0], input_names=names).simulate(U, np.zeros(1))
    rec = gb.Record(U * k, y + 0.01 * rng.standard_normal(y.size), Ts=1.0, input_names=names)
    unc = gb.ls_uncertainty(gb.els(st, rec, noise=0).model, rec)
    lv = np.array([[a, b, c] for c in (0.5, 1.5) for b in (0.5, 1.5) for a in np.linspace(0, 2, 5)]) * k
    band = gb.static_surface_band(unc, lv)
    pu = np.array([[a, b, c] for c in (0.5, 1.5) for b in (0.5, 1.5) for a in (0.5, 1.0)]) * k
    pts = gb.StaticPoints(pu, np.arange(8.0), input_names=names)
    ax = plots.plot_static_band(band, pts, against="u1", gain=False).axes[0]
    stars = [ln for ln in ax.get_lines() if ln.get_marker() == "*"]
    assert len(stars) == 4 and [len(s.get_xdata()) for s in stars] == [2, 2, 2, 2]
    for s in stars:  # each slice's points are the two at its levels of u2 and u3, in the band's order
        assert len({float(v) for v in s.get_ydata() // 2}) == 1


TRUE = gb.Structure(["y(k-1)", "y(k-1)u(k-1)", "u(k-1)", "u(k-1)^2", "1"])
THETA = np.array([0.5, 0.15, 0.3, -0.05, 0.2])
UB = np.linspace(0.25, 1.75, 7)


def _rational(u_offset: float = 0.0, y_scale: float = 1.0, y_offset: float = 0.0, n: int = 400):
    rng = np.random.default_rng(1)
    u = np.repeat(rng.uniform(0.0, 2.0, n // 20 + 1), 20)[:n]
    y = gb.Model(TRUE, THETA).simulate(u, np.zeros(1)) + 0.02 * rng.standard_normal(n)
    pts = gb.StaticPoints(UB + u_offset, y_scale * gb.Model(TRUE, THETA).static_curve(UB) + y_offset)
    return gb.Record(u + u_offset, y * y_scale + y_offset), gb.StaticCurve.fit(pts, degree=2)


@pytest.mark.parametrize("bound", [(0.0, None), (None, 0.0)])
def test_a_bound_the_curve_equality_meets_exactly_is_kept_at_an_output_offset(bound):
    # eq. (22) sets Σyu = 0; a bound on it the equalities leave constant was judged against 1e-9 of the output's
    # spread while its slack carried the round-off of z_p's size: an output of 2e9 ± 50 with u = 1000 ± 1 read
    # 0 <= -1.1e-07 and cls raised InfeasibleError
    rec, curve = _rational(1e3, 100.0, 2e9)
    m = gb.cls(TRUE, rec, curve, constraints=[gb.ClusterBounds({"Σyu": bound})]).model
    free = gb.cls(TRUE, rec, curve).model
    np.testing.assert_allclose(m.static_curve(UB + 1e3), curve(UB + 1e3), rtol=1e-9)
    np.testing.assert_allclose(m.theta, free.theta, rtol=1e-6, atol=1e-9)
    with pytest.raises(gb.InfeasibleError, match="Σyu"):  # one it misses is still refused
        gb.cls(TRUE, rec, curve, constraints=[gb.ClusterBounds({"Σyu": (1e-6, None)})])


def test_a_surface_band_whose_gain_band_is_crossed_is_refused_naming_the_entry(surface_band, tmp_path):
    # check_band_values indexed the (M, m) gains with a flat index: IndexError 'index 2 is out of bounds' from a
    # hand-edited file (and from the constructor) instead of the ValueError naming the entry
    b = surface_band
    low = b.gain_low.copy()
    low[1, 0] = b.gain_high[1, 0] + 1.0
    with pytest.raises(ValueError, match=r"gain_low must not exceed gain_high, .* at index \(1, 0\)"):
        type(b)(b.ubar, b.input_names, b.ybar, b.ybar_low, b.ybar_high, b.ybar_std, b.gain, low, b.gain_high,
                b.gain_std, b.level, b.method, b.n_samples, b.undefined)
    std = b.gain_std.copy()
    std[1, 1] = -1.0
    with pytest.raises(ValueError, match=r"gain_std must be >= 0 .* at index \(1, 1\)"):
        type(b)(b.ubar, b.input_names, b.ybar, b.ybar_low, b.ybar_high, b.ybar_std, b.gain, b.gain_low,
                b.gain_high, std, b.level, b.method, b.n_samples, b.undefined)
    p = edited_file(b, tmp_path / "band.json", lambda o: o["gain_low"][1].__setitem__(0, 1e308))
    with pytest.raises(gb.GrayboxFileError, match="gain_low must not exceed gain_high"):
        gb.load(p)


def test_a_hand_edited_cov_factor_that_overflows_is_refused_without_a_warning(tmp_path):
    # FᵀF of a factor entry of 1e308 overflowed with numpy's RuntimeWarning before the file was refused
    d = gb.load_pumping()
    st = ["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)y(k-1)", "u(k-1)^2", "1"]
    unc = gb.ls_uncertainty(gb.els(st, d.ident, noise=0).model, d.ident)
    p = edited_file(unc, tmp_path / "unc.json", lambda o: o["cov_factor"][0].__setitem__(0, 1e308))
    with pytest.raises(gb.GrayboxFileError, match="cov_factor F is not a factor of cov"):
        gb.load(p)


def test_plot_static_band_draws_a_curve_band_in_the_order_of_its_levels():
    # a curve band of levels given unsorted was drawn in their given order (a line back and forth, the band filled
    # between crossing segments), where a surface band's slices are sorted
    from graybox import plots

    d = gb.load_pumping()
    st = ["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)y(k-1)", "u(k-1)^2", "1"]
    unc = gb.ls_uncertainty(gb.els(st, d.ident, noise=0).model, d.ident)
    levels = np.array([1600.0, 800.0, 1200.0, 1000.0])
    band = gb.static_curve_band(unc, levels)
    fig = plots.plot_static_band(band)
    for ax in fig.axes:
        line = [ln for ln in ax.get_lines() if ln.get_linestyle() == "-"][0]
        np.testing.assert_array_equal(line.get_xdata(), np.sort(levels))
    order = np.argsort(levels)
    np.testing.assert_array_equal(fig.axes[0].get_lines()[0].get_ydata(), band.ybar[order])
    np.testing.assert_array_equal(fig.axes[1].get_lines()[0].get_ydata(), band.gain[order])
    shade = fig.axes[0].collections[0].get_paths()[0].vertices[:, 0]  # the fill's outline, in x
    assert np.all(np.diff(shade[1:len(levels) + 1]) >= 0)


@pytest.fixture(scope="module")
def selection():
    import warnings

    true, theta = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2", "1"]), np.array([0.6, 0.2, 0.3, 0.05, 0.4])

    def plant(seed, n=1200):
        rng = np.random.default_rng(seed)
        u = np.repeat(rng.uniform(0.0, 3.0, n // 25 + 1), 25)[:n]
        y = gb.Model(true, theta).simulate(u, np.zeros(2)) + 0.02 * rng.standard_normal(n)
        return gb.Record(u, y, name=f"r{seed}")

    ub = np.linspace(0.2, 2.8, 7)
    data = gb.Dataset(plant(1), plant(2), gb.StaticPoints(ub, gb.Model(true, theta).static_curve(ub)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gb.select_graybox(gb.Candidates(3, 3, ne=0, degree=2), data, band=1e-3, sizes=[3, 5], test=plant(3))


def test_a_selection_table_with_a_negative_mean_square_is_refused(selection, tmp_path):
    # a hand-edited JS_test of -1 loaded, and regret was then -0.0004 (a J_S is a mean square)
    def edit(o):
        t = o["table"]
        t["data"][t["columns"].index("JS_test")][1] = -1.0

    p = edited_file(selection, tmp_path / "sel.json", edit)
    with pytest.raises(gb.GrayboxFileError, match="JS_test must be >= 0"):
        gb.load(p)


def test_regret_and_optimism_where_a_test_record_is_met_exactly(selection):
    # a J_S test of 0 (a noise-free test record met exactly) divided by zero: RuntimeWarning, and inf or NaN
    import dataclasses

    t = selection.table.copy()
    chosen = np.flatnonzero(t["rank"].to_numpy() == 1)[0]
    other = np.flatnonzero((t["rank"].to_numpy() != 1) & t["in_band"].to_numpy(bool))[0]  # a row regret compares
    js = t["JS_test"].to_numpy(float).copy()
    js[other] = 0.0
    t["JS_test"] = js
    assert dataclasses.replace(selection, table=t).regret == np.inf
    js[chosen] = 0.0
    t["JS_test"] = js
    s = dataclasses.replace(selection, table=t)
    assert s.regret == 1.0 and s.optimism == np.inf
    assert "regret=1" in repr(s)


def test_slices_of_an_offset_input_are_told_apart_in_the_legend():
    # levels 10000.01 and 10000.02 of the held input were both labelled 'u2 = 10000' (%g's six digits): in a unit
    # with an offset, the slices' legend could not say which line is which; at 0.01 and 0.02 it could
    from graybox import plots

    rng = np.random.default_rng(0)
    st, names = ["y(k-1)", "u1(k-1)", "u2(k-1)", "1"], ("u1", "u2")
    U = np.column_stack([np.repeat(rng.uniform(0, 1, 30), 20), 1e4 + np.repeat(rng.uniform(0, 0.05, 30), 20)])
    y = gb.Model(st, [0.5, 0.2, 3.0, -3e4], input_names=names).simulate(U, np.zeros(1))
    rec = gb.Record(U, y + 1e-3 * rng.standard_normal(y.size), Ts=1.0, input_names=names)
    unc = gb.ls_uncertainty(gb.els(st, rec, noise=0).model, rec)
    pts = np.array([[a, b] for b in (1e4 + 0.01, 1e4 + 0.02) for a in (0.2, 0.5, 0.8)])
    band = gb.static_surface_band(unc, pts)
    ax = plots.plot_static_band(band, against="u1", gain=False).axes[0]
    labels = [ln.get_label() for ln in ax.get_lines() if ln.get_linestyle() == "-"]
    assert len(labels) == 2 and labels[0] != labels[1]
    assert labels[0].endswith("(u2 = 10000.01)") and labels[1].endswith("(u2 = 10000.02)")
    fig = plots.plot_surface_slices(lambda u: u[:, 0] + u[:, 1], against=0, at=[1e4 + 0.01, 1e4 + 0.02],
                                    urange=(0.0, 1.0), input_labels=("u1", "u2"))
    assert [ln.get_label() for ln in fig.axes[0].get_lines()] == ["u2 = 10000.01", "u2 = 10000.02"]


def test_a_band_with_a_point_no_draw_reached_says_its_width_over_the_others():
    # a Monte Carlo band has NaN ends where no draw reached an equilibrium; one such point made the repr 'max ±nan'
    ub, g = np.array([[0.0, 1.0], [1.0, 1.0]]), np.ones((2, 2))
    low, std = np.array([np.nan, 0.5]), np.array([np.nan, 0.5])
    nan_at_0 = g * np.array([[np.nan], [1.0]])  # the gains' band is NaN where the ȳ band is: no draw kept there
    b = gb.StaticSurfaceBand(ub, ("u1", "u2"), np.array([1.0, 1.0]), low, low + 1.0, std, g, nan_at_0,
                             nan_at_0, nan_at_0 * 0, 0.95, "monte-carlo", 100, np.array([1.0, 0.0]))
    assert "max ±0.5 in ȳ" in repr(b)
    c = gb.StaticCurveBand(ub[:, 0], b.ybar, low, low + 1.0, std, g[:, 0], g[:, 0], g[:, 0], g[:, 0] * 0, 0.95,
                           "monte-carlo", 100, np.array([1.0, 0.0]))
    assert "max ±0.5 in ȳ" in repr(c)
    none = gb.StaticCurveBand(ub[:, 0], b.ybar, low * np.nan, low * np.nan, std, g[:, 0], g[:, 0], g[:, 0],
                              g[:, 0] * 0, 0.95, "monte-carlo", 100, np.ones(2))
    assert "no band" in repr(none)


def test_a_point_off_the_curve_beside_eq22_with_a_free_sigma_y_is_said_to_conflict():
    # the constraints admit only Σ_y = 1 (numerator and denominator both zero); the error told the user to fix Σ*_y
    # from a reference model, not that a point to pass through lies off the curve
    rec, curve = _rational()
    off_curve = gb.StaticPoints([1.0], [float(curve(np.array([1.0]))[0]) + 0.1])
    with pytest.raises(ValueError, match="off the curve"):
        gb.cls(TRUE, rec, curve, constraints=[gb.PassesThrough(off_curve)])
