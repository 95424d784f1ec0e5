"""Selection on centred signals: the one home of ``centre=True`` (frols, semp, select_graybox).

The candidate terms are monomials of the raw signals, so a greedy (or best-subset) pick depends on
where each signal's zero is: y(k-1)u(k-1) is not (y(k-1) − c)(u(k-1) − d). With ``centre=True`` the
search runs on the signals minus a reference (the identification records' mean of y and of each
input), and each chosen centred term is then expanded into the raw monomials it implies. Those are
its divisors (``(y − c)(u − d)`` needs ``yu``, ``y``, ``u`` and ``1``), so a chosen structure is
replaced by its *hierarchical closure*: the smallest set of terms holding every divisor of every
term. A closed set spans the same functions whatever the offsets, so the model stays a raw-signal
NARX that every other part of the library handles, and its least-squares fit, free run and J_S do
not depend on the offsets (up to round-off); the price is more terms than were chosen.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import replace
from typing import Mapping, Sequence

import numpy as np

from ..core._gram import DaskRecord, is_dask_data
from ..core._records import Dataset, Record, StaticPoints, as_records
from ..core._least_squares import column_scales, rank_tolerance
from ..core._regressors import stacked_regressors
from ..core._terms import Structure, Term
from ._subset_search import rss_floor


def signal_offsets(data: object) -> dict[str, float]:
    """The reference each signal is centred on: its mean over the identification records.

    Parameters
    ----------
    data : Record, sequence of Record, or Dataset
        Identification data (a Dataset contributes its ``ident`` record).

    Returns
    -------
    dict
        ``{"y": mean of y, name: mean of that input, ...}`` in engineering units, over every sample of
        every record (pooled); a signal held at one level, that level (centred, exactly zero).
    """
    if is_dask_data(data):
        raise ValueError("centre=True needs the records in memory (a DaskRecord is not centred): give a Record of "
                         "its samples, or leave centre out (a fit on signals less means subtracted by hand is a model "
                         "of those, not of the signals in their own units)")
    return {name: _centre_of(x) for name, x in pooled_signals(data).items()}


def pooled_signals(data: object) -> dict[str, np.ndarray]:
    """``{"y": y, name: that input, ...}``, each pooled over every sample of every record of ``data`` (in memory)."""
    records = as_records(data)
    us = np.concatenate([r.u.reshape(len(r.y), -1) for r in records])
    return {"y": np.concatenate([r.y for r in records]),
            **{n: us[:, i] for i, n in enumerate(records[0].input_names)}}


def round_off_gain(data: object, centred: object) -> float:
    """How much the centred signals' round-off exceeds what their own size suggests: their digits were rounded at
    the size recorded. The largest ratio of a signal's mean square as recorded to centred, at least 1 (a signal
    that centring makes zero counts none)."""
    raw, cen = pooled_signals(data), pooled_signals(centred)
    gain = 1.0
    with np.errstate(over="ignore"):  # near the float range's ends: no gain said (the caller scales there)
        for name, x in raw.items():
            c = cen[name]
            ratio = float(np.mean(x * x)) / float(np.mean(c * c)) if np.any(c) else 1.0
            if np.isfinite(ratio):
                gain = max(gain, ratio)
    return gain


def _centre_of(x: np.ndarray) -> float:
    """The mean of a signal; for one held at a single level (:func:`_held`), that level: centred it is then exactly
    zero (:func:`centred_data`), where the mean's round-off (7.3 held: 7.3 − mean ≈ 1e-15) left columns of
    round-off that the searches took for candidates, so that what they chose depended on the level the input was
    held at."""
    return float(x[0]) if is_held(x) else float(x.mean())


def is_held(x: np.ndarray) -> bool:
    """Whether a signal (pooled over the records) is held at one level: its spread is within the round-off of its
    level by the one rank rule (the uncentred regression cannot tell it from the constant), so that a level said
    apart by round-off (7.3 in one record, 73 * 0.1 = 7.300000000000001 in another, a converted unit) is one
    level, as bit-for-bit equal samples are."""
    return bool(x.size) and float(np.ptp(x)) <= rank_tolerance(float(np.max(np.abs(x))), x.size)


def search_offsets(data: object) -> dict[str, float]:
    """:func:`signal_offsets` for a structure search on the centred signals; ``ValueError`` when the output is
    constant over the records: centred it is zero (or its mean's round-off, where the mean is inexact), which
    no search can rank structures on."""
    offsets = signal_offsets(data)
    ys = np.concatenate([r.y for r in as_records(data)])
    if is_held(ys):
        said = "" if np.ptp(ys) == 0.0 else f" to its round-off (spread {np.ptp(ys):.1e})"
        raise ValueError(f"the output is constant (y = {ys[0]:.6g} at every sample of the identification data{said}): "
                         "centred on its mean it is zero, and a structure search has nothing to rank there; its "
                         "model is the constant alone (which frols and semp choose with centre left out)")
    return offsets


def dask_levels(records: Sequence[DaskRecord]) -> tuple[dict[str, float], frozenset, dict[str, float]]:
    """For Dask records (one input, ``u``): each signal's mean over every sample of every record (as
    :func:`signal_offsets`; NaN or inf where a sample is not finite), the signals held at one level (:func:`is_held`'s
    rule) and each signal's first sample, from one pass on the active Dask scheduler."""
    import dask

    parts = [(a.sum(), a.min(), a.max(), a[0]) for r in records for a in (r.u, r.y)]
    got = np.array(dask.compute(*[v for p in parts for v in p]), dtype=float).reshape(len(records), 2, 4)
    size = sum(len(r) for r in records)
    offsets, held, first = {}, [], {}
    for j, name in enumerate(("u", "y")):
        total, lo, hi = got[:, j, 0].sum(), got[:, j, 1].min(), got[:, j, 2].max()
        offsets[name] = float(total / size)
        first[name] = float(got[0, j, 3])
        with np.errstate(invalid="ignore"):  # inf - inf: not held (and the offsets are not finite)
            if hi - lo <= rank_tolerance(max(abs(lo), abs(hi)), size):
                held.append(name)
    return offsets, frozenset(held), first


