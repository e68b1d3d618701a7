"""How far an export is from its model: the deviation grid and :class:`Deviation`.

Every export reports ``|f_Mitsuba - f|/f`` (r.m.s. and maximum) on :func:`deviation_grid`, with
``f_Mitsuba`` from :func:`roughbrdf.export.mitsuba.emulation.mitsuba_values`; a mapping is
"exact" when the maximum is at most :data:`EXACT` (package notes, :mod:`roughbrdf.export.mitsuba`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ...errors import ArgumentError

__all__ = ["EXACT", "FLOOR", "PEAK_FLOOR", "Deviation", "deviation_grid"]

#: half of the 1e-4 the tests check with Mitsuba, the other half for its float32 arithmetic
EXACT = 5e-5
#: BRDF values (sr^-1) below which deviations count as absolute, not relative: Mitsuba sets
#: ``D`` to 0 where ``D cos(theta_h) <= 1e-20``, which removes BRDF values up to ~5e-19 for
#: ``theta <= 80 deg`` (far tails of narrow Beckmann lobes); 1e-12 keeps that below 1e-6
FLOOR = 1e-12
#: ... and values below this fraction of the model's largest value on the grid: where a
#: narrow lobe's tail underflows to 0, any other lobe shape is infinitely far in relative terms
PEAK_FLOOR = 1e-6


@dataclass(frozen=True)
class Deviation:
    """Relative deviation ``|f_Mitsuba - f|/max(f, floor)`` of an export from its model;
    ``floor = max(FLOOR, PEAK_FLOOR max(f))`` (:data:`FLOOR`, :data:`PEAK_FLOOR`).

    Attributes
    ----------
    rms, max : float
        Root mean square and maximum over the samples (every channel).
    points : int
        Number of geometries (:func:`deviation_grid`).
    """

    rms: float
    max: float
    points: int

    @classmethod
    def of(cls, mitsuba: np.ndarray, model: np.ndarray) -> Deviation:
        """From Mitsuba's values and the model's (same shape)."""
        floor = max(FLOOR, PEAK_FLOOR * float(np.max(np.abs(model))))
        rel = np.abs(mitsuba - model) / np.maximum(np.abs(model), floor)
        return cls(float(np.sqrt(np.mean(rel * rel))), float(rel.max()), int(model.shape[-1]))



@lru_cache(maxsize=8)
def _grid(theta_max: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    from ...geometry import from_rusinkiewicz

    # a regular grid in the library's angles ...
    a, b, c = np.meshgrid(np.linspace(0.0, theta_max, 9), np.linspace(0.0, theta_max, 17),
                          np.linspace(0.0, math.pi, 13), indexing="ij")
    # ... and one in Rusinkiewicz's half/difference angles, dense near the specular peak
    # (theta_h quadratic in the index), where the narrow lobes are; phi_d in [0, pi/2] covers
    # an isotropic, reciprocal BRDF
    h, d, p = np.meshgrid(0.5 * math.pi * (np.arange(24) / 24.0) ** 2,
                          np.linspace(0.0, math.radians(85.0), 18),
                          np.linspace(0.0, 0.5 * math.pi, 7), indexing="ij")
    ti, tr, ph = from_rusinkiewicz(h.ravel(), d.ravel(), p.ravel())
    keep = np.isfinite(ti) & np.isfinite(tr) & (ti <= theta_max) & (tr <= theta_max)
    out = (np.concatenate([a.ravel(), ti[keep]]), np.concatenate([b.ravel(), tr[keep]]),
           np.concatenate([c.ravel(), np.abs(ph[keep])]))
    for x in out:
        x.setflags(write=False)
    return out


def deviation_grid(theta_max: float = math.radians(80.0)
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The geometries ``(theta_i, theta_r, phi)`` (radians) of the reported deviations and of
    the fits: a 9 x 17 x 13 grid of ``theta_i, theta_r <= theta_max``, ``phi`` in [0, pi],
    and a half/difference-angle grid dense near the specular direction (about 4700 in all).

    Examples
    --------
    >>> from roughbrdf.export.mitsuba import deviation_grid
    >>> ti, tr, phi = deviation_grid()
    >>> ti.size > 4000, round(float(max(ti.max(), tr.max())), 4)   # 80 deg
    (True, 1.3963)
    """
    t = float(theta_max)
    if not (0.0 < t < 0.5 * math.pi):
        raise ArgumentError("theta_max", "must be in (0, pi/2) radians", value=theta_max,
                            unit="rad")
    return _grid(t)
