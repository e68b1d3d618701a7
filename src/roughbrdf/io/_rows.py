"""Reading the text of a measurement file and its rows of numbers, shared by the text readers.

* :func:`read_text` - the file's lines: a pipe or device (not a regular file) is read up to
  :data:`MAX_STREAM_BYTES` and refused beyond; a UTF-16 or UTF-32 file with a byte-order mark is
  decoded as such; a file with NUL bytes and no byte-order mark (UTF-16/32 without one, or a
  binary file) is refused, saying so; anything else is UTF-8, an undecodable byte (a stray
  Latin-1 ``°`` in a comment) becoming U+FFFD;
* :func:`begin_read` - the start of every text reader's ``read()``;
* :func:`parse_rows` - the numbers of the data rows, **checked row by row**: each row must have
  the expected number of fields, none empty, each a plain ASCII number (:func:`is_number`:
  optional sign, digits with an optional point and exponent, ``nan``, ``inf``, ``infinity``).
  An empty field, a blank inside a number (``1 5``), an underscore (``1_5``) or a non-ASCII
  digit (``１５``) is a :class:`~roughbrdf.io.FormatError` naming the file, the line and the
  column - never a number read from the wrong column;
* :func:`whole_number` and :func:`check_row_count` - a header's row count and the rows found.
"""

from __future__ import annotations

import codecs
import os
import re
import stat
import warnings
from pathlib import Path

import numpy as np

from ..quantity import Quantity
from ._common import FormatError, UnterminatedRowWarning, data_lines, outside_stacklevel

__all__ = ["MAX_STREAM_BYTES", "read_text", "begin_read", "is_number", "parse_number",
           "split_fields", "parse_rows", "decode", "whole_number", "check_row_count",
           "count_fields", "row_separator", "rows_from"]

#: the most bytes read from a file that is not a regular file (a pipe, ``/dev/zero``...), whose
#: size is not known beforehand: 1 GiB, far beyond any measurement; beyond it the file is refused
MAX_STREAM_BYTES = 1 << 30
#: bytes read at a time from a pipe or device
_CHUNK = 1 << 20

#: a plain number: what :func:`float` accepts, less underscores, blanks and non-ASCII digits
_NUMBER = re.compile(r"[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|inf(?:inity)?|nan)",
                     re.ASCII | re.IGNORECASE)
#: every byte a number can contain; with blanks and the separators, all a fast-path block may
#: hold (anything else sends the block to the row-by-row check)
_NUMBER_BYTES = b"0123456789.+-eEnNaAiIfFtTyY"
#: characters a number can end with: a file ending on one of them may end inside a number
_NUMBER_END = frozenset("0123456789.")
#: byte-order marks (UTF-32 first: its little-endian mark starts with UTF-16's)
_BOMS = ((codecs.BOM_UTF32_LE, "utf-32", "UTF-32"), (codecs.BOM_UTF32_BE, "utf-32", "UTF-32"),
         (codecs.BOM_UTF16_LE, "utf-16", "UTF-16"), (codecs.BOM_UTF16_BE, "utf-16", "UTF-16"))


# --------------------------------------------------------------------------------------------
# the file's text
# --------------------------------------------------------------------------------------------
def _check_no_nul(data: bytes, path: str | os.PathLike | None) -> None:
    """A file with NUL bytes and no byte-order mark is no UTF-8 text: refuse it, saying what it
    may be (read as UTF-8 it gives one NUL per character and nonsense keys)."""
    k = data.find(b"\0")
    if k >= 0:
        raise FormatError(f"NUL bytes (the first at byte {k}): not UTF-8 text - UTF-16 or UTF-32 "
                          "text without a byte-order mark, or a binary file; save it as UTF-8 "
                          "(UTF-16 and UTF-32 files with a byte-order mark are read)", path)


def _read_bytes(path: Path) -> bytes:
    """The file's bytes; a pipe or device at most :data:`MAX_STREAM_BYTES` of them."""
    with open(path, "rb") as fh:
        if stat.S_ISREG(os.fstat(fh.fileno()).st_mode):
            return fh.read()  # a regular file has a size: read whole, as every file always was
        # a pipe or device (/dev/zero) may never end: read at most the limit, and stop at once
        # on NUL bytes in the first chunk (the text check would refuse them anyway)
        limit = MAX_STREAM_BYTES
        parts: list[bytes] = []
        total = 0
        while chunk := fh.read(min(_CHUNK, limit + 1 - total)):
            parts.append(chunk)
            total += len(chunk)
            if total > limit:
                raise FormatError(f"not a regular file (a pipe or device) and longer than "
                                  f"{limit} bytes, the most read from one; not reading "
                                  "further (save it to a file to read it)", path)
            if len(parts) == 1 and not parts[0].startswith(tuple(b for b, _, _ in _BOMS)):
                _check_no_nul(chunk, path)
    return b"".join(parts)


