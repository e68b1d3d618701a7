"""Run every benchmark module ``benchmarks/bench_*.py`` (each defines ``main()``); ``make bench``.

Benchmarks print evaluations per second, fit times and start-up times (``bench_startup``);
they are figures, never tests. ``python benchmarks/run.py bench_startup`` runs one of them.

``bench_worker_memory`` (the memory of catalogue workers) is slow: it runs last, as an optional
section, only if its file exists; ``python benchmarks/run.py --skip-worker-memory`` leaves it
out. Benchmarks named on the command line run alone (this one too, when named).
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
#: the slow optional section: run last, if its file exists, unless SKIP_SLOW is given
SLOW = "bench_worker_memory"
SKIP_SLOW = "--skip-worker-memory"


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


def _run_one(path: Path) -> bool:
    """Run the benchmark module at ``path`` (its ``main()``); False if it failed."""
    print(f"\n## {path.stem}", flush=True)
    try:
        spec = importlib.util.spec_from_file_location(path.stem, path)
        assert spec is not None and spec.loader is not None
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        mod.main()
    except Exception:  # report it and run the next benchmark
        traceback.print_exc()
        return False
    finally:
        sys.stdout.flush()
    return True


def main(argv: list[str] | None = None) -> int:
    """Run the benchmarks (or those named in ``argv``); one that fails is reported and the
    others still run. The slow :data:`SLOW` section runs last, if its file exists, unless
    :data:`SKIP_SLOW` is given."""
    args = sys.argv[1:] if argv is None else argv
    skip_slow = SKIP_SLOW in args
    only = [a for a in args if a != SKIP_SLOW]
    unknown = [a for a in only if a.startswith("-")]
    if unknown:  # a mistyped flag would otherwise be taken as a benchmark's name
        print(f"run.py: unknown option {unknown[0]} (the only one is {SKIP_SLOW})",
              file=sys.stderr)
        return 2
    print(f"# roughbrdf benchmarks - {datetime.datetime.now():%Y-%m-%d %H:%M} - {machine()}")
    paths = [p for p in sorted(HERE.glob("bench_*.py")) if p.stem != SLOW]
    failed = [p.stem for p in paths if (not only or p.stem in only) and not _run_one(p)]
    slow = HERE / f"{SLOW}.py"
    wanted = not only or SLOW in only
    if wanted and skip_slow:
        print(f"\n## {SLOW}: skipped ({SKIP_SLOW})")
    elif wanted and not slow.is_file():  # written separately: absent in trees before it
        print(f"\n## {SLOW}: skipped ({slow.name} not found)")
    elif wanted and not _run_one(slow):
        failed.append(SLOW)
    missing = sorted(set(only) - {p.stem for p in paths} - {SLOW})
    if missing:  # a mistyped name would otherwise run nothing, silently
        print(f"\nno benchmark named {', '.join(missing)}", file=sys.stderr)
        failed += missing
    if failed:
        print(f"\nfailed: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
