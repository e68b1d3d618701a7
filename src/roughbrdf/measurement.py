"""The Measurement type: geometry in the common frame, values per channel, provenance.

Data flows one way: file -> reader (:mod:`roughbrdf.io`) -> :class:`Measurement` -> ``fit`` ->
``FitResult``. A measurement never silently drops samples: non-finite and negative values are
counted by :meth:`Measurement.validate` and reported; a fit chooses what to do with them by an
explicit option and :meth:`Measurement.drop`, which returns what it removed.

Polarimetric data
-----------------
A measurement may hold **Mueller-matrix elements** instead of one value per wavelength: then
``mueller`` says how they are stored and every channel is an element named ``m00`` ... ``m33``
(:data:`MUELLER_ELEMENTS`; row ``i`` = output Stokes component, column ``j`` = input one;
``m00`` required, any subset of the others, one wavelength per measurement):

* ``mueller="absolute"``: every element in the unit of ``quantity`` (sr⁻¹ for ``brdf``);
* ``mueller="normalized"``: ``m00`` in the unit of ``quantity`` and the others divided by
  ``m00`` (dimensionless, in [-1, 1] for a physical matrix).

``mueller_basis`` names the polarization basis of the elements, as
:meth:`roughbrdf.models.Model.mueller` does: ``"psps"`` (default; the s/p basis of each
direction, ``docs/models.md`` and :mod:`roughbrdf.mueller`) or ``"xyxy"``.
:meth:`Measurement.mueller_array` returns the ``(N, 4, 4)`` matrices; ``m00`` is the
unpolarized BRDF. Mueller data describe every incident state at once, so such a measurement has
no ``polarization`` column.

Examples
--------
>>> import numpy as np
>>> m = Measurement([0.5], [0.5], [0.0], [[0.8, 0.1]], channels=["m00", "m01"],
...                 mueller="normalized")
>>> m.mueller, m.mueller_basis, m.mueller_array("absolute")[0, 0, :2].tolist()
('normalized', 'psps', [0.8, 0.08000000000000002])
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from .errors import ArgumentError
from .geometry import check_angles
from .quantity import Quantity

__all__ = ["Measurement", "QUANTITIES", "MUELLER_ELEMENTS", "MUELLER_KINDS", "MUELLER_BASES"]

#: What a measurement's values hold: the names of :class:`~roughbrdf.quantity.Quantity`.
#: ``brdf`` f_r (sr⁻¹); ``brdf_cos`` f_r cos(theta_r) (ALTA INV_STERADIAN_COSINE_FACTOR);
#: ``bridf`` TR75's BRIDF (identical to brdf_cos, kept as its own name); ``relative`` any
#: quantity proportional to f_r with an unknown scale (TR75's relative BRIDF is relative x cos).
QUANTITIES = tuple(q.value for q in Quantity)

#: the channel names of Mueller-matrix elements, row-major: ``m<i><j>``, ``i`` the output and
#: ``j`` the input Stokes component (``I, Q, U, V`` = 0, 1, 2, 3)
MUELLER_ELEMENTS = tuple(f"m{i}{j}" for i in range(4) for j in range(4))
#: how Mueller elements are stored (:attr:`Measurement.mueller`)
MUELLER_KINDS = ("absolute", "normalized")
#: the polarization bases of :meth:`roughbrdf.models.Model.mueller`
MUELLER_BASES = ("psps", "xyxy")

#: provenance keys that every reader fills in ``meta`` (None when the file does not say)
PROVENANCE = ("file", "format", "sample", "instrument", "date")


@dataclass(eq=False, repr=False)
class Measurement:
    """A set of BRDF samples.

    Attributes
    ----------
    theta_i, theta_r, phi : numpy.ndarray, shape (N,)
        Geometry in the common frame (radians; phi = 0 forward/specular side, pi source side).
    values : numpy.ndarray, shape (N, C)
        One column per channel.
    channels : list of str
        Channel labels (e.g. ``"465nm"``); ``len(channels) == C``.
    quantity : Quantity
        What the values hold; given as a :class:`~roughbrdf.quantity.Quantity` or any name
        :meth:`Quantity.parse <roughbrdf.quantity.Quantity.parse>` accepts (one of
        :data:`QUANTITIES`), stored as a ``Quantity`` (a ``str``: ``m.quantity == "brdf"``
        works, and it is written as its plain name), also when assigned later.
    polarization : numpy.ndarray, shape (N,), optional
        Per-sample incident polarization angle gamma (radians; NaN = unpolarized).
    uncertainty : numpy.ndarray, shape (N, C), optional
        One-sigma uncertainty of ``values`` (same unit).
    original : dict of str -> numpy.ndarray
        The file's own angle columns, untouched (e.g. ``{"theta_l": ..., "x1": ...}``), each of
        shape (N,), in the file's own units (``meta["original_units"]`` says which).
    meta : dict
        Provenance: ``file``, ``format``, ``sample``, ``instrument``, ``date`` and anything else
        the reader found. The file's header keys, as read, are under ``meta["header"]`` (a
        writer of the same format writes them all back); ``meta["file_abs"]`` is the absolute
        path of the file read, which no writer replaces
        (:func:`roughbrdf.io.write` refuses it even with ``overwrite=True``).
    mueller : {None, "absolute", "normalized"}
        None for ordinary data; else the channels are Mueller elements ``m00`` ... ``m33``,
        absolute or (all but ``m00``) divided by ``m00`` (module notes, "Polarimetric data").
    mueller_basis : {None, "psps", "xyxy"}
        Polarization basis of the Mueller elements (default ``"psps"`` when ``mueller`` is
        set; None otherwise).
    """

    theta_i: np.ndarray
    theta_r: np.ndarray
    phi: np.ndarray
    values: np.ndarray
    channels: list[str] = field(default_factory=lambda: ["value"])
    quantity: Quantity = Quantity.BRDF
    polarization: np.ndarray | None = None
    uncertainty: np.ndarray | None = None
    original: dict[str, np.ndarray] = field(default_factory=dict)
    meta: dict[str, Any] = field(default_factory=dict)
    mueller: str | None = None
    mueller_basis: str | None = None

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
        if len(set(self.channels)) != len(self.channels):
            raise ValueError(f"channel labels must be distinct, got {self.channels}{where}")
        try:
            self.quantity = Quantity.parse(self.quantity, "quantity")
        except ValueError as exc:
            raise ValueError(f"{exc}{where}") from None
        try:
            check_angles(self.theta_i, self.theta_r, self.phi)
        except ArgumentError as exc:  # keep the argument's name, value and unit (CLI wording)
            raise ArgumentError(exc.argument, f"{exc.message}{where}", value=exc.value,
                                fix=exc.fix, unit=exc.unit) from exc
        except ValueError as exc:
            raise ValueError(f"{exc}{where}") from exc
        if self.polarization is not None:
            self.polarization = np.broadcast_to(
                np.asarray(self.polarization, dtype=float), (n,)).copy()
        if self.uncertainty is not None:
            u = np.asarray(self.uncertainty, dtype=float)
            self.uncertainty = np.broadcast_to(u if u.ndim == 2 else u.reshape(-1, 1),
                                               v.shape).copy()
        orig = {}
        for k, a in (self.original or {}).items():
            a = np.asarray(a)
            if a.shape[:1] != (n,):
                raise ValueError(f"original[{k!r}] has shape {a.shape}, expected ({n}, ...)"
                                 f"{where}")
            orig[str(k)] = a
        self.original = orig
        self.meta = dict(self.meta or {})
        self._check_mueller(where)

    def _check_mueller(self, where: str) -> None:
        """The Mueller declaration: a known kind and basis, element channels with ``m00``, no
        ``polarization``; ArgumentError naming the argument otherwise."""
        if self.mueller is None:
            if self.mueller_basis is not None:
                raise ArgumentError("mueller_basis", "a polarization basis only describes "
                                    f"Mueller data: give mueller= too{where}",
                                    value=self.mueller_basis)
            return
        kind = str(self.mueller).strip().lower() if isinstance(self.mueller, str) else None
        if kind not in MUELLER_KINDS:
            raise ArgumentError("mueller", f"must be None or one of {', '.join(MUELLER_KINDS)}"
                                f"{where}", value=self.mueller)
        basis = "psps" if self.mueller_basis is None else self.mueller_basis
        basis = str(basis).strip().lower() if isinstance(basis, str) else None
        if basis not in MUELLER_BASES:
            raise ArgumentError("mueller_basis", f"must be one of {', '.join(MUELLER_BASES)}"
                                f"{where}", value=self.mueller_basis)
        other = [c for c in self.channels if c not in MUELLER_ELEMENTS]
        if other or "m00" not in self.channels:
            raise ArgumentError("channels", "Mueller data need the channel 'm00' and only "
                                "element channels m00 ... m33" + (
                                    f" (not elements: {other})" if other else "") + where,
                                value=self.channels)
        if self.polarization is not None:
            raise ArgumentError("polarization", "Mueller data hold every incident "
                                f"polarization at once: no per-sample polarization{where}")
        object.__setattr__(self, "mueller", kind)
        object.__setattr__(self, "mueller_basis", basis)

    def __setattr__(self, name: str, value: Any) -> None:
        # once constructed (meta is the last field set by __init__), an assigned quantity is
        # parsed too, so that m.quantity is always a Quantity
        if name == "quantity" and "meta" in self.__dict__:
            value = Quantity.parse(value, "quantity")
        object.__setattr__(self, name, value)

    def __repr__(self) -> str:
        return (f"<Measurement {self.n_samples} samples x {len(self.channels)} channels "
                f"{self.channels}, {self.quantity}, file={self.meta.get('file')!r}>")

    def _repr_html_(self) -> str:
        """Jupyter's rich display (:func:`roughbrdf.html_repr.measurement_html`, registered
        from above: :mod:`roughbrdf.rich_display`)."""
        from .rich_display import html

        return html("measurement", self)

    # ------------------------------------------------------------------------------------------
    # size and provenance
    # ------------------------------------------------------------------------------------------
    @property
    def n_samples(self) -> int:
        return int(self.theta_i.size)

    @property
    def n_channels(self) -> int:
        return int(self.values.shape[1])

    @property
    def is_mueller(self) -> bool:
        """Whether the channels are Mueller-matrix elements (:attr:`mueller` is set)."""
        return self.mueller is not None

    def mueller_array(self, kind: str = "normalized") -> np.ndarray:
        """The Mueller matrices of the samples, shape (N, 4, 4); NaN for elements not held.

        ``kind="normalized"`` divides by ``m00`` (``[0, 0]`` is then 1, NaN where ``m00``
        is 0); ``"absolute"`` gives every element in the unit of :attr:`quantity`. Raises
        :class:`~roughbrdf.errors.ArgumentError` for a measurement without Mueller data or an
        unknown ``kind``.
        """
        if not self.is_mueller:
            raise ArgumentError("mueller", "this measurement holds no Mueller elements")
        if kind not in MUELLER_KINDS:
            raise ArgumentError("kind", f"must be one of {', '.join(MUELLER_KINDS)}", value=kind)
        out = np.full((self.n_samples, 16), np.nan)
        for j, ch in enumerate(self.channels):
            out[:, MUELLER_ELEMENTS.index(ch)] = self.values[:, j]
        m00 = out[:, :1].copy()
        if kind == "absolute":
            if self.mueller == "normalized":  # the others times m00; m00 itself stays
                out[:, 1:] *= m00
            return out.reshape(-1, 4, 4)
        if self.mueller == "absolute":
            with np.errstate(divide="ignore", invalid="ignore"):
                out /= m00
        out[:, 0] = 1.0
        # m00 = 0 (or not finite) has no normalized matrix: NaN there, not inf or 1
        out[~(np.isfinite(m00[:, 0]) & (m00[:, 0] != 0))] = np.nan
        return out.reshape(-1, 4, 4)

    def __len__(self) -> int:
        return self.n_samples

    @property
    def file(self) -> str | None:
        """Path of the file read (``meta["file"]``)."""
        return self.meta.get("file")

    @property
    def sample(self) -> str | None:
        """Sample name declared in the file (``meta["sample"]``)."""
        return self.meta.get("sample")

    @property
    def instrument(self) -> str | None:
        """Instrument / laboratory (``meta["instrument"]``)."""
        return self.meta.get("instrument")

    @property
    def date(self) -> str | None:
        """Measurement date as written in the file (``meta["date"]``)."""
        return self.meta.get("date")

    # ------------------------------------------------------------------------------------------
    # validation
    # ------------------------------------------------------------------------------------------
    def validate(self) -> dict[str, dict[str, int]]:
        """Count non-finite and negative values per channel (nothing is removed).

        Returns ``{channel: {"n": N, "nonfinite": count, "negative": count}}``. For Mueller data
        (:attr:`mueller`) negative values of the elements other than ``m00`` are normal; those
        elements also get ``"beyond_m00"``: the count of ``|m_ij| > m00`` (``|m_ij| > 1`` when
        normalized), which no physical Mueller matrix has (noise can give it).
        """
        report = {}
        m00 = (np.ones(self.n_samples) if self.mueller == "normalized"
               else self.values[:, self.channel_index("m00")]) if self.is_mueller else None
        for j, ch in enumerate(self.channels):
            col = self.values[:, j]
            report[ch] = {"n": int(col.size), "nonfinite": int((~np.isfinite(col)).sum()),
                          "negative": int((col < 0).sum())}
            if m00 is not None and ch != "m00":
                report[ch]["beyond_m00"] = int((np.abs(col) > m00).sum())
        return report

    def _problems(self, ch: str, r: dict[str, int]) -> list[str]:
        """The counts of :meth:`validate` for one channel that point at a problem, in words."""
        out = [f"{r['nonfinite']} non-finite"] if r["nonfinite"] else []
        if r["negative"] and (not self.is_mueller or ch == "m00"):
            out.append(f"{r['negative']} negative")
        if r.get("beyond_m00"):
            out.append(f"{r['beyond_m00']} with |{ch}| > m00")
        return out

    def validation_text(self) -> str:
        """One line per channel with the counts of :meth:`validate` (for reports and the CLI)."""
        lines = []
        for ch, r in self.validate().items():
            line = (f"channel {ch}: {r['n']} values, {r['nonfinite']} non-finite, "
                    f"{r['negative']} negative")
            if "beyond_m00" in r:
                line += f", {r['beyond_m00']} with |{ch}| > m00"
            lines.append(line)
        return "\n".join(lines)

    def bad_mask(self, *, nonfinite: bool = True, negative: bool = False,
                 channels: Sequence[int | str] | None = None) -> np.ndarray:
        """Boolean (N,) mask of the samples :meth:`drop` would remove with the same options."""
        idx = (range(self.n_channels) if channels is None
               else [self.channel_index(c) for c in channels])
        v = self.values[:, list(idx)]
        bad = np.zeros(self.n_samples, dtype=bool)
        if nonfinite:
            bad |= (~np.isfinite(v)).any(axis=1)
        if negative:
            bad |= (v < 0).any(axis=1)
        return bad

    def drop(self, *, nonfinite: bool = True, negative: bool = False,
             channels: list[int | str] | None = None) -> tuple[Measurement, dict[str, Any]]:
        """Remove the samples with non-finite and/or negative values, and say what was removed.

        A sample (row) is removed when any of the considered ``channels`` (default: all) has a
        non-finite value (``nonfinite=True``) or a negative value (``negative=True``). For a
        per-channel fit, call :meth:`select_channel` first so that a bad value in one channel does
        not remove the others' good values.

        Returns
        -------
        (Measurement, dict)
            The kept samples, and ``{"n_before", "n_after", "n_dropped", "mask" (bool (N,) of the
            removed rows), "nonfinite": {channel: count}, "negative": {channel: count}}`` where the
            per-channel counts are those of the removed rows. The same record (without the mask)
            is appended to ``meta["dropped"]`` of the returned measurement.
        """
        idx = (list(range(self.n_channels)) if channels is None
               else [self.channel_index(c) for c in channels])
        bad = self.bad_mask(nonfinite=nonfinite, negative=negative, channels=idx)
        v = self.values
        info: dict[str, Any] = {
            "n_before": self.n_samples,
            "n_after": int((~bad).sum()),
            "n_dropped": int(bad.sum()),
            "options": {"nonfinite": nonfinite, "negative": negative,
                        "channels": [self.channels[j] for j in idx]},
            "nonfinite": {self.channels[j]: int((~np.isfinite(v[bad, j])).sum()) for j in idx},
            "negative": {self.channels[j]: int((v[bad, j] < 0).sum()) for j in idx},
        }
        kept = self.subset(~bad)
        kept.meta["dropped"] = list(self.meta.get("dropped", [])) + [dict(info)]
        info["mask"] = bad
        return kept, info

    # ------------------------------------------------------------------------------------------
    # selection
    # ------------------------------------------------------------------------------------------
    def channel_index(self, channel: int | str) -> int:
        """Index of a channel given by label or position (``"525"`` also finds ``"525nm"``)."""
        if isinstance(channel, str):
            if channel in self.channels:
                return self.channels.index(channel)
            alt = [i for i, c in enumerate(self.channels) if c.removesuffix("nm") == channel]
            if len(alt) == 1:
                return alt[0]
            if channel.lstrip("-").isdigit() and not alt:
                return self.channel_index(int(channel))
            raise ValueError(f"unknown channel {channel!r}; channels: {self.channels}")
        idx = int(channel)
        if not -len(self.channels) <= idx < len(self.channels):
            raise ValueError(f"channel index {idx} out of range for {len(self.channels)} channels")
        return idx % len(self.channels)

    def subset(self, mask: np.ndarray) -> Measurement:
        """A new measurement with only the samples where ``mask`` is true (or at indices)."""
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

    def _check_mueller_selection(self, idx: list[int]) -> None:
        """A selection of a Mueller measurement's channels must keep ``m00`` (the others are
        relative to it or meaningless without it)."""
        if self.is_mueller and "m00" not in [self.channels[j] for j in idx]:
            raise ArgumentError("channel", "a selection of Mueller elements must include "
                                "'m00' (use mueller_array() for single elements)",
                                value=[self.channels[j] for j in idx])

    def select_channel(self, channel: int | str) -> Measurement:
        """A single-channel measurement (of Mueller data: only ``m00``)."""
        j = self.channel_index(channel)
        self._check_mueller_selection([j])
        return replace(self, values=self.values[:, j:j + 1], channels=[self.channels[j]],
                       uncertainty=None if self.uncertainty is None
                       else self.uncertainty[:, j:j + 1], meta=dict(self.meta))

    def select_channels(self, channels: list[int | str]) -> Measurement:
        """A measurement with the given channels, in the given order."""
        idx = [self.channel_index(c) for c in channels]
        self._check_mueller_selection(idx)
        return replace(self, values=self.values[:, idx], channels=[self.channels[j] for j in idx],
                       uncertainty=None if self.uncertainty is None
                       else self.uncertainty[:, idx], meta=dict(self.meta))

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

    def with_polarization(self, gamma: float | None) -> Measurement:
        """Samples with incident polarization angle ``gamma`` (radians; None = unpolarized)."""
        if self.polarization is None:
            if gamma is None:
                return self.subset(np.ones(self.n_samples, dtype=bool))
            return self.subset(np.zeros(self.n_samples, dtype=bool))
        if gamma is None:
            return self.subset(np.isnan(self.polarization))
        return self.subset(np.abs(self.polarization - gamma) <= 1e-9)

    # ------------------------------------------------------------------------------------------
    # quantities
    # ------------------------------------------------------------------------------------------
    def to_brdf(self) -> np.ndarray:
        """Values converted to BRDF (sr⁻¹) where the quantity allows it (cosine-weighted
        quantities, ``brdf_cos``/``bridf``, are divided by cos(theta_r)).

        Raises ``ValueError`` for a ``relative`` measurement (no absolute scale).
        """
        if not self.quantity.absolute:
            raise ValueError("a 'relative' measurement has no absolute BRDF scale")
        if not self.quantity.cosine_weighted:
            return self.values
        c = np.cos(self.theta_r)[:, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            return self.values / c ** self._scaled_columns()

    def _scaled_columns(self) -> np.ndarray:
        """(C,) 1 for the columns that carry the quantity's unit, 0 for the others (the
        normalized Mueller elements, which are ratios)."""
        if self.mueller != "normalized":
            return np.ones(self.n_channels)
        return np.array([1.0 if c == "m00" else 0.0 for c in self.channels])

    def as_quantity(self, quantity: Quantity | str) -> Measurement:
        """The same samples holding ``quantity`` (``brdf`` <-> ``brdf_cos``/``bridf``).

        Uncertainties are scaled with the values. ``relative`` converts to nothing else; anything
        converts to ``relative`` only by relabelling (the values are kept). ``ValueError`` for a
        name that is not a quantity.
        """
        target = Quantity.parse(quantity, "quantity")
        if target == self.quantity:
            return replace(self, meta=dict(self.meta))
        if not target.absolute:
            return replace(self, quantity=target, meta=dict(self.meta))
        if not self.quantity.absolute:
            raise ValueError("a 'relative' measurement has no absolute scale; cannot convert it "
                             f"to {target.value!r}")
        if self.quantity.cosine_weighted == target.cosine_weighted:
            factor = np.ones((self.n_samples, 1))
        else:
            c = np.cos(self.theta_r)[:, None]
            with np.errstate(divide="ignore", invalid="ignore"):
                factor = c if target.cosine_weighted else 1.0 / c
        factor = factor ** self._scaled_columns()  # normalized Mueller elements: ratios, kept
        return replace(self, values=self.values * factor, quantity=target,
                       uncertainty=None if self.uncertainty is None
                       else self.uncertainty * np.abs(factor), meta=dict(self.meta))

    # ------------------------------------------------------------------------------------------
    def summary(self) -> str:
        """One paragraph describing the measurement, with its validation counts."""
        inc = ", ".join(f"{math.degrees(t):g}" for t in self.incidences(4))
        text = (f"{self.meta.get('file', '<memory>')}: {self.n_samples} samples x "
                f"{len(self.channels)} channels {self.channels}, quantity {self.quantity}, "
                f"incidences [{inc}] deg; sample {self.meta.get('sample', '?')!r}")
        if self.is_mueller:
            text += f"; Mueller elements ({self.mueller}, basis {self.mueller_basis})"
        bad = {ch: p for ch, r in self.validate().items() if (p := self._problems(ch, r))}
        if bad:
            text += "; " + ", ".join(f"{ch}: {', '.join(p)}" for ch, p in bad.items())
        return text
