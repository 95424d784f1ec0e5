"""hunt44b: files and runs that outlive one call: the grid's store, select_graybox's checkpoint, the CLI on them.

Read-only files and folders are made as a user meets them: by their mode for a user, by the immutable attribute
(``chattr +i``) for root, whom modes do not stop; where neither can be had the test is skipped.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sqlite3
import subprocess
from pathlib import Path

import numpy as np
import pytest

from graybox import experiments as gx
from graybox._cli import main
from _reports import undrawn_figures

ONE = gx.StructureSpec("first-order", terms=["y(k-1)", "u(k-1)", "1"])
LS = gx.Variant("LS", "ls")


def grid(structures=(ONE,), variants=(LS,), name="g") -> gx.Grid:
    return gx.Grid([gx.DataSpec("pumping", bundled="pumping")], list(structures), list(variants), name=name)


@pytest.fixture(scope="module")
def store(tmp_path_factory) -> Path:
    """One finished cell; tests use copies."""
    p = tmp_path_factory.mktemp("base") / "base.sqlite"
    gx.run_grid(grid(), p)
    return p


def copy_of(src: Path, folder: Path, name: str = "s.sqlite") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    dst = folder / name
    shutil.copyfile(src, dst)  # the file alone: the run closed it, its log folded in
    return dst


@contextlib.contextmanager
def read_only(path: Path):
    """``path`` (a file or a folder) read-only for this process while the block runs."""
    if os.geteuid() != 0:
        mode = path.stat().st_mode
        path.chmod(0o555 if path.is_dir() else 0o444)
        try:
            yield
        finally:
            path.chmod(mode)
        return
    chattr = shutil.which("chattr")
    if chattr is None or subprocess.run([chattr, "+i", str(path)], capture_output=True).returncode != 0:
        pytest.skip("no way to make a file read-only for root here (chattr +i)")
    try:
        yield
    finally:
        subprocess.run([chattr, "-i", str(path)], check=True)


def test_a_store_in_a_read_only_folder_is_read_not_called_damaged(store, tmp_path, capsys, monkeypatch):
    # a colleague's results folder, an archive: reading a store there said "damaged … restore it from a copy"
    # (SQLite could not make the WAL index beside it)
    folder = tmp_path / "archive"
    p = copy_of(store, folder)
    expected = gx.load_results(store)
    gx.load_results(p)  # a reader leaves the log's index beside it (and the empty log: removed, as a copy lacks it)
    Path(f"{p}-wal").unlink(missing_ok=True)
    assert Path(f"{p}-shm").exists()
    with read_only(folder):
        df = gx.load_results(p)
        assert list(df["key"]) == list(expected["key"])
        assert list(df["JS_valid"]) == list(expected["JS_valid"])
        assert len(gx.store_specs(p)) == 1
        assert gx.grid_status(p).done == 1
        assert main(["grid", "status", str(p)]) == 0
        assert "1 of 1 cells done" in capsys.readouterr().out
        undrawn_figures(monkeypatch)  # the store is read; its report's figures are not what is asked
        assert main(["grid", "report", str(p), "--out", str(tmp_path / "rep")]) == 0
    assert (tmp_path / "rep" / "leaderboard.csv").exists()


def test_a_store_whose_log_holds_writes_in_a_read_only_folder_is_refused_naming_the_log(store, tmp_path):
    # read without its log, such a store would lose the cells written last: refused, saying what to copy
    folder = tmp_path / "archive"
    p = copy_of(store, folder)
    conn = sqlite3.connect(p, isolation_level=None)
    conn.execute("PRAGMA wal_autocheckpoint=0")
    conn.execute("UPDATE specs SET name = 'renamed'")
    shutil.copyfile(f"{p}-wal", tmp_path / "log")
    conn.close()  # folds the log into the file and removes it: the log is put back as a killed run leaves it
    shutil.copyfile(tmp_path / "log", f"{p}-wal")
    os.remove(tmp_path / "log")
    for f in folder.glob("*-shm"):
        f.unlink()
    with read_only(folder), pytest.raises(gx.StoreError, match=r"s\.sqlite-wal.*copy the store and s\.sqlite-wal"):
        gx.load_results(p)


@pytest.mark.parametrize("what", ["file", "folder"])
def test_running_into_a_read_only_store_is_refused_naming_it_and_the_fix(store, tmp_path, capsys, what):
    # a read-only file raised sqlite3's bare "attempt to write a readonly database" (a traceback from the command),
    # a read-only folder its "unable to open database file"
    folder = tmp_path / "archive"
    p = copy_of(store, folder)
    before = p.read_bytes()
    two = grid(variants=(LS, gx.Variant("LS2", "els", options={"noise": 0})))
    with read_only(p if what == "file" else folder):
        with pytest.raises(gx.StoreError, match=rf"{p.name}.*read-only.*nothing was written.*--store"):
            gx.run_grid(two, p)
        assert main(["grid", "run", str(_spec(tmp_path)), "--store", str(p)]) == 2
    assert p.read_bytes() == before
    err = capsys.readouterr().err
    assert str(p) in err and "read-only" in err


def test_a_new_store_in_a_read_only_folder_is_refused_naming_it(tmp_path):
    # the half-made store's clean-up, refused by a read-only file system, hid the refusal behind an OSError
    # naming a hidden temporary file
    folder = tmp_path / "archive"
    folder.mkdir()
    with read_only(folder), pytest.raises(gx.StoreError, match=r"new\.sqlite.*folder you can write in"):
        gx.run_grid(grid(), folder / "new.sqlite")
    assert list(folder.iterdir()) == []


def test_a_checkpoint_in_a_read_only_folder_is_refused_before_any_fit(tmp_path, monkeypatch):
    # select_graybox fitted its first row (seconds to hours), then failed on an OSError naming the checkpoint's
    # temporary file; a folder that does not exist was refused before, a folder it cannot write in was not
    import graybox as gb
    from graybox.experiments import _select

    def fitted(job):
        raise AssertionError("a row was fitted before the checkpoint was refused")

    monkeypatch.setattr(_select, "_score_job", fitted)
    folder = tmp_path / "archive"
    folder.mkdir()
    with read_only(folder):
        with pytest.raises(ValueError, match=r"checkpoint: .*archive.*cannot be written.*another path"):
            gb.select_graybox(gb.Candidates(ny=1, nu=1, degree=2), gb.load_pumping(), sizes=[2], estimator=["pe"],
                              progress=False, checkpoint=folder / "sel.npz")
        with pytest.raises(ValueError, match=r"checkpoint: .*archive.*cannot be written"):
            gb.se_pareto(gb.Structure(["y(k-1)", "u(k-1)", "1"]), gb.load_pumping(), method="gradient",
                         lambdas=[0.5], progress=False, checkpoint=folder / "se.npz")


WRITER = """
import sys
import numpy as np
from graybox.experiments._select_checkpoint import SelectionCheckpoint
ck = SelectionCheckpoint(sys.argv[1])
row = {"blocks": np.zeros((2, 3)), "weights": np.ones(3), "jsf": np.zeros(2), "jsf_full": np.zeros(2),
       "thetas": np.zeros((2, 5000)), "lambdas": np.ones(2), "failed": ["", ""], "warnings": []}
