"""hunt53c: the honest-selection surfaces (select_graybox, output error, the best-subset searches)."""

import warnings

import numpy as np
import pytest

import graybox as gb


def _first_order(seed, n=200):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.5, 2.0, n // 10 + 1), 10)[:n]
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.7 * y[k - 1] + 0.2 * u[k - 1] + 0.05 * u[k - 1] ** 2
    return gb.Record(u, y + 0.01 * rng.standard_normal(n), name=f"first order {seed}")


@pytest.fixture(scope="module")
def small():
    return gb.Dataset(_first_order(1), _first_order(2))


@pytest.mark.parametrize("sources", [["swap"], ["exact"], ["frols", "swap"]])
def test_a_size_below_the_included_terms_is_left_out_by_every_source(small, sources):
    # sizes=[1, 2, 3] with two included terms: the semp and frols sources leave size 1 out with a SelectionWarning,
    # but a swap or exact source ended the whole call with frols's "n_terms = 1 is fewer than the 2 included terms"
    with pytest.warns(gb.SelectionWarning, match=r"sizes no search reached are left out: .*(swap|exact): \[1\]"):
        s = gb.select_graybox(gb.Candidates(ny=1, nu=1, degree=1), small, estimator="ls", include=["1", "y(k-1)"],
                              sizes=[1, 2, 3], sources=sources)
    assert set(s.table["size"]) == {2, 3}
