"""Renhorn & Boreman (2008): Fig. 2 (Vm against scattering angle) and Fig. 3 (in-plane BRDF).

I. G. E. Renhorn and G. D. Boreman, "Analytical fitting model for rough-surface BRDF",
Opt. Express 16(17), 12892-12898 (2008). Targets: MODELS.md §4.14.

The paper's fitted parameter values and its measured data are not available (seed ``004_...``
has the abstract, the three figure captions and flattened equations only), so the figures use
the parameter set :data:`PARAMS` (see its comment for where it comes from). What can be checked
without the paper: Vm's identities (§4.8) and the claim that the model spans two orders of
magnitude of BRDF over a range of incidences (§4.14).
"""

from __future__ import annotations

import math

import numpy as np

import roughbrdf as rb

from ..geometry import from_signed_angle
from ..plot import SIGNED_LABEL, incidence_colors
from ._common import Reproduction, Table, Unavailable, new_figure

__all__ = ["PARAMS", "PARAMS_SOURCE", "INCIDENCES_FIG2", "INCIDENCES_FIG3", "model", "fig2",
           "fig3", "ALL"]

#: The parameter set of Figs. 2 and 3. No fitted values are published (MODELS.md §7), so this
#: is a *plausible* set chosen by us, not the paper's: a rough dielectric (n_eff = 1.5) with a
#: moderately wide surface lobe (rho = 0.2 in direction-cosine space), shadowing that narrows the
#: lobe toward grazing (w = 1.0, n = 2), a Vm that enhances the backward side and attenuates the
#: forward side (w_a = 0.8 /rad, w_b = 0.5, gamma = 1.5 /rad, delta = 1.0 /rad²), a small
#: Lambertian bulk (0.1) and a weak, narrow retro lobe (retro = 0.005, rho_r = 0.1). It gives
#: in-plane BRDFs from ~0.03 to ~50 sr⁻¹ over 0-75° incidence. Replace it with values fitted to
#: measurements (the CEA gray tape of the fitting issue) once those are published.
PARAMS = {"rho": 0.2, "w": 1.0, "n": 2.0, "w_a": 0.8, "w_b": 0.5, "gamma": 1.5, "delta": 1.0,
          "n_eff": 1.5, "k_eff": 0.0, "bulk": 0.1, "retro": 0.005, "rho_r": 0.1, "w_r": 0.9,
          "n_r": 4.0}
PARAMS_SOURCE = "plausible set chosen for roughbrdf (no published fit); see rb08.PARAMS"

INCIDENCES_FIG2 = (20.0, 60.0)
INCIDENCES_FIG3 = (0.0, 20.0, 40.0, 60.0, 75.0)


def model(params: dict | None = None) -> rb.Model:
    """The RB08 model with :data:`PARAMS` (recommended readings of MODELS.md §4)."""
    try:
        return rb.model("renhorn-boreman-2008", **(params or PARAMS))
    except ValueError as exc:
        if "unknown model" in str(exc):
            raise Unavailable("the RB08 model ('renhorn-boreman-2008') is not available in "
                              "this version of roughbrdf") from exc
        raise


def _vm(zeta: np.ndarray, theta_i_deg: float, p: dict) -> np.ndarray:
    if not hasattr(rb.shadowing, "Vm"):
        raise Unavailable("rb.shadowing.Vm (RB08 Eq. 13) is not available in this version")
    return np.asarray(rb.shadowing.Vm(zeta, math.radians(theta_i_deg), p["w_a"], p["w_b"],
                                      p["gamma"], p["delta"]), dtype=float)


