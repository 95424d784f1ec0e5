"""``real_array`` is ``float_array`` after refusing what a float conversion would take silently: one conversion
of numbers (a ragged nesting keeps real_array's TypeError, in float_array's words)."""

from __future__ import annotations

import numpy as np
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
