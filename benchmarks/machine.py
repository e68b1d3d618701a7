"""What machine a benchmark ran on: the CPU's name, its widest vector unit, the load average.

Shared by the benchmarks that print them beside their figures (``bench_auto``,
``bench_explore``): a loaded 2-core machine can double every figure, and the kernels' speed
depends on the vector width.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["cpu_name", "load", "vector_width"]


def _cpuinfo() -> list[str]:
    try:
        return Path("/proc/cpuinfo").read_text().splitlines()
    except OSError:  # not Linux
        return []


def cpu_name() -> str:
    """The CPU's ``model name`` in ``/proc/cpuinfo`` ("unknown" elsewhere)."""
    return next((ln.split(":", 1)[1].strip() for ln in _cpuinfo()
                 if ln.startswith("model name")), "unknown")


def vector_width() -> str:
    """The widest SIMD unit the CPU reports (``/proc/cpuinfo`` flags)."""
    flags = next((ln.split() for ln in _cpuinfo() if ln.startswith("flags")), None)
    if flags is None:
        return "unknown"
    return next((f for f in ("avx512f", "avx2", "avx", "sse4_2") if f in flags), "none")


def load() -> str:
    """The 1-minute load average (``os.getloadavg``), or "n/a"."""
    try:
        return f"{os.getloadavg()[0]:.2f}"
    except OSError:
        return "n/a"
