"""Bug hunt 43a: reports that explain, and the plots."""

import re
import shutil
import warnings

import numpy as np
import pandas as pd
import pandas.testing as pd_testing
import pytest

import graybox as gb
from _reports import undrawn_figures


def _named_points(text: str) -> list[str]:
    return re.findall(r"ū = (\([^)]*\)|[^:;,\s]+)", text)


@pytest.mark.parametrize("offset", [0.0, 1e4, 1e6])
def test_reached_explain_names_each_point_apart_at_any_offset(offset):
    """Three static points 0.01 apart on an input offset by 1e4: jsf's warning (Reached.explain) named every one
    'ū = 10000', so the reader could not tell which point failed (at offset 0 they read 0.01, 0.02, 0.03)."""
    model = gb.Model(gb.parse_structure(["y(k-1)", "u(k-1)"]), np.array([1.5, 1.0]))  # unstable: no point reached
    pts = gb.StaticPoints(offset + np.array([0.01, 0.02, 0.03]), [1.0, 2.0, 3.0])
    with pytest.warns(RuntimeWarning) as rec:
        assert gb.jsf(model, pts) == np.inf
    named = _named_points(str(rec[0].message))
    assert len(named) == 3 and len(set(named)) == 3, named
    np.testing.assert_allclose([float(t) for t in named], pts.ubar, rtol=1e-12)


@pytest.mark.parametrize("offset", [0.0, 1e4])
def test_static_curve_names_each_point_apart_at_any_offset(offset):
    """A non-rational model with no stable equilibrium: static_curve's error named each point with %g."""
    model = gb.Model(gb.parse_structure(["y(k-1)", "y(k-1)^2", "u(k-1)"]), np.array([1.0, 1.0, 1.0]))  # ȳ² = −ū: none
    ub = offset + np.array([0.01, 0.02])
    with pytest.raises(ValueError) as exc:
        model.static_curve(ub)
    named = _named_points(str(exc.value))
    assert len(set(named)) == 2, str(exc.value)
    np.testing.assert_allclose([float(t) for t in dict.fromkeys(named)], ub, rtol=1e-12)


def test_reached_explain_names_surface_points_apart():
    """Points (ū1, ū2) of a surface with ū2 offset by 1e4: each printed '(1, 10000)'."""
    st = gb.parse_structure(["y(k-1)", "u1(k-1)", "u2(k-1)"])
    model = gb.Model(st, np.array([1.5, 1.0, 1.0]), input_names=("u1", "u2"))
    ub = np.array([[1.0, 1e4 + 0.01], [1.0, 1e4 + 0.02]])
    pts = gb.StaticPoints(ub, [1.0, 2.0])
    with pytest.warns(RuntimeWarning) as rec:
        assert gb.jsf(model, pts) == np.inf
    named = _named_points(str(rec[0].message))
    assert len(named) == 2 and len(set(named)) == 2, named


# -- grids of two data sets, one without a band of its own ------------------------------------------
from graybox import experiments as gx  # noqa: E402


@pytest.fixture(scope="module")
def two_data(tmp_path_factory):
    """The bundled plant (its points carry a band) and the same records whose points carry none."""
    d = gb.load_pumping()
    bare = gb.Dataset(d.ident, d.valid, gb.StaticPoints(d.static.ubar, d.static.ybar))
    grid = gx.Grid([gx.DataSpec("pumping", bundled="pumping"), gx.DataSpec("bare", dataset=bare)],
                   [gx.StructureSpec("fo", terms=["y(k-1)", "u(k-1)", "y(k-1)u(k-1)", "1"]),
                    gx.StructureSpec("so", terms=["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)^2", "1"])],
                   [gx.Variant("LS", "ls"),
                    gx.Variant("PE", "pe", lambdas=[1e-3, 1e-2, 1e-1, 1.0], decision=gx.DecisionRule("min_jsf"),
                               options={"solver": "closed"})], name="two")
    path = tmp_path_factory.mktemp("two") / "two.sqlite"
    gx.run_grid(grid, path, progress=False)
    return path, d.static.band


@pytest.fixture(scope="module")
def band_report(two_data, tmp_path_factory):
    """The report of ``two_data`` with bare's band given (B = 0.05), html too: its folder and the files written
    (written once: two tests read it, one a copy; every report's figures cost seconds)."""
    out = tmp_path_factory.mktemp("band") / "report"
    return out, gx.write_report(two_data[0], out, band={"bare": 0.05}, html=True)


