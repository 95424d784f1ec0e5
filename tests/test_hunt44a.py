"""Bug hunt 44a: reproducing the paper, the bundled data, decimation, input design, the neural NARMAX model."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb
from graybox.estimation._neural import neural_narx


@pytest.mark.parametrize("level", [0.1, 1000.1, 1e4 + 0.3])
def test_neural_refuses_a_held_input_at_any_level(level: float) -> None:
    # the mean of a constant 1000.1 is not exactly 1000.1: its std was 2e-13, taken for a scale, and the
    # network trained on a held input (0.1 was refused)
    rng = np.random.default_rng(0)
    rec = gb.Record(np.full(400, level), rng.standard_normal(400))
    with pytest.raises(ValueError, match="input is constant"):
        neural_narx(rec, ny=2, nu=2, ne=1, hidden=3, epochs=2, sim_epochs=0)


@pytest.mark.parametrize("level", [0.1, 1000.1, 1e4 + 0.3])
def test_neural_refuses_a_held_output_at_any_level(level: float) -> None:
    rng = np.random.default_rng(0)
    rec = gb.Record(rng.uniform(0.0, 1.0, 400), np.full(400, level))
    with pytest.raises(ValueError, match="output is constant"):
        neural_narx(rec, ny=2, nu=2, ne=1, hidden=3, epochs=2, sim_epochs=0)
