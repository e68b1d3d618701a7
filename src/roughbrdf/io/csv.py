"""roughbrdf CSV: a plain, documented text layout for any measurement (``.csv``).

Layout::

    # roughbrdf-csv 1
    # angles: deg
    # quantity: brdf
    # sample: C1_Black
    # instrument: Light Tec Mini-Diff V2
    # date: 2023/12/05 11:8:25
    theta_i,theta_r,phi,465nm,525nm,630nm,sigma_465nm,sigma_525nm,sigma_630nm,polarization
    60,61,0,12.9,20.8,30.0,0.1,0.1,0.1,nan

Header (``#`` lines before the column names, each ``# key: value``):

* ``# roughbrdf-csv 1`` - the format tag and version (written always; optional when reading);
* ``# angles: deg`` or ``# angles: rad`` - **required** unit of every angle column (or give the
  unit in the angle column names, ``theta_i_deg``, as ``roughbrdf eval`` writes them, or pass
  ``angles=``); a file with neither is refused;
* ``# quantity: brdf|brdf_cos|bridf|relative`` - what the values hold (required, unless the
  single value column is named after a quantity, e.g. ``brdf``, or ``quantity=`` is given);
* ``# relative_to: brdf|bridf`` - for ``relative`` data, whether the values are proportional to
  the BRDF or to BRDF x cos(theta_r) (TR75's relative BRIDF); read by ``rb.fit``;
* optional provenance: ``sample``, ``instrument``, ``date``, ``source_file``, ``source_format``
  and any other ``key: value`` (kept as strings in ``Measurement.meta``).

Columns (comma separated, first non-``#`` line; order free):

* ``theta_i``, ``theta_r``, ``phi`` - the library's common frame: incidence zenith, reflection
  zenith, reflection azimuth with ``phi = 0`` on the forward (specular) side and ``phi = 180°``
  on the source (retro) side; each may carry a unit suffix ``_deg``/``_rad``;
* every other column is a **channel** (value column) named by its label, e.g. ``525nm``;
* ``sigma_<label>`` - one-sigma uncertainty of channel ``<label>`` (all channels or none);
* ``polarization`` - incident polarization angle gamma from the plane of incidence, in the
  declared angle unit, or ``s``/``p``/``unpolarized``; ``nan`` or empty means unpolarized;
* ``orig_<name>`` - the source file's own angle columns, kept in ``Measurement.original``.

Non-finite values in channels (``nan``, ``inf``) are read and counted by
``Measurement.validate``; a non-finite angle is an error naming the line.
"""

from __future__ import annotations

import math
import os
import re
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
    parse_rows,
)

__all__ = ["read", "write", "EXTENSIONS", "TAG"]

EXTENSIONS = (".csv",)
TAG = "roughbrdf-csv"
VERSION = 1
_ANGLES = ("theta_i", "theta_r", "phi")
_SUFFIX = re.compile(r"^(theta_i|theta_r|phi|polarization)_(deg|rad)$")


