"""Validation at the boundary: the one home for checking ints, reals, choices, θ, λ and arrays.

Every public function of graybox validates its arguments with these helpers, so the same
mistake gets the same message everywhere. Each returns the value in its canonical form
(a Python ``int``, a ``float``, a read-only float array …) or raises, naming the argument and
what was wrong with it, as NumPy and scikit-learn do: ``TypeError`` for a value of the wrong type
(``"x"`` or ``True`` where a number is meant, ``2.5`` where a count is meant), ``ValueError`` for
a value of the right type outside its allowed range (``-1``, ``nan``, ``inf``, an unknown choice).
"""

from __future__ import annotations

import dataclasses
import datetime
import numbers
import os
import reprlib
import sys
import types
import typing
import warnings
from collections.abc import Mapping
from typing import Any, Callable, Iterable, Sequence

import numpy as np

__all__ = [
    "check_bool",
    "check_int",
    "check_count",
    "check_workers",
    "check_real",
    "check_level",
    "check_band",
    "check_choice",
    "check_seed",
    "check_theta",
    "check_lambdas",
    "as_1d_finite",
    "float_array",
    "frozen",
    "frozen_value",
    "FrozenList",
    "warn",
    "check_per_point",
    "check_sequence",
    "check_path",
    "check_fields",
    "check_frame_columns",
    "refuse_flags",
    "SAMPLES",
]

# graybox/, not graybox/core/: a frame in any subpackage is graybox's own
_PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + os.sep


def _is_bool(value: object) -> bool:
    return isinstance(value, (bool, np.bool_))


def _is_number(value: object) -> bool:
    """A real number: Python's, NumPy's, or a 0-d numeric array (never a bool or a string)."""
    if _is_bool(value):
        return False
    if isinstance(value, np.ndarray):
        return value.ndim == 0 and value.dtype.kind in "iuf"
    return isinstance(value, numbers.Real)


def check_bool(value: object, name: str) -> bool:
    """``value`` as a Python ``bool``, or ``TypeError`` (``1``, ``"yes"`` and ``None`` are not flags)."""
    if not _is_bool(value):
        raise TypeError(f"{name} must be True or False, got {value!r} ({type(value).__name__})")
    return bool(value)


def check_str(value: object, name: str) -> str:
    """``value`` as text, or ``TypeError`` (a label saved to a file must load back as the same text)."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a str, got {value!r} ({type(value).__name__})")
    return value


def check_int(value: object, name: str, *, low: int | None = None, high: int | None = None) -> int:
    """``value`` as an ``int`` in [low, high].

    ``TypeError`` for anything but an integer: booleans (``True`` is not a count), strings and
    non-integral numbers (``2.5``); an integral float such as ``3.0`` is accepted.
    ``ValueError`` for an integer outside [low, high] (and for ``nan`` or ``inf``).
    """
    if not _is_number(value):
        raise TypeError(f"{name} must be an integer, got {value!r} ({type(value).__name__})")
    if isinstance(value, (numbers.Integral, np.integer)) or (isinstance(value, np.ndarray) and value.dtype.kind in "iu"):
        v = int(value)  # type: ignore[arg-type]  (exact: an int beyond any float, 10**400, is no OverflowError)
    elif isinstance(value, numbers.Rational):  # a Fraction, exact: float() of Fraction(10**400) overflowed
        if value.denominator != 1:
            raise TypeError(f"{name} must be an integer, got {value!r}")
        v = int(value)
    else:
        f = float(value)  # type: ignore[arg-type]
        if not np.isfinite(f):
            if _finite_beyond(value):
                raise _BeyondFloats(f"{name} must be an integer, got one beyond the float range (about 1.8e308)")
            raise ValueError(f"{name} must be a finite integer, got {value!r}")
        if f != int(f):
            raise TypeError(f"{name} must be an integer, got {value!r}")
        v = int(f)
    if low is not None and v < low:
        raise ValueError(f"{name} must be an integer >= {low}, got {value!r}")
    if high is not None and v > high:
        raise ValueError(f"{name} must be an integer <= {high}, got {value!r}")
    return v


def _memory_bytes() -> int:
    """This machine's memory, physical and swap (bytes): more than any one array graybox makes can ever take."""
    total = 0
    try:
        page, pages = os.sysconf("SC_PAGE_SIZE"), os.sysconf("SC_PHYS_PAGES")
        if page <= 0 or pages <= 0:  # sysconf's -1: not known here (the swap alone is no machine's memory)
            return 2**50
        total = page * pages
        with open("/proc/meminfo") as f:  # Linux: the swap, which an allocation may also use
            for line in f:
                if line.startswith("SwapTotal:"):
                    total += int(line.split()[1]) * 1024
    except (AttributeError, ValueError, OSError):
        pass
    return total if total > 0 else 2**50  # unknown: 1 PiB, beyond any machine's


def _bytes_text(n: float) -> str:
    for unit in ("bytes", "kB", "MB", "GB", "TB", "PB"):
        if n < 1000 or unit == "PB":
            return f"{n:.0f} {unit}" if unit == "bytes" else f"{n:.3g} {unit}"
        n /= 1000
    return f"{n:.3g} EB"  # pragma: no cover


def check_count(value: object, name: str, *, low: int | None = None, high: int | None = None,
                item_bytes: float = 8, each: Sequence[tuple[int, str]] = ()) -> int:
    """``value`` as an ``int`` in [low, high], as :func:`check_int`, that sizes something allocated in proportion:
    ``ValueError`` naming ``name`` for a count whose memory (``item_bytes`` per unit: 8 for one float) is more
    than this machine has, physical and swap, which could never be allocated (numpy's ``MemoryError`` named
    nothing, after the other checks and any work before the allocation).

    ``each``: the sizes of the array each unit builds, as (size, what) pairs, e.g. ``((M, "points"), (n, "terms"))``
    for Monte Carlo draws that each hold M × n floats: the memory counted is ``value`` × M × n × ``item_bytes``,
    and the message names the factors (a count checked at 8 bytes a unit let N × M × n arrays through)."""
    v = check_int(value, name, low=low, high=high)
    have = _memory_bytes()
    try:
        need = float(v) * float(item_bytes)
        for size, _ in each:
            need *= float(size)
    except OverflowError:  # a count beyond any float (10**400)
        need = float("inf")
    if need > have:
        size = _bytes_text(need) if np.isfinite(need) else "more than 1e308 bytes"
        times = "".join(f" × {int(k)} {what}" for k, what in each)
        of = f" ({v}{times})" if each else ""
        raise ValueError(f"{name}={v} is too large: it would need at least {size} of memory{of}, more than "
                         f"this machine has ({_bytes_text(have)})")
    return v


#: The least memory one worker process takes (bytes): a Python with graybox imported, before any work (30 MB measured).
PROCESS_BYTES = 30 * 2**20


