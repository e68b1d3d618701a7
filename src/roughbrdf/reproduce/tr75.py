"""Trowbridge & Reitz (1975): Fig. 5, Fig. 6-style polar plots and Table 1.

T. S. Trowbridge and K. P. Reitz, "Average irregularity representation of a rough surface for
ray reflection", J. Opt. Soc. Am. 65(5), 531-536 (1975); Naval Missile Center report TP-75-01.
Targets: docs/models.md §3.10-3.12.

TR75's angles: β (incidence zenith), θ (reflection **elevation**) and ψ (azimuth, 0 toward the
source), converted to the common frame with :func:`roughbrdf.geometry.from_tr75`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from matplotlib.ticker import MaxNLocator
from scipy.optimize import brentq

import roughbrdf as rb

from ..plot import plot_polar
from ._common import Reproduction, Table, new_figure

__all__ = ["STRUCTURE_FUNCTIONS", "TABLE1", "hwhm", "fig5", "fig6", "table1", "ALL"]

#: TR75 Fig. 5 (report) / Fig. 4 (JOSA): best fits to Rense's ground-glass data, as
#: ``(label, registered distribution, parameter, caption parameter)`` (docs/models.md §3.11).
#: Beckmann's ``cos^-4 exp(-A^2 tan^2)`` is our ``beckmann`` with ``m = 1/A``; Rense's
#: ``exp(-A^2 alpha^2)`` with ``A^2 = 0.0021 deg^-2`` is TS67's gaussian in the facet angle with
#: ``c = A = 0.0458 per degree``; Sirohi is read with ``p = 2`` (docs/models.md §3.11, recommended).
STRUCTURE_FUNCTIONS = (
    ("TR75 e⁴/(e²cos²α + sin²α)²", "trowbridge-reitz", 0.40, "e = 0.40"),
    ("Berry e²/(e²cos²α + sin²α)", "berry", 0.25, "e = 0.25"),
    ("Beckmann cos⁻⁴α exp(−A² tan²α)", "beckmann", 1.0 / math.sqrt(7.62), "A² = 7.62"),
    ("Sirohi cos⁻²α exp(−A² tan²α)", "sirohi", 6.93, "A² = 6.93"),
    ("Rense exp(−A² α²)", "gaussian-angle", math.sqrt(0.0021), "A² = 0.0021 deg⁻²"),
)
#: the alternative reading of the Sirohi exponent (p = 4) equals Beckmann with m = 1/sqrt(6.93)
SIROHI_P4 = ("Sirohi read with cos⁻⁴α (p = 4)", "beckmann", 1.0 / math.sqrt(6.93), "A² = 6.93")

#: Table 1 (docs/models.md §3.10 transcription): sigma_m, rho_L, e, n, k; the paper's DHR estimate
#: at normal incidence ("order of ...") and the measured DHR it quotes.
TABLE1 = (
    {"surface": "3M Black Velvet (min 1)", "key": "black_velvet_1", "sigma_m": 0.290,
     "rho_L": 0.020, "e": 0.89, "n": 1.60, "k": 0.00, "paper": 0.04, "paper_text": "~4 %",
     "measured": "2.5 %"},
    {"surface": "3M Black Velvet (min 2)", "key": "black_velvet_2", "sigma_m": 0.293,
     "rho_L": 0.022, "e": 0.88, "n": 1.62, "k": 0.3, "paper": 0.04, "paper_text": "~4 %",
     "measured": "2.5 %"},
    {"surface": "soiled olive drab", "key": "olive_drab", "sigma_m": 0.345, "rho_L": 0.06,
     "e": 0.24, "n": 1.0, "k": 0.4, "paper": 0.05, "paper_text": "~5 %", "measured": "4 %"},
    {"surface": "cement", "key": "cement", "sigma_m": 0.200, "rho_L": 0.33, "e": 0.68,
     "n": 1.00, "k": 0.9, "paper": 0.50, "paper_text": "~50 %", "measured": "30-50 %"},
    {"surface": "plywood", "key": "plywood", "sigma_m": 0.186, "rho_L": 0.40, "e": 0.51,
     "n": 0.9, "k": 1.9, "paper": 0.70, "paper_text": "~70 %", "measured": "-"},
    {"surface": "grass", "key": "grass", "sigma_m": 0.328, "rho_L": 0.5, "e": 1.6, "n": 0.7,
     "k": 1.3, "paper": 0.60, "paper_text": "~60 %", "measured": "5-20 %"},
)

#: (beta, elevation) columns of the Fig. 6-style polar plots, degrees. The report's column
#: headings are illegible in the OCR; its measurements used elevations 15-90 deg and
#: incidences 0-70 deg. The third column passes through the specular direction (psi = 180 deg).
FIG6_COLUMNS = ((0.0, 45.0), (30.0, 45.0), (60.0, 30.0))


def surface_model(row: dict, *, rho_L: float | None = None) -> rb.Model:  # noqa: N803
    """The TR75 model for one Table 1 row (``rho_L`` overrides the Lambertian part)."""
    return rb.model("trowbridge-reitz-1975", e=row["e"], n=row["n"], k=row["k"],
                    rho_L=row["rho_L"] if rho_L is None else rho_L)


def _peak_shape(name: str, param: float, alpha: np.ndarray) -> np.ndarray:
    return np.asarray(rb.distributions.evaluate(name, np.cos(alpha), param,
                                                peak_normalized=True), dtype=float)


def hwhm(name: str, param: float) -> float:
    """Half width at half maximum (degrees) of a peak-normalized structure function."""
    def f(a: float) -> float:
        return float(_peak_shape(name, param, np.array([a]))[0]) - 0.5

    return math.degrees(brentq(f, 1e-9, 0.5 * math.pi - 1e-9, xtol=1e-12))


# --------------------------------------------------------------------------------------------
# Fig. 5
# --------------------------------------------------------------------------------------------
def fig5() -> Reproduction:
    """Fig. 5: the five structure functions, normalized to 1 at α = 0, with their HWHMs."""
    alpha_deg = np.round(np.arange(0.0, 89.95, 0.1), 1)
    alpha = np.radians(alpha_deg)
    fig, axes = new_figure(1, 2, figsize=(13.0, 4.8))
    styles = ["-", ":", "-.", "--", (0, (5, 2, 1, 2, 1, 2))]
    cols = ["k", "C0", "C2", "C3", "C1"]
    curves, rows = {}, []
    for (label, name, param, cap), ls, col in zip(STRUCTURE_FUNCTIONS, styles, cols,
                                                  strict=True):
        y = _peak_shape(name, param, alpha)
        curves[name] = y
        h = hwhm(name, param)
        rows.append([label, name, param, cap, h])
        for ax in axes[0]:
            ax.plot(alpha_deg, y, ls=ls, color=col, lw=1.6 if name == "trowbridge-reitz" else 1.2,
                    label=f"{label}, {cap} (HWHM {h:.1f}°)")
    label, name, param, cap = SIROHI_P4
    y4 = _peak_shape(name, param, alpha)
    h4 = hwhm(name, param)
    rows.append([label, name, param, cap, h4])
    for ax in axes[0]:
        ax.plot(alpha_deg, y4, color="0.6", lw=0.8, label=f"{label}, {cap} (HWHM {h4:.1f}°)")
    axes[0, 0].set_xlim(0, 60)
    axes[0, 0].set_ylim(0, 1.05)
    axes[0, 1].set_xlim(0, 90)
    axes[0, 1].set_yscale("log")
    axes[0, 1].set_ylim(1e-4, 1.5)
    for ax in axes[0]:
        ax.set_xlabel(r"$\alpha$, zenith of microarea normal [deg]")
        ax.set_ylabel("relative microarea distribution function")
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend(fontsize="x-small", loc="upper right")
    axes[0, 0].set_title("TR75 Fig. 5: best fits to Rense's ground-glass data (linear)",
                         fontsize="medium")
    axes[0, 1].set_title("same, logarithmic (tails)", fontsize="medium")
    axes[0, 1].legend(fontsize="x-small", loc="lower left")
    curve_rows = [[a, *(curves[nm][i] for _, nm, _, _ in STRUCTURE_FUNCTIONS), y4[i]]
                  for i, a in enumerate(alpha_deg)]
    return Reproduction(
        "tr75_fig05", "TR75 Fig. 5: comparison of structure functions", fig,
        {"curves": Table(["alpha_deg", *(nm for _, nm, _, _ in STRUCTURE_FUNCTIONS),
                          "sirohi_p4"], curve_rows),
         "hwhm": Table(["function", "distribution", "parameter", "caption", "hwhm_deg"], rows)},
        notes=["Rense's measured points are not available as numbers, so only the fitted "
               "curves are drawn."])


# --------------------------------------------------------------------------------------------
# Fig. 6
# --------------------------------------------------------------------------------------------
def fig6(columns: tuple[tuple[float, float], ...] = FIG6_COLUMNS) -> Reproduction:
    """Fig. 6-style polar plots: BRIDF against ψ for the Table 1 surfaces, ⊥ and ∥ incidence.

    Black Velvet uses its first parameter set, as the paper's Fig. 6 does.
    """
    surfaces = [r for r in TABLE1 if r["key"] != "black_velvet_2"]
    fig, axes = new_figure(len(surfaces), len(columns), polar=True,
                           figsize=(3.0 * len(columns), 2.9 * len(surfaces) + 0.4))
    psi_deg = np.arange(0.0, 360.0 + 1e-9, 2.0)
    psi = np.radians(psi_deg)
    rows: list[list[Any]] = []
    for i, row in enumerate(surfaces):
        model = surface_model(row)
        for j, (beta, elev) in enumerate(columns):
            ax = axes[i, j]
            plot_polar(model, math.radians(beta), math.radians(elev), n=psi.size,
                       label=str(row["surface"]), ax=ax)
            ax.set_title(f"{row['surface']}\nβ = {beta:g}°, θ = {elev:g}° elev.",
                         fontsize="small")
            ax.tick_params(labelsize="x-small", pad=1)
            ax.yaxis.set_major_locator(MaxNLocator(3))
            ax.set_thetagrids(range(0, 360, 45))
            handles, labels = ax.get_legend_handles_labels()
            ax.get_legend().remove()
            ax.set_xlabel("")
            ax.set_ylabel("")
            ti, tr, ph = rb.geometry.from_tr75(math.radians(beta), math.radians(elev), psi)
            s = np.asarray(model.bridf(ti, tr, ph, "s"), dtype=float)
            p = np.asarray(model.bridf(ti, tr, ph, "p"), dtype=float)
            u = np.asarray(model.bridf(ti, tr, ph), dtype=float)
            rows.extend([row["key"], beta, elev, a, vs, vp, vu]
                        for a, vs, vp, vu in zip(psi_deg, s, p, u, strict=True))
    fig.suptitle("TR75 Fig. 6 style: BRIDF (radius, sr⁻¹) against azimuth ψ\n"
                 "(ψ = 0° toward the source, 180° forward)", fontsize="medium")
    fig.legend(handles, ["⊥ incident polarization (s)", "∥ incident polarization (p)"],
               loc="outside lower center", ncols=2, fontsize="small")
    # docs/models.md §3.12 check values: cement, unpolarized, beta = 45 deg
    cement = surface_model(next(r for r in TABLE1 if r["key"] == "cement"))
    checks = []
    for elev in (15.0, 45.0, 75.0, 90.0):
        for a in (0.0, 90.0, 180.0):
            ti, tr, ph = rb.geometry.from_tr75(math.radians(45.0), math.radians(elev),
                                               math.radians(a))
            checks.append(["cement", 45.0, elev, a, float(cement.bridf(ti, tr, ph))])
    return Reproduction(
        "tr75_fig06", "TR75 Fig. 6: polar plots of BRIDF for the Table 1 surfaces", fig,
        {"curves": Table(["surface", "beta_deg", "elevation_deg", "psi_deg", "bridf_perp",
                          "bridf_par", "bridf_unpolarized"], rows),
         "checks": Table(["surface", "beta_deg", "elevation_deg", "psi_deg",
                          "bridf_unpolarized"], checks)},
        notes=["The measured points of the paper's Fig. 6 are not available as numbers and "
               "its column headings are illegible; we draw the model for three (β, θ) pairs "
               "from the paper's measurement grid."])


# --------------------------------------------------------------------------------------------
# Table 1
# --------------------------------------------------------------------------------------------
def table1() -> Reproduction:
    """Table 1 with our directional-hemispherical reflectances next to the paper's estimates."""
    rows = []
    for r in TABLE1:
        interface = float(rb.albedo(surface_model(r, rho_L=0.0), 0.0))
        total = float(rb.albedo(surface_model(r), 0.0))
        rows.append([r["surface"], r["sigma_m"], r["rho_L"], r["e"], r["n"], r["k"],
                     interface, total, r["paper"], r["paper_text"], r["measured"]])
    cols = ["surface", "sigma_m", "rho_L", "e", "n", "k", "dhr_interface", "dhr_total",
            "paper_estimate", "paper_estimate_text", "measured_in_paper"]
    main = Table(cols, rows)
    betas = (0.0, 30.0, 60.0, 80.0)
    vs_beta = []
    for key in ("black_velvet_1", "cement"):
        r = next(x for x in TABLE1 if x["key"] == key)
        vals = np.atleast_1d(rb.albedo(surface_model(r), np.radians(betas)))
        vs_beta.append([r["surface"], *vals])
    beta_table = Table(["surface", *(f"dhr_beta_{b:g}" for b in betas)], vs_beta)
    od = next(x for x in TABLE1 if x["key"] == "olive_drab")
    od_alt = float(rb.albedo(surface_model(od, rho_L=0.006), 0.0))
    md = ["# TR75 Table 1: optimum parameters and directional-hemispherical reflectance",
          "",
          "Parameters as transcribed in docs/models.md §3.10 (Black Velvet has two nearly equal "
          "minima). DHR at normal incidence, unpolarized, computed with `rb.albedo` from the "
          "TR75 model (Eqs. 30 + 32): *interface* is the ellipsoid term alone, *total* adds "
          "ρ_L. The paper's estimate is its \"order of\" value from the absolute BRIDF.",
          "",
          "| surface | σ_m | ρ_L | e | n | k | DHR interface | DHR total (ours) "
          "| paper's estimate | measured (paper) |",
          "|---|---|---|---|---|---|---|---|---|---|"]
    for r, row in zip(TABLE1, rows, strict=True):
        md.append(f"| {r['surface']} | {r['sigma_m']:.3f} | {r['rho_L']:g} | {r['e']:g} | "
                  f"{r['n']:g} | {r['k']:g} | {row[6]:.3f} | **{row[7]:.3f}** | "
                  f"{r['paper_text']} | {r['measured']} |")
    md += ["",
           "DHR against incidence β (no shadowing in TR75, so it rises toward grazing):",
           "",
           "| surface | " + " | ".join(f"β = {b:g}°" for b in betas) + " |",
           "|---|" + "---|" * len(betas)]
    for row in vs_beta:
        md.append(f"| {row[0]} | " + " | ".join(f"{v:.3f}" for v in row[1:]) + " |")
    md += ["",
           f"Olive drab: ρ_L = 0.06 alone exceeds the paper's \"order of 5 %\"; our total is "
           f"{rows[2][7]:.3f}, about twice the estimate. With ρ_L = 0.006 (a dropped zero in "
           f"the OCR'd table, docs/models.md §3.10) the total would be {od_alt:.3f}. Grass: ours "
           f"and the paper's estimate agree (~60 %), and both disagree with the 5-20 % "
           f"measured for meadows, as the paper itself says.", ""]
    return Reproduction(
        "tr75_table1", "TR75 Table 1 and directional-hemispherical reflectances", None,
        {"dhr": main, "dhr_vs_beta": beta_table}, markdown="\n".join(md),
        notes=[f"Olive drab: total DHR {rows[2][7]:.3f} vs the paper's ~5 %; "
               f"{od_alt:.3f} if rho_L were 0.006."])


ALL = (fig5, fig6, table1)