def test_a_band_mapping_leaves_the_data_sets_it_does_not_name_to_their_stored_band(two_data):
    """leaderboard's band: 'default: each data set's band as stored'. A mapping giving the band of the data set that
    stores none raised 'band gives no value for data set pumping', though pumping stores its own: a store of such
    data sets could not be ranked by D_SF at all without restating every stored band."""
    path, b = two_data
    df = gb.load_results(path)
    lb = gx.leaderboard(path, band={"bare": 0.05})
    alone = gx.leaderboard(df[df["data"] == "pumping"])  # by pumping's stored band
    of = lb.index.get_level_values("data")
    pd_testing.assert_frame_equal(lb[of == "pumping"], alone)
    assert (lb.loc[of == "pumping", "JSF"].dropna() <= b).all() and lb.loc[of == "pumping", "JSF"].notna().any()
    pd_testing.assert_frame_equal(lb[of == "bare"], gx.leaderboard(df[df["data"] == "bare"], band=0.05))
    t = gx.heatmap_table(path, data="pumping", band={"bare": 0.05})
    pd_testing.assert_frame_equal(t, gx.heatmap_table(df[df["data"] == "pumping"]))
    # the figures draw pumping's stored band, the one named 'bare''s
    scatter = gx.plot_scatter(path, band={"bare": 0.05})
    for ax, want in zip(scatter.axes, (b, 0.05)):
        assert any(np.allclose(ln.get_ydata(), want) for ln in ax.lines if len(ln.get_ydata()) == 2)
    assert f"B = {b:g}" in gx.plot_fronts(path, data="pumping", band={"bare": 0.05}).get_suptitle()


def test_grid_status_ranks_each_data_set_by_its_own_rule_and_says_which(two_data):
    """One data set without a band made grid status rank every data set by each cell's own choice: pumping's 'best so
    far' was least squares with J_SF 0.74, 24 times outside the band its own report ranks by, and nothing said so."""
    path, b = two_data
    df = gb.load_results(path)
    st = gx.grid_status(path)
    best = st.best
    want = gx.leaderboard(df[df["data"] == "pumping"]).iloc[0]
    assert best.loc["pumping", "JS_valid"] == want["JS_valid"] and best.loc["pumping", "JSF"] <= b
    chosen = gx.leaderboard(df[df["data"] == "bare"], rule="chosen").iloc[0]
    assert best.loc["bare", "JS_valid"] == chosen["JS_valid"]
    assert list(best["rule"]) == ["dsf_valid", "chosen"]
    text = st.summary()
    assert "dsf_valid" in text and "rule chosen: each cell's own choice, for a data set without a band" in text


def test_grid_report_takes_a_band_per_data_set(two_data, tmp_path, capsys, monkeypatch):
    """graybox grid report of a store whose one data set has no band could only be made with --band B for every data
    set (pumping's stored band overridden by the other's number, in the other's units) or --rule chosen: --band
    NAME=B (repeatable) gives the data sets their own, the others keep theirs."""
    from graybox._cli import main

    path, b = two_data
    undrawn_figures(monkeypatch)  # the leaderboards are read; band_report draws this store's figures with this band
    assert main(["grid", "report", str(path), "--out", str(tmp_path / "r"), "--band", "bare=0.05"]) == 0
    lb = pd.read_csv(tmp_path / "r" / "leaderboard.csv", index_col=[0, 1, 2])
    want = gx.leaderboard(path, band={"bare": 0.05})
    np.testing.assert_allclose(lb["JS_valid"].to_numpy(float), want["JS_valid"].to_numpy(float))
    assert main(["grid", "report", str(path), "--out", str(tmp_path / "s"), "--band", "0.05"]) == 0  # one for all
    lb = pd.read_csv(tmp_path / "s" / "leaderboard.csv", index_col=[0, 1, 2])
    np.testing.assert_allclose(lb["JS_valid"].to_numpy(float),
                               gx.leaderboard(path, band=0.05)["JS_valid"].to_numpy(float))
    capsys.readouterr()
    with pytest.raises(SystemExit):  # argparse: not a number
        main(["grid", "report", str(path), "--out", str(tmp_path / "t"), "--band", "bare=x"])
    assert "bare=x" in capsys.readouterr().err
    for bad, said in ((["--band", "0.05", "--band", "bare=0.05"], "one number for every data set"),
                      (["--band", "nope=0.05"], "'nope'")):
        assert main(["grid", "report", str(path), "--out", str(tmp_path / "t"), *bad]) == 2
        assert said in capsys.readouterr().err


