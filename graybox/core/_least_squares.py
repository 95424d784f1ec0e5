"""Least squares with internal column scaling.

Polynomial regressors in engineering units span many decades (u ≈ 1e3 rpm, u³ ≈ 1e9),
so every least-squares path in graybox scales columns to unit RMS, solves, and maps the
solution back: results do not depend on the units the user chose.
"""

from __future__ import annotations

from contextlib import AbstractContextManager

import numpy as np
from threadpoolctl import ThreadpoolController

__all__ = ["column_scales", "scaled_lstsq", "thread_pools", "one_blas_thread", "check_rows"]

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


def column_scales(A: np.ndarray) -> np.ndarray:
    """RMS of each column of ``A`` (1 for an all-zero column), shape (n,)."""
    s = np.sqrt(np.mean(np.asarray(A) ** 2, axis=0))
    return np.where(s > 0, s, 1.0)


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
        When A or b has non-finite values, the shapes disagree, or A is rank deficient after
        scaling (the parameters are not identifiable from these data).
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
    return x / s
