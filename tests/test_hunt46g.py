"""hunt46g: the neural NARMAX baseline and the experiment's planning (design_input, decimation)."""

from __future__ import annotations

import inspect

import numpy as np
import pytest

import graybox as gb
from graybox import Record
from graybox import experiments as gx
from graybox.experiments._cell import _estimate
from graybox.experiments._spec import OPTIONS, SpecError
from test_neural import small_record  # the small network tests' plant, u in the hundreds


# -- a grid's neural options are neural_narx's ------------------------------------------------------------------

def test_every_neural_option_a_grid_accepts_is_one_neural_narx_takes():
    """The spec accepted options={"lam0": ...}, which neural_narx has no parameter for: every such cell failed
    with a TypeError at run time after the spec had been checked; sim_epochs, holdout and patience were refused."""
    takes = set(inspect.signature(gb.neural_narx).parameters)
    assert set(OPTIONS["neural"]) <= takes
    with pytest.raises(SpecError, match="lam0"):
        gx.Variant("NN", "neural", options={"lam0": 0.5})
    v = gx.Variant("NN", "neural", options={"sim_epochs": 0, "holdout": 0.25, "patience": 2})
    assert dict(v.options) == {"sim_epochs": 0, "holdout": 0.25, "patience": 2}
    with pytest.raises(SpecError, match="holdout"):
        gx.Variant("NN", "neural", options={"holdout": 0.5})
    with pytest.raises(SpecError, match="patience"):  # early stopping needs its held-out part
        gx.Variant("NN", "neural", options={"patience": 2})


def test_a_grid_cell_trains_the_network_with_its_options():
    rec = small_record()
    data = gb.Dataset(rec, small_record(1))
    v = gx.Variant("NN", "neural", options={"hidden": 2, "ne": 0, "epochs": 3, "sim_epochs": 0})
    cell = type("Cell", (), {"variant_spec": v.content(), "variant": "NN", "structure": "s", "seed": 1})()
    st = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)"])
    model = _estimate(cell, st, data)[0]
    want = gb.neural_narx(rec, ny=2, nu=1, ne=0, hidden=2, epochs=3, sim_epochs=0, seed=1).model
    assert np.array_equal(model.W1, want.W1) and model.b2 == want.b2


# -- a NeuralModel's weights are numbers ------------------------------------------------------------------------

def _net(**kw):
    args = dict(W1=np.full((2, 2), 0.1), b1=[0.0, 0.1], w2=[1.0, -0.5], b2=0.2, ny=1, nu=1)
    return gb.NeuralModel(**{**args, **kw})


@pytest.mark.parametrize("field,value", [("W1", np.full((2, 2), 0.1 + 1j)), ("W1", [["0.1", "0.2"], ["1", "2"]]),
                                         ("b1", [True, False]), ("w2", [None, 1.0]), ("b2", "0.2"), ("b2", True),
                                         ("b2", None)])
def test_a_network_refuses_weights_that_are_not_real_numbers(field, value):
    """Complex weights lost their imaginary part (a ComplexWarning), text was parsed, booleans read as 1 and 0, and
    None as NaN ("has non-finite values"): each a TypeError naming the field, as every graybox value's numbers."""
    with pytest.raises(TypeError, match=field):
        _net(**{field: value})


def test_a_network_names_a_bias_that_is_no_number():
    with pytest.raises(TypeError, match="b2"):  # was numpy's "only 0-dimensional arrays can be converted"
        _net(b2=np.array([0.1, 0.2]))
    net = _net(b2=np.float32(0.25), W1=np.ones((2, 2), dtype=np.float32))  # numbers of any real dtype
    assert net.b2 == 0.25 and net.W1.dtype == np.float64


@pytest.mark.parametrize("ubar,error", [(True, TypeError), ([300.0], TypeError), (np.array([300.0, 500.0]), TypeError),
                                        ("300", TypeError), (np.nan, ValueError)])
def test_a_network_takes_one_input_level_for_its_equilibria_as_a_model_does(ubar, error):
    """net.equilibria(True) gave the equilibria at ū = 1 and net.equilibria([300.0]) said "ubar must be 1-D, got shape
    (1, 1)"; a polynomial Model refuses both as no single input level."""
    poly = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 0.01])
    with pytest.raises(error, match="ubar"):
        poly.equilibria(ubar)
    with pytest.raises(error, match="ubar"):
        _net().equilibria(ubar)
    assert _net().equilibria(np.float32(300.0))[0].ubar == poly.equilibria(300)[0].ubar == 300.0


# -- decimation in units near the float range ------------------------------------------------------------------

def _sine_record(scale: float, offset: float = 0.0) -> Record:
    k = np.arange(4000)
    rng = np.random.default_rng(0)
    y = np.sin(2 * np.pi * k / 400) + 0.01 * rng.standard_normal(k.size)
    return Record(rng.standard_normal(k.size), y * scale + offset, Ts=0.01, units=("V", "Pa"))


@pytest.mark.parametrize("scale,offset", [(1e307, 1.5e308), (1.6e308, 0.0), (1e-310, 0.0)])
def test_decimation_works_in_any_units_of_the_output(scale, offset):
    """An output near 1.5e308 failed in decimate with "y has 20 non-finite value(s)" (its ends' reflection 2·y[0] − y
    overflowed) and warned in decimation_advice (np.ptp overflowed on a range of ±1.6e308); the filter now works in
    units of max|y| (a power of two: the same bits elsewhere), as the advice reads its autocorrelations."""
    ref = _sine_record(1.0)
    rec = _sine_record(scale, offset)
    assert gb.decimation_advice(rec) == gb.decimation_advice(ref)
    got = gb.decimate(rec, 4)
    want = gb.decimate(ref, 4)
    assert got.units == rec.units and got.Ts == want.Ts
    np.testing.assert_allclose((got.y - offset) / scale, want.y, rtol=0, atol=1e-6 if offset else 1e-12)


