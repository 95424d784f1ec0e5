"""Least squares with internal column scaling.

Polynomial regressors in engineering units span many decades (u ≈ 1e3 rpm, u³ ≈ 1e9),
so every least-squares path in graybox scales columns to unit RMS, solves, and maps the
solution back: results do not depend on the units the user chose.
"""

from __future__ import annotations

import math
from contextlib import AbstractContextManager
from dataclasses import replace
from typing import TYPE_CHECKING, Mapping, Sequence

import numpy as np
from threadpoolctl import ThreadpoolController

from ._gram import as_gram_records, is_dask_data
from ._terms import Structure, Term

if TYPE_CHECKING:
    from ._records import Record, StaticPoints

__all__ = ["column_scales", "scaled_lstsq", "thread_pools", "one_blas_thread", "check_rows", "free_directions",
           "regular_by_bounds", "check_identified", "rank_tolerance", "HELD_OUTPUT", "CONSTANT_RTOL", "output_spread",
           "output_scale", "spread_scale", "beyond_float_range", "refuse_beyond_float_range", "refuse_parameter_scales",
           "binary_scaled", "scaled_records", "scaled_theta", "scaled_points", "unscaled_theta", "unscaled_rss",
           "unscaled_levels", "scaled_norm", "scaled_norms", "mean_square", "binary_exponent"]

_CONTROLLER: list[ThreadpoolController] = []


def thread_pools() -> ThreadpoolController:
    """This process's BLAS/OpenMP thread pools, found once: building a controller scans the loaded
    libraries (``threadpool_limits`` does on every call, which costs as much as a short fit);
    limiting with it is cheap."""
    if not _CONTROLLER:
        _CONTROLLER.append(ThreadpoolController())
    return _CONTROLLER[0]


def one_blas_thread() -> AbstractContextManager:
    """A context in which BLAS runs on one thread: the fits make thousands of small BLAS calls, where
    a multi-threaded BLAS only adds synchronisation (30× slower on a loaded 2-core machine)."""
    return thread_pools().limit(limits=1, user_api="blas")


def check_rows(rows: int, n: int, what: str = "") -> None:
    """``ValueError`` unless there are more regression rows than parameters (every estimator's one rule:
    with as many rows as parameters least squares interpolates, and no error is left to fit or judge)."""
    if rows <= n:
        raise ValueError(f"{what}{rows} regression rows for {n} parameters: the data are too short")


#: The smallest RMS whose mean square is a normal float (below it the squares lose their bits).
_SQRT_TINY = float(np.sqrt(np.finfo(float).tiny))


def column_scales(A: np.ndarray) -> np.ndarray:
    """RMS of each column of ``A`` (1 for an all-zero column), shape (n,)."""
    A = np.asarray(A, dtype=float)
    with np.errstate(over="ignore", under="ignore"):
        s = np.sqrt(np.mean(A**2, axis=0))
    # squaring a large finite column (y(k-1)^2 ~ 1e300) overflowed to an inf scale (a tiny one underflowed to 0, or
    # to a subnormal mean square of a few bits): such columns' RMS is taken through their largest |value| (the others
    # as before, to the bit)
    # (only the columns so flagged are read again: np.any and np.all over the whole of A cost up to 10× the RMS)
    far = np.flatnonzero(~np.isfinite(s) | (s < _SQRT_TINY))
    if far.size:
        B = A[:, far]
        keep = np.all(np.isfinite(B), axis=0) & np.any(B, axis=0)  # not a NaN's or an all-zero column
        far, B = far[keep], B[:, keep]
        # over the power of two above the largest |value| (exact), and reduced over A's own shape (numpy sums a lone
        # column in another order): the RMS of a column times 2^k is 2^k times its RMS to the bit, as the plain RMS
        # is where it stays in range (over m itself, and as a lone column, it was rounded otherwise)
        e = np.zeros(A.shape[1], dtype=int)
        e[far] = binary_exponent(np.max(np.abs(B), axis=0))
        with np.errstate(over="ignore", under="ignore"):  # the other columns' squares are not read
            ms = np.mean(np.ldexp(A, -e) ** 2, axis=0)
        s = np.array(s, dtype=float, ndmin=1)
        s[far] = np.ldexp(np.sqrt(ms[far]), e[far])
    return np.where(s > 0, s, 1.0)


