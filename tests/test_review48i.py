"""review48i: the residual tests' round-off rules and units (04abe94 … 01e3e8b) and the child a Dask worker keeps
for a run's tasks under a cell time limit (ae7adda)."""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

from test_grid_executors import _death_cells  # noqa: E402

from graybox.experiments import _executors  # noqa: E402
from graybox.experiments._cell import run_cell  # noqa: E402


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:  # a zombie not reaped yet is gone too
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def test_a_kept_child_whose_run_never_ends_on_the_worker_exits_once_idle(monkeypatch):
    # the child a worker thread keeps for a run's tasks was closed only by the run's plugin teardown: a driver
    # killed mid-run (SIGKILL, lost connection) never unregisters the plugin, and each worker thread kept an idle
    # child (Python, graybox, the data sets) for as long as the worker lived
    monkeypatch.setattr(_executors, "KEPT_IDLE", 1.0, raising=False)
    cells, data = _death_cells(("LS",))
    kept: dict = {}  # the run's GridData.kept, whose teardown never comes
    try:
        _serve_then_idle(cells, data, kept)
    finally:
        for v in list(kept.values()):
            v.close()


def _serve_then_idle(cells, data, kept):
    rows = _executors._cells_in_a_child(run_cell, 60.0, cells[:1], data, kept)
    assert [r["status"] for r in rows] == ["ok"]
    (pool,) = kept.values()
    (slot,) = pool.pool._kept
    child = slot.proc.pid
    assert _alive(child)  # kept for the run's next task
    deadline = time.monotonic() + 30
    while _alive(child) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not _alive(child), "the kept child outlived its run's tasks with nothing left to close it"
    # a task of the run after that starts a child again and is served
    rows = _executors._cells_in_a_child(run_cell, 60.0, cells[:1], data, kept)
    assert [r["status"] for r in rows] == ["ok"]
