"""Zemax OpticStudio ABg catalog rows: the fitted ABg values as OpticStudio's dialog asks for them.

``docs/straylight.md`` ("Hand-off"). OpticStudio keeps ABg data in a catalog file
(``ABG_DATA.DAT`` in the ``ABg_Data`` folder) edited through its "ABg Scatter Data Catalogs"
dialog: per name, a wavelength in µm ("Wave"; 0: no scaling with wavelength) and up to 10
rows of ``Use``, ``Angle`` (incidence in degrees, "linearly interpolated in cosine space",
the first row below it and the last above), ``A``, ``B``, ``g``, with a TIS button whose value
"must be less than 1.0" (OpticStudio help, "ABg Scatter Data Catalogs"). The file's own text
layout is not publicly documented, so this module does not write one: it writes a clearly
labelled text table of exactly those fields — one row per kept incidence of a
:func:`~roughbrdf.fitting.kinds.per_incidence.fit_per_incidence`, or a single row (``Angle 0``,
serving every incidence) for a fit of one parameter set — plus each row's TIS
(:func:`roughbrdf.albedo`), to type into the dialog.

A model whose TIS exceeds ``1 + 1e-3`` at any incidence of the export grid is refused unless
``allow_energy_gain=True``, which the table records (as every export does).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import ArgumentError

if TYPE_CHECKING:
    from ..models import Model

__all__ = ["AbgRow", "abg_rows", "catalog_text", "write_abg_catalog"]

#: OpticStudio's rows per ABg name
MAX_ROWS = 10


@dataclass(frozen=True)
class AbgRow:
    """One row of the dialog: incidence (degrees), ``A`` (sr⁻¹), ``B``, ``g`` and the TIS of
    that row's model at that incidence."""

    angle_deg: float
    A: float  # noqa: N815 - Zemax's symbol
    B: float  # noqa: N815
    g: float
    tis: float


def _abg_of(model: Model) -> tuple[float, float, float]:
    if getattr(model, "name", None) != "abg":
        raise ArgumentError("source", "the Zemax ABg catalog holds ABg models only (fit with "
                            "--model abg); other models go to Zemax as a tabular BSDF "
                            "(--to zemax)", value=getattr(model, "name", model))
    p = model.params
    return float(p["A"]), float(p["B"]), float(p["g"])


def abg_rows(source: Any, channel: str | int | None = None) -> tuple[list[AbgRow], str | None]:
    """The rows of ``source`` (an ABg model, a fit of one, or a per-incidence fit) and the
    channel they are of (None for a model).

    Examples
    --------
    >>> import roughbrdf as rb, roughbrdf.models.straylight
    >>> rows, _ = abg_rows(rb.model("abg", A=0.01, B=0.001, g=2.0))
    >>> rows[0].angle_deg, rows[0].A, round(rows[0].tis, 3)
    (0.0, 0.01, 0.217)
    """
    from ..fitting.kinds.per_incidence import PerIncidenceFit
    from ..fitting.results.result import FitResult
    from ..integrate import albedo

    ch: str | None
    if isinstance(source, dict) and source.get("per_incidence"):  # its saved fit.json
        return _saved_rows(source, channel)
    if isinstance(source, PerIncidenceFit):
        ch = str(channel) if channel is not None else source.channels[0]
        if ch not in source.channels:
            raise ArgumentError("channel", "not a channel of the fit "
                                f"({', '.join(source.channels)})", value=channel)
        rows = []
        for k in source.chosen:
            r = source.rows[k]
            a, b, g = _abg_of(r.result[ch].model)
            rows.append(AbgRow(math.degrees(r.theta_i), a, b, g, r.tis[ch]))
        return rows, ch
    if isinstance(source, FitResult):
        labels = [c.channel for c in source.channels]
        ch = str(channel) if channel is not None else labels[0]
        if ch not in labels:
            raise ArgumentError("channel", f"not a channel of the fit ({', '.join(labels)})",
                                value=channel)
        model = source[ch].model
    else:
        model, ch = source, None
    a, b, g = _abg_of(model)
    return [AbgRow(0.0, a, b, g, float(albedo(model, 0.0)))], ch


