"""The rows of the text
readers are read row by row, never shifted, and the angles' unit is checked for plausibility.

* An empty field in one row and a number with a blank inside in a later row used to cancel
  out (the fast parser compared only the total count of numbers): every row between them was
  read shifted by one column, without an error. Now the first bad row is named.
* ``1_5`` was read as 15 and full-width digits (``１５``) as numbers; now refused.
* A radians file read with ``angles="deg"`` (every angle below 1.6 deg) was read without a
  word; now an ``ImplausibleAnglesWarning`` says the angles look like radians (and the other
  way round for an angle above 2 pi read as radians).
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.io import FormatError, ImplausibleAnglesWarning

CSV_HEAD = """# roughbrdf-csv 1
# angles: deg
# quantity: brdf
theta_i,theta_r,phi,465nm,525nm
"""  # data from line 5 on
CSV_ROWS = ["0,10,0,0.5,0.6", "30,30,0,2.0,2.1", "30,35,0,0.1,0.2", "30,40,180,0.1,0.2",
            "30,45,180,0.3,0.4"]

ASTM_HEAD = """SAMPLE_NAME S1
MEAS_NAME BRDF
NUM_POINTS 5
VARS theta_i,phi_i,theta_s,phi_s,465nm
"""  # data from line 5 on
ASTM_ROWS = ["0,0,0.1,0,0.5", "0,0,0.2,0,0.25", "0,0,0.3,0,0.75", "0,0,0.4,0,0.5",
             "0,0,0.5,0,0.25"]

ALTA_HEAD = """#DIM 3 1
#VS 0
#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI
#PARAM_OUT INV_STERADIAN
"""  # data from line 5 on
ALTA_ROWS = ["0.5 0.5 0.0 5.0", "0.5 -0.5 0.0 3.0", "0.5 0.3 0.2 1.0", "0.5 0.2 0.1 2.0",
             "0.5 0.1 0.1 4.0"]

FORMATS = {"csv": (CSV_HEAD, CSV_ROWS, ".csv", ","), "astm": (ASTM_HEAD, ASTM_ROWS, ".astm", ","),
           "alta": (ALTA_HEAD, ALTA_ROWS, ".dat", " ")}
FIRST = 5  # line of the first data row in every head above


def _write(tmp_path: Path, fmt: str, rows: list[str], name: str = "f") -> Path:
    head, _, ext, _ = FORMATS[fmt]
    p = tmp_path / f"{name}{ext}"
    p.write_text(head + "\n".join(rows) + "\n", encoding="utf-8")
    return p


def _with_field(fmt: str, row: int, col: int, text: str) -> list[str]:
    """The format's rows with field ``col`` of row ``row`` (0-based) replaced by ``text``."""
    _, rows, _, sep = FORMATS[fmt]
    out = list(rows)
    fields = out[row].split(sep)
    fields[col] = text
    out[row] = sep.join(fields)
    return out


# ------------------------------------------------------------------------------------------
# an empty field and a later inner-blank field never shift the rows between them
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("fmt", ["csv", "astm"])
def test_empty_field_then_inner_blank_is_refused_at_the_first_bad_line(tmp_path, fmt):
    """Why: the empty field of line 6 and the ``0 5`` of line 8 cancelled out in the total
    count of numbers, and lines 6-8 were read one column off, without an error."""
    rows = _with_field(fmt, 1, 3, "")
    rows[3] = _with_field(fmt, 3, 4, "0 5")[3]
    path = _write(tmp_path, fmt, rows)
    with pytest.raises(FormatError, match=r"empty field in column 4") as info:
        rb.read(path)
    assert info.value.line == FIRST + 1
    assert str(info.value).startswith(f"{path}, line {FIRST + 1}: ")


@pytest.mark.parametrize("fmt", ["csv", "astm"])
def test_inner_blank_then_empty_field_is_refused_at_the_first_bad_line(tmp_path, fmt):
    """Why: the other order (a number with a blank inside first, an empty field later) shifted
    the rows the other way, silently too."""
    rows = _with_field(fmt, 1, 4, "0 5")
    rows[3] = _with_field(fmt, 3, 3, "")[3]
    path = _write(tmp_path, fmt, rows)
    with pytest.raises(FormatError, match=r"blank inside the field '0 5' in column 5") as info:
        rb.read(path)
    assert info.value.line == FIRST + 1


