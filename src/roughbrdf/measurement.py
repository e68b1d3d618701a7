"""The Measurement type: geometry in the common frame, values per channel, provenance.

Data flows one way: file -> reader (:mod:`roughbrdf.io`) -> :class:`Measurement` -> ``fit`` ->
``FitResult``. A measurement never silently drops samples: non-finite and negative values are
counted by :meth:`Measurement.validate` and reported; a fit chooses what to do with them by an
explicit option.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from .geometry import check_angles

__all__ = ["Measurement", "QUANTITIES"]

#: What a measurement's values hold.
#: ``brdf`` f_r (sr⁻¹); ``brdf_cos`` f_r cos(theta_r) (ALTA INV_STERADIAN_COSINE_FACTOR);
#: ``bridf`` TR75's BRIDF (identical to brdf_cos, kept as its own name); ``relative`` any
#: quantity proportional to f_r with an unknown scale (TR75's relative BRIDF is relative x cos).
QUANTITIES = ("brdf", "brdf_cos", "bridf", "relative")


@dataclass
class Measurement:
    """A set of BRDF samples.

    Attributes
    ----------
    theta_i, theta_r, phi : numpy.ndarray, shape (N,)
        Geometry in the common frame (radians; phi = 0 forward/specular side).
    values : numpy.ndarray, shape (N, C)
        One column per channel.
    channels : list of str
        Channel labels (e.g. ``"465nm"``); ``len(channels) == C``.
    quantity : str
        One of :data:`QUANTITIES`.
    polarization : numpy.ndarray, shape (N,), optional
        Per-sample incident polarization angle gamma (radians; NaN = unpolarized).
    uncertainty : numpy.ndarray, shape (N, C), optional
        One-sigma uncertainty of ``values`` (same unit).
    original : dict of str -> numpy.ndarray
        The file's own angle columns, untouched (e.g. ``{"theta_l": ..., "x1": ...}``).
    meta : dict
        Provenance: ``file``, ``format``, ``sample``, ``instrument``, ``date`` and anything else.
    """

    theta_i: np.ndarray
    theta_r: np.ndarray
    phi: np.ndarray
    values: np.ndarray
    channels: list[str] = field(default_factory=lambda: ["value"])
    quantity: str = "brdf"
    polarization: np.ndarray | None = None
    uncertainty: np.ndarray | None = None
    original: dict[str, np.ndarray] = field(default_factory=dict)
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.theta_i = np.asarray(self.theta_i, dtype=float).reshape(-1)
        self.theta_r = np.asarray(self.theta_r, dtype=float).reshape(-1)
        self.phi = np.asarray(self.phi, dtype=float).reshape(-1)
        v = np.asarray(self.values, dtype=float)
        if v.ndim == 1:
            v = v[:, None]
        self.values = v
        n = self.theta_i.size
        where = f" in {self.meta['file']}" if self.meta.get("file") else ""
        for name in ("theta_r", "phi"):
            if getattr(self, name).size != n:
                raise ValueError(f"{name} has {getattr(self, name).size} samples, theta_i has "
                                 f"{n}{where}")
        if v.ndim != 2 or v.shape[0] != n:
            raise ValueError(f"values must have shape (N, channels) with N = {n}, got "
                             f"{v.shape}{where}")
        self.channels = [str(c) for c in self.channels]
        if len(self.channels) != v.shape[1]:
            raise ValueError(f"{len(self.channels)} channel labels for {v.shape[1]} value "
                             f"columns{where}")
        if self.quantity not in QUANTITIES:
            raise ValueError(f"quantity must be one of {QUANTITIES}, got {self.quantity!r}{where}")
        check_angles(self.theta_i, self.theta_r, self.phi)
        if self.polarization is not None:
            self.polarization = np.broadcast_to(
                np.asarray(self.polarization, dtype=float), (n,)).copy()
        if self.uncertainty is not None:
            u = np.asarray(self.uncertainty, dtype=float)
            self.uncertainty = np.broadcast_to(u if u.ndim == 2 else u.reshape(-1, 1),
                                               v.shape).copy()

    # ------------------------------------------------------------------------------------------
    @property
    def n_samples(self) -> int:
        return int(self.theta_i.size)

    def __len__(self) -> int:
        return self.n_samples

    def validate(self) -> dict[str, dict[str, int]]:
        """Count non-finite and negative values per channel (nothing is removed)."""
        report = {}
        for j, ch in enumerate(self.channels):
            col = self.values[:, j]
            report[ch] = {"n": int(col.size), "nonfinite": int((~np.isfinite(col)).sum()),
                          "negative": int((col < 0).sum())}
        return report

    def channel_index(self, channel: int | str) -> int:
        """Index of a channel given by label or position."""
        if isinstance(channel, str):
            if channel in self.channels:
                return self.channels.index(channel)
            raise ValueError(f"unknown channel {channel!r}; channels: {self.channels}")
        idx = int(channel)
        if not -len(self.channels) <= idx < len(self.channels):
            raise ValueError(f"channel index {idx} out of range for {len(self.channels)} channels")
        return idx % len(self.channels)

    def subset(self, mask: np.ndarray) -> Measurement:
        """A new measurement with only the samples where ``mask`` is true."""
        mask = np.asarray(mask)
        return replace(
            self,
            theta_i=self.theta_i[mask], theta_r=self.theta_r[mask], phi=self.phi[mask],
            values=self.values[mask],
            polarization=None if self.polarization is None else self.polarization[mask],
            uncertainty=None if self.uncertainty is None else self.uncertainty[mask],
            original={k: np.asarray(v)[mask] for k, v in self.original.items()},
            meta=dict(self.meta),
        )

    def select_channel(self, channel: int | str) -> Measurement:
        """A single-channel measurement."""
        j = self.channel_index(channel)
        return replace(self, values=self.values[:, j:j + 1], channels=[self.channels[j]],
                       uncertainty=None if self.uncertainty is None
                       else self.uncertainty[:, j:j + 1], meta=dict(self.meta))

    def incidences(self, decimals: int = 6) -> np.ndarray:
        """Distinct incidence angles (radians, rounded to ``decimals``)."""
        return np.unique(np.round(self.theta_i, decimals))

    def at_incidence(self, theta_i: float, atol: float = math.radians(0.05)) -> Measurement:
        """Samples whose incidence is within ``atol`` of ``theta_i`` (radians)."""
        return self.subset(np.abs(self.theta_i - theta_i) <= atol)

    def in_plane(self, atol: float = math.radians(0.5)) -> Measurement:
        """Samples in the plane of incidence (phi near 0 or pi, or theta_r = 0)."""
        c = np.cos(self.phi)
        on = (np.abs(np.abs(c) - 1.0) <= 1.0 - math.cos(atol)) | (self.theta_r <= atol)
        return self.subset(on)

    def to_brdf(self) -> np.ndarray:
        """Values converted to BRDF (sr⁻¹) where the quantity allows it (brdf_cos/bridf / cos)."""
        if self.quantity == "brdf":
            return self.values
        if self.quantity in ("brdf_cos", "bridf"):
            c = np.cos(self.theta_r)[:, None]
            with np.errstate(divide="ignore", invalid="ignore"):
                return self.values / c
        raise ValueError("a 'relative' measurement has no absolute BRDF scale")

    def summary(self) -> str:
        """One paragraph describing the measurement."""
        inc = ", ".join(f"{math.degrees(t):g}" for t in self.incidences(4))
        return (f"{self.meta.get('file', '<memory>')}: {self.n_samples} samples x "
                f"{len(self.channels)} channels {self.channels}, quantity {self.quantity}, "
                f"incidences [{inc}] deg; sample {self.meta.get('sample', '?')!r}")
