"""Bug hunt 51a: plots and reports (figures, leaderboards, the texts results print)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import graybox as gb


def _first_order_record(n: int = 400, seed: int = 0) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = rng.uniform(1.0, 3.0, n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + 0.1 * u[k - 1] + 0.05 * rng.standard_normal()
    return gb.Record(u, y, Ts=0.1)


def test_residual_tests_of_one_test_are_drawn():
    # a ResidualTests holding one test (it takes any non-empty set: a file, dataclasses.replace) failed to draw with
    # "'Axes' object is not iterable": fig.subplots(1, 1) gives one Axes, not an array of them
    from graybox.plots import plot_residual_tests

    m = gb.Model(gb.parse_structure(["y(k-1)", "u(k-1)"]), np.array([0.5, 0.1]), Ts=0.1)
    tests = gb.residual_tests(m, _first_order_record())
    one = dataclasses.replace(tests, tests={"xi_xi": tests.tests["xi_xi"]})
    fig = plot_residual_tests(one)
    (ax,) = fig.axes
    assert ax.get_title(loc="left").startswith(tests.tests["xi_xi"].label)
