"""hunt50b: saving and loading (graybox.io and every result's JSON), and the files they write."""

import dataclasses
import json
import os
import stat
import sys

import numpy as np
import pytest

import graybox as gb


def _model():
    return gb.Model(structure=["y(k-1)", "u(k-1)"], theta=[0.5, 0.1], name="m", units=("rpm", "mlc"))


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes here")
def test_save_to_a_pipe_writes_into_it_and_keeps_it_a_pipe(tmp_path):
    # write_atomically moved a file of its own over whatever the path named: a named pipe (or, for root, the
    # character device os.devnull itself: gb.save(m, os.devnull) left /dev/null a regular file holding the model)
    fifo = tmp_path / "out.json"
    os.mkfifo(fifo)
    reader = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)  # a reader waiting on the pipe, as a shell's would
    try:
        gb.save(_model(), fifo)
        assert stat.S_ISFIFO(os.stat(fifo).st_mode)
        got = os.read(reader, 1 << 16).decode("utf-8")
    finally:
        os.close(reader)
    assert gb.from_json(got).theta.tolist() == [0.5, 0.1]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.json"]  # nothing of the write left beside it


@pytest.mark.parametrize("number", ["1e400", "-1e400", "1.5e309"])
def test_a_float_beyond_the_float_range_is_refused_as_an_integer_is(number):
    # JSON's 1e400 was read as inf: a hand-written finite number loaded as an infinite one (a modulus of inf, a
    # diverged member's J_S), where the integer 10**400 was refused as "a number beyond the float range"
    text = gb.to_json(gb.Equilibrium(ubar=1.0, ybar=2.0, stable=True, spectral_radius=0.5))
    assert '"spectral_radius": 0.5' in text
    with pytest.raises(gb.GrayboxFileError, match="beyond the float range"):
        gb.from_json(text.replace('"spectral_radius": 0.5', f'"spectral_radius": {number}'), source="eq.json")
    with pytest.raises(gb.GrayboxFileError, match="beyond the float range"):
        gb.from_json(text.replace('"ybar": 2.0', f'"ybar": {number}'))


def test_numbers_at_the_float_range_still_load():
    text = gb.to_json(gb.Equilibrium(ubar=1.0, ybar=2.0, stable=True, spectral_radius=0.5))
    big = gb.from_json(text.replace('"ybar": 2.0', '"ybar": 1.7976931348623157e308'))
    assert big.ybar == sys.float_info.max
    assert gb.from_json(text.replace('"ybar": 2.0', '"ybar": 5e-324')).ybar == 5e-324  # the smallest subnormal
    assert gb.from_json(text.replace('"ybar": 2.0', '"ybar": 0e-400')).ybar == 0.0  # zero, as written
    # below the subnormals float() reads 0.0: a number written not zero would load as another (mend61e)
    with pytest.raises(gb.GrayboxFileError, match=r"object\.ybar: the number 1e-400 is not zero but below"):
        gb.from_json(text.replace('"ybar": 2.0', '"ybar": 1e-400'))


@pytest.fixture(scope="module")
def pumping():
    return gb.load_pumping()


@pytest.fixture(scope="module")
def bootstrap(pumping):
    return gb.bootstrap_decision(["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)"], pumping, estimator="pe",
                                 lambdas=[1e-4, 1e-2, 0.5, 1.0], n_boot=3, options={"solver": "closed"},
                                 fallback="min_jsf", seed=0)


@pytest.mark.parametrize("bad", [0.0, -1.0, 1.5, "nan", "inf"])
def test_a_bootstraps_sweep_lambdas_are_checked_as_its_call_checks_them(bootstrap, bad):
    # _check_values holds a loaded bootstrap to "the settings in range", and bootstrap_decision refuses a λ1
    # outside (0, 1]; the sweep's own lambdas were never checked: a file whose grid held 0, -1, 1.5, NaN or inf
    # loaded as a bootstrap of a sweep no call can run
    doc = json.loads(gb.to_json(bootstrap))
    lam = doc["object"]["lambdas"]
    chosen = {float(x) for x in bootstrap.lambda1[bootstrap.ok]}
    i = next(k for k, x in enumerate(lam) if x not in chosen)  # a λ1 no replicate chose: only its range is wrong
    lam[i] = bad
    with pytest.raises(gb.GrayboxFileError, match=r"lambdas.*\(0, 1\]"):
        gb.from_json(json.dumps(doc), source="boot.json")
    with pytest.raises(ValueError, match=r"lambdas.*\(0, 1\]"):
        dataclasses.replace(bootstrap, lambdas=np.array([0.0, *bootstrap.lambdas[1:]]))