#: A measured output whose spread ‖y − mean(y)‖ is at most this fraction of ‖y‖ is constant: what is left
#: is the mean's own round-off (a level of 0.8 held for 39 samples leaves 1e-16), not a signal.
CONSTANT_RTOL = 1e-13


def binary_exponent(m: float | np.ndarray) -> int | np.ndarray:
    """The exponent e of the power of two above ``m`` (m = f 2^e, 0.5 <= f < 1; exact), elementwise, 0 where m is 0,
    inf or NaN: x over 2^e, e of m = max|x|, keeps every square of x in the float range."""
    m = np.asarray(m, float)
    e = np.where((m > 0) & np.isfinite(m), np.frexp(m)[1], 0)
    return int(e) if e.ndim == 0 else e


def scaled_norm(x: np.ndarray) -> float:
    """‖x‖ (Euclidean) of a 1-D array, computed on x over the power of two above max|x| so that no square leaves the
    float range: numpy's norm of values near 1e200 was inf (with an overflow warning) and of values near 1e-200 was 0
    (the squares underflowed), 1e-160 a few digits off. inf where x holds an inf or its norm is beyond the float
    range."""
    x = np.asarray(x, float)
    m = float(np.max(np.abs(x), initial=0.0))
    if not 0.0 < m < np.inf:
        return m  # 0 (or empty), inf, or NaN
    e = int(np.frexp(m)[1])  # by a power of two, exact: in range, the very norm numpy takes of x (Table I's pins)
    with np.errstate(over="ignore"):
        return float(np.ldexp(np.linalg.norm(np.ldexp(x, -e)), e))


def scaled_norms(A: np.ndarray, axis: int) -> np.ndarray:
    """The Euclidean norms of A's columns (``axis=0``) or rows (``axis=1``), each computed as :func:`scaled_norm` over
    the power of two above its largest |entry| (exact): rows of a static constraint in an output near 1e155 overflowed
    in numpy's norm (their squares), near 1e-170 underflowed to 0 (a row read as no condition at all)."""
    A = np.asarray(A, float)
    e = binary_exponent(np.max(np.abs(A), axis=axis, keepdims=True, initial=0.0))
    with np.errstate(over="ignore"):
        return np.ldexp(np.linalg.norm(np.ldexp(A, -e), axis=axis), np.squeeze(e, axis=axis))


def mean_square(x: np.ndarray, axis: int = -1) -> np.ndarray:
    """mean(x²) along ``axis`` (units²), each computed over the power of two above its largest |x| and mapped back
    (exact): inf or 0 only where the mean square itself leaves the float range, as y² there (errors about 1e160 warned
    'overflow encountered in square', an error under warnings-as-errors)."""
    x = np.asarray(x, float)
    e = binary_exponent(np.max(np.abs(x), axis=axis, keepdims=True, initial=0.0))
    with np.errstate(over="ignore", under="ignore"):
        return np.ldexp(np.mean(np.ldexp(x, -e) ** 2, axis=axis), 2 * np.squeeze(e, axis=axis))


