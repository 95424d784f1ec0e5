"""Mends of batch 36a: items earlier bug hunts left open — the delta-method static band at an
input offset, PE's QP scaling at an output offset, a NaN θ scored as a model, unchecked ``name=``
arguments, and SEMP's unbounded pruning scores."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb


# -- 3. evaluate_thetas and a parameter vector that is not a model ------------------------------

@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_evaluate_thetas_refuses_a_non_finite_theta_row_naming_it(bad):
    # was: a NaN (or inf) θ row scored J1 = JS = JSF = inf with no word, as if it were a diverging model
    data = gb.load_pumping()
    st = gb.parse_structure(["1", "y(k-1)", "u(k-1)"])
    th = np.array([[0.1, 0.9, 1e-3], [0.1, 0.9, 1e-3], [bad, 0.9, 1e-3]])
    with pytest.raises(ValueError, match=r"thetas.*row.*\[2\]"):
        gb.evaluate_thetas(st, th, data.valid, data.static)
    with pytest.raises(ValueError, match=r"thetas.*row.*\[2\]"):
        gb.evaluate_thetas(st, th, None, data.static)
    ok = gb.evaluate_thetas(st, th[:2], data.valid, data.static)
    assert np.all(np.isfinite(ok["JS"])) and np.all(np.isfinite(ok["JSF"]))
