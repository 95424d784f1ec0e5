"""The neural NARMAX baseline (graybox.neural)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from threadpoolctl import threadpool_limits

from graybox import Candidates, Record
from graybox.datasets import load_pumping
from graybox.estimation._extended_least_squares import els
from graybox.models._evaluate import evaluate, mse
from graybox.estimation._neural import (
    NeuralModel,
    _deterministic,
    _pe_jacobian_kernel,
    _pe_kernel,
    _sim_kernel,
    _unpack,
    neural_narx,
)
from graybox.selection._forward_regression import frols
from graybox.reproduce import section_neural
from graybox.core._records import Dataset
from graybox.core._simulation import DivergenceError

# The small network of the fast tests: ny = nu = 2, ne = 1, 3 hidden nodes.
SMALL = dict(ny=2, nu=2, ne=1, hidden=3)


def small_record(seed: int = 0, n: int = 400) -> Record:
    """A first-order nonlinear system in engineering-like units (u in the hundreds)."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(200.0, 800.0, n // 20 + 1), 20)[:n]
    y = np.zeros(n)
    y[0] = 5.0
    for k in range(1, n):
        y[k] = 0.6 * y[k - 1] + 4.0 * math.tanh((u[k - 1] - 500.0) / 200.0) + 2.0 + 0.05 * rng.standard_normal()
    return Record(u, y, Ts=0.1, name=f"small{seed}")


def ref_output(net: NeuralModel, ylags, ulags, elags=()) -> float:
    """Plain-Python network output in engineering units; ylags[i] = y(k-1-i), etc."""
    s = net.b2
    for j in range(net.hidden):
        a = net.b1[j]
        for i in range(net.ny):
            a += net.W1[j, i] * (ylags[i] - net.y_offset) / net.y_scale
        for i in range(net.nu):
            a += net.W1[j, net.ny + i] * (ulags[i] - net.u_offset) / net.u_scale
        for i, e in enumerate(elags):
            a += net.W1[j, net.ny + net.nu + i] * e / net.y_scale
        s += net.w2[j] * math.tanh(a)
    return net.y_offset + net.y_scale * s


def hand_net(w2: float, gain: float, ne: int = 0) -> NeuralModel:
    """y(k) = w2 tanh(gain y(k-1) + 0.001 u(k-1)) in unit scaling: bistable for w2·gain > 1."""
    W1 = np.zeros((1, 2 + ne))
    W1[0, 0], W1[0, 1] = gain, 0.001
    return NeuralModel(W1, [0.0], [w2], 0.0, ny=1, nu=1, ne=ne, name="hand")


@pytest.fixture(scope="module")
def plant():
    return load_pumping()


@pytest.fixture(scope="module")
def plant_net(plant):
    """The default training of the paper's network on the bundled identification record."""
    return neural_narx(plant.ident, seed=0, name="Neural").model


@pytest.fixture(scope="module")
def els15(plant):
    """ELS (15) as `graybox reproduce` builds it: the reference row of the neural claim."""
    sel = frols(Candidates(6, 6, ne=2, degree=2, max_y_power=1), plant.ident, n_terms=17, include=["1"])
    return els(sel, plant.ident, name="ELS (15)").model


@pytest.fixture(scope="module")
def small_net():
    return neural_narx(small_record(), **SMALL, epochs=15, seed=1).model


# -- parameter count and immutability --------------------------------------------------------

def test_n_params_is_99_for_the_paper_sizes(plant_net):
    net = NeuralModel(np.zeros((7, 14)), np.zeros(7), np.zeros(7), 0.0, ny=6, nu=6, ne=2)
    assert net.n_params == 99 == 12 * 7 + 7 + 7 + 1
    assert net.n_trained == 113
    assert plant_net.n_params == 99 and plant_net.max_lag == 6
    assert neural_narx(small_record(), ny=6, nu=6, ne=0, hidden=7, epochs=1, sim_epochs=1).model.n_params == 99


