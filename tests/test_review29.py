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
