"""review48g: check_count, frozen values, ParetoSet's fitting records, SEMP's budget warning."""

import numpy as np
import pytest

import graybox as gb
from graybox.core._validation import check_count


# 1. check_count: a count too large for a float (> 1.8e308) ended in a bare OverflowError naming nothing

@pytest.mark.parametrize("make, name", [
    (lambda: gb.GAOptions(population=10**400), "population"),
    (lambda: gb.design_input("prbs", 10**400, low=0.0, high=1.0, hold=2), "n_samples"),
    (lambda: check_count(10**400, "c"), "c"),
    (lambda: check_count(10**300, "c", item_bytes=10**300), "c"),
])
def test_a_count_beyond_any_float_is_refused_by_name(make, name):
    with pytest.raises(ValueError, match=f"{name}=10+ is too large"):
        make()


def test_check_count_still_takes_what_fits():
    assert check_count(10**6, "population") == 10**6
    assert check_count(10**8, "n_samples", item_bytes=8) == 10**8
