"""review46e: the equilibria and local models of hunt46a's folds (c51eb19 … c2215e6)."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb
from graybox.static._analysis import schur_stable


@pytest.mark.parametrize("k", [2.0**-50, 2.0**-52])
def test_the_static_analysis_and_the_local_model_agree_on_a_pole_at_one_to_rounding(k):
    # y⁺ = (1 − k) y − y³ + u: at ū = 0 the one real root ȳ = 0 has a = 1 − k, Σa = 1 to rounding (an inflection,
    # F'' = 0, which the multiplicity test does not see). The static analysis called it stable, LocalModel (its own
    # unit-pole rule) not: local_model raised "status 'reached' linearises at a stable equilibrium, but …", and so
    # did operating_curve for the whole curve.
    m = gb.Model(["y(k-1)", "y(k-1)^3", "u(k-1)"], [1.0 - k, -1.0, 1.0], Ts=1.0)
    (e,) = m.equilibria(0.0)
    lm = gb.local_model(m, 0.0)
    assert lm.stable == e.stable == bool(schur_stable(lm.a)) == (lm.status == "reached") == (e.spectral_radius < 1)
    oc = gb.operating_curve(m, [0.0, 0.3])
    assert oc.status[1] == "reached" and oc.status[0] == lm.status
    assert np.isfinite(m.static_curve([0.0], strict=False)[0]) == e.stable
