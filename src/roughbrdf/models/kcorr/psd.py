"""The ABC (K-correlation) PSD and its metrology: rms roughness, correlation length, slope.

Normalization (NIST SCATMECH ``ABC_PSD_Function``, ``docs/psd.htm``; its
``Gaussian_PSD_Function`` fixes the convention, ``A = pi sigma^2 l^2``): ``S_2(f_x, f_y)`` is
the **two-dimensional** (areal) PSD of the height, in µm⁴, of the spatial frequency ``f`` in
cycles per µm (not radians per µm), with

.. math::

    \\sigma^2 = \\iint S_2\\,df_x\\,df_y = 2\\pi\\int_0^\\infty S_2(f)\\,f\\,df,\\qquad
    S_2(f) = \\frac{A}{(1 + (Bf)^2)^{C/2}}.

Closed forms (``u = 1 + (B f)^2``; Church & Takacs, *Proc. SPIE* 1530 (1991); Dittman,
*Proc. SPIE* 6291 (2006)):

* band ``[f1, f2]``: ``sigma^2 = (pi A / B^2) int_{u1}^{u2} u^(-C/2) du``; the total (``f1 = 0,
  f2 = inf``) converges for ``C > 2``: ``sigma^2 = 2 pi A / (B^2 (C - 2))``;
* rms slope: ``m^2 = iint (2 pi f)^2 S_2 = (4 pi^3 A / B^4) int (u - 1) u^(-C/2) du``; the
  total converges for ``C > 4``: ``m^2 = 16 pi^3 A / (B^4 (C - 2)(C - 4))``;
* correlation length ``l = B / (2 pi)``: for ``C = 3`` the PSD is the transform of the
  exponential autocovariance ``sigma^2 exp(-r/l)`` (``A = 2 pi sigma^2 l^2``); for any
  ``C > 2`` that of the Matérn (K-correlation) one ``sigma^2 2^(1-v)/Gamma(v) (r/l)^v K_v(r/l)``,
  ``v = C/2 - 1``.

1-D vs 2-D: a profilometer's **1-D** PSD of the same isotropic surface is
``S_1(f) = int S_2(sqrt(f^2 + f_y^2)) df_y``, an ABC form with ``C_1 = C - 1`` and
``A_1 = A sqrt(pi) Gamma((C-1)/2) / (B Gamma(C/2))`` (µm³): :func:`abc_1d_from_2d` and its
inverse. Church's papers often quote the 1-D form; SCATMECH and this model use the 2-D one.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike
from scipy import special

from ...errors import ArgumentError

__all__ = ["abc_psd", "abc_from_metrology", "abc_1d_from_2d", "abc_2d_from_1d",
           "correlation_length", "rms_slope", "sigma_rms", "spatial_frequency"]


def _positive(name: str, v: float) -> float:
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise ArgumentError(name, "must be a number", value=v) from None
    if not (math.isfinite(x) and x > 0):
        raise ArgumentError(name, "must be finite and > 0", value=v)
    return x


def _abc(a: float, b: float, c: float) -> tuple[float, float, float]:
    a, b = _positive("A", a), _positive("B", b)
    try:
        cf = float(c)
    except (TypeError, ValueError):
        raise ArgumentError("C", "must be a number", value=c) from None
    if not (math.isfinite(cf) and cf >= 0):
        raise ArgumentError("C", "must be finite and >= 0", value=c)
    return a, b, cf


def _band(f_min: float, f_max: float) -> tuple[float, float]:
    lo = float(f_min)
    hi = float(f_max)
    if not (math.isfinite(lo) and lo >= 0):
        raise ArgumentError("f_min", "must be finite and >= 0 (cycles/µm)", value=f_min)
    if not (hi > lo) or math.isnan(hi):
        raise ArgumentError("f_max", f"must be > f_min = {lo:g} (cycles/µm; inf allowed)",
                            value=f_max)
    return lo, hi


def _power_integral(e: float, lu1: float, lu2: float) -> float:
    """``int_{u1}^{u2} u^(e - 1) du`` from ``ln u1``, ``ln u2`` (``u2 = inf``: ``lu2 = inf``),
    without cancellation: ``(u2^e - u1^e)/e`` as expm1, ``ln(u2/u1)`` at ``e = 0``."""
    if math.isinf(lu2):
        return math.inf if e >= 0 else -math.exp(e * lu1) / e
    if abs(e) < 1e-12:  # the e -> 0 limit (C = 2 for sigma, C = 4 for the slope), to 1e-12
        return lu2 - lu1
    return math.exp(e * lu1) * math.expm1(e * (lu2 - lu1)) / e


def sigma_rms(a: float, b: float, c: float, f_min: float = 0.0, f_max: float = math.inf
              ) -> float:
    """RMS roughness (µm) of the ABC PSD over the band ``f_min <= f <= f_max`` (cycles/µm).

    ``sigma^2 = 2 pi int S_2(f) f df`` (module notes); the band is what a measurement covers
    (:func:`spatial_frequency` of its geometries); ``f_max = inf`` and ``f_min = 0`` (the
    defaults) give the total, finite only for ``C > 2``.

    Raises
    ------
    roughbrdf.errors.ArgumentError
        Naming ``C`` when the total is asked for ``C <= 2`` (the integral diverges), or the bad
        argument.

    Examples
    --------
    >>> from roughbrdf.models.kcorr import sigma_rms
    >>> two_pi = 2 * 3.141592653589793
    >>> round(sigma_rms(two_pi * 1e-6, two_pi, 3.0), 9)   # A = 2 pi s^2 l^2, B = 2 pi l, C = 3
    0.001
    """
    a, b, c = _abc(a, b, c)
    lo, hi = _band(f_min, f_max)
    if math.isinf(hi) and c <= 2:
        raise ArgumentError("C", "the total rms roughness diverges for C <= 2: give the band "
                            "of spatial frequencies (f_max) the measurement covers", value=c)
    lu1 = math.log1p((b * lo) ** 2)
    lu2 = math.log1p((b * hi) ** 2) if math.isfinite(hi) else math.inf
    s2 = math.pi * a / (b * b) * _power_integral(1.0 - 0.5 * c, lu1, lu2)
    return math.sqrt(max(s2, 0.0))  # max: a rounding of a band of zero width


def rms_slope(a: float, b: float, c: float, f_min: float = 0.0, f_max: float = math.inf
              ) -> float:
    """RMS surface slope (rad, dimensionless) over a band, ``m^2 = iint (2 pi f)^2 S_2``.

    The total converges for ``C > 4`` (module notes); otherwise give ``f_max``.

    Examples
    --------
    >>> from roughbrdf.models.kcorr import rms_slope
    >>> a, b, c = 1e-4, 2.0, 5.0
    >>> round(rms_slope(a, b, c) ** 2 / (16 * 3.141592653589793**3 * a / (b**4 * 3 * 1)), 12)
    1.0
    """
    a, b, c = _abc(a, b, c)
    lo, hi = _band(f_min, f_max)
    if math.isinf(hi) and c <= 4:
        raise ArgumentError("C", "the total rms slope diverges for C <= 4: give the band of "
                            "spatial frequencies (f_max) the measurement covers", value=c)
    lu1 = math.log1p((b * lo) ** 2)
    lu2 = math.log1p((b * hi) ** 2) if math.isfinite(hi) else math.inf
    # int (u - 1) u^(-C/2) du = int u^(1 - C/2) - int u^(-C/2)
    i = _power_integral(2.0 - 0.5 * c, lu1, lu2) - _power_integral(1.0 - 0.5 * c, lu1, lu2)
    return math.sqrt(max(4.0 * math.pi**3 * a / b**4 * i, 0.0))


def correlation_length(b: float) -> float:
    """Correlation length ``l = B / (2 pi)`` (µm) of the K-correlation PSD (module notes)."""
    return _positive("B", b) / (2.0 * math.pi)


def abc_from_metrology(sigma: float, length: float, c: float) -> tuple[float, float, float]:
    """``(A, B, C)`` of the PSD with total rms roughness ``sigma`` (µm), correlation length
    ``length`` (µm) and exponent ``C > 2``: ``B = 2 pi l``, ``A = sigma^2 B^2 (C - 2)/(2 pi)``.

    Examples
    --------
    >>> from roughbrdf.models.kcorr import abc_from_metrology, sigma_rms
    >>> a, b, c = abc_from_metrology(0.002, 1.5, 2.6)
    >>> round(sigma_rms(a, b, c), 12), round(b / (2 * 3.141592653589793), 12)
    (0.002, 1.5)
    """
    s = _positive("sigma", sigma)
    ell = _positive("length", length)
    cf = float(c)
    if not (math.isfinite(cf) and cf > 2):
        raise ArgumentError("C", "must be > 2 for a finite total rms roughness", value=c)
    b = 2.0 * math.pi * ell
    return s * s * b * b * (cf - 2.0) / (2.0 * math.pi), b, cf


def abc_1d_from_2d(a: float, b: float, c: float) -> tuple[float, float, float]:
    """The 1-D (profile) ABC PSD ``(A_1 [µm³], B, C - 1)`` of the isotropic 2-D one (C > 1)."""
    a, b, c = _abc(a, b, c)
    if c <= 1:
        raise ArgumentError("C", "the profile PSD of a 2-D ABC PSD exists for C > 1", value=c)
    ratio = math.exp(special.gammaln(0.5 * (c - 1.0)) - special.gammaln(0.5 * c))
    return a * math.sqrt(math.pi) * ratio / b, b, c - 1.0


def abc_2d_from_1d(a1: float, b: float, c1: float) -> tuple[float, float, float]:
    """The isotropic 2-D ABC PSD ``(A [µm⁴], B, C_1 + 1)`` whose profile PSD is
    ``A_1 / (1 + (B f)^2)^(C_1/2)`` (the inverse of :func:`abc_1d_from_2d`, ``C_1 > 0``)."""
    a1, b, c1 = _abc(a1, b, c1)
    if c1 <= 0:
        raise ArgumentError("C", "must be > 0 for a 1-D PSD", value=c1)
    c = c1 + 1.0
    ratio = math.exp(special.gammaln(0.5 * (c - 1.0)) - special.gammaln(0.5 * c))
    return a1 * b / (math.sqrt(math.pi) * ratio), b, c


def abc_psd(f: ArrayLike, a: float, b: float, c: float) -> np.ndarray:
    """The 2-D ABC PSD ``A / (1 + (B f)^2)^(C/2)`` (µm⁴) at ``f`` (cycles/µm, >= 0).

    Examples
    --------
    >>> from roughbrdf.models.kcorr import abc_psd
    >>> float(abc_psd(0.0, 1e-3, 10.0, 3.0))
    0.001
    """
    a, b, c = _abc(a, b, c)
    fa = np.asarray(f, dtype=np.float64)
    bad = ~(fa >= 0) | np.isinf(fa)
    if bad.any():
        raise ArgumentError("f", "spatial frequencies must be finite and >= 0",
                            value=fa[bad].flat[0])
    return a * np.exp(-0.5 * c * np.log1p((b * fa) ** 2))


def spatial_frequency(theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike,
                      wavelength: float) -> np.ndarray:
    """The Bragg frequency ``f = |beta - beta_0| / lambda`` (cycles/µm) of each geometry.

    ``beta = sin theta_r (cos phi, sin phi)``, ``beta_0 = (sin theta_i, 0)`` (radians, the
    library's frame, ``phi = 0`` specular); ``wavelength`` in µm. The band a measurement covers
    is the range of ``f`` over its samples: give it to :func:`sigma_rms`.

    Examples
    --------
    >>> from roughbrdf.models.kcorr import spatial_frequency
    >>> round(float(spatial_frequency(0.0, 0.5235987755982988, 0.0, 0.5)), 12)  # sin 30°/0.5
    1.0
    """
    lam = _positive("wavelength", wavelength)
    ti, tr, ph = (np.asarray(x, dtype=np.float64) for x in (theta_i, theta_r, phi))
    fx = np.sin(tr) * np.cos(ph) - np.sin(ti)
    fy = np.sin(tr) * np.sin(ph)
    return np.hypot(fx, fy) / lam