def centred_dask(records: Sequence[DaskRecord], offsets: Mapping[str, float]) -> list[DaskRecord]:
    """Dask records with u and y less their ``offsets`` (nothing computed: the blocks are shifted as they are read)."""
    return [DaskRecord(r.u - offsets["u"], r.y - offsets["y"], Ts=r.Ts, name=r.name, units=r.units) for r in records]


def _shift_record(rec: Record, offsets: Mapping[str, float], held: frozenset = frozenset()) -> Record:
    d = np.array([offsets[n] for n in rec.input_names])
    u = rec.u - (d[0] if rec.u.ndim == 1 else d)
    y = rec.y - offsets["y"]
    # a held signal is exactly zero once centred, not the round-off of a level said apart by it
    if held:
        u = u.reshape(len(y), -1)
        u[:, [i for i, n in enumerate(rec.input_names) if n in held]] = 0.0
        u = u.reshape(rec.u.shape)
        if "y" in held:
            y[:] = 0.0
    return replace(rec, u=u, y=y)


def centred_data(data: object, offsets: Mapping[str, float], keep: frozenset = frozenset()) -> Record | list[Record]:
    """The identification records with each signal minus its offset (new arrays; the data untouched); a signal
    held at one level over the records (:func:`is_held`) exactly zero, but those named in ``keep`` (each then
    minus its offset only, e.g. 0: left at its level)."""
    records = as_records(data)
    names = records[0].input_names
    us = np.concatenate([r.u.reshape(len(r.y), -1) for r in records])
    held = frozenset([n for i, n in enumerate(names) if is_held(us[:, i])]
                     + (["y"] if is_held(np.concatenate([r.y for r in records])) else [])) - keep
    shifted = [_shift_record(r, offsets, held) for r in records]
    return shifted[0] if isinstance(data, (Record, Dataset)) else shifted


def centred_points(points: StaticPoints, offsets: Mapping[str, float]) -> StaticPoints:
    """Static points on the signals less ``offsets`` (as :func:`centred_data`'s records, no signal zeroed): ū less
    the input's offset (one input: the records' one, whatever the points call it; several: by name), ȳ less y's."""
    ub = np.asarray(points.ubar, float)
    if ub.ndim == 1:
        ub = ub - next(v for k, v in offsets.items() if k != "y")
    else:
        ub = ub - np.array([offsets[n] for n in points.input_names])
    return replace(points, ubar=ub, ybar=np.asarray(points.ybar, float) - offsets["y"])


