"""Where cells run: in the driver, in local worker processes, or on a Dask distributed cluster.

Every executor takes the cells and the data and yields rows *as they complete*; only the driver
writes them to the store. An executor starts a cell only once ``take`` has given it (the driver's
claim on the store, so that two runs on one store share the cells): it asks for as many as it can
start at that moment (a free worker, a Dask task), not for all of them when it begins. Parallel
executors keep workers × threads ≤ cores: each worker process gets ``NUMBA_NUM_THREADS`` (and the
BLAS thread variables) = cores // workers, and a cell itself runs BLAS and numba on one thread
(see :func:`graybox.experiments._cell.run_cell`).

A worker process that dies while running a cell (killed, out of memory, a crash in compiled
code) gets that cell retried once on a fresh worker; if it dies again the cell is a failed row
naming what happened. The driver does this itself for both pools, and knows which cells a dead
worker held: the local pool gives a worker one cell at a time; on Dask the driver keeps
``IN_FLIGHT`` tasks per worker thread in flight, and a task is a batch of cells (see
:class:`_Batches`). When a Dask worker dies, every cell of its tasks is retried alone, so the one
that kills its worker dies alone the second time.
The ``LocalCluster`` graybox starts reports a worker's death at once (``allowed-failures`` 0); a
cluster the user brings first retries as its own ``distributed.scheduler.allowed-failures`` says.
A Dask worker of several threads (``dask worker ADDRESS`` runs one of a thread per core) runs the cells of each
thread in a child process of its own, as under a cell time limit: a process's warning filters and BLAS thread
limits are not a thread's, and cells side by side in one process took each other's warnings.

Inside ``with executor.session():`` an executor keeps what it started (the local pool's workers, the Dask
client and its ``LocalCluster``) from one :meth:`run` to the next while it is alive, and stops it when the
session ends: a run that waits for another run's cells and then takes some over starts nothing again (a
``LocalCluster`` start is seconds; BENCHMARKS.md, grids).
"""

from __future__ import annotations

import itertools
import logging
import multiprocessing as mp
import os
import shutil
import signal
import sys
import tempfile
import threading
import time
import uuid
from collections import deque
from contextlib import AbstractContextManager, ExitStack, contextmanager, nullcontext, suppress
from dataclasses import dataclass, field
from functools import partial
from multiprocessing.connection import wait as mp_wait
from typing import Any, Callable, Iterator, Mapping, Sequence

import numpy as np

from .. import _api as gb

from ..core._files import lock_fd
from ..core._validation import check_choice, check_real, check_workers
from . import _dask_worker
from ._cell import failed_row, run_cell
from ._spec import Cell

__all__ = ["EXECUTORS", "InProcess", "ProcessPool", "DaskCluster", "check_cluster", "local_cluster", "make_executor",
           "scheduler_client", "session", "worker_threads"]

#: Executor names accepted by :func:`graybox.experiments.run_grid`.
EXECUTORS = ("inprocess", "processes", "dask")

CellFn = Callable[[Cell, gb.Dataset, int], dict]
#: Given cells an executor is about to start, those it may start (the others another run on the store holds or
#: has written: the driver knows of them and sees to them).
Take = Callable[[Sequence[Cell]], Sequence[Cell]]
#: Where an executor tells what is worth telling at the start (e.g. the dashboard's address).
Log = Callable[[str], None]


def _bokeh() -> bool:
    """Whether Dask's dashboard can be served here (it needs bokeh, an optional package)."""
    import importlib.util

    return importlib.util.find_spec("bokeh") is not None


def _has_dashboard(client: Any) -> bool:
    try:
        return "dashboard" in client.scheduler_info().get("services", {})
    except Exception:  # an old or odd scheduler: say nothing rather than a wrong address
        return False

#: A Dask task runs a batch of cells lasting at most about this long (seconds, by the times of the
#: cells already run): the scheduler's cost per task (milliseconds) is then well under a per cent,
#: and a killed driver loses at most IN_FLIGHT × threads of them.
BATCH_SECONDS = 3.0
#: Towards the end a batch holds at most 1/(GUIDE × in-flight tasks) of the work left ...
GUIDE = 1
#: ... but not less than this (seconds), so that the last tasks do not become many tiny ones.
MIN_BATCH_SECONDS = 0.04
#: A new task waits behind the worker's task in flight: of the work left, the share the workers
#: will do meanwhile (this fraction of an in-flight task's estimated time, per worker thread) is
#: not counted when the task is sized, lest a task sized for the work left at its submission start
#: when little is left and end long after the other workers (chosen by a simulation of the
#: batcher: BENCHMARKS.md, grids).
QUEUE_SHARE = 0.75
#: Most cells in one Dask task.
MAX_BATCH = 64
#: Dask tasks in flight per worker thread: the next one waits on the worker, so no round trip
#: through the driver sits between two tasks.
IN_FLIGHT = 2
#: How long the driver tries to reach a Dask scheduler given by its address.
CONNECT_TIMEOUT = "30s"
#: How long the driver waits for the first worker of a Dask scheduler given by its address, and how long a
#: Dask run goes on once its cluster has no worker left (seconds): tasks sent to a cluster without workers
#: wait for ever.
WORKER_TIMEOUT = 60


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


def session(executor: Any) -> AbstractContextManager:
    """The executor's session (see the module's docstring); one that starts nothing to keep (the in-process
    one) has none."""
    opened = getattr(executor, "session", None)
    return opened() if opened is not None else nullcontext(executor)


def _take_next(pending: deque, n: int, take: Take | None) -> list[Cell]:
    """Up to ``n`` cells from the front of ``pending`` that ``take`` gives (all of them without ``take``): fewer
    only when ``pending`` runs out."""
    out: list[Cell] = []
    while pending and len(out) < n:
        ask = [pending.popleft() for _ in range(min(n - len(out), len(pending)))]
        out.extend(ask if take is None else take(ask))
    return out


class InProcess:
    """Cells one after another in the driver process (the default)."""

    name = "in-process"

    def __init__(self, fn: CellFn = run_cell):
        self.fn = fn

    def run(self, cells: Sequence[Cell], datasets: Mapping[str, gb.Dataset], log: Log | None = None,
            take: Take | None = None) -> Iterator[dict]:
        """Yield each cell's row, each cell taken (``take``) as it is about to run."""
        pending = deque(cells)
        while pending:
            for c in _take_next(pending, 1, take):
                yield self.fn(c, datasets[c.data_hash], threads=1)


# --------------------------------------------------------------------------------------------
# local worker processes
# --------------------------------------------------------------------------------------------
def _raise_exit(signum, frame) -> None:  # pragma: no cover - runs in the child process
    raise SystemExit(0)


def exit_on_sigterm() -> None:  # pragma: no cover - runs in the child process
    """Make SIGTERM end this (worker) process through Python's clean-up, even when it lands in a callback."""
    signal.signal(signal.SIGTERM, _raise_exit)
    sys.unraisablehook = _exit_past_callbacks