def check_workers(value: object, name: str = "workers") -> int:
    """A count of worker processes to start on this machine, as :func:`check_count`: ``ValueError`` for more than
    its memory could ever hold (:data:`PROCESS_BYTES` each; 10**20 workers was handed to the pool or to Dask)."""
    return check_count(value, name, low=1, item_bytes=PROCESS_BYTES)


def check_real(
    value: object,
    name: str,
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
) -> float:
    """``value`` as a finite ``float`` in the interval given by ``low``/``high``.

    ``low_open`` / ``high_open`` exclude the end points (``low=0, low_open=True``: positive).
    ``TypeError`` for a bool, a string or anything else that is not a real number (``"0.1"`` is
    refused: a number read from a file is converted where it is read); ``ValueError`` for
    ``nan``, ``inf``, an integer beyond the float range or a number outside the interval.
    """
    if not _is_number(value):
        raise TypeError(f"{name} must be a real number, got {value!r} ({type(value).__name__})")
    try:
        v = float(value)  # type: ignore[arg-type]
    except OverflowError:  # an integer beyond the float range (10**400), as float_array says it (no repr: 10**5000
        # has none within Python's digit limit)
        raise _BeyondFloats(f"{name} must be a finite number, got one beyond the float range (about 1.8e308)") from None
    if not np.isfinite(v):
        if _finite_beyond(value):  # a longdouble of 1e400 is a number, not inf
            raise _BeyondFloats(f"{name} must be a finite number, got one beyond the float range (about 1.8e308)")
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    lo_bad = low is not None and (v <= low if low_open else v < low)
    hi_bad = high is not None and (v >= high if high_open else v > high)
    if lo_bad or hi_bad:
        lo = "(-inf" if low is None else ("(" if low_open else "[") + f"{low:g}"
        hi = "inf)" if high is None else f"{high:g}" + (")" if high_open else "]")
        raise ValueError(f"{name} must lie in {lo}, {hi}, got {value!r}")
    return v


def check_level(value: object, name: str = "level") -> float:
    """A confidence ``level`` in (0, 1) whose two-sided quantile the floats hold: ``ValueError`` naming ``name`` where
    0.5 + level/2 rounds to 0.5 (a band of width 0, level below ~1e-16) or to 1 (an infinite band, level above
    1 − 2e-16), which a level in (0, 1) alone let through to a band of 0 or ±inf."""
    level = check_real(value, name, low=0, high=1, low_open=True, high_open=True)
    if not 0.5 < 0.5 + level / 2 < 1.0:
        raise ValueError(f"{name} must lie in (0, 1) far enough from its ends that its two-sided quantile is finite and "
                         f"not 0 (0.5 + {name}/2 strictly between 0.5 and 1 in floats), got {level!r}")
    return level


def check_band(band: object, name: str = "band") -> tuple[float, float]:
    """A band on a mean square error (output units²) as ``(low, high)``, or ``TypeError``/``ValueError``.

    ``band`` is the upper end ``B > 0`` of [0, B], or a pair ``(low, high)`` with
    ``0 <= low < high``. A band of width 0 asks for an exact fit of noisy data, so it is refused.
    """
    if isinstance(band, (tuple, list)) or (isinstance(band, np.ndarray) and band.ndim == 1):
        if len(band) != 2:
            raise ValueError(f"{name} must be a number B > 0 or a pair (low, high), got {len(band)} values")
        lo = check_real(band[0], f"{name}[0] (low)", low=0)
        hi = check_real(band[1], f"{name}[1] (high)", low=lo, low_open=True)
        return lo, hi
    if not _is_number(band):
        raise TypeError(f"{name} must be a number B > 0 (output units²) or a pair (low, high), got {band!r} "
                        f"({type(band).__name__})")
    return 0.0, check_real(band, name, low=0, low_open=True)


def check_agrees(value: float, expected: float, name: str, said: str, rtol: float = 1e-9) -> None:
    """``ValueError`` naming ``name`` where a figure a result holds is not the one its own fields give (``said``:
    which, in words), to ``rtol``: a result built by hand, or read from an edited file, must not carry a band or
    limit of other data beside its verdict."""
    if not abs(value - expected) <= rtol * abs(expected):
        raise ValueError(f"{name} is {value!r}, but {said} give {expected!r}")


def check_mean_square(value: object, name: str) -> None:
    """``ValueError`` when a mean square error (J_1, J_S, J_SF: output units²) held by a result is negative.

    NaN (not computed) and inf (a free run that diverged, no static curve) are values such a figure takes;
    a negative one is what no computation gives (a file edited by hand, a result built wrong).
    """
    a = np.asarray(value, dtype=float)
    bad = a < 0  # NaN compares False
    if np.any(bad):
        raise ValueError(f"{name} is a mean square error, never negative; got {float(a[bad].ravel()[0])!r}")


def check_weight(value: object, name: str) -> None:
    """``ValueError`` unless each λ1 held by a result lies in (0, 1] or is NaN (a member of no weight)."""
    a = np.asarray(value, dtype=float)
    bad = ~np.isnan(a) & ~((a > 0) & (a <= 1))
    if np.any(bad):
        raise ValueError(f"{name} must lie in (0, 1] (λ2 = 1 − λ1), or be NaN; got {float(a[bad].ravel()[0])!r}")


def check_margin_value(value: float, name: str = "margin") -> None:
    """``ValueError`` unless a stability margin held by a result lies in [0, 1) or is NaN (none)."""
    if not (np.isnan(value) or 0.0 <= value < 1.0):
        raise ValueError(f"{name} must lie in [0, 1), or be NaN (no margin); got {value!r}")


def _first_bad(bad: np.ndarray) -> tuple[tuple[int, ...], str]:
    """The index of the first True entry of ``bad`` in the array's own shape (a surface band's gains are (M, m): a
    flat index into them raised IndexError instead of the message), and that index in words."""
    i = tuple(int(k) for k in np.argwhere(bad)[0])
    return i, str(i[0]) if len(i) == 1 else str(i)


def check_band_values(std: np.ndarray, low: np.ndarray, high: np.ndarray, *names: str) -> None:
    """``ValueError`` unless a band's standard deviations are >= 0 and its low ends at most its high ones, where they
    are numbers (NaN: no draw there; a value read from a hand-edited file is held to what a band can be)."""
    s, lo, hi = names
    if np.any(std < 0):
        i, said = _first_bad(std < 0)
        raise ValueError(f"{s} must be >= 0 (standard deviations), got {float(std[i]):g} at index {said}")
    if np.any(low > high):
        i, said = _first_bad(low > high)
        raise ValueError(f"{lo} must not exceed {hi}, got {low[i]:g} > {high[i]:g} at index {said}")