def output_spread(y: np.ndarray) -> float:
    """‖y − mean(y)‖ of a measured output (output units), 0.0 where it is constant to round-off
    (:data:`CONSTANT_RTOL`): the denominator of RRSE and fit %, undefined for a held output."""
    y = np.asarray(y, float)
    if y.size == 0:  # no samples: no spread (and no mean of an empty slice)
        return 0.0
    # in a scale of the output's own (an output near 1e200 was 'constant', its norms inf; near 1e-200 their squares
    # were 0): the same spread in any units
    # read over the power of two above max|y| (exact), mapped back: near the float range's end y's sum (its mean)
    # and ‖y‖ were inf, and ±1e308 'constant'
    e = binary_exponent(float(np.max(np.abs(y))))
    y = np.ldexp(y, -e)
    den = scaled_norm(y - y.mean())
    with np.errstate(over="ignore"):  # a spread beyond the float range: inf, as the norm's
        return 0.0 if den <= CONSTANT_RTOL * scaled_norm(y) else float(np.ldexp(den, e))


def spread_scale(std: float, rms: float) -> float:
    """:func:`output_scale` from the output's standard deviation and RMS (for data reduced elsewhere)."""
    if np.isfinite(std) and std > CONSTANT_RTOL * rms:
        return float(std)
    return float(rms) if np.isfinite(rms) and rms > 0 else 1.0


def output_scale(y: np.ndarray) -> float:
    """The output's scale for a solver or a tolerance, output units: its spread about its mean, RMS(y − mean y).

    Not RMS(y): that counts the offset, so an output of 2e9 ± 50 (a pressure in Pa) made every step the
    solvers take a relative 1e-8 of their variable, at their tolerances. The floor is units-free too:
    an output constant to round-off (:data:`CONSTANT_RTOL`) has its RMS as its scale, one identically 0
    has 1 (0 in any units).
    """
    y = np.asarray(y, float).ravel()
    if y.size == 0:
        return 1.0
    # on y over the power of two above max|y| (exact), mapped back: y² of an output near 1e155 overflowed (the scale
    # fell to 1, and a QP's step in output units reached 1e155) and near 1e-170 underflowed
    e = binary_exponent(np.max(np.abs(y)))
    e = e if 2 * abs(e) > _SAFE_EXPONENT else 0  # ordinary outputs as they are (no copy of a long y)
    x = np.ldexp(y, -e) if e else y
    std, rms = float(np.std(x)), float(np.sqrt(np.mean(x**2)))
    if np.isfinite(std) and std > CONSTANT_RTOL * rms:
        return math.ldexp(std, e)
    return math.ldexp(rms, e) if np.isfinite(rms) and rms > 0 else 1.0


def scaled_lstsq(A: np.ndarray, b: np.ndarray, rcond: float | None = None) -> np.ndarray:
    """argmin ‖A x − b‖₂ solved on unit-RMS columns, returned in the original units.

    Parameters
    ----------
    A : ndarray, shape (m, n)
    b : ndarray, shape (m,)

    Returns
    -------
    ndarray, shape (n,)

    Raises
    ------
    ValueError
        When A or b has non-finite values, the shapes disagree, A is rank deficient after
        scaling (the parameters are not identifiable from these data), or a parameter is beyond the float range.
    """
    A = np.asarray(A, dtype=float)
    b = np.asarray(b, dtype=float)
    if A.ndim != 2 or b.ndim != 1 or A.shape[0] != b.shape[0]:
        raise ValueError(f"shapes do not match for least squares: A {A.shape}, b {b.shape}")
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(b))):
        raise ValueError("least squares: non-finite values in the regressors or the target")
    s = column_scales(A)
    x, _, rank, _ = np.linalg.lstsq(A / s, b, rcond=rcond)
    if rank < A.shape[1]:
        raise ValueError(
            f"least squares: regressor matrix has rank {rank} < {A.shape[1]} columns "
            "(collinear or constant terms: the parameters are not identifiable from these data)"
        )
    with np.errstate(over="ignore"):  # a column of 1e-320 for a target of 1 has a θ of 1e320, not a float
        theta = x / s
    if not np.all(np.isfinite(theta)):
        raise beyond_float_range(f"column(s) {np.flatnonzero(~np.isfinite(theta)).tolist()}", "least squares: ")
    return theta


