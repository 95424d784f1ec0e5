"""Bug hunt 43a: reports that explain, and the plots."""

import re
import warnings

import numpy as np
import pytest

import graybox as gb


def _named_points(text: str) -> list[str]:
    return re.findall(r"ū = (\([^)]*\)|[^:;,\s]+)", text)


@pytest.mark.parametrize("offset", [0.0, 1e4, 1e6])
def test_reached_explain_names_each_point_apart_at_any_offset(offset):
    """Three static points 0.01 apart on an input offset by 1e4: jsf's warning (Reached.explain) named every one
    'ū = 10000', so the reader could not tell which point failed (at offset 0 they read 0.01, 0.02, 0.03)."""
    model = gb.Model(gb.parse_structure(["y(k-1)", "u(k-1)"]), np.array([1.5, 1.0]))  # unstable: no point reached
    pts = gb.StaticPoints(offset + np.array([0.01, 0.02, 0.03]), [1.0, 2.0, 3.0])
    with pytest.warns(RuntimeWarning) as rec:
        assert gb.jsf(model, pts) == np.inf
    named = _named_points(str(rec[0].message))
    assert len(named) == 3 and len(set(named)) == 3, named
    np.testing.assert_allclose([float(t) for t in named], pts.ubar, rtol=1e-12)


@pytest.mark.parametrize("offset", [0.0, 1e4])
def test_static_curve_names_each_point_apart_at_any_offset(offset):
    """A non-rational model with no stable equilibrium: static_curve's error named each point with %g."""
    model = gb.Model(gb.parse_structure(["y(k-1)", "y(k-1)^2", "u(k-1)"]), np.array([1.0, 1.0, 1.0]))  # ȳ² = −ū: none
    ub = offset + np.array([0.01, 0.02])
    with pytest.raises(ValueError) as exc:
        model.static_curve(ub)
    named = _named_points(str(exc.value))
    assert len(set(named)) == 2, str(exc.value)
    np.testing.assert_allclose([float(t) for t in dict.fromkeys(named)], ub, rtol=1e-12)


def test_reached_explain_names_surface_points_apart():
    """Points (ū1, ū2) of a surface with ū2 offset by 1e4: each printed '(1, 10000)'."""
    st = gb.parse_structure(["y(k-1)", "u1(k-1)", "u2(k-1)"])
    model = gb.Model(st, np.array([1.5, 1.0, 1.0]), input_names=("u1", "u2"))
    ub = np.array([[1.0, 1e4 + 0.01], [1.0, 1e4 + 0.02]])
    pts = gb.StaticPoints(ub, [1.0, 2.0])
    with pytest.warns(RuntimeWarning) as rec:
        assert gb.jsf(model, pts) == np.inf
    named = _named_points(str(rec[0].message))
    assert len(named) == 2 and len(set(named)) == 2, named
