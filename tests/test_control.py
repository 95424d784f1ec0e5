"""From model to controller (issue 23): local linear models, python-control systems, closed loop."""

from __future__ import annotations

import dataclasses
import re
import sys

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st

import graybox as gb
from graybox import Model, reference
from graybox.control import _local as local_module
from graybox.control._local import jacobian_rows
from graybox.datasets.pumping import PumpingPlant
from graybox.static._analysis import _linear_coefficients

ct = pytest.importorskip("control")

#: A non-rational single-input model (y² terms), stable near ū = 1 … 3.
NONRATIONAL = Model(["1", "y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)y(k-1)", "y(k-1)^2", "u(k-3)^2"],
                    [0.1, 0.5, 0.2, 0.3, 0.05, -0.04, 0.01], name="nonrational")
#: Two inputs, products across inputs and with y.
TWO_INPUTS = Model(["1", "y(k-1)", "y(k-2)", "u1(k-1)", "u2(k-2)", "u1(k-1)u2(k-1)", "y(k-1)u1(k-2)", "y(k-2)^2"],
                   [0.2, 0.4, 0.1, 0.3, -0.2, 0.05, 0.04, -0.02], name="two", input_names=("u1", "u2"))


def one_step(model: Model, ylags: np.ndarray, ulags: np.ndarray) -> float:
    """y(L) of the model's own compiled free run from y(L-1) … y(0) = ylags and u(L-1) … u(0) = ulags (L, m)."""
    L = ylags.size
    u = np.vstack([ulags[::-1], ulags[:1]])  # u(0) … u(L-1), then u(L) (unused by y(L))
    y0 = ylags[::-1]
    if model.n_inputs == 1:
        return float(model.simulate(u[:, 0], y0)[L])
    return float(model.simulate(u, y0)[L])


