"""hunt42b: bugs found in graybox.control (local models, operating curves), the CSV loaders and hand-edited saved
files of local models, operating curves and bands; each test failed before its fix."""

from __future__ import annotations


import numpy as np
import pytest

import graybox as gb
from conftest import edited_file
from graybox.control import local_model, operating_curve




ST = ["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)y(k-1)", "u(k-1)^2", "1"]


@pytest.fixture(scope="module")
def pumping_unc():
    d = gb.load_pumping()
    return gb.ls_uncertainty(gb.els(ST, d.ident, noise=0).model, d.ident), d


@pytest.mark.parametrize("b", [[0.0, 1e308], [1e308, 1e308]])
def test_a_local_model_whose_figures_overflow_is_refused_on_loading(pumping_unc, tmp_path, b):
    # b = 1e308 in a hand-edited file loaded, and its gain then overflowed with numpy's RuntimeWarning (an inf gain
    # of a stable model); b = [1e308, 1e308] overflowed in the sum
    lm = local_model(pumping_unc[0].model, 1000.0)
    p = edited_file(lm, tmp_path / "lm.json", lambda o: o.__setitem__("b", [b]))
    with pytest.raises(gb.GrayboxFileError, match="overflow"):
        gb.load(p)


def test_an_integrators_local_model_still_loads_with_its_infinite_gain(tmp_path):
    # the check above refuses overflow, not the 1 − Σa = 0 of an integrator, whose gain is inf by definition
    lm = type(local_model(gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0]), 1.0, Ts=1.0))(
        np.array([0.0]), 1.0, "continuum of equilibria", "ū = 0: every ȳ", np.array([1.0]), np.array([[1.0]]), 1.0,
        ("u",))
    gb.save(lm, tmp_path / "int.json")
    back = gb.load(tmp_path / "int.json")
    with np.errstate(divide="ignore"):
        assert np.isinf(back.dc_gain[0])


def _band_of(kind, unc, d, method):
    if kind == "curve":
        return gb.static_curve_band(unc, np.array([800.0, 1200.0, 1600.0]), method=method, n_samples=50)
    return gb.simulation_band(unc, d.valid.slice(0, 200) if hasattr(d.valid, "slice") else d.valid, method=method,
                              n_samples=50)


@pytest.mark.parametrize("kind", ["curve", "simulation"])
@pytest.mark.parametrize("method, edit", [("delta", {"n_samples": 500}), ("monte-carlo", {"n_samples": 0}),
                                          ("monte-carlo", {"n_samples": 3}), ("delta", {"method": "monte-carlo"}),
                                          ("monte-carlo", {"method": "delta"})])
def test_a_band_whose_method_and_draws_disagree_is_refused_on_loading(pumping_unc, tmp_path, kind, method, edit):
    # a delta band saying it drew 500 models, or a Monte Carlo band of 0 draws, loaded as it was written
    unc, d = pumping_unc
    band = _band_of(kind, unc, d, method)
    p = edited_file(band, tmp_path / "band.json", lambda o: o.update(edit))
    with pytest.raises(gb.GrayboxFileError, match="n_samples"):
        gb.load(p)
    gb.save(band, tmp_path / "ok.json")  # the band as made loads
    assert gb.load(tmp_path / "ok.json").method == method


@pytest.mark.parametrize("kind, share", [("curve", "undefined"), ("simulation", "diverged")])
def test_a_delta_band_with_dropped_draws_is_refused_on_loading(pumping_unc, tmp_path, kind, share):
    # the delta method draws nothing, so none is left out; a Monte Carlo share is a count of its draws
    unc, d = pumping_unc
    delta = _band_of(kind, unc, d, "delta")
    value = [0.5] * 3 if kind == "curve" else 0.5
    p = edited_file(delta, tmp_path / "band.json", lambda o: o.update({share: value}))
    with pytest.raises(gb.GrayboxFileError, match=share):
        gb.load(p)
    mc = _band_of(kind, unc, d, "monte-carlo")  # 50 draws: a share of 0.013 is no count of them
    value = [0.013] * 3 if kind == "curve" else 0.013
    p = edited_file(mc, tmp_path / "mc.json", lambda o: o.update({share: value}))
    with pytest.raises(gb.GrayboxFileError, match=share):
        gb.load(p)


@pytest.fixture(scope="module")
def curve_with_band(pumping_unc):
    unc, _ = pumping_unc
    return operating_curve(unc.model, [800.0, 1200.0, 1600.0], uncertainty=unc, n_samples=50)


