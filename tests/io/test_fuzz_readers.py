"""Fuzz the readers with mutated real files: every outcome is a Measurement or a FormatError.

The seeds are small real files: the header and a few hundred rows of each Mini-Diff ``.astm``
and CEA ALTA ``.dat`` file in ``../shared/data`` (the text formats skip without it), the
roughbrdf CSV written from them, and a MERL binary written from a model on a coarse grid.
Hypothesis mutates them - truncates anywhere, duplicates, drops or swaps lines, flips bytes,
inserts bytes, edits header keys and values, changes separators, units and quantities - and
:func:`roughbrdf.read` must return a :class:`Measurement` with finite angles in range, or raise
:class:`~roughbrdf.io.FormatError`: never another exception, never a hang (each read has a 20 s
alarm where the platform has one). Warnings are allowed.

Bounded: ``MAX_EXAMPLES`` examples per format, no per-example deadline; the whole file runs in
well under a minute.
"""

from __future__ import annotations

import contextlib
import math
import signal
import threading
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import roughbrdf as rb
from roughbrdf.io import FormatError, merl
from roughbrdf.measurement import Measurement

MAX_EXAMPLES = 150
#: rows kept from each real file (spread over the whole file, so every incidence is present)
ROWS = 300
#: seconds one read may take before it counts as a hang
HANG_SECONDS = 20

FUZZ = settings(max_examples=MAX_EXAMPLES, deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow, HealthCheck.data_too_large])


