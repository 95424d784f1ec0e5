"""Bug hunt hunt37e: today's changes on main and how they meet (the one rank rule, SpecTypeError in grid specs,
an integrator's continuum of equilibria, grid keys holding the band only where read, hunt37a/b/c's changes), used
as a control engineer would on their own data. Each test fails without its fix."""

import numpy as np
import pytest

import graybox as gb

from test_mend37 import GOOD_SPEC  # the smallest valid grid spec (bundled pumping data, one LS variant)


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


def _pressure_uncertainty() -> gb.ParameterUncertainty:
    """ls_uncertainty of p(k) = 1e5 + 0.5 p(k-1) + 20 n(k-1) (Pa against rpm) on a noisy record."""
    rng = np.random.default_rng(0)
    true = gb.Model(["1", "y(k-1)", "n(k-1)"], [1e5, 0.5, 20.0], input_names=("n",))
    n_ = np.repeat(rng.uniform(2500.0, 3500.0, 30), 20)[:500]
    rec = gb.Record(n_, true.simulate(n_, np.full(1, 3.2e5)) + 50.0 * rng.standard_normal(500), 0.1,
                    input_names=("n",))
    return gb.ls_uncertainty(gb.cls(true.structure, rec, solver="closed").model, rec)


def test_a_covariance_changed_without_its_factor_is_refused():
    # Monte Carlo bands and contractions draw through cov_factor (hunt37b), intervals read cov: a covariance
    # replaced without its factor (dataclasses.replace(unc, cov=100 * unc.cov), or a hand-edited file) gave
    # std 10 times as large and the very same static band, without a word.
    import dataclasses

    unc = _pressure_uncertainty()
    with pytest.raises(ValueError, match="cov_factor F is not a factor of cov"):
        dataclasses.replace(unc, cov=100.0 * unc.cov)
    big = dataclasses.replace(unc, cov=100.0 * unc.cov, cov_factor=None)  # a covariance of one's own: its own band
    np.testing.assert_allclose(big.std, 10.0 * unc.std)
    wide, narrow = (gb.static_curve_band(u, [3000.0], seed=0).to_frame().iloc[0] for u in (big, unc))
    assert wide["ybar high"] - wide["ybar low"] > 5.0 * (narrow["ybar high"] - narrow["ybar low"])
    assert dataclasses.replace(unc, cov=unc.cov.copy()).cov_factor is not None  # the same covariance keeps it


@pytest.mark.parametrize("edit, what", [
    (lambda c: np.full_like(c, np.nan), "non-finite"),
    (lambda c: -c, "negative variances"),
    (lambda c: c + np.triu(np.ones_like(c), 1), "is no covariance"),   # not symmetric, a correlation beyond 1
    (lambda c: c + np.triu(np.ones_like(c), 1) + np.tril(np.ones_like(c), -1), "is no covariance"),
])
def test_a_covariance_that_is_none_is_refused(edit, what):
    # ParameterUncertainty took any matrix as cov (a hand-edited file loads through it): NaN gave NaN intervals
    # and bands, a negative one zero-width ones (std clipped to 0), a correlation beyond ±1 a band of ±1.2e5 Pa
    # around 3.2e5 Pa, each without a word.
    unc = _pressure_uncertainty()
    with pytest.raises(ValueError, match=what):
        gb.ParameterUncertainty(unc.model, edit(unc.cov), 0.95, unc.dof, unc.sigma2, "LS", np.zeros((0, 3)),
                                np.zeros((0, 0)))


@pytest.mark.parametrize("value", ['"a"', '"ab"', "5", "true"])
def test_a_gain_range_that_is_no_list_is_a_spec_type_error(value):
    # ubar_range = "a" or 5 was 'ubar_range must be [low, high]', a plain SpecError (a ValueError), and "ab" (two
    # characters) a SpecTypeError about its letters: each is a value of the wrong type. A list of the wrong length
    # stays a wrong value.
    err = _spec_type_error('estimator = "ls"', f'estimator = "pe"\nconstraints = [{{type = "gain", lower = 0, '
                                               f'ubar_range = {value}}}]')
    assert "constraints[0].ubar_range" in str(err) and "must be a list" in str(err)
    text = GOOD_SPEC.replace('estimator = "ls"', 'estimator = "pe"\nconstraints = [{type = "gain", lower = 0, '
                                                 'ubar_range = [1, 2, 3]}]')
    with pytest.raises(gb.experiments.SpecError) as info:
        gb.experiments.Grid.from_toml_text(text, source="spec.toml")
    assert not isinstance(info.value, TypeError)


@pytest.fixture(scope="module")
def selection_doc():
    """The JSON document of a select_graybox result (least squares, p against n, two static points)."""
    import json

    from test_hunt37a import _pressure

    sel = gb.select_graybox(gb.Candidates(1, 1, degree=1), _pressure(400), sizes=[2, 3], estimator="ls",
                            progress=False)
    return json.loads(gb.to_json(sel))


