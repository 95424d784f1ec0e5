"""review50g: what the review of mend50d, hunt50e, hunt50c and hunt50a's merges found."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb
from graybox.core._records import check_overlap, check_print_overlap, record_print


# 1. a record's print and repeated blocks ---------------------------------------------------------------------------

def _at_rest_first(rest: int, n: int = 3000, seed: int = 0) -> gb.Record:
    """A record that starts with ``rest`` samples at rest (u = y = 0, every block of them the same) then varies."""
    rng = np.random.default_rng(seed)
    u = np.concatenate([np.zeros(rest), rng.standard_normal(n)])
    y = np.concatenate([np.zeros(rest), rng.standard_normal(n)])
    return gb.Record(u, y, name="fit")


@pytest.mark.parametrize("rest, start", [(10000, 1000), (10000, 5000), (70000, 1000)])
def test_a_print_refuses_a_slice_that_begins_in_a_long_rest(rest, start):
    # the slice's first 4096 windows matched only the rest's blocks (each one of hundreds alike), so the true
    # alignment was never tried and the loaded set took the slice its fresh self refuses
    f = _at_rest_first(rest)
    c = f.slice(start, None, "piece")
    with pytest.raises(ValueError, match="fitting"):
        check_overlap(c, f, "choosing", "fitting", "advice")
    with pytest.raises(ValueError, match=f"its samples 0\\.\\.{len(c) - 1} are samples {start}\\.\\."):
        check_print_overlap(c, record_print(f), "choosing", "fitting", "advice")
    # a record of its own beside the same rest is still not refused
    other = _at_rest_first(rest, seed=1).slice(start, None, "other")
    check_print_overlap(other, record_print(f), "choosing", "fitting", "advice")


# 2. ELS's round-off test and tiny noise on a large level -------------------------------------------------------------

@pytest.mark.parametrize("offset, scale", [(1e4, 1e-9), (-1e4, 1e-10), (1e6, 1e-8)])
def test_els_finds_the_ma_part_of_tiny_noise_on_a_large_level_as_at_y(offset, scale):
    # noise of 1e-12 of the level and less (here 45-450 ulps of it) was read as round-off: MA part zero, 0
    # iterations, where at y (and with the former test at y + offset too) ELS finds the same C as at any noise size
    rng = np.random.default_rng(0)
    n = 300
    u = rng.uniform(0.0, 1.0, n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.1 + 0.5 * y[k - 1] + 0.3 * u[k - 1] + 0.4 * u[k - 1] ** 2
    e = rng.standard_normal(n)
    v = e.copy()
    v[1:] += 0.5 * e[:-1]
    terms = ["1", "y(k-1)", "u(k-1)", "u(k-1)^2"]
    at_y = gb.els(terms, gb.Record(u=u, y=y + scale * v), noise=1)
    assert at_y.n_iter > 0 and abs(at_y.model.noise_theta[0]) > 0.05
    res = gb.els(terms, gb.Record(u=u, y=y + offset + scale * v), noise=1)
    assert res.n_iter > 0
    np.testing.assert_allclose(res.model.noise_theta, at_y.model.noise_theta, atol=0.01)
    # noise-free, the same level: still round-off (c94100a's case)
    exact = gb.els(terms, gb.Record(u=u, y=y + offset), noise=1)
    assert exact.n_iter == 0 and np.all(exact.model.noise_theta == 0.0)


# 3. the roots of a static equation whose groups of roots lie far apart ----------------------------------------------

def test_equilibria_of_roots_beyond_the_float_range_and_far_out_ones():
    # F(ȳ) = 6.4e-259 ū - (1.26e262 + 1) ȳ + ... + 9.5e-257 ȳ^4: one group of roots near 5e-521 (below the float
    # range: its scale 2^e was 0), and ȳ³ = 1.32e518 (ȳ = 5.097e172, whose scale cubed, 2^1719, is not a float):
    # numpy.roots met the NaN of 0 · inf and raised LinAlgError('Array must not contain infs or NaNs'), from
    # Model.equilibria, static_curve and the batched solver's one-at-a-time path alike
    th = [6.36279666e-259, -1.26424354e262, -9.99089567e-278, 8.72751169e-290, 9.54740351e-257]
    m = gb.Model(["u(k-1)", "y(k-1)", "y(k-1)^2", "y(k-1)^3", "y(k-1)^4"], th)
    eqs = m.equilibria(1.0)
    curve = m.static_curve(np.linspace(1.0, 2.0, 6), strict=False)
    assert len(eqs) == 1 and not eqs[0].stable
    np.testing.assert_allclose(eqs[0].ybar, np.exp((np.log(1.26424354e262 + 1) - np.log(9.54740351e-257)) / 3),
                               rtol=1e-12)
    assert curve.shape == (6,)


# 4. a damaged print in a Pareto set's file ---------------------------------------------------------------------------

@pytest.mark.parametrize("field, value, said", [
    ("length", 300.0, r"^<json>: object\.fitted_on\[0\]\.length: expected an integer, got 300\.0$"),
    ("name", 5, r"^<json>: object\.fitted_on\[0\]\.name: expected a string, got int$"),
    ("input_names", "u", r"^<json>: object\.fitted_on\[0\]\.input_names: expected a list, got str$"),
    ("block", 0, r"^<json>: object\.fitted_on\[0\]: RecordPrint: need 1 <= block <= length"),
    # an input named twice, or as the output, which no record's inputs are (loaded as given: mend61e)
    ("input_names", ["u", "u"], r"^<json>: object\.fitted_on\[0\]: RecordPrint: input_names: input 'u' is named twice"),
    ("input_names", ["y"], r"^<json>: object\.fitted_on\[0\]: RecordPrint: input_names: input name 'y' is not a valid"),
])
def test_a_damaged_print_is_named_once(field, value, said):
    # a field of the wrong kind was said with its place twice: '<json>: object.fitted_on[0]: <json>:
    # object.fitted_on[0].length: expected an integer, got 300.0'
    import json

    from graybox.core._terms import parse_structure
    rng = np.random.default_rng(0)
    rec = gb.Record(u=rng.standard_normal(300), y=rng.standard_normal(300), name="ident")
    ps = gb.ParetoSet(parse_structure(["y(k-1)", "u(k-1)"]), np.array([[0.5, 1.0], [0.4, 1.1]]), np.array([1.0, 0.5]),
                      np.zeros(2), np.array([1.0, 2.0]), np.array([0.1, 0.05]), "PE", fitted_on=(rec,))
    doc = json.loads(gb.to_json(ps))
    doc["object"]["fitted_on"][0][field] = value
    with pytest.raises(gb.io.GrayboxFileError, match=said):
        gb.from_json(json.dumps(doc))


def test_a_print_does_not_refuse_a_record_that_shares_only_a_held_level():
    # fit: 200 samples at rest between varying ones; valid: 40 at rest between 10 of its own at each end. The print
    # matched valid's rest to the fit's (the only whole blocks in that alignment) and, y varying in valid's own
    # samples at the ends (never compared), refused it: 'its samples 0..59 are samples 97..156 of the other', where
    # the records' own check (the fresh set's) takes it
    rng = np.random.default_rng(0)
    f = gb.Record(u=np.concatenate([rng.standard_normal(100), np.zeros(200), rng.standard_normal(100)]),
                  y=np.concatenate([rng.standard_normal(100), np.zeros(200), rng.standard_normal(100)]), name="fit")
    a = gb.Record(u=np.concatenate([rng.standard_normal(10), np.zeros(40), rng.standard_normal(10)]),
                  y=np.concatenate([rng.standard_normal(10), np.zeros(40), rng.standard_normal(10)]), name="valid")
    check_overlap(a, f, "choosing", "fitting", "advice")
    check_print_overlap(a, record_print(f), "choosing", "fitting", "advice")
    # a true piece across the rest's edge is still refused by both
    piece = f.slice(90, 150, "piece")
    for check, other in ((check_overlap, f), (check_print_overlap, record_print(f))):
        with pytest.raises(ValueError, match="fitting"):
            check(piece, other, "choosing", "fitting", "advice")


def test_a_print_refuses_a_slice_mostly_at_rest_that_ends_in_the_varying_part():
    # fit[197:307] of 300 samples at rest then 101 varying: 103 at rest and 7 varying. One window of the slice is a
    # block the print holds once; each of its 88 windows at rest is each of the rest's 18 blocks. Alignments were
    # ranked by their count of hits, ties by nearness: the true one (count 6) tied with dozens nearer, was not
    # among the 32 tried, and the slice taken
    rng = np.random.default_rng(3)
    f = gb.Record(u=np.concatenate([np.zeros(300), rng.standard_normal(101)]),
                  y=np.concatenate([np.zeros(300), rng.standard_normal(101)]), name="fit")
    c = f.slice(197, 307, "piece")
    with pytest.raises(ValueError, match="fitting"):
        check_overlap(c, f, "choosing", "fitting", "advice")
    with pytest.raises(ValueError, match=r"its samples 0\.\.109 are samples 197\.\.306"):
        check_print_overlap(c, record_print(f), "choosing", "fitting", "advice")
