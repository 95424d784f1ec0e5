"""Pictures of models against data: free-run simulation over a record (Figs. 6 and 8)."""

from __future__ import annotations

from typing import Mapping

from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..models._coerce import as_model, as_record
from ..models._model import Model
from ..core._records import Dataset, Record
from ._data import legend_text, unit_label

__all__ = ["plot_free_run"]


def plot_free_run(
    record: Record | Dataset,
    models: Model | Mapping[str, Model] | object,
    *,
    ax: Axes | None = None,
    ylabel: str = "output",
) -> Figure:
    """The measured output (solid) and each model's free run (dashed) against time.

    Parameters
    ----------
    record : Record or Dataset
        Input and output, shape (N,); each free run starts from its first max-lag samples. A
        Dataset stands for its validation record.
    models : Model, a result that carries one in ``.model``, or a mapping name -> either
        One model (an ELSResult, CLSResult, Decision, DSFResult, NeuralFit … stands for its
        model) or several by name.
    ax : matplotlib Axes, optional
        Draw here; by default a new 8 × 3.6 in figure is made.
    ylabel : str
        Output label (``record.units[1]`` is appended unless the label names it, as in
        ``"Temperature (°C)"``).

    Returns
    -------
    matplotlib.figure.Figure
        One line for the data and one per model; a diverging model is drawn up to where it
        left its bound (the rest is NaN) and its legend entry says so.
    """
    record = as_record(record, "valid", "record")
    if isinstance(models, Mapping):
        if not models:
            raise ValueError("models is an empty mapping: give at least one model to draw against the record")
        ms = {name: as_model(m, f"models[{name!r}]", duck="simulate") for name, m in models.items()}
    else:
        m = as_model(models, "models", duck=("simulate", "name"))
        ms = {m.name or "model": m}
    if ax is None:  # laid out as it is drawn (a caller's figure keeps its own layout: no tight_layout on it)
        fig = Figure(figsize=(8, 3.6), layout="constrained")
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
        ax.plot(t, y, "--", lw=1.0, label=legend_text(name) + (" (diverged)" if diverged else ""))
    unit = record.units[1]
    ax.set_xlabel("time (s)")
    ax.set_ylabel(unit_label(ylabel, unit))  # "Temperature (°C)" as given, not "Temperature (°C) (°C)"
    ax.legend(loc="best", fontsize=8)
    return fig
