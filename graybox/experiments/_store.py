"""The result store: one SQLite file that grows with its grid (standard library :mod:`sqlite3`).

Each finished cell is one row of the ``cells`` table, keyed by the hash of its content (data,
structure, variant, seed, graybox version, and the band where the variant reads it), committed in its
own transaction as soon as the driver receives it, so a run that is killed loses only the cells in
flight. Every spec run against the store is kept (table ``specs``: its canonical form, its data sets' content hashes,
the graybox version, when it was first and last run) with the keys and names of its cells
(table ``spec_cells``). A spec run on an existing store runs only the cells the store does not
hold: new data sets, structures, variants, seeds or options add cells; the rest are reused.

A store gives a data set name one meaning: a spec whose data set of that name reads other data
is refused. So is a store written by a newer graybox, any file that is not a graybox store,
and a damaged one; a refused file is never written to. Stores of the first format (one grid per
store) are read as they are, and upgraded in place when their own spec runs on them again.
"""

from __future__ import annotations

import contextlib
import datetime
import json
import os
import re
import secrets
import socket
import sqlite3
import threading
import time
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from ..core._files import CAN_FLOCK, folder_now, lock_fd, sweep_leftovers
from ..core._processes import pid_alive, pid_started
from ..core._terms import parse_term
from ..core._validation import check_path, check_sequence
from ._cell import COLUMNS, JSON_COLUMNS, STATUSES
from ._spec import Cell, _hash

__all__ = ["StoreError", "ResultStore", "load_results", "compare_results", "store_specs", "FORMAT",
           "FORMAT_VERSION"]

#: What a graybox store says it is (table ``meta``, key ``format``).
FORMAT = "graybox-grid-store"
#: The format this graybox writes; it reads every format in ``READS``.
FORMAT_VERSION = "2"
READS = ("1", "2")
_SQLITE_MAGIC = b"SQLite format 3\x00"
#: What to do with a damaged store.
_DAMAGED = "restore it from a copy, or run the spec into a new --store path"
#: Pages of write-ahead log after which a commit folds the log into the database.
WAL_PAGES = 128

#: Every spec run against the store.
SPECS: dict[str, str] = {
    "id": "INTEGER PRIMARY KEY",
    "name": "TEXT NOT NULL",
    "fingerprint": "TEXT NOT NULL UNIQUE",
    "spec": "TEXT NOT NULL",
    "data": "TEXT NOT NULL",  # JSON: data set name -> content hash
    "graybox_version": "TEXT NOT NULL",
    "created": "TEXT NOT NULL",
    "last_run": "TEXT NOT NULL",
    "n_cells": "INTEGER NOT NULL",
}
#: The cells of every spec, in its grid order, under the names that spec gives them.
SPEC_CELLS: dict[str, str] = {
    "spec": "INTEGER NOT NULL",
    "position": "INTEGER NOT NULL",
    "key": "TEXT NOT NULL",
    "data": "TEXT NOT NULL",
    "structure": "TEXT NOT NULL",
    "variant": "TEXT NOT NULL",
    "seed": "INTEGER",
    "data_hash": "TEXT NOT NULL",
    "structure_hash": "TEXT NOT NULL",
    "variant_hash": "TEXT NOT NULL",
}


#: The drivers running into the store now (table ``drivers``; a row per run, gone when it ends).
DRIVERS: dict[str, str] = {"owner": "TEXT PRIMARY KEY", "host": "TEXT NOT NULL", "pid": "INTEGER NOT NULL",
                           "beat": "REAL NOT NULL"}
#: The cells a running driver has taken (table ``claims``): no other driver starts them.
CLAIMS: dict[str, str] = {"key": "TEXT PRIMARY KEY", "owner": "TEXT NOT NULL"}
#: Seconds without a sign of life after which a driver on another host is taken for dead (on this host
#: the process itself is asked). A running driver beats every tenth of it (:meth:`ResultStore.beating`); one
#: silent longer (a host suspended) has its cells run twice, which costs time only.
STALE_SECONDS = 900.0
#: Seconds a process's start time, read from /proc (boot time to the second), may seem to lie after a beat its
#: own driver wrote.
_CLOCK_SLACK = 5.0


#: The ``drivers`` rows of the stores this process has open: one of this process's rows that is not here belongs
#: to a run that ended without taking its row away (closing could not write the store).
_OPEN_OWNERS: set[str] = set()


#: The runs (``run_grid`` calls) this thread is inside of, innermost last: a run further up a thread's own calls
#: (one whose log callback started another run of the store) cannot go on while an inner one waits for it.
_RUNS_HERE = threading.local()


def _outer_runs() -> set[str]:
    """The ``drivers`` owners of the runs up this thread's calls."""
    return {st._owner for st in getattr(_RUNS_HERE, "stores", ()) if st._owner is not None}


def _driver_name(host: str, pid: int) -> str:
    """A run's driver in words, as claims and grid status name it."""
    return f"pid {pid} on host {host}"


def _alive(owner: str, host: str, pid: int, beat: float, now: float) -> bool:
    """Whether the driver that wrote a ``drivers`` row still runs."""
    if host == socket.gethostname() and pid == os.getpid():
        return owner in _OPEN_OWNERS
    if host != socket.gethostname() or os.name != "posix":  # os.kill(pid, 0) would end a process on Windows
        return now - beat < STALE_SECONDS
    if not pid_alive(pid):  # no such process, or a killed driver its parent has not reaped yet (a zombie)
        return False
    # a process started after the driver's last beat is not the driver: it died and its pid was reused
    started = pid_started(pid)
    return started is None or started <= beat + _CLOCK_SLACK


class StoreError(ValueError):
    """A store cannot be used: not a graybox store, damaged, written by a newer graybox, or
    asked to give a data set name a second meaning."""


def _now() -> str:
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="milliseconds")


def _release(v: str | None) -> tuple[int, ...] | None:
    """A release version as numbers (``"0.3.1"`` -> (0, 3, 1)); None for a local or unknown one."""
    m = re.fullmatch(r"(\d+(?:\.\d+)*)", v or "")
    return tuple(int(x) for x in m.group(1).split(".")) if m else None


def _newer(a: str | None, b: str | None) -> bool:
    """Whether release ``a`` is newer than release ``b`` (False when either is not a plain release)."""
    ra, rb = _release(a), _release(b)
    return ra is not None and rb is not None and ra > rb


def _not_a_store(reading: bool) -> str:
    """The tail of a refusal: a run says it wrote nothing and where to run instead; a reader (load_results,
    graybox grid status / report, which take the store's path, not --store) what to give."""
    return "give the path of a grid store" if reading else "nothing was written to it. Choose another --store path"


def _check_file(path: Path, reading: bool = False) -> None:
    """Refuse, without writing, a file that is not an SQLite database."""
    try:
        with open(path, "rb") as f:
            head = f.read(len(_SQLITE_MAGIC))
    except OSError as exc:
        raise StoreError(f"{path}: cannot read the store: {exc}") from None
    if head != _SQLITE_MAGIC:
        what = "an empty file" if not head else "not an SQLite database"
        raise StoreError(f"{path} is {what}, so not a graybox grid store; {_not_a_store(reading)}")


#: Seconds a run waits for the lock beside a store another run makes in place (as long as SQLite's own lock wait).
MAKING_TIMEOUT = 30.0


def _making_path(p: Path) -> Path:
    """The lock beside a store ``p`` that a run making it in place holds (:func:`_making`)."""
    return p.with_name(f".{p.name}.making")


@contextlib.contextmanager
def _making(p: Path):
    """While a run makes the store ``p`` in place: ``.NAME.making`` beside it, locked from before the store's file
    exists until its first transaction ends (removed then). A file appears at its connect, empty and unlocked
    for a statement until its ``BEGIN IMMEDIATE``; a run finding it empty then waited for no lock and refused
    it. flock (not SQLite's POSIX locks) so that two threads of one process wait for each other too."""
    lock = _making_path(p)
    fd = None
    if CAN_FLOCK:
        with contextlib.suppress(OSError):  # a folder this user cannot write in: the connect says so
            fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        if fd is not None and lock_fd(fd, MAKING_TIMEOUT):
            with contextlib.suppress(OSError):
                os.utime(fd)  # a killed maker's old file, taken again: not to be swept as a leftover meanwhile
        yield
    finally:
        if fd is not None:
            with contextlib.suppress(OSError):
                lock.unlink()  # before its lock ends: a run opening it still finds the store whole
            os.close(fd)


def _wait_for_maker(path: Path) -> None:
    """An empty file, or an SQLite file without tables, at a store's path may be a store another run is making in
    place (a file system without hard links, :meth:`ResultStore.open`): wait for that run's first transaction
    to end (its lock), so that the file is checked once made. Nothing is written; a file nobody is making is
    checked (and refused) as it is."""
    try:
        if path.stat().st_size:
            ro = _connect(path, readonly=True)
            try:
                if ro.execute("SELECT 1 FROM sqlite_master").fetchone() is not None:
                    return
            finally:
                ro.close()
        if CAN_FLOCK:  # a maker holds its lock from before the file exists (_making)
            try:
                fd = os.open(_making_path(path), os.O_RDONLY)
            except OSError:  # none: nobody is making it, or its maker is done
                pass
            else:
                try:
                    lock_fd(fd, MAKING_TIMEOUT, shared=True)
                finally:
                    os.close(fd)
        conn = _connect(path)
        try:
            conn.execute("BEGIN IMMEDIATE")  # waits (up to the timeout) for a maker's transaction
            conn.execute("ROLLBACK")
        finally:
            conn.close()
    except (OSError, sqlite3.Error, UnicodeDecodeError):  # not SQLite, damaged (a schema that is not UTF-8 too),
        pass                                                # locked past the timeout, not writable: the checks say


