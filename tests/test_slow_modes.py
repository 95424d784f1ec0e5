"""margin="auto" and the slow-mode check: modes far slower than the least-squares model's are named, or kept out."""

import contextlib
import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st

import graybox as gb
from graybox.estimation._local_models import SLOW_FACTOR, slow_margin
from graybox.estimation._simulation_error import SEProblem
from graybox.reference import STRUCTURE_15

THIS = __file__


def _arx_record(a, b=0.5, n=400, seed=0, noise=0.01, u_scale=1.0, y_scale=1.0):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1.0, 1.0, n // 8 + 1), 8)[:n]
    y = gb.simulate(gb.Structure(["y(k-1)", "u(k-1)"]), np.array([a, b]), u, np.zeros(1))
    return gb.Record(u_scale * u, y_scale * (y + noise * rng.standard_normal(n)), Ts=1.0)


def _auto_margin(structure, rec):
    p = SEProblem(structure, [rec], None)
    return slow_margin(p.radius(p.ls_theta()))


@settings(max_examples=30, deadline=None)
@given(a=st.floats(-0.95, 0.95), seed=st.integers(0, 1000))
def test_the_margin_is_a_tenth_of_the_least_squares_models_distance_to_the_unit_circle(a, seed):
    assume(abs(a) > 0.05)
    rec = _arx_record(a, seed=seed)
    structure = gb.Structure(["y(k-1)", "u(k-1)"])
    a_ls = SEProblem(structure, [rec], None).ls_theta()[0]  # a first-order model's local model: ρ = |a|
    assert _auto_margin(structure, rec) == pytest.approx((1 - abs(a_ls)) / SLOW_FACTOR, rel=1e-9)


def test_the_margin_does_not_depend_on_units_or_on_the_sampling_period():
    structure = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"])
    base = _auto_margin(structure, _arx_record(0.8))
    assert _auto_margin(structure, _arx_record(0.8, u_scale=1e3, y_scale=1e-3)) == pytest.approx(base, rel=1e-6)
    # halving the sampling period of a first-order system takes its pole from a to √a: 1 − ρ about halves, and
    # so does the margin, whose slowest allowed time constant stays the same in seconds
    first = gb.Structure(["y(k-1)", "u(k-1)"])
    ratio = _auto_margin(first, _arx_record(np.sqrt(0.8), noise=0.0)) / _auto_margin(first, _arx_record(0.8, noise=0.0))
    assert ratio == pytest.approx((1 - np.sqrt(0.8)) / 0.2, rel=1e-6)


def test_no_reference_where_least_squares_is_itself_unstable():
    assert slow_margin(1.0) is None and slow_margin(1.2) is None
    assert slow_margin(0.9) == pytest.approx(0.1 / SLOW_FACTOR)
    rec = _arx_record(1.02, n=60, noise=0.0)  # an unstable plant: LS finds ρ > 1
    assert _auto_margin(gb.Structure(["y(k-1)", "u(k-1)"]), rec) is None


def test_margin_is_checked():
    rec = _arx_record(0.8)
    with pytest.raises(ValueError, match="margin"):
        gb.output_error(gb.Structure(["y(k-1)", "u(k-1)"]), rec, margin="slow")
    with pytest.raises(ValueError, match="margin"):
        gb.output_error(gb.Structure(["y(k-1)", "u(k-1)"]), rec, margin=1.5)
    with pytest.raises(ValueError, match="resolved by the estimators"):
        SEProblem(gb.Structure(["y(k-1)", "u(k-1)"]), [rec], None, margin="auto")


def _front(margin):
    data = gb.load_pumping()
    with warnings.catch_warnings(record=True) as ws:
        warnings.simplefilter("always")
        se = gb.se_pareto(STRUCTURE_15, data, lambdas=[0.6, 0.3], method="gradient", margin=margin, progress=False)
    return data, se, [w for w in ws if issubclass(w.category, gb.SlowModeWarning)]


