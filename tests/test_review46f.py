"""Review 46f: the structure and record coercions, a Dataset's frozen extra, and the term order they keep."""

from __future__ import annotations

import collections
import warnings

import numpy as np
import pytest

import graybox as gb
from graybox.core._validation import frozen_value

_REC = gb.Record([1.0, 2.0, 3.0, 4.0], [0.5, 0.25, 0.125, 0.0625], name="short")


# -- a set of terms has no order, and the terms' order is θ's --------------------------------------------
@pytest.mark.parametrize("kind", [set, frozenset])
def test_a_set_of_terms_is_refused_naming_its_lack_of_order(kind):
    # was: Structure({...}), hence simulate(set, θ) and, since the one coercion (383ee90), els(set, data) took a set,
    # whose order (that of θ) changes with PYTHONHASHSEED: θ was matched to the terms in no stated order
    terms = kind({"y(k-1)", "u(k-1)", "1"})
    with pytest.raises(TypeError, match="no order"):
        gb.Structure(terms)
    with pytest.raises(TypeError, match="no order"):
        gb.simulate(terms, [0.5, 0.2, 0.1], _REC)
    with pytest.raises(TypeError, match="no order"):
        gb.els(terms, _REC)


def test_ordered_collections_of_terms_are_still_taken():
    want = ["y(k-1)", "u(k-1)", "1"]
    for given in (want, tuple(want), dict.fromkeys(want).keys(), np.array(want)):
        assert [str(t) for t in gb.Structure(given)] == want


# -- a Dataset's extra: frozen all the way down, at a cost linear in what it holds --------------------------
_Pair = collections.namedtuple("_Pair", "levels gain")


def test_a_named_tuple_in_extra_is_frozen_too():
    # was: a named tuple was kept as given ("immutable itself"), so the list it held stayed the caller's, changeable
    mine = [1.0, 2.0]
    data = gb.Dataset(_REC, _REC, extra={"pair": _Pair(mine, 3.0)})
    mine.append(3.0)
    pair = data.extra["pair"]
    assert isinstance(pair, _Pair) and list(pair.levels) == [1.0, 2.0]
    with pytest.raises(TypeError, match="cannot be changed"):
        pair.levels.append(4.0)


def test_a_value_shared_inside_extra_is_frozen_once():
    # was: every path to a shared list was frozen apart: 2^depth copies (a list of two references to one list took
    # 45 s at 22 levels and never finished at 40); now each value is frozen once and stays shared, as deepcopy keeps it
    x: list = [0.0]
    for _ in range(12):
        x = [x, x]
    out = frozen_value(x, "extra")
    assert out[0] is out[1] and out[0][0] is out[0][1]
    inner = out
    for _ in range(12):
        inner = inner[0]
    assert inner == [0.0]


def test_a_value_held_twice_but_not_inside_itself_is_no_cycle():
    shared = [1.0]
    out = frozen_value({"a": shared, "b": [shared, shared]}, "extra")
    assert out["a"] == [1.0] and out["b"][0] is out["a"]
    loop: list = [1.0]
    loop.append(loop)
    with pytest.raises(ValueError, match="holds itself"):
        frozen_value({"a": loop}, "extra")


# -- a surface sampled over its domain: the grid's cap names what the caller can change --------------------
def test_a_surface_of_many_inputs_sampled_without_ubar_says_to_give_ubar():
    # was: "levels: 6 levels per input over 8 varying inputs make a grid …; take fewer levels", of an option pe_pareto
    # does not have (the default sampling of a surface without ubar); the fix is to give ubar
    m = 8
    surf = gb.StaticSurface(tuple(tuple(int(i == j) for i in range(m)) for j in range(m)), np.ones(m),
                            domain=tuple((0.0, 1.0) for _ in range(m)))
    rng = np.random.default_rng(0)
    u = rng.uniform(0.0, 1.0, (80, m))
    y = np.zeros(len(u))
    for k in range(1, len(u)):
        y[k] = 0.5 * y[k - 1] + u[k - 1].sum() + 0.01 * rng.standard_normal()
    rec = gb.Record(u, y)
    st = gb.parse_structure(" + ".join(["y(k-1)"] + [f"u{i + 1}(k-1)" for i in range(m)]))
    with pytest.raises(ValueError, match="give ubar") as info:
        gb.pe_pareto(st, rec, surf, lambdas=[1.0])
    assert "take fewer levels" not in str(info.value)
    # the points asked for by ubar are taken
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)  # (the records' box is not the surface's concern here)
        assert len(gb.pe_pareto(st, rec, surf, lambdas=[1.0], ubar=u[10:15])) == 1


def test_changing_a_list_in_extra_says_how_to_get_one_to_change():
    # a user's ds.extra["k"].append(...) was told the list cannot be changed, not how to get one that can
    data = gb.Dataset(_REC, _REC, extra={"levels": [1.0, 2.0]})
    with pytest.raises(TypeError, match=r"cannot be changed .*: change a copy, list\(x\)"):
        data.extra["levels"].append(3.0)
    mine = list(data.extra["levels"])  # the copy it names
    mine.append(3.0)
    assert mine == [1.0, 2.0, 3.0] and list(data.extra["levels"]) == [1.0, 2.0]


def test_a_set_of_noise_terms_is_refused_too():
    # noise terms went through check_sequence (a list of the set's items, in no stated order) before Structure
    st = gb.parse_structure("y(k-1) + u(k-1)")
    with pytest.raises(TypeError, match="noise_structure: .*no order"):
        gb.Model(st, [0.5, 0.2], noise_structure={"e(k-1)", "e(k-2)"}, noise_theta=[0.1, 0.2])
    with pytest.raises(TypeError, match="noise: .*no order"):
        gb.els(st, _REC, noise=frozenset({"e(k-1)", "e(k-2)"}))
