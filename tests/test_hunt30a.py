"""Bugs found by a bug hunt in static analysis (graybox.static and the models' static curves,
surfaces, equilibria and gains) on one's own models: inputs not named "u", units far from 1, cross
and cubic terms, several or no equilibria, one and two inputs. Each test fails without its fix."""

import numpy as np
import pytest

import graybox as gb


def test_the_static_gain_is_nan_where_the_static_curve_is():
    # y(k) = 1.5 y(k-1) + s(k-1) (+ s(k-1)²): its one equilibrium is unstable, so the static curve
    # is NaN with strict=False; the gain read NaN⁰ = 1 in −F_ū/F_ȳ and gave a finite slope (−2, −6)
    # of a curve that does not exist there.
    st = gb.Structure(["y(k-1)", "s(k-1)", "s(k-1)^2"])
    th = [1.5, 1.0, 1.0]
    assert np.isnan(gb.static_curve(st, th, [1.0, 2.0], strict=False)).all()
    assert np.isnan(gb.static_gain(st, th, [1.0, 2.0], strict=False)).all()
    two = gb.Structure(["y(k-1)", "a(k-1)", "b(k-1)"])
    assert np.isnan(gb.static_surface_gain(two, [1.5, 1.0, 2.0], [[1.0, 2.0]], strict=False)).all()
