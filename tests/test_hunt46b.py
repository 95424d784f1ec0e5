"""Bug hunt 46b: the agreements of the whole public API (immutable values, validation, coercion, files)."""

import copy
import operator
import pickle

import numpy as np
import pytest

import graybox as gb

_REC = gb.Record([1.0, 2.0, 3.0, 4.0], [0.5, 0.25, 0.125, 0.0625], name="short")


# -- a Dataset's extra: a read-only copy all the way down ---------------------------------------------------
def test_a_dataset_s_extra_shares_no_nested_list_dict_or_array_with_the_caller():
    # was: only the outer mapping was copied; the caller's nested list, dict and array stayed tied to the Dataset
    mine = {"levels": [1.0, 2.0], "info": {"site": "A"}, "curve": np.array([1.0, 2.0])}
    data = gb.Dataset(_REC, _REC, extra=mine)
    mine["levels"].append(3.0)
    mine["info"]["site"] = "B"
    mine["curve"][0] = 99.0
    assert list(data.extra["levels"]) == [1.0, 2.0]
    assert data.extra["info"]["site"] == "A"
    assert data.extra["curve"][0] == 1.0


def test_a_dataset_s_extra_cannot_be_changed_through_its_nested_values():
    data = gb.Dataset(_REC, _REC, extra={"levels": [1.0, [2.0]], "info": {"site": "A"}, "curve": np.ones(2)})
    for change in (lambda: data.extra["levels"].append(3.0), lambda: operator.setitem(data.extra["levels"], 0, 5.0),
                   lambda: data.extra["levels"][1].append(1.0), lambda: data.extra["levels"].sort(),
                   lambda: operator.setitem(data.extra["info"], "site", "B")):
        with pytest.raises(TypeError):
            change()
    with pytest.raises(ValueError):
        data.extra["curve"][0] = 2.0
    levels = data.extra["levels"]
    with pytest.raises(TypeError):
        levels += [4.0]
    assert data.extra["levels"] == [1.0, [2.0]]  # still a list to the reader, equal to the one given


def test_a_frozen_extra_pickles_copies_and_round_trips_through_json_as_lists():
    data = gb.Dataset(_REC, _REC, extra={"names": ["u1", "u2"], "pair": (1, [2])})
    for back in (pickle.loads(pickle.dumps(data)), copy.deepcopy(data), gb.from_json(gb.to_json(data))):
        assert back.extra["names"] == ["u1", "u2"] and back.extra["pair"] == (1, [2])
        assert isinstance(back.extra["names"], list) and isinstance(back.extra["pair"], tuple)
        with pytest.raises(TypeError):
            back.extra["names"].append("u3")


def test_a_self_holding_or_absurdly_nested_extra_is_refused_with_the_field_named():
    # was: a bare RecursionError from to_json (and no word of which field)
    loop = []
    loop.append(loop)
    deep = []
    for _ in range(5000):
        deep = [deep]
    for bad in (loop, deep):
        with pytest.raises(ValueError, match=r"extra\['a'\]"):
            gb.Dataset(_REC, _REC, extra={"a": bad})


def test_to_json_refuses_a_value_nested_deeper_than_a_file_reads_back():
    from graybox.io import _json

    deep = []
    for _ in range(5000):
        deep = [deep]
    with pytest.raises(ValueError, match="nested deeper"):
        _json._enc_plain(deep, "Dataset.extra['a']")
    ok = []
    for _ in range(50):
        ok = [ok]
    data = gb.Dataset(_REC, _REC, extra={"a": ok})
    assert gb.from_json(gb.to_json(data)).extra["a"] == ok


def test_from_json_refuses_a_hand_nested_plain_value_as_a_corrupt_file():
    text = gb.to_json(gb.Dataset(_REC, _REC, extra={"a": 1.0}))
    deep = "1.0"
    for _ in range(450):  # within what json itself reads
        deep = '{"list": [' + deep + "]}"
    with pytest.raises(gb.GrayboxFileError, match="nested deeper"):
        gb.from_json(text.replace('"a": 1.0', '"a": ' + deep))


# -- sizes that end in a MemoryError are refused up front, naming the option -------------------------------
def test_gain_bounds_refuses_an_absurd_number_of_levels():
    # was: any n; GainBounds(lower=0, n=10**9) ended in a MemoryError inside the estimator
    with pytest.raises(ValueError, match="n must be an integer <="):
        gb.GainBounds(lower=0.0, n=10**9)
    assert gb.GainBounds(lower=0.0, n=1000).n == 1000


