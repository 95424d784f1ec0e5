"""hunt51c: from model to controller (local models, python-control systems) and the input-design helpers."""

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st

from graybox.datasets.pumping import speed_reference


@settings(deadline=None, max_examples=60)
@given(low=st.floats(100.0, 1500.0), span=st.floats(85.0, 1500.0), seed=st.integers(0, 1000))
def test_speed_reference_forces_holds_within_30_rpm_of_both_ends(low, span, seed):
    # the docstring: "one hold is forced to within 30 rpm of low, another of high". The forced level was drawn in
    # [low, low + 30] and then rounded to a multiple of 10 rpm, which went up to 5 rpm past: low = 188 rpm gave a
    # part whose lowest level was 220 rpm (32 rpm above low)
    high = low + span
    assume(np.floor(high / 10) - np.ceil(low / 10) >= 8)  # the span the reference takes
    r = speed_reference(n_samples=1200, n_ident=600, seed=seed, low=low, high=high)
    for part in (r[:600], r[600:]):
        assert part.min() - low <= 30.0
        assert high - part.max() <= 30.0


def test_speed_reference_end_holds_at_a_range_off_the_10_rpm_grid():
    r = speed_reference(n_samples=2818, n_ident=1495, seed=395, low=188.0, high=1300.0)
    assert r[:1495].min() <= 218.0  # was 220
    assert np.all(r % 10 == 0) and r.min() >= 188.0 and r.max() <= 1300.0