def _read_meta(conn: sqlite3.Connection, path: Path, reading: bool = False) -> dict[str, str]:
    """Check integrity, format and tables (read-only statements only) and return the meta table (``reading``: for a
    reader, whose refusals say what to give rather than that nothing was written)."""
    written = "" if reading else "nothing was written to it; "
    damaged = "restore it from a copy" if reading else _DAMAGED
    try:
        ok = conn.execute("PRAGMA quick_check").fetchone()
        if ok is None or ok[0] != "ok":
            raise StoreError(f"{path} is damaged (SQLite integrity check: {ok[0] if ok else 'no answer'}); "
                             f"{written}{damaged}")
        tables = {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
        if not {"meta", "cells"} <= tables:
            raise StoreError(f"{path} is an SQLite database but not a graybox grid store (tables: "
                             f"{sorted(tables) or 'none'}); {_not_a_store(reading)}")
        meta = dict(conn.execute("SELECT key, value FROM meta").fetchall())
        cols = [r[1] for r in conn.execute("PRAGMA table_info(cells)")]
    except (sqlite3.DatabaseError, UnicodeDecodeError) as exc:
        # a schema damaged into bytes that are not UTF-8: SQLite's message quotes them, which Python cannot decode
        why = exc if isinstance(exc, sqlite3.Error) else f"its schema is not UTF-8 text: {exc}"
        raise StoreError(f"{path} is damaged or not a graybox grid store ({why}); {written}{damaged}") from None
    if meta.get("format") != FORMAT:
        raise StoreError(f"{path} is an SQLite database but not a graybox grid store (no format mark); "
                         f"{_not_a_store(reading)}")
    fv = meta.get("format_version")
    if fv not in READS:
        if _newer(fv, FORMAT_VERSION):
            raise StoreError(f"{path} was written by a newer graybox (store format {fv}, graybox "
                             f"{meta.get('graybox_version')}); this graybox reads formats {', '.join(READS)}. "
                             "Upgrade graybox to read or grow it" + ("" if reading else "; nothing was written to it"))
        raise StoreError(f"{path} is a graybox store of unknown format {fv!r}; this graybox reads formats "
                         f"{', '.join(READS)}" + ("" if reading else "; nothing was written to it"))
    if cols != list(COLUMNS):
        raise StoreError(f"{path}: the cells table has columns {cols}, expected {list(COLUMNS)}: damaged or "
                         f"written by another graybox; {damaged}")
    if fv != "1" and not {"specs", "spec_cells"} <= tables:
        raise StoreError(f"{path} is damaged: a store of format {fv} without its specs tables; {damaged}")
    return meta


def _check_held(conn: sqlite3.Connection, p: Path, cells: Sequence[Cell]) -> None:
    """A StoreError (for a run: nothing was written) when a row the store holds of ``cells``, which a run reuses,
    does not read back as every report reads it (:func:`_decode_row`): the run reused it and counted it ok, or in
    no status, and every report then refused the store."""
    keys = list(dict.fromkeys(c.key for c in cells))
    for i in range(0, len(keys), 500):  # SQLite's bound on a statement's parameters
        part = keys[i:i + 500]
        cur = conn.execute(f"SELECT {', '.join(COLUMNS)} FROM cells WHERE key IN ({', '.join('?' * len(part))})", part)
        for r in cur.fetchall():
            _decode_row(dict(zip(COLUMNS, r)), p, reading=False)


def _damaged(p: Path, what: str, reading: bool) -> StoreError:
    """A store whose text SQLite's integrity check cannot judge (a spec's or a cell's JSON) does not read back."""
    return StoreError(f"{p} is damaged: {what}; " + ("restore it from a copy" if reading else
                                                     f"nothing was written to it; {_DAMAGED}"))


def _json_of(text: Any, p: Path, what: str, kind: type, reading: bool = True) -> Any:
    """The JSON ``text`` of a store's column, decoded and of ``kind``, or a StoreError naming ``what`` it is."""
    try:
        v = json.loads(text)
    except (TypeError, ValueError) as exc:
        raise _damaged(p, f"{what} is not JSON ({exc})", reading) from None
    if not isinstance(v, kind):
        raise _damaged(p, f"{what} is {type(v).__name__}, not {kind.__name__}", reading)
    return v


def _stored_band(band: Any) -> bool:
    """Whether a stored spec's data set band is one a DataSpec holds: None, or a real number > 0."""
    return band is None or (isinstance(band, (int, float)) and not isinstance(band, bool) and band > 0)


def _specs(conn: sqlite3.Connection, meta: Mapping[str, str], p: Path, reading: bool = True) -> list[dict[str, Any]]:
    """The store's specs, oldest first (a first-format store: the one grid its meta names); their JSON checked."""
    if meta.get("format_version") == "1":
        created = meta.get("created", "")
        specs = [{"id": 1, "name": meta.get("grid_name", "grid"), "fingerprint": meta.get("grid_fingerprint", ""),
                  "spec": meta.get("grid_spec", "{}"), "data": "{}", "graybox_version": meta.get("graybox_version", ""),
                  "created": created, "last_run": created, "n_cells": int(meta.get("n_cells", 0))}]
    else:
        cur = conn.execute(f"SELECT {', '.join(SPECS)} FROM specs ORDER BY id")
        specs = [dict(zip(SPECS, r)) for r in cur.fetchall()]
    for s in specs:
        spec = _json_of(s["spec"], p, f"spec {s['id']}'s canonical form", dict, reading)
        # its data sets give every cell's row its band (_spec_bands): a list of tables, each band > 0 or none
        sets = spec.get("data", [])
        if not isinstance(sets, list) or not all(_stored_band(d.get("band")) for d in sets if isinstance(d, dict)):
            raise _damaged(p, f"spec {s['id']}'s data sets are not a list of tables whose band is a number > 0 or "
                           "none", reading)
        data = _json_of(s["data"], p, f"spec {s['id']}'s data set hashes", dict, reading)
        if not all(isinstance(v, str) for v in data.values()):
            raise _damaged(p, f"spec {s['id']}'s data set hashes are not text", reading)
    return specs


def _settings(conn: sqlite3.Connection) -> None:
    """Durable against a killed process (WAL), where an fsync per cell would only guard against
    power loss; the log folded into the database every WAL_PAGES pages, not SQLite's 1000, so that
    closing the store, which folds what is left while every worker waits, stays short. (Read the
    schema: only on a file already checked.)"""
    conn.execute("PRAGMA synchronous=NORMAL")
    conn.execute(f"PRAGMA wal_autocheckpoint={WAL_PAGES}")


#: Seconds a statement waits for another connection's write lock on a store (SQLite's busy timeout).
LOCK_TIMEOUT = 30.0


def _begin(conn: sqlite3.Connection, p: Path, running: bool = False) -> None:
    """``BEGIN IMMEDIATE`` on the store ``p``, or a StoreError when another program keeps its write lock past
    :data:`LOCK_TIMEOUT` (``running``: a run that has committed cells already, which it keeps)."""
    try:
        conn.execute("BEGIN IMMEDIATE")
    except sqlite3.OperationalError as exc:
        if getattr(exc, "sqlite_errorcode", 0) & 0xFF not in (sqlite3.SQLITE_BUSY, sqlite3.SQLITE_LOCKED):
            raise
        kept = ("the cells finished so far are kept, and the same command runs only the cells left" if running
                else "nothing was written to it")
        raise StoreError(f"{p} has been locked by another program for {LOCK_TIMEOUT:g} s ({exc}: a connection "
                         f"holding a write transaction, e.g. an SQLite browser with unsaved changes); {kept}. "
                         "Close that connection, then run again") from None


def _cannot_open(exc: sqlite3.Error) -> bool:
    """Whether SQLite could not open a file it needs (the database, or the log or its index beside it)."""
    return getattr(exc, "sqlite_errorcode", 0) & 0xFF == sqlite3.SQLITE_CANTOPEN


def _connect(path: Path, readonly: bool = False) -> sqlite3.Connection:
    if not readonly:
        return sqlite3.connect(str(path), timeout=LOCK_TIMEOUT, isolation_level=None)  # explicit transactions
    uri = path.resolve().as_uri()
    conn = sqlite3.connect(uri + "?mode=ro", uri=True, timeout=LOCK_TIMEOUT, isolation_level=None)
    try:
        conn.execute("SELECT 1 FROM sqlite_master LIMIT 1")
    except sqlite3.OperationalError as exc:
        # a store in a folder this process cannot write in (an archive, a colleague's results): a WAL store is read
        # through an index (-shm) made beside it, which cannot be made there. With no log beside it (no run has it
        # open, every write is in the file) nothing can change it meanwhile: read as it is, without the index
        wal = Path(f"{path}-wal")
        if not _cannot_open(exc):
            return conn  # what the caller's first statement says
        conn.close()
        if wal.exists() and wal.stat().st_size:
            raise StoreError(f"{path} cannot be read where it is: its folder is read-only to this process and its log "
                             f"{wal.name} holds writes not yet in the store; copy the store and {wal.name} together "
                             "into a folder you can write in and read the copy") from None
        return sqlite3.connect(uri + "?mode=ro&immutable=1", uri=True, timeout=LOCK_TIMEOUT, isolation_level=None)
    except (sqlite3.Error, UnicodeDecodeError):  # not SQLite, damaged (a schema that is not UTF-8): the caller's
        pass                                      # checks say so (_read_meta)
    return conn


def _connect_to_write(path: Path, store: Path, verb: str) -> sqlite3.Connection:
    """A writing connection to ``path`` for the store at ``store``, or a StoreError saying what to do (``verb``:
    "open" or "create")."""
    try:
        return _connect(path)
    except sqlite3.OperationalError as exc:  # e.g. a folder this user cannot write in
        raise StoreError(f"cannot {verb} the store {store} ({exc}); choose a --store path in a folder you can "
                         "write in") from None


def _refuse_unwritable(exc: BaseException, store: Path) -> None:
    """A StoreError for SQLite's refusal to write a store whose file or folder is read-only (its own words name
    neither the file nor what to do); nothing else."""
    code = getattr(exc, "sqlite_errorcode", 0) & 0xFF
    if isinstance(exc, sqlite3.OperationalError) and code in (sqlite3.SQLITE_READONLY, sqlite3.SQLITE_CANTOPEN):
        raise StoreError(f"cannot write the store {store} ({exc}): the file or its folder is read-only to this "
                         "process; nothing was written to it. Make them writable, or choose a --store path in a "
                         "folder you can write in (a copy of the store there keeps its cells)") from None


def _table(name: str, cols: Mapping[str, str], extra: str = "") -> str:
    return f"CREATE TABLE {name} ({', '.join(f'{k} {t}' for k, t in cols.items())}{extra})"


def _data_hashes(cells: Sequence[Cell]) -> dict[str, str]:
    return {c.data: c.data_hash for c in cells}


def _check_growth(p: Path, specs: list[dict[str, Any]], cells: Sequence[Cell], version: str) -> None:
    """Refuse (before anything is written) a spec that a store cannot take."""
    for s in specs:
        if _newer(s["graybox_version"], version):
            raise StoreError(f"{p} holds cells of graybox {s['graybox_version']} (spec {s['id']} {s['name']!r}), "
                             f"newer than this graybox {version}: upgrade graybox to grow it, or choose another "
                             "--store path; nothing was written to it")
    known: dict[str, tuple[str, dict]] = {}
    for s in specs:
        for name, h in json.loads(s["data"]).items():
            known.setdefault(name, (h, s))
    for name, h in _data_hashes(cells).items():
        if name in known and known[name][0] != h:
            old, s = known[name]
            raise StoreError(
                f"{p}: data set {name!r} of this spec reads other data than the data set {name!r} in the store "
                f"(content hash {h} now, {old} in spec {s['id']} {s['name']!r} of {s['created']}). A store gives "
                f"a data set name one meaning: if the files changed on purpose, give the data set a new name (it "
                f"then runs as a new data set beside the old one) or choose another --store path; if not, point "
                f"{name!r} back at the files it was run on. Nothing was written to the store")


class ResultStore:
    """An open store with one spec registered: which cells it holds; write a finished cell.

    Use :meth:`open`; close with :meth:`close` (or ``with``).

    Attributes
    ----------
    path : Path
    spec_id : int
        The spec's number in the store (1 = the first spec run on it).
    new_spec : bool
        Whether the spec was new to the store (False: the same grid run again, e.g. to resume).
    known_data : dict
        Data set names the store held before, by content hash.
    band_changes : dict
        Data set name -> (its band in the store's spec of the same cells, this spec's), where they differ.
    unit_changes : dict
        Data set name -> (its output's unit in the store's spec of the same cells, this spec's; "" for none), where
        they differ.
    """

    def __init__(self, path: Path, conn: sqlite3.Connection, meta: Mapping[str, str], spec_id: int, new_spec: bool,
                 known_data: Mapping[str, str],
                 band_changes: Mapping[str, tuple[float | None, float | None]] | None = None,
                 unit_changes: Mapping[str, tuple[str, str]] | None = None):
        self.path = path
        self._conn = conn
        self.meta = dict(meta)
        self.spec_id = spec_id
        self.new_spec = new_spec
        self.known_data = dict(known_data)
        self.band_changes = dict(band_changes or {})
        self.unit_changes = dict(unit_changes or {})
        self._owner: str | None = None

    @classmethod
    def open(cls, path: str | os.PathLike, *, grid_name: str, fingerprint: str, spec: Mapping[str, Any],
             cells: Sequence[Cell], version: str) -> "ResultStore":
        """Create the store, or open an existing one and register the spec (its cells and names).

        Raises
        ------
        StoreError
            The file is not a graybox store, is damaged, was written by a newer graybox, a data
            set name of the spec reads other data than the store's data set of that name, or a
            first-format store is asked to take a grid other than its own.
        """
        p = Path(path)
        exists = p.exists()
        if not exists and not p.parent.exists():
            raise StoreError(f"{p.parent} does not exist; create the folder for the store first")
        if not exists and not p.parent.is_dir():
            raise StoreError(f"{p.parent} is a file, not a folder; give a store path inside a folder")
        _sweep_leftovers(p)
        if not exists and _create_whole(p, version):  # made whole, by this run or another started with it
            return cls.open(p, grid_name=grid_name, fingerprint=fingerprint, spec=spec, cells=cells, version=version)
        migrate = False
        known: dict[str, str] = {}
        if exists:
            if p.is_dir():
                raise StoreError(f"{p} is a folder; give a file path for the store")
            _wait_for_maker(p)
            _check_file(p)
            # checked through a read-only connection: closing it folds no log left by a killed writer
            ro = _connect(p, readonly=True)
            try:
                meta = _read_meta(ro, p)
                if meta["format_version"] == "1":
                    if meta.get("grid_fingerprint") != fingerprint:
                        n = ro.execute("SELECT COUNT(*) FROM cells").fetchone()[0]
                        head = (f"{p} is a store of the first format (graybox {meta.get('graybox_version')}), which "
                                f"holds one grid ({meta.get('grid_name')!r}, {n} cell(s))")
                        if meta.get("graybox_version") != version:
                            # its own spec, run by this graybox, has other keys (cells are keyed by version), so
                            # another fingerprint: it is refused as any other grid, and "run its own spec" never held
                            raise StoreError(
                                f"{head}; it was written by graybox {meta.get('graybox_version')}, this is {version}: "
                                "cells are keyed by version, so this graybox can neither resume nor grow it (its "
                                "grid's cells, run by this graybox, are new ones). It can be read (load_results, "
                                "graybox grid report); run the spec into another --store path; nothing was written "
                                "to it")
                        raise StoreError(
                            f"{head}. It can be read (load_results, graybox grid report) and resumed by its own spec, "
                            "which upgrades it so that it can grow; this is another grid. Run the store's own spec on "
                            "it first, or choose another --store path; nothing was written to it")
                    migrate = True
                else:
                    specs = _specs(ro, meta, p, reading=False)
                    _check_growth(p, specs, cells, version)
                    # a spec's row deleted (an SQLite browser): its number, which its cells keep, would be the next
                    # spec's, whose cells then clashed with them (sqlite3.IntegrityError, a traceback)
                    lost = [r[0] for r in ro.execute("SELECT DISTINCT spec FROM spec_cells WHERE spec NOT IN "
                                                     "(SELECT id FROM specs) ORDER BY spec")]
                    if lost:
                        raise _damaged(p, f"its spec_cells table holds the cells of spec(s) {lost}, which its specs "
                                       "table lacks", False)
                    for s in specs:
                        for name, h in json.loads(s["data"]).items():
                            known.setdefault(name, h)
                _check_held(ro, p, cells)
            except sqlite3.DatabaseError as exc:
                raise StoreError(f"{p} is damaged ({exc}); nothing was written to it; {_DAMAGED}") from None
            finally:
                ro.close()
        made_before = exists
        # made in place (a file system without hard links, _create_whole), the file appears at the connect and is
        # locked a statement later: the maker's lock beside it (_making) is held from before the file exists
        with contextlib.nullcontext() if exists else _making(p):
            conn = _connect_to_write(p, p, "open")
            try:
                if exists:
                    _settings(conn)
                else:
                    # the tables in the file's first transaction, WAL after: until it commits, the file stays empty
                    # and its lock held, which a run opening the path meanwhile waits for (_wait_for_maker)
                    conn.execute("BEGIN IMMEDIATE")
                    made_before = conn.execute("SELECT 1 FROM sqlite_master").fetchone() is not None
                    if made_before:  # by another run (started at once) since this one looked
                        conn.execute("ROLLBACK")
                        conn.close()
                    else:
                        meta = _create_tables(conn, version)
                        conn.execute("COMMIT")
                        conn.execute("PRAGMA journal_mode=WAL")
                        _settings(conn)
            except BaseException as exc:
                conn.close()
                _refuse_unwritable(exc, p)
                raise
        if not exists and made_before:  # the other run's store: opened as it is, checked
            return cls.open(p, grid_name=grid_name, fingerprint=fingerprint, spec=spec, cells=cells, version=version)
        try:
            if migrate:
                _upgrade(conn, p, meta, cells)
                meta["format_version"] = FORMAT_VERSION
            spec_id, new, changed, unit_changes = _register(conn, p, grid_name, fingerprint, spec, cells, version)
        except BaseException as exc:
            conn.close()
            _refuse_unwritable(exc, p)
            raise
        return cls(p, conn, meta, spec_id, new, known, changed, unit_changes)

    @contextlib.contextmanager
    def running(self):
        """While ``run_grid`` runs into this store: a run its callbacks start on the same store (in this thread)
        does not wait for this one's cells."""
        stores = getattr(_RUNS_HERE, "stores", None)
        if stores is None:
            stores = _RUNS_HERE.stores = []
        stores.append(self)
        try:
            yield self
        finally:
            stores.remove(self)

    def claim(self, keys: Sequence[str]) -> dict[str, str]:
        """Take the cells of ``keys`` for this run, but those a live driver of another run has taken.

        Returns those, each with its driver in words ("pid 123 on host h"). A driver that is gone
        (killed, or silent for :data:`STALE_SECONDS` on another host) loses its cells. A cell's
        claim ends when its row is written, and every claim when the store is closed.
        """
        return self._claims(keys, take=True)

    def held(self, keys: Sequence[str]) -> dict[str, str]:
        """Those of ``keys`` a live driver of another run holds, each with its driver in words, as :meth:`claim`
        says them, but taking none: a run that waits for them looks without holding what it does not start yet
        (a dead driver's claims end here too)."""
        return self._claims(keys, take=False)

    def _claims(self, keys: Sequence[str], take: bool) -> dict[str, str]:
        host, pid, now = socket.gethostname(), os.getpid(), time.time()
        _begin(self._conn, self.path, running=True)
        try:
            self._conn.execute(_table("drivers", DRIVERS).replace("CREATE TABLE", "CREATE TABLE IF NOT EXISTS"))
            self._conn.execute(_table("claims", CLAIMS).replace("CREATE TABLE", "CREATE TABLE IF NOT EXISTS"))
            if self._owner is None:
                self._owner = secrets.token_hex(8)
                _OPEN_OWNERS.add(self._owner)
            self._conn.execute("INSERT OR REPLACE INTO drivers VALUES (?, ?, ?, ?)", (self._owner, host, pid, now))
            drivers = self._conn.execute("SELECT owner, host, pid, beat FROM drivers").fetchall()
            outer = _outer_runs()  # never waited for: they wait for this one to return
            gone = [(o,) for o, h, p, b in drivers if o != self._owner and (o in outer or not _alive(o, h, p, b, now))]
            self._conn.executemany("DELETE FROM drivers WHERE owner = ?", gone)
            self._conn.execute("DELETE FROM claims WHERE owner NOT IN (SELECT owner FROM drivers)")
            if take:
                self._conn.executemany("INSERT OR IGNORE INTO claims VALUES (?, ?)", [(k, self._owner) for k in keys])
            who = {o: _driver_name(h, p) for o, h, p, _ in drivers}
            held = dict(self._conn.execute("SELECT key, owner FROM claims WHERE owner != ?", (self._owner,)))
        except BaseException:
            self._conn.execute("ROLLBACK")
            raise
        self._conn.execute("COMMIT")
        return {k: who[held[k]] for k in keys if k in held}

    def unclaim(self, keys: Sequence[str] | None = None) -> None:
        """End this run's claims on ``keys``; ``None``: all of them, and the run's ``drivers`` row (an empty
        sequence ends none: the cells a run has just taken stay taken when none of the others is let go)."""
        if self._owner is None or (keys is not None and not keys):
            return
        _begin(self._conn, self.path, running=True)
        try:
            if keys is not None:
                self._conn.executemany("DELETE FROM claims WHERE key = ? AND owner = ?",
                                       [(k, self._owner) for k in keys])
            else:
                self._conn.execute("DELETE FROM claims WHERE owner = ?", (self._owner,))
                self._conn.execute("DELETE FROM drivers WHERE owner = ?", (self._owner,))
        except BaseException:
            self._conn.execute("ROLLBACK")
            raise
        self._conn.execute("COMMIT")
        if keys is None:
            _OPEN_OWNERS.discard(self._owner)
            self._owner = None

    @contextlib.contextmanager
    def beating(self):
        """While the block runs, write this run's beat every tenth of :data:`STALE_SECONDS` (its own connection,
        in a thread): a driver busy with long cells writes no row for a long time, and a run on another host
        would take it for dead and run its cells again."""
        stop = threading.Event()

        def beat() -> None:
            conn = _connect(self.path)
            try:
                while not stop.wait(STALE_SECONDS / 10):
                    owner = self._owner
                    if owner is not None:
                        try:
                            conn.execute("UPDATE drivers SET beat = ? WHERE owner = ?", (time.time(), owner))
                        except sqlite3.Error:  # a store busy past the timeout: the next beat
                            pass
            finally:
                conn.close()

        t = threading.Thread(target=beat, name="graybox store beat", daemon=True)
        t.start()
        try:
            yield
        finally:
            stop.set()
            t.join()

    def marks(self, keys: Sequence[str] | None = None) -> dict[str, tuple[str, str | None]]:
        """Status and finishing time of every cell the store holds (``keys``: of those among them), by key: a
        row written over one (a failed cell retried) changes its mark even where the status stays the same."""
        if keys is None:
            return {k: (s, t) for k, s, t in self._conn.execute("SELECT key, status, finished_at FROM cells")}
        out: dict[str, tuple[str, str | None]] = {}
        keys = list(keys)
        for i in range(0, len(keys), 500):  # SQLite takes at most 999 parameters in a statement (older builds)
            part = keys[i:i + 500]
            out.update((k, (s, t)) for k, s, t in self._conn.execute(
                f"SELECT key, status, finished_at FROM cells WHERE key IN ({', '.join('?' * len(part))})", part))
        return out

    def write(self, row: Mapping[str, Any], replace: bool = False) -> bool:
        """Commit one finished cell (``replace``: overwrite a failed row of the same key).

        Returns False when the store already holds the cell (another run on the store wrote it
        since this one looked): a cell is its content, so that row is kept.
        """
        values = [encode_value(k, row.get(k)) for k in COLUMNS]
        verb = "INSERT OR REPLACE" if replace else "INSERT OR IGNORE"
        _begin(self._conn, self.path, running=True)
        try:
            cur = self._conn.execute(f"{verb} INTO cells ({', '.join(COLUMNS)}) "
                                     f"VALUES ({', '.join('?' * len(COLUMNS))})", values)
            if self._owner is not None:  # the cell is no longer taken, and this run is alive
                self._conn.execute("DELETE FROM claims WHERE key = ? AND owner = ?", (row.get("key"), self._owner))
                self._conn.execute("UPDATE drivers SET beat = ? WHERE owner = ?", (time.time(), self._owner))
        except BaseException:
            self._conn.execute("ROLLBACK")
            raise
        self._conn.execute("COMMIT")
        return cur.rowcount == 1

    def made_by_other_versions(self, cells: Sequence[Cell], version: str) -> dict[str, int]:
        """How many of ``cells`` (each key once) the store holds as another graybox version made them (the same data,
        structure, variant and seed under that version's key), by version: cells are keyed by version, so those
        run again."""
        made: dict[tuple, set[str]] = {}
        for dh, sh, vh, seed, v in self._conn.execute(
                "SELECT DISTINCT s.data_hash, s.structure_hash, s.variant_hash, s.seed, c.version FROM spec_cells s "
                "JOIN cells c ON c.key = s.key WHERE c.version != ?", (version,)):
            made.setdefault((dh, sh, vh, seed), set()).add(v)
        out: dict[str, int] = {}
        for c in {c.key: c for c in cells}.values():
            for v in made.get((c.data_hash, _hash(c.structure_spec), _hash(c.variant_spec), c.seed), ()):
                out[v] = out.get(v, 0) + 1
        return out

    def counts(self) -> dict[str, int]:
        """The registered spec's cells by status (a cell two data set names of the same data share counts for each)."""
        return dict(self._conn.execute(
            "SELECT c.status, COUNT(*) FROM spec_cells s JOIN cells c ON c.key = s.key WHERE s.spec = ? "
            "GROUP BY c.status", (self.spec_id,)).fetchall())

    def close(self) -> None:
        """End this run's claims and close the connection."""
        try:
            self.unclaim()
        except (sqlite3.Error, StoreError):  # closing must not fail on a store it cannot write: the claims die with the run
            pass
        finally:
            if self._owner is not None:  # its row, left in the store, is known for a dead run's (_alive)
                _OPEN_OWNERS.discard(self._owner)
                self._owner = None
            self._conn.close()

    def __enter__(self) -> "ResultStore":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _create_tables(conn: sqlite3.Connection, version: str) -> dict[str, str]:
    """A new store's tables and meta (inside the caller's transaction); returns the meta."""
    meta = {"format": FORMAT, "format_version": FORMAT_VERSION, "graybox_version": version, "created": _now()}
    conn.execute("CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)")
    conn.execute(_table("cells", COLUMNS))
    conn.executemany("INSERT INTO meta VALUES (?, ?)", list(meta.items()))
    _create_spec_tables(conn)
    return meta


def _sweep_leftovers(p: Path) -> None:
    """Remove the half-made stores (and their -wal, -shm), and the making lock (:func:`_making`), that a run killed
    while making the store at ``p`` left: those older than ``core._files.LEFTOVER_SECONDS`` on the folder's clock."""
    try:
        now = folder_now(p.parent)
    except OSError:  # a folder this user cannot write in: nothing in it can be removed either
        return
    sweep_leftovers(p.parent, re.compile(rf"\.{re.escape(p.name)}\.([0-9a-f]{{8}}\.new(-wal|-shm)?|making)"), now)


def _create_whole(p: Path, version: str) -> bool:
    """Make a new store at ``p`` under a name of its own beside it, then link it into place, so that no other run
    ever sees it half made (made in place, a run started at the same moment found an empty file, or an SQLite file
    without tables, and refused it). A store another run linked there first is left to be opened. False where
    the file system has no hard links (the caller makes the store in place)."""
    tmp = p.with_name(f".{p.name}.{secrets.token_hex(4)}.new")
    try:
        conn = _connect_to_write(tmp, p, "create")
        try:
            conn.execute("PRAGMA journal_mode=WAL")
            conn.execute("BEGIN IMMEDIATE")
            _create_tables(conn, version)
            conn.execute("COMMIT")
        finally:
            conn.close()  # the last connection: its log folded into the file, which is then whole
        try:
            os.link(tmp, p)
        except FileExistsError:  # another run linked its store first, that one is the store; or a dangling link
            return p.exists()
        except OSError:
            return False
        return True
    finally:
        for f in (tmp, Path(f"{tmp}-wal"), Path(f"{tmp}-shm")):
            with contextlib.suppress(OSError):  # a read-only file system refuses even to unlink what is not there
                f.unlink(missing_ok=True)


def _create_spec_tables(conn: sqlite3.Connection) -> None:
    conn.execute(_table("specs", SPECS))
    conn.execute(_table("spec_cells", SPEC_CELLS, ", PRIMARY KEY (spec, position)"))
    conn.execute("CREATE INDEX spec_cells_key ON spec_cells (key)")


def _spec_cell_rows(spec_id: int, cells: Sequence[Cell]) -> list[tuple]:
    return [(spec_id, i, c.key, c.data, c.structure, c.variant, c.seed, c.data_hash, _hash(c.structure_spec),
             _hash(c.variant_spec)) for i, c in enumerate(cells)]


def _upgrade(conn: sqlite3.Connection, p: Path, meta: Mapping[str, str], cells: Sequence[Cell]) -> None:
    """A first-format store run again by its own grid (same fingerprint, so the same cells and
    data): its grid becomes spec 1, in one transaction."""
    _begin(conn, p)
    try:
        if conn.execute("SELECT value FROM meta WHERE key = 'format_version'").fetchone() != ("1",):
            conn.execute("ROLLBACK")  # another run of the same grid upgraded it since this one looked
            return
        _create_spec_tables(conn)
        created = meta.get("created", _now())
        conn.execute(f"INSERT INTO specs ({', '.join(SPECS)}) VALUES ({', '.join('?' * len(SPECS))})",
                     (1, meta.get("grid_name", "grid"), meta["grid_fingerprint"], meta.get("grid_spec", "{}"),
                      json.dumps(_data_hashes(cells), sort_keys=True), meta.get("graybox_version", ""), created,
                      created, len(cells)))
        conn.executemany(f"INSERT INTO spec_cells VALUES ({', '.join('?' * len(SPEC_CELLS))})",
                         _spec_cell_rows(1, cells))
        conn.execute("UPDATE meta SET value = ? WHERE key = 'format_version'", (FORMAT_VERSION,))
        conn.execute("INSERT OR REPLACE INTO meta VALUES ('upgraded', ?)", (_now(),))
    except BaseException:
        conn.execute("ROLLBACK")
        raise
    conn.execute("COMMIT")


def _register(conn: sqlite3.Connection, p: Path, grid_name: str, fingerprint: str, spec: Mapping[str, Any],
              cells: Sequence[Cell], version: str) -> tuple[int, bool, dict[str, tuple[float | None, float | None]],
                                                            dict[str, tuple[str, str]]]:
    """(spec id, new, bands changed: data set name -> (band of the spec of the same cells, this one's), output units
    changed: the same with units): the spec's row and its cells, written before any of them runs.

    The same cells under the same names with other bands (no variant reading them: the cells' keys do not say them)
    are another spec: the rows read back, and the reports rank, with the band of the spec they are read with."""
    _begin(conn, p)
    try:
        # checked again under the write lock: a run started meanwhile may have given a data set name of this spec
        # other data since this one looked (the first look, read-only, refuses without waiting for any lock)
        _check_growth(p, _specs(conn, {"format_version": FORMAT_VERSION}, p, reading=False), cells, version)
        row = conn.execute("SELECT id, spec FROM specs WHERE fingerprint = ?", (fingerprint,)).fetchone()
        bands = _spec_bands({"spec": json.dumps(spec)})
        changed: dict[str, tuple[float | None, float | None]] = {}
        old = None if row is None else _spec_bands({"spec": row[1]})
        # the output's unit is in no cell's key (the same numbers), but every report says it: a spec that says another
        # than the stored spec named is another spec (one that named none, also a spec stored before specs kept
        # units, is not contradicted)
        old_units = {} if row is None else _spec_units(json.loads(row[1]))
        units = _spec_units(spec)
        unit_changes = {k: (old_units[k], u) for k, u in units.items() if old_units.get(k) not in ("", None, u)}
        if old is not None and (old != bands or unit_changes):
            changed = {k: (old.get(k), b) for k, b in bands.items() if old.get(k) != b}
            # (a fingerprint whose bands alone differ is hashed as before)
            fingerprint = _hash({"grid": fingerprint, "bands": bands, **({"y_units": units} if unit_changes else {})})
            row = conn.execute("SELECT id, spec FROM specs WHERE fingerprint = ?", (fingerprint,)).fetchone()
        now = _now()
        if row is not None:
            spec_id, new = int(row[0]), False
            conn.execute("UPDATE specs SET last_run = ? WHERE id = ?", (now, spec_id))
        else:
            cur = conn.execute(
                "INSERT INTO specs (name, fingerprint, spec, data, graybox_version, created, last_run, n_cells) "
                "VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                (grid_name, fingerprint, json.dumps(spec, sort_keys=True),
                 json.dumps(_data_hashes(cells), sort_keys=True), version, now, now, len(cells)))
            spec_id, new = int(cur.lastrowid), True
            conn.executemany(f"INSERT INTO spec_cells VALUES ({', '.join('?' * len(SPEC_CELLS))})",
                             _spec_cell_rows(spec_id, cells))
    except BaseException:
        conn.execute("ROLLBACK")
        raise
    conn.execute("COMMIT")
    return spec_id, new, changed, unit_changes