def test_a_grid_of_levels_beyond_a_million_points_names_the_option():
    from graybox.static._surfaces import box_grid

    with pytest.raises(ValueError, match="GainBounds: n.*1000\\^3"):
        box_grid([(0.0, 1.0)] * 3, 1000, "GainBounds: n")
    assert box_grid([(0.0, 1.0), (2.0, 2.0)], 1000).shape == (1000, 2)  # an input held at one level is one level


def test_candidates_refuses_an_absurd_lag_or_degree_up_front():
    # was: Candidates(ny=10**9, nu=1) ended in a MemoryError; a degree of 10**9 never finished
    for kwargs in ({"ny": 10**9, "nu": 1}, {"ny": 1, "nu": 10**9}, {"ny": 2, "nu": 2, "ne": 10**9},
                   {"ny": 10**9, "nu": 10**9, "degree": 10**9}, {"ny": 100, "nu": 100, "degree": 3}):
        with pytest.raises(ValueError, match="candidate terms, more than"):
            gb.Candidates(**kwargs)


def test_candidates_builds_only_the_output_powers_it_keeps():
    # max_y_power=1 of ny=400 at degree 3 enumerated all 10^7 products of y before dropping them
    s = gb.Candidates(ny=400, nu=1, degree=3, max_y_power=1)
    assert max(t.power_of("y") for t in s.terms) == 1 and len(s) == 1 + 401 + 401 + 1 + 400
    assert len(gb.Candidates(ny=3, nu=0, degree=10**9, max_y_power=1)) == 4
    assert len(gb.Candidates(ny=10**9, nu=2, degree=2, max_y_power=0)) == 1 + 2 + 3
    assert len(gb.Candidates(ny=10**9, nu=10**9, degree=0)) == 1  # the constant alone (was: killed, out of memory)


@pytest.mark.parametrize("kwargs", [{"ny": 3, "nu": 2, "degree": 3}, {"ny": 2, "nu": 3, "degree": 3, "max_y_power": 1},
                                    {"ny": 2, "nu": {"a": 2, "b": 3}, "degree": 2, "delay": {"b": 2}, "ne": 2},
                                    {"ny": 0, "nu": 3, "degree": 2, "constant": False},
                                    {"ny": 2, "nu": 1, "degree": 4, "max_y_power": 2}])
def test_candidates_count_agrees_with_every_monomial_by_brute_force(kwargs):
    import itertools

    s = gb.Candidates(**kwargs)
    nu = kwargs["nu"] if isinstance(kwargs["nu"], dict) else {"u": kwargs["nu"]}
    delay = kwargs.get("delay", {})
    var = [("y", i) for i in range(1, kwargs["ny"] + 1)] + [(n, j) for n, m in nu.items()
                                                           for j in range(delay.get(n, 1), m + 1)]
    want = {gb.Term(tuple((v, l, 1) for v, l in c)) for d in range(kwargs["degree"] + 1)
            for c in itertools.combinations_with_replacement(var, d)}
    want = {t for t in want if t.power_of("y") <= kwargs.get("max_y_power", 99)
            and (kwargs.get("constant", True) or not t.is_constant)}
    assert set(s.process.terms) == want and len(s.process) == len(want)
    assert list(s.process.terms) == sorted(s.process.terms, key=gb.Term.sort_key)
    assert len(s.noise) == kwargs.get("ne", 0)


# -- one coercion of a structure: every function that takes one takes the same kinds ------------------------
@pytest.fixture(scope="module")
def fitted():
    rng = np.random.default_rng(3)
    u = np.repeat(rng.uniform(1.0, 2.0, 40), 10)
    y = np.zeros(u.size)
    for k in range(1, u.size):
        y[k] = 0.6 * y[k - 1] + 0.5 * u[k - 1] + 0.1 * u[k - 1] ** 2
    rec = gb.Record(u, y + 1e-3 * rng.standard_normal(u.size), name="r")
    cand = gb.Candidates(1, 1, degree=2)
    res = gb.els(gb.frols(cand, rec, n_terms=3), rec)
    return rec, cand, res


