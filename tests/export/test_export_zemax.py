"""Models and fits as Zemax tabular BSDF files: read back by roughbrdf's reader they equal the
model on the grid; TIS is rb.albedo; the table's own integral agrees with TIS within the
default grid's accuracy; one file per channel of a fit; nothing overwritten unless asked."""

from __future__ import annotations

import math

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.errors import ArgumentError
from roughbrdf.export.grids import TableAccuracyWarning
from roughbrdf.export.zemax import default_grid, lobe_width, to_zemax
from roughbrdf.io.zemax import read_table, table_integral
from roughbrdf.output import OverwriteRefused

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="each export checks the albedo at 19 incidences: ~1 min in plain Python")

MODELS = {
    "lambertian": lambda: rb.model("lambertian", rho=0.5),
    "coated": lambda: rb.model("coated"),
    "ggx_alpha_0.05": lambda: rb.model("microfacet", distribution="trowbridge-reitz",
                                       alpha=0.05),
    "ggx_alpha_0.3": lambda: rb.model("microfacet", distribution="trowbridge-reitz", alpha=0.3),
    "tr75": lambda: rb.model("trowbridge-reitz-1975"),
}


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """Each model written once with the default grid: {name: (model, ZemaxFile)}."""
    folder = tmp_path_factory.mktemp("zemax")
    out = {}
    for name, make in MODELS.items():
        m = make()
        # TR75 has no shadowing: its albedo exceeds 1 at grazing incidence
        out[name] = (m, to_zemax(m, folder / f"{name}.bsdf",
                                 allow_energy_gain=name == "tr75")[0])
    return out


@pytest.mark.parametrize("name", MODELS)
def test_read_back_equals_the_model_on_the_grid(exported, name):
    model, f = exported[name]
    m = rb.read(f.path)
    with np.errstate(invalid="ignore", divide="ignore"):
        expected = model.brdf(m.theta_i, m.theta_r, m.phi)
    finite = np.isfinite(expected)  # TR75 has no finite value at theta_r = 90 deg: 0 there
    assert np.allclose(m.values[finite, 0], expected[finite], rtol=1e-6, atol=1e-12)
    assert (m.values[~finite, 0] == 0).all() and (~finite).sum() == f.n_horizon_nonfinite
    assert (m.theta_r[~finite] == math.pi / 2).all()
    assert m.meta["zemax_grid"]["angle_of_incidence"] == list(f.grid.aoi_deg)
    # every node is there: above the horizon a sample, below the horizon a 0 in the file
    table = read_table(f.path)
    _, _, _, cz = f.grid.directions()
    assert (table.values[0][cz < -1e-12] == 0).all()
    assert f.n_below_horizon == int((cz < -1e-12).sum()) > 0
    assert m.n_samples + m.meta["zemax_duplicates"] == int((cz >= -1e-12).sum())


@pytest.mark.parametrize("name", MODELS)
def test_tis_is_the_directional_hemispherical_reflectance(exported, name):
    model, f = exported[name]
    tis = np.asarray(read_table(f.path).tis[0])
    assert np.allclose(tis, rb.albedo(model, np.radians(f.grid.aoi_deg)), atol=1e-3, rtol=0)


@pytest.mark.parametrize("name", MODELS)
def test_table_integral_agrees_with_tis(exported, name):
    """1e-2 is required; the default grid gives 1.3e-3 for these models (worst: TR75
    at normal incidence, the coated and GGX 0.05 lobes cut by the horizon at 80 deg)."""
    _, f = exported[name]
    table = read_table(f.path)
    own = table_integral(table.values, table.grid)[0]
    assert np.allclose(own, f.integral)
    assert np.abs(own - table.tis[0]).max() < 1.3e-3
    assert f.integral_error < 1e-2


def test_default_grid_follows_the_lobe():
    sharp = rb.model("microfacet", distribution="trowbridge-reitz", alpha=0.05)
    w = lobe_width(sharp, [0, 40, 80])
    g = default_grid(sharp)
    assert g.aoi_deg == tuple(float(a) for a in range(0, 81, 10))
    assert g.radial_deg[0] == 0 and g.radial_deg[-1] == 90 + 80   # the whole hemisphere
    assert g.radial_deg[1] <= w / 8 + 1e-9                         # dense near specular
    assert max(np.diff(g.radial_deg)) <= 2.0 + 1e-9
    assert g.azimuth_deg[1] == 5.0 and g.azimuth_deg[-1] == 180    # narrow lobe: 5 deg
    flat = default_grid(rb.model("lambertian", rho=0.5))
    assert lobe_width(rb.model("lambertian", rho=0.5), [0, 40]) is None
    assert flat.radial_deg[1] == 2.0 and flat.azimuth_deg[1] == 10.0
    assert len(flat.radial_deg) < len(g.radial_deg)


def test_user_grid_in_radians_written_in_degrees(tmp_path):
    m = rb.model("microfacet", distribution="trowbridge-reitz", alpha=0.3)
    with pytest.warns(TableAccuracyWarning, match="too coarse"):  # 3 azimuths: 3.1 % off
        f = to_zemax(m, tmp_path / "g.bsdf", angles_of_incidence=np.radians([0, 22.5, 45]),
                     radial=np.radians(np.arange(0, 135.1, 2.5)),
                     azimuth=np.radians([0, 90, 180]))[0]
    text = f.path.read_text()
    assert "AngleOfIncidence\t3\n0\t22.5\t45\n" in text
    assert "ScatterAzimuth\t3\n0\t90\t180\n" in text
    assert "\n0\t2.5\t5\t7.5\t" in text
    back = rb.read(f.path)
    assert np.allclose(back.values[:, 0], m.brdf(back.theta_i, back.theta_r, back.phi),
                       rtol=1e-6)
    with pytest.raises(ArgumentError, match="ScatterRadial angles must increase") as exc:
        to_zemax(m, tmp_path / "bad.bsdf", radial=np.radians([0, 5, 5]))
    assert exc.value.argument == "radial"


