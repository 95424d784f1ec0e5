"""The driver: load the data, open the store, run the cells not yet finished, write each as it completes."""

from __future__ import annotations

import os
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from .. import _api as gb

from ..core._progress import progress_bar
from ..core._reprs import bound_text
from ..core._validation import FrozenMap, check_bool, check_fields, check_path
from ._cell import STATUSES, failed_row, run_cell
from ._executors import WORKER_TIMEOUT, make_executor, session
from ._spec import Grid, SpecError, reads_uncertainty, stored_spec
from ._store import ResultStore

__all__ = ["GridRun", "run_grid"]


@dataclass(frozen=True, eq=False)
class GridRun:
    """What :func:`run_grid` did.

    Attributes
    ----------
    store : str
        Path of the store.
    grid : str
        The grid's name.
    cells : int
        Cells in the grid.
    ran : int
        Cells run now.
    skipped : int
        Cells not run now: the store held them (reused), or another run on the store made
        them meanwhile (its notes say how many).
    counts : mapping str -> int
        The grid's cells in the store by status (ok, infeasible, diverged, failed).
    executor : str
        Where the cells ran.
    wall_time : float
        Seconds for the whole run.
    spec : int
        The grid's number among the specs the store has seen (1 = the first).
    notes : tuple of str
        What the store made of the grid: a spec new to the store, new data sets, a data set's
        band other than in the store's spec of the same cells, cells of an older graybox that
        could not be reused.
    """

    store: str
    grid: str
    cells: int
    ran: int
    skipped: int
    counts: Mapping[str, int]
    executor: str
    wall_time: float
    spec: int = 1
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        check_fields(self)
        object.__setattr__(self, "counts", FrozenMap(self.counts))  # not the caller's dict

    @property
    def reused(self) -> int:
        """Cells the store already held (the same as ``skipped``)."""
        return self.skipped

    def summary(self) -> str:
        """How many cells, how many reused and run now, their statuses, and any notes.

        Returns
        -------
        str
            One line, then one indented line per note.
        """
        st = ", ".join(f"{self.counts.get(s, 0)} {s}" for s in STATUSES)
        head = (f"grid {self.grid!r} (spec {self.spec} of {self.store}): {self.cells} cells, {self.skipped} reused, "
                f"{self.ran} run now ({self.executor}, {self.wall_time:.1f} s); {st}")
        return "\n".join([head, *(f"  {n}" for n in self.notes)])


