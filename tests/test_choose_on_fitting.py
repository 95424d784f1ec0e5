"""decide_dsf(choose_on=) refuses the records the front was fitted on (its own J_S, chosen on again)."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb
from conftest import quadratic_first_order_data

ST = gb.Structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"])


def _data(seed: int) -> gb.Dataset:
    return quadratic_first_order_data(seed)


def test_choosing_on_the_fitting_record_is_refused():
    # was taken: every member scored on the identification record again, the choice the plain D_SF makes, said to
    # be chosen on data the fit did not see (output_error(choose_on=) refuses the same)
    data = _data(0)
    front = gb.pe_pareto(ST, data, lambdas=np.logspace(-3, 0, 6))
    with pytest.raises(ValueError, match="choose_on.*fitt"):
        gb.decide_dsf(front, band=1.0, choose_on=data.ident)
    copy = gb.Record(data.ident.u.copy(), data.ident.y.copy(), name="the same samples")
    with pytest.raises(ValueError, match="choose_on.*fitt"):
        gb.decide_dsf(front, band=1.0, choose_on=copy)
    d = gb.decide_dsf(front, band=1.0, choose_on=data.valid)  # data the fit did not see: chosen on
    assert d.chosen_on == "valid"
    assert np.isfinite(d.score) and d.score != front.JS[d.index]  # its J_S on the choosing record
