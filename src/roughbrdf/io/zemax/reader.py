"""Reading a Zemax tabular BSDF: the text into a :class:`~.format.ZemaxTable`
(:func:`read_table`), and the table into a :class:`~roughbrdf.measurement.Measurement`
(:func:`read`; :func:`kept_nodes` says which nodes become samples, for the writer's report too).

The text is read in phases - the header's words (comments and blank lines out), the counted
keywords and their angles, the checks of what roughbrdf can read, then the data blocks (one
``TIS`` line and one row per ScatterAzimuth per block) up to ``DataEnd`` - and every problem is
a :class:`~roughbrdf.io.FormatError` naming the file and the line. The format and its
conventions are described in :mod:`roughbrdf.io.zemax`.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...measurement import Measurement
from ...quantity import Quantity
from .._common import FormatError, unit_word
from .._rows import begin_read, parse_number, parse_rows
from .format import (
    COUNTED,
    GRID_TOL,
    HORIZON_EPS,
    SYMMETRIES,
    ZemaxGrid,
    ZemaxTable,
    normalize_symmetry,
)

__all__ = ["read", "read_table", "kept_nodes"]

_WORD_KEYS = ("Source", "Symmetry", "SpectralContent", "ScatterType")


# --------------------------------------------------------------------------------------------
# reading the text
# --------------------------------------------------------------------------------------------
@dataclass
class _Tokens:
    """The header's words with their 1-based line numbers (comments and blank lines out)."""

    words: list[str]
    lines: list[int]
    #: index (0-based) in the file's lines of the DataBegin line
    data_begin: int


def _header_tokens(lines: list[str], path: Path) -> tuple[_Tokens, list[str]]:
    """Split the lines before ``DataBegin`` into words; collect the comments of the file."""
    words: list[str] = []
    nums: list[int] = []
    comments = [s.strip()[1:].strip() for s in lines if s.strip().startswith("#")]
    for i, raw in enumerate(lines):
        s = raw.strip()
        if not s or s.startswith("#"):
            continue
        if s.split()[0].lower() == "databegin":
            return _Tokens(words, nums, i), comments
        for w in s.split():
            words.append(w)
            nums.append(i + 1)
    raise FormatError("no DataBegin line: this is not a Zemax tabular BSDF file (expected "
                      "the header keywords, 'Monochrome', then 'DataBegin')", path,
                      len(lines) + 1 if lines else None)


def _keyword(word: str) -> str | None:
    """The canonical header keyword for ``word`` (any capitalization), else None."""
    for k in (*_WORD_KEYS, *COUNTED, "Monochrome"):
        if word.lower() == k.lower():
            return k
    return None


def _read_counted(tok: _Tokens, k: int, key: str, path: Path) -> tuple[list[float], int]:
    """The angles after a counted keyword at word ``k``: its count, then that many numbers."""
    line = tok.lines[k]
    if k + 1 >= len(tok.words):
        raise FormatError(f"{key} has no count (expected '{key} N' and N angles)", path, line)
    try:
        count = parse_number(tok.words[k + 1])
    except ValueError:
        count = math.nan
    if not (math.isfinite(count) and count >= 1 and count.is_integer()):
        raise FormatError(f"{key} count must be a whole number >= 1, got "
                          f"{tok.words[k + 1]!r}", path, tok.lines[k + 1])
    n = int(count)
    vals: list[float] = []
    j = k + 2
    while j < len(tok.words) and _keyword(tok.words[j]) is None:
        try:
            vals.append(parse_number(tok.words[j]))
        except ValueError:
            raise FormatError(f"non-numeric angle {tok.words[j]!r} after {key} (line "
                              f"{line})", path, tok.lines[j]) from None
        j += 1
    if len(vals) != n:
        where = f"line {tok.lines[j - 1]}" if vals else "none"
        raise FormatError(f"{key} {n} (line {line}) is followed by {len(vals)} angles "
                          f"({where}); the count and the angles must agree", path,
                          tok.lines[j - 1] if vals else line)
    return vals, j


def _parse_header(tok: _Tokens, path: Path) -> tuple[dict[str, str], dict[str, list[float]],
                                                     dict[str, int]]:
    """Header phase: the word keywords, the counted keywords' angles, and their lines."""
    words: dict[str, str] = {}
    angles: dict[str, list[float]] = {}
    where: dict[str, int] = {}
    k = 0
    while k < len(tok.words):
        key = _keyword(tok.words[k])
        line = tok.lines[k]
        if key is None:
            raise FormatError(f"unexpected {tok.words[k]!r} in the header (known keywords: "
                              f"{', '.join((*_WORD_KEYS, *COUNTED))}, then 'Monochrome' and "
                              "'DataBegin')", path, line)
        if key in where:
            raise FormatError(f"{key} is given twice: line {where[key]} and line {line}; keep "
                              "one", path, line)
        where[key] = line
        if key in COUNTED:
            angles[key], k = _read_counted(tok, k, key, path)
        elif key == "Monochrome":
            k += 1
        else:
            if k + 1 >= len(tok.words) or tok.lines[k + 1] != line:
                raise FormatError(f"{key} has no value", path, line)
            words[key] = tok.words[k + 1]
            k += 2
    return words, angles, where


