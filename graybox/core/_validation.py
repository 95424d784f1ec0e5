"""Validation at the boundary: the one home for checking ints, reals, choices, θ, λ and arrays.

Every public function of graybox validates its arguments with these helpers, so the same
mistake gets the same message everywhere. Each returns the value in its canonical form
(a Python ``int``, a ``float``, a read-only float array …) or raises ``ValueError`` naming the
argument and what was wrong with it.
"""

from __future__ import annotations

import os
import sys
import warnings
from typing import Iterable, Sequence

import numpy as np

__all__ = [
    "check_int",
    "check_real",
    "check_choice",
    "check_seed",
    "check_theta",
    "check_lambdas",
    "as_1d_finite",
    "frozen",
    "warn",
    "renamed",
    "check_per_point",
]

#: The graybox package folder (this module sits in graybox/core): warnings skip every frame inside it.
_PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def check_int(value: object, name: str, *, low: int | None = None, high: int | None = None) -> int:
    """``value`` as an ``int`` in [low, high], or ``ValueError``.

    Booleans and non-integral numbers are refused (``True`` is not a count, nor is ``2.5``);
    an integral float such as ``3.0`` is accepted.
    """
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be an integer, got {value!r}")
    try:
        ok = int(value) == value  # type: ignore[call-overload]
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise ValueError(f"{name} must be an integer, got {value!r}")
    v = int(value)  # type: ignore[call-overload]
    if low is not None and v < low:
        raise ValueError(f"{name} must be an integer >= {low}, got {value!r}")
    if high is not None and v > high:
        raise ValueError(f"{name} must be an integer <= {high}, got {value!r}")
    return v


def check_real(
    value: object,
    name: str,
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
) -> float:
    """``value`` as a finite ``float`` in the interval given by ``low``/``high``, or ``ValueError``.

    ``low_open`` / ``high_open`` exclude the end points (``low=0, low_open=True``: positive).
    """
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be a number, got {value!r}")
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not np.isfinite(v):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    lo_bad = low is not None and (v <= low if low_open else v < low)
    hi_bad = high is not None and (v >= high if high_open else v > high)
    if lo_bad or hi_bad:
        lo = "(-inf" if low is None else ("(" if low_open else "[") + f"{low:g}"
        hi = "inf)" if high is None else f"{high:g}" + (")" if high_open else "]")
        raise ValueError(f"{name} must lie in {lo}, {hi}, got {value!r}")
    return v


def check_choice(value: object, name: str, choices: Iterable[str]) -> str:
    """``value`` if it is one of ``choices`` (strings), or ``ValueError`` listing them."""
    opts = tuple(choices)
    if not isinstance(value, str) or value not in opts:
        raise ValueError(f"{name} must be one of {', '.join(repr(c) for c in opts)}; got {value!r}")
    return value


def check_seed(seed: object, name: str = "seed") -> int:
    """A seed for ``numpy.random.default_rng``: an integer >= 0."""
    return check_int(seed, name, low=0)


def check_theta(n_terms: int, theta: object, name: str = "theta") -> np.ndarray:
    """θ as a finite float array of length ``n_terms``, shape (n_terms,), or ``ValueError``."""
    try:
        th = np.asarray(theta, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be an array of numbers, got {type(theta).__name__}") from None
    if th.ndim != 1:
        raise ValueError(f"{name} must be 1-D, got shape {th.shape}")
    if th.size != n_terms:
        raise ValueError(f"{name} has {th.size} values but the structure has {n_terms} terms")
    if not np.all(np.isfinite(th)):
        raise ValueError(f"{name} has non-finite values at {np.flatnonzero(~np.isfinite(th)).tolist()}")
    return th


def check_lambdas(lambdas: Sequence[float] | np.ndarray | float, name: str = "lambdas") -> np.ndarray:
    """λ1 values of a weighted-sum sweep as a non-empty 1-D float array in (0, 1], shape (K,).

    λ2 = 1 − λ1. λ1 = 0 would ignore the dynamic data entirely (θ is then not identifiable from
    the static points alone), so it is refused.
    """
    try:
        lam = np.atleast_1d(np.asarray(lambdas, dtype=float))
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be numbers in (0, 1], got {lambdas!r}") from None
    if lam.ndim != 1 or lam.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D array of λ1 values, got shape {lam.shape}")
    bad = ~np.isfinite(lam) | (lam <= 0) | (lam > 1)
    if bad.any():
        raise ValueError(f"every λ1 in {name} must lie in (0, 1] (λ2 = 1 − λ1); got {lam[bad].tolist()}")
    return lam


def check_per_point(value: object, n: int, name: str) -> np.ndarray:
    """A scalar or one value per point, as a finite float array of shape (n,), or ``ValueError``."""
    a = np.asarray(value, dtype=float)
    if a.ndim > 1 or (a.ndim == 1 and a.size not in (1, n)):
        raise ValueError(f"{name} must be a scalar or have one value per ū ({n}), got shape {a.shape}")
    out = np.broadcast_to(np.ravel(a) if a.ndim else a, (n,))
    if not np.all(np.isfinite(out)):
        raise ValueError(f"{name} has non-finite values")
    return out


def as_1d_finite(x: object, name: str) -> np.ndarray:
    """``x`` as a read-only 1-D float64 copy, or ``ValueError`` naming ``name`` and the problem."""
    try:
        a = np.array(x, dtype=float, copy=True)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be an array of numbers, got {type(x).__name__}") from None
    if a.ndim == 2 and 1 in a.shape:
        raise ValueError(f"{name} must be 1-D, got shape {a.shape}; pass a flat array (e.g. x.ravel())")
    if a.ndim != 1:
        raise ValueError(f"{name} must be 1-D, got {a.ndim}-D with shape {a.shape}")
    bad = ~np.isfinite(a)
    if bad.any():
        idx = np.flatnonzero(bad)
        raise ValueError(f"{name} has {idx.size} non-finite value(s) (NaN or inf), first at index {idx[0]}")
    a.setflags(write=False)
    return a


def frozen(a: object, dtype: type = float) -> np.ndarray:
    """A read-only copy of ``a``: how every immutable value in graybox stores its arrays."""
    x = np.array(a, dtype=dtype, copy=True)
    x.setflags(write=False)
    return x


def warn(message: str, category: type[Warning]) -> None:
    """``warnings.warn`` attributed to the caller's code, not to graybox's internals.

    The warning points at the first frame outside the graybox package, so that Python's default
    filter says it once per place in the user's code (and the user sees which line caused it).
    """
    level = 2  # stacklevel 1 is this function; 2 its caller, the frame below
    frame = sys._getframe(1)
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(_PACKAGE_DIR):
        frame = frame.f_back
        level += 1
    warnings.warn(message, category, stacklevel=level)


def renamed(value: object, old_value: object, new: str, old: str) -> object:
    """The value of keyword ``new``, or of its former name ``old`` (kept one release, with a DeprecationWarning).

    ``None`` means "not given"; both given is a ``TypeError``.
    """
    if old_value is None:
        return value
    if value is not None:
        raise TypeError(f"{old}= is the former name of {new}=: give {new}= only")
    warn(f"{old}= is deprecated (one name per concept): use {new}=", DeprecationWarning)
    return old_value
