"""Review of two runs sharing one store (review41e): what a run holds while it takes over another run's cells,
and where a new store is made."""

from __future__ import annotations

import threading
import time

from graybox import experiments as gx
from graybox.experiments import _run, _store
from graybox.experiments._store import running_cells

from test_grid_claims import _open, grid  # noqa: F401  (a fixture)


def test_a_run_taking_over_a_stopped_runs_cells_holds_only_the_one_it_runs(grid, tmp_path, monkeypatch):  # noqa: F811
    # a run left with cells another run held (a Dask run's batches, here every cell) waits; when that run stops,
    # the waiting run claimed every one of them at once and ran them one at a time: grid status said it ran all
    # of them, and a third run started meanwhile waited for them instead of sharing them
    spec, g, _, cells = grid
    store = tmp_path / "s.sqlite"
    other = _open(store, g, cells)
    assert other.claim([c.key for c in cells]) == {}
    held, real = [], _run.run_cell

    def cell(c, data, threads=1):
        held.append(sum(running_cells(store).values()))
        return real(c, data, threads=threads)

    monkeypatch.setattr(_run, "run_cell", cell)
    lines, out = [], {}

    def target():
        try:
            out["run"] = gx.run_grid(spec, store, log=lines.append)
        except BaseException as exc:  # pragma: no cover - reported below
            out["error"] = exc

    t = threading.Thread(target=target)
    t.start()
    try:
        deadline = time.monotonic() + 60
        while not any("waits for them" in x for x in lines):
            assert t.is_alive() and time.monotonic() < deadline, (lines, out)
            time.sleep(0.01)
    finally:
        other.close()  # it stops without running any: the waiting run takes them over
    t.join(120)
    assert not t.is_alive() and "error" not in out, out
    assert out["run"].ran == len(cells) and len(held) == len(cells)
    assert held == [1] * len(cells)  # while it runs a cell, it holds that one only
    assert gx.grid_status(store).running == {}
