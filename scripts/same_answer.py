"""The same fit on every machine: host kernels against AVX2 kernels, in one run.

The compiled kernels round differently with another vector width (AVX-512, AVX2), and the BLAS
library picks its kernels by processor too. A fit's outcome must not depend on it
(``docs/fitting.md``, "The same answer on every machine"). This script runs, in a fresh
process per variant, ``rb.compare`` of every ``--model auto`` candidate
(``roughbrdf.fitting.choice.compare.AUTO_CANDIDATES``, with its cross-validation score, i.e. what
``--model auto`` decides on) on each of the three shared Mini-Diff paints, under

``host``
    the kernels compiled for this processor (numba's default);
``haswell``
    the kernels compiled for an AVX2 processor without AVX-512: ``NUMBA_CPU_NAME=haswell``
    *and* ``NUMBA_CPU_FEATURES=`` (empty: the features of the named CPU; without it numba
    keeps the host's features, AVX-512 included), and OpenBLAS's Haswell kernels
    (``OPENBLAS_CORETYPE=Haswell``, unless the environment sets it);
``perturbed``
    the host kernels on the data multiplied by ``1 + 1e-13 z`` (``z`` standard normal, a fixed
    seed): a change at the last bits, as another machine's rounding makes, that any machine
    can try,

and compares them with ``host``::

    python scripts/same_answer.py [--data ../shared/data] [--variants haswell,perturbed]

Agreement (the criterion of ``docs/fitting.md``): per candidate, paint and channel,
``success`` and the parameters on a bound (and which bound) identical; a parameter at a bound
within ``1e-6`` relative; any other parameter within ``0.1`` of its standard error (or, in a
fit held by its energy constraint in both runs, within ``1e-6`` relative); the kept
candidate (the best by cross-validation) identical. A parameter without a finite standard
error in both runs and on no bound is one the data do not determine (the width of a lobe
switched off, TR75's ``e`` when ``n = 1`` turns its lobe off): its value is any, and it is
counted apart ("undetermined"), not compared. Prints a Markdown table per
variant and exits 0 when everything agrees, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
PAINTS = ("C2_Black", "C8_Silver", "C12_OliveDrab")
#: a parameter's agreement in units of its standard error
SIGMA_TOL = 0.1
#: relative agreement of a parameter at a bound, or one without a finite standard error
REL_TOL = 1e-6
#: the perturbation's relative size (a few units in the last place of a double are 1e-16:
#: 1e-13 stands for the accumulated rounding of a model evaluation)
PERTURB = 1e-13

#: run in each variant's process: prints one JSON object
CHILD = r"""
import json, math, sys, warnings
import numpy as np
import roughbrdf as rb
from roughbrdf.fitting.choice.compare import AUTO_CANDIDATES
data, paints, perturb = sys.argv[1], sys.argv[2].split(","), float(sys.argv[3])
out = {}
for paint in paints:
    meas = rb.read(f"{data}/minidiff/{paint}.astm")
    if perturb:
        z = np.random.default_rng(1).standard_normal(meas.values.shape)
        meas.values[...] = meas.values * (1.0 + perturb * z)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cmp = rb.compare(meas, list(AUTO_CANDIDATES), progress=False)
    out[paint] = {"best": cmp.best.label, "cv": {c.label: c.cv for c in cmp.candidates}}
    for cand in cmp.candidates:
        for c in cand.result:
            out[paint][f"{cand.label}|{c.channel}"] = {
                "success": bool(c.success), "at_bound": dict(c.at_bound),
                "params": {k: float(v) for k, v in c.params.items() if v is not None},
                "stderr": {k: math.nan if v is None else float(v)
                           for k, v in c.stderr.items()},
                "constrained": bool(c.energy_constraint is not None
                                    and c.energy_constraint.active)}
print(json.dumps(out))
"""


def environment(variant: str, cache: Path) -> dict[str, str]:
    """The environment of one variant's process (module notes); its own numba cache."""
    env = {**os.environ, "PYTHONPATH": str(REPO / "src"), "NUMBA_CACHE_DIR": str(cache)}
    if variant == "haswell":
        env.update(NUMBA_CPU_NAME="haswell", NUMBA_CPU_FEATURES="")
        env.setdefault("OPENBLAS_CORETYPE", "Haswell")  # a machine's own setting stands
    return env


