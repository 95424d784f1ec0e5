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

__all__ = ["GridData", "CellRows", "cells_task"]


class GridData(WorkerPlugin):
    """The data sets of one grid run, by content hash, on every worker."""

    idempotent = True

    def __init__(self, datasets: Mapping[str, gb.Dataset]):
        self.datasets = dict(datasets)
        #: What the run's tasks keep on this worker from one task to the next (a task's runner's, e.g. the child
        #: process that runs cells under a time limit): each value's ``close()`` is called when the run ends.
        self.kept: dict = {}

    def setup(self, worker) -> None:  # noqa: D102 - WorkerPlugin interface
        pass

    def teardown(self, worker) -> None:  # noqa: D102 - WorkerPlugin interface: the run is over (or the worker)
        kept, self.kept = self.kept, {}
        for v in kept.values():
            v.close()


class CellRows:
    """A task's rows, with a size Dask reads instead of walking them.

    A worker measures every task result (``dask.sizeof``) before it starts its next task; on a
    batch of rows, with their nested Pareto members, that walk took as long as Dask's own
    hand-over between two tasks (BENCHMARKS.md, grids). The size given is an estimate, used by
    Dask only to account for memory and transfers.
    """

    #: Estimated bytes per row (a PE row with 100 members pickles to about 6 kB, a CLS row to 0.7 kB).
    ROW_BYTES = 4096

    def __init__(self, rows: list[dict]):
        self.rows = rows

    def __sizeof__(self) -> int:
        return 64 + self.ROW_BYTES * len(self.rows)


def cells_task(fn: Callable[[Cell, gb.Dataset, int], dict], plugin: str, cells: list[Cell],
               runner: Callable[[list[Cell], Mapping[str, gb.Dataset], dict], list[dict]] | None = None) -> CellRows:
    """Run ``fn`` on a batch of cells, one after another; their rows in order. ``runner``, when given, runs the
    batch instead (the cells, the data sets by hash and what it keeps on the worker for the run's next task,
    :attr:`GridData.kept`), e.g. in a child process under a cell time limit."""
    data = get_worker().plugins[plugin]
    if runner is not None:
        return CellRows(list(runner(cells, data.datasets, data.kept)))
    return CellRows([fn(c, data.datasets[c.data_hash], threads=1) for c in cells])
