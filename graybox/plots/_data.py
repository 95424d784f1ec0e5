"""Pictures of data: the static curve with its points (the paper's Fig. 2) and a record (Fig. 3).

The functions build figures with :class:`matplotlib.figure.Figure` directly, not through pyplot:
they hold no global state, work with the Agg backend (servers, CI) and never open windows. Pass
``ax`` to draw into an existing figure instead.
"""

from __future__ import annotations

import re
from typing import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..static._curves import StaticCurve
from ..core._records import Dataset, Record, StaticPoints, input_unit
from ..models._coerce import as_model
from ..models._model import Model
from ..core._reprs import LISTED
from ..core._validation import check_count, check_int, check_real, check_sequence

__all__ = ["plot_static_curve", "plot_record"]


def distinct_colours(n: int) -> list:
    """``n`` colours told apart: matplotlib's ten (C0 … C9) while they suffice, then tab20's twenty, then as many
    spread over a colour map (cycling the ten drew the 1st and 11th of a figure's lines alike)."""
    if n <= 10:
        return [f"C{i}" for i in range(n)]
    from matplotlib import colormaps

    cmap = colormaps["tab20" if n <= 20 else "turbo"]
    return [cmap(i if n <= 20 else i / (n - 1)) for i in range(n)]


#: What to pass instead of the objects most often given where static points belong.
_POINTS_HINT = {"Dataset": " (pass data.static)", "StaticCurve": " (pass a curve as curve=)"}


def check_one_input_points(points: object, who: str) -> None:
    """``points`` None or StaticPoints of one input, else ``TypeError``/``ValueError`` saying what to pass."""
    if points is None:
        return
    if not isinstance(points, StaticPoints):
        raise TypeError(f"points must be StaticPoints, got {type(points).__name__}"
                        + _POINTS_HINT.get(type(points).__name__, ""))
    if points.n_inputs != 1:
        raise ValueError(f"{who}: the points have {points.n_inputs} inputs {points.input_names}; a static curve is "
                         "drawn against one input: use plot_surface_slices or plot_surface_contours")


def varied_input_levels(points: StaticPoints | None, who: str) -> tuple[np.ndarray | None, str | None]:
    """The points' ū as a 1-D array: of their one input, or of the one input they vary when they hold the others (a
    transient input's z̄ = 0 beside ū), with that input's name (None for points of one input); ``ValueError`` for
    points that vary several (a surface's)."""
    if points is None:
        return None, None
    if not isinstance(points, StaticPoints) or points.n_inputs == 1:
        check_one_input_points(points, who)  # raises for what is no static points
        return points.ubar, None
    ub = np.asarray(points.ubar, float)
    varied = [j for j in range(ub.shape[1]) if np.ptp(ub[:, j]) > 0]
    if len(varied) != 1:
        check_one_input_points(points, who)  # raises, naming the inputs
    j = varied[0]
    return ub[:, j], points.input_names[j]


def on_level(held: np.ndarray, level: np.ndarray) -> np.ndarray:
    """Which static points lie on a slice: ``held`` (N, k) their held inputs' levels, ``level`` (k,) the slice's;
    equal to 1e-9 of each held input's own size (any unit: nA or MW, one input's unit apart from another's),
    shape (N,)."""
    held = np.asarray(held, float)
    level = np.asarray(level, float)
    scale = np.abs(held).max(axis=0, initial=0.0)  # per input: one in MW must not set the tolerance of one in nA
    return (np.abs(held - level) <= 1e-9 * np.maximum(np.abs(level), scale)).all(axis=1)


#: The most slices a surface panel's legend names (plot_surface_slices, plot_static_band of a surface band): 20 and
#: the points' or the band's own entry (and the title saying one in k) ran off the bottom of the panel.
SLICES_NAMED = 15


