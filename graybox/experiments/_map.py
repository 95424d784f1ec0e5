"""A parallel ``map`` on the experiment layer's executors, for jobs that are not grid cells.

:func:`graybox.bootstrap_decision` (and any user loop of independent jobs) takes a ``map``
callable. :func:`parallel_map` gives one that runs the jobs on local processes or on a Dask
cluster, with the same thread budget as grid cells (workers × threads ≤ cores), and closes what
it started on exit::

    with gb.experiments.parallel_map(workers=2) as pmap:
        boot = gb.bootstrap_decision(structure, data, n_boot=200, map=pmap)
"""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from contextlib import ExitStack, contextmanager
from typing import Any, Callable, Iterable, Iterator

from ..core._validation import check_int
from ._executors import _environ, _thread_env, local_cluster, worker_threads

__all__ = ["parallel_map"]


@contextmanager
def parallel_map(
    *,
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
    processes: bool = False,
) -> Iterator[Callable[[Callable, Iterable], list]]:
    """A ``map(fn, items)`` that runs the jobs in parallel and returns their results in order.

    Parameters
    ----------
    workers : int, optional
        Start a Dask ``LocalCluster`` of this many worker processes (or, with ``processes``, a
        local process pool of this many workers).
    client : distributed.Client, optional
        Run on this client's cluster (left open).
    scheduler : str, optional
        Run on the Dask scheduler at this address.
    processes : bool
        Use a ``concurrent.futures.ProcessPoolExecutor`` instead of Dask (``workers`` processes).

    Yields
    ------
    callable
        ``map(fn, items) -> list`` of results in the order of ``items``; ``fn`` and the items must
        be picklable.
    """
    given = sum(x is not None for x in (workers, client, scheduler))
    if given != 1:
        raise ValueError("give exactly one of workers, client or scheduler")
    if processes and workers is None:
        raise ValueError("processes=True needs workers=N")
    with ExitStack() as stack:
        if processes:
            n = check_int(workers, "workers", low=1)
            stack.enter_context(_environ(_thread_env(worker_threads(n))))
            pool = stack.enter_context(ProcessPoolExecutor(n))
            yield lambda fn, items: list(pool.map(fn, items))
            return
        from distributed import Client

        if client is None:
            if scheduler is not None:
                client = stack.enter_context(Client(scheduler))
            else:
                cluster = stack.enter_context(local_cluster(check_int(workers, "workers", low=1)))
                client = stack.enter_context(Client(cluster))

        def dmap(fn: Callable, items: Iterable) -> list:
            return client.gather(client.map(fn, list(items), pure=False))

        yield dmap
