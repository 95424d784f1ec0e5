"""Pictures of static surfaces ȳ(ū₁, ū₂): slices against one input, and contour maps, with static points.

A *surface* here is anything that maps constant inputs of shape (K, 2) to outputs of shape (K,):
a :class:`~graybox.StaticSurface`, a model of two inputs (its static surface), or a plant's
theoretical one (``lambda U: plant.static_pressure(U[:, 0], U[:, 1])``). Its ``name`` attribute,
when it has one, labels it; a ``domain`` attribute (one (low, high) per input) sets the default
ranges. A surface that names its inputs (``input_names``, as a StaticSurface does) is called with
its columns taken by name from the plot's inputs (the points', else the first named surface's), so
points in another column order draw the same surface on swapped axes; a surface of other inputs is
refused.
"""

from __future__ import annotations

import numbers
from typing import Callable, Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..core._records import check_units, input_unit
from ..core._validation import check_count, check_int, check_real, check_sequence
from ..core._reprs import level_texts
from ..models._coerce import as_model
from ..models._model import Model
from ._data import SLICES_NAMED, distinct_colours, legend_every, legend_text, on_level, unit_label

__all__ = ["plot_surface_slices", "plot_surface_contours"]

Surface = Callable[[np.ndarray], np.ndarray]


class _ModelSurface:
    """A model's static surface as a plot's surface: its ``static_curve`` (NaN where no equilibrium is reached, as
    a picture shows it), named as the model and its inputs."""

    def __init__(self, model: Model) -> None:
        if model.n_inputs != 2:
            raise ValueError(f"surface: model {model.name!r} has {model.n_inputs} input(s) {model.input_names}: "
                             + ("a model of one input has no surface (plot_static_curve draws its curve)"
                                if model.n_inputs == 1 else "a surface is drawn over two inputs"))
        self.model, self.name, self.input_names = model, model.name or "model", model.input_names

    def __call__(self, U: np.ndarray) -> np.ndarray:
        return self.model.static_curve(U, strict=False)


def _surface(s: object) -> Surface:
    """One surface: a callable as it is, a Model (or a result carrying one) as its static surface."""
    if isinstance(s, Model) or (not callable(s) and isinstance(getattr(s, "model", None), Model)):
        return _ModelSurface(as_model(s, "surface"))  # type: ignore[arg-type]
    if not callable(s):
        raise TypeError(f"surface: each surface must be callable on ū of shape (K, 2) or a Model, got "
                        f"{type(s).__name__}")
    return s  # type: ignore[return-value]


def _surfaces(surface: Surface | Sequence[Surface] | None) -> list[Surface]:
    if surface is None:
        return []
    if callable(surface) or isinstance(surface, Model) or isinstance(getattr(surface, "model", None), Model):
        return [_surface(surface)]
    out = check_sequence(surface, "surface", "a callable on ū of shape (K, 2), a Model, or a sequence of them")
    return [_surface(s) for s in out]


def _against(against: object, names: tuple[str, ...] | None) -> int:
    """The input on the horizontal axis, 0 or 1: by position, or by the name the points (else a surface) give it."""
    if isinstance(against, str):
        if names is None:
            raise ValueError(f"against={against!r} names an input, but neither the points nor the surfaces name "
                             "theirs: give its position, 0 or 1")
        if against not in names:
            raise ValueError(f"against={against!r} names no input of {names}")
        return names.index(against)
    return check_int(against, "against (the input on the horizontal axis)", low=0, high=1)


def _input_labels(labels: object, names: tuple[str, ...] | None = None) -> tuple:
    """The two inputs' labels (any values, shown with str()), or an error naming ``input_labels``; None: "input
    <name>" where the points or a surface name their inputs (as plot_static_band labels them), else ū₁ and ū₂."""
    if labels is None:
        return tuple(f"input {n}" for n in names) if names is not None else ("input ū₁", "input ū₂")
    out = tuple(check_sequence(labels, "input_labels", "a pair of labels (ū₁, ū₂)"))
    if len(out) != 2:
        raise ValueError(f"input_labels must be a pair of labels (ū₁, ū₂), got {len(out)}")
    return out


