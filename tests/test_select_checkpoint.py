"""select_graybox(checkpoint=): rows kept as they finish, a run SIGKILLed and called again refits only the rest
(a real subprocess, a real SIGKILL, a real file), on the driver, local processes and Dask."""

from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import sys
import textwrap
import time
import warnings

import numpy as np
import pandas as pd
import pytest

import graybox as gb
from graybox.experiments import _select

from conftest import two_level_records

CAND = gb.Candidates(ny=2, nu=2, degree=2)
KW = dict(sizes=[3, 4, 5], estimator=["pe", "se-gradient"], progress=False)

RUN = textwrap.dedent("""
    import sys
    import graybox as gb
    gb.select_graybox(gb.Candidates(ny=2, nu=2, degree=2), gb.load_pumping(), sizes=[3, 4, 5],
                      estimator=["pe", "se-gradient"], progress=False, checkpoint=sys.argv[1])
""")


@pytest.fixture(scope="module")
def data():
    return gb.load_pumping()


@pytest.fixture(scope="module")
def uninterrupted(data):
    return gb.select_graybox(CAND, data, **KW)


def _counting(monkeypatch) -> list:
    calls: list = []
    score = _select._score_job
    monkeypatch.setattr(_select, "_score_job", lambda job: (calls.append(job), score(job))[1])
    return calls


def _rows(path) -> int:
    try:
        with np.load(path, allow_pickle=False) as z:
            return sum(name.endswith("/thetas") for name in z.files)
    except (OSError, ValueError, EOFError):
        return 0


def test_a_killed_selection_resumes_with_the_rows_it_finished(tmp_path, data, uninterrupted, monkeypatch):
    path = tmp_path / "sel.npz"
    proc = subprocess.Popen([sys.executable, "-c", RUN, str(path)])
    try:
        deadline = time.monotonic() + 300
        while _rows(path) < 2 and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.wait(timeout=60)
    kept = _rows(path)
    assert kept >= 2  # read whole after the kill: the file is replaced atomically, never torn
    calls = _counting(monkeypatch)
    res = gb.select_graybox(CAND, data, checkpoint=path, **KW)
    n = len(uninterrupted.table)
    assert len(calls) == n - kept  # only the rows the killed run had not finished
    pd.testing.assert_frame_equal(res.table, uninterrupted.table)
    np.testing.assert_array_equal(res.model.theta, uninterrupted.model.theta)
    assert _rows(path) == n and sorted(os.listdir(tmp_path)) == ["sel.npz"]


def test_rows_kept_by_worker_processes_serve_a_call_with_other_sizes(tmp_path, data, uninterrupted, monkeypatch):
    path = tmp_path / "sel.npz"
    res = gb.select_graybox(CAND, data, checkpoint=path, executor="processes", workers=2, **KW)
    pd.testing.assert_frame_equal(res.table, uninterrupted.table)
    assert _rows(path) == len(res.table)
    calls = _counting(monkeypatch)
    grown = gb.select_graybox(CAND, data, checkpoint=path, **{**KW, "sizes": [3, 4, 5, 6]})
    fresh = {j.terms for j in calls}  # the structures of size 6 only, each with both estimators
    assert len(calls) == 2 * len(fresh) and fresh and not fresh & set(res.table["terms"])
    assert fresh <= set(grown.table["terms"]) and len(grown.table) == len(res.table) + len(calls)
    # other options are other rows: the ones of another λ1 grid are fitted, not read (the size-3 rows: each a fit)
    calls.clear()
    gb.select_graybox(CAND, data, checkpoint=path, **{**KW, "sizes": [3], "lambdas": [0.1, 1.0]})
    assert len(calls) == int((res.table["size"] == 3).sum()) > 0


def test_a_file_that_is_no_selection_checkpoint_is_refused_before_anything_runs(tmp_path, data, monkeypatch):
    calls = _counting(monkeypatch)
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip file")
    with pytest.raises(ValueError, match="is not a readable select_graybox checkpoint"):
        gb.select_graybox(CAND, data, checkpoint=bad, **KW)
    other = tmp_path / "other.npz"
    np.savez(other, meta="{}", thetas=np.zeros((2, 3)))
    with pytest.raises(ValueError, match="is not a select_graybox checkpoint"):
        gb.select_graybox(CAND, data, checkpoint=other, **KW)
    pickled = tmp_path / "pickled.npz"
    np.savez(pickled, kind=np.array("select_graybox"), x=np.array([{"a": 1}], dtype=object))
    with pytest.raises(ValueError, match="not a readable select_graybox checkpoint"):
        gb.select_graybox(CAND, data, checkpoint=pickled, **KW)
    torn = tmp_path / "torn.npz"
    np.savez(torn, **{"kind": np.array("select_graybox"), "0" * 32 + "/thetas": np.zeros((1, 3))})
    with pytest.raises(ValueError, match="corrupt"):
        gb.select_graybox(CAND, data, checkpoint=torn, **KW)
    with pytest.raises(ValueError, match="does not exist"):
        gb.select_graybox(CAND, data, checkpoint=tmp_path / "no" / "sel.npz", **KW)
    with pytest.raises(TypeError, match="checkpoint"):
        gb.select_graybox(CAND, data, checkpoint=3, **KW)
    assert calls == []


