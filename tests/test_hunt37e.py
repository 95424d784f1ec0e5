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


def test_min_correlation_on_a_record_that_does_not_move_names_it():
    # decide_min_correlation on a record held at a steady state (input and output constant: every member's free
    # run and one-step prediction constant, no correlation defined) said 'no member has a defined residual/output
    # correlation (every free run diverged?)', blaming free runs that had all stayed finite.
    true = gb.Model(["1", "y(k-1)", "n(k-1)"], [1e5, 0.5, 20.0], input_names=("n",))
    rng = np.random.default_rng(0)
    n_ = np.repeat(rng.uniform(2500.0, 3500.0, 30), 20)[:500]
    rec = gb.Record(n_, true.simulate(n_, np.full(1, 3.2e5)) + 5.0 * rng.standard_normal(500), 0.1,
                    input_names=("n",))
    levels = np.linspace(2600.0, 3400.0, 5)
    front = gb.pe_pareto(true.structure, gb.Dataset(rec, rec, gb.StaticPoints(levels, true.static_curve(levels),
                                                                                input_names=("n",))),
                         lambdas=[1e-3, 0.1, 1.0])
    steady = gb.Record(np.full(100, 3000.0), np.full(100, true.static_curve([3000.0])[0]), 0.1, input_names=("n",))
    for output in ("free-run", "one-step"):
        with pytest.raises(ValueError, match="does not move") as info:
            gb.decide_min_correlation(front, steady, output=output)
        assert "diverged" not in str(info.value)
    assert np.isfinite(gb.decide_min_correlation(front, rec).score)  # a record that moves: decided as before
