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


def test_among_exact_fits_the_criterion_takes_the_fewest_terms():
    # was: exact search (EBIC) on 10 noise-free rows of y(k) = 0.6 y(k-1) + 0.2 y(k-2) + 0.3 u(k-1) + 0.05 u(k-2)
    # took those four terms and 1: both fits at the round-off floor, EBIC's ln C(5, k) is smaller for all five
    # candidates (ln 1) than for four (ln 5) by more than ln N; at y × 1e-300 the constant's round-off θ then
    # underflowed and frols refused the data
    sizes, frac = np.array([1, 2, 3, 4, 5]), np.array([4e-2, 6e-4, 1e-4, 1e-27, 1e-27])
    crit = np.array([-18.6, -57.6, -72.0, -601.0, -601.9])
    i, why = choose_model(stop_rule(None, None, "ebic", curve_default="bic"), sizes, crit, frac, can_grow=False,
                          fraction="f", round_off=np.full(5, 1e-27))
    assert i == 3 and "4 of 5" in why
    # a smaller model that is not exact is not taken for the exact one (its criterion is larger)
    assert choose_model(stop_rule(None, None, "ebic", curve_default="bic"), sizes, crit, frac, can_grow=False,
                        fraction="f", round_off=np.full(5, 1e-28))[0] == 4


def test_exact_search_on_few_noise_free_rows_chooses_the_true_terms_in_any_units():
    import graybox as gb

    true = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)"])
    u = np.repeat([1.91, 0.81, 0.12], 5)[:12]
    y = gb.Model(true, np.array([0.6, 0.2, 0.3, 0.05])).simulate(u, np.zeros(2))
    for scale in (1.0, 1e-300, 1e300):
        sel = gb.frols(gb.Candidates(2, 2, degree=1), gb.Record(u, y * scale), search="exact")
        assert set(map(str, sel.structure.terms)) == set(map(str, true.terms)), scale


def test_a_model_floored_at_the_whole_output_energy_is_no_exact_fit():
    # rss_floor gives yᵀy (fraction 1) to a fit whose parameters are too large for any digit of y to survive: such a
    # model explains nothing, and was taken as an exact fit (tol met at 1 term; the fewest exact terms)
    sizes, frac = np.array([1, 2, 3]), np.array([1.0, 0.5, 1e-30])
    floor = np.array([1.0, 1e-28, 1e-28])
    i, why = choose_model(stop_rule(None, 1e-3, None, curve_default="bic"), sizes, np.array([0.0, -5.0, -60.0]),
                          frac, can_grow=False, fraction="f", round_off=floor)
    assert i == 2, why
    i, why = choose_model(stop_rule(None, None, "bic", curve_default="bic"), sizes, np.array([0.0, -5.0, -60.0]),
                          frac, can_grow=False, fraction="f", round_off=floor)
    assert i == 2, why
