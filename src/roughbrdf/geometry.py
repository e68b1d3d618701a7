"""The common frame, conversions to each paper's own angles, and the derived angles.

Common frame (docs/models.md §1.1, the only one used inside roughbrdf)
-----------------------------------------------------------------
* mean-surface normal ``+z``; plane of incidence x-z; the source on the ``-x`` side;
* ``theta_i`` incidence zenith, ``theta_r`` reflection zenith, ``phi`` azimuth of the reflected
  ray with ``phi = 0`` on the forward (specular) side and ``phi = pi`` on the source (retro) side;
* unit vectors, both pointing away from the surface::

      w_i = (-sin theta_i, 0, cos theta_i)
      w_r = (sin theta_r cos phi, sin theta_r sin phi, cos theta_r)

* half vector ``h = (w_i + w_r)/|w_i + w_r|``, ``|w_i + w_r| = 2 cos theta_d``;
  ``theta_h`` is the facet-normal zenith, ``theta_d`` the local angle of incidence on the facet.

All angles are radians. Each paper's convention is reached only through the functions here:

==========  ==========================  ======================================================
paper       its angles                  functions
==========  ==========================  ======================================================
TS67        (psi, theta, phi)           :func:`from_ts67`, :func:`to_ts67` (same as common)
TR75        (beta, elevation, psi_TR)   :func:`from_tr75`, :func:`to_tr75` (psi_TR = pi - phi)
RB08        (alpha, beta, alpha0)       :func:`from_rb08`, :func:`to_rb08` (direction cosines)
MERL        (theta_h, theta_d, phi_d)   :func:`from_rusinkiewicz`, :func:`to_rusinkiewicz`
Zemax       (radial, azimuth) about     :func:`specular_to_common`, :func:`common_to_specular`
            the specular direction      (the tabular BSDF's frame, :mod:`roughbrdf.io.zemax`)
==========  ==========================  ======================================================

Layout: this module holds the validation of angles, the compiled scalar parts and their NumPy
front ends; the conversions between frames (the table above, with :func:`unit_vectors` and
:func:`angles_from_vectors`) are in :mod:`roughbrdf.geometry_frames` (NumPy, not used inside
kernels) and importable from here, which is where to import every name of the table from.

The scalar functions (``half_vector``, ``ts67_projected``, ``tr75_eta_from_h``) are Numba
parts used inside every model kernel; the ufuncs of the same names without the suffix are their
NumPy front ends.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from ._kernels import SINCOS_MAX_ARG, TINY, jit, sincos, ufunc
from ._kernels.vmath import vatan2
from .errors import ArgumentError
from .geometry_frames import (
    angles_from_vectors,
    common_to_specular,
    from_rb08,
    from_rusinkiewicz,
    from_signed_angle,
    from_tr75,
    from_ts67,
    signed_angle,
    specular_to_common,
    to_rb08,
    to_rusinkiewicz,
    to_tr75,
    to_ts67,
    unit_vectors,
)

HALF_PI = 0.5 * math.pi

__all__ = [
    "as_angle_array",
    "check_angles",
    "check_broadcast",
    "check_zenith",
    "unit_vectors",
    "angles_from_vectors",
    "half_vector",
    "theta_h",
    "theta_d",
    "phi_h",
    "ts67_projected",
    "ts67_psi_p",
    "ts67_theta_p",
    "tr75_eta",
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
# validation
# --------------------------------------------------------------------------------------------
def as_angle_array(x: ArrayLike, name: str) -> np.ndarray:
    """``x`` as a float64 array, or :class:`~roughbrdf.errors.ArgumentError` naming ``name``.

    Accepts numbers (``bool`` too) and arrays of them; ``None``, strings, complex numbers,
    ragged or object sequences (``[0.1, None]``) and numbers beyond the float range are refused
    with the argument's name and the value (NumPy would read ``None`` as NaN and ``"0.5"`` as
    0.5).

    Examples
    --------
    >>> as_angle_array([0.1, 0.2], "theta_r")
    array([0.1, 0.2])
    >>> as_angle_array(None, "theta_r")
    Traceback (most recent call last):
    ...
    roughbrdf.errors.ArgumentError: theta_r = None: must be a number or an array of numbers \
