"""LightTools BSDF files (``.bsdf``, Synopsys LightTools' tabular BSDF; the layout pinned by
libbsdf's ``LightToolsBsdfReader``).

Layout (``#`` begins a comment, to the end of its line)::

    Symmetry  Asymmetric               <- or PlaneSymmetrical
    SpectralContent  Monochrome        <- or XYZ (three blocks per incidence)
    ScatterAzimuth  37                 <- count N, then N azimuths (degrees)
    0  10  20  ...  360
    ScatterRadial  46                  <- count M, then M polar angles (degrees)
    0  2  4  ...  90
    DataBegin
    AOI  30                            <- one block per incidence (and channel): its keywords
    POI  0                                in any order, defaults POI 0, Side Front,
    Side  Front                           ScatterType BRDF ...
    Wavelength  550
    ScatterType  BRDF
    TIS  0.4231                        <- ... then TIS and N x M values:
    3.1e-02  3.1e-02  ...              <- one row per ScatterAzimuth, one value per ScatterRadial
    ...
    DataEnd

Source: libbsdf (K. Ryo, MPL-2.0, https://github.com/KimuraRyo/libbsdf,
``src/Reader/LightToolsBsdfReader.cpp`` and ``reader_utility::classifyFile``, commit
``eb62dc164b6c6d6b107f720aef17dc0b6b2eda23``); no public description by Synopsys was found.
What libbsdf's reader expects, and this module follows (``tests/io/test_io_lighttools.py`` pins
each point):

* header keywords ``Symmetry`` (``PlaneSymmetrical`` or ``Asymmetric`` - libbsdf refuses
  Zemax's spelling ``Asymmetrical``), ``SpectralContent`` (``Monochrome`` or ``XYZ``),
  ``ScatterAzimuth`` and ``ScatterRadial`` (each a count and that many angles), then
  ``DataBegin``; other header words are skipped;
* per block ``AOI`` (incidence zenith; libbsdf reads an ``AOI`` above 90 as 0),
  ``POI`` (plane of incidence, ignored by libbsdf), ``Side`` (``Front``/``Back``),
  ``Wavelength``, ``ScatterType`` (``BRDF``/``BTDF``), ``TristimulusValue``
  (``TrisX``/``TrisY``/``TrisZ``), and ``TIS`` followed by the values, azimuth outer, radial
  inner; ``DataEnd`` closes the data;
* the file is LightTools' and not Zemax's when a line begins with ``AOI``; Zemax's when one
  begins with ``AngleOfIncidence`` (:func:`sniff_bsdf`).

Angles (libbsdf, ``createBrdf``): ``ScatterRadial`` is the polar angle of the scattered
direction from the surface normal (libbsdf's spherical outgoing theta; **not** Zemax's angle
from the specular direction), ``AOI`` the incidence zenith, and ``ScatterAzimuth`` the
azimuth about the normal with the source at azimuth 90 deg ("An incoming azimuthal angle of
an isotropic LightTools BSDF is 90 degrees"; libbsdf turns it by -90 deg to its own frame,
where the source is at 0). In roughbrdf's frame (source at ``phi = pi``, specular at 0)::

    theta_i = AOI,  theta_r = ScatterRadial,  phi = ScatterAzimuth + 90 deg  (mod 360)

so the specular direction is ``ScatterAzimuth = 270`` and ``PlaneSymmetrical`` files hold
one side of the plane of incidence, azimuths 90-270 (or 270-450). Values are the BRDF in
sr⁻¹. Nodes with ``ScatterRadial > 90`` (below the horizon) are not read; the normal
direction (radial 0) repeated at every azimuth, and azimuth 360 repeating 0, are read once
where the values agree.

Reading (:func:`read`): one channel per wavelength (``"550nm"``; ``"value"`` when the blocks
give none) or per tristimulus value (``"X"``, ``"Y"``, ``"Z"``); the front side's BRDF blocks
by default (``side="back"`` for the other); BTDF blocks and the other side are left out and
counted in ``meta["lighttools_ignored"]``. Writing: :mod:`roughbrdf.io.lighttools_write`
(``format_table``, the text; ``write_measurement``, a measurement on a LightTools grid) and
:mod:`roughbrdf.export.lighttools` (``to_lighttools``, a model on a grid).
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ArgumentError
from ..measurement import Measurement
from ..quantity import Quantity
from ._common import FormatError, unit_word
from ._rows import decode, parse_number, read_text

__all__ = ["read", "sniff_bsdf", "read_blocks", "kept_nodes", "LightToolsGrid",
           "EXTENSIONS", "SYMMETRIES"]

#: the extension LightTools shares with Zemax (tell them apart with :func:`sniff_bsdf`)
EXTENSIONS = (".bsdf",)
#: the Symmetry words libbsdf accepts
SYMMETRIES = ("PlaneSymmetrical", "Asymmetric")
#: angles closer than this (degrees) are the same grid angle
GRID_TOL = 1e-6
#: how much of a file :func:`sniff_bsdf` reads at most (bytes)
SNIFF_BYTES = 1 << 20

_BLOCK_WORDS = ("AOI", "POI", "Side", "Wavelength", "ScatterType", "TristimulusValue", "TIS")
_TRIS = {"TrisX": "X", "TrisY": "Y", "TrisZ": "Z"}


# --------------------------------------------------------------------------------------------
# telling LightTools from Zemax
# --------------------------------------------------------------------------------------------
def sniff_bsdf(path: str | os.PathLike) -> str:
    """``"lighttools"`` or ``"zemax"``: which of the two ``.bsdf`` formats ``path`` holds.

    Decided as libbsdf's ``reader_utility::classifyFile`` does, by the first word of the
    lines (comments out): a line beginning with ``AOI`` (LightTools' per-block incidence) or
    with ``AngleOfIncidence``/``SampleRotation`` (Zemax's header). The first kilobyte
    usually decides; long angle lists are read on, up to 1 MiB.

    Raises
    ------
    FormatError
        Naming the file, when neither format's keywords appear.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "a.bsdf"
    >>> _ = p.write_text("Symmetry Asymmetric\\nScatterAzimuth 1\\n0\\nDataBegin\\nAOI 0\\n")
    >>> sniff_bsdf(p)
    'lighttools'
    """
    p = Path(path)
    with open(p, "rb") as fh:
        head = fh.read(1024)
        while True:
            found = _first_words(decode(head, p))
            if found is not None:
                return found
            more = fh.read(len(head))
            if not more or len(head) >= SNIFF_BYTES:
                break
            head += more
    raise FormatError("neither a Zemax nor a LightTools BSDF: no line begins with "
                      "'AngleOfIncidence' or 'SampleRotation' (Zemax) or 'AOI' (LightTools) "
                      f"in its first {min(len(head), SNIFF_BYTES)} bytes; pass the format "
                      "(format='zemax' or 'lighttools', CLI --format)", p)


def _first_words(text: str) -> str | None:
    """The format named by the first line-initial keyword of ``text`` (None: none yet)."""
    m = re.search(r"^[ \t]*(AOI|AngleOfIncidence|SampleRotation)(?=[\s#]|$)", text,
                  re.MULTILINE | re.IGNORECASE)
    if m is None:
        return None
    return "lighttools" if m.group(1).upper() == "AOI" else "zemax"


# --------------------------------------------------------------------------------------------
# the grid
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class LightToolsGrid:
    """Incidences, azimuths and polar angles (degrees) of a LightTools table.

    Examples
    --------
    >>> g = LightToolsGrid((0.0, 30.0), (0.0, 90.0, 180.0, 270.0, 360.0), (0.0, 30.0, 90.0))
    >>> g.shape
    (2, 5, 3)
    >>> [round(float(np.degrees(x)), 6) for x in g.directions()[2][0, 3, :1]]  # az 270
    [0.0]
    """

    aoi_deg: tuple[float, ...]
    azimuth_deg: tuple[float, ...]
    radial_deg: tuple[float, ...]
    symmetry: str = "Asymmetric"

    def __post_init__(self) -> None:
        for name, lo, hi in (("aoi_deg", 0.0, 90.0), ("azimuth_deg", 0.0, 360.0),
                             ("radial_deg", 0.0, 180.0)):
            a = np.asarray(getattr(self, name), dtype=float)
            if a.ndim != 1 or a.size < 1 or not np.isfinite(a).all():
                raise ArgumentError(name, "must be a non-empty list of finite angles (deg)",
                                    value=getattr(self, name))
            if a.min() < lo or a.max() > hi:
                raise ArgumentError(name, f"angles must lie in [{lo:g}, {hi:g}] deg",
                                    value=float(a.min() if a.min() < lo else a.max()))
            if a.size > 1 and not (np.diff(a) > GRID_TOL).all():
                raise ArgumentError(name, "angles must increase strictly", value=a.tolist())
            object.__setattr__(self, name, tuple(float(x) for x in a))
        if self.symmetry not in SYMMETRIES:
            raise ArgumentError("symmetry", f"must be one of {', '.join(SYMMETRIES)}",
                                value=self.symmetry)

    @property
    def shape(self) -> tuple[int, int, int]:
        """``(incidences, azimuths, radials)``."""
        return len(self.aoi_deg), len(self.azimuth_deg), len(self.radial_deg)

    def directions(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``theta_i, theta_r, phi`` (radians, roughbrdf's frame, ``phi`` in (-pi, pi]) of
        every node, each of shape :attr:`shape` (module docstring for the mapping)."""
        ti, az, rad = np.meshgrid(np.radians(self.aoi_deg), np.asarray(self.azimuth_deg),
                                  np.radians(self.radial_deg), indexing="ij")
        phi = np.radians(-(np.mod(180.0 - (az + 90.0), 360.0) - 180.0))  # wrap to (-180, 180]
        return ti, rad, phi

    def as_meta(self) -> dict[str, Any]:
        """The grid as plain lists (for ``meta``)."""
        return {"aoi_deg": list(self.aoi_deg), "azimuth_deg": list(self.azimuth_deg),
                "radial_deg": list(self.radial_deg), "symmetry": self.symmetry}


# --------------------------------------------------------------------------------------------
# the text into blocks
# --------------------------------------------------------------------------------------------
@dataclass
class _Block:
    """One data block: its keywords (word -> (value, line)) and values."""

    words: dict[str, tuple[str, int]]
    values: np.ndarray
    line: int  # the TIS line


def _tokens(lines: list[str]) -> tuple[list[str], list[int], list[str]]:
    """The words of the file with their 1-based lines (``#`` to the end of a line is a
    comment), and the comments' texts."""
    words: list[str] = []
    nums: list[int] = []
    comments: list[str] = []
    for i, raw in enumerate(lines):
        body, hash_, rest = raw.partition("#")
        if hash_:
            comments.append(rest.strip())
        split = body.split()
        words.extend(split)
        nums.extend([i + 1] * len(split))
    return words, nums, comments


#: one plain number (no ``nan``/``inf``, no ``_``), many of them blank-separated
_PLAIN = r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?"
_PLAIN_RUN = re.compile(rf"{_PLAIN}(?: {_PLAIN})*", re.ASCII)


def _values(words: list[str], lines: list[int], k: int, n: int, tis_line: int, path: Path
            ) -> np.ndarray:
    """The ``n`` values from word ``k`` as one array (checked in one pass: plain numbers
    only; the first culprit named with its line otherwise)."""
    chunk = words[k:k + n]
    if _PLAIN_RUN.fullmatch(" ".join(chunk)):
        return np.asarray(chunk, dtype=float)
    bad = next(j for j, w in enumerate(chunk) if not re.fullmatch(_PLAIN, w, re.ASCII))
    raise FormatError(f"expected value {bad + 1} of {n} of the block of TIS line {tis_line}, "
                      f"found {chunk[bad][:40]!r}", path, lines[k + bad])


def _number(words: list[str], lines: list[int], k: int, what: str, path: Path) -> float:
    """The number at word ``k`` (``what`` it is for the message)."""
    if k >= len(words):
        raise FormatError(f"the file ends where {what} was expected", path,
                          lines[-1] if lines else None)
    try:
        return parse_number(words[k])
    except ValueError:
        raise FormatError(f"expected {what}, found {words[k][:40]!r}", path, lines[k]) from None


def _header(words: list[str], lines: list[int], path: Path
            ) -> tuple[dict[str, tuple[str, int]], dict[str, list[float]], list[str], int]:
    """Header phase up to ``DataBegin``: the word keywords, the angle lists, the words not
    known (libbsdf skips them), and the index of the first data word."""
    keys: dict[str, tuple[str, int]] = {}
    angles: dict[str, list[float]] = {}
    other: list[str] = []
    k = 0
    while k < len(words):
        w, ln = words[k], lines[k]
        if w.lower() == "databegin":
            return keys, angles, other, k + 1
        if w.lower() in ("angleofincidence", "samplerotation"):
            raise FormatError(f"{w} is a Zemax tabular BSDF keyword: this is a Zemax file "
                              "(read it with format='zemax')", path, ln)
        if w in ("ScatterAzimuth", "ScatterRadial"):
            if w in angles:
                raise FormatError(f"{w} is given twice", path, ln)
            n = _number(words, lines, k + 1, f"the count after {w}", path)
            if not (n >= 1 and float(n).is_integer()):
                raise FormatError(f"{w} count must be a whole number >= 1, got "
                                  f"{words[k + 1]!r}", path, lines[k + 1])
            angles[w] = [_number(words, lines, k + 2 + j, f"angle {j + 1} of {int(n)} after "
                                 f"{w} (line {ln})", path) for j in range(int(n))]
            k += 2 + int(n)
        elif w in ("Symmetry", "SpectralContent"):
            if k + 1 >= len(words) or words[k + 1].lower() == "databegin":
                raise FormatError(f"{w} has no value", path, ln)
            if w in keys:
                raise FormatError(f"{w} is given twice: line {keys[w][1]} and line {ln}",
                                  path, ln)
            keys[w] = (words[k + 1], ln)
            k += 2
        else:
            other.append(w)
            k += 1
    raise FormatError("no DataBegin: not a LightTools BSDF file (expected Symmetry, "
                      "SpectralContent, ScatterAzimuth, ScatterRadial, then DataBegin)", path,
                      lines[-1] if lines else None)


def _grid(keys: dict[str, tuple[str, int]], angles: dict[str, list[float]], aois: list[float],
          path: Path) -> LightToolsGrid:
    """The header checked: the keywords present and angles in range."""
    for key in ("ScatterAzimuth", "ScatterRadial"):
        if key not in angles:
            raise FormatError(f"no {key} line in the header", path)
    sym_word, sym_line = keys.get("Symmetry", ("Asymmetric", 0))
    sym = {"planesymmetrical": "PlaneSymmetrical", "asymmetric": "Asymmetric",
           "asymmetrical": "Asymmetric"}.get(sym_word.lower())
    if sym is None:
        raise FormatError(f"Symmetry {sym_word!r} is not one of {', '.join(SYMMETRIES)}",
                          path, sym_line or None)
    try:
        return LightToolsGrid(tuple(aois), tuple(angles["ScatterAzimuth"]),
                              tuple(angles["ScatterRadial"]), sym)
    except ArgumentError as exc:
        name = {"azimuth_deg": "ScatterAzimuth", "radial_deg": "ScatterRadial",
                "aoi_deg": "AOI"}.get(exc.argument, exc.argument)
        raise FormatError(f"{name}: {exc.message}", path) from None


def _block_word(words: list[str], lines: list[int], k: int, blk: dict[str, tuple[str, int]],
                path: Path) -> int:
    """Record the block keyword at word ``k`` and its value; returns the next word index."""
    w, ln = words[k], lines[k]
    if w in blk:
        raise FormatError(f"{w} twice in one block (line {blk[w][1]} and line {ln}): a block "
                          "ends with its TIS line and values", path, ln)
    if k + 1 >= len(words):
        raise FormatError(f"{w} has no value", path, ln)
    value = words[k + 1]
    allowed = {"Side": ("Front", "Back"), "ScatterType": ("BRDF", "BTDF"),
               "TristimulusValue": tuple(_TRIS)}.get(w)
    if allowed is not None and value not in allowed:
        raise FormatError(f"{w} {value!r} is not one of {', '.join(allowed)}", path, ln)
    if allowed is None:
        _number(words, lines, k + 1, f"a number after {w}", path)
    blk[w] = (value, ln)
    return k + 2


def _data(words: list[str], lines: list[int], k: int, n_values: int, path: Path
          ) -> list[_Block]:
    """Data phase: the blocks up to ``DataEnd``."""
    blocks: list[_Block] = []
    blk: dict[str, tuple[str, int]] = {}
    while k < len(words):
        w, ln = words[k], lines[k]
        if w.lower() == "dataend":
            if blk:
                raise FormatError(f"DataEnd inside a block begun on line "
                                  f"{min(v[1] for v in blk.values())} (no TIS and values)",
                                  path, ln)
            if k + 1 < len(words):
                raise FormatError(f"text after DataEnd: {words[k + 1][:40]!r}", path,
                                  lines[k + 1])
            return blocks
        if w not in _BLOCK_WORDS:
            raise FormatError(f"unexpected {w[:40]!r} in the data (block keywords: "
                              f"{', '.join(_BLOCK_WORDS)}; then the values; DataEnd)", path, ln)
        if w != "TIS":
            k = _block_word(words, lines, k, blk, path)
            continue
        _number(words, lines, k + 1, "a number after TIS", path)
        blk["TIS"] = (words[k + 1], ln)
        if len(words) < k + 2 + n_values:
            raise FormatError(f"the file ends inside the block of TIS line {ln}: "
                              f"{len(words) - k - 2} of {n_values} values (ScatterAzimuth x "
                              "ScatterRadial)", path, lines[-1])
        blocks.append(_Block(blk, _values(words, lines, k + 2, n_values, ln, path), ln))
        blk = {}
        k += 2 + n_values
    raise FormatError("no DataEnd after the last block (the file may be cut short)", path,
                      lines[-1] if lines else None)


def read_blocks(path: str | os.PathLike) -> tuple[dict[str, Any], list[_Block], list[str]]:
    """The file's header (``keys``, ``angles``, ``other``), data blocks and comments, as
    written (no selection); :class:`FormatError` naming the file and line otherwise."""
    p = Path(path)
    lines = read_text(p)
    words, nums, comments = _tokens(lines)
    keys, angles, other, k = _header(words, nums, p)
    n_values = len(angles.get("ScatterAzimuth", ())) * len(angles.get("ScatterRadial", ()))
    if n_values == 0:
        missing = [x for x in ("ScatterAzimuth", "ScatterRadial") if x not in angles]
        raise FormatError(f"no {missing[0]} line in the header", p)
    blocks = _data(words, nums, k, n_values, p)
    return {"keys": keys, "angles": angles, "other": other}, blocks, comments



# --------------------------------------------------------------------------------------------
# the blocks into a measurement
# --------------------------------------------------------------------------------------------
def _channel_of(b: _Block, spectral: str, path: Path) -> str:
    """The channel label of a block: its tristimulus value (XYZ) or wavelength."""
    if spectral == "XYZ":
        if "TristimulusValue" not in b.words:
            raise FormatError("SpectralContent XYZ: each block needs a TristimulusValue "
                              "(TrisX, TrisY or TrisZ)", path, b.line)
        return _TRIS[b.words["TristimulusValue"][0]]
    if "Wavelength" in b.words:
        return f"{parse_number(b.words['Wavelength'][0]):g}nm"
    return "value"


def _aoi_of(b: _Block, notes: list[str], path: Path) -> float:
    """The block's AOI (degrees; 0 when absent, as libbsdf); 180 is read as 0 (libbsdf reads
    every AOI above 90 as 0), other values outside [0, 90] are refused."""
    word, line = b.words.get("AOI", ("0", b.line))
    aoi = parse_number(word)
    if aoi == 180.0:
        notes.append(f"AOI 180 (line {line}) read as 0 (normal incidence), as libbsdf does")
        return 0.0
    if not 0.0 <= aoi <= 90.0:
        raise FormatError(f"AOI {word} is outside [0, 90] deg", path, line)
    return aoi


def _select(blocks: list[_Block], side: str, spectral: str, path: Path
            ) -> tuple[dict[tuple[str, float], _Block], dict[str, int], list[str]]:
    """The blocks of ``side``'s BRDF by (channel, AOI), the others counted, and notes."""
    chosen: dict[tuple[str, float], _Block] = {}
    ignored: dict[str, int] = {}
    notes: list[str] = []
    pois: dict[float, int] = {}
    for b in blocks:
        kind = (f"{b.words.get('Side', ('Front', 0))[0]} "
                f"{b.words.get('ScatterType', ('BRDF', 0))[0]}")
        if kind != f"{side.capitalize()} BRDF":
            ignored[kind] = ignored.get(kind, 0) + 1
            continue
        poi = parse_number(b.words.get("POI", ("0", 0))[0])
        pois.setdefault(poi, b.line)
        key = (_channel_of(b, spectral, path), _aoi_of(b, notes, path))
        if key in chosen:
            first = chosen[key].words.get("AOI", ("", chosen[key].line))[1]
            raise FormatError(f"a second block for AOI {key[1]:g} ({key[0]}): the first is at "
                              f"line {first}", path, b.words.get("AOI", ("", b.line))[1])
        chosen[key] = b
    if not chosen:
        held = ", ".join(f"{n} {k}" for k, n in ignored.items()) or "none"
        raise FormatError(f"no {side.capitalize()} BRDF block (blocks: {held}); roughbrdf reads "
                          "reflection (ScatterType BRDF); pass side='back' for the back side",
                          path)
    if len(pois) > 1:
        raise FormatError(f"blocks for {len(pois)} planes of incidence (POI "
                          f"{', '.join(f'{v:g}' for v in pois)}; an anisotropic sample); "
                          "roughbrdf's models are isotropic", path, list(pois.values())[1])
    return chosen, ignored, notes


def _table(chosen: dict[tuple[str, float], _Block], grid_shape: tuple[int, int], path: Path
           ) -> tuple[list[str], list[float], np.ndarray, np.ndarray]:
    """Channels, incidences, the values ``(channels, aoi, az, rad)`` and TIS
    ``(channels, aoi)``; every channel must hold every incidence."""
    channels = list(dict.fromkeys(c for c, _ in chosen))
    aois = sorted({a for _, a in chosen})
    values = np.empty((len(channels), len(aois), *grid_shape))
    tis = np.empty((len(channels), len(aois)))
    for ci, c in enumerate(channels):
        for ai, a in enumerate(aois):
            b = chosen.get((c, a))
            if b is None:
                raise FormatError(f"channel {c} has no block for AOI {a:g} deg (each channel "
                                  "needs every incidence)", path)
            values[ci, ai] = b.values.reshape(grid_shape)
            tis[ci, ai] = parse_number(b.words["TIS"][0])
    return channels, aois, values, tis


def kept_nodes(grid: LightToolsGrid, values: np.ndarray) -> tuple[np.ndarray, dict[str, int]]:
    """Flat indices (into ``grid.shape``) of the nodes :func:`read` makes samples: above the
    horizon (``ScatterRadial <= 90``), the normal (radial 0) once per incidence and azimuth
    360 not repeating 0 when their values agree across the azimuths (``values``: shape
    ``(channels, *grid.shape)``), and counts of the others."""
    n_aoi, n_az, n_rad = grid.shape
    rad, az = np.asarray(grid.radial_deg), np.asarray(grid.azimuth_deg)
    keep = np.broadcast_to(rad <= 90.0 + GRID_TOL, grid.shape).copy()
    dup = np.zeros(grid.shape, dtype=bool)
    r0 = np.flatnonzero(np.abs(rad) <= GRID_TOL)
    if r0.size and n_az > 1:  # radial 0 is one direction (the normal) at every azimuth
        v = values[:, :, :, r0[0]]
        same = (v == v[:, :, :1]).all(axis=(0, 2))
        dup[same, 1:, r0[0]] = True
    if n_az > 1 and abs(az[-1] - az[0] - 360.0) <= GRID_TOL:  # azimuth 360 is azimuth 0
        same = (values[:, :, -1, :] == values[:, :, 0, :]).all(axis=0)
        dup[:, -1, :] |= same
    counts = {"lighttools_below_horizon": int((~keep).sum()),
              "lighttools_duplicates": int((keep & dup).sum())}
    return np.flatnonzero((keep & ~dup).ravel()), counts


def read(path: str | os.PathLike, *, side: str = "front", quantity: Any = None,
         angles: str | None = None, **options: Any) -> Measurement:
    """Read a LightTools BSDF into a :class:`~roughbrdf.measurement.Measurement`.

    Parameters
    ----------
    path : str or path-like
    side : {"front", "back"}
        Which side's BRDF blocks to read (``Side``; default front).
    quantity, angles : str, optional
        Accepted for symmetry with the other readers: the format holds the BRDF (sr⁻¹) at
        angles in degrees, so only ``"brdf"`` and ``"deg"`` agree with it.

    Returns
    -------
    Measurement
        One channel per wavelength or tristimulus value, quantity ``brdf``; the file's angles
        in ``original`` (``aoi``, ``scatter_azimuth``, ``scatter_radial``, degrees, and
        ``lighttools_index``, the node's flat index in the grid), the grid, TIS, header and
        counts in ``meta``.

    Examples
    --------
    >>> import roughbrdf as rb, tempfile, pathlib
    >>> from roughbrdf.export.lighttools import to_lighttools
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "white.bsdf"
    >>> _ = to_lighttools(rb.model("lambertian", rho=0.5), out)
    >>> m = read(out)
    >>> m.channels, str(m.quantity), m.meta["format"]
    (['value'], 'brdf', 'lighttools')
    """
    if options:
        raise TypeError(f"lighttools.read got unknown options {sorted(options)}")
    p = Path(path)
    if side not in ("front", "back"):
        raise ArgumentError("side", "must be 'front' or 'back'", value=side)
    if angles is not None and unit_word(angles, p) != "deg":
        raise FormatError(f"angles={angles!r} contradicts the LightTools format, whose angles "
                          "are degrees by definition", p)
    if quantity is not None and Quantity.parse(quantity, "quantity") != Quantity.BRDF:
        raise FormatError(f"quantity={quantity!r} contradicts the format's BRDF (sr^-1)", p)
    head, blocks, comments = read_blocks(p)
    spectral, sp_line = head["keys"].get("SpectralContent", ("Monochrome", 0))
    if spectral not in ("Monochrome", "XYZ"):
        raise FormatError(f"SpectralContent {spectral!r} is not Monochrome or XYZ", p,
                          sp_line or None)
    chosen, ignored, notes = _select(blocks, side, spectral, p)
    shape = (len(head["angles"]["ScatterAzimuth"]), len(head["angles"]["ScatterRadial"]))
    channels, aois, values, tis = _table(chosen, shape, p)
    grid = _grid(head["keys"], head["angles"], aois, p)
    if head["other"]:
        notes.append(f"header words skipped (as libbsdf does): {' '.join(head['other'][:20])}")
    return _measurement(grid, channels, values, tis, p, {
        "header": {k: v for k, (v, _) in head["keys"].items()}, "comments": comments,
        "lighttools_ignored": ignored, "lighttools_side": side, "quirks": notes})


def _measurement(grid: LightToolsGrid, channels: list[str], values: np.ndarray,
                 tis: np.ndarray, path: Path, extra: dict[str, Any]) -> Measurement:
    """The kept nodes as samples, with the file's angles in ``original``."""
    keep, counts = kept_nodes(grid, values)
    ti, tr, ph = (x.ravel()[keep] for x in grid.directions())
    idx = np.unravel_index(keep, grid.shape)
    original = {"aoi": np.asarray(grid.aoi_deg)[idx[0]],
                "scatter_azimuth": np.asarray(grid.azimuth_deg)[idx[1]],
                "scatter_radial": np.asarray(grid.radial_deg)[idx[2]],
                "lighttools_index": keep.astype(np.int64)}
    meta: dict[str, Any] = {
        "file": str(path), "file_abs": str(path.resolve()), "format": "lighttools",
        "sample": path.stem, "instrument": None, "date": None, **extra,
        "lighttools_grid": grid.as_meta(),
        "lighttools_tis": {c: tis[i].tolist() for i, c in enumerate(channels)}, **counts,
        "wavelengths_nm": [float(c[:-2]) if c.endswith("nm") else None for c in channels],
        "angle_units": "deg", "original_units": "deg (AOI, ScatterAzimuth, ScatterRadial); "
        "lighttools_index: flat index of the node in the file's grid"}
    vals = values.reshape(len(channels), -1)[:, keep].T
    return Measurement(theta_i=ti, theta_r=np.minimum(tr, 0.5 * math.pi), phi=ph, values=vals,
                       channels=channels, quantity=Quantity.BRDF, original=original, meta=meta)