def _check_header(words: dict[str, str], angles: dict[str, list[float]],
                  where: dict[str, int], path: Path) -> ZemaxGrid:
    """Header phase, checks: the keywords the reader needs and what it can read."""
    for key in ("Symmetry", "SpectralContent", "ScatterType", *COUNTED):
        if key not in where:
            raise FormatError(f"no {key} line in the header", path)
    sym = normalize_symmetry(words["Symmetry"])
    if sym is None:
        raise FormatError(f"Symmetry {words['Symmetry']!r} is not one of "
                          f"{', '.join(SYMMETRIES)}", path, where["Symmetry"])
    if words["SpectralContent"].lower() != "monochrome":
        raise FormatError(f"SpectralContent {words['SpectralContent']} is not supported: "
                          "roughbrdf reads Monochrome files (one channel)", path,
                          where["SpectralContent"])
    if words["ScatterType"].upper() != "BRDF":
        raise FormatError(f"ScatterType {words['ScatterType']} is not supported: roughbrdf "
                          "reads reflection (BRDF) files", path, where["ScatterType"])
    if "Monochrome" not in where:
        raise FormatError("no 'Monochrome' line before DataBegin (the spectral content "
                          "indicator)", path)
    kw = {COUNTED[k]: tuple(v) for k, v in angles.items()}
    try:
        return ZemaxGrid(symmetry=sym, **kw)
    except ValueError as exc:
        msg = str(exc).removeprefix("not a Zemax grid: ")
        line = next((where[k] for k in COUNTED if msg.startswith(k)), None)
        raise FormatError(msg, path, line) from None


def _data_blocks(lines: list[str], start: int, grid: ZemaxGrid, path: Path
                 ) -> tuple[list[str], list[int], list[tuple[str, int]]]:
    """Rows phase: the value rows and the TIS lines of every block, up to ``DataEnd``."""
    n_rot, n_aoi, n_az, _ = grid.shape
    n_blocks = n_rot * n_aoi
    rows: list[str] = []
    row_lines: list[int] = []
    tis: list[tuple[str, int]] = []
    i = start + 1
    while len(tis) < n_blocks or len(rows) < n_blocks * n_az:
        while i < len(lines) and (not lines[i].strip() or lines[i].strip().startswith("#")):
            i += 1
        block = len(tis)
        if i >= len(lines):
            raise FormatError(f"the file ends inside the data, without DataEnd: {block} of "
                              f"{n_blocks} blocks (SampleRotation x AngleOfIncidence) begun",
                              path, len(lines) + 1)
        s = lines[i].strip()
        first = s.split()[0]
        if first.lower() == "dataend":
            raise FormatError(f"DataEnd after {len(rows)} value rows of {n_blocks * n_az} "
                              f"({n_blocks} blocks of {n_az} ScatterAzimuth rows)", path, i + 1)
        if len(rows) == block * n_az:  # a block begins: its TIS line
            if first.upper() != "TIS":
                raise FormatError(f"expected 'TIS <value>' to begin block {block + 1} of "
                                  f"{n_blocks}, found {s[:40]!r}", path, i + 1)
            tis.append((s, i + 1))
        elif first.upper() == "TIS":
            raise FormatError(f"TIS after {len(rows) - (block - 1) * n_az} of {n_az} "
                              f"ScatterAzimuth rows of block {block}", path, i + 1)
        else:
            rows.append(s)
            row_lines.append(i + 1)
        i += 1
    _data_end(lines, i, path)
    return rows, row_lines, tis


def _data_end(lines: list[str], i: int, path: Path) -> None:
    """The DataEnd line after the last block, and nothing but comments after it."""
    while i < len(lines) and (not lines[i].strip() or lines[i].strip().startswith("#")):
        i += 1
    if i >= len(lines):
        raise FormatError("no DataEnd after the last block (the file may be cut short)",
                          path, len(lines) + 1)
    if lines[i].strip().lower() != "dataend":
        raise FormatError(f"expected DataEnd after the last block, found "
                          f"{lines[i].strip()[:40]!r} (more data than SampleRotation x "
                          "AngleOfIncidence blocks)", path, i + 1)
    for j in range(i + 1, len(lines)):
        if lines[j].strip() and not lines[j].strip().startswith("#"):
            raise FormatError(f"text after DataEnd: {lines[j].strip()[:40]!r}", path, j + 1)


