"""Free-run fits and Monte Carlo draws that do not depend on the units' zeros and scales (units41b).

1. A structure closed under shifts (every divisor of every term, as ``centre=True`` returns) spans the same
   models whatever offsets and scales u and y carry, so its simulation-error fits (``se_pareto`` gradient and
   GA, ``se_dsf``, ``output_error``) should be the same model. They were not: the optimisers moved in raw
   scaled parameters, so their steps, tolerances, the ridge towards least squares, the pulled-in starts and
   the GA's mutations meant other changes of the model at another offset (output_error's J_S moved by up to
   35 %, the GA's by up to 58 %, u + 1e4 and y + 1e4 on the bundled plant; BENCHMARKS.md).
2. Monte Carlo bands draw θ = θ̂ + zF for a factor F of the covariance; F came from each estimator's own
   coordinates, so one seed drew other models at another offset or unit.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import graybox as gb
from graybox.selection._centring import closure, is_closed, shift_map

TRUE = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "u(k-2)^2"])
THETA = np.array([0.5, 0.3, 0.2, 0.1])
CLOSED = closure(TRUE)  # 1, y(k-1), u(k-1), u(k-2) besides the true terms


def _record(seed: int, n: int = 300) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1.0, 1.0, n // 5 + 1), 5)[:n]
    y = gb.Model(TRUE, THETA).simulate(u, np.zeros(2)) + 0.02 * rng.standard_normal(n)
    return gb.Record(u, y, name=f"narx {seed}")


UB = np.linspace(-0.9, 0.9, 7)
DATA = gb.Dataset(_record(0), _record(1), gb.StaticPoints(UB, gb.Model(TRUE, THETA).static_curve(UB) + 0.01,
                                                          uncertainty=0.05))
BAND = 0.05 ** 2


def _moved(data: gb.Dataset, su: float, ou: float, sy: float, oy: float) -> gb.Dataset:
    def rec(r):
        return replace(r, u=su * r.u + ou, y=sy * r.y + oy)
    sp = data.static
    return gb.Dataset(rec(data.ident), rec(data.valid),
                      gb.StaticPoints(su * sp.ubar + ou, sy * sp.ybar + oy, uncertainty=sy * sp.uncertainty))


def _run_back(model: gb.Model, data: gb.Dataset, sy: float, oy: float) -> np.ndarray:
    """The model's free run on the validation record, in the untransformed output's units."""
    return (model.simulate(data.valid, data.valid.y[: model.max_lag]) - oy) / sy


def _same_run(a: np.ndarray, b: np.ndarray, rtol: float) -> None:
    assert np.max(np.abs(a - b)) <= rtol * DATA.valid.y.std()


# offsets up to 100 spreads of u and of y, positive scales over six decades; the raw model's free run loses
# about (offset / spread)² ulps (the closed structure's raw parameters hold the offsets' powers)
transforms = st.tuples(st.sampled_from([1.0, 1000.0, 1e-3, 3.7]), st.floats(-100.0, 100.0),
                       st.sampled_from([1.0, 1000.0, 1e-3, 0.3]), st.floats(-100.0, 100.0))
FAST = settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _fit_all(data: gb.Dataset, sy: float):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # slow-mode and static-range notes: the same at every offset
        return {
            "oe": [gb.output_error(CLOSED, data.ident, n_starts=2).model],
            "gradient": gb.se_pareto(CLOSED, data, lambdas=[1.0, 0.3], method="gradient", tol=1e-12).models(),
            "ga": gb.se_pareto(CLOSED, data, lambdas=[1.0, 0.3], method="ga",
                               options=gb.GAOptions(population=30, generations=10)).models(),
            "dsf": [gb.se_dsf(CLOSED, data, band=BAND * sy * sy, lambdas=[0.9, 0.5]).model],
        }


@pytest.fixture(scope="module")
def base_fits():
    return {k: [_run_back(m, DATA, 1.0, 0.0) for m in ms] for k, ms in _fit_all(DATA, 1.0).items()}


def test_the_structure_is_closed():
    assert is_closed(CLOSED) and not is_closed(TRUE)


@FAST
@given(transforms)
def test_closed_structure_free_run_fits_do_not_depend_on_units(base_fits, tr):
    su, du, sy, dy = tr
    assume((su, sy) != (1.0, 1.0) or abs(du) + abs(dy) > 1.0)  # the base case itself proves nothing
    ou, oy = du * su * DATA.ident.u.std(), dy * sy * DATA.ident.y.std()
    moved = _moved(DATA, su, ou, sy, oy)
    for name, models in _fit_all(moved, sy).items():
        assert len(models) == len(base_fits[name]), name
        for m, base in zip(models, base_fits[name]):
            _same_run(_run_back(m, moved, sy, oy), base, 1e-6)


def test_output_error_ridge_is_invariant_at_a_far_offset():
    # the default ridge (γ = 1) is a penalty in the optimisers' coordinates: in raw ones its constant term moved
    # with the offsets, 12 % of J_S here
    base = gb.output_error(CLOSED, DATA.ident, n_starts=0)
    moved = _moved(DATA, 1.0, 1e4, 1.0, 500.0)
    fit = gb.output_error(CLOSED, moved.ident, n_starts=0)
    assert fit.JS == pytest.approx(base.JS, rel=1e-6)  # u + 1e4 is 2e4 spreads: (2e4)² ulps of round-off
    _same_run(_run_back(fit.model, moved, 1.0, 500.0), _run_back(base.model, DATA, 1.0, 0.0), 1e-6)


def test_select_graybox_centred_free_run_rows_do_not_depend_on_offsets():
    # centre=True closes every structure, so its SE and output-error rows are closed-structure fits: their
    # scores moved by 7.5e-5 (gray, gradient SE) and 3.4e-2 (black, output error) at these offsets
    cand = gb.Candidates(ny=2, nu=2, degree=2)
    moved = _moved(DATA, 1.0, 30 * DATA.ident.u.std(), 1.0, 10 * DATA.ident.y.std())
    kw = {"sizes": [2, 3], "sources": ["frols"], "centre": True}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # slow-mode and range notes: the same at both offsets
        for extra in ({"estimator": ["se-gradient", "oe"]}, {"estimator": ["oe"], "band": np.inf}):
            a, b = gb.select_graybox(cand, DATA, **kw, **extra), gb.select_graybox(cand, moved, **kw, **extra)
            assert list(a.table.index) == list(b.table.index) and a.chosen.name == b.chosen.name
            np.testing.assert_allclose(b.table["JS_valid"], a.table["JS_valid"], rtol=1e-9)


def test_shift_map_is_raw_theta_and_its_inverse_is_the_negated_offsets():
    rng = np.random.default_rng(0)
    off = {"y": 3.0, "u": -7.0}
    A, t = shift_map(CLOSED, off)
    Ainv, tinv = shift_map(CLOSED, {k: -v for k, v in off.items()})
    th = rng.standard_normal(len(CLOSED))
    np.testing.assert_allclose(Ainv @ (A @ th + t) + tinv, th, atol=1e-12)
    with pytest.raises(ValueError, match="not closed"):
        shift_map(TRUE, off)


# -- 2. Monte Carlo draws -----------------------------------------------------------------------------------

def _ls(data: gb.Dataset) -> gb.ParameterUncertainty:
    return gb.ls_uncertainty(gb.els(CLOSED, data.ident, noise=0).model, data.ident)


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(transforms)
def test_monte_carlo_band_draws_the_same_models_at_every_offset_and_unit(tr):
    su, du, sy, dy = tr
    assume((su, sy) != (1.0, 1.0) or abs(du) + abs(dy) > 1.0)
    ou, oy = du * su * DATA.ident.u.std(), dy * sy * DATA.ident.y.std()
    moved = _moved(DATA, su, ou, sy, oy)
    a = gb.simulation_band(_ls(DATA), DATA.valid, method="monte-carlo", n_samples=50, seed=3)
    b = gb.simulation_band(_ls(moved), moved.valid, method="monte-carlo", n_samples=50, seed=3)
    # the quantiles of the same 50 runs, mapped back: one seed draws the same models
    tol = 1e-7 * DATA.valid.y.std()
    np.testing.assert_allclose((b.low - oy) / sy, a.low, rtol=0, atol=tol)
    np.testing.assert_allclose((b.high - oy) / sy, a.high, rtol=0, atol=tol)
    np.testing.assert_allclose(b.std / sy, a.std, rtol=0, atol=tol)


def test_scaled_units_draw_the_same_models_for_an_open_structure():
    # a unit's scale maps any structure's parameters linearly (diagonally): the draws follow it too
    st_ = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "u(k-2)^2"])
    a_unc = gb.ls_uncertainty(gb.els(st_, DATA.ident, noise=0).model, DATA.ident)
    moved = _moved(DATA, 1000.0, 0.0, 0.3, 0.0)
    b_unc = gb.ls_uncertainty(gb.els(st_, moved.ident, noise=0).model, moved.ident)
    a = gb.simulation_band(a_unc, DATA.valid, method="monte-carlo", n_samples=40, seed=1)
    b = gb.simulation_band(b_unc, moved.valid, method="monte-carlo", n_samples=40, seed=1)
    np.testing.assert_allclose(b.low / 0.3, a.low, rtol=0, atol=1e-9 * DATA.valid.y.std())
    np.testing.assert_allclose(b.high / 0.3, a.high, rtol=0, atol=1e-9 * DATA.valid.y.std())


def test_static_curve_band_monte_carlo_follows_the_offsets():
    moved = _moved(DATA, 1.0, 50.0, 1.0, -20.0)
    a = gb.static_curve_band(_ls(DATA), UB, method="monte-carlo", n_samples=200, seed=2)
    b = gb.static_curve_band(_ls(moved), UB + 50.0, method="monte-carlo", n_samples=200, seed=2)
    np.testing.assert_allclose(b.ybar_low + 20.0, a.ybar_low, rtol=0, atol=1e-7)
    np.testing.assert_allclose(b.ybar_high + 20.0, a.ybar_high, rtol=0, atol=1e-7)
