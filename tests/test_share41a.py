"""Two runs on one store share the grid: each takes a cell as it is about to start it, so a run started a moment
later takes the cells not started yet (before, the first run took every cell at its start and the second waited
for all of them); a run killed mid-grid leaves the cell it held to the other (real processes, a real SIGKILL, a
real SQLite file)."""

from __future__ import annotations

import os
import re
import signal
import sqlite3
import subprocess
import sys
import time
from collections import deque
from pathlib import Path

import pytest

from graybox import experiments as gx
from graybox.experiments._cell import COLUMNS
from graybox.experiments._executors import InProcess, ProcessPool

from test_grid_claims import SPEC as CLAIMS_SPEC, _open

# test_grid_claims' grid (four structures, PE with three λ1) with a least-squares variant beside it
SPEC = CLAIMS_SPEC.replace("[[variants]]", '[[variants]]\nname = "LS"\nestimator = "ls"\n[[variants]]', 1)

# A driver process: its first cell waits until the other driver has started one too (so the test fails, by a
# timeout, if the second run waits for every cell of the first), its cells take a little longer than they do, and
# the driver given "stall" stops in its second cell (it is killed there, holding that cell).
DRIVER = """\
import os, sys, time
from pathlib import Path
from graybox import experiments as gx
from graybox.experiments import _run

spec, store, sync, role = sys.argv[1], sys.argv[2], Path(sys.argv[3]), sys.argv[4]
real, n = _run.run_cell, [0]

def cell(c, data, threads=1):
    n[0] += 1
    if n[0] == 1:
        (sync / f"started-{os.getpid()}").touch()
        deadline = time.monotonic() + 60
        while len(list(sync.glob("started-*"))) < 2 and time.monotonic() < deadline:
            time.sleep(0.01)
    if role == "stall" and n[0] == 2:
        (sync / "stalled").write_text(c.key)
        time.sleep(600)
    time.sleep(0.05)
    return real(c, data, threads=threads)

_run.run_cell = cell
run = gx.run_grid(spec, store)
print(run.ran, "run now", flush=True)
print("\\n".join(run.notes), flush=True)
"""


@pytest.fixture
def setup(tmp_path):
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC)
    driver = tmp_path / "driver.py"
    driver.write_text(DRIVER)
    sync = tmp_path / "sync"
    sync.mkdir()
    g = gx.Grid.from_toml(spec)
    return spec, driver, sync, g.cells(g.load_data())


def _driver(driver: Path, spec: Path, store: Path, sync: Path, role: str = "run") -> subprocess.Popen:
    return subprocess.Popen([sys.executable, str(driver), str(spec), str(store), str(sync), role],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _rows(store: Path) -> dict[str, tuple]:
    """The cells table by key, without what says where and when a cell ran."""
    cols = [c for c in COLUMNS if c not in ("wall_time", "worker", "finished_at")]
    conn = sqlite3.connect(store)
    try:
        return {r[0]: r for r in conn.execute(f"SELECT {', '.join(cols)} FROM cells")}
    finally:
        conn.close()


def _workers(store: Path) -> dict[str, str | None]:
    conn = sqlite3.connect(store)
    try:
        return dict(conn.execute("SELECT key, worker FROM cells"))
    finally:
        conn.close()


def test_two_runs_started_together_share_the_cells_and_write_what_one_run_alone_writes(setup, tmp_path):
    spec, driver, sync, cells = setup
    store = tmp_path / "two.sqlite"
    procs = [_driver(driver, spec, store, sync) for _ in range(2)]
    outs = [p.communicate(timeout=300) for p in procs]
    assert all(p.returncode == 0 for p in procs), outs
    ran = [int(re.search(r"(\d+) run now", o).group(1)) for o, _ in outs]
    assert min(ran) > 0 and sum(ran) == len(cells), outs  # both ran a share, together every cell once
    by = _workers(store)
    assert sorted(by) == sorted(c.key for c in cells)
    counts = {p.pid: sum(w.endswith(f":{p.pid}") for w in by.values()) for p in procs}
    assert sorted(counts.values()) == sorted(ran), (counts, ran)  # each wrote the cells it says it ran
    alone = tmp_path / "one.sqlite"
    assert gx.run_grid(spec, alone).ran == len(cells)
    assert _rows(store) == _rows(alone)  # the same rows whichever run computed a cell


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="a killed driver is told dead by /proc")
def test_a_run_killed_mid_grid_leaves_the_cell_it_held_to_the_other_which_finishes_the_grid(setup, tmp_path):
    spec, driver, sync, cells = setup
    store = tmp_path / "s.sqlite"
    killed = _driver(driver, spec, store, sync, "stall")
    other = _driver(driver, spec, store, sync)
    try:
        deadline = time.monotonic() + 120
        # the driver's write_text makes the file, then writes the key: an empty read came before the key
        while not ((sync / "stalled").exists() and (sync / "stalled").read_text()):
            assert killed.poll() is None and time.monotonic() < deadline, killed.communicate()
            time.sleep(0.01)
        held = (sync / "stalled").read_text()
        assert dict(gx.grid_status(store).running).get(f"pid {killed.pid} on host {os.uname().nodename}") == 1
        killed.send_signal(signal.SIGKILL)  # while it runs its second cell, its first written
        out, err = other.communicate(timeout=300)
    finally:
        for p in (killed, other):
            p.kill()
            p.communicate()
    assert other.returncode == 0, (out, err)
    by = _workers(store)
    assert sorted(by) == sorted(c.key for c in cells)  # every cell once
    mine = [k for k, w in by.items() if w.endswith(f":{killed.pid}")]
    assert len(mine) == 1 and held not in mine  # the killed run's finished cell is kept, not run again
    assert by[held].endswith(f":{other.pid}")  # the cell it held, the other ran
    assert int(re.search(r"(\d+) run now", out).group(1)) == len(cells) - 1
    assert (gx.load_results(store)["status"] != "failed").all()
    assert gx.grid_status(store).running == {}


