"""Transient inputs: low-pass filtered squared input changes, zero at every steady state."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import graybox as gb


def _loop(u, Ts, tau):
    """The defining recursion, sample by sample."""
    rho, gain = np.exp(-Ts / tau), -np.expm1(-Ts / tau)  # gain = 1 − ρ, exact also where ρ rounds to 1
    z = np.zeros(len(u))
    for k in range(1, len(u)):
        z[k] = rho * z[k - 1] + gain * (u[k] - u[k - 1]) ** 2
    return z


_arrays = st.lists(st.floats(-1e3, 1e3), min_size=2, max_size=60)


@given(u=_arrays, Ts=st.floats(1e-3, 10), tau=st.floats(1e-3, 1e18))
@settings(max_examples=60, deadline=None)
def test_the_channel_is_its_recursion_nonnegative_and_quadratic_in_the_units(u, Ts, tau):
    u = np.array(u)
    rec = gb.transient_inputs(gb.Record(u, np.zeros(len(u)), Ts=Ts), taus=[tau])
    z = rec.input(gb.transient_name("u", tau))
    np.testing.assert_allclose(z, _loop(u, Ts, tau), rtol=1e-9, atol=1e-12 * np.max(np.diff(u) ** 2, initial=0.0))
    assert (z >= -1e-12 * max(1.0, np.ptp(u) ** 2)).all()
    # rpm → rad/s: the channel scales by the square of the unit's factor
    c = np.pi / 30
    z2 = gb.transient_inputs(gb.Record(c * u, np.zeros(len(u)), Ts=Ts), taus=[tau]).inputs[:, 1]
    np.testing.assert_allclose(z2, c ** 2 * z, rtol=1e-9, atol=1e-12 * max(1.0, np.ptp(u) ** 2))


@settings(deadline=None)
@given(level=st.floats(-1e4, 1e4), n=st.integers(2, 50), tau=st.floats(1e-2, 1e3))
def test_zero_while_the_input_rests(level, n, tau):
    rec = gb.transient_inputs(gb.Record(np.full(n, level), np.zeros(n), Ts=0.1), taus=[tau])
    assert (rec.inputs[:, 1] == 0).all()


@settings(deadline=None)
@given(h=st.floats(0.1, 100), tau=st.floats(0.05, 100))
def test_a_step_sets_it_off_and_it_decays_by_rho_per_sample(h, tau):
    Ts = 0.05
    u = np.r_[np.zeros(10), np.full(30, h)]
    z = gb.transient_inputs(gb.Record(u, np.zeros(40), Ts=Ts), taus=[tau]).inputs[:, 1]
    rho = np.exp(-Ts / tau)
    assert (z[:10] == 0).all()
    assert z[10] == pytest.approx((1 - rho) * h ** 2)
    np.testing.assert_allclose(z[11:], z[10] * rho ** np.arange(1, 30), rtol=1e-9)


def test_a_dataset_gets_the_channels_in_both_records_and_zero_at_the_static_points():
    data = gb.load_pumping()
    out = gb.transient_inputs(data, taus=(10, 30))
    assert out.input_names == ("u", "u_tau10", "u_tau30")
    assert out.extra["transient_inputs"] == {"u_tau10": ("u", 10.0), "u_tau30": ("u", 30.0)}
    assert out.extra["seed"] == data.extra["seed"] and out.description == data.description
    for part in ("ident", "valid"):
        a, b = getattr(out, part), getattr(data, part)
        np.testing.assert_array_equal(a.input("u"), b.u)
        np.testing.assert_array_equal(a.y, b.y)
        np.testing.assert_array_equal(a.input("u_tau30"), gb.transient_inputs(b, taus=[30]).input("u_tau30"))
    np.testing.assert_array_equal(out.static.ubar[:, 0], data.static.ubar)
    assert (out.static.ubar[:, 1:] == 0).all()
    np.testing.assert_array_equal(out.static.uncertainty, data.static.uncertainty)
    assert out.static.band == data.static.band


def test_terms_in_a_transient_input_leave_the_static_curve_alone():
    """At z̄ = 0 a model's static curve is that of the same model without its z terms."""
    data = gb.transient_inputs(gb.load_pumping(), taus=[30])
    st_ = gb.parse_structure("1 + y(k-1) + u(k-2) + u(k-2)^2 + u_tau30(k-1) + u_tau30(k-1)u(k-2)")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = gb.els(st_, data.ident, max_iter=5).model
    keep = [i for i, t in enumerate(model.structure) if "u_tau30" not in str(t)]
    assert len(keep) == 4 and all(model.theta[i] != 0 for i in range(len(model.theta)))
    theta0 = model.theta.copy()
    theta0[[i for i in range(len(theta0)) if i not in keep]] = 0.0
    pts = data.static.ubar
    np.testing.assert_allclose(model.static_curve(pts), gb.Model(model.structure, theta0).static_curve(pts), rtol=1e-12)
    assert gb.jsf(model, data.static) == pytest.approx(gb.jsf(gb.Model(model.structure, theta0), data.static), rel=1e-12)