def test_the_low_level_functions_take_a_result_that_carries_a_model(fitted):
    # was: simulate, predict, static_curve, equilibria, the cluster maps … refused an ELSResult or a Decision
    # ("structure must be a Structure, a sequence of terms or a model, got ELSResult") while the estimators took it
    rec, _, res = fitted
    m = res.model
    th = m.theta
    np.testing.assert_array_equal(gb.simulate(res, th, rec), gb.simulate(m.structure, th, rec))
    np.testing.assert_array_equal(gb.predict(res, th, rec), gb.predict(m.structure, th, rec))
    np.testing.assert_array_equal(gb.static_curve(res, th, [1.5]), m.static_curve([1.5]))
    assert gb.equilibria(res, th, 1.5) == m.equilibria(1.5)
    assert gb.cluster_map(res).names == m.cluster_map().names
    np.testing.assert_array_equal(gb.regressor_matrix(res, rec.u, rec.y), gb.regressor_matrix(m.structure, rec.u, rec.y))
    assert gb.Model(res, th).structure == m.structure


def test_frols_and_semp_take_their_candidates_as_every_structure_argument_is_taken(fitted):
    # was: "candidates must be a Structure (e.g. Candidates(...)), got list" for a list of terms
    rec, cand, _ = fitted
    terms = [str(t) for t in cand]
    assert gb.frols(terms, rec, n_terms=3).structure == gb.frols(cand, rec, n_terms=3).structure
    assert gb.semp(terms, rec, n_terms=2).structure == gb.semp(cand, rec, n_terms=2).structure
    with pytest.raises(TypeError, match="candidates must be a Structure, a sequence of terms.*parse_structure"):
        gb.frols(" + ".join(terms), rec, n_terms=3)
    with pytest.raises(TypeError, match="candidates must be a Structure, a sequence of terms.*OEResult"):
        gb.semp(3, rec, n_terms=2)


def test_the_estimators_take_any_sequence_of_terms_as_the_rest_do(fitted):
    # was: els and the other estimators refused a NumPy array of term strings (what a DataFrame column gives), which
    # simulate and static_curve took; a generator of terms was taken by simulate and refused by els
    rec, _, res = fitted
    terms = [str(t) for t in res.model.structure]
    want = gb.els(terms, rec).model.theta
    np.testing.assert_array_equal(gb.els(np.array(terms), rec).model.theta, want)
    with pytest.raises(TypeError, match=r"structure: a term must be a string"):
        gb.els([1, 2], rec)
    # read once, a generator is refused alike (pe_pareto, which reads its structure twice, said "no terms")
    for call in (lambda s: gb.els(s, rec), lambda s: gb.pe_pareto(s, rec, lambdas=[1.0]),
                 lambda s: gb.simulate(s, res.model.theta, rec)):
        with pytest.raises(TypeError, match="which can be read only once: pass a list of its terms"):
            call(t for t in terms)


def test_els_refuses_an_ma_order_beyond_the_records_before_building_its_terms(fitted):
    # was: els(..., noise=10**12) built 10^12 noise terms before the record's length was read (never finished)
    rec, _, res = fitted
    with pytest.raises(ValueError, match=r"noise: ne = 1000000000000 .*longest record has \(400\)"):
        gb.els(res, rec, noise=10**12)
    with pytest.raises(ValueError, match=r"noise: ne = 400"):
        gb.els(res, rec, noise=400)
    assert len(gb.els(res, rec, noise=3).model.noise_structure) == 3


def test_els_names_noise_for_a_number_among_its_terms(fitted):
    rec, _, res = fitted
    with pytest.raises(TypeError, match="noise: a term must be a string"):
        gb.els(res, rec, noise=[1, 2])


# -- design_input: a staircase of many inputs ----------------------------------------------------------------
def test_a_staircase_of_many_inputs_says_which_never_move_instead_of_running_out_of_memory():
    # was: n_inputs=30 built the whole 2^30-point grid (MemoryError: 8 GiB) before taking the record's 100 holds
    with pytest.raises(ValueError, match="never moves"):
        gb.design_input("staircase", 1000, n_inputs=30, low=0.0, high=1.0, hold=10)
    with pytest.raises(ValueError, match="never moves"):
        gb.design_input("staircase", 1000, n_inputs=80, low=0.0, high=1.0, hold=10)


@pytest.mark.parametrize("n, m, hold", [(1000, 3, 10), (300, 2, 5), (2000, 4, 5), (60, 1, 3), (4000, 6, 20)])
def test_a_staircase_that_fits_is_the_same_walk_as_before(n, m, hold):
    # the serpentine over the whole grid, there and back: every move changes one input by one level
    u = gb.design_input("staircase", n, n_inputs=m, low=0.0, high=1.0, hold=hold)
    holds = u[::hold] if m > 1 else u[::hold, None]
    steps = np.abs(np.diff(holds, axis=0))
    assert np.all((steps > 0).sum(axis=1) <= 1)
    assert holds.min() == 0.0 and holds.max() == 1.0


