"""Where cells run: in the driver, in local worker processes, or on a Dask distributed cluster.

Every executor takes the cells and the data and yields rows *as they complete*; only the driver
writes them to the store. Parallel executors keep workers × threads ≤ cores: each worker process
gets ``NUMBA_NUM_THREADS`` (and the BLAS thread variables) = cores // workers, and a cell itself
runs BLAS and numba on one thread (see :func:`graybox.experiments._cell.run_cell`).

A worker process that dies while running a cell (killed, out of memory, a crash in compiled
code) gets that cell retried once on a fresh worker; if it dies again the cell is a failed row
naming what happened. The local process pool does this itself and knows exactly which cell a
dead worker was running. On Dask the scheduler does it: the ``LocalCluster`` graybox starts
allows one failure per task (``allowed-failures`` 1) and hands each worker one cell at a time, so
a death is charged to the cell that was running — Dask charges every task it had placed on the
dead worker, which can include a retried cell waiting there. A cluster the user brings keeps its
own ``distributed.scheduler.allowed-failures``.
"""

from __future__ import annotations

import logging
import multiprocessing as mp
import os
import uuid
from collections import deque
from contextlib import contextmanager
from dataclasses import dataclass, field
from multiprocessing.connection import wait as mp_wait
from typing import Any, Callable, Iterator, Mapping, Sequence

import graybox as gb

from ._cell import failed_row, run_cell
from ._spec import Cell

__all__ = ["EXECUTORS", "InProcess", "ProcessPool", "DaskCluster", "local_cluster", "make_executor", "worker_threads"]

#: Executor names accepted by :func:`graybox.experiments.run_grid`.
EXECUTORS = ("inprocess", "processes", "dask")

CellFn = Callable[[Cell, gb.Dataset, int], dict]


