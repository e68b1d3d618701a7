"""Diffuse parts: Oren-Nayar's rough-diffuse factor and diffuse light seen through a coating.

Two compiled scalar parts, each used by every model that needs it (``docs/models.md`` §10):

* :func:`oren_nayar_factor` -- the factor ``A + B max(0, cos(phi_r - phi_i)) sin(alpha)
  tan(beta)`` of Oren & Nayar's qualitative model (1994, Eq. 30) that multiplies ``rho/pi``;
* :func:`coated_diffuse` -- a diffuse substrate of albedo ``rho`` under a smooth dielectric
  interface of index ``n``: Fresnel transmission into the coating at incidence and out of it
  at exit, the ``1/n^2`` of radiance crossing the interface, and the internal reflections
  between substrate and interface summed as a geometric series (Weidlich & Wilkie 2007, §3;
  the form of Mitsuba 3's ``roughplastic`` with ``nonlinear=true``, ``docs/models.md`` §10.3).

Conventions: the library's frame (``docs/models.md`` §1.1): ``phi = 0`` is the forward
(specular) side, the source lies at ``phi = pi``, so Oren-Nayar's ``cos(phi_r - phi_i)`` is
``-cos(phi)``. ``gamma`` is TR75's polarization angle (NaN: unpolarized).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from ._kernels import as_float_array, jit, ufunc
from .fresnel import fresnel_polarized_cs, fresnel_sp
from .geometry import check_angles

__all__ = ["oren_nayar_factor", "coated_diffuse", "oren_nayar"]


@jit(inline=True)
def oren_nayar_factor(ci, cr, si, sr, cos_phi, sigma2):
    """Oren & Nayar (1994) Eq. 30: ``A + B max(0, cos(phi_r - phi_i)) sin(alpha) tan(beta)``.

    ``alpha = max(theta_i, theta_r)``, ``beta = min(theta_i, theta_r)``,
    ``A = 1 - sigma^2/(2 (sigma^2 + 0.33))``, ``B = 0.45 sigma^2/(sigma^2 + 0.09)``, ``sigma``
    the standard deviation of the facet slope angle (radians). Written with cosines only:
    ``sin(alpha) tan(beta) = sin(theta_i) sin(theta_r)/max(cos theta_i, cos theta_r)``
    (the larger cosine belongs to the smaller angle ``beta``).
    """
    a = 1.0 - 0.5 * sigma2 / (sigma2 + 0.33)
    b = 0.45 * sigma2 / (sigma2 + 0.09)
    c = -cos_phi  # cos(phi_r - phi_i): the source lies at phi = pi in the library's frame
    c = c if c > 0.0 else 0.0
    m = ci if ci > cr else cr
    # m = 0 only with both directions grazing (not in the domain of the models that use this,
    # theta_i < pi/2); the stand-in 1 keeps compiled code, which runs both sides, free of 0/0
    t = si * sr / (m if m > 0.0 else 1.0)
    return a + b * c * t


@jit(inline=True)
def coated_diffuse(ci, cr, n, gamma, rho, fdr_int):
    """Diffuse substrate under a smooth dielectric interface, BRDF in sr⁻¹ (Weidlich & Wilkie).

    ``rho/pi (1 - R(theta_i; gamma)) (1 - R(theta_r)) / (n^2 (1 - rho F_dr,int))`` with ``R``
    the Fresnel reflectance of the interface (index ``n``, ``k = 0``) at the macroscopic
    angles: at incidence for the incident polarization ``gamma`` (the macroscopic planes of
    incidence coincide, ``eta = 0``), at exit unpolarized (an unpolarized detector);
    ``fdr_int`` is the interface's internal diffuse reflectance
    (:func:`roughbrdf.fresnel.diffuse_reflectance`). For ``rho = 1`` the albedo is exactly
    ``1 - R(theta_i)``: all transmitted light comes back out.
    """
    t_in = 1.0 - fresnel_polarized_cs(ci, n, 0.0, gamma, 1.0, 0.0)
    rs, rp = fresnel_sp(cr, n, 0.0)
    t_out = 1.0 - 0.5 * (rs + rp)
    return rho / math.pi * t_in * t_out / (n * n * (1.0 - rho * fdr_int))


@ufunc(4)
def _oren_nayar(ti, tr, phi, sigma2):
    si, ci = math.sin(ti), math.cos(ti)
    sr, cr = math.sin(tr), math.cos(tr)
    return oren_nayar_factor(ci, cr, si, sr, math.cos(phi), sigma2)


def oren_nayar(theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike,
               sigma: float) -> np.ndarray:
    """Oren-Nayar factor (Eq. 30) that multiplies ``rho/pi``; angles in radians.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> float(rb.diffuse.oren_nayar(0.3, 0.2, 1.0, 0.0))      # sigma = 0: Lambertian
    1.0
    >>> # retro direction, sigma = 0.5: A + B sin(0.5) tan(0.5) = 0.78448 + 0.33088 * 0.26191
    >>> round(float(rb.diffuse.oren_nayar(0.5, 0.5, 3.141592653589793, 0.5)), 4)
    0.8711
    """
    s = float(as_float_array(sigma, "sigma"))
    if not (math.isfinite(s) and s >= 0.0):
        raise ValueError(f"sigma must be finite and >= 0 (radians), got {sigma!r}")
    ti, tr, ph = check_angles(theta_i, theta_r, phi, grazing_incidence=False)
    return _oren_nayar(ti, tr, ph, s * s)
