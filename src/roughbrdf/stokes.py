"""Stokes vectors: polarization states, the reflected state, its degree and angle, frames.

Everything follows the conventions of :mod:`roughbrdf.mueller` (SCATMECH's): Stokes vectors
``[I, Q, U, V]`` (arrays of shape ``(..., 4)``) on a right-handed basis ``{e1, e2, k}``, ``k``
the direction of propagation, with ``Q = |E1|² - |E2|²``, ``U = 2 Re(E1* E2)``,
``V = 2 Im(E1* E2)``. In the ``psps`` basis of a direction ``e1 = s`` and ``e2 = p``:

* **Q > 0 is s**: ``s() = [1, 1, 0, 0]``, ``p() = [1, -1, 0, 0]``;
* TR75's angle ``gamma`` (``docs/models.md`` §3.5; the electric field at ``gamma`` from the
  plane of incidence, ``0`` = p, ``pi/2`` = s; the Jones vector ``(sin gamma, cos gamma)``) is
  ``linear(gamma) = [1, -cos 2 gamma, sin 2 gamma, 0]``; ``gamma`` grows from ``e2`` (p)
  toward ``e1`` (s), i.e. clockwise as seen by an observer looking toward the source;
* **V > 0** is the field turning from ``e1`` to ``e2``: counter-clockwise as seen looking
  toward the source (SCATMECH's and Born & Wolf's "left circular", IEEE's right-hand, positive
  helicity): ``circular("ccw") = [1, 0, 0, 1]``.

So ``model.brdf(..., polarization=gamma)`` is ``(M @ linear(gamma))[0]`` for
``M = model.mueller(...)`` (tested to round-off); :func:`reflected_stokes` gives the whole
reflected vector, :func:`dolp`, :func:`aolp`, :func:`docp` and :func:`dop` describe a state.

Frames
------
:func:`rotate_stokes` re-expresses a state in a basis turned about ``k``; ``rotate_stokes(
linear(g), a) == linear(g - a)``. :func:`basis_vectors` gives ``(e1, e2, k)`` of either beam in
the library frame (``docs/models.md`` §1.1) for the ``psps`` and ``xyxy`` bases, and
:func:`from_frame` / :func:`to_frame` convert Stokes vectors (or analyzer rows) between ours
and a polarimeter's own frame, given by its **reference axis** (the lab direction of its
``Q > 0`` axis, e.g. the goniometer's vertical) and handedness; :func:`change_basis` converts
between ``psps`` and ``xyxy``; :func:`mueller_from_frames` converts a whole Mueller matrix.

Checked arrays
--------------
:func:`as_stokes` is the one check of a Stokes vector or an analyzer row given by a user (shape
``(..., 4)``, finite real numbers, a physical state): :class:`roughbrdf.polarization.Polarization`
and :func:`reflected_stokes` use it, and :data:`BASES` names the polarization bases.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .errors import ArgumentError

__all__ = ["as_stokes", "linear", "s", "p", "unpolarized", "circular", "analyzer_row",
           "reflected_stokes", "dolp", "aolp", "docp", "dop", "rotate_stokes", "rotation_matrix",
           "basis_vectors", "reference_angle", "from_frame", "to_frame", "change_basis",
           "mueller_from_frames"]

#: the polarization bases of :meth:`roughbrdf.models.Model.mueller` (:mod:`roughbrdf.mueller`)
BASES = ("psps", "xyxy")
#: relative slack of the physical-state check ``S0 >= |(S1, S2, S3)|``: a vector built from
#: cosines and sines (``[1, cos 2g, sin 2g, 0]``) may exceed it by a rounding error
PHYSICAL_RTOL = 1e-9
#: circular senses: V = +1 for the field turning counter-clockwise seen looking toward the
#: source (``"ccw"``, SCATMECH's and Born & Wolf's ``"left"``), -1 for ``"cw"``/``"right"``
_SENSES = {"ccw": 1.0, "left": 1.0, "cw": -1.0, "right": -1.0}
#: a reference axis closer than this (sine of the angle) to the beam has no transverse part
_PARALLEL = 1e-9


# --------------------------------------------------------------------------------------------
# checked arrays
# --------------------------------------------------------------------------------------------
def as_stokes(value: Any, argument: str) -> np.ndarray:
    """``value`` as a float array of shape ``(..., 4)``: finite real numbers, each vector a
    physical state ``v0 >= |(v1, v2, v3)|``; ArgumentError naming ``argument`` otherwise.

    ``argument`` is the name the caller knows the value by (``"stokes"``, ``"analyzer"``,
    ``"incident"``); for ``"stokes"`` a non-physical vector is "no physical light", for any
    other name a detector row that "would read a negative signal". The result is a copy.

    Examples
    --------
    >>> as_stokes([1, 0, 0, 1], "stokes").tolist()
    [1.0, 0.0, 0.0, 1.0]
    >>> as_stokes([1.0, 2.0, 0.0, 0.0], "stokes")
    Traceback (most recent call last):
    ...
    roughbrdf.errors.ArgumentError: stokes = [1.0, 2.0, 0.0, 0.0]: no physical light has it: ...
    """
    shown = repr(value) if len(repr(value)) <= 80 else repr(value)[:70] + " ..."
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError, OverflowError):
        raise ArgumentError(argument, f"must be an array of 4 real numbers per vector, got "
                            f"{shown}") from None
    if arr.dtype.kind not in "biuf" or arr.ndim == 0 or arr.shape[-1] != 4:
        raise ArgumentError(argument, "must be an array of shape (..., 4) of real numbers "
                            f"[I, Q, U, V], got {shown}")
    arr = np.array(arr, dtype=np.float64)  # a copy: the caller's array may change later
    if not np.isfinite(arr).all():
        raise ArgumentError(argument, f"must be finite, got {shown}")
    pol = np.sqrt(np.sum(arr[..., 1:] ** 2, axis=-1))
    bad = pol > arr[..., 0] * (1.0 + PHYSICAL_RTOL)  # also v0 < 0, and v0 = 0 with v != 0
    if bad.any():
        first = arr[np.nonzero(bad)][0].tolist() if arr.ndim > 1 else arr.tolist()
        what = ("no physical light has it: I >= |(Q, U, V)| is needed" if argument == "stokes"
                else "a detector with it would read a negative signal for some light: "
                "a0 >= |(a1, a2, a3)| is needed")
        raise ArgumentError(argument, what, value=first)
    return arr


# --------------------------------------------------------------------------------------------
# states
# --------------------------------------------------------------------------------------------
def linear(gamma: ArrayLike) -> np.ndarray:
    """Linear polarization at TR75's angle ``gamma`` (radians; 0 = p, pi/2 = s), psps basis.

    Returns ``[1, -cos 2 gamma, sin 2 gamma, 0]``, shape ``gamma.shape + (4,)``.

    Examples
    --------
    >>> linear(0.0).tolist(), linear(np.pi / 2).round(12).tolist()
    ([1.0, -1.0, 0.0, 0.0], [1.0, 1.0, 0.0, 0.0])
    >>> linear([0.0, np.pi / 4]).round(12).tolist()
    [[1.0, -1.0, 0.0, 0.0], [1.0, -0.0, 1.0, 0.0]]
    """
    g = np.asarray(gamma, dtype=float)
    if not np.isfinite(g).all():
        raise ArgumentError("gamma", "must be finite (radians)", value=gamma, unit="rad")
    out = np.zeros(g.shape + (4,))
    out[..., 0] = 1.0
    out[..., 1] = -np.cos(2.0 * g)
    out[..., 2] = np.sin(2.0 * g)
    return out


def s() -> np.ndarray:
    """s-polarized light (``gamma = pi/2``), ``[1, 1, 0, 0]``.

    Examples
    --------
    >>> s().tolist()
    [1.0, 1.0, 0.0, 0.0]
    """
    return np.array([1.0, 1.0, 0.0, 0.0])


def p() -> np.ndarray:
    """p-polarized light (``gamma = 0``), ``[1, -1, 0, 0]``.

    Examples
    --------
    >>> p().tolist()
    [1.0, -1.0, 0.0, 0.0]
    """
    return np.array([1.0, -1.0, 0.0, 0.0])


def unpolarized() -> np.ndarray:
    """Natural light, ``[1, 0, 0, 0]``.

    Examples
    --------
    >>> unpolarized().tolist()
    [1.0, 0.0, 0.0, 0.0]
    """
    return np.array([1.0, 0.0, 0.0, 0.0])


def circular(sense: str = "ccw") -> np.ndarray:
    """Circular polarization, ``[1, 0, 0, V]``.

    Parameters
    ----------
    sense : {"ccw", "cw", "left", "right"}
        ``"ccw"`` (= ``"left"``, SCATMECH / Born & Wolf; IEEE right-hand): the field turns
        counter-clockwise as seen by an observer looking toward the source, ``V = +1``;
        ``"cw"`` (= ``"right"``): ``V = -1``.

    Examples
    --------
    >>> circular().tolist(), circular("right").tolist()
    ([1.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, -1.0])
    """
    key = sense.strip().lower() if isinstance(sense, str) else None
    if key not in _SENSES:
        raise ArgumentError("sense", "must be 'ccw' (= 'left', V > 0) or 'cw' (= 'right'), "
                            "seen looking toward the source", value=sense)
    return np.array([1.0, 0.0, 0.0, _SENSES[key]])


def analyzer_row(state: ArrayLike) -> np.ndarray:
    """The detector row of an ideal polarizer passing the polarized part of ``state``.

    An ideal polarizer for the pure state ``[1, u]`` (``|u| = 1``) has the Mueller matrix
    ``(1/2) [[1, u], [u, u u^T]]``; a detector behind it reads ``(1/2)(I + u . (Q, U, V))``
    of the light, so its row is ``[1, u]/2`` (``Polarization(analyzer=...)``). ``u`` is the
    direction of ``state[..., 1:]``, which must not vanish.

    Examples
    --------
    >>> analyzer_row(s()).tolist()
    [0.5, 0.5, 0.0, 0.0]
    >>> float(analyzer_row(p()) @ s())      # crossed: nothing passes
    0.0
    """
    st = np.asarray(state, dtype=float)
    if st.ndim == 0 or st.shape[-1] != 4 or not np.isfinite(st).all():
        raise ArgumentError("state", "must be finite Stokes vectors of shape (..., 4)",
                            value=state)
    norm = np.sqrt(np.sum(st[..., 1:] ** 2, axis=-1, keepdims=True))
    if (norm == 0).any():  # no polarized part: no polarizer passes "unpolarized"
        raise ArgumentError("state", "an analyzer passes a polarized state; this one has "
                            "Q = U = V = 0", value=state)
    return 0.5 * np.concatenate([np.ones_like(norm), st[..., 1:] / norm], axis=-1)


# --------------------------------------------------------------------------------------------
# the reflected state and its description
# --------------------------------------------------------------------------------------------
def reflected_stokes(model: Any, theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike,
                     incident: ArrayLike, *, basis: str = "psps",
                     term: str | None = None) -> np.ndarray:
    """The Stokes vector of the reflected radiance, ``M @ incident`` (sr⁻¹ per unit
    incident irradiance ``I``).

    Parameters
    ----------
    model : Model
        Any model with :meth:`~roughbrdf.models.Model.mueller`.
    theta_i, theta_r, phi : array_like
        Angles, radians (library frame).
    incident : array_like, shape (..., 4)
        Incident Stokes vector(s) in ``basis``; the leading axes broadcast against the angles.
    basis : {"psps", "xyxy"}
        Basis of ``incident`` and of the result (:mod:`roughbrdf.mueller`).
    term : str, optional
        A component of a sum.

    Returns
    -------
    numpy.ndarray, shape (broadcast shape, 4)

    Examples
    --------
    >>> import roughbrdf as rb
    >>> m = rb.model("microfacet", distribution="beckmann", alpha=0.3, n=0.2, k=3.0)
    >>> out = reflected_stokes(m, 0.6, 0.6, 0.0, linear(0.3))
    >>> bool(np.isclose(out[0], m.brdf(0.6, 0.6, 0.0, polarization=0.3), rtol=1e-12))
    True
    """
    s_in = as_stokes(incident, "incident")
    mat = np.asarray(model.mueller(theta_i, theta_r, phi, basis=basis, term=term), dtype=float)
    try:
        shape = np.broadcast_shapes(mat.shape[:-2], s_in.shape[:-1])
    except ValueError:
        raise ArgumentError("incident", f"Stokes vectors of shape {s_in.shape} do not "
                            f"broadcast against the angles' shape {mat.shape[:-2]}") from None
    out = np.matmul(mat, s_in[..., None])[..., 0]
    return np.broadcast_to(out, shape + (4,))


def _split(stokes: ArrayLike) -> tuple[np.ndarray, ...]:
    st = np.asarray(stokes, dtype=float)
    if st.ndim == 0 or st.shape[-1] != 4:
        raise ArgumentError("stokes", "must have shape (..., 4): [I, Q, U, V]", value=stokes)
    return st[..., 0], st[..., 1], st[..., 2], st[..., 3]


def _ratio(num: np.ndarray, den: np.ndarray) -> np.ndarray | float:
    # I = 0 (no light) has no degree of polarization: NaN, not a division warning
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(den > 0, num / np.where(den > 0, den, 1.0), np.nan)
    return float(out) if out.ndim == 0 else out


def dolp(stokes: ArrayLike) -> np.ndarray | float:
    """Degree of linear polarization ``sqrt(Q² + U²)/I`` (NaN where ``I <= 0``).

    Examples
    --------
    >>> dolp([2.0, 1.0, 0.0, 1.0])
    0.5
    """
    i, q, u, _ = _split(stokes)
    return _ratio(np.hypot(q, u), i)


def docp(stokes: ArrayLike) -> np.ndarray | float:
    """Signed degree of circular polarization ``V/I`` (> 0: counter-clockwise seen looking
    toward the source; NaN where ``I <= 0``).

    Examples
    --------
    >>> docp(circular("cw"))
    -1.0
    """
    i, _, _, v = _split(stokes)
    return _ratio(v, i)


def dop(stokes: ArrayLike) -> np.ndarray | float:
    """Degree of polarization ``sqrt(Q² + U² + V²)/I`` (NaN where ``I <= 0``).

    Examples
    --------
    >>> dop([2.0, 1.0, 0.0, 1.0]) == math.sqrt(2) / 2
    True
    """
    i, q, u, v = _split(stokes)
    return _ratio(np.sqrt(q * q + u * u + v * v), i)


def aolp(stokes: ArrayLike) -> np.ndarray | float:
    """Angle of linear polarization as TR75's ``gamma``: from ``e2`` toward ``e1`` (in psps,
    from p toward s), radians in ``[0, pi)``; NaN where ``Q = U = 0`` (no linear part).

    ``aolp(linear(g)) == g mod pi``.

    Examples
    --------
    >>> round(aolp(linear(0.3)), 12), round(aolp(s()), 12), aolp(unpolarized())
    (0.3, 1.570796326795, nan)
    """
    _, q, u, _ = _split(stokes)
    # Q + iU = -exp(-2i gamma): gamma = pi/2 - atan2(U, Q)/2, reduced to [0, pi)
    g = np.mod(0.5 * math.pi - 0.5 * np.arctan2(u, q), math.pi)
    out = np.where((q == 0) & (u == 0), np.nan, g)  # atan2(0, 0) = 0 would be a made-up angle
    return float(out) if out.ndim == 0 else out


# --------------------------------------------------------------------------------------------
# frames
# --------------------------------------------------------------------------------------------
def rotation_matrix(angle: ArrayLike) -> np.ndarray:
    """The Mueller matrix of :func:`rotate_stokes`, shape ``angle.shape + (4, 4)``.

    ``[[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1]]`` with ``c = cos 2 angle``,
    ``s = sin 2 angle``.

    Examples
    --------
    >>> rotation_matrix(np.pi / 4).round(12)[1:3, 1:3].tolist()
    [[0.0, -1.0], [1.0, 0.0]]
    """
    a = np.asarray(angle, dtype=float)
    if not np.isfinite(a).all():
        raise ArgumentError("angle", "must be finite (radians)", value=angle, unit="rad")
    c, sn = np.cos(2.0 * a), np.sin(2.0 * a)
    out = np.zeros(a.shape + (4, 4))
    out[..., 0, 0] = out[..., 3, 3] = 1.0
    out[..., 1, 1] = out[..., 2, 2] = c
    out[..., 1, 2] = -sn
    out[..., 2, 1] = sn
    return out


def rotate_stokes(stokes: ArrayLike, angle: ArrayLike) -> np.ndarray:
    """The same light in a basis turned by ``angle`` in the sense of ``gamma``.

    The new basis has its ``e2`` axis at ``gamma = angle`` of the old one (turned from ``e2``
    toward ``e1``, clockwise seen looking toward the source), so every linear angle drops by
    ``angle``: ``rotate_stokes(linear(g), a) == linear(g - a)``. ``I`` and ``V`` do not
    change. Works on analyzer rows too (the rotation is orthogonal).

    Examples
    --------
    >>> bool(np.allclose(rotate_stokes(linear(0.7), 0.2), linear(0.5)))
    True
    >>> rotate_stokes(s(), np.pi / 2).round(12).tolist()     # s, seen from a frame turned 90 deg
    [1.0, -1.0, 0.0, 0.0]
    """
    st = np.asarray(stokes, dtype=float)
    if st.ndim == 0 or st.shape[-1] != 4:
        raise ArgumentError("stokes", "must have shape (..., 4): [I, Q, U, V]", value=stokes)
    return np.matmul(rotation_matrix(angle), st[..., None])[..., 0]


def basis_vectors(theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike, *,
                  beam: str = "incident", basis: str = "psps"
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(e1, e2, k)`` of a beam in the library frame, each of shape (broadcast shape, 3).

    ``beam="incident"``: ``k = (sin ti, 0, -cos ti)``, ``e1 = s_i = (0, 1, 0)``,
    ``e2 = p_i = (cos ti, 0, sin ti)`` in both bases. ``beam="reflected"``: ``k = w_r``;
    psps ``e1 = s_r = (-sin phi, cos phi, 0)``, ``e2 = p_r = (-cos tr cos phi, -cos tr sin phi,
    sin tr)``; xyxy ``e1 = -cos phi s_r + sin phi p_r``, ``e2 = -sin phi s_r - cos phi p_r``
    (:mod:`roughbrdf.mueller`). Always ``e1 x e2 = k``.

    Examples
    --------
    >>> e1, e2, k = basis_vectors(0.3, 0.5, 1.0, beam="reflected")
    >>> bool(np.allclose(np.cross(e1, e2), k))
    True
    """
    if beam not in ("incident", "reflected"):
        raise ArgumentError("beam", "must be 'incident' or 'reflected'", value=beam)
    if basis not in BASES:
        raise ArgumentError("basis", f"must be one of {', '.join(BASES)}", value=basis)
    ti, tr, ph = np.broadcast_arrays(*(np.asarray(a, dtype=float)
                                       for a in (theta_i, theta_r, phi)))
    zero, one = np.zeros_like(ti), np.ones_like(ti)
    if beam == "incident":
        return (np.stack([zero, one, zero], -1),
                np.stack([np.cos(ti), zero, np.sin(ti)], -1),
                np.stack([np.sin(ti), zero, -np.cos(ti)], -1))
    sp, cp, st, ct = np.sin(ph), np.cos(ph), np.sin(tr), np.cos(tr)
    e1 = np.stack([-sp, cp, zero], -1)
    e2 = np.stack([-ct * cp, -ct * sp, st], -1)
    k = np.stack([st * cp, st * sp, ct], -1)
    if basis == "xyxy":
        c, d = -cp[..., None], sp[..., None]
        e1, e2 = c * e1 + d * e2, -d * e1 + c * e2
    return e1, e2, k


