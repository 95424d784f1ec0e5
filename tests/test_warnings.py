"""Every warning graybox gives goes through the one helper: attributed to the caller's line, said once per call.

Each test makes one call that warns and checks that exactly one warning of the category came out, and
that its filename is this file (the line that called graybox), not one of graybox's own modules.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import graybox as gb
from graybox.estimation._extended_least_squares import ELSConvergenceWarning

THIS = __file__


def caught(category, call):
    """The warnings of ``category`` that ``call()`` gives, with every filter set to always."""
    with warnings.catch_warnings(record=True) as ws:
        warnings.simplefilter("always")
        call()
    return [w for w in ws if issubclass(w.category, category)]


def said_once_here(ws, match: str):
    assert len(ws) == 1, [str(w.message) for w in ws]
    assert match in str(ws[0].message)
    assert ws[0].filename == THIS, ws[0].filename


def _record(seed=0, n=400, noise=0.01):
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + u[k - 1] + 0.2 * u[k - 1] ** 2
    return gb.Record(u, y + noise * rng.standard_normal(n))


def test_frols_skipped_and_dependent_candidates_are_one_warning():
    rng = np.random.default_rng(0)
    n = 300
    u = np.full(n, 1.0)  # a constant input: every input term copies the constant
    e = 0.05 * rng.standard_normal(n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + 2.0 + e[k]
    ws = caught(gb.CandidateWarning, lambda: gb.frols(gb.Candidates(2, 2, degree=2), gb.Record(u, y), n_terms=3))
    said_once_here(ws, "candidate(s) skipped")


def test_frols_tolerance_not_reached():
    ws = caught(RuntimeWarning, lambda: gb.frols(gb.Candidates(3, 3, degree=2), _record(1), tol=1e-12,
                                                 max_terms=2))
    said_once_here(ws, "not reached")


def test_frols_criterion_at_the_edge():
    ws = caught(RuntimeWarning, lambda: gb.frols(gb.Candidates(3, 3, degree=2), _record(1), criterion="aic",
                                                 max_terms=2))
    said_once_here(ws, "may still be falling")


def test_els_not_converged():
    st = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "e(k-1)", "e(k-2)"])
    ws = caught(ELSConvergenceWarning, lambda: gb.els(st, _record(2, noise=0.3), max_iter=2, tol=1e-14))
    said_once_here(ws, "did not converge")


def test_jsf_infinite():
    # y(k) = 1.5 y(k-1) + u: no stable equilibrium anywhere
    m = gb.Model(gb.Structure(["y(k-1)", "u(k-1)"]), [1.5, 1.0])
    ws = caught(RuntimeWarning, lambda: gb.jsf(m, gb.StaticPoints([0.5, 1.0], [1.0, 2.0])))
    said_once_here(ws, "is infinite")


def test_static_points_well_outside_the_records():
    rec = _record(3)
    far = gb.StaticPoints([0.0, 5.0], [0.0, 15.0])
    st = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"])
    ws = caught(gb.StaticRangeWarning, lambda: gb.pe_pareto(st, rec, far, lambdas=[1.0, 0.5], solver="closed"))
    said_once_here(ws, "lie outside the input range")
    # just past the records' extremes (within 5 % of their span) is ordinary: no warning
    near = gb.StaticPoints([-1.02, 0.0, 1.02], [-0.5, 0.0, 3.0])
    assert not caught(gb.StaticRangeWarning, lambda: gb.pe_pareto(st, rec, near, lambdas=[1.0], solver="closed"))


def test_se_dsf_band_out_of_reach():
    st = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"])
    rec = _record(4)
    sp = gb.StaticPoints(np.linspace(-0.8, 0.8, 5), np.linspace(-0.8, 0.8, 5) + 3.0)  # far from the dynamics
    ws = caught(RuntimeWarning, lambda: gb.se_dsf(st, rec, sp, band=1e-12, theta0=[0.5, 1.0, 0.2, 0.0],
                                                  max_iter=5))
    said_once_here(ws, "infeasible")


def test_the_helper_skips_every_graybox_frame():
    # a warning raised two graybox frames deep is still attributed here
    from graybox.core._validation import warn

    def inner():
        warn("x", UserWarning)

    with warnings.catch_warnings(record=True) as ws:
        warnings.simplefilter("always")
        inner()
    assert ws[0].filename == THIS
    with pytest.warns(UserWarning) as rec:
        gb.core._validation.warn("y", UserWarning)
    assert rec[0].filename == THIS


def test_pe_inaccurate_optimum_is_one_warning_for_the_sweep(monkeypatch):
    # make every solve report "optimal_inaccurate" (the solver's status is the only input of this warning)
    import cvxpy as cp


    monkeypatch.setattr(cp, "OPTIMAL_INACCURATE", cp.OPTIMAL)  # the module pe imports when it solves
    st = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"])
    rec = _record(5)
    sp = gb.StaticPoints(np.linspace(-0.8, 0.8, 4), 2 * np.linspace(-0.8, 0.8, 4) + 0.4 * np.linspace(-0.8, 0.8, 4) ** 2)
    ws = caught(RuntimeWarning, lambda: gb.pe_thetas(st, rec, sp, lambdas=[1.0, 0.5, 0.1], solver="clarabel",
                                                     constraints=gb.GainBounds(lower=0.0)))
    said_once_here(ws, "inaccurate optimum at 3 weight(s)")
