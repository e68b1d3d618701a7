"""The library's writers and readers: nothing a user has is lost.

* writers never replace an existing file unless ``overwrite=True``, never write onto the
  measurement's own input, and write atomically (no partial or 0-byte file on error or Ctrl-C);
* conversions tell the truth or refuse: MERL's fixed grid needs ``resample=True`` and reports
  what it binned, averaged and dropped; a round trip within one format keeps every header key;
  across formats, keys the target has no place for are named in a warning;
* readers: keys given twice and contradicting declarations are errors naming both lines; a
  ``quantity=``/``angles=`` that contradicts the file raises in every reader; a file cut inside
  its last number gets a warning naming the line.

Each problem is reproduced here (each test failed before the change).
"""

from __future__ import annotations

import json
import math
import os
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import roughbrdf as rb
import roughbrdf.output
from roughbrdf.cli import app
from roughbrdf.errors import ArgumentError
from roughbrdf.io import (
    FormatError,
    LossyWriteWarning,
    UnterminatedRowWarning,
    alta,
    astm,
    csv,
    merl,
)
from roughbrdf.measurement import Measurement

ASTM = """LAB_NAME Test Lab
SYSTEM_NAME Gonio 2
APERTURE Circular

SAMPLE_NAME S1
MEAS_NAME BRDF
FILE_NAME S1.astm
MEAS_DATE 2024/01/02
MEAS_TIME 10:00:00
NUM_POINTS 4
VARS theta_i,phi_i,theta_s,phi_s,465nm,525nm
0,3.141592653589793,0.1,0,1.5,1.6
0,3.141592653589793,0.2,0,1.25,1.5
0.5,3.141592653589793,0.5,0,3.0,3.5
0.5,3.141592653589793,0.7,3.141592653589793,0.5,-0.001
"""

ALTA = """#SAMPLE "Gray tape"
#ORIGIN "CEA"
#URL https://example.org/x
# measured with the CEA gonio-reflectometer
#CMD data2data --foo
#DIM 3 1
#VS 0
#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI
#PARAM_OUT INV_STERADIAN
0.5 0.5 0.0 5.0
0.5 -0.5 0.0 3.0
0.5 0.3 0.2 1.0
"""

CSV = """# roughbrdf-csv 1
# angles: deg
# quantity: brdf
# sample: paint
# Operator: Ann
# lamp: halogen, 3200 K
theta_i,theta_r,phi,465nm,525nm
0,10,0,0.5,0.6
30,30,0,2.0,2.1
30,30,180,0.1,0.2
"""

runner = CliRunner()


def _file(tmp_path: Path, text: str, name: str) -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def _measurement(n: int = 6) -> Measurement:
    rng = np.random.default_rng(2)
    return Measurement(theta_i=rng.uniform(0, 1.4, n), theta_r=rng.uniform(0, 1.4, n),
                       phi=rng.uniform(-np.pi, np.pi, n), values=rng.uniform(0.1, 2, (n, 3)),
                       channels=["R", "G", "B"], quantity="brdf")


def _merl_file(tmp_path: Path, name: str = "m.binary") -> Path:
    p = tmp_path / name
    merl.write_table(p, merl.table_from_model(rb.model("lambertian", rho=0.5), dims=(6, 6, 12)))
    return p


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith(".roughbrdf-tmp-"))


# ------------------------------------------------------------------------------------------
# writers never overwrite without asking, never write onto their input, atomically
# ------------------------------------------------------------------------------------------
FORMATS = [("astm", ".astm"), ("alta", ".dat"), ("csv", ".csv"), ("merl", ".binary")]


@pytest.mark.parametrize("fmt, ext", FORMATS)
def test_writer_refuses_an_existing_file_unless_overwrite(tmp_path, fmt, ext):
    m = _measurement()
    out = tmp_path / f"out{ext}"
    out.write_text("the user's file")
    with pytest.raises(FileExistsError, match=re.escape(str(out))):
        rb.write(m, out, resample=True) if fmt == "merl" else rb.write(m, out)
    assert out.read_text() == "the user's file"
    with pytest.raises(FileExistsError):  # the format's own writer too
        rb.io._module(fmt).write(m, out)
    assert out.read_text() == "the user's file"
    opts = {"resample": True} if fmt == "merl" else {}
    rb.write(m, out, overwrite=True, **opts)
    assert rb.read(out).n_samples > 0
    assert _leftovers(tmp_path) == []


