"""hunt48b: statics and free runs."""

import numpy as np
import pytest

import graybox as gb


@pytest.mark.parametrize("domain", [None, (0.0, 10.0)])
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_static_curve_refuses_non_finite_levels(domain, bad):
    # StaticCurve(NaN) returned NaN (a NaN lies outside no range, so the domain's check let it pass) where
    # StaticSurface refuses it: a bad level is said, not evaluated
    c = gb.StaticCurve.polynomial([1.0, 2.0, 3.0], domain=domain)
    for f in (c, c.gain):
        with pytest.raises(ValueError, match="non-finite"):
            f([1.0, bad])
        with pytest.raises(ValueError, match="non-finite"):
            f(bad)
    assert c([1.0, 2.0]).tolist() == [6.0, 17.0]
    assert c.gain(2.0) == 14.0