def test_a_report_rewritten_in_its_folder_leaves_no_file_of_the_last_one(band_report, tmp_path, monkeypatch):
    """A report written again into its folder overwrote the files it wrote and kept the others: the figures of a data
    set the new report does not hold, and a report.html (of the old leaderboard) when the new one was written without
    html, sat beside the new tables as if they were of them. A file the reports did not write stays."""
    one = gx.Grid([gx.DataSpec("pumping", bundled="pumping")], [gx.StructureSpec("fo", terms=["y(k-1)", "u(k-1)"])],
                  [gx.Variant("LS", "ls")], name="one")
    small = tmp_path / "one.sqlite"
    gx.run_grid(one, small, progress=False)
    src, written = band_report
    out = shutil.copytree(src, tmp_path / "report")  # the last report's folder, its manifest too
    first = [out / p.relative_to(src) for p in written]
    assert (out / "heatmap_bare.png") in first and (out / "report.html") in first
    (out / "notes.txt").write_text("mine")
    undrawn_figures(monkeypatch)  # the files' names are what is asserted
    second = gx.write_report(small, out)
    held = sorted(p.name for p in out.iterdir() if not p.name.startswith("."))
    assert held == sorted([p.name for p in second] + ["notes.txt"])
    assert (out / "notes.txt").read_text() == "mine"


@pytest.mark.parametrize("spread", [1.0, 100.0])  # a linear and a log colour scale
def test_the_heat_map_says_inf_where_a_model_s_figure_is_inf_and_a_dash_only_where_there_is_no_model(two_data,
                                                                                                    spread):
    """rule='chosen' ranks an ok cell whose model reaches no equilibrium at a static point (J_SF = inf): its heat map
    of J_SF drew '—', the mark the docstring keeps for 'no model qualified', as for a failed cell."""
    path, _ = two_data
    df = gb.load_results(path)
    df = df[df["data"] == "pumping"].copy()
    ls = df["variant"] == "LS"
    df.loc[ls & (df["structure"] == "fo"), "JSF"] = np.inf
    df.loc[ls & (df["structure"] == "so"), "JSF"] *= spread
    t = gx.heatmap_table(df, value="JSF", rule="chosen")
    assert t.loc["fo", "LS"] == np.inf
    fig = gx.plot_heatmap(df, value="JSF", rule="chosen")
    texts = [x.get_text() for x in fig.axes[0].texts]
    assert "inf" in texts and "—" not in texts


@pytest.fixture(scope="module")
def fallback_selection():
    """A selection where no row meets the band and fallback='min_jsf' chose the smallest J_SF."""
    data = gb.load_pumping()
    with pytest.warns(gx.SelectionWarning):
        sel = gb.select_graybox(gb.Candidates(ny=1, nu=1, degree=2, max_y_power=1), data, band=1e-6,
                                fallback="min_jsf", estimator=["pe"])
    assert not sel.in_band
    return sel


def test_plot_selection_says_when_no_row_met_the_band_and_the_smallest_j_sf_chose(fallback_selection):
    """With no row in the band, fallback='min_jsf' chose the smallest J_SF; the figure said "rule 'min': 0 of 2 rows
    drawn" and 'chosen: semp-5 by pe', as if the J_S rule had chosen, and nowhere that no row met the band."""
    sel = fallback_selection
    fig = gx.plot_selection(sel)
    said = " ".join([fig.get_suptitle()] + [ax.get_title() for ax in fig.axes])
    assert "no row meets the band B = 1e-06" in said and "smallest J_SF" in said
    assert f"{sel.chosen['JSF']:.4g}" in said
    assert len(fig.axes[0].get_yticks()) == 0 and fig.axes[0].texts  # the empty rule panel: no scale of nothing


