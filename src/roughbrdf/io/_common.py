"""Helpers shared by the readers: the one exception class, the phases every text reader goes
through, and the two rules every reader applies.

A text reader's ``read()`` is a short sequence of phases, each reading one part of the file:

1. **header** - the keywords / metadata lines before the data (format specific);
2. **units** - the angle unit: :func:`resolve_angle_unit` chooses among the ``angles=`` option,
   the file's declarations (:class:`UnitClaim`) and the format's default;
3. **columns** - which column holds what (format specific);
4. **quantity** - what the values hold: :func:`resolve_quantity` chooses among the
   ``quantity=`` option, the file's declarations (:class:`QuantityClaim`) and the format's
   default;
5. **rows** - the numbers: :func:`data_lines` collects them with their line numbers,
   :func:`parse_rows` converts them (naming the first bad line), :func:`check_zenith_rows` and
   :func:`azimuth_rows` check the angle columns;

and ends in a :class:`~roughbrdf.measurement.Measurement`. Every problem is a
:class:`FormatError` naming the file and, where one line is at fault, the line.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..geometry import angles_from_vectors
from ..quantity import Quantity

__all__ = ["FormatError", "read_text", "begin_read", "data_lines", "parse_rows",
           "check_zenith_rows", "azimuth_rows", "common_frame_from_spherical", "angle_factor",
           "AngleUnit", "UnitClaim", "resolve_angle_unit", "QuantityClaim", "resolve_quantity"]

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


def read_text(path: str | os.PathLike) -> list[str]:
    """The file's lines (no line ends). Undecodable bytes become U+FFFD instead of failing."""
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"{p}: no such file")
    if p.is_dir():
        raise FormatError("is a directory, not a measurement file", p)
    with open(p, encoding="utf-8-sig", errors="replace", newline=None) as fh:
        return fh.read().splitlines()


def begin_read(fmt: str, path: str | os.PathLike, options: dict, quantity: object = None
               ) -> tuple[Path, list[str]]:
    """Shared start of the text readers: reject unknown options and quantities, read the lines.

    Raises ``TypeError`` for an unknown option and ``ValueError`` (from
    :meth:`~roughbrdf.quantity.Quantity.parse`) for a ``quantity=`` that is not a quantity.
    """
    if options:
        raise TypeError(f"{fmt}.read got unknown options {sorted(options)}")
    if quantity is not None:
        Quantity.parse(quantity, "quantity")
    return Path(path), read_text(path)


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


def _is_number(tok: str) -> bool:
    try:
        float(tok)
    except ValueError:
        return False
    return True


def split_fields(text: str, sep: str | None) -> list[str]:
    """Fields of one data line (``sep`` ``","`` or None for whitespace)."""
    if sep is None:
        return text.split()
    return [f.strip() for f in text.split(sep)]


def parse_rows(texts: list[str], linenos: list[int] | np.ndarray, ncols: int | tuple[int, ...],
               path, sep: str | None = None, what: str = "values") -> np.ndarray:
    """Parse data lines into a float array (n, ncols) fast, or raise a FormatError naming the line.

    ``ncols`` may be a tuple of accepted column counts (all rows must then share one).
    The fast path joins all lines and converts once with NumPy; only on failure are the lines
    examined one by one to name the first bad one.
    """
    accepted = (ncols,) if isinstance(ncols, int) else tuple(ncols)
    n = len(texts)
    if n == 0:
        return np.empty((0, accepted[0]))
    if sep is None:
        counts = np.fromiter((len(t.split()) for t in texts), dtype=np.int64, count=n)
    else:
        counts = np.fromiter((t.count(sep) for t in texts), dtype=np.int64, count=n) + 1
    first = int(counts[0])
    if first not in accepted:
        exp = " or ".join(str(a) for a in accepted)
        raise FormatError(f"expected {exp} {what} per row, found {first}: {texts[0].strip()!r}",
                          path, int(linenos[0]))
    bad = np.flatnonzero(counts != first)
    if bad.size:
        k = int(bad[0])
        raise FormatError(f"wrong column count: expected {first} {what} (as in the first data "
                          f"row, line {int(linenos[0])}), found {int(counts[k])}: "
                          f"{texts[k].strip()!r}", path, int(linenos[k]))
    joined = " ".join(texts)
    if sep is not None:
        joined = joined.replace(sep, " ")
    tokens = joined.split()
    try:
        if len(tokens) != n * first:
            raise ValueError("empty field")
        arr = np.array(tokens, dtype=float)
    except ValueError:
        for t, ln in zip(texts, linenos, strict=True):
            for j, f in enumerate(split_fields(t, sep)):
                if f == "":
                    raise FormatError(f"empty field in column {j + 1}: {t.strip()!r}", path,
                                      int(ln)) from None
                if not _is_number(f):
                    raise FormatError(f"non-numeric field {f!r} in column {j + 1}", path,
                                      int(ln)) from None
        raise  # pragma: no cover - the loop above always finds the culprit
    return arr.reshape(n, first)


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
            hint = " - the angles look like degrees; declare the unit (angles='deg')"
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


