"""Pareto fronts in the style of the paper's Figs. 5 and 7: J_SF against J_S.

Each front is drawn as markers (its non-dominated members joined by a line), single models
(ELS, CLS, a D_SF choice, …) as large labelled markers, and the uncertainty band B of D_SF as
a shaded strip. Figures are built with :class:`matplotlib.figure.Figure` directly (no pyplot
state); pass ``ax`` to draw into an existing figure.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..core._reprs import squared_unit
from ..core._validation import check_bool, check_real, check_sequence
from ..estimation._pareto import ParetoSet, nondominated_mask
from ._data import legend_text

__all__ = ["plot_pareto"]

_MARKERS = ("o", "s", "^", "v", "D", "P", "X", "*")


def _points_of(points) -> dict[str, tuple[float, float]]:
    """Accept {name: (J_S, J_SF)} or a Table-I DataFrame (columns "JS_ident", "JSF")."""
    if points is None:
        return {}
    if isinstance(points, pd.DataFrame):
        missing = {"JS_ident", "JSF"} - set(points.columns)
        if missing:
            raise ValueError(f"points: a table of models needs columns 'JS_ident' and 'JSF'; missing {sorted(missing)}")
        return {str(k): (float(r["JS_ident"]), float(r["JSF"])) for k, r in points.iterrows()}
    what = "a mapping name -> (J_S, J_SF) or a DataFrame with columns 'JS_ident' and 'JSF'"
    seq = points if isinstance(points, Mapping) else check_sequence(points, "points", what)
    try:
        given = dict(seq)
    except (TypeError, ValueError):  # items that are not (name, value) pairs
        raise TypeError(f"points must be {what}, got {points!r}") from None
    out = {}
    for k, v in given.items():
        try:
            js, jsf = (float(x) for x in v)
        except (TypeError, ValueError):
            raise ValueError(f"points: point {k!r} must be (J_S, J_SF), got {v!r}") from None
        out[str(k)] = (js, jsf)
    return out


def _why_not_drawn(js: float, jsf: float, log: bool) -> str:
    """Why a point (J_S, J_SF) is not drawn: an infinite or undefined J, or one at or below 0 on a log axis."""
    why = []
    for name, v in (("J_S", js), ("J_SF", jsf)):
        if np.isnan(v):
            why.append(f"{name} undefined")
        elif np.isinf(v):
            why.append(f"{name} = {v:g}")
        elif log and v <= 0:
            why.append(f"{name} = {v:g} on a log axis")
    return ", ".join(why)


def plot_pareto(
    fronts: ParetoSet | Mapping[str, ParetoSet],
    points: Mapping[str, tuple[float, float]] | pd.DataFrame | None = None,
    *,
    band: float | None = None,
    ax: Axes | None = None,
    log: bool = True,
    xlabel: str | None = None,
    ylabel: str | None = None,
    title: str | None = None,
) -> Figure:
    """J_SF against J_S of Pareto sets and single models (Figs. 5 and 7).

    Parameters
    ----------
    fronts : ParetoSet or mapping name -> ParetoSet
        Sets to draw; every member is a small marker, the non-dominated ones (in J_S, J_SF)
        are joined by a line. Members that failed or have an infinite J (or, on log axes, one at
        or below 0) are left out, counted in the legend with the reason.
    points : mapping name -> (J_S, J_SF), or DataFrame, optional
        Single models such as ELS and CLS, drawn as large markers with their names; a table
        from :func:`graybox.evaluate` works too (its ``JS_ident`` and ``JSF``).
    band : float or None
        Shade J_SF in B = [0, band] (D_SF's band, output units², e.g. ``data.static.band``);
        None (default) draws no band.
    ax : matplotlib Axes, optional
        Draw here; by default a new 6.4 × 4.6 in figure is made.
    log : bool
        Logarithmic axes (the errors span decades).
    xlabel, ylabel : str, optional
        Axis labels; default ``"J_S (mlc²)"`` and ``"J_SF (mlc²)"`` in the output unit the fronts
        carry (their ``units``), ``"(output units²)"`` when they carry none or differ.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    if not isinstance(fronts, (ParetoSet, Mapping)):
        raise TypeError(f"fronts must be a ParetoSet or a mapping name -> ParetoSet, got {type(fronts).__name__}")
    sets = {"": fronts} if isinstance(fronts, ParetoSet) else dict(fronts)
    for k, v in sets.items():
        if not isinstance(v, ParetoSet):
            raise TypeError(f"front {k!r} must be a ParetoSet, got {type(v).__name__}")
    log = check_bool(log, "log")
    if band is not None:
        band = check_real(band, "band", low=0, low_open=True)
    pts = _points_of(points)
    # J_S and J_SF are in the output unit squared: the fronts' own where they all name the same one
    named = {ps.units[1] for ps in sets.values()}
    sq = (squared_unit(named.pop()).strip() if len(named) == 1 else "") or "output units²"
    xlabel = f"J_S ({sq})" if xlabel is None else xlabel
    ylabel = f"J_SF ({sq})" if ylabel is None else ylabel
    if not sets and not pts:
        raise ValueError("nothing to plot: give at least one front or one point")
    if ax is None:
        fig = Figure(figsize=(6.4, 4.6))
        ax = fig.add_subplot()
    else:
        if not isinstance(ax, Axes):
            raise TypeError(f"ax must be a matplotlib Axes, got {type(ax).__name__}")
        fig = ax.figure
    for i, (name, ps) in enumerate(sets.items()):
        js, jsf = ps.JS, ps.JSF
        ok = np.isfinite(js) & np.isfinite(jsf)
        if log:
            ok &= (js > 0) & (jsf > 0)
        label = legend_text(name or ps.method or "Pareto set")
        if not len(ps):  # an empty set (a subset of none, the non-dominated of a set whose members all failed)
            label += " (no members)"
        if (~ok).any():  # failed members (J = inf), diverged ones, or J <= 0 on log axes: each reason counted
            whys = ["failed" if i in ps.failures else _why_not_drawn(js[i], jsf[i], log) for i in np.flatnonzero(~ok)]
            label += f" ({int((~ok).sum())} not drawn: " + "; ".join(
                f"{whys.count(w)} {w}" if len(set(whys)) > 1 else w for w in dict.fromkeys(whys)) + ")"
        mk = _MARKERS[i % len(_MARKERS)]
        line = ax.plot(js[ok], jsf[ok], mk, ms=4, alpha=0.45, label=label)[0]
        if ok.any():
            nd = nondominated_mask(np.column_stack([js[ok], jsf[ok]]))
            order = np.argsort(js[ok][nd])
            ax.plot(js[ok][nd][order], jsf[ok][nd][order], "-", color=line.get_color(), lw=1.2)
    for j, (name, (js, jsf)) in enumerate(pts.items()):
        drawable = np.isfinite(js) and np.isfinite(jsf) and (not log or (js > 0 and jsf > 0))
        if not drawable:  # say so in the legend rather than leave an entry without a marker
            ax.plot([], [], _MARKERS[(j + 3) % len(_MARKERS)], ms=10, mec="k",
                    label=f"{legend_text(name)} (not drawn: {_why_not_drawn(js, jsf, log)})")
            continue
        ax.plot([js], [jsf], _MARKERS[(j + 3) % len(_MARKERS)], ms=10, mec="k", label=legend_text(name), zorder=5)
        ax.annotate(name, (js, jsf), textcoords="offset points", xytext=(6, 6), fontsize=9)
    drawn = any(ln.get_xdata().size for ln in ax.lines)
    if log:
        if not drawn:  # every J infinite: no data limits, and a log axis cannot take matplotlib's (0, 1)
            ax.set_xlim(0.1, 10.0)
            ax.set_ylim(*((0.1, 10.0) if band is None else (band / 100, band * 10)))
        ax.set_xscale("log")
        ax.set_yscale("log")
    elif not drawn:  # no member or point drawn: errors from 0, not matplotlib's (-0.055, 0.055) about nothing
        ax.set_xlim(0.0, 1.0)
        ax.set_ylim(0.0, 1.0 if band is None else band * 1.5)
    if band is not None:
        band = check_real(band, "band", low=0, low_open=True)
        lo, hi = ax.get_ylim()
        if band <= lo:  # a band below every member is brought into the panel (else the legend names no shade seen)
            lo = band / 3 if log else 0.0
        ax.axhspan(lo if log else 0.0, band, color="0.85", zorder=0, label=f"B = [0, {band:g}]")
        ax.set_ylim(lo, max(hi, band))
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    return fig