def _pair(given: object, name: str) -> tuple[float, float]:
    """A (low, high) range given by the caller, as floats, or an error naming it."""
    pair = check_sequence(given, name, "a pair (low, high)")
    if len(pair) != 2:
        raise ValueError(f"{name} must be a pair (low, high), got {len(pair)} values")
    lo = check_real(pair[0], f"{name}[0] (low)")
    return lo, check_real(pair[1], f"{name}[1] (high)", low=lo, low_open=True)


def _name(s: Surface, i: int) -> str:
    return str(getattr(s, "name", None) or f"surface {i + 1}")


def _surface_inputs(s: Surface) -> tuple[str, ...] | None:
    """The names a surface gives its two columns (a StaticSurface's ``input_names``), or None (a bare function)."""
    names = getattr(s, "input_names", None)
    if isinstance(names, (tuple, list)) and len(names) == 2 and all(isinstance(n, str) for n in names):
        return tuple(names)
    return None


def _plot_inputs(surfaces: list[Surface], points: object) -> tuple[str, ...] | None:
    """The inputs the plot's columns are, by name: the points' (the data's order), else the first named surface's."""
    names = getattr(points, "input_names", None)
    if not (isinstance(names, (tuple, list)) and len(names) == 2):
        names = next((n for n in map(_surface_inputs, surfaces) if n is not None), None)
    for i, s in enumerate(surfaces):
        _columns(s, i, names)  # a surface of other inputs is refused before any range is read off it
    return None if names is None else tuple(names)


def _columns(s: Surface, i: int, names: tuple[str, ...] | None) -> list[int] | None:
    """Which of the plot's columns feed the surface's, in its order (None: as they are). A surface is called
    with its own inputs in its own order, so points in another column order draw the same picture with the axes
    swapped; a surface of other inputs than the points' is refused, naming both."""
    own = _surface_inputs(s)
    if own is None or names is None or own == names:
        return None
    if set(own) != set(names):
        raise ValueError(f"{_name(s, i)} is a surface in the inputs {own} but the plot's inputs are {names}: "
                         "draw a surface with the static points of its own inputs")
    return [names.index(n) for n in own]


def _points(points: object) -> tuple[np.ndarray, np.ndarray, str, tuple] | None:
    if points is None:
        return None
    ub = np.asarray(getattr(points, "ubar", None), dtype=float)
    yb = np.asarray(getattr(points, "ybar", None), dtype=float)
    if ub.ndim != 2 or ub.shape[1] != 2 or yb.shape != (ub.shape[0],):
        raise ValueError(f"static points must have ubar of shape (K, 2) and ybar of shape (K,), got {ub.shape} "
                         f"and {yb.shape}")
    # units as the points say them (check_units' form: the inputs' one unit or one per column)
    units = check_units(getattr(points, "units", ("", "")), "static points")
    return ub, yb, str(getattr(points, "name", "static points")), units


def _domain(s: Surface, i: int, names: tuple[str, ...] | None) -> tuple[float, float] | None:
    """The surface's (low, high) for the plot's input ``i`` (its own column of that name), or None."""
    dom = getattr(s, "domain", None)
    if dom is None:
        return None
    own = _surface_inputs(s)
    j = i if own is None or names is None else own.index(names[i])
    return float(dom[j][0]), float(dom[j][1])


def _range(i: int, surfaces: list[Surface], pts, given: tuple[float, float] | None, margin: float,
           name: str = "urange", names: tuple[str, ...] | None = None) -> tuple[float, float]:
    if given is not None:
        lo, hi = _pair(given, name)
    elif pts is not None:
        lo, hi = float(pts[0][:, i].min()), float(pts[0][:, i].max())
        pad = margin * (hi - lo)
        lo, hi = lo - pad, hi + pad
        for s in surfaces:  # never draw a surface beyond its own domain
            dom = _domain(s, i, names)
            if dom is not None:
                lo, hi = max(lo, dom[0]), min(hi, dom[1])
    else:
        doms = [d for d in (_domain(s, i, names) for s in surfaces) if d is not None]
        if not doms:
            raise ValueError(f"no range for input {i + 1}: give static points, a surface with a domain, or the range")
        lo, hi = max(d[0] for d in doms), min(d[1] for d in doms)
    if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
        raise ValueError(f"empty range for input {i + 1}: ({lo:g}, {hi:g})")
    return lo, hi


