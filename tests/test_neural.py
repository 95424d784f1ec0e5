"""The neural NARMAX baseline (graybox.neural)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from graybox import Record
from graybox.datasets import load_pumping
from graybox._evaluate import evaluate, mse
from graybox._neural import (
    NeuralModel,
    _pe_jacobian_kernel,
    _pe_kernel,
    _unpack,
    neural_narx,
)
from graybox.reproduce import section_neural
from graybox._records import Dataset
from graybox._simulation import DivergenceError

# Few epochs keep the suite fast; 20 epochs from seed 0 already give a stable, accurate net.
PLANT_EPOCHS = 20


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
    return neural_narx(plant.ident, epochs=PLANT_EPOCHS, seed=0, name="Neural").model


@pytest.fixture(scope="module")
def small_net():
    return neural_narx(small_record(), ny=2, nu=2, ne=1, hidden=3, epochs=15, seed=1).model


# -- parameter count and immutability --------------------------------------------------------

def test_n_params_is_99_for_the_paper_sizes(plant_net):
    net = NeuralModel(np.zeros((7, 14)), np.zeros(7), np.zeros(7), 0.0, ny=6, nu=6, ne=2)
    assert net.n_params == 99 == 12 * 7 + 7 + 7 + 1
    assert net.n_trained == 113
    assert plant_net.n_params == 99 and plant_net.max_lag == 6
    assert neural_narx(small_record(), ny=6, nu=6, ne=0, hidden=7, epochs=1).model.n_params == 99


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
    a = neural_narx(rec, ny=2, nu=2, ne=1, hidden=3, epochs=8, seed=3).model
    b = neural_narx(rec, ny=2, nu=2, ne=1, hidden=3, epochs=8, seed=3).model
    c = neural_narx(rec, ny=2, nu=2, ne=1, hidden=3, epochs=8, seed=4).model
    for f in ("W1", "b1", "w2"):
        assert np.array_equal(getattr(a, f), getattr(b, f))
    assert a.b2 == b.b2
    assert not np.array_equal(a.W1, c.W1)


def test_training_cost_decreases_and_info_is_consistent():
    rec = small_record()
    info = neural_narx(rec, ny=2, nu=2, ne=1, hidden=3, epochs=15, seed=0)
    net = info.model
    assert info.epochs == len(info.cost) == len(info.lam) <= 15
    assert np.all(np.diff(info.cost) <= 0)  # only improving steps are kept
    assert 0 < info.accepted <= info.epochs
    _, e = net.predict_narmax(rec)
    assert info.rmse_train == pytest.approx(np.sqrt(np.mean(e[net.max_lag:] ** 2)), rel=1e-9)
    assert info.cost[-1] == pytest.approx(0.5 * np.sum((e / net.y_scale) ** 2), rel=1e-9)


def test_jacobian_matches_finite_differences_across_two_records():
    """ψ = dŷ/dθ including the residual feedback, with the recursion restarting per record."""
    rng = np.random.default_rng(0)
    ny, nu, ne, H = 2, 1, 2, 3
    n_in = ny + nu + ne
    P = H * (n_in + 2) + 1
    theta = rng.uniform(-0.5, 0.5, P)
    un = rng.standard_normal(60)
    yn = rng.standard_normal(60)
    seg = np.array([0, 25, 60], dtype=np.int64)
    mask = np.ones(60, bool)
    mask[[0, 1, 25, 26]] = False

    def yhat(th):
        W1, b1, w2, b2 = _unpack(th, H, n_in)
        return _pe_kernel(W1, b1, w2, b2, un, yn, seg, ny, nu, ne)[0][mask]

    W1, b1, w2, b2 = _unpack(theta, H, n_in)
    _, e = _pe_kernel(W1, b1, w2, b2, un, yn, seg, ny, nu, ne)
    psi = _pe_jacobian_kernel(W1, b1, w2, un, yn, e, seg, ny, nu, ne)
    fd = np.empty_like(psi)
    for p in range(P):
        d = np.zeros(P)
        d[p] = 1e-6
        fd[:, p] = (yhat(theta + d) - yhat(theta - d)) / 2e-6
    np.testing.assert_allclose(psi, fd, rtol=1e-5, atol=1e-8)


def test_narx_variant_and_several_records():
    recs = [small_record(1, 200), small_record(2, 200)]
    net = neural_narx(recs, ny=2, nu=2, ne=0, hidden=3, epochs=10, seed=0).model
    assert net.ne == 0 and net.n_params == net.n_trained == 3 * 6 + 1
    yh, e = net.predict_narmax(recs[0])
    np.testing.assert_allclose(yh, net.predict(recs[0]), rtol=1e-12)  # no residual inputs: same predictor
    ds = Dataset(recs[0], recs[1])
    a = neural_narx(ds, ny=2, nu=2, ne=0, hidden=3, epochs=3).model
    b = neural_narx(recs[0], ny=2, nu=2, ne=0, hidden=3, epochs=3).model
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
    assert mse(plant.static.ybar, yb) < 1.0  # mlc², against a spread of about 30 mlc²
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

def test_trained_net_on_plant_data(plant_net, plant):
    v = plant.valid
    L = plant_net.max_lag
    sim = plant_net.simulate(v)  # raises on divergence
    assert np.all(np.isfinite(sim))
    js_valid = mse(v.y, sim, L)
    assert js_valid < 0.1 * np.var(v.y)
    # one-step prediction beats persistence y(k) = y(k-1)
    j1 = mse(v.y, plant_net.predict(v), L)
    persistence = mse(v.y[L:], v.y[L - 1:-1])
    assert j1 < persistence


def test_works_with_the_shared_evaluator(plant_net, plant):
    table = evaluate({"Neural": plant_net}, plant)
    row = table.loc["Neural"]
    assert row["N_p"] == 99
    for col in ("J_S ident", "J_S valid", "J_SF", "J_1 ident"):
        assert np.isfinite(row[col]) and row[col] >= 0
    # relative to the data, not an absolute figure: the bundled plant's disturbances set the level
    assert row["J_S valid"] < 0.1 * np.var(plant.valid.y) and row["fit % valid"] > 70.0


def test_section_neural_reports_the_table_row(plant):
    text = section_neural(quick=True, data=plant)
    assert "Neural" in text and "J_S valid" in text and "99" in text


# -- bad input -------------------------------------------------------------------------------

@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"ny": -1}, "ny must be an integer >= 0"),
        ({"nu": 0}, "nu must be an integer >= 1"),
        ({"ne": 1.5}, "ne must be an integer"),
        ({"hidden": 0}, "hidden must be an integer >= 1"),
        ({"hidden": True}, "hidden must be an integer"),
        ({"epochs": 0}, "epochs must be an integer >= 1"),
        ({"seed": -1}, "seed must be"),
        ({"weight_decay": -1.0}, "weight_decay"),
        ({"lam0": 0.0}, "lam0"),
    ],
)
def test_bad_training_arguments(kwargs, match):
    with pytest.raises(ValueError, match=match):
        neural_narx(small_record(), **kwargs).model


def test_bad_training_data():
    with pytest.raises(ValueError, match="non-finite"):
        Record([1.0, np.nan, 3.0], [1.0, 2.0, 3.0])  # NaN never reaches the trainer
    short = small_record(0, 6)
    with pytest.raises(ValueError, match="fewer than max lag"):
        neural_narx(short, ny=6, nu=6).model
    with pytest.raises(ValueError, match="fewer than the 113 weights"):
        neural_narx(small_record(0, 100)).model
    flat = Record(np.full(300, 500.0), np.linspace(0, 1, 300))
    with pytest.raises(ValueError, match="input is constant"):
        neural_narx(flat, ny=1, nu=1, hidden=1).model
    with pytest.raises(ValueError, match="Record"):
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
    with pytest.raises(ValueError, match="Record"):
        small_net.predict(u)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="fewer than max lag"):
        small_net.predict(Record([1.0, 2.0], [1.0, 2.0]))
