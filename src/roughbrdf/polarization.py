"""The polarization argument of every evaluation, as one explicit type.

:class:`Polarization` holds the incident polarization per sample as TR75's angle ``gamma``
(radians) of the incident electric field from the macroscopic plane of incidence (TR75 Eq. 24,
``docs/models.md`` §3.5): ``gamma = pi/2`` is s (perpendicular), ``0`` is p (parallel) and NaN
is unpolarized (natural) light. Everything a user may pass as ``polarization=`` is turned into
one by :meth:`Polarization.parse`:

* ``None``, ``"unpolarized"`` (also ``"natural"``, ``"circular"``): unpolarized;
* ``"s"``/``"perpendicular"``/``"te"``, ``"p"``/``"parallel"``/``"tm"``;
* a number: the linear angle ``gamma``; an array (numbers or the names above): one per sample.

Two fields are reserved for polarimetry (an incident Stokes vector and an analyzer); the
evaluation paths of this version reject them rather than ignore them.

Examples
--------
>>> from roughbrdf.polarization import Polarization
>>> Polarization.parse("s").gamma
array(1.57079633)
>>> Polarization.parse(None).is_unpolarized
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .errors import ArgumentError
from .fresnel import polarization_angle

__all__ = ["Polarization"]


@dataclass(frozen=True)
class Polarization:
    """Incident polarization, one value of ``gamma`` per sample (or one for all).

    Attributes
    ----------
    gamma : numpy.ndarray
        TR75's polarization angle in radians, broadcastable against the angles; NaN entries
        are unpolarized.
    stokes, analyzer : None
        Reserved for an incident Stokes vector and an analyzer (polarimetric evaluation);
        must be ``None`` in this version.
    """

    gamma: np.ndarray = field(default_factory=lambda: np.asarray(np.nan))
    stokes: Any = None
    analyzer: Any = None

    def __post_init__(self) -> None:
        if self.stokes is not None or self.analyzer is not None:
            raise ArgumentError("polarization", "polarization: an incident Stokes vector or an "
                                "analyzer is not supported by this version (use 's', 'p' or "
                                "an angle gamma)")

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
        """Whether every sample is unpolarized."""
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
