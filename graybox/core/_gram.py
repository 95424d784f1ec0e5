"""The Gram (covariance) form of a regression: ΨᵀΨ, Ψᵀy and yᵀy accumulated over chunks.

Everything an orthogonal-least-squares selection (:func:`graybox.frols`, method ``"gram"``) or a
least-squares / PE closed form needs from the dynamic data is the augmented Gram matrix
``[Ψ, y]ᵀ[Ψ, y]`` and the row count. It is a sum over regression rows, so it is built one chunk
of rows at a time: the cost is one pass over the data and the memory does not grow with the
record length N (one chunk of the candidate matrix plus a few (n+1)² matrices).

* Rows never straddle records: each record contributes its own rows ``k = start … N_r − 1``.
* Chunk sums are combined pairwise (a binary counter of partial sums), so the rounding error of
  the accumulation grows with log(number of chunks), not with it.
* No centring: the constant term is a candidate like any other, and ERR is defined on the
  uncentred energy yᵀy.
* Records held as Dask arrays (:class:`DaskRecord`) are reduced block by block on whatever
  scheduler is active (e.g. a ``distributed`` cluster): each block carries the ``start`` samples
  before it so its rows see their lags, and the per-block Gram matrices are summed in a tree.
  Dask is imported only when such a record is given.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ._records import as_records, check_one_period, check_units, check_units_agree, require_lengths
from ._regressors import check_record_inputs, input_signals
from ._terms import Term
from ._reprs import short_repr
from ._validation import check_real, check_str

__all__ = ["DaskRecord", "GramSums", "gram_sums", "r_factor", "triangular_factor", "available_memory", "require_memory", "is_dask_data"]

# Entries of one chunk of the candidate matrix (16 MiB of float64): large enough that the
# chunk's AᵀA runs at BLAS-3 speed, small enough to stay in a few MiB of cache-friendly memory.
_CHUNK_ENTRIES = 1 << 21


def available_memory() -> int:
    """Bytes the system can give this process now: MemAvailable, else the physical memory."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return int(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover - exotic platforms
        return 1 << 62


def _gib(nbytes: float) -> str:
    return f"{nbytes / 2**30:.2f} GiB" if nbytes >= 2**28 else f"{nbytes / 2**20:.1f} MiB"


def require_memory(nbytes: int, what: str, *, hint: str = "") -> None:
    """Raise ``MemoryError`` naming the bytes needed and available if ``nbytes`` will not fit."""
    avail = available_memory()
    if nbytes > avail:
        raise MemoryError(
            f"{what} needs {_gib(nbytes)} ({nbytes} bytes) but only {_gib(avail)} ({avail} bytes) are available"
            + (f"; {hint}" if hint else "")
        )


