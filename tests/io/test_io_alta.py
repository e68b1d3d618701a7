"""ALTA text reader/writer: the CEA retro-reflection files, the angle mapping, error cases."""

from __future__ import annotations

import math

import numpy as np
import pytest
from spies import python_calls_parsing_rows

import roughbrdf as rb
from roughbrdf.io import FormatError, alta
from roughbrdf.measurement import Measurement

HEAD = "#DIM 3 1\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT INV_STERADIAN\n"


def _write(tmp_path, rows, head=HEAD, name="a.dat"):
    p = tmp_path / name
    p.write_text(head + "\n".join(rows) + "\n")
    return p


def _row(tl, tv, dphi, *vals):
    return " ".join(repr(float(v)) for v in (tl, tv * math.cos(dphi), tv * math.sin(dphi), *vals))


# ------------------------------------------------------------------------------------------
# real files
# ------------------------------------------------------------------------------------------
def test_missing_param_out_asks_for_quantity(shared_data):
    path = shared_data / "cea_retro" / "retro-gray-tape.dat"
    with pytest.raises(FormatError, match="PARAM_OUT.*quantity=.*--quantity") as exc:
        rb.read(path)
    assert exc.value.path == str(path)
    m = rb.read(path, quantity="brdf_cos")
    assert m.quantity == "brdf_cos" and m.meta["sample"] == "Gray Tape"


def test_gray_tape_retro_peak_at_retro_direction(shared_data, monkeypatch):
    """ALTA's dphi = 0 is the source side: the retro peak must land at theta_r = theta_i,
    phi = pi. data/README.md gives the peak heights 72.5, 42.5, 1.13 (BRDF x cos)."""
    parsed = python_calls_parsing_rows(monkeypatch, alta)
    m = rb.read(shared_data / "cea_retro" / "retro-gray-tape.dat", quantity="brdf_cos")
    # the rows are parsed in one block, in NumPy (the read's time: benchmarks/)
    (rows, calls), = parsed
    assert rows == m.n_samples and calls < 100, parsed
    assert np.allclose(np.degrees(m.incidences(4)), [15, 30, 60], atol=0.01)
    for deg, height in ((15, 72.5), (30, 42.5), (60, 1.13)):
        s = m.at_incidence(math.radians(deg))
        retro = (np.abs(s.theta_r - s.theta_i) < 1e-9) & (np.cos(s.phi) < -1 + 1e-12)
        assert retro.sum() == 1
        assert s.values[retro, 0][0] == pytest.approx(height, rel=0.01)
        # the original x1 = +theta_l, x2 = 0 is kept
        assert s.original["x1"][retro][0] == pytest.approx(math.radians(deg), abs=1e-12)
        back = s.subset(np.cos(s.phi) < 0)  # source half: the retro lobe
        k = int(np.argmax(back.values[:, 0]))
        dist = math.hypot(back.theta_r[k] * math.cos(back.phi[k]) + math.radians(deg),
                          back.theta_r[k] * math.sin(back.phi[k]))
        assert math.degrees(dist) < 1.5
        if deg < 60:  # at 15 and 30 deg the retro peak is also the global maximum
            k = int(np.argmax(s.values[:, 0]))
            assert math.degrees(s.theta_r[k]) == pytest.approx(deg, abs=1e-9)
            assert abs(math.cos(s.phi[k]) + 1) < 1e-12


@pytest.mark.parametrize("name, quantity", [("retro-gray-tape-dense.dat", "brdf"),
                                            ("retro-3M-jaune.dat", "brdf_cos"),
                                            ("retro-3M-jaune-dense.dat", "brdf_cos")])
def test_param_out_gives_quantity(shared_data, name, quantity):
    m = rb.read(shared_data / "cea_retro" / name)
    assert m.quantity == quantity and m.meta["param_in"] == "ISOTROPIC_TL_TV_PROJ_DPHI"
    assert set(m.original) == {"x0", "x1", "x2"}
    assert np.array_equal(m.theta_i, m.original["x0"])
    assert all(r["nonfinite"] == 0 for r in m.validate().values())


# ------------------------------------------------------------------------------------------
# mapping and round trips on synthetic files
# ------------------------------------------------------------------------------------------
def test_mapping_source_side_is_dphi_zero(tmp_path):
    tl = math.radians(40)
    rows = [_row(tl, tl, 0.0, 5.0),            # retro
            _row(tl, tl, math.pi, 3.0),        # mirror
            _row(tl, math.radians(20), math.radians(60), 1.0),
            _row(tl, 0.0, 0.0, 2.0)]           # normal view
    m = rb.read(_write(tmp_path, rows))
    assert np.allclose(m.theta_r, [tl, tl, math.radians(20), 0.0])
    assert abs(math.cos(m.phi[0]) + 1) < 1e-12       # retro -> phi = pi
    assert abs(m.phi[1]) < 1e-12                      # mirror -> phi = 0
    assert abs(abs(m.phi[2]) - math.radians(120)) < 1e-12   # |phi| = pi - |dphi|
    # the common-frame geometry gives the same theta_h as ALTA's own vectors
    th = rb.geometry.theta_h(m.theta_i, m.theta_r, m.phi)
    assert th[1] == pytest.approx(0.0, abs=1e-7) and th[0] == pytest.approx(tl, abs=1e-12)


