"""Reproduce the paper's results (Table I, the static analysis, the figures).

Each section is a function returning text (and, where it makes pictures, writing them
under ``out``); :func:`run` strings them together. The CLI's ``graybox reproduce``
calls :func:`run`. ``quick`` mode shortens only the expensive searches, never the
definitions of the numbers.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Callable, TextIO

import numpy as np

from . import reference
from .evaluate import mse
from .static import equilibria

__all__ = ["run", "section_reference_models"]


def section_reference_models(quick: bool = True, out: Path | None = None) -> str:
    """The paper's printed models: clusters, static curves and J_SF against eq. (1)."""
    pts = reference.eq1_points()
    lines = ["== The paper's models as printed (Tables II and III) ==",
             "J_SF is the MSE of the model's static curve against eq. (1) at ū = 750, 850, …, 1650 rpm."]
    for eq, table in ((15, reference.TABLE_II), (17, reference.TABLE_III)):
        for col in table:
            if (("II" if eq == 15 else "III"), col) in reference.MISPRINTED:
                lines.append(f"-- ({eq}) {col}: misprinted in the paper (static curve diverges); skipped")
                continue
            m = reference.paper_model(eq, col)
            cl = ", ".join(f"{k} = {v:.4g}" for k, v in m.clusters().items())
            try:
                yb = m.static_curve(pts.ubar)
                jsf = f"{mse(pts.ybar, yb):.4f}"
                curve = " ".join(f"{v:.2f}" for v in yb)
            except ValueError as exc:
                jsf, curve = "inf", f"undefined ({exc})"
            lines.append(f"-- ({eq}) {col}: N_p = {m.n_params}, J_SF = {jsf}")
            lines.append(f"   clusters: {cl}")
            lines.append(f"   static curve at 750…1650 rpm: {curve}")
    m17 = reference.paper_model(17)
    eqs = equilibria(m17.structure, m17.theta, 750.0)
    lines.append("-- (17) ELS equilibria at ū = 750 rpm: " + "; ".join(
        f"ȳ = {e.ybar:.3f} ({'stable' if e.stable else 'unstable'}, ρ = {e.spectral_radius:.3f})" for e in eqs))
    return "\n".join(lines)


def _sections() -> list[Callable[..., str]]:
    # imported here so that `import graybox.reproduce` stays light
    from .els import section_black_box

    return [section_reference_models, section_black_box]


def run(quick: bool = True, out: Path | None = None, stream: TextIO = sys.stdout) -> None:
    """Run every section in order, printing each as it finishes."""
    if out is not None:
        Path(out).mkdir(parents=True, exist_ok=True)
    for sec in _sections():
        print(sec(quick=quick, out=out), file=stream, flush=True)
        print(file=stream)
