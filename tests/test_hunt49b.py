"""hunt49b: from model to controller and the signals (control, inputs, decimation, plants, reference)."""

import numpy as np
import pytest

import graybox as gb
from graybox.datasets import TwoSpeedPumpingPlant
from graybox.datasets.pumping import PumpingPlant

QUIET = {"noise": False, "process_noise": False}


@pytest.mark.parametrize("x0,error,match", [
    ((1200.0, 1200.0), ValueError, "x0 must be 3"),                    # numpy's 'not enough values to unpack'
    ((1200.0, 1200.0, 40.0, 1.0), ValueError, "x0 must be 3"),         # 'too many values to unpack (expected 3)'
    (1200.0, ValueError, "x0 must be 3"),                               # "'float' object is not iterable"
    ("123", TypeError, "x0"),                                           # read as the state (1, 2, 3)
    ((1200.0, 1200.0, "40"), TypeError, "x0"),                          # the flow parsed from text
    ((1200.0, 1200.0, True), TypeError, "x0"),                          # a flow of 1 L/s
    ({"a": 1, "b": 2, "c": 3}, TypeError, "x0"),                         # 'could not convert string to float'
    ((1200.0, np.nan, 40.0), ValueError, "x0 must be 3 finite"),
    ((1200.0, 1200.0, -1.0), ValueError, "Q >= 0"),
])
def test_plant_initial_state_is_three_numbers(x0, error, match):
    # simulate and closed_loop unpacked x0 with (float(x) for x in x0): a wrong length failed in Python's words
    # naming nothing, text was parsed and a bool taken for a number; the two-speed rig took text and bools too
    plant = PumpingPlant()
    with pytest.raises(error, match=match):
        plant.simulate(np.full(5, 1200.0), x0=x0, **QUIET)
    with pytest.raises(error, match=match):
        plant.closed_loop(lambda k, y: 1200.0, 5, u0=1200.0, x0=x0, **QUIET)
    run = plant.simulate(np.full(5, 1200.0), x0=np.array(plant.steady_state(1200.0)), **QUIET)
    assert run.y == pytest.approx(plant.simulate(np.full(5, 1200.0), **QUIET).y)


@pytest.mark.parametrize("x0,error", [((1200.0, 1200.0, 1100.0, 1100.0, "40"), TypeError),
                                      ((1200.0, 1200.0, 1100.0, 1100.0, True), TypeError),
                                      ("12345", TypeError), (1200.0, ValueError)])
def test_two_speed_initial_state_is_five_numbers(x0, error):
    with pytest.raises(error, match="x0"):
        TwoSpeedPumpingPlant().simulate(np.full((5, 2), 1200.0), x0=x0, **QUIET)
