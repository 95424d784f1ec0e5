"""hunt50c: reproducing the paper and the bundled data (graybox.reproduce, graybox.datasets)."""

import numpy as np
import pytest

from graybox.datasets.pumping import PumpingPlant


@pytest.mark.parametrize("kw,error,match", [
    ({"surge_time": True}, TypeError, "surge_time"),         # a surge decaying in 1 s, silently
    ({"air_vent_time": True}, TypeError, "air_vent_time"),   # air venting in 1 s, silently
    ({"surge_time": "6"}, TypeError, "surge_time"),          # text is a wrong type, not a wrong value
    ({"dead_time": "0.02"}, TypeError, "dead_time"),         # "unsupported operand type(s) for /: 'str' and 'float'"
    ({"dead_time": None}, TypeError, "dead_time"),
])
def test_pumping_plant_times_are_numbers(kw, error, match):
    with pytest.raises(error, match=f"PumpingPlant: {match}"):
        PumpingPlant(**kw)


def test_pumping_plant_takes_numpy_times():
    # np.float32(6.0) was refused as 'surge_time must be a positive finite number', as inertia's was before hunt49b
    plant = PumpingPlant(surge_time=np.float32(6.0), air_vent_time=np.float32(30.0), dead_time=np.float64(0.02))
    u = np.r_[np.full(40, 1000.0), np.full(40, 1300.0)]
    assert plant.simulate(u, seed=3).y == pytest.approx(PumpingPlant().simulate(u, seed=3).y, rel=1e-6)
