"""ASTM E1392-style text files (``.astm``), as written by Light Tec's Mini-Diff and others.

Layout::

    LAB_NAME Light Tec            <- "KEY value" header lines (blank lines allowed)
    SAMPLE_NAME C1_Black
    MEAS_NAME BRDF
    MEAS_DATE 2023/12/05
    NUM_POINTS 12964
    VARS theta_i,phi_i,theta_s,phi_s,465nm,525nm,630nm
    0,3.14159265358979,0,0,11.41,11.46,11.13      <- NUM_POINTS rows, comma or blank separated

Angles are the source (``theta_i, phi_i``) and the scattered direction (``theta_s, phi_s``) in
one frame with the normal at +z; the remaining columns are the channels (BRDF, sr⁻¹).

Conventions verified on the Mini-Diff files (``../shared/data/minidiff``):

* the source sits at ``phi_i = 180°`` and the mirror direction is ``theta_s = theta_i,
  phi_s = 0`` (C2_Black at 60° incidence peaks at phi_s = 0, theta_s = 66°), so in the library's
  frame ``phi = phi_s - phi_i + pi`` (= ``phi_s`` for these files, wrapped into (-pi, pi]),
  computed by :func:`roughbrdf.geometry.angles_from_vectors`;
* angles are radians unless the header declares a unit (a key containing ``UNIT`` or ``ANGLE``
  whose value is ``deg``/``rad``, or a unit in the VARS names such as ``theta_i(deg)``); the
  ``angles=`` option overrides;
* ``VARS`` lists 6 names but rows have 7 values: the missing name is ``phi_s``, inserted after
  ``theta_s`` (recorded in ``meta["quirks"]``);
* ``SAMPLE_NAME`` may disagree with the file name (C2_Black.astm says C1_Black): both are kept,
  ``meta["sample"]`` and ``meta["file"]``, plus ``meta["file_name_declared"]`` (``FILE_NAME``);
* small negative values (noise) are kept and counted (``Measurement.validate``);
* the pole ``theta_s = 0`` is stored once per incidence (``meta["pole_rows"]``).

``MEAS_NAME`` gives the quantity: BRDF/BSDF -> ``brdf``; CCBRDF (cosine-corrected) ->
``brdf_cos``; others need ``quantity=``. A ``quantity=`` or ``angles=`` option must agree with
what the file declares (it supplies what the file does not say); a key given twice, or two
declarations of the angle unit or the polarization that disagree, are errors naming both lines.

Every header key is kept, as read, in ``meta["header"]``; :func:`write` writes them back when
the measurement came from an ASTM file (only ``NUM_POINTS``, ``VARS``, ``MEAS_NAME``, the unit
and polarization declarations are rewritten to describe the rows written).
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..fresnel import polarization_angle
from ..measurement import QUANTITIES, Measurement
from ..quantity import Quantity
from ._common import (
    LAYOUT,
    AngleUnit,
    FormatError,
    QuantityClaim,
    UnitClaim,
    add_key,
    azimuth_rows,
    check_zenith_rows,
    common_frame_from_spherical,
    describe_keys,
    header_not_written,
    prepare_target,
    resolve_angle_unit,
    resolve_quantity,
    unit_word,
    warn_implausible_angles,
    warn_not_written,
    write_table,
)
from ._rows import (
    begin_read,
    check_row_count,
    count_fields,
    parse_number,
    parse_rows,
    row_separator,
    rows_from,
    whole_number,
)

__all__ = ["read", "write", "EXTENSIONS", "header_field"]

EXTENSIONS = (".astm",)

_ANGLE_NAMES = {
    "theta_i": "theta_i", "thetai": "theta_i", "theta_in": "theta_i",
    "phi_i": "phi_i", "phii": "phi_i", "phi_in": "phi_i",
    "theta_s": "theta_s", "thetas": "theta_s", "theta_r": "theta_s", "theta_scat": "theta_s",
    "theta_o": "theta_s",
    "phi_s": "phi_s", "phis": "phi_s", "phi_r": "phi_s", "phi_scat": "phi_s", "phi_o": "phi_s",
}
_ANGLES = ("theta_i", "phi_i", "theta_s", "phi_s")
_UNIT_IN_NAME = re.compile(r"^(?P<name>[^\[\(]+?)\s*[\[\(](?P<unit>[^\]\)]*)[\]\)]\s*$")
_WAVELENGTH = re.compile(r"^\s*(\d+(?:\.\d+)?)\s*nm\s*$", re.IGNORECASE)
#: MEAS_NAME (upper case, blanks and dashes as ``_``) -> quantity
_QUANTITY = {"BRDF": Quantity.BRDF, "BSDF": Quantity.BRDF, "CCBRDF": Quantity.BRDF_COS,
             "CC_BRDF": Quantity.BRDF_COS, "COSINE_CORRECTED_BRDF": Quantity.BRDF_COS}
_NO_MEAS_NAME = "no MEAS_NAME"
_POLARIZATION_KEYS = ("POLARIZATION", "SOURCE_POLARIZATION", "INCIDENT_POLARIZATION")
#: header key -> the provenance field of ``meta`` it feeds (what other formats can write)
_FIELDS = {"SAMPLE_NAME": "sample", "LAB_NAME": "instrument", "SYSTEM_NAME": "instrument",
           "MEAS_DATE": "date", "MEAS_TIME": "date", "FILE_NAME": "file_name_declared"}
#: the provenance fields :func:`write` writes for a measurement read from another format
WRITES = ("sample", "instrument", "date")
#: beyond this an azimuth in radians is taken for degrees
_TWO_PI_SLACK = 2 * math.pi + 1e-6


@dataclass
class _Header:
    """The ``KEY value`` lines before the first data row."""

    keys: dict[str, str]
    lines: dict[str, int]
    #: index (0-based) of the first data row in the file's lines, None without data
    data_start: int | None
    quirks: list[str] = field(default_factory=list)

    def line(self, key: str) -> int | None:
        """1-based line of ``key`` (None when absent)."""
        return self.lines.get(key)


@dataclass
class _Columns:
    """Column names (VARS, with units stripped and the Mini-Diff ``phi_s`` restored) and roles."""

    names: list[str]
    #: canonical angle name of each column (``theta_i``...), None for a channel
    canon: list[str | None]

    @property
    def channel_idx(self) -> list[int]:
        """Indices of the value columns."""
        return [j for j, c in enumerate(self.canon) if c is None]

    @property
    def angle_idx(self) -> dict[str, int]:
        """Index of each angle column present (``theta_i, phi_i, theta_s, phi_s``)."""
        return {c: self.canon.index(c) for c in _ANGLES if c in self.canon}


def _split_vars(text: str) -> list[str]:
    """VARS names: comma (or semicolon) separated, else blank separated."""
    sep = "," if "," in text else (";" if ";" in text else None)
    parts = text.split(sep) if sep else text.split()
    return [p.strip() for p in parts if p.strip()]


def _unit_word(word: str) -> str | None:
    """``deg``/``rad`` for an ASTM unit word (``deg``, ``degrees``, ``rad``...), else None."""
    w = word.strip().lower()
    return "deg" if w.startswith("deg") else "rad" if w.startswith("rad") else None


# --------------------------------------------------------------------------------------------
# phases of read()
# --------------------------------------------------------------------------------------------
def _read_header(lines: list[str], path: Path) -> _Header:
    """Header phase: the ``KEY value`` lines up to the first numeric line (``#``/``;`` lines are
    comments); keys are upper-cased and ``:``/``=`` after a key is dropped. A ``VARS`` line is
    required."""
    keys: dict[str, str] = {}
    key_lines: dict[str, int] = {}
    data_start = None
    for i, raw in enumerate(lines):
        s = raw.strip()
        if not s or s.startswith("#") or s.startswith(";"):
            continue
        first = re.split(r"[,\s]+", s, maxsplit=1)[0]
        try:
            float(first)
        except ValueError:
            key, *rest = s.split(None, 1)
            add_key(keys, key_lines, key.rstrip(":=").upper(), rest[0].strip() if rest else "",
                    i + 1, path)
            continue
        data_start = i
        break
    if "VARS" not in keys:
        raise FormatError("no VARS line (the list of column names) before the data; this does "
                          "not look like an ASTM E1392 file", path,
                          None if data_start is None else data_start + 1)
    return _Header(keys, key_lines, data_start)


def _is_unit_key(key: str) -> bool:
    """Whether a header key can declare the angle unit (``ANGLE_UNITS``, ``UNITS``...)."""
    return ("UNIT" in key and ("ANG" in key or key in ("UNITS", "UNIT"))) or \
        key in ("ANGLES", "ANGLE")


def _header_unit_claims(header: _Header) -> list[UnitClaim]:
    """The header's angle-unit declarations: every key containing ``UNIT`` (with ``ANG``, or
    ``UNIT(S)`` alone) or ``ANGLE(S)`` whose value starts with ``deg``/``rad``."""
    claims = []
    for key, val in header.keys.items():
        if _is_unit_key(key):
            word = _unit_word(val.split()[0]) if val.strip() else None
            if word is not None:
                claims.append(UnitClaim((word,), f"header {key}", f"{key} {val}",
                                        header.line(key)))
    return claims


def header_field(key: str) -> str | None:
    """What an ASTM header key holds, for a writer of another format: :data:`LAYOUT` (column
    names, count, quantity, unit and polarization declarations: every writer writes its own),
    the provenance field of ``meta`` it feeds (``"sample"``...), or None."""
    if key in ("NUM_POINTS", "VARS", "MEAS_NAME", *_POLARIZATION_KEYS) or _is_unit_key(key):
        return LAYOUT
    return _FIELDS.get(key)


def _read_units(header: _Header, angles: str | None, path: Path
                ) -> tuple[list[str], AngleUnit]:
    """Units phase: the VARS names without their unit suffixes (``theta_i(deg)`` ->
    ``theta_i``) and the angle unit - the ``angles=`` option, else the header's declaration,
    else the units in the angle names of VARS (all alike), else radians."""
    names: list[str] = []
    name_units: list[str] = []
    if not _split_vars(header.keys["VARS"]):
        raise FormatError("VARS lists no column names", path, header.line("VARS"))
    for nm in _split_vars(header.keys["VARS"]):
        m = _UNIT_IN_NAME.match(nm)
        unit = m.group("unit").strip().lower().rstrip("s") if m else ""
        if m is None or unit not in ("deg", "degree", "rad", "radian"):
            names.append(nm)
            continue
        names.append(str(m.group("name")).strip())
        word = _unit_word(unit)
        if names[-1].lower() in _ANGLE_NAMES and word is not None:  # always a unit word here
            name_units.append(word)
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise FormatError(f"VARS names the column(s) {dup} twice: {header.keys['VARS']!r}",
                          path, header.line("VARS"))
    claims = _header_unit_claims(header)
    if name_units:
        claims.append(UnitClaim(tuple(name_units), "VARS names", "the units in VARS",
                                header.line("VARS")))
    unit = resolve_angle_unit(angles, claims, path, default="rad",
                              default_source="default (radians)")
    return names, unit


def _read_columns(names: list[str], first_row: str, header: _Header) -> _Columns:
    """Columns phase: canonical angle names; when the rows have one value more than VARS has
    names and VARS has ``theta_s`` but no ``phi_s`` (the Mini-Diff files), ``phi_s`` is inserted
    after ``theta_s`` (recorded as a quirk)."""
    names = list(names)
    canon = [_ANGLE_NAMES.get(n.lower()) for n in names]
    if count_fields(first_row, row_separator(first_row)) == len(names) + 1 and \
            "phi_s" not in canon and "theta_s" in canon:
        k = canon.index("theta_s") + 1
        names.insert(k, "phi_s")
        canon.insert(k, "phi_s")
        header.quirks.append("VARS lists one name fewer than the rows have values; inserted the "
                             "missing 'phi_s' after 'theta_s'")
    return _Columns(names, canon)


def _check_roles(cols: _Columns, header: _Header, path: Path) -> None:
    """Columns phase, after the rows: theta_i, theta_s and a channel are required."""
    for needed in ("theta_i", "theta_s"):
        if needed not in cols.canon:
            raise FormatError(f"VARS has no {needed} column: {cols.names}", path,
                              header.line("VARS"))
    if not cols.channel_idx:
        raise FormatError(f"VARS has no value column besides the angles: {cols.names}", path,
                          header.line("VARS"))


def _parse_rows(texts: list[str], linenos: list[int], cols: _Columns, declared_n: int | None,
                n_lines: int, path: Path) -> np.ndarray:
    """Rows phase: the numbers (comma or blank separated, one value per column) and their count
    against ``NUM_POINTS``."""
    data = parse_rows(texts, linenos, len(cols.names), path, sep=row_separator(texts[0]),
                      what=f"values (VARS: {', '.join(cols.names)})")
    check_row_count(data.shape[0], declared_n, "NUM_POINTS", linenos, n_lines, path)
    return data


def _read_angles(data: np.ndarray, cols: _Columns, unit: AngleUnit, ln: np.ndarray,
                 header: _Header, path: Path) -> dict[str, np.ndarray]:
    """Rows phase: the angle columns in radians (``theta_i, phi_i, theta_s, phi_s``), checked
    row by row; a missing ``phi_i`` puts the source at 180 deg (a quirk)."""
    col = {c: data[:, j] for c, j in cols.angle_idx.items()}
    out = {"theta_i": check_zenith_rows(col["theta_i"] * unit.factor, "theta_i", ln, path,
                                        unit=unit.word),
           "theta_s": check_zenith_rows(col["theta_s"] * unit.factor, "theta_s", ln, path,
                                        unit=unit.word)}
    if "phi_i" in col:
        out["phi_i"] = azimuth_rows(col["phi_i"], "phi_i", ln, path) * unit.factor
    else:
        out["phi_i"] = np.full_like(out["theta_i"], math.pi)
        header.quirks.append("no phi_i column: source assumed at phi_i = 180 deg")
    if "phi_s" not in col:
        raise FormatError(f"VARS has no phi_s column and the rows have no extra value: "
                          f"{cols.names}", path, header.line("VARS"))
    out["phi_s"] = azimuth_rows(col["phi_s"], "phi_s", ln, path) * unit.factor
    warn_implausible_angles(unit, path, [col["theta_i"], col["theta_s"]], list(col.values()),
                            names="theta_i and theta_s")
    beyond = (np.abs(out["phi_i"]) > _TWO_PI_SLACK) | (np.abs(out["phi_s"]) > _TWO_PI_SLACK)
    if unit.word == "rad" and beyond.any():
        raise FormatError("azimuth beyond 2 pi rad: the angles look like degrees; declare the "
                          "unit (ANGLE_UNITS deg in the header, or angles='deg'; CLI: "
                          "--angles-in deg)", path,
                          int(ln[int(np.flatnonzero(beyond)[0])]))
    return out


def _read_quantity(header: _Header, quantity: str | None, path: Path) -> Quantity:
    """Quantity phase: the ``quantity=`` option, else ``MEAS_NAME`` (BRDF/BSDF -> brdf,
    CCBRDF -> brdf_cos; anything else is an error asking for ``quantity=``), else brdf (a
    quirk)."""
    meas_name = header.keys.get("MEAS_NAME", "").strip()
    claims = []
    if meas_name:
        key = meas_name.upper().replace(" ", "_").replace("-", "_")
        claims.append(QuantityClaim(
            _QUANTITY.get(key), f"MEAS_NAME {meas_name}", header.line("MEAS_NAME"),
            problem=f"MEAS_NAME {meas_name!r} is not a BRDF; pass quantity= (--quantity) with "
                    f"one of {QUANTITIES}"))
    q, source = resolve_quantity(quantity, claims, path, default=Quantity.BRDF,
                                 default_source=_NO_MEAS_NAME)
    if source == _NO_MEAS_NAME and quantity is None:
        header.quirks.append("no MEAS_NAME: values taken as BRDF (sr^-1)")
    return q


def _polarization_value(key: str, val: str, unit: AngleUnit, path: Path,
                        line: int | None) -> float:
    """One polarization declaration: an angle in the file's unit, or ``s``/``p``/
    ``unpolarized`` (NaN; also ``nan``)."""
    try:
        g = parse_number(val) * unit.factor
    except ValueError:
        try:
            return polarization_angle(val.lower())
        except ValueError as exc:
            raise FormatError(f"{key}: {exc}", path, line) from None
    if math.isinf(g):
        raise FormatError(f"{key} {val!r} is not a finite angle", path, line)
    return g


def _read_polarization(header: _Header, unit: AngleUnit, n: int, path: Path
                       ) -> np.ndarray | None:
    """Header phase, polarization: ``POLARIZATION``, ``SOURCE_POLARIZATION`` or
    ``INCIDENT_POLARIZATION`` - an angle in the file's unit or ``s``/``p``/``unpolarized``;
    several must agree."""
    found: list[tuple[str, float]] = []
    for key in _POLARIZATION_KEYS:
        val = header.keys.get(key, "").strip()
        if not val:
            continue
        g = _polarization_value(key, val, unit, path, header.line(key))
        if found and not (g == found[0][1] or (math.isnan(g) and math.isnan(found[0][1]))):
            first = found[0][0]
            raise FormatError(f"{first} {header.keys[first]!r} (line {header.line(first)}) "
                              f"contradicts {key} {val!r} (line {header.line(key)})", path,
                              header.line(key))
        found.append((key, g))
    return np.full(n, found[0][1]) if found else None


def _meta(header: _Header, path: Path, channels: list[str], unit: AngleUnit,
          declared_n: int | None, pole_rows: int) -> dict[str, Any]:
    """Provenance: sample (SAMPLE_NAME, a quirk when it is not the file name), instrument
    (LAB_NAME SYSTEM_NAME), date (MEAS_DATE MEAS_TIME), wavelengths from ``NNNnm`` channel names,
    the angle unit and its source, the raw header."""
    keys = header.keys
    sample = keys.get("SAMPLE_NAME") or None
    if sample and sample != path.stem:
        header.quirks.append(f"SAMPLE_NAME {sample!r} differs from the file name {path.name!r}")
    instrument = " ".join(v for v in (keys.get("LAB_NAME"), keys.get("SYSTEM_NAME")) if v)
    date = " ".join(v for v in (keys.get("MEAS_DATE"), keys.get("MEAS_TIME")) if v) or None
    found = [_WAVELENGTH.match(c) for c in channels]
    wavelengths = [float(m.group(1)) if m else None for m in found]
    return {
        "file": str(path),
        "file_abs": str(path.resolve()),
        "format": "astm",
        "sample": sample,
        "instrument": instrument or None,
        "date": date,
        "file_name_declared": keys.get("FILE_NAME"),
        "measurement_name": keys.get("MEAS_NAME", "").strip() or None,
        "wavelengths_nm": wavelengths if any(w is not None for w in wavelengths) else None,
        "angle_units": unit.word,
        "angle_units_source": unit.source,
        "original_units": unit.word,
        "num_points_declared": declared_n,
        "pole_rows": pole_rows,
        "quirks": header.quirks,
        "header": dict(keys),
    }


def read(path: str | os.PathLike, *, angles: str | None = None, quantity: str | None = None,
         **options: Any) -> Measurement:
    """Read an ASTM E1392-style file into a :class:`~roughbrdf.measurement.Measurement`.

    Parameters
    ----------
    path : str or path-like
    angles : {"rad", "deg"}, optional
        Override the angle unit (default: the header's declaration, else units in the VARS
        names, else radians).
    quantity : str, optional
        Override the quantity (default from ``MEAS_NAME``).

    Raises
    ------
    FormatError
        For anything the file gets wrong, naming the file and line.
    """
    path, lines = begin_read("astm", path, options, quantity)
    header = _read_header(lines, path)
    names, unit = _read_units(header, angles, path)
    declared_n = whole_number(header.keys.get("NUM_POINTS"), "NUM_POINTS", path,
                              header.line("NUM_POINTS"))
    texts, linenos = rows_from(lines, header.data_start, path,
                               f"no data rows (NUM_POINTS {declared_n})")
    cols = _read_columns(names, texts[0], header)
    data = _parse_rows(texts, linenos, cols, declared_n, len(lines), path)
    _check_roles(cols, header, path)
    ang = _read_angles(data, cols, unit, np.asarray(linenos), header, path)
    theta_i, theta_r, phi = common_frame_from_spherical(ang["theta_i"], ang["phi_i"],
                                                        ang["theta_s"], ang["phi_s"])
    q = _read_quantity(header, quantity, path)
    polarization = _read_polarization(header, unit, theta_i.size, path)
    channels = [cols.names[j] for j in cols.channel_idx]
    meta = _meta(header, path, channels, unit, declared_n, int((ang["theta_s"] == 0.0).sum()))
    original = {c: data[:, j].copy() for c, j in cols.angle_idx.items()}
    return Measurement(theta_i=theta_i, theta_r=theta_r, phi=phi,
                       values=data[:, cols.channel_idx], channels=channels, quantity=q,
                       polarization=polarization, original=original, meta=meta)


def _uniform_polarization(m: Measurement) -> float | None:
    """The one incident polarization of every sample (radians; NaN = unpolarized), None when
    the measurement has none; ``ValueError`` when the samples differ (ASTM has one header
    value)."""
    if m.polarization is None or m.n_samples == 0:
        return None
    p = np.asarray(m.polarization, dtype=float)
    if np.isnan(p).all():
        return math.nan
    if np.isnan(p).any() or np.ptp(p) > 0:
        raise ValueError("an ASTM file holds one polarization for all its rows (header "
                         "POLARIZATION); these samples differ: write CSV, or select one "
                         "polarization (Measurement.with_polarization)")
    return float(p[0])


def _polarization_text(gamma: float, factor: float, as_read: str | None) -> str:
    """The header value for ``gamma``: the value as read when it says the same, else
    ``unpolarized`` or the angle in the written unit."""
    if as_read:
        try:
            same = polarization_angle(as_read.lower())
        except ValueError:
            same = None
        if same is not None and (same == gamma or (math.isnan(same) and math.isnan(gamma))):
            return as_read
    return "unpolarized" if math.isnan(gamma) else f"{gamma * factor:.17g}"


def _meas_name(quantity: Quantity, as_read: str | None) -> str:
    """``MEAS_NAME``: the value as read when it names this quantity, else BRDF or CCBRDF."""
    if as_read:
        known = _QUANTITY.get(as_read.upper().replace(" ", "_").replace("-", "_"))
        if known is not None and (known == quantity or (known.cosine_weighted and
                                                        quantity.cosine_weighted)):
            return as_read
    return "CCBRDF" if quantity.cosine_weighted else "BRDF"


def _insert_before_rows(entries: list[tuple[str, str]], key: str, value: str) -> None:
    """Insert a key before ``NUM_POINTS``/``VARS`` (the keys that end a header)."""
    at = next((k for k, (name, _) in enumerate(entries) if name in ("NUM_POINTS", "VARS")),
              len(entries))
    entries.insert(at, (key, value))


def _header_entries(m: Measurement, target: Path, unit: str, quantity: Quantity,
                    gamma: float | None) -> list[tuple[str, str]]:
    """The header to write, as (key, value) pairs in order. A measurement read from an ASTM
    file gets its own header back, key for key, with the keys that describe the rows
    rewritten; any other measurement gets the provenance it has."""
    factor = 180.0 / math.pi if unit == "deg" else 1.0
    names = ",".join(["theta_i", "phi_i", "theta_s", "phi_s", *m.channels])
    meta = m.meta
    source = meta.get("header") if meta.get("format") == "astm" else None
    if not isinstance(source, dict):
        entries = [(k, str(v)) for k, v in (("LAB_NAME", meta.get("instrument")),
                                            ("SAMPLE_NAME", meta.get("sample") or target.stem),
                                            ("MEAS_NAME", _meas_name(quantity, None)),
                                            ("FILE_NAME", target.name),
                                            ("MEAS_DATE", meta.get("date"))) if v]
        source = {}
    else:
        entries = []
    for key, val in source.items():
        if key == "MEAS_NAME":
            val = _meas_name(quantity, val)
        elif key == "NUM_POINTS":
            val = str(m.n_samples)
        elif key == "VARS":
            val = names
        elif _is_unit_key(key) and val.strip() and _unit_word(val.split()[0]):
            val = unit
        elif key in _POLARIZATION_KEYS and val.strip():
            val = _polarization_text(math.nan if gamma is None else gamma, factor, val)
        entries.append((key, val))
    present = {k for k, _ in entries}
    if "MEAS_NAME" not in present:
        _insert_before_rows(entries, "MEAS_NAME", _meas_name(quantity, None))
    declared = [k for k, v in entries if _is_unit_key(k) and v == unit]
    if unit == "deg" and not declared:
        _insert_before_rows(entries, "ANGLE_UNITS", "deg")
    if gamma is not None and not present & set(_POLARIZATION_KEYS):
        _insert_before_rows(entries, "POLARIZATION", _polarization_text(gamma, factor, None))
    for key, val in (("NUM_POINTS", str(m.n_samples)), ("VARS", names)):
        if key not in present:
            entries.append((key, val))
    return entries


def write(measurement: Measurement, path: str | os.PathLike, *, angles: str = "rad",
          overwrite: bool = False) -> None:
    """Write an ASTM E1392-style file (7+ columns, VARS lists every column, phi_i = 180 deg).

    Parameters
    ----------
    measurement : Measurement
        Only absolute quantities: ``brdf`` (MEAS_NAME BRDF) and the cosine-weighted ``brdf_cos``
        / ``bridf`` (MEAS_NAME CCBRDF); one polarization for all samples (``POLARIZATION``).
    path : str or path-like
        Never the file the measurement was read from.
    angles : {"rad", "deg"}
        Angles are radians (the Mini-Diff convention) unless ``angles="deg"``, which is declared
        in an ``ANGLE_UNITS`` header line.
    overwrite : bool
        Replace an existing file (default: :class:`FileExistsError`).

    Notes
    -----
    A measurement read from an ASTM file keeps every header key it had (``meta["header"]``).
    What the file has no place for - another format's header keys without an ASTM
    counterpart, uncertainties - is named in one :class:`~roughbrdf.io.LossyWriteWarning`.
    The file is written atomically (a temporary file renamed over ``path``).

    Raises
    ------
    FileExistsError
        ``path`` exists and ``overwrite`` is false.
    roughbrdf.errors.ArgumentError
        ``path`` is the measurement's own input file.
    ValueError
        A relative measurement, per-sample polarizations, or channel labels that cannot be
        VARS names.
    """
    target = prepare_target(measurement, path, overwrite)
    m = measurement
    quantity = Quantity.parse(m.quantity)
    if not quantity.absolute:
        raise ValueError("ASTM E1392 holds absolute BRDF; a 'relative' measurement cannot be "
                         "written as .astm (use CSV)")
    unit = unit_word(angles)
    bad = [c for c in m.channels if re.search(r"[\s,;()\[\]]", c) or
           c.lower() in _ANGLE_NAMES or not c]
    if bad:
        raise ValueError(f"channel labels {bad} cannot be ASTM VARS names (no spaces, commas, "
                         "brackets or angle names)")
    gamma = _uniform_polarization(m)
    entries = _header_entries(m, target, unit, quantity, gamma)
    lost = header_not_written(m.meta, "astm", WRITES)
    items = [describe_keys(lost, str(m.meta.get("format")))] if lost else []
    if m.uncertainty is not None:
        items.append("the uncertainties (sigma)")
    factor = 180.0 / math.pi if unit == "deg" else 1.0
    cols = np.column_stack([m.theta_i * factor, np.full(m.n_samples, math.pi * factor),
                            m.theta_r * factor, np.mod(m.phi, 2 * math.pi) * factor, m.values])
    head = "".join(f"{k} {v}".rstrip() + "\n" for k, v in entries) + "\n"
    write_table(target, head, cols, delimiter=",", overwrite=overwrite)
    warn_not_written(target, "ASTM", items)