def test_model_is_immutable(small_net):
    with pytest.raises(ValueError):
        small_net.W1[0, 0] = 1.0
    with pytest.raises(AttributeError):
        small_net.b2 = 1.0  # type: ignore[misc]
    w = np.ones((1, 2))
    net = NeuralModel(w, [0.0], [1.0], 0.0, ny=1, nu=1)
    w[0, 0] = 5.0  # the model holds a copy
    assert net.W1[0, 0] == 1.0


def test_str_and_repr(small_net, plant_net):
    s = str(plant_net)
    assert "N_p = 99" in s and "residual" in s and s.startswith("Neural:")
    assert "n_params=" in repr(small_net)
    renamed = small_net.with_name("NN")
    assert renamed.name == "NN" and np.array_equal(renamed.W1, small_net.W1)


# -- training --------------------------------------------------------------------------------

def test_training_is_reproducible_with_a_seed():
    rec = small_record()
    a = neural_narx(rec, **SMALL, epochs=8, sim_epochs=8, seed=3).model
    b = neural_narx(rec, **SMALL, epochs=8, sim_epochs=8, seed=3).model
    c = neural_narx(rec, **SMALL, epochs=8, sim_epochs=8, seed=4).model
    for f in ("W1", "b1", "w2"):
        assert np.array_equal(getattr(a, f), getattr(b, f))
    assert a.b2 == b.b2
    assert not np.array_equal(a.W1, c.W1)


def test_training_does_not_depend_on_the_blas_thread_count():
    rec = small_record()
    with threadpool_limits(limits=1):
        a = neural_narx(rec, **SMALL, epochs=8, sim_epochs=8, seed=2).model
    with threadpool_limits(limits=2):
        b = neural_narx(rec, **SMALL, epochs=8, sim_epochs=8, seed=2).model
    assert np.array_equal(a.W1, b.W1) and np.array_equal(a.w2, b.w2) and a.b2 == b.b2


def test_training_costs_decrease_and_info_is_consistent():
    rec = small_record()
    D = 0.5
    info = neural_narx(rec, **SMALL, epochs=15, sim_epochs=20, weight_decay=D, seed=0)
    net = info.model
    assert np.all(np.diff(info.prediction_cost) < 0)  # only improving steps are kept
    assert np.all(np.diff(info.simulation_cost) < 0)
    assert len(info.prediction_cost) <= 16 and 1 < len(info.simulation_cost) <= 21
    assert 15 + 20 <= info.epochs <= 15 + 20 + 20  # the residual re-fit adds up to 20
    assert info.stopped in ("epochs", "converged")
    assert info.holdout_cost == () and info.best_step is None
    L = net.max_lag
    # the NARMAX predictor's residuals (with the re-fitted residual weights)
    _, e = net.predict_narmax(rec)
    assert info.rmse_train == pytest.approx(np.sqrt(np.mean(e[L:] ** 2)), rel=1e-9)
    # the simulation cost is the free run's, from the record's first L outputs, plus the decay
    # of the weights the free run uses
    sim = net.simulate(rec)
    assert info.rmse_sim == pytest.approx(np.sqrt(mse(rec.y, sim, start=L)), rel=1e-9)
    theta = np.concatenate([net.W1.ravel(), net.b1, net.w2, [net.b2]])
    det = _deterministic(net.hidden, net.ny, net.nu, net.ne)
    expect = 0.5 * np.sum(((sim - rec.y) / net.y_scale)[L:] ** 2) + 0.5 * D * np.sum(theta[det] ** 2)
    assert info.simulation_cost[-1] == pytest.approx(expect, rel=1e-9)


def test_paper_training_is_prediction_error_only():
    info = neural_narx(small_record(), **SMALL, epochs=12, sim_epochs=0, weight_decay=0.0, seed=0)
    assert info.simulation_cost == () and info.epochs == 12
    net = info.model
    _, e = net.predict_narmax(small_record())
    assert info.prediction_cost[-1] == pytest.approx(0.5 * np.sum((e / net.y_scale) ** 2), rel=1e-9)