def _exit_past_callbacks(args) -> None:  # pragma: no cover - runs in the child process
    """sys.unraisablehook of a worker: a SIGTERM whose SystemExit was raised inside a C library's callback into
    Python (numba compiling through ctypes) or a finaliser is swallowed there, printed as 'Exception ignored ...
    Traceback', and the worker ran its cell on. It is raised again at the next call outside this hook (a profile
    function's first event): the caller's next line, or inside the next callback, which lands here again."""
    if not isinstance(args.exc_value, SystemExit):
        sys.__unraisablehook__(args)
        return
    here = sys._getframe()

    def stop(frame, event, arg):
        if frame is here:  # this hook's own return
            return
        sys.setprofile(None)
        raise SystemExit(0)

    sys.setprofile(stop)


#: What a pool worker sends when it starts a cell (before its row): the cell's time limit counts from it, not
#: from the worker's own start-up.
STARTED = "started"
#: What a pool worker sends once it has started up and waits for its first cell: only then is it sent one (the first
#: carries the cell's data set, more than a pipe holds, and a send to a worker that never reads waited for ever).
READY = "ready"
#: Seconds a pool worker may go without a word where one is due: from its start to :data:`READY` (Python's start-up
#: and graybox's imports, seconds), and from a cell's send to :data:`STARTED` (its unpickling, milliseconds); past
#: them it is stopped and its cell is a failed row saying so, rather than the run waiting on it for ever. Also how
#: long a start waits for another thread's (``_START_LOCK``).
START_LIMIT = 120.0


def _exit_when_orphaned(parent: int) -> None:  # pragma: no cover - runs in the child process
    """Exit at once when the process that started this one is gone (SIGKILLed, say: a Dask worker the nanny
    replaces), rather than running a cell, perhaps a hung one, for nobody."""
    while os.getppid() == parent:
        time.sleep(1.0)
    os._exit(1)


def _worker_main(conn, fn: CellFn) -> None:  # pragma: no cover - runs in the child process
    """A worker process: say it is ready; then receive (cell, data or None), say it started, run it, send the row;
    stop on None, EOF, SIGTERM or the death of the process that started it."""
    # stopped mid-cell (the driver interrupted), exit through Python's clean-up: a killed worker leaves
    # numba's named semaphore behind, for the resource tracker to warn of
    exit_on_sigterm()
    threading.Thread(target=_exit_when_orphaned, args=(os.getppid(),), daemon=True,
                     name="graybox worker's parent watch").start()
    cache: dict[str, gb.Dataset] = {}
    try:
        conn.send(READY)
    except (BrokenPipeError, OSError):
        return
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
        try:
            conn.send(STARTED)
        except (BrokenPipeError, OSError):
            return
        row = fn(cell, cache[cell.data_hash], threads=1)
        try:
            conn.send(row)
        except (BrokenPipeError, OSError):
            return


