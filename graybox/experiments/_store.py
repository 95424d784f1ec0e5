"""The result store: one SQLite file per grid (standard library :mod:`sqlite3`).

Each finished cell is one row, committed in its own transaction as soon as the driver receives
it, so a run that is killed loses only the cells in flight. A store knows the grid that wrote it
(a fingerprint of its cells' keys and names, and the whole spec): running another grid against
it is refused, and so is any file that is not a graybox store or is damaged. A refused file is
never written to.
"""

from __future__ import annotations

import datetime
import json
import os
import sqlite3
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import pandas as pd

from ._cell import COLUMNS, JSON_COLUMNS

__all__ = ["StoreError", "ResultStore", "load_results", "FORMAT", "FORMAT_VERSION"]

#: What a graybox store says it is (table ``meta``, key ``format``).
FORMAT = "graybox-grid-store"
FORMAT_VERSION = "1"
_SQLITE_MAGIC = b"SQLite format 3\x00"
#: Pages of write-ahead log after which a commit folds the log into the database.
WAL_PAGES = 128


class StoreError(ValueError):
    """A store cannot be used: not a graybox store, damaged, or written by another grid."""


def _check_file(path: Path) -> None:
    """Refuse, without writing, a file that is not an SQLite database."""
    try:
        with open(path, "rb") as f:
            head = f.read(len(_SQLITE_MAGIC))
    except OSError as exc:
        raise StoreError(f"{path}: cannot read the store: {exc}") from None
    if head != _SQLITE_MAGIC:
        what = "an empty file" if not head else "not an SQLite database"
        raise StoreError(f"{path} is {what}, so not a graybox grid store; nothing was written to it. "
                         "Choose another --store path")


