"""Which fit loss should be the default? Measure ``relative``, ``log`` and ``robust`` side by side.

Issue 20, item 2 (``docs/fitting.md``, "Choosing the loss"). For each loss and each model
(``coated``, ``microfacet``, ``tr75``, built by name with their default options), on

* the three shared Mini-Diff paints (``../shared/data/minidiff``: ``C2_Black``, ``C8_Silver``,
  ``C12_OliveDrab``; every channel), and
* synthetic data from known parameters of the same models on the paints' own geometry (the
  Mini-Diff grid, incidences 0/20/40/60 deg, theta_r <= 75 deg), with the noise of a
  gonioreflectometer: multiplicative log-normal (5 %) plus an additive Gaussian floor (1e-3 of
  the peak), one data set per seed (also the seed of its fits' search),

it measures

(a) prediction of an incidence the fit did not see: fit 0/20/40 deg, predict 60 deg; the r.m.s.
    of ``ln x - ln f`` there (paints: against the data, samples with ``x > 0``; synthetic:
    against the noise-free truth) and the model/data peak ratio at 60 deg;
(b) the model/data peak ratio per incidence of a fit on every incidence (synthetic: against the
    truth's peak), with TR75's sigma and the largest albedo (0-85 deg, 89 deg) of that fit;
(c) recovery of known parameters (synthetic): the relative error of each parameter.

Every fit uses the library's defaults (``rb.fit(model, meas, loss=..., negative="drop")``: the
log-type losses need positive data, and the same samples are dropped for every loss). It prints
Markdown tables (medians over channels or seeds, with the range; "at a search limit": how
many of the fits on all incidences end with a parameter on a search bound: often a basin the
default search missed) and writes nothing else unless ``--out FILE``.

Usage::

    .venv/bin/python scripts/compare_losses.py            # the full run (3-9 min on 2 cores)
    .venv/bin/python scripts/compare_losses.py --quick    # one paint, 2 seeds, 2 starts
"""

from __future__ import annotations

import argparse
import math
import subprocess
import sys
import time
import warnings
from dataclasses import dataclass, field, fields, replace
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

import roughbrdf as rb
from roughbrdf.extrapolation import extrapolated_mask
from roughbrdf.fitting import FitOptions

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data" / "minidiff"
PAINTS = ("C2_Black", "C8_Silver", "C12_OliveDrab")
LOSSES = ("relative", "log", "robust")
MODELS = ("coated", "microfacet", "tr75")
FIT_INCIDENCES_DEG = (0.0, 20.0, 40.0)
HELD_OUT_DEG = 60.0
#: known parameters of the synthetic sets (only the names the model has; the rest keep the
#: model's defaults, so the script runs whatever the model's parameterization)
TRUTH = {"coated": {"n": 1.5, "rho": 0.05, "alpha": 0.1},
         "microfacet": {"alpha": 0.2, "n": 1.5, "k": 0.5, "ks": 0.5},
         "tr75": {"e": 0.3, "n": 1.5, "k": 0.2, "rho_L": 0.05}}
NOISE_LOG = 0.05
NOISE_FLOOR = 1e-3
ALBEDO_GRID_DEG = (*range(0, 90, 5), 89)


@dataclass
class Row:
    """The measured numbers of one model and loss, one entry per channel or seed."""

    heldout_rms: list[float] = field(default_factory=list)
    heldout_peak: list[float] = field(default_factory=list)
    peak: dict[float, list[float]] = field(default_factory=dict)
    sigma: list[float] = field(default_factory=list)
    albedo: list[float] = field(default_factory=list)
    seconds: list[float] = field(default_factory=list)
    search_limit: list[bool] = field(default_factory=list)
    param_err: dict[str, list[float]] = field(default_factory=dict)


def incidence_deg(meas: rb.Measurement) -> np.ndarray:
    """Each sample's incidence in degrees, rounded to the measured grid (0.1 deg)."""
    return np.round(np.degrees(meas.theta_i), 1)


def nearest(deg: np.ndarray, wanted: float) -> float:
    """The measured incidence nearest to ``wanted`` (degrees)."""
    grid = np.unique(deg)
    return float(grid[np.argmin(np.abs(grid - wanted))])


