"""Helpers shared by the readers: the one exception class, the phases every text reader goes
through, and the two rules every reader applies.

A text reader's ``read()`` is a short sequence of phases, each reading one part of the file:

1. **header** - the keywords / metadata lines before the data (format specific);
2. **units** - the angle unit: :func:`resolve_angle_unit` chooses among the ``angles=`` option,
   the file's declarations (:class:`UnitClaim`) and the format's default; once the angles are
   read, :func:`warn_implausible_angles` warns (:class:`ImplausibleAnglesWarning`) when they
   look like the other unit (every zenith below 2 read as degrees, an angle above 2 pi read as
   radians);
3. **columns** - which column holds what (format specific);
4. **quantity** - what the values hold: :func:`resolve_quantity` chooses among the
   ``quantity=`` option, the file's declarations (:class:`QuantityClaim`) and the format's
   default;
5. **rows** - the numbers: :func:`data_lines` collects them with their line numbers,
   :func:`roughbrdf.io._rows.parse_rows` converts them (checked row by row, naming the first
   bad line and column), :func:`check_zenith_rows` and :func:`azimuth_rows` check the angle
   columns;

The file's text (encodings, a bounded read of pipes and devices) and the rows' numbers are
read by :mod:`roughbrdf.io._rows` (``read_text``, ``begin_read``, ``parse_rows``).

and ends in a :class:`~roughbrdf.measurement.Measurement`. Every problem is a
:class:`FormatError` naming the file and, where one line is at fault, the line; a header key
given twice is one (:func:`add_key`, naming both lines), and so is an option (``angles=``,
``quantity=``) that contradicts the file. A file that ends inside a number without a final line
end is read, with an :class:`UnterminatedRowWarning` naming the line.

The writers share :func:`prepare_target` (never an existing file unless ``overwrite=True``,
never the measurement's own input), :func:`write_table` (atomic, through
:func:`roughbrdf.output.staged`) and :func:`warn_not_written` (a :class:`LossyWriteWarning`
naming what the target format has no place for).
"""

from __future__ import annotations

import importlib
import math
import os
import sys
import warnings
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from ..errors import ArgumentError
from ..geometry import angles_from_vectors
from ..output import same_file, staged
from ..quantity import Quantity

__all__ = ["FormatError", "FormatWarning", "LossyWriteWarning", "UnterminatedRowWarning",
           "ImplausibleAnglesWarning", "outside_stacklevel", "add_key", "data_lines",
           "check_zenith_rows", "azimuth_rows", "common_frame_from_spherical", "angle_factor",
           "AngleUnit", "UnitClaim", "resolve_angle_unit", "warn_implausible_angles",
           "QuantityClaim", "resolve_quantity", "check_fixed_units", "prepare_target",
           "write_table", "warn_not_written", "header_not_written", "describe_keys",
           "write_bytes", "LAYOUT"]

HALF_PI = 0.5 * math.pi
#: angles this far beyond pi/2 (radians) are rounding in the file and are clipped to pi/2
ZENITH_SLACK = 1e-6


class FormatError(ValueError):
    """A file that cannot be read as the format it claims to be.

    The message starts with ``path`` and, where one line is at fault, ``line N`` (1-based);
    both are also attributes (``line`` is None for whole-file problems).
    """

    def __init__(self, message: str, path: str | os.PathLike | None = None,
                 line: int | None = None) -> None:
        self.path = None if path is None else str(path)
        self.line = line
        self.reason = message
        where = self.path or "<input>"
        if line is not None:
            where += f", line {line}"
        super().__init__(f"{where}: {message}")


class FormatWarning(UserWarning):
    """Base of the warnings of :mod:`roughbrdf.io` (a file read or written with a caveat)."""


class UnterminatedRowWarning(FormatWarning):
    """The file ends inside a number, without a final line end: the last row is read, but its
    last number may have been cut short (an interrupted copy or download). The message names
    the file and the line."""


class ImplausibleAnglesWarning(FormatWarning):
    """A file's angles look like the other unit: read as degrees, every zenith angle is below
    2 deg (radians, whose zeniths end at 1.57, read as degrees); read as radians, an angle is
    above 2 pi (degrees). The file is read as told; the message names the file, the largest
    angle, where the unit came from and the ``angles=`` option to use."""