def reference_angle(reference: ArrayLike, theta_i: ArrayLike, theta_r: ArrayLike,
                    phi: ArrayLike, *, beam: str = "incident", basis: str = "psps"
                    ) -> np.ndarray | float:
    """The ``gamma`` (angle from ``e2`` toward ``e1``) of a lab axis seen across a beam.

    ``reference`` (shape (..., 3), library frame; need not be unit nor transverse) is projected
    onto the plane across the beam. ArgumentError when it is (nearly) along the beam.

    Examples
    --------
    >>> round(reference_angle([0.0, 1.0, 0.0], 0.4, 0.4, 0.0), 12)    # y is s: gamma = pi/2
    1.570796326795
    """
    e1, e2, k = basis_vectors(theta_i, theta_r, phi, beam=beam, basis=basis)
    ref = np.asarray(reference, dtype=float)
    if ref.ndim == 0 or ref.shape[-1] != 3 or not np.isfinite(ref).all():
        raise ArgumentError("reference", "must be finite 3-vectors (library frame)",
                            value=reference)
    x1, x2 = np.sum(ref * e1, -1), np.sum(ref * e2, -1)
    size = np.sqrt(np.sum(ref * ref, -1))
    if (np.hypot(x1, x2) <= _PARALLEL * size).any() or (size == 0).any():
        raise ArgumentError("reference", "has no component across the beam (it is along "
                            "the direction of propagation)", value=reference)
    out = np.arctan2(x1, x2)  # gamma: cos along e2, sin along e1
    return float(out) if out.ndim == 0 else out


