"""Model choice speed: ``rb.fit("auto")`` on one Mini-Diff file, and a single ``coated`` fit.

The budget: ``--model auto`` on one Mini-Diff file (3 channels, every candidate, the
leave-one-incidence-out score and the energy constraint included) at most 6x one ``coated``
fit of the same run (the ratio travels between machines; the absolute time does not).

Printed, warm (the compiled kernels and the lobe-albedo tables built by a first run, not
counted), best of :data:`REPEAT`: the default ``rb.fit("auto")``; the same with the candidates
as it was until 2026-12-06 (:func:`as_before`: the Beckmann pair among the candidates, no
parsimony rule); and in the same run the
references that show what each part costs -- without the cross-validation (``cv=False``), without
the energy constraint -- and one ``coated`` fit; with the CPU, its widest vector unit
(``avx512f``/``avx2`` in ``/proc/cpuinfo``) and the load average before and after, since a
loaded 2-core machine can double every figure. Then where one ``rb.fit("auto")`` spends its
time (:func:`breakdown`: per candidate and stage, seconds, model evaluations, units of one
coated fit), and each shared paint's ``--model auto`` beside one coated fit and beside the
whole comparison it replaced (:func:`per_file`). Needs ``../shared/data`` (or
``ROUGHBRDF_SHARED_DATA``); prints a note and returns without it.
"""

from __future__ import annotations

import math
import os
import sys
import time
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import roughbrdf as rb
from roughbrdf.fitting.choice import auto as auto_module
from roughbrdf.fitting.choice.auto import fit_auto
from roughbrdf.models import spec_text

sys.path.insert(0, str(Path(__file__).resolve().parent))  # run.py loads by path
from machine import cpu_name, load, vector_width  # noqa: E402

HERE = Path(__file__).resolve().parent
DATA = Path(os.environ.get("ROUGHBRDF_SHARED_DATA", HERE.parent.parent / "shared" / "data"))
FILE = "C2_Black"
#: the shared paints (``per_file``)
PAINTS = ("C2_Black", "C8_Silver", "C12_OliveDrab")
REPEAT = 2
#: ``AUTO_CANDIDATES`` until 2026-12-06 (the Beckmann pair among them), run as then: without
#: the parsimony rule (``PARSIMONY_MARGIN``, :func:`as_before`) -- the "before" of the figures
BEFORE = ("trowbridge-reitz-1975", "coated", "coated(lobes=2)",
          "coated(lobes=2, distribution=beckmann)",
          "coated-conductor(coat=false, diffuse=true, flakes=reflectance)",
          "coated-conductor(diffuse=true, flakes=reflectance)")


def as_before(meas: rb.Measurement) -> Any:
    """``--model auto`` as it was until 2026-12-06: :data:`BEFORE`, no parsimony rule (the
    module's margin set to -inf for the call: every candidate within ``SKIP_MARGIN`` goes on)."""
    margin = auto_module.PARSIMONY_MARGIN
    auto_module.PARSIMONY_MARGIN = -math.inf
    try:
        return fit_auto(meas, BEFORE, progress=False)
    finally:
        auto_module.PARSIMONY_MARGIN = margin


def best(call: Callable[[], object]) -> float:
    """The best wall time of :data:`REPEAT` calls (seconds)."""
    times = []
    for _ in range(REPEAT):
        t0 = time.perf_counter()
        call()
        times.append(time.perf_counter() - t0)
    return min(times)


@contextmanager
def timed_stages() -> Iterator[list[dict[str, Any]]]:
    """Record every fit and every set of folds that ``fit_auto``'s two stages make: the
    module's ``fit_model`` and ``held_out_residuals`` wrapped for the duration (a benchmark's
    probe; the library is not changed). Each record: ``what`` ("fit" or "folds"), ``model``,
    ``stage`` (1: the first channel, 2: the others), seconds and model evaluations."""
    log: list[dict[str, Any]] = []
    fit, held = auto_module.fit_model, auto_module.held_out_residuals

    def fit_probe(model: Any, *args: Any, **kw: Any) -> Any:
        t0 = time.perf_counter()
        res = fit(model, *args, **kw)
        new = res.channels[len(kw.get("done") or []):]
        log.append({"what": "fit", "model": spec_text(model), "stage": 2 if kw.get("done")
                    else 1, "s": time.perf_counter() - t0, "nfev": sum(c.nfev for c in new)})
        return res

    def held_probe(res: Any, *args: Any, **kw: Any) -> Any:
        t0 = time.perf_counter()
        out = held(res, *args, **kw)
        stage = 1 if len(res.channels) == 1 and res.channels[0].channel == \
            res.measurement.channels[0] else 2
        log.append({"what": "folds", "model": kw.get("label") or res.model_name,
                    "stage": stage, "s": time.perf_counter() - t0, "nfev": None})
        return out

    auto_module.fit_model, auto_module.held_out_residuals = fit_probe, held_probe
    try:
        yield log
    finally:
        auto_module.fit_model, auto_module.held_out_residuals = fit, held


