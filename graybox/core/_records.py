"""Measured data as immutable values: dynamic records and static points.

A :class:`Record` is one experiment (input and output sampled at ``Ts``). A
:class:`StaticPoints` holds measured steady states (ū_i, ȳ_i). Both validate at
construction, so everything downstream may assume finite, equally long arrays.

Several inputs: ``u`` of shape (N, m) with ``input_names`` (default ``u1 … um``). A single
input stays 1-D, shape (N,), named ``"u"`` unless named otherwise, so that every
single-input path is exactly what it was.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from typing import Any, Mapping, Sequence

import numpy as np

from ._reprs import listed, range_text
from ._terms import check_input_names, default_input_names, missing_input_hint, transient_source
from ._validation import (SAMPLES, Relocked, as_1d_finite, locked, check_int, check_ordered, check_per_point,
                          check_real, check_str, float_array, frozen_value, refuse_flags, refuse_non_real, short_value,
                          warn)

__all__ = ["Record", "StaticPoints", "StaticRangeWarning", "warn_static_range"]


def is_frame(x: object) -> bool:
    """Whether ``x`` is a pandas DataFrame (told without importing pandas: ``import graybox`` stays fast)."""
    return type(x).__module__.split(".")[0] == "pandas" and hasattr(x, "columns") and hasattr(x, "iloc")


def _is_series(x: object) -> bool:
    """Whether ``x`` is a pandas Series (e.g. one row of a DataFrame: ``df.iloc[0]``), told without pandas."""
    return type(x).__module__.split(".")[0] == "pandas" and hasattr(x, "index") and getattr(x, "ndim", 0) == 1


def labelled_point(x: object, names: Sequence[str]) -> bool:
    """Whether ``x`` is a pandas Series whose index labels are the inputs ``names`` (a DataFrame's row), or a dict
    of one number per input by name: one point ū by what it says, never levels of one input, whatever its values."""
    if isinstance(x, Mapping):
        return (len(x) == len(names) and sorted(str(c) for c in x) == sorted(names)
                and all(np.ndim(v) == 0 for v in x.values()))
    return (_is_series(x) and len(x) == len(names)  # type: ignore[arg-type]
            and sorted(str(c) for c in x.index) == sorted(names))  # type: ignore[attr-defined]


def _levels_by_name(x: Mapping[Any, Any], name: str) -> object:
    """Steady levels given as a dict by input name (``{"flow": 7.0, "inlet": 20.0}``, as ``GainBounds`` takes
    its bounds): the pandas Series (one number each: one point ū) or DataFrame (a sequence each) that
    :func:`frame_inputs` reads by name. The levels are paired by position; pandas Series among them must share one
    index (the same labels in the same order), else ``ValueError`` naming them: pandas would align them by label,
    and reading them by position paired levels their indexes put on other rows."""
    import pandas as pd  # only for a dict: `import graybox` stays fast

    if not all(isinstance(k, str) for k in x):
        raise TypeError(f"{name}: a dict of input levels is keyed by the inputs' names (str), got keys {list(x)!r}")
    series = {k: v for k, v in x.items() if _is_series(v)}
    if series:
        first, *rest = series
        other = next((k for k in rest if not series[k].index.equals(series[first].index)), None)
        if other is not None:
            def shown(k):
                return short_value(list(series[k].index))
            raise ValueError(f"{name}: the Series of {first!r} and {other!r} have different indexes ({shown(first)} "
                             f"and {shown(other)}); the levels are paired by position, not aligned by label: give them "
                             f"one index ({other!r} reindexed by the index of {first!r}) or plain sequences")
    given = {k: np.asarray(v, dtype=object) for k, v in x.items()}
    for k, v in given.items():  # a matrix of levels would be flattened row by row into points no one gave
        if v.ndim > 1:
            raise ValueError(f"{name}[{k!r}] must be one level or a 1-D sequence of levels, got shape {v.shape}")
    # each level a number, said by its key (a bool, None or text would be refused later as the whole Series)
    cols = {k: np.array([check_real(e, f"{name}[{k!r}]") for e in v.reshape(-1)]) for k, v in given.items()}
    if all(np.ndim(v) == 0 for v in x.values()):
        return pd.Series([c[0] for c in cols.values()], index=list(cols))
    sizes = {k: len(v) for k, v in cols.items()}
    if len(set(sizes.values())) > 1:
        raise ValueError(f"{name}: the dict gives the inputs different numbers of levels {sizes}: one level each "
                         "(one point ū) or equally many (one point per position)")
    return pd.DataFrame(cols)


def points_by_name(x: object, names: Sequence[str] | None, name: str) -> tuple[object, Sequence[str] | None]:
    """Static levels ``x`` and their inputs' names: a dict keyed by input name (``{"flow": [1.0, 2.0], "inlet":
    [20.0, 25.0]}``, as static curves take levels) becomes the DataFrame :func:`frame_inputs` reads by name, its keys
    the names where ``names`` is None, and ``ValueError`` where ``names`` names other inputs; anything else as it is."""
    if not isinstance(x, Mapping):
        return x, names
    if not x:  # not "no input column (shape (1, 0))", as the one point of no levels would be read
        raise ValueError(f"{name}: the dict names no input; key each input's levels by its name")
    levels = _levels_by_name(x, name)
    frame = levels.to_frame().T if _is_series(levels) else levels  # one number each: one point
    keys = tuple(x)
    if names is not None and (isinstance(names, str) or set(keys) != set(names)):
        raise ValueError(f"{name}: the dict's keys {list(keys)!r} are not the input_names {names!r}: name each input "
                         "once, as a key or in input_names (both: the same names)")
    return frame, (keys if names is None else names)


def frame_names(x: object, names: Sequence[str] | None, name: str, *, column: bool = False
                ) -> Sequence[str] | None:
    """The inputs' names of samples or levels ``x``: ``names`` where given (a DataFrame then read by name where its
    columns are those names, by position where they name none); else a DataFrame's column labels where each is text
    (``flow``, ``inlet``), as a dict's keys are (:func:`points_by_name`), not pandas' default 0, 1, … nor other
    numbers; ``column``: a Series whose index labels are no text (a column, not a row) is samples or levels of one
    input, whose text name (``df["flow"]``) then names it as ``df[["flow"]]``'s column does; None (the default names
    ``u`` / ``u1 … um``) for anything else. Text labels beside others (``0`` and ``"flow"``) are refused
    (``ValueError``, prefixed by ``name``): read by position, the names said were dropped."""
    if (names is None and column and _is_series(x) and isinstance(getattr(x, "name", None), str)
            and getattr(x.index, "inferred_type", "") != "string"):  # type: ignore[attr-defined]
        return (x.name,)  # type: ignore[attr-defined]  (labels of text: a row, one point by its labels)
    if names is not None or not is_frame(x):
        return names
    labels = list(x.columns)  # type: ignore[attr-defined]
    text = [c for c in labels if isinstance(c, str)]
    if text and len(text) < len(labels):
        other = [c for c in labels if not isinstance(c, str)]
        raise ValueError(f"{name}: the DataFrame's columns {labels!r} name some inputs ({text!r}) "
                         f"and not others ({other!r}): name every input column by text (df.rename(columns=...)), or "
                         "give input_names= to read the columns by position")
    return tuple(labels) if text else None


def _named_levels(x: object, names: Sequence[str] | None, name: str) -> tuple[object, Sequence[str] | None, bool]:
    """Static levels ``x`` as :func:`as_input_array` reads them (a dict's keys its names: :func:`points_by_name`), their
    inputs' names, and whether those names are a frame's own columns (:func:`frame_names`), said so in messages."""
    x, given = points_by_name(x, names, name)
    named = frame_names(x, given, name, column=True)  # a frame's columns name its inputs, as a dict's keys do
    return x, named, named is not given


#: What an input name given by a DataFrame's column is called in messages.
_COLUMNS_NAME = "the DataFrame's column names, its inputs' names (input_names= names them otherwise, read by position)"


def output_series(y: object) -> object | None:
    """``y`` when it is a pandas Series with a name (``df["p"]``), else None: its column is no input."""
    label = getattr(y, "name", None) if _is_series(y) else None
    return y if isinstance(label, str) and label else None


def _same_samples(a: object, b: object) -> bool:
    """Whether two signals hold the same samples (the output's column passed again as an input)."""
    try:
        return np.array_equal(np.asarray(a, dtype=float), np.asarray(b, dtype=float), equal_nan=True)
    except (TypeError, ValueError):
        return False


def _varies(y: object) -> bool:
    """Whether a signal takes more than one value (False for what is no array of numbers: said where it is read)."""
    try:
        a = np.asarray(y, dtype=float)
    except (TypeError, ValueError):
        return False
    return a.size > 1 and bool(np.any(a != a.flat[0]))


def _time_step(x: object) -> float | None:
    """The step of a column that looks like time or a count of samples (at least 3 values, strictly increasing, in
    steps equal to 1e-6 of theirs: a clock's seconds written out keep that), else None. Numbers only: dates and text
    are refused as such where they are read (:func:`~graybox.core._validation.refuse_non_real`)."""
    if getattr(getattr(x, "dtype", None), "kind", "") not in "iuf":
        return None
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        return None
    if a.ndim != 1 or a.size < 3 or not np.all(np.isfinite(a)):
        return None
    d = np.diff(a)
    step = float(np.mean(d))
    return step if d.min() > 0 and d.max() - d.min() <= 1e-6 * step else None


def _refuse_time_column(x: Any, cols: list, labels: list[str], expected: Sequence[str], name: str) -> None:
    """``ValueError`` naming the one column of the DataFrame of samples ``x`` that names no input and looks like time
    (:func:`_time_step`) where the others do not: read by position it was an input, and the record failed later, on
    the inputs' names. Two or more such columns are ramps (a synthetic test's inputs), none of them told from time."""
    if not all(getattr(k, "kind", "") in "iuf" for k in x.dtypes):
        return  # a column of dates or text is refused as such (refuse_non_real), beside whatever ramps
    steps = [_time_step(x[c]) for c in cols]
    found = [i for i, step in enumerate(steps) if step is not None]
    if len(found) == 1 and labels[found[0]] not in expected:
        label, step = labels[found[0]], steps[found[0]]
        rest = [l for l in labels if l != label]
        # a count in steps of 1 (a sample number, a saved index) says nothing of seconds: the period is the user's
        period = ("with the sampling period (s) as Ts=" if step == 1 and x[cols[found[0]]].dtype.kind in "iu" else
                  f"with its step as Ts={step:g} if it is seconds")
        # the columns named as the inputs the call reads, which every entry takes (a model's free run has no
        # input_names, and a frame's default columns 0, 1 are no identifiers to give it)
        named = f"df.set_axis({list(expected)!r}, axis=1)"
        if all(l.isidentifier() for l in labels):
            named = f"input_names={labels!r} (where the call takes them) or {named}"
        raise ValueError(f"{name}: column {label!r} of the DataFrame's columns {labels} looks like time or a count of "
                         f"samples (strictly increasing in even steps of {step:g}), which is no input: pass the input "
                         f"columns only, e.g. df[{rest!r}], {period} (graybox.load_record_csv(path, u=..., y=..., "
                         f"time={label!r}) reads a file's time column so); if it is an input that ramps, name the "
                         f"columns as the inputs: {named}")


def frame_inputs(x: object, names: Sequence[str] | None, name: str, output: object = None, *,
                 steady: bool = False, samples: bool = False, own: bool = False) -> object:
    """A DataFrame of inputs with its columns in the order of ``names`` (the one rule for every input).

    Columns named exactly as the inputs (every name once, no other column) are read by name, reordered as
    needed; columns named as none of them (e.g. pandas' default 0, 1, …) are read by position. Anything
    between would be read by position with some named column landing on another input, or a column
    dropped unseen: ``ValueError`` naming the columns. ``names`` None: the default names
    (``u`` for one column, ``u1 … um`` for m). A pandas Series (one point ū, a DataFrame's row
    ``df.iloc[k]``) is read so by its index labels; one named as an input whose labels are none (a column,
    ``df["speed"]``) is that input's samples or levels, read as the one-column DataFrame it came from. Anything else is returned as it is. ``output``:
    the output: a named Series (:func:`output_series`), whose column (its name, its samples) no input may be, neither
    a column of ``x`` nor ``x`` itself; or a record's output samples given without a name (array_like), which no
    column of a frame of two or more may hold (one input passed as the output is a caller's own choice). Static
    points pass a named Series or None: a few ȳ may equal an input's levels by the plant's own law (a unit gain).
    ``steady``: ``x`` is steady-state levels, where the transient inputs among ``names`` rest at 0 and may be left
    out (:func:`~graybox.core._transient.steady_levels` fills them in): columns naming every other input are read
    by name too, in their order. ``samples``: ``x`` is samples in time (a record's, a free run's), where the one
    column that looks like time or a count of samples (strictly increasing in even steps; the others not) is refused
    unless it names an input, naming it: read by position it would be an input. ``own``: ``names`` are the frame's
    own columns (:func:`frame_names`), which name no input to that check (a time column is no input for its name).
    """
    by_name = steady and isinstance(x, Mapping)
    if by_name:
        x = _levels_by_name(x, name)  # type: ignore[arg-type]
    series = _is_series(x)
    if not (series or is_frame(x)):
        return x
    named = output_series(output)
    label = None if named is None else named.name  # type: ignore[attr-defined]
    if series and label is not None and getattr(x, "name", None) == label and _same_samples(x, output):
        raise ValueError(f"{name}: {label!r} is both the input and the output; pass the input column as u")
    if series and getattr(getattr(x.index, "dtype", None), "kind", "O") in "iufcmMb":
        # labels of numbers or times (a RangeIndex of 10⁶ samples): none is an input's name, an identifier, so none
        # is read one by one (as a DataFrame's columns are not), nor are N default names built to meet them
        said = getattr(x, "name", None)
        if isinstance(said, str) and (said in names if names is not None else _default_name(said, len(x))):
            return frame_inputs(x.to_frame(), names, name, output, steady=steady)  # a column, read as below
        return x
    cols = list(x.index if series else x.columns)
    labels = [str(c) for c in cols]
    what = "dict's keys" if by_name else "Series' index labels" if series else "DataFrame's columns"
    # read by position, the output would be an input (a Series' labels are samples'); a column named as the
    # output's Series but holding other samples (another frame's signal of that name) is an input like any
    for out in ("y", *([label] if label not in (None, "y") else [])):
        if not series and out in labels and (out == "y" or _same_samples(x[cols[labels.index(out)]], output)):
            whose = "the output's name, which no input may have" if out == "y" else "the output's column"
            rest = [c for c in labels if c != out]
            raise ValueError(f"{name}: the {what} {labels} hold {out!r}, {whose}: pass the input columns only, e.g. "
                             f"df.drop(columns={out!r}) or df[{rest!r}] (a time column is no input: give its step "
                             "as Ts=)")
    if not series and named is None and output is not None and len(cols) > 1 and _varies(output):
        # the output's column under another name, y given as an array (df["p"].to_numpy(), np.loadtxt's column): no
        # name to tell it by, its samples do (where the output moves: one held where an input is held is a rest)
        same = [l for c, l in zip(cols, labels) if _same_samples(x[c], output)]
        if same:
            rest = [c for c in labels if c not in same]
            raise ValueError(f"{name}: the {what} {labels}: column {same[0]!r} holds the output's samples, which no "
                             f"input may be: pass the input columns only, e.g. df[{rest!r}] (a time column is no "
                             "input: give its step as Ts=)")
    expected = tuple(default_input_names(len(cols)) if names is None else names)
    if samples and not series and len(cols) > 1:
        _refuse_time_column(x, cols, labels, () if own else expected, name)
    known = frozenset(expected)  # a Series of N samples meets N default names (u1 … uN): `in` a tuple made it N²
    hits = [c for c in labels if c in known]
    if series and not hits and isinstance(getattr(x, "name", None), str) and x.name in expected:
        # a column of a frame (df["speed"]): its name is the input's, its labels the samples'; read as the
        # one-column frame it came from, by name (its values are that input's levels, never one point)
        return frame_inputs(x.to_frame(), names, name, output, steady=steady)
    if not hits:
        if by_name:  # a dict says its levels by name: none read by position
            raise ValueError(f"{name}: the {what} {labels} name none of the inputs {list(expected)}")
        return x
    if len(labels) == len(expected) and sorted(labels) == sorted(expected):
        order = [labels.index(n) for n in expected]
        return x.iloc[order] if series else x[[cols[i] for i in order]]
    others = [n for n in expected if transient_source(n, expected) is None]
    if steady and len(others) < len(expected) and len(labels) == len(others) and sorted(labels) == sorted(others):
        order = [labels.index(n) for n in others]
        return x.iloc[order] if series else x[[cols[i] for i in order]]
    extra = [c for c in labels if c not in expected]
    missing = [n for n in expected if n not in labels]
    repeated = sorted({c for c in labels if labels.count(c) > 1})
    # every input has its column, and columns more: those are no input to rename, but to leave out
    fix = (f"Pass the inputs' columns alone, e.g. {'point' if series else 'df'}[{list(expected)!r}]"
           if extra and not missing and not repeated else
           "Name every column as an input (any order: read by name) or none (read by position)")
    # every input named and columns more is no "some of the inputs": the extra columns are the fault
    said = (f"name only some of the inputs {list(expected)}" if missing else
            f"name every input {list(expected)}, some more than once" if repeated else
            f"name every input {list(expected)} and more columns")
    if by_name:  # keys are names: nothing is read by position
        raise ValueError(f"{name}: the {what} {labels} {said} (not inputs: {extra or 'none'}; inputs without a "
                         f"level: {missing or 'none'}): key one level, or one sequence of levels, by each input's name")
    raise ValueError(f"{name}: the {what} {labels} {said} "
                     f"(not inputs: {extra or 'none'}; inputs without a column: {missing or 'none'}; repeated: "
                     f"{repeated or 'none'}): read by position they would land on other inputs. {fix}")


def _default_name(label: str, m: int) -> bool:
    """Whether ``label`` is one of the default names of ``m`` inputs (``label in default_input_names(m)``, told
    without making the m names)."""
    if m == 1:
        return label == "u"
    k = label[1:]
    return label[:1] == "u" and k.isascii() and k.isdigit() and k[0] != "0" and 1 <= int(k) <= m


def as_input_array(x: object, name: str, names: Sequence[str] | None = None, *, output: object = None,
                   row: str = "sample", own: bool = False) -> np.ndarray:
    """Input samples as a read-only float64 copy: shape (N,) for one input, C-contiguous (N, m) for several.

    The one coercion of inputs (records, static points, free runs, static surfaces): a pandas DataFrame
    is read by column name where its columns are the inputs ``names`` (default ``u`` / ``u1 … um``), in
    any order, by position where they name none of them, and refused where they name some
    (:func:`frame_inputs`; ``output``, the output as a named Series, never an input). A non-finite value is
    said by its ``row`` (``"sample"``, ``"point"``; counted from 0) and its input's name.
    """
    x = frame_inputs(x, names, name, output, samples=row == "sample", own=own)
    refuse_non_real(x, name)
    refuse_flags(x, name, SAMPLES, none=False)  # an on/off input's True read as 1 is the caller's to say
    a = float_array(x, name)
    if a.ndim == 2 and a.shape[1] == 1:
        a = a[:, 0].copy()
    if a.ndim == 1:
        return as_1d_finite(a, name)
    if a.ndim != 2:
        raise ValueError(f"{name} must be 1-D (one input) or 2-D of shape (N, m) (m inputs), got {a.ndim}-D "
                         f"with shape {a.shape}")
    settled = ((names is not None and len(names) == a.shape[1])  # the inputs named are the columns
               or (output is not None and np.size(output) == a.shape[0]))  # the output's samples are the rows
    if row == "sample" and 0 < a.shape[0] < a.shape[1] and not is_frame(x) and not settled:
        # [u1, u2] (or np.array of it): numpy's rows are samples, so 2 samples of N inputs; the one rule of every
        # entry that takes samples (a free run said N inputs u1 … uN, the regressors 2 samples against N outputs)
        k, n = a.shape
        raise ValueError(f"{name} has shape {a.shape}, one row per input: give one column per input, shape ({n}, {k}) "
                         f"(the transpose, x.T, or np.column_stack of the inputs). Or {k} separate run(s) of one "
                         f"input: pass them one at a time (a Record each). (As numpy reads it, {k} sample(s) of {n} "
                         f"inputs: fewer samples than inputs; if that is meant, name the {n} inputs (input_names=...))")
    if a.shape[1] == 0:
        raise ValueError(f"{name} has no input column (shape {a.shape}); for output-only data (a structure "
                         "without input terms) pass a column of zeros")
    bad = ~np.isfinite(a)
    if bad.any():
        r, c = np.argwhere(bad)[0]
        # by name: "input 1" read as u1 by whoever counts inputs from 1 (as the default names do) was u2
        said = names if names is not None and len(names) == a.shape[1] else default_input_names(a.shape[1])
        raise ValueError(f"{name} has {int(bad.sum())} non-finite value(s) (NaN or inf), first at {row} {r}, input "
                         f"{said[c]!r}")
    return locked(a)


def _lengths(name: str, u_name: str, y_name: str, u: np.ndarray, y: np.ndarray) -> str:
    """The message for inputs and an output of different lengths; inputs stacked as rows (``np.array([u1, u2])``,
    shape (m, N)) are said so, with the fix."""
    msg = f"{name}: {u_name} and {y_name} must have the same length, got {u.shape[0]} and {y.size}"
    if u.ndim == 2 and u.shape[1] == y.size:
        msg += (f"; {u_name} has shape {u.shape}, one row per input: give one column per input, shape "
                f"({y.size}, {u.shape[0]}) (its transpose {u_name}.T, or np.column_stack of the inputs)")
    return msg


# eq=False here and on every value holding arrays: == on arrays has no single truth value, so these
# compare by identity and hash, as Model and the results do
@dataclass(frozen=True, eq=False)
class Record(Relocked):
    """One dynamic experiment: input ``u`` and output ``y`` sampled every ``Ts`` seconds.

    Parameters
    ----------
    u : array_like or pandas.DataFrame, shape (N,) or (N, m)
        Input samples (engineering units, e.g. rpm); one column per input. One input is
        stored 1-D (an (N, 1) array is flattened), several as a C-contiguous (N, m) array. A
        DataFrame's text column names are the ``input_names`` where those are not given (``df[["flow",
        "inlet"]]``: the inputs flow and inlet, as a dict's keys name them; one that cannot name an input, such
        as ``"flow rate"`` or ``"e"``, is refused); pandas' default columns 0, 1 … give the default names,
        and columns naming some inputs by text but not others (``0`` and ``"flow"``) are refused. A
        DataFrame whose columns are the ``input_names`` given is read by
        name, in any column order; one whose columns name none of them, by position; one whose
        columns name some of them is refused (``ValueError`` naming the columns), as is one that
        holds the output's column (``y`` a Series of that name: ``Record(df, df["p"])``) and one with a
        column that names no input and looks like time or a count of samples (strictly increasing in
        even steps, where the other columns are not): a record's time is its ``Ts``. A list of equal-length
        arrays with fewer samples than inputs (``[u1, u2]``: one row per input) is refused too, naming
        the transpose. Booleans are refused (``TypeError``): convert an on/off signal with ``astype(float)``.
    y : array_like, shape (N,)
        Output samples (engineering units, e.g. mlc).
    Ts : float, optional
        Sampling period in seconds (default 1.0).
    name : str, optional
        A label used in messages and tables.
    units : tuple, optional
        Units of ``(u, y)``, e.g. ``("rpm", "mlc")``; with several inputs in different units, one per input:
        ``(("l/min", "°C"), "m")``. Shown in reprs and on plots, and checked: the data of one
        identification must name the same ones, and a model fitted on them refuses a record or static points
        that name others (``""``, the default, names none and is never refused).
    input_names : sequence of str, optional
        The inputs' names as terms use them (default: a DataFrame's column names, else ``("u",)`` for one
        input, ``u1 … um`` for several); identifiers other than y, e, k, none given twice.
    """

    u: np.ndarray
    y: np.ndarray
    Ts: float = 1.0
    name: str = "record"
    units: tuple[str | tuple[str, ...], str] = ("", "")
    input_names: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        check_str(self.name, "Record: name")  # a label every message and file carries
        # a frame's columns (a Series' name) name its inputs, as a dict's keys do
        given = frame_names(self.u, self.input_names, f"{self.name}: u", column=True)
        own = given is not self.input_names
        u = as_input_array(self.u, f"{self.name}: u", given, output=self.y, own=own)
        y = as_1d_finite(self.y, f"{self.name}: y")
        if u.shape[0] != y.shape[0]:
            raise ValueError(_lengths(self.name, "u", "y", u, y))
        if y.size == 0:  # nothing downstream (nor the repr's ranges) has a meaning for an empty run
            raise ValueError(f"{self.name}: no samples")
        if not isinstance(self.Ts, (str, bytes)) and np.ndim(self.Ts) > 0 and np.size(self.Ts) == 1:
            # one value in an array (scipy.io.loadmat's array([[0.05]]) for a saved scalar): no time column
            raise TypeError(f"{self.name}: Ts is the sampling period, one number of seconds, got one value inside "
                            f"a {type(self.Ts).__name__} of shape {np.shape(self.Ts)}: pass float(Ts)")
        if not isinstance(self.Ts, (str, bytes)) and np.ndim(self.Ts) > 0:  # the record's time column, passed as Ts
            raise TypeError(f"{self.name}: Ts is the sampling period, one number of seconds, got {np.size(self.Ts)} "
                            f"values ({type(self.Ts).__name__}): a time column? Pass its step, e.g. "
                            "Ts=float(np.median(np.diff(t))), or read the file with graybox.load_record_csv(path, "
                            "u=..., y=..., time='t')")
        object.__setattr__(self, "Ts", check_real(self.Ts, f"{self.name}: Ts (seconds)", low=0, low_open=True))
        m = 1 if u.ndim == 1 else u.shape[1]
        object.__setattr__(self, "units", check_units(self.units, self.name, m))
        names = default_input_names(m) if given is None else check_input_names(
            given, m, f"{self.name}: {_COLUMNS_NAME if own else 'input_names'}")
        object.__setattr__(self, "u", u)
        object.__setattr__(self, "y", y)
        object.__setattr__(self, "input_names", names)

    def __len__(self) -> int:
        return int(self.y.size)

    @property
    def n_inputs(self) -> int:
        """m, the number of inputs."""
        return 1 if self.u.ndim == 1 else int(self.u.shape[1])

    def input(self, name: str) -> np.ndarray:
        """The samples of one input.

        Parameters
        ----------
        name : str
            One of ``input_names`` (another is refused: ``ValueError`` naming the record's inputs).

        Returns
        -------
        ndarray, shape (N,)
            The input's samples in its own units (a read-only view).
        """
        if name not in self.input_names:
            raise ValueError(f"{self.name}: no input named {name!r}; its inputs are {self.input_names}")
        return self.u if self.u.ndim == 1 else self.u[:, self.input_names.index(name)]

    @property
    def inputs(self) -> np.ndarray:
        """All inputs as shape (N, m) (a view; m = 1 for a single input)."""
        return self.u.reshape(len(self), self.n_inputs)

    def __repr__(self) -> str:
        uu, yu = _unit_suffixes(self.units)
        if self.u.ndim == 1 and self.input_names == ("u",):
            ins = f"u in {range_text(self.u.min(), self.u.max())}{uu}"
        else:
            ins = _input_ranges(self.input_names, self.inputs.T, self.units)
        return f"Record({self.name!r}: {len(self)} samples, Ts = {self.Ts:g} s, {ins}, y in {range_text(self.y.min(), self.y.max())}{yu})"

    @property
    def t(self) -> np.ndarray:
        """Time stamps in seconds, shape (N,), starting at 0."""
        return np.arange(len(self)) * self.Ts

    def slice(self, start: int | None = None, stop: int | None = None, name: str | None = None) -> "Record":
        """The samples ``start:stop`` as a new record, with the same ``Ts``, units and inputs.

        Parameters
        ----------
        start, stop : int, optional
            Sample indices, as Python's slice ``start:stop`` reads them (default: from the first, to the last).
        name : str, optional
            The new record's name (default: this one's name).

        Returns
        -------
        Record
        """
        # a bool was read as 0 or 1, a float numpy's "slice indices must be integers" naming neither
        start, stop = (None if v is None else check_int(v, f"{self.name}: slice {what}")
                       for what, v in (("start", start), ("stop", stop)))
        return Record(self.u[start:stop], self.y[start:stop], self.Ts, name or self.name, self.units, self.input_names)

    def require_length(self, max_lag: int) -> None:
        """Raise ``ValueError`` unless the record has more than ``max_lag`` samples.

        Parameters
        ----------
        max_lag : int
            A structure's largest lag (samples).
        """
        if len(self) < max_lag + 1:
            raise ValueError(
                f"{self.name}: record has {len(self)} samples, fewer than max lag + 1 = {max_lag + 1}"
            )


@dataclass(frozen=True, eq=False)
class StaticPoints(Relocked):
    """Measured steady states: at constant input ``ubar[i]`` the output settled at ``ybar[i]``.

    Parameters
    ----------
    ubar : array_like, pandas.DataFrame or dict, shape (M,) or (M, m)
        Constant input levels (engineering units), all distinct; one column per input (a
        point ū in input space per row) for several inputs. A DataFrame's text column names are the
        ``input_names`` where those are not given; given, it is read by column name
        where its columns are the ``input_names``, by position where they name none of them, and
        refused where they name some (as :class:`Record`'s ``u``). A dict keyed by input name
        (``{"flow": [1.0, 2.0], "inlet": [20.0, 25.0]}``, as static curves take levels) gives the
        ``input_names`` by its keys; with ``input_names`` given, its keys must be those names. Its
        levels are paired by position: pandas Series among them must share one index (refused
        otherwise, naming them; they are not aligned by label).
    ybar : array_like, shape (M,)
        Settled output at each level.
    name : str, optional
        A label used in messages.
    input_names : sequence of str, optional
        The inputs' names (default: a DataFrame's column names or a dict's keys, else ``("u",)`` for one
        input, ``u1 … um`` for several).
    uncertainty : float or array_like of shape (M,), optional
        δ_i, how far the measured ȳ_i may lie from the true steady state, output units (e.g. a
        transmitter's ±0.175 mlc); one number for every point or one per point, each > 0. When
        given, it supplies the bands that otherwise must be passed: D_SF's B (:attr:`band`) and
        :class:`~graybox.StaticBand`'s half-widths. None (default): every band must be given.
    units : tuple, optional
        Units of ``(ubar, ybar)``, as :class:`Record`'s ``units`` (the input's one string, or one per
        input): shown (plots label their axes with
        them) and checked against the records' and a model's; default ``("", "")``, no unit said.
    """

    ubar: np.ndarray
    ybar: np.ndarray
    name: str = "static points"
    input_names: tuple[str, ...] | None = None
    uncertainty: np.ndarray | None = None
    units: tuple[str | tuple[str, ...], str] = ("", "")

    def __post_init__(self) -> None:
        check_str(self.name, "StaticPoints: name")
        ubar, given, own = _named_levels(self.ubar, self.input_names, f"{self.name}: ubar")
        u = as_input_array(ubar, f"{self.name}: ubar", given, output=output_series(self.ybar), row="point")
        y = as_1d_finite(self.ybar, f"{self.name}: ybar")
        if u.shape[0] != y.shape[0]:
            raise ValueError(_lengths(self.name, "ubar", "ybar", u, y))
        if u.shape[0] == 0:
            raise ValueError(f"{self.name}: no static points")
        uniq, counts = np.unique(u, return_counts=True, axis=0)
        if (counts > 1).any():
            raise ValueError(f"{self.name}: duplicated ubar value(s) {listed(uniq[counts > 1].tolist())}; for repeated "
                             "measurements at one level use StaticPoints.from_repeats, which averages them")
        m = 1 if u.ndim == 1 else u.shape[1]
        names = default_input_names(m) if given is None else check_input_names(
            given, m, f"{self.name}: {_COLUMNS_NAME if own else 'input_names'}")
        object.__setattr__(self, "ubar", u)
        object.__setattr__(self, "ybar", y)
        object.__setattr__(self, "input_names", names)
        object.__setattr__(self, "units", check_units(self.units, self.name, m))
        if self.uncertainty is not None:
            d = locked(_uncertainty(self.uncertainty, y.size, self.name, "point"))
            object.__setattr__(self, "uncertainty", d)

    def __len__(self) -> int:
        return int(self.ybar.size)

    @property
    def band(self) -> float:
        """D_SF's B from the points' own uncertainty: the mean of δ_i², output units².

        J_SF is the mean of (ȳ_i − ŷ_i)², so a static curve through the true steady states has
        J_SF ≤ mean δ_i² when each measured ȳ_i is within δ_i of the truth: the rule reads the
        same in any units (the paper's B = 0.175² = 0.031 mlc² is this rule for its transmitter).
        ``ValueError`` when the points carry no uncertainty: then pass the band yourself. 0 or inf where δ² leaves
        the float range (δ near 1e-170 or 1e160), as J_SF's squares there.
        """
        if self.uncertainty is None:
            raise ValueError(f"{self.name}: these static points carry no uncertainty, so no band follows from them; "
                             "pass band=B (J_SF's bound, output units², e.g. the square of the static measurements' "
                             "error) or build the points with uncertainty=δ (output units)")
        with np.errstate(over="ignore", under="ignore"):  # beyond the float range: 0 or inf, said, not warned
            return float(np.mean(self.uncertainty**2))

    def with_uncertainty(self, uncertainty: object) -> "StaticPoints":
        """The same points carrying another uncertainty.

        Parameters
        ----------
        uncertainty : float or array_like, shape (M,), or None
            δ, output units (each > 0): one number for every point, or one per point in the order of ``ubar``;
            None drops it.

        Returns
        -------
        StaticPoints
        """
        return StaticPoints(self.ubar, self.ybar, self.name, self.input_names, uncertainty, self.units)

    @classmethod
    def from_repeats(cls, ubar: object, ybar: object, *, name: str = "static points",
                     input_names: Sequence[str] | None = None, uncertainty: object = None,
                     units: tuple[str | tuple[str, ...], str] = ("", "")) -> "StaticPoints":
        """Static points from repeated measurements: the mean ȳ at each distinct ū.

        Parameters
        ----------
        ubar : array_like, pandas.DataFrame or dict, shape (N,) or (N, m)
            Input level of each measurement (engineering units); levels may repeat. A DataFrame
            or dict is read as :class:`StaticPoints` reads one (by name where its columns are the inputs).
        ybar : array_like, shape (N,)
            Settled output of each measurement.
        name, input_names
            As for :class:`StaticPoints`.
        uncertainty : float or array_like of shape (N,), optional
            δ (output units, each > 0): one number for every measurement, or one per measurement,
            paired with ``ybar`` as written; a level's δ is the mean of its measurements' (as its
            ȳ is: when each measured ȳ_j is within δ_j of the steady state, their mean is within
            the mean δ_j). One per distinct level is refused (``ValueError``): the order of the
            levels is ambiguous. To give those, set them on the result,
            ``points.with_uncertainty(δ)``, in the order of ``points.ubar`` (sorted).
        units : tuple of str, optional
            Units of ``(ubar, ybar)``, as for :class:`StaticPoints`.

        Returns
        -------
        StaticPoints
            One point per distinct level, sorted by ū; its ȳ is the mean of the measurements
            there. (Their spread is the static uncertainty that D_SF's band B stands for.)
        """
        check_str(name, "StaticPoints: name")
        ubar, input_names, _ = _named_levels(ubar, input_names, f"{name}: ubar")
        u = as_input_array(ubar, f"{name}: ubar", input_names, output=output_series(ybar), row="point")
        y = as_1d_finite(ybar, f"{name}: ybar")
        if u.shape[0] != y.shape[0]:
            raise ValueError(_lengths(name, "ubar", "ybar", u, y))
        if u.shape[0] == 0:
            raise ValueError(f"{name}: no static points")
        uniq, inverse = np.unique(u, return_inverse=True, axis=0)
        inverse = np.asarray(inverse).reshape(-1)
        count = np.bincount(inverse)
        mean = np.bincount(inverse, weights=y) / count
        if uncertainty is not None:
            given = np.shape(uncertainty)
            if len(given) == 1 and given[0] not in (1, y.size):
                raise ValueError(f"{name}: uncertainty must be one number or one δ per measurement ({y.size}, as "
                                 f"ybar), got {given[0]}: paired with the {uniq.shape[0]} levels it would "
                                 "follow their sorted order, not the order written; give it per measurement, or "
                                 "set it on the points: points.with_uncertainty(δ), in the order of points.ubar")
            uncertainty = np.bincount(inverse, weights=_uncertainty(uncertainty, y.size, name, "measurement")) / count
        names = None if input_names is None else check_input_names(input_names, what=f"{name}: input_names")
        return cls(uniq, mean, name, names, uncertainty, units)

    @property
    def n_inputs(self) -> int:
        """m, the number of inputs."""
        return 1 if self.ubar.ndim == 1 else int(self.ubar.shape[1])

    def __repr__(self) -> str:
        uu, yu = _unit_suffixes(self.units)
        if self.ubar.ndim == 1:
            ins = f"ū in {range_text(self.ubar.min(), self.ubar.max())}{uu}"
        else:
            ins = _input_ranges(self.input_names, self.ubar.T, self.units)
        # δ per point from a file's column: its range, so that one number never stands for them all
        lo, hi = (None, None) if self.uncertainty is None else (np.min(self.uncertainty), np.max(self.uncertainty))
        unc = ("" if lo is None else f", ±{hi:.4g}{yu}" if f"{lo:.4g}" == f"{hi:.4g}"
               else f", ±{lo:.4g}–{hi:.4g}{yu}")
        return (f"StaticPoints({self.name!r}: {len(self)} points, {ins}, ȳ in "
                f"{range_text(self.ybar.min(), self.ybar.max())}{yu}{unc})")


def require_lengths(records: Sequence[Any], max_lag: int, *, prefix: str = "", what: str = "") -> None:
    """Raise ``ValueError`` unless every record has more than ``max_lag`` samples; of several, a short one is named
    by its position too (records made or loaded without a name are all called "record"). ``what``: the records'
    part, e.g. ``"choosing"`` (counted among their own, so that no fitting record is blamed), after ``prefix`` (the
    argument, e.g. ``"choose_on: "``)."""
    kind = f"{what} record" if what else "record"
    for i, r in enumerate(records):
        if len(r) >= max_lag + 1:
            continue
        if len(records) > 1:
            raise ValueError(f"{prefix}{kind} {i + 1} of {len(records)} ({r.name!r}) has {len(r)} samples, fewer than "
                             f"max lag + 1 = {max_lag + 1}")
        if what:
            raise ValueError(f"{prefix}the {kind} {r.name!r} has {len(r)} samples, fewer than max lag + 1 = "
                             f"{max_lag + 1}")
        r.require_length(max_lag)


def check_units(units: object, name: str, m: int | None = None) -> tuple[str | tuple[str, ...], str]:
    """``units`` as a pair (input unit, output unit), or ``TypeError`` / ``ValueError`` naming ``name``.

    The input unit is one str for every input, or a sequence of str, one per input (``("l/min", "°C")`` for a flow
    and a temperature), kept as a tuple; a sequence whose units are all one is that one str, so two spellings of
    the same units compare equal. Each unit is stripped of surrounding blanks (a CSV header's ``" rpm "`` is the
    unit ``"rpm"``: units are compared, and blanks would make two of one unit). ``m``, where known, is the number of
    inputs a sequence must give (``ValueError`` otherwise)."""
    pair = isinstance(units, (tuple, list)) and len(units) == 2 and isinstance(units[1], str)
    ins = units[0] if pair else None  # type: ignore[index]
    per_input = isinstance(ins, (tuple, list)) and len(ins) > 0 and all(isinstance(x, str) for x in ins)
    if not pair or not (isinstance(ins, str) or per_input):
        raise TypeError(f"{name}: units must be a pair of strings (input unit, output unit), the input's one string "
                        f"or one string per input, got {units!r}")
    out = units[1].strip()  # type: ignore[index]
    if isinstance(ins, str):
        return (ins.strip(), out)
    each = tuple(x.strip() for x in ins)  # type: ignore[union-attr]
    if m is not None and len(each) != m:
        raise ValueError(f"{name}: units give {len(each)} input units {each} for {m} input(s): one per input, or "
                         "one string for all")
    return (each[0] if len(set(each)) == 1 else each, out)


def input_unit(units: tuple[str | tuple[str, ...], str], j: int = 0) -> str:
    """The unit of input ``j`` (position among the inputs) in ``units`` (:func:`check_units`' form); ``""``: none
    said."""
    u = units[0]
    return u if isinstance(u, str) else u[j]


def input_unit_text(units: tuple[str | tuple[str, ...], str]) -> str:
    """The input unit as text: the one unit, or the inputs' units joined by commas (``"l/min, °C"``)."""
    u = units[0]
    return u if isinstance(u, str) else ", ".join(x or "(none)" for x in u)


def _unit_suffixes(units: tuple[str | tuple[str, ...], str]) -> tuple[str, str]:
    """`` unit`` after a value for each of (input, output), empty where no unit is said (the inputs' own units,
    each after its range, are :func:`_input_ranges`')."""
    u = input_unit_text(units) if isinstance(units[0], str) else ""
    return (f" {u}" if u else "", f" {units[1]}" if units[1] else "")


def _input_ranges(names: Sequence[str], columns: np.ndarray, units: tuple[str | tuple[str, ...], str]) -> str:
    """``"u1 in [a, b], u2 in [c, d] °C"``: each input's range, followed by its own unit where the inputs' units
    differ, else the one unit once at the end."""
    per = not isinstance(units[0], str)
    text = ", ".join(f"{n} in {range_text(c.min(), c.max())}" + (f" {input_unit(units, j)}" if per and
                     input_unit(units, j) else "") for j, (n, c) in enumerate(zip(names, columns)))
    return text + _unit_suffixes(units)[0]


def _uncertainty(value: object, n: int, name: str, each: str) -> np.ndarray:
    """δ as a float array of shape (n,), each > 0 (output units), or ``TypeError``/``ValueError`` naming it."""
    d = np.array(check_per_point(value, n, f"{name}: uncertainty"), dtype=float)
    if (d <= 0).any():
        raise ValueError(f"{name}: uncertainty must be > 0 at every {each} (output units), got "
                         f"{d[d <= 0][:3].tolist()}")
    return d


def static_point_inputs(static: StaticPoints, inputs: tuple[str, ...]) -> np.ndarray:
    """The static points' ū in the column order ``inputs``: shape (M,) for one input, (M, k) for several.

    One input: any single-input points (whatever their input's name, as before several inputs), or the column of
    that name among several (as a record's input is taken by name: points that also hold an input the model does
    not use). Several: the columns are taken by name; ``ValueError`` naming a missing input or a count mismatch.
    """
    if len(inputs) <= 1:
        if static.n_inputs != 1 and len(inputs) == 1 and inputs[0] in static.input_names:
            return np.ascontiguousarray(static.ubar[:, static.input_names.index(inputs[0])])
        if static.n_inputs != 1:
            raise ValueError(f"{static.name}: {static.n_inputs} input columns {static.input_names}, but the model has "
                             f"one input {tuple(inputs)}")
        return static.ubar
    if tuple(inputs) == static.input_names:
        return static.ubar
    missing = [n for n in inputs if n not in static.input_names]
    if missing:
        # a transient input (z̄ = 0 at every static point): how to add it; other hints speak of records
        hint = ("" if transient_source(missing[0], static.input_names) is None
                else missing_input_hint(inputs, static.input_names, "static"))
        raise ValueError(f"{static.name}: the model has the inputs {tuple(inputs)} but the static points have "
                         f"{static.input_names} (no {missing[0]!r}){hint}")
    return static.ubar[:, [static.input_names.index(n) for n in inputs]]


#: How a units disagreement within one identification's data ends its message.
_SAME_UNITS = "all data of one identification must be in the same units (convert one of them)"


def check_compatible(a: object, b: object) -> None:
    """``ValueError`` naming both unless ``a`` and ``b`` (records, static points) can belong to one
    identification: the same inputs in the same order, the same units where both name them and, two
    records, the same sampling period (:func:`check_same_period`)."""
    if a.input_names != b.input_names:  # type: ignore[attr-defined]
        raise ValueError(f"{a.name!r} has inputs {a.input_names} but {b.name!r} has inputs {b.input_names}: "  # type: ignore[attr-defined]
                         "all data of one identification must have the same inputs, in the same order"
                         + _unnamed_hint(a, b))
    first: Any = a
    check_same_units(getattr(a, "units", ("", "")), f"{first.name!r} has", b, _SAME_UNITS, first.input_names)
    if isinstance(a, Record) and isinstance(b, Record):
        check_same_period(a, b)


def _unnamed_hint(a: Any, b: Any) -> str:
    """How to name the inputs of whichever of ``a`` and ``b`` (records, static points) left them with the default
    names beside the other's own, as many (a DataFrame whose columns name no default is read by position)."""
    for this, other in ((a, b), (b, a)):
        n = len(this.input_names)
        if (n == len(other.input_names) and this.input_names == default_input_names(n)
                and other.input_names != default_input_names(n)):
            kind = "StaticPoints" if isinstance(this, StaticPoints) else "Record"
            return (f" ({this.name!r} has the default names: name them, e.g. {kind}(..., input_names="
                    f"{tuple(other.input_names)!r}), one per column in the columns' order)")
    return ""


def check_units_agree(items: Sequence[object], advice: str) -> None:
    """``ValueError`` naming both when two of ``items`` (records, static points) name different units for an input
    or the output: each is held to every earlier one where both name a unit (an empty unit says nothing, so holding
    all to a first that names none would let the others disagree). ``advice`` ends the message."""
    for i, x in enumerate(items):
        for first in items[:i]:
            name = getattr(first, "name", "")
            check_same_units(getattr(first, "units", ("", "")), f"{name!r} has", x, advice,
                             getattr(first, "input_names", None))


def said_units(records: object, static: object = None) -> tuple[str | tuple[str, ...], str]:
    """The units a fit's records (a Record, a DaskRecord or a sequence of them) and static points say together:
    per slot the first named, as one record may name a unit the others leave empty (where two name one they agree:
    :func:`check_compatible`). Inputs in units of their own are merged input by input, by name (in the first item's
    order: a model beside a record may use fewer of its inputs, or list them in another order)."""
    items = list(records) if isinstance(records, (list, tuple)) else [records]
    items += [static] if isinstance(static, StaticPoints) else []
    said = [getattr(x, "units", ("", "")) for x in items]
    out = next((u[1] for u in said if u[1]), "")
    if all(isinstance(u[0], str) for u in said):
        return (next((u[0] for u in said if u[0]), ""), out)
    names = list(getattr(items[0], "input_names", None) or ())
    n = len(names) if names else len(next(u[0] for u in said if not isinstance(u[0], str)))
    owns = [getattr(x, "input_names", None) for x in items]
    each = [next((v for v in (_unit_of(u, own, names[j] if names else None, j) for u, own in zip(said, owns))
                  if v), "") for j in range(n)]
    return check_units((each, out), "units")


def carried_from(records: object, static: object = None) -> dict:
    """What a model (or a result handing out models) carries from the records it was fitted on (a Record, a
    DaskRecord or a sequence of them; ``static``: the static points fitted too, if any): the inputs' names and the
    sampling period (the first record's: all share them) and the units any of them name (:func:`said_units`), as
    keyword arguments (``Model(st, θ, **carried_from(recs))``)."""
    first = records[0] if isinstance(records, (list, tuple)) else records
    return {"input_names": first.input_names, "Ts": first.Ts,  # type: ignore[attr-defined]
            "units": said_units(records, static)}


def _unit_of(units: tuple, own: Sequence[str] | None, name: str | None, j: int) -> str:
    """The unit ``units`` (of the inputs ``own``) give one input of another side: the input called ``name`` where
    both sides' names are known (``""`` where there is no such input), else the input at position ``j`` (``""``
    past the last)."""
    u = units[0]
    if name is not None and own:
        if name not in own:
            return ""
        j = list(own).index(name)
    return u if isinstance(u, str) else (u[j] if j < len(u) else "")


def _input_clash(units: tuple, names: Sequence[str] | None, theirs: tuple, their_names: Sequence[str] | None
                 ) -> tuple[str, str, str] | None:
    """(what, mine, theirs) of the first input unit two sides both name and name differently, or None: one unit
    each, compared; else input by input: by name where both sides' names are known (inputs are read by name, and a
    record may hold inputs a model does not use), else by position; what is ``"input"`` or ``"input 'name'"``."""
    a, b = units[0], theirs[0]
    if isinstance(a, str) and isinstance(b, str):
        return ("input", a, b) if a and b and a != b else None
    n_a = len(a) if not isinstance(a, str) else len(names) if names is not None else len(b)
    known = names is not None and their_names is not None and len(names) == n_a
    for j in range(n_a):
        name = names[j] if known else None  # type: ignore[index]
        x, y = _unit_of(units, None, None, j), _unit_of(theirs, their_names, name, j)
        if x and y and x != y:
            return (f"input {name!r}" if known else f"input {j + 1}", x, y)
    return None


def check_same_units(units: tuple, what: str, other: object, advice: str,
                     names: Sequence[str] | None = None) -> None:
    """``ValueError`` when ``other``'s units (a Record's or StaticPoints') differ from ``units`` where both
    name them (an empty unit says nothing; inputs in units of their own are compared input by input, by name
    where ``names``, the first side's input names, are given). ``what`` names the first side, e.g. "'ident' has"
    or "model 'ELS' was identified with"; ``advice`` ends the message."""
    theirs, who = getattr(other, "units", ("", "")), getattr(other, "name", "")
    clash = _input_clash(units, names, theirs, getattr(other, "input_names", None))
    if clash is not None:
        raise ValueError(f"{what} {clash[0]} unit {clash[1]!r} but {who!r} has {clash[2]!r}: " + advice)
    if units[1] and theirs[1] and units[1] != theirs[1]:
        raise ValueError(f"{what} output unit {units[1]!r} but {who!r} has {theirs[1]!r}: " + advice)


#: Relative difference of two sampling periods taken as one period: a period read from printed time
#: stamps is their mean step, rounded by the print (the CSV loader accepts steps within 1e-3 too).
PERIOD_RTOL = 1e-3


def check_same_period(a: Record, b: Record) -> None:
    """``ValueError`` naming both unless two records (in memory or Dask) share their sampling
    period, to :data:`PERIOD_RTOL` relative."""
    check_period(a.Ts, f"{a.name!r} is sampled", b)


def check_one_period(records: Sequence[Any], name: str = "records") -> None:
    """``ValueError`` naming two of them (by position too, after ``name``, the argument) unless ``records`` (in
    memory or Dask) share one sampling period: the slowest and the fastest to :data:`PERIOD_RTOL` relative (each
    held to the first alone, periods that drift let 1, 1.0009 and 1.0018 s pass in one order and not in another)."""
    periods = [r.Ts for r in records]
    i, j = int(np.argmin(periods)), int(np.argmax(periods))
    try:
        check_same_period(records[i], records[j])
    except ValueError as exc:
        raise ValueError(f"{name}: records {i + 1} and {j + 1} of {len(records)}: {exc}") from None


def check_alike(a: Record | Sequence[Record], b: Record) -> None:
    """``ValueError`` naming both unless a further record ``b`` (one to choose or test on) can be read as the fitting
    record(s) ``a`` are: the same sampling period and, where both name them, the same units (those any of ``a``
    names: :func:`said_units`; inputs are read by name)."""
    recs = list(a) if isinstance(a, (list, tuple)) else [a]
    for r in recs:  # each, not the first alone: the fitting records' periods may differ within the tolerance
        check_same_period(r, b)
    for r in recs:  # the first that names a unit b contradicts is the one named
        check_same_units(r.units, f"{r.name!r} has", b, "convert one of them: a model holds in one set of units",
                         r.input_names)


def check_fitted_on(Ts: float | None, units: tuple, who: str, data: object, advice: str,
                    names: Sequence[str] | None = None) -> None:
    """``ValueError`` when ``data`` (a Record, or static points) cannot be met by what was fitted at period ``Ts``
    in ``units``: a Record at another period, or data in other units where both name them. ``who`` says what was
    fitted and how, e.g. "model 'ELS' was identified" (the message goes on "on records sampled …" or "with …");
    ``advice`` ends a units message."""
    if isinstance(data, Record):  # static points have no period
        check_period(Ts, f"{who} on records sampled", data)
    check_same_units(units, f"{who} with", data, advice, names)


def check_period(Ts: float | None, what: str, record: Record, advice: str = "") -> None:
    """``ValueError`` unless ``record`` is sampled every ``Ts`` seconds (to :data:`PERIOD_RTOL`; None:
    unknown, nothing to check). ``what`` names the other side, e.g. "'ident' is sampled" or "model
    'ELS' was identified on records sampled"; ``advice`` ends the message."""
    if Ts is not None and abs(Ts - record.Ts) > PERIOD_RTOL * max(Ts, record.Ts):
        raise ValueError(f"{what} every {Ts:.9g} s but {record.name!r} every {record.Ts:.9g} s: a "
                         "discrete-time model holds at one sampling period; resample one of them (a Record "
                         "made without Ts= has Ts = 1 s)" + advice)


@dataclass(frozen=True, eq=False)
class Dataset(Relocked):
    """A named bundle: identification and validation records plus static points.

    The records and the static points must have the same inputs, in the same order, and the
    records one sampling period (``PERIOD_RTOL``); ``ValueError`` otherwise.

    Attributes
    ----------
    ident, valid : Record
        Identification and validation records.
    static : StaticPoints or None
        Measured steady states, if any.
    description : str
        Where the data come from, in plain words.
    extra : mapping
        Anything else a loader wants to expose (e.g. a theoretical static curve); kept as a read-only
        copy all the way down (``FrozenMap``; nested lists ``FrozenList``, named tuples their type, arrays
        read-only copies; a value held twice frozen once and still shared), as every mapping of a graybox
        value; ``ValueError`` for one nested deeper than 100 levels or holding itself.
    """

    ident: Record
    valid: Record
    static: StaticPoints | None = None
    description: str = ""
    extra: Mapping = field(default_factory=dict)

    def __post_init__(self) -> None:
        for nm in ("ident", "valid"):
            if not isinstance(getattr(self, nm), Record):
                raise TypeError(f"Dataset: {nm} must be a Record, got {type(getattr(self, nm)).__name__}"
                                f"{record_hint(getattr(self, nm))}")
        if self.static is not None and not isinstance(self.static, StaticPoints):
            raise TypeError(f"Dataset: static must be StaticPoints or None, got {type(self.static).__name__}"
                            f"{static_hint(self.static)}")
        check_str(self.description, "Dataset: description")  # text a file carries: None or 3 saved, then refused
        if not isinstance(self.extra, Mapping):
            raise TypeError(f"Dataset: extra must be a mapping (e.g. a dict), got {type(self.extra).__name__}")
        # not the caller's dict, nor its nested lists, dicts and arrays, and not changeable
        object.__setattr__(self, "extra", frozen_value(self.extra, "Dataset: extra"))
        check_compatible(self.ident, self.valid)
        if self.static is not None:
            check_compatible(self.ident, self.static)
        check_units_agree([self.ident, self.valid, self.static], _SAME_UNITS)

    @property
    def input_names(self) -> tuple[str, ...]:
        """The inputs' names, shared by every record and the static points."""
        return self.ident.input_names

    @property
    def Ts(self) -> float:
        """Sampling period in seconds."""
        return self.ident.Ts

    @property
    def units(self) -> tuple[str, str]:
        """The units (input, output) its records and static points name (per slot the first named; where two
        name one they agree)."""
        return said_units([self.ident, self.valid], self.static)

    def __repr__(self) -> str:
        st = "static=None" if self.static is None else f"static={self.static!r}"
        return f"Dataset(ident={self.ident!r},\n        valid={self.valid!r},\n        {st})"


__all__.append("Dataset")


def record_hint(data: object, call: str = "") -> str:
    """How to make a Record of what was given where one is meant (a path, a DataFrame, arrays), else ``""``.
    ``call``: the call on one record ``r`` that a list of records is told to make once per record."""
    if isinstance(data, Dataset):  # where one record is meant and the call cannot tell which
        return "; pass one of its records: data.ident or data.valid"
    if call and isinstance(data, (tuple, list)) and data and all(isinstance(r, Record) for r in data):
        # no function scores or runs several records at once: one call per record
        return f"; it takes one record: call it once per record, [{call} for r in records]"
    # by name: core._gram (DaskRecord's home) imports this module
    dask = [r for r in (data if isinstance(data, (tuple, list)) else [data]) if type(r).__name__ == "DaskRecord"]
    if dask:
        mixed = isinstance(data, (tuple, list)) and len(dask) < len(data)
        return ("; a DaskRecord (held out of memory) is taken by frols, pe_thetas and cls only, "
                + ("and not among Records: give them all as DaskRecords, or all as Records" if mixed else
                   "alone or among DaskRecords only: elsewhere give a Record of its samples, e.g. "
                   "Record(r.u.compute(), r.y.compute(), Ts=r.Ts, units=r.units)"))
    if isinstance(data, (str, os.PathLike)):
        return ("; read the file first: graybox.load_record_csv(path, u='input column', y='output column', "
                "time='time column') (or Ts=seconds)")
    if is_frame(data):
        return "; make one of its columns: graybox.Record(df['input column'], df['output column'], Ts=seconds)"
    if isinstance(data, Mapping):
        return "; make one of its signals: graybox.Record(d['u'], d['y'], Ts=seconds)"
    if isinstance(data, (tuple, list)) and any(isinstance(r, Dataset) for r in data):
        return ("; several experiments are a list of their records, e.g. [d.ident for d in datasets] "
                "(select_graybox: with their validation records as validation=[d.valid for d in datasets] and "
                "the static points as static=)")
    if isinstance(data, np.ndarray) or (isinstance(data, (tuple, list)) and data and all(
            isinstance(r, (np.ndarray, list, tuple, int, float, np.number)) or _is_series(r) for r in data)):
        return "; make one of the input and output samples: graybox.Record(u, y, Ts=seconds)"
    return ""


def require_record(record: object, name: str = "record", call: str = "") -> Record:
    """``record`` if it is a Record, else ``TypeError`` naming ``name`` and how to make one (a Dataset: which of its
    records to pass; a list of records: ``call`` once per record)."""
    if not isinstance(record, Record):
        raise TypeError(f"{name} must be a Record, got {type(record).__name__}{record_hint(record, call)}")
    return record


def static_hint(static: object) -> str:
    """How to make StaticPoints of what was given where they are meant (a path, a DataFrame, arrays, a function)."""
    if isinstance(static, (str, os.PathLike)):
        return "; read the file first: graybox.load_static_csv(path, u='input column', y='output column')"
    if is_frame(static):
        return "; make them of its columns: graybox.StaticPoints(df['input column'], df['output column'])"
    if isinstance(static, (tuple, list)) and static and all(isinstance(p, StaticPoints) for p in static):
        # levels measured in more than one set are repeats, which StaticPoints refuses and from_repeats averages; the
        # sets' δ (one per measurement) go along where every set has them
        try:
            ub = np.concatenate([p.ubar for p in static])
            levels, counts = np.unique(ub, axis=0, return_counts=True)
            shared = levels[counts > 1].tolist()
        except ValueError:  # sets of different numbers of inputs: the points' own check says so
            shared = []
        make = "StaticPoints.from_repeats" if shared else "StaticPoints"
        unc = (", uncertainty=np.concatenate([p.uncertainty for p in sets])"
               if all(p.uncertainty is not None for p in static) else "")
        why = (f" (from_repeats: the sets measure the level(s) {listed(shared)} more than once, and it averages the "
               "measurements at each level)" if shared else "")
        return (f"; several sets are one StaticPoints of all their points: graybox.{make}(np.concatenate("
                "[p.ubar for p in sets]), np.concatenate([p.ybar for p in sets]), input_names=sets[0].input_names, "
                f"units=sets[0].units{unc}){why}")
    if isinstance(static, (np.ndarray, tuple, list)):
        return "; make them of the levels and the settled outputs: graybox.StaticPoints(ubar, ybar)"
    if callable(static):
        return ("; a function is sampled first: graybox.StaticPoints(ubar, f(ubar)), or given as a polynomial: "
                "graybox.StaticCurve.polynomial([c0, c1, ...])")
    return ""


def as_records(data: object, part: str = "ident", name: str = "data") -> list[Record]:
    """The records an entry works on, as a non-empty list.

    Parameters
    ----------
    data : Record, Dataset or sequence of Record
        A Dataset stands for its record ``part``.
    part : {"ident", "valid"}
        Which record of a Dataset: ``"ident"`` for an estimate, ``"valid"`` for a judgement.
    name : str
        The argument's name, for the error message.

    Raises
    ------
    TypeError
        ``data`` (or an element) is of another type; the message lists what is accepted.
    ValueError
        No records, or records whose inputs or sampling periods differ.
    """
    if isinstance(data, Dataset):
        # one identification: its record speaks in the units any part of it names (an ident loaded without units
        # beside a validation file that names them gives models that know them)
        rec, units = getattr(data, part), data.units
        return [rec if rec.units == units else replace(rec, units=units)]
    if isinstance(data, Record):
        return [data]
    # a DataFrame or an array iterates over what are no records (column names, rows): said as what it is
    if isinstance(data, (str, bytes, Mapping, os.PathLike, np.ndarray)) or is_frame(data) or not hasattr(data, "__iter__"):
        raise TypeError(f"{name} must be a Record, a sequence of Records or a Dataset (whose {part} record is used); "
                        f"got {type(data).__name__}{record_hint(data)}")
    # a set's order follows the records' addresses (a Record hashes by identity): seeded starts, the model's period
    # and input names (the first record's) would change from one run to the next
    check_ordered(data, name, "records")
    if iter(data) is data:  # type: ignore[call-overload]
        # a generator or an iterator is read once, and entries read their records more than once: frols or pe_pareto
        # then found it empty ("no records given") while els took it
        raise TypeError(f"{name} must be a Record, a sequence of Records or a Dataset; got a {type(data).__name__}, "
                        "which can be read only once: pass a list of its records (list(...))")
    recs = list(data)  # type: ignore[call-overload]
    if not recs:
        raise ValueError(f"{name}: no records given (an empty sequence)")
    for r in recs:
        if not isinstance(r, Record):
            own = isinstance(r, (str, os.PathLike)) or is_frame(r)  # a file or a frame: its own way to a Record
            raise TypeError(f"{name} must be a Record, a sequence of Records or a Dataset; got a sequence holding a "
                            f"{type(r).__name__}{record_hint(r if own else recs)}")
    for i, r in enumerate(recs[1:], 2):
        try:
            check_compatible(recs[0], r)
        except ValueError as exc:  # by position too: records made or loaded without a name are all called "record"
            raise ValueError(f"{name}: records 1 and {i} of {len(recs)}: {exc}") from None
    check_one_period(recs, name)
    check_units_agree(recs, _SAME_UNITS)
    return recs


__all__ += ["check_units", "require_lengths", "as_records", "record_hint", "static_hint", "as_input_array", "frame_inputs", "is_frame", "check_compatible", "check_alike", "carried_from", "said_units", "check_units_agree", "check_same_units", "check_fitted_on", "check_period", "check_same_period", "static_point_inputs",
            "check_one_period",
            "PERIOD_RTOL"]


class StaticRangeWarning(UserWarning):
    """Static points lie well outside the input range of the dynamic records (said once per call).

    Not an error: static knowledge where the dynamic data do not reach is what gray-box
    identification is for. The warning names the points so that a units mix-up is visible.
    """


#: How far beyond the records' input span (a fraction of it) a static ū must lie to be named: a
#: level just past the records' extremes (the bundled plant's 750 rpm against records from 770) is
#: ordinary; one well beyond them is what a units mix-up looks like. A fraction: the same in any units.
RANGE_MARGIN = 0.05


def outside_range(u: np.ndarray, lo: np.ndarray | float, hi: np.ndarray | float, margin: float = 0.0) -> np.ndarray:
    """Where ``u`` lies outside [lo, hi] (element-wise, broadcast: per column with per-input bounds).

    The tolerance is the larger of 1e-9 × (hi − lo), ``margin`` × (hi − lo) and the round-off of the bounds'
    size (8 units in the last place of the larger magnitude), so the same in any units and at any offset: a
    fraction of the bounds' size accepted 1e9 + 0.5 in [1e9, 1e9 + 0.04].
    """
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    width = np.maximum(hi - lo, 0.0)
    tol = np.maximum(np.maximum(1e-9, margin) * width, 8.0 * np.spacing(np.maximum(np.abs(lo), np.abs(hi))))
    return (u < lo - tol) | (u > hi + tol)


#: What a StaticRangeWarning says of points outside the records' range, for a fit the points shape.
_EXTRAPOLATED = "the model is extrapolated there by the static information"


def warn_static_range(ubar: np.ndarray, records: list[Record], what: str = "static points",
                      consequence: str = _EXTRAPOLATED) -> None:
    """Warn once, in words, which static ū lie well outside the dynamic records' input range (box, per input).

    "Well outside": by more than :data:`RANGE_MARGIN` of the records' span of that input. ``consequence``: what
    that means for the model (default: the static information extrapolates it; a black box, which the points
    only score, says otherwise).
    """
    ubar = np.asarray(ubar, float)
    if ubar.ndim == 2 and ubar.shape[1] > 1:
        lo_ = np.min([r.inputs.min(axis=0) for r in records], axis=0)
        hi_ = np.max([r.inputs.max(axis=0) for r in records], axis=0)
        rows = np.unique(ubar, axis=0)
        out_ = rows[outside_range(rows, lo_, hi_, RANGE_MARGIN).any(axis=1)]
        if out_.size:
            box = " × ".join(f"[{a:.6g}, {b:.6g}]" for a, b in zip(lo_, hi_))
            msg = (f"{what}: ū = {rounded_levels(out_)} lie outside the input box {box} of the dynamic "
                   f"records; {consequence} (if the points and the "
                   "records should overlap, check their units)")
            warn(msg, StaticRangeWarning)
        return
    ub = np.unique(np.atleast_1d(np.asarray(ubar, float)))
    lo = min(float(r.u.min()) for r in records)
    hi = max(float(r.u.max()) for r in records)
    out = ub[outside_range(ub, lo, hi, RANGE_MARGIN)]
    if out.size:
        msg = (f"{what}: ū = {rounded_levels(out)} lie outside the input range [{lo:.6g}, {hi:.6g}] of the "
               f"dynamic records; {consequence} (if the points and the "
               "records should overlap, check their units)")
        warn(msg, StaticRangeWarning)


def rounded_levels(values: np.ndarray) -> list:
    """Input levels for a message, as a (nested) list, each to 6 significant digits: the same digits in
    any units (rounding to decimals printed levels of 1e-8 A as 0.0)."""
    return np.vectorize(lambda v: float(f"{v:.6g}"), otypes=[float])(np.asarray(values, float)).tolist()


def same_record(a: Record, b: Record) -> bool:
    """Whether two records hold the same data (the same object, or equal inputs, matched by name,
    and outputs): a choosing or test record must not be one the fit saw."""
    if a is b:
        return True
    za, zb = _samples(a, b)
    return za.shape == zb.shape and za.shape[1] > 1 and np.array_equal(za, zb)


#: Places of each record whose windows are looked up in the other (see :func:`shared_stretch`).
_ANCHORS = 8
#: Samples in an anchor window.
_WINDOW = 16
#: Places an anchor's window is grown at, at most (each a stretch of its own).
_GROWN = 8


def shared_stretch(a: Record, b: Record) -> tuple[int, int, int] | None:
    """A stretch of samples two records share, the same (u, y) in the same order, or None.

    Returns ``(start in a, start in b, length)``, the stretch grown as far as the samples agree.
    Windows of 16 samples along which y varies (a held input at a constant quantised output
    repeats without being the same data), at 8 evenly spaced places of each record, are looked
    up in the other: a shared stretch longer than an eighth of either record (plus a window) is
    always found, a shorter one may be. Identical records give ``(0, 0, N)``.

    A stretch that slicing one record gives (:func:`sliced`: one record inside the other, or the
    end of one the start of the other) is returned before any other found. Any other is
    ambiguous: a record built around a piece of another shares one, and so do separate
    noise-free runs of one system at designed input levels, wherever their states meet (the
    same first steps from rest, the same steps after the same level).
    """
    za, zb = _samples(a, b)
    if za.shape[1] < 2:
        return None  # no input in common: not the same data (the caller says what else is wrong)
    found = None
    for x, z, flip in ((za, zb, False), (zb, za, True)):
        k = min(_WINDOW, len(x), len(z))
        if k < 2:
            continue
        moves = np.concatenate([[0], np.cumsum(np.diff(x[:, -1]) != 0)])
        varied = np.flatnonzero(moves[k - 1:] - moves[:len(x) - k + 1] > 0)  # windows along which y varies
        for p in np.linspace(0, len(x) - k, _ANCHORS).astype(int):
            at = np.searchsorted(varied, p)
            if at == varied.size:
                continue  # y constant from here on: no anchor that means anything
            q = int(varied[at])
            cands = np.flatnonzero(z[:len(z) - k + 1, -1] == x[q, -1])  # y first: one column to scan
            for t in range(k):  # keep the places whose next samples agree too (few survive a step or two)
                cands = cands[(z[cands + t] == x[q + t]).all(axis=1)]
            end = -1
            for c in cands[:_GROWN]:  # a few places per anchor: noise-free runs repeat a window many times
                if c < end:
                    continue  # inside the stretch just grown
                i, j, n = _grow(x, z, q, int(c), k)
                end = j + n
                s = (j, i, n) if flip else (i, j, n)
                if sliced(s, len(a), len(b)):
                    return s
                found = s if found is None else found
    return found


def sliced(stretch: tuple[int, int, int], na: int, nb: int) -> bool:
    """Whether a shared stretch ``(start in a, start in b, length)`` of records of ``na`` and
    ``nb`` samples is what slicing one record gives: one inside the other, or the end of one
    the start of the other."""
    i, j, n = stretch
    return n == na or n == nb or (i == 0 and j + n == nb) or (j == 0 and i + n == na)


class RecordOverlapWarning(UserWarning):
    """Two records share a stretch of samples that slicing one record would not give.

    A record built around a piece of another shares one (then it is the same data there); so do
    separate noise-free runs of one system at designed input levels, wherever their states meet
    (then it is not). The warning names the stretch; a stretch that slicing gives is an error.
    """


def check_overlap(a: Record, b: Record, a_name: str, b_name: str, advice: str, prefix: str = "") -> None:
    """Refuse ``a`` where it shares data with ``b`` as slices of one record would; warn where it
    shares a stretch that separate noise-free runs could share too.

    Raises
    ------
    ValueError
        The records share a stretch that slicing gives (:func:`sliced`); the message (after
        ``prefix``, e.g. the argument's name) names it and ends with ``advice``.
    """
    s = shared_stretch(a, b)
    if s is None:
        _check_rescaled(a, b, a_name, b_name, advice, prefix)
        return
    said = _stretch_message(a, b, a_name, b_name, s)
    if sliced(s, len(a), len(b)):
        raise ValueError(f"{prefix}{said}: {advice}")
    warn(f"{prefix}{said}. Separate noise-free runs of one system share such stretches where their states meet; if it is "
         f"a piece of the {b_name} record instead, {advice}", RecordOverlapWarning)


#: A column of one record is an affine map (other units, another zero) of the other's along a stretch when the map
#: misses none of its samples by more than this fraction of the column's spread there plus 1e-5 of its largest
#: magnitude (a file another tool wrote to 6 significant digits).
_RESCALED_TOL = 1e-3
#: Alignments tried per anchor window of :func:`rescaled_stretch`, the best correlated first.
_RESCALED_TRIES = 4


def _window_spread(y: np.ndarray, k: int) -> np.ndarray:
    """The standard deviation of every window of ``k`` consecutive samples of ``y`` (y about 0: its median taken
    off), from sliding sums of each window alone (no running sum's rounding): a window whose spread is below
    rounding reads as about that rounding, which the caller's checks of whole stretches then refuse."""
    ones = np.full(k, 1.0 / k)
    mean = np.convolve(y, ones, "valid")
    return np.sqrt(np.maximum(np.convolve(y * y, ones, "valid") - mean * mean, 0.0))


def _rescaled_tol(z: np.ndarray) -> float:
    """How far an affine map may miss a sample of ``z`` (see :data:`_RESCALED_TOL`), without squaring z."""
    m = float(np.max(np.abs(z)))
    return m * _RESCALED_TOL * (float(np.std(z / m)) + 1e-2) if m > 0.0 else 0.0


def _affine(x: np.ndarray, z: np.ndarray) -> tuple[float, float] | None:
    """(s, o) with z = s x + o on every sample to :data:`_RESCALED_TOL`, or None: a held x maps to a held z (s the
    ratio of their levels, or 1 at 0), a varying x to a varying z."""
    tol = _rescaled_tol(z)
    if np.ptp(x) == 0.0:
        if np.ptp(z) > 2.0 * tol:
            return None
        return (float(z[0] / x[0]), 0.0) if x[0] != 0.0 else (1.0, float(z[0]))
    if np.ptp(z) <= 2.0 * tol or np.ptp(x) <= 2.0 * _rescaled_tol(x):
        return None  # one varies where the other is held (within its tolerance): no map of one onto the other
    xc = x - x.mean()
    s = float(xc @ (z - z.mean()) / (xc @ xc))
    o = float(z.mean() - s * x.mean())
    return (s, o) if float(np.max(np.abs(z - (s * x + o)))) <= tol else None


def _rough_windows(y: np.ndarray, k: int, m: int) -> list[int]:
    """Starts of ``m`` windows of ``k`` samples, one in each of m equal parts of ``y``: the one whose slope changes
    most for its length (a step's onset; of a smooth response every window looks alike up to an affine map, a
    decaying exponential's all of them), among those along which y varies."""
    d1, d2 = np.abs(np.diff(y)), np.abs(np.diff(y, 2))
    c1, c2 = np.concatenate([[0.0], np.cumsum(d1)]), np.concatenate([[0.0], np.cumsum(d2)])
    count = len(y) - k + 1
    moved = c1[k - 1:k - 1 + count] - c1[:count]
    with np.errstate(divide="ignore", invalid="ignore"):
        rough = (c2[k - 2:k - 2 + count] - c2[:count]) / moved
    rough[~(moved > 0.0)] = -1.0
    edges = np.linspace(0, count, m + 1).astype(int)
    return [int(e0 + np.argmax(rough[e0:e1])) for e0, e1 in zip(edges[:-1], edges[1:])
            if e1 > e0 and rough[e0:e1].max() > 0.0]


def rescaled_stretch(a: Record, b: Record) -> tuple[tuple[int, int, int], list[tuple[float, float]]] | None:
    """A stretch that slicing one record gives (:func:`sliced`) along which every column of ``a`` is an affine map of
    ``b``'s, ``a = s b + o`` (the same data in other units, from another zero, or rounded by a file), or None.

    Returns ``((start in a, start in b, length), [(s, o) of each input in common, in a's order, then of y])``.
    A window of 16 samples in each of 8 parts of each record (the one where y's slope changes most) is matched
    by correlation in the other; each alignment whose affine map holds at 64 samples spread over the stretch the
    records share there (at least two windows long) is then checked over the whole of it, where an input varies
    (at a held input, the settling of a plant of one mode is an affine map of any other of its settlings).
    """
    za, zb = _samples(a, b)
    k = _WINDOW
    if za.shape[1] < 2 or min(len(za), len(zb)) < 2 * k:
        return None
    # each column times a power of two (exact) to at most 1 in magnitude: no square below overflows or underflows
    ea, eb = (np.frexp(np.max(np.abs(z), axis=0))[1] for z in (za, zb))
    za, zb = np.ldexp(za, -ea), np.ldexp(zb, -eb)
    for x, z, flip in ((za, zb, False), (zb, za, True)):
        yx, yz = x[:, -1], z[:, -1] - np.median(z[:, -1])
        spread = _window_spread(yz, k)
        level = np.convolve(yz, np.full(k, 1.0 / k), "valid")
        loose = 1e-2 * (float(np.std(yz)) + 1e-2 * float(np.max(np.abs(yz))))
        tried: set[int] = set()
        for p in _rough_windows(yx, k, _ANCHORS):
            w = yx[p:p + k] - yx[p:p + k].mean()
            sw = float(np.linalg.norm(w))
            with np.errstate(divide="ignore", invalid="ignore"):
                corr = np.correlate(yz, w / sw, "valid") / (spread * np.sqrt(k))
            near = np.flatnonzero((spread > 0.0) & (np.abs(corr) >= 1.0 - 1e-4))  # the window's shape
            # the window's map (z = s x + o there), tried at 64 samples spread over the stretch shared at each
            sc = corr[near] * spread[near] * np.sqrt(k) / sw
            oc = level[near] - sc * yx[p:p + k].mean()
            d = p - near  # x[i] is z[i - d]
            i0 = np.maximum(0, d)
            n = np.minimum(len(x) - i0, len(z) - (i0 - d))
            probe = i0[:, None] + (np.linspace(0.0, 1.0, 64)[None, :] * np.maximum(n - 1, 0)[:, None]).astype(int)
            held = np.abs(yz[probe - d[:, None]] - (sc[:, None] * yx[probe] + oc[:, None])).max(axis=1) <= loose
            keep = np.flatnonzero(held & (n >= 2 * k))
            keep = keep[np.argsort(-np.abs(corr[near[keep]]), kind="stable")][:_RESCALED_TRIES]
            for q in keep:
                dq, iq, nq = int(d[q]), int(i0[q]), int(n[q])
                if dq in tried:
                    continue
                tried.add(dq)
                xs, zs = x[iq:iq + nq], z[iq - dq:iq - dq + nq]
                if flip:  # a's columns as maps of b's
                    maps = [_affine(xs[:, c], zs[:, c]) for c in range(x.shape[1])]
                    stretch = (iq - dq, iq, nq)
                else:
                    maps = [_affine(zs[:, c], xs[:, c]) for c in range(x.shape[1])]
                    stretch = (iq, iq - dq, nq)
                if any(m is None for m in maps) or all(np.ptp(xs[:, c]) == 0.0 for c in range(x.shape[1] - 1)):
                    # (every input held there: a settling at one input is an affine map of any other of it, from
                    # any state, for a plant of one mode; such a stretch says nothing of which data it is)
                    continue
                # a = s b + o on the scaled columns: in their own units s·2^(ea − eb) and o·2^ea
                return stretch, [(float(np.ldexp(s, int(e - f))), float(np.ldexp(o, int(e))))
                                 for (s, o), e, f in zip(maps, ea, eb)]  # type: ignore[misc]
    return None


def _check_rescaled(a: Record, b: Record, a_name: str, b_name: str, advice: str, prefix: str) -> None:
    """:func:`check_overlap` for :func:`rescaled_stretch`: refused where every signal is the other's up to rounding, or
    where one side (the inputs, or the output) is the other's and a signal of the other side is scaled (no experiment
    gives y·1000 at the same inputs); said (a :class:`RecordOverlapWarning`) where both sides are changed (other
    units, or a run of an affine plant at affinely mapped inputs), or one side by offsets alone (an integrating
    plant's run from another level, a washout plant's at another input level)."""
    found = rescaled_stretch(a, b)
    if found is None:
        return
    (i, j, n), maps = found
    names = [nm for nm in a.input_names if nm in b.input_names] + ["y"]
    kept, said_maps = [], []
    for nm, (s, o) in zip(names, maps):
        x = (a.y if nm == "y" else a.input(nm))[i:i + n]
        unit, zero = abs(s - 1.0) <= 1e-4, abs(o) <= _rescaled_tol(x)
        kept.append(unit and zero)
        if not (unit and zero):  # the map in words, round-off left out ("its y = 1000 × the other's")
            said_maps.append(f"its {nm} = {'' if unit else f'{s:.6g} × '}the other's"
                             + ("" if zero else f" {'+' if o > 0 else '−'} {abs(o):.6g}"))
    how = ", ".join(said_maps)
    said = (f"the {a_name} record ({a.name!r}) shares {n} samples with the {b_name} record ({b.name!r}) "
            + (f"up to rounding (to {_RESCALED_TOL:g} of each signal's spread)" if all(kept)
               else f"in other units ({how}, to {_RESCALED_TOL:g} of each signal's spread)")
            + f": its samples {i}..{i + n - 1} are samples {j}..{j + n - 1} of the other")
    scaled = any(abs(s - 1.0) > 1e-4 for s, _ in maps)
    if all(kept) or (scaled and (kept[-1] or all(kept[:-1]))):
        raise ValueError(f"{prefix}{said}: {advice}")
    if scaled:
        warn(f"{prefix}{said.replace('in other units', 'scaled')}. A run of a linear (or affine) plant at inputs "
             f"mapped so gives such outputs; if it is the {b_name} data in other units instead, {advice}",
             RecordOverlapWarning)
        return
    # offsets alone on one side: an integrating plant run again from another level (or under another constant
    # load) gives outputs offset so at the same inputs, a plant that answers its inputs' changes only one output at
    # inputs offset so; separate experiments as likely as one record from another zero
    warn(f"{prefix}{said.replace('in other units', 'offset')}. An integrating plant run again from another level "
         "(or under another constant load) gives outputs offset so, and a plant that answers its inputs' changes "
         f"only one output at inputs offset so; if it is the {b_name} data from another zero instead, {advice}",
         RecordOverlapWarning)


def _samples(a: Record, b: Record) -> tuple[np.ndarray, np.ndarray]:
    """Each record's (u, y) as rows of one array, shape (N, c + 1): the c inputs both have, taken by
    name in ``a``'s order (the same data read with its columns in another order, or with transient
    inputs added, is still the same data)."""
    names = [n for n in a.input_names if n in b.input_names]
    return tuple(np.column_stack([r.input(n) for n in names] + [r.y]) for r in (a, b))  # type: ignore[return-value]


def _grow(x: np.ndarray, z: np.ndarray, i: int, j: int, n: int) -> tuple[int, int, int]:
    """Extend the matching stretch x[i:i+n] == z[j:j+n] backwards and forwards while rows agree."""
    back = _agreeing(x[:i][::-1], z[:j][::-1])
    i, j, n = i - back, j - back, n + back
    return i, j, n + _agreeing(x[i + n:], z[j + n:])


def _agreeing(x: np.ndarray, z: np.ndarray) -> int:
    """How many leading rows of x and z agree, compared in blocks that double (most stop early)."""
    m = min(len(x), len(z))
    k, step = 0, 16
    while k < m:
        stop = min(m, k + step)
        differ = np.flatnonzero((x[k:stop] != z[k:stop]).any(axis=1))
        if differ.size:
            return k + int(differ[0])
        k, step = stop, 2 * step
    return m


def _stretch_message(a: Record, b: Record, a_name: str, b_name: str, s: tuple[int, int, int]) -> str:
    i, j, n = s
    return (f"the {a_name} record ({a.name!r}) shares {n} samples with the {b_name} record ({b.name!r}): its "
            f"samples {i}..{i + n - 1} are samples {j}..{j + n - 1} of the other")


#: Samples in a block of a record's print (:class:`RecordPrint`), at least.
_PRINT_BLOCK = 16
#: Blocks in a print, at most: longer records take longer blocks, so that a saved Pareto set stays small (about
#: 44 kB of base64 per fitting record of any length, against 670 kB for 10⁶ samples in blocks of 16); a slice
#: shorter than two blocks is then not seen after loading.
_PRINT_BLOCKS = 4096
#: Alignments of a choosing record against a print tried, at most (the most often matched first).
_PRINT_TRIES = 32
_MIX = (np.uint64(0xBF58476D1CE4E5B9), np.uint64(0x94D049BB133111EB))


def _mix(z: np.ndarray) -> np.ndarray:
    """splitmix64's finaliser on uint64 arrays (wrapping; a bijection that spreads every bit)."""
    z = z ^ (z >> np.uint64(30))
    z = z * _MIX[0]
    z = z ^ (z >> np.uint64(27))
    z = z * _MIX[1]
    return z ^ (z >> np.uint64(31))


def _row_hashes(rows: np.ndarray) -> np.ndarray:
    """One uint64 per row of (u, y) samples, from their float64 bits (-0.0 read as 0.0, as ``==`` reads it)."""
    bits = np.ascontiguousarray(np.asarray(rows, np.float64) + 0.0).view(np.uint64)
    h = np.zeros(len(rows), np.uint64)
    for j in range(bits.shape[1]):
        h = _mix(h ^ bits[:, j] ^ np.uint64(j + 1))
    return h


def _window_hashes(h: np.ndarray, width: int) -> np.ndarray:
    """The hash of every window of ``width`` consecutive rows (its rows in order), shape (len(h) - width + 1,)."""
    m = len(h) - width + 1
    acc = np.zeros(max(m, 0), np.uint64)
    for t in range(width):
        acc = acc + _mix(h[t:t + m] ^ np.uint64(0x9E3779B97F4A7C15 * (t + 1) % (1 << 64)))
    return _mix(acc)


@dataclass(frozen=True, eq=False)
class RecordPrint(Relocked):
    """A record's fingerprint, kept where its samples are not (a Pareto set saved to a file): enough to
    recognise the record, a copy of it and slices of it (:func:`check_print_overlap`) as
    :func:`same_record` and :func:`check_overlap` recognise them with the samples at hand.

    ``digests`` (uint64): the hash of each whole block of ``block`` samples (u by ``input_names``, then y) from
    sample 0, then the hash of the last ``block`` samples.
    """

    name: str
    length: int
    input_names: tuple[str, ...]
    block: int
    digests: np.ndarray

    def __post_init__(self) -> None:
        d = np.asarray(self.digests)
        if d.dtype != np.uint64 or d.ndim != 1:
            raise TypeError("RecordPrint: digests must be a 1-D uint64 array")
        if not (isinstance(self.length, int) and isinstance(self.block, int) and 1 <= self.block <= self.length):
            raise ValueError(f"RecordPrint: need 1 <= block <= length; got block {self.block!r}, length {self.length!r}")
        if d.size != self.length // self.block + 1:
            raise ValueError(f"RecordPrint: {d.size} digests for {self.length} samples in blocks of {self.block} "
                             f"(want {self.length // self.block + 1})")
        # the inputs' names as a record's are (a file's print naming one twice, or none, describes no record)
        object.__setattr__(self, "input_names", check_input_names(self.input_names, what="RecordPrint: input_names"))
        object.__setattr__(self, "digests", locked(d))


def record_print(record: Record) -> RecordPrint:
    """The :class:`RecordPrint` of ``record``."""
    names = tuple(record.input_names)
    h = _row_hashes(np.column_stack([record.input(n) for n in names] + [record.y]))
    N = len(record)
    W = min(max(_PRINT_BLOCK, -(-N // _PRINT_BLOCKS)), N)
    win = _window_hashes(h, W)
    return RecordPrint(record.name, N, names, W, np.concatenate([win[0:N - W + 1:W][:N // W], win[-1:]]))


def check_print_overlap(a: Record, p: RecordPrint, a_name: str, b_name: str, advice: str, prefix: str = "") -> None:
    """:func:`same_record` and :func:`check_overlap`'s refusal against a record known by its print only.

    ``ValueError`` when ``a`` holds the print's record, or shares with it the samples slicing one record gives
    (one inside the other, or the end of one the start of the other), seen in the print's whole blocks (a
    stretch's first and last few samples, inside a block, are not compared); nothing when ``a`` lacks one of
    the print's inputs, or the output does not vary along the samples compared (as the records' own check: a
    held level is no evidence; so a slice whose output varies only in its first or last few samples, at a held
    level elsewhere, is not seen). A stretch that slicing does not give is not looked for (the records' check
    warns of one). Records that share samples except a few at an end (separate noise-free runs whose states meet
    after a step) are refused where the records' own check warns: those samples are not compared."""
    if not all(n in a.input_names for n in p.input_names):
        return
    n, N, W = len(a), p.length, p.block
    if n < W:
        return
    z = np.column_stack([a.input(m) for m in p.input_names] + [a.y])
    hc = _window_hashes(_row_hashes(z), W)
    blocks, tail = p.digests[:-1], p.digests[-1]
    # alignments (a[k] is the record's k + off) where one of a's windows is one of the print's blocks or its tail
    starts = np.concatenate([np.arange(blocks.size) * W, [N - W]])
    order = np.argsort(p.digests, kind="stable")
    keys = p.digests[order]
    lo = np.searchsorted(keys, hc, "left")
    hi = np.searchsorted(keys, hc, "right")
    hit = np.flatnonzero(hi > lo)
    if not hit.size:
        return
    # the windows whose block is rarest in the print first: a record at rest (or repeating) for long holds one
    # block many times, each of a's windows there a hit that names none of the alignments the tries look at
    hit = hit[np.argsort((hi - lo)[hit], kind="stable")]
    # each hit's vote shared among the blocks it matches: one of a block the print holds once outweighs the many
    # that a held level's windows cast for every alignment of its blocks (counted alike, they tied with the true one
    # and the nearer alignments went first)
    offs: dict[int, float] = {}
    for q in hit[:4096]:
        vote = 1.0 / float(hi[q] - lo[q])
        for k in order[lo[q]:hi[q]][:_PRINT_TRIES]:
            off = int(starts[k]) - int(q)
            offs[off] = offs.get(off, 0.0) + vote
    for off in sorted(offs, key=lambda o: (-offs[o], abs(o)))[:_PRINT_TRIES]:
        s, e = max(0, -off), min(n, N - off)  # the overlap, in a's samples
        b0, b1 = -(-(s + off) // W), (e + off) // W  # the print's whole blocks inside it
        idx = np.arange(b0, b1)
        ok = bool(np.all(hc[idx * W - off] == blocks[idx]))
        seen = idx.size
        v0, v1 = (b0 * W - off, b1 * W - off) if idx.size else (e, s)  # the samples of a compared, in a
        if e == N - off and N - W - off >= s:  # the record's end is inside a: its last samples too
            ok = ok and bool(hc[N - W - off] == tail)
            seen += 1
            v0, v1 = min(v0, N - W - off), e
        # y must vary along the samples compared (not merely the overlap, whose ends are not compared: a record
        # sharing only a held level with the other, between samples of its own, is no piece of it)
        if not (ok and seen and np.ptp(a.y[v0:v1]) > 0):
            continue
        if s == 0 and e == n == N and off == 0:
            raise ValueError(f"{prefix}the {a_name} record {a.name!r} is a {b_name} record ({p.name!r}): {advice}")
        raise ValueError(f"{prefix}the {a_name} record ({a.name!r}) shares {e - s} samples with the {b_name} record "
                         f"({p.name!r}): its samples {s}..{e - 1} are samples {s + off}..{e + off - 1} of the other: "
                         f"{advice}")


def choosing_records(value: object, name: str = "choose_on", example: str = "data.valid") -> list[Record]:
    """Records to choose (or test) on: a Record or a non-empty list or tuple of them (a Dataset is refused:
    as one record it would stand for its ident, the fitting data). ``TypeError`` for anything else, its
    message naming ``example`` as one."""
    recs = [value] if isinstance(value, Record) else list(value) if isinstance(value, (list, tuple)) else None
    if recs is None:
        raise TypeError(f"{name} must be a Record or a sequence of Records (e.g. {example}), got a "
                        f"{type(value).__name__}")
    for i, r in enumerate(recs):  # the element named, not the whole list (each record's repr is long)
        if not isinstance(r, Record):
            raise TypeError(f"{name} must be a Record or a sequence of Records (e.g. {example}): {name}[{i}] is a "
                            f"{type(r).__name__}")
    if not recs:
        raise ValueError(f"{name}: an empty list; at least one record is needed")
    return recs


__all__ += ["outside_range", "rounded_levels", "same_record", "shared_stretch", "sliced", "check_overlap", "RecordOverlapWarning", "choosing_records",
            "rescaled_stretch",
            "RecordPrint", "record_print", "check_print_overlap"]