def run_grid(
    grid: Grid | str | os.PathLike,
    store: str | os.PathLike,
    *,
    executor: str | None = None,
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
    retry_failed: bool = False,
    cell_time_limit: float | None = None,
    worker_timeout: float | None = WORKER_TIMEOUT,
    progress: bool | None = None,
    log: Callable[[str], None] | None = None,
) -> GridRun:
    """Run a grid's cells that the store does not hold yet; each finished cell is committed at once.

    A store grows: run a grid with one more data set, structure, variant, seed or option on a
    finished store and only the new cells run (a cell is its content: a variant whose options
    changed is a new cell, and the old one is kept). The store keeps every spec run on it.

    Parameters
    ----------
    grid : Grid or path
        The grid, or a TOML spec file.
    store : path
        The SQLite store (created if missing, grown if not). A store whose data set of the same
        name holds other data, a store of a newer graybox, a damaged file or a file that is not
        a graybox store is refused and left untouched. Another run may use it meanwhile (another
        process, notebook or host), and the two share the work: each takes a cell as it is about
        to start it (as many at a time as its executor can start), so a run started later takes
        the cells not started yet. A run does not start a cell another live run has taken: with
        no other cell left, it waits for it (and runs it itself if that run stops or dies first),
        so no cell runs twice; the notes say how many cells the other run made.
    executor : {"inprocess", "processes", "dask"}, optional
        Default: "dask" when ``client``, ``scheduler`` or ``workers`` is given, else "inprocess".
    workers : int, optional
        "processes": worker processes (default: the number of cores); "dask": start a
        ``LocalCluster`` of this many worker processes for the run.
    client : distributed.Client, optional
        Run on this Dask client's cluster (left open).
    scheduler : str, optional
        Run on the Dask scheduler at this address.
    retry_failed : bool
        Run the cells whose stored status is "failed" again (their rows are replaced).
    cell_time_limit : float, optional
        Seconds (wall time) a cell may run, with worker processes (``executor="processes"`` or Dask; a
        cell in the driver cannot be stopped): past them the process running it is killed and the cell is
        stored as failed, saying so (not retried in the run; ``retry_failed`` with a larger limit runs it
        again). On Dask the cells then run in a child process of each worker thread, kept for the run (a
        second or two more per worker for its start-up). None (default): no limit.
    worker_timeout : float or None
        With Dask: seconds a run goes on once its cluster, having had workers, has none left (all
        gone, none restarted): then it ends with a ``ConnectionError``, the rows finished kept (running
        again resumes). None waits for ever (a cluster whose workers may all be requeued in a batch
        system). A cluster with no worker yet at the start is always waited for. Default 60.
    progress : bool, optional
        Progress bar (cells done, ETA); default: on a terminal only.
    log : callable, optional
        Called with lines worth telling at the start of a run (cells reused and to run, the
        Dask dashboard's address); the ``graybox`` command prints them.

    Returns
    -------
    GridRun
        Counts and timing; the rows are in the store (:func:`graybox.load_results`).

    Raises
    ------
    SpecError
        The spec is invalid or its data cannot be loaded.
    StoreError
        The store cannot be used, or gives one of the spec's data set names other data.
    ConnectionError
        A Dask scheduler cannot be reached or has no worker, or the cluster has had no worker for 60 s
        mid-run (all gone, none restarted): the rows finished are kept, and running again resumes. (A
        ``client`` whose cluster has no worker yet, an adaptive one starting them, is waited for.)

    Notes
    -----
    A row is committed as soon as the driver receives it. On Dask, cells travel in batches (at
    most about three seconds of work each, smaller towards the end, two per worker thread in
    flight), so a killed driver loses at most the batches in flight. A Dask worker of several threads (``dask
    worker``'s default) runs each thread's cells in a child process of its own, kept for the run: a process's
    warning filters are not a thread's, and cells side by side in one process took each other's warnings (a
    row's ``warnings``). Worker processes are
    started with the ``spawn`` method (the local pool and a Dask ``LocalCluster``), which imports
    the calling script again: a script that runs a grid on workers must do so under
    ``if __name__ == "__main__":``. Notebooks and the ``graybox``
    command need nothing.
    """
    t0 = time.perf_counter()
    # the options before the data are read or the store is touched
    store = check_path(store, "store", file=True)
    retry_failed = check_bool(retry_failed, "retry_failed")
    if progress is not None:
        check_bool(progress, "progress")
    if log is not None and not callable(log):
        raise TypeError(f"log must be a callable taking a line of text, got {log!r}")
    ex = make_executor(executor, workers=workers, client=client, scheduler=scheduler, fn=run_cell,
                       cell_time_limit=cell_time_limit, worker_timeout=worker_timeout)
    g = grid if isinstance(grid, Grid) else Grid.from_toml(grid)
    datasets = g.load_data()
    cells = g.cells(datasets)
    by_hash = _by_hash(cells, datasets)
    version = gb.__version__
    say = log or (lambda line: None)
    with ResultStore.open(store, grid_name=g.name, fingerprint=g.fingerprint(cells), spec=stored_spec(g, datasets),
                          cells=cells, version=version) as st, st.running():
        marks = st.marks()
        done = {k: status for k, (status, _) in marks.items()}
        todo, seen = [], set()
        # two data set names of one grid may hold the same data: their cells share keys, run once and count for each
        mult = Counter(c.key for c in cells)
        for c in cells:
            # two data set names of one grid may hold the same data: their cells share keys, run once
            if c.key not in seen and (c.key not in done or (retry_failed and done[c.key] == "failed")):
                todo.append(c)
            seen.add(c.key)
        notes = _notes(st, cells, done, version)
        n_todo = sum(mult[c.key] for c in todo)
        say(f"grid {g.name!r}: {len(cells)} cells, {len(cells) - n_todo} reused from {store}, {n_todo} to run")
        for n in notes:
            say(f"  {n}")
        bar = progress_bar(len(cells), f"grid {g.name}", progress, initial=len(cells) - n_todo)
        # each cell is claimed as the executor is about to start it (a batch at a time, never all at once), so
        # that another run on the store takes the cells this one has not started yet and the two share the grid
        share = _Share(st, marks, bar, mult)
        ran = taken = 0
        try:
            # alive to the other runs while a long cell writes no row; the executor keeps its workers (or cluster)
            # for the cells it takes over after a wait
            with st.beating(), session(ex):
                while True:
                    for row in ex.run(todo, by_hash, log=say, take=share.take):
                        if row.get("version") != version:
                            row = failed_row(next(c for c in todo if c.key == row["key"]),
                                             f"the worker runs graybox {row.get('version')}, the driver {version}: "
                                             "install the same graybox on every worker")
                        taken += mult[row["key"]] * (not st.write(row, replace=row["key"] in done))
                        ran += mult[row["key"]]
                        bar.update(mult[row["key"]])
                    if not share.waiting:
                        break
                    if not share.said:
                        # the cells skipped as held over the run: most may be finished by now (two in-process
                        # runs leapfrog), so those still held are counted, by the runs that hold them
                        held = st.held(list(share.waiting))
                        if held:
                            share.said = True
                            say(f"  {len(held)} of the cells to run are being run by another run on this "
                                f"store ({', '.join(sorted(set(held.values())))}): this one waits for them")
                    # those released go back to the executor, which takes them as it starts them (another run
                    # may take some first)
                    todo, finished = _wait_for_others(st, share.waiting, marks)
                    n_finished = sum(mult[k] for k in finished)
                    share.by_others += n_finished
                    bar.update(n_finished)
        finally:
            bar.close()
        if share.by_others:
            who = f" ({', '.join(sorted(share.others))})" if share.others else ""
            notes.append(f"{share.by_others} cell(s) were run meanwhile by another run on this store{who}; "
                         "this one did not run them again")
        if taken:
            notes.append(f"{taken} cell(s) run now were written meanwhile by another run on this store: "
                         "its rows are kept")
        counts = st.counts()
        spec_id = st.spec_id
    return GridRun(str(Path(store)), g.name, len(cells), ran, len(cells) - ran,
                   FrozenMap({s: counts.get(s, 0) for s in STATUSES}), ex.name, time.perf_counter() - t0,
                   spec_id, tuple(notes))