def measured(meas: rb.Measurement) -> np.ndarray:
    """The samples the instrument measured (not the reader-flagged extrapolated tail)."""
    return ~extrapolated_mask(meas.theta_r, meas.meta.get("extrapolated_beyond"))


def fit(model: str, meas: rb.Measurement, loss: str, starts: int | None,
        extra: dict[str, Any]) -> Any:
    """``rb.fit`` with the library's defaults but the loss (and ``negative="drop"``)."""
    kw: dict[str, Any] = dict(extra) if starts is None else {**extra, "starts": starts}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # energy, bound and convergence notes: measured here
        return rb.fit(model, meas, loss=loss, negative="drop", progress=False, **kw)


def peak_ratio(pred: np.ndarray, ref: np.ndarray) -> float:
    """max(model)/max(reference) over one incidence's samples (NaN without a positive one)."""
    top = float(np.max(ref)) if ref.size else math.nan
    return float(np.max(pred)) / top if top > 0 else math.nan


def rms_log(pred: np.ndarray, ref: np.ndarray) -> float:
    """r.m.s. of ``ln ref - ln pred`` over ``ref > 0`` (model floored at 1e-12 of the peak)."""
    ok = ref > 0
    floor = 1e-12 * float(np.max(np.abs(ref)))
    return float(np.sqrt(np.mean((np.log(ref[ok]) - np.log(np.maximum(pred[ok], floor))) ** 2)))


def max_albedo(model: rb.Model) -> float:
    """The largest directional-hemispherical reflectance over :data:`ALBEDO_GRID_DEG`."""
    return float(np.max(rb.albedo(model, np.radians(ALBEDO_GRID_DEG))))


def measure(model: str, loss: str, meas: rb.Measurement, refs: np.ndarray, row: Row,
            starts: int | None, extra: dict[str, Any] | None = None
            ) -> list[dict[str, float | None]]:
    """Fit ``meas`` (every channel) twice, add the numbers to ``row``; the fitted parameters.

    ``refs`` (N, C): the values the predictions are scored against (the data, or the noise-free
    truth of a synthetic set); ``extra``: more options of ``rb.fit``."""
    extra = extra or {}
    deg = incidence_deg(meas)
    keep = measured(meas)
    fit_set = np.isin(deg, [nearest(deg, t) for t in FIT_INCIDENCES_DEG])
    held = keep & (deg == nearest(deg, HELD_OUT_DEG))
    part = fit(model, meas.subset(fit_set), loss, starts, extra)
    t0 = time.perf_counter()
    whole = fit(model, meas, loss, starts, extra)
    row.seconds.append((time.perf_counter() - t0) / meas.n_channels)
    for j in range(meas.n_channels):
        pred = np.asarray(part.predict(meas.theta_i[held], meas.theta_r[held], meas.phi[held],
                                       channel=j), float)
        row.heldout_rms.append(rms_log(pred, refs[held, j]))
        row.heldout_peak.append(peak_ratio(pred, refs[held, j]))
        pred = np.asarray(whole.predict(meas.theta_i, meas.theta_r, meas.phi, channel=j), float)
        for t in np.unique(deg):
            sel = keep & (deg == t)
            row.peak.setdefault(float(t), []).append(peak_ratio(pred[sel], refs[sel, j]))
        row.sigma.append(float(whole[j].sigma))
        row.albedo.append(max_albedo(whole[j].model))
        limits = getattr(whole[j], "limits", {})  # (older trees: no kinds of limit)
        row.search_limit.append(any(str(v).startswith("search") for v in limits.values()))
    return [dict(c.params) for c in whole]


def paints(files: list[Path], starts: int | None, log: Any) -> dict[tuple[str, str], Row]:
    """(a) and (b) on the shared paints, every channel."""
    rows = {(m, loss): Row() for m in MODELS for loss in LOSSES}
    for path in files:
        meas = rb.read(path)
        for m in MODELS:
            for loss in LOSSES:
                log(f"paint {path.stem} {m} {loss}")
                measure(m, loss, meas, meas.values, rows[m, loss], starts)
    return rows


