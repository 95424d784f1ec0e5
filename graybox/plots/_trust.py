"""Pictures for trusting a model: residual correlation tests, static-curve bands, decision bootstrap.

Built with :class:`matplotlib.figure.Figure` directly (no pyplot state), like the other plots.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from .._residuals import ResidualTests

__all__ = ["plot_residual_tests"]


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
