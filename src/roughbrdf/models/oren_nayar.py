"""Oren-Nayar rough diffuse reflector (Oren & Nayar 1994, qualitative model, Eq. 30)."""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from .._kernels import at, driver, jit, sincos
from ..diffuse import oren_nayar_factor
from .base import Model, PreparedGeometry, register
from .parameters import nonnegative, reflectance


@jit(inline=True)
def _on_point(ti, tr, phi, gamma, p, flag):
    si, ci = sincos(ti)
    sr, cr = sincos(tr)
    cp = sincos(phi)[1]
    # cos(pi/2) rounds to 6e-17: below 1e-15 it is exactly 0 (theta_r = pi/2 is exactly
    # grazing, docs/models.md §1.1, as in geometry.half_vector), so bridf is 0 on the horizon
    cr = 0.0 if cr < 1e-15 else cr
    f = p[0] / math.pi * oren_nayar_factor(ci, cr, si, sr, cp, p[1])
    return f * cr if flag else f


@driver
def _on_drive(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # module-level loop: cached on disk (roughbrdf._kernels.compile.driver); the quantity flag
    # a literal in each loop
    if flag:
        for i in prange(out.size):
            out[i] = _on_point(at(a, i), at(b, i), at(c, i), at(g, i), p, 1)
    else:
        for i in prange(out.size):
            out[i] = _on_point(at(a, i), at(b, i), at(c, i), at(g, i), p, 0)


@register
class OrenNayar(Model):
    """Rough diffuse reflector: ``rho/pi (A + B max(0, cos(phi_r - phi_i)) sin(alpha) tan(beta))``.

    Oren & Nayar (1994), Eq. 30 (the "qualitative" model: Lambertian V-cavities of slope-angle
    standard deviation ``sigma``, with masking, shadowing and the retro-reflective brightening
    of rough diffuse surfaces; without the inter-reflection term). ``sigma = 0`` is Lambertian.
    Reciprocal; ``theta_i < pi/2`` (``tan beta`` diverges with both directions grazing).
    ``docs/models.md`` §10.2.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> m = rb.model("oren-nayar", rho=0.8, sigma=0.0)
    >>> round(m.brdf(0.3, 0.2, 1.0), 6)                       # sigma = 0: rho/pi
    0.254648
    >>> m = m.with_params(sigma=0.4)
    >>> bool(m.brdf(0.6, 0.6, 3.14159) > m.brdf(0.6, 0.6, 0.0))   # brighter toward the source
    True
    """

    name = "oren-nayar"
    aliases = ("orennayar", "rough-diffuse")
    short = "on"
    reference = "Oren & Nayar 1994, Eq. 30"
    PARAMETERS = (
        reflectance("rho", 0.5, "albedo of the facets (rho/pi: Lambertian facets)"),
        nonnegative("sigma", 0.3, (0.0, 1.2), "rad", "standard deviation of the facet slope"),
    )
    _drive = _on_drive

    def _pack(self) -> tuple:
        v = self._floats()
        return (v["rho"], v["sigma"] ** 2)

    def _mueller(self, g: PreparedGeometry, basis: int, term: str | None) -> np.ndarray:
        # an ideal depolarizer times the BRDF, in every basis (docs/models.md §11)
        return self._mueller_depolarizer(g, term)
