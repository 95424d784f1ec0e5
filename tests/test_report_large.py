"""A report of a grid with many structures: its figures draw the best few, its tables every one."""

import pytest

import graybox as gb
from graybox import experiments as gx
from graybox.experiments import _report
from _reports import undrawn_figures

TERMS = ["y(k-2)", "u(k-2)", "u(k-1)^2", "u(k-1)y(k-1)", "y(k-3)"]


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    # five structures, each the plant's core terms plus one more: five ranked rows of one variant
    structures = [gx.StructureSpec(f"s{i}", terms=["1", "y(k-1)", "u(k-1)", t]) for i, t in enumerate(TERMS)]
    grid = gx.Grid([gx.DataSpec("pumping", bundled="pumping")], structures, [gx.Variant("LS", "ls")], name="many")
    path = tmp_path_factory.mktemp("report") / "many.sqlite"
    gx.run_grid(grid, path, progress=False)
    return path


def _ranked(store):
    lb = gx.leaderboard(store, rule="chosen")
    return list(lb.xs("pumping", level="data").sort_values("rank", kind="stable").index.get_level_values("structure"))


def test_the_figures_draw_the_best_structures_by_rank_and_say_so(store, tmp_path):
    written = gx.write_report(store, tmp_path, rule="chosen", max_structures=2)
    best = _ranked(store)[:2]
    summary = (tmp_path / "summary.txt").read_text()
    assert "pumping: the figures draw the 2 best of 5 structures (max_structures=2)" in summary
    assert len(gb.load_results(store)) == 5 and (tmp_path / "leaderboard.csv").read_text().count("\npumping,") == 5
    assert {p.name for p in written} >= {"heatmap_pumping.png", "fronts_pumping.png"}
    assert _report._best_structures(gx.leaderboard(store, rule="chosen"), "pumping", 2) == (best, 5)
    fig = gx.plot_heatmap(store, rule="chosen", structures=best)
    assert [t.get_text() for t in fig.axes[0].get_yticklabels()] == best
    assert _report._best_structures(gx.leaderboard(store, rule="chosen"), "pumping", 5) == (None, 5)


def test_every_structure_is_drawn_when_asked(store, tmp_path, monkeypatch):
    undrawn_figures(monkeypatch)  # its summary.txt is read; plot_heatmap's figure below is the one checked
    gx.write_report(store, tmp_path, rule="chosen", max_structures=None)
    assert "best of" not in (tmp_path / "summary.txt").read_text()
    fig = gx.plot_heatmap(store, rule="chosen")
    assert len(fig.axes[0].get_yticklabels()) == 5


@pytest.mark.parametrize("bad, error", [(0, ValueError), (2.5, TypeError), ("3", TypeError)])
def test_max_structures_is_checked(store, tmp_path, bad, error):
    with pytest.raises(error, match="max_structures"):
        gx.write_report(store, tmp_path, max_structures=bad)


def test_plot_heatmap_names_an_unknown_structure(store):
    with pytest.raises(ValueError, match=r"structures holds \['s9'\]: no such structure"):
        gx.plot_heatmap(store, rule="chosen", structures=["s0", "s9"])


def test_the_cli_takes_max_structures(store, tmp_path, capsys, monkeypatch):
    # the command's main in this process (two `python -m graybox` runs cost 2 s of imports; test_cli_help runs it so)
    from graybox._cli import main

    undrawn_figures(monkeypatch)  # its summary.txt is read; the first test here draws a report of this store

    argv = ["grid", "report", str(store), "--out", str(tmp_path), "--rule", "chosen", "--max-structures", "3"]
    assert main(argv) == 0
    assert "the figures draw the 3 best of 5 structures" in (tmp_path / "summary.txt").read_text()
    capsys.readouterr()
    with pytest.raises(SystemExit) as bad:
        main(["grid", "report", str(store), "--out", str(tmp_path), "--max-structures", "0"])
    assert bad.value.code == 2 and "a number of structures is >= 1, got 0" in capsys.readouterr().err


def test_structures_are_names_each_given_once(store):
    with pytest.raises(TypeError, match=r"structures\[…\] must be a str, got 1"):
        gx.plot_heatmap(store, rule="chosen", structures=["s0", 1])
    with pytest.raises(TypeError, match=r"structures\[…\] must be a str"):
        gx.plot_fronts(store, structures=[None])
    with pytest.raises(ValueError, match=r"structures names \['s1'\] more than once"):
        gx.plot_fronts(store, structures=["s1", "s0", "s1"])


