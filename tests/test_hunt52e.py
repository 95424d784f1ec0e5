"""Constrained estimation (CLS, PE) against the zero and the units of the signals, and its edge cases (hunt52e)."""

import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as hst

import graybox as gb
from graybox.selection._centring import shift_map

# a structure closed under shifts, quadratic in y, with a constant
_QUADRATIC = ["1", "y(k-1)", "y(k-1)^2", "y(k-1)u(k-1)", "u(k-1)"]


def _pumping_at(c: float):
    data = gb.load_pumping()
    r = data.ident
    pts = gb.StaticPoints(data.static.ubar, data.static.ybar + c)
    return gb.Record(r.u, r.y + c, name=r.name), pts


def _fits(c: float, solver: str):
    rec, pts = _pumping_at(c)
    three = gb.StaticPoints(pts.ubar[[0, 5, 9]], pts.ybar[[0, 5, 9]])
    st = gb.parse_structure(_QUADRATIC)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        th_cls = gb.cls(st, rec, three, how="points", solver=solver).model.theta
        th_pe = gb.pe_thetas(st, rec, pts, lambdas=[1e-6, 1e-3, 0.5, 1.0], solver=solver)
        bands = [] if solver == "closed" else [
            gb.cls(st, rec, pts, how="context", constraints=gb.StaticBand(b=0.05), solver=solver).model.theta]
    return rec, np.vstack([th_cls, th_pe, *bands])


@pytest.mark.parametrize("solver", ["clarabel", "osqp", "closed"])
def test_cls_and_pe_of_a_closed_quadratic_in_y_do_not_depend_on_the_output_zero(solver):
    # was: CLS and PE built their QP on the raw signals: at y + 1e6 the regressor y(k-1)² ≈ 1e12 carries a round-off
    # of 1e-4 against a centred size of ~25, so the fits moved with the output's zero by 29 (CLS) to 220 (PE) times
    # the round-off of the models themselves, and PE's closed form called every λ1 < 1 singular ("θ is not
    # identifiable"); LS, ELS and SE centre such a structure. Now CLS and PE are fitted on the centred signals too
    # (with points to pass through or a band, made on the centred signals)
    st = gb.parse_structure(_QUADRATIC)
    _, base = _fits(0.0, solver)
    rec, got = _fits(1e6, solver)
    A, t = shift_map(st, {"y": 1e6, "u": 0.0})
    X = gb.regressor_matrix(st, rec.u, rec.y)
    mapped = base @ A.T + t
    diff = np.abs(got @ X.T - mapped @ X.T)
    # the one-step predictions of the raw models at y + 1e6 are good to their own evaluation's round-off,
    # eps · Σ_j |θ_j x_j| (terms ~1e8 that cancel to ~1e6): measured 0.2 to 1.2 of it; 5 leaves room and fails the raw
    # fits (29 to 220 times; a StaticBand fit 1.3e5 times, 1e-3 of y in output units)
    bound = np.finfo(float).eps * (np.abs(got) @ np.abs(X).T)
    assert np.all(diff <= 5 * bound), np.max(diff / bound, axis=1)


@pytest.mark.parametrize("solver", ["clarabel", "osqp"])
def test_gain_bounds_on_a_closed_quadratic_in_y_do_not_depend_on_the_output_zero(solver):
    # was: a GainBounds constraint kept CLS on the raw signals (its rows on θ, mapped to the centred parameters, would
    # carry the offsets' powers), so at y + 1e6 the fit moved with the output's zero by 3.4e4 times its own round-off
    # (1e-2 output units). Its rows are now made on the centred signals, on its grid shifted (the gains and the
    # denominator D are derivatives of the static equation, the same there)
    st = gb.parse_structure(_QUADRATIC)
    fits = []
    for c in (0.0, 1e6):
        rec, pts = _pumping_at(c)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", gb.StaticRangeWarning)
            fits.append(gb.cls(st, rec, pts, how="context", constraints=gb.GainBounds(lower=0.0, upper=0.005),
                               solver=solver).model.theta)
    A, t = shift_map(st, {"y": 1e6, "u": 0.0})
    X = gb.regressor_matrix(st, rec.u, rec.y)
    diff = np.abs(X @ fits[1] - X @ (A @ fits[0] + t))
    # as above: the raw model's own evaluation round-off, measured 1.1 of it
    bound = np.finfo(float).eps * (np.abs(X) @ np.abs(fits[1]))
    assert np.all(diff <= 5 * bound), np.max(diff / bound)