def test_a_bootstrap_round_trips(bootstrap):
    back = gb.from_json(gb.to_json(bootstrap))
    assert np.array_equal(back.lambdas, bootstrap.lambdas) and np.array_equal(back.thetas, bootstrap.thetas,
                                                                               equal_nan=True)
    assert back.frequencies().equals(bootstrap.frequencies())


@pytest.fixture(scope="module")
def els_fit(pumping):
    return gb.els(["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)"], pumping)


@pytest.mark.parametrize("edit,match", [
    (lambda o: o["theta_ls"].pop(), "theta_ls"),                      # 4 least-squares parameters of 5 terms
    (lambda o: o["theta_ls"].append(0.0), "theta_ls"),
    (lambda o: o.__setitem__("n_iter", -1), "n_iter"),
    (lambda o: o.__setitem__("n_direct", -3), "n_direct"),
])
def test_an_els_result_holds_its_least_squares_theta_and_counts_as_els_makes_them(els_fit, edit, match):
    # ELSResult checked its fields' types only: a file whose θ_LS had another length than the model's terms, or a
    # negative count of iterations or direct solves, loaded as an ELS result
    doc = json.loads(gb.to_json(els_fit))
    edit(doc["object"])
    with pytest.raises(gb.GrayboxFileError, match=match):
        gb.from_json(json.dumps(doc), source="els.json")


def test_an_els_result_round_trips(els_fit, pumping):
    back = gb.from_json(gb.to_json(els_fit), expect=gb.ELSResult)
    assert back.theta_ls.tobytes() == els_fit.theta_ls.tobytes() and back.n_iter == els_fit.n_iter
    np.testing.assert_array_equal(back.model.simulate(pumping.valid), els_fit.model.simulate(pumping.valid))


_SMALL_GRID = """
name = "small"
[[data]]
name = "pumping"
bundled = "pumping"
[[structures]]
name = "first"
terms = ["y(k-1)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)", "1"]
[[variants]]
name = "PE"
estimator = "pe"
lambdas = [0.001, 0.1, 1.0]
decision = {rule = "dsf"}
"""


@pytest.fixture(scope="module")
def small_store(tmp_path_factory):
    from graybox import experiments as gx
    path = tmp_path_factory.mktemp("store") / "small.sqlite"
    gx.run_grid(gx.Grid.from_toml_text(_SMALL_GRID), path, progress=False)
    return path


def _edited(store, tmp_path, table, column, edit=None, value=None, where=""):
    """A copy of the store whose ``table.column`` (rows ``where``) is ``value``, or its JSON as ``edit`` changes it."""
    import shutil
    import sqlite3
    path = tmp_path / "edited.sqlite"
    shutil.copy(store, path)
    with sqlite3.connect(path) as conn:
        if edit is not None:
            (text,) = conn.execute(f"SELECT {column} FROM {table} {where}").fetchone()
            obj = json.loads(text)
            edit(obj)
            value = json.dumps(obj)
        conn.execute(f"UPDATE {table} SET {column} = ? {where}", (value,))
    conn.close()
    return path