def test_the_summary_says_when_it_shows_only_the_best_five(store, tmp_path):
    # two copies of the store compared: ten ranked models of one data set, of which summary.txt lists five
    import shutil

    other = tmp_path / "other.sqlite"
    shutil.copy(store, other)
    df = gx.compare_results([store, other], labels=["a", "b"])
    lb = gx.leaderboard(df, rule="chosen")
    assert int(lb["rank"].notna().sum()) == 10
    text = "\n".join(_report._summary_lines(df, lb, "chosen"))
    assert "pumping: the best 5 of 10 ranked models; every one in leaderboard.csv" in text
    # five or fewer: all shown, nothing to say
    alone = gb.load_results(store)
    assert "ranked models; every one" not in "\n".join(
        _report._summary_lines(alone, gx.leaderboard(alone, rule="chosen"), "chosen"))


def test_the_page_says_which_spec_its_cells_are_of(store, tmp_path):
    # the environment's "cells shown" read "1" for a store's latest spec (one spec, 5 cells): a count, to a reader
    import shutil

    from graybox.experiments._html import report_page

    def shown(df):
        page = report_page(df, gx.leaderboard(df, rule="chosen"), rule="chosen", summary=[], figures={})
        return page.split('cells shown</td><td class="t">')[1].split("<")[0]

    assert shown(gb.load_results(store)) == "the cells of spec 1"
    assert shown(gb.load_results(store, spec="all")) == "every cell the store holds (spec=&#x27;all&#x27;)"
    shutil.copy(store, tmp_path / "b.sqlite")
    assert shown(gx.compare_results([store, tmp_path / "b.sqlite"])) == "each store&#x27;s latest spec"


@pytest.fixture(scope="module")
def inf_member_store(tmp_path_factory):
    # buck's converter with a cubic term: PE's λ1 = 1 member (the least-squares end) reaches no equilibrium at a
    # static point (J_SF = inf); the other two members are finite
    grid = gx.Grid([gx.DataSpec("buck", bundled="buck")],
                   [gx.StructureSpec("cub", terms=["1", "y(k-1)", "y(k-1)^3", "u(k-1)", "y(k-2)^2"])],
                   [gx.Variant("PE", "pe", lambdas=[1e-4, 0.01, 1.0])], name="inf member")
    path = tmp_path_factory.mktemp("inf") / "inf.sqlite"
    gx.run_grid(grid, path, progress=False)
    return path


def test_the_fronts_say_how_many_models_a_panel_leaves_out(inf_member_store):
    import numpy as np

    m = gb.load_results(inf_member_store)["members"][0]
    jsf = np.asarray(m["JSF"], float)
    assert jsf.size == 3 and int(np.isinf(jsf).sum()) == 1  # the store's own: one member without a static curve
    fig = gx.plot_fronts(inf_member_store)
    assert fig.axes[0].get_title() == "cub\n(1 of 3 models not drawn: J_S or J_SF not finite)"


def test_the_fronts_of_finite_models_are_titled_by_their_structure_alone(store):
    assert [ax.get_title() for ax in gx.plot_fronts(store).axes if ax.get_visible()] == [f"s{i}" for i in range(5)]


def test_the_page_never_shows_two_models_ranked_apart_with_one_figure(store):
    # hunt62e: report.html printed every figure to 4 digits: two structures whose J_S differ by 1e-5 (relative),
    # ranked 1 and 2 apart, both read "0.5252" beside a page saying that models whose J_S agree share a rank
    import re

    from graybox.experiments._html import report_page

    df = gb.load_results(store)
    first, second = df.index[:2]
    df.loc[second, "JS_valid"] = df.loc[first, "JS_valid"] * (1 + 1e-5)
    df.loc[second, "fit_valid"] = df.loc[first, "fit_valid"] - 1e-4
    lb = gx.leaderboard(df, rule="chosen")
    page = report_page(df, lb, rule="chosen", summary=[], figures={})
    board = page.split('<h2 id="leaderboard">')[1].split("</table>")[0]
    rows = {}
    for tr in re.findall(r"<tr>(.*?)</tr>", board)[1:]:
        cells = re.findall(r"<td[^>]*>(.*?)</td>", tr)
        rows[cells[1]] = cells
    a, b = rows[df.loc[first, "structure"]], rows[df.loc[second, "structure"]]
    assert a[3] != b[3]  # ranked apart
    assert a[4] != b[4] and float(a[4]) < float(b[4])  # JS_valid
    assert a[7] != b[7] and float(a[7]) > float(b[7])  # fit_valid
    assert len(a[4].replace(".", "").lstrip("0")) <= 7  # no more digits than tell them apart
