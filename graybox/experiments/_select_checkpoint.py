"""``select_graybox``'s checkpoint: each structure × estimator row's scores kept as it finishes.

A selection over many structures and slow estimators (SE fronts) runs for minutes or hours; with
``checkpoint=`` a killed run resumes without refitting the rows it finished. A row is kept under a key
hashing everything that decides its scores: the row's terms, estimator, λ1 and constraints, the plan
(every record's samples, Ts, names and units, the folds and blocks, the static points, the largest
lag, the data set's extra values) and graybox's version. Not the band, which chooses among the rows
and changes none of them; not the test records, which only report (a row's test scores are kept with
a hash of the records they score, and remade from its members' θ, no fit, for others); not the
caller's warning filters: a script and a
notebook (or a test run) filter differently, and a row keeps the warnings of the run that fitted it.
A row whose key the file does not hold is fitted: a file written for other data, options or another
version is not wrong, only not reused; a row with fields this graybox does not know (a newer one's, sharing the
file) is written back as it was read. The file is an ``.npz`` of numeric and text arrays, read
without pickle, and replaced atomically after each row, so a kill never tears it.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
import re
from collections.abc import Mapping
from typing import Any

import numpy as np

from .. import _api as gb
from ..estimation._simulation_error import NPZ_ERRORS, CheckpointError, checkpoint_path, read_npz, save_npz
from ._spec import canonical_json

__all__ = ["SelectionCheckpoint", "checkpoint_of", "plan_digest", "row_key", "test_digest"]

#: What a row's result holds: arrays, optional arrays and lists of text.
_ARRAYS = ("blocks", "weights", "jsf", "jsf_full", "thetas", "lambdas")
_OPTIONAL = ("test",)
_TEXTS = ("failed", "warnings")
# not in rows a checkpoint of 0.3.0 kept; test_key only in rows with test scores (a hash of the records they score)
_OPTIONAL_TEXTS = ("member_failed", "test_key")
_ALL_TEXTS = _TEXTS + _OPTIONAL_TEXTS
_KEY = re.compile(r"^[0-9a-f]{32}$")
_FIELD = re.compile(r"^[a-z][a-z0-9_]*$")  # a field's name, known to this graybox or of a newer one


def _feed(h: Any, obj: Any) -> None:
    """Hash ``obj``'s content into ``h``: arrays by dtype, shape and bytes, values field by field."""
    if obj is None or isinstance(obj, (bool, int, float, str)):
        h.update(f"{type(obj).__name__}:{obj!r};".encode())
    elif isinstance(obj, np.ndarray):
        a = np.ascontiguousarray(obj)
        h.update(f"array:{a.dtype.str}:{a.shape};".encode())
        h.update(a.tobytes() if a.dtype != object else repr(a.tolist()).encode())
    elif isinstance(obj, np.generic):
        _feed(h, obj.item())
    elif isinstance(obj, Mapping):
        h.update(f"map:{len(obj)};".encode())
        for k in sorted(obj, key=repr):
            _feed(h, k)
            _feed(h, obj[k])
    elif isinstance(obj, (tuple, list)):
        h.update(f"seq:{len(obj)};".encode())
        for v in obj:
            _feed(h, v)
    elif dataclasses.is_dataclass(obj):
        h.update(f"value:{type(obj).__qualname__};".encode())
        for f in dataclasses.fields(obj):
            h.update(f.name.encode())
            _feed(h, getattr(obj, f.name))
    elif isinstance(obj, gb.Structure):
        _feed(h, [str(t) for t in obj])
    else:  # nothing a fit reads (e.g. a bundled data set's simulator in its extra values): its kind only
        h.update(f"other:{type(obj).__module__}.{type(obj).__qualname__};".encode())


def plan_digest(plan: Any) -> bytes:
    """A hash of what the plan gives a row's fits and choosing scores: its records, splits, static points, largest
    lag and extra values. Not the band, which decides the choice among the rows, not their scores: a selection
    called again with another B reuses every row; not the test records, which only report: a row's test scores
    are kept with :func:`test_digest` and remade from its θ for other test records. Made once per call (the records
    may be long)."""
    h = hashlib.sha256()
    _feed(h, dataclasses.replace(plan, band=None, test=None, test_floors=()))  # (the test records' round-off floors)
    return h.digest()


def test_digest(plan: Any) -> str:
    """A hash of the plan's test records and largest lag (from which the test samples count): which records a kept
    row's test scores are of."""
    h = hashlib.sha256()
    _feed(h, (plan.test, plan.lag))
    return h.hexdigest()[:32]