def test_passes_through_a_point_of_small_slope_at_y_plus_1e6_as_at_y():
    # was: PassesThrough's check that each point is an isolated equilibrium (D = 1 − ∂(static equation)/∂ȳ not
    # vanishing) was made on the raw θ, where D is judged against the size of its terms: at y + 1e6 the terms
    # θ_y(k-1) and 2 θ_y(k-1)² ȳ are 3.7e6 each, and D = −0.0039 fell under 1e-9 of them, so cls refused the fit
    # ("a vanishing derivative in ȳ") it made at y, 1e3, 1e4 and 1e5. The check is now made again on the centred
    # signals the fit ran on, the estimate refused only when it fails there too
    rng = np.random.default_rng(0)
    rng.uniform(0, 1, 12)
    u, y = rng.uniform(0, 1, 7), rng.uniform(0, 1, 7)
    st = gb.parse_structure(_QUADRATIC)
    fits = []
    for c in (0.0, 1e6):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", gb.StaticRangeWarning)
            fits.append(gb.cls(st, gb.Record(u, y + c), gb.StaticPoints([0.2, 0.8], [0.3 + c, 0.6 + c]),
                               how="points").model.theta)
    A, t = shift_map(st, {"y": 1e6, "u": 0.0})
    # the same model: the slope at the points, D = 1 − θ_y − 2 θ_yy ȳ − θ_yu ū, to its round-off at y + 1e6
    # (eps · 3.7e6 ≈ 1e-9; measured 4e-10)
    for th, c in ((fits[1], 1e6), (A @ fits[0] + t, 1e6)):
        D = 1 - th[1] - 2 * th[2] * (np.array([0.3, 0.6]) + c) - th[3] * np.array([0.2, 0.8])
        assert np.allclose(D, [0.62995, -0.0039208], atol=1e-5)


def test_a_degenerate_pass_through_is_still_refused_at_an_offset():
    # the centred check refuses what it should: Σy = 1 with every other cluster 0 meets any points (0 = 0)
    rng = np.random.default_rng(3)
    u = rng.uniform(0, 1, 200)
    y = np.cumsum(0.01 * rng.standard_normal(200))  # a random walk: y(k) = y(k-1) fits it best
    st = gb.parse_structure(["1", "y(k-1)", "u(k-1)"])
    for c in (0.0, 1e6):
        pts = gb.StaticPoints([0.1, 0.5, 0.9], np.array([0.0, 0.3, 0.1]) + c)  # on no line: only Σy = 1 meets them
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", gb.StaticRangeWarning)
            with pytest.raises(ValueError, match="static function"):
                gb.cls(st, gb.Record(u, y + c), pts, how="points")