def beyond_float_range(which: str, prefix: str = "") -> ValueError:
    """The error of a fit whose parameters ``which`` (columns, terms) are beyond the float range: columns far too
    small beside the target in the signals' units (u(k-1)² of an input of 1e-160 is 1e-320, its θ 1e320), or far
    too large (an input of 1e153 beside an output of 1e-20: a θ of 1e-327, below the normal floats)."""
    return ValueError(f"{prefix}the parameter(s) of {which} are beyond the float range (those columns are too small "
                      "or too large beside the target in these units: rescale the signals)")


def refuse_beyond_float_range(terms: Sequence, *thetas: np.ndarray, prefix: str = "") -> None:
    """:func:`beyond_float_range` naming the terms whose θ is not finite in any of ``thetas`` (each aligned with
    ``terms``): a fit on scaled signals (:func:`binary_scaled`) whose θ is no float in the data's own units."""
    far = [str(t) for t, *vs in zip(terms, *thetas) if not all(np.isfinite(v) for v in vs)]
    if far:  # u(k-1)² of an input about 1e-160 is about 1e-320: its θ, about 1e320, is no float
        raise beyond_float_range(str(far), prefix)


def refuse_parameter_scales(terms: Sequence, y_scale: float, scales: np.ndarray, prefix: str = "") -> None:
    """:func:`beyond_float_range` naming the terms whose parameter's scale, the output's ``y_scale`` over the column's
    RMS ``scales``, is no normal float: above the range (a column of 1e-320 beside an output of 1) or below it (u(k-1)²
    of an input of 1e100 beside an output of 1e-150: a θ about 1e-351, which became 0 and dropped the term without a
    word)."""
    with np.errstate(over="ignore", under="ignore", divide="ignore"):
        r = float(y_scale) / np.asarray(scales, float)
    far = np.flatnonzero(~np.isfinite(r) | (r < np.finfo(float).tiny))
    if far.size:
        raise beyond_float_range(str([str(terms[j]) for j in far]), prefix)


def rank_tolerance(largest: float, rows: int, n: int = 0) -> float:
    """The one rank rule's threshold: a singular value at most this is zero, units-free.

    ``largest`` is the largest singular value of a regression (columns at unit RMS) standing for ``rows``
    regression rows of ``n`` parameters; the threshold is eps · max(rows, n) · largest, as
    ``numpy.linalg.lstsq`` (hence :func:`scaled_lstsq`) and :func:`free_directions` judge rank. The QP's
    basis and the covariances judge singularity with it too, so that what one path calls identified no
    other calls singular (a fixed ratio such as 1e-12 disagreed with it at every N but ~4500).
    """
    return float(largest) * np.finfo(float).eps * max(int(rows), int(n))


def regular_by_bounds(R: np.ndarray, ratio: float) -> np.ndarray:
    """Whether each square matrix of ``R`` (K, n, n) surely has σ_min > ``ratio`` · σ_max, the rank rule's test
    (:func:`rank_tolerance` at largest = 1), judged without an SVD: shape (K,) bool, False where unsure.

    σ_max <= ‖R‖_F and σ_min >= 1 / ‖R⁻¹‖_F, one batched inverse; a matrix is called regular only where these
    clear the rule by a factor 10, so that the inverse's rounding (about cond · eps, below 1/10 there) cannot turn
    the verdict. A False (near the threshold, singular, non-square, non-finite) is for the SVD to judge, as every
    matrix was judged before: the rule's verdicts are unchanged, its cost in the common case a fifth of the SVD's."""
    ok = np.zeros(R.shape[0], dtype=bool)
    if R.ndim != 3 or not R.shape[0] or R.shape[1] != R.shape[2] or not R.shape[1] or not np.all(np.isfinite(R)):
        return ok
    try:
        with np.errstate(all="ignore"):  # a near-singular R: an inverse of huge entries, its norm inf
            low = 1.0 / np.linalg.norm(np.linalg.inv(R), axis=(1, 2))
            return low > 10.0 * ratio * np.linalg.norm(R, axis=(1, 2))
    except np.linalg.LinAlgError:  # an exactly singular one (numpy inverts the batch or none)
        return ok


