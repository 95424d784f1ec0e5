"""review47i: the centred rank of the equality rows (b7c8aa3, d01a4e8, 006f6c6)."""

import numpy as np
import pytest

import graybox as gb
from graybox import Record, StaticPoints, Structure
from test_mend47f import cubic_case


def _case():
    return cubic_case()


def test_points_whose_last_condition_is_below_their_round_off_give_no_silent_wrong_model():
    # six points for six cluster coefficients at u + 3e3, y + 2e9: the points' ȳ are stored to 2.4e-7 (1e-7 of their
    # spread), and the centred rows' sixth singular value is 1.3e-8 of the first, so the sixth condition is round-off
    # of ȳ; the centred rank counted it, and cls returned θ with u(k-1)^3 = -4.6e-5 and y(k-1)u(k-1) = 2.3e-4 (the
    # plant's 0.0098 and -0.049, which do not move with the signals' zeros) and no stable equilibrium, without a word
    s, u, y, ub, yb = _case()
    ref = gb.cls(s, Record(u=u, y=y), StaticPoints(ub, yb), how="points").model.theta
    try:
        fit = gb.cls(s, Record(u=u + 3e3, y=y + 2e9), StaticPoints(ub + 3e3, yb + 2e9), how="points").model
    except ValueError:  # refused (not identifiable, or the points over-determine it): said, not silent
        return
    np.testing.assert_allclose(fit.theta[[3, 5]], ref[[3, 5]], rtol=0.1)


def test_a_long_dead_time_of_a_finely_sampled_plant_is_analysed():
    # u(k-15000) (15 s at 1 kHz): its lags take per-lag arrays only, and 8d0b03b analysed it in half a second; the
    # limit of 10 000 samples meant for the output's companion matrix refused it
    m = gb.Model(Structure(["y(k-1)", "u(k-15000)", "1"]), np.array([0.5, 0.3, 0.2]))
    np.testing.assert_allclose(m.static_curve([1.0, 2.0]), [1.0, 1.6])
    assert m.equilibria(1.0)[0].stable
    np.testing.assert_allclose(np.ravel(gb.local_model(m, 1.0, Ts=0.001).dc_gain), [0.6])
    for bad in (Structure(["y(k-1)", "u(k-99999999999)", "1"]), Structure(["y(k-20000)", "u(k-1)", "1"])):
        with pytest.raises(ValueError, match=r"has a lag of (99999999999|20000) samples"):
            gb.Model(bad, np.array([0.5, 0.3, 0.2])).static_curve([1.0])


def test_a_solve_stopped_by_its_time_limit_names_the_time_limit():
    # ec32ebd's message for a solve stopped at a limit named only max_iter: clarabel stopped by the caller's
    # time_limit said "max_iter = 400" (its default) and asked to raise max_iter
    from graybox.static._constraints import GainBounds

    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(0, 2, 20), 20)
    y = np.zeros(400)
    for k in range(1, 400):
        y[k] = 0.5 * y[k - 1] + 0.3 * u[k - 1] + 0.2
    rec, pts = Record(u=u, y=y + 0.01 * rng.standard_normal(400)), StaticPoints([0.5, 1.5], [0.7, 1.3])
    s = Structure(["y(k-1)", "u(k-1)", "1"])
    with pytest.raises(ValueError, match=r"time_limit = 1e-09.*a larger time_limit"):
        gb.cls(s, rec, pts, solver="clarabel", constraints=[GainBounds(upper=0.3)], solver_options={"time_limit": 1e-9})
    with pytest.raises(ValueError, match=r"max_iter = 3\) before it converged.*\{'max_iter': \.\.\.\}, or use solver"):
        gb.cls(s, rec, pts, solver="osqp", constraints=[GainBounds(upper=0.3)], solver_options={"max_iter": 3})


def test_a_none_among_lambdas_in_an_object_array_is_named():
    # c787960 named a None in a list or tuple of lambdas; np.array([0.5, None], dtype=object) still said "got [nan]"
    from graybox.core._validation import check_lambdas

    with pytest.raises(TypeError, match=r"got None \(at position 1\)"):
        check_lambdas(np.array([0.5, None], dtype=object))
    np.testing.assert_allclose(check_lambdas(np.array([0.5, 1.0], dtype=object)), [0.5, 1.0])
