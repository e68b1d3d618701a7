"""The README's table of the shared paints: ``rb.fit("auto")`` on each, every candidate's figures.

For each Mini-Diff paint of ``../shared/data/minidiff`` (or ``ROUGHBRDF_SHARED_DATA``), the
comparison ``rb.fit("auto")`` attaches (``FitResult.model_choice``, ``docs/fitting.md``, "Model
choice"): per candidate, ranked as ``--model auto`` ranks them, its loss, sigma and rms-log per
channel (465 / 525 / 630 nm), the leave-one-incidence-out score (CV), the model/data peak ratio
at every measured incidence (0, 20, 40, 60 deg; per channel), the largest albedo (0-85, 89 deg)
and the parameters on a search limit. A candidate skipped after the first channel (its score
there more than ``SKIP_MARGIN`` behind the best) has that channel's figures only. Prints
Markdown; run from the repository::

    python scripts/paint_table.py
"""

from __future__ import annotations

import os
import sys
import warnings
from pathlib import Path

import roughbrdf as rb

HERE = Path(__file__).resolve().parent
DATA = Path(os.environ.get("ROUGHBRDF_SHARED_DATA", HERE.parent.parent / "shared" / "data"))
PAINTS = ("C2_Black", "C8_Silver", "C12_OliveDrab")


def _per_channel(values: list[float], fmt: str = ".3f") -> str:
    return " / ".join(format(v, fmt) for v in values)


def _rows(paint: str, res: rb.fitting.FitResult) -> list[str]:
    rows = []
    for cand in res.model_choice.candidates:
        r = cand.result
        plaus = [r.plausibility(i) for i in range(len(r.channels))]
        incid = plaus[0].peak_theta_deg
        peaks = [_per_channel([p.peak_ratio[j] for p in plaus], ".2g") for j in range(len(incid))]
        limits = r.search_limits
        name = f"**{cand.label}** (auto)" if cand is res.model_choice.best else cand.label
        if cand.partial:
            name += " (first channel only)"
        sig = _per_channel([c.sigma for c in r.channels])
        cv = "-" if cand.cv is None else f"{cand.cv:.3f}"  # a candidate stopped unscored
        rows.append(f"| {paint} | {name} | {r.loss} | {sig} | {cand.rms_log:.3f} | {cv} | "
                    + " | ".join(peaks) + " | "
                    f"{max(p.max_albedo for p in plaus):.3f} | {', '.join(limits) or '-'} |")
    return rows


def main() -> int:
    if not (DATA / "minidiff").is_dir():
        print(f"no shared data at {DATA}: nothing to do (set ROUGHBRDF_SHARED_DATA)")
        return 0
    warnings.simplefilter("ignore")
    print("| file | model | loss | sigma (465 / 525 / 630 nm) | rms-log | CV | peak ratio 0° "
          "| 20° | 40° | 60° | max albedo | search limit |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for paint in PAINTS:
        res = rb.fit("auto", rb.read(DATA / "minidiff" / f"{paint}.astm"), progress=False)
        print("\n".join(_rows(paint, res)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