def _spec_units(spec: Mapping[str, Any]) -> dict[str, str]:
    """Each data set's output unit in a canonical spec (:func:`graybox.experiments._spec.stored_spec`), by name
    ("" where it names none)."""
    return {d["name"]: d.get("y_unit", "") for d in spec.get("data", []) if isinstance(d, Mapping) and "name" in d}


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


#: The columns of figures, read as float.
_FLOAT_COLUMNS = ("lambda1", "band", "J1_ident", "JS_ident", "fit_ident", "J1_valid", "JS_valid", "fit_valid", "JSF",
                  "static_miss", "wall_time")


#: The figures every cell's members hold since the first store (``fit_valid`` came later; ``failure`` is text).
_MEMBER_FIGURES = ("lambda1", "J1", "JS", "JSF", "JS_valid")


def _decode_members(d: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """A cell's members (decoded JSON) as arrays of floats and the list of failures, one entry per member each;
    ``ValueError`` naming what a damaged cell's members lack (the reports read them all, and failed on one missing or
    of another length with a bare KeyError, TypeError or pandas' words)."""
    missing = [k for k in _MEMBER_FIGURES if k not in d]
    if missing:
        raise ValueError(f"members without {', '.join(missing)}")
    out: dict[str, Any] = {}
    for k, v in d.items():
        if k == "failure":
            if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
                raise ValueError("members' failure is not a list of texts, one per member")
            out[k] = list(v)
            continue
        a = np.array(v, dtype=float)
        if a.ndim != 1:
            raise ValueError(f"members' {k} is not a list of numbers, one per member")
        out[k] = a
    lengths = {k: len(v) for k, v in out.items()}
    if len(set(lengths.values())) > 1:
        raise ValueError(f"members' lists have different lengths {lengths}")
    return out


def _open_readonly(path: str | os.PathLike) -> tuple[Path, sqlite3.Connection, dict[str, str]]:
    p = Path(check_path(path, "store", file=True))
    if not p.is_file():
        raise StoreError(f"{p}: no such store" + (" (a folder)" if p.is_dir() else ""))
    _check_file(p, reading=True)
    conn = _connect(p, readonly=True)  # closing it folds no log left by a killed writer into the file
    try:
        return p, conn, _read_meta(conn, p, reading=True)
    except BaseException:
        conn.close()
        raise


def _pick(specs: list[dict[str, Any]], spec: str | int, p: Path) -> dict[str, Any] | None:
    """The spec record ``spec`` names ("latest": the one run last; "all": None)."""
    if isinstance(spec, str):
        if spec == "all":
            return None
        if spec != "latest":
            raise ValueError(f"spec must be 'latest', 'all' or a spec number, got {spec!r}")
    elif isinstance(spec, bool) or not isinstance(spec, (int, np.integer)):
        raise TypeError(f"spec must be 'latest', 'all' or a spec number (int), got {type(spec).__name__}")
    if not specs:  # made whole, and the run that made it has not registered its spec: yet, or it stopped first
        raise StoreError(f"{p} is a grid store that holds no spec yet: the run that made it is starting (it registers "
                         "its grid a moment after it makes the store: look again), or it stopped before it registered "
                         "it (run a spec on it)")
    if isinstance(spec, str):  # "latest"
        return max(specs, key=lambda s: (s["last_run"], s["id"]))
    for s in specs:
        if s["id"] == int(spec):
            return s
    raise ValueError(f"{p} has no spec {spec}; its specs are "
                     + ", ".join(f"{s['id']} ({s['name']!r})" for s in specs))


def read_store(path: str | os.PathLike, spec: str | int = "latest") -> tuple[dict[str, str], list[dict[str, Any]],
                                                                                list[dict[str, Any]], dict | None, int]:
    """(meta, specs, rows, the chosen spec record or None for "all", the cells of the choice: the spec's, or every
    cell a spec of the store holds, run or not) of a store, read-only.

    Rows of one spec carry that spec's names and grid positions (``cell_index``); rows of all
    specs carry the names of the first spec that ran each cell, a name that means different
    structures or variants in different specs followed by the spec that defined it, e.g. ``"PE
    (spec 2)"``.
    """
    p, conn, meta = _open_readonly(path)
    cols = ", ".join(f"c.{k}" for k in COLUMNS)
    try:
        specs = _specs(conn, meta, p)
        chosen = _pick(specs, spec, p)
        n = int(chosen["n_cells"]) if chosen is not None else None
        if meta["format_version"] == "1":
            cur = conn.execute(f"SELECT {cols} FROM cells c ORDER BY c.cell_index")
            rows = [dict(zip(COLUMNS, r)) for r in cur.fetchall()]
            n = int(specs[0]["n_cells"])
        elif chosen is not None:
            cur = conn.execute(f"SELECT {cols}, s.position, s.data, s.structure, s.variant FROM spec_cells s "
                               "JOIN cells c ON c.key = s.key WHERE s.spec = ? ORDER BY s.position", (chosen["id"],))
            rows = []
            bands = _spec_bands(chosen)
            for r in cur.fetchall():
                row = dict(zip(COLUMNS, r))
                row.update(zip(("cell_index", "data", "structure", "variant"), r[len(COLUMNS):]))
                row["band"] = bands.get(row["data"], row["band"])
                rows.append(row)
        else:
            # the cells the specs hold, run or not (a spec's cells not run yet are left, not absent), one under each
            # data set name its first spec gives it
            rows, n = _all_rows(conn, cols, {s["id"]: _spec_bands(s) for s in specs})
    except sqlite3.DatabaseError as exc:
        raise StoreError(f"{p} is damaged ({exc}); {_DAMAGED}") from None
    finally:
        conn.close()
    return meta, specs, rows, chosen, max(int(n), len(rows))


def _spec_bands(spec: Mapping[str, Any]) -> dict[str, float | None]:
    """Each data set's band in a stored spec, by name. A cell whose variant reads no band is keyed without it
    (:func:`graybox.experiments._spec.reads_band`) and kept once for every band: its row shows the band of the
    spec it is read with, not the one of the spec that ran it (read with every spec, the largest of theirs:
    :func:`_all_rows`)."""
    data = json.loads(spec["spec"]).get("data", [])
    return {d["name"]: d.get("band") for d in data if isinstance(d, Mapping) and "name" in d}


def _all_rows(conn: sqlite3.Connection, cols: str, bands: Mapping[int, Mapping[str, float | None]]
              ) -> tuple[list[dict[str, Any]], int]:
    """Every cell once under each data set name the first spec that holds it gives it (two data sets of one
    content share their band-free cells), named by that spec; names with two meanings told apart; and how many such
    rows the specs hold, run or not. Its band is the
    largest the specs holding it give its data set under the name the row shows (:func:`_spec_bands`): a cell that
    reads no band is one result under each of them, and a variant that reads it has a cell under each, whose members
    the leaderboard judges each by its own; judged by the first spec's band alone, the same Pareto set or model
    qualified in the one variant and not in the other."""
    entries = conn.execute("SELECT spec, position, key, data, structure, variant, structure_hash, variant_hash "
                           "FROM spec_cells ORDER BY spec, position").fetchall()
    # key -> the places the first spec holding it gives it: one cell is one result under each of its data set names
    # there (two data sets of one content, say with two bands, share their band-free cells)
    first: dict[str, list[tuple]] = {}
    held: dict[tuple[str, str], list[float | None]] = {}  # (key, data set name) -> each band a spec holding it gives
    meanings: dict[tuple[str, str], dict[str, int]] = {}  # (kind, name) -> content hash -> first spec
    for spec, pos, key, d, s, v, sh, vh in entries:
        places = first.setdefault(key, [])
        if not places or (places[0][0] == spec and all(p[2] != d for p in places)):
            places.append((spec, pos, d, s, v, sh, vh))
        if d in bands.get(spec, {}):
            held.setdefault((key, d), []).append(bands[spec][d])
        meanings.setdefault(("structure", s), {}).setdefault(sh, spec)
        meanings.setdefault(("variant", v), {}).setdefault(vh, spec)

    # a name of two meanings is shown with the spec that defined each, e.g. "PE (spec 2)"; where that is a name
    # some spec gives another structure or variant (or another label), with the content's hash too: one label, one
    # meaning (else the leaderboard held both in one group)
    labels: dict[tuple[str, str, str], str] = {}
    for kind in ("structure", "variant"):
        used = {n for (k, n), m in meanings.items() if k == kind and len(m) == 1}
        for (k, n), m in meanings.items():
            if k != kind or len(m) == 1:
                continue
            for h, first_spec in m.items():
                lab = f"{n} (spec {first_spec})"
                if lab in used:
                    lab = f"{n} (spec {first_spec}, {kind} {h[:12]})"
                while lab in used:
                    lab += "'"
                used.add(lab)
                labels[(kind, n, h)] = lab

    def label(kind: str, name: str, h: str) -> str:
        return labels.get((kind, name, h), name)

    rows = []
    for r in conn.execute(f"SELECT {cols} FROM cells c").fetchall():
        cell = dict(zip(COLUMNS, r))
        places = first.get(cell["key"])
        if not places:  # not reachable through the API: every cell is registered before it runs
            rows.append({**cell, "_order": (10**9, cell["cell_index"])})
            continue
        for spec, pos, d, s, v, sh, vh in places:
            row = dict(cell, data=d, structure=label("structure", s, sh), variant=label("variant", v, vh))
            # the bands given to the data set by the name the row shows (a data set renamed in a later spec keeps its
            # rows under the first name, ranked apart from the new name's)
            at = (row["key"], d)
            given = [b for b in held.get(at, ()) if b is not None]
            row["band"] = max(given) if given else None if at in held else row["band"]
            row["_order"] = (spec, pos)
            rows.append(row)
    rows.sort(key=lambda r: r.pop("_order"))
    for i, row in enumerate(rows):
        row["cell_index"] = i
    return rows, sum(len(p) for p in first.values())


def output_units(attrs: Mapping) -> dict[str, str]:
    """Each data set's output unit, by name, from the specs of the results' ``attrs`` (empty when the specs
    stored none: data without units, or a store written before the specs kept them): the spec read first (``attrs``'
    ``selection``), then the others, the one run last first (a spec that says its data's unit again, corrected, is
    the latest word on it; the first spec's was said of every spec read)."""
    if "y_units" in attrs:
        return dict(attrs["y_units"])
    out: dict[str, str] = {}
    sel = attrs.get("selection")
    infos = [i for i in attrs.get("specs", ()) if isinstance(i, Mapping)]
    infos.sort(key=lambda i: (isinstance(sel, (int, np.integer)) and i.get("id") == sel, str(i.get("last_run", "")),
                              i.get("id") if isinstance(i.get("id"), int) else 0), reverse=True)
    for info in infos:
        spec = info.get("spec")
        for d in (spec.get("data", ()) if isinstance(spec, Mapping) else ()):
            if isinstance(d, Mapping) and isinstance(d.get("y_unit"), str) and d["y_unit"]:
                out.setdefault(str(d.get("name")), d["y_unit"])
    return out


def held_text(n_rows: int, attrs: Mapping) -> str:
    """"k of n cells in the store" for results of ``n_rows`` rows with ``attrs``; "in the m stores" for stores
    compared (their specs carry their labels), whose cells were said to be in "the store"."""
    labels = {s["store"] for s in attrs.get("specs") or () if isinstance(s, Mapping) and "store" in s}
    where = f"the {len(labels)} stores" if len(labels) > 1 else "the store"
    return f"{n_rows} of {attrs.get('n_cells', n_rows)} cells in {where}"


def _spec_info(s: Mapping[str, Any]) -> dict[str, Any]:
    return {"id": s["id"], "name": s["name"], "created": s["created"], "last_run": s["last_run"],
            "version": s["graybox_version"], "n_cells": s["n_cells"], "fingerprint": s["fingerprint"],
            "data": json.loads(s["data"]), "spec": json.loads(s["spec"])}


def store_specs(path: str | os.PathLike) -> pd.DataFrame:
    """The specs a store has seen, one row each (oldest first).

    Parameters
    ----------
    path : str or path-like
        A grid store.

    Returns
    -------
    pandas.DataFrame
        Index ``id`` (the spec's number, what ``spec=`` of :func:`load_results` takes); columns
        ``name``, ``created`` and ``last_run`` (UTC, ISO 8601), ``version`` (graybox), ``n_cells``,
        ``held`` (how many of its cells the store holds), ``fingerprint``, ``data`` (data set name
        -> content hash; empty for a first-format store) and ``spec`` (its canonical form).
    """
    p, conn, meta = _open_readonly(path)
    try:
        specs = _specs(conn, meta, p)
        if meta["format_version"] == "1":
            held = {1: conn.execute("SELECT COUNT(*) FROM cells").fetchone()[0]}
        else:
            held = dict(conn.execute("SELECT s.spec, COUNT(*) FROM spec_cells s JOIN cells c ON c.key = s.key "
                                     "GROUP BY s.spec").fetchall())
    except sqlite3.DatabaseError as exc:
        raise StoreError(f"{p} is damaged ({exc}); {_DAMAGED}") from None
    finally:
        conn.close()
    rows = [dict(_spec_info(s), held=int(held.get(s["id"], 0))) for s in specs]
    cols = ["name", "created", "last_run", "version", "n_cells", "held", "fingerprint", "data", "spec"]
    return pd.DataFrame(rows, columns=["id"] + cols).set_index("id")


def running_cells(path: str | os.PathLike) -> dict[str, int]:
    """Cells being run into the store now, by live run ("pid 123 on host h" -> cells it has taken and not
    written yet); read-only, so callable while runs write the store. {} for a store no run uses now."""
    p = Path(path)
    conn = _connect(p, readonly=True)
    try:
        if not {"drivers", "claims"} <= {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}:
            return {}
        rows = conn.execute("SELECT d.owner, d.host, d.pid, d.beat, COUNT(c.key) FROM drivers d JOIN claims c "
                            "ON c.owner = d.owner GROUP BY d.owner").fetchall()
    except sqlite3.DatabaseError as exc:
        raise StoreError(f"{p} is damaged ({exc}); {_DAMAGED}") from None
    finally:
        conn.close()
    now = time.time()
    out: dict[str, int] = {}
    for o, host, pid, beat, n in rows:
        if n and _alive(o, host, pid, beat, now):  # two runs of one process (threads, a notebook): one entry
            who = _driver_name(host, pid)
            out[who] = out.get(who, 0) + int(n)
    return out


#: The rules whose cells read no band: their rows hold in_band NULL. Rows written before 7937b3f8 hold 1 for them
#: (D_SF's own "min J_SF", its fallback, holds 0), which load_results reads as NULL, not as "in the band".
_NO_BAND_RULES = frozenset({"min J_SF", "min correlation"})


def _decode_row(r: dict[str, Any], p: Path, reading: bool = True) -> None:
    """A cell's row as read from the store ``p``, decoded in place (JSON columns, numbers, flags), or a StoreError
    naming the cell and what is damaged (``reading``: for a reader; else for a run, which wrote nothing)."""
    cell = f"the cell {r['data']!r} / {r['structure']!r} / {r['variant']!r}"
    if r["status"] not in STATUSES:  # what every count and reason of the reports is made of
        raise _damaged(p, f"{cell} has status {r['status']!r}, none of {', '.join(STATUSES)}", reading)
    r["terms"] = None if r["terms"] is None else tuple(_json_of(r["terms"], p, f"{cell}'s terms", list, reading))
    r["theta"] = None if r["theta"] is None else _json_of(r["theta"], p, f"{cell}'s theta", list, reading)
    r["warnings"] = () if r["warnings"] is None else tuple(_json_of(r["warnings"], p, f"{cell}'s warnings", list,
                                                                    reading))
    for c in ("terms", "warnings"):  # texts, as a cell writes them (the report joins them)
        if r[c] is not None and not all(isinstance(t, str) for t in r[c]):
            raise _damaged(p, f"{cell}'s {c} are not all texts", reading)
    members = None if r["members"] is None else _json_of(r["members"], p, f"{cell}'s members", dict, reading)
    try:  # numbers where numbers are stored (SQLite keeps whatever a column is given)
        r["theta"] = None if r["theta"] is None else np.array(r["theta"], dtype=float)
        if r["theta"] is not None and r["theta"].ndim != 1:
            raise ValueError(f"theta of shape {r['theta'].shape}, not one number per term")
        r["members"] = None if members is None else _decode_members(members)
        # a flag and counts as a cell writes them: bool() took any text for True, int() cut 1.5 to 1
        if r["in_band"] is not None and (isinstance(r["in_band"], bool) or r["in_band"] not in (0, 1)):
            raise ValueError(f"in_band {r['in_band']!r}, not 0 or 1")
        r["in_band"] = None if r["in_band"] is None else bool(r["in_band"])
        if r["in_band"] and r["rule"] in _NO_BAND_RULES:
            r["in_band"] = None  # written before 7937b3f8 (the cell's key unchanged, never rerun): no band read
        for c in ("seed", "n_params"):
            if r[c] is not None and (isinstance(r[c], bool) or not isinstance(r[c], int)):
                raise ValueError(f"{c} {r[c]!r}, not an integer")
        r["seed"] = None if r["seed"] is None else int(r["seed"])
        r["n_params"] = None if r["n_params"] is None else int(r["n_params"])
        for c in _FLOAT_COLUMNS:
            r[c] = None if r[c] is None else float(r[c])
    except (TypeError, ValueError) as exc:
        raise _damaged(p, f"{cell} holds a value that is not what its column holds ({exc})", reading) from None


def load_results(path: str | os.PathLike, *, spec: str | int = "latest") -> pd.DataFrame:
    """The cells of a grid store as a DataFrame, one row per cell, in grid order.

    Parameters
    ----------
    path : str or path-like
        A store written by :func:`graybox.experiments.run_grid` (``graybox grid run``).
    spec : "latest", "all" or int
        Which cells: those of the spec run last (default), every cell the store holds, or those
        of spec number ``spec`` (:func:`store_specs` lists them). With "all", a structure or
        variant name that stood for different contents in different specs is followed by the
        spec that defined it, e.g. ``"PE (spec 2)"`` (and by its content's hash where a spec gives that name to
        another variant: no two meanings share a name); a cell two data sets of one content share (a band-free
        one) is a row under each name the first spec holding it gives it, as that spec reads it.

    Returns
    -------
    pandas.DataFrame
        Columns: ``data``, ``structure``, ``variant``, ``seed`` (nullable integer; missing for deterministic
        estimators), ``estimator``, ``status`` (ok, infeasible, diverged, failed), ``message`` (why a
        cell is not ok);
        the chosen model's ``terms`` (tuple of str), ``theta`` (ndarray, engineering units; None
        for neural models), ``n_params`` (N_p: the structure's number of terms once it is made, whatever
        the cell's status; a network's parameters once it is fitted), ``lambda1``, ``rule`` and ``in_band`` of the
        decision (``in_band`` missing where the rule reads no band: min J_SF, min correlation; also in rows an
        older graybox wrote with in_band 1 for them), ``band`` (the data
        set's J_SF band; with "all", the largest of the specs holding the cell: a cell that reads no band is one
        result under each); the shared evaluator's figures on both
        records ``J1_ident``, ``JS_ident``, ``fit_ident``, ``J1_valid``, ``JS_valid``,
        ``fit_valid`` (MSE in output units², fit in %), ``JSF`` and ``static_miss`` (largest
        |ȳ_model(ū_i) − ȳ_i|, output units); ``members`` (Pareto sets: dict of arrays
        ``lambda1``, ``J1``, ``JS``, ``JSF``, ``JS_valid``, ``fit_valid`` and the list ``failure``); ``wall_time``
        (s), ``version``, ``warnings`` (tuple of str), ``worker``, ``finished_at``, ``key``,
        ``cell_index``. ``df.attrs`` holds the spec's name (``grid``), ``fingerprint``, ``spec``
        (its canonical form), ``version``, ``n_cells``, ``data_hashes`` (data set name -> content
        hash), ``specs`` (every spec of the store) and ``store`` (the path).

    Raises
    ------
    StoreError
        Not a graybox store, or damaged.
    ValueError
        No such spec in the store.
    """
    meta, specs, rows, chosen, n_cells = read_store(path, spec)
    p = Path(path)
    for r in rows:
        _decode_row(r, p)
    df = pd.DataFrame(rows, columns=list(COLUMNS))
    front = ["data", "structure", "variant", "seed", "estimator", "status", "message"]
    df = df[front + [c for c in df.columns if c not in front]]
    for c in _FLOAT_COLUMNS:
        df[c] = df[c].astype(float)
    for c, dtype in (("seed", "Int64"), ("n_params", "Int64"), ("in_band", "boolean")):
        df[c] = pd.array([r[c] for r in rows], dtype=dtype)
    infos = [_spec_info(s) for s in specs]
    if chosen is not None:
        info = _spec_info(chosen)
        df.attrs.update(grid=info["name"], fingerprint=info["fingerprint"], spec=info["spec"],
                        version=info["version"], n_cells=int(info["n_cells"]), data_hashes=info["data"])
    else:
        hashes: dict[str, str] = {}
        for i in infos:
            for k, h in i["data"].items():
                hashes.setdefault(k, h)
        df.attrs.update(grid=" + ".join(dict.fromkeys(i["name"] for i in infos)), fingerprint=None,
                        spec={str(i["id"]): i["spec"] for i in infos},
                        version=", ".join(dict.fromkeys(i["version"] for i in infos)), n_cells=n_cells,
                        data_hashes=hashes)
    df.attrs.update(specs=infos, store=str(path), selection=spec if chosen is None else int(chosen["id"]))
    return df


def _same_data_text(paths: Sequence[Path], frames: Sequence[pd.DataFrame]) -> str:
    """The data sets the stores hold under different names with the same content hash, as a sentence ('' if none)."""
    by_hash: dict[str, list[tuple[str, Path]]] = {}
    for p, df in zip(paths, frames):
        for name, h in df.attrs.get("data_hashes", {}).items():
            by_hash.setdefault(h, []).append((name, p))
    pairs = ["; ".join(f"{n!r} in {p}" for n, p in at) for at in by_hash.values()
             if len({p for _, p in at}) > 1 and len({n for n, _ in at}) > 1]
    if not pairs:
        return ""
    return (". Yet the same data (equal content hashes) are stored under other names: " + " | ".join(pairs)
            + ". Rename the data set in one spec to compare them")


def _structure_contents(df: pd.DataFrame) -> dict[str, set[str]]:
    """Each structure name of a store's results and the contents (canonical JSON) its specs give it: the spec
    read, or every spec of the store for ``spec="all"``."""
    sel = df.attrs.get("selection")
    out: dict[str, set[str]] = {}
    for info in df.attrs.get("specs", ()):
        if sel != "all" and info.get("id") != sel:
            continue
        for st in info.get("spec", {}).get("structures", ()):
            if isinstance(st, Mapping) and isinstance(st.get("name"), str):
                body = {k: v for k, v in st.items() if k != "name"}
                # a set of terms, each as graybox prints it: u(k-1)y(k-1) is y(k-1)u(k-1)
                for k in ("terms", "include"):
                    try:
                        body[k] = sorted(str(parse_term(t)) for t in body[k])
                    except (KeyError, TypeError, ValueError):
                        pass  # none, or not terms: compared as written
                out.setdefault(st["name"], set()).add(json.dumps(body, sort_keys=True))
    return out


def _told_apart_structures(labels: Sequence[str], frames: Sequence[pd.DataFrame]) -> list[dict[str, str]]:
    """Per store, its structure names that another store gives other terms or candidates, each followed by the
    store's label (``"made (a)"``): the heat map's rows and the leaderboard's index then never show two structures
    as one."""
    contents = [_structure_contents(df) for df in frames]
    shown = [set(df["structure"]) for df in frames]
    used = set().union(*shown)
    out: list[dict[str, str]] = [{} for _ in frames]
    for name in sorted(set().union(*shown)):
        holders = [i for i, names in enumerate(shown) if name in names]
        if len(holders) < 2 or any(name not in contents[i] for i in holders):
            continue  # in one store only, or a label of load_results' own ("PE (spec 2)"): as it is
        if len(set().union(*(contents[i][name] for i in holders))) == 1:
            continue  # one meaning in every store
        for i in holders:
            new = f"{name} ({labels[i]})"
            while new in used:
                new += "'"
            used.add(new)
            out[i][name] = new
    return out


def compare_results(
    stores: Sequence[str | os.PathLike],
    *,
    labels: Sequence[str] | None = None,
    spec: str | int = "latest",
) -> pd.DataFrame:
    """Several stores' cells in one frame, side by side: each variant name prefixed by its store's label.

    The report functions take the result as they take :func:`load_results`' frame: a heat map
    shows the stores' variants next to each other, a leaderboard ranks them together.

    Parameters
    ----------
    stores : sequence of path
        Two or more grid stores run on the same data (two paths of one store, e.g. through a
        link, are refused with ``ValueError``: it would be compared with itself).
    labels : sequence of str, optional
        One label per store (default: the file names without their suffix, a ``": "`` in them read as ``":"``),
        without ``": "`` (which parts a label from the variant names it prefixes, so that no two stores' variants
        read alike).
    spec : "latest", "all" or int
        Which cells of each store (see :func:`load_results`).

    Returns
    -------
    pandas.DataFrame
        :func:`load_results`' columns and ``store`` (the label); variants read ``"label: name"``; a structure
        name that two stores give different terms or candidates reads ``"name (label)"`` in each.

    Raises
    ------
    StoreError
        A store cannot be read, or two stores hold different data under one data set name, or
        share no data set.
    """
    if isinstance(stores, (str, os.PathLike)) or not isinstance(stores, (list, tuple)):
        raise TypeError(f"stores must be a sequence of two or more store paths, got {stores!r}")
    paths = [Path(s) for s in stores]
    if len(paths) < 2:
        raise ValueError(f"compare_results needs two or more stores, got {len(paths)}")
    seen_at: dict[object, Path] = {}
    for p in paths:  # a store named twice (a typo, a link) would be compared with itself, every row twice
        try:  # one file under two names (a hard link) has one device and inode; a missing one is refused below
            st = os.stat(p)
            at: object = (st.st_dev, st.st_ino)
        except OSError:
            at = p.resolve()
        if at in seen_at:
            raise ValueError(f"{seen_at[at]} and {p} are the same store: compare two or more different stores")
        seen_at[at] = p
    if labels is None:
        # a file name's ': ', which parts a label from its variants, as ':' ("run: 2.sqlite" is "run:2")
        stems = [re.sub(": +", ":", p.stem) for p in paths]
        labels = stems if len(set(stems)) == len(stems) else [f"{i + 1}:{s}" for i, s in enumerate(stems)]
    labels = list(check_sequence(labels, "labels", "a sequence of names, one per store"))
    for lab in labels:  # each prefixes its store's variants ("label: name") in every table and figure
        if not isinstance(lab, str):
            raise TypeError(f"labels must be names (str), one per store; got {lab!r} ({type(lab).__name__})")
        if not lab.strip():
            raise ValueError(f"labels must be non-empty names, one per store; got {lab!r}")
        if ": " in lab:  # "a" + "b: X" and "a: b" + "X" both read "a: b: X": two stores' variants in one group
            raise ValueError(f"labels must not hold ': ', which parts a label from its variant names ('label: name'); "
                             f"got {lab!r}")
    if len(labels) != len(paths) or len(set(labels)) != len(labels):
        raise ValueError(f"labels must be {len(paths)} distinct names, one per store; got {labels}")
    frames = [load_results(p, spec=spec) for p in paths]
    seen: dict[str, tuple[str, Path]] = {}
    for p, df in zip(paths, frames):
        for name, h in df.attrs.get("data_hashes", {}).items():
            if name in seen and seen[name][0] != h:
                raise StoreError(f"{p} and {seen[name][1]} hold different data under the data set name {name!r} "
                                 f"(content hashes {h} and {seen[name][0]}): their results are not comparable. "
                                 "Compare stores run on the same data, or rename the data set in one spec")
            seen.setdefault(name, (h, p))
    said: dict[str, tuple[str, Path]] = {}
    for p, df in zip(paths, frames):  # the same numbers (hashes checked above) in two units: one store mislabels them
        for name, unit in output_units(df.attrs).items():
            if name in said and said[name][0] != unit:
                raise StoreError(f"{said[name][1]} gives data set {name!r} in {said[name][0]}, {p} in {unit}, for the "
                                 "same numbers (equal content hashes): one of them says a wrong unit, and the report "
                                 "would say either's of both. Run the spec with the right units on that store (a new "
                                 "spec: its cells are reused), then compare")
            said.setdefault(name, (unit, p))
    names = [set(df["data"]) for df in frames]
    if all(n for n in names) and not set.intersection(*names):
        raise StoreError("the stores share no data set ("
                         + "; ".join(f"{p}: {sorted(n)}" for p, n in zip(paths, names))
                         + "): there is nothing to compare side by side" + _same_data_text(paths, frames))
    renamed = _told_apart_structures(labels, frames)
    out = []
    for lab, df, names in zip(labels, frames, renamed):
        d = df.copy()
        d["structure"] = [names.get(s, s) for s in d["structure"]]
        d["variant"] = [f"{lab}: {v}" for v in d["variant"]]
        d.insert(0, "store", lab)
        out.append(d)
    res = pd.concat(out, ignore_index=True)
    res["cell_index"] = np.arange(len(res))
    res.attrs = {"grid": " vs ".join(labels), "fingerprint": None,
                 "spec": {lab: df.attrs.get("spec") for lab, df in zip(labels, frames)},
                 "version": ", ".join(dict.fromkeys(df.attrs.get("version") or "" for df in frames)),
                 "n_cells": sum(int(df.attrs.get("n_cells", len(df))) for df in frames),
                 "data_hashes": {k: h for k, (h, _) in seen.items()},
                 "specs": [dict(s, store=lab) for lab, df in zip(labels, frames) for s in df.attrs.get("specs", [])],
                 "store": ", ".join(str(p) for p in paths), "selection": spec}
    return res
