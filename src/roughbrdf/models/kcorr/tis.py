"""Total integrated scatter (directional-hemispherical reflectance) of the K-correlation model.

Quadrature (:func:`tis`)
------------------------
In direction cosines ``cos theta_r dOmega = d^2 beta`` (the unit disc), so

.. math::

    \\mathrm{TIS}(\\theta_i) = \\frac{16\\pi^2\\cos\\theta_i}{\\lambda^4}
    \\int_0^{2\\pi}\\!d\\psi\\int_0^{\\rho_{max}(\\psi)} \\cos\\theta_r\\,Q\\,
    S_2(\\rho/\\lambda)\\,\\rho\\,d\\rho

in polar coordinates ``beta = beta_0 + rho (cos psi, sin psi)`` about the specular point,
``rho_max = -beta_0 cos psi + sqrt(1 - beta_0^2 sin^2 psi)`` the unit circle. The PSD is
peaked at ``rho ~ lambda/B`` (tiny for long correlation lengths) and has a power-law tail, so
the radial variable is the PSD's own cumulative measure ``G(rho) = int_0^rho S_2 rho' drho'``,
known and invertible in closed form (``u = 1 + (B rho/lambda)^2``, ``G = lambda^2 (A/(2B^2))
(u^(1-C/2) - 1)/(1 - C/2)``, ``ln u`` at ``C = 2``): the radial integral is
``G(rho_max) int_0^1 cos theta_r Q ds`` with a smooth integrand, whatever ``B`` and ``C``. A
last substitution ``s = t (2 - t)`` removes the square-root zero of ``cos theta_r`` at the
horizon (``s -> 1``). Then Gauss–Legendre in ``t`` (``n_radial`` nodes) and the midpoint
(trapezoid) rule in the periodic ``psi`` (``n_psi`` nodes). The radial rule converges
slowest near grazing incidence, where ``cos theta_r`` has a branch point at ``rho = -(1 -
sin theta_i)`` just behind the start: measured for ``0.5 <= B/lambda <= 500``,
``0.5 <= C <= 6``, the defaults (128 x 192) agree with a 512 x 1024 rule to 5e-6 relative up
to ``theta_i = 89°`` (3e-7 up to 60°), and with :func:`roughbrdf.albedo` to 1e-4 relative,
the tested bound, up to ``theta_i = 80°`` (tests/models/test_straylight_kcorr.py).

Small-roughness closed form (:func:`tis_smooth_limit`)
------------------------------------------------------
``TIS ≈ (4 pi sigma cos theta_i / lambda)^2 R(theta_i)`` (Davies 1954; Bennett & Porteus 1961;
Stover, *Optical Scattering*), ``R`` the Fresnel reflectance of the incident
polarization and ``sigma`` the total rms roughness. It follows from the model when all of the
PSD lies near the specular point, where ``Q -> R`` and ``cos theta_r -> cos theta_i``: it needs
``C > 2`` and ``B >> lambda`` (correlation length much longer than the wavelength). Its
relative error is about the PSD fraction beyond the horizon, at most
``(1 + (B (1 - sin theta_i)/lambda)^2)^(1 - C/2)``, plus ``O((lambda/B)^2)`` from the change of
``Q cos theta_r`` over the PSD's width (measured: 1.6e-4 up to ``theta_i = 30°`` and 1.5e-3 at
60° for ``C = 4``, ``B/lambda = 100``; 4 % at normal incidence for ``C = 2.5``,
``B/lambda = 572``, SCATMECH's default PSD at 0.6328 µm).
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ... import _kernels
from ...errors import ArgumentError
from ...fresnel import reflectance
from ...geometry import check_zenith
from ...polarization import Polarization
from .kernel import WITHOUT_PSD, kcorr_drive
from .model import KCorrelation

__all__ = ["tis", "tis_smooth_limit"]


@functools.lru_cache(maxsize=8)
def _radial_rule(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes ``s`` in (0, 1) and weights for ``int_0^1 g(s) ds`` with ``s = t (2 - t)``."""
    x, w = np.polynomial.legendre.leggauss(n)
    t = 0.5 * (x + 1.0)
    return t * (2.0 - t), w * (1.0 - t)  # ds = 2 (1 - t) dt, dt = dx / 2


def _cumulative(e: float, log_u: np.ndarray) -> np.ndarray:
    """``H(u) = (u^e - 1)/e`` (``ln u`` at ``e = 0``) from ``ln u``, without cancellation."""
    if abs(e) < 1e-12:  # C = 2 to 2e-12: the limit ln u, to 1e-12 relative
        return log_u
    return np.expm1(e * log_u) / e


def _inverse_cumulative(e: float, h: np.ndarray) -> np.ndarray:
    """``ln u`` with ``H(u) = h`` (the inverse of :func:`_cumulative`)."""
    if abs(e) < 1e-12:
        return h
    return np.log1p(e * h) / e


