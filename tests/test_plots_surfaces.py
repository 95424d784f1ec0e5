"""Pictures of static surfaces: slices and contours with static points (issue 15)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib.figure import Figure

from graybox import StaticPoints
from graybox.static._surfaces import StaticSurface
from graybox.datasets import TwoSpeedPumpingPlant
from graybox.datasets._pumping_miso import static_grid
from graybox.plots import plot_surface_contours, plot_surface_slices

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
PLANT = TwoSpeedPumpingPlant()


def theory(U):
    return PLANT.static_pressure(U[:, 0], U[:, 1])


theory.name = "theoretical surface"


def _grid_points():
    U = static_grid()
    return StaticPoints(U, theory(U) + 0.01, name="grid")


def test_slices_draw_one_line_per_level_and_surface_with_the_points(tmp_path):
    pts = _grid_points()
    fit = StaticSurface.fit(pts, 2)
    fig = plot_surface_slices([theory, fit], pts)
    ax = fig.axes[0]
    lines, markers = ax.lines[:12], ax.lines[12:]
    assert len(ax.lines) == 12 + 6  # 2 surfaces x 6 levels of u2, then the points of each level
    x = lines[0].get_xdata()
    assert x[0] == 1150 and x[-1] == 1650 and len(x) == 100
    np.testing.assert_allclose(lines[0].get_ydata(), PLANT.static_pressure(x, 1150.0))
    np.testing.assert_allclose(lines[6 + 5].get_ydata(), fit(np.c_[x, np.full(100, 1650.0)]))
    assert lines[0].get_linestyle() == "-" and lines[6].get_linestyle() == "--"
    assert lines[0].get_color() == lines[6].get_color() == markers[0].get_color()
    np.testing.assert_array_equal(np.sort(markers[2].get_xdata()), static_grid()[:6, 1])
    np.testing.assert_allclose(markers[2].get_ydata(), PLANT.static_pressure(markers[2].get_xdata(), 1350.0) + 0.01)
    assert ax.get_xlabel() == "input u1"  # the points' input name; the defaults name no unit
    fig.savefig(tmp_path / "s.png", dpi=50)
    assert (tmp_path / "s.png").read_bytes().startswith(PNG_MAGIC)


def test_the_points_of_a_level_are_found_in_any_units():
    # "on the level" had an absolute floor (1e-9 × max(|level|, 1)): with the inputs in units of 1e-12
    # (levels 1e-10 apart) every point was drawn on every level
    U = static_grid() * 1e-12
    pts = StaticPoints(U, theory(static_grid()), name="grid")
    fig = plot_surface_slices(StaticSurface.fit(pts, 2), pts)
    markers = fig.axes[0].lines[6:]
    assert len(markers) == 6 and all(m.get_xdata().size == 6 for m in markers)
    np.testing.assert_array_equal(np.sort(markers[2].get_xdata()), U[:6, 1])


def test_slices_against_the_second_input_at_chosen_levels():
    fit = StaticSurface.fit(_grid_points(), 2)
    fig = plot_surface_slices(fit, against=1, at=[1200.0, 1600.0], n_grid=11)
    ax = fig.axes[0]
    assert len(ax.lines) == 2 and ax.get_xlabel() == "input u2"  # the surface's own input name
    x = ax.lines[1].get_xdata()
    np.testing.assert_allclose(ax.lines[1].get_ydata(), fit(np.c_[np.full(11, 1600.0), x]))
    assert x[0] == 1150 and x[-1] == 1650  # the fit's domain


def test_contours_with_points(tmp_path):
    pts = _grid_points()
    fig = plot_surface_contours(theory, pts, levels=8, n_grid=30)
    assert isinstance(fig, Figure) and len(fig.axes) == 2  # the map and its colour bar
    ax = fig.axes[0]
    (scatter,) = ax.collections[-1:]
    np.testing.assert_array_equal(scatter.get_offsets(), pts.ubar)
    np.testing.assert_allclose(scatter.get_array(), pts.ybar)
    assert ax.get_title() == "theoretical surface"
    fig.savefig(tmp_path / "c.png", dpi=50)
    assert (tmp_path / "c.png").read_bytes().startswith(PNG_MAGIC)
    host = Figure()
    a = host.add_subplot()
    assert plot_surface_contours(StaticSurface.fit(pts, 2), ax=a) is host


def test_surface_plot_errors():
    with pytest.raises(ValueError, match="give a surface, static points, or both"):
        plot_surface_slices()
    with pytest.raises(ValueError, match="no range for input 2"):
        plot_surface_slices(theory)
    with pytest.raises(ValueError, match=r"against \(the input on the horizontal axis\) must be an integer <= 1"):
        plot_surface_slices(theory, _grid_points(), against=2)
    with pytest.raises(ValueError, match=r"ubar of shape \(K, 2\)"):
        plot_surface_slices(theory, SimpleNamespace(ubar=np.ones(3), ybar=np.ones(3)))
    with pytest.raises(ValueError, match="one surface"):
        plot_surface_contours([theory, theory], _grid_points())
    with pytest.raises(ValueError, match="returned shape"):
        plot_surface_contours(lambda U: np.ones(3), _grid_points())


def test_record_with_two_inputs_has_a_line_and_a_legend_entry_per_input():
    from graybox.datasets import load_pumping_miso
    from graybox.plots import plot_record

    rec = load_pumping_miso().valid
    fig = plot_record(rec, stop=300)
    ax_u = fig.axes[0]
    assert len(ax_u.lines) == 2
    assert [t.get_text() for t in ax_u.get_legend().get_texts()] == ["u1", "u2"]
    np.testing.assert_array_equal(ax_u.lines[1].get_ydata()[:300], rec.u[:300, 1])


def test_surface_plots_label_their_axes_by_the_points_input_names():
    """The surface plots labelled their inputs "input ū₁/ū₂" whatever the points named them (plot_static_band uses
    the names); a pair given keeps its place, and a surface without points or names keeps ū₁ and ū₂."""
    pts = StaticPoints([[1.0, 1.0], [2.0, 1.0], [1.0, 2.0], [2.0, 2.0]], [1.0, 2.0, 3.0, 4.0],
                          input_names=("speed", "valve"), units=("rpm", "mlc"))
    ax = plot_surface_slices(None, pts).axes[0]
    assert ax.get_xlabel() == "input speed (rpm)"
    assert plot_surface_slices(None, pts, against=1).axes[0].get_xlabel() == "input valve (rpm)"
    fig = plot_surface_contours(lambda U: U[:, 0] + U[:, 1], pts)
    assert (fig.axes[0].get_xlabel(), fig.axes[0].get_ylabel()) == ("input speed (rpm)", "input valve (rpm)")
    fig = plot_surface_contours(lambda U: U[:, 0] + U[:, 1], pts, input_labels=("a", "b"))
    assert (fig.axes[0].get_xlabel(), fig.axes[0].get_ylabel()) == ("a (rpm)", "b (rpm)")
    bare = plot_surface_slices(lambda U: U[:, 0], None, urange=(0.0, 1.0), at=[0.0, 1.0]).axes[0]
    assert bare.get_xlabel() == "input ū₁"


def test_slices_refuse_a_bad_label_pair_before_reading_the_surfaces():
    """A bad input_labels was reported after a surface/points mismatch (review51i): the pair is named first."""
    pts = StaticPoints([[1.0, 1.0], [2.0, 1.0], [1.0, 2.0], [2.0, 2.0]], [1.0, 2.0, 3.0, 4.0],
                       input_names=("speed", "valve"))
    class Other:  # a surface of other inputs than the points'
        input_names, domain, name = ("a", "b"), None, "other"

        def __call__(self, U):
            return U[:, 0]

    other = Other()
    with pytest.raises(ValueError, match="a surface in the inputs"):  # the mismatch alone is still named
        plot_surface_slices(other, pts)
    with pytest.raises(ValueError, match="input_labels must be a pair"):
        plot_surface_slices(other, pts, input_labels=("x",))


def test_slices_take_a_model_as_its_static_surface_and_the_input_on_the_axis_by_name():
    # was: plot_surface_slices(model, points) raised "surface must be a callable ... got Model" (a model's surface had
    # to be passed as model.static_curve), and against="inlet" "must be an integer", where plot_static_band takes
    # against by name
    from graybox import Model

    model = Model(["1", "y(k-1)", "flow(k-1)", "inlet(k-1)", "flow(k-1)inlet(k-1)"], [0.5, 0.5, 0.2, 0.3, 0.01],
                  name="tank", input_names=("flow", "inlet"))
    U = np.array([[2.0, 10.0], [2.0, 30.0], [6.0, 10.0], [6.0, 30.0]])
    pts = StaticPoints(U, model.static_curve(U), input_names=("flow", "inlet"), units=("", "degC"))
    by_name = plot_surface_slices(model, pts, against="inlet")
    by_position = plot_surface_slices(model.static_curve, pts, against=1)
    for a, b in zip(by_name.axes[0].get_lines(), by_position.axes[0].get_lines()):
        np.testing.assert_allclose(a.get_xydata(), b.get_xydata(), rtol=1e-12)
    assert by_name.axes[0].get_xlabel() == "input inlet"
    legend = plot_surface_slices([model, model.static_curve], pts).axes[0].get_legend().get_texts()
    assert legend[0].get_text().startswith("tank, input inlet = ")
    with pytest.raises(ValueError, match=r"against='speed' names no input of \('flow', 'inlet'\)"):
        plot_surface_slices(model, pts, against="speed")
    one = Model(["y(k-1)", "u(k-1)"], [0.5, 1.0], name="one input")
    with pytest.raises(ValueError, match="one input has no surface"):
        plot_surface_slices(one, pts)
