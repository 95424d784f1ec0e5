"""Pictures for trusting a model: residual correlation tests, static-curve bands, decision bootstrap.

Built with :class:`matplotlib.figure.Figure` directly (no pyplot state), like the other plots.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..diagnostics._bootstrap import DecisionBootstrap
from ..core._records import StaticPoints, check_same_units, input_unit
from ..core._validation import check_bool, check_choice, check_int
from ..core._reprs import level_texts, per_unit, percent_text
from ._pareto import _why_not_drawn
from ._data import (SLICES_NAMED, check_axes, check_one_input_points, distinct_colours, legend_every, legend_text,
                    on_level, unit_label)
from ..diagnostics._residuals import ResidualTests, verdict_limit
from ..diagnostics._simulation_band import SimulationBand
from ..diagnostics._uncertainty import StaticCurveBand, StaticSurfaceBand

__all__ = ["plot_residual_tests", "plot_static_band", "plot_simulation_band", "plot_decision_bootstrap"]


def plot_residual_tests(
    tests: ResidualTests,
    *,
    axes: Sequence[Axes] | None = None,
    title: str | None = None,
) -> Figure:
    """The five correlation tests as five stacked panels, with their bands.

    Parameters
    ----------
    tests : ResidualTests
        From :func:`graybox.residual_tests`.
    axes : sequence of 5 Axes, optional
        Draw here; by default a new figure with one row per test (7 × 9 in for one input's five) is made.
    title : str, optional
        Figure title, also on the figure of ``axes`` (default: the model's name and the verdict, on a
        figure it makes).

    Returns
    -------
    matplotlib.figure.Figure
        Per panel: φ(τ) as stems, the pointwise band ±z/√N (dashed, 1.96/√N at 95 %) and, with the
        simultaneous rule, the limit the verdict uses (dotted); the panel title says pass or FAIL.
    """
    if not isinstance(tests, ResidualTests):
        raise TypeError(f"tests must be a ResidualTests (from residual_tests), got {type(tests).__name__}")
    items = list(tests.tests.values())
    if axes is None:
        fig = Figure(figsize=(7.0, 1.8 * len(items)), layout="constrained")  # 9 in for the five tests of one input
        axs = list(fig.subplots(len(items), 1, squeeze=False)[:, 0])  # a set of one test: one Axes, not an array
    else:
        axs = check_axes(axes, len(items), "plot_residual_tests")
        fig = axs[0].figure
    for ax, t in zip(axs, items):
        bad = np.abs(t.phi) > verdict_limit(t.limit, t.permutations)  # the lags the verdict fails
        ax.vlines(t.lags, 0.0, t.phi, color="C0", lw=1.2)
        ax.plot(t.lags[~bad], t.phi[~bad], "o", ms=3, color="C0")
        if bad.any():
            ax.plot(t.lags[bad], t.phi[bad], "o", ms=4, color="C3", label="beyond the limit")
        ax.axhline(0.0, color="k", lw=0.6)
        for s in (-1, 1):
            ax.axhline(s * t.band, color="0.4", ls="--", lw=0.9,
                       label=f"±{t.band:.3g} ({percent_text(tests.level)} pointwise)" if s > 0 else None)
            if t.limit != t.band:
                ax.axhline(s * t.limit, color="0.4", ls=":", lw=0.9,
                           label=f"±{t.limit:.3g} ({percent_text(tests.level)} for the test)" if s > 0 else None)
        # a φ NaN at every lag (a 0/0 test in a file of an older graybox, kept as failed) draws nothing
        top = max(1.2 * float(np.max(np.abs(t.phi), initial=0.0, where=np.isfinite(t.phi))), 1.5 * t.limit)
        ax.set_ylim(-min(top, 1.05), min(top, 1.05))
        ax.set_ylabel(t.label)
        ax.set_title(f"{t.label}: {'pass' if t.passed else 'FAIL'}", fontsize=9, loc="left")
        ax.grid(True, alpha=0.3)
    axs[-1].set_xlabel("lag τ (samples)")
    axs[0].legend(fontsize=7, loc="upper right")
    if title is not None:  # asked for: on the caller's figure too
        fig.suptitle(title, fontsize=10)
    elif axes is None:  # the default title on a figure of its own only
        verdict = "all tests passed" if tests.passed else f"{len(tests.failed)} test(s) failed"
        fig.suptitle(f"{tests.model_name or 'model'}: residual correlation tests, N = {tests.n} ({verdict})",
                     fontsize=10)
    return fig


def plot_static_band(
    band: StaticCurveBand | StaticSurfaceBand,
    points: StaticPoints | None = None,
    *,
    gain: bool = True,
    against: int | str = 0,
    axes: Sequence[Axes] | None = None,
    xlabel: str | None = None,
    ylabel: str = "output ȳ",
    gain_label: str | None = None,
) -> Figure:
    """The static curve with its confidence band (shaded) and the static points; the gain beside it.

    A band of a static surface (:func:`graybox.static_surface_band`) is drawn as slices: ȳ against the input
    ``against``, one line and band per level of the other inputs (its points grouped by them, as
    :func:`graybox.plots.plot_surface_slices` draws surfaces), the gain ∂ȳ/∂ū of that input beside it.

    Parameters
    ----------
    band : StaticCurveBand or StaticSurfaceBand
        From :func:`graybox.static_curve_band` or :func:`graybox.static_surface_band`.
    points : StaticPoints, optional
        Measured steady states, drawn as ``*`` markers (of a surface: those on a slice, in its colour).
    gain : bool
        Add a second panel with the static gain and its band.
    against : int or str
        A surface band's input on the horizontal axis (position or name); a curve's is its one input.
    axes : sequence of Axes, optional
        Draw here (one Axes, or two with ``gain``); by default a new figure is made.
    xlabel, ylabel, gain_label : str, optional
        Axis labels (default x: "input ū", or the input's name; gain: "static gain dȳ/dū", or ∂ȳ/∂ of the
        input); the band's ``units`` (its model's; else the points') are appended (the gain's as output unit /
        input unit) unless a label names them already. Without units: the labels as given. Points in other
        units than the band's are refused (``ValueError``).

    Returns
    -------
    matplotlib.figure.Figure
        The curve (or each slice) as a line over its shaded band (with the level and method in the
        legend), the points as asterisks; the gain panel likewise.
    """
    if not isinstance(band, (StaticCurveBand, StaticSurfaceBand)):
        raise TypeError("band must be a StaticCurveBand or StaticSurfaceBand (from static_curve_band or "
                        f"static_surface_band), got {type(band).__name__}")
    gain = check_bool(gain, "gain")
    surface = isinstance(band, StaticSurfaceBand)
    if surface:
        names = band.input_names
        i = (names.index(check_choice(against, "against", names)) if isinstance(against, str)
             else check_int(against, "against", low=0, high=len(names) - 1))
        if points is not None:
            if not isinstance(points, StaticPoints):
                raise TypeError(f"points must be StaticPoints, got {type(points).__name__}")
            if points.input_names != names:
                raise ValueError(f"plot_static_band: the points' inputs {points.input_names} are not the band's "
                                 f"{names}")
        held = [k for k in range(len(names)) if k != i]
        levels = np.unique(band.ubar[:, held], axis=0)
        groups = [np.flatnonzero((band.ubar[:, held] == lev).all(axis=1)) for lev in levels]
        groups = [g[np.argsort(band.ubar[g, i], kind="stable")] for g in groups]
        x, gains = band.ubar[:, i], band.gain[:, i]
        glo, ghi = band.gain_low[:, i], band.gain_high[:, i]
        texts = [level_texts(levels[:, c]) for c in range(len(held))]  # per held input, digits to tell levels apart
        tags = [", ".join(f"{names[k]} = {texts[c][r]}" for c, k in enumerate(held)) for r in range(len(levels))]
        xlabel = f"input {names[i]}" if xlabel is None else xlabel
        gain_label = f"static gain ∂ȳ/∂{names[i]}" if gain_label is None else gain_label
    else:
        if isinstance(against, str):  # a curve's band keeps no input name to compare with
            raise ValueError(f"against={against!r}: a static curve's band has one input, against must be 0")
        check_int(against, "against", low=0, high=0)
        check_one_input_points(points, "plot_static_band")
        # in ū's order, as a slice's levels are: levels given unsorted (the static points' measured order) drew the
        # line back and forth and the band as a fill between crossing segments
        groups, tags = [np.argsort(band.ubar, kind="stable")], [""]
        x, gains, glo, ghi = band.ubar, band.gain, band.gain_low, band.gain_high
        xlabel = "input ū" if xlabel is None else xlabel
        gain_label = "static gain dȳ/dū" if gain_label is None else gain_label
    need = 2 if gain else 1
    if axes is None:
        fig = Figure(figsize=(10.0 if gain else 6.4, 4.0), layout="constrained")
        axs = list(np.atleast_1d(fig.subplots(1, need)))
    else:
        axs = check_axes(axes, need, "plot_static_band")
        fig = axs[0].figure
    what = f"{percent_text(band.level)} band ({band.method})"
    name = band.model_name or "model"
    if points is not None:  # drawn over the band, points in other units would sit at the wrong ū and ȳ
        check_same_units(band.units, "plot_static_band: the band is in", points, "convert the points",
                         getattr(band, "input_names", None))
    # the band's units (its model's), the points' where the band names none
    k_in = i if surface else 0  # the input drawn against
    u_unit = input_unit(band.units, k_in) or ("" if points is None else input_unit(points.units, k_in))
    y_unit = band.units[1] or ("" if points is None else points.units[1])
    xlabel = unit_label(xlabel, u_unit)
    colours = distinct_colours(len(groups))
    every = legend_every(len(groups), SLICES_NAMED)  # one in this many slices named, beyond SLICES_NAMED
    for j, (g, tag) in enumerate(zip(groups, tags)):
        named = j % every == 0
        color = colours[j] if surface else "C0"
        on = f" ({tag})" if tag else ""
        axs[0].fill_between(x[g], band.ybar_low[g], band.ybar_high[g], color=color, alpha=0.25, lw=0,
                            label=what if j == 0 else None)
        axs[0].plot(x[g], band.ybar[g], "-", color=color,
                    label=f"{legend_text(name)} static {'surface' if surface else 'curve'}{on}" if named else None)
        if points is not None and surface:
            lev = band.ubar[g[0], held]
            pu = points.ubar.reshape(points.ybar.size, -1)  # one input's points hold ubar as shape (N,)
            hit = on_level(pu[:, held], lev)
            axs[0].plot(pu[hit, i], points.ybar[hit], "*", linestyle="none", markersize=9, color=color)
        if gain:
            gcolor = color if surface else "C1"
            axs[1].fill_between(x[g], glo[g], ghi[g], color=gcolor, alpha=0.25, lw=0, label=what if j == 0 else None)
            axs[1].plot(x[g], gains[g], "-", color=gcolor, label=f"{legend_text(name)} static gain{on}" if named else None)
    if points is not None and not surface:
        axs[0].plot(points.ubar, points.ybar, "*", linestyle="none", markersize=9, color="k", label=legend_text(points.name))
    axs[0].set_xlabel(xlabel)
    axs[0].set_ylabel(unit_label(ylabel, y_unit))
    axs[0].grid(True, alpha=0.3)
    slices = None if every == 1 else f"one in {every} of the {len(groups)} slices"
    axs[0].legend(fontsize=8, loc="best", title=slices, title_fontsize=8)
    if gain:
        axs[1].set_xlabel(xlabel)
        axs[1].set_ylabel(unit_label(gain_label, per_unit(y_unit, u_unit)))
        axs[1].grid(True, alpha=0.3)
        axs[1].legend(fontsize=8, loc="best", title=slices, title_fontsize=8)
    return fig


def plot_simulation_band(
    band: SimulationBand,
    *,
    ax: Axes | None = None,
    ylabel: str = "output",
) -> Figure:
    """The measured output, the model's free run and its confidence band (shaded) against time.

    Parameters
    ----------
    band : SimulationBand
        From :func:`graybox.simulation_band`.
    ax : matplotlib Axes, optional
        Draw here; by default a new 8 × 3.6 in figure is made.
    ylabel : str
        Output label without units (the record's output unit is appended).

    Returns
    -------
    matplotlib.figure.Figure
        The measurement as a black line, the free run over its shaded band (level and method in the
        legend).
    """
    if not isinstance(band, SimulationBand):
        raise TypeError(f"band must be a SimulationBand (from simulation_band), got {type(band).__name__}")
    if ax is None:
        fig = Figure(figsize=(8, 3.6), layout="constrained")
        ax = fig.add_subplot(1, 1, 1)
    else:
        if not isinstance(ax, Axes):
            raise TypeError(f"ax must be a matplotlib Axes, got {type(ax).__name__}")
        fig = ax.figure
    ax.plot(band.t, band.y, "-", color="black", lw=1.0, label="measured")
    ax.fill_between(band.t, band.low, band.high, color="C0", alpha=0.3, lw=0,
                    label=f"{percent_text(band.level)} band ({band.method})")
    ax.plot(band.t, band.yhat, "--", color="C0", lw=1.2, label=f"{legend_text(band.model_name or 'model')} free run")
    ax.set_xlabel("time (s)")
    ax.set_ylabel(unit_label(ylabel, band.units[1]))
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    return fig


def plot_decision_bootstrap(
    boot: DecisionBootstrap,
    *,
    axes: Sequence[Axes] | None = None,
    xlabel: str = "J_S (output units²)",
    ylabel: str = "J_SF (output units²)",
) -> Figure:
    """How often each λ1 was chosen, and where the chosen members lie in (J_S, J_SF).

    Parameters
    ----------
    boot : DecisionBootstrap
        From :func:`graybox.bootstrap_decision`.
    axes : pair of Axes, optional
        Draw here; by default a new 10 × 4 in figure with two panels is made.
    xlabel, ylabel : str
        Labels of the right panel (e.g. ``"J_S (mlc²)"``; the defaults name no unit).

    Returns
    -------
    matplotlib.figure.Figure
        Left: the fraction of replicates choosing each λ1 (log axis), the reference decision's
        λ1 dashed. Right: each replicate's chosen member (J_S, J_SF) on log axes, D_SF's band
        shaded, the reference decision as a star; failed replicates are counted in the title.
    """
    if not isinstance(boot, DecisionBootstrap):
        raise TypeError(f"boot must be a DecisionBootstrap (from bootstrap_decision), got {type(boot).__name__}")
    if axes is None:
        fig = Figure(figsize=(10.0, 4.0), layout="constrained")
        ax_l, ax_r = fig.subplots(1, 2)
    else:
        ax_l, ax_r = check_axes(axes, 2, "plot_decision_bootstrap")
        fig = ax_l.figure
    freq = boot.frequencies()
    lam = freq.index.to_numpy(float)
    ax_l.vlines(lam, 0.0, freq["fraction"], color="C0", lw=3)
    ax_l.plot(lam, freq["fraction"], "o", color="C0", ms=4)
    ref = boot.reference.get("lambda1")
    if ref is not None:
        ax_l.axvline(ref, color="k", ls="--", lw=1, label=f"original data: λ1 = {ref:.3g}")
        ax_l.legend(fontsize=8, loc="best")
    ax_l.set_xscale("log")
    lo, hi = float(np.min(boot.lambdas)), float(np.max(boot.lambdas))
    ax_l.set_xlim(lo / 1.5, hi * 1.5)
    ax_l.set_ylim(0, 1.05)
    ax_l.set_xlabel("λ1 chosen by D_SF")
    ax_l.set_ylabel("fraction of replicates")
    ax_l.grid(True, which="both", alpha=0.3)
    ok = boot.ok & np.isfinite(boot.JS) & np.isfinite(boot.JSF) & (boot.JS > 0) & (boot.JSF > 0)
    ax_r.plot(boot.JS[ok], boot.JSF[ok], "o", ms=4, alpha=0.6, color="C0", label=f"replicates ({int(ok.sum())})")
    ref_js, ref_jsf = (float(boot.reference[k]) if k in boot.reference else np.nan for k in ("JS", "JSF"))
    drew_ref = bool(np.isfinite(ref_js) and np.isfinite(ref_jsf) and ref_js > 0 and ref_jsf > 0)
    if drew_ref:
        ax_r.plot([ref_js], [ref_jsf], "*", ms=14, mec="k", color="C1", label="original data", zorder=5)
    elif "JS" in boot.reference:  # a reference the log axes cannot show (a fallback's J_S = inf): said, not a star
        ax_r.plot([], [], "*", ms=14, mec="k", color="C1",
                  label=f"original data (not drawn: {_why_not_drawn(ref_js, ref_jsf, True)})")
    ax_r.set_xscale("log")
    ax_r.set_yscale("log")
    band_lo, band_hi = (0.0, boot.band) if np.ndim(boot.band) == 0 else boot.band
    ylo, yhi = ax_r.get_ylim()
    if not ok.any() and not drew_ref:  # nothing on the log axes: their limits are matplotlib's (0, 1)
        ylo, yhi = band_hi / 100, band_hi * 10
    if band_lo > 0:  # a log axis has no 0: a band from 0 is shaded from the bottom
        ylo = min(ylo, band_lo)
    elif band_hi <= ylo:  # a band below every replicate brought into the panel (else the legend names no shade seen)
        ylo = band_hi / 3
    ax_r.axhspan(band_lo if band_lo > 0 else ylo, band_hi, color="0.85", zorder=0,
                 label=f"B = [{band_lo:g}, {band_hi:g}]")
    ax_r.set_ylim(ylo, max(yhi, band_hi))
    ax_r.set_xlabel(xlabel)
    ax_r.set_ylabel(ylabel)
    ax_r.grid(True, which="both", alpha=0.3)
    ax_r.legend(fontsize=8, loc="best")
    failed = f", {len(boot.failures)} failed" if boot.failures else ""
    ax_r.set_title(f"{boot.estimator.upper()} + D_SF, {boot.n_replicates} replicates{failed}", fontsize=9)
    return fig
