"""ALTA text data files (Belcour, Pacanowski et al., ``.dat`` / ``.alta``).

Layout::

    #SAMPLE "Gray tape"                 <- optional metadata (#SAMPLE, #ORIGIN, #URL ...)
    #DIM 3 1                            <- input dimension, output dimension (channels)
    #VS 0                               <- optional confidence interval kind (0, 1 or 2)
    #PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI
    #PARAM_OUT INV_STERADIAN            <- INV_STERADIAN (BRDF) or INV_STERADIAN_COSINE_FACTOR
    0.2618  0.0000  -0.2618  0.1293     <- x0 x1 x2 value [confidence]

Each row holds DIM[0] inputs, DIM[1] outputs and, per ``#VS``: nothing (0), a half-width per
output (1), or lower and upper bounds per output (2). The half-width (or half the bound
interval) becomes ``Measurement.uncertainty``.

Input parametrizations (ALTA's cartesian convention: light L at azimuth 0 in the x-z plane,
view V; ``Δφ = φ_v - φ_l``):

* ``ISOTROPIC_TL_TV_PROJ_DPHI``: ``x0 = theta_l``, ``x1 = theta_v cos Δφ``,
  ``x2 = theta_v sin Δφ``; so ``theta_v = hypot(x1, x2)``, ``Δφ = atan2(x2, x1)``.
* ``ISOTROPIC_TV_TL_DPHI``: ``(theta_v, theta_l, Δφ)``.
* ``SPHERICAL_TL_PL_TV_PV``: ``(theta_l, phi_l, theta_v, phi_v)``.
* ``RUSIN_TH_TD_PD``: Rusinkiewicz ``(theta_h, theta_d, phi_d)``, through
  :func:`roughbrdf.geometry.from_rusinkiewicz` (ALTA takes ``d`` from the view vector, MERL from
  the light; the two differ by ``phi_d -> phi_d + pi``, the same BRDF value by reciprocity).

ALTA's ``Δφ = 0`` is the **source** side (the retro direction is ``(θl, +θl, 0)``), the opposite
of this library's ``phi = 0``. The mapping is the rotation that puts the source at azimuth pi
(:func:`roughbrdf.geometry.angles_from_vectors`): ``phi = Δφ + pi`` wrapped into (-pi, pi], i.e.
``|phi| = pi - |Δφ|`` (the mirror image ``phi = pi - Δφ`` gives the same value on an isotropic
surface). Verified on ``retro-gray-tape.dat``: the retro peaks land at ``theta_r = theta_i``,
``phi = pi``. ``Measurement.original`` keeps ``x0, x1, x2`` (``x3`` for 4-D inputs) untouched.

Outputs: ``#PARAM_OUT INV_STERADIAN`` -> ``brdf``; ``INV_STERADIAN_COSINE_FACTOR`` ->
``brdf_cos`` (BRDF · cos theta_v). A missing or other ``PARAM_OUT`` is an error that asks for
``quantity=`` (CLI ``--quantity``); ``retro-gray-tape.dat`` is such a file (it holds
BRDF · cos theta_v). A ``quantity=`` that contradicts ``#PARAM_OUT`` is an error, and so is
``angles="deg"`` (ALTA angles are radians).

The keys this reader interprets (:data:`KEYS`) may appear once each: a second ``#PARAM_OUT``
(or ``#DIM``...) is an error naming both lines. Other ``#`` lines are comments. Every ``#`` line
is kept, as written, in ``meta["header_lines"]`` (and the keys in ``meta["header"]``);
:func:`write` writes them back when the measurement came from an ALTA file, with ``#DIM``,
``#VS``, ``#PARAM_IN``, ``#PARAM_OUT``, ``#CHANNELS`` and ``#SAMPLE_COUNT`` rewritten to
describe the rows written.
"""

from __future__ import annotations

import math
import os
import shlex
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..geometry import from_rusinkiewicz
from ..measurement import QUANTITIES, Measurement
from ..quantity import Quantity
from ._common import (
    HALF_PI,
    LAYOUT,
    ZENITH_SLACK,
    AngleUnit,
    FormatError,
    QuantityClaim,
    add_key,
    azimuth_rows,
    check_fixed_units,
    check_zenith_rows,
    common_frame_from_spherical,
    describe_keys,
    header_not_written,
    prepare_target,
    resolve_angle_unit,
    resolve_quantity,
    warn_implausible_angles,
    warn_not_written,
    write_table,
)
from ._rows import begin_read, parse_rows