def test_gain_bounds_name_their_range_apart_at_any_offset():
    """GainBounds over ū in [10000.01, 10000.03] described itself as 'over ū in [10000, 10000]', and the range beyond
    the points said 'the ū range [10000, 10000] extends beyond the static points [10000, 10000]'."""
    g = gb.GainBounds(lower=0.0, ubar_range=(1e4 + 0.01, 1e4 + 0.03))
    assert "[10000.01, 10000.03]" in g.describe()
    two = gb.GainBounds(lower=[0.0, 0.0], ubar_range=[(1e4 + 0.01, 1e4 + 0.03), (1.0, 2.0)])
    assert "[10000.01, 10000.03] × [1, 2]" in two.describe()
    st = gb.parse_structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"])
    rng = np.random.default_rng(0)
    u = 1e4 + np.repeat(rng.uniform(0.0, 0.05, 40), 10)
    y = np.zeros(u.size)
    for k in range(1, u.size):
        y[k] = 0.5 * y[k - 1] + 0.1 * (u[k - 1] - 1e4)
    pts = gb.StaticPoints(1e4 + np.array([0.02, 0.03, 0.04]), [0.04, 0.06, 0.08])
    with pytest.raises(ValueError) as exc:
        gb.pe_pareto(st, gb.Record(u, y), pts, lambdas=[0.5], constraints=g)
    assert "the ū range [10000.01, 10000.03] extends beyond the static points [10000.02, 10000.04]" in str(exc.value)


def test_local_model_plots_name_operating_points_apart_at_any_offset():
    """plot_local_models labelled local models at ū = 10000.01 and 10000.02 both 'ū = 10000', and
    plot_operating_curve's 'not reached at ū = …' named the points the same way."""
    from graybox import plots

    st = gb.parse_structure(["y(k-1)", "u(k-1)", "1"])
    model = gb.Model(st, np.array([0.5, 0.1, -1000.0]), Ts=0.1)
    lms = [gb.local_model(model, 1e4 + d) for d in (0.01, 0.02)]
    fig = plots.plot_local_models(lms)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert labels == ["ū = 10000.01", "ū = 10000.02"]
    growing = gb.Model(gb.parse_structure(["y(k-1)", "y(k-1)u(k-1)", "u(k-1)"]), np.array([0.5, 0.0001, 0.1]), Ts=0.1)
    curve = gb.operating_curve(growing, 1e4 + np.array([0.01, 0.02, 0.03]))  # Σy + Σyu ū > 1: none stable
    fig = plots.plot_operating_curve(curve)
    assert fig.axes[0].get_title() == "not reached at ū = 10000.01, 10000.02, 10000.03"


