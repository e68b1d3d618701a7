"""Fit speed and global optimum of ``rb.fit`` on real Mini-Diff files (``make bench``).

Needs ``../shared/data`` (or ``ROUGHBRDF_SHARED_DATA``); prints a note and returns without it.

1. **Speed.** TR75 (with its Lambertian part rho_L, Eq. 33) fitted to one Mini-Diff file (12,964
   geometries x 3 channels, relative loss) with ``rb.fit`` at its defaults, against the same job
   written by hand with SciPy + NumPy: the TR75 BRDF in vectorized NumPy (:func:`tr75_numpy`),
   ``scipy.optimize.least_squares`` with its own finite-difference Jacobian (``jac="2-point"``),
   from the same starting points (the model's values, then the same number of Sobol points), on
   every sample. A plain single-start ``least_squares`` is timed too, with NumPy's default
   OpenBLAS threads and with one (as ``rb.fit`` runs it). The compiled kernel is
   warmed up first (Numba compilation is not counted); each time is the best of ``REPEAT`` runs.
2. **Global optimum.** On each of the three paint files, TR75 via ``rb.fit`` against a careful
   hand-written multistart: ``least_squares`` (2-point Jacobian, tight tolerances) from
   ``CAREFUL_STARTS`` uniform random points in the bounds plus the model's defaults, on every
   sample, keeping the lowest cost. The model there is evaluated through the public
   ``Model.brdf`` (compiled), so that the comparison is about the search, not the kernel.
3. **Table.** sigma and rms-log per channel for the three paints x three models (TR75; TS67
   absolute form with F = 1 and g up to 2000; microfacet Trowbridge-Reitz + Smith + Fresnel +
   Lambertian). Printed as Markdown for ``docs/fitting.md``.
4. **RB08** on the CEA retro-reflector files (log loss, samples within 2 deg of the retro
   direction weighted x20), without and with the instrument aperture (``rb.fit(...,
   aperture=...)``, ``APERTURE_DEG`` half-angle; the aperture fit starts from the plain fit):
   retro peak heights, measured vs the model as the instrument would read it (averaged over the
   aperture), per incidence. With ``--scan`` the fit cost is also tabulated against the aperture
   (on the test subset of ``tests/fitting/test_fitting_real.py``), which is how ``APERTURE_DEG`` was
   chosen. With ``--docs`` the fit plots are saved as ``docs/img/rb08_<file>.png``: the
   panels of ``FitResult.plot`` (drawn through the fit's aperture) and a zoom on the retro peak
   with the model at each direction and through the aperture.
5. **RB08 on one Mini-Diff channel** (part of the default run; ``--rb08-paints`` runs only
   this): the 14-parameter fit of channel 465 nm of each paint (relative loss, ``rb.fit``
   defaults) with the literal and the numeric normalization: time, cost (chi-square) and
   model evaluations, against the fit with the bulk and retro terms switched off (``bulk =
   retro = 0`` fixed, and ``rho_r, w_r, n_r``, which then do nothing); and where one
   evaluation's time goes (the tabulated kernel that runs real ``n``, the general kernel it
   replaced, the numeric N of one lobe at the channel's four incidences). Until 2026-12 the
   numeric-N fit of C2_Black took ~40-77 s (the 2-D lobe quadrature, ~3 ms per incidence and
   parameter change) and the literal fit of C8_Silver ~40-60 s (the general kernel, 1.6 ms per
   evaluation), then 11.8 s (the polish creeping towards a bound; docs/fitting.md, "Polish").
"""

from __future__ import annotations

import math
import os
import time
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import qmc

import roughbrdf as rb
from roughbrdf import geometry
from roughbrdf.fitting.solvers.threads import single_thread_blas

