"""Short reprs for value types: one line that fits a log line, whatever the value holds.

A dataclass's default repr prints every field in full: the arrays of a run, the history of a
fit, every cell of a grid. :func:`short_repr` prints scalars and short strings as they are and
summarises the rest (an array by its shape, a long sequence by its length), so ``print(x)``,
``repr(x)`` in an f-string or a debugger's variable view stay readable.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

import numpy as np

__all__ = ["apart_digits", "beside", "bound_text", "level_texts", "listed", "percent_text", "point_texts",
           "range_text", "share_text", "short_repr", "summary", "LISTED"]

#: A field's text longer than this is summarised.
WIDTH = 48

#: The most values, points or phrases a message lists one by one, then says how many in all: 10⁴ levels outside a
#: range or without an equilibrium made messages of megabytes, which a notebook prints whole.
LISTED = 20


def listed(values: object) -> str:
    """Values (levels, points) for a message, as a list: all of them up to :data:`LISTED`, else the first ones
    and how many in all (``[0.5, 0.6, …] (50000 in all)``)."""
    items = list(values)  # type: ignore[call-overload]
    if len(items) <= LISTED:
        return str(items)
    return "[" + ", ".join(map(str, items[:LISTED])) + f", …] ({len(items)} in all)"


def percent_text(level: float) -> str:
    """A confidence level as a percentage with the digits it has: "95%", "97.5%", "99.9%" (``:.0%`` printed 0.975 as
    "98%" and 0.999 as "100%", a band no model has). Six significant digits (``%g``: a float32 0.95 is "95%", not
    "94.99999881%"), and as many more as keep a level strictly inside (0, 1) off "0%" and "100%"."""
    level = float(level)
    text = f"{100 * level:g}"
    if 0 < level < 1:
        for digits in range(7, 18):
            if 0 < float(text) < 100:
                break
            text = f"{100 * level:.{digits}g}"
        else:
            text = repr(100 * level)
    return text + "%"


def share_text(share: float) -> str:
    """A share (of draws, of runs) as a percentage: ``:.1%`` ("12.5%"), or as many significant digits as keep a
    share strictly between 0 and 1 off "0%" and "100%" where that reads them (``:.1%`` printed 1 run of 10 000 as
    "0.0%" and 9 995 as "100.0%", beside the words that some, or not all, are left out)."""
    share = float(share)
    if not 0 < share < 1:
        return f"{100 * share:g}%"
    text = f"{100 * share:.1f}"  # as shares were printed before
    if 0 < float(text) < 100:
        return text + "%"
    for digits in range(2, 18):
        text = f"{100 * share:.{digits}g}"
        if 0 < float(text) < 100:
            return text + "%"
    return f"{100 * share!r}%"


def level_texts(levels: np.ndarray) -> list[str]:
    """Levels of one input as text: ``%g``, with as many more digits as tell apart levels it would print alike
    (10000.01 and 10000.02 are both '10000' to six digits: an offset input's points or slices read as one).

    Parameters
    ----------
    levels : array_like
        The levels (any shape; read flat).

    Returns
    -------
    list of str
        One text per level, in order.
    """
    v = np.asarray(levels, float).ravel() + 0.0  # -0.0 is the level 0: "-0" names a level no one set
    distinct = np.unique(v).size
    # up to 16 digits, then repr: '%.17g' printed 0.3 beside 0.1 * 3 as '0.29999999999999999', below what it is
    for digits in range(6, 17):
        texts = [f"{x:.{digits}g}" for x in v]
        if len(set(texts)) >= distinct:
            return texts
    return [repr(float(x)) for x in v]


def exact_text(x: float) -> str:
    """A number as ``%g`` where that reads back as it, else with as many more significant digits as do: one value
    said alone, with no others to tell it from (a local model's ū 10000.01 printed '10000', as 10000.02 did). A text
    within a few units in the last place reads back as it: 0.1 * 3 is "0.3", not "0.30000000000000004" (``repr``),
    the rounding of the arithmetic that made the value. -0.0 is "0" (an input of -1 * 0.0 read "ū = -0")."""
    x = float(x) + 0.0
    if not np.isfinite(x):
        return f"{x:g}"
    for digits in range(6, 18):
        text = f"{x:.{digits}g}"
        if abs(float(text) - x) <= 4 * math.ulp(x):  # (np.spacing of the largest float is inf, and warns)
            return text
    return repr(x)


def range_text(low: float, high: float, digits: int = 4) -> str:
    """A range as ``[low, high]`` to ``digits`` significant digits, or with as many more as tell its ends apart
    (:func:`level_texts`) where those print alike: a signal from 10003.9 to 10020.9 read 'y in [1e+04, 1e+04]',
    as if it were constant."""
    a, b = f"{float(low):.{digits}g}", f"{float(high):.{digits}g}"
    if a == b and low != high:
        a, b = level_texts(np.array([low, high], float))
    return f"[{a}, {b}]"


def bound_text(x: float, value: float | None = None) -> str:
    """A bound as text: ``%g``, or as many more digits as keep ``value`` (said beside it) on its side of the printed
    bound (a band of 0.03059995 printed "0.0306" would put a J_SF of 0.0305999503 inside it; a band 0.175² is
    0.030625, not 0.030624999999999996)."""
    x = float(x)
    if value is None or not np.isfinite(value) or not np.isfinite(x) or float(value) == x:
        return f"{x:g}"  # a value at the bound is said at it as printed (repr was the only text "exactly at" 0.175²)
    side = np.sign(float(value) - x)
    for d in range(6, 18):
        text = f"{x:.{d}g}"
        if np.sign(float(value) - float(text)) == side:
            return text
    return repr(x)


def squared_unit(unit: str | None) -> str:
    """The unit of a squared error in ``unit`` as a suffix (" mlc²", " (m/s)²"), or "" for a record without one."""
    unit = str(unit or "").strip()
    if not unit:
        return ""
    # one word of letters (° and % too) takes the square as it is; any other (a digit or superscript, an operator,
    # a space) is bracketed: "m²" squared is not "m²²", "m3" not "m3²"
    if all(c.isalpha() or c in "°%" for c in unit) or _bracketed(unit):  # "(m/s)" is "(m/s)²", not "((m/s))²"
        return f" {unit}²"
    return f" ({unit})²"


def per_unit(unit: str | None, per: str | None) -> str:
    """The unit of ``unit`` per ``per`` (a gain: output unit per input unit) as text, "mlc/rpm", with a compound
    ``per`` bracketed ("Pa/(rad/s)", not "Pa/rad/s", which reads Pa·s/rad) and a missing side as 1; "" when
    neither is said."""
    unit, per = str(unit or "").strip(), str(per or "").strip()
    if not unit and not per:
        return ""
    if any(c in "/*·^" or c.isspace() for c in per) and not _bracketed(per):
        per = f"({per})"
    return f"{unit or '1'}/{per or '1'}"


def _bracketed(text: str) -> bool:
    """Whether ``text`` is one bracketed group: "(m/s)", not "(m)(s)" nor "(m)/s"."""
    depth = 0
    for i, c in enumerate(text):
        depth += (c == "(") - (c == ")")
        if depth < 0 or (depth == 0 and i < len(text) - 1):
            return False
    return depth == 0 and text.startswith("(")


def squared_text(value: float, unit: str | None, digits: int = 4) -> str:
    """A squared error as text with its unit (``squared_unit``): "1.158 mlc²"; NaN and inf without one."""
    value = float(value)
    return f"{value:.{digits}g}" + (squared_unit(unit) if np.isfinite(value) else "")


#: Relative difference below which two figures of a table may print alike: a report's tie (models whose J_S agree to
#: it share a rank).
APART_RTOL = 1e-8


def apart_digits(values: np.ndarray, low: int = 6, high: int = 17) -> int:
    """Significant digits (``%.{d}g``) for a table's column of ``values``: ``low``, or as many more as print every two
    values that differ by more than :data:`APART_RTOL` (relative) apart (two models ranked 1 and 2 read "0.8109"
    both at 4 digits).

    Parameters
    ----------
    values : ndarray
        The column's numbers (NaN and infinities are left out).
    low, high : int
        The fewest and the most digits.

    Returns
    -------
    int
    """
    v = np.unique(np.asarray(values, float))
    v = v[np.isfinite(v)]
    a, b = v[:-1], v[1:]
    apart = (b - a) > APART_RTOL * np.maximum(np.abs(a), np.abs(b))
    a, b = a[apart], b[apart]  # neighbours suffice: rounding keeps the order
    for d in range(low, high):
        if all(f"{x:.{d}g}" != f"{y:.{d}g}" for x, y in zip(a, b)):
            return d
    return high


def beside(value: float, ref: float, digits: int = 4) -> str:
    """``value`` as text to ``digits`` significant digits, or as many more as keep it on its side of ``ref`` as
    :func:`bound_text` prints it (a J_SF just outside a band B = 0.0306 reads 0.03060003, not 0.0306: 'no model
    has J_SF ≤ B = 0.0306: the smallest reached is 0.0306' contradicts itself).

    Parameters
    ----------
    value, ref : float
        The value said, and the bound it is said beside (printed with ``bound_text(ref, value)``).
    digits : int
        Significant digits when they suffice.

    Returns
    -------
    str
    """
    value, ref = float(value), float(ref)
    shown = float(bound_text(ref, value))
    side = np.sign(value - ref)
    for d in range(digits, 18):
        text = f"{value:.{d}g}"
        if not np.isfinite(value) or np.sign(float(text) - shown) == side:
            return text
    return repr(value)


def point_texts(ubar: np.ndarray) -> list[str]:
    """Input points as text, each told apart from the others (:func:`level_texts` per input): ``"1000.5"`` for a
    point of one input, ``"(1, 10000.01)"`` for a row ū = (ū_1, …, ū_m).

    Parameters
    ----------
    ubar : array_like, shape (M,) or (M, m)
        The points.

    Returns
    -------
    list of str
        One text per point, in order.
    """
    ub = np.asarray(ubar, float)
    if ub.ndim <= 1:
        return level_texts(ub)
    cols = [level_texts(ub[:, c]) for c in range(ub.shape[1])]
    return ["(" + ", ".join(col[i] for col in cols) + ")" for i in range(ub.shape[0])]


def summary(value: object, width: int = WIDTH) -> str:
    """A short text for one value: itself when short, else its kind and size.

    Parameters
    ----------
    value : object
        Any value.
    width : int
        Longest text kept as is (characters).
    """
    if isinstance(value, np.ndarray):
        if value.size <= 4 and value.ndim <= 1:
            return np.array2string(value, precision=4, separator=", ")
        return f"<array {'×'.join(map(str, value.shape)) or 'scalar'} {value.dtype}>"
    if isinstance(value, float):
        return f"{value:.6g}"
    text = repr(value)
    if len(text) <= width:
        return text
    if isinstance(value, str):
        return repr(value[: width - 5] + "…")
    if isinstance(value, Mapping):
        return f"<{type(value).__name__} of {len(value)} keys>"
    if isinstance(value, (list, tuple)):
        return f"<{type(value).__name__} of {len(value)}>"
    if hasattr(value, "shape") and hasattr(value, "columns"):  # a DataFrame, without importing pandas
        return f"<{type(value).__name__} {value.shape[0]}×{value.shape[1]}>"
    first = text.split("(", 1)[0]
    return f"<{first if first.isidentifier() else type(value).__name__}>"


def short_repr(self: object) -> str:
    """``ClassName(field=summary, …)`` over a dataclass's repr fields: use as ``__repr__ = short_repr``."""
    parts = [f"{f.name}={summary(getattr(self, f.name))}" for f in dataclasses.fields(self) if f.repr]  # type: ignore[arg-type]
    return f"{type(self).__name__}({', '.join(parts)})"
