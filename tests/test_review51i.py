"""review51i: checks of 9e64312, 1558d0e, eba37a4, fd1e84a and 2e32c0a."""
from fractions import Fraction

import pytest

from graybox.core._validation import check_int


def test_check_int_of_a_huge_fraction_is_no_bare_overflow():
    # Fraction(10**400) is an integer: check_int took it through float() and raised Python's
    # 'integer division result too large for a float' (OverflowError), naming nothing
    assert check_int(Fraction(10**400, 1), "n") == 10**400
    with pytest.raises(TypeError, match="n must be an integer"):
        check_int(Fraction(10**400 + 1, 3), "n")
    with pytest.raises(ValueError, match="n must be an integer <= 5"):
        check_int(Fraction(10**400, 1), "n", high=5)
    assert check_int(Fraction(6, 2), "n") == 3
    with pytest.raises(TypeError, match="n must be an integer"):
        check_int(Fraction(7, 2), "n")
