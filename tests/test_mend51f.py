"""Mend 51f: items the hunters left."""

import numpy as np
import pytest

import graybox as gb
import graybox.experiments as gx


@pytest.fixture(scope="module")
def one_data(tmp_path_factory):
    d = gb.load_pumping()
    grid = gx.Grid([gx.DataSpec("pumping", bundled="pumping")],
                   [gx.StructureSpec("fo", terms=["y(k-1)", "u(k-1)", "y(k-1)u(k-1)", "1"])],
                   [gx.Variant("LS", "ls")], name="one")
    path = tmp_path_factory.mktemp("one") / "one.sqlite"
    gx.run_grid(grid, path, progress=False)
    return path, d.static.band


@pytest.mark.parametrize("bad", [np.inf, np.nan])
def test_chosen_rule_does_not_rank_an_ok_cell_whose_model_has_no_finite_js_valid(one_data, bad):
    """rule='chosen' ranked an ok cell whose chosen model diverged on the validation record (J_S valid inf or
    NaN) as a model: rank 1, reason ''."""
    path, _ = one_data
    df = gb.load_results(path)
    assert (df["status"] == "ok").all()
    df["JS_valid"] = bad
    lb = gx.leaderboard(df, rule="chosen")
    row = lb.iloc[0]
    assert np.isnan(row["rank"]) and np.isnan(row["JS_valid"])
    assert "no finite J_S" in row["reason"] and "1 ok cell" in row["reason"]
