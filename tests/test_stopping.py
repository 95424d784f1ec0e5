"""The stopping rule FROLS and SEMP share (graybox.selection._stopping)."""

import warnings

import numpy as np
import pytest

from graybox.selection._stopping import choose_model, stop_rule


def test_rules_pick_by_count_tolerance_and_criterion():
    # a SEMP-like path: sizes go up and down (pruning), the criterion and the fraction with them
    sizes = np.array([1, 2, 3, 2, 3, 4])
    crit = np.array([10.0, 5.0, 4.0, 3.0, 3.0, 3.5])
    frac = np.array([0.5, 0.2, 0.05, 0.04, 0.01, 0.009])
    rule = stop_rule(2, None, None, curve_default="aic")
    assert rule.mode == "n_terms" and rule.criterion == "aic"
    assert choose_model(rule, sizes, crit, frac, can_grow=True, fraction="f") == (3, "n_terms = 2")
    # the fewest terms within the tolerance, then the smallest criterion, the last met among ties
    i, why = choose_model(stop_rule(None, 0.045, None, curve_default="aic"), sizes, crit, frac, can_grow=True,
                          fraction="f")
    assert i == 3 and why == "f ≤ 0.045"
    i, _ = choose_model(stop_rule(None, 0.02, None, curve_default="aic"), sizes, crit, frac, can_grow=True,
                        fraction="f")
    assert i == 4
    # the criterion's minimum, the first met among ties; BIC by default
    rule = stop_rule(None, None, None, curve_default="aic")
    assert rule.criterion == "bic"
    assert choose_model(rule, sizes, crit, frac, can_grow=True, fraction="f") == (3, "bic minimum at 2 of 4 sizes")


def test_rules_cut_short_warn():
    sizes = np.arange(1, 4)
    crit = np.array([3.0, 2.0, 1.0])
    frac = np.array([0.5, 0.4, 0.3])
    with pytest.warns(RuntimeWarning, match="tolerance 0.1 not reached: f = 3.000e-01 after 3 terms"):
        i, why = choose_model(stop_rule(None, 0.1, None, curve_default="aic"), sizes, crit, frac, can_grow=True,
                              fraction="f")
    assert i == 2 and "not reached" in why
    with pytest.warns(RuntimeWarning, match="largest size looked at"):
        choose_model(stop_rule(None, None, "aic", curve_default="aic"), sizes, crit, frac, can_grow=True, fraction="f")
    # nothing left to add: the minimum at the largest size is the answer, not a cut
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert choose_model(stop_rule(None, None, "aic", curve_default="aic"), sizes, crit, frac, can_grow=False,
                            fraction="f")[0] == 2
    with pytest.raises(ValueError, match="no model of 5 terms"):
        choose_model(stop_rule(5, None, None, curve_default="aic"), sizes, crit, frac, can_grow=True, fraction="f")