def _two_record_problem(ny, nu, ne, H):
    rng = np.random.default_rng(0)
    P = H * (ny + nu + ne + 2) + 1
    theta = rng.uniform(-0.5, 0.5, P)
    un = rng.standard_normal(60)
    yn = rng.standard_normal(60)
    seg = np.array([0, 25, 60], dtype=np.int64)
    L = max(ny, nu)
    mask = np.ones(60, bool)
    mask[list(range(L)) + list(range(25, 25 + L))] = False
    return theta, un, yn, seg, mask


def _finite_differences(f, theta, idx):
    fd = []
    for p in idx:
        d = np.zeros(theta.size)
        d[p] = 1e-6
        fd.append((f(theta + d) - f(theta - d)) / 2e-6)
    return np.array(fd).T


def test_prediction_jacobian_matches_finite_differences_across_two_records():
    """ψ = dŷ/dθ including the residual feedback, with the recursion restarting per record."""
    ny, nu, ne, H = 2, 1, 2, 3
    n_in = ny + nu + ne
    theta, un, yn, seg, mask = _two_record_problem(ny, nu, ne, H)

    def yhat(th):
        W1, b1, w2, b2 = _unpack(th, H, n_in)
        return _pe_kernel(W1, b1, w2, b2, un, yn, seg, ny, nu, ne)[0][mask]

    W1, b1, w2, b2 = _unpack(theta, H, n_in)
    _, e = _pe_kernel(W1, b1, w2, b2, un, yn, seg, ny, nu, ne)
    psi = _pe_jacobian_kernel(W1, b1, w2, un, yn, e, seg, ny, nu, ne)
    np.testing.assert_allclose(psi, _finite_differences(yhat, theta, range(theta.size)), rtol=1e-5, atol=1e-8)


def test_simulation_jacobian_matches_finite_differences_across_two_records():
    """ψ = dŷ/dθ_d of the free run (output feedback through all ny lags), restarting per record."""
    ny, nu, ne, H = 3, 2, 1, 3
    n_in = ny + nu + ne
    theta, un, yn, seg, mask = _two_record_problem(ny, nu, ne, H)
    det = _deterministic(H, ny, nu, ne)

    def run(th):
        W1, b1, w2, b2 = _unpack(th, H, n_in)
        return _sim_kernel(W1, b1, w2, b2, un, yn, seg, ny, nu, False)[0]

    W1, b1, w2, b2 = _unpack(theta, H, n_in)
    ys, psi = _sim_kernel(W1, b1, w2, b2, un, yn, seg, ny, nu, True)
    assert psi.shape == (mask.sum(), det.sum())
    np.testing.assert_array_equal(ys[~mask], yn[~mask])  # each record starts from its measured outputs
    np.testing.assert_allclose(psi, _finite_differences(lambda t: run(t)[mask], theta, np.flatnonzero(det)),
                               rtol=1e-5, atol=1e-8)
    # the residual-input weights do not enter a free run
    assert np.array_equal(run(theta), run(np.where(det, theta, 0.0)))
    # the kernel's run is the model's free run of each record
    net = NeuralModel(W1, b1, w2, b2, ny, nu, ne)
    np.testing.assert_allclose(ys[25:], net.simulate(un[25:], yn[25:25 + 3]), rtol=1e-12, atol=1e-12)


def test_early_stopping_stops_on_the_held_out_cost(plant):
    """Without weight decay the free-run fit overfits: the held-out cost turns up and training stops."""
    patience = 4
    info = neural_narx(plant.ident, weight_decay=0.0, sim_epochs=200, holdout=0.2, patience=patience, seed=0)
    h = np.array(info.holdout_cost)
    assert info.stopped == "patience"
    assert len(h) - 1 - info.best_step == patience and h[info.best_step] == h.min()
    assert np.all(h[info.best_step + 1:] > h[info.best_step])
    # fewer steps than the budget, and the returned weights are those of the best held-out cost,
    # measured here on the held-out part (the last 20 %) by the model's own free run
    assert len(info.simulation_cost) - 1 < 200
    net = info.model
    n = len(plant.ident)
    held = plant.ident.slice(n - int(round(0.2 * n)), n)
    assert mse(held.y, net.simulate(held), start=net.max_lag) == pytest.approx(h[info.best_step], rel=1e-9)
    # the held-out part was not trained on: the normalisation comes from the first 80 % alone
    assert net.y_offset == pytest.approx(float(np.mean(plant.ident.y[: n - len(held)])), rel=1e-12)