def fd_jacobian(model: Model, ybar: float, ubar: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Central differences of the one-step map at the steady state, in every lagged output and input."""
    L = model.max_lag
    m = model.n_inputs
    y = np.full(L, ybar)
    U = np.tile(np.asarray(ubar, float), (L, 1))
    a = np.zeros(L)
    b = np.zeros((m, L))
    for l in range(L):
        h = 1e-6 * max(abs(ybar), 1.0)
        e = np.zeros(L)
        e[l] = h
        a[l] = (one_step(model, y + e, U) - one_step(model, y - e, U)) / (2 * h)
        for i in range(m):
            hu = 1e-6 * max(abs(ubar[i]), 1.0)
            E = np.zeros((L, m))
            E[l, i] = hu
            b[i, l] = (one_step(model, y, U + E) - one_step(model, y, U - E)) / (2 * hu)
    return a, b


def padded(x: np.ndarray, n: int, axis: int = -1) -> np.ndarray:
    pad = [(0, 0)] * x.ndim
    pad[axis] = (0, n - x.shape[axis])
    return np.pad(x, pad)


@pytest.mark.parametrize("model,ubar", [
    (reference.paper_model(15), [1200.0]),
    (reference.paper_model(17), [1000.0]),
    (NONRATIONAL, [2.0]),
    (TWO_INPUTS, [1.0, 0.5]),
])
def test_linearisation_equals_finite_differences_of_the_one_step_map(model, ubar):
    lm = gb.local_model(model, ubar if model.n_inputs > 1 else ubar[0], Ts=0.05)
    assert lm.reached
    a_fd, b_fd = fd_jacobian(model, lm.ybar, np.array(ubar))
    L = model.max_lag
    np.testing.assert_allclose(padded(lm.a, L), a_fd, rtol=1e-5, atol=1e-7 * np.abs(a_fd).max())
    np.testing.assert_allclose(padded(lm.b, L), b_fd, rtol=1e-5, atol=1e-7 * np.abs(b_fd).max())


@settings(deadline=None, max_examples=60)  # the first example compiles the static kernels
@given(theta=st.lists(st.floats(-0.6, 0.6), min_size=7, max_size=7), u=st.floats(0.2, 3.0))
def test_dc_gain_is_the_static_gain_and_poles_are_the_stability_tests(theta, u):
    m = NONRATIONAL.with_theta(np.array(theta))
    eqs = m.equilibria(u)
    stable = [e for e in eqs if e.stable]
    assume(len(stable) == 1)
    lm = gb.local_model(m, u, Ts=1.0)
    assert lm.reached and lm.ybar == pytest.approx(stable[0].ybar, rel=1e-9, abs=1e-12)
    np.testing.assert_allclose(lm.dc_gain, m.static_gain([u]), rtol=1e-8, atol=1e-12)
    # the stability test's own linearisation, its verdict and spectral radius
    np.testing.assert_allclose(lm.a, _linear_coefficients(m.structure, m.theta, lm.ybar, u), rtol=1e-12, atol=1e-15)
    assert lm.stable == stable[0].stable
    assert lm.spectral_radius == pytest.approx(stable[0].spectral_radius, rel=1e-9, abs=1e-12)


def test_two_input_dc_gain_is_the_static_surface_gradient():
    pts = np.array([[1.0, 0.5], [0.6, 1.2], [1.5, 1.5]])
    oc = gb.operating_curve(TWO_INPUTS, pts, Ts=0.1)
    np.testing.assert_allclose(oc.gain, TWO_INPUTS.static_gain(pts), rtol=1e-10)
    np.testing.assert_allclose(oc.ybar, TWO_INPUTS.static_curve(pts), rtol=1e-12)
    for lm, e in zip(oc.local_models, pts):
        eq = [q for q in TWO_INPUTS.equilibria(e) if q.stable][0]
        assert lm.spectral_radius == pytest.approx(eq.spectral_radius, rel=1e-9)


def test_jacobian_rows_of_many_draws_equal_one_at_a_time():
    rng = np.random.default_rng(0)
    th = NONRATIONAL.theta[None, :] * (1 + 0.05 * rng.standard_normal((5, 7)))
    yb, ub = rng.uniform(1, 2, 5), rng.uniform(1, 3, (5, 1))
    a, b = jacobian_rows(NONRATIONAL.structure, ("u",), th, yb, ub)
    for k in range(5):
        np.testing.assert_allclose(a[k], _linear_coefficients(NONRATIONAL.structure, th[k], yb[k], ub[k, 0]))


def test_time_constant_damping_and_settling_of_a_first_order_model():
    p, g, Ts = 0.9, 2.0, 0.05
    m = Model(["y(k-1)", "u(k-1)"], [p, g * (1 - p)])
    lm = gb.local_model(m, 3.0, Ts=Ts)
    assert lm.time_constant == pytest.approx(-Ts / np.log(p))
    assert lm.damping == pytest.approx(1.0)
    # the step response 1 - p^k stays within 2 % from the first k with p^k <= 0.02
    k = int(np.ceil(np.log(0.02) / np.log(p)))
    assert lm.settling_time() == pytest.approx(k * Ts)
    np.testing.assert_allclose(lm.step(20), g * (1 - p ** np.arange(20)))
    # an oscillating pair: the damping of its continuous equivalent
    r, phi = 0.8, 0.5
    m2 = Model(["y(k-1)", "y(k-2)", "u(k-1)"], [2 * r * np.cos(phi), -r * r, 1.0])
    lm2 = gb.local_model(m2, 1.0, Ts=Ts)
    s = np.log(r) + 1j * phi
    assert lm2.damping == pytest.approx(-s.real / abs(s))
    assert np.angle(lm2.dominant_pole) == pytest.approx(phi)


@pytest.mark.parametrize("model,u", [(reference.paper_model(15), 1200.0), (NONRATIONAL, 2.0)])
def test_small_step_of_the_nonlinear_model_matches_the_local_model_to_first_order(model, u):
    lm = gb.local_model(model, u, Ts=0.05)
    L, n = model.max_lag, 200
    errors = []
    for delta in (0.02 * u, 0.005 * u):
        uu = np.r_[np.full(L, u), np.full(n, u + delta)]
        y = model.simulate(uu, np.full(L, lm.ybar))[L:]
        dy = (y - lm.ybar) / delta
        errors.append(np.max(np.abs(dy - lm.step(n))))
    # first order: the error per unit step shrinks with the step, here 4-fold
    assert errors[1] < 0.3 * errors[0]
    assert errors[1] < 0.05 * np.max(np.abs(lm.step(n)))


def test_local_model_as_python_control_systems():
    lm = gb.local_model(reference.paper_model(15), 1200.0, Ts=0.05)
    ss, tf = lm.to_statespace(), lm.to_transfer_function()
    assert ss.dt == 0.05 and tf.dt == 0.05
    assert ss.input_labels == ["u"] and ss.output_labels == ["y"]
    np.testing.assert_allclose(ct.dcgain(ss), lm.dc_gain[0], rtol=1e-9)
    np.testing.assert_allclose(ct.dcgain(tf), lm.dc_gain[0], rtol=1e-9)
    # the state-space poles: the local model's, plus poles at 0 for input lags beyond the output lags
    pss = ss.poles()
    for p in lm.poles:
        assert np.min(np.abs(pss - p)) < 1e-8
    n = 60
    t = 0.05 * np.arange(n)
    np.testing.assert_allclose(ct.step_response(ss, t).outputs, lm.step(n), atol=1e-12)
    np.testing.assert_allclose(ct.step_response(tf, t).outputs, lm.step(n), atol=1e-10)
    w = np.array([0.1, 1.0, 10.0])
    np.testing.assert_allclose(ct.frequency_response(tf, w).complex, lm.frequency_response(w), rtol=1e-9)


def test_two_input_local_model_has_two_system_inputs():
    lm = gb.local_model(TWO_INPUTS, [1.0, 0.5], Ts=0.1)
    ss = lm.to_statespace()
    assert ss.ninputs == 2 and ss.input_labels == ["u1", "u2"]
    np.testing.assert_allclose(np.ravel(ct.dcgain(ss)), lm.dc_gain, rtol=1e-9)
    tf = lm.to_transfer_function()
    np.testing.assert_allclose(np.ravel(ct.dcgain(tf)), lm.dc_gain, rtol=1e-9)


def test_nonlinear_system_free_run_equals_simulate_one_input():
    data = gb.load_pumping()
    for model in (reference.paper_model(15), reference.paper_model(17)):
        rec = data.valid
        L = model.max_lag
        sysm = gb.narx_iosystem(model, Ts=rec.Ts)
        x0 = gb.narx_initial_state(model, rec)
        assert sysm.nstates == x0.size and sysm.state_labels == gb.narx_state_names(model)
        r = ct.input_output_response(sysm, rec.Ts * np.arange(len(rec) - L), rec.u[L:], x0)
        y = model.simulate(rec)
        np.testing.assert_allclose(r.outputs, y[L:], rtol=0, atol=1e-12)


def test_nonlinear_system_free_run_equals_simulate_two_inputs():
    data = gb.load_pumping_miso()
    names = data.input_names
    sel = gb.frols(gb.Candidates(3, 3, input_names=names, degree=2, max_y_power=1), data, n_terms=10, include=["1"])
    model = gb.els(sel, data).model
    assert set(model.structure.input_names) == set(names)
    rec = data.valid
    L = model.max_lag
    sysm = gb.narx_iosystem(model, Ts=rec.Ts)
    assert sysm.ninputs == 2 and sysm.input_labels == list(names)
    r = ct.input_output_response(sysm, rec.Ts * np.arange(len(rec) - L), rec.inputs[L:].T,
                                 gb.narx_initial_state(model, rec))
    np.testing.assert_allclose(r.outputs[0], model.simulate(rec)[L:], rtol=0, atol=1e-12)


def test_closed_loop_with_the_model_reaches_the_reference():
    model = reference.paper_model(15)
    Ts, u0 = 0.05, 1000.0
    y0 = float(model.static_curve([u0])[0])
    lm = gb.local_model(model, u0, Ts=Ts)
    g, tau = lm.dc_gain[0], lm.time_constant
    kp, ki = 0.5 / g, 0.5 / (g * tau)  # a slow PI: integral action brings the error to zero
    pi = ct.ss([[1.0]], [[ki * Ts]], [[1.0]], [[kp + ki * Ts]], dt=Ts, inputs="e", outputs="u", name="pi")
    plant = gb.narx_iosystem(model, Ts=Ts, name="plant")
    loop = ct.interconnect([plant, pi, ct.summing_junction(["r", "-y"], "e", dt=Ts)], inputs="r", outputs=["y", "u"])
    x0 = np.r_[gb.narx_steady_state(model, u0, y0), u0]  # the PI's integrator holds u0
    n = 600
    r = ct.input_output_response(loop, Ts * np.arange(n), np.full(n, y0 + 1.0), x0)
    assert abs(r.outputs[0, -1] - (y0 + 1.0)) < 1e-3
    # the model's static curve there: the controller settles on the input that reaches it
    assert float(model.static_curve([r.outputs[1, -1]])[0]) == pytest.approx(y0 + 1.0, abs=1e-3)


# -- the bundled plant's closed-loop interface -----------------------------------------------------
def test_plant_closed_loop_with_an_open_loop_controller_is_simulate():
    plant = PumpingPlant()
    u = np.repeat([900.0, 1100.0, 1000.0], 50)
    a = plant.simulate(u, seed=3)
    b = plant.closed_loop(lambda k, y: u[k], u.size, u0=u[0], seed=3)
    for f in ("u", "y", "pressure", "speed", "flow", "surge", "air_loss"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))


def test_plant_closed_loop_pi_tracks_and_bad_references_are_named():
    plant = PumpingPlant()
    y_ref = float(plant.static_pressure(1200.0))
    state = {"i": 1000.0}

    def pi(k, y):
        e = y_ref - y
        u = state["i"] + 20.0 * e
        state["i"] += 2.0 * e
        return u

    run = plant.closed_loop(pi, 800, u0=1000.0, noise=False, process_noise=False)
    assert run.pressure[-1] == pytest.approx(y_ref, abs=1e-3)
    assert run.u[-1] == pytest.approx(1200.0, abs=0.5)
    with pytest.raises(ValueError, match="sample 3"):
        plant.closed_loop(lambda k, y: 1000.0 if k < 3 else 5000.0, 10, u0=1000.0, noise=False, process_noise=False)
    with pytest.raises(ValueError, match="pass seed"):
        plant.closed_loop(lambda k, y: 1000.0, 10, u0=1000.0)


def test_plant_linearisation_gain_is_the_static_slope_and_its_time_constant_falls():
    plant = PumpingPlant()
    taus = []
    for s in (800.0, 1200.0, 1600.0):
        A, B, C = plant.linearize(s)
        gain = (C @ np.linalg.solve(np.eye(4) - A, B))[0, 0]
        k, a, b = plant.static_coefficients
        assert gain == pytest.approx(2 * b * s + a, rel=1e-6)
        taus.append(plant.local_time_constant(s))
    assert taus[0] > taus[1] > taus[2] > 0  # the paper's "variable time-constant"


# -- along the static curve -------------------------------------------------------------------------
def test_operating_curve_band_from_the_parameter_covariance():
    data = gb.load_pumping()
    model = reference.paper_model(15)
    fit = gb.els(model.structure, data, noise=2).model
    unc = gb.ls_uncertainty(fit, data)
    u = np.linspace(800, 1600, 5)
    oc = gb.operating_curve(fit, u, data=data, uncertainty=unc, n_samples=200, seed=1)
    assert oc.has_band and oc.level == unc.level
    assert np.all(oc.gain_low <= oc.gain) and np.all(oc.gain <= oc.gain_high)
    assert np.all(oc.time_constant_low <= oc.time_constant) and np.all(oc.time_constant <= oc.time_constant_high)
    assert np.all(oc.gain_high > oc.gain_low)
    frame = oc.to_frame()
    assert list(frame.index) == list(u) and "time constant" in frame
    again = gb.operating_curve(fit, u, data=data, uncertainty=unc, n_samples=200, seed=1)
    np.testing.assert_array_equal(again.time_constant_high, oc.time_constant_high)


# -- bad input -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("terms,theta", [
    (["y(k-1)", "y(k-2)", "u(k-1)"], [1.0, -1.0, 0.1]),  # z² − z + 1: e^{±iπ/3}
    (["y(k-1)", "y(k-2)", "u(k-1)"], [2 * np.cos(0.3), -1.0, 0.1]),  # z² − 2cos(0.3) z + 1: e^{±0.3i}
    (["y(k-5)", "u(k-1)"], [-1.0, 0.1]),  # z⁵ + 1: the fifth roots of −1
    (["y(k-1)", "y(k-2)", "y(k-3)", "u(k-1)"], [-1.0, -1.0, -1.0, 0.1]),  # (z + 1)(z² + 1): −1 and ±i
])
def test_poles_on_the_unit_circle_never_decay_whatever_rounding_made_of_their_modulus(terms, theta):
    # every pole has modulus 1 (the polynomial's roots by hand), the one stability test says not stable, yet the
    # eigensolver's moduli came out 1 − 1e-16 for some: τ = −Ts / ln|p| was 9.0e15 s (a number for a mode that never
    # decays) and ζ 1e-16, or ζ NaN ("outside the circle") where they came out 1 + 2e-16; the dominant pole's modulus
    # was also taken by Python's abs where spectral_radius takes numpy's (1.0 beside τ = 9.0e15 s)
    model = Model(terms, theta, Ts=0.5)
    lm = gb.local_model(model, 1.0)
    assert lm.exists and not lm.stable
    np.testing.assert_allclose(np.abs(lm.poles), 1.0, rtol=1e-12)
    assert lm.time_constant == np.inf and lm.damping == 0.0 and lm.settling_time() == np.inf
    assert abs(lm.dominant_pole) == pytest.approx(1.0, rel=1e-12)
    # the spectral radius on the verdict's side, as the static analysis's Equilibrium reports it (it said 1 − 1e-16)
    eq, = model.equilibria(1.0)
    assert not eq.stable and lm.spectral_radius >= 1.0 and eq.spectral_radius >= 1.0
    oc = gb.operating_curve(model, [1.0])
    assert oc.time_constant[0] == np.inf and oc.damping[0] == 0.0


def test_the_settling_time_of_an_equilibrium_that_is_not_stable_runs_no_step_response(monkeypatch):
    # z² − 2cos(0.3)z + 1: its roots' moduli came out 1 − 1e-16, and settling_time ran its step response over the
    # longest window (4e7 samples, 3 s, in operating_curve once per such point) before saying inf
    lm = gb.local_model(Model(["y(k-1)", "y(k-2)", "u(k-1)"], [2 * np.cos(0.3), -1.0, 0.1], Ts=0.5), 1.0)
    assert np.abs(lm.poles).max() < 1.0 and not lm.stable  # as rounding made them: the test below needs both

    def no_run(*args, **kwargs):
        raise AssertionError("a step response was run")

    monkeypatch.setattr(local_module, "_step_error", no_run)
    assert lm.settling_time() == np.inf


@pytest.mark.parametrize("ubar,y0", [(0.7, 1e4), (1.4, 100.0), (2.3, 1e6)])
def test_a_continuum_of_equilibria_linearises_with_its_pole_at_one_whatever_rounding_made_of_its_coefficients(ubar, y0):
    # y(k) = y(k-1) + (0.1 u(k-1) − c) y(k-1)² with c = 0.1 ū: at ū every ȳ is an equilibrium (the continuum the
    # status names), so 1 − Σa = −∂(F − ȳ)/∂ȳ = 0 there, by hand. Rounding left 0.1·0.7 − 0.07 = −7e-18 and the
    # linearisation at y0 = 1e4 had Σa = 1 − 2e-13: stable, τ = 4.4e12 s, gain 4.4e19, under the status that says the
    # output stays where it starts
    model = Model(["y(k-1)", "y(k-1)^2u(k-1)", "y(k-1)^2"], [1.0, 0.1, -round(0.1 * ubar, 6)], Ts=1.0)
    lm = gb.local_model(model, ubar, y0=y0)
    assert lm.status == "continuum of equilibria" and lm.ybar == y0
    assert lm.a.sum() == 1.0 and not lm.stable and lm.spectral_radius == 1.0
    assert lm.time_constant == np.inf and lm.damping == 0.0 and lm.settling_time() == np.inf
    assert np.all(np.isinf(lm.dc_gain))
    oc = gb.operating_curve(model, [ubar], y0=[y0])
    assert oc.time_constant[0] == np.inf and np.isinf(oc.gain[0])


def test_operating_point_outside_the_data_warns():
    data = gb.load_pumping()
    with pytest.warns(gb.StaticRangeWarning, match="2000") as record:
        gb.local_model(reference.paper_model(15), 2000.0, data=data)
    assert record[0].filename == __file__  # attributed to the caller, not to graybox's internals
    with pytest.warns(gb.StaticRangeWarning, match=r"\[700.0, 2000.0\]"):
        gb.operating_curve(reference.paper_model(15), [700.0, 1000.0, 2000.0], data=data)


def test_no_stable_equilibrium_is_said_not_nan():
    unstable = Model(["y(k-1)", "u(k-1)"], [1.2, 1.0])
    lm = gb.local_model(unstable, 1.0, Ts=1.0)
    assert lm.status == "no stable equilibrium" and not lm.reached and "no stable" in lm.reason
    assert lm.exists and np.all(np.isfinite(lm.poles)) and lm.poles[0] == pytest.approx(1.2)
    assert not lm.stable and lm.time_constant == np.inf and lm.settling_time() == np.inf
    none = Model(["y(k-1)", "1"], [1.0, 0.5])  # ȳ = ȳ + 0.5: no equilibrium
    lm2 = gb.local_model(none, 1.0, Ts=1.0)
    assert lm2.status == "no equilibrium" and not lm2.exists
    with pytest.raises(ValueError, match="no equilibrium"):
        lm2.poles
    with pytest.raises(ValueError, match="no equilibrium"):
        lm2.to_statespace()
    oc = gb.operating_curve(none, [1.0, 2.0], Ts=1.0)
    assert oc.status == ("no equilibrium", "no equilibrium") and np.all(np.isnan(oc.gain))


def test_equilibrium_not_reached_from_y0_is_said():
    # y(k) = 1.5 y(k-1) - 0.5 y(k-1)^2 + 0.1 u: stable root near 1 (+ u), unstable root near 0
    m = Model(["y(k-1)", "y(k-1)^2", "u(k-1)"], [1.5, -0.5, 0.1])
    eqs = m.equilibria(0.0)
    assert [e.stable for e in eqs] == [False, True]
    lm = gb.local_model(m, 0.0, Ts=1.0, y0=-0.5)  # below the unstable root: the run diverges
    assert lm.status == "diverged" and not lm.reached
    assert lm.ybar == pytest.approx(eqs[0].ybar)  # linearised at the equilibrium nearest y0
    assert gb.local_model(m, 0.0, Ts=1.0, y0=0.5).ybar == pytest.approx(eqs[1].ybar)


def test_python_control_missing_names_the_extra(monkeypatch):
    lm = gb.local_model(reference.paper_model(15), 1200.0, Ts=0.05)
    monkeypatch.setitem(sys.modules, "control", None)
    for call in (lm.to_statespace, lm.to_transfer_function, lambda: gb.narx_iosystem(reference.paper_model(15), Ts=0.05)):
        with pytest.raises(ImportError, match=r"pip install graybox\[control\]"):
            call()


def test_python_control_too_old_names_the_version_it_needs(monkeypatch):
    # python-control 0.9 (still a distribution's package) has no nlsys: narx_iosystem failed with "module 'control'
    # has no attribute 'nlsys'", naming neither the version found nor the one needed (hunt59a)
    import types

    lm = gb.local_model(reference.paper_model(15), 1200.0, Ts=0.05)
    old = types.ModuleType("control")
    old.__version__ = "0.9.4"
    old.ss, old.tf = ct.ss, ct.tf  # 0.9 has these, not nlsys
    monkeypatch.setitem(sys.modules, "control", old)
    for call in (lm.to_statespace, lm.to_transfer_function, lambda: gb.narx_iosystem(reference.paper_model(15))):
        with pytest.raises(ImportError, match=r"python-control 0\.10 or later.*0\.9\.4.*pip install"):
            call()


def test_neural_model_gets_a_clear_error():
    net = gb.NeuralModel(np.zeros((2, 2)), np.zeros(2), np.zeros(2), 0.0, ny=1, nu=1)
    for fn in (lambda: gb.local_model(net, 1.0, Ts=1.0), lambda: gb.operating_curve(net, [1.0], Ts=1.0),
               lambda: gb.narx_iosystem(net, Ts=1.0)):
        with pytest.raises(TypeError, match="polynomial NARX Model, got NeuralModel"):
            fn()


def test_the_papers_models_carry_its_period_so_their_time_constants_come_in_seconds():
    # the paper samples every 50 ms (Section II-B): its models' local models need no Ts= and give seconds
    for eq in (15, 17):
        m = reference.paper_model(eq)
        assert m.Ts == reference.TS == 0.05
        lm = gb.local_model(m, 1200.0)
        by_hand = gb.local_model(dataclasses.replace(m, Ts=None), 1200.0, Ts=0.05)
        assert lm.Ts == 0.05 and lm.time_constant == by_hand.time_constant
        # the dominant pole's time constant: −Ts / ln|p|, in seconds
        assert lm.time_constant == pytest.approx(-0.05 / np.log(np.abs(lm.poles).max()), rel=1e-12)
    # a record sampled at another period is refused rather than simulated at the wrong one
    with pytest.raises(ValueError, match="every 0.05 s"):
        reference.paper_model(15).simulate(gb.Record(np.full(20, 1000.0), np.full(20, 5.0)))


def test_arguments_are_checked():
    m = reference.paper_model(15)
    with pytest.raises(ValueError, match="Ts"):  # a model of unknown period
        gb.local_model(dataclasses.replace(m, Ts=None), 1000.0)
    with pytest.raises(ValueError, match="ubar"):
        gb.local_model(m, [1000.0, 1100.0], Ts=0.05)
    with pytest.raises(ValueError, match="Ts"):
        gb.narx_iosystem(m, Ts=-1.0)
    with pytest.raises(ValueError, match="start"):
        gb.narx_initial_state(m, gb.load_pumping().valid, start=2)
    with pytest.raises(TypeError, match="uncertainty must be a ParameterUncertainty"):  # a wrong type (hunt37b)
        gb.operating_curve(m, [1000.0], Ts=0.05, uncertainty=object())


def test_plots_of_local_models():
    from graybox import plots

    oc = gb.operating_curve(reference.paper_model(15), np.linspace(800, 1600, 3), Ts=0.05)
    fig = plots.plot_local_models(oc)
    assert len(fig.axes) == 3 and len(fig.axes[0].lines) == 3
    # the legend's operating points in the input's unit where the model says it (hunt60e: "ū = 20", no unit)
    rpm = gb.operating_curve(gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0], units=("rpm", "mlc")), [800.0], Ts=0.05)
    assert [t.get_label() for t in plots.plot_local_models(rpm).axes[0].lines] == ["ū = 800 rpm"]
    fig2 = plots.plot_operating_curve(oc, reference=([800.0, 1600.0], [0.5, 0.3]))
    assert len(fig2.axes) == 3 and len(fig2.axes[1].lines) == 2


def test_nonlinear_system_with_its_noise_input_reproduces_the_record():
    data = gb.load_pumping()
    sel = gb.frols(gb.Candidates(ny=6, nu=6, ne=2, degree=2, max_y_power=1), data, n_terms=17, include=["1"])
    model = gb.els(sel, data).model
    assert len(model.noise_structure) == 2
    rec = data.valid
    L = model.max_lag
    xi = gb.one_step_residuals(model, rec)[0]  # ξ(k), k = L … N−1 (0 before L)
    sysm = gb.narx_iosystem(model, Ts=rec.Ts, noise=True)
    assert sysm.input_labels == ["u", "noise"] and sysm.state_labels[-2:] == ["noise[k-1]", "noise[k-2]"]
    x0 = gb.narx_initial_state(model, rec, noise=True)
    r = ct.input_output_response(sysm, rec.Ts * np.arange(len(rec) - L), np.vstack([rec.u[L:], xi]), x0)
    np.testing.assert_allclose(r.outputs[0], rec.y[L:], rtol=0, atol=1e-9)
    # without the noise input it is the free run
    assert gb.narx_iosystem(model, Ts=rec.Ts).ninputs == 1
    bad = Model(["y(k-1)", "u(k-1)"], [0.5, 1.0], noise_structure=["e(k-1)y(k-1)"], noise_theta=[0.1])
    with pytest.raises(ValueError, match="linear MA part"):
        gb.narx_iosystem(bad, Ts=1.0, noise=True)


def test_results_that_carry_a_model_are_accepted_as_it():
    """local_model and the systems take a result with a .model (ELSResult, Decision, …) as that model."""
    p, g, Ts = 0.9, 2.0, 0.05
    m = Model(["y(k-1)", "u(k-1)"], [p, g * (1 - p)])

    class Carrier:  # what every graybox result is to these functions: something with a .model
        model = m

    a, b = gb.local_model(Carrier(), 3.0, Ts=Ts), gb.local_model(m, 3.0, Ts=Ts)
    np.testing.assert_array_equal(a.a, b.a)
    assert a.dc_gain == b.dc_gain
    with pytest.raises(TypeError, match="needs a polynomial NARX Model, got str"):
        gb.local_model("model", 3.0, Ts=Ts)


def test_an_integrator_has_no_local_model_and_the_reason_names_the_vanishing_denominator():
    # y(k) = y(k-1) + 0.5 u(k-1): at ū = 0 every output is an equilibrium, at ū ≠ 0 none; the reason
    # said "the static equation has no real root" (its denominator 1 − Σy is what vanishes)
    m = gb.Model(gb.Structure(["y(k-1)", "u(k-1)"]), [1.0, 0.5], Ts=0.1)
    lm = gb.local_model(m, 2.0)
    assert not lm.exists and lm.status == "no equilibrium"
    assert re.search("denominator.*vanishes", lm.reason)
    with pytest.raises(ValueError, match="no local model: .*denominator.*vanishes"):
        lm.poles
    # at ū = 0 every output is one (mend37: it said "no equilibrium" there too)
    lm = gb.local_model(m, 0.0)
    assert not lm.exists and lm.status == "continuum of equilibria"
    with pytest.raises(ValueError, match="no local model: .*continuum of equilibria"):
        lm.poles


def test_local_model_refuses_frequencies_above_nyquist_and_says_which_inputs_it_has(tmp_path):
    # above π/Ts e^{jωTs} comes round again: the "response" there was an alias, given without a word; step(input=1)
    # of a one-input model said only "input must be an integer <= 0"
    lm = gb.local_model(gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0]), 1.0, Ts=0.1)
    nyq = np.pi / 0.1
    assert lm.frequency_response(np.logspace(0, np.log10(nyq), 7)).shape == (7,)  # up to Nyquist, rounding included
    np.testing.assert_allclose(lm.frequency_response([-1.0]), np.conj(lm.frequency_response([1.0])))
    with pytest.raises(ValueError, match="Nyquist frequency π/Ts = 31.4159 rad/s"):
        lm.frequency_response([1.0, 2 * nyq])
    with pytest.raises(ValueError, match=r"input 1 is out of range: the local model has 1 input\(s\), 0 \(u\)"):
        lm.step(10, input=1)
    # a reached local model has no reason: a hand-edited one with a reason is refused
    gb.save(lm, tmp_path / "lm.json")
    import json
    doc = json.loads((tmp_path / "lm.json").read_text())
    doc["object"]["reason"] = "ū = 1: did not settle"
    (tmp_path / "lm.json").write_text(json.dumps(doc))
    with pytest.raises(gb.GrayboxFileError, match="status 'reached' has no reason"):
        gb.load(tmp_path / "lm.json")


def test_local_models_of_a_pole_near_one_are_drawn_over_a_bounded_number_of_samples():
    """τ ≈ 5e5 s at Ts = 0.05 s asked six τ of samples by default (6e7: out of memory); the default is now cut at
    MAX_STEP_SAMPLES samples, and a duration asking for absurdly many is refused by name."""
    from graybox import plots
    from graybox.plots._control import MAX_STEP_SAMPLES

    m = gb.Model(gb.parse_structure(["y(k-1)", "u(k-1)", "1"]), np.array([1 - 1e-7, 1e-7, 0.0]), Ts=0.05)
    fig = plots.plot_local_models(gb.operating_curve(m, [1.0, 2.0]))
    xs = [line.get_xdata() for line in fig.axes[0].get_lines()]
    assert xs and all(len(x) == MAX_STEP_SAMPLES for x in xs)
    with pytest.raises(ValueError, match="duration"):
        plots.plot_local_models(gb.operating_curve(m, [1.0]), duration=1e9)


def test_a_noise_input_is_not_joined_to_a_loop_error_named_e():
    """The README's PI loop names its error "e": with noise=True the model's noise input must not take it by name
    (control.interconnect joins signals by name, silently)."""
    m = Model(["y(k-1)", "u(k-1)"], [0.5, 1.0], noise_structure=["e(k-1)"], noise_theta=[0.3])
    sysm = gb.narx_iosystem(m, Ts=1.0, noise=True, name="model")
    pi = ct.ss([[1.0]], [[0.1]], [[1.0]], [[0.5]], dt=1.0, inputs="e", outputs="u", name="pi")
    loop = ct.interconnect([sysm, pi, ct.summing_junction(["r", "-y"], "e", dt=1.0)],
                           inputs=["r", "noise"], outputs=["y", "u"])
    # the loop's error drives the controller only, and the noise is an input of the loop of its own
    assert loop.ninputs == 2
    T = np.arange(30.0)
    quiet = ct.input_output_response(loop, T, np.vstack([np.ones(30), np.zeros(30)]))
    noisy = ct.input_output_response(loop, T, np.vstack([np.ones(30), np.r_[1.0, np.zeros(29)]]))
    assert quiet.outputs[0][0] == 0.0 and noisy.outputs[0][0] == 1.0  # e(0) reaches y(0) directly, r does not
    with pytest.raises(ValueError, match="input of that name"):
        gb.narx_iosystem(Model(["y(k-1)", "noise(k-1)"], [0.5, 1.0], input_names=["noise"]), Ts=1.0, noise=True)


def test_a_transient_inputs_time_constant_comes_back_whole_from_its_name():
    # the system reads τ from the input's name: written to 6 digits, τ = 1/3 came back as 0.333333 and the
    # system's z drifted from the record's by 1e-6 relative; the name now holds every digit τ needs (30 stays 30)
    assert gb.transient_name("u", 30.0) == "u_tau30" and gb.transient_name("u", 2.5) == "u_tau2p5"
    # two τ alike to 6 digits are two channels (they were refused as giving one name)
    two = gb.transient_inputs(gb.Record(u=np.arange(5.0), y=np.zeros(5)), taus=[2.0, 2.0000001])
    assert two.input_names == ("u", "u_tau2", "u_tau2p0000001")
    u = np.r_[np.full(3, 1000.0), np.full(6, 1100.0), np.full(6, 950.0)]
    rec = gb.transient_inputs(gb.Record(u=u, y=np.full(u.size, 7.75), Ts=0.1), taus=[1 / 3])
    name = rec.input_names[1]
    model = Model(["y(k-1)", "u(k-1)", f"{name}(k-1)"], [0.5, 0.001, -1.0], input_names=("u", name), Ts=0.1)
    x0 = gb.narx_initial_state(model, rec)
    r = ct.input_output_response(gb.narx_iosystem(model), 0.1 * np.arange(u.size - 1), u[1:], x0)
    y = model.simulate(rec)
    assert np.ptp(y[1:]) > 1000  # the transient term carries the output
    np.testing.assert_allclose(r.outputs, y[1:], rtol=1e-13, atol=0)


def test_a_transient_input_is_computed_inside_the_nonlinear_system_from_its_source():
    # narx_iosystem made u_tau3 a system input of its own: a loop whose controller sets u left it unconnected
    # (python-control's 'Unused input(s)' warning, then z = 0), so the loop ran without the model's transient effect
    model = Model(["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "u_tau3(k-2)"], [0.1, 0.6, 0.002, 1e-6, -0.5],
                  input_names=("u", "u_tau3"), Ts=0.5)
    sysm = gb.narx_iosystem(model, noise=True)
    assert sysm.input_labels == ["u", "noise"] and sysm.state_labels == gb.narx_state_names(model, noise=True)
    u = np.r_[np.full(4, 1000.0), np.full(10, 1100.0), np.full(10, 950.0)]
    rec = gb.transient_inputs(gb.Record(u=u, y=np.full(u.size, 7.75), Ts=0.5), taus=[3])
    z = 0.0  # transient_inputs' z(k) = ρ z(k−1) + (1 − ρ)(u(k) − u(k−1))², ρ = exp(−Ts/τ), by hand
    for k in range(1, u.size):
        z = np.exp(-0.5 / 3) * z + (1 - np.exp(-0.5 / 3)) * (u[k] - u[k - 1]) ** 2
        assert rec.input("u_tau3")[k] == pytest.approx(z, rel=1e-12)
    L = model.max_lag
    x0 = gb.narx_initial_state(model, rec, noise=True)
    r = ct.input_output_response(sysm, 0.5 * np.arange(u.size - L), np.vstack([u[L:], np.zeros(u.size - L)]), x0)
    y = model.simulate(rec)
    assert np.ptp(y[L:]) > 100  # the transient term moves the output: a run without it would differ
    np.testing.assert_allclose(r.outputs[0], y[L:], rtol=1e-12, atol=1e-9)
    # settled, the transient input rests at 0 and the system stays put
    lm = gb.local_model(model, 1000.0)
    x = gb.narx_steady_state(model, 1000.0, lm.ybar)
    r = ct.input_output_response(gb.narx_iosystem(model), 0.5 * np.arange(5), np.full(5, 1000.0), x)
    np.testing.assert_allclose(r.outputs, lm.ybar, rtol=1e-12)
    # a transient input rests at 0 at every steady state: a state settled at z̄ = 5 is none (the system computes z
    # from u, and it decays), so it is refused; z̄ = 0 given is the point without it
    with pytest.raises(ValueError, match=r"u_tau3.*0 at every steady state"):
        gb.narx_steady_state(model, [1000.0, 5.0], lm.ybar)
    np.testing.assert_array_equal(gb.narx_steady_state(model, [1000.0, 0.0], lm.ybar), x)
    # a record without the transient input: told how to add it, as Model.simulate tells it (it said only 'no input
    # named 'u_tau3'')
    plain = gb.Record(u=u, y=np.full(u.size, 7.75), Ts=0.5)
    with pytest.raises(ValueError, match=r"u_tau3.*transient_inputs\(record, taus=\[3\], input_names=\['u'\]\)"):
        gb.narx_initial_state(model, plain)
    # a step whose square overflows is the run's divergence, said as for any other (not numpy's overflow warning)
    with pytest.raises(gb.DivergenceError, match="diverged"):
        ct.input_output_response(sysm, 0.5 * np.arange(5), np.vstack([[1000.0, 1e200, 0, 0, 0], np.zeros(5)]), x0)


def test_a_local_models_python_control_systems_take_the_inputs_the_nonlinear_system_takes():
    # to_statespace and to_transfer_function made a transient input u_tau2 a system input of its own, as narx_iosystem
    # did before 0f19ff64: a loop whose controller sets u left it unconnected (python-control's 'Unused input(s)'
    # warning), and the linear plant disagreed with control.linearize of narx_iosystem's, which takes u alone. z is
    # (1 − ρ)(Δu(k) − Δu(k−1))² filtered: zero to first order in Δu, so the linear system from u is B_u / A alone
    model = Model(["1", "y(k-1)", "u(k-1)", "u_tau2(k-1)", "u_tau2(k-1)y(k-1)", "u(k-2)u_tau2(k-1)"],
                  [0.1, 0.5, 0.3, 0.5, 0.1, 0.2], input_names=("u", "u_tau2"), Ts=0.5, name="tr")
    lm = gb.local_model(model, 1.0)
    assert lm.input_names == ("u", "u_tau2")  # the linearisation's coefficients keep every input's row
    nl = gb.narx_iosystem(model)
    ss, tf = lm.to_statespace(), lm.to_transfer_function()
    assert ss.input_labels == tf.input_labels == nl.input_labels == ["u"]
    # B_u / A by hand: b_u = (0.3, 0), a = 0.5 + 0.1 z̄ = 0.5 at z̄ = 0
    w = np.array([0.1, 1.0, 2 * np.pi])
    z = np.exp(1j * w * 0.5)
    by_hand = 0.3 / (z - 0.5)
    np.testing.assert_allclose(np.squeeze(ct.frequency_response(ss, w).complex), by_hand, rtol=1e-12)
    np.testing.assert_allclose(np.squeeze(ct.frequency_response(tf, w).complex), by_hand, rtol=1e-12)
    lin = ct.linearize(nl, gb.narx_steady_state(model, 1.0, lm.ybar), [1.0], copy_names=True)
    assert lin.input_labels == ss.input_labels
    np.testing.assert_allclose(np.squeeze(ct.frequency_response(lin, w).complex), by_hand, rtol=1e-5)
    # a loop whose controller sets u leaves no input unconnected (warnings are errors here)
    C = ct.tf([0.5], [1, -1], dt=0.5, inputs="e", outputs="u", name="C")
    loop = ct.interconnect([ss, C, ct.summing_junction(inputs=["r", "-y"], output="e")], inputs="r", outputs="y")
    assert loop.input_labels == ["r"]


def test_a_transient_input_decays_per_step_as_in_the_records_when_ts_relabels_a_one_second_model():
    # a model fitted on a record made without Ts= (1 s) has u_tau3 computed with ρ = exp(−1/3) per step; given the
    # real period, narx_iosystem(model, Ts=0.05) computed it with exp(−0.05/3) and ran 3924 off Model.simulate
    model = Model(["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "u_tau3(k-2)"], [0.1, 0.6, 0.002, 1e-6, -0.5],
                  input_names=("u", "u_tau3"), Ts=1.0)
    u = np.r_[np.full(4, 1000.0), np.full(10, 1100.0), np.full(10, 950.0)]
    rec = gb.transient_inputs(gb.Record(u=u, y=np.full(u.size, 7.75)), taus=[3])
    y = model.simulate(rec)
    assert np.ptp(y) > 1000  # the transient term moves the output
    L = model.max_lag
    x0 = gb.narx_initial_state(model, rec)
    for Ts in (None, 0.05):
        sysm = gb.narx_iosystem(model, Ts=Ts)
        assert sysm.dt == (Ts or 1.0)
        r = ct.input_output_response(sysm, sysm.dt * np.arange(u.size - L), u[L:], x0)
        np.testing.assert_allclose(r.outputs, y[L:], rtol=1e-12, atol=1e-9)


def test_a_nameless_models_divergence_names_the_system_not_none():
    # a model without a name (python-control then numbers the system) said 'None: the model's output is no longer a
    # finite number …'
    model = Model(["y(k-1)", "u(k-1)"], [2.0, 1.0], Ts=1.0)
    with pytest.raises(gb.DivergenceError, match=r"^narx_iosystem's system: the model's output") as e:
        ct.input_output_response(gb.narx_iosystem(model), np.arange(2000.0), np.ones(2000), np.zeros(2))
    assert not str(e.value).startswith("None")
    named = dataclasses.replace(model, name="tank")
    with pytest.raises(gb.DivergenceError, match=r"^tank_narx: "):
        ct.input_output_response(gb.narx_iosystem(named), np.arange(2000.0), np.ones(2000), np.zeros(2))


def test_an_operating_input_of_minus_zero_is_said_as_zero():
    """ū = -0.0 (e.g. -1 * 0.0, a level read from a file) is the level 0: a reason or a repr reading "ū = -0" names
    an input the user never set (mend58b)."""
    unstable = gb.Model(["y(k-1)", "u(k-1)", "1"], [2.0, 1.0, 0.5], Ts=1.0)  # ȳ = -(ū + 0.5): one, unstable
    lm = gb.local_model(unstable, -0.0)
    assert lm.reason.startswith("ū = 0: no stable equilibrium; linearised at the unstable ȳ = -0.5 ")
    assert repr(lm).startswith("LocalModel(ū = (0), ȳ = -0.5, no stable equilibrium")
    integrator = gb.Model(["y(k-1)", "u(k-1)"], [1.0, 1.0], Ts=1.0)  # a continuum of equilibria at ū = 0
    assert gb.local_model(integrator, -0.0, y0=-0.0).reason.startswith("ū = 0: a continuum of equilibria")
    assert gb.local_model(integrator, -0.0, y0=-0.0).reason.endswith("; linearised at ȳ = y0 = 0")
    assert repr(gb.local_model(integrator, -0.0, y0=-0.0)).startswith("LocalModel(ū = (0), ȳ = 0, continuum")
    with pytest.raises(ValueError, match=r"^ū = 0: a continuum"):
        integrator.equilibria(-0.0)
    two = gb.Model(["y(k-1)", "u1(k-1)", "u2(k-1)", "1"], [2.0, 1.0, 1.0, 0.5], Ts=1.0)
    assert gb.local_model(two, [-0.0, 1.0]).reason.startswith("ū = (0, 1): no stable equilibrium")
    assert repr(gb.local_model(two, [-0.0, 1.0])).startswith("LocalModel(ū = (0, 1), ȳ = -1.5,")


def test_narx_initial_state_takes_the_period_narx_iosystem_was_given_over_a_one_second_model():
    # a model fitted on a record made without Ts= (1 s), run by narx_iosystem(model, Ts=0.05) at the real period:
    # the state at a start of the real record (0.05 s) was refused as 'sampled every 1 s', with no way to say the
    # period the system runs at (mend58b)
    model = Model(["y(k-1)", "u(k-1)", "u(k-2)"], [0.6, 0.5, 0.1], noise_structure=["e(k-1)"], noise_theta=[0.3],
                  Ts=1.0)
    rng = np.random.default_rng(3)
    u, y = rng.normal(size=30), rng.normal(size=30)
    one, real = gb.Record(u=u, y=y), gb.Record(u=u, y=y, Ts=0.05)
    with pytest.raises(ValueError, match=r"every 1 s but 'record' every 0.05 s.*Ts=0.05"):
        gb.narx_initial_state(model, real)
    for start in (2, 9):  # the lags alone; past the residuals' first sample, with them
        x = gb.narx_initial_state(model, real, Ts=0.05, start=start, noise=True)
        np.testing.assert_array_equal(x, [y[start - 1], u[start - 1], u[start - 2],
                                          gb.one_step_residuals(model, one)[0][start - 1 - 2] if start > 2 else 0.0])
    np.testing.assert_array_equal(x, gb.narx_initial_state(model, one, start=9, noise=True))
    with pytest.raises(ValueError, match=r"runs every 0.05 s but 'record' every 1 s"):  # the system's period, not 1 s
        gb.narx_initial_state(model, one, Ts=0.05)
    at_real = dataclasses.replace(model, Ts=0.05)  # a model that knows its period: another is refused, as for the system
    with pytest.raises(ValueError, match=r"identified at Ts = 0.05 s"):
        gb.narx_initial_state(at_real, one, Ts=1.0)
    np.testing.assert_array_equal(gb.narx_initial_state(at_real, real, Ts=0.05), gb.narx_initial_state(at_real, real))


def test_a_given_period_that_the_data_contradict_is_refused():
    # Ts= was checked against the model's period only: a hand-written model (no Ts) with its records at 0.05 s and
    # Ts=50 (meant as ms) gave τ = 72 s, a thousand times too long, and a model at 0.05 s with data at 0.1 s, refused
    # without Ts=, was taken with Ts=0.05 (hunt59a)
    rng = np.random.default_rng(5)
    u, y = rng.uniform(0.5, 2.0, 40), rng.uniform(0.0, 1.0, 40)
    hand = Model(["1", "y(k-1)", "u(k-1)"], [0.3, 0.5, 0.4], name="hand")
    at_005 = dataclasses.replace(hand, Ts=0.05)
    fast, slow, one = gb.Record(u, y, Ts=0.05), gb.Record(u, y, Ts=0.1), gb.Record(u, y)
    for model, data in ((hand, fast), (hand, [fast, fast]), (at_005, slow)):
        for f in (gb.local_model, gb.operating_curve):
            with pytest.raises(ValueError, match=r"every (50|0.05) s but 'record' every (0.05|0.1) s"):
                f(model, 1.0, Ts=50 if model is hand else 0.05, data=data)
    # the data at the period given, or made without Ts= (1 s, relabelled by Ts= as a model's 1 s is), are taken
    lm = gb.local_model(hand, 1.0, Ts=0.05, data=fast)
    assert lm.Ts == 0.05 and lm.time_constant == pytest.approx(-0.05 / np.log(0.5), rel=1e-12)
    assert gb.local_model(hand, 1.0, Ts=0.05, data=one).Ts == 0.05
    assert gb.local_model(dataclasses.replace(hand, Ts=1.0), 1.0, Ts=0.05, data=gb.Dataset(one, one)).Ts == 0.05
    assert gb.local_model(at_005, 1.0, Ts=0.05, data=fast).Ts == 0.05
    # and so beside a model of a known period: records made without Ts= with Ts= the model's own were taken before
    # this check and are as the docstring says (was: refused, 'identified on records sampled every 0.05 s but
    # 'record' every 1 s', review59f)
    assert gb.local_model(at_005, 1.0, Ts=0.05, data=one).Ts == 0.05
    assert gb.operating_curve(at_005, [1.0], Ts=0.05, data=[one, one]).local_models[0].Ts == 0.05


def _settling_by_hand(a: list[float], b: float, band: float, n: int) -> float:
    """The 2-pole, 1-lag step response s(k) = g + Σ c_i p_i^k (k >= 1), c_i from s(1) and s(2): the last sample
    outside the band, plus one."""
    p = np.roots([1.0, -a[0], -a[1]])
    g = b / (1.0 - sum(a))
    s1, s2 = b, a[0] * b + b
    c = np.linalg.solve(np.array([p, p ** 2]), np.array([s1 - g, s2 - g]))
    k = np.arange(1, n)
    err = np.abs(np.real(c[0] * p[0] ** k + c[1] * p[1] ** k))
    return float(k[np.flatnonzero(err > band * abs(g))[-1]] + 1)


def test_settling_time_is_not_held_up_by_the_round_off_of_the_step_response():
    # the step response was run to its final value and compared with g: where 1 − Σa is small its floating-point
    # limit sits off g by eps / (1 − Σa), and a band under a thousand times that never 'settled'. a = (1.5, −0.5001):
    # the 1e-9 band, entered for good after 103566 samples, gave inf; y(k) = 0.3 y(k-1) + 0.7 u(k-1) with the band
    # 1e-16 gave the end of the window run, 41 samples for 31 (hunt59a)
    slow = gb.LocalModel(np.array([0.0]), 0.0, "reached", "", np.array([1.5, -0.5001]), np.array([[0.3]]), 1.0, ("u",))
    for band in (1e-6, 1e-9, 1e-12):
        assert slow.settling_time(band=band) == _settling_by_hand([1.5, -0.5001], 0.3, band, 400_000)
    fast = gb.LocalModel(np.array([0.0]), 0.0, "reached", "", np.array([0.3]), np.array([[0.7]]), 1.0, ("u",))
    for band in (0.02, 1e-6, 1e-12, 1e-16, 1e-17):  # the first k with 0.3^k <= band
        assert fast.settling_time(band=band) == np.ceil(np.log(band) / np.log(0.3))


def test_operating_points_named_by_input_in_a_dict_are_read_by_name_and_none_is_said_to_be_empty():
    # was: local_model(model, {"u2": 0.5, "u1": 1.0}) raised "ubar must be input levels (numbers), got dict" (a
    # Series of the same levels was read by name; GainBounds and ubar_range take dicts by name), and
    # operating_curve(model, []) "ubar must have shape (M,) ... got shape (0,)", a shape it has
    by_name = gb.local_model(TWO_INPUTS, {"u2": 0.5, "u1": 1.0}, Ts=0.1)
    in_order = gb.local_model(TWO_INPUTS, [1.0, 0.5], Ts=0.1)
    assert by_name.ubar == pytest.approx(in_order.ubar) and by_name.ybar == pytest.approx(in_order.ybar)
    curve = gb.operating_curve(TWO_INPUTS, {"u2": [0.5, 1.2], "u1": [1.0, 0.6]}, Ts=0.1)
    np.testing.assert_allclose(curve.ybar, TWO_INPUTS.static_curve([[1.0, 0.5], [0.6, 1.2]]), rtol=1e-12)
    assert TWO_INPUTS.static_curve({"u2": 0.5, "u1": 1.0}) == pytest.approx(in_order.ybar)
    with pytest.raises(ValueError, match=r"'u3'.*\['u1', 'u2'\].*each input's name"):
        gb.local_model(TWO_INPUTS, {"u1": 1.0, "u3": 0.5}, Ts=0.1)
    with pytest.raises(ValueError, match=r"different numbers of levels \{'u1': 2, 'u2': 1\}"):
        gb.operating_curve(TWO_INPUTS, {"u1": [1.0, 0.6], "u2": 0.5}, Ts=0.1)
    with pytest.raises(TypeError, match=r"ubar\['u2'\] must be a real number, got True"):
        gb.local_model(TWO_INPUTS, {"u1": 1.0, "u2": True}, Ts=0.1)
    with pytest.raises(ValueError, match="no input level"):
        gb.operating_curve(reference.paper_model(15), [], Ts=0.05)


def test_a_transient_inputs_level_other_than_0_is_refused_alike_by_every_steady_state_entry():
    """local_model took ū = (1, z̄ = 0.3) and gave a local model at ȳ = 3.2, an equilibrium the plant never rests at
    (a transient input is 0 at every steady state), where narx_steady_state refused the same ū: one check now
    (mend60g)."""
    model = gb.Model(gb.Structure(["y(k-1)", "u(k-1)", "u_tau30(k-1)"]), [0.5, 1.0, 2.0])
    for call in (lambda ub: gb.local_model(model, ub, Ts=1.0), lambda ub: gb.narx_steady_state(model, ub, 2.0),
                 lambda ub: gb.operating_curve(model, [ub, [2.0, 0.0]], Ts=1.0)):
        with pytest.raises(ValueError, match=r"ubar gives the transient input\(s\) u_tau30 a level other than 0"):
            call([1.0, 0.3])
    lm = gb.local_model(model, [1.0, 0.0], Ts=1.0)
    assert lm.ybar == pytest.approx(1.0 / (1 - 0.5)) and gb.local_model(model, 1.0, Ts=1.0).ybar == lm.ybar
    np.testing.assert_array_equal(gb.narx_steady_state(model, [1.0, 0.0], lm.ybar), [2.0, 1.0, 0.0])