@pytest.mark.parametrize("edit", [
    lambda m: m.pop("JS"),                              # the leaderboard's bare KeyError: 'JS'
    lambda m: m.__setitem__("JS", 1.0),                 # TypeError: 'float' object is not iterable
    lambda m: m.__setitem__("JS", [[1.0], [2.0], [3.0]]),  # numpy's 'setting an array element with a sequence'
    lambda m: m.__setitem__("failure", [""]),           # pandas' 'All arrays must be of the same length'
    lambda m: m.__setitem__("J1", m["J1"][:2]),          # 2 J_1 for 3 members, read as they were
    lambda m: m.__setitem__("failure", "abc"),          # read as the failures ['a', 'b', 'c']
    lambda m: m.clear(),                                # a Pareto cell without members
])
def test_a_stores_damaged_members_are_a_store_error_not_a_reports_crash(small_store, tmp_path, edit):
    # load_results checked the members column was a JSON object, never what it held: a damaged cell's members
    # loaded, and the leaderboard and write_report then failed with a bare KeyError, TypeError or pandas' words
    from graybox import experiments as gx
    assert gx.leaderboard(gb.load_results(small_store)).shape[0] == 1  # the store as run reads and reports
    path = _edited(small_store, tmp_path, "cells", "members", edit, where="WHERE members IS NOT NULL")
    with pytest.raises(gx.StoreError, match="members"):
        gb.load_results(path)


@pytest.mark.parametrize("column,value", [
    ("terms", json.dumps([1, 2])),          # write_report: 'sequence item 0: expected str instance, int found'
    ("warnings", json.dumps([1, 2])),       # the same
    ("theta", json.dumps([[0.5], [0.1]])),  # a (2, 1) θ read as it was
    ("in_band", "maybe"),                   # bool('maybe'): read as in the band
    ("in_band", 7),
    ("seed", 1.5),                          # int(1.5): read as seed 1
    ("n_params", 2.5),
])
def test_a_stores_damaged_cell_columns_are_a_store_error(small_store, tmp_path, column, value):
    # load_results decoded the JSON columns as lists and converted the numbers with bool() and int(): a damaged cell's
    # terms or warnings of numbers loaded (write_report then failed joining them), a θ of rows loaded, in_band
    # 'maybe' read True and seed 1.5 read 1
    from graybox import experiments as gx
    with pytest.raises(gx.StoreError, match=f"damaged.*{column}"):
        gb.load_results(_edited(small_store, tmp_path, "cells", column, value=value))


_SE_ST = ["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)"]
_SE_GA = dict(lambdas=[0.5, 0.9, 0.99], method="ga", options=gb.GAOptions(population=10, generations=3), seed=1)


@pytest.fixture(scope="module")
def ga_checkpoint(pumping, tmp_path_factory):
    path = tmp_path_factory.mktemp("ck") / "front.npz"
    front = gb.se_pareto(_SE_ST, pumping, checkpoint=path, **_SE_GA)
    with np.load(path, allow_pickle=False) as z:
        return front, {k: z[k] for k in z.files}


@pytest.mark.parametrize("failures", ['{"0": "no start was feasible"}', '{" 1": "x"}', '{"+1": "x"}'])
def test_an_se_checkpoint_naming_a_fitted_member_failed_is_corrupt(pumping, ga_checkpoint, tmp_path, failures):
    # the sweep writes a failed member as NaN θ and an infinite cost; a checkpoint naming a member with a finite θ
    # and cost failed resumed into a front that had lost that member (its θ NaN, its J's inf) without a word, and
    # int() read the member " 1" or "+1" as member 1
    front, arrays = ga_checkpoint
    assert np.all(np.isfinite(front.thetas)) and not front.failures
    path = tmp_path / "front.npz"
    np.savez(path, **{**arrays, "failures": np.array(failures)})
    with pytest.raises(gb.estimation._simulation_error.CheckpointError, match="corrupt|not a readable"):
        gb.se_pareto(_SE_ST, pumping, checkpoint=path, **_SE_GA)


def test_an_se_checkpoint_with_its_failed_members_resumes(pumping, ga_checkpoint, tmp_path):
    front, arrays = ga_checkpoint
    th, costs = arrays["thetas"].copy(), arrays["costs"].copy()
    th[1], costs[1] = np.nan, np.inf
    path = tmp_path / "front.npz"
    np.savez(path, **{**arrays, "thetas": th, "costs": costs, "failures": np.array('{"1": "no start was feasible"}')})
    again = gb.se_pareto(_SE_ST, pumping, checkpoint=path, **_SE_GA)
    assert dict(again.failures) == {1: "no start was feasible"}
    assert np.array_equal(again.thetas[[0, 2]], front.thetas[[0, 2]])