def _system(seed, n, tau_true=8.0, Ts=0.1, span=(0.0, 2.0), hold=20):
    """y(k) = 0.7 y(k-1) + 0.5 u(k-1) − 0.1 u(k-1)² + 0.2 − 0.3 z(k-1) + noise, z the transient input of τ = 8 s."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(*span, size=n // hold + 1), hold)[:n]
    z = gb.transient_inputs(gb.Record(u, np.zeros(n), Ts=Ts), taus=[tau_true]).inputs[:, 1]
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.7 * y[k - 1] + 0.5 * u[k - 1] - 0.1 * u[k - 1] ** 2 + 0.2 - 0.3 * z[k - 1]
    return gb.Record(u, y + 0.01 * rng.standard_normal(n), Ts=Ts, name=f"system {seed}")


def test_selection_finds_a_known_transient_effect_that_meets_the_band_and_holds_on_new_data():
    ubar = np.linspace(0.0, 2.0, 7)
    static = gb.StaticPoints(ubar, (0.5 * ubar - 0.1 * ubar ** 2 + 0.2) / 0.3, uncertainty=0.01)
    plain = gb.Dataset(_system(1, 600), _system(2, 400), static)
    taus = (2.0, 8.0, 30.0)
    test = _system(3, 2000)
    rich = gb.transient_inputs(plain, taus=taus)
    cand = gb.Candidates(2, {"u": 2, **{gb.transient_name("u", t): 1 for t in taus}}, degree=2,
                         input_names=rich.input_names)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with_z = gb.select_graybox(cand, rich, test=gb.transient_inputs(test, taus=taus), sizes=[3, 5, 7])
        without = gb.select_graybox(gb.Candidates(2, 2, degree=2), plain, test=test, sizes=[3, 5, 7])
    assert "u_tau8(k-1)" in str(with_z.structure)
    assert with_z.chosen["JSF_test"] <= static.band
    assert with_z.chosen["JS_test"] < 0.2 * without.chosen["JS_test"]


@pytest.mark.parametrize("kw, err, msg", [
    (dict(taus=[]), ValueError, "taus is empty"),
    (dict(taus=[0.0]), ValueError, r"taus \(seconds\) must lie"),
    (dict(taus=[float("nan")]), ValueError, "finite"),
    (dict(taus=[2.0, 2.0]), ValueError, "repeated"),
    (dict(taus=2.0), TypeError, "taus must be a sequence"),
    (dict(taus=[True]), TypeError, "real number"),
    (dict(taus=[1.0], input_names=["v"]), ValueError, "no input named 'v'"),
    (dict(taus=[1.0], input_names=[3]), TypeError, "must name inputs"),
    (dict(taus=[1.0], input_names=[]), ValueError, "at least one input"),
])
def test_bad_options_are_named(kw, err, msg):
    with pytest.raises(err, match=msg):
        gb.transient_inputs(gb.Record(np.arange(5.0), np.zeros(5)), **kw)


def test_bad_data_and_twice_added():
    with pytest.raises(TypeError, match="Record, a Dataset or StaticPoints"):
        gb.transient_inputs(np.arange(5.0), taus=[1.0])
    once = gb.transient_inputs(gb.Record(np.arange(5.0), np.zeros(5)), taus=[1.0])
    with pytest.raises(ValueError, match="added twice"):
        gb.transient_inputs(once, taus=[1.0], input_names=["u"])
    # a model that uses the channel refuses a record without it, by name
    st_ = gb.parse_structure("y(k-1) + u_tau1(k-1)")
    with pytest.raises(ValueError, match=r"u_tau1.*transient_inputs\(record, taus=\[1\], input_names=\['u'\]\)"):
        gb.Model(st_, np.array([0.5, 0.1])).simulate(gb.Record(np.arange(5.0), np.zeros(5)))
    with pytest.raises(ValueError, match=r"transient_inputs\(record, taus=\[2.5\], input_names=\['u'\]\)"):
        gb.simulate(gb.parse_structure("y(k-1) + u(k-1) + u_tau2p5(k-1)"), np.array([0.5, 0.2, 0.1]),
                    np.c_[np.arange(5.0), np.ones(5)], np.zeros(1), input_names=("u", "v"))


def test_names():
    assert gb.transient_name("u", 30) == "u_tau30"
    assert gb.transient_name("speed", 2.5) == "speed_tau2p5"
    with pytest.raises(ValueError, match="tau"):
        gb.transient_name("u", -1.0)


def test_a_held_input_asks_no_static_form():
    """The static form is judged over the inputs the points vary: a transient input (z̄ = 0) changes nothing."""
    from graybox.static._form_check import carried_degree, static_degree, varied_inputs, static_terms

    plain = gb.load_pumping().static
    held = gb.transient_inputs(plain, taus=(10, 30))
    assert varied_inputs(held) == ("u",) and varied_inputs(plain) == ("u",)
    for band in (1e-4, 1e-2, 1.0, 100.0):
        assert static_degree(held, band=band) == static_degree(plain, band=band)
    cand = gb.Candidates(2, {"u": 2, "u_tau10": 1, "u_tau30": 1}, degree=2, input_names=held.input_names)
    assert carried_degree(cand, 2, varied_inputs(held)) == 2
    added = static_terms(gb.Structure(["y(k-1)"]), cand, 2, varied_inputs(held))
    assert {str(t) for t in added} == {"1", "u(k-1)", "u(k-1)^2"}
    # over every input the same completion would also ask for clusters in the transient inputs
    assert any("tau" in str(t) for t in static_terms(gb.Structure(["y(k-1)"]), cand, 2))


def test_every_input_check_gives_the_hint():
    """The model, the free runs and the static surface all check a structure's inputs the same way."""
    st_ = gb.parse_structure("1 + y(k-1) + u(k-1) + u_tau5(k-1)")
    with pytest.raises(ValueError, match=r"not among input_names .*taus=\[5\]"):
        gb.Model(st_, np.array([0.1, 0.5, 0.2, 0.1]), input_names=("u",))
    with pytest.raises(ValueError, match=r"not among the inputs .*taus=\[5\]"):
        gb.static_surface(st_, np.array([0.1, 0.5, 0.2, 0.1]), np.array([[1.0]]), input_names=("u",))


