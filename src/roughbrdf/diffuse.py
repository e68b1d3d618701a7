"""Diffuse parts: Oren-Nayar's rough-diffuse factor and diffuse light seen through a coating.

Two compiled scalar parts, each used by every model that needs it (``docs/models.md`` §10):

* :func:`oren_nayar_factor` -- the factor ``A + B max(0, cos(phi_r - phi_i)) sin(alpha)
  tan(beta)`` of Oren & Nayar's qualitative model (1994, Eq. 30) that multiplies ``rho/pi``;
* :func:`coated_diffuse` -- a diffuse substrate of albedo ``rho`` under a smooth dielectric
  interface of index ``n``: Fresnel transmission in and out (:func:`interface_transmission`),
  the ``1/n^2`` of radiance crossing the interface, and the internal reflections summed as a
  geometric series (:func:`diffuse_through`; Weidlich & Wilkie 2007, §3; the form of Mitsuba
  3's ``roughplastic`` with ``nonlinear=true``, ``docs/models.md`` §10.3);
* :func:`coated_diffuse_rough` -- the same substrate under the *rough* interface, with the
  transmission and the internal reflectance of the interface's single-scattering microfacet
  lobes, computed exactly as Mitsuba 3's ``roughplastic`` computes them
  (:func:`rough_interface`, "Rough interface" below).

Rough interface
---------------
Mitsuba 3.9's ``roughplastic`` (``src/bsdfs/roughplastic.cpp``, ``parameters_changed`` and
``eval``; ``include/mitsuba/render/microfacet.h``, ``eval_transmittance`` and
``eval_reflectance``) replaces the smooth factors ``1 - R(theta)`` and ``F_dr,int`` by:

* ``T(mu)``, the albedo of the rough interface's transmission lobe for light from outside,
  ``T(mu) = ∫ (1 - F(wi.m; n)) G1(wt) D_wi(m) dω_m`` (``D_wi``: the distribution of visible
  normals, ``wt``: ``wi`` refracted through ``m``), tabulated at the 64 values
  ``mu_k = max(1e-6, k/63)`` and interpolated linearly in ``cos theta``;
* ``F_int = 2 mean_k(E(mu_k) mu_k)`` over the same 64 values, ``E(mu) = ∫ F(wi.m; 1/n) G1(wo)
  D_wi(m) dω_m`` the albedo of the reflection lobe for light inside the coating (index ``1/n``,
  total internal reflection included);

each integral by a Gauss-Legendre product rule on the square of the visible-normal sampling
routine (``sample_visible_11``: Heitz 2018 for GGX, Jakob 2014's inversion with three Newton
steps for Beckmann), 32 x 32 nodes for ``T``, 128 x 128 for ``E``: Mitsuba's rule, node for
node (a finer one moves ``T`` by up to ~4e-4 and would break the one-to-one Mitsuba export).
The integrands are the library's parts (:func:`roughbrdf.fresnel.fresnel_sp`, Smith ``G1``
from :func:`roughbrdf.distributions.lambda_cos`); Mitsuba's Beckmann ``G1`` is a rational
approximation (within 0.35 %; ``g1="mitsuba"`` reproduces it). The substrate term is then
``rho/pi T(mu_i) T(mu_r) / (n^2 (1 - rho F_int))``, unpolarized.

Conventions: the library's frame (``docs/models.md`` §1.1): ``phi = 0`` is the forward
(specular) side, the source lies at ``phi = pi``, so Oren-Nayar's ``cos(phi_r - phi_i)`` is
``-cos(phi)``. ``gamma`` is TR75's polarization angle (NaN: unpolarized).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numba import prange
from numpy.typing import ArrayLike

from . import distributions as dist
from . import shadowing as shd
from ._kernels import as_float_array, driver, jit, ufunc
from .fresnel import fresnel_polarized_cs, fresnel_sp
from .geometry import check_angles

__all__ = ["oren_nayar_factor", "coated_diffuse", "coated_diffuse_rough", "oren_nayar",
           "interface_transmission", "diffuse_through", "lobe_albedo", "rough_interface",
           "ROUGH_TABLE_SIZE", "TABLE_NODES", "ALBEDO_NODES_PER_DECADE", "FRESNEL_GRID_SIZE"]

#: table size of Mitsuba's roughplastic (``MI_ROUGH_TRANSMITTANCE_RES``): the rough interface's
#: transmittance at 64 equally spaced values of cos(theta), interpolated linearly
ROUGH_TABLE_SIZE = 64
#: the table's values of cos(theta): ``max(1e-6, k/63)``, k = 0..63 (Mitsuba's)
TABLE_NODES = np.maximum(1e-6, np.linspace(0.0, 1.0, ROUGH_TABLE_SIZE))
TABLE_NODES.setflags(write=False)
#: Gauss-Legendre nodes per axis of Mitsuba's quadratures on the visible-normal sample square
#: (``eval_transmittance``/``eval_reflectance``: 32 for an index > 1, 128 for one < 1)
_NODES_EXTERNAL, _NODES_INTERNAL = 32, 128
#: Mitsuba clamps the quadrature samples of its Beckmann sampling routine into [1e-6, 1 - 1e-6]
_SAMPLE_CLAMP = 1e-6
_INV_SQRT_PI = 1.0 / math.sqrt(math.pi)
_TWO_OVER_SQRT_PI = 2.0 / math.sqrt(math.pi)
#: ``g1`` argument of :func:`rough_interface` -> code of the compiled table kernel
G1_CODES = {"exact": 0, "mitsuba": 1}
#: what a visible-normal sample of :func:`_lobe_sample` integrates: reflection inside the
#: coating (index 1/n), transmission into it, reflection outside (separable or correlated Smith)
_INTERNAL, _TRANSMIT, _EXTERNAL_SEPARABLE, _EXTERNAL_CORRELATED = 0, 1, 2, 3
#: Gauss-Legendre nodes per axis of :func:`lobe_albedo` (a smooth integrand: 32 x 32)
_NODES_ALBEDO = 32
#: the grid of :func:`_albedo_smooth`: ``alpha = 10^(i/128)``, every integer ``i`` (built
#: when first needed), and the Fresnel factor at ``cos = m/63``, m = 0..63
ALBEDO_NODES_PER_DECADE, FRESNEL_GRID_SIZE = 128, 64


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
    """Diffuse substrate under a smooth dielectric interface, BRDF in sr⁻¹ (Weidlich & Wilkie):
    :func:`diffuse_through` of :func:`interface_transmission`, ``fdr_int`` the interface's
    internal diffuse reflectance (:func:`roughbrdf.fresnel.diffuse_reflectance`). For ``rho =
    1`` the albedo is exactly ``1 - R(theta_i)``: all transmitted light comes back out."""
    t_in, t_out = interface_transmission(ci, cr, n, gamma)
    return diffuse_through(t_in, t_out, n, rho, fdr_int)


@jit(inline=True)
def interface_transmission(ci, cr, n, gamma):
    """``(1 - R(theta_i; gamma), 1 - R(theta_r))``: a smooth interface's (index ``n``, ``k =
    0``) Fresnel transmittance at the macroscopic angles, at incidence for the polarization
    ``gamma`` (the planes of incidence coincide, ``eta = 0``), at exit unpolarized."""
    t_in = 1.0 - fresnel_polarized_cs(ci, n, 0.0, gamma, 1.0, 0.0)
    rs, rp = fresnel_sp(cr, n, 0.0)
    return t_in, 1.0 - 0.5 * (rs + rp)


@jit(inline=True)
def diffuse_through(t_in, t_out, n, rho, fdr_int):
    """``rho/pi t_in t_out / (n^2 (1 - rho F_int))``: a substrate of albedo ``rho`` under an
    interface of transmittances ``t_in``, ``t_out`` and internal reflectance ``F_int``."""
    return rho / math.pi * t_in * t_out / (n * n * (1.0 - rho * fdr_int))


@jit(inline=True)
def table_lerp(c, table, offset):
    """``table[offset:offset + 64]`` interpolated linearly at ``c = cos theta`` in [0, 1].

    Mitsuba's ``lerp_gather``: ``x = 63 c``, cell ``min(floor(x), 62)``, linear in ``x``.
    """
    x = c * (ROUGH_TABLE_SIZE - 1)
    i = min(int(x), ROUGH_TABLE_SIZE - 2)  # c = 1 lies in the last cell, at its end
    v0 = table[offset + i]
    return v0 + (table[offset + i + 1] - v0) * (x - i)


@jit(inline=True)
def coated_diffuse_rough(ci, cr, n, rho, f_int, table, offset):
    """Diffuse substrate under a *rough* dielectric interface, BRDF in sr⁻¹ (unpolarized).

    ``rho/pi T(theta_i) T(theta_r) / (n^2 (1 - rho F_int))`` with the transmittance table
    ``T`` at ``table[offset:offset + 64]`` and the internal reflectance ``f_int`` from
    :func:`rough_interface` (Mitsuba 3's ``roughplastic`` with ``nonlinear=true``).
    """
    return diffuse_through(table_lerp(ci, table, offset), table_lerp(cr, table, offset), n,
                           rho, f_int)


@jit
def _erfinv(y):
    """Inverse error function: Giles (2010)'s single-precision polynomial, then Newton steps
    (on ``erf`` near 0, on ``log erfc`` in the tails) to double precision; +-inf at +-1."""
    if y <= -1.0 or y >= 1.0:
        return math.copysign(math.inf, y)
    w = -math.log((1.0 - y) * (1.0 + y))
    if w < 5.0:
        w -= 2.5
        p = 2.81022636e-08
        for c in (3.43273939e-07, -3.5233877e-06, -4.39150654e-06, 0.00021858087,
                  -0.00125372503, -0.00417768164, 0.246640727, 1.50140941):
            p = c + p * w
    else:
        w = math.sqrt(w) - 3.0
        p = -0.000200214257
        for c in (0.000100950558, 0.00134934322, -0.00367342844, 0.00573950773,
                  -0.0076224613, 0.00943887047, 1.00167406, 2.83297682):
            p = c + p * w
    x = p * y
    if abs(y) <= 0.5:
        for _ in range(2):
            x -= (math.erf(x) - y) / (_TWO_OVER_SQRT_PI * math.exp(-x * x))
        return x
    # tails: Newton on log erfc(|x|) = log(1 - |y|), well conditioned where erf(x) is 1 to
    # the last bits (1 - |y| is exact there)
    ax, q = abs(x), math.log1p(-abs(y))
    for _ in range(4):
        ec = math.erfc(ax)
        ax += (math.log(ec) - q) * ec / (_TWO_OVER_SQRT_PI * math.exp(-ax * ax))
    return math.copysign(ax, y)


@jit
def _concentric_disk(u1, u2):
    """Shirley-Chiu concentric map of the unit square onto the unit disk (Mitsuba's
    ``square_to_uniform_disk_concentric``)."""
    x = 2.0 * u1 - 1.0
    y = 2.0 * u2 - 1.0
    if x == 0.0 and y == 0.0:
        return 0.0, 0.0  # the centre (also guards the divisions below)
    if abs(x) < abs(y):
        r, phi = y, 0.5 * math.pi - 0.25 * math.pi * x / y
    else:
        r, phi = x, 0.25 * math.pi * y / x
    return r * math.cos(phi), r * math.sin(phi)


@jit
def _beckmann_slope_x(ct, st, u1):
    """Beckmann's visible slope along the plane of incidence (Mitsuba's numerical inversion,
    Jakob 2014, three Newton steps as in ``sample_visible_11``)."""
    tan = st / ct
    # normal incidence: cot = inf, erf(inf) = 1 and tan exp(-cot^2) = 0, as in Mitsuba
    cot = 1.0 / tan if tan > 0.0 else math.inf
    maxval = math.erf(cot)
    u1 = min(max(u1, _SAMPLE_CLAMP), 1.0 - _SAMPLE_CLAMP)
    x = maxval - (maxval + 1.0) * math.erf(math.sqrt(-math.log(u1)))
    u1 *= 1.0 + maxval + _INV_SQRT_PI * tan * math.exp(-cot * cot)
    for _ in range(3):
        slope = _erfinv(x)
        value = 1.0 + x + _INV_SQRT_PI * tan * math.exp(-slope * slope) - u1
        d = 1.0 - slope * tan
        # d = 0 (a stationary point) does not occur for slopes from this start; the stand-in
        # keeps the step finite instead of dividing by 0
        x -= value / (d if d != 0.0 else 1.0)
    return _erfinv(x)


@jit(inline=True)
def _ggx_slope_11(ct, st, px, py):
    """GGX's visible slopes for roughness 1 and ``cos theta_i = ct`` from the disk point
    ``(px, py)`` of the sample (Heitz 2018; Mitsuba's ``sample_visible_11``): the point is
    squeezed onto the visible half of the disk and projected."""
    s = 0.5 * (1.0 + ct)
    py = math.sqrt(max(0.0, 1.0 - px * px)) * (1.0 - s) + py * s
    z = math.sqrt(max(0.0, 1.0 - px * px - py * py))
    den = st * py + ct * z
    # den = 0 only for a sample on the rim of the projected disk seen exactly edge-on; its
    # normal is horizontal (slope inf), weight 0 in the quadrature: the stand-in avoids 0/0
    norm = 1.0 / (den if den > 0.0 else 1.0)
    return (ct * py - st * z) * norm, px * norm


@jit(inline=True)
def _g1(dcode, a, c, approx):
    """Smith ``G1`` at ``cos theta = |c|``; ``approx`` with Beckmann: Mitsuba's rational
    approximation (``smith_g1`` in ``microfacet.h``)."""
    c = min(1.0, abs(c))
    if approx and dcode == dist.BECKMANN:
        s = math.sqrt(1.0 - c * c)
        x = c / (a * s) if s > 0.0 else math.inf  # s = 0: the normal direction
        return 1.0 if x >= 1.6 else (3.535 * x + 2.181 * x * x) / (
            1.0 + 2.276 * x + 2.577 * x * x)
    den = c + dist.lambda_cos(dcode, c, a)
    return c / den if den > 0.0 else 0.0  # den = 0: c = 0, fully masked


@jit(inline=True)
def _visible_normal(a, sx, cz, gx, gy):
    """``(wi.m, m_z)`` of the normal of slopes ``(gx, gy)`` (roughness 1) for ``wi = (sx, 0,
    cz)``: unstretched (``wi`` lies in the x-z plane, ``sx >= 0``: no azimuth rotation)."""
    mx, my = -gx * a, -gy * a
    mz = 1.0 / math.sqrt(mx * mx + my * my + 1.0)
    mx, my = mx * mz, my * mz
    return max(0.0, sx * mx + cz * mz), mz  # visible normals face wi; max: rounding below 0


@jit(inline=True)
def _reflect_g(dcode, a, approx, mode, cz, z):
    """The shadowing factor of a reflected sample with ``z`` its direction's z: ``G1(wo)``, or
    ``G2(wi, wo)/G1(wi)`` height-correlated (:data:`_EXTERNAL_CORRELATED`)."""
    if mode == _EXTERNAL_CORRELATED and z > 0.0:
        # G2/G1(wi) = co (ci + Li)/(ci co + co Li + ci Lo), L = Lambda cos; den > 0 for z > 0
        li = dist.lambda_cos(dcode, cz, a)
        lo = dist.lambda_cos(dcode, min(1.0, z), a)
        return z * (cz + li) / (cz * z + z * li + cz * lo)
    # z <= 0: reflected below the interface, lost
    return _g1(dcode, a, z, approx) if z > 0.0 else 0.0


@jit(inline=True)
def _lobe_sample(dcode, a, n, approx, mode, sx, cz, gx, gy):
    """One visible-normal sample of slopes ``(gx, gy)`` (roughness 1) for ``wi = (sx, 0, cz)``:
    ``mode`` 1 (:data:`_TRANSMIT`): ``(1 - F) G1(wt)`` for light refracted into index ``n > 1``
    (Mitsuba's ``eval_transmittance``); 0 (:data:`_INTERNAL`): ``F G1(wo)`` for light inside,
    reflected at index ``1/n`` (``eval_reflectance``; total internal reflection included);
    2, 3 (:data:`_EXTERNAL_SEPARABLE`, :data:`_EXTERNAL_CORRELATED`): ``F G2(wi, wo)/G1(wi)``
    for light from outside reflected at index ``n`` (separable or height-correlated Smith)."""
    c, mz = _visible_normal(a, sx, cz, gx, gy)
    if mode == _TRANSMIT:
        rs, rp = fresnel_sp(c, n, 0.0)
        ct = math.sqrt(max(0.0, 1.0 - (1.0 - c * c) / (n * n)))
        z = mz * (c / n - ct) - cz / n  # z of wi refracted through m (Mitsuba's refract)
        # z >= 0: not below the interface, no transmission
        return (1.0 - 0.5 * (rs + rp)) * _g1(dcode, a, z, approx) if z < 0.0 else 0.0
    rs, rp = fresnel_sp(c, n if mode >= _EXTERNAL_SEPARABLE else 1.0 / n, 0.0)
    # z of wi mirrored about m
    return 0.5 * (rs + rp) * _reflect_g(dcode, a, approx, mode, cz, 2.0 * c * mz - cz)


@jit(inline=True)
def _deposit(row, c, g):
    """Add ``g`` to ``row`` (the Fresnel grid ``c_m = m/(M - 1)``) with the cubic Lagrange
    weights of ``c`` on its 4 nearest nodes: ``sum_m row_m F(c_m) = g F(c)`` to the cubic
    interpolation error of the smooth ``F``."""
    size = row.size
    x = c * (size - 1)
    i = min(max(int(x) - 1, 0), size - 4)  # the 4 nodes around x, inside the grid
    t = x - i
    row[i] += g * (-(t - 1.0) * (t - 2.0) * (t - 3.0) / 6.0)
    row[i + 1] += g * (t * (t - 2.0) * (t - 3.0) / 2.0)
    row[i + 2] += g * (-t * (t - 1.0) * (t - 3.0) / 2.0)
    row[i + 3] += g * (t * (t - 1.0) * (t - 2.0) / 6.0)


@jit
def _lobe_albedo(dcode, a, n, approx, mode, cz, x, w, dx, dy, row):
    """Mitsuba's Gauss-Legendre product rule over the visible-normal sample square for
    ``wi = (sqrt(1 - cz^2), 0, cz)``: nodes ``x`` on [0, 1], weights ``w`` of [-1, 1] (hence
    1/4), ``(dx, dy)`` the concentric-disk points of the node pairs (GGX). With a non-empty
    ``row`` (external reflection only): each sample's weight without its Fresnel factor,
    deposited on the Fresnel grid (:func:`_deposit`) instead of summed (returns 0)."""
    sx = math.sqrt(1.0 - cz * cz)
    ct = cz / math.sqrt(a * a * sx * sx + cz * cz)  # wi stretched by the roughness
    st = math.sqrt(max(0.0, 1.0 - ct * ct))
    size = x.size
    bx = np.zeros(size)
    by = np.zeros(size)
    if dcode == dist.BECKMANN:  # its slopes are separable: x from u1 (and ct), y from u2
        for j in range(size):
            bx[j] = _beckmann_slope_x(ct, st, x[j])
            by[j] = _erfinv(2.0 * min(max(x[j], _SAMPLE_CLAMP), 1.0 - _SAMPLE_CLAMP) - 1.0)
    acc = 0.0
    for j in range(size):  # u2 = x[j]
        for m in range(size):  # u1 = x[m]
            if dcode == dist.BECKMANN:
                gx, gy = bx[m], by[j]
            else:
                gx, gy = _ggx_slope_11(ct, st, dx[j * size + m], dy[j * size + m])
            if row.size == 0:
                acc += w[j] * w[m] * _lobe_sample(dcode, a, n, approx, mode, sx, cz, gx, gy)
            else:
                c, mz = _visible_normal(a, sx, cz, gx, gy)
                g = _reflect_g(dcode, a, approx, mode, cz, 2.0 * c * mz - cz)
                _deposit(row, c, 0.25 * w[j] * w[m] * g)
    return 0.25 * acc


@driver
def _rough_tables(dcode, a, n, approx, mu, xe, we, dxe, dye, xi, wi, dxi, dyi, t, e
                  ):  # pragma: no cover - compiled
    # one table entry per iteration (64): T(mu_k) on the 32 x 32 rule, E(mu_k) on 128 x 128
    none = np.zeros(0)  # no deposit row: the samples are summed
    for k in prange(mu.size):
        t[k] = _lobe_albedo(dcode, a, n, approx, _TRANSMIT, mu[k], xe, we, dxe, dye, none)
        e[k] = _lobe_albedo(dcode, a, n, approx, _INTERNAL, mu[k], xi, wi, dxi, dyi, none)


@driver
def _reflect_table(dcode, a, n, mode, mu, x, w, dx, dy, e):  # pragma: no cover - compiled
    # one entry per iteration: the external reflection lobe's albedo E(mu_k)
    none = np.zeros(0)  # no deposit row: the samples are summed
    for k in prange(mu.size):
        e[k] = _lobe_albedo(dcode, a, n, 0, mode, mu[k], x, w, dx, dy, none)


@driver
def _reflect_weights(dcode, a, mode, mu, x, w, dx, dy, out):  # pragma: no cover - compiled
    # one row per iteration: E(mu_k) = out[k] . F(c_m; n), the Fresnel factor left out
    for k in prange(mu.size):
        _lobe_albedo(dcode, a, 1.0, 0, mode, mu[k], x, w, dx, dy, out[k])


@jit
def _fresnel_grid(n, out):
    # the unpolarized F(c_m; n) at c_m = m/(M - 1)
    size = out.size
    for m in range(size):
        rs, rp = fresnel_sp(m / (size - 1), n, 0.0)
        out[m] = 0.5 * (rs + rp)


@jit
def _disk_points(x, dx, dy):
    # the concentric-disk point of every node pair (u1 = x[m], u2 = x[j]) at j * size + m
    size = x.size
    for j in range(size):
        for m in range(size):
            dx[j * size + m], dy[j * size + m] = _concentric_disk(x[m], x[j])


@functools.lru_cache(maxsize=4)
def _unit_square_rule(points: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes mapped to [0, 1] (``x/2 + 1/2``), their weights on [-1, 1], and
    the concentric-disk points of the node pairs."""
    x, w = np.polynomial.legendre.leggauss(points)
    x = 0.5 * x + 0.5
    dx = np.empty(points * points)
    dy = np.empty(points * points)
    _disk_points(x, dx, dy)
    return x, w, dx, dy


@functools.lru_cache(maxsize=1024)  # a fit asks for the same (alpha, n) many times
def _rough_cached(dcode: int, alpha: float, n: float, approx: int
                  ) -> tuple[tuple[float, ...], float]:
    mu = TABLE_NODES  # Mitsuba's table nodes
    t = np.empty(ROUGH_TABLE_SIZE)
    e = np.empty(ROUGH_TABLE_SIZE)
    _rough_tables(dcode, alpha, n, approx, mu, *_unit_square_rule(_NODES_EXTERNAL),
                  *_unit_square_rule(_NODES_INTERNAL), t, e)
    return tuple(float(v) for v in t), float(2.0 * np.mean(e * mu))


def rough_interface(alpha: float, n: float, distribution: str = "trowbridge-reitz", *,
                    g1: str = "exact") -> tuple[np.ndarray, float]:
    """Transmittance table and internal reflectance of a rough dielectric interface.

    Mitsuba 3's ``roughplastic`` tables, computed the same way (module notes, "Rough
    interface"): ``T(mu_k)`` at ``mu_k = max(1e-6, k/63)``, ``k = 0..63``, and ``F_int``.
    Cached per argument set; about 10 ms compiled.

    Parameters
    ----------
    alpha : float
        Width of the distribution (> 0).
    n : float
        Index of the coating (> 1).
    distribution : str
        ``"trowbridge-reitz"`` (GGX) or ``"beckmann"``.
    g1 : {"exact", "mitsuba"}
        Smith ``G1``: the library's (exact), or Mitsuba's rational approximation for Beckmann
        (used by :mod:`roughbrdf.export.mitsuba` to predict Mitsuba's values; the same for GGX).

    Returns
    -------
    t : numpy.ndarray, shape (64,)
        ``T(mu_k)``.
    f_int : float
        Internal reflectance ``2 mean(E(mu_k) mu_k)``.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> t, f_int = rb.diffuse.rough_interface(0.3, 1.5)
    >>> round(float(t[-1]), 4), round(f_int, 4)   # normal incidence; smooth: 0.96 and 0.5963
    (0.9532, 0.4149)
    """
    d = dist.get(distribution)
    if d.code not in (dist.TR, dist.BECKMANN):
        raise ValueError(f"distribution must be 'trowbridge-reitz' or 'beckmann' for a rough "
                         f"interface, got {distribution!r}")
    a, nn = float(alpha), float(n)
    if not (math.isfinite(a) and a > 0.0):
        raise ValueError(f"alpha must be finite and > 0, got {alpha!r}")
    if not (math.isfinite(nn) and nn > 1.0):
        raise ValueError(f"n must be finite and > 1 (a coating denser than air), got {n!r}")
    if g1 not in G1_CODES:
        raise ValueError(f"g1 must be 'exact' or 'mitsuba', got {g1!r}")
    t, f_int = _rough_cached(d.code, a, nn, G1_CODES[g1])
    return np.array(t), f_int


@functools.lru_cache(maxsize=1024)  # a fit asks for the same (alpha, n) many times
def _albedo_cached(dcode: int, mode: int, alpha: float, n: float) -> tuple[float, ...]:
    e = np.empty(ROUGH_TABLE_SIZE)
    _reflect_table(dcode, alpha, n, mode, TABLE_NODES, *_unit_square_rule(_NODES_ALBEDO), e)
    return tuple(float(v) for v in e)


def lobe_albedo(alpha: float, n: float, distribution: str = "trowbridge-reitz",
                shadowing: str = "smith-separable", *, smooth: bool = False) -> np.ndarray:
    """Directional albedo of one specular lobe of a dielectric interface, at the table nodes.

    ``E(mu) = ∫ F(theta_d; n) D G / (4 cos theta_i cos theta_r) cos theta_r dω_r`` (the
    ``microfacet`` model with ``k = 0``, ``ks = 1``) at ``cos theta_i = mu_k`` =
    :data:`TABLE_NODES`, integrated over the distribution of visible normals on a 32 x 32
    Gauss-Legendre rule of its sampling square (as :func:`rough_interface`; within 1e-3 of
    :func:`roughbrdf.albedo` for ``alpha >= 0.05``, more near grazing incidence for narrower
    lobes). Cached per argument set; 2.5 ms (GGX), 6 ms (Beckmann) compiled. The coated
    model compares it with the smooth interface's ``R(theta)`` (``docs/models.md`` §10.3).

    Parameters
    ----------
    alpha : float
        Width of the distribution (> 0).
    n : float
        Index of the interface (> 0).
    distribution : str
        ``"trowbridge-reitz"`` (GGX) or ``"beckmann"``.
    shadowing : str
        ``"smith-separable"`` or ``"smith-height-correlated"``.
    smooth : bool
        The rule's values interpolated on a fixed grid, smooth in ``alpha`` and ``n``
        (``n >= 1``; what the coated model uses, :func:`_albedo_smooth`).

    Returns
    -------
    numpy.ndarray, shape (64,)

    Examples
    --------
    >>> import roughbrdf as rb
    >>> e = rb.diffuse.lobe_albedo(0.01, 1.5)
    >>> round(float(e[-1]), 4)            # normal incidence, nearly smooth: F(0) = 0.04
    0.04
    >>> e = rb.diffuse.lobe_albedo(0.1, 1.5, smooth=True)    # at a node: the rule's value
    >>> bool(abs(e - rb.diffuse.lobe_albedo(0.1, 1.5)).max() < 1e-6)
    True
    """
    dcode, mode = _albedo_codes(distribution, shadowing)
    a, nn = float(alpha), float(n)
    if not (math.isfinite(a) and a > 0.0):
        raise ValueError(f"alpha must be finite and > 0, got {alpha!r}")
    # smooth: n < 1 reflects totally, where F is not smooth in cos (the grid needs it smooth)
    if not (math.isfinite(nn) and nn >= (1.0 if smooth else 0.0) and nn > 0.0):
        raise ValueError(f"n must be finite and {'>= 1' if smooth else '> 0'}, got {n!r}")
    if smooth:
        return _albedo_smooth(dcode, mode, a, nn)
    return np.array(_albedo_cached(dcode, mode, a, nn))


def _albedo_codes(distribution: str, shadowing: str) -> tuple[int, int]:
    """The distribution code and the :func:`_lobe_sample` mode of a lobe albedo."""
    d = dist.get(distribution)
    if d.code not in (dist.TR, dist.BECKMANN):
        raise ValueError(f"distribution must be 'trowbridge-reitz' or 'beckmann', "
                         f"got {distribution!r}")
    s = shd.get(shadowing).code
    if s not in (shd.SMITH_SEPARABLE, shd.SMITH_HEIGHT_CORRELATED):
        raise ValueError(f"shadowing must be 'smith-separable' or 'smith-height-correlated', "
                         f"got {shadowing!r}")
    return d.code, (_EXTERNAL_SEPARABLE if s == shd.SMITH_SEPARABLE else _EXTERNAL_CORRELATED)


@functools.lru_cache(maxsize=1024)  # one matrix (32 KB) per alpha node
def _albedo_node(dcode: int, mode: int, i: int) -> np.ndarray:
    """The weights ``W`` at the grid node ``alpha_i`` of :func:`_albedo_smooth`:
    ``E(mu_k; n) = W[k] . F(c_m; n)``."""
    w = np.zeros((ROUGH_TABLE_SIZE, FRESNEL_GRID_SIZE))
    _reflect_weights(dcode, 10.0 ** (i / ALBEDO_NODES_PER_DECADE), mode, TABLE_NODES,
                     *_unit_square_rule(_NODES_ALBEDO), w)
    w.setflags(write=False)
    return w


def _albedo_smooth(dcode: int, mode: int, a: float, nn: float) -> np.ndarray:
    """``lobe_albedo(..., smooth=True)``: smooth in ``alpha`` and ``n``.

    ``E`` depends on ``n`` only through each sample's Fresnel factor: at each node ``alpha_i
    = 10^(i/128)`` (every integer ``i``; built when first needed and cached, 2.5 ms GGX, 6 ms
    Beckmann) the rule's samples without it are gathered onto the grid ``cos = m/63``
    (cubic Lagrange weights), so that ``E(n)`` is a dot product with ``F(m/63; n)``, analytic
    in ``n``; between the nodes a Catmull-Rom spline in ``log alpha`` (continuous first
    derivative). A fit's finite differences (steps ~1e-8 relative) see the model's
    derivative, which a table per rounded argument would not. Against the rule's own value
    (1200 random points, alpha 0.005-1.5, n 1.05-2.6, each distribution and shadowing):
    at most 7e-5 (GGX) and 1.2e-4 (Beckmann), median 3e-6; the rule's value itself moves
    unevenly in ``alpha`` by that much, and is within ~1e-3 of the exact integral.
    """
    f = np.empty(FRESNEL_GRID_SIZE)
    _fresnel_grid(nn, f)
    x = math.log10(a) * ALBEDO_NODES_PER_DECADE
    i = math.floor(x)
    t = x - i
    t2, t3 = t * t, t * t * t
    weights = (-t3 + 2 * t2 - t, 3 * t3 - 5 * t2 + 2, -3 * t3 + 4 * t2 + t, t3 - t2)
    out = np.zeros(ROUGH_TABLE_SIZE)
    for p, wp in enumerate(weights):
        if wp != 0.0:  # on a node (t = 0) the spline is that node's value (no other table)
            out += 0.5 * wp * (_albedo_node(dcode, mode, i - 1 + p) @ f)
    return out


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
