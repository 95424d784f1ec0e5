"""A parallel ``map`` on the experiment layer's executors, for jobs that are not grid cells.

:func:`graybox.bootstrap_decision` (and any user loop of independent jobs) takes a ``map``
callable. :func:`parallel_map` gives one that runs the jobs on local processes or on a Dask
cluster, with the same thread budget as grid cells (workers × threads ≤ cores), and closes what
it started on exit::

    with gb.experiments.parallel_map(workers=2) as pmap:
        boot = gb.bootstrap_decision(structure, data, n_boot=200, map=pmap)
"""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor, as_completed, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import ExitStack, contextmanager
from typing import Any, Callable, Iterable, Iterator

from ..core._validation import check_choice, check_workers
from ._executors import (EXECUTORS, _environ, _thread_env, check_cluster, ignore_sigint, local_cluster,
                         scheduler_client, worker_threads)

__all__ = ["parallel_map"]


@contextmanager
def parallel_map(
    *,
    executor: str | None = None,
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
) -> Iterator[Callable[[Callable, Iterable], list]]:
    """A ``map(fn, items)`` that runs the jobs in parallel and returns their results in order.

    The words are :func:`run_grid`'s and :func:`select_graybox`'s (one parallelism vocabulary:
    ``threads=`` for the threads of one process everywhere, ``executor``/``workers``/``client``/
    ``scheduler`` for processes and clusters, and ``map=`` for the layers below the experiment
    layer, which take the map this function builds).

    Parameters
    ----------
    executor : {"processes", "dask", "inprocess"}, optional
        Default: "dask". "processes" runs a local ``ProcessPoolExecutor``; "inprocess" runs the
        jobs in turn here (the same results, no parallelism).
    workers : int, optional
        "dask": start a ``LocalCluster`` of this many worker processes; "processes": the pool's
        size (default: the number of cores).
    client : distributed.Client, optional
        "dask": run on this client's cluster (left open).
    scheduler : str, optional
        "dask": run on the Dask scheduler at this address.

    Yields
    ------
    callable
        ``map(fn, items, each=None) -> list`` of results in the order of ``items``; ``fn`` and the
        items must be picklable. ``each(i, result)``, if given, is called in this process as each
        job finishes (in any order; ``i`` its position in ``items``): e.g. to keep finished work.
    """
    executor = check_choice("dask" if executor is None else executor, "executor", EXECUTORS)
    if workers is not None:
        workers = check_workers(workers)
    check_cluster(client, scheduler)
    if executor != "dask" and (client is not None or scheduler is not None):
        raise ValueError(f"client and scheduler are for executor='dask', not {executor!r}")
    if executor == "inprocess" and workers is not None:
        raise ValueError("workers is for executor='processes' or 'dask'; 'inprocess' runs the jobs here, in turn")
    if executor == "dask" and sum(x is not None for x in (workers, client, scheduler)) != 1:
        raise ValueError("executor='dask' needs exactly one of workers, client or scheduler")
    with ExitStack() as stack:
        if executor == "inprocess":
            yield _in_turn
            return
        if executor == "processes":
            n = (os.cpu_count() or 1) if workers is None else workers
            stack.enter_context(_environ(_thread_env(worker_threads(n))))
            # spawned, not forked: a fork copies a parent whose numba threads are running, and the
            # child then refuses the NUMBA_NUM_THREADS set above (as ProcessPool spawns too)
            # the workers ignore SIGINT (Ctrl-C reaches the terminal's whole process group): the driver stops them
            pool = stack.enter_context(ProcessPoolExecutor(n, mp_context=multiprocessing.get_context("spawn"),
                                                           initializer=ignore_sigint))
            yield lambda fn, items, each=None: _pool_map(pool, fn, items, each)
            return
        from distributed import Client

        if client is None:
            if scheduler is not None:
                client = stack.enter_context(scheduler_client(scheduler))
            else:
                cluster = stack.enter_context(local_cluster(workers))
                client = stack.enter_context(Client(cluster))

        def dmap(fn: Callable, items: Iterable, each: Each | None = None) -> list:
            futures = client.map(fn, list(items), pure=False)
            told: set = set()
            in_each = False
            try:
                if each is None:
                    return client.gather(futures)
                from distributed import as_completed

                where = {f.key: i for i, f in enumerate(futures)}
                out: list = [None] * len(futures)
                for f, r in as_completed(futures, with_results=True):  # raises a job's error, as gather does
                    out[where[f.key]] = r
                    told.add(f.key)
                    in_each = True
                    each(where[f.key], r)
                    in_each = False
                return out
            except BaseException as exc:
                # the jobs not finished are dropped, on a caller's cluster too (it is left open, and a traceback
                # kept, as a notebook keeps it, would keep them running): after a job's error, Ctrl-C or an
                # error of each's own. After a job's error, as on local processes, those that finished before it
                # was seen (their results already on the workers) are told of, so that the work done is kept
                # (select_graybox's checkpoint)
                client.cancel([f for f in futures if f.status != "finished"])
                if each is not None and not in_each and isinstance(exc, Exception):
                    for f in futures:
                        if f.key not in told and f.status == "finished":
                            each(where[f.key], f.result())
                raise

        yield dmap


#: ``each(i, result)``: told of each finished job.
Each = Callable[[int, Any], None]


def _in_turn(fn: Callable, items: Iterable, each: Each | None = None) -> list:
    """The jobs run here, in turn."""
    out = []
    for i, x in enumerate(items):
        out.append(fn(x))
        if each is not None:
            each(i, out[-1])
    return out


def _pool_map(pool: ProcessPoolExecutor, fn: Callable, items: Iterable, each: Each | None = None) -> list:
    """``pool.map``, with a dead worker explained: the usual cause is a script without a main guard."""
    try:
        futures = [pool.submit(fn, x) for x in items]
        where = {f: i for i, f in enumerate(futures)}
        told: set = set()
        in_each = False
        try:
            for f in as_completed(futures):
                r = f.result()  # a job's error ends the map ...
                if each is not None:
                    told.add(f)
                    in_each = True
                    each(where[f], r)
                    in_each = False
        except Exception:
            # ... without running the jobs still queued: leaving the pool waits for every queued job (its
            # shutdown runs them), whose results would be thrown away. The running ones cannot be stopped
            # cleanly: they are waited for and, when a job's error (not each's own) ended the map, told of, so
            # that the work done is kept (select_graybox's checkpoint)
            for f in futures:
                f.cancel()
            wait(futures)
            if each is not None and not in_each:
                for f in futures:
                    if f not in told and not f.cancelled() and f.exception() is None:
                        each(where[f], f.result())
            raise
        return [f.result() for f in futures]
    except KeyboardInterrupt:
        # Ctrl-C: the jobs left are dropped and the running ones stopped now, not run to their end (the
        # workers ignore SIGINT); the executor has no public way to stop a running worker
        procs = list((getattr(pool, "_processes", None) or {}).values())  # before shutdown, which forgets them
        pool.shutdown(wait=False, cancel_futures=True)
        for proc in procs:
            proc.terminate()
        raise
    except BrokenProcessPool as exc:
        raise RuntimeError(
            "a worker process died before returning its job. Workers are spawned and import the "
            "main module again: a script that runs select_graybox or parallel_map on processes must "
            "do so under `if __name__ == \"__main__\":` (notebooks and the graybox command need "
            "nothing). Otherwise the worker was killed (out of memory, a signal)") from exc