@settings(max_examples=25, deadline=None)
@given(seed=hst.integers(0, 2**16), cy=hst.floats(-7.0, 7.0), cu=hst.floats(-4.0, 4.0), ky=hst.sampled_from([1e-3, 1.0, 1e3]))
def test_pe_of_a_closed_structure_is_one_model_at_any_zero_and_unit(seed, cy, cu, ky):
    # the law behind the fixes above: a structure closed under shifts spans the same functions at any zero of y and u
    # and in any unit of y, so PE's members (closed form, eq. (11)) are one model, to the round-off of evaluating it
    rng = np.random.default_rng(seed)
    n = 120
    u = np.repeat(rng.uniform(0, 1, n // 6), 6)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.2 + 0.5 * y[k - 1] - 0.3 * y[k - 1] ** 2 + 0.4 * u[k - 1] + 0.2 * y[k - 1] * u[k - 1] \
            + 0.01 * rng.standard_normal()
    assume(np.ptp(y) > 0.05)
    ub = np.array([0.1, 0.5, 0.9])
    yb = np.interp(ub, np.sort(u), np.sort(y))  # points near the record's levels (their values matter little here)
    oy, ou = np.sign(cy) * 10 ** abs(cy) if abs(cy) > 1 else 0.0, np.sign(cu) * 10 ** abs(cu) if abs(cu) > 1 else 0.0
    structure = gb.parse_structure(_QUADRATIC)
    lam = [1e-3, 0.5, 1.0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        base = gb.pe_thetas(structure, gb.Record(u, y), gb.StaticPoints(ub, yb), lambdas=lam, solver="closed")
        rec = gb.Record(u + ou, ky * y + oy)
        got = gb.pe_thetas(structure, rec, gb.StaticPoints(ub + ou, ky * yb + oy), lambdas=lam, solver="closed")
    A, t = shift_map(structure, {"y": oy, "u": ou})
    powers = np.array([sum(p for s, _, p in term.factors if s == "y") for term in structure])
    mapped = (base * ky / ky**powers) @ A.T + t  # to y in its unit (θ_j scaled by ky^(1 − y power)), then shifted
    X = gb.regressor_matrix(structure, rec.u, rec.y)
    diff = np.abs(got @ X.T - mapped @ X.T)
    # the evaluation's round-off of each, eps · Σ_j |θ_j x_j|, and the record's own: its levels at the offsets carry
    # eps · |offset| (y), which the solve amplifies by the conditioning of the centred problem (up to 16 of that bound
    # over 60 draws, at λ1 = 1e-3); the raw fits failed it from y + 316 on (every λ1 < 1 'singular' further out)
    bound = np.finfo(float).eps * (np.abs(got) @ np.abs(X).T + np.abs(mapped) @ np.abs(X).T)
    assert np.all(diff <= 200 * bound + 1e-9 * ky * np.ptp(y)), np.max(diff / bound, axis=1)


def test_se_dsf_gauss_newton_model_does_not_depend_on_the_output_zero():
    # was: se_dsf's Gauss–Newton model (_GN) took the free-run and static residuals and their Jacobians of raw θ, on
    # the raw records: for the pumping plant's closed 1, y1, y1², y1 u1, u1 at y + 1e6 (a constant of 9e7 for a spread
    # of 4) J_S and J_SF at one z came out 4e-8 and 8e-7 apart from y's, their Gram matrices 1.3e-5, and the edge
    # iterations stopped on that round-off ('no step improves') at other points (J_S 1.1e-5 apart, another start
    # named). They are now made from z as the optimisers' runs are: the centred model on the centred signals
    from graybox.estimation._epsilon_constraint import _GN
    from graybox.estimation._simulation_error import SEProblem

    st = gb.parse_structure(_QUADRATIC)
    problems = [SEProblem(st, *_pumping_at(c)) for c in (0.0, 1e6)]
    z = problems[0].ls_z()  # the problems' coordinates are those of the centred signals, the same at both zeros
    (f0, g0, G0), (f1, g1, G1) = (_GN(p).parts(z, True) for p in problems)
    # the centred signals differ by the round-off of y + 1e6 (eps · 1e6 ≈ 2e-10 against a spread of 4): measured
    # 7e-12 (J_S), 9e-12 (J_SF) and up to 1.3e-10 (the Gram matrices)
    assert abs(f1 - f0) <= 1e-9 * f0 and abs(g1 - g0) <= 1e-9 * g0
    for a, b in zip(G0, G1):
        assert np.max(np.abs(a - b)) <= 1e-8 * np.max(np.abs(a))