# --------------------------------------------------------------------------------------------
# records held as Dask arrays
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class DaskRecord:
    """A dynamic experiment whose ``u`` and ``y`` are Dask arrays (possibly larger than memory).

    Accepted by :func:`graybox.frols` and by the PE/CLS estimators' dynamic data
    (:func:`graybox.pe_thetas`); they reduce it to its Gram matrix block by block on the active
    Dask scheduler (e.g. a ``distributed`` cluster) and never hold the whole record. Nothing is
    computed at construction.

    Parameters
    ----------
    u, y : dask.array.Array, shape (N,)
        Input and output samples (engineering units). ``y`` is rechunked to ``u``'s blocks.
    Ts : float
        Sampling period, seconds (> 0).
    name : str
        A label used in messages (default ``"record"``, as :class:`~graybox.Record`'s).
    units : (str, str), optional
        Units of (u, y), as :class:`~graybox.Record`'s: the models fitted on it carry them.
    """

    u: Any
    y: Any
    Ts: float = 1.0
    name: str = "record"  # as a Record's: messages said "'' is sampled every 1 s but '' every 2 s"
    units: tuple[str | tuple[str, ...], str] = ("", "")

    def __post_init__(self) -> None:
        check_str(self.name, "DaskRecord: name")
        object.__setattr__(self, "units", check_units(self.units, "DaskRecord", 1))  # one input
        try:
            import dask.array as da
        except ImportError as exc:  # pragma: no cover - dask is optional
            raise ImportError("DaskRecord needs dask: pip install 'dask[array]'") from exc
        for nm in ("u", "y"):
            a = getattr(self, nm)
            # a wrong type (an array in memory, complex samples) is a TypeError, as a Record's
            if not isinstance(a, da.Array):
                raise TypeError(f"DaskRecord.{nm} must be a dask array, got {type(a).__name__}: wrap it, e.g. "
                                "dask.array.from_array(x, chunks=100_000), or give samples in memory as a Record")
            if nm == "u" and a.ndim == 2 and a.shape[1] == 1:  # one input as a column, as a Record takes it
                a = a[:, 0]
                object.__setattr__(self, "u", a)
            if a.ndim != 1:
                one = " (a DaskRecord holds one input: several are a Record of shape (N, m))" if nm == "u" else ""
                raise ValueError(f"DaskRecord.{nm} must be 1-D, got shape {a.shape}{one}")
            if not np.issubdtype(a.dtype, np.number) or np.issubdtype(a.dtype, np.complexfloating):
                raise TypeError(f"DaskRecord.{nm} must hold real numbers, got dtype {a.dtype}")
        if self.u.shape[0] != self.y.shape[0] or np.isnan(self.u.shape[0]):
            raise ValueError(f"DaskRecord: u and y must have the same known length, got {self.u.shape[0]} and "
                             f"{self.y.shape[0]}")
        object.__setattr__(self, "Ts", check_real(self.Ts, "Ts", low=0, low_open=True))  # seconds
        # astype and rechunk hand back the caller's own array objects where nothing changes, and dask assigns items
        # in place (``u[0] = nan`` rewrites the array's graph): the record held the caller's later edits and took its
        # own. Its arrays are new objects over the same graph (nothing computed) that refuse item assignment
        u = _read_only(self.u.astype(float))
        object.__setattr__(self, "u", u)
        object.__setattr__(self, "y", _read_only(self.y.astype(float).rechunk(u.chunks)))

    def __len__(self) -> int:
        return int(self.u.shape[0])

    @property
    def input_names(self) -> tuple[str, ...]:
        """The input's name as terms use it (one input: ``"u"``)."""
        return ("u",)

    @property
    def n_inputs(self) -> int:
        """m, the number of inputs (a DaskRecord holds one)."""
        return 1

    def require_length(self, max_lag: int) -> None:
        """Raise ``ValueError`` unless the record has more than ``max_lag`` samples.

        Parameters
        ----------
        max_lag : int
            A structure's largest lag (samples).
        """
        if len(self) < max_lag + 1:
            raise ValueError(f"record {self.name!r} has {len(self)} samples, fewer than max lag + 1 = {max_lag + 1}")

    def __repr__(self) -> str:
        return f"DaskRecord({self.name!r}: {len(self)} samples in {len(self.u.chunks[0])} blocks, Ts = {self.Ts:g} s)"


@functools.lru_cache(maxsize=None)
def _read_only_array_type() -> type:
    """A dask.array.Array whose item assignment raises (made once, when a DaskRecord first needs it)."""
    import dask.array as da

    class ReadOnlyDaskArray(da.Array):
        __slots__ = ()

        def __setitem__(self, key: object, value: object) -> None:
            raise TypeError("a DaskRecord's samples are read-only: make a new DaskRecord of the changed arrays "
                            "(e.g. da.where(...))")

        # dask.array.Array rebuilds a plain (writable) Array when pickled or deep-copied: a record sent to a worker
        # process or copy.deepcopy(record) took item assignment again
        def __reduce__(self) -> tuple:
            return _read_only, (da.Array(self.dask, self.name, self.chunks, meta=self._meta),)

        def __deepcopy__(self, memo: dict) -> "ReadOnlyDaskArray":
            return self

    return ReadOnlyDaskArray


def _read_only(a: Any) -> Any:
    """A new read-only Dask array object over ``a``'s graph (the caller's ``a`` is not aliased)."""
    return _read_only_array_type()(a.dask, a.name, a.chunks, meta=a._meta)


def is_dask_data(data: object) -> bool:
    """True for a DaskRecord or a non-empty sequence of them."""
    if isinstance(data, DaskRecord):
        return True
    if isinstance(data, (list, tuple)) and data and all(isinstance(r, DaskRecord) for r in data):
        return True
    return False


# --------------------------------------------------------------------------------------------
# the chunked candidate builder
# --------------------------------------------------------------------------------------------
def term_factors(terms: Sequence[Term]) -> list[tuple[tuple[str, int], ...]]:
    """Each term as its multiset of lagged signals, e.g. u(k-1)²y(k-2) -> (("u",1),("u",1),("y",2))."""
    return [tuple((s, lag) for s, lag, p in t.factors for _ in range(p)) for t in terms]


