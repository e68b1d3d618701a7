"""Lambertian reflector: constant BRDF ``rho/pi`` (TR75 Eq. 32 in BRIDF form)."""

from __future__ import annotations

import math

from numba import prange

from .._kernels import at, driver, jit
from .base import Model, register
from .parameters import unit_interval


@jit
def _lambert_point(ti, tr, phi, gamma, p, flag):
    if flag:
        return p[0] / math.pi * max(0.0, math.cos(tr))  # BRIDF = rho cos(theta_r)/pi
    return p[0] / math.pi


@driver
def _lambert_drive(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # module-level loop: cached on disk (roughbrdf._kernels.compile.driver), unlike the generic driver
    for i in prange(out.size):
        out[i] = _lambert_point(at(a, i), at(b, i), at(c, i), at(g, i), p, flag)


@register
class Lambertian(Model):
    """Ideal diffuse reflector, ``f_r = rho/pi`` sr⁻¹, ``rho`` its directional-hemispherical
    reflectance (independent of incidence). Reciprocal; defined at grazing incidence too.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> round(rb.model("lambertian", rho=0.5).brdf(0.3, 0.2, 1.0), 6)
    0.159155
    """

    name = "lambertian"
    aliases = ("lambert", "diffuse")
    short = "lambertian"
    reference = "Lambert 1760; TR75 Eq. 32"
    PARAMETERS = (unit_interval("rho", 0.5, "directional-hemispherical reflectance"),)
    grazing_incidence = True
    _drive = _lambert_drive

    def _pack(self) -> tuple:
        return (self._values["rho"],)
