"""Review of select_graybox over several records and of decimation (review38): each test a bug found."""

import numpy as np
import pytest

import graybox as gb


@pytest.mark.parametrize("scale, offset", [(1.0, 10.0), (1000.0, -3.0), (1e-3, 50.0)])
def test_decimation_advice_does_not_depend_on_the_outputs_unit_or_offset(scale, offset):
    """y² − mean(y²) of an offset output is mostly 2·offset·y: its minimum was τ_y's, not the nonlinear one."""
    P, n = 400, 20000
    k = np.arange(n)
    y = np.sin(2 * np.pi * k / P)
    a = gb.decimation_advice(gb.Record(np.zeros(n), y))
    b = gb.decimation_advice(gb.Record(np.zeros(n), scale * y + offset))
    assert (b.q, b.q_range, b.tau_y, b.tau_y2, b.tau_m) == (a.q, a.q_range, a.tau_y, a.tau_y2, a.tau_m)


def test_a_centred_drift_gets_no_advice_as_the_drift_does():
    """The square of a centred drift is a U: read as a time scale of the record's length it gave a factor."""
    y = np.arange(2000.0) ** 1.5
    for rec in (gb.Record(np.zeros(2000), y), gb.Record(np.zeros(2000), y - y.mean())):
        assert gb.decimation_advice(rec).q is None


def test_a_list_of_choosing_records_holding_something_else_names_that_element_not_the_whole_list():
    """The message printed the whole list (every record's repr) and said not which element was wrong; an
    empty list of test records was 'at least one choosing record is needed' (a test record chooses nothing)."""
    from graybox.core._records import choosing_records

    rec = gb.Record(np.zeros(50), np.arange(50.0), name="r")
    ds = gb.Dataset(rec, rec)
    with pytest.raises(TypeError, match=r"validation\[1\] is a Dataset") as err:
        choosing_records([rec, ds], "validation")
    assert repr(rec) not in str(err.value)
    with pytest.raises(TypeError, match=r"test\[2\] is a str"):
        choosing_records((rec, rec, "x"), "test", "a fresh record of the plant")
    with pytest.raises(TypeError, match="validation must be a Record or a sequence of Records.*got a Dataset"):
        choosing_records(ds, "validation")
    with pytest.raises(ValueError, match="test: an empty list; at least one record is needed"):
        choosing_records([], "test", "a fresh record of the plant")