#: Seconds between two looks at the store while another run finishes cells this one waits for.
POLL_SECONDS = 0.5


class _Share:
    """What a run takes of the cells it would run, as its executor is about to start them (:meth:`take`): those
    another live run holds wait (:attr:`waiting`), those another run has written meanwhile are not run again
    (:attr:`by_others`, on the progress bar at once)."""

    def __init__(self, st: ResultStore, seen: Mapping[str, tuple], bar: Any, mult: Mapping[str, int]):
        self.st, self.seen, self.bar, self.mult = st, seen, bar, mult  # mult: the grid's cells of each key
        self.waiting: dict[str, Any] = {}  # key -> cell another live run holds
        self.others: set[str] = set()  # those runs, in words
        self.by_others = 0
        self.said = False

    def take(self, cells) -> list:
        """Of ``cells``, those this run now holds and may start (the executor's ``take``)."""
        if not cells:
            return []
        # a cell written since this run looked is dropped before it is claimed: a run that starts late goes
        # through the cells another has finished with reads only
        written = _changed_since(self.st, [c.key for c in cells], self.seen)
        ask = [c for c in cells if c.key not in written]
        held = self.st.claim([c.key for c in ask]) if ask else {}
        for c in ask:
            if c.key in held:
                self.waiting[c.key] = c
        self.others.update(held.values())
        mine = [c for c in ask if c.key not in held]
        # another run may have written (and let go) a cell between that look and this claim: kept, not run again
        written |= _written_since(self.st, [c.key for c in mine], self.seen)
        n = sum(self.mult[k] for k in written)
        self.by_others += n
        self.bar.update(n)
        return [c for c in mine if c.key not in written]


