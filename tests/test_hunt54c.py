"""hunt54c: several inputs, long records and the statics of several inputs."""

import numpy as np
import pytest

import graybox as gb


def test_regressor_matrix_reads_one_input_column_as_a_record_does_whatever_its_container():
    # an (N, 1) float64 array skipped the coercion and was read as input 'u1', while the same samples as a list (or in
    # a Record) are the one input 'u': u(k-1) was refused for the array and u1(k-1) for the list
    rng = np.random.default_rng(0)
    u, y = rng.uniform(size=20), rng.uniform(size=20)
    st = gb.Structure(["u(k-1)", "y(k-1)"])
    flat = gb.regressor_matrix(st, u, y)
    for col in (u[:, None], u[:, None].tolist(), np.asfortranarray(u[:, None])):
        assert np.array_equal(gb.regressor_matrix(st, col, y), flat)
    assert np.array_equal(gb.stacked_regressors(st, gb.Record(u[:, None], y))[0], flat)
    named = gb.Structure(["u1(k-1)", "y(k-1)"])
    assert np.array_equal(gb.regressor_matrix(named, u[:, None], y, input_names=("u1",)), flat)
    for col in (u[:, None], u[:, None].tolist()):
        with pytest.raises(ValueError, match="needs input 'u1'"):
            gb.regressor_matrix(named, col, y)