(radians)
    """
    if isinstance(x, np.ndarray) and x.dtype.kind in "fub" or isinstance(x, float | np.floating):
        return np.asarray(x, dtype=np.float64)  # the common case, without inspecting values
    need = "must be a number or an array of numbers (radians)"
    if x is None or isinstance(x, str | bytes):
        raise ArgumentError(name, need, value=x)
    try:
        raw = np.asarray(x)
    except (TypeError, ValueError, OverflowError):
        raise ArgumentError(name, need, value=_shown(x)) from None
    if raw.dtype.kind not in "fiub":
        bad = next((v for v in raw.ravel() if not _is_real(v)), x) if raw.dtype == object else x
        raise ArgumentError(name, need + (f"; found {_shown(bad)!r}" if bad is not x else ""),
                            value=_shown(x))
    try:
        return np.asarray(raw, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):  # e.g. integers beyond the float range
        raise ArgumentError(name, need, value=_shown(x)) from None


def _is_real(v: object) -> bool:
    # a real number that converts to float (bool, int within range, float, NumPy reals)
    if v is None or isinstance(v, str | bytes | complex | np.complexfloating):
        return False
    try:
        float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        return False
    return True


def _shown(x: object) -> object:
    # the value as shown in a message: short arrays as lists, long ones abbreviated
    text = repr(x)
    return x if len(text) <= 80 else _Abbrev(text[:70] + " ...")


class _Abbrev:
    """A long value shown abbreviated in messages."""

    def __init__(self, text: str) -> None:
        self.text = text

    def __repr__(self) -> str:
        return self.text

    __str__ = __repr__


def _first_bad(arr: np.ndarray, bad: np.ndarray) -> float:
    return float(arr[bad].flat[0])


def check_zenith(x: ArrayLike, name: str, *, open_upper: bool = False) -> np.ndarray:
    """Return ``x`` as a float array after checking it is a zenith angle in [0, pi/2] radians.

    Raises
    ------
    roughbrdf.errors.ArgumentError
        (a ``ValueError``) if ``x`` is not a number or an array of numbers (``None``
        included), or if any value is NaN/inf or outside ``[0, pi/2]`` (``[0, pi/2)`` with
        ``open_upper``); the message names ``name`` and the first offending value (in radians;
        the CLI shows it in degrees).
    """
    arr = as_angle_array(x, name)
    if arr.size:
        # fast path: two passes without temporaries (min/max propagate NaN, so NaN fails here)
        lo, hi = arr.min(), arr.max()
        if lo >= 0.0 and (hi < HALF_PI if open_upper else hi <= HALF_PI):
            return arr
    bad = ~np.isfinite(arr)
    if bad.any():
        raise ArgumentError(name, "must be finite", value=_first_bad(arr, bad), unit="rad")
    upper = arr >= HALF_PI if open_upper else arr > HALF_PI
    bad = (arr < 0.0) | upper
    if bad.any():
        v = _first_bad(arr, bad)
        rng = "[0, pi/2) rad, i.e. [0, 90) deg" if open_upper else "[0, pi/2] rad, i.e. [0, 90] deg"
        raise ArgumentError(
            name, f"must be in {rng}"
            + (" (the model divides by its cosine)" if open_upper and v == HALF_PI else ""),
            value=v, unit="rad")
    return arr


def check_broadcast(**arrays: np.ndarray) -> tuple[int, ...]:
    """The broadcast shape of the named arrays, or :class:`~roughbrdf.errors.ArgumentError`
    naming the first two that do not broadcast, with their shapes.

    Examples
    --------
    >>> check_broadcast(theta_i=np.zeros(3), theta_r=np.zeros((2, 1)))
    (2, 3)
    >>> check_broadcast(theta_i=np.zeros(3), theta_r=np.zeros(4))
    Traceback (most recent call last):
    ...
    roughbrdf.errors.ArgumentError: theta_i (3,) and theta_r (4,) do not broadcast (NumPy \
rules: each dimension must be equal or 1)
    """
    shape: tuple[int, ...] = ()
    seen: list[tuple[str, tuple[int, ...]]] = []
    for name, arr in arrays.items():
        s = tuple(np.shape(arr))
        try:
            shape = np.broadcast_shapes(shape, s)
        except ValueError:
            other = next((n, t) for n, t in seen if not _broadcastable(t, s))
            raise ArgumentError(
                name, f"{other[0]} {other[1]} and {name} {s} do not broadcast (NumPy rules: "
                f"each dimension must be equal or 1)") from None
        seen.append((name, s))
    return shape


def _broadcastable(a: tuple[int, ...], b: tuple[int, ...]) -> bool:
    try:
        np.broadcast_shapes(a, b)
    except ValueError:
        return False
    return True


def check_angles(
    theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike, *, grazing_incidence: bool = True
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Validate and convert a (theta_i, theta_r, phi) triple of the common frame.

    ``grazing_incidence=False`` rejects ``theta_i = pi/2`` for models that divide by
    ``cos theta_i``. ``phi`` may be any finite angle (it is periodic); azimuths beyond
    ``roughbrdf._kernels.vmath.SINCOS_MAX_ARG`` (8e5 rad) are reduced to [0, 2 pi) here, because the
    kernels' sine/cosine are accurate only up to there.

    Raises
    ------
    roughbrdf.errors.ArgumentError
        (a ``ValueError``) naming the argument: not a number or array of numbers (``None``
        included), a zenith angle outside the hemisphere, a non-finite azimuth, or (naming
        both arrays and their shapes) arrays that do not broadcast together.
    """
    ti = check_zenith(theta_i, "theta_i", open_upper=not grazing_incidence)
    tr = check_zenith(theta_r, "theta_r")
    ph = as_angle_array(phi, "phi")
    if ph.size and not (ph.min() >= -SINCOS_MAX_ARG and ph.max() <= SINCOS_MAX_ARG):
        bad = ~np.isfinite(ph)
        if bad.any():
            raise ArgumentError("phi", "must be finite (any angle: the azimuth is periodic)",
                                value=_first_bad(ph, bad), unit="rad")
        ph = np.mod(ph, 2.0 * math.pi)
    check_broadcast(theta_i=ti, theta_r=tr, phi=ph)
    return ti, tr, ph