HERE = Path(__file__).resolve().parent
DATA = Path(os.environ.get("ROUGHBRDF_SHARED_DATA", HERE.parent.parent / "shared" / "data"))
PAINTS = ("C2_Black", "C8_Silver", "C12_OliveDrab")
SPEED_FILE = "C2_Black"
REPEAT = 3
CAREFUL_STARTS = 24

# TR75 parameters e, n, k, rho_L: the model's defaults and bounds (read from the model itself)
_TR75 = rb.model("trowbridge-reitz-1975")
NAMES = _TR75.param_names
X0 = np.array([_TR75.params[n] for n in NAMES])
LO = np.array([p.bounds[0] for p in _TR75.parameters])
HI = np.array([p.bounds[1] for p in _TR75.parameters])


# ---------------------------------------------------------------------------------------------
# the hand-written baseline: TR75 BRDF in NumPy, residuals, least_squares with 2-point Jacobian
# ---------------------------------------------------------------------------------------------
def tr75_numpy(p: np.ndarray, ti: np.ndarray, tr: np.ndarray, ph: np.ndarray) -> np.ndarray:
    """TR75 BRDF (unpolarized), Eqs. 30, 32, 33 divided by cos(theta_r), in plain NumPy.

    ``R(theta_d) D(theta_h)/(4 cos theta_i cos theta_r) + rho_L/pi`` with ``D`` the normalized
    Trowbridge-Reitz distribution (GGX alpha = e) and ``R`` the unpolarized Fresnel reflectance of
    ``n + ik`` (complex arithmetic).
    """
    e, n, k, rho = p
    si, ci = np.sin(ti), np.cos(ti)
    sr, cr = np.sin(tr), np.cos(tr)
    sx = sr * np.cos(ph) - si
    sy = sr * np.sin(ph)
    sz = ci + cr
    length = np.sqrt(sx * sx + sy * sy + sz * sz)
    hz = sz / length
    cd = 0.5 * length
    eps = complex(n, k) ** 2
    q = np.sqrt(eps - (1.0 - cd * cd) + 0j)
    rs = np.abs((cd - q) / (cd + q)) ** 2
    rp = np.abs((eps * cd - q) / (eps * cd + q)) ** 2
    e2 = e * e
    d = e2 / (np.pi * (hz * hz * (e2 - 1.0) + 1.0) ** 2)
    with np.errstate(divide="ignore"):
        return 0.5 * (rs + rp) * d / (4.0 * ci * cr) + rho / np.pi


def numpy_channel_fit(x: np.ndarray, geo: tuple, starts: np.ndarray) -> tuple[float, np.ndarray]:
    """Hand-written multistart: least_squares (2-point Jacobian) from each start; best cost."""

    def residual(p: np.ndarray) -> np.ndarray:
        return x / tr75_numpy(p, *geo) - 1.0  # (x - f)/f

    best = (math.inf, starts[0])
    for p0 in starts:
        r = least_squares(residual, p0, bounds=(LO, HI), method="trf", jac="2-point",
                          x_scale="jac")
        if r.cost < best[0]:
            best = (float(r.cost), r.x)
    return best


def sigma_of(x: np.ndarray, f: np.ndarray) -> float:
    return float(np.sqrt(np.mean((x / f - 1.0) ** 2)))


def usable(meas: rb.measurement.Measurement) -> tuple[np.ndarray, tuple]:
    """Samples where the unshadowed TR75 BRDF is finite (theta_r < 90 deg), as rb.fit uses."""
    keep = meas.theta_r < 0.5 * math.pi - 1e-12
    return keep, (meas.theta_i[keep], meas.theta_r[keep], meas.phi[keep])


