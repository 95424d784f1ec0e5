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



def test_an_equilibrium_saved_with_a_fourfold_roots_radius_loads():
    # 7f7c737 allowed 1e-4 'a fourfold root's' error, but numpy's roots of a fourfold root at z = 0.99999 (stable)
    # have modulus 1.000133 (2.4e-4 off at worst): such a file written before d0cd32f was still refused
    import json

    import numpy as np

    import graybox as gb
    radius = float(np.abs(np.roots(np.poly([0.99999] * 4))).max())
    assert radius > 1.0 + 1e-4
    doc = json.loads(gb.to_json(gb.Equilibrium(ubar=1.0, ybar=2.0, stable=True, spectral_radius=0.5)))
    doc["object"]["spectral_radius"] = radius
    back = gb.from_json(json.dumps(doc))
    assert back.stable and back.spectral_radius == radius
    doc["object"]["spectral_radius"] = 1.001  # clearly across: still refused
    with pytest.raises(gb.GrayboxFileError, match="spectral_radius"):
        gb.from_json(json.dumps(doc))
