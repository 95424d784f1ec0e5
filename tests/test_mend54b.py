"""mend54b: offsets and units in the simulation-error and uncertainty paths."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

import graybox as gb
from graybox.selection._centring import closure

_TRUE = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "u(k-2)^2"])
_THETA = np.array([0.5, 0.3, 0.2, 0.1])
_CLOSED = closure(_TRUE)  # with 1 and u(k-2): closed under shifts, so se_dsf fits it in centred coordinates
_UB = np.linspace(-0.9, 0.9, 7)


def _on_grid(v: np.ndarray) -> np.ndarray:
    """``v`` on the grid 2⁻³⁰: any offset up to 2²² moves it exactly, so the data are the same to the last bit."""
    return np.round(v * 2.0 ** 30) / 2.0 ** 30


def _small_plant(n: int = 200, seed: int = 2, ky: float = 0.01) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """u, y and the static points' ȳ of a small plant whose output's spread is ``ky`` (about)."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1.0, 1.0, n // 5 + 1), 5)[:n]
    m = gb.Model(_TRUE, _THETA)
    y = _on_grid(ky * (m.simulate(u, np.zeros(2)) + 0.02 * rng.standard_normal(n)))
    yb = _on_grid(ky * (m.static_curve(_UB) + 0.05 * np.sin(3 * _UB)))
    return u, y, yb


def _dsf_at(oy: float) -> gb.DSFResult:
    u, y, yb = _small_plant()
    assert np.array_equal((y + oy) - oy, y) and np.array_equal((yb + oy) - oy, yb)  # the offset is exact
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # static-range and slow-mode notes: the same at both offsets
        return gb.se_dsf(_CLOSED, gb.Record(u, y + oy), gb.StaticPoints(_UB, yb + oy), band=0.0005 * 0.01 ** 2,
                         margin=None, lambdas=[0.5], pe_lambdas=[0.01, 0.1])


def _dsf_from_theta0(oy: float) -> gb.DSFResult:
    from graybox.selection._centring import shift_map
    u, y, yb = _small_plant()
    A, t = shift_map(_CLOSED, {"y": oy, "u": 0.0})
    theta0 = A @ np.r_[0.5, 0.003, 0.2, 0.001, 0.0, 0.0] + t  # the plant's model (y in its units) at y + oy
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gb.se_dsf(_CLOSED, gb.Record(u, y + oy), gb.StaticPoints(_UB, yb + oy), band=0.0005 * 0.01 ** 2,
                         margin=None, theta0=theta0)


def test_se_dsf_reports_the_errors_of_its_own_coordinates_at_a_far_output_offset():
    # J_S and J_SF were recomputed from the raw θ on the records as given, whose parameters carry the offsets'
    # powers (a constant of 2e6 for a spread of 0.01): at y + 2²² (the data the same to the last bit) they came out
    # 5.7e-7 and 2.1e-6 off relative from y + 0, where the fit itself, made in centred coordinates, was the same to 1e-9
    a, b = _dsf_from_theta0(0.0), _dsf_from_theta0(2.0 ** 22)
    assert a.in_band and b.in_band
    assert b.JS == pytest.approx(a.JS, rel=2e-8, abs=0)
    assert b.JSF == pytest.approx(a.JSF, rel=2e-8, abs=0)


# -- 2. cls_uncertainty and pe_uncertainty at an offset of y ---------------------------------------------------------

_QUADRATIC = closure(gb.Structure(["y(k-1)", "u(k-1)", "y(k-1)^2", "u(k-1)y(k-1)"]))  # with 1: closed under shifts