def test_early_stopping_without_patience_keeps_the_best():
    info = neural_narx(small_record(), **SMALL, epochs=5, sim_epochs=15, holdout=0.25, seed=0)
    assert info.best_step is not None and info.holdout_cost[info.best_step] == min(info.holdout_cost)
    assert len(info.holdout_cost) == len(info.simulation_cost)  # taken at the start and after each kept step
    # with prediction error only, early stopping applies to that stage
    pe = neural_narx(small_record(), **SMALL, epochs=10, sim_epochs=0, holdout=0.25, seed=0)
    assert len(pe.holdout_cost) == len(pe.prediction_cost) and pe.best_step is not None


def test_training_does_not_depend_on_units():
    """u in rpm or krpm, y in mlc or Pa: the same network up to rounding (internal normalisation)."""
    rec = small_record()
    a = neural_narx(rec, **SMALL, epochs=6, sim_epochs=6, seed=0).model
    b = neural_narx(Record(rec.u * 1e-3, rec.y * 9806.65, Ts=rec.Ts), **SMALL, epochs=6, sim_epochs=6, seed=0).model
    np.testing.assert_allclose(b.W1, a.W1, rtol=1e-6, atol=1e-9)
    test = small_record(5, 200)
    ya = a.simulate(test)
    yb = b.simulate(Record(test.u * 1e-3, test.y * 9806.65, Ts=test.Ts))
    np.testing.assert_allclose(yb / 9806.65, ya, rtol=1e-7)


def test_narx_variant_and_several_records():
    recs = [small_record(1, 200), small_record(2, 200)]
    net = neural_narx(recs, ny=2, nu=2, ne=0, hidden=3, epochs=10, sim_epochs=10, seed=0).model
    assert net.ne == 0 and net.n_params == net.n_trained == 3 * 6 + 1
    yh, e = net.predict_narmax(recs[0])
    np.testing.assert_allclose(yh, net.predict(recs[0]), rtol=1e-12, atol=1e-12)  # no residual inputs: same predictor
    ds = Dataset(recs[0], recs[1])
    a = neural_narx(ds, ny=2, nu=2, ne=0, hidden=3, epochs=3, sim_epochs=3).model
    b = neural_narx(recs[0], ny=2, nu=2, ne=0, hidden=3, epochs=3, sim_epochs=3).model
    assert np.array_equal(a.W1, b.W1)  # a Dataset trains on its identification record


# -- predict / simulate against a plain loop -------------------------------------------------

def test_predict_equals_reference_loop(small_net):
    rec = small_record(7, 120)
    L = small_net.max_lag
    yh = small_net.predict(rec)
    np.testing.assert_array_equal(yh[:L], rec.y[:L])
    for k in range(L, len(rec)):
        ref = ref_output(small_net, rec.y[k - 1::-1][:2], rec.u[k - 1::-1][:2])
        assert yh[k] == pytest.approx(ref, rel=1e-12, abs=1e-12)


def test_predict_narmax_equals_reference_loop(small_net):
    rec = small_record(7, 120)
    L = small_net.max_lag
    yh, e = small_net.predict_narmax(rec)
    ref_e = np.zeros(len(rec))
    for k in range(L, len(rec)):
        el = [ref_e[k - 1 - i] if k - 1 - i >= L else 0.0 for i in range(small_net.ne)]
        ref = ref_output(small_net, rec.y[k - 1::-1][:2], rec.u[k - 1::-1][:2], el)
        ref_e[k] = rec.y[k] - ref
        assert yh[k] == pytest.approx(ref, rel=1e-12, abs=1e-12)
    np.testing.assert_allclose(e, ref_e, rtol=1e-9, atol=1e-12)


