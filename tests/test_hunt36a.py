"""Bugs found by a bug hunt from model to controller (graybox.control), in growing grids and their
reports (graybox.experiments, select_graybox's result) and on the command line, used as a control
engineer would on a plant of their own (Pa and rpm, inputs not named "u", two inputs): each test
fails without its fix."""

import numpy as np
import pytest

import graybox as gb

#: p(k) = 0.5 p(k-1) + 2e-5 n(k-1) + 3 (a pressure in bar against a speed in rpm).
RPM = gb.Model(["1", "y(k-1)", "n(k-1)"], [3.0, 0.5, 2e-5], input_names=("n",))
#: Two inputs, "n" (rpm) and "valve" (0-1).
TWO = gb.Model(["1", "y(k-1)", "n(k-1)", "valve(k-1)"], [3.0, 0.5, 2e-5, 1.0], input_names=("n", "valve"))


@pytest.mark.parametrize("bad", ["3000", None, [1.0, "a"], True, [[1.0, 2.0], [3.0]], object()])
@pytest.mark.parametrize("call", [
    lambda bad: gb.local_model(RPM, bad, Ts=0.1),
    lambda bad: gb.operating_curve(RPM, bad, Ts=0.1),
    lambda bad: gb.local_model(TWO, bad, Ts=0.1),
    lambda bad: gb.narx_steady_state(RPM, bad, 9.0),
])
def test_operating_points_that_are_not_numbers_are_a_type_error_naming_ubar(call, bad):
    # ubar went through numpy's float conversion: a string was "ValueError: could not convert string to float"
    # (naming no argument), None became NaN ("ubar has non-finite values"), True became the level 1.0
    with pytest.raises(TypeError, match="ubar"):
        call(bad)
