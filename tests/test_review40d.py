"""Review of the session's changes on main (41da6a3..): each test failed before its fix."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import graybox as gb
from graybox import experiments as gx
from graybox.experiments import _run
from graybox.experiments._cell import failed_row, run_cell

from test_grid_claims import _open, grid  # noqa: F401 - one claims grid (the fixture) and one opener


def test_a_cell_taken_over_after_its_run_let_it_go_unwritten_stays_claimed_while_this_run_runs_it(grid, tmp_path):
    _, g, _, cells = grid
    store = tmp_path / "s.sqlite"
    a, b, c = (_open(store, g, cells) for _ in range(3))
    try:
        x, y = cells[0].key, cells[1].key
        assert a.claim([x, y]) == {}
        waiting = {x: cells[0], y: cells[1]}
        assert set(b.claim([x, y])) == {x, y}
        a.unclaim([x])  # the other run lets x go without writing it
        seen = b.marks()
        todo, finished = _run._wait_for_others(b, waiting, seen)
        assert [t.key for t in todo] == [x] and finished == [] and list(waiting) == [y]
        # b's executor takes x as it starts it (not all the waited-for cells at once, review41e)
        share = _run._Share(b, seen, type("Bar", (), {"update": lambda self, n: None})(), {x: 1, y: 1})
        assert [t.key for t in share.take(todo)] == [x] and not share.waiting
        assert set(c.claim([x])) == {x}  # b runs x now: no third run may start it
    finally:
        for s in (a, b, c):
            s.close()


def test_unclaim_of_no_keys_ends_no_claim(grid, tmp_path):
    _, g, _, cells = grid
    store = tmp_path / "s.sqlite"
    a, b = _open(store, g, cells), _open(store, g, cells)
    try:
        assert a.claim([cells[0].key]) == {}
        a.unclaim([])
        assert set(b.claim([cells[0].key])) == {cells[0].key}
    finally:
        a.close()
        b.close()


def test_a_cell_another_run_writes_between_this_runs_look_and_its_claim_is_not_run_again(grid, tmp_path,
                                                                                       monkeypatch):
    spec, g, data, cells = grid
    store = tmp_path / "s.sqlite"
    other = _open(store, g, cells)
    notes = _run._notes

    def notes_then_other_writes(st, cells_, done, version):  # the other run writes cell 0 and lets it go
        assert cells[0].key not in done
        other.claim([cells[0].key])
        other.write(run_cell(cells[0], data[cells[0].data]))
        return notes(st, cells_, done, version)

    monkeypatch.setattr(_run, "_notes", notes_then_other_writes)
    try:
        run = gx.run_grid(spec, store)
    finally:
        other.close()
    assert run.ran == len(cells) - 1, run.summary()
    assert not any("its rows are kept" in n for n in run.notes), run.notes


def test_a_failed_cell_another_run_retried_and_failed_again_is_not_retried_twice(grid, tmp_path):
    spec, g, data, cells = grid
    store = tmp_path / "s.sqlite"
    other = _open(store, g, cells)
    try:
        other.write(failed_row(cells[0], "first failure"))
        assert other.claim([cells[0].key]) == {}  # the other run retries it
        lines, out = [], {}
        t = threading.Thread(target=lambda: out.update(run=gx.run_grid(spec, store, retry_failed=True,
                                                                       log=lines.append)))
        t.start()
        deadline = time.monotonic() + 60
        while not any("waits for them" in x for x in lines):
            assert t.is_alive() and time.monotonic() < deadline, lines
            time.sleep(0.01)
        time.sleep(0.05)
        other.write(failed_row(cells[0], "failed again"), replace=True)  # retried: it fails again
    finally:
        other.close()
    t.join(120)
    assert not t.is_alive()
    run = out["run"]
    assert run.ran == len(cells) - 1, run.summary()
    res = gx.load_results(store).set_index("key")
    assert res.loc[cells[0].key, "message"] == "failed again"


def _leave_driver(store: Path, owner: str, pid: int, beat: float, keys: list[str]) -> None:
    """A drivers row and its claims as a run that is gone left them."""
    import sqlite3
    import socket

    conn = sqlite3.connect(store, isolation_level=None)
    try:
        conn.execute("INSERT INTO drivers VALUES (?, ?, ?, ?)", (owner, socket.gethostname(), pid, beat))
        conn.executemany("INSERT INTO claims VALUES (?, ?)", [(k, owner) for k in keys])
    finally:
        conn.close()


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc")
def test_the_cells_of_a_dead_run_whose_pid_a_younger_process_took_are_free(grid, tmp_path):
    import subprocess
    import sys

    _, g, _, cells = grid
    store = tmp_path / "s.sqlite"
    st = _open(store, g, cells)
    proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        assert st.claim([]) == {}  # the tables
        # the driver beat an hour ago, then died; its pid now belongs to a process started since
        _leave_driver(store, "gone", proc.pid, time.time() - 3600, [c.key for c in cells])
        assert st.claim([c.key for c in cells]) == {}
    finally:
        st.close()
        proc.kill()
        proc.wait()


def test_claims_a_run_could_not_end_on_closing_do_not_hold_this_process_for_ever(grid, tmp_path, monkeypatch):
    import sqlite3

    _, g, _, cells = grid
    store = tmp_path / "s.sqlite"
    keys = [c.key for c in cells]
    a = _open(store, g, cells)
    assert a.claim(keys) == {}

    def locked(keys=None):
        raise sqlite3.OperationalError("database is locked")

    monkeypatch.setattr(a, "unclaim", locked)
    a.close()  # the claims stay in the file, their driver (this process) lives on
    b = _open(store, g, cells)
    try:
        assert b.claim(keys) == {}  # this process knows that run is over: a notebook's next run does not wait
    finally:
        b.close()


def test_grid_status_counts_the_cells_of_two_runs_in_one_process(grid, tmp_path):
    import os
    import socket

    _, g, _, cells = grid
    store = tmp_path / "s.sqlite"
    a, b = _open(store, g, cells), _open(store, g, cells)
    try:
        assert a.claim([cells[0].key]) == {} and b.claim([cells[1].key]) == {}
        assert dict(gx.grid_status(store).running) == {f"pid {os.getpid()} on host {socket.gethostname()}": 2}
    finally:
        a.close()
        b.close()


def _surface_band(ubar: np.ndarray, names=("u1", "u2")):
    """A hand-made band over points ``ubar`` (M, 2): ȳ = Σū, gains 1."""
    M = ubar.shape[0]
    yb, z, g = ubar.sum(axis=1), np.zeros(M), np.ones_like(ubar)
    return gb.StaticSurfaceBand(ubar, names, yb, yb - 0.1, yb + 0.1, z + 0.05, g, g - 0.1, g + 0.1, g * 0.05, 0.95,
                                "delta", 0, z)


@pytest.mark.parametrize("k", [1.0, 1e-9, 1e9])
def test_the_points_drawn_on_a_surface_slice_are_those_at_its_level_in_any_units(k):
    from graybox import plots

    u1 = np.array([1.0, 2.0, 3.0])
    band = _surface_band(k * np.array([[a, b] for b in (1.0, 2.0) for a in u1]))
    pts = gb.StaticPoints(k * np.array([[1.5, 1.0], [2.5, 1.0], [1.5, 2.0]]), np.array([2.5, 3.5, 3.5]),
                          input_names=("u1", "u2"))
    fig = plots.plot_static_band(band, pts, against="u1", gain=False)
    stars = [len(ln.get_xdata()) for ln in fig.axes[0].get_lines() if ln.get_marker() == "*"]
    assert stars == [2, 1]  # u2 = 1: two points, u2 = 2: one


@pytest.mark.parametrize("x", [pd.Series([1.0, None], dtype=object), pd.DataFrame({"u": [1.0, None]}, dtype=object),
                               pd.Series([True, 2.0], dtype=object), pd.array([True, False], dtype="boolean")],
                         ids=["Series with None", "DataFrame with None", "Series with a bool", "pandas booleans"])
def test_real_array_refuses_none_and_booleans_inside_pandas_values_too(x):
    from graybox.core._validation import real_array

    with pytest.raises(TypeError, match="x must be numbers"):
        real_array(x, "x")


def test_a_public_path_refuses_a_series_holding_none():
    curve = gb.StaticCurve([0.5, 1.0])
    with pytest.raises(TypeError, match="ubar must be"):
        curve(pd.Series([1.0, None], dtype=object))


def test_a_numpy_string_in_a_plain_value_is_saved_and_reads_back_as_one():
    r = gb.Record([1.0, 2.0, 3.0], [0.5, 0.25, 0.125], name="short")
    data = gb.Dataset(r, r, extra={"solver": np.str_("clarabel"), "names": [np.str_("u1"), "u2"]})
    back = gb.from_json(gb.to_json(data)).extra
    assert type(back["solver"]) is np.str_ and back["solver"] == "clarabel"
    assert [type(x) for x in back["names"]] == [np.str_, str] and back["names"] == ["u1", "u2"]


def test_a_run_busy_with_a_long_cell_keeps_its_beat_so_another_host_does_not_take_its_cells(grid, tmp_path,
                                                                                          monkeypatch):
    import sqlite3

    from graybox.experiments import _store

    spec, _, data, _ = grid
    store = tmp_path / "s.sqlite"
    monkeypatch.setattr(_store, "STALE_SECONDS", 1.0)  # another host takes a run silent for 1 s for dead
    beats = []

    def beat():
        conn = sqlite3.connect(store)
        try:
            return conn.execute("SELECT MAX(beat) FROM drivers").fetchone()[0]
        finally:
            conn.close()

    class Slow:  # an executor whose cells take 2 s, the driver waiting meanwhile
        name = "slow"

        def run(self, todo, by_hash, log, take):
            for c in todo:
                assert take([c]) == [c]  # claimed as it starts
                beats.append(beat())
                time.sleep(2.0)
                beats.append(beat())
                yield run_cell(c, data[c.data])

    monkeypatch.setattr(_run, "make_executor", lambda *a, **k: Slow())
    gx.run_grid(spec, store)
    assert beats[1] > beats[0]  # the run beat while its cell ran (a run silent for STALE_SECONDS is taken for dead)


def _another_run_opens_first(monkeypatch, store: Path, g, cells) -> None:
    """Between this run's look at the file and its writing connection, another run opens the store (creates or
    upgrades it) and closes it."""
    from graybox.experiments import _store

    orig, state = _store._connect, {"raced": False}

    def racing(path, readonly=False):
        if not readonly and not state["raced"]:
            state["raced"] = True
            _open(store, g, cells).close()
        return orig(path, readonly)

    monkeypatch.setattr(_store, "_connect", racing)


def test_two_runs_creating_one_store_at_once_both_open_it(grid, tmp_path, monkeypatch):
    _, g, _, cells = grid
    store = tmp_path / "s.sqlite"
    _another_run_opens_first(monkeypatch, store, g, cells)
    st = _open(store, g, cells)  # created meanwhile by the other run: opened as it is
    try:
        assert (st.spec_id, st.new_spec) == (1, False)
    finally:
        st.close()
    assert len(gx.store_specs(store)) == 1


def test_two_runs_upgrading_one_first_format_store_at_once_both_open_it(grid, tmp_path, monkeypatch):
    import json
    import sqlite3

    from graybox.experiments._cell import COLUMNS

    _, g, _, cells = grid
    store = tmp_path / "v1.sqlite"
    con = sqlite3.connect(store)  # a store of the first format: meta and cells only
    con.execute("CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)")
    con.execute(f"CREATE TABLE cells ({', '.join(f'{k} {t}' for k, t in COLUMNS.items())})")
    meta = {"format": "graybox-grid-store", "format_version": "1", "grid_fingerprint": g.fingerprint(cells),
            "grid_name": g.name, "grid_spec": json.dumps(g.to_dict()), "graybox_version": gb.__version__,
            "n_cells": str(len(cells)), "created": "2026-01-01T00:00:00+00:00"}
    con.executemany("INSERT INTO meta VALUES (?, ?)", list(meta.items()))
    con.commit()
    con.close()
    _another_run_opens_first(monkeypatch, store, g, cells)
    st = _open(store, g, cells)  # upgraded meanwhile by the other run
    try:
        assert st.spec_id == 1
    finally:
        st.close()
    specs = gx.store_specs(store)
    assert len(specs) == 1 and list(specs["created"]) == ["2026-01-01T00:00:00+00:00"]


def test_a_one_input_surface_band_is_drawn_with_its_points():
    from graybox import plots

    ub = np.linspace(0.0, 1.0, 4)[:, None]
    band = _surface_band(np.column_stack([ub[:, 0], ub[:, 0]]))  # fields, then one input of them
    band = gb.StaticSurfaceBand(ub, ("u",), band.ybar, band.ybar_low, band.ybar_high, band.ybar_std, band.gain[:, :1],
                                band.gain_low[:, :1], band.gain_high[:, :1], band.gain_std[:, :1], 0.95, "delta", 0,
                                band.undefined)
    pts = gb.StaticPoints([0.2, 0.5], [0.4, 1.0], input_names=("u",))  # one input: ubar of shape (N,)
    fig = plots.plot_static_band(band, pts)
    stars = [len(ln.get_xdata()) for ln in fig.axes[0].get_lines() if ln.get_marker() == "*"]
    assert stars == [2]
