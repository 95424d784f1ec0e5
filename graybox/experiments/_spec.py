"""Grid specifications: data sets × structures × variants × seeds, in Python and in TOML.

Every piece is a small frozen dataclass that validates itself and has a *canonical* form
(:meth:`to_dict`: plain JSON values, defaults filled in). The canonical forms are what a cell's
key hashes and what the store keeps, so a grid written in Python and the same grid written in
TOML give the same cells. A TOML spec is parsed with :mod:`tomllib`; every problem in it is a
:class:`SpecError` naming the key and the line it is on.
"""

from __future__ import annotations

import hashlib
import json
import numbers
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

from .. import _api as gb

from ..core._terms import Term, default_input_names, parse_term
from ..datasets._loaders import BUCK_STATIC_UNCERTAINTY, PUMPING_STATIC_UNCERTAINTY
from ..core._validation import (check_bool, check_choice, check_count, check_fields, check_int, check_lambdas,
                                check_path, check_real, check_sequence, check_str)
from ..core._files import bom_encoding
from ..core._records import check_units
from ..core._reprs import short_repr
from ..estimation._extended_least_squares import DEFAULT_NE
from ..estimation._simulation_error import gradient_front
from ..selection._forward_regression import CRITERIA
from ..static._constraints import FREE_SIGMA_Y, check_min_denominator
from ..static._surfaces import monomial_exponents

__all__ = [
    "SpecError",
    "SpecTypeError",
    "DataSpec",
    "StructureSpec",
    "Variant",
    "DecisionRule",
    "Grid",
    "Cell",
    "ESTIMATORS",
    "CONSTRAINT_TYPES",
    "DECISION_RULES",
    "BUNDLED",
]

#: Estimators a variant may name.
ESTIMATORS = ("ls", "els", "cls", "pe", "se-ga", "se-gradient", "se-dsf", "neural")
#: Estimators that give a Pareto set (and so need a decision maker).
PARETO_ESTIMATORS = ("pe", "se-ga", "se-gradient")
#: Estimators that take a λ set (se-dsf: the λ1 of the coarse sweep that finds its starts).
LAMBDA_ESTIMATORS = PARETO_ESTIMATORS + ("se-dsf",)
#: Estimators whose result depends on the seed; the others run once per (data, structure, variant).
STOCHASTIC_ESTIMATORS = ("se-ga", "neural")
#: Estimators that take static constraints.
CONSTRAINED_ESTIMATORS = ("cls", "pe")
#: Constraint types (TOML ``type = …``) and the graybox object each stands for.
CONSTRAINT_TYPES = {
    "equality": "CurveEquality (eq. (22))",
    "points": "PassesThrough",
    "band": "StaticBand",
    "gain": "GainBounds",
    "clusters": "ClusterBounds",
}
#: Decision makers for Pareto sets.
DECISION_RULES = ("dsf", "min_correlation", "min_jsf")
#: Bundled data sets and their J_SF band B (output units²), the band their static points carry
#: (``load_*().static.band``, the mean of δ²): the pumping plant's transmitter error ±0.175 mlc
#: (0.175² mlc²), the buck converter's half resolution 0.1 V (0.1² V²).
BUNDLED = {"pumping": PUMPING_STATIC_UNCERTAINTY**2, "buck": BUCK_STATIC_UNCERTAINTY**2,
           "pumping_miso": PUMPING_STATIC_UNCERTAINTY**2}


# --------------------------------------------------------------------------------------------
# errors that know where they are
# --------------------------------------------------------------------------------------------
class SpecError(ValueError):
    """A grid specification is wrong; the message names the key (and, for a TOML file, its line).

    Attributes
    ----------
    path : tuple
        Where the problem is, e.g. ``("variants", 2, "options", "solver")``.
    problem : str
        What is wrong, in words.
    source : str or None
        The spec's file (or the name given to its text), when known.
    line : int or None
        The line of the key in that TOML text, when known.
    """

    def __init__(self, problem: str, path: Sequence[str | int] = (), source: str | None = None,
                 line: int | None = None):
        self.problem = problem
        self.path = tuple(path)
        self.source = source
        self.line = line
        super().__init__(self._text())

    def _text(self) -> str:
        where = _dotted(self.path)
        head = ""
        if self.source:
            head = f"{self.source}" + (f", line {self.line}" if self.line else "") + ": "
        return f"{head}{where + ': ' if where else ''}{self.problem}"

    def within(self, *prefix: str | int) -> "SpecError":
        """The same error with ``prefix`` put in front of its path.

        Parameters
        ----------
        *prefix : str or int
            Keys and list positions of the spec, outermost first (e.g. ``"variants", 2``).

        Returns
        -------
        SpecError
            Of this error's type (a :class:`SpecTypeError` stays one), with the same problem, source and line.
        """
        return type(self)(self.problem, tuple(prefix) + self.path, self.source, self.line)


class SpecTypeError(SpecError, TypeError):
    """A value of the wrong *type* in a grid specification (a number for a name, a string for a table …).

    A ``TypeError``, as graybox's argument checks raise for a wrong type (``graybox.core._validation``),
    and a :class:`SpecError`, so that ``except SpecError`` (the command line's one-line message) still
    catches every problem of a spec, with its key and line.

    Attributes
    ----------
    problem, path, source, line
        As for :class:`SpecError`.
    """


def _dotted(path: Sequence[str | int]) -> str:
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out


def _wrap(fn, path: Sequence[str | int], *args, **kw):
    """Call a graybox validator; turn its ValueError into a SpecError, its TypeError into a SpecTypeError, at
    ``path``."""
    try:
        return fn(*args, **kw)
    except SpecError:
        raise
    except TypeError as exc:
        raise SpecTypeError(str(exc), path) from None
    except ValueError as exc:
        raise SpecError(str(exc), path) from None


def _check_keys(d: Mapping, allowed: Iterable[str], what: str, path: Sequence[str | int] = ()) -> None:
    if not isinstance(d, Mapping):
        raise SpecTypeError(f"{what} must be a table (key = value pairs), got {type(d).__name__}", path)
    allowed = tuple(allowed)
    for k in d:
        if k not in allowed:
            raise SpecError(f"unknown key {k!r} in {what}; known keys: {', '.join(allowed)}", tuple(path) + (k,))


def _name(v: object, path: Sequence[str | int]) -> str:
    _wrap(check_str, tuple(path) + ("name",), v, "name")
    if not v.strip():
        raise SpecError(f"name must be a non-empty string, got {v!r}", tuple(path) + ("name",))
    return v


class FrozenDict(dict):
    """A dict that refuses changes (and, unlike a mapping proxy, pickles: cells travel to workers)."""

    def _refuse(self, *args, **kwargs):
        raise TypeError("a grid's specification is immutable")

    __setitem__ = __delitem__ = clear = pop = popitem = setdefault = update = __ior__ = _refuse  # type: ignore

    def __reduce__(self):
        return (FrozenDict, (dict(self),))

    def __hash__(self) -> int:  # type: ignore[override]
        return hash(canonical_json(self))


def _freeze(obj: Any) -> Any:
    """Read-only copies of nested canonical values (dicts become FrozenDicts, lists tuples)."""
    if isinstance(obj, Mapping):
        return FrozenDict({k: _freeze(v) for k, v in obj.items()})
    if isinstance(obj, (list, tuple)):
        return tuple(_freeze(v) for v in obj)
    return obj


