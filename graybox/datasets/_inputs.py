"""Input design for an identification experiment (MATLAB's ``idinput``, with the nonlinear case first).

A nonlinear model learns only the amplitudes and the rates its record shows: an APRBS visits the
whole operating range at random levels held for random times; a staircase up and down shows the
static curve (and any hysteresis) level by level; a PRBS and a multisine excite a linear model's
band at one operating point. Every design is a pure function of its arguments and its seed.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from ..core._validation import check_count, check_choice, check_int, check_real, check_seed

__all__ = ["design_input"]

KINDS = ("aprbs", "staircase", "prbs", "multisine")

#: Feedback taps of maximal-length linear shift registers (a primitive polynomial per order): the
#: register x(k) = XOR of x(k − t) over the taps has period 2^order − 1.
_PRBS_TAPS = {2: (2, 1), 3: (3, 2), 4: (4, 3), 5: (5, 3), 6: (6, 5), 7: (7, 6), 8: (8, 6, 5, 4), 9: (9, 5),
              10: (10, 7), 11: (11, 9), 12: (12, 11, 10, 4), 13: (13, 12, 11, 8), 14: (14, 13, 12, 2),
              15: (15, 14), 16: (16, 15, 13, 4), 17: (17, 14), 18: (18, 11), 19: (19, 18, 17, 14), 20: (20, 17)}


def _scale(t: np.ndarray, lo: float | np.ndarray, hi: float | np.ndarray) -> np.ndarray:
    """Fractions t in [0, 1] as levels in [lo, hi], each end exact (lo + (hi − lo)·1 can round past hi); ``lo`` and
    ``hi`` may be one per column of ``t``."""
    t = np.asarray(t, float)
    half = hi / 2 - lo / 2
    if np.all(half <= np.finfo(float).max / 2):
        return np.where(t <= 0.5, lo + (hi - lo) * t, hi - (hi - lo) * (1 - t))
    # a range wider than the largest float (±1e308): each end's distance as a product of the half range, which
    # stays finite because it is at most half the range
    return np.where(t <= 0.5, lo + half * (2 * np.minimum(t, 0.5)), hi - half * (2 * np.minimum(1 - t, 0.5)))


def _sequence(value: object) -> list | None:
    """``value`` as a list when it is a 1-D array-like (a tuple, a list, an array, a range, a pandas Series: read by
    position, not by its index), else None (a number, text, a mapping, a set …)."""
    if isinstance(value, (str, bytes, Mapping, set, frozenset)):
        return None
    try:
        if np.ndim(value) != 1:
            return None
        return list(np.asarray(value, dtype=object).tolist())
    except (TypeError, ValueError):  # ragged
        return None


def _holds(kind: str, hold: object) -> tuple[int, int]:
    """``hold`` as (shortest, longest) samples a level is held."""
    if hold is None:
        raise ValueError(f"design_input(kind={kind!r}) needs hold=: the samples a level is held (an int, or a pair "
                         "(shortest, longest) for an APRBS); choose it from the plant's settling time")
    pair = _sequence(hold)  # a pair computed with numpy or pandas, e.g. from a settling time
    if pair is not None:
        hold = tuple(pair)
    if isinstance(hold, (tuple, list)):
        if kind != "aprbs" or len(hold) != 2:
            raise ValueError(f"hold must be an int{' or a pair (shortest, longest)' if kind == 'aprbs' else ''} for "
                             f"kind={kind!r}, got {hold!r}")
        lo = check_int(hold[0], "hold[0] (shortest)", low=1)
        return lo, check_int(hold[1], "hold[1] (longest)", low=lo)
    h = check_int(hold, "hold", low=1)
    return h, h


def _m_sequence(order: int) -> np.ndarray:
    """One period of the maximal-length sequence of ``order``, 0/1, shape (2^order − 1,)."""
    period = 2**order - 1
    taps = _PRBS_TAPS[order]
    # s(k) = XOR of s(k − t) over the taps, from a start of ones; min(taps) bits at a time, vectorised
    s = np.ones(period + order, dtype=np.int8)
    step = min(taps)
    for k in range(order, period + order, step):
        j = min(step, period + order - k)
        s[k:k + j] = np.bitwise_xor.reduce([s[k - t:k - t + j] for t in taps])
    return s[:period]


def _prbs(bits: np.ndarray, n: int, clock: int, shift: int) -> np.ndarray:
    """The sequence ``bits`` started ``shift`` bits in, each bit held ``clock`` samples, repeated to ``n`` samples."""
    reps = -(-n // (bits.size * clock))
    return np.tile(np.repeat(np.roll(bits, -shift), clock), reps)[:n]


def design_input(
    kind: str,
    n_samples: int,
    *,
    low: float | Sequence[float],
    high: float | Sequence[float],
    hold: int | tuple[int, int] | None = None,
    n_inputs: int = 1,
    order: int | None = None,
    frequencies: tuple[float, float] | np.ndarray | None = None,
    seed: int = 0,
) -> np.ndarray:
    """An input signal for an identification experiment.

    Parameters
    ----------
    kind : {"aprbs", "staircase", "prbs", "multisine"}
        ``"aprbs"``: amplitude-modulated pseudo-random binary signal, the usual choice for a
        nonlinear model: each hold lasts a random number of samples in ``hold`` and takes a level
        from an even spread over [low, high] in random order, so the record visits the whole range
        at every rate. ``"staircase"``: levels evenly spaced from ``low`` up to ``high`` and back
        down, each held ``hold`` samples, as many levels as the record has room for: the static
        curve level by level, and a hysteresis, if any, as a gap between the way up and the way
        down (several inputs: a serpentine over a grid of levels, one input moving one level at a
        time, there and back: the static surface). ``"prbs"``: a maximal-length binary sequence
        (levels ``low`` and ``high``) whose bits last ``hold`` samples: a flat spectrum for a linear
        model at one operating point, periodic with period (2^order − 1)·hold. ``"multisine"``: one
        period of a sum of sines at every frequency line in ``frequencies``, with Schroeder's
        phases (a low crest factor), scaled to span [low, high] exactly.
    n_samples : int
        Samples of the signal (its length N).
    low, high : float or sequence of float
        The input range, input units (no default: they are the plant's); one number for every input,
        or one per input (``low=[750.0, 20.0], high=[1650.0, 80.0]`` for a speed in rpm and a valve
        in %).
    hold : int or (int, int)
        Samples a level is held (a bit of a PRBS; for an APRBS a pair (shortest, longest), any 1-D array-like):
        choose it from the plant's settling time (a staircase's or an APRBS's longest hold about
        the settling time, a PRBS's bit near the fastest time constant). Refused for a multisine.
        The record's last hold is cut where the record ends, so it may be shorter.
    n_inputs : int
        Number of input columns: each APRBS column is drawn from its own stream, a PRBS column is
        the sequence shifted by i/n_inputs of its period, and a multisine column takes every
        n_inputs-th line (which share, by the seed; each column keeps Schroeder's low crest factor), so those columns are nearly uncorrelated over a long record
        (a PRBS's and a multisine's over whole periods: on a record of one period or less a PRBS's
        shifted columns may correlate, e.g. |corr| 0.67 for 3 inputs on 5 bits); a staircase's
        columns walk a grid (above).
    order : int, optional
        PRBS register length, 2–20 (default: the shortest whose period covers ``n_samples`` and
        holds at least ``n_inputs`` bits; one whose period is shorter than ``n_inputs`` is refused:
        two columns would be the same). Refused for the other kinds.
    frequencies : (float, float) or array_like, shape (2,)
        Multisine band as fractions of the Nyquist frequency, 0 < f_low < f_high <= 1 (required
        for a multisine, refused for the other kinds).
    seed : int
        Seed of the APRBS draws and of which multisine column takes which share of the lines (the
        other kinds are deterministic).

    Returns
    -------
    ndarray, shape (N,) or (N, n_inputs)
        The input, column i in the units of ``low`` and ``high`` (their i-th, when one per input).

    Raises
    ------
    ValueError
        ``low >= high``; a hold longer than the record (an APRBS's longest, than half of it), or too
        long for every input to move (a column held at one level); an option the kind does not use; a band
        with no frequency line; a PRBS order whose period is shorter than ``n_inputs``, or a record
        of too few bits for ``n_inputs`` different columns; an unknown kind.
    TypeError
        A count that is not an integer, a level that is not a number, a band that is not a pair.
    """
    kind = check_choice(kind, "kind", KINDS)
    n = check_int(n_samples, "n_samples", low=2)
    m = check_count(n_inputs, "n_inputs", low=1)
    n = check_count(n, "n_samples", item_bytes=8 * m)  # the signal, N × n_inputs floats
    lo, hi = _ranges(low, high, m)
    seed = check_seed(seed)
    if order is not None and kind != "prbs":
        raise ValueError(f"order is the PRBS register length; kind={kind!r} does not use it")
    if frequencies is not None and kind != "multisine":
        raise ValueError(f"frequencies is the multisine's band; kind={kind!r} does not use it")
    if kind == "multisine":
        if hold is not None:
            raise ValueError("hold does not apply to a multisine (it holds no level); give frequencies=(f_low, f_high)")
        cols = _multisine(n, m, frequencies, seed)
        cols = (cols - cols.min(axis=0)) / (cols.max(axis=0) - cols.min(axis=0))
        out = _scale(cols, lo, hi)
        return out[:, 0] if m == 1 else out
    h0, h1 = _holds(kind, hold)
    if h1 > n:
        raise ValueError(f"hold of {h1} samples is longer than the record ({n} samples)")
    if kind == "aprbs" and 2 * h1 > n:  # one hold could fill the record: a constant input, said nowhere
        raise ValueError(f"an APRBS needs at least two holds in the record: its longest hold ({h1} samples) must be "
                         f"at most half the record ({n // 2} samples)")
    if kind == "prbs":
        if order is not None:
            order = check_int(order, "order", low=min(_PRBS_TAPS), high=max(_PRBS_TAPS))
            if 2**order - 1 < m:  # the columns' shifts, i/n_inputs of the period, would repeat
                raise ValueError(f"order={order} gives a period of {2**order - 1} bits, fewer than the {m} inputs, "
                                 "whose columns are the sequence shifted by whole bits: some would be the same "
                                 "column; raise order")
        else:  # the shortest register whose period covers the record and gives each input its own shift
            order = next((o for o in _PRBS_TAPS if (2**o - 1) * h0 >= n and 2**o - 1 >= m), max(_PRBS_TAPS))
        bits = _m_sequence(order)  # once: the columns are its shifts
        cols = np.column_stack([_prbs(bits, n, h0, (i * bits.size) // m) for i in range(m)])
        if len({c.tobytes() for c in cols.T}) < m:  # shifted sequences that agree over the record's few bits
            raise ValueError(f"a record of {-(-n // h0)} PRBS bits (n_samples={n}, hold={h0}) is too short for "
                             f"{m} different input columns: shorten hold or lengthen the record")
        out = _scale(cols, lo, hi)
    elif kind == "staircase":
        out = _staircase(-(-n // h0), m)
        out = np.repeat(_scale(out, lo, hi), h0, axis=0)[:n]
    else:  # aprbs
        cols = []
        for i in range(m):
            rng = np.random.default_rng([seed, i])
            holds, total = [], 0
            while total < n:  # a running total: summing the list at each draw was quadratic in the holds
                holds.append(int(rng.integers(h0, h1 + 1)))
                total += holds[-1]
            # an even spread of levels over the range, visited in random order: every part of the range is met
            levels = _scale(rng.permutation(len(holds)) / max(len(holds) - 1, 1), lo[i], hi[i])
            cols.append(np.repeat(levels, holds)[:n])
        out = np.column_stack(cols)
    # too few holds for the record (a staircase's serpentine moves its slower inputs last; a PRBS's first
    # bits may agree): a column held at one level is an experiment in which that input never moves
    still = [i for i in range(m) if np.all(out[:, i] == out[0, i])]  # not np.ptp: it overflows on ±1e308
    if still:
        which = "the input" if m == 1 else f"input column(s) {still}"
        raise ValueError(f"{which} of this {kind} never moves: {-(-n // h0)} hold(s) of {h0} samples fit in the "
                         f"{n}-sample record; shorten hold or lengthen the record")
    return out[:, 0] if m == 1 else out


def _ranges(low: object, high: object, m: int) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) as arrays of one bound per input, shape (m,), each pair checked low < high."""
    out = []
    for what, v in (("low", low), ("high", high)):
        # any array-like of one dimension is one bound per input (a list, a range, a Series of df.min()); a 0-d
        # array is one number, as check_real reads it
        if not isinstance(v, (str, bytes)) and np.ndim(v) > 0:
            if np.ndim(v) != 1 or len(v) != m:
                raise ValueError(f"{what} must be one number, or one per input ({m}), got {v!r}")
            out.append(np.array([check_real(x, f"{what}[{i}]") for i, x in enumerate(np.asarray(v, dtype=object))]))
        else:
            out.append(np.full(m, check_real(v, what)))
    lo, hi = out
    bad = np.flatnonzero(~(lo < hi))
    if bad.size:
        i = int(bad[0])
        where = f" for input {i}" if m > 1 else ""
        raise ValueError(f"design_input needs low < high{where}, got low={float(lo[i])!r}, high={float(hi[i])!r}")
    return lo, hi


def _staircase(k: int, m: int) -> np.ndarray:
    """``k`` holds of a staircase over the unit cube [0, 1]^m, shape (k, m): a serpentine over an even grid
    of levels (each move changes one input by one level) and back along the same path."""
    # levels per input: the finest grid whose way there and back fits in the record's holds
    L = 2
    while 2 * (L + 1) ** m - 2 <= k:
        L += 1
    # a grid of more points than holds is walked part of the way only: its first k points (2^30 of them for 30
    # inputs ran out of memory), each digit 0 where its place value exceeds every index (none past int64)
    j = np.arange(min(L**m, k))
    top = int(j[-1]) if j.size else 0
    digits = np.column_stack([(j // L ** (m - 1 - i)) % L if L ** (m - 1 - i) <= top else np.zeros(j.size, int)
                              for i in range(m)])  # column 0 the slowest
    for i in range(1, m):  # serpentine: a digit runs backwards while the slower digits' sum is odd
        odd = digits[:, :i].sum(axis=1) % 2 == 1
        digits[odd, i] = L - 1 - digits[odd, i]
    path = digits / (L - 1)
    if len(path) < L**m:
        return path
    there_and_back = np.vstack([path, path[-2:0:-1]]) if len(path) > 2 else path
    return np.resize(there_and_back, (k, m))


def _multisine(n: int, m: int, frequencies: object, seed: int) -> np.ndarray:
    """Columns of one period of n samples of Schroeder-phased multisines on interleaved lines, shape (n, m)."""
    if frequencies is None:
        raise ValueError("design_input(kind='multisine') needs frequencies=(f_low, f_high): the band as fractions of "
                         "the Nyquist frequency")
    band = _sequence(frequencies)  # any 1-D pair, as low= and high= take any 1-D bounds
    if band is None:
        if isinstance(frequencies, (tuple, list, np.ndarray)):  # nested: a pair of the wrong shape
            raise ValueError(f"frequencies must be a pair (f_low, f_high), got {frequencies!r}")
        raise TypeError(f"frequencies must be a pair (f_low, f_high), got {frequencies!r} ({type(frequencies).__name__})")
    if len(band) != 2:
        raise ValueError(f"frequencies must be a pair (f_low, f_high), got {frequencies!r}")
    frequencies = band
    f0 = check_real(frequencies[0], "frequencies[0] (f_low)", low=0, low_open=True, high=1)
    f1 = check_real(frequencies[1], "frequencies[1] (f_high)", low=f0, low_open=True, high=1)
    # line j has frequency j/n cycles a sample, j/(n/2) of Nyquist
    lines = np.arange(1, n // 2 + 1)
    lines = lines[(lines * 2 / n >= f0) & (lines * 2 / n <= f1)]
    if lines.size < m:
        raise ValueError(f"the band {f0:g}–{f1:g} of Nyquist holds {lines.size} frequency line(s) of a {n}-sample "
                         f"period, fewer than the {m} input(s): widen it or lengthen the record")
    # interleaved: every m-th line, which column starts where drawn by the seed. Schroeder's phases flatten the
    # envelope of equally spaced lines only: on a random share of the lines they gave crest factors of 3.2-3.8,
    # those of random phases
    start = np.random.default_rng([seed, 99]).permutation(m) if m > 1 else np.zeros(1, int)
    cols = []
    for i in range(m):
        ln = lines[start[i]::m]
        K = np.arange(1, ln.size + 1)
        phase = -np.pi * K * (K - 1) / ln.size  # Schroeder: a flat spectrum with a low crest factor
        # Σ_j cos(2π j k / n + φ_j) over one period is an inverse real FFT (a sum over an (n × lines) matrix was
        # quadratic in n: 10⁵ samples needed 15 GB): X_j = (n/2) e^{iφ_j}, and at Nyquist (j = n/2) n cos φ_j
        X = np.zeros(n // 2 + 1, complex)
        X[ln] = (n / 2) * np.exp(1j * phase)
        if n % 2 == 0 and ln.size and ln[-1] == n // 2:
            X[n // 2] = n * np.cos(phase[-1])
        cols.append(np.fft.irfft(X, n))
    return np.column_stack(cols)
