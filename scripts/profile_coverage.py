"""Do profile intervals cover the truth better than the standard errors? A parametric bootstrap.

As ``one_sided_coverage.py``: C8_Silver's 525 nm fit (the model ``rb.fit("auto")`` keeps) with
the flakes' edge tint ``g_m`` set to ``--truth`` (default 0.3: near its physical limit 0, where
the cost is far from quadratic) is the truth of synthetic sets on the paint's geometry with the
noise of ``coverage_paints``; each set is fitted with ``rb.fit`` defaults and
``intervals="profile"``. For every free parameter, over the fits where it has a standard error,
it counts how often ``value +/- stderr`` and ``+/- 2 stderr`` cover the truth, and how often the
68 % and 95 % profile intervals do (a side the data did not bound counts as open). Prints a
Markdown table. Run from the repository::

    python scripts/profile_coverage.py [--seeds 40] [--truth 0.3] [--channel 525nm]

Time: about 4 s per seed on the idle 2-core development machine.
"""

from __future__ import annotations

import argparse
import math
import sys
import time

from coverage_paints import DATA, FLOOR, PAINTS, file_floor, geometry, noisy

import roughbrdf as rb

PAINT = "C8_Silver"


def covered(lo: float | None, hi: float | None, truth: float) -> bool:
    """Whether ``[lo, hi]`` holds ``truth`` (None: that side open)."""
    return (lo is None or lo <= truth) and (hi is None or truth <= hi)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=40)
    parser.add_argument("--truth", type=float, default=0.3)
    parser.add_argument("--channel", default="525nm")
    args = parser.parse_args(argv)
    if not (DATA / "minidiff").is_dir():
        print(f"no Mini-Diff data in {DATA}: set ROUGHBRDF_SHARED_DATA", file=sys.stderr)
        return 2
    spec = PAINTS[PAINT]
    meas = rb.read(DATA / "minidiff" / f"{PAINT}.astm")
    (c0,) = rb.fit(spec, meas, channel=args.channel, progress=False).channels
    truth = c0.model.with_values(["g_m"], [args.truth])
    keep = geometry(meas, None)
    geo = [meas.theta_i[keep], meas.theta_r[keep], meas.phi[keep]]
    measured = meas.values[keep, list(meas.channels).index(args.channel)]
    floor = file_floor(truth.brdf(*geo), measured, FLOOR)
    counts = {nm: [0, 0, 0, 0, 0] for nm in c0.free}  # fits, wald 1, wald 2, prof 68, prof 95
    t0 = time.perf_counter()
    for seed in range(args.seeds):
        (c,) = rb.fit(spec, noisy(truth, geo, seed, floor), intervals="profile",
                      progress=False).channels
        for nm, n in counts.items():
            t, se = float(truth.params[nm]), c.stderr[nm]  # type: ignore[arg-type]
            if nm not in c.intervals or se is None or not math.isfinite(se):
                continue
            v = float(c.params[nm])  # type: ignore[arg-type]
            n[0] += 1
            n[1] += abs(v - t) <= se
            n[2] += abs(v - t) <= 2 * se
            n[3] += covered(*c.intervals[nm]["68"], t)
            n[4] += covered(*c.intervals[nm]["95"], t)
        print(f"seed {seed}: {time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)
    print(f"{PAINT} `{spec}`, {args.channel}, g_m of the truth {args.truth:g}; "
          f"{args.seeds} seeds, rb.fit defaults + intervals='profile'")
    print("| parameter | truth | fits with a stderr | +/- 1 se | 68 % profile | +/- 2 se | "
          "95 % profile |")
    print("|---|---|---|---|---|---|---|")
    for nm, (n, w1, w2, p68, p95) in counts.items():
        if n:
            print(f"| {nm} | {float(truth.params[nm]):.4g} | {n} | {w1 / n:.0%} | {p68 / n:.0%} "  # type: ignore[arg-type]
                  f"| {w2 / n:.0%} | {p95 / n:.0%} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