__all__ = ["read", "write", "EXTENSIONS", "PARAM_IN", "KEYS", "header_field"]

EXTENSIONS = (".dat", ".alta")

#: supported input parametrizations and their dimension
PARAM_IN = {"ISOTROPIC_TL_TV_PROJ_DPHI": 3, "ISOTROPIC_TV_TL_DPHI": 3,
            "SPHERICAL_TL_PL_TV_PV": 4, "RUSIN_TH_TD_PD": 3}
#: #PARAM_OUT -> quantity
_PARAM_OUT = {"INV_STERADIAN": Quantity.BRDF,
              "INV_STERADIAN_COSINE_FACTOR": Quantity.BRDF_COS}
#: keys that describe the rows (rewritten by :func:`write`)
_LAYOUT_KEYS = ("DIM", "VS", "PARAM_IN", "PARAM_OUT", "CHANNELS", "SAMPLE_COUNT")
#: provenance keys -> the field of ``meta`` they feed
_FIELDS = {"SAMPLE": "sample", "ORIGIN": "instrument", "DATE": "date", "URL": "url"}
#: the keys this reader interprets: each may appear once
KEYS = (*_LAYOUT_KEYS, *_FIELDS)
#: the provenance fields :func:`write` writes for a measurement read from another format
WRITES = tuple(_FIELDS.values())
_MISSING_PARAM_OUT = ("no #PARAM_OUT line, so the unit of the values is unknown: say what they "
                      "hold with quantity= (CLI: --quantity): 'brdf' (INV_STERADIAN) or "
                      "'brdf_cos' (INV_STERADIAN_COSINE_FACTOR, BRDF x cos theta_v)")


@dataclass
class _Header:
    """The ``#KEY value`` lines (keys upper-cased) and the data rows between them."""

    keys: dict[str, str]
    lines: dict[str, int]
    #: data rows (stripped) and their 1-based line numbers
    texts: list[str]
    linenos: list[int]
    #: every ``#`` line as written (stripped), in order
    raw: list[str]

    def line(self, key: str) -> int | None:
        """1-based line of ``#key`` (None when absent)."""
        return self.lines.get(key)

    def first_word(self, key: str) -> str:
        """The first word of ``#key``'s value ("" when absent or empty)."""
        return self.keys.get(key, "").split()[0] if self.keys.get(key) else ""


@dataclass(frozen=True)
class _Layout:
    """What a row holds: ``nin`` inputs (``#PARAM_IN``), ``nout`` outputs, confidence ``vs``."""

    param_in: str
    nin: int
    nout: int
    vs: int

    @property
    def per_row(self) -> int:
        """Numbers per row."""
        return self.nin + self.nout * (1 + self.vs)


def _unquote(text: str) -> str:
    try:
        parts = shlex.split(text)
    except ValueError:
        return text.strip()
    return " ".join(parts)


# --------------------------------------------------------------------------------------------
# phases of read()
# --------------------------------------------------------------------------------------------
def header_field(key: str) -> str | None:
    """What an ALTA header key holds, for a writer of another format: :data:`LAYOUT` (``#DIM``,
    ``#PARAM_OUT``...: every writer writes its own), the provenance field of ``meta`` it feeds
    (``"sample"``...), or None (a comment)."""
    return LAYOUT if key in _LAYOUT_KEYS else _FIELDS.get(key)


def _read_header(lines: list[str], path: Path) -> _Header:
    """Header phase: every ``#KEY value`` line (anywhere in the file; a key of :data:`KEYS`
    given twice is an error naming both lines, other keys are comments) and, apart, every
    other non-blank line as a data row."""
    keys: dict[str, str] = {}
    key_lines: dict[str, int] = {}
    texts: list[str] = []
    linenos: list[int] = []
    raw_lines: list[str] = []
    for i, raw in enumerate(lines):
        s = raw.strip()
        if not s:
            continue
        if s.startswith("#"):
            raw_lines.append(s)
            key, *rest = s[1:].split(None, 1) or [""]
            key, val = key.upper(), rest[0].strip() if rest else ""
            if key in KEYS:
                add_key(keys, key_lines, key, val, i + 1, path, shown="#{key}")
            elif key and key not in keys:
                keys[key] = val
                key_lines[key] = i + 1
            continue
        texts.append(s)
        linenos.append(i + 1)
    return _Header(keys, key_lines, texts, linenos, raw_lines)


