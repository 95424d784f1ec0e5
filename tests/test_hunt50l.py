"""hunt50l: diagnostics (residual tests, parameter uncertainty, simulation band, bootstrap) against their promises."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import graybox as gb

STRUCT = ["y(k-1)", "u(k-1)", "u(k-1)^2", "1"]


def _record(seed: int = 0, n: int = 400) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = rng.uniform(0, 2, n)
    e = 0.05 * rng.standard_normal(n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.7 * y[k - 1] + 0.8 * u[k - 1] - 0.2 * u[k - 1] ** 2 + 0.1 + e[k]
    return gb.Record(u, y, name="r")


REC = _record()
MODEL = gb.els(STRUCT, REC, noise=0).model


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_covers_refuses_a_non_finite_theta(bad):
    # covers(θ) answered False for a NaN (or inf) component, silently, as if a true value lay outside its interval
    unc = gb.ls_uncertainty(MODEL, REC)
    th = unc.theta.copy()
    th[1] = bad
    with pytest.raises(ValueError, match="finite"):
        unc.covers(th)
    assert unc.covers(unc.theta).all()