def fill_columns(out: np.ndarray, factors: Sequence[tuple], sig: dict[str, np.ndarray], k0: int, k1: int) -> None:
    """Write the candidate columns at samples ``k0 … k1−1`` of one record into ``out`` (k1−k0, n).

    Each monomial is one multiply of a lower-degree monomial by a lagged signal, written straight
    into its column; only the proper prefixes other monomials need are kept, in a dict local to
    this call (no closure refers to it), so they are freed on return.
    """
    needed = {vars_[:m] for vars_ in factors for m in range(1, len(vars_))}
    memo: dict[tuple, np.ndarray] = {}

    def prefix(key: tuple) -> np.ndarray | None:
        # iterative: build the shortest missing prefix first
        if not key:
            return None
        m = len(key)
        while m > 1 and key[: m - 1] not in memo:
            m -= 1
        for i in range(m, len(key) + 1):
            s, lag = key[i - 1]
            x = sig[s][k0 - lag : k1 - lag]
            base = memo.get(key[: i - 1])
            memo[key[:i]] = x.copy() if base is None else base * x
        return memo[key]

    for j, vars_ in enumerate(factors):
        col = out[:, j]
        if not vars_:
            col[...] = 1.0
            continue
        s, lag = vars_[-1]
        x = sig[s][k0 - lag : k1 - lag]
        head = vars_[:-1]
        if not head:
            col[...] = x
            continue
        base = memo[head] if head in memo else prefix(head)
        np.multiply(base, x, out=col)
        if vars_ in needed and vars_ not in memo:
            memo[vars_] = col.copy()