def test_the_papers_structure_near_integrators_are_named_then_kept_out():
    # issue 26: without a margin the gradient SE front on structure (15) has spectral radius ≈ 1 along the
    # record and a validation J_S near 2000 mlc²; margin="auto" keeps its modes within 10× least squares'
    data, plain, ws = _front(None)
    assert len(ws) == 1 and ws[0].filename == THIS
    assert "2 of 2" in str(ws[0].message) and "margin='auto'" in str(ws[0].message)
    assert np.all(plain.extra["radius"] > 0.999)
    js_plain = gb.evaluate_thetas(plain.structure, plain.thetas, data.valid, one_step=False)["JS"]
    assert np.all(js_plain > 100)
    data, auto, ws = _front("auto")
    assert not ws
    margin = _auto_margin(STRUCTURE_15, data.ident)
    assert 0 < margin < 0.05
    np.testing.assert_array_equal(auto.extra["margin"], margin)  # both members refitted inside it
    assert np.all(auto.extra["radius"] <= 1 - margin)
    js_auto = gb.evaluate_thetas(auto.structure, auto.thetas, data.valid, one_step=False)["JS"]
    assert np.all(js_auto < 5)


def test_the_radius_column_is_each_members_own():
    data, se, _ = _front("auto")
    p = SEProblem(STRUCTURE_15, [data.ident], data.static)
    for th, r in zip(se.thetas, se.extra["radius"]):
        assert r == pytest.approx(p.radius(th), rel=1e-12)