def best_time(fn, repeat: int = REPEAT):
    out, best = None, math.inf
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def speed() -> None:
    meas = rb.read(DATA / "minidiff" / f"{SPEED_FILE}.astm")
    starts = 8
    rb.fit(rb.model("trowbridge-reitz-1975"), meas, channel=0, starts=2)  # compile (not timed)
    # every sample, as the hand-written search fits them (extrapolated="keep": the Mini-Diff's
    # theta_r > 75 deg, which rb.fit leaves out by default, docs/fitting.md)
    t_rb, res = best_time(lambda: rb.fit(rb.model("trowbridge-reitz-1975"), meas, starts=starts,
                                         progress=False, extrapolated="keep"))
    t_rb1, res1 = best_time(lambda: rb.fit(rb.model("trowbridge-reitz-1975"), meas, starts=1,
                                           progress=False, extrapolated="keep"))
    keep, geo = usable(meas)
    sob = qmc.Sobol(len(NAMES), scramble=True, seed=0).random_base2(3)[:starts - 1]
    pts = np.vstack([X0, LO + sob * (HI - LO)])

    def by_hand(points):
        return [numpy_channel_fit(meas.values[keep, j], geo, points)
                for j in range(len(meas.channels))]

    t_np, fits = best_time(lambda: by_hand(pts), repeat=1)
    t_np1, fits1 = best_time(lambda: by_hand(X0[None, :]), repeat=1)
    with single_thread_blas():  # the same, with one BLAS thread (as rb.fit runs)
        t_np1b, _ = best_time(lambda: by_hand(X0[None, :]), repeat=1)
    print(f"### Speed: TR75 fit of {SPEED_FILE}.astm ({meas.n_samples} geometries x "
          f"{len(meas.channels)} channels, relative loss)\n")
    print("| fit | time (s) | sigma per channel |")
    print("|---|---|---|")
    sig_rb = [c.sigma for c in res]
    sig_np = [sigma_of(meas.values[keep, j], tr75_numpy(f[1], *geo)) for j, f in enumerate(fits)]
    sig_1 = [sigma_of(meas.values[keep, j], tr75_numpy(f[1], *geo)) for j, f in enumerate(fits1)]
    fmt = ", ".join
    print(f"| rb.fit, {starts} starts (default) | {t_rb:.3f} | "
          f"{fmt(f'{s:.4f}' for s in sig_rb)} |")
    print(f"| rb.fit, 1 start | {t_rb1:.3f} | {fmt(f'{c.sigma:.4f}' for c in res1)} |")
    print(f"| SciPy + NumPy by hand, same {starts} starts | {t_np:.2f} | "
          f"{fmt(f'{s:.4f}' for s in sig_np)} |")
    print(f"| SciPy + NumPy by hand, 1 start | {t_np1:.2f} | "
          f"{fmt(f'{s:.4f}' for s in sig_1)} |")
    print(f"| SciPy + NumPy by hand, 1 start, one BLAS thread | {t_np1b:.2f} | (same) |")
    worse = max(a - b for a, b in zip(sig_rb, sig_np, strict=True))
    print(f"\nrb.fit: {t_rb:.3f} s (target <= 1 s); speed-up {t_np / t_rb:.1f}x over the same "
          f"search by hand (target >= 10x), {t_np1 / t_rb:.1f}x over a single hand-written "
          f"start ({t_np1b / t_rb:.1f}x with one BLAS thread); sigma rb.fit - by hand <= "
          f"{worse:+.1e}")
    print(f"one local fit each (1 start): rb.fit {t_rb1:.3f} s, {t_np1 / t_rb1:.1f}x faster than "
          f"by hand ({t_np1b / t_rb1:.1f}x with one BLAS thread)\n")


def careful_multistart(meas, j: int, rng: np.random.Generator) -> float:
    """Careful hand-written global search for TR75 on channel j; returns the best sigma."""
    keep, geo = usable(meas)
    x = meas.values[keep, j]

    def residual(p: np.ndarray) -> np.ndarray:
        m = rb.model("trowbridge-reitz-1975", **dict(zip(NAMES, p, strict=True)))
        return x / m.brdf(*geo) - 1.0

    pts = np.vstack([X0, LO + rng.random((CAREFUL_STARTS, len(NAMES))) * (HI - LO)])
    best = (math.inf, X0)
    for p0 in pts:
        r = least_squares(residual, p0, bounds=(LO, HI), method="trf", jac="2-point",
                          x_scale="jac", ftol=1e-12, xtol=1e-12, gtol=1e-12, max_nfev=2000)
        if r.cost < best[0]:
            best = (float(r.cost), r.x)
    return float(np.sqrt(2 * best[0] / x.size))