def worker_threads(workers: int, cores: int | None = None) -> int:
    """Threads each of ``workers`` processes may use so that workers × threads ≤ cores (at least 1)."""
    cores = cores or os.cpu_count() or 1
    return max(1, cores // max(1, workers))


def _thread_env(threads: int) -> dict[str, str]:
    t = str(threads)
    return {"NUMBA_NUM_THREADS": t, "OMP_NUM_THREADS": t, "OPENBLAS_NUM_THREADS": t, "MKL_NUM_THREADS": t}


@contextmanager
def _environ(values: Mapping[str, str]):
    """Temporarily set environment variables (inherited by processes started inside)."""
    old = {k: os.environ.get(k) for k in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


class InProcess:
    """Cells one after another in the driver process (the default)."""

    name = "in-process"

    def __init__(self, fn: CellFn = run_cell):
        self.fn = fn

    def run(self, cells: Sequence[Cell], datasets: Mapping[str, gb.Dataset]) -> Iterator[dict]:
        """Yield each cell's row."""
        for c in cells:
            yield self.fn(c, datasets[c.data_hash], 1)


# --------------------------------------------------------------------------------------------
# local worker processes
# --------------------------------------------------------------------------------------------
def _worker_main(conn, fn: CellFn) -> None:  # pragma: no cover - runs in the child process
    """A worker process: receive (cell, data or None), run it, send the row; stop on None or EOF."""
    cache: dict[str, gb.Dataset] = {}
    while True:
        try:
            msg = conn.recv()
        except (EOFError, OSError):  # the driver is gone
            return
        if msg is None:
            return
        cell, data = msg
        if data is not None:
            cache[cell.data_hash] = data
        row = fn(cell, cache[cell.data_hash], 1)
        try:
            conn.send(row)
        except (BrokenPipeError, OSError):
            return


@dataclass
class _Slot:
    proc: Any
    conn: Any
    sent: set = field(default_factory=set)
    cell: Cell | None = None
    attempt: int = 0


class ProcessPool:
    """Cells in ``workers`` local processes (spawned), results taken as they complete.

    Parameters
    ----------
    workers : int
        Number of worker processes.
    fn : callable
        What a worker runs for a cell (default: :func:`run_cell`).
    """

    def __init__(self, workers: int, fn: CellFn = run_cell):
        self.workers = int(workers)
        self.threads = worker_threads(self.workers)
        self.fn = fn
        self.name = f"{self.workers} local processes ({self.threads} thread(s) each)"
        self._ctx = mp.get_context("spawn")

    def _start(self) -> _Slot:
        parent, child = self._ctx.Pipe()
        proc = self._ctx.Process(target=_worker_main, args=(child, self.fn), daemon=True,
                                 name="graybox-grid-worker")
        with _environ(_thread_env(self.threads)):
            proc.start()
        child.close()
        return _Slot(proc, parent)

    @staticmethod
    def _stop(slot: _Slot, graceful: bool) -> None:
        try:
            if graceful:
                slot.conn.send(None)
        except (BrokenPipeError, OSError):
            pass
        slot.proc.join(timeout=5 if graceful else 0.1)
        if slot.proc.is_alive():
            slot.proc.kill()
            slot.proc.join(timeout=5)
        slot.conn.close()

    def run(self, cells: Sequence[Cell], datasets: Mapping[str, gb.Dataset]) -> Iterator[dict]:
        """Yield each cell's row as it completes."""
        pending: deque[tuple[Cell, int]] = deque((c, 0) for c in cells)
        slots: list[_Slot] = []
        try:
            slots = [self._start() for _ in range(min(self.workers, max(1, len(pending))))]
            while pending or any(s.cell is not None for s in slots):
                for s in slots:
                    if s.cell is None and pending:
                        s.cell, s.attempt = pending.popleft()
                        h = s.cell.data_hash
                        s.conn.send((s.cell, None if h in s.sent else datasets[h]))
                        s.sent.add(h)
                busy = [s for s in slots if s.cell is not None]
                ready = set(mp_wait([s.conn for s in busy] + [s.proc.sentinel for s in busy]))
                for i, s in enumerate(slots):
                    if s.cell is None or not ({s.conn, s.proc.sentinel} & ready):
                        continue
                    row = None
                    try:
                        if s.conn.poll():
                            row = s.conn.recv()
                    except (EOFError, OSError):
                        row = None
                    if row is not None:
                        s.cell = None
                        yield row
                        continue
                    # the worker died while running s.cell
                    s.proc.join(timeout=5)
                    code = s.proc.exitcode
                    cell, attempt = s.cell, s.attempt + 1
                    self._stop(s, graceful=False)
                    slots[i] = self._start()
                    if attempt < 2:
                        pending.appendleft((cell, attempt))
                    else:
                        yield failed_row(cell, f"the worker process died twice while running this cell "
                                               f"(last exit code {code}); it was retried once")
        finally:
            for s in slots:
                self._stop(s, graceful=s.proc.is_alive())


# --------------------------------------------------------------------------------------------
# Dask distributed
# --------------------------------------------------------------------------------------------
@contextmanager
def local_cluster(workers: int):
    """The Dask ``LocalCluster`` graybox starts for ``workers`` processes (closed on exit).

    One thread per worker, ``NUMBA_NUM_THREADS`` = cores // workers; the scheduler hands a
    worker one queued cell at a time (``worker-saturation`` 1.0) and retries a cell once after
    its worker died (``allowed-failures`` 1): a second death makes it a failed row.
    """
    import dask
    from distributed import LocalCluster

    with dask.config.set({"distributed.scheduler.worker-saturation": 1.0,
                          "distributed.scheduler.allowed-failures": 1}):
        cluster = LocalCluster(n_workers=int(workers), threads_per_worker=1, processes=True, dashboard_address=None,
                               silence_logs=logging.ERROR, env=_thread_env(worker_threads(int(workers))))
    try:
        yield cluster
    finally:
        cluster.close()


class DaskCluster:
    """Cells on a Dask distributed cluster: a Client given, a scheduler address, or a LocalCluster.

    Parameters
    ----------
    client : distributed.Client, optional
        A client the caller owns (not closed here).
    scheduler : str, optional
        Address of a running scheduler, e.g. ``"tcp://10.0.0.5:8786"``.
    workers : int, optional
        Start a ``LocalCluster`` of this many worker processes (one thread each) for the run.
    fn : callable
        What a worker runs for a cell.
    """

    def __init__(self, client: Any = None, scheduler: str | None = None, workers: int | None = None,
                 fn: CellFn = run_cell):
        given = [k for k, v in (("client", client), ("scheduler", scheduler), ("workers", workers)) if v is not None]
        if len(given) != 1:
            raise ValueError(f"the Dask executor needs exactly one of client, scheduler or workers; got {given or 'none'}")
        self.client, self.scheduler, self.workers, self.fn = client, scheduler, workers, fn
        if workers is not None:
            self.workers = int(workers)
            self.name = f"Dask LocalCluster of {self.workers} worker processes"
        elif scheduler is not None:
            self.name = f"Dask scheduler at {scheduler}"
        else:
            self.name = "Dask client"

    @contextmanager
    def _client(self):
        from distributed import Client

        if self.client is not None:
            if not isinstance(self.client, Client):
                raise ValueError(f"client must be a distributed.Client, got {type(self.client).__name__}")
            yield self.client
            return
        if self.scheduler is not None:
            client = Client(self.scheduler, timeout="30s")
            try:
                client.wait_for_workers(1, timeout=60)
                yield client
            finally:
                client.close()
            return
        with local_cluster(self.workers) as cluster:
            client = Client(cluster)
            try:
                yield client
            finally:
                client.close()

    def run(self, cells: Sequence[Cell], datasets: Mapping[str, gb.Dataset]) -> Iterator[dict]:
        """Submit the cells, yield each row as it completes."""
        from distributed import as_completed

        if not cells:
            return
        from ._dask import GridData, cell_task

        with self._client() as client:
            plugin = f"graybox-grid-data-{uuid.uuid4().hex[:8]}"
            client.register_plugin(GridData({h: datasets[h] for h in {c.data_hash for c in cells}}), name=plugin)
            nthreads = max(1, sum(client.nthreads().values()))
            # A grid larger than twice the cluster's threads is queued on the scheduler, which then
            # hands a worker one cell at a time (worker-saturation 1.0 on a LocalCluster we start).
            # A smaller one would be assigned to workers all at once, so a worker's death would be
            # charged to the cells waiting behind the one it was running: such grids are fed one
            # cell per thread from here. The data sets reach every worker (restarted ones too)
            # in a worker plugin; a scattered copy would be lost with a worker that dies.
            window = len(cells) if len(cells) > 2 * nthreads else nthreads
            tag = uuid.uuid4().hex[:8]
            todo = iter(cells)
            futures: dict = {}

            def submit() -> bool:
                c = next(todo, None)
                if c is None:
                    return False
                f = client.submit(cell_task, self.fn, plugin, c, key=f"graybox-cell-{c.key[:24]}-{tag}", pure=False)
                futures[f] = c
                return True

            for _ in range(window):
                if not submit():
                    break
            pending = as_completed(list(futures))
            try:
                for f in pending:
                    c = futures.pop(f)
                    if submit():
                        pending.add(next(reversed(futures)))
                    if f.status == "finished":
                        row = f.result()
                    else:
                        try:
                            exc = f.exception(timeout=10)
                        except Exception as err:  # e.g. a cancelled future has no exception to give
                            exc = err
                        why = f"{type(exc).__name__}: {exc}" if exc is not None else f"the task ended as {f.status!r}"
                        row = failed_row(c, why)
                    f.release()
                    yield row
            finally:
                for f in futures:
                    f.cancel()
                try:
                    client.unregister_worker_plugin(plugin)
                except Exception:  # the cluster may be going away; the plugin goes with it
                    pass


def make_executor(executor: str | None = None, *, workers: int | None = None, client: Any = None,
                  scheduler: str | None = None, fn: CellFn = run_cell):
    """The executor for :func:`graybox.experiments.run_grid`'s arguments (see there)."""
    if executor is None:
        executor = "dask" if (client is not None or scheduler is not None or workers is not None) else "inprocess"
    if executor not in EXECUTORS:
        raise ValueError(f"executor must be one of {', '.join(map(repr, EXECUTORS))}; got {executor!r}")
    if workers is not None:
        if isinstance(workers, bool) or int(workers) != workers or workers < 1:
            raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
        workers = int(workers)
    if executor == "inprocess":
        if any(v is not None for v in (workers, client, scheduler)):
            raise ValueError("the in-process executor takes no workers, client or scheduler")
        return InProcess(fn)
    if executor == "processes":
        if client is not None or scheduler is not None:
            raise ValueError("the local process executor takes workers only (a client or scheduler means Dask)")
        return ProcessPool(workers or os.cpu_count() or 1, fn)
    return DaskCluster(client=client, scheduler=scheduler, workers=workers, fn=fn)
