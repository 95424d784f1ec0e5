"""mend49h: the GA's fronts of a structure closed under shifts, wherever the output's zero is (hunt49's find)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import graybox as gb
import graybox.estimation._simulation_error as se
from graybox.estimation._simulation_error import CheckpointError, GAOptions, SEProblem, ga_front, se_pareto

OE_STRUCT = gb.Structure(["y(k-1)", "u(k-1)", "u(k-2)^2", "u(k-1)y(k-1)"])
OE_THETA = np.array([0.7, 0.25, 0.1, -0.05])
# closed under shifts: every divisor of every term is present, so the problem is fitted in centred coordinates
CLOSED = ["1", "y(k-1)", "u(k-1)", "u(k-2)", "u(k-2)^2", "u(k-1)y(k-1)", "y(k-1)^2"]
UBAR = np.array([-0.8, -0.3, 0.2, 0.7])
YBAR = np.array([-0.52307692, -0.23157895, 0.17419355, 0.66865672]) + 0.02
LAMBDAS = [1.0, 0.5, 0.2, 0.1, 0.05]


def oe_record(offset: float = 0.0, seed: int = 1, N: int = 600, noise: float = 0.15) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1.0, 1.0, N // 8 + 1), 8)[:N]
    x = gb.Model(OE_STRUCT, OE_THETA).simulate(u, np.zeros(2))
    return gb.Record(u, x + noise * rng.standard_normal(N) + offset, name="oe")


def front(offset: float, **kw) -> gb.ParetoSet:
    return se_pareto(CLOSED, oe_record(offset), gb.StaticPoints(UBAR, YBAR + offset), lambdas=LAMBDAS,
                     options=GAOptions(population=50, generations=40), seed=3, margin=None, progress=False, **kw)


@pytest.fixture(scope="module")
def at_zero() -> gb.ParetoSet:
    return front(0.0)


@pytest.mark.parametrize("offset", [1e4, -3e3])
def test_the_ga_front_of_a_closed_structure_does_not_depend_on_the_outputs_zero(at_zero, offset):
    # the carried member, the least-squares individual and the random individuals went through raw θ, whose
    # constant carries the offset's powers: ~1e-8 lost at y + 1e4, which the GA amplified (cost 0.5 % apart,
    # J_SF 72 %); in the optimiser's coordinates throughout, the fronts agree to round-off of the centring
    there = front(offset)
    np.testing.assert_allclose(there.extra["cost"], at_zero.extra["cost"], rtol=1e-6)
    np.testing.assert_allclose(there.JSF, at_zero.JSF, rtol=1e-5)
    np.testing.assert_allclose(there.JS, at_zero.JS, rtol=1e-6)


@settings(max_examples=6, deadline=None)
@given(offset=st.floats(-2e4, 2e4, allow_nan=False))
def test_a_small_ga_front_is_the_same_at_any_offset_of_y(offset):
    # the law: y and ȳ moved together by any offset leave the centred problem, hence its GA's draws and choices,
    # as they were (to the round-off of the centring, far below the fronts' differences when it was raw θ)
    fronts = [ga_front(problem(off), [1.0, 0.3, 0.05], options=SMALL, seed=7, progress=False) for off in (0.0, offset)]
    np.testing.assert_allclose(fronts[1].costs, fronts[0].costs, rtol=1e-7)


SMALL = GAOptions(population=20, generations=12)


def problem(offset: float) -> SEProblem:
    return SEProblem(gb.Structure(CLOSED), oe_record(offset, N=300), gb.StaticPoints(UBAR, YBAR + offset))


def _interrupted(prob, lam, ck, monkeypatch, at=3):
    real = se._ga_run
    calls = {"n": 0}

    def dying(*args, **kw):
        calls["n"] += 1
        if calls["n"] == at:
            raise KeyboardInterrupt  # killed during this λ
        return real(*args, **kw)

    monkeypatch.setattr(se, "_ga_run", dying)
    with pytest.raises(KeyboardInterrupt):
        ga_front(prob, lam, options=SMALL, seed=5, checkpoint=ck, progress=False)
    monkeypatch.setattr(se, "_ga_run", real)


def test_a_resumed_ga_sweep_of_a_centred_problem_at_an_offset_is_the_uninterrupted_one(tmp_path, monkeypatch):
    # the carried member is kept in z, which its θ does not give back at y + 1e4: the checkpoint stores it
    prob, lam = problem(1e4), [1.0, 0.6, 0.3, 0.1]
    full = ga_front(prob, lam, options=SMALL, seed=5, progress=False)
    ck = tmp_path / "front.npz"
    _interrupted(prob, lam, ck, monkeypatch)
    with np.load(ck) as z:
        assert int(z["done"]) == 2 and z["coords"].shape == (4, len(CLOSED))
    resumed = ga_front(prob, lam, options=SMALL, seed=5, checkpoint=ck, progress=False)
    np.testing.assert_array_equal(resumed.thetas, full.thetas)
    np.testing.assert_array_equal(resumed.costs, full.costs)


def test_a_centred_ga_checkpoint_without_the_members_coordinates_is_refused_by_name(tmp_path, monkeypatch):
    prob, lam = problem(1e4), [1.0, 0.6, 0.3]
    ck = tmp_path / "front.npz"
    _interrupted(prob, lam, ck, monkeypatch)
    arrays = dict(np.load(ck))
    del arrays["coords"]
    np.savez(ck, **arrays)
    with pytest.raises(CheckpointError, match="older graybox.*centred coordinates"):
        ga_front(prob, lam, options=SMALL, seed=5, checkpoint=ck, progress=False)
    arrays["coords"] = np.zeros((2, len(CLOSED)))  # not one row per member
    np.savez(ck, **arrays)
    with pytest.raises(CheckpointError, match="corrupt.*coordinates"):
        ga_front(prob, lam, options=SMALL, seed=5, checkpoint=ck, progress=False)


def test_a_raw_problems_ga_checkpoint_keeps_its_format(tmp_path):
    # not closed under shifts: the genes are θ itself, nothing more to store (the plant's checkpoints stay valid)
    prob = SEProblem(OE_STRUCT, oe_record(N=300), gb.StaticPoints(UBAR, YBAR))
    assert prob.z_map is None
    ck = tmp_path / "front.npz"
    ga_front(prob, [1.0, 0.5], options=SMALL, seed=5, checkpoint=ck, progress=False)
    with np.load(ck) as z:
        assert "coords" not in z.files


def test_a_centred_problems_ga_front_is_reproduced_by_its_seed():
    prob = problem(1e4)
    a, b, c = (ga_front(prob, [1.0, 0.3], options=SMALL, seed=s, progress=False) for s in (11, 11, 12))
    np.testing.assert_array_equal(a.thetas, b.thetas)
    np.testing.assert_array_equal(a.costs, b.costs)
    assert not np.array_equal(a.thetas, c.thetas)
    # the members returned are θ of the genes kept: their cost is the optimised one
    np.testing.assert_allclose([prob.cost(t[None], lam)[0] for t, lam in zip(a.thetas, a.lambdas)], a.costs,
                               rtol=1e-6)