def read(path: str | os.PathLike, *, angles: str | None = None, quantity: str | None = None,
         **options: Any) -> Measurement:
    """Read a roughbrdf CSV file (see the module docstring for the layout).

    ``angles`` and ``quantity`` supply or override the header's declarations.
    """
    path, lines = begin_read("csv", path, options, quantity)
    header: dict[str, str] = {}
    hline: dict[str, int] = {}
    col_line = None
    for i, raw in enumerate(lines):
        s = raw.strip()
        if not s:
            continue
        if s.startswith("#"):
            body = s.lstrip("#").strip()
            if body.startswith(TAG):
                header["format_version"] = body[len(TAG):].strip() or str(VERSION)
                hline["format_version"] = i + 1
                continue
            key, sep, val = body.partition(":")
            if sep:
                header[key.strip().lower()] = val.strip()
                hline[key.strip().lower()] = i + 1
            continue
        col_line = i
        break
    if col_line is None:
        raise FormatError("no column-name line (e.g. 'theta_i,theta_r,phi,brdf')", path,
                          len(lines) + 1)
    names = [c.strip() for c in lines[col_line].split(",")]
    cl = col_line + 1
    if any(n == "" for n in names):
        raise FormatError(f"empty column name in {lines[col_line].strip()!r}", path, cl)
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise FormatError(f"duplicate column names {dup}", path, cl)

    # --- units: option > header > column suffix ----------------------------------------------
    suffix_units = {}
    base = []
    for n in names:
        m = _SUFFIX.match(n.lower())
        if m:
            base.append(m.group(1))
            suffix_units[m.group(1)] = m.group(2)
        else:
            base.append(n.lower() if n.lower() in (*_ANGLES, "polarization") else n)
    for a in _ANGLES:
        if a not in base:
            raise FormatError(f"missing column {a!r}; columns are {names} (needed: theta_i, "
                              "theta_r, phi, then one column per channel)", path, cl)
    if len(set(suffix_units.values())) > 1:
        raise FormatError(f"angle columns mix units: {names}", path, cl)
    head_unit = header.get("angles") or header.get("angle_units") or header.get("units")
    if angles is not None:
        unit = "deg" if angle_factor(angles, path) != 1.0 else "rad"
    elif head_unit:
        unit = "deg" if angle_factor(head_unit, path, hline.get("angles")) != 1.0 else "rad"
        if suffix_units and set(suffix_units.values()) != {unit}:
            raise FormatError(f"'# angles: {head_unit}' contradicts the column names {names}",
                              path, cl)
    elif suffix_units:
        unit = next(iter(suffix_units.values()))
    else:
        raise FormatError("missing angle units: add a header line '# angles: deg' or "
                          "'# angles: rad' before the column names (or name the columns "
                          "theta_i_deg, ...; or pass angles=)", path, cl)
    factor = math.pi / 180.0 if unit == "deg" else 1.0

    # --- column roles ------------------------------------------------------------------------
    idx = {a: base.index(a) for a in _ANGLES}
    pol_col = base.index("polarization") if "polarization" in base else None
    sigma_cols = {n[len("sigma_"):]: j for j, n in enumerate(names) if n.startswith("sigma_")}
    orig_cols = {n[len("orig_"):]: j for j, n in enumerate(names) if n.startswith("orig_")}
    used = set(idx.values()) | set(sigma_cols.values()) | set(orig_cols.values())
    if pol_col is not None:
        used.add(pol_col)
    chan_cols = [j for j in range(len(names)) if j not in used]
    channels = [names[j] for j in chan_cols]
    if not channels:
        raise FormatError(f"no value column besides the angles: {names}", path, cl)
    if sigma_cols:
        missing = [c for c in channels if c not in sigma_cols]
        extra = [c for c in sigma_cols if c not in channels]
        if missing or extra:
            raise FormatError(f"sigma_ columns must match the channels one to one (channels "
                              f"{channels}; no sigma for {missing}; sigma without channel "
                              f"{extra})", path, cl)

    # --- quantity ---------------------------------------------------------------------------
    declared = header.get("quantity")
    if declared is not None and declared not in QUANTITIES:
        raise FormatError(f"quantity {declared!r} is not one of {QUANTITIES}", path,
                          hline["quantity"])
    if quantity is not None:
        q = quantity
    elif declared:
        q = declared
    elif len(channels) == 1 and channels[0].lower() in QUANTITIES:
        q = channels[0].lower()
    else:
        raise FormatError("missing quantity: add a header line '# quantity: brdf' (or "
                          "brdf_cos, bridf, relative), or pass quantity= (--quantity)", path,
                          cl)

    # --- rows -------------------------------------------------------------------------------
    texts: list[str] = []
    linenos: list[int] = []
    for i in range(col_line + 1, len(lines)):
        s = lines[i].strip()
        if s and not s.startswith("#"):
            texts.append(s)
            linenos.append(i + 1)
    if not texts:
        raise FormatError("no data rows after the column names", path, cl)
    polarization = None
    ncol = len(names)
    if pol_col is not None:
        rows = [t.split(",") for t in texts]
        for r, t, ln_ in zip(rows, texts, linenos, strict=True):
            if len(r) != ncol:
                raise FormatError(f"wrong column count: expected {ncol} values ({', '.join(names)}"
                                  f"), found {len(r)}: {t!r}", path, ln_)
        ptok = [r[pol_col].strip() for r in rows]
        polarization = np.empty(len(rows))
        cache: dict[str, float] = {}
        for k, tok in enumerate(ptok):
            if tok not in cache:
                try:
                    cache[tok] = float(tok) * factor if tok else math.nan
                except ValueError:
                    try:
                        cache[tok] = polarization_angle(tok)
                    except ValueError:
                        raise FormatError(f"polarization {tok!r} is neither an angle nor s/p/"
                                          "unpolarized", path, linenos[k]) from None
            polarization[k] = cache[tok]
        texts = [",".join(r[:pol_col] + ["0"] + r[pol_col + 1:]) for r in rows]
    data = parse_rows(texts, linenos, ncol, path, sep=",",
                      what=f"values ({', '.join(names)})")
    ln = np.asarray(linenos)
    ti = check_zenith_rows(data[:, idx["theta_i"]] * factor, "theta_i", ln, path, unit=unit)
    tr = check_zenith_rows(data[:, idx["theta_r"]] * factor, "theta_r", ln, path, unit=unit)
    ph = azimuth_rows(data[:, idx["phi"]], "phi", ln, path) * factor
    values = data[:, chan_cols]
    uncertainty = data[:, [sigma_cols[c] for c in channels]] if sigma_cols else None
    original = {k: data[:, j].copy() for k, j in orig_cols.items()}

    meta: dict[str, Any] = {k: v for k, v in header.items()
                            if k not in ("angles", "quantity", "format_version")}
    meta.update({
        "file": str(path),
        "format": "csv",
        "sample": header.get("sample"),
        "instrument": header.get("instrument"),
        "date": header.get("date"),
        "angle_units": unit,
        "format_version": header.get("format_version"),
    })
    if original:
        meta["original_units"] = header.get("original_units", "as in the source file")
    return Measurement(theta_i=ti, theta_r=tr, phi=ph, values=values, channels=channels,
                       quantity=q, polarization=polarization, uncertainty=uncertainty,
                       original=original, meta=meta)