def check_band_finite(band: object, fields: Sequence[str], none_drawn: np.ndarray | None = None) -> None:
    """A band's ``fields`` finite numbers, NaN allowed only at the points of ``none_drawn`` (shape (M,), along the
    fields' first axis: where no Monte Carlo draw was kept, there is no band); a hand-edited file is held to it."""
    for f in fields:
        v = getattr(band, f)
        bad = ~np.isfinite(v)
        if none_drawn is not None:
            bad &= ~(np.isnan(v) & none_drawn.reshape((-1,) + (1,) * (v.ndim - 1)))
        if bad.any():
            i, said = _first_bad(bad)
            where = "" if none_drawn is None else " (NaN only where no draw was kept)"
            raise ValueError(f"{f} must hold finite numbers{where}, got {v[i]} at index {said}")


def check_choice(value: object, name: str, choices: Iterable[str]) -> str:
    """``value`` if it is one of ``choices`` (strings): ``TypeError`` for a non-string, else ``ValueError`` listing them."""
    opts = tuple(choices)
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a string, one of {', '.join(repr(c) for c in opts)}; got {value!r} "
                        f"({type(value).__name__})")
    if value not in opts:
        raise ValueError(f"{name} must be one of {', '.join(repr(c) for c in opts)}; got {value!r}")
    return value


def check_seed(seed: object, name: str = "seed") -> int:
    """A seed for ``numpy.random.default_rng``: an integer >= 0."""
    return check_int(seed, name, low=0)


def refuse_non_real(x: object, name: str) -> None:
    """``TypeError`` naming ``name`` when ``x`` holds complex numbers, strings or dates, which converting
    to float would take silently: a complex number's real part (with at most numpy's warning), a
    string's parse (a column read as text), a date's count of nanoseconds since 1970."""
    try:
        arr = np.asarray(x)
    except (TypeError, ValueError):  # ragged or not numbers: the conversion that follows says so
        return
    kind = arr.dtype.kind
    if kind == "c":
        raise TypeError(f"{name} must be real numbers, got complex values")
    # text in an object array too: a pandas column of strings (object or "string" dtype) arrives so
    if kind in "US" or (kind == "O" and any(isinstance(v, (str, bytes)) for v in arr.flat)):
        raise TypeError(f"{name} must be numbers, got strings; convert them first (e.g. with float), or read a "
                        "file with graybox.load_record_csv / load_static_csv")
    held = arr.dtype
    if kind == "O":
        # a DataFrame's time column beside numbers arrives as objects (Timestamps), which the conversion turns into
        # counts of µs since 1970 as it does a datetime64 column
        stamp = next((v for v in arr.flat if isinstance(v, _TIMES)), None)
        if stamp is not None:
            kind = "m" if isinstance(stamp, (datetime.timedelta, np.timedelta64)) else "M"
            held = type(stamp).__name__
    if kind in "Mm":  # numpy turns them into counts of its time unit (ns or µs since 1970) without a word
        what = "dates or clock times" if kind == "M" else "time spans"
        raise TypeError(f"{name} must be numbers, got {what} ({held}): a time column is no signal; a record's "
                        "time is its sampling period Ts (seconds)")


#: Values of time that a float conversion reads as counts of a time unit (pandas' Timestamp and Timedelta among them).
_TIMES = (datetime.date, datetime.time, datetime.timedelta, np.datetime64, np.timedelta64)


def real_array(x: object, name: str, what: str = "numbers") -> np.ndarray:
    """``x`` as a new float array: :func:`float_array` after refusing (``TypeError`` naming ``name``) text, complex
    values, dates, booleans and None anywhere inside (numpy's own conversion parses text, drops an imaginary part,
    reads True as 1 and None as NaN, and its errors name neither the argument nor the problem). A ragged nesting is
    a ``TypeError`` here too, with float_array's words: levels or points are no array of numbers (records and θ,
    read by float_array itself, call it a bad shape)."""
    refuse_non_real(x, name)
    refuse_flags(x, name, what)
    try:
        return float_array(x, name, what)
    except _BadValue:  # a value, not a type
        raise
    except ValueError as exc:  # ragged: the paths that read levels and points have always called it a type
        raise TypeError(str(exc)) from None


def refuse_flags(x: object, name: str, what: str = "numbers", *, none: bool = True) -> None:
    """``TypeError`` naming ``name`` when ``x`` is or holds a boolean or (``none``) None, which a float conversion
    reads as 1 and NaN (a parameter of 1, a diverged run): the check :func:`real_array`, θ (:func:`check_theta`)
    and samples (:func:`as_1d_finite`, which leaves None to be said as a missing, non-finite value) share."""
    flag = (bool, np.bool_, type(None)) if none else (bool, np.bool_)
    dtype = getattr(x, "dtype", None)  # numpy's, or pandas' (its "boolean" too: kind "b")
    look = x
    if dtype is None and type(x).__module__.startswith("pandas") and hasattr(x, "dtypes"):
        # a DataFrame: by its columns' dtypes; only columns of objects are looked into (not 10⁶ floats one by one)
        kinds = list(x.dtypes)  # type: ignore[attr-defined]
        dtype = np.dtype(bool) if any(getattr(k, "kind", "") == "b" for k in kinds) else np.dtype(object)
        look = x[[c for c, k in zip(x.columns, kinds) if k == object]]  # type: ignore[attr-defined, index]
    bad = isinstance(x, flag) or getattr(dtype, "kind", "") == "b"
    if not bad and (dtype is None or dtype == object):
        # None inside a list (or a pandas Series or DataFrame of objects) too: a float conversion reads it as NaN,
        # which callers take for a diverged run. By the items' types, met in C (map): a flat list of 10⁶ floats
        # is not made an object array first, nor its items tested one by one in Python
        kinds = set(map(type, look)) if isinstance(look, (list, tuple)) else None
        if kinds is None or any(issubclass(k, (list, tuple, np.ndarray)) or _is_pandas_type(k) for k in kinds):
            try:
                raw = np.asarray(look, dtype=object)
            except ValueError:  # ragged below the first level: float_array names it
                raw = np.empty(0, dtype=object)
            kinds = set(map(type, raw.flat))
        bad = any(issubclass(k, flag) for k in kinds)
    if bad:
        raise TypeError(f"{name} must be {what}, got {short_value(x)}")


def _is_pandas_type(t: type) -> bool:
    return t.__module__.split(".")[0] == "pandas"


#: What samples must be, said where a flag is among them: a logic signal is the caller's to convert, knowingly.
SAMPLES = "numbers, not True/False (a logic signal, on/off: x.astype(float) reads it as 1 and 0)"


