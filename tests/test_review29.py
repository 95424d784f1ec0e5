"""Bugs found by a review of the day's speed and divergence-bound work: each test fails without its fix."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb


@pytest.mark.parametrize("threads", [1, 2])
def test_a_population_member_stays_stopped_after_its_run_leaves_the_bound(threads):
    # y(k) = 1.5 y(k-2): the odd samples grow from y(1) = 1 until the bound stops the run, while the
    # even ones stay at 0. simulate stops the run there (NaN from that sample on); the batch kernel
    # made only that sample NaN and went on with the samples that do not read it (0, NaN, 0, ...)
    st_ = gb.Structure(["y(k-2)", "u(k-1)"])
    u = np.zeros(200)
    y = np.zeros(200)
    y[1] = 1.0
    rec = gb.Record(u, y)
    thetas = np.array([[1.5, 1.0], [0.5, 1.0], [1.5, 1.0], [0.5, 1.0], [1.5, 1.0]])
    runs = gb.simulate_many(st_, thetas, rec, threads=threads)
    for th, run in zip(thetas, runs):
        alone = gb.simulate(st_, th, rec, on_diverge="nan")
        np.testing.assert_array_equal(np.isnan(run), np.isnan(alone))
    assert np.isnan(runs[0, -1])


def test_a_static_curve_at_many_levels_leaves_no_copy_of_its_points_behind():
    # the linearisation remembers each point set's input parts for the fits (the same static points at
    # every trial θ), on a structure's map, which lives as long as the process: a static curve at
    # 2·10⁵ levels left 24 MB there (and up to 16 such sets per structure)
    from graybox.static._linearisation import derivative_map

    st_ = gb.Structure(["1", "u(k-1)", "y(k-1)", "u(k-1)y(k-1)", "y(k-2)^2", "y(k-1)^3", "u(k-2)y(k-2)"])
    th = np.array([0.1, 0.5, 0.5, 0.01, -0.01, 0.001, 0.02])
    levels = np.linspace(0.1, 1.0, 200_000)
    gb.static_curve(st_, th, levels, strict=False)
    cache = derivative_map(st_)._point_cache
    kept = sum(U.nbytes + len(key[1]) for key, U in cache.items())
    assert kept < levels.nbytes
    # a fit's few static points are still remembered: the same array for the same points
    dm = derivative_map(st_)
    pts = np.array([0.2, 0.5, 0.9])
    assert dm.entry_inputs(pts) is dm.entry_inputs(pts.copy())


ST_POLE = gb.Structure(["y(k-1)", "u(k-1)y(k-1)", "u(k-1)"])


def _pole_moving_record(seed: int, name: str) -> gb.Record:
    # y(k) = 0.6 y(k-1) + 0.2 u(k-1) y(k-1) + u(k-1): pole 0.6 + 0.2 u, stable for u in [0, 1]
    rng = np.random.default_rng(seed)
    u = rng.uniform(0.0, 1.0, 600)
    y = np.zeros(600)
    y[0] = 1.0
    for k in range(1, 600):
        y[k] = 0.6 * y[k - 1] + 0.2 * u[k - 1] * y[k - 1] + u[k - 1]
    return gb.Record(u, y, name=name)


def test_output_error_does_not_choose_a_model_whose_free_run_diverges_on_the_choosing_record():
    # the choice scored each candidate by an unbounded J_S on the choosing records: at u = 2.05 the pole
    # is 1.01, a slow divergence (1.01^3000 ≈ 1e13: beyond simulate's bound, far from an overflow), and
    # the model was chosen there with JS_choose 6e28 where gb.js says inf
    fit = _pole_moving_record(0, "fit")
    diverging = gb.Record(np.full(3000, 2.05), np.ones(3000), name="choose")
    with pytest.raises(ValueError, match="diverges on the choosing record"):
        gb.output_error(ST_POLE, fit, choose_on=diverging, n_starts=2, progress=False)
    choose = _pole_moving_record(1, "choose")
    result = gb.output_error(ST_POLE, fit, choose_on=choose, n_starts=2, progress=False)
    assert result.JS_choose == pytest.approx(gb.js(result.model, choose), rel=1e-9)