@pytest.mark.parametrize("content", [b"", b"garbage", None])
def test_grid_status_and_report_of_a_file_that_is_no_store_say_what_to_give(tmp_path, capsys, content):
    """graybox grid status / report of a file that is no store said '…; nothing was written to it. Choose another
    --store path': a reader's command has no --store option and writes nothing to the store."""
    import sqlite3

    from graybox._cli import main

    p = tmp_path / "x.sqlite"
    if content is None:  # an SQLite database of something else
        sqlite3.connect(p).execute("CREATE TABLE t (a)").connection.close()
    else:
        p.write_bytes(content)
    for argv in (["grid", "status", str(p)], ["grid", "report", str(p), "--out", str(tmp_path / "r")]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "not a graybox grid store" in err and "--store" not in err and "written" not in err
        assert "give the path of a grid store" in err


def test_the_report_says_why_member_fits_failed_in_a_ranked_group_too(tmp_path):
    """A PE cell whose member at λ1 = 1 failed (an input held in the identification record: θ not identifiable
    without the static points) was ranked on its two other members; summary.txt and report.html said nothing of the
    third, nor why the leaderboard compared 2 candidates of 3 (the reason was kept only for unranked groups)."""
    d = gb.load_pumping()
    rng = np.random.default_rng(0)
    u = np.full(600, 1200.0)
    y = np.zeros(600)
    for k in range(1, 600):
        y[k] = 0.6 * y[k - 1] + 0.0005 * u[k - 1] + 1e-7 * u[k - 1] ** 2
    held = gb.Record(u, y + 0.01 * rng.standard_normal(600), Ts=d.ident.Ts, units=d.ident.units, name="held")
    grid = gx.Grid([gx.DataSpec("held", dataset=gb.Dataset(held, d.valid, d.static))],
                   [gx.StructureSpec("s", terms=["1", "y(k-1)", "u(k-1)", "u(k-1)^2"])],
                   [gx.Variant("PE", "pe", lambdas=[0.1, 0.5, 1.0], options={"solver": "closed"})], name="held")
    store = tmp_path / "held.sqlite"
    gx.run_grid(grid, store, progress=False)
    lb = gx.leaderboard(store)
    assert lb["rank"].iloc[0] == 1 and lb["candidates"].iloc[0] == 2
    gx.write_report(store, tmp_path / "r", html=True)
    summary = (tmp_path / "r" / "summary.txt").read_text()
    line = next(ln for ln in summary.splitlines() if "member fit(s) failed" in ln)
    assert "s / PE" in line and "1 of 3" in line and "λ1 = 1" in line and "not identifiable" in line
    assert "not identifiable" in (tmp_path / "r" / "report.html").read_text()


def test_grid_status_says_why_cells_are_not_ok(tmp_path, capsys):
    """graybox grid status counted '2 failed, 1 infeasible' and said nothing of why: a grid failing cell after cell (a
    structure spec the data cannot give) was seen only in the report written after it ended."""
    from graybox._cli import main

    grid = gx.Grid([gx.DataSpec("pumping", bundled="pumping")],
                   [gx.StructureSpec("toolong", terms=["y(k-1)", "u(k-5000)", "1"]),  # lags beyond the records
                    gx.StructureSpec("fo", terms=["y(k-1)", "u(k-1)", "y(k-1)u(k-1)", "1"])],
                   [gx.Variant("LS", "ls"), gx.Variant("PE tight", "pe", lambdas=[1e-3, 1.0],
                                                      decision=gx.DecisionRule("dsf", band=1e-9),
                                                      options={"solver": "closed"})], name="fail")
    store = tmp_path / "fail.sqlite"
    gx.run_grid(grid, store, progress=False)
    st = gx.grid_status(store)
    assert dict(st.counts)["failed"] == 2 and dict(st.counts)["infeasible"] == 1
    assert set(st.reasons) == {"failed", "infeasible"}
    assert "fewer than max lag + 1 = 5001" in st.reasons["failed"]
    assert "B = [0, 1e-09]" in st.reasons["infeasible"]
    assert main(["grid", "status", str(store)]) == 0
    out = capsys.readouterr().out
    assert "fewer than max lag + 1" in out and "B = [0, 1e-09]" in out


def test_a_near_miss_of_the_band_is_said_with_the_digits_that_show_it(two_data):
    """A model just outside the band was said 'no model has J_SF ≤ B = 0.0306: the smallest J_SF reached is 0.0306'
    (4 significant digits), a reason that contradicts itself; a miss by a clear margin keeps its 4 digits."""
    path, _ = two_data
    df = gb.load_results(path)
    df = df[df["data"] == "pumping"].copy()
    ls = df["variant"] == "LS"
    df.loc[ls & (df["structure"] == "fo"), "JSF"] = 0.0306 * (1 + 1e-6)
    df.loc[ls & (df["structure"] == "so"), "JSF"] = 0.04321234
    lb = gx.leaderboard(df, band=0.0306)
    reason = {s: r for (_, s, v), r in lb["reason"].items() if v == "LS"}
    said = float(reason["fo"].split("the smallest J_SF reached is ")[1].split(" ")[0])
    assert said > 0.0306 and "B = 0.0306:" in reason["fo"]
    assert "the smallest J_SF reached is 0.04321 " in reason["so"]


def test_a_fallback_selection_s_repr_says_the_smallest_j_sf_chose(fallback_selection):
    """repr said "rule='min', J_S valid=50.24, in_band=False": the J_S rule's name for a choice the smallest J_SF made."""
    text = repr(fallback_selection)
    assert "chosen by the smallest J_SF" in text and "no row meets the band B = 1e-06" in text
    assert "rule=" not in text


def _many(two_data, n_structures: int = 1, n_variants: int = 1) -> pd.DataFrame:
    """The pumping cells of the two-data store copied under more structure and variant names."""
    df = gb.load_results(two_data[0])
    df = df[df["data"] == "pumping"]
    parts = []
    for i in range(n_structures):
        for j in range(n_variants):
            p = df.copy()
            p["structure"] = p["structure"] + f"-{i}"
            p["variant"] = p["variant"] + f"-{j}"
            parts.append(p)
    return pd.concat(parts, ignore_index=True)


def test_the_scatter_of_a_grid_of_many_structures_keeps_a_legend_that_fits(two_data):
    """write_report's max_structures kept the heat map and fronts readable, not the scatter: a grid of 60 × 2
    structures listed all 120 in its legend (12 markers reused ten times over), which covered the points and ran off
    the figure after 38 of them."""
    big = _many(two_data, n_structures=60)
    fig = gx.plot_scatter(big)
    texts = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert len(texts) <= 4 and any("120 structures" in t for t in texts + [fig.axes[0].get_title()])
    few = gx.plot_scatter(_many(two_data, n_structures=2))  # few structures: one marker each, named
    assert len(few.axes[0].get_legend().get_texts()) == 2 + 4 + 1  # variants, structures, the band


def test_report_figures_give_every_variant_its_own_colour(two_data):
    """The variants' colours cycled through ten: in a grid of 12 variants the 1st and the 11th were drawn alike in the
    scatter and the fronts, and a reader could not tell their points apart."""
    from matplotlib.colors import to_hex

    big = _many(two_data, n_variants=6)  # 12 variants
    for fig in (gx.plot_scatter(big), gx.plot_fronts(big)):
        handles, labels = fig.axes[0].get_legend_handles_labels()
        colours = {lab: to_hex(h.get_color()) for h, lab in zip(handles, labels) if lab in set(big["variant"])}
        assert len(colours) == 12 and len(set(colours.values())) == 12


def test_grid_status_names_the_data_sets_with_no_qualifying_model_yet(two_data, tmp_path, capsys):
    """With one data set's models all outside its band, grid status listed the other's best and said nothing of the
    first, as if the grid held one data set ('no model qualifies yet' was said only when no data set had one)."""
    from graybox._cli import main

    d = gb.load_pumping()
    grid = gx.Grid([gx.DataSpec("pumping", bundled="pumping"),
                    gx.DataSpec("tight", dataset=gb.Dataset(d.ident, d.valid, d.static), band=1e-9)],
                   [gx.StructureSpec("fo", terms=["y(k-1)", "u(k-1)", "y(k-1)u(k-1)", "1"])],
                   [gx.Variant("PE", "pe", lambdas=[1e-3, 1.0], decision=gx.DecisionRule("min_jsf"),
                               options={"solver": "closed"})], name="tight")
    store = tmp_path / "tight.sqlite"
    gx.run_grid(grid, store, progress=False)
    st = gx.grid_status(store)
    assert list(st.best.index) == ["pumping"] and st.waiting == ("tight",)
    assert main(["grid", "status", str(store)]) == 0
    # the grid is complete: nothing is still to come ('yet' said so while every cell was done; hunt49c's note)
    assert st.left == 0 and "no model qualifies for data set 'tight'" in capsys.readouterr().out


def test_plot_selection_titles_stay_inside_the_figure(fallback_selection):
    """The test panel's title ('test record (not used to choose): the choice is 1.04× the best row it compared') ran
    52 px past the figure's right edge and was cut; the fallback's suptitle likewise."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from graybox.datasets import pumping

    test = pumping.generate(seed=5)[0].record("test")
    data = gb.load_pumping()
    sel = gb.select_graybox(gb.Candidates(ny=1, nu=1, degree=2, max_y_power=1), data, test=test, estimator=["pe"])
    for s in (sel, fallback_selection):
        fig = gx.plot_selection(s)
        FigureCanvasAgg(fig)
        fig.canvas.draw()
        r = fig.canvas.get_renderer()
        for text in [ax.title for ax in fig.axes] + [fig._suptitle]:
            box = text.get_window_extent(r)
            assert box.x0 >= fig.bbox.x0 - 1 and box.x1 <= fig.bbox.x1 + 1, text.get_text()


def _outside(fig) -> list[str]:
    """The titles of ``fig`` that reach past its left or right edge."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    texts = [ax.title for ax in fig.axes if ax.get_visible()] + ([fig._suptitle] if fig._suptitle else [])
    return [t.get_text() for t in texts if t.get_text() and (t.get_window_extent(r).x0 < fig.bbox.x0 - 1 or
                                                              t.get_window_extent(r).x1 > fig.bbox.x1 + 1)]


def test_the_fronts_title_of_a_grid_of_one_structure_stays_inside_the_figure(two_data, tmp_path):
    """A one-structure grid's fronts (one panel, 5.2 in wide) titled 'pumping: fronts per structure (shaded below the
    dashed line: J_SF ≤ B = 0.030625)' across 680 px of a 520 px figure: both ends were cut. Likewise with the
    variants' own bands, and in write_report with the note of the structures drawn."""
    df = gb.load_results(two_data[0])
    one = df[(df["data"] == "pumping") & (df["structure"] == "fo")]
    assert _outside(gx.plot_fronts(one)) == []
    two_bands = one.assign(band=np.where(one["variant"] == "LS", 0.03, 0.05))
    assert _outside(gx.plot_fronts(two_bands)) == []
    assert _outside(gx.plot_heatmap(one)) == []


def test_plot_pareto_says_why_a_point_is_not_drawn():
    """The true model of a simulation study meets noise-free static points exactly (J_SF = 0): on log axes plot_pareto
    left it out with the legend 'true (not drawn: J = inf)', a reason it does not have."""
    from graybox import plots

    data = gb.load_pumping()
    st = gb.parse_structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"])
    pe = gb.pe_pareto(st, data, lambdas=[0.1, 1.0])
    fig = plots.plot_pareto(pe, {"true": (0.5, 0.0), "gone": (np.inf, 0.1)})
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "true (not drawn: J_SF = 0 on a log axis)" in labels and "gone (not drawn: J_S = inf)" in labels
    fig = plots.plot_pareto(pe, {"true": (0.5, 0.0)}, log=False)  # linear axes draw it
    assert "true" in [t.get_text() for t in fig.axes[0].get_legend().get_texts()]


def test_the_heat_map_of_a_grid_with_no_qualifying_model_draws_no_colour_scale(tmp_path):
    """Every cell failed: the heat map had only dashes and a colour bar from -0.1 to 0.1 for J_S, a scale of values
    nothing has (a mean square is never negative)."""
    grid = gx.Grid([gx.DataSpec("pumping", bundled="pumping")],
                   [gx.StructureSpec("toolong", terms=["y(k-1)", "u(k-5000)", "1"])],  # lags beyond the records
                   [gx.Variant("LS", "ls")], name="allfail")
    store = tmp_path / "af.sqlite"
    gx.run_grid(grid, store, progress=False)
    fig = gx.plot_heatmap(store)
    assert len(fig.axes) == 1 and [t.get_text() for t in fig.axes[0].texts] == ["—"]
    assert "no model qualified" in fig.axes[0].get_title()
    # the scatter likewise drew empty axes from -0.05 to 0.05 of J_S and J_SF
    ax = gx.plot_scatter(store).axes[0]
    assert len(ax.get_xticks()) == 0 and len(ax.get_yticks()) == 0 and ax.texts


def test_the_heat_map_tells_a_pair_never_run_from_one_with_no_qualifying_model(two_data):
    """Read with spec='all' (or two stores compared), a structure and a variant of different specs were never run
    together: the heat map drew their cell '—', the mark of 'no model qualified', as for a run that failed."""
    df = gb.load_results(two_data[0])
    df = df[(df["data"] == "pumping") & ~((df["structure"] == "so") & (df["variant"] == "PE"))]
    fig = gx.plot_heatmap(df)
    t = gx.heatmap_table(df)
    texts = {(round(x.get_position()[1]), round(x.get_position()[0])): x.get_text() for x in fig.axes[0].texts}
    rows, cols = list(t.index), list(t.columns)
    assert texts[(rows.index("so"), cols.index("PE"))] == "not run"
    assert texts[(rows.index("so"), cols.index("LS"))] == "—"  # run: no model in the band


def test_the_summary_says_which_band_ranked_each_data_set(two_data, band_report, tmp_path, monkeypatch):
    """summary.txt (and report.html) said 'ranking rule: dsf_valid' and '<data>: best by J_S on the validation
    record', never within which band: a report made with --band, or of a data set whose band the spec gave, ranked by
    a B the reader could find only in the reasons of rows that missed it."""
    path, b = two_data
    text = (band_report[0] / "summary.txt").read_text()  # write_report(path, ..., band={"bare": 0.05}, html=True)
    assert f"pumping: best by J_S on the validation record among the models with J_SF ≤ B = {b:g}" in text
    assert "bare: best by J_S on the validation record among the models with J_SF ≤ B = 0.05" in text
    undrawn_figures(monkeypatch)  # its summary.txt is read
    gx.write_report(path, tmp_path / "c", rule="chosen")
    assert "bare: best by J_S on the validation record (each cell's own choice)" in \
        (tmp_path / "c" / "summary.txt").read_text()
