"""Pictures of models against data: free-run simulation over a record (Figs. 6 and 8)."""

from __future__ import annotations

from typing import Mapping

from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..models._model import Model
from ..core._records import Record

__all__ = ["plot_free_run"]


def plot_free_run(
    record: Record,
    models: Model | Mapping[str, Model],
    *,
    ax: Axes | None = None,
    ylabel: str = "output",
) -> Figure:
    """The measured output (solid) and each model's free run (dashed) against time.

    Parameters
    ----------
    record : Record
        Input and output, shape (N,); each free run starts from its first max-lag samples.
    models : Model or mapping name -> Model
    ax : matplotlib Axes, optional
        Draw here; by default a new 8 × 3.6 in figure is made.
    ylabel : str
        Output label without units (``record.units[1]`` is appended).

    Returns
    -------
    matplotlib.figure.Figure
        One line for the data and one per model; a diverging model is drawn up to where it
        left its bound (the rest is NaN) and its legend entry says so.
    """
    ms = {models.name or "model": models} if isinstance(models, Model) else dict(models)
    if ax is None:
        fig = Figure(figsize=(8, 3.6))
        ax = fig.add_subplot(1, 1, 1)
    else:
        if not isinstance(ax, Axes):
            raise TypeError(f"ax must be a matplotlib Axes, got {type(ax).__name__}")
        fig = ax.figure
    t = record.t
    ax.plot(t, record.y, "-", color="black", lw=1.0, label="measured")
    for name, m in ms.items():
        y = m.simulate(record, on_diverge="nan")
        diverged = not (y == y).all()
        ax.plot(t, y, "--", lw=1.0, label=name + (" (diverged)" if diverged else ""))
    unit = record.units[1]
    ax.set_xlabel("time (s)")
    ax.set_ylabel(f"{ylabel} ({unit})" if unit else ylabel)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    return fig
