"""Results that should not depend on the zero or the units of the signals (mend51e): each test fits the same data
at two zeros (or units) and compares the results to a relative tolerance justified beside it."""

import numpy as np
import pytest

import graybox as gb
from graybox.reference import STRUCTURE_15
from graybox.selection._centring import closure


def _pumping_at(c: float, data=None):
    """The bundled plant's identification record and static points with c added to the output."""
    data = gb.load_pumping() if data is None else data
    r = data.ident
    return gb.Record(r.u, r.y + c, name=r.name), gb.StaticPoints(data.static.ubar, data.static.ybar + c)


# -- 1. starts="pe" ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("offset", [1e4, 1e6])
def test_pe_starts_of_a_centred_problem_do_not_depend_on_the_output_zero(offset):
    # was: _pe_members solved PE's closed form on the raw records, so the starts of the GA and the gradient
    # (starts="pe") carried y's zero: in the optimisers' coordinates z the starts of the ℓ = 2 structure's closure
    # moved by 5e-8 of their norm at y + 1e4 and 1.7e-7 at y + 1e6 (the closed form's round-off on a constant of
    # 1e4 against a spread of 5), and a GA's result with them by 2e-10
    from graybox.estimation._simulation_error import SEProblem, _pe_starts

    data = gb.load_pumping()
    st = closure(STRUCTURE_15)
    p0, p1 = (SEProblem(st, *_pumping_at(c, data)) for c in (0.0, offset))
    z0, z1 = (p.to_z(np.array(_pe_starts(p))) for p in (p0, p1))
    # the optimisers' coordinates z are those of the centred signals, the same at every offset: the starts agree
    # there to the round-off of centring and of the map back from θ, eps·offset relative to y's spread of ~5
    # (measured 1e-12 at 1e4, 1.5e-10 at 1e6); 1e-8 leaves that 60 times at 1e6 and fails the raw closed form
    assert z0.shape == z1.shape == (4, len(st))
    err = np.linalg.norm(z1 - z0, axis=1) / np.linalg.norm(z0, axis=1)
    assert np.all(err < 1e-8), err
