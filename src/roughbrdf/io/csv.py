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
* ``# mueller: absolute|normalized`` - the value columns are Mueller-matrix elements
  ``m00`` ... ``m33`` (``Measurement.mueller``): all in the unit of ``quantity``, or ``m00`` in
  that unit and the others divided by ``m00``; required when such columns are present, and
  then every value column must be an element, ``m00`` among them, and there is no
  ``polarization`` column;
* ``# mueller_basis: psps|xyxy`` - the polarization basis of those elements (default ``psps``,
  :mod:`roughbrdf.mueller`); only with ``# mueller:``;
* optional provenance: ``sample``, ``instrument``, ``date``, ``source_file``, ``source_format``
  and any other ``key: value`` (kept as strings in ``Measurement.meta``).

Columns (comma separated, first non-``#`` line; order free):

* ``theta_i``, ``theta_r``, ``phi`` - the library's common frame: incidence zenith, reflection
  zenith, reflection azimuth with ``phi = 0`` on the forward (specular) side and ``phi = 180°``
  on the source (retro) side; each may carry a unit suffix ``_deg``/``_rad``;
* every other column is a **channel** (value column) named by its label, e.g. ``525nm``, or a
  Mueller element ``m<i><j>`` (``i`` output, ``j`` input Stokes component, 0-3) under
  ``# mueller:``;
* ``sigma_<label>`` - one-sigma uncertainty of channel ``<label>`` (all channels or none);
* ``polarization`` - incident polarization angle gamma from the plane of incidence, in the
  declared angle unit, or ``s``/``p``/``unpolarized``; ``nan`` or empty means unpolarized;
* ``orig_<name>`` - the source file's own angle columns, kept in ``Measurement.original``.

Non-finite values in channels (``nan``, ``inf``) are read and counted by
``Measurement.validate``; a non-finite angle is an error naming the line.

A header key given twice, unit declarations that disagree (``# angles:``, ``# units:``, the
column suffixes), and an ``angles=`` or ``quantity=`` option that contradicts the file are
errors naming both places; the options supply what the file does not say.

Every header key is kept, as written, in ``meta["header"]`` (and, lower-cased, in ``meta``);
:func:`write` writes them all back when the measurement came from a CSV file (``angles`` and
``quantity`` rewritten to describe the rows written). A measurement read from another format
gets that file's header as JSON in ``# source_header:``, so nothing of it is lost.
"""

from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..fresnel import polarization_angle
from ..measurement import MUELLER_BASES, MUELLER_ELEMENTS, MUELLER_KINDS, QUANTITIES, Measurement
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
    data_lines,
    prepare_target,
    resolve_angle_unit,
    resolve_quantity,
    unit_word,
    warn_implausible_angles,
    write_table,
)
from ._rows import begin_read, parse_number, parse_rows

__all__ = ["read", "write", "EXTENSIONS", "TAG", "header_field"]

EXTENSIONS = (".csv",)
TAG = "roughbrdf-csv"
VERSION = 1
_ANGLES = ("theta_i", "theta_r", "phi")
_SUFFIX = re.compile(r"^(theta_i|theta_r|phi|polarization)_(deg|rad)$")
#: header keys that declare the angle unit, first found wins
_UNIT_KEYS = ("angles", "angle_units", "units")
#: header keys of the Mueller declaration: attributes of the measurement, not ``meta``
_MUELLER_KEYS = ("mueller", "mueller_basis")
_ELEMENT = re.compile(r"^m[0-3][0-3]$", re.IGNORECASE)
#: provenance keys taken from ``meta`` when writing (an edited ``meta["sample"]`` is written)
_PROVENANCE = ("sample", "instrument", "date", "relative_to")
_MISSING_UNITS = ("missing angle units: add a header line '# angles: deg' or '# angles: rad' "
                  "before the column names (or name the columns theta_i_deg, ...; or pass "
                  "angles=)")
_MISSING_QUANTITY = ("missing quantity: add a header line '# quantity: brdf' (or brdf_cos, "
                     "bridf, relative), or pass quantity= (--quantity)")


@dataclass
class _Header:
    """The ``# key: value`` lines before the column names (keys lower-cased)."""

    keys: dict[str, str]
    lines: dict[str, int]
    #: index (0-based) of the column-name line
    col_line: int
    #: key (lower case) -> the key as written
    spelled: dict[str, str]

    def line(self, key: str) -> int | None:
        """1-based line of ``# key:`` (None when absent)."""
        return self.lines.get(key)


@dataclass
class _Columns:
    """The column-name line: names as written, base names (unit suffix removed, angle names
    lower-cased) and the units given by suffixes."""

    names: list[str]
    base: list[str]
    suffix_units: dict[str, str]
    #: 1-based line of the column names
    line: int


@dataclass
class _Roles:
    """Which column is what: angle columns, channels, ``sigma_``, ``orig_``, ``polarization``."""

    angles: dict[str, int]
    channels: list[str]
    channel_cols: list[int]
    sigma_cols: dict[str, int]
    orig_cols: dict[str, int]
    pol_col: int | None


# --------------------------------------------------------------------------------------------
# phases of read()
# --------------------------------------------------------------------------------------------
def _read_header(lines: list[str], path: Path) -> _Header:
    """Header phase: the ``#`` lines before the first other non-blank line (the column names):
    ``# roughbrdf-csv N`` gives ``format_version``, ``# key: value`` a keyword; other comments
    are ignored."""
    keys: dict[str, str] = {}
    key_lines: dict[str, int] = {}
    spelled: dict[str, str] = {}
    for i, raw in enumerate(lines):
        s = raw.strip()
        if not s:
            continue
        if not s.startswith("#"):
            return _Header(keys, key_lines, i, spelled)
        body = s.lstrip("#").strip()
        if body.startswith(TAG):
            add_key(keys, key_lines, "format_version", body[len(TAG):].strip() or str(VERSION),
                    i + 1, path, shown=f"the '# {TAG}' line")
            continue
        key, sep, val = body.partition(":")
        if sep:
            add_key(keys, key_lines, key.strip().lower(), val.strip(), i + 1, path,
                    shown="'# {key}:'")
            spelled[key.strip().lower()] = key.strip()
    raise FormatError("no column-name line (e.g. 'theta_i,theta_r,phi,brdf')", path,
                      len(lines) + 1)


def header_field(key: str) -> str | None:
    """What a CSV header key holds, for a writer of another format: :data:`LAYOUT` (the unit
    and quantity declarations: every writer writes its own), else the field of ``meta`` it is
    kept in (its lower-case name)."""
    k = key.strip().lower()
    return LAYOUT if k in (*_UNIT_KEYS, "quantity", "format_version") else k


def _read_column_names(lines: list[str], header: _Header, path: Path) -> _Columns:
    """Columns phase, names: comma separated, none empty, no duplicates; ``theta_i``,
    ``theta_r`` and ``phi`` present (each may carry a ``_deg``/``_rad`` suffix, all the same)."""
    text = lines[header.col_line]
    names = [c.strip() for c in text.split(",")]
    cl = header.col_line + 1
    if any(n == "" for n in names):
        raise FormatError(f"empty column name in {text.strip()!r}", path, cl)
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise FormatError(f"duplicate column names {dup}", path, cl)
    suffix_units: dict[str, str] = {}
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
    return _Columns(names, base, suffix_units, cl)


def _read_units(header: _Header, cols: _Columns, angles: str | None, path: Path) -> AngleUnit:
    """Units phase: the ``angles=`` option, else ``# angles:`` (or ``angle_units``/``units``),
    which the column suffixes must agree with, else the column suffixes; a file with neither
    is refused (there is no default unit)."""
    claims = [UnitClaim((header.keys[k],), f"header {k}", f"'# {k}: {header.keys[k]}'",
                        header.line(k)) for k in _UNIT_KEYS if header.keys.get(k)]
    if cols.suffix_units:
        claims.append(UnitClaim(tuple(cols.suffix_units.values()), "column names",
                                f"the column names {cols.names}", cols.line))
    return resolve_angle_unit(angles, claims, path, default=None, missing=_MISSING_UNITS,
                              missing_line=cols.line)


def _read_roles(cols: _Columns, path: Path) -> _Roles:
    """Columns phase, roles: the angle columns, ``polarization``, ``sigma_<label>`` (one per
    channel or none), ``orig_<name>``; every other column is a channel (at least one)."""
    names = cols.names
    angles = {a: cols.base.index(a) for a in _ANGLES}
    pol_col = cols.base.index("polarization") if "polarization" in cols.base else None
    sigma_cols = {n[len("sigma_"):]: j for j, n in enumerate(names) if n.startswith("sigma_")}
    orig_cols = {n[len("orig_"):]: j for j, n in enumerate(names) if n.startswith("orig_")}
    used = set(angles.values()) | set(sigma_cols.values()) | set(orig_cols.values())
    if pol_col is not None:
        used.add(pol_col)
    chan_cols = [j for j in range(len(names)) if j not in used]
    channels = [names[j] for j in chan_cols]
    if not channels:
        raise FormatError(f"no value column besides the angles: {names}", path, cols.line)
    if sigma_cols:
        missing = [c for c in channels if c not in sigma_cols]
        extra = [c for c in sigma_cols if c not in channels]
        if missing or extra:
            raise FormatError(f"sigma_ columns must match the channels one to one (channels "
                              f"{channels}; no sigma for {missing}; sigma without channel "
                              f"{extra})", path, cols.line)
    return _Roles(angles, channels, chan_cols, sigma_cols, orig_cols, pol_col)


def _read_quantity(header: _Header, roles: _Roles, quantity: str | None, path: Path,
                   line: int) -> Quantity:
    """Quantity phase: ``# quantity:`` (must be a quantity; a ``quantity=`` option must agree
    with it), else the option, else the name of a single value column (``brdf``...); one of
    them is required."""
    claims = []
    declared = header.keys.get("quantity")
    if declared is not None:
        try:
            q = Quantity.parse(declared)
        except ValueError:
            raise FormatError(f"quantity {declared!r} is not one of {QUANTITIES}", path,
                              header.line("quantity")) from None
        claims.append(QuantityClaim(q, f"# quantity: {declared}", header.line("quantity")))
    fallback = None
    if len(roles.channels) == 1 and roles.channels[0].lower() in QUANTITIES:
        fallback = QuantityClaim(Quantity(roles.channels[0].lower()),
                                 f"column name {roles.channels[0]!r}", line)
    q, _ = resolve_quantity(quantity, claims, path, fallback=fallback,
                            missing=_MISSING_QUANTITY, missing_line=line)
    return q


def _read_mueller(header: _Header, roles: _Roles, path: Path, line: int
                  ) -> tuple[str | None, str | None]:
    """Mueller phase: ``# mueller:`` and ``# mueller_basis:`` against the columns. Element
    columns need the declaration (absolute or normalized cannot be guessed); a declaration
    needs ``m00``, only element columns and no ``polarization`` column."""
    kind, basis = header.keys.get("mueller"), header.keys.get("mueller_basis")
    elements = [c for c in roles.channels if _ELEMENT.match(c)]
    if kind is None:
        if basis is not None:
            raise FormatError("'# mueller_basis:' without '# mueller: absolute|normalized'",
                              path, header.line("mueller_basis"))
        if elements:
            raise FormatError(f"columns {elements} look like Mueller elements: declare them "
                              "with a header line '# mueller: normalized' (elements other than "
                              "m00 divided by m00) or '# mueller: absolute'", path, line)
        return None, None
    kline = header.line("mueller")
    if kind.strip().lower() not in MUELLER_KINDS:
        raise FormatError(f"mueller {kind!r} is not one of {', '.join(MUELLER_KINDS)}", path,
                          kline)
    if basis is not None and basis.strip().lower() not in MUELLER_BASES:
        raise FormatError(f"mueller_basis {basis!r} is not one of {', '.join(MUELLER_BASES)}",
                          path, header.line("mueller_basis"))
    other = [c for c in roles.channels if c not in MUELLER_ELEMENTS]
    if other or "m00" not in roles.channels:
        raise FormatError(f"'# mueller: {kind}' (line {kline}) needs a column m00 and only "
                          "Mueller element columns m00 ... m33 besides the angles"
                          + (f"; not elements: {other}" if other else "; m00 is missing"),
                          path, line)
    if roles.pol_col is not None:
        raise FormatError(f"'# mueller: {kind}' (line {kline}) and a polarization column "
                          "contradict each other: Mueller elements hold every incident "
                          "polarization at once", path, line)
    return kind.strip().lower(), (basis or "psps").strip().lower()


def _read_polarization(texts: list[str], linenos: list[int], cols: _Columns, pol_col: int,
                       unit: AngleUnit, path: Path) -> tuple[list[str], np.ndarray]:
    """Rows phase, ``polarization`` column: an angle in the file's unit, ``s``/``p``/
    ``unpolarized``, or empty (unpolarized). Returns the rows with that field replaced by 0
    (numeric for :func:`parse_rows`) and the angles (radians, NaN = unpolarized)."""
    ncol = len(cols.names)
    rows = [t.split(",") for t in texts]
    for r, t, ln_ in zip(rows, texts, linenos, strict=True):
        if len(r) != ncol:
            raise FormatError(f"wrong column count: expected {ncol} values "
                              f"({', '.join(cols.names)}), found {len(r)}: {t!r}", path, ln_)
    polarization = np.empty(len(rows))
    cache: dict[str, float] = {}
    for k, r in enumerate(rows):
        tok = r[pol_col].strip()
        if tok not in cache:
            try:
                cache[tok] = parse_number(tok) * unit.factor if tok else math.nan
            except ValueError:
                try:
                    cache[tok] = polarization_angle(tok)
                except ValueError:
                    raise FormatError(f"polarization {tok!r} is neither an angle nor s/p/"
                                      "unpolarized", path, linenos[k]) from None
            if math.isinf(cache[tok]):
                raise FormatError(f"polarization {tok!r} is not a finite angle", path,
                                  linenos[k])
        polarization[k] = cache[tok]
    return [",".join(r[:pol_col] + ["0"] + r[pol_col + 1:]) for r in rows], polarization


def _read_rows(lines: list[str], header: _Header, cols: _Columns, roles: _Roles,
               unit: AngleUnit, path: Path) -> dict[str, Any]:
    """Rows phase: the lines after the column names (``#`` lines skipped), one number per
    column, angles checked row by row. Returns the :class:`Measurement` arrays."""
    texts, linenos = data_lines(lines, header.col_line + 1, comments="#")
    if not texts:
        raise FormatError("no data rows after the column names", path, cols.line)
    polarization = None
    if roles.pol_col is not None:
        texts, polarization = _read_polarization(texts, linenos, cols, roles.pol_col, unit,
                                                 path)
    data = parse_rows(texts, linenos, len(cols.names), path, sep=",",
                      what=f"values ({', '.join(cols.names)})")
    ln = np.asarray(linenos)
    col = {a: data[:, j] for a, j in roles.angles.items()}
    angles = {
        "theta_i": check_zenith_rows(col["theta_i"] * unit.factor, "theta_i", ln, path,
                                     unit=unit.word),
        "theta_r": check_zenith_rows(col["theta_r"] * unit.factor, "theta_r", ln, path,
                                     unit=unit.word),
        "phi": azimuth_rows(col["phi"], "phi", ln, path) * unit.factor,
    }
    warn_implausible_angles(unit, path, [col["theta_i"], col["theta_r"]], [col["phi"]])
    return {
        **angles,
        "values": data[:, roles.channel_cols],
        "polarization": polarization,
        "uncertainty": (data[:, [roles.sigma_cols[c] for c in roles.channels]]
                        if roles.sigma_cols else None),
        "original": {k: data[:, j].copy() for k, j in roles.orig_cols.items()},
    }


def _meta(header: _Header, path: Path, unit: AngleUnit, has_original: bool) -> dict[str, Any]:
    """Provenance: every header keyword but ``angles``, ``quantity`` and the format tag (as
    strings), with ``sample``, ``instrument``, ``date`` always present."""
    keys = header.keys
    meta: dict[str, Any] = {k: v for k, v in keys.items()
                            if k not in ("angles", "quantity", "format_version", *_MUELLER_KEYS)}
    meta.update({
        "file": str(path),
        "file_abs": str(path.resolve()),
        "format": "csv",
        "sample": keys.get("sample"),
        "instrument": keys.get("instrument"),
        "date": keys.get("date"),
        "angle_units": unit.word,
        "format_version": keys.get("format_version"),
        "header": {header.spelled[k]: v for k, v in keys.items() if k in header.spelled},
    })
    if has_original:
        meta["original_units"] = keys.get("original_units", "as in the source file")
    return meta


def read(path: str | os.PathLike, *, angles: str | None = None, quantity: str | None = None,
         **options: Any) -> Measurement:
    """Read a roughbrdf CSV file (see the module docstring for the layout).

    Parameters
    ----------
    path : str or path-like
    angles : {"deg", "rad"}, optional
        The angle unit, supplying or overriding ``# angles:``.
    quantity : str, optional
        What the values hold, supplying or overriding ``# quantity:``.

    Raises
    ------
    FormatError
        For anything the file gets wrong, naming the file and line.
    """
    path, lines = begin_read("csv", path, options, quantity)
    header = _read_header(lines, path)
    cols = _read_column_names(lines, header, path)
    unit = _read_units(header, cols, angles, path)
    roles = _read_roles(cols, path)
    q = _read_quantity(header, roles, quantity, path, cols.line)
    kind, basis = _read_mueller(header, roles, path, cols.line)
    arrays = _read_rows(lines, header, cols, roles, unit, path)
    meta = _meta(header, path, unit, bool(arrays["original"]))
    return Measurement(channels=roles.channels, quantity=q, meta=meta, mueller=kind,
                       mueller_basis=basis, **arrays)


def _clean(text: Any) -> str:
    return " ".join(str(text).split())


def _header_from_csv(meta: dict[str, Any], unit: str, quantity: str) -> list[str]:
    """The header of a measurement read from a CSV file: its own keys, in order, with the unit
    and quantity declarations rewritten (and added where the file had none)."""
    head = []
    seen = set()
    for key, val in meta["header"].items():
        k = key.lower()
        if k in _MUELLER_KEYS:  # written from the measurement's attributes (_header)
            continue
        seen.add(k)
        if k in _UNIT_KEYS:
            val = unit
        elif k == "quantity":
            val = quantity
        elif k in _PROVENANCE and isinstance(meta.get(k), str):
            val = meta[k]
        head.append(f"# {key}: {_clean(val)}")
    if not seen & set(_UNIT_KEYS):
        head.insert(0, f"# angles: {unit}")
    if "quantity" not in seen:
        head.insert(1, f"# quantity: {quantity}")
    return head


def _header(m: Measurement, unit: str, orig_keys: list[str]) -> list[str]:
    """Every ``#`` line: the tag, the unit and quantity, the provenance, the source file's
    header (kept key for key from a CSV file, as JSON ``source_header`` from another
    format)."""
    meta = m.meta
    quantity = Quantity.parse(m.quantity).value
    from_csv = meta.get("format") == "csv" and isinstance(meta.get("header"), dict)
    head = [f"# {TAG} {VERSION}"]
    if from_csv:
        head += _header_from_csv(meta, unit, quantity)
    else:
        head += [f"# angles: {unit}", f"# quantity: {quantity}"]
        head += [f"# {k}: {_clean(meta[k])}" for k in _PROVENANCE if meta.get(k)]
    if m.mueller is not None:  # right after the quantity line (always written)
        at = next(i for i, line in enumerate(head) if line.lower().startswith("# quantity:")) + 1
        head[at:at] = [f"# mueller: {m.mueller}", f"# mueller_basis: {m.mueller_basis}"]
    present = {line[2:].partition(":")[0].strip().lower() for line in head}
    if meta.get("file") and "source_file" not in present:
        head.append(f"# source_file: {_clean(meta.get('source_file', meta['file']))}")
    if meta.get("format") and "source_format" not in present:
        head.append(f"# source_format: {_clean(meta.get('source_format', meta['format']))}")
    if orig_keys and meta.get("original_units") and "original_units" not in present:
        head.append(f"# original_units: {_clean(meta['original_units'])}")
    if not from_csv and isinstance(meta.get("header"), dict) and meta["header"]:
        head.append("# source_header: " + json.dumps({str(k): str(v) for k, v in
                                                      meta["header"].items()}))
    return head


def write(measurement: Measurement, path: str | os.PathLike, *, angles: str = "deg",
          original: bool = True, overwrite: bool = False) -> None:
    """Write a roughbrdf CSV file (layout in the module docstring).

    Parameters
    ----------
    measurement : Measurement
        Any quantity; ``# quantity:`` gets its plain name (``brdf``...).
    path : str or path-like
        Never the file the measurement was read from.
    angles : {"deg", "rad"}
        Unit of the angle and polarization columns, declared in ``# angles:``.
    original : bool
        Add the source file's one-dimensional numeric angle columns as ``orig_<name>``.
    overwrite : bool
        Replace an existing file (default: :class:`FileExistsError`).

    Notes
    -----
    A measurement read from a CSV file keeps every header key it had; one read from another
    format gets that file's header as JSON in ``# source_header:``. The file is written
    atomically (a temporary file renamed over ``path``).
    """
    target = prepare_target(measurement, path, overwrite)
    m = measurement
    unit = unit_word(angles)
    factor = 180.0 / math.pi if unit == "deg" else 1.0
    reserved = {*_ANGLES, "polarization"}
    for c in m.channels:
        if "," in c or c.strip() != c or not c or c.lower() in reserved or \
                c.startswith(("sigma_", "orig_")) or _SUFFIX.match(c.lower()):
            raise ValueError(f"channel label {c!r} cannot be a CSV column name")
        if m.mueller is None and _ELEMENT.match(c):  # the reader would ask for '# mueller:'
            raise ValueError(f"channel label {c!r} is a Mueller element name but the "
                             "measurement declares no Mueller data (mueller=None)")
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
            if a.ndim == 1 and np.issubdtype(a.dtype, np.number) and "," not in k and \
                    f"orig_{k}" not in names and k.strip() == k and k:
                orig_keys.append(k)
                names.append(f"orig_{k}")
                cols.append(a.astype(float))
    head = "\n".join(_header(m, unit, orig_keys)) + "\n" + ",".join(names) + "\n"
    write_table(target, head, np.column_stack(cols), delimiter=",", overwrite=overwrite)
