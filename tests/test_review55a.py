"""review55a: regressions found reviewing c924f2a … 531b15e."""

import copy
import pickle

import numpy as np
import pytest

import graybox as gb


def _cannot_be_made_writeable(a, name):
    for target in (a, a.base):
        if isinstance(target, np.ndarray):
            with pytest.raises(ValueError, match="WRITEABLE"):
                target.flags.writeable = True
    assert not a.flags.writeable, name


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
