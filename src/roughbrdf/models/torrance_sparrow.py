"""Torrance & Sparrow (1967): V-groove facets, gaussian slope-angle distribution, Fresnel.

K. E. Torrance and E. M. Sparrow, "Theory for off-specular reflection from roughened surfaces",
J. Opt. Soc. Am. 57(9), 1105-1114 (1967). docs/models.md §2.

Absolute form (from Eq. 12, docs/models.md §2.3)::

    f_r = (rho_d/pi) [ g F(theta_d) G exp(-c^2 alpha^2) / (cos theta_i cos theta_r) + 1 ]

with ``alpha = theta_h`` in degrees and ``c`` per degree (docs/models.md §2.3), ``G`` the V-groove
attenuation factor (Table I = the 3-D closed form), ``F`` the Fresnel reflectance at the local
angle ``theta_d`` (unpolarized unless a polarization is given; ``n=None`` gives ``F = 1``), and
``g = b f dω_i/(4 a)`` the paper's ratio of facet to diffuse contributions. The first term is the
facet part (``P(alpha) = b exp(-c^2 alpha^2)`` with ``b f/4`` absorbed into ``g rho_d/pi``), the
second the uniform diffuse part ``a/dω_i = rho_d/pi``. Dividing by its value at the specular
direction gives the paper's relative reflectance, Eq. 23 (:meth:`TorranceSparrow1967.relative`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange
from numpy.typing import ArrayLike

from .. import distributions as dist
from .._kernels import at, driver, jit
from ..errors import ArgumentError
from ..fresnel import check_index, fresnel_polarized_xy
from ..geometry import half_vector, tr75_eta_xy
from ..mueller import facet_mueller
from ..shadowing import v_groove_g_over_cos_cos, v_groove_g_over_cos_r
from .base import Model, PreparedGeometry, register, require_index
from .parameters import Parameter, nonnegative, positive, reflectance


@jit(inline=True)
def _ts67_facet(ti, tr, phi, gamma, p, flag, use_f):
    """``(g F G gauss/(cos theta_i cos theta_r), cos theta_r)``: the facet part of the absolute
    form in units of ``rho_d/pi`` (``flag = 1``: times ``cos theta_r``); ``use_f`` False: F = 1.
    """
    # Inlined into the driver and free of libm calls (vacos/vexp in the gaussian, eta as a
    # vector instead of atan2, selects instead of branches), so that the driver loop
    # vectorizes; see docs/benchmarks.md. flag/use_f are literals in the driver's loops.
    g, c, n, k = p[0], p[1], p[2], p[3]
    hx, hy, hz, cd, ci, cr, si = half_vector(ti, tr, phi)
    if use_f:
        # F at the local angle; eta (TR75 Eq. 24) from the unnormalized sin(s) (cos, sin)
        ex, ey = tr75_eta_xy(si, ci, hx, hy, hz)
        f = fresnel_polarized_xy(cd, n, k, gamma, ex, ey)
    else:
        f = 1.0
    gauss = dist.peak(dist.GAUSS_ANGLE, hz, c)  # exp(-(c alpha_deg)^2), TS67 Eq. 5
    t = g * f * gauss
    if flag:  # G/cos(theta_i) per branch (symmetry of G): finite also where cos(theta_i) = 0
        geo = v_groove_g_over_cos_r(cr, ci, hz, cd)
    else:
        # G/(cos theta_i cos theta_r) per branch: finite at theta_r = 90 deg (docs/models.md
        # §2.5) and where cos(theta_i) rounds to 0
        geo = v_groove_g_over_cos_cos(ci, cr, hz, cd)
    # t = 0 (gaussian underflow) gives 0, never 0 * inf
    return (t * geo if t > 0.0 else 0.0), cr


@jit(inline=True)
def _ts67_eval(ti, tr, phi, gamma, p, flag, use_f):
    facet, cr = _ts67_facet(ti, tr, phi, gamma, p, flag, use_f)
    rho_d = p[4]
    if flag:  # BRIDF: f_r cos(theta_r) = rho_d/pi [g F gauss G/cos(theta_i) + cos(theta_r)]
        return rho_d / math.pi * (facet + cr)
    return rho_d / math.pi * (facet + 1.0)


@driver
def _ts67_drive(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # module-level loop: cached on disk (roughbrdf._kernels.compile.driver). One loop per
    # quantity and Fresnel switch, both literals, so that the unused code is compiled away
    # (as TR75's quantity flag; F = 1, the paper's Figs. 8, 10, 11, skips the Fresnel part)
    if p[5] > 0.0:
        if flag:
            for i in prange(out.size):
                out[i] = _ts67_eval(at(a, i), at(b, i), at(c, i), at(g, i), p, 1, True)
        else:
            for i in prange(out.size):
                out[i] = _ts67_eval(at(a, i), at(b, i), at(c, i), at(g, i), p, 0, True)
    elif flag:
        for i in prange(out.size):
            out[i] = _ts67_eval(at(a, i), at(b, i), at(c, i), at(g, i), p, 1, False)
    else:
        for i in prange(out.size):
            out[i] = _ts67_eval(at(a, i), at(b, i), at(c, i), at(g, i), p, 0, False)


@driver
def _ts67_mueller_drive(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # Mueller matrices (roughbrdf.mueller; flag = basis code): the facet part of the scalar
    # kernel with F = 1 as the facet factor, n + ik = p[2] + i p[3], and the diffuse part
    # rho_d/pi as an ideal depolarizer
    nan = math.nan
    kd = p[4] / math.pi
    for i in prange(out.shape[0]):
        ti, tr, ph = at(a, i), at(b, i), at(c, i)
        facet = _ts67_facet(ti, tr, ph, nan, p, 0, False)[0]
        facet_mueller(out, i, ti, tr, ph, p[2], p[3], flag, kd * facet)
        out[i, 0, 0] += kd


@register
class TorranceSparrow1967(Model):
    """Torrance-Sparrow (1967) off-specular reflection model (docs/models.md §2).

    Parameters
    ----------
    g : float
        Ratio of facet to diffuse contributions (TS67 Eq. 13); 0 = purely diffuse.
    c : float
        Width of the gaussian facet-angle distribution, **per degree** (0.05 in the paper).
    n, k : float or None
        Complex index ``n + i k`` of the facet material; ``n=None`` sets ``F = 1``
        (Figs. 8, 10, 11).
    rho_d : float
        Scale of the absolute form: ``rho_d/pi`` is the diffuse BRDF (sr⁻¹), so ``rho_d`` is the
        directional-hemispherical reflectance of the diffuse part, in [0, 1] like every
        reflectance-like parameter (:data:`~roughbrdf.models.parameters.REFLECTANCE_DOMAIN`).

    Notes
    -----
    Angles are the common frame (TS67's own psi, theta, phi are the same). ``theta_i`` must be
    below 90 deg (Eq. 23's denominator ``g F/cos psi`` diverges). The model is finite at
    ``theta_r = 90 deg`` through the per-branch ``G/cos theta_r`` (docs/models.md §2.5).

    Examples
    --------
    >>> import numpy as np, roughbrdf as rb
    >>> ts = rb.model("torrance-sparrow-1967", g=2/3, c=0.05, n=None, k=None, rho_d=0.3)
    >>> round(float(ts.relative(np.radians(75), np.radians(80), 0.0)), 3)   # docs/models.md §2.7
    1.425
    """

    name = "torrance-sparrow-1967"
    aliases = ("ts67", "torrance-sparrow")
    short = "ts67"
    reference = "Torrance & Sparrow, JOSA 57, 1105 (1967)"
    PARAMETERS = (
        nonnegative("g", 2.0 / 3.0, (0.0, 50.0), "1",
                    "ratio of facet to diffuse contributions (Eq. 13)"),
        positive("c", 0.05, (0.005, 0.5), "1/deg",
                 "gaussian facet-angle width, exp(-(c alpha_deg)^2) (Eq. 5)"),
        Parameter("n", None, (0.2, 5.0), "1", "refractive index (None: F = 1)",
                  (0.0, False, math.inf, False), optional=True),
        Parameter("k", None, (0.0, 10.0), "1", "extinction index, n + ik (None: 0)",
                  (0.0, True, math.inf, False), optional=True),
        reflectance("rho_d", 0.3, "reflectance of the diffuse part (its BRDF is rho_d/pi sr^-1)",
                    bounds=(1e-4, 1.0)),
    )

    def _validate(self) -> None:
        n, k = self._values["n"], self._values["k"]
        if n is None and k not in (None, 0.0):
            raise ArgumentError("k", "parameter 'k' given without 'n' (n=None means F = 1)",
                                value=k)
        if n is not None:
            check_index(n, 0.0 if k is None else k)

    def _pack(self) -> tuple:
        v = self._values
        use_f = v["n"] is not None
        return (v["g"], v["c"], v["n"] if use_f else 1.0, (v["k"] or 0.0) if use_f else 0.0,
                v["rho_d"], 1.0 if use_f else 0.0)

    _drive = _ts67_drive

    def _mueller(self, g: PreparedGeometry, basis: int, term: str | None) -> np.ndarray:
        require_index(self)
        return self._mueller_drive(_ts67_mueller_drive, g, self._pack(), basis, term)

    def relative(self, theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike,
                 polarization=None) -> np.ndarray | float:
        """TS67 Eq. 23: ``rho(psi; theta, phi)/rho(psi; psi, 0)``, relative to the specular value.

        Equal to ``brdf(theta_i, theta_r, phi)/brdf(theta_i, theta_i, 0)``: at the specular
        direction ``G = 1``, ``alpha = 0`` and ``theta_d = psi``, so the ratio of the absolute
        forms is exactly Eq. 23 (``rho_d`` cancels).
        """
        return self.evaluate(theta_i, theta_r, phi, quantity="relative",
                             polarization=polarization)