@pytest.mark.parametrize("fmt, ext", FORMATS)
def test_writer_never_replaces_its_own_input(tmp_path, fmt, ext, monkeypatch):
    """Why: ``rb.write(m, path)`` overwrote any file, its own input included."""
    src = tmp_path / f"in{ext}"
    rb.write(_measurement(), src, **({"resample": True} if fmt == "merl" else {}))
    before = src.read_bytes()
    m = rb.read(src)
    for target in (src, Path(os.path.relpath(src)), tmp_path / "." / src.name):
        with pytest.raises(ArgumentError, match="read from") as exc:
            rb.write(m, target, overwrite=True)
        assert exc.value.argument == "path"
    link = tmp_path / f"link{ext}"
    link.symlink_to(src)
    with pytest.raises(ArgumentError, match="read from"):
        rb.write(m.subset(np.ones(m.n_samples, bool)), link, overwrite=True)
    monkeypatch.chdir(tmp_path.parent)  # a relative meta["file"] no longer resolves here
    with pytest.raises(ArgumentError, match="read from"):
        rb.write(m, src, overwrite=True)
    assert src.read_bytes() == before


@pytest.mark.parametrize("fmt, ext", FORMATS)
@pytest.mark.parametrize("existed", [False, True])
def test_interrupted_write_leaves_old_file_or_none(tmp_path, monkeypatch, fmt, ext, existed):
    """Ctrl-C (or an error) after some bytes are written: no partial, no 0-byte file, no
    temporary file left; an existing file is untouched."""
    out = tmp_path / f"out{ext}"
    if existed:
        out.write_text("old complete file")

    def interrupted(fd):
        raise KeyboardInterrupt

    monkeypatch.setattr(roughbrdf.output.os, "fsync", interrupted)
    opts = {"resample": True} if fmt == "merl" else {}
    with pytest.raises(KeyboardInterrupt):
        rb.write(_measurement(), out, overwrite=True, **opts)
    if existed:
        assert out.read_text() == "old complete file"
    else:
        assert not out.exists()
    assert _leftovers(tmp_path) == []


def test_a_folder_is_not_a_file(tmp_path):
    with pytest.raises(IsADirectoryError, match="folder"):
        rb.write(_measurement(), tmp_path, format="csv", overwrite=True)
    d = tmp_path / "x.csv"
    d.mkdir()
    with pytest.raises(IsADirectoryError):
        rb.write(_measurement(), d, overwrite=True)


def test_merl_write_table_is_atomic_and_refuses(tmp_path):
    p = _merl_file(tmp_path)
    before = p.read_bytes()
    with pytest.raises(FileExistsError):
        merl.write_table(p, np.zeros((3, 2, 2, 2)))
    assert p.read_bytes() == before
    merl.write_table(p, np.zeros((3, 2, 2, 2)), overwrite=True)
    assert merl.read_table(p).shape == (3, 2, 2, 2)