def _quadratic_plant(n: int = 200) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(2)
    u = np.repeat(rng.uniform(-1.0, 1.0, n // 5 + 1), 5)[:n]
    m = gb.Model(gb.Structure(["y(k-1)", "u(k-1)", "y(k-1)^2", "u(k-1)y(k-1)"]), np.array([0.5, 0.3, -0.1, 0.1]))
    y = _on_grid(m.simulate(u, np.zeros(2)) + 0.02 * rng.standard_normal(n))
    return u, y, _on_grid(m.static_curve(_UB) + 0.05 * np.sin(3 * _UB))


def _at(model: gb.Model, oy: float) -> gb.Model:
    """The same model on y + oy (the last digits of its θ rounded there)."""
    from graybox.selection._centring import shift_map
    A, t = shift_map(model.structure, {"y": oy, "u": 0.0})
    return model.with_theta(A @ model.theta + t)


# y(k-1)^2 and u(k-1)y(k-1): their coefficients are the same at any offset of y, and so must their std be
_SAME = [2, 3]


@pytest.mark.parametrize("lam, oy, rel", [(0.5, 2.0 ** 20, 1e-4), (1e-3, 2.0 ** 14, 1e-3)])
def test_pe_uncertainty_is_the_same_at_an_offset_of_y(lam, oy, rel):
    # computed on the raw signals, where y(k-1)^2 at y + 2^20 carries the offset's powers: the covariance was
    # refused as "not identifiable" at y + 2^20 (λ1 = 0.5) and y + 2^18 (λ1 = 1e-3), and 2.4e-6 off at y + 2^14,
    # where pe_pareto (which centres) fits the same model at every offset
    u, y, yb = _quadratic_plant()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # static-range notes: the same at both offsets
        m0 = gb.pe_pareto(_QUADRATIC, gb.Record(u, y), gb.StaticPoints(_UB, yb), lambdas=[lam]).member_model(0)
        a = gb.pe_uncertainty(m0, gb.Record(u, y), gb.StaticPoints(_UB, yb), lambda1=lam)
        b = gb.pe_uncertainty(_at(m0, oy), gb.Record(u, y + oy), gb.StaticPoints(_UB, yb + oy), lambda1=lam)
    np.testing.assert_allclose(b.std[_SAME], a.std[_SAME], rtol=rel, atol=0)
    assert b.sigma2 == pytest.approx(a.sigma2, rel=1e-12, abs=0)
    assert b.static_sigma2 == pytest.approx(a.static_sigma2, rel=rel, abs=0)


@pytest.mark.parametrize("how", ["none", "points", "band"])
def test_cls_uncertainty_is_the_same_at_an_offset_of_y(how):
    # on the raw signals: plain least squares refused as "not identifiable" at y + 2^20, static points 2.4e-4 off at
    # y + 2^18, and a static band counted all 21 rows active at y + 2^20 (the std of u(k-1)y(k-1) 100 % off)
    u, y, yb = _quadratic_plant()
    oy = 2.0 ** 20

    def kw(o):
        if how == "points":
            return {"static": gb.StaticPoints(_UB[::3], yb[::3] + o), "how": "points"}
        if how == "band":
            return {"constraints": gb.StaticBand(0.03, points=gb.StaticPoints(_UB, yb + o))}
        return {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = gb.cls(_QUADRATIC, gb.Record(u, y), **kw(0.0))
        a = gb.cls_uncertainty(fit, gb.Record(u, y), **kw(0.0))
        b = gb.cls_uncertainty(_at(fit.model, oy), gb.Record(u, y + oy), **kw(oy))
    assert b.constraints.shape == a.constraints.shape
    np.testing.assert_allclose(b.std[_SAME], a.std[_SAME], rtol=1e-4, atol=0)
    assert b.sigma2 == pytest.approx(a.sigma2, rel=1e-4, abs=0)


def test_se_dsf_names_the_same_start_at_an_offset_of_y():
    # least squares and the fresh fit started from it end on one model, their J_S an ulp apart: the run the last bit
    # favoured was named, 'least squares' at y and 'SE λ1=0.95 (fresh fit)' at y + 1e4
    rng = np.random.default_rng(3)
    u = np.repeat(rng.uniform(-1.0, 1.0, 41), 5)[:200]
    m = gb.Model(_TRUE, _THETA)
    y = m.simulate(u, np.zeros(2)) + 0.02 * rng.standard_normal(200)
    yb = m.static_curve(_UB) + 0.05 * np.sin(3 * _UB + 3)
    starts = []
    for oy in (0.0, 1e4):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            starts.append(gb.se_dsf(_CLOSED, gb.Record(u, y + oy), gb.StaticPoints(_UB, yb + oy), band=0.002,
                                    margin=None, lambdas=[0.5], pe_lambdas=[0.01, 0.1]).start)
    assert starts[0] == starts[1] == "least squares"


def test_se_uncertainty_is_the_same_at_an_offset_of_y():
    # the free runs and equilibria were made with the raw θ on the raw signals, where y(k-1)^2 carries the offset's
    # powers: the std came out 0.6 % off at y + 2^18 and the covariance was refused as "not identifiable" at y + 2^20
    u, y, yb = _quadratic_plant()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # static-range and slow-mode notes: the same at every offset
        m0 = gb.se_pareto(_QUADRATIC, gb.Record(u, y), gb.StaticPoints(_UB, yb), lambdas=[0.5], method="gradient",
                          margin=None).member_model(0)
        a = gb.se_uncertainty(m0, gb.Record(u, y), gb.StaticPoints(_UB, yb), lambda1=0.5)
        for oy in (2.0 ** 18, 2.0 ** 20):
            b = gb.se_uncertainty(_at(m0, oy), gb.Record(u, y + oy), gb.StaticPoints(_UB, yb + oy), lambda1=0.5)
            np.testing.assert_allclose(b.std[_SAME], a.std[_SAME], rtol=1e-4, atol=0)
            assert b.sigma2 == pytest.approx(a.sigma2, rel=1e-4, abs=0)
            assert b.static_sigma2 == pytest.approx(a.static_sigma2, rel=1e-4, abs=0)



def test_cls_names_the_regressor_that_overflows_at_the_offsets_of_a_closed_structure():
    # the centring of a closed structure raised a bare OverflowError when the offsets' powers overflow (u ≈ 1e160 with
    # u(k-1)^2); the raw regressors' check names the term
    rng = np.random.default_rng(0)
    u = rng.uniform(1.0, 3.0, 100)
    y = u + 0.01 * rng.standard_normal(100)
    with pytest.raises(ValueError, match=r"regressors overflow.*u\(k-1\)\^2"):
        gb.cls(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"], gb.Record(u * 1e160, y))


def test_ls_uncertainty_is_the_same_at_an_offset_of_y():
    # on the raw signals y(k-1)^2 at y + 2^20 was refused as "not identifiable" (6e-5 off at y + 2^18), where els
    # (which centres a closed structure) fits the same model at every offset
    u, y, _ = _quadratic_plant()
    m0 = gb.els(_QUADRATIC, gb.Record(u, y), noise=0).model
    a = gb.ls_uncertainty(m0, gb.Record(u, y))
    b = gb.ls_uncertainty(_at(m0, 2.0 ** 20), gb.Record(u, y + 2.0 ** 20))
    np.testing.assert_allclose(b.std[_SAME], a.std[_SAME], rtol=1e-5, atol=0)
    assert b.sigma2 == pytest.approx(a.sigma2, rel=1e-5, abs=0)


def test_els_uncertainty_is_the_same_at_an_offset_of_y():
    # the ELS path too built its regressors and residuals from the raw θ on the raw signals: refused as "not
    # identifiable" at y + 2^20, 1.3e-4 off at y + 2^18
    u, y, _ = _quadratic_plant()
    m0 = gb.els(_QUADRATIC, gb.Record(u, y), noise=1).model
    mo = replace(m0, theta=_at(m0, 2.0 ** 20).theta)  # e(k-1)'s coefficient is the same at any offset
    a = gb.ls_uncertainty(m0, gb.Record(u, y))
    b = gb.ls_uncertainty(mo, gb.Record(u, y + 2.0 ** 20))
    np.testing.assert_allclose(b.std[_SAME], a.std[_SAME], rtol=1e-4, atol=0)
    np.testing.assert_allclose(b.noise_std, a.noise_std, rtol=1e-4, atol=0)
    assert b.sigma2 == pytest.approx(a.sigma2, rel=1e-4, abs=0)


def test_pe_uncertainty_default_static_sigma_holds_the_misfit_near_a_fold_of_the_member():
    # mend55b. At λ1 = 1e-3 the member bends its static curve to a fold at ū = -0.9 (∂s/∂ȳ = 0.001 there); the
    # default σ_SF was Σ(s_i/g_i)² over a first-order ν of ȳ-distances, and both blew up with 1/g at that one
    # point (ν = 466 for 7 points): σ_SF came from that point alone. The points here carry a known systematic
    # error 0.05 sin(3ū) (rms 0.035) under noise of σ = 0.005, so an honest σ_SF (which counts the systematic
    # misfit as noise, the safe side) is well above σ; it read as little as 1.3 σ. Now about 2.6 σ or more.
    u, y, yb = _quadratic_plant()
    rec = gb.Record(u, y)
    rng = np.random.default_rng(0)
    reported = []
    for _ in range(16):
        pts = gb.StaticPoints(_UB, yb + 0.005 * rng.standard_normal(_UB.size))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", gb.StaticRangeWarning)
            th = gb.pe_thetas(_QUADRATIC, rec, pts, lambdas=[1e-3], solver="closed")[0]
            reported.append(np.sqrt(gb.pe_uncertainty(gb.Model(_QUADRATIC, th), rec, pts, lambda1=1e-3).static_sigma2))
    assert min(reported) > 2 * 0.005


def test_pe_pareto_reports_the_errors_of_its_own_coordinates_at_a_far_output_offset():
    # mend55b. pe_pareto fits a closed structure on the centred signals, but the set's J_1, J_S, J_SF (and J_SF^QR)
    # were computed from the raw θ on the raw signals, whose y(k-1)^2 carries the offset's powers: at y + 2^20 (the
    # data the same to the last bit) J_1 came out 1.2e-4, J_S 7e-4 and J_SF^QR 2e-2 off relative from y + 0
    u, y, yb = _quadratic_plant()
    lams = [1e-3, 0.1, 1.0]
    sets = []
    for oy in (0.0, 2.0 ** 20):
        assert np.array_equal((y + oy) - oy, y) and np.array_equal((yb + oy) - oy, yb)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", gb.StaticRangeWarning)
            sets.append(gb.pe_pareto(_QUADRATIC, gb.Record(u, y + oy), gb.StaticPoints(_UB, yb + oy), lambdas=lams))
    a, b = sets
    # at y + 0 the raw θ is exact enough: the set's J's are the evaluator's of its members on the data as given
    ev = gb.evaluate_thetas(_QUADRATIC, a.thetas, gb.Record(u, y), gb.StaticPoints(_UB, yb))
    for name in ("J1", "JS", "JSF"):
        np.testing.assert_allclose(getattr(a, name), ev[name], rtol=1e-9, atol=0)
        np.testing.assert_allclose(getattr(b, name), getattr(a, name), rtol=1e-9, atol=0)
    np.testing.assert_allclose(b.extra["JSF_QR"], a.extra["JSF_QR"], rtol=1e-9, atol=0)


def test_pareto_set_from_centred_thetas_refuses_offsets_that_do_not_name_every_signal():
    u, y, yb = _quadratic_plant()
    th = np.zeros((1, len(_QUADRATIC)))
    with pytest.raises(ValueError, match=r"missing \['u'\]"):
        gb.ParetoSet.from_thetas(_QUADRATIC, th, [0.5], gb.Record(u, y), None, centred=(th, {"y": 0.0}))
    with pytest.raises(ValueError, match="shape of thetas"):
        gb.ParetoSet.from_thetas(_QUADRATIC, th, [0.5], gb.Record(u, y), None, centred=(th[:, :2], {"y": 0.0, "u": 0.0}))