def _thaw(obj: Any) -> Any:
    """Plain JSON values (dicts and lists) from frozen ones."""
    if isinstance(obj, Mapping):
        return {k: _thaw(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_thaw(v) for v in obj]
    return obj


def canonical_json(obj: Any) -> str:
    """Deterministic JSON text of a canonical value (sorted keys, exact float repr)."""
    return json.dumps(_thaw(obj), sort_keys=True, separators=(",", ":"), allow_nan=False)


def _hash(obj: Any, n: int = 16) -> str:
    return hashlib.sha256(canonical_json(obj).encode()).hexdigest()[:n]


# --------------------------------------------------------------------------------------------
# data sets
# --------------------------------------------------------------------------------------------
#: How a file is read, as the loaders take it (their messages name these options, e.g. "pass skiprows=3"): the
#: loader checks the values; in the canonical form only when given.
_READ_KEYS = ("delimiter", "decimal", "encoding", "skiprows", "units_row", "units")
_RECORD_KEYS = ("path", "u", "y", "time", "Ts", "input_names", "time_rtol", *_READ_KEYS)
_STATIC_KEYS = ("path", "u", "y", "repeats", "uncertainty", "input_names", *_READ_KEYS)


#: A loader's hint naming one of its keyword options as Python writes it (``decimal=','``, ``units_row=True``,
#: ``skiprows=3``, a bare ``delimiter=``): what a spec's user writes differently, in TOML.
_PY_OPTION = re.compile(r"\b(delimiter|decimal|encoding|skiprows|units_row|units|time_rtol)="
                        r"('(?:[^'\\]|\\.)*'|\"(?:[^\"\\]|\\.)*\"|True\b|False\b|[0-9][0-9.eE+-]*|\([^()]*\))?")


def _toml_hints(text: str) -> str:
    """A loader's message with its keyword options as a spec's file table takes them: ``decimal=','`` becomes
    ``decimal = ","``, ``units_row=True`` ``units_row = true``, a bare ``delimiter=`` the key ``delimiter``."""
    import ast

    def toml(m: re.Match) -> str:
        key, value = m.group(1), m.group(2)
        if value is None:
            return key
        if value in ("True", "False"):
            return f"{key} = {value.lower()}"
        if value[0] == "(":  # units=(input unit, output unit): a TOML array
            return f"{key} = [{value[1:-1]}]"
        if value[0] in "'\"":
            return f"{key} = {json.dumps(ast.literal_eval(value), ensure_ascii=False)}"
        return f"{key} = {value}"

    return _PY_OPTION.sub(toml, text)


def _read_options(entry: Mapping[str, Any]) -> dict[str, Any]:
    """The loader's keyword options a file entry gives."""
    return {k: entry[k] for k in ("input_names", "time_rtol", *_READ_KEYS) if k in entry}


def _file_entry(d: object, keys: tuple[str, ...], what: str, path: tuple) -> dict:
    _check_keys(d, keys, what, path)
    assert isinstance(d, Mapping)
    out: dict[str, Any] = {}
    for k in ("path", "u", "y"):
        if k not in d:
            raise SpecError(f"{what} needs {k!r}", path + (k,))
        v = d[k]
        if k == "path" and isinstance(v, os.PathLike):  # a pathlib.Path, as every other path of graybox takes
            v = os.fspath(v)
        if k == "u" and isinstance(v, Sequence) and not isinstance(v, str):  # several input columns
            for i, c in enumerate(v):
                _wrap(check_str, path + (k, i), c, f"{k}[{i}]")
            if not v or not all(v):
                raise SpecError(f"u must be a column name or a non-empty list of column names, got {v!r}", path + (k,))
            out[k] = list(v)
            continue
        if not isinstance(v, str):  # a wrong type (the same message as its empty value's)
            raise SpecTypeError(f"{k} must be a non-empty string{' or a list of them' if k == 'u' else ''}, got {v!r}",
                                path + (k,))
        if not v:
            raise SpecError(f"{k} must be a non-empty string{' or a list of them' if k == 'u' else ''}, got {v!r}",
                            path + (k,))
        out[k] = v
    if d.get("input_names") is not None:  # absent: the canonical form is as before
        n = len(out["u"]) if isinstance(out["u"], list) else 1
        names = _wrap(check_sequence, path + ("input_names",), d["input_names"], "input_names", "a list of names")
        for i, c in enumerate(names):
            _wrap(check_str, path + ("input_names", i), c, f"input_names[{i}]")
        if len(names) != n or not all(names):
            raise SpecError(f"input_names must be a list of {n} name(s), one per input column of u, got {names!r}",
                            path + ("input_names",))
        out["input_names"] = names
    for k in ("delimiter", "decimal", "encoding"):
        if d.get(k) is not None:
            out[k] = _wrap(check_str, path + (k,), d[k], k)
    if d.get("skiprows") is not None:
        out["skiprows"] = _wrap(check_int, path + ("skiprows",), d["skiprows"], "skiprows", low=0)
    if d.get("units_row") is not None:
        out["units_row"] = _wrap(check_bool, path + ("units_row",), d["units_row"], "units_row")
    if d.get("units") is not None:  # absent: the canonical form is as before
        u, y = _wrap(check_units, path + ("units",), d["units"], "units")
        out["units"] = [u if isinstance(u, str) else list(u), y]  # a TOML/JSON array: the inputs' one or each
    if "time_rtol" in keys and d.get("time_rtol") is not None:
        out["time_rtol"] = _wrap(check_real, path + ("time_rtol",), d["time_rtol"], "time_rtol", low=0, high=1,
                                 low_open=True, high_open=True)
    if "repeats" in keys:
        out["repeats"] = _wrap(check_choice, path + ("repeats",), d.get("repeats", "error"), "repeats", ("error", "mean"))
    if "uncertainty" in keys and isinstance(d.get("uncertainty"), str):  # the column of each point's δ
        if not d["uncertainty"].strip():
            raise SpecError("uncertainty must be δ (a number > 0, output units) or the name of the column holding "
                            "each point's δ, got ''", path + ("uncertainty",))
        out["uncertainty"] = d["uncertainty"]
    elif "uncertainty" in keys and d.get("uncertainty") is not None:  # absent: the canonical form is as before
        out["uncertainty"] = _wrap(check_real, path + ("uncertainty",), d["uncertainty"], "uncertainty", low=0,
                                   low_open=True)
    if "time" in keys:
        t = d.get("time")
        if t is not None:
            _wrap(check_str, path + ("time",), t, "time (a column name)")
        Ts = d.get("Ts")
        if Ts is not None:
            Ts = _wrap(check_real, path + ("Ts",), Ts, "Ts", low=0, low_open=True)
        if t is None and Ts is None:
            raise SpecError(f"{what} needs a time column (time = …) or a sampling period (Ts = … seconds)", path)
        out["time"], out["Ts"] = t, Ts
    return out


@dataclass(frozen=True, eq=False)
class DataSpec:
    """One data set of a grid: a bundled one by name, the user's CSV files, or a Dataset in memory.

    Parameters
    ----------
    name : str
        Label in the results.
    bundled : {"pumping", "buck", "pumping_miso"}, optional
        :func:`graybox.load_pumping`, :func:`graybox.load_buck` or :func:`graybox.load_pumping_miso`
        (the rig with two independent pump speeds: two inputs).
    ident, valid : mapping, optional
        CSV records ``{"path", "u", "y", "time" or "Ts"}`` and optionally ``input_names``,
        ``time_rtol``, ``delimiter``, ``decimal``, ``encoding``, ``skiprows``, ``units_row``, ``units`` (see
        :func:`graybox.load_record_csv`; ``u`` a column name, or a list of them for several inputs;
        ``units = ["rpm", "Pa"]`` the (input, output) units, or ``units = [["rpm", "%"], "Pa"]`` one per
        input (checked against a units row, where one is read);
        ``input_names`` the names terms use for them, needed when the column names are not
        identifiers, e.g. ``"speed [rpm]"``); relative paths are resolved against the spec file's folder.
    static : mapping, optional
        CSV static points ``{"path", "u", "y", "repeats", "uncertainty"}`` and optionally ``input_names``,
        ``delimiter``, ``decimal``, ``encoding``, ``skiprows``, ``units_row``, ``units`` (see
        :func:`graybox.load_static_csv`; ``repeats = "mean"`` averages repeated measurements at one
        level; ``uncertainty`` is δ, the static measurements' error in output units, which gives
        the band and the half-width of a ``{type = "band"}`` without ``b``: one number, or the name
        of the column holding each point's δ).
    band : float, optional
        The J_SF band B = [0, band] (output units²) for D_SF decisions and the reports. Default:
        the static points' own band, mean δ² (:attr:`graybox.StaticPoints.band`): for the bundled sets
        0.175² mlc² (pumping and pumping_miso: the same transmitter) and 0.1² V² (buck); for CSV
        data the static file's ``uncertainty`` (a column's δ once the file is read: the
        attribute stays None, and ``band_of`` gives it); for a Dataset its static points' uncertainty.
        None when there is none (then D_SF decisions need a band given).
    dataset : Dataset, optional
        A Dataset built in Python (not expressible in TOML); its content is hashed.
    """

    name: str
    bundled: str | None = None
    ident: Mapping[str, Any] | None = None
    valid: Mapping[str, Any] | None = None
    static: Mapping[str, Any] | None = None
    band: float | None = None
    dataset: gb.Dataset | None = None

    def __post_init__(self) -> None:
        _name(self.name, ())
        given = [k for k in ("bundled", "dataset") if getattr(self, k) is not None]
        files = [k for k in ("ident", "valid", "static") if getattr(self, k) is not None]
        if len(given) + bool(files) != 1:
            raise SpecError("a data set is exactly one of: bundled = \"pumping\"/\"buck\"/\"pumping_miso\", CSV files "
                            "(ident, valid, static), or dataset = a Dataset in memory")
        if self.bundled is not None:
            _wrap(check_choice, ("bundled",), self.bundled, "bundled", tuple(BUNDLED))
        if self.dataset is not None and not isinstance(self.dataset, gb.Dataset):
            raise SpecTypeError(f"dataset must be a graybox Dataset, got {type(self.dataset).__name__}", ("dataset",))
        if files:
            for k in ("ident", "valid", "static"):
                if getattr(self, k) is None:
                    raise SpecError(f"CSV data need ident, valid and static files; {k} is missing", (k,))
            object.__setattr__(self, "ident", _freeze(_file_entry(self.ident, _RECORD_KEYS, "a record file", ("ident",))))
            object.__setattr__(self, "valid", _freeze(_file_entry(self.valid, _RECORD_KEYS, "a record file", ("valid",))))
            object.__setattr__(self, "static", _freeze(_file_entry(self.static, _STATIC_KEYS, "a static file", ("static",))))
        band = self.band
        if band is None and self.bundled is not None:
            band = BUNDLED[self.bundled]
        elif band is None and self.static is not None and isinstance(self.static.get("uncertainty"), float):
            # (a column's δ give theirs once read: band_of)
            band = _points_band(float(self.static["uncertainty"]) ** 2, self.static["uncertainty"], self.name)
        elif band is None and self.dataset is not None and self.dataset.static is not None \
                and self.dataset.static.uncertainty is not None:
            band = _points_band(self.dataset.static.band, max(self.dataset.static.uncertainty), self.name)
        if band is not None:
            band = _wrap(check_real, ("band",), band, "band", low=0, low_open=True)
        object.__setattr__(self, "band", band)

    def to_dict(self) -> dict:
        """Canonical form (what the spec says, not the data's content).

        Returns
        -------
        dict
            ``name``, the source (``bundled``; ``dataset``: ``"in memory"``; or the ``ident``, ``valid`` and
            ``static`` file tables) and ``band`` (output units², or None).
        """
        if self.bundled is not None:
            src: dict[str, Any] = {"bundled": self.bundled}
        elif self.dataset is not None:
            src = {"dataset": "in memory"}
        else:
            src = {k: _thaw(getattr(self, k)) for k in ("ident", "valid", "static")}
        return {"name": self.name, **src, "band": self.band}

    def load(self, base_dir: str | Path | None = None) -> gb.Dataset:
        """The data as a :class:`~graybox.Dataset` (identification, validation, static points).

        Only what cells use is kept: the records, the static points and, when the source has
        one, ``extra["static_curve"]`` (e.g. eq. (1) for the pumping plant).

        Parameters
        ----------
        base_dir : path, optional
            Folder that relative CSV paths are resolved against (default: the working folder).

        Returns
        -------
        Dataset
            In the units the files or the bundled set give.
        """
        if base_dir is not None:
            base_dir = check_path(base_dir, "base_dir")  # '~/data' the home folder's, as check_path reads it
        if self.dataset is not None:
            ds = self.dataset
        elif self.bundled == "pumping":
            ds = gb.load_pumping()
        elif self.bundled == "buck":
            ds = gb.load_buck()
        elif self.bundled == "pumping_miso":
            ds = gb.load_pumping_miso()
        else:
            base = Path(base_dir) if base_dir is not None else Path.cwd()

            def p(entry: Mapping) -> Path:
                q = Path(entry["path"]).expanduser()
                return q if q.is_absolute() else base / q

            assert self.ident is not None and self.valid is not None and self.static is not None
            ident = gb.load_record_csv(p(self.ident), u=self.ident["u"], y=self.ident["y"], time=self.ident["time"],
                                       Ts=self.ident["Ts"], name=f"{self.name} ident", **_read_options(self.ident))
            valid = gb.load_record_csv(p(self.valid), u=self.valid["u"], y=self.valid["y"], time=self.valid["time"],
                                       Ts=self.valid["Ts"], name=f"{self.name} valid", **_read_options(self.valid))
            static = gb.load_static_csv(p(self.static), u=self.static["u"], y=self.static["y"],
                                        name=f"{self.name} static points", repeats=self.static["repeats"],
                                        uncertainty=self.static.get("uncertainty"), **_read_options(self.static))
            ds = gb.Dataset(ident, valid, static, description=f"CSV files of data set {self.name!r}")
        if ds.static is None:
            raise SpecError("the data set has no static points: gray-box cells and J_SF need them", ())
        extra = {"static_curve": ds.extra["static_curve"]} if "static_curve" in ds.extra else {}
        return gb.Dataset(ds.ident, ds.valid, ds.static, description=ds.description, extra=extra)

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape


def _column_uncertainty(d: DataSpec) -> bool:
    """Whether a data set's static file gives each point's δ in a column (its band is known once read)."""
    return d.static is not None and isinstance(d.static.get("uncertainty"), str)


def _points_band(band: float, delta: float, name: str) -> float:
    """The band mean δ² the static points' uncertainty gives (output units²), or a ``ValueError`` naming the
    data set and its δ where it leaves the float range (δ near 1e154 or 1e-162): a band the user never set must
    not be refused as 'band must be finite' (hunt60c)."""
    if not (0 < band < float("inf")):
        raise ValueError(f"data set {name!r}: the band its static points' uncertainty gives, mean δ² with δ up to "
                         f"{float(delta):.3g} (output units), is {band:g}, beyond the float range: give the data "
                         "set's band = B yourself, or the output in other units")
    return band


def band_of(d: DataSpec, ds: gb.Dataset) -> float | None:
    """The band B of a data set, loaded as ``ds``: the spec's, or its static points' own when a column of
    the static file gave their δ."""
    if d.band is None and _column_uncertainty(d) and ds.static is not None and ds.static.uncertainty is not None:
        return _points_band(ds.static.band, max(ds.static.uncertainty), d.name)
    return d.band


def stored_spec(grid: "Grid", datasets: Mapping[str, gb.Dataset]) -> dict:
    """A grid's canonical form as a store keeps it: each data set's band as its cells hold it (a static
    file's column of δ gives it once read, :func:`band_of`), which the rows read back show, and its output's
    unit (``y_unit``, when the data carry one) for the reports."""
    out = grid.to_dict()
    for d, entry in zip(grid.data, out["data"]):
        entry["band"] = band_of(d, datasets[d.name])
        unit = datasets[d.name].valid.units[1]
        if unit:  # the reports say J_S, J_SF and B in it (squared); none said: the specs stored before read as before
            entry["y_unit"] = unit
    return out


def _structure_inputs(st: "StructureSpec") -> list[str]:
    """The input names a structure spec names itself (its terms; per-input lags and delays, included terms): a made
    structure with one lag count for all inputs takes the data set's, whatever they are called."""
    if st.terms is not None:
        return list(gb.parse_structure(list(st.terms)).input_names)
    assert st.candidates is not None
    named = [n for k in ("nu", "delay") if isinstance(st.candidates[k], Mapping) for n in st.candidates[k]]
    if st.include:
        named += gb.parse_structure(list(st.include)).input_names
    return list(dict.fromkeys(named))


def _carries_uncertainty(d: DataSpec) -> bool:
    """Whether a data set's static points carry their uncertainty δ (the bundled sets' do)."""
    if d.dataset is not None:
        return d.dataset.static is not None and d.dataset.static.uncertainty is not None
    return d.bundled is not None or (d.static is not None and d.static.get("uncertainty") is not None)


def data_fingerprint(ds: gb.Dataset) -> str:
    """A hash of a data set's content: records (u, y, Ts), static points, static curve (a surface's monomials and
    inputs too), and the inputs' names when they are not the default ones (made structures' terms carry them)."""
    h = hashlib.sha256()
    names = ds.input_names
    if tuple(names) != tuple(default_input_names(len(names))):  # default names hash as before
        h.update(repr(tuple(names)).encode())
    for r in (ds.ident, ds.valid):
        h.update(np.ascontiguousarray(r.u, dtype="<f8").tobytes())
        h.update(np.ascontiguousarray(r.y, dtype="<f8").tobytes())
        h.update(repr(float(r.Ts)).encode())
    if ds.static is not None:
        h.update(np.ascontiguousarray(ds.static.ubar, dtype="<f8").tobytes())
        h.update(np.ascontiguousarray(ds.static.ybar, dtype="<f8").tobytes())
    curve = ds.extra.get("static_curve")
    if curve is not None:
        h.update(np.ascontiguousarray(curve.coefficients, dtype="<f8").tobytes())
        h.update(repr(curve.domain).encode())
        if isinstance(curve, gb.StaticSurface) and not _plain_surface(curve, names):
            # its coefficients say nothing without their monomials and inputs; the surface a fit in the records'
            # order gives (every monomial up to its degree, in order) hashes as before, so stores keep their keys
            h.update(repr((tuple(curve.exponents), tuple(curve.input_names))).encode())
    return h.hexdigest()[:16]


def _plain_surface(surface: gb.StaticSurface, names: Sequence[str]) -> bool:
    """Whether ``surface`` is in the inputs ``names``, in that order, on every monomial up to its degree in
    :func:`~graybox.static._surfaces.monomial_exponents` order: the one such surface of its coefficients."""
    return (tuple(surface.input_names) == tuple(names)
            and tuple(surface.exponents) == monomial_exponents(surface.n_inputs, surface.degree))


def uncertainty_key(ds: gb.Dataset, band: float | None) -> list[float] | None:
    """The static points' uncertainty δ (output units) as a cell key holds it, or None when the key needs
    none: no δ, or one δ for every point whose square is the data set's band (already in the key)."""
    d = None if ds.static is None else ds.static.uncertainty
    if d is None or (band is not None and np.all(d == d[0]) and float(d[0]) ** 2 == band):
        return None
    return [float(v) for v in d]


def reads_band(variant_content: Mapping[str, Any]) -> bool:
    """Whether a variant's result depends on the data set's band (a cell's ``band``): se-dsf without its own band
    solves in it, and a Pareto estimator's D_SF decision without its own band decides with it. No other
    estimator reads it (ls, els, neural and cls take none; a band constraint without b takes the points' δ, and
    the Pareto sets themselves none): their cells are keyed without it, so that a new band reruns only the cells
    it changes."""
    est = variant_content["estimator"]
    if est == "se-dsf":
        return variant_content["options"].get("band") is None
    d = variant_content.get("decision")
    return est in PARETO_ESTIMATORS and d is not None and d["rule"] == "dsf" and d["band"] is None


def reads_uncertainty(variant_content: Mapping[str, Any]) -> bool:
    """Whether a variant's result depends on the static points' uncertainty δ: a band constraint without
    its half-width b takes each point's δ."""
    return any(c["type"] == "band" and c.get("b") is None for c in variant_content["constraints"])


# --------------------------------------------------------------------------------------------
# structures
# --------------------------------------------------------------------------------------------
_CANDIDATE_KEYS = ("ny", "nu", "ne", "degree", "delay", "constant", "max_y_power")
_STRUCTURE_RULE_KEYS = ("n_terms", "tol", "criterion", "max_terms", "include")


@dataclass(frozen=True, eq=False)
class StructureSpec:
    """One structure of a grid: given terms, or made by FROLS from a candidate space and a rule.

    Parameters
    ----------
    name : str
        Label in the results.
    terms : sequence of str, optional
        The process terms, e.g. ``["y(k-1)", "u(k-1)", "1"]`` (given structure).
    candidates : mapping, optional
        Keyword arguments of :func:`graybox.Candidates` (``ny``, ``nu``, ``degree``,
        ``max_y_power`` …): the space FROLS selects from (made structure). With several inputs
        ``nu`` and ``delay`` may be tables of one value per input name (``{"u1": 2, "u2": 3}``);
        a single ``nu`` applies to every input of the data set.
    n_terms, tol, criterion, max_terms, include : optional
        The selection rule, as for :func:`graybox.frols` (count, ERR tolerance, or information
        criterion; ``include``: terms selected first, e.g. ``["1"]``).
    """

    name: str
    terms: Sequence[str] | None = None
    candidates: Mapping[str, Any] | None = None
    n_terms: int | None = None
    tol: float | None = None
    criterion: str | None = None
    max_terms: int | None = None
    include: Sequence[str] = ()

    def __post_init__(self) -> None:
        _name(self.name, ())
        if (self.terms is None) == (self.candidates is None):
            raise SpecError("a structure is either given (terms = [...]) or made (candidates = {...} and a rule)")
        rule = {k: getattr(self, k) for k in _STRUCTURE_RULE_KEYS if getattr(self, k) not in (None, ())}
        if self.terms is not None:
            if rule:
                raise SpecError(f"a given structure (terms) takes no selection rule; remove {', '.join(rule)}",
                                (next(iter(rule)),))
            if isinstance(self.terms, str) or not isinstance(self.terms, Sequence):
                raise SpecTypeError("terms must be a non-empty list of term strings such as \"u(k-1)y(k-2)\"",
                                    ("terms",))
            if not self.terms:
                raise SpecError("terms must be a non-empty list of term strings such as \"u(k-1)y(k-2)\"", ("terms",))
            st = _wrap(gb.parse_structure, ("terms",), list(self.terms))
            if len(st.noise):
                raise SpecError(f"noise terms {[str(t) for t in st.noise]} have no place in a grid structure "
                                "(ELS takes its MA order from the variant's options)", ("terms",))
            object.__setattr__(self, "terms", tuple(str(t) for t in st))
            object.__setattr__(self, "include", ())
            return
        _check_keys(self.candidates, _CANDIDATE_KEYS, "candidates", ("candidates",))
        assert self.candidates is not None
        c = dict(self.candidates)
        for k in ("ny", "nu"):
            if k not in c:
                raise SpecError(f"candidates need {k!r}", ("candidates", k))
        cand = {"ny": c["ny"], "nu": c["nu"], "ne": c.get("ne", 0), "degree": c.get("degree", 2),
                "delay": c.get("delay", 1), "constant": c.get("constant", True),
                "max_y_power": c.get("max_y_power")}
        for k in ("ny", "nu", "ne", "degree", "delay", "max_y_power"):
            if k in ("nu", "delay") and isinstance(cand[k], Mapping):  # several inputs: one value per input name
                cand[k] = {str(n): _wrap(check_int, ("candidates", k, n), v, f"{k} of input {n!r}",
                                         low=1 if k == "delay" else 0) for n, v in cand[k].items()}
            elif cand[k] is not None:
                cand[k] = _wrap(check_int, ("candidates", k), cand[k], k, low=1 if k == "delay" else 0)
        if cand["ne"]:
            raise SpecError("noise candidates (ne > 0) are not selected by FROLS; give ELS its MA order in the "
                            "variant's options (noise = 2)", ("candidates", "ne"))
        _wrap(check_bool, ("candidates", "constant"), cand["constant"], "constant")
        if isinstance(self.include, str) or not isinstance(self.include, Sequence):
            raise SpecTypeError("include must be a list of term strings", ("include",))
        inc = _wrap(gb.parse_structure, ("include",), list(self.include)) if self.include else gb.Structure(())
        kw: dict[str, Any] = {}
        if not isinstance(cand["nu"], Mapping):
            # one lag count for every input of the data set, whose names the spec does not know: check
            # against the inputs the delays or the included terms name (the cell uses the data set's)
            named = list(cand["delay"]) if isinstance(cand["delay"], Mapping) else list(inc.input_names)
            if named:
                kw["input_names"] = tuple(named)
        space = _wrap(lambda: gb.Candidates(**cand, **kw), ("candidates",))
        object.__setattr__(self, "candidates", _freeze(cand))
        # with one lag count for all inputs the data set decides how many inputs, so how many
        # candidates there are: FROLS checks n_terms and max_terms against the count in the cell then
        high = len(space) if isinstance(cand["nu"], Mapping) else None
        if self.n_terms is not None:
            object.__setattr__(self, "n_terms", _wrap(check_int, ("n_terms",), self.n_terms, "n_terms", low=1,
                                                      high=high))
        if self.tol is not None:
            object.__setattr__(self, "tol", _wrap(check_real, ("tol",), self.tol, "tol", low=0, high=1,
                                                  low_open=True, high_open=True))
        if self.criterion is not None:
            _wrap(check_choice, ("criterion",), self.criterion, "criterion", CRITERIA)
        if self.max_terms is not None:
            object.__setattr__(self, "max_terms", _wrap(check_int, ("max_terms",), self.max_terms, "max_terms", low=1,
                                                        high=high))
        if self.n_terms is not None and self.tol is not None:
            raise SpecError("give n_terms or tol, not both", ("tol",))
        if self.n_terms is not None and self.max_terms is not None:  # FROLS refuses it: said here, not by each cell
            raise SpecError("max_terms caps tol and criterion stopping; with n_terms leave it out", ("max_terms",))
        missing = [str(t) for t in inc if t not in space]
        if missing:
            raise SpecError(f"included terms {missing} are not among the candidates", ("include",))
        for k in ("n_terms", "max_terms"):  # FROLS refuses it: said here, not by each cell
            n = getattr(self, k)
            if n is not None and n < len(inc):
                raise SpecError(f"{k} = {n} is fewer than the {len(inc)} included terms {[str(t) for t in inc]}",
                                (k,))
        object.__setattr__(self, "include", tuple(str(t) for t in inc))

    @property
    def made(self) -> bool:
        """True when FROLS makes the structure."""
        return self.candidates is not None

    def to_dict(self) -> dict:
        """Canonical form: the name and :meth:`content` (which leaves the name out).

        Returns
        -------
        dict
            ``{"name": …, **content()}``.
        """
        return {"name": self.name, **self.content()}

    def content(self) -> dict:
        """What determines the structure (the part a cell's key hashes).

        Returns
        -------
        dict
            ``{"terms": [...]}`` for given terms, else the candidates and FROLS's options (``n_terms``, ``tol``,
            ``criterion``, ``max_terms``, ``include``).
        """
        if self.terms is not None:
            return {"terms": list(self.terms)}
        return {"candidates": _thaw(self.candidates), "n_terms": self.n_terms, "tol": self.tol,
                "criterion": self.criterion, "max_terms": self.max_terms, "include": list(self.include)}

    def identity(self) -> dict:
        """:meth:`content` with its terms (given or included) as a set, in the candidates' order
        (:meth:`graybox.Term.sort_key`): two structures of one identity are one fit, its θ in another order.
        The content keeps the order given (θ's, and the cells' keys of stores written before).

        Returns
        -------
        dict
            :meth:`content` with ``terms`` (or ``include``) sorted.
        """
        c = self.content()
        key = "terms" if self.terms is not None else "include"
        c[key] = sorted(c[key], key=lambda t: Term.sort_key(parse_term(t)))
        return c

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape


# --------------------------------------------------------------------------------------------
# variants: estimator, constraints, λ set, decision maker, options
# --------------------------------------------------------------------------------------------
def _opt_int(low: int | None = None, high: int | None = None):
    return lambda v, name: check_int(v, name, low=low, high=high)


def _opt_real(low: float | None = None, high: float | None = None, low_open: bool = False, high_open: bool = False):
    return lambda v, name: check_real(v, name, low=low, high=high, low_open=low_open, high_open=high_open)


def _opt_choice(*choices: str):
    return lambda v, name: check_choice(v, name, choices)


def _opt_reference(v: object, name: str) -> str | float:
    if isinstance(v, str):
        return check_choice(v, name, (FREE_SIGMA_Y, "ls", "els"))  # "free": the estimators' default
    return check_real(v, name)


def _opt_stall(v: object, name: str) -> int | None:
    # 0: never stop early (TOML has no null); a bool is no count (False == 0 passed as 0)
    return None if v is None or (not isinstance(v, bool) and v == 0) else check_int(v, name, low=1)


def _opt_margin(v: object, name: str) -> str | float:
    """A stability margin in a spec: "auto" (the estimators' default), "none" (the paper's problem, no margin:
    TOML has no null) or a number in [0, 1)."""
    if isinstance(v, str):
        return check_choice(v, name, ("auto", "none"))
    return check_real(v, name, low=0.0, high=1.0, high_open=True)


_GA_FIELDS = {
    "population": _opt_int(4), "generations": _opt_int(1), "stall": _opt_stall,
    "crossover_prob": _opt_real(0, 1), "crossover_ratio": _opt_real(0, low_open=True),
    "mutation_prob": _opt_real(0, 1), "mutation_scale": _opt_real(0), "elite": _opt_int(0),
    "random_samples": _opt_int(1), "selective_pressure": _opt_real(1, 2),
}
#: Options each estimator takes (validators); they are passed to the graybox function.
OPTIONS: dict[str, dict[str, Any]] = {
    "ls": {},
    "els": {"noise": _opt_int(0), "max_iter": _opt_int(1), "tol": _opt_real(0, low_open=True),
            "relaxation": _opt_real(0, 1, low_open=True)},
    "cls": {"solver": _opt_choice("clarabel", "osqp", "closed"), "reference": _opt_reference},
    "pe": {"solver": _opt_choice("clarabel", "osqp", "closed"), "weights": _opt_choice("mse", "sum"),
           "reference": _opt_reference},
    "se-ga": {**_GA_FIELDS, "theta0": _opt_choice("ls", "none"), "margin": _opt_margin},
    "se-gradient": {"max_nfev": _opt_int(1), "tol": _opt_real(0, low_open=True),
                    "solver": _opt_choice("trf", "dogbox", "lm"), "margin": _opt_margin},
    "se-dsf": {"band": _opt_real(0, low_open=True), "max_iter": _opt_int(1), "tol": _opt_real(0, low_open=True),
               "margin": _opt_margin},
    # neural_narx's training options (its seed is the grid's, its name the cell's)
    "neural": {"ny": _opt_int(0), "nu": _opt_int(1), "ne": _opt_int(0), "hidden": _opt_int(1), "epochs": _opt_int(1),
               "sim_epochs": _opt_int(0), "weight_decay": _opt_real(0), "holdout": _opt_real(0, 0.5, high_open=True),
               "patience": _opt_int(1)},
}

_CONSTRAINT_KEYS = {
    "equality": ("type", "curve", "sigma_y"),
    "points": ("type",),
    "band": ("type", "b", "form", "min_denominator"),
    "gain": ("type", "lower", "upper", "ubar_range", "n", "min_denominator"),
    "clusters": ("type", "bounds"),
}


def _bound(v: object, path: tuple, name: str) -> float | None:
    return None if v is None else _wrap(check_real, path, v, name)


def _gain_bound(v: object, path: tuple, name: str) -> float | list[float | None] | dict[str, float | None] | None:
    """A gain bound: a number (every input), one number or None per input (several inputs), or a table of them by
    input name ({speed = 0.0})."""
    if isinstance(v, Mapping):
        if not v:
            raise SpecError(f"{name} by input name needs at least one input's bound, got an empty table", path)
        return {str(k): _bound(x, path + (k,), name) for k, x in v.items()}
    if isinstance(v, Sequence) and not isinstance(v, str):
        if not v:
            raise SpecError(f"{name} must be a number or one entry per input, got an empty list", path)
        return [_bound(x, path + (i,), name) for i, x in enumerate(v)]
    return _bound(v, path, name)


def canonical_constraint(c: object, path: tuple = ()) -> dict:
    """The canonical dict of one constraint given as a TOML-style table ``{"type": …, …}``."""
    if not isinstance(c, Mapping):
        raise SpecTypeError(f"a constraint is a table such as {{type = \"band\", b = 0.175}}, got {c!r}", path)
    kind = c.get("type")
    if kind is not None and not isinstance(kind, str):
        raise SpecTypeError(f"a constraint's type must be a string, one of {', '.join(CONSTRAINT_TYPES)}; got "
                            f"{kind!r} ({type(kind).__name__})", path + ("type",))
    if kind not in _CONSTRAINT_TYPES_KEYS:
        raise SpecError(f"unknown constraint type {kind!r}; known: {', '.join(CONSTRAINT_TYPES)}", path + ("type",))
    _check_keys(c, _CONSTRAINT_KEYS[kind], f"a {kind!r} constraint", path)
    if kind == "equality":
        curve = c.get("curve", "fit")
        if isinstance(curve, str):
            _wrap(check_choice, path + ("curve",), curve, "curve", ("fit", "dataset"))
        elif isinstance(curve, Sequence) and curve:
            curve = [_wrap(check_real, path + ("curve",), v, "curve coefficient") for v in curve]
        else:
            # an empty list is a wrong value; anything but text or a list a wrong type
            raise (SpecError if isinstance(curve, Sequence) else SpecTypeError)(
                "curve must be \"fit\" (fitted to the data set's static points), \"dataset\" (the data set's own "
                f"static curve) or a list of ascending polynomial coefficients, got {curve!r}", path + ("curve",))
        sy = c.get("sigma_y")
        if isinstance(sy, str) and sy != FREE_SIGMA_Y:
            raise SpecError(f"sigma_y must be a number or \"{FREE_SIGMA_Y}\" (estimated, the default), got {sy!r}",
                            path + ("sigma_y",))
        if sy != FREE_SIGMA_Y:
            sy = _bound(sy, path + ("sigma_y",), "sigma_y")
            if sy is not None and sy >= 1.0:  # as CurveEquality: read here, not in every cell that would fail
                raise SpecError(f"sigma_y must be < 1 (1 − Σ*_y is eq. (22)'s static denominator; at 1 or above "
                                f"no model meeting it has a stable equilibrium), got {sy!r}", path + ("sigma_y",))
        return {"type": kind, "curve": curve, "sigma_y": sy}
    if kind == "points":
        return {"type": kind}
    if kind == "band":
        # no b: each static point's own uncertainty (carried by the data set's static points)
        b = None if c.get("b") is None else _wrap(check_real, path + ("b",), c["b"], "b", low=0, low_open=True)
        form = _wrap(check_choice, path + ("form",), c.get("form", "exact"), "form", ("exact", "residual"))
        md = _wrap(check_min_denominator, path + ("min_denominator",), c.get("min_denominator", "auto"),
                   "min_denominator", 1.0)
        return {"type": kind, "b": b, "form": form, "min_denominator": md}
    if kind == "gain":
        lo = _gain_bound(c.get("lower"), path + ("lower",), "lower")
        hi = _gain_bound(c.get("upper"), path + ("upper",), "upper")
        if lo is None and hi is None:
            raise SpecError("gain bounds need lower or upper", path)
        rng = c.get("ubar_range")
        if isinstance(rng, Mapping):  # by input name: a table of [low, high]
            for k, r in rng.items():
                if isinstance(r, str) or not isinstance(r, Sequence) or len(r) != 2:  # no list: a wrong type
                    raise (SpecError if isinstance(r, Sequence) and not isinstance(r, str) else SpecTypeError)(
                        f"ubar_range of input {k!r} must be [low, high], got {r!r}", path + ("ubar_range", k))
            rng = {k: [_wrap(check_real, path + ("ubar_range", k), v, "ubar_range") for v in r] for k, r in rng.items()}
        elif rng is not None and (isinstance(rng, str) or not isinstance(rng, Sequence)):
            raise SpecTypeError(f"ubar_range must be a list [low, high], one [low, high] per input or a table of "
                                f"[low, high] by input name, got {rng!r}",
                                path + ("ubar_range",))
        if rng is not None and not isinstance(rng, Mapping):
            box = isinstance(rng, Sequence) and rng and all(isinstance(r, Sequence) and not isinstance(r, str)
                                                            for r in rng)
            if box:  # several inputs: one [low, high] per input
                if not all(len(r) == 2 for r in rng):
                    raise SpecError(f"ubar_range must be [low, high] or one [low, high] per input, got {rng!r}",
                                    path + ("ubar_range",))
                rng = [[_wrap(check_real, path + ("ubar_range",), v, "ubar_range") for v in r] for r in rng]
            else:
                if not (isinstance(rng, Sequence) and len(rng) == 2):
                    raise SpecError(f"ubar_range must be [low, high], got {rng!r}", path + ("ubar_range",))
                rng = [_wrap(check_real, path + ("ubar_range",), v, "ubar_range") for v in rng]
        n = _wrap(check_int, path + ("n",), c.get("n", 25), "n", low=1)
        md = _wrap(check_min_denominator, path + ("min_denominator",), c.get("min_denominator", "auto"),
                   "min_denominator", None)
        out = {"type": kind, "lower": lo, "upper": hi, "ubar_range": rng, "n": n, "min_denominator": md}
        _wrap(build_constraint, path, out)  # the object's own checks (e.g. lower <= upper)
        return out
    bounds = c.get("bounds")
    if not isinstance(bounds, Mapping):
        raise SpecTypeError("cluster bounds need bounds = {Sy = {upper = 0.999}, …}", path + ("bounds",))
    if not bounds:
        raise SpecError("cluster bounds need bounds = {Sy = {upper = 0.999}, …}", path + ("bounds",))
    clean = {}
    for name, b in bounds.items():
        p = path + ("bounds", name)
        if not str(name).strip().startswith(("Σ", "S")):  # a key (3, a TOML "3") only fails once a structure reads it
            raise SpecError(f"cluster bounds name their clusters (\"Sy\", \"Su^2\", \"Σy·speed\", …), got {name!r}", p)
        if isinstance(b, Mapping):
            _check_keys(b, ("lower", "upper"), f"the bounds of cluster {name!r}", p)
            lo, hi = b.get("lower"), b.get("upper")
        elif isinstance(b, Sequence) and not isinstance(b, str) and len(b) == 2:
            lo, hi = b
        else:
            raise SpecTypeError(f"bounds of cluster {name!r} must be {{lower = …, upper = …}}", p)
        clean[str(name)] = [_bound(lo, p, "lower"), _bound(hi, p, "upper")]
    out = {"type": kind, "bounds": clean}
    _wrap(build_constraint, path, out)
    return out


_CONSTRAINT_TYPES_KEYS = tuple(CONSTRAINT_TYPES)


def constraint_from_object(obj: object, path: tuple = ()) -> list[dict]:
    """Canonical dicts of graybox constraint objects (``a & b`` flattened), for grids written in Python."""
    if isinstance(obj, Mapping):
        return [canonical_constraint(obj, path)]
    if not isinstance(obj, (gb.StaticBand, gb.CurveEquality, gb.PassesThrough, gb.GainBounds, gb.ClusterBounds)):
        members = list(obj) if hasattr(obj, "__iter__") and not isinstance(obj, (str, bytes)) else None
        if members is None or (len(members) == 1 and members[0] is obj):
            if not isinstance(obj, gb.UserConstraint):
                raise SpecTypeError(f"{obj!r} ({type(obj).__name__}) is not a constraint: give StaticBand, "
                                    "CurveEquality, PassesThrough, GainBounds or ClusterBounds objects, or their tables",
                                    path)
            raise SpecTypeError(f"{obj!r} cannot be part of a grid: a grid stores its constraints as data "
                                "(equality, points, band, gain, clusters); a UserConstraint's function cannot be "
                                "stored or hashed", path)
        return [d for m in members for d in constraint_from_object(m, path)]
    if isinstance(obj, gb.CurveEquality):
        c = obj.curve
        if isinstance(c, gb.StaticSurface):
            # a table's curve is ascending coefficients of one input; a surface's are by exponent (1 + 3ū² is
            # [1, 3] at exponents 0 and 2, which as a curve read 1 + 3ū)
            if c.n_inputs != 1:
                raise SpecError(f"{obj.describe()}: a grid's equality takes a curve of one input as its coefficients; "
                                f"{c.name} is a surface in {c.n_inputs} inputs, which a table cannot hold: use "
                                "curve = \"fit\" (the surface fitted to the data set's static points) or \"dataset\"",
                                path)
            coef = np.zeros(max(e[0] for e in c.exponents) + 1)
            for e, v in zip(c.exponents, c.coefficients):
                coef[e[0]] += float(v)
        else:
            coef = c.coefficients
        return [canonical_constraint({"type": "equality", "curve": [float(v) for v in coef],
                                      "sigma_y": obj.sigma_y}, path)]
    if getattr(obj, "points", None) is not None:
        raise SpecError(f"{obj.describe()}: in a grid, constraints use the data set's static points; "
                        "give the points as the data set's static file instead", path)
    if isinstance(obj, gb.PassesThrough):
        return [{"type": "points"}]
    if isinstance(obj, gb.StaticBand):
        return [canonical_constraint({"type": "band", "b": obj.b, "form": obj.form,
                                      "min_denominator": obj.min_denominator}, path)]
    if isinstance(obj, gb.GainBounds):
        if obj.reference is not None:
            raise SpecError(f"{obj.describe()}: a grid's gain bounds take the data set's reference (its static "
                            "points); a reference function cannot be stored", path)
        def plain(v):  # tuples (per input, a box) as lists, bounds by input name as a table
            if isinstance(v, Mapping):
                return {k: plain(x) for k, x in v.items()}
            return [plain(x) for x in v] if isinstance(v, (list, tuple)) else v
        return [canonical_constraint({"type": "gain", "lower": plain(obj.lower), "upper": plain(obj.upper),
                                      "ubar_range": plain(obj.ubar_range) if obj.ubar_range else None,
                                      "n": obj.n, "min_denominator": obj.min_denominator}, path)]
    bounds = {}
    for k, (lo, hi) in obj.bounds.items():
        if not isinstance(k, str):
            raise SpecError(f"cluster bounds in a grid name their clusters (\"Sy\", \"Su^2\", …), got key {k!r}", path)
        bounds[k] = [lo, hi]
    return [canonical_constraint({"type": "clusters", "bounds": bounds}, path)]


def _is_constraint_object(obj: object) -> bool:
    return callable(getattr(obj, "affine", None)) and callable(getattr(obj, "describe", None))


def constraint_entries(raw: Any) -> Any:
    """The constraints as given, one entry per table or object: () for None, a one-item list for a
    single table or graybox constraint object, anything else as it is (a list, a generator, …)."""
    if raw is None:
        return ()
    if isinstance(raw, Mapping) or _is_constraint_object(raw):
        return [raw]
    return raw


def build_constraint(d: Mapping, *, curve: gb.StaticCurve | None = None) -> Any:
    """The graybox constraint object of a canonical dict (``curve``: the resolved curve of an equality)."""
    kind = d["type"]
    if kind == "equality":
        if curve is None:
            if isinstance(d["curve"], str):
                raise ValueError("an equality's curve is resolved against the data set when the cell runs")
            curve = gb.StaticCurve.polynomial(d["curve"], name="given static curve")
        return gb.CurveEquality(curve, sigma_y=d["sigma_y"])
    if kind == "points":
        return gb.PassesThrough()
    if kind == "band":
        return gb.StaticBand(d["b"], form=d["form"], min_denominator=d["min_denominator"])
    if kind == "gain":
        rng = d["ubar_range"]
        if isinstance(rng, Mapping):
            rng = {k: tuple(r) for k, r in rng.items()}
        elif rng is not None:
            rng = tuple(tuple(r) for r in rng) if np.ndim(rng) == 2 else tuple(rng)
        lo, hi = (tuple(v) if isinstance(v, Sequence) else v for v in (d["lower"], d["upper"]))
        return gb.GainBounds(lo, hi, ubar_range=rng, n=d["n"], min_denominator=d["min_denominator"])
    return gb.ClusterBounds({k: tuple(v) for k, v in d["bounds"].items()})


def _lambdas(v: object, path: tuple) -> list[float] | None:
    if v is None:
        return None
    if isinstance(v, Mapping):
        _check_keys(v, ("logspace", "linspace"), "lambdas", path)
        if len(v) != 1:
            raise SpecError("lambdas: give one of logspace = [a, b, n] or linspace = [a, b, n]", path)
        (kind, args), = v.items()
        if not (isinstance(args, Sequence) and len(args) == 3):
            raise SpecError(f"{kind} needs [start, stop, count], got {args!r}", path + (kind,))
        a = _wrap(check_real, path + (kind,), args[0], "start")
        b = _wrap(check_real, path + (kind,), args[1], "stop")
        n = _wrap(check_count, path + (kind,), args[2], "count", low=1)  # (numpy's refusal named no key)
        if kind == "logspace":  # 10**400 overflowed with numpy's warning, 10**-400 read as λ1 = 0
            for name, e in (("start", a), ("stop", b)):
                if not -307 <= e <= 308:
                    raise SpecError(f"{name} = {e!r}: 10**{name} is beyond the float range (exponents in "
                                    "[-307, 308]; λ1 = 10**x must lie in (0, 1])", path + (kind,))
        lam = np.logspace(a, b, n) if kind == "logspace" else np.linspace(a, b, n)
    else:
        lam = v
    arr = _wrap(check_lambdas, path, lam)
    return [float(x) for x in arr]


@dataclass(frozen=True, eq=False)
class DecisionRule:
    """How a cell picks one member of a Pareto set.

    Parameters
    ----------
    rule : {"dsf", "min_correlation", "min_jsf"}
        D_SF (eq. (14): smallest J_S with J_SF in B = [0, band]); the minimal-correlation rule
        (:func:`graybox.decide_min_correlation`); or the smallest J_SF.
    band : float, optional
        D_SF's band (output units²); default: the data set's band.
    fallback : {"min_jsf"}, optional
        D_SF only: what to take when no member lies in the band: the member whose J_SF is nearest
        B = [0, band], the smallest (as :func:`graybox.decide_dsf` takes it; default: the cell is
        ``infeasible``, and its members are still stored).
    output : {"free-run", "one-step"}
        Minimal correlation only: which output the residuals are correlated with.
    """

    rule: str = "dsf"
    band: float | None = None
    fallback: str | None = None
    output: str = "free-run"

    def __post_init__(self) -> None:
        _wrap(check_choice, ("rule",), self.rule, "rule", DECISION_RULES)
        if self.rule != "dsf":
            for k in ("band", "fallback"):
                if getattr(self, k) is not None:
                    raise SpecError(f"{k} applies to rule = \"dsf\" only", (k,))
        if self.rule != "min_correlation" and self.output != "free-run":
            raise SpecError("output applies to rule = \"min_correlation\" only", ("output",))
        if self.band is not None:
            object.__setattr__(self, "band", _wrap(check_real, ("band",), self.band, "band", low=0, low_open=True))
        if self.fallback is not None:
            _wrap(check_choice, ("fallback",), self.fallback, "fallback", ("min_jsf",))
        _wrap(check_choice, ("output",), self.output, "output", ("free-run", "one-step"))

    def to_dict(self) -> dict:
        """Canonical form.

        Returns
        -------
        dict
            ``rule``, and for ``"dsf"`` its ``band`` (output units², or None) and ``fallback``, for
            ``"min_correlation"`` its ``output``.
        """
        if self.rule == "dsf":
            return {"rule": "dsf", "band": self.band, "fallback": self.fallback}
        if self.rule == "min_correlation":
            return {"rule": self.rule, "output": self.output}
        return {"rule": self.rule}


@dataclass(frozen=True, eq=False)
class Variant:
    """One way of estimating: estimator, constraints, λ set, decision maker and options.

    Parameters
    ----------
    name : str
        Label in the results.
    estimator : {"ls", "els", "cls", "pe", "se-ga", "se-gradient", "se-dsf", "neural"}
        Least squares, extended least squares (:func:`graybox.els`), constrained least squares
        (:func:`graybox.cls`), the PE Pareto set (:func:`graybox.pe_pareto`), the SE Pareto set
        by GA or gradient (:func:`graybox.se_pareto`), the D_SF model solved directly
        (:func:`graybox.se_dsf`: one model; its band is ``options["band"]``, default the data
        set's; a band it cannot reach gives the smallest J_SF reached, ``in_band`` False), the
        neural NARX baseline (:func:`graybox.neural_narx`; its lags default to the structure's
        largest y and u lags).
    constraints : constraint object(s) or sequence of tables, optional
        For cls and pe: graybox constraint objects (``gb.StaticBand(0.175) & gb.GainBounds(lower=0)``)
        or TOML-style tables ``{"type": "band", "b": 0.175}``; types: equality (eq. (22); its
        ``curve`` is "fit" — the polynomial the structure's numerator carries, fitted to the data
        set's static points, with exactly the ū powers of its numerator clusters —, "dataset" or
        coefficients), points, band, gain, clusters.
    lambdas : sequence of float or mapping, optional
        λ1 values in (0, 1] of a Pareto estimator (se-dsf: of the coarse sweep that finds its
        starts), or ``{"logspace": [a, b, n]}``; default: the estimator's own (the paper's 100).
    decision : DecisionRule or mapping, optional
        Pareto estimators only; default D_SF with the data set's band.
    options : mapping, optional
        Keyword options of the estimator (e.g. ``{"solver": "closed"}`` for pe,
        ``{"max_nfev": 20}`` for se-gradient, GAOptions fields for se-ga, ``band``, ``max_iter``
        and ``tol`` for se-dsf, :func:`graybox.neural_narx`'s ``ny``, ``nu``, ``ne``, ``hidden``, ``epochs``,
        ``sim_epochs``, ``weight_decay``, ``holdout`` and ``patience`` for neural). The three SE estimators take
        ``margin``: ``"auto"`` (default, as :func:`graybox.se_pareto`), ``"none"`` (the paper's problem, no margin) or
        a number in [0, 1).
    """

    name: str
    estimator: str
    constraints: Any = ()
    lambdas: Any = None
    decision: Any = None
    options: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        _name(self.name, ())
        est = _wrap(check_choice, ("estimator",), self.estimator, "estimator", ESTIMATORS)
        # constraints
        raw = constraint_entries(self.constraints)
        if not isinstance(raw, Sequence) or isinstance(raw, str):
            raise SpecTypeError("constraints must be a list of tables or graybox constraint objects", ("constraints",))
        cons: list[dict] = []
        for i, c in enumerate(raw):
            cons += constraint_from_object(c, ("constraints", i))
        if cons and est not in CONSTRAINED_ESTIMATORS:
            raise SpecError(f"estimator {est!r} takes no constraints (only {', '.join(CONSTRAINED_ESTIMATORS)} do)",
                            ("constraints",))
        if est == "cls" and not cons:
            raise SpecError("cls needs at least one constraint (without any it is plain least squares: use ls)",
                            ("constraints",))
        kinds = [c["type"] for c in cons]
        if kinds.count("equality") > 1:
            raise SpecError("at most one equality (22) constraint per variant", ("constraints",))
        object.__setattr__(self, "constraints", _freeze(cons))
        # λ set
        if self.lambdas is not None and est not in LAMBDA_ESTIMATORS:
            raise SpecError(f"estimator {est!r} gives one model: lambdas apply to {', '.join(LAMBDA_ESTIMATORS)}",
                            ("lambdas",))
        lam = _lambdas(self.lambdas, ("lambdas",))
        object.__setattr__(self, "lambdas", None if lam is None else tuple(lam))
        # decision maker
        dec = self.decision
        if dec is not None and est not in PARETO_ESTIMATORS:
            hint = " (se-dsf solves D_SF itself: give its band as options = {band = ...})" if est == "se-dsf" else ""
            raise SpecError(f"estimator {est!r} gives one model: a decision maker applies to "
                            f"{', '.join(PARETO_ESTIMATORS)}{hint}", ("decision",))
        if est in PARETO_ESTIMATORS:
            if dec is None:
                dec = DecisionRule()
            elif isinstance(dec, Mapping):
                _check_keys(dec, ("rule", "band", "fallback", "output"), "decision", ("decision",))
                try:
                    dec = DecisionRule(**dec)
                except SpecError as e:
                    raise e.within("decision") from None
            elif not isinstance(dec, DecisionRule):
                raise SpecTypeError(f"decision must be a DecisionRule or a table, got {type(dec).__name__}",
                                    ("decision",))
        object.__setattr__(self, "decision", dec)
        # options
        opts = self.options if self.options is not None else {}
        known = OPTIONS[est]
        if not isinstance(opts, Mapping):
            raise SpecTypeError(f"options must be a table, got {type(opts).__name__}", ("options",))
        clean = {}
        for k, v in opts.items():
            if k not in known:
                # a grid gives the stochastic estimators their seeds itself (one cell per seed)
                hint = ("; the grid's seeds = [0, 1, …] at the top of the spec give a stochastic estimator its seeds, "
                        "one cell each" if k in ("seed", "seeds") else "")
                raise SpecError(f"unknown option {k!r} for estimator {est!r}; known: {', '.join(known) or '(none)'}"
                                + hint, ("options", k))
            clean[k] = _wrap(known[k], ("options", k), v, k)
        if est == "se-ga":  # GAOptions' checks across its fields (elite < population): here, not by each cell
            _wrap(lambda: gb.GAOptions(**{k: v for k, v in clean.items() if k in _GA_FIELDS}), ("options",))
        if clean.get("solver") == "closed":  # the closed form solves equalities only: said here, not by each cell
            rows = [c["type"] for c in cons if c["type"] in ("band", "gain")
                    or (c["type"] == "clusters" and any(lo is None or lo != hi for lo, hi in c["bounds"].values()))]
            if rows:
                raise SpecError(f"solver \"closed\" handles equality constraints only (equality, points, clusters of "
                                f"equal bounds); the {rows[0]!r} constraint has inequality rows: use solver = "
                                "\"clarabel\" or \"osqp\"", ("options", "solver"))
        if "patience" in clean and not clean.get("holdout"):  # said here, not by each cell's failure
            raise SpecError("patience applies to early stopping only: give holdout > 0 with it",
                            ("options", "patience"))
        if "reference" in clean and "equality" not in kinds:
            raise SpecError("reference (where Σ*_y of eq. (22) comes from) needs an equality constraint",
                            ("options", "reference"))
        object.__setattr__(self, "options", FrozenDict(sorted(clean.items())))

    @property
    def stochastic(self) -> bool:
        """Whether the seed matters (se-ga, neural)."""
        return self.estimator in STOCHASTIC_ESTIMATORS

    def to_dict(self) -> dict:
        """Canonical form (name included).

        Returns
        -------
        dict
            ``{"name": …, **content()}``.
        """
        return {"name": self.name, **self.content()}

    def content(self) -> dict:
        """What determines the estimate (the part a cell's key hashes).

        Returns
        -------
        dict
            ``estimator``, ``constraints``, ``lambdas``, ``decision`` (its canonical form, or None) and ``options``.
        """
        options = dict(self.options)
        if (self.estimator in ("cls", "pe") and "reference" not in options
                and any(c["type"] == "equality" and c.get("sigma_y") is None for c in self.constraints)):
            # the estimators' default Σ*_y (reference="free") said in the key: it was "ls" before, within the same
            # graybox version, and a store's cells estimated with that default must not be reused as this one's
            options["reference"] = FREE_SIGMA_Y
        return {"estimator": self.estimator, "constraints": _thaw(self.constraints),
                "lambdas": None if self.lambdas is None else list(self.lambdas),
                "decision": None if self.decision is None else self.decision.to_dict(),
                "options": options}

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape


def _default_options(est: str) -> dict[str, Any]:
    """The options of estimator ``est`` a variant may give (:data:`OPTIONS`) at the values its cells take when they are
    left out: the graybox function's defaults (GAOptions' for se-ga's GA). A neural cell's lags default to the
    structure's, not to neural_narx's, and are left out."""
    import dataclasses
    import inspect

    if est == "ls":
        return {}
    fn = {"els": gb.els, "cls": gb.cls, "pe": gb.pe_pareto, "se-ga": gb.se_pareto, "se-gradient": gb.se_pareto,
          "se-dsf": gb.se_dsf, "neural": gb.neural_narx}[est]
    given = {k: p.default for k, p in inspect.signature(fn).parameters.items() if p.default is not p.empty}
    if est == "se-ga":
        given.update({f.name: f.default for f in dataclasses.fields(gb.GAOptions)})
    # a None that stands for a value: els's noise is the structure's noise terms, else ne = DEFAULT_NE (a grid's
    # structures carry none); se_pareto's gradient max_nfev and tol are gradient_front's (its solver None is
    # "auto", which no option spells: "trf" is not it)
    if est == "els":
        given["noise"] = DEFAULT_NE
    if est == "se-gradient":
        front = inspect.signature(gradient_front).parameters
        given.update({k: front[k].default for k in ("max_nfev", "tol")})
    skip = ("ny", "nu") if est == "neural" else ()
    return {k: given[k] for k in OPTIONS[est] if k in given and k not in skip}


def _meaning(variant_content: Mapping[str, Any]) -> dict:
    """A variant's content with the options it gives at their defaults left out: what it estimates (two variants of the
    same meaning run the same cells under two keys)."""
    out = dict(variant_content)
    defaults = _default_options(out["estimator"])
    out["options"] = {k: v for k, v in out["options"].items()
                      if not (k in defaults and type(v) is not bool and v == defaults[k])}
    return out


# --------------------------------------------------------------------------------------------
# cells and the grid
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Cell:
    """One (data, structure, variant, seed) of a grid: everything a worker needs except the data.

    Attributes
    ----------
    index : int
        Position in the grid's cell order (data, then structure, then variant, then seed).
    key : str
        Hash of the data's content, the structure, the variant, the seed and graybox's version; of the
        band when the variant reads it (``reads_band``); and of the static points' uncertainty when
        the variant's band constraint takes it and a band in the key does not say it (per-point δ, or a δ
        other than √band).
    data, structure, variant : str
        Names.
    seed : int or None
        The seed (None for deterministic estimators, which run once).
    data_hash : str
        Content hash of the data set (workers look the data up by it).
    band : float or None
        The resolved J_SF band of the data set (output units²).
    structure_spec, variant_spec : mapping
        Canonical contents (see :meth:`StructureSpec.content`, :meth:`Variant.content`).
    version : str
        graybox version the key was made for.
    """

    index: int
    key: str
    data: str
    structure: str
    variant: str
    seed: int | None
    data_hash: str
    band: float | None
    structure_spec: Mapping[str, Any]
    variant_spec: Mapping[str, Any]
    version: str

    def __post_init__(self) -> None:
        check_fields(self)

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape


def _names_a_cluster(structure: StructureSpec, name: str) -> bool:
    """Does ``name`` name a cluster of a given structure, read as a curve's clusters or a surface's (the data set
    decides which: a structure of one input on data of several has a surface's)? An ambiguous name is one."""
    st = gb.parse_structure(list(structure.terms or ()))
    readings = [lambda: gb.surface_cluster_map(st, input_names=st.input_names)] if st.input_names else []
    if len(st.input_names) <= 1:
        readings.append(lambda: gb.cluster_map(st))
    for read in readings:
        try:
            read().index(name)
            return True
        except ValueError as e:
            if not str(e).startswith("no cluster"):  # a name that fits several clusters names clusters
                return True
    return False


def _check_cluster_names(structures: Sequence[StructureSpec], variants: Sequence["Variant"]) -> None:
    """A cluster bound naming a cluster no structure of the grid has (Sz) is refused with the spec, where every
    structure is given (terms): each of its cells would fail with "no cluster 'Sz'". With a structure FROLS makes
    the clusters are known only once it is made, and a name some given structures have and others lack is a cross
    the grid may mean: those cells fail with the message, as before."""
    if any(s.terms is None for s in structures):
        return
    for i, v in enumerate(variants):
        for j, c in enumerate(v.constraints):
            if c["type"] != "clusters":
                continue
            for name in c["bounds"]:
                if not any(_names_a_cluster(s, name) for s in structures):
                    have = "; ".join(f"{s.name!r}: {', '.join(_cluster_names(s))}" for s in structures)
                    raise SpecError(f"cluster {name!r} of variant {v.name!r} is a cluster of no structure of the grid "
                                    f"(their clusters: {have})", ("variants", i, "constraints", j, "bounds", name))


def _cluster_names(structure: StructureSpec) -> list[str]:
    """The clusters of a given structure, as its cells name them (a curve's, or a surface's with several inputs)."""
    st = gb.parse_structure(list(structure.terms or ()))
    return (gb.cluster_map(st) if len(st.input_names) <= 1 else gb.surface_cluster_map(st)).names


@dataclass(frozen=True, eq=False)
class Grid:
    """Data sets × structures × variants × seeds.

    Deterministic estimators (ls, els, cls, pe, se-gradient) run once per (data, structure,
    variant); the stochastic ones (se-ga, neural) once per seed as well.

    Parameters
    ----------
    data : sequence of DataSpec
    structures : sequence of StructureSpec
    variants : sequence of Variant
    seeds : sequence of int
        Seeds of the stochastic estimators (default ``(0,)``).
    name : str
        The grid's name (stored with its results).
    base_dir : str, optional
        Folder that relative CSV paths are resolved against (a TOML spec's own folder).
    """

    data: Sequence[DataSpec]
    structures: Sequence[StructureSpec]
    variants: Sequence[Variant]
    seeds: Sequence[int] = (0,)
    name: str = "grid"
    base_dir: str | None = None

    def __post_init__(self) -> None:
        _name(self.name, ())
        if self.base_dir is not None:
            check_path(self.base_dir, "base_dir")
        for what, cls_, items in (("data", DataSpec, self.data), ("structures", StructureSpec, self.structures),
                                  ("variants", Variant, self.variants)):
            if isinstance(items, (str, Mapping)) or not isinstance(items, Sequence | tuple):
                raise SpecTypeError(f"a grid needs a non-empty list of {what}, got {type(items).__name__}", (what,))
            if not items:
                raise SpecError(f"a grid needs a non-empty list of {what}", (what,))
            for i, it in enumerate(items):
                if not isinstance(it, cls_):
                    raise SpecTypeError(f"{what} must hold {cls_.__name__} objects, got {type(it).__name__}", (what, i))
            names = [it.name for it in items]
            dup = sorted({n for n in names if names.count(n) > 1})
            if dup:
                raise SpecError(f"duplicated {what} names {dup}: names identify rows in the results",
                                (what, names.index(dup[0], names.index(dup[0]) + 1)))
            object.__setattr__(self, what, tuple(items))
        if isinstance(self.seeds, (numbers.Number, np.generic)):  # one seed, or a wrong scalar checked below
            object.__setattr__(self, "seeds", (self.seeds,))
        # below 2**63: the store keeps a seed as an SQLite INTEGER (a larger one failed the run with an OverflowError)
        seeds = [_wrap(check_int, ("seeds", i), s, "seed", low=0, high=2 ** 63 - 1) for i, s in enumerate(self.seeds)]
        if not seeds or len(set(seeds)) != len(seeds):
            raise SpecError("seeds must be a non-empty list of distinct integers >= 0", ("seeds",))
        object.__setattr__(self, "seeds", tuple(seeds))
        for kind, items in (("structures", self.structures), ("variants", self.variants)):
            seen: dict[str, tuple[str, str]] = {}
            for i, it in enumerate(items):
                raw = canonical_json(it.content())
                # a variant's options written out at the estimator's defaults estimate as those left out
                c = canonical_json(_meaning(it.content())) if kind == "variants" else raw
                if c in seen:
                    other, other_raw = seen[c]
                    why = "" if raw == other_raw else ", the options one writes out being the estimator's defaults"
                    raise SpecError(f"{kind[:-1]} {it.name!r} is identical to {other!r} (same content, same "
                                    f"cells{why})", (kind, i))
                seen[c] = (it.name, raw)
                if kind == "structures":
                    # a structure is its set of terms: ["y(k-1)", "u(k-1)"] and ["u(k-1)", "y(k-1)"] were two
                    # structures, two cells of one fit and two rows in the store and the report
                    key = "\0" + canonical_json(it.identity())
                    if key in seen:
                        which = "terms" if it.terms is not None else "candidates, rule and included terms"
                        raise SpecError(f"structure {it.name!r} has the same {which} as {seen[key][0]!r} in another "
                                        "order: one fit (its θ in another order), the same cells; list it once",
                                        (kind, i))
                    seen[key] = (it.name, raw)
        _check_cluster_names(self.structures, self.variants)
        # what a variant reads from every data set, refused here rather than as a failed cell in every row
        for i, v in enumerate(self.variants):
            nob = [d.name for d in self.data if d.band is None and not _column_uncertainty(d)]
            if v.decision is not None and v.decision.rule == "dsf" and v.decision.band is None and nob:
                raise SpecError(f"variant {v.name!r} decides by D_SF with the data set's band, but data set(s) "
                                f"{nob} have none: give band = … to the data set or the decision",
                                ("variants", i, "decision"))
            if v.estimator == "se-dsf" and v.options.get("band") is None and nob:
                raise SpecError(f"variant {v.name!r} (se-dsf) solves within the data set's band, but data set(s) "
                                f"{nob} have none: give band = … to the data set or options = {{band = …}} to the "
                                "variant", ("variants", i))
            if reads_uncertainty(v.content()):
                no_delta = [d.name for d in self.data if not _carries_uncertainty(d)]
                if no_delta:
                    raise SpecError(f"variant {v.name!r} has a band constraint without its half-width b, which the "
                                    f"static points' uncertainty gives, but the points of data set(s) {no_delta} carry "
                                    "none: give the constraint b = … (output units) or the static file "
                                    "uncertainty = …", ("variants", i, "constraints"))

    # -- construction from TOML ------------------------------------------------------------
    @classmethod
    def from_toml(cls, path: str | Path) -> "Grid":
        """Read the TOML spec at ``path`` (see ``graybox grid init`` for a commented example); its data files'
        relative paths are resolved against its folder.

        Parameters
        ----------
        path : str or path-like
            A UTF-8 TOML file.

        Returns
        -------
        Grid

        Raises
        ------
        SpecError
            Invalid TOML, or an unknown or wrong key, estimator or constraint, naming the key and
            its line.
        """
        p = Path(path)
        try:
            raw = p.read_bytes()
        except OSError as exc:
            raise SpecError(f"cannot read the spec: {exc}", source=str(p)) from None
        try:
            text = raw.decode("utf-8-sig")  # "-sig": a byte-order mark an editor added is not TOML
        except UnicodeDecodeError as exc:
            line, marked = None, bom_encoding(raw)
            if raw.startswith(b"SQLite format 3\x00"):
                what = "it is a grid store (SQLite), not a spec: graybox grid run SPEC.toml --store STORE"
            elif marked not in (None, "utf-8"):  # Notepad's "Unicode": every line is unreadable, none is to blame
                what = (f"it is {marked.upper()} text (its byte-order mark says so), and TOML is UTF-8: save it as "
                        "UTF-8")
            else:  # the line of the first bad byte (an offset into the file found no line in an editor); a UTF-8
                # byte-order mark says nothing of the bytes after it (utf-8-sig counts them from after the mark)
                at = exc.start + (3 if marked else 0)  # the byte's offset in the file
                line = raw.count(b"\n", 0, at) + 1
                what = (f"it is not UTF-8 text (byte {at}); a spec is a TOML text file in UTF-8 (graybox grid "
                        "init prints one): save it as UTF-8")
            raise SpecError(f"cannot read the spec: {what}", source=str(p), line=line) from None
        return cls.from_toml_text(text, source=str(p), base_dir=str(p.resolve().parent))

    @classmethod
    def from_toml_text(cls, text: str, source: str = "<spec>", base_dir: str | None = None) -> "Grid":
        """Parse a TOML spec given as text.

        Parameters
        ----------
        text : str
            The TOML spec.
        source : str, optional
            Names it in messages (default ``"<spec>"``).
        base_dir : str, optional
            Folder that relative data paths are resolved against (default: the working directory).

        Returns
        -------
        Grid

        Raises
        ------
        SpecError
            Invalid TOML, or an unknown or wrong key, naming the key and its line.
        """
        try:
            d = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            if text.lstrip().startswith("{"):  # no TOML text starts so: JSON (json.dump of the grid's tables)
                raise SpecError("invalid TOML: it is JSON (it starts with '{'); a spec is TOML (graybox grid init "
                                "prints one); from Python, Grid.from_dict(json.load(file)) reads the same tables",
                                source=source, line=1) from None
            at = re.search(r"at line (\d+)", str(exc))
            raise SpecError(f"invalid TOML: {exc}", source=source, line=int(at.group(1)) if at else None) from None
        lines = _TomlLines(text)
        try:
            grid = cls.from_dict(d, base_dir=base_dir)
        except SpecError as e:
            raise type(e)(e.problem, e.path, source, lines.line_of(e.path)) from None
        object.__setattr__(grid, "_toml", (source, lines))  # the problems found once the data are read say it too
        return grid

    @classmethod
    def from_dict(cls, d: Mapping, base_dir: str | None = None) -> "Grid":
        """Build from ``d``, nested dicts shaped like the TOML spec (keys: name, seeds, data, structures,
        variants); relative data paths are resolved against ``base_dir``. A spec as a store keeps it
        (:func:`graybox.experiments.store_specs`) is one: a data set's ``y_unit`` there (its output's unit) is held
        to the data's once they are read, and is no part of the grid's canonical form.

        Parameters
        ----------
        d : mapping
            The spec's tables, as ``tomllib`` reads them.
        base_dir : str, optional
            Folder that relative data paths are resolved against (default: the working directory).

        Returns
        -------
        Grid

        Raises
        ------
        SpecError
            An unknown or wrong key, naming its path in the spec.
        """
        _check_keys(d, ("name", "seeds", "data", "structures", "variants"), "the grid spec")
        parts: dict[str, list] = {}
        y_units: dict[str, str] = {}  # a stored spec's (stored_spec) output unit of a data set: held to its data's
        for key, cls_, allowed in (("data", DataSpec, ("name", "bundled", "ident", "valid", "static", "band",
                                                       "y_unit")),
                                   ("structures", StructureSpec, ("name", "terms", "candidates") + _STRUCTURE_RULE_KEYS),
                                   ("variants", Variant, ("name", "estimator", "constraints", "lambdas", "decision",
                                                          "options"))):
            items = d.get(key)
            if items is not None and not isinstance(items, list):
                raise SpecTypeError(f"the spec needs at least one [[{key}]] table, got {items!r}", (key,))
            if not items:
                raise SpecError(f"the spec needs at least one [[{key}]] table", (key,))
            out = []
            for i, it in enumerate(items):
                if key == "data" and isinstance(it, Mapping):  # a file's option written beside the files
                    misplaced = [k for k in it if k not in allowed and k in (*_RECORD_KEYS, *_STATIC_KEYS)]
                    if misplaced:
                        k = misplaced[0]
                        raise SpecError(f"{k!r} is an option of each CSV file, not of the [[data]] table: give it in "
                                        f"the file tables it concerns, e.g. ident = {{path = …, u = …, y = …, {k} = …}} "
                                        "(and likewise valid and static)", (key, i, k))
                _check_keys(it, allowed, f"a [[{key}]] table", (key, i))
                if "name" not in it:
                    raise SpecError(f"every [[{key}]] table needs a name", (key, i))
                if key == "variants" and "estimator" not in it:  # (the dataclass's bare TypeError named no line)
                    raise SpecError(f"every [[variants]] table needs an estimator, one of {', '.join(ESTIMATORS)}",
                                    (key, i))
                if key == "data" and "y_unit" in it:
                    if not isinstance(it["y_unit"], str):
                        raise SpecTypeError(f"y_unit must be a string (the unit of the data's output), got "
                                            f"{it['y_unit']!r}", (key, i, "y_unit"))
                    y_units[str(it["name"])] = it["y_unit"]
                    it = {k: v for k, v in it.items() if k != "y_unit"}
                try:
                    out.append(cls_(**it))
                except SpecError as e:
                    raise e.within(key, i) from None
            parts[key] = out
        seeds = d.get("seeds", [0])
        if not isinstance(seeds, list):
            seeds = [seeds]
        grid = cls(parts["data"], parts["structures"], parts["variants"], seeds=seeds, name=d.get("name", "grid"),
                   base_dir=base_dir)
        object.__setattr__(grid, "_y_units", y_units)  # checked once the data are read (_load_data)
        return grid

    # -- canonical form, data, cells --------------------------------------------------------
    def to_dict(self) -> dict:
        """Canonical form of the whole grid (names, contents, seeds).

        Returns
        -------
        dict
            ``name``, ``seeds`` and the canonical forms of the ``data``, ``structures`` and ``variants``.
        """
        return {"name": self.name, "seeds": list(self.seeds),
                "data": [d.to_dict() for d in self.data],
                "structures": [s.to_dict() for s in self.structures],
                "variants": [v.to_dict() for v in self.variants]}

    def load_data(self) -> dict[str, gb.Dataset]:
        """Every data set, loaded, by name (CSV paths relative to ``base_dir``).

        Returns
        -------
        dict of str to Dataset

        Raises
        ------
        SpecError
            A data set that cannot be loaded, or does not meet the spec (naming the file and line of a grid read
            from TOML).
        """
        try:
            return self._load_data()
        except SpecError as e:
            toml = getattr(self, "_toml", None)  # a grid read from TOML: its problems name the file and the line
            if toml is None or e.source is not None:
                raise
            raise type(e)(e.problem, e.path, toml[0], toml[1].line_of(e.path)) from None

    def _load_data(self) -> dict[str, gb.Dataset]:
        out = {}
        for i, d in enumerate(self.data):
            try:
                ds = d.load(self.base_dir)
            except SpecError as e:
                raise e.within("data", i) from None
            except (OSError, ValueError) as exc:  # the loader's hints name its options in Python: said in TOML
                raise SpecError(f"data set {d.name!r} cannot be loaded: {_toml_hints(str(exc))}", ("data", i)) from None
            said = getattr(self, "_y_units", {}).get(d.name)
            if said is not None and said != ds.valid.units[1]:  # a stored spec's unit: the data it was run on said it
                given = repr(ds.valid.units[1]) if ds.valid.units[1] else "no unit"  # (not the quoted words 'no unit')
                # y_unit only checks (a stored spec's record of the unit): CSV data are given theirs in the file tables
                how = ("; y_unit names no unit, it holds the data to theirs: give the CSV files' units as units = "
                       "[input unit, output unit] in the ident, valid and static tables (or units_row = true)"
                       if d.bundled is None and d.dataset is None else "")
                raise SpecError(f"data set {d.name!r} gives its output in {given}, but the spec says y_unit = {said!r}"
                                f"{how}", ("data", i, "y_unit"))
            names = tuple(ds.input_names)
            for j, st in enumerate(self.structures):  # an input the data lack fails every cell of the structure
                unknown = [n for n in _structure_inputs(st) if n not in names]
                if unknown:
                    raise SpecError(f"structure {st.name!r} names input(s) {', '.join(map(repr, unknown))}, which data "
                                    f"set {d.name!r} does not have (its inputs: {', '.join(names)})", ("structures", j))
                if st.candidates is not None and not isinstance(st.candidates["nu"], Mapping):
                    # one lag count for every input: the data set's inputs decide how many candidates FROLS has
                    n_cand = len(gb.Candidates(**st.candidates, input_names=names))
                    for k in ("n_terms", "max_terms"):
                        if getattr(st, k) is not None and getattr(st, k) > n_cand:
                            raise SpecError(f"structure {st.name!r}: {k} = {getattr(st, k)} is more than the {n_cand} "
                                            f"candidates it has on data set {d.name!r} (inputs: {', '.join(names)})",
                                            ("structures", j, k))
            for j, v in enumerate(self.variants):
                for k, c in enumerate(v.constraints):
                    if c["type"] == "equality" and c["curve"] == "dataset" and "static_curve" not in ds.extra:
                        raise SpecError(f"variant {v.name!r} imposes the data set's own static curve, but data set "
                                        f"{d.name!r} has none; use curve = \"fit\" or coefficients",
                                        ("variants", j, "constraints"))
                    if c["type"] == "gain":  # as select_graybox: a name or count the data lack fails every cell
                        try:
                            build_constraint(c)._bounds(len(names), names)
                            rng = c["ubar_range"]
                            if rng is not None and not isinstance(rng, Mapping) and np.ndim(rng) == 2 \
                                    and len(rng) != len(names):  # one (low, high) per input
                                raise ValueError(f"ubar_range has {len(rng)} ranges, one per input, but the data set "
                                                 f"has {len(names)} input(s) {names}")
                        except ValueError as exc:
                            raise SpecError(f"variant {v.name!r} on data set {d.name!r}: {exc}",
                                            ("variants", j, "constraints", k)) from None
            out[d.name] = ds
        return out

    def cells(self, datasets: Mapping[str, gb.Dataset] | None = None) -> tuple[Cell, ...]:
        """The grid's cells in order (data, structure, variant, seed), with their keys.

        Parameters
        ----------
        datasets : mapping name -> Dataset, optional
            The loaded data (default: :meth:`load_data`); keys hash their content.

        Returns
        -------
        tuple of Cell
            One per data set × structure × variant (× seed, for a stochastic variant), in that order.
        """
        if datasets is None:
            ds = self.load_data()
        elif not isinstance(datasets, Mapping):
            raise TypeError(f"datasets must map data set names to Datasets, got {datasets!r}")
        else:
            missing = [d.name for d in self.data if d.name not in datasets]
            if missing:
                raise ValueError(f"datasets has no data set named {missing}")
            for d in self.data:  # (the content hash read their attributes: a bare AttributeError)
                if not isinstance(datasets[d.name], gb.Dataset):
                    raise TypeError(f"datasets[{d.name!r}] must be a graybox Dataset, got "
                                    f"{type(datasets[d.name]).__name__}")
            ds = datasets
        version = gb.__version__
        out: list[Cell] = []
        # a key hashes the canonical JSON of {band (where read), data, seed, structure, variant, version}; the
        # structure's and the variant's texts are made once, not once per cell (the same bytes)
        structures = [(s, s.content()) for s in self.structures]
        structures = [(s, canonical_json(sc), _freeze(sc)) for s, sc in structures]
        variants = [(v, v.content()) for v in self.variants]
        variants = [(v, canonical_json(vc), _freeze(vc)) for v, vc in variants]
        tail = ',"version":' + canonical_json(version) + "}"
        for d in self.data:
            dh = data_fingerprint(ds[d.name])
            band = band_of(d, ds[d.name])
            tail_data = '"data":' + canonical_json(dh) + ',"seed":'
            # the band only where the variant reads it; the points' δ where it reads δ and a band in the key does
            # not say it (keys of band-reading cells written before unchanged)
            heads = {True: '{"band":' + canonical_json(band) + "," + tail_data, False: "{" + tail_data}
            unc_texts = {}
            for banded in (True, False):
                unc = uncertainty_key(ds[d.name], band if banded else None)
                unc_texts[banded] = "" if unc is None else ',"uncertainty":' + canonical_json(unc)
            for s, sc, frozen_s in structures:
                for v, vc, frozen_v in variants:
                    banded = reads_band(frozen_v)
                    extra = unc_texts[banded] if reads_uncertainty(frozen_v) else ""
                    for seed in (self.seeds if v.stochastic else (None,)):
                        text = (heads[banded] + canonical_json(seed) + ',"structure":' + sc + extra + ',"variant":'
                                + vc + tail)
                        key = hashlib.sha256(text.encode()).hexdigest()[:32]
                        out.append(Cell(len(out), key, d.name, s.name, v.name, seed, dh, band, frozen_s, frozen_v,
                                        version))
        return tuple(out)

    def fingerprint(self, cells: Sequence[Cell]) -> str:
        """A hash of the grid: its names and its cells' keys (so: contents, data, version).

        Parameters
        ----------
        cells : sequence of Cell
            The grid's cells (:meth:`cells`).

        Returns
        -------
        str
            16 hexadecimal digits.
        """
        return _hash({"name": self.name, "cells": [[c.key, c.data, c.structure, c.variant, c.seed] for c in cells]})

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape


# --------------------------------------------------------------------------------------------
# where a key is in a TOML text
# --------------------------------------------------------------------------------------------
class _TomlLines:
    """Line numbers of the keys of a TOML text (tomllib keeps none).

    Table headers (``[a.b]``, ``[[a]]``) and ``key = value`` lines at the top level of a table are
    indexed exactly; a key inside an inline table or a multi-line array is found by searching
    for ``key =`` after the line of the enclosing key.
    """

    _HEADER = re.compile(r"^\s*(\[\[?)\s*(.+?)\s*\]\]?\s*(?:#.*)?$")
    _KEY = re.compile(r"^\s*((?:[A-Za-z0-9_-]+|\"[^\"]*\"|'[^']*')(?:\s*\.\s*(?:[A-Za-z0-9_-]+|\"[^\"]*\"|'[^']*'))*)\s*=")

    def __init__(self, text: str):
        self.lines = text.splitlines()
        self.index: dict[tuple, int] = {}
        self.headers: list[int] = []
        arrays: dict[tuple, int] = {}
        table: tuple = ()
        depth = 0
        for n, line in enumerate(self.lines, start=1):
            if depth == 0:
                m = self._HEADER.match(line)
                if m and not self._KEY.match(line):
                    names = tuple(self._split(m.group(2)))
                    if m.group(1) == "[[":
                        arrays[names] = arrays.get(names, 0) + 1
                    table = self._resolve(names, arrays)
                    self.index.setdefault(table, n)
                    self.headers.append(n)
                    continue
                k = self._KEY.match(line)
                if k:
                    self.index.setdefault(table + tuple(self._split(k.group(1))), n)
            depth = max(0, depth + self._depth_change(line))

    @staticmethod
    def _split(dotted: str) -> list[str]:
        parts = re.findall(r"\"[^\"]*\"|'[^']*'|[^.\s]+", dotted)
        return [p[1:-1] if p[:1] in "\"'" else p for p in parts]

    @staticmethod
    def _resolve(names: tuple, arrays: dict[tuple, int]) -> tuple:
        out: list = []
        for i, nm in enumerate(names):
            out.append(nm)
            if names[: i + 1] in arrays:
                out.append(arrays[names[: i + 1]] - 1)
        return tuple(out)

    @staticmethod
    def _depth_change(line: str) -> int:
        d, quote = 0, ""
        for ch in line:
            if quote:
                if ch == quote:
                    quote = ""
            elif ch in "\"'":
                quote = ch
            elif ch == "#":
                break
            elif ch in "[{":
                d += 1
            elif ch in "]}":
                d -= 1
        return d

    def line_of(self, path: Sequence[str | int]) -> int | None:
        """The line of ``path`` (or of its nearest enclosing key), 1-based; None if unknown."""
        path = tuple(path)
        for cut in range(len(path), 0, -1):
            if path[:cut] in self.index:
                start = self.index[path[:cut]]
                rest = path[cut:]
                break
        else:
            return None
        keys = [p for p in rest if isinstance(p, str)]
        if not keys:
            return start
        target = keys[-1]
        ints = [p for p in rest if isinstance(p, int)]
        skip = ints[-1] if ints else 0
        stop = next((h for h in self.headers if h > start), len(self.lines) + 1)
        pat = re.compile(r"(?:^|[\s{,])(?:" + re.escape(target) + r"|\"" + re.escape(target) + r"\")\s*=")
        seen = 0
        for n in range(start, stop):
            for _ in pat.finditer(self.lines[n - 1]):
                if seen == skip:
                    return n
                seen += 1
        return start