def test_held_inputs_elsewhere():
    """CLS says what to do with points that hold a transient input; a second call adds no transient of a
    transient; a varied input no candidate has lowers the asked form with a warning; a long τ is not lost."""
    from graybox.experiments._select import _static_points

    data = gb.transient_inputs(gb.load_pumping(), taus=[10])
    st_ = gb.parse_structure("1 + y(k-1) + u(k-1) + u(k-1)^2 + u_tau10(k-1)")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ValueError, match=r"hold the input\(s\) \['u_tau10'\].*StaticBand"):
            gb.cls(st_, data.ident, static=data.static)
        banded = gb.cls(st_, data.ident, static=data.static, how="context", constraints=gb.StaticBand())
    assert gb.jsf(banded.model, data.static) <= data.static.band
    assert banded.model.theta[-1] != 0  # the transient term is not switched off
    again = gb.transient_inputs(data, taus=[30])
    assert again.input_names == ("u", "u_tau10", "u_tau30")
    assert set(again.extra["transient_inputs"]) == {"u_tau10", "u_tau30"}
    only_z = gb.Candidates(2, {"u": 0, "u_tau10": 2}, degree=2, input_names=data.input_names)
    with pytest.warns(gb.SelectionWarning, match="carry degree 0"):
        _, form = _static_points(data.static, only_z.process, 0.031, data.ident)
    assert form.degree == 0
    z = gb.transient_inputs(gb.Record(np.r_[0.0, np.ones(5)], np.zeros(6)), taus=[1e17]).inputs[:, 1]
    np.testing.assert_allclose(z[1:], 1e-17, rtol=1e-12)


