"""FRED's three-parameter Harvey–Shack scatter model: ``b0 (1 + (|β - β0|/L)²)^(S/2)``.

Definition pinned from FRED's help ("Scatter Types > Harvey-Shack": "the modified three term
Harvey model", linear shift-invariant; ``b0`` the BSDF at ``|β - β0| = 0``, ``L`` the knee
(near-specular roll-over) in ``|β - β0|``, ``S`` the log-log slope far from specular, ``S < 0``,
typically -0.5 to -2) and Harvey's shift-invariant scatter (Stover, *Optical Scattering*,
§1.5): far from the knee the BSDF falls as ``|β - β0|^S``. ``β``, ``β0`` as for ABg
(:func:`~.abg.beta_distance`). FRED's Extended Harvey–Shack (Greynolds; parameters P, Q) is not
implemented: its incidence dependence is published only as an equation image whose "g term"
the text does not define (``docs/straylight.md`` §Harvey–Shack).
"""

from __future__ import annotations

import numpy as np
from numba import prange
from numpy.typing import ArrayLike

from ..._kernels import at, driver, jit, sincos
from ..base import Model, PreparedGeometry, register
from ..parameters import Parameter, positive
from .abg import beta_distance
from .tis import check_harvey_shack, harvey_shack_bsdf, harvey_shack_tis

__all__ = ["HarveyShack"]


@jit(inline=True)
def _hs_point(ti, tr, phi, gamma, p, flag):
    f = harvey_shack_bsdf(beta_distance(ti, tr, phi), p[0], p[1], p[2])
    if flag:
        cr = sincos(tr)[1]
        # cos(pi/2) rounds to 6e-17: below 1e-15 it is exactly 0 (the horizon, as in ABg)
        return f * (0.0 if cr < 1e-15 else cr)
    return f


@driver
def _hs_drive(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # module-level loop, cached on disk; the quantity flag a literal in each loop
    if flag:
        for i in prange(out.size):
            out[i] = _hs_point(at(a, i), at(b, i), at(c, i), at(g, i), p, 1)
    else:
        for i in prange(out.size):
            out[i] = _hs_point(at(a, i), at(b, i), at(c, i), at(g, i), p, 0)


@register
class HarveyShack(Model):
    """Harvey–Shack scatter model (FRED): ``BSDF = b0 (1 + (|β - β0|/L)²)^(S/2)`` sr⁻¹.

    ``brdf`` is this BSDF; no separate specular delta (:meth:`tis` is all of the reflectance).
    FRED's rules: ``b0 > 0``, ``L > 0``, ``S < 0``. Reciprocal; defined at grazing incidence.

    Examples
    --------
    >>> import roughbrdf as rb, roughbrdf.models.straylight
    >>> m = rb.model("harvey-shack", b0=0.1, L=0.01, S=-1.5)
    >>> round(m.brdf(0.2, 0.2, 0.0), 12)                # at the specular: b0
    0.1
    """

    name = "harvey-shack"
    aliases = ("hs", "harveyshack")
    short = "hs"
    reference = "FRED help, Scatter Types > Harvey-Shack (modified three-term Harvey model)"
    PARAMETERS = (
        positive("b0", 0.1, (1e-6, 1e3), "sr^-1", "BSDF at the specular direction"),
        positive("L", 0.01, (1e-5, 1.0), "1",
                 "knee (roll-over) of the BSDF in |beta - beta0| (direction cosines)"),
        Parameter("S", -1.5, (-4.0, -1e-3), "1", "log-log slope far from specular (< 0)",
                  (-np.inf, False, 0.0, False)),
    )
    grazing_incidence = True
    _drive = _hs_drive

    def _validate(self) -> None:
        v = self._floats()  # every parameter is set (none is optional)
        check_harvey_shack(v["b0"], v["L"], v["S"])

    def _pack(self) -> tuple:
        v = self._floats()
        return (v["b0"], v["L"], v["S"])

    def _mueller(self, g: PreparedGeometry, basis: int, term: str | None) -> np.ndarray:
        # an ideal depolarizer times the BSDF in every basis: the model has no polarization
        return self._mueller_depolarizer(g, term)

    def tis(self, theta_i: ArrayLike) -> np.ndarray | float:
        """Total integrated scatter at ``theta_i`` (radians): :func:`~.tis.harvey_shack_tis`.

        Examples
        --------
        >>> import roughbrdf as rb, roughbrdf.models.straylight
        >>> round(float(rb.model("hs", b0=0.1, L=0.01, S=-1.5).tis(0.0)), 6)
        0.001131
        """
        v = self._floats()
        return harvey_shack_tis(theta_i, v["b0"], v["L"], v["S"])
