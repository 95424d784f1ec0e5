"""Processes of this host: whether one still runs, asked by its pid; whether Ctrl-C stopped this one.

Files a process leaves beside a store or a checkpoint (its claim, its half-written file) are judged by whether
their writer still runs; the store's drivers and the checkpoints' writers ask it the same way.
"""

from __future__ import annotations

import os

__all__ = ["interrupted_by_user", "pid_alive", "pid_started"]


def pid_alive(pid: int) -> bool:
    """Whether process ``pid`` of this host may still run: False for no such process, or a killed one its parent
    has not reaped yet (a zombie, which ``os.kill(pid, 0)`` still answers); True where that cannot be asked
    (another user's process, a system without ``/proc``, Windows, where ``os.kill(pid, 0)`` would end it)."""
    if pid == os.getpid():
        return True
    if os.name != "posix":
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):  # another user's process; a number no pid is
        return True
    state = _stat_fields(pid)
    return state is None or state[0] != b"Z"


def pid_started(pid: int) -> float | None:
    """When process ``pid`` of this host started (s since the epoch, this host's clock), or None where that cannot
    be read: a process started after its claim's last sign of life is another one, the pid reused."""
    fields = _stat_fields(pid)
    if fields is None:  # no such process, or no /proc: the boot time would say nothing
        return None
    try:
        with open("/proc/stat", "rb") as f:
            boot = next(int(ln.split()[1]) for ln in f if ln.startswith(b"btime "))
        return boot + int(fields[19]) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError, StopIteration):
        return None


def _stat_fields(pid: int) -> list[bytes] | None:
    """``/proc/<pid>/stat`` after the command's name (state first), or None where it cannot be read."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            return f.read().rsplit(b")", 1)[1].split()
    except (OSError, IndexError):
        return None


def interrupted_by_user(exc: BaseException) -> bool:
    """Whether ``exc`` is, or was caused by, a KeyboardInterrupt (Ctrl-C).

    Ctrl-C while a numba kernel runs reaches Python as ``SystemError("CPUDispatcher(...) returned a result with an
    exception set")`` whose cause is the KeyboardInterrupt: whoever catches Exception (a grid cell's failure, the
    command's messages) asks this to tell the user's interrupt from a failure.
    """
    seen: set[int] = set()
    cur: BaseException | None = exc
    while cur is not None and id(cur) not in seen:
        if isinstance(cur, KeyboardInterrupt):
            return True
        seen.add(id(cur))
        cur = cur.__cause__ or cur.__context__
    return False
