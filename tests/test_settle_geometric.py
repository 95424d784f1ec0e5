"""The geometric test of a settling run: a run heading for a slow candidate ends once its distance to
it shrinks at the candidate's own rate, not only once it has decayed to the tolerance; and it ends
that way only where the long run reaches the same equilibrium."""

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st

import graybox as gb
from graybox.static import _analysis
from graybox.static._analysis import POLY, SETTLE_RTOL, STALL_RTOL, _fold_map, reached_equilibria, settle_budget
from graybox.static._equilibrium_kernels import (GEOM_TAUS, GEOM_WINDOWS, NOT_SETTLED, REACHED, settle_candidates,
                                                 settle_runs)
from graybox.core._simulation_kernels import encode

#: y = a y1 + c y1² + u1: one output lag, a y² term that keeps the settling run in play.
QUAD = gb.Structure(["y(k-1)", "y(k-1)^2", "u(k-1)"])


def _pole_at_one(rho: float) -> tuple[np.ndarray, float]:
    """θ of QUAD whose equilibrium ȳ = 1 has the pole ``rho`` (|rho| < 1, either sign), and its ū.

    c = (1 − |rho|)/10, a = rho − 2c (f'(1) = a + 2c = rho); the other equilibrium lies far off.
    """
    c = (1.0 - abs(rho)) / 10.0
    a = rho - 2.0 * c
    return np.array([a, c, 1.0]), 1.0 - a - c


def _pair(theta: np.ndarray, u: float, y0: float):
    """settle_runs' arguments for one (θ, ū, y0) pair of QUAD: ip, fp, the candidates and their tolerances."""
    ip, onehot, L = _fold_map(QUAD)
    fp = (theta * u ** encode(QUAD).mu)[None, :] @ onehot
    roots = np.sort(np.roots([theta[1], theta[0] - 1.0, u]).real)[None, :]
    stable = np.abs(theta[0] + 2.0 * theta[1] * roots) < 1.0
    y0a = np.array([y0])
    cand, ncand, tol, ntol = settle_candidates(roots, stable, y0a, 0.0, SETTLE_RTOL)
    return ip, fp, y0a, cand, ncand, tol, ntol, L


def _run(args, steps: int, lograte: np.ndarray):
    ip, fp, y0, cand, ncand, tol, ntol, L = args
    yb, status, _, _ = settle_runs(POLY, ip, fp, y0, cand, ncand, tol, ntol, L, 0.0, steps,
                                   np.zeros(0, dtype=np.int64), np.zeros((0, L)), STALL_RTOL, lograte)
    return float(yb[0]), int(status[0])


def test_a_slow_approach_ends_at_the_candidates_rate_not_at_the_tolerance():
    # a pole near −1 with τ = 10⁵ samples, started 10⁻⁴ off: the run alternates about ȳ, so its
    # increments never vanish and the stall test cannot end it; the decay to the tolerance (10⁻⁶) takes
    # ln(100) τ ≈ 4.6 τ; the geometric test ends it within GEOM_WINDOWS + 1 windows of GEOM_TAUS τ each
    # (the plant's slow trial models are of this kind: BENCHMARKS.md, the session of 2026-11-26 08:48)
    rho = -np.exp(-1e-5)
    theta, u = _pole_at_one(rho)
    args = _pair(theta, u, 1.0 + 1e-4)
    tau = -1.0 / np.log(abs(rho))
    _, lograte = settle_budget(POLY, args[0], args[1], args[3], args[4], args[7])
    budget = int((GEOM_WINDOWS + 2) * GEOM_TAUS * tau)
    assert _run(args, budget, lograte) == (pytest.approx(1.0, rel=1e-12), REACHED)
    assert _run(args, budget, np.zeros((0, 1)))[1] == NOT_SETTLED  # without it: not within that budget
    assert _run(args, int(6 * tau), np.zeros((0, 1))) == (pytest.approx(1.0, rel=1e-12), REACHED)


def test_a_run_slower_than_its_candidates_rate_is_not_taken_for_one_that_arrives():
    # the rate handed in is 10× the true one: the run, shrinking at its own (slower) rate, fails the test
    theta, u = _pole_at_one(-np.exp(-1e-5))
    args = _pair(theta, u, 1.0 + 1e-4)
    _, lograte = settle_budget(POLY, args[0], args[1], args[3], args[4], args[7])
    assert _run(args, 200_000, 10.0 * lograte)[1] == NOT_SETTLED


def test_a_run_that_does_not_shrink_is_not_taken_for_one_that_arrives():
    # y = −y1 + 2 (ρ = −1 exactly: a 2-cycle about ȳ = 1 that never dies), handed ȳ = 1 as a candidate
    # with a stable candidate's rate
    ip, onehot, L = _fold_map(QUAD)
    fp = (np.array([-1.0, 0.0, 1.0]) * 2.0 ** encode(QUAD).mu)[None, :] @ onehot
    y0 = np.array([1.0 + 1e-4])
    cand, ncand, tol, ntol = settle_candidates(np.array([[1.0]]), np.array([[True]]), y0, 0.0, SETTLE_RTOL)
    lograte = np.full(cand.shape, np.log(1.0 - 1e-5))
    assert _run((ip, fp, y0, cand, ncand, tol, ntol, L), 200_000, lograte)[1] == NOT_SETTLED


@settings(max_examples=30, deadline=None)
@given(lt=st.floats(3.0, 5.3), sign=st.sampled_from([-1.0, 1.0]), off=st.floats(-0.3, 0.3), du=st.floats(-0.2, 0.2))
def test_the_geometric_test_changes_no_outcome_of_the_long_run(lt, sign, off, du):
    # τ from 10³ to 2·10⁵ samples, a pole of either sign, the run started up to 30 % off and ū moved off the
    # constructed point: with the test or run to the end of the budget without it, the same status and ȳ
    theta, u = _pole_at_one(sign * np.exp(-(10.0 ** -lt)))
    ub, y0 = u * (1.0 + du), 1.0 + off
    assume(abs(y0) > 1e-3)
    fast = reached_equilibria(QUAD, theta[None], [ub], [y0])
    with pytest.MonkeyPatch.context() as mp:
        plain = _analysis.settle_runs

        def without(*a):
            return plain(*a[:-1], np.zeros((0, 1)))  # the same runs, no geometric test

        mp.setattr(_analysis, "settle_runs", without)
        slow = reached_equilibria(QUAD, theta[None], [ub], [y0])
    assert fast.status.tolist() == slow.status.tolist()
    np.testing.assert_array_equal(fast.ybar, slow.ybar)
