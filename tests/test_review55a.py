"""review55a: regressions found reviewing c924f2a … 531b15e."""

import copy
import pickle
import re

import numpy as np
import pytest

import graybox as gb
from test_review54a import _cannot_be_made_writeable


@pytest.mark.parametrize("how", [lambda o: pickle.loads(pickle.dumps(o)), copy.deepcopy], ids=["pickle", "deepcopy"])
def test_a_datasets_extra_keeps_its_arrays_locked_through_pickle_and_deepcopy(how):
    """2436e7f (Relocked) locks the arrays of a value restored from a pickle or a deep copy again, but Dataset was left
    out: its extra's arrays came back writeable (pickle.loads(pickle.dumps(data)).extra['curve'][0] = 5 edited a
    frozen value), in lists, tuples and maps inside it too."""
    rec = gb.Record(np.linspace(0.0, 1.0, 12), np.linspace(1.0, 2.0, 12), name="r")
    data = gb.Dataset(rec, rec, extra={"curve": np.arange(3.0), "runs": [np.ones(2)], "pair": (np.zeros(2),),
                                       "map": {"x": np.ones(2)}})
    d2 = how(data)
    arrays = {"extra['curve']": d2.extra["curve"], "extra['runs'][0]": d2.extra["runs"][0],
              "extra['pair'][0]": d2.extra["pair"][0], "extra['map']['x']": d2.extra["map"]["x"]}
    for name, a in arrays.items():
        _cannot_be_made_writeable(a, name)
    assert np.array_equal(d2.extra["curve"], [0.0, 1.0, 2.0]) and np.array_equal(d2.extra["map"]["x"], [1.0, 1.0])


def test_a_copy_shares_the_locked_arrays_it_cannot_change():
    """Relocked (2436e7f) copied every array of a value restored by copy.copy, or from a protocol-5 pickle (Dask's),
    though nothing can make those writeable (read-only over bytes): copy.copy(model) took 4× as long, and a Dask
    worker's records were copied twice. Such arrays are kept as they come; the value stays locked."""
    rec = gb.Record(np.linspace(0.0, 1.0, 12), np.linspace(1.0, 2.0, 12), name="r")
    model = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0])
    assert copy.copy(rec).y is rec.y and copy.copy(model).theta is model.theta
    r5 = pickle.loads(pickle.dumps(rec, protocol=5))
    for name, a in {"copy.copy Record.y": copy.copy(rec).y, "protocol 5 Record.u": r5.u}.items():
        _cannot_be_made_writeable(a, name)
    assert np.array_equal(r5.y, rec.y)


def _bytes_under(a):
    base = a.base
    while isinstance(base, np.ndarray):
        base = base.base
    return base


@pytest.mark.parametrize("protocol", range(pickle.HIGHEST_PROTOCOL + 1))
def test_values_pickle_and_copy_their_locked_arrays_as_bytes_not_copied_again(protocol, monkeypatch):
    """Relocked (2436e7f) locked a restored value's arrays by copying each: numpy's own pickling (protocols below 5)
    and deep copying give an array owning its memory, which could be made writeable again, so pickle.loads of a
    Record of 24 MB took about ten times as long and copy.deepcopy copied its samples twice. Below protocol 5 the
    arrays now travel as their bytes, which come back locked as they are (nothing is copied to lock them); a deep copy
    shares them (no one can change them)."""
    from graybox.core import _validation

    rng = np.random.default_rng(0)
    rec = gb.Record(rng.standard_normal((50, 2)), rng.standard_normal(50), input_names=("a", "b"), name="r")
    data = pickle.dumps(rec, protocol=protocol)
    copies = []
    monkeypatch.setattr(_validation, "locked", lambda a: copies.append(a) or _validation.frozen(a, a.dtype))
    back = pickle.loads(data)
    deep = copy.deepcopy(rec)
    monkeypatch.undo()
    assert copies == []
    for name, a in {"Record.u": back.u, "Record.y": back.y, "deep copy's Record.y": deep.y}.items():
        _cannot_be_made_writeable(a, name)
    assert np.array_equal(back.u, rec.u) and np.array_equal(back.y, rec.y) and back.input_names == ("a", "b")
    assert _bytes_under(deep.y) is _bytes_under(rec.y) and np.array_equal(deep.u, rec.u)


def test_a_gap_in_a_toa5_files_large_record_numbers_is_said_with_the_numbers_themselves(tmp_path):
    """31dcc64 names the RECORD numbers either side of a gap with %g: a logger's record numbers pass a million after
    twelve days at 1 Hz, and the gap from 1234568 to 1234570 read 'jumps from 1.23457e+06 (line 7) to 1.23457e+06
    (line 8)', the same number twice; a gap of 2345678 records '2.34568e+06 record(s) missing'."""
    head = ('"TOA5","st","CR1000","1","os","prog","sig","T1"\n"TIMESTAMP","RECORD","u","y"\n"TS","RN","V","C"\n'
            '"","","Smp","Smp"\n')
    for numbers, said in (([1234567, 1234568, 1234570], "jumps from 1234568 (line 6) to 1234570 (line 7): 1 record"),
                          ([7, 2345686], "jumps from 7 (line 5) to 2345686 (line 6): 2345678 record"),
                          ([1234568, 1234568], "goes back from 1234568 (line 5) to 1234568 (line 6)")):
        f = tmp_path / "big.dat"
        f.write_text(head + "".join(f'"2026-01-01 00:00:0{i}",{r},{i},{2 * i}\n' for i, r in enumerate(numbers)))
        with pytest.raises(ValueError, match=re.escape(said)):
            gb.load_record_csv(f, u="u", y="y", Ts=1.0)