def _finite_beyond(v: object) -> bool:
    """``v``, which float64 holds as ±inf, is a finite number in its own type (a ``Decimal`` or a NumPy
    ``longdouble`` beyond 1.8e308): no NaN or inf, a number beyond the float range."""
    is_finite = getattr(v, "is_finite", None)  # Decimal's own test: float() of it would say inf
    if callable(is_finite):
        try:
            return bool(is_finite())
        except TypeError:
            return False
    try:
        return bool(np.isfinite(v))  # type: ignore[call-overload]  (a longdouble, in its own precision)
    except (TypeError, ValueError):
        return False


def _refuse_beyond_floats(x: object, a: np.ndarray, name: str) -> None:
    """``_BeyondFloats`` naming ``name`` where the float64 array ``a`` converted from ``x`` is ±inf at a number that is
    finite in ``x`` (a ``Decimal`` or ``longdouble`` beyond the float range): the finite checks that follow would
    call it non-finite, NaN or inf."""
    inf = np.isinf(a)
    if not inf.any():
        return
    try:
        src = np.asarray(x)
    except (TypeError, ValueError):
        return
    if src.shape != a.shape or src.dtype.kind not in "fO":  # float64 itself is inf where it says so
        return
    if src.dtype.kind == "f" and src.dtype.itemsize <= 8:
        return
    if any(_finite_beyond(v) for v in src[inf].ravel()):
        raise _BeyondFloats(f"{name} holds a number beyond the float range (about 1.8e308)")


class _BadValue(ValueError):
    """A value refused by :func:`float_array` as such, which :func:`real_array` and :func:`check_per_point` do not
    take for a ragged shape (a type error there)."""


class _BeyondFloats(_BadValue):
    """A number beyond the float range."""


class _Masked(_BadValue):
    """Masked (missing) entries of a NumPy masked array."""


def float_array(x: object, name: str, what: str = "an array of numbers") -> np.ndarray:
    """``x`` as a new float64 array: ``TypeError`` naming ``name`` for None or an object that is no array of
    numbers (a dict, a record of another kind), ``ValueError`` for a ragged nesting of numbers or a masked array
    with masked (missing) entries.

    numpy reads None as a NaN scalar and raises its own ``TypeError`` for other objects; the shared
    conversions of records, θ and inputs all go through here so that a wrong type is one error everywhere.
    Text, complex values and dates are for :func:`refuse_non_real` to refuse first.
    """
    if x is None:
        raise TypeError(f"{name} must be {what}, got None")
    if isinstance(x, np.ma.MaskedArray) and np.ma.getmaskarray(x).any():
        # numpy's conversion keeps a masked entry's data (netCDF4's fill value 9.97e36, genfromtxt's stand-in for
        # an empty cell) and drops the mask that says it is missing
        bad = np.argwhere(np.ma.getmaskarray(x))
        at = int(bad[0][0]) if x.ndim == 1 else tuple(int(i) for i in bad[0])
        raise _Masked(f"{name} has {len(bad)} masked (missing) value(s), first at index {at}: a masked entry is "
                         "no sample; cut the data where they are, or fill them first (x.filled(value))")
    if type(x).__module__.startswith("pandas") and hasattr(x, "to_numpy"):
        # pandas' nullable columns (Int64, Float64) hold pd.NA, which numpy cannot make a float: read as NaN,
        # that the finite checks name it (a Series did, a DataFrame of them was "no array of numbers")
        try:
            with np.errstate(over="ignore"):  # a longdouble beyond float64's range: said below, no warning
                a = np.array(x.to_numpy(dtype=float, na_value=np.nan), dtype=float, copy=True)
            _refuse_beyond_floats(x, a, name)
            return a
        except _BadValue:
            raise
        except (TypeError, ValueError):
            pass  # text, dates …: said below as for any other object
    try:
        with np.errstate(over="ignore"):  # numpy's "overflow encountered in cast" named nothing: said below
            a = np.array(x, dtype=float, copy=True)
        _refuse_beyond_floats(x, a, name)
        return a
    except _BadValue:
        raise
    except TypeError:
        raise TypeError(f"{name} must be {what}, got {type(x).__name__}") from None
    except OverflowError:  # an integer beyond the float range (10**400): numpy's message names nothing
        raise _BeyondFloats(f"{name} holds a number beyond the float range (about 1.8e308)") from None
    except ValueError:
        ragged = isinstance(x, (list, tuple)) and len({np.ndim(v) if np.ndim(v) == 0 else np.shape(v) for v in x}) > 1
        raise ValueError(f"{name} must be {what}, got {type(x).__name__}"
                         + (" of rows of different lengths" if ragged else "")) from None


def short_value(x: object) -> str:
    """``repr(x)`` cut to 80 characters, for a message about a bad argument."""
    text = repr(x)
    return text if len(text) <= 80 else text[:77] + "..."


def check_theta(n_terms: int, theta: object, name: str = "theta") -> np.ndarray:
    """θ as a finite float array of length ``n_terms``, shape (n_terms,); ``TypeError`` for what is no array of
    numbers, ``ValueError`` for a wrong shape or a non-finite value."""
    refuse_non_real(theta, name)
    refuse_flags(theta, name, "parameters (numbers)")  # True is no parameter 1, None no NaN
    th = float_array(theta, name)
    if th.ndim != 1:
        raise ValueError(f"{name} must be 1-D, got shape {th.shape}")
    if th.size != n_terms:
        raise ValueError(f"{name} has {th.size} values but the structure has {n_terms} terms")
    if not np.all(np.isfinite(th)):
        raise ValueError(f"{name} has non-finite values at {np.flatnonzero(~np.isfinite(th)).tolist()}")
    return th


def check_finite_rows(th: np.ndarray, name: str = "thetas") -> None:
    """``ValueError`` naming the rows of the parameter vectors ``th`` (P, n_terms) that are not finite (NaN or
    inf): such a θ is no model to run or score (a caller with failed members leaves them out)."""
    bad = np.flatnonzero(~np.all(np.isfinite(th), axis=1))
    if bad.size:
        rows = bad[:10].tolist()
        raise ValueError(f"{name}: row{'s' if bad.size > 1 else ''} {rows}{' …' if bad.size > 10 else ''} "
                         f"({bad.size} of {th.shape[0]}) not finite (NaN or inf): such a θ is no model to run or "
                         "score; leave failed members out")