def _frame_matrix(reference: ArrayLike, theta_i: ArrayLike, theta_r: ArrayLike,
                  phi: ArrayLike, beam: str, basis: str, left_handed: bool) -> np.ndarray:
    """``T`` with ``S_user = T S_ours`` (module notes of :func:`from_frame`)."""
    chi = reference_angle(reference, theta_i, theta_r, phi, beam=beam, basis=basis)
    # the user's Q > 0 axis is at gamma = chi: in a basis with e1 there, gamma' = gamma - (chi -
    # pi/2), so T = rotation by chi - pi/2; a left-handed frame also flips U and V
    t = rotation_matrix(np.asarray(chi) - 0.5 * math.pi)
    if left_handed:
        t = t * np.array([1.0, 1.0, -1.0, -1.0])[:, None]
    return t


def to_frame(stokes: ArrayLike, reference: ArrayLike, theta_i: ArrayLike, theta_r: ArrayLike,
             phi: ArrayLike, *, beam: str = "incident", basis: str = "psps",
             left_handed: bool = False) -> np.ndarray:
    """Stokes vectors (or analyzer rows) from our basis to a polarimeter's frame.

    The polarimeter's frame (see :func:`from_frame`) is its reference axis ``x_u`` (its
    ``Q > 0`` direction) across the beam and ``y_u``: ``{x_u, y_u, k}`` right-handed, or
    left-handed with ``left_handed=True`` (its ``U`` and ``V`` then have the other sign).

    Examples
    --------
    >>> to_frame(s(), [0.0, 0.0, 1.0], 0.5, 0.5, 0.0).round(12).tolist()   # reference ~ p
    [1.0, -1.0, 0.0, 0.0]
    """
    t = _frame_matrix(reference, theta_i, theta_r, phi, beam, basis, left_handed)
    return np.matmul(t, np.asarray(stokes, dtype=float)[..., None])[..., 0]


