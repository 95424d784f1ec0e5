"""hunt51b: grids under Dask and the SQLite store, grid specs in TOML."""

from __future__ import annotations

import pytest

import graybox.experiments as gx

_BASE = '''
name = "t"
[[data]]
name = "pumping"
bundled = "pumping"
[[structures]]
name = "first"
terms = ["y(k-1)", "u(k-1)", "1"]
'''


def _spec(variant: str) -> str:
    return _BASE + "[[variants]]\n" + variant


@pytest.mark.parametrize("options", ["{population = 4, elite = 4}", "{population = 4, elite = 10}"])
def test_ga_elite_not_below_population_is_a_spec_error(options):
    # GAOptions refuses elite >= population: the spec accepted it, and every se-ga cell of the grid failed
    text = _spec(f'name = "GA"\nestimator = "se-ga"\noptions = {options}\n')
    with pytest.raises(gx.SpecError, match="elite"):
        gx.Grid.from_toml_text(text)


def test_ga_stall_false_is_a_type_error():
    # stall = 0 is the spec's "never stop early" (TOML has no null); false passed as 0 (False == 0), where every
    # other count of the spec refuses a bool with a TypeError, and stall = true did too
    with pytest.raises(gx.SpecTypeError, match="stall"):
        gx.Grid.from_toml_text(_spec('name = "GA"\nestimator = "se-ga"\noptions = {stall = false}\n'))
    g = gx.Grid.from_toml_text(_spec('name = "GA"\nestimator = "se-ga"\noptions = {stall = 0}\n'))
    assert g.variants[0].options["stall"] is None


@pytest.mark.parametrize("estimator, constraint", [
    ("cls", '{type = "band", b = 0.2}'),
    ("cls", '{type = "gain", lower = 0.0}'),
    ("pe", '{type = "band"}'),
    ("pe", '{type = "clusters", bounds = {Sy = {upper = 0.9}}}'),
])
def test_closed_solver_with_inequality_constraints_is_a_spec_error(estimator, constraint):
    # the closed form solves equality constraints only: the spec accepted solver = "closed" with a band, gain or
    # cluster bound, and every cell of the variant failed with the estimator's ValueError
    text = _spec(f'name = "V"\nestimator = "{estimator}"\nconstraints = [{constraint}]\n'
                 'options = {solver = "closed"}\n')
    with pytest.raises(gx.SpecError, match="closed") as info:
        gx.Grid.from_toml_text(text)
    assert info.value.path == ("variants", 0, "options", "solver")


@pytest.mark.parametrize("constraint", ['{type = "equality", sigma_y = 0.5}', '{type = "points"}',
                                        '{type = "clusters", bounds = {Sy = {lower = 0.5, upper = 0.5}}}'])
def test_closed_solver_with_equality_constraints_is_accepted(constraint):
    g = gx.Grid.from_toml_text(_spec(f'name = "V"\nestimator = "cls"\nconstraints = [{constraint}]\n'
                                     'options = {solver = "closed"}\n'))
    assert g.variants[0].options["solver"] == "closed"


_MISO = '''name = "m"
[[data]]
name = "two"
bundled = "pumping_miso"
[[structures]]
name = "fine"
terms = ["y(k-1)", "u1(k-1)", "1"]
STRUCTURE
[[variants]]
name = "LS"
estimator = "ls"
'''


@pytest.mark.parametrize("structure, said", [
    ('[[structures]]\nname = "s"\nterms = ["y(k-1)", "u(k-1)", "1"]', "'u'"),             # the one-input name
    ('[[structures]]\nname = "s"\ncandidates = {ny = 1, nu = 1}\nn_terms = 3\ninclude = ["speed(k-1)"]', "'speed'"),
    ('[[structures]]\nname = "s"\ncandidates = {ny = 1, nu = {u1 = 1, u3 = 1}}\nn_terms = 3', "'u3'"),
    ('[[structures]]\nname = "s"\ncandidates = {ny = 1, nu = 1, delay = {u2 = 1, n3 = 1}}\nn_terms = 3', "'n3'"),
])
def test_structures_naming_inputs_the_data_lacks_are_refused_before_any_cell_runs(tmp_path, structure, said):
    # the grid took them and every cell of the structure on that data set failed, one by one (gain bounds naming an
    # input the data lack are refused at the data's load, hunt45g)
    g = gx.Grid.from_toml_text(_MISO.replace("STRUCTURE", structure), source="spec.toml")
    with pytest.raises(gx.SpecError, match=said) as err:
        gx.run_grid(g, tmp_path / "r.sqlite")
    assert err.value.path[:2] == ("structures", 1)
    assert "'two'" in str(err.value)  # the data set it was checked against
    assert not (tmp_path / "r.sqlite").exists()