# --------------------------------------------------------------------------------------------
# scalar parts (compiled)
# --------------------------------------------------------------------------------------------
@jit(inline=True)
def half_vector(ti, tr, phi):
    """Half vector of the common frame, scalar part.

    Returns ``(hx, hy, hz, cos_d, cos_i, cos_r, sin_i)`` where ``h`` is the unit half vector
    (``hz = cos theta_h``) and ``cos_d = w_i . h = |w_i + w_r|/2``.
    """
    si, ci = sincos(ti)  # vectorizable sin/cos (see roughbrdf._kernels.vmath.sincos)
    sr, cr = sincos(tr)
    sp, cp = sincos(phi)
    return half_vector_cs(si, ci, sr, cr, sp, cp)


@jit(inline=True)
def half_vector_cs(si, ci, sr, cr, sp, cp):
    """:func:`half_vector` from the sines and cosines of ``theta_i``, ``theta_r`` and ``phi``
    (for directions known by them, e.g. refracted into a coat: ``sin theta' = sin theta/n``,
    no ``asin``)."""
    # cos(pi/2) is 6e-17, not 0; clip so that exact grazing gives exactly zero cosines.
    ci = 0.0 if ci < 1e-15 else ci
    cr = 0.0 if cr < 1e-15 else cr
    sx = sr * cp - si
    sy = sr * sp
    sz = ci + cr
    length = math.sqrt(sx * sx + sy * sy + sz * sz)
    if length == 0.0:
        # w_i = -w_r: theta_i = theta_r = 90 deg and phi = 0 (the forward grazing pair). The
        # half vector is undefined and the limits depend on the path (G -> 1 along the specular
        # direction, G = 0 at grazing incidence). Return a horizontal "half vector" with
        # cos_d = 0, so that every model gives its shadowed limit (nothing reflects) there.
        return 1.0, 0.0, 0.0, 0.0, ci, cr, si
    # TINY: see roughbrdf._kernels.vmath.TINY (compiled code runs both sides of the branch)
    inv = 1.0 / (length + TINY)
    return sx * inv, sy * inv, sz * inv, 0.5 * length, ci, cr, si


@jit
def ts67_projected(ti, tr, phi):
    """TS67 projected angles ``(psi_p, theta_p, alpha_signed)`` (docs/models.md §2.4, vector form).

    The projection plane is spanned by ``z`` and the horizontal direction ``u`` of the facet tilt;
    ``psi_p >= 0`` and ``theta_p = psi_p + 2 alpha_signed`` with the paper's sign convention
    (positive on the far side of the normal from the source). Used instead of the printed Eq. 14,
    whose arcsin branches are wrong for 19 % of geometries.
    """
    hx, hy, hz, cd, ci, cr, si = half_vector(ti, tr, phi)
    sr = sincos(tr)[0]
    sp, cp = sincos(phi)
    wrx = sr * cp
    wry = sr * sp
    hxy = math.sqrt(hx * hx + hy * hy)
    # alpha = 0 (specular): any horizontal u works; take the plane of incidence. (TINY keeps
    # compiled code, which evaluates both sides of the select, free of 0/0.)
    tilted = hxy > 1e-300
    inv = 1.0 / (hxy + TINY)
    ux = hx * inv if tilted else 1.0
    uy = hy * inv if tilted else 0.0
    # vatan2: the vectorizable atan2 (roughbrdf._kernels.vmath), <= 1 ulp
    alpha = vatan2(hxy, hz)  # = acos(hz), without acos's sqrt(eps) error near alpha = 0
    a_i = vatan2(-si * ux, ci)
    a_r = vatan2(wrx * ux + wry * uy, cr)
    if a_i <= 0.0:
        return -a_i, a_r, alpha
    return a_i, -a_r, -alpha


