"""hunt50l: diagnostics (residual tests, parameter uncertainty, simulation band, bootstrap) against their promises."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import graybox as gb

STRUCT = ["y(k-1)", "u(k-1)", "u(k-1)^2", "1"]


def _record(seed: int = 0, n: int = 400) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = rng.uniform(0, 2, n)
    e = 0.05 * rng.standard_normal(n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.7 * y[k - 1] + 0.8 * u[k - 1] - 0.2 * u[k - 1] ** 2 + 0.1 + e[k]
    return gb.Record(u, y, name="r")


REC = _record()
MODEL = gb.els(STRUCT, REC, noise=0).model


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_covers_refuses_a_non_finite_theta(bad):
    # covers(θ) answered False for a NaN (or inf) component, silently, as if a true value lay outside its interval
    unc = gb.ls_uncertainty(MODEL, REC)
    th = unc.theta.copy()
    th[1] = bad
    with pytest.raises(ValueError, match="finite"):
        unc.covers(th)
    assert unc.covers(unc.theta).all()


def _rt(**kw):
    t = gb.residual_tests(MODEL, REC)
    return dataclasses.replace(t, **kw)


@pytest.mark.parametrize("kw, said", [
    (dict(n=5), "n"),                                          # 399 residuals, said to be 5
    (dict(residuals=()), "residuals"),                         # no record's residuals at all
    (dict(residuals=(np.full(399, np.nan),)), "residuals"),    # residuals are numbers
    (dict(tests={}), "tests"),                                 # no test made, yet 'all passed'
    (dict(undefined={"u_xi": "edited"}), "undefined"),         # a test both made and left out
    (dict(undefined={"zzz": "edited"}), "undefined"),          # no such test
    (dict(undefined={"u2_xi": 3}), "undefined"),               # the reason is words
])
def test_residual_tests_that_contradict_themselves_are_refused(kw, said):
    # ResidualTests checked its level, rule and each test's name, but not the rest against itself: N = 5 beside 399
    # residuals, NaN residuals, no test at all ('all passed', vacuously), a test both made and said undefined, or an
    # unknown key left out, all built (and loaded from an edited file) and printed as a verdict
    with pytest.raises(ValueError, match=said):
        _rt(**kw)


def test_a_correlation_test_of_a_known_name_has_its_kind():
    t = gb.residual_tests(MODEL, REC)["u_xi"]
    with pytest.raises(ValueError, match="kind"):
        dataclasses.replace(t, kind="nonlinear")  # φ_uξ is a linear test: .nonlinear_passed would count it
    assert dataclasses.replace(t).kind == "linear"


def test_an_edited_residual_tests_file_with_another_n_is_refused(tmp_path):
    path = tmp_path / "r.json"
    t = gb.residual_tests(MODEL, REC)
    gb.save(t, path)
    assert repr(gb.load(path)) == repr(t)
    path.write_text(path.read_text(encoding="utf-8").replace('"n": 399', '"n": 5'), encoding="utf-8")
    with pytest.raises(gb.GrayboxFileError, match="n"):
        gb.load(path)


@pytest.mark.parametrize("level", [1e-20, 1 - 1e-16, 1 - 1e-15])
def test_residual_tests_at_a_level_whose_band_the_floats_cannot_hold_name_the_level(level):
    # a level in (0, 1) whose band is 0 (1e-20: 0.5 + level/2 rounds to 0.5) or infinite (1 − 1e-16, or the
    # Bonferroni quantile of 41 lags at 1 − 1e-15) failed inside CorrelationTest with 'band must lie in (0, inf),
    # got 0.0' or 'band must be a finite number, got inf', naming no argument the caller gave
    with pytest.raises(ValueError, match="level"):
        gb.residual_tests(MODEL, REC, level=level)
    assert gb.residual_tests(MODEL, REC, level=0.999).level == 0.999


@pytest.mark.parametrize("level", [1e-20, 1 - 1e-16])
def test_parameter_uncertainty_at_a_level_whose_quantile_is_0_or_inf_is_refused(level):
    # ls_uncertainty(level=1 − 1e-16) gave intervals ±inf, and simulation_band of it failed with numpy's
    # 'invalid value encountered in multiply' and 'low must hold finite numbers, got nan at index 0'
    with pytest.raises(ValueError, match="level"):
        gb.ls_uncertainty(MODEL, REC, level=level)
    unc = gb.ls_uncertainty(MODEL, REC)
    with pytest.raises(ValueError, match="level"):
        unc.with_level(level)
    with pytest.raises(ValueError, match="level"):
        dataclasses.replace(unc, level=level)
    assert np.all(np.isfinite(unc.with_level(1 - 1e-9).intervals))


def test_els_uncertainty_names_the_record_shorter_than_the_lags():
    # the LS path named it ("record 2 of 2 ('short') has 1 samples …"); the ELS path said only "record has 1 samples,
    # fewer than start + 1 (start = 2, the structure's max lag 1) = 3": a max lag of 1 beside a start of 2, no record
    els = gb.els(STRUCT, REC, noise=2).model
    with pytest.raises(ValueError, match="short") as info:
        gb.ls_uncertainty(els, [REC, REC.slice(0, 1, name="short")])
    assert "max lag 1)" not in str(info.value)


@pytest.mark.parametrize("diverged", [1.0, 0.9])
def test_a_simulation_band_of_fewer_than_two_bounded_runs_is_refused(diverged, tmp_path):
    # simulation_band refuses a band of fewer than two bounded runs, but SimulationBand took one (built by hand or
    # loaded from an edited file) whose every run, or all but one of its 10, diverged, and printed it as a band
    unc = gb.ls_uncertainty(MODEL, REC)
    b = gb.simulation_band(unc, REC, method="monte-carlo", n_samples=10)
    with pytest.raises(ValueError, match="diverged"):
        dataclasses.replace(b, diverged=diverged)
    assert dataclasses.replace(b, diverged=0.8).diverged == 0.8  # two bounded runs of 10 are a band
    path = tmp_path / "b.json"
    gb.save(b, path)
    path.write_text(path.read_text(encoding="utf-8").replace('"diverged": 0.0', f'"diverged": {diverged}'),
                    encoding="utf-8")
    with pytest.raises(gb.GrayboxFileError, match="diverged"):
        gb.load(path)
