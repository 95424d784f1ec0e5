"""The paper's printed models (Tables II and III): clusters, static curves, J_SF against eq. (1)."""

from __future__ import annotations

from pathlib import Path

from .. import reference
from ..models._evaluate import mse
from ..static._analysis import equilibria

__all__ = ["section_reference_models"]


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
