"""Is a fitted model physically plausible? Its albedo by incidence and its peak against the data's.

Two checks of every fitted channel, in ``fit.json``, the report, ``compare`` and the
catalogue (``docs/fitting.md``, "Plausibility"):

* the **albedo** (directional-hemispherical reflectance, :func:`roughbrdf.albedo`) of the fitted
  model at the incidences :data:`ALBEDO_INCIDENCES_DEG`: a surface cannot reflect more than it
  receives, so an albedo above ``1 +`` :data:`ENERGY_TOLERANCE` (the quadrature is good to
  about 1e-4) means the model *gains energy* there: :class:`EnergyWarning`, exit status 1 at
  the command line, and :mod:`roughbrdf.export` refuses it (over :data:`EXPORT_INCIDENCES_DEG`)
  unless told otherwise;
* the **peak ratio** per measured incidence: the model's maximum over that incidence's fitted
  samples divided by the data's maximum there (the data times the fit's scale ``K``: for
  relative data the scaled data), both the quantity the fit compared. Far from 1, the fitted
  lobe does not have the measured peak height.

The cost: one vectorized :func:`~roughbrdf.albedo` call of the 10 incidences per channel,
about 0.1 s for TR75 (a fit takes seconds).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ...errors import ArgumentError

if TYPE_CHECKING:
    from ...models import Model
    from .result import ChannelFit, FitResult

__all__ = ["ALBEDO_INCIDENCES_DEG", "ENERGY_TOLERANCE", "EXPORT_INCIDENCES_DEG", "EnergyWarning",
           "Plausibility", "albedo_by_incidence", "channel_plausibility", "energy_gain",
           "refuse_energy_gain", "warn_energy"]

#: incidences (degrees) of the albedo reported for every fitted channel
ALBEDO_INCIDENCES_DEG: tuple[float, ...] = (0, 10, 20, 30, 40, 50, 60, 70, 80, 85)
#: incidences (degrees) an export checks: a model gaining energy at any is refused
EXPORT_INCIDENCES_DEG: tuple[float, ...] = (*range(0, 86, 5), 89)
#: an albedo above ``1 + ENERGY_TOLERANCE`` gains energy (:func:`roughbrdf.albedo` is good to
#: about 1e-4: a margin ten times that)
ENERGY_TOLERANCE = 1e-3


class EnergyWarning(UserWarning):
    """A fitted model reflects more light than it receives at some incidence (albedo > 1)."""


def albedo_by_incidence(model: Model, theta_deg: Sequence[float] = ALBEDO_INCIDENCES_DEG
                        ) -> np.ndarray:
    """:func:`roughbrdf.albedo` of ``model`` at the incidences ``theta_deg`` (degrees)."""
    from ...integrate import albedo

    return np.atleast_1d(np.asarray(albedo(model, np.radians(np.asarray(theta_deg, float))),
                                    dtype=float))


def energy_gain(model: Model, theta_deg: Sequence[float] = EXPORT_INCIDENCES_DEG
                ) -> tuple[float, float] | None:
    """``(incidence in degrees, albedo)`` where ``model`` reflects the most when that albedo
    exceeds ``1 +`` :data:`ENERGY_TOLERANCE`, else None."""
    a = albedo_by_incidence(model, theta_deg)
    if not np.any(a > 1 + ENERGY_TOLERANCE):  # NaN compares False: not a gain
        return None
    j = int(np.nanargmax(a))
    return float(theta_deg[j]), float(a[j])


def refuse_energy_gain(models: Mapping[Any, Model], allow: Any) -> list[str]:
    """Refuse to export a model that gains energy (:func:`energy_gain` over
    :data:`EXPORT_INCIDENCES_DEG`), unless ``allow`` (``allow_energy_gain=True``).

    ``models`` maps channel labels (None or ``""``: a model) to models. Raises an
    :class:`~roughbrdf.errors.ArgumentError` of ``allow_energy_gain`` naming the channel, the
    albedo and the incidence; with ``allow``, returns one line per such model for the file
    written (Zemax comment, Mitsuba XML comment or JSON key), else ``[]``.
    """
    if not isinstance(allow, bool):  # a string "no" would be truthy
        raise ArgumentError("allow_energy_gain", "must be True or False", value=allow)
    notes = []
    for label, m in models.items():
        gain = energy_gain(m)
        if gain is None:
            continue
        where = f" (channel {label})" if label not in (None, "") else ""
        text = (f"the model{where} reflects more than it receives: albedo {gain[1]:.4g} at "
                f"theta_i = {gain[0]:g} deg ({math.radians(gain[0]):.4g} rad), above "
                f"1 + {ENERGY_TOLERANCE:g}")
        if not allow:
            raise ArgumentError("allow_energy_gain", text + "; not exported (not physical)",
                                fix=True)
        notes.append(f"allow_energy_gain: exported although {text}")
    return notes


@dataclass(frozen=True)
class Plausibility:
    """The plausibility figures of one fitted channel (module notes).

    Attributes
    ----------
    albedo_theta_deg, albedo : tuple of float
        Incidences (degrees) and the fitted model's albedo there.
    peak_theta_deg, peak_ratio : tuple of float
        Measured incidences (degrees) and max(model)/max(K x) over their fitted samples
        (NaN where the data's maximum is not positive).
    """

    albedo_theta_deg: tuple[float, ...]
    albedo: tuple[float, ...]
    peak_theta_deg: tuple[float, ...]
    peak_ratio: tuple[float, ...]

    @property
    def max_albedo(self) -> float:
        """The largest albedo (NaN when none is finite)."""
        finite = [a for a in self.albedo if math.isfinite(a)]
        return max(finite) if finite else math.nan

    @property
    def gains_energy(self) -> bool:
        """Whether the albedo exceeds ``1 +`` :data:`ENERGY_TOLERANCE` at some incidence."""
        return self.max_albedo > 1 + ENERGY_TOLERANCE

    @property
    def worst_incidence(self) -> float:
        """The incidence (degrees) of :attr:`max_albedo` (NaN without one)."""
        if not math.isfinite(self.max_albedo):
            return math.nan
        return self.albedo_theta_deg[self.albedo.index(self.max_albedo)]

    def to_dict(self) -> dict[str, Any]:
        """The keys this adds to a channel of ``fit.json``."""
        return {"albedo": {"theta_i_deg": list(self.albedo_theta_deg),
                           "value": list(self.albedo)},
                "max_albedo": self.max_albedo, "gains_energy": self.gains_energy,
                "peak_ratio": {"theta_i_deg": list(self.peak_theta_deg),
                               "value": list(self.peak_ratio)}}

    def lines(self) -> list[str]:
        """The report's lines."""
        alb = ", ".join(f"{t:g}: {a:.4g}" for t, a in zip(self.albedo_theta_deg, self.albedo,
                                                         strict=True))
        peak = ", ".join(f"{t:g}: {r:.3g}" for t, r in zip(self.peak_theta_deg, self.peak_ratio,
                                                          strict=True))
        out = ["[[Plausibility]]",
               f"    albedo (TIS) by theta_i (deg): {alb}",
               f"    peak model/data by theta_i (deg): {peak or 'none'}"]
        if self.gains_energy:
            out.append(f"    GAINS ENERGY: albedo {self.max_albedo:.4g} > 1 at theta_i = "
                       f"{self.worst_incidence:g} deg (not physical; export refuses it)")
        return out


def peak_ratios(theta_i: np.ndarray, data: np.ndarray, fitted: np.ndarray
                ) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Per incidence of ``theta_i`` (radians; to 1e-6 deg): max(fitted)/max(data)."""
    deg = np.round(np.degrees(np.asarray(theta_i, float)), 6)
    thetas, ratios = [], []
    for t in np.unique(deg):
        sel = deg == t
        top = float(np.max(data[sel]))
        # a data maximum <= 0 (or NaN) gives no ratio
        ratios.append(float(np.max(fitted[sel])) / top if top > 0 else math.nan)
        thetas.append(float(t))
    return tuple(thetas), tuple(ratios)


def channel_plausibility(c: ChannelFit, theta_i: np.ndarray) -> Plausibility:
    """The :class:`Plausibility` of channel fit ``c``; ``theta_i`` the incidences (radians)
    of its fitted samples (``c.index``)."""
    a = albedo_by_incidence(c.model)
    fitted = np.asarray(c.fitted, float).reshape(c.data.shape[0], -1)[:, 0]
    data = c.scale * np.asarray(c.data, float).reshape(c.data.shape[0], -1)[:, 0]
    th, r = peak_ratios(theta_i, data, fitted)
    return Plausibility(tuple(float(t) for t in ALBEDO_INCIDENCES_DEG),
                        tuple(float(v) for v in a), th, r)


def warn_energy(result: FitResult, what: str = "fitted model", stacklevel: int = 3) -> None:
    """One :class:`EnergyWarning` per channel of ``result`` whose model gains energy."""
    for i, c in enumerate(result.channels):
        p = result.plausibility(i)
        if p.gains_energy:
            warnings.warn(
                f"the {what} {result.model_name} of channel {c.channel} reflects more than it "
                f"receives: albedo {p.max_albedo:.4g} at theta_i = {p.worst_incidence:g} deg "
                f"(> 1 + {ENERGY_TOLERANCE:g}); not physical", EnergyWarning,
                stacklevel=stacklevel)