def _tis_values(tis: list[tuple[str, int]], path: Path) -> np.ndarray:
    """The number on each ``TIS`` line."""
    out = []
    for s, ln in tis:
        parts = s.split()
        try:
            if len(parts) != 2:
                raise ValueError
            out.append(parse_number(parts[1]))
        except ValueError:
            raise FormatError(f"a TIS line holds 'TIS' and one number, got {s[:40]!r}", path,
                              ln) from None
    return np.asarray(out)


def read_table(path: str | os.PathLike) -> ZemaxTable:
    """The whole file as a :class:`ZemaxTable` (grid, values, TIS, header, comments).

    Raises :class:`~roughbrdf.io.FormatError` naming the file and line for anything the file
    gets wrong (counts, missing keywords or DataEnd, a row with the wrong number of values, a
    non-numeric value...).
    """
    p, lines = begin_read("zemax", path, {})
    tok, comments = _header_tokens(lines, p)
    words, angles, where = _parse_header(tok, p)
    grid = _check_header(words, angles, where, p)
    rows, row_lines, tis = _data_blocks(lines, tok.data_begin, grid, p)
    n_rad = grid.shape[3]
    data = parse_rows(rows, row_lines, n_rad, p,
                      what=f"values (one per ScatterRadial angle, line {where['ScatterRadial']})")
    return ZemaxTable(grid, data.reshape(grid.shape), _tis_values(tis, p).reshape(grid.shape[:2]),
                      {k: v for k, v in words.items()}, comments)


# --------------------------------------------------------------------------------------------
# read: the table as a Measurement
# --------------------------------------------------------------------------------------------
def _select_rotation(table: ZemaxTable, sample_rotation: Any, path: Path) -> np.ndarray:
    """Indices of the rotations to read (the ``sample_rotation=`` option)."""
    rots = np.asarray(table.grid.rotation_deg)
    if isinstance(sample_rotation, str):
        if sample_rotation != "all":
            raise ValueError(f"sample_rotation must be an angle (radians) or 'all', got "
                             f"{sample_rotation!r}")
        return np.arange(rots.size)
    if sample_rotation is None:
        if rots.size > 1:
            raise FormatError(f"the file has {rots.size} sample rotations "
                              f"({', '.join(f'{r:g}' for r in rots)} deg; an anisotropic "
                              "sample) and roughbrdf's models are isotropic: pass "
                              "sample_rotation=<one of them, radians> or sample_rotation='all'",
                              path)
        return np.arange(1)
    k = np.flatnonzero(np.abs(rots - math.degrees(float(sample_rotation))) <= GRID_TOL)
    if k.size == 0:
        raise ValueError(f"sample_rotation = {float(sample_rotation)!r} rad "
                         f"({math.degrees(float(sample_rotation)):g} deg) is not in the file's "
                         f"SampleRotation list ({', '.join(f'{r:g}' for r in rots)} deg)")
    return k


def kept_nodes(table: ZemaxTable, rot_idx: np.ndarray
               ) -> tuple[np.ndarray, dict[str, int], list[str]]:
    """The nodes of ``table`` that :func:`read` makes samples, for the rotations ``rot_idx``.

    A node is kept when it is above the horizon (``cos theta_r >= -HORIZON_EPS``) and does
    not repeat, with the same value, the direction of an earlier node (radial 0 at every
    azimuth; azimuth 360 = azimuth 0).

    Parameters
    ----------
    table : ZemaxTable
    rot_idx : numpy.ndarray of int
        Indices of the sample rotations read.

    Returns
    -------
    keep : numpy.ndarray of int
        Flat indices (into ``table.grid.shape``) of the kept nodes, in order.
    counts : dict of str -> int
        ``zemax_below_horizon``, ``zemax_below_horizon_nonzero``, ``zemax_duplicates`` (the
        ``meta`` keys of :func:`read`).
    notes : list of str
        The ``meta["quirks"]`` lines (nodes repeating a direction with another value).
    """
    grid = table.grid
    n_rot, n_aoi, n_az, n_rad = grid.shape
    _, _, _, cz = grid.directions()
    above = np.broadcast_to(cz >= -HORIZON_EPS, grid.shape)
    vals = table.values
    rep = grid.representatives()
    flat_vals = vals.reshape(n_rot, n_aoi, n_az * n_rad)
    # a node repeating an earlier node's direction with the same value is kept once; one
    # with another value is kept too (noted)
    same = flat_vals == flat_vals[..., rep]
    dup = (rep != np.arange(rep.size))[None, None, :] & same
    differing = int(((rep != np.arange(rep.size))[None, None, :] & ~same)[rot_idx].sum())
    keep = above.reshape(n_rot, n_aoi, -1) & ~dup
    sel = np.zeros(n_rot, dtype=bool)
    sel[rot_idx] = True
    keep &= sel[:, None, None]
    below = ~above.reshape(n_rot, n_aoi, -1) & sel[:, None, None]
    counts = {"zemax_below_horizon": int(below.sum()),
              "zemax_below_horizon_nonzero": int((below & (flat_vals != 0)).sum()),
              "zemax_duplicates": int((dup & above.reshape(n_rot, n_aoi, -1)
                                       & sel[:, None, None]).sum())}
    notes = []
    if differing:
        notes.append(f"{differing} nodes repeat the direction of an earlier node (radial 0 at "
                     "every azimuth, or azimuth 360) with another value: all are kept")
    return np.flatnonzero(keep.ravel()), counts, notes


