"""What runs on Dask workers: the grid's data sets, held by a worker plugin, and the cell task.

Imported only when a grid runs on Dask (importing :mod:`distributed` is not free). The data
sets travel once to each worker inside a :class:`GridData` plugin — a worker that joins later
(e.g. one the nanny restarted after a crash) receives it from the scheduler too — so a task
carries only its cells (about a kilobyte each), not tens of kilobytes of records.
"""

from __future__ import annotations

from typing import Callable, Mapping

from distributed import WorkerPlugin, get_worker

from .. import _api as gb

from ._spec import Cell

__all__ = ["GridData", "cells_task"]


class GridData(WorkerPlugin):
    """The data sets of one grid run, by content hash, on every worker."""

    idempotent = True

    def __init__(self, datasets: Mapping[str, gb.Dataset]):
        self.datasets = dict(datasets)

    def setup(self, worker) -> None:  # noqa: D102 - WorkerPlugin interface
        pass


def cells_task(fn: Callable[[Cell, gb.Dataset, int], dict], plugin: str, cells: list[Cell]) -> list[dict]:
    """Run ``fn`` on a batch of cells, one after another; their rows in order."""
    store = get_worker().plugins[plugin].datasets
    return [fn(c, store[c.data_hash], threads=1) for c in cells]
