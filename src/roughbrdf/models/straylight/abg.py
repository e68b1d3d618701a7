"""The ABg scatter model of the optical codes (Zemax OpticStudio, FRED): ``A / (B + |β - β0|^g)``.

Definition pinned from Zemax OpticStudio's help ("Available Scatter Models", ABg Model
Scattering; "Scatter Models" for ``β``, ``β0``) and FRED's help ("Scatter Types > ABg"): the BSDF
in sr⁻¹ is a function of ``|β - β0|`` only (linear shift invariance), ``β`` and ``β0`` the
projections onto the mean surface of the unit vectors of the scattered and the specular
directions. In roughbrdf's frame (``docs/models.md`` §1.1): ``β = sin(theta_r) (cos phi,
sin phi)``, ``β0 = (sin(theta_i), 0)``, so::

    |β - β0|² = (sin theta_r - sin theta_i)² + 4 sin theta_r sin theta_i sin²(phi/2)

(cancellation-free near the specular direction). ``docs/straylight.md`` §ABg.
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange
from numpy.typing import ArrayLike

from ..._kernels import at, driver, jit, sincos
from ..base import Model, PreparedGeometry, register
from ..parameters import Parameter, nonnegative
from .tis import abg_bsdf, abg_tis, check_abg

__all__ = ["ABg", "beta_distance"]


@jit(inline=True)
def beta_distance(ti, tr, phi):
    """``|β - β0|`` for the library's angles (radians), cancellation-free at the specular.

    Examples
    --------
    >>> import math
    >>> round(beta_distance(0.3, 0.3, math.pi), 12) == round(2 * math.sin(0.3), 12)
    True
    """
    si = sincos(ti)[0]
    sr = sincos(tr)[0]
    h = sincos(0.5 * phi)[0]
    u = sr - si
    return math.sqrt(u * u + 4.0 * sr * si * h * h)


@jit(inline=True)
def _abg_point(ti, tr, phi, gamma, p, flag):
    f = abg_bsdf(beta_distance(ti, tr, phi), p[0], p[1], p[2])
    if flag:
        cr = sincos(tr)[1]
        # cos(pi/2) rounds to 6e-17: below 1e-15 it is exactly 0 (theta_r = pi/2 is exactly
        # grazing, as in oren_nayar), so the BSDF * cos is 0 on the horizon, never negative
        return f * (0.0 if cr < 1e-15 else cr)
    return f


@driver
def _abg_drive(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # module-level loop, cached on disk; the quantity flag a literal in each loop
    if flag:
        for i in prange(out.size):
            out[i] = _abg_point(at(a, i), at(b, i), at(c, i), at(g, i), p, 1)
    else:
        for i in prange(out.size):
            out[i] = _abg_point(at(a, i), at(b, i), at(c, i), at(g, i), p, 0)


@register
class ABg(Model):
    """ABg scatter model: ``BSDF = A / (B + |β - β0|^g)`` sr⁻¹ (Zemax OpticStudio, FRED).

    ``brdf`` *is* this BSDF (sr⁻¹); ``bridf`` is ``BSDF cos(theta_r)``. There is no separate
    specular delta: :meth:`tis` is everything the model reflects. Zemax's rules: ``A >= 0``;
    ``B > 1e-12`` unless ``g = 0`` (then ``B >= 0`` and the BSDF is the constant
    ``A/(B + 1)``); ``g`` any real (typically 0 to 3). No wavelength scaling
    (``docs/straylight.md`` §ABg). Reciprocal (``|β - β0|`` is symmetric in the two zenith
    angles); defined at grazing incidence.

    Examples
    --------
    >>> import roughbrdf as rb, roughbrdf.models.straylight
    >>> m = rb.model("abg", A=0.0025, B=0.001, g=1.8)
    >>> round(m.brdf(0.3, 0.3, 0.0), 9)                      # at the specular: A/B
    2.5
    >>> round(rb.model("abg", A=0.5, B=0.25, g=0.0).brdf(0.1, 1.2, 2.0), 12)   # A/(B+1)
    0.4
    """

    name = "abg"
    aliases = ("a-b-g", "zemax-abg")
    short = "abg"
    reference = "Zemax OpticStudio help, ABg Model Scattering; FRED help, Scatter Types > ABg"
    PARAMETERS = (
        nonnegative("A", 0.0025, (0.0, 100.0), "sr^-1",
                    "numerator: A/B is the BSDF at the specular direction"),
        nonnegative("B", 0.001, (1e-10, 10.0), "1",
                    "roll-off: |beta - beta0|^g = B at the knee; > 1e-12 unless g = 0"),
        Parameter("g", 1.8, (0.0, 4.0), "1",
                  "log-log slope of the BSDF far from specular (negative of)"),
    )
    grazing_incidence = True
    _drive = _abg_drive

    def _validate(self) -> None:
        # Zemax's cross-parameter rule: B > 1e-12 unless g = 0 (ArgumentError naming B)
        v = self._floats()  # every parameter is set (none is optional)
        check_abg(v["A"], v["B"], v["g"])

    def _pack(self) -> tuple:
        v = self._floats()
        return (v["A"], v["B"], v["g"])

    def _mueller(self, g: PreparedGeometry, basis: int, term: str | None) -> np.ndarray:
        # an ideal depolarizer times the BSDF in every basis: the model has no polarization
        return self._mueller_depolarizer(g, term)

    def tis(self, theta_i: ArrayLike) -> np.ndarray | float:
        """Total integrated scatter at ``theta_i`` (radians): :func:`~.tis.abg_tis`.

        Examples
        --------
        >>> import math, roughbrdf as rb, roughbrdf.models.straylight
        >>> m = rb.model("abg", A=0.3, B=0.5, g=0.0)
        >>> round(m.tis(0.4) / (math.pi * 0.3 / 1.5), 10)
        1.0
        """
        v = self._floats()
        return abg_tis(theta_i, v["A"], v["B"], v["g"])
