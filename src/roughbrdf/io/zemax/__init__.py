"""Zemax OpticStudio tabular BSDF files (``.bsdf``; Radiant Imaging's "BSDF Data Interchange"
format, read by OpticStudio's BSDF scatter model).

Layout (``#`` lines are comments, anywhere)::

    Source  Measured
    Symmetry  PlaneSymmetrical        <- or Asymmetrical / Asymmetrical4D
    SpectralContent  Monochrome
    ScatterType  BRDF
    SampleRotation  1                 <- each keyword with its count N, then N angles (degrees)
    0
    AngleOfIncidence  4
    15  30  50  70
    ScatterAzimuth  19
    0  10  20  ...  180
    ScatterRadial  12
    0  5  10  15  20  30  40  50  60  70  80  90

    Monochrome
    DataBegin
    TIS  0.1345                       <- one block per sample rotation, then per incidence:
    6.375E-02  6.180E-02  ...         <- one row per ScatterAzimuth, one value per ScatterRadial
    ...
    DataEnd

Sources: Zemax knowledge base, "Zemax Tabular BSDF data file format" (R. Rykowski, reviewed by
S. Auriol; https://support.zemax.com/hc/en-us/articles/1500005486801) and its 2008 original
"BSDF Data Interchange File Format Specification"
(http://www.zemax.com/kb/articles/229/1/BSDF-Data-Interchange-File-Format-Specification);
"How to use tabular BSDF data to define the surface scattering distribution"
(https://support.zemax.com/hc/en-us/articles/1500005576362).

Conventions (each pinned by a test in ``tests/test_io_zemax.py``):

* **AngleOfIncidence** is, in Zemax's words, "a misnomer: this angle actually represents the
  specular reflected or transmitted angle". For a BRDF the specular angle equals the angle of
  incidence, so ``theta_i = AngleOfIncidence``.
* **ScatterRadial** is the angle between the scattered direction and the specular direction
  ("Radial 0 deg is defined at the angle of specular reflection, with increasing Radial angles
  extending outward") - a true angle on the sphere, not the projected distance
  ``|beta - beta0|`` of direction cosines that OpticStudio's ABg model uses. It runs past 90 deg
  (up to ``90 + AngleOfIncidence`` toward the normal); directions beyond the horizon hold no
  BRDF.
* **ScatterAzimuth** is measured about the specular direction: "Azimuth 0 deg is defined by
  pointing from the angle of specular reflection towards the axis normal to the sample, with
  Azimuth angles increasing in a counter-clockwise fashion" (seen from above the sample).
  In the library's frame (specular direction ``s = (sin t, 0, cos t)``, source on -x) the
  scattered direction at radial ``r``, azimuth ``a`` is::

      w = cos r s + sin r (cos a u0 + sin a v),  u0 = (-cos t, 0, sin t),  v = s x u0 = (0, -1, 0)

  (:func:`specular_to_common`; at normal incidence azimuth 0 points to the source side,
  ``phi = pi``, the limit of ``u0``). This is also the specular coordinate system of libbsdf
  (K. Ryo, ``SpecularCoordinateSystem``, MPL-2.0, which reads these files), and it is what public
  measured files obey: in the University of Arizona LOFT group's files (MIT licence;
  ``tests/data/zemax``) every non-zero value maps to ``theta_r <= 80`` deg and every zero to
  ``theta_r > 80`` deg (their cut-off) only with this convention; with the azimuth origin
  reversed, non-zero values would fall below the horizon.
* **Symmetry** ``PlaneSymmetrical``: the data are symmetric about the plane of incidence, so
  only azimuths 0-180 deg are given (the other half is their mirror image; this reader returns
  the samples of the file, ``phi <= 0`` by the handedness above, and isotropic models do not
  depend on the sign of ``phi``); ``Asymmetrical``/``Asymmetrical4D``: azimuths 0-360 deg.
* **SampleRotation** turns the sample about its normal (anisotropic samples). The library's
  models are isotropic and its frame has no sample rotation: a file with one rotation (any
  value) is read as it is (the value is kept in ``meta`` and ``original``); a file with several
  needs ``sample_rotation=`` (one of them, radians) or ``sample_rotation="all"`` (every sample,
  ``original["sample_rotation"]`` tells them apart).
* **TIS** is the total integrated scatter at that incidence, the directional-hemispherical
  reflectance of the scattered light ``int f cos(theta_r) d omega``
  (:func:`roughbrdf.albedo`). The reader keeps the file's values (``meta["zemax_tis"]``,
  shape ``(rotations, incidences)``) without using them; :func:`table_integral` computes the
  table's own integral. (Zemax's example BrownVinyl, TIS 0.1345 at 15 deg, is close to the
  cosine-weighted integral of its table, 0.129 - its radial angles stop at 80 deg - and far
  from ``int f d omega``, 0.215; some public files compute TIS otherwise.)
* Values are the BRDF in sr⁻¹ (``ScatterType BRDF``; BTDF and XYZ/tristimulus files are
  refused).

Reading: each (rotation, incidence, azimuth, radial) node is a sample; nodes below the horizon
are not BRDF geometries and are left out (counted in ``meta["zemax_below_horizon"]``, with
``meta["zemax_below_horizon_nonzero"]`` of them holding a non-zero value); nodes that are the
same direction as an earlier node (radial 0 at every azimuth: the specular direction; azimuth
360 = azimuth 0) are kept once when they hold the same value (``meta["zemax_duplicates"]``).
The file's angles (degrees) are kept in ``original`` with each node's flat index
(``zemax_index``), and the grid and TIS values in ``meta``, so that :func:`write` puts every
sample back where it was: reading and writing a ``.bsdf`` is exact.

Writing a measurement that is not on a Zemax grid (or lacks part of one) would bin, average
or fill samples: :func:`write` refuses it unless ``resample=True`` and then returns a
:class:`ZemaxWriteReport` of what it did (the rule of :mod:`roughbrdf.io.merl`). Models and
fits are written by :func:`roughbrdf.export.zemax.to_zemax`.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import ArgumentError
from ...measurement import Measurement
from ...output import staged
from ...quantity import Quantity
from .._common import (
    LAYOUT,
    FormatError,
    describe_keys,
    header_not_written,
    prepare_target,
    unit_word,
    warn_not_written,
)
from .._rows import begin_read, parse_number, parse_rows

__all__ = ["read", "write", "read_table", "write_table", "table_integral", "plan",
           "specular_to_common", "common_to_specular", "grid_from_radians",
           "default_measurement_grid", "ZemaxGrid", "ZemaxTable", "ZemaxWriteReport",
           "EXTENSIONS", "SYMMETRIES"]

EXTENSIONS = (".bsdf",)
#: the Symmetry keyword's values (read case-insensitively; ``ASymmetrical4D`` also occurs)
SYMMETRIES = ("PlaneSymmetrical", "Asymmetrical", "Asymmetrical4D")
#: the counted header keywords, in the file's order, and their ZemaxGrid field
COUNTED = {"SampleRotation": "rotation_deg", "AngleOfIncidence": "aoi_deg",
           "ScatterAzimuth": "azimuth_deg", "ScatterRadial": "radial_deg"}
_WORD_KEYS = ("Source", "Symmetry", "SpectralContent", "ScatterType")
#: a direction is above the horizon when cos(theta_r) exceeds this; nodes within it of 0 are
#: at the horizon (theta_r = 90 deg exactly: rounding of the node's angles, not a direction
#: below the surface)
HORIZON_EPS = 1e-12
#: two angles of a grid (degrees) closer than this are the same node
GRID_TOL = 1e-6
#: written by :func:`write` and ``to_zemax`` in ``#`` comment lines
WRITES = ("sample", "instrument", "date")


# --------------------------------------------------------------------------------------------
# geometry: specular-centred (radial, azimuth) <-> the library's frame
# --------------------------------------------------------------------------------------------
def specular_to_common(theta_s: Any, radial: Any, azimuth: Any
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Library-frame ``(theta_r, phi, cos_theta_r)`` of the direction at ``radial`` from the
    specular direction ``theta_s`` (Zemax's AngleOfIncidence), at ``azimuth`` about it
    (radians; conventions in the module docstring). ``theta_r > pi/2`` (``cos_theta_r < 0``)
    is below the horizon.

    Examples
    --------
    >>> import math
    >>> t, p, c = specular_to_common(math.radians(30), 0.0, 1.0)   # radial 0: the specular
    >>> round(math.degrees(float(t)), 9), float(p)
    (30.0, 0.0)
    >>> t, p, c = specular_to_common(math.radians(30), math.radians(30), 0.0)  # toward normal
    >>> round(math.degrees(float(t)), 9)
    0.0
    >>> t, p, c = specular_to_common(math.radians(30), math.radians(10), math.pi)  # outward
    >>> round(math.degrees(float(t)), 9), round(float(p), 12)
    (40.0, 0.0)
    """
    st, ct = np.sin(theta_s), np.cos(theta_s)
    sr, cr = np.sin(radial), np.cos(radial)
    sa, ca = np.sin(azimuth), np.cos(azimuth)
    wx = cr * st - sr * ca * ct
    wy = -sr * sa
    wz = cr * ct + sr * ca * st
    # atan2 keeps full accuracy near the specular direction and the pole (arccos would not)
    theta_r = np.arctan2(np.hypot(wx, wy), wz)
    return theta_r, np.arctan2(wy, wx), wz


