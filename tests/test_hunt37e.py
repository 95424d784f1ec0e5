"""Bug hunt hunt37e: today's changes on main and how they meet (the one rank rule, SpecTypeError in grid specs,
an integrator's continuum of equilibria, grid keys holding the band only where read, hunt37a/b/c's changes), used
as a control engineer would on their own data. Each test fails without its fix."""

import numpy as np
import pytest

import graybox as gb

GOOD_SPEC = """name = "g"
[[data]]
name = "pumping"
bundled = "pumping"
[[structures]]
name = "s1"
terms = ["1", "y(k-1)", "u(k-1)"]
[[variants]]
name = "LS"
estimator = "ls"
"""


def _spec_type_error(old: str, new: str) -> gb.experiments.SpecError:
    text = GOOD_SPEC.replace(old, new, 1)
    assert text != GOOD_SPEC
    with pytest.raises(TypeError) as info:
        gb.experiments.Grid.from_toml_text(text, source="spec.toml")
    assert isinstance(info.value, gb.experiments.SpecError) and "spec.toml, line" in str(info.value)
    return info.value


@pytest.mark.parametrize("make", [lambda: gb.Structure([1, 2]), lambda: gb.Model([3], [1.0]),
                                  lambda: gb.Structure(["1", None]), lambda: gb.parse_term(2.5)])
def test_a_term_that_is_no_text_is_a_type_error(make):
    # parse_term raised ValueError('a term must be a string, got int') for a term that is not text, so
    # Structure([1, 2]) and Model([3], …) gave a ValueError for a wrong type, and a grid spec's terms = [1, 2]
    # a plain SpecError where every other wrong type of a spec is a SpecTypeError.
    with pytest.raises(TypeError, match="a term must be a string"):
        make()


def test_a_spec_term_that_is_no_text_is_a_spec_type_error():
    err = _spec_type_error('terms = ["1", "y(k-1)", "u(k-1)"]', "terms = [1, 2]")
    assert "structures[0].terms" in str(err)


@pytest.mark.parametrize("new, where", [
    ('estimator = "pe"\nconstraints = [{type = 3}]', "constraints[0].type"),
    ('estimator = "pe"\nconstraints = [{type = ["band"]}]', "constraints[0].type"),
    ('estimator = "pe"\nconstraints = [{type = "equality", curve = 3}]', "constraints[0].curve"),
    ('estimator = "pe"\nconstraints = [{type = "equality", curve = true}]', "constraints[0].curve"),
])
def test_a_constraint_type_or_curve_of_the_wrong_type_is_a_spec_type_error(new, where):
    # {type = 3} was 'unknown constraint type 3' and {curve = 3} 'curve must be "fit", …', both plain SpecErrors
    # (ValueErrors) for a value of the wrong type; a wrong value ({type = "bands"}) stays a plain SpecError.
    err = _spec_type_error('estimator = "ls"', new)
    assert where in str(err)
    text = GOOD_SPEC.replace('estimator = "ls"', 'estimator = "pe"\nconstraints = [{type = "bands"}]')
    with pytest.raises(gb.experiments.SpecError) as info:
        gb.experiments.Grid.from_toml_text(text, source="spec.toml")
    assert not isinstance(info.value, TypeError) and "unknown constraint type 'bands'" in str(info.value)
