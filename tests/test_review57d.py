"""review57d: regressions found reviewing the stability judgements of the static analysis and graybox.control."""

import pytest

import graybox as gb


def test_a_local_model_s_reason_names_its_equilibrium_as_it_is_at_an_offset():
    # 'linearised at the unstable ȳ = 10000' of the equilibrium 10000.01 (%g), as 00e9f2d's ū were
    m = gb.Model(["y(k-1)", "u(k-1)"], [1.5, 1.0], Ts=1.0)  # ȳ = −2ū, pole 1.5
    lm = gb.local_model(m, -5000.005)
    assert lm.ybar == pytest.approx(10000.01, rel=1e-15)
    assert "unstable ȳ = 10000.01 " in lm.reason
    # every ȳ an equilibrium (y(k) = y(k-1) + u(k-1) at ū = 0): linearised at y0, named as given
    lm = gb.local_model(gb.Model(["y(k-1)", "u(k-1)"], [1.0, 1.0], Ts=1.0), 0.0, y0=10000.01)
    assert lm.reason.endswith("ȳ = y0 = 10000.01")
