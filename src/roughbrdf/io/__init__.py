"""Readers and writers of measured-BRDF files; one module per format (Zemax: a package).

==========  ======================  ================================================  ====  =====
format      extensions              module                                            read  write
==========  ======================  ================================================  ====  =====
astm        ``.astm``               :mod:`roughbrdf.io.astm` (ASTM E1392 text)        yes   yes
alta        ``.dat``, ``.alta``     :mod:`roughbrdf.io.alta` (ALTA text)              yes   yes
merl        ``.binary``, ``.merl``  :mod:`roughbrdf.io.merl` (MERL 2003 binary)       yes   yes
csv         ``.csv``                :mod:`roughbrdf.io.csv` (roughbrdf CSV)           yes   yes
zemax       ``.bsdf``               :mod:`roughbrdf.io.zemax` (Zemax tabular BSDF)    yes   yes
lighttools  ``.bsdf``               :mod:`roughbrdf.io.lighttools` (LightTools BSDF)  yes   yes
rgl         ``.bsdf``               :mod:`roughbrdf.io.rgl` (RGL tensor file)         yes   no
==========  ======================  ================================================  ====  =====

``read(path)`` chooses the format from the extension (``format=`` overrides); when the
extension is unknown it looks at the first bytes. Zemax, LightTools and RGL share ``.bsdf``:
an existing ``.bsdf`` file is read by its contents (an RGL tensor file by its magic bytes
``tensor_file``, :func:`roughbrdf.io.rgl.sniff`; then
:func:`roughbrdf.io.lighttools.sniff_bsdf`), a new one is written as Zemax unless
``format="lighttools"`` (RGL files are written by ``roughbrdf.export``, ``to="rgl"``).
Every problem with a file raises :class:`FormatError` (a ``ValueError``) whose message starts
with the path and, where one line is at fault, the line number (also in ``.path`` and
``.line``).

Each text reader's ``read()`` runs the same phases - header, angle unit, columns, quantity,
rows - and every reader applies the same two rules, from :mod:`roughbrdf.io._common`: the angle
unit (``angles=`` option, else the file's declarations, else the format's default or an error
where a declaration is required) and the quantity (``quantity=`` option, else the file's
declaration, else the format's default or an error), as a
:class:`~roughbrdf.quantity.Quantity`. An option that contradicts the file, a header key given
twice and two declarations that disagree are :class:`FormatError` naming both places; a file
that ends inside a number without a final line end is read with an
:class:`UnterminatedRowWarning`.

The text readers read each data row field by field: an empty field, a blank inside a number
(``1 5``), an underscore (``1_5``) or a non-ASCII digit (``１５``) is a :class:`FormatError`
naming the line and the column (numbers are plain ASCII: sign, digits, point, exponent,
``nan``, ``inf``). Angles that look like the other unit - every zenith below 2 read as degrees
(a radians file), an angle above 2 pi read as radians - are read as told, with an
:class:`ImplausibleAnglesWarning` naming the ``angles=`` option to use. A UTF-16 or UTF-32 file
with a byte-order mark is read; one without (NUL bytes) is refused, saying so. A pipe or device
(not a regular file) is read up to 1 GiB (``roughbrdf.io._rows.MAX_STREAM_BYTES``) and refused
beyond, naming the file and the limit.

``write(m, path)`` never replaces an existing file unless ``overwrite=True`` (the CLI's
``--force``), never writes onto the file ``m`` was read from, and writes atomically (a temporary
file renamed over ``path``: an error or Ctrl-C leaves the old file or none). Written in its own
format, a measurement keeps every header key it was read with; what another format has no
place for is named in a :class:`LossyWriteWarning`. MERL's fixed grid changes most
measurements' samples, so writing MERL needs ``resample=True`` for them and returns a report of
what was binned, averaged and dropped (:class:`~roughbrdf.io.merl.MerlWriteReport`). Zemax's
tabular BSDF is a grid about the specular direction: a measurement read from a ``.bsdf`` (or
lying on such a grid) is written exactly, any other needs ``resample=True`` and gets a
:class:`~roughbrdf.io.zemax.ZemaxWriteReport`.
"""

from __future__ import annotations

import importlib
import os
import re
from pathlib import Path
from typing import Any

