"""Regression tests for the items mended by mend51f."""
from __future__ import annotations

from decimal import Decimal

import numpy as np
import pytest


def test_check_lambdas_beyond_float_range_is_named():
    from graybox.core._validation import check_lambdas
    with pytest.raises(ValueError, match="beyond the float range"):
        check_lambdas([Decimal("1e400")])
    with pytest.raises(ValueError, match="beyond the float range"):
        check_lambdas([0.5, 10**400])
    assert check_lambdas([Decimal("0.5")]).tolist() == [0.5]