# ------------------------------------------------------------------------------------------
# conversions tell the truth or refuse
# ------------------------------------------------------------------------------------------
def test_minidiff_to_merl_refuses_then_reports_exactly(shared_data, tmp_path):
    """Why: converting a Mini-Diff .astm to MERL said all 12,964 samples and the negative values
    were kept; reading the result back gave fewer samples, the negatives gone."""
    m = rb.read(shared_data / "minidiff" / "C2_Black.astm")
    out = tmp_path / "black.binary"
    with pytest.raises(ArgumentError) as exc:
        rb.write(m, out)
    assert exc.value.argument == "resample" and "resample=True" in str(exc.value)
    for word in ("binned", "averaged", "negative", "12964", "reading the file back gives"):
        assert word in str(exc.value)
    assert not out.exists()
    with pytest.warns(LossyWriteWarning, match="APERTURE"):
        report = rb.write(m, out, resample=True)
    back = rb.read(out)
    assert report.n_read_back == back.n_samples < m.n_samples == report.n_samples
    neg = {c: r["negative"] for c, r in m.validate().items()}
    assert report.negative == neg and sum(neg.values()) > 0
    assert report.n_binned > 0 and report.n_averaged > 0 and report.n_shared_cells > 0
    # every sample is accounted for: read back (some averaged together) or lost for a reason
    represented = m.n_samples - report.n_off_grid - report.n_lost_invalid
    merged = report.n_averaged - report.n_shared_cells
    assert represented - merged <= report.n_read_back <= represented
    assert report.channel_map == {"R": "630nm", "G": "525nm", "B": "465nm"}
    assert "8" in report.text() and "binned" in report.text()
    assert (back.values >= 0).all()


def test_merl_report_counts_on_a_small_case(tmp_path):
    """Two samples in one cell (averaged), one off the grid, one negative value, one NaN."""
    th, td, pd = merl.cell_angles(np.array([10, 10, 20, 30]), np.array([20, 20, 40, 50]),
                                  np.array([30, 30, 60, 90]), dims=merl.DIMS)
    ti, tr, ph = merl.from_rusinkiewicz(th, td, pd)
    ti[2] += 0.01  # off the grid
    values = np.array([[1.0, 1.0, 1.0], [3.0, 3.0, 3.0], [2.0, -0.5, 2.0], [1.0, 1.0, np.nan]])
    m = Measurement(ti, tr, ph, values, channels=["R", "G", "B"])
    table, report = merl.plan(m)
    assert report.n_binned == 1 and report.n_averaged == 2 and report.n_shared_cells == 1
    assert report.negative == {"R": 0, "G": 1, "B": 0}
    assert report.nonfinite == {"R": 0, "G": 0, "B": 1}
    assert report.changes_samples
    with pytest.raises(ArgumentError, match="resample"):
        merl.write(m, tmp_path / "x.binary")
    report = merl.write(m, tmp_path / "x.binary", resample=True)
    back = rb.read(tmp_path / "x.binary")
    assert back.n_samples == report.n_read_back == 1  # the averaged cell; the others lack a value
    assert back.values[0] == pytest.approx([2.0, 2.0, 2.0])
    assert report.n_lost_invalid == 2


def test_merl_on_grid_needs_no_resample(tmp_path):
    src = _merl_file(tmp_path)
    m = rb.read(src)
    report = rb.write(m, tmp_path / "again.binary", dims=(6, 6, 12))
    assert not report.changes_samples and report.by_index
    assert report.n_read_back == m.n_samples == rb.read(tmp_path / "again.binary").n_samples
    # through CSV the cell index is gone; the angles find the cells again, except that the
    # cells at theta_h = 0 or theta_d = 0 (phi_d does not change the geometry there) are one
    # geometry each: MERL -> CSV -> MERL averages them, and says so
    via_csv = tmp_path / "m.csv"
    rb.write(m, via_csv, angles="rad")
    m2 = rb.read(via_csv)
    m2.original.pop("merl_index")
    plan_table, rep2 = merl.plan(m2, dims=(6, 6, 12))
    pole = (m2.original["theta_h"] == 0) | (m2.original["theta_d"] == 0)
    assert rep2.n_binned == 0 and rep2.n_dropped_values == 0
    assert rep2.n_averaged == pole.sum() > 0 and rep2.changes_samples
    with pytest.raises(ArgumentError, match="averaged"):
        rb.write(m2, tmp_path / "back.binary", dims=(6, 6, 12))
    with pytest.warns(LossyWriteWarning, match="source_file"):
        rb.write(m2, tmp_path / "back.binary", dims=(6, 6, 12), resample=True)
    assert rb.read(tmp_path / "back.binary").n_samples == rep2.n_read_back


