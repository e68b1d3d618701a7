"""MERL binary: a full-size file written from known models, read back and compared; the
Rusinkiewicz conventions checked against geometry.to/from_rusinkiewicz; truncated files."""

from __future__ import annotations

import math

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf._kernels import DISABLE_JIT
from roughbrdf.geometry import from_rusinkiewicz, to_rusinkiewicz
from roughbrdf.io import FormatError, merl


def _models():
    # three different models so that a channel mix-up cannot pass. Under NUMBA_DISABLE_JIT=1
    # (make test-nojit) three Lambertians: the full-size table is 1.4M cells a channel, written
    # and compared again, and the microfacet models take over 5 min of plain Python for it
    # (a Lambertian seconds); the reader and writer under test are the same NumPy code
    if DISABLE_JIT:
        return [rb.model("lambertian", rho=r) for r in (0.2, 0.35, 0.5)]
    return [rb.model("microfacet", distribution="trowbridge-reitz", alpha=a, shadowing="smith",
                     n=1.5, k=0.0) for a in (0.15, 0.3, 0.5)]


@pytest.fixture(scope="module")
def merl_file(tmp_path_factory):
    """A 35 MB file in the real layout (90 x 90 x 180 x 3 doubles) with some invalid cells."""
    table = merl.table_from_model(_models())  # NaN (-> -1) below the horizon and at 90 deg
    table[:, 45, 10, 7] = -1.0          # invalid marker, one cell above the horizon
    table[1, 60, 20, 33] = -1.0         # invalid in one channel only
    path = tmp_path_factory.mktemp("merl") / "model.binary"
    merl.write_table(path, table)
    return path


def _expected_invalid(path):
    """Cells above the horizon with a -1 in any channel, counted independently of the reader."""
    table = merl.read_table(path, scaled=False).reshape(3, -1)
    th, td, pd = merl.cell_angles(*np.unravel_index(np.arange(table.shape[1]), merl.DIMS))
    ti, _, _ = from_rusinkiewicz(th, td, pd)
    return int(((table < 0).any(axis=0) & np.isfinite(ti)).sum())


def test_layout_on_disk(merl_file):
    raw = merl_file.read_bytes()
    assert len(raw) == 12 + 8 * 3 * 90 * 90 * 180
    assert np.frombuffer(raw[:12], "<i4").tolist() == [90, 90, 180]
    # stored numbers are BRDF / scale; channel blocks R, G, B
    data = np.frombuffer(raw[12:], "<f8").reshape(3, 90, 90, 180)
    table = merl.read_table(merl_file)
    i, j, k = 30, 40, 50
    for c, s in enumerate((1 / 1500, 1.15 / 1500, 1.66 / 1500)):
        assert table[c, i, j, k] == data[c, i, j, k] * s


def test_read_back_equals_the_model(merl_file):
    m = rb.read(merl_file)
    assert m.channels == ["R", "G", "B"] and m.quantity == "brdf"
    meta = m.meta
    assert meta["merl_dims"] == (90, 90, 180) and meta["merl_cells_read"] == 1458000
    n_invalid = _expected_invalid(merl_file)
    assert n_invalid >= 2  # the two marked cells and the cells at exactly 90 deg
    assert meta["merl_invalid"] == n_invalid  # counted, and dropped explicitly (policy "drop")
    assert meta["merl_invalid_policy"] == "drop"
    assert meta["merl_below_horizon"] > 0
    assert m.n_samples == 1458000 - meta["merl_below_horizon"] - n_invalid
    assert (m.values >= 0).all()
    # compare with the models on every valid cell
    for c, mdl in enumerate(_models()):
        f = mdl.brdf(m.theta_i, m.theta_r, m.phi)
        assert np.allclose(m.values[:, c], f, rtol=1e-13, atol=0)
    # the original (theta_h, theta_d, phi_d) and cell index are kept
    assert {"theta_h", "theta_d", "phi_d", "merl_index"} <= set(m.original)


def test_invalid_policies_and_stride(merl_file):
    keep = merl.read(merl_file, invalid="nan")
    assert keep.meta["merl_invalid"] == _expected_invalid(merl_file)
    assert keep.n_samples == 1458000 - keep.meta["merl_below_horizon"]
    assert np.isnan(keep.values[:, 1]).sum() == keep.meta["merl_invalid"]  # G: 1 more
    assert np.isnan(keep.values[:, 0]).sum() == keep.meta["merl_invalid"] - 1
    k = merl.read(merl_file, stride=4)
    assert k.meta["merl_stride"] == (4, 4, 4) and k.meta["merl_cells_read"] == 23 * 23 * 45
    f = _models()[0].brdf(k.theta_i, k.theta_r, k.phi)
    ok = k.values[:, 0] >= 0
    assert np.allclose(k.values[ok, 0], f[ok], rtol=1e-13)
    with pytest.raises(ValueError, match="invalid must be"):
        merl.read(merl_file, invalid="ignore")


