"""Pictures for trusting a model: residual correlation tests, static-curve bands, decision bootstrap.

Built with :class:`matplotlib.figure.Figure` directly (no pyplot state), like the other plots.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from .._records import StaticPoints
from .._residuals import ResidualTests
from .._uncertainty import StaticCurveBand

__all__ = ["plot_residual_tests", "plot_static_band"]


def plot_residual_tests(
    tests: ResidualTests,
    axes: Sequence[Axes] | None = None,
    title: str | None = None,
) -> Figure:
    """The five correlation tests as five stacked panels, with their bands.

    Parameters
    ----------
    tests : ResidualTests
        From :func:`graybox.residual_tests`.
    axes : sequence of 5 Axes, optional
        Draw here; by default a new 7 × 9 in figure with five rows is made.
    title : str, optional
        Figure title (default: the model's name and the verdict).

    Returns
    -------
    matplotlib.figure.Figure
        Per panel: φ(τ) as stems, the pointwise band ±z/√N (dashed, 1.96/√N at 95 %) and, with the
        simultaneous rule, the limit the verdict uses (dotted); the panel title says pass or FAIL.
    """
    if not isinstance(tests, ResidualTests):
        raise ValueError(f"plot_residual_tests needs a ResidualTests, got {type(tests).__name__}")
    items = list(tests.tests.values())
    if axes is None:
        fig = Figure(figsize=(7.0, 9.0), layout="constrained")
        axs = fig.subplots(len(items), 1)
    else:
        axs = list(axes)
        if len(axs) != len(items):
            raise ValueError(f"plot_residual_tests: axes must hold {len(items)} Axes, got {len(axs)}")
        fig = axs[0].figure
    for ax, t in zip(axs, items):
        bad = np.abs(t.phi) > t.limit
        ax.vlines(t.lags, 0.0, t.phi, color="C0", lw=1.2)
        ax.plot(t.lags[~bad], t.phi[~bad], "o", ms=3, color="C0")
        if bad.any():
            ax.plot(t.lags[bad], t.phi[bad], "o", ms=4, color="C3", label="beyond the limit")
        ax.axhline(0.0, color="k", lw=0.6)
        for s in (-1, 1):
            ax.axhline(s * t.band, color="0.4", ls="--", lw=0.9,
                       label=f"±{t.band:.3g} ({tests.level:.0%} pointwise)" if s > 0 else None)
            if t.limit != t.band:
                ax.axhline(s * t.limit, color="0.4", ls=":", lw=0.9,
                           label=f"±{t.limit:.3g} ({tests.level:.0%} for the test)" if s > 0 else None)
        top = max(1.2 * float(np.max(np.abs(t.phi))), 1.5 * t.limit)
        ax.set_ylim(-min(top, 1.05), min(top, 1.05))
        ax.set_ylabel(t.label)
        ax.set_title(f"{t.label}: {'pass' if t.passed else 'FAIL'}", fontsize=9, loc="left")
        ax.grid(True, alpha=0.3)
    axs[-1].set_xlabel("lag τ (samples)")
    axs[0].legend(fontsize=7, loc="upper right")
    if axes is None:
        verdict = "all tests passed" if tests.passed else f"{len(tests.failed)} test(s) failed"
        fig.suptitle(title or f"{tests.model_name or 'model'}: residual correlation tests, N = {tests.n} ({verdict})",
                     fontsize=10)
    return fig


def plot_static_band(
    band: StaticCurveBand,
    points: StaticPoints | None = None,
    gain: bool = True,
    axes: Sequence[Axes] | None = None,
    xlabel: str = "Pump speed (rpm)",
    ylabel: str = "Pressure (mlc)",
    gain_label: str = "static gain (mlc/rpm)",
) -> Figure:
    """The static curve with its confidence band (shaded) and the static points; the gain beside it.

    Parameters
    ----------
    band : StaticCurveBand
        From :func:`graybox.static_curve_band`.
    points : StaticPoints, optional
        Measured steady states, drawn as ``*`` markers.
    gain : bool
        Add a second panel with the static gain and its band.
    axes : sequence of Axes, optional
        Draw here (one Axes, or two with ``gain``); by default a new figure is made.
    xlabel, ylabel, gain_label : str
        Axis labels (defaults: the pumping plant's).

    Returns
    -------
    matplotlib.figure.Figure
        The curve as a line over its shaded band (with the level and method in the legend), the
        points as asterisks; the gain panel likewise.
    """
    if not isinstance(band, StaticCurveBand):
        raise ValueError(f"plot_static_band needs a StaticCurveBand, got {type(band).__name__}")
    need = 2 if gain else 1
    if axes is None:
        fig = Figure(figsize=(10.0 if gain else 6.4, 4.0), layout="constrained")
        axs = list(np.atleast_1d(fig.subplots(1, need)))
    else:
        axs = list(axes)
        if len(axs) != need:
            raise ValueError(f"plot_static_band: axes must hold {need} Axes, got {len(axs)}")
        fig = axs[0].figure
    what = f"{band.level:.0%} band ({band.method})"
    name = band.model_name or "model"
    ax = axs[0]
    ax.fill_between(band.ubar, band.ybar_low, band.ybar_high, color="C0", alpha=0.25, lw=0, label=what)
    ax.plot(band.ubar, band.ybar, "-", color="C0", label=f"{name} static curve")
    if points is not None:
        ax.plot(points.ubar, points.ybar, "*", linestyle="none", markersize=9, color="k", label=points.name)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    if gain:
        ax = axs[1]
        ax.fill_between(band.ubar, band.gain_low, band.gain_high, color="C1", alpha=0.25, lw=0, label=what)
        ax.plot(band.ubar, band.gain, "-", color="C1", label=f"{name} static gain")
        ax.set_xlabel(xlabel)
        ax.set_ylabel(gain_label)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    return fig