def test_structures_on_a_subset_of_the_inputs_still_run(tmp_path):
    g = gx.Grid.from_toml_text(_MISO.replace("STRUCTURE", '[[structures]]\nname = "s"\ncandidates = {ny = 1, nu = '
                                                          '{u2 = 1}}\nn_terms = 2\ninclude = ["u2(k-1)"]'))
    res = gx.run_grid(g, tmp_path / "r.sqlite")
    assert res.counts["ok"] == 2, res.summary()


def test_a_problem_found_when_the_data_load_names_the_spec_file_and_line(tmp_path):
    # "every problem in [a TOML spec] is a SpecError naming the key and the line it is on": those found once the data
    # are read (a CSV file missing, a structure or gain bound naming an input the data lack) named neither the file
    # nor the line (graybox grid run: "structures[1]: …")
    spec = tmp_path / "spec.toml"
    spec.write_text(_MISO.replace("STRUCTURE", '[[structures]]\nname = "s"\nterms = ["y(k-1)", "q(k-1)", "1"]'))
    with pytest.raises(gx.SpecError) as err:
        gx.run_grid(spec, tmp_path / "r.sqlite")
    assert err.value.source == str(spec) and err.value.line == 8  # the [[structures]] table of "s"
    assert str(err.value).startswith(f"{spec}, line 8: structures[1]: ")
    missing = tmp_path / "csv.toml"
    missing.write_text('name = "c"\n[[data]]\nname = "mine"\nident = {path = "no.csv", u = "u", y = "y", Ts = 1.0}\n'
                       'valid = {path = "no.csv", u = "u", y = "y", Ts = 1.0}\n'
                       'static = {path = "no.csv", u = "u", y = "y", uncertainty = 0.1}\n'
                       '[[structures]]\nname = "s"\nterms = ["y(k-1)", "u(k-1)", "1"]\n'
                       '[[variants]]\nname = "LS"\nestimator = "ls"\n')
    with pytest.raises(gx.SpecError, match="cannot be loaded") as err:
        gx.Grid.from_toml(missing).load_data()
    assert err.value.source == str(missing) and err.value.line == 2


@pytest.mark.parametrize("rule, said", [("n_terms = 2", "n_terms"), ("max_terms = 2\ncriterion = \"bic\"", "max_terms"),
                                        ("max_terms = 2\ntol = 0.01", "max_terms")])
def test_a_rule_with_fewer_terms_than_included_is_a_spec_error(rule, said):
    # FROLS refuses n_terms or max_terms below the included terms' count: the spec took them, and every cell of the
    # structure failed
    text = ('name = "t"\n[[data]]\nname = "pumping"\nbundled = "pumping"\n[[structures]]\nname = "s"\n'
            f'candidates = {{ny = 2, nu = 2, degree = 2}}\n{rule}\ninclude = ["1", "y(k-1)", "u(k-1)"]\n'
            '[[variants]]\nname = "LS"\nestimator = "ls"\n')
    with pytest.raises(gx.SpecError, match=f"{said}.*3 included") as err:
        gx.Grid.from_toml_text(text)
    assert err.value.path == ("structures", 0, said)
    ok = text.replace("= 2\n", "= 3\n", 1)
    assert len(gx.Grid.from_toml_text(ok).structures[0].include) == 3


@pytest.mark.parametrize("rule, said", [("n_terms = 16", "n_terms"), ("max_terms = 16\ncriterion = \"bic\"", "max_terms")])
def test_a_rule_with_more_terms_than_the_data_sets_candidates_is_a_spec_error(tmp_path, rule, said):
    # with one lag count for every input the data set decides how many candidates there are (15 here, one input):
    # n_terms or max_terms above it was accepted and FROLS refused it in every cell of the structure
    text = ('name = "t"\n[[data]]\nname = "pumping"\nbundled = "pumping"\n[[structures]]\nname = "s"\n'
            f'candidates = {{ny = 2, nu = 2, degree = 2}}\n{rule}\n[[variants]]\nname = "LS"\nestimator = "ls"\n')
    g = gx.Grid.from_toml_text(text)
    with pytest.raises(gx.SpecError, match=f"{said} = 16.*15 candidates.*'pumping'") as err:
        gx.run_grid(g, tmp_path / "r.sqlite")
    assert err.value.path == ("structures", 0, said)
    assert not (tmp_path / "r.sqlite").exists()
    g = gx.Grid.from_toml_text(text.replace("= 16", "= 15"))
    assert g.load_data()["pumping"] is not None