def ignore_sigint() -> None:  # pragma: no cover - runs in the worker process
    """A pool worker's initializer: SIGINT ignored, so that Ctrl-C (sent to the terminal's whole process
    group) is the driver's to handle, without a traceback from every worker."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextmanager
def _sigint_ignored():
    """Processes started inside ignore SIGINT for good (a spawned Python keeps an ignored SIGINT ignored).

    Ctrl-C at a terminal reaches the whole process group: the workers died of it, each with its
    traceback, while the driver, which stops them anyway, is the one to say what was kept.
    """
    if threading.current_thread() is not threading.main_thread():  # signal handlers are the main thread's
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


#: Held while a pool worker is started: the environment (its thread variables) and the daemon flag it is started
#: with are the process's, and the threads of a Dask worker start theirs at once (each task's, under a time limit).
_START_LOCK = threading.Lock()


@contextmanager
def _children_allowed():
    """Let a daemonic process (a Dask worker under its nanny) start processes meanwhile (hold ``_START_LOCK``):
    multiprocessing refuses them there, for they would be left behind when it is ended; the pool's workers exit
    once it is gone."""
    me = mp.current_process()
    if not me.daemon:
        yield
        return
    me.daemon = False
    try:
        yield
    finally:
        me.daemon = True


@dataclass
class _Slot:
    proc: Any
    conn: Any
    sent: set = field(default_factory=set)
    cell: Cell | None = None
    attempt: int = 0
    started: float | None = None  # time.monotonic() when the worker said it started ``cell``
    ready: bool = False  # the worker said READY: it reads what it is sent (its cell goes then)
    since: float = field(default_factory=time.monotonic)  # since when a word is due: its start, or its cell's send


class ProcessPool:
    """Cells in ``workers`` local processes (spawned), results taken as they complete.

    A worker that goes ``START_LIMIT`` s (120) without the word due from it, after its start or after a cell was sent
    to it, and without dying (its start-up or its reading of the cell hangs), is stopped and replaced, and the cell is
    a failed row saying so (not retried): the run never waits on a silent worker for ever.

    Parameters
    ----------
    workers : int
        Number of worker processes.
    fn : callable
        What a worker runs for a cell (default: :func:`run_cell`).
    time_limit : float, optional
        Seconds a cell may run (from its start in the worker): past them its worker is stopped (SIGTERM,
        then SIGKILL) and the cell is a failed row saying so (not retried). None: no limit.
    threads : int, optional
        Threads each worker may use; default: the machine's cores shared among the workers.
    process : str, optional
        What its failed rows call a worker process (default ``"worker"``; a Dask worker's child under a cell
        time limit is ``"child process"``: the Dask worker itself is not stopped).
    """

    def __init__(self, workers: int, fn: CellFn = run_cell, time_limit: float | None = None,
                 threads: int | None = None, process: str = "worker"):
        self.process = process
        self.workers = int(workers)
        self.threads = threads or worker_threads(self.workers)
        self.fn = fn
        self.time_limit = time_limit
        self.name = f"{self.workers} local processes ({self.threads} thread(s) each)"
        self._ctx = mp.get_context("spawn")
        self._kept: list[_Slot] | None = None  # in a session: the idle workers of the last run

    @contextmanager
    def session(self):
        """The workers a run started are kept for the next run (those still alive), and stopped at the end."""
        self._kept = []
        try:
            yield self
        finally:
            kept, self._kept = self._kept, None
            for s in kept:
                self._stop(s, graceful=s.proc.is_alive())

    def _reused(self) -> list[_Slot]:
        """The live workers kept from the session's last run (none outside a session); dead ones stopped."""
        kept, self._kept = self._kept, ([] if self._kept is not None else None)
        live = []
        for s in kept or ():
            if s.proc.is_alive():
                live.append(s)
            else:
                self._stop(s, graceful=False)
        return live

    @property
    def _process_text(self) -> str:
        """The process its failed rows name: "worker process", or "child process on its Dask worker"."""
        return "worker process" if self.process == "worker" else f"{self.process} on its Dask worker"

    def _start(self) -> _Slot:
        parent, child = self._ctx.Pipe()
        proc = self._ctx.Process(target=_worker_main, args=(child, self.fn), daemon=True,
                                 name="graybox-grid-worker")
        # one start at a time: two threads each setting and restoring the variables gave one child the other's
        # restored value, and left the first's in the process's environment
        if not _START_LOCK.acquire(timeout=START_LIMIT):
            parent.close()
            child.close()
            raise RuntimeError(f"could not start a new {self.process}: another thread of this process has held "
                               f"graybox's process-start lock (_START_LOCK) for {START_LIMIT:g} s (its start hung)")
        try:
            with _environ(_thread_env(self.threads)), _sigint_ignored(), _children_allowed():
                proc.start()
        finally:
            _START_LOCK.release()
        child.close()
        return _Slot(proc, parent)

    @staticmethod
    def _stop(slot: _Slot, graceful: bool) -> None:
        try:
            if graceful:
                slot.conn.send(None)
        except (BrokenPipeError, OSError):
            pass
        slot.proc.join(timeout=5 if graceful else 2)  # not graceful: dead, or sent SIGTERM (run's clean-up)
        if slot.proc.is_alive():
            slot.proc.kill()
            slot.proc.join(timeout=5)
        slot.conn.close()

    @staticmethod
    def _send(slot: _Slot, cell: Cell, datasets: Mapping[str, gb.Dataset]) -> bool:
        """Send ``cell`` (and its data set, the first time) to the slot's worker; False if its worker is gone."""
        h = cell.data_hash
        try:
            slot.conn.send((cell, None if h in slot.sent else datasets[h]))
        except OSError:  # BrokenPipeError, ConnectionResetError: the worker's end of the pipe is closed
            return False
        slot.sent.add(h)
        return True

    def _wait(self, busy: Sequence[_Slot]) -> float | None:
        """How long to wait for a word at most (seconds): until the first deadline of a busy worker (a word due
        within ``START_LIMIT``, a started cell's time limit), and an hour at most (the loop waits again): a wait of
        more than 2^31 ms is an OverflowError in poll()."""
        due = [s.since + START_LIMIT for s in busy if s.started is None]
        if self.time_limit is not None:
            due += [s.started + self.time_limit for s in busy if s.started is not None]
        if not due:
            return None
        return min(3600.0, max(0.0, min(due) - time.monotonic()))

    def _overdue(self, slot: _Slot) -> bool:
        """Whether the slot's cell has run past the time limit without a row come back (a row sent just in time
        is not lost: it is read on the next wait)."""
        return (self.time_limit is not None and slot.started is not None
                and time.monotonic() - slot.started >= self.time_limit and not slot.conn.poll())

    @staticmethod
    def _silent(slot: _Slot) -> bool:
        """Whether the slot's worker, given a cell, has gone ``START_LIMIT`` s without the word due from it (READY
        after its start, STARTED after the cell's send) and without dying: its start-up, or its reading of the cell,
        hangs (a word sent just in time is read on the next wait)."""
        return (slot.cell is not None and slot.started is None and time.monotonic() - slot.since >= START_LIMIT
                and not slot.conn.poll())

    def run(self, cells: Sequence[Cell], datasets: Mapping[str, gb.Dataset], log: Log | None = None,
            take: Take | None = None) -> Iterator[dict]:
        """Yield each cell's row as it completes; a cell is taken (``take``) when a worker is free for it."""
        pending: deque[Cell] = deque(cells)  # not taken yet
        # taken, each with the worker deaths it has seen: no worker to start when none is (every cell reused, or
        # another run's), each costs a Python start-up and graybox's imports
        queued: deque[tuple[Cell, int]] = deque((c, 0) for c in _take_next(pending, self.workers, take))
        if not queued:
            return
        slots: list[_Slot] = []
        graceful = True
        try:
            slots = self._reused()
            slots += [self._start() for _ in range(len(queued) - len(slots))]
            while True:
                free = [s for s in slots if s.cell is None]
                if len(queued) < len(free):
                    queued.extend((c, 0) for c in _take_next(pending, len(free) - len(queued), take))
                for s in free:
                    if not queued:
                        break
                    cell, attempt = queued.popleft()
                    if s.ready and not self._send(s, cell, datasets):
                        # the worker died idle (killed between two cells, its row being written): no death of this
                        # cell's, which goes to a worker started in its place
                        i = slots.index(s)
                        self._stop(s, graceful=False)
                        slots[i] = s = self._start()
                    # a worker not ready yet (just started) is sent its cell once it says READY
                    s.cell, s.attempt, s.started = cell, attempt, None
                    if s.ready:
                        s.since = time.monotonic()
                busy = [s for s in slots if s.cell is not None]
                if not busy:  # nothing in flight, none taken, none left to take
                    break
                ready = set(mp_wait([s.conn for s in busy] + [s.proc.sentinel for s in busy], self._wait(busy)))
                for i, s in enumerate(slots):
                    if s.cell is None or not ({s.conn, s.proc.sentinel} & ready):
                        continue
                    row = None
                    try:
                        if s.conn.poll():
                            row = s.conn.recv()
                    except (EOFError, OSError):
                        row = None
                    if isinstance(row, str) and row == STARTED:
                        s.started = time.monotonic()
                        continue
                    if isinstance(row, str) and row == READY:
                        s.ready, s.since = True, time.monotonic()
                        # a send that fails (it died just now) is seen on the next wait, as a death while running
                        # the cell: retried once, so a worker that dies at every start cannot loop for ever
                        self._send(s, s.cell, datasets)
                        continue
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
                        queued.appendleft((cell, attempt))  # still this run's: it goes next
                    else:
                        yield failed_row(cell, f"the {self._process_text} died twice while running this cell "
                                               f"(last exit code {code}); it was retried once")
                for i, s in enumerate(slots):  # no word where one is due: stopped, its cell not retried
                    if not self._silent(s):
                        continue
                    cell, what = s.cell, ("start up" if not s.ready else "take the cell it was sent")
                    s.proc.terminate()
                    self._stop(s, graceful=False)
                    slots[i] = self._start()
                    yield failed_row(cell, f"its {self._process_text} did not {what} within {START_LIMIT:g} s (it "
                                           "was stopped and replaced): run it again with retry_failed (graybox grid "
                                           "run --retry-failed)")
                for i, s in enumerate(slots):  # past the time limit and still without a row: stopped, not retried
                    if s.cell is None or not self._overdue(s):
                        continue
                    cell = s.cell
                    s.proc.terminate()  # a clean exit if it returns to Python within _stop's wait, else SIGKILL
                    self._stop(s, graceful=False)
                    slots[i] = self._start()
                    # on Dask the pool is a worker's child: only that child was stopped, the Dask worker runs on
                    rest = "" if self.process == "worker" else "; the Dask worker itself runs on"
                    yield failed_row(cell, f"stopped after the cell time limit of {self.time_limit:g} s (its "
                                           f"{self._process_text} was stopped and replaced{rest}); run it again "
                                           "with a larger cell_time_limit and retry_failed (graybox grid run "
                                           "--cell-time-limit S --retry-failed)")
        except BaseException:  # interrupted (Ctrl-C, the caller stopped): the cells in flight are not waited for
            graceful = False
            raise
        finally:
            if not graceful:  # all at once: each takes a moment to exit cleanly
                for s in slots:
                    if s.proc.is_alive():
                        s.proc.terminate()
            for s in slots:
                if graceful and self._kept is not None and s.cell is None and s.proc.is_alive():
                    self._kept.append(s)  # idle and alive: the session's next run uses it
                else:
                    self._stop(s, graceful=graceful and s.proc.is_alive())


