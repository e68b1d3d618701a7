"""Conversions between the common frame and other angles (NumPy; not used inside kernels).

The common frame is :mod:`roughbrdf.geometry`'s (docs/models.md §1.1): normal ``+z``, the source
on the ``-x`` side, ``w_i = (-sin theta_i, 0, cos theta_i)``,
``w_r = (sin theta_r cos phi, sin theta_r sin phi, cos theta_r)``. Every name here is importable
from :mod:`roughbrdf.geometry` (``rb.geometry.to_tr75``...), which is where to import it from.

==============  ==========================  ================================================
frame           its angles                  functions
==============  ==========================  ================================================
vectors         ``(w_i, w_r)``              :func:`unit_vectors`, :func:`angles_from_vectors`
TS67            (psi, theta, phi)           :func:`from_ts67`, :func:`to_ts67`
TR75            (beta, elevation, psi_TR)   :func:`from_tr75`, :func:`to_tr75`
RB08            (alpha, beta, alpha0)       :func:`from_rb08`, :func:`to_rb08`
MERL            (theta_h, theta_d, phi_d)   :func:`from_rusinkiewicz`, :func:`to_rusinkiewicz`
in-plane        signed theta_r              :func:`signed_angle`, :func:`from_signed_angle`
specular        (radial, azimuth)           :func:`specular_to_common`,
                                            :func:`common_to_specular`
==============  ==========================  ================================================

The specular frame (Zemax OpticStudio's tabular BSDF, :mod:`roughbrdf.io.zemax`, where the
format and its sources are)
---------------------------------------------------------------------------------------------
A direction is given by its angle ``radial`` from the specular direction
``s = (sin t, 0, cos t)`` (``t``: Zemax's AngleOfIncidence, which for a BRDF is ``theta_i``) and
its ``azimuth`` about ``s``: azimuth 0 points from ``s`` toward the surface normal, and the
azimuth increases counter-clockwise seen from above the sample::

    w = cos r s + sin r (cos a u0 + sin a v),  u0 = (-cos t, 0, sin t),  v = s x u0 = (0, -1, 0)

(at normal incidence azimuth 0 points to the source side, ``phi = pi``, the limit of ``u0``).
``radial`` is a true angle on the sphere (not a projected distance of direction cosines) and
runs past 90 deg, up to ``90 + t`` toward the normal; ``theta_r > pi/2`` is below the horizon.
This is also the specular coordinate system of libbsdf (K. Ryo, ``SpecularCoordinateSystem``,
MPL-2.0); the azimuth origin is pinned by public measured files (``tests/io/test_io_zemax.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

#: pi/2 (the same float as :data:`roughbrdf.geometry.HALF_PI`)
HALF_PI = 0.5 * math.pi

__all__ = [
    "unit_vectors",
    "angles_from_vectors",
    "from_ts67",
    "to_ts67",
    "from_tr75",
    "to_tr75",
    "from_rb08",
    "to_rb08",
    "from_rusinkiewicz",
    "to_rusinkiewicz",
    "signed_angle",
    "from_signed_angle",
    "specular_to_common",
    "common_to_specular",
]


# --------------------------------------------------------------------------------------------
# vectors and the papers' angles
# --------------------------------------------------------------------------------------------
def unit_vectors(
    theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors ``(w_i, w_r)`` of the common frame, each of shape ``(..., 3)``."""
    ti, tr, ph = (np.asarray(v, dtype=float) for v in (theta_i, theta_r, phi))
    ti, tr, ph = np.broadcast_arrays(ti, tr, ph)
    wi = np.stack([-np.sin(ti), np.zeros_like(ti), np.cos(ti)], axis=-1)
    wr = np.stack([np.sin(tr) * np.cos(ph), np.sin(tr) * np.sin(ph), np.cos(tr)], axis=-1)
    return wi, wr


def angles_from_vectors(w_i: ArrayLike, w_r: ArrayLike) -> tuple[np.ndarray, ...]:
    """Common-frame angles from arbitrary unit vectors ``(..., 3)`` (isotropic surfaces).

    The pair is rotated about ``z`` so that ``w_i`` lies in the x-z plane on the ``-x`` side.
    """
    wi = np.asarray(w_i, dtype=float)
    wr = np.asarray(w_r, dtype=float)
    ti = np.arccos(np.clip(wi[..., 2], -1.0, 1.0))
    tr = np.arccos(np.clip(wr[..., 2], -1.0, 1.0))
    phi_i = np.arctan2(wi[..., 1], wi[..., 0])
    phi_r = np.arctan2(wr[..., 1], wr[..., 0])
    phi = np.mod(phi_r - phi_i + np.pi, 2 * np.pi)  # source at azimuth pi -> forward at 0
    phi = np.where(phi > np.pi, phi - 2 * np.pi, phi)
    return ti, tr, phi


