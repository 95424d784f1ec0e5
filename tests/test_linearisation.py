"""One derivative map (graybox.static._linearisation): its three users read the same local linear model."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st

from graybox import Structure
from graybox.control._local import jacobian_rows
from graybox.estimation._local_models import LocalModels, within_at
from graybox.static._analysis import _linear_coefficients, schur_stable, stable_mask
from graybox.static._linearisation import static_partials, static_powers
from graybox.static._surface_analysis import _folded

#: A rational structure (no y power above 1), one with y² terms, and one with two inputs.
STRUCTURES = {
    "rational": Structure(["1", "y(k-1)", "y(k-3)", "u(k-1)", "u(k-2)y(k-1)", "u(k-1)^2", "u(k-2)u(k-3)y(k-2)"]),
    "y squared": Structure(["1", "y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)y(k-1)", "y(k-1)^2", "y(k-1)y(k-2)u(k-1)",
                                  "y(k-2)^3"]),
    "two inputs": Structure(["1", "y(k-1)", "y(k-2)", "u1(k-1)", "u2(k-2)", "u1(k-1)u2(k-1)", "y(k-1)u1(k-2)",
                                   "y(k-2)^2u2(k-1)", "u1(k-2)^2"]),
}


@pytest.mark.parametrize("name", list(STRUCTURES))
@settings(deadline=None, max_examples=40)
@given(data=st.data())
def test_static_estimation_and_control_read_the_same_local_model(name, data):
    structure = STRUCTURES[name]
    names = structure.input_names
    theta = np.array(data.draw(st.lists(st.floats(-0.8, 0.8), min_size=len(structure), max_size=len(structure))))
    ubar = np.array(data.draw(st.lists(st.floats(-3.0, 3.0), min_size=len(names), max_size=len(names))))
    ybar = data.draw(st.floats(-4.0, 4.0))
    assume(np.any(theta != 0.0))

    a_ctrl, b_ctrl = jacobian_rows(structure, names, theta[None, :], np.array([ybar]), ubar[None, :])
    a_est = LocalModels(structure, ubar[None, :], np.array([ybar])).coefficients(theta)
    if len(names) == 1:
        a_static = _linear_coefficients(structure, theta, ybar, float(ubar[0]))
        mask = stable_mask(structure, theta[None, :], ubar, np.array([[ybar]]))
    else:  # the static analysis of several inputs folds ū into θ (the skeleton at ū' = 1)
        sk, th = _folded(structure, theta, ubar[None, :], names)
        a_static = _linear_coefficients(sk, th[0, 0], ybar, 1.0)
        mask = stable_mask(sk, th[0], np.ones(1), np.array([[ybar]]))
    scale = np.abs(a_ctrl).max(initial=0.0) + 1e-300
    np.testing.assert_allclose(a_est[0], a_ctrl[0], rtol=1e-12, atol=1e-13 * scale)
    np.testing.assert_allclose(a_static, a_ctrl[0], rtol=1e-12, atol=1e-13 * scale)

    # the stability test, the margin at margin 0 and the Schur–Cohn test of these coefficients agree
    stable = schur_stable(a_ctrl[0])
    assert bool(mask[0, 0]) == stable
    assert bool(within_at(structure, theta[None, :], ubar[None, :] if len(names) > 1 else ubar,
                          np.array([[ybar]]), 0.0)[0]) == stable

    # summed over the lags, a and b are the derivatives of the static equation (computed term by term)
    Fy, Fu = (f[0] for f in static_partials(*static_powers(structure, names), theta[None, :], ubar[None, :],
                                            np.array([[ybar]])))
    bscale = np.abs(b_ctrl).max(initial=0.0) + 1e-300
    np.testing.assert_allclose(a_ctrl[0].sum() - 1.0, Fy[0], rtol=1e-12, atol=1e-12 * (scale + 1.0))
    np.testing.assert_allclose(b_ctrl[0].sum(axis=1), Fu[0], rtol=1e-12, atol=1e-12 * bscale)


@pytest.mark.parametrize("name", ["rational", "y squared"])
@settings(deadline=None, max_examples=30)
@given(data=st.data())
def test_the_curve_by_clusters_and_the_surface_by_terms_give_one_static_gain(name, data):
    """static_gain sums each cluster's coefficients first (the curve's own form), static_surface_gain reads the
    terms one by one; one kernel under both, the same gain (and ∂ȳ/∂θ, curve against surface)."""
    from graybox.static._analysis import static_gain, static_theta_gradient
    from graybox.static._surface_analysis import static_surface, static_surface_gain, surface_theta_gradient

    structure = STRUCTURES[name]
    theta = np.array(data.draw(st.lists(st.floats(-0.6, 0.6), min_size=len(structure), max_size=len(structure))))
    ubar = np.array(data.draw(st.lists(st.floats(0.1, 3.0), min_size=1, max_size=4)))
    yb = static_surface(structure, theta, ubar[:, None], strict=False)
    assume(np.all(np.isfinite(yb)))
    g_curve = static_gain(structure, theta, ubar)
    g_surface = static_surface_gain(structure, theta, ubar[:, None])[:, 0]
    scale = np.abs(g_curve).max() + 1.0
    np.testing.assert_allclose(g_curve, g_surface, rtol=1e-9, atol=1e-9 * scale)
    d_curve = static_theta_gradient(structure, theta, ubar, yb)
    d_surface = surface_theta_gradient(structure, theta, ubar[:, None], yb)
    np.testing.assert_allclose(d_curve, d_surface, rtol=1e-12, atol=0)


def test_a_zero_term_that_overflows_leaves_the_gain_gradient_finite():
    """The sums of the gains' θ-gradient skip θ_t = 0 as the partials do: a zero term whose power of ū overflows
    (ū ≈ 1e110, u³) must not turn the whole gradient into NaN; its own column is then the overflow it is."""
    from graybox.static._linearisation import static_gain_gradient, static_theta_gradient_of

    structure = Structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^3"])
    theta = np.array([0.5, 0.5, 0.2, 0.0])
    ub = np.array([[1e110]])
    p, A = static_powers(structure, ("u",))
    yb = (theta[0] + theta[2] * ub[:, 0]) / (1 - theta[1])
    dy = static_theta_gradient_of(p, A, theta, ub, yb)
    G = static_gain_gradient(p, A, theta, ub, yb, dy)
    assert np.all(np.isfinite(G[..., :3]))
    np.testing.assert_allclose(G[0, 0, 2], 1 / (1 - theta[1]), rtol=1e-12)  # ∂(gain)/∂θ_u = 1/(1 − θ_y)