def test_select_graybox_says_when_the_static_information_lacks_the_channels():
    data = gb.transient_inputs(gb.load_pumping(), taus=[10])
    curve = gb.StaticCurve.fit(gb.load_pumping().static, degree=2)  # a curve in u alone
    cand = gb.Candidates(2, {"u": 2, "u_tau10": 1}, degree=2, input_names=data.input_names)
    with pytest.raises(ValueError, match=r"has inputs \('u', 'u_tau10'\) but .* has inputs \('u',\)"):
        gb.select_graybox(cand, data.ident, curve, validation=data.valid, band=0.031)


def test_the_old_names_of_input_names_still_work_and_say_the_new_one():
    """Structure.inputs, Term.inputs, SurfaceClusterMap.inputs and transient_inputs(inputs=) were renamed
    input_names (the name every other value uses); the old spellings warn and give the same."""
    st = gb.parse_structure(["y(k-1)", "u2(k-1)y(k-1)", "u1(k-2)"])
    with pytest.warns(DeprecationWarning, match=r"Structure.inputs is now Structure.input_names"):
        assert st.inputs == st.input_names == ("u1", "u2")
    with pytest.warns(DeprecationWarning, match=r"Term.inputs is now Term.input_names"):
        assert st.terms[1].inputs == ("u2",)
    cm = gb.surface_cluster_map(st)
    with pytest.warns(DeprecationWarning, match=r"SurfaceClusterMap.inputs is now"):
        assert cm.inputs == cm.input_names == ("u1", "u2")
    rec = gb.Record(np.arange(12.0).reshape(6, 2), np.zeros(6), input_names=("a", "b"))
    with pytest.warns(DeprecationWarning, match=r"transient_inputs\(inputs=\) is now transient_inputs\(input_names=\)"):
        old = gb.transient_inputs(rec, taus=[1.0], inputs=["b"])
    new = gb.transient_inputs(rec, taus=[1.0], input_names=["b"])
    assert old.input_names == new.input_names and np.array_equal(old.u, new.u)
    with pytest.raises(TypeError, match="give input_names= only"):
        gb.transient_inputs(rec, taus=[1.0], input_names=["b"], inputs=["b"])


def test_local_model_on_data_lacking_a_transient_input_says_how_to_add_it():
    # local_model(M, 1.5, data=rec0) said the bare "no input named 'u_tau3'" where Model.simulate says how to add it
    rng = np.random.default_rng(0)
    rec0 = gb.Record(np.repeat(rng.uniform(0, 2, 10), 10), np.zeros(100), Ts=1.0)
    model = gb.Model(gb.Structure(["y(k-1)", "u(k-1)", "u_tau3(k-1)"]), np.array([0.5, 1.0, 0.2]), Ts=1.0)
    with pytest.raises(ValueError) as simulated:
        model.simulate(rec0)
    with pytest.raises(ValueError) as local:
        gb.local_model(model, 1.5, data=rec0)
    assert "transient_inputs(record, taus=[3], input_names=['u'])" in str(local.value)
    assert str(local.value) == str(simulated.value)
    lm = gb.local_model(model, 1.5, data=gb.transient_inputs(rec0, (3,)))
    assert lm is not None


