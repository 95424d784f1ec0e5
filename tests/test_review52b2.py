"""review52b2: unit_label's bracketed naming (ac45c81): "in" before the unit in a bracket names it too."""

from __future__ import annotations

import pytest

from graybox.plots._data import unit_label


@pytest.mark.parametrize("text, unit", [("Speed (in rpm)", "rpm"), ("Level [in m]", "m"),
                                        ("Speed (rpm, filtered)", "rpm"), ("Flow [m^3/h; mean]", "m^3/h")])
def test_a_unit_named_in_brackets_with_in_or_a_remark_is_not_added_again(text, unit):
    # ac45c81 took a bracket as naming the unit only when it held the unit alone: 'Speed (in rpm)' became
    # 'Speed (in rpm) (rpm)' (before it, the word rule kept it as given)
    assert unit_label(text, unit) == text


@pytest.mark.parametrize("text, unit, want", [("Current of pump A", "A", "Current of pump A (A)"),
                                              ("Level in tank", "in", "Level in tank (in)"),
                                              ("Speed (mean)", "rpm", "Speed (mean) (rpm)"),
                                              ("P (kPa)", "Pa", "P (kPa) (Pa)"),
                                              ("Level (in tank)", "m", "Level (in tank) (m)")])
def test_brackets_without_the_unit_still_get_it(text, unit, want):
    assert unit_label(text, unit) == want