def _mean_square_stack(blocks: Sequence[tuple[np.ndarray, int]]) -> np.ndarray:
    """The blocks stacked, each as a mean square (A / √rows)."""
    return np.vstack([np.asarray(A, float) / np.sqrt(max(int(m), 1)) for A, m in blocks])


def free_directions(blocks: Sequence[tuple[np.ndarray, int]]) -> np.ndarray:
    """The directions of θ that the stacked regression of ``blocks`` leaves free, units-free.

    Each block is (A, rows): A (k, n) in θ's coordinates with AᵀA the Gram matrix of ``rows`` regression
    rows (A may be those rows or a triangular factor of them). Each block is taken as a mean square
    (A / √rows, so a block's weight does not depend on its length), the stack's columns are scaled to
    unit RMS (so the judgement does not depend on units), and its rank is judged as
    ``numpy.linalg.lstsq`` judges it (singular values ≤ eps · max(rows, n) · the largest): with one
    block this is exactly :func:`scaled_lstsq`'s rank test.

    Returns
    -------
    ndarray, shape (n, n − rank)
        An orthonormal basis of the free directions in the scaled coordinates (θ_j times the stack's
        column RMS c_j); no columns when the blocks identify θ.
    """
    A = _mean_square_stack(blocks)
    n = A.shape[1]
    A = A / column_scales(A)
    if not np.all(np.isfinite(A)):
        raise ValueError("non-finite regressors: identifiability cannot be judged")
    # the SVD of the stack's triangular factor (the same singular values and right vectors): the stack's own
    # SVD with full_matrices would form its N × N left factor, N the records' samples (290 MB at N = 6000)
    R = np.linalg.qr(A, mode="r") if A.shape[0] > n else A
    rows = sum(int(m) for _, m in blocks)
    if regular_by_bounds(R[None], rank_tolerance(1.0, rows, n))[0]:  # full rank, no SVD needed (the common case)
        return np.zeros((n, 0))
    _, sv, Vt = np.linalg.svd(R, full_matrices=True)
    tol = rank_tolerance(sv[0] if sv.size else 0.0, rows, n)
    rank = int(np.sum(sv > tol))
    return Vt[rank:].T


#: What is wrong when the free directions move no input term (the output's terms and the constant only): the
#: records' output, not their input, is what does not move (a record whose input moves does not help).
HELD_OUTPUT = ("the records' output does not move enough to tell these terms apart (e.g. a constant output: check that "
               "the column read as y is the plant's output, e.g. not a stuck or disconnected sensor); give a record "
               "whose output moves")

#: What data would identify the free directions: when rows fixing every static cluster would (static
#: points could), and when they would not (terms that differ within one cluster).
REMEDIES = ("give a record whose input moves, or static points at more input levels (with a weight on them: λ1 < 1)",
            "give a record whose input moves (static points fix only the static clusters, and these terms differ "
            "within one, e.g. one power of u at two lags)")


