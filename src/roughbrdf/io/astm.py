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
from pathlib import Path
from typing import Any

import numpy as np

from ..fresnel import polarization_angle
from ..measurement import QUANTITIES, Measurement
from ._common import (
    FormatError,
    angle_factor,
    azimuth_rows,
    begin_read,
    check_zenith_rows,
    common_frame_from_spherical,
    parse_rows,
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
_UNIT_IN_NAME = re.compile(r"^(?P<name>[^\[\(]+?)\s*[\[\(](?P<unit>[^\]\)]*)[\]\)]\s*$")
_WAVELENGTH = re.compile(r"^\s*(\d+(?:\.\d+)?)\s*nm\s*$", re.IGNORECASE)
_QUANTITY = {"BRDF": "brdf", "BSDF": "brdf", "CCBRDF": "brdf_cos", "CC_BRDF": "brdf_cos",
             "COSINE_CORRECTED_BRDF": "brdf_cos"}


def _split_vars(text: str) -> list[str]:
    """VARS names: comma (or semicolon) separated, else blank separated."""
    sep = "," if "," in text else (";" if ";" in text else None)
    parts = text.split(sep) if sep else text.split()
    return [p.strip() for p in parts if p.strip()]


def _header_unit(header: dict[str, str], path) -> tuple[str | None, str | None]:
    """(unit, key) from an angle-unit declaration in the header, if any."""
    for key, val in header.items():
        k = key.upper()
        if ("UNIT" in k and ("ANG" in k or k in ("UNITS", "UNIT"))) or k in ("ANGLES", "ANGLE"):
            word = val.strip().split()[0].lower() if val.strip() else ""
            if word.startswith("deg") or word.startswith("rad"):
                return ("deg" if word.startswith("deg") else "rad"), key
    return None, None


def read(path: str | os.PathLike, *, angles: str | None = None, quantity: str | None = None,
         **options: Any) -> Measurement:
    """Read an ASTM E1392-style file into a :class:`~roughbrdf.measurement.Measurement`.

    Parameters
    ----------
    angles : {"rad", "deg"}, optional
        Override the angle unit (default: the header's declaration, else radians).
    quantity : str, optional
        Override the quantity (default from ``MEAS_NAME``).
    """
    path, lines = begin_read("astm", path, options, quantity)
    header: dict[str, str] = {}
    header_lines: dict[str, int] = {}
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
            key = key.strip().rstrip(":=")
            header[key.upper()] = val.strip()
            header_lines[key.upper()] = i + 1
            continue
        data_start = i
        break
    if "VARS" not in header:
        raise FormatError("no VARS line (the list of column names) before the data; this does "
                          "not look like an ASTM E1392 file", path,
                          None if data_start is None else data_start + 1)
    vars_line = header_lines["VARS"]
    names_raw = _split_vars(header["VARS"])

    # --- angle unit: option > header key > units in VARS names > radians ----------------------
    unit_source = "default (radians)"
    names: list[str] = []
    name_units: set[str] = set()
    for nm in names_raw:
        m = _UNIT_IN_NAME.match(nm)
        if m and m.group("unit").strip().lower().rstrip("s") in ("deg", "degree", "rad",
                                                                  "radian"):
            names.append(m.group("name").strip())
            if m.group("name").strip().lower() in _ANGLE_NAMES:
                name_units.add("deg" if m.group("unit").lower().startswith("deg") else "rad")
        else:
            names.append(nm)
    head_unit, head_key = _header_unit(header, path)
    if angles is not None:
        unit = "deg" if angle_factor(angles, path) != 1.0 else "rad"
        unit_source = "option angles="
    elif head_unit is not None:
        unit = head_unit
        unit_source = f"header {head_key}"
    elif name_units:
        if len(name_units) > 1:
            raise FormatError(f"VARS mixes angle units {sorted(name_units)}", path, vars_line)
        unit = name_units.pop()
        unit_source = "VARS names"
    else:
        unit = "rad"
    factor = math.pi / 180.0 if unit == "deg" else 1.0

    # --- data rows --------------------------------------------------------------------------
    quirks: list[str] = []
    declared_n = None
    if "NUM_POINTS" in header:
        try:
            declared_n = int(float(header["NUM_POINTS"].split()[0]))
        except (ValueError, IndexError):
            raise FormatError(f"NUM_POINTS is not a number: {header['NUM_POINTS']!r}", path,
                              header_lines["NUM_POINTS"]) from None
    if data_start is None:
        raise FormatError(f"no data rows (NUM_POINTS {declared_n})", path, len(lines) + 1)
    texts: list[str] = []
    linenos: list[int] = []
    for i in range(data_start, len(lines)):
        s = lines[i].strip()
        if s:
            texts.append(s)
            linenos.append(i + 1)
    sep = "," if "," in texts[0] else None

    ncols_first = (texts[0].count(",") + 1) if sep else len(texts[0].split())
    lnames = [n.lower() for n in names]
    canon = [_ANGLE_NAMES.get(n) for n in lnames]
    if ncols_first == len(names) + 1 and "phi_s" not in canon and "theta_s" in canon:
        k = canon.index("theta_s") + 1
        names.insert(k, "phi_s")
        canon.insert(k, "phi_s")
        quirks.append("VARS lists one name fewer than the rows have values; inserted the "
                      "missing 'phi_s' after 'theta_s'")
    data = parse_rows(texts, linenos, len(names), path, sep=sep,
                      what=f"values (VARS: {', '.join(names)})")
    if declared_n is not None and data.shape[0] != declared_n:
        if data.shape[0] < declared_n:
            raise FormatError(f"truncated file: NUM_POINTS is {declared_n} but only "
                              f"{data.shape[0]} data rows follow (file ends at line "
                              f"{len(lines)})", path, len(lines) + 1)
        raise FormatError(f"{data.shape[0]} data rows but NUM_POINTS is {declared_n}; first "
                          "extra row here", path, linenos[declared_n])
    for needed in ("theta_i", "theta_s"):
        if needed not in canon:
            raise FormatError(f"VARS has no {needed} column: {names}", path, vars_line)
    idx = {c: canon.index(c) for c in ("theta_i", "phi_i", "theta_s", "phi_s") if c in canon}
    chan_idx = [j for j, c in enumerate(canon) if c is None]
    if not chan_idx:
        raise FormatError(f"VARS has no value column besides the angles: {names}", path,
                          vars_line)
    ln = np.asarray(linenos)
    col = {c: data[:, j] for c, j in idx.items()}
    ti = check_zenith_rows(col["theta_i"] * factor, "theta_i", ln, path, unit=unit)
    ts = check_zenith_rows(col["theta_s"] * factor, "theta_s", ln, path, unit=unit)
    if "phi_i" in col:
        pi_ = azimuth_rows(col["phi_i"], "phi_i", ln, path) * factor
    else:
        pi_ = np.full_like(ti, math.pi)
        quirks.append("no phi_i column: source assumed at phi_i = 180 deg")
    if "phi_s" in col:
        ps = azimuth_rows(col["phi_s"], "phi_s", ln, path) * factor
    else:
        raise FormatError(f"VARS has no phi_s column and the rows have no extra value: {names}",
                          path, vars_line)
    if unit == "rad" and max(np.abs(pi_).max(), np.abs(ps).max()) > 2 * math.pi + 1e-6:
        k = int(np.flatnonzero((np.abs(pi_) > 2 * math.pi + 1e-6)
                               | (np.abs(ps) > 2 * math.pi + 1e-6))[0])
        raise FormatError("azimuth beyond 2 pi rad: the angles look like degrees; declare the "
                          "unit (angles='deg' / --angles deg)", path, int(ln[k]))
    theta_i, theta_r, phi = common_frame_from_spherical(ti, pi_, ts, ps)

    channels = [names[j] for j in chan_idx]
    values = data[:, chan_idx]

    # --- quantity, polarization, provenance --------------------------------------------------
    meas_name = header.get("MEAS_NAME", "").strip()
    if quantity is not None:  # validated by begin_read
        q = quantity
    elif not meas_name:
        q = "brdf"
        quirks.append("no MEAS_NAME: values taken as BRDF (sr^-1)")
    else:
        key = meas_name.upper().replace(" ", "_").replace("-", "_")
        if key not in _QUANTITY:
            raise FormatError(f"MEAS_NAME {meas_name!r} is not a BRDF; pass quantity= "
                              f"(--quantity) with one of {QUANTITIES}", path,
                              header_lines["MEAS_NAME"])
        q = _QUANTITY[key]
    polarization = None
    for key in ("POLARIZATION", "SOURCE_POLARIZATION", "INCIDENT_POLARIZATION"):
        if key in header and header[key].strip():
            val = header[key].strip()
            try:
                g = math.radians(float(val)) if unit == "deg" else float(val)
            except ValueError:
                try:
                    g = polarization_angle(val.lower())
                except ValueError as exc:
                    raise FormatError(str(exc), path, header_lines[key]) from None
            polarization = np.full(theta_i.shape, g)
            break

    sample = header.get("SAMPLE_NAME") or None
    if sample and sample != path.stem:
        quirks.append(f"SAMPLE_NAME {sample!r} differs from the file name {path.name!r}")
    instrument = " ".join(v for v in (header.get("LAB_NAME"), header.get("SYSTEM_NAME")) if v)
    date = " ".join(v for v in (header.get("MEAS_DATE"), header.get("MEAS_TIME")) if v) or None
    wavelengths = []
    for c in channels:
        m = _WAVELENGTH.match(c)
        wavelengths.append(float(m.group(1)) if m else None)
    meta: dict[str, Any] = {
        "file": str(path),
        "format": "astm",
        "sample": sample,
        "instrument": instrument or None,
        "date": date,
        "file_name_declared": header.get("FILE_NAME"),
        "measurement_name": meas_name or None,
        "wavelengths_nm": wavelengths if any(w is not None for w in wavelengths) else None,
        "angle_units": unit,
        "angle_units_source": unit_source,
        "original_units": unit,
        "num_points_declared": declared_n,
        "pole_rows": int((ts == 0.0).sum()),
        "quirks": quirks,
        "header": dict(header),
    }
    original = {c: col[c].copy() for c in ("theta_i", "phi_i", "theta_s", "phi_s") if c in col}
    return Measurement(theta_i=theta_i, theta_r=theta_r, phi=phi, values=values,
                       channels=channels, quantity=q, polarization=polarization,
                       original=original, meta=meta)


def write(measurement: Measurement, path: str | os.PathLike, *, angles: str = "rad") -> None:
    """Write an ASTM E1392-style file (7+ columns, VARS lists every column, phi_i = 180 deg).

    Only ``brdf`` (MEAS_NAME BRDF) and ``brdf_cos``/``bridf`` (MEAS_NAME CCBRDF) can be written.
    Angles are radians (the Mini-Diff convention) unless ``angles="deg"``, which is declared in
    an ``ANGLE_UNITS`` header line.
    """
    m = measurement
    if m.quantity == "relative":
        raise ValueError("ASTM E1392 holds absolute BRDF; a 'relative' measurement cannot be "
                         "written as .astm (use CSV)")
    factor = 180.0 / math.pi if angle_factor(angles) != 1.0 else 1.0
    meas_name = "BRDF" if m.quantity == "brdf" else "CCBRDF"
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
