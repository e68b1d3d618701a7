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

from dataclasses import dataclass, field
from typing import Any

import numpy as np

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
            raise ValueError("polarization: an incident Stokes vector or an analyzer is not "
                             "supported by this version (use 's', 'p' or an angle gamma)")

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

        Raises ``ValueError`` naming the offending value for an unknown name, a non-numeric
        value or an infinite angle.
        """
        if isinstance(value, Polarization):
            return value
        if value is None or isinstance(value, str | float | int):
            return cls(np.asarray(polarization_angle(value), dtype=np.float64))
        arr = np.asarray(value)
        if arr.dtype.kind in "US" or arr.dtype == object:
            try:
                gam = np.vectorize(polarization_angle, otypes=[np.float64])(arr)
            except TypeError as exc:
                raise ValueError(f"polarization must be 's', 'p', 'unpolarized' or angles in "
                                 f"radians, got {value!r}") from exc
            return cls(gam)
        try:
            gam = np.asarray(arr, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"polarization must be numeric, got {value!r}") from exc
        if np.isinf(gam).any():
            bad = gam[np.isinf(gam)].flat[0]
            raise ValueError(f"polarization angle gamma must be finite, got {bad!r}")
        return cls(gam)  # NaN entries mean unpolarized

    @property
    def is_unpolarized(self) -> bool:
        """Whether every sample is unpolarized."""
        return bool(np.isnan(self.gamma).all())
