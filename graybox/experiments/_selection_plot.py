"""A picture of a :func:`graybox.select_graybox` choice: why that row, and how it fared.

Built with :class:`matplotlib.figure.Figure` directly (no pyplot state), as every graybox figure.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from ..core._reprs import beside, bound_text, squared_unit
from ..plots._data import check_axes
from ._report import _MARKERS, _band_on, _finite_pos, _scale
from ._select import GrayboxSelection

__all__ = ["plot_selection"]


def plot_selection(selection: GrayboxSelection, *, axes: Sequence[Axes] | None = None, title: str | None = None
                   ) -> Figure:
    """Every row :func:`graybox.select_graybox` compared, against its number of terms, in two or three panels.

    1. **The rule.** Each row's J_S on the choosing data over the best row's (dimensionless, 1 = the
       best row) with ± one standard error of that ratio's log over the blocks. A row whose bar reaches 1
       (or lies below it) is within one standard error of the best: eligible, drawn filled (hollow
       otherwise); ``rule="one-se"`` takes the fewest terms among them. Rows without a qualifying model are
       left out and counted.
    2. **The static error.** J_SF of each row's member (output units²), the band B shaded (gray
       boxes; left out when no row has a J_SF, as for a black box without static points).
    3. **The test record**, when the selection was given one: each row's J_S there (output
       units²). Nothing in it took part in the choice; it shows what the choice cost against
       the best row on new data (the regret).

    One marker per estimator; the chosen row is ringed in red on every panel. When no row meets
    the band and ``fallback="min_jsf"`` chose the smallest J_SF, the titles say so (the rule
    panel is then empty: no row qualified).

    Parameters
    ----------
    selection : GrayboxSelection
        From :func:`graybox.select_graybox` (or loaded with :func:`graybox.load`).
    axes : sequence of Axes, optional
        Draw here, one Axes per panel (2, or 3 with a test record); by default a new figure with
        the panels side by side is made.
    title : str, optional
        Figure title (default: the chosen row, its estimator and the rule; with ``axes`` given, the
        figure's own title is left as it is unless ``title`` is given).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if not isinstance(selection, GrayboxSelection):
        raise TypeError(f"selection must be a GrayboxSelection (from select_graybox), got {type(selection).__name__}")
    t = selection.table
    panels = ["rule"]
    if np.isfinite(t["JSF"].to_numpy(float)).any():
        panels.append("static")
    if "JS_test" in t.columns:
        panels.append("test")
    if axes is None:
        fig = Figure(figsize=(4.6 * len(panels), 4.2), layout="constrained")
        axs = list(fig.subplots(1, len(panels), squeeze=False)[0])
    else:
        # the count a ValueError, an item that is no Axes a TypeError (as every plot's axes are checked)
        axs = check_axes(axes, len(panels), "plot_selection", f" (panels {panels})")
        fig = axs[0].figure
    chosen = selection.chosen
    estimators = list(dict.fromkeys(t["estimator"]))
    mark = {e: _MARKERS[i % len(_MARKERS)] for i, e in enumerate(estimators)}
    color = {e: f"C{i % 10}" for i, e in enumerate(estimators)}
    n = t["n_terms"].to_numpy(float)
    est = t["estimator"].to_numpy()
    elig = t["eligible"].to_numpy(bool) if "eligible" in t.columns else np.zeros(len(t), bool)
    has_model = np.isfinite(t["JS_valid"].to_numpy(float))
    sq = squared_unit(selection.model.units[1]).strip() or "output units²"  # J_S and J_SF: the model's output unit²
    for ax, panel in zip(axs, panels):
        if panel == "rule":
            vs = t["vs_best"].to_numpy(float) if "vs_best" in t.columns else np.full(len(t), np.nan)
            se = t["vs_best_se"].to_numpy(float) if "vs_best_se" in t.columns else np.full(len(t), np.nan)
            y, ok = np.exp(vs), has_model & np.isfinite(vs)
            values = y[ok]
            err = np.where(np.isfinite(se), se, 0.0)  # no error bar where one block only was cut
            _points(ax, est, elig, ok, n, y, mark, color, (y - np.exp(vs - err), np.exp(vs + err) - y))
            ax.axhline(1.0, color="0.45", lw=0.8, ls="--", zorder=1)
            ax.set_ylabel("J_S on the choosing data / the best row's")
            ax.set_title(f"rule {selection.rule!r}: {int(ok.sum())} of {len(t)} rows drawn" if selection.in_band else
                         f"no row meets the band B = {selection.band:g}: no J_S rule chose", fontsize=9)
            _ring(ax, chosen["n_terms"], np.exp(chosen["vs_best"]) if "vs_best" in t.columns else np.nan)
        elif panel == "static":
            jsf = t["JSF"].to_numpy(float)
            ok = _finite_pos(jsf)
            values = jsf[ok]
            _points(ax, est, elig, ok, n, jsf, mark, color)
            ax.set_ylabel(f"J_SF of the row's member ({sq})")
            ax.set_title(f"static error: {int(ok.sum())} of {len(t)} rows drawn"
                         + ("" if selection.in_band else "; the choice: the smallest J_SF"), fontsize=9)
            _ring(ax, chosen["n_terms"], chosen["JSF"])
        else:
            js = t["JS_test"].to_numpy(float)
            ok = _finite_pos(js)
            values = js[ok]
            _points(ax, est, elig, ok, n, js, mark, color)
            ax.set_ylabel(f"J_S on the test record ({sq})")
            try:
                # above 1 never printed as 1 ('1×' said no row did better)
                said = f"the choice is {beside(selection.regret, 1.0, 3)}× the best row it compared"
            except ValueError:
                said = "every row's free run diverged there"
            ax.set_title(f"test record (not used to choose):\n{said}", fontsize=9)  # one line ran off the figure
            _ring(ax, chosen["n_terms"], chosen["JS_test"])
        _scale(ax, "y", values)
        if not values.size:  # empty axes would show a scale (matplotlib's 0 to 1) of values no row has
            ax.text(0.5, 0.5, "no row to draw", transform=ax.transAxes, ha="center", va="center", color="0.4",
                    fontsize=8)
            ax.set_yticks([])
        if panel == "static" and np.isfinite(selection.band):
            _band_on(ax, selection.band, label=True)
        ax.set_xlabel("terms")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.grid(True, which="major", alpha=0.3)
        if ax.get_legend_handles_labels()[0]:  # a panel with no row drawn has nothing to name
            ax.legend(fontsize=7, loc="best")
    said = f"chosen: {chosen.name} by {chosen['estimator']} ({int(chosen['n_terms'])} terms)"
    if not selection.in_band:  # fallback "min_jsf": the J_S rule had no row to choose from
        said += (f",\nthe smallest J_SF reached, {beside(chosen['JSF'], selection.band)}: no row meets the band "
                 f"B = {bound_text(selection.band, chosen['JSF'])} (fallback 'min_jsf')")
    if title is not None or axes is None:  # drawn into the caller's axes: their figure keeps its own title
        fig.suptitle(str(title) if title is not None else said, fontsize=10)
    return fig


def _points(ax: Axes, est: np.ndarray, elig: np.ndarray, ok: np.ndarray, n: np.ndarray, y: np.ndarray, mark: dict,
            color: dict, yerr: tuple[np.ndarray, np.ndarray] | None = None) -> None:
    """The rows ``ok``: one marker per estimator, filled where the row was eligible; error bars ``yerr``
    (below, above) when given."""
    for e in mark:
        for yes in (True, False):
            m = ok & (est == e) & (elig == yes)
            if m.any():
                ax.errorbar(n[m], y[m], yerr=None if yerr is None else [yerr[0][m], yerr[1][m]], fmt=mark[e],
                            color=color[e], ms=6, capsize=2, lw=0.8, mfc=color[e] if yes else "none",
                            label=f"{e} ({'eligible' if yes else 'not eligible'})")


def _ring(ax: Axes, x: float, y: float) -> None:
    """The chosen row, ringed in red."""
    if np.isfinite(y) and y > 0:
        ax.plot([x], [y], "o", ms=14, mfc="none", mec="red", mew=1.5, label="chosen", zorder=5)
