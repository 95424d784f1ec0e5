"""review52b: unit_label (ac45c81) after its bracket rule."""
import pytest

from graybox.plots._data import unit_label


@pytest.mark.parametrize("text", ["Speed (rpm, mean)", "Speed (mean, rpm)", "Speed [rpm; filtered]"])
def test_unit_label_unit_in_a_bracket_with_a_remark_is_named(text):
    # before ac45c81 '(rpm,' counted as naming the unit; the bracket rule asked for '(rpm)' exactly
    assert unit_label(text, "rpm") == text


@pytest.mark.parametrize("text,unit", [("y (rpm)", "rpm"), ("Level [m]", "m"), ("Pressure in Pa", "Pa"),
                                       ("u (%)", "%"), ("Speed", "")])
def test_unit_label_ordinary_units(text, unit):
    assert unit_label(text, unit) == text


def test_unit_label_remark_bracket_without_unit_still_gets_it():
    assert unit_label("Speed (mean, filtered)", "rpm") == "Speed (mean, filtered) (rpm)"
    assert unit_label("Current (pump A, mean)", "A") == "Current (pump A, mean) (A)"
