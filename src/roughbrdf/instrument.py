"""The instrument's angular response: the model averaged over the aperture cone.

A gonioreflectometer does not measure the BRDF in one direction: its detector and source see
small cones, and a peak narrower than them is read flat-topped (the CEA gray tape's retro peak,
``docs/fitting.md``, "Instrument aperture"). Here the instrument is a **uniform cone of half-angle**
``a`` (uniform in solid angle, i.e. a spherical cap) **about the measured reflection direction**
``w_r``, ``theta_i`` kept: each sample reads the average of the model over that cone. The cone
stands for the combined response of source and detector (for a peak that depends on the angle
between ``w_r`` and a fixed direction, retro or mirror, a source cone acts like a detector cone
of the same size).

The average is a fixed cubature rule (:func:`aperture_stencil`): the cone's axis plus rings at
Gauss-Radau values (:func:`gauss_radau01`, the node ``u = 0`` is the axis) of
``u = (1 - cos beta)/(1 - cos a)``, which is uniform on [0, 1] over the cap, with equally spaced
azimuths on each ring and alternate rings staggered. ``points`` chooses the rule
(:data:`APERTURE_POINTS`):

====  ======================  ==============================================================
 S    rings x points          exact (to round-off) for polynomials of the direction vector's
                              components of degree <= (flat-disk limit: degree in the plane)
====  ======================  ==============================================================
 7    1 x 6 (Radon's rule)    2   (5)
 19   2 x 9 (default)         4   (8)
 37   3 x 12                  6   (11)
====  ======================  ==============================================================

so a constant and any quadratic function of direction are averaged exactly by every rule
(``tests/fitting/test_fitting.py`` checks each degree against a 40 x 64-point product rule).

Near grazing, nodes of the cone below the surface are clipped to the horizon (``theta_r = 90``
deg, same azimuth, :func:`aperture_directions`): BRDF cos(theta_r) is 0 there for every model,
and a model whose BRDF is infinite at the horizon makes such a sample not finite (a fit leaves it
out and counts it).

Used by :func:`roughbrdf.fit` (``aperture=``), :meth:`roughbrdf.fitting.FitResult.predict` and
:func:`roughbrdf.plot.plot_comparison` (``aperture=``). The perturbed directions of ``N`` samples
are built once (:class:`InstrumentGeometry`) and the model is evaluated on all ``N x S``
directions in one call of its compiled kernel.

Examples
--------
>>> import math
>>> import roughbrdf as rb
>>> from roughbrdf import instrument
>>> beta, psi, weight = instrument.aperture_stencil(math.radians(1.0), 7)
>>> beta.size, round(float(weight.sum()), 12)
(7, 1.0)
>>> lam = rb.model("lambertian", rho=0.5)           # a constant is averaged exactly
>>> value = instrument.aperture_average(lam, 0.3, 0.5, 0.0, math.radians(2.0))
>>> round(float(value) * math.pi, 12)
0.5
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from .errors import ArgumentError
from .quantity import Quantity

if TYPE_CHECKING:
    from .models import Model, PreparedGeometry

__all__ = [
    "APERTURE_POINTS",
    "Aperture",
    "InstrumentGeometry",
    "aperture_average",
    "aperture_directions",
    "aperture_stencil",
    "check_aperture",
    "gauss_radau01",
]

#: stencil sizes accepted by ``points`` / ``aperture_points`` -> (rings, points per ring)
APERTURE_POINTS: dict[int, tuple[int, int]] = {7: (1, 6), 19: (2, 9), 37: (3, 12)}


def _check_points(points: Any) -> int:
    try:
        ok = not isinstance(points, bool) and points in APERTURE_POINTS
    except TypeError:  # unhashable
        ok = False
    if not ok:
        raise ArgumentError("aperture_points", f"aperture_points must be one of "
                            f"{sorted(APERTURE_POINTS)}, got {points!r}")
    return int(points)


# --------------------------------------------------------------------------------------------
# the cubature rule
# --------------------------------------------------------------------------------------------
def gauss_radau01(m: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Radau rule on [0, 1] with the node 0 and ``m`` interior nodes.

    Exact for polynomials of degree ``<= 2m``.

    Parameters
    ----------
    m : int
        Number of nodes besides ``u = 0``.

    Returns
    -------
    u, weight : numpy.ndarray, shape (m + 1,)
        Nodes (``u[0] = 0``, increasing) and weights (summing to 1).

    Examples
    --------
    >>> u, w = gauss_radau01(1)
    >>> u.round(12).tolist(), w.round(12).tolist()
    ([0.0, 0.666666666667], [0.25, 0.75])
    """
    from numpy.polynomial import legendre as leg
    from numpy.polynomial import polynomial as poly

    # on [-1, 1] with the node -1: the other nodes are the roots of (P_m + P_{m+1})/(1 + x)
    c = np.zeros(m + 2)
    c[m] = c[m + 1] = 1.0
    q, _ = poly.polydiv(leg.leg2poly(c), [1.0, 1.0])
    x = np.sort(np.real(poly.polyroots(q)))
    u = np.concatenate([[0.0], 0.5 * (x + 1.0)])
    # weights from the moments int_0^1 u^k du = 1/(k+1), k = 0..m (the rule is then exact to 2m)
    vander = np.vander(u, m + 1, increasing=True).T
    w = np.linalg.solve(vander, 1.0 / np.arange(1, m + 2))
    return u, w