def test_simulate_equals_reference_loop(small_net):
    rec = small_record(8, 150)
    L = small_net.max_lag
    y = small_net.simulate(rec)
    ref = np.array(rec.y[:L].tolist() + [0.0] * (len(rec) - L))
    for k in range(L, len(rec)):
        ref[k] = ref_output(small_net, ref[k - 1::-1][:2], rec.u[k - 1::-1][:2])  # e ≡ 0
    np.testing.assert_allclose(y, ref, rtol=1e-11, atol=1e-11)
    # array input with explicit initial conditions gives the same run
    np.testing.assert_array_equal(small_net.simulate(rec.u, rec.y[:L]), y)


def test_divergence_contract():
    net = hand_net(3.0, 1.0)
    u = np.zeros(50)
    with pytest.raises(DivergenceError, match="sample"):
        net.simulate(u, [0.5], bound=1.0)
    y = net.simulate(u, [0.5], on_diverge="nan", bound=1.0)
    k = int(np.flatnonzero(np.isnan(y))[0])
    assert k >= 1 and np.all(np.isnan(y[k:])) and np.all(np.abs(y[:k]) <= 1.0)
    assert np.all(np.isfinite(net.simulate(u, [0.5])))  # bounded: no divergence at the default bound


# -- statics ---------------------------------------------------------------------------------

@settings(max_examples=15, deadline=None)
@given(ubar=st.floats(770.0, 1620.0), ystart=st.floats(4.0, 20.0))
def test_static_curve_is_where_a_long_free_run_settles(plant_net, ubar, ystart):
    yb = plant_net.static_curve([ubar], y0=ystart)[0]
    L = plant_net.max_lag
    run = plant_net.simulate(np.full(L + 6000, ubar), np.full(L, ystart))
    assert run[-1] == pytest.approx(yb, abs=1e-6)


def test_static_curve_follows_the_measured_points(plant_net, plant):
    yb = plant_net.static_curve(plant.static.ubar, y0=plant.static.ybar)
    # relative to the data: the bundled plant's slow disturbances bias every dynamic model's static
    # curve (ELS (15) misses the points by about 1 mlc² too); the points spread over about 30 mlc²
    assert mse(plant.static.ybar, yb) < 0.1 * np.var(plant.static.ybar)
    eq = plant_net.equilibria(1200.0)
    assert any(e.stable and e.ybar == pytest.approx(plant_net.static_curve([1200.0], y0=10.0)[0]) for e in eq)


def test_static_curve_with_two_stable_equilibria_picks_the_one_reached():
    net = hand_net(2.0, 2.0)  # y = 2 tanh(2y + 0.001u): stable ±1.9…, unstable middle root
    eq = net.equilibria(0.0)
    assert [e.stable for e in eq] == [True, False, True]
    assert eq[1].ybar == pytest.approx(0.0, abs=1e-12)
    lo, hi = eq[0].ybar, eq[2].ybar
    assert hi == pytest.approx(2.0 * math.tanh(2.0 * hi), abs=1e-12)
    np.testing.assert_allclose(net.static_curve([0.0, 0.0], y0=[1.0, -1.0]), [hi, lo], atol=1e-12)
    assert net.static_curve([0.0], y0=-0.3)[0] == pytest.approx(lo)
    with pytest.raises(ValueError, match="ū = 0.*pass y0"):
        net.static_curve([0.0])
    assert np.isnan(net.static_curve([0.0], strict=False)[0])
    # started on the unstable middle root the run stays there: no stable equilibrium is reached
    with pytest.raises(ValueError, match="did not settle"):
        net.static_curve([0.0], y0=0.0)
    assert np.isnan(net.static_curve([0.0], y0=0.0, strict=False)[0])