def fig2(params: dict | None = None) -> Reproduction:
    """Fig. 2: the masking/shadowing multiplier Vm against scattering angle, two incidences.

    Reading Z-a of MODELS.md §4.8: ζ = signed in-plane scattering angle (radians; > 0 forward),
    ζ0 = θi; Vm = B for ζ < 0 (the same for every incidence) and 1 − E0 (1 − B) for ζ > 0.
    """
    p = params or PARAMS
    model(p)  # fail early (Unavailable) if the model is missing
    zeta_deg = np.round(np.arange(-90.0, 90.0 + 1e-9, 0.5), 1)
    zeta = np.radians(zeta_deg)
    fig, axes = new_figure(figsize=(7.0, 4.8))
    ax = axes[0, 0]
    curves = {}
    for ti, col in zip(INCIDENCES_FIG2, ("C0", "C3"), strict=True):
        curves[ti] = _vm(zeta, ti, p)
        ax.plot(zeta_deg, curves[ti], color=col, label=rf"$\theta_i$ = {ti:g}°")
    ax.axhline(1.0, color="0.5", lw=0.6)
    ax.axvline(0.0, color="0.5", lw=0.6)
    ax.set_xlim(-90, 90)
    ax.set_xticks(np.arange(-90, 91, 30))
    ax.set_xlabel(r"scattering angle $\zeta$ [deg] (negative = source side)")
    ax.set_ylabel(r"masking/shadowing multiplier $V_m$")
    ax.set_title(f"RB08 Fig. 2: Vm (Eq. 13), w_a = {p['w_a']:g}, w_b = {p['w_b']:g}, "
                 f"γ = {p['gamma']:g}, δ = {p['delta']:g}", fontsize="medium")
    ax.grid(True, alpha=0.3)
    ax.legend()
    # identities of MODELS.md §4.8, evaluated through the public API
    checks = []
    eps = 1e-9
    for ti in INCIDENCES_FIG2:
        z0 = math.radians(ti)
        e0 = math.exp(-p["gamma"] * z0 * math.exp(-p["delta"] * z0 * z0))
        at0 = float(_vm(np.array([0.0]), ti, p)[0])
        jump = float(abs(_vm(np.array([eps]), ti, p)[0] - _vm(np.array([-eps]), ti, p)[0]))
        zs = np.radians([-60.0, -30.0, 30.0, 60.0])
        b = np.exp(-p["w_a"] * zs * np.exp(-p["w_b"] * np.sin(zs) ** 2))
        expect = np.where(zs < 0, b, 1.0 - e0 * (1.0 - b))
        err = float(np.max(np.abs(_vm(zs, ti, p) - expect)))
        checks.append([ti, e0, at0, jump, err])
    rows = [[z, *(curves[t][i] for t in INCIDENCES_FIG2)] for i, z in enumerate(zeta_deg)]
    return Reproduction(
        "rb08_fig02", "RB08 Fig. 2: masking/shadowing function Vm against scattering angle", fig,
        {"curves": Table(["zeta_deg", *(f"vm_theta_i_{t:g}" for t in INCIDENCES_FIG2)], rows),
         "checks": Table(["theta_i_deg", "E0", "vm_at_0", "jump_at_0", "max_piecewise_error"],
                         checks)},
        notes=[f"Parameters: {PARAMS_SOURCE}.",
               "ζ read as the signed in-plane scattering angle, ζ0 = θi (MODELS.md §4.8, Z-a)."])


def fig3(params: dict | None = None) -> Reproduction:
    """Fig. 3: in-plane BRDF against scattering angle for several incidences (log scale)."""
    p = params or PARAMS
    m = model(p)
    x = np.round(np.arange(-89.5, 89.5 + 1e-9, 0.25), 2)
    tr, ph = from_signed_angle(np.radians(x))
    fig, axes = new_figure(figsize=(7.5, 5.0))
    ax = axes[0, 0]
    curves, summary = {}, []
    for ti, col in zip(INCIDENCES_FIG3, incidence_colors(len(INCIDENCES_FIG3)), strict=True):
        y = np.asarray(m.brdf(math.radians(ti), tr, ph), dtype=float)
        curves[ti] = y
        ax.semilogy(x, y, color=col, label=rf"$\theta_i$ = {ti:g}°")
        summary.append([ti, float(y.min()), float(y.max()), float(x[np.argmax(y)]),
                        float(y.max() / y.min())])
    allv = np.concatenate(list(curves.values()))
    summary.append(["all", float(allv.min()), float(allv.max()), float("nan"),
                    float(allv.max() / allv.min())])
    ax.set_xlim(-90, 90)
    ax.set_xticks(np.arange(-90, 91, 30))
    ax.set_xlabel(SIGNED_LABEL.replace("reflection", "scattering"))
    ax.set_ylabel(r"BRDF [sr$^{-1}$]")
    ax.set_title("RB08 Fig. 3: in-plane BRDF, parameterized on incidence\n"
                 f"({PARAMS_SOURCE.split(';')[0]})", fontsize="medium")
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize="small")
    rows = [[xi, *(curves[t][i] for t in INCIDENCES_FIG3)] for i, xi in enumerate(x)]
    return Reproduction(
        "rb08_fig03", "RB08 Fig. 3: rough-surface BRDF against in-plane scattering angle", fig,
        {"curves": Table(["theta_signed_deg", *(f"brdf_theta_i_{t:g}" for t in INCIDENCES_FIG3)],
                         rows),
         "range": Table(["theta_i_deg", "brdf_min", "brdf_max", "theta_at_max_deg",
                         "max_over_min"], summary),
         "params": Table(["parameter", "value"], [[k, v] for k, v in m.params.items()])},
        notes=[f"Parameters: {PARAMS_SOURCE}; the paper's fitted values are not published "
               "in the seed."])


ALL = (fig2, fig3)
