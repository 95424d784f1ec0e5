"""Polynomial static surfaces in several inputs (issue 15)."""

from __future__ import annotations


import numpy as np
import pytest

from graybox import StaticPoints
from graybox.static._surfaces import StaticSurface, monomial_exponents
from graybox.datasets import TwoSpeedPumpingPlant
from graybox.datasets._pumping_miso import static_grid

TRUE = {(0, 0): -1.3, (1, 0): 1.5e-3, (0, 1): 1.4e-3, (2, 0): 2e-6, (1, 1): 3.2e-6, (0, 2): 2.1e-6}


def _points(ubar, ybar, name="pts"):
    return StaticPoints(ubar, ybar, name=name)


def test_monomial_exponents():
    assert monomial_exponents(2, 2) == ((0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2))
    assert len(monomial_exponents(3, 3)) == 20  # C(3 + 3, 3)
    assert monomial_exponents(1, 2) == ((0,), (1,), (2,))


def test_fit_recovers_a_quadratic_surface_in_rpm_and_in_rad_per_s():
    U = static_grid()
    true = StaticSurface.polynomial(TRUE)
    fit = StaticSurface.fit(_points(U, true(U)), 2)
    assert fit.exponents == monomial_exponents(2, 2)
    for e, c in TRUE.items():
        assert fit.coefficient(e) == pytest.approx(c, rel=1e-8)
    assert fit.domain == ((1150.0, 1650.0), (1150.0, 1650.0))
    # units: ū in rad/s gives c_e (30/π)^|e|, the same surface
    k = np.pi / 30
    fit_rad = StaticSurface.fit(_points(U * k, true(U)), 2)
    for e, c in TRUE.items():
        assert fit_rad.coefficient(e) == pytest.approx(c / k ** sum(e), rel=1e-8)


def test_fit_to_the_plants_surface_is_within_the_documented_error():
    plant = TwoSpeedPumpingPlant()
    g = np.linspace(1150, 1650, 21)
    U = np.array([(a, b) for a in g for b in g])
    P = plant.static_pressure(U[:, 0], U[:, 1])
    fit = StaticSurface.fit(_points(U, P), 2)
    err = fit(U) - P
    assert np.abs(err).max() < 0.1 and err.std() < 0.015  # module docs of _pumping_miso


def test_gradient_matches_finite_differences():
    s = StaticSurface.polynomial({(0, 0, 0): 1.0, (1, 2, 0): 0.5, (0, 1, 1): -2.0, (3, 0, 0): 0.1})
    U = np.array([[1.0, 2.0, 3.0], [-0.5, 0.3, 1.1]])
    G = s.gradient(U)
    h = 1e-6
    for j in range(3):
        d = np.zeros(3)
        d[j] = h
        np.testing.assert_allclose(G[:, j], (s(U + d) - s(U - d)) / (2 * h), rtol=1e-7)


def test_fit_takes_the_points_input_names_and_samples_back():
    U = static_grid()
    true = StaticSurface.polynomial(TRUE)
    fit = StaticSurface.fit(StaticPoints(U, true(U), input_names=("n1", "n2")), 2)
    assert fit.input_names == ("n1", "n2")
    pts = fit.points(U[:5])
    assert pts.input_names == ("n1", "n2") and pts.ubar.shape == (5, 2)
    np.testing.assert_allclose(pts.ybar, true(U[:5]), rtol=1e-9)


def test_evaluation_shapes_domain_and_text():
    s = StaticSurface.polynomial(TRUE, domain=[(1000, 1700), (1000, 1700)], name="H")
    assert s(np.array([1200.0, 1300.0])).shape == (1,)
    assert s.n_inputs == 2 and s.degree == 2 and s.coefficient((5, 0)) == 0.0
    with pytest.raises(ValueError, match="u2 = \\[1800.0\\] outside the domain"):
        s(np.array([[1200.0, 1800.0]]))
    with pytest.raises(ValueError, match=r"shape \(K, 2\)"):
        s(np.ones((3, 3)))
    assert s.describe().startswith("-1.3 + 0.0015 u1 + 0.0014 u2")
    assert StaticSurface.polynomial({(1, 1): 2.0}, input_names=("n1", "n2")).describe() == "2 n1*n2"


def test_bad_surfaces():
    with pytest.raises(ValueError, match="same length"):
        StaticSurface(((0, 0), (1,)), np.ones(2))
    with pytest.raises(ValueError, match="given twice"):
        StaticSurface(((1, 0), (1, 0)), np.ones(2))
    with pytest.raises(ValueError, match="2 coefficients for 3 monomials"):
        StaticSurface(((0, 0), (1, 0), (0, 1)), np.ones(2))
    with pytest.raises(ValueError, match="low < high"):
        StaticSurface.polynomial(TRUE, domain=[(1, 0), (0, 1)])
    with pytest.raises(ValueError, match="distinct names"):
        StaticSurface.polynomial(TRUE, input_names=("a", "a"))
    with pytest.raises(ValueError, match="needs at least 6 static points"):
        StaticSurface.fit(_points(np.c_[np.arange(4.0), np.ones(4)], np.ones(4)), 2)
    with pytest.raises(ValueError, match="rank"):  # all points on a line: u1*u2, u1², u2² collinear
        t = np.linspace(0, 1, 10)
        StaticSurface.fit(_points(np.c_[t, t], t), 2)


def test_surface_fit_counts_levels_equal_to_round_off_as_one():
    # u1 at 0, 0.1 * 3 and 0.3: three levels to np.unique, two to the fit; its power 2 passed the levels check and the
    # fit's rank test said "the inputs move together over them", of points on a grid
    u1 = [0.0, 0.1 * 3, 0.3, 0.0, 0.1 * 3, 0.3, 0.0, 0.3]
    u2 = [0.0, 0.0, 1.0, 1.0, 2.0, 2.0, 2.0, 0.0]
    pts = StaticPoints(np.column_stack([u1, u2]), np.arange(8.0))
    with pytest.raises(ValueError, match=r"input 'u1' at 2 levels, too few for its power 2"):
        StaticSurface.fit(pts, 2)
    assert StaticSurface.fit(pts, exponents=[(0, 0), (1, 0), (0, 1), (1, 1), (0, 2)]).degree == 2
