"""Files written whole or not at all, the leftovers of killed writers, and advisory locks.

One home for what every file graybox writes beside a user's folder needs: a value's JSON file, an SE sweep's and a
selection's checkpoint, a grid's store. A file is written under a name of its own beside its target and moved into
place (a kill never leaves a torn file); a killed write leaves that file behind, and the next write or open sweeps
it. Ages are judged on the folder's clock (a file server's, read from a file just made there), never this host's,
which may be ahead of it by minutes.
"""

from __future__ import annotations

import codecs
import contextlib
import errno
import hashlib
import os
import re
import secrets
import socket
import stat
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import IO

from ._processes import pid_alive

try:  # pragma: no cover - every POSIX system has it
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]

#: Whether this platform has flock (:func:`lock_fd` then may lock; without it, it always answers False).
CAN_FLOCK = fcntl is not None

__all__ = ["BOMS", "CAN_FLOCK", "LEFTOVER_SECONDS", "bom_encoding", "folder_now", "lock_fd", "sweep_leftovers",
           "sweep_written_beside", "write_atomically", "written_path", "writer_tag"]

#: Byte-order marks and the encodings they say, UTF-32's first: its little-endian mark starts with UTF-16's.
BOMS = ((codecs.BOM_UTF32_LE, "utf-32"), (codecs.BOM_UTF32_BE, "utf-32"), (codecs.BOM_UTF8, "utf-8"),
        (codecs.BOM_UTF16_LE, "utf-16"), (codecs.BOM_UTF16_BE, "utf-16"))


def bom_encoding(raw: bytes) -> str | None:
    """The encoding a file's byte-order mark says (``"utf-8"``, ``"utf-16"``, ``"utf-32"``), or None without one."""
    return next((e for bom, e in BOMS if raw.startswith(bom)), None)


#: Seconds after which a file a killed writer left (its own name beside a target) is swept even when its writer's
#: liveness cannot be asked (another host's process); a write takes far less.
LEFTOVER_SECONDS = 600.0


def writer_tag() -> str:
    """``host-pid`` of this process, as a write's file beside its target is named: a folder may be shared by
    several hosts (NFS), where a pid says nothing of another host's processes."""
    return f"{re.sub(r'[^A-Za-z0-9_.]', '_', socket.gethostname()) or '_'}-{os.getpid()}"


def folder_now(folder: str | os.PathLike) -> float:
    """The folder's clock: the modification time of a file made and removed in it at once (s since the epoch).

    Raises the ``OSError`` of that file when the folder cannot be written in (its mode, a read-only mount, an ACL
    all say so here, before any work whose first write would fail)."""
    with tempfile.TemporaryFile(dir=folder) as f:
        return os.fstat(f.fileno()).st_mtime


def sweep_leftovers(folder: Path, name: re.Pattern[str], now: float, max_age: float = LEFTOVER_SECONDS) -> list[Path]:
    """Remove the files in ``folder`` whose name ``name`` matches whole and that a killed writer left.

    A file is a leftover when it is older than ``max_age`` seconds on the folder's clock ``now`` (see
    :func:`folder_now`), or, when the pattern has groups ``host`` and ``pid`` and they name a process of this host,
    at once when that process is gone. Files gone meanwhile, or that this user cannot remove, are left.

    Returns
    -------
    list of Path
        The files removed.
    """
    groups = name.groupindex
    host = writer_tag().rsplit("-", 1)[0]
    removed = []
    with contextlib.suppress(OSError):  # a folder gone or unreadable: nothing to sweep
        for f in folder.iterdir():
            m = name.fullmatch(f.name)
            if not m:
                continue
            with contextlib.suppress(OSError):  # gone meanwhile, or not ours to remove
                gone = ("pid" in groups and "host" in groups and m.group("host") == host
                        and m.group("pid") is not None and not pid_alive(int(m.group("pid"))))
                if gone or now - f.stat().st_mtime > max_age:
                    f.unlink()
                    removed.append(f)
    return removed


#: Bytes of a target's name that the name of a write's file beside it keeps: a file name holds 255 bytes, and the
#: write's own part (".host-pid-0badc0de.tmp") up to 86 (a host name of 64, a pid of 7 digits).
_STEM_BYTES = 255 - 86


def _stem(target: Path) -> str:
    """The part of the name of a write's file beside ``target`` that names the target: its name, or for a name too
    long to take the write's part beside it (a file name of 170 to 255 bytes, which ``open(target, "w")`` writes),
    its first bytes and a hash of the whole name (two long names alike in their first bytes keep apart)."""
    raw = os.fsencode(target.name)
    if len(raw) <= _STEM_BYTES:
        return target.name
    digest = hashlib.blake2s(raw, digest_size=4).hexdigest()
    return os.fsdecode(raw[:_STEM_BYTES - 9]) + "~" + digest  # bytes as the name's (a character cut: escaped)


def _written_beside(target: Path) -> re.Pattern[str]:
    """The names :func:`write_atomically` gives its files beside ``target`` (with the writer's host and pid)."""
    # without host (graybox 0.3.0's checkpoints) or without host and pid (its JSON saves): swept by age only
    return re.compile(rf"{re.escape(_stem(target))}\.(?:(?:(?P<host>[^-]+)-)?(?P<pid>\d+)-)?[0-9a-f]{{8}}\.tmp")


