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
``brdf_cos``; others need ``quantity=``.
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
    AngleUnit,
    FormatError,
    QuantityClaim,
    UnitClaim,
    angle_factor,
    azimuth_rows,
    begin_read,
    check_zenith_rows,
    common_frame_from_spherical,
    data_lines,
    parse_rows,
    resolve_angle_unit,
    resolve_quantity,
)

__all__ = ["read", "write", "EXTENSIONS"]

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
            key, _, val = s.partition(" ")
            key = key.strip().rstrip(":=").upper()
            keys[key] = val.strip()
            key_lines[key] = i + 1
            continue
        data_start = i
        break
    if "VARS" not in keys:
        raise FormatError("no VARS line (the list of column names) before the data; this does "
                          "not look like an ASTM E1392 file", path,
                          None if data_start is None else data_start + 1)
    return _Header(keys, key_lines, data_start)


def _header_unit_claim(header: _Header) -> UnitClaim | None:
    """The header's angle-unit declaration: the first key containing ``UNIT`` (with ``ANG``, or
    ``UNIT(S)`` alone) or ``ANGLE(S)`` whose value starts with ``deg``/``rad``."""
    for key, val in header.keys.items():
        if ("UNIT" in key and ("ANG" in key or key in ("UNITS", "UNIT"))) or \
                key in ("ANGLES", "ANGLE"):
            word = _unit_word(val.split()[0]) if val.strip() else None
            if word is not None:
                return UnitClaim((word,), f"header {key}", key, header.line(key))
    return None


def _read_units(header: _Header, angles: str | None, path: Path
                ) -> tuple[list[str], AngleUnit]:
    """Units phase: the VARS names without their unit suffixes (``theta_i(deg)`` ->
    ``theta_i``) and the angle unit - the ``angles=`` option, else the header's declaration,
    else the units in the angle names of VARS (all alike), else radians."""
    names: list[str] = []
    name_units: list[str] = []
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
    claims = [c for c in (_header_unit_claim(header),) if c is not None]
    if name_units:
        claims.append(UnitClaim(tuple(name_units), "VARS names", "VARS", header.line("VARS")))
    unit = resolve_angle_unit(angles, claims, path, default="rad",
                              default_source="default (radians)")
    return names, unit


def _read_num_points(header: _Header, path: Path) -> int | None:
    """The ``NUM_POINTS`` keyword, if any (a number, else an error naming its line)."""
    if "NUM_POINTS" not in header.keys:
        return None
    try:
        return int(float(header.keys["NUM_POINTS"].split()[0]))
    except (ValueError, IndexError):
        raise FormatError(f"NUM_POINTS is not a number: {header.keys['NUM_POINTS']!r}", path,
                          header.line("NUM_POINTS")) from None


def _read_columns(names: list[str], first_row: str, header: _Header) -> _Columns:
    """Columns phase: canonical angle names; when the rows have one value more than VARS has
    names and VARS has ``theta_s`` but no ``phi_s`` (the Mini-Diff files), ``phi_s`` is inserted
    after ``theta_s`` (recorded as a quirk)."""
    names = list(names)
    canon = [_ANGLE_NAMES.get(n.lower()) for n in names]
    sep = "," if "," in first_row else None
    ncols_first = (first_row.count(",") + 1) if sep else len(first_row.split())
    if ncols_first == len(names) + 1 and "phi_s" not in canon and "theta_s" in canon:
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


def _read_rows(lines: list[str], header: _Header, declared_n: int | None, path: Path
               ) -> tuple[list[str], list[int]]:
    """Rows phase: the non-blank lines from the first data row on, with their line numbers."""
    if header.data_start is None:
        raise FormatError(f"no data rows (NUM_POINTS {declared_n})", path, len(lines) + 1)
    return data_lines(lines, header.data_start)