def check_included(include: Sequence[Term | str], process: Structure, data: object,
                   dropped: Sequence[tuple[Term, str]] = ()) -> None:
    """Refuse (``ValueError``) an included term that a centred search cannot keep.

    A term of an input held at one level over every identification record is zero once centred (or
    round-off of zero), and a term :func:`told_apart` leaves out is not in the structure returned:
    either would break ``include``'s promise that every structure holds it. Call before the search
    (``dropped`` empty) and after the closure (the terms it left out).
    """
    terms = [process[j] for j in process.positions(include, "included term")]
    records = as_records(data)
    names = records[0].input_names
    us = np.concatenate([r.u.reshape(len(r.y), -1) for r in records])
    held = {n: float(us[0, i]) for i, n in enumerate(names) if is_held(us[:, i])}  # as centred_data zeroes them
    gone = dict(dropped)
    for t in terms:
        for s in (s for s, _, _ in t.factors if s in held):
            raise ValueError(f"included term {t} cannot be fitted with centre=True: input {s} is held at {held[s]:g} "
                             "over the identification records, so centred the term is zero there; leave it out of "
                             "include (the constant 1 carries a held input's level), or centre out")
        if t in gone:
            raise ValueError(f"included term {t} cannot stay in a structure closed under shifts: it is {gone[t]}; "
                             "leave it out of include, or centre out")


def _divisors(term: Term) -> list[Term]:
    ranges = [range(p + 1) for _, _, p in term.factors]
    out = []
    for powers in itertools.product(*ranges):
        out.append(Term(tuple((s, l, j) for (s, l, _), j in zip(term.factors, powers) if j)))
    return out


def closure(structure: Structure | Sequence[Term | str]) -> Structure:
    """The hierarchical closure of a structure's process terms: every divisor of every term.

    The terms given keep their order; the divisors they bring follow, smallest degree first (the
    constant ``1`` is a divisor of every term). Noise terms are kept as they are, last.
    """
    st = structure if isinstance(structure, Structure) else Structure(structure)
    process = [t for t in st if not t.is_noise]
    seen = set(process)
    added = sorted({d for t in process for d in _divisors(t)} - seen, key=Term.sort_key)
    return Structure(process + added + [t for t in st if t.is_noise])


def told_apart(structure: Structure, records: Record | list[Record], rank_tol: float,
               start: int | None = None) -> tuple[Structure, tuple[tuple[Term, str], ...]]:
    """The terms of a closed structure that the centred ``records`` tell apart, the set still closed.

    A closure can hold a term the data cannot tell from its divisors: with a two-level input (a PRBS)
    ``(u(k-1) − d)²`` is a combination of ``u(k-1) − d`` and ``1``, and every term of a held input is zero.
    Taken by degree (the constant, then single signals, then products), a term whose unit-RMS column
    leaves at most ``rank_tol`` √N outside the span of the terms kept before it is dropped, and so is
    every multiple of a dropped term (or the set is not closed). The span of the terms before a term
    of degree d is that of a closed set plus terms of degree d, which a shift changes only by lower
    terms: what is dropped does not depend on the offsets. It is judged on the rows from sample ``start`` of
    each record (default: the structure's largest lag), those the closure is then fitted on.

    Returns
    -------
    kept : Structure
        The process terms kept, in the structure's order.
    dropped : tuple of (Term, str)
        Each term left out and why, in degree order.
    """
    process = structure.process
    order = sorted(process, key=Term.sort_key)
    X, _ = stacked_regressors(Structure(order), records, start=start)
    X = X / column_scales(X)
    bound = rank_tol * math.sqrt(X.shape[0])
    basis = np.zeros((X.shape[0], 0))
    dropped: dict[Term, str] = {}
    for j, t in enumerate(order):
        gone = next((d for d in _divisors(t) if d in dropped), None)
        if gone is not None:
            dropped[t] = f"a multiple of {gone}, which these data cannot tell from its divisors"
            continue
        r = X[:, j] - basis @ (basis.T @ X[:, j])
        r -= basis @ (basis.T @ r)  # twice is enough (Kahan): the residual is orthogonal to round-off
        norm = float(np.linalg.norm(r))
        if norm <= bound:
            dropped[t] = "a linear combination of lower terms on these (centred) data"
        else:
            basis = np.column_stack([basis, r / norm])
    kept = Structure([t for t in process if t not in dropped]) if dropped else process
    return kept, tuple(dropped.items())


def from_sample(records: Record | list[Record], skip: int) -> Record | list[Record]:
    """The records without their first ``skip`` samples (new records): a structure whose largest lag is
    ``L − skip`` has its regression rows there at the samples L, L + 1, … of the records given, the search's rows
    when L is the candidates' largest lag."""
    if skip <= 0:
        return records
    out = [replace(r, u=r.u[skip:], y=r.y[skip:]) for r in as_records(records)]
    return out[0] if isinstance(records, Record) else out