def check_lambdas(lambdas: Sequence[float] | np.ndarray | float, name: str = "lambdas") -> np.ndarray:
    """λ1 values of a weighted-sum sweep as a non-empty 1-D float array in (0, 1], shape (K,).

    λ2 = 1 − λ1. λ1 = 0 would ignore the dynamic data entirely (θ is then not identifiable from
    the static points alone), so it is refused.
    """
    if _is_bool(lambdas) or isinstance(lambdas, str):
        raise TypeError(f"{name} must be numbers in (0, 1], got {lambdas!r}")
    refuse_non_real(lambdas, name)  # ["0.5"] is text, not a λ1
    items = (list(lambdas) if isinstance(lambdas, (list, tuple)) else
             lambdas.ravel().tolist() if isinstance(lambdas, np.ndarray) and lambdas.dtype == object else [])
    if lambdas is None or any(v is None for v in items):
        # None became NaN in the float array: [0.5, None] (or its object array) was told "got [nan]"
        where = "" if lambdas is None else f" (at position {[v is None for v in items].index(True)})"
        raise TypeError(f"{name} must be numbers in (0, 1], got None{where}")
    try:  # float_array: a Decimal or integer beyond the float range is said as such, not "got [inf]"
        lam = np.atleast_1d(float_array(lambdas, name))
    except _BadValue:
        raise
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be numbers in (0, 1], got {lambdas!r}") from None
    if np.asarray(lambdas).dtype == bool:
        raise TypeError(f"{name} must be numbers in (0, 1], got booleans")
    if lam.ndim != 1 or lam.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D array of λ1 values, got shape {lam.shape}")
    bad = ~np.isfinite(lam) | (lam <= 0) | (lam > 1)
    if bad.any():
        raise ValueError(f"every λ1 in {name} must lie in (0, 1] (λ2 = 1 − λ1); got {lam[bad].tolist()}")
    return lam


def check_per_point(value: object, n: int, name: str) -> np.ndarray:
    """A scalar or one value per point, as a finite float array of shape (n,), or ``ValueError``
    (``TypeError`` for text, complex values or booleans, which numpy would convert)."""
    refuse_non_real(value, name)
    try:
        a = float_array(value, name, "a number or an array of numbers")
    except _BadValue:  # a value, said naming it
        raise
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a number or an array of numbers, got {type(value).__name__}") from None
    if _is_bool(value) or np.asarray(value).dtype == bool or a.dtype == object:
        raise TypeError(f"{name} must be a number or an array of numbers, got {value!r}")
    if a.ndim > 1 or (a.ndim == 1 and a.size not in (1, n)):
        raise ValueError(f"{name} must be a scalar or have one value per ū ({n}), got shape {a.shape}")
    out = np.broadcast_to(np.ravel(a) if a.ndim else a, (n,))
    if not np.all(np.isfinite(out)):
        raise ValueError(f"{name} has non-finite values")
    return out


def check_ordered(value: object, name: str, what: str) -> None:
    """``TypeError`` naming ``name`` for a set or frozenset where the order of ``what`` is read: a set's order
    changes with PYTHONHASHSEED from one process to the next."""
    if isinstance(value, (set, frozenset)):
        raise TypeError(f"{name}: an ordered sequence of {what} is needed, got a {type(value).__name__}, which has "
                        "no order (it would change with PYTHONHASHSEED): pass a list")


def check_sequence(value: object, name: str, what: str = "a sequence", *, ordered: str | None = None) -> list:
    """``value`` as a list of its items, or ``TypeError`` for a number, a bool, a string or a mapping.

    For options that take several things (terms, start vectors, labels): a lone scalar or a
    string would otherwise be iterated, or fail inside NumPy, without naming the option.
    ``ordered``: what the items are, where their order is read (a set is then refused, :func:`check_ordered`).
    """
    if (_is_bool(value) or _is_number(value) or isinstance(value, (str, bytes, dict))
            or not isinstance(value, Iterable)):
        raise TypeError(f"{name} must be {what}, got {value!r} ({type(value).__name__})")
    if ordered is not None:
        check_ordered(value, name, ordered)
    return list(value)  # type: ignore[call-overload]


def check_path(value: object, name: str, *, file: bool = False) -> str | os.PathLike:
    """``value`` if it is a file or folder name (``str`` or path-like), or ``TypeError`` naming ``name``.

    Python's own message for ``Path(2.5)`` names neither the option nor what it wanted. ``file``: a file's name,
    where an empty one is a ``ValueError`` (``Path("")`` is the current folder: "Is a directory: '.'"), and so is one
    ending in a folder separator (``Path("out/")`` is ``out``: a file where the user named a folder). A name holding
    a NUL character is a ``ValueError`` naming ``name`` (the OS's says only "embedded null byte"). A leading ``~``
    is the home folder (``os.path.expanduser``), as a shell, numpy and pandas read it.
    """
    if not isinstance(value, (str, os.PathLike)):
        raise TypeError(f"{name} must be a file or folder name (str or path-like), got {value!r} "
                        f"({type(value).__name__})")
    if file and not os.fspath(value):
        raise ValueError(f"{name} is empty: give the file's name")
    text = os.fspath(value)
    if ("\0" if isinstance(text, str) else b"\0") in text:  # the OS's call said only 'embedded null byte'
        raise ValueError(f"{name} {text!r} holds a NUL character (\\x00), which no file name can: a name read from "
                         "binary data or a C string?")
    if file and isinstance(text, str) and text.endswith(tuple(s for s in (os.sep, os.altsep, "/") if s)):
        # a folder's name ('results/'): Path drops the separator, and the file was written (or read) as 'results'
        raise ValueError(f"{name} {text!r} ends in a folder separator, so it names a folder, not a file: give a file's "
                         f"name (in that folder: {text}NAME)")
    if isinstance(text, str) and text.startswith("~"):
        # '~/m.json' means the home folder, as in a shell, numpy and pandas; open() would look for a folder '~'
        return os.path.expanduser(text)
    return value


def as_1d_finite(x: object, name: str) -> np.ndarray:
    """``x`` as a read-only 1-D float64 copy, or an error naming ``name`` and the problem (``TypeError`` for
    what is no array of numbers or holds booleans, which numpy reads as 1 and 0, ``ValueError`` for a wrong shape or
    a non-finite value, None's NaN among them)."""
    refuse_non_real(x, name)
    refuse_flags(x, name, SAMPLES, none=False)
    a = float_array(x, name)
    if a.ndim == 2 and 1 in a.shape:
        cols = getattr(x, "columns", None) if type(x).__module__.startswith("pandas") else None
        columns = [] if cols is None else list(cols)
        if len(columns) == 1:  # df[["p"]]: a DataFrame has no ravel()
            raise ValueError(f"{name} must be 1-D, got a DataFrame of one column, shape {a.shape}; pass the column "
                             f"itself, a Series: df[{columns[0]!r}] (one pair of brackets)")
        raise ValueError(f"{name} must be 1-D, got shape {a.shape}; pass a flat array (e.g. x.ravel())")
    if a.ndim != 1:
        raise ValueError(f"{name} must be 1-D, got {a.ndim}-D with shape {a.shape}")
    bad = ~np.isfinite(a)
    if bad.any():
        idx = np.flatnonzero(bad)
        raise ValueError(f"{name} has {idx.size} non-finite value(s) (NaN or inf), first at index {idx[0]}")
    return locked(a)


