"""review40a: centre=True of frols, semp and select_graybox in the combinations its own tests leave out."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

import graybox as gb
from graybox.selection._centring import closure, signal_offsets, centred_data

TRUE = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "u(k-2)^2"])
THETA = np.array([0.5, 0.3, 0.2, 0.1])
CAND = gb.Candidates(ny=2, nu=2, degree=2)


def _two_level(seed: int, n: int = 400) -> gb.Record:
    # a PRBS-like input on levels 0 and 1 held 5 samples: u(k-1)^2 is u(k-1) itself on these data, and
    # (u(k-1) - d)^2 a combination of u(k-1) - d and 1, whatever d
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.choice([0.0, 1.0], n // 5), 5)
    y = gb.Model(TRUE, THETA).simulate(u, np.zeros(2)) + 0.01 * rng.standard_normal(n)
    return gb.Record(u, y, name=f"two-level {seed}")


def _quiet(fn, *args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.CandidateWarning)
        return fn(*args, **kw)


def _rank(structure: gb.Structure, rec: gb.Record) -> int:
    X, _ = gb.stacked_regressors(structure, centred_data(rec, signal_offsets(rec)))
    return int(np.linalg.matrix_rank(X / np.sqrt(np.mean(X**2, axis=0))))


@pytest.mark.parametrize(("seed", "fn", "kw"), [
    (12, gb.frols, {"criterion": "bic"}),
    (13, gb.frols, {"criterion": "bic"}),
    (11, gb.frols, {"n_terms": 5, "search": "exact"}),
    (11, gb.semp, {"criterion": "bic"}),
])
def test_centred_selection_on_a_two_level_input_drops_what_the_data_cannot_tell(seed, fn, kw):
    # frols raised FewerTermsError ("n_terms = 11 asked", which nobody asked) when the closure held a term the
    # data cannot tell from its divisors; semp returned such a closure, with θ an arbitrary point of a null space
    rec = _two_level(seed)
    sel = _quiet(fn, CAND, rec, centre=True, **kw)
    assert set(closure(sel.structure)) == set(sel.structure)  # still closed under shifts
    assert _rank(sel.structure, rec) == len(sel.structure)  # every term told apart from the others
    moved = replace(rec, u=rec.u + 300.0, y=rec.y - 50.0)
    other = _quiet(fn, CAND, moved, centre=True, **kw)
    assert set(other.structure) == set(sel.structure)


def test_select_graybox_centred_on_a_two_level_input():
    # every row's closure held u(k-1)^2 beside u(k-1) and 1: every fit refused it ("not identifiable"), and the
    # call raised "no structure has a finite free-run J_S", where centre=False chooses
    ident, valid = _two_level(12), _two_level(13)
    kw = {"band": np.inf, "estimator": "ls", "sizes": [4, 6, 8], "sources": ["frols", "semp"], "centre": True}
    a = gb.select_graybox(CAND, gb.Dataset(ident, valid), **kw)
    for row in a.table.index:
        st = a.structure_of(row)
        assert set(closure(st)) == set(st)
        assert _rank(st, ident) == len(st)
    assert np.isfinite(a.table["JS_valid"]).all()
    b = gb.select_graybox(CAND, gb.Dataset(replace(ident, u=ident.u + 300.0, y=ident.y - 50.0),
                                           replace(valid, u=valid.u + 300.0, y=valid.y - 50.0)), **kw)
    assert set(b.structure) == set(a.structure)
    np.testing.assert_allclose(b.table["JS_valid"], a.table["JS_valid"], rtol=1e-6)


def test_centred_stop_text_spells_a_negative_mean_as_a_sum():
    # "u − -3000" was the stop text of an input whose mean is negative
    rec = _two_level(12)
    moved = replace(rec, u=rec.u - 3000.0, y=rec.y + 2.0)
    for fn, kw in ((gb.frols, {"n_terms": 3}), (gb.semp, {"n_terms": 3})):
        stop = _quiet(fn, CAND, moved, centre=True, **kw).stop
        assert "− -" not in stop
        assert "u + 2999.49" in stop and "y − " in stop


def _held_b(level: float, n: int = 400, seed: int = 7) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = np.column_stack([rng.uniform(-1.0, 1.0, n), np.full(n, level)])
    m = gb.Model(gb.Structure(["y(k-1)", "a(k-1)", "a(k-1)y(k-1)", "a(k-2)^2"]), THETA, input_names=("a", "b"))
    y = m.simulate(u, np.zeros(2)) + 0.01 * rng.standard_normal(n)
    return gb.Record(u, y, input_names=("a", "b"))


CAND_AB = gb.Candidates(ny=2, nu=2, degree=2, input_names=("a", "b"))


@pytest.mark.parametrize("level", [1.5, 2.3])
@pytest.mark.parametrize("fn", [gb.frols, gb.semp])
def test_centred_include_of_a_held_input_is_refused_by_name(level, fn):
    # held at 1.5 the call said "all-zero column" (frols) or "collinear" (semp) of a column the caller never saw;
    # held at 2.3 (centred: -8.9e-16, not 0) the included term was dropped from the result, against include=
    with pytest.raises(ValueError, match=r"included term b\(k-1\).*input b is held"):
        _quiet(fn, CAND_AB, _held_b(level), n_terms=4, include=["b(k-1)"], centre=True)


def test_centred_include_of_a_term_the_data_cannot_tell_is_refused():
    # u(k-1)^2 on a two-level input was included, then left out of the closure the result holds
    with pytest.raises(ValueError, match=r"included term u\(k-1\)\^2"):
        _quiet(gb.frols, CAND, _two_level(12), n_terms=3, include=["u(k-1)^2"], centre=True)
    with pytest.raises(ValueError, match=r"included term u\(k-1\)\^2"):
        gb.select_graybox(CAND, gb.Dataset(_two_level(12), _two_level(13)), band=np.inf, estimator="ls",
                          sizes=[3], sources=["frols"], include=["u(k-1)^2"], centre=True)


def test_centred_include_of_a_held_input_is_refused_by_select_graybox():
    data = gb.Dataset(_held_b(1.5), _held_b(1.5, seed=8))
    with pytest.raises(ValueError, match=r"included term b\(k-1\).*input b is held"):
        gb.select_graybox(CAND_AB, data, band=np.inf, estimator="ls", sizes=[3], sources=["frols"],
                          include=["b(k-1)"], centre=True)


def test_select_graybox_centred_gray_rows_keep_what_the_static_points_tell_apart():
    # on a two-level input the records cannot tell u(k-1)^2 from u(k-1) and 1, but static points at six levels
    # can: a gray row keeps the whole closure (as the raw search keeps the static form's u^2), and the true
    # structure's static curve, which the noise-free points lie on, is met
    ub = np.linspace(0.0, 1.0, 6)
    data = gb.Dataset(_two_level(12), _two_level(13), gb.StaticPoints(ub, gb.Model(TRUE, THETA).static_curve(ub)))
    a = gb.select_graybox(CAND, data, band=0.01, estimator="pe", sizes=[5], sources=["frols"], centre=True)
    assert a.table["JSF"].min() < 1e-8


def test_centred_selection_does_not_call_a_term_of_its_structure_skipped():
    # the centred search dropped 1 as a combination of its picks (u(k-1)^2 among them); the closure brought 1
    # back, and Selection.skipped (and its printout) still said 1 was left out
    with warnings.catch_warnings(record=True) as heard:
        warnings.simplefilter("always")
        sel = gb.frols(CAND, _two_level(12), criterion="bic", centre=True)
    said = [str(w.message) for w in heard if issubclass(w.category, gb.CandidateWarning)]
    assert len(said) == 1 and ": 1 (" not in said[0] and "; 1 (" not in said[0]  # one, as frols says it, true
    assert gb.Term(()) in set(sel.structure)
    assert not {t for t, _ in sel.skipped} & set(sel.structure)
    line = next(x for x in str(sel).splitlines() if x.startswith("skipped: "))
    named = {item.split(" (")[0] for item in line.removeprefix("skipped: ").split("; ")}
    assert not named & {str(t) for t in sel.structure}
