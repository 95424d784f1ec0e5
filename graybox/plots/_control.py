"""Pictures of local linear models: step and Bode responses over the operating range, gain and time constant against ū."""

from __future__ import annotations

import textwrap
from typing import Sequence

import numpy as np
from matplotlib.figure import Figure

from ..control._local import LocalModel, OperatingCurve
from ..core._reprs import LISTED, level_texts, per_unit, percent_text, point_texts
from ..core._records import input_unit, input_unit_text
from ..core._validation import as_1d_finite, check_count, check_real, check_sequence
from ._data import distinct_colours, legend_every, legend_text, unit_label

__all__ = ["plot_local_models", "plot_operating_curve"]


def _models(models: OperatingCurve | Sequence[LocalModel]) -> list[LocalModel]:
    what = "an OperatingCurve or a non-empty sequence of LocalModel"
    lms = list(models.local_models) if isinstance(models, OperatingCurve) else check_sequence(models, "models", what)
    if not all(isinstance(m, LocalModel) for m in lms):
        raise TypeError(f"models must be {what}, got {sorted({type(m).__name__ for m in lms} - {'LocalModel'})} items")
    if not lms:
        raise ValueError(f"models must be {what}, got an empty sequence")
    return lms


def _points(lms: Sequence[LocalModel]) -> list[str]:
    """Each local model's operating point as text, told apart from the others' (10000.01 and 10000.02)."""
    ub = np.array([np.asarray(m.ubar, float).ravel() for m in lms])
    return point_texts(ub[:, 0] if ub.shape[1] == 1 else ub)


def _per_input(units: tuple, j: int = 0) -> str:
    """The unit of a gain, output unit per unit of input ``j`` (``"mlc/rpm"``), or empty when neither is said."""
    return per_unit(units[1], input_unit(units, j))


def _points_title(head: str, points: Sequence[str], width: float) -> str:
    """``head`` and the operating points, the first :data:`~graybox.core._reprs.LISTED` and how many in all, in
    lines that fit a figure ``width`` inches wide at 9 pt (one line of 40 levels ran off both edges, unread)."""
    told = ", ".join(points[:LISTED]) + (f", … ({len(points)} in all)" if len(points) > LISTED else "")
    return textwrap.fill(head + told, max(20, int(width * 72 / (0.6 * 9))), break_long_words=False)


#: Most samples of a local model's step response drawn by default (a figure shows a few thousand points).
MAX_STEP_SAMPLES = 100_000


