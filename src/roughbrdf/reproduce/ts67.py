"""Torrance & Sparrow (1967): Figs. 7, 8, 9, 10 and 11 from the library's public API.

K. E. Torrance and E. M. Sparrow, "Theory for off-specular reflection from roughened surfaces",
J. Opt. Soc. Am. 57(9), 1105-1114 (1967). Targets: docs/models.md §2.7.

All curves are in TS67's own angles, which are the library's common frame: ψ (incidence zenith)
= ``theta_i``, θ = ``theta_r`` and φ = ``phi`` (0 forward). In-plane plots use the paper's
signed θ: positive for φ = 0, negative for φ = 180° (TS67 text under Fig. 2).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

import roughbrdf as rb

from ..geometry import from_signed_angle
from ..plot import SIGNED_LABEL, incidence_colors
from ._common import Reproduction, Table, new_figure

__all__ = [
    "OPTICAL_CONSTANTS",
    "fig7",
    "fig8",
    "fig9",
    "fig10",
    "fig11",
    "peak_table",
    "relative_model",
    "ALL",
]

#: Incidence angles ψ (degrees) of each figure (TS67 Figs. 7 and 8 captions and text).
PSI_FIG7 = (0.0, 30.0, 45.0, 60.0, 75.0)
PSI_FIG8 = (10.0, 30.0, 45.0, 60.0, 75.0)
PSI_OUT_OF_PLANE = (30.0, 60.0, 75.0)
PHI_FAMILY = (0.0, 30.0, 60.0, 90.0, 120.0, 150.0, 180.0)

#: Fig. 7 target columns (docs/models.md §2.7), signed θ in degrees.
FIG7_THETAS = (-89.9, -80.0, -60.0, -45.0, -30.0, 0.0, 30.0, 45.0, 60.0, 75.0, 80.0, 85.0, 89.9)

#: Optical constants at λ = 0.5 µm for Fig. 9 (complex index n + ik).
#:
#: The paper took its indices from the AIP Handbook (1963) without printing them
#: (docs/models.md §7).
#: We use published modern values near 500 nm:
#:
#: * aluminium: n = 0.77, k = 6.08 -- A. D. Rakić, "Algorithm for the determination of
#:   intrinsic optical constants of metal films: application to aluminum", Appl. Opt. 34,
#:   4755-4767 (1995) (values at 0.50 µm as tabulated from that paper, e.g. on
#:   refractiveindex.info);
#:   the Palik *Handbook of Optical Constants of Solids* (1985, Al by Shiles et al.) gives values
#:   within a few per cent at the same wavelength. These are also docs/models.md §2.7's values.
#: * magnesium oxide (MgO): n = 1.746, k = 0 -- R. E. Stephens and I. H. Malitson, "Index of
#:   refraction of magnesium oxide", J. Res. Natl. Bur. Stand. 49, 249-252 (1952): n falls from
#:   1.845 at 0.2537 µm through n_D = 1.7375 (0.5893 µm) to 1.731 at 0.7065 µm; at 0.5 µm it is
#:   1.746 to three decimals. docs/models.md §2.7 rounds it to 1.74.
#:
#: g follows docs/models.md §2.7: 2/3 for aluminium, 2 for MgO (the paper chose g so that
#: g·F(75°) ≈ 2/3).
OPTICAL_CONSTANTS = {
    "aluminium": {"n": 0.77, "k": 6.08, "g": 2.0 / 3.0,
                  "source": "Rakic, Appl. Opt. 34, 4755 (1995), 0.50 um"},
    "MgO": {"n": 1.746, "k": 0.0, "g": 2.0,
            "source": "Stephens & Malitson, J. Res. NBS 49, 249 (1952), 0.50 um"},
}

_C = 0.05  # per degree (docs/models.md §2.3)
_G = 2.0 / 3.0


def relative_model(g: float = _G, c: float = _C, n: float | None = None,
                   k: float | None = None) -> rb.Model:
    """The TS67 model whose ``relative`` method is Eq. 23 (``rho_d`` cancels in the ratio)."""
    return rb.model("torrance-sparrow-1967", g=g, c=c, n=n, k=k, rho_d=0.3)


def _signed_axis(step: float = 0.1, limit: float = 89.9) -> np.ndarray:
    n = int(round(2 * limit / step)) + 1
    return np.linspace(-limit, limit, n)


def _relative_signed(model: rb.Model, psi_deg: float, theta_signed_deg: np.ndarray) -> np.ndarray:
    tr, ph = from_signed_angle(np.radians(theta_signed_deg))
    return np.asarray(model.evaluate(math.radians(psi_deg), tr, ph, quantity="relative"),
                      dtype=float)


def _g_over_cos_signed(psi_deg: float, theta_signed_deg: np.ndarray) -> np.ndarray:
    tr, ph = from_signed_angle(np.radians(theta_signed_deg))
    return np.asarray(rb.shadowing.g_over_cos_r(math.radians(psi_deg), tr, ph), dtype=float)


def _style_in_plane(ax, ylabel: str, title: str) -> None:
    ax.set_xlabel(SIGNED_LABEL)
    ax.set_ylabel(ylabel)
    ax.set_xlim(-90, 90)
    ax.set_xticks(np.arange(-90, 91, 15))
    ax.grid(True, alpha=0.3)
    ax.set_title(title, fontsize="medium")
    ax.legend(fontsize="small", loc="upper left")


# --------------------------------------------------------------------------------------------
# Fig. 7
# --------------------------------------------------------------------------------------------
def fig7() -> Reproduction:
    """Fig. 7: G/cos θ in the plane of incidence for ψ = 0, 30, 45, 60, 75°."""
    x = _signed_axis()
    curves = {psi: _g_over_cos_signed(psi, x) for psi in PSI_FIG7}
    fig, axes = new_figure(figsize=(7.0, 4.8))
    ax = axes[0, 0]
    for psi, col in zip(PSI_FIG7, incidence_colors(len(PSI_FIG7)), strict=True):
        ax.plot(x, curves[psi], color=col, label=f"ψ = {psi:g}°")
    ax.set_ylim(0, 16)
    _style_in_plane(ax, r"$G(\psi,\theta)/\cos\theta$",
                    "TS67 Fig. 7: geometrical attenuation factor over cos θ, plane of incidence")
    rows = [[xi, *(curves[p][i] for p in PSI_FIG7)] for i, xi in enumerate(x)]
    curve_table = Table(["theta_signed_deg", *(f"psi_{p:g}" for p in PSI_FIG7)], rows)
    t = np.asarray(FIG7_THETAS)
    targets = Table(["psi_deg", *(f"theta_{v:g}" for v in FIG7_THETAS)],
                    [[p, *_g_over_cos_signed(p, t)] for p in PSI_FIG7])
    # backward local maximum ("back peaks", compared by the paper with the aluminium data)
    back = []
    xb = np.round(np.arange(-89.9, 0.0, 0.01), 2)
    for psi in (10.0, 20.0, 30.0, 45.0, 60.0, 75.0):
        yb = _g_over_cos_signed(psi, xb)
        j = int(np.argmax(yb))
        back.append([psi, xb[j], yb[j]])
    return Reproduction(
        "ts67_fig07", "TS67 Fig. 7: G/cos θ in the plane of incidence", fig,
        {"curves": curve_table, "targets": targets,
         "back_peaks": Table(["psi_deg", "theta_back_max_deg", "G_over_cos_max"], back)})


# --------------------------------------------------------------------------------------------
# Fig. 8 and Fig. 9
# --------------------------------------------------------------------------------------------
def peak_table(model: rb.Model, psis: tuple[float, ...] = PSI_FIG8) -> Table:
    """Forward maximum of Eq. 23 (0.01° grid up to 89.99°) and the ratios docs/models.md §2.7
    lists."""
    xs = np.round(np.arange(0.0, 89.995, 0.01), 2)
    rows = []
    for psi in psis:
        y = _relative_signed(model, psi, xs)
        j = int(np.argmax(y))
        pick = _relative_signed(model, psi, np.array([0.0, 89.0, 89.99, -60.0]))
        rows.append([psi, xs[j], y[j], pick[0], pick[1], pick[2], pick[3]])
    return Table(["psi_deg", "theta_max_deg", "ratio_at_max", "ratio_theta_0",
                  "ratio_theta_89", "ratio_theta_89.99", "ratio_theta_-60"], rows)


def _relative_family(ax, model: rb.Model, psis, x, title: str) -> dict[float, np.ndarray]:
    curves = {psi: _relative_signed(model, psi, x) for psi in psis}
    for psi, col in zip(psis, incidence_colors(len(psis)), strict=True):
        ax.plot(x, curves[psi], color=col, label=f"ψ = {psi:g}°")
        ax.axvline(psi, color=col, lw=0.6, ls=":")
    _style_in_plane(ax, r"$\rho(\psi;\theta,\phi)/\rho(\psi;\psi,0)$", title)
    return curves


def fig8() -> Reproduction:
    """Fig. 8: Eq. 23 in the plane of incidence, F = 1, g = 2/3, c = 0.05/deg."""
    model = relative_model()
    x = _signed_axis()
    fig, axes = new_figure(figsize=(7.0, 4.8))
    ax = axes[0, 0]
    curves = _relative_family(ax, model, PSI_FIG8, x,
                              "TS67 Fig. 8: Eq. 23, F = 1, g = 2/3, c = 0.05/deg")
    ax.set_ylim(0, 3.5)
    rows = [[xi, *(curves[p][i] for p in PSI_FIG8)] for i, xi in enumerate(x)]
    return Reproduction(
        "ts67_fig08", "TS67 Fig. 8: relative bidirectional reflectance, F = 1", fig,
        {"curves": Table(["theta_signed_deg", *(f"psi_{p:g}" for p in PSI_FIG8)], rows),
         "peaks": peak_table(model)},
        notes=["No sharp drop-off beyond the off-specular peak (the paper notes the same "
               "deficiency of its model) and no back peaks at negative θ (removed by the "
               "gaussian factor, as the paper says)."])


def fig9(constants: dict | None = None) -> Reproduction:
    """Fig. 9: Eq. 23 with Fresnel at 0.5 µm, (a) aluminium g = 2/3, (b) MgO g = 2."""
    consts = constants or OPTICAL_CONSTANTS
    x = _signed_axis()
    fig, axes = new_figure(1, 2, figsize=(12.0, 4.8), sharey=True)
    tables = {}
    gf_rows: list[list[Any]] = []
    for ax, (name, letter) in zip(axes[0], (("aluminium", "a"), ("MgO", "b")), strict=True):
        cst: dict[str, Any] = consts[name]
        model = relative_model(g=cst["g"], n=cst["n"], k=cst["k"])
        curves = _relative_family(
            ax, model, PSI_FIG8, x,
            f"TS67 Fig. 9({letter}): {name}, n = {cst['n']:g} + {cst['k']:g}i, "
            f"g = {cst['g']:.3g}")
        ax.set_ylim(0, 6)
        key = name.lower()
        tables[f"{key}_curves"] = Table(["theta_signed_deg", *(f"psi_{p:g}" for p in PSI_FIG8)],
                                        [[xi, *(curves[p][i] for p in PSI_FIG8)]
                                         for i, xi in enumerate(x)])
        tables[f"{key}_peaks"] = peak_table(model)
        f75 = float(rb.fresnel.reflectance(math.cos(math.radians(75.0)), cst["n"], cst["k"]))
        gf_rows.append([name, cst["n"], cst["k"], cst["g"], f75, cst["g"] * f75,
                        cst.get("source", "")])
    tables["constants"] = Table(["material", "n", "k", "g", "F_75deg", "g_times_F_75deg",
                                 "source"], gf_rows)
    return Reproduction(
        "ts67_fig09", "TS67 Fig. 9: Eq. 23 with Fresnel reflectance at 0.5 µm", fig, tables,
        notes=["The paper's indices (AIP Handbook, 1963) are not printed; we use published "
               "modern values (see OPTICAL_CONSTANTS)."])


# --------------------------------------------------------------------------------------------
# Figs. 10 and 11 (out of the plane of incidence)
# --------------------------------------------------------------------------------------------
def _phi_family(values, ylabel: str, title: str, ylims, logs=(False, False, False)) -> tuple:
    theta = np.unique(np.append(np.arange(0.0, 89.9, 0.25), 89.9))
    fig, axes = new_figure(1, 3, figsize=(15.0, 4.6))
    rows: list[list[float]] = []
    for ax, psi, letter, ylim, log in zip(axes[0], PSI_OUT_OF_PLANE, "abc", ylims, logs,
                                          strict=True):
        for phi, col in zip(PHI_FAMILY, incidence_colors(len(PHI_FAMILY), "plasma"),
                            strict=True):
            y = values(psi, theta, phi)
            ax.plot(theta, y, color=col, label=f"φ = {phi:g}°")
            rows.extend([psi, phi, t, v] for t, v in zip(theta, y, strict=True))
        ax.set_xlim(0, 90)
        ax.set_xticks(np.arange(0, 91, 15))
        if log:
            ax.set_yscale("log")
        ax.set_ylim(*ylim)
        ax.set_xlabel(r"reflection angle $\theta$ [deg]")
        ax.set_ylabel(ylabel)
        ax.set_title(f"({letter}) ψ = {psi:g}°" + (" (log scale)" if log else ""),
                     fontsize="medium")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="small", loc="upper left")
    fig.suptitle(title)
    return fig, rows


def _phi_row(values) -> Table:
    """docs/models.md §2.7 check row: ψ = 75°, θ = 80°, φ = 0…180°."""
    row = [float(values(75.0, np.array([80.0]), phi)[0]) for phi in PHI_FAMILY]
    return Table(["psi_deg", "theta_deg", *(f"phi_{p:g}" for p in PHI_FAMILY)],
                 [[75.0, 80.0, *row]])


def _g_over_cos(psi: float, theta_deg: np.ndarray, phi_deg: float) -> np.ndarray:
    return np.asarray(rb.shadowing.g_over_cos_r(math.radians(psi), np.radians(theta_deg),
                                                math.radians(phi_deg)), dtype=float)


def fig10() -> Reproduction:
    """Fig. 10: G(ψ_p, θ_p)/cos θ for azimuths φ = 0…180°, ψ = 30, 60, 75°."""
    fig, rows = _phi_family(_g_over_cos, r"$G(\psi_p,\theta_p)/\cos\theta$",
                            "TS67 Fig. 10: G/cos θ for various azimuths φ",
                            [(0, 4), (0, 8), (0, 16)])
    return Reproduction("ts67_fig10", "TS67 Fig. 10: G/cos θ out of the plane of incidence",
                        fig, {"curves": Table(["psi_deg", "phi_deg", "theta_deg",
                                               "G_over_cos"], rows),
                              "check": _phi_row(_g_over_cos)})


def fig11() -> Reproduction:
    """Fig. 11: Eq. 23 for azimuths φ = 0…180°, ψ = 30, 60, 75°, F = 1, g = 2/3, c = 0.05."""
    model = relative_model()

    def rel(psi: float, theta_deg: np.ndarray, phi_deg: float) -> np.ndarray:
        return np.asarray(model.evaluate(math.radians(psi), np.radians(theta_deg),
                                         math.radians(phi_deg), quantity="relative"),
                          dtype=float)

    fig, rows = _phi_family(rel, r"$\rho(\psi;\theta,\phi)/\rho(\psi;\psi,0)$",
                            "TS67 Fig. 11: Eq. 23 for various azimuths φ "
                            "(F = 1, g = 2/3, c = 0.05/deg)",
                            [(0, 1.2), (0, 2.0), (0.05, 5.0)], logs=(False, False, True))
    return Reproduction("ts67_fig11", "TS67 Fig. 11: Eq. 23 out of the plane of incidence",
                        fig, {"curves": Table(["psi_deg", "phi_deg", "theta_deg", "ratio"], rows),
                              "check": _phi_row(rel)})


ALL = (fig7, fig8, fig9, fig10, fig11)
