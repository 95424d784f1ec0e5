"""What the workers of graybox's own Dask ``LocalCluster`` load at start (a Dask worker preload).

A worker closes its connections to the scheduler while it closes (``Worker.close``); a heartbeat
still waiting for the scheduler's answer then failed with ``CommClosedError`` and distributed
logged ``ERROR - Failed to communicate with scheduler during heartbeat`` with its traceback on
the user's terminal, at the end of a run or after Ctrl-C. A heartbeat is in flight more often
the busier the machine (its answer waits for two busy event loops); distributed's known
shutdown race (dask/distributed#7192, #9032). This preload removes it: its teardown, which
``Worker.close`` runs before it closes those connections, stops the heartbeats and cancels the
one in flight, whose answer a closing worker has no use for. Nothing is filtered: any other error
a worker logs still shows.

Imports nothing of graybox: every worker loads it at start, before any task.
"""

from __future__ import annotations

import asyncio
from typing import Any

__all__ = ["dask_setup", "dask_teardown"]

#: id(worker) -> (its heartbeat's periodic callback, the heartbeats in flight).
_BEATS: dict[int, tuple[Any, set]] = {}


def dask_setup(worker: Any) -> None:
    """Run the worker's heartbeats as tasks that :func:`dask_teardown` can cancel (Dask's preload hook)."""
    pc = getattr(worker, "periodic_callbacks", {}).get("heartbeat")
    beat = getattr(pc, "callback", None)
    if not callable(beat):  # a distributed whose worker beats otherwise: left as it is
        return
    flying: set[asyncio.Task] = set()

    async def heartbeat() -> None:
        task = asyncio.ensure_future(beat())
        flying.add(task)
        try:
            await task
        except asyncio.CancelledError:
            me = asyncio.current_task()
            if me is not None and me.cancelling():  # this callback itself was cancelled, not only the beat
                raise
        finally:
            flying.discard(task)

    pc.callback = heartbeat
    _BEATS[id(worker)] = (pc, flying)


async def dask_teardown(worker: Any) -> None:
    """Stop the heartbeats and cancel the one in flight (``Worker.close`` runs this before it closes
    its connections to the scheduler)."""
    pc, flying = _BEATS.pop(id(worker), (None, set()))
    if pc is None:
        return
    pc.stop()
    tasks = list(flying)
    for task in tasks:
        task.cancel()
    await asyncio.gather(*tasks, return_exceptions=True)
