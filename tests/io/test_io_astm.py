"""ASTM E1392 reader/writer: the real Mini-Diff files and every error case on small files."""

from __future__ import annotations

import math

import numpy as np
import pytest
from spies import python_calls_parsing_rows

import roughbrdf as rb
from roughbrdf.io import FormatError, astm

HEADER = """LAB_NAME Test Lab

SAMPLE_NAME Sample1
MEAS_NAME BRDF
MEAS_DATE 2024/01/02
NUM_POINTS {n}
VARS theta_i,phi_i,theta_s,465nm,525nm
"""


def _rows(deg: bool = False) -> list[str]:
    rows = []
    for ti in (0, 30):
        for ts in (0, 30, 60):
            for ps in (0, 180):
                a = [ti, 180, ts, ps] if deg else [math.radians(v) for v in (ti, 180, ts, ps)]
                rows.append(",".join(repr(float(v)) for v in a) + f",{0.1 + ts / 100},0.2")
    return rows


def _write(tmp_path, rows, n=None, header=HEADER, name="s.astm"):
    p = tmp_path / name
    p.write_text(header.format(n=len(rows) if n is None else n) + "\n".join(rows) + "\n")
    return p


# ------------------------------------------------------------------------------------------
# real files
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["C2_Black", "C8_Silver", "C12_OliveDrab"])
def test_real_minidiff_files(shared_data, name, monkeypatch):
    path = shared_data / "minidiff" / f"{name}.astm"
    parsed = python_calls_parsing_rows(monkeypatch, astm)
    m = rb.read(path)
    # the 12964 rows are parsed in one block, in NumPy (the read's time: benchmarks/)
    (rows, calls), = parsed
    assert rows == 12964 and calls < 100, parsed
    assert m.values.shape == (12964, 3)
    assert m.channels == ["465nm", "525nm", "630nm"]
    assert m.meta["wavelengths_nm"] == [465.0, 525.0, 630.0]
    assert m.quantity == "brdf"
    assert m.meta["format"] == "astm"
    assert m.meta["instrument"] == "Light Tec Mini-Diff V2"
    assert m.meta["date"].startswith("2023/12/05")
    assert any("phi_s" in q for q in m.meta["quirks"])
    assert m.meta["pole_rows"] == 4  # one pole row per incidence
    assert np.allclose(np.degrees(m.incidences(4)), [0, 20, 40, 60], atol=0.01)
    # negatives are kept and counted, there is no NaN
    rep = m.validate()
    n_neg = sum(r["negative"] for r in rep.values())
    assert 76 <= n_neg <= 120
    assert all(r["nonfinite"] == 0 for r in rep.values())
    assert (m.values < 0).sum() == n_neg and m.values.min() > -1e-3  # small noise
    # geometry: phi = phi_s (wrapped), the file's angles kept
    assert set(m.original) == {"theta_i", "phi_i", "theta_s", "phi_s"}
    assert np.allclose(np.cos(m.phi), np.cos(m.original["phi_s"]), atol=1e-12)
    assert np.allclose(np.sin(m.phi), np.sin(m.original["phi_s"]), atol=1e-12)
    assert np.allclose(m.theta_r, m.original["theta_s"], rtol=0, atol=1e-14)  # 90 deg clipped


def test_sample_name_disagreeing_with_file_name_is_kept(shared_data):
    m = rb.read(shared_data / "minidiff" / "C2_Black.astm")
    assert m.meta["sample"] == "C1_Black"
    assert m.meta["file"].endswith("C2_Black.astm")
    assert m.meta["file_name_declared"] == "C1_Black.astm"
    assert any("differs from the file name" in q for q in m.meta["quirks"])


def test_mirror_direction_of_glossy_black(shared_data):
    """data/README.md: mirror at theta_s = theta_i, phi_s = 0; at 60 deg the peak of C2_Black is
    off-specular, between 61 and 75 deg, on the forward side."""
    m = rb.read(shared_data / "minidiff" / "C2_Black.astm").at_incidence(math.radians(60))
    for j in range(3):
        k = int(np.argmax(m.values[:, j]))
        assert 61 - 1e-6 <= math.degrees(m.theta_r[k]) <= 75
        assert abs(math.degrees(m.phi[k])) < 1e-6  # forward side, phi = 0
        # the retro direction (phi = pi) is far below the peak
        retro = (np.abs(m.theta_r - math.radians(60)) < 1e-6) & (np.cos(m.phi) < -0.999)
        assert m.values[retro, j].max() < 0.05 * m.values[k, j]


