"""Bug hunt 45g: grids of experiments run from the command line and Python over a day."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb
from _reports import undrawn_figures
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
    ('{type = "gain", lower = 0.0, ubar_range = [[1200, 1600], [1200, 1600], [0, 1]]}', "3 ranges"),
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


_PUMPING = '''name = "p"
[[data]]
name = "pumping"
bundled = "pumping"
[[structures]]
name = "first-order"
terms = ["y(k-1)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)", "1"]
[[variants]]
name = "PE band"
estimator = "pe"
lambdas = {logspace = [-3, 0, 4]}
constraints = [{type = "band"}]
'''


def test_a_report_says_the_units_of_its_mean_squares(tmp_path):
    # the summary, the heat map and the fronts gave J_S, J_SF and B as bare numbers: a newcomer could not tell an
    # mlc² from a V² (nor that fit_valid is in %), though the bundled plant's records carry their units
    gx.run_grid(gx.Grid.from_toml_text(_PUMPING), tmp_path / "r.sqlite")
    unit = gb.load_pumping().valid.units[1] + "²"
    written = {p.name: p for p in gx.write_report(tmp_path / "r.sqlite", tmp_path / "rep", html=True)}
    text = written["summary.txt"].read_text(encoding="utf-8")
    assert f"unit squared: pumping: {unit}; fit_valid in %" in written["report.html"].read_text("utf-8")
    assert f"B = {0.175 ** 2:g} {unit}" in text
    assert f"both in {unit}; fit_valid in %" in text
    df = gb.load_results(tmp_path / "r.sqlite")
    ax = gx.plot_fronts(df, data="pumping").axes[0]
    assert ax.get_xlabel() == f"J_S on the validation record ({unit})" and ax.get_ylabel() == f"J_SF ({unit})"
    fig = gx.plot_heatmap(df, data="pumping")
    assert any(a.get_ylabel() == f"JS_valid ({unit})" for a in fig.axes)  # the colour bar's
    assert gx.plot_scatter(df).axes[0].get_ylabel() == f"J_SF ({unit})"


def test_data_without_units_keep_bare_labels(tmp_path, monkeypatch):
    ds = gb.load_pumping()
    bare = gb.Dataset(*(r.__class__(r.u, r.y, r.Ts, r.name) for r in (ds.ident, ds.valid)), ds.static)
    g = gx.Grid.from_toml_text(_PUMPING)
    g = gx.Grid(name="p", data=[gx.DataSpec("pumping", dataset=bare)], structures=g.structures, variants=g.variants)
    gx.run_grid(g, tmp_path / "r.sqlite")
    df = gb.load_results(tmp_path / "r.sqlite")
    assert gx.plot_fronts(df, data="pumping").axes[0].get_ylabel() == "J_SF"
    undrawn_figures(monkeypatch)  # its summary.txt is read
    written = {p.name: p for p in gx.write_report(tmp_path / "r.sqlite", tmp_path / "rep")}
    assert "²" not in written["summary.txt"].read_text(encoding="utf-8")


def test_a_file_option_written_in_the_data_table_says_where_it_belongs():
    # "unknown key 'input_names' in a [[data]] table; known keys: name, bundled, …" left the user to guess that the
    # example's input_names (and delimiter, Ts, …) go in each file's table
    text = _MISO.replace('bundled = "pumping_miso"', 'input_names = ["n1", "n2"]\n'
                         'ident = {path = "i.csv", u = ["a", "b"], y = "p", Ts = 0.05}').replace(
        ', GAIN', '')
    with pytest.raises(gx.SpecError, match=r"input_names.*each CSV file.*ident = \{") as err:
        gx.Grid.from_toml_text(text, source="spec.toml")
    assert err.value.path == ("data", 0, "input_names") and err.value.line == 4


def test_a_least_squares_cell_on_a_held_input_does_not_call_itself_els():
    # a grid's "ls" cell (els with noise=0) on a record whose input is held failed with "the ELS process θ is not
    # identifiable … (ELS takes no static points …)": the variant the user wrote is least squares
    u = np.full(200, 3.0)
    y = gb.Model(gb.Structure(["y(k-1)", "u(k-1)", "1"]), [0.5, 0.2, 1.0]).simulate(u, np.zeros(1))
    rec = gb.Record(u, y + 0.01 * np.random.default_rng(0).standard_normal(200))
    with pytest.raises(ValueError, match=r"^the least-squares θ .*not identifiable") as err:
        gb.els(gb.Structure(["y(k-1)", "u(k-1)", "1"]), rec, noise=0)
    assert "ELS process" not in str(err.value) and "least squares takes no static points" in str(err.value)
    with pytest.raises(ValueError, match=r"^the ELS process θ .*ELS takes no static points"):
        gb.els(gb.Structure(["y(k-1)", "u(k-1)", "1"]), rec, noise=1)


def test_two_stores_side_by_side_say_each_band_in_its_unit(tmp_path, monkeypatch):
    gx.run_grid(gx.Grid.from_toml_text(_PUMPING), tmp_path / "a.sqlite")
    gx.run_grid(gx.Grid.from_toml_text(_PUMPING.replace('bundled = "pumping"', 'bundled = "pumping"\nband = 0.05')),
                tmp_path / "b.sqlite")
    unit = gb.load_pumping().valid.units[1] + "²"
    undrawn_figures(monkeypatch)  # its summary.txt is read; plot_fronts' suptitle below is built as the report's
    written = {p.name: p for p in gx.write_report([tmp_path / "a.sqlite", tmp_path / "b.sqlite"], tmp_path / "rep")}
    text = written["summary.txt"].read_text(encoding="utf-8")
    assert f"{0.175 ** 2:g} {unit} for a: PE band; 0.05 {unit} for b: PE band" in text
    fig = gx.plot_fronts(gx.compare_results([tmp_path / "a.sqlite", tmp_path / "b.sqlite"]), data="pumping")
    assert f"0.05 {unit} for b: PE band" in fig.get_suptitle().replace("\n", " ")


def test_a_seed_the_store_cannot_hold_is_refused_by_the_spec(tmp_path):
    # seeds = [2**64] passed the spec and the run ended in a traceback: "OverflowError: Python int too large to
    # convert to SQLite INTEGER" as it registered the cells
    text = _PUMPING.replace('name = "p"', 'name = "p"\nseeds = [18446744073709551616]').replace(
        'estimator = "pe"\nlambdas = {logspace = [-3, 0, 4]}\nconstraints = [{type = "band"}]',
        'estimator = "se-ga"\nlambdas = [0.5]\noptions = {population = 10, generations = 2}')
    with pytest.raises(gx.SpecError, match=r"seed") as err:
        gx.Grid.from_toml_text(text, source="spec.toml")
    assert err.value.path == ("seeds", 0) and err.value.line == 2
    top = _PUMPING.replace('name = "p"', f'name = "p"\nseeds = [{2 ** 63 - 1}]').replace(
        'estimator = "pe"\nlambdas = {logspace = [-3, 0, 4]}\nconstraints = [{type = "band"}]',
        'estimator = "se-ga"\nlambdas = [0.5]\noptions = {population = 10, generations = 2}')
    gx.run_grid(gx.Grid.from_toml_text(top), tmp_path / "r.sqlite")
    assert list(gb.load_results(tmp_path / "r.sqlite")["seed"]) == [2 ** 63 - 1]


def test_a_seed_given_as_an_option_points_to_the_grids_seeds():
    text = _PUMPING.replace('lambdas = {logspace = [-3, 0, 4]}\nconstraints = [{type = "band"}]',
                            'lambdas = {logspace = [-3, 0, 4]}\nconstraints = [{type = "band"}]\noptions = {seed = 3}')
    with pytest.raises(gx.SpecError, match=r"unknown option 'seed'.*seeds = \[0, 1, …\] at the top of the spec") as err:
        gx.Grid.from_toml_text(text, source="spec.toml")
    assert err.value.path == ("variants", 0, "options", "seed")


def test_grid_status_says_the_unit_of_its_best_rows(tmp_path):
    # graybox grid status printed the best rows as a raw pandas table (an empty 'data' header line) with J_S and J_SF
    # as bare numbers (hunt45g's note)
    g = gx.Grid.from_toml_text(_PUMPING, source="spec.toml")
    gx.run_grid(g, tmp_path / "r.sqlite")
    text = gx.grid_status(tmp_path / "r.sqlite").summary()
    lines = text.splitlines()
    head = lines[lines.index("best so far:") + 1]
    assert head.split()[:2] == ["data", "structure"]
    assert "in mlc² for pumping" in text