def _parse_rows(texts: list[str], linenos: list[int], cols: _Columns, declared_n: int | None,
                n_lines: int, path: Path) -> np.ndarray:
    """Rows phase: the numbers (comma or blank separated, one value per column) and their count
    against ``NUM_POINTS``."""
    sep = "," if "," in texts[0] else None
    data = parse_rows(texts, linenos, len(cols.names), path, sep=sep,
                      what=f"values (VARS: {', '.join(cols.names)})")
    if declared_n is not None and data.shape[0] != declared_n:
        if data.shape[0] < declared_n:
            raise FormatError(f"truncated file: NUM_POINTS is {declared_n} but only "
                              f"{data.shape[0]} data rows follow (file ends at line "
                              f"{n_lines})", path, n_lines + 1)
        raise FormatError(f"{data.shape[0]} data rows but NUM_POINTS is {declared_n}; first "
                          "extra row here", path, linenos[declared_n])
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
    beyond = (np.abs(out["phi_i"]) > _TWO_PI_SLACK) | (np.abs(out["phi_s"]) > _TWO_PI_SLACK)
    if unit.word == "rad" and beyond.any():
        raise FormatError("azimuth beyond 2 pi rad: the angles look like degrees; declare the "
                          "unit (angles='deg' / --angles deg)", path,
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
    if source == _NO_MEAS_NAME:
        header.quirks.append("no MEAS_NAME: values taken as BRDF (sr^-1)")
    return q


def _read_polarization(header: _Header, unit: AngleUnit, n: int, path: Path
                       ) -> np.ndarray | None:
    """Header phase, polarization: the first non-empty ``POLARIZATION``,
    ``SOURCE_POLARIZATION`` or ``INCIDENT_POLARIZATION`` - an angle in the file's unit or
    ``s``/``p``/``unpolarized``."""
    for key in ("POLARIZATION", "SOURCE_POLARIZATION", "INCIDENT_POLARIZATION"):
        val = header.keys.get(key, "").strip()
        if not val:
            continue
        try:
            g = float(val) * unit.factor
        except ValueError:
            try:
                g = polarization_angle(val.lower())
            except ValueError as exc:
                raise FormatError(str(exc), path, header.line(key)) from None
        return np.full(n, g)
    return None


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
    declared_n = _read_num_points(header, path)
    texts, linenos = _read_rows(lines, header, declared_n, path)
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


def write(measurement: Measurement, path: str | os.PathLike, *, angles: str = "rad") -> None:
    """Write an ASTM E1392-style file (7+ columns, VARS lists every column, phi_i = 180 deg).

    Parameters
    ----------
    measurement : Measurement
        Only absolute quantities: ``brdf`` (MEAS_NAME BRDF) and the cosine-weighted ``brdf_cos``
        / ``bridf`` (MEAS_NAME CCBRDF).
    path : str or path-like
    angles : {"rad", "deg"}
        Angles are radians (the Mini-Diff convention) unless ``angles="deg"``, which is declared
        in an ``ANGLE_UNITS`` header line.
    """
    m = measurement
    quantity = Quantity.parse(m.quantity)
    if not quantity.absolute:
        raise ValueError("ASTM E1392 holds absolute BRDF; a 'relative' measurement cannot be "
                         "written as .astm (use CSV)")
    factor = 180.0 / math.pi if angle_factor(angles) != 1.0 else 1.0
    meas_name = "CCBRDF" if quantity.cosine_weighted else "BRDF"
    bad = [c for c in m.channels if re.search(r"[\s,;]", c)]
    if bad:
        raise ValueError(f"channel labels with spaces or commas cannot be ASTM VARS: {bad}")
    meta = m.meta
    lines = []
    if meta.get("instrument"):
        lines.append(f"LAB_NAME {meta['instrument']}")
    lines.append(f"SAMPLE_NAME {meta.get('sample') or Path(path).stem}")
    lines.append(f"MEAS_NAME {meas_name}")
    lines.append(f"FILE_NAME {Path(path).name}")
    if meta.get("date"):
        lines.append(f"MEAS_DATE {meta['date']}")
    if factor != 1.0:
        lines.append("ANGLE_UNITS deg")
    lines.append(f"NUM_POINTS {m.n_samples}")
    lines.append("VARS " + ",".join(["theta_i", "phi_i", "theta_s", "phi_s", *m.channels]))
    phi_s = np.mod(m.phi, 2 * math.pi)
    cols = np.column_stack([m.theta_i * factor, np.full(m.n_samples, math.pi * factor),
                            m.theta_r * factor, phi_s * factor, m.values])
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(lines) + "\n\n")
        np.savetxt(fh, cols, delimiter=",", fmt="%.17g")
