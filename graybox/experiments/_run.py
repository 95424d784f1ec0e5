"""The driver: load the data, open the store, run the cells not yet finished, write each as it completes."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping

from .. import _api as gb

from ..core._progress import progress_bar
from ._cell import STATUSES, failed_row, run_cell
from ._executors import make_executor
from ._spec import Grid
from ._store import ResultStore

__all__ = ["GridRun", "run_grid"]


@dataclass(frozen=True)
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
        Cells already finished in the store (not run again).
    counts : mapping str -> int
        Cells of the whole store by status (ok, infeasible, diverged, failed).
    executor : str
        Where the cells ran.
    wall_time : float
        Seconds for the whole run.
    """

    store: str
    grid: str
    cells: int
    ran: int
    skipped: int
    counts: Mapping[str, int]
    executor: str
    wall_time: float

    def summary(self) -> str:
        """One line: how many cells, how many run now, and their statuses."""
        st = ", ".join(f"{self.counts.get(s, 0)} {s}" for s in STATUSES)
        return (f"grid {self.grid!r}: {self.cells} cells, {self.ran} run now ({self.executor}, {self.wall_time:.1f} s), "
                f"{self.skipped} already in {self.store}; {st}")


def run_grid(
    grid: Grid | str | os.PathLike,
    store: str | os.PathLike,
    *,
    executor: str | None = None,
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
    retry_failed: bool = False,
    progress: bool | None = None,
) -> GridRun:
    """Run a grid's cells that are not in the store yet; each finished cell is committed at once.

    Parameters
    ----------
    grid : Grid or path
        The grid, or a TOML spec file.
    store : path
        The SQLite store (created if missing). A store written by another grid, a damaged file
        or a file that is not a graybox store is refused and left untouched.
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
    progress : bool, optional
        Progress bar (cells done, ETA); default: on a terminal only.

    Returns
    -------
    GridRun
        Counts and timing; the rows are in the store (:func:`graybox.load_results`).

    Raises
    ------
    SpecError
        The spec is invalid or its data cannot be loaded.
    StoreError
        The store cannot be used.

    Notes
    -----
    A row is committed as soon as the driver receives it. On Dask, cells travel in batches (at
    most about three seconds of work each, smaller towards the end, two per worker thread in
    flight), so a killed driver loses at most the batches in flight. Worker processes are
    started with the ``spawn`` method (the local pool and a Dask ``LocalCluster``), which imports
    the calling script again: a script that runs a grid on workers must do so under
    ``if __name__ == "__main__":``. Notebooks and the ``graybox``
    command need nothing.
    """
    t0 = time.perf_counter()
    g = grid if isinstance(grid, Grid) else Grid.from_toml(grid)
    datasets = g.load_data()
    cells = g.cells(datasets)
    by_hash = {c.data_hash: datasets[c.data] for c in cells}
    ex = make_executor(executor, workers=workers, client=client, scheduler=scheduler, fn=run_cell)
    version = gb.__version__
    with ResultStore.open(store, fingerprint=g.fingerprint(cells), grid_name=g.name, spec=g.to_dict(),
                          n_cells=len(cells), version=version) as st:
        done = st.statuses()
        todo = [c for c in cells if c.key not in done or (retry_failed and done[c.key] == "failed")]
        bar = progress_bar(len(cells), f"grid {g.name}", progress, initial=len(cells) - len(todo))
        ran = 0
        try:
            for row in ex.run(todo, by_hash):
                if row.get("version") != version:
                    row = failed_row(next(c for c in todo if c.key == row["key"]),
                                     f"the worker runs graybox {row.get('version')}, the driver {version}: "
                                     "install the same graybox on every worker")
                st.write(row, replace=row["key"] in done)
                ran += 1
                bar.update(1)
        finally:
            bar.close()
        counts = st.counts()
    return GridRun(str(Path(store)), g.name, len(cells), ran, len(cells) - len(todo),
                   MappingProxyType({s: counts.get(s, 0) for s in STATUSES}), ex.name, time.perf_counter() - t0)
