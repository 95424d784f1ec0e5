"""Grids: specs in Python and TOML, cells and their keys, the SQLite store, statuses, reports, CLI.

The executors on real worker processes (Dask LocalCluster, the local pool, SIGKILL) are in
tests/test_grid_executors.py.
"""

from __future__ import annotations

import re
import sqlite3
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

import graybox as gb
from _reports import undrawn_figures
from graybox import experiments as gx
from graybox._cli import main
from graybox.experiments._spec import data_fingerprint
from graybox.experiments._store import ResultStore

FIGURES = ["status", "message", "terms", "n_params", "lambda1", "rule", "J1_ident", "JS_ident", "fit_ident",
           "J1_valid", "JS_valid", "fit_valid", "JSF", "static_miss"]

TOML = """\
name = "small"
seeds = [0, 1]

[[data]]
name = "pumping"
bundled = "pumping"

[[structures]]
name = "first-order"
terms = ["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "1"]

[[structures]]
name = "made"
candidates = {ny = 2, nu = 2, degree = 2, max_y_power = 1}
n_terms = 6
include = ["1"]

[[variants]]
name = "LS"
estimator = "ls"

[[variants]]
name = "CLS"
estimator = "cls"
constraints = [{type = "equality"}]

[[variants]]
name = "PE band"
estimator = "pe"
lambdas = {logspace = [-3, 0, 4]}
constraints = [{type = "band", b = 0.175}, {type = "gain", lower = 0.0}]

[[variants]]
name = "PE"
estimator = "pe"
lambdas = [0.001, 0.01, 0.1, 1.0]
decision = {rule = "min_jsf"}
options = {solver = "closed"}

[[variants]]
name = "NN"
estimator = "neural"
options = {hidden = 2, epochs = 3, ne = 0}
"""


def python_grid() -> gx.Grid:
    """The grid of TOML, written in Python (constraint objects, numpy λ)."""
    return gx.Grid(
        name="small",
        seeds=[0, 1],
        data=[gx.DataSpec("pumping", bundled="pumping")],
        structures=[gx.StructureSpec("first-order", terms=["y(k-1)", "u(k-1)", "y(k-1)u(k-1)", "1"]),
                    gx.StructureSpec("made", candidates={"ny": 2, "nu": 2, "degree": 2, "max_y_power": 1},
                                     n_terms=6, include=["1"])],
        variants=[gx.Variant("LS", "ls"),
                  gx.Variant("CLS", "cls", constraints=[{"type": "equality"}]),
                  gx.Variant("PE band", "pe", lambdas=np.logspace(-3, 0, 4),
                             constraints=gb.StaticBand(0.175) & gb.GainBounds(lower=0.0)),
                  gx.Variant("PE", "pe", lambdas=[1e-3, 1e-2, 1e-1, 1.0], decision=gx.DecisionRule("min_jsf"),
                             options={"solver": "closed"}),
                  gx.Variant("NN", "neural", options={"hidden": 2, "epochs": 3, "ne": 0})],
    )


@pytest.fixture(scope="module")
def pumping():
    return {"pumping": gb.load_pumping()}


@pytest.fixture(scope="module")
def small_store(tmp_path_factory):
    path = tmp_path_factory.mktemp("store") / "small.sqlite"
    run = gx.run_grid(python_grid(), path)
    return path, run


# --------------------------------------------------------------------------------------------
# specs
# --------------------------------------------------------------------------------------------
def test_toml_and_python_give_the_same_cells(tmp_path, pumping):
    spec = tmp_path / "spec.toml"
    spec.write_text(TOML)
    a, b = gx.Grid.from_toml(spec), python_grid()
    ca, cb = a.cells(pumping), b.cells(pumping)
    assert [(c.key, c.data, c.structure, c.variant, c.seed) for c in ca] == \
           [(c.key, c.data, c.structure, c.variant, c.seed) for c in cb]
    assert a.fingerprint(ca) == b.fingerprint(cb)
    # 2 structures × (4 deterministic variants + the neural one for each of 2 seeds)
    assert len(ca) == 2 * (4 + 2)
    assert [c.seed for c in ca if c.variant == "NN"] == [0, 1, 0, 1]
    assert {c.seed for c in ca if c.variant != "NN"} == {None}


def test_cell_keys_follow_content_not_names(pumping):
    g = python_grid()
    keys = {c.key for c in g.cells(pumping)}
    assert len(keys) == len(g.cells(pumping))  # all distinct
    renamed = gx.Grid(g.data, g.structures, [gx.Variant("least squares", "ls")] + list(g.variants[1:]), g.seeds,
                      name="other")
    assert {c.key for c in renamed.cells(pumping)} == keys
    d = pumping["pumping"]
    shifted = gb.Dataset(d.ident, d.valid, gb.StaticPoints(d.static.ubar, d.static.ybar + 1e-9))
    assert {c.key for c in g.cells({"pumping": shifted})}.isdisjoint(keys)


def test_cell_keys_are_the_hash_of_their_canonical_content(pumping):
    """A key is the SHA-256 of the canonical JSON of (band where the variant reads it, data, seed, structure,
    variant, version), so that stores written before keep the keys of the cells that read the band; the grid
    builds that text in pieces."""
    from graybox.experiments._spec import _hash, reads_band

    g = python_grid()
    for band in (None, 0.02):  # the bundled set's own band, and another
        data = [gx.DataSpec(d.name, bundled="pumping", band=band) for d in g.data]
        grid = gx.Grid(data, g.structures, g.variants, g.seeds, name=g.name)
        for c in grid.cells(pumping):
            s = next(s for s in grid.structures if s.name == c.structure)
            v = next(v for v in grid.variants if v.name == c.variant)
            # the bundled set's band is its static points' own: (±0.175 mlc)², the mean of δ²
            assert c.band == (pumping["pumping"].static.band if band is None else band)
            content = {"data": c.data_hash, "structure": s.content(), "variant": v.content(), "seed": c.seed,
                       "version": gb.__version__}
            if reads_band(v.content()):
                content["band"] = c.band
            assert c.key == _hash(content, 32)


def test_data_from_csv_files_hash_like_the_same_data_in_memory(tmp_path, pumping):
    d = pumping["pumping"]
    for name, rec in (("ident", d.ident), ("valid", d.valid)):
        pd.DataFrame({"t": rec.t, "speed": rec.u, "pressure": rec.y}).to_csv(tmp_path / f"{name}.csv", index=False,
                                                                              float_format="%.17g")
    pd.DataFrame({"u": d.static.ubar, "y": d.static.ybar}).to_csv(tmp_path / "static.csv", index=False,
                                                                  float_format="%.17g")
    spec = tmp_path / "spec.toml"
    spec.write_text(TOML.replace('bundled = "pumping"', """band = 0.031
ident = {path = "ident.csv", u = "speed", y = "pressure", time = "t"}
valid = {path = "valid.csv", u = "speed", y = "pressure", time = "t"}
static = {path = "static.csv", u = "u", y = "y"}"""))
    g = gx.Grid.from_toml(spec)
    loaded = g.load_data()["pumping"]
    plain = gb.Dataset(d.ident, d.valid, d.static)  # the bundled set without its static curve
    assert data_fingerprint(loaded) == data_fingerprint(plain)
    np.testing.assert_array_equal(loaded.ident.y, d.ident.y)


