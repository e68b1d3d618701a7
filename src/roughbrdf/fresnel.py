"""Complex-index Fresnel reflectance: s, p, unpolarized and a linear polarization angle.

Conventions
-----------
* Complex index ``n + i k`` with ``k >= 0`` absorbing (TS67 and TR75 write ``n - i k``; the
  reflectances are identical, the two indices being complex conjugates; docs/models.md §1.4).
* ``n`` is the index of the reflecting medium relative to the incident one; ``n < 1`` is allowed
  (total internal reflection beyond the critical angle when ``k = 0``).
* Polarization ``gamma`` (TR75 Eq. 24): angle of the incident electric field from the
  macroscopic plane of incidence; ``gamma = 0`` is p (parallel), ``gamma = pi/2`` is s
  (perpendicular); NaN means unpolarized. ``eta`` is the angle from the macroscopic to the local
  plane of incidence (:func:`roughbrdf.geometry.tr75_eta`).

The scalar part :func:`fresnel_sp` evaluates, for ``c = cos t``,

.. math::

    q = \\sqrt{(n + ik)^2 - (1 - c^2)},\\quad
    R_s = \\left|\\frac{c - q}{c + q}\\right|^2,\\quad
    R_p = \\left|\\frac{(n+ik)^2 c - q}{(n+ik)^2 c + q}\\right|^2

in real arithmetic (principal branch, ``Re q >= 0``), which Numba vectorizes, unlike complex
``sqrt``. TR75 Eqs. 20-22 are an independent real-arithmetic form of the same reflectances and
serve as the test oracle.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numpy.typing import ArrayLike

from ._kernels import TINY, as_float_array, jit, sincos, ufunc

__all__ = ["fresnel_sp", "fresnel_amplitudes", "fresnel_polarized", "fresnel_polarized_cs",
           "fresnel_polarized_xy", "reflectance", "diffuse_reflectance",
           "polarization_angle", "check_index", "index_from_reflectance"]


@jit(inline=True, contract=False)  # plain rounding: see roughbrdf._kernels.compile.jit
def _index_q(c, n, k):
    """``(a, b, re, im)``: ``q = a + i b = sqrt((n + ik)^2 - (1 - c^2))`` (principal branch,
    ``a >= 0``) and ``(n + ik)^2 = re + i im``; the common part of :func:`fresnel_sp` and
    :func:`fresnel_amplitudes`."""
    s2 = 1.0 - c * c
    re = n * n - k * k  # Re (n + ik)^2
    im = 2.0 * n * k  # Im (n + ik)^2
    zr = re - s2
    mod = math.sqrt(zr * zr + im * im)
    # principal square root q = a + ib of z = zr + i im, computed without cancellation: the
    # larger component is t = sqrt((|z| + |zr|)/2), the other one im/(2 t). Written with
    # selects (no branches), and every denominator that can be 0 gets + TINY: compiled code
    # evaluates both sides of a select (LLVM also turns x/(d if d > 0 else 1) into one), and a
    # 0/0 there would show up as a NumPy RuntimeWarning in the ufuncs. TINY = 1e-300 changes
    # no result: it is below the last bit of every non-zero denominator.
    t = math.sqrt(0.5 * (mod + abs(zr)))
    u = 0.5 * im / (t + TINY)  # t = 0 only if z = 0, and then im = 0: u = 0
    a = t if zr >= 0.0 else u
    b = u if zr >= 0.0 else t
    return a, b, re, im


@jit(inline=True, contract=False)  # plain rounding: see roughbrdf._kernels.compile.jit
def fresnel_sp(c, n, k):
    """Scalar part: ``(R_s, R_p)`` at ``cos t = c`` for index ``n + i k`` (docs/models.md §1.4)."""
    a, b, re, im = _index_q(c, n, k)
    # den = 0 only for n + ik = 1 at exactly grazing incidence (z = 0, c = 0): index matched,
    # no interface; the limit along c -> 0 is R = 0, which the guarded quotients give.
    den = (c + a) * (c + a) + b * b
    pr = re * c
    pi_ = im * c
    denp = (pr + a) * (pr + a) + (pi_ + b) * (pi_ + b)
    inv = 1.0 / (den * denp + TINY)  # one division for both quotients
    rs = ((c - a) * (c - a) + b * b) * denp * inv
    rp = ((pr - a) * (pr - a) + (pi_ - b) * (pi_ - b)) * den * inv
    return rs, rp


@jit(inline=True, contract=False)  # plain rounding, as fresnel_sp
def fresnel_amplitudes(c, n, k):
    """Scalar part: complex amplitudes ``(Re r_s, Im r_s, Re r_p, Im r_p)`` at ``cos t = c``.

    ``r_s = (c - q)/(c + q)``, ``r_p = ((n + ik)^2 c - q)/((n + ik)^2 c + q)`` with ``q`` of
    :func:`fresnel_sp` (time dependence ``exp(-i omega t)``, ``k >= 0``), so that
    ``|r_s|^2 = R_s`` and ``|r_p|^2 = R_p`` to round-off. **Sign of r_p**: the reflected field
    is referred to ``p_r = k_r × s`` and the incident one to ``p_i = k_i × s`` (``s`` the
    common perpendicular, ``k`` the directions of propagation), SCATMECH's convention: a
    perfect conductor has ``r_s = -1``, ``r_p = +1``, and at normal incidence
    ``r_p = -r_s = (n + ik - 1)/(n + ik + 1)``. Other texts (Hecht, the "Verdet" form) flip
    ``r_p``; the Mueller matrices of :mod:`roughbrdf.mueller` need this one.

    Examples
    --------
    >>> from roughbrdf.fresnel import fresnel_amplitudes
    >>> [round(x, 6) for x in fresnel_amplitudes(1.0, 1.5, 0.0)]   # r_p = -r_s = 0.2
    [-0.2, -0.0, 0.2, 0.0]
    """
    a, b, re, im = _index_q(c, n, k)
    den = (c + a) * (c + a) + b * b  # |c + q|^2
    pr = re * c
    pi_ = im * c
    denp = (pr + a) * (pr + a) + (pi_ + b) * (pi_ + b)  # |P + q|^2, P = (n + ik)^2 c
    # den = 0 (or denp = 0) only for n + ik = 1 at exactly grazing incidence, where the
    # numerators vanish too: + TINY gives the limit 0 (as in fresnel_sp)
    inv = 1.0 / (den * denp + TINY)
    # (c - q)(c + q)* = (c - a)(c + a) - b^2 - 2i b c; (c - a) first: no cancellation near r = 0
    rs_re = ((c - a) * (c + a) - b * b) * denp * inv
    rs_im = -2.0 * b * c * denp * inv
    # (P - q)(P + q)* = (Pr - a)(Pr + a) + (Pi - b)(Pi + b) + 2i (a Pi - b Pr)
    rp_re = ((pr - a) * (pr + a) + (pi_ - b) * (pi_ + b)) * den * inv
    rp_im = 2.0 * (a * pi_ - b * pr) * den * inv
    return rs_re, rs_im, rp_re, rp_im


@jit(inline=True)
def fresnel_polarized_xy(c, n, k, gamma, x, y):
    """TR75 Eq. 24 with ``eta`` given by any vector ``(x, y)`` along ``(cos eta, sin eta)``.

    ``sin^2(gamma - eta) = (sin(gamma) x - cos(gamma) y)^2/(x^2 + y^2)``: no square root and
    no normalization (:func:`roughbrdf.geometry.tr75_eta_xy` gives ``sin(s) (cos eta,
    sin eta)``). Where ``(x, y)`` vanishes (s = 0, R_s = R_p) the result is R_p = R_s.
    """
    rs, rp = fresnel_sp(c, n, k)
    unpolarized = gamma != gamma  # NaN encodes "unpolarized"
    sg, cg = sincos(0.0 if unpolarized else gamma)  # no arithmetic on the NaN (ufunc warnings)
    d = sg * x - cg * y
    sn2 = d * d / (x * x + y * y + TINY)
    pol = rs * sn2 + rp * (1.0 - sn2)
    return 0.5 * (rs + rp) if unpolarized else pol


@jit(inline=True)
def fresnel_polarized_cs(c, n, k, gamma, cos_eta, sin_eta):
    """Scalar part of TR75 Eq. 24 with ``eta`` given as ``(cos eta, sin eta)``.

    ``R = R_s sin^2(gamma - eta) + R_p cos^2(gamma - eta)``; ``gamma`` NaN -> ``(R_s + R_p)/2``.
    Branch-free and without libm calls, so model loops that use it vectorize (the
    ``(cos eta, sin eta)`` pair comes from :func:`roughbrdf.geometry.tr75_eta_cs`).
    """
    rs, rp = fresnel_sp(c, n, k)
    unpolarized = gamma != gamma  # NaN encodes "unpolarized"
    # no arithmetic on the NaN: it would raise NumPy's "invalid value" warning in ufuncs
    sg, cg = sincos(0.0 if unpolarized else gamma)
    sn = sg * cos_eta - cg * sin_eta  # sin(gamma - eta)
    pol = rs * sn * sn + rp * (1.0 - sn * sn)
    return 0.5 * (rs + rp) if unpolarized else pol


@jit(inline=True)
def fresnel_polarized(c, n, k, gamma, eta):
    """Scalar part of TR75 Eq. 24: reflectance for incident polarization angle ``gamma``.

    ``R = R_s sin^2(gamma - eta) + R_p cos^2(gamma - eta)``; ``gamma`` NaN -> ``(R_s + R_p)/2``.
    """
    se, ce = sincos(eta)
    return fresnel_polarized_cs(c, n, k, gamma, ce, se)


@ufunc(5)
def _reflectance(c, n, k, gamma, eta):
    return fresnel_polarized(c, n, k, gamma, eta)


def polarization_angle(polarization: str | float | None) -> float:
    """Map a polarization argument to TR75's ``gamma`` (radians; NaN = unpolarized).

    Accepts ``None``/``"unpolarized"``/``"natural"``/``"circular"``, ``"s"``/``"perpendicular"``
    (gamma = pi/2), ``"p"``/``"parallel"`` (gamma = 0), or a number (gamma itself).
    """
    if polarization is None:
        return math.nan
    if isinstance(polarization, str):
        key = polarization.strip().lower()
        table = {"unpolarized": math.nan, "natural": math.nan, "circular": math.nan,
                 "s": 0.5 * math.pi, "perpendicular": 0.5 * math.pi, "te": 0.5 * math.pi,
                 "p": 0.0, "parallel": 0.0, "tm": 0.0}
        if key not in table:
            raise ValueError(
                f"polarization must be 'unpolarized', 's', 'p' or an angle in radians, "
                f"got {polarization!r}"
            )
        return table[key]
    g = float(polarization)
    if not math.isfinite(g):
        raise ValueError(f"polarization angle gamma must be finite, got {polarization!r}")
    return g


def check_index(n: float, k: float) -> None:
    """Raise ``ValueError`` for a non-physical complex index ``n + i k``."""
    if not (math.isfinite(n) and n > 0):
        raise ValueError(f"refractive index n must be finite and > 0, got {n!r}")
    if not (math.isfinite(k) and k >= 0):
        raise ValueError(
            f"extinction index k must be finite and >= 0 (n + ik, absorbing), got {k!r}")


#: the largest normal reflectance :func:`index_from_reflectance` maps: ``r = 1`` (a perfect
#: mirror) has an infinite index (g < 1) or n = 0 (g = 1); at ``1 - 1e-6`` the normal
#: reflectance is within 1e-6 of 1 and the index stays finite and positive (n about 4e6 at
#: g = 0, 5e-7 at g = 1)
R_MAX = 1.0 - 1e-6


def index_from_reflectance(r: float, g: float) -> tuple[float, float]:
    """The complex index ``n + i k`` of a conductor of normal reflectance ``r`` and edge tint
    ``g`` (Gulbrandsen 2014, "Artist Friendly Metallic Fresnel", JCGT 3(4), Eqs. 2-3).

    ``n = g (1 - r)/(1 + r) + (1 - g)(1 + sqrt r)/(1 - sqrt r)`` and
    ``k = sqrt((r (n + 1)^2 - (n - 1)^2)/(1 - r))``: every ``(r, g)`` in ``[0, 1]^2`` gives a
    physical index (``n > 0``, ``k >= 0``) whose :func:`fresnel_sp` reflectance at normal
    incidence is exactly ``r``; ``g`` sets how the reflectance rises toward grazing (``g = 1``:
    the smallest ``n`` of that ``r``, ``g = 0``: the largest, ``k = 0``). The index is relative
    to the medium the conductor is in. ``r`` above :data:`R_MAX` is taken as :data:`R_MAX`.

    Examples
    --------
    >>> n, k = index_from_reflectance(0.95, 0.5)
    >>> round(float(fresnel_sp(1.0, n, k)[0]), 12)        # the normal reflectance is r
    0.95
    >>> [round(v, 9) for v in index_from_reflectance(0.04, 0.0)]   # g = 0: glass, n = 1.5
    [1.5, 0.0]
    """
    if not (0.0 <= r <= 1.0 and 0.0 <= g <= 1.0):
        raise ValueError(f"normal reflectance r and edge tint g must be in [0, 1], got "
                         f"r={r!r}, g={g!r}")
    r = min(r, R_MAX)
    sr = math.sqrt(r)
    n = g * (1.0 - r) / (1.0 + r) + (1.0 - g) * (1.0 + sr) / (1.0 - sr)
    # the radicand is >= 0 for n between the two bounds; rounding can make it -1e-16 at g = 0
    k = math.sqrt(max(0.0, (r * (n + 1.0) ** 2 - (n - 1.0) ** 2) / (1.0 - r)))
    return n, k


def reflectance(
    cos_theta: ArrayLike,
    n: ArrayLike,
    k: ArrayLike = 0.0,
    polarization: str | float | None = "unpolarized",
    eta: ArrayLike = 0.0,
) -> np.ndarray:
    """Fresnel reflectance of a smooth interface with complex index ``n + i k``.

    Parameters
    ----------
    cos_theta : array_like
        Cosine of the local angle of incidence, in [0, 1].
    n, k : array_like
        Real and imaginary parts of the index (``k >= 0`` absorbing; ``n > 0``; ``n < 1`` allowed).
    polarization : {"unpolarized", "s", "p"} or float
        Incident polarization; a float is TR75's angle ``gamma`` (radians) of the electric field
        from the macroscopic plane of incidence (Eq. 24), combined with ``eta``.
    eta : array_like
        TR75's angle from the macroscopic to the local plane of incidence (0 when they coincide).

    Returns
    -------
    numpy.ndarray
        Reflectance in [0, 1], broadcast over the inputs.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> round(float(rb.fresnel.reflectance(1.0, 1.5)), 6)   # ((n-1)/(n+1))^2, TR75 Eq. 22
    0.04
    >>> float(rb.fresnel.reflectance(0.0, 1.5, 0.0, "p"))   # grazing incidence
    1.0
    """
    c = as_float_array(cos_theta, "cos_theta")
    bad = ~np.isfinite(c) | (c < 0) | (c > 1)
    if bad.any():
        raise ValueError(f"cos_theta must be in [0, 1], got {c[bad].flat[0]!r}")
    na = as_float_array(n, "n")
    ka = as_float_array(k, "k")
    if np.any(~np.isfinite(na) | (na <= 0)):
        bad = na[~(np.isfinite(na) & (na > 0))].flat[0]
        raise ValueError(f"refractive index n must be finite and > 0, got {bad!r}")
    if np.any(~np.isfinite(ka) | (ka < 0)):
        bad = ka[~(np.isfinite(ka) & (ka >= 0))].flat[0]
        raise ValueError(f"extinction index k must be finite and >= 0, got {bad!r}")
    g = polarization_angle(polarization)
    return _reflectance(c, na, ka, g, as_float_array(eta, "eta"))



#: Gauss-Legendre rule on [0, 1] in ``mu = cos theta`` for :func:`diffuse_reflectance`: the
#: integrand ``R(mu) mu`` is smooth on [0, 1] for ``k = 0`` (no kink: the critical angle of
#: internal reflection is handled by the identity below, not by quadrature); 64 points give it
#: to 1e-12 (checked against 4096 points in tests/models/test_coated.py)
_GL_POINTS = 64


def diffuse_reflectance(n: float, k: float = 0.0, *, internal: bool = False) -> float:
    """Hemispherical-average Fresnel reflectance ``F_dr`` of a smooth interface (diffuse light).

    ``F_dr = 2 int_0^1 R(mu) mu dmu`` (the reflectance for light incident equally from every
    direction of the hemisphere: Lambertian illumination), docs/models.md §10.1. With
    ``internal=True``, the light comes from inside a dielectric of index ``n`` (``k = 0``):
    by the reciprocity of the interface (Stokes relations) ``1 - F_dr,int = (1 - F_dr)/n^2``,
    which includes total internal reflection beyond the critical angle exactly.

    Parameters
    ----------
    n, k : float
        Index ``n + i k`` of the medium beyond the interface (``k >= 0``; ``internal`` needs
        ``k = 0`` and ``n > 0``).
    internal : bool
        Light incident from inside the medium.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> round(rb.fresnel.diffuse_reflectance(1.5), 4)          # external, n = 1.5
    0.0918
    >>> round(rb.fresnel.diffuse_reflectance(1.5, internal=True), 4)
    0.5964
    """
    check_index(n, k)
    if internal and k != 0.0:
        raise ValueError(f"internal diffuse reflectance needs a dielectric (k = 0), got k={k!r}")
    if k == 0.0 and n < 1.0:
        # a dielectric of n < 1 is the inside of one of 1/n: its R(mu) has a kink at the
        # critical angle, which the Gauss-Legendre rule misses (2.8e-3 low at n = 0.8); the
        # reciprocity identity of the docstring, read backwards, is exact
        external = 1.0 - n * n * (1.0 - _external_diffuse_reflectance(1.0 / n, 0.0))
    else:
        external = _external_diffuse_reflectance(float(n), float(k))
    return 1.0 - (1.0 - external) / (n * n) if internal else external


@functools.lru_cache(maxsize=1)
def _gauss_legendre() -> tuple[np.ndarray, np.ndarray]:
    """Nodes ``mu`` on [0, 1] and weights ``w mu`` of :data:`_GL_POINTS`-point Gauss-Legendre."""
    x, w = np.polynomial.legendre.leggauss(_GL_POINTS)
    mu = 0.5 * (x + 1.0)
    return mu, w * mu  # 2 * (1/2 from the interval) * w: the factor 2 of F_dr cancels


@functools.lru_cache(maxsize=4096)  # a fit asks for the same index many times (Jacobians)
def _external_diffuse_reflectance(n: float, k: float) -> float:
    mu, wmu = _gauss_legendre()
    return float(np.dot(wmu, _reflectance(mu, n, k, math.nan, 0.0)))