def resolve_angle_unit(option: str | None, claims: Sequence[UnitClaim], path, *,
                       default: str | None = None, default_source: str = "default",
                       agree: bool = False, missing: str = "missing angle units",
                       missing_line: int | None = None) -> AngleUnit:
    """The angle unit of a file: the one rule of every reader.

    Precedence: the ``angles=`` option (never checked against the file), then the first of the
    file's ``claims`` (in the format's order of precedence), then ``default``.

    Parameters
    ----------
    option : str or None
        The reader's ``angles=`` option (``deg``/``rad``; the CLI's ``--angles-in``).
    claims : sequence of UnitClaim
        The file's declarations, highest precedence first.
    path
        The file, for error messages.
    default : {"rad", "deg"} or None
        The unit of a file that declares none; None means a declaration is **required** and
        its absence is a :class:`FormatError` with message ``missing`` at ``missing_line``.
    default_source : str
        ``AngleUnit.source`` when ``default`` is used.
    agree : bool
        If true, every claim must name the unit of the first (``"{first.text} contradicts
        {other.text}"`` at the other's line); if false the first claim wins and the others are
        not looked at.

    Examples
    --------
    ASTM E1392: radians unless declared; CSV: a declaration is required::

        resolve_angle_unit(angles, [header, vars_names], path, default="rad")
        resolve_angle_unit(angles, [header, column_suffixes], path, agree=True,
                           missing="missing angle units: ...", missing_line=column_line)
    """
    if option is not None:
        return AngleUnit(unit_word(option, path), "option angles=")
    if not claims:
        if default is None:
            raise FormatError(missing, path, missing_line)
        return AngleUnit(unit_word(default, path), default_source)
    first, *others = claims
    unit = first.unit(path)
    if agree:
        for other in others:
            if {unit_word(w, path, other.line) for w in other.words} != {unit}:
                raise FormatError(f"{first.text} contradicts {other.text}", path, other.line)
    return AngleUnit(unit, first.source)


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


def resolve_quantity(option: object, claims: Sequence[QuantityClaim], path, *,
                     default: Quantity | None = None, default_source: str = "default",
                     agree: bool = False, missing: str = "missing quantity",
                     missing_line: int | None = None) -> tuple[Quantity, str]:
    """What a file's values hold, and where that was said: the one rule of every reader.

    Precedence: the ``quantity=`` option, then the first of the file's ``claims``, then
    ``default`` (None: a declaration is required; :class:`FormatError` ``missing`` at
    ``missing_line``). With ``agree``, an option must agree with every known claim, the
    cosine-weighted quantities (``brdf_cos``, ``bridf``) agreeing with each other; the source is
    then the claim's. Without ``agree`` the option wins unchecked (source ``"option quantity="``).

    Returns
    -------
    (Quantity, str)
        The quantity and its source.
    """
    if option is not None:
        q = Quantity.parse(option, "quantity")
        source = "option quantity="
        for claim in claims if agree else ():
            if claim.quantity is None:
                continue
            if q != claim.quantity and not (q.cosine_weighted and claim.quantity.cosine_weighted):
                raise FormatError(f"quantity={q.value!r} contradicts {claim.source} "
                                  f"({claim.quantity.value})", path, claim.line)
            source = claim.source
        return q, source
    if claims:
        claim = claims[0]
        if claim.quantity is None:
            raise FormatError(claim.problem or f"{claim.source} is not a BRDF quantity", path,
                              claim.line)
        return claim.quantity, claim.source
    if default is None:
        raise FormatError(missing, path, missing_line)
    return Quantity.parse(default), default_source
