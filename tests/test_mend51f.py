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


def test_compare_results_names_the_same_data_stored_under_other_names(tmp_path):
    """Two stores of the same data under different names were told 'the stores share no data set' though their
    content hashes match: the message now names those data sets (names are not merged)."""
    paths = []
    for name in ("plant", "pump"):
        grid = gx.Grid([gx.DataSpec(name, bundled="pumping")],
                       [gx.StructureSpec("fo", terms=["y(k-1)", "u(k-1)", "1"])],
                       [gx.Variant("LS", "ls")], name=name)
        paths.append(tmp_path / f"{name}.sqlite")
        gx.run_grid(grid, paths[-1], progress=False)
    with pytest.raises(gx.StoreError, match="share no data set") as e:
        gx.compare_results(paths)
    assert "same data" in str(e.value) and "'plant'" in str(e.value) and "'pump'" in str(e.value)