# --------------------------------------------------------------------------------------------
# seeds
# --------------------------------------------------------------------------------------------
def _small_astm(path: Path) -> bytes:
    """Header + ROWS rows of an ASTM file, NUM_POINTS set to match."""
    lines = path.read_text().splitlines()
    start = next(i for i, s in enumerate(lines) if s[:1].isdigit())
    rows = [s for s in lines[start:] if s.strip()]
    rows = rows[::max(1, len(rows) // ROWS)]
    head = [f"NUM_POINTS {len(rows)}" if s.startswith("NUM_POINTS") else s
            for s in lines[:start]]
    return ("\n".join(head + rows) + "\n").encode()


def _small_alta(path: Path) -> bytes:
    """``#`` header + ROWS rows of an ALTA file."""
    lines = path.read_text().splitlines()
    head = [s for s in lines if s.startswith("#")]
    rows = [s for s in lines if s.strip() and not s.startswith("#")]
    return ("\n".join(head + rows[::max(1, len(rows) // ROWS)]) + "\n").encode()


class _Seeds(dict):
    """format -> [(extension, bytes, read options)]; shown short in Hypothesis's reports."""

    #: why a format has no seeds (the real files are absent)
    missing = ""

    def __repr__(self) -> str:
        return f"<seeds: {', '.join(f'{len(v)} {k}' for k, v in self.items())}>"


@pytest.fixture(scope="module")
def seeds(request, tmp_path_factory) -> _Seeds:
    """format -> [(extension, bytes, read options)]; the text formats only with the real
    files of ../shared/data (the ``shared_data`` fixture), the MERL file always."""
    d = tmp_path_factory.mktemp("seeds")
    out = _Seeds(astm=[], alta=[], csv=[], merl=[])
    mdl = rb.model("microfacet", distribution="ggx", alpha=0.3, shadowing="smith", n=1.5, k=0.0)
    mp = d / "model.binary"  # a coarse grid keeps the file small (24 kB)
    merl.write_table(mp, merl.table_from_model(mdl, dims=(6, 6, 12)))
    out["merl"].append((".binary", mp.read_bytes(), {}))
    try:
        shared_data = request.getfixturevalue("shared_data")
    except pytest.skip.Exception as exc:
        out.missing = str(exc)
        return out
    for p in sorted((shared_data / "minidiff").glob("*.astm")):
        out["astm"].append((".astm", _small_astm(p), {}))
    for p in sorted((shared_data / "cea_retro").glob("*.dat")):
        opts = {} if b"#PARAM_OUT" in p.read_bytes()[:2000] else {"quantity": "brdf_cos"}
        out["alta"].append((".dat", _small_alta(p), opts))
    for fmt, ext in (("astm", ".astm"), ("alta", ".dat")):
        for k, (_, raw, opts) in enumerate(out[fmt]):
            src = d / f"{fmt}{k}{ext}"
            src.write_bytes(raw)
            dst = d / f"{fmt}{k}.csv"
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                rb.write(rb.read(src, **opts), dst)
            out["csv"].append((".csv", dst.read_bytes(), {}))
    assert all(out.values()), {k: len(v) for k, v in out.items()}
    return out


@pytest.fixture
def format_seeds(request, seeds) -> list[tuple[str, bytes, dict]]:
    """The seeds of one format (indirect parameter); skips when there are none."""
    if not seeds[request.param]:
        pytest.skip(seeds.missing or f"no {request.param} seed files")
    return seeds[request.param]


# --------------------------------------------------------------------------------------------
# mutations
# --------------------------------------------------------------------------------------------
#: edits of units, quantities and keys (the first occurrence of the left side is replaced)
_EDITS = [
    (b"deg", b"rad"), (b"rad", b"deg"),
    (b"INV_STERADIAN_COSINE_FACTOR", b"INV_STERADIAN"),
    (b"INV_STERADIAN\n", b"INV_STERADIAN_COSINE_FACTOR\n"),
    (b"# quantity: brdf", b"# quantity: relative"), (b"MEAS_NAME BRDF", b"MEAS_NAME BTDF"),
    (b"# angles: deg", b"# angles: grad"), (b"VARS ", b"ANGLE_UNITS deg\nVARS "),
    (b"NUM_POINTS", b"ANGLE_UNITS rad\nNUM_POINTS"),
    (b"#DIM", b"#PARAM_OUT INV_STERADIAN\n#DIM"),
    (b"theta_i,", b"theta_i(deg),"), (b"# angles:", b"# units: rad\n# angles:"),
    # repeated names, keys and counts
    (b"630nm", b"465nm"), (b"#DIM 3 1", b"#DIM 3 2\n#CHANNELS a a"),
    (b"#PARAM_IN", b"#SAMPLE_COUNT\n#PARAM_IN"), (b"NUM_POINTS", b"NUM_POINTS 1e400\nX"),
    (b"#PARAM_IN", b"#PARAM_OUT INV_STERADIAN\n#PARAM_IN"),
    (b"VARS", b"VARS theta_i\nVARS"), (b"# quantity:", b"# quantity: brdf\n# quantity:"),
    (b"MEAS_NAME", b"POLARIZATION s\nSOURCE_POLARIZATION 0\nMEAS_NAME"),
]
#: values a field or a header value is replaced with
_NASTY = [b"", b"nan", b"inf", b"-inf", b"1e400", b"-1e400", b"1e-400", b"-0", b"0", b"-1",
          b"99999999999999999999", b"0x10", b"1_0", b"\xd9\xa3", b"+", b"deg", b"rad", b"a b",
          b"3 1", b"3", b"\"", b"s", b"p", b"brdf", b"theta_i", b"465nm", b"value", b"c0 c0"]
_SEPARATORS = [b",", b" ", b"  ", b"\t", b";", b"\r\n", b"\n", b"", b",,", b"\r"]


#: mutation kinds; the edits of keys and header values are listed more than once (they find
#: more than a flipped byte in the middle of a number)
_KINDS = ["truncate", "drop_line", "dup_line", "swap_lines", "flip", "flip_head", "insert",
          "separator", "all_separators", "field", "dup_field", *["edit", "header_value"] * 3]


@st.composite
def mutation(draw, size: int):
    """One mutation: (kind, parameters); positions are fractions of the file."""
    kind = draw(st.sampled_from(_KINDS))
    frac = st.floats(0.0, 1.0, allow_nan=False)
    if kind in ("truncate", "drop_line", "dup_line"):
        return kind, (draw(frac), draw(frac))
    if kind == "swap_lines":
        return kind, (draw(frac), draw(frac))
    if kind == "flip":
        return kind, (draw(frac), draw(st.integers(1, 255)))
    if kind == "flip_head":  # the first bytes: MERL dimensions, format tags, first keys
        return "flip", (draw(st.floats(0.0, min(1.0, 16 / max(size, 1)))),
                        draw(st.integers(1, 255)))
    if kind == "insert":
        return kind, (draw(frac), draw(st.binary(min_size=1, max_size=12)))
    if kind == "header_value":  # the value of one of the first lines (the header)
        return kind, (draw(st.integers(0, 15)), draw(st.sampled_from(_NASTY)))
    if kind in ("field", "dup_field"):  # one field of one line
        line = draw(st.one_of(frac, st.integers(0, 15)))  # an int: a header line
        return kind, (line, draw(st.integers(0, 12)), draw(st.sampled_from(_NASTY)))
    if kind in ("separator", "all_separators"):
        return kind, (draw(frac), draw(st.sampled_from(_SEPARATORS)),
                      draw(st.sampled_from(_SEPARATORS)))
    return "edit", (draw(st.sampled_from(_EDITS)),)


def _pos(frac: float, n: int) -> int:
    return min(n, int(frac * n))


def apply(raw: bytes, kind: str, args: tuple) -> bytes:
    """Apply one mutation to the file's bytes."""
    lines = raw.split(b"\n")
    if kind == "truncate":
        return raw[:_pos(args[0], len(raw))]
    if kind == "drop_line":
        del lines[min(_pos(args[0], len(lines)), len(lines) - 1)]
        return b"\n".join(lines)
    if kind == "dup_line":
        i = min(_pos(args[0], len(lines)), len(lines) - 1)
        lines.insert(_pos(args[1], len(lines)), lines[i])
        return b"\n".join(lines)
    if kind == "swap_lines":
        i, j = (min(_pos(a, len(lines)), len(lines) - 1) for a in args)
        lines[i], lines[j] = lines[j], lines[i]
        return b"\n".join(lines)
    if kind == "flip":
        if not raw:
            return raw
        i = min(_pos(args[0], len(raw)), len(raw) - 1)
        return raw[:i] + bytes([raw[i] ^ args[1]]) + raw[i + 1:]
    if kind == "insert":
        i = _pos(args[0], len(raw))
        return raw[:i] + args[1] + raw[i:]
    if kind == "separator":  # one line
        i = min(_pos(args[0], len(lines)), len(lines) - 1)
        if args[1]:
            lines[i] = lines[i].replace(args[1], args[2])
        return b"\n".join(lines)
    if kind == "header_value":
        i = min(args[0], len(lines) - 1)
        key = lines[i].split(None, 1)[0] if lines[i].split() else b""
        if key.startswith(b"#") and len(key) == 1:  # "# key: value"
            key = lines[i].partition(b":")[0] + b":"
        lines[i] = key + b" " + args[1]
        return b"\n".join(lines)
    if kind in ("field", "dup_field"):
        i = min(args[0] if isinstance(args[0], int) else _pos(args[0], len(lines)),
                len(lines) - 1)
        sep = b"," if b"," in lines[i] else b" "
        fields = lines[i].split(sep)
        j = min(args[1], len(fields) - 1)
        if kind == "field":
            fields[j] = args[2]
        else:
            fields.insert(j, fields[j])
        lines[i] = sep.join(fields)
        return b"\n".join(lines)
    if kind == "all_separators":
        return raw.replace(args[1], args[2]) if args[1] else raw
    old, new = args[0]
    return raw.replace(old, new, 1)


# --------------------------------------------------------------------------------------------
# the property
# --------------------------------------------------------------------------------------------
class _Hang(Exception):
    pass


@contextlib.contextmanager
def _alarm(seconds: int):
    """Raise _Hang if the block runs longer than ``seconds`` (POSIX main thread only)."""
    usable = hasattr(signal, "SIGALRM") and threading.current_thread() is threading.main_thread()
    if not usable:
        yield
        return

    def on_alarm(signum, frame):
        raise _Hang(f"read did not finish in {seconds} s")

    previous = signal.signal(signal.SIGALRM, on_alarm)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def _check_read(path: Path, options: dict) -> None:
    with _alarm(HANG_SECONDS), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            m = rb.read(path, **options)
        except FormatError as exc:
            assert str(path) in str(exc)
            return
    assert isinstance(m, Measurement)
    for a in (m.theta_i, m.theta_r, m.phi):
        assert np.isfinite(a).all()
    assert ((m.theta_i >= 0) & (m.theta_i <= math.pi / 2)).all()
    assert ((m.theta_r >= 0) & (m.theta_r <= math.pi / 2)).all()
    assert m.values.shape == (m.n_samples, len(m.channels))


def _fuzz(choices: list[tuple[str, bytes, dict]], data, tmp: Path) -> None:
    ext, raw, options = choices[data.draw(st.integers(0, len(choices) - 1), label="seed")]
    for kind, args in data.draw(st.lists(mutation(len(raw)), min_size=1, max_size=4),
                                label="mutations"):
        raw = apply(raw, kind, args)
    path = tmp / f"fuzzed{ext}"
    path.write_bytes(raw)
    _check_read(path, options)


@pytest.fixture(scope="module")
def scratch(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


@pytest.mark.parametrize("format_seeds", ["astm", "alta", "csv", "merl"], indirect=True)
@FUZZ
@given(data=st.data())
def test_mutated_files_read_or_raise_format_error(format_seeds, scratch, data):
    _fuzz(format_seeds, data, scratch)


def test_seeds_read_cleanly(seeds, tmp_path):
    """The unmutated seeds are good files (so the mutations, not the seeds, cause the errors)."""
    for fmt, items in seeds.items():
        for k, (ext, raw, options) in enumerate(items):
            p = tmp_path / f"{fmt}{k}{ext}"
            p.write_bytes(raw)
            assert rb.read(p, **options).n_samples > 0
