import numpy as np
import pytest

from graybox import Candidates, Record, regressor_matrix, stacked_regressors


def naive(structure, u, y, start):
    rows = []
    for k in range(start, len(u)):
        row = []
        for t in structure:
            v = 1.0
            for s, lag, p in t.factors:
                v *= ({"u": u, "y": y}[s][k - lag]) ** p
            row.append(v)
        rows.append(row)
    return np.array(rows)


def test_matches_naive_loop(rng):
    u = rng.uniform(700, 1700, 80)
    y = rng.normal(10, 3, 80)
    s = Candidates(3, 3, ne=0, degree=3)
    np.testing.assert_allclose(regressor_matrix(s, u, y), naive(s, u, y, 3), rtol=1e-14)
    np.testing.assert_allclose(regressor_matrix(s, u, y, start=5), naive(s, u, y, 5), rtol=1e-14)


def test_records_are_not_straddled(rng):
    s = Candidates(2, 2, ne=0, degree=1)
    r1 = Record(rng.normal(size=20), rng.normal(size=20))
    r2 = Record(rng.normal(size=15), rng.normal(size=15))
    psi, target = stacked_regressors(s, [r1, r2])
    assert psi.shape == (18 + 13, len(s))
    np.testing.assert_array_equal(psi[18:], regressor_matrix(s, r2.u, r2.y))
    np.testing.assert_array_equal(target[18:], r2.y[2:])


def test_start_below_max_lag_and_short_record():
    s = Candidates(3, 3, ne=0, degree=1)
    with pytest.raises(ValueError, match="max lag"):
        regressor_matrix(s, np.ones(10), np.ones(10), start=2)
    with pytest.raises(ValueError, match="fewer than max lag"):
        stacked_regressors(s, Record(np.ones(3), np.ones(3)))