def locked(a: np.ndarray) -> np.ndarray:
    """A copy of ``a`` (shape and dtype kept) that nothing can make writeable again: its memory is an immutable
    ``bytes`` object, so ``flags.writeable = True`` is refused on it and on its base (a read-only array that owns its
    memory could be made writeable, and a value edited in place through it). Object arrays are copied read-only (a
    :class:`FrozenMap` hands them out as fresh copies: a reader can make one writeable)."""
    a = np.asarray(a)
    if a.dtype.hasobject:
        x = a.copy()
        x.setflags(write=False)
        return x
    return np.frombuffer(np.ascontiguousarray(a).tobytes(), dtype=a.dtype).reshape(a.shape)


def _is_locked(a: np.ndarray) -> bool:
    """Whether nothing can make ``a`` writeable: read-only over an immutable ``bytes`` object (as :func:`locked`
    makes them)."""
    return not a.flags.writeable and _bytes_base(a) is not None


def _relocked(v: object) -> object:
    """``v`` with its arrays :func:`locked` again (in tuples, frozen lists and maps too): how a value restored from a
    pickle or a deep copy gets back what numpy's own pickling and copying drop (they give writeable arrays)."""
    if isinstance(v, _AsBytes):  # copy.copy hands the state over as it was reduced
        return v.a
    if isinstance(v, np.ndarray):
        # one locked already (a copy.copy's, or protocol 5's, which gives a read-only array back over bytes) is kept:
        # copying it again made copy.copy(model) 4× slower, a Dask worker's records a second copy
        return v if _is_locked(v) else locked(v)
    if isinstance(v, FrozenMap):
        return FrozenMap({k: _relocked(x) for k, x in v._items.items()})
    if isinstance(v, FrozenList):
        return FrozenList(_relocked(x) for x in v)
    if type(v) is tuple:
        return tuple(_relocked(x) for x in v)
    if isinstance(v, tuple) and hasattr(type(v), "_make"):
        return type(v)._make(_relocked(x) for x in v)
    return v


def _array_of_bytes(data: bytes, dtype: str, shape: tuple[int, ...]) -> np.ndarray:
    """A locked array over ``data`` itself (no copy): how a :class:`Relocked` value's arrays come back."""
    return np.frombuffer(data, dtype=np.dtype(dtype)).reshape(shape)


class _AsBytes:
    """A locked array in a :class:`Relocked` value's state, pickled (and deep-copied) as its bytes: they come back as
    a locked array over them, where numpy's own pickling below protocol 5 (and its deep copy) gives a writeable array
    owning its memory, which locking had to copy again (pickle.loads of a 24 MB Record took ten times as long)."""

    __slots__ = ("a",)

    def __init__(self, a: np.ndarray) -> None:
        self.a = a

    def __reduce__(self) -> tuple:
        a, base = self.a, _bytes_base(self.a)
        # the bytes under a locked array that covers them (a contiguous view of all of them starts at their start)
        data = base if base is not None and len(base) == a.nbytes and a.flags.c_contiguous else a.tobytes()
        return _array_of_bytes, (data, a.dtype.str, a.shape)


def _bytes_base(a: np.ndarray) -> bytes | None:
    """The ``bytes`` object under ``a`` (through its bases), or None."""
    base = a.base
    while isinstance(base, np.ndarray):
        base = base.base
    return base if type(base) is bytes else None


class Relocked:
    """A base of the immutable values that hold arrays: restored from a pickle (a process pool, a Dask worker) or by
    ``copy.deepcopy``, their arrays are :func:`locked` again (numpy restores an array writeable, and a frozen
    dataclass takes its fields back as they come, so ``copy.deepcopy(model).theta[0] = 5`` edited a frozen value).
    Below pickle's protocol 5 (and in copies) a field that is a locked array travels as its bytes (:class:`_AsBytes`),
    which come back locked without a copy; protocol 5 pickles a read-only array as bytes itself."""

    __slots__ = ()

    def __reduce_ex__(self, protocol: Any) -> Any:
        rv = super().__reduce_ex__(protocol)
        if protocol >= 5 or not (isinstance(rv, tuple) and len(rv) > 2 and isinstance(rv[2], dict)):
            return rv
        state = {k: _AsBytes(v) if isinstance(v, np.ndarray) and _plain_locked(v) else v for k, v in rv[2].items()}
        return (*rv[:2], state, *rv[3:])

    def __setstate__(self, state: Any) -> None:
        if isinstance(state, tuple):  # (__dict__, __slots__ values) of a class with slots
            state = {**(state[0] or {}), **(state[1] or {})}
        for k, v in state.items():
            object.__setattr__(self, k, _relocked(v))


def _plain_locked(a: np.ndarray) -> bool:
    """A locked array (:func:`_is_locked`) of numbers (or times), whose dtype its text names in full."""
    return a.dtype.kind in "biufcmM" and _is_locked(a)


def frozen(a: object, dtype: type = float) -> np.ndarray:
    """A read-only copy of ``a`` (:func:`locked`): how every immutable value in graybox stores its arrays."""
    return locked(np.asarray(a, dtype=dtype))


def _is_pandas(x: object) -> bool:
    """A pandas DataFrame or Series (told without importing pandas: `import graybox` stays light)."""
    return type(x).__module__.startswith("pandas") and type(x).__name__ in ("DataFrame", "Series")


def _is_object_array(x: object) -> bool:
    """An object array: read-only, but owning its memory (no bytes buffer holds objects), so a reader could make it
    writeable again (:func:`locked`); handed out fresh, as a table is."""
    return isinstance(x, np.ndarray) and x.dtype.hasobject


def _holds_pandas(x: object, _seen: set | None = None) -> bool:
    """Whether ``x`` is a pandas DataFrame or Series (or an object array) or holds one in its lists and tuples (a
    mapping inside is a FrozenMap of its own, which hands out its own tables fresh); each list or tuple looked at once
    (one that holds itself, given to a FrozenMap directly, ends)."""
    if _is_pandas(x) or _is_object_array(x):
        return True
    if not isinstance(x, (list, tuple)):
        return False
    seen = set() if _seen is None else _seen
    if id(x) in seen:
        return False
    seen.add(id(x))
    return any(_holds_pandas(v, seen) for v in x)


def _fresh(x: object) -> object:
    """``x`` with each pandas table and object array in it (in its lists and tuples) a fresh copy; all else as it is
    (frozen)."""
    if _is_pandas(x):
        return x.copy(deep=True)  # type: ignore[attr-defined]
    if _is_object_array(x):
        return locked(x)
    if isinstance(x, FrozenList):
        return FrozenList(_fresh(v) for v in x)
    if isinstance(x, list):
        return [_fresh(v) for v in x]
    if isinstance(x, tuple):
        items = [_fresh(v) for v in x]
        return type(x)._make(items) if hasattr(type(x), "_make") else type(x)(items)
    return x


