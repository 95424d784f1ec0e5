"""Review of hunts 45a-c: what their fixes left wrong (each test failed before its fix)."""
import numpy as np
import pytest

import graybox as gb


# -- simulate: a frame of the default input names is read by them in any column order ------------------------------
def test_a_frame_of_the_default_names_in_another_order_still_feeds_a_structure_using_some_of_them():
    import pandas as pd

    # 62ed8d8 kept the default names' reading only for the columns in the order u1, u2: a frame of columns u2, u1
    # (read by name before 440cdd0) was refused as naming 'only some of the inputs ['u2']'
    rng = np.random.default_rng(0)
    u = rng.uniform(size=(10, 2))
    st, th = ["y(k-1)", "u2(k-1)"], [0.5, 1.0]
    want = gb.simulate(st, th, u, [0.0])
    assert np.array_equal(gb.simulate(st, th, pd.DataFrame({"u2": u[:, 1], "u1": u[:, 0]}), [0.0]), want)
    st1 = ["y(k-1)", "u1(k-1)"]
    assert np.array_equal(gb.simulate(st1, th, pd.DataFrame({"u2": u[:, 1], "u1": u[:, 0]}), [0.0]),
                          gb.simulate(st1, th, u, [0.0]))


# -- static_fit_mse: an input's levels are told apart by the rank rule, not by exact equality ------------------------
def _curved_in_speed(s, v):
    return 0.4 * s + 0.3 * s ** 2 + 0.2 * v + 0.3


@pytest.mark.parametrize("low", [0.1 * 3, 0.3 * (1 + 2e-15)])
def test_two_valve_levels_apart_by_round_off_in_some_rows_are_still_two_levels(low):
    # bf53a00 counted an input's levels with np.unique: a grid whose valve is 0.3 in some rows and 0.1 * 3 (or 0.3
    # to the last digits) in others has 3 or 4 'levels', so valve² was asked of them, the fit was rank deficient and
    # the degree stopped at 1 (MSE 0.43 against a band of 0.0025), as before bf53a00
    from graybox.static._form_check import static_degree, static_fit_mse
    g = np.array([(a, low if i % 2 else 0.3) for i, a in enumerate((0.0, 0.6, 1.3, 2.0))]
                 + [(a, 2.5) for a in (0.0, 0.6, 1.3, 2.0)])
    assert len(np.unique(g[:, 1])) > 2
    pts = gb.StaticPoints(g, _curved_in_speed(g[:, 0], g[:, 1]) / 0.2, input_names=("speed", "valve"),
                          uncertainty=np.full(len(g), 0.05))
    mse = static_fit_mse(pts, 2)
    assert mse is not None and mse < 1e-20
    assert static_degree(pts, band=pts.band) == 2


# -- check_real: an integer beyond the float range is a ValueError naming the argument, as float_array's -------------
@pytest.mark.parametrize("call", [
    lambda big: gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0], Ts=big),
    lambda big: gb.Equilibrium(big, 1.0, True, 0.5),
    lambda big: gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0]).simulate(np.ones(5), [0.0], bound=big),
])
@pytest.mark.parametrize("digits", [400, 5000])  # 10**5000 has no repr (Python's 4300-digit limit)
def test_a_scalar_beyond_the_float_range_is_a_value_error_naming_it(call, digits):
    # 02b9655 turned numpy's OverflowError ('int too large to convert to float', naming nothing) into a ValueError
    # in float_array, the arrays' conversion; check_real, every scalar option's (Ts, bound, an equilibrium's
    # level), still let it through bare
    with pytest.raises(ValueError, match=r"(Ts|ubar|bound).*beyond the float range"):
        call(10**digits)


# -- a centred search: a signal held at one level whose records say the level apart by round-off --------------------
def test_a_centred_search_takes_a_level_said_apart_by_round_off_for_one_level():
    import sys
    import warnings
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from test_hunt45c import _rig

    # fbb827b centred a held input on its level only where every sample is bit-for-bit that level: the valve held at
    # 7.3 in one record and at 73 * 0.1 (7.300000000000001, a converted unit) in the other was centred on its mean, a
    # column of round-off that semp took for candidates (valve(k-1), speed(k-1)valve(k-1): 11 terms where both records
    # at 7.3 gave 10)
    cand = gb.Candidates(ny=2, nu=2, degree=2, input_names=("speed", "valve"))
    (s1, y1), (s2, y2) = _rig(200, 1), _rig(200, 2)
    found = []
    for second in (7.3, 73 * 0.1):
        recs = [gb.Record(np.c_[s1, np.full(200, 7.3)], y1, input_names=("speed", "valve"), name="a"),
                gb.Record(np.c_[s2, np.full(200, second)], y2, input_names=("speed", "valve"), name="b")]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", gb.CandidateWarning)  # the valve's terms, which the records cannot tell
            found.append((frozenset(map(str, gb.semp(cand, recs, centre=True).structure)),
                          frozenset(map(str, gb.frols(cand, recs, centre=True, criterion="bic").structure))))
    assert found[0] == found[1]
    assert not any("valve" in t for t in found[1][0] | found[1][1])
    # an output said apart by round-off is as constant as one said alike (eaf0046's refusal)
    rec = gb.Record(np.arange(40.0) % 3, np.r_[np.full(20, 7.3), np.full(20, 73 * 0.1)])
    with pytest.raises(ValueError, match=r"the output is constant \(y = 7\.3 at every sample .* to its round-off"):
        gb.frols(gb.Candidates(ny=1, nu=1, degree=1), rec, centre=True, n_terms=2)