def _read_meta(conn: sqlite3.Connection, path: Path) -> dict[str, str]:
    """Check integrity and ownership (read-only statements only) and return the meta table."""
    try:
        ok = conn.execute("PRAGMA quick_check").fetchone()
        if ok is None or ok[0] != "ok":
            raise StoreError(f"{path} is damaged (SQLite integrity check: {ok[0] if ok else 'no answer'}); "
                             "nothing was written to it")
        tables = {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
        if not {"meta", "cells"} <= tables:
            raise StoreError(f"{path} is an SQLite database but not a graybox grid store (tables: "
                             f"{sorted(tables) or 'none'}); nothing was written to it. Choose another --store path")
        meta = dict(conn.execute("SELECT key, value FROM meta").fetchall())
        cols = [r[1] for r in conn.execute("PRAGMA table_info(cells)")]
    except sqlite3.DatabaseError as exc:
        raise StoreError(f"{path} is damaged or not a graybox grid store ({exc}); nothing was written to it") from None
    if meta.get("format") != FORMAT:
        raise StoreError(f"{path} is an SQLite database but not a graybox grid store (no format mark); nothing "
                         "was written to it")
    if meta.get("format_version") != FORMAT_VERSION:
        raise StoreError(f"{path} is a graybox store of format {meta.get('format_version')!r}; this graybox reads "
                         f"format {FORMAT_VERSION!r}")
    if cols != list(COLUMNS):
        raise StoreError(f"{path}: the cells table has columns {cols}, expected {list(COLUMNS)}: damaged or "
                         "written by another graybox")
    return meta


def _settings(conn: sqlite3.Connection) -> None:
    """Durable against a killed process (WAL), where an fsync per cell would only guard against
    power loss; the log folded into the database every WAL_PAGES pages, not SQLite's 1000, so that
    closing the store, which folds what is left while every worker waits, stays short. (Read the
    schema: only on a file already checked.)"""
    conn.execute("PRAGMA synchronous=NORMAL")
    conn.execute(f"PRAGMA wal_autocheckpoint={WAL_PAGES}")


def _connect(path: Path, readonly: bool = False) -> sqlite3.Connection:
    if readonly:
        return sqlite3.connect(path.resolve().as_uri() + "?mode=ro", uri=True, timeout=30.0, isolation_level=None)
    return sqlite3.connect(str(path), timeout=30.0, isolation_level=None)  # explicit transactions


class ResultStore:
    """An open store for one grid: which cells are finished; write a finished cell.

    Use :meth:`open`; close with :meth:`close` (or ``with``).
    """

    def __init__(self, path: Path, conn: sqlite3.Connection, meta: Mapping[str, str]):
        self.path = path
        self._conn = conn
        self.meta = dict(meta)

    @classmethod
    def open(cls, path: str | os.PathLike, *, fingerprint: str, grid_name: str, spec: Mapping[str, Any],
             n_cells: int, version: str) -> "ResultStore":
        """Create the store, or reopen one written by the same grid.

        Raises
        ------
        StoreError
            The file is not a graybox store, is damaged, or was written by another grid (or
            another graybox version, whose cells have other keys).
        """
        p = Path(path)
        exists = p.exists()
        if not exists and not p.parent.exists():
            raise StoreError(f"{p.parent} does not exist; create the folder for the store first")
        if exists:
            if p.is_dir():
                raise StoreError(f"{p} is a folder; give a file path for the store")
            _check_file(p)
            # checked through a read-only connection: closing it folds no log left by a killed writer
            ro = _connect(p, readonly=True)
            try:
                meta = _read_meta(ro, p)
                if meta.get("grid_fingerprint") != fingerprint:
                    n = ro.execute("SELECT COUNT(*) FROM cells").fetchone()[0]
                    why = ""
                    if meta.get("graybox_version") != version:
                        why = (f" (it was written by graybox {meta.get('graybox_version')}, this is {version}: "
                               "cells are keyed by version)")
                    raise StoreError(
                        f"{p} holds {n} cell(s) of another grid ({meta.get('grid_name')!r}, fingerprint "
                        f"{meta.get('grid_fingerprint')}){why}; this grid ({grid_name!r}) has fingerprint "
                        f"{fingerprint}. Results of two grids are not mixed: choose another --store path")
            finally:
                ro.close()
        conn = _connect(p)
        try:
            if exists:
                _settings(conn)
            else:
                conn.execute("PRAGMA journal_mode=WAL")
                _settings(conn)
                cols = ", ".join(f"{k} {t}" for k, t in COLUMNS.items())
                meta = {"format": FORMAT, "format_version": FORMAT_VERSION, "grid_fingerprint": fingerprint,
                        "grid_name": grid_name, "grid_spec": json.dumps(spec, sort_keys=True),
                        "graybox_version": version, "n_cells": str(n_cells),
                        "created": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")}
                conn.execute("BEGIN")
                conn.execute("CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)")
                conn.execute(f"CREATE TABLE cells ({cols})")
                conn.executemany("INSERT INTO meta VALUES (?, ?)", list(meta.items()))
                conn.execute("COMMIT")
        except BaseException:
            conn.close()
            raise
        return cls(p, conn, meta)

    def statuses(self) -> dict[str, str]:
        """Status of every finished cell, by key."""
        return dict(self._conn.execute("SELECT key, status FROM cells").fetchall())

    def write(self, row: Mapping[str, Any], replace: bool = False) -> None:
        """Commit one finished cell (``replace``: overwrite a failed row of the same key)."""
        values = [encode_value(k, row.get(k)) for k in COLUMNS]
        verb = "INSERT OR REPLACE" if replace else "INSERT"
        self._conn.execute("BEGIN IMMEDIATE")
        try:
            self._conn.execute(f"{verb} INTO cells ({', '.join(COLUMNS)}) VALUES ({', '.join('?' * len(COLUMNS))})",
                               values)
        except BaseException:
            self._conn.execute("ROLLBACK")
            raise
        self._conn.execute("COMMIT")

    def counts(self) -> dict[str, int]:
        """Cells by status."""
        return dict(self._conn.execute("SELECT status, COUNT(*) FROM cells GROUP BY status").fetchall())

    def close(self) -> None:
        """Close the connection."""
        self._conn.close()

    def __enter__(self) -> "ResultStore":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _plain(v: Any) -> Any:
    """numpy arrays and scalars as the lists and numbers JSON writes."""
    if isinstance(v, (np.ndarray, np.generic)):
        return v.tolist()
    raise TypeError(f"{type(v).__name__} cannot be written to the store")


def encode_value(k: str, v: Any) -> Any:
    """A row's value of column ``k`` as the store holds it (JSON text for the list columns)."""
    if k in JSON_COLUMNS:
        return None if v is None else json.dumps(v, default=_plain)
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    return v


def _decode_members(text: str | None) -> dict[str, np.ndarray] | None:
    if text is None:
        return None
    d = json.loads(text)
    return {k: (np.array(v, dtype=float) if k != "failure" else list(v)) for k, v in d.items()}


def read_store(path: str | os.PathLike) -> tuple[dict[str, str], list[dict[str, Any]]]:
    """(meta, rows) of a store, read-only."""
    p = Path(path)
    if not p.is_file():
        raise StoreError(f"{p}: no such store")
    _check_file(p)
    conn = _connect(p, readonly=True)  # closing it folds no log left by a killed writer into the file
    try:
        meta = _read_meta(conn, p)
        cur = conn.execute(f"SELECT {', '.join(COLUMNS)} FROM cells ORDER BY cell_index")
        rows = [dict(zip(COLUMNS, r)) for r in cur.fetchall()]
    except sqlite3.DatabaseError as exc:
        raise StoreError(f"{p} is damaged ({exc})") from None
    finally:
        conn.close()
    return meta, rows


def load_results(path: str | os.PathLike) -> pd.DataFrame:
    """The cells of a grid store as a DataFrame, one row per cell, in grid order.

    Parameters
    ----------
    path : str or path-like
        A store written by :func:`graybox.experiments.run_grid` (``graybox grid run``).

    Returns
    -------
    pandas.DataFrame
        Columns: ``data``, ``structure``, ``variant``, ``seed`` (nullable integer; missing for deterministic
        estimators), ``estimator``, ``status`` (ok, infeasible, diverged, failed), ``message``;
        the chosen model's ``terms`` (tuple of str), ``theta`` (ndarray, engineering units; None
        for neural models), ``n_params`` (N_p), ``lambda1``, ``rule`` and ``in_band`` of the
        decision, ``band`` (the data set's J_SF band); the shared evaluator's figures on both
        records ``J1_ident``, ``JS_ident``, ``fit_ident``, ``J1_valid``, ``JS_valid``,
        ``fit_valid`` (MSE in output units², fit in %), ``JSF`` and ``static_miss`` (largest
        |ȳ_model(ū_i) − ȳ_i|, output units); ``members`` (Pareto sets: dict of arrays
        ``lambda1``, ``J1``, ``JS``, ``JSF``, ``JS_valid``, ``fit_valid`` and the list ``failure``); ``wall_time``
        (s), ``version``, ``warnings`` (tuple of str), ``worker``, ``finished_at``, ``key``,
        ``cell_index``. ``df.attrs`` holds the grid's name, fingerprint and spec.

    Raises
    ------
    StoreError
        Not a graybox store, or damaged.
    """
    meta, rows = read_store(path)
    for r in rows:
        r["terms"] = None if r["terms"] is None else tuple(json.loads(r["terms"]))
        r["theta"] = None if r["theta"] is None else np.array(json.loads(r["theta"]), dtype=float)
        r["warnings"] = () if r["warnings"] is None else tuple(json.loads(r["warnings"]))
        r["members"] = _decode_members(r["members"])
        r["in_band"] = None if r["in_band"] is None else bool(r["in_band"])
        r["seed"] = None if r["seed"] is None else int(r["seed"])
    df = pd.DataFrame(rows, columns=list(COLUMNS))
    front = ["data", "structure", "variant", "seed", "estimator", "status", "message"]
    df = df[front + [c for c in df.columns if c not in front]]
    for c in ("lambda1", "band", "J1_ident", "JS_ident", "fit_ident", "J1_valid", "JS_valid", "fit_valid", "JSF",
              "static_miss", "wall_time"):
        df[c] = df[c].astype(float)
    for c, dtype in (("seed", "Int64"), ("n_params", "Int64"), ("in_band", "boolean")):
        df[c] = pd.array([r[c] for r in rows], dtype=dtype)
    df.attrs.update(grid=meta.get("grid_name"), fingerprint=meta.get("grid_fingerprint"),
                    spec=json.loads(meta.get("grid_spec", "{}")), version=meta.get("graybox_version"),
                    n_cells=int(meta.get("n_cells", len(df))))
    return df
