"""Directional-hemispherical reflectance (albedo) and reciprocity checks.

``albedo(model, theta_i) = ∫_hemisphere f_r(theta_i, w_r) cos(theta_r) dω_r``.

Why a hand-written quadrature: the integrand can be a lobe a few degrees wide (TR75 with
e = 0.05) sitting anywhere on the hemisphere and cut by the horizon, which generic cubature
(``scipy.integrate.nquad``) handles slowly and unreliably. Here the hemisphere is parametrized
by polar coordinates ``(rho, psi)`` *centred on the specular direction* ``w_s``::

    w_r = cos(rho) w_s + sin(rho) (cos(psi) e1 + sin(psi) e2),   dω = sin(rho) drho dpsi

Each ray ``psi`` is integrated exactly up to the horizon ``rho_max(psi)`` (where ``w_r,z = 0``), so
the horizon cut is not a discontinuity of the integrand; ``rho`` uses composite Gauss-Legendre
panels graded geometrically from ``1e-4`` rad (resolving lobes of any width centred at the
specular direction); ``psi`` uses the periodic trapezoid rule (spectrally accurate). All samples
of all incidences are evaluated in one vectorized model call.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numpy.typing import ArrayLike

from .errors import ArgumentError
from .geometry import check_zenith
from .models.base import Model, PreparedGeometry
from .polarization import Polarization

__all__ = ["albedo", "reciprocity_error"]


def _rho_panels(n_panels: int, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes/weights on [0, 1] in units of rho_max, graded geometrically toward 0."""
    x, w = np.polynomial.legendre.leggauss(order)
    edges = np.concatenate([[0.0], np.geomspace(1e-4 / math.pi, 1.0, n_panels)])
    nodes, weights = [], []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        nodes.append(0.5 * (b - a) * x + 0.5 * (a + b))
        weights.append(0.5 * (b - a) * w)
    return np.concatenate(nodes), np.concatenate(weights)


#: quadratures of at most this many samples are kept (:func:`_quadrature`): the ten
#: incidences of every fit's plausibility check (7.4e5 samples, 18 MB), not larger grids
CACHED_SAMPLES = 1_000_000


def _quadrature(ti_bytes: bytes, n_psi: int, n_panels: int, order: int
                ) -> tuple[np.ndarray, ...]:
    """``(theta_r, phi, sin rho, rho_max, w)`` of the rule (module notes) at the incidences
    ``ti_bytes`` (float64 radians, as bytes), each of shape ``(incidences, n_psi, n_panels *
    order)`` (the last two broadcast views); the albedo is ``2 pi/n_psi sum(f cos theta_r sin
    rho rho_max w)`` over the last two axes. Grids of at most
    :data:`CACHED_SAMPLES` samples are cached (:func:`_quadrature_cached`): every fit checks
    its channels' albedo at the same ten incidences, and building the directions (``arccos``,
    ``arctan2`` of every sample) cost as much as evaluating a coated model on them."""
    n = len(ti_bytes) // 8 * n_psi * n_panels * order
    if n <= CACHED_SAMPLES:
        return _quadrature_cached(ti_bytes, n_psi, n_panels, order)
    return _build_quadrature(ti_bytes, n_psi, n_panels, order)