@pytest.mark.parametrize("edit", [
    lambda spec: spec.__setitem__("data", 5),                 # _spec_bands: "'int' object is not iterable"
    lambda spec: spec["data"][0].__setitem__("band", -1.0),   # every cell's band read as -1: no member in it
    lambda spec: spec["data"][0].__setitem__("band", True),
])
def test_a_stores_damaged_spec_data_sets_are_a_store_error(small_store, tmp_path, edit):
    # _specs checked a stored spec was a JSON object, not its data sets, whose bands every cell's row takes: a spec
    # whose data was no list failed load_results, grid_status and run_grid with a bare TypeError, and a band of -1
    # loaded as every cell's band
    from graybox import experiments as gx
    path = _edited(small_store, tmp_path, "specs", "spec", edit)
    for read in (gb.load_results, gx.grid_status):
        with pytest.raises(gx.StoreError, match="damaged.*data sets"):
            read(path)


_SEL = dict(sizes=[4, 6], estimator="pe", lambdas=[0.1, 0.5, 1.0], sources=("frols",), progress=False)


@pytest.fixture(scope="module")
def selection_checkpoint(pumping, tmp_path_factory):
    path = tmp_path_factory.mktemp("sel") / "sel.npz"
    cand = gb.Candidates(ny=2, nu=2, ne=0, degree=2, max_y_power=1)
    chosen = gb.select_graybox(cand, pumping, checkpoint=path, **_SEL)
    with np.load(path, allow_pickle=False) as z:
        return cand, chosen, {k: z[k] for k in z.files}


def _row_edited(arrays, field, edit):
    out = dict(arrays)
    for name in [k for k in arrays if k.endswith("/" + field)]:
        v = arrays[name].copy()
        edit(v)
        out[name] = v
    return out


@pytest.mark.parametrize("field,edit", [
    ("lambdas", lambda v: v.__setitem__(0, -1.0)),    # 'ParetoSet: lambdas must lie in (0, 1]', no file named
    ("lambdas", lambda v: v.__setitem__(0, 0.0)),
    ("lambdas", lambda v: v.__setitem__(0, 2.0)),
])
def test_a_selection_checkpoints_damaged_row_is_a_checkpoint_error(pumping, selection_checkpoint, tmp_path, field,
                                                                    edit):
    # _row_problem checked the arrays' kinds and shapes, not a λ1 outside (0, 1], which no fit writes: select_graybox
    # then failed after reading the file with the ValueError of the ParetoSet it built, naming no file
    from graybox.estimation._simulation_error import CheckpointError
    cand, _, arrays = selection_checkpoint
    path = tmp_path / "sel.npz"
    np.savez(path, **_row_edited(arrays, field, edit))
    with pytest.raises(CheckpointError, match=f"{path}.*corrupt.*{field}"):
        gb.select_graybox(cand, pumping, checkpoint=path, **_SEL)


def test_a_kept_member_without_theta_is_never_chosen(pumping, selection_checkpoint, tmp_path):
    # the fit gives a member without θ (its refit on all the identification data failed) inf block scores; a kept
    # row with finite ones for it (an edit, or a graybox before that rule) had it chosen, and select_graybox then
    # failed with 'member 0 of this set failed: the fit failed at this λ'
    cand, chosen, arrays = selection_checkpoint
    k = chosen.decision.index
    path = tmp_path / "sel.npz"
    np.savez(path, **_row_edited(arrays, "thetas", lambda v: v.__setitem__((k, 0), np.nan)))
    with pytest.warns(gb.SelectionWarning, match="no structure meets the band"):  # none other is in it
        again = gb.select_graybox(cand, pumping, checkpoint=path, fallback="min_jsf", **_SEL)
    assert again.decision.lambda1 != chosen.decision.lambda1 and np.all(np.isfinite(again.model.theta))


