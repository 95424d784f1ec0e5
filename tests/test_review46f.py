"""Review 46f: the structure and record coercions, a Dataset's frozen extra, and the term order they keep."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb

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
