"""hunt47d: structure search and least squares (frols, semp, subset search, stopping rules, ELS)."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb


def _plant(n: int = 200, seed: int = 0) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.0, 1.0, n)
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = 0.5 * y[k - 1] + u[k - 1] - 0.2 * u[k - 2] * y[k - 1] + 0.05 * rng.standard_normal()
    return gb.Record(u=u, y=y)


SPACE = gb.Candidates(ny=2, nu=2, degree=2)


def test_a_semp_result_made_from_an_array_keeps_its_own_read_only_copy():
    res = gb.semp(SPACE, _plant(), n_terms=3)
    theta = np.array(res.theta)
    made = gb.SEMPResult(res.structure, theta, res.score, res.path, res.forward_scores, res.criterion, res.stop,
                         res.n_rows)
    theta[0] = 99.0  # the caller's array changes; the result does not
    assert made.theta[0] == res.theta[0]
    with pytest.raises(ValueError):
        made.theta[0] = 99.0
    assert isinstance(gb.SEMPResult(res.structure, list(res.theta), res.score, res.path, res.forward_scores,
                                    res.criterion, res.stop, res.n_rows).theta, np.ndarray)


def test_an_els_result_made_from_arrays_keeps_its_own_read_only_copies():
    res = gb.els(["y(k-1)", "u(k-1)"], _plant())
    theta_ls, residuals = np.array(res.theta_ls), tuple(np.array(r) for r in res.residuals)
    made = gb.ELSResult(res.model, res.n_iter, res.converged, res.history, residuals, theta_ls)
    theta_ls[0] = 99.0
    residuals[0][5] = 99.0
    assert made.theta_ls[0] == res.theta_ls[0]
    assert made.residuals[0][5] == res.residuals[0][5]
    for a in (made.theta_ls, made.residuals[0]):
        with pytest.raises(ValueError):
            a[0] = 1.0