def global_optimum() -> None:
    print(f"### Global optimum: TR75, rb.fit (defaults) vs careful multistart by hand "
          f"({CAREFUL_STARTS + 1} starts, tight tolerances)\n")
    print("| file | channel | sigma rb.fit | sigma by hand | rb.fit - by hand |")
    print("|---|---|---|---|---|")
    rng = np.random.default_rng(2024)
    worst = -math.inf
    for name in PAINTS:
        meas = rb.read(DATA / "minidiff" / f"{name}.astm")
        # on the same samples as the search by hand: every sample (extrapolated="keep")
        res = rb.fit(rb.model("trowbridge-reitz-1975"), meas, progress=False,
                     extrapolated="keep")
        for j, c in enumerate(res):
            s_hand = careful_multistart(meas, j, rng)
            worst = max(worst, c.sigma - s_hand)
            print(f"| {name} | {c.channel} | {c.sigma:.5f} | {s_hand:.5f} | "
                  f"{c.sigma - s_hand:+.1e} |")
    print(f"\nlargest sigma excess of rb.fit over the careful search: {worst:+.1e} "
          f"({'none: rb.fit is never worse' if worst <= 1e-6 else 'rb.fit WORSE'})\n")


#: the models of the table: label -> (model factory, fit options)
def table_models() -> dict:
    return {
        "TR75 (+ Lambertian rho_L)": lambda: rb.model("trowbridge-reitz-1975"),
        "TS67 absolute (F = 1)": lambda: rb.model("torrance-sparrow-1967", n=None, k=None),
        "microfacet TR + Smith + Fresnel + Lambertian":
            lambda: rb.model("microfacet", distribution="trowbridge-reitz", shadowing="smith",
                             n=1.5, k=0.0) + rb.model("lambertian", rho=0.1),
    }


def table() -> None:
    print("### sigma and rms-log per fit (relative loss, rb.fit defaults)\n")
    print("| file | model | sigma (465 / 525 / 630 nm) | rms-log (465 / 525 / 630 nm) | "
          "time (s) |")
    print("|---|---|---|---|---|")
    for name in PAINTS:
        meas = rb.read(DATA / "minidiff" / f"{name}.astm")
        for label, make in table_models().items():
            t = time.perf_counter()
            bounds = {"g": (0.0, 2000.0)} if label.startswith("TS67") else None
            res = rb.fit(make(), meas, bounds=bounds, progress=False)
            dt = time.perf_counter() - t
            s = " / ".join(f"{c.sigma:.3f}" for c in res)
            lg = " / ".join(f"{c.rms_log:.3f}" for c in res)
            ok = "" if res.success else " (not converged)"
            print(f"| {name} | {label}{ok} | {s} | {lg} | {dt:.2f} |")
    print()


def retro_distance_deg(meas) -> np.ndarray:
    ti, tr, ph = meas.theta_i, meas.theta_r, meas.phi
    dot = -np.sin(ti) * np.sin(tr) * np.cos(ph) + np.cos(ti) * np.cos(tr)
    return np.degrees(np.arccos(np.clip(dot, -1.0, 1.0)))


#: instrument aperture (half-angle, deg) of the CEA gonio-reflectometer: the minimum over
#: SCAN_DEG of the gray tape's fit cost (its retro peak is the sharpest); see ``--scan``
APERTURE_DEG = 1.0
SCAN_DEG = (0.5, 0.75, 1.0, 1.25, 1.5, 2.0)
RETRO_FILES = ("retro-gray-tape.dat", "retro-3M-jaune.dat")


