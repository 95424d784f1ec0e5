"""A record too short for the lags, among several, is named by its position (records made or loaded without a
name are all called "record")."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb


def _record(n: int, seed: int = 0) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0, 1, n // 5 + 1), 5)[:n]
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.7 * y[k - 1] + 0.5 * u[k - 1] + 0.01 * rng.standard_normal()
    return gb.Record(u, y, Ts=0.1)


@pytest.mark.parametrize("call", [
    lambda recs: gb.frols(gb.Candidates(2, 2, degree=2), recs, n_terms=3),
    lambda recs: gb.semp(gb.Candidates(2, 2, degree=2), recs, max_terms=3),
    lambda recs: gb.els(["y(k-1)", "u(k-1)"], recs),
    lambda recs: gb.cls(["1", "y(k-2)", "u(k-1)"], recs),
])
def test_a_short_record_among_several_is_named_by_its_position(call):
    # was: "record: record has 2 samples, fewer than max lag + 1 = 3", of three records all named "record"
    recs = [_record(300), _record(200, seed=1), _record(2, seed=2)]
    with pytest.raises(ValueError, match=r"record 3 of 3 \('record'\) has 2 samples, fewer than max lag \+ 1 = 3"):
        call(recs)
    with pytest.raises(ValueError, match=r"^record: record has 2 samples"):  # alone, as before
        call(recs[2])


def test_a_short_choosing_record_is_said_to_be_one_not_a_fitting_record():
    # was "record 2 of 2 ('record') has 2 samples …", beside two fitting records all named "record": the second of
    # those was the one blamed
    fit = [_record(300), _record(200, seed=1)]
    choose = [_record(150, seed=3), _record(2, seed=2)]
    st = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)"])
    front = gb.ParetoSet.from_thetas(st, np.array([[0.7, 0.0, 0.5], [0.6, 0.1, 0.5]]), np.array([1.0, 0.5]), fit,
                                     gb.StaticPoints([0.2, 0.8], [0.35, 1.4]))
    for call in (lambda c: gb.output_error(st, fit, choose_on=c, n_starts=0),
                 lambda c: gb.decide_dsf(front, band=1.0, choose_on=c)):
        with pytest.raises(ValueError, match=r"^choose_on: choosing record 2 of 2 \('record'\) has 2 samples, fewer "
                                             r"than max lag \+ 1 = 3"):
            call(choose)
        with pytest.raises(ValueError, match=r"^choose_on: the choosing record 'record' has 2 samples"):
            call(choose[1])


def test_a_record_too_short_for_the_neural_holdout_among_several_is_named_by_its_position():
    # was "holdout = 0.2 of record 'record' (12 samples) …" of three records all named "record"
    recs = [_record(300), _record(12, seed=2), _record(200, seed=1)]
    with pytest.raises(ValueError, match=r"holdout = 0\.2 of record 2 of 3 \('record', 12 samples\) leaves 10 "):
        gb.neural_narx(recs, ny=2, nu=2, ne=0, hidden=2, epochs=1, sim_epochs=0, holdout=0.2)
    with pytest.raises(ValueError, match=r"holdout = 0\.2 of record 'record' \(12 samples\)"):  # alone, as before
        gb.neural_narx(recs[1], ny=2, nu=2, ne=0, hidden=2, epochs=1, sim_epochs=0, holdout=0.2)


def test_records_that_disagree_among_several_are_named_by_their_positions():
    # was "'record' has inputs ('u',) but 'record' has inputs ('u1', 'u2')" and "'record' is sampled every 0.1 s but
    # 'record' every 0.2 s", of three records all named "record"
    rng = np.random.default_rng(0)
    two = gb.Record(rng.uniform(size=(50, 2)), rng.uniform(size=50), Ts=0.1)
    slow = gb.Record(rng.uniform(size=50), rng.uniform(size=50), Ts=0.2)
    recs = [_record(300), _record(200, seed=1)]
    with pytest.raises(ValueError, match=r"^data: records 1 and 3 of 3: 'record' has inputs \('u',\) but 'record' "
                                         r"has inputs \('u1', 'u2'\)"):
        gb.cls(["y(k-1)", "u(k-1)"], recs + [two])
    with pytest.raises(ValueError, match=r"^data: records 1 and 2 of 3: 'record' is sampled every 0\.1 s but "
                                         r"'record' every 0\.2 s"):
        gb.cls(["y(k-1)", "u(k-1)"], [recs[0], slow, recs[1]])


def test_static_points_left_with_the_default_names_beside_named_records_are_told_to_name_them():
    # StaticPoints(df[["speed", "valve"]], ȳ) reads the frame by position, names u1, u2: refused beside records of
    # the inputs speed, valve with "… has inputs ('u1', 'u2')" and no word of how to name them
    import pandas as pd

    rng = np.random.default_rng(0)
    rec = gb.Record(rng.uniform(size=(60, 2)), rng.uniform(size=60), input_names=("speed", "valve"))
    levels = pd.DataFrame({"speed": [0.1, 0.5, 0.9], "valve": [0.2, 0.2, 0.8]})
    # a frame's columns now name its inputs (mend61e), as a dict's keys do: these points meet the records
    assert gb.Dataset(rec, rec, gb.StaticPoints(levels, [1.0, 2.0, 3.0])).static.input_names == ("speed", "valve")
    points = gb.StaticPoints(levels.to_numpy(), [1.0, 2.0, 3.0])  # an array's columns have no names
    with pytest.raises(ValueError, match=r"has inputs \('u1', 'u2'\).*default names: name them, e\.g\. "
                                         r"StaticPoints\(\.\.\., input_names=\('speed', 'valve'\)\)"):
        gb.Dataset(rec, rec, points)
    plain = gb.Record(rec.u, rec.y)
    with pytest.raises(ValueError, match=r"e\.g\. Record\(\.\.\., input_names=\('speed', 'valve'\)\)"):
        gb.cls(["y(k-1)", "speed(k-1)"], [rec, plain])
