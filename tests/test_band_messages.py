"""A J_SF just outside the band is said with the digits that keep it outside, as B is printed."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

import graybox as gb


@pytest.mark.parametrize("band, rel", [(0.0306, 1e-6), (0.0306, 1e-9), (0.03059995, 1e-8), (2.0, 1e-12)])
def test_decide_dsf_says_the_smallest_jsf_outside_the_band_it_missed(band, rel):
    # was: "has J_SF in B = [0, 0.0306] …; the smallest J_SF is 0.0306", a reason that contradicts itself
    data = gb.load_pumping()
    front = gb.pe_pareto(gb.parse_structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"]), data,
                         lambdas=np.logspace(-4, 0, 5))
    jsf = np.asarray(front.JSF, float)
    front = dataclasses.replace(front, JSF=band * (1 + rel) * jsf / np.min(jsf))  # the smallest just outside B
    with pytest.raises(ValueError, match="no member of the Pareto set") as err:
        gb.decide_dsf(front, band=band)
    shown_band, shown_best = re.search(r"B = \[0, ([^\]]+)\].*the smallest J_SF is ([0-9.e+-]+)\.", str(err.value)).groups()
    assert float(shown_best) > float(shown_band)
