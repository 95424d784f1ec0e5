"""Two runs on one store: each takes the cells it starts, and neither starts a cell the other holds; a run
waits for the other's cells and runs them itself when that run stops or dies (a real SIGKILL, a real file)."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

import graybox as gb
from graybox import experiments as gx
from graybox.experiments._cell import run_cell
from graybox.experiments._store import ResultStore

SPEC = """\
name = "shared"
[[data]]
name = "pumping"
bundled = "pumping"
[[structures]]
name = "a"
terms = ["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)y(k-1)", "1"]
[[structures]]
name = "b"
terms = ["y(k-1)", "u(k-1)", "u(k-2)", "u(k-1)^2", "1"]
[[structures]]
name = "c"
terms = ["y(k-1)", "u(k-1)", "y(k-1)^2", "1"]
[[structures]]
name = "d"
terms = ["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)", "1"]
[[variants]]
name = "PE"
estimator = "pe"
lambdas = {logspace = [-3, 0, 3]}
options = {solver = "closed"}
"""


@pytest.fixture
def grid(tmp_path):
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC)
    g = gx.Grid.from_toml(spec)
    data = g.load_data()
    return spec, g, data, g.cells(data)


def _open(store: Path, g, cells) -> ResultStore:
    return ResultStore.open(store, grid_name=g.name, fingerprint=g.fingerprint(cells), spec=g.to_dict(), cells=cells,
                            version=gb.__version__)


def _claiming_driver(spec: Path, store: Path) -> subprocess.Popen:
    """Another process that opens the store, takes every cell of the spec, prints "claimed" and sleeps."""
    code = (f"import sys, time\nfrom pathlib import Path\nsys.path.insert(0, {str(Path(__file__).parent)!r})\n"
            f"from test_grid_claims import _open\nfrom graybox import experiments as gx\n"
            f"g = gx.Grid.from_toml({str(spec)!r})\nc = g.cells(g.load_data())\n"
            f"st = _open(Path({str(store)!r}), g, c)\nassert st.claim([x.key for x in c]) == {{}}\n"
            "print('claimed', flush=True)\ntime.sleep(120)\n")
    return subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def test_a_cell_one_run_holds_is_not_given_to_another_until_written_or_released(grid, tmp_path):
    """Two runs in two threads of one process (as two notebooks' grids would be in two processes)."""
    from concurrent.futures import ThreadPoolExecutor

    _, g, data, cells = grid
    keys = [c.key for c in cells]
    with ThreadPoolExecutor(1) as pool:  # run a lives in its own thread, as its connection must
        def in_a(fn, *args):
            return pool.submit(fn, *args).result()

        a = in_a(_open, tmp_path / "s.sqlite", g, cells)
        b = _open(tmp_path / "s.sqlite", g, cells)
        try:
            assert in_a(a.claim, keys) == {}
            held = b.claim(keys)
            assert set(held) == set(keys) and set(held.values()) == {f"pid {os.getpid()} on host {os.uname().nodename}"}
            in_a(a.write, run_cell(cells[0], data[cells[0].data]))  # written: no longer held
            assert set(b.claim(keys)) == set(keys[1:])
            in_a(a.unclaim, [keys[1]])
            in_a(a.unclaim, [])  # no keys: nothing ends
            assert set(b.claim(keys)) == set(keys[2:])
            in_a(a.close)  # every claim ends with the run
            assert b.claim(keys) == {}
        finally:
            in_a(a.close)
            b.close()


def test_a_run_started_by_a_run_of_its_own_thread_does_not_wait_for_it(grid, tmp_path):
    """A run whose log callback starts another run on the store (a run up the same thread's calls, which cannot
    go on while the inner one waits): the inner run does not wait for it, and nothing runs twice in vain."""
    spec, _, _, cells = grid
    store = tmp_path / "s.sqlite"
    inner = []

    def log(line: str) -> None:
        if "waits for them" in line:
            raise AssertionError("the inner run waited for the outer one")
        if not inner and "to run" in line:
            inner.append(None)
            inner[0] = gx.run_grid(spec, store)

    outer = gx.run_grid(spec, store, log=log)
    assert inner[0].ran == len(cells) and outer.ran == 0
    assert any(f"{len(cells)} cell(s) were run meanwhile by another run" in n for n in outer.notes)


def test_the_cells_of_a_killed_run_are_free_even_before_it_is_reaped(grid, tmp_path):
    _, g, _, cells = grid
    store = tmp_path / "s.sqlite"
    _open(store, g, cells).close()
    proc = _claiming_driver(tmp_path / "spec.toml", store)
    st = None
    try:
        assert proc.stdout.readline().strip() == "claimed", proc.stderr.read()
        st = _open(store, g, cells)
        assert len(st.claim([c.key for c in cells[:1]])) == 1  # alive: its cells are held
        os.kill(proc.pid, signal.SIGKILL)
        deadline = time.monotonic() + 30
        while Path(f"/proc/{proc.pid}/stat").exists() and b") Z" not in Path(f"/proc/{proc.pid}/stat").read_bytes():
            assert time.monotonic() < deadline
            time.sleep(0.01)
        assert st.claim([c.key for c in cells]) == {}  # killed, not reaped yet (a zombie): its cells are free
    finally:
        if st is not None:
            st.close()
        proc.kill()
        proc.communicate()


def _run_in_thread(spec, store):
    lines, out = [], {}

    def target():
        try:
            out["run"] = gx.run_grid(spec, store, log=lines.append)
        except BaseException as exc:  # pragma: no cover - reported by the test
            out["error"] = exc

    t = threading.Thread(target=target)
    t.start()
    deadline = time.monotonic() + 60
    while not any("waits for them" in x for x in lines):
        assert t.is_alive() and time.monotonic() < deadline, (lines, out)
        time.sleep(0.01)
    return t, lines, out


def test_a_run_waits_for_the_cells_another_run_holds_and_runs_those_it_releases(grid, tmp_path):
    spec, g, data, cells = grid
    store = tmp_path / "s.sqlite"
    other = _open(store, g, cells)
    try:
        assert other.claim([c.key for c in cells]) == {}
        t, lines, out = _run_in_thread(spec, store)
        assert any(f"{len(cells)} of the cells to run are being run by another run" in x for x in lines)
        for c in cells[:2]:  # the other run finishes two cells, then stops
            other.write(run_cell(c, data[c.data]))
    finally:
        other.close()
    t.join(120)
    assert not t.is_alive() and "error" not in out, out
    run = out["run"]
    assert run.ran == len(cells) - 2 and run.skipped == 2
    assert any("2 cell(s) were run meanwhile by another run" in n for n in run.notes)
    res = gx.load_results(store)
    assert len(res) == len(cells) and res["key"].is_unique and (res["status"] != "failed").all()


def test_a_run_takes_over_the_cells_of_a_run_killed_while_it_waits(grid, tmp_path):
    spec, g, _, cells = grid
    store = tmp_path / "s.sqlite"
    _open(store, g, cells).close()
    proc = _claiming_driver(spec, store)
    try:
        assert proc.stdout.readline().strip() == "claimed", proc.stderr.read()
        t, lines, out = _run_in_thread(spec, store)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        proc.kill()
        proc.communicate()
    t.join(120)
    assert not t.is_alive() and "error" not in out, out
    assert out["run"].ran == len(cells) and not any("meanwhile" in n for n in out["run"].notes)
    assert len(gx.load_results(store)) == len(cells)


def test_two_drivers_started_together_run_every_cell_once(grid, tmp_path):
    spec, g, _, cells = grid
    assert len(cells) == 4
    store = tmp_path / "s.sqlite"
    _open(store, g, cells).close()
    cmd = [sys.executable, "-m", "graybox._cli", "grid", "run", str(spec), "--store", str(store)]
    procs = [subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(2)]
    outs = [p.communicate(timeout=300) for p in procs]
    assert all(p.returncode == 0 for p in procs), outs
    ran = [int(re.search(r"(\d+) run now", o).group(1)) for o, _ in outs]
    assert sum(ran) == len(cells), outs
    res = gx.load_results(store)
    assert len(res) == len(cells) and res["key"].is_unique


def test_grid_status_names_the_runs_and_their_cells_and_forgets_a_killed_one(grid, tmp_path):
    spec, g, data, cells = grid
    store = tmp_path / "s.sqlite"
    first = _open(store, g, cells)
    try:
        first.claim([c.key for c in cells[:3]])
        first.write(run_cell(cells[0], data[cells[0].data]))
        status = gx.grid_status(store)
        me = f"pid {os.getpid()} on host {os.uname().nodename}"
        assert dict(status.running) == {me: 2} and status.done == 1
        assert f"being run now: 2 cell(s) by {me}" in status.summary()
    finally:
        first.close()
    assert dict(gx.grid_status(store).running) == {}
    proc = _claiming_driver(spec, store)
    try:
        assert proc.stdout.readline().strip() == "claimed", proc.stderr.read()
        assert dict(gx.grid_status(store).running) == {f"pid {proc.pid} on host {os.uname().nodename}": len(cells)}
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        proc.kill()
        proc.communicate()
    status = gx.grid_status(store)
    assert dict(status.running) == {} and "being run now" not in status.summary()