def _size(cell: Cell) -> int:
    """Terms of a cell's structure as its spec gives them (1 when a rule other than a count decides)."""
    spec = cell.structure_spec
    if spec.get("terms") is not None:
        return max(1, len(spec["terms"]))
    return max(1, int(spec.get("n_terms") or 1))


class _Batches:
    """The cells of the Dask tasks: which go together, and in which order.

    A cell's time is estimated from its (data, variant) group's finished cells as a + b × its
    structure's terms (least squares, a, b ≥ 0; proportional to the terms while one size has
    been seen): a variant's estimator sets most of a cell's time, the structure's size most of
    the rest, and the evaluation every cell ends with costs the same at any size. One cell of each
    group runs first (these probes are spread over the first tasks), so that every group's time
    is known early; a group whose probe has not come back yet sends its cells one per task (one
    whose probe came back without a time, e.g. infeasible, is costed at the mean rate). Then
    the cells go longest first, so the cheapest come last, in batches of about ``BATCH_SECONDS``
    of estimated work that shrink towards the end to one in-flight task's share of the work left
    (less what the workers will do while the new task waits behind the one in flight, see
    ``QUEUE_SHARE``), but not below ``MIN_BATCH_SECONDS`` (guided self-scheduling), so the
    workers finish nearly together. The executor says when a task came back (:meth:`returned`).
    A cell retried after its worker died goes alone, before the others.
    """

    def __init__(self, cells: Sequence[Cell], slots: int):
        self.slots = max(1, int(slots))
        self.retry: deque[tuple[Cell, int]] = deque()
        self.probes: deque[Cell] = deque()
        self.groups: dict[tuple[str, str], deque[Cell]] = {}
        for c in cells:
            g = (c.data, c.variant)
            if g in self.groups:
                self.groups[g].append(c)
            else:
                self.groups[g] = deque()
                self.probes.append(c)
        for g, q in self.groups.items():  # larger structures first: each group's head is its longest cell
            self.groups[g] = deque(sorted(q, key=lambda c: -_size(c)))
        self._left = {g: [len(q), sum(_size(c) for c in q)] for g, q in self.groups.items()}  # cells, terms queued
        self._fit: dict[tuple[str, str], list[float]] = {}  # group -> [n, Σ terms, Σ s, Σ terms², Σ terms × s]
        self._flight: dict[str, float] = {}  # first cell's key -> estimated seconds of a task in flight
        self._back: set[tuple[str, str]] = set()  # groups with a cell come back, timed or not
        self._probe_k = -(-len(self.probes) // self.slots)

    def __len__(self) -> int:
        return len(self.retry) + len(self.probes) + sum(len(q) for q in self.groups.values())

    def observe(self, cell: Cell, seconds: Any) -> None:
        """Record a finished cell's wall time (seconds; anything but a finite number ≥ 0 is ignored)."""
        try:
            seconds = float(seconds)
        except (TypeError, ValueError):
            return
        if np.isfinite(seconds) and seconds >= 0:
            k = _size(cell)
            f = self._fit.setdefault((cell.data, cell.variant), [0, 0.0, 0.0, 0.0, 0.0])
            f[0] += 1
            f[1] += k
            f[2] += seconds
            f[3] += k * k
            f[4] += k * seconds

    def model(self, group: tuple[str, str]) -> tuple[float, float] | None:
        """(a, b) of the group's time a + b × terms (seconds), or None before its first finished cell."""
        f = self._fit.get(group)
        if not f:
            return None
        n, sk, st, skk, sks = f
        var = skk - sk * sk / n
        if n > 1 and var > 1e-9 * skk:
            b = (sks - sk * st / n) / var
            a = (st - b * sk) / n
            if b < 0:
                return st / n, 0.0
            if a >= 0:
                return a, b
        return 0.0, st / sk

    def returned(self, items: Sequence[tuple[Cell, int]]) -> None:
        """A task given by :meth:`next` came back (finished or not): it is no longer in flight."""
        if items:
            self._flight.pop(items[0][0].key, None)
        self._back.update((c.data, c.variant) for c, _ in items)

    def dropped(self, items: Sequence[tuple[Cell, int]], kept: Sequence[tuple[Cell, int]]) -> None:
        """Of a task given by :meth:`next`, only ``kept`` goes (another run on the store holds or has written the
        others): the task in flight, if any goes, is that much shorter."""
        work = self._flight.pop(items[0][0].key, None) if items else None
        if work is not None and kept:
            self._flight[kept[0][0].key] = work * len(kept) / len(items)

    def requeue(self, cell: Cell, deaths: int) -> None:
        """Put back a cell whose worker died (it runs alone, next)."""
        self.retry.appendleft((cell, deaths))

    def _take(self, g: tuple[str, str]) -> Cell:
        c = self.groups[g].popleft()
        self._left[g][0] -= 1
        self._left[g][1] -= _size(c)
        return c

    def next(self) -> list[tuple[Cell, int]]:
        """The next task's cells, each with the number of worker deaths it has seen."""
        if self.retry:
            return [self.retry.popleft()]
        if self.probes:  # spread over the first tasks, one for each in-flight slot
            return [(self.probes.popleft(), 0) for _ in range(min(self._probe_k, len(self.probes)))]
        fits = list(self._fit.values())
        default = sum(f[2] for f in fits) / sum(f[1] for f in fits) if fits else BATCH_SECONDS  # s per term
        models = {g: self.model(g) for g, q in self.groups.items() if q}
        for g, m in models.items():  # its probe came back untimed (failed, infeasible): the default
            if m is None and g in self._back:
                models[g] = (0.0, default)
        known = {g: m for g, m in models.items() if m is not None}
        if not known:  # only groups whose probe is still out: one cell, lest a long group fill a batch
            return [(self._take(next(iter(models))), 0)]
        left = sum(a * self._left[g][0] + b * self._left[g][1] for g, (a, b) in known.items())
        left += default * sum(self._left[g][1] for g in models if g not in known)
        if self._flight:
            threads = max(1, self.slots // IN_FLIGHT)
            left -= QUEUE_SHARE * threads * sum(self._flight.values()) / len(self._flight)
        target = min(BATCH_SECONDS, max(left / (GUIDE * self.slots), MIN_BATCH_SECONDS))
        out: list[tuple[Cell, int]] = []
        work = 0.0
        def head(g: tuple[str, str]) -> float:  # the estimated time of a group's longest cell left
            a, b = known[g]
            return a + b * _size(self.groups[g][0])

        while known and len(out) < MAX_BATCH:
            g = max(known, key=head)
            t = head(g)
            if out and work + t > target:
                break
            out.append((self._take(g), 0))
            work += t
            if not self.groups[g]:
                del known[g]
        self._flight[out[0][0].key] = work
        return out


def _next_taken(batches: _Batches, take: Take | None) -> list[tuple[Cell, int]]:
    """The next task's cells (:meth:`_Batches.next`) that ``take`` gives (a retried cell, worker deaths > 0, is
    this run's already); ``[]`` when no batch is left."""
    while batches:
        items = batches.next()
        if take is not None:
            given = {c.key for c in take([c for c, d in items if d == 0])}
            kept = [(c, d) for c, d in items if d > 0 or c.key in given]
            if len(kept) < len(items):
                batches.dropped(items, kept)
                items = kept
        if items:
            return items
    return []


# --------------------------------------------------------------------------------------------
# Dask distributed
# --------------------------------------------------------------------------------------------
#: The LocalCluster's housekeeping, made rarer: on a machine with as many cores as workers, the
#: scheduler and the nannies (in the driver process) and each worker's own threads take their CPU
#: from the cells. The workers' statistical profiler (a stack sample every 10 ms) is off.
_QUIET = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.admin.tick.interval": "200ms",
}


@contextmanager
def local_cluster(workers: int, dashboard: bool = False):
    """The Dask ``LocalCluster`` graybox starts for ``workers`` processes (closed on exit).

    One thread per worker, ``NUMBA_NUM_THREADS`` = cores // workers; the scheduler reports a
    task whose worker died at once (``allowed-failures`` 0): the driver decides what to retry.
    The workers start without the ``MALLOC_TRIM_THRESHOLD_`` that Dask's nanny sets by default:
    setting it switches off glibc's adaptive mmap threshold, so every array of more than 64 KiB
    is mapped and unmapped afresh, which made graybox's cells about 1.5–2 times slower on a
    worker than in the driver (BENCHMARKS.md, grids).

    The workers' scratch folders live in a temporary folder of the cluster's own, removed on exit (and,
    if the driver was killed before it could, by the next cluster started on the machine).
    The workers ignore SIGINT, as the local pool's do: Ctrl-C is the driver's to handle.
    Each worker cancels its heartbeat in flight when it closes (:mod:`._dask_worker`), so that the
    end of a run, or Ctrl-C, prints no heartbeat traceback from a worker.

    ``dashboard``: serve Dask's dashboard on a free port when bokeh is installed (off by default:
    it costs start-up time and a port).
    """
    import dask
    from distributed import LocalCluster

    environ = {k: v for k, v in dask.config.get("distributed.nanny.pre-spawn-environ", {}).items()
               if k != "MALLOC_TRIM_THRESHOLD_"}
    # a nanny started earlier in this process (another cluster) leaves the variable in os.environ,
    # whence every worker spawned later (a restarted one too) would inherit it: off while we run
    inherited = os.environ.pop("MALLOC_TRIM_THRESHOLD_", None)
    # the workers' scratch folders in a folder of our own, removed on exit: Dask's default
    # ("dask-scratch-space" in the temporary folder) outlives the cluster
    scratch, owner = _scratch_folder()
    # each worker cancels its heartbeat in flight when it closes, before it closes its connections:
    # else that heartbeat failed and logged an ERROR with a traceback (see _dask_worker)
    preload = dask.config.get("distributed.worker.preload", None) or []
    preload = [preload] if isinstance(preload, str) else list(preload)
    preload.append(_dask_worker.__name__)
    try:
        with dask.config.set({"distributed.scheduler.allowed-failures": 0, "temporary-directory": scratch,
                              "distributed.nanny.pre-spawn-environ": environ, "distributed.worker.preload": preload,
                              **_QUIET}), _sigint_ignored():
            # ":0": any free port; None still binds 8787 and warns when another cluster holds it
            cluster = LocalCluster(n_workers=int(workers), threads_per_worker=1, processes=True,
                                   # ":0": a free port; None would still bind 8787, taken by any other cluster
                                   dashboard_address=":0",
                                   silence_logs=logging.ERROR,
                                   env=_thread_env(worker_threads(int(workers))))
        try:
            yield cluster
        finally:
            cluster.close()
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
        os.close(owner)
        if inherited is not None:
            os.environ["MALLOC_TRIM_THRESHOLD_"] = inherited


#: The prefix of a LocalCluster's scratch folder in the temporary folder (:func:`_scratch_folder`).
SCRATCH_PREFIX = "graybox-dask-"
#: The lock a live driver holds in its scratch folder (released by the kernel however it ends).
SCRATCH_OWNER = ".owner"


def _scratch_folder() -> tuple[str, int]:
    """A new scratch folder for a ``LocalCluster``'s workers and the descriptor of the lock held on it.

    A driver SIGKILLed (or crashed) never reaches its ``rmtree``: the next one removes the folders
    whose lock no live process holds (:func:`_sweep_scratch`). The lock file is locked under another
    name and then renamed into place, so a sweeper never sees an owner file that is not yet held.
    """
    _sweep_scratch(tempfile.gettempdir())
    path = tempfile.mkdtemp(prefix=SCRATCH_PREFIX)
    fd = os.open(os.path.join(path, ".owner-new"), os.O_RDWR | os.O_CREAT, 0o600)
    # a new file: nobody else can hold it; without locks the folder is still removed on a normal exit
    if lock_fd(fd, 0.0):
        with suppress(OSError):
            os.rename(os.path.join(path, ".owner-new"), os.path.join(path, SCRATCH_OWNER))
    return path, fd


def _sweep_scratch(base: str) -> list[str]:
    """Remove the scratch folders in ``base`` left by drivers that are gone; return their paths.

    A folder is left only by its owner's death: its owner file exists and can be locked. Folders
    without one (an owner between ``mkdtemp`` and its rename, or a file system without locks), and
    anything the sweep cannot read or lock, are left alone.
    """
    removed: list[str] = []
    try:
        entries = [e for e in os.scandir(base) if e.name.startswith(SCRATCH_PREFIX) and e.is_dir(follow_symlinks=False)]
    except OSError:
        return removed
    for e in entries:
        try:
            fd = os.open(os.path.join(e.path, SCRATCH_OWNER), os.O_RDWR)
        except OSError:  # no owner file (not ours, or not yet), or not ours to open
            continue
        if not lock_fd(fd, 0.0):  # held: its driver is alive (or no locks here: nothing can be told)
            os.close(fd)
            continue
        try:
            shutil.rmtree(e.path, ignore_errors=True)
            removed.append(e.path)
        finally:
            os.close(fd)
    return removed


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
    worker_timeout : float or None
        Seconds a run goes on once the cluster has no worker left (all of them gone, none restarted): then it
        ends with a ``ConnectionError``, the rows it finished kept (the store's run resumes them). A cluster
        that has had no worker yet in the run (an adaptive one whose first workers wait in a batch queue) is
        waited for. ``None`` waits for ever.
    time_limit : float, optional
        Seconds a cell may run: each task then runs its cells in a child process of its worker (one per worker
        thread, kept for the run's next tasks and closed at its end or after ``KEPT_IDLE`` = 30 s idle), one
        after another, and a cell past the limit has that process stopped (and replaced) and is a failed row
        saying so (not retried), as :class:`ProcessPool` does (a second or two more per worker thread: the
        child's start-up).
        None: no limit; cells run in the worker itself, or, on a worker of several threads, in a child process of
        each of its threads as under a limit (a process's warning filters and BLAS thread limits are its own, not a
        thread's: cells side by side in one process took each other's warnings).
    """

    def __init__(self, client: Any = None, scheduler: str | None = None, workers: int | None = None,
                 fn: CellFn = run_cell, worker_timeout: float | None = WORKER_TIMEOUT,
                 time_limit: float | None = None):
        given = [k for k, v in (("client", client), ("scheduler", scheduler), ("workers", workers)) if v is not None]
        if len(given) != 1:
            raise ValueError(f"the Dask executor needs exactly one of client, scheduler or workers; got {given or 'none'}")
        self.client, self.scheduler, self.workers, self.fn = client, scheduler, workers, fn
        self.worker_timeout = (None if worker_timeout is None else
                               check_real(worker_timeout, "worker_timeout", low=0, low_open=True))
        self.time_limit = (None if time_limit is None else
                           check_real(time_limit, "cell_time_limit", low=0, low_open=True))
        if workers is not None:
            self.workers = int(workers)
            self.name = f"Dask LocalCluster of {self.workers} worker processes"
        elif scheduler is not None:
            self.name = f"Dask scheduler at {scheduler}"
        else:
            self.name = "Dask client"
        self._stack: ExitStack | None = None  # in a session: what closes the kept client (and its cluster)
        self._kept: Any = None

    @contextmanager
    def session(self):
        """The client a run opened (and the ``LocalCluster`` it started) is kept for the next run while it is
        running, and closed at the end."""
        self._stack = ExitStack()
        try:
            yield self
        finally:
            stack, self._stack, self._kept = self._stack, None, None
            stack.close()

    @contextmanager
    def _using(self, dashboard: bool = False):
        """(client, whether it is new): the session's kept client while it runs, else one opened now (kept
        when in a session, closed on exit when not)."""
        if self._stack is None:
            with self._client(dashboard) as client:
                yield client, True
            return
        new = self._kept is None or getattr(self._kept, "status", None) != "running"
        if new:  # a dead one is closed with the session
            self._kept = self._stack.enter_context(self._client(dashboard))
        yield self._kept, new

    @contextmanager
    def _client(self, dashboard: bool = False):
        from distributed import Client

        if self.client is not None:
            if not isinstance(self.client, Client):
                raise ValueError(f"client must be a distributed.Client, got {type(self.client).__name__}")
            yield self.client
            return
        if self.scheduler is not None:
            with scheduler_client(self.scheduler) as client:
                yield client
            return
        with local_cluster(self.workers, dashboard) as cluster:
            client = Client(cluster)
            try:
                yield client
            finally:
                client.close()

    def run(self, cells: Sequence[Cell], datasets: Mapping[str, gb.Dataset], log: Log | None = None,
            take: Take | None = None) -> Iterator[dict]:
        """Submit the cells in batches, yield each row as its batch completes; a batch's cells are taken
        (``take``) as it is submitted, and graybox's ``LocalCluster`` starts only once the first batch is taken
        (while another run holds every cell left, none starts)."""
        from distributed import as_completed
        from distributed.scheduler import KilledWorker

        from ._dask import GridData, cells_task

        if not cells:
            return
        first: list = []  # the first task's cells, taken before a LocalCluster is started for them
        batches = None
        if self.workers is not None:  # its slots known before it starts: none started while every cell left is
            batches = _Batches(cells, IN_FLIGHT * self.workers)  # another run's (this one then only waits)
            first = _next_taken(batches, take)
            if not first:
                return
        with self._using(dashboard=log is not None) as (client, new):
            started_with = _worker_count(client)  # asked first: its workers may go while the data are sent
            if log is not None and new:
                link = getattr(client, "dashboard_link", None) if _has_dashboard(client) else None
                log(f"Dask dashboard: {link}" if link else
                    "Dask dashboard: none (it needs the bokeh package: pip install bokeh); "
                    "graybox grid status STORE shows the progress")
            plugin = f"graybox-grid-data-{uuid.uuid4().hex[:8]}"
            client.register_plugin(GridData({h: datasets[h] for h in {c.data_hash for c in cells}}), name=plugin)
            tag = uuid.uuid4().hex[:8]
            runner = partial(_cells_on_a_worker, self.fn, self.time_limit)
            futures: dict = {}
            counter = itertools.count()
            if batches is None:
                batches = _Batches(cells, IN_FLIGHT * max(1, sum(client.nthreads().values())))
            asked = [time.monotonic()]

            def submit() -> None:
                if watch.lost:
                    return
                if batches.retry or any(d for items in futures.values() for _, d in items):
                    # while cells whose worker died are retried, at most one task per live worker
                    # process: a task beside or behind the one that kills its worker would be
                    # charged with that death too
                    limit = max(1, len(client.nthreads()))
                else:
                    if time.monotonic() - asked[0] > 1.0:  # workers may come and go (at most one question a second)
                        batches.slots = IN_FLIGHT * max(1, sum(client.nthreads().values()))
                        asked[0] = time.monotonic()
                    limit = batches.slots
                while len(futures) < limit:
                    items = first.copy() if first else _next_taken(batches, take)
                    first.clear()
                    if not items:
                        break
                    seq = next(counter)  # a retried cell gets a new key: the old one may still be known as erred
                    f = client.submit(cells_task, self.fn, plugin, [c for c, _ in items], runner,
                                      key=f"graybox-cells-{items[0][0].key[:16]}-{seq}-{tag}", pure=False)
                    futures[f] = items
                    pending.add(f)

            # results are gathered in the background as tasks finish (no round trip per task here)
            pending = as_completed([], with_results=True, raise_errors=False)
            watch = _WorkerWatch(client, self.worker_timeout, pending, seen=started_with > 0)
            try:
                submit()  # in the try: a first submission that raises closes the watch too
                for f, result in pending:
                    items = futures.pop(f)
                    batches.returned(items)
                    rows: list[dict] = []
                    if f.status == "finished":
                        rows = list(result.rows)
                        for (c, _), r in zip(items, rows):
                            if r.get("status") in ("ok", "diverged"):  # a cell that fails at once says little
                                batches.observe(c, r.get("wall_time"))
                    else:
                        exc = result[1] if isinstance(result, tuple) and len(result) > 1 else result
                        if not isinstance(exc, BaseException):
                            exc = RuntimeError(f"the task ended as {f.status!r}")
                        if getattr(exc, "reason", None) == "scheduler-connection-lost":
                            # the client cancels every future once its scheduler is gone: the cluster was lost, the
                            # cells were not run (failed rows would keep them out of the next run); said below
                            raise ConnectionError(str(exc)) from exc
                        if isinstance(exc, KilledWorker):
                            # every cell of the batch goes back alone (the one that kills its worker
                            # is then found out); a second death makes a cell a failed row
                            for c, deaths in reversed(items):
                                if deaths + 1 >= 2:
                                    rows.append(failed_row(c, "the worker died twice while running this cell; "
                                                              f"it was retried once ({type(exc).__name__}: {exc})"))
                                else:
                                    batches.requeue(c, deaths + 1)
                        else:
                            rows = [failed_row(c, f"{type(exc).__name__}: {exc}") for c, _ in items]
                    f.release()
                    submit()
                    yield from rows
                if watch.lost:
                    raise ConnectionError(
                        f"the {self.name} has had no worker for {watch.limit:g} s (all gone, none restarted): "
                        f"{len(futures)} task(s) in flight and the cells not yet started were not run; the rows "
                        "finished are kept: run the grid again once the cluster has workers")
            except OSError as exc:
                if watch.lost:  # (said above)
                    raise
                # the client's own errors once its scheduler is gone (CommClosedError, a connect that times out)
                raise ConnectionError(f"lost the {self.name} ({type(exc).__name__}: {exc}); the rows finished are "
                                      "kept: run the grid again once it answers") from exc
            finally:
                watch.close()
                for f in futures:
                    f.cancel()
                try:
                    client.unregister_worker_plugin(plugin)
                except Exception:  # the cluster may be going away; the plugin goes with it
                    pass


#: Seconds a Dask worker's kept child (:class:`_KeptPool`) may wait idle for its run's next task before it is
#: closed: a driver that died without ending its run (SIGKILL, a lost connection) never unregisters the run's
#: plugin, whose teardown closes the children; a task of the run after that starts a child again.
KEPT_IDLE = 30.0


class _KeptPool:
    """A one-process :class:`ProcessPool` in a session, kept on a Dask worker for the run's next task (its child
    and the data sets it was sent reused: starting one per task cost 2 s a task); closed at the run's end, or
    once idle for ``KEPT_IDLE`` s (a run whose driver died never ends on the worker)."""

    def __init__(self, fn: CellFn, time_limit: float | None):
        self.pool = ProcessPool(1, fn, time_limit=time_limit, threads=1, process="child process")
        self._stack = ExitStack()
        self._stack.enter_context(self.pool.session())
        self._lock = threading.Lock()
        self._busy = False
        self._used = time.monotonic()
        self.closed = False
        self._shut = False
        self._done = threading.Event()
        threading.Thread(target=self._close_when_idle, daemon=True, name="graybox kept child's idle watch").start()

    def run(self, cells: Sequence[Cell], datasets: Mapping[str, gb.Dataset]) -> list[dict] | None:
        """The cells' rows, or None if the pool was closed meanwhile (idle too long, or the run's end)."""
        with self._lock:
            if self.closed:
                return None
            self._busy = True
        try:
            return list(self.pool.run(cells, datasets))
        finally:
            with self._lock:
                self._busy = False
                self._used = time.monotonic()

    def _close_when_idle(self) -> None:
        while not self._done.wait(min(1.0, KEPT_IDLE)):
            with self._lock:
                idle = not self._busy and time.monotonic() - self._used >= KEPT_IDLE
                if idle:
                    self.closed = True
            if idle:
                self.close()

    def close(self) -> None:
        with self._lock:  # once (the run's end and the idle watch may both come)
            first, self._shut = not self._shut, True
            self.closed = True
        self._done.set()
        if first:
            self._stack.close()


def _cells_on_a_worker(fn: CellFn, time_limit: float | None, cells: Sequence[Cell],
                       datasets: Mapping[str, gb.Dataset], kept: dict) -> list[dict]:
    """A Dask task's ``cells``, their rows in order: in the worker itself when it runs one thread and they have no
    time limit, else in a child process of the worker thread (:func:`_cells_in_a_child`). A process's warning
    filters and BLAS thread limits are the process's, not a thread's: two cells side by side in one worker undid
    each other's ``catch_warnings`` and thread limits (a row lost its own warnings, or held another cell's, or one
    se_pareto silences)."""
    from distributed import get_worker

    worker = get_worker()
    threads = getattr(getattr(worker, "state", worker), "nthreads", 1)
    if time_limit is None and threads == 1:
        return [fn(c, datasets[c.data_hash], threads=1) for c in cells]
    return _cells_in_a_child(fn, time_limit, cells, datasets, kept)


def _cells_in_a_child(fn: CellFn, time_limit: float | None, cells: Sequence[Cell],
                      datasets: Mapping[str, gb.Dataset], kept: dict) -> list[dict]:
    """On a Dask worker: ``cells`` one after another in a child process, each stopped past ``time_limit`` s
    (a failed row saying so; None: no limit); their rows in the cells' order. The child is kept in ``kept`` (the
    run's, on this worker) for the next task of the same worker thread."""
    key = ("cells in a child", threading.get_ident())
    got = None
    while got is None:
        pool = kept.get(key)
        if pool is None or pool.closed:  # the first task of this thread, or its child was closed when idle
            pool = kept[key] = _KeptPool(fn, time_limit)
        got = pool.run(cells, datasets)
    rows = {r["key"]: r for r in got}
    return [rows[c.key] for c in cells]


