"""Bug hunt 46b: the agreements of the whole public API (immutable values, validation, coercion, files)."""

import copy
import operator
import pickle

import numpy as np
import pytest

import graybox as gb

_REC = gb.Record([1.0, 2.0, 3.0, 4.0], [0.5, 0.25, 0.125, 0.0625], name="short")


# -- a Dataset's extra: a read-only copy all the way down ---------------------------------------------------
def test_a_dataset_s_extra_shares_no_nested_list_dict_or_array_with_the_caller():
    # was: only the outer mapping was copied; the caller's nested list, dict and array stayed tied to the Dataset
    mine = {"levels": [1.0, 2.0], "info": {"site": "A"}, "curve": np.array([1.0, 2.0])}
    data = gb.Dataset(_REC, _REC, extra=mine)
    mine["levels"].append(3.0)
    mine["info"]["site"] = "B"
    mine["curve"][0] = 99.0
    assert list(data.extra["levels"]) == [1.0, 2.0]
    assert data.extra["info"]["site"] == "A"
    assert data.extra["curve"][0] == 1.0


def test_a_dataset_s_extra_cannot_be_changed_through_its_nested_values():
    data = gb.Dataset(_REC, _REC, extra={"levels": [1.0, [2.0]], "info": {"site": "A"}, "curve": np.ones(2)})
    for change in (lambda: data.extra["levels"].append(3.0), lambda: operator.setitem(data.extra["levels"], 0, 5.0),
                   lambda: data.extra["levels"][1].append(1.0), lambda: data.extra["levels"].sort(),
                   lambda: operator.setitem(data.extra["info"], "site", "B")):
        with pytest.raises(TypeError):
            change()
    with pytest.raises(ValueError):
        data.extra["curve"][0] = 2.0
    levels = data.extra["levels"]
    with pytest.raises(TypeError):
        levels += [4.0]
    assert data.extra["levels"] == [1.0, [2.0]]  # still a list to the reader, equal to the one given


def test_a_frozen_extra_pickles_copies_and_round_trips_through_json_as_lists():
    data = gb.Dataset(_REC, _REC, extra={"names": ["u1", "u2"], "pair": (1, [2])})
    for back in (pickle.loads(pickle.dumps(data)), copy.deepcopy(data), gb.from_json(gb.to_json(data))):
        assert back.extra["names"] == ["u1", "u2"] and back.extra["pair"] == (1, [2])
        assert isinstance(back.extra["names"], list) and isinstance(back.extra["pair"], tuple)
        with pytest.raises(TypeError):
            back.extra["names"].append("u3")


def test_a_self_holding_or_absurdly_nested_extra_is_refused_with_the_field_named():
    # was: a bare RecursionError from to_json (and no word of which field)
    loop = []
    loop.append(loop)
    deep = []
    for _ in range(5000):
        deep = [deep]
    for bad in (loop, deep):
        with pytest.raises(ValueError, match=r"extra\['a'\]"):
            gb.Dataset(_REC, _REC, extra={"a": bad})


def test_to_json_refuses_a_value_nested_deeper_than_a_file_reads_back():
    from graybox.io import _json

    deep = []
    for _ in range(5000):
        deep = [deep]
    with pytest.raises(ValueError, match="nested deeper"):
        _json._enc_plain(deep, "Dataset.extra['a']")
    ok = []
    for _ in range(50):
        ok = [ok]
    data = gb.Dataset(_REC, _REC, extra={"a": ok})
    assert gb.from_json(gb.to_json(data)).extra["a"] == ok


def test_from_json_refuses_a_hand_nested_plain_value_as_a_corrupt_file():
    text = gb.to_json(gb.Dataset(_REC, _REC, extra={"a": 1.0}))
    deep = "1.0"
    for _ in range(450):  # within what json itself reads
        deep = '{"list": [' + deep + "]}"
    with pytest.raises(gb.GrayboxFileError, match="nested deeper"):
        gb.from_json(text.replace('"a": 1.0', '"a": ' + deep))


# -- sizes that end in a MemoryError are refused up front, naming the option -------------------------------
def test_gain_bounds_refuses_an_absurd_number_of_levels():
    # was: any n; GainBounds(lower=0, n=10**9) ended in a MemoryError inside the estimator
    with pytest.raises(ValueError, match="n must be an integer <="):
        gb.GainBounds(lower=0.0, n=10**9)
    assert gb.GainBounds(lower=0.0, n=1000).n == 1000


def test_a_grid_of_levels_beyond_a_million_points_names_the_option():
    from graybox.static._surfaces import box_grid

    with pytest.raises(ValueError, match="GainBounds: n.*1000\\^3"):
        box_grid([(0.0, 1.0)] * 3, 1000, "GainBounds: n")
    assert box_grid([(0.0, 1.0), (2.0, 2.0)], 1000).shape == (1000, 2)  # an input held at one level is one level
