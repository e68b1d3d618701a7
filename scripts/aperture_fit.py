"""Can a fit find the instrument aperture the Mini-Diff does not record? Measured, two ways.

Issue 28, item 5 (``docs/fitting.md``, "Fitting the aperture: measured, not offered"). The
aperture is chosen by a **profile**: the model is fitted at each half-angle of
:data:`GRID_DEG` (``rb.fit(..., aperture=a)``, every incidence and channel of the set given,
``negative="drop"``), the total cost (sum of ``chi2`` over the channels) is read at each, the
lowest is kept and refined by the vertex of the parabola through it and its two neighbours (a
minimum on the grid's edge is reported as that edge). One aperture per file: shared by all
incidences and channels.

(a) **Synthetic**: data from a known one-lobe ``coated`` model (``n = 1.5``, ``rho = 0.05``,
    ``alpha`` of :data:`ALPHAS`) on the Mini-Diff grid (C2_Black's geometry, incidences
    0/20/40/60 deg), blurred by known apertures (:data:`TRUE_DEG`, the library's own average,
    :func:`roughbrdf.instrument.aperture_average`, with the 37-point rule so that the data are
    not made with the fit's 19-point rule), with the instrument noise of ``docs/fitting.md``
    (x exp(0.05 N(0,1)) + 1e-3 of the peak x N(0,1)). Per set: the chosen aperture, the fitted
    ``alpha`` at no aperture, at the truth and at the chosen one, the correlation of aperture
    and fitted ``alpha`` along the profile and the profile's flatness (how much the cost at no
    aperture is above the minimum; the 1-sigma width of the aperture from the parabola's
    curvature, the noise variance taken as ``cost_min / (N - p)``, samples counted as
    independent, so a lower bound).
(b) **The shared paints** (``$ROUGHBRDF_SHARED_DATA/minidiff`` or ``../shared/data/minidiff``):
    the profile on the 0/20/40 deg incidences, then the 60 deg incidence predicted (r.m.s. of
    ``ln x - ln f`` over the measured samples with ``x > 0``; model/data peak ratio) with the
    chosen aperture and without, per channel, as ``scripts/compare_losses.py`` does.

It prints Markdown tables (and writes them to ``--out FILE``). Run from the repository::

    python scripts/aperture_fit.py              # both parts, about 16 min on 2 loaded cores
    python scripts/aperture_fit.py --part paints --paint C8_Silver \
        --model "coated-conductor(coat=false, diffuse=true, flakes=reflectance)"
    python scripts/aperture_fit.py --part synthetic --seeds 3   # 723 s
    python scripts/aperture_fit.py --quick      # 3 grid points, one paint, starts = 2 (not timed)

Every fit uses ``starts = 4`` on the synthetic sets (one lobe, known box) and the default
search on the paints; a run of the whole script took 939 s on two cores loaded by other work
(2026-12-06; each aperture fit costs about 19 times the model evaluations of a plain one).
``--model`` changes the paints' model (its roughness column is the first of ``alpha``,
``alpha_m`` it has), ``--paint`` the paints, ``--seeds`` the noise draws per synthetic set
(one table row each).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

import roughbrdf as rb
from roughbrdf.extrapolation import extrapolated_mask
from roughbrdf.instrument import aperture_average

HERE = Path(__file__).resolve().parent
DATA = Path(os.environ.get("ROUGHBRDF_SHARED_DATA", HERE.parent.parent / "shared" / "data"))
PAINTS = ("C2_Black", "C8_Silver", "C12_OliveDrab")
GRID_DEG = tuple(0.5 * k for k in range(9))  # 0, 0.5, ..., 4 deg
ALPHAS = (0.02, 0.05)
TRUE_DEG = (0.0, 1.0, 2.0, 3.0)
TRUTH = {"n": 1.5, "rho": 0.05}
NOISE_LOG = 0.05
NOISE_FLOOR = 1e-3
FIT_INCIDENCES_DEG = (0.0, 20.0, 40.0)
HELD_OUT_DEG = 60.0


@dataclass
class Profile:
    """Costs and fits over the aperture grid, and the chosen aperture."""

    grid: np.ndarray       # degrees
    cost: np.ndarray       # sum of chi2 over channels
    fits: list[Any]        # FitResult per grid point
    chosen: float          # degrees
    edge: bool             # minimum on the grid's edge (no parabola)
    width: float           # 1-sigma from the curvature (degrees; NaN at an edge)
    n_points: int
    n_free: int


def fit(model: str, meas: rb.Measurement, aperture_deg: float, **kw: Any) -> Any:
    """``rb.fit`` at one aperture (degrees; 0: none), defaults otherwise but ``negative``."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # bound and convergence notes: measured here
        return rb.fit(model, meas, aperture=math.radians(aperture_deg) or None,
                      negative="drop", progress=False, **kw)