def _bad(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


@pytest.mark.parametrize("old,new,needle", [
    ('estimator = "ls"', 'estimator = "lsq"', "estimator must be one of"),
    ('{type = "band", b = 0.175}', '{type = "bands", b = 0.175}', "unknown constraint type 'bands'"),
    ('{type = "band", b = 0.175}', '{type = "band", width = 0.175}', "unknown key 'width'"),
    ('options = {solver = "closed"}', 'options = {solvr = "closed"}', "unknown option 'solvr'"),
    ('n_terms = 6', 'n_term = 6', "unknown key 'n_term'"),
    ('seeds = [0, 1]', 'seeds = [0, 1]\nworkers = 2', "unknown key 'workers'"),
    ('bundled = "pumping"', 'bundled = "pumps"', "bundled must be one of"),
    ('decision = {rule = "min_jsf"}', 'decision = {rule = "min_jsf", band = 0.1}', "band applies to rule"),
    ('name = "LS"\nestimator = "ls"', 'name = "LS"\nestimator = "ls"\nconstraints = [{type = "points"}]',
     "takes no constraints"),
    ('name = "NN"\nestimator = "neural"', 'name = "NN"\nestimator = "neural"\nlambdas = [0.5]', "lambdas apply to"),
])
def test_bad_spec_is_refused_with_key_and_line(old, new, needle):
    text = _bad(TOML, old, new)
    with pytest.raises(gx.SpecError) as ei:
        gx.Grid.from_toml_text(text, source="spec.toml")
    msg = str(ei.value)
    assert needle in msg
    m = re.match(r"spec\.toml, line (\d+): ", msg)
    assert m, msg
    line = text.splitlines()[int(m.group(1)) - 1]
    # the line named holds the offending key (the last component of the error's path)
    key = [p for p in ei.value.path if isinstance(p, str)][-1]
    assert key in line, (msg, line)


def test_invalid_toml_names_its_line():
    with pytest.raises(gx.SpecError, match=r"^spec\.toml, line 4: invalid TOML"):
        gx.Grid.from_toml_text(_bad(TOML, "[[data]]", "[[data]\n"), source="spec.toml")


def test_python_specs_are_validated():
    with pytest.raises(gx.SpecError, match="cls needs at least one constraint"):
        gx.Variant("c", "cls")
    with pytest.raises(gx.SpecError, match="cannot be stored or hashed"):
        gx.Variant("u", "pe", constraints=gb.UserConstraint(lambda th: [th[0] <= 1]))
    with pytest.raises(gx.SpecError, match="use the data set's static points"):
        gx.Variant("p", "cls", constraints=gb.PassesThrough(gb.StaticPoints([1.0, 2.0], [1.0, 2.0])))
    with pytest.raises(gx.SpecError, match="unknown option 'generation'"):
        gx.Variant("g", "se-ga", options={"generation": 3})
    with pytest.raises(gx.SpecError, match="population"):
        gx.Variant("g", "se-ga", options={"population": 2})
    with pytest.raises(gx.SpecError, match="either given"):
        gx.StructureSpec("s")
    with pytest.raises(gx.SpecError, match="not among the candidates"):
        gx.StructureSpec("s", candidates={"ny": 1, "nu": 1}, n_terms=2, include=["u(k-3)"])
    ls = gx.Variant("a", "ls")
    data = [gx.DataSpec("p", bundled="pumping")]
    st = [gx.StructureSpec("s", terms=["y(k-1)", "u(k-1)"])]
    with pytest.raises(gx.SpecError, match="duplicated variants names"):
        gx.Grid(data, st, [ls, gx.Variant("a", "els")])
    with pytest.raises(gx.SpecError, match="identical to 'a'"):
        gx.Grid(data, st, [ls, gx.Variant("b", "ls")])
    d = gb.load_pumping()
    assert gx.DataSpec("mine", dataset=d).band == d.static.band  # carried on the points
    no_band = gx.DataSpec("mine", dataset=gb.Dataset(d.ident, d.valid, gb.StaticPoints(d.static.ubar, d.static.ybar)))
    with pytest.raises(gx.SpecError, match="have none: give band"):
        gx.Grid([no_band], st, [gx.Variant("pe", "pe")])


# --------------------------------------------------------------------------------------------
# running in-process and the store
# --------------------------------------------------------------------------------------------
def test_run_fills_the_store_and_rerun_skips_finished_cells(small_store):
    path, run = small_store
    df = gx.load_results(path)
    assert run.ran == run.cells == len(df) == 12 and run.skipped == 0
    assert df["key"].is_unique
    assert set(df["status"]) <= set(gx.STATUSES)
    again = gx.run_grid(python_grid(), path)
    assert again.ran == 0 and again.skipped == 12 and dict(again.counts) == dict(run.counts)
    pd.testing.assert_frame_equal(gx.load_results(path)[FIGURES], df[FIGURES])
    assert df.attrs["grid"] == "small" and df.attrs["n_cells"] == 12


def test_rows_hold_the_shared_evaluators_figures(small_store, pumping):
    path, _ = small_store
    df = gx.load_results(path)
    data = pumping["pumping"]
    r = df[(df.structure == "first-order") & (df.variant == "CLS")].iloc[0]
    assert r.status == "ok" and r.rule is None or pd.isna(r.rule)
    m = gb.Model(gb.parse_structure(list(r.terms)), r.theta)
    table = gb.evaluate({"m": m}, data).loc["m"]
    assert r.JS_ident == pytest.approx(table["JS_ident"], rel=1e-12)
    assert r.JS_valid == pytest.approx(table["JS_valid"], rel=1e-12)
    assert r.JSF == pytest.approx(table["JSF"], rel=1e-12)
    assert r.fit_valid == pytest.approx(table["fit_valid"], rel=1e-12)
    assert r.J1_valid == pytest.approx(gb.j1(m, data.valid), rel=1e-12)
    miss = np.abs(m.static_curve(data.static.ubar, y0=data.static.ybar) - data.static.ybar).max()
    assert r.static_miss == pytest.approx(miss, rel=1e-12)
    assert r.n_params == 4 and r.version == gb.__version__ and r.wall_time > 0
    # a Pareto cell keeps every member's figures, and its choice is one of them
    p = df[(df.structure == "made") & (df.variant == "PE")].iloc[0]
    mem = p.members
    assert len(mem["lambda1"]) == 4
    i = int(np.flatnonzero(mem["lambda1"] == p.lambda1)[0])
    assert mem["chosen"].tolist() == [float(k == i) for k in range(4)]  # the cell marks its choice, once
    assert mem["JSF"][i] == pytest.approx(p.JSF, rel=1e-9) and mem["JSF"][i] == np.min(mem["JSF"])
    assert mem["JS_valid"][i] == pytest.approx(p.JS_valid, rel=1e-9)
    assert mem["fit_valid"][i] == pytest.approx(p.fit_valid, rel=1e-9)
    assert p.rule == "min J_SF"
    # min J_SF (as min correlation) decides by no band: in_band unknown, as for least squares (it read True
    # whatever the J_SF: a band of 1e-5 for the data set, its stored cell reused, read True beside J_SF 6.6e-4)
    assert pd.isna(p.in_band)
    assert gx.leaderboard(df, rule="chosen").loc[("pumping", "made", "PE"), "in_band"] is pd.NA


def test_infeasible_diverged_and_failed_cells_are_rows(tmp_path):
    d = gb.load_pumping()
    short = gb.Dataset(d.ident.slice(0, 12), d.valid, d.static)
    g = gx.Grid(
        data=[gx.DataSpec("pumping", bundled="pumping"), gx.DataSpec("short", dataset=short, band=0.031)],
        structures=[gx.StructureSpec("quadratic-y", terms=["y(k-1)^2", "y(k-2)^2", "u(k-1)", "1"]),
                    gx.StructureSpec("wide", terms=["y(k-1)", "y(k-2)", "y(k-3)", "u(k-1)", "u(k-2)", "u(k-3)",
                                                    "u(k-1)y(k-1)", "u(k-2)^2", "1"])],
        variants=[gx.Variant("LS", "ls"),
                  gx.Variant("contradiction", "cls", constraints=[{"type": "clusters", "bounds": {"Sy": [0.5, 0.5]}},
                                                                  {"type": "clusters", "bounds": {"Sy": [0.6, 0.6]}}])])
    run = gx.run_grid(g, tmp_path / "s.sqlite")
    df = gx.load_results(tmp_path / "s.sqlite").set_index(["data", "structure", "variant"])
    assert run.ran == 8
    assert df.loc[("pumping", "quadratic-y", "LS"), "status"] == "diverged"
    assert "diverges" in df.loc[("pumping", "quadratic-y", "LS"), "message"]
    assert np.isinf(df.loc[("pumping", "quadratic-y", "LS"), "JS_valid"])
    assert df.loc[("pumping", "wide", "contradiction"), "status"] == "infeasible"
    assert "inconsistent" in df.loc[("pumping", "wide", "contradiction"), "message"]
    assert df.loc[("pumping", "wide", "LS"), "status"] == "ok"
    short_rows = df.loc["short"]
    assert (short_rows.loc["wide", "status"] == "failed").all()
    assert "too short" in short_rows.loc[("wide", "LS"), "message"] or "too few" in short_rows.loc[("wide", "LS"), "message"]
    assert sum(run.counts.values()) == 8


def _bytes(p: Path) -> bytes:
    return p.read_bytes()


def _shifted_pumping() -> gb.Dataset:
    d = gb.load_pumping()
    return gb.Dataset(d.ident, d.valid, gb.StaticPoints(d.static.ubar, d.static.ybar + 1e-9))


def test_a_data_set_name_that_now_reads_other_data_is_refused_untouched(small_store, tmp_path):
    path, _ = small_store
    before = _bytes(path)
    g = python_grid()
    other = gx.Grid([gx.DataSpec("pumping", dataset=_shifted_pumping(), band=0.031)], g.structures[:1], g.variants[:1],
                    name="other")
    with pytest.raises(gx.StoreError, match=r"data set 'pumping' of this spec reads other data.*new name"):
        gx.run_grid(other, path)
    assert _bytes(path) == before
    # the same data under a new name is a new data set: its cells are the store's (keys hash content)
    renamed = gx.Grid([gx.DataSpec("plant", bundled="pumping")], g.structures, g.variants, g.seeds, name="renamed")
    copy = tmp_path / "copy.sqlite"
    copy.write_bytes(before)
    run = gx.run_grid(renamed, copy)
    assert run.ran == 0 and run.skipped == 12 and run.spec == 2
    assert any("'plant' is new to the store (the same data as 'pumping'" in n for n in run.notes)
    assert set(gx.load_results(copy)["data"]) == {"plant"}
    assert set(gx.load_results(copy, spec=1)["data"]) == {"pumping"}


def test_store_left_by_a_killed_writer_is_refused_without_folding_its_log(tmp_path):
    """A store whose writer was killed still has its rows in the write-ahead log; refusing it
    (here: its data set 'pumping' held other data) must not fold that log into the file
    (nothing is written to a refused store)."""
    import signal
    import subprocess
    import sys

    path = tmp_path / "killed.sqlite"
    code = (f"import os, signal\nimport graybox as gb\nfrom graybox import experiments as gx\n"
            f"from graybox.experiments._store import ResultStore\nd = gb.load_pumping()\n"
            f"d = gb.Dataset(d.ident, d.valid, gb.StaticPoints(d.static.ubar, d.static.ybar + 1e-9))\n"
            f"g = gx.Grid([gx.DataSpec('pumping', dataset=d, band=0.031)], "
            f"[gx.StructureSpec('s', terms=['y(k-1)', 'u(k-1)', '1'])], [gx.Variant('LS', 'ls')], name='other')\n"
            f"c = g.cells()\n"
            f"ResultStore.open({str(path)!r}, grid_name='other', fingerprint=g.fingerprint(c), spec=g.to_dict(), "
            f"cells=c, version=gb.__version__)\nos.kill(os.getpid(), signal.SIGKILL)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True)
    assert proc.returncode == -signal.SIGKILL, proc.stderr
    wal = Path(str(path) + "-wal")
    assert wal.exists() and wal.stat().st_size > 0  # the store's tables are still in the log
    before, wal_before = _bytes(path), _bytes(wal)
    with pytest.raises(gx.StoreError, match="reads other data"):
        gx.run_grid(python_grid(), path)
    assert _bytes(path) == before and _bytes(wal) == wal_before
    assert len(gx.load_results(path)) == 0  # readable, and reading it writes nothing either
    assert _bytes(path) == before and _bytes(wal) == wal_before


@pytest.mark.parametrize("kind", ["text", "empty", "foreign", "corrupt", "header"])
def test_foreign_or_corrupt_files_are_refused_untouched(kind, small_store, tmp_path):
    p = tmp_path / "store.sqlite"
    if kind == "text":
        p.write_text("ident,valid\n1,2\n")
    elif kind == "empty":
        p.write_bytes(b"")
    elif kind == "foreign":
        con = sqlite3.connect(p)
        con.execute("CREATE TABLE cells (key TEXT, value REAL)")
        con.execute("INSERT INTO cells VALUES ('a', 1.0)")
        con.commit()
        con.close()
    elif kind == "header":  # an SQLite header and nothing readable after it
        p.write_bytes(b"SQLite format 3\x00" + bytes(range(256)) * 40)
    else:
        src = _bytes(small_store[0])
        page = 4096
        garbled = bytearray(src)
        garbled[page: page + 512] = bytes(range(256)) * 2  # a page of the cells table overwritten
        p.write_bytes(bytes(garbled))
    before = _bytes(p)
    with pytest.raises(gx.StoreError, match="nothing was written|damaged"):
        gx.run_grid(python_grid(), p)
    with pytest.raises(gx.StoreError):
        gx.load_results(p)
    assert _bytes(p) == before
    assert not Path(str(p) + "-wal").exists() or kind in ("corrupt", "header")


def test_store_writes_arrays_as_the_same_json_as_lists():
    """Rows carry the Pareto members as numpy arrays (cheaper for a Dask task to return); the store
    writes exactly the text the lists would give."""
    import json

    from graybox.experiments._store import encode_value

    lists = {"JS": [0.1, float("inf"), 1e-300], "failure": ["", "no equilibrium", ""]}
    arrays = {"JS": np.array(lists["JS"]), "failure": lists["failure"]}
    assert encode_value("members", arrays) == encode_value("members", lists) == json.dumps(lists)
    assert encode_value("theta", np.array([1.0, -2.5])) == "[1.0, -2.5]"
    with pytest.raises(TypeError, match="object"):
        encode_value("members", {"x": object()})


def test_store_log_stays_short_so_closing_is_quick(tmp_path, pumping):
    """The write-ahead log is folded into the database as the rows come, not all at close."""
    from graybox.experiments._cell import failed_row
    from graybox.experiments._store import WAL_PAGES

    g = python_grid()
    cells = g.cells()
    path = tmp_path / "s.sqlite"
    with ResultStore.open(path, fingerprint=g.fingerprint(cells), grid_name=g.name, spec=g.to_dict(), cells=cells,
                          version=gb.__version__) as st:
        page = st._conn.execute("PRAGMA page_size").fetchone()[0]
        for i in range(400):  # rows of two pages or more: 800 pages of log in all
            row = failed_row(cells[i % len(cells)], "x" * (2 * page) + str(i))
            st.write(dict(row, key=f"{row['key']}-{i}"))
        wal = Path(str(path) + "-wal").stat().st_size
    assert wal <= 32 + (WAL_PAGES + 8) * (page + 24)
    assert len(gx.load_results(path, spec="all")) == 400  # rows of no spec: only "all" shows them


def test_retry_failed_reruns_only_failed_cells(tmp_path, pumping):
    g = gx.Grid(python_grid().data, python_grid().structures[:1], python_grid().variants[:2], name="tiny")
    path = tmp_path / "s.sqlite"
    cells = g.cells(pumping)
    with ResultStore.open(path, fingerprint=g.fingerprint(cells), grid_name=g.name, spec=g.to_dict(), cells=cells,
                          version=gb.__version__) as st:
        st.write(gx._cell.failed_row(cells[0], "the worker process died twice (simulated)"))
    run = gx.run_grid(g, path)
    assert run.ran == 1 and dict(run.counts)["failed"] == 1
    run = gx.run_grid(g, path, retry_failed=True)
    assert run.ran == 1 and dict(run.counts) == {"ok": 2, "infeasible": 0, "diverged": 0, "failed": 0}
    assert gx.load_results(path)["key"].is_unique


# --------------------------------------------------------------------------------------------
# reports
# --------------------------------------------------------------------------------------------
def test_leaderboard_is_dsf_on_the_validation_record(small_store):
    path, _ = small_store
    df = gx.load_results(path)
    lb = gx.leaderboard(df)
    assert lb.index.names == ["data", "structure", "variant"] and len(lb) == 2 * 5
    band = 0.031
    for (d, s, v), row in lb.iterrows():
        g = df[(df.data == d) & (df.structure == s) & (df.variant == v)]
        cands = []
        for _, r in g.iterrows():
            if r.members is not None:
                cands += [(js, jsf) for js, jsf in zip(r.members["JS_valid"], r.members["JSF"])]
            elif r.status == "ok":
                cands.append((r.JS_valid, r.JSF))
        inside = [js for js, jsf in cands if jsf <= band and np.isfinite(js)]
        if inside:
            assert row.JS_valid == min(inside) and row.JSF <= band
        else:
            assert np.isnan(row.JS_valid) and np.isnan(row["rank"])
    ranked = lb.dropna(subset=["rank"])
    assert list(ranked["rank"]) == sorted(ranked["rank"])
    chosen = gx.leaderboard(df, rule="chosen")
    ok = df[df.status == "ok"].groupby(["data", "structure", "variant"])["JS_valid"].min()
    pd.testing.assert_series_equal(chosen["JS_valid"].dropna().sort_index(), ok.sort_index(), check_names=False)
    t = gx.heatmap_table(df, value="JSF")
    assert list(t.index) == ["first-order", "made"] and list(t.columns) == ["LS", "CLS", "PE band", "PE", "NN"]
    with pytest.raises(ValueError, match="rule must be"):
        gx.leaderboard(df, rule="best")


def test_figures_and_report_files(small_store, tmp_path):
    path, _ = small_store
    df = gx.load_results(path)
    for fig in (gx.plot_scatter(df), gx.plot_fronts(df), gx.plot_heatmap(df, value="JS_valid")):
        assert isinstance(fig, Figure) and fig.axes
    fronts = gx.plot_fronts(df, structures=["made"])
    assert len([a for a in fronts.axes if a.get_visible()]) == 1
    assert len(fronts.axes[0].lines) > 5  # members, front lines and chosen markers
    out = tmp_path / "report"
    written = gx.write_report(path, out)
    names = {p.name for p in written}
    assert {"cells.csv", "leaderboard.csv", "summary.txt", "scatter.png", "fronts_pumping.png",
            "heatmap_pumping.png", "heatmap_pumping.csv"} <= names
    cells = pd.read_csv(out / "cells.csv")
    assert len(cells) == 12 and cells["key"].is_unique
    assert "12 of 12 cells" in (out / "summary.txt").read_text()


# --------------------------------------------------------------------------------------------
# CLI
# --------------------------------------------------------------------------------------------
def test_cli_init_run_report(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["grid", "init"]) == 0
    example = capsys.readouterr().out
    g = gx.Grid.from_toml_text(example)
    assert len(g.structures) >= 3 and len(g.variants) >= 6 and "#" in example
    spec = tmp_path / "spec.toml"
    spec.write_text(TOML)
    assert main(["grid", "run", str(spec), "--store", "r.sqlite"]) == 0
    out = capsys.readouterr().out
    assert "12 cells, 0 reused, 12 run now" in out and " ok" in out and "failed" in out
    assert main(["grid", "run", str(spec), "--store", "r.sqlite"]) == 0
    out = capsys.readouterr().out
    assert "12 cells, 12 reused from r.sqlite, 0 to run" in out and "12 reused, 0 run now" in out
    # one variant more in the spec: only its cells run (a structure each), the store grows
    spec.write_text(TOML + '\n[[variants]]\nname = "ELS"\nestimator = "els"\n')
    assert main(["grid", "run", str(spec), "--store", "r.sqlite"]) == 0
    out = capsys.readouterr().out
    assert "14 cells, 12 reused, 2 run now" in out and "a new spec for this store (spec 2)" in out
    spec.write_text(TOML)
    undrawn_figures(monkeypatch)  # its leaderboard.csv is read; test_figures_and_report_files draws such a report
    assert main(["grid", "report", "r.sqlite", "--out", "rep"]) == 0
    assert (tmp_path / "rep" / "leaderboard.csv").is_file()
    (tmp_path / "notes.txt").write_text("not a store")
    assert main(["grid", "run", str(spec), "--store", "notes.txt"]) == 2
    assert "not an SQLite database" in capsys.readouterr().err
    spec.write_text(_bad(TOML, 'estimator = "ls"', 'estimator = "lsq"'))
    assert main(["grid", "run", str(spec), "--store", "x.sqlite"]) == 2
    assert re.search(r"line \d+: variants\[0\]\.estimator", capsys.readouterr().err)
    assert not (tmp_path / "x.sqlite").exists()


def test_cli_refuses_zero_workers_and_names_an_unreachable_scheduler(tmp_path, capsys, monkeypatch):
    from graybox.experiments import _executors

    monkeypatch.chdir(tmp_path)
    spec = tmp_path / "spec.toml"
    spec.write_text(TOML)
    for flag in ("--workers", "--processes"):  # 0 used to mean "in-process" without a word
        assert main(["grid", "run", str(spec), "--store", "z.sqlite", flag, "0"]) == 2
        assert f"{flag} must be an integer >= 1, got 0" in capsys.readouterr().err
    # a cell time limit only where a cell can be stopped: the message names the flag to add
    assert main(["grid", "run", str(spec), "--store", "z.sqlite", "--cell-time-limit", "60"]) == 2
    assert "cell_time_limit needs worker processes" in (err := capsys.readouterr().err) and "--processes N" in err
    assert not (tmp_path / "z.sqlite").exists()
    monkeypatch.setattr(_executors, "CONNECT_TIMEOUT", "1s")
    assert main(["grid", "run", str(spec), "--store", "s.sqlite", "--scheduler", "tcp://127.0.0.1:1"]) == 2
    assert "cannot reach the Dask scheduler at tcp://127.0.0.1:1" in capsys.readouterr().err


def test_public_api_is_documented():
    import inspect

    for name in gx.__all__:
        obj = getattr(gx, name)
        if not (inspect.isfunction(obj) or inspect.isclass(obj)):
            continue
        assert obj.__doc__ and obj.__doc__.strip(), name
        funcs = [obj] if inspect.isfunction(obj) else [
            m for n, m in inspect.getmembers(obj, inspect.isfunction)
            if not n.startswith("_") and m.__qualname__.startswith(obj.__name__ + ".")]
        for f in funcs:
            doc = f.__doc__ or ""
            missing = [p.name for p in inspect.signature(f).parameters.values()
                       if p.name not in ("self", "cls") and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
                       and p.name not in doc]
            assert doc and not missing, f"{name}.{f.__name__}: undocumented {missing}"


def test_se_dsf_variant_gives_the_direct_dsf_model(tmp_path):
    terms = ["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)", "1"]
    lam = [0.05, 0.3, 1.0]
    g = gx.Grid([gx.DataSpec("pumping", bundled="pumping")], [gx.StructureSpec("s", terms=terms)],
                [gx.Variant("direct", "se-dsf", lambdas=lam),
                 gx.Variant("direct, wide band", "se-dsf", lambdas=lam, options={"band": 0.5})], name="dsf")
    gx.run_grid(g, tmp_path / "dsf.sqlite")
    df = gx.load_results(tmp_path / "dsf.sqlite").set_index("variant")
    data = gb.load_pumping()
    for v, band in (("direct", df.loc["direct", "band"]), ("direct, wide band", 0.5)):
        r = df.loc[v]
        assert r["status"] == "ok" and r["estimator"] == "se-dsf"
        res = gb.se_dsf(gb.parse_structure(terms), data, band=band, lambdas=lam)
        np.testing.assert_array_equal(r["theta"], res.model.theta)  # the same model as the function gives
        assert r["rule"] == ("D_SF (direct)" if res.in_band else "min J_SF (band infeasible)")
        assert bool(r["in_band"]) == res.in_band
        if res.in_band:
            assert r["JSF"] <= band * (1 + 1e-9)
    # a wider band allows a smaller free-run error
    assert df.loc["direct, wide band", "JS_ident"] <= df.loc["direct", "JS_ident"] * (1 + 1e-9)


def test_se_dsf_variant_refuses_a_decision_maker_and_unknown_options():
    with pytest.raises(gx.SpecError, match="gives one model.*band = "):
        gx.Variant("v", "se-dsf", decision={"rule": "dsf"})
    with pytest.raises(gx.SpecError, match="unknown option 'max_nfev' for estimator 'se-dsf'"):
        gx.Variant("v", "se-dsf", options={"max_nfev": 3})
    with pytest.raises(gx.SpecError, match="band"):
        gx.Variant("v", "se-dsf", options={"band": -1.0})


def test_a_made_structure_takes_every_input_of_the_data_set(tmp_path):
    """nu = 2 on a two-input data set: the candidates hold both inputs' lags (as nu = {u1 = 2, u2 = 2}),
    and n_terms is not bounded by a single input's candidate count."""
    n_siso = len(gb.Candidates(2, 2, degree=2))
    g = gx.Grid([gx.DataSpec("miso", bundled="pumping_miso")],
                [gx.StructureSpec("one nu", candidates={"ny": 2, "nu": 2, "degree": 2}, n_terms=n_siso + 2,
                                  include=["1"]),
                 gx.StructureSpec("per input", candidates={"ny": 2, "nu": {"u1": 2, "u2": 2}, "degree": 2},
                                  n_terms=n_siso + 2, include=["1"])],
                [gx.Variant("ls", "ls")], name="miso-made")
    gx.run_grid(g, tmp_path / "m.sqlite")
    df = gx.load_results(tmp_path / "m.sqlite").set_index("structure")
    assert set(df["status"]) == {"ok"}
    assert df.loc["one nu", "terms"] == df.loc["per input", "terms"]
    assert {"u1", "u2"} <= {gb.parse_term(t).factors[0][0] for t in df.loc["one nu", "terms"] if t != "1"}


def test_two_input_csv_data_with_repeated_static_measurements(tmp_path):
    """A user's two-input rig in CSV files, described in TOML: u is a list of columns, and the static
    file repeats each operating point (repeats = "mean" averages them, else the spec names the lines)."""
    d = gb.load_pumping_miso()
    for name, rec in (("ident", d.ident), ("valid", d.valid)):
        pd.DataFrame({"t": rec.t, "n1": rec.u[:, 0], "n2": rec.u[:, 1], "p": rec.y}).to_csv(
            tmp_path / f"{name}.csv", index=False, float_format="%.17g")
    ub, yb = d.static.ubar, d.static.ybar
    pd.DataFrame({"n1": np.r_[ub[:, 0], ub[:, 0]], "n2": np.r_[ub[:, 1], ub[:, 1]],
                  "p": np.r_[yb - 0.01, yb + 0.01]}).to_csv(tmp_path / "static.csv", index=False, float_format="%.17g")
    text = """name = "rig"
[[data]]
name = "rig"
band = 0.031
ident = {path = "ident.csv", u = ["n1", "n2"], y = "p", time = "t"}
valid = {path = "valid.csv", u = ["n1", "n2"], y = "p", time = "t"}
static = {path = "static.csv", u = ["n1", "n2"], y = "p", repeats = "mean"}
[[structures]]
name = "made"
candidates = {ny = 1, nu = 1, degree = 2}
n_terms = 8
include = ["1"]
[[variants]]
name = "PE"
estimator = "pe"
options = {solver = "closed"}
"""
    (tmp_path / "spec.toml").write_text(text)
    g = gx.Grid.from_toml(tmp_path / "spec.toml")
    loaded = g.load_data()["rig"]
    assert loaded.input_names == ("n1", "n2") and len(loaded.static) == len(d.static)
    order = np.lexsort((ub[:, 1], ub[:, 0]))  # from_repeats sorts the points
    np.testing.assert_allclose(loaded.static.ybar, yb[order], atol=1e-12)
    gx.run_grid(g, tmp_path / "rig.sqlite")
    df = gx.load_results(tmp_path / "rig.sqlite")
    assert list(df["status"]) == ["ok"] and np.isfinite(df["JSF"].iloc[0])
    (tmp_path / "spec.toml").write_text(text.replace(', repeats = "mean"', ""))
    with pytest.raises(gx.SpecError, match="same input level.*repeats"):
        gx.Grid.from_toml(tmp_path / "spec.toml").load_data()


def test_input_names_are_part_of_the_data_and_of_made_structures():
    """Same numbers, other input names: other cell keys (a made structure's terms carry the names),
    and the structure cache does not mix them up; default names hash as before."""
    from graybox.experiments._cell import make_structure

    d = gb.load_pumping_miso()
    renamed = gb.Dataset(*(gb.Record(r.u, r.y, Ts=r.Ts, input_names=("a", "b")) for r in (d.ident, d.valid)),
                         gb.StaticPoints(d.static.ubar, d.static.ybar, input_names=("a", "b")))
    plain = gb.Dataset(d.ident, d.valid, d.static)
    assert data_fingerprint(renamed) != data_fingerprint(plain)
    spec = gx.StructureSpec("m", candidates={"ny": 1, "nu": 1, "degree": 2}, n_terms=5, include=["1"])
    st_plain = make_structure(spec.content(), plain, data_fingerprint(plain))
    st_named = make_structure(spec.content(), renamed, data_fingerprint(renamed))
    assert set(st_plain.input_names) == {"u1", "u2"} and set(st_named.input_names) == {"a", "b"}
    # the spec checks included terms and per-input delays against the inputs they name
    gx.StructureSpec("n", candidates={"ny": 1, "nu": 2, "delay": {"n1": 1, "n2": 2}}, n_terms=4, include=["n1(k-1)"])
    gx.StructureSpec("n", candidates={"ny": 1, "nu": 2}, n_terms=4, include=["n1(k-1)"])


def test_a_band_for_a_data_set_the_results_do_not_hold_is_refused_by_name(small_store, tmp_path):
    # a mapping's misspelt key left the data set meant to the store's own band, without a word (hunt40b)
    path, _ = small_store
    held = gx.load_results(path)["data"].iloc[0]
    good = gx.leaderboard(path, band={held: 0.031})
    for call in (lambda b: gx.leaderboard(path, band=b), lambda b: gx.heatmap_table(path, band=b),
                 lambda b: gx.plot_fronts(path, band=b), lambda b: gx.plot_heatmap(path, band=b),
                 lambda b: gx.write_report(path, tmp_path / "r", band=b)):
        with pytest.raises(ValueError, match=r"band names data sets the results do not hold: 'pumpin' \(they hold"):
            call({held: 0.031, "pumpin": 0.031})
    assert len(good)


def test_fronts_and_scatter_draw_each_variants_own_band_where_they_differ(small_store):
    # both shaded one band per data set (its first cell's), while the leaderboard judges each group by its
    # own cells' band: a variant with a band of its own was drawn against another's
    path, _ = small_store
    df = gx.load_results(path)
    d = df["data"].iloc[0]
    own = df["variant"] == df["variant"].iloc[0]
    df.loc[own, "band"] = 1e-3
    other = float(df.loc[~own, "band"].iloc[0])
    fig = gx.plot_scatter(df, data=d)
    labels = fig.axes[0].get_legend_handles_labels()[1]
    assert f"B = {1e-3:g} ({df['variant'].iloc[0]})" in labels
    assert any(lb.startswith(f"B = {other:g} (") for lb in labels)
    assert not [p for p in fig.axes[0].patches]  # no region is every variant's: nothing shaded
    fronts = gx.plot_fronts(df, data=d)
    assert "the variants' own bands" in fronts._suptitle.get_text()
    same = gx.plot_fronts(gx.load_results(path), data=d)  # one band: shaded, as before
    assert f"J_SF ≤ B = {other:g}" in same._suptitle.get_text()


@pytest.mark.parametrize("key", [3, "3", "y"])
def test_a_cluster_bound_that_names_no_cluster_is_refused_with_the_spec(key):
    # was: a key that is no cluster name (a TOML table turns 3 into "3") passed the spec and failed each cell once
    # a structure read it
    with pytest.raises(gx.SpecError, match="cluster bounds name their clusters"):
        gx.Variant("bounded", "cls", constraints=[{"type": "clusters", "bounds": {key: [None, 0.99]}}])
    gx.Variant("bounded", "cls", constraints=[{"type": "clusters", "bounds": {"Sy": [None, 0.99]}}])


_CLUSTER_SPEC = """name = "g"
[[data]]
name = "pumping"
bundled = "pumping"
[[structures]]
name = "first"
terms = ["y(k-1)", "u(k-1)", "1"]
STRUCTURE
[[variants]]
name = "V"
estimator = "cls"
constraints = [{type = "clusters", bounds = {NAME = {upper = 1}}}]
"""


def test_a_cluster_bound_no_given_structure_has_is_refused_with_the_spec_naming_the_key_and_line():
    # was: Sz passed the spec and every cell failed with "no cluster 'Sz' in this structure; it has ['Σ0', 'Σu',
    # 'Σy']"
    with pytest.raises(gx.SpecError, match="cluster 'Sz' of variant 'V' is a cluster of no structure") as info:
        gx.Grid.from_toml_text(_CLUSTER_SPEC.replace("STRUCTURE", "").replace("NAME", "Sz"))
    assert info.value.path == ("variants", 0, "constraints", 0, "bounds", "Sz") and info.value.line == 12
    assert "Σ0, Σu, Σy" in str(info.value)
    gx.Grid.from_toml_text(_CLUSTER_SPEC.replace("STRUCTURE", "").replace("NAME", "Sy"))
    # a cluster one given structure has and another lacks: a cross the grid may mean, its cells say why
    fir = '[[structures]]\nname = "fir"\nterms = ["u(k-1)", "1"]'
    gx.Grid.from_toml_text(_CLUSTER_SPEC.replace("STRUCTURE", fir).replace("NAME", "Sy"))
    # a structure FROLS makes has its clusters only once made: the name is left to its cells
    made = '[[structures]]\nname = "made"\ncandidates = {ny = 1, nu = 1, degree = 2}\nn_terms = 3'
    gx.Grid.from_toml_text(_CLUSTER_SPEC.replace("STRUCTURE", made).replace("NAME", "Sz"))


@pytest.mark.parametrize("call, arg, said", [
    ("leaderboard", 42, "results must be a frame"), ("grid_status", None, "store must be a file"),
    ("load_results", 3.5, "store must be a file"), ("write_report", 7, "results must be a frame"),
])
def test_a_store_that_is_no_path_is_refused_naming_the_argument(call, arg, said, tmp_path):
    # was Python's own "expected str, bytes or os.PathLike object, not int", naming no argument
    fn = getattr(gx, call)
    with pytest.raises(TypeError, match=said):
        fn(arg, tmp_path / "out") if call == "write_report" else fn(arg)


def test_models_equal_to_round_off_share_a_rank(small_store):
    # the same model fitted twice (least squares and a CLS whose constraint is not active, two solvers) scores J_S
    # valid 1e-12 apart: the leaderboard ranked them 1, 2, 3 by round-off. They share a rank, listed by fewer
    # parameters then in the grid's order; the next rank counts the models before it
    path, _ = small_store
    df = gx.load_results(path)
    df = df[(df.status == "ok") | (df.variant == "NN")].copy()
    df["status"] = "ok"
    js = {("first-order", "LS"): 2.0 + 2e-12, ("first-order", "CLS"): 2.0, ("first-order", "PE band"): 2.0 - 1e-12,
          ("first-order", "PE"): 2.0 * (1 + 1e-6), ("first-order", "NN"): 1.0, ("made", "LS"): 2.0 + 1e-12,
          ("made", "CLS"): 3.0, ("made", "PE band"): 3.0 + 3e-12, ("made", "PE"): 4.0, ("made", "NN"): np.inf}
    df["JS_valid"] = [js[(s, v)] for s, v in zip(df.structure, df.variant)]
    lb = gx.leaderboard(df, rule="chosen")
    n_params = lb["n_params"].to_dict()
    got = [(s, v, r) for (_, s, v), r in lb["rank"].items()]
    # 1.0 alone first; the four at 2.0 to round-off share rank 2, the made LS (6 parameters) after the three
    # first-order ones (4), which keep the grid's order; 2.000002 is another result
    assert n_params[("pumping", "made", "LS")] > n_params[("pumping", "first-order", "LS")]
    assert got[:8] == [("first-order", "NN", 1), ("first-order", "LS", 2), ("first-order", "CLS", 2),
                       ("first-order", "PE band", 2), ("made", "LS", 2), ("first-order", "PE", 6),
                       ("made", "CLS", 7), ("made", "PE band", 7)]
    assert got[8][:2] == ("made", "PE") and got[8][2] == 9 and np.isnan(got[9][2])


def test_compare_results_labels_keep_the_stores_variants_apart(small_store, tmp_path):
    # labels "x" and "x: PE" made store one's "PE band" and a store two variant "band" both 'x: PE band', one group
    # of the leaderboard with both stores' cells: a label holding the separator ': ' is refused
    import shutil
    path, _ = small_store
    other = tmp_path / "other.sqlite"
    shutil.copy(path, other)
    with pytest.raises(ValueError, match="labels must not hold ': '.*'x: PE'"):
        gx.compare_results([path, other], labels=["x", "x: PE"])
    named = tmp_path / "run: 2.sqlite"  # a file name, the label the command line gives it: ': ' read as ':'
    shutil.copy(path, named)
    assert set(gx.compare_results([path, named])["store"]) == {"small", "run:2"}
    df = gx.compare_results([path, named], labels=["x", "x:PE"])
    lb = gx.leaderboard(df)
    assert len(lb) == 2 * len(gx.leaderboard(path)) and set(df["store"]) == {"x", "x:PE"}


def test_a_no_band_rules_in_band_written_by_an_older_graybox_reads_missing(small_store, tmp_path):
    # before 7937b3f8 a min-J_SF or min-correlation cell stored in_band = 1 whatever its J_SF; its key is unchanged,
    # so a store of then is never rerun, and load_results said in_band True beside J_SF far outside the band
    import shutil
    path, _ = small_store
    old = tmp_path / "old.sqlite"
    shutil.copy(path, old)
    with sqlite3.connect(old) as con:
        n = con.execute("UPDATE cells SET in_band = 1 WHERE variant = 'PE' AND rule = 'min J_SF'").rowcount
    con.close()
    assert n == 2  # one cell per structure: a deterministic estimator runs one seed
    now, then = gx.load_results(path), gx.load_results(old)
    pe = (then["variant"] == "PE").to_numpy()
    assert then.loc[pe, "in_band"].isna().all()
    pd.testing.assert_series_equal(then["in_band"], now["in_band"])  # the D_SF cells' True / False as written
    assert gx.leaderboard(old, rule="chosen").xs("PE", level="variant")["in_band"].isna().all()


def test_all_specs_name_each_meaning_once(tmp_path):
    # spec 1's least squares named "PE (spec 2)" and spec 2's PE, another variant than spec 1's "PE", read with
    # spec="all" as "PE (spec 2)" too: the leaderboard held an LS model and a PE front in one group
    path = tmp_path / "s.sqlite"

    def grid(variants):
        return gx.Grid(name="g", data=[gx.DataSpec("pumping", bundled="pumping", band=1.0)],
                       structures=[gx.StructureSpec("fo", terms=["y(k-1)", "u(k-1)", "1"])], variants=variants)

    pe = {"estimator": "pe", "options": {"solver": "closed"}, "decision": gx.DecisionRule("min_jsf")}
    gx.run_grid(grid([gx.Variant("PE", lambdas=[1.0], **pe), gx.Variant("PE (spec 2)", "ls")]), path)
    gx.run_grid(grid([gx.Variant("PE", lambdas=[0.5], **pe)]), path)
    df = gx.load_results(path, spec="all")
    assert len(df) == 3 and df["variant"].is_unique, df["variant"].tolist()
    assert df.set_index("estimator")["variant"]["ls"] == "PE (spec 2)"  # a name that has one meaning stays itself
    assert df.loc[df["lambda1"] == 1.0, "variant"].item() == "PE (spec 1)"
    assert df.loc[df["lambda1"] == 0.5, "variant"].item().startswith("PE (spec 2, variant ")
    assert (gx.leaderboard(df)["cells"] == 1).all()


def test_compare_results_tells_apart_structures_two_stores_define_differently(small_store, tmp_path):
    # store two's "first-order" has other terms than the small store's: compare_results showed both as one
    # structure, one heat-map row and one leaderboard structure for two models of different terms
    path, _ = small_store
    other = tmp_path / "other.sqlite"
    gx.run_grid(gx.Grid(name="o", data=[gx.DataSpec("pumping", bundled="pumping")],
                        structures=[gx.StructureSpec("first-order", terms=["y(k-1)", "u(k-1)", "1"]),
                                    gx.StructureSpec("made", candidates={"ny": 2, "nu": 2, "degree": 2,
                                                                         "max_y_power": 1}, n_terms=6, include=["1"])],
                        variants=[gx.Variant("LS", "ls")]), other)
    df = gx.compare_results([path, other], labels=["s", "o"])
    got = {(st, v): tuple(t) for st, v, t in zip(df["structure"], df["variant"], df["terms"]) if v.endswith(": LS")}
    assert got[("first-order (o)", "o: LS")] == ("y(k-1)", "u(k-1)", "1")
    assert len(got[("first-order (s)", "s: LS")]) == 4
    assert got[("made", "o: LS")] == got[("made", "s: LS")]  # one meaning in both stores: one name
    assert set(gx.heatmap_table(df).index) == {"first-order (s)", "first-order (o)", "made"}
    # the same terms in another order, and a product written the other way round, are the same structure
    same = tmp_path / "same.sqlite"
    gx.run_grid(gx.Grid(name="o", data=[gx.DataSpec("pumping", bundled="pumping")],
                        structures=[gx.StructureSpec("first-order", terms=["1", "y(k-1)u(k-1)", "u(k-1)", "y(k-1)"])],
                        variants=[gx.Variant("LS", "ls")]), same)
    assert set(gx.compare_results([path, same], labels=["s", "o"])["structure"]) == {"first-order", "made"}


def test_all_specs_keep_a_band_free_cell_under_each_data_set_that_shares_it(tmp_path):
    # two data sets of one content with two bands share their band-free cells (least squares: one key); read with
    # spec="all", each cell was one row under the first data set name, and "loose" had no LS at all
    path = tmp_path / "s.sqlite"
    gx.run_grid(gx.Grid(name="two bands", data=[gx.DataSpec("tight", bundled="pumping", band=0.01),
                                                gx.DataSpec("loose", bundled="pumping", band=0.5)],
                        structures=[gx.StructureSpec("fo", terms=["y(k-1)", "u(k-1)", "1"])],
                        variants=[gx.Variant("LS", "ls")]), path)
    latest, every = gx.load_results(path), gx.load_results(path, spec="all")
    assert latest["key"].nunique() == 1 and every.attrs["n_cells"] == latest.attrs["n_cells"] == 2
    cols = ["data", "structure", "variant", "status", "band", "JS_valid"]
    pd.testing.assert_frame_equal(every[cols], latest[cols])
    assert set(gx.leaderboard(every, rule="chosen").index.get_level_values("data")) == {"tight", "loose"}


def test_candidates_mark_only_the_chosen_member_not_a_neighbour_of_close_lambda():
    """Two members whose λ differ by 1e-9 (np.isclose takes them for one): only the member the cell chose is
    marked chosen, by its index (``members["chosen"]``), else by λ's exact value (stores written before)."""
    from graybox.experiments._report import _candidates

    lam = [0.25, 0.25 + 1e-9, 0.5]
    members = {"lambda1": np.array(lam), "J1": np.ones(3), "JS": np.ones(3), "JSF": np.ones(3),
               "JS_valid": np.ones(3), "failure": ["", "", ""]}
    row = {"data": "d", "structure": "s", "variant": "PE", "lambda1": lam[1], "seed": 0, "status": "ok",
           "JS_ident": 1.0, "JS_valid": 1.0, "JSF": 1.0, "fit_valid": 0.0, "n_params": 2, "band": np.nan}
    old = _candidates(pd.DataFrame([{**row, "members": members}]))
    assert old["chosen"].tolist() == [False, True, False]
    marked = {**members, "chosen": np.array([1.0, 0.0, 0.0])}  # the index wins over λ
    assert _candidates(pd.DataFrame([{**row, "members": marked}]))["chosen"].tolist() == [True, False, False]


def test_ctrl_c_inside_a_compiled_kernel_stops_an_in_process_grid_and_stores_no_failed_cell(tmp_path, monkeypatch):
    # Ctrl-C while an in-process `graybox grid run` was inside a numba kernel (se-ga's _batch_sse) reached the cell
    # as SystemError("CPUDispatcher(...) returned a result with an exception set"), caused by the KeyboardInterrupt:
    # run_cell stored the cell as failed and the grid went on to its end (exit 0), so the user's Ctrl-C was lost
    # and the next run skipped that cell unless --retry-failed. This is the chain numba 0.6x gives a real SIGINT.
    from graybox.experiments import _cell

    g = gx.Grid(name="ctrl-c", data=[gx.DataSpec("pumping", bundled="pumping")],
                structures=[gx.StructureSpec("first-order", terms=["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "1"])],
                variants=[gx.Variant("LS", "ls"), gx.Variant("ELS", "els", options={"noise": 1})])
    estimate = _cell._estimate

    def interrupted(cell, st, data):
        if cell.variant == "ELS":
            raise SystemError("CPUDispatcher(<function _batch_sse>) returned a result with an exception set") \
                from _kernel_interrupt()
        return estimate(cell, st, data)

    monkeypatch.setattr(_cell, "_estimate", interrupted)
    path = tmp_path / "s.sqlite"
    with pytest.raises(KeyboardInterrupt):
        gx.run_grid(g, path)
    assert set(gx.load_results(path)["status"]) <= {"ok"}  # the interrupted cell is not stored as failed
    monkeypatch.setattr(_cell, "_estimate", estimate)
    run = gx.run_grid(g, path)  # the same command runs the cell Ctrl-C stopped
    assert dict(run.counts)["ok"] == 2 and dict(run.counts)["failed"] == 0


def _kernel_interrupt() -> SystemError:
    """What Ctrl-C inside a numba kernel raises (seen under a real SIGINT): SystemError caused by the interrupt."""
    try:
        raise KeyboardInterrupt
    except KeyboardInterrupt as exc:
        err = SystemError("CPUDispatcher(<function _batch_sse_parallel>) returned a result with an exception set")
        err.__cause__ = exc
        return err


def test_ctrl_c_inside_a_compiled_kernel_during_reproduce_says_what_is_kept(tmp_path, monkeypatch, capsys):
    # Ctrl-C 15 s into `graybox reproduce --quick` (the GA of Table I in _batch_sse_parallel) printed a SystemError
    # traceback ("returned a result with an exception set") and exited 1, not "interrupted; the checkpoints in
    # ... are kept" and 130 as a Ctrl-C elsewhere does
    import graybox.reproduce as rp

    def section(quick, out):
        raise _kernel_interrupt()

    monkeypatch.setattr(rp, "SECTIONS", (section,))
    assert main(["reproduce", "--quick", "--out", str(tmp_path)]) == 130
    err = capsys.readouterr().err
    assert err.startswith("graybox reproduce: interrupted") and str(tmp_path) in err


def test_a_systemerror_not_caused_by_ctrl_c_still_surfaces_from_reproduce(tmp_path, monkeypatch):
    import graybox.reproduce as rp

    def section(quick, out):
        raise SystemError("a real bug")

    monkeypatch.setattr(rp, "SECTIONS", (section,))
    with pytest.raises(SystemError, match="a real bug"):
        main(["reproduce", "--quick", "--out", str(tmp_path)])


def test_a_store_and_its_hard_link_are_not_compared_as_two_stores(small_store, tmp_path):
    # `graybox grid report a.sqlite b.sqlite` with b a hard link of a (ln a.sqlite b.sqlite: one file, two names)
    # wrote a comparison of the store with itself, every row twice; a symbolic link was refused as the same store
    import os

    path, _ = small_store
    os.link(path, tmp_path / "link.sqlite")
    with pytest.raises(ValueError, match="same store"):
        gx.compare_results([path, tmp_path / "link.sqlite"])


def test_a_json_spec_is_told_to_be_json_not_invalid_toml(tmp_path, capsys):
    # `graybox grid run spec.json --store s.sqlite` (the grid's tables written by json.dump) said only "invalid
    # TOML: Invalid statement (at line 1, column 1)", as for a typo on line 1: it now says the file is JSON
    import json

    spec = tmp_path / "spec.json"
    spec.write_text(json.dumps({"name": "t", "data": [{"name": "pumping", "bundled": "pumping"}]}), encoding="utf-8")
    assert main(["grid", "run", str(spec), "--store", str(tmp_path / "s.sqlite")]) == 2
    err = capsys.readouterr().err
    assert "JSON" in err and "TOML" in err and "Traceback" not in err
    assert not (tmp_path / "s.sqlite").exists()


def test_worker_timeout_without_dask_names_the_options_that_take_it(tmp_path, capsys):
    # `graybox grid run spec.toml --store s.sqlite --worker-timeout 5` said "the 'inprocess' executor has none to
    # lose": an executor name the command has no option for, and not which options give a Dask run
    spec = tmp_path / "spec.toml"
    spec.write_text(TOML, encoding="utf-8")
    for extra in ([], ["--processes", "1"]):
        assert main(["grid", "run", str(spec), "--store", str(tmp_path / "s.sqlite"), "--worker-timeout", "5",
                     *extra]) == 2
        err = capsys.readouterr().err
        assert "--worker-timeout" in err and "--workers N or --scheduler ADDRESS" in err and "inprocess" not in err
    assert not (tmp_path / "s.sqlite").exists()


def test_the_scatter_says_why_cells_with_j_0_are_not_on_its_log_axis(small_store):
    """A cell with J_SF = 0 (an exact fit) was left off the scatter and counted ("k of n cells drawn") without a word
    why: a log axis has no 0. The title now says so; on a linear axis the cell is drawn (mend60g)."""
    path, _ = small_store
    df = gx.load_results(path)
    d = df["data"].iloc[0]
    df = df[df["data"] == d]
    finite = np.isfinite(df["JS_valid"].to_numpy(float)) & np.isfinite(df["JSF"].to_numpy(float))
    rows = df.index[finite]
    spread = df.copy()
    spread.loc[rows[0], "JSF"] = 0.0
    spread.loc[rows[1], "JSF"] = 100 * float(spread.loc[rows[1:], "JSF"].max()) + 1.0  # a log axis for J_SF
    ax = gx.plot_scatter(spread).axes[0]
    assert ax.get_yscale() == "log"
    assert ax.get_title().endswith(f"{finite.sum() - 1} of {len(df)} cells drawn (1 with J_SF = 0, which a log axis "
                                   "cannot show)")
    near = df.copy()
    near.loc[rows, "JSF"] = 1.0 + np.arange(len(rows)) / len(rows)
    near.loc[rows[0], "JSF"] = 0.0
    ax = gx.plot_scatter(near).axes[0]
    assert ax.get_yscale() == "linear" and ax.get_title().endswith(f"{finite.sum()} of {len(df)} cells drawn")


def test_a_data_sets_band_from_points_beyond_the_float_range_names_the_points():
    # an output scaled by 2^600 with its static δ: the band mean δ² overflowed and the grid said "band must be a finite
    # number, got inf" about a band the user never set (hunt60c); now the data set and its δ are named
    import graybox as gb
    from graybox.experiments._spec import DataSpec

    d = gb.load_pumping()
    far = gb.Dataset(d.ident, d.valid, gb.StaticPoints(d.static.ubar, d.static.ybar, uncertainty=2.0 ** 600))
    with pytest.raises(ValueError, match=r"data set 'far': the band its static points' uncertainty gives.*4\.15e\+180"
                                         r".*band = B yourself"):
        DataSpec(name="far", dataset=far)
    assert DataSpec(name="near", dataset=d).band == pytest.approx(0.175 ** 2)


def test_a_folder_under_the_home_folder_written_with_a_tilde(small_store, tmp_path, monkeypatch):
    # fe76d520 made check_path expand a leading '~', but write_report, reproduce.run and a grid's base_dir checked
    # the name and went on with the one given: out='~/rep' wrote a literal folder '~' in the working folder
    import graybox.reproduce as rp

    home, work = tmp_path / "home", tmp_path / "work"
    home.mkdir(), work.mkdir()
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.chdir(work)
    undrawn_figures(monkeypatch)  # its file names are read; test_figures_and_report_files draws such a report
    gx.write_report(small_store[0], "~/rep")
    assert (home / "rep" / "leaderboard.csv").is_file()
    seen = []

    def section(quick, out):
        seen.append(Path(out))
        return "done"

    monkeypatch.setattr(rp, "SECTIONS", (section,))
    with open(work / "log.txt", "w") as log:
        rp.run(quick=True, out="~/figs", stream=log)
    assert seen == [home / "figs"] and (home / "figs").is_dir()
    rows = ["t,u,y"] + [f"{k * 0.1:.1f},{1 + k % 3},{0.5 * k}" for k in range(12)]
    for name in ("id.csv", "va.csv"):
        (home / name).write_text("\n".join(rows) + "\n", encoding="utf-8")
    (home / "st.csv").write_text("u,y\n1,2\n2,4\n3,6\n", encoding="utf-8")
    rec = dict(u="u", y="y", time="t")
    spec = {"name": "g", "data": [{"name": "m", "ident": dict(path="id.csv", **rec),
                                   "valid": dict(path="va.csv", **rec), "static": dict(path="st.csv", u="u", y="y")}],
            "structures": [{"name": "one", "terms": ["y(k-1)", "u(k-1)", "1"]}],
            "variants": [{"name": "LS", "estimator": "ls"}]}
    assert gx.Grid.from_dict(spec, base_dir="~").load_data()["m"].static.ybar.tolist() == [2.0, 4.0, 6.0]
    assert not (work / "~").exists()
