"""Start-up times of two commits, measured in one run on one machine (a refactoring check).

A restructuring must not make ``import roughbrdf`` or ``roughbrdf --help`` slower. This script
checks out ``BASE`` and ``HEAD`` into temporary worktrees and times, in fresh processes and
interleaved (base, head, base, head, ...) so that the machine's load falls on both alike:

* ``python -c "import roughbrdf"``;
* ``python -m roughbrdf.cli --help``;
* import and one TR75 evaluation with a warm Numba cache (each worktree's own cache, filled
  by an untimed first run)::

    python scripts/same_startup.py BASE [HEAD] [--repeat 9] [--tolerance 0.2]

It prints the median of each and the ratio head/base; the exit status is 1 when a ratio is
above ``1 + tolerance``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
STEPS = {
    "import roughbrdf": ["-c", "import roughbrdf"],
    "roughbrdf --help": ["-m", "roughbrdf.cli", "--help"],
    "import + TR75 evaluation (warm cache)":
        ["-c", "import roughbrdf as rb; rb.model('tr75').brdf(0.5, 0.5, 0.0)"],
}


def _time(args: list[str], env: dict[str, str], cwd: str) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, *args], env=env, cwd=cwd, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("base")
    ap.add_argument("head", nargs="?", default="HEAD")
    ap.add_argument("--repeat", type=int, default=9)
    ap.add_argument("--tolerance", type=float, default=0.2)
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="same-startup-") as tmp:
        envs = {}
        for label, commit in (("base", args.base), ("head", args.head)):
            tree = Path(tmp) / label
            subprocess.run(["git", "-C", str(REPO), "worktree", "add", "-q", "--detach",
                            str(tree), commit], check=True)
            envs[label] = {**os.environ, "PYTHONPATH": str(tree / "src"),
                           "NUMBA_CACHE_DIR": str(Path(tmp) / f"cache-{label}")}
        try:
            times: dict[tuple[str, str], list[float]] = {}
            for step, cmd in STEPS.items():
                for env in envs.values():
                    _time(cmd, env, tmp)  # untimed: fills the Numba cache, warms the disk
                for _ in range(args.repeat):
                    for label, env in envs.items():
                        times.setdefault((step, label), []).append(_time(cmd, env, tmp))
        finally:
            for label in envs:
                subprocess.run(["git", "-C", str(REPO), "worktree", "remove", "--force",
                                str(Path(tmp) / label)], check=False)
    load = os.getloadavg()[0]
    print(f"start-up, median of {args.repeat} interleaved runs, load {load:.1f}, "
          f"{args.base} vs {args.head}")
    print("| step | base (s) | head (s) | head/base |\n|---|---|---|---|")
    worst = 0.0
    for step in STEPS:
        b = statistics.median(times[(step, "base")])
        h = statistics.median(times[(step, "head")])
        worst = max(worst, h / b)
        print(f"| {step} | {b:.3f} | {h:.3f} | {h / b:.2f} |")
    return 0 if worst <= 1 + args.tolerance else 1


if __name__ == "__main__":
    sys.exit(main())