def parabola(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Vertex and curvature ``k`` (``y = k (x - x0)^2 + c``) through three points."""
    a, b, _ = np.polyfit(x, y, 2)
    return float(-b / (2 * a)), float(a)


def profile(model: str, meas: rb.Measurement, grid: tuple[float, ...], log: Any,
            **kw: Any) -> Profile:
    """The profile over ``grid`` (degrees) and the refined minimum."""
    fits, cost = [], []
    for a in grid:
        log(f"  aperture {a:g} deg")
        r = fit(model, meas, a, **kw)
        fits.append(r)
        cost.append(sum(c.chi2 for c in r.channels))
    g, c = np.asarray(grid, float), np.asarray(cost, float)
    i = int(np.argmin(c))
    n = sum(ch.n_points for ch in fits[i].channels)
    p = sum(ch.n_varys for ch in fits[i].channels)
    if 0 < i < g.size - 1:
        x0, k = parabola(g[i - 1:i + 2], c[i - 1:i + 2])
        # guard: a parabola through three points around a grid minimum opens upward and has
        # its vertex between the outer two; anything else (round-off on a flat profile) keeps
        # the grid point
        if not (k > 0 and g[i - 1] <= x0 <= g[i + 1]):
            x0, k = float(g[i]), math.nan
        noise = c[i] / max(n - p, 1)  # guard: more free values than samples cannot happen here
        width = math.sqrt(noise / k) if k > 0 else math.nan
        return Profile(g, c, fits, x0, False, width, n, p)
    return Profile(g, c, fits, float(g[i]), True, math.nan, n, p)


def along(prof: Profile, name: str, at: float, channel: int = 0) -> float:
    """A fitted parameter along the profile, linearly interpolated at ``at`` degrees."""
    v = [float(r[channel].params[name]) for r in prof.fits]
    return float(np.interp(at, prof.grid, v))


def measured(meas: rb.Measurement) -> np.ndarray:
    """The samples the instrument measured (not the reader's extrapolated tail)."""
    return ~extrapolated_mask(meas.theta_r, meas.meta.get("extrapolated_beyond"))


def incidence_deg(meas: rb.Measurement) -> np.ndarray:
    """Each sample's incidence, degrees, rounded to 0.1 deg."""
    return np.round(np.degrees(meas.theta_i), 1)


def rms_log(pred: np.ndarray, ref: np.ndarray) -> float:
    """r.m.s. of ``ln ref - ln pred`` over ``ref > 0`` (model floored at 1e-12 of the peak:
    a model value of 0 has no logarithm)."""
    ok = ref > 0
    floor = 1e-12 * float(np.max(np.abs(ref)))
    return float(np.sqrt(np.mean((np.log(ref[ok]) - np.log(np.maximum(pred[ok], floor))) ** 2)))


def synthetic_set(geometry: rb.Measurement, alpha: float, aperture_deg: float, seed: int
                  ) -> rb.Measurement:
    """Noisy data from the known model blurred by a known aperture."""
    truth = rb.model("coated", alpha=alpha, **TRUTH)
    f = np.asarray(aperture_average(truth, geometry.theta_i, geometry.theta_r, geometry.phi,
                                    math.radians(aperture_deg), points=37), float)
    rng = np.random.default_rng(seed)
    peak = float(np.max(f[measured(geometry)]))
    x = f * np.exp(NOISE_LOG * rng.standard_normal(f.shape)) \
        + NOISE_FLOOR * peak * rng.standard_normal(f.shape)
    return replace(geometry, values=x[:, None], channels=["synthetic"], uncertainty=None)


def num(v: float, digits: int = 3) -> str:
    """``digits`` significant digits; a dash for NaN."""
    return "–" if not math.isfinite(v) else f"{v:.{digits}g}"


def synthetic(grid: tuple[float, ...], starts: int, log: Any, seeds: int = 1) -> list[str]:
    """Part (a): one table row per (alpha, true aperture, seed); seed ``s`` of the ``k``-th
    true aperture draws noise (and searches) with ``k + 10 s``."""
    geometry = rb.read(DATA / "minidiff" / "C2_Black.astm").select_channel(0)
    head = ["true alpha", "true aperture (deg)", "seed", "chosen (deg)", "1σ width (deg)",
            "cost at 0 / min", "alpha at 0", "alpha at truth", "alpha at chosen",
            "corr(aperture, alpha)", "d alpha / d aperture (per deg)"]
    rows = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for alpha in ALPHAS:
        for a_true, seed in ((a, k + 10 * s) for k, a in enumerate(TRUE_DEG)
                             for s in range(seeds)):
            log(f"synthetic alpha {alpha} aperture {a_true} deg seed {seed}")
            meas = synthetic_set(geometry, alpha, a_true, seed=seed)
            prof = profile("coated", meas, grid, log, starts=starts, seed=seed)
            al = np.array([float(r[0].params["alpha"]) for r in prof.fits])
            corr = float(np.corrcoef(prof.grid, al)[0, 1]) if np.ptp(al) > 0 else math.nan
            slope = float(np.polyfit(prof.grid, al, 1)[0])
            chosen = num(prof.chosen, 3) + (" (edge)" if prof.edge else "")
            rows.append("| " + " | ".join([
                f"{alpha:g}", f"{a_true:g}", str(seed), chosen, num(prof.width, 2),
                num(prof.cost[0] / prof.cost.min(), 4), num(al[0], 3),
                num(along(prof, "alpha", a_true), 3), num(along(prof, "alpha", prof.chosen), 3),
                num(corr, 3), num(slope, 2)]) + " |")
            print(rows[-1], file=sys.stderr, flush=True)
    return rows


def roughness(r: Any, j: int) -> float:
    """Channel ``j``'s fitted roughness: the first of ``alpha``, ``alpha_m`` the model has."""
    params = r[j].params
    name = next((k for k in ("alpha", "alpha_m") if k in params), None)
    return math.nan if name is None else float(params[name])


def paints(names: tuple[str, ...], grid: tuple[float, ...], starts: int | None, log: Any,
           model: str = "coated") -> list[str]:
    """Part (b): one row per paint and channel."""
    kw: dict[str, Any] = {} if starts is None else {"starts": starts}
    head = ["paint", "channel", "chosen aperture (deg)", "1σ width (deg)", "cost at 0 / min",
            "alpha at 0", "alpha at chosen", "60° rms-log without", "60° rms-log with",
            "change", "60° peak ratio without", "60° peak ratio with"]
    rows = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for paint in names:
        meas = rb.read(DATA / "minidiff" / f"{paint}.astm")
        deg = incidence_deg(meas)
        fit_set = np.isin(deg, FIT_INCIDENCES_DEG)
        held = measured(meas) & (deg == HELD_OUT_DEG)
        log(f"paint {paint}")
        prof = profile(model, meas.subset(fit_set), grid, log, **kw)
        without = prof.fits[0]
        i = int(np.argmin(prof.cost))
        with_ = prof.fits[i] if abs(prof.chosen - prof.grid[i]) < 1e-9 else \
            fit(model, meas.subset(fit_set), prof.chosen, **kw)
        for j, ch in enumerate(meas.channels):
            ref = meas.values[held, j]
            out = []
            for r in (without, with_):
                pred = np.asarray(r.predict(meas.theta_i[held], meas.theta_r[held],
                                            meas.phi[held], channel=j), float)
                out.append((rms_log(pred, ref), float(pred.max()) / float(ref.max())))
            chosen = num(prof.chosen, 3) + (" (edge)" if prof.edge else "")
            rows.append("| " + " | ".join([
                paint, str(ch), chosen, num(prof.width, 2),
                num(prof.cost[0] / prof.cost.min(), 4),
                num(roughness(without, j), 3), num(roughness(with_, j), 3),
                num(out[0][0]), num(out[1][0]), f"{100 * (out[1][0] / out[0][0] - 1):+.1f} %",
                num(out[0][1]), num(out[1][1])]) + " |")
            print(rows[-1], file=sys.stderr, flush=True)
        rows_cost = ", ".join(f"{a:g}: {c / prof.cost.min():.4f}"
                              for a, c in zip(prof.grid, prof.cost, strict=True))
        print(f"  {paint} profile cost / min: {rows_cost}", file=sys.stderr, flush=True)
        rows.append(f"<!-- {paint} profile cost / min: {rows_cost} -->")
    return rows


def main(argv: list[str] | None = None) -> int:
    """Run the measurement; print the Markdown."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--part", choices=("both", "synthetic", "paints"), default="both")
    ap.add_argument("--quick", action="store_true",
                    help="grid 0/1.5/3 deg, one paint, starts = 2")
    ap.add_argument("--seeds", type=int, default=1,
                    help="noise seeds per synthetic set (default 1)")
    ap.add_argument("--model", default="coated", help="the paints' model (default coated)")
    ap.add_argument("--paint", action="append", choices=PAINTS, default=None,
                    help="a paint (repeatable; default all three)")
    ap.add_argument("--out", type=Path, default=None, help="also write the Markdown here")
    args = ap.parse_args(argv)
    grid = (0.0, 1.5, 3.0) if args.quick else GRID_DEG
    t0 = time.perf_counter()

    def log(msg: str) -> None:
        print(f"[{time.perf_counter() - t0:6.1f} s] {msg}", file=sys.stderr, flush=True)

    text = [f"Aperture grid (deg): {', '.join(f'{a:g}' for a in grid)}; roughbrdf "
            f"{rb.__version__}.", ""]
    if args.part in ("both", "paints"):
        names = tuple(args.paint) if args.paint else (PAINTS[:1] if args.quick else PAINTS)
        text += [f"**(b) Shared paints**, `{args.model}`, profile on 0/20/40°, 60° "
                 "predicted.", "",
                 *paints(names, grid, 2 if args.quick else None, log, args.model), ""]
    if args.part in ("both", "synthetic"):
        text += ["**(a) Synthetic**, `coated` n = 1.5, rho = 0.05, C2_Black geometry, noise "
                 f"×exp({NOISE_LOG:g} N) + {NOISE_FLOOR:g}·peak·N, all incidences.", "",
                 *synthetic(grid, 2 if args.quick else 4, log, args.seeds), ""]
    text.append(f"Run time {time.perf_counter() - t0:.0f} s.")
    out = "\n".join(text)
    print(out)
    if args.out is not None:
        args.out.write_text(out + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