def test_convert_astm_to_merl_refuses_without_resample(shared_data, tmp_path):
    src = shared_data / "minidiff" / "C8_Silver.astm"
    out = tmp_path / "silver.binary"
    res = runner.invoke(app, ["convert", str(src), str(out)])
    assert res.exit_code == 2 and not out.exists()
    text = " ".join(res.output.split())
    assert "binned" in text and "averaged" in text and "negative" in text
    assert "--resample" in text and "resample=True" not in text
    res = runner.invoke(app, ["convert", str(src), str(out), "--resample"])
    assert res.exit_code == 0, res.output
    n = rb.read(out).n_samples
    assert f"{n} read back" in res.output and "kept as they are" not in res.output
    warning_lines = [ln for ln in res.output.splitlines() if ln.startswith("warning:")]
    assert len(warning_lines) == 1 and "APERTURE" in warning_lines[0]


def test_resample_only_for_grid_outputs(tmp_path):
    # MERL and Zemax write fixed grids; the other formats keep every sample
    src = _file(tmp_path, CSV, "in.csv")
    res = runner.invoke(app, ["convert", str(src), str(tmp_path / "o.dat"), "--resample"])
    assert res.exit_code == 2 and "--resample applies to MERL and Zemax output" in res.output
    res = runner.invoke(app, ["convert", str(src), str(tmp_path / "o.dat"), "--channel", "1"])
    assert res.exit_code == 2 and "--channel applies to Zemax output" in res.output