def test_write_measurement_round_trip(merl_file, tmp_path):
    m = rb.read(merl_file, invalid="keep")
    out = tmp_path / "again.binary"
    rb.write(m, out)  # uses original merl_index
    a = merl.read_table(merl_file, scaled=False)
    b = merl.read_table(out, scaled=False)
    assert np.array_equal(a < 0, b < 0)
    assert np.allclose(a, b, rtol=1e-15, atol=0)


def test_rusinkiewicz_conventions_match_merl():
    """Cell angles -> common frame (from_rusinkiewicz) -> to_rusinkiewicz gives back the same
    (theta_h, theta_d, phi_d), phi_d included (MERL: d = R_y(-theta_h) R_z(-phi_h) w_in)."""
    rng = np.random.default_rng(3)
    i = rng.integers(1, 90, 4000)
    j = rng.integers(1, 90, 4000)
    k = rng.integers(0, 180, 4000)
    th, td, pd = merl.cell_angles(i, j, k)
    ti, tr, ph = from_rusinkiewicz(th, td, pd)
    ok = np.isfinite(ti)
    th2, td2, pd2 = to_rusinkiewicz(ti[ok], tr[ok], ph[ok])
    assert np.allclose(th2, th[ok], atol=1e-7) and np.allclose(td2, td[ok], atol=1e-7)
    assert np.allclose(np.angle(np.exp(1j * (pd2 - pd[ok]))), 0, atol=1e-9)
    ii, jj, kk = merl.cell_index(th2, td2, pd2)
    assert np.array_equal(ii, i[ok]) and np.array_equal(jj, j[ok]) and np.array_equal(kk, k[ok])
    # MERL's explicit index formulas
    assert merl.cell_index(math.pi / 2 * (45 / 90) ** 2 + 1e-9, 0.0, 0.0)[0] == 45
    assert merl.cell_index(0.0, math.radians(44.5), 0.0)[1] == 89 // 2
    assert merl.cell_index(0.0, 0.0, -math.radians(10.5))[2] == 169  # folded by + pi
    # reciprocity: phi_d + pi is the same geometry with the two directions swapped
    a = from_rusinkiewicz(th[:50], td[:50], pd[:50])
    b = from_rusinkiewicz(th[:50], td[:50], pd[:50] + math.pi)
    fin = np.isfinite(a[0]) & np.isfinite(b[0])
    assert np.allclose(a[0][fin], b[1][fin]) and np.allclose(a[1][fin], b[0][fin])
    # the specular cell (theta_h = 0) is the mirror direction
    ti0, tr0, ph0 = from_rusinkiewicz(0.0, math.radians(30), 0.0)
    assert float(ti0) == pytest.approx(math.radians(30)) and float(tr0) == pytest.approx(
        math.radians(30)) and abs(float(ph0)) < 1e-12


def test_general_measurement_is_binned(tmp_path):
    mdl = _models()[1]
    th, td, pd = merl.cell_angles(*np.meshgrid(np.arange(5, 80, 7), np.arange(5, 80, 9),
                                               np.arange(3, 180, 11), indexing="ij"))
    ti, tr, ph = (a.ravel() for a in from_rusinkiewicz(th.ravel(), td.ravel(), pd.ravel()))
    ok = np.isfinite(ti)
    from roughbrdf.measurement import Measurement

    m = Measurement(ti[ok], tr[ok], ph[ok], mdl.brdf(ti[ok], tr[ok], ph[ok]), channels=["v"])
    out = tmp_path / "binned.merl"
    rb.write(m, out)
    r = rb.read(out)
    assert r.n_samples == ok.sum()
    assert np.allclose(np.sort(r.values[:, 1]), np.sort(m.values[:, 0]), rtol=1e-13)
    # the empty cells are -1: dropped on reading, and counted
    assert r.meta["merl_invalid"] == 1458000 - r.meta["merl_below_horizon"] - ok.sum()


@pytest.mark.parametrize("cut, match", [(8, "fewer than the 12-byte header"),
                                        (12 + 8 * 1000, "truncated MERL file"),
                                        (-8, "truncated MERL file")])
def test_truncated_binary(merl_file, tmp_path, cut, match):
    raw = merl_file.read_bytes()
    p = tmp_path / "cut.binary"
    p.write_bytes(raw[:cut])
    with pytest.raises(FormatError, match=match) as exc:
        rb.read(p)
    assert exc.value.path == str(p) and str(p) in str(exc.value)


def test_not_a_merl_file(tmp_path):
    p = tmp_path / "bad.binary"
    p.write_bytes(np.array([-5, 3, 2], "<i4").tobytes() + b"\0" * 16)
    with pytest.raises(FormatError, match="not a MERL binary"):
        rb.read(p)
    q = tmp_path / "long.binary"
    q.write_bytes(np.array([2, 2, 2], "<i4").tobytes() + b"\0" * (8 * 25))
    with pytest.raises(FormatError, match="over-long"):
        rb.read(q)


def test_sniffed_without_extension(merl_file, tmp_path):
    p = tmp_path / "brdf_no_ext"
    p.write_bytes(merl_file.read_bytes())
    assert rb.read(p, stride=9).meta["format"] == "merl"
