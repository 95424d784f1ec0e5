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


def _quartic_in_units(roots: list[float], lead: float, s: float) -> gb.Model:
    """y⁺ = y + lead Π(y − r) + u, exact in binary for dyadic roots, then with y in units s times smaller."""
    c = np.poly(np.array(roots))[::-1] * lead
    theta = np.array([c[0], 1.0 + c[1], c[2], c[3], c[4], 1.0]) * np.array([s, 1.0, s**-1, s**-2, s**-3, s])
    return gb.Model(["1", "y(k-1)", "y(k-1)^2", "y(k-1)^3", "y(k-1)^4", "u(k-1)"], theta, Ts=1.0)


@pytest.mark.parametrize("roots,lead,s", [([0.90625] * 3 + [3.578125], -2.0, 1e-3), ([0.125] * 3 + [2.953125], -0.25, 10.0),
                                          ([0.921875] * 3 + [-0.546875], 1.0, 10.0)])
def test_the_local_model_at_a_triple_root_has_its_pole_at_one_whichever_way_rounding_went(roots, lead, s):
    # d826ae7 put the pole at z = 1 only where rounding left Σa below 1 (the a_l passed Schur–Cohn); where it left
    # them above (1 + 4e-10 here), the pole stayed outside: a finite DC gain of −2.6e6, damping NaN, ρ = 1 + 4e-10
    m = _quartic_in_units(roots, lead, s)
    lm = gb.local_model(m, 0.0)
    assert lm.status == "no stable equilibrium" and abs(lm.ybar - roots[0] * s) < 1e-4 * s
    assert lm.a.sum() == pytest.approx(1.0, abs=1e-15) and lm.spectral_radius == 1.0
    assert np.isinf(lm.dc_gain).all() and lm.damping == 0.0 and np.isinf(lm.time_constant) and not lm.stable
