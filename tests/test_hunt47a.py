"""Bug hunt 47a: plots and reports (figures, leaderboards, the HTML page, the report command)."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

import graybox as gb
from _reports import undrawn_figures
import graybox.experiments as gx

_PUMPING = '''name = "p"
[[data]]
name = "pumping"
bundled = "pumping"
[[structures]]
name = "first-order"
terms = ["y(k-1)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)", "1"]
[[variants]]
name = "LS"
estimator = "ls"
'''


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    path = tmp_path_factory.mktemp("store") / "r.sqlite"
    gx.run_grid(gx.Grid.from_toml_text(_PUMPING), path)
    return path


@pytest.fixture(scope="module")
def earlier_report(store, tmp_path_factory):
    """The folder of a report of ``store`` (written once; the cases below each take a copy)."""
    out = tmp_path_factory.mktemp("earlier") / "rep"
    with pytest.MonkeyPatch.context() as m:
        undrawn_figures(m)  # its files' bytes are compared, not drawn
        gx.write_report(store, out)
    return out


@pytest.mark.parametrize("band, said", [({"pumpin": 1.0}, "pumpin"), (-1.0, "band")])
def test_a_refused_band_leaves_the_reports_folder_as_it_was(store, earlier_report, tmp_path, band, said):
    # write_report wrote cells.csv before the leaderboard refused a band naming no data set: the folder of an earlier
    # report then held a new cells.csv beside the old leaderboard and figures, and a new folder was made for nothing
    out = shutil.copytree(earlier_report, tmp_path / "rep")
    (out / "cells.csv").write_text("an earlier report's cells\n", encoding="utf-8")  # told apart from a new one
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    with pytest.raises(ValueError, match=said):
        gx.write_report(store, out, band=band)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    with pytest.raises(ValueError, match=said):
        gx.write_report(store, tmp_path / "new", band=band)
    assert not (tmp_path / "new").exists()


def _first_order(units=("rpm", "mlc")) -> gb.Model:
    s = gb.parse_structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"])
    return gb.Model(s, np.array([0.9, 2e-4, 1e-8, 0.1]), name="m", Ts=0.05, units=units)


def test_an_operating_curve_of_unsorted_points_is_drawn_in_their_order_along_u():
    # ū given out of order ([1500, 1300, 1700, 1400]) drew the gain and time constant back and forth across the
    # panel, a zigzag of crossing segments, though the curve is one function of ū (plot_static_band sorts its levels)
    from graybox.plots import plot_operating_curve

    m = _first_order()
    ub = [1500.0, 1300.0, 1700.0, 1400.0]
    fig = plot_operating_curve(gb.operating_curve(m, ub))
    ref = plot_operating_curve(gb.operating_curve(m, sorted(ub)))
    for ax, ax_ref in zip(fig.axes, ref.axes):
        x, y = ax.lines[0].get_data()
        assert np.all(np.diff(x) > 0)
        np.testing.assert_allclose(y, ax_ref.lines[0].get_data()[1])


def test_the_operating_curve_figures_say_their_units():
    # the curve carries its model's units (rpm, mlc) but the gain's axis said "gain", ū's "ū", the step response
    # "Δy per unit step" and the Bode magnitude "|G|", all bare: a gain of 0.03 in mlc/rpm or in Pa/(rad/s)?
    from graybox.plots import plot_local_models, plot_operating_curve

    oc = gb.operating_curve(_first_order(), [1300.0, 1500.0])
    fig = plot_operating_curve(oc)
    assert fig.axes[0].get_ylabel() == "gain (mlc/rpm)" and fig.axes[2].get_xlabel() == "ū (rpm)"
    labels = [a.get_ylabel() for a in plot_local_models(oc).axes]
    assert labels[0] == "Δy per unit step (mlc/rpm)" and labels[1] == "|G| (mlc/rpm)"
    bare = gb.operating_curve(_first_order(("", "")), [1300.0, 1500.0])
    assert plot_operating_curve(bare).axes[0].get_ylabel() == "gain"
    assert [a.get_ylabel() for a in plot_local_models(bare).axes][:2] == ["Δy per unit step", "|G|"]


_SELECTION: list = []


def _small_selection():
    """A gray-box selection on data in (V, Pa), with a test record (made once)."""
    import warnings

    if _SELECTION:
        return _SELECTION[0]
    true = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2", "1"])
    theta = np.array([0.6, 0.2, 0.3, 0.05, 0.4])

    def record(seed, n=400):
        rng = np.random.default_rng(seed)
        u = np.repeat(rng.uniform(0.0, 3.0, n // 25 + 1), 25)[:n]
        y = gb.Model(true, theta).simulate(u, np.zeros(2)) + 0.02 * rng.standard_normal(n)
        return gb.Record(u, y, units=("V", "Pa"))

    ub = np.linspace(0.0, 3.0, 7)
    data = gb.Dataset(record(1), record(2), gb.StaticPoints(ub, gb.Model(true, theta).static_curve(ub),
                                                            units=("V", "Pa")))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _SELECTION.append(gb.select_graybox(gb.Candidates(2, 2, ne=0, degree=2), data, band=1e-3, sizes=[3],
                                            test=record(3), estimator=("pe",)))
    return _SELECTION[0]


def test_plot_selection_says_the_unit_of_its_mean_squares():
    # the static and test panels read "(output units²)" though the selection's model carries its data's units, and
    # plot_selection takes no label to say them
    sel = _small_selection()
    labels = [a.get_ylabel() for a in gx.plot_selection(sel).axes]
    assert labels[1:] == ["J_SF of the row's member (Pa²)", "J_S on the test record (Pa²)"]


@pytest.fixture(scope="module")
def empty_store(tmp_path_factory):
    """A store whose run stopped before its first cell finished."""
    path = tmp_path_factory.mktemp("empty") / "e.sqlite"

    def interrupt(line):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        gx.run_grid(gx.Grid.from_toml_text(_PUMPING), path, log=interrupt)
    return path


_LEADERBOARD_COLUMNS = ["rank", "JS_valid", "JS_ident", "JSF", "fit_valid", "n_params", "seed", "lambda1", "in_band",
                        "band", "candidates", "cells", "ok", "reason"]


@pytest.mark.parametrize("rule", ["dsf_valid", "chosen"])
def test_the_leaderboard_of_a_store_without_finished_cells_keeps_its_columns(store, empty_store, rule):
    # it was a frame without index or columns (shape (0, 0)): lb["rank"], lb.loc["pumping"] raised a bare KeyError in
    # code that reads a leaderboard while a grid is starting
    lb = gx.leaderboard(empty_store, rule=rule)
    full = gx.leaderboard(store, rule=rule)
    assert lb.empty and list(lb.columns) == list(full.columns) == _LEADERBOARD_COLUMNS
    assert list(lb.index.names) == list(full.index.names) == ["data", "structure", "variant"]
    assert lb["rank"].dtype == full["rank"].dtype and lb["reason"].tolist() == []


@pytest.mark.parametrize("draw", [gx.plot_scatter, gx.plot_fronts, gx.plot_heatmap, gx.heatmap_table])
def test_the_figures_of_a_store_without_finished_cells_say_so(empty_store, draw):
    # plot_scatter failed in matplotlib ("Number of columns must be a positive integer, not 0"), the others asked to
    # "choose one with data=…" among 0 data sets
    with pytest.raises(ValueError, match="no finished cell"):
        draw(empty_store)


def test_a_heat_map_of_a_figure_a_qualifying_model_lacks_does_not_say_no_model_qualified(store):
    # a heat map of lambda1 (or seed) over least-squares cells, every one ranked, was titled "no model qualified (the
    # leaderboard's reason says why)" and drew "—" (no model) in every cell, while the leaderboard's reasons are empty
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        lb = gx.leaderboard(store, rule="chosen")
        assert lb["rank"].notna().all() and (lb["reason"] == "").all()
        fig = gx.plot_heatmap(store, value="lambda1", rule="chosen")
    ax = fig.axes[0]
    assert "no model qualified" not in " ".join(ax.get_title().split())  # (the title is wrapped)
    assert [t.get_text() for t in ax.texts] == ["n/a"]
    # a group without a qualifying model keeps its dash and the title its reason
    fig = gx.plot_heatmap(store, value="lambda1", band=1e-9)
    assert [t.get_text() for t in fig.axes[0].texts] == ["—"]
    assert "no model qualified" in " ".join(fig.axes[0].get_title().split())


@pytest.mark.parametrize("contours", [False, True])
def test_surface_input_labels_of_any_value_are_drawn_with_their_unit(contours):
    # input_labels are "any values, shown with str()", but with points in units (rpm, mlc) a label such as 1 raised
    # TypeError: argument of type 'int' is not iterable (the unit was looked for inside the label)
    from graybox.plots import plot_surface_contours, plot_surface_slices

    points = gb.load_pumping_miso().static
    if contours:
        fig = plot_surface_contours(lambda U: 0.01 * U[:, 0], points, input_labels=(1, 2))
        assert (fig.axes[0].get_xlabel(), fig.axes[0].get_ylabel()) == ("1 (rpm)", "2 (rpm)")
    else:
        fig = plot_surface_slices(None, points, input_labels=(1, 2))
        assert fig.axes[0].get_xlabel() == "1 (rpm)"


def test_plot_free_run_refuses_an_empty_mapping_of_models():
    # {} drew the measurement alone, without a word: a dictionary of results filtered down to nothing went unnoticed
    # (plot_pareto refuses "nothing to plot" the same way)
    from graybox.plots import plot_free_run

    with pytest.raises(ValueError, match="models"):
        plot_free_run(gb.load_pumping(), {})


def test_plot_pareto_labels_its_axes_with_the_fronts_units():
    # the Pareto sets carry their data's units (rpm, mlc) but the default labels read "J_S (output units²)", as the
    # docs' notebooks drew them; labels given are kept, and sets without units keep the generic ones
    from graybox.plots import plot_pareto

    lam = np.array([0.01, 0.1, 1.0])
    s = gb.parse_structure(["y(k-1)", "u(k-1)", "1"])
    th = np.array([[0.9, 0.01, 0.1]] * 3)
    js, jsf = np.array([1.0, 2.0, 3.0]), np.array([0.3, 0.2, 0.1])

    def front(units):
        return gb.ParetoSet(s, th, lam, js, js, jsf, method="PE", units=units)

    ax = plot_pareto(front(("rpm", "mlc"))).axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("J_S (mlc²)", "J_SF (mlc²)")
    ax = plot_pareto(front(("", ""))).axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("J_S (output units²)", "J_SF (output units²)")
    ax = plot_pareto({"a": front(("rpm", "mlc")), "b": front(("rad/s", "Pa"))}).axes[0]
    assert ax.get_xlabel() == "J_S (output units²)"  # two units: none of them names the axis
    ax = plot_pareto(front(("rpm", "mlc")), xlabel="J_S", ylabel="J_SF").axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("J_S", "J_SF")


def test_plot_free_run_into_a_given_axes_leaves_the_figures_layout_alone():
    # it called tight_layout on the caller's figure: a constrained-layout figure of several panels was switched to
    # the tight layout, with "UserWarning: The figure layout has changed to tight"
    import warnings

    from matplotlib.figure import Figure
    from matplotlib.layout_engine import ConstrainedLayoutEngine

    from graybox.plots import plot_free_run

    s = gb.parse_structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"])
    m = gb.Model(s, np.array([0.9, 2e-4, 1e-8, 0.1]), name="m", Ts=0.05, units=("rpm", "mlc"))
    fig = Figure(layout="constrained")
    axs = fig.subplots(1, 2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert plot_free_run(gb.load_pumping(), m, ax=axs[0]) is fig
    assert isinstance(fig.get_layout_engine(), ConstrainedLayoutEngine)


@pytest.mark.parametrize("column", ["band", "message", "n_params", "terms", "lambda1", "seed", "JS_ident",
                                    "fit_valid"])
@pytest.mark.parametrize("draw", [gx.leaderboard, gx.plot_scatter, gx.plot_fronts, gx.plot_heatmap])
def test_a_results_frame_without_a_column_the_report_reads_is_named(store, column, draw):
    # the frame was checked for seven columns, and one without band, message, n_params, … raised a bare KeyError
    df = gb.load_results(store).drop(columns=column)
    with pytest.raises(ValueError, match=f"graybox.load_results.*{column}"):
        draw(df)


def test_the_fronts_title_says_the_band_is_shaded_only_when_a_panel_shades_it(store):
    # every panel's points above B (the band "below every point"), or no panel with a model, and the title still read
    # "shaded below the dashed line: J_SF ≤ B = …" over panels with no shade and no dashed line
    def title(fig):
        return " ".join(fig.get_suptitle().split())

    far = gx.plot_fronts(store, band=1e-9)  # least squares' J_SF is far above
    assert "shaded" not in title(far) and "J_SF ≤ B = 1e-09" in title(far)
    assert not far.axes[0].patches  # nothing shaded indeed
    near = gx.plot_fronts(store, band=1e6)  # above every point: no shading either
    assert "shaded" not in title(near)
    jsf = float(gb.load_results(store)["JSF"].iloc[0])
    inside = gx.plot_fronts(store, band=jsf * 1.001)  # B between the point and the panel's top: shaded
    assert "shaded below the dashed line" in title(inside) and inside.axes[0].patches


def test_the_html_page_shows_a_missing_value_of_a_text_column_as_missing(store, tmp_path):
    # ranked by each cell's choice, a least-squares row's in_band is missing (no band decided it): the page's table
    # wrote it as the text "<NA>" (or "nan"), where its numeric columns write a dash
    written = {p.name: p for p in gx.write_report(store, tmp_path / "rep", rule="chosen", html=True)}
    page = written["report.html"].read_text(encoding="utf-8")
    assert "&lt;NA&gt;" not in page and ">nan<" not in page and ">None<" not in page


def test_plot_residual_tests_into_given_axes_keeps_a_title_given():
    # with axes given, title= was dropped without a word (the figure's title is set only for a figure it makes);
    # without title the caller's figure keeps its own
    from matplotlib.figure import Figure

    from graybox.plots import plot_residual_tests

    ds = gb.load_pumping()
    m = gb.els(gb.parse_structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)", "1"]), ds).model
    rt = gb.residual_tests(m, ds)
    fig = Figure()
    plot_residual_tests(rt, axes=list(fig.subplots(len(rt.tests), 1)), title="my model")
    assert fig.get_suptitle() == "my model"
    fig = Figure()
    fig.suptitle("theirs")
    plot_residual_tests(rt, axes=list(fig.subplots(len(rt.tests), 1)))
    assert fig.get_suptitle() == "theirs"


@pytest.mark.parametrize("log", [True, False])
def test_plot_pareto_shows_a_band_below_every_member(log):
    # the band B = [0, 0.01] under members with J_SF from 1 to 3 was shaded outside the panel's y range: the legend
    # named a shade the figure did not show
    from graybox.plots import plot_pareto

    s = gb.parse_structure(["y(k-1)", "u(k-1)", "1"])
    ps = gb.ParetoSet(s, np.array([[0.9, 0.01, 0.1]] * 3), np.array([0.01, 0.1, 1.0]), np.ones(3),
                      np.array([1.0, 2.0, 3.0]), np.array([3.0, 2.0, 1.0]), method="PE")
    ax = plot_pareto(ps, band=0.01, log=log).axes[0]
    lo, hi = ax.get_ylim()
    assert lo < 0.01 and hi >= 3.0  # the band's top and every member inside the panel
    assert [p.get_label() for p in ax.patches] == ["B = [0, 0.01]"]


def test_plot_decision_bootstrap_shows_a_band_below_every_replicate():
    # a band [0, B] below every replicate's J_SF was shaded below the panel's y range: the legend named a shade the
    # figure did not show (a band [B_lo, B_hi] was brought in already)
    import dataclasses
    import warnings

    from graybox.plots import plot_decision_bootstrap

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        boot = gb.bootstrap_decision(gb.parse_structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)", "1"]),
                                     gb.load_pumping(), n_boot=4, lambdas=np.logspace(-3, 0, 4))
    low = float(np.nanmin(boot.JSF[boot.ok])) / 100
    ax = plot_decision_bootstrap(dataclasses.replace(boot, band=low)).axes[1]
    assert ax.get_ylim()[0] < low


def test_a_gain_per_compound_input_unit_is_bracketed():
    # a gain in Pa per rad/s was labelled "Pa/rad/s", which reads Pa·s/rad: the input unit is now bracketed
    import warnings

    from graybox.plots import plot_operating_curve, plot_static_band

    oc = gb.operating_curve(_first_order(("rad/s", "Pa")), [1300.0, 1500.0])
    assert plot_operating_curve(oc).axes[0].get_ylabel() == "gain (Pa/(rad/s))"
    s = gb.parse_structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"])
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(1.0, 3.0, 40), 20)
    y = gb.Model(s, np.array([0.8, 0.3, 0.05, 0.1])).simulate(u, np.zeros(1)) + 0.01 * rng.standard_normal(u.size)
    rec = gb.Record(u, y, Ts=0.1, units=("rad/s", "Pa"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = gb.els(s, gb.Dataset(rec, rec)).model
        band = gb.static_curve_band(gb.ls_uncertainty(model, rec), np.linspace(1.0, 3.0, 5))
    assert plot_static_band(band).axes[1].get_ylabel() == "static gain dȳ/dū (Pa/(rad/s))"


def test_plot_selection_refuses_axes_that_are_not_axes_as_a_type_error():
    # axes=[1, 2] (the right count, the wrong type) raised ValueError "axes must hold 2 matplotlib Axes …, got 2
    # items": a wrong type is a TypeError, and the message counted what it had not checked
    sel = _small_selection()
    n = len(gx.plot_selection(sel).axes)
    with pytest.raises(TypeError, match="matplotlib Axes.*int"):
        gx.plot_selection(sel, axes=list(range(n)))
    with pytest.raises(ValueError, match=f"axes must hold {n}"):
        gx.plot_selection(sel, axes=list(range(n + 1)))


def test_a_compound_output_unit_is_bracketed_when_squared_in_reports(tmp_path):
    # an output in m/s (or a flow in m3/h) was squared as "m/s²" (an acceleration) in the summary, the HTML page, the
    # heat map's colour bar, the fronts' and the scatter's axes (the grid status already wrote "(m/s)²")
    ds = gb.load_pumping()
    recs = [gb.Record(r.u, r.y, r.Ts, r.name, units=("rpm", "m/s")) for r in (ds.ident, ds.valid)]
    st = ds.static
    static = gb.StaticPoints(st.ubar, st.ybar, st.name, uncertainty=st.uncertainty, units=("rpm", "m/s"))
    g = gx.Grid.from_toml_text(_PUMPING)
    g = gx.Grid(name="p", data=[gx.DataSpec("pumping", dataset=gb.Dataset(*recs, static))], structures=g.structures,
                variants=g.variants)
    gx.run_grid(g, tmp_path / "r.sqlite")
    written = {p.name: p for p in gx.write_report(tmp_path / "r.sqlite", tmp_path / "rep", html=True)}
    for name in ("summary.txt", "report.html"):
        text = written[name].read_text(encoding="utf-8")
        assert "(m/s)²" in text and "m/s²" not in text.replace("(m/s)²", ""), name
    df = gb.load_results(tmp_path / "r.sqlite")
    labels = [a.get_ylabel() for a in gx.plot_heatmap(df, rule="chosen").axes] + [gx.plot_fronts(df).axes[0].get_ylabel(),
                                                                   gx.plot_scatter(df).axes[0].get_xlabel()]
    assert "JS_valid ((m/s)²)" in labels and labels[-2:] == ["J_SF ((m/s)²)", "J_S on the validation record ((m/s)²)"]
    title = " ".join(gx.plot_fronts(df, band=1e9).get_suptitle().split())
    assert "(m/s)²" in title and "m/s²" not in title.replace("(m/s)²", "")


def test_a_store_given_twice_is_not_compared_with_itself(store, tmp_path):
    # "graybox grid report a.sqlite ./a.sqlite" (a typo for two stores) wrote a report of '1:r vs 2:r': every row twice,
    # ranked against itself, without a word
    import os

    with pytest.raises(ValueError, match="same store"):
        gx.compare_results([store, store])
    os.symlink(store, tmp_path / "again.sqlite")
    with pytest.raises(ValueError, match="same store"):
        gx.leaderboard([store, tmp_path / "again.sqlite"])
