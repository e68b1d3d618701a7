"""The polarization argument of every evaluation, as one explicit type.

:class:`Polarization` holds the incident polarization per sample as TR75's angle ``gamma``
(radians) of the incident electric field from the macroscopic plane of incidence (TR75 Eq. 24,
``docs/models.md`` §3.5): ``gamma = pi/2`` is s (perpendicular), ``0`` is p (parallel) and NaN
is unpolarized (natural) light. Everything a user may pass as ``polarization=`` is turned into
one by :meth:`Polarization.parse`:

* ``None``, ``"unpolarized"`` (also ``"natural"``, ``"circular"``): unpolarized;
* ``"s"``/``"perpendicular"``/``"te"``, ``"p"``/``"parallel"``/``"tm"``;
* a number: the linear angle ``gamma``; an array (numbers or the names above): one per sample.

Polarimetry (Stokes in, analyzer out) goes through explicit fields, never through the ``gamma``
array: ``stokes``, the incident Stokes vector ``[I, Q, U, V]`` (shape ``(..., 4)``, one per
sample allowed), and ``analyzer``, the detector's row vector ``a`` (shape ``(..., 4)``; None:
the total reflected intensity). With either set the model is evaluated through its Mueller
matrix (:meth:`roughbrdf.models.Model.mueller`, in ``basis``) as ``a . (M S)``
(:func:`roughbrdf.models.polarimetry.evaluate_stokes`); ``gamma`` (NaN: unpolarized) gives
``S`` when ``stokes`` is not set. The ``s``, ``p``, ``gamma`` and unpolarized evaluations
without an analyzer stay on the scalar kernels, unchanged. Stokes vectors, angles and
handedness follow the conventions of :mod:`roughbrdf.mueller`; :mod:`roughbrdf.stokes` builds
the vectors (``stokes.linear(gamma)``, ``stokes.circular(...)``, ``stokes.analyzer_row(...)``)
and checks them (:func:`roughbrdf.stokes.as_stokes`).

Examples
--------
>>> from roughbrdf.polarization import Polarization
>>> Polarization.parse("s").gamma
array(1.57079633)
>>> Polarization.parse(None).is_unpolarized
True
>>> pol = Polarization(stokes=[1.0, 0.0, 0.0, 1.0])
>>> pol.is_polarimetric, pol.incident_stokes().tolist()
(True, [1.0, 0.0, 0.0, 1.0])
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .errors import ArgumentError
from .fresnel import polarization_angle

# the vectors and their check live in roughbrdf.stokes; BASES and PHYSICAL_RTOL stay
# importable from here, where they were first defined
from .stokes import BASES, PHYSICAL_RTOL, as_stokes, linear, unpolarized  # noqa: F401

__all__ = ["Polarization", "BASES"]


@dataclass(frozen=True)
class Polarization:
    """Incident polarization (one value of ``gamma`` per sample, or one for all), or a
    polarimetric setting: an incident Stokes vector and/or an analyzer.

    Attributes
    ----------
    gamma : numpy.ndarray
        TR75's polarization angle in radians, broadcastable against the angles; NaN entries
        are unpolarized.
    stokes : numpy.ndarray or None
        Incident Stokes vector ``[I, Q, U, V]``, shape ``(..., 4)`` (the leading axes broadcast
        against the angles: one vector per sample allowed), in ``basis``; ``I`` is the
        incident irradiance (1: values per unit irradiance, as a BRDF). Must be a physical
        state, ``I >= |(Q, U, V)|``. None: from ``gamma``. Not together with a ``gamma``.
    analyzer : numpy.ndarray or None
        The detector's row vector ``a`` (the first row of its Mueller matrix), shape
        ``(..., 4)``, in ``basis``: the value is ``a . S_out``. ``[1, 0, 0, 0]`` (or None) is
        the total intensity; an ideal polarizer passing the state ``S`` (``S0 = 1``) has
        ``a = S/2`` (:func:`roughbrdf.stokes.analyzer_row`). Must satisfy
        ``a0 >= |(a1, a2, a3)|`` (no negative reading for any light).
    basis : {"psps", "xyxy"}
        Basis of ``stokes`` and ``analyzer`` (:mod:`roughbrdf.mueller`); ``"xyxy"`` needs an
        explicit ``stokes`` (``gamma`` is an angle from the plane of incidence, a ``psps``
        notion).
    """

    gamma: np.ndarray = field(default_factory=lambda: np.asarray(np.nan))
    stokes: Any = None
    analyzer: Any = None
    basis: str = "psps"

    def __post_init__(self) -> None:
        if self.stokes is not None:
            object.__setattr__(self, "stokes", as_stokes(self.stokes, "stokes"))
            if not np.isnan(np.asarray(self.gamma, dtype=float)).all():
                raise ArgumentError("stokes", "give the incident polarization once: either "
                                    "an angle gamma or a Stokes vector", value=self.gamma)
        if self.analyzer is not None:
            object.__setattr__(self, "analyzer", as_stokes(self.analyzer, "analyzer"))
        if self.basis not in BASES:
            raise ArgumentError("basis", f"must be one of {', '.join(BASES)}",
                                value=self.basis)
        if self.basis != "psps" and self.stokes is None:
            raise ArgumentError("basis", "gamma is an angle from the plane of incidence (the "
                                "psps basis): give the incident Stokes vector in this basis",
                                value=self.basis)

    @classmethod
    def from_stokes(cls, stokes: Any, analyzer: Any = None, *, basis: str = "psps"
                    ) -> Polarization:
        """An incident Stokes vector (and optionally an analyzer row) in ``basis``."""
        return cls(np.asarray(np.nan), stokes, analyzer, basis)

    @property
    def is_polarimetric(self) -> bool:
        """Whether a Stokes vector or an analyzer is set (evaluation through the Mueller
        matrix, :func:`roughbrdf.models.polarimetry.evaluate_stokes`)."""
        return self.stokes is not None or self.analyzer is not None

    def incident_stokes(self) -> np.ndarray:
        """The incident Stokes vector, shape ``(..., 4)``: ``stokes``, or the one of
        ``gamma`` (:func:`roughbrdf.stokes.linear`; unpolarized ``[1, 0, 0, 0]`` where NaN)."""
        if self.stokes is not None:
            return self.stokes
        gam = np.asarray(self.gamma, dtype=float)
        nan = np.isnan(gam)[..., None]
        return np.where(nan, unpolarized(), linear(np.where(nan[..., 0], 0.0, gam)))

    def kernel_gamma(self) -> np.ndarray:
        """``gamma`` for the scalar kernels; ArgumentError naming ``polarization`` when a
        Stokes vector or an analyzer is set (the scalar kernels would drop them)."""
        if self.is_polarimetric:
            raise ArgumentError("polarization", "an incident Stokes vector or an analyzer is "
                                "evaluated through the Mueller matrix by Model.evaluate/brdf "
                                "(or roughbrdf.stokes.reflected_stokes); prepare(), apertures "
                                "and albedos take 's', 'p', an angle gamma or unpolarized")
        return self.gamma

    @classmethod
    def unpolarized(cls) -> Polarization:
        """Natural (unpolarized) light."""
        return cls(np.asarray(np.nan))

    @classmethod
    def linear(cls, gamma: Any) -> Polarization:
        """Linear polarization at angle(s) ``gamma`` (radians) from the plane of incidence."""
        return cls.parse(np.asarray(gamma, dtype=np.float64))

    @classmethod
    def parse(cls, value: Any) -> Polarization:
        """A :class:`Polarization` from any accepted ``polarization=`` argument.

        Raises :class:`~roughbrdf.errors.ArgumentError` (a ``ValueError``) naming
        ``polarization`` and the offending value for an unknown name, a value that is not a
        real number (complex, bytes, a dict ...), an infinite angle or a ragged array.
        """
        if isinstance(value, Polarization):
            return value
        if value is None or isinstance(value, str):
            return cls(np.asarray(_gamma(value), dtype=np.float64))
        if isinstance(value, bool | int | float | np.integer | np.floating):
            return cls(np.asarray(_gamma(value), dtype=np.float64))
        try:
            arr = np.asarray(value)
        except (TypeError, ValueError, OverflowError):
            raise _bad(value) from None
        if arr.dtype.kind in "biuf":
            gam = np.asarray(arr, dtype=np.float64)
            if np.isinf(gam).any():
                _gamma(float(gam[np.isinf(gam)].flat[0]))  # raises naming the value
            return cls(gam)  # NaN entries mean unpolarized
        if arr.dtype.kind in "UO":
            return cls(np.vectorize(_gamma, otypes=[np.float64])(arr))
        raise _bad(value)

    @property
    def is_unpolarized(self) -> bool:
        """Whether every sample is unpolarized (natural light, no analyzer)."""
        if self.analyzer is not None:
            return False
        if self.stokes is not None:
            return bool((self.stokes[..., 1:] == 0).all())
        return bool(np.isnan(self.gamma).all())


def _bad(value: Any) -> ArgumentError:
    shown = repr(value)
    shown = shown if len(shown) <= 80 else shown[:70] + " ..."
    return ArgumentError("polarization", f"polarization must be 's', 'p', 'unpolarized' (None) "
                         f"or an angle gamma in radians, got {shown}")


def _gamma(value: Any) -> float:
    """TR75's gamma of one polarization value (a name, None or a real number)."""
    if value is None or isinstance(value, str):
        name: str | None = value
        try:
            return polarization_angle(name)
        except ValueError:
            raise _bad(value) from None
    if not isinstance(value, bool | int | float | np.integer | np.floating):
        raise _bad(value)
    try:
        g = float(value)
    except OverflowError:  # an int beyond the float range
        raise _bad(value) from None
    if not math.isfinite(g):
        raise ArgumentError("polarization", "the polarization angle gamma must be finite",
                            value=g, unit="rad")
    return g