class LossyWriteWarning(FormatWarning):
    """A writer had no place in the target format for part of the measurement (header keys of
    the source file, uncertainties...); the message names each of them."""


def outside_stacklevel() -> int:
    """``stacklevel`` for :func:`warnings.warn`, called from the function that warns, pointing
    at the first caller outside roughbrdf (the user's line, not the reader's)."""
    frame = sys._getframe(2)
    level = 2
    while frame is not None and str(frame.f_globals.get("__name__", "")).startswith(
            "roughbrdf"):
        frame = frame.f_back  # type: ignore[assignment]
        level += 1
    return level


def add_key(keys: dict[str, str], lines: dict[str, int], key: str, value: str, line: int,
            path, *, shown: str = "{key}") -> None:
    """Record header ``key`` (its ``value`` and 1-based ``line``); a key given twice is a
    :class:`FormatError` naming both lines - a file must not say one thing twice, since the
    reader cannot know which one is meant.

    ``shown`` formats the key for the message (``"#{key}"`` for ALTA).
    """
    if key in keys:
        name = shown.format(key=key)
        same = "the same value" if keys[key] == value else "different values"
        raise FormatError(f"{name} is given twice, with {same}: line {lines[key]} "
                          f"({keys[key]!r}) and line {line} ({value!r}); keep one", path, line)
    keys[key] = value
    lines[key] = line


def data_lines(lines: list[str], start: int, *, comments: str | tuple[str, ...] = ()
               ) -> tuple[list[str], list[int]]:
    """The non-blank lines from index ``start`` on, stripped, with their 1-based line numbers.

    Lines starting with one of ``comments`` (e.g. ``"#"``) are skipped as well.
    """
    texts: list[str] = []
    linenos: list[int] = []
    for i in range(start, len(lines)):
        s = lines[i].strip()
        if s and not (comments and s.startswith(comments)):
            texts.append(s)
            linenos.append(i + 1)
    return texts, linenos


def check_zenith_rows(values: np.ndarray, name: str, linenos, path, *, unit: str = "rad",
                      slack: float = ZENITH_SLACK) -> np.ndarray:
    """Check a zenith column (radians) row by row; clip rounding just past pi/2; name bad lines."""
    v = np.asarray(values, dtype=float)
    bad = ~np.isfinite(v)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise FormatError(f"{name} is {float(v[k])!r} (an angle must be a finite number); "
                          f"{int(bad.sum())} such rows", path, int(linenos[k]))
    out = (v < -slack) | (v > HALF_PI + slack)
    if out.any():
        k = int(np.flatnonzero(out)[0])
        shown = math.degrees(v[k])
        hint = ""
        if unit == "rad" and v[k] > 2 * math.pi:
            hint = (" - the angles look like degrees; declare the unit (angles='deg'; CLI: "
                    "--angles-in deg)")
        raise FormatError(f"{name} = {float(v[k])!r} rad ({shown:.6g} deg) is outside [0, 90] deg"
                          f"{hint}", path, int(linenos[k]))
    return np.clip(v, 0.0, HALF_PI)


def azimuth_rows(values: np.ndarray, name: str, linenos, path) -> np.ndarray:
    """Check an azimuth column is finite, naming the first bad line."""
    v = np.asarray(values, dtype=float)
    bad = ~np.isfinite(v)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise FormatError(f"{name} is {float(v[k])!r} (an angle must be a finite number); "
                          f"{int(bad.sum())} such rows", path, int(linenos[k]))
    return v