def retro_weights(meas) -> np.ndarray:
    """x20 within 2 deg of the retro direction: the peak is a few dozen of ~7400 samples."""
    return np.where(retro_distance_deg(meas) <= 2.0, 20.0, 1.0)


def retro_peak_text(meas, res) -> tuple[str, str]:
    """Per incidence: 'measured -> model (rel.)' with the model averaged over the fit's
    aperture (what the instrument reads), and the model's own value at the retro point."""
    d = retro_distance_deg(meas)
    peaks, raw = [], []
    for ti in meas.incidences(4):
        sel = (np.abs(meas.theta_i - ti) < 1e-3) & (d <= 0.5)
        measured = float(meas.values[sel, 0].max())
        model = float(res.predict(float(ti), float(ti), math.pi))
        peaks.append(f"{measured:.3g} -> {model:.3g} ({model / measured - 1:+.0%})")
        raw.append(f"{float(res.predict(float(ti), float(ti), math.pi, aperture=False)):.3g}")
    return " / ".join(peaks), " / ".join(raw)


def rb08_scan() -> None:
    """Fit cost vs aperture on the test subset (every 6th sample + all within 3 deg of retro),
    each aperture fit starting from the plain fit, as in tests/fitting/test_fitting_real.py."""
    print("### RB08: fit cost vs aperture (test subset; plain fit 8 starts, aperture fits 2 "
          "starts from it)\n")
    print("| file | aperture (deg) | weighted chi2 (log loss) | sigma | rms-log | "
          "retro peak, measured -> model (15 / 30 / 60 deg) | time (s) |")
    print("|---|---|---|---|---|---|---|")
    for name in RETRO_FILES:
        meas = rb.read(DATA / "cea_retro" / name, quantity="brdf_cos")
        d = retro_distance_deg(meas)
        keep = (np.arange(meas.n_samples) % 6 == 0) | (d <= 3.0)
        sub = meas.subset(keep)
        w = retro_weights(sub)
        plain = rb.fit(rb.model("renhorn-boreman-2008"), sub, loss="log", weights=w, starts=8,
                       progress=False)
        for a in (0.0, *SCAN_DEG):
            t = time.perf_counter()
            res = plain if a == 0 else rb.fit(plain.model, sub, loss="log", weights=w,
                                              starts=2, aperture=math.radians(a),
                                              progress=False)
            dt = time.perf_counter() - t
            c = res.channels[0]
            peaks, _ = retro_peak_text(sub, res)
            print(f"| {name} | {a:g} | {c.chi2:.0f} | {c.sigma:.3f} | {c.rms_log:.3f} | "
                  f"{peaks} | {dt if a else 0:.1f} |")
    print()


def rb08_cea(docs: bool = False, scan: bool = False) -> None:
    if "renhorn-boreman-2008" not in rb.available():
        print("### RB08: model not available\n")
        return
    if scan:
        rb08_scan()
    print("### RB08 on the CEA retro-reflectors (log loss, x20 weight within 2 deg of retro; "
          f"all samples; plain fit: rb.fit defaults; aperture {APERTURE_DEG:g} deg: 2 starts, "
          "the first the plain optimum)\n")
    print("| file | aperture (deg) | sigma | rms-log | time (s) | retro peak BRDF cos, measured "
          "-> model read through the aperture (15 / 30 / 60 deg) | model at the retro point |")
    print("|---|---|---|---|---|---|---|")
    for name in RETRO_FILES:
        meas = rb.read(DATA / "cea_retro" / name, quantity="brdf_cos")
        w = retro_weights(meas)
        t = time.perf_counter()
        plain = rb.fit(rb.model("renhorn-boreman-2008"), meas, loss="log", weights=w,
                       progress=False)
        t_plain = time.perf_counter() - t
        t = time.perf_counter()
        res = rb.fit(plain.model, meas, loss="log", weights=w, starts=2,
                     aperture=math.radians(APERTURE_DEG), progress=False)
        t_ap = time.perf_counter() - t
        for r, dt in ((plain, t_plain), (res, t_ap)):
            peaks, raw = retro_peak_text(meas, r)
            a = "none" if r.aperture is None else f"{math.degrees(r.aperture):g}"
            print(f"| {name} | {a} | {r.sigma:.3g} | {r.rms_log:.3f} | {dt:.1f} | {peaks} | "
                  f"{raw} |")
        if docs:
            save_rb08_plot(name, res)
    print()