def aperture_stencil(aperture: float, points: int = 19
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cubature rule for the average over a uniform cone of half-angle ``aperture`` (radians).

    Parameters
    ----------
    aperture : float
        Half-angle of the cone, radians.
    points : {7, 19, 37}
        Size of the rule (:data:`APERTURE_POINTS`; accuracy in the module notes).

    Returns
    -------
    beta, psi, weight : numpy.ndarray, shape (points,)
        Polar angle of each node from the cone's axis, its azimuth about the axis, and weights
        summing to 1. The first node is the axis.

    Examples
    --------
    >>> beta, psi, w = aperture_stencil(0.1, 19)
    >>> float(beta[0]), bool(beta.max() <= 0.1), w.size
    (0.0, True, 19)
    """
    rings, per = APERTURE_POINTS[_check_points(points)]
    u, wu = gauss_radau01(rings)
    one_minus_cos = 2.0 * math.sin(0.5 * aperture) ** 2  # 1 - cos(a) without cancellation
    beta = [0.0]
    psi = [0.0]
    wt = [wu[0]]
    for r in range(1, rings + 1):
        b = math.acos(1.0 - u[r] * one_minus_cos)
        offset = math.pi / per if r % 2 == 0 else 0.0  # alternate rings are staggered
        for k in range(per):
            beta.append(b)
            psi.append(offset + 2.0 * math.pi * k / per)
            wt.append(wu[r] / per)
    return np.array(beta), np.array(psi), np.array(wt)


def aperture_directions(theta_r: ArrayLike, phi: ArrayLike, aperture: float, points: int = 19
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Reflection directions of the stencil's nodes about each measured direction.

    Parameters
    ----------
    theta_r, phi : array_like, shape (N,)
        The measured reflection directions (radians, the library's frame).
    aperture : float
        Half-angle of the cone, radians.
    points : {7, 19, 37}
        Size of the rule.

    Returns
    -------
    theta_r, phi : numpy.ndarray, shape (N, points)
        The nodes' angles (the first column is the measured direction itself). Nodes below the
        surface are clipped to the horizon (``theta_r = pi/2``, same azimuth).
    weight : numpy.ndarray, shape (points,)
        The stencil's weights.

    Examples
    --------
    >>> tr, ph, w = aperture_directions([0.5], [0.0], 0.01, 7)
    >>> tr.shape, float(tr[0, 0]), bool(abs(tr[0, 1] - 0.5) <= 0.01)
    ((1, 7), 0.5, True)
    """
    from . import geometry

    beta, psi, wt = aperture_stencil(aperture, points)
    tr = np.asarray(theta_r, dtype=float)[:, None]
    ph = np.asarray(phi, dtype=float)[:, None]
    zero = np.zeros_like(tr)
    w_i, w_r = geometry.unit_vectors(zero, tr, ph)  # (N, 1, 3); w_i only for the conversion
    # orthonormal frame about w_r: d w_r/d theta_r and d w_r/d phi / sin(theta_r); both are
    # defined at the pole, so the cone is right for theta_r = 0 too
    e1 = np.stack([np.cos(tr) * np.cos(ph), np.cos(tr) * np.sin(ph), -np.sin(tr)], axis=-1)
    e2 = np.stack([-np.sin(ph), np.cos(ph), zero], axis=-1)
    cb, sb = np.cos(beta)[:, None], np.sin(beta)[:, None]
    cp, sp = np.cos(psi)[:, None], np.sin(psi)[:, None]
    w = cb * w_r + sb * (cp * e1 + sp * e2)  # (N, S, 3)
    _, tr_s, ph_s = geometry.angles_from_vectors(np.broadcast_to(w_i, w.shape), w)
    # horizon guard: the part of a cone below the surface, where no model is defined
    tr_s = np.minimum(tr_s, 0.5 * math.pi)
    return tr_s, ph_s, wt


# --------------------------------------------------------------------------------------------
# the aperture as a value
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Aperture:
    """An instrument aperture: a uniform cone of half-angle ``half_angle`` about ``w_r``.

    Attributes
    ----------
    half_angle : float
        Radians, ``0 < half_angle < pi/2`` (no aperture is ``None``, see :meth:`parse`).
    points : {7, 19, 37}
        Size of the cubature rule.

    Examples
    --------
    >>> Aperture.parse(0.0) is None
    True
    >>> Aperture.parse(0.02, 7)
    Aperture(half_angle=0.02, points=7)
    """

    half_angle: float
    points: int = 19

    def __post_init__(self) -> None:
        a = check_aperture(self.half_angle, self.points)
        if a is None:
            raise ArgumentError("aperture", "an Aperture needs a half-angle > 0; no aperture is "
                                "None (Aperture.parse gives None for 0)", value=self.half_angle)
        object.__setattr__(self, "half_angle", a)
        object.__setattr__(self, "points", int(self.points))

    @classmethod
    def parse(cls, aperture: Any, points: Any = 19) -> Aperture | None:
        """The aperture for ``aperture`` radians, or None for no aperture (None or 0).

        Raises :class:`~roughbrdf.errors.ArgumentError` (a ``ValueError``, naming
        ``aperture`` or ``aperture_points``) for anything else than a half-angle
        ``0 <= aperture < pi/2`` or a stencil size of :data:`APERTURE_POINTS`.
        """
        a = check_aperture(aperture, points)
        return None if a is None else cls(a, int(points))

    def stencil(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:func:`aperture_stencil` of this aperture."""
        return aperture_stencil(self.half_angle, self.points)

    def directions(self, theta_r: ArrayLike, phi: ArrayLike
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:func:`aperture_directions` of this aperture."""
        return aperture_directions(theta_r, phi, self.half_angle, self.points)

    def to_dict(self) -> dict[str, Any]:
        """The ``fit.json`` description (``half_angle_rad``, ``half_angle_deg``, ``points``,
        ``convention``)."""
        return {"half_angle_rad": self.half_angle,
                "half_angle_deg": math.degrees(self.half_angle),
                "points": self.points,
                "convention": "model averaged over a uniform cone (solid angle) of this "
                              "half-angle about the measured reflection direction"}

    def describe(self) -> str:
        """One line for reports: ``"1 deg half-angle, uniform cone about w_r (19-point
        stencil)"``."""
        return (f"{math.degrees(self.half_angle):.4g} deg half-angle, uniform cone about w_r "
                f"({self.points}-point stencil)")


def check_aperture(aperture: Any, points: Any = 19) -> float | None:
    """The aperture half-angle as a float, or None for no aperture (``None`` or 0).

    Raises
    ------
    roughbrdf.errors.ArgumentError
        (a ``ValueError``) ``aperture`` not a number with ``0 <= aperture < pi/2`` (the value
        in radians, ``unit="rad"``: the CLI shows it in degrees), or ``points`` not one of
        :data:`APERTURE_POINTS`.

    Examples
    --------
    >>> check_aperture(None), check_aperture(0), check_aperture(0.01)
    (None, None, 0.01)
    """
    if aperture is None:
        return None
    need = "must be a cone half-angle >= 0 and below 90 deg (None or 0: no aperture)"
    if isinstance(aperture, str | bytes | bool | complex):
        raise ArgumentError("aperture", need, value=aperture)
    try:
        a = float(aperture)
    except (TypeError, ValueError, OverflowError):
        raise ArgumentError("aperture", need, value=aperture) from None
    if not (math.isfinite(a) and 0.0 <= a < 0.5 * math.pi):
        raise ArgumentError("aperture", need, value=a, unit="rad")
    _check_points(points)  # only with an aperture (without one, the rule is not used)
    return a if a > 0.0 else None


# --------------------------------------------------------------------------------------------
# samples seen through the instrument
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class InstrumentGeometry:
    """``N`` samples as the instrument sees them: the directions to evaluate, and the weights.

    Without an aperture ``geometry`` holds the ``N`` samples themselves and ``weights`` is None;
    with one it holds the ``N x S`` stencil directions, flattened (sample-major) for one kernel
    call, and ``weights`` the ``S`` stencil weights. Build it with :meth:`build`.

    Attributes
    ----------
    geometry : PreparedGeometry
        Arrays of shape (N,) or (N * S,) (``gamma`` may be a 0-d NaN: unpolarized).
    weights : numpy.ndarray or None
        Stencil weights, shape (S,).
    n : int
        Number of samples ``N``.
    """

    geometry: PreparedGeometry
    weights: np.ndarray | None
    n: int

    @classmethod
    def build(cls, theta_i: np.ndarray, theta_r: np.ndarray, phi: np.ndarray,
              gamma: np.ndarray, aperture: Aperture | None) -> InstrumentGeometry:
        """From 1-d arrays of ``N`` samples inside the hemisphere (not checked again) and
        ``gamma`` of shape (N,) or a 0-d NaN."""
        from .models import PreparedGeometry

        ti, tr, ph = (np.ascontiguousarray(a, dtype=float) for a in (theta_i, theta_r, phi))
        gam = np.asarray(gamma, dtype=float)
        if gam.ndim:
            gam = np.ascontiguousarray(gam)
        if aperture is None:
            return cls(PreparedGeometry(ti, tr, ph, gam), None, ti.size)
        tr_s, ph_s, wt = aperture.directions(tr, ph)
        shape = tr_s.shape

        def flat(a: np.ndarray) -> np.ndarray:
            return np.ascontiguousarray(np.broadcast_to(a, shape)).ravel()

        gam_s = flat(gam[:, None]) if gam.ndim else gam
        return cls(PreparedGeometry(flat(ti[:, None]), flat(tr_s), flat(ph_s), gam_s), wt,
                   ti.size)

    @property
    def stencil_size(self) -> int:
        """``S``, the directions per sample (1 without an aperture)."""
        return 1 if self.weights is None else int(self.weights.size)

    def average(self, values: np.ndarray) -> np.ndarray:
        """Per-sample weighted average of values at :attr:`geometry` (shape (N,))."""
        f = np.asarray(values, dtype=float)
        if self.weights is None:
            return f
        return f.reshape(self.n, self.weights.size) @ self.weights

    def evaluate(self, model: Model, quantity: Quantity | str) -> np.ndarray:
        """The model's ``quantity`` as the instrument reads it at each sample (one kernel
        call), shape (N,)."""
        return self.average(np.asarray(model.evaluate_prepared(self.geometry, quantity),
                                       dtype=float))

    def take(self, index: np.ndarray) -> InstrumentGeometry:
        """The samples at ``index`` (integer indices into the ``N`` samples)."""
        from .models import PreparedGeometry

        s = self.stencil_size
        index = np.asarray(index)

        def pick(a: np.ndarray) -> np.ndarray:
            if a.ndim == 0:
                return a
            return np.ascontiguousarray(a.reshape(self.n, s)[index]).ravel()

        g = self.geometry
        return InstrumentGeometry(PreparedGeometry(pick(g.theta_i), pick(g.theta_r),
                                                   pick(g.phi), pick(g.gamma)),
                                  self.weights, int(index.size))


def aperture_average(model: Model, theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike,
                     aperture: float | Aperture | None, *, points: int = 19,
                     quantity: str = "brdf", polarization: Any = None) -> np.ndarray | float:
    """Average of ``model`` over a uniform cone of half-angle ``aperture`` about each ``w_r``.

    What an instrument of that angular response would read; the prediction :func:`roughbrdf.fit`
    compares with the data when given ``aperture``.

    Parameters
    ----------
    model : Model
    theta_i, theta_r, phi : array_like
        Geometry (radians), broadcast together; checked like :meth:`Model.prepare
        <roughbrdf.models.Model.prepare>`.
    aperture : float, Aperture or None
        Half-angle, radians (``None`` or 0: the model itself); an :class:`Aperture` brings its
        own ``points``.
    points : {7, 19, 37}
        Size of the cubature rule (for a float ``aperture``).
    quantity : {"brdf", "bridf"}
        ``"bridf"`` is BRDF cos(theta_r), averaged as such.
    polarization : optional
        As for :meth:`Model.evaluate <roughbrdf.models.Model.evaluate>`.

    Returns
    -------
    numpy.ndarray or float
        Broadcast shape of the inputs; a float for scalar inputs.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> m = rb.model("lambertian", rho=0.3)
    >>> aperture_average(m, [0.1, 0.2], [0.3, 0.4], 0.0, 0.05, quantity="brdf").round(6)
    array([0.095493, 0.095493])
    """
    if isinstance(aperture, Aperture):
        ap: Aperture | None = aperture
    else:
        ap = Aperture.parse(aperture, points)
    q = Quantity.parse(quantity)
    if q is Quantity.RELATIVE:  # the average of a ratio to the specular value is not defined
        raise ArgumentError("quantity", f"quantity must be 'brdf' or 'bridf', got {quantity!r}")
    g = model.prepare(theta_i, theta_r, phi, polarization)
    if ap is None:
        return model.evaluate_prepared(g, q)
    ti, tr, ph, gam = np.broadcast_arrays(g.theta_i, g.theta_r, g.phi, g.gamma)
    shape = ti.shape
    inst = InstrumentGeometry.build(ti.ravel(), tr.ravel(), ph.ravel(), gam.ravel(), ap)
    out = inst.evaluate(model, q)
    return float(out[0]) if shape == () else out.reshape(shape)