def _whole_number(header: _Header, key: str, path: Path) -> int:
    """``#key``'s value as a whole number >= 0 (else an error naming its line)."""
    text = header.keys[key]
    try:
        tok = text.split()[0]
        # int() would read '1_5' as 15 and full-width digits as digits: plain ASCII only
        n = int(tok) if tok.isascii() and "_" not in tok else -1
    except (ValueError, IndexError):
        n = -1
    if n < 0:
        raise FormatError(f"#{key} must be a whole number, got {text!r}", path,
                          header.line(key))
    return n


def _read_vs(header: _Header, path: Path) -> int:
    """``#VS``: the confidence-interval kind, 0 (none, also when absent), 1 or 2."""
    if "VS" not in header.keys:
        return 0
    try:
        vs = int(header.keys["VS"].split()[0])
    except (ValueError, IndexError):
        raise FormatError(f"#VS must be 0, 1 or 2, got {header.keys['VS']!r}", path,
                          header.line("VS")) from None
    if vs not in (0, 1, 2):
        raise FormatError(f"#VS must be 0, 1 or 2, got {vs}", path, header.line("VS"))
    return vs


def _read_layout(header: _Header, path: Path) -> _Layout:
    """Columns phase: ``#DIM nin nout`` (required), ``#PARAM_IN`` (required, one of
    :data:`PARAM_IN`, with ``nin`` inputs) and ``#VS``."""
    if "DIM" not in header.keys:
        raise FormatError("no #DIM line (e.g. '#DIM 3 1'); this does not look like an ALTA "
                          "data file", path, 1)
    try:
        nin, nout = (int(t) for t in header.keys["DIM"].split()[:2])
    except ValueError:
        raise FormatError(f"#DIM must hold two integers, got {header.keys['DIM']!r}", path,
                          header.line("DIM")) from None
    pin = header.first_word("PARAM_IN")
    if not pin:
        raise FormatError("no #PARAM_IN line: the angle parametrization is unknown "
                          f"(supported: {', '.join(PARAM_IN)})", path, header.line("DIM"))
    if pin not in PARAM_IN:
        raise FormatError(f"#PARAM_IN {pin} is not supported (supported: "
                          f"{', '.join(PARAM_IN)})", path, header.line("PARAM_IN"))
    if PARAM_IN[pin] != nin:
        raise FormatError(f"#PARAM_IN {pin} has {PARAM_IN[pin]} inputs but #DIM says {nin}",
                          path, header.line("DIM"))
    if nout < 1:
        raise FormatError(f"#DIM declares {nout} outputs", path, header.line("DIM"))
    return _Layout(pin, nin, nout, _read_vs(header, path))


def _read_quantity(header: _Header, quantity: str | None, path: Path) -> tuple[Quantity, str]:
    """Quantity phase: ``#PARAM_OUT`` (INV_STERADIAN -> brdf, INV_STERADIAN_COSINE_FACTOR ->
    brdf_cos) and the ``quantity=`` option, which must agree with it (brdf_cos and bridf agree);
    without a BRDF ``#PARAM_OUT`` the option is required. Returns the quantity and its source."""
    pout = header.first_word("PARAM_OUT")
    claims = []
    if pout:
        claims.append(QuantityClaim(
            _PARAM_OUT.get(pout), f"#PARAM_OUT {pout}", header.line("PARAM_OUT"),
            problem=f"#PARAM_OUT {pout} is not a BRDF unit (INV_STERADIAN or "
                    "INV_STERADIAN_COSINE_FACTOR); say what the values hold with quantity= "
                    f"(CLI: --quantity), one of {QUANTITIES}"))
    return resolve_quantity(quantity, claims, path, missing=_MISSING_PARAM_OUT)