def test_static_curve_with_no_stable_equilibrium():
    net = hand_net(-2.0, 2.0)  # y = -2 tanh(2y): the only root 0 has a = -4 (oscillates)
    assert [e.stable for e in net.equilibria(250.0)] == [False]
    with pytest.raises(ValueError, match="no stable equilibrium at ū = 250"):
        net.static_curve([250.0])
    assert np.isnan(net.static_curve([250.0, 260.0], strict=False)).all()


def test_static_gain_matches_finite_differences(plant_net):
    ub = np.array([900.0, 1200.0, 1500.0])
    g = plant_net.static_gain(ub, y0=10.0)
    h = 1e-2
    fd = (plant_net.static_curve(ub + h, y0=10.0) - plant_net.static_curve(ub - h, y0=10.0)) / (2 * h)
    np.testing.assert_allclose(g, fd, rtol=1e-5)
    assert np.all(g > 0)  # pressure rises with pump speed


# -- on the bundled plant data ---------------------------------------------------------------

def test_default_training_matches_els15_on_the_validation_record(plant, els15):
    """The claim of the module docstring: over five seeds, the default training's free run on the
    validation record is at least as good as ELS (15)'s (the validation record is never trained on)."""
    v = plant.valid
    ref = mse(v.y, els15.simulate(v), start=els15.max_lag)
    for sd in range(5):
        net = neural_narx(plant.ident, seed=sd).model
        assert mse(v.y, net.simulate(v), start=net.max_lag) <= ref, f"seed {sd}"


def test_trained_net_on_plant_data(plant_net, plant):
    v = plant.valid
    L = plant_net.max_lag
    sim = plant_net.simulate(v)  # raises on divergence
    assert np.all(np.isfinite(sim))
    assert mse(v.y, sim, start=L) < 0.1 * np.var(v.y)
    # the re-fitted residual inputs make the NARMAX predictor better than the e ≡ 0 one
    assert mse(v.y, plant_net.predict_narmax(v)[0], start=L) < mse(v.y, plant_net.predict(v), start=L)


def test_works_with_the_shared_evaluator(plant_net, plant):
    table = evaluate({"Neural": plant_net}, plant)
    row = table.loc["Neural"]
    assert row["n_params"] == 99
    for col in ("JS_ident", "JS_valid", "JSF", "J1_ident"):
        assert np.isfinite(row[col]) and row[col] >= 0
    # relative to the data, not an absolute figure: the bundled plant's disturbances set the level
    assert row["JS_valid"] < 0.1 * np.var(plant.valid.y) and row["fit_valid"] > 70.0


def test_section_neural_reports_the_table_row(plant):
    text = section_neural(quick=True, data=plant)
    assert "Neural" in text and "JS_valid" in text and "99" in text
    assert "paper's training" in text and "seed 0" in text


# -- bad input -------------------------------------------------------------------------------

@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"ny": -1}, "ny must be an integer >= 0"),
        ({"nu": 0}, "nu must be an integer >= 1"),
        ({"hidden": 0}, "hidden must be an integer >= 1"),
        ({"epochs": 0}, "epochs must be an integer >= 1"),
        ({"seed": -1}, "seed must be"),
        ({"weight_decay": -1.0}, "weight_decay"),
        ({"sim_epochs": -1}, "sim_epochs must be an integer >= 0"),
        ({"holdout": 0.5}, "holdout"),
        ({"holdout": -0.1}, "holdout"),
        ({"patience": 3}, "patience applies to early stopping only"),
        ({"holdout": 0.2, "patience": 0}, "patience must be an integer >= 1"),
    ],
)
def test_bad_training_arguments(kwargs, match):
    with pytest.raises(ValueError, match=match):
        neural_narx(small_record(), **kwargs).model


@pytest.mark.parametrize("kwargs, match", [({"ne": 1.5}, "ne must be an integer"),
                                           ({"hidden": True}, "hidden must be an integer")])
def test_training_arguments_of_the_wrong_type(kwargs, match):
    with pytest.raises(TypeError, match=match):
        neural_narx(small_record(), **kwargs).model