def test_blank_separated_rows_with_a_missing_and_an_extra_value_name_the_first(tmp_path):
    """A regression guard (this was refused before too): ALTA rows are blank separated, so a
    field cannot be empty and a blank always separates two fields - each row's count of values
    was already checked, and the finding's misalignment cannot happen there. A row one value
    short (``1_5`` standing for two) and a later row one value long: the first is named."""
    rows = list(ALTA_ROWS)
    rows[1] = "0.5 -0.5 1_5"     # three fields, '1_5' would have been read as 15
    rows[3] = "0.5 0.2 0.1 2.0 7"
    path = _write(tmp_path, "alta", rows)
    with pytest.raises(FormatError) as info:
        rb.read(path)
    assert info.value.line == FIRST + 1


# ------------------------------------------------------------------------------------------
# numbers that float() reads but a measurement file must not hold
# ------------------------------------------------------------------------------------------
BAD_NUMBERS = [("1_5", r"'_' in the field '1_5'"),
               ("１５", r"non-ASCII characters U\+FF11, U\+FF15 in the field '１５'"),
               ("1\u00a05", r"non-ASCII characters U\+00A0 in the field '1\\xa05'")]


@pytest.mark.parametrize("fmt, text, reason", [
    (fmt, text, reason) for fmt in ("csv", "astm", "alta") for text, reason in BAD_NUMBERS
    # a no-break space separates blank-separated fields (as str.split does): not in ALTA
    if not (fmt == "alta" and "\u00a0" in text)])
def test_numbers_that_are_not_plain_ascii_are_refused_naming_line_and_column(tmp_path, fmt,
                                                                             text, reason):
    """Why: ``1_5`` was read as 15 and ``１５`` as 15 (Python's float() accepts both)."""
    col = 4 if fmt != "alta" else 3
    path = _write(tmp_path, fmt, _with_field(fmt, 2, col - 1, text))
    with pytest.raises(FormatError, match=reason + rf" in column {col}") as info:
        rb.read(path)
    assert info.value.line == FIRST + 2
    assert str(path) in str(info.value)


@pytest.mark.parametrize("fmt", ["csv", "astm"])
def test_a_number_with_a_blank_inside_is_named_as_such(tmp_path, fmt):
    """Why: `` 1 5`` in a comma separated row was 'non-numeric', with no word of the blank."""
    path = _write(tmp_path, fmt, _with_field(fmt, 2, 3, " 1 5"))
    with pytest.raises(FormatError, match=r"blank inside the field '1 5' in column 4") as info:
        rb.read(path)
    assert info.value.line == FIRST + 2


def test_csv_polarization_column_refuses_an_underscore_number(tmp_path):
    """Why: the polarization column was read with float(): '4_5' was 45 degrees."""
    p = tmp_path / "pol.csv"
    p.write_text("# roughbrdf-csv 1\n# angles: deg\n# quantity: brdf\n"
                 "theta_i,theta_r,phi,polarization,v\n0,10,0,4_5,0.5\n", encoding="utf-8")
    with pytest.raises(FormatError, match=r"polarization '4_5'") as info:
        rb.read(p)
    assert info.value.line == 5


def test_astm_num_points_refuses_an_underscore_number(tmp_path):
    """Why: ``NUM_POINTS 5_0`` was read as 50."""
    p = tmp_path / "n.astm"
    p.write_text(ASTM_HEAD.replace("NUM_POINTS 5", "NUM_POINTS 5_0") + "\n".join(ASTM_ROWS)
                 + "\n", encoding="utf-8")
    with pytest.raises(FormatError, match=r"NUM_POINTS must be a whole number") as info:
        rb.read(p)
    assert info.value.line == 3


def test_astm_polarization_header_refuses_an_underscore_number(tmp_path):
    """Why: ``POLARIZATION 0_5`` was read as 5 (radians)."""
    p = tmp_path / "p.astm"
    p.write_text(ASTM_HEAD.replace("NUM_POINTS", "POLARIZATION 0_5\nNUM_POINTS")
                 + "\n".join(ASTM_ROWS) + "\n", encoding="utf-8")
    with pytest.raises(FormatError, match=r"0_5") as info:
        rb.read(p)
    assert info.value.line == 3


@pytest.mark.parametrize("fmt", ["csv", "astm", "alta"])
def test_plain_numbers_still_read(tmp_path, fmt):
    """nan (a value), signs, exponents and blanks around commas read as always."""
    col = 4 if fmt != "alta" else 3  # the last value column
    rows = _with_field(fmt, 2, col, "+2.5E-1")
    rows[4] = _with_field(fmt, 4, col, "nan")[4]
    if FORMATS[fmt][3] == ",":
        rows[0] = rows[0].replace(",", " , ")
    m = rb.read(_write(tmp_path, fmt, rows))
    assert m.n_samples == 5
    assert np.isnan(m.values[4, -1]) and 0.25 in m.values[2]


