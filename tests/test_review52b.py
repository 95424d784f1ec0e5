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


def _large_record():
    import numpy as np

    import graybox as gb
    rng = np.random.default_rng(0)
    u = rng.uniform(1, 2, 60)
    y = 1e150 * rng.uniform(1, 2, 60)  # y(k-1)^2 near 1e300: large, finite
    return gb.Record(u=u, y=y, Ts=1.0)


def test_column_scales_of_a_large_finite_column():
    import numpy as np

    from graybox.core._least_squares import column_scales
    A = np.array([[1e300, 1.0], [2e300, 3.0]])
    s = column_scales(A)
    np.testing.assert_allclose(s, [np.sqrt((1 + 4) / 2) * 1e300, np.sqrt(5.0)], rtol=1e-12)


def test_els_and_semp_take_a_large_finite_regressor():
    # the columns' RMS squared them: y(k-1)^2 ~ 1e300 overflowed to an inf scale, numpy warned 'overflow encountered
    # in square' and ELS called the structure not identifiable (its column scaled to zero)
    import graybox as gb
    rec = _large_record()
    res = gb.els(["y(k-1)^2", "y(k-1)*u(k-1)", "1"], rec)
    assert len(res.model.structure) == 3
    sel = gb.semp(gb.Candidates(1, 1, degree=2), rec, n_terms=3)
    assert sel is not None