def plot_local_models(
    models: OperatingCurve | Sequence[LocalModel],
    *,
    input: int | str = 0,
    duration: float | None = None,
    n_frequencies: int = 400,
) -> Figure:
    """Step responses and Bode diagrams of local models at several operating points (one colour each).

    Parameters
    ----------
    models : OperatingCurve or sequence of LocalModel
        Local models with an equilibrium (those without one are listed in the title and skipped).
    input : int or str
        The input stepped (by position or name).
    duration : float, optional
        Length of the step responses (s); default six times the largest finite time constant, cut at
        100 000 samples of a model (a pole near 1 would otherwise ask for millions). Given, it may ask
        for at most 10⁷ samples of a model (``ValueError`` beyond).
    n_frequencies : int
        Frequencies of the Bode diagram, log-spaced up to each model's Nyquist frequency π/Ts
        (each model is drawn on its own sampling period).

    Returns
    -------
    matplotlib.figure.Figure
        Left: Δy per unit step of the input against time; right: magnitude (output units per
        input unit) and phase (degrees) against frequency (rad/s). The models' units, when they
        say them, label both (e.g. ``|G| (mlc/rpm)``); with several inputs the labels name the input stepped
        (``Δy per unit step of u2``).
    """
    if duration is not None:
        duration = check_real(duration, "duration", low=0, low_open=True)  # seconds
    n_frequencies = check_count(n_frequencies, "n_frequencies", low=2)
    lms = _models(models)
    at = dict(zip(map(id, lms), _points(lms)))
    shown = [m for m in lms if m.exists]
    missing = [m for m in lms if not m.exists]
    if not shown:
        raise ValueError("none of the local models has an equilibrium: " + "; ".join(m.reason for m in missing))
    taus = [m.time_constant for m in shown if np.isfinite(m.time_constant) and m.time_constant > 0]
    T = duration if duration is not None else 6 * max(taus, default=20 * max(m.Ts for m in shown))
    fig = Figure(figsize=(10, 5))
    # one colour each (matplotlib's cycle of ten drew the 1st and 11th models alike)
    colours = distinct_colours(len(shown))
    ax_s = fig.add_subplot(1, 2, 1)
    ax_m = fig.add_subplot(2, 2, 2)
    ax_p = fig.add_subplot(2, 2, 4, sharex=ax_m)
    for m, colour in zip(shown, colours):
        # each model on its own sampling: its samples in time, its frequencies up to its Nyquist π/Ts
        n = max(int(np.ceil(T / m.Ts - 1e-9)) + 1, 2)
        if duration is None:
            n = min(n, MAX_STEP_SAMPLES)
        elif n > 100 * MAX_STEP_SAMPLES:
            raise ValueError(f"duration={duration:g} s is {n} samples of a model sampled every {m.Ts:g} s: at most "
                             f"{100 * MAX_STEP_SAMPLES} are drawn; give a shorter duration")
        w = np.logspace(np.log10(np.pi / m.Ts) - 3, np.log10(np.pi / m.Ts), n_frequencies)
        said = input_unit_text(m.units)
        tag = f"ū = {at[id(m)]}{' ' + said if said else ''}" + ("" if m.reached else f" ({m.status})")
        line, = ax_s.plot(np.arange(n) * m.Ts, m.step(n, input), lw=1.2, color=colour, label=tag)
        G = m.frequency_response(w, input)
        ax_m.loglog(w, np.abs(G), color=line.get_color(), lw=1.0)
        ax_p.semilogx(w, np.degrees(np.unwrap(np.angle(G))), color=line.get_color(), lw=1.0)
    # the models' units (output per input) where they all say the same ones
    units = {m.units for m in shown}
    # with several inputs, which one was stepped (input=0 and input=1 drew figures labelled alike)
    names = shown[0].input_names
    per = _per_input(units.pop(), shown[0]._input_index(input)) if len(units) == 1 else ""
    of = f" of {names[shown[0]._input_index(input)]}" if len(names) > 1 else ""
    ax_s.set_xlabel("time (s)")
    ax_s.set_ylabel(unit_label(f"Δy per unit step{of}", per))
    # a legend of at most LISTED entries: one of 200 models ran off the figure ("Tight layout not applied")
    lines = ax_s.get_lines()
    every = legend_every(len(lines))
    if every > 1:
        ax_s.legend(lines[::every], [ln.get_label() for ln in lines[::every]], fontsize=8, loc="best",
                    title=f"one in {every} of the {len(lines)} models", title_fontsize=8)
    else:
        ax_s.legend(fontsize=8, loc="best")
    ax_m.set_ylabel(unit_label(f"|G|{of}", per))
    ax_p.set_ylabel("phase (°)")
    ax_p.set_xlabel("ω (rad/s)")
    if missing:
        fig.suptitle(_points_title("no equilibrium at ū = ", [at[id(m)] for m in missing], 10.0), fontsize=9)
    fig.tight_layout()
    return fig


