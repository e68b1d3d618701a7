"""Model choice speed: ``rb.fit("auto")`` on one Mini-Diff file, and a single ``coated`` fit.

The budget: ``--model auto`` on one Mini-Diff file (3 channels, every candidate, the
leave-one-incidence-out score and the energy constraint included) at most 6x one ``coated``
fit of the same run (the ratio travels between machines; the absolute time does not).

Printed, warm (the compiled kernels and the lobe-albedo tables built by a first run, not
counted), best of :data:`REPEAT`: the default ``rb.fit("auto")``; the same with the candidates
before the metallic ones (:data:`BEFORE_METALLIC`, issue 28: the cost the metallic candidates
add); and in the same run the
references that show what each part costs -- without the cross-validation (``cv=False``), without
the energy constraint -- and one ``coated`` fit; with the CPU, its widest vector unit
(``avx512f``/``avx2`` in ``/proc/cpuinfo``) and the load average before and after, since a
loaded 2-core machine can double every figure. Needs ``../shared/data`` (or
``ROUGHBRDF_SHARED_DATA``); prints a note and returns without it.
"""

from __future__ import annotations

import os
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path

import roughbrdf as rb
from roughbrdf.fitting.choice.auto import fit_auto

sys.path.insert(0, str(Path(__file__).resolve().parent))  # run.py loads by path
from machine import cpu_name, load, vector_width  # noqa: E402

HERE = Path(__file__).resolve().parent
DATA = Path(os.environ.get("ROUGHBRDF_SHARED_DATA", HERE.parent.parent / "shared" / "data"))
FILE = "C2_Black"
REPEAT = 2
#: ``AUTO_CANDIDATES`` before the metallic-paint candidates (2026-12-06)
BEFORE_METALLIC = ("trowbridge-reitz-1975", "coated", "coated(lobes=2)",
                   "coated(lobes=2, distribution=beckmann)")


def best(call: Callable[[], object]) -> float:
    """The best wall time of :data:`REPEAT` calls (seconds)."""
    times = []
    for _ in range(REPEAT):
        t0 = time.perf_counter()
        call()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    path = DATA / "minidiff" / f"{FILE}.astm"
    print("\n## Model choice speed (bench_auto)")
    if not path.is_file():
        print(f"skipped: {path} not found (set ROUGHBRDF_SHARED_DATA)")
        return
    meas = rb.read(path)
    warnings.simplefilter("ignore")  # the candidates' plausibility warnings are not timed
    print(f"CPU: {cpu_name()}; vector unit: {vector_width()}; load average before: {load()}")
    runs = {
        "rb.fit('auto') (defaults: CV score, energy constraint)":
            lambda: rb.fit("auto", meas, progress=False),
        "rb.fit('auto'), the candidates before the metallic ones":
            lambda: fit_auto(meas, BEFORE_METALLIC, progress=False),
        "fit_auto(cv=False) (reference: no CV refits)":
            lambda: fit_auto(meas, cv=False, progress=False),
        "rb.fit('auto', energy_constraint=False) (reference)":
            lambda: rb.fit("auto", meas, energy_constraint=False, progress=False),
        "rb.fit('coated') (one candidate: the reference of the ratios)":
            lambda: rb.fit("coated", meas, progress=False),
    }
    rb.fit("auto", meas, progress=False)  # warm: kernels compiled, tables built
    print(f"\n{FILE} ({meas.n_samples} geometries x {len(meas.channels)} channels), best of "
          f"{REPEAT}, warm\n")
    # the ratio to one coated fit of the same run travels between machines (issue budget:
    # auto <= 6x coated); the absolute time does not
    times = {label: best(call) for label, call in runs.items()}
    coated = times[next(reversed(times))]
    print("| run | time (s) | ratio to one coated fit |\n|---|---|---|")
    for label, t in times.items():
        print(f"| {label} | {t:.2f} | {t / coated:.1f}x |", flush=True)
    print(f"\nload average after: {load()}")


if __name__ == "__main__":
    main()