# -- a structure pickled to another process ------------------------------------------------------------------
def test_a_structure_pickled_to_another_process_hashes_as_an_equal_one_there():
    # was: the cached hash travelled with the pickle; str hashes differ per process (PYTHONHASHSEED), so in a
    # worker the structure equalled a fresh one but missed every set and dict keyed by it
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = str(Path(gb.__file__).parents[1])
    env = {**os.environ, "PYTHONPATH": root + os.pathsep + os.environ.get("PYTHONPATH", "")}
    make = ("import pickle, sys, graybox as gb; s = gb.Structure(['y(k-1)', 'u(k-1)', 'u(k-1)y(k-1)']); hash(s); "
            "m = gb.Model(s, [0.5, 1.0, 0.1]); hash(m.structure); sys.stdout.buffer.write(pickle.dumps((s, m)))")
    blob = subprocess.run([sys.executable, "-c", make], capture_output=True, check=True,
                          env={**env, "PYTHONHASHSEED": "1"}).stdout
    read = ("import pickle, sys, graybox as gb; s, m = pickle.loads(sys.stdin.buffer.read()); "
            "t = gb.Structure(['y(k-1)', 'u(k-1)', 'u(k-1)y(k-1)']); "
            "print(s == t, hash(s) == hash(t), s in {t}, m.structure in {t})")
    out = subprocess.run([sys.executable, "-c", read], input=blob, capture_output=True, check=True,
                         env={**env, "PYTHONHASHSEED": "2"}).stdout.decode().split()
    assert out == ["True"] * 4
    s = gb.Structure(["y(k-1)"])
    hash(s)
    assert copy.deepcopy(s) == s and hash(copy.deepcopy(s)) == hash(s) and pickle.loads(pickle.dumps(s)) in {s}


# -- constructors name the field of a wrong type ---------------------------------------------------------------
@pytest.mark.parametrize("bounds", [0.5, [("Σy", (0, 1))], None, "Σy", True])
def test_cluster_bounds_of_a_wrong_type_is_a_type_error_naming_bounds(bounds):
    # was: "'float' object is not iterable", "dictionary update sequence element #0 …" (a ValueError for a str)
    with pytest.raises(TypeError, match="ClusterBounds: bounds must be a mapping"):
        gb.ClusterBounds(bounds)
    with pytest.raises(ValueError, match="at least one cluster"):
        gb.ClusterBounds({})


def test_model_names_noise_structure_for_a_number_among_its_terms():
    with pytest.raises(TypeError, match="noise_structure: a term must be a string"):
        gb.Model(["y(k-1)"], [0.5], noise_structure=[1, 2])


def test_gain_bounds_per_input_are_a_copy_not_the_caller_s_list():
    # was: GainBounds kept the caller's list (or array), so changing it afterwards changed the constraint
    lows, highs = [0.0, None], np.array([5.0, 6.0])
    g = gb.GainBounds(lower=lows, upper=highs)
    lows[0], highs[0] = -100.0, -50.0
    assert g.lower == (0.0, None) and g.upper == (5.0, 6.0)
    assert g._bounds(2) == [(0.0, 5.0), (None, 6.0)]
    assert gb.GainBounds(lower=np.float32(0.5)).lower == 0.5
    assert gb.GainBounds(lower=[0.0])._bounds(2) == [(0.0, None), (0.0, None)]  # one entry: every input


# -- the guide's calls match the signatures ----------------------------------------------------------------------
def _split_args(text):
    parts, depth, cur = [], 0, ""
    for ch in text:
        if ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append(cur.strip())
            cur = ""
        else:
            cur += ch
    return [p for p in parts + [cur.strip()] if p]


