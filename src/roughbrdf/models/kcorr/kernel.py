"""Compiled parts of the K-correlation model: Rayleigh–Rice Jones elements, ABC PSD, drivers.

First-order vector perturbation (Rayleigh–Rice) theory for a single rough interface in the
smooth-surface limit (Rice 1951; Church & Zavada 1975; Stover, *Optical Scattering*, the
Rayleigh–Rice chapter; Germer, *Appl. Opt.* 36, 8798 (1997), cited by SCATMECH for these
elements; NIST SCATMECH ``code/urough.cpp``, ``Microroughness_BRDF_Model::jones``):

.. math::

    f_r = \\frac{16\\pi^2}{\\lambda^4}\\cos\\theta_i\\cos\\theta_r\\,Q\\,S_2(f),\\qquad
    f = |\\boldsymbol\\beta - \\boldsymbol\\beta_0|/\\lambda,

``beta = sin theta_r (cos phi, sin phi)``, ``beta_0 = (sin theta_i, 0)``, ``Q = |J e|^2``
summed over the two reflected polarizations (unpolarized detection), ``e`` the incident Jones
vector and ``J`` the dimensionless Jones matrix below (``epsilon = (n + ik)^2``,
``q_x = sqrt(epsilon - sin^2 theta_x)`` on the principal branch, the time dependence
``exp(-i omega t)``)::

    ss =  (eps - 1) cos phi / ((ci + qi)(cr + qr))
    pp =  (eps - 1)(eps si sr - qr qi cos phi) / ((eps ci + qi)(eps cr + qr))
    ps = -(eps - 1) qi sin phi / ((eps ci + qi)(cr + qr))      # p in -> s out
    sp = -(eps - 1) qr sin phi / ((ci + qi)(eps cr + qr))      # s in -> p out

in the s/p bases of :mod:`roughbrdf.mueller` (SCATMECH's ``psps``), so that the Mueller matrix
is ``(16 pi^2/lambda^4) ci cr S_2 M(J)`` with :func:`roughbrdf.mueller.jones_mueller`.

The parts use complex arithmetic (``cmath.sqrt``, principal branch as C++ ``std::sqrt``, which
SCATMECH uses): the loops do not vectorize, unlike the real-arithmetic Fresnel of
:mod:`roughbrdf.fresnel`, which costs speed only.

Packed parameters ``p = (A, B, C, n, k, wavelength)``: A in µm⁴, B in µm, wavelength in µm.
"""

from __future__ import annotations

import cmath
import math

from numba import prange

from ..._kernels import at, driver, jit, sincos
from ...mueller import XYXY, jones_mueller

#: the BRDF without the PSD factor S_2 (flag of the drivers): what the TIS quadrature needs
WITHOUT_PSD = 2


@jit(inline=True)
def abc_psd_point(f, a, b, c):
    """The 2-D ABC (K-correlation) PSD ``A / (1 + (B f)^2)^(C/2)`` (SCATMECH
    ``ABC_PSD_Function::psd``), ``f`` in µm⁻¹."""
    bf = b * f
    return a * math.exp(-0.5 * c * math.log1p(bf * bf))


@jit(inline=True)
def _safe_div(num, den):
    # den = 0 only for an index-matched interface (epsilon = 1, n + ik = 1) at exactly grazing
    # incidence or view, where num = 0 too (factor epsilon - 1): the limit there is 0
    return num / den if den != 0.0 else 0.0 * num


@jit(inline=True)
def jones_elements(si, ci, sr, cr, cp, sp, n, k):
    """``(ss, ps, sp, pp)`` of the module notes (complex, dimensionless) for the sines and
    cosines of theta_i, theta_r and phi and the index ``n + i k``."""
    eps = complex(n, k) * complex(n, k)
    em1 = eps - 1.0
    qi = cmath.sqrt(eps - si * si)
    qr = cmath.sqrt(eps - sr * sr)
    ds_i = ci + qi  # s denominators
    ds_r = cr + qr
    dp_i = eps * ci + qi  # p denominators
    dp_r = eps * cr + qr
    ss = _safe_div(em1 * cp, ds_i * ds_r)
    pp = _safe_div(em1 * (eps * si * sr - qr * qi * cp), dp_i * dp_r)
    ps = _safe_div(-em1 * qi * sp, dp_i * ds_r)
    sp_ = _safe_div(-em1 * qr * sp, ds_i * dp_r)
    return ss, ps, sp_, pp