def _taker(cells, refuse: int):
    """A ``take`` that refuses every ``refuse``-th cell it is asked for (another run holds it), recording the
    batches it was asked for."""
    asked: list[list[str]] = []
    n = [0]

    def take(batch):
        asked.append([c.key for c in batch])
        out = []
        for c in batch:
            n[0] += 1
            if n[0] % refuse:
                out.append(c)
        return out

    return take, asked


@pytest.mark.parametrize("kind", ["in-process", "processes", "dask"])
def test_an_executor_runs_the_cells_take_gives_asking_for_no_more_than_it_can_start(setup, kind):
    _, _, _, cells = setup
    g = gx.Grid.from_toml(setup[0])
    data = g.load_data()
    by_hash = {c.data_hash: data[c.data] for c in cells}
    if kind == "dask":
        pytest.importorskip("distributed")
        from graybox.experiments._executors import DaskCluster

        ex = DaskCluster(workers=1)
    else:
        ex = InProcess() if kind == "in-process" else ProcessPool(2)
    take, asked = _taker(cells, refuse=3)
    rows = list(ex.run(cells, by_hash, take=take))
    flat = [k for a in asked for k in a]
    given = [k for i, k in enumerate(flat) if (i + 1) % 3]
    assert sorted(r["key"] for r in rows) == sorted(given) and len(given) < len(cells)
    assert sorted(flat) == sorted(c.key for c in cells)  # each cell asked for once
    if kind == "dask":  # longest first, a task's batch at a time
        assert len(asked) > 1 and len(asked[0]) < len(cells)
    else:  # in the grid's order, no more at a time than there are workers to start them
        assert flat == [c.key for c in cells] and max(map(len, asked)) <= getattr(ex, "workers", 1)


def test_take_next_asks_again_for_the_cells_refused_until_it_has_enough_or_none_are_left():
    from graybox.experiments._executors import _take_next

    pending = deque(range(10))
    got = _take_next(pending, 3, lambda b: [x for x in b if x % 2])
    assert got == [1, 3, 5] and list(pending) == [6, 7, 8, 9]
    assert _take_next(pending, 5, lambda b: []) == [] and not pending


def test_a_new_store_appears_whole_so_a_run_started_with_its_maker_opens_it(setup, tmp_path, monkeypatch):
    # made in place, the file was an empty file, then an SQLite file without tables, for a moment: a run started
    # together with the one making it refused it ("an empty file, so not a graybox grid store"), half the times
    # two drivers were started on a new store path
    from graybox.experiments import _store

    spec, _, _, cells = setup
    g = gx.Grid.from_toml(spec)
    store = tmp_path / "new.sqlite"
    make, seen = _store._create_tables, []

    def making(conn, version):  # midway through this run's making, another run opens the path
        seen.append(store.exists())
        if len(seen) == 1:
            _open(store, g, cells).close()
        return make(conn, version)

    monkeypatch.setattr(_store, "_create_tables", making)
    st = _open(store, g, cells)
    try:
        assert seen == [False, False]  # neither run's half-made store was ever at the path
        assert (st.spec_id, st.new_spec) == (1, False)  # the other run's store, opened
    finally:
        st.close()
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []  # no half-made file left


@pytest.mark.skipif(os.name != "posix", reason="a symbolic link")
def test_a_store_path_that_is_a_dangling_link_makes_the_store_where_it_points(setup, tmp_path):
    spec, _, _, cells = setup
    g = gx.Grid.from_toml(spec)
    store, target = tmp_path / "link.sqlite", tmp_path / "target.sqlite"
    store.symlink_to(target)
    _open(store, g, cells).close()  # linking beside it finds the name taken, by a link to nothing: made in place
    assert target.is_file() and len(gx.store_specs(store)) == 1
