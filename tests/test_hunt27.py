"""Bugs found by a bug hunt from model to controller (graybox.control) and in growing grids
(graybox.experiments): each test fails without its fix."""

import warnings

import numpy as np
import pytest

import graybox as gb

#: y(k) = 0.5 y(k-1) + s(k-1): one input named "speed", gain 2.
SPEED = gb.Model(["y(k-1)", "speed(k-1)"], [0.5, 1.0], input_names=("speed",))


def two_input_record(n: int = 200) -> gb.Record:
    """A record of two inputs, "valve" in [0, 1] and "speed" in [5, 10], whose output SPEED explains."""
    rng = np.random.default_rng(0)
    valve, speed = rng.uniform(0.0, 1.0, n), rng.uniform(5.0, 10.0, n)
    return gb.Record(np.column_stack([valve, speed]), SPEED.simulate(speed, np.zeros(1)), 1.0,
                     input_names=("valve", "speed"))


def test_range_of_a_one_input_model_is_read_from_its_own_input_of_the_record():
    # the range check took a one-input model's range from every column of the record: a record with a
    # second input was refused, and a record whose one input has another name gave that input's range
    rec = two_input_record()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        lm = gb.local_model(SPEED, 7.0, data=rec)  # inside the speed's range [5, 10]: no warning
    assert lm.reached and lm.dc_gain[0] == pytest.approx(2.0)
    with pytest.warns(gb.StaticRangeWarning, match="outside the input range"):
        gb.local_model(SPEED, 0.5, data=rec)  # inside the valve's range, outside the speed's
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        oc = gb.operating_curve(SPEED, [6.0, 8.0], data=rec)
    assert np.allclose(oc.gain, 2.0)
    other = gb.Record(rec.input("valve"), rec.y, 1.0, input_names=("valve",))
    with pytest.raises(ValueError, match="speed"):
        gb.local_model(SPEED, 0.5, data=other)


def test_two_input_operating_curve_frame_keeps_the_gain_bands():
    # to_frame kept only one-dimensional bands: a two-input curve's gain bands were silently left out
    two = gb.Model(["1", "y(k-1)", "u1(k-1)", "u2(k-1)", "u1(k-1)u2(k-1)"], [0.2, 0.5, 0.3, -0.2, 0.05],
                   input_names=("u1", "u2"))
    rng = np.random.default_rng(1)
    U = np.column_stack([rng.uniform(0.5, 1.5, 400), rng.uniform(0.2, 0.8, 400)])
    rec = gb.Record(U, two.simulate(U, np.zeros(1)) + 0.01 * rng.standard_normal(400), 0.1,
                    input_names=("u1", "u2"))
    model = gb.els(two.structure, rec, noise=0).model
    oc = gb.operating_curve(model, [[1.0, 0.5], [1.2, 0.4]], data=rec,
                            uncertainty=gb.ls_uncertainty(model, rec), n_samples=50)
    frame = oc.to_frame()
    for i, name in enumerate(("u1", "u2")):
        assert np.array_equal(frame[f"gain low {name}"], oc.gain_low[:, i])
        assert np.array_equal(frame[f"gain high {name}"], oc.gain_high[:, i])
    assert np.array_equal(frame["time constant low"], oc.time_constant_low)
