"""mend50d: D_SF's fallback takes the member nearest the band; a loaded Pareto set still knows its fitting records;
batched equilibria of static equations of degree >= 4; the grid's counts."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as hs

import graybox as gb
from conftest import quadratic_first_order_data
from graybox import reference
from graybox.estimation._decisions import decide_dsf
from graybox.estimation._pareto import ParetoSet

S15 = reference.STRUCTURE_15


def front(js, jsf):
    k = len(js)
    th = np.tile(reference.TABLE_II["ELS"], (k, 1)) * (1 + 0.01 * np.arange(k))[:, None]
    return ParetoSet(S15, th, np.linspace(1.0, 0.1, k), np.zeros(k), np.asarray(js, float), np.asarray(jsf, float),
                     "PE")


# 1. the fallback 'min_jsf' with a two-sided band -------------------------------------------------------------------

def test_fallback_takes_the_member_nearest_a_two_sided_band():
    # every J_SF below B = [0.1, 0.2]: was member 2 (J_SF 0.001, the farthest from B); the nearest is member 0
    ps = front([1.0, 2.0, 3.0], [0.09, 0.05, 0.001])
    d = decide_dsf(ps, band=(0.1, 0.2), fallback="min_jsf")
    assert d.index == 0 and d.rule == "min J_SF" and not d.in_band
    assert "nearest" in d.model.name
    # without a fallback the error names the J_SF nearest B (0.09), not the smallest (0.001), and what the fallback takes
    with pytest.raises(ValueError, match=r"the J_SF nearest B is 0\.09\b.*fallback='min_jsf' to take the member with "
                                         r"the J_SF nearest B"):
        decide_dsf(ps, band=(0.1, 0.2))
    # below and above: the nearer side wins (0.25 is 0.05 above, 0.02 is 0.08 below)
    assert decide_dsf(front([1.0, 2.0], [0.02, 0.25]), band=(0.1, 0.2), fallback="min_jsf").index == 1
    # equally far on either side: the smaller J_S, as ties always were
    assert decide_dsf(front([2.0, 1.0], [0.05, 0.25]), band=(0.1, 0.2), fallback="min_jsf").index == 1


@settings(max_examples=60, deadline=None)
@given(hs.lists(hs.floats(0.0, 10.0), min_size=1, max_size=6), hs.floats(0.01, 5.0), hs.floats(0.01, 5.0))
def test_fallback_is_nearest_to_the_band_and_unchanged_for_zero_low(jsf, low, width):
    jsf = np.asarray(jsf)
    js = 1.0 + np.arange(jsf.size)
    high = low + width
    assume(not np.any((jsf >= low) & (jsf <= high)))
    d = decide_dsf(front(js, jsf), band=(low, high), fallback="min_jsf")
    dist = np.maximum(np.maximum(low - jsf, jsf - high), 0.0)
    assert dist[d.index] == dist.min()
    # B = [0, b]: still the smallest J_SF (ties by J_S: the lower index here)
    assume(not np.any(jsf <= high))
    assert decide_dsf(front(js, jsf), band=high, fallback="min_jsf").index == int(np.argmin(jsf))


# 2. a Pareto set saved and loaded still refuses its fitting records as choosing records -----------------------------

ST2 = gb.Structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"])


def _data2(seed: int = 0) -> gb.Dataset:
    return quadratic_first_order_data(seed)


def _joined(a: gb.Record, b: gb.Record, name: str) -> gb.Record:
    return gb.Record(np.concatenate([a.u, b.u]), np.concatenate([a.y, b.y]), name=name)


def _fitting_pieces(data: gb.Dataset) -> list[gb.Record]:
    """Records the fresh set refuses as choosing records: a copy, slices, and the end of one record the start of
    the fitting one (and the reverse)."""
    ident, valid = data.ident, data.valid
    return [gb.Record(ident.u.copy(), ident.y.copy(), name="copy"), ident.slice(50, 250, "middle"),
            ident.slice(123, None, "tail"), ident.slice(0, 77, "head"),
            _joined(valid.slice(0, 150), ident.slice(0, 150), "valid then ident"),
            _joined(ident.slice(200), valid, "ident's end then valid"),
            _joined(valid.slice(0, 100), _joined(ident, valid.slice(100, 200), "x"), "ident inside")]


def test_a_loaded_pareto_set_refuses_what_the_fresh_one_refuses(tmp_path):
    data = _data2()
    fresh = gb.pe_pareto(ST2, data, lambdas=np.logspace(-3, 0, 6))
    gb.save(fresh, tmp_path / "front.json")
    loaded = gb.load(tmp_path / "front.json")
    for rec in _fitting_pieces(data):
        with pytest.raises(ValueError, match="choose_on.*fitting"):
            gb.decide_dsf(fresh, band=1.0, choose_on=rec)
        with pytest.raises(ValueError, match="choose_on.*fitting"):
            gb.decide_dsf(loaded, band=1.0, choose_on=rec)
    # saved again, and subsets of it, still know
    gb.save(loaded.subset([0, 2, 4]), tmp_path / "again.json")
    with pytest.raises(ValueError, match="choose_on.*fitting"):
        gb.decide_dsf(gb.load(tmp_path / "again.json"), band=1.0, choose_on=data.ident.slice(10, 200))
    # data the fit did not see: chosen on, the same choice
    assert gb.decide_dsf(loaded, band=1.0, choose_on=data.valid).index == gb.decide_dsf(
        fresh, band=1.0, choose_on=data.valid).index
    # several fitting records: a slice of either is recognised
    r2 = _data2(1).ident
    two = gb.pe_pareto(ST2, [data.ident, r2], data.static, lambdas=np.logspace(-3, 0, 4))
    back = gb.from_json(gb.to_json(two))
    for rec in (data.ident.slice(30, 230, "first"), r2.slice(40, 280, "second")):
        with pytest.raises(ValueError, match="choose_on.*fitting"):
            gb.decide_dsf(back, band=1.0, choose_on=rec)
    assert gb.decide_dsf(back, band=1.0, choose_on=data.valid).chosen_on == "valid"


def test_a_loaded_set_sees_copies_by_their_bits_and_its_records_given_back_see_other_units():
    # the fresh set refused the fitting record with y × 1000 (the same data in other units, no units named) while
    # the set read from a file chose on it: prints compare bits. The docstrings say so, and how to give the records back
    import dataclasses
    data = _data2()
    fresh = gb.pe_pareto(ST2, data, lambdas=np.logspace(-3, 0, 4))
    loaded = gb.from_json(gb.to_json(fresh))
    kilo = gb.Record(data.ident.u, 1e3 * data.ident.y, name="ident in other units")
    with pytest.raises(ValueError, match=r"choose_on: .*fitting record .* in other units \(its y = 1000 ×"):
        gb.decide_dsf(fresh, band=1.0, choose_on=kilo)
    assert gb.decide_dsf(loaded, band=1.0, choose_on=kilo).chosen_on == "ident in other units"
    for doc in (ParetoSet.__doc__, gb.decide_dsf.__doc__):
        assert "fitted_on=(data.ident,)" in doc and "other units" in doc
    given_back = dataclasses.replace(loaded, fitted_on=(data.ident,))
    with pytest.raises(ValueError, match=r"choose_on: .*fitting record .* in other units \(its y = 1000 ×"):
        gb.decide_dsf(given_back, band=1.0, choose_on=kilo)
    # units named on both sides are compared from the file as well
    named = gb.pe_pareto(ST2, gb.Record(data.ident.u, data.ident.y, units=("V", "m")), data.static,
                         lambdas=[1.0, 0.1])
    with pytest.raises(ValueError, match="Pareto set was fitted with output unit 'm'"):
        gb.decide_dsf(gb.from_json(gb.to_json(named)), band=1.0,
                      choose_on=gb.Record(data.ident.u, 1e3 * data.ident.y, units=("V", "mm")))


def test_an_old_file_without_the_prints_loads_and_checks_as_before():
    import json
    data = _data2()
    fresh = gb.pe_pareto(ST2, data, lambdas=np.logspace(-3, 0, 6))
    doc = json.loads(gb.to_json(fresh))
    assert len(doc["object"].pop("fitted_on")) == 1
    old = gb.from_json(json.dumps(doc))
    np.testing.assert_array_equal(old.thetas, fresh.thetas)
    with pytest.raises(ValueError, match="choose_on.*fitted on"):  # the whole record: by the set's own J_S
        gb.decide_dsf(old, band=1.0, choose_on=data.ident)
    assert gb.decide_dsf(old, band=1.0, choose_on=data.ident.slice(50, 250)).chosen_on == "ident"  # as today


@settings(max_examples=60, deadline=None)
@given(hs.integers(0, 2**32 - 1), hs.integers(40, 400), hs.integers(0, 400), hs.integers(32, 400))
def test_a_print_refuses_the_slices_the_records_check_refuses(seed, n, start, length):
    from graybox.core._records import check_overlap, check_print_overlap, record_print
    rng = np.random.default_rng(seed)
    f = gb.Record(rng.standard_normal(n), rng.standard_normal(n), name="fit")
    assume(start + length <= n)
    c = f.slice(start, start + length, "piece")
    with pytest.raises(ValueError, match="fitting"):
        check_overlap(c, f, "choosing", "fitting", "advice")
    with pytest.raises(ValueError, match="fitting"):
        check_print_overlap(c, record_print(f), "choosing", "fitting", "advice")
    other = gb.Record(rng.standard_normal(length), rng.standard_normal(length), name="other")
    check_print_overlap(other, record_print(f), "choosing", "fitting", "advice")  # no shared samples: nothing


# 3. the equilibria of static equations of degree >= 4, every level at once ------------------------------------------

def _roots_both_ways(structure, thetas, ubar):
    from graybox.static import _analysis
    together = _analysis._roots_and_folds(structure, thetas, ubar)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(_analysis, "_BATCH_FROM", 10**9)  # one polynomial at a time
        alone = _analysis._roots_and_folds(structure, thetas, ubar)
    return together, alone


def _assert_same_roots(together, alone):
    (r1, f1), (r2, f2) = together, alone
    np.testing.assert_array_equal(np.isnan(r1), np.isnan(r2))
    np.testing.assert_allclose(r1[~np.isnan(r1)], r2[~np.isnan(r2)], rtol=1e-12, atol=0)
    np.testing.assert_array_equal(f1, f2)


def test_many_levels_are_solved_together(monkeypatch):
    # was one numpy.roots (eigvals) call per polynomial and group: 200 levels, 200 calls
    from graybox.static import _analysis
    calls = []
    eigvals = np.linalg.eigvals
    monkeypatch.setattr(np.linalg, "eigvals", lambda a: (calls.append(np.shape(a)), eigvals(a))[1])
    s = gb.Structure(["y(k-1)", "y(k-2)", "y(k-1)^4", "u(k-1)y(k-1)^2", "1"])
    roots = _analysis.real_roots(s, np.array([[0.3, 0.2, -0.05, 0.001, 0.4]]), np.linspace(-300, 300, 200))
    assert roots.shape == (1, 200, 4) and np.isfinite(roots).any()
    assert 0 < len(calls) <= 4, len(calls)


def _fold_model_theta(scale: float) -> np.ndarray:
    c = np.array([1.0, -2.0, 2.0, -2.0, 1.0]) * scale  # ascending: scale (ȳ − 1)² (ȳ² + 1) at ū = 1 (hunt46a's)
    return np.array([c[1] + 1, c[2], c[3], c[4], c[0]])


def test_folds_and_double_roots_are_the_same_together():
    s = gb.Structure(["y(k-1)", "y(k-1)^2", "y(k-1)^3", "y(k-1)^4", "u(k-1)"])
    ub = np.concatenate([[1.0, 1.0 + 1e-12, 1.0 - 1e-9], np.linspace(-3.0, 3.0, 301)])
    th = np.array([_fold_model_theta(k) for k in (1.0, 0.1, 1 / 3, 0.01)])
    together, alone = _roots_both_ways(s, th, ub)
    _assert_same_roots(together, alone)
    roots, fold = together
    for p in range(th.shape[0]):  # the fold at ū = 1: one double root ȳ = 1, a fold
        got = roots[p, 0][np.isfinite(roots[p, 0])]
        np.testing.assert_allclose(got, [1.0], rtol=1e-6)
        assert fold[p, 0, 0]
    # a double root beside simple ones (hunt46a's), at many scales of the model
    c = np.polynomial.polynomial.polyfromroots([1.0, 1.0, 2.0, -3.0]) * 0.05
    th = np.array([[c[1] + 1, c[2], c[3], c[4], c[0]]]) * np.array([[1.0, 1, 1, 1, 1]])
    together, alone = _roots_both_ways(s, th, np.linspace(0.0, 2.0, 41))
    _assert_same_roots(together, alone)
    assert np.isfinite(together[0][0, 20]).sum() == 3 and together[1][0, 20].sum() == 1  # ū = 1


@settings(max_examples=40, deadline=None)
@given(hs.integers(0, 2**32 - 1), hs.sampled_from([4, 5]), hs.integers(-6, 6))
def test_random_quartic_and_quintic_models_have_the_same_equilibria_together(seed, degree, decade):
    rng = np.random.default_rng(seed)
    terms = ["1", "y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)y(k-1)", "u(k-1)^2y(k-1)^2"] + \
        [f"y(k-1)^{p}" for p in range(2, degree + 1)] + [f"u(k-1)y(k-1)^{degree}"]
    s = gb.Structure(terms)
    th = rng.standard_normal((3, len(terms))) * 10.0 ** rng.integers(-3, 2, (3, len(terms)))
    th[rng.random(th.shape) < 0.2] = 0.0
    assume(np.any(th[:, -2] != 0))
    ub = np.linspace(-2.0, 2.0, 49) * 10.0 ** decade  # 3 × 49 polynomials an example, 40 examples
    together, alone = _roots_both_ways(s, th, ub)
    _assert_same_roots(together, alone)


def _curve_both_ways(model, ub, **kw):
    from graybox.control import _local
    together = gb.operating_curve(model, ub, Ts=1.0, **kw)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(_local, "_equilibria_at", lambda m, u: [None] * u.shape[0])  # each point's own equilibria()
        alone = gb.operating_curve(model, ub, Ts=1.0, **kw)
    return together, alone


@pytest.mark.parametrize("model,ub", [
    (gb.Model(["y(k-1)", "y(k-1)^2", "y(k-1)^3", "y(k-1)^4", "u(k-1)"], _fold_model_theta(1 / 3)),
     np.concatenate([[1.0], np.linspace(-2.0, 2.0, 41)])),
    (gb.Model(["y(k-1)", "y(k-2)", "y(k-1)^4", "u(k-1)y(k-1)^2", "1"], [0.3, 0.2, -0.05, 0.001, 0.4]),
     np.linspace(-300.0, 300.0, 61)),
    (gb.Model(["y(k-1)", "u(k-1)", "u(k-1)y(k-1)"], [0.5, 1.0, 0.1]), np.linspace(-8.0, 8.0, 33)),  # rational: its pole at ū = 5
    (gb.Model(["y(k-1)", "u(k-1)", "1"], [1.0, 0.5, -0.5]), np.array([0.0, 1.0, 2.0])),  # ū = 1: a continuum
])
def test_an_operating_curve_solves_its_levels_together_with_the_same_local_models(model, ub):
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the continuum's and the no-equilibrium points' notes: the same both ways
        together, alone = _curve_both_ways(model, ub)
        assert gb.to_json(together) == gb.to_json(alone)
        assert together.status == alone.status
        together, alone = _curve_both_ways(model, ub, y0=np.full(ub.size, 0.5))  # each from a start of its own
        assert gb.to_json(together) == gb.to_json(alone)


def test_a_long_records_print_stays_small_and_still_sees_long_slices():
    """A print holds at most 4096 blocks (a saved Pareto set of a long fit stays small); a slice two blocks long
    is still refused, one shorter than a block is not looked for."""
    from graybox.core._records import check_print_overlap, record_print
    rng = np.random.default_rng(3)
    N = 200_000
    r = gb.Record(u=rng.normal(size=N), y=rng.normal(size=N), Ts=1.0, name="long")
    p = record_print(r)
    assert p.digests.size <= 4097 and p.block == -(-N // 4096)
    with pytest.raises(ValueError, match="shares 200 samples"):
        check_print_overlap(r.slice(1000, 1200), p, "choosing", "fitting", "advice")
    check_print_overlap(r.slice(1000, 1000 + p.block - 1), p, "choosing", "fitting", "advice")


def test_a_damaged_print_field_is_named_once():
    """A print's field of the wrong type in a saved set: the file's error names the place once (it said
    '<json>: object.fitted_on[0]: <json>: object.fitted_on[0].length: …')."""
    import json
    d = _data2()
    f = gb.pe_pareto(ST2, d, lambdas=np.logspace(-3, 0, 3))
    doc = json.loads(gb.to_json(f))
    doc["object"]["fitted_on"][0]["length"] = 3.5
    with pytest.raises(gb.GrayboxFileError) as err:
        gb.from_json(json.dumps(doc))
    assert str(err.value).count("fitted_on[0]") == 1, str(err.value)


def test_the_fitting_records_survive_replace_copy_pickle_and_json():
    # dataclasses.replace(front, method=...) dropped the records the set was fitted on (a hidden attribute, no
    # field), and decide_dsf then chose on a slice of the fitting record ('middle', ident[50:250]) with no word
    import copy
    import dataclasses
    import pickle
    data = _data2()
    fresh = gb.pe_pareto(ST2, data, lambdas=np.logspace(-3, 0, 4))
    piece = data.ident.slice(50, 250, "middle")
    loaded = gb.from_json(gb.to_json(fresh))
    kin = {"replace": dataclasses.replace(fresh, method="renamed"), "copy": copy.copy(fresh),
           "deepcopy": copy.deepcopy(fresh), "pickle": pickle.loads(pickle.dumps(fresh)), "json": loaded,
           "replace after json": dataclasses.replace(loaded, method="renamed"),
           "json after replace": gb.from_json(gb.to_json(dataclasses.replace(fresh, units=("", "")))),
           "pickle after json": pickle.loads(pickle.dumps(loaded))}
    for how, ps in kin.items():
        with pytest.raises(ValueError, match="choose_on.*fitting"):
            gb.decide_dsf(ps, band=1.0, choose_on=piece)
        assert gb.decide_dsf(ps, band=1.0, choose_on=data.valid).chosen_on == "valid", how
    # a set built from its fields knows none unless told, and is told as a field
    bare = ParetoSet(fresh.structure, fresh.thetas, fresh.lambdas, fresh.J1, fresh.JS, fresh.JSF, "PE")
    assert bare.fitted_on == ()
    assert gb.decide_dsf(bare, band=1.0, choose_on=piece).chosen_on == "middle"
    told = dataclasses.replace(bare, fitted_on=(data.ident,))
    with pytest.raises(ValueError, match="choose_on.*fitting"):
        gb.decide_dsf(told, band=1.0, choose_on=piece)
    with pytest.raises(TypeError, match="fitted_on"):
        dataclasses.replace(bare, fitted_on=(data.ident.u,))