def common_to_specular(theta_i: Any, theta_r: Any, phi: Any) -> tuple[np.ndarray, np.ndarray]:
    """Zemax ``(radial, azimuth)`` of library-frame directions (radians; azimuth in
    ``[0, 2 pi)``), the inverse of :func:`specular_to_common` (the specular angle is
    ``theta_i``).

    Examples
    --------
    >>> import math
    >>> r, a = common_to_specular(math.radians(30), math.radians(30), 0.0)
    >>> round(float(r), 12)
    0.0
    >>> r, a = common_to_specular(math.radians(30), 0.0, 0.0)
    >>> round(math.degrees(float(r)), 9), round(math.degrees(float(a)), 9)
    (30.0, 0.0)
    """
    st, ct = np.sin(theta_i), np.cos(theta_i)
    sr = np.sin(theta_r)
    wx, wy, wz = sr * np.cos(phi), sr * np.sin(phi), np.cos(theta_r)
    w_s = wx * st + wz * ct      # along the specular direction s
    w_u = -wx * ct + wz * st     # along u0 (toward the normal)
    w_v = -wy                    # along v = s x u0
    radial = np.arctan2(np.hypot(w_u, w_v), w_s)
    return radial, np.mod(np.arctan2(w_v, w_u), 2 * math.pi)


# --------------------------------------------------------------------------------------------
# the grid
# --------------------------------------------------------------------------------------------
def _normalize_symmetry(text: str) -> str | None:
    """``PlaneSymmetrical``/``Asymmetrical``/``Asymmetrical4D`` for any capitalization."""
    for name in SYMMETRIES:
        if text.strip().lower() == name.lower():
            return name
    return None


def _check_axis(name: str, values: np.ndarray, low: float, high: float) -> str | None:
    """What is wrong with one axis of a grid (degrees), or None."""
    if values.size == 0:
        return f"{name} lists no angles"
    if not np.isfinite(values).all():
        return f"{name} has a non-finite angle"
    if values.min() < low - GRID_TOL or values.max() > high + GRID_TOL:
        return (f"{name} angles must lie in [{low:g}, {high:g}] deg, got "
                f"[{values.min():g}, {values.max():g}]")
    if values.size > 1 and not (np.diff(values) > 0).all():
        return f"{name} angles must increase strictly (each once), got {values.tolist()}"
    return None


