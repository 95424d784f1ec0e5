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


@pytest.mark.parametrize("field,value", [
    ("ubar", ["1"]),        # numpy's "ufunc 'isfinite' not supported for the input types", naming nothing
    ("a", ["0.5"]),         # parsed as 0.5, silently
    ("a", [0.5 + 0j]),      # "float() argument must be a string or a real number, not 'complex'"
    ("a", [True]),          # read as 1.0: a pole at z = 1 said of a coefficient nobody gave
    ("b", [["1.0"]]),       # parsed, silently
    ("b", [[None]]),        # read as NaN: "b has non-finite values"
])
def test_local_model_fields_refuse_what_is_not_numbers(field, value):
    from graybox import LocalModel

    kw = dict(ubar=[1.0], ybar=2.0, status="diverged", reason="diverged from y0", a=[0.5], b=[[1.0]], Ts=1.0,
              input_names=("u",))
    kw[field] = value
    with pytest.raises(TypeError, match=rf"\b{field} must"):
        LocalModel(**kw)


@pytest.mark.parametrize("field", ["ubar", "ybar", "gain", "time_constant", "damping", "spectral_radius",
                                   "settling_time"])
@pytest.mark.parametrize("bad", ["text", "none"])
def test_operating_curve_fields_refuse_what_is_not_numbers(field, bad):
    # text was parsed (ubar=['1.0', '2.0'] made a curve), and None in settling_time read as NaN, a curve whose
    # settling times were "not computed" where its local models settle
    import dataclasses

    import graybox as gb

    curve = gb.operating_curve(gb.Model(["1", "y(k-1)", "u(k-1)"], [1.0, 0.8, 0.5], Ts=0.1), [1.0, 2.0])
    v = getattr(curve, field)
    with pytest.raises(TypeError, match=rf"\b{field} must"):
        dataclasses.replace(curve, **{field: [str(x) for x in v] if bad == "text" else [None] * len(v)})


@pytest.mark.parametrize("ybar", [2, np.int64(2), np.float32(2.0), 10**20])
def test_local_model_keeps_its_equilibrium_as_a_float(ybar):
    # an int or a numpy scalar was kept as given (LocalModel.ybar typed float), and an integer beyond int64 (10**20,
    # a finite float) failed with numpy's "ufunc 'isfinite' not supported for the input types"
    from graybox import LocalModel

    lm = LocalModel([1.0], ybar, "reached", "", [0.5], [[1.0]], 1.0, ("u",))
    assert type(lm.ybar) is float and lm.ybar == float(ybar)


def test_local_model_refuses_an_equilibrium_beyond_the_float_range():
    from graybox import LocalModel

    with pytest.raises(ValueError, match="ybar must be finite"):
        LocalModel([1.0], 10**400, "reached", "", [0.5], [[1.0]], 1.0, ("u",))
