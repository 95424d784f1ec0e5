"""Review of the neural stop rule, decimation in units of max|y|, the neural grid options, the weight and file checks,
design_input's pairs, frozen_value's memo and the refusal of sets as structures (review46h)."""
from collections.abc import Mapping

import pytest

from graybox.core._validation import MAX_NESTING, frozen_value


class _LazyMapping(Mapping):
    """A mapping that makes each value when asked (as a lazy loader's may): the lists are temporaries."""

    def __init__(self, n: int) -> None:
        self.n = n

    def __getitem__(self, k):
        return [k, k]

    def __iter__(self):
        return iter(range(self.n))

    def __len__(self) -> int:
        return self.n


def test_frozen_value_of_temporaries_is_each_its_own():
    # the memo was keyed by id alone: a value made for one key and dropped left its id to the next one's, which
    # was then given the first one's copy ({2: [0, 0]})
    out = frozen_value(_LazyMapping(6), "extra")
    assert {k: list(v) for k, v in out.items()} == {k: [k, k] for k in range(6)}


def _wrap(x, n):
    for _ in range(n):
        x = [x]
    return x


@pytest.mark.parametrize("first", ["shallow", "deep"])
def test_frozen_value_depth_of_a_shared_value_whichever_path_comes_first(first):
    # a value of MAX_NESTING - 1 levels met at depth 1 and again 50 levels down is nested deeper than MAX_NESTING
    # (to_json refuses to write it): refused whichever path is walked first, not only when the deep one is
    shared = _wrap(0, MAX_NESTING - 1)
    items = [("a", shared), ("b", _wrap(shared, 50))]
    value = dict(items if first == "shallow" else items[::-1])
    with pytest.raises(ValueError, match="nested deeper"):
        frozen_value(value, "extra")


def test_frozen_value_shared_value_within_the_limit_stays_shared():
    shared = _wrap(0, MAX_NESTING - 3)
    out = frozen_value({"a": shared, "b": [shared]}, "extra")
    assert out["b"][0] is out["a"]


# -- input names given as a set -----------------------------------------------------------------------------------

def _two_inputs():
    import numpy as np
    return np.c_[np.arange(10.0), np.full(10, 3.0)], np.arange(10.0)


@pytest.mark.parametrize("make", ["record", "candidates", "model", "simulate"])
def test_input_names_given_as_a_set_are_refused(make):
    # a set's order is its hash order: which column was named 'speed' and which 'valve' changed with PYTHONHASHSEED
    import graybox as gb
    names = {"speed", "valve"}
    u, y = _two_inputs()
    with pytest.raises(TypeError, match="no order"):
        if make == "record":
            gb.Record(u, y, Ts=1.0, input_names=names)
        elif make == "candidates":
            gb.Candidates(1, [1, 2], degree=1, input_names=frozenset(names))
        elif make == "model":
            gb.Model(gb.Structure(["speed(k-1)", "valve(k-1)"]), [0.1, 0.2], input_names=names)
        else:
            gb.simulate(gb.Structure(["speed(k-1)", "valve(k-1)", "y(k-1)"]), [0.1, 0.2, 0.5], u, y, input_names=names)


def test_input_names_in_any_ordered_sequence_still_taken():
    import graybox as gb
    u, y = _two_inputs()
    for names in (["speed", "valve"], ("speed", "valve"), {"speed": 0, "valve": 1}.keys()):
        assert gb.Record(u, y, Ts=1.0, input_names=names).input_names == ("speed", "valve")


# -- included terms given as a set ---------------------------------------------------------------------------------

def _plant():
    import numpy as np
    import graybox as gb
    rng = np.random.default_rng(0)
    n = 200
    u = rng.uniform(-1, 1, n)
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = 0.5 * y[k - 1] - 0.2 * y[k - 2] + u[k - 1] + 0.3 * u[k - 1] ** 2 + 0.01 * rng.standard_normal()
    return gb.Candidates(2, 2, degree=2), gb.Record(u, y, Ts=1.0)


@pytest.mark.parametrize("search", ["frols", "semp"])
def test_included_terms_given_as_a_set_are_refused(search):
    # the included terms lead the structure chosen in the order given: a set's order, so the structure's (θ's)
    # order changed with PYTHONHASHSEED (u(k-2) + y(k-2) + u(k-1)^2 + … or u(k-1)^2 + u(k-2) + …)
    import graybox as gb
    cands, rec = _plant()
    with pytest.raises(TypeError, match="no order"):
        getattr(gb, search)(cands, rec, n_terms=4, include={"u(k-2)", "y(k-2)"})


def test_included_terms_in_a_list_lead_in_the_order_given():
    import graybox as gb
    cands, rec = _plant()
    fit = gb.frols(cands, rec, n_terms=4, include=["y(k-2)", "u(k-2)"])
    assert [str(t) for t in fit.model.structure.terms[:2]] == ["y(k-2)", "u(k-2)"]


def test_select_graybox_refuses_included_terms_given_as_a_set():
    import graybox.experiments as gx
    cands, rec = _plant()
    with pytest.raises(TypeError, match="no order"):
        gx.select_graybox(cands, rec, estimator="ls", include={"1", "y(k-1)"})


def test_frozen_value_keeps_an_array_held_twice_shared():
    # the docstring's promise (a value held twice frozen once and still shared, as deepcopy keeps it) held for
    # lists and mappings, not arrays: each path got its own copy (twice the memory of a large shared array)
    import numpy as np
    arr = np.arange(5.0)
    out = frozen_value({"x": arr, "y": [arr]}, "extra")
    assert out["x"] is out["y"][0] and not out["x"].flags.writeable
    assert np.array_equal(out["x"], arr) and out["x"] is not arr
