"""Save and load graybox values as readable JSON (never pickle).

One file holds one value::

    {
      "format": "graybox",
      "format_version": 1,
      "graybox_version": "0.2.1",
      "type": "Model",
      "units": {"u": "rpm", "y": "mlc"},
      "object": {
        "name": "ELS",
        "structure": ["y(k-1)", "u(k-2)y(k-6)", …],      terms as the paper prints them
        "theta": [0.6303, 0.00023011, …],
        …
        "equation": "y(k) = 0.6303 y(k-1) + …"          for the reader, from the terms and θ; checked on load
      }
    }

Numbers are JSON numbers written with Python's shortest round-trip ``repr``, so every finite float
comes back bit for bit (−0.0 and subnormals included); ±∞ and NaN, which JSON lacks, are the
strings ``"inf"``, ``"-inf"`` and ``"nan"``. Vectors are written on one line, matrices one row per
line. Loading reads the ``NaN`` and ``Infinity`` literals Python's json writes as the values they name (each
value's constructor then refuses a non-finite number where it has none, e.g. in θ); a number written finite and not
zero that no float holds is refused, naming it and its place (``object.theta[2]: the number 1e400 is beyond the
float range``): beyond ±1.8e308, which float() reads as ±inf, or below 5e-324, which it reads as 0.0 (``1e-400``).
Either would load as a number other than the one written (an underflow is refused as an overflow is: a term's
coefficient silently 0 is a term dropped); graybox never writes one.

Types: :class:`~graybox.Model`, :class:`~graybox.NeuralModel`, :class:`~graybox.ParetoSet`,
:class:`~graybox.Selection`, :class:`~graybox.ELSResult`, :class:`~graybox.NeuralFit`,
:class:`~graybox.Decision`, :class:`~graybox.DSFResult`, :class:`~graybox.OEResult`, :class:`~graybox.SEMPResult`,
:class:`~graybox.ParameterUncertainty`, :class:`~graybox.StaticCurveBand`, :class:`~graybox.StaticSurfaceBand`,
:class:`~graybox.SimulationBand`, :class:`~graybox.CLSResult`, :class:`~graybox.GAOptions`, the diagnostics (:class:`~graybox.ResidualTests` and
its tests, :class:`~graybox.CorrelationTest`; :class:`~graybox.DecisionBootstrap`), the static
information (:class:`~graybox.StaticPoints`, :class:`~graybox.StaticCurve`, :class:`~graybox.StaticSurface`,
:class:`~graybox.Equilibrium`), the local models (:class:`~graybox.LocalModel`, :class:`~graybox.OperatingCurve`),
the data (:class:`~graybox.Record`, :class:`~graybox.Dataset`, :class:`~graybox.Structure`) and, registered by
the layers above this one, :class:`~graybox.DecimationAdvice` (datasets) and :class:`~graybox.GrayboxSelection`
(experiments). A bootstrap's ``options`` and ``reference`` and a Dataset's ``extra`` are mappings of plain
values: null, true/false, integers, numbers with a point and text as JSON has them, the rest as an object of
one key (``{"float": "nan"}``, ``{"scalar": {"dtype", "value"}}`` for NumPy's (its text: dtype "str"), ``{"array": {"dtype", "shape", "data"}}``, ``{"tuple": […]}``, ``{"list": […]}``,
``{"map": {…}}``, ``{"type": {"type", "object"}}`` for a saved type), so that each reads back as the type it was.
What JSON cannot carry (a function, a plant simulator, a constraint, Dask's lazy arrays) is refused when saving,
naming the field. Their tables (pandas DataFrames of int64, float64, bool or
text columns with distinct text labels) are written one column per line, with the index and each
column's kind; text loads as pandas' default text dtype. A table the format cannot carry is
refused when saving, not converted.

Loading refuses, with a :class:`GrayboxFileError` naming the file and the problem: a file that is
not JSON or not a graybox file, a newer or unknown ``format_version``, an unknown type, a type other
than the one expected, a missing or unknown field, a value of the wrong kind; the value's own
constructor then validates shapes and meaning (e.g. θ's length against the structure). A Model's
``structure`` and ``theta`` (and the noise terms) are the model; its ``equation`` is written from them to 6
significant digits for the reader, and a file whose equation disagrees with them (θ edited and the equation not, or
the other way round) is refused naming both: each coefficient must be θ to the 6 significant digits written (or
to more, where the text shows more), term by term in order (a file without the equation loads). Its ``clusters``
are read and not checked. The units
(of u and y) are written when given and read back with :func:`read_header`.

A :class:`~graybox.ParetoSet`'s ``fitted_on`` is saved as a print of each record it was fitted on (its name, length,
input names and hashes of its samples in blocks of 16, or of N / 4096 for longer records: not the samples), so that
the set read back refuses those records, copies and slices of them (at least two blocks long) as choosing records (:func:`graybox.decide_dsf`'s ``choose_on``) as the set
did when it was made; a file written without it loads, with that check left to the set's own J_S. A print compares
the samples' bits: the fitting data in other units, from another zero or rounded (y × 1000, a file written to 6
digits), which the set with its records refuses, pass it (units named on both sides are still compared); give the set
read back its records (``dataclasses.replace(pareto, fitted_on=(data.ident,))``) to run that check.
"""

from __future__ import annotations

import base64
import binascii
import errno
import importlib
import itertools
import json
import math
import os
import re
import reprlib
from pathlib import Path
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from ..estimation._decisions import Decision
from ..estimation._extended_least_squares import ELSResult
from ..models._model import Model
from ..estimation._neural import NeuralFit, NeuralModel
from ..estimation._pareto import ParetoSet
from ..estimation._epsilon_constraint import DSFResult
from ..selection._forward_regression import Selection
from ..core._records import Dataset, Record, RecordPrint, StaticPoints, check_units, input_unit, record_print
from ..core._files import bom_encoding, write_atomically
from ..core._validation import MAX_NESTING, FrozenMap, check_path, locked
from ..core._version import graybox_version
from ..core._terms import Structure, parse_term
from ..static._analysis import Equilibrium
from ..static._constraints import StaticConstraint
from ..static._curves import StaticCurve
from ..static._surfaces import StaticSurface
from ..estimation._prediction_error import CLSResult
from ..control._local import LocalModel, OperatingCurve
from ..diagnostics._simulation_band import SimulationBand
from ..diagnostics._uncertainty import ParameterUncertainty, StaticCurveBand, StaticSurfaceBand
from ..diagnostics._residuals import CorrelationTest, ResidualTests
from ..diagnostics._bootstrap import DecisionBootstrap
from ..estimation._simulation_error import GAOptions

if TYPE_CHECKING:  # pandas takes ~0.4 s to import: loaded where a table is made
    import pandas as pd

__all__ = ["FORMAT_VERSION", "GrayboxFileError", "save", "load", "to_json", "from_json", "read_header"]

#: The version of the file layout this graybox writes and reads.
FORMAT_VERSION = 1


class GrayboxFileError(ValueError):
    """A file (or JSON text) cannot be loaded: not graybox's, a newer format, corrupt, or of another type."""



# --------------------------------------------------------------------------------------------
# scalars and arrays
# --------------------------------------------------------------------------------------------
def _num(x: float) -> float | str:
    x = float(x)
    if math.isfinite(x):
        return x
    return "nan" if math.isnan(x) else ("inf" if x > 0 else "-inf")


def _arr(a: Any) -> Any:
    a = np.asarray(a, float)
    if a.ndim == 0:
        return _num(a)
    if np.isfinite(a).all():  # Python floats at once, bit for bit (-0.0 too)
        return a.tolist()
    return [_arr(r) for r in a] if a.ndim > 1 else [_num(v) for v in a]


#: The strings a number may be written as (JSON has no ±∞ nor NaN).
_NON_FINITE = frozenset({"nan", "inf", "-inf"})


def _numbers(v: Any, ndim: int) -> np.ndarray | None:
    """``v`` as an array of ``ndim`` dimensions in one conversion, when it is one: a non-empty nest of lists of equal
    lengths holding JSON numbers and ``"nan"``, ``"inf"``, ``"-inf"`` (read as ``float()`` reads them, bit for bit);
    None for anything else, which the reader then refuses (or reads) number by number, naming where."""
    if type(v) is not list or not v:
        return None
    flat = v
    for _ in range(ndim - 1):
        if set(map(type, flat)) != {list} or len(set(map(len, flat))) != 1:
            return None
        flat = list(itertools.chain.from_iterable(flat))
    kinds = set(map(type, flat))
    if not kinds <= {float, int, str}:  # bool, None, lists deeper than ndim, objects
        return None
    if str in kinds and not {x for x in flat if type(x) is str} <= _NON_FINITE:
        return None
    try:
        a = np.array(v, dtype=float)
    except (OverflowError, ValueError):  # an integer beyond the float range
        return None
    return a if a.ndim == ndim else None