def common_frame_from_spherical(theta_l: np.ndarray, phi_l: np.ndarray, theta_v: np.ndarray,
                                phi_v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Common-frame angles of a source at (theta_l, phi_l) and a viewer at (theta_v, phi_v),
    both given in any one frame with the normal at +z (radians).

    Uses :func:`roughbrdf.geometry.angles_from_vectors` (which rotates the pair so the source is
    at azimuth pi); the zeniths are returned exactly as given (no arccos round trip).
    """
    sl, sv = np.sin(theta_l), np.sin(theta_v)
    w_l = np.stack([sl * np.cos(phi_l), sl * np.sin(phi_l), np.cos(theta_l)], axis=-1)
    w_v = np.stack([sv * np.cos(phi_v), sv * np.sin(phi_v), np.cos(theta_v)], axis=-1)
    _, _, phi = angles_from_vectors(w_l, w_v)
    # at normal incidence the source azimuth is undefined for the vectors; keep the file's
    at_pole = sl == 0.0
    if np.any(at_pole):
        d = np.mod(phi_v - phi_l + np.pi, 2 * np.pi)
        d = np.where(d > np.pi, d - 2 * np.pi, d)
        phi = np.where(at_pole, d, phi)
    return np.asarray(theta_l, float), np.asarray(theta_v, float), phi


_DEG_WORDS = ("deg", "degree", "degrees", "°")
_RAD_WORDS = ("rad", "radian", "radians")


def angle_factor(unit: str, path=None, line: int | None = None) -> float:
    """Factor from an angle unit word to radians (``deg`` -> pi/180, ``rad`` -> 1)."""
    u = unit.strip().lower().strip("[]()")
    if u in _DEG_WORDS:
        return math.pi / 180.0
    if u in _RAD_WORDS:
        return 1.0
    raise FormatError(f"unknown angle unit {unit!r}; use 'deg' or 'rad'", path, line)


def unit_word(unit: str, path=None, line: int | None = None) -> str:
    """Normalized unit name, ``deg`` or ``rad`` (:class:`FormatError` for anything else)."""
    return "deg" if angle_factor(unit, path, line) != 1.0 else "rad"


# --------------------------------------------------------------------------------------------
# the angle-unit rule
# --------------------------------------------------------------------------------------------
class AngleUnit(NamedTuple):
    """The angle unit of a file's angle columns and where it came from."""

    #: ``"deg"`` or ``"rad"``
    word: str
    #: where it came from: ``"option angles="``, ``"header ANGLE_UNITS"``, ``"VARS names"``,
    #: ``"default (radians)"``...
    source: str
    #: whether the file itself declares the unit (a header key, units in the column names)
    declared: bool = False

    @property
    def factor(self) -> float:
        """Factor from the file's numbers to radians."""
        return math.pi / 180.0 if self.word == "deg" else 1.0


@dataclass(frozen=True)
class UnitClaim:
    """One declaration of the angle unit found in a file.

    Attributes
    ----------
    words : tuple of str
        The unit word(s) as written (``"deg"``, ``"rad"``, ``"degrees"``...); several when the
        unit is given per column (``theta_i(deg), theta_s(deg)``).
    source : str
        Where the declaration is, as recorded in ``meta`` (``"header ANGLE_UNITS"``).
    text : str
        The declaration as messages quote it (``"'# angles: deg'"``, ``"VARS"``).
    line : int or None
        1-based line of the declaration.
    """

    words: tuple[str, ...]
    source: str
    text: str
    line: int | None = None

    def unit(self, path) -> str:
        """The one unit claimed (``deg``/``rad``); :class:`FormatError` for an unknown word or
        for several different units."""
        units = {unit_word(w, path, self.line) for w in self.words}
        if len(units) > 1:
            raise FormatError(f"{self.text} mixes angle units {sorted(units)}", path, self.line)
        return units.pop()


def _where(line: int | None) -> str:
    return "" if line is None else f" (line {line})"


def resolve_angle_unit(option: str | None, claims: Sequence[UnitClaim], path, *,
                       default: str | None = None, default_source: str = "default",
                       missing: str = "missing angle units",
                       missing_line: int | None = None) -> AngleUnit:
    """The angle unit of a file: the one rule of every reader.

    Every declaration in the file (``claims``) must name the same unit, and an ``angles=``
    option must name that unit too: a contradiction is a :class:`FormatError` naming both
    places. Where the file declares nothing, the option is used, else ``default``.

    Parameters
    ----------
    option : str or None
        The reader's ``angles=`` option (``deg``/``rad``; the CLI's ``--angles-in``).
    claims : sequence of UnitClaim
        The file's declarations, in the format's order of precedence (the first gives
        ``AngleUnit.source``).
    path
        The file, for error messages.
    default : {"rad", "deg"} or None
        The unit of a file that declares none; None means a declaration (or the option) is
        **required** and its absence is a :class:`FormatError` with message ``missing`` at
        ``missing_line``.
    default_source : str
        ``AngleUnit.source`` when ``default`` is used.

    Examples
    --------
    ASTM E1392: radians unless declared; CSV: a declaration is required::

        resolve_angle_unit(angles, [header, vars_names], path, default="rad")
        resolve_angle_unit(angles, [header, column_suffixes], path,
                           missing="missing angle units: ...", missing_line=column_line)
    """
    wanted = None if option is None else unit_word(option, path)
    if not claims:
        if wanted is not None:
            return AngleUnit(wanted, "option angles=")
        if default is None:
            raise FormatError(missing, path, missing_line)
        return AngleUnit(unit_word(default, path), default_source)
    first, *others = claims
    unit = first.unit(path)
    for other in others:
        if {unit_word(w, path, other.line) for w in other.words} != {unit}:
            raise FormatError(f"{first.text}{_where(first.line)} contradicts {other.text}"
                              f"{_where(other.line)}", path, other.line)
    if wanted is not None and wanted != unit:
        raise FormatError(f"angles={wanted!r} (CLI: --angles-in {wanted}) contradicts "
                          f"{first.text}{_where(first.line)}, which says {unit}", path,
                          first.line)
    return AngleUnit(unit, first.source, declared=True)


#: read as degrees, a file whose every zenith angle is below this (deg) looks like radians
RADIAN_LIKE_DEG = 2.0
#: read as radians, a file with an angle above this (rad) looks like degrees
DEGREE_LIKE_RAD = 2 * math.pi + 1e-6


def warn_implausible_angles(unit: AngleUnit, path, zeniths: Sequence[np.ndarray],
                            azimuths: Sequence[np.ndarray] = (), *,
                            names: str = "theta_i and theta_r", fixed: str = "") -> None:
    """Warn (:class:`ImplausibleAnglesWarning`) when a file's angles, as written in it (in
    ``unit``), look like the other unit; also when the file declares ``unit`` itself (the
    numbers are implausible all the same).

    Parameters
    ----------
    unit : AngleUnit
        The unit the angles were read in (:func:`resolve_angle_unit`).
    path
        The file, for the message.
    zeniths, azimuths : sequence of arrays
        The angle columns as written in the file (finite: checked before). Read as degrees,
        the warning needs every zenith below :data:`RADIAN_LIKE_DEG` (and one above 0: zeros
        are the same in both units); read as radians, any zenith or azimuth above
        :data:`DEGREE_LIKE_RAD`.
    names : str
        The zenith columns, as the message calls them.
    fixed : str
        For a format whose unit is fixed by its definition (ALTA): the advice of the message.
    """
    z = [np.abs(np.asarray(a, dtype=float)) for a in zeniths if np.size(a)]
    if unit.word == "deg":
        top = max((float(a.max()) for a in z), default=0.0)
        if not 0.0 < top < RADIAN_LIKE_DEG:
            return
        other, seen = "rad", f"every {names} is below {RADIAN_LIKE_DEG:g} deg (the largest is " \
            f"{top:.6g})"
        looks = "radians"
    else:
        a = [*z, *(np.abs(np.asarray(v, dtype=float)) for v in azimuths if np.size(v))]
        top = max((float(v.max()) for v in a), default=0.0)
        if not top > DEGREE_LIKE_RAD:
            return
        other, seen, looks = "deg", f"an angle is {top:.6g}, above 2 pi", "degrees"
    if fixed:
        advice = fixed
    elif unit.declared:
        advice = "if they are, correct the file's declaration"
    else:
        advice = f"if they are, read the file with angles={other!r}"
    warnings.warn(f"{path}: {seen}, with the angles read in {unit.word} ({unit.source}): they "
                  f"look like {looks}; {advice}", ImplausibleAnglesWarning,
                  stacklevel=outside_stacklevel())


def check_fixed_units(fmt: str, angles: str | None, quantity: object, path,
                      quantities: Sequence[Quantity] = (Quantity.BRDF,)) -> None:
    """For a format whose angle unit and quantity are fixed by its definition (ALTA angles are
    radians; MERL holds BRDF): an ``angles=`` or ``quantity=`` option that says otherwise
    contradicts the file (:class:`FormatError`)."""
    if angles is not None and unit_word(angles, path) != "rad":
        raise FormatError(f"angles={angles!r} (CLI: --angles-in {angles}) contradicts the {fmt} "
                          "format, whose angles are radians by definition", path)
    if quantity is not None and quantities:
        q = Quantity.parse(quantity, "quantity")
        if not any(_agrees(q, k) for k in quantities):
            raise FormatError(f"quantity={q.value!r} (CLI: --quantity {q.value}) contradicts "
                              f"the {fmt} format, which holds "
                              f"{' or '.join(k.value for k in quantities)}", path)


# --------------------------------------------------------------------------------------------
# the quantity rule
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class QuantityClaim:
    """What a file says its values hold.

    Attributes
    ----------
    quantity : Quantity or None
        The quantity declared; None when the file names something that is not a BRDF quantity
        (``MEAS_NAME BTDF``, ``#PARAM_OUT RGB_COLOR``): an error (``problem``) unless the
        ``quantity=`` option says what the values hold.
    source : str
        The declaration as written (``"#PARAM_OUT INV_STERADIAN"``, ``"MEAS_NAME BRDF"``).
    line : int or None
        1-based line of the declaration.
    problem : str
        Message for an unknown declaration (``quantity`` None).
    """

    quantity: Quantity | None
    source: str
    line: int | None = None
    problem: str = ""


def _agrees(a: Quantity, b: Quantity) -> bool:
    """Whether two quantities name the same values (brdf_cos and bridf are the same numbers)."""
    return a == b or (a.cosine_weighted and b.cosine_weighted)


def resolve_quantity(option: object, claims: Sequence[QuantityClaim], path, *,
                     default: Quantity | None = None, default_source: str = "default",
                     fallback: QuantityClaim | None = None, missing: str = "missing quantity",
                     missing_line: int | None = None) -> tuple[Quantity, str]:
    """What a file's values hold, and where that was said: the one rule of every reader.

    The file's declarations (``claims``) must agree with each other, and a ``quantity=``
    option with every known one (``brdf_cos`` and ``bridf`` agree): a contradiction is a
    :class:`FormatError` naming both places. A claim whose quantity is unknown (``MEAS_NAME
    BTDF``) is an error unless the option says what the values hold. Where the file declares
    nothing, the option is used, then ``fallback`` (a hint such as a CSV value column named
    ``brdf``, never checked), then ``default`` (None: :class:`FormatError` ``missing`` at
    ``missing_line``).

    Returns
    -------
    (Quantity, str)
        The quantity and its source (the first declaration's text, or ``"option quantity="``).
    """
    known = [c for c in claims if c.quantity is not None]
    for other in known[1:]:
        first = known[0]
        if not _agrees(first.quantity, other.quantity):  # type: ignore[arg-type]
            raise FormatError(f"{first.source}{_where(first.line)} contradicts "
                              f"{other.source}{_where(other.line)}", path, other.line)
    if option is not None:
        q = Quantity.parse(option, "quantity")
        for claim in known:
            if not _agrees(q, claim.quantity):  # type: ignore[arg-type]
                raise FormatError(f"quantity={q.value!r} (CLI: --quantity {q.value}) "
                                  f"contradicts {claim.source}{_where(claim.line)}, which "
                                  f"says {claim.quantity.value}", path,  # type: ignore[union-attr]
                                  claim.line)
        return q, known[0].source if known else "option quantity="
    if claims:
        claim = known[0] if known else claims[0]
        if claim.quantity is None:
            raise FormatError(claim.problem or f"{claim.source} is not a BRDF quantity", path,
                              claim.line)
        return claim.quantity, claim.source
    if fallback is not None and fallback.quantity is not None:
        return fallback.quantity, fallback.source
    if default is None:
        raise FormatError(missing, path, missing_line)
    return Quantity.parse(default), default_source


# --------------------------------------------------------------------------------------------
# writing
# --------------------------------------------------------------------------------------------
#: what :func:`header_not_written` calls a header key that describes the data's layout
#: (column names, counts, unit and quantity declarations): every writer writes its own
LAYOUT = "<layout>"


def prepare_target(measurement: Any, path: str | os.PathLike, overwrite: bool) -> Path:
    """Check a writer's target before any work: not the measurement's own input file (even with
    ``overwrite=True``: :class:`~roughbrdf.errors.ArgumentError` for ``path``), not a folder
    (:class:`IsADirectoryError`), not an existing file unless ``overwrite``
    (:class:`FileExistsError` naming it)."""
    target = Path(path)
    meta = getattr(measurement, "meta", {}) or {}
    for key in ("file", "file_abs"):
        src = meta.get(key)
        if isinstance(src, str) and src and same_file(src, target):
            raise ArgumentError("path", f"{target} is the file this measurement was read from; "
                                "write to another file (a measurement never replaces its own "
                                "input, even with overwrite=True)")
    if target.is_dir():
        raise IsADirectoryError(f"{target} is a folder, not a file; give a file name")
    if target.exists() and not overwrite:
        raise FileExistsError(f"{target} exists; not overwriting it (pass overwrite=True; "
                              "CLI: --force)")
    return target


def write_table(path: Path, head: str, table: np.ndarray, *, delimiter: str, overwrite: bool,
                fmt: str = "%.17g") -> None:
    """Write ``head`` then ``table`` (``numpy.savetxt`` rows, LF line ends) atomically:
    a temporary file beside ``path`` renamed over it (:func:`roughbrdf.output.staged`), so an
    error or Ctrl-C leaves the old file or none, never a partial one."""
    with staged(path, overwrite=overwrite) as fh:
        fh.write(head)
        np.savetxt(fh, table, delimiter=delimiter, fmt=fmt, newline="\n")


def write_bytes(path: Path, parts: Iterable[bytes], *, overwrite: bool) -> None:
    """Write ``parts`` one after the other atomically (see :func:`write_table`)."""
    with staged(path, overwrite=overwrite, binary=True) as fh:
        for part in parts:
            fh.write(part)


def _header_field(fmt: str) -> Callable[[str], str | None]:
    mod = importlib.import_module(f"{__package__}.{fmt}")
    return getattr(mod, "header_field", lambda key: None)


def header_not_written(meta: dict[str, Any], target: str, fields: Iterable[str]) -> list[str]:
    """Header keys of the source file (``meta["header"]``, read from format ``meta["format"]``)
    that a ``target`` writer, which writes the provenance ``fields`` (``"sample"``...), has no
    place for. A file written in its own format keeps every key (the writer writes them
    back), so the list is then empty, as it is for a measurement not read from a file."""
    src = meta.get("format")
    header = meta.get("header")
    if src == target or not isinstance(header, dict) or not header or src not in (
            "astm", "alta", "csv", "zemax"):
        return []
    field_of = _header_field(str(src))
    kept = set(fields)
    lost = [k for k in header if field_of(k) != LAYOUT and field_of(k) not in kept]
    if src == "zemax":  # what a Zemax table holds besides its header keywords
        lost += [what for k, what in (("zemax_tis", "TIS"), ("comments", "# comments"))
                 if meta.get(k)]
    return lost


def warn_not_written(path: Path, target: str, items: Sequence[str]) -> None:
    """One :class:`LossyWriteWarning` naming everything the ``target`` file cannot hold."""
    if items:
        warnings.warn(f"{path}: the {target} format has no place for {'; '.join(items)} - not "
                      "written", LossyWriteWarning, stacklevel=outside_stacklevel())


def describe_keys(keys: Sequence[str], source: str) -> str:
    """``"the astm header keys APERTURE, FILE_NAME"`` for :func:`warn_not_written`."""
    word = "key" if len(keys) == 1 else "keys"
    return f"the {source} header {word} {', '.join(keys)}"

