"""``real_array`` is ``float_array`` after refusing what a float conversion would take silently: one conversion
of numbers (a ragged nesting keeps real_array's TypeError, in float_array's words)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import graybox as gb
from graybox.core._validation import float_array, real_array


@pytest.mark.parametrize("x", [[1, 2.5], [[1, 2], [3, 4]], np.arange(4.0), 3.0, (np.float32(1), 2)])
def test_numbers_convert_as_float_array_does(x):
    got = real_array(x, "x")
    assert got.dtype == np.float64
    np.testing.assert_array_equal(got, float_array(x, "x"))


def test_the_result_is_a_copy():
    a = np.arange(3.0)
    real_array(a, "x")[0] = 7.0
    assert a[0] == 0.0


@pytest.mark.parametrize("x", [None, [1.0, None], True, np.array([True, False]), [True, 2.0], "1.5", [1 + 2j]])
def test_what_a_float_conversion_would_take_silently_is_a_type_error(x):
    with pytest.raises(TypeError, match="x must be"):
        real_array(x, "x")


def test_a_ragged_nesting_is_a_type_error_in_float_arrays_words():
    with pytest.raises(TypeError, match="rows of different lengths"):
        real_array([[1.0, 2.0], [3.0]], "x")
    with pytest.raises(ValueError, match="rows of different lengths"):  # float_array: a bad shape
        float_array([[1.0, 2.0], [3.0]], "x")


def test_a_public_path_gives_the_same_errors():
    curve = gb.StaticCurve([0.5, 1.0])
    with pytest.raises(TypeError, match="ubar .*rows of different lengths"):
        curve([[1.0, 2.0], [3.0]])
    with pytest.raises(TypeError, match="ubar must be"):
        curve([1.0, None])


_FLAGS = np.array([True, False, True, True, False, True])
_NUMS = _FLAGS.astype(float)


@pytest.mark.parametrize("call, name", [
    (lambda: gb.fit_percent([True, False, True], [1.0, 0.0, 1.0]), "y"),  # was 100 (%): True read as 1
    (lambda: gb.mse(_FLAGS, _NUMS), "y"),
    (lambda: gb.Record(_NUMS, _FLAGS), "record: y"),
    (lambda: gb.Record(_FLAGS, _NUMS), "record: u"),
    (lambda: gb.Record([True, 1.5, 2.0, 3.0, 1.0, 0.0], _NUMS), "record: u"),  # one flag among numbers
    (lambda: gb.Record(pd.Series(_FLAGS, name="u"), _NUMS), "record: u"),
    (lambda: gb.Record(pd.DataFrame({"u1": _FLAGS, "u2": _NUMS[::-1]}), np.arange(6.0)), "record: u"),
    (lambda: gb.StaticPoints([1.0, 2.0, 3.0], [True, False, True]), "static points: ybar"),
    (lambda: gb.StaticPoints([True, False], [1.0, 2.0]), "static points: ubar"),
    (lambda: gb.regressor_matrix(gb.Structure(["y(k-1)", "u(k-1)"]), _FLAGS, _NUMS), "u"),
    (lambda: gb.regressor_matrix(gb.Structure(["y(k-1)", "u(k-1)"]), _NUMS, _FLAGS), "y"),
    (lambda: gb.Model(gb.Structure(["y(k-1)", "u(k-1)"]), [0.5, 1.0]).simulate(_FLAGS, y0=[0.0]), "u"),
])
def test_booleans_are_no_samples_a_type_error_naming_the_argument(call, name):
    """True and False were read as 1 and 0 (fit_percent([True, False, True], [1, 0, 1]) was 100 %): a flag where
    samples are meant is a wrong type, as it is in θ (mend60g)."""
    with pytest.raises(TypeError, match=f"^{name} must be numbers.*astype\\(float\\)"):
        call()