def synthetic_set(geometry: rb.Measurement, truth: rb.Model, seed: int
                  ) -> tuple[rb.Measurement, np.ndarray]:
    """Noisy data from ``truth`` on ``geometry``: ``f exp(0.05 e1) + 1e-3 max(f) e2``."""
    f = np.asarray(truth.brdf(geometry.theta_i, geometry.theta_r, geometry.phi), float)
    rng = np.random.default_rng(seed)
    peak = float(np.max(f[measured(geometry)]))
    x = f * np.exp(NOISE_LOG * rng.standard_normal(f.shape)) \
        + NOISE_FLOOR * peak * rng.standard_normal(f.shape)
    meas = replace(geometry, values=x[:, None], channels=["synthetic"], uncertainty=None)
    return meas, f[:, None]


def truth_model(name: str) -> rb.Model:
    """The model ``name`` (default options) at the :data:`TRUTH` values it has."""
    model = rb.model(name)
    return model.with_params(**{k: v for k, v in TRUTH[name].items() if k in model.param_names})


def unconstrained_if_infeasible(truth: rb.Model) -> dict[str, Any]:
    """``{"energy_constraint": False}`` when the truth itself reflects more than it receives on
    the albedo grid (the unshadowed TR75 does at 89 deg whatever its parameters) and this
    version of the library has the constraint: a constrained fit could not reach the truth, and
    the comparison is of the losses. Else no option."""
    if "energy_constraint" in {f.name for f in fields(FitOptions)} \
            and max_albedo(truth) > 1 + 1e-3:
        return {"energy_constraint": False}
    return {}


def synthetic(geometry: rb.Measurement, seeds: int, starts: int | None, log: Any
              ) -> dict[tuple[str, str], Row]:
    """(a), (b) and (c) on synthetic sets from known parameters, one per seed."""
    rows = {(m, loss): Row() for m in MODELS for loss in LOSSES}
    for m in MODELS:
        truth = truth_model(m)
        known = {k: float(v) for k, v in truth.params.items() if v}  # a 0 has no relative error
        for seed in range(seeds):
            meas, f = synthetic_set(geometry, truth, seed)
            # each set is searched from its own Sobol points: with one search seed for all sets
            # a missed basin repeats on every set and reads as a property of the loss
            extra = {**unconstrained_if_infeasible(truth), "seed": seed}
            for loss in LOSSES:
                log(f"synthetic {m} seed {seed} {loss}")
                row = rows[m, loss]
                got = measure(m, loss, meas, f, row, starts, extra)[0]
                for k, v in known.items():
                    value = got.get(k)
                    if value is not None:  # a parameter the fitted model has
                        row.param_err.setdefault(k, []).append(abs(float(value) - v) / abs(v))
    return rows


def med(values: list[float]) -> float:
    """The median of the finite values (NaN without one)."""
    a = np.asarray(values, float)
    a = a[np.isfinite(a)]
    return float(np.median(a)) if a.size else math.nan


def num(v: float) -> str:
    """Three significant digits."""
    return "–" if not math.isfinite(v) else f"{v:.3g}"


def span(values: list[float]) -> str:
    """``median (min–max)`` of the finite values."""
    a = np.asarray(values, float)
    a = a[np.isfinite(a)]
    if not a.size:
        return "–"
    return f"{num(float(np.median(a)))} ({num(float(a.min()))}–{num(float(a.max()))})"


def table(rows: dict[tuple[str, str], Row], synthetic_rows: bool) -> list[str]:
    """One Markdown table: a line per model and loss."""
    incid = sorted({t for r in rows.values() for t in r.peak})
    head = ["model", "loss", f"(a) held-out {HELD_OUT_DEG:g}° r.m.s. ln",
            f"(a) held-out {HELD_OUT_DEG:g}° peak ratio"]
    head += [f"(b) peak ratio {t:g}°" for t in incid]
    head += ["TR75 σ", "max albedo", "at a search limit", "s/fit"]
    if synthetic_rows:
        head.append("(c) relative error per parameter")
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for (m, loss), r in rows.items():
        cells = [m, loss, span(r.heldout_rms), span(r.heldout_peak)]
        cells += [span(r.peak.get(t, [])) for t in incid]
        cells += [num(med(r.sigma)), span(r.albedo),
                  f"{sum(r.search_limit)}/{len(r.search_limit)}", num(med(r.seconds))]
        if synthetic_rows:
            cells.append(", ".join(f"{k} {num(med(v))}" for k, v in r.param_err.items()))
        out.append("| " + " | ".join(cells) + " |")
    return out


