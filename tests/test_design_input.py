"""design_input: the input of an identification experiment, judged by the laws each design states
(hold times, levels, the m-sequence's period and two-valued autocorrelation, the multisine's lines
and crest factor), with seeds, several inputs and refusals of options a kind does not use."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as hs

import graybox as gb
from graybox.datasets._inputs import _PRBS_TAPS

design_input = gb.design_input


def _runs(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Levels and lengths of the constant runs of x."""
    edges = np.flatnonzero(np.diff(x) != 0) + 1
    starts = np.concatenate([[0], edges])
    return x[starts], np.diff(np.concatenate([starts, [x.size]]))


@settings(max_examples=60, deadline=None)
@given(n=hs.integers(50, 3000), h0=hs.integers(1, 40), extra=hs.integers(0, 40), seed=hs.integers(0, 2**31),
       low=hs.floats(-1e5, 1e5), width=hs.floats(1e-3, 1e5))
def test_aprbs_holds_and_levels(n, h0, extra, seed, low, width):
    h1 = h0 + extra
    assume(2 * h1 <= n)  # an APRBS holds at least two levels
    x = design_input("aprbs", n, low=low, high=low + width, hold=(h0, h1), seed=seed)
    assert x.shape == (n,)
    assert x.min() >= low and x.max() <= low + width
    levels, lengths = _runs(x)
    # adjacent holds at one level merge into one run; every finished run is at least the shortest hold
    assert np.all(lengths[:-1] >= h0)
    np.testing.assert_array_equal(design_input("aprbs", n, low=low, high=low + width, hold=(h0, h1), seed=seed), x)


def test_aprbs_visits_the_whole_range_evenly_and_columns_are_independent():
    x = design_input("aprbs", 20000, low=750.0, high=1650.0, hold=(20, 60), n_inputs=2, seed=3)
    assert x.shape == (20000, 2)
    for c in x.T:
        levels, lengths = _runs(c)
        assert np.all(lengths[:-1] <= 60 * 2)  # two holds may share a level only by chance; not three in a row
        hist = np.histogram(levels, bins=4, range=(750, 1650))[0]
        assert hist.min() >= 0.8 * hist.mean()  # an even spread of levels, not a clump
    assert abs(np.corrcoef(x.T)[0, 1]) < 0.1
    assert not np.array_equal(design_input("aprbs", 500, low=0, high=1, hold=(5, 9), seed=1),
                              design_input("aprbs", 500, low=0, high=1, hold=(5, 9), seed=2))