# ------------------------------------------------------------------------------------------
# the angles' unit is plausible, or a warning says so
# ------------------------------------------------------------------------------------------
def test_radians_file_read_in_degrees_warns(tmp_path):
    """Why: an ASTM file in radians read with ``angles="deg"`` (every angle below 1.6 deg) was
    read and fitted without a word."""
    path = _write(tmp_path, "astm", ASTM_ROWS)
    with pytest.warns(ImplausibleAnglesWarning,
                      match=r"every theta_i and theta_s is below 2 deg \(the largest is 0\.5\)"
                            r".*look like radians; if they are, read the file with "
                            r"angles='rad'") as rec:
        rb.read(path, angles="deg")
    assert str(path) in str(rec[0].message)


def test_radians_in_a_file_declaring_degrees_warns(tmp_path):
    """A file whose own declaration says degrees, with angles that look like radians: the
    numbers are implausible all the same; the message points at the declaration."""
    p = tmp_path / "r.csv"
    p.write_text(CSV_HEAD + "0,0.1,0,0.5,0.6\n0.5,0.7,0,2.0,2.1\n1.2,1.5,3.1,0.1,0.2\n",
                 encoding="utf-8")
    with pytest.warns(ImplausibleAnglesWarning,
                      match=r"read in deg \(header angles\): they look like radians; if they "
                            r"are, correct the file's declaration$"):
        rb.read(p)


def test_degrees_file_read_as_radians_warns(tmp_path):
    """Why: a degrees file whose zeniths stay below 1.57 but whose azimuths reach 180 was read
    as radians without a word (zeniths above 90 deg are an error already)."""
    p = tmp_path / "d.csv"
    p.write_text(CSV_HEAD.replace("# angles: deg\n", "") + "0,1,0,0.5,0.6\n1,1.5,90,2.0,2.1\n"
                 "1,1.5,180,0.1,0.2\n", encoding="utf-8")
    with pytest.warns(ImplausibleAnglesWarning,
                      match=r"an angle is 180, above 2 pi.*look like degrees; if they are, read "
                            r"the file with angles='deg'"):
        rb.read(p, angles="rad")


@pytest.mark.parametrize("fmt", ["csv", "astm", "alta"])
def test_plausible_angles_do_not_warn(tmp_path, fmt):
    path = _write(tmp_path, fmt, FORMATS[fmt][1])
    with warnings.catch_warnings():
        warnings.simplefilter("error", ImplausibleAnglesWarning)
        rb.read(path)


def test_a_mini_diff_file_reads_without_warning(shared_data):
    path = shared_data / "minidiff" / "C2_Black.astm"
    if not path.exists():
        pytest.skip(f"{path} is absent")
    with warnings.catch_warnings():
        warnings.simplefilter("error", ImplausibleAnglesWarning)
        m = rb.read(path)
    assert m.n_samples == 12964
    assert not re.search("look like", str(m.meta))


ZEMAX = ("# hand-written test file\nSource\tMeasured\nSymmetry\tPlaneSymmetrical\n"
         "SpectralContent\tMonochrome\nScatterType\tBRDF\n\nSampleRotation\t1\n0\n"
         "AngleOfIncidence\t1\n30\nScatterAzimuth\t3\n0\t90\t180\nScatterRadial\t3\n0\t10\t20\n"
         "\nMonochrome\nDataBegin\nTIS\t0.5\n0.1\t0.11\t0.12\n0.1\t0.11\t0.12\n0.1\t0.11\t0.12\n"
         "DataEnd\n")


@pytest.mark.parametrize("old, new, line, reason", [
    ("0\t10\t20", "0\t1_0\t20", 14, r"non-numeric angle '1_0'"),
    ("TIS\t0.5", "TIS\t0_5", 18, r"a TIS line holds 'TIS' and one number"),
    ("0.1\t0.11\t0.12\nDataEnd", "0.1\t0.1_1\t0.12\nDataEnd", 21, r"'_' in the field '0.1_1'"),
    ("0.1\t0.11\t0.12\nDataEnd", "0.1\t０.11\t0.12\nDataEnd", 21, r"non-ASCII characters U\+FF10"),
])
def test_zemax_numbers_that_are_not_plain_ascii_are_refused(tmp_path, old, new, line, reason):
    """Why: the Zemax reader read ``1_0`` as 10 in its angle lists, its TIS and its rows."""
    p = tmp_path / "t.bsdf"
    p.write_text(ZEMAX.replace(old, new), encoding="utf-8")
    with pytest.raises(FormatError, match=reason) as info:
        rb.read(p)
    assert info.value.line == line


def test_zemax_sample_reads(tmp_path):
    p = tmp_path / "t.bsdf"
    p.write_text(ZEMAX, encoding="utf-8")
    assert rb.read(p).n_samples > 0
