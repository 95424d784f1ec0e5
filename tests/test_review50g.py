"""review50g: what the review of mend50d, hunt50e, hunt50c and hunt50a's merges found."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb
from graybox.core._records import check_overlap, check_print_overlap, record_print


# 1. a record's print and repeated blocks ---------------------------------------------------------------------------

def _at_rest_first(rest: int, n: int = 3000, seed: int = 0) -> gb.Record:
    """A record that starts with ``rest`` samples at rest (u = y = 0, every block of them the same) then varies."""
    rng = np.random.default_rng(seed)
    u = np.concatenate([np.zeros(rest), rng.standard_normal(n)])
    y = np.concatenate([np.zeros(rest), rng.standard_normal(n)])
    return gb.Record(u, y, name="fit")


@pytest.mark.parametrize("rest, start", [(10000, 1000), (10000, 5000), (70000, 1000)])
def test_a_print_refuses_a_slice_that_begins_in_a_long_rest(rest, start):
    # the slice's first 4096 windows matched only the rest's blocks (each one of hundreds alike), so the true
    # alignment was never tried and the loaded set took the slice its fresh self refuses
    f = _at_rest_first(rest)
    c = f.slice(start, None, "piece")
    with pytest.raises(ValueError, match="fitting"):
        check_overlap(c, f, "choosing", "fitting", "advice")
    with pytest.raises(ValueError, match=f"its samples 0\\.\\.{len(c) - 1} are samples {start}\\.\\."):
        check_print_overlap(c, record_print(f), "choosing", "fitting", "advice")
    # a record of its own beside the same rest is still not refused
    other = _at_rest_first(rest, seed=1).slice(start, None, "other")
    check_print_overlap(other, record_print(f), "choosing", "fitting", "advice")