def chunk_rows(n_columns: int) -> int:
    """Rows of one chunk for ``n_columns`` columns."""
    return max(256, _CHUNK_ENTRIES // max(1, n_columns))


def chunk_bytes(n_columns: int) -> int:
    """Peak working memory of the chunked builder for ``n_columns`` columns (chunk, prefixes, sums)."""
    rows = chunk_rows(n_columns)
    return 8 * (3 * rows * (n_columns + 1) + 64 * (n_columns + 1) ** 2)


def _r_combine(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """R factor of [a; b] for two triangular factors (the TSQR reduction step)."""
    return np.linalg.qr(np.vstack([a, b]), mode="r")


class _Pairwise:
    """Reduce many equally shaped arrays with ``combine``, pairwise (error ~ log of their count)."""

    def __init__(self, combine=np.add) -> None:
        self._combine = combine
        self._stack: list[tuple[int, np.ndarray]] = []

    def add(self, a: np.ndarray) -> None:
        level = 0
        while self._stack and self._stack[-1][0] == level:
            _, b = self._stack.pop()
            a = self._combine(b, a)
            level += 1
        self._stack.append((level, a))

    def total(self) -> np.ndarray | None:
        if not self._stack:
            return None
        out = self._stack[0][1]
        for _, b in self._stack[1:]:
            out = self._combine(out, b)
        return out


def _block_reduce(factors: Sequence[tuple], u: np.ndarray, y: np.ndarray, start: int, form: str,
                  input_names: tuple[str, ...] = ("u",)) -> np.ndarray:
    """[Ψ, y]ᵀ[Ψ, y] (form "gram") or the R factor of [Ψ, y] (form "qr") of the rows
    ``k = start … len(u)−1`` of one stretch of samples (u of shape (N,) or (N, m), its inputs
    named ``input_names``), shape (n+1, n+1)."""
    n = len(factors)
    sig = input_signals(np.asarray(u, float), input_names)
    sig["y"] = np.asarray(y, float)
    N = sig["y"].shape[0]
    acc = _Pairwise(np.add if form == "gram" else _r_combine)
    step = chunk_rows(n + 1)
    A = np.empty((min(step, max(N - start, 0)), n + 1), order="F")
    # a non-finite sum is refused after the reduction, naming its cause (a Dask record's NaN or inf, read here first;
    # an overflow of a high power): numpy's RuntimeWarnings before that error said nothing of either
    with np.errstate(over="ignore", invalid="ignore"):
        for k0 in range(start, N, step):
            k1 = min(k0 + step, N)
            Ak = A[: k1 - k0]
            fill_columns(Ak, factors, sig, k0, k1)
            Ak[:, n] = sig["y"][k0:k1]
            acc.add(Ak.T @ Ak if form == "gram" else np.linalg.qr(Ak, mode="r"))
    tot = acc.total()
    if tot is None:
        return np.zeros((n + 1, n + 1))
    if form == "qr" and tot.shape[0] < n + 1:  # fewer rows than columns: pad the factor
        tot = np.vstack([tot, np.zeros((n + 1 - tot.shape[0], n + 1))])
    return tot


@dataclass(frozen=True, eq=False)
class GramSums:
    """The Gram form of a regression over some records.

    Attributes
    ----------
    G : ndarray, shape (n, n)
        ΨᵀΨ (engineering units; symmetric).
    b : ndarray, shape (n,)
        Ψᵀy.
    yy : float
        yᵀy.
    N : int
        Regression rows (summed over records).
    """

    G: np.ndarray
    b: np.ndarray
    yy: float
    N: int

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape


def gram_sums(terms: Sequence[Term], data: object, start: int) -> GramSums:
    """ΨᵀΨ, Ψᵀy, yᵀy over the rows ``k ≥ start`` of every record, in one chunked pass.

    Parameters
    ----------
    terms : sequence of Term
        Process terms (columns of Ψ): inputs (by the records' input names) and ``y``.
    data : Record, sequence of Record, Dataset, DaskRecord or sequence of DaskRecord
    start : int
        First regression sample of each record (≥ the terms' largest lag).

    Returns
    -------
    GramSums

    Raises
    ------
    ValueError
        A record shorter than ``start + 1``; non-finite sums (overflow of a high power), naming
        the columns.
    """
    factors = term_factors(terms)
    n = len(factors)
    Ga, N = _reduce(factors, data, start, "gram")
    if not np.all(np.isfinite(Ga)):
        bad = np.flatnonzero(~np.isfinite(np.diag(Ga)[:n]))
        names = ", ".join(str(terms[j]) for j in bad[:5]) or "products of columns"
        raise ValueError(f"candidate columns overflow to non-finite values (e.g. {names})")
    Ga = 0.5 * (Ga + Ga.T)
    return GramSums(Ga[:n, :n], Ga[:n, n].copy(), float(Ga[n, n]), int(N))


def r_factor(terms: Sequence[Term], data: object, start: int) -> tuple[np.ndarray, int]:
    """Upper-triangular R of [Ψ, y] = Q R (Q never formed) by TSQR over chunks, and the row count.

    As accurate as one Householder QR of the stacked matrix (no squaring of the conditioning as
    in the Gram form); used where a few dozen columns make the n² per row affordable.

    Returns
    -------
    R : ndarray, shape (n+1, n+1)
    N : int
    """
    R, N = _reduce(term_factors(terms), data, start, "qr")
    if not np.all(np.isfinite(R)):
        raise ValueError("non-finite regressors (overflow of a high power of u or y?)")
    return R, N


def triangular_factor(columns: np.ndarray, y: np.ndarray, scale: np.ndarray | None = None) -> np.ndarray:
    """R of [S, y] = Q R by one Householder QR (Q never formed), S = ``columns`` / ``scale``: the factor
    :func:`r_factor` gives by TSQR, for columns in memory, shape (n+1, n+1) (rows past N are zero).

    [S, y] is written once into a Fortran-ordered array that the QR overwrites: the peak is the columns and
    that one copy (no scaled copy beside them)."""
    from scipy.linalg import qr

    n1 = columns.shape[1] + 1
    A = np.empty((y.size, n1), order="F")
    if scale is None:
        A[:, :-1] = columns
    else:
        np.divide(columns, scale, out=A[:, :-1])
    A[:, -1] = y
    Rf = qr(A, mode="r", overwrite_a=True, check_finite=False)[0]
    R = np.zeros((n1, n1))
    R[: min(Rf.shape[0], n1)] = Rf[:n1]
    return R


def _reduce(factors: Sequence[tuple], data: object, start: int, form: str) -> tuple[np.ndarray, int]:
    """[Ψ, y]'s Gram matrix summed (``form="gram"``) or its R factor by TSQR (``"qr"``) over the
    records, in memory or on Dask, pairwise; and the number of rows."""
    # the inputs the terms use, by name: a record without one is refused naming it, before any block is read
    inputs = list(dict.fromkeys(s for f in factors for s, _ in f if s != "y"))
    if is_dask_data(data):
        recs = [data] if isinstance(data, DaskRecord) else list(data)
        require_lengths(recs, start)
        check_record_inputs(inputs, recs)
        M = _dask_reduce(factors, recs, start, form)
        if not np.all(np.isfinite(M)):
            # a Dask record's samples are first read here: a NaN among them is the data's, said as a Record says it,
            # not an overflow of the candidates (a second pass, on this error's path only)
            _refuse_non_finite_samples(recs)
    else:
        recs = as_records(data)
        acc = _Pairwise(np.add if form == "gram" else _r_combine)
        require_lengths(recs, start)
        check_record_inputs(inputs, recs)
        for r in recs:
            acc.add(_block_reduce(factors, r.u, r.y, start, form, r.input_names))
        M = acc.total()
    return M, int(sum(len(r) - start for r in recs))


def _refuse_non_finite_samples(recs: list[DaskRecord]) -> None:
    """``ValueError`` naming the first non-finite sample of u or y of the first Dask record that has one, as
    :class:`~graybox.Record` refuses it at construction (a DaskRecord's samples are not read then)."""
    import dask
    import dask.array as da

    counts = []
    for r in recs:
        for a in (r.u, r.y):
            bad = ~da.isfinite(a)
            counts += [bad.sum(), da.argmax(bad)]
    found = dask.compute(*counts)
    for i, r in enumerate(recs):
        for j, nm in enumerate(("u", "y")):
            n, first = (int(v) for v in found[4 * i + 2 * j: 4 * i + 2 * j + 2])
            if n:
                raise ValueError(f"{r.name or f'DaskRecord {i}'}: {nm} has {n} non-finite value(s) (NaN or inf), "
                                 f"first at index {first}")


def _dask_reduce(factors: Sequence[tuple], recs: list[DaskRecord], start: int, form: str) -> np.ndarray:
    """Per-block Gram matrices (summed) or R factors (TSQR) of Dask records, reduced in a tree on
    the active scheduler."""
    import dask

    parts = []
    for r in recs:
        bounds = np.cumsum((0,) + tuple(r.u.chunks[0]))
        for a, b in zip(bounds[:-1], bounds[1:]):
            k0 = max(int(a), start)  # rows k0 … b−1 belong to this block; they need samples from k0 − start
            if k0 >= b:
                continue
            lo = k0 - start
            parts.append(dask.delayed(_checked_block_reduce)(factors, r.u[lo:b], r.y[lo:b], start, form))
    combine = np.add if form == "gram" else _r_combine
    while len(parts) > 1:
        parts = [dask.delayed(combine)(parts[i], parts[i + 1]) if i + 1 < len(parts) else parts[i]
                 for i in range(0, len(parts), 2)]
    (total,) = dask.compute(parts[0])
    return np.asarray(total, float)


def _checked_block_reduce(factors: Sequence[tuple], u: np.ndarray, y: np.ndarray, start: int,
                          form: str) -> np.ndarray:
    """:func:`_block_reduce` of one Dask block's stretch, NaN throughout where any of its samples is not finite.

    The stretches cover every sample, so a NaN among samples no row reads (u's last, one before a term's smallest
    lag), taken silently before, makes the sum non-finite and :func:`_reduce` refuses it naming the sample, as a
    Record refuses its own at construction. Checked here, in the task that reads the block: a separate
    ``da.isfinite`` in the same ``dask.compute`` is optimised apart from the delayed reduction and read every
    block once more."""
    M = _block_reduce(factors, u, y, start, form)
    if not (np.all(np.isfinite(u)) and np.all(np.isfinite(y))):
        M = np.full(M.shape, np.nan)
    return M


def dask_input_range(data: object) -> np.ndarray:
    """(min, max) of u over Dask records, computed on the scheduler (for static-range warnings)."""
    import dask
    import dask.array as da

    recs = [data] if isinstance(data, DaskRecord) else list(data)
    lo, hi = dask.compute(da.stack([r.u.min() for r in recs]).min(), da.stack([r.u.max() for r in recs]).max())
    return np.array([float(lo), float(hi)])


def as_gram_records(data: object) -> list:
    """Records as a list (in-memory or Dask), for code that only needs lengths."""
    if is_dask_data(data):
        recs = [data] if isinstance(data, DaskRecord) else list(data)
        check_one_period(recs, "data")
        check_units_agree(recs, "the records of one fit must be in the same units (convert one of them)")
        return recs
    return as_records(data)  # a Dataset: its ident, in the units the Dataset names
