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


def test_slices_of_a_static_surface_past_ten_are_drawn_in_colours_told_apart():
    # was: plot_surface_slices (and plot_static_band's slices) coloured slice k with C{k % 10}: the 1st and 11th alike
    from matplotlib.colors import to_rgba

    from graybox.plots import plot_surface_slices

    surface = gb.StaticSurface.polynomial({(0, 0): 1.0, (1, 0): 2.0, (0, 1): 0.5})
    for n in (3, 12, 25):
        fig = plot_surface_slices(surface, at=np.linspace(0.0, 1.0, n), urange=(0.0, 1.0), n_grid=5)
        colours = [to_rgba(line.get_color()) for line in fig.axes[0].lines]
        assert len(colours) == n and len(set(colours)) == n


def test_members_failing_for_one_reason_are_told_once():
    # was: pe_pareto with a constraint every member's check refused raised its message 40 times over, one per λ1
    # ('λ1 = 1e-06: static function passes …; λ1 = 1.4251e-06: static function passes …; …'), 20,000 characters
    data = gb.load_pumping()
    st = gb.parse_structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"])
    with pytest.raises(ValueError, match=r"^λ1 = 1e-06, 1\.4251e-06, 2\.03092e-06, … \(40 members\): static function "
                                         r"passes through") as err:
        gb.pe_pareto(st, data, constraints=[gb.PassesThrough()], lambdas=np.logspace(-6, 0, 40))
    assert str(err.value).count("static function passes through") == 1