def check_identified(blocks: Sequence[tuple[str, np.ndarray, int]], terms: Sequence[object], *,
                     clusters: np.ndarray | None = None, what: str = "θ",
                     remedies: tuple[str, str] = REMEDIES) -> None:
    """The one identifiability rule: ``ValueError`` unless the stacked regression of ``blocks`` has full rank.

    Parameters
    ----------
    blocks : sequence of (str, ndarray (k, n), int)
        What each block is (e.g. ``"the identification records"``), its rows in θ's coordinates (or a
        triangular factor of them) and how many regression rows it stands for (:func:`free_directions`).
    terms : sequence of Term (or str)
        The n terms, to name those a free direction moves. Given as Terms, a free direction that moves
        no input term is named as the output's (:data:`HELD_OUTPUT`), whatever ``remedies`` say.
    clusters : ndarray, shape (n_clusters, n), optional
        The 0/1 map from θ to the static clusters: with it the message tells whether static points
        (which fix only the clusters) could identify what is left free.
    what : str
        What is estimated, for the message.
    remedies : (str, str)
        What to give when static points could identify the free directions, and when they could not
        (default :data:`REMEDIES`).

    Raises
    ------
    ValueError
        Naming the rank, the terms that the free directions move and what data would identify them.
    """
    free = free_directions([(A, m) for _, A, m in blocks])
    if not free.shape[1]:
        return
    n = len(terms)
    moved_at = [j for j in range(n) if np.max(np.abs(free[j])) > 1e-8]
    moved = [str(terms[j]) for j in moved_at]
    by = " and ".join(name for name, _, _ in blocks)
    msg = (f"{what} is not identifiable from {by}: their stacked regression has rank {n - free.shape[1]} for {n} "
           f"terms (judged with every column at unit RMS), and leaves free {free.shape[1]} combination(s) of {moved}")
    if moved_at and all(getattr(terms[j], "input_names", None) == () for j in moved_at):
        raise ValueError(f"{msg}: {HELD_OUTPUT}")
    static_helps = True
    if clusters is not None:
        # whether rows fixing every cluster would remove the free directions (units-free: R's columns are scaled
        # as the directions' are, each row to unit norm)
        c = column_scales(_mean_square_stack([(A, m) for _, A, m in blocks]))
        Rs = np.asarray(clusters, float) / c
        Rs = Rs[np.linalg.norm(Rs, axis=1) > 0]
        Rs = Rs / np.linalg.norm(Rs, axis=1, keepdims=True)
        static_helps = np.linalg.matrix_rank(Rs @ free, tol=1e-8) == free.shape[1]
    raise ValueError(f"{msg}: {remedies[0] if static_helps else remedies[1]}")


#: The data are scaled (:func:`binary_scaled`) when a candidate column's square, or y's, could reach 2^±this.
_SAFE_EXPONENT = 900


def binary_scaled(data: object, process: Structure) -> tuple[object, dict[str, int]]:
    """The in-memory records with y and each input times 2^-e, e the exponent that brings the signal's largest
    magnitude over the records into [0.5, 1), and those exponents by signal name (``"e"``, a noise term's, is y's);
    the data as they are, and {}, where no candidate column's square (nor y's) can come near the ends of the
    floating-point range (no copy of ordinary data), and for Dask records.

    A power of two is exact: every candidate column is the data's times a power of two, so once scaled to unit
    RMS the columns, ERR and the choice are those of the data themselves, bit for bit, while products of large
    signals (y ≈ 1e160, y²) or yᵀy of small ones (y ≈ 1e-200) no longer leave the floating-point range."""
    if is_dask_data(data):
        return data, {}
    records = as_gram_records(data)
    names = records[0].input_names
    us = [np.asarray(r.u, dtype=float).reshape(len(r.y), -1) for r in records]
    if any(u.shape[1] != len(names) for u in us):
        return data, {}  # records that do not agree: refused, in their own words, where they are read
    exps = {}
    for i, name in enumerate(("y",) + tuple(names)):
        top = max(float(np.max(np.abs(r.y if i == 0 else u[:, i - 1]), initial=0.0)) for r, u in zip(records, us))
        exps[name] = int(np.frexp(top)[1]) if np.isfinite(top) and top > 0 else 0
    exps["e"] = exps["y"]  # an MA part's noise is in the output's units (ELS's e(k-1)y(k-1))
    reach = max([abs(exps["y"])] + [sum(p * abs(exps.get(s, 0)) for s, _, p in t.factors) for t in process])
    if 2 * reach <= _SAFE_EXPONENT:
        return data, {}
    return scaled_records(records, exps), exps