def save_rb08_plot(name: str, res) -> None:
    """Left and middle: FitResult.plot's panels (in-plane slices and residual map, the model
    read through the fit's aperture, as the fit compared it with the data); right: a zoom on
    the retro peak, in-plane, with the model at each direction (thin) and read through the
    aperture (thick)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from roughbrdf import plot as rbplot

    model, meas = res.plot_data(0)
    fig = plt.figure(figsize=(18, 5.2))
    ax1 = fig.add_subplot(1, 3, 1)
    ax2 = fig.add_subplot(1, 3, 2)
    ax3 = fig.add_subplot(1, 3, 3)
    rbplot.plot_comparison(model, meas, channel=0, ax=ax1, aperture=res.instrument)
    rbplot.plot_residual_map(model, meas, channel=0, ax=ax2, aperture=res.instrument)
    inplane = meas.in_plane()
    incs = inplane.incidences(4)
    off = np.radians(np.linspace(-6.0, 6.0, 1201))  # 0.01 deg: resolves the retro cusp
    for t, col in zip(incs, rbplot.incidence_colors(len(incs)), strict=True):
        sel = inplane.at_incidence(float(t), atol=1e-4)
        x = np.degrees(geometry.signed_angle(sel.theta_r, sel.phi) + t)  # 0 at retro
        near = np.abs(x) <= 6.0
        lab = f"{math.degrees(t):.3g}°"
        ax3.plot(x[near], sel.values[near, 0], "o", ms=4, mfc="none", color=col,
                 label=rf"data $\theta_i$ = {lab}")
        tr, ph = geometry.from_signed_angle(off - t)
        ax3.plot(np.degrees(off), res.predict(float(t), tr, ph, aperture=False), color=col,
                 lw=0.8, alpha=0.7, label="model")
        if res.aperture is not None:
            ax3.plot(np.degrees(off), res.predict(float(t), tr, ph), color=col, lw=2.2,
                     label="model through the aperture")
    ax3.set_yscale("log")
    ax3.set_xlim(-6, 6)
    ax3.set_xlabel(r"in-plane angle from the retro direction [deg]")
    ax3.set_ylabel(rbplot.QUANTITY_LABELS["bridf"])
    ap = "none" if res.aperture is None else f"{math.degrees(res.aperture):g}° half-angle"
    ax3.set_title(f"retro peak, aperture {ap}", fontsize="medium")
    ax3.grid(True, alpha=0.3)
    ax3.legend(fontsize="x-small", ncol=1, loc="upper right")
    fig.tight_layout()
    out = HERE.parent / "docs" / "img" / f"rb08_{name.removesuffix('.dat')}.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=90)
    plt.close(fig)
    print(f"\nsaved {out.relative_to(HERE.parent)}\n")


#: the fit with RB08's bulk and retro terms switched off: these fixed (bulk = retro = 0)
RB08_OFF = ("bulk", "retro", "rho_r", "w_r", "n_r")
RB08_CHANNEL = 0


def rb08_paint_fit(meas, normalization: str, off: bool = False):
    """``rb.fit`` of RB08 (defaults) to channel :data:`RB08_CHANNEL`; ``off``: bulk and retro
    switched off. Returns (time in s, ChannelFit)."""
    model = rb.model("renhorn-boreman-2008", normalization=normalization,
                     **({"bulk": 0.0, "retro": 0.0} if off else {}))
    t = time.perf_counter()
    res = rb.fit(model, meas, channel=RB08_CHANNEL, fix=RB08_OFF if off else (), progress=False)
    return time.perf_counter() - t, res.channels[0]


def rb08_evaluation_split(meas) -> str:
    """Time of one model evaluation on the channel's geometry (best of 20), by part."""
    from roughbrdf.models import renhorn_boreman as rbm

    keep = meas.theta_r <= math.radians(75.0) + 1e-9  # the fitted samples (no extrapolation)
    m = rb.model("renhorn-boreman-2008", n=4.37, n_r=2.61, w_a=0.3)  # real n: not integer
    g = m.prepare(meas.theta_i[keep], meas.theta_r[keep], meas.phi[keep])
    general = m.with_general_kernel()
    ti = np.unique(meas.theta_i)
    t_tab, _ = best_time(lambda: m.evaluate_prepared(g), repeat=20)
    t_gen, _ = best_time(lambda: general.evaluate_prepared(g), repeat=20)
    t_num, _ = best_time(lambda: rbm.lobe_integral(ti, 0.31, 0.87, 4.37), repeat=20)
    return (f"one evaluation on {int(keep.sum())} geometries: tabulated kernel (real n, V once "
            f"per distinct angle) {1e3 * t_tab:.2f} ms, general kernel (V per sample, which ran "
            f"real n until 2026-12) {1e3 * t_gen:.2f} ms; numeric N of one lobe at the "
            f"{ti.size} incidences {1e3 * t_num:.3f} ms (the 2-D quadrature took ~12 ms)")


