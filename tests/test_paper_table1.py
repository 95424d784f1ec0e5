"""Table I as read from the paper's extracted text, and reproduce's comparison with it."""

import pandas as pd
import pytest

from graybox.reference import TABLE_I
from graybox.reproduce._table1 import se_against_els

B = 0.031  # the paper's band, mlc²


def _row(name):
    js_ident, js_valid, jsf, n_p = TABLE_I[name]
    return {"ident": js_ident, "valid": js_valid, "jsf": jsf, "n_p": n_p}


def test_every_ordering_the_text_states_holds_in_the_reading():
    els15, cls, pe2, se2 = (_row(k) for k in ("ELS (15)", "CLS (22)", "PE (D_SF) l=2", "SE (D_SF) l=2"))
    els17, pe3, se3, neural = (_row(k) for k in ("ELS (17)", "PE (D_SF) l=3", "SE (D_SF) l=3", "Neural"))
    # "the steady state performance ... improved at a rather acceptable loss of dynamical performance"
    assert cls["jsf"] < els15["jsf"] and cls["valid"] > els15["valid"]
    # PE (D_SF): "its dynamic response is worse than the ELS solution to (15) in the identification and validation"
    assert pe2["ident"] > els15["ident"] and pe2["valid"] > els15["valid"]
    # "Model (17) outperforms model (15) in all criteria shown in Table I"
    assert all(els17[k] < els15[k] for k in ("ident", "valid", "jsf"))
    # the ℓ = 3 SE model: better statically and on identification than ELS (17), "but was worse over the
    # dynamic validation data set"
    assert se3["jsf"] < els17["jsf"] and se3["ident"] < els17["ident"] and se3["valid"] > els17["valid"]
    # the SE ℓ = 2 set "dominates ... all solutions obtained by the black-box and other gray-box" approaches
    assert se2["ident"] < min(els15["ident"], cls["ident"], pe2["ident"]) and se2["valid"] < els15["valid"]
    # the neural model "outperformed the polynomial black-box models in all criteria"
    assert all(neural[k] < min(els15[k], els17[k]) for k in ("ident", "valid", "jsf"))
    # every D_SF choice lies in the band; ELS (15) far outside it; the parameter counts of (15), (17), the MLP
    assert all(r["jsf"] <= B for r in (cls, pe2, se2, pe3, se3)) and els15["jsf"] > 50 * B
    assert [r["n_p"] for r in (els15, els17, neural)] == [17, 23, 99]


def test_reproduce_reports_the_se_over_els_ratio_beside_the_papers():
    frame = pd.DataFrame({"JS_valid": [2.0, 1.0, 3.0, 4.0, 2.0, 6.0]},
                         index=["ELS (15)", "SE (D_SF) ℓ=2", "SE-grad (D_SF) ℓ=2",
                                "ELS (17)", "SE (D_SF) ℓ=3", "SE-grad (D_SF) ℓ=3"])
    line = se_against_els(frame)
    # the paper: 1.751 / 2.116 at ℓ = 2, 1.306 / 1.104 at ℓ = 3
    assert "ℓ = 2: paper 0.83, here SE 0.50, SE-grad 1.50" in line
    assert "ℓ = 3: paper 1.18, here SE 0.50, SE-grad 1.50" in line


def test_a_missing_row_is_named():
    frame = pd.DataFrame({"JS_valid": [2.0]}, index=["ELS (15)"])
    with pytest.raises(KeyError, match="SE"):
        se_against_els(frame)
