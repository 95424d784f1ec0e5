"""review49e: checks of the simulation-error and selection commits efe008e … a07e3bc."""

import warnings

import numpy as np
import pytest

import graybox as gb

SPACE = gb.Candidates(ny=2, nu=2, degree=2)


@pytest.mark.parametrize("ey", [-600, 500])
def test_frols_centre_chooses_the_same_closure_on_data_scaled_by_a_power_of_two(ey):
    """8da3e11 scaled frols's search by powers of two, but frols(centre=True) judged its closure (told_apart), fitted
    its subsets and mapped θ on the centred data as given: on y × 2^-600 the closure of the same 5 chosen terms lost
    y(k-1), y(k-2) and u(k-2)y(k-1) ('a linear combination of lower terms'), ['u(k-2)', '1'] returned without an
    error, and on y × 2^500 it lost u(k-2)y(k-1)."""
    r = gb.load_pumping().ident
    base = gb.frols(SPACE, r, n_terms=5, centre=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sel = gb.frols(SPACE, gb.Record(r.u, np.ldexp(r.y, ey)), n_terms=5, centre=True)
    assert list(sel.structure) == list(base.structure)
    assert sel.skipped == base.skipped
    shift = [ey - sum(p * ey for s, _, p in t.factors if s == "y") for t in sel.structure]
    np.testing.assert_allclose(sel.theta, np.ldexp(base.theta, shift), rtol=1e-9)
    np.testing.assert_allclose(sel.rss, np.ldexp(base.rss, 2 * ey), rtol=1e-12)
    np.testing.assert_allclose(np.diff(sel.criterion_curve), np.diff(base.criterion_curve), rtol=1e-9)
    # the stop text names the offsets in the data's own units
    from graybox.selection._centring import search_offsets
    assert f"y − {search_offsets(gb.Record(r.u, np.ldexp(r.y, ey)))['y']:g}" in sel.stop
    assert sel.stop.replace(sel.stop.split("(y − ")[1].split(",")[0], "") == \
        base.stop.replace(base.stop.split("(y − ")[1].split(",")[0], "")
