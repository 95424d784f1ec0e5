"""Bug hunt 51a: plots and reports (figures, leaderboards, the texts results print)."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

import graybox as gb
from _reports import undrawn_figures


def _first_order_record(n: int = 400, seed: int = 0) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = rng.uniform(1.0, 3.0, n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + 0.1 * u[k - 1] + 0.05 * rng.standard_normal()
    return gb.Record(u, y, Ts=0.1)


def test_residual_tests_of_one_test_are_drawn():
    # a ResidualTests holding one test (it takes any non-empty set: a file, dataclasses.replace) failed to draw with
    # "'Axes' object is not iterable": fig.subplots(1, 1) gives one Axes, not an array of them
    from graybox.plots import plot_residual_tests

    m = gb.Model(gb.parse_structure(["y(k-1)", "u(k-1)"]), np.array([0.5, 0.1]), Ts=0.1)
    tests = gb.residual_tests(m, _first_order_record())
    one = dataclasses.replace(tests, tests={"xi_xi": tests.tests["xi_xi"]})
    fig = plot_residual_tests(one)
    (ax,) = fig.axes
    assert ax.get_title(loc="left").startswith(tests.tests["xi_xi"].label)


def _bootstrap(reference: dict):
    from graybox.diagnostics._bootstrap import DecisionBootstrap

    s = gb.parse_structure(["y(k-1)", "u(k-1)"])
    lam1 = np.array([0.5, 0.5, 1.0])
    return DecisionBootstrap(s, "pe", np.array([0.1, 0.5, 1.0]), 0.05, 10, 5, 0, lam1, np.array([1.0, 2.0, 1.5]),
                             np.array([0.01, 0.02, 0.03]), np.ones(3, bool), np.ones((3, 2)), ("D_SF",) * 3,
                             reference, {})


@pytest.mark.parametrize("js, jsf, said", [(np.inf, 0.2, "J_S = inf"), (1.0, 0.0, "J_SF = 0 on a log axis")])
def test_a_bootstrap_reference_the_log_axes_cannot_show_is_not_named_as_drawn(js, jsf, said):
    # the reference decision with J_S = inf (the min_jsf fallback takes a member whose free run diverged) was
    # "drawn" at inf: the legend named 'original data' with no star in the panel (a J_SF of 0 left it out unsaid)
    from graybox.plots import plot_decision_bootstrap

    ref = dict(lambda1=0.5, JS=js, JSF=jsf, in_band=False, rule="min J_SF", theta=[1.0, 1.0])
    fig = plot_decision_bootstrap(_bootstrap(ref))
    ax = fig.axes[1]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert f"original data (not drawn: {said})" in labels
    assert "original data" not in labels
    stars = [ln for ln in ax.lines if ln.get_marker() == "*"]
    assert all(ln.get_xdata().size == 0 for ln in stars)


def test_a_bootstrap_reference_drawn_is_named_plainly():
    from graybox.plots import plot_decision_bootstrap

    ref = dict(lambda1=0.5, JS=1.2, JSF=0.015, in_band=True, rule="D_SF", theta=[1.0, 1.0])
    ax = plot_decision_bootstrap(_bootstrap(ref)).axes[1]
    assert "original data" in [t.get_text() for t in ax.get_legend().get_texts()]
    (star,) = [ln for ln in ax.lines if ln.get_marker() == "*"]
    assert list(star.get_xdata()) == [1.2] and list(star.get_ydata()) == [0.015]


_GRID = '''name = "p"
[[data]]
name = "pumping"
bundled = "pumping"
[[structures]]
name = "first-order"
terms = ["y(k-1)", "u(k-1)", "u(k-1)^2", "1"]
[[variants]]
name = "LS"
estimator = "ls"
'''


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    import graybox.experiments as gx

    path = tmp_path_factory.mktemp("store") / "r.sqlite"
    gx.run_grid(gx.Grid.from_toml_text(_GRID), path)
    return path


def test_write_report_refuses_an_empty_folder_name(store, tmp_path, monkeypatch):
    # write_report(store, "") (an unset variable, out=os.environ.get("OUT", "")) wrote the report into the current
    # folder, which nobody named (and its manifest then removes files an earlier report there listed)
    import graybox.experiments as gx

    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError, match="out is empty"):
        gx.write_report(store, "")
    with pytest.raises(TypeError, match="out must be a file or folder name"):
        gx.write_report(store, 5)
    assert list(tmp_path.iterdir()) == []


def test_grid_report_refuses_an_empty_out(store, tmp_path, monkeypatch, capsys):
    # graybox grid report r.sqlite --out "$DIR" with DIR unset wrote the report into the current folder (exit 0),
    # as graybox reproduce --out '' did before 8bcb032
    from graybox._cli import main

    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exc:
        main(["grid", "report", str(store), "--out", ""])
    assert exc.value.code == 2
    assert "--out" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def _legend(ax) -> list[str]:
    return [t.get_text() for t in ax.get_legend().get_texts()]


def test_a_name_with_a_leading_underscore_is_named_in_the_legend():
    # matplotlib leaves a label starting with "_" out of the legend: a model named "_base" (a mapping's key, a
    # Model's name) was drawn as a line the legend did not name, and a front or point so named likewise
    from graybox.plots import plot_free_run, plot_pareto, plot_static_curve

    rec = _first_order_record()
    m = gb.Model(gb.parse_structure(["y(k-1)", "u(k-1)"]), np.array([0.5, 0.1]), Ts=0.1, name="_tuned")
    assert _legend(plot_free_run(rec, {"_base": m, "other": m}).axes[0]) == ["measured", " _base", "other"]
    assert _legend(plot_free_run(rec, m).axes[0]) == ["measured", " _tuned"]
    s = gb.parse_structure(["y(k-1)", "u(k-1)"])
    ps = gb.ParetoSet(s, np.ones((2, 2)), np.array([0.1, 1.0]), np.ones(2), np.array([1.0, 2.0]),
                      np.array([0.2, 0.1]), "PE")
    assert _legend(plot_pareto({"_front": ps}, {"_ELS": (1.5, 0.3)}).axes[0]) == [" _front", " _ELS"]
    pts = gb.StaticPoints(np.array([1.0, 2.0, 3.0]), np.array([0.2, 0.4, 0.6]), name="_points")
    curve = gb.StaticCurve.fit(pts, 1, name="_curve")
    assert _legend(plot_static_curve(pts, curve).axes[0]) == [" _curve", " _points"]


def test_an_empty_front_says_so_in_the_legend():
    # a ParetoSet of no member (ps.subset([]), ps.nondominated() of a set whose members all failed) was named in the
    # legend as any drawn front ('PE'), with a marker and no point anywhere; a set of failed members says why
    from graybox.plots import plot_pareto

    s = gb.parse_structure(["y(k-1)", "u(k-1)"])
    ps = gb.ParetoSet(s, np.ones((2, 2)), np.array([0.1, 1.0]), np.ones(2), np.array([1.0, 2.0]),
                      np.array([0.2, 0.1]), "PE")
    empty = ps.subset([])
    assert _legend(plot_pareto(empty).axes[0]) == ["PE (no members)"]
    assert _legend(plot_pareto({"a": ps, "b": empty}, log=False).axes[0]) == ["a", "b (no members)"]
    assert _legend(plot_pareto(ps).axes[0]) == ["PE"]


def test_local_models_of_several_inputs_name_the_input_stepped():
    # plot_local_models(curve, input=1) and input=0 drew two different responses under the same labels ('Δy per
    # unit step', '|G|'): nothing in the figure said which input was stepped
    from graybox.plots import plot_local_models

    s = gb.parse_structure(["y(k-1)", "u1(k-1)", "n2(k-1)", "u1(k-1)^2", "1"])
    m = gb.Model(s, np.array([0.9, 2e-4, 1e-3, 1e-8, 0.1]), Ts=0.05, units=("rpm", "mlc"), input_names=("u1", "n2"))
    curve = gb.operating_curve(m, np.column_stack([np.linspace(800, 1600, 3), np.zeros(3)]))
    for given, name in ((0, "u1"), (1, "n2"), ("n2", "n2")):
        fig = plot_local_models(curve, input=given)
        assert fig.axes[0].get_ylabel() == f"Δy per unit step of {name} (mlc/rpm)"
        assert fig.axes[1].get_ylabel() == f"|G| of {name} (mlc/rpm)"
    one = gb.Model(gb.parse_structure(["y(k-1)", "u(k-1)", "1"]), np.array([0.9, 2e-4, 0.1]), Ts=0.05,
                   units=("rpm", "mlc"))
    fig = plot_local_models(gb.operating_curve(one, [800.0, 1600.0]))
    assert fig.axes[0].get_ylabel() == "Δy per unit step (mlc/rpm)"


def _dsf(jsf: float, band: float, in_band: bool):
    from graybox.estimation._epsilon_constraint import DSFResult

    m = gb.Model(gb.parse_structure(["y(k-1)", "u(k-1)"]), np.array([0.5, 0.1]))
    return DSFResult(m, 1.2, jsf, band, in_band, "PE λ1=0.1", 2.0, 0.1, 10, "converged", np.nan)


def _said(text: str, field: str) -> float:
    import re

    return float(re.search(rf"{field}=([0-9.e+-]+)", text).group(1))


@pytest.mark.parametrize("jsf, band, in_band", [
    (0.0306300004, 0.03063, False),  # a solve ending just outside its band: was 'J_SF=0.03063, band=0.03063'
    (0.03062501, 0.03062502, True),  # just inside: 4 digits rounded it above the band as printed
    (0.03063 * (1 + 1e-13), 0.03063, True),  # within se_dsf's round-off of the band: in it
    (0.5, 0.03063, False),
    (0.001, 0.03063, True),
])
def test_a_dsf_result_prints_its_static_error_on_its_side_of_the_band(jsf, band, in_band):
    text = repr(_dsf(jsf, band, in_band))
    shown, b = _said(text, "J_SF"), _said(text, "band")
    assert (shown <= b) == in_band, text


def test_the_degree_warning_prints_the_fit_on_its_side_of_the_band():
    # 'a degree-1 polynomial fits the points with MSE 0.03063, band B = 0.03063': the fit misses the band (that is
    # why a higher degree is asked) by less than 4 digits show
    import re

    from graybox.experiments._select import _static_points
    from graybox.static._form_check import static_fit_mse

    ub = np.linspace(0.0, 3.0, 7)
    sp = gb.StaticPoints(ub, 0.1 * ub**2)
    fit = static_fit_mse(sp, 1)
    band = fit * (1 - 1e-7)
    process = gb.Candidates(1, 1, ne=0, degree=1).process
    rec = gb.Record(np.linspace(0.0, 3.0, 50), np.zeros(50))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _static_points(sp, process, band, (rec,))
    text = " ".join(str(w.message) for w in caught)
    said = re.search(r"fits the points with MSE ([0-9.e+-]+), band B = ([0-9.e+-]+)\)", text)
    assert said, text
    assert float(said.group(1)) > float(said.group(2))


def test_table_one_free_run_figures_name_their_row(monkeypatch, tmp_path):
    # fig6 (ℓ = 2) and fig8 (ℓ = 3) both named their model 'SE (ga) D_SF' (the decision's name): the two figures
    # of two Table I rows were labelled alike, and unlike the table's rows 'SE (D_SF) ℓ=2' / 'SE (D_SF) ℓ=3'
    import graybox.reproduce._table1 as t1

    drawn = []

    def se_pareto(structure, data, **kwargs):  # the PE front stands in for the SE sweeps (seconds, not minutes)
        return t1.pe_pareto(structure, data.ident, data.static, lambdas=kwargs["lambdas"])

    real = t1.plot_free_run

    def plot_free_run(record, models, **kwargs):
        drawn.append(list(models))
        return real(record, models, **kwargs)

    monkeypatch.setattr(t1, "se_pareto", se_pareto)
    monkeypatch.setattr(t1, "plot_free_run", plot_free_run)
    undrawn_figures(monkeypatch)  # the models handed to plot_free_run are asserted; the figures are built, not drawn
    with warnings.catch_warnings():  # the bundled data's notes (run() says each once)
        warnings.simplefilter("ignore")
        t1.section_table1(quick=True, out=tmp_path)
    assert [names[0].split(" (min J_SF")[0] for names in drawn] == ["SE (D_SF) ℓ=2", "SE (D_SF) ℓ=3"]


def test_the_operating_curve_panels_share_one_u_axis():
    # 'three stacked panels sharing ū': the panels were drawn each on its own, so where τ and ζ are NaN or inf (no
    # stable equilibrium beyond ū = 1800) their panels spanned 750-1850 rpm under a gain panel of 690-3110 rpm
    from graybox.plots import plot_operating_curve

    s = gb.parse_structure(["y(k-1)", "u(k-1)y(k-1)", "u(k-1)", "1"])
    m = gb.Model(s, np.array([0.8, 1e-4, 2e-4, 0.1]), Ts=0.05, units=("rpm", "mlc"))
    curve = gb.operating_curve(m, np.linspace(800.0, 3000.0, 12))
    assert np.isfinite(curve.gain).sum() > np.isfinite(curve.time_constant).sum()  # the case in point
    fig = plot_operating_curve(curve)
    limits = [ax.get_xlim() for ax in fig.axes]
    assert limits[0][0] < 800.0 and limits[0][1] > 3000.0
    assert limits[1] == limits[0] and limits[2] == limits[0]


def _inside_the_figure(fig, text) -> bool:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    box = text.get_window_extent(renderer=canvas.get_renderer())
    return box.x0 >= 0 and box.x1 <= fig.bbox.width


def test_a_long_list_of_operating_points_in_a_title_stays_on_the_figure():
    # 'not reached at ū = ' with 40 levels was one line some three times the figure's width, cut at both edges; the
    # points are listed as messages list them (the first 20 and how many in all) in lines that fit
    from graybox.plots import plot_local_models, plot_operating_curve

    s = gb.parse_structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"])
    m = gb.Model(s, np.array([1.0001, 2e-4, 1e-8, 0.1]), Ts=0.05, units=("rpm", "mlc"))
    curve = gb.operating_curve(m, np.linspace(800.0, 1600.0, 40) + 0.001)
    assert not any(st == "reached" for st in curve.status)
    title = plot_operating_curve(curve).axes[0].title
    assert "(40 in all)" in title.get_text() and "800.001" in title.get_text()
    assert _inside_the_figure(title.figure, title)
    few = gb.operating_curve(m, [800.0, 900.0])
    assert plot_operating_curve(few).axes[0].get_title() == "not reached at ū = 800, 900"
    names = [f"ū = {v}" for v in ("800", "900")]
    assert [t.get_text() for t in plot_local_models(few).axes[0].get_legend().get_texts()][0].startswith(names[0])


@pytest.mark.parametrize("level, said", [(0.95, "95%"), (0.975, "97.5%"), (0.999, "99.9%"), (0.9973, "99.73%")])
def test_a_confidence_level_is_printed_with_its_digits(level, said):
    # ':.0%' printed level=0.975 as '98%' and 0.999 as '100%' (a band no model has) in the residual tests' repr and
    # legends and in the bands' legends
    from graybox.plots import plot_residual_tests, plot_simulation_band

    rec = _first_order_record()
    theta = np.linalg.lstsq(np.column_stack([rec.y[:-1], rec.u[:-1]]), rec.y[1:], rcond=None)[0]
    m = gb.Model(gb.parse_structure(["y(k-1)", "u(k-1)"]), theta, Ts=0.1)  # the least-squares fit
    tests = gb.residual_tests(m, rec, level=level)
    assert f"simultaneous {said};" in repr(tests)
    labels = _legend(plot_residual_tests(tests).axes[0])
    assert any(f"({said} pointwise)" in t for t in labels) and any(f"({said} for the test)" in t for t in labels)
    band = gb.simulation_band(gb.ls_uncertainty(m, rec, level=level), rec)
    assert f"{said} band (delta)" in _legend(plot_simulation_band(band).axes[0])


@given(st.floats(min_value=0.0, max_value=1.0, exclude_min=True, exclude_max=True))
def test_a_share_of_some_draws_is_printed_neither_none_nor_all(share):
    # ':.1%' printed 1 run of 10 000 as '0.0%' ('0.0% of the Monte Carlo runs diverged') and 9 995 of them as
    # '100.0%' beside a band of the others
    from graybox.core._reprs import share_text

    text = share_text(share)
    assert text.endswith("%")
    assert 0.0 < float(text[:-1]) < 100.0


def test_the_dropped_draws_warning_says_a_share_above_zero():
    from graybox.diagnostics._uncertainty import UncertaintyWarning, warn_dropped_draws

    with pytest.warns(UncertaintyWarning, match=r"up to 0\.01% of the Monte Carlo draws"):
        warn_dropped_draws("static_curve_band", np.array([0.0, 1e-4, np.nan]))


@pytest.mark.parametrize("n", [12, 200])
def test_local_models_are_drawn_one_colour_each_with_a_legend_that_fits(n):
    # 'one colour each': matplotlib's cycle of ten drew the 1st and 11th models alike; and 200 models made a legend of
    # 200 entries, matplotlib warning 'Tight layout not applied' (an error under the suite's filter)
    from graybox.plots import plot_local_models

    s = gb.parse_structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"])
    m = gb.Model(s, np.array([0.9, 2e-4, 1e-8, 0.1]), Ts=0.05, units=("rpm", "mlc"))
    curve = gb.operating_curve(m, np.linspace(800.0, 1600.0, n))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = plot_local_models(curve)
    ax = fig.axes[0]
    from matplotlib.colors import to_rgba

    colours = {tuple(np.round(to_rgba(ln.get_color()), 6)) for ln in ax.get_lines()}
    assert len(ax.get_lines()) == n and len(colours) == n
    legend = ax.get_legend()
    assert 2 <= len(legend.get_texts()) <= 20
    assert legend.get_texts()[0].get_text() == "ū = 800 rpm"  # in the model's input unit (hunt60e)


def test_slices_of_many_levels_keep_a_legend_that_fits():
    # 30 slices made a legend of 30 entries that ran off the panel: matplotlib warned 'constrained_layout not applied
    # because axes sizes collapsed to zero' (plot_surface_slices and plot_static_band of a surface band alike)
    from graybox.plots import plot_static_band, plot_surface_slices

    s = gb.parse_structure(["y(k-1)", "u1(k-1)", "u2(k-1)", "u1(k-1)^2", "1"])
    rng = np.random.default_rng(1)
    u = rng.uniform(1.0, 3.0, (300, 2))
    y = np.zeros(300)
    for k in range(1, 300):
        y[k] = 0.5 * y[k - 1] + 0.2 * u[k - 1, 0] + 0.1 * u[k - 1, 1] + 0.05 * u[k - 1, 0] ** 2 + 0.1 \
            + 0.01 * rng.standard_normal()
    rec = gb.Record(u, y, Ts=0.1, units=("V", "Pa"))
    theta = np.linalg.lstsq(gb.regressor_matrix(s, rec.u, rec.y, start=1, input_names=rec.input_names), y[1:],
                            rcond=None)[0]
    m = gb.Model(s, theta, Ts=0.1, units=("V", "Pa"))
    g = np.linspace(1.0, 3.0, 30)
    grid = np.array([(a, b) for a in g for b in g])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        band = gb.static_surface_band(gb.ls_uncertainty(m, rec), grid)
        figs = [plot_static_band(band), plot_surface_slices(lambda v: m.static_curve(v, strict=False), at=g,
                                                            urange=(1.0, 3.0))]
        for fig in figs:
            fig.savefig(__import__("io").BytesIO(), format="png")  # laid out as drawn: the warning came here
    for fig in figs:
        texts = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
        assert 2 <= len(texts) <= 21
        assert fig.axes[0].get_legend().get_title().get_text().startswith("one in 2 of the 30")


@given(st.floats(min_value=-1e6, max_value=1e6), st.floats(min_value=1e-9, max_value=1e3))
def test_a_range_that_is_no_single_value_prints_two_ends_apart(low, width):
    # 'ȳ in [1e+05, 1e+05]' for static points from 100003.9 to 100020.9 (data offset by 1e5) read as constant
    from graybox.core._reprs import range_text

    high = low + width
    assume(high > low)
    a, b = range_text(low, high)[1:-1].split(", ")
    assert a != b and float(a) <= float(b)


def test_records_and_static_points_far_from_zero_print_their_ranges_apart():
    d = gb.load_pumping()
    pts = gb.StaticPoints(d.static.ubar, d.static.ybar + 1e5)
    assert "ȳ in [100004, 100021]" in repr(pts)
    rec = gb.Record(d.ident.u, d.ident.y * 1e-3 + 1e4, Ts=d.ident.Ts)
    lo, hi = repr(rec).split("y in [")[1].split("]")[0].split(", ")
    assert lo != hi
    assert "ȳ in [3.874, 20.93] mlc" in repr(d.static)  # as before where 4 digits tell the ends apart


def test_a_bootstrap_where_one_replicate_disagrees_does_not_print_full_agreement():
    # 'agreement=1.00' (':.2f') for 999 of 1000 replicates choosing the reference λ1
    from graybox.diagnostics._bootstrap import DecisionBootstrap

    s = gb.parse_structure(["y(k-1)", "u(k-1)"])
    lam1 = np.full(1000, 0.5)
    lam1[0] = 1.0
    ref = dict(lambda1=0.5, JS=1.0, JSF=0.01, in_band=True, rule="D_SF", theta=[1.0, 1.0])
    boot = DecisionBootstrap(s, "pe", np.array([0.1, 0.5, 1.0]), 0.05, 10, 5, 0, lam1, np.ones(1000),
                             np.full(1000, 0.01), np.ones(1000, bool), np.ones((1000, 2)), ("D_SF",) * 1000, ref, {})
    assert boot.agreement == 0.999
    assert "agreement=99.9%" in repr(boot)
    assert "agreement=nan" in repr(_bootstrap({"failure": "no member"}))


def test_table_one_ratio_to_els_stays_on_its_side_of_one():
    # 'SE (D_SF) validation J_S over ELS's (below 1: SE better): … here SE 1.00' for a ratio of 0.9951
    import pandas as pd

    from graybox.reproduce._table1 import se_against_els

    rows = {"ELS (15)": 1.0, "SE (D_SF) ℓ=2": 0.9951, "SE-grad (D_SF) ℓ=2": 1.48, "ELS (17)": 2.0,
            "SE (D_SF) ℓ=3": 2.0 * 1.00049, "SE-grad (D_SF) ℓ=3": 1.0}
    text = se_against_els(pd.DataFrame({"JS_valid": rows}))
    assert "here SE 0.995, SE-grad 1.48" in text
    assert "here SE 1.0005, SE-grad 0.50" in text


@pytest.fixture(scope="module")
def selection():
    true = gb.parse_structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"])
    theta = np.array([0.6, 0.5, -0.1, 0.2])

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
        return gb.select_graybox(gb.Candidates(2, 2, ne=0, degree=2), data, band=1e-3, sizes=[3, 4], test=record(3),
                                 estimator=("pe", "ls"))


def test_a_regret_above_one_is_not_printed_as_one(selection):
    # regret 1.0004 (another row did better on the test record) printed 'regret=1' and 'the choice is 1× the best
    # row it compared', which the docstring reads as no row doing better
    import graybox.experiments as gx

    t = selection.table.copy()
    chosen = t["rank"].to_numpy() == 1
    others = (~chosen) & t["in_band"].to_numpy(bool) & np.isfinite(t["JS_test"].to_numpy(float))
    assert others.any()
    t.loc[chosen, "JS_test"] = float(t.loc[others, "JS_test"].min()) * 1.0004
    sel = dataclasses.replace(selection, table=t)
    assert 1.0 < sel.regret < 1.001
    assert "regret=1.0004" in repr(sel)
    fig = gx.plot_selection(sel)
    assert "the choice is 1.0004× the best row" in fig.axes[-1].get_title()
    assert "regret=1," in repr(selection) or "regret=1)" in repr(selection)  # the best row itself: 1


@pytest.mark.parametrize("section", ["section_table1", "section_neural"])
def test_reproduce_sections_refuse_an_empty_out_and_make_a_missing_one_before_any_work(section, tmp_path, monkeypatch):
    # run(out='') is refused since 8bcb032, but section_table1(out='') and section_neural(out='') still wrote their
    # figures into the current folder; and a missing folder failed at the first figure (section_neural: after its
    # trainings) with matplotlib's FileNotFoundError, where run() makes the folder
    import graybox.reproduce as rp
    from graybox.reproduce import _neural, _table1

    class Started(Exception):
        pass

    def started():
        raise Started

    for mod in (_neural, _table1):
        monkeypatch.setattr(mod, "load_pumping", started)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError, match="out is empty"):
        getattr(rp, section)(quick=True, out="")
    (tmp_path / "a file").write_text("")
    with pytest.raises(NotADirectoryError, match="a file"):
        getattr(rp, section)(quick=True, out=tmp_path / "a file")
    with pytest.raises(Started):  # the folder made, then the work began
        getattr(rp, section)(quick=True, out=tmp_path / "new" / "figures")
    assert (tmp_path / "new" / "figures").is_dir()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a file", "new"]


@pytest.mark.parametrize("levels", [[0.5], [2.0, 1.0], []])
def test_contour_levels_of_fewer_than_two_are_refused_naming_levels(levels):
    # levels=[0.5] passed the check (only an empty or unsorted sequence was refused) and failed in matplotlib's
    # contourf: 'Filled contours require at least 2 levels.'
    from graybox.plots import plot_surface_contours

    def plane(u):
        return u[:, 0] + u[:, 1]

    plane.domain = ((0.0, 1.0), (0.0, 1.0))
    with pytest.raises(ValueError, match=r"levels must be two or more increasing output levels"):
        plot_surface_contours(plane, levels=levels)
    assert plot_surface_contours(plane, levels=[0.5, 1.5]).axes


def test_static_points_without_a_name_draw_without_a_legend_warning():
    # StaticPoints(..., name='') drew with matplotlib's 'No artists with labels found to put in legend' (an error
    # under the suite's filter): the docstring promises a legend only when there is anything to label
    from graybox.plots import plot_static_curve

    pts = gb.StaticPoints(np.array([1.0, 2.0, 3.0]), np.array([1.0, 2.0, 4.0]), name="")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = plot_static_curve(pts)
    assert fig.axes[0].get_legend() is None
    named = plot_static_curve(gb.StaticPoints(np.array([1.0, 2.0, 3.0]), np.array([1.0, 2.0, 4.0]), name="p"))
    assert _legend(named.axes[0]) == ["p"]


def test_slices_of_two_surfaces_keep_a_legend_that_fits():
    from graybox.plots import plot_surface_slices

    def a(u):
        return u[:, 0] + u[:, 1]

    def b(u):
        return u[:, 0] - u[:, 1]

    g = np.linspace(0.0, 1.0, 15)  # 2 × 15 lines: 30 entries
    fig = plot_surface_slices([a, b], at=g, urange=(0.0, 1.0))
    legend = fig.axes[0].get_legend()
    assert len(legend.get_texts()) <= 20
    assert legend.get_title().get_text() == "one in 2 of the 15 levels"


def test_a_variant_with_nothing_drawn_in_the_fronts_says_so(store):
    # plot_fronts named every variant in its legend as drawn: one whose every model has J_S or J_SF infinite (each
    # member diverged on the validation record) had an entry, a colour and no point in any panel
    import graybox.experiments as gx

    df = gx.load_results(store)
    assert _legend(gx.plot_fronts(df).axes[0]) == ["LS"]
    gone = df.copy()
    gone["JS_valid"] = np.inf
    assert _legend(gx.plot_fronts(gone).axes[0]) == ["LS (nothing drawn: no finite J_S and J_SF)"]
