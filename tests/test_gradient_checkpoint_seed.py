"""The gradient SE sweep draws no random numbers: its checkpoint resumes whatever seed the call gives."""

from __future__ import annotations

import numpy as np

import graybox as gb
from graybox.estimation._simulation_error import CheckpointError
from conftest import QUADRATIC_FIRST_ORDER, quadratic_first_order_data


def _problem():
    rng = np.random.default_rng(3)
    u = rng.uniform(1.0, 3.0, 200)
    y = np.zeros(200)
    for k in range(1, 200):
        y[k] = 0.6 * y[k - 1] + 0.3 * u[k - 1] - 0.05 * u[k - 1] ** 2 + 0.01 * rng.standard_normal()
    static = gb.StaticPoints([1.0, 2.0, 3.0], [0.625, 1.0, 1.125])
    return ["y(k-1)", "u(k-1)", "u(k-1)^2"], gb.Record(u, y), static


def test_a_gradient_checkpoint_resumes_under_another_seed_and_a_ga_one_does_not(tmp_path):
    terms, rec, static = _problem()
    ck = tmp_path / "front.npz"
    first = gb.se_pareto(terms, rec, static, lambdas=[0.1, 1.0], method="gradient", seed=0, checkpoint=ck)
    again = gb.se_pareto(terms, rec, static, lambdas=[0.1, 1.0], method="gradient", seed=7, checkpoint=ck)
    assert np.array_equal(first.thetas, again.thetas)  # (before: "written for another problem (differs in: seed)")
    ga = tmp_path / "ga.npz"
    opts = gb.GAOptions(population=20, generations=2)
    gb.se_pareto(terms, rec, static, lambdas=[1.0], method="ga", options=opts, seed=0, checkpoint=ga)
    try:
        gb.se_pareto(terms, rec, static, lambdas=[1.0], method="ga", options=opts, seed=1, checkpoint=ga)
    except CheckpointError as exc:
        assert "seed" in str(exc)
    else:
        raise AssertionError("a GA checkpoint of seed 0 was resumed by seed 1")


def test_an_archive_of_another_tool_is_refused_naming_what_it_lacks(tmp_path):
    # an .npz that numpy (or another tool) wrote under the name: refused with the reason in words, not a KeyError's
    # bare repr "('meta')"
    terms, rec, static = _problem()
    ck = tmp_path / "front.npz"
    np.savez(ck, a=np.arange(3))
    try:
        gb.se_pareto(terms, rec, static, lambdas=[1.0], method="gradient", checkpoint=ck)
    except CheckpointError as exc:
        assert "holds no SE sweep's metadata" in str(exc) and "'a'" in str(exc)
        assert "('meta')" not in str(exc)
    else:
        raise AssertionError("an archive without an SE sweep's metadata was taken for a checkpoint")
    assert np.array_equal(np.load(ck)["a"], np.arange(3))  # the user's file is left as it was


def test_a_gradient_sweep_resumed_from_its_checkpoint_is_the_uninterrupted_one_to_the_last_bit(tmp_path):
    # the static points' equilibria were remembered by θ alone, while a centred problem solves them from the
    # optimiser's z (of which two can give one θ): the member a fit ended on was then read back as the next λ's start
    # from the other z, and a sweep resumed from a checkpoint (a fresh problem, nothing remembered) fitted its later
    # members 4e-16 apart from the uninterrupted sweep's
    data = quadratic_first_order_data(0)
    lam = np.logspace(-2, 0, 12)
    ck = tmp_path / "front.npz"
    whole = gb.se_pareto(QUADRATIC_FIRST_ORDER, data, lambdas=lam, method="gradient", checkpoint=ck)
    cut = dict(np.load(ck))  # as a sweep killed after its fourth λ leaves it
    cut["done"] = np.array(4)
    cut["thetas"][4:], cut["costs"][4:], cut["nfev"][4:] = np.nan, np.inf, 0
    np.savez(ck, **cut)
    resumed = gb.se_pareto(QUADRATIC_FIRST_ORDER, data, lambdas=lam, method="gradient", checkpoint=ck)
    assert np.array_equal(resumed.thetas, whole.thetas)
    assert np.array_equal(resumed.JS, whole.JS) and np.array_equal(resumed.JSF, whole.JSF)