def _wrap(phi: np.ndarray) -> np.ndarray:
    """Wrap an azimuth to (-pi, pi]."""
    out = np.mod(phi + np.pi, 2 * np.pi) - np.pi
    return np.where(out == -np.pi, np.pi, out)


def from_ts67(psi: ArrayLike, theta: ArrayLike, phi: ArrayLike) -> tuple[np.ndarray, ...]:
    """TS67 ``(psi, theta, phi)`` -> common frame; TS67's frame is the common frame (§1.3)."""
    return tuple(np.asarray(v, dtype=float) for v in (psi, theta, phi))


def to_ts67(theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike) -> tuple[np.ndarray, ...]:
    """Common frame -> TS67 ``(psi, theta, phi)`` (identical conventions, docs/models.md §1.3)."""
    return tuple(np.asarray(v, dtype=float) for v in (theta_i, theta_r, phi))


def from_tr75(beta: ArrayLike, elevation: ArrayLike, psi: ArrayLike) -> tuple[np.ndarray, ...]:
    """TR75 ``(beta, elevation theta, azimuth psi from the source side)`` -> common frame.

    ``theta_r = pi/2 - elevation``, ``phi = pi - psi`` (docs/models.md §1.3; TR75 report
    Eqs. 9, 11).
    """
    b = np.asarray(beta, dtype=float)
    return b, HALF_PI - np.asarray(elevation, dtype=float), _wrap(np.pi - np.asarray(psi, float))


def to_tr75(theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike) -> tuple[np.ndarray, ...]:
    """Common frame -> TR75 ``(beta, elevation, psi)``; ``psi`` in [0, 2 pi)."""
    psi = np.mod(np.pi - np.asarray(phi, dtype=float), 2 * np.pi)
    return np.asarray(theta_i, float), HALF_PI - np.asarray(theta_r, float), psi


def to_rb08(theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike) -> tuple[np.ndarray, ...]:
    """Common frame -> RB08 direction cosines ``(alpha, beta, alpha0)`` (docs/models.md §4.3).

    ``alpha = sin theta_s cos phi``, ``beta = sin theta_s sin phi``, ``alpha0 = sin theta_i``;
    the specular point is ``(alpha0, 0)`` and the retro point ``(-alpha0, 0)``.
    """
    tr = np.asarray(theta_r, dtype=float)
    ph = np.asarray(phi, dtype=float)
    return np.sin(tr) * np.cos(ph), np.sin(tr) * np.sin(ph), np.sin(np.asarray(theta_i, float))


def from_rb08(alpha: ArrayLike, beta: ArrayLike, alpha0: ArrayLike) -> tuple[np.ndarray, ...]:
    """RB08 direction cosines -> common frame; requires ``alpha^2 + beta^2 <= 1``."""
    a = np.asarray(alpha, dtype=float)
    b = np.asarray(beta, dtype=float)
    r = np.hypot(a, b)
    if np.any(r > 1.0 + 1e-12):
        raise ValueError(f"direction cosines outside the unit disk: |(alpha, beta)| = {r.max()!r}")
    a0 = np.asarray(alpha0, dtype=float)
    if np.any((a0 < 0) | (a0 > 1)):
        raise ValueError(f"alpha0 = sin(theta_i) must be in [0, 1], got {a0!r}")
    return np.arcsin(a0), np.arcsin(np.minimum(r, 1.0)), np.arctan2(b, a)


def _rot_z(v: np.ndarray, ang: np.ndarray) -> np.ndarray:
    c, s = np.cos(ang), np.sin(ang)
    return np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1], v[..., 2]], -1)


def _rot_y(v: np.ndarray, ang: np.ndarray) -> np.ndarray:
    c, s = np.cos(ang), np.sin(ang)
    return np.stack([c * v[..., 0] + s * v[..., 2], v[..., 1], -s * v[..., 0] + c * v[..., 2]], -1)


def to_rusinkiewicz(
    theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike
) -> tuple[np.ndarray, ...]:
    """Common frame -> Rusinkiewicz (1998) half/difference angles ``(theta_h, theta_d, phi_d)``.

    ``d`` is ``w_i`` expressed in the frame where ``h`` is the pole: rotate by ``-phi_h`` about
    z, then by ``-theta_h`` about y; ``phi_d = atan2(d_y, d_x)`` in (-pi, pi].
    """
    wi, wr = unit_vectors(theta_i, theta_r, phi)
    s = wi + wr
    norm = np.linalg.norm(s, axis=-1, keepdims=True)
    h = s / np.where(norm == 0, 1.0, norm)
    th = np.arccos(np.clip(h[..., 2], -1, 1))
    ph = np.arctan2(h[..., 1], h[..., 0])
    d = _rot_y(_rot_z(wi, -ph), -th)
    td = np.arccos(np.clip(d[..., 2], -1, 1))
    pd = np.arctan2(d[..., 1], d[..., 0])
    return th, td, pd


