"""review42f: what a run keeps between the runs of one run_grid call, pinned where no test held it: a Dask run takes
its first task's cells before it starts its LocalCluster, so a cluster that fails to start must leave them free;
a pool worker kept idle while the run waits may die meanwhile, and the run must go on without it."""

from __future__ import annotations

import os
import signal
import sqlite3
from contextlib import contextmanager

import pytest

from graybox import experiments as gx
from graybox.experiments import _executors

from test_review41e import shared_run
from test_grid_claims import grid  # noqa: F401  (a fixture)


def test_cells_taken_before_a_local_cluster_that_fails_to_start_are_left_free(grid, tmp_path, monkeypatch):  # noqa: F811
    # the first task's cells are claimed before the LocalCluster starts (grid42a): its start failing must not
    # leave them held, or another run on the store would wait for a run that is gone
    spec, g, _, cells = grid
    pytest.importorskip("distributed")
    tried = []

    @contextmanager
    def failing(workers, dashboard=False):
        tried.append(workers)
        raise OSError("no port free for the scheduler")
        yield  # pragma: no cover

    monkeypatch.setattr(_executors, "local_cluster", failing)
    store = tmp_path / "s.sqlite"
    with pytest.raises(OSError, match="no port free"):
        gx.run_grid(spec, store, executor="dask", workers=1)
    assert tried == [1]  # it got as far as starting one: the first cells were taken
    with sqlite3.connect(store) as conn:
        assert conn.execute("SELECT COUNT(*) FROM claims").fetchone()[0] == 0
    run = gx.run_grid(spec, store)  # another run neither waits nor finds any cell another run made
    assert run.ran == len(cells) and not any("another run" in n for n in run.notes)


def test_a_kept_pool_worker_that_dies_while_the_run_waits_is_replaced(grid, tmp_path):  # noqa: F811
    # the pool's idle workers are kept while the run waits for another run's cells (executors.session); one killed
    # meanwhile is not sent the cells taken over: a new one is started, and every cell runs
    spec, g, _, cells = grid
    before = set()

    def kill_workers():
        for p in _executors.mp.active_children():
            if p.name == "graybox-grid-worker":
                before.add(p.pid)
                os.kill(p.pid, signal.SIGKILL)

    run, _ = shared_run(spec, tmp_path / "s.sqlite", g, cells, cells[len(cells) // 2:], executor="processes",
                         workers=2, at_wait=kill_workers)
    assert before  # there were kept workers to kill
    assert run.ran == len(cells) and run.counts["failed"] == 0
    assert not {p.pid for p in _executors.mp.active_children()} & before  # none left behind
