"""Mueller matrices: Stokes conventions, Jones to Mueller, the facet term, bases.

The BRDF Mueller matrix ``M`` (sr⁻¹) of a model maps the Stokes vector of the incident
irradiance to the Stokes vector of the reflected radiance, ``S_r = M S_i`` with Stokes vectors
``[I, Q, U, V]`` as **column** vectors; ``M[..., 0, 0]`` is the unpolarized BRDF. Every
convention below is NIST SCATMECH's (``docs/convent.htm``, ``code/jmatrix.cpp``,
``code/brdf.cpp``, SCATMECH 7.x), so that ``model.mueller`` and SCATMECH's
``BRDF_Model::Mueller(thetai, thetas, phis, 0, psps|xyxy)`` agree element by element
(``docs/models.md`` §11; ``tests/core/test_mueller.py``).

Conventions
-----------
* **Fields.** Time dependence ``exp(-i omega t)``; complex index ``n + i k`` with ``k >= 0``
  absorbing (the library's, ``docs/models.md`` §1.4).
* **Jones vectors** ``(E1, E2)`` on a right-handed basis ``{e1, e2, k}``, ``k`` the direction
  of propagation. In the ``psps`` basis ``e1 = s``, ``e2 = p``; in ``xyxy`` ``e1 = y``,
  ``e2 = x`` (below).
* **Stokes vector** ``I = |E1|² + |E2|²``, ``Q = |E1|² - |E2|²``, ``U = 2 Re(E1* E2)``,
  ``V = 2 Im(E1* E2)``. Hence (psps):

  ===============  ==========================================================================
  ``(1, 0, 0, 0)``  unpolarized
  ``(1, 1, 0, 0)``  s-polarized (**Q > 0 is s**; in xyxy, y)
  ``(1, -1, 0, 0)`` p-polarized
  ``(1, 0, 1, 0)``  linear along ``s + p`` (in xyxy, ``y + x``)
  ``(1, 0, 0, 1)``  Jones ``(1, i)``: the field turns from ``e1`` to ``e2``, i.e.
                    counter-clockwise seen by an observer looking toward the source —
                    SCATMECH's "left circular" (LCP), Born & Wolf's left-handed, positive
                    helicity (IEEE right-hand). ``V`` is the same in psps and xyxy (both bases
                    are right-handed about ``k``).
  ===============  ==========================================================================

* **TR75's polarization angle** ``gamma`` (``polarization=`` of every scalar evaluation,
  ``docs/models.md`` §3.5: angle of the incident electric field from the plane of incidence,
  ``0`` = p, ``pi/2`` = s) is the Jones vector ``(sin gamma, cos gamma)`` in psps, the Stokes
  vector ``(1, -cos 2gamma, sin 2gamma, 0)``: ``brdf(..., polarization=gamma)`` equals
  ``(M @ [1, -cos 2gamma, sin 2gamma, 0])[0]`` in either basis (the incident bases coincide).
  ``"s"`` is ``m00 + m01``, ``"p"`` is ``m00 - m01``.

Bases (library frame, ``docs/models.md`` §1.1: normal ``+z``, source on ``-x``)
------------------------------------------------------------------------------
Incident propagation ``k_i = (sin ti, 0, -cos ti)``, reflected ``k_r = w_r =
(sin tr cos phi, sin tr sin phi, cos tr)`` (SCATMECH's ``ki``, ``ks``; its ``phis`` is the
library's ``phi``, 0 on the specular side).

* ``"psps"`` (SCATMECH ``psps``): ``s = (z × k)/|z × k|``, ``p = k × s``. Incident:
  ``s_i = (0, 1, 0)``, ``p_i = (cos ti, 0, sin ti)``. Reflected: ``s_r = (-sin phi, cos phi, 0)``,
  ``p_r = (-cos tr cos phi, -cos tr sin phi, sin tr)``. At ``tr = 0`` the reflected basis is
  the limit ``tr -> 0`` at the given ``phi`` (SCATMECH takes ``s = y`` there whatever ``phi``;
  the two differ only at exactly ``tr = 0`` and only by the basis, i.e. a rotation).
* ``"xyxy"`` (SCATMECH ``xyxy``, ``GetBasisVectorsXY``): regular at the normal. Incident:
  ``(e1, e2) = (y_i, x_i) = (s_i, p_i)``. Reflected: ``e1 = y_r = -cos phi s_r + sin phi p_r``,
  ``e2 = x_r = -sin phi s_r - cos phi p_r``; at ``tr = 0``, ``x_r = +x``, ``y_r = -y``.

Symmetries (tested; ``docs/models.md`` §11.4): mirror, ``M(ti, tr, -phi) = D M(ti, tr, phi) D``
with ``D = diag(1, 1, -1, -1)`` (both bases); reciprocity, ``M(tr, ti, -phi) = Q M(ti, tr,
phi)^T Q`` with ``Q = diag(1, 1, -1, 1)`` (psps).

The facet term
--------------
A mirror facet (normal ``h``, the half vector) reflects with the complex Fresnel amplitudes
``r_s``, ``r_p`` (:func:`roughbrdf.fresnel.fresnel_amplitudes`, SCATMECH's sign of ``r_p``) at
the local angle ``theta_d``, in the facet's own s/p basis ``s_f = (w_i × h)/sin theta_d``,
``p_f = k × s_f``. Its Jones matrix in the macroscopic bases is

``J = R_r diag(r_s, r_p) R_i``,
``R_i = [[a, b], [-b, a]]``, ``(a, b) = (s_f·e1_i, s_f·e2_i)``,
``R_r = [[c, -d], [d, c]]``, ``(c, d) = (e1_r·s_f, e2_r·s_f)``

(change-of-basis rotations; ``a = cos eta``, ``b = -sin eta`` with TR75's ``eta``), and the
facet term is ``f · M(J)`` with ``f`` the model's scalar facet factor *without* ``F`` (e.g.
``D G/(4 cos ti cos tr)``), so that ``m00 = f (R_s + R_p)/2`` is the scalar model.
``M(J)`` is :func:`jones_mueller` (SCATMECH's ``MuellerMatrix(const JonesMatrix&)``). At
``theta_d = 0`` (the retro direction) ``s_f`` is undefined but ``M`` is not (``r_p = -r_s``
there): any ``s_f`` perpendicular to ``k_i`` gives the same matrix; ``s_i`` is used.

Scalar parts (compiled, :func:`roughbrdf._kernels.jit`) write sample ``i`` of the driver's
output, ``out[i, :, :]`` (indexing, not a view per sample: the 128 bytes of output per matrix
make the drivers memory-bound already, ``docs/models.md`` §11.6). The NumPy front ends are
:func:`jones_to_mueller`, :func:`fresnel_mueller`, :func:`depolarizer` and :func:`coherency`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import prange
from numpy.typing import ArrayLike

from ._kernels import as_float_array, at, driver, evaluate, jit, run_driver, sincos
from .errors import ArgumentError
from .fresnel import check_index, fresnel_amplitudes
from .geometry import half_vector

__all__ = ["PSPS", "XYXY", "BASES", "basis_code", "jones_mueller", "facet_jones",
           "facet_mueller", "jones_to_mueller", "fresnel_mueller", "depolarizer", "coherency"]

#: basis codes passed to the compiled Mueller drivers (their ``flag``)
PSPS, XYXY = 0, 1
#: basis name -> code
BASES = {"psps": PSPS, "xyxy": XYXY}


def basis_code(basis: Any) -> int:
    """The code of a basis name (``"psps"`` or ``"xyxy"``, case-insensitive).

    Raises :class:`~roughbrdf.errors.ArgumentError` naming ``basis`` for anything else.

    Examples
    --------
    >>> basis_code("XYXY")
    1
    """
    key = basis.strip().lower() if isinstance(basis, str) else None
    if key not in BASES:
        raise ArgumentError("basis", "must be 'psps' (s/p of each direction) or 'xyxy' "
                            "(regular at the normal), as SCATMECH's coordinate systems",
                            value=basis)
    return BASES[key]


# --------------------------------------------------------------------------------------------
# compiled scalar parts
# --------------------------------------------------------------------------------------------
@jit(inline=True)
def _cmul_conj(xr, xi, yr, yi):
    """``x y*`` of two complex numbers given as (re, im) pairs."""
    return xr * yr + xi * yi, xi * yr - xr * yi


@jit(inline=True)
def _n2(xr, xi):
    return xr * xr + xi * xi


@jit(inline=True)
def _put(out, i, r, c, scale, x):
    # x = 0 stays 0 also for scale = inf (a model's divergent limit): never inf * 0 = nan
    out[i, r, c] = scale * x if x != 0.0 else 0.0


@jit(inline=True)
def jones_mueller(out, i, scale, j11r, j11i, j12r, j12i, j21r, j21i, j22r, j22i):
    """Write ``scale * M(J)`` into ``out[i]`` (shape ``(4, 4)``): the Mueller matrix of the Jones
    matrix ``J = [[j11, j12], [j21, j22]]`` (``j12``: e1 out from e2 in), module conventions.

    SCATMECH's ``MuellerMatrix(const JonesMatrix&)`` (Bohren & Huffman) with ``SS = j11``,
    ``PS = j12``, ``SP = j21``, ``PP = j22``. An element whose unscaled value is exactly 0 is 0
    also for ``scale = inf`` (a model's divergent limit, e.g. TR75 at ``theta_r = 90 deg``),
    never ``inf * 0 = nan``.
    """
    a11, a12 = _n2(j11r, j11i), _n2(j12r, j12i)
    a21, a22 = _n2(j21r, j21i), _n2(j22r, j22i)
    x1r, x1i = _cmul_conj(j11r, j11i, j12r, j12i)  # j11 j12*
    x2r, x2i = _cmul_conj(j22r, j22i, j21r, j21i)  # j22 j21*
    y1r, y1i = _cmul_conj(j11r, j11i, j21r, j21i)  # j11 j21*
    y2r, y2i = _cmul_conj(j22r, j22i, j12r, j12i)  # j22 j12*
    z1r, z1i = _cmul_conj(j22r, j22i, j11r, j11i)  # j22 j11*
    z2r, z2i = _cmul_conj(j12r, j12i, j21r, j21i)  # j12 j21*
    _put(out, i, 0, 0, scale, 0.5 * (a11 + a22 + a12 + a21))
    _put(out, i, 0, 1, scale, 0.5 * (a11 - a22 + a21 - a12))
    _put(out, i, 0, 2, scale, x1r + x2r)
    _put(out, i, 0, 3, scale, x1i - x2i)
    _put(out, i, 1, 0, scale, 0.5 * (a11 - a22 - a21 + a12))
    _put(out, i, 1, 1, scale, 0.5 * (a11 + a22 - a21 - a12))
    _put(out, i, 1, 2, scale, x1r - x2r)
    _put(out, i, 1, 3, scale, x1i + x2i)
    _put(out, i, 2, 0, scale, y1r + y2r)
    _put(out, i, 2, 1, scale, y1r - y2r)
    _put(out, i, 2, 2, scale, z1r + z2r)
    _put(out, i, 2, 3, scale, -z1i - z2i)  # Im(j11 j22* + j21 j12*)
    _put(out, i, 3, 0, scale, y2i - y1i)  # Im(j21 j11* + j22 j12*)
    _put(out, i, 3, 1, scale, -y1i - y2i)  # Im(j21 j11* - j22 j12*)
    _put(out, i, 3, 2, scale, z1i - z2i)
    _put(out, i, 3, 3, scale, z1r - z2r)


@jit(inline=True)
def facet_jones(ti, tr, phi, basis):
    """The facet's change-of-basis coefficients and ``cos theta_d``.

    Returns ``(cos_d, ac, bd, bc, ad)``: with ``a, b, c, d`` of the module notes (each
    already divided by ``|s_f|``), the facet Jones matrix is
    ``[[ac r_s + bd r_p, bc r_s - ad r_p], [ad r_s - bc r_p, bd r_s + ac r_p]]``.
    """
    hx, hy, hz, cd, ci, cr, si = half_vector(ti, tr, phi)
    sr_, cr_ = sincos(tr)
    sp, cp = sincos(phi)
    # s_f sin(theta_d) = w_i x h, with w_i = (-si, 0, ci)
    fx, fy, fz = -ci * hy, ci * hx + si * hz, -si * hy
    l2 = fx * fx + fy * fy + fz * fz  # sin^2 theta_d
    # theta_d = 0 (retro direction, and the w_i = -w_r pair): s_f undefined, M is not (r_p =
    # -r_s there); take s_f = s_i. Below 1e-30 (theta_d < 1e-15) the direction of the
    # unnormalized vector is round-off, and the matrix changes only by O(theta_d^2) with it.
    small = l2 < 1e-30
    fx, fy, fz = (0.0, 1.0, 0.0) if small else (fx, fy, fz)
    inv = 1.0 / (1.0 if small else l2)  # no 1/0 on the unused side of the select
    a = fy  # s_f . s_i, s_i = (0, 1, 0)
    b = ci * fx + si * fz  # s_f . p_i, p_i = (cos ti, 0, sin ti)
    c = -sp * fx + cp * fy  # s_r . s_f, s_r = (-sin phi, cos phi, 0)
    d = -cr_ * cp * fx - cr_ * sp * fy + sr_ * fz  # p_r . s_f
    if basis == XYXY:  # (e1, e2) = (y_r, x_r) = (-cp s_r + sp p_r, -sp s_r - cp p_r)
        c, d = -cp * c + sp * d, -sp * c - cp * d
    return cd, a * c * inv, b * d * inv, b * c * inv, a * d * inv


@jit(inline=True)
def facet_mueller(out, i, ti, tr, phi, n, k, basis, scale):
    """Write the facet term ``scale * M(R_r diag(r_s, r_p) R_i)`` into ``out[i]`` (module notes);
    ``scale`` is the model's facet factor without ``F``, ``n + i k`` the facet's index."""
    cd, ac, bd, bc, ad = facet_jones(ti, tr, phi, basis)
    sr, si, pr, pi_ = fresnel_amplitudes(cd, n, k)
    jones_mueller(out, i, scale,
                  ac * sr + bd * pr, ac * si + bd * pi_, bc * sr - ad * pr, bc * si - ad * pi_,
                  ad * sr - bc * pr, ad * si - bc * pi_, bd * sr + ac * pr, bd * si + ac * pi_)


# --------------------------------------------------------------------------------------------
# NumPy front ends
# --------------------------------------------------------------------------------------------
@driver
def _jones_drive(j, out):  # pragma: no cover - compiled
    for i in prange(out.shape[0]):
        jones_mueller(out, i, 1.0, j[i, 0], j[i, 1], j[i, 2], j[i, 3], j[i, 4], j[i, 5],
                      j[i, 6], j[i, 7])


@driver
def _fresnel_drive(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # a = cos(theta), b = n, c = k (roughbrdf._kernels.evaluate broadcasts them)
    for i in prange(out.shape[0]):
        sr, si, pr, pi_ = fresnel_amplitudes(at(a, i), at(b, i), at(c, i))
        jones_mueller(out, i, 1.0, sr, si, 0.0, 0.0, 0.0, 0.0, pr, pi_)


def jones_to_mueller(jones: ArrayLike) -> np.ndarray:
    """Mueller matrices of Jones matrices (module conventions).

    Parameters
    ----------
    jones : array_like, complex, shape (..., 2, 2)
        ``[[j11, j12], [j21, j22]]`` on the bases ``(e1, e2)`` of the incident (columns) and
        outgoing (rows) directions.

    Returns
    -------
    numpy.ndarray, shape (..., 4, 4)

    Examples
    --------
    >>> import numpy as np
    >>> from roughbrdf.mueller import jones_to_mueller
    >>> jones_to_mueller(np.diag([1.0, 0.0]))          # polarizer passing e1 (s)
    array([[0.5, 0.5, 0. , 0. ],
           [0.5, 0.5, 0. , 0. ],
           [0. , 0. , 0. , 0. ],
           [0. , 0. , 0. , 0. ]])
    """
    j = np.asarray(jones, dtype=np.complex128)
    if j.shape[-2:] != (2, 2):
        raise ArgumentError("jones", "must have shape (..., 2, 2)", value=j.shape)
    flat = np.ascontiguousarray(j.reshape(-1, 4).view(np.float64))  # re, im interleaved
    out = np.empty((flat.shape[0], 4, 4))
    if flat.shape[0]:
        run_driver(_jones_drive, flat, out)
    return out.reshape(*j.shape[:-2], 4, 4)


def fresnel_mueller(cos_theta: ArrayLike, n: ArrayLike, k: ArrayLike = 0.0) -> np.ndarray:
    """Mueller reflection matrix of a smooth interface, psps bases (module conventions).

    ``[[A, B, 0, 0], [B, A, 0, 0], [0, 0, C, S], [0, 0, -S, C]]`` with ``A = (R_s + R_p)/2``,
    ``B = (R_s - R_p)/2``, ``C + i S = r_s r_p*`` (:func:`roughbrdf.fresnel.fresnel_amplitudes`).
    It is dimensionless (a reflectance); a model's facet term tends to it times a scalar at the
    specular direction of a smooth surface.

    Parameters
    ----------
    cos_theta : array_like
        Cosine of the angle of incidence, in [0, 1].
    n, k : array_like
        Index ``n + i k`` (``n > 0``, ``k >= 0``).

    Returns
    -------
    numpy.ndarray, shape (broadcast shape, 4, 4)

    Examples
    --------
    >>> from roughbrdf.mueller import fresnel_mueller
    >>> fresnel_mueller(1.0, 1.5).round(4)          # normal incidence: R diag(1, 1, -1, -1)
    array([[ 0.04,  0.  ,  0.  ,  0.  ],
           [ 0.  ,  0.04,  0.  ,  0.  ],
           [ 0.  ,  0.  , -0.04,  0.  ],
           [ 0.  ,  0.  ,  0.  , -0.04]])
    """
    c = as_float_array(cos_theta, "cos_theta")
    bad = ~(np.isfinite(c) & (c >= 0) & (c <= 1))
    if bad.any():
        raise ArgumentError("cos_theta", "must be in [0, 1]", value=float(c[bad].flat[0]))
    na, ka = as_float_array(n, "n"), as_float_array(k, "k")
    for nv, kv in np.broadcast(na, ka):
        check_index(float(nv), float(kv))
    out = evaluate(_fresnel_drive, c, na, ka, np.asarray(math.nan), (), 0, out_shape=(4, 4))
    return np.asarray(out)


def depolarizer(value: ArrayLike = 1.0) -> np.ndarray:
    """Ideal depolarizer(s): ``value`` in ``m00``, every other element 0.

    The Mueller matrix of a Lambertian (or Oren-Nayar) term is ``depolarizer(brdf)``.

    Examples
    --------
    >>> from roughbrdf.mueller import depolarizer
    >>> depolarizer([1.0, 2.0]).shape
    (2, 4, 4)
    >>> float(depolarizer(0.5)[0, 0])
    0.5
    """
    v = as_float_array(value, "value")
    out = np.zeros((*v.shape, 4, 4))
    out[..., 0, 0] = v
    return out


def coherency(mueller: ArrayLike) -> np.ndarray:
    """Cloude's coherency matrix ``H`` (4×4 Hermitian) of Mueller matrices.

    ``H = (1/4) sum_ij m_ij (sigma_i ⊗ sigma_j*)`` in the basis SCATMECH's
    ``MuellerToHermitian`` uses (``h[0,0] = (m00 + m01 + m10 + m11)/2`` ...), scaled so that
    ``trace(H) = 2 m00``. A Mueller matrix is a non-negative sum of Jones-Mueller matrices
    (physically realizable) exactly when ``H`` has no negative eigenvalue; a single facet term
    has rank 1.

    Examples
    --------
    >>> import numpy as np
    >>> from roughbrdf.mueller import coherency, depolarizer
    >>> np.linalg.eigvalsh(coherency(depolarizer(1.0))).round(12)   # ideal depolarizer
    array([0.5, 0.5, 0.5, 0.5])
    """
    m = np.asarray(mueller, dtype=np.float64)
    if m.shape[-2:] != (4, 4):
        raise ArgumentError("mueller", "must have shape (..., 4, 4)", value=m.shape)
    h = np.empty((*m.shape[:-2], 4, 4), dtype=np.complex128)
    g = lambda r, c: m[..., r, c]  # noqa: E731 - local shorthand
    h[..., 0, 0] = (g(0, 0) + g(1, 1) + g(0, 1) + g(1, 0)) / 2
    h[..., 0, 1] = (g(0, 2) + g(1, 2) + 1j * (g(0, 3) + g(1, 3))) / 2
    h[..., 0, 2] = (g(2, 0) + g(2, 1) - 1j * (g(3, 0) + g(3, 1))) / 2
    h[..., 0, 3] = (g(2, 2) + g(3, 3) + 1j * (g(2, 3) - g(3, 2))) / 2
    h[..., 1, 1] = (g(0, 0) - g(1, 1) - g(0, 1) + g(1, 0)) / 2
    h[..., 1, 2] = (g(2, 2) - g(3, 3) - 1j * (g(2, 3) + g(3, 2))) / 2
    h[..., 1, 3] = (g(2, 0) - g(2, 1) - 1j * (g(3, 0) - g(3, 1))) / 2
    h[..., 2, 2] = (g(0, 0) - g(1, 1) + g(0, 1) - g(1, 0)) / 2
    h[..., 2, 3] = (g(0, 2) - g(1, 2) + 1j * (g(0, 3) - g(1, 3))) / 2
    h[..., 3, 3] = (g(0, 0) + g(1, 1) - g(0, 1) - g(1, 0)) / 2
    for r in range(4):
        for c in range(r):
            h[..., r, c] = np.conj(h[..., c, r])
    return h