def _check_model(model: Any) -> KCorrelation:
    if not isinstance(model, KCorrelation):
        raise ArgumentError("model", "must be a k-correlation model "
                            "(rb.model('k-correlation', ...))", value=type(model).__name__)
    return model


def _check_count(name: str, v: Any, least: int) -> int:
    if isinstance(v, bool) or not isinstance(v, int | np.integer) or v < least:
        raise ArgumentError(name, f"must be an integer >= {least}", value=v)
    return int(v)


def tis(model: KCorrelation, theta_i: ArrayLike, *, polarization: Any = None,
        n_psi: int = 128, n_radial: int = 192) -> np.ndarray | float:
    """Total integrated scatter (directional-hemispherical reflectance) of a k-correlation
    model at incidence ``theta_i`` (radians, any shape), by the quadrature of the module notes.

    Parameters
    ----------
    model : KCorrelation
        The model (with its wavelength).
    theta_i : array_like
        Incidence zenith angles in ``[0, pi/2]`` radians.
    polarization : None, "s", "p" or float
        Incident polarization (TR75's ``gamma``), unpolarized detection.
    n_psi, n_radial : int
        Azimuthal (midpoint) and radial (Gauss–Legendre) node counts.

    Returns
    -------
    numpy.ndarray or float
        The shape of ``theta_i`` (a float for a scalar).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> from roughbrdf.models.kcorr import tis, tis_smooth_limit
    >>> m = rb.model("k-correlation", A=1e-3, B=60.0, C=4.0, n=1.5, wavelength=0.5)
    >>> round(tis(m, 0.0) / tis_smooth_limit(m, 0.0), 2)   # B >> lambda, C > 2: the limit
    1.0
    """
    m = _check_model(model)
    lam = m.wavelength
    n_psi = _check_count("n_psi", n_psi, 4)
    n_radial = _check_count("n_radial", n_radial, 2)
    ti = check_zenith(theta_i, "theta_i")
    gamma = Polarization.parse(polarization).kernel_gamma()
    if gamma.ndim:
        raise ArgumentError("polarization", "tis takes one polarization for all incidences",
                            value=polarization)
    a, b, c = (m.params[x] for x in ("A", "B", "C"))
    shape = ti.shape
    t = ti.reshape(-1, 1, 1)
    b0 = np.sin(t)
    psi = (np.arange(n_psi) + 0.5) * (2.0 * math.pi / n_psi)
    cp, sp = np.cos(psi)[None, :, None], np.sin(psi)[None, :, None]
    rho_max = -b0 * cp + np.sqrt(np.maximum(1.0 - (b0 * sp) ** 2, 0.0))
    e = 1.0 - 0.5 * c
    h_max = _cumulative(e, np.log1p((b * rho_max / lam) ** 2))
    g_max = lam * lam * a / (2.0 * b * b) * h_max  # G(rho_max) per psi
    s, ws = _radial_rule(n_radial)
    log_u = _inverse_cumulative(e, s[None, None, :] * h_max)
    rho = lam / b * np.sqrt(np.expm1(log_u))
    # rounding can put the last nodes a hair beyond the unit circle: rho <= rho_max
    rho = np.minimum(rho, rho_max)
    bx, by = b0 + rho * cp, rho * sp
    bm = np.minimum(np.hypot(bx, by), 1.0)
    theta_r = np.arctan2(bm, np.sqrt(1.0 - bm * bm))
    phi = np.arctan2(by, bx)
    tt = np.broadcast_to(t, theta_r.shape)
    g = np.asarray(gamma, dtype=np.float64)
    vals = _kernels.evaluate(kcorr_drive, np.ascontiguousarray(tt), theta_r, phi, g, m._pack(),
                             WITHOUT_PSD)
    radial = (np.asarray(vals) * ws[None, None, :]).sum(axis=2)
    out = (g_max[..., 0] * radial).sum(axis=1) * (2.0 * math.pi / n_psi)
    out = out.reshape(shape)
    return float(out) if out.ndim == 0 else out


def tis_smooth_limit(model: KCorrelation, theta_i: ArrayLike, *, polarization: Any = None
                     ) -> np.ndarray | float:
    """The small-roughness closed form ``(4 pi sigma cos theta_i / lambda)^2 R(theta_i)``
    (module notes: valid for ``C > 2`` and ``B >> lambda``; ``sigma`` the total rms roughness).

    Raises :class:`~roughbrdf.errors.ArgumentError` naming ``C`` for ``C <= 2`` (no finite
    total sigma).
    """
    m = _check_model(model)
    lam = m.wavelength
    ti = check_zenith(theta_i, "theta_i")
    sigma = m.sigma_rms()
    pol = "unpolarized" if polarization is None else polarization
    r = reflectance(np.cos(ti), m.params["n"], m.params["k"], pol)
    out = (4.0 * math.pi * sigma * np.cos(ti) / lam) ** 2 * r
    return float(out) if np.ndim(out) == 0 else np.asarray(out)
