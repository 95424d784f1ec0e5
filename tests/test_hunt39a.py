"""hunt39a: laws that must hold across the package (units, inputs' order and names, lists of records,
searches), and the bugs found where one failed."""

import numpy as np
import pytest

import graybox as gb


# -- the error measures take the model's output as they take the measured one ----------------------------
@pytest.mark.parametrize("measure", [gb.mse, gb.rrse, gb.fit_percent])
@pytest.mark.parametrize("yhat, said", [
    (np.array(["1.0", "2.0", "4.0"]), "strings"),      # was parsed: mse 0.33, a score of text
    ([True, False, True], "yhat"),                     # was read as 1, 0, 1
    ([1.0, None, 4.0], "yhat"),                        # was NaN, a "diverged" run (mse inf, fit -inf)
    (np.array([1.0 + 1j, 2.0, 4.0]), "complex"),       # was its real part, with at most numpy's warning
    (gb.Model(["y(k-1)"], [0.5]), "yhat"),             # was numpy's "float() argument must be …", naming nothing
])
def test_a_model_output_that_is_not_numbers_is_refused_naming_yhat(measure, yhat, said):
    y = np.array([1.0, 2.0, 3.0])
    with pytest.raises(TypeError, match=said):
        measure(y, yhat)
    # numbers are scored as they were, NaN (a diverged free run) included
    assert measure(y, np.array([1.0, 2.0, 3.0])) == (100.0 if measure is gb.fit_percent else 0.0)
    assert np.isinf(measure(y, np.array([1.0, np.nan, 3.0])))
