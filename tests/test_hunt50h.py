"""Bugs found by hunt50h in the foundation layer (terms, records, kernels, models)."""

import numpy as np
import pytest

import graybox as gb


@pytest.mark.parametrize("text", ["y(k-1)*", "u(k-2) * ", "y(k-1)u(k-1)*"])
def test_term_ending_in_a_product_sign_is_refused(text):
    # 'y(k-1)*' is a product with its last factor missing (a truncated 'y(k-1)*u(k-2)'): it read as y(k-1)
    with pytest.raises(ValueError, match="factor"):
        gb.parse_term(text)
    with pytest.raises(ValueError, match="factor"):
        gb.parse_structure(text + " + y(k-2)")
