"""Do the one-sided limits of parameters on a physical limit cover the truth? A bootstrap.

The metallic paint C8_Silver (``../shared/data/minidiff`` or ``ROUGHBRDF_SHARED_DATA``) fitted by
the model ``rb.fit("auto")`` keeps there (``coverage_paints.PAINTS``) ends with the flakes' edge
tint ``g_m`` on its physical limit 0 at 525 nm. Its fit, with ``g_m`` set to each ``--truths``
value in turn, is the truth of synthetic sets on the paint's own geometry with the
gonioreflectometer noise of ``coverage_paints`` (log-normal 5 %, the additive floor it chooses),
one noise seed per set, each fitted with ``rb.fit`` defaults and its one-sided limits added as
``intervals="profile"`` adds them. A fit that ends with ``g_m`` on 0 reports the one-sided 95 %
limit ``u`` (``roughbrdf.fitting.results.one_sided``); it *misses* when ``u`` is below the
truth. What the limits promise (``docs/fitting.md``, "One-sided limits at a
physical limit"): misses in at most 5 % of all seeds, for every truth.

Prints a Markdown table: truth, seeds, fits on the limit, misses (count and share of all seeds),
the median ``u`` of the fits on the limit, and for the others how often ``value - 1.645 stderr``
(their one-sided 95 % lower end) lies above the truth. Run from the repository::

    python scripts/one_sided_coverage.py [--seeds 40] [--truths 0,0.1,0.2,0.4] [--channel 525nm]

Time: about 1 s per seed on the idle 2-core development machine.
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np
from coverage_paints import DATA, FLOOR, PAINTS, file_floor, geometry, noisy

import roughbrdf as rb
from roughbrdf.fitting import FitOptions
from roughbrdf.fitting.results.intervals import add_profiles

PAINT = "C8_Silver"
NAME = "g_m"
Z = 1.6448536269514722  # one-sided 95 %


def run(truth_value: float, seeds: int, channel: str) -> str:
    """One table row: ``g_m`` of the truth set to ``truth_value``."""
    spec = PAINTS[PAINT]
    meas = rb.read(DATA / "minidiff" / f"{PAINT}.astm")
    (c0,) = rb.fit(spec, meas, channel=channel, progress=False).channels
    truth = c0.model.with_values([NAME], [truth_value])
    keep = geometry(meas, None)
    geo = [meas.theta_i[keep], meas.theta_r[keep], meas.phi[keep]]
    measured = meas.values[keep, list(meas.channels).index(channel)]
    floor = file_floor(truth.brdf(*geo), measured, FLOOR)
    on_limit, misses, above, limits = 0, 0, 0, []
    t0 = time.perf_counter()
    for seed in range(seeds):
        synthetic = noisy(truth, geo, seed, floor)
        # rb.fit(..., intervals="profile") without the two-sided intervals (not counted here)
        (c,) = add_profiles(rb.fit(spec, synthetic, progress=False), synthetic,
                            FitOptions(intervals="profile", progress=False),
                            two_sided=False).channels
        if c.limits.get(NAME, "").startswith("physical"):
            on_limit += 1
            u = c.one_sided.get(NAME)
            limits.append(math.inf if u is None else u)
            misses += u is not None and u < truth_value
        else:
            se = c.stderr[NAME]
            above += se is not None and c.params[NAME] - Z * se > truth_value  # type: ignore
        print(f"truth {truth_value} seed {seed}: {time.perf_counter() - t0:.0f} s",
              file=sys.stderr, flush=True)
    med = f"{np.median(limits):.3g}" if limits else "-"
    return (f"| {truth_value:g} | {seeds} | {on_limit} | {misses} ({misses / seeds:.0%}) | {med} "
            f"| {above} of {seeds - on_limit} |")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=40)
    parser.add_argument("--truths", default="0,0.1,0.2,0.4")
    parser.add_argument("--channel", default="525nm")
    args = parser.parse_args(argv)
    if not (DATA / "minidiff").is_dir():
        print(f"no Mini-Diff data in {DATA}: set ROUGHBRDF_SHARED_DATA", file=sys.stderr)
        return 2
    print(f"{PAINT} `{PAINTS[PAINT]}`, {args.channel}, {NAME} set to each truth; "
          f"rb.fit defaults")
    print("| truth | seeds | on the limit | u below the truth | median u | interior: "
          "value - 1.645 se above the truth |")
    print("|---|---|---|---|---|---|")
    for t in (float(v) for v in args.truths.split(",")):
        print(run(t, args.seeds, args.channel), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
