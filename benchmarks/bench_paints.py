"""Paints everywhere on the hemisphere: model choice on the Mini-Diff files (``make bench``).

Needs ``../shared/data`` (or ``ROUGHBRDF_SHARED_DATA``); prints a note and returns without it.

1. **Table per paint and model.** Each candidate of ``--model auto``
   (:data:`roughbrdf.fitting.choice.compare.AUTO_CANDIDATES`) and two more (three lobes; two lobes
   over an Oren-Nayar substrate), fitted with ``rb.fit`` defaults (relative loss, every
   measured sample: theta_r > 75 deg is the instrument's extrapolation and left out,
   :mod:`roughbrdf.extrapolation`), and the joint fit of the chosen model: sigma and rms-log per
   channel, BIC differences, the leave-one-incidence-out score. Markdown for
   ``docs/fitting.md``.
2. **The must-show figures.** The best model by ``--model auto`` on the three paints x three
   channels: the median sigma and rms-log (targets 0.20 and 0.25), and the same fits' figures
   on every sample of the file (extrapolated ones included), for comparison.
3. **Time of ``--model auto``** on one file (three channels), the ``roughbrdf fit`` path
   through ``rb.fit("auto")`` (the compiled kernels warmed up first; best of ``REPEAT``).

With ``--docs`` the figures of the chosen fits are saved as ``docs/img/paint_<file>.png``.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np

import roughbrdf as rb
from roughbrdf.fitting.choice.compare import AUTO_CANDIDATES, information

HERE = Path(__file__).resolve().parent
DATA = Path(os.environ.get("ROUGHBRDF_SHARED_DATA", HERE.parent.parent / "shared" / "data"))
PAINTS = ("C2_Black", "C8_Silver", "C12_OliveDrab")
EXTRA = ("coated(lobes=3)", "coated(lobes=2, diffuse=oren-nayar)")
REPEAT = 3


def _metrics_all_samples(res) -> tuple[list[float], list[float]]:
    """sigma and rms-log of each channel's fitted model on every sample of the file with a
    positive value (the extrapolated ones included; x <= 0 has no log)."""
    m = res.measurement
    sig, rl = [], []
    for c in res.channels:
        x = m.values[:, m.channel_index(c.channel)]
        f = res.predict(m.theta_i, m.theta_r, m.phi, channel=c.channel)
        fs = np.maximum(f, 1e-12 * np.max(np.abs(x)))  # the fit's floor (fitting.problem.objective)
        sig.append(float(np.sqrt(np.mean((x / fs - 1.0) ** 2))))
        pos = (x > 0) & (f > 0)
        rl.append(float(np.sqrt(np.mean(np.log(x[pos] / f[pos]) ** 2))))
    return sig, rl


def table() -> list:
    """Print the table per paint and model; return the chosen fits."""
    print("### Paints: every candidate (relative loss, measured samples)\n")
    print("| file | model | k | sigma (465 / 525 / 630 nm) | rms-log (465 / 525 / 630 nm) "
          "| dBIC | CV | time (s) |")
    print("|---|---|---|---|---|---|---|---|")
    chosen = []
    for name in PAINTS:
        meas = rb.read(DATA / "minidiff" / f"{name}.astm")
        comp = rb.compare(meas, [*AUTO_CANDIDATES, *EXTRA])
        auto = [c for c in comp.candidates if c.label in
                {rb.models.spec_text(rb.models.from_spec(s)) for s in AUTO_CANDIDATES}]
        for c in comp.candidates:
            star = " **(auto)**" if c is auto[0] else ""
            print(f"| {name} | {c.label}{star} | {c.k} | "
                  + " / ".join(f"{ch.sigma:.3f}" for ch in c.result.channels) + " | "
                  + " / ".join(f"{ch.rms_log:.3f}" for ch in c.result.channels)
                  + f" | {c.bic - comp.best.bic:.0f} | {c.cv:.4f} | {c.elapsed:.1f} |")
        best = auto[0]
        joint = rb.fit(best.result.channels[0].model, meas, joint=True, progress=False)
        k, _, _, bic = information(joint)
        print(f"| {name} | {best.label}, joint | {k} | "
              + " / ".join(f"{ch.sigma:.3f}" for ch in joint.channels) + " | "
              + " / ".join(f"{ch.rms_log:.3f}" for ch in joint.channels)
              + f" | {bic - comp.best.bic:.0f} | - | {joint.elapsed:.1f} |")
        chosen.append((name, best))
    print()
    return chosen


def must_show(chosen: list) -> None:
    """Medians of the best-by-auto fits over 3 paints x 3 channels; the same on all samples."""
    sig = [ch.sigma for _, b in chosen for ch in b.result.channels]
    rl = [ch.rms_log for _, b in chosen for ch in b.result.channels]
    print("### Best model by --model auto, 3 paints x 3 channels\n")
    print(f"- models chosen: {', '.join(f'{n}: {b.label}' for n, b in chosen)}")
    print(f"- median sigma {np.median(sig):.3f} (target <= 0.20), median rms-log "
          f"{np.median(rl):.3f} (target <= 0.25), on the samples the fits use by default")
    alls, allr = [], []
    for _, b in chosen:
        s, r = _metrics_all_samples(b.result)
        alls += s
        allr += r
    print(f"- the same fitted models on every sample of the files, theta_r > 75 deg (the "
          f"instrument's extrapolation) included: median sigma {np.median(alls):.3f}, median "
          f"rms-log {np.median(allr):.3f}")
    refit_s, refit_r = [], []
    for name, b in chosen:
        meas = rb.read(DATA / "minidiff" / f"{name}.astm")
        res = rb.fit(rb.models.from_spec(b.label), meas, extrapolated="keep", progress=False)
        refit_s += [c.sigma for c in res.channels]
        refit_r += [c.rms_log for c in res.channels]
    print(f"- the chosen models fitted to every sample (extrapolated='keep'): median sigma "
          f"{np.median(refit_s):.3f}, median rms-log {np.median(refit_r):.3f}\n")


def auto_time() -> None:
    """``rb.fit("auto")`` on one file, three channels."""
    meas = rb.read(DATA / "minidiff" / "C2_Black.astm")
    times = []
    for _ in range(REPEAT + 1):  # the first run compiles what is not cached yet
        t0 = time.perf_counter()
        res = rb.fit("auto", meas, progress=False)
        times.append(time.perf_counter() - t0)
    print("### --model auto on one Mini-Diff file (3 channels, 4 candidates, CV included)\n")
    print(f"- C2_Black: best of {REPEAT} warm runs {min(times[1:]):.2f} s (first run "
          f"{times[0]:.2f} s); chosen {res.model_name} (target <= 10 s)\n")


def save_figures(chosen: list) -> None:
    """``docs/img/paint_<file>.png``: the chosen fit's figure of the 525 nm channel."""
    out = HERE.parent / "docs" / "img"
    for name, best in chosen:
        fig, _ = best.result.plot("525nm")
        fig.savefig(out / f"paint_{name}.png", dpi=90)
        print(f"saved {out / f'paint_{name}.png'}")


def main(argv: list[str] | None = None) -> None:
    args = sys.argv[1:] if argv is None else argv
    if not (DATA / "minidiff").is_dir():
        print(f"no shared data at {DATA}: skipped (set ROUGHBRDF_SHARED_DATA)")
        return
    auto_time()
    chosen = table()
    must_show(chosen)
    if "--docs" in args:
        save_figures(chosen)


if __name__ == "__main__":
    main()