@dataclass(frozen=True)
class ZemaxGrid:
    """The angles of a tabular BSDF, in **degrees** (the file's unit).

    Attributes
    ----------
    aoi_deg, azimuth_deg, radial_deg, rotation_deg : tuple of float
        AngleOfIncidence (= theta_i), ScatterAzimuth, ScatterRadial and SampleRotation.
    symmetry : str
        ``PlaneSymmetrical`` (azimuths in [0, 180]) or ``Asymmetrical``/``Asymmetrical4D``
        (azimuths in [0, 360]).

    Examples
    --------
    >>> g = ZemaxGrid((0, 30), (0, 90, 180), (0, 10, 20))
    >>> g.shape
    (1, 2, 3, 3)
    """

    aoi_deg: tuple[float, ...]
    azimuth_deg: tuple[float, ...]
    radial_deg: tuple[float, ...]
    rotation_deg: tuple[float, ...] = (0.0,)
    symmetry: str = "PlaneSymmetrical"

    def __post_init__(self) -> None:
        for name in ("aoi_deg", "azimuth_deg", "radial_deg", "rotation_deg"):
            object.__setattr__(self, name, tuple(float(v) for v in np.ravel(getattr(self,
                                                                                 name))))
        sym = _normalize_symmetry(str(self.symmetry))
        if sym is None:
            raise ArgumentError("symmetry", f"must be one of {', '.join(SYMMETRIES)}",
                                value=self.symmetry)
        object.__setattr__(self, "symmetry", sym)
        problem = self.problem()
        if problem:
            raise ValueError(f"not a Zemax grid: {problem}")

    def problem(self) -> str | None:
        """What makes these angles unusable as a grid (None when they are fine)."""
        top = 180.0 if self.symmetry == "PlaneSymmetrical" else 360.0
        for name, vals, low, high in (
                ("AngleOfIncidence", self.aoi_deg, 0.0, 90.0),
                ("ScatterAzimuth", self.azimuth_deg, 0.0, top),
                ("ScatterRadial", self.radial_deg, 0.0, 180.0),
                ("SampleRotation", self.rotation_deg, -360.0, 360.0)):
            p = _check_axis(name, np.asarray(vals, float), low, high)
            if p:
                return p + (f" ({self.symmetry})" if name == "ScatterAzimuth" else "")
        return None

    @property
    def shape(self) -> tuple[int, int, int, int]:
        """``(rotations, incidences, azimuths, radials)``: the shape of the table."""
        return (len(self.rotation_deg), len(self.aoi_deg), len(self.azimuth_deg),
                len(self.radial_deg))

    def directions(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(theta_i, theta_r, phi, cos_theta_r)`` of every node of one rotation, each of
        shape ``(incidences, azimuths, radials)`` (radians; theta_r > pi/2 below the horizon)."""
        t = np.radians(np.asarray(self.aoi_deg))[:, None, None]
        a = np.radians(np.asarray(self.azimuth_deg))[None, :, None]
        r = np.radians(np.asarray(self.radial_deg))[None, None, :]
        theta_r, phi, cz = specular_to_common(t, r, a)
        shape = np.broadcast_shapes(t.shape, a.shape, r.shape)
        return (np.broadcast_to(t, shape).copy(), np.broadcast_to(theta_r, shape).copy(),
                np.broadcast_to(phi, shape).copy(), np.broadcast_to(cz, shape).copy())

    def representatives(self) -> np.ndarray:
        """For each ``(azimuth, radial)`` node of a block, the flat index of the first node
        with the same direction: radial 0 is the specular direction at every azimuth, and
        azimuth 360 is azimuth 0 (when both are listed)."""
        n_az, n_rad = len(self.azimuth_deg), len(self.radial_deg)
        rep = np.arange(n_az * n_rad).reshape(n_az, n_rad)
        az = np.asarray(self.azimuth_deg)
        zero = np.flatnonzero(np.abs(az) <= GRID_TOL)
        full = np.flatnonzero(np.abs(az - 360.0) <= GRID_TOL)
        if zero.size and full.size:
            rep[full[0], :] = rep[zero[0], :]
        pole = np.flatnonzero(np.abs(np.asarray(self.radial_deg)) <= GRID_TOL)
        if pole.size:
            rep[:, pole[0]] = rep[0, pole[0]]
        return rep.ravel()

    def as_meta(self) -> dict[str, Any]:
        """The grid as plain lists (``meta["zemax_grid"]``)."""
        return {"symmetry": self.symmetry, "sample_rotation": list(self.rotation_deg),
                "angle_of_incidence": list(self.aoi_deg),
                "scatter_azimuth": list(self.azimuth_deg),
                "scatter_radial": list(self.radial_deg)}

    @classmethod
    def from_meta(cls, meta: dict[str, Any]) -> ZemaxGrid:
        """The grid recorded by :func:`read` in ``meta["zemax_grid"]``."""
        return cls(tuple(meta["angle_of_incidence"]), tuple(meta["scatter_azimuth"]),
                   tuple(meta["scatter_radial"]), tuple(meta["sample_rotation"]),
                   str(meta["symmetry"]))


def table_integral(values: Any, grid: ZemaxGrid) -> np.ndarray:
    """The table's own directional-hemispherical reflectance, ``int f cos(theta_r) d omega``
    at each (rotation, incidence): shape ``(rotations, incidences)``.

    The integrand ``f cos(theta_r) sin(r)`` is integrated with the trapezoid rule over the
    grid's (radial, azimuth) nodes (``d omega = sin r dr da`` about the specular direction);
    ``cos theta_r`` is 0 at and below the horizon. ``PlaneSymmetrical`` tables count twice
    (the mirror half); an ``Asymmetrical`` table is closed periodically from its last azimuth
    to its first + 360 deg. Directions beyond the grid's last radial angle (or outside its
    azimuths) count as 0. The accuracy is the grid's: a lobe narrower than the radial spacing,
    or a horizon cut between nodes, is what limits it (``docs``: ``export.zemax``).

    Examples
    --------
    >>> import numpy as np
    >>> g = ZemaxGrid((0,), np.arange(0, 181, 10), np.arange(0, 91, 1))
    >>> lambertian = np.full(g.shape, 0.5 / np.pi)
    >>> round(float(table_integral(lambertian, g)[0, 0]), 3)
    0.5
    """
    v = np.asarray(values, dtype=float).reshape(grid.shape)
    _, _, _, cz = grid.directions()
    r = np.radians(np.asarray(grid.radial_deg))
    a = np.radians(np.asarray(grid.azimuth_deg))
    g = v * np.clip(cz, 0.0, None)[None] * np.sin(r)
    inner = np.trapezoid(g, r, axis=-1) if r.size > 1 else np.zeros(g.shape[:-1])
    if grid.symmetry == "PlaneSymmetrical":
        return 2.0 * (np.trapezoid(inner, a, axis=-1) if a.size > 1 else 0.0 * inner[..., 0])
    closed = np.concatenate([inner, inner[..., :1]], axis=-1)
    return np.trapezoid(closed, np.concatenate([a, a[:1] + 2 * math.pi]), axis=-1)


# --------------------------------------------------------------------------------------------
# reading the text
# --------------------------------------------------------------------------------------------
@dataclass
class ZemaxTable:
    """A tabular BSDF as it is in the file.

    Attributes
    ----------
    grid : ZemaxGrid
    values : numpy.ndarray, shape ``grid.shape``
        BRDF (sr⁻¹) at ``[rotation, incidence, azimuth, radial]``.
    tis : numpy.ndarray, shape ``(rotations, incidences)``
        The TIS line of each block.
    header : dict of str -> str
        ``Source``, ``Symmetry``, ``SpectralContent``, ``ScatterType`` as written.
    comments : list of str
        The ``#`` lines (without ``#``), in order.
    """

    grid: ZemaxGrid
    values: np.ndarray
    tis: np.ndarray
    header: dict[str, str] = field(default_factory=dict)
    comments: list[str] = field(default_factory=list)


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
    sym = _normalize_symmetry(words["Symmetry"])
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


def _kept_nodes(table: ZemaxTable, rot_idx: np.ndarray
                ) -> tuple[np.ndarray, dict[str, int], list[str]]:
    """Flat indices of the nodes that become samples, their counts and notes."""
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
        One channel (``"value"``), quantity ``brdf``; conventions and ``meta`` keys in the
        module docstring.

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
    keep, counts, notes = _kept_nodes(table, rot_idx)
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


# --------------------------------------------------------------------------------------------
# writing the text
# --------------------------------------------------------------------------------------------
def _num(v: float) -> str:
    """The shortest text that reads back as exactly ``v`` (``10.0`` -> ``10``)."""
    s = repr(float(v))
    return s[:-2] if s.endswith(".0") else s


def _angle_text(values: tuple[float, ...]) -> str:
    return "\t".join(_num(v) for v in values)


def write_table(path: str | os.PathLike, grid: ZemaxGrid, values: Any, tis: Any, *,
                comments: Any = (), source: str = "Measured", overwrite: bool = False) -> Path:
    """Write a tabular BSDF atomically (a temporary file renamed over ``path``).

    Parameters
    ----------
    grid : ZemaxGrid
    values : array_like, shape ``grid.shape``
        BRDF (sr⁻¹), finite.
    tis : array_like, shape ``(rotations, incidences)``
    comments : sequence of str
        Written first, each as a ``#`` line.
    source : str
        The ``Source`` keyword (the format knows ``Measured``).
    overwrite : bool
        Replace an existing file (default: :class:`FileExistsError`).

    Numbers are written in their shortest exact form, tab separated: reading the file back
    gives the same floats.
    """
    v = np.asarray(values, dtype=float)
    t = np.asarray(tis, dtype=float)
    if v.shape != grid.shape or t.shape != grid.shape[:2]:
        raise ValueError(f"values must have shape {grid.shape} and tis {grid.shape[:2]}, got "
                         f"{v.shape} and {t.shape}")
    if not (np.isfinite(v).all() and np.isfinite(t).all()):
        raise ValueError("a .bsdf holds finite numbers only (no NaN or inf in values or tis)")
    head = [f"# {c}".rstrip() for c in comments]
    head += [f"Source\t{source}", f"Symmetry\t{grid.symmetry}", "SpectralContent\tMonochrome",
             "ScatterType\tBRDF"]
    for key, name in COUNTED.items():
        vals = getattr(grid, name)
        head += [f"{key}\t{len(vals)}", _angle_text(vals)]
    head += ["", "Monochrome", "DataBegin"]
    with staged(path, overwrite=overwrite) as fh:
        fh.write("\n".join(head) + "\n")
        for i in range(grid.shape[0]):
            for j in range(grid.shape[1]):
                fh.write(f"TIS\t{_num(t[i, j])}\n")
                fh.write("\n".join("\t".join(map(_num, row)) for row in v[i, j]) + "\n")
        fh.write("DataEnd\n")
    return Path(path)


def grid_from_radians(angles_of_incidence: Any, azimuth: Any, radial: Any, *,
                      symmetry: str = "PlaneSymmetrical", sample_rotation: Any = (0.0,)
                      ) -> ZemaxGrid:
    """A :class:`ZemaxGrid` from angles in radians (the Python API's unit), converted to
    degrees rounded to 1e-9 deg so that ``radians(10)`` is written as ``10``.

    Raises :class:`~roughbrdf.errors.ArgumentError` naming the argument that is not a valid
    axis (range, order, finiteness).

    Examples
    --------
    >>> import numpy as np
    >>> grid_from_radians(np.radians([0, 45]), np.radians([0, 180]), np.radians([0, 5])).aoi_deg
    (0.0, 45.0)
    """
    axes = {"angles_of_incidence": angles_of_incidence, "azimuth": azimuth, "radial": radial,
            "sample_rotation": sample_rotation}
    deg = {}
    for name, val in axes.items():
        try:
            arr = np.atleast_1d(np.asarray(val, dtype=float))
        except (TypeError, ValueError):
            raise ArgumentError(name, "must be angles in radians (a number or a sequence)",
                                value=val) from None
        # 9 decimals of a degree: removes the rounding of radians(d) -> d, keeps 1e-11 rad
        deg[name] = tuple(np.round(np.degrees(arr.ravel()), 9))
    top = 180.0 if _normalize_symmetry(str(symmetry)) == "PlaneSymmetrical" else 360.0
    for name, key, low, high in (("angles_of_incidence", "AngleOfIncidence", 0, 90),
                                 ("azimuth", "ScatterAzimuth", 0, top),
                                 ("radial", "ScatterRadial", 0, 180)):
        p = _check_axis(key, np.asarray(deg[name]), low, high)
        if p:
            raise ArgumentError(name, p + " (radians here: "
                                f"{np.radians(low):.4g} to {np.radians(high):.4g})")
    return ZemaxGrid(deg["angles_of_incidence"], deg["azimuth"], deg["radial"],
                     deg["sample_rotation"], symmetry)


# --------------------------------------------------------------------------------------------
# write: a Measurement onto a grid
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ZemaxWriteReport:
    """What writing a measurement as a tabular BSDF did to its samples.

    Attributes
    ----------
    path : str
        The file (written, or refused).
    shape : (int, int, int, int)
        The grid: rotations, incidences, azimuths, radials.
    symmetry : str
    n_samples : int
        Samples in the measurement.
    by_index : bool
        Samples were placed by their ``original["zemax_index"]`` (read from a .bsdf): none
        moved.
    n_binned : int
        Samples off the grid's nodes, moved to the nearest node.
    n_folded : int
        Samples with azimuth beyond 180 deg mirrored into 0-180 (``PlaneSymmetrical``).
    n_averaged, n_shared_cells : int
        Samples with different values sharing a node, and those nodes (each holds the mean).
    n_duplicates : int
        Samples repeating another sample's node and value (written once; no change).
    n_filled : int
        Nodes above the horizon without any sample: written as 0 (the format has no "no
        value").
    n_below_horizon_cells : int
        Nodes below the horizon: written as 0, never read back as samples.
    nonfinite, negative : int
        Values that cannot be written (NaN, inf: dropped) and negative values (kept).
    tis_source : str
        Where the TIS lines come from: the source file, or the table's own integral.
    n_read_back : int
        Samples :func:`read` gives back from the file.
    converted : str or None
        The quantity the values were converted from (``brdf_cos``: divided by cos theta_r).
    """

    path: str
    shape: tuple[int, int, int, int]
    symmetry: str
    n_samples: int
    by_index: bool
    n_binned: int = 0
    n_folded: int = 0
    n_averaged: int = 0
    n_shared_cells: int = 0
    n_duplicates: int = 0
    n_filled: int = 0
    n_below_horizon_cells: int = 0
    nonfinite: int = 0
    negative: int = 0
    tis_source: str = ""
    n_read_back: int = 0
    converted: str | None = None

    @property
    def changes_samples(self) -> bool:
        """Whether the file holds other samples than the measurement (moved, mirrored,
        averaged, dropped, or nodes filled with 0)."""
        return bool(self.n_binned or self.n_folded or self.n_averaged or self.n_filled or
                    self.nonfinite)

    def summary(self) -> str:
        """One line: the counts that change the samples."""
        d = "x".join(map(str, self.shape))
        parts = [f"{self.n_binned} off the grid's nodes (binned: moved to the nearest)",
                 f"{self.n_folded} mirrored into azimuth 0-180 deg ({self.symmetry})",
                 f"{self.n_averaged} sharing {self.n_shared_cells} nodes (averaged)",
                 f"{self.nonfinite} non-finite values (dropped)",
                 f"{self.n_filled} nodes above the horizon without a sample (written as 0)"]
        return (f"the Zemax grid {d} (rotations x incidences x azimuths x radials): of "
                f"{self.n_samples} samples, " + ", ".join(parts) +
                f"; reading the file back gives {self.n_read_back} samples")

    def text(self) -> str:
        """Several lines: every count and why (what the CLI prints)."""
        d = "x".join(map(str, self.shape))
        lines = [f"Zemax tabular BSDF {d} ({self.symmetry}): {self.n_samples} samples written, "
                 f"{self.n_read_back} read back"]
        if self.by_index:
            lines.append("  placed by their node index (read from a .bsdf): none moved")
        lines += [f"  binned:   {self.n_binned} samples off the nodes, moved to the nearest node",
                  f"  mirrored: {self.n_folded} samples at azimuth > 180 deg folded into 0-180",
                  f"  averaged: {self.n_averaged} samples with different values share "
                  f"{self.n_shared_cells} nodes; each holds their mean ({self.n_duplicates} "
                  "exact duplicates written once)",
                  f"  dropped:  {self.nonfinite} non-finite values; {self.negative} negative "
                  "values kept as they are",
                  f"  filled:   {self.n_filled} nodes above the horizon had no sample: 0 written",
                  f"  horizon:  {self.n_below_horizon_cells} nodes below the horizon: 0 written",
                  f"  TIS:      {self.tis_source}"]
        if self.converted:
            lines.append(f"  values converted from {self.converted} to BRDF (divided by cos "
                         "theta_r)")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.text()


def _brdf_column(m: Measurement, channel: Any) -> np.ndarray:
    """The one channel to write, as BRDF (sr⁻¹)."""
    if not Quantity.parse(m.quantity).absolute:
        raise ValueError("a tabular BSDF holds absolute BRDF (sr^-1); a 'relative' measurement "
                         "cannot be written as .bsdf")
    if m.polarization is not None and np.isfinite(m.polarization).any():
        raise ValueError("a tabular BSDF holds no polarization; select one polarization "
                         "(Measurement.with_polarization) and drop it")
    if channel is None:
        if m.n_channels != 1:
            raise ArgumentError("channel", f"a .bsdf holds one channel (Monochrome); this "
                                f"measurement has {m.n_channels} ({m.channels}): name one "
                                "(a label or index)", fix=m.channels[0])
        channel = 0
    j = m.channel_index(channel)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray(m.to_brdf()[:, j], dtype=float)


def _by_index(m: Measurement) -> tuple[ZemaxGrid, np.ndarray, np.ndarray] | None:
    """Grid (restricted to the blocks present), node index and TIS of a measurement read from
    a .bsdf whose samples are still where their index says; None otherwise."""
    meta, orig = m.meta, m.original
    if meta.get("format") != "zemax" or "zemax_grid" not in meta or "zemax_index" not in orig:
        return None
    try:
        full = ZemaxGrid.from_meta(meta["zemax_grid"])
        tis = np.asarray(meta["zemax_tis"], dtype=float).reshape(full.shape[:2])
    except (KeyError, TypeError, ValueError):
        return None
    idx = np.asarray(orig["zemax_index"], dtype=np.int64)
    if idx.size == 0 or idx.min() < 0 or idx.max() >= int(np.prod(full.shape)):
        return None
    ir, ia, iz, ik = np.unravel_index(idx, full.shape)
    ti, tr, ph, _ = full.directions()
    at = (ia, iz, ik)
    dphi = np.angle(np.exp(1j * (ph[at] - m.phi)))
    # the samples must still be at their nodes' directions (1e-9 rad: the reader's own values)
    if not (np.allclose(ti[at], m.theta_i, atol=1e-9, rtol=0) and
            np.allclose(np.minimum(tr[at], 0.5 * math.pi), m.theta_r, atol=1e-9, rtol=0) and
            np.all((np.abs(dphi) <= 1e-9) | (m.theta_r <= 1e-9))):
        return None
    rots, aois = np.unique(ir), np.unique(ia)
    grid = ZemaxGrid(tuple(np.asarray(full.aoi_deg)[aois]), full.azimuth_deg, full.radial_deg,
                     tuple(np.asarray(full.rotation_deg)[rots]), full.symmetry)
    new = np.ravel_multi_index((np.searchsorted(rots, ir), np.searchsorted(aois, ia), iz, ik),
                               grid.shape)
    return grid, new, tis[np.ix_(rots, aois)]


def _nearest(nodes: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Index of the node nearest to each ``x`` (nodes sorted)."""
    k = np.clip(np.searchsorted(nodes, x), 1, max(nodes.size - 1, 1))
    if nodes.size == 1:
        return np.zeros(x.shape, dtype=np.int64)
    left = nodes[k - 1]
    return np.where(np.abs(x - left) <= np.abs(nodes[k] - x), k - 1, k).astype(np.int64)


def _specular_coords(m: Measurement, symmetry: str) -> tuple[np.ndarray, ...]:
    """(incidence, azimuth, radial) of every sample in degrees, the azimuth folded into
    0-180 for PlaneSymmetrical, and which samples were folded."""
    rad, az = common_to_specular(m.theta_i, m.theta_r, m.phi)
    aoi, az, rad = np.degrees(m.theta_i), np.degrees(az), np.degrees(rad)
    pole = rad <= GRID_TOL
    az = np.where(pole | (np.abs(az - 360.0) <= GRID_TOL), 0.0, az)
    folded = np.zeros(az.shape, dtype=bool)
    if symmetry == "PlaneSymmetrical":
        folded = az > 180.0 + GRID_TOL
        az = np.where(folded, 360.0 - az, np.minimum(az, 180.0))
    return aoi, az, rad, folded, pole


def _by_geometry(m: Measurement, grid: ZemaxGrid) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Node index of every sample (nearest node), whether it sat on that node, and whether its
    azimuth was mirrored."""
    aoi, az, rad, folded, pole = _specular_coords(m, grid.symmetry)
    nodes = [np.asarray(v) for v in (grid.aoi_deg, grid.azimuth_deg, grid.radial_deg)]
    ia, iz, ik = (_nearest(n, x) for n, x in zip(nodes, (aoi, az, rad), strict=True))
    on = ((np.abs(nodes[0][ia] - aoi) <= GRID_TOL) & (np.abs(nodes[2][ik] - rad) <= GRID_TOL) &
          ((np.abs(nodes[1][iz] - az) <= GRID_TOL) | pole))
    ir = np.zeros(aoi.shape, dtype=np.int64)
    if "sample_rotation" in m.original and grid.shape[0] > 1:
        ir = _nearest(np.asarray(grid.rotation_deg),
                      np.asarray(m.original["sample_rotation"], dtype=float))
    return np.ravel_multi_index((ir, ia, iz, ik), grid.shape), on, folded


def _infer_grid(m: Measurement, symmetry: str) -> ZemaxGrid | None:
    """The grid the samples lie on, if they are on one (their distinct angles)."""
    aoi, az, rad, _, pole = _specular_coords(m, symmetry)
    # angles equal to GRID_TOL (1e-6 deg) are one node: rounding of a file's angles through
    # radians and back (a .bsdf written to CSV/ASTM and read again) is ~1e-13 deg
    axes = [np.unique(np.round(x, 6)) for x in (aoi, az[~pole] if (~pole).any() else
                                                np.zeros(1), rad)]
    try:
        return ZemaxGrid(tuple(axes[0]), tuple(axes[1]), tuple(axes[2]), symmetry=symmetry)
    except ValueError:
        return None


def default_measurement_grid(m: Measurement, symmetry: str = "PlaneSymmetrical") -> ZemaxGrid:
    """The grid ``resample=True`` uses without angles: the measurement's incidences, azimuths
    every 10 deg, radial angles every 2.5 deg up to the horizon of the largest incidence."""
    aoi = np.unique(np.round(np.degrees(m.theta_i), 6))
    top = 180.0 if _normalize_symmetry(symmetry) == "PlaneSymmetrical" else 360.0
    rmax = 90.0 + float(aoi.max(initial=0.0))
    return ZemaxGrid(tuple(aoi), tuple(np.arange(0.0, top + 1e-9, 10.0)),
                     tuple(np.append(np.arange(0.0, rmax, 2.5), rmax)), symmetry=symmetry)


def _fill(grid: ZemaxGrid, index: np.ndarray, values: np.ndarray
          ) -> tuple[np.ndarray, dict[str, int]]:
    """The table: the mean of the samples at each node; an empty node repeating the direction
    of a node with samples (radial 0 at every azimuth, azimuth 360) takes that node's value;
    0 at the other empty nodes and below the horizon."""
    n = int(np.prod(grid.shape))
    n_az, n_rad = grid.shape[2:]
    ok = np.isfinite(values)
    sums = np.bincount(index[ok], weights=values[ok], minlength=n)
    cnt = np.bincount(index[ok], minlength=n)
    table = np.where(cnt > 0, sums / np.maximum(cnt, 1), 0.0).reshape(-1, n_az * n_rad)
    cnt = cnt.reshape(-1, n_az * n_rad)
    rep = grid.representatives()
    empty = (cnt == 0) & (cnt[:, rep] > 0)
    table = np.where(empty, table[:, rep], table).reshape(grid.shape)
    # samples sharing a node with different values are averaged; identical copies are
    # duplicates (written once: no change)
    mean = table.ravel()[index]
    shared = ok & (cnt.ravel()[index] > 1)
    changed = np.unique(index[shared & (values != mean)])
    averaged = shared & np.isin(index, changed)
    _, _, _, cz = grid.directions()
    above = np.broadcast_to(cz >= -HORIZON_EPS, grid.shape)
    own = np.broadcast_to((rep == np.arange(rep.size)).reshape(n_az, n_rad), grid.shape)
    covered = (cnt > 0) | (cnt[:, rep] > 0)
    filled = above & own & ~covered.reshape(grid.shape)
    counts = {"n_averaged": int(averaged.sum()), "n_shared_cells": int(changed.size),
              "n_duplicates": int((shared & ~averaged).sum()
                                  - np.unique(index[shared & ~averaged]).size),
              "n_filled": int(filled.sum()), "n_below_horizon_cells": int((~above).sum()),
              "nonfinite": int((~ok).sum()), "negative": int((values[ok] < 0).sum())}
    return np.where(above, table, 0.0), counts


def plan(measurement: Measurement, path: str = "", *, channel: Any = None,
         angles_of_incidence: Any = None, azimuth: Any = None, radial: Any = None,
         symmetry: str | None = None
         ) -> tuple[ZemaxGrid, np.ndarray, np.ndarray, ZemaxWriteReport]:
    """The grid, table, TIS and report of writing ``measurement`` as a .bsdf; writes nothing.

    The grid is, in order: the angles given (radians; the others default as in
    :func:`default_measurement_grid`); the source file's grid for a measurement read from a
    .bsdf (placed by node index: exact); the grid the samples lie on, when every node above
    the horizon holds a sample; else the default grid (which ``resample=True`` needs).
    """
    m = measurement
    values = _brdf_column(m, channel)
    sym = _normalize_symmetry(symmetry or "PlaneSymmetrical")
    if sym is None:
        raise ArgumentError("symmetry", f"must be one of {', '.join(SYMMETRIES)}",
                            value=symmetry)
    given = any(v is not None for v in (angles_of_incidence, azimuth, radial))
    placed = None if given or symmetry is not None else _by_index(m)
    if placed is not None:
        grid, index, tis = placed
        on, folded = np.ones(index.size, bool), np.zeros(index.size, bool)
    else:
        grid = _grid_for(m, sym, given, angles_of_incidence, azimuth, radial)
        index, on, folded = _by_geometry(m, grid)
        tis = None
    table, counts = _fill(grid, index, values)
    changed = bool((~on).sum() or folded.sum() or counts["n_averaged"] or counts["n_filled"]
                   or counts["nonfinite"])
    if tis is None or changed:
        tis, source = table_integral(table, grid), ("the table's own integral (trapezoid on "
                                                    "the grid)")
    else:
        source = "the source file's TIS lines"
    keep, _, _ = _kept_nodes(ZemaxTable(grid, table, tis), np.arange(grid.shape[0]))
    report = ZemaxWriteReport(
        path=str(path), shape=grid.shape, symmetry=grid.symmetry, n_samples=m.n_samples,
        by_index=placed is not None, n_binned=int((~on).sum()), n_folded=int(folded.sum()),
        tis_source=source, n_read_back=int(keep.size),
        converted=m.quantity.value if m.quantity.cosine_weighted else None, **counts)
    return grid, table, np.asarray(tis, dtype=float), report


def _grid_for(m: Measurement, symmetry: str, given: bool, angles_of_incidence: Any,
              azimuth: Any, radial: Any) -> ZemaxGrid:
    """The grid of a measurement not placed by index: the angles given, else the grid its
    samples lie on (when complete), else the default grid."""
    default = default_measurement_grid(m, symmetry)
    if given:
        return grid_from_radians(
            np.radians(default.aoi_deg) if angles_of_incidence is None else angles_of_incidence,
            np.radians(default.azimuth_deg) if azimuth is None else azimuth,
            np.radians(default.radial_deg) if radial is None else radial, symmetry=symmetry)
    inferred = _infer_grid(m, symmetry)
    if inferred is not None and m.n_samples:
        index, on, folded = _by_geometry(m, inferred)
        _, counts = _fill(inferred, index, np.zeros(m.n_samples))  # coverage only
        if on.all() and not folded.any() and counts["n_filled"] == 0:
            return inferred
    return default


def write(measurement: Measurement, path: str | os.PathLike, *, overwrite: bool = False,
          resample: bool = False, channel: Any = None, angles_of_incidence: Any = None,
          azimuth: Any = None, radial: Any = None, symmetry: str | None = None
          ) -> ZemaxWriteReport:
    """Write a measurement as a Zemax tabular BSDF (one channel, Monochrome).

    A measurement read from a .bsdf goes back onto its own grid by node index (its TIS lines
    and comments too): exact. A measurement whose samples form a complete grid in Zemax's
    specular-centred angles is written exactly on it, with TIS the table's own integral
    (:func:`table_integral`). Anything else would bin, mirror, average or fill samples: it is
    refused unless ``resample=True``, and the report says what was done.

    Parameters
    ----------
    measurement : Measurement
        Absolute BRDF (``brdf``, or ``brdf_cos``/``bridf``, converted), no polarization.
    path : str or path-like
        Never the file the measurement was read from.
    overwrite : bool
        Replace an existing file (default: :class:`FileExistsError`).
    resample : bool
        Write even when the grid changes the samples.
    channel : str or int, optional
        The channel to write (required when there are several).
    angles_of_incidence, azimuth, radial : array_like, optional
        The grid (radians); see :func:`plan` for the defaults.
    symmetry : {"PlaneSymmetrical", "Asymmetrical", "Asymmetrical4D"}, optional

    Returns
    -------
    ZemaxWriteReport

    Examples
    --------
    >>> import roughbrdf as rb, tempfile, pathlib
    >>> from roughbrdf.export.zemax import to_zemax
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = to_zemax(rb.model("lambertian", rho=0.5), d / "a.bsdf")
    >>> m = rb.read(d / "a.bsdf")
    >>> report = write(m, d / "b.bsdf")          # back onto its own grid: exact
    >>> report.by_index, report.changes_samples
    (True, False)
    >>> bool((read_table(d / "b.bsdf").values == read_table(d / "a.bsdf").values).all())
    True
    >>> write(m.subset(m.theta_r < 1.0), d / "c.bsdf")
    Traceback (most recent call last):
    ...
    roughbrdf.errors.ArgumentError: writing ... would change the samples - ...

    Raises
    ------
    roughbrdf.errors.ArgumentError
        ``path`` is the measurement's own input; the grid would change the samples and
        ``resample`` is false; several channels and no ``channel``.
    FileExistsError
        ``path`` exists and ``overwrite`` is false.
    """
    target = prepare_target(measurement, path, overwrite)
    grid, table, tis, report = plan(measurement, str(target), channel=channel,
                                    angles_of_incidence=angles_of_incidence, azimuth=azimuth,
                                    radial=radial, symmetry=symmetry)
    if report.changes_samples and not resample:
        raise ArgumentError("resample", f"writing {target} would change the samples - "
                            f"{report.summary()}", fix=True)
    m = measurement
    label = m.channels[0 if channel is None else m.channel_index(channel)]
    comments = _comments(m, report, label)
    write_table(target, grid, table, tis, comments=comments,
                source=str(m.meta.get("header", {}).get("Source", "Measured"))
                if m.meta.get("format") == "zemax" else "Measured", overwrite=overwrite)
    items = []
    lost = header_not_written(m.meta, "zemax", WRITES)
    if lost:
        items.append(describe_keys(lost, str(m.meta.get("format"))))
    if m.uncertainty is not None:
        items.append("the uncertainties (sigma)")
    warn_not_written(target, "Zemax tabular BSDF", items)
    return report


def _comments(m: Measurement, report: ZemaxWriteReport, label: str) -> list[str]:
    """The ``#`` lines: the source file's comments, else the provenance the format can hold
    (and the channel written, since the format has one unnamed channel)."""
    if m.meta.get("format") == "zemax" and report.by_index:
        return [str(c) for c in m.meta.get("comments", [])]
    lines = ["written by roughbrdf (roughbrdf.io.zemax)", f"channel: {label}"]
    for key in WRITES:
        if m.meta.get(key):
            lines.append(f"{key}: {m.meta[key]}")
    if m.meta.get("file"):
        lines.append(f"from: {Path(str(m.meta['file'])).name}")
    if report.changes_samples:
        lines.append("resampled onto this grid: " + report.summary())
    return [re.sub(r"[\r\n]+", " ", s) for s in lines]


def header_field(key: str) -> str | None:
    """What a Zemax header keyword holds, for a writer of another format: :data:`LAYOUT` for the
    table's layout (``Symmetry``, ``SpectralContent``, ``ScatterType``: every writer writes its
    own), None for the rest (``Source``), which another format has no place for."""
    return LAYOUT if key in ("Symmetry", "SpectralContent", "ScatterType") else None
