"""The figures and the table of ``docs/straylight.md``: the stray-light models fitted to the
committed Zemax examples and to a shared Mini-Diff paint.

``.venv/bin/python scripts/straylight_figures.py [--out docs/img]`` (about a minute). For each
file: ABg and Harvey-Shack fitted with ``rb.fit`` defaults (one parameter set for all
incidences; the energy constraint keeps TIS <= 1), and ABg per incidence
(:func:`roughbrdf.fitting.kinds.per_incidence.fit_per_incidence`); prints a Markdown table (the
parameters, rms-log, the largest TIS over 0-89 deg) and draws the in-plane cuts (data points and
model lines per measured incidence, log scale) into ``straylight_<file>.png``. The Mini-Diff
paints need ``../shared/data`` (or ``ROUGHBRDF_SHARED_DATA``); without it that file is skipped
with a note.
"""

from __future__ import annotations

import argparse
import math
import os
import warnings
from pathlib import Path

import numpy as np

import roughbrdf as rb
from roughbrdf.fitting.kinds.per_incidence import fit_per_incidence
from roughbrdf.fitting.results.plausibility import EXPORT_INCIDENCES_DEG

HERE = Path(__file__).resolve().parent
SHARED = Path(os.environ.get("ROUGHBRDF_SHARED_DATA", HERE.parent.parent / "shared" / "data"))
ZEMAX = HERE.parent / "tests" / "data" / "zemax"
FILES = {"AnoBlack": (ZEMAX / "AnoBlackNiTEonINVAR.bsdf", None),
         "Aeroglaze": (ZEMAX / "aeroglaze.bsdf", None),
         "C2_Black": (SHARED / "minidiff" / "C2_Black.astm", "630nm"),
         "C8_Silver": (SHARED / "minidiff" / "C8_Silver.astm", "630nm"),
         "C12_OliveDrab": (SHARED / "minidiff" / "C12_OliveDrab.astm", "630nm")}
MODELS = ("abg", "harvey-shack")


def _in_plane(meas: rb.Measurement, theta_i: float) -> np.ndarray:
    """The samples of one incidence in the plane of incidence (phi near 0 or pi)."""
    at = np.abs(meas.theta_i - theta_i) < 1e-6
    c = np.cos(meas.phi)
    return at & ((np.abs(np.abs(c) - 1.0) < 1e-6) | (meas.theta_r < 1e-9))


def _row(name: str, label: str, res) -> str:
    c = res[0]
    tis = rb.albedo(c.model, np.radians(EXPORT_INCIDENCES_DEG))
    params = ", ".join(f"{k} = {v:.4g}" for k, v in c.params.items())
    return (f"| {name} | {label} | {params} | {c.rms_log:.3f} | {float(np.max(tis)):.4f} | "
            f"{'yes' if c.success else 'no'} |")


def figure(name: str, meas: rb.Measurement, fits: dict, per_inc, out: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    angles = np.sort(meas.incidences())
    fig, axes = plt.subplots(1, len(angles), figsize=(3.2 * len(angles), 3.2), sharey=True)
    for ax, t in zip(np.atleast_1d(axes), angles, strict=True):
        sel = _in_plane(meas, t)
        signed = np.where(np.cos(meas.phi[sel]) > 0, 1.0, -1.0) * np.degrees(meas.theta_r[sel])
        order = np.argsort(signed)
        x = signed[order]
        v = meas.values[sel, 0][order]
        ax.semilogy(x[v > 0], v[v > 0], ".", ms=3, color="k", label="data")
        tr = np.radians(np.abs(x))
        ph = np.where(x >= 0, 0.0, math.pi)
        for label, res in fits.items():
            ax.semilogy(x, res[0].model.brdf(t, tr, ph), lw=1.2, label=label)
        ax.semilogy(x, per_inc.model_at(float(t)).brdf(t, tr, ph), "--", lw=1.0,
                    label="abg per incidence")
        ax.set_title(f"{name}, θi = {math.degrees(t):.0f}°", fontsize=9)
        ax.set_xlabel("θr in the plane of incidence (°; + specular side)", fontsize=8)
    np.atleast_1d(axes)[0].set_ylabel("BSDF (sr⁻¹)", fontsize=8)
    np.atleast_1d(axes)[0].legend(fontsize=7)
    fig.tight_layout()
    path = out / f"straylight_{name}.png"
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(HERE.parent / "docs" / "img"))
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print("| file | model | parameters | rms-log | max TIS (0-89°) | converged |")
    print("|---|---|---|---|---|---|")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, (path, channel) in FILES.items():
            if not path.exists():
                print(f"| {name} | (skipped: {path} not found) | | | | |")
                continue
            meas = rb.read(path)
            if channel is not None:
                meas = meas.subset(np.ones(meas.n_samples, bool))
                meas = rb.Measurement(meas.theta_i, meas.theta_r, meas.phi,
                                      meas.values[:, meas.channel_index(channel)],
                                      channels=[channel], meta=dict(meas.meta))
            fits = {m: rb.fit(m, meas, progress=False) for m in MODELS}
            per_inc = fit_per_incidence("abg", meas, progress=False)
            for m, res in fits.items():
                print(_row(name, m, res))
            worst = max(per_inc.rows[k].tis[per_inc.channels[0]] for k in per_inc.chosen)
            print(f"| {name} | abg per incidence ({len(per_inc.chosen)} rows) | see the "
                  f"report | {per_inc.rms_log[per_inc.channels[0]]:.3f} | {worst:.4f} "
                  f"(at the rows) | {'yes' if per_inc.success else 'no'} |")
            figure(name, meas, fits, per_inc, out)


if __name__ == "__main__":
    main()