def test_the_calls_the_guide_and_readme_write_in_prose_fit_the_signatures():
    # was: black_box.md said `Candidates(ny, nu, ne, degree, ...)`, but ne and degree are keyword-only
    import inspect
    import re
    from pathlib import Path

    root = Path(__file__).parents[1]
    bad = []
    for path in sorted((root / "docs" / "guide").glob("*.md")) + [root / "README.md"]:
        for m in re.finditer(r"`(?:gb\.)?([A-Za-z_]\w*)\(([^`]*)\)`", path.read_text(encoding="utf-8")):
            f = getattr(gb, m.group(1), None)
            if not inspect.isfunction(f):
                continue
            params = inspect.signature(f).parameters.values()
            parts = _split_args(m.group(2))
            pos = [a for a in parts if not re.match(r"^\w+\s*=", a) and a not in ("...", "…") and not a.startswith("*")]
            kws = [a.split("=")[0].strip() for a in parts if re.match(r"^\w+\s*=", a)]
            n_pos = sum(p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) for p in params)
            if len(pos) > n_pos or any(k not in {p.name for p in params} for k in kws):
                bad.append(f"{path.name}: {m.group(0)}")
    assert not bad, bad


# -- a Dataset where one record is meant and the call cannot tell which --------------------------------------
def test_the_free_run_and_prediction_entries_tell_a_dataset_which_record_to_pass(fitted):
    # was: "record must be a Record, got Dataset" and "u must be an array of numbers, got Dataset", no word of
    # data.ident or data.valid (the plots said it; README: a Dataset stands for a record where the call means one)
    rec, _, res = fitted
    m = res.model
    data = gb.Dataset(rec, rec)
    for call in (lambda: gb.predict(m.structure, m.theta, data), lambda: gb.simulate_many(m.structure, m.theta[None], data),
                 lambda: gb.simulate(m.structure, m.theta, data), lambda: m.simulate(data), lambda: m.predict(data),
                 lambda: gb.narx_initial_state(m, data)):
        with pytest.raises(TypeError, match=r"got Dataset; pass one of its records: data.ident or data.valid"):
            call()


# -- regressor_matrix checks the signals it is given -------------------------------------------------------------
def test_regressor_matrix_takes_lists_and_refuses_bad_signals_naming_them(fitted):
    # was: lists or None were an AttributeError ("'list' object has no attribute 'shape'"), a u shorter than y
    # numpy's broadcast error, a NaN in u a silent NaN column
    rec, _, res = fitted
    want = gb.regressor_matrix(res, rec.u, rec.y)
    np.testing.assert_array_equal(gb.regressor_matrix(res, list(rec.u), list(rec.y)), want)
    with pytest.raises(TypeError, match="^u must be"):
        gb.regressor_matrix(res, None, rec.y)
    with pytest.raises(TypeError, match="^y must be"):
        gb.regressor_matrix(res, rec.u, "x")
    with pytest.raises(ValueError, match="u has 10 samples but y has 400"):
        gb.regressor_matrix(res, rec.u[:10], rec.y)
    u = np.array(rec.u)
    u[7] = np.nan
    with pytest.raises(ValueError, match="u"):
        gb.regressor_matrix(res, u, rec.y)


def test_parse_structure_refuses_what_is_neither_text_nor_a_sequence_naming_it():
    # was: "'NoneType' object is not iterable"; a dict had its keys parsed as terms
    for bad in (None, 3, {"y(k-1)": 1}):
        with pytest.raises(TypeError, match="text must be a '\\+'-joined string"):
            gb.parse_structure(bad)
    assert gb.parse_structure(("y(k-1)", "u(k-1)")) == gb.parse_structure("y(k-1) + u(k-1)")


def test_stacked_regressors_names_its_records_argument(fitted):
    with pytest.raises(TypeError, match="^records must be a Record"):
        gb.stacked_regressors(fitted[2], 3.0)


# -- records given as a generator ------------------------------------------------------------------------------
def test_records_given_as_a_generator_are_refused_alike_by_every_entry(fitted):
    # was: frols, pe_pareto, local_model(data=) said "data: no records given (an empty sequence)" of two records
    # given as a generator (read once, then read again), while els and semp took it
    rec, cand, res = fitted
    other = gb.Record(rec.u[::-1].copy(), rec.y[::-1].copy(), name="other")
    for call in (lambda d: gb.frols(cand, d, n_terms=2), lambda d: gb.semp(cand, d, n_terms=2),
                 lambda d: gb.els(res, d, noise=2), lambda d: gb.pe_pareto(res, d, lambdas=[1.0]),
                 lambda d: gb.local_model(res.model, 1.5, data=d)):
        with pytest.raises(TypeError, match="which can be read only once: pass a list"):
            call(r for r in (rec, other))
    assert len(gb.els(res, [rec, other], noise=2).model.noise_structure) == 2
