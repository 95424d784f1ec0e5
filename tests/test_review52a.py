"""Review 52a: the plots/reports series (number formatters, legends, titles, shared axes, refused output names)."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb


def _first_order_record(n: int = 400, seed: int = 0) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = rng.uniform(1.0, 3.0, n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + 0.1 * u[k - 1] + 0.05 * rng.standard_normal()
    return gb.Record(u, y, Ts=0.1)


@pytest.mark.parametrize("level, said", [(np.float32(0.95), "95%"), (np.float32(0.99), "99%"),
                                         (0.9973002039367398, "99.73%"), (0.95, "95%"), (0.975, "97.5%"),
                                         (0.999, "99.9%"), (0.9973, "99.73%")])
def test_a_confidence_level_prints_as_a_reader_wrote_it(level, said):
    # percent_text printed 100·level to ten digits: a level given as np.float32(0.95) (check_level takes it) read
    # '94.99999881%' in ResidualTests' repr and every band legend where ':.0%' said '95%', and the 3σ level
    # 2Φ(3) − 1 read '99.73002039%'
    from graybox.core._reprs import percent_text
    from graybox.plots import plot_residual_tests

    assert percent_text(level) == said
    m = gb.Model(gb.parse_structure(["y(k-1)", "u(k-1)"]), np.array([0.5, 0.1]), Ts=0.1)
    tests = gb.residual_tests(m, _first_order_record(), level=level, rule="pointwise")
    assert f"pointwise {said};" in repr(tests)
    labels = [t.get_text() for t in plot_residual_tests(tests).axes[0].get_legend().get_texts()]
    assert any(f"({said} pointwise)" in t for t in labels)


@pytest.mark.parametrize("level", [1 - 1e-12, 1 - 1e-15, 1e-12])
def test_a_confidence_level_check_level_takes_never_prints_as_100_or_0(level):
    # a level strictly inside (0, 1) that check_level takes (up to 1 − 2e-16) read '100%' to ten digits: the
    # '100%' band no model has, which percent_text was made to remove
    from graybox.core._reprs import percent_text
    from graybox.core._validation import check_level

    check_level(level)
    text = percent_text(level)
    assert text.endswith("%") and 0.0 < float(text[:-1]) < 100.0


@pytest.mark.parametrize("share, said", [(0.125, "12.5%"), (0.975, "97.5%"), (0.5, "50.0%"), (0.0123, "1.2%"),
                                         (1e-4, "0.01%"), (0.9995, "99.95%"), (0.0, "0%"), (1.0, "100%")])
def test_a_share_prints_as_before_unless_it_reads_none_or_all(share, said):
    # share_text (94be029, meant to keep a share strictly between 0 and 1 off '0.0%' and '100.0%') printed every
    # share to two significant digits: 1 of 8 runs diverged read '12%' and 975 of 1000 draws '98%', where ':.1%'
    # said '12.5%' and '97.5%'
    from graybox.core._reprs import share_text

    assert share_text(share) == said


def test_the_simulation_band_warning_says_an_ordinary_share_as_before():
    from graybox.diagnostics._uncertainty import UncertaintyWarning, warn_dropped_draws

    with pytest.warns(UncertaintyWarning, match=r"up to 12\.5% of the Monte Carlo draws"):
        warn_dropped_draws("static_curve_band", np.array([0.0, 0.125, np.nan]))


def _legends_inside(fig) -> list[bool]:
    fig.savefig(__import__("io").BytesIO(), format="png")
    out = []
    for ax in fig.axes:
        if ax.get_legend() is not None:
            box = ax.bbox  # the panel the legend is drawn in
            lb = ax.get_legend().get_window_extent()
            out.append(bool(lb.y0 >= box.y0 - 1 and lb.y1 <= box.y1 + 1
                            and lb.x0 >= box.x0 - 1 and lb.x1 <= box.x1 + 1))
    return out


@pytest.mark.parametrize("n", [20, 40])
def test_a_surface_band_of_many_slices_keeps_its_legend_inside_its_panel(n):
    # 2ccf186 named at most 20 slices: with the band's own entry that is 21, and the legend of a band of 20 (or 40,
    # one in 2 of them) slices still ran off the bottom of its panel (the promise was a legend that fits)
    from graybox.plots import plot_static_band

    s = gb.parse_structure(["y(k-1)", "u1(k-1)", "u2(k-1)", "1"])
    rng = np.random.default_rng(1)
    u = rng.uniform(1.0, 3.0, (300, 2))
    y = np.zeros(300)
    for k in range(1, 300):
        y[k] = 0.5 * y[k - 1] + 0.2 * u[k - 1, 0] + 0.1 * u[k - 1, 1] + 0.1 + 0.01 * rng.standard_normal()
    rec = gb.Record(u, y, Ts=0.1)
    theta = np.linalg.lstsq(gb.regressor_matrix(s, rec.u, rec.y, start=1, input_names=rec.input_names), y[1:],
                            rcond=None)[0]
    m = gb.Model(s, theta, Ts=0.1)
    g = np.linspace(1.0, 3.0, n)
    band = gb.static_surface_band(gb.ls_uncertainty(m, rec), np.array([(a, b) for a in g for b in g]))
    assert all(_legends_inside(plot_static_band(band)))


@pytest.mark.parametrize("levels, surfaces", [(20, 1), (10, 2), (15, 2), (40, 1), (7, 3)])
def test_slices_of_many_levels_keep_their_legend_inside_their_panel(levels, surfaces):
    # 20 levels (or two surfaces of 10) with their static points: 21 entries, the legend ran off the panel's bottom
    from graybox.plots import plot_surface_slices

    g1, g2 = np.meshgrid(np.linspace(1.0, 3.0, 6), np.linspace(1.0, 2.0, levels))
    ub = np.column_stack([g1.ravel(), g2.ravel()])
    sp = gb.StaticPoints(ub, ub[:, 0] + 0.5 * ub[:, 1] ** 2, name="points")
    fit = gb.StaticSurface.fit(sp, 2, name="fit")
    assert all(_legends_inside(plot_surface_slices([fit] * surfaces, sp)))


@pytest.mark.parametrize("u, said", [(0.1 * 3, "0.3"), (np.arange(0.1, 1.0, 0.1)[6], "0.7"), (10000.01, "10000.01"),
                                     (1000.0, "1000"), (0.5, "0.5"), (1 / 3, "0.3333333333333333")])
def test_a_local_models_point_prints_without_float_noise(u, said):
    # exact_text (484afd8) printed repr() wherever %g did not read back exactly: a local model at an operating point
    # of np.arange(0.1, 1, 0.1) said 'ū = (0.30000000000000004)' and 'ū = (0.7000000000000001)', where %g said 0.3
    # and 0.7, and 0.1 * 3 printed unlike 0.3; the rounding error of the arithmetic that made the point is not a digit
    # a reader wrote
    from graybox.core._reprs import exact_text

    assert exact_text(u) == said
    model = gb.Model(gb.Structure(["y(k-1)", "u(k-1)", "1"]), [0.5, 0.4, 0.05])
    assert repr(gb.local_model(model, u, Ts=1.0)).startswith(f"LocalModel(ū = ({said}), ")


def test_surface_contours_of_points_without_a_name_draw_without_a_legend_warning():
    # 627bd55 made plot_static_curve's legend only when something is named; plot_surface_contours still called
    # legend() for points named '': matplotlib's 'No artists with labels found to put in legend' (an error under the
    # suite's filter, and in any script that turns warnings into errors)
    import warnings

    from graybox.plots import plot_surface_contours

    g1, g2 = np.meshgrid(np.linspace(1.0, 3.0, 4), np.linspace(1.0, 2.0, 3))
    ub = np.column_stack([g1.ravel(), g2.ravel()])
    sp = gb.StaticPoints(ub, ub[:, 0] + 0.5 * ub[:, 1] ** 2, name="")
    fit = gb.StaticSurface.fit(sp, 2, name="fit")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = plot_surface_contours(fit, sp)
    assert fig.axes[0].get_legend() is None
    named = plot_surface_contours(fit, gb.StaticPoints(ub, sp.ybar, name="points"))
    assert [t.get_text() for t in named.axes[0].get_legend().get_texts()] == ["points"]


@pytest.mark.parametrize("factor", [1.0, 1 + 1e-13])
def test_a_dsf_result_on_its_band_prints_the_band_as_written(factor):
    # the D_SF optimum sits on J_SF = B, and 29bd14b says a J_SF within se_dsf's round-off of B at B: with the
    # paper's B = 0.175² (the bundled data's band) bound_text(B, B) found no text on the bound's 'side 0' short of
    # repr, and the repr read 'J_SF=0.030624999999999996, band=0.030624999999999996'
    from graybox.estimation._epsilon_constraint import DSFResult

    m = gb.Model(gb.parse_structure(["y(k-1)", "u(k-1)"]), np.array([0.5, 0.1]))
    band = 0.175**2
    text = repr(DSFResult(m, 1.2, band * factor, band, True, "PE λ1=0.1", 2.0, 0.1, 10, "converged", np.nan))
    assert "J_SF=0.030625, band=0.030625, in_band=True" in text


def test_a_value_at_its_bound_prints_both_as_percent_g():
    from graybox.core._reprs import beside, bound_text

    band = 0.175**2
    assert bound_text(band, band) == "0.030625" and beside(band, band) == "0.030625"
    assert bound_text(band, 0.0306249) == "0.030625" and float(beside(0.0306249, band)) < 0.030625


def test_ends_a_rounding_apart_print_as_the_values_they_are():
    # range_text (1fab8ff) tells ends that print alike apart with level_texts, whose last try was '%.17g': a record's
    # y of 0.3 and 0.1 * 3 read 'y in [0.29999999999999999, 0.30000000000000004]', 0.3 printed as a number below it;
    # the shortest text that reads back (repr) tells any two floats apart and prints 0.3 as 0.3
    from graybox.core._reprs import level_texts, range_text

    assert range_text(0.3, 0.1 * 3) == "[0.3, 0.30000000000000004]"
    assert level_texts(np.array([0.3, 0.1 * 3])) == ["0.3", "0.30000000000000004"]
    rec = gb.Record(np.ones(5), np.r_[np.full(4, 0.3), 0.1 * 3], Ts=1.0)
    assert "y in [0.3, 0.30000000000000004]" in repr(rec)
    assert level_texts(np.array([10000.01, 10000.02])) == ["10000.01", "10000.02"]  # as before
