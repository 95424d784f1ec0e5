"""PumpingPlant's drive ramps (ramp_up=, ramp_down=): off by default, and a limit on the commanded speed's rate when on."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from graybox import reference
from graybox.datasets.pumping import DEFAULT_SEED, PumpingPlant, generate

PLANT = PumpingPlant()


def _step(a: float, b: float, hold: int = 10, after: int = 400) -> np.ndarray:
    return np.r_[np.full(hold, a), np.full(after, b)]


def test_default_has_no_ramp_and_leaves_the_runs_unchanged():
    assert PLANT.ramp_up == math.inf and PLANT.ramp_down == math.inf
    # a ramp that never binds (far above any rate the drive filter produces) gives the default run bit for bit
    never = PumpingPlant(ramp_up=1e12, ramp_down=1e12)
    run, static = generate(DEFAULT_SEED)
    run2, static2 = generate(DEFAULT_SEED, never)
    np.testing.assert_array_equal(run.y, run2.y)
    np.testing.assert_array_equal(static.ybar, static2.ybar)


def test_ramp_up_limits_rising_speed_only():
    slow = PumpingPlant(ramp_up=100.0)
    up, down = _step(1000.0, 1500.0), _step(1500.0, 1000.0)
    r = slow.simulate(up, noise=False, process_noise=False)
    free = PLANT.simulate(up, noise=False, process_noise=False)
    # the shaft lags the commanded speed, which rises at most 100 rpm/s from the step instant (sample 10)
    t = np.maximum(np.arange(r.speed.size) - 10, 0) * slow.Ts
    assert np.all(r.speed <= 1000.0 + 100.0 * t + 1e-9)
    assert np.diff(free.speed).max() / PLANT.Ts > 500.0  # without the ramp the same step is much faster
    # 500 rpm at 100 rpm/s takes 5 s: half-way after 2.5 s at the earliest
    half = np.argmax(r.speed >= 1250.0)
    assert (half - 10) * slow.Ts >= 2.5
    # falling is not ramped: the down step is the unramped plant's, sample for sample
    np.testing.assert_array_equal(slow.simulate(down, noise=False, process_noise=False).pressure,
                                  PLANT.simulate(down, noise=False, process_noise=False).pressure)


def test_ramp_down_limits_falling_speed_only():
    slow = PumpingPlant(ramp_down=80.0)
    r = slow.simulate(_step(1600.0, 900.0), noise=False, process_noise=False)
    t = np.maximum(np.arange(r.speed.size) - 10, 0) * slow.Ts
    assert np.all(r.speed >= 1600.0 - 80.0 * t - 1e-9)
    assert r.speed[10 + int(5.0 / slow.Ts)] > 1150.0  # 700 rpm at 80 rpm/s: still above 1200 rpm after 5 s
    up = _step(900.0, 1600.0)
    np.testing.assert_array_equal(slow.simulate(up, noise=False, process_noise=False).pressure,
                                  PLANT.simulate(up, noise=False, process_noise=False).pressure)


@settings(max_examples=15, deadline=None)
@given(up=st.floats(20.0, 2000.0), down=st.floats(20.0, 2000.0), a=st.integers(75, 165), b=st.integers(75, 165))
def test_ramps_bound_the_shaft_speed_and_keep_the_static_curve(up, down, a, b):
    plant = PumpingPlant(ramp_up=up, ramp_down=down)
    u = _step(10.0 * a, 10.0 * b, after=int(round((abs(a - b) * 10.0 / min(up, down) + 20.0) / plant.Ts)))
    r = plant.simulate(u, noise=False, process_noise=False)
    # the shaft lags the commanded speed, which moves at most up (down) rpm/s from the step instant
    t = np.maximum(np.arange(r.speed.size) - 10, 0) * plant.Ts
    assert np.all(r.speed <= 10.0 * a + up * t + 1e-9) and np.all(r.speed >= 10.0 * a - down * t - 1e-9)
    # a ramp delays the steady state, it does not move it: the rig still settles on eq. (1)
    assert abs(r.pressure[-1] - reference.eq1(10.0 * b)) < 1e-6


@pytest.mark.parametrize("bad", [0.0, -5.0, float("nan"), "fast"])
def test_ramps_are_validated(bad):
    for name in ("ramp_up", "ramp_down"):
        with pytest.raises(ValueError, match=name):
            PumpingPlant(**{name: bad})


def test_two_speed_rig_refuses_ramps():
    from graybox.datasets._pumping_miso import TwoSpeedPumpingPlant
    with pytest.raises(ValueError, match="no drive ramps"):
        TwoSpeedPumpingPlant(rig=PumpingPlant(ramp_down=300.0))
    TwoSpeedPumpingPlant(rig=PumpingPlant())  # the default rig has none
