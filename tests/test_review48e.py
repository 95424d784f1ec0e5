"""Review of the cell time limit on Dask (review48e): pool workers started from several threads at once."""

from __future__ import annotations

import os
import threading
import time

from graybox.experiments._executors import ProcessPool


class _SlowStart:
    """A stand-in for the spawn context: a process whose start takes a while (a spawn's fork and exec read the
    environment meanwhile) and notes the thread variables it was started with."""

    def __init__(self):
        self.seen: list[tuple[int, str | None]] = []

    def Pipe(self):
        class _End:
            def close(self):
                pass

        return _End(), _End()

    def Process(self, target, args, daemon, name):
        ctx = self

        class _Proc:
            def start(self):
                time.sleep(0.3)
                ctx.seen.append((threading.get_ident(), os.environ.get("NUMBA_NUM_THREADS")))

        return _Proc()


def test_two_threads_starting_pool_workers_at_once_give_each_its_threads_and_leave_the_environment(monkeypatch):
    # a Dask worker of two threads runs two tasks at once, each starting its child (one thread) under a cell time
    # limit; the thread variables were set around each start without a lock: the first start's restore gave the
    # second child the worker's own 2 threads, and the second's restore left 1 in the worker's environment for good
    monkeypatch.setenv("NUMBA_NUM_THREADS", "2")  # the worker's, as graybox's LocalCluster gives it
    ctx = _SlowStart()
    pools = [ProcessPool(1, threads=1), ProcessPool(1, threads=1)]
    for p in pools:
        p._ctx = ctx

    ts = [threading.Thread(target=p._start) for p in pools]
    for t in ts:
        t.start()
        time.sleep(0.05)
    for t in ts:
        t.join()
    assert [value for _, value in ctx.seen] == ["1", "1"]
    assert os.environ.get("NUMBA_NUM_THREADS") == "2"
