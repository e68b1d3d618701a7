"""Zemax OpticStudio tabular BSDF (``.bsdf``): every convention pinned (specular direction,
azimuth origin and handedness, PlaneSymmetrical's half range, AngleOfIncidence = theta_i, TIS),
the public LOFT files read, the reader's errors with their lines, and the writer of a
Measurement (exact on a Zemax grid, refusing and reporting otherwise)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.errors import ArgumentError
from roughbrdf.io import FormatError, format_for, zemax
from roughbrdf.io.zemax import (
    ZemaxGrid,
    common_to_specular,
    read_table,
    specular_to_common,
    table_integral,
)

DATA = Path(__file__).parents[1] / "data" / "zemax"
NITE = DATA / "AnoBlackNiTEonINVAR.bsdf"
AERO = DATA / "aeroglaze.bsdf"
D = math.pi / 180


def _vector(theta_r, phi):
    return np.stack([np.sin(theta_r) * np.cos(phi), np.sin(theta_r) * np.sin(phi),
                     np.cos(theta_r)], axis=-1)


def _text(aoi=(30,), az=(0, 90, 180), rad=(0, 10, 20), sym="PlaneSymmetrical", rot=(0,),
          value=lambda i, j, k: 0.1 + 0.01 * k, tis=0.5, extra_header="") -> str:
    """A small valid file, written by hand from the documented layout."""
    lines = ["# hand-written test file", "Source\tMeasured", f"Symmetry\t{sym}",
             "SpectralContent\tMonochrome", "ScatterType\tBRDF", extra_header]
    for key, vals in (("SampleRotation", rot), ("AngleOfIncidence", aoi),
                      ("ScatterAzimuth", az), ("ScatterRadial", rad)):
        lines += [f"{key}\t{len(vals)}", "\t".join(str(v) for v in vals)]
    lines += ["", "Monochrome", "DataBegin"]
    for _ in rot:
        for i, _a in enumerate(aoi):
            lines.append(f"TIS\t{tis}")
            for j in range(len(az)):
                lines.append("\t".join(f"{value(i, j, k):.6g}" for k in range(len(rad))))
    lines.append("DataEnd")
    return "\n".join(line for line in lines if line is not None) + "\n"


def _write(tmp_path, text, name="t.bsdf") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


# ------------------------------------------------------------------------------------------
# conventions
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("aoi_deg", [0.0, 10.0, 30.0, 60.0, 85.0])
def test_radial_zero_is_the_specular_direction_at_every_azimuth(aoi_deg):
    t = aoi_deg * D
    for a in np.radians([0, 45, 90, 180, 270]):
        tr, ph, cz = specular_to_common(t, 0.0, a)
        assert float(tr) == pytest.approx(t, abs=1e-15)
        assert float(cz) == pytest.approx(math.cos(t), abs=1e-15)
        if aoi_deg:
            assert float(ph) == pytest.approx(0.0, abs=1e-15)   # phi = 0: the specular side


def test_radial_is_the_true_angle_from_the_specular_direction():
    rng = np.random.default_rng(1)
    t, r, a = rng.uniform(0, 1.5, 200), rng.uniform(0, math.pi, 200), rng.uniform(0, 6.28, 200)
    tr, ph, _ = specular_to_common(t, r, a)
    cosang = np.sum(_vector(tr, ph) * _vector(t, 0.0), axis=-1)
    assert np.allclose(np.arccos(np.clip(cosang, -1, 1)), r, atol=1e-7)
    # not the projected distance |beta - beta0| of direction cosines (ABg's variable): 70 deg
    # sideways of a 70 deg specular direction is a direction above the horizon, where
    # |beta - beta0| could not exceed sin(20 deg)
    tr, ph, _ = specular_to_common(70 * D, 70 * D, 90 * D)
    assert float(np.cos(tr)) == pytest.approx(math.cos(70 * D) ** 2, abs=1e-15)


def test_azimuth_zero_points_toward_the_normal_180_outward():
    t = 40 * D
    tr, ph, _ = specular_to_common(t, 40 * D, 0.0)       # 40 deg toward the normal: normal
    assert float(tr) == pytest.approx(0.0, abs=1e-12)
    tr, ph, _ = specular_to_common(t, 60 * D, 0.0)       # past the normal: source side
    assert math.degrees(float(tr)) == pytest.approx(20.0) and abs(float(ph)) == pytest.approx(
        math.pi)
    tr, ph, _ = specular_to_common(t, 10 * D, math.pi)   # outward: toward the horizon
    assert math.degrees(float(tr)) == pytest.approx(50.0) and float(ph) == pytest.approx(0.0)
    tr, ph, cz = specular_to_common(t, 50 * D, math.pi)  # the horizon at 90 - aoi
    assert abs(float(cz)) < 1e-15
    _, _, cz = specular_to_common(t, 131 * D, 0.0)       # past 90 + aoi toward the normal
    assert float(cz) < 0


def test_azimuth_increases_counter_clockwise_seen_from_above():
    """Azimuth 90 deg is v = s x u0: a counter-clockwise turn from u0 (toward the normal)
    about the specular direction s, seen from its tip (from above the sample)."""
    t, r = 30 * D, 1e-3
    s = _vector(t, 0.0)
    w0 = _vector(*specular_to_common(t, r, 0.0)[:2]) - s
    w90 = _vector(*specular_to_common(t, r, 90 * D)[:2]) - s
    u0, v = w0 / np.linalg.norm(w0), w90 / np.linalg.norm(w90)
    assert np.allclose(np.cross(u0, v), s, atol=1e-3)     # right-handed about s
    assert v[1] < 0                                        # i.e. azimuth 90 has phi < 0
    # libbsdf's SpecularCoordinateSystem (incidence on +x) rotated by pi about z: the same
    assert np.allclose(u0, [-math.cos(t), 0, math.sin(t)], atol=1e-3)


def test_normal_incidence_azimuth_zero_is_the_source_side():
    tr, ph, _ = specular_to_common(0.0, 20 * D, 0.0)
    assert math.degrees(float(tr)) == pytest.approx(20.0) and abs(float(ph)) == pytest.approx(
        math.pi)
    near = specular_to_common(1e-9, 20 * D, 0.0)
    assert float(near[0]) == pytest.approx(float(tr)) and abs(float(near[1])) == pytest.approx(
        math.pi)


def test_common_to_specular_inverts_specular_to_common():
    rng = np.random.default_rng(2)
    t = rng.uniform(0, 1.5, 500)
    r = rng.uniform(1e-6, math.pi, 500)
    a = rng.uniform(0, 2 * math.pi, 500)
    tr, ph, cz = specular_to_common(t, r, a)
    above = cz > 0
    r2, a2 = common_to_specular(t[above], tr[above], ph[above])
    assert np.allclose(r2, r[above], atol=1e-9)
    assert np.allclose(np.angle(np.exp(1j * (a2 - a[above]))), 0, atol=1e-7)


def test_angle_of_incidence_is_theta_i_and_the_specular_angle(tmp_path):
    p = _write(tmp_path, _text(aoi=(0, 30, 75)))
    m = rb.read(p)
    assert sorted(set(np.round(np.degrees(m.theta_i), 9))) == [0, 30, 75]
    spec = m.original["scatter_radial"] == 0
    assert np.allclose(m.theta_r[spec], m.theta_i[spec], atol=1e-12)  # theta_s = theta_i
    assert np.allclose(m.phi[spec & (m.theta_i > 0)], 0, atol=1e-12)
    assert np.allclose(m.original["angle_of_incidence"], np.degrees(m.theta_i))


def test_plane_symmetrical_half_range(tmp_path):
    ok = rb.read(_write(tmp_path, _text(az=(0, 45, 90, 135, 180))))
    assert ok.meta["zemax_grid"]["symmetry"] == "PlaneSymmetrical"
    assert (ok.phi <= 1e-12).all()                  # azimuths 0-180: the phi <= 0 half
    with pytest.raises(FormatError, match=r"ScatterAzimuth angles must lie in \[0, 180\]") as e:
        rb.read(_write(tmp_path, _text(az=(0, 90, 180, 270)), "bad.bsdf"))
    assert e.value.line == 11                       # the ScatterAzimuth keyword line
    full = rb.read(_write(tmp_path, _text(az=(0, 90, 180, 270, 360), sym="Asymmetrical"),
                          "full.bsdf"))
    assert (full.phi > 0).any() and (full.phi < 0).any()
    assert full.meta["zemax_duplicates"] >= 3       # azimuth 360 repeats azimuth 0


def test_plane_symmetrical_counts_the_mirror_half_in_the_integral():
    rad = np.arange(0, 111, 1.0)                    # 90 + 20: the whole hemisphere
    half = ZemaxGrid((20,), tuple(np.arange(0, 181, 10.0)), tuple(rad))
    full = ZemaxGrid((20,), tuple(np.arange(0, 361, 10.0)), tuple(rad), symmetry="Asymmetrical")
    c = 0.4 / math.pi
    assert table_integral(np.full(half.shape, c), half)[0, 0] == pytest.approx(
        table_integral(np.full(full.shape, c), full)[0, 0], rel=1e-12)
    assert table_integral(np.full(half.shape, c), half)[0, 0] == pytest.approx(0.4, abs=2e-3)


def test_tis_is_kept_and_the_table_integral_is_the_cosine_weighted_reflectance(tmp_path):
    p = _write(tmp_path, _text(aoi=(10, 50), az=tuple(range(0, 181, 10)),
                               rad=tuple(range(0, 141, 2)), value=lambda i, j, k: 0.1, tis=0.31))
    m = rb.read(p)
    assert m.meta["zemax_tis"] == [[0.31, 0.31]]
    table = read_table(p)
    assert np.allclose(table_integral(table.values, table.grid), 0.1 * math.pi, atol=2e-3)


# ------------------------------------------------------------------------------------------
# the public files (tests/data/zemax, MIT, LOFT group)
# ------------------------------------------------------------------------------------------
def test_public_file_cut_off_pins_the_conventions():
    """The LOFT writers set the BRDF to 0 beyond 80 deg from the normal: with these
    conventions every non-zero node lies at theta_r <= 80 deg and every zero node beyond;
    with the azimuth origin reversed, non-zero nodes would lie below the horizon."""
    table = read_table(NITE)
    g = table.grid
    _, tr, _, cz = g.directions()
    v = table.values[0]
    assert np.degrees(tr[v > 0]).max() <= 80 + 1e-9
    assert np.degrees(tr[v == 0]).min() > 80.1
    t = np.radians(g.aoi_deg)[:, None, None]
    a = np.radians(g.azimuth_deg)[None, :, None] + math.pi      # azimuth 0 pointing outward
    _, _, cz_flipped = specular_to_common(t, np.radians(g.radial_deg)[None, None, :], a)
    assert (cz_flipped[v > 0] < -0.3).any()


def test_public_in_plane_file_crosses_the_normal():
    m = rb.read(AERO)
    g = m.meta["zemax_grid"]
    assert g["scatter_azimuth"] == [0, 180] and g["scatter_radial"][-1] == 160
    o = m.original
    # incidence 70: azimuth 0, radial 150 is 80 deg on the source side (phi = pi), non-zero
    k = np.flatnonzero((o["angle_of_incidence"] == 70) & (o["scatter_azimuth"] == 0) &
                       (o["scatter_radial"] == 150))[0]
    assert math.degrees(m.theta_r[k]) == pytest.approx(80) and abs(m.phi[k]) == pytest.approx(
        math.pi)
    assert m.values[k, 0] > 0
    nz = m.values[:, 0] > 0
    assert np.degrees(m.theta_r[nz]).max() == pytest.approx(80)
    assert np.degrees(m.theta_r[~nz]).min() == pytest.approx(81)


def test_public_file_read_specular_and_tis():
    m = rb.read(NITE)
    table = read_table(NITE)
    assert m.n_samples == 714 and m.channels == ["value"] and m.quantity == "brdf"
    assert m.meta["zemax_below_horizon"] == 126 and m.meta["zemax_below_horizon_nonzero"] == 0
    assert m.meta["zemax_duplicates"] == 4 * 18      # radial 0 repeated at 18 more azimuths
    assert m.meta["zemax_tis"] == [[0.043801, 0.04566, 0.059009, 0.11661]]
    for i, aoi in enumerate((10, 30, 50, 70)):
        spec = (m.original["angle_of_incidence"] == aoi) & (m.original["scatter_radial"] == 0)
        assert spec.sum() == 1                        # the specular direction, once
        assert math.degrees(m.theta_r[spec][0]) == pytest.approx(aoi)
        assert m.phi[spec][0] == pytest.approx(0.0, abs=1e-12)
        assert m.values[spec, 0][0] == table.values[0, i, 0, 0]
    # the file's TIS lines were computed by its writer's own formula (an integral without
    # the cosine); the cosine-weighted reflectance of its table differs from them by far more
    # than the grid's accuracy, so the reader keeps them as read and uses none of them
    own = table_integral(table.values, table.grid)[0]
    assert np.allclose(own, [0.0623, 0.0590, 0.0591, 0.0852], atol=5e-4)
    assert np.abs(own - table.tis[0]).max() > 0.01


def test_public_file_round_trip_is_exact(tmp_path):
    m = rb.read(NITE)
    out = tmp_path / "copy.bsdf"
    report = rb.write(m, out)
    assert report.by_index and not report.changes_samples
    assert report.tis_source.startswith("the source file")
    a, b = read_table(NITE), read_table(out)
    assert a.grid == b.grid and np.array_equal(a.values, b.values)
    assert np.array_equal(a.tis, b.tis) and a.comments == b.comments
    m2 = rb.read(out)
    for k in ("theta_i", "theta_r", "phi", "values"):
        assert np.array_equal(getattr(m, k), getattr(m2, k))
    again = tmp_path / "again.bsdf"
    rb.write(m2, again)
    assert again.read_bytes() == out.read_bytes()


def test_public_file_can_be_fitted():
    m = rb.read(NITE)
    measured = m.subset(m.values[:, 0] > 0)          # the zeros are the writer's cut-off
    res = rb.fit("lambertian", measured, starts=1, loss="absolute")
    # least squares in BRDF: rho = pi x the mean BRDF of the samples
    assert res.success
    assert res.params["rho"] == pytest.approx(math.pi * measured.values.mean(), rel=1e-3)


# ------------------------------------------------------------------------------------------
# reader errors: FormatError with the line at fault
# ------------------------------------------------------------------------------------------
def _replace_line(text: str, lineno: int, new: str | None) -> str:
    lines = text.splitlines()
    if new is None:
        del lines[lineno - 1]
    else:
        lines[lineno - 1] = new
    return "\n".join(lines) + "\n"


GOOD = _text()   # lines: 1 comment, 2-5 keywords, 6 blank extra, 7-14 counted, 16 Monochrome,
#                  17 DataBegin, 18 TIS, 19-21 rows, 22 DataEnd


@pytest.mark.parametrize("lineno, new, line, match", [
    (11, "ScatterAzimuth\t4", 12, r"ScatterAzimuth 4 \(line 11\) is followed by 3 angles"),
    (12, "0\t90\t180\t270", 12, r"followed by 4 angles"),
    (13, "ScatterRadial\tthree", 13, "count must be a whole number"),
    (13, "ScatterRadial\t2.5", 13, "count must be a whole number"),
    (14, "0\t10\tx", 14, "non-numeric angle 'x'"),
    (14, "0\t20\t10", 13, "must increase strictly"),
    (10, "95", 9, r"AngleOfIncidence angles must lie in \[0, 90\]"),
    (19, "0.1\t0.11", 19, "expected 3 values"),
    (20, "0.1\t0.11\t0.12\t0.5", 20, "found 4"),
    (21, "0.1\tabc\t0.12", 21, "non-numeric field 'abc'"),
    (18, "0.1\t0.11\t0.12", 18, "expected 'TIS <value>' to begin block 1"),
    (18, "TIS\thigh", 18, "TIS line holds 'TIS' and one number"),
    (22, None, 22, "no DataEnd after the last block"),
    (21, "DataEnd", 21, r"DataEnd after 2 value rows of 3"),
    (3, "Symmetry\tRound", 3, "Symmetry 'Round' is not one of"),
    (4, "SpectralContent\tXYZ", 4, "XYZ is not supported"),
    (5, "ScatterType\tBTDF", 5, "reads reflection"),
    (6, "Wavelength 550", 6, "unexpected 'Wavelength'"),
    (6, "ScatterType BRDF", 6, "ScatterType is given twice: line 5 and line 6"),
    (17, "Databeginning", 23, "no DataBegin line"),
])
def test_reader_errors_name_the_line(tmp_path, lineno, new, line, match):
    p = _write(tmp_path, _replace_line(GOOD, lineno, new))
    with pytest.raises(FormatError, match=match) as exc:
        rb.read(p, format="zemax")
    assert exc.value.line == line
    assert str(exc.value).startswith(f"{p}, line {line}: ")


def test_reader_errors_whole_file(tmp_path):
    with pytest.raises(FormatError, match="no ScatterRadial line"):
        rb.read(_write(tmp_path, _replace_line(_replace_line(GOOD, 14, None), 13, None)))
    with pytest.raises(FormatError, match="text after DataEnd") as exc:
        rb.read(_write(tmp_path, GOOD + "TIS 0.5\n", "after.bsdf"))
    assert exc.value.line == 23
    with pytest.raises(FormatError, match="no 'Monochrome' line"):
        rb.read(_write(tmp_path, _replace_line(GOOD, 16, None), "nomono.bsdf"))
    with pytest.raises(FormatError, match="ends inside the data, without DataEnd"):
        rb.read(_write(tmp_path, "\n".join(GOOD.splitlines()[:18]) + "\n", "cut.bsdf"))


def test_truncated_and_corrupted_files_raise_format_errors_only(tmp_path):
    """Cut after every line, and every line replaced by junk: always a FormatError (or a
    valid read), never another exception."""
    lines = GOOD.splitlines()
    for n in range(len(lines)):
        p = _write(tmp_path, "\n".join(lines[:n]) + "\n", f"cut{n}.bsdf")
        with pytest.raises(FormatError):
            zemax.read(p)
    rng = np.random.default_rng(3)
    junk = ["", "#", "DataBegin", "TIS", "1e400 nan -1", "ScatterRadial 0", "Monochrome",
            "\t\t", "DataEnd DataEnd", "AngleOfIncidence 1 90"]
    for k in range(len(lines)):
        p = _write(tmp_path, _replace_line(GOOD, k + 1, junk[rng.integers(len(junk))]),
                   f"junk{k}.bsdf")
        try:
            zemax.read(p)
        except FormatError as exc:
            assert exc.path == str(p)


def test_options_and_sniffing(tmp_path):
    p = _write(tmp_path, GOOD)
    with pytest.raises(FormatError, match="degrees by definition"):
        rb.read(p, angles="rad")
    with pytest.raises(FormatError, match="contradicts the file's ScatterType BRDF"):
        rb.read(p, quantity="brdf_cos")
    assert rb.read(p, angles="deg", quantity="brdf").n_samples > 0
    with pytest.raises(TypeError, match="unknown options"):
        rb.read(p, stride=2)
    bare = _write(tmp_path, GOOD, "noext")
    assert format_for(bare) == "zemax" and format_for(tmp_path / "x.BSDF") == "zemax"
    assert rb.read(bare).n_samples == rb.read(p).n_samples


def test_sample_rotations(tmp_path):
    p = _write(tmp_path, _text(rot=(0, 90), value=lambda i, j, k: 0.1))
    with pytest.raises(FormatError, match="2 sample rotations.*sample_rotation="):
        rb.read(p)
    both = rb.read(p, sample_rotation="all")
    assert sorted(set(both.original["sample_rotation"])) == [0, 90]
    one = rb.read(p, sample_rotation=math.radians(90))
    assert set(one.original["sample_rotation"]) == {90}
    assert one.n_samples * 2 == both.n_samples
    with pytest.raises(ValueError, match="not in the file's SampleRotation list"):
        rb.read(p, sample_rotation=0.3)
    out = tmp_path / "both.bsdf"
    rb.write(both, out)
    assert np.array_equal(read_table(out).values, read_table(p).values)
    single = rb.read(_write(tmp_path, _text(rot=(45,)), "r45.bsdf"))   # one rotation: as is
    assert single.meta["zemax_sample_rotations_read"] == [45]


# ------------------------------------------------------------------------------------------
# writing a Measurement
# ------------------------------------------------------------------------------------------
def test_writer_refuses_existing_file_and_own_input(tmp_path):
    src = _write(tmp_path, GOOD, "in.bsdf")
    m = rb.read(src)
    with pytest.raises(ArgumentError, match="read from") as exc:
        rb.write(m, src, overwrite=True)
    assert exc.value.argument == "path"
    out = tmp_path / "out.bsdf"
    out.write_text("the user's file")
    with pytest.raises(FileExistsError, match=re.escape(str(out))):
        rb.write(m, out)
    assert out.read_text() == "the user's file"
    rb.write(m, out, overwrite=True)
    assert read_table(out).grid == read_table(src).grid


def test_a_grid_measurement_from_another_format_is_written_exactly(tmp_path):
    """.bsdf -> CSV -> .bsdf: the samples still lie on the grid (found from their angles)."""
    m = rb.read(NITE)
    csv = tmp_path / "nite.csv"
    rb.write(m, csv)
    back = rb.read(csv)
    out = tmp_path / "nite.bsdf"
    with pytest.warns(rb.io.LossyWriteWarning, match="csv header keys"):
        report = rb.write(back, out)
    assert not report.by_index and not report.changes_samples and report.n_duplicates == 0
    a, b = read_table(NITE), read_table(out)
    assert np.allclose(a.grid.radial_deg, b.grid.radial_deg, atol=1e-6)
    assert np.array_equal(a.grid.azimuth_deg, b.grid.azimuth_deg)
    assert np.array_equal(a.values, b.values)
    assert report.tis_source.startswith("the table's own integral")
    assert np.allclose(b.tis, table_integral(a.values, a.grid))


def test_scattered_samples_are_refused_unless_resampled(tmp_path):
    rng = np.random.default_rng(4)
    n = 300
    m = rb.Measurement(np.full(n, 30 * D), rng.uniform(0, 1.5, n), rng.uniform(-3.1, 3.1, n),
                       np.full(n, 0.2))
    out = tmp_path / "scattered.bsdf"
    with pytest.raises(ArgumentError, match="would change the samples") as exc:
        rb.write(m, out)
    assert exc.value.argument == "resample" and not out.exists()
    report = rb.write(m, out, resample=True)
    assert report.changes_samples and report.n_binned == n
    assert report.n_folded == int((m.phi > 1e-9).sum())
    assert report.n_filled > 0 and report.shape[1] == 1
    back = rb.read(out)
    assert back.n_samples == report.n_read_back
    assert "resampled onto this grid" in " ".join(read_table(out).comments)
    assert "binned" in report.text() and "filled" in report.text()


def test_missing_nodes_are_refused_then_filled_with_zero(tmp_path):
    m = rb.read(NITE)
    part = m.subset(m.original["scatter_radial"] != 40)
    with pytest.raises(ArgumentError, match=r"\d+ nodes above the horizon without a sample"):
        rb.write(part, tmp_path / "part.bsdf")
    report = rb.write(part, tmp_path / "part.bsdf", resample=True)
    _, _, _, cz = read_table(NITE).grid.directions()
    assert report.n_filled == int((cz[:, :, 6] >= 0).sum()) and report.by_index
    assert (read_table(tmp_path / "part.bsdf").values[0, :, :, 6] == 0).all()
    one = m.at_incidence(30 * D)                       # a whole incidence: its own grid
    r1 = rb.write(one, tmp_path / "one.bsdf")
    assert r1.shape == (1, 1, 19, 12) and not r1.changes_samples
    assert read_table(tmp_path / "one.bsdf").tis.tolist() == [[0.04566]]


def test_writer_rejects_what_the_format_cannot_hold(tmp_path):
    m = rb.read(NITE)
    two = rb.Measurement(m.theta_i, m.theta_r, m.phi, np.column_stack([m.values, m.values]),
                         channels=["a", "b"])
    with pytest.raises(ArgumentError, match="one channel") as exc:
        rb.write(two, tmp_path / "two.bsdf")
    assert exc.value.argument == "channel"
    assert not rb.write(two, tmp_path / "b.bsdf", channel="b").changes_samples
    rel = rb.Measurement(m.theta_i, m.theta_r, m.phi, m.values, quantity="relative")
    with pytest.raises(ValueError, match="relative"):
        rb.write(rel, tmp_path / "rel.bsdf")
    cosw = m.as_quantity("brdf_cos")
    report = rb.write(cosw, tmp_path / "cos.bsdf", resample=True)
    assert report.converted == "brdf_cos"
    with pytest.warns(rb.io.LossyWriteWarning, match="uncertainties"):
        sig = rb.Measurement(m.theta_i, m.theta_r, m.phi, m.values, uncertainty=m.values * 0.1)
        rb.write(sig, tmp_path / "sig.bsdf")