def test_a_fit_with_no_slow_mode_says_nothing():
    rec = _arx_record(0.8, seed=3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = gb.output_error(gb.Structure(["y(k-1)", "u(k-1)"]), rec, n_starts=2)
    assert r.radius == pytest.approx(0.8, abs=0.02)


def test_auto_keeps_a_fit_whose_modes_are_not_slow():
    # the buck converter's degree-3 structure: its J_S-only member is within the factor without a margin, and a
    # margin imposed during the fit (a wall on the optimiser's path) would have ended elsewhere, diverging on valid
    data = gb.load_buck()
    structure = gb.frols(gb.Candidates(4, 4, ne=0, degree=3), data.ident, criterion="bic").structure
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        auto = gb.se_pareto(structure, data, None, lambdas=[1.0], method="gradient", progress=False)
        plain = gb.se_pareto(structure, data, None, lambdas=[1.0], method="gradient", progress=False, margin=None)
    np.testing.assert_array_equal(auto.thetas, plain.thetas)
    assert np.isnan(auto.extra["margin"][0])
    assert np.isfinite(gb.js(auto.member_model(0), data.valid))


def test_se_dsf_auto_warns_about_the_band_once_and_of_the_model_it_returns():
    # margin="auto" solves twice when the first model is slow: only the returned model's band warning is given
    data, plain, _ = _front(None)
    with pytest.warns(RuntimeWarning, match="band B = 1e-06 is infeasible") as ws:
        res = gb.se_dsf(STRUCTURE_15, data, band=1e-6, theta0=plain.thetas[0], max_iter=20)
    band = [w for w in ws if "is infeasible" in str(w.message)]
    assert len(band) == 1 and band[0].filename == THIS
    assert not res.in_band and f"start {res.start}:" in str(band[0].message)
    assert f"(J_S {res.JS:.4g})" in str(band[0].message)


@pytest.mark.parametrize("margin", [None, 0.01, "auto"])
def test_se_dsf_says_which_margin_its_model_was_solved_with(margin):
    data, plain, _ = _front(None)
    # without a margin the model is the slow one, and is named; with one, no SlowModeWarning (an error here)
    named = pytest.warns(gb.SlowModeWarning, match="se_dsf's model") if margin is None else contextlib.nullcontext()
    with named, pytest.warns(RuntimeWarning, match="is infeasible"):
        res = gb.se_dsf(STRUCTURE_15, data, band=1e-6, theta0=plain.thetas[0], max_iter=20, margin=margin)
    if margin is None:
        assert np.isnan(res.margin)
    else:
        expected = _auto_margin(STRUCTURE_15, data.ident) if margin == "auto" else margin
        assert res.margin == pytest.approx(expected, rel=1e-12)
        assert SEProblem(STRUCTURE_15, [data.ident], data.static).radius(res.model.theta) <= 1 - expected + 1e-12


def test_the_warning_prints_the_least_squares_radius_below_one_when_it_is():
    # ρ_LS = 0.99995 printed to 4 digits read "1": a slow member's 0.999999 then looked faster than least squares
    structure = gb.Structure(["y(k-1)", "u(k-1)"])
    problem = SEProblem(structure, [_arx_record(0.99995, noise=0.0)], None)
    rho_ls = problem.radius(problem.ls_theta())
    assert rho_ls < 1
    with pytest.warns(gb.SlowModeWarning) as ws:
        problem.warn_slow(np.array([[0.999999, 0.5]]), "the fit")
    message = str(ws[0].message)
    printed = float(message.split("least-squares model's ")[1].split(":")[0])
    assert printed < 1 and printed == pytest.approx(rho_ls, abs=1e-6)
    assert ws[0].filename == THIS


def test_a_refit_that_misses_the_band_the_first_fit_met_is_not_taken():
    from types import SimpleNamespace

    from graybox.estimation._simulation_error import refit_if_slow

    structure = gb.Structure(["y(k-1)", "u(k-1)"])
    problem = SEProblem(structure, [_arx_record(0.8)], None)
    slow = SimpleNamespace(model=gb.Model(structure, np.array([0.9999, 0.5])), in_band=True)
    sane = gb.Model(structure, np.array([0.8, 0.5]))
    margins = []

    def fit(in_band):
        def run(p):
            if p.margin is None:
                return slow
            margins.append(p.margin)
            return SimpleNamespace(model=sane, in_band=in_band)
        return run

    with pytest.warns(gb.SlowModeWarning, match="the fit inside that factor .* misses the band this one meets"):
        assert refit_if_slow(problem, fit(False), "the fit", auto=True) is slow  # the band is what was asked
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert refit_if_slow(problem, fit(True), "the fit", auto=True).model is sane
    assert margins[0] == pytest.approx(_auto_margin(structure, _arx_record(0.8)))


def test_the_probe_of_the_first_member_is_not_fitted_again(monkeypatch):
    # se_pareto's probe (the largest λ1 fitted alone, to tell whether the fits run slow) is the gradient sweep's
    # own first member: the sweep takes it as fitted, and gives the same front as the sweep without a probe
    import graybox.estimation._simulation_error as se

    data = gb.load_pumping()
    structure = gb.frols(gb.Candidates(6, 6, degree=2), data.ident, n_terms=4).structure
    lam = [1.0, 0.3, 0.05]
    calls = []
    real = se._multistart

    def counted(problem, lam1, *args, **kwargs):
        calls.append(lam1)
        return real(problem, lam1, *args, **kwargs)

    monkeypatch.setattr(se, "_multistart", counted)
    problem = se.SEProblem(structure, [data.ident], data.static)
    alone = se.gradient_front(problem, lam, progress=False, starts=se._pe_starts(problem))
    n_alone, calls[:] = len(calls), []
    front = gb.se_pareto(structure, data, lambdas=lam, method="gradient", progress=False)
    assert np.isnan(front.extra["margin"]).all()  # not slow: the sweep without a margin, after the probe
    np.testing.assert_array_equal(front.thetas, alone.thetas)
    assert len(calls) == n_alone and calls.count(1.0) == 1  # the first member's restarts ran once, in the probe
    with pytest.raises(ValueError, match="first λ1"):
        se.gradient_front(problem, lam, progress=False, fitted=se.SEFront(np.array([0.3]), alone.thetas[:1],
                                                                          alone.costs[:1]))
