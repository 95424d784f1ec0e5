import pytest
from hypothesis import given, settings, strategies as st

from graybox import Candidates, Structure, Term, parse_structure, parse_term


@pytest.mark.parametrize("text", ["y(k-1)", "u(k-2)y(k-6)", "u(k-6)^2", "1", "u(k-6)^2u(k-4)", "u(k-5)y(k-1)y(k-3)", "e(k-2)"])
def test_paper_strings_round_trip(text):
    t = parse_term(text)
    assert parse_term(str(t)) == t
    if text not in ("u(k-6)^2u(k-4)", "u(k-5)y(k-1)y(k-3)"):
        assert str(t) == text


def test_factor_order_does_not_matter():
    assert parse_term("y(k-6)u(k-2)") == parse_term("u(k-2)y(k-6)")
    assert parse_term("u(k-2)*u(k-2)") == parse_term("u(k-2)^2")
    assert parse_term("u(k-6)^2u(k-4)").degree == 3
    assert parse_term("u(k-6)^2u(k-4)").power_of("u") == 3


@given(st.lists(st.tuples(st.sampled_from(["y", "u", "e"]), st.integers(1, 9), st.integers(1, 3)), max_size=4))
@settings(max_examples=60, deadline=None)
def test_round_trip_property(factors):
    t = Term(tuple(factors))
    assert parse_term(str(t)) == t


@pytest.mark.parametrize("ny,nu,degree,count", [(6, 6, 2, 91), (6, 6, 3, 455), (2, 2, 1, 5), (1, 0, 2, 3)])
def test_candidate_counts(ny, nu, degree, count):
    c = Candidates(ny, nu, ne=0, degree=degree)
    assert len(c) == count
    assert len(set(c)) == count
    assert all(t.degree <= degree for t in c)


def test_candidates_noise_and_delay():
    c = Candidates(2, 4, ne=2, degree=1, delay=2)
    assert [str(t) for t in c.noise] == ["e(k-1)", "e(k-2)"]
    assert {str(t) for t in c.process} == {"1", "y(k-1)", "y(k-2)", "u(k-2)", "u(k-3)", "u(k-4)"}


def test_structure_basics():
    s = parse_structure("y(k-1) + u(k-2)y(k-6) + 1")
    assert len(s) == 3 and s.max_lag == 6 and s.index("1") == 2 and "u(k-2)y(k-6)" in s
    with pytest.raises(ValueError, match="duplicated term"):
        Structure(["y(k-1)", "y(k-1)"])


@pytest.mark.parametrize("bad", ["", "y(k+1)", "k(k-1)", "y(k-0)", "y(k-1)^0", "y(k-1)+", "hello", "y(k-1)^"])
def test_unparsable_terms_raise(bad):
    with pytest.raises(ValueError):
        parse_term(bad)


def test_rational_candidates():
    c = Candidates(6, 6, ne=0, degree=2, max_y_power=1)
    assert len(c) == 91 - 21  # the 21 products y(k-i)y(k-j) are gone
    assert all(t.power_of("y") <= 1 for t in c)
    with pytest.raises(ValueError, match="max_y_power"):
        Candidates(2, 2, ne=0, degree=2, max_y_power=-1)