# -- a frame holding every input and a column more is told to pass the inputs' columns ------------------------------
def test_a_frame_with_a_column_more_than_the_inputs_is_told_to_pass_the_inputs_columns():
    import pandas as pd

    # d3e7317 refuses df[['speed', 'valve']] for a model in speed alone, with frame_inputs' advice for a frame naming
    # some inputs: 'Name every column as an input ... or none (read by position)', which renaming valve (no input
    # of the model) cannot follow; what reads it is the inputs' columns alone
    m = gb.Model(["y(k-1)", "speed(k-1)"], [0.5, 1.0])
    df = pd.DataFrame({"speed": np.ones(5), "valve": np.zeros(5)})
    with pytest.raises(ValueError, match=r"not inputs: \['valve'\].*df\[\['speed'\]\]"):
        m.simulate(df, [0.0])


# -- thetas and per-point values beyond the float range: the ValueError float_array says, not numpy's -----------------
@pytest.mark.parametrize("call", [
    lambda rec: gb.simulate_many(["y(k-1)", "u(k-1)"], [[0.5, 10**400]], rec),
    lambda rec: gb.evaluate_thetas(["y(k-1)", "u(k-1)"], [[0.5, 10**400]], rec),
    lambda rec: gb.StaticPoints([0.1, 0.2], [1.0, 2.0], uncertainty=[1.0, 10**400]),
], ids=["simulate_many", "evaluate_thetas", "uncertainty"])
def test_thetas_and_per_point_values_beyond_the_float_range_are_a_value_error_naming_them(call):
    # 02b9655 said an integer beyond the float range as a ValueError in float_array; simulate_many's and
    # evaluate_thetas' thetas and check_per_point (static points' uncertainty) converted with np.asarray and
    # raised numpy's bare OverflowError ('int too large to convert to float')
    rng = np.random.default_rng(0)
    rec = gb.Record(rng.uniform(size=50), rng.uniform(size=50))
    with pytest.raises(ValueError, match=r"(thetas|uncertainty).*beyond the float range"):
        call(rec)


# -- Model(carrier, θ) keeps the carrier's input names ----------------------------------------------------------------
def test_a_model_made_from_what_carries_a_structure_keeps_its_input_names():
    import pandas as pd

    # 4529674 took the structure from a Selection or a Model and left their input names: Model(sel, θ) of a selection
    # on (speed, valve) data, speed alone chosen, had inputs ('speed',) where sel.model has ('speed', 'valve'), so
    # the frame of the data's inputs that sel.model simulates was refused by it
    rng = np.random.default_rng(0)
    u = rng.uniform(size=(200, 2))
    y = np.zeros(200)
    for k in range(1, 200):
        y[k] = 0.5 * y[k - 1] + u[k - 1, 0]
    rec = gb.Record(u, y, input_names=("speed", "valve"))
    sel = gb.frols(gb.Candidates(1, 1, degree=1, input_names=("speed", "valve")), rec, n_terms=2)
    assert sel.structure.input_names == ("speed",)
    df = pd.DataFrame(u, columns=["speed", "valve"])
    for carrier in (sel, sel.model):
        m = gb.Model(carrier, sel.model.theta)
        assert m.input_names == ("speed", "valve")
        assert np.array_equal(m.simulate(df, y[:1]), sel.model.simulate(df, y[:1]))
    # input_names given still rule
    assert gb.Model(sel, sel.model.theta, input_names=("speed",)).input_names == ("speed",)


# -- the public regressor functions take a structure from what carries one, as the static ones now do -----------------
def test_the_regressor_functions_take_terms_or_what_carries_a_structure():
    # d611268 made the static functions read a Model's or a Selection's .structure; gb.regressor_matrix and
    # gb.stacked_regressors still failed on them, and on a list of terms, with "'Selection' object has no attribute
    # 'max_lag'" or "object of type 'Model' has no len()", naming nothing
    rng = np.random.default_rng(0)
    rec = gb.Record(rng.uniform(size=100), rng.uniform(size=100))
    sel = gb.frols(gb.Candidates(1, 1), rec, n_terms=2)
    want = gb.regressor_matrix(sel.structure, rec.u, rec.y)
    for carrier in (sel, sel.model, [str(t) for t in sel.structure]):
        assert np.array_equal(gb.regressor_matrix(carrier, rec.u, rec.y), want)
        psi, _ = gb.stacked_regressors(carrier, [rec])
        assert np.array_equal(psi, want)
    with pytest.raises(TypeError, match="structure must be"):
        gb.regressor_matrix(None, rec.u, rec.y)