def _worker_count(client: Any) -> int:
    """The workers of ``client``'s cluster (0 when its scheduler cannot be asked: it runs nothing either)."""
    try:
        return len(client.nthreads())
    except Exception:
        return 0


class _WorkerWatch:
    """Ends a Dask run whose cluster has had no worker for ``limit`` seconds, once it has had one in the run (a
    cluster still starting its first, from a batch queue say, is waited for): a thread asks the scheduler
    once a second, and then sets :attr:`lost` and has ``pending`` (the ``as_completed`` the run waits on) forget its
    tasks in flight, so that it stops once the rows it holds are taken; it keeps doing so until :meth:`close` (a
    task added meanwhile is not waited for)."""

    def __init__(self, client: Any, limit: float | None, pending: Any, seen: bool = False):
        self.client, self.limit, self.pending = client, limit, pending
        self.lost = False
        self.seen = seen  # whether the run's cluster has had a worker (else it is waited for: none *left* yet)
        self._stop = threading.Event()
        self._thread = None
        if limit is not None:
            self._thread = threading.Thread(target=self._watch, name="graybox Dask worker watch", daemon=True)
            self._thread.start()

    def _watch(self) -> None:
        since = None
        while not self._stop.wait(min(1.0, max(0.05, self.limit / 4))):  # at most 20 questions a second
            if self.lost:
                self._forget()
            elif _worker_count(self.client):
                since, self.seen = None, True
            elif not self.seen:  # a cluster with no worker yet (an adaptive one starting them): waited for
                continue
            elif since is None:
                since = time.monotonic()
            elif time.monotonic() - since >= self.limit:
                self.lost = True
                self._forget()

    def _forget(self) -> None:
        """Stop waiting for the tasks in flight: ``pending`` forgets them and, once the rows it holds are taken,
        stops. Its queue of finished ones is left to the run's thread (``as_completed.clear()`` empties it, and a
        run then between looking at it and taking from it would wait for ever on it emptied)."""
        with self.pending.lock:
            self.pending.futures.clear()

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()


