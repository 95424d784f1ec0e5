"""What runs on Dask workers: the grid's data sets, held by a worker plugin, and the cell task.

Imported only when a grid runs on Dask (importing :mod:`distributed` is not free). The data
sets travel once to each worker inside a :class:`GridData` plugin — a worker that joins later
(e.g. one the nanny restarted after a crash) receives it from the scheduler too — so a cell's
task carries only the cell (about a kilobyte), not tens of kilobytes of records.
"""

from __future__ import annotations

from typing import Callable, Mapping

from distributed import WorkerPlugin, get_worker

import graybox as gb

from ._spec import Cell

__all__ = ["GridData", "cell_task"]


class GridData(WorkerPlugin):
    """The data sets of one grid run, by content hash, on every worker."""

    idempotent = True

    def __init__(self, datasets: Mapping[str, gb.Dataset]):
        self.datasets = dict(datasets)

    def setup(self, worker) -> None:  # noqa: D102 - WorkerPlugin interface
        pass


def cell_task(fn: Callable[[Cell, gb.Dataset, int], dict], plugin: str, cell: Cell) -> dict:
    """Run ``fn`` on a cell with the data set the worker's plugin ``plugin`` holds."""
    data = get_worker().plugins[plugin].datasets[cell.data_hash]
    return fn(cell, data, 1)