# ------------------------------------------------------------------------------------------
# synthetic files
# ------------------------------------------------------------------------------------------
def test_synthetic_file_and_mapping(tmp_path):
    p = _write(tmp_path, _rows())
    m = rb.read(p)
    assert m.n_samples == 12 and m.channels == ["465nm", "525nm"]
    # phi_s = 0 -> phi = 0 (forward), phi_s = 180 -> phi = pi (source side)
    fwd = np.isclose(m.original["phi_s"], 0)
    assert np.allclose(m.phi[fwd], 0, atol=1e-12)
    assert np.allclose(np.abs(m.phi[~fwd]), math.pi, atol=1e-12)
    # a source at phi_i = 0 instead: phi = phi_s - phi_i + pi
    rows = [r.replace(repr(math.pi), "0.0", 1) for r in _rows()]
    m0 = rb.read(_write(tmp_path, rows, name="b.astm"))
    assert np.allclose(np.cos(m0.phi), -np.cos(m.phi), atol=1e-12)


def test_declared_degrees_are_honoured(tmp_path):
    header = HEADER.replace("VARS", "ANGLE_UNITS deg\nVARS")
    m = rb.read(_write(tmp_path, _rows(deg=True), header=header))
    assert m.meta["angle_units"] == "deg"
    assert np.allclose(np.degrees(m.incidences()), [0, 30])
    assert np.allclose(np.degrees(np.unique(m.theta_r)), [0, 30, 60])
    # unit in the VARS names
    header2 = HEADER.replace("theta_i,phi_i,theta_s", "theta_i(deg),phi_i(deg),theta_s(deg)")
    m2 = rb.read(_write(tmp_path, _rows(deg=True), header=header2, name="c.astm"))
    assert np.allclose(m2.theta_r, m.theta_r)
    # undeclared degrees: a clear error suggesting the unit
    with pytest.raises(FormatError, match="degrees"):
        rb.read(_write(tmp_path, _rows(deg=True), name="d.astm"))
    assert np.allclose(rb.read(tmp_path / "d.astm", angles="deg").theta_r, m.theta_r)


def test_nan_value_is_counted_not_an_error(tmp_path):
    rows = _rows()
    rows[3] = rows[3].rsplit(",", 1)[0] + ",nan"
    m = rb.read(_write(tmp_path, rows))
    assert m.validate()["525nm"]["nonfinite"] == 1 and m.n_samples == 12


@pytest.mark.parametrize("case, line, match", [
    ("truncated", 20, "truncated file: NUM_POINTS is 20 but only 12"),
    ("columns", 11, "wrong column count"),
    ("text", 12, "non-numeric field 'abc'"),
    ("nan_angle", 13, "theta_s is nan"),
    ("empty", 10, "empty field"),
    ("extra", 20, "NUM_POINTS is 12"),
])
def test_bad_input_names_file_and_line(tmp_path, case, line, match):
    rows = _rows()
    n = None
    if case == "truncated":
        n = 20
    elif case == "columns":
        rows[3] = rows[3] + ",0.5"
    elif case == "text":
        rows[4] = rows[4].replace("0.2", "abc")
    elif case == "nan_angle":
        f = rows[5].split(",")
        f[2] = "nan"
        rows[5] = ",".join(f)
    elif case == "empty":
        rows[2] = rows[2].rsplit(",", 1)[0] + ","  # row 3 (file line 10) ends with an empty field
    elif case == "extra":
        rows = rows + [rows[0]]
        n = 12
    p = _write(tmp_path, rows, n=n)
    with pytest.raises(FormatError, match=match) as exc:
        rb.read(p)
    assert exc.value.path == str(p)
    assert exc.value.line == line
    assert f"{p}, line {line}:" in str(exc.value)


def test_missing_vars_and_unknown_measurement(tmp_path):
    p = tmp_path / "novars.astm"
    p.write_text("SAMPLE_NAME x\nNUM_POINTS 1\n0,0,0,0,1\n")
    with pytest.raises(FormatError, match="no VARS line") as exc:
        rb.read(p)
    assert exc.value.line == 3
    p2 = _write(tmp_path, _rows(), header=HEADER.replace("MEAS_NAME BRDF", "MEAS_NAME BTDF"),
                name="btdf.astm")
    with pytest.raises(FormatError, match="quantity"):
        rb.read(p2)
    assert rb.read(p2, quantity="relative").quantity == "relative"


def test_write_read_round_trip(tmp_path, shared_data=None):
    m = rb.read(_write(tmp_path, _rows()))
    for unit in ("rad", "deg"):
        out = tmp_path / f"rt_{unit}.astm"
        astm.write(m, out, angles=unit)
        r = rb.read(out)
        assert r.channels == m.channels and r.quantity == "brdf"
        assert not r.meta["quirks"] or "phi_s" not in " ".join(r.meta["quirks"])
        for a in ("theta_i", "theta_r", "values"):
            assert np.allclose(getattr(r, a), getattr(m, a), rtol=1e-14, atol=1e-14)
        assert np.allclose(np.cos(r.phi), np.cos(m.phi), atol=1e-14)
    with pytest.raises(ValueError, match="relative"):
        astm.write(m.as_quantity("relative"), tmp_path / "r.astm")
