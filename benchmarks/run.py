"""Run every benchmark module ``benchmarks/bench_*.py`` (each defines ``main()``); ``make bench``.

Benchmarks print evaluations per second and fit times; they are figures, never tests.
"""

from __future__ import annotations

import datetime
import importlib.util
import os
import platform
import sys
from pathlib import Path

HERE = Path(__file__).parent


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}"


def main() -> None:
    only = sys.argv[1:]
    print(f"# roughbrdf benchmarks - {datetime.date.today()} - {machine()}")
    for path in sorted(HERE.glob("bench_*.py")):
        if only and path.stem not in only:
            continue
        spec = importlib.util.spec_from_file_location(path.stem, path)
        mod = importlib.util.module_from_spec(spec)
        assert spec.loader is not None
        spec.loader.exec_module(mod)
        print(f"\n## {path.stem}")
        mod.main()


if __name__ == "__main__":
    main()