def test_bad_training_data():
    with pytest.raises(ValueError, match="non-finite"):
        Record([1.0, np.nan, 3.0], [1.0, 2.0, 3.0])  # NaN never reaches the trainer
    short = small_record(0, 6)
    with pytest.raises(ValueError, match="fewer than max lag"):
        neural_narx(short, ny=6, nu=6).model
    with pytest.raises(ValueError, match="fewer than the 113 weights"):
        neural_narx(small_record(0, 100)).model
    with pytest.raises(ValueError, match="held-out parts.* fewer than the 113 weights"):
        neural_narx(small_record(0, 200), holdout=0.45).model
    two = Record(np.column_stack([small_record().u, small_record().u[::-1]]), small_record().y, input_names=("u1", "u2"))
    with pytest.raises(ValueError, match=r"neural_narx takes one input.*\('u1', 'u2'\)"):
        neural_narx(two)
    with pytest.raises(ValueError, match="holdout = 0.1 of record 'small0' .* leaves 36 training and 4 held-out"):
        neural_narx(small_record(0, 40), hidden=1, holdout=0.1).model
    flat = Record(np.full(300, 500.0), np.linspace(0, 1, 300))
    with pytest.raises(ValueError, match="input is constant"):
        neural_narx(flat, ny=1, nu=1, hidden=1).model
    with pytest.raises(TypeError, match="Record"):
        neural_narx(np.zeros((10, 2))).model  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="no records"):
        neural_narx([]).model


def test_bad_model_and_call_arguments(small_net):
    with pytest.raises(ValueError, match="W1 must have shape"):
        NeuralModel(np.zeros((2, 3)), np.zeros(2), np.zeros(2), 0.0, ny=1, nu=1)
    with pytest.raises(ValueError, match="non-finite"):
        NeuralModel(np.full((1, 2), np.nan), [0.0], [1.0], 0.0, ny=1, nu=1)
    with pytest.raises(ValueError, match="y_scale"):
        NeuralModel(np.zeros((1, 2)), [0.0], [1.0], 0.0, ny=1, nu=1, y_scale=0.0)
    u = np.full(20, 500.0)
    with pytest.raises(ValueError, match="y0 .* is required"):
        small_net.simulate(u)
    with pytest.raises(ValueError, match="y0 has 1 samples"):
        small_net.simulate(u, [1.0])
    with pytest.raises(ValueError, match="non-finite"):
        small_net.simulate(np.r_[u, np.nan], [1.0, 1.0])
    with pytest.raises(ValueError, match="on_diverge"):
        small_net.simulate(u, [1.0, 1.0], on_diverge="ignore")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="fewer than max lag"):
        small_net.simulate(u[:2], [1.0, 1.0])
    with pytest.raises(ValueError, match="ubar"):
        small_net.static_curve([np.nan])
    with pytest.raises(ValueError, match="one value per ū"):
        small_net.static_curve([300.0, 400.0, 500.0], y0=[1.0, 2.0])
    with pytest.raises(TypeError, match="Record"):  # a wrong type is a TypeError, as everywhere
        small_net.predict(u)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="fewer than max lag"):
        small_net.predict(Record([1.0, 2.0], [1.0, 2.0]))


def test_a_network_given_a_list_of_records_says_to_run_each():
    # NeuralModel.predict([a, b]) said "record must be a Record, got list" and nothing more
    net = hand_net(0.5, 1.0)
    rng = np.random.default_rng(0)
    recs = [Record(rng.uniform(0, 1, 20), rng.uniform(0, 1, 20)) for _ in range(2)]
    with pytest.raises(TypeError, match=r"once per record, \[model\.predict\(r\) for r in records\]"):
        net.predict(recs)
    with pytest.raises(TypeError, match=r"once per record, \[model\.predict_narmax\(r\) for r in records\]"):
        net.predict_narmax(recs)
    with pytest.raises(TypeError, match=r"once per record, \[model\.simulate\(r\) for r in records\]"):
        net.simulate(recs)