def _at(key, i, v):
    return lambda o: o[key].__setitem__(i, v)


@pytest.mark.parametrize("edit, match", [
    (_at("damping", 0, 0.1), "damping disagrees"),
    (_at("settling_time", 1, -3.0), "settling_time"),
    (_at("gain_low", 0, 10.0), "gain_low must not exceed gain_high"),
    (_at("time_constant_low", 2, 50.0), "time_constant_low must not exceed time_constant_high"),
    (_at("time_constant_low", 0, -5.0), "time_constant_low"),
    (_at("undefined", 0, 7.0), "undefined"),
    (lambda o: o.__setitem__("level", 5.0), "level"),
    (lambda o: o.__setitem__("gain_high", None), "bands"),
    (lambda o: [o.__setitem__(k, None) for k in ("gain_low", "gain_high", "time_constant_low", "time_constant_high",
                                                  "undefined")], "level"),
])
def test_a_hand_edited_operating_curve_is_held_to_what_a_curve_can_be(curve_with_band, tmp_path, edit, match):
    # each loaded as written: crossed bands, a level of 5, an undefined share of 7, a damping the local models
    # contradict, a negative settling time, and half a band (to_frame then raised AttributeError on None)
    p = edited_file(curve_with_band, tmp_path / "oc.json", edit)
    with pytest.raises(gb.GrayboxFileError, match=match):
        gb.load(p)
    gb.save(curve_with_band, tmp_path / "ok.json")
    back = gb.load(tmp_path / "ok.json")
    assert back.has_band and np.array_equal(back.gain_low, curve_with_band.gain_low)


def test_a_surface_fit_names_the_input_with_too_few_levels_for_its_power():
    # a degree-2 surface on a 2 × 3 grid of (u1, u2): u1² is not identifiable from two levels of u1, and the fit said
    # only 'regressor matrix has rank 5 < 6 columns', naming neither the input nor the power
    P = np.array([[a, b] for a in (0.5, 1.5) for b in (0.5, 1.0, 1.5)])
    pts = gb.StaticPoints(P, P.sum(axis=1) + P[:, 1] ** 2, input_names=("u1", "u2"))
    with pytest.raises(ValueError, match=r"u1.* 2 levels.*power 2"):
        gb.StaticSurface.fit(pts, degree=2)
    s = gb.StaticSurface.fit(pts, exponents=[(0, 0), (1, 0), (0, 1), (0, 2), (1, 1)])  # u2² from its 3 levels
    np.testing.assert_allclose(s(P), pts.ybar, atol=1e-9)


@pytest.mark.parametrize("header, asked, meant", [("t [s];power [%];temperature [°C]", "power", "power [%]"),
                                                   ("t;P (kW);T", "p", "P (kW)"),
                                                   ("t;power;temperature", "power [%]", "power")])
def test_a_missing_column_names_the_column_with_its_unit_in_brackets(tmp_path, header, asked, meant):
    # a logger's header 'power [%]' asked for as 'power': the message listed the columns but suggested none (the
    # close-match ratio of 'power' to 'power [%]' is below difflib's cutoff for short names)
    p = tmp_path / "run.csv"
    p.write_text(header + "\n" + "\n".join(f"{k};{k % 3};{k}" for k in range(6)) + "\n")
    with pytest.raises(ValueError, match=rf"Did you mean .*{__import__('re').escape(repr(meant))}"):
        gb.load_record_csv(p, u=asked, y=header.split(";")[2], Ts=1.0)


def test_narx_iosystem_without_a_period_asks_for_what_it_takes():
    # the message said 'pass Ts= or data= (records)', and narx_iosystem takes no data=: passing it was a TypeError
    m = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0])
    with pytest.raises(ValueError, match="Ts") as info:
        gb.narx_iosystem(m)
    assert "data=" not in str(info.value)
    with pytest.raises(ValueError, match="data="):  # local_model does take it
        local_model(m, 1.0)


@pytest.mark.parametrize("field, i, value", [("ubar", 0, "nan"), ("ybar", 0, "nan"), ("gain", 1, "inf"),
                                             ("ybar_low", 0, "nan"), ("ybar_std", 0, "inf"), ("gain_high", 2, "nan")])
