"""Trowbridge & Reitz (1975): ellipsoid "average irregularity", absolute BRIDF, polarization.

T. S. Trowbridge and K. P. Reitz, "Average irregularity representation of a rough surface for
ray reflection", J. Opt. Soc. Am. 65(5), 531-536 (1975); Naval Missile Center report TP-75-01.
docs/models.md §3.

BRIDF (Eqs. 30, 32, 33), in sr⁻¹::

    f_rI = R(s, gamma, n, k) e^2 / [4 pi cos(beta) (e^2 cos^2 alpha + sin^2 alpha)^2]
           + sin(theta_elev) rho_L / pi

with ``beta = theta_i``, ``alpha = theta_h``, ``s = theta_d``, ``sin(theta_elev) = cos theta_r``.
The specular part equals ``R D/(4 cos theta_i)`` with ``D`` the normalized Trowbridge-Reitz (GGX,
alpha = e) distribution. ``brdf = bridf/cos theta_r``. ``R`` follows Eq. 24 with the angle ``eta``
between the local and macroscopic planes of incidence (docs/models.md §3.5).

The published model has no shadowing, so its BRDF diverges at ``theta_r = 90 deg``: there
``brdf()`` returns its limit ``inf`` while ``bridf()`` stays finite. The report's footnote allows
multiplying by TS67's G (option ``shadowing="v-groove"``), which makes the BRDF finite.
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from .. import distributions as dist
from .. import shadowing as shd
from .._kernels import at, driver, jit
from ..fresnel import check_index, fresnel_polarized_xy
from ..geometry import half_vector, tr75_eta_xy
from ..mueller import facet_mueller
from .base import Model, PreparedGeometry, register
from .parameters import nonnegative, positive, reflectance


@jit(inline=True)
def _tr75_value(r, hz, cd, ci, cr, e, rho_l, shadow, flag):
    """Eq. 33 for the reflectance ``r`` (``flag = 1``: BRIDF; 0: BRDF); with ``r = 1`` and
    ``rho_l = 0`` the specular part's factor without R, exactly (``x + 0 = x``)."""
    spec4 = 0.25 * r * dist.trowbridge_reitz_d(hz, e)  # R D/4; Eq. 30 = spec4/cos(theta_i)
    if flag:  # BRIDF, Eq. 33
        if shadow > 0.0:  # G/cos(theta_i) per branch (G symmetric), finite at grazing
            spec = spec4 * shd.v_groove_g_over_cos_r(cr, ci, hz, cd)
        else:  # Eq. 30 diverges as 1/cos(beta) at grazing incidence (docs/models.md §3.13): inf
            spec = spec4 / ci if ci > 0.0 else math.inf
        return spec + cr * rho_l / math.pi
    # BRDF = BRIDF / cos(theta_r)
    if shadow > 0.0:
        return spec4 * shd.v_groove_g_over_cos_cos(ci, cr, hz, cd) + rho_l / math.pi
    den = ci * cr
    if den <= 0.0:
        return math.inf  # unshadowed Eq. 30 over cos(theta_r) diverges at the horizon
    return spec4 / den + rho_l / math.pi


@jit(inline=True)
def _tr75_point(ti, tr, phi, gamma, p, flag):
    e, n, k, rho_l, shadow = p[0], p[1], p[2], p[3], p[4]
    hx, hy, hz, cd, ci, cr, si = half_vector(ti, tr, phi)
    ex, ey = tr75_eta_xy(si, ci, hx, hy, hz)  # sin(s) (cos, sin) eta, Eq. 23 (docs/models.md §3.5)
    r = fresnel_polarized_xy(cd, n, k, gamma, ex, ey)
    return _tr75_value(r, hz, cd, ci, cr, e, rho_l, shadow, flag)


@driver
def _tr75_drive(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # one loop per quantity, with the flag a literal: the compiler then drops the other
    # quantity's code from the loop body (measured: ~25 % faster than a runtime flag)
    if flag:
        for i in prange(out.size):
            out[i] = _tr75_point(at(a, i), at(b, i), at(c, i), at(g, i), p, 1)
    else:
        for i in prange(out.size):
            out[i] = _tr75_point(at(a, i), at(b, i), at(c, i), at(g, i), p, 0)


@driver
def _tr75_mueller_drive(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # Mueller matrices (roughbrdf.mueller; flag = basis code): the specular part with R = 1 as
    # the facet factor, n + ik = p[1] + i p[2], and the Lambertian part rho_L/pi as an ideal
    # depolarizer
    kd = p[3] / math.pi
    for i in prange(out.shape[0]):
        ti, tr, ph = at(a, i), at(b, i), at(c, i)
        hz, cd, ci, cr = half_vector(ti, tr, ph)[2:6]
        facet_mueller(out, i, ti, tr, ph, p[1], p[2], flag,
                      _tr75_value(1.0, hz, cd, ci, cr, p[0], 0.0, p[4], 0))
        out[i, 0, 0] += kd


@register
class TrowbridgeReitz1975(Model):
    """Trowbridge-Reitz (1975) ellipsoid model plus a Lambertian part (docs/models.md §3).

    Parameters
    ----------
    e : float
        Ellipsoid axis ratio (rotation axis / perpendicular axis); < 1 glossy, > 1 prolate.
    n, k : float
        Complex index ``n + i k`` (TR75 writes ``n - i k``; same reflectance).
    rho_L : float
        Directional-hemispherical reflectance of the Lambertian part (Eq. 32).
    shadowing : {"none", "v-groove"}
        Option: multiply the specular part by TS67's G (report footnote). Default ``"none"``.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> m = rb.model("trowbridge-reitz-1975", e=0.68, n=1.0, k=0.9, rho_L=0.33)
    >>> round(m.bridf(0.0, 0.0, 0.0), 5)      # R(0)/(4 pi e^2) + rho_L/pi
    0.13402
    """

    name = "trowbridge-reitz-1975"
    aliases = ("tr75", "trowbridge-reitz")
    short = "tr75"
    reference = "Trowbridge & Reitz, JOSA 65, 531 (1975)"
    PARAMETERS = (
        positive("e", 0.68, (0.02, 3.0), "1", "ellipsoid axis ratio (GGX alpha = e)"),
        # n = 1 with k = 0 matches the index: F = 0, the specular lobe off (a fit's end
        # there is tried on it exactly: Parameter.neutral)
        positive("n", 1.0, (0.2, 5.0), "1", "refractive index (n + ik)", neutral=1.0),
        nonnegative("k", 0.9, (0.0, 10.0), "1", "extinction index (n + ik), >= 0 absorbing"),
        reflectance("rho_L", 0.33, "Lambertian directional-hemispherical reflectance"),
    )
    OPTIONS = {"shadowing": "none"}
    _drive = _tr75_drive

    def _check_options(self, options):
        code = shd.get(options["shadowing"]).code
        if code not in (shd.NONE, shd.V_GROOVE):
            raise ValueError(f"TR75 shadowing must be 'none' or 'v-groove' (report footnote), "
                             f"got {options['shadowing']!r}")
        return {"shadowing": shd.canonical(code)}

    def _validate(self) -> None:
        v = self._floats()
        check_index(v["n"], v["k"])

    def _pack(self) -> tuple:
        v = self._floats()
        return (v["e"], v["n"], v["k"], v["rho_L"],
                1.0 if self._options["shadowing"] == "v-groove" else 0.0)

    def _mueller(self, g: PreparedGeometry, basis: int, term: str | None) -> np.ndarray:
        return self._mueller_drive(_tr75_mueller_drive, g, self._pack(), basis, term)
