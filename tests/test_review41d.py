"""Review 41d: where a model meets data in other units, and the static map's one kernel of partials."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import graybox as gb
from graybox.static._linearisation import (local_coefficients, static_gain_gradient, static_gains,
                                           static_partials, static_powers, static_theta_gradient_of)

UNITS = ("rpm", "mlc")
OTHER = ("rad/s", "mlc")
ST = gb.Structure(["1", "y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2"])


def _record(seed: int = 0, n: int = 400, units: tuple[str, str] = UNITS, Ts: float = 0.1) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.0, 1.0, n // 10), 10)
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = 0.6 * y[k - 1] + 0.2 * y[k - 2] + 0.3 * u[k - 1] + 0.05 * u[k - 2] ** 2 + 0.4
    return gb.Record(u, y + 0.01 * rng.standard_normal(n), Ts=Ts, units=units, name=f"run {seed} {units[0]}")


def _static(units: tuple[str, str] = UNITS) -> gb.StaticPoints:
    return gb.StaticPoints(np.array([0.2, 0.5, 0.8]), np.array([2.3, 2.7, 3.1]), units=units,
                           name=f"points in {units[0] or 'no unit'}")


def _relabelled(d: gb.Dataset, units: tuple[str, str] = OTHER, Ts: float | None = None) -> gb.Dataset:
    """The same numbers under other units (or another period): only the labels differ."""
    def rec(r: gb.Record) -> gb.Record:
        return gb.Record(r.u, r.y, Ts=r.Ts if Ts is None else Ts, units=units, name=f"{r.name} as {units[0]}")
    s = d.static
    return gb.Dataset(rec(d.ident), rec(d.valid), gb.StaticPoints(s.ubar, s.ybar, units=units, name="points as"))


@pytest.fixture(scope="module")
def data() -> gb.Dataset:
    return gb.Dataset(_record(0), _record(1), _static())


@pytest.fixture(scope="module")
def fits(data) -> dict:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {
            "ls": gb.frols(gb.Candidates(2, 2, degree=2), data, n_terms=5),
            "cls": gb.cls(ST, data, gb.StaticCurve.fit(data.static, degree=2)),
            "pe": gb.pe_pareto(ST, data, lambdas=[0.5]).member_model(0),
            "se": gb.se_pareto(ST, data, lambdas=[0.5], method="gradient").member_model(0),
        }


def _uncertainty(kind: str, fit: object, data: object, **kw: object) -> gb.ParameterUncertainty:
    if kind == "ls":
        return gb.ls_uncertainty(fit, data, **kw)
    if kind == "cls":
        return gb.cls_uncertainty(fit, data, **kw)
    return getattr(gb, f"{kind}_uncertainty")(fit, data, lambda1=0.5, **kw)


# -- 1. the uncertainty of a model met data in other units (or at another period) without a word -----------

@pytest.mark.parametrize("kind", ["ls", "cls", "pe", "se"])
def test_an_uncertainty_refuses_data_in_other_units_than_the_models(kind, fits, data):
    _uncertainty(kind, fits[kind], data)  # its own data: fine
    with pytest.raises(ValueError, match="input unit 'rpm' but .* has 'rad/s'"):
        _uncertainty(kind, fits[kind], _relabelled(data))
    with pytest.raises(ValueError, match="sampled every 0.1 s"):
        _uncertainty(kind, fits[kind], _relabelled(data, UNITS, Ts=0.2))


def test_se_uncertainty_refuses_static_points_in_other_units_than_the_models(fits, data):
    unlabelled = _relabelled(data, ("", ""))  # records that say nothing, static points in another unit
    with pytest.raises(ValueError, match="output unit 'mlc' but 'points in rpm' has 'Pa'"):
        gb.se_uncertainty(fits["se"], unlabelled, static=gb.StaticPoints(data.static.ubar, data.static.ybar,
                                                                         units=("rpm", "Pa"), name="points in rpm"),
                          lambda1=0.5)


# -- 2. static points given beside the records, in other units, joined the fit --------------------------

def test_static_points_in_other_units_than_the_records_are_refused_by_every_fit(data):
    other = _static(OTHER)
    calls = {
        "cls": lambda s: gb.cls(ST, data.ident, s),
        "pe_pareto": lambda s: gb.pe_pareto(ST, data.ident, static=s, lambdas=[0.5]),
        "se_dsf": lambda s: gb.se_dsf(ST, data.ident, static=s, band=1.0),
        "se_uncertainty": lambda s: gb.se_uncertainty(gb.Model(ST, np.array([0.4, 0.6, 0.2, 0.3, 0.05])), data.ident,
                                                      static=s, lambda1=0.5),
        "evaluate_thetas": lambda s: gb.evaluate_thetas(ST, np.array([[0.4, 0.6, 0.2, 0.3, 0.05]]), data.ident, s),
        "a Dataset's records": lambda s: gb.pe_pareto(ST, data, static=s, lambdas=[0.5]),
    }
    for name, call in calls.items():
        with pytest.raises(ValueError, match="input unit 'rpm' but 'points in rad/s' has 'rad/s'"):
            call(other)
    # points that name no unit say nothing: taken
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert np.isfinite(gb.evaluate_thetas(ST, np.array([[0.4, 0.6, 0.2, 0.3, 0.05]]), data.ident,
                                              _static(("", "")))["JSF"]).all()


# -- 3. the control bridge's data= (the range it warns about) in other units -----------------------------

def test_local_models_refuse_data_in_other_units_than_the_models(fits, data):
    m = fits["cls"].model
    for other in (_record(2, units=OTHER), _static(OTHER), _relabelled(data)):
        with pytest.raises(ValueError, match="input unit 'rpm'"):
            gb.local_model(m, 0.5, data=other)
        with pytest.raises(ValueError, match="input unit 'rpm'"):
            gb.operating_curve(m, [0.3, 0.5], data=other)
        with pytest.raises(ValueError, match="input unit 'rpm'"):
            gb.local_model(m, 0.5, data=other, Ts=0.1)  # a period given does not skip the units
    assert gb.local_model(m, 0.5, data=_record(2, units=("", ""))).status == "reached"


# -- 4. a simulation band over a record that names no unit is in the model's units --------------------------

def test_a_simulation_band_says_the_models_units_where_the_record_says_none(fits, data):
    unc = gb.ls_uncertainty(fits["ls"], data)
    band = gb.simulation_band(unc, _record(3, units=("", "")))
    assert band.units == UNITS
    assert gb.simulation_band(unc, _record(3, units=("rpm", ""))).units == UNITS


# -- 5. the static map's partials: unreached equilibria give no number -------------------------------------

# linear in y: F_ȳ and F_ū do not depend on ȳ, so a NaN ȳ (no equilibrium reached) left them finite
LINEAR_IN_Y = gb.Structure(["1", "y(k-1)", "u1(k-1)", "u2(k-2)^2", "u1(k-1)*u2(k-1)"])


def test_no_equilibrium_gives_nan_partials_gains_and_gradients():
    p, A = static_powers(LINEAR_IN_Y, ("u1", "u2"))
    th = np.array([0.1, 0.5, 0.3, 0.2, 0.1])
    ub = np.array([[0.7, -1.3], [0.0, 2.0]])
    Y = np.array([[np.nan, 1.0]])
    Fy, Fu = static_partials(p, A, th[None], ub, Y)
    assert np.isnan(Fy[0, 0]) and np.isnan(Fu[0, 0]).all() and np.isfinite(Fy[0, 1]) and np.isfinite(Fu[0, 1]).all()
    g = static_gains(p, A, th[None], ub, Y)
    assert np.isnan(g[0, 0]).all() and np.isfinite(g[0, 1]).all()
    dy = static_theta_gradient_of(p, A, th, ub, Y[0])
    assert np.isnan(dy[0]).all() and np.isfinite(dy[1]).all()
    gg = static_gain_gradient(p, A, th, ub, Y[0], dy)
    assert np.isnan(gg[0]).all() and np.isfinite(gg[1]).all()


# -- checked and right: the kernel against the lag sums and finite differences ------------------------------

SEVERAL = gb.Structure(["1", "y(k-1)", "y(k-2)*u1(k-1)", "u1(k-1)", "u2(k-2)^2", "y(k-1)^2", "u1(k-1)*u2(k-1)",
                        "u1(k-2)^3"])


def _F(th: np.ndarray, p: np.ndarray, A: np.ndarray, y: float, u: np.ndarray) -> float:
    return float(sum(t * y**q * np.prod(u**a) for t, q, a in zip(th, p, A)) - y)


def test_partials_are_the_local_models_lag_sums_and_the_maps_derivatives():
    names = ("u1", "u2")
    p, A = static_powers(SEVERAL, names)
    th = np.array([0.1, 0.3, 0.05, 0.4, -0.02, -0.01, 0.03, 0.0])  # a zero θ too
    ub = np.array([[0.7, -1.3], [0.0, 2.0], [-0.5, 0.0]])  # ū = 0 and negative ū
    yb = np.array([0.9, -0.4, 1.7])
    Fy, Fu = static_partials(p, A, th[None], ub, yb[None])
    a, b = local_coefficients(SEVERAL, names, np.repeat(th[None], 3, axis=0), yb, ub)
    np.testing.assert_allclose(Fy[0], a.sum(axis=1) - 1.0, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(Fu[0], b.sum(axis=2), rtol=1e-12, atol=1e-15)
    h = 1e-6
    for j in range(3):
        fy = (_F(th, p, A, yb[j] + h, ub[j]) - _F(th, p, A, yb[j] - h, ub[j])) / (2 * h)
        fu = [(_F(th, p, A, yb[j], ub[j] + h * e) - _F(th, p, A, yb[j], ub[j] - h * e)) / (2 * h) for e in np.eye(2)]
        np.testing.assert_allclose(Fy[0, j], fy, rtol=1e-7)
        np.testing.assert_allclose(Fu[0, j], fu, rtol=1e-6, atol=1e-8)


# -- 6. records of one fit where only some name the units: the model said none --------------------------------

def test_a_model_carries_the_units_any_of_its_records_or_static_points_name(data):
    r0, r1 = _record(0, units=("", "")), _record(1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert gb.els(ST, [r0, r1]).model.units == UNITS
        assert gb.frols(gb.Candidates(2, 2, degree=2), [r0, r1], n_terms=4).model.units == UNITS
        assert gb.pe_pareto(ST, [r0, r0.slice(0, 300, "part")], static=_static(), lambdas=[0.5]).units == UNITS
        assert gb.cls(ST, r0, _static()).model.units == UNITS
        assert gb.output_error(ST, [r0, r1], n_starts=1).model.units == UNITS
    with pytest.raises(ValueError, match="input unit 'rpm' but .* has 'rad/s'"):
        gb.output_error(ST, [r0, r1], n_starts=1, choose_on=_record(2, units=OTHER))


# -- 7. a Pareto set's check_record took no static points (AttributeError), as a Model's does ---------------

def test_a_pareto_sets_check_record_takes_static_points_as_a_models_does(data):
    ps = gb.pe_pareto(ST, data, lambdas=[0.5])
    ps.check_record(_static())
    ps.check_record(_static(("", "")))
    with pytest.raises(ValueError, match="input unit 'rpm' but 'points in rad/s' has 'rad/s'"):
        ps.check_record(_static(OTHER))
    ps.member_model(0).check_record(_static())  # as the member's model


# -- 8. the control bridge's local models lost the model's units (their gains are in them) --------------------

def test_local_models_and_operating_curves_keep_the_models_units(fits, tmp_path):
    m = fits["cls"].model
    lm = gb.local_model(m, 0.5)
    assert lm.units == UNITS
    oc = gb.operating_curve(m, [0.3, 0.5])
    assert oc.units == UNITS and all(x.units == UNITS for x in oc.local_models)
    for v in (lm, oc):
        path = gb.save(v, tmp_path / f"{type(v).__name__}.json")
        assert gb.read_header(path)["units"] == UNITS
        assert gb.load(path).units == UNITS
    assert gb.local_model(gb.Model(ST, m.theta), 0.5, Ts=0.1).units == ("", "")  # a model that says none
    with pytest.raises(ValueError, match="not of one model"):
        gb.OperatingCurve(**{f.name: getattr(oc, f.name) for f in dataclasses.fields(oc)}
                          | {"local_models": (oc.local_models[0],
                                             gb.local_model(gb.Model(ST, m.theta, Ts=m.Ts, units=OTHER), 0.5))})


# -- 9. units were held to the first record only: one that names none let two others disagree ---------------

def test_records_that_disagree_are_refused_when_the_first_names_no_unit(data):
    r0, r1, r2 = _record(0, units=("", "")), _record(1), _record(2, units=OTHER)
    with pytest.raises(ValueError, match="'run 1 rpm' has input unit 'rpm' but 'run 2 rad/s' has 'rad/s'"):
        gb.els(ST, [r0, r1, r2])
    with pytest.raises(ValueError, match="input unit 'rpm' but 'run 2 rad/s' has 'rad/s'"):
        gb.frols(gb.Candidates(2, 2, degree=2), [r0, r1, r2], n_terms=4)
    with pytest.raises(ValueError, match="input unit 'rpm' but 'points in rad/s' has 'rad/s'"):
        gb.Dataset(r0, r1, _static(OTHER))
    gb.Dataset(r0, r1, _static(("", "mlc")))  # what is named agrees