def test_decimating_in_units_of_max_y_leaves_ordinary_units_bit_for_bit():
    rec = _sine_record(1000.0, 1e4)
    half = 10 * 3
    from scipy.signal import firwin

    y = rec.y
    ext = np.concatenate([2 * y[0] - y[half:0:-1], y, 2 * y[-1] - y[-2:-half - 2:-1]])
    assert np.array_equal(gb.decimate(rec, 3).y, np.convolve(ext, firwin(2 * half + 1, 1 / 3), mode="valid")[::3])


# -- a NeuralFit says what a training can say -------------------------------------------------------------------

@pytest.fixture(scope="module")
def early_stopped():
    return gb.neural_narx(small_record(), ny=2, nu=2, ne=1, hidden=3, epochs=3, sim_epochs=3, holdout=0.2, seed=0)


@pytest.mark.parametrize("field,value,match", [("epochs", -1, "epochs"), ("best_step", 99, "best_step"),
                                               ("best_step", None, "best_step"), ("stopped", "xyz", "stopped"),
                                               ("rmse_train", -1.0, "rmse_train"),
                                               ("rmse_sim", float("nan"), "rmse_sim"),
                                               ("prediction_cost", [], "prediction_cost"),
                                               ("holdout_cost", [1.0, -2.0], "holdout_cost"),
                                               ("seconds", -0.5, "seconds")])
def test_a_neural_fit_file_that_no_training_could_write_is_refused(early_stopped, field, value, match):
    """A NeuralFit file edited to say epochs = -1, a best step past its held-out costs (or none beside them), an
    unknown reason to stop, a negative RMSE or cost loaded without a word (as OEResult and Decision refuse theirs)."""
    import json

    doc = json.loads(gb.to_json(early_stopped))
    doc["object"][field] = value
    with pytest.raises(gb.GrayboxFileError, match=match):
        gb.from_json(json.dumps(doc))


def test_a_neural_fit_reads_back_as_written(early_stopped):
    back = gb.from_json(gb.to_json(early_stopped))
    assert back.best_step == early_stopped.best_step is not None
    assert back.holdout_cost == early_stopped.holdout_cost and back.stopped == early_stopped.stopped
    plain = gb.neural_narx(small_record(), ny=2, nu=2, ne=0, hidden=2, epochs=2, sim_epochs=0)
    assert gb.from_json(gb.to_json(plain)).best_step is None


# -- a training's course does not depend on the units ----------------------------------------------------------

@pytest.mark.parametrize("options", [dict(ny=2, nu=2, ne=1, hidden=3, epochs=5, sim_epochs=10),
                                     dict(ny=1, nu=1, ne=0, hidden=2, epochs=30, sim_epochs=80),
                                     dict(ny=2, nu=1, ne=2, hidden=2, epochs=40, sim_epochs=0)])
def test_the_training_takes_the_same_steps_in_any_units(options):
    """Once a stage had converged, its further trial steps were kept or refused by the rounding of the cost alone,
    which differs with the units: 10 of 18 small trainings (3 sizes × 6 seeds) reported other epochs, other numbers
    of accepted steps (so weights apart by rounding) in krpm and mPa, or with offsets, than in rpm and Pa (35 against 23
    epochs). A step whose predicted decrease is rounding of the cost now ends the stage as converged."""
    for seed in range(3):
        rec = small_record(seed, 300)
        runs = [gb.neural_narx(Record(rec.u * us + uo, rec.y * ys + yo, Ts=rec.Ts), **options, seed=seed)
                for us, uo, ys, yo in [(1.0, 0.0, 1.0, 0.0), (1e3, 0.0, 1e-3, 0.0), (1.0, 1e4, 7.0, 1e4),
                                       (1e-3, 0.0, 1e3, -50.0)]]
        course = {(f.epochs, f.stopped, len(f.prediction_cost), len(f.simulation_cost)) for f in runs}
        assert len(course) == 1, course
        np.testing.assert_allclose(runs[1].model.W1, runs[0].model.W1, rtol=1e-7, atol=1e-9)


# -- design_input reads a pair as it reads a range --------------------------------------------------------------

def test_a_multisine_band_and_an_aprbs_hold_may_be_any_pair_of_numbers():
    """frequencies=pd.Series([0.1, 0.5]) was refused with "frequencies must be a pair (f_low, f_high)" (and hold= a
    Series or range with "hold must be an integer"), though low= and high= take a Series of df.min()."""
    import pandas as pd

    want = gb.design_input("multisine", 400, low=0.0, high=1.0, frequencies=(0.1, 0.5))
    assert np.array_equal(gb.design_input("multisine", 400, low=0.0, high=1.0,
                                          frequencies=pd.Series([0.1, 0.5])), want)
    want = gb.design_input("aprbs", 400, low=0.0, high=1.0, hold=(5, 20), seed=2)
    for pair in (pd.Series([5, 20]), range(5, 21, 15)):
        assert np.array_equal(gb.design_input("aprbs", 400, low=0.0, high=1.0, hold=pair, seed=2), want)
    for bad in ("ab", {"a": 1}, {0.1, 0.5}, 0.5):
        with pytest.raises(TypeError, match="frequencies"):
            gb.design_input("multisine", 400, low=0.0, high=1.0, frequencies=bad)
    with pytest.raises(ValueError, match="frequencies"):
        gb.design_input("multisine", 400, low=0.0, high=1.0, frequencies=[0.1, 0.2, 0.3])