def test_other_parametrizations(tmp_path):
    tl, tv, dphi = math.radians(30), math.radians(50), math.radians(70)
    ref = rb.read(_write(tmp_path, [_row(tl, tv, dphi, 1.0)]))
    p2 = _write(tmp_path, [f"{tv!r} {tl!r} {dphi!r} 1.0"],
                head="#DIM 3 1\n#PARAM_IN ISOTROPIC_TV_TL_DPHI\n#PARAM_OUT INV_STERADIAN\n",
                name="b.dat")
    p3 = _write(tmp_path, [f"{tl!r} 0.3 {tv!r} {0.3 + dphi!r} 1.0"],
                head="#DIM 4 1\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n#PARAM_OUT INV_STERADIAN\n",
                name="c.dat")
    th, td, pd = rb.geometry.to_rusinkiewicz(ref.theta_i, ref.theta_r, ref.phi)
    p4 = _write(tmp_path, [f"{float(th[0])!r} {float(td[0])!r} {float(pd[0])!r} 1.0"],
                head="#DIM 3 1\n#PARAM_IN RUSIN_TH_TD_PD\n#PARAM_OUT INV_STERADIAN\n",
                name="d.dat")
    for p in (p2, p3, p4):
        m = rb.read(p)
        assert m.theta_i[0] == pytest.approx(ref.theta_i[0], abs=1e-9)
        assert m.theta_r[0] == pytest.approx(ref.theta_r[0], abs=1e-9)
        assert abs(m.phi[0]) == pytest.approx(abs(ref.phi[0]), abs=1e-9)


def test_write_read_round_trip_multichannel_with_uncertainty(tmp_path):
    rng = np.random.default_rng(1)
    n = 50
    m = Measurement(theta_i=rng.uniform(0, 1.4, n), theta_r=rng.uniform(0, 1.5, n),
                       phi=rng.uniform(-np.pi, np.pi, n), values=rng.uniform(0, 3, (n, 3)),
                       channels=["465nm", "525nm", "630nm"], quantity="brdf_cos",
                       uncertainty=rng.uniform(0, 0.1, (n, 3)), meta={"sample": "S x"})
    out = tmp_path / "rt.alta"
    rb.write(m, out)
    r = rb.read(out)
    assert r.quantity == "brdf_cos" and r.channels == m.channels and r.meta["vs"] == 1
    assert r.meta["sample"] == "S x"
    assert np.allclose(r.theta_i, m.theta_i, atol=1e-15)
    assert np.allclose(r.theta_r, m.theta_r, atol=1e-14)
    assert np.allclose(r.phi, m.phi, atol=1e-13)
    assert np.allclose(r.values, m.values, rtol=1e-15)
    assert np.allclose(r.uncertainty, m.uncertainty, rtol=1e-15)
    with pytest.raises(ValueError, match="relative"):
        rb.write(m.as_quantity("relative"), tmp_path / "x.dat")


def test_confidence_interval_vs2(tmp_path):
    head = HEAD.replace("#DIM 3 1", "#DIM 3 1\n#VS 2")
    m = rb.read(_write(tmp_path, [_row(0.3, 0.3, 0.0, 2.0, 1.8, 2.4)], head=head))
    assert m.values[0, 0] == 2.0 and m.uncertainty[0, 0] == pytest.approx(0.3)


# ------------------------------------------------------------------------------------------
# errors
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("case, line, match", [
    ("columns", 5, "wrong column count"),
    ("text", 6, "non-numeric field 'x'"),
    ("nan_angle", 5, "x1 is nan"),
    ("tv_range", 6, r"theta_v = hypot\(x1, x2\) = .* outside \[0, 90\] deg"),
])
def test_bad_rows_name_file_and_line(tmp_path, case, line, match):
    rows = [_row(0.3, 0.2 * k, 0.1, 1.0) for k in range(4)]  # file lines 4..7
    if case == "columns":
        rows[1] += " 7"
    elif case == "text":
        rows[2] = rows[2].rsplit(" ", 1)[0] + " x"
    elif case == "nan_angle":
        f = rows[1].split()
        f[1] = "nan"
        rows[1] = " ".join(f)
    elif case == "tv_range":
        rows[2] = _row(0.3, 2.0, 0.1, 1.0)
    p = _write(tmp_path, rows)
    with pytest.raises(FormatError, match=match) as exc:
        rb.read(p)
    assert exc.value.line == line and exc.value.path == str(p)
    assert f"line {line}" in str(exc.value)


def test_nan_value_is_counted(tmp_path):
    m = rb.read(_write(tmp_path, [_row(0.3, 0.2, 0.1, 1.0), _row(0.3, 0.3, 0.1, float("nan"))]))
    assert m.validate()["value"]["nonfinite"] == 1 and m.n_samples == 2


@pytest.mark.parametrize("head, match", [
    ("#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT INV_STERADIAN\n", "no #DIM"),
    ("#DIM 3 1\n#PARAM_OUT INV_STERADIAN\n", "no #PARAM_IN"),
    ("#DIM 3 1\n#PARAM_IN STEREOGRAPHIC\n#PARAM_OUT INV_STERADIAN\n", "not supported"),
    ("#DIM 4 1\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT INV_STERADIAN\n", "#DIM says 4"),
    ("#DIM 3 1\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT RGB_COLOR\n", "--quantity"),
    ("#DIM 3 1\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT INV_STERADIAN\n"
     "#SAMPLE_COUNT 9\n", "truncated file"),
])
def test_bad_headers(tmp_path, head, match):
    with pytest.raises(FormatError, match=match):
        rb.read(_write(tmp_path, [_row(0.3, 0.2, 0.1, 1.0)], head=head))


def test_quantity_conflicting_with_param_out(tmp_path):
    p = _write(tmp_path, [_row(0.3, 0.2, 0.1, 1.0)])
    with pytest.raises(FormatError, match="contradicts"):
        alta.read(p, quantity="brdf_cos")
    assert alta.read(p, quantity="brdf").quantity == "brdf"
