"""Bug hunt 45g: grids of experiments run from the command line and Python over a day."""

from __future__ import annotations

import pytest

import graybox as gb
import graybox.experiments as gx

_MISO = '''name = "miso"
[[data]]
name = "two"
bundled = "pumping_miso"
[[structures]]
name = "s"
terms = ["y(k-1)", "u1(k-1)", "u2(k-1)", "u1(k-1)^2", "1"]
[[variants]]
name = "LS"
estimator = "ls"
[[variants]]
name = "CLS gain"
estimator = "cls"
constraints = [{type = "band"}, GAIN]
'''


@pytest.mark.parametrize("gain, said", [
    ('{type = "gain", upper = {speed1 = 0.01}}', "speed1"),                        # a column's name, not the input's
    ('{type = "gain", lower = 0.0, ubar_range = {n3 = [1200, 1600]}}', "n3"),     # a range of an input not held
    ('{type = "gain", lower = [0.0, 0.0, 0.0]}', "3 entries"),                     # three bounds, two inputs
])
def test_gain_bounds_naming_inputs_the_data_lacks_are_refused_before_any_cell_runs(tmp_path, gain, said):
    # the grid took them and every cell of the variant failed, one by one, with a ValueError that named no key of the
    # spec (select_graybox checks the same bounds against its data before any fit)
    g = gx.Grid.from_toml_text(_MISO.replace("GAIN", gain), source="spec.toml")
    with pytest.raises(gx.SpecError, match=said) as err:
        gx.run_grid(g, tmp_path / "r.sqlite")
    assert err.value.path[:4] == ("variants", 1, "constraints", 1)
    assert "two" in str(err.value)  # the data set it was checked against
    assert not (tmp_path / "r.sqlite").exists() or gb.load_results(tmp_path / "r.sqlite").empty


def test_gain_bounds_by_the_data_sets_input_names_still_run(tmp_path):
    g = gx.Grid.from_toml_text(_MISO.replace("GAIN", '{type = "gain", lower = {u1 = 0.0}, ubar_range = '
                                                      '{u1 = [1200, 1600]}}'), source="spec.toml")
    res = gx.run_grid(g, tmp_path / "r.sqlite")
    df = gb.load_results(tmp_path / "r.sqlite")
    assert "failed" not in set(df["status"]), res.summary()  # (the band and the gain together may be infeasible)
