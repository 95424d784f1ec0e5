"""hunt49g: several inputs and long records."""

import numpy as np
import pytest

import graybox as gb


def test_regressor_matrix_one_column_with_two_input_names_is_refused():
    # a 1-D u with input_names of two inputs was silently read as the first input alone
    rng = np.random.default_rng(0)
    u, y = rng.uniform(size=20), rng.uniform(size=20)
    st = gb.Structure(["a(k-1)", "y(k-1)"])
    with pytest.raises(ValueError, match="one input column.*2 input names"):
        gb.regressor_matrix(st, u, y, input_names=("a", "b"))
    with pytest.raises(ValueError, match="one input column.*2 input names"):
        gb.regressor_matrix(st, u.tolist(), y, input_names=("a", "b"))
    # one input, one name: as before
    psi = gb.regressor_matrix(st, u, y, input_names=("a",))
    assert np.array_equal(psi[:, 0], u[:-1])