@contextmanager
def scheduler_client(scheduler: str):
    """A ``distributed.Client`` of the Dask scheduler at ``scheduler`` with a worker to run on (closed on
    exit); a ``ConnectionError`` naming the address when it cannot be reached, or when no worker joins it
    within ``WORKER_TIMEOUT`` seconds (jobs sent to a scheduler without workers wait for ever)."""
    from distributed import Client

    try:
        client = Client(scheduler, timeout=CONNECT_TIMEOUT)
    except OSError as exc:
        raise ConnectionError(f"cannot reach the Dask scheduler at {scheduler} ({exc}); is it running, "
                              "and is the address right?") from None
    except (TypeError, ValueError) as exc:  # e.g. tls:// without the cluster's security settings in Dask's config
        raise ValueError(f"cannot connect to the Dask scheduler at {scheduler} ({exc}); a cluster that needs "
                         "security settings (TLS) is reached through a distributed.Client made with them: pass "
                         "client= in Python") from None
    try:
        try:
            client.wait_for_workers(1, timeout=WORKER_TIMEOUT)
        except (TimeoutError, OSError):
            raise ConnectionError(f"the Dask scheduler at {scheduler} has no worker (none joined in "
                                  f"{WORKER_TIMEOUT} s): start some (dask worker {scheduler}), or check the "
                                  "address") from None
        yield client
    finally:
        client.close()


