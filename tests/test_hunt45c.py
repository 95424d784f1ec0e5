"""Bug hunt 45c: issue 26's promises (select_graybox, frols, semp, output_error) on small plants of one's own."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import graybox as gb
from graybox.static._form_check import carried_degree, static_terms


def _plant(n, seed, noise=0.02, hold=10):
    """A first-order NARX plant under a staircase in 0..2: y(k) = 0.8 y(k-1) + 0.5 u(k-1) + 0.1 u(k-1)² + 0.3."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.0, 2.0, n // hold + 1), hold)[:n]
    y = np.zeros(n)
    y[0] = (0.5 * u[0] + 0.1 * u[0] ** 2 + 0.3) / 0.2
    for k in range(1, n):
        y[k] = 0.8 * y[k - 1] + 0.5 * u[k - 1] + 0.1 * u[k - 1] ** 2 + 0.3
    return gb.Record(u, y + noise * np.std(y) * rng.standard_normal(n), name=f"run {seed}")


def _static(delta=0.05):
    ub = np.linspace(0.0, 1.9, 5)
    return gb.StaticPoints(ub, (0.5 * ub + 0.1 * ub ** 2 + 0.3) / 0.2, uncertainty=np.full(5, delta))


# --- a gray box of candidates without output terms (NFIR) ------------------------------------------------------
def test_a_candidate_set_without_output_terms_carries_a_polynomial_static_curve():
    # with no y term the static function is the numerator alone (Σy = 0): the clusters Σ0 … Σ_{u^d} carry a
    # degree-d curve; Σy was asked all the same, and select_graybox refused an NFIR gray box ("they need
    # output terms (Σy)") that pe_pareto and se_dsf fit
    cand = gb.Candidates(ny=0, nu=4, degree=2)
    assert carried_degree(cand, 2) == 2
    assert static_terms(gb.parse_structure("u(k-2)"), cand, 2) == [gb.parse_structure("1")[0],
                                                                   gb.parse_structure("u(k-1)^2")[0]]


def test_select_graybox_chooses_a_gray_box_among_nfir_structures():
    data = gb.Dataset(_plant(200, 1), _plant(150, 2), _static())
    sel = gb.select_graybox(gb.Candidates(ny=0, nu=4, degree=2), data, estimator="pe", sizes=[4, 6])
    assert sel.in_band and sel.degree == 2
    assert not any(t.power_of("y") for t in sel.structure)
    # the chosen static curve meets the points within the band
    assert gb.jsf(sel.model, data.static) <= sel.band