def row_key(job: Any, plan: bytes | None = None) -> str:
    """The key of a row's scores: a hash of the job (terms, estimator, λ1, constraints and the plan's data and
    splits, ``plan`` its :func:`plan_digest` when made already) and graybox's version."""
    h = hashlib.sha256()
    _feed(h, gb.__version__)
    # the folds' own structures when searched per fold (a row fitted on the full structure per fold is another row)
    _feed(h, (job.terms, job.estimator, job.lambdas) if job.fold_terms is None else
          (job.terms, job.estimator, job.lambdas, job.fold_terms))
    h.update(canonical_json(job.constraints).encode())  # the canonical tables, as a grid cell's key holds them
    h.update(plan_digest(job.plan) if plan is None else plan)
    return h.hexdigest()[:32]


class SelectionCheckpoint:
    """The rows a checkpoint file holds, and the file rewritten as rows finish.

    Parameters
    ----------
    path : path
        The ``.npz`` file (created at the first finished row; its folder must exist).
    """

    def __init__(self, path: str | os.PathLike):
        self.path = checkpoint_path(path)
        #: Rows of another graybox (fields this one does not know): never offered, written back as they were read
        #: (unless this graybox fits a row of the same key: :meth:`put`).
        self.foreign: dict[str, dict[str, np.ndarray]] = {}
        self.rows: dict[str, dict[str, Any]] = self._read() if self.path.exists() else {}

    def _read(self) -> dict[str, dict[str, Any]]:
        try:
            arrays = read_npz(self.path)
        except NPZ_ERRORS as exc:  # not an npz, torn, or holding objects (which would need pickle)
            raise CheckpointError(f"checkpoint {self.path} is not a readable select_graybox checkpoint ({exc}); "
                                  "delete it or choose another checkpoint path") from None
        if "kind" not in arrays and "meta" in arrays:  # another function's file, perhaps hours of work: not offered
            raise CheckpointError(f"checkpoint {self.path} is se_pareto's checkpoint (an SE sweep), and is not a "
                                  "select_graybox checkpoint; choose another checkpoint path")
        if str(arrays.pop("kind", "")) != "select_graybox":
            raise CheckpointError(f"checkpoint {self.path} is not a select_graybox checkpoint; delete it or choose "
                                  "another checkpoint path")
        rows: dict[str, dict[str, Any]] = {}
        for name, value in arrays.items():
            key, _, field = name.partition("/")
            if not _KEY.match(key) or not _FIELD.match(field):
                raise CheckpointError(f"checkpoint {self.path} is corrupt (an entry {name!r}); delete it or choose "
                                      "another checkpoint path")
            rows.setdefault(key, {})[field] = value
        for key, row in rows.items():
            if not set(row) <= set(_ARRAYS + _OPTIONAL + _ALL_TEXTS):
                # a field this graybox does not know: a row of a newer graybox sharing the file (its key hashes its
                # version, so it is never one of this version's rows), kept as it is and written back unread
                self.foreign[key] = row
            elif any(f not in row for f in _ARRAYS + _TEXTS):
                raise CheckpointError(f"checkpoint {self.path} is corrupt (a row without all its scores); delete it or "
                                      "choose another checkpoint path")
            else:
                why = _row_problem(row)
                if why:  # read as it was, a broken row failed after the search with a bare IndexError, or scored
                    raise CheckpointError(f"checkpoint {self.path} is corrupt (a row's {why}); delete it or choose "
                                          "another checkpoint path")
                for field in _ALL_TEXTS:
                    if field in row:
                        row[field] = [str(s) for s in row[field]]
        return {k: r for k, r in rows.items() if k not in self.foreign}

    def get(self, key: str, shape: tuple[int, int, int] | None = None) -> dict[str, Any] | None:
        """The scores kept under ``key`` (a copy), or None; ``shape``: the (members, blocks, parameters) the row's
        job makes (``CheckpointError`` when the row kept there has others: the file was edited)."""
        row = self.rows.get(key)
        if row is None:
            return None
        if shape is not None and (row["blocks"].shape[0], row["blocks"].shape[1], row["thetas"].shape[1]) != shape:
            raise CheckpointError(f"checkpoint {self.path} is corrupt (a row of {row['blocks'].shape[0]} member(s), "
                                  f"{row['blocks'].shape[1]} block(s) and {row['thetas'].shape[1]} parameter(s) where "
                                  f"its job makes {shape[0]}, {shape[1]} and {shape[2]}); delete it or choose another "
                                  "checkpoint path")
        out = {k: (list(v) if k in _ALL_TEXTS else v.copy()) for k, v in row.items()}
        # as a fit gives its row: a member without θ (its fit on all the identification data failed) cannot be chosen
        # (a row kept with finite scores for one, by an edit or a graybox before that rule, had it chosen, and the
        # selection then failed taking its model)
        out["blocks"] = out["blocks"].astype(float)
        out["blocks"][~np.all(np.isfinite(out["thetas"]), axis=1)] = np.inf
        return out

    def put(self, key: str, row: Mapping[str, Any], write: bool = True) -> None:
        """Keep a finished row's scores and rewrite the file (atomically: a kill leaves the old one or the new);
        with ``write=False`` only here, until the next :meth:`write`."""
        self.rows[key] = {k: (list(row[k]) if k in _ALL_TEXTS else np.asarray(row[k]))
                          for k in _ARRAYS + _TEXTS + tuple(k for k in _OPTIONAL + _OPTIONAL_TEXTS if k in row)}
        # a row under this key with fields this graybox does not know (a graybox of the same version string, e.g. a
        # development checkout) is replaced whole: kept, its fields merged into this row made it unknown again
        self.foreign.pop(key, None)
        if write:
            self.write()

    def write(self) -> None:
        """Rewrite the file with every row kept (atomically)."""
        out: dict[str, np.ndarray] = {"kind": np.array("select_graybox")}
        for k, r in self.foreign.items():
            for field, v in r.items():
                out[f"{k}/{field}"] = v
        for k, r in self.rows.items():
            for field, v in r.items():
                out[f"{k}/{field}"] = np.array(v, dtype=str) if field in _ALL_TEXTS else v
        save_npz(self.path, **out)