def _read_rows(header: _Header, layout: _Layout, n_lines: int, path: Path
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Rows phase: ``nin`` inputs (finite), ``nout`` values and, per ``#VS``, a half-width (1)
    or lower and upper bounds (2) per value; a ``#SAMPLE_COUNT`` above the row count is a
    truncated file. Returns inputs, values and uncertainty (half-widths)."""
    if not header.texts:
        raise FormatError("no data rows after the header", path, n_lines + 1)
    nin, nout, vs = layout.nin, layout.nout, layout.vs
    data = parse_rows(header.texts, header.linenos, layout.per_row, path, sep=None,
                      what=f"values (#DIM {nin} {nout}, #VS {vs})")
    if "SAMPLE_COUNT" in header.keys:
        declared_n = _whole_number(header, "SAMPLE_COUNT", path)
        if declared_n > data.shape[0]:
            raise FormatError(f"truncated file: #SAMPLE_COUNT is {declared_n} but only "
                              f"{data.shape[0]} rows follow", path, n_lines + 1)
    x = data[:, :nin]
    for j in range(nin):
        azimuth_rows(x[:, j], f"x{j}", header.linenos, path)  # finite, else names the line
    uncertainty = None
    if vs == 1:
        uncertainty = np.abs(data[:, nin + nout:nin + 2 * nout])
    elif vs == 2:
        lo = data[:, nin + nout:nin + 3 * nout:2]
        hi = data[:, nin + nout + 1:nin + 3 * nout:2]
        uncertainty = 0.5 * np.abs(hi - lo)
    return x, data[:, nin:nin + nout], uncertainty


def _tl_tv_proj_dphi(x, ln, path, unit):
    """``(theta_l, theta_v cos dphi, theta_v sin dphi)``."""
    tl = check_zenith_rows(x[:, 0], "theta_l (x0)", ln, path, unit=unit)
    tv = check_zenith_rows(np.hypot(x[:, 1], x[:, 2]), "theta_v = hypot(x1, x2)", ln, path,
                           unit=unit)
    return common_frame_from_spherical(tl, np.zeros_like(tl), tv, np.arctan2(x[:, 2], x[:, 1]))


def _tv_tl_dphi(x, ln, path, unit):
    """``(theta_v, theta_l, dphi)``."""
    tv = check_zenith_rows(x[:, 0], "theta_v (x0)", ln, path, unit=unit)
    tl = check_zenith_rows(x[:, 1], "theta_l (x1)", ln, path, unit=unit)
    return common_frame_from_spherical(tl, x[:, 2], tv, np.zeros_like(tv))


def _tl_pl_tv_pv(x, ln, path, unit):
    """``(theta_l, phi_l, theta_v, phi_v)``."""
    tl = check_zenith_rows(x[:, 0], "theta_l (x0)", ln, path, unit=unit)
    tv = check_zenith_rows(x[:, 2], "theta_v (x2)", ln, path, unit=unit)
    return common_frame_from_spherical(tl, x[:, 1], tv, x[:, 3])


def _rusin_th_td_pd(x, ln, path, unit):
    """Rusinkiewicz ``(theta_h, theta_d, phi_d)``; a direction below the horizon is an error."""
    theta_i, theta_r, phi = from_rusinkiewicz(x[:, 0], x[:, 1], x[:, 2])
    below = ~np.isfinite(theta_i)
    if below.any():
        k = int(np.flatnonzero(below)[0])
        raise FormatError(f"(theta_h, theta_d, phi_d) = {tuple(x[k])} puts a direction below "
                          f"the horizon ({int(below.sum())} such rows)", path, int(ln[k]))
    return np.clip(theta_i, 0.0, HALF_PI), np.clip(theta_r, 0.0, HALF_PI), phi


#: #PARAM_IN -> (inputs, line numbers, path, unit) -> common-frame (theta_i, theta_r, phi)
_GEOMETRY = {"ISOTROPIC_TL_TV_PROJ_DPHI": _tl_tv_proj_dphi, "ISOTROPIC_TV_TL_DPHI": _tv_tl_dphi,
             "SPHERICAL_TL_PL_TV_PV": _tl_pl_tv_pv, "RUSIN_TH_TD_PD": _rusin_th_td_pd}


def _read_channels(header: _Header, nout: int, path: Path) -> list[str]:
    """Channel labels: ``#CHANNELS`` (written by roughbrdf, one label per output), else
    ``value`` for one output and ``c0, c1, ...`` for several."""
    if not header.keys.get("CHANNELS"):
        return ["value"] if nout == 1 else [f"c{j}" for j in range(nout)]
    labels = header.keys["CHANNELS"].split()
    if len(labels) != nout:
        raise FormatError(f"#CHANNELS lists {len(labels)} labels for {nout} outputs", path,
                          header.line("CHANNELS"))
    if len(set(labels)) != len(labels):
        raise FormatError(f"#CHANNELS names a channel twice: {labels}", path,
                          header.line("CHANNELS"))
    return labels


def _meta(header: _Header, path: Path, layout: _Layout, quantity_source: str,
          unit: AngleUnit) -> dict[str, Any]:
    """Provenance: ``#SAMPLE``, ``#ORIGIN`` (instrument), ``#DATE`` (quotes removed), ``#URL``,
    the parametrizations, the raw header."""
    keys = header.keys

    def unquoted(key: str) -> str | None:
        return _unquote(keys[key]) if keys.get(key) else None

    return {
        "file": str(path),
        "file_abs": str(path.resolve()),
        "format": "alta",
        "sample": unquoted("SAMPLE"),
        "instrument": unquoted("ORIGIN"),
        "date": unquoted("DATE"),
        "url": keys.get("URL"),
        "param_in": layout.param_in,
        "param_out": header.first_word("PARAM_OUT") or None,
        "quantity_source": quantity_source,
        "vs": layout.vs,
        "original_units": unit.word,
        "zenith_clip_tolerance": ZENITH_SLACK,
        "header": dict(keys),
        "header_lines": list(header.raw),
    }


def read(path: str | os.PathLike, *, quantity: str | None = None, angles: str | None = None,
         **options: Any) -> Measurement:
    """Read an ALTA text file into a :class:`~roughbrdf.measurement.Measurement`.

    Parameters
    ----------
    path : str or path-like
    quantity : str, optional
        What the values hold when the file has no ``#PARAM_OUT`` (or to state it explicitly;
        it must then agree with the file's declaration).
    angles : {"rad"}, optional
        ALTA angles are radians; ``"deg"`` contradicts the format (:class:`FormatError`).

    Raises
    ------
    FormatError
        For anything the file gets wrong, naming the file and, where one line is at fault, the
        line.
    """
    path, lines = begin_read("alta", path, options, quantity)
    check_fixed_units("ALTA", angles, None, path, ())
    header = _read_header(lines, path)
    layout = _read_layout(header, path)
    # ALTA has no unit declaration: its angles are radians
    unit = resolve_angle_unit(None, (), path, default="rad", default_source="ALTA (radians)")
    q, quantity_source = _read_quantity(header, quantity, path)
    x, values, uncertainty = _read_rows(header, layout, len(lines), path)
    theta_i, theta_r, phi = _GEOMETRY[layout.param_in](x, np.asarray(header.linenos), path,
                                                      unit.word)
    warn_implausible_angles(unit, path, (), list(x.T), fixed="ALTA angles are radians by "
                            "definition: check how the file was written")
    return Measurement(theta_i=theta_i, theta_r=theta_r, phi=phi, values=values,
                       channels=_read_channels(header, layout.nout, path), quantity=q,
                       uncertainty=uncertainty,
                       original={f"x{j}": x[:, j].copy() for j in range(layout.nin)},
                       meta=_meta(header, path, layout, quantity_source, unit))


def _channels_line(m: Measurement, had_it: bool) -> str | None:
    """``#CHANNELS`` value: written when there are several channels, a label other than
    ``value``, or the source file had one."""
    bad = [c for c in m.channels if not c or any(ch.isspace() for ch in c)]
    if bad:
        raise ValueError(f"channel labels {bad} cannot be ALTA #CHANNELS labels (no spaces)")
    if had_it or m.n_channels > 1 or m.channels != ["value"]:
        return " ".join(m.channels)
    return None


def _header_lines(m: Measurement, computed: dict[str, str]) -> list[str]:
    """The ``#`` lines to write. A measurement read from an ALTA file gets its own lines back,
    in order, with the keys of ``computed`` rewritten (``#SAMPLE_COUNT`` only where it was);
    any other measurement gets its provenance and ``computed``."""
    meta = m.meta
    raw = meta.get("header_lines") if meta.get("format") == "alta" else None
    out: list[str] = []
    if not isinstance(raw, list):
        for key, field in _FIELDS.items():
            val = meta.get(field)
            if val:
                out.append(f"#{key} {val}" if key == "URL" else f'#{key} "{val}"')
        raw = []
    else:
        if "SAMPLE_COUNT" not in (meta.get("header") or {}):
            computed = {k: v for k, v in computed.items() if k != "SAMPLE_COUNT"}
    done: set[str] = set()
    for line in map(str, raw):
        words = line[1:].split(None, 1)
        key = words[0].upper() if words else ""
        if key in computed:
            if key not in done:
                out.append(f"#{key} {computed[key]}")
                done.add(key)
            continue
        out.append(line)
    out += [f"#{k} {v}" for k, v in computed.items() if k not in done and k != "SAMPLE_COUNT"]
    return out


def write(measurement: Measurement, path: str | os.PathLike, *, overwrite: bool = False
          ) -> None:
    """Write an ALTA text file: ``#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI``, one output per channel.

    ``brdf`` -> ``#PARAM_OUT INV_STERADIAN``; ``brdf_cos``/``bridf`` ->
    ``INV_STERADIAN_COSINE_FACTOR``. A ``relative`` measurement has no ALTA unit and is refused
    (convert it, or write CSV). Uncertainties are written as ``#VS 1`` half-widths.
    Per-sample polarization cannot be stored in ALTA and is refused unless all unpolarized.

    Parameters
    ----------
    measurement : Measurement
    path : str or path-like
        Never the file the measurement was read from.
    overwrite : bool
        Replace an existing file (default: :class:`FileExistsError`).

    Notes
    -----
    A measurement read from an ALTA file keeps every ``#`` line it had
    (``meta["header_lines"]``). Header keys of another format that ALTA has no place for are
    named in one :class:`~roughbrdf.io.LossyWriteWarning`. The file is written atomically.
    """
    target = prepare_target(measurement, path, overwrite)
    m = measurement
    quantity = Quantity.parse(m.quantity)
    if not quantity.absolute:
        raise ValueError(f"ALTA files hold INV_STERADIAN or INV_STERADIAN_COSINE_FACTOR; a "
                         f"{quantity.value!r} measurement cannot be written (use CSV)")
    if m.polarization is not None and np.isfinite(m.polarization).any():
        raise ValueError("ALTA files cannot hold per-sample polarization; write CSV, or select "
                         "one polarization (Measurement.with_polarization) and drop it")
    # library frame -> ALTA: light at azimuth 0, so Δφ = phi - pi (the inverse rotation)
    dphi = m.phi - math.pi
    cols = [m.theta_i, m.theta_r * np.cos(dphi), m.theta_r * np.sin(dphi), m.values]
    if m.uncertainty is not None:
        cols.append(m.uncertainty)
    had_channels = m.meta.get("format") == "alta" and "CHANNELS" in (m.meta.get("header") or {})
    computed = {"DIM": f"3 {m.n_channels}", "VS": "1" if m.uncertainty is not None else "0",
                "PARAM_IN": "ISOTROPIC_TL_TV_PROJ_DPHI",
                "PARAM_OUT": ("INV_STERADIAN_COSINE_FACTOR" if quantity.cosine_weighted
                              else "INV_STERADIAN"),
                "CHANNELS": _channels_line(m, had_channels), "SAMPLE_COUNT": str(m.n_samples)}
    lines = _header_lines(m, {k: v for k, v in computed.items() if v is not None})
    lost = header_not_written(m.meta, "alta", WRITES)
    write_table(target, "\n".join(lines) + "\n", np.column_stack(cols), delimiter="  ",
                overwrite=overwrite)
    if lost:
        warn_not_written(target, "ALTA", [describe_keys(lost, str(m.meta.get("format")))])