def check_closure_rows(closed: Structure, records: Record | list[Record], chosen: int, start: int) -> None:
    """Refuse (``ValueError``) a closure with as many terms as its regression rows (from sample ``start`` of each
    record, the search's), or more.

    A closure holds more terms than were chosen, so on a short record the terms a search chose on the centred
    signals (a criterion smallest at the most terms the rows allow) can close to a structure whose least-squares
    fit interpolates the record: no error is left to fit, which every estimator refuses (``check_rows``).
    """
    rows = sum(len(r) - start for r in as_records(records))
    if len(closed) >= rows:
        raise ValueError(f"the {chosen} terms chosen on the centred signals close under shifts to {len(closed)} terms, "
                         f"which need more than their {rows} regression rows (their fit would interpolate the record, "
                         "no error left to fit); use a longer record, fewer candidates (smaller lags or degree), a "
                         "smaller n_terms or max_terms, or centre out")


def raw_theta(structure: Structure, theta: np.ndarray, offsets: Mapping[str, float], *,
              level: bool = True) -> np.ndarray:
    """The parameters, on the raw signals, of a model fitted on the centred ones.

    ``y(k) − c_y = Σ θ_j Π (x − c_x)`` expanded by the binomial theorem into the raw monomials; a
    closed ``structure`` holds every one of them (``ValueError`` otherwise). Noise signals are not
    shifted.
    ``level=False``: without the output's offset ``c_y`` added to the constant (the map's linear part).
    """
    pos = {t: i for i, t in enumerate(structure)}
    out = np.zeros(len(structure))
    for t, th in zip(structure, np.asarray(theta, dtype=float)):
        for powers in itertools.product(*[range(p + 1) for _, _, p in t.factors]):
            coef = th
            for (s, _, p), j in zip(t.factors, powers):
                c = 0.0 if s == "e" else offsets[s]
                if j < p:
                    coef *= math.comb(p, j) * (-c) ** (p - j)
            if coef == 0.0:
                continue
            d = Term(tuple((s, l, j) for (s, l, _), j in zip(t.factors, powers) if j))
            if d not in pos:
                raise ValueError(f"the structure is not closed under shifts: {t} needs {d}")
            out[pos[d]] += coef
    if level and offsets["y"] != 0.0:
        if Term(()) not in pos:
            raise ValueError("the structure is not closed under shifts: an offset of y needs the constant 1")
        out[pos[Term(())]] += offsets["y"]
    return out


def is_closed(structure: Structure) -> bool:
    """Whether the process terms hold every divisor of every term (the constant ``1`` included): a set whose
    functions are the same wherever the signals' zeros are (:func:`closure`)."""
    process = [t for t in structure if not t.is_noise]
    have = set(process)
    return bool(process) and all(d in have for t in process for d in _divisors(t))


