"""Review of the session's eq. (22) (Σ*_y estimated), leaderboard and report changes."""

import pytest

from graybox.experiments._spec import Variant


def test_a_spec_s_cls_and_pe_take_reference_free_as_the_estimators_do():
    """reference = "free" is cls's and pe_pareto's default and the spec's equality takes sigma_y = "free", but
    the variant option was refused ('must be one of ls, els')."""
    for est in ("cls", "pe"):
        v = Variant("v", est, constraints=[{"type": "equality", "curve": "fit"}], options={"reference": "free"})
        assert v.options["reference"] == "free"
    with pytest.raises(ValueError, match="reference"):
        Variant("v", "cls", constraints=[{"type": "equality", "curve": "fit"}], options={"reference": "loose"})