from ..extrapolation import mark_extrapolated
from ..measurement import Measurement
from ._common import (
    FormatError,
    FormatWarning,
    ImplausibleAnglesWarning,
    LossyWriteWarning,
    UnterminatedRowWarning,
)
from ._rows import decode

__all__ = ["read", "write", "FormatError", "FormatWarning", "ImplausibleAnglesWarning",
           "LossyWriteWarning", "UnterminatedRowWarning", "FORMATS", "format_for"]

#: format name -> module name under roughbrdf.io
#: (zemax before lighttools: a new .bsdf file is written as Zemax unless told otherwise)
FORMATS = {"astm": "astm", "alta": "alta", "merl": "merl", "csv": "csv", "zemax": "zemax",
           "lighttools": "lighttools", "rgl": "rgl"}
_ALIASES = {"ascii": "alta", "dat": "alta", "binary": "merl", "e1392": "astm", "txt": "alta",
            "bsdf": "zemax", "opticstudio": "zemax", "lt": "lighttools"}


def _module(fmt: str):
    try:
        return importlib.import_module(f"{__name__}.{FORMATS[fmt]}")
    except ModuleNotFoundError as exc:
        if exc.name != f"{__name__}.{FORMATS[fmt]}":
            raise
        raise FormatError(f"format {fmt!r} is not available in this version") from None


def _extensions(fmt: str) -> tuple[str, ...]:
    try:
        return tuple(getattr(_module(fmt), "EXTENSIONS", ()))
    except FormatError:
        return ()


def _normalize(fmt: str, path=None) -> str:
    key = fmt.strip().lower().lstrip(".")
    key = _ALIASES.get(key, key)
    if key not in FORMATS:
        raise FormatError(f"unknown format {fmt!r}; known formats: {', '.join(FORMATS)}", path)
    return key


def _sniff(path: Path) -> str | None:
    """Guess a format from the first bytes (None when nothing matches)."""
    try:
        size = path.stat().st_size
        with open(path, "rb") as fh:
            head = fh.read(4096)
    except OSError:
        return None
    if head.startswith(b"tensor_file\0"):  # the RGL tensor file's magic (roughbrdf.io.rgl)
        return "rgl"
    if size >= 12:
        import numpy as np

        dims = np.frombuffer(head[:12], dtype="<i4")
        if dims.tolist() == [90, 90, 180]:
            return "merl"
    try:
        text = decode(head, path)  # UTF-16/32 by their byte-order mark, as the readers do
    except FormatError:
        return None  # NUL bytes and no byte-order mark: no text format
    if text.lstrip().startswith("# roughbrdf-csv"):
        return "csv"
    if re.search(r"^#DIM\s+\d+\s+\d+", text, re.MULTILINE):
        return "alta"
    if re.search(r"^VARS\s", text, re.MULTILINE) and re.search(r"^NUM_POINTS\s", text,
                                                                 re.MULTILINE):
        return "astm"
    # LightTools BSDF: its blocks start with AOI lines (it shares Zemax's ScatterAzimuth N /
    # ScatterRadial N header lines, so it is told first; libbsdf's classifyFile does the same)
    if re.search(r"^\s*AOI\s", text, re.MULTILINE):
        return "lighttools"
    # Zemax tabular BSDF: the counted keywords of its header (comments may come first)
    counted = re.findall(r"^\s*(SampleRotation|AngleOfIncidence|ScatterAzimuth|ScatterRadial)"
                         r"\s+\d+\s*$", text, re.MULTILINE | re.IGNORECASE)
    if len({c.lower() for c in counted}) >= 2:
        return "zemax"
    return None


def format_for(path: str | os.PathLike, format: str | None = None) -> str:
    """The format name used for ``path``: ``format`` if given, else from the extension,
    else from the contents (for an existing file); raises :class:`FormatError` otherwise."""
    if format:
        return _normalize(format, path)
    p = Path(path)
    ext = p.suffix.lower()
    for name in FORMATS:
        if ext in _extensions(name):
            return name
    if p.is_file():
        guess = _sniff(p)
        if guess:
            return guess
    known = ", ".join(f"{e} ({n})" for n in FORMATS for e in _extensions(n))
    raise FormatError(f"unknown format for extension {ext or '(none)'!r}; known extensions: "
                      f"{known}; pass format= (CLI: --from/--to)", path)


