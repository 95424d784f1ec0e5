"""hunt48c: grids and their store (spec, run, cells, store, CLI)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import graybox as gb
from graybox import experiments as gx

FIRST = gx.StructureSpec("first-order", terms=["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "1"])


def test_n_params_is_stored_by_one_rule_whatever_the_status(tmp_path):
    # a failed LS cell (too short a record) kept no N_p while an infeasible PE cell of the same
    # structure kept 4: N_p is the structure's number of terms once the structure is made
    d = gb.load_pumping()
    short = gb.Dataset(d.ident.slice(0, 12), d.valid, d.static)
    g = gx.Grid(data=[gx.DataSpec("short", dataset=short)], structures=[FIRST],
                variants=[gx.Variant("LS", "ls"), gx.Variant("CLS", "cls", constraints=[{"type": "gain", "lower": 1e6}]),
                          gx.Variant("PE", "pe", lambdas=[0.1, 1.0], decision={"rule": "dsf", "band": 1e-12})],
                name="np")
    gx.run_grid(g, tmp_path / "s.sqlite")
    df = gx.load_results(tmp_path / "s.sqlite").set_index("variant")
    assert set(df["status"]) >= {"failed", "infeasible"}
    for v, r in df.iterrows():
        assert r["terms"] is not None
        assert not pd.isna(r["n_params"]), (v, r["status"])
        assert int(r["n_params"]) == len(r["terms"]) == 4, (v, r["status"], r["n_params"])


def test_two_names_of_the_same_data_count_every_cell_of_the_grid(tmp_path):
    # two data set names of the same records share the cells that read no band: they ran once, and a
    # fresh store said '4 cells, 1 reused, 3 run now; 3 ok' (nothing was reused; grid status said 4 ok)
    g = gx.Grid([gx.DataSpec("a", bundled="pumping"), gx.DataSpec("b", bundled="pumping", band=0.05)], [FIRST],
                [gx.Variant("LS", "ls"), gx.Variant("PE", "pe", lambdas=[0.1, 1.0], options={"solver": "closed"})],
                name="twins")
    lines: list[str] = []
    run = gx.run_grid(g, tmp_path / "s.sqlite", log=lines.append)
    assert (run.cells, run.ran, run.skipped) == (4, 4, 0)
    assert dict(run.counts) == {"ok": 4, "infeasible": 0, "diverged": 0, "failed": 0}
    assert "4 cells, 0 reused" in lines[0] and "4 to run" in lines[0]
    assert gx.grid_status(tmp_path / "s.sqlite").counts["ok"] == 4
    again = gx.run_grid(g, tmp_path / "s.sqlite")
    assert (again.ran, again.skipped) == (0, 4) and again.counts["ok"] == 4


def test_a_structure_with_n_terms_and_max_terms_is_refused_by_the_spec():
    # accepted by the spec, then every cell of the structure failed 'max_terms applies to tol and criterion
    # stopping; with n_terms leave it out' (frols' own refusal), data set after data set
    with pytest.raises(gx.SpecError, match="max_terms") as e:
        gx.StructureSpec("s", candidates={"ny": 1, "nu": 1, "degree": 1}, n_terms=3, max_terms=5)
    assert e.value.path == ("max_terms",)
    text = '[[structures]]\nname = "s"\ncandidates = {ny = 1, nu = 1}\nn_terms = 2\nmax_terms = 4\n'
    spec = ('name = "g"\n[[data]]\nname = "p"\nbundled = "pumping"\n' + text
            + '[[variants]]\nname = "LS"\nestimator = "ls"\n')
    with pytest.raises(gx.SpecError, match=r"line 9: structures\[0\]\.max_terms"):
        gx.Grid.from_toml_text(spec)
    # with tol or a criterion it stays FROLS' cap
    assert gx.StructureSpec("s", candidates={"ny": 1, "nu": 1}, criterion="bic", max_terms=4).max_terms == 4


@pytest.fixture(scope="module")
def small_store(tmp_path_factory):
    path = tmp_path_factory.mktemp("small") / "s.sqlite"
    g = gx.Grid([gx.DataSpec("p", bundled="pumping")], [FIRST], [gx.Variant("LS", "ls")], name="small")
    gx.run_grid(g, path)
    return path


def _copy_with(src, tmp_path, sql: str):
    import shutil
    import sqlite3

    dst = tmp_path / "c.sqlite"
    shutil.copy(src, dst)
    conn = sqlite3.connect(dst)
    conn.execute(sql)
    conn.commit()
    conn.close()
    return dst


def test_a_stored_n_params_that_is_no_integer_is_said_damaged(small_store, tmp_path):
    # a bare ValueError: invalid literal for int() with base 10: np.str_('abc'), from building the frame
    p = _copy_with(small_store, tmp_path, "UPDATE cells SET n_params = 'abc'")
    for read in (gx.load_results, gx.grid_status):
        with pytest.raises(gx.StoreError, match="damaged.*'p' / 'first-order' / 'LS'"):
            read(p)


def test_a_store_that_holds_no_spec_is_refused_in_words(small_store, tmp_path):
    # a store made whole whose run stopped before it registered its spec: load_results said
    # 'max() arg is an empty sequence' (spec='latest') or 'has no spec 1; its specs are ' (spec=1)
    p = _copy_with(small_store, tmp_path, "DELETE FROM specs")
    for kw in ({}, {"spec": 1}, {"spec": "latest"}):
        with pytest.raises(gx.StoreError, match="holds no spec"):
            gx.load_results(p, **kw)
        with pytest.raises(gx.StoreError, match="holds no spec"):
            gx.grid_status(p, **kw)
    assert len(gx.store_specs(p)) == 0


def test_a_stored_status_that_is_none_of_the_statuses_is_said_damaged(small_store, tmp_path):
    # 'weird' was read as it was: grid status said '1 of 1 cells done (0 ok, 0 infeasible, 0 diverged,
    # 0 failed)', counting a cell under no status, and the leaderboard said 'no cell is ok'
    p = _copy_with(small_store, tmp_path, "UPDATE cells SET status = 'weird'")
    for read in (gx.load_results, gx.grid_status):
        with pytest.raises(gx.StoreError, match="damaged.*status 'weird'"):
            read(p)