def _saved_rows(doc: dict[str, Any], channel: str | int | None
                ) -> tuple[list[AbgRow], str | None]:
    """The kept rows of a per-incidence ``fit.json`` (:meth:`PerIncidenceFit.to_dict`)."""
    if doc.get("model") != "abg":
        raise ArgumentError("source", "the Zemax ABg catalog holds ABg fits only",
                            value=doc.get("model"))
    kept = [r for r in doc["rows"] if r["kept"]]
    labels = list(kept[0]["channels"])
    ch = str(channel) if channel is not None else labels[0]
    if ch not in labels:
        raise ArgumentError("channel", f"not a channel of the fit ({', '.join(labels)})",
                            value=channel)
    rows = [AbgRow(float(r["theta_i_deg"]), float(r["channels"][ch]["params"]["A"]),
                   float(r["channels"][ch]["params"]["B"]),
                   float(r["channels"][ch]["params"]["g"]), float(r["channels"][ch]["tis"]))
            for r in kept]
    return rows, ch


def catalog_text(rows: list[AbgRow], name: str, wavelength_um: float | None,
                 notes: list[str] | tuple[str, ...] = ()) -> str:
    """The labelled table (module notes)."""
    if not rows or len(rows) > MAX_ROWS:
        raise ArgumentError("rows", f"an ABg name holds 1 to {MAX_ROWS} rows", value=len(rows))
    wave = 0.0 if wavelength_um is None else wavelength_um
    lines = [
        "# roughbrdf: Zemax OpticStudio ABg catalog entry, the values to enter by hand",
        "# (OpticStudio: Libraries > ABg Scatter Data Catalogs; the ABG_DATA.DAT file layout is",
        "# not publicly documented, so roughbrdf writes no such file). Insert the name, set",
        "# Wave, then one row per line below with Use checked.",
        "# BSDF = A / (B + |beta - beta0|^g) sr^-1 (beta: direction cosines on the surface).",
        "# Angle: incidence (deg); OpticStudio interpolates rows linearly in cos(angle) and holds",
        "# the first row below it, the last above. TIS (roughbrdf.albedo of the row's model at",
        "# its angle) must be below 1 (OpticStudio's TIS button computes the same quantity).",
        ("# Wave 0: no wavelength scaling." if wavelength_um is None else
         "# Wave: the measurement's wavelength; OpticStudio scales A and B from it at other"
         "\n# wavelengths by its own rule (enter 0 to disable)."),
        *[f"# {n}" for n in notes],
        f"Name      {name}",
        f"Wave (um) {wave:.6g}",
        f"{'Use':<4s} {'Angle':>8s} {'A':>14s} {'B':>14s} {'g':>10s} {'TIS':>10s}",
    ]
    for r in rows:
        lines.append(f"{'yes':<4s} {r.angle_deg:8.3f} {r.A:14.7e} {r.B:14.7e} {r.g:10.6f} "
                     f"{r.tis:10.6f}")
    return "\n".join(lines) + "\n"


def write_abg_catalog(source: Any, out: str | os.PathLike, *, name: str | None = None,
                      channel: str | int | None = None, wavelength_um: float | None = None,
                      overwrite: bool = False, allow_energy_gain: bool = False) -> Path:
    """Write the ABg catalog table of ``source`` (:func:`abg_rows`) to ``out`` (``.txt``
    added without a suffix), atomically, refusing an existing file unless ``overwrite``.

    ``name``: the catalog name (default the file's stem, at most 31 characters of letters,
    digits, ``_`` and ``-``); ``wavelength_um``: "Wave" (default: the channel's wavelength
    when its label is one, e.g. ``"630nm"``, else 0).
    """
    from ..fitting.results.plausibility import refuse_energy_gain
    from ..models.kcorr import parse_wavelength
    from ..output import atomic_write, refuse_existing

    path = Path(out) if Path(out).suffix else Path(out).with_suffix(".txt")
    refuse_existing(path, overwrite)
    rows, ch = abg_rows(source, channel)
    label = name if name is not None else path.stem
    if not label or len(label) > 31 or not all(c.isalnum() or c in "_-" for c in label):
        raise ArgumentError("name", "an ABg catalog name of 1-31 letters, digits, _ or -",
                            value=label)
    if wavelength_um is None and ch is not None:
        try:
            wavelength_um = parse_wavelength(ch)
        except ArgumentError:  # a label that is no wavelength ("value"): Wave 0
            wavelength_um = None
    import roughbrdf as rb

    models = {f"{ch or ''} {r.angle_deg:g} deg": rb.model("abg", A=r.A, B=r.B, g=r.g)
              for r in rows}
    notes = refuse_energy_gain(models, allow_energy_gain)
    atomic_write(path, catalog_text(rows, label, wavelength_um, notes), overwrite=overwrite)
    return path
