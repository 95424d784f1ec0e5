"""Models and results are immutable values, all the way down: every field of every value graybox
returns is frozen (a dataclass field cannot be reassigned, an array cannot be written, a mapping
cannot be changed), and a table a result holds cannot be changed through what a user reads of it."""

import dataclasses
import sys
import types
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import graybox as gb
import graybox.experiments as gx
from graybox.core._validation import FrozenFrame, FrozenMap
from graybox.experiments._spec import FrozenDict

sys.path.insert(0, str(Path(__file__).parent))
import test_io  # noqa: E402  (its fixture builds one value of every savable type)
import test_selection_plot  # noqa: E402


@pytest.fixture(scope="module")
def values():
    out = dict(test_io.values.__wrapped__())
    gray, black = test_selection_plot.selections.__wrapped__()
    out["gray selection"], out["black selection"] = gray, black
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out["residual tests"] = gb.residual_tests(out["model"], test_io.record(seed=2))
    return out


def _holes(obj, path, seen, out):
    """Every place under ``obj`` a user could change: (path, what)."""
    if id(obj) in seen:
        return
    seen.add(id(obj))
    if isinstance(obj, np.ndarray):
        if obj.flags.writeable and obj.size:
            out.append((path, "a writable array"))
        if obj.dtype == object:
            for i, x in enumerate(obj.ravel()):
                _holes(x, f"{path}[{i}]", seen, out)
    elif isinstance(obj, (pd.DataFrame, pd.Series)):
        out.append((path, f"a {type(obj).__name__} held as itself"))
    elif isinstance(obj, (list, dict, set, bytearray)) and not isinstance(obj, FrozenDict):
        out.append((path, f"a {type(obj).__name__}"))
    if isinstance(obj, (list, tuple)):
        for i, x in enumerate(obj):
            _holes(x, f"{path}[{i}]", seen, out)
    elif isinstance(obj, (dict, types.MappingProxyType, FrozenMap)):
        for k, x in obj.items():
            _holes(x, f"{path}[{k!r}]", seen, out)
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        if not obj.__dataclass_params__.frozen:
            out.append((path, "a dataclass that is not frozen"))
        for f in dataclasses.fields(obj):
            if isinstance(type(obj).__dict__.get(f.name), FrozenFrame):
                continue  # read below: a fresh copy at every read
            _holes(getattr(obj, f.name), f"{path}.{f.name}", seen, out)


def test_no_value_has_a_field_a_user_could_change(values):
    out = []
    for name, v in values.items():
        _holes(v, name, set(), out)
    assert out == []


def _frame_fields(v):
    return [f.name for f in dataclasses.fields(v) if isinstance(type(v).__dict__.get(f.name), FrozenFrame)]


def test_every_table_a_result_holds_is_a_frozen_frame(values):
    # the classes that hold tables (a DataFrame annotation) declare them as FrozenFrame fields
    kinds = set()
    for v in values.values():
        for f in dataclasses.fields(v):
            if f.type in ("pd.DataFrame", pd.DataFrame):
                assert isinstance(type(v).__dict__.get(f.name), FrozenFrame), (type(v).__name__, f.name)
                kinds.add(type(v).__name__)
    assert {"OEResult", "SEMPResult", "GrayboxSelection"} <= kinds


def test_changing_a_table_one_read_never_changes_the_result(values):
    checked = 0
    for name, v in values.items():
        for field in _frame_fields(v):
            before = getattr(v, field)
            t = getattr(v, field)
            if len(t) and len(t.columns):
                num = pd.api.types.is_numeric_dtype(t.dtypes.iloc[0])
                t.iloc[0, 0] = -12345 if num else "changed"
            t["new column"] = 1
            del t[t.columns[-2]]
            after = getattr(v, field)
            pd.testing.assert_frame_equal(after, before)
            assert "new column" not in after.columns
            with pytest.raises(dataclasses.FrozenInstanceError):
                setattr(v, field, t)
            checked += 1
    assert checked >= 4