def _new_file_beside(target: Path) -> tuple[int, Path]:
    """A new file of this write's own next to ``target``, with the mode ``open(target, "w")`` would leave:
    ``target``'s own when it exists, else 0666 less the umask (``mkstemp`` would make every file private, 0600).

    The file is made no wider than ``target`` (its mode less the umask, the owner's write kept), then given
    ``target``'s mode exactly where the file system takes modes: a mount refusing chmod (some FUSE and CIFS ones)
    takes the write as ``open(target, "w")`` would, and never makes a private file readable by others."""
    try:
        mode = stat.S_IMODE(os.stat(target).st_mode)
    except OSError:
        mode = None
    while True:
        tmp = target.with_name(f"{_stem(target)}.{writer_tag()}-{secrets.token_hex(4)}.tmp")
        try:  # the umask applies
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666 if mode is None else (mode & 0o666) | 0o200)
        except FileExistsError:  # pragma: no cover - a name drawn twice
            continue
        if mode is not None:
            # by descriptor where chmod takes one (Windows' Python before 3.13 does not: a TypeError), else by name
            with contextlib.suppress(OSError):
                os.chmod(fd if os.chmod in os.supports_fd else tmp, mode)
        return fd, tmp


def written_path(path: Path) -> Path:
    """The file a write to ``path`` replaces: the file a symbolic link names (written through, as ``open(path, "w")``
    would, the link kept), else ``path`` itself; beside it go the write's own file and its sweep."""
    return Path(os.path.realpath(path)) if path.is_symlink() else path


def _not_writable(target: Path) -> str:
    """Why a file that exists may not be written, with the fix: another user's, read-only by its mode, or neither
    (a read-only mount, an ACL, an immutable flag)."""
    st = os.stat(target)
    if hasattr(os, "geteuid") and os.geteuid() not in (0, st.st_uid):  # root writes anyone's: not the cause
        return (f"the file belongs to another user (uid {st.st_uid}) and may not be written by this one: write to "
                "another name, or have its owner make it writable")
    if not st.st_mode & stat.S_IWUSR:
        return "the file is read-only (its mode forbids writing): make it writable (chmod u+w) or write to another name"
    return ("the file may not be written (a read-only file system, an access list or an immutable flag?): write to "
            "another name")


def write_atomically(path: str | os.PathLike, write: Callable[[IO[bytes]], object]) -> None:
    """Write the file ``path`` by ``write(f)`` on a binary file, whole or not at all.

    The bytes go to a file of this write's own beside the target (named by host, pid and a random tag: two writers
    of one file at once never move each other's half-written file), which then replaces the target. A symbolic link
    is written through, as ``open(path, "w")`` would: the file it names is replaced, the link kept. An existing
    file's mode is kept. A device or a named pipe (``os.devnull``, a FIFO) is written into, as ``open(path, "w")``
    would, never replaced. After the move, the files killed writes left beside the target are swept
    (:func:`sweep_leftovers`).

    Raises
    ------
    OSError
        Of the same kind, naming the folder and ``path`` (not the file beside it) when the folder cannot be written
        in; ``PermissionError`` for a file that exists and may not be written (read-only), as ``open(path, "w")``;
        any error of ``write`` itself, after removing the file beside the target.
    """
    path = Path(path)
    target = written_path(path)
    if target.exists() and not (target.is_file() or target.is_dir()):
        # a device or a pipe (os.devnull, a FIFO a reader waits on) is written into, as open(path, "wb") would: the
        # move below replaced it with a regular file (for root, /dev/null itself, left holding the value)
        with open(target, "wb") as f:
            write(f)
        return
    if target.is_file() and not os.access(target, os.W_OK):
        # open(path, "w") refuses a file its owner made read-only; the move below would replace it all the same
        raise PermissionError(errno.EACCES, _not_writable(target), str(path))
    try:
        fd, tmp = _new_file_beside(target)
    except OSError as exc:
        raise type(exc)(exc.errno, f"cannot write in the folder {target.parent}: {exc.strerror}", str(path)) from None
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
        now = os.stat(tmp).st_mtime  # the folder's clock (a file server's), as its files' times are
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise
    sweep_leftovers(target.parent, _written_beside(target), now)


def sweep_written_beside(target: Path, now: float) -> list[Path]:
    """Sweep the files killed :func:`write_atomically` calls left beside ``target`` (``now``: the folder's clock)."""
    return sweep_leftovers(target.parent, _written_beside(target), now)


def lock_fd(fd: int, timeout: float, shared: bool = False) -> bool:
    """flock ``fd`` (exclusive, or ``shared``), waiting up to ``timeout`` seconds (0: one try); False where it cannot
    (held past the timeout, a file system without such locks, a platform without flock)."""
    if fcntl is None:
        return False
    kind = fcntl.LOCK_SH if shared else fcntl.LOCK_EX
    deadline = time.monotonic() + timeout
    while True:
        try:
            fcntl.flock(fd, kind | fcntl.LOCK_NB)
            return True
        except BlockingIOError:
            if time.monotonic() > deadline:
                return False
            time.sleep(0.005)
        except OSError:  # a file system without such locks: the caller's own wait is all there is
            return False
