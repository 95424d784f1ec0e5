"""hunt50e: the less hunted estimators (neural NARMAX, se_dsf, the local models, ELS)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import graybox as gb


def _exact(n: int = 300, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A noise-free record of 0.1 + 0.5 y(k-1) + 0.3 u(k-1) + 0.4 u(k-1)²: least squares fits it to round-off."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(0.0, 1.0, n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.1 + 0.5 * y[k - 1] + 0.3 * u[k - 1] + 0.4 * u[k - 1] ** 2
    return u, y


EXACT = ["1", "y(k-1)", "u(k-1)", "u(k-1)^2"]


@pytest.mark.parametrize("offset", [1e4, -1e4, 1e6])
def test_els_of_data_it_fits_exactly_has_no_ma_part_at_any_zero_of_y(offset):
    # noise-free data: the least-squares residuals are round-off, and ELS gives the MA part zero, 0 iterations. At
    # y + 1e4 (the same data in another zero) the centred output carried the round-off of the raw levels (1e4 ulps),
    # which the test held against the centred output's RMS: it fitted an MA part to round-off, C = 1 - 0.50 q^-1 -
    # 0.16 q^-2 in 58 iterations
    u, y = _exact()
    ref = gb.els(EXACT, gb.Record(u=u, y=y))
    assert ref.n_iter == 0 and np.all(ref.model.noise_theta == 0.0)
    res = gb.els(EXACT, gb.Record(u=u, y=y + offset))
    assert res.n_iter == 0 and res.converged
    assert np.all(res.model.noise_theta == 0.0), res.model.noise_theta
    sim = res.model.simulate(gb.Record(u=u, y=y + offset)) - offset
    assert np.max(np.abs(sim - y)) < 1e-9 * max(1.0, abs(offset))


def _els_fit() -> gb.ELSResult:
    rng = np.random.default_rng(1)
    u = rng.uniform(0.0, 1.0, 300)
    y = np.convolve(u, [0.0, 0.5, 0.3])[:300] + 0.05 * rng.standard_normal(300)
    return gb.els(["y(k-1)", "u(k-1)"], gb.Record(u=u, y=y))


@pytest.mark.parametrize("field, value, words", [
    ("n_iter", -5, "n_iter"),
    ("n_iter", 3, "history"),  # 3 iterations with another number of residual changes
    ("n_direct", -1, "n_direct"),
    ("history", (), "history"),
    ("history", "negative", "history"),
    ("theta_ls", [1.0], "theta_ls"),
    ("residuals", (), "residuals"),
])
def test_an_els_result_that_no_iteration_gives_is_refused_naming_the_field(field, value, words, tmp_path):
    # a file edited by hand (or a result built wrong) with n_iter = -5, theta_ls of 1 value for a 2-term model, no
    # residuals or a history of another length than n_iter loaded silently; NeuralFit, DSFResult and OEResult refuse
    # theirs
    res = _els_fit()
    fields = {f: getattr(res, f) for f in ("model", "n_iter", "converged", "history", "residuals", "theta_ls",
                                           "n_direct")}
    assert len(res.history) == res.n_iter > 0
    if value == "negative":
        value = (-1.0,) + tuple(res.history[1:])
    fields[field] = value
    with pytest.raises(ValueError, match=words):
        gb.ELSResult(**fields)
    path = tmp_path / "els.json"
    gb.save(res, path)
    assert gb.load(path).n_iter == res.n_iter  # the result itself still round-trips


@pytest.mark.parametrize("band", ["1", True, b"1", {"B": 1.0}])
def test_se_dsf_refuses_a_band_that_is_no_number_without_offering_a_pair(band):
    # se_dsf's band is one number B (a pair is refused: "se_dsf: band must be a number B > 0"); a string, a flag or
    # a mapping was refused by the shared band check, whose message offered "or a pair (low, high)"
    rng = np.random.default_rng(1)
    u = rng.uniform(0.0, 1.0, 100)
    rec = gb.Record(u=u, y=np.convolve(u, [0.0, 0.5])[:100])
    sp = gb.StaticPoints(ubar=[0.0, 1.0], ybar=[0.0, 0.5])
    with pytest.raises(TypeError, match="band must be a number B > 0") as exc:
        gb.se_dsf(["y(k-1)", "u(k-1)"], rec, sp, band=band, theta0=[0.0, 0.5], max_iter=2)
    assert "pair" not in str(exc.value)
    with pytest.raises(TypeError, match="band must be a number B > 0") as exc:
        gb.se_dsf(["y(k-1)", "u(k-1)"], rec, sp, band=(0.0, 1e-3), theta0=[0.0, 0.5], max_iter=2)
    assert "pair" not in str(exc.value)


def _neural_fit() -> gb.NeuralFit:
    rng = np.random.default_rng(1)
    u = rng.uniform(-1.0, 1.0, 120)
    y = np.zeros(120)
    for k in range(1, 120):
        y[k] = 0.6 * y[k - 1] + 0.5 * np.tanh(u[k - 1]) + 0.05 * rng.standard_normal()
    return gb.neural_narx(gb.Record(u=u, y=y), ny=1, nu=1, ne=1, hidden=2, epochs=3, sim_epochs=3, holdout=0.2,
                          seed=0)


@pytest.mark.parametrize("change, words", [
    (dict(epochs=1), "epochs"),  # fewer trial steps than the accepted ones the costs record
    (dict(simulation_cost=()), "holdout_cost"),  # the held-out costs of a stage 2 that is not there
    (dict(holdout_cost=(1.0,)), "holdout_cost"),  # one held-out cost for a stage of several accepted steps
])
def test_a_neural_fit_whose_counts_disagree_is_refused(change, words):
    # NeuralFit checked each field alone: a file saying 1 epoch beside 3 accepted steps in each stage, or held-out
    # costs of a last stage with another number of steps than its costs, loaded silently
    fit = _neural_fit()
    assert len(fit.holdout_cost) == len(fit.simulation_cost) > 1
    assert fit.epochs >= len(fit.prediction_cost) - 1 + len(fit.simulation_cost) - 1
    fields = {f: getattr(fit, f) for f in ("model", "prediction_cost", "simulation_cost", "holdout_cost", "best_step",
                                           "epochs", "stopped", "rmse_train", "rmse_sim", "seconds")}
    fields.update(change)
    if "holdout_cost" in change:
        fields["best_step"] = 0
    with pytest.raises(ValueError, match=words):
        gb.NeuralFit(**fields)


@pytest.mark.parametrize("noise", [["e(k-1)", "e(k-1)u(k-1)"], ["e(k-2)", "e(k-1)^2"]])
def test_els_warning_diagnoses_no_linear_ma_part_that_is_only_part_of_the_noise_model(noise):
    # with a nonlinear noise term beside plain lags the warning said "The MA part C(q) = 1 + 0.214 q^-2 lets the
    # iteration contract only by a factor 0.607": the MA part it named left out e(k-1)^2 (θ -0.68), and so did the
    # contraction figures; a noise model not made of plain lags alone is not diagnosed, as one without any is not
    rng = np.random.default_rng(1)
    n = 500
    u, e = rng.uniform(0.0, 1.0, n), 0.05 * rng.standard_normal(n)
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = 0.5 * y[k - 1] + 0.3 * u[k - 1] + 0.2 * u[k - 1] ** 2 + e[k] + 0.8 * e[k - 1] + 0.5 * e[k - 2]
    with pytest.warns(gb.ELSConvergenceWarning) as caught:
        gb.els(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"], gb.Record(u=u, y=y), noise=noise, max_iter=3)
    msg = str(caught[0].message)
    assert "C(q)" not in msg, msg
    assert "no cause is diagnosed" in msg


def test_a_network_whose_output_lags_cancel_in_the_static_equation_still_has_its_stability_tested():
    # y(k) = tanh(3 y(k-1) - 3 y(k-2) + u(k-1)): the static equation does not depend on ȳ (the lags' weights sum to
    # 0), so ȳ = 0 at ū = 0 is the one equilibrium, but its local model y(k) = 3 y(k-1) - 3 y(k-2) has roots of
    # modulus √3. equilibria() said stable=True, spectral_radius=0.0 without looking, and static_curve returned 0
    # where a free run from next to it swings between ±0.995 for ever (static_curve from y0 said NaN)
    net = gb.NeuralModel(np.array([[3.0, -3.0, 1.0]]), np.array([0.0]), np.array([1.0]), 0.0, 2, 1, 0)
    (eq,) = net.equilibria(0.0)
    assert eq.ybar == 0.0
    assert not eq.stable
    assert eq.spectral_radius == pytest.approx(np.sqrt(3.0))
    with pytest.raises(ValueError, match="ū = 0"):
        net.static_curve([0.0])
    assert np.isnan(net.static_curve([0.0], strict=False)[0])
    run = net.simulate(np.zeros(200), y0=[0.01, 0.0])
    assert np.max(np.abs(run[-20:])) > 0.9  # the free run does not settle on it
    # a stable one of the same kind: y(k) = 0.9 tanh(0.3 y(k-1) - 0.3 y(k-2) + u(k-1))
    calm = gb.NeuralModel(np.array([[0.3, -0.3, 1.0]]), np.array([0.0]), np.array([0.9]), 0.0, 2, 1, 0)
    (eq,) = calm.equilibria(0.5)
    assert eq.stable and 0.0 < eq.spectral_radius < 1.0
    assert calm.static_curve([0.5])[0] == pytest.approx(0.9 * np.tanh(0.5))


def test_a_network_without_output_lags_does_not_print_one():
    # str() of a network with ny = 0 listed 'y(k-1..0)' among its inputs: it has no output input at all
    net = gb.NeuralModel(np.ones((2, 3)), np.ones(2), np.ones(2), 0.0, 0, 2, 1)
    text = str(net)
    assert "y(k-1" not in text and "u(k-1..2), e(k-1..1)]" in text
    assert "[y(k-1..2), u(k-1..1)]" in str(gb.NeuralModel(np.ones((2, 3)), np.ones(2), np.ones(2), 0.0, 2, 1, 0))


def test_the_els_result_says_when_an_ma_part_gets_no_iteration():
    # noise-free data: ELS returns its MA part zero after 0 iterations; ELSResult said n_iter is 0 "when there is no
    # MA part" only
    u, y = _exact()
    res = gb.els(EXACT, gb.Record(u=u, y=y), noise=2)
    assert len(res.model.noise_structure) == 2 and res.n_iter == 0 and np.all(res.model.noise_theta == 0.0)
    doc = " ".join(gb.ELSResult.__doc__.split())
    assert "0 when there is no MA part, or when least squares fits the data to round-off" in doc


@settings(max_examples=40, deadline=None)
@given(w=st.lists(st.floats(-4.0, 4.0), min_size=2, max_size=2), wu=st.floats(-2.0, 2.0),
       b1=st.floats(-1.0, 1.0), w2=st.floats(-2.0, 2.0), ubar=st.floats(-1.0, 1.0))
def test_a_networks_equilibrium_is_stable_exactly_when_its_local_model_is(w, wu, b1, w2, ubar):
    # y(k) = w2 tanh(w1 y(k-1) + w2' y(k-2) - (w1 + w2') y(k-3) + wu u(k-1) + b1): the output lags cancel in the static
    # equation, so its one equilibrium ȳ = w2 tanh(wu ū + b1); stable must be what the local model's roots say
    w1, w2p = w
    net = gb.NeuralModel(np.array([[w1, w2p, -(w1 + w2p), wu]]), np.array([b1]), np.array([w2]), 0.0, 3, 1, 0)
    (eq,) = net.equilibria(ubar)
    d = w2 * (1.0 - np.tanh(wu * ubar + b1) ** 2)
    rho = float(np.max(np.abs(np.roots([1.0, -d * w1, -d * w2p, d * (w1 + w2p)]))))
    assume(abs(rho - 1.0) > 1e-6)  # on the unit circle either answer is round-off
    assert eq.ybar == pytest.approx(w2 * np.tanh(wu * ubar + b1), abs=1e-12)
    assert eq.spectral_radius == pytest.approx(rho, rel=1e-6, abs=1e-12)
    assert eq.stable == (rho < 1.0)


def _dsf_problem() -> tuple[gb.Record, gb.StaticPoints]:
    rng = np.random.default_rng(1)
    n = 300
    u, e = rng.uniform(0.0, 1.0, n), 0.05 * rng.standard_normal(n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + 0.3 * u[k - 1] + 0.4 * u[k - 1] ** 2 + e[k]
    ub = np.linspace(0.0, 1.0, 5)
    return gb.Record(u=u, y=y), gb.StaticPoints(ubar=ub, ybar=(0.3 * ub + 0.4 * ub**2) / 0.5 + 0.05)


@pytest.mark.parametrize("max_iter", [8, 12, 30])
def test_se_dsf_says_why_a_run_that_restored_the_band_stopped(max_iter):
    # a start outside the band whose restoration steps each gained less than tol and whose third step reached the
    # band: the message was set to "converged: relative decrease of J_SF below tol for 3 steps" there, the run went
    # on inside the band (J_SF's stall count carried into J_S's) and when it then ran out of iterations the result
    # still said it had converged on J_SF
    rec, sp = _dsf_problem()
    theta0 = [-0.27626025566875984, 0.4647363303387978, 0.10988302778344453, 0.44068965382325526]
    res = gb.se_dsf(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"], rec, sp, band=1.2795016088905733e-05, theta0=theta0,
                    max_iter=max_iter, tol=0.6552732859872454, margin=None)
    assert res.start_JSF > res.band and res.in_band
    assert "J_SF" not in res.message, res.message
    if res.n_iter == max_iter:
        assert res.message == f"{max_iter} iterations reached"
