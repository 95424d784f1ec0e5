"""Grids on real worker processes: a Dask LocalCluster, the local process pool, workers killed
with SIGKILL, and the driver itself killed with SIGKILL mid-grid and run again."""

from __future__ import annotations

import logging
import os
import signal
import sqlite3
import subprocess
import sys
import threading
import time
import traceback
from collections import deque
from functools import partial
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from graybox import experiments as gx
from graybox.experiments._cell import run_cell
from graybox.experiments import _executors
from graybox.experiments._executors import (BATCH_SECONDS, MAX_BATCH, DaskCluster, ProcessPool, _Batches, _size,
                                            local_cluster, worker_threads)

VALUES = ["data", "structure", "variant", "seed", "status", "message", "n_params", "lambda1", "rule", "in_band",
          "J1_ident", "JS_ident", "fit_ident", "J1_valid", "JS_valid", "fit_valid", "JSF", "static_miss"]


def tiny_grid() -> gx.Grid:
    """ls / cls / PE closed form / a short SE gradient on two structures: 8 cells of milliseconds."""
    return gx.Grid(
        name="tiny",
        data=[gx.DataSpec("pumping", bundled="pumping")],
        structures=[gx.StructureSpec("first-order", terms=["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "1"]),
                    gx.StructureSpec("second-order", terms=["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)^2", "1"])],
        variants=[gx.Variant("LS", "ls"),
                  gx.Variant("CLS", "cls", constraints=[{"type": "equality"}]),
                  gx.Variant("PE", "pe", lambdas={"logspace": [-4, 0, 8]}, options={"solver": "closed"}),
                  gx.Variant("SE", "se-gradient", lambdas=[0.1, 1.0], options={"max_nfev": 5})],
    )


def assert_same_rows(a: pd.DataFrame, b: pd.DataFrame) -> None:
    """Same cells, each once, with identical values (members and θ included)."""
    assert a["key"].is_unique and b["key"].is_unique
    a, b = a.set_index("key").sort_index(), b.set_index("key").sort_index()
    assert list(a.index) == list(b.index)
    pd.testing.assert_frame_equal(a[VALUES], b[VALUES])
    for x, y in zip(a["theta"], b["theta"]):
        assert (x is None and y is None) or np.array_equal(x, y)
    for x, y in zip(a["members"], b["members"]):
        assert (x is None and y is None) or all(np.array_equal(np.asarray(x[k]), np.asarray(y[k])) for k in x)


@pytest.fixture(scope="module")
def reference_store(tmp_path_factory):
    path = tmp_path_factory.mktemp("ref") / "inprocess.sqlite"
    gx.run_grid(tiny_grid(), path)
    return path


@pytest.fixture(scope="module")
def reference(reference_store):
    return gx.load_results(reference_store)


def test_dask_localcluster_gives_the_in_process_rows(reference, tmp_path):
    run = gx.run_grid(tiny_grid(), tmp_path / "dask.sqlite", workers=2)
    assert "LocalCluster of 2 worker processes" in run.executor and run.ran == 8
    df = gx.load_results(tmp_path / "dask.sqlite")
    assert_same_rows(df, reference)
    # the cells ran in the workers, not in the driver
    assert not (df["worker"].str.endswith(f":{os.getpid()}")).any()


def _kill_myself(marker_dir: str, cell, data, threads):
    """Run a cell, except: variant "LS" SIGKILLs its worker every time, "CLS" the first time only."""
    marker = Path(marker_dir) / f"{cell.key}.{len(list(Path(marker_dir).glob(cell.key + '*')))}"
    if cell.variant == "LS" or (cell.variant == "CLS" and not list(Path(marker_dir).glob(cell.key + "*"))):
        marker.touch()
        os.kill(os.getpid(), signal.SIGKILL)
    row = run_cell(cell, data, threads=threads)
    row["NUMBA_NUM_THREADS"] = os.environ.get("NUMBA_NUM_THREADS")  # what the executor gave this worker
    return row


def _death_cells(variants):
    g = gx.Grid(tiny_grid().data, tiny_grid().structures[:1], [v for v in tiny_grid().variants if v.name in variants],
                name="deaths")
    datasets = g.load_data()
    cells = g.cells(datasets)
    return cells, {c.data_hash: datasets[c.data] for c in cells}


def _check_deaths(rows, cells, markers: Path, reference):
    ref = reference.set_index("key")
    for c in cells:
        r = rows[c.variant]
        starts = len(list(markers.glob(c.key + "*")))
        if c.variant == "LS":  # killed, retried once, killed again: failed, with the error
            assert starts == 2 and r["status"] == "failed"
            assert "died" in r["message"] or "KilledWorker" in r["message"]
        else:
            assert starts == (1 if c.variant == "CLS" else 0)  # CLS: killed once, the retry finished
            assert r["status"] == "ok" and r["JS_valid"] == ref.loc[r["key"], "JS_valid"]
            # 2 workers × NUMBA_NUM_THREADS <= cores
            assert r["NUMBA_NUM_THREADS"] == str(worker_threads(2))


def test_a_dying_worker_gets_its_cell_retried_once_processes(tmp_path, reference):
    cells, data = _death_cells(("LS", "CLS", "PE"))
    rows = {r["variant"]: r for r in ProcessPool(2, partial(_kill_myself, str(tmp_path))).run(cells, data)}
    assert set(rows) == {"LS", "CLS", "PE"}
    _check_deaths(rows, cells, tmp_path, reference)


def _dead(pid: int) -> bool:
    """Whether process ``pid`` has exited (a zombie its parent has not reaped yet counts: its pipes are closed)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z"
    except OSError:
        return True


def test_a_pool_worker_killed_between_two_cells_is_replaced_and_the_run_goes_on(reference):
    # was: the next cell, sent to the dead worker, raised BrokenPipeError, which ended the run (a worker killed while
    # its row was being written: the OOM killer, a kill by pid); on Dask under a time limit, a failed batch
    cells, data = _death_cells(("LS", "CLS", "PE"))
    rows = ProcessPool(1).run(cells, data)
    first = next(rows)  # its worker is idle now: the next cell is sent once the row is taken
    pid = int(first["worker"].rsplit(":", 1)[1])
    os.kill(pid, signal.SIGKILL)
    deadline = time.monotonic() + 30
    while not _dead(pid):
        assert time.monotonic() < deadline, "the worker outlived SIGKILL"
        time.sleep(0.01)
    done = [first, *rows]
    assert sorted(r["variant"] for r in done) == ["CLS", "LS", "PE"]
    ref = reference.set_index("key")
    for r in done:
        assert r["status"] == "ok" and r["JS_valid"] == ref.loc[r["key"], "JS_valid"]
    assert all(r["worker"] != first["worker"] for r in done[1:])  # on the worker started in its place


def test_a_dying_worker_gets_its_cell_retried_once_dask_and_a_scheduler_address(tmp_path, reference, monkeypatch):
    from distributed import Client

    # not the one BLAS thread conftest sets for the suite, which the workers would inherit: graybox must set it
    monkeypatch.setenv("OMP_NUM_THREADS", "7")
    with local_cluster(2) as cluster, Client(cluster) as client:
        cells, data = _death_cells(("LS", "CLS", "PE"))
        ex = DaskCluster(client=client, fn=partial(_kill_myself, str(tmp_path)))
        rows = {r["variant"]: r for r in ex.run(cells, data)}
        assert set(rows) == {"LS", "CLS", "PE"}
        _check_deaths(rows, cells, tmp_path, reference)
        # the same cluster by its scheduler's address, as `graybox grid run --scheduler ADDRESS` reaches it
        run = gx.run_grid(tiny_grid(), tmp_path / "by-address.sqlite", scheduler=cluster.scheduler_address)
        assert run.executor.startswith("Dask scheduler at tcp://") and run.ran == 8
        assert_same_rows(gx.load_results(tmp_path / "by-address.sqlite"), reference)
        # the workers run without Dask's MALLOC_TRIM_THRESHOLD_ (it slows numpy's allocations) and
        # with one BLAS thread and cores // workers numba threads (a killed worker's nanny restarts it)
        env = _environments_of_two_workers(client)
        for e in env.values():
            assert e["MALLOC_TRIM_THRESHOLD_"] is None and e["OMP_NUM_THREADS"] == "1"
            assert e["NUMBA_NUM_THREADS"] == str(worker_threads(2))


def _environments_of_two_workers(client) -> dict:
    """Each of the cluster's two workers' environment variables that graybox sets. Asked again while a worker is
    still being replaced (a killed worker's nanny restarts it: under load the scheduler may count one worker that
    is about to be removed, and the question then fails with "Address removed")."""
    for _ in range(10):
        client.wait_for_workers(2, timeout=300)  # a nanny's restart took over 60 s at load average 7
        env = client.run(lambda: {k: os.environ.get(k) for k in ("MALLOC_TRIM_THRESHOLD_", "OMP_NUM_THREADS",
                                                                 "NUMBA_NUM_THREADS")}, on_error="return")
        if len(env) == 2 and all(isinstance(e, dict) for e in env.values()):
            return env
        time.sleep(1)
    raise AssertionError(f"two workers never answered: {env}")


@pytest.fixture(scope="module")
def two_thread_client():
    """A user's cluster: one worker process of two threads (as `dask worker ADDRESS` runs one of a thread per core)."""
    import dask
    from distributed import Client, LocalCluster

    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        cluster = LocalCluster(n_workers=1, threads_per_worker=2, processes=True, dashboard_address=":0",
                               silence_logs=logging.ERROR)
    with cluster, Client(cluster) as client:
        yield client


def test_a_dying_worker_with_two_threads_takes_only_its_own_cell_down(tmp_path, reference, two_thread_client):
    """A user's cluster whose worker runs two threads: the cell that kills its process is the only one failed."""
    cells, data = _death_cells(("LS", "PE", "SE"))
    rows = {r["variant"]: r for r in DaskCluster(client=two_thread_client, fn=partial(_kill_myself, str(tmp_path))).run(
        cells, data)}
    assert set(rows) == {"LS", "PE", "SE"}
    assert rows["LS"]["status"] == "failed" and "died" in rows["LS"]["message"]
    ref = reference.set_index("key")
    for v in ("PE", "SE"):
        assert rows[v]["status"] == "ok", rows[v]["message"]
        assert rows[v]["JS_valid"] == ref.loc[rows[v]["key"], "JS_valid"]


def _where(cell, data, threads):
    """A cell's row and the process that ran it."""
    return {**run_cell(cell, data, threads=threads), "pid": os.getpid()}


def test_cells_on_a_worker_of_two_threads_run_each_in_a_process_of_its_own(reference, two_thread_client):
    # was: side by side in the worker process, whose warning filters and BLAS thread limits are the process's, not a
    # thread's: one cell's catch_warnings undid the other's, and a row lost its own warnings or held another cell's
    # (buck's PE cell without its StaticRangeWarning; an SE cell with one of centred ū that se_pareto silences)
    (worker,) = two_thread_client.run(os.getpid).values()
    cells, data = _death_cells(("LS", "PE", "SE"))
    rows = list(DaskCluster(client=two_thread_client, fn=_where).run(cells, data))
    pids = {r["pid"] for r in rows}
    assert worker not in pids and len(pids) <= 2  # a child process of each worker thread, kept for the run's tasks
    ref = reference.set_index("key")
    for r in rows:
        assert r["status"] == "ok" and r["JS_valid"] == ref.loc[r["key"], "JS_valid"]
        assert tuple(r["warnings"]) == ref.loc[r["key"], "warnings"]


SPEC = """\
name = "killed"
seeds = [0, 1, 2, 3]
[[data]]
name = "pumping"
bundled = "pumping"
[[structures]]
name = "a"
terms = ["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)y(k-1)", "1"]
[[structures]]
name = "b"
terms = ["y(k-1)", "u(k-1)", "u(k-2)", "u(k-1)^2", "1"]
[[variants]]
name = "GA"
estimator = "se-ga"
lambdas = [0.1, 0.5, 1.0]
decision = {rule = "dsf", fallback = "min_jsf"}
options = {population = 150, generations = 25}
[[variants]]
name = "PE"
estimator = "pe"
lambdas = {logspace = [-4, 0, 5]}
options = {solver = "closed"}
"""


def _count(store: Path) -> int:
    try:
        con = sqlite3.connect(f"file:{store}?mode=ro", uri=True, timeout=0.1)
        try:
            return con.execute("SELECT COUNT(*) FROM cells").fetchone()[0]
        finally:
            con.close()
    except sqlite3.Error:
        return 0


def _kill_when(proc: subprocess.Popen, store: Path, cells: int, watch=None) -> int:
    """SIGKILL ``proc`` once the store holds ``cells`` cells (``watch(count)`` called while it
    waits); the cells the store then holds."""
    try:
        deadline = time.monotonic() + 120
        while _count(store) < cells:
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "the grid did not get that far"
            if watch is not None:
                watch(_count(store))
            time.sleep(0.01)
        if watch is not None:
            watch(_count(store))
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.communicate()  # reaps the process and closes its pipes (left open they warn at collection)
    assert proc.returncode == -signal.SIGKILL
    return _count(store)


def test_driver_killed_mid_grid_then_run_again(tmp_path):
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC)
    store = tmp_path / "results.sqlite"
    n = len(gx.Grid.from_toml(spec).cells())
    assert n == 10
    proc = subprocess.Popen([sys.executable, "-m", "graybox._cli", "grid", "run", str(spec), "--store", str(store)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    done = _kill_when(proc, store, 2)
    assert 2 <= done < n, f"{done} of {n} cells were finished when the driver was killed"
    again = gx.run_grid(spec, store)
    assert again.skipped == done and again.ran == n - done
    resumed = gx.load_results(store)
    assert len(resumed) == n and resumed["key"].is_unique
    gx.run_grid(spec, tmp_path / "uninterrupted.sqlite")
    assert_same_rows(resumed, gx.load_results(tmp_path / "uninterrupted.sqlite"))
    assert (resumed["status"] == "ok").all()


@settings(max_examples=60, deadline=None)
@given(groups=st.lists(st.tuples(st.integers(1, 40), st.floats(1e-4, 0.2)), min_size=1, max_size=8),
       slots=st.integers(1, 8), deaths=st.lists(st.integers(0, 200), max_size=3))
def test_dask_batches_hold_every_cell_once_probes_first_then_longest_first(groups, slots, deaths):
    """The Dask executor's batching: every cell exactly once (retried cells again, alone), one cell of
    each (data, variant) group before any group's second, then the cells longest first (a group's
    seconds per term × the cell's terms), in batches of at most ~BATCH_SECONDS of work (or one
    cell) and at most MAX_BATCH cells."""
    cells = [_FakeCell(f"{g}-{i}", "d", f"v{g}", {"terms": ["1"] * ((7 * i) % 5)} if i % 2 else {"n_terms": i % 4})
             for g, (n, _) in enumerate(groups) for i in range(n)]
    rate = {f"v{g}": t for g, (_, t) in enumerate(groups)}

    def seconds(c):
        return rate[c.variant] * _size(c)

    b = _Batches(cells, slots)
    out, retried, n_batches, requeued = [], [], 0, 0
    deaths = set(deaths)
    while b:
        batch = b.next()
        n_batches += 1
        assert 1 <= len(batch) <= MAX_BATCH
        if any(d for _, d in batch):
            assert len(batch) == 1
            retried.append(batch[0][0])
            continue
        if len(out) >= len(groups):  # past the probes: at most ~BATCH_SECONDS of work unless one cell
            assert len(batch) == 1 or sum(seconds(c) for c, _ in batch) <= BATCH_SECONDS * (1 + 1e-9)
        for c, _ in batch:
            out.append(c)
            b.observe(c, seconds(c))
        if n_batches in deaths:
            b.requeue(batch[0][0], 1)
            requeued += 1
    assert sorted(c.key for c in out) == sorted(c.key for c in cells)
    assert len(retried) == requeued  # each requeued cell came back, alone
    assert sorted(c.variant for c in out[:len(groups)]) == sorted(rate)  # one probe per group first
    rest = [seconds(c) for c in out[len(groups):]]
    assert all(x >= y * (1 - 1e-9) for x, y in zip(rest, rest[1:]))  # then the longest cell first


class _FakeCell:
    def __init__(self, key, data, variant, structure_spec):
        self.key, self.data, self.variant, self.structure_spec = key, data, variant, structure_spec


def test_dask_batches_learn_only_from_finite_times():
    cells = [_FakeCell(f"c{i}", "d", "v", {"n_terms": 4}) for i in range(3)]
    b = _Batches(cells, 2)
    for bad in (None, "x", float("nan"), float("inf"), -1.0):
        b.observe(cells[0], bad)
    assert b.model(("d", "v")) is None
    b.observe(cells[0], 0.2)
    assert b.model(("d", "v")) == (0.0, 0.05)  # one size seen: proportional to the terms


@settings(max_examples=60, deadline=None)
@given(groups=st.lists(st.tuples(st.integers(1, 40), st.floats(0, 0.05), st.floats(0, 0.05)), min_size=1,
                       max_size=12),
       slots=st.integers(1, 8))
def test_dask_batches_with_results_late_never_fill_a_batch_from_an_unmeasured_group(groups, slots):
    """With ``slots`` tasks in flight (a task's cells are measured only when it comes back), a batch of
    more than one cell holds only groups already measured, and once a group's time a + b × terms has
    been seen at two sizes its estimate is exact, so such a batch holds at most ~BATCH_SECONDS."""
    assume(any(a + b > 0 for _, a, b in groups))
    cells = [_FakeCell(f"{g}-{i}", "d", f"v{g}", {"n_terms": 1 + (5 * i) % 13})
             for g, (n, _, _) in enumerate(groups) for i in range(n)]
    ab = {f"v{g}": (a, b) for g, (_, a, b) in enumerate(groups)}

    def seconds(c):
        a, b = ab[c.variant]
        return a + b * _size(c)

    bt = _Batches(cells, slots)
    flight: deque = deque()
    sizes: dict[str, set] = {}
    out = []
    while bt or flight:
        if bt and len(flight) < slots:
            batch = [c for c, _ in bt.next()]
            assert batch
            if len(batch) > 1 and len(out) + sum(len(f) for f in flight) >= len(groups):  # past the probes
                assert all(c.variant in sizes for c in batch)
                if all(len(sizes[c.variant]) > 1 for c in batch):
                    assert sum(seconds(c) for c in batch) <= BATCH_SECONDS * (1 + 1e-6) + 1e-12
            flight.append(batch)
            continue
        done = flight.popleft()
        bt.returned([(c, 0) for c in done])
        for c in done:
            bt.observe(c, seconds(c))
            sizes.setdefault(c.variant, set()).add(_size(c))
            out.append(c)
    assert sorted(c.key for c in out) == sorted(c.key for c in cells)


def test_dask_batches_cost_a_group_whose_probe_came_back_untimed_at_the_mean_rate():
    """A probe that came back failed or infeasible (no time learnt) does not leave its group sent
    one cell per task: the group is costed at the other groups' mean rate."""
    cells = [_FakeCell(f"{g}{i}", "d", g, {"n_terms": 4}) for g in ("A", "B") for i in range(20)]
    bt = _Batches(cells, 2)
    probes = bt.next() + bt.next()  # one per in-flight task
    assert sorted(c.variant for c, _ in probes) == ["A", "B"]
    bt.returned(probes[:1])
    bt.returned(probes[1:])
    bt.observe(next(c for c, _ in probes if c.variant == "A"), 0.01)  # B's probe: no time
    batches = []
    while bt:
        batches.append([c for c, _ in bt.next()])
        bt.returned([(c, 0) for c in batches[-1]])
    assert sorted(c.key for b in batches for c in b) == sorted(c.key for c in cells if c not in {p for p, _ in probes})
    assert any(len(b) > 1 and any(c.variant == "B" for c in b) for b in batches)
    assert len(batches) < 12


def test_dask_batches_leave_out_the_work_done_while_a_new_task_waits():
    """A new batch is sized on the work left less what the workers do while it waits behind the
    tasks in flight (QUEUE_SHARE of an in-flight task's estimate per worker thread)."""
    from graybox.experiments._executors import GUIDE, IN_FLIGHT, MIN_BATCH_SECONDS, QUEUE_SHARE

    cells = [_FakeCell(f"c{i}", "d", "v", {"n_terms": 2 + i % 2}) for i in range(400)]
    slots = 2 * IN_FLIGHT
    bt = _Batches(cells, slots)
    (probe,), = [bt.next()]
    bt.returned([probe])
    for k in (2, 3):  # a + b × terms with a = 0.01 s, b = 5 ms, seen at two sizes: estimates exact
        bt.observe(_FakeCell(f"seen{k}", "d", "v", {"n_terms": k}), 0.01 + 0.005 * k)
    est = lambda batch: sum(0.01 + 0.005 * _size(c) for c, _ in batch)  # noqa: E731
    first = bt.next()  # nothing in flight: a share of the work left as it is
    flight = [est(first)]
    for _ in range(3):
        left = sum(0.01 + 0.005 * _size(c) for q in bt.groups.values() for c in q)
        batch = bt.next()
        target = max((left - QUEUE_SHARE * (slots // IN_FLIGHT) * sum(flight) / len(flight)) / (GUIDE * slots),
                     MIN_BATCH_SECONDS)
        head = 0.01 + 0.005 * max(_size(c) for c, _ in batch)
        assert target - head < est(batch) <= target + 1e-12
        assert est(batch) < left / (GUIDE * slots) - head  # smaller than without the tasks in flight
        flight.append(est(batch))


def test_a_growing_run_watched_then_killed_then_resumed(tmp_path):
    """A store made in-process (PE only) grows by the GA variant in another process; `grid status`
    reads it while that process writes; SIGKILL, then the run again: no cell lost or run twice."""
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC)
    base = tmp_path / "base.toml"
    base.write_text(SPEC[: SPEC.index('[[variants]]\nname = "GA"')] + SPEC[SPEC.index('[[variants]]\nname = "PE"'):])
    store = tmp_path / "results.sqlite"
    first = gx.run_grid(base, store)
    assert first.ran == 2
    n = len(gx.Grid.from_toml(spec).cells())
    assert n == 2 + 8
    proc = subprocess.Popen([sys.executable, "-m", "graybox._cli", "grid", "run", str(spec), "--store", str(store)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    seen = []

    def watch(count: int) -> None:
        if count > 2:  # the new spec is registered and its cells are coming in
            seen.append(gx.grid_status(store))

    done = _kill_when(proc, store, 2 + 2, watch)
    # read while the other process wrote: the growing spec, done + left = its cells
    assert seen and all(s.spec == 2 and s.cells == n and s.done + s.left == n for s in seen)
    assert seen[-1].done >= 4 and seen[-1].counts["ok"] >= 2 and np.isfinite(seen[-1].time_per_cell)
    assert "best so far" in seen[-1].summary()
    assert 4 <= done < n, f"{done} of {n} cells were in the store when the run was killed"
    again = gx.run_grid(spec, store)
    assert (again.skipped, again.ran, again.spec) == (done, n - done, 2)
    resumed = gx.load_results(store)
    assert len(resumed) == n and resumed["key"].is_unique and (resumed["status"] == "ok").all()
    assert len(gx.load_results(store, spec="all")) == n  # nothing else in the store
    gx.run_grid(spec, tmp_path / "uninterrupted.sqlite")
    assert_same_rows(resumed, gx.load_results(tmp_path / "uninterrupted.sqlite"))


def test_a_dask_localcluster_grows_a_store_made_in_process(reference_store, reference, tmp_path):
    store = tmp_path / "grown.sqlite"
    store.write_bytes(reference_store.read_bytes())
    g = tiny_grid()
    more = gx.Grid(g.data, g.structures, list(g.variants) + [gx.Variant("ELS", "els")], name="tiny")
    lines: list[str] = []
    # (twice on 2026-11-29 the suite's waiting lane hung here, the driver waiting in as_completed for a task that
    # never came back, until the lane was killed and all its tests errored: a hang now fails here, saying where)
    run = _within(240, lambda: gx.run_grid(more, store, workers=2, log=lines.append))
    assert (run.ran, run.skipped, run.spec) == (2, 8, 2) and "LocalCluster" in run.executor
    assert any("8 reused" in ln and "2 to run" in ln for ln in lines)
    assert any(ln.startswith("Dask dashboard: ") for ln in lines)  # an address, or why there is none
    df = gx.load_results(store)
    assert len(df) == 10 and (df[df["variant"] == "ELS"]["worker"] != df["worker"].iloc[0]).all()
    assert_same_rows(df[df["variant"] != "ELS"], reference)


def _hang_on_ls(marker_dir: str, cell, data, threads):
    """Run a cell, except: variant "LS" writes its pid and sleeps for ten minutes (a cell that hangs)."""
    if cell.variant == "LS":
        (Path(marker_dir) / f"{cell.key}.{os.getpid()}").touch()
        time.sleep(600)
    return run_cell(cell, data, threads=threads)


def test_a_cell_past_the_time_limit_is_stopped_and_failed_and_the_others_run(tmp_path, reference):
    # was: a cell that hung (no row, its worker alive) held its worker, and the run, for ever
    cells, data = _death_cells(("LS", "CLS", "PE"))
    # the limit counts from the cell's start in its worker, not the worker's start-up (imports: seconds)
    pool = ProcessPool(2, partial(_hang_on_ls, str(tmp_path)), time_limit=5.0)
    rows = {r["variant"]: r for r in pool.run(cells, data)}
    assert set(rows) == {"LS", "CLS", "PE"}
    assert rows["LS"]["status"] == "failed" and "cell time limit of 5 s" in rows["LS"]["message"]
    ref = reference.set_index("key")
    for v in ("CLS", "PE"):
        assert rows[v]["status"] == "ok" and rows[v]["JS_valid"] == ref.loc[rows[v]["key"], "JS_valid"]
    (marker,) = tmp_path.glob("*.*")  # started once, not retried
    pid = int(marker.suffix[1:])
    with pytest.raises(ProcessLookupError):  # its worker was killed, not left sleeping
        os.kill(pid, 0)


def _rows_within(limit: float, ex, cells, data) -> list[dict]:
    """``ex.run(cells, data)``'s rows, within ``limit`` s (:func:`_within`)."""
    return _within(limit, lambda: list(ex.run(cells, data)))


def _within(limit: float, run_it):
    """``run_it()``'s result; a run still going after ``limit`` s fails the test with the stack of every thread of
    the driver (what it waits on), rather than hang the pytest it runs in and every test after it."""
    out: dict = {}

    def run() -> None:
        try:
            out["rows"] = run_it()
        except BaseException as exc:  # raised again in the test's thread
            out["exc"] = exc

    t = threading.Thread(target=run, daemon=True, name="the test's run")
    t.start()
    t.join(limit)
    if t.is_alive():
        frames = sys._current_frames()
        stacks = "".join(f"--- {th.name}\n" + "".join(traceback.format_stack(frames[th.ident]))
                         for th in threading.enumerate() if th.ident in frames)
        pytest.fail(f"the run still went on after {limit:g} s; the driver's threads:\n{stacks}")
    if "exc" in out:
        raise out["exc"]
    return out["rows"]


def test_a_cell_past_the_time_limit_on_dask_is_stopped_and_failed_and_the_others_run(tmp_path, reference):
    # was: refused on Dask ("a Dask task's start is not known"), and a hung cell hung its task and the run
    cells, data = _death_cells(("LS", "CLS", "PE"))
    with DaskCluster(workers=1, fn=partial(_hang_on_ls, str(tmp_path)), time_limit=5.0).session() as ex:
        # (once, a fresh clone's suite hung here until its lane was killed: a hang now fails here, saying where)
        rows = {r["variant"]: r for r in _rows_within(240, ex, cells, data)}
    assert set(rows) == {"LS", "CLS", "PE"}
    assert rows["LS"]["status"] == "failed" and "cell time limit of 5 s" in rows["LS"]["message"]
    ref = reference.set_index("key")
    for v in ("CLS", "PE"):
        assert rows[v]["status"] == "ok", rows[v]["message"]
        assert rows[v]["JS_valid"] == ref.loc[rows[v]["key"], "JS_valid"]
    (marker,) = tmp_path.glob("*.*")  # started once, in a child of the Dask worker, not retried
    pid = int(marker.suffix[1:])
    with pytest.raises(ProcessLookupError):  # that child was killed, not left sleeping
        os.kill(pid, 0)


class _StallingStart:
    """A cell function whose unpickling hangs, once, in a process started by the process whose pid ``flag`` holds
    (a Dask worker's child being started: a start-up that never ends, its process alive and silent)."""

    def __init__(self, flag: str):
        self.flag = flag

    def __call__(self, cell, data, threads):
        return run_cell(cell, data, threads=threads)

    def __reduce__(self):
        return _stall_at_start, (self.flag,)


def _stall_at_start(flag: str) -> _StallingStart:
    try:
        parent = int(Path(flag).read_text())
    except (OSError, ValueError):
        parent = None
    if parent == os.getppid():
        os.replace(flag, f"{flag}.{os.getpid()}")  # taken: the next start runs; its name says whose it was
        time.sleep(600)
    return _StallingStart(flag)


def _set_start_limit(seconds: float) -> float:
    """Set START_LIMIT (where this runs: a Dask worker); the one it replaces."""
    old = getattr(_executors, "START_LIMIT", None)  # (main had none: its run waited for ever)
    _executors.START_LIMIT = seconds
    return old


@pytest.fixture(scope="module")
def one_worker_client():
    """graybox's own LocalCluster of one worker (one thread), and a client of it."""
    from distributed import Client

    with local_cluster(1) as cluster, Client(cluster) as client:
        yield client


def test_a_dask_workers_child_that_never_starts_up_fails_its_cell_and_the_run_ends(tmp_path, one_worker_client):
    # was: a task sent its cell (with its data set, more than a pipe holds) to a child that never read it, and waited
    # for ever: the run hung, its Dask worker alive, the cell neither run nor failed
    client = one_worker_client
    cells, data = _death_cells(("CLS",))
    flag = tmp_path / "stall"
    (worker,) = client.run(os.getpid).values()
    (limit,) = client.run(_set_start_limit, 1.0).values()  # on the worker, where its task starts the child
    try:
        flag.write_text(str(worker))
        ex = DaskCluster(client=client, fn=_StallingStart(str(flag)), time_limit=60)
        rows = _rows_within(120, ex, cells, data)  # (on main it waited for ever on the silent child)
    finally:
        client.run(_set_start_limit, limit)
    (row,) = rows
    assert row["status"] == "failed"
    assert "its child process on its Dask worker did not start up within 1 s" in row["message"]
    assert "retry_failed" in row["message"]
    (taken,) = tmp_path.glob("stall.*")  # the child that stalled was stopped, not left behind
    assert _dead(int(taken.suffix[1:]))


def test_a_process_start_waits_for_another_threads_start_only_so_long(monkeypatch):
    # was: a start waited for ever on the start lock another thread's start held (no process started, none failed)
    monkeypatch.setattr(_executors, "START_LIMIT", 0.2, raising=False)  # (main had none: it waited)
    pool = ProcessPool(1, run_cell, process="child process")
    got: list = []

    def start() -> None:
        try:
            got.append(pool._start())
        except RuntimeError as exc:
            got.append(exc)

    with _executors._START_LOCK:
        t = threading.Thread(target=start, daemon=True)
        t.start()
        t.join(10)
        waited = t.is_alive()
    t.join(30)
    for slot in got:  # (a process started once the lock was let go: stopped)
        if not isinstance(slot, RuntimeError):
            ProcessPool._stop(slot, graceful=True)
    assert not waited, "the start waited for the lock past START_LIMIT"
    (exc,) = got
    assert isinstance(exc, RuntimeError)
    assert "could not start a new child process" in str(exc) and "_START_LOCK" in str(exc) and "0.2 s" in str(exc)


def _note_pid(marker_dir: str, cell, data, threads):
    (Path(marker_dir) / f"{cell.key}.{os.getpid()}").touch()
    return run_cell(cell, data, threads=threads)


def test_under_a_time_limit_a_dask_workers_child_serves_the_runs_tasks_and_ends_with_the_run(tmp_path,
                                                                                             one_worker_client):
    # a child process per task cost its start-up (2 s) per task: 24 cheap cells took 57 s instead of 4
    cells, data = _death_cells(("LS", "CLS", "PE", "SE"))
    client = one_worker_client
    (worker,) = client.run(os.getpid).values()
    by_run = []
    for name in ("a", "b"):  # two runs of the four cells, each in several tasks
        (tmp_path / name).mkdir()
        ex = DaskCluster(client=client, fn=partial(_note_pid, str(tmp_path / name)), time_limit=60)
        assert [r["status"] for r in ex.run(cells, data)] == ["ok"] * 4
        by_run.append({int(m.suffix[1:]) for m in (tmp_path / name).iterdir()})
    for pids in by_run:  # one child served every task of a run, and the next run has its own
        assert len(pids) == 1 and worker not in pids
    assert by_run[0] != by_run[1]
    (child,) = by_run[0]
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:  # its run's end closed it (the worker itself lives on)
        try:
            os.kill(child, 0)
        except ProcessLookupError:
            break
        time.sleep(0.2)
    else:
        pytest.fail("the child kept for a run's tasks outlived the run")


_ORPHAN_SCRIPT = """
import os, sys, time
from pathlib import Path
from graybox.experiments._executors import ProcessPool


def sleep_in_cell(cell, data, threads):
    Path(sys.argv[1], str(os.getpid())).touch()
    time.sleep(600)


if __name__ == "__main__":
    sys.path.insert(0, sys.argv[2])
    from test_grid_executors import _death_cells
    cells, data = _death_cells(("LS",))
    list(ProcessPool(1, sleep_in_cell).run(cells, data))
"""


def test_a_pool_worker_whose_driver_is_killed_exits_rather_than_run_its_cell_for_nobody(tmp_path):
    # was: a worker went on with its cell (a hung one for ever) once its driver, or the Dask worker that started
    # it under a cell time limit, was SIGKILLed
    script = tmp_path / "driver.py"
    script.write_text(_ORPHAN_SCRIPT)
    marks = tmp_path / "marks"
    marks.mkdir()
    driver = subprocess.Popen([sys.executable, str(script), str(marks), str(Path(__file__).parent)],
                              stdin=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 120
        while not list(marks.iterdir()) and time.monotonic() < deadline and driver.poll() is None:
            time.sleep(0.2)
        (mark,) = marks.iterdir()
        worker = int(mark.name)
        driver.send_signal(signal.SIGKILL)
        driver.wait()
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            try:
                os.kill(worker, 0)
            except ProcessLookupError:
                break
            time.sleep(0.2)
        else:
            os.kill(worker, signal.SIGKILL)
            pytest.fail("the pool's worker outlived its killed driver by 30 s")
    finally:
        if driver.poll() is None:
            driver.kill()
            driver.wait()


def test_a_cell_time_limit_is_refused_where_a_cell_cannot_be_stopped(tmp_path):
    for how in ({}, {"executor": "inprocess"}):
        with pytest.raises(ValueError, match="cell_time_limit needs worker processes"):
            gx.run_grid(tiny_grid(), tmp_path / "s.sqlite", cell_time_limit=5, **how)
    for bad, err in ((0, ValueError), (float("inf"), ValueError), ("5", TypeError)):
        with pytest.raises(err, match="cell_time_limit"):
            gx.run_grid(tiny_grid(), tmp_path / "s.sqlite", executor="processes", cell_time_limit=bad)
    assert not (tmp_path / "s.sqlite").exists()  # refused before the store is made


def _sleep_then_run(seconds: float, cell, data, threads):
    time.sleep(seconds)
    return run_cell(cell, data, threads=threads)


def test_a_dask_run_whose_cluster_has_no_worker_left_ends_with_the_reason(tmp_path):
    """Every worker gone and none restarted (here the cluster scaled to 0 mid-run): the tasks would wait
    for ever; the run ends after ``worker_timeout`` seconds with a ConnectionError saying so."""
    import threading

    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0",
                           silence_logs=logging.ERROR)
    with cluster, Client(cluster) as client:
        cells, data = _death_cells(("LS", "CLS", "PE"))
        ex = DaskCluster(client=client, fn=partial(_sleep_then_run, 60.0), worker_timeout=2)
        out: dict = {}

        def drive():
            try:
                out["rows"] = list(ex.run(cells, data))
            except Exception as exc:  # noqa: BLE001 - what the run ended with is the test's object
                out["error"] = exc

        t = threading.Thread(target=drive, daemon=True)
        t.start()
        time.sleep(1.5)
        t0 = time.monotonic()
        cluster.scale(0)
        t.join(timeout=45)
        assert not t.is_alive(), "the run still waits on a cluster without workers"
        assert time.monotonic() - t0 >= 2
    assert "rows" not in out
    assert isinstance(out["error"], ConnectionError)
    assert "no worker for 2 s" in str(out["error"]) and "run the grid again" in str(out["error"])


def test_the_dask_worker_timeout_is_checked():
    with pytest.raises(ValueError, match="worker_timeout"):
        DaskCluster(workers=1, worker_timeout=0)
    with pytest.raises(TypeError, match="worker_timeout"):
        DaskCluster(workers=1, worker_timeout="60")
    assert DaskCluster(workers=1, worker_timeout=None).worker_timeout is None


def test_run_grid_passes_worker_timeout_to_dask_and_refuses_it_elsewhere(tmp_path):
    from graybox.experiments._executors import make_executor

    assert make_executor("dask", workers=1, worker_timeout=None).worker_timeout is None
    assert make_executor("dask", workers=1, worker_timeout=5).worker_timeout == 5.0
    assert make_executor("dask", workers=1).worker_timeout == 60
    with pytest.raises(ValueError, match="worker_timeout is for a Dask cluster"):
        gx.run_grid(tiny_grid(), tmp_path / "s.sqlite", executor="processes", worker_timeout=10)
    with pytest.raises(TypeError, match="worker_timeout"):
        gx.run_grid(tiny_grid(), tmp_path / "s.sqlite", worker_timeout="10")
    assert not (tmp_path / "s.sqlite").exists()


def _say_started_then_sleep(marker: str, cell, data, threads):
    Path(marker).touch()
    time.sleep(30)
    return run_cell(cell, data, threads=threads)


def test_a_dask_run_whose_scheduler_is_killed_ends_with_a_connection_error_that_says_what_to_do(tmp_path):
    """The scheduler SIGKILLed mid-run: the client's own error (a connect timing out, CommClosedError) became a
    ConnectionError saying the rows finished are kept and to run again."""
    import socket
    import threading
    from contextlib import suppress

    import dask
    from distributed import Client

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    # the cell function lives in this file: the scheduler and the worker unpickle it
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(Path(__file__).parent), *sys.path]))
    procs = [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                               "--port", str(port), "--dashboard-address", ":0"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True, env=env)]
    try:
        with dask.config.set({"distributed.comm.timeouts.connect": "3s"}):
            client = Client(address, timeout="8s")  # also how long it tries to reconnect once the scheduler is gone
            procs.append(subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads",
                                           "1", "--nworkers", "1"], stdout=subprocess.DEVNULL,
                                          stderr=subprocess.DEVNULL, start_new_session=True,
                                          env=env))
            client.wait_for_workers(1, timeout=60)
            marker = tmp_path / "started"
            cells, data = _death_cells(("LS", "CLS", "PE"))
            ex = DaskCluster(client=client, fn=partial(_say_started_then_sleep, str(marker)), worker_timeout=None)

            def kill_the_scheduler_once_a_cell_runs():
                while not marker.exists():
                    time.sleep(0.2)
                os.killpg(procs[0].pid, signal.SIGKILL)

            threading.Thread(target=kill_the_scheduler_once_a_cell_runs, daemon=True).start()
            with pytest.raises(ConnectionError, match="rows finished are kept: run the grid again"):
                rows = list(ex.run(cells, data))
                raise AssertionError(f"the run ended without an error: {rows}")
    finally:
        for p in procs:
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            p.wait()
        with suppress(Exception):
            client.close(timeout=2)


_CALLBACK_WORKER = """
import ctypes, os, signal, sys, threading, time
from graybox.experiments._executors import exit_on_sigterm
exit_on_sigterm()
def busy(x):  # Python called back from C, as numba's compiler calls it through ctypes
    t = time.monotonic()
    while time.monotonic() - t < 1.0:
        pass
    return x
cb = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_int)(busy)
threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGTERM)).start()
for i in range(3):
    cb(i)
print("the cell ran on")
"""


def test_a_worker_stopped_inside_a_callback_exits_without_a_traceback():
    # a SIGTERM landing while a worker ran Python called back from C (numba compiling) raised its SystemExit inside
    # the callback: ctypes printed it as 'Exception ignored ... Traceback' and the worker ran its cell on
    r = subprocess.run([sys.executable, "-c", _CALLBACK_WORKER], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and "the cell ran on" not in r.stdout, (r.stdout, r.stderr)
    assert r.stderr == ""
