"""What the text readers do with the
bytes of a file.

* A UTF-16 or UTF-32 file with a byte-order mark is read (decoded as such); one without a mark
  (NUL bytes) is refused with a message naming UTF-16 - it used to be read as UTF-8, a NUL per
  character, and refused for a "duplicated key".
* A stray Latin-1 byte in a comment still reads (as U+FFFD).
* A pipe or device (``/dev/zero``, a FIFO) is read up to ``roughbrdf.io._rows.MAX_STREAM_BYTES``
  and refused beyond, naming the file and the limit - it used to be read without end.
"""

from __future__ import annotations

import codecs
import os
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.io import FormatError

ASTM = """SAMPLE_NAME S1
MEAS_NAME BRDF
NUM_POINTS 3
VARS theta_i,phi_i,theta_s,phi_s,465nm
0,3.141592653589793,0.1,0,1.5
0,3.141592653589793,0.2,0,1.25
0.5,3.141592653589793,0.5,0,3.0
"""

CSV = """# roughbrdf-csv 1
# angles: deg
# quantity: brdf
theta_i,theta_r,phi,465nm
0,10,0,0.5
30,30,0,2.0
30,30,180,0.1
"""


#: the limit of a read from a pipe or device (a module constant, lowered here)
LIMIT = "roughbrdf.io._rows.MAX_STREAM_BYTES"


def _expected() -> np.ndarray:
    return np.array([[1.5], [1.25], [3.0]])


@pytest.mark.parametrize("encoding, bom", [
    ("utf-16", b""),                             # Python writes the mark of its byte order
    ("utf-16-be", codecs.BOM_UTF16_BE),
    ("utf-32", b""),
    ("utf-32-be", codecs.BOM_UTF32_BE),
])
def test_utf16_and_utf32_files_with_a_byte_order_mark_are_read(tmp_path, encoding, bom):
    """Why: a UTF-16 file (Windows' "Unicode" text) was refused for a key "given twice"."""
    p = tmp_path / "u.astm"
    p.write_bytes(bom + ASTM.replace("\n", "\r\n").encode(encoding))
    m = rb.read(p)
    np.testing.assert_array_equal(m.values, _expected())
    assert m.meta["sample"] == "S1"


def test_a_utf16_file_of_unknown_extension_is_recognized_by_its_contents(tmp_path):
    """Why: the contents were looked at as UTF-8 only: a UTF-16 ASTM file named ``.txt`` was an
    'unknown format'."""
    p = tmp_path / "u.txt"
    p.write_bytes(ASTM.encode("utf-16"))
    np.testing.assert_array_equal(rb.read(p).values, _expected())


@pytest.mark.parametrize("encoding", ["utf-16-le", "utf-16-be"])
@pytest.mark.parametrize("fmt, text, ext", [("astm", ASTM, ".astm"), ("csv", CSV, ".csv")])
def test_utf16_without_byte_order_mark_is_refused_naming_utf16(tmp_path, encoding, fmt, text,
                                                               ext):
    """Why: read as UTF-8, the NUL after each character made nonsense keys, and the file was
    refused for a key given twice (or a missing VARS line) - not for its encoding."""
    p = tmp_path / f"u{ext}"
    p.write_bytes(text.encode(encoding))
    with pytest.raises(FormatError, match=r"NUL bytes .*UTF-16 or UTF-32 text without a "
                                          r"byte-order mark") as info:
        rb.read(p)
    assert "twice" not in str(info.value)
    assert str(info.value).startswith(f"{p}: ")


def test_a_latin1_byte_in_a_comment_still_reads(tmp_path):
    """A regression guard (this read before too): a stray Latin-1 byte is no reason to refuse
    a file - only NUL bytes are."""
    p = tmp_path / "l.astm"
    p.write_bytes(ASTM.replace("VARS", "# temp\xe9rature 20 \xb0C\nVARS").encode("latin-1"))
    m = rb.read(p)
    np.testing.assert_array_equal(m.values, _expected())


needs_posix = pytest.mark.skipif(sys.platform == "win32" or not hasattr(os, "mkfifo"),
                                 reason="needs /dev/zero and FIFOs (POSIX)")


@needs_posix
def test_dev_zero_is_refused_at_the_limit_naming_file_and_limit(monkeypatch):
    """Why: ``rb.read("/dev/zero", format=...)`` read without end (memory, then the machine)."""
    if not Path("/dev/zero").exists():
        pytest.skip("no /dev/zero")
    monkeypatch.setattr(LIMIT, 4096)
    with pytest.raises(FormatError, match=r"^/dev/zero: not a regular file \(a pipe or device\) "
                                          r"and longer than 4096 bytes"):
        rb.read("/dev/zero", format="astm")


def _feed(fifo: Path, data: bytes) -> threading.Thread:
    """A thread writing ``data`` into ``fifo`` (it ends when the reader closes its end)."""
    def run() -> None:
        try:
            with open(fifo, "wb") as fh:
                fh.write(data)
        except BrokenPipeError:
            pass  # the reader stopped at its limit: expected
    t = threading.Thread(target=run, daemon=True)
    t.start()
    return t


@needs_posix
def test_a_fifo_fed_more_than_the_limit_is_refused(tmp_path, monkeypatch):
    """Why: a pipe was read to its end, however long (a FIFO fed by ``yes``, ``cat /dev/zero``)."""
    monkeypatch.setattr(LIMIT, 1000)
    fifo = tmp_path / "feed.csv"
    os.mkfifo(fifo)
    writer = _feed(fifo, (CSV + "30,40,0,0.5\n" * 2000).encode())
    with pytest.raises(FormatError, match=r"longer than 1000 bytes") as info:
        rb.read(fifo, format="csv")
    assert str(info.value).startswith(f"{fifo}: ")
    writer.join(timeout=60)
    assert not writer.is_alive()


@needs_posix
def test_a_fifo_within_the_limit_is_read(tmp_path, monkeypatch):
    monkeypatch.setattr(LIMIT, 1000)
    fifo = tmp_path / "feed.csv"
    os.mkfifo(fifo)
    writer = _feed(fifo, CSV.encode())
    m = rb.read(fifo, format="csv")
    writer.join(timeout=60)
    np.testing.assert_array_equal(m.values, [[0.5], [2.0], [0.1]])
