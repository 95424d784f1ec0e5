"""mend50d: D_SF's fallback takes the member nearest the band; a loaded Pareto set still knows its fitting records;
batched equilibria of static equations of degree >= 4; the grid's counts."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as hs

import graybox as gb
from graybox import reference
from graybox.estimation._decisions import decide_dsf
from graybox.estimation._pareto import ParetoSet

S15 = reference.STRUCTURE_15


def front(js, jsf):
    k = len(js)
    th = np.tile(reference.TABLE_II["ELS"], (k, 1)) * (1 + 0.01 * np.arange(k))[:, None]
    return ParetoSet(S15, th, np.linspace(1.0, 0.1, k), np.zeros(k), np.asarray(js, float), np.asarray(jsf, float),
                     "PE")


# 1. the fallback 'min_jsf' with a two-sided band -------------------------------------------------------------------

def test_fallback_takes_the_member_nearest_a_two_sided_band():
    # every J_SF below B = [0.1, 0.2]: was member 2 (J_SF 0.001, the farthest from B); the nearest is member 0
    ps = front([1.0, 2.0, 3.0], [0.09, 0.05, 0.001])
    d = decide_dsf(ps, band=(0.1, 0.2), fallback="min_jsf")
    assert d.index == 0 and d.rule == "min J_SF" and not d.in_band
    assert "nearest" in d.model.name
    # below and above: the nearer side wins (0.25 is 0.05 above, 0.02 is 0.08 below)
    assert decide_dsf(front([1.0, 2.0], [0.02, 0.25]), band=(0.1, 0.2), fallback="min_jsf").index == 1
    # equally far on either side: the smaller J_S, as ties always were
    assert decide_dsf(front([2.0, 1.0], [0.05, 0.25]), band=(0.1, 0.2), fallback="min_jsf").index == 1


@settings(max_examples=60, deadline=None)
@given(hs.lists(hs.floats(0.0, 10.0), min_size=1, max_size=6), hs.floats(0.01, 5.0), hs.floats(0.01, 5.0))
def test_fallback_is_nearest_to_the_band_and_unchanged_for_zero_low(jsf, low, width):
    jsf = np.asarray(jsf)
    js = 1.0 + np.arange(jsf.size)
    high = low + width
    assume(not np.any((jsf >= low) & (jsf <= high)))
    d = decide_dsf(front(js, jsf), band=(low, high), fallback="min_jsf")
    dist = np.maximum(np.maximum(low - jsf, jsf - high), 0.0)
    assert dist[d.index] == dist.min()
    # B = [0, b]: still the smallest J_SF (ties by J_S: the lower index here)
    assume(not np.any(jsf <= high))
    assert decide_dsf(front(js, jsf), band=high, fallback="min_jsf").index == int(np.argmin(jsf))