def test_static_points_lacking_a_transient_input_are_told_how_to_add_it():
    # jsf(M, points) and local_model(M, ū, data=points) said only "(no 'u_tau3')"; transient_inputs adds z̄ = 0 columns
    model = gb.Model(gb.Structure(["y(k-1)", "u(k-1)", "u_tau3(k-1)"]), np.array([0.5, 1.0, 0.2]), Ts=1.0)
    points = gb.StaticPoints(np.array([0.5, 1.0, 1.5]), np.array([1.1, 2.0, 2.9]))
    hint = "transient_inputs(static, taus=[3], input_names=['u'])"
    for call in (lambda: gb.jsf(model, points), lambda: gb.local_model(model, 1.5, data=points)):
        with pytest.raises(ValueError) as err:
            call()
        assert hint in str(err.value)
    # as told: the static curve at z̄ = 0 is ȳ = ū / (1 − 0.5) = 2 ū, so J_SF = mean((ȳ − 2 ū)²)
    want = np.mean((np.array([1.1, 2.0, 2.9]) - 2.0 * np.array([0.5, 1.0, 1.5])) ** 2)
    assert gb.jsf(model, gb.transient_inputs(points, (3,))) == pytest.approx(want)


def test_several_records_are_told_to_be_given_one_at_a_time():
    """A list of records (several experiments) was refused as 'got list', naming no way on (mend60g)."""
    rec = gb.Record(np.arange(10.0) % 3, np.arange(10.0))
    with pytest.raises(TypeError, match=r"got list: it takes one; call it once for each, "
                                        r"\[graybox\.transient_inputs\(r, taus=\.\.\.\) for r in records\]"):
        gb.transient_inputs([rec, rec], taus=[2.0])
    each = [gb.transient_inputs(r, taus=[2.0]) for r in (rec, rec)]
    assert all(r.input_names == ("u", "u_tau2") for r in each)


def test_inputs_in_units_of_their_own_get_transient_inputs_in_their_squares():
    # a record, points or data set whose inputs have units of their own (l/min, °C) raised 'units give 2 input units
    # for 4 input(s)': the new channels had no unit; each is now its input's unit squared, as documented
    each = (("l/min", "°C"), "m")
    rng = np.random.default_rng(0)
    u = np.column_stack([np.repeat(rng.uniform(0, 10, 20), 10), np.repeat(rng.uniform(20, 60, 20), 10)])
    rec = gb.Record(u, rng.standard_normal(200), Ts=2.0, units=each, input_names=("q", "T"))
    pts = gb.StaticPoints(np.array([[2.0, 30], [5, 40], [8, 50]]), np.array([1.0, 2, 3]), input_names=("q", "T"),
                          units=(("", "°C"), "m"))
    ext = gb.transient_inputs(rec, [5.0])
    assert ext.input_names == ("q", "T", "q_tau5", "T_tau5")
    assert ext.units == (("l/min", "°C", "(l/min)²", "°C²"), "m")
    assert gb.transient_inputs(pts, [5.0]).units == (("", "°C", "", "°C²"), "m")
    data = gb.transient_inputs(gb.Dataset(rec, rec.slice(100, 200), pts), [5.0])
    assert data.units == (("l/min", "°C", "(l/min)²", "°C²"), "m")
    # one unit for every input is kept as it was (models saved with it hold their transient inputs in it)
    assert gb.transient_inputs(gb.Record(u, rec.y, units=("rpm", "mlc"), input_names=("q", "T")), [5.0]).units == \
        ("rpm", "mlc")
