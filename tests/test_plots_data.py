"""Pictures of data: Fig. 2 (static curve and points) and Fig. 3 (a record) (issue 3, item 7)."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.figure import Figure

from graybox import Record, reference
from graybox.static._curves import StaticCurve
from graybox.datasets import load_pumping
from graybox.plots import plot_record, plot_static_curve

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _saved(fig: Figure, path) -> bytes:
    fig.savefig(path, dpi=60)
    return path.read_bytes()


def test_fig2_static_curve_with_points(tmp_path):
    ds = load_pumping()
    fig = plot_static_curve(ds.static, ds.extra["static_curve"], xlabel="Pump speed (rpm)", ylabel="Pressure (mlc)")
    assert isinstance(fig, Figure) and len(fig.axes) == 1
    ax = fig.axes[0]
    curve_line, point_line = ax.lines
    assert len(curve_line.get_xdata()) == 200 and curve_line.get_linestyle() == "-"
    np.testing.assert_allclose(curve_line.get_ydata(), reference.eq1(curve_line.get_xdata()))
    assert point_line.get_marker() == "*" and point_line.get_linestyle() == "None"
    np.testing.assert_array_equal(point_line.get_xdata(), ds.static.ubar)
    assert ax.get_xlabel() == "Pump speed (rpm)" and ax.get_ylabel() == "Pressure (mlc)"
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["eq. (1)", "pumping static points"]
    assert _saved(fig, tmp_path / "fig2.png").startswith(PNG_MAGIC)


def test_fig2_variants():
    ds = load_pumping()
    fit = StaticCurve.fit(ds.static, 2)  # its domain is the points' range
    fig = plot_static_curve(ds.static, [ds.extra["static_curve"], fit])
    assert len(fig.axes[0].lines) == 3
    assert len(plot_static_curve(points=ds.static).axes[0].lines) == 1
    free = StaticCurve.polynomial(reference.EQ1_COEFFICIENTS)  # no domain: drawn over the points
    line = plot_static_curve(ds.static, free, margin=0.1).axes[0].lines[0]
    assert line.get_xdata()[0] == pytest.approx(750 - 90) and line.get_xdata()[-1] == pytest.approx(1650 + 90)
    host = Figure()
    ax = host.add_subplot()
    assert plot_static_curve(ds.static, ax=ax) is host


def test_fig2_errors():
    with pytest.raises(ValueError, match="give static points, a curve, or both"):
        plot_static_curve()
    with pytest.raises(ValueError, match="has no domain"):
        plot_static_curve(curve=StaticCurve.polynomial([1.0, 2.0]))


def test_fig3_record(tmp_path):
    ds = load_pumping()
    fig = plot_record(ds.ident, input_label="Pump speed reference", output_label="Pressure")
    assert isinstance(fig, Figure) and len(fig.axes) == 2
    ax_u, ax_y = fig.axes
    assert len(ax_u.lines) == 1 and len(ax_y.lines) == 1
    assert ax_u.lines[0].get_drawstyle() == "steps-post"  # the input is held over each sample
    np.testing.assert_array_equal(ax_y.lines[0].get_ydata(), ds.ident.y)
    np.testing.assert_allclose(ax_y.lines[0].get_xdata()[[0, -1]], [0.0, 3199 * 0.05])
    assert ax_u.get_ylabel() == "Pump speed reference (rpm)" and ax_y.get_ylabel() == "Pressure (mlc)"
    assert ax_y.get_xlabel() == "Time (s)"
    # the defaults name no plant: the units come from the record
    ax_u, ax_y = plot_record(ds.ident).axes
    assert ax_u.get_ylabel() == "input (rpm)" and ax_y.get_ylabel() == "output (mlc)"
    assert ax_u.get_shared_x_axes().joined(ax_u, ax_y)
    assert _saved(fig, tmp_path / "fig3.png").startswith(PNG_MAGIC)


def test_fig3_range_labels_and_axes():
    r = Record(np.arange(10.0), np.arange(10.0) ** 2, Ts=0.5, name="r", units=("", "V"))
    fig = plot_record(r, input_label="duty", output_label="voltage", start=2, stop=6)
    ax_u, ax_y = fig.axes
    np.testing.assert_array_equal(ax_y.lines[0].get_xdata(), [1.0, 1.5, 2.0, 2.5])
    assert ax_u.get_ylabel() == "duty" and ax_y.get_ylabel() == "voltage (V)"
    host = Figure()
    axes = host.subplots(2, 1)
    assert plot_record(r, axes=axes) is host
    with pytest.raises(ValueError, match="start < stop"):
        plot_record(r, start=5, stop=5)
    with pytest.raises(ValueError, match="pair"):
        plot_record(r, axes=[axes[0]])


def test_static_curve_draws_models_beside_the_points():
    # was: plot_static_curve(points, [black, gray]) raised "curve must be a StaticCurve ... got Model", and the README
    # drew each model by hand (ax.plot(ubar, model.static_curve(ubar, strict=False))); plot_surface_slices takes models
    import graybox as gb

    model = gb.Model(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"], [2.0, 0.5, 0.4, -0.001], name="heater")
    pts = gb.StaticPoints([20.0, 40.0, 60.0], model.static_curve([20.0, 40.0, 60.0]) + 0.1, units=("%", "degC"))
    fig = plot_static_curve(pts, [model, StaticCurve.fit(pts, degree=2)], margin=0.1)
    line = fig.axes[0].lines[0]
    assert line.get_label() == "heater"
    x = line.get_xdata()
    assert x[0] == pytest.approx(16.0) and x[-1] == pytest.approx(64.0)  # the points' range widened by margin
    np.testing.assert_allclose(line.get_ydata(), 2 * (2.0 + 0.4 * x - 0.001 * x ** 2), rtol=1e-12)  # ȳ = f(ū)/(1 − 0.5)
    with pytest.raises(ValueError, match="heater.*give points to set the range"):
        plot_static_curve(curve=model)