def _levels(levels: object) -> int | np.ndarray:
    """Contour levels: a count >= 1, or increasing finite output levels; errors name ``levels``."""
    if isinstance(levels, numbers.Real) or (isinstance(levels, np.ndarray) and levels.ndim == 0):
        return check_int(levels, "levels (a count)", low=1)
    items = check_sequence(levels, "levels", "a count or a sequence of output levels")
    out = np.array([check_real(v, f"levels[{k}]") for k, v in enumerate(items)])
    if out.size < 2 or np.any(np.diff(out) <= 0):  # filled contours lie between two levels (one: matplotlib's error)
        raise ValueError(f"levels must be two or more increasing output levels (filled contours lie between them), "
                         f"got {out.tolist()}")
    return out


def _evaluate(s: Surface, U: np.ndarray, i: int, names: tuple[str, ...] | None = None) -> np.ndarray:
    cols = _columns(s, i, names)
    y = np.asarray(s(U if cols is None else U[:, cols]), dtype=float).reshape(-1)
    if y.shape != (U.shape[0],):
        raise ValueError(f"{_name(s, i)} returned shape {y.shape} for {U.shape[0]} points; expected ({U.shape[0]},)")
    return y


def plot_surface_slices(
    surface: Surface | Sequence[Surface] | None = None,
    points: object | None = None,
    *,
    against: int | str = 0,
    at: Sequence[float] | None = None,
    urange: tuple[float, float] | None = None,
    ax: Axes | None = None,
    xlabel: str | None = None,
    ylabel: str = "output ȳ",
    input_labels: tuple[str, str] | None = None,
    n_grid: int = 100,
    margin: float = 0.0,
) -> Figure:
    """Slices of static surfaces: ȳ against one input with the other held at several levels.

    One colour per level of the held input; each surface has its own line style (solid, dashed,
    dotted, …), and the static points lying on a slice are drawn as ``*`` in its colour.

    Parameters
    ----------
    surface : callable, Model or a sequence of them, optional
        Surfaces mapping ū of shape (K, 2) to ȳ of shape (K,) (module docs); a Model of two inputs (or a
        result carrying one) is drawn as its static surface, NaN where no equilibrium is reached.
    points : StaticPoints, optional
        Static points with ``ubar`` of shape (K, 2); a point is drawn on the slice whose level its
        held input equals (to 1e-9 relative).
    against : {0, 1} or str
        The input on the horizontal axis (0: ū₁), or its name (the points', else a surface's); the
        other one is held.
    at : sequence of float, optional
        Levels of the held input; default: the distinct levels of the points' held input, else 5
        levels across the surfaces' domain.
    urange : (float, float), optional
        Range of the horizontal axis; default the points' range (widened by ``margin``), else the
        surfaces' domain.
    ax : matplotlib Axes, optional
        Draw here; by default a new 6.4 × 4.2 in figure is made.
    xlabel, ylabel : str
        Axis labels (default x: the label of input ``against``); the points' ``units`` are
        appended unless a label names them already.
    input_labels : (str, str), optional
        Labels of the two inputs (used for the axis and the legend's levels); default "input <name>" with the
        names the points (else a surface) give their inputs, else "input ū₁" and "input ū₂".
    n_grid : int
        Points per slice.
    margin : float
        Relative widening of the points' range.

    Returns
    -------
    matplotlib.figure.Figure
        One line per (surface, level), then one marker-only line per level that has points.
    """
    surfaces = _surfaces(surface)
    pts = _points(points)
    if not surfaces and pts is None:
        raise ValueError("plot_surface_slices: give a surface, static points, or both")
    n_grid = check_int(n_grid, "n_grid", low=2)
    check_count(n_grid, "n_grid", item_bytes=8 * n_grid)  # a grid of n_grid² points
    margin = check_real(margin, "margin", low=0)
    if input_labels is not None:
        _input_labels(input_labels)  # a bad pair refused before any other work, as plot_surface_contours does
    names = _plot_inputs(surfaces, points)
    against = _against(against, names)
    held = 1 - against
    input_labels = _input_labels(input_labels, names)
    if at is None:
        if pts is not None:
            levels = np.unique(pts[0][:, held])
        else:
            levels = np.linspace(*_range(held, surfaces, None, None, 0.0, names=names), 5)
    else:
        if isinstance(at, (bool, np.bool_, str)):
            raise TypeError(f"at must be levels of the held input (numbers), got {at!r}")
        try:
            levels = np.asarray(at, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise TypeError(f"at must be levels of the held input (numbers), got {at!r}") from None
        if levels.size == 0 or not np.all(np.isfinite(levels)):
            raise ValueError("at must hold at least one finite level")
    lo, hi = _range(against, surfaces, pts, urange, margin, names=names)
    if ax is None:
        fig = Figure(figsize=(6.4, 4.2), layout="constrained")
        ax = fig.add_subplot()
    else:
        if not isinstance(ax, Axes):
            raise TypeError(f"ax must be a matplotlib Axes, got {type(ax).__name__}")
        fig = ax.figure
    colors = distinct_colours(levels.size)
    styles = ["-", "--", ":", "-."]
    x = np.linspace(lo, hi, n_grid)
    texts = level_texts(levels)
    # one in this many levels named, beyond SLICES_NAMED lines in all
    every = legend_every(levels.size * max(1, len(surfaces)), SLICES_NAMED)
    for i, s in enumerate(surfaces):
        for k, (lev, text, col) in enumerate(zip(levels, texts, colors)):
            U = np.empty((n_grid, 2))
            U[:, against] = x
            U[:, held] = lev
            label = f"{_name(s, i)}, {input_labels[held]} = {text}" if len(surfaces) > 1 else \
                f"{input_labels[held]} = {text}"
            ax.plot(x, _evaluate(s, U, i, names), styles[i % len(styles)], color=col,
                    label=legend_text(label) if k % every == 0 else None)
    if pts is not None:
        ub, yb, pname, _ = pts
        labelled = False
        for lev, col in zip(levels, colors):
            on = on_level(ub[:, [held]], [lev])
            if on.any():
                # one legend entry for the points (their colour already names the level)
                ax.plot(ub[on, against], yb[on], "*", linestyle="none", markersize=9, color=col,
                        label=None if labelled else legend_text(pname))
                labelled = True
    u_unit, y_unit = ("", "") if pts is None else (input_unit(pts[3], against), pts[3][1])
    ax.set_xlabel(unit_label(xlabel if xlabel is not None else input_labels[against], u_unit))
    ax.set_ylabel(unit_label(ylabel, y_unit))
    ax.grid(True, alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="best", fontsize="small",
                  title=None if every == 1 else f"one in {every} of the {levels.size} levels", title_fontsize="small")
    return fig


def plot_surface_contours(
    surface: Surface,
    points: object | None = None,
    *,
    levels: int | Sequence[float] = 12,
    ranges: tuple[tuple[float, float], tuple[float, float]] | None = None,
    ax: Axes | None = None,
    input_labels: tuple[str, str] | None = None,
    output_label: str = "output ȳ",
    n_grid: int = 60,
    margin: float = 0.0,
    cmap: str = "viridis",
) -> Figure:
    """Contour map of one static surface over (ū₁, ū₂), with the static points coloured by ȳ.

    The points use the contours' colour scale, so a point whose colour differs from the map
    around it is one the surface misses; a colour bar gives the scale.

    Parameters
    ----------
    surface : callable or Model
        Maps ū of shape (K, 2) to ȳ of shape (K,) (module docs); a Model of two inputs (or a result
        carrying one) is drawn as its static surface, NaN where no equilibrium is reached.
    points : StaticPoints, optional
        Static points with ``ubar`` of shape (K, 2), drawn as filled circles.
    levels : int or sequence of float
        Number of contour levels, or the levels (output units; two or more, increasing).
    ranges : ((float, float), (float, float)), optional
        Ranges of ū₁ and ū₂; default the points' ranges (widened by ``margin``), else the
        surface's domain.
    ax : matplotlib Axes, optional
        Draw here; by default a new 6.0 × 4.8 in figure is made.
    input_labels : (str, str), optional
        Axis labels (the points' input unit appended unless a label names it); default "input <name>" with the
        names the points (else the surface) give their inputs, else "input ū₁" and "input ū₂".
    output_label : str
        Colour bar label (the points' output unit appended unless it names it).
    n_grid : int
        Grid points per input.
    margin : float
        Relative widening of the points' ranges.
    cmap : str
        Matplotlib colour map.

    Returns
    -------
    matplotlib.figure.Figure
        Filled contours, contour lines, the points (one scatter collection) and a colour bar.
    """
    surfaces = _surfaces(surface)
    if len(surfaces) != 1:
        raise ValueError("plot_surface_contours draws one surface; call it once per surface")
    s = surfaces[0]
    pts = _points(points)
    n_grid = check_int(n_grid, "n_grid", low=2)
    check_count(n_grid, "n_grid", item_bytes=8 * n_grid)  # a grid of n_grid² points
    margin = check_real(margin, "margin", low=0)
    if input_labels is not None:
        _input_labels(input_labels)  # a bad pair refused before any other work, as before
    levels = _levels(levels)
    if ranges is not None:
        ranges = check_sequence(ranges, "ranges", "two (low, high) pairs")
        if len(ranges) != 2:
            raise ValueError(f"ranges must be two (low, high) pairs, got {ranges!r}")
    names = _plot_inputs(surfaces, points)
    input_labels = _input_labels(input_labels, names)
    r1 = _range(0, surfaces, pts, None if ranges is None else ranges[0], margin, "ranges[0]", names)
    r2 = _range(1, surfaces, pts, None if ranges is None else ranges[1], margin, "ranges[1]", names)
    g1, g2 = np.linspace(*r1, n_grid), np.linspace(*r2, n_grid)
    G1, G2 = np.meshgrid(g1, g2)
    Z = _evaluate(s, np.column_stack([G1.ravel(), G2.ravel()]), 0, names).reshape(G1.shape)
    if ax is None:
        fig = Figure(figsize=(6.0, 4.8), layout="constrained")
        ax = fig.add_subplot()
    else:
        if not isinstance(ax, Axes):
            raise TypeError(f"ax must be a matplotlib Axes, got {type(ax).__name__}")
        fig = ax.figure
    filled = ax.contourf(G1, G2, Z, levels=levels, cmap=cmap)
    ax.contour(G1, G2, Z, levels=filled.levels, colors="k", linewidths=0.5, alpha=0.5)
    if pts is not None:
        ub, yb, pname, _ = pts
        ax.scatter(ub[:, 0], ub[:, 1], c=yb, cmap=cmap, norm=filled.norm, edgecolors="k", s=40, zorder=3,
                   label=legend_text(pname))
        if ax.get_legend_handles_labels()[0]:  # points named "": nothing to label (matplotlib warned), as in
            # plot_static_curve
            ax.legend(loc="upper left", fontsize="small")
    units = ("", "") if pts is None else pts[3]
    fig.colorbar(filled, ax=ax, label=unit_label(output_label, units[1]))
    ax.set_xlabel(unit_label(input_labels[0], input_unit(units, 0)))
    ax.set_ylabel(unit_label(input_labels[1], input_unit(units, 1)))
    ax.set_title(_name(s, 0))
    return fig
