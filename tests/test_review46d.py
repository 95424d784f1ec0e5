"""Review of session 46 (d): the SE problem's free runs on the centred signals (b0deb6a) and what came with it."""

from __future__ import annotations

import itertools
import tracemalloc

import numpy as np

import graybox as gb
from graybox.estimation._simulation_error import SEProblem


def _closed_problem_data(N: int = 60000):
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(-1.0, 1.0, N // 50), 50) + 5.0
    e = 0.01 * rng.standard_normal(N)
    y = np.zeros(N)
    for k in range(2, N):
        y[k] = 0.5 * y[k - 1] + 0.2 * y[k - 2] + 0.3 * u[k - 1] + 0.05 * (u[k - 2] - 5.0) ** 2 + e[k]
    lin = ["y(k-1)", "y(k-2)", "y(k-3)", "u(k-1)", "u(k-2)"]
    quad = [f"{a}{b}" if a != b else f"{a}^2" for a, b in itertools.combinations_with_replacement(lin, 2)]
    return gb.parse_structure(["1"] + lin + quad[:14]), gb.Record(u, y + 100.0, Ts=1.0)


def test_a_centred_se_problem_holds_the_raw_input_products_only_when_asked():
    # the centred free runs (b0deb6a) made their own input products beside the raw ones, which only residuals()
    # (se_dsf, se_uncertainty) reads: a second N × n array held through every sweep (+31 MB at N = 200000, n = 20)
    st, rec = _closed_problem_data()
    P = SEProblem(st, [rec], gb.StaticPoints([4.5, 5.0, 5.5], [101.0, 102.0, 103.0]))
    assert P.run_scale is not None  # the centred case
    one = P.run_U[0].nbytes
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        raw = P.U
        grown = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    assert grown >= 0.9 * one  # made now, not held since the problem was built
    assert raw[0].shape == P.run_U[0].shape
    # and the raw residuals read them as before: the same errors as the centred runs
    th = P.ls_theta()
    e = P.residuals(th, jacobian=False)[0]
    np.testing.assert_allclose(np.mean(e ** 2), P.js(th[None])[0], rtol=1e-9)