def breakdown(meas: rb.Measurement, coated: float) -> None:
    """Where one ``rb.fit("auto")`` spends its time: per candidate, the first channel's fit
    and folds (stage 1), the other channels' fit and folds (stage 2), in seconds and in
    units of one coated fit of the same run; the rest (ranking, albedo checks) as the
    remainder."""
    with timed_stages() as log:
        t0 = time.perf_counter()
        res = rb.fit("auto", meas, progress=False)
        total = time.perf_counter() - t0
    print(f"\nWhere the time goes (one run; total {total:.2f} s = {total / coated:.1f}x one "
          f"coated fit; kept: {res.model_name})\n")
    print("| candidate | stage 1 fit (s, evaluations) | stage 1 folds (s) | stage 2 fit (s, "
          "evaluations) | stage 2 folds (s) | sum (x coated) |\n|---|---|---|---|---|---|")
    models = list(dict.fromkeys(r["model"] for r in log))
    for m in models:
        cell = {}
        for what in ("fit", "folds"):
            for stage in (1, 2):
                rows = [r for r in log if r["model"] == m and r["what"] == what
                        and r["stage"] == stage]
                cell[what, stage] = "-" if not rows else (
                    f"{rows[0]['s']:.2f}" + (f", {rows[0]['nfev']}" if what == "fit" else ""))
        spent = sum(r["s"] for r in log if r["model"] == m)
        print(f"| {m} | {cell['fit', 1]} | {cell['folds', 1]} | {cell['fit', 2]} | "
              f"{cell['folds', 2]} | {spent:.2f} ({spent / coated:.1f}x) |")
    rest = total - sum(r["s"] for r in log)
    print(f"| the rest (ranking, albedo of the rows) | | | | | {rest:.2f} "
          f"({rest / coated:.1f}x) |")


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
        "before (until 2026-12-06: the Beckmann pair a candidate, no parsimony rule)":
            lambda: as_before(meas),
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
    breakdown(meas, coated)
    per_file()
    print(f"\nload average after: {load()}")


def per_file() -> None:
    """``--model auto`` on each shared paint and its ratio to one coated fit of the same file,
    beside the same before 2026-12-07 (:func:`as_before`) and the whole comparison
    (``rb.compare`` of today's candidates, every one fitted whole and scored: what ``--model
    auto`` cost before its two stages), one run."""
    print("\nEach shared paint (auto and coated: best of "
          f"{REPEAT}; the whole comparison: one run)\n")
    print("| file | one coated fit (s) | rb.fit('auto') (s) | ratio | before (s) | ratio "
          "| whole comparison (s) | ratio | kept (auto / before / whole) |\n"
          "|---|---|---|---|---|---|---|---|---|")
    for paint in PAINTS:
        meas = rb.read(DATA / "minidiff" / f"{paint}.astm")
        kept = rb.fit("auto", meas, progress=False).model_name  # warm: this file's tables
        kept_before = as_before(meas).model_name
        coated = best(lambda m=meas: rb.fit("coated", m, progress=False))
        auto = best(lambda m=meas: rb.fit("auto", m, progress=False))
        before = best(lambda m=meas: as_before(m))
        t0 = time.perf_counter()
        whole = rb.compare(meas, progress=False)
        t_whole = time.perf_counter() - t0
        print(f"| {paint} | {coated:.2f} | {auto:.2f} | {auto / coated:.1f}x | {before:.2f} | "
              f"{before / coated:.1f}x | {t_whole:.2f} | {t_whole / coated:.1f}x | {kept} / "
              f"{kept_before} / {whole.best.label} |", flush=True)


if __name__ == "__main__":
    main()
