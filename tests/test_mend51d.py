"""mend51d: residual tests held to their own n, level and rule; a unit named in a label; a regressor beyond the
float range; numbers beyond float64's range said so; a grid structure listed twice in another order."""

from __future__ import annotations

import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from graybox.plots._data import unit_label

# --- 2. unit_label: a unit that is also a word ("in", "A") was taken for the unit named; "Speed/rpm" got it again ---

@pytest.mark.parametrize("text, unit, label", [
    ("Speed (rpm)", "rpm", "Speed (rpm)"),
    ("Speed [rpm]", "rpm", "Speed [rpm]"),
    ("Speed/rpm", "rpm", "Speed/rpm"),
    ("Speed / rpm", "rpm", "Speed / rpm"),
    ("speed_rpm", "rpm", "speed_rpm"),
    ("Speed, rpm", "rpm", "Speed, rpm"),
    ("Speed in rpm", "rpm", "Speed in rpm"),
    ("Speed", "rpm", "Speed (rpm)"),
    ("rpm counter", "rpm", "rpm counter (rpm)"),       # the word, not the unit said
    ("Current (A)", "A", "Current (A)"),
    ("Current in A", "A", "Current in A"),
    ("Current_A", "A", "Current_A"),
    ("Current", "A", "Current (A)"),
    ("A pump's current", "A", "A pump's current (A)"),  # the article
    ("Current of pump A", "A", "Current of pump A (A)"),  # the pump's name
    ("Level in tank", "in", "Level in tank (in)"),       # the preposition
    ("Level in tank 2", "in", "Level in tank 2 (in)"),
    ("Level in in", "in", "Level in in"),
    ("Level (in)", "in", "Level (in)"),
    ("level [mlc]", "mlc", "level [mlc]"),
    ("level in mlc", "mlc", "level in mlc"),
    ("level_mlc", "mlc", "level_mlc"),
    ("level", "mlc", "level (mlc)"),
    ("Temperature in °C (mean)", "°C", "Temperature in °C (mean)"),
    ("Speed", "", "Speed"),
])
def test_unit_label_takes_a_unit_as_named_only_where_a_unit_is_written(text, unit, label):
    assert unit_label(text, unit) == label


@given(head=st.sampled_from(["Speed", "Level in tank", "A pump", "Pump A", "in", "Current in"]),
       unit=st.sampled_from(["A", "in", "rpm", "mlc", "°C"]),
       form=st.sampled_from(["{h} ({u})", "{h} [{u}]", "{h}/{u}", "{h}_{u}", "{h} in {u}", "{h}, {u}"]))
def test_a_label_with_its_unit_is_kept_and_a_label_without_it_gets_it_once(head, unit, form):
    named = form.format(h=head, u=unit)
    assert unit_label(named, unit) == named
    assert unit_label(unit_label(head, unit), unit) == unit_label(head, unit)  # never doubled
    assert unit_label(head, unit) == f"{head} ({unit})"
