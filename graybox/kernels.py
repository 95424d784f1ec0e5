"""Compiled free-run kernels (numba).

A structure is encoded once as flat integer arrays (see :func:`encode`): for term
``t`` its factors are ``fsig[fptr[t]:fptr[t+1]]`` (0 = y, 1 = u), with lags and
powers alongside. Noise terms are never encoded: free runs ignore the MA part.

The batch kernel keeps the population on the innermost, contiguous axis of its
work buffer (shape (N, P)) so that every term update is a unit-stride loop that
LLVM vectorises; the input-only part of each term is computed once per sample
and shared by the whole population.

Nothing here validates input: callers in :mod:`graybox.simulation` do.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from .terms import Structure

__all__ = ["encode", "simulate_one", "simulate_batch", "input_products"]

_SIG = {"y": 0, "u": 1}


def encode(structure: Structure) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Encode the process terms of ``structure`` as (fptr, fsig, flag, fpow) int64 arrays."""
    fptr = [0]
    fsig: list[int] = []
    flag: list[int] = []
    fpow: list[int] = []
    for term in structure:
        if term.is_noise:
            raise ValueError(f"noise term {term} cannot be simulated; pass the process structure")
        for s, l, p in term.factors:
            fsig.append(_SIG[s])
            flag.append(l)
            fpow.append(p)
        fptr.append(len(fsig))
    as_i = lambda a: np.asarray(a, dtype=np.int64)  # noqa: E731
    return as_i(fptr), as_i(fsig), as_i(flag), as_i(fpow)


@nb.njit(cache=True, nogil=True)
def simulate_one(fptr, fsig, flag, fpow, theta, u, y0, start, bound):  # pragma: no cover - compiled
    """Free run of one model. ``y0`` gives samples ``0 … start-1``; returns y of len(u).

    The run stops at the first sample whose magnitude exceeds ``bound`` (or is not
    finite); that sample and all later ones are set to NaN.
    """
    n = u.shape[0]
    nt = fptr.shape[0] - 1
    y = np.empty(n)
    for k in range(start):
        y[k] = y0[k]
    for k in range(start, n):
        acc = 0.0
        for t in range(nt):
            v = theta[t]
            for f in range(fptr[t], fptr[t + 1]):
                x = y[k - flag[f]] if fsig[f] == 0 else u[k - flag[f]]
                for _ in range(fpow[f]):
                    v *= x
            acc += v
        if not (abs(acc) <= bound):
            for j in range(k, n):
                y[j] = np.nan
            break
        y[k] = acc
    return y


@nb.njit(cache=True, nogil=True)
def input_products(fptr, fsig, flag, fpow, u, start):  # pragma: no cover - compiled
    """U[k, t] = product of the input factors of term t at sample k (1 for none)."""
    n = u.shape[0]
    nt = fptr.shape[0] - 1
    U = np.ones((n, nt))
    for k in range(start, n):
        for t in range(nt):
            v = 1.0
            for f in range(fptr[t], fptr[t + 1]):
                if fsig[f] == 1:
                    x = u[k - flag[f]]
                    for _ in range(fpow[f]):
                        v *= x
            U[k, t] = v
    return U


@nb.njit(cache=True, nogil=True)
def _batch_block(fptr, fsig, flag, fpow, thT, U, Y, start, p0, p1, tmp):  # pragma: no cover - compiled
    n = Y.shape[0]
    nt = fptr.shape[0] - 1
    for k in range(start, n):
        row = Y[k]
        for p in range(p0, p1):
            row[p] = 0.0
        for t in range(nt):
            c = U[k, t]
            th = thT[t]
            # count the output factors of this term
            ny = 0
            last = -1
            for f in range(fptr[t], fptr[t + 1]):
                if fsig[f] == 0:
                    ny += fpow[f]
                    last = f
            if ny == 0:
                for p in range(p0, p1):
                    row[p] += th[p] * c
            elif ny == 1:
                yl = Y[k - flag[last]]
                for p in range(p0, p1):
                    row[p] += th[p] * c * yl[p]
            else:
                for p in range(p0, p1):
                    tmp[p] = th[p] * c
                for f in range(fptr[t], fptr[t + 1]):
                    if fsig[f] == 0:
                        yl = Y[k - flag[f]]
                        for _ in range(fpow[f]):
                            for p in range(p0, p1):
                                tmp[p] *= yl[p]
                for p in range(p0, p1):
                    row[p] += tmp[p]


@nb.njit(cache=True, parallel=True)
def _batch_parallel(fptr, fsig, flag, fpow, thT, U, Y, start, nblocks):  # pragma: no cover - compiled
    P = Y.shape[1]
    tmp = np.empty(P)
    step = (P + nblocks - 1) // nblocks
    for b in nb.prange(nblocks):
        p0 = b * step
        p1 = min(P, p0 + step)
        if p0 < p1:
            _batch_block(fptr, fsig, flag, fpow, thT, U, Y, start, p0, p1, tmp)


def simulate_batch(
    code: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    thetas: np.ndarray,
    u: np.ndarray,
    y0: np.ndarray,
    start: int,
    threads: int = 1,
) -> np.ndarray:
    """Free runs of P parameter vectors of one structure.

    Parameters
    ----------
    code : tuple
        :func:`encode` of the structure.
    thetas : ndarray, shape (P, n_terms)
    u : ndarray, shape (N,)
    y0 : ndarray, shape (start,)
        Initial outputs shared by the population.
    start : int
        Number of initial samples (>= the structure's max lag).
    threads : int
        Population blocks run in parallel (numba threads); 1 runs in the calling thread.

    Returns
    -------
    ndarray, shape (P, N)
        Outputs; a diverging member has non-finite samples (never raises).
    """
    fptr, fsig, flag, fpow = code
    P = thetas.shape[0]
    n = u.shape[0]
    thT = np.ascontiguousarray(thetas.T, dtype=np.float64)
    U = input_products(fptr, fsig, flag, fpow, u, start)
    Y = np.empty((n, P))
    Y[:start, :] = y0[:start, None]
    with np.errstate(all="ignore"):
        if threads <= 1 or P < 2 * threads:
            _batch_block(fptr, fsig, flag, fpow, thT, U, Y, start, 0, P, np.empty(P))
        else:
            _batch_parallel(fptr, fsig, flag, fpow, thT, U, Y, start, int(threads))
    return np.ascontiguousarray(Y.T)