def test_a_selection_checkpoint_with_a_failed_member_resumes(pumping, selection_checkpoint, tmp_path):
    cand, chosen, arrays = selection_checkpoint

    k = chosen.decision.index  # the chosen member of every row had no fit, as the fit writes it: θ NaN, blocks inf
    edited = _row_edited(_row_edited(arrays, "thetas", lambda v: v.__setitem__(k, np.nan)), "blocks",
                         lambda v: v.__setitem__(k, np.inf))
    path = tmp_path / "sel.npz"
    np.savez(path, **edited)
    with pytest.warns(gb.SelectionWarning, match="no structure meets the band"):  # none other is in it
        again = gb.select_graybox(cand, pumping, checkpoint=path, fallback="min_jsf", **_SEL)
    assert again.decision.lambda1 != chosen.decision.lambda1
    assert np.all(np.isfinite(again.model.theta))


@pytest.mark.parametrize("edit", [  # θ edited and its equation removed (a stale one is refused as such: mend61e)
    lambda o: o["model"]["theta"].__setitem__(0, o["model"]["theta"][0] + 1.0) or o["model"].pop("equation"),
    lambda o: o["decision"]["model"]["theta"].__setitem__(1, 0.0) or o["decision"]["model"].pop("equation"),
])
def test_a_graybox_selections_model_is_its_decisions(selection_checkpoint, edit):
    # select_graybox gives the decision's model as the selection's model; a file whose two differed loaded, and the
    # selection then simulated one model (.model) and took the other's covariance (.uncertainty uses the decision)
    _, chosen, _ = selection_checkpoint
    doc = json.loads(gb.to_json(chosen))
    edit(doc["object"])
    with pytest.raises(gb.GrayboxFileError, match="decision"):
        gb.from_json(json.dumps(doc), source="sel.json")
    back = gb.from_json(gb.to_json(chosen))
    assert back.model.theta.tobytes() == chosen.model.theta.tobytes() == back.decision.model.theta.tobytes()


@pytest.mark.parametrize("stable,radius", [(True, 1.5), (True, float("inf")), (True, 1.001), (False, 0.5), (False, 0.0)])
def test_an_equilibriums_stability_agrees_with_its_spectral_radius(stable, radius):
    # stable says every root of the linearisation lies strictly inside the unit circle, spectral_radius is the
    # largest modulus of those roots: an Equilibrium (a hand-edited file) saying stable with a root at 1.5 or inf, or
    # unstable with every root inside, loaded as it said
    text = gb.to_json(gb.Equilibrium(ubar=1.0, ybar=2.0, stable=stable, spectral_radius=0.5 if stable else 1.5))
    doc = json.loads(text)
    doc["object"]["spectral_radius"] = "inf" if radius == float("inf") else radius
    with pytest.raises(gb.GrayboxFileError, match="spectral_radius"):
        gb.from_json(json.dumps(doc), source="eq.json")


@pytest.mark.parametrize("stable,radius", [(True, 0.999999999999), (True, 0.0), (True, 1.0 + 1e-9), (False, 1.0),
                                           (False, float("inf")), (False, 1.0 - 1e-12)])
def test_an_equilibrium_at_its_rounding_still_builds(stable, radius):
    # the stability test and the roots' moduli are computed apart: at the unit circle they may differ by rounding (a
    # root at 1 to rounding is not inside, the Schur-Cohn test's rule; a double root's modulus is good to ~1e-8)
    assert gb.Equilibrium(1.0, 2.0, stable, radius).stable is stable


def test_computed_equilibria_keep_stability_and_radius_together():
    rng = np.random.default_rng(5)
    st = gb.Structure(["1", "y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)", "y(k-1)^2", "y(k-2)^2"])
    scale = np.array([1, 0.8, 0.5, 0.1, 0.01, 0.05, 0.05, 0.05])
    count = 0
    for _ in range(300):
        for e in gb.equilibria(st, rng.standard_normal(len(st)) * scale, float(rng.uniform(-2, 2))):
            assert e.stable == (e.spectral_radius < 1)
            count += 1
    assert count > 100
