"""select_graybox(checkpoint=): rows kept as they finish, a run SIGKILLed and called again refits only the rest
(a real subprocess, a real SIGKILL, a real file), on the driver, local processes and Dask."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pandas as pd
import pytest

import graybox as gb
from graybox.experiments import _select

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
    # other options are other rows: the ones of another λ1 grid are fitted, not read
    calls.clear()
    gb.select_graybox(CAND, data, checkpoint=path, **{**KW, "lambdas": [0.1, 1.0]})
    assert len(calls) == len(res.table)


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