@pytest.mark.parametrize("order", sorted(_PRBS_TAPS))
def test_prbs_is_a_maximal_length_sequence(order):
    # the m-sequence's laws: period exactly 2^order − 1, 2^(order−1) ones in a period, and a
    # two-valued autocorrelation (P at lag 0, −1 at every other lag of the ±1 sequence)
    P = 2**order - 1
    x = design_input("prbs", 2 * P, low=0.0, high=1.0, hold=1, order=order)
    b = 2 * x[:P] - 1
    np.testing.assert_array_equal(x[:P], x[P:])
    assert int(x[:P].sum()) == 2 ** (order - 1)
    if order <= 12:
        r = np.array([b @ np.roll(b, s) for s in range(P)])
        assert r[0] == P and np.all(r[1:] == -1)
    else:  # the full correlation is P² work: the period is the law that fails for a wrong tap set
        assert all(not np.array_equal(x[:P], np.roll(x[:P], s)) for s in (1, P // 3, P // 2))


def test_prbs_bits_last_hold_samples_and_columns_are_shifted():
    x = design_input("prbs", 600, low=-2.0, high=3.0, hold=4, n_inputs=2)
    assert set(np.unique(x)) == {-2.0, 3.0}
    for c in x.T:
        _, lengths = _runs(c)
        assert np.all(lengths[:-1] % 4 == 0)
    assert abs(np.corrcoef(x.T)[0, 1]) < 0.2
    assert design_input("prbs", 600, low=0, high=1, hold=4).size == 600  # order from the record: 2^8 − 1 bits ≥ 150


def test_staircase_goes_up_and_back_down_level_by_level():
    x = design_input("staircase", 400, low=1.0, high=11.0, hold=20)
    levels, lengths = _runs(x)
    assert np.all(lengths == 20)
    np.testing.assert_allclose(levels, np.r_[np.arange(1.0, 12.0), np.arange(10.0, 1.0, -1)])


def test_staircase_of_two_inputs_walks_a_grid_one_input_at_a_time():
    x = design_input("staircase", 2000, low=0.0, high=6.0, hold=20, n_inputs=2)
    holds = x[::20]
    moves = np.abs(np.diff(holds, axis=0))
    step = 6.0 / (len(np.unique(holds[:, 0])) - 1)
    assert np.all((moves > 0).sum(axis=1) <= 1)  # one input moves at a time
    np.testing.assert_allclose(moves[moves > 0], step)  # by one level
    grid = {tuple(r) for r in np.round(holds, 9)}
    assert len(grid) == len(np.unique(holds[:, 0])) ** 2  # every grid point visited


def test_multisine_lines_and_crest_factor():
    n = 1024
    x = design_input("multisine", n, low=-1.0, high=1.0, frequencies=(0.05, 0.4))
    assert x.min() == -1.0 and x.max() == 1.0
    X = np.abs(np.fft.rfft(x - x.mean()))
    lines = np.flatnonzero(X > 1e-6 * X.max())
    f = lines * 2 / n
    assert f.min() >= 0.05 and f.max() <= 0.4
    assert lines.size == np.sum((np.arange(1, n // 2 + 1) * 2 / n >= 0.05) & (np.arange(1, n // 2 + 1) * 2 / n <= 0.4))
    crest = np.max(np.abs(x - x.mean())) / np.std(x)
    assert crest < 2.0  # Schroeder's phases; random or zero phases give 3 or more
    two = design_input("multisine", n, low=0.0, high=1.0, frequencies=(0.05, 0.4), n_inputs=2, seed=1)
    S = np.abs(np.fft.rfft(two - two.mean(axis=0), axis=0)) > 1e-6
    assert not np.any(S[:, 0] & S[:, 1])  # no shared line: the inputs are uncorrelated over a period


def test_refusals_name_the_problem():
    with pytest.raises(ValueError, match="low < high"):
        design_input("aprbs", 100, low=2.0, high=1.0, hold=(2, 5))
    with pytest.raises(ValueError, match="needs hold="):
        design_input("staircase", 100, low=0, high=1)
    with pytest.raises(ValueError, match="longer than the record"):
        design_input("prbs", 10, low=0, high=1, hold=20)
    with pytest.raises(ValueError, match="hold does not apply to a multisine"):
        design_input("multisine", 100, low=0, high=1, hold=3, frequencies=(0.1, 0.2))
    with pytest.raises(ValueError, match="needs frequencies="):
        design_input("multisine", 100, low=0, high=1)
    with pytest.raises(ValueError, match="frequencies is the multisine's band"):
        design_input("aprbs", 100, low=0, high=1, hold=(2, 5), frequencies=(0.1, 0.2))
    with pytest.raises(ValueError, match="order is the PRBS register length"):
        design_input("staircase", 100, low=0, high=1, hold=5, order=7)
    with pytest.raises(ValueError, match="fewer than the 3 input"):
        design_input("multisine", 20, low=0, high=1, frequencies=(0.1, 0.15), n_inputs=3)
    with pytest.raises(ValueError, match="hold must be an int for kind='prbs'"):
        design_input("prbs", 100, low=0, high=1, hold=(2, 5))
    with pytest.raises(ValueError, match="kind"):
        design_input("chirp", 100, low=0, high=1)
    with pytest.raises(TypeError, match="n_samples"):
        design_input("aprbs", "100", low=0, high=1, hold=(2, 5))
    with pytest.raises(TypeError, match="low"):
        design_input("aprbs", 100, low="0", high=1, hold=(2, 5))
    with pytest.raises(ValueError, match="hold\\[1\\]"):
        design_input("aprbs", 100, low=0, high=1, hold=(5, 2))


def test_a_designed_experiment_identifies_a_known_system():
    # what the design is for: an APRBS over the range identifies a NARX system's structure (by the
    # exact subset search: greedy FROLS takes u(k-2)y(k-1) for y(k-2) on this record) and its θ
    u = design_input("aprbs", 1500, low=0.0, high=2.0, hold=(3, 15), seed=4)
    y = np.zeros(u.size)
    for k in range(2, u.size):
        y[k] = 0.6 * y[k - 1] - 0.1 * y[k - 2] + 0.5 * u[k - 1] - 0.2 * u[k - 2] ** 2 + 0.3
    sel = gb.frols(gb.Candidates(ny=2, nu=2, degree=2), gb.Record(u, y), n_terms=5, search="exact")
    truth = {"y(k-1)": 0.6, "y(k-2)": -0.1, "u(k-1)": 0.5, "u(k-2)^2": -0.2, "1": 0.3}
    assert set(map(str, sel.structure)) == set(truth)
    np.testing.assert_allclose([dict(zip(map(str, sel.structure), sel.model.theta))[t] for t in truth],
                               list(truth.values()), rtol=1e-6)


def test_an_aprbs_that_one_hold_could_fill_is_refused():
    # review37: hold=(20, 100) on 100 samples with seed 161 drew one hold of 100 samples: a constant input at `low`
    with pytest.raises(ValueError, match=r"at least two holds.*longest hold \(100 samples\) must be at most half"):
        design_input("aprbs", 100, low=2900.0, high=3100.0, hold=(20, 100), seed=161)
    x = design_input("aprbs", 100, low=2900.0, high=3100.0, hold=(20, 50), seed=161)
    assert np.unique(x).size >= 2


@pytest.mark.parametrize("kind, kw", [("aprbs", {"hold": (20, 60)}), ("staircase", {"hold": 50}),
                                      ("prbs", {"hold": 4}), ("multisine", {"frequencies": (0.01, 0.2)})])
def test_each_input_takes_its_own_range(kind, kw):
    # was: one low and high for every input, so a speed in rpm and a valve in % could not be designed together
    u = gb.design_input(kind, 4000, low=[750.0, 20.0], high=[1650.0, 80.0], n_inputs=2, **kw)
    np.testing.assert_array_equal(u.min(axis=0), [750.0, 20.0])
    np.testing.assert_array_equal(u.max(axis=0), [1650.0, 80.0])
    same = gb.design_input(kind, 4000, low=750.0, high=1650.0, n_inputs=2, **kw)
    np.testing.assert_array_equal(gb.design_input(kind, 4000, low=[750.0] * 2, high=[1650.0] * 2, n_inputs=2, **kw),
                                  same)  # one number for every input is the same design
    # each column is the one-range design's column mapped onto its own range
    frac = (same - 750.0) / 900.0
    np.testing.assert_allclose(u, np.array([750.0, 20.0]) + frac * np.array([900.0, 60.0]), rtol=0, atol=1e-9)


def test_ranges_given_per_input_are_checked_per_input():
    with pytest.raises(ValueError, match=r"low must be one number, or one per input \(2\)"):
        gb.design_input("aprbs", 400, low=[1.0, 2.0, 3.0], high=5.0, hold=(5, 10), n_inputs=2)
    with pytest.raises(ValueError, match="low < high for input 1, got low=6.0, high=5.0"):
        gb.design_input("aprbs", 400, low=[1.0, 6.0], high=5.0, hold=(5, 10), n_inputs=2)
    with pytest.raises(TypeError, match=r"high\[1\] must be a real number"):
        gb.design_input("aprbs", 400, low=1.0, high=[5.0, "x"], hold=(5, 10), n_inputs=2)