def from_frame(stokes: ArrayLike, reference: ArrayLike, theta_i: ArrayLike,
               theta_r: ArrayLike, phi: ArrayLike, *, beam: str = "incident",
               basis: str = "psps", left_handed: bool = False) -> np.ndarray:
    """Stokes vectors (or analyzer rows) measured in a polarimeter's frame, in our basis.

    A polarimeter states ``Q > 0`` along its reference axis ``x_u`` (a lab direction, given as
    a 3-vector ``reference`` in the library frame, ``docs/models.md`` §1.1, e.g.
    ``(0, 0, 1)``; only its part across the beam counts), ``U > 0`` along ``x_u + y_u`` and
    ``V > 0`` for the field turning from ``x_u`` to ``y_u``, where ``{x_u, y_u, k}`` is
    right-handed (``k`` the direction of propagation; ``left_handed=True``: ``y_u = x_u x k``).
    This returns the same light on ``(e1, e2)`` of ``basis`` (:func:`basis_vectors`) for the
    ``beam``: a rotation by the angle between ``x_u`` and ``e1``, and for a left-handed frame
    a change of sign of ``U`` and ``V``. Inverse of :func:`to_frame`.

    Examples
    --------
    >>> ref = [0.0, 1.0, 0.0]                      # along s_i: the frames coincide
    >>> from_frame([1.0, 0.2, 0.3, 0.1], ref, 0.4, 0.4, 0.0).round(12).tolist()
    [1.0, 0.2, 0.3, 0.1]
    """
    t = _frame_matrix(reference, theta_i, theta_r, phi, beam, basis, left_handed)
    # T is orthogonal (a rotation, times diag(1, 1, -1, -1) if mirrored): its inverse is T^T
    return np.matmul(np.swapaxes(t, -1, -2), np.asarray(stokes, dtype=float)[..., None])[..., 0]


