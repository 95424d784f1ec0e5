"""decimation_advice and decimate: Billings & Aguirre's sampling rule, and decimation judged by the laws it states."""

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import graybox as gb


def sine(period, n=20000, Ts=0.01):
    k = np.arange(n)
    return gb.Record(np.cos(2 * np.pi * k / period), np.sin(2 * np.pi * k / period), Ts=Ts, name="sine",
                     units=("V", "m"))


def test_the_rule_on_a_sine():
    """r_y = cos(2πτ/P): first minimum P/2; y² − mean = −cos(4πk/P)/2: first minimum P/4 (the nonlinear one
    is the smaller): decimate by a factor in [P/80, P/40]."""
    P = 400
    a = gb.decimation_advice(sine(P))
    assert abs(a.tau_y - P // 2) <= 1 and abs(a.tau_y2 - P // 4) <= 1 and a.tau_m == a.tau_y2
    assert a.q_range == (int(np.ceil(a.tau_m / 20)), int(a.tau_m // 10))
    assert a.q_range[0] <= a.q <= a.q_range[1] and a.reason == ""
    assert a.Ts_new == pytest.approx(a.q * 0.01)
    assert "q=" in repr(a)


@settings(max_examples=15, deadline=None)
@given(period=st.integers(150, 3000), phase=st.floats(0, 6.28))
def test_decimating_by_the_advice_puts_tau_m_between_10_and_20_samples(period, phase):
    n = 12 * period
    k = np.arange(n)
    y = np.sin(2 * np.pi * k / period + phase) + 0.3 * np.sin(4 * np.pi * k / period)
    a = gb.decimation_advice(gb.Record(np.zeros(n), y))
    assume(a.q is not None and a.q > 1)
    b = gb.decimation_advice(gb.decimate(gb.Record(np.zeros(n), y), a.q))
    assert 9 <= b.tau_m <= 21  # the rule's 10..20, give or take a sample of rounding


def test_a_record_not_oversampled_is_left_as_it_is():
    rng = np.random.default_rng(0)
    rec = gb.Record(rng.standard_normal(3000), rng.standard_normal(3000))
    a = gb.decimation_advice(rec)
    assert a.q == 1 and a.q_range == (1, 1)
    assert gb.decimate(rec, 1) is rec


def test_a_decay_without_a_turn_is_read_where_it_dies_out():
    """A first-order plant driven by a staircase of random levels: the output's autocorrelation decays
    (the levels are independent) and never turns beyond its noise; the rule reads the decay's end, the
    staircase's hold plus the plant's settling, not a wiggle of the estimate far beyond."""
    hold = 100
    for seed in range(4):
        rng = np.random.default_rng(seed)
        u = np.repeat(rng.uniform(0, 1, 400), hold)
        y = np.zeros(u.size)
        for i in range(1, u.size):
            y[i] = 0.99 * y[i - 1] + 0.01 * (u[i - 1] + 0.5 * u[i - 1] ** 2)
        a = gb.decimation_advice(gb.Record(u, y + 0.01 * rng.standard_normal(u.size)))
        assert hold <= a.tau_m <= 6 * hold


def test_no_advice_for_a_drift():
    rec = gb.Record(np.zeros(2000), np.arange(2000.0) ** 1.5, name="drift")
    a = gb.decimation_advice(rec)
    assert a.q is None and a.Ts_new is None and "no autocorrelation minimum below its 95 % band" in a.reason
    assert "q=None" in repr(a)


def test_several_records_take_the_fastest():
    fast, slow = sine(300), sine(1200)
    a = gb.decimation_advice([slow, fast])
    assert a.tau_m == gb.decimation_advice(fast).tau_m
    assert gb.decimation_advice(gb.Dataset(fast, slow)).tau_m == a.tau_m  # a Dataset: its identification record


def test_without_the_filter_decimation_keeps_every_qth_sample():
    rec = sine(500)
    d = gb.decimate(rec, 7, antialias=False)
    np.testing.assert_array_equal(d.u, rec.u[::7])
    np.testing.assert_array_equal(d.y, rec.y[::7])
    assert d.Ts == pytest.approx(0.07) and d.units == rec.units and d.input_names == rec.input_names
    assert d.name == "sine / 7"


def test_the_filter_passes_the_band_and_stops_what_would_fold():
    """Decimating by q: a sine at a quarter of the new Nyquist frequency passes within 1 %; one at 1.5
    times it (which would fold to half of it) is stopped to below 1 % (Hamming window: about −53 dB)."""
    q, n = 8, 16000
    k = np.arange(n)
    nyq = 0.5 / q  # cycles per original sample
    keep = np.sin(2 * np.pi * 0.25 * nyq * k)
    fold = np.sin(2 * np.pi * 1.5 * nyq * k)
    mid = slice(200, -200)  # away from the ends
    d = gb.decimate(gb.Record(np.zeros(n), keep), q)
    np.testing.assert_allclose(d.y[mid], keep[::q][mid], atol=0.01)
    d = gb.decimate(gb.Record(np.zeros(n), fold), q)
    assert np.max(np.abs(d.y[mid])) < 0.01
    # a level and a ramp pass unchanged, ends included (odd reflection there)
    ramp = 3.0 + 0.01 * k
    np.testing.assert_allclose(gb.decimate(gb.Record(np.zeros(n), ramp), q).y, ramp[::q], rtol=1e-12)


@settings(max_examples=25, deadline=None)
@given(scale=st.floats(1e-3, 1e4), offset=st.floats(-1e5, 1e5), q=st.integers(2, 9), seed=st.integers(0, 50))
def test_units_and_offsets_change_the_filtered_output_by_the_same_scale_and_offset(scale, offset, q, seed):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(600)
    y = np.cumsum(rng.standard_normal(600))
    assume(np.ptp(y) > 0)
    a = gb.decimate(gb.Record(u, y), q).y
    b = gb.decimate(gb.Record(u, scale * y + offset), q).y
    np.testing.assert_allclose(b, scale * a + offset, rtol=0, atol=1e-9 * (abs(offset) + scale * np.ptp(y)))


def test_a_dataset_and_a_list_come_back_as_they_went_in():
    data = gb.load_pumping()
    d = gb.decimate(data, 5)
    assert isinstance(d, gb.Dataset) and d.static is data.static
    assert len(d.ident) == len(data.ident) // 5 and d.valid.Ts == pytest.approx(5 * data.valid.Ts)
    assert "decimated by 5" in d.description
    out = gb.decimate([data.ident, data.valid], 5, antialias=False)
    assert isinstance(out, list) and [len(r) for r in out] == [len(d.ident), len(d.valid)]


def test_bad_input():
    rec = sine(400, n=500)
    with pytest.raises(ValueError, match="q must be"):
        gb.decimate(rec, 0)
    with pytest.raises(TypeError, match="q must be"):
        gb.decimate(rec, 2.5)
    with pytest.raises(TypeError, match="antialias must be True or False"):
        gb.decimate(rec, 2, antialias="yes")
    with pytest.raises(ValueError, match="too few for the anti-alias filter"):
        gb.decimate(rec, 60)
    with pytest.raises(ValueError, match="fewer than 2 after decimating"):
        gb.decimate(rec.slice(0, 3), 3, antialias=False)  # samples 0 … 2: only sample 0 is kept
    with pytest.raises(ValueError, match="the output does not move"):
        gb.decimation_advice(gb.Record(np.zeros(100), np.ones(100), name="flat"))
    with pytest.raises(TypeError, match="data must be a Record"):
        gb.decimation_advice(np.zeros(100))
