"""StaticCurve: given or fitted polynomials (issue 3, item 5)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from graybox import StaticPoints, reference
from graybox.static._curves import StaticCurve
from graybox.datasets import load_pumping
from graybox.datasets.pumping import PumpingPlant

EQ1 = np.array(reference.EQ1_COEFFICIENTS)  # (κ, α, β)


def test_polynomial_eq1():
    c = StaticCurve.polynomial(EQ1, domain=(750, 1650), name="eq. (1)")
    ub = np.array([750.0, 1200.0, 1650.0])
    np.testing.assert_allclose(c(ub), reference.eq1(ub))
    np.testing.assert_allclose(c.gain(ub), 2 * EQ1[2] * ub + EQ1[1])
    assert c.degree == 2 and c.domain == (750.0, 1650.0)
    p = c.points(ub)
    assert isinstance(p, StaticPoints)
    np.testing.assert_allclose(p.ybar, reference.eq1(ub))


def test_domain_is_enforced():
    c = StaticCurve.polynomial(EQ1, domain=(750, 1650))
    with pytest.raises(ValueError, match="outside the domain"):
        c(np.array([700.0]))
    with pytest.raises(ValueError, match="outside the domain"):
        c.gain(np.array([1700.0]))
    assert np.isfinite(StaticCurve.polynomial(EQ1)(np.array([1e4]))).all()  # no domain: anywhere


def test_curve_is_immutable():
    c = StaticCurve.polynomial(EQ1)
    with pytest.raises(ValueError):
        c.coefficients[0] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        c.domain = (0, 1)


def test_bad_curves():
    with pytest.raises(ValueError, match="at least one coefficient"):
        StaticCurve.polynomial([])
    with pytest.raises(ValueError, match="non-finite"):
        StaticCurve.polynomial([1.0, np.nan])
    with pytest.raises(ValueError, match=r"domain high must lie in \(2, inf\)"):
        StaticCurve.polynomial([1.0], domain=(2, 1))
    with pytest.raises(TypeError, match="domain must be a pair"):
        StaticCurve.polynomial([1.0], domain=2.0)


def test_fit_recovers_a_noise_free_polynomial():
    pts = reference.eq1_points()
    c = StaticCurve.fit(pts, 2)
    np.testing.assert_allclose(c.coefficients, EQ1, rtol=1e-8)
    assert c.domain == (750.0, 1650.0)
    line = StaticCurve.fit(pts, 1)
    assert line.degree == 1


def test_fit_validates_degree_and_point_count():
    pts = StaticPoints([1.0, 2.0], [3.0, 4.0])
    with pytest.raises(ValueError, match="degree must be an integer >= 0"):
        StaticCurve.fit(pts, -1)
    with pytest.raises(TypeError, match="degree must be an integer"):
        StaticCurve.fit(pts, 1.5)
    with pytest.raises(ValueError, match="at least 3 static points"):
        StaticCurve.fit(pts, 2)


def test_fitting_eq1_form_to_bundled_points_recovers_beta_alpha_kappa():
    """Fit H(u) = β u² + α u + κ to the 10 bundled points; compare with eq. (1).

    Tolerance, and why: each bundled point is the mean of 120 settled noisy samples; its std σ_i
    comes from the plant's noise model (PumpingPlant.static_point_std: white transmitter noise plus
    AR(1) process noise through the water column; checked against Monte Carlo in
    test_datasets.py), about 0.030–0.032 mlc. With V the Vandermonde matrix of the 10 speeds and
    Σ = diag(σ_i²), the least-squares estimate has covariance (VᵀV)⁻¹ Vᵀ Σ V (VᵀV)⁻¹; its
    diagonal gives standard errors of about 0.19 (κ), 3.4e-4 (α) and 1.4e-7 (β). The three
    estimates are strongly correlated, so individually they may be far off in relative terms
    (κ and α by tens of percent) while the curve stays within a few hundredths of mlc. We assert
    each coefficient within 4 standard errors (a false alarm about 1 time in 16 000 per
    coefficient for Gaussian errors), and the fitted curve within 4 of its own standard errors
    of eq. (1) on the measured range.
    """
    ds = load_pumping()
    plant = PumpingPlant()
    fit = StaticCurve.fit(ds.static, 2)
    ub = ds.static.ubar
    sd = np.array([plant.static_point_std(s, n_samples=120) for s in ub])
    V = np.vander(ub, 3, increasing=True)
    A = np.linalg.pinv(V)  # (VᵀV)⁻¹ Vᵀ
    cov = A @ np.diag(sd**2) @ A.T
    se = np.sqrt(np.diag(cov))
    np.testing.assert_allclose(se, [0.19, 3.4e-4, 1.4e-7], rtol=0.15)  # the numbers quoted above
    z = (fit.coefficients - EQ1) / se
    assert np.all(np.abs(z) < 4), z
    grid = np.linspace(750, 1650, 19)
    G = np.vander(grid, 3, increasing=True)
    se_curve = np.sqrt(np.einsum("ij,jk,ik->i", G, cov, G))
    assert np.all(np.abs(fit(grid) - reference.eq1(grid)) < 4 * se_curve)
    assert np.max(np.abs(fit(grid) - reference.eq1(grid))) < 0.1  # mlc: the curve itself is close


def test_a_fit_on_two_levels_equal_to_round_off_names_them_not_an_input_far_from_zero():
    # 0.1 * 3 and 0.3 are two levels to StaticPoints (they differ by 5.6e-17) and one to the fit: the quadratic on
    # three points was refused as "powers of an input far from zero over a narrow range: express the input nearer
    # zero", of levels in [0, 0.3]
    pts = StaticPoints([0.0, 0.1 * 3, 0.3], [0.0, 1.0, 2.0])
    with pytest.raises(ValueError, match=r"levels 0\.3 and 0\.30000000000000004, one level to round-off") as err:
        StaticCurve.fit(pts, 2)
    assert "nearer zero" not in str(err.value)
    assert StaticCurve.fit(pts, 1).degree == 1  # two levels carry a line


def test_check_domain_refuses_what_is_no_level_as_a_surfaces_does():
    # StaticCurve.check_domain let NaN pass (NaN lies in no range, so it was outside none) and met text with numpy's
    # UFuncTypeError; StaticSurface.check_domain refuses both by name
    c = StaticCurve.polynomial([1.0, 2.0], domain=(0.0, 1.0))
    with pytest.raises(ValueError, match="non-finite"):
        c.check_domain([0.5, np.nan])
    with pytest.raises(TypeError, match=r"ubar must be numbers"):
        c.check_domain(["a"])
    c.check_domain([0.0, 1.0])
    with pytest.raises(ValueError, match=r"outside the domain \[0, 1\]"):
        c.check_domain(2.0)
    StaticCurve.polynomial([1.0]).check_domain([5.0])  # no domain: nothing to check, as a surface's