def commit() -> str:
    """The tree's commit (short hash; ``+changes`` when the work tree differs)."""
    def git(*args: str) -> str:
        return subprocess.run(["git", "-C", str(ROOT), *args], capture_output=True,
                              text=True, check=False).stdout.strip()
    dirty = git("status", "--porcelain", "--untracked-files=no")
    return (git("rev-parse", "--short", "HEAD") or "unknown") + (" +changes" if dirty else "")


def main(argv: list[str] | None = None) -> int:
    """Run the comparison; print the Markdown (and write it to ``--out``)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help="one paint (C2_Black), 2 seeds, 2 starts per fit (under 2 min)")
    ap.add_argument("--seeds", type=int, default=None, help="synthetic seeds (default 5)")
    ap.add_argument("--data", type=Path, default=DATA, help=f"paint folder (default {DATA})")
    ap.add_argument("--out", type=Path, default=None, help="also write the Markdown here")
    ap.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    args = ap.parse_args(argv)
    seeds = args.seeds if args.seeds is not None else (2 if args.quick else 5)
    if seeds < 1:
        ap.error(f"--seeds must be >= 1 (got {seeds})")
    names = PAINTS[:1] if args.quick else PAINTS
    files = [args.data / f"{p}.astm" for p in names]
    missing = [str(f) for f in files if not f.is_file()]
    if missing:  # the paints are shared data beside the checkout, not part of the repository
        ap.error(f"--data: paint file(s) not found: {', '.join(missing)}")
    starts = 2 if args.quick else None

    def log(msg: str) -> None:
        if not args.quiet:
            print(f"[{time.perf_counter() - t0:6.1f} s] {msg}", file=sys.stderr, flush=True)

    t0 = time.perf_counter()
    tree = commit()  # the code this run imported (the tree may move on while it runs)
    paint_rows = paints(files, starts, log)
    geometry = rb.read(files[0])
    synth_rows = synthetic(geometry.select_channel(0), seeds, starts, log)
    elapsed = time.perf_counter() - t0
    text = report(paint_rows, synth_rows, names, seeds, starts, elapsed, tree)
    print(text)
    if args.out is not None:
        args.out.write_text(text + "\n", encoding="utf-8")
    return 0


def report(paint_rows: dict[tuple[str, str], Row], synth_rows: dict[tuple[str, str], Row],
           names: tuple[str, ...], seeds: int, starts: int | None, elapsed: float,
           tree: str) -> str:
    """The Markdown: what was run, then the two tables."""
    when = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    truth = "; ".join(f"{m}: " + ", ".join(f"{k} = {v:g}" for k, v in
                                           truth_model(m).params.items() if v is not None)
                      + f" (max albedo {max_albedo(truth_model(m)):.3g}"
                      + (", fitted without the energy constraint)"
                         if unconstrained_if_infeasible(truth_model(m)) else ")")
                      for m in MODELS)
    lines = [f"Run {when}, commit {tree}, roughbrdf {rb.__version__}, "
             f"{elapsed:.0f} s; fits with the default options"
             + ("" if starts is None else f" but starts = {starts}")
             + ", `negative=\"drop\"`. Each cell: median (min–max).", "",
             f"**Paints** ({', '.join(names)}; every channel: {3 * len(names)} channels). "
             f"(a) fit {'/'.join(f'{t:g}' for t in FIT_INCIDENCES_DEG)}°, predict "
             f"{HELD_OUT_DEG:g}° (r.m.s. of ln data − ln model, data > 0); (b) fit on all.", "",
             *table(paint_rows, False), "",
             f"**Synthetic** ({seeds} seeds; C2_Black geometry; noise ×exp({NOISE_LOG:g} N(0,1)) "
             f"+ {NOISE_FLOOR:g}·peak·N(0,1); search seed = noise seed); scored against the "
             f"noise-free truth. "
             f"Truth: {truth}.", "",
             *table(synth_rows, True)]
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