def test_the_selection_s_methods_read_its_own_table_not_a_changed_copy(values):
    sel = values["gray selection"]
    chosen = sel.chosen.name
    want = sel.model_of(chosen, sel.chosen["estimator"]).theta
    t = sel.table
    t["theta"] = ""  # what a user does to the table read
    t["rank"] = 99
    assert sel.chosen.name == chosen
    np.testing.assert_array_equal(sel.model_of(chosen, sel.chosen["estimator"]).theta, want)
    assert np.isfinite(sel.regret)


def test_a_frame_handed_to_the_constructor_is_copied_in(values):
    oe = values["oe"]
    starts = oe.starts
    made = dataclasses.replace(oe, starts=starts)
    starts.loc[starts.index[0], "JS"] = -1.0  # the caller's frame, changed after the result was made
    assert made.starts["JS"].iloc[0] == oe.starts["JS"].iloc[0] != -1.0


def test_a_table_field_takes_only_a_data_frame(values):
    with pytest.raises(TypeError, match="starts must be a pandas DataFrame"):
        dataclasses.replace(values["oe"], starts=[{"start": "x"}])


def test_results_with_tables_still_pickle_and_save(values, tmp_path):
    import pickle  # the library never loads with pickle; values must still travel to Dask workers

    for name in ("oe", "semp", "gray selection"):
        v = values[name]
        back = pickle.loads(pickle.dumps(v))
        for field in _frame_fields(v):
            pd.testing.assert_frame_equal(getattr(back, field), getattr(v, field))
    p = gb.save(values["gray selection"], tmp_path / "sel.json")
    pd.testing.assert_frame_equal(gb.load(p).table, values["gray selection"].table)


def test_grid_counts_are_frozen_even_from_a_plain_dict():
    counts = {"ok": 2}
    run = gx.GridRun("s.sqlite", "g", 2, 2, 0, counts, "inprocess", 1.0)
    counts["ok"] = 5
    assert run.counts["ok"] == 2
    with pytest.raises(TypeError):
        run.counts["ok"] = 3


def test_a_dataset_s_extra_is_a_read_only_copy():
    # was: a plain dict inside a frozen Dataset: data.extra["seed"] = 5 changed the bundled set's facts
    # for everything that read them later, and the caller's dict stayed tied to the Dataset
    rec = test_io.record()
    mine = {"seed": 1}
    data = gb.Dataset(rec, rec, None, extra=mine)
    mine["seed"] = 2
    assert data.extra["seed"] == 1
    with pytest.raises(TypeError):
        data.extra["seed"] = 3
    with pytest.raises(TypeError, match="extra must be a mapping"):
        gb.Dataset(rec, rec, None, extra=[("seed", 1)])
    import pickle  # a Dataset still travels to worker processes

    assert pickle.loads(pickle.dumps(data)).extra["seed"] == 1


def test_the_arrays_of_records_models_and_static_points_cannot_be_made_writeable_again(tmp_path):
    """A read-only array that owns its memory is made writeable by ``a.flags.writeable = True``, and a Record's y or
    a Model's θ could then be edited in place; their memory is now immutable, so the flag is refused (on the base
    too), for values made and for values loaded."""
    rec = gb.Record(np.linspace(0.0, 1.0, 12), np.linspace(1.0, 2.0, 12), name="r")
    rec2 = gb.Record(np.ones((12, 2)), np.zeros(12), name="two inputs")
    model = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0])
    points = gb.StaticPoints([1.0, 2.0], [3.0, 4.0], uncertainty=[0.1, 0.2])
    loaded = gb.load(gb.save(model, tmp_path / "m.json"))
    arrays = {"Record.u": rec.u, "Record.y": rec.y, "Record.u (two inputs)": rec2.u, "Model.theta": model.theta,
              "StaticPoints.ubar": points.ubar, "StaticPoints.ybar": points.ybar,
              "StaticPoints.uncertainty": points.uncertainty, "loaded Model.theta": loaded.theta}
    for name, a in arrays.items():
        for target in (a, a.base):
            if isinstance(target, np.ndarray):
                with pytest.raises(ValueError, match="WRITEABLE"):
                    target.flags.writeable = True
        assert not a.flags.writeable, name
    np.testing.assert_array_equal(model.theta, [0.5, 1.0])