def check_cluster(client: Any, scheduler: Any) -> None:
    """``client`` and ``scheduler`` checked before anything runs or is written: a wrong one would
    otherwise fail only when the first job reaches the cluster, or never when no job is left."""
    if client is not None:
        from distributed import Client

        if not isinstance(client, Client):
            raise TypeError(f"client must be a distributed.Client, got {client!r} ({type(client).__name__})")
    if scheduler is not None:
        if not isinstance(scheduler, str):
            raise TypeError(f"scheduler must be an address string such as 'tcp://host:8786', got {scheduler!r}")
        if ":" not in scheduler:
            raise ValueError(f"scheduler must be an address such as 'tcp://host:8786', got {scheduler!r}")
        _check_address(scheduler)


def _check_address(scheduler: str) -> None:
    """``ValueError`` naming ``scheduler`` when it is no address a Dask client can connect to (parsed as
    distributed parses it, without connecting): its own message named neither the option nor the form
    ('invalid literal for int() with base 10: ...'), and only once the store had been written."""
    from distributed.comm import get_address_host_port, parse_address
    from distributed.comm.registry import get_backend

    form = "an address such as 'tcp://host:8786'"
    scheme = scheduler.split("://", 1)[0].lower() if "://" in scheduler else ""
    if scheme in ("http", "https"):  # the dashboard's URL, which the scheduler prints too
        raise ValueError(f"scheduler {scheduler!r} is a web address, such as the Dask dashboard's (port 8787): the "
                         f"scheduler itself listens at {form} (port 8786 by default)")
    try:
        kind, _ = parse_address(scheduler)
        get_backend(kind)  # a scheme distributed does not know: ValueError naming the known ones
        if kind not in ("tcp", "tls", "ws", "wss"):
            return  # inproc (a cluster in this process), ucx: addresses of their own form
        _, port = get_address_host_port(scheduler)
    except ValueError as exc:
        raise ValueError(f"scheduler {scheduler!r} is not a Dask scheduler's address ({exc}); give {form}, or a "
                         "port number after the host") from None
    if not 0 < port < 65536:
        raise ValueError(f"scheduler {scheduler!r}: port {port} is outside 1-65535; give {form}")


