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


def test_decimate_refuses_only_records_that_keep_fewer_than_two_samples() -> None:
    # samples 0 and q exist once the record has q + 1 samples: 1001 samples by 1000 keep two, yet the check
    # was n < 2q and said they "make fewer than 2"
    rng = np.random.default_rng(1)
    n, q = 1001, 1000
    rec = gb.Record(rng.uniform(0.0, 1.0, (n, 2)), rng.standard_normal(n), Ts=0.01, units=("rpm", "Pa"))
    out = gb.decimate(rec, q, antialias=False)
    assert len(out) == 2
    np.testing.assert_array_equal(out.u, rec.u[[0, q]])
    np.testing.assert_array_equal(out.y, rec.y[[0, q]])
    assert out.Ts == pytest.approx(q * rec.Ts) and out.units == rec.units
    with pytest.raises(ValueError, match="fewer than 2"):
        gb.decimate(rec.slice(0, q), q, antialias=False)