def rb08_paints() -> None:
    if "renhorn-boreman-2008" not in rb.available():
        print("### RB08 on one Mini-Diff channel: model not available\n")
        return
    print("### RB08 on one Mini-Diff channel (465 nm, relative loss, rb.fit defaults: 8 starts; "
          "bulk/retro off: bulk = retro = 0 and rho_r, w_r, n_r fixed)\n")
    print("| file | normalization | time (s) | chi2 | model evals | chi2, bulk/retro off | "
          "time, off (s) | default reaches the off fit |")
    print("|---|---|---|---|---|---|---|---|")
    split = ""
    for name in PAINTS:
        meas = rb.read(DATA / "minidiff" / f"{name}.astm")
        if not split:
            for norm in ("literal", "numeric"):  # compile / load the kernels (not timed)
                rb.fit(rb.model("renhorn-boreman-2008", normalization=norm), meas,
                       channel=RB08_CHANNEL, starts=1, max_nfev=2, progress=False)
            split = rb08_evaluation_split(meas)
        for norm in ("literal", "numeric"):
            t_full, full = rb08_paint_fit(meas, norm)
            t_off, off = rb08_paint_fit(meas, norm, off=True)
            print(f"| {name} | {norm} | {t_full:.2f} | {full.chi2:.4f} | {full.nfev} | "
                  f"{off.chi2:.4f} | {t_off:.2f} | "
                  f"{'yes' if full.chi2 <= off.chi2 else 'NO'} |", flush=True)
    print(f"\n{split}\n")


def main(argv: list[str] | None = None) -> None:
    import sys

    args = sys.argv[1:] if argv is None else argv
    if not (DATA / "minidiff").is_dir():
        print(f"skipped: real data not found at {DATA} (set ROUGHBRDF_SHARED_DATA)")
        return
    if "--rb08-paints" in args:  # only the RB08 paint section
        rb08_paints()
        return
    if "--rb08" in args:  # only the RB08 section
        rb08_cea(docs="--docs" in args, scan="--scan" in args)
        return
    speed()
    global_optimum()
    table()
    rb08_cea(docs="--docs" in args, scan="--scan" in args)
    rb08_paints()


if __name__ == "__main__":
    main()