@pytest.mark.parametrize("field, value, why", [("degree", -1, "degree must be None"),
                                                ("in_band", False, "chosen row's in_band is True")])
def test_a_graybox_selection_that_disagrees_with_itself_is_refused(selection_doc, field, value, why):
    # A hand-edited GrayboxSelection file with degree -1, or in_band False where the chosen row's in_band is True
    # (its repr then said 'in_band=False' of a choice its own table says is in the band), loaded without a word.
    import copy
    import json

    doc = copy.deepcopy(selection_doc)
    doc["object"][field] = value
    with pytest.raises(gb.GrayboxFileError, match=why):
        gb.from_json(json.dumps(doc))
    assert isinstance(gb.from_json(json.dumps(selection_doc)), gb.GrayboxSelection)


def test_pe_uncertainty_refuses_a_member_its_constraints_make_meet_the_points_exactly():
    # pe_uncertainty's default σ_SF is said to be refused when the member meets its static points exactly (its
    # misfit says nothing of their noise); a member held on 3 noisy points by PassesThrough met them exactly and
    # got σ_SF = 0 without a word (ν counted the points as free, misfit 0 / 3): the points taken as exact, as only
    # static_sigma=0 should say.
    rng = np.random.default_rng(0)
    st = ["1", "y(k-1)", "n(k-1)", "n(k-1)^2"]
    n_ = np.repeat(rng.uniform(2500.0, 3500.0, 30), 20)[:500]
    y = np.zeros(500)
    for k in range(1, 500):
        y[k] = 1e5 + 0.5 * y[k - 1] + 20.0 * n_[k - 1] + 1e-3 * (n_[k - 1] - 3000.0) ** 2
    rec = gb.Record(n_, y + 30.0 * rng.standard_normal(500), 0.1, input_names=("n",))
    levels = np.array([2600.0, 3000.0, 3400.0])
    ybar = 2e5 + 40.0 * levels + 20.0 * rng.standard_normal(3)
    data = gb.Dataset(rec, rec, gb.StaticPoints(levels, ybar, input_names=("n",)))
    for lam in (1.0, 0.1):
        front = gb.pe_pareto(st, data, lambdas=[lam], constraints=gb.PassesThrough())
        with pytest.raises(ValueError, match="meets its 3 static points exactly"):
            gb.pe_uncertainty(front.member_model(0), data, lambda1=lam, constraints=gb.PassesThrough())
        given = gb.pe_uncertainty(front.member_model(0), data, lambda1=lam, constraints=gb.PassesThrough(),
                                  static_sigma=20.0)
        assert given.static_sigma2 == 400.0


def test_inputs_left_with_their_default_names_say_how_to_name_them():
    # hunt37e's note: a single CSV input column is named "u", so a grid whose terms say speed(k-1) failed every
    # cell with "uses input 'speed', but the record's inputs are ('u',)" and no word of input_names
    rec = gb.Record(np.arange(20.0), np.arange(20.0))
    with pytest.raises(ValueError, match=r"default names: name them, e\.g\. Record\(\.\.\., input_names=\['speed'\]\)"):
        gb.simulate(["y(k-1)", "speed(k-1)"], [0.5, 1.0], rec)
    two = gb.Record(np.ones((20, 2)), np.arange(20.0))
    with pytest.raises(ValueError, match=r"one per column in the columns' order \(the structure uses 'n', 'p'\)"):
        gb.simulate(["y(k-1)", "p(k-1)", "n(k-1)"], [0.5, 1.0, 1.0], two)
    named = gb.Record(np.arange(20.0), np.arange(20.0), input_names=("valve",))
    with pytest.raises(ValueError) as e:  # named inputs: the plain message, no advice to name them
        gb.simulate(["y(k-1)", "speed(k-1)"], [0.5, 1.0], named)
    assert "default names" not in str(e.value)


def test_a_local_model_whose_status_contradicts_its_fields_is_refused():
    # hunt37e's note: a hand-edited file with status "no equilibrium" but a ȳ, or a status other than reached
    # with no reason, loaded without a word
    import dataclasses
    m = gb.Model(gb.parse_structure(["y(k-1)", "u(k-1)"]), [1.0, 0.5])
    none = gb.local_model(m, 1.0, Ts=0.1)  # an integrator off its balancing input: no equilibrium
    assert none.status == "no equilibrium" and none.ybar is None
    with pytest.raises(ValueError, match="status 'no equilibrium' has no ybar"):
        dataclasses.replace(none, ybar=3.0)
    with pytest.raises(ValueError, match="needs its reason"):
        dataclasses.replace(none, reason=" ")
