"""A record that shares samples with another is found, where it starts in each and how long it is."""

import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import graybox as gb
from graybox.core._records import check_overlap, shared_stretch, sliced


def _record(seed, n, m=1, quantum=None):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, m)) if m > 1 else rng.standard_normal(n)
    y = rng.standard_normal(n)
    if quantum:
        y = np.round(y / quantum) * quantum
    return gb.Record(u, y, name=f"r{seed}")


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(40, 600), m=st.integers(1, 2), data=st.data())
def test_any_stretch_longer_than_an_eighth_plus_a_window_is_found_where_it_is(seed, n, m, data):
    rec = _record(seed, n, m, quantum=0.5)
    start = data.draw(st.integers(0, n - 20))
    length = data.draw(st.integers(20, n - start))
    part = rec.slice(start, start + length)
    assume(length > n // 8 + 16 + 1)
    # a shared stretch grows to its true extent unless the neighbouring samples happen to agree too
    i, j, k = shared_stretch(rec, part)
    assert j == 0 and i == start and k == length
    a, b, k2 = shared_stretch(part, rec)
    assert (a, b, k2) == (0, start, length)
    assert sliced((i, j, k), n, length)
    # a new record around the part: shares exactly the part; warned of, or refused where slicing would
    # give it too (the part the old record's start: the new record's end is then the old one's start)
    other = _record(seed + 1, 50, m, quantum=0.5)
    mixed = gb.Record(np.concatenate([other.u, part.u]), np.concatenate([other.y, part.y]))
    assert shared_stretch(mixed, rec) == (50, start, length)
    if start == 0:
        with pytest.raises(ValueError, match=f"shares {length} samples"):
            check_overlap(mixed, rec, "test", "identification", "test on other data")
    else:
        with pytest.warns(gb.RecordOverlapWarning, match=f"shares {length} samples"):
            check_overlap(mixed, rec, "test", "identification", "test on other data")


@given(seed=st.integers(0, 10_000))
def test_independent_records_share_nothing(seed):
    assert shared_stretch(_record(seed, 300), _record(seed + 1, 300)) is None


def _designed_runs(model, n_runs, n=600, hold=60, y0=1):
    """Noise-free runs of ``model`` under staircases of 5 designed levels, each from rest."""
    levels = np.array([0.0, 0.5, 1.0, 1.5, 2.0])
    out = []
    for seed in range(n_runs):
        u = np.repeat(np.random.default_rng(seed).choice(levels, n // hold + 1), hold)[:n]
        out.append(gb.Record(u, model.simulate(u, np.zeros(y0)), 1.0, name=f"run {seed}"))
    return out


@pytest.mark.parametrize("model, y0", [
    (gb.Model(gb.Structure(["1", "u(k-1)", "y(k-1)"]), np.array([0.1, 0.5, 0.5])), 1),
    (gb.Model(gb.Structure(["1", "u(k-2)", "y(k-1)", "y(k-2)", "u(k-1)y(k-1)"]),
              np.array([0.1, 0.3, 0.6, -0.1, 0.05])), 2),
])
def test_noise_free_runs_whose_states_meet_are_warned_of_not_refused(model, y0):
    # separate experiments on one noise-free system at designed levels share stretches (the same first
    # step from rest; the same steps once settled at the same level): 28 and 24 of these 29 pairs were
    # refused as the same data; such a stretch is now a warning, and a slice is still an error
    runs = _designed_runs(model, 30, y0=y0)
    shared = [s for k in range(29) if (s := shared_stretch(runs[k], runs[k + 1])) is not None]
    assert len(shared) >= 10 and not any(sliced(s, 600, 600) for s in shared)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for k in range(29):
            check_overlap(runs[k], runs[k + 1], "test", "identification", "test on other data")
    assert len(caught) == len(shared) and all(w.category is gb.RecordOverlapWarning for w in caught)
    assert "noise-free runs" in str(caught[0].message)
    with pytest.raises(ValueError, match="shares 400 samples .* test on other data"):
        check_overlap(runs[0].slice(200, 600), runs[0], "test", "identification", "test on other data")
    with pytest.raises(ValueError, match="shares 100 samples"):
        check_overlap(runs[0].slice(0, 400), runs[0].slice(300, 600), "test", "identification", "x")


def test_a_long_noise_free_record_is_checked_in_few_grows(monkeypatch):
    # a window of a noise-free run at two levels recurs at every step: only a few places per anchor are grown
    import graybox.core._records as records

    calls = []
    real = records._grow
    monkeypatch.setattr(records, "_grow", lambda *a: calls.append(1) or real(*a))
    model = gb.Model(gb.Structure(["1", "u(k-1)", "y(k-1)"]), np.array([0.1, 0.5, 0.5]))
    u = np.tile(np.repeat([0.0, 2.0], 60), 400)
    v = np.tile(np.repeat([2.0, 0.0], 60), 400)
    a = gb.Record(u, model.simulate(u, np.zeros(1)), 1.0)
    b = gb.Record(v, model.simulate(v, np.full(1, 4.2)), 1.0)
    assert shared_stretch(a, b) is not None
    assert len(calls) <= 2 * 8 * records._GROWN


def test_a_held_input_at_a_constant_output_is_not_an_overlap():
    """Two runs at the same operating point with a quantised sensor repeat samples without being the same data."""
    held = gb.Record(np.ones(200), np.full(200, 3.0), name="held")
    again = gb.Record(np.ones(80), np.full(80, 3.0), name="again")
    assert shared_stretch(held, again) is None
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_overlap(held, again, "test", "validation", "test on other data")  # neither refused nor warned of


def test_the_message_names_both_records_and_the_samples():
    rec = _record(3, 400)
    with pytest.raises(ValueError) as caught:
        check_overlap(rec.slice(100, 400), rec, "test", "validation", "test on other data")
    msg = str(caught.value)
    assert "test record" in msg and "validation record" in msg and "300 samples" in msg
    assert "samples 0..299 are samples 100..399" in msg and msg.endswith(": test on other data")


def test_selection_and_output_error_refuse_overlapping_records():
    true = gb.Structure(["y(k-1)", "u(k-1)", "1"])
    rng = np.random.default_rng(5)
    u = np.repeat(rng.uniform(0, 2, 60), 20)
    y = gb.Model(true, np.array([0.7, 0.4, 0.1])).simulate(u, np.zeros(1)) + 0.01 * rng.standard_normal(u.size)
    ident, valid = gb.Record(u[:800], y[:800], name="ident"), gb.Record(u[800:], y[800:], name="valid")
    data = gb.Dataset(ident, valid, None)
    cand = gb.Candidates(2, 2, degree=1)
    with pytest.raises(ValueError, match=r"test record \('valid'\) shares 200 samples with the validation record"):
        gb.select_graybox(cand, data, band=np.inf, sizes=[2], test=valid.slice(100, 300))
    with pytest.raises(ValueError, match="shares 300 samples with the identification record"):
        gb.select_graybox(cand, data, band=np.inf, sizes=[2], test=ident.slice(500, 800))
    with pytest.raises(ValueError, match="validation record .* shares 400 samples with the identification"):
        gb.select_graybox(cand, gb.Dataset(ident, ident.slice(400, 800), None), band=np.inf, sizes=[2])
    with pytest.raises(ValueError, match="choose_on: the choosing record .* shares 200 samples with the fitting"):
        gb.output_error(true, ident, choose_on=ident.slice(0, 200))


def test_records_of_other_input_counts_share_nothing():
    one, two = _record(1, 200), _record(1, 200, m=2)
    assert shared_stretch(one, two) is None and shared_stretch(two, one) is None


def test_the_same_data_in_other_units_or_rounded_by_another_tool_is_refused():
    """A test or choosing record that is a fitting record's samples with y (or u) in other units, or written to
    6 significant digits by another tool, is the fitting data: its score would be made up (a model of the data in
    one set of units scored on them in another), or optimistic (rounded), and no exact sample matches it."""
    rng = np.random.default_rng(4)
    u = np.repeat(rng.uniform(0.0, 2.0, 40), 10)
    y = gb.Model(gb.Structure(["y(k-1)", "u(k-1)", "1"]), np.array([0.7, 0.4, 0.1])).simulate(u, np.zeros(1))
    y = y + 0.01 * rng.standard_normal(u.size)
    ident = gb.Record(u, y, name="ident")
    for other, what in [(gb.Record(u, 1e3 * y), "y = 1000·y"), (gb.Record(u, 1.8 * y + 32.0), "y = 1.8·y + 32"),
                        (gb.Record(60.0 * u[100:300], y[100:300]), "u = 60·u"),
                        (gb.Record(np.array([float(f"{v:.6g}") for v in u[50:]]),
                                   np.array([float(f"{v:.6g}") for v in y[50:]]) - 0.0), "rounded"),
                        (gb.Record(u, 1e200 * y), "huge")]:  # its squares beyond the float range: nothing overflows
        assert shared_stretch(other, ident) is None  # no sample of it is one of the fitting record's
        with pytest.raises(ValueError, match="other units|rounding") as caught:
            check_overlap(other, ident, "test", "identification", "test on other data")
        assert caught.value.args[0].endswith(": test on other data")
    # a run at inputs and outputs both scaled (a linear plant's response to a scaled input, or both in other units)
    # is said, not refused; independent records are neither
    with pytest.warns(gb.RecordOverlapWarning, match="scaled"):
        check_overlap(gb.Record(2.0 * u, 2.0 * y), ident, "test", "identification", "test on other data")
    # y from another zero alone (y + 273.15) is what an integrating plant's run from another level gives: said
    with pytest.warns(gb.RecordOverlapWarning, match=r"offset \(its y = the other's \+ 273.15"):
        check_overlap(gb.Record(u, y + 273.15), ident, "test", "identification", "test on other data")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_overlap(_record(1, 400), ident, "test", "identification", "test on other data")
        check_overlap(gb.Record(u[::-1].copy(), y[::-1].copy()), ident, "test", "identification", "x")
        # noise-free runs of a first-order plant at a held input, from other states: any two stretches of such a
        # settling are affine maps of each other (the input says nothing of which data they are), nothing is said
        first = gb.Model(gb.Structure(["y(k-1)", "u(k-1)", "1"]), np.array([0.9, 0.5, 0.2]))
        held = np.ones(200)
        runs = [gb.Record(held, first.simulate(held, np.array([y0])), name=f"from {y0}") for y0 in (0.0, 3.0, 50.0)]
        for a, b in ((runs[1], runs[0]), (runs[0], runs[1]), (runs[2], runs[0])):
            check_overlap(a, b, "validation", "identification", "x")


def test_select_graybox_refuses_a_test_or_validation_record_that_is_the_fitting_data_in_other_units():
    # the test record Record(u, 1000·y) ran, and its JS_test scored a model of y on 1000·y (a made-up number)
    rng = np.random.default_rng(5)
    u = np.repeat(rng.uniform(0, 2, 60), 20)
    y = gb.Model(gb.Structure(["y(k-1)", "u(k-1)", "1"]), np.array([0.7, 0.4, 0.1])).simulate(u, np.zeros(1))
    y = y + 0.01 * rng.standard_normal(u.size)
    ident, valid = gb.Record(u[:800], y[:800], name="ident"), gb.Record(u[800:], y[800:], name="valid")
    cand = gb.Candidates(2, 2, degree=1)
    with pytest.raises(ValueError, match=r"test record .* shares 400 samples with the identification record .* in "
                                         r"other units \(its y = 1000 × the other's.*samples 0..399 are samples "
                                         r"200..599 of the other"):
        gb.select_graybox(cand, gb.Dataset(ident, valid, None), band=np.inf, sizes=[2],
                          test=gb.Record(u[200:600], 1e3 * y[200:600]))
    with pytest.raises(ValueError, match=r"validation record .* in other units \(its u = 60 × the other's"):
        gb.select_graybox(cand, gb.Dataset(ident, gb.Record(60.0 * u[:800], y[:800]), None), band=np.inf, sizes=[2])


def test_separate_runs_whose_signals_differ_by_an_offset_alone_are_said_not_refused():
    """An integrating plant run twice on one designed input from other levels gives outputs that differ by a
    constant, and a plant that answers its input's changes only (a washout) gives one output at inputs offset by a
    constant: separate experiments, which were refused as the other record in other units (y + 3, u + 5). An
    offset alone is said; a scale on one side alone (y·1000 at the same inputs) is still refused."""
    u = gb.design_input("aprbs", 300, low=0.0, high=10.0, hold=(5, 20), seed=0)
    tank = gb.Model(gb.Structure(["y(k-1)", "u(k-1)"]), np.array([1.0, 0.5]))
    ident = gb.Record(u, tank.simulate(u, np.zeros(1)), name="from 0")
    again = gb.Record(u, tank.simulate(u, np.array([3.0])), name="from 3")
    np.testing.assert_allclose(again.y - ident.y, 3.0, rtol=0, atol=1e-9)  # an offset, independently of graybox
    with pytest.warns(gb.RecordOverlapWarning, match=r"its y = the other's \+ 3"):
        check_overlap(again, ident, "test", "identification", "x")
    washout = gb.Model(gb.Structure(["y(k-1)", "u(k-1)", "u(k-2)"]), np.array([0.8, 1.0, -1.0]))
    low = gb.Record(u, washout.simulate(u, np.zeros(2)), name="low")
    high = gb.Record(u + 5.0, washout.simulate(u + 5.0, np.zeros(2)), name="high")
    np.testing.assert_allclose(high.y, low.y, rtol=0, atol=1e-9)
    with pytest.warns(gb.RecordOverlapWarning, match=r"its u = the other's \+ 5"):
        check_overlap(high, low, "test", "identification", "x")
    with pytest.raises(ValueError, match="other units"):
        check_overlap(gb.Record(u, 1e3 * ident.y), ident, "test", "identification", "x")