def fits_of(variant: str, data: Path) -> dict:
    """Every candidate's fits on the paints under ``variant``."""
    with tempfile.TemporaryDirectory(prefix=f"same-answer-{variant}-") as tmp:
        perturb = PERTURB if variant == "perturbed" else 0.0
        run = subprocess.run([sys.executable, "-c", CHILD, str(data), ",".join(PAINTS),
                              repr(perturb)], capture_output=True, text=True,
                             env=environment(variant, Path(tmp) / "numba"), cwd=tmp)
    if run.returncode:  # the child's own words (an unset parameter broke it once)
        sys.exit(f"variant {variant} failed (exit {run.returncode}):\n{run.stderr[-3000:]}")
    return json.loads(run.stdout.strip().splitlines()[-1])


def _close(x: float, y: float, sigma: float, bound: bool,
           constrained: bool = False) -> tuple[bool, str]:
    """Whether two values of one parameter agree, and the difference in words. On an active
    energy constraint (a bound on a combination of the parameters, met to its solver's
    tolerance) either criterion will do: 1e-6 relative, as on a bound, or 0.1 sigma."""
    rel = abs(x - y) / max(abs(x), abs(y), 1e-300)
    if bound or not (math.isfinite(sigma) and sigma > 0):
        return rel <= REL_TOL, f"{rel:.1e} rel"
    ok = abs(x - y) <= SIGMA_TOL * sigma or (constrained and rel <= REL_TOL)
    return ok, f"{abs(x - y) / sigma:.2g} sigma"


def undetermined(a: dict, b: dict, name: str) -> bool:
    """Whether a parameter is one the data do not determine in both fits (module notes)."""
    def free(c: dict) -> bool:
        s = c["stderr"][name]
        return name not in c["at_bound"] and not (math.isfinite(s) and s > 0)
    return free(a) and free(b)


def differences(ref: dict, other: dict) -> list[tuple[str, str, str]]:
    """``(where, what, how)`` of every disagreement between two variants' fits."""
    out = []
    for paint in ref:
        if ref[paint]["best"] != other[paint]["best"]:
            out.append((paint, "kept candidate", f"{ref[paint]['best']} vs "
                                                 f"{other[paint]['best']}"))
        for key, a in ref[paint].items():
            if key in ("best", "cv"):
                continue
            b = other[paint][key]
            where = f"{paint} {key}"
            if a["success"] != b["success"]:
                out.append((where, "success", f"{a['success']} vs {b['success']}"))
            if a["at_bound"] != b["at_bound"]:
                out.append((where, "at a bound", f"{a['at_bound']} vs {b['at_bound']}"))
            for name, x in a["params"].items():
                if undetermined(a, b, name):
                    continue
                ok, how = _close(x, b["params"][name], a["stderr"][name],
                                 name in a["at_bound"], a["constrained"] and b["constrained"])
                if not ok:
                    out.append((where, name, how))
    return out


def worst(ref: dict, other: dict) -> dict[str, str]:
    """Per paint, the largest parameter difference in units of its standard error."""
    out = {}
    for paint in ref:
        top = 0.0
        for key, a in ref[paint].items():
            if key in ("best", "cv"):
                continue
            for name, x in a["params"].items():
                s = a["stderr"][name]
                if name not in a["at_bound"] and math.isfinite(s) and s > 0:
                    top = max(top, abs(x - other[paint][key]["params"][name]) / s)
        out[paint] = f"{top:.2g}"
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", type=Path, default=REPO.parent / "shared" / "data")
    ap.add_argument("--variants", default="haswell,perturbed")
    args = ap.parse_args(argv)
    if not (args.data / "minidiff").is_dir():
        print(f"no {args.data / 'minidiff'}: nothing to compare", file=sys.stderr)
        return 2
    ref = fits_of("host", args.data)
    failed = False
    for variant in args.variants.split(","):
        other = fits_of(variant, args.data)
        diffs = differences(ref, other)
        failed |= bool(diffs)
        print(f"\n### host vs {variant}\n")
        print("| paint | kept (host) | kept | fits | parameters | undetermined | "
              "largest difference / sigma | disagreements |\n|---|---|---|---|---|---|---|---|")
        big = worst(ref, other)
        for paint in ref:
            fits = [k for k in ref[paint] if k not in ("best", "cv")]
            n = sum(len(ref[paint][k]["params"]) for k in fits)
            free = sum(undetermined(ref[paint][k], other[paint][k], nm)
                       for k in fits for nm in ref[paint][k]["params"])
            bad = sum(1 for d in diffs if d[0].startswith(paint))
            print(f"| {paint} | {ref[paint]['best']} | {other[paint]['best']} | {len(fits)} | "
                  f"{n} | {free} | {big[paint]} | {bad} |")
        for where, what, how in diffs[:20]:
            print(f"- {where}: {what}: {how}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