@jit(inline=True)
def polarization_factor(si, ci, sr, cr, cp, sp, gamma, n, k):
    """Rayleigh–Rice ``Q`` for TR75's incident polarization angle ``gamma`` (0 = p, pi/2 = s;
    NaN = unpolarized), unpolarized detection: ``|ss e_s + ps e_p|^2 + |sp e_s + pp e_p|^2``
    with ``(e_s, e_p) = (sin gamma, cos gamma)``, or half the sum of the four ``|J|^2``."""
    ss, ps, sp_, pp = jones_elements(si, ci, sr, cr, cp, sp, n, k)
    if gamma != gamma:  # NaN: unpolarized incidence
        return 0.5 * (abs(ss) ** 2 + abs(ps) ** 2 + abs(sp_) ** 2 + abs(pp) ** 2)
    es, ep = sincos(gamma)
    return abs(ss * es + ps * ep) ** 2 + abs(sp_ * es + pp * ep) ** 2


@jit(inline=True)
def _geometry(ti, tr, phi):
    si, ci = sincos(ti)
    sr, cr = sincos(tr)
    sp, cp = sincos(phi)
    # cos can round to -6e-17 at pi/2: the BRDF factor cos theta is >= 0 by definition
    return si, max(ci, 0.0), sr, max(cr, 0.0), cp, sp


@jit(inline=True)
def kcorr_point(ti, tr, phi, gamma, p, flag):
    """The model's scalar kernel: f_r (``flag = 0``), f_r cos theta_r (``flag = 1``), or f_r
    without the PSD factor (``flag = WITHOUT_PSD``)."""
    a, b, c, n, k, lam = p[0], p[1], p[2], p[3], p[4], p[5]
    si, ci, sr, cr, cp, sp = _geometry(ti, tr, phi)
    q = polarization_factor(si, ci, sr, cr, cp, sp, gamma, n, k)
    lam2 = lam * lam
    pre = 16.0 * math.pi * math.pi / (lam2 * lam2) * ci * cr * q
    if flag == WITHOUT_PSD:
        return pre
    fx = sr * cp - si
    fy = sr * sp
    s2 = abc_psd_point(math.sqrt(fx * fx + fy * fy) / lam, a, b, c)
    return pre * s2 * (cr if flag == 1 else 1.0)


@driver
def kcorr_drive(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # module-level loop: cached on disk (roughbrdf._kernels.compile.driver)
    for i in prange(out.size):
        out[i] = kcorr_point(at(a, i), at(b, i), at(c, i), at(g, i), p, flag)


@jit(inline=True)
def _mueller_point(out, i, ti, tr, phi, p, basis):
    a, b, c, n, k, lam = p[0], p[1], p[2], p[3], p[4], p[5]
    si, ci, sr, cr, cp, sp = _geometry(ti, tr, phi)
    ss, ps, sp_, pp = jones_elements(si, ci, sr, cr, cp, sp, n, k)
    if basis == XYXY:
        # reflected (e1, e2) = (y_r, x_r) = (-cos phi s_r + sin phi p_r, -sin phi s_r - cos
        # phi p_r) (roughbrdf.mueller); the incident xyxy basis is (s_i, p_i) itself
        ss, ps, sp_, pp = (-cp * ss + sp * sp_, -cp * ps + sp * pp,
                           -sp * ss - cp * sp_, -sp * ps - cp * pp)
    fx = sr * cp - si
    fy = sr * sp
    s2 = abc_psd_point(math.sqrt(fx * fx + fy * fy) / lam, a, b, c)
    lam2 = lam * lam
    scale = 16.0 * math.pi * math.pi / (lam2 * lam2) * ci * cr * s2
    jones_mueller(out, i, scale, ss.real, ss.imag, ps.real, ps.imag, sp_.real, sp_.imag,
                  pp.real, pp.imag)


@driver
def kcorr_mueller_drive(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # Mueller matrices (flag = basis code of roughbrdf.mueller); g unused
    for i in prange(out.shape[0]):
        _mueller_point(out, i, at(a, i), at(b, i), at(c, i), p, flag)