def from_rusinkiewicz(
    theta_h: ArrayLike, theta_d: ArrayLike, phi_d: ArrayLike
) -> tuple[np.ndarray, ...]:
    """Rusinkiewicz ``(theta_h, theta_d, phi_d)`` -> common frame ``(theta_i, theta_r, phi)``.

    Directions whose ``w_i`` or ``w_r`` falls below the horizon give NaN (they are not BRDF
    geometries); isotropy fixes ``phi_h`` so that the source lies at azimuth pi.
    """
    th, td, pd = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (theta_h, theta_d,
                                                                          phi_d)))
    d = np.stack([np.sin(td) * np.cos(pd), np.sin(td) * np.sin(pd), np.cos(td)], -1)
    dr = d * np.array([-1.0, -1.0, 1.0])  # w_r is w_i mirrored about h
    wi = _rot_y(d, th)
    wr = _rot_y(dr, th)
    ti, tr, phi = angles_from_vectors(wi, wr)
    below = (wi[..., 2] < -1e-12) | (wr[..., 2] < -1e-12)
    return (np.where(below, np.nan, ti), np.where(below, np.nan, tr),
            np.where(below, np.nan, phi))


def signed_angle(theta_r: ArrayLike, phi: ArrayLike) -> np.ndarray:
    """In-plane signed reflection angle: ``+theta_r`` at phi = 0, ``-theta_r`` at phi = pi."""
    tr = np.asarray(theta_r, dtype=float)
    return np.where(np.cos(np.asarray(phi, dtype=float)) < 0, -tr, tr)


def from_signed_angle(theta_signed: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Signed in-plane angle -> ``(theta_r, phi)`` with phi in {0, pi}."""
    t = np.asarray(theta_signed, dtype=float)
    return np.abs(t), np.where(t < 0, np.pi, 0.0)


# --------------------------------------------------------------------------------------------
# the specular frame: (radial, azimuth) about the specular direction <-> the common frame
# --------------------------------------------------------------------------------------------
def specular_to_common(theta_s: ArrayLike, radial: ArrayLike, azimuth: ArrayLike
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Common-frame ``(theta_r, phi, cos_theta_r)`` of the direction at ``radial`` from the
    specular direction ``theta_s`` (Zemax's AngleOfIncidence), at ``azimuth`` about it
    (radians; the frame in the module docstring). ``theta_r > pi/2`` (``cos_theta_r < 0``)
    is below the horizon.

    Examples
    --------
    >>> import math
    >>> t, p, c = specular_to_common(math.radians(30), 0.0, 1.0)   # radial 0: the specular
    >>> round(math.degrees(float(t)), 9), float(p)
    (30.0, 0.0)
    >>> t, p, c = specular_to_common(math.radians(30), math.radians(30), 0.0)  # toward normal
    >>> round(math.degrees(float(t)), 9)
    0.0
    >>> t, p, c = specular_to_common(math.radians(30), math.radians(10), math.pi)  # outward
    >>> round(math.degrees(float(t)), 9), round(float(p), 12)
    (40.0, 0.0)
    """
    st, ct = np.sin(theta_s), np.cos(theta_s)
    sr, cr = np.sin(radial), np.cos(radial)
    sa, ca = np.sin(azimuth), np.cos(azimuth)
    wx = cr * st - sr * ca * ct
    wy = -sr * sa
    wz = cr * ct + sr * ca * st
    # atan2 keeps full accuracy near the specular direction and the pole (arccos would not)
    theta_r = np.arctan2(np.hypot(wx, wy), wz)
    return theta_r, np.arctan2(wy, wx), wz


def common_to_specular(theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike
                       ) -> tuple[np.ndarray, np.ndarray]:
    """``(radial, azimuth)`` about the specular direction of common-frame directions
    (radians; azimuth in ``[0, 2 pi)``), the inverse of :func:`specular_to_common` (the
    specular angle is ``theta_i``).

    Examples
    --------
    >>> import math
    >>> r, a = common_to_specular(math.radians(30), math.radians(30), 0.0)
    >>> round(float(r), 12)
    0.0
    >>> r, a = common_to_specular(math.radians(30), 0.0, 0.0)
    >>> round(math.degrees(float(r)), 9), round(math.degrees(float(a)), 9)
    (30.0, 0.0)
    """
    st, ct = np.sin(theta_i), np.cos(theta_i)
    sr = np.sin(theta_r)
    wx, wy, wz = sr * np.cos(phi), sr * np.sin(phi), np.cos(theta_r)
    w_s = wx * st + wz * ct      # along the specular direction s
    w_u = -wx * ct + wz * st     # along u0 (toward the normal)
    w_v = -wy                    # along v = s x u0
    radial = np.arctan2(np.hypot(w_u, w_v), w_s)
    return radial, np.mod(np.arctan2(w_v, w_u), 2 * math.pi)