class FrozenMap(Mapping):
    """A read-only mapping that pickles: how every immutable value in graybox stores a mapping field.

    ``types.MappingProxyType`` is read-only too but cannot be pickled (nor copied), so a ParetoSet, a
    GridRun or ResidualTests holding one could not travel to a process pool or be ``copy.deepcopy``-ed.
    """

    __slots__ = ("_items", "_tables")

    def __init__(self, items: Any = ()) -> None:
        d = dict(items)
        object.__setattr__(self, "_items", d)
        # the keys whose values are or hold (in lists and tuples) a pandas table, handed out fresh at each read
        object.__setattr__(self, "_tables", frozenset(k for k, v in d.items() if _holds_pandas(v)))

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"a {type(self).__name__} cannot be changed")

    def __getitem__(self, key: Any) -> Any:
        x = self._items[key]
        # a pandas table cannot be made read-only (a new column, .loc …): each read is a fresh copy, as FrozenFrame's,
        # a table inside a list or tuple too (the rest of that value, frozen already, shared)
        return _fresh(x) if key in self._tables else x

    def __iter__(self):
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._items!r})"

    def __reduce__(self):
        return (type(self), (self._items,))


#: Deepest nesting of plain values (lists in lists …) a graybox value keeps and a file carries: far beyond any
#: real use, and far within Python's recursion limit, which a deeper value (or one that holds itself) would hit.
MAX_NESTING = 100


class FrozenList(list):
    """A read-only list: how an immutable graybox value keeps a list it was given (a Dataset's ``extra``).

    A list still to its reader (equal to the list given, ``isinstance(x, list)``), it refuses every change;
    it pickles and copies as itself (a list's own pickling would rebuild it by appending).
    """

    __slots__ = ()

    def _refuse(self, *args: Any, **kwargs: Any) -> Any:
        raise TypeError(f"a {type(self).__name__} cannot be changed (it is part of an immutable value): change a copy, "
                        "list(x)")

    append = extend = insert = remove = pop = clear = sort = reverse = _refuse
    __setitem__ = __delitem__ = __iadd__ = __imul__ = _refuse

    def __reduce__(self):
        return (type(self), (list(self),))

    def __reduce_ex__(self, protocol: Any):
        return self.__reduce__()

    def __copy__(self) -> "FrozenList":
        return self

    def __deepcopy__(self, memo: dict) -> "FrozenList":
        import copy

        return type(self)(copy.deepcopy(list(self), memo))


def frozen_value(v: object, name: str, _depth: int = 0, _open: frozenset = frozenset(),
                 _done: dict | None = None, *, numbers_as_arrays: bool = False) -> object:
    """A read-only copy of a plain value a caller gave (``name`` says which, for the message): arrays frozen
    (their dtype kept), lists :class:`FrozenList`, tuples (named ones keep their type) and sets their frozen items,
    mappings :class:`FrozenMap`, all the way down; anything else (a number, a str, a graybox value, a function) as
    it is. Every array is copied, a read-only one too (its owner could make it writeable again); a pandas
    DataFrame or Series is copied, and a :class:`FrozenMap` holding one gives each reader a fresh copy (a table
    cannot be made read-only). ``numbers_as_arrays`` (a bootstrap's options and decision): a list or plain tuple
    of numbers (no bools) becomes a read-only float array (its θ), any other list a tuple. A value held in several places is frozen once and stays shared (as
    ``copy.deepcopy`` keeps it): the cost is linear in the distinct values, not in the paths to them.

    ``ValueError`` naming ``name`` for a value nested deeper than :data:`MAX_NESTING` levels or one that holds itself.
    """
    if _is_pandas(v):
        return v.copy(deep=True)  # type: ignore[attr-defined]
    if not isinstance(v, (np.ndarray, list, tuple, set, frozenset, Mapping)):
        return v
    if (numbers_as_arrays and (isinstance(v, list) or type(v) is tuple) and v
            and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v)):
        return frozen(v)
    # id → (the value, its frozen copy, its height in nested containers); the value is kept so that its id is not
    # reused by another while the walk runs (a mapping may make its values when asked, temporaries)
    done: dict = {} if _done is None else _done
    if isinstance(v, np.ndarray):  # an array held twice frozen once too (one copy, still shared)
        if id(v) not in done:
            done[id(v)] = (v, frozen(v, v.dtype), 0)  # a read-only array too: its owner can make it writeable
        return done[id(v)][1]
    if id(v) in done:  # frozen already, by another path to it
        _, out, height = done[id(v)]
        if _depth + height > MAX_NESTING:  # met here, deeper than where it was frozen
            raise ValueError(f"{name} is nested deeper than {MAX_NESTING} levels (lists or mappings inside each other)")
        return out
    if id(v) in _open:
        raise ValueError(f"{name} holds itself (a list or mapping inside itself has no copy and no file)")
    if _depth >= MAX_NESTING:
        raise ValueError(f"{name} is nested deeper than {MAX_NESTING} levels (lists or mappings inside each other)")
    inner = _open | {id(v)}
    below = 0  # the height of the deepest container inside

    def freeze(x: object, where: str) -> object:
        nonlocal below
        fx = frozen_value(x, where, _depth + 1, inner, done, numbers_as_arrays=numbers_as_arrays)
        if id(x) in done:
            below = max(below, done[id(x)][2])
        return fx

    out: object
    if isinstance(v, Mapping):
        out = FrozenMap({k: freeze(x, f"{name}[{k!r}]") for k, x in v.items()})
    else:
        items = [freeze(x, f"{name}[{i}]") for i, x in enumerate(v)]
        if isinstance(v, list):
            out = tuple(items) if numbers_as_arrays else FrozenList(items)
        elif isinstance(v, (set, frozenset)):
            out = frozenset(items)
        elif hasattr(type(v), "_make") and hasattr(type(v), "_fields"):  # a named tuple: its type, its items frozen
            out = type(v)._make(items)
        else:
            out = tuple(items) if type(v) is tuple else v  # another tuple type: kept as given (immutable itself)
    done[id(v)] = (v, out, below + 1)
    return out


class FrozenFrame:
    """A dataclass field holding a pandas DataFrame: how every immutable value in graybox stores its tables.

    A DataFrame cannot be made read-only (``.loc``, ``.iloc``, new columns and ``inplace=``
    methods all change it), so the value keeps a copy of the frame it was made with and every read
    of the field gives a fresh copy: what a user does to the table they get never changes the result
    (nor, through it, what its methods read). Declared as the field's default
    (``table: pd.DataFrame = FrozenFrame()``), it gives the field no default value; the class keeps
    its own checks in ``__post_init__``.
    """

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, obj: object, objtype: type | None = None) -> Any:
        if obj is None:  # the class's own attribute: dataclasses reads "no default" from this
            raise AttributeError(self.name)
        try:
            df = obj.__dict__[self.name]
        except KeyError:
            raise AttributeError(f"{type(obj).__name__} has no {self.name} yet") from None
        return df.copy(deep=True)

    def __set__(self, obj: object, value: object) -> None:
        import pandas as pd  # only where a table is made: `import graybox` stays light

        if not isinstance(value, pd.DataFrame):
            raise TypeError(f"{type(obj).__name__}: {self.name} must be a pandas DataFrame, got "
                            f"{reprlib.repr(value)} ({type(value).__name__})")
        obj.__dict__[self.name] = value.copy(deep=True)