def test_asymmetrical_export_covers_360_degrees(tmp_path):
    m = rb.model("microfacet", distribution="trowbridge-reitz", alpha=0.3)
    half = to_zemax(m, tmp_path / "half.bsdf")[0]
    full = to_zemax(m, tmp_path / "full.bsdf", symmetry="Asymmetrical")[0]
    assert full.grid.azimuth_deg[-1] == 360 and half.grid.azimuth_deg[-1] == 180
    assert np.allclose(full.integral, half.integral, atol=1e-12)
    back = rb.read(full.path)
    assert (back.phi > 0).any() and (back.phi < 0).any()
    assert back.meta["zemax_grid"]["symmetry"] == "Asymmetrical"


def test_a_fit_gives_one_file_per_channel(tmp_path):
    rng = np.random.default_rng(5)
    n = 120
    ti, tr, ph = rng.uniform(0, 1.2, n), rng.uniform(0, 1.4, n), rng.uniform(-3, 3, n)
    vals = np.column_stack([rb.model("lambertian", rho=r).brdf(ti, tr, ph) for r in (0.3, 0.6)])
    res = rb.fit("lambertian", rb.Measurement(ti, tr, ph, vals, channels=["465nm", "630 nm"]),
                 starts=1)
    out = tmp_path / "paint.bsdf"
    export = to_zemax(res, out)
    assert [p.name for p in export.paths] == ["paint_465nm.bsdf", "paint_630_nm.bsdf"]
    assert [f.channel for f in export] == ["465nm", "630 nm"]
    assert not out.exists()
    for f, rho in zip(export, (0.3, 0.6), strict=True):
        assert read_table(f.path).tis[0] == pytest.approx(rho, abs=1e-6)
        assert "channel: " + f.channel in f.path.read_text()
    one = to_zemax(res, tmp_path / "red", channel="630 nm")
    assert one.paths == [tmp_path / "red.bsdf"]
    assert "630 nm" in one.text() and "TIS" in one.text()


def test_nothing_is_overwritten_unless_asked(tmp_path):
    rng = np.random.default_rng(6)
    ti, tr, ph = rng.uniform(0, 1, 50), rng.uniform(0, 1, 50), rng.uniform(-3, 3, 50)
    vals = np.column_stack([np.full(50, 0.1), np.full(50, 0.2)])
    res = rb.fit("lambertian", rb.Measurement(ti, tr, ph, vals, channels=["a", "b"]), starts=1)
    (tmp_path / "x_b.bsdf").write_text("the user's file")
    with pytest.raises(OverwriteRefused, match="x_b.bsdf"):
        to_zemax(res, tmp_path / "x.bsdf")
    assert not (tmp_path / "x_a.bsdf").exists()            # refused before writing any
    assert (tmp_path / "x_b.bsdf").read_text() == "the user's file"
    to_zemax(res, tmp_path / "x.bsdf", overwrite=True)
    assert read_table(tmp_path / "x_b.bsdf").tis[0, 0] == pytest.approx(0.2 * math.pi,
                                                                        abs=1e-6)
    (tmp_path / "d.bsdf").mkdir()
    with pytest.raises(IsADirectoryError):
        to_zemax(rb.model("lambertian"), tmp_path / "d.bsdf", overwrite=True)


def test_domain_and_argument_errors(tmp_path):
    coated = rb.model("coated")
    assert not coated.grazing_incidence
    with pytest.raises(ArgumentError, match="grazing incidence") as exc:
        to_zemax(coated, tmp_path / "c.bsdf", angles_of_incidence=[0.0, math.pi / 2])
    assert exc.value.argument == "angles_of_incidence"
    lam = rb.model("lambertian", rho=0.5)
    f = to_zemax(lam, tmp_path / "grazing.bsdf", angles_of_incidence=[math.pi / 2])[0]
    assert f.tis[0] == pytest.approx(0.5, abs=1e-4)
    with pytest.raises(TypeError, match="Model .* a FitResult .* or a mapping"):
        to_zemax("lambertian", tmp_path / "s.bsdf")
    # {channel: model}, as fitting.results.fit_json.fitted_models gives it for a saved fit
    files = to_zemax({"a": lam, "b": lam.with_params(rho=0.2)}, tmp_path / "m.bsdf")
    assert [f.path.name for f in files] == ["m_a.bsdf", "m_b.bsdf"]
    assert files[1].tis[0] == pytest.approx(0.2, abs=1e-4)
    one = to_zemax({"a": lam, "b": lam}, tmp_path / "one.bsdf", channel="b")
    assert [f.path.name for f in one] == ["one.bsdf"]
    with pytest.raises(ArgumentError, match="applies to a fit"):
        to_zemax(lam, tmp_path / "s.bsdf", channel=0)
    with pytest.raises(ArgumentError, match="symmetry"):
        to_zemax(lam, tmp_path / "s.bsdf", symmetry="round")
    assert not list(tmp_path.glob("s.bsdf"))


def test_polarization_is_passed_to_the_model(tmp_path):
    m = rb.model("microfacet", distribution="trowbridge-reitz", alpha=0.3, n=1.5)
    s = to_zemax(m, tmp_path / "s.bsdf", polarization="s")[0]
    p = to_zemax(m, tmp_path / "p.bsdf", polarization="p")[0]
    assert (s.tis[1:] > p.tis[1:]).all()      # s reflects more than p off normal incidence
    assert np.allclose(s.tis, rb.albedo(m, np.radians(s.grid.aoi_deg), polarization="s"))