def _row_problem(row: Mapping[str, np.ndarray]) -> str:
    """What is wrong with a row read from a file (empty when nothing): its arrays as a fit writes them, P members'
    scores on B blocks (``blocks`` (P, B) of mean squares, ``weights`` (B,) positive, ``jsf``, ``jsf_full``,
    ``lambdas`` and ``test`` (P,), ``thetas`` (P, n)), its texts one-dimensional."""
    arrays = {f: row[f] for f in _ARRAYS + _OPTIONAL if f in row}
    for f, v in arrays.items():
        if v.dtype.kind not in "fi":
            return f"{f} is not numbers ({v.dtype})"
        if v.dtype.kind == "f" and v.dtype != np.float64:  # rewritten as float32 by another tool: its θ rounded
            return f"{f} is {v.dtype}, not the float64 a fit writes (its values were rounded)"
    blocks, thetas = arrays["blocks"], arrays["thetas"]
    if blocks.ndim != 2 or 0 in blocks.shape:
        return f"blocks has shape {blocks.shape}, not (members, blocks)"
    P, B = blocks.shape
    want = {"weights": (B,), "jsf": (P,), "jsf_full": (P,), "lambdas": (P,), "test": (P,)}
    for f, shape in want.items():
        if f in arrays and arrays[f].shape != shape:
            return f"{f} has shape {arrays[f].shape} beside blocks of shape {blocks.shape}"
    if thetas.ndim != 2 or thetas.shape[0] != P or thetas.shape[1] == 0:
        return f"thetas has shape {thetas.shape} beside blocks of shape {blocks.shape}"
    for f in _ALL_TEXTS:
        if f in row and np.ndim(row[f]) != 1:
            return f"{f} is not a list of texts"
    if "member_failed" in row and len(row["member_failed"]) != P:
        return f"member_failed has {len(row['member_failed'])} entries for {P} members"
    with np.errstate(invalid="ignore"):
        # mean squares: >= 0 or inf (a diverged run; NaN only for J_SF without static points)
        for f in ("blocks", "test", "jsf", "jsf_full"):
            v = arrays.get(f)
            if v is not None and (np.any(v < 0) or (f in ("blocks", "test") and np.isnan(v).any())):
                return f"{f} holds {'negative' if np.any(v < 0) else 'NaN'} mean squares"
    if not (np.all(np.isfinite(arrays["weights"])) and np.all(arrays["weights"] > 0)):
        return "weights are not positive numbers"
    lam = arrays["lambdas"]
    with np.errstate(invalid="ignore"):
        if np.any(~np.isnan(lam) & ~((lam > 0) & (lam <= 1))):  # NaN: a member of no weight (a black box)
            return f"lambdas hold a λ1 outside (0, 1] ({lam.tolist()})"
    return ""


def checkpoint_of(checkpoint: str | os.PathLike | None) -> SelectionCheckpoint | None:
    """The checkpoint ``select_graybox`` was given (read and checked now, before any search), or None."""
    return None if checkpoint is None else SelectionCheckpoint(checkpoint)

