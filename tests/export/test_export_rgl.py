"""RGL measured-BSDF export (``roughbrdf.export.rgl``), checked with Mitsuba 3's ``measured``.

Every file is loaded by Mitsuba's ``measured`` plugin (``scalar_rgb``) and

* ``eval`` at :data:`N` random directions (``theta_i, theta_o <= 80`` deg, uniform in solid
  angle, any azimuth) must equal the model's ``f_r cos(theta_o)``: median relative error
  <= 1 %, 95th percentile <= 5 % (the file is a table; interpolation between its nodes is the
  error);
* the furnace test: the mean of ``sample()``'s weights over a stratified 316 x 316 grid of
  the unit square (> 1e5 samples) must equal ``rb.albedo`` within 1 % at 0, 30 and 60 deg.

Models: coated (one and two lobes), a microfacet conductor (exact NDF), TR75 with V-groove
shadowing, ABg (its default 1-degree lobe), and a coated fit of each shared Mini-Diff paint
(one channel, skipped without ../shared/data). The tests skip only where ``mitsuba`` cannot be
imported (it is in the ``test`` extra).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import MINIDIFF_PAINTS
from mitsuba_support import mitsuba_variant

import roughbrdf as rb
from roughbrdf.errors import ArgumentError
from roughbrdf.export import export
from roughbrdf.export.rgl import to_rgl
from roughbrdf.io.rgl_tensor import decode
from roughbrdf.output import OverwriteRefused

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="RGL exports: power iterations and 19 albedos per export, minutes in plain Python")

mi = pytest.importorskip("mitsuba", reason="the mitsuba package (test extra) is not installed "
                         "or cannot be imported on this platform", exc_type=ImportError)

N = 1500
#: stratified furnace grid: K x K > 1e5 samples
K = 317
TOP = math.radians(80.0)

MODELS = {
    "coated": rb.model("coated", alpha=0.15, n=1.5, rho=0.4),
    "coated-2-lobes": rb.model("coated", lobes=2, alpha=0.08, alpha2=0.3, w2=0.3, rho=0.3),
    "microfacet-conductor": rb.model("microfacet", distribution="ggx", alpha=0.25, n=0.2, k=3.0),
    "tr75-v-groove": rb.model("trowbridge-reitz-1975", shadowing="v-groove"),
    "abg": rb.model("abg"),
}


@pytest.fixture(autouse=True)
def scalar_rgb():
    """Mitsuba's ``scalar_rgb`` for each test, the variant before it restored after."""
    with mitsuba_variant(mi, "scalar_rgb"):
        yield


def directions(seed: int, n: int = N):
    """Angles (library frame: source on -x, phi = 0 forward) and Mitsuba's directions."""
    rng = np.random.default_rng(seed)
    ti = np.arccos(rng.uniform(math.cos(TOP), 1.0, n))
    tr = np.arccos(rng.uniform(math.cos(TOP), 1.0, n))
    ph = rng.uniform(-math.pi, math.pi, n)
    wi = np.stack([-np.sin(ti), np.zeros(n), np.cos(ti)], 1)
    wo = np.stack([np.sin(tr) * np.cos(ph), np.sin(tr) * np.sin(ph), np.cos(tr)], 1)
    return (ti, tr, ph), wi, wo