def plot_operating_curve(
    curve: OperatingCurve,
    *,
    reference: tuple[np.ndarray, np.ndarray] | None = None,
    reference_label: str = "plant",
    xlabel: str = "ū",
) -> Figure:
    """The local gain, dominant time constant and damping against the operating input.

    A model of several inputs is drawn against the one input its operating points vary (the others held,
    e.g. a transient input at its static level 0), with the gain ∂ȳ/∂ū of that input; points that vary
    several inputs are refused (plot slices of :meth:`OperatingCurve.to_frame` instead).

    Parameters
    ----------
    curve : OperatingCurve
        From :func:`graybox.operating_curve`; its bands (when computed) are shaded.
    reference : (ubar, time_constant), optional
        Another time constant against ū (e.g. the plant's own, linearised), drawn as points.
    reference_label : str
        Its legend label.
    xlabel : str
        The input's label; default ``ū``, with several inputs ``ū (name)``. The curve's input unit
        (its model's ``units``) is appended unless the label names it already.

    Returns
    -------
    matplotlib.figure.Figure
        Three stacked panels sharing ū, in ū's order: gain (output unit per input unit, named
        when the model's units are), time constant (s), damping.
    """
    if not isinstance(curve, OperatingCurve):
        raise TypeError(f"curve must be an OperatingCurve, got {type(curve).__name__}")
    u, gain, gain_low, gain_high = curve.ubar, curve.gain, curve.gain_low, curve.gain_high
    j = 0  # the input drawn against
    if u.ndim != 1:
        # several inputs (e.g. a transient input's z̄ = 0 beside u): drawn against the one the points vary
        names = curve.local_models[0].input_names
        varied = [j for j in range(u.shape[1]) if np.ptp(u[:, j]) > 0]
        if len(varied) != 1:
            said = ", ".join(repr(names[j]) for j in varied) or "none"
            raise ValueError(f"plot_operating_curve draws against one input, but the operating points vary {said} "
                             f"of the inputs {names}: hold all but one (a transient input at 0), or plot slices of "
                             "the curve's to_frame()")
        j = varied[0]
        u, gain = u[:, j], gain[:, j]
        gain_low, gain_high = (None, None) if gain_low is None else (gain_low[:, j], gain_high[:, j])
        if xlabel == "ū":
            xlabel = f"ū ({names[j]})"
    if reference is not None:
        pair = check_sequence(reference, "reference", "a pair (ubar, time_constant)")
        if len(pair) != 2:
            raise ValueError(f"reference must be a pair (ubar, time_constant), got {len(pair)} items")
        reference = (as_1d_finite(pair[0], "reference[0] (ubar)"),
                     as_1d_finite(pair[1], "reference[1] (time constant)"))
        if reference[0].size != reference[1].size:
            raise ValueError(f"reference holds {reference[0].size} ū and {reference[1].size} time constants")
    fig = Figure(figsize=(7, 7))
    # one ū axis for the three (its docstring's "sharing ū"): each drawn on its own, a panel with NaN or inf at some
    # points (τ of the unstable ones) spanned only its finite ones, a point's ū at another place in each panel
    axes = [fig.add_subplot(3, 1, 1)]
    axes += [fig.add_subplot(3, 1, i + 1, sharex=axes[0]) for i in (1, 2)]
    name = curve.model_name or "model"
    # in ū's order: points given unsorted drew each line (and band) back and forth across the panel
    o = np.argsort(u, kind="stable")
    for ax, y, lo, hi, lab in ((axes[0], gain, gain_low, gain_high, "gain"),
                               (axes[1], curve.time_constant, curve.time_constant_low, curve.time_constant_high,
                                "time constant (s)"),
                               (axes[2], curve.damping, None, None, "damping ζ")):
        ax.plot(u[o], y[o], "-o", ms=3, lw=1.2, label=legend_text(name))
        if lo is not None:
            ax.fill_between(u[o], lo[o], hi[o], alpha=0.25, label=f"{percent_text(curve.level)} band")
        ax.set_ylabel(unit_label(lab, _per_input(curve.units, j)) if lab == "gain" else lab)
    if reference is not None:
        axes[1].plot(*reference, "s", ms=5, color="black", label=legend_text(reference_label))
    axes[2].set_ylim(0.0, 1.05)  # ζ of a stable pole lies in [0, 1]
    bad = [t for t, s in zip(level_texts(u), curve.status) if s != "reached"]  # told apart at any offset
    if bad:
        axes[0].set_title(_points_title("not reached at ū = ", bad, 7.0), fontsize=9)
    axes[1].legend(fontsize=8, loc="best")
    axes[2].set_xlabel(unit_label(xlabel, input_unit(curve.units, j)))
    fig.tight_layout()
    return fig
