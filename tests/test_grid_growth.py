"""A store that grows: new data sets, variants and options add cells, the rest are reused; the
specs a store has seen; stores of the first format; reasons carried into every report; the
one-page HTML report; figures readable at any data range; stores compared side by side.

Real worker processes (a killed growing run, status read while another process writes, a Dask
LocalCluster growing an in-process store) are in tests/test_grid_executors.py.
"""

from __future__ import annotations

import base64
import html
import json
import re
import sqlite3
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

import graybox as gb
from graybox import _api
from graybox import experiments as gx
from graybox._cli import main
from graybox.experiments._cell import COLUMNS
from graybox.experiments._report import _summary_lines
from graybox.experiments._store import output_units

FIRST = gx.StructureSpec("first-order", terms=["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "1"])
SECOND = gx.StructureSpec("second-order", terms=["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)^2", "1"])
LS = gx.Variant("LS", "ls")
CLS = gx.Variant("CLS", "cls", constraints=[{"type": "equality"}])
PE = gx.Variant("PE", "pe", lambdas=[1e-3, 1e-2, 1e-1, 1.0], options={"solver": "closed"})


def grid(variants=(LS, CLS), data=None, structures=(FIRST, SECOND), name="g") -> gx.Grid:
    return gx.Grid(data or [gx.DataSpec("pumping", bundled="pumping")], list(structures), list(variants), name=name)


def other_pumping() -> gb.Dataset:
    """The bundled plant with its static points moved: other data."""
    d = gb.load_pumping()
    return gb.Dataset(d.ident, d.valid, gb.StaticPoints(d.static.ubar, d.static.ybar + 0.01))


@pytest.fixture
def calls(monkeypatch):
    """How many times each estimator ran (the cells call them through graybox's namespace)."""
    n = {"els": 0, "cls": 0, "pe_pareto": 0}
    for name in n:
        real = getattr(_api, name)

        def counted(*a, _real=real, _name=name, **k):
            n[_name] += 1
            return _real(*a, **k)

        monkeypatch.setattr(_api, name, counted)
    return n


@pytest.fixture(scope="module")
def base_store(tmp_path_factory):
    """LS and CLS on two structures: 4 cells, run once; tests grow copies of it."""
    path = tmp_path_factory.mktemp("base") / "base.sqlite"
    gx.run_grid(grid(), path)
    return path


def copy_of(store: Path, tmp_path: Path, name: str = "s.sqlite") -> Path:
    p = tmp_path / name
    p.write_bytes(store.read_bytes())
    return p


def _values(df: pd.DataFrame) -> pd.DataFrame:
    return df.set_index("key")[["status", "JS_valid", "JSF", "finished_at"]].sort_index()


# --------------------------------------------------------------------------------------------
# growth
# --------------------------------------------------------------------------------------------
def test_adding_a_variant_runs_only_its_cells(base_store, tmp_path, calls):
    path = copy_of(base_store, tmp_path)
    before = gx.load_results(path)
    run = gx.run_grid(grid((LS, CLS, PE)), path)
    # only PE ran, on each structure: no LS (els) or CLS fit again
    assert calls == {"els": 0, "cls": 0, "pe_pareto": 2}
    assert (run.cells, run.skipped, run.ran, run.spec) == (6, 4, 2, 2)
    assert "6 cells, 4 reused, 2 run now" in run.summary()
    df = gx.load_results(path)
    assert len(df) == 6 and df["key"].is_unique and list(df["variant"].unique()) == ["LS", "CLS", "PE"]
    # the reused rows are the stored ones, untouched
    pd.testing.assert_frame_equal(_values(df[df["variant"] != "PE"]), _values(before))
    specs = gx.store_specs(path)
    assert list(specs.index) == [1, 2] and list(specs["n_cells"]) == [4, 6] and list(specs["held"]) == [4, 6]
    assert (specs["version"] == gb.__version__).all() and specs["created"].is_monotonic_increasing
    assert [v["name"] for v in specs.loc[2, "spec"]["variants"]] == ["LS", "CLS", "PE"]
    # the same spec again: nothing runs, no new spec
    again = gx.run_grid(grid((LS, CLS, PE)), path)
    assert (again.ran, again.skipped, again.spec) == (0, 6, 2) and calls["pe_pareto"] == 2
    assert len(gx.store_specs(path)) == 2


def test_adding_a_data_set_runs_only_its_cells(base_store, tmp_path, calls):
    path = copy_of(base_store, tmp_path)
    two = [gx.DataSpec("pumping", bundled="pumping"), gx.DataSpec("moved", dataset=other_pumping(), band=0.031)]
    run = gx.run_grid(grid(data=two), path)
    assert calls == {"els": 2, "cls": 2, "pe_pareto": 0}  # LS and CLS on the two structures of "moved"
    assert (run.skipped, run.ran) == (4, 4)
    assert any("data set 'moved' is new to the store" in n for n in run.notes)
    df = gx.load_results(path)
    assert list(df["data"].unique()) == ["pumping", "moved"] and len(df) == 8
    assert df.attrs["data_hashes"]["moved"] != df.attrs["data_hashes"]["pumping"]


def test_a_changed_option_is_a_new_cell_and_the_old_one_is_kept(base_store, tmp_path, calls):
    path = copy_of(base_store, tmp_path)
    gx.run_grid(grid((LS, CLS, PE), structures=(FIRST,)), path)
    wider = gx.Variant("PE", "pe", lambdas=[1e-4, 1e-3, 1e-2, 1e-1, 1.0], options={"solver": "closed"})
    run = gx.run_grid(grid((LS, CLS, wider), structures=(FIRST,)), path)
    assert (run.ran, run.skipped) == (1, 2) and calls["pe_pareto"] == 2
    latest = gx.load_results(path)
    assert len(latest) == 3 and len(latest.set_index("variant").loc["PE", "members"]["lambda1"]) == 5
    old = gx.load_results(path, spec=2)
    assert len(old.set_index("variant").loc["PE", "members"]["lambda1"]) == 4
    every = gx.load_results(path, spec="all")
    assert every["key"].is_unique and len(every) == 4 + 1 + 1
    # one name, two definitions: told apart by the spec that defined each
    assert {"PE (spec 2)", "PE (spec 3)"} <= set(every["variant"]) and "LS" in set(every["variant"])
    lb = gx.leaderboard(every)
    assert {"PE (spec 2)", "PE (spec 3)"} <= set(lb.index.get_level_values("variant"))
    with pytest.raises(ValueError, match=r"no spec 9; its specs are 1 \('g'\), 2 \('g'\), 3 \('g'\)"):
        gx.load_results(path, spec=9)


def test_same_name_other_data_is_refused_untouched(base_store, tmp_path):
    path = copy_of(base_store, tmp_path)
    before = path.read_bytes()
    moved = [gx.DataSpec("pumping", dataset=other_pumping(), band=0.031)]
    with pytest.raises(gx.StoreError) as err:
        gx.run_grid(grid(data=moved), path)
    msg = str(err.value)
    assert str(path) in msg and "data set 'pumping' of this spec reads other data" in msg
    assert "spec 1 'g'" in msg and "give the data set a new name" in msg
    assert path.read_bytes() == before


def _edited(store: Path, tmp_path: Path, name: str, sql: str) -> tuple[Path, bytes]:
    """A copy of ``store`` changed by one SQL statement, and its bytes."""
    p = copy_of(store, tmp_path, name)
    con = sqlite3.connect(p)
    con.execute(sql)
    con.commit()
    con.close()
    return p, p.read_bytes()


def test_a_store_of_a_newer_graybox_is_refused(base_store, tmp_path):
    newer_format, before = _edited(base_store, tmp_path, "format.sqlite",
                                   "UPDATE meta SET value = '99' WHERE key = 'format_version'")
    for call in (lambda: gx.run_grid(grid(), newer_format), lambda: gx.load_results(newer_format)):
        with pytest.raises(gx.StoreError, match=re.escape(str(newer_format)) + ".*newer graybox.*Upgrade graybox"):
            call()
    assert newer_format.read_bytes() == before
    newer_cells, before = _edited(base_store, tmp_path, "cells.sqlite", "UPDATE specs SET graybox_version = '99.0'")
    with pytest.raises(gx.StoreError, match="graybox 99.0.*newer than this graybox.*upgrade graybox"):
        gx.run_grid(grid(), newer_cells)
    assert newer_cells.read_bytes() == before
    assert len(gx.load_results(newer_cells)) == 4  # still readable


def _first_format(src: Path, dst: Path, g: gx.Grid, version: str | None = None) -> None:
    """The store a graybox of the first store format wrote for grid ``g``: meta and cells only (``version``: a
    graybox other than this one wrote it, its cells keyed by that version)."""
    rows = sqlite3.connect(src).execute(f"SELECT {', '.join(COLUMNS)} FROM cells").fetchall()
    con = sqlite3.connect(dst)
    con.execute("CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)")
    con.execute(f"CREATE TABLE cells ({', '.join(f'{k} {t}' for k, t in COLUMNS.items())})")
    cells = g.cells()
    fingerprint = g.fingerprint(cells)
    if version is not None:  # its cells' keys, and so the grid's fingerprint, are that version's
        rows = [(f"{version}-{r[0]}", *r[1:-4], version, *r[-3:]) for r in rows]
        fingerprint = f"{version}-{fingerprint}"
    meta = {"format": "graybox-grid-store", "format_version": "1", "grid_fingerprint": fingerprint,
            "grid_name": g.name, "grid_spec": json.dumps(g.to_dict()), "graybox_version": version or gb.__version__,
            "n_cells": str(len(cells)), "created": "2026-01-01T00:00:00+00:00"}
    con.executemany("INSERT INTO meta VALUES (?, ?)", list(meta.items()))
    con.executemany(f"INSERT INTO cells VALUES ({', '.join('?' * len(COLUMNS))})", rows)
    con.commit()
    con.close()


def test_a_first_format_store_is_read_upgraded_by_its_own_spec_and_then_grows(base_store, tmp_path, calls):
    old = tmp_path / "v1.sqlite"
    _first_format(base_store, old, grid())
    df = gx.load_results(old)
    assert len(df) == 4 and df.attrs["grid"] == "g" and df.attrs["n_cells"] == 4
    pd.testing.assert_frame_equal(_values(df), _values(gx.load_results(base_store)))
    before = old.read_bytes()
    with pytest.raises(gx.StoreError, match="first format.*Run the store's own spec on it first"):
        gx.run_grid(grid((LS, CLS, PE)), old)
    assert old.read_bytes() == before
    run = gx.run_grid(grid(), old)  # its own spec: upgraded, nothing runs
    assert (run.ran, run.skipped, run.spec) == (0, 4, 1) and sum(calls.values()) == 0
    run = gx.run_grid(grid((LS, CLS, PE)), old)
    assert (run.ran, run.skipped, run.spec) == (2, 4, 2) and calls["pe_pareto"] == 2
    assert list(gx.store_specs(old)["created"])[0] == "2026-01-01T00:00:00+00:00"


def test_a_first_format_store_of_another_graybox_is_not_sent_to_its_own_spec(base_store, tmp_path):
    # was: "... this is another grid. Run the store's own spec on it first": its own spec was refused alike, for ever
    old = tmp_path / "v1.sqlite"
    _first_format(base_store, old, grid(), version="0.1.0")
    before = old.read_bytes()
    for g in (grid(), grid((LS, CLS, PE))):  # its own grid, and another
        with pytest.raises(gx.StoreError) as err:
            gx.run_grid(g, old)
        text = str(err.value)
        assert "written by graybox 0.1.0" in text and "another --store path" in text and "nothing was written" in text
        assert "own spec" not in text and "another grid" not in text
    assert old.read_bytes() == before
    assert len(gx.load_results(old)) == 4  # read as it is


# --------------------------------------------------------------------------------------------
# reasons
# --------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def troubled(tmp_path_factory):
    """A band no member reaches (infeasible D_SF), a diverging structure, a failing data set."""
    d = gb.load_pumping()
    short = gb.Dataset(d.ident.slice(0, 12), d.valid, d.static)
    g = gx.Grid(
        data=[gx.DataSpec("pumping", bundled="pumping", band=1e-9), gx.DataSpec("short", dataset=short, band=1e-9)],
        structures=[FIRST, gx.StructureSpec("quadratic-y", terms=["y(k-1)^2", "y(k-2)^2", "u(k-1)", "1"]),
                    gx.StructureSpec("wide", terms=["y(k-1)", "y(k-2)", "y(k-3)", "u(k-1)", "u(k-2)", "u(k-3)",
                                                    "u(k-1)y(k-1)", "u(k-2)^2", "1"])],
        variants=[LS, gx.Variant("PE", "pe", lambdas=[1e-3, 1e-2, 1e-1, 1.0], options={"solver": "closed"})],
        name="troubled")
    path = tmp_path_factory.mktemp("troubled") / "t.sqlite"
    gx.run_grid(g, path)
    return path


def test_every_outcome_that_is_not_ok_carries_its_reason(troubled):
    df = gx.load_results(troubled)
    data = gb.load_pumping()
    by = df.set_index(["data", "structure", "variant"])
    # a band no member reaches: infeasible, the smallest J_SF reached named
    pe = by.loc[("pumping", "first-order", "PE")]
    assert pe["status"] == "infeasible"
    assert f"the smallest J_SF is {np.min(pe['members']['JSF']):.4g}" in pe["message"]
    assert pe["n_params"] == 4  # known without a chosen member
    # a diverging free run: the sample where it left
    dv = by.loc[("pumping", "quadratic-y", "LS")]
    assert dv["status"] == "diverged"
    m = gb.Model(gb.parse_structure(list(dv["terms"])), dv["theta"])
    sim = m.simulate(data.valid, on_diverge="nan")
    first = int(np.flatnonzero(~np.isfinite(sim[m.max_lag:]))[0]) + m.max_lag
    assert f"validation record at sample {first} of {len(data.valid)}" in dv["message"]
    # a failed cell: the exception
    assert re.match(r"\w+Error: ", by.loc[("short", "wide", "LS"), "message"])
    lb = gx.leaderboard(df)
    empty = lb[lb["JS_valid"].isna()]
    assert len(empty) and (empty["reason"].str.len() > 0).all()
    assert (lb.loc[lb["JS_valid"].notna(), "reason"] == "").all()
    r = lb.loc[("pumping", "first-order", "PE"), "reason"]
    assert f"smallest J_SF reached is {np.min(pe['members']['JSF']):.4g}" in r and "1 infeasible" in r
    assert "1 diverged: the free run of the chosen model diverges" in lb.loc[("pumping", "quadratic-y", "LS"), "reason"]
    assert "1 failed: " in lb.loc[("short", "wide", "LS"), "reason"]
    # every N_p is known where the cells know it, whichever band the report uses
    wide = gx.leaderboard(df, band=1e3)
    ran = wide.xs("pumping", level="data")
    assert ran["n_params"].notna().all()
    assert not wide.loc[("pumping", "first-order", "PE"), "reason"]  # now it qualifies
    # the summary says the same
    text = "\n".join(_summary_lines(df, lb, "dsf_valid"))
    for (d, s, v), reason in empty["reason"].items():
        assert f"{s} / {v}: {reason}" in text
    for _, c in df[df["status"] != "ok"].iterrows():
        assert c["message"] in text


class _Page(HTMLParser):
    def __init__(self):
        super().__init__()
        self.images: list[str] = []
        self.external: list[str] = []
        self.text: list[str] = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.images.append(a.get("src", ""))
        for k in ("src", "href"):
            if a.get(k, "").startswith(("http:", "https:", "//", "file:")):
                self.external.append(a[k])
        if tag in ("link", "script"):
            self.external.append(tag)

    def handle_data(self, data):
        self.text.append(data)


def test_html_report_is_one_self_contained_page_with_every_figure_and_reason(troubled, tmp_path):
    written = gx.write_report(troubled, tmp_path / "rep", html=True)
    page = tmp_path / "rep" / "report.html"
    assert page in written
    p = _Page()
    p.feed(page.read_text(encoding="utf-8"))
    assert not p.external  # nothing fetched: readable offline
    pngs = sorted(w.name for w in written if w.suffix == ".png")
    assert len(p.images) == len(pngs) == 2 * 2 + 1  # heat map and fronts per data set, the scatter
    for src, name in zip(p.images, sorted(pngs)):
        assert src.startswith("data:image/png;base64,")
    embedded = sorted(base64.b64decode(s.split(",", 1)[1]) for s in p.images)
    assert embedded == sorted((tmp_path / "rep" / n).read_bytes() for n in pngs)
    text = " ".join(p.text)
    df = gx.load_results(troubled)
    for reason in gx.leaderboard(df)["reason"]:
        if reason:
            assert reason in text
    for m in df.loc[df["status"] != "ok", "message"]:
        assert m in text
    assert '"name": "troubled"' in html.unescape(page.read_text(encoding="utf-8"))  # the spec
    assert gb.__version__ in text and "numpy" in text  # the environment


def test_html_report_says_a_band_as_its_reasons_do(base_store):
    # B = 0.175² = 0.030625 (0.030624999999999996 in binary) read "0.03062" in the leaderboard's band column while
    # the reason in the same row said "B = 0.030625": the column now says it as the reasons do (bound_text)
    from graybox.experiments._html import report_page
    df = gx.load_results(base_store)
    lb = gx.leaderboard(df, band=0.175 ** 2)
    assert any("B = 0.030625" in r for r in lb["reason"])  # the reasons' figure, and a row that has one
    page = report_page(df, lb, rule="dsf_valid", summary=[], figures={})
    board = page.split('id="leaderboard"', 1)[1].split('id="figures"', 1)[0]
    cells = re.findall(r"<td>(0\.0306[0-9]*)</td>", board)
    assert len(cells) == len(lb) and set(cells) == {"0.030625"}


def test_cli_report_says_a_band_given_with_rule_chosen_ranks_nothing(tmp_path, capsys, monkeypatch, base_store):
    # graybox grid report --rule chosen --band B ranked each cell's own choice, ignoring --band with no word (only the
    # figures drew it): the command and summary.txt now say so, and the ranking is the one without --band
    from _reports import undrawn_figures
    undrawn_figures(monkeypatch)  # the message, summary.txt and leaderboard.csv are read, not the figures
    common = ["grid", "report", str(base_store), "--rule", "chosen"]
    assert main([*common, "--out", str(tmp_path / "b"), "--band", "0.01"]) == 0
    err = capsys.readouterr().err
    assert "--band does not change the ranking under --rule chosen" in err
    summary = (tmp_path / "b" / "summary.txt").read_text(encoding="utf-8")
    assert "the band given, B = 0.01, is drawn on the figures only" in summary
    assert (tmp_path / "b" / "leaderboard.csv").read_text() == gx.leaderboard(base_store, rule="chosen").to_csv()


def test_cli_status_report_html_and_growth(tmp_path, capsys, monkeypatch, base_store):
    monkeypatch.chdir(tmp_path)
    path = copy_of(base_store, tmp_path)
    assert main(["grid", "status", str(path)]) == 0
    out = capsys.readouterr().out
    assert "spec 1 of 1 ('g'): 4 of 4 cells done (4 ok" in out and "0 left" in out and "best so far" in out
    assert main(["grid", "report", str(path), "--out", "rep", "--html"]) == 0
    assert (tmp_path / "rep" / "report.html").is_file()
    assert main(["grid", "status", str(path), "--spec", "7"]) == 2
    assert "no spec 7" in capsys.readouterr().err
    assert main(["grid", "status", str(tmp_path / "missing.sqlite")]) == 2
    assert "no such store" in capsys.readouterr().err
    garbled = bytearray(path.read_bytes())
    garbled[4096: 4096 + 512] = bytes(range(256)) * 2  # a page of the store overwritten
    bad = tmp_path / "bad.sqlite"
    bad.write_bytes(bytes(garbled))
    for cmd in (["grid", "status", str(bad)], ["grid", "report", str(bad), "--out", "x"]):
        assert main(cmd) == 2
        err = capsys.readouterr().err
        assert str(bad) in err and "damaged" in err and "restore it from a copy" in err


# --------------------------------------------------------------------------------------------
# comparing stores
# --------------------------------------------------------------------------------------------
def test_two_stores_side_by_side_and_stores_of_other_data_refused(base_store, tmp_path, capsys):
    b = tmp_path / "pe.sqlite"
    gx.run_grid(grid((PE,), structures=(FIRST,)), b)
    both = gx.compare_results([base_store, b])
    assert set(both["store"]) == {"base", "pe"}
    assert set(both["variant"]) == {"base: LS", "base: CLS", "pe: PE"}
    t = gx.heatmap_table(both)
    assert list(t.columns) == ["base: LS", "base: CLS", "pe: PE"]
    out = tmp_path / "cmp"
    assert main(["grid", "report", str(base_store), str(b), "--out", str(out)]) == 0
    assert len(pd.read_csv(out / "leaderboard.csv")) == 5
    moved = tmp_path / "moved.sqlite"
    gx.run_grid(grid((LS,), data=[gx.DataSpec("pumping", dataset=other_pumping(), band=0.031)],
                     structures=(FIRST,)), moved)
    with pytest.raises(gx.StoreError, match=re.escape(str(moved)) + ".*different data under the data set name "
                                                                     "'pumping'"):
        gx.compare_results([base_store, moved])
    assert main(["grid", "report", str(base_store), str(moved), "--out", str(tmp_path / "x")]) == 2
    assert "not comparable" in capsys.readouterr().err


# --------------------------------------------------------------------------------------------
# figures
# --------------------------------------------------------------------------------------------
def _labels_overlap(fig, ax) -> list[tuple[str, str]]:
    FigureCanvasAgg(fig).draw()
    r = fig.canvas.get_renderer()
    out = []
    for axis in (ax.xaxis, ax.yaxis):
        boxes = [(t.get_text(), t.get_window_extent(r)) for t in axis.get_ticklabels(which="both")
                 if t.get_visible() and t.get_text()]
        for i in range(len(boxes)):
            for j in range(i + 1, len(boxes)):
                if boxes[i][1].overlaps(boxes[j][1]):
                    out.append((boxes[i][0], boxes[j][0]))
    return out


@pytest.mark.parametrize("lo, hi", [(0.0101, 0.0109), (0.031, 0.089), (2.0, 3.0), (1e-5, 10.0), (123.4, 123.9)])
def test_figures_have_tick_labels_that_never_overlap(base_store, lo, hi):
    df = gx.load_results(base_store).copy()
    n = len(df)
    df["JS_valid"] = np.linspace(lo, hi, n)
    df["JSF"] = np.geomspace(lo, hi, n)
    fig = gx.plot_scatter(df)
    ax = fig.axes[0]
    assert not _labels_overlap(fig, ax)
    assert ax.get_xscale() == ("log" if hi >= 10 * lo else "linear")
    assert len([t for t in ax.get_xticklabels() if t.get_text()]) >= 1
    heat = gx.plot_heatmap(df, band=1e9)  # every model in the band: the colours are the J_S above
    assert not _labels_overlap(heat, heat.axes[1])  # the colour bar
    fronts = gx.plot_fronts(df, band=1e9)
    for a in fronts.axes:
        if a.get_visible():
            assert not _labels_overlap(fronts, a)


def test_fronts_shade_only_the_band_inside_the_panel(base_store):
    from matplotlib.patches import Polygon, Rectangle

    df = gx.load_results(base_store)
    jsf = df.loc[np.isfinite(df["JSF"]), "JSF"]
    inside = float(np.sqrt(jsf.min() * jsf.max())) if jsf.max() > jsf.min() else float(jsf.min())
    fig = gx.plot_fronts(df, structures=["first-order", "second-order"], band=inside)
    for ax in fig.axes[:2]:
        lo, hi = ax.get_ylim()
        spans = [p for p in ax.patches if isinstance(p, (Polygon, Rectangle))]
        for p in spans:  # the shading ends at B, inside the panel
            top = p.get_path().transformed(p.get_patch_transform()).vertices[:, 1].max() \
                if isinstance(p, Rectangle) else p.get_xy()[:, 1].max()
            assert top <= inside * (1 + 1e-9) and top < hi
    above = gx.plot_fronts(df, band=1e6)
    for ax in above.axes:
        if ax.get_visible():
            assert not ax.patches and any("above every point" in t.get_text() for t in ax.texts)


def test_select_graybox_table_says_why_a_structure_has_no_figures():
    """The band no structure reaches: each structure's row in select_graybox's table carries the
    leaderboard's reason (the smallest J_SF reached), not a bare NaN."""
    import warnings

    true = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2", "1"])
    m = gb.Model(true, np.array([0.6, 0.2, 0.3, 0.05, 0.4]))
    rng = np.random.default_rng(1)
    recs = []
    for _ in range(2):
        u = np.repeat(rng.uniform(0.0, 3.0, 49), 25)[:1200]
        recs.append(gb.Record(u, m.simulate(u, np.zeros(2)) + 0.02 * rng.standard_normal(1200)))
    ub = np.linspace(-0.5, 3.5, 7)
    far = gb.StaticPoints(ub, m.static_curve(ub) + 0.5 * (-1.0) ** np.arange(7))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = gb.select_graybox(gb.Candidates(3, 3, ne=0, degree=2), gb.Dataset(recs[0], recs[1], far), band=1e-6,
                                sizes=[5], fallback="min_jsf")
    t = res.table
    assert (~t["in_band"]).all()
    for reason in t["reason"]:
        assert re.search(r"no member meets the band B = 1e-06: the smallest J_SF reached is [0-9.e+-]+", reason)


def test_the_cell_and_decide_dsf_share_one_no_member_in_band_rule():
    """D_SF with no member in the band raises InfeasibleError (still a ValueError) naming the smallest
    J_SF; a grid cell records exactly that message as its infeasible status."""
    from graybox.estimation._decisions import min_jsf_index

    data = gb.load_pumping()
    st = gb.parse_structure(FIRST.terms)
    front = gb.pe_pareto(st, data, lambdas=[1e-3, 1e-2, 1e-1, 1.0], solver="closed")
    with pytest.raises(gb.InfeasibleError, match=f"the smallest J_SF is {np.min(front.JSF):.4g}") as err:
        gb.decide_dsf(front, band=1e-12)
    assert isinstance(err.value, ValueError)
    i = min_jsf_index(front)
    assert front.JSF[i] == np.min(front.JSF)
    assert gb.decide_dsf(front, band=1e-12, fallback="min_jsf").index == i
    g = gx.Grid([gx.DataSpec("pumping", bundled="pumping", band=1e-12)], [FIRST],
                [gx.Variant("PE", "pe", lambdas=[1e-3, 1e-2, 1e-1, 1.0], options={"solver": "closed"})])
    from graybox.experiments._cell import run_cell

    row = run_cell(g.cells()[0], data)
    assert row["status"] == "infeasible" and row["message"] == str(err.value)


def _older(store: Path, tmp_path: Path) -> Path:
    """A copy of ``store`` as an older graybox (0.0.1) wrote it: its cells under the keys that version gave them."""
    path, _ = _edited(store, tmp_path, "old.sqlite", "UPDATE cells SET version = '0.0.1'")
    con = sqlite3.connect(path)
    for table in ("cells", "spec_cells"):
        con.execute(f"UPDATE {table} SET key = 'old-' || key")
    con.commit()
    con.close()
    return path


def test_cells_of_another_graybox_version_are_not_reused_and_the_run_says_why(base_store, tmp_path):
    path = _older(base_store, tmp_path)
    run = gx.run_grid(grid(), path)
    assert (run.ran, run.skipped) == (4, 0)
    assert any("4 cell(s) of this grid were made before by graybox 0.0.1" in n for n in run.notes)
    assert len(gx.load_results(path, spec="all")) == 8 and len(gx.load_results(path)) == 4


def test_only_the_cells_an_older_graybox_made_alike_are_said_to_run_again_for_the_version(base_store, tmp_path):
    # was: "none of the store's N cells is reused: they were made by graybox 0.0.1" whenever the grid reused none,
    # counting every cell of the store, this version's too, and said of a grid whose cells no version had made
    path = _older(base_store, tmp_path)
    run = gx.run_grid(grid((LS, PE), structures=(FIRST,)), path)  # LS on FIRST made by 0.0.1, PE new
    assert run.ran == 2
    assert any("1 cell(s) of this grid were made before by graybox 0.0.1" in n for n in run.notes), run.notes
    third = gx.StructureSpec("third", terms=["y(k-1)", "y(k-2)", "u(k-1)", "1"])
    run = gx.run_grid(grid((PE,), structures=(third,)), path)  # nothing of it made before, by any version
    assert run.ran == 1 and not any("0.0.1" in n for n in run.notes), run.notes


def test_compare_results_wants_a_sequence_of_paths():
    with pytest.raises(TypeError, match="stores must be a sequence of two or more store paths"):
        gx.compare_results("results.sqlite")


def _pumping_in(y_unit: str, scale: float = 1.0) -> gb.Dataset:
    """The bundled plant with its output said to be in ``y_unit`` (its numbers times ``scale``)."""
    d = gb.load_pumping()

    def rec(r):
        return gb.Record(r.u, r.y * scale, Ts=r.Ts, name=r.name, units=("rpm", y_unit))

    s = d.static
    return gb.Dataset(rec(d.ident), rec(d.valid), gb.StaticPoints(s.ubar, s.ybar * scale, uncertainty=s.uncertainty
                                                                   * scale, units=("rpm", y_unit)))


def test_a_report_says_the_unit_of_the_spec_it_reads_not_the_first_specs(tmp_path):
    # hunt62e: the first spec's unit of a data set was said for every spec read (spec 1 in kPa, spec 2, the latest,
    # in Pa: the latest's J_S, J_SF and B were said in kPa²)
    path = tmp_path / "s.sqlite"
    gx.run_grid(grid((LS,), data=[gx.DataSpec("p", dataset=_pumping_in("kPa"))], structures=(FIRST,)), path)
    # the same numbers, their unit said right now; another grid (CLS too)
    run = gx.run_grid(grid((LS, CLS), data=[gx.DataSpec("p", dataset=_pumping_in("Pa"))], structures=(FIRST,)), path)
    assert run.spec == 2
    for spec, unit in ((1, "kPa"), (2, "Pa"), ("all", "Pa")):  # what summary, page, figures and status read
        assert output_units(gx.load_results(path, spec=spec).attrs) == {"p": unit}, spec
    df = gx.load_results(path)
    lines = "\n".join(_summary_lines(df, gx.leaderboard(df), "dsf_valid", df.attrs, None))
    assert set(re.findall(r"(?<![A-Za-z])(k?Pa)²", lines)) == {"Pa"}, lines


def test_a_spec_that_corrects_only_its_datas_unit_is_a_new_spec_reported_in_it(tmp_path):
    # hunt62e: the unit is in no cell's key, so the spec with the unit corrected had the fingerprint of the one it
    # corrects: the run reused that spec, and every report went on saying the old unit (Pa² for kPa²)
    path = tmp_path / "s.sqlite"
    gx.run_grid(grid((LS,), data=[gx.DataSpec("p", dataset=_pumping_in("Pa"))], structures=(FIRST,)), path)
    fixed = grid((LS,), data=[gx.DataSpec("p", dataset=_pumping_in("kPa"))], structures=(FIRST,))
    run = gx.run_grid(fixed, path)
    assert (run.spec, run.ran, run.skipped) == (2, 0, 1)  # the cell is reused: the same numbers
    assert any("output in kPa in this spec, in Pa in the store's spec of the same cells" in n for n in run.notes), \
        run.notes
    for spec, unit in ((1, "Pa"), ("latest", "kPa")):
        assert output_units(gx.load_results(path, spec=spec).attrs) == {"p": unit}, spec
    again = gx.run_grid(fixed, path)  # the corrected spec again: itself, no third
    assert again.spec == 2 and len(gx.store_specs(path)) == 2
    assert gx.run_grid(grid((LS,), data=[gx.DataSpec("p", dataset=_pumping_in("Pa"))], structures=(FIRST,)),
                       path).spec == 1


@pytest.mark.parametrize("column, value", [("status", "OK"), ("theta", "[1, 2"), ("JS_valid", "abc")])
def test_a_run_refuses_untouched_a_store_whose_cell_it_would_reuse_is_damaged(base_store, tmp_path, column, value):
    # hunt62e: the run read a cell's key and status only: a damaged cell (edited in an SQLite browser) was reused,
    # "4 reused, 0 run now; 4 ok" (3 ok with status 'OK', the fourth cell in no count), and every report then
    # refused the store as damaged
    path, before = _edited(base_store, tmp_path, "d.sqlite",
                           f"UPDATE cells SET {column} = '{value}' WHERE variant = 'LS' AND structure = 'first-order'")
    with pytest.raises(gx.StoreError) as load_err:
        gx.load_results(path)
    with pytest.raises(gx.StoreError) as err:
        gx.run_grid(grid(), path)
    msg = str(err.value)
    assert "is damaged" in msg and "'first-order' / 'LS'" in msg and "nothing was written to it" in msg, msg
    assert msg.split("; nothing was written")[0] == str(load_err.value).split("; restore")[0]  # the reader's words
    assert path.read_bytes() == before


def test_stores_compared_are_counted_as_stores(base_store, tmp_path):
    # hunt62e: summary.txt and report.html of two stores compared said "8 of 8 cells in the store"
    from graybox.experiments._html import report_page

    df = gx.compare_results([base_store, copy_of(base_store, tmp_path)])
    lb = gx.leaderboard(df)
    head = _summary_lines(df, lb, "dsf_valid", df.attrs, None)[0]
    assert "8 of 8 cells in the 2 stores;" in head, head
    assert "<p>8 of 8 cells in the 2 stores: " in report_page(df, lb, rule="dsf_valid", summary=[], figures={})
    one = gx.load_results(base_store)
    assert "4 of 4 cells in the store;" in _summary_lines(one, gx.leaderboard(one), "dsf_valid", one.attrs, None)[0]


def test_a_store_whose_spec_row_was_deleted_is_refused_untouched_not_a_traceback(base_store, tmp_path):
    # hunt62e: a spec's row deleted (an SQLite browser) left its spec_cells: the next new spec took its number and
    # the run ended in sqlite3.IntegrityError 'UNIQUE constraint failed: spec_cells.spec, spec_cells.position'
    path = copy_of(base_store, tmp_path)
    gx.run_grid(grid((LS,), structures=(FIRST,)), path)  # spec 2
    con = sqlite3.connect(path)
    con.execute("DELETE FROM specs WHERE id = 2")
    con.commit()
    con.close()
    before = path.read_bytes()
    with pytest.raises(gx.StoreError, match=r"is damaged: its spec_cells table holds the cells of spec\(s\) \[2\], "
                                            r"which its specs table lacks; nothing was written to it"):
        gx.run_grid(grid((CLS,), structures=(FIRST,)), path)
    assert path.read_bytes() == before


def test_summary_figures_keep_six_digits_and_their_side_of_the_band(base_store):
    # hunt62e: summary.txt printed its table with pandas' 6 decimals: in bar (J's near 1e-4 bar²) a J_SF of
    # 6.3e-6 read 0.000006, and one of 0.00021078597 ranked within B = 0.000210786 read 0.000211, above it
    df = gx.load_results(base_store)
    k2 = 0.0980665**2  # the plant in bar
    for c in ("J1_ident", "JS_ident", "J1_valid", "JS_valid", "JSF", "band"):
        df[c] = df[c] * k2
    B = float(df.loc[df["variant"] == "CLS", "JSF"].max()) * (1 + 1e-7)
    lb = gx.leaderboard(df, band=B)
    lines = _summary_lines(df, lb, "dsf_valid", df.attrs, B)
    text = "\n".join(lines)
    said_b = float(re.search(r"J_SF ≤ B = (\S+)", text).group(1))
    rows = [ln.split()[-4:] for ln in text.splitlines() if re.fullmatch(r".*\s\d+", ln) and len(ln.split()) >= 5]
    assert len(rows) == int(lb["JS_valid"].notna().sum()) >= 2, text
    for js, jsf, fit, _ in rows:
        assert float(jsf) <= said_b, text
        for said, col in ((js, "JS_valid"), (jsf, "JSF"), (fit, "fit_valid")):
            assert np.nanmin(np.abs(lb[col].to_numpy(float) / float(said) - 1)) < 6e-6, (said, text)


def test_stores_that_give_the_same_data_two_units_are_not_compared_under_one(tmp_path):
    # hunt62e: a store whose data set 'p' says kPa and one whose 'p', the same numbers, says Pa were compared, and the
    # report said every J in the unit of the store run last (Pa²), the other's word dropped without a note
    a, b = tmp_path / "a.sqlite", tmp_path / "b.sqlite"
    for path, unit in ((a, "kPa"), (b, "Pa")):
        gx.run_grid(grid((LS,), data=[gx.DataSpec("p", dataset=_pumping_in(unit))], structures=(FIRST,)), path)
    with pytest.raises(gx.StoreError, match=r"data set 'p'.*in kPa.*in Pa.*the same numbers"):
        gx.compare_results([a, b])