def mitsuba_eval(bsdf, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """``bsdf.eval`` (BRDF cos theta_o), shape (N, 3)."""
    ctx, si = mi.BSDFContext(), mi.SurfaceInteraction3f()
    out = np.empty((len(wi), 3))
    for j in range(len(wi)):  # scalar variant: one direction a call
        si.wi = mi.Vector3f(*(float(x) for x in wi[j]))
        v = bsdf.eval(ctx, si, mi.Vector3f(*(float(x) for x in wo[j])))
        out[j] = (v[0], v[1], v[2])
    return out


def furnace(bsdf, theta: float) -> np.ndarray:
    """Mean of ``sample()``'s weights (R, G, B) over a stratified K x K grid."""
    ctx, si = mi.BSDFContext(), mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(math.sin(theta), 0.0, math.cos(theta))
    g = (np.arange(K) + 0.5) / K
    total = np.zeros(3)
    for a in g.tolist():
        for b in g.tolist():
            _, w = bsdf.sample(ctx, si, 0.5, mi.Point2f(a, b))
            total += (w[0], w[1], w[2])
    return total / K ** 2


def check(model, path, seed: int = 1, source=None) -> dict[str, float]:
    """Write ``source`` (default: ``model``), load, compare with ``model``; returns the
    measured errors (reported on failure)."""
    done = to_rgl(model if source is None else source, path)
    bsdf = mi.load_dict({"type": "measured", "filename": str(done.path)})
    angles, wi, wo = directions(seed)
    ref = np.asarray(model.brdf(*angles)) * np.cos(angles[1])
    got = mitsuba_eval(bsdf, wi, wo)
    err = np.abs(got - ref[:, None]) / np.abs(ref[:, None])
    out = {"median": float(np.median(err)), "p95": float(np.percentile(err, 95))}
    for deg in (0, 30, 60):
        albedo = float(rb.albedo(model, math.radians(deg)))
        out[f"furnace{deg}"] = float(np.max(np.abs(furnace(bsdf, math.radians(deg)) / albedo
                                                   - 1)))
    assert out["median"] <= 0.01 and out["p95"] <= 0.05, (model, out)
    assert max(out[f"furnace{d}"] for d in (0, 30, 60)) <= 0.01, (model, out)
    return out


@pytest.mark.parametrize("name", list(MODELS))
def test_mitsuba_measured_matches_the_model(name, tmp_path):
    check(MODELS[name], tmp_path / f"{name}.bsdf")


@pytest.fixture(scope="module")
def paint_fits(paints):
    """A coated fit of each Mini-Diff paint, one channel (525 nm), fitted once."""
    return {name: rb.fit("coated", paints[name], channel="525nm", starts=1, progress=False)
            for name in MINIDIFF_PAINTS}


@pytest.mark.parametrize("name", MINIDIFF_PAINTS)
def test_mitsuba_measured_matches_a_paint_fit(name, paint_fits, tmp_path):
    fit = paint_fits[name]  # the FitResult itself is exported (one channel: grey RGB)
    check(fit.model, tmp_path / f"{name}.bsdf", source=fit)


def test_the_file_is_mitsubas_layout(tmp_path):
    done = to_rgl(MODELS["coated"], tmp_path / "c", resolution={"theta_i": 5, "samples": 8,
                                                                 "vndf": 16, "ndf": 32})
    assert done.path.suffix == ".bsdf" and done.size == done.path.stat().st_size
    f = decode(done.path.read_bytes())
    assert f["rgb"].shape == (1, 5, 3, 8, 8) and f["luminance"].shape == (1, 5, 8, 8)
    assert f["vndf"].shape == (1, 5, 16, 16) and f["ndf"].shape == (2, 32)
    assert f["jacobian"].tolist() == [1] and f["phi_i"].tolist() == [0.0]
    assert "power iteration" in bytes(f["description"]).decode()
    assert "12 incidences" not in done.text() and "5 incidences" in done.text()


def test_exact_ndf_for_the_microfacet_model(tmp_path):
    done = to_rgl(MODELS["microfacet-conductor"], tmp_path / "m.bsdf",
                  resolution={"theta_i": 4, "samples": 8, "vndf": 16, "ndf": 32})
    assert done.ndf_source.startswith("exact")


def test_spectral_file_of_a_fit_loads_in_a_spectral_variant(tmp_path):
    truth = {"465nm": rb.model("coated", alpha=0.2, rho=0.2),
             "525nm": rb.model("coated", alpha=0.2, rho=0.5),
             "630nm": rb.model("coated", alpha=0.2, rho=0.7)}
    res = export(truth, tmp_path / "s.bsdf", to="rgl")
    assert res.target == "rgl" and res.detail.color == "spectral"
    f = decode(res.paths[0].read_bytes())
    assert f["wavelengths"].tolist() == [465.0, 525.0, 630.0]
    assert f["spectra"].shape[2] == 3
    mi.set_variant("scalar_spectral")
    bsdf = mi.load_dict({"type": "measured", "filename": str(res.paths[0])})
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(0.0, 0.0, 1.0)
    si.wavelengths = mi.Spectrum([525.0, 525.0, 630.0, 465.0])
    wo = mi.Vector3f(math.sin(0.5), 0.0, math.cos(0.5))
    got = np.array(bsdf.eval(mi.BSDFContext(), si, wo))
    ref = [float(truth[k].brdf(0.0, 0.5, 0.0)) * math.cos(0.5)
           for k in ("525nm", "525nm", "630nm", "465nm")]
    np.testing.assert_allclose(got, ref, rtol=0.03)
    rgb = export(truth, tmp_path / "c.bsdf", to="rgl", color="rgb")
    assert rgb.detail.channels == ["R", "G", "B"]
    # R, G, B: the channels interpolated linearly in wavelength at 612, 549 and 465 nm
    spec, col = f["spectra"][0], decode(rgb.paths[0].read_bytes())["rgb"][0]
    for c, nm in enumerate((612.0, 549.0, 465.0)):
        k = (nm - 525.0) / (630.0 - 525.0)
        want = spec[:, 0] if nm < 525 else (1 - k) * spec[:, 1] + k * spec[:, 2]
        np.testing.assert_allclose(col[:, c], want, rtol=1e-5, atol=1e-9)


def test_refuses_to_overwrite_and_names_bad_arguments(tmp_path):
    small = {"theta_i": 3, "samples": 4, "vndf": 8, "ndf": 16}
    path = tmp_path / "x.bsdf"
    to_rgl(MODELS["abg"], path, resolution=small)
    before = path.read_bytes()
    with pytest.raises(OverwriteRefused):
        to_rgl(MODELS["abg"], path, resolution=small)
    assert path.read_bytes() == before
    to_rgl(MODELS["coated"], path, resolution=small, overwrite=True)
    assert path.read_bytes() != before
    with pytest.raises(ArgumentError, match="resolution"):
        to_rgl(MODELS["abg"], tmp_path / "y.bsdf", resolution={"samples": 1})
    with pytest.raises(ArgumentError, match="color"):
        to_rgl(MODELS["abg"], tmp_path / "y.bsdf", color="cmyk")
    with pytest.raises(ArgumentError, match="channel"):
        to_rgl(MODELS["abg"], tmp_path / "y.bsdf", channel=0)
    gain = rb.model("microfacet", alpha=0.3, n=None, k=None, ks=1.5)  # albedo above 1
    with pytest.raises(ArgumentError, match="allow_energy_gain"):
        to_rgl(gain, tmp_path / "y.bsdf", resolution=small)
    assert not (tmp_path / "y.bsdf").exists()
    done = to_rgl(gain, tmp_path / "y.bsdf", resolution=small, allow_energy_gain=True)
    text = bytes(decode(done.path.read_bytes())["description"]).decode()
    assert "allow_energy_gain: exported although" in text


def test_one_channel_of_a_fit_by_label_or_index(tmp_path):
    fit = {"465nm": rb.model("coated", rho=0.2), "630nm": rb.model("coated", rho=0.7)}
    small = {"theta_i": 3, "samples": 4, "vndf": 8, "ndf": 16}
    by_label = to_rgl(fit, tmp_path / "a.bsdf", channel="630nm", resolution=small)
    by_index = to_rgl(fit, tmp_path / "b.bsdf", channel=1, resolution=small)
    assert by_label.color == by_index.color == "rgb"  # one channel: grey
    a, b = (decode(p.read_bytes())["rgb"] for p in (by_label.path, by_index.path))
    np.testing.assert_array_equal(a, b)
    with pytest.raises(ArgumentError, match="channel"):
        to_rgl(fit, tmp_path / "c.bsdf", channel="550nm", resolution=small)


def test_cli_writes_and_reports_size_and_time(tmp_path):
    from typer.testing import CliRunner

    from roughbrdf.cli import app

    out = tmp_path / "paint.bsdf"
    args = ["export", "coated", "-p", "alpha=0.2", "--to", "rgl", "--out", str(out),
            "--resolution", "theta_i=4,samples=8,vndf=16,ndf=32"]
    done = CliRunner().invoke(app, args)
    assert done.exit_code == 0, done.output
    assert "MB in" in done.output and "4 incidences x 8x8" in done.output and out.is_file()
    again = CliRunner().invoke(app, args)
    assert again.exit_code != 0 and "--force" in again.output
    bad = CliRunner().invoke(app, [*args[:-1], "samples=1", "--force"])
    assert bad.exit_code != 0 and "--resolution" in bad.output
    wrong = CliRunner().invoke(app, ["export", "coated", "--to", "zemax", "--out",
                                     str(tmp_path / "z.bsdf"), "--color", "rgb"])
    assert wrong.exit_code != 0 and "--color" in wrong.output


@pytest.mark.parametrize("alpha, distribution", [(0.3, "ggx"), (0.1, "ggx"), (0.3, "beckmann")])
def test_power_iteration_recovers_a_microfacet_distribution(alpha, distribution):
    """With separable Smith masking and F = 1, f(w, w) = D / (4 sigma^2) exactly: the power
    iteration (Dupuy et al. 2015) must give the exact D back (measured: <= 1.5e-4 to 80 deg;
    the quadrature of sigma over the interpolated table is what limits it)."""
    from roughbrdf.export.rgl.ndf import ndf_table, power_iteration

    m = rb.model("microfacet", alpha=alpha, distribution=distribution, n=None, k=None,
                 shadowing="smith-separable")
    u, exact, source = ndf_table([m], 256)
    assert source.startswith("exact")
    found = power_iteration([m], u)
    upto = u ** 2 * 90 < 80  # theta < 80 deg
    np.testing.assert_allclose(found[upto], exact[upto], rtol=3e-4)
