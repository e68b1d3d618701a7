"""roughbrdf CSV: round trips, declared units, and every error case naming file and line."""

from __future__ import annotations

import math

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.io import FormatError, csv
from roughbrdf.measurement import Measurement

GOOD = """# roughbrdf-csv 1
# angles: deg
# quantity: brdf
# sample: paint
theta_i,theta_r,phi,465nm,525nm
0,10,0,0.5,0.6
30,30,0,2.0,2.1
30,30,180,0.1,0.2
60,70,90,0.3,0.4
"""


def _write(tmp_path, text, name="m.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def _measurement(n=40, seed=0):
    rng = np.random.default_rng(seed)
    return Measurement(
        theta_i=rng.uniform(0, 1.5, n), theta_r=rng.uniform(0, 1.5707963267948966, n),
        phi=rng.uniform(-np.pi, np.pi, n), values=rng.uniform(-0.01, 5, (n, 2)),
        channels=["465nm", "525nm"], quantity="relative",
        polarization=np.where(rng.uniform(size=n) < 0.3, np.nan, rng.uniform(0, 1.5, n)),
        uncertainty=rng.uniform(0, 0.1, (n, 2)), original={"x1": rng.normal(size=n)},
        meta={"sample": "S", "instrument": "gonio, lab A", "date": "2024-01-01",
              "file": "src.astm", "format": "astm"})


def test_read_documented_layout(tmp_path):
    m = rb.read(_write(tmp_path, GOOD))
    assert m.channels == ["465nm", "525nm"] and m.quantity == "brdf" and m.n_samples == 4
    assert np.allclose(np.degrees(m.theta_r), [10, 30, 30, 70])
    assert np.allclose(np.degrees(m.phi), [0, 0, 180, 90])
    assert m.meta["sample"] == "paint" and m.meta["format"] == "csv"
    assert m.polarization is None and m.uncertainty is None


@pytest.mark.parametrize("unit", ["deg", "rad"])
def test_round_trip(tmp_path, unit):
    m = _measurement()
    out = tmp_path / f"rt_{unit}.csv"
    rb.write(m, out, angles=unit)
    r = rb.read(out)
    assert r.channels == m.channels and r.quantity == "relative"
    for a in ("theta_i", "theta_r", "phi"):
        assert np.allclose(getattr(r, a), getattr(m, a), rtol=1e-15, atol=1e-15)
    assert np.array_equal(r.values, m.values)
    assert np.array_equal(r.uncertainty, m.uncertainty)
    assert np.allclose(r.polarization, m.polarization, rtol=1e-15, equal_nan=True)
    assert np.array_equal(r.original["x1"], m.original["x1"])
    assert r.meta["instrument"] == "gonio, lab A" and r.meta["source_file"] == "src.astm"
    assert r.meta["angle_units"] == unit


def test_units_from_column_names_as_eval_writes_them(tmp_path):
    text = "theta_i_deg,theta_r_deg,phi_deg,brdf\n30,20,0,0.25\n30,40,0,0.5\n"
    m = rb.read(_write(tmp_path, text))
    assert m.quantity == "brdf" and m.channels == ["brdf"]
    assert np.allclose(np.degrees(m.theta_r), [20, 40])


def test_polarization_tokens_and_nan_values(tmp_path):
    text = ("# angles: deg\n# quantity: bridf\ntheta_i,theta_r,phi,v,polarization\n"
            "30,30,0,1.0,s\n30,30,0,nan,p\n30,30,0,2.0,\n30,30,0,3.0,45\n")
    m = rb.read(_write(tmp_path, text))
    assert m.polarization[0] == pytest.approx(math.pi / 2) and m.polarization[1] == 0.0
    assert math.isnan(m.polarization[2]) and m.polarization[3] == pytest.approx(math.pi / 4)
    assert m.validate()["v"]["nonfinite"] == 1  # counted, not an error


@pytest.mark.parametrize("text, line, match", [
    (GOOD.replace("# angles: deg\n", ""), 4, "missing angle units"),
    (GOOD.replace("# quantity: brdf\n", ""), 4, "missing quantity"),
    (GOOD.replace("30,30,180,0.1,0.2", "30,30,180,0.1"), 8, "wrong column count"),
    (GOOD.replace("30,30,180,0.1,0.2", "30,30,180,0.1,0.2,9"), 8, "wrong column count"),
    (GOOD.replace("60,70,90,0.3,0.4", "60,70,90,abc,0.4"), 9, "non-numeric field 'abc'"),
    (GOOD.replace("0,10,0,0.5,0.6", "0,nan,0,0.5,0.6"), 6, "theta_r is nan"),
    (GOOD.replace("60,70,90,0.3,0.4", "60,70,inf,0.3,0.4"), 9, "phi is inf"),
    (GOOD.replace("60,70,90,0.3,0.4", "60,100,90,0.3,0.4"), 9, "outside"),
    (GOOD.replace("30,30,0,2.0,2.1", "30,,0,2.0,2.1"), 7, "empty field"),
    (GOOD.replace("theta_r,", "theta_s,"), 5, "missing column 'theta_r'"),
    (GOOD.replace("# angles: deg", "# angles: grad"), 2, "unknown angle unit"),
    (GOOD.replace("# quantity: brdf", "# quantity: radiance"), 3, "not one of"),
    (GOOD.replace("525nm", "465nm"), 5, "duplicate column"),
    (GOOD.replace("525nm", "525nm,sigma_630nm").replace(",0.6", ",0.6,0"), 5, "sigma_"),
])
def test_errors_name_file_and_line(tmp_path, text, line, match):
    p = _write(tmp_path, text)
    with pytest.raises(FormatError, match=match) as exc:
        rb.read(p)
    assert exc.value.path == str(p) and exc.value.line == line
    assert str(exc.value).startswith(f"{p}, line {line}: ")


def test_options_supply_missing_declarations(tmp_path):
    text = "theta_i,theta_r,phi,v\n0.5,0.5,0,1\n"
    m = csv.read(_write(tmp_path, text), angles="rad", quantity="brdf_cos")
    assert m.quantity == "brdf_cos" and m.theta_i[0] == 0.5


def test_unknown_extension_and_format_override(tmp_path):
    p = _write(tmp_path, GOOD, name="data.xyz")
    assert rb.read(p).n_samples == 4  # sniffed from the '# roughbrdf-csv' tag
    q = _write(tmp_path, GOOD.replace("# roughbrdf-csv 1\n", ""), name="data.txt2")
    with pytest.raises(FormatError, match="unknown format for extension '.txt2'") as exc:
        rb.read(q)
    assert exc.value.path == str(q)
    assert rb.read(q, format="csv").n_samples == 4
    with pytest.raises(FormatError, match="unknown format 'hdf5'"):
        rb.read(q, format="hdf5")
    with pytest.raises(FileNotFoundError):
        rb.read(tmp_path / "missing.csv")


def test_writer_refuses_bad_channel_names(tmp_path):
    m = _measurement()
    m.channels = ["a,b", "c"]
    with pytest.raises(ValueError, match="cannot be a CSV column"):
        rb.write(m, tmp_path / "x.csv")


def test_relative_to_and_bom_survive(tmp_path):
    text = "\ufeff" + GOOD.replace("# quantity: brdf", "# quantity: relative\n# relative_to: bridf")
    m = rb.read(_write(tmp_path, text))
    assert m.quantity == "relative" and m.meta["relative_to"] == "bridf"
    rb.write(m, tmp_path / "again.csv")
    assert rb.read(tmp_path / "again.csv").meta["relative_to"] == "bridf"