def _changed_since(st: ResultStore, keys: list[str], seen: Mapping[str, tuple]) -> set[str]:
    """Those of ``keys`` whose row another run wrote, or wrote over, since this run saw the store as ``seen``."""
    now = st.marks(keys)
    return {k for k in keys if now.get(k) != seen.get(k)}


def _written_since(st: ResultStore, keys: list[str], seen: Mapping[str, tuple]) -> set[str]:
    """:func:`_changed_since` of this run's claims ``keys``; their claims end (this run does not run them)."""
    written = _changed_since(st, keys, seen)
    st.unclaim(sorted(written))
    return written


def _wait_for_others(st: ResultStore, waiting: dict, seen: Mapping[str, tuple]) -> tuple[list, list]:
    """Wait until another run releases some of the ``waiting`` cells (it wrote them, stopped or died); remove
    them from ``waiting``; return (those left to run, not taken yet: the executor takes each as it starts it;
    those another run finished)."""
    while True:
        time.sleep(POLL_SECONDS)
        held = st.held(list(waiting))  # taken only as each starts: a run taking them all here held cells it had
        free = [k for k in waiting if k not in held]  # not started, which grid status said it ran and a third
        if free:  # run could not share
            break
    # a row other than the one this run saw (a new one, or a retried failed cell's new row): the other run's
    finished = _changed_since(st, free, seen)
    todo = [waiting.pop(k) for k in free if k not in finished]
    for k in finished:
        waiting.pop(k)
    return todo, sorted(finished)


def _by_hash(cells, datasets: Mapping[str, gb.Dataset]) -> dict[str, gb.Dataset]:
    """The data sets by content hash (how workers find a cell's data); ``SpecError`` for two data sets of
    the same records and points whose uncertainties differ, which one hash cannot tell apart."""
    out: dict[str, gb.Dataset] = {}
    names: dict[str, str] = {}
    reads = any(reads_uncertainty(c.variant_spec) for c in cells)
    for c in cells:
        ds = datasets[c.data]
        if reads and c.data_hash in out and out[c.data_hash] is not ds:
            a, b = (x.static.uncertainty for x in (out[c.data_hash], ds))
            if (a is None) != (b is None) or (a is not None and not np.array_equal(a, b)):
                raise SpecError(f"data sets {names[c.data_hash]!r} and {c.data!r} hold the same records and static "
                                "points with other uncertainties, which their cells cannot tell apart: run them in "
                                "two grids, or give the band constraints their half-width b")
        out.setdefault(c.data_hash, ds)
        names.setdefault(c.data_hash, c.data)
    return out


def _band(b: float | None) -> str:
    return "none" if b is None else bound_text(b)


def _notes(st: ResultStore, cells, done: Mapping[str, str], version: str) -> list[str]:
    """What the store made of the grid, in words."""
    out = []
    if st.new_spec and st.spec_id > 1:
        out.append(f"a new spec for this store (spec {st.spec_id}): only the cells it does not hold run")
    for name, (was, now) in (st.band_changes if st.new_spec else {}).items():
        out.append(f"data set {name!r}: band {_band(now)} in this spec, {_band(was)} in the store's spec of the same "
                   "cells: its results are read, and ranked, with this spec's")
    for name, (was, now) in (st.unit_changes if st.new_spec else {}).items():
        out.append(f"data set {name!r}: output in {now or 'no unit'} in this spec, in {was or 'no unit'} in the "
                   "store's spec of the same cells: its results are reported in this spec's")
    hashes = {c.data: c.data_hash for c in cells}
    for name, h in hashes.items():
        if st.known_data and name not in st.known_data:
            same = [k for k, v in st.known_data.items() if v == h]
            out.append(f"data set {name!r} is new to the store" + (f" (the same data as {same[0]!r}: its cells are "
                                                                   "reused)" if same else ""))
    # the cells of this grid an older (or other) graybox made: keyed by version, they run again
    for v, n in sorted(st.made_by_other_versions([c for c in cells if c.key not in done], version).items()):
        out.append(f"{n} cell(s) of this grid were made before by graybox {v}, and cells are keyed by version: "
                   "they run again (the old rows are kept)")
    return out
