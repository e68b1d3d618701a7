"""Helpers shared by the readers: the one exception class, fast numeric parsing of text rows
with line-accurate diagnostics, and angle checks that name the offending line."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from ..geometry import angles_from_vectors

__all__ = ["FormatError", "read_text", "parse_rows", "check_zenith_rows", "azimuth_rows",
           "common_frame_from_spherical", "angle_factor"]

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


def begin_read(fmt: str, path: str | os.PathLike, options: dict, quantity: str | None = None
               ) -> tuple[Path, list[str]]:
    """Shared start of the text readers: reject unknown options and quantities, read the lines."""
    from ..measurement import QUANTITIES

    if options:
        raise TypeError(f"{fmt}.read got unknown options {sorted(options)}")
    if quantity is not None and quantity not in QUANTITIES:
        raise ValueError(f"quantity must be one of {QUANTITIES}, got {quantity!r}")
    return Path(path), read_text(path)


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


def unit_word(unit: str) -> str:
    """Normalized unit name, ``deg`` or ``rad``."""
    return "deg" if angle_factor(unit) != 1.0 else "rad"
