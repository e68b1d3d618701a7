"""Lambertian reflector: constant BRDF ``rho/pi`` (TR75 Eq. 32 in BRIDF form)."""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from .._kernels import at, driver, jit, sincos
from .base import Model, PreparedGeometry, register
from .parameters import reflectance


@jit(inline=True)
def _lambert_point(ti, tr, phi, gamma, p, flag):
    if flag:  # BRIDF = rho cos(theta_r)/pi; sincos: no libm cos in the driver loop
        # max: no negative value from a rounded cosine at theta_r = pi/2
        return p[0] / math.pi * max(0.0, sincos(tr)[1])
    return p[0] / math.pi


@driver
def _lambert_drive(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # module-level loop: cached on disk (roughbrdf._kernels.compile.driver); one loop per
    # quantity with the flag a literal (the BRDF loop is then a plain fill)
    if flag:
        for i in prange(out.size):
            out[i] = _lambert_point(at(a, i), at(b, i), at(c, i), at(g, i), p, 1)
    else:
        for i in prange(out.size):
            out[i] = _lambert_point(at(a, i), at(b, i), at(c, i), at(g, i), p, 0)


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
    PARAMETERS = (reflectance("rho", 0.5, "directional-hemispherical reflectance"),)
    grazing_incidence = True
    _drive = _lambert_drive

    @property
    def conserves_energy(self) -> bool:
        """True: the albedo is ``rho <= 1`` at every incidence."""
        return True

    def _pack(self) -> tuple:
        return (self._values["rho"],)

    def _mueller(self, g: PreparedGeometry, basis: int, term: str | None) -> np.ndarray:
        # an ideal depolarizer times the BRDF, in every basis (docs/models.md §11)
        return self._mueller_depolarizer(g, term)
