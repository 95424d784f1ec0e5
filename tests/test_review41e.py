"""Review of two runs sharing one store (review41e): what a run holds while it takes over another run's cells,
and where a new store is made."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from graybox import experiments as gx
from graybox.core import _files
from graybox.experiments import _run
from graybox.experiments._store import running_cells

from test_grid_claims import _open, grid  # noqa: F401  (a fixture)


def shared_run(spec, store, g, cells, held, at_wait=None, **options):
    """Run the grid while another run (this process, its own connection) holds the cells ``held``; that run stops
    once the grid's run (``run_grid``'s ``options``) says it waits for them (``at_wait()`` called first). The
    grid's run, its log lines."""
    other = _open(store, g, cells)
    assert other.claim([c.key for c in held]) == {}
    lines, out = [], {}

    def target():
        try:
            out["run"] = gx.run_grid(spec, store, log=lines.append, **options)
        except BaseException as exc:  # pragma: no cover - reported below
            out["error"] = exc

    t = threading.Thread(target=target)
    t.start()
    try:
        deadline = time.monotonic() + 120
        while not any("waits for them" in x for x in lines):
            assert t.is_alive() and time.monotonic() < deadline, (lines, out)
            time.sleep(0.01)
        if at_wait is not None:
            at_wait()
    finally:
        other.close()  # it stops without running them: the waiting run takes them over
    t.join(180)
    assert not t.is_alive() and "error" not in out, out
    return out["run"], lines


def test_a_run_taking_over_a_stopped_runs_cells_holds_only_the_one_it_runs(grid, tmp_path, monkeypatch):  # noqa: F811
    # a run left with cells another run held (a Dask run's batches, here every cell) waits; when that run stops,
    # the waiting run claimed every one of them at once and ran them one at a time: grid status said it ran all
    # of them, and a third run started meanwhile waited for them instead of sharing them
    spec, g, _, cells = grid
    store = tmp_path / "s.sqlite"
    held, real = [], _run.run_cell

    def cell(c, data, threads=1):
        held.append(sum(running_cells(store).values()))
        return real(c, data, threads=threads)

    monkeypatch.setattr(_run, "run_cell", cell)
    run, _ = shared_run(spec, store, g, cells, cells)
    assert run.ran == len(cells) and len(held) == len(cells)
    assert held == [1] * len(cells)  # while it runs a cell, it holds that one only
    assert gx.grid_status(store).running == {}


def _maker(spec, store, patch: str) -> str:
    """A driver process's code that opens ``store`` for the grid ``spec`` (and closes it) with the store's table
    making replaced by ``patch``'s ``making(conn, version)`` (``real`` is the original; ``store`` its path)."""
    return ("import errno, os, sys, time\nfrom pathlib import Path\nfrom graybox.experiments import _store\n"
            f"sys.path.insert(0, {str(Path(__file__).parent)!r})\nfrom test_grid_claims import _open\n"
            "from graybox import experiments as gx\n"
            f"store = Path({str(store)!r})\nreal = _store._create_tables\n" + patch
            + "_store._create_tables = making\n"
            f"g = gx.Grid.from_toml({str(spec)!r})\n_open(store, g, g.cells(g.load_data())).close()\n")


def open_while_made(spec, store, g, cells, patch: str, said: str, meanwhile=None) -> None:
    """A maker process (``_maker(spec, store, patch)``) started; once it prints ``said`` (and ``meanwhile()``, if
    given, has checked the path), this process opens the store and closes it; the maker must then end well."""
    code = _maker(spec, store, "def nolink(a, b):\n    raise OSError(errno.EPERM, 'no hard links here')\n"
                               "os.link = nolink\n" + patch)
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == said, proc.stderr.read()
        if meanwhile is not None:
            meanwhile()
        _open(store, g, cells).close()  # while the other process is in it
        out, err = proc.communicate(timeout=60)
        assert proc.returncode == 0, err
    finally:
        proc.kill()
        proc.communicate()


@pytest.mark.skipif(os.name != "posix", reason="a real SIGKILL")
def test_the_half_made_store_of_a_run_killed_while_making_it_is_swept_by_a_later_run(grid, tmp_path):  # noqa: F811
    # a new store is made under a name of its own beside its path and linked into place; a run killed meanwhile
    # left that file (and its -wal and -shm) in the store's folder for ever
    spec, g, _, cells = grid
    store = tmp_path / "s.sqlite"
    code = _maker(spec, store, "def making(conn, version):\n    print('making', flush=True)\n    time.sleep(120)\n")
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "making", proc.stderr.read()
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        proc.kill()
        proc.communicate()
    left = sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".s.sqlite."))
    assert left and all(n.split(".new")[0] == left[0].split(".new")[0] for n in left)
    young = tmp_path / ".s.sqlite.0123abcd.new"  # another run making the store right now: not its to sweep
    young.write_bytes(b"")
    old = time.time() - 2 * _files.LEFTOVER_SECONDS
    for n in left:
        os.utime(tmp_path / n, (old, old))
    _open(store, g, cells).close()
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == [young.name]
    young.unlink()
    os.utime(store, (old, old))  # a file of another name is never swept, however old
    (tmp_path / ".s.sqlite.keep").write_bytes(b"")
    os.utime(tmp_path / ".s.sqlite.keep", (old, old))
    _open(store, g, cells).close()
    assert store.is_file() and (tmp_path / ".s.sqlite.keep").is_file()


def test_without_hard_links_a_run_opening_the_store_another_makes_in_place_waits_for_it(grid, tmp_path):  # noqa: F811
    # where the file system has no hard links the store is made in place: a run opening the path meanwhile found
    # an SQLite file without tables (or an empty file) and refused it as "not a graybox grid store"
    spec, g, _, cells = grid
    store = tmp_path / "s.sqlite"
    open_while_made(spec, store, g, cells, "def making(conn, version):\n    if store.exists():  # in place\n"
                                           "        print('making', flush=True)\n        time.sleep(1.0)\n"
                                           "    return real(conn, version)\n", "making")
    assert len(gx.store_specs(store)) == 1