def change_basis(stokes: ArrayLike, theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike,
                 *, beam: str = "reflected", source: str = "xyxy",
                 target: str = "psps") -> np.ndarray:
    """Stokes vectors of a beam from the ``source`` basis to the ``target`` one.

    The incident bases coincide; the reflected ``xyxy`` basis is ``psps`` turned by
    ``pi - phi`` about ``k`` (:mod:`roughbrdf.mueller`).

    Examples
    --------
    >>> out = change_basis(s(), 0.3, 0.4, np.pi / 2, source="psps", target="xyxy")
    >>> out.round(12).tolist()       # at phi = 90 deg y_r = p_r: s is along x_r
    [1.0, -1.0, 0.0, 0.0]
    """
    e1, e2, _ = basis_vectors(theta_i, theta_r, phi, beam=beam, basis=source)
    return from_frame(stokes, e1, theta_i, theta_r, phi, beam=beam, basis=target)


def mueller_from_frames(mueller: ArrayLike, reference_in: ArrayLike,
                        reference_out: ArrayLike, theta_i: ArrayLike, theta_r: ArrayLike,
                        phi: ArrayLike, *, basis: str = "psps",
                        left_handed: bool = False) -> np.ndarray:
    """A Mueller matrix measured between two polarimeter frames, in our basis.

    ``M_user`` maps Stokes vectors in the source-side frame (``reference_in``, across the
    incident beam) to those in the detector-side frame (``reference_out``, across the
    reflected beam), frames as in :func:`from_frame`; returns ``T_out^-1 M_user T_in``, which
    maps our incident basis to our reflected one (``basis``), as
    :meth:`~roughbrdf.models.Model.mueller` and :attr:`Measurement.mueller
    <roughbrdf.measurement.Measurement.mueller>` data.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> m = rb.model("microfacet", distribution="beckmann", alpha=0.3, n=0.2, k=3.0)
    >>> M = m.mueller(0.5, 0.6, 0.4)
    >>> s_r = basis_vectors(0.5, 0.6, 0.4, beam="reflected")[0]     # frames equal to ours
    >>> bool(np.allclose(mueller_from_frames(M, [0.0, 1.0, 0.0], s_r, 0.5, 0.6, 0.4), M))
    True
    """
    m = np.asarray(mueller, dtype=float)
    if m.ndim < 2 or m.shape[-2:] != (4, 4):
        raise ArgumentError("mueller", "must have shape (..., 4, 4)", value=m.shape)
    t_in = _frame_matrix(reference_in, theta_i, theta_r, phi, "incident", basis, left_handed)
    t_out = _frame_matrix(reference_out, theta_i, theta_r, phi, "reflected", basis,
                          left_handed)
    return np.swapaxes(t_out, -1, -2) @ m @ t_in