def test_parallel_map_tells_of_each_finished_job_on_dask():
    seen: dict = {}
    with gb.experiments.parallel_map(workers=1) as pmap:
        out = pmap(abs, [-1, 2, -3], each=lambda i, r: seen.__setitem__(i, r))
    assert out == [1, 2, 3] and seen == {0: 1, 1: 2, 2: 3}
    with gb.experiments.parallel_map(executor="inprocess") as pmap:
        seen.clear()
        assert pmap(abs, [-4], each=lambda i, r: seen.__setitem__(i, r)) == [4] and seen == {0: 4}


# -- a member whose fit failed: said in the table, kept in the checkpoint ----------------------------

def _two_level_dataset() -> gb.Dataset:
    return gb.Dataset(*two_level_records())


def _pe_selection(ds, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gb.select_graybox(gb.Candidates(1, 1, ne=0, degree=2), ds, band=1e-2, sizes=[3], estimator="pe",
                                 sources=("frols",), include=("1", "u(k-1)^2"), **kw)


def test_a_member_whose_fit_failed_is_said_with_its_reason_and_kept_so(tmp_path):
    ds = _two_level_dataset()
    path = tmp_path / "sel.npz"
    first = _pe_selection(ds, checkpoint=path)
    said = first.table["failed_members"].iloc[0]
    # was: the member was dropped (a NaN row) and nothing in the result said which or why
    assert said.startswith("1 of ") and "(λ1 = 1)" in said and "not identifiable" in said and "'ident'" in said
    assert first.decision.lambda1 < 1.0
    again = _pe_selection(ds, checkpoint=path)  # every row from the file: the reason with it
    pd.testing.assert_frame_equal(again.table, first.table)
    with np.load(path) as z:  # a file an earlier 0.3.0 wrote: no member reasons kept
        old = {k: z[k] for k in z.files if not k.endswith("/member_failed")}
    np.savez(path, **old)
    from_old = _pe_selection(ds, checkpoint=path)
    assert from_old.table["failed_members"].iloc[0] == said.split(": ", 1)[0] + ": the fit failed at this λ"
    assert from_old.decision.lambda1 == first.decision.lambda1


def _slow_or_failing(job: tuple) -> int:
    """Job 1 returns at once; jobs 0 and 2 wait until the first result was told of (``told`` exists, so that the
    order does not hang on which worker started first), then 0 fails and 2 returns half a second later."""
    import pathlib
    import time

    x, told = job
    if x == 1:
        return x
    while not pathlib.Path(told).exists():
        time.sleep(0.01)
    if x == 0:
        raise RuntimeError("job 0 fails")
    time.sleep(0.5)
    return x


def test_a_job_error_on_dask_still_tells_of_the_jobs_that_finished_before_it(tmp_path):
    # was: the first error ended the loop over finished jobs, and a job that had finished but was not yet yielded
    # was never told of: a select_graybox(checkpoint=) row lost on Dask (local processes kept it). Here the first
    # job's `each` takes 3 s; meanwhile job 0 fails and then job 2 finishes
    import time

    told = tmp_path / "told"
    seen: dict = {}

    def each(i, r):
        seen[i] = r
        if len(seen) == 1:
            told.touch()
            time.sleep(3.0)

    with gb.experiments.parallel_map(workers=2) as pmap:
        with pytest.raises(RuntimeError, match="job 0 fails"):
            pmap(_slow_or_failing, [(1, str(told)), (0, str(told)), (2, str(told))], each=each)
    assert seen == {0: 1, 2: 2}



def test_a_test_record_added_or_changed_refits_no_row(tmp_path, data, monkeypatch):
    # was: the test records were part of every row's key, so a selection called again to report on a new test
    # record refitted every row (hours for SE rows), though a test record never changes a fit or a choice
    kw = dict(sizes=[3, 4], estimator="pe", progress=False)
    path = tmp_path / "sel.npz"
    first, second = data.valid.slice(400, 600), data.valid.slice(500, 800)
    data = gb.Dataset(data.ident, data.valid.slice(0, 400), data.static)
    gb.select_graybox(CAND, data, checkpoint=path, **kw)  # no test record
    calls = _counting(monkeypatch)
    fresh: dict = {}  # each test record's selection without a checkpoint (the first's made once, read twice)
    for name, test in (("first", first), ("second", second), ("first", first)):
        kept = gb.select_graybox(CAND, data, checkpoint=path, test=test, **kw)
        assert calls == []  # test scores remade from the kept θ: no fit
        if name not in fresh:
            monkeypatch.undo()
            fresh[name] = gb.select_graybox(CAND, data, test=test, **kw)
            calls = _counting(monkeypatch)
        pd.testing.assert_frame_equal(kept.table, fresh[name].table)
    plain = gb.select_graybox(CAND, data, checkpoint=path, **kw)
    assert calls == [] and "JS_test" not in plain.table


def test_the_choice_and_its_decision_say_the_units_of_their_squared_errors():
    # was: "J_S valid=1.158, J_SF=0.01611" with no unit; J_S and J_SF are in the output's units squared
    from graybox.core._reprs import squared_unit

    ds = _two_level_dataset()
    rec = dataclasses.replace(ds.ident, units=("V", "m/s"))
    ds = gb.Dataset(rec, dataclasses.replace(ds.valid, units=("V", "m/s")),
                    dataclasses.replace(ds.static, units=("V", "m/s")))
    sel = _pe_selection(ds)
    assert f"J_S valid={sel.chosen['JS_valid']:.4g} (m/s)²" in repr(sel)
    assert f"J_SF={sel.decision.JSF:.4g} (m/s)²" in repr(sel.decision)
    assert squared_unit("mlc") == " mlc²" and squared_unit("") == ""
    assert "²" not in repr(_pe_selection(_two_level_dataset()))  # records without units: no unit said


def test_a_newer_graybox_row_is_kept_unread_and_written_back(tmp_path, data, monkeypatch):
    # a row with a field this graybox does not know (a newer graybox's, sharing the file) made the whole file
    # "corrupt": the rows of this version were refused with it
    from graybox.core._files import write_atomically
    from graybox.experiments._select_checkpoint import SelectionCheckpoint

    path = tmp_path / "sel.npz"
    kw = dict(sizes=[3], estimator=["pe"], progress=False)
    first = gb.select_graybox(CAND, data, checkpoint=path, **kw)
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    newer = "f" * 32
    arrays[f"{newer}/thetas"] = np.zeros((1, 3))
    arrays[f"{newer}/a_newer_score"] = np.array([1.5])
    write_atomically(path, lambda f: np.savez(f, **arrays))
    calls = _counting(monkeypatch)
    again = gb.select_graybox(CAND, data, checkpoint=path, **kw)
    assert calls == []  # every row of this version reused
    assert again.table.equals(first.table)
    ck = SelectionCheckpoint(path)
    assert set(ck.foreign) == {newer} and newer not in ck.rows
    ck.write()
    with np.load(path, allow_pickle=False) as z:
        assert float(z[f"{newer}/a_newer_score"][0]) == 1.5
    arrays[f"{'0' * 32}/Not A Field"] = np.zeros(1)  # a name no graybox writes: corrupt, as before
    write_atomically(path, lambda f: np.savez(f, **arrays))
    with pytest.raises(ValueError, match="corrupt"):
        SelectionCheckpoint(path)


@pytest.mark.parametrize("dtype", [np.float32, np.float16])
def test_a_row_rewritten_in_another_precision_is_refused(tmp_path, dtype):
    # a row whose thetas another tool rewrote as float32 was resumed with θ rounded (3e-9 off), without a word
    from graybox.estimation._simulation_error import CheckpointError
    from graybox.experiments._select_checkpoint import SelectionCheckpoint

    path, key = tmp_path / "sel.npz", "0" * 32
    row = {"blocks": np.array([[1.0, 2.0]]), "weights": np.array([1.0, 1.0]), "jsf": np.array([0.5]),
           "jsf_full": np.array([0.5]), "thetas": np.array([[0.1 + 1e-9, 0.2]]), "lambdas": np.array([0.5]),
           "failed": [], "warnings": []}
    SelectionCheckpoint(path).put(key, row)
    assert SelectionCheckpoint(path).get(key)["thetas"].tolist() == row["thetas"].tolist()
    with np.load(path) as z:
        arrays = dict(z)
    arrays[f"{key}/thetas"] = arrays[f"{key}/thetas"].astype(dtype)
    np.savez(path, **arrays)
    with pytest.raises(CheckpointError, match=f"corrupt \\(a row's thetas is {np.dtype(dtype)}, not the float64"):
        SelectionCheckpoint(path)