def test_a_static_band_with_a_non_finite_value_is_refused_on_loading(pumping_unc, tmp_path, field, i, value):
    # NaN and inf in a hand-edited file loaded as written (a delta band has every value; a Monte Carlo band NaN only
    # where no draw reached an equilibrium)
    unc, _ = pumping_unc
    band = gb.static_curve_band(unc, np.array([800.0, 1200.0, 1600.0]))
    p = edited_file(band, tmp_path / "band.json", _at(field, i, value))
    with pytest.raises(gb.GrayboxFileError, match=field):
        gb.load(p)


def test_a_monte_carlo_static_band_keeps_nan_only_where_no_draw_reached(pumping_unc, tmp_path):
    unc, _ = pumping_unc
    band = gb.static_curve_band(unc, np.array([800.0, 1200.0, 1600.0]), method="monte-carlo", n_samples=20)
    nan_everywhere = lambda o: [o[f].__setitem__(1, "nan") for f in ("ybar_low", "ybar_high", "ybar_std", "gain_low",
                                                                       "gain_high", "gain_std")]
    p = edited_file(band, tmp_path / "band.json", nan_everywhere)
    with pytest.raises(gb.GrayboxFileError, match="ybar_low"):
        gb.load(p)
    p = edited_file(band, tmp_path / "band.json", lambda o: (nan_everywhere(o), o["undefined"].__setitem__(1, 1.0)))
    assert np.isnan(gb.load(p).ybar_low[1])  # no draw reached an equilibrium there: no band, as made


@pytest.mark.parametrize("edit, match", [
    (_at("t", 1, 0.0), "t must increase"), (_at("t", 1, "nan"), "t must increase"), (_at("yhat", 5, "nan"), "yhat"),
    (_at("low", 5, "nan"), "low"), (_at("std", 5, "inf"), "std"), (_at("y", 3, "inf"), "y"),
    (lambda o: [o.__setitem__(f, []) for f in ("t", "y", "yhat", "low", "high", "std")], "sample"),
])
def test_a_hand_edited_simulation_band_is_held_to_what_a_band_can_be(pumping_unc, tmp_path, edit, match):
    # each loaded as written (an empty one then made repr raise 'zero-size array to reduction operation')
    unc, d = pumping_unc
    band = gb.simulation_band(unc, d.valid)
    p = edited_file(band, tmp_path / "band.json", edit)
    with pytest.raises(gb.GrayboxFileError, match=match):
        gb.load(p)


@pytest.mark.parametrize("a", [[1.0], [1.5, -0.2], [0.0, 1.2]])
def test_a_reached_local_model_with_poles_on_or_outside_the_unit_circle_is_refused(pumping_unc, tmp_path, a):
    # 'reached' is a stable equilibrium; a hand-edited a = [1.0] loaded as reached with an infinite gain and τ
    lm = local_model(pumping_unc[0].model, 1000.0)
    p = edited_file(lm, tmp_path / "lm.json", lambda o: o.__setitem__("a", a))
    with pytest.raises(gb.GrayboxFileError, match="reached"):
        gb.load(p)
    p = edited_file(lm, tmp_path / "lm2.json", lambda o: o.update(a=a, status="no stable equilibrium", reason="edited"))
    assert not gb.load(p).stable  # the same coefficients under a status that says so load


def test_a_local_model_with_no_stable_equilibrium_and_stable_poles_is_refused(pumping_unc, tmp_path):
    # the converse: 'no stable equilibrium' over the estimate's stable coefficients loaded as written
    lm = local_model(pumping_unc[0].model, 1000.0)
    p = edited_file(lm, tmp_path / "lm.json", lambda o: o.update(status="no stable equilibrium", reason="edited"))
    with pytest.raises(gb.GrayboxFileError, match="no stable equilibrium"):
        gb.load(p)


def _plant_loop(controller=lambda k, y: 1000.0, n=3, **kw):
    from graybox.datasets import PumpingPlant

    return PumpingPlant().closed_loop(controller, n, **({"u0": 1000.0, "noise": False, "process_noise": False} | kw))


@pytest.mark.parametrize("n, error", [(True, TypeError), ("3", TypeError), (2.5, TypeError), (0, ValueError)])
def test_closed_loop_checks_n_samples(n, error):
    # True ran one sample, '3' was a ValueError
    with pytest.raises(error, match="n_samples"):
        _plant_loop(n=n)


@pytest.mark.parametrize("option", ["noise", "process_noise"])
def test_the_plant_refuses_a_noise_switch_that_is_no_bool(option):
    # noise='no' (truthy) asked for a seed, as if noise had been switched on
    from graybox.datasets import PumpingPlant

    with pytest.raises(TypeError, match=option):
        _plant_loop(**{option: "no"})
    with pytest.raises(TypeError, match=option):
        PumpingPlant().simulate(np.full(5, 1000.0), **({"noise": False, "process_noise": False} | {option: "no"}))


