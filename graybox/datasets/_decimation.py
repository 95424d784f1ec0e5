"""The sampling period of a polynomial NARX model: how far an oversampled record may be decimated, and decimation.

A record sampled much faster than its dynamics makes a poor NARX record: consecutive samples nearly
agree, y(k−1) and y(k−2) are nearly collinear, the model's poles crowd onto 1 and its terms' lags
must reach far back. Billings & Aguirre (1995, "Effects of the sampling time on the dynamics and
identification of nonlinear models", Int. J. Bifurcation and Chaos 5(6):1541–1556) give a rule read
off the output alone: with y' = y − mean(y), τ_y and τ_y² the first minima of the autocorrelations of y'
and of y'² − mean(y'²) (the second sees the nonlinear part; of y² itself, an offset would leave mostly y), and τ_m = min(τ_y, τ_y²), choose the sampling
period so that 10 ≤ τ_m ≤ 20 in the new samples: decimate by a factor q in [τ_m / 20, τ_m / 10].
Where an autocorrelation decays without a minimum beyond its noise (an output driven by a staircase
of random levels), the lag at which it dies out (can no longer be told from zero) stands in for the
minimum (see :func:`_first_minimum`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Mapping, Sequence

import numpy as np

from ..core._records import Dataset, Record, as_records
from ..core._transient import recomputed_transients
from ..core._validation import check_bool, check_fields, check_int
from ..io._json import register_type

__all__ = ["DecimationAdvice", "decimation_advice", "decimate"]

#: The rule's span of τ_m in the decimated record's samples.
TAU_SAMPLES = (10, 20)
#: Half-length of the anti-alias filter in decimated samples (scipy.signal.decimate's FIR: 20q + 1 taps).
_HALF_TAPS = 10


@dataclass(frozen=True)
class DecimationAdvice:
    """How far a record may be decimated (:func:`decimation_advice`).

    Attributes
    ----------
    q : int or None
        The suggested factor: τ_m / 15 rounded, at least 1 (1: the record is not oversampled). None
        when no autocorrelation minimum was found (``reason`` says why): there is nothing to advise.
    q_range : tuple of int or None
        The factors the rule allows, (max(1, ⌈τ_m / 20⌉), max(1, ⌊τ_m / 10⌋)).
    tau_y : int or None
        First minimum of the autocorrelation of y' = y − mean(y) below its 95 % band, or where there is
        none the lag at which it dies out (enters the band to stay: can no longer be told from zero), in
        samples of the record (the smallest over several records); None where there is neither within a
        quarter of the record.
    tau_y2 : int or None
        The same for y'² − mean(y'²), the squared deviation (nonlinear correlation).
    tau_m : int or None
        min(tau_y, tau_y2).
    Ts : float
        The record's sampling period (s).
    reason : str
        Empty when ``q`` is given; otherwise why not.
    """

    q: int | None
    q_range: tuple | None
    tau_y: int | None
    tau_y2: int | None
    tau_m: int | None
    Ts: float
    reason: str = ""

    def __post_init__(self) -> None:
        check_fields(self)
        if self.q_range is not None:
            object.__setattr__(self, "q_range", tuple(self.q_range))  # a JSON list comes back a tuple
        taus = [t for t in (self.tau_y, self.tau_y2) if t is not None]
        if any(t < 1 for t in taus) or self.tau_m != (min(taus) if taus else None):
            raise ValueError(f"DecimationAdvice: tau_m must be the smaller of tau_y and tau_y2 (lags >= 1), got "
                             f"tau_m={self.tau_m}, tau_y={self.tau_y}, tau_y2={self.tau_y2}")
        if not (self.Ts > 0 and np.isfinite(self.Ts)):
            raise ValueError(f"DecimationAdvice: Ts must be a finite period > 0 (s), got {self.Ts!r}")
        if self.q is None:
            if self.q_range is not None or not self.reason or self.tau_m is not None:
                raise ValueError("DecimationAdvice: without a q there is no q_range and no minimum tau_m (the rule "
                                 "advises a q wherever it read one), and the reason says why")
            return
        if (self.reason or self.q_range is None or len(self.q_range) != 2
                or not all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in self.q_range)
                or not 1 <= self.q_range[0] <= self.q <= self.q_range[1]):
            raise ValueError(f"DecimationAdvice: q={self.q} must lie in q_range, a pair 1 <= low <= high, got "
                             f"{self.q_range!r}, and a q needs no reason")
        # the rule's figures for tau_m (a hand-edited file held q and q_range to each other only)
        if self.tau_m is None or (self.q, tuple(self.q_range)) != _rule(self.tau_m):
            want = "a minimum tau_m" if self.tau_m is None else f"q, q_range = {_rule(self.tau_m)}"
            raise ValueError(f"DecimationAdvice: the rule gives {want} for tau_m = {self.tau_m}, got q={self.q}, "
                             f"q_range={self.q_range!r}")

    @property
    def Ts_new(self) -> float | None:
        """The sampling period after decimating by ``q`` (s); None without a ``q``."""
        return None if self.q is None else self.q * self.Ts

    def __repr__(self) -> str:
        if self.q is None:
            return f"DecimationAdvice(q=None: {self.reason})"
        return (f"DecimationAdvice(q={self.q} (allowed {self.q_range[0]}..{self.q_range[1]}), Ts {self.Ts:g} s -> "
                f"{self.Ts_new:g} s; tau_y={self.tau_y}, tau_y2={self.tau_y2} samples)")


# saved by gb.save as JSON; this layer sits above io, so it registers its own type (as the experiment layer does)
register_type("DecimationAdvice", DecimationAdvice,
              (("q", "int_or_none"), ("q_range", "ints_or_none"), ("tau_y", "int_or_none"), ("tau_y2", "int_or_none"),
               ("tau_m", "int_or_none"), ("Ts", "float"), ("reason", "str")))


def _first_minimum(x: np.ndarray) -> int | None:
    """The lag τ ≥ 1 the rule reads off the sample autocorrelation r of ``x`` (centred), searched up to a
    quarter of the record: its first local minimum below the autocorrelation's 95 % band (Bartlett's,
    ±2·√((1 + 2 Σ_{v<τ} r(v)²) / N)) before r has died out; where it has none, the lag at which r dies
    out (enters the band, and below 1/e, to stay there up to twice that lag, within the quarter); None
    when neither comes (a drift, or a record too short for its slowest motion, whose band widens over
    r itself).

    A signal that oscillates (a sine: r = cos) turns deeply below the band: its first minimum is the
    rule's. One whose autocorrelation decays to zero without turning (an output driven by a staircase
    of random levels, a first-order plant driven by noise) has only the wiggles of the estimate
    beyond, at any lag (they are slow in τ, and some cross the band): the decay's end is then its time
    scale. A crossing of the band on the way down (a sine's zero) does not end it."""
    x = x - x.mean()
    n = x.size
    top = n // 4
    if top < 3 or not np.any(x):
        return None
    f = np.fft.rfft(x, 2 * n)  # zero-padded: the linear (not circular) correlation
    r = np.fft.irfft(f * np.conj(f))[:top + 1]
    r = r / r[0]
    lags = np.arange(1, top)
    band = 2.0 * np.sqrt((1.0 + 2.0 * np.concatenate([[0.0], np.cumsum(r[1:-2] ** 2)])) / n)  # at lags 1 … top − 1
    inner = r[1:-1]
    outside = lags[np.abs(inner) > band]
    # the next lag outside the band from each lag on (top: none)
    nxt = np.append(outside, top)[np.searchsorted(outside, lags)]
    # inside the band, a band below 1/e (a record short for a slow motion widens the band over r itself: the
    # centred square of a drift, a U, falls inside it), to stay up to twice the lag, within the quarter searched
    died = lags[(np.abs(inner) <= band) & (band <= np.exp(-1.0)) & (nxt > 2 * lags) & (2 * lags < top)]
    end = int(died[0]) if died.size else None
    # r[τ] ≤ r[τ − 1] and r[τ] < r[τ + 1], below the band, before r died out
    turns = lags[(inner <= r[:-2]) & (inner < r[2:]) & (inner < -band)]
    if turns.size and (end is None or turns[0] < end):
        return int(turns[0])
    return end


def decimation_advice(data: Record | Dataset | Sequence[Record]) -> DecimationAdvice:
    """How far a record may be decimated for a polynomial NARX model (Billings & Aguirre's rule).

    Parameters
    ----------
    data : Record, Dataset or sequence of Record
        The records (a Dataset: its identification record). Only their outputs are read.

    Returns
    -------
    DecimationAdvice
        The factor q to pass to :func:`decimate` (1 when the record is not oversampled; None, with
        the reason, when no minimum was found), the range the rule allows, and the minima it read.

    Notes
    -----
    Read the rule's range as the most the record can be decimated, not as a target: on four cases
    the black box chosen at its q had 1.06 to thousands of times the test error of the one chosen at
    the record's own rate, and half of q was best on two (BENCHMARKS.md, "Decimation"). Choose the
    factor on a validation record; decimation's sure gain is time.

    Raises
    ------
    TypeError
        ``data`` is not records.
    ValueError
        An output that does not move.
    """
    recs = as_records(data, name="data")
    taus = []
    for rec in recs:
        y = rec.y
        if np.all(y == y[0]):  # not np.ptp: it overflows on ±1e308
            raise ValueError(f"record {rec.name!r}: the output does not move, so it says nothing of the sampling "
                             "period")
        # in units of its largest value, centred, and again: the autocorrelations are unit-free, but their squares
        # and sums are not (y in 1e-150 or 1e150 units under- or overflowed y'² and lost τ_y², q moved)
        y = y / np.abs(y).max()
        yc = y - y.mean()  # the square of the centred output: of y itself an offset c makes y² ≈ c² + 2cy, read as y
        yc = yc / np.abs(yc).max()
        taus.append((_first_minimum(yc), _first_minimum(yc * yc)))
    tau_y = min((t for t, _ in taus if t is not None), default=None)
    tau_y2 = min((t for _, t in taus if t is not None), default=None)
    found = [t for t in (tau_y, tau_y2) if t is not None]
    Ts = recs[0].Ts
    if not found:
        return DecimationAdvice(None, None, None, None, None, Ts,
                                "no autocorrelation minimum below its 95 % band, and no decay into that band, within a "
                                "quarter of the record (a minimum inside the band is noise, not a time scale): its "
                                "slowest motion does not turn within it (a drift, or a record too short for its "
                                "dynamics)")
    tau_m = min(found)
    q, q_range = _rule(tau_m)
    return DecimationAdvice(q, q_range, tau_y, tau_y2, tau_m, Ts)


def _rule(tau_m: int) -> tuple[int, tuple[int, int]]:
    """(q, q_range) of the rule for τ_m: 10 ≤ τ_m / q ≤ 20, q = τ_m / 15 rounded, each at least 1."""
    lo, hi = TAU_SAMPLES
    q_range = (max(1, math.ceil(tau_m / hi)), max(1, math.floor(tau_m / lo)))
    return min(max(q_range[0], round(tau_m / ((lo + hi) / 2))), q_range[1]), q_range


def decimate(data: Record | Dataset | Sequence[Record], q: int, *, antialias: bool = True
             ) -> Record | Dataset | list[Record]:
    """Keep every ``q``-th sample of a record, its output low-passed first.

    Parameters
    ----------
    data : Record, Dataset or sequence of Record
        What to decimate (a Dataset: both records; its static points are kept as they are).
    q : int
        The factor (>= 1), e.g. :func:`decimation_advice`'s ``q``. The sampling period becomes ``q * Ts``.
    antialias : bool
        Low-pass the output before keeping every q-th sample (default): a linear-phase FIR filter
        (Hamming window, 20q + 1 taps, cutoff at the new Nyquist frequency, unit gain at zero
        frequency) applied forwards without delay, the record's ends extended by odd reflection so
        that a level or a ramp passes unchanged (an offset or a unit never changes the result but
        by the same offset and scale). Noise above the new Nyquist frequency would otherwise fold
        into the band the model fits. The inputs are never filtered, only subsampled: they are what
        was applied, and a filtered input is one the plant never saw. Transient inputs
        (:func:`graybox.transient_inputs`) are no samples of the plant but filters of an input at the
        sampling period: they are computed afresh at the new period, as for a record sampled there.

    Returns
    -------
    Record, Dataset or list of Record
        The same kind as ``data``: samples 0, q, 2q, … of each record, named "<name> / q" (a Dataset's
        description ends in "(decimated by q)"). ``q = 1`` is a no-op: the records come back as they are,
        names and description unchanged (:func:`decimation_advice` says ``q = 1`` when the sampling is
        already slow enough, and then nothing was decimated).

    Raises
    ------
    TypeError
        ``data`` is not records; ``q`` not an int.
    ValueError
        ``q`` < 1; a record too short for the filter (more than 10q + 1 samples needed with
        ``antialias``) or for two samples after decimation.
    """
    q = check_int(q, "q", low=1)
    antialias = check_bool(antialias, "antialias")
    if isinstance(data, Dataset):
        if q == 1:  # nothing decimated: the records are kept as they are (_decimate), and so is the description
            return data
        taus = data.extra.get("transient_inputs")
        ident, valid = (_decimate(r, q, antialias, taus if isinstance(taus, Mapping) else None)
                        for r in (data.ident, data.valid))
        return replace(data, ident=ident, valid=valid,
                       description=(data.description + f" (decimated by {q})").strip())
    recs = as_records(data, name="data")
    out = [_decimate(r, q, antialias) for r in recs]
    return out[0] if isinstance(data, Record) else out


def _decimate(rec: Record, q: int, antialias: bool, taus: Mapping | None = None) -> Record:
    n = len(rec)
    if q == 1:
        return rec
    if n <= q:  # samples 0, q, 2q, …: a second one needs q + 1 samples
        raise ValueError(f"record {rec.name!r}: {n} samples make fewer than 2 after decimating by {q} (more than {q} "
                         "needed)")
    y = rec.y
    if antialias:
        half = _HALF_TAPS * q
        if n <= half + 1:
            raise ValueError(f"record {rec.name!r}: {n} samples are too few for the anti-alias filter of decimation by "
                             f"{q} (more than {half + 1} needed); decimate with antialias=False, or by less")
        from scipy.signal import firwin  # scipy.signal is slow to import: only when a record is filtered

        taps = firwin(2 * half + 1, 1.0 / q)
        # in units of max|y|, a power of two (the same bits in any other units): 2·y[0] − y overflowed near 1e308
        top = float(np.max(np.abs(y)))
        scale = 2.0 ** np.floor(np.log2(top)) if top > 0 else 1.0
        y = y / scale
        # odd reflection about each end: a level and a ramp continue as they are, so the filter leaves them be
        ext = np.concatenate([2 * y[0] - y[half:0:-1], y, 2 * y[-1] - y[-2:-half - 2:-1]])
        y = np.convolve(ext, taps, mode="valid") * scale
    # a transient input is no sample of the plant but a filter of its input at the period: computed afresh
    u = recomputed_transients(rec.u[::q], rec.input_names, rec.Ts * q, taus)
    return Record(u, y[::q], rec.Ts * q, f"{rec.name} / {q}", rec.units, rec.input_names)