def _build_quadrature(ti_bytes: bytes, n_psi: int, n_panels: int, order: int
                      ) -> tuple[np.ndarray, ...]:
    """:func:`_quadrature`, built."""
    t = np.frombuffer(ti_bytes, dtype=float).reshape(-1, 1, 1)
    u, wu = _rho_panels(n_panels, order)  # fraction of rho_max
    psi = (np.arange(n_psi) + 0.5) * (2 * math.pi / n_psi)
    cp, sp = np.cos(psi)[None, :, None], np.sin(psi)[None, :, None]
    # specular direction w_s and the orthonormal pair (e1, e2) perpendicular to it
    sz, sx = np.cos(t), np.sin(t)
    # tangent direction t(psi) = cos psi e1 + sin psi e2, e1 = (cos ti, 0, -sin ti), e2 = y
    tx, ty, tz = cp * sz, sp, -cp * sx
    # horizon: w_z = cos(rho) sz + sin(rho) tz = 0  ->  rho_max = atan2(sz, -tz) in (0, pi]
    rho_max = np.arctan2(sz, -tz)
    rho = u[None, None, :] * rho_max
    cr_, sr_ = np.cos(rho), np.sin(rho)
    wx = cr_ * sx + sr_ * tx
    wy = sr_ * ty
    wz = np.clip(cr_ * sz + sr_ * tz, 0.0, 1.0)
    out = (np.arccos(wz), np.arctan2(wy, wx), sr_, np.broadcast_to(rho_max, sr_.shape),
           np.broadcast_to(wu[None, None, :], sr_.shape))
    for a in out:
        a.setflags(write=False)  # shared by every call (cached)
    return out


_quadrature_cached = functools.lru_cache(maxsize=2)(_build_quadrature)


def albedo(model: Model, theta_i: ArrayLike, *, polarization=None, n_psi: int = 256,
           n_panels: int = 24, order: int = 12) -> np.ndarray | float:
    """Directional-hemispherical reflectance of ``model`` at incidence ``theta_i`` (radians).

    Accurate to about 1e-5 absolute for the facet models, including sharp lobes (e = 0.05);
    ``n_psi``, ``n_panels`` and ``order`` trade accuracy for time.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> round(float(rb.albedo(rb.model("lambertian", rho=0.5), 0.3)), 8)
    0.5
    """
    if not isinstance(model, Model):
        raise TypeError(f"model must be a roughbrdf Model (rb.model(...)), got "
                        f"{type(model).__name__}")
    for name, v, least in (("n_psi", n_psi, 4), ("n_panels", n_panels, 1), ("order", order, 1)):
        if isinstance(v, bool) or not isinstance(v, int | np.integer) or v < least:
            raise ArgumentError(name, f"{name} must be an integer >= {least}, got {v!r}")
    ti = check_zenith(theta_i, "theta_i", open_upper=not model.grazing_incidence)
    # kernel_gamma refuses a Stokes/analyzer setting (the albedo integrates the scalar kernel)
    gamma = Polarization.parse(polarization).kernel_gamma()
    if gamma.ndim:
        raise ArgumentError("polarization", "albedo takes one polarization for all "
                            "incidences (a name or one angle gamma)")
    shape = ti.shape
    theta_r, phi, sin_rho, rho_max, wu = _quadrature(ti.tobytes(), n_psi, n_panels, order)
    # the directions are built inside the hemisphere: no second validation
    g = PreparedGeometry(np.broadcast_to(ti.reshape(-1, 1, 1), theta_r.shape), theta_r, phi,
                         gamma)
    f = model.evaluate_prepared(g, "brdf_cos")
    # the products in this order, the sum, then 2 pi/n_psi: the rounding of the albedo a
    # fit's energy constraint and its checks see does not change with the cache
    integrand = f * sin_rho * rho_max * wu
    out = (integrand.sum(axis=(1, 2)) * (2 * math.pi / n_psi)).reshape(shape)
    return float(out) if out.ndim == 0 else out


def reciprocity_error(model: Model, theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike
                      ) -> np.ndarray:
    """Relative difference ``|f(i, r) - f(r, i)| / max(f)`` (0 for a reciprocal model).

    Equal values, infinite ones included (a model's limit at the horizon), give 0.
    """
    a = np.asarray(model.brdf(theta_i, theta_r, phi))
    b = np.asarray(model.brdf(theta_r, theta_i, phi))
    scale = np.maximum(np.maximum(np.abs(a), np.abs(b)), 1e-300)
    with np.errstate(invalid="ignore"):  # inf - inf
        err = np.abs(a - b) / scale
    return np.where(a == b, 0.0, err)