@pytest.mark.parametrize("out, error", [("a", TypeError), (None, TypeError), ([1000.0, 1100.0], ValueError)])
def test_closed_loop_names_the_controller_and_sample_of_a_bad_reference(out, error):
    # a string or None gave float()'s own message, naming neither the controller nor the sample
    with pytest.raises(error, match="controller.*sample 0"):
        _plant_loop(lambda k, y: out)


def test_closed_loop_takes_a_controller_returning_a_one_element_array():
    # a python-control controller's output is an array of one value: float() refused it (numpy 2) without naming it
    a = _plant_loop(lambda k, y: np.array([[1000.0 + k]]))
    b = _plant_loop(lambda k, y: 1000.0 + k)
    np.testing.assert_array_equal(a.u, b.u)
    np.testing.assert_array_equal(a.y, b.y)


def test_an_uncertainty_column_in_another_unit_than_the_output_is_refused(tmp_path):
    # the units row said δ in mbar beside ȳ in bar; δ = 0.1 was read as 0.1 bar, a band 1000 times too wide
    p = tmp_path / "steady.csv"
    p.write_text("u;y;d\nrpm;bar;mbar\n1;2;0,1\n2;3;0,1\n")
    with pytest.raises(ValueError, match=r"'d'.*mbar.*bar"):
        gb.load_static_csv(p, u="u", y="y", units_row=True, uncertainty="d")
    p.write_text("u;y;d\nrpm;bar;[bar]\n1;2;0,1\n2;3;0,1\n")  # the output's unit, or none said, is read
    assert gb.load_static_csv(p, u="u", y="y", units_row=True, uncertainty="d").uncertainty.tolist() == [0.1, 0.1]
    p.write_text("u;y;d\nrpm;bar;\n1;2;0,1\n2;3;0,1\n")
    assert gb.load_static_csv(p, u="u", y="y", units_row=True, uncertainty="d").units == ("rpm", "bar")


def test_local_zeros_are_the_transfer_functions_zeros_away_from_the_origin():
    # the docstring said 'roots of Σ_l b_il z^(L_u − l)', which for u2 (lags to 2, L_u = 3 from u1) has a root at 0
    # that zeros() leaves out and python-control's transfer function shows
    ct = pytest.importorskip("control")
    m = gb.Model(["y(k-1)", "y(k-2)", "u1(k-3)", "u2(k-1)", "u1(k-1)u2(k-2)", "1"], [0.5, 0.2, 1.0, -0.5, 0.01, 0.3],
                 Ts=0.2, input_names=("u1", "u2"))
    lm = local_model(m, [2.0, 3.0])
    tf = lm.to_transfer_function()
    for i in range(2):
        z = tf[0, i].zeros()
        want = np.sort_complex(z[np.abs(z) > 1e-12])
        np.testing.assert_allclose(np.sort_complex(lm.zeros(i)), want, atol=1e-12)
    assert "other than 0" in type(lm).zeros.__doc__


def test_a_local_model_whose_time_constant_overflows_is_refused_on_loading(pumping_unc, tmp_path):
    # Ts = 1e308 s in a hand-edited file loaded, and τ = −Ts / ln ρ then overflowed with numpy's RuntimeWarning
    lm = local_model(pumping_unc[0].model, 1000.0)
    p = edited_file(lm, tmp_path / "lm.json", lambda o: o.__setitem__("Ts", 1e308))
    with pytest.raises(gb.GrayboxFileError, match="time constant"):
        gb.load(p)
    p = edited_file(lm, tmp_path / "lm2.json", lambda o: o.__setitem__("Ts", 1e300))  # large, but its τ is a number
    assert np.isfinite(gb.load(p).time_constant)


@pytest.mark.parametrize("field", ["gain_low", "gain_high", "time_constant_low", "time_constant_high"])
def test_an_operating_curve_band_is_nan_only_where_no_draw_was_kept(curve_with_band, tmp_path, field):
    # a band of NaN at points the estimate reaches, with every draw kept (undefined 0), loaded as written
    p = edited_file(curve_with_band, tmp_path / "oc.json", lambda o: o.__setitem__(field, ["nan"] * 3))
    with pytest.raises(gb.GrayboxFileError, match=field):
        gb.load(p)
