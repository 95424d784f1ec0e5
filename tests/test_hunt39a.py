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


# -- equilibria whose roots span the float range ----------------------------------------------------------
def test_a_quadratic_whose_far_root_is_beyond_1e205_keeps_its_near_root():
    # y = 1 + c y²: the stable root near 1 and an unstable one near 1/c. The root kernel scaled the cubic's
    # absent coefficient by s³, which overflowed (0 · inf = NaN) once 1/c passed ~1e205, and every root
    # was lost: no equilibrium, static curve NaN, while c = 0 (and c = 1e-200) gave ȳ = 1
    st = gb.Structure(["1", "y(k-1)^2"])
    for c in (1e-200, 1e-212, 1e-250, 1e-300):
        m = gb.Model(st, [1.0, c])
        eq = m.equilibria(0.0)
        assert [e.stable for e in eq] == [True, False]
        assert eq[0].ybar == pytest.approx(1.0 + c, rel=1e-12) and eq[1].ybar == pytest.approx(1.0 / c, rel=1e-9)
        assert m.static_curve([0.0])[0] == pytest.approx(1.0, rel=1e-12)


def test_an_equilibrium_whose_linearisation_overflows_is_unstable_not_a_crash():
    # y = 1 + 1e-100 y² + 1e-270 y³ has roots near 1, 1e100 and -1e170; at -1e170, ∂f/∂y = 2e-100 y + 3e-270 y²
    # is 3e70 but y² overflows on the way: the spectral radius was numpy's LinAlgError "Array must not
    # contain infs or NaNs", and equilibria() and the local model with it
    m = gb.Model(gb.Structure(["1", "y(k-1)^2", "y(k-1)^3"]), [1.0, 1e-100, 1e-270])
    eq = m.equilibria(0.0)
    assert [e.stable for e in eq] == [False, True, False]
    assert eq[0].ybar == pytest.approx(-1e170, rel=1e-9) and eq[1].ybar == pytest.approx(1.0, rel=1e-12)
    assert eq[0].spectral_radius > 1 and eq[2].spectral_radius > 1
    assert m.static_curve([0.0])[0] == pytest.approx(1.0, rel=1e-12)