for i in range(400):
    ck.put(f"{sys.argv[2]}{i:031x}", row)
    ck.rows.pop(next(iter(ck.rows)))  # a few rows: each rewrite short, many rewrites
"""


def test_two_selections_writing_one_checkpoint_both_finish_and_leave_it_whole(tmp_path):
    # the docstring's promise ("two running at once each rewrite it with their own rows, the file stays whole"):
    # both wrote the same temporary file, so one moved the other's (half written) into place and the other's
    # move then failed: FileNotFoundError, that selection ended after fitting its row
    import sys

    from graybox.experiments._select_checkpoint import SelectionCheckpoint

    path = tmp_path / "sel.npz"
    procs = [subprocess.Popen([sys.executable, "-c", WRITER, str(path), tag], stderr=subprocess.PIPE, text=True)
             for tag in "ab"]
    errs = [p.communicate(timeout=300)[1] for p in procs]
    assert [p.returncode for p in procs] == [0, 0], errs
    assert 1 <= len(SelectionCheckpoint(path).rows) <= 2  # the last rewrite, read whole
    assert sorted(f.name for f in tmp_path.iterdir()) == ["sel.npz"]


def test_a_file_whose_header_contradicts_its_values_units_is_refused(tmp_path):
    # save refuses to write a header naming other units than the value's own; a file edited so (the header's units
    # "corrected" by hand) loaded a Model in rpm while read_header told the reader rad/s
    import json

    import graybox as gb

    d = gb.load_pumping()
    m = gb.els(gb.Structure(["y(k-1)", "u(k-1)", "1"]), d.ident).model
    assert m.units == ("rpm", "mlc")
    path = tmp_path / "m.json"
    gb.save(m, path)
    doc = json.loads(path.read_text())
    doc["units"] = {"u": "rad/s", "y": "mlc"}
    path.write_text(json.dumps(doc))
    with pytest.raises(gb.GrayboxFileError, match=r"m\.json.*'rad/s'.*'rpm'"):
        gb.load(path)
    doc["units"] = {"u": "rpm"}  # naming fewer, as save(units=) may: the value's fill the rest
    path.write_text(json.dumps(doc))
    assert gb.load(path).units == ("rpm", "mlc")


def test_a_new_band_on_a_store_of_the_same_cells_is_the_band_its_results_are_read_with(store, tmp_path, capsys):
    # the band of a data set changed in the spec, no variant reading it: the same cells, so the same fingerprint,
    # and the store kept the spec of the first run; load_results, grid status and grid report went on ranking by
    # the old band, the new one silently ignored
    p = copy_of(store, tmp_path)

    def g(band):
        return gx.Grid([gx.DataSpec("pumping", bundled="pumping", band=band)], [ONE], [LS], name="g")

    first = gx.run_grid(g(1e-6), p)
    assert set(gx.load_results(p)["band"]) == {1e-6}
    res = gx.run_grid(g(5.0), p)
    assert res.ran == 0 and res.spec != first.spec  # a spec of its own: the store keeps every spec it has seen
    assert any("band" in n for n in res.notes)
    assert set(gx.load_results(p)["band"]) == {5.0}
    assert set(gx.load_results(p, spec=first.spec)["band"]) == {1e-6}
    assert gx.run_grid(g(1e-6), p).spec == first.spec  # and the old band is the old spec again
    assert set(gx.load_results(p)["band"]) == {1e-6}
    assert len(gx.store_specs(p)) == 3  # the fixture's (the bundled band), 1e-6, 5.0


def test_two_runs_at_once_cannot_give_one_data_set_name_two_meanings(store, tmp_path, monkeypatch):
    # each run checked the store's data set names before taking its write lock: a run started meanwhile (two
    # terminals, a job array) registering the same name for other data slipped between that check and the
    # registration, and the store held the name with two meanings, mixed in load_results(spec="all") and
    # refused to the second spec for ever after
    import graybox as gb
    from graybox.experiments import _store

    p = copy_of(store, tmp_path)
    d = gb.load_pumping()
    other = gb.Dataset(d.ident, d.valid, gb.StaticPoints(d.static.ubar, d.static.ybar + 0.01))
    mine = gx.Grid([gx.DataSpec("plant", dataset=other)], [ONE], [LS], name="mine")
    theirs = gx.Grid([gx.DataSpec("plant", bundled="pumping")], [ONE], [LS], name="theirs")
    real = _store._connect_to_write
    state = {"other run": False}

    def meanwhile(path, at, verb):  # the other run registers while this one is between its check and its lock
        if not state["other run"]:
            state["other run"] = True
            gx.run_grid(theirs, p)
        return real(path, at, verb)

    monkeypatch.setattr(_store, "_connect_to_write", meanwhile)
    with pytest.raises(gx.StoreError, match=r"data set 'plant'.*other data.*Nothing was written"):
        gx.run_grid(mine, p)
    assert state["other run"]
    assert list(gx.store_specs(p)["name"]) == ["g", "theirs"]
    hashes = {h for d in gx.store_specs(p)["data"] for n, h in d.items() if n == "plant"}
    assert len(hashes) == 1


@pytest.mark.parametrize("sql", [
    "UPDATE cells SET theta = 'garbage'", "UPDATE cells SET members = '[1, 2]'", "UPDATE cells SET terms = '5'",
    "UPDATE cells SET JS_valid = 'abc'", "UPDATE cells SET warnings = '{'", "UPDATE specs SET spec = '{bad'",
    "UPDATE specs SET data = '[1]'"])
def test_a_store_damaged_inside_its_rows_is_refused_naming_it(store, tmp_path, capsys, sql):
    # a text SQLite's integrity check cannot judge (a cell's JSON, a spec's) raised json's "Expecting value: line 1
    # column 1 (char 0)", naming no file, or an AttributeError / TypeError traceback from graybox grid status
    p = copy_of(store, tmp_path)
    conn = sqlite3.connect(p)
    conn.execute(sql)
    conn.commit()
    conn.close()
    with pytest.raises(gx.StoreError, match=rf"{p.name}.*damaged.*restore it from a copy"):
        gx.load_results(p)
    assert main(["grid", "status", str(p)]) == 2
    assert str(p) in capsys.readouterr().err


def test_a_checkpoint_path_naming_another_file_is_refused_without_talk_of_pickle(store, tmp_path):
    # select_graybox(checkpoint=) given the grid store (or a spec, a model file) by mistake said numpy's "This file
    # contains pickled (object) data. If you trust the file you can load it unsafely using allow_pickle= or
    # pickle.load()": neither true nor advice to give (se_pareto's checkpoint says what the file is instead)
    import graybox as gb

    p = copy_of(store, tmp_path, "results.sqlite")
    before = p.read_bytes()
    for given in (p, tmp_path / "spec.toml"):
        if given.suffix == ".toml":
            given.write_text("name = 'g'\n")
        with pytest.raises(ValueError, match=r"results\.sqlite|spec\.toml") as exc:
            gb.select_graybox(gb.Candidates(ny=1, nu=1, degree=2), gb.load_pumping(), sizes=[2], estimator=["pe"],
                              progress=False, checkpoint=given)
        # refused by its name (another format's ending) before the file is read
        assert "pickle" not in str(exc.value) and "a checkpoint is an .npz file" in str(exc.value)
    assert p.read_bytes() == before


def test_a_store_another_program_keeps_locked_is_refused_naming_it_not_a_traceback(store, tmp_path, capsys,
                                                                                    monkeypatch):
    # an SQLite browser with unsaved changes, a stuck process: after SQLite's wait graybox grid run ended in a
    # traceback of sqlite3's bare "database is locked", at the start of a run or in the middle of one
    from graybox.experiments import _store

    monkeypatch.setattr(_store, "LOCK_TIMEOUT", 0.3)
    p = copy_of(store, tmp_path)
    other = sqlite3.connect(p, isolation_level=None)
    other.execute("BEGIN IMMEDIATE")
    other.execute("UPDATE meta SET value = value")
    two = grid(variants=(LS, gx.Variant("LS2", "els", options={"noise": 0})))
    with pytest.raises(gx.StoreError, match=rf"{p.name}.*locked by another program.*nothing was written"):
        gx.run_grid(two, p)
    other.execute("ROLLBACK")

    def lock_now(line):  # the run has registered its spec: the lock comes as its cells start
        if not other.in_transaction:
            other.execute("BEGIN IMMEDIATE")
            other.execute("UPDATE meta SET value = value")

    with pytest.raises(gx.StoreError, match=rf"{p.name}.*locked by another program.*cells finished so far are kept"):
        gx.run_grid(two, p, log=lock_now)
    other.execute("ROLLBACK")
    other.close()
    assert gx.run_grid(two, p).ran == 1  # the lock gone, the run ends what the last one left


def test_status_of_all_specs_counts_the_cells_left(store, tmp_path, capsys):
    # with --spec all the cells were counted as those the store holds: "1 of 1 cells done, 0 left" of a store whose
    # second spec had not run its new cell (a run killed, or still running)
    import graybox as gb
    from graybox.experiments._spec import stored_spec
    from graybox.experiments._store import ResultStore

    p = copy_of(store, tmp_path)
    g = grid(variants=(LS, gx.Variant("LS2", "els", options={"noise": 0})))
    ds = g.load_data()
    cells = g.cells(ds)
    ResultStore.open(p, grid_name=g.name, fingerprint=g.fingerprint(cells), spec=stored_spec(g, ds), cells=cells,
                     version=gb.__version__).close()  # registered, as a run does before its first cell
    st = gx.grid_status(p, spec="all")
    assert (st.cells, st.done, st.left) == (2, 1, 1)
    assert gx.load_results(p, spec="all").attrs["n_cells"] == 2
    assert main(["grid", "status", str(p), "--spec", "all"]) == 0
    assert "1 of 2 cells done" in capsys.readouterr().out


def test_a_checkpoint_path_that_is_a_folder_is_refused_as_one(tmp_path):
    # checkpoint="out" (the folder meant to hold it) said "is not a readable … checkpoint ([Errno 21] Is a
    # directory); delete it or choose another checkpoint path": delete the folder?
    import graybox as gb

    folder = tmp_path / "out"
    folder.mkdir()
    (folder / "keep.txt").write_text("results")
    calls = (lambda: gb.select_graybox(gb.Candidates(ny=1, nu=1, degree=2), gb.load_pumping(), sizes=[2],
                                       estimator=["pe"], progress=False, checkpoint=folder),
             lambda: gb.se_pareto(gb.Structure(["y(k-1)", "u(k-1)", "1"]), gb.load_pumping(), method="gradient",
                                  lambdas=[0.5], progress=False, checkpoint=folder))
    for call in calls:
        with pytest.raises(ValueError, match=r"checkpoint: .*out is a folder.*file path") as exc:
            call()
        assert "delete" not in str(exc.value)
    assert (folder / "keep.txt").read_text() == "results"


def test_a_file_edited_to_hold_a_field_twice_is_refused_naming_it(tmp_path):
    # a theta line copied to be changed and the old one left: JSON reads the last and the file loaded silently
    # with whichever came last
    import graybox as gb

    d = gb.load_pumping()
    m = gb.els(gb.Structure(["y(k-1)", "u(k-1)", "1"]), d.ident).model
    path = tmp_path / "m.json"
    gb.save(m, path)
    text = path.read_text()
    line = next(ln for ln in text.splitlines() if ln.strip().startswith('"theta"'))
    path.write_text(text.replace(line, line.replace("[", "[2.0, ", 1) + "\n" + line))
    with pytest.raises(gb.GrayboxFileError, match=r"m\.json.*'theta'.*twice"):
        gb.load(path)


def test_one_functions_checkpoint_given_to_the_other_is_named_not_offered_for_deletion(tmp_path):
    # se_pareto's checkpoint (a sweep of hours) given to select_graybox, or the other way round, was "not a
    # select_graybox checkpoint; delete it or …" / "not a readable SE checkpoint ('meta'); delete it or …"
    import graybox as gb
    from graybox.estimation._simulation_error import save_npz
    from graybox.experiments._select_checkpoint import SelectionCheckpoint

    se, sel = tmp_path / "se.npz", tmp_path / "sel.npz"
    save_npz(se, meta="{}", thetas=np.zeros((1, 3)))  # an SE sweep's arrays (its meta JSON text first)
    save_npz(sel, kind=np.array("select_graybox"))
    with pytest.raises(ValueError, match=r"se\.npz is se_pareto's checkpoint.*choose another") as exc:
        SelectionCheckpoint(se)
    assert "delete" not in str(exc.value)
    with pytest.raises(ValueError, match=r"sel\.npz is select_graybox's checkpoint.*choose another") as exc:
        gb.se_pareto(gb.Structure(["y(k-1)", "u(k-1)", "1"]), gb.load_pumping(), method="gradient", lambdas=[0.5],
                     progress=False, checkpoint=sel)
    assert "delete" not in str(exc.value)


def test_report_files_of_data_sets_named_apart_only_by_case_stay_apart_on_any_file_system(tmp_path, monkeypatch):
    # "Plant" and "plant" wrote heatmap_Plant.png and heatmap_plant.png: one file on macOS's and Windows' file
    # systems, which do not tell case apart, so one data set's figures and table overwrote the other's
    import graybox as gb

    d = gb.load_pumping()
    other = gb.Dataset(d.ident, d.valid, gb.StaticPoints(d.static.ubar, d.static.ybar + 0.01))
    g = gx.Grid([gx.DataSpec("Plant", bundled="pumping"), gx.DataSpec("plant", dataset=other, band=0.1)], [ONE],
                [LS], name="g")
    p = tmp_path / "s.sqlite"
    gx.run_grid(g, p)
    undrawn_figures(monkeypatch)  # the files' names are asserted
    names = [f.name for f in gx.write_report(p, tmp_path / "rep")]
    assert len({n.lower() for n in names}) == len(names)


def test_a_checkpoint_behind_a_symbolic_link_is_written_through_it(tmp_path):
    # checkpoint="latest.npz", a link to runs/a.npz: the first row replaced the link by a file of its own, and
    # runs/a.npz kept the rows it had (graybox's JSON files are written through a link, as open(p, "w") would)
    from graybox.experiments._select_checkpoint import SelectionCheckpoint

    (tmp_path / "runs").mkdir()
    link = tmp_path / "latest.npz"
    link.symlink_to(tmp_path / "runs" / "a.npz")
    ck = SelectionCheckpoint(link)
    row = {"blocks": np.zeros((2, 3)), "weights": np.ones(3), "jsf": np.zeros(2), "jsf_full": np.zeros(2),
           "thetas": np.zeros((2, 3)), "lambdas": np.ones(2), "failed": ["", ""], "warnings": []}
    ck.put("0" * 32, row)
    assert link.is_symlink()
    assert list(SelectionCheckpoint(tmp_path / "runs" / "a.npz").rows) == ["0" * 32]


def test_a_checkpoint_write_killed_leaves_no_file_for_ever(tmp_path):
    # each rewrite goes through a file of its own beside the checkpoint: one a killed call left is swept by the next
    # call on the checkpoint (a live process's is left to it; on another host, one old is taken for a killed one's)
    import sys
    import time

    from graybox.core._files import writer_tag
    from graybox.estimation._simulation_error import checkpoint_path, save_npz

    host = writer_tag().rsplit("-", 1)[0]  # a write's file names its host and its process
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    live = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        path = tmp_path / "sel.npz"
        dead, alive, old, other = (tmp_path / f"sel.npz.{host}-{gone.pid}-0badc0de.tmp",
                                   tmp_path / f"sel.npz.{host}-{live.pid}-1badc0de.tmp",
                                   tmp_path / f"sel.npz.{host}-{live.pid}-2badc0de.tmp",
                                   tmp_path / "notes.1-0badc0de.tmp")
        for f in (dead, alive, old, other):
            f.write_bytes(b"half")
        an_hour_ago = time.time() - 3600
        for f in (old, other):
            os.utime(f, (an_hour_ago, an_hour_ago))
        checkpoint_path(path)
        assert not dead.exists() and not old.exists() and alive.exists() and other.exists()
        alive.unlink()
        save_npz(path, x=np.zeros(2))  # and a write: nothing beside the file but what is not its
        assert sorted(f.name for f in tmp_path.iterdir()) == ["notes.1-0badc0de.tmp", "sel.npz"]
    finally:
        live.kill()
        live.wait()


def _spec(tmp_path: Path) -> Path:
    p = tmp_path / "spec.toml"
    p.write_text('name = "g"\n[[data]]\nname = "pumping"\nbundled = "pumping"\n[[structures]]\nname = "first-order"\n'
                 'terms = ["y(k-1)", "u(k-1)", "1"]\n[[variants]]\nname = "LS"\nestimator = "ls"\n')
    return p
