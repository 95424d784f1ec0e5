import graybox.experiments as gx
import pytest


def test_a_spec_refuses_max_terms_above_its_candidates_as_it_does_n_terms():
    # da84fbd made frols refuse max_terms above the candidates' count; a spec whose inputs it knows
    # (nu per input) took max_terms = 50 of 6 candidates, and every cell of the structure then failed
    with pytest.raises(gx.SpecError, match=r"max_terms must be an integer <= 6, got 50") as e:
        gx.StructureSpec("s", candidates={"ny": 1, "nu": {"u": 1}, "degree": 2}, criterion="bic", max_terms=50)
    assert e.value.path == ("max_terms",)
    assert gx.StructureSpec("s", candidates={"ny": 1, "nu": {"u": 1}, "degree": 2}, criterion="bic",
                            max_terms=6).max_terms == 6