class _Reader:
    """Typed access to decoded JSON, with errors that say where."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, where: str, what: str) -> GrayboxFileError:
        return GrayboxFileError(f"{self.source}: {where}: {what}")

    def float(self, v: Any, where: str) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float, str)):
            raise self.fail(where, f"expected a number, got {type(v).__name__}")
        if isinstance(v, str):
            if v not in ("nan", "inf", "-inf"):
                raise self.fail(where, f"expected a number, got the string {v!r}")
            return float(v)
        try:
            return float(v)
        except OverflowError:  # an integer beyond the float range
            raise self.fail(where, "a number beyond the float range") from None

    def int(self, v: Any, where: str) -> int:
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.fail(where, f"expected an integer, got {v!r}")
        if not -2**63 <= v < 2**63:
            raise self.fail(where, "an integer beyond the 64-bit range")
        return v

    def seed(self, v: Any, where: str) -> int:
        """A random generator's seed: an integer >= 0 of any size, as NumPy takes it (a 128-bit one from
        ``SeedSequence().entropy`` too), not only 64-bit."""
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.fail(where, f"expected an integer, got {v!r}")
        if v < 0:
            raise self.fail(where, f"a seed is an integer >= 0, got {v}")
        return v

    def str(self, v: Any, where: str) -> str:
        if not isinstance(v, str):
            raise self.fail(where, f"expected a string, got {type(v).__name__}")
        return v

    def bool(self, v: Any, where: str) -> bool:
        if not isinstance(v, bool):
            raise self.fail(where, f"expected true or false, got {v!r}")
        return v

    def list(self, v: Any, where: str) -> list:
        if not isinstance(v, list):
            raise self.fail(where, f"expected a list, got {type(v).__name__}")
        return v

    def dict(self, v: Any, where: str) -> dict:
        if not isinstance(v, dict):
            raise self.fail(where, f"expected an object, got {type(v).__name__}")
        return v

    def array(self, v: Any, where: str, ndim: int) -> np.ndarray:
        if ndim == 0:
            return np.array(self.float(v, where))
        whole = _numbers(v, ndim)
        if whole is not None:
            return locked(whole)
        # number by number: what is not a regular array of numbers is refused, naming where
        rows = self.list(v, where)
        out = [self.array(r, f"{where}[{i}]", ndim - 1) for i, r in enumerate(rows)]
        if ndim > 1 and len({o.shape for o in out}) > 1:
            raise self.fail(where, "rows of different lengths")
        return locked(np.zeros((0,) * ndim) if not out else np.array(out, dtype=float))  # as computed ones

    def floats(self, v: Any, where: str) -> tuple[float, ...]:
        return tuple(self.float(x, f"{where}[{i}]") for i, x in enumerate(self.list(v, where)))

    def structure(self, v: Any, where: str) -> Structure:
        terms = [self.str(t, f"{where}[{i}]") for i, t in enumerate(self.list(v, where))]
        try:
            return Structure(parse_term(t) for t in terms)
        except ValueError as exc:
            raise self.fail(where, str(exc)) from None


# --------------------------------------------------------------------------------------------
# codecs: per type, its fields as (name, kind); kinds map to an encoder and a reader method
# --------------------------------------------------------------------------------------------
def _enc(kind: str, v: Any, where: str = "") -> Any:
    if kind.endswith(_OR_NONE):
        return None if v is None else _enc(kind[:-len(_OR_NONE)], v, where)
    if kind in ("float", "array1", "array2", "inputs"):
        return _arr(v)
    if kind in ("int", "seed", "str", "bool"):
        # a NumPy bool (rho < 1, a comparison of arrays), which the classes take for True or False, is no JSON
        return int(v) if kind in ("int", "seed") else bool(v) if kind == "bool" else v
    if kind == "floats":
        return [_num(x) for x in v]
    if kind == "pairs":
        return [[_num(x) for x in p] for p in v]
    if kind == "exponents":
        return [[int(x) for x in e] for e in v]
    if kind == "static":
        return {"type": _saved_name(v, where), "object": _encode_fields(v, where)}
    if kind == "local_models":
        return [_encode_fields(m, f"{where}[{i}]") for i, m in enumerate(v)]
    if kind == "structure":
        return [str(t) for t in v]
    if kind == "structures":
        return [[str(t) for t in x] for x in v]
    if kind == "names":
        return [str(n) for n in v]
    if kind == "units":  # (input unit, output unit); the input's a str, or a list of one per input
        return [v[0] if isinstance(v[0], str) else [str(x) for x in v[0]], str(v[1])]
    if kind == "arrays":
        return [_arr(a) for a in v]
    if kind == "dict_arrays":
        return {str(k): _arr(a) for k, a in dict(v).items()}
    if kind == "failures":
        return {str(k): str(r) for k, r in dict(v).items()}
    if kind == "prints":  # a ParetoSet's fitting records: their prints, never their samples
        return [_enc_print(record_print(r) if isinstance(r, Record) else r) for r in v]
    if kind == "skipped":
        return [[str(t), str(why)] for t, why in v]
    if kind == "frame":
        return _enc_frame(v)
    if kind == "ints":
        return [int(x) for x in v]
    if kind == "int_array1":
        return [int(x) for x in np.asarray(v).ravel()]
    if kind == "bool_array1":
        return [bool(x) for x in np.asarray(v).ravel()]
    if kind == "texts":
        return {str(k): str(r) for k, r in dict(v).items()}
    if kind in ("band", "float_or_floats"):
        return _num(v) if np.ndim(v) == 0 else [_num(x) for x in v]
    if kind == "correlation_tests":
        return {str(k): _encode_fields(t, f"{where}[{k!r}]") for k, t in dict(v).items()}
    if kind == "plain_map":
        try:
            return _enc_plain_map(v, where)
        except ValueError as exc:
            if where != "Dataset.extra":
                raise
            # a bundled set's simulator or theoretical surface: what to save instead, every entry JSON cannot carry
            bad = tuple(k for k, x in v.items() if not isinstance(k, str) or not _plain(x, f"{where}[{k!r}]"))
            raise ValueError(f"{exc}. The records and points save without {'it' if len(bad) == 1 else 'them'}: "
                             f"dataclasses.replace(data, extra={{k: v for k, v in data.extra.items() if k not in "
                             f"{bad!r}}})") from None
    if kind in _CODECS:
        return _encode_fields(v, where)
    raise AssertionError(kind)  # pragma: no cover - a codec table error


def _dec(kind: str, v: Any, where: str, rd: _Reader) -> Any:
    if kind.endswith(_OR_NONE):
        return None if v is None else _dec(kind[:-len(_OR_NONE)], v, where, rd)
    if kind == "float":
        return rd.float(v, where)
    if kind == "array1":
        return rd.array(v, where, 1)
    if kind == "array2":
        return rd.array(v, where, 2)
    if kind == "inputs":  # shape (M,) for one input, (M, m) for several: the nesting says which
        return rd.array(v, where, 2 if rd.list(v, where) and isinstance(v[0], list) else 1)
    if kind == "int":
        return rd.int(v, where)
    if kind == "seed":
        return rd.seed(v, where)
    if kind == "pairs":
        return tuple(rd.floats(p, f"{where}[{i}]") for i, p in enumerate(rd.list(v, where)))
    if kind == "exponents":
        return tuple(tuple(rd.int(x, f"{where}[{i}][{j}]") for j, x in enumerate(rd.list(e, f"{where}[{i}]")))
                     for i, e in enumerate(rd.list(v, where)))
    if kind == "static":
        d = rd.dict(v, where)
        typ = d.get("type")
        if typ not in _STATIC or set(d) != {"type", "object"}:
            raise rd.fail(where, f"expected {{\"type\": one of {list(_STATIC)}, \"object\": …}}")
        return _decode_fields(typ, d["object"], f"{where}.object", rd)
    if kind == "local_models":
        return tuple(_decode_fields("LocalModel", m, f"{where}[{i}]", rd) for i, m in enumerate(rd.list(v, where)))
    if kind == "str":
        return rd.str(v, where)
    if kind == "bool":
        return rd.bool(v, where)
    if kind == "floats":
        return rd.floats(v, where)
    if kind == "structure":
        return rd.structure(v, where)
    if kind == "structures":
        return tuple(rd.structure(x, f"{where}[{i}]") for i, x in enumerate(rd.list(v, where)))
    if kind == "names":
        return tuple(rd.str(n, f"{where}[{i}]") for i, n in enumerate(rd.list(v, where)))
    if kind == "units":
        return _read_units(rd, v, where)
    if kind == "arrays":
        return tuple(rd.array(a, f"{where}[{i}]", 1) for i, a in enumerate(rd.list(v, where)))
    if kind == "dict_arrays":
        return {k: rd.array(a, f"{where}.{k}", 1) for k, a in rd.dict(v, where).items()}
    if kind == "prints":
        return tuple(_dec_print(x, f"{where}[{i}]", rd) for i, x in enumerate(rd.list(v, where)))
    if kind == "failures":
        out = {}
        for k, r in rd.dict(v, where).items():
            if not re.fullmatch(r"-?[0-9]+", k):  # str.isdigit takes '²', and lstrip('-') '--1': int() refuses both
                raise rd.fail(f"{where}.{k}", "a member index must be an integer")
            out[int(k)] = rd.str(r, f"{where}.{k}")
        return out
    if kind == "skipped":
        out = []
        for i, pair in enumerate(rd.list(v, where)):
            p = rd.list(pair, f"{where}[{i}]")
            if len(p) != 2:
                raise rd.fail(f"{where}[{i}]", "expected [term, reason]")
            try:
                out.append((parse_term(rd.str(p[0], f"{where}[{i}][0]")), rd.str(p[1], f"{where}[{i}][1]")))
            except ValueError as exc:
                raise rd.fail(f"{where}[{i}][0]", str(exc)) from None
        return tuple(out)
    if kind == "frame":
        return _dec_frame(v, where, rd)
    if kind == "ints":
        return tuple(rd.int(x, f"{where}[{i}]") for i, x in enumerate(rd.list(v, where)))
    if kind == "int_array1":
        return _read_only(np.array([rd.int(x, f"{where}[{i}]") for i, x in enumerate(rd.list(v, where))], np.int64))
    if kind == "bool_array1":
        return _read_only(np.array([rd.bool(x, f"{where}[{i}]") for i, x in enumerate(rd.list(v, where))], np.bool_))
    if kind == "texts":
        return {k: rd.str(r, f"{where}.{k}") for k, r in rd.dict(v, where).items()}
    if kind == "float_or_floats":  # one number, or a list of them read as a tuple
        return rd.floats(v, where) if isinstance(v, list) else rd.float(v, where)
    if kind == "band":  # one number (0, B] or a pair [low, high]
        if not isinstance(v, list):
            return rd.float(v, where)
        if len(v) != 2:
            raise rd.fail(where, f"expected a number or a pair [low, high], got {len(v)} numbers")
        return rd.floats(v, where)
    if kind == "correlation_tests":
        return {k: _decode_fields("CorrelationTest", t, f"{where}.{k}", rd) for k, t in rd.dict(v, where).items()}
    if kind == "plain_map":
        return {k: _dec_plain(x, f"{where}.{k}", rd) for k, x in rd.dict(v, where).items()}
    if kind in _CODECS:
        return _decode_fields(kind, v, where, rd)
    raise AssertionError(kind)  # pragma: no cover


# --------------------------------------------------------------------------------------------
# tables (pandas DataFrames of result objects): columns of int, float, bool or str
# --------------------------------------------------------------------------------------------
#: Column kinds of a saved table: the reader's method, the dtype it loads as, the writer.
#: Text loads as pandas' default text dtype ("str").
_FRAME_KINDS = {"int": ("int", np.int64, int), "float": ("float", np.float64, _num), "bool": ("bool", np.bool_, bool),
                "str": ("str", "str", str)}

#: Largest table the loader builds (rows), so that a crafted length cannot ask for terabytes.
_MAX_ROWS = 10**8


def _column_kind(values: pd.Series | pd.Index, name: str) -> str:
    import pandas as pd

    dtype = values.dtype
    if isinstance(dtype, np.dtype) and dtype in (np.int64, np.float64, np.bool_):
        return {"i": "int", "f": "float", "b": "bool"}[dtype.kind]
    text = isinstance(dtype, pd.StringDtype) or (isinstance(dtype, np.dtype) and dtype.kind == "O")
    if text and all(isinstance(x, str) for x in values):
        return "str"
    raise ValueError(f"cannot save the table column {name!r} of dtype {dtype}: a saved table holds int64, float64, "
                     "bool or text columns (text without missing values)")


def _column(kind: str, values: Any) -> list:
    write = _FRAME_KINDS[kind][2]
    return [write(x) for x in values]


def _enc_frame(df: pd.DataFrame) -> dict:
    """A table as {index, columns, kinds, data}: one list per column (a row of the file each)."""
    import pandas as pd

    idx = df.index
    labels = list(df.columns)
    bad = [c for c in labels if not isinstance(c, str)]
    if bad or len(set(labels)) < len(labels) or df.columns.name is not None or isinstance(idx, pd.MultiIndex) \
            or not (idx.name is None or isinstance(idx.name, str)):
        raise ValueError("cannot save this table: a saved table has distinct text column labels, no name on its "
                         f"column axis and one index named by text or not at all (columns {labels[:5]}, "
                         f"column axis name {df.columns.name!r}, index name {idx.name!r})")
    index_kind = "range" if isinstance(idx, pd.RangeIndex) and idx.start == 0 and idx.step == 1 else \
        _column_kind(idx, "index")
    kinds = [_column_kind(df[c], c) for c in labels]
    return {"index_name": idx.name, "index_kind": index_kind,
            "index": len(idx) if index_kind == "range" else _column(index_kind, idx),
            "columns": labels, "kinds": kinds,
            "data": [_column(k, df[c].to_numpy()) for c, k in zip(labels, kinds)]}


def _dec_column(kind: str, values: Any, where: str, rd: _Reader) -> Any:
    import pandas as pd

    if kind not in _FRAME_KINDS:
        raise rd.fail(where, f"unknown column kind {kind!r} (one of {sorted(_FRAME_KINDS)})")
    read = getattr(rd, _FRAME_KINDS[kind][0])
    out = [read(x, f"{where}[{i}]") for i, x in enumerate(rd.list(values, where))]
    return pd.array(out, dtype="str") if kind == "str" else np.array(out, dtype=_FRAME_KINDS[kind][1])


def _dec_frame(v: Any, where: str, rd: _Reader) -> pd.DataFrame:
    import pandas as pd

    d = rd.dict(v, where)
    need = ["index_name", "index_kind", "index", "columns", "kinds", "data"]
    missing = [k for k in need if k not in d]
    unknown = sorted(set(d) - set(need))
    if missing or unknown:
        raise rd.fail(where, f"a table needs {need}" + (f"; missing {missing}" if missing else "")
                      + (f"; unknown {unknown}" if unknown else ""))
    cols = [rd.str(c, f"{where}.columns[{i}]") for i, c in enumerate(rd.list(d["columns"], f"{where}.columns"))]
    kinds = [rd.str(k, f"{where}.kinds[{i}]") for i, k in enumerate(rd.list(d["kinds"], f"{where}.kinds"))]
    data = rd.list(d["data"], f"{where}.data")
    if not (len(cols) == len(kinds) == len(data)):
        raise rd.fail(where, f"{len(cols)} columns, {len(kinds)} kinds and {len(data)} data lists")
    if len(set(cols)) < len(cols):
        raise rd.fail(f"{where}.columns", "repeated column names")
    values = {c: _dec_column(k, x, f"{where}.data[{i}]", rd) for i, (c, k, x) in enumerate(zip(cols, kinds, data))}
    name = d["index_name"]
    if name is not None:
        name = rd.str(name, f"{where}.index_name")
    ik = rd.str(d["index_kind"], f"{where}.index_kind")
    if ik == "range":
        n = rd.int(d["index"], f"{where}.index")
        if not 0 <= n <= _MAX_ROWS:
            raise rd.fail(f"{where}.index", f"a table length must be in [0, {_MAX_ROWS}], got {n}")
        index = pd.RangeIndex(n, name=name)
    else:
        index = pd.Index(_dec_column(ik, d["index"], f"{where}.index", rd), name=name)
    lengths = {len(x) for x in values.values()} | {len(index)}
    if len(lengths) > 1:
        raise rd.fail(where, f"columns and index of different lengths {sorted(lengths)}")
    return pd.DataFrame(values, index=index, columns=cols or None)  # no columns: an empty RangeIndex, as pandas makes


# --------------------------------------------------------------------------------------------
# plain values (a bootstrap's options and reference decision): None, bool, int, float, str, arrays,
# tuples, lists, mappings with text keys and the saved types, each written so that it reads back as
# the same type (JSON's own null, true/false, integers, numbers with a point and strings for the
# first five; a one-key object tagged with the kind for the rest)
# --------------------------------------------------------------------------------------------
#: Array dtypes a plain value may have, by the name the file gives them.
_PLAIN_DTYPES = frozenset({"float64", "float32", "float16", "int64", "int32", "int16", "int8", "uint32",
                           "uint16", "uint8", "bool"})
#: Tags of the plain values JSON has no literal for.
_PLAIN_TAGS = ("float", "scalar", "array", "tuple", "list", "map", "type")


def _read_only(a: np.ndarray) -> np.ndarray:
    return locked(a)  # loaded values are as immutable as computed ones


def _enc_plain_map(v: Mapping, where: str, depth: int = 0) -> dict:
    bad = [k for k in v if not isinstance(k, str)]
    if bad:
        raise ValueError(f"cannot save {where}: its keys must be text, got {bad[0]!r} ({type(bad[0]).__name__})")
    return {k: _enc_plain(x, f"{where}[{k!r}]", depth + 1) for k, x in v.items()}


def _enc_plain(v: Any, where: str, depth: int = 0) -> Any:
    if depth > MAX_NESTING:  # deeper, or a list that holds itself, ended in a bare RecursionError
        raise ValueError(f"cannot save {where}: nested deeper than {MAX_NESTING} levels (lists or mappings inside "
                         "each other, or one that holds itself)")
    if isinstance(v, np.str_):  # text from an array of labels (np.array(["a", "b"])[0]) reads back as such
        return {"scalar": {"dtype": "str", "value": str(v)}}
    if isinstance(v, np.generic):  # a NumPy scalar (np.float64(0.1), np.int64(3)) reads back as one
        if v.dtype.name not in _PLAIN_DTYPES:
            raise ValueError(f"cannot save {where}: a NumPy scalar of dtype {v.dtype} (a saved one holds a number, a "
                             "bool or text)")
        return {"scalar": {"dtype": v.dtype.name, "value": _enc_plain(v.item(), where)}}
    if v is None or isinstance(v, (bool, str)):
        return v
    if isinstance(v, int):
        if not -2**63 <= v < 2**63:  # the loader reads 64-bit integers only: refused now, not when loading
            raise ValueError(f"cannot save {where}: the integer {v} is beyond the 64-bit range")
        return v
    if isinstance(v, float):
        x = float(v)  # written with a point (1.0, 1e-05): it reads back a float, not an int
        return x if math.isfinite(x) else {"float": _num(x)}
    if isinstance(v, np.ndarray):
        if v.dtype.name not in _PLAIN_DTYPES:
            raise ValueError(f"cannot save {where}: an array of dtype {v.dtype} (a saved array holds numbers or bools)")
        conv = bool if v.dtype.kind == "b" else int if v.dtype.kind in "iu" else _num
        return {"array": {"dtype": v.dtype.name, "shape": list(v.shape), "data": [conv(x) for x in v.ravel()]}}
    if isinstance(v, (tuple, list)):  # a FrozenList (a Dataset's extra keeps lists so) is a list
        return {"tuple" if isinstance(v, tuple) else "list": [_enc_plain(x, f"{where}[{i}]", depth + 1)
                                                              for i, x in enumerate(v)]}
    if isinstance(v, Mapping):
        return {"map": _enc_plain_map(v, where, depth)}
    if _type_name(type(v)) is not None:
        return {"type": {"type": _type_name(type(v)), "object": _encode_fields(v)}}
    why = _why_not(v)
    raise ValueError(f"cannot save {where}: " + (why or f"a {type(v).__name__}, which graybox does not save"))


def _plain(v: Any, where: str) -> bool:
    """Whether ``v`` is a plain value :func:`_enc_plain` writes."""
    try:
        _enc_plain(v, where)
        return True
    except ValueError:
        return False


def _why_not(v: Any) -> str:
    """What a value holds that JSON cannot carry, in words ("" for a value merely of a type graybox does not save)."""
    if type(v).__name__ == "DaskRecord":  # by name: core._gram loads dask only when one is made
        return ("a DaskRecord, whose u and y are lazy Dask arrays (a task graph over files or a cluster, not "
                "numbers): save a Record of its computed samples, or the results fitted on it")
    if isinstance(v, StaticConstraint):
        return (f"a {type(v).__name__}, a static constraint: an instruction to an estimator, which may hold a Python "
                "function (UserConstraint's fn, GainBounds' reference) that JSON cannot carry; a result fitted "
                "under it names it (CLSResult.constraints)")
    if callable(v) and not isinstance(v, type):
        return f"a function ({getattr(v, '__qualname__', type(v).__name__)}), which JSON cannot carry (code is not data)"
    return ""


def _dec_plain(v: Any, where: str, rd: _Reader, depth: int = 0) -> Any:
    if depth > MAX_NESTING:  # what to_json refuses to write (deeper ran out of Python's recursion)
        raise rd.fail(where, f"plain values nested deeper than {MAX_NESTING} levels")
    if v is None or isinstance(v, (bool, str, float)):
        return v
    if isinstance(v, int):
        return rd.int(v, where)
    if isinstance(v, list):
        raise rd.fail(where, "a bare list (a list or a tuple is written {\"list\": …} or {\"tuple\": …})")
    d = rd.dict(v, where)
    if len(d) != 1 or next(iter(d)) not in _PLAIN_TAGS:
        raise rd.fail(where, f"expected a value or an object of one key among {list(_PLAIN_TAGS)}, got keys {sorted(d)}")
    tag, x = next(iter(d.items()))
    at = f"{where}.{tag}"
    if tag == "float":
        f = rd.float(x, at)
        if isinstance(x, str):
            return f
        raise rd.fail(at, "a finite number is written as a JSON number")
    if tag in ("tuple", "list"):
        items = [_dec_plain(y, f"{at}[{i}]", rd, depth + 1) for i, y in enumerate(rd.list(x, at))]
        return tuple(items) if tag == "tuple" else items
    if tag == "map":
        return {k: _dec_plain(y, f"{at}.{k}", rd, depth + 1) for k, y in rd.dict(x, at).items()}
    if tag == "type":
        t = rd.dict(x, at)
        name = t.get("type")
        if set(t) != {"type", "object"} or not _saved_type(name):
            raise rd.fail(at, f"expected {{\"type\": one of {sorted(_CODECS)}, \"object\": …}}")
        return _decode_fields(name, t["object"], f"{at}.object", rd)
    if tag == "scalar":
        sc = rd.dict(x, at)
        if set(sc) != {"dtype", "value"}:
            raise rd.fail(at, f"a NumPy scalar needs ['dtype', 'value'], got {sorted(sc)}")
        dtype = rd.str(sc["dtype"], f"{at}.dtype")
        if dtype == "str":
            return np.str_(rd.str(sc["value"], f"{at}.value"))
        if dtype not in _PLAIN_DTYPES:
            raise rd.fail(f"{at}.dtype", f"unknown dtype {dtype!r} (one of {sorted(_PLAIN_DTYPES | {'str'})})")
        kind = np.dtype(dtype).kind
        read = rd.bool if kind == "b" else rd.int if kind in "iu" else rd.float
        value = sc["value"]
        if kind == "f" and isinstance(value, dict):  # a non-finite one, {"float": "nan"}
            value = rd.dict(value, f"{at}.value").get("float")
        value = read(value, f"{at}.value")
        try:
            with np.errstate(over="raise"):  # a hand-edited 1e300 of a float32 would otherwise become inf
                return np.array(value, dtype=dtype)[()]
        except (OverflowError, FloatingPointError):
            raise rd.fail(f"{at}.value", f"a value beyond the range of {dtype}") from None
    a = rd.dict(x, at)  # an array
    if set(a) != {"dtype", "shape", "data"}:
        raise rd.fail(at, f"an array needs ['dtype', 'shape', 'data'], got {sorted(a)}")
    dtype = rd.str(a["dtype"], f"{at}.dtype")
    if dtype not in _PLAIN_DTYPES:
        raise rd.fail(f"{at}.dtype", f"unknown dtype {dtype!r} (one of {sorted(_PLAIN_DTYPES)})")
    shape = tuple(rd.int(n, f"{at}.shape[{i}]") for i, n in enumerate(rd.list(a["shape"], f"{at}.shape")))
    kind = np.dtype(dtype).kind
    read = rd.bool if kind == "b" else rd.int if kind in "iu" else rd.float
    raw = rd.list(a["data"], f"{at}.data")
    data = _plain_numbers(raw, kind)
    if data is None:  # number by number, naming the one refused
        data = [read(y, f"{at}.data[{i}]") for i, y in enumerate(raw)]
    if any(n < 0 for n in shape) or math.prod(shape) != len(data):
        raise rd.fail(f"{at}.shape", f"shape {list(shape)} does not hold the {len(data)} values of data")
    try:
        with np.errstate(over="raise"):
            values = np.array(data, dtype=dtype)
    except (OverflowError, FloatingPointError):
        raise rd.fail(f"{at}.data", f"a value beyond the range of {dtype}") from None
    try:  # a shape of its values' count, but beyond NumPy's (more than 64 axes, or bytes past the address space)
        return _read_only(values.reshape(shape))
    except ValueError as exc:
        raise rd.fail(f"{at}.shape", f"no array has the shape {reprlib.repr(list(shape))} ({exc})") from None


def _plain_numbers(raw: list, kind: str) -> Any:
    """A plain array's data in one conversion when every value is of its kind (as the reader would take each one:
    float, bool, or a 64-bit integer), else None."""
    if kind == "f":
        return _numbers(raw, 1)
    kinds = set(map(type, raw))
    if kind == "b":
        return raw if kinds <= {bool} else None
    return raw if kinds <= {int} and (not raw or -2**63 <= min(raw) and max(raw) < 2**63) else None


#: Per saved type, its class and its constructor's fields as (name, kind). A class whose module imports pandas at the
#: top (OEResult, SEMPResult) is named by that module instead, imported where a file names the type (:func:`_cls`) or a
#: value of it is written (then already imported): ``gb.save(model)`` in a fresh process loads no pandas (~0.3 s).
_CODECS: dict[str, tuple[type | str, tuple[tuple[str, str], ...]]] = {
    "StaticPoints": (StaticPoints, (("ubar", "inputs"), ("ybar", "array1"), ("name", "str"), ("input_names", "names"),
                                    ("uncertainty", "array1_or_none"), ("units", "units"))),
    "StaticCurve": (StaticCurve, (("coefficients", "array1"), ("domain", "floats_or_none"), ("name", "str"))),
    "StaticSurface": (StaticSurface, (("exponents", "exponents"), ("coefficients", "array1"), ("domain", "pairs_or_none"),
                                      ("name", "str"), ("input_names", "names"))),
    "Model": (Model, (("name", "str"), ("structure", "structure"), ("theta", "array1"),
                      ("noise_structure", "structure"), ("noise_theta", "array1"), ("input_names", "names"),
                      ("Ts", "float_or_none"), ("units", "units"))),
    "NeuralModel": (NeuralModel, (("name", "str"), ("ny", "int"), ("nu", "int"), ("ne", "int"), ("W1", "array2"),
                                  ("b1", "array1"), ("w2", "array1"), ("b2", "float"), ("u_offset", "float"),
                                  ("u_scale", "float"), ("y_offset", "float"), ("y_scale", "float"),
                                  ("input_names", "names"), ("Ts", "float_or_none"), ("units", "units"))),
    "ParetoSet": (ParetoSet, (("method", "str"), ("structure", "structure"), ("lambdas", "array1"),
                              ("thetas", "array2"), ("J1", "array1"), ("JS", "array1"), ("JSF", "array1"),
                              ("extra", "dict_arrays"), ("failures", "failures"), ("input_names", "names"),
                              ("Ts", "float_or_none"), ("units", "units"), ("fitted_on", "prints"))),
    "Selection": (Selection, (("structure", "structure"), ("err", "array1"), ("theta", "array1"),
                              ("noise", "structure"), ("evaluated", "structure"), ("err_evaluated", "array1"),
                              ("rss", "array1"), ("criterion", "str"), ("criterion_curve", "array1"), ("stop", "str"),
                              ("n_rows", "int"), ("n_candidates", "int"), ("skipped", "skipped"), ("search", "str"),
                              ("subsets", "structures"), ("subset_rss", "array1"), ("input_names", "names"),
                              ("Ts", "float_or_none"), ("units", "units"))),
    "ELSResult": (ELSResult, (("model", "Model"), ("n_iter", "int"), ("converged", "bool"), ("history", "floats"),
                              ("theta_ls", "array1"), ("residuals", "arrays"), ("n_direct", "int"))),
    "NeuralFit": (NeuralFit, (("model", "NeuralModel"), ("prediction_cost", "floats"), ("simulation_cost", "floats"),
                              ("holdout_cost", "floats"), ("best_step", "int_or_none"), ("epochs", "int"),
                              ("stopped", "str"), ("rmse_train", "float"), ("rmse_sim", "float"), ("seconds", "float"))),
    "Decision": (Decision, (("rule", "str"), ("index", "int"), ("lambda1", "float"), ("JS", "float"), ("JSF", "float"),
                            ("in_band", "bool"), ("score", "float"), ("model", "Model"), ("chosen_on", "str"))),
    "SEMPResult": ("graybox.selection._simulation_error_pruning",
                   (("structure", "structure"), ("theta", "array1"), ("score", "float"), ("path", "frame"),
                    ("forward_scores", "frame"), ("criterion", "str"), ("stop", "str"), ("n_rows", "int"),
                    ("input_names", "names"), ("Ts", "float_or_none"), ("units", "units"))),
    "DSFResult": (DSFResult, (("model", "Model"), ("JS", "float"), ("JSF", "float"), ("band", "float"),
                              ("in_band", "bool"), ("start", "str"), ("start_JS", "float"), ("start_JSF", "float"),
                              ("n_iter", "int"), ("message", "str"), ("margin", "float"))),
    "OEResult": ("graybox.estimation._output_error",
                 (("model", "Model"), ("JS", "float"), ("JS_choose", "float"), ("chosen_on", "str"),
                  ("start", "str"), ("starts", "frame"), ("margin", "float"), ("radius", "float"), ("seed", "seed"))),
    "ParameterUncertainty": (ParameterUncertainty, (("method", "str"), ("model", "Model"), ("cov", "array2"),
                                                    ("level", "float"), ("dof", "int"), ("sigma2", "float"),
                                                    ("constraints", "array2"), ("noise_cov", "array2"),
                                                    ("static_sigma2", "float"), ("cov_factor", "array2_or_none"))),
    "StaticCurveBand": (StaticCurveBand, (("model_name", "str"), ("method", "str"), ("level", "float"),
                                          ("n_samples", "int"), ("ubar", "array1"), ("ybar", "array1"),
                                          ("ybar_low", "array1"), ("ybar_high", "array1"), ("ybar_std", "array1"),
                                          ("gain", "array1"), ("gain_low", "array1"), ("gain_high", "array1"),
                                          ("gain_std", "array1"), ("undefined", "array1"), ("units", "units"))),
    "SimulationBand": (SimulationBand, (("model_name", "str"), ("record_name", "str"), ("method", "str"),
                                        ("level", "float"), ("n_samples", "int"), ("diverged", "float"),
                                        ("units", "units"), ("t", "array1"), ("y", "array1"), ("yhat", "array1"),
                                        ("low", "array1"), ("high", "array1"), ("std", "array1"),
                                        ("input_names", "names_or_none"))),
    "CLSResult": (CLSResult, (("model", "Model"), ("static", "static_or_none"), ("constraints", "names"), ("solver", "str"))),
    "LocalModel": (LocalModel, (("ubar", "array1"), ("ybar", "float_or_none"), ("status", "str"), ("reason", "str"),
                                ("a", "array1"), ("b", "array2"), ("Ts", "float"), ("input_names", "names"), ("name", "str"),
                                ("units", "units"))),
    "OperatingCurve": (OperatingCurve, (("local_models", "local_models"), ("ubar", "inputs"), ("ybar", "array1"),
                                        ("gain", "inputs"), ("time_constant", "array1"), ("damping", "array1"),
                                        ("spectral_radius", "array1"), ("settling_time", "array1"), ("status", "names"),
                                        ("level", "float"), ("gain_low", "inputs_or_none"), ("gain_high", "inputs_or_none"),
                                        ("time_constant_low", "array1_or_none"),
                                        ("time_constant_high", "array1_or_none"), ("undefined", "array1_or_none"),
                                        ("model_name", "str"))),
    "StaticSurfaceBand": (StaticSurfaceBand, (("ubar", "array2"), ("input_names", "names"), ("ybar", "array1"),
                                              ("ybar_low", "array1"), ("ybar_high", "array1"), ("ybar_std", "array1"),
                                              ("gain", "array2"), ("gain_low", "array2"), ("gain_high", "array2"),
                                              ("gain_std", "array2"), ("level", "float"), ("method", "str"),
                                              ("n_samples", "int"), ("undefined", "array1"), ("model_name", "str"),
                                              ("units", "units"))),
    "CorrelationTest": (CorrelationTest, (("name", "str"), ("label", "str"), ("kind", "str"), ("lags", "int_array1"),
                                          ("phi", "array1"), ("band", "float"), ("limit", "float"),
                                          ("outside", "int_array1"), ("passed", "bool"),
                                          ("excess_kurtosis", "float"), ("skewness", "float"),
                                          ("permutations", "int"))),
    "ResidualTests": (ResidualTests, (("tests", "correlation_tests"), ("n", "int"), ("level", "float"), ("rule", "str"),
                                      ("model_name", "str"), ("residuals", "arrays"), ("undefined", "texts"),
                                      ("seed", "seed_or_none"))),
    "GAOptions": (GAOptions, (("population", "int"), ("generations", "int"), ("stall", "int_or_none"),
                              ("crossover_prob", "float"), ("crossover_ratio", "float"), ("mutation_prob", "float"),
                              ("mutation_scale", "float"), ("elite", "int"), ("random_samples", "int"),
                              ("selective_pressure", "float"))),
    "DecisionBootstrap": (DecisionBootstrap, (("structure", "structure"), ("estimator", "str"), ("lambdas", "array1"),
                                              ("band", "band"), ("block_length", "int"), ("n_blocks", "int"),
                                              ("seed", "seed"), ("lambda1", "array1"), ("JS", "array1"),
                                              ("JSF", "array1"), ("in_band", "bool_array1"), ("thetas", "array2"),
                                              ("rules", "names"), ("reference", "plain_map"), ("failures", "failures"),
                                              ("options", "plain_map"), ("static_sigma", "float_or_none"))),
    "Equilibrium": (Equilibrium, (("ubar", "float_or_floats"), ("ybar", "float"), ("stable", "bool"),
                                  ("spectral_radius", "float"))),
    "Structure": (Structure, (("terms", "structure"),)),
    "Record": (Record, (("u", "inputs"), ("y", "array1"), ("Ts", "float"), ("name", "str"), ("units", "units"),
                        ("input_names", "names_or_none"))),
    "Dataset": (Dataset, (("ident", "Record"), ("valid", "Record"), ("static", "StaticPoints_or_none"),
                          ("description", "str"), ("extra", "plain_map"))),
}


def register_type(name: str, cls: type, spec: tuple[tuple[str, str], ...]) -> None:
    """Add a saved type defined above this module (the experiment layer's results).

    ``spec`` lists every constructor field as (name, kind), with the kinds of ``_CODECS``.
    """
    spec = tuple((str(k), str(kind)) for k, kind in spec)
    unknown = sorted({kind for _, kind in spec} - _KINDS - set(_CODECS))
    if unknown:
        raise ValueError(f"unknown field kind(s) {unknown} for {name!r}; kinds: {sorted(_KINDS | set(_CODECS))}")
    old = (_cls(name), _CODECS[name][1]) if name in _CODECS else None
    same_class = old is not None and (old[0].__module__, old[0].__qualname__) == (cls.__module__, cls.__qualname__)
    if old is not None and not (same_class and old[1] == spec):  # a module reloaded may register its class again
        raise ValueError(f"a saved type named {name!r} exists already")
    if _type_name(cls) not in (None, name):
        raise ValueError(f"{cls.__qualname__} is saved as {_type_name(cls)!r} already")
    if old is not None:
        _TYPES.pop(old[0], None)
    _CODECS[name] = (cls, spec)
    _TYPES[cls] = name


#: Saved types defined above this layer, by the module whose import registers them (:func:`register_type`).
_REGISTERED_ABOVE = {"GrayboxSelection": "graybox.experiments._select", "DecimationAdvice": "graybox.datasets._decimation"}

def _saved_type(name: Any) -> bool:
    """Whether ``name`` (a file's type: the header's, or a saved value's inside a Dataset's extra or a bootstrap's
    options) is a saved type. A type of a layer above this one registers itself when its module is imported: it is
    imported by name (as graybox's lazy attributes do), so that a fresh session loads the file."""
    if isinstance(name, str) and name not in _CODECS and name in _REGISTERED_ABOVE:
        importlib.import_module(_REGISTERED_ABOVE[name])
    return isinstance(name, str) and name in _CODECS


#: A kind ending so is that kind or None (JSON null).
_OR_NONE = "_or_none"

#: The saved types a static field (e.g. CLSResult.static) may hold, written with their type's name.
_STATIC = ("StaticPoints", "StaticCurve", "StaticSurface")

#: Field kinds other than the saved types themselves.
_KINDS = frozenset({"float", "array1", "array2", "inputs", "int", "seed", "str", "bool", "floats", "pairs", "exponents",
                    "structure", "structures", "names", "arrays", "dict_arrays", "failures", "skipped", "frame",
                    "static", "local_models", "ints", "int_array1", "bool_array1", "texts", "band",
                    "correlation_tests", "plain_map", "float_or_floats", "prints", "units"})
_KINDS = _KINDS | {k + _OR_NONE for k in _KINDS}

#: The significant digits of a Model's equation in a file.
_EQUATION_DIGITS = 6

#: Fields written for the reader (not read as the value: a Model's equation is checked against it), per type: their
#: names and how to write them.
_READABLE: dict[str, tuple[tuple[str, ...], Callable[[Any], Mapping[str, Any]]]] = {
    "Model": (("equation", "clusters"),
              lambda m: {"equation": m.equation(digits=_EQUATION_DIGITS),
                         "clusters": {k: _num(v) for k, v in m.clusters().items()}}),
}

#: Saved type's name by class, for the classes imported so far (:func:`_type_name` adds the others when met).
_TYPES = {cls: name for name, (cls, _) in _CODECS.items() if isinstance(cls, type)}


def _cls(name: str) -> type:
    """The class of the saved type ``name``, its module imported now where the table names it by its module."""
    cls, spec = _CODECS[name]
    if isinstance(cls, str):
        cls = getattr(importlib.import_module(cls), name)
        _CODECS[name] = (cls, spec)
        _TYPES[cls] = name
    return cls


def _type_name(cls: type) -> str | None:
    """The saved type's name of the class ``cls`` (None: not a saved type). A value's class is imported already: one
    the table names by its module is looked up by its module and name, importing nothing."""
    name = _TYPES.get(cls)
    if name is None and _CODECS.get(cls.__name__, (None,))[0] == cls.__module__ and _cls(cls.__name__) is cls:
        name = cls.__name__
    return name

#: A field a file may lack reads as the constructor's default (see :data:`_ADDED`).
_DEFAULT = object()

#: Fields added after files of this format version were written, with the value a file without them
#: means (:data:`_DEFAULT`: the constructor's own).
_ADDED: dict[str, dict[str, Any]] = {"ELSResult": {"n_direct": 0}, "Decision": {"chosen_on": ""},
                                     # the sampling period, carried since 0.2.2: unknown (None) in older files
                                     "DSFResult": {"margin": float("nan")},  # not recorded: none said
                                     # selections saved before the fit / choose / test protocol chose by the
                                     # smallest validation J_S
                                     "GrayboxSelection": {"rule": "min"},
                                     # and the units of the records fitted on, carried since 2026-11-27: none said ("", "")
                                     "Model": {"input_names": _DEFAULT, "Ts": None, "units": _DEFAULT},
                                     "NeuralModel": {"input_names": _DEFAULT, "Ts": None, "units": _DEFAULT},
                                     # and the prints of its fitting records: none known
                                     "ParetoSet": {"input_names": _DEFAULT, "Ts": None, "units": _DEFAULT,
                                                   "fitted_on": _DEFAULT},
                                     "Selection": {k: _DEFAULT for k in ("search", "subsets", "subset_rss",
                                                                         "input_names", "units")} | {"Ts": None},
                                     "SEMPResult": {"input_names": _DEFAULT, "Ts": None, "units": _DEFAULT},
                                     "LocalModel": {"units": _DEFAULT},
                                     # the covariance's factor, carried since mend36a: contractions use cov
                                     "ParameterUncertainty": {"cov_factor": None},
                                     # units for display, carried since loaders36: none said
                                     "StaticPoints": {"units": _DEFAULT},
                                     "StaticCurveBand": {"units": _DEFAULT}, "StaticSurfaceBand": {"units": _DEFAULT},
                                     # the record's inputs its per-input units are of, kept since mend62b: unknown
                                     "SimulationBand": {"input_names": None},
                                     # the sequences' tails, carried since hunt59d: normal ones (the Bonferroni
                                     # limit those files hold); the permutations the limit was set on, since
                                     # stats61f: none (the Bonferroni limit, or its Edgeworth tails)
                                     "CorrelationTest": {"excess_kurtosis": 0.0, "skewness": 0.0, "permutations": 0},
                                     # the seed of those permutations, kept since mend61k: unknown
                                     "ResidualTests": {"seed": None}}

#: Fields that files written by an older graybox carry and this one no longer has: read and dropped.
#: A GrayboxSelection named the SQLite store its cells ran in; it no longer runs through a store.
_DROPPED: dict[str, frozenset[str]] = {"GrayboxSelection": frozenset({"store"})}

#: Fields renamed after files were written (one name per concept): old name -> (new name, how the old value
#: reads as the new one). "Met the band" was DSFResult.feasible and, inverted, GrayboxSelection.fallback.
_RENAMED: dict[str, dict[str, tuple[str, Callable[[Any], Any]]]] = {
    "DSFResult": {"feasible": ("in_band", lambda v: v)},
    "GrayboxSelection": {"fallback": ("in_band", lambda v: (not v) if isinstance(v, bool) else v)},
}


def _enc_print(p: RecordPrint) -> dict:
    return {"name": p.name, "length": p.length, "input_names": list(p.input_names), "block": p.block,
            "digests": base64.b64encode(p.digests.astype("<u8").tobytes()).decode("ascii")}


def _dec_print(v: Any, where: str, rd: _Reader) -> RecordPrint:
    d = rd.dict(v, where)
    keys = {"name", "length", "input_names", "block", "digests"}
    if set(d) != keys:
        raise rd.fail(where, f"a fitting record's print has the fields {sorted(keys)}, got {sorted(d)}")
    try:
        raw = base64.b64decode(rd.str(d["digests"], f"{where}.digests"), validate=True)
    except binascii.Error:
        raise rd.fail(f"{where}.digests", "not base64 text") from None
    if len(raw) % 8:
        raise rd.fail(f"{where}.digests", f"{len(raw)} bytes, not whole 8-byte digests")
    fields = (rd.str(d["name"], f"{where}.name"), rd.int(d["length"], f"{where}.length"),
              tuple(rd.str(n, f"{where}.input_names") for n in rd.list(d["input_names"], f"{where}.input_names")),
              rd.int(d["block"], f"{where}.block"), np.frombuffer(raw, "<u8").astype(np.uint64))
    try:  # the fields' own types read above, each naming its place; here what they mean together
        return RecordPrint(*fields)
    except (ValueError, TypeError) as exc:
        raise rd.fail(where, str(exc)) from None


def _saved_name(obj: Any, where: str) -> str:
    """The saved type's name of ``obj``, held in the field ``where``; ``ValueError`` for a value of another type (a
    subclass of a saved type: a file holds graybox's own types, and would read it back without the subclass)."""
    name = _type_name(type(obj))
    if name is None:
        base = next((c.__name__ for c in type(obj).__mro__[1:] if _type_name(c) is not None), None)
        raise ValueError(f"cannot save {where or 'the value'}: a {type(obj).__name__}"
                         + (f", a subclass of {base}; a file holds graybox's own types, and would load it as a "
                            f"{base}: give a {base}" if base else ", which graybox does not save"))
    return name


def _encode_fields(obj: Any, where: str = "") -> dict:
    name = _saved_name(obj, where)
    out = {k: _enc(kind, getattr(obj, k), f"{name}.{k}") for k, kind in _CODECS[name][1]}
    if name in _READABLE:
        out.update(_READABLE[name][1](obj))
    return out


def _decode_fields(name: str, v: Any, where: str, rd: _Reader) -> Any:
    cls, spec = _cls(name), _CODECS[name][1]
    d = rd.dict(v, where)
    for old, (new, read) in _RENAMED.get(name, {}).items():
        if old in d and new not in d:
            d = {**{k: x for k, x in d.items() if k != old}, new: read(d[old])}
    d = {k: x for k, x in d.items() if k not in _DROPPED.get(name, frozenset())}
    known = {k for k, _ in spec} | set(_READABLE[name][0] if name in _READABLE else ())
    unknown = sorted(set(d) - known)
    if unknown:
        raise rd.fail(where, f"unknown field(s) {unknown} for a {name}")
    added = _ADDED.get(name, {})
    missing = [k for k, _ in spec if k not in d and k not in added]
    if missing:
        raise rd.fail(where, f"missing field(s) {missing} for a {name}")
    kwargs = {k: _dec(kind, d[k], f"{where}.{k}", rd) if k in d else added[k] for k, kind in spec
              if k in d or added[k] is not _DEFAULT}
    try:
        obj = cls(**kwargs)
    except (ValueError, TypeError) as exc:
        raise rd.fail(where, f"not a valid {name}: {exc}") from None
    if name == "Model" and "equation" in d:
        _check_equation(rd.str(d["equation"], f"{where}.equation"), obj, f"{where}.equation", rd)
    return obj


def _equation_pieces(text: str) -> list[tuple[int, str, str]] | None:
    """The signed pieces of an equation as :meth:`Model.equation` writes it (``y(k) = -0.5 y(k-1) + 1 u(k-1) + e(k)``):
    (sign, coefficient's text, term's text: ``1`` for the constant, ``e(k)`` for the noise), None where it is not so
    written."""
    words = text.split()
    if words[:2] != ["y(k)", "="] or len(words) < 3:
        return None
    words, pieces = words[2:], []
    if words == ["0"]:
        return []
    if words[0].startswith("-") and len(words[0]) > 1:
        words = ["-", words[0][1:], *words[1:]]
    elif words[0] not in "+-":
        words = ["+", *words]
    i, n = 0, len(words)
    while i < n:
        if i + 1 >= n or words[i] not in ("+", "-"):
            return None
        sign, coef, i = (1 if words[i] == "+" else -1), words[i + 1], i + 2
        if coef == "e(k)":
            pieces.append((sign, "1", "e(k)"))
            continue
        term = "1"
        if i < n and words[i] not in ("+", "-"):
            term, i = words[i], i + 1
        pieces.append((sign, coef, term))
    return pieces


def _check_equation(text: str, m: Model, where: str, rd: _Reader) -> None:
    """Refuse a Model's ``equation`` text that does not say its terms and θ: each coefficient θ to the 6 significant
    digits it is written with (or more, where the text shows more; 0 only for 0), each term the structure's, in
    order."""
    import decimal

    want = [(th, str(t)) for th, t in zip(m.theta, m.structure)]
    want += [(th, str(t)) for th, t in zip(m.noise_theta, m.noise_structure)]
    want += [(1.0, "e(k)")] if len(m.noise_structure) else []
    got = _equation_pieces(text)
    first = None if got is not None and len(got) == len(want) else min(len(want), len(got or ()))
    with decimal.localcontext() as exact:
        exact.prec = 1200  # a float's decimal expansion in full (a subnormal's has ~750 digits): no rounding
        for i, ((sign, coef, term), (th, t)) in enumerate(zip(got or (), want)):
            if term == t and coef == f"{abs(th):.{_EQUATION_DIGITS}g}" and (sign < 0) == (th < 0):
                continue  # as graybox writes it
            try:
                c = decimal.Decimal(coef)
                # 6 significant digits as written (a coefficient 1 is 1.00000), more where the text shows more
                shown = max(_EQUATION_DIGITS, len(c.as_tuple().digits))
                ok = c.is_finite() and c >= 0 and term == t and (
                    abs(sign * c - decimal.Decimal(float(th))) <= (decimal.Decimal(5).scaleb(c.adjusted() - shown)
                                                                   if c else 0))
            except decimal.InvalidOperation:  # not a number
                ok = False
            if not ok:
                first = i
                break
    if first is None:
        return

    def short(x: str) -> str:
        return repr(x if len(x) <= 200 else x[:150] + " … " + x[-40:])

    at = ""
    if first < len(want) and got is not None and first < len(got):
        sign, coef, term = got[first]
        at = (f"; first at term {first + 1}, where it says {'-' if sign < 0 else ''}{coef} {term} and the model "
              f"{float(want[first][0])!r} {want[first][1]}")
    raise rd.fail(where, f"the equation {short(text)} disagrees with the structure and theta, which say "
                  f"{short(m.equation(digits=_EQUATION_DIGITS))}{at}. The structure and theta are the model; the "
                  "equation is written from them for the reader: correct it to agree, or remove it")


# --------------------------------------------------------------------------------------------
# the document
# --------------------------------------------------------------------------------------------
#: A lone UTF-16 surrogate: what os.listdir and os.fsdecode make of a file name's bytes that are no UTF-8
#: ('run\xe9.csv' is 'run\udce9.csv'), and what no UTF-8 file can hold.
_SURROGATE = re.compile("[\ud800-\udfff]")


def _text(v: Any) -> str:
    """``v`` as JSON, readable (non-ASCII text as it is) but a lone surrogate as its escape ``\\udce9``, which
    JSON reads back as the same character: the text is UTF-8 whatever a name held."""
    return _SURROGATE.sub(lambda m: f"\\u{ord(m.group()):04x}", json.dumps(v, ensure_ascii=False, allow_nan=False))


def _dump(v: Any, level: int = 0) -> str:
    """JSON with objects indented and vectors on one line (matrices: a row per line)."""
    pad, inner = "  " * level, "  " * (level + 1)
    if isinstance(v, dict):
        if not v:
            return "{}"
        items = [f"{inner}{_text(k)}: {_dump(x, level + 1)}" for k, x in v.items()]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    if isinstance(v, list):
        if not any(issubclass(k, (dict, list)) for k in set(map(type, v))):  # by kind: one pass in C, not per value
            return _text(v)
        return "[\n" + ",\n".join(inner + _dump(x, level + 1) for x in v) + "\n" + pad + "]"
    return _text(v)


def _read_units(rd: Any, v: Any, where: str) -> tuple:
    """A file's (input unit, output unit): the input's one str or a list of str, one per input (checked by the
    value's constructor against its inputs)."""
    pair = rd.list(v, where)
    if len(pair) != 2:
        raise rd.fail(where, "units must be a pair of strings (input unit, output unit), the input's one string or "
                             f"one string per input, got {v!r}")
    ins = pair[0]
    ins = (rd.str(ins, f"{where}[0]") if not isinstance(ins, list) else
           tuple(rd.str(x, f"{where}[0][{i}]") for i, x in enumerate(ins)))
    return (ins, rd.str(pair[1], f"{where}[1]"))


def _units_arg(units: tuple | Mapping[str, Any] | None, m: int | None = None) -> dict | None:
    """``units=`` of :func:`to_json` as the header's ``{"u", "y"}``, checked (one input unit per input where they are
    listed and the value's ``m`` inputs are known)."""
    if units is None:
        return None
    if isinstance(units, Mapping):
        other = sorted(map(repr, set(units) - {"u", "y"}))
        if other:  # dropped, they would leave the header without the units meant
            raise ValueError(f"units: unknown key(s) {', '.join(other)}; a mapping of units has the keys 'u' and 'y'")
        units = (units.get("u", ""), units.get("y", ""))
    u, y = check_units(units, "the file's header", m)  # a str is one unit, not a pair: never split into its letters
    return {"u": u if isinstance(u, str) else list(u), "y": y}


def _n_inputs(obj: Any, own: tuple | None) -> int | None:
    """How many inputs a value to save has (its or its model's ``input_names``, else as many as its own units list),
    or None where it does not say."""
    for v in (obj, getattr(obj, "model", None)):
        names = getattr(v, "input_names", None)
        if isinstance(names, tuple):
            return len(names)
    return None if own is None or isinstance(own[0], str) else len(own[0])


def _filled(said: tuple, own: tuple) -> tuple:
    """Units ``said`` where they name one, the value's ``own`` elsewhere, input by input (they do not contradict:
    :func:`_contradicts`)."""
    n = max(_n_units(said), _n_units(own))
    each = [input_unit(said, j) or input_unit(own, j) for j in range(n)]
    return check_units((each, said[1] or own[1]), "units")


def _contradicts(said: Sequence, own: Sequence) -> bool:
    """Whether units ``said`` (input, output) name another unit than a value's ``own`` where both name one (an
    empty unit says nothing; inputs in units of their own, input by input; lists of as many inputs as they are)."""
    if 1 < _n_units(said) != _n_units(own) > 1:
        return True
    return any(input_unit(said, j) and input_unit(own, j) and input_unit(said, j) != input_unit(own, j)
               for j in range(max(_n_units(said), _n_units(own)))) or bool(said[1] and own[1] and said[1] != own[1])


def _n_units(units: Sequence) -> int:
    """How many input units ``units`` lists (1: one for every input)."""
    return 1 if isinstance(units[0], str) else len(units[0])


def _own_units(obj: Any) -> tuple[str, str] | None:
    """The units a value carries itself: its own ``units``, its ``.model``'s, or a Dataset's (those any of its
    records and static points name)."""
    if isinstance(obj, Dataset):
        return obj.units
    if isinstance(obj, OperatingCurve):
        return obj.units
    for v in (obj, getattr(obj, "model", None)):
        units = getattr(v, "units", None)
        if isinstance(units, tuple) and len(units) == 2 and isinstance(units[1], str) and (
                isinstance(units[0], str) or isinstance(units[0], tuple)):
            return units
    return None


def to_json(obj: Any, *, units: tuple | Mapping[str, Any] | None = None) -> str:
    """The JSON text of a graybox value (see the module docstring for the layout).

    Parameters
    ----------
    obj : Model, NeuralModel, ParetoSet, Selection, ELSResult, NeuralFit, Decision, DSFResult, OEResult, SEMPResult, ParameterUncertainty, StaticCurveBand, StaticSurfaceBand, SimulationBand, CLSResult, GAOptions, ResidualTests, CorrelationTest, DecisionBootstrap, StaticPoints, StaticCurve, StaticSurface, Equilibrium, LocalModel, OperatingCurve, Record, Dataset, Structure, DecimationAdvice or GrayboxSelection
        The value to write.
    units : tuple or mapping, optional
        Units of the input and output: a pair (e.g. ``("rpm", "mlc")``, or a Record's ``units``; the input's one
        str, or one per input: ``(("l/min", "°C"), "m")``) or a
        mapping with the keys ``"u"`` and ``"y"`` (a missing one: no unit said), written
        in the header; default: the units the value carries (a Record's, StaticPoints', a model's or a
        result's, a Dataset's records'), when it names any. Given for a value that carries units of
        its own, they must agree with those (they may name fewer: the value's fill the rest).

    Returns
    -------
    str

    Raises
    ------
    ValueError
        A value of a type graybox does not save, or holding what JSON cannot carry (a function, a plant
        simulator, …: the field is named), or a table the format cannot carry; ``units`` that contradict
        the value's own.
    """
    if _type_name(type(obj)) is None:
        hint = "; save its .model" if _type_name(type(getattr(obj, "model", None))) is not None else ""
        why = _why_not(obj)
        what = why if why else f"a {type(obj).__name__}"
        raise ValueError(f"cannot save {what}; graybox saves {sorted(_CODECS)}{hint}")
    doc: dict[str, Any] = {"format": "graybox", "format_version": FORMAT_VERSION, "graybox_version": graybox_version(),
                           "type": _type_name(type(obj))}
    own = _own_units(obj)
    given = units
    u = _units_arg(units, _n_inputs(obj, own))
    if own is not None and any(own):  # the header says what the value itself carries, never another unit
        said = ("", "") if u is None else (u["u"] if isinstance(u["u"], str) else tuple(u["u"]), u["y"])
        if _contradicts(said, own):
            raise ValueError(f"units={given!r} contradicts the units the {type(obj).__name__} carries {own!r} (those "
                             "its numbers hold in); omit units= (the header then says the value's own), or convert "
                             "the data and refit in the units meant")
        u = _units_arg(_filled(said, own))
    if u is not None:
        doc["units"] = u
    doc["object"] = _encode_fields(obj)
    return _dump(doc) + "\n"


def _header(doc: Any, rd: _Reader) -> dict:
    if not isinstance(doc, dict) or doc.get("format") != "graybox":
        raise rd.fail("header", "not a graybox file (no \"format\": \"graybox\")")
    ver = doc.get("format_version")
    if isinstance(ver, bool) or not isinstance(ver, int) or ver < 1:
        raise rd.fail("header", f"unknown format_version {ver!r}")
    if ver > FORMAT_VERSION:
        raise rd.fail("header", f"written by a newer graybox ({doc.get('graybox_version', '?')}, format version {ver}); "
                      f"this graybox ({graybox_version()}) reads format version {FORMAT_VERSION}: upgrade graybox to load it")
    typ = doc.get("type")
    if not _saved_type(typ):  # a list or an object cannot even be looked up
        raise rd.fail("header", f"unknown type {typ!r}; graybox loads {sorted(_CODECS)}"
                      + _newer(str(doc.get("graybox_version", ""))))
    units = doc.get("units")
    if units is not None:
        d = rd.dict(units, "units")
        per_input = isinstance(d.get("u"), list) and all(isinstance(x, str) for x in d["u"]) and d["u"]
        if set(d) - {"u", "y"} or not isinstance(d.get("y", ""), str) or not (isinstance(d.get("u", ""), str)
                                                                              or per_input):
            raise rd.fail("units", f"expected {{\"u\": str or [str, …], \"y\": str}}, got {units!r}")
    allowed = {"format", "format_version", "graybox_version", "type", "units", "object"}
    extra = sorted(set(doc) - allowed)
    if extra:
        raise rd.fail("header", f"unknown field(s) {extra}" + _newer(str(doc.get("graybox_version", ""))))
    return {"format": "graybox", "format_version": ver, "graybox_version": str(doc.get("graybox_version", "")),
            "type": typ, "units": None if units is None else check_units((units.get("u", ""), units.get("y", "")),
                                                                          "the file's header")}


class _Refused(ValueError):
    """What JSON reads but a graybox file may not hold: an object naming one key twice."""


def _once(pairs: list[tuple[str, Any]]) -> dict:
    """A JSON object whose keys are all different: JSON would keep the last of a key given twice (a line of a
    hand-edited file copied to be changed, the old one left), and the file load as whichever came last."""
    out = dict(pairs)
    if len(out) < len(pairs):
        seen: set[str] = set()
        twice = next(k for k, _ in pairs if k in seen or seen.add(k))
        raise _Refused(f"the field {twice!r} is given twice in one object; keep one of them")
    return out


class _Unheld:
    """A JSON number the float cannot hold, in place of its value until the reader names where it is."""

    def __init__(self, text: str):
        self.text = text


def _held(text: str) -> str | None:
    """Why the JSON number ``text`` (with a point or an exponent) has no float, or None when it has one: beyond the
    float range (float() reads 1e400 as inf) or, not zero, below the smallest subnormal (1e-400 read as 0.0), so that a
    hand-written number would load as another one."""
    x = float(text)
    shown = text if len(text) <= 30 else f"{text[:12]}…{text[-12:]}"  # its head and its exponent
    if math.isinf(x):
        return (f"the number {shown} is beyond the float range (an infinite value is written \"inf\" or "
                "\"-inf\")")
    if x == 0.0 and re.search("[1-9]", re.split("[eE]", text)[0]):
        return (f"the number {shown} is not zero but below the smallest float (5e-324), and would read as 0.0 "
                "(write 0 where zero is meant)")
    return None


def _finite_float(text: str) -> float | _Unheld:
    """A JSON number with a point or an exponent, or an :class:`_Unheld` where the float cannot hold it."""
    return _Unheld(text) if _held(text) else float(text)


def _unheld(doc: Any) -> tuple[str, str] | None:
    """Where decoded JSON holds an :class:`_Unheld` number first (``object.theta[2]``), and its text; a stack, not
    recursion, for a document nested as deep as json reads."""
    stack = [("", doc)]
    while stack:
        where, v = stack.pop()
        if isinstance(v, _Unheld):
            return where, v.text
        if type(v) is dict:
            stack.extend((f"{where}.{k}" if where else k, x) for k, x in reversed(v.items()))
        elif type(v) is list:
            stack.extend((f"{where}[{i}]", x) for i, x in reversed(list(enumerate(v))))
    return None


#: Where a JSON number may underflow to 0.0 (below 2.5e-324): an exponent of -320 or below; 4 zeros after the point
#: and one of -300 to -319; 20 zeros after the point (the number around it then checked by :func:`_held`; graybox
#: writes a subnormal as 5e-324, 1e-310 …, never a number that underflows, and 1e-300 matches none). Each pattern
#: starts with a literal, which re finds fast, and those of zeros are searched only where str's faster search finds
#: their zeros: a long record's text is searched in a few % of its parse.
_TINY = ((re.compile(r"e-0*(?:3[2-9]\d|[4-9]\d\d|[1-9]\d{3,})"), "e-"),
         (re.compile(r"E-0*(?:3[2-9]\d|[4-9]\d\d|[1-9]\d{3,})"), "E-"),
         (re.compile(r"0\.0000\d*[eE]-0*3[01]\d"), "0.0000"), (re.compile(r"\.0{20}"), "." + "0" * 20))

#: The characters of a JSON number.
_NUMBER = frozenset("0123456789.eE+-")


def _underflows(text: str) -> bool:
    """Whether the JSON text holds a number that is not zero but reads as 0.0 (a string's text that looks like one
    too: the document is then read number by number, which tells them apart)."""
    maybe = [p for p, zeros in _TINY if zeros in text]
    for m in itertools.chain.from_iterable(p.finditer(text) for p in maybe):
        start, end = m.start(), m.end()
        while start and text[start - 1] in _NUMBER:
            start -= 1
        while end < len(text) and text[end] in _NUMBER:
            end += 1
        try:
            if _held(text[start:end]):
                return True
        except ValueError:  # not a number: inside a string
            continue
    return False


def _any_infinite(floats: list[float]) -> bool:
    return any(map(math.isinf, floats))


def _any_zero_or_infinite(floats: list[float]) -> bool:
    return not all(floats) or _any_infinite(floats)  # a float's truth, in C: 8 times faster than 0.0 in floats


def _holds_infinity(v: Any, found: Callable[[list[float]], bool] = _any_infinite) -> bool:
    """Whether decoded JSON holds an infinite float anywhere (a list of numbers checked in one pass), or with
    another ``found`` what it finds in a list of floats (:func:`_any_zero_or_infinite`)."""
    if type(v) is dict:
        return any(_holds_infinity(x, found) for x in v.values())
    if type(v) is not list:
        return type(v) is float and found([v])
    while v and set(map(type, v)) == {list}:  # the rows of a matrix: one list of their numbers
        v = list(itertools.chain.from_iterable(v))
    kinds = set(map(type, v))
    if float in kinds and found(v if kinds == {float} else [x for x in v if type(x) is float]):
        return True
    return bool(kinds & {list, dict}) and any(_holds_infinity(x, found) for x in v if type(x) in (list, dict))


def _parse(text: str, source: str) -> tuple[dict, Any]:
    rd = _Reader(source)
    # JSON's floats read by json's own parser (a Python call for each, to refuse 1e400, took most of the time of a
    # long record): a number beyond the float range then reads as an infinity, as only a NaN/Infinity literal would
    # too, and one below the subnormals as 0.0 (its text then looked for). A document holding either, or refused, is
    # read again number by number, refused or read as it always was
    constants: list[str] = []
    try:
        doc = json.loads(text, object_pairs_hook=_once, parse_constant=lambda c: constants.append(c) or float(c))
        # one walk for both: an infinity (a number beyond the float range?) or a 0.0 (one that underflows?)
        fast = not constants and not (_holds_infinity(doc, _any_zero_or_infinite)
                                      and (_holds_infinity(doc) or _underflows(text)))
    except (ValueError, RecursionError):
        fast = False
    try:
        if not fast:
            doc = json.loads(text, object_pairs_hook=_once, parse_float=_finite_float)
    except _Refused as exc:
        raise rd.fail("JSON", str(exc)) from None
    except json.JSONDecodeError as exc:
        body = text.lstrip()
        if not body:
            raise rd.fail("JSON", "the file is empty (graybox.load reads the JSON files graybox.save writes)") from None
        if not body.startswith("{"):  # no JSON object, as every graybox file is: a CSV of samples (its first number
            # or quoted name read by json as a value, then "Extra data"), a notebook's text … given to load
            raise rd.fail("JSON", f"not a graybox file: no JSON text (it starts {body[:30]!r}); graybox.load reads the "
                          "JSON files graybox.save writes; a CSV file of samples is read by graybox.load_record_csv "
                          "or graybox.load_static_csv") from None
        raise rd.fail("JSON", f"corrupt file ({exc.msg} at line {exc.lineno}, column {exc.colno})") from None
    except (ValueError, RecursionError) as exc:  # e.g. an integer of more digits than Python converts
        raise rd.fail("JSON", f"corrupt file ({exc})") from None
    unheld = None if fast else _unheld(doc)
    if unheld:
        raise rd.fail(unheld[0], str(_held(unheld[1])))
    return _header(doc, rd), doc


def _expected(expect: object) -> tuple[type, ...] | None:
    """``expect`` as a tuple of saved types (None: any), checked before any file is read: ``TypeError`` for what is
    not a class or a tuple of classes (a type's name, a list), ``ValueError`` for a class graybox does not save."""
    if expect is None:
        return None
    want = expect if isinstance(expect, tuple) else (expect,)
    if not want:  # no type at all: every file would be refused as holding the wrong one
        raise ValueError("expect=() names no type: give a graybox type (e.g. graybox.Model), a tuple of them, or "
                         "None for any")
    for w in want:
        if not isinstance(w, type):
            raise TypeError(f"expect must be a graybox type (e.g. graybox.Model) or a tuple of them, got {w!r} "
                            f"({type(w).__name__})")
        if _type_name(w) is None:
            raise ValueError(f"expect must be one of graybox's saved types {sorted(_CODECS)}, got {w!r}")
    return want


def _expect(want: tuple[type, ...] | None, typ: str, source: str, obj: object = None) -> None:
    wanted = set() if want is None else {_type_name(w) for w in want}  # by name: a file's type imports nothing
    if want is not None and typ not in wanted:
        # a value that carries one asked for (an ELSResult's model, a Dataset's records): how to have it; a field
        # that may be None is named only where the file's object holds one (a Dataset without static points: no)
        carried = [(name, kind.removesuffix(_OR_NONE)) for name, kind in _CODECS[typ][1]
                   if not (kind.endswith(_OR_NONE) and isinstance(obj, dict) and obj.get(name) is None)]
        carried = [(name, kind) for name, kind in carried if kind in wanted]
        hint = (f" (a {typ} carries a {carried[0][1]}: load it without expect= and take its "
                f"{' or '.join('.' + name for name, _ in carried)})" if carried else "")
        raise GrayboxFileError(f"{source}: holds a {typ}, expected {' or '.join(w.__name__ for w in want)}{hint}")


def from_json(text: str, *, expect: type | tuple[type, ...] | None = None, source: str = "<json>") -> Any:
    """The value in a graybox JSON text.

    Parameters
    ----------
    text : str
        As written by :func:`to_json`.
    expect : type or tuple of types, optional
        Refuse a value of any other type (e.g. ``expect=gb.Model``).
    source : str
        Name used in error messages.

    Returns
    -------
    The value (a Model, ParetoSet, …).

    Raises
    ------
    GrayboxFileError
        Corrupt JSON, not a graybox document, a newer or unknown format version, an unknown or
        unexpected type, a missing, unknown or malformed field.
    """
    if not isinstance(text, str):
        raise TypeError(f"text must be a str, got {type(text).__name__} (decode the bytes of a file as UTF-8)")
    want = _expected(expect)
    head, doc = _parse(text.removeprefix("\ufeff"), source)  # an editor's byte-order mark is no text (as load)
    _expect(want, head["type"], source, doc.get("object"))
    if "object" not in doc:
        raise GrayboxFileError(f"{source}: no \"object\" in the document")
    try:
        obj = _decode_fields(head["type"], doc["object"], "object", _Reader(source))
    except RecursionError:  # saved values inside plain values inside saved values …: each type counts its own nesting
        raise GrayboxFileError(f"{source}: object: values nested too deeply (a Dataset's extra or a bootstrap's options "
                               "holding saved values that hold more, beyond what Python's recursion reads)") from None
    except GrayboxFileError as exc:
        said = _newer(head["graybox_version"])  # a field added since
        if said:
            raise GrayboxFileError(f"{exc}{said}") from None
        raise
    # the header says the units the value's numbers hold in (to_json never writes other ones): a file whose header
    # was edited to other units would tell read_header's reader one unit and load a value in another
    own, said = _own_units(obj), head["units"]
    if own is not None and said is not None and _contradicts(said, own):
        raise GrayboxFileError(f"{source}: header: units {said} contradict the units the {head['type']} holds its "
                               f"numbers in, {own} (a hand edit, or a file saved with units= by a graybox that did not check "
                               "them): set the header's units to the value's (or remove them), or convert the data and "
                               "refit in the units meant")
    return obj


def _newer(written_by: str) -> str:
    """`` (the file was written by graybox X, newer than this Y: upgrade …)`` when ``written_by`` is a newer
    release than this graybox (a type or a field added since, within one format version), else ``""``."""
    ours = graybox_version()
    if ours != "0+unknown" and _release(written_by) > _release(ours):
        return f" (the file was written by graybox {written_by}, newer than this {ours}: upgrade graybox to load it)"
    return ""


def _release(version: str) -> tuple[int, ...]:
    """The release numbers of a version text (``"0.2.1"`` → (0, 2, 1)), for telling a newer writer."""
    m = re.match(r"\d+(?:\.\d+)*", version.strip())
    return tuple(int(x) for x in m.group(0).split(".")) if m else ()


def save(
    obj: Any,
    path: str | os.PathLike,
    *,
    units: tuple | Mapping[str, Any] | None = None,
) -> Path:
    """Write a graybox value to a JSON file (atomically: a crash never leaves a torn file).

    Parameters
    ----------
    obj : Model, NeuralModel, ParetoSet, Selection, ELSResult, NeuralFit, Decision, DSFResult, OEResult, SEMPResult, ParameterUncertainty, StaticCurveBand, StaticSurfaceBand, SimulationBand, CLSResult, GAOptions, ResidualTests, CorrelationTest, DecisionBootstrap, StaticPoints, StaticCurve, StaticSurface, Equilibrium, LocalModel, OperatingCurve, Record, Dataset, Structure, DecimationAdvice or GrayboxSelection
        The value.
    path : str or PathLike
        Where to write (conventionally ``*.json``).
    units : tuple or mapping, optional
        Units of u and y for the header, as :func:`to_json` takes them (e.g. ``data.ident.units``).

    Returns
    -------
    pathlib.Path
        The path written.
    """
    p = Path(check_path(path, "path", file=True))
    text = to_json(obj, units=units)
    if p.is_dir():
        raise IsADirectoryError(errno.EISDIR, "a folder, not a file to save to", str(p))
    write_atomically(p, lambda f: f.write(text.encode("utf-8")))  # through a symbolic link, keeping the file's mode
    return p


def _read(path: str | os.PathLike) -> str:
    p = Path(check_path(path, "path", file=True))
    raw = p.read_bytes()
    # a byte-order mark an editor added says the encoding (UTF-16 from "Unicode" saves) and is not text
    enc = bom_encoding(raw) or "utf-8"
    enc = "utf-8-sig" if enc == "utf-8" else enc
    try:
        return raw.decode(enc)
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].decode(enc, errors="replace").count("\n") + 1
        where = f"line {line} is not {enc.removesuffix('-sig').upper()} text (byte {raw[exc.start]:#04x})"
        if re.match(r'\s*\{\s*"format"\s*:\s*"graybox"', raw.decode("latin-1").removeprefix("\xef\xbb\xbf")):
            # an edit saved by an editor in its own encoding (cp1252, "ANSI"): a graybox file all the same
            raise GrayboxFileError(f"{p}: {where}: a graybox file saved again in another encoding (cp1252, Latin-1?) "
                                   "after an edit; graybox files are UTF-8: open it in that encoding and save it as "
                                   "UTF-8") from None
        raise GrayboxFileError(f"{p}: not a graybox file: {where}") from None


def load(path: str | os.PathLike, *, expect: type | tuple[type, ...] | None = None) -> Any:
    """Read a value written by :func:`save`. No pickle is involved, whatever the file holds.

    Parameters
    ----------
    path : str or PathLike
        The JSON file.
    expect : type or tuple of types, optional
        Refuse a value of any other type (e.g. ``expect=gb.Model``).

    Returns
    -------
    The value (a Model, ParetoSet, …).

    Raises
    ------
    GrayboxFileError
        See :func:`from_json`.
    FileNotFoundError
        No such file.
    """
    _expected(expect)  # a bad expect is said before the file is read
    return from_json(_read(path), expect=expect, source=str(path))


def read_header(path: str | os.PathLike) -> Mapping[str, Any]:
    """The header of a graybox file: ``format_version``, ``graybox_version``, ``type``, ``units``.

    Parameters
    ----------
    path : str or PathLike
        The JSON file.

    Returns
    -------
    mapping
        ``units`` is ``(u unit, y unit)`` or None when the file has none.
    """
    head, _ = _parse(_read(path), str(path))
    return FrozenMap(head)
