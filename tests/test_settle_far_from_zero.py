"""A slow equilibrium far from the input's zero settles: the run and the root finder fold the model's terms
(there about 1e6 each, cancelling to y near 1) in two ways, whose roundings put a slow equilibrium apart by
more than the settling tolerance, and such runs went on for their whole budget (9e6 steps) and ended 'not
settled'; select_graybox(centre=True) on data offset by 1e4 spreads spent minutes in them."""

from __future__ import annotations

import numpy as np

import graybox as gb
from graybox.static._analysis import REACHED, reached_equilibria

# an SE trial point met on the slow-disturbance case with u offset by 1e4 standard deviations: its stable
# equilibria have spectral radius 0.99999 at every static point
STRUCTURE = gb.Structure(["1", "y(k-1)", "u(k-1)", "y(k-2)", "u(k-3)", "y(k-3)", "u(k-2)^2", "u(k-3)^2", "u(k-2)",
                          "u(k-3)y(k-2)", "u(k-3)y(k-3)", "y(k-1)^2", "y(k-3)^2", "y(k-2)^2", "y(k-2)y(k-3)",
                          "u(k-1)u(k-3)"])
THETA = np.array([12.377766910481562, 1.5681237040932274, 204.0715272383953, -49.7596075250235, 299.0836904488699,
                  49.190931079404926, 0.03047671510867173, -0.005780805886837347, -503.15822165607324,
                  0.005996116708944546, -0.005996049776183604, 0.032059290660595145, -0.037092563284905206,
                  -0.12515069587359598, 0.13018395285595744, -0.02469572696302385])
UBAR = 8244.004051635331 + np.arange(7) * 0.6666666666666667
Y0 = np.array([1.3125, 2.256944444444445, 3.423611111111112, 4.8125, 6.423611111111112, 8.256944444444446, 10.3125])


def test_a_slow_equilibrium_far_from_the_input_s_zero_is_reached():
    model = gb.Model(STRUCTURE, THETA)
    stable = [[e for e in model.equilibria(u) if e.stable] for u in UBAR]
    assert all(len(s) == 1 and 0.9999 < s[0].spectral_radius < 1 for s in stable)  # the premise: slow, unique
    r = reached_equilibria(STRUCTURE, THETA[None], UBAR, Y0)
    assert (r.status == REACHED).all(), r.explain(0)
    np.testing.assert_allclose(r.ybar[0], [s[0].ybar for s in stable], rtol=1e-4)


def test_the_run_itself_heads_for_the_equilibrium_it_is_said_to_reach():
    model = gb.Model(STRUCTURE, THETA)
    r = reached_equilibria(STRUCTURE, THETA[None], UBAR[:1], Y0[:1])
    y = model.simulate(np.full(3_000_000, UBAR[0]), np.full(3, Y0[0]))  # 15 time constants
    # the free run adds the raw terms, each near 1e6, at every step: at ρ = 0.999995 their rounding moves its
    # end by 1e-4 of the level, which is as well as this model's equilibrium is defined so far from u's zero
    assert abs(y[-1] - r.ybar[0, 0]) <= 2e-4 * abs(r.ybar[0, 0])
    assert abs(y[-1] - r.ybar[0, 0]) < abs(y[0] - r.ybar[0, 0]) / 100
