import numpy as np
import pytest

from graybox import Model, Record, StaticPoints, parse_term, reference


def test_nan_or_inf_in_record():
    with pytest.raises(ValueError, match=r"u has 1 non-finite value.*index 3"):
        Record([1, 2, 3, np.nan, 5], [1, 2, 3, 4, 5])
    with pytest.raises(ValueError, match="y has 1 non-finite"):
        Record([1, 2, 3], [1, np.inf, 3])


def test_mismatched_lengths():
    with pytest.raises(ValueError, match="same length, got 3 and 4"):
        Record([1, 2, 3], [1, 2, 3, 4])


def test_two_d_where_one_d_expected():
    # u of shape (N, m) is m inputs (issue 15); y stays 1-D and u cannot be 3-D
    with pytest.raises(ValueError, match="must be 1-D"):
        Record(np.ones(5), np.ones((5, 2)))
    with pytest.raises(ValueError, match="must be 1-D .* or 2-D"):
        Record(np.ones((5, 2, 1)), np.ones(5))
    assert Record(np.ones((5, 1)), np.ones(5)).u.shape == (5,)
    assert Record(np.ones((5, 2)), np.ones(5)).input_names == ("u1", "u2")


def test_record_shorter_than_max_lag():
    m = reference.paper_model(15)
    r = Record(np.full(6, 1000.0), np.full(6, 5.0))
    with pytest.raises(ValueError, match="fewer than max lag"):
        m.predict(r)
    with pytest.raises(ValueError, match="fewer than max lag"):
        m.simulate(np.full(6, 1000.0), np.full(6, 5.0))
    with pytest.raises(ValueError, match="y0 has 3 samples"):
        m.simulate(np.full(60, 1000.0), np.full(3, 5.0))


def test_unparsable_term():
    with pytest.raises(ValueError, match="cannot parse term 'u\\(k-2\\)k\\(k-1\\)'"):
        parse_term("u(k-2)k(k-1)")


def test_theta_length():
    with pytest.raises(ValueError, match="theta has 16 values but the structure has 17 terms"):
        Model(reference.STRUCTURE_15, np.zeros(16))
    with pytest.raises(ValueError, match="non-finite"):
        Model(reference.STRUCTURE_15, np.full(17, np.nan))


def test_static_points_validation():
    with pytest.raises(ValueError, match="duplicated ubar.*StaticPoints.from_repeats"):
        StaticPoints([1.0, 1.0], [2.0, 3.0])
    # repeated measurements at one level: their mean, one point per level, sorted by ū
    sp = StaticPoints.from_repeats([2.0, 1.0, 2.0, 1.0, 3.0], [5.0, 2.0, 7.0, 4.0, 1.0])
    np.testing.assert_array_equal(sp.ubar, [1.0, 2.0, 3.0])
    np.testing.assert_allclose(sp.ybar, [3.0, 6.0, 1.0])
    two = StaticPoints.from_repeats([[1.0, 2.0], [1.0, 2.0], [2.0, 1.0]], [1.0, 3.0, 5.0], input_names=("a", "b"))
    assert two.ubar.shape == (2, 2) and two.input_names == ("a", "b")
    np.testing.assert_allclose(two.ybar, [2.0, 5.0])
    with pytest.raises(ValueError, match="non-finite"):
        StaticPoints.from_repeats([1.0, 1.0], [2.0, np.nan])
    with pytest.raises(ValueError, match="non-finite"):
        StaticPoints([1.0, np.nan], [2.0, 3.0])


def test_noise_terms_rejected_in_process_structure():
    with pytest.raises(ValueError, match="noise terms belong"):
        Model(["y(k-1)", "e(k-1)"], [0.5, 0.1])


def test_models_are_immutable():
    m = reference.paper_model(15)
    with pytest.raises(ValueError):
        m.theta[0] = 1.0
    with pytest.raises(Exception):
        m.name = "x"
