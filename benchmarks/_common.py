"""Shared helpers for the benchmark scripts (timing, machine facts, SysIdentPy codes)."""

from __future__ import annotations

import os
import platform
import statistics
import subprocess
import time
from typing import Callable

import numpy as np


def machine() -> str:
    """One line naming the CPU, core count, Python and numpy versions."""
    cpu = platform.processor() or "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, numpy {np.__version__}"


def timeit(fn: Callable[[], object], repeat: int = 7, number: int = 1) -> float:
    """Median wall time of ``number`` calls of ``fn`` over ``repeat`` rounds, in seconds per call."""
    fn()  # warm-up (JIT compilation, caches)
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        times.append((time.perf_counter() - t0) / number)
    return statistics.median(times)


def sysidentpy_code(structure) -> np.ndarray:
    """SysIdentPy's regressor code of a single-input structure: 1000+j = y(k-j), 2000+j = u(k-j)."""
    deg = max(t.degree for t in structure)
    rows = []
    for t in structure:
        codes = []
        for s, lag, p in t.factors:
            codes += [(1000 if s == "y" else 2000) + lag] * p
        codes = sorted(codes, reverse=True) + [0] * (deg - len(codes))
        rows.append(codes)
    return np.array(rows)


def git_rev() -> str:
    try:
        return subprocess.check_output(["git", "rev-parse", "--short", "HEAD"], text=True).strip()
    except Exception:
        return "unknown"