def test_astm_round_trip_keeps_every_header_key(tmp_path):
    """Why: the rewritten ASTM header lost keys it read (APERTURE) and merged others
    (LAB_NAME + SYSTEM_NAME, MEAS_DATE + MEAS_TIME)."""
    m = rb.read(_file(tmp_path, ASTM, "s.astm"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing is lost within one format
        astm.write(m, tmp_path / "again.astm")
    r = rb.read(tmp_path / "again.astm")
    assert list(r.meta["header"]) == list(m.meta["header"])
    for key, val in m.meta["header"].items():
        if key not in ("VARS",):  # VARS now names phi_s (the Mini-Diff quirk repaired)
            assert r.meta["header"][key] == val, key
    assert r.meta["header"]["LAB_NAME"] == "Test Lab"
    assert r.meta["header"]["APERTURE"] == "Circular"
    assert np.allclose(r.values, m.values)
    # in degrees: the unit declared, every other key kept
    astm.write(m, tmp_path / "deg.astm", angles="deg")
    d = rb.read(tmp_path / "deg.astm")
    assert d.meta["header"]["ANGLE_UNITS"] == "deg" and np.allclose(d.theta_r, m.theta_r)
    assert set(m.meta["header"]) <= set(d.meta["header"])


def test_minidiff_round_trip_keeps_every_header_key(shared_data, tmp_path):
    m = rb.read(shared_data / "minidiff" / "C2_Black.astm")
    rb.write(m, tmp_path / "black.astm")
    r = rb.read(tmp_path / "black.astm")
    same = {k: v for k, v in m.meta["header"].items() if k != "VARS"}
    assert {k: r.meta["header"][k] for k in same} == same
    assert r.meta["header"]["APERTURE"] == "Circular"
    assert r.meta["header"]["FILE_NAME"] == "C1_Black.astm"


def test_alta_round_trip_keeps_every_header_line(tmp_path):
    m = rb.read(_file(tmp_path, ALTA, "a.dat"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        alta.write(m, tmp_path / "again.dat")
    text = (tmp_path / "again.dat").read_text()
    for line in ALTA.splitlines():
        if line.startswith("#"):
            assert line in text.splitlines(), line
    r = rb.read(tmp_path / "again.dat")
    assert r.meta["header_lines"] == m.meta["header_lines"]
    # a subset in another quantity: the layout keys follow the rows, the others stay
    alta.write(m.subset([0, 2]).as_quantity("brdf_cos"), tmp_path / "cos.dat")
    c = rb.read(tmp_path / "cos.dat")
    assert c.quantity == "brdf_cos" and c.n_samples == 2
    assert "# measured with the CEA gonio-reflectometer" in c.meta["header_lines"]


def test_real_alta_round_trip(shared_data, tmp_path):
    m = rb.read(shared_data / "cea_retro" / "retro-3M-jaune.dat")
    rb.write(m, tmp_path / "3m.dat")
    r = rb.read(tmp_path / "3m.dat")
    assert r.meta["header_lines"][:len(m.meta["header_lines"])] == m.meta["header_lines"]
    assert np.array_equal(r.values, m.values)


def test_csv_round_trip_keeps_every_header_key(tmp_path):
    m = rb.read(_file(tmp_path, CSV, "c.csv"))
    csv.write(m, tmp_path / "again.csv", angles="rad")
    r = rb.read(tmp_path / "again.csv")
    for key, val in m.meta["header"].items():
        if key not in ("angles",):
            assert r.meta["header"][key] == val, key
    assert r.meta["header"]["angles"] == "rad"
    assert r.meta["header"]["Operator"] == "Ann" and r.meta["lamp"] == "halogen, 3200 K"


def test_cross_format_names_what_has_no_place(tmp_path):
    m = rb.read(_file(tmp_path, ASTM, "s.astm"))
    with pytest.warns(LossyWriteWarning) as rec:
        rb.write(m, tmp_path / "s.dat")
    assert len(rec) == 1
    msg = str(rec[0].message)
    assert "APERTURE" in msg and "FILE_NAME" in msg and "s.dat" in msg
    assert "LAB_NAME" not in msg and "MEAS_TIME" not in msg  # they have a place: #ORIGIN, #DATE
    with warnings.catch_warnings():  # CSV keeps the source header, as JSON
        warnings.simplefilter("error")
        rb.write(m, tmp_path / "s.csv")
    c = rb.read(tmp_path / "s.csv")
    assert json.loads(c.meta["source_header"])["APERTURE"] == "Circular"
    a = rb.read(_file(tmp_path, ALTA, "a.dat"))
    with pytest.warns(LossyWriteWarning, match="URL") as rec:
        rb.write(a, tmp_path / "a.astm")
    assert "CMD" in str(rec[0].message)
    u = Measurement([0.2], [0.3], [0.0], [[1.0]], uncertainty=[[0.1]])
    with pytest.warns(LossyWriteWarning, match="uncertainties"):
        rb.write(u, tmp_path / "u.astm")


def test_convert_prints_each_warning_on_one_line(tmp_path):
    src = _file(tmp_path, ASTM, "s.astm")
    res = runner.invoke(app, ["convert", str(src), str(tmp_path / "s.dat")])
    assert res.exit_code == 0, res.output
    lines = [ln for ln in res.output.splitlines() if "APERTURE" in ln]
    assert len(lines) == 1 and lines[0].startswith("warning: ")


def test_writers_refuse_what_they_cannot_hold(tmp_path):
    m = _measurement()
    m.polarization = np.array([0.0, 0.0, 1.0, 1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="one polarization"):
        rb.write(m, tmp_path / "p.astm")
    m.polarization = np.full(6, math.pi / 2)
    rb.write(m, tmp_path / "p.astm")
    assert np.allclose(rb.read(tmp_path / "p.astm").polarization, math.pi / 2)
    with pytest.raises(ValueError, match="polarization"):
        rb.write(m, tmp_path / "p.binary", resample=True)
    one = Measurement([0.2], [0.3], [0.0], [[1.0]], channels=["465nm"])
    rb.write(one, tmp_path / "one.dat")  # a single label is kept (#CHANNELS)
    assert rb.read(tmp_path / "one.dat").channels == ["465nm"]


# ------------------------------------------------------------------------------------------
# readers
# ------------------------------------------------------------------------------------------
def _both_lines(exc: FormatError, first: int, second: int) -> None:
    assert exc.line == second
    assert f"line {first}" in str(exc) and f"line {second}" in str(exc)


def test_two_alta_param_out_lines_are_an_error(tmp_path):
    """Why: two #PARAM_OUT lines (BRDF·cos, then BRDF) were read as BRDF."""
    text = ALTA.replace("#PARAM_OUT INV_STERADIAN",
                        "#PARAM_OUT INV_STERADIAN_COSINE_FACTOR\n#PARAM_OUT INV_STERADIAN")
    with pytest.raises(FormatError, match="#PARAM_OUT is given twice") as exc:
        rb.read(_file(tmp_path, text, "a.dat"))
    _both_lines(exc.value, 9, 10)
    # other '#' lines are comments and may repeat
    ok = "# note\n# note\n" + ALTA
    assert rb.read(_file(tmp_path, ok, "b.dat")).n_samples == 3


def test_second_astm_vars_line_is_an_error(tmp_path):
    """Why: a second ASTM VARS line renamed the channels."""
    text = ASTM.replace("VARS theta_i", "VARS theta_i,phi_i,theta_s,phi_s,a,b\nVARS theta_i")
    with pytest.raises(FormatError, match="VARS is given twice") as exc:
        rb.read(_file(tmp_path, text, "s.astm"))
    _both_lines(exc.value, 11, 12)
    text = ASTM.replace("SAMPLE_NAME S1", "SAMPLE_NAME S1\nSAMPLE_NAME S2")
    with pytest.raises(FormatError, match="SAMPLE_NAME is given twice"):
        rb.read(_file(tmp_path, text, "t.astm"))


def test_repeated_csv_key_is_an_error(tmp_path):
    text = CSV.replace("# sample: paint", "# sample: paint\n# Sample: other")
    with pytest.raises(FormatError, match="given twice") as exc:
        rb.read(_file(tmp_path, text, "c.csv"))
    _both_lines(exc.value, 4, 5)
    text = CSV.replace("# roughbrdf-csv 1", "# roughbrdf-csv 1\n# roughbrdf-csv 1")
    with pytest.raises(FormatError, match="given twice"):
        rb.read(_file(tmp_path, text, "d.csv"))


@pytest.mark.parametrize("name, text, first, second", [
    ("a.astm", ASTM.replace("NUM_POINTS", "ANGLE_UNITS deg\nUNITS rad\nNUM_POINTS"), 10, 11),
    ("b.astm", ASTM.replace("NUM_POINTS", "ANGLE_UNITS rad\nNUM_POINTS").replace(
        "VARS theta_i,phi_i,theta_s,phi_s", "VARS theta_i(deg),phi_i(deg),theta_s(deg),"
        "phi_s(deg)"), 10, 12),
    ("c.csv", CSV.replace("# angles: deg", "# angles: deg\n# units: rad"), 2, 3),
    ("d.csv", CSV.replace("theta_i,theta_r,phi,", "theta_i_rad,theta_r_rad,phi_rad,"), 2, 7),
    ("e.astm", ASTM.replace("MEAS_NAME", "POLARIZATION s\nINCIDENT_POLARIZATION p\nMEAS_NAME"),
     6, 7),
])
def test_contradicting_declarations_name_both_lines(tmp_path, name, text, first, second):
    with pytest.raises(FormatError, match="contradicts") as exc:
        rb.read(_file(tmp_path, text, name))
    _both_lines(exc.value, first, second)


def test_quantity_option_contradicting_the_file_raises_in_every_reader(tmp_path):
    """Why: an ASTM quantity= that contradicts the file was accepted (ALTA raised)."""
    files = {"astm": _file(tmp_path, ASTM, "s.astm"), "alta": _file(tmp_path, ALTA, "a.dat"),
             "csv": _file(tmp_path, CSV, "c.csv"), "merl": _merl_file(tmp_path)}
    for fmt, path in files.items():
        with pytest.raises(FormatError, match="quantity='relative'.*contradicts") as exc:
            rb.read(path, quantity="relative")
        assert exc.value.path == str(path), fmt
        assert rb.read(path, quantity="brdf").quantity == "brdf"  # agreeing is fine
    # where the file does not say, the caller's value is used
    no_name = _file(tmp_path, ASTM.replace("MEAS_NAME BRDF\n", ""), "n.astm")
    assert rb.read(no_name, quantity="brdf_cos").quantity == "brdf_cos"
    no_q = _file(tmp_path, CSV.replace("# quantity: brdf\n", ""), "n.csv")
    assert rb.read(no_q, quantity="relative").quantity == "relative"
    gray = _file(tmp_path, ALTA.replace("#PARAM_OUT INV_STERADIAN\n", ""), "n.dat")
    assert rb.read(gray, quantity="brdf_cos").quantity == "brdf_cos"


def test_angles_option_contradicting_the_file_raises_in_every_reader(tmp_path):
    deg_astm = _file(tmp_path, ASTM.replace("NUM_POINTS", "ANGLE_UNITS rad\nNUM_POINTS"),
                     "s.astm")
    files = {"astm": deg_astm, "alta": _file(tmp_path, ALTA, "a.dat"),
             "csv": _file(tmp_path, CSV.replace("# angles: deg", "# angles: rad").replace(
                 "0,10,", "0,0.1,").replace("30,30,", "0.5,0.5,"), "c.csv"),
             "merl": _merl_file(tmp_path)}
    for fmt, path in files.items():
        with pytest.raises(FormatError, match="angles='deg'.*contradicts") as exc:
            rb.read(path, angles="deg")
        assert exc.value.path == str(path), fmt
        assert rb.read(path, angles="rad").n_samples > 0
    plain = _file(tmp_path, ASTM, "p.astm")  # no declaration: the option is used
    assert rb.read(plain, angles="deg").meta["angle_units_source"] == "option angles="


@pytest.mark.parametrize("name, text", [("s.astm", ASTM), ("a.dat", ALTA), ("c.csv", CSV)])
def test_row_cut_inside_its_last_number_warns(tmp_path, name, text):
    """Why: a row cut inside its last number was read as a shorter number, without a word."""
    cut = text.rstrip("\n")[:-1]  # no final line end, last digit gone
    n_lines = len(cut.splitlines())
    p = _file(tmp_path, cut, name)
    with pytest.warns(UnterminatedRowWarning, match=rf"line {n_lines}\b.*cut short"):
        m = rb.read(p)
    assert m.n_samples == 3 if name != "s.astm" else m.n_samples == 4
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rb.read(_file(tmp_path, text, "whole" + Path(name).suffix))
        rb.read(_file(tmp_path, text.rstrip("\n") + "  ", "spaces" + Path(name).suffix))


@pytest.mark.parametrize("name, text, match", [
    ("a.astm", ASTM.replace("NUM_POINTS 4", "NUM_POINTS 1e400"), "NUM_POINTS must be a whole"),
    ("b.astm", ASTM.replace("NUM_POINTS 4", "NUM_POINTS 4.5"), "NUM_POINTS must be a whole"),
    ("c.astm", ASTM.replace("465nm,525nm", "465nm,465nm"), "twice"),
    ("d.astm", ASTM.replace("VARS theta_i,phi_i,theta_s,phi_s,465nm,525nm", "VARS"),
     "no column names"),
    ("e.astm", ASTM.replace("MEAS_NAME", "POLARIZATION inf\nMEAS_NAME"), "finite"),
    ("a.dat", ALTA.replace("#DIM 3 1", "#DIM 3 2\n#CHANNELS a a").replace(
        " 5.0\n", " 5.0 1\n").replace(" 3.0\n", " 3.0 1\n").replace(" 1.0\n", " 1.0 1\n"),
     "twice"),
    ("b.dat", ALTA.replace("#VS 0", "#VS 0\n#SAMPLE_COUNT"), "whole number"),
    ("a.csv", CSV.replace("# quantity: brdf", "# quantity: brdf\n# angles: rad"), "twice"),
    ("b.csv", "# angles: deg\n# quantity: brdf\ntheta_i,theta_r,phi,v,polarization\n"
     "10,10,0,1,inf\n", "finite"),
])
def test_crashes_found_by_the_fuzzer_are_format_errors(tmp_path, name, text, match):
    """Inputs that used to end in IndexError, OverflowError or a ValueError from Measurement
    (or were read silently: NUM_POINTS 4.5, an infinite polarization)."""
    with pytest.raises(FormatError, match=match):
        rb.read(_file(tmp_path, text, name))
