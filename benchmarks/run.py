"""Run every benchmark module ``benchmarks/bench_*.py`` (each defines ``main()``); ``make bench``.

Benchmarks print evaluations per second, fit times and start-up times (``bench_startup``);
they are figures, never tests. ``python benchmarks/run.py bench_startup`` runs one of them.
"""

from __future__ import annotations

import datetime
import importlib.util
import os
import platform
import subprocess
import sys
import traceback
from pathlib import Path

HERE = Path(__file__).parent


def machine() -> str:
    """CPU model (``lscpu``, else ``/proc/cpuinfo``), cores, Python and load average."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout
        cpu = next(ln.split(":", 1)[1].strip() for ln in out.splitlines()
                   if ln.startswith("Model name:"))
    except (OSError, subprocess.CalledProcessError, StopIteration):
        pass
    try:
        load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:
        load = "?"
    return (f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, "
            f"load average {load}")


def main() -> int:
    """Run the benchmarks; one that fails is reported and the others still run."""
    only = sys.argv[1:]
    print(f"# roughbrdf benchmarks - {datetime.datetime.now():%Y-%m-%d %H:%M} - {machine()}")
    failed = []
    for path in sorted(HERE.glob("bench_*.py")):
        if only and path.stem not in only:
            continue
        print(f"\n## {path.stem}", flush=True)
        try:
            spec = importlib.util.spec_from_file_location(path.stem, path)
            assert spec is not None and spec.loader is not None
            mod = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(mod)
            mod.main()
        except Exception:  # report it and run the next benchmark
            traceback.print_exc()
            failed.append(path.stem)
        sys.stdout.flush()
    if failed:
        print(f"\nfailed: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