def make_executor(executor: str | None = None, *, workers: int | None = None, client: Any = None,
                  scheduler: str | None = None, fn: CellFn = run_cell, cell_time_limit: float | None = None,
                  worker_timeout: float | None = WORKER_TIMEOUT):
    """The executor for :func:`graybox.experiments.run_grid`'s arguments (see there)."""
    if executor is None:
        executor = "dask" if (client is not None or scheduler is not None or workers is not None) else "inprocess"
    check_choice(executor, "executor", EXECUTORS)
    if workers is not None:
        workers = check_workers(workers)
    check_cluster(client, scheduler)
    if cell_time_limit is not None:
        cell_time_limit = check_real(cell_time_limit, "cell_time_limit", low=0, low_open=True)
        if executor == "inprocess":
            # numba's compiled loops cannot be interrupted in a thread: a cell is stopped by ending its process
            raise ValueError("cell_time_limit needs worker processes (executor='processes' or 'dask'; graybox grid "
                             "run --processes N, --workers N or --scheduler ADDRESS): a cell run in the driver "
                             "cannot be stopped on time")
    if worker_timeout is not None:
        worker_timeout = check_real(worker_timeout, "worker_timeout (seconds)", low=0, low_open=True)
    if worker_timeout != WORKER_TIMEOUT and executor != "dask":
        where = "local worker processes" if executor == "processes" else "the driver alone"
        raise ValueError(f"worker_timeout is for a Dask cluster's workers (executor='dask'; graybox grid run "
                         f"--worker-timeout S with --workers N or --scheduler ADDRESS); a run on {where} has none to "
                         "lose")
    if executor == "inprocess":
        if any(v is not None for v in (workers, client, scheduler)):
            raise ValueError("the in-process executor takes no workers, client or scheduler")
        return InProcess(fn)
    if executor == "processes":
        if client is not None or scheduler is not None:
            raise ValueError("the local process executor takes workers only (a client or scheduler means Dask)")
        return ProcessPool(workers or os.cpu_count() or 1, fn, time_limit=cell_time_limit)
    return DaskCluster(client=client, scheduler=scheduler, workers=workers, fn=fn, worker_timeout=worker_timeout,
                       time_limit=cell_time_limit)