def _clean(text: Any) -> str:
    return " ".join(str(text).split())


def write(measurement: Measurement, path: str | os.PathLike, *, angles: str = "deg",
          original: bool = True) -> None:
    """Write a roughbrdf CSV file (``angles="deg"`` or ``"rad"``; ``original`` adds the source
    file's angle columns as ``orig_<name>``)."""
    m = measurement
    unit = "deg" if angle_factor(angles) != 1.0 else "rad"
    factor = 180.0 / math.pi if unit == "deg" else 1.0
    reserved = {*_ANGLES, "polarization"}
    for c in m.channels:
        if "," in c or c.strip() != c or not c or c.lower() in reserved or \
                c.startswith(("sigma_", "orig_")) or _SUFFIX.match(c.lower()):
            raise ValueError(f"channel label {c!r} cannot be a CSV column name")
    names = ["theta_i", "theta_r", "phi", *m.channels]
    cols = [m.theta_i * factor, m.theta_r * factor, m.phi * factor, m.values]
    if m.uncertainty is not None:
        names += [f"sigma_{c}" for c in m.channels]
        cols.append(m.uncertainty)
    if m.polarization is not None:
        names.append("polarization")
        cols.append(m.polarization * factor)
    orig_keys = []
    if original:
        for k, v in m.original.items():
            a = np.asarray(v)
            if a.ndim == 1 and np.issubdtype(a.dtype, np.number) and "," not in k:
                orig_keys.append(k)
                names.append(f"orig_{k}")
                cols.append(a.astype(float))
    head = [f"# {TAG} {VERSION}", f"# angles: {unit}", f"# quantity: {m.quantity}"]
    meta = m.meta
    for key in ("sample", "instrument", "date", "relative_to"):
        if meta.get(key):
            head.append(f"# {key}: {_clean(meta[key])}")
    if meta.get("file"):
        head.append(f"# source_file: {_clean(meta.get('source_file', meta['file']))}")
    if meta.get("format"):
        head.append(f"# source_format: {_clean(meta.get('source_format', meta['format']))}")
    if orig_keys and meta.get("original_units"):
        head.append(f"# original_units: {_clean(meta['original_units'])}")
    table = np.column_stack(cols)
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(head) + "\n" + ",".join(names) + "\n")
        np.savetxt(fh, table, delimiter=",", fmt="%.17g")
