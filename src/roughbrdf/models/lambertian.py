"""Lambertian reflector: constant BRDF ``rho/pi`` (TR75 Eq. 32 in BRIDF form)."""

from __future__ import annotations

import math

from .._jit import jit
from .base import Model, register, unit_interval


@jit
def _lambert_point(ti, tr, phi, gamma, p, flag):
    if flag:
        return p[0] / math.pi * max(0.0, math.cos(tr))  # BRIDF = rho cos(theta_r)/pi
    return p[0] / math.pi


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
    _point = _lambert_point

    def _pack(self) -> tuple:
        return (self._values["rho"],)