def decode(data: bytes, path: str | os.PathLike | None) -> str:
    """The text of a file: UTF-16/32 by its byte-order mark, else UTF-8 (with or without a
    mark; undecodable bytes become U+FFFD, as a stray Latin-1 byte in a comment always did)."""
    for bom, codec, _ in _BOMS:
        if data.startswith(bom):
            return data.decode(codec, errors="replace")
    _check_no_nul(data, path)
    return data.decode("utf-8-sig", errors="replace")


def read_text(path: str | os.PathLike) -> list[str]:
    """The file's lines (no line ends); see the module docstring for encodings and pipes.

    Warns (:class:`~roughbrdf.io.UnterminatedRowWarning`) when the file ends inside a number
    without a final line end.
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"{p}: no such file")
    if p.is_dir():
        raise FormatError("is a directory, not a measurement file", p)
    text = decode(_read_bytes(p), p)
    lines = text.splitlines()
    if lines and text[-1] in _NUMBER_END and not lines[-1].lstrip().startswith("#"):
        tail = lines[-1].strip()[-24:]
        warnings.warn(f"{p}, line {len(lines)}: the file ends inside a number without a line "
                      f"end (...{tail!r}); the row is read, but its last number may be cut "
                      "short - check that the file is complete", UnterminatedRowWarning,
                      stacklevel=outside_stacklevel())
    return lines


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


# --------------------------------------------------------------------------------------------
# numbers
# --------------------------------------------------------------------------------------------
def is_number(tok: str) -> bool:
    """Whether ``tok`` is a plain ASCII number (see the module docstring)."""
    return _NUMBER.fullmatch(tok) is not None


def parse_number(tok: str) -> float:
    """``float(tok)`` for a plain ASCII number; ``ValueError`` for anything else (``1_5``,
    ``１５``, ``1 5``), which :func:`float` would partly accept."""
    if not is_number(tok):
        raise ValueError(f"not a plain number: {tok!r}")
    return float(tok)


def _field_problem(f: str) -> tuple[str, str] | None:
    """What is wrong with field ``f`` (stripped) and why it matters (``" (...)"`` or ``""``),
    None when it is a number."""
    if f == "":
        return "empty field", ""
    if is_number(f):
        return None
    if not f.isascii():
        odd = sorted({f"U+{ord(c):04X}" for c in f if not c.isascii()})
        why = ", bytes that are not UTF-8" if "\ufffd" in f else ""
        return (f"non-ASCII characters {', '.join(odd)} in the field {f!r}",
                f" (numbers are read in ASCII digits 0-9 only{why})")
    if "_" in f:
        return f"'_' in the field {f!r}", " (numbers are read without digit separators)"
    if any(c.isspace() for c in f) and all(is_number(p) for p in f.split()):
        return f"blank inside the field {f!r}", " (a number cannot contain blanks)"
    return f"non-numeric field {f!r}", ""


def split_fields(text: str, sep: str | None) -> list[str]:
    """Fields of one data line (``sep`` ``","`` or None for whitespace)."""
    if sep is None:
        return text.split()
    return [f.strip() for f in text.split(sep)]


def row_separator(text: str) -> str | None:
    """The separator of a data row: ``","`` when it has a comma, else None (blanks)."""
    return "," if "," in text else None


def count_fields(text: str, sep: str | None) -> int:
    """The number of fields of a data row (empty ones count, between separators)."""
    return text.count(sep) + 1 if sep is not None else len(text.split())


# --------------------------------------------------------------------------------------------
# rows
# --------------------------------------------------------------------------------------------
def _block_is_clean(joined: str, sep: str | None) -> bool:
    """Fast check of all rows at once (``joined``: the rows joined by ``"\\n"``): ASCII,
    nothing but number characters, blanks and separators, and - comma separated, with blanks -
    no empty field and no blank between two number characters of one field. True means every
    field is at most one token (and, without blanks, an empty field is none: the caller's count
    of tokens catches it), so splitting the block on blanks and separators keeps the rows
    aligned (the conversion still checks each token's grammar); False sends the rows to the
    row-by-row check, which names the culprit."""
    try:
        raw = joined.encode("ascii")
    except UnicodeEncodeError:
        return False
    seps = b"\n" + (b"," if sep is not None else b"")
    if raw.translate(None, _NUMBER_BYTES + b" \t" + seps):
        return False  # another character: '_', ';', a quote...
    if sep is None:
        return True   # blank separated: no empty fields, and each row's count was checked
    if b" " not in raw and b"\t" not in raw:
        # no blanks (the Mini-Diff files): no blank inside a field, and an empty field leaves
        # fewer tokens than fields, which the caller counts (cheaper than searching for ',,')
        return True
    cls = np.frombuffer(raw, dtype=np.uint8)
    blank = (cls == 0x20) | (cls == 0x09)
    idx = np.flatnonzero(~blank)
    is_sep = (cls[idx] == 0x2C) | (cls[idx] == 0x0A)
    gap = np.diff(idx) > 1
    # a blank between two number characters (``1 5``), or only blanks between two separators
    # or before the first / after the last (an empty field)
    return not (np.any(gap & ~is_sep[:-1] & ~is_sep[1:]) or np.any(is_sep[:-1] & is_sep[1:])
                or is_sep[0] or is_sep[-1])


def _rows_one_by_one(texts: list[str], linenos, ncols: int, path, sep: str | None,
                     what: str) -> np.ndarray:
    """The row-by-row parse: the first bad field is a FormatError naming its line and column;
    rows that are all good (e.g. with a non-ASCII blank between fields) are read."""
    out = np.empty((len(texts), ncols))
    for k, (t, ln) in enumerate(zip(texts, linenos, strict=True)):
        fields = split_fields(t, sep)
        if len(fields) != ncols:
            raise FormatError(f"wrong column count: expected {ncols} {what}, found "
                              f"{len(fields)}: {t.strip()!r}", path, int(ln))
        for j, f in enumerate(fields):
            problem = _field_problem(f)
            if problem is not None:
                raise FormatError(f"{problem[0]} in column {j + 1}{problem[1]}: {t.strip()!r}",
                                  path, int(ln))
        out[k] = [float(f) for f in fields]
    return out


def parse_rows(texts: list[str], linenos: list[int] | np.ndarray, ncols: int | tuple[int, ...],
               path, sep: str | None = None, what: str = "values") -> np.ndarray:
    """Parse data lines into a float array (n, ncols), or raise a FormatError naming the line.

    ``ncols`` may be a tuple of accepted column counts (all rows must then share one). Each
    row's field count is checked, then the whole block at once (:func:`_block_is_clean`) and
    converted with NumPy; a block that fails is parsed row by row, naming the first bad line
    and column (an empty field, a blank inside a number, ``1_5``, a non-ASCII digit...).
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
    joined = "\n".join(texts)
    if _block_is_clean(joined, sep):
        tokens = (joined.replace(sep, " ") if sep is not None else joined).split()
        # fewer tokens than fields: an empty field (not searched for by _block_is_clean)
        if len(tokens) == n * first:
            try:
                return np.array(tokens, dtype=float).reshape(n, first)
            except ValueError:
                pass  # a malformed number ('1e', '1-2'): the row-by-row parse names it
    return _rows_one_by_one(texts, linenos, first, path, sep, what)


def whole_number(text: str | None, key: str, path, line: int | None) -> int | None:
    """The whole number at the start of header value ``text`` (``NUM_POINTS 12964``), else a
    :class:`~roughbrdf.io.FormatError` naming ``key`` and its line; None for no ``text`` (the
    key is absent)."""
    if text is None:
        return None
    try:
        n = parse_number(text.split()[0])
    except (ValueError, IndexError):
        n = float("nan")
    if not (np.isfinite(n) and n >= 0 and n.is_integer()):
        raise FormatError(f"{key} must be a whole number of rows, got {text!r}", path, line)
    return int(n)


def rows_from(lines: list[str], start: int | None, path, missing: str
              ) -> tuple[list[str], list[int]]:
    """The data rows: the non-blank lines from index ``start`` on, stripped, with their 1-based
    line numbers; ``start`` None (no data row found) is a FormatError ``missing`` at the end."""
    if start is None:
        raise FormatError(missing, path, len(lines) + 1)
    return data_lines(lines, start)


def check_row_count(n_rows: int, declared: int | None, key: str, linenos, n_lines: int,
                    path) -> None:
    """The rows found against a header's count (``NUM_POINTS``): fewer is a truncated file
    (named at the end), more names the first extra row."""
    if declared is None or n_rows == declared:
        return
    if n_rows < declared:
        raise FormatError(f"truncated file: {key} is {declared} but only {n_rows} data rows "
                          f"follow (file ends at line {n_lines})", path, n_lines + 1)
    raise FormatError(f"{n_rows} data rows but {key} is {declared}; first extra row here", path,
                      linenos[declared])
