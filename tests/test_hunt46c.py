"""Bugs found by the hunt of session 46 (c): simulation-error estimation as a researcher drives it."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb


def _set(lambdas, J1=(0.0, 0.0), JS=(0.0, 0.0), JSF=(0.0, 0.0)):
    st = gb.parse_structure(["1", "y(k-1)"])
    return gb.ParetoSet(st, np.zeros((2, 2)), np.asarray(lambdas, float), np.asarray(J1, float),
                        np.asarray(JS, float), np.asarray(JSF, float))


@pytest.mark.parametrize("lam", [(1.5, 0.5), (0.5, 0.0), (-0.2, 1.0), (np.inf, 1.0)])
def test_pareto_set_refuses_a_weight_outside_0_1(lam):
    with pytest.raises(ValueError, match="lambdas"):
        _set(lam)


@pytest.mark.parametrize("field", ["J1", "JS", "JSF"])
def test_pareto_set_refuses_a_negative_mean_square(field):
    with pytest.raises(ValueError, match=field):
        _set((0.5, 1.0), **{field: (-1.0, 0.0)})


def test_pareto_set_keeps_nan_weights_and_inf_errors():
    p = _set((np.nan, 1.0), JS=(np.inf, 0.0), JSF=(np.nan, 0.0))
    assert np.isnan(p.lambdas[0]) and p.JS[0] == np.inf