def test_a_rule_with_more_terms_than_one_inputs_candidates_runs_on_two_inputs(tmp_path):
    # 20 terms: more than one input's 15 candidates, fewer than two inputs' 28
    g = gx.Grid.from_toml_text(_MISO.replace("STRUCTURE", '[[structures]]\nname = "s"\ncandidates = {ny = 2, nu = 2, '
                                                          'degree = 2}\nn_terms = 20'))
    assert set(g.load_data()) == {"two"}


def test_a_store_whose_schema_is_damaged_into_bytes_that_are_not_utf8_is_a_store_error(tmp_path):
    # SQLite's message for a malformed schema quotes the schema's text; where a damaged byte made it other than UTF-8,
    # Python's sqlite3 raised a bare UnicodeDecodeError (naming no store) from load_results, store_specs, grid status
    # and run_grid, instead of the StoreError every other damaged store gives
    import sqlite3

    text = _BASE + '[[variants]]\nname = "LS"\nestimator = "ls"\n'
    path = tmp_path / "r.sqlite"
    gx.run_grid(gx.Grid.from_toml_text(text), path)
    conn = sqlite3.connect(path)
    conn.execute("PRAGMA writable_schema=ON")
    conn.execute("UPDATE sqlite_master SET sql = 'CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL' || "
                 "CAST(x'ff' AS TEXT) WHERE name = 'meta'")
    conn.commit()
    conn.close()
    before = path.read_bytes()
    for call in (lambda: gx.load_results(path), lambda: gx.store_specs(path), lambda: gx.grid_status(path),
                 lambda: gx.run_grid(gx.Grid.from_toml_text(text), path)):
        with pytest.raises(gx.StoreError, match="damaged") as err:
            call()
        assert str(path) in str(err.value)
    assert path.read_bytes() == before  # a refused store is left untouched


def test_a_csv_entrys_path_may_be_a_path_object(tmp_path):
    # every other path of graybox (a store, a spec, base_dir, load_record_csv's file) takes str or os.PathLike; a grid
    # built in Python refused the pathlib.Path of a CSV file with a SpecTypeError ("path must be a non-empty string")
    from pathlib import Path

    import numpy as np
    import pandas as pd

    rng = np.random.default_rng(0)
    for name in ("ident", "valid"):
        u = rng.uniform(1.0, 2.0, 60)
        y = np.zeros(60)
        for k in range(1, 60):
            y[k] = 0.5 * y[k - 1] + u[k - 1]
        pd.DataFrame({"u": u, "y": y}).to_csv(tmp_path / f"{name}.csv", index=False)
    pd.DataFrame({"u": [1.0, 1.5, 2.0], "y": [2.0, 3.0, 4.0]}).to_csv(tmp_path / "static.csv", index=False)
    entries = {k: {"path": tmp_path / f"{k}.csv", "u": "u", "y": "y", **({"Ts": 1.0} if k != "static" else
                                                                          {"uncertainty": 0.1})}
               for k in ("ident", "valid", "static")}
    by_path = gx.DataSpec("csv", **entries)
    by_text = gx.DataSpec("csv", **{k: {**e, "path": str(e["path"])} for k, e in entries.items()})
    assert by_path.to_dict() == by_text.to_dict()  # the same canonical form (JSON text), so the same cells
    assert isinstance(by_path.ident["path"], str)
    ds = by_path.load()
    np.testing.assert_array_equal(ds.ident.y, by_text.load().ident.y)
    assert isinstance(Path(by_path.static["path"]), Path)