@jit(inline=True)
def tr75_eta_from_h(si, ci, hx, hy, hz):
    """TR75 angle eta between the local and the macroscopic planes of incidence (Eq. 23).

    ``sin eta sin s = h_y`` and
    ``cos eta sin s = (w_i x h)_y = sin(theta_i) h_z + cos(theta_i) h_x``
    (docs/models.md §3.5, recommended sign). At ``s = 0`` both vanish and eta = 0 (R_s = R_p
    there); below ``sin s = 1e-12`` the two are round-off, and eta = 0 is returned too.
    Vectorizable (:func:`roughbrdf._kernels.vmath.vatan2`); the model kernels use the cheaper
    :func:`tr75_eta_xy` instead of the angle.
    """
    x = si * hz + ci * hx
    eta = vatan2(hy, x)
    return 0.0 if x * x + hy * hy < 1e-24 else eta


@jit(inline=True)
def tr75_eta_xy(si, ci, hx, hy, hz):
    """``sin(s) (cos eta, sin eta)`` of :func:`tr75_eta_from_h`, unnormalized (no sqrt)."""
    return si * hz + ci * hx, hy


@jit(inline=True)
def tr75_eta_cs(si, ci, hx, hy, hz):
    """``(cos eta, sin eta)`` of :func:`tr75_eta_from_h` without ``atan2`` (vectorizable).

    ``(1, 0)`` at ``s = 0`` (the local plane of incidence is undefined; R_s = R_p there), and
    below ``sin s = 1e-12``, where the direction is round-off.
    """
    x = si * hz + ci * hx
    length = math.sqrt(x * x + hy * hy)
    inv = 1.0 / (length + TINY)
    if length > 1e-12:
        return x * inv, hy * inv
    return 1.0, 0.0


# --------------------------------------------------------------------------------------------
# NumPy front ends of the scalar parts
# --------------------------------------------------------------------------------------------
@ufunc(3)
def _theta_h(ti, tr, phi):
    hx, hy, hz, cd, ci, cr, si = half_vector(ti, tr, phi)
    # atan2 instead of acos(hz): accurate also near theta_h = 0 (acos loses half the digits)
    return math.atan2(math.sqrt(hx * hx + hy * hy), hz)


@ufunc(3)
def _theta_d(ti, tr, phi):
    hx, hy, hz, cd, ci, cr, si = half_vector(ti, tr, phi)
    # sin(theta_d) = |w_i - w_r|/2 and cos(theta_d) = |w_i + w_r|/2: atan2 of the two is
    # accurate also near theta_d = 0 (the retro direction), unlike acos(cos_d)
    sr, cr_ = sincos(tr)
    sp, cp = sincos(phi)
    dx = -si - sr * cp
    dy = -sr * sp
    dz = ci - cr
    return math.atan2(0.5 * math.sqrt(dx * dx + dy * dy + dz * dz), cd)


@ufunc(3)
def _phi_h(ti, tr, phi):
    sr = math.sin(tr)
    return math.atan2(sr * math.sin(phi), sr * math.cos(phi) - math.sin(ti))


@ufunc(3)
def _psi_p(ti, tr, phi):
    return ts67_projected(ti, tr, phi)[0]


@ufunc(3)
def _theta_p(ti, tr, phi):
    return ts67_projected(ti, tr, phi)[1]


@ufunc(3)
def _eta(ti, tr, phi):
    hx, hy, hz, cd, ci, cr, si = half_vector(ti, tr, phi)
    return tr75_eta_from_h(si, ci, hx, hy, hz)


def theta_h(theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike) -> np.ndarray:
    """Zenith angle of the half vector (facet normal), radians; TS67 alpha, TR75 alpha."""
    return _theta_h(*check_angles(theta_i, theta_r, phi))


def theta_d(theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike) -> np.ndarray:
    """Local angle of incidence on the facet, radians; TS67 psi', TR75 s."""
    return _theta_d(*check_angles(theta_i, theta_r, phi))


def phi_h(theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike) -> np.ndarray:
    """Azimuth of the half vector in the common frame (docs/models.md §1.1), radians."""
    return _phi_h(*check_angles(theta_i, theta_r, phi))


def ts67_psi_p(theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike) -> np.ndarray:
    """TS67 projected incidence angle psi_p >= 0 (docs/models.md §2.4)."""
    return _psi_p(*check_angles(theta_i, theta_r, phi))


def ts67_theta_p(theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike) -> np.ndarray:
    """TS67 projected reflection angle theta_p (signed, docs/models.md §2.4)."""
    return _theta_p(*check_angles(theta_i, theta_r, phi))


def tr75_eta(theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike) -> np.ndarray:
    """TR75 eta: angle from the macroscopic to the local plane of incidence (Eq. 23), radians."""
    return _eta(*check_angles(theta_i, theta_r, phi))
