"""The margin of ``--model auto``'s skip (``roughbrdf.fitting.choice.auto.SKIP_MARGIN``), measured.

For each shared paint: every default candidate compared on the whole file (``rb.compare``, the
choice without any skip), each candidate's score on the first channel alone and its ratio to
the best there, and ``rb.fit("auto")`` (the two stages): which candidates it skipped and
whether it keeps the same candidate; with the times of both and of one ``coated`` fit. Run from
the repository with ``../shared/data`` beside it::

    python scripts/auto_margin.py

Exits 1 when ``rb.fit("auto")`` keeps another candidate than the whole comparison.
"""

from __future__ import annotations

import os
import sys
import time
import warnings
from pathlib import Path

import roughbrdf as rb
from roughbrdf.fitting.choice.auto import SKIP_MARGIN
from roughbrdf.fitting.choice.compare import AUTO_CANDIDATES, cross_validate, score_metric
from roughbrdf.fitting.problem.options import FitOptions
from roughbrdf.models import from_spec, spec_text

LABELS = [spec_text(from_spec(c)) for c in AUTO_CANDIDATES]

HERE = Path(__file__).resolve().parent
DATA = Path(os.environ.get("ROUGHBRDF_SHARED_DATA", HERE.parent.parent / "shared" / "data"))
PAINTS = ("C2_Black", "C8_Silver", "C12_OliveDrab")


def first_channel_scores(meas: rb.Measurement) -> dict[str, float]:
    """Each candidate's leave-one-incidence-out score on the first channel alone."""
    opts = FitOptions(progress=False, channel=[0])
    metric, _ = score_metric([from_spec(c) for c in AUTO_CANDIDATES], opts)
    return {label: cross_validate(rb.fit(c, meas, options=opts), opts, metric=metric)
            for c, label in zip(AUTO_CANDIDATES, LABELS, strict=True)}


def main() -> int:
    warnings.simplefilter("ignore")
    same = True
    print(f"SKIP_MARGIN = {SKIP_MARGIN}\n")
    print("| paint | candidate | first-channel score | / best | whole-file score | kept (whole) "
          "| skipped by auto | kept (auto) |\n|---|---|---|---|---|---|---|---|")
    for paint in PAINTS:
        meas = rb.read(DATA / "minidiff" / f"{paint}.astm")
        t0 = time.perf_counter()
        whole = rb.compare(meas)
        t_whole = time.perf_counter() - t0
        t0 = time.perf_counter()
        auto = rb.fit("auto", meas, progress=False)
        t_auto = time.perf_counter() - t0
        t0 = time.perf_counter()
        rb.fit("coated", meas, progress=False)
        t_coated = time.perf_counter() - t0
        first = first_channel_scores(meas)
        low = min(first.values())
        cv = {c.label: c.cv for c in whole.candidates}
        skipped = {c.label for c in auto.model_choice.candidates if c.partial}
        for label in LABELS:
            print(f"| {paint} | {label} | {first[label]:.4f} | {first[label] / low:.2f} | "
                  f"{cv[label]:.4f} | {'yes' if whole.best.label == label else ''} | "
                  f"{'yes' if label in skipped else ''} | "
                  f"{'yes' if auto.model_name == label else ''} |")
        same &= whole.best.label == auto.model_name
        print(f"\n{paint}: whole comparison {t_whole:.1f} s ({t_whole / t_coated:.1f}x one coated "
              f"fit), auto {t_auto:.1f} s ({t_auto / t_coated:.1f}x), coated {t_coated:.2f} s\n",
              file=sys.stderr)
    print("\nthe same choice on every paint" if same else "\nDIFFERENT CHOICE")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
