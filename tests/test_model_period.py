"""A model knows the sampling period it was identified at, and refuses a record sampled at another:
a discrete-time model holds at one period (graybox.Model.Ts, NeuralModel.Ts)."""

from __future__ import annotations

import dataclasses
import json
import warnings

import numpy as np
import pytest

import graybox as gb


def _records(Ts: float, n: int = 400, seed: int = 0) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.0, 1.0, n // 10), 10)
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = 0.6 * y[k - 1] + 0.2 * y[k - 2] + 0.3 * u[k - 1] + 0.05 * u[k - 2] ** 2 + 0.4
    return gb.Record(u, y + 0.01 * rng.standard_normal(n), Ts=Ts)


ST = gb.Structure(["1", "y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2"])


def test_every_estimator_gives_its_model_the_records_period():
    rec = _records(0.1)
    data = gb.Dataset(rec, _records(0.1, seed=1), gb.StaticPoints(np.array([0.2, 0.5, 0.8]),
                                                                  np.array([2.3, 2.7, 3.1])))
    cand = gb.Candidates(2, 2, degree=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        models = {
            "frols": gb.frols(cand, data, n_terms=5).model,
            "semp": gb.semp(cand, data, n_terms=4).model,
            "els": gb.els(ST, data).model,
            "pe": gb.pe_pareto(ST, data, lambdas=[1.0, 0.1]).member_model(0),
            "se": gb.se_pareto(ST, data, lambdas=[1.0, 0.5], method="gradient").member_model(1),
            "output_error": gb.output_error(ST, data, n_starts=1).model,
            "neural": gb.neural_narx(rec, ny=2, nu=2, ne=0, hidden=2, epochs=2, sim_epochs=2, seed=0).model,
        }
    for name, m in models.items():
        assert m.Ts == 0.1, name
        m.simulate(data.valid, on_diverge="nan")  # the same period: fine
        other = gb.Record(data.valid.u, data.valid.y, Ts=0.2, name="fast logger")
        with pytest.raises(ValueError, match=r"every 0\.1 s but 'fast logger' every 0\.2 s"):
            m.simulate(other)
        with pytest.raises(ValueError, match="every 0.1 s"):
            gb.js(m, other)
        with pytest.raises(ValueError, match="every 0.1 s"):
            gb.evaluate({name: m}, gb.Dataset(other, other, None))


def test_a_model_without_a_period_is_used_at_any_and_a_file_from_before_reads_as_unknown():
    m = gb.Model(ST, np.array([0.4, 0.6, 0.2, 0.3, 0.05]))
    assert m.Ts is None
    for Ts in (0.1, 7.0):
        m.simulate(_records(Ts))
    known = gb.Model(ST, m.theta, Ts=0.1)
    back = gb.from_json(gb.to_json(known))
    assert back.Ts == 0.1 and back.with_theta(m.theta).Ts == 0.1
    doc = json.loads(gb.to_json(known))
    del doc["object"]["Ts"]
    assert gb.from_json(json.dumps(doc)).Ts is None
    with pytest.raises(ValueError, match="Ts"):
        gb.Model(ST, m.theta, Ts=0.0)


def test_a_choosing_record_at_another_period_is_refused():
    data = gb.Dataset(_records(0.1), _records(0.1, seed=1), gb.StaticPoints(np.array([0.2, 0.5, 0.8]),
                                                                            np.array([2.3, 2.7, 3.1])))
    front = gb.pe_pareto(ST, data, lambdas=[1.0, 0.1, 0.01])
    assert front.Ts == 0.1 and gb.from_json(gb.to_json(front)).Ts == 0.1
    gb.decide_dsf(front, band=1.0, choose_on=_records(0.1, seed=2))
    with pytest.raises(ValueError, match="fitted on records sampled every 0.1 s"):
        gb.decide_dsf(front, band=1.0, choose_on=_records(0.05, seed=2))


def test_a_local_model_takes_the_period_the_model_was_identified_at():
    pytest.importorskip("control")
    m = gb.els(ST, gb.Dataset(_records(0.1), _records(0.1, seed=1), None)).model
    lm = gb.local_model(m, 0.5)
    assert lm.Ts == 0.1 and lm.to_statespace().dt == 0.1
    # given at another period: refused (Ts=100 meant as ms beside a 0.1 s model gave τ 1000 times too long), but
    # over a model's 1 s, the period of records made without Ts=, it is the user's word
    with pytest.raises(ValueError, match=r"Ts = 100 s, but model .* identified at Ts = 0.1 s.*dataclasses.replace"):
        gb.local_model(m, 0.5, Ts=100)
    assert gb.local_model(m, 0.5, Ts=0.1).Ts == 0.1
    assert gb.local_model(dataclasses.replace(m, Ts=1.0), 0.5, Ts=0.2).Ts == 0.2
    with pytest.raises(ValueError, match="Ts .*is needed"):
        gb.local_model(gb.Model(m.structure, m.theta), 0.5)  # a hand-made model: no period known


def test_a_models_repr_says_its_period_and_a_networks_its_input():
    m = gb.Model(ST, np.array([0.4, 0.6, 0.2, 0.3, 0.05]), name="M", Ts=0.1)
    assert "Ts=0.1 s" in repr(m) and "Ts=" not in repr(gb.Model(ST, m.theta))
    net = gb.neural_narx(gb.Record(_records(0.1).u, _records(0.1).y, Ts=0.1, input_names=("speed",)), ny=2, nu=2,
                         ne=0, hidden=2, epochs=2, sim_epochs=2, seed=0).model
    assert "input='speed'" in repr(net) and "Ts=0.1 s" in repr(net)


def test_a_local_model_refuses_data_at_another_period_than_its_model():
    # the model's coefficients a_l hold per step of the period it was identified at: data at another period
    # cannot lend the local model theirs (an explicit Ts= stays the user's word)
    m = gb.els(ST, gb.Dataset(_records(0.1), _records(0.1, seed=1), None)).model
    assert gb.local_model(m, 0.5, data=_records(0.1, seed=2)).Ts == 0.1
    with pytest.raises(ValueError, match="every 0.1 s"):
        gb.local_model(m, 0.5, data=_records(0.2, seed=2))
    assert gb.local_model(gb.Model(m.structure, m.theta), 0.5, data=_records(0.2, seed=2)).Ts == 0.2


def test_records_whose_periods_drift_past_the_tolerance_are_refused_in_any_order():
    # each record was held to the first alone: 0.1, 0.10009 and 0.10018 s (the last two each within 1e-3 of the middle
    # one, 1.8e-3 apart) were one period listed from the middle and refused listed from the end
    import itertools

    import dask.array as da

    recs = [dataclasses.replace(_records(0.1, seed=s), Ts=0.1 * (1 + 0.9e-3 * s), name=f"r{s}") for s in range(3)]
    for order in itertools.permutations(recs):
        with pytest.raises(ValueError, match=r"'r[02]' is sampled every 0\.1(0018)? s but 'r[02]' every"):
            gb.cls(ST, list(order))
    drecs = [gb.DaskRecord(da.from_array(r.u, chunks=100), da.from_array(r.y, chunks=100), Ts=r.Ts, name=r.name)
             for r in recs]
    with pytest.raises(ValueError, match="'r[02]' is sampled every"):
        gb.pe_thetas(ST, [drecs[1], drecs[0], drecs[2]], lambdas=[1.0])
    # a choosing record is held to every fitting record, not to the first alone
    with pytest.raises(ValueError, match="'r0' is sampled every 0.1 s but 'r2' every"):
        gb.output_error(ST, [recs[1], recs[0]], choose_on=recs[2], n_starts=0)
    assert gb.cls(ST, [recs[1], recs[0]]).model.Ts == recs[1].Ts  # within the tolerance: one period