def legend_every(n: int, most: int = LISTED) -> int:
    """Of ``n`` lines one per level (slices, operating points), name one in this many in the legend: about ``most``
    entries at most (:data:`~graybox.core._reprs.LISTED` by default; a legend of 30 slices ran off its panel,
    matplotlib warning 'constrained_layout not applied')."""
    return max(1, -(-int(n) // most))


def legend_text(text: object) -> str:
    """A legend entry named by the caller (a model's, a curve's, an input's name) as ``str(text)``, kept off a
    leading ``_``: matplotlib leaves a label that starts with one out of the legend, so the line it names was
    drawn unnamed."""
    text = str(text)
    return " " + text if text.startswith("_") else text


def unit_label(text: str, unit: str) -> str:
    """An axis label with its unit: ``text (unit)``, or ``text`` as given when no unit is said or the text
    already names it where a unit is written: in brackets, alone or as one of its items
    (``"Speed (rpm)"``, ``"Speed [rpm]"``, ``"Speed (in rpm)"``, ``"Speed (rpm, mean)"``), or last,
    after ``in``, a slash, a comma, a colon or an underscore (``"Temperature in °C"``, ``"Speed/rpm"``,
    ``"Speed, rpm"``, ``"speed_rpm"``), a remark in brackets allowed after it (``"Temperature in °C (mean)"``).
    A unit that is also a word elsewhere is not its naming: ``"Level in tank"`` in inches is
    ``"Level in tank (in)"``, ``"Current of pump A"`` in amperes ``"Current of pump A (A)"``. A label that is no
    text is shown as ``str(text)`` (as matplotlib shows any label; a surface's ``input_labels`` may be any values)."""
    text = str(text)
    if not unit:
        return text
    u = re.escape(unit)
    # a word rule ("the unit as a word of its own anywhere") took the "in" of "Level in tank" or the "A" of
    # "A pump" for the unit, and missed "Speed/rpm" and "speed_rpm"
    # a bracket holding the unit as one of its items, a remark beside it ("Speed (rpm, mean)")
    bracketed = rf"[(\[](?:[^()\[\]]*[,;])?\s*(?:in\s+)?{u}\s*(?:[,;][^()\[\]]*)?[)\]]"
    last = rf"(?:(?<![^\W_])in\s+|[/,:_]\s*){u}\s*(?:[(\[][^()\[\]]*[)\]]\s*)?$"
    if re.search(bracketed, text) or re.search(last, text):
        return text
    return f"{text} ({unit})"


def check_axes(axes: object, n: int, who: str, what: str = "") -> list[Axes]:
    """``axes`` as a list of ``n`` matplotlib Axes, or ``TypeError``/``ValueError`` naming ``axes``."""
    axs = check_sequence(axes, f"{who}: axes", f"a sequence of {n} matplotlib Axes{what}")
    if len(axs) != n:
        raise ValueError(f"{who}: axes must hold {n} Axes{what}, got {len(axs)}")
    bad = [type(a).__name__ for a in axs if not isinstance(a, Axes)]
    if bad:
        raise TypeError(f"{who}: axes must hold matplotlib Axes, got {', '.join(bad)}")
    return axs

def _model_of(c: object) -> bool:
    """Whether ``c`` is a Model or a result that carries one (drawn as the model's static curve)."""
    return isinstance(c, Model) or isinstance(getattr(c, "model", None), Model)


class _ModelCurve:
    """A model's static curve as a line of :func:`plot_static_curve`: over the points' range (it has no domain),
    NaN where no equilibrium is reached, named as the model."""

    domain = None

    def __init__(self, model: Model) -> None:
        self.model, self.name = model, model.name or "model"

    def __call__(self, ubar: np.ndarray) -> np.ndarray:
        return self.model.static_curve(ubar, strict=False)


def plot_static_curve(
    points: StaticPoints | None = None,
    curve: StaticCurve | Model | Sequence[StaticCurve | Model] | None = None,
    *,
    ax: Axes | None = None,
    xlabel: str = "input ū",
    ylabel: str = "output ȳ",
    n_grid: int = 200,
    margin: float = 0.05,
) -> Figure:
    """Static curve(s) drawn as lines and measured static points as asterisks (Fig. 2).

    Parameters
    ----------
    points : StaticPoints, optional
        Measured steady states (ū_i, ȳ_i), drawn as ``*`` markers without a line.
    curve : StaticCurve, Model or a sequence of them, optional
        Curves drawn as lines over their domain (a curve without a domain is drawn over the
        points' range, widened by ``margin``); a Model (or a result carrying one) is drawn as its
        static curve over the points' range, NaN where it reaches no equilibrium.
    ax : matplotlib Axes, optional
        Draw here; by default a new 6.4 × 4.2 in figure is made.
    xlabel, ylabel : str
        Axis labels; the points' ``units`` are appended (``"input ū (rpm)"``) unless the label
        names them already (``"Pump speed (rpm)"``). Points without units: the labels as given.
    n_grid : int
        Points per curve.
    margin : float
        Relative widening of the points' range for curves without a domain.

    Returns
    -------
    matplotlib.figure.Figure
        One line per curve, then one marker-only line for the points; a legend when there is
        anything to label.

    Raises
    ------
    ValueError
        When there is nothing to draw, or a curve has no domain and there are no points.
    TypeError
        ``points`` that are not :class:`~graybox.StaticPoints` (a Dataset's are ``data.static``), a
        ``curve`` that is not a :class:`~graybox.StaticCurve` or Model (or a sequence of them).
    ValueError
        Points that vary several inputs (draw them with :func:`plot_surface_slices`); points that
        hold all inputs but one (a transient input's z̄ = 0 beside ū) are drawn against that one.
    """
    levels, varied = varied_input_levels(points, "plot_static_curve")
    if varied is not None and xlabel == "input ū":
        xlabel = f"input {varied}"
    curves = [] if curve is None else ([curve] if isinstance(curve, StaticCurve) or _model_of(curve) else None)
    if curves is None:
        given = list(curve) if isinstance(curve, Sequence) and not isinstance(curve, str) else [curve]
        bad = [type(c).__name__ for c in given if not (isinstance(c, StaticCurve) or _model_of(c))]
        if bad:
            raise TypeError(f"curve must be a StaticCurve, a Model or a sequence of them, got {', '.join(bad)}")
        curves = given
    # a model (or a result carrying one) is drawn as its static curve: NaN where it reaches no equilibrium
    curves = [_ModelCurve(as_model(c, "curve")) if _model_of(c) else c for c in curves]
    if points is None and not curves:
        raise ValueError("plot_static_curve: give static points, a curve, or both")
    n_grid = check_count(n_grid, "n_grid", low=2)
    margin = check_real(margin, "margin", low=0)
    fig, ax = _figure(ax, (6.4, 4.2))
    for c in curves:
        if c.domain is not None:
            lo, hi = c.domain
        elif points is not None:
            lo, hi = float(levels.min()), float(levels.max())
            pad = margin * (hi - lo)
            lo, hi = lo - pad, hi + pad
        else:
            raise ValueError(f"plot_static_curve: {c.name} has no domain; give points to set the range")
        ub = np.linspace(lo, hi, n_grid)
        ax.plot(ub, c(ub), "-", label=legend_text(c.name))
    if points is not None:
        ax.plot(levels, points.ybar, "*", linestyle="none", markersize=9, color="k", label=legend_text(points.name))
    # the varied input's own unit (points holding all inputs but one: that one's)
    u_unit, y_unit = ("", "") if points is None else (
        input_unit(points.units, 0 if varied is None else points.input_names.index(varied)), points.units[1])
    ax.set_xlabel(unit_label(xlabel, u_unit))
    ax.set_ylabel(unit_label(ylabel, y_unit))
    ax.grid(True, alpha=0.3)
    if ax.get_legend_handles_labels()[0]:  # points or curves named "": nothing to label (matplotlib warned)
        ax.legend(loc="best")
    return fig


def plot_record(
    record: Record,
    *,
    input_label: str = "input",
    output_label: str = "output",
    start: int = 0,
    stop: int | None = None,
    axes: Sequence[Axes] | None = None,
) -> Figure:
    """A record's input (top) and output (bottom) against time, sharing the time axis (Fig. 3).

    Parameters
    ----------
    record : Record
        Input and output of shape (N,), sampled every ``record.Ts`` seconds (several inputs,
        shape (N, m): one line per input, named in a legend); the units in ``record.units`` are
        appended to the labels.
    input_label, output_label : str
        Axis labels without units (the record's units are appended unless a label names them).
    start, stop : int, optional
        Sample range to draw (default: all); the time axis keeps the record's time.
    axes : pair of Axes, optional
        Draw here (input, output); by default a new 8 × 5 in figure with two rows is made.

    Returns
    -------
    matplotlib.figure.Figure
        Two axes, one line each: the input drawn as steps held over each sample, the output as
        a line through the samples.
    """
    if not isinstance(record, Record):
        hint = " (pass data.ident or data.valid)" if isinstance(record, Dataset) else ""
        raise TypeError(f"record must be a Record, got {type(record).__name__}{hint}")
    n = len(record)
    start = check_int(start, "start", low=0)
    stop = n if stop is None else check_int(stop, "stop", low=1)
    if not (0 <= start < stop <= n):
        raise ValueError(f"plot_record: need 0 <= start < stop <= {n}, got start={start}, stop={stop}")
    if axes is None:
        fig = Figure(figsize=(8.0, 5.0), layout="constrained")
        ax_u, ax_y = fig.subplots(2, 1, sharex=True)
    else:
        ax_u, ax_y = check_axes(axes, 2, "plot_record", ", a pair (input, output)")
        fig = ax_u.figure
    t = record.t[start:stop]
    # the input is held over [t_k, t_k + Ts): draw it as steps, as the plant sees it
    if record.u.ndim == 1:
        ax_u.step(t, record.u[start:stop], where="post", label=input_label)
    else:  # several inputs: one line each, named in a legend (with its own unit where the inputs' differ)
        per = not isinstance(record.units[0], str)
        for j, nm in enumerate(record.input_names):
            ax_u.step(t, record.u[start:stop, j], where="post",
                      label=legend_text(unit_label(nm, input_unit(record.units, j)) if per else nm))
        ax_u.legend(loc="best", fontsize="small")
    ax_y.plot(t, record.y[start:stop], "-", linewidth=0.8, label=output_label)
    u_unit, y_unit = ("" if not isinstance(record.units[0], str) else record.units[0]), record.units[1]
    ax_u.set_ylabel(unit_label(input_label, u_unit))
    ax_y.set_ylabel(unit_label(output_label, y_unit))
    ax_y.set_xlabel("Time (s)")
    ax_u.set_title(record.name)
    for a in (ax_u, ax_y):
        a.grid(True, alpha=0.3)
    return fig


def _figure(ax: Axes | None, size: tuple[float, float]) -> tuple[Figure, Axes]:
    if ax is not None:
        if not isinstance(ax, Axes):
            raise TypeError(f"ax must be a matplotlib Axes, got {type(ax).__name__}")
        return ax.figure, ax
    fig = Figure(figsize=size, layout="constrained")
    return fig, fig.add_subplot()