@pytest.mark.parametrize("estimator, written", [
    ("pe", '{solver = "clarabel", weights = "mse"}'),
    ("cls", '{solver = "clarabel"}'),
    ("se-ga", '{population = 200, generations = 50, elite = 1, theta0 = "ls", margin = "auto"}'),
    ("se-dsf", '{max_iter = 200, margin = "auto"}'),
    ("els", '{max_iter = 500, relaxation = 0.5}'),
])
def test_a_variant_that_writes_out_its_estimators_defaults_duplicates_the_one_that_leaves_them_out(estimator, written):
    # the spec refuses a variant identical to another (same cells), but one that wrote the estimator's default options
    # out was taken as another variant: the same estimates ran twice, under two names, ranked as two
    more = {"cls": 'constraints = [{type = "band", b = 0.2}]\n', "pe": "lambdas = [0.5, 1.0]\n",
            "se-ga": "lambdas = [1.0]\n", "se-dsf": "lambdas = [1.0]\n", "els": "options = {noise = 1}\n"}[estimator]
    plain = f'name = "A"\nestimator = "{estimator}"\n{more}'
    if estimator == "els":
        spelt = plain.replace("options = {noise = 1}", "options = " + written.replace("{", "{noise = 1, "))
    else:
        spelt = plain + f"options = {written}\n"
    text = _spec(plain) + "[[variants]]\n" + spelt.replace('name = "A"', 'name = "B"')
    with pytest.raises(gx.SpecError, match="'B' is identical to 'A'") as err:
        gx.Grid.from_toml_text(text)
    assert err.value.path == ("variants", 1)
    other = text.replace("= 200", "= 100").replace("= 500", "= 50").replace('"clarabel"', '"osqp"')
    assert len(gx.Grid.from_toml_text(other).variants) == 2  # options other than the defaults: another variant


def test_neural_lags_written_out_are_not_taken_for_defaults():
    # a grid's neural variant takes the structure's lags by default, not neural_narx's ny = nu = 6
    text = _spec('name = "A"\nestimator = "neural"\n') + '[[variants]]\nname = "B"\nestimator = "neural"\n' \
        'options = {ny = 6, nu = 6}\n'
    assert len(gx.Grid.from_toml_text(text).variants) == 2


def test_cells_of_datasets_that_are_not_datasets_is_a_type_error():
    # Grid.cells(datasets) documents a mapping name -> Dataset: a Record (or anything else) in it failed with a bare
    # AttributeError ('Record' object has no attribute 'ident') from the content hash
    import graybox as gb

    g = gx.Grid.from_toml_text(_spec('name = "LS"\nestimator = "ls"\n'))
    d = gb.load_pumping()
    for wrong in (d.ident, 3, None):
        with pytest.raises(TypeError, match="pumping"):
            g.cells({"pumping": wrong})
    assert len(g.cells({"pumping": d})) == 1


def test_a_store_read_before_its_first_run_registered_its_spec_is_not_said_to_be_stopped(tmp_path):
    # a run makes its store whole (tables, no spec) and registers its grid a moment later: graybox grid status run in
    # that moment (just after starting a run in another terminal) said "the run that made it stopped before it
    # registered its grid", of a run going on
    import graybox as gb
    from graybox.experiments._store import _create_whole

    path = tmp_path / "r.sqlite"
    assert _create_whole(path, gb.__version__)
    for call in (lambda: gx.load_results(path), lambda: gx.grid_status(path)):
        with pytest.raises(gx.StoreError, match="holds no spec yet") as err:
            call()
        assert "is starting" in str(err.value) and "stopped" in str(err.value)  # both: it cannot tell which


def test_a_variant_table_without_an_estimator_is_a_spec_error_naming_its_line(tmp_path, capsys):
    # a [[variants]] table without estimator failed with the dataclass's bare TypeError ("Variant.__init__() missing 1
    # required positional argument: 'estimator'"), no key nor line, and graybox grid run printed a traceback
    from graybox._cli import main

    text = _spec('name = "LS"\n')
    with pytest.raises(gx.SpecError, match="estimator") as err:
        gx.Grid.from_toml_text(text, source="spec.toml")
    assert err.value.path == ("variants", 0) and err.value.line == 9  # its [[variants]] header
    spec = tmp_path / "spec.toml"
    spec.write_text(text)
    assert main(["grid", "run", str(spec), "--store", str(tmp_path / "r.sqlite")]) == 2
    assert "needs an estimator" in capsys.readouterr().err


@pytest.mark.parametrize("count", ["1e300", "100000000000000000000"])
def test_a_lambda_count_beyond_any_memory_is_a_spec_error(count):
    # lambdas = {logspace = [a, b, n]} with n beyond any machine's memory reached numpy: "ValueError: Maximum allowed
    # size exceeded" (or a MemoryError) naming no key of the spec
    text = _spec(f'name = "PE"\nestimator = "pe"\nlambdas = {{logspace = [-3, 0, {count}]}}\n')
    with pytest.raises(gx.SpecError, match="count.*too large") as err:
        gx.Grid.from_toml_text(text)
    assert err.value.path == ("variants", 0, "lambdas", "logspace")