def _is_integer(value: object) -> bool:
    return _is_number(value) and bool(np.isfinite(value)) and float(value) == round(float(value))  # type: ignore


def check_frame_columns(table: Any, kinds: Mapping[str, str], owner: str) -> None:
    """``ValueError``/``TypeError`` naming ``owner``'s table and the column, for a table its methods cannot read.

    For a result's ``__post_init__`` (a table built by hand, edited with ``dataclasses.replace`` or loaded from a
    hand-edited file): every column label once, and each column of ``kinds`` that the table has of its kind,
    ``"real"`` (real numbers, NaN and inf included, never text, bools or arrays), ``"int"`` (integers, or reals
    of integer value) or ``"bool"`` (True or False). Columns it lacks are the caller's to require.
    """
    labels = list(table.columns)
    twice = sorted({str(c) for c in labels if labels.count(c) > 1})
    if twice:
        raise ValueError(f"{owner}: the table's column(s) {twice} appear more than once")
    rules = {"real": ("iuf", _is_number, "real numbers (NaN or inf where a row has none)"),
             "int": ("iu", _is_integer, "integers"), "bool": ("b", _is_bool, "True or False")}
    for c, kind in kinds.items():
        if c not in table.columns:
            continue
        col = table[c]
        dtype_kinds, fits, what = rules[kind]
        if isinstance(col.dtype, np.dtype) and col.dtype.kind in dtype_kinds:
            continue  # a NumPy column of the kind: every entry fits
        bad = next((v for v in col if not fits(v)), fits)
        if bad is not fits:  # text, an array, a bool where a number is meant, a missing value (pd.NA) ...
            raise TypeError(f"{owner}: the table's column {c!r} must hold {what}, got {reprlib.repr(bad)} "
                            f"({type(bad).__name__}, column dtype {col.dtype})")


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


# -- the fields of a result object ---------------------------------------------------------------
#: An annotation's test: (types passed at once, the test for any other type, "what is accepted").
#: The exact types make the usual case a set look-up: results are built often (a Decision per decision).
_Rule = tuple[frozenset, Callable[[object], bool], str]

_SIMPLE_RULES: dict[object, _Rule] = {
    # a result's figure: any real, NaN and inf included (a diverged J_S is inf, λ1 of no weight NaN)
    float: (frozenset({float, int, np.float64}), _is_number, "a real number"),
    int: (frozenset({int}), lambda v: isinstance(v, (int, np.integer)) and not _is_bool(v), "an integer"),
    bool: (frozenset({bool, np.bool_}), _is_bool, "True or False"),
    str: (frozenset({str}), lambda v: isinstance(v, str), "a string"),
    # an array, or the list or tuple the class freezes into one (Selection's subset_rss defaults to ())
    np.ndarray: (frozenset({np.ndarray, list, tuple}), lambda v: isinstance(v, (np.ndarray, list, tuple)),
                 "an array (a NumPy array, list or tuple)"),
    type(None): (frozenset({type(None)}), lambda v: False, "None"),
}

#: class -> ((field, types passed at once, test, what), ...): each dataclass's annotations, resolved once.
_FIELD_RULES: dict[type, tuple[tuple[str, frozenset, Callable[[object], bool], str], ...]] = {}


def _rule(hint: object) -> _Rule | None:
    """The test of a resolved annotation, or None where it is not checked (Any, Literal, a type variable …)."""
    if hint in _SIMPLE_RULES:
        return _SIMPLE_RULES[hint]
    origin = typing.get_origin(hint)
    if origin is typing.Union or origin is types.UnionType:
        rules = [_rule(h) for h in typing.get_args(hint)]
        if any(r is None for r in rules):
            return None
        tests = tuple(r[1] for r in rules)  # type: ignore[index]
        return (frozenset().union(*(r[0] for r in rules)),  # type: ignore[index]
                lambda v: any(t(v) for t in tests), " or ".join(r[2] for r in rules))  # type: ignore[index]
    # a container (tuple[...], Mapping[...], list[...]): its outer type only, the items are the class's to check
    cls = origin if origin is not None else hint
    if isinstance(cls, type) and cls is not object:
        return frozenset({cls}), lambda v: isinstance(v, cls), f"a {cls.__name__}"
    return None


def _field_rules(cls: type) -> tuple[tuple[str, frozenset, Callable[[object], bool], str], ...]:
    """The rules of ``cls``'s init fields, from its annotations (strings under postponed evaluation).

    An annotation that does not resolve (a name imported for type checkers only) leaves its field unchecked.
    """
    fields = [f for f in dataclasses.fields(cls) if f.init]
    try:
        hints: dict[str, Any] = typing.get_type_hints(cls)
    except Exception:  # one unresolvable name: resolve field by field, as get_type_hints would
        glob = vars(sys.modules[cls.__module__])
        hints = {}
        for f in fields:
            try:
                # the class's own annotation text, evaluated where the class was defined
                hints[f.name] = eval(f.type, glob) if isinstance(f.type, str) else f.type  # noqa: S307
            except Exception:
                continue
    out = []
    for f in fields:
        r = _rule(hints[f.name]) if f.name in hints else None
        if r is not None:
            out.append((f.name, *r))
    return tuple(out)


def check_fields(obj: object) -> None:
    """``TypeError`` naming the class, the field and what it takes, for a field of the wrong type.

    For a dataclass's ``__post_init__``, before its other checks: each field is checked against its
    annotation (``float``: a real number, NaN and inf included, never a bool or a string; ``int``: an
    integer, not a bool; ``np.ndarray``: an array, list or tuple, which the classes freeze into arrays;
    ``X | None``: None or X; a class: an instance; a container: its outer type; ``Any``, ``Literal``
    and the like: unchecked). Ranges are the class's own business. The annotations are resolved once
    per class.
    """
    cls = type(obj)
    rules = _FIELD_RULES.get(cls)
    if rules is None:
        rules = _FIELD_RULES[cls] = _field_rules(cls)
    for name, exact, test, what in rules:
        value = getattr(obj, name)
        if type(value) not in exact and not test(value):
            raise TypeError(f"{cls.__name__}: {name} must be {what}, got {reprlib.repr(value)} "
                            f"({type(value).__name__})")
