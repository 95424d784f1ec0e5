"""hunt50e: the less hunted estimators (neural NARMAX, se_dsf, the local models, ELS)."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb


def _exact(n: int = 300, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A noise-free record of 0.1 + 0.5 y(k-1) + 0.3 u(k-1) + 0.4 u(k-1)²: least squares fits it to round-off."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(0.0, 1.0, n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.1 + 0.5 * y[k - 1] + 0.3 * u[k - 1] + 0.4 * u[k - 1] ** 2
    return u, y


EXACT = ["1", "y(k-1)", "u(k-1)", "u(k-1)^2"]


@pytest.mark.parametrize("offset", [1e4, -1e4, 1e6])
def test_els_of_data_it_fits_exactly_has_no_ma_part_at_any_zero_of_y(offset):
    # noise-free data: the least-squares residuals are round-off, and ELS gives the MA part zero, 0 iterations. At
    # y + 1e4 (the same data in another zero) the centred output carried the round-off of the raw levels (1e4 ulps),
    # which the test held against the centred output's RMS: it fitted an MA part to round-off, C = 1 - 0.50 q^-1 -
    # 0.16 q^-2 in 58 iterations
    u, y = _exact()
    ref = gb.els(EXACT, gb.Record(u=u, y=y))
    assert ref.n_iter == 0 and np.all(ref.model.noise_theta == 0.0)
    res = gb.els(EXACT, gb.Record(u=u, y=y + offset))
    assert res.n_iter == 0 and res.converged
    assert np.all(res.model.noise_theta == 0.0), res.model.noise_theta
    sim = res.model.simulate(gb.Record(u=u, y=y + offset)) - offset
    assert np.max(np.abs(sim - y)) < 1e-9 * max(1.0, abs(offset))