def shift_map(structure: Structure, offsets: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """``(A, t)`` with ``raw_theta(structure, θ_c, offsets) = A @ θ_c + t`` for every θ_c: the affine map from
    the parameters on the centred signals to those on the raw ones (``t`` carries the output's offset into the
    constant). ``structure`` must be closed (:func:`is_closed`; ``ValueError`` otherwise); its inverse is the map
    of the negated offsets."""
    if not is_closed(structure):
        raise ValueError(f"the structure is not closed under shifts: {structure}")
    return affine_map(structure, offsets)


def affine_map(structure: Structure, offsets: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """:func:`shift_map` without its closure check, for a structure the caller knows has every term's divisors
    (noise terms included, whose e factors are never shifted)."""
    n = len(structure)
    t = raw_theta(structure, np.zeros(n), offsets)
    A = np.column_stack([raw_theta(structure, e, offsets, level=False) for e in np.eye(n)])
    return A, t


def least_squares(structure: Structure, records: Record | list[Record], start: int,
                  gain: float = 1.0) -> tuple[np.ndarray, float]:
    """θ and residual sum of squares of ``structure`` fitted by least squares on ``records``, the RSS floored at
    its round-off (:func:`~graybox.selection._subset_search.rss_floor`, times ``gain``: :func:`round_off_gain` for
    centred signals), as FROLS floors its own.

    Rows start at sample ``start`` of each record (the search's: the candidates' largest lag, at least the
    structure's) and never straddle two records (:func:`~graybox.stacked_regressors`); the columns are scaled to
    unit RMS for the solve.
    """
    X, y = stacked_regressors(structure, records, start=start)
    scale = column_scales(X)
    theta = np.linalg.lstsq(X / scale, y, rcond=None)[0] / scale
    r = y - X @ theta
    return theta, max(float(r @ r), rss_floor(float(y @ y), y.size, theta * scale, gain))


def round_off_zeroed(structure: Structure, theta: np.ndarray, records: Record | list[Record],
                     start: int) -> np.ndarray:
    """``theta`` (raw signals, :func:`raw_theta`) with 0 for each term whose part of the output is within the
    round-off of evaluating the model: |θ_j| rms(x_j) at most n eps Σ_i |θ_i| rms(x_i), x the raw columns from sample
    ``start`` on, n the terms. Such a θ is cancellation or the fit's round-off, not signal (a closure's divisor
    whose raw parameter is truly 0 came out 7e-18, a term the search took at round-off 1.8e-16); in units where y
    is 1e-300 times smaller it is no float (θ 1e-317, refused as beyond the float range where y × 1 was not). A
    ratio of like quantities: the same terms are zero in any units."""
    theta = np.asarray(theta, dtype=float)
    X, _ = stacked_regressors(structure, records, start=start)
    part = np.abs(theta) * column_scales(X)
    return np.where(part <= len(structure) * np.finfo(float).eps * np.sum(part), 0.0, theta)


def stop_note(stop: str, chosen: int, closed: int, offsets: Mapping[str, float],
              dropped: Sequence[tuple[Term, str]] = ()) -> str:
    """A centred search's ``stop``: the search's own, what it chose on which centred signals, and the closure
    (less the terms the data cannot tell apart, :func:`told_apart`)."""
    signals = ", ".join(f"{s} − {c:.6g}" if c >= 0 else f"{s} + {-c:.6g}" for s, c in offsets.items())
    note = f"{stop}; {chosen} terms chosen on centred signals ({signals}), closed under shifts: {closed} terms"
    if dropped:
        note += (f", {closed - len(dropped)} without " + ", ".join(str(t) for t, _ in dropped)
                 + " (the data cannot tell them from their divisors)")
    return note


# |mean| / std above which a signal is said to sit far from zero. At a ratio r the part of x² that the constant and x
# leave unexplained carries about r⁻⁴ of its energy (1e-8 at r = 100), within three decades of the Gram form's
# dependence threshold (1e-11) and of what round-off in sums of r²-sized products can resolve; products of lagged
# copies fare alike. Below it, offsets are an unlikely cause of a search running out of independent terms.
_FAR_FROM_ZERO = 100.0


def offset_note(data: object, process: Structure, rank_tol: float) -> str:
    """For an uncentred search that ran out of independent terms: a sentence naming the signals (y and the inputs
    ``process`` uses) whose mean over ``data`` exceeds :data:`_FAR_FROM_ZERO` times their spread (none held at one
    level: :func:`is_held`), and pointing to ``centre=True``; ``""`` when none does, when the candidates on the
    centred signals are no more independent than on the raw ones (a two-level input's u² is affine in u about any
    zero: centre=True runs out alike, the search's ``rank_tol`` judging both), or for Dask records, which centre=True
    does not take."""
    if is_dask_data(data):
        return ""
    signals = {n: x for n, x in pooled_signals(data).items() if n == "y" or n in process.input_names}
    far = []
    with np.errstate(invalid="ignore", over="ignore"):
        for name, x in signals.items():
            mean, spread = float(np.mean(x)), float(np.std(x))
            # a held signal is no offset: centred it is zero, which centre=True cannot select on either
            if np.isfinite(mean) and np.isfinite(spread) and abs(mean) > _FAR_FROM_ZERO * spread and not is_held(x):
                far.append(f"{name} (mean {mean:.4g}, spread {spread:.3g})")
    if not far or (_independent(process, centred_data(data, signal_offsets(data)), rank_tol)
                   <= _independent(process, data, rank_tol)):
        return ""
    return ("the signals sit far from zero against their spread: " + ", ".join(far) + "; their raw monomials are "
            "nearly collinear with one another and the constant, and centre=True selects on them about their means")


def _independent(process: Structure, data: object, rank_tol: float) -> int:
    """How many of the candidates' columns on ``data`` are independent: singular values of the columns at unit RMS
    above ``rank_tol`` of the largest (the searches' threshold on a column's orthogonalised share of its norm)."""
    X, _ = stacked_regressors(process, as_records(data))
    with np.errstate(all="ignore"):
        s = np.linalg.svd(X / column_scales(X), compute_uv=False)
    return int(np.sum(s > rank_tol * s[0])) if s.size and np.all(np.isfinite(s)) else 0