def read(path: str | os.PathLike, *, sample_rotation: Any = None, quantity: Any = None,
         angles: str | None = None, **options: Any) -> Measurement:
    """Read a Zemax tabular BSDF into a :class:`~roughbrdf.measurement.Measurement`.

    Parameters
    ----------
    path : str or path-like
    sample_rotation : float or "all", optional
        Which SampleRotation to read (radians) when the file has several; ``"all"`` reads
        every one (``original["sample_rotation"]``).
    quantity, angles : str, optional
        Accepted for symmetry with the other readers: the format holds BRDF at angles in
        degrees, so only ``"brdf"`` and ``"deg"`` agree with it.

    Returns
    -------
    Measurement
        One channel (``"value"``), quantity ``brdf``; conventions and ``meta`` keys in
        :mod:`roughbrdf.io.zemax`.

    Examples
    --------
    >>> import roughbrdf as rb, tempfile, pathlib
    >>> from roughbrdf.export.zemax import to_zemax
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "white.bsdf"
    >>> _ = to_zemax(rb.model("lambertian", rho=0.5), out)
    >>> m = read(out)
    >>> m.channels, str(m.quantity), m.meta["format"]
    (['value'], 'brdf', 'zemax')
    """
    if options:
        raise TypeError(f"zemax.read got unknown options {sorted(options)}")
    p = Path(path)
    if angles is not None and unit_word(angles, p) != "deg":
        raise FormatError(f"angles={angles!r} contradicts the Zemax format, whose angles are "
                          "degrees by definition", p)
    if quantity is not None and Quantity.parse(quantity, "quantity") != Quantity.BRDF:
        raise FormatError(f"quantity={quantity!r} contradicts the file's ScatterType BRDF "
                          "(values in sr^-1)", p)
    table = read_table(p)
    rot_idx = _select_rotation(table, sample_rotation, p)
    keep, counts, notes = kept_nodes(table, rot_idx)
    return _measurement(table, keep, counts, notes, p)


def _measurement(table: ZemaxTable, keep: np.ndarray, counts: dict[str, int],
                 notes: list[str], path: Path) -> Measurement:
    """The kept nodes as samples, with the file's angles in ``original`` and its grid, TIS,
    header and comments in ``meta``."""
    grid = table.grid
    ti, tr, ph, _ = grid.directions()
    n_rot = grid.shape[0]
    idx = np.unravel_index(keep, grid.shape)
    block = np.ravel_multi_index(idx[1:], grid.shape[1:])
    rots, aois = np.asarray(grid.rotation_deg), np.asarray(grid.aoi_deg)
    az, rad = np.asarray(grid.azimuth_deg), np.asarray(grid.radial_deg)
    original = {"sample_rotation": rots[idx[0]], "angle_of_incidence": aois[idx[1]],
                "scatter_azimuth": az[idx[2]], "scatter_radial": rad[idx[3]],
                "zemax_index": keep.astype(np.int64)}
    meta: dict[str, Any] = {
        "file": str(path), "file_abs": str(path.resolve()), "format": "zemax",
        "sample": path.stem, "instrument": None, "date": None,
        "header": dict(table.header), "comments": list(table.comments),
        "zemax_grid": grid.as_meta(), "zemax_tis": table.tis.tolist(),
        "zemax_sample_rotations_read": sorted({float(r) for r in rots[idx[0]]}) if n_rot else [],
        **counts, "angle_units": "deg", "original_units":
            "deg (SampleRotation, AngleOfIncidence, ScatterAzimuth, ScatterRadial); "
            "zemax_index: flat index of the node in the file's table", "quirks": notes}
    return Measurement(theta_i=ti.ravel()[block],
                       theta_r=np.minimum(tr.ravel()[block], 0.5 * math.pi),
                       phi=ph.ravel()[block], values=table.values.ravel()[keep],
                       channels=["value"], quantity=Quantity.BRDF, original=original, meta=meta)
