"""Fitted parameters of two commits, compared in one run on one machine (a refactoring check).

A change that promises "no behaviour change" (a restructuring of the code) must give the same
fits. This script checks out two commits into temporary worktrees, fits every candidate of
``--model auto`` (``roughbrdf.fitting.AUTO_CANDIDATES``, ``rb.fit`` defaults) to each
channel of the three shared Mini-Diff paints with each commit's own code, in a fresh process
per commit, and compares every fitted parameter::

    python scripts/same_fits.py BASE [HEAD] [--tol 1e-12] [--data ../shared/data]

Both commits run on this machine in the same invocation: the compiled kernels round
differently on AVX2 and AVX-512 processors, so figures from two machines cannot be compared to
1e-12. The exit status is 0 when every parameter agrees within ``--tol`` (relative, with an
absolute floor of ``tol`` for values near 0), 1 otherwise; the table of the largest differences
is printed either way.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
PAINTS = ("C2_Black", "C8_Silver", "C12_OliveDrab")

#: run in each worktree's own interpreter process: prints one JSON object
#: {"paint|candidate|channel": {param: value}}
CHILD = r"""
import json, sys
import roughbrdf as rb
from roughbrdf.fitting import AUTO_CANDIDATES
data, paints = sys.argv[1], sys.argv[2].split(",")
out = {}
for paint in paints:
    meas = rb.read(f"{data}/minidiff/{paint}.astm")
    for cand in AUTO_CANDIDATES:
        res = rb.fit(cand, meas, progress=False)
        for c in res:
            out[f"{paint}|{cand}|{c.channel}"] = {k: float(v) for k, v in c.params.items()}
print(json.dumps(out))
"""


def fits_of(commit: str, data: Path) -> dict[str, dict[str, float]]:
    """Every candidate's fitted parameters on the paints, computed by ``commit``'s code."""
    with tempfile.TemporaryDirectory(prefix="same-fits-") as tmp:
        tree = Path(tmp) / "tree"
        subprocess.run(["git", "-C", str(REPO), "worktree", "add", "-q", "--detach",
                        str(tree), commit], check=True)
        try:
            env = {**os.environ, "PYTHONPATH": str(tree / "src"),
                   "NUMBA_CACHE_DIR": str(Path(tmp) / "numba-cache")}
            run = subprocess.run([sys.executable, "-c", CHILD, str(data), ",".join(PAINTS)],
                                 check=True, capture_output=True, text=True, env=env,
                                 cwd=tmp)
        finally:
            subprocess.run(["git", "-C", str(REPO), "worktree", "remove", "--force",
                            str(tree)], check=False)
    return json.loads(run.stdout.strip().splitlines()[-1])


def differences(a: dict[str, dict[str, float]], b: dict[str, dict[str, float]]
                ) -> list[tuple[float, str, float, float]]:
    """(relative difference, key/param, a, b) of every parameter, largest first; a key or
    parameter present in one commit only counts as an infinite difference."""
    rows = []
    for key in sorted(set(a) | set(b)):
        pa, pb = a.get(key, {}), b.get(key, {})
        for name in sorted(set(pa) | set(pb)):
            if name not in pa or name not in pb:
                rows.append((float("inf"), f"{key}|{name}", pa.get(name, float("nan")),
                             pb.get(name, float("nan"))))
                continue
            x, y = pa[name], pb[name]
            rel = abs(x - y) / max(abs(x), abs(y), 1.0)
            rows.append((rel, f"{key}|{name}", x, y))
    return sorted(rows, reverse=True)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("base")
    ap.add_argument("head", nargs="?", default="HEAD")
    ap.add_argument("--tol", type=float, default=1e-12)
    ap.add_argument("--data", type=Path, default=REPO.parent / "shared" / "data")
    args = ap.parse_args(argv)
    if not (args.data / "minidiff").is_dir():
        print(f"no {args.data / 'minidiff'}: nothing to compare", file=sys.stderr)
        return 2
    a, b = fits_of(args.base, args.data), fits_of(args.head, args.data)
    rows = differences(a, b)
    print(f"{len(rows)} fitted parameters ({len(a)} channel fits), {args.base} vs {args.head}")
    print("| relative difference | fit / parameter | base | head |\n|---|---|---|---|")
    for rel, what, x, y in rows[:10]:
        print(f"| {rel:.2e} | {what} | {x:.17g} | {y:.17g} |")
    worst = rows[0][0] if rows else 0.0
    print(f"largest relative difference {worst:.3e} (tolerance {args.tol:g})")
    return 0 if worst <= args.tol else 1


if __name__ == "__main__":
    sys.exit(main())