def read(path: str | os.PathLike, format: str | None = None, **options: Any) -> Measurement:
    """Read a measurement file into a :class:`~roughbrdf.measurement.Measurement`.

    Parameters
    ----------
    path : str or path-like
    format : {"astm", "alta", "merl", "csv", "zemax", "lighttools", "rgl"}, optional
        Override the format chosen from the extension (a ``.bsdf`` file: by its contents).
    **options
        Passed to the format's reader, e.g. ``quantity="brdf_cos"`` (ALTA without
        ``#PARAM_OUT``), ``angles="deg"`` (ASTM), ``stride=4`` (MERL),
        ``sample_rotation="all"`` (Zemax, several sample rotations), ``side="back"``
        (LightTools: the other side's blocks). ``quantity=`` and
        ``angles=`` supply what the file does not say; if the file says otherwise they raise
        :class:`FormatError` (every reader accepts both).

    Raises
    ------
    FormatError
        Anything wrong with the file, naming it and, where one line is at fault, the line.
    FileNotFoundError
        No file at ``path``.

    Notes
    -----
    Values the instrument did not measure (a linear extrapolation to 0 at ``theta_r = 90``
    deg, :mod:`roughbrdf.extrapolation`) are recorded as ``meta["extrapolated_beyond"]``
    (radians); fits leave them out unless asked.
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"{p}: no such file")
    fmt = format_for(p, format)
    if format is None and p.suffix.lower() == ".bsdf":  # Zemax, LightTools or RGL: by content
        from .lighttools import sniff_bsdf
        from .rgl import sniff

        fmt = "rgl" if sniff(p) else sniff_bsdf(p)
    measurement = _module(fmt).read(p, **options)
    # samples the instrument's software filled in (roughbrdf.extrapolation): recorded in meta,
    # left out by fits unless asked; the values are not changed
    mark_extrapolated(measurement)
    return measurement


def write(measurement: Measurement, path: str | os.PathLike, format: str | None = None, *,
          overwrite: bool = False, **options: Any) -> Any:
    """Write a measurement in the format chosen from the extension (``format=`` overrides).

    Parameters
    ----------
    measurement : Measurement
    path : str or path-like
        The file to write; never the file ``measurement`` was read from.
    format : {"astm", "alta", "merl", "csv", "zemax", "lighttools"}, optional
        Override the format chosen from the extension (``.bsdf``: Zemax unless
        ``"lighttools"``).
    overwrite : bool
        Replace an existing file (default: refuse with :class:`FileExistsError`).
    **options
        Passed to the format's writer, e.g. ``angles="rad"`` (CSV, ASTM), ``resample=True``
        (MERL, Zemax: write even though the grid bins, averages or drops samples),
        ``channel=`` (Zemax: one channel a file).

    Returns
    -------
    MerlWriteReport, ZemaxWriteReport or None
        For MERL and Zemax, what the grid did to the samples; None for the other formats.

    Raises
    ------
    FileExistsError
        ``path`` exists and ``overwrite`` is false.
    roughbrdf.errors.ArgumentError
        ``path`` is the measurement's own input file (even with ``overwrite=True``), or MERL
        or Zemax would change the samples and ``resample`` is false.
    IsADirectoryError
        ``path`` is a folder.
    ValueError
        A measurement the format cannot hold (e.g. relative values in ASTM, Mueller elements
        in anything but CSV).
    """
    fmt = format_for(path, format)
    if fmt == "lighttools":  # its writer is a module of its own (the reader is long enough)
        from .lighttools_write import write_measurement

        return write_measurement(measurement, path, overwrite=overwrite, **options)
    mod = _module(fmt)
    if not hasattr(mod, "write"):
        raise FormatError(f"format {fmt!r} has no writer", path)
    if getattr(measurement, "mueller", None) and fmt != "csv":
        # the other formats would write the elements as plain BRDF channels: refuse
        raise ValueError(f"{path}: a measurement of Mueller elements ({measurement.mueller}) "
                         f"can be written as roughbrdf CSV only (its '# mueller:' line says "
                         f"what the columns hold); the {fmt} format has no place for that")
    return mod.write(measurement, path, overwrite=overwrite, **options)
