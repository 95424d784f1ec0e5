"""Two runs sharing one store (grid42a): the executor a run starts, when it starts it, and a store made in place
seen by a run opening its path at the first moment (real SQLite files, real processes, a real LocalCluster)."""

from __future__ import annotations

import os
import time

import pytest

from graybox import experiments as gx
from graybox.experiments import _executors

from test_grid_claims import _open, grid  # noqa: F401  (a fixture)
from test_review41e import open_while_made, shared_run


def test_a_process_run_taking_over_another_runs_cells_keeps_its_workers(grid, tmp_path, monkeypatch):  # noqa: F811
    # after waiting for another run's cells, a run started a new pool (a Python start-up and graybox's imports
    # per worker) for the cells it took over, though its own workers were alive and idle
    spec, g, _, cells = grid
    starts, real = [], _executors.ProcessPool._start

    def start(self):
        slot = real(self)
        starts.append(slot.proc.pid)
        return slot

    monkeypatch.setattr(_executors.ProcessPool, "_start", start)
    run, _ = shared_run(spec, tmp_path / "s.sqlite", g, cells, cells[len(cells) // 2:], executor="processes",
                         workers=1)
    assert run.ran == len(cells) == sum(run.counts.values())
    assert len(starts) == 1  # one worker, started once, ran its cells and those it took over


def _counted_clusters(monkeypatch) -> list[int]:
    """The LocalClusters graybox starts from now on (their worker counts), counted as each starts."""
    started, real = [], _executors.local_cluster

    def counting(workers, dashboard=False):
        started.append(workers)
        return real(workers, dashboard)

    monkeypatch.setattr(_executors, "local_cluster", counting)
    return started


def test_a_dask_run_taking_over_another_runs_cells_keeps_its_cluster(grid, tmp_path, monkeypatch):  # noqa: F811
    # a LocalCluster start is seconds: a run started a second one for the cells it took over after waiting
    spec, g, _, cells = grid
    started = _counted_clusters(monkeypatch)
    run, _ = shared_run(spec, tmp_path / "s.sqlite", g, cells, cells[len(cells) // 2:], executor="dask", workers=1)
    assert run.ran == len(cells) == sum(run.counts.values())
    assert started == [1]


def test_a_dask_run_starts_no_cluster_while_another_run_holds_every_cell_left(grid, tmp_path, monkeypatch):  # noqa: F811
    # with every cell held by another live run, a Dask run started its LocalCluster, submitted nothing, closed it
    # and waited
    spec, g, _, cells = grid
    started = _counted_clusters(monkeypatch)
    while_waiting = []
    run, lines = shared_run(spec, tmp_path / "s.sqlite", g, cells, cells, executor="dask", workers=1,
                             at_wait=lambda: while_waiting.append(list(started)))
    assert while_waiting == [[]]  # none while it only waited
    assert started == [1] and run.ran == len(cells)  # one for the cells it took over
    assert sum("Dask dashboard" in x for x in lines) == 1


def test_without_hard_links_a_run_opening_the_path_as_the_maker_creates_the_file_waits_for_it(grid, tmp_path):  # noqa: F811
    # made in place, the file is created by the maker's connect and locked by its BEGIN IMMEDIATE a statement
    # later: a run opening the path between the two found an empty file nobody held and refused it
    spec, g, _, cells = grid
    store = tmp_path / "s.sqlite"

    def meanwhile():
        assert store.exists() and store.stat().st_size == 0  # the window: an empty file at the path

    open_while_made(spec, store, g, cells, "making = real\nconnect = _store._connect_to_write\n"
                                           "def paused(path, p, verb):\n    conn = connect(path, p, verb)\n"
                                           "    if Path(path) == store and store.stat().st_size == 0:  # just created\n"
                                           "        print('created', flush=True)\n        time.sleep(1.0)\n"
                                           "    return conn\n"
                                           "_store._connect_to_write = paused\n", "created", meanwhile)
    assert len(gx.store_specs(store)) == 1
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []  # nothing left beside it


def test_an_empty_file_nobody_is_making_is_still_refused_untouched(grid, tmp_path):  # noqa: F811
    _, g, _, cells = grid
    store = tmp_path / "s.sqlite"
    store.write_bytes(b"")
    with pytest.raises(gx.StoreError, match="an empty file"):
        _open(store, g, cells)
    assert store.stat().st_size == 0


def test_the_making_lock_a_killed_maker_left_is_swept_when_old(grid, tmp_path):  # noqa: F811
    from graybox.core import _files

    _, g, _, cells = grid
    store = tmp_path / "s.sqlite"
    lock = tmp_path / ".s.sqlite.making"
    lock.write_bytes(b"")  # a maker killed a moment ago, or making the store right now: not swept
    _open(store, g, cells).close()
    assert lock.is_file()
    old = time.time() - 2 * _files.LEFTOVER_SECONDS
    os.utime(lock, (old, old))
    _open(store, g, cells).close()
    assert not lock.exists() and len(gx.store_specs(store)) == 1