def scaled_records(records: Sequence[Record], exps: Mapping[str, int]) -> list[Record]:
    """The records with y and each input times 2^-e, the exponents :func:`binary_scaled` chose (e.g. for choosing
    records, which take the fitting records' powers; an input the exponents do not name is kept, and refused in its
    own words where it is read)."""
    if not exps:
        return list(records)
    out = []
    for r in records:
        d = np.array([exps.get(n, 0) for n in r.input_names], dtype=int)
        out.append(replace(r, u=np.ldexp(r.u, -d[0] if r.u.ndim == 1 else -d), y=np.ldexp(r.y, -exps["y"])))
    return out


def unscaled_theta(theta: np.ndarray, terms: Sequence[Term], exps: Mapping[str, int]) -> np.ndarray:
    """θ on the data's own signals of a fit on the signals times 2^-e (:func:`binary_scaled`): inf where it leaves
    the float range above, NaN where a nonzero θ leaves it below (ldexp's 0 or few-bit subnormal would drop the term
    without a word); callers refuse both (:func:`beyond_float_range`)."""
    if not exps:
        return theta
    theta = np.asarray(theta, dtype=float)
    with np.errstate(over="ignore", under="ignore"):  # a θ beyond the range is refused by the caller, named
        out = np.ldexp(theta, np.array([exps["y"] - sum(p * exps.get(s, 0) for s, _, p in t.factors) for t in terms],
                                       dtype=int))
    return np.where((theta != 0) & (np.abs(out) < np.finfo(float).tiny), np.nan, out)


def scaled_theta(theta: np.ndarray, structure: Structure, exps: Mapping[str, int]) -> np.ndarray:
    """θ (rows) on the signals times 2^-e (:func:`binary_scaled`), the inverse of
    :func:`unscaled_theta`: each term's parameter times 2^(Σ p e_s − e_y)."""
    shift = np.array([sum(p * exps.get(s, 0) for s, _, p in t.factors) - exps["y"] for t in structure], dtype=int)
    with np.errstate(over="ignore", under="ignore"):
        return np.ldexp(np.asarray(theta, float), shift)


def scaled_points(points: StaticPoints, exps: Mapping[str, int]) -> StaticPoints:
    """Static points on the signals times 2^-e (as :func:`scaled_theta`'s): ȳ and its uncertainty δ by y's exponent,
    ū by its input's."""
    ub = np.asarray(points.ubar, float)
    names = [n for n in exps if n not in ("y", "e")]
    # an input the exponents do not name is left as it is: the caller refuses points of other inputs, in its words
    d = exps[names[0]] if ub.ndim == 1 else np.array([exps.get(n, 0) for n in points.input_names])
    delta = points.uncertainty
    return replace(points, ubar=np.ldexp(ub, -d), ybar=np.ldexp(np.asarray(points.ybar, float), -exps["y"]),
                   uncertainty=None if delta is None else np.ldexp(np.asarray(delta, float), -exps["y"]))


def unscaled_levels(levels: Mapping[str, float], exps: Mapping[str, int]) -> dict[str, float]:
    """Signal levels (a centred fit's offsets, by signal name) of the signals times 2^-e (:func:`binary_scaled`) in
    the data's own units, for what a result says of them."""
    return {k: math.ldexp(v, exps.get(k, 0)) for k, v in levels.items()}


def unscaled_rss(rss: np.ndarray, exps: Mapping[str, int]) -> np.ndarray:
    """The data's own RSS (output units²): the nearest float to it, as y² there (one rounding, exact otherwise): a
    subnormal of fewer digits below 2.2e-308, 0 only below 2.5e-324, inf above 1.8e308."""
    with np.errstate(over="ignore", under="ignore"):
        return np.ldexp(rss, 2 * exps.get("y", 0))
