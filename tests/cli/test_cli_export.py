"""``roughbrdf export (MODEL -p ... | --fit DIR) --to zemax|mitsuba|mitsuba-xml --out PATH``.

The command is a thin layer over :func:`roughbrdf.export.export` (the Zemax and Mitsuba exports
are tested against the format's conventions and against Mitsuba itself in
``tests/export/test_export_zemax.py`` and ``tests/export/test_export_mitsuba.py``): what is
checked here is that the files it writes are the library's, read back or loaded, that a saved
fit's models are exported per channel, and the command's own rules (no overwrite without
``--force``, errors naming its options, option/target mismatches refused before anything is
written).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

import roughbrdf as rb
from roughbrdf.cli import app
from roughbrdf.export.mitsuba import to_mitsuba

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

runner = CliRunner()


def _run(*args):
    return runner.invoke(app, [*map(str, args)])


@pytest.fixture(scope="module")
def fit_dir(tmp_path_factory):
    """A saved two-channel fit of the coated model (data from the model itself)."""
    d = tmp_path_factory.mktemp("fit")
    g = list(np.radians(np.mgrid[10:61:25, 0:81:10, 0:181:45].reshape(3, -1)))
    vals = np.stack([rb.model("coated", rho=r, alpha=0.2).brdf(*g) for r in (0.2, 0.5)], 1)
    res = rb.fit("coated", rb.Measurement(*g, vals, channels=["525nm", "630nm"]), starts=1,
                 progress=False)
    res.save(d / "out", plots=False)
    return d / "out"


def test_zemax_of_a_model_reads_back_as_the_model(tmp_path):
    out = tmp_path / "paint.bsdf"
    res = _run("export", "coated(lobes=2)", "-p", "rho=0.3", "--to", "zemax", "--out", out,
               "--incidences", "0:60:30")
    assert res.exit_code == 0, res.output
    m = rb.read(out)
    model = rb.model("coated", lobes=2, rho=0.3)
    assert sorted(set(np.round(np.degrees(m.theta_i), 9))) == [0.0, 30.0, 60.0]
    expected = model.brdf(m.theta_i, m.theta_r, m.phi)
    # the model on the file's grid: written with 17 digits, read back (io.zemax)
    np.testing.assert_allclose(m.values[:, 0], expected, rtol=1e-12, atol=1e-300)
    assert "TIS = rb.albedo" in res.output


def test_a_saved_fit_gives_one_zemax_file_per_channel(fit_dir, tmp_path):
    res = _run("export", "--fit", fit_dir, "--to", "zemax", "--out", tmp_path / "p.bsdf",
               "--incidences", "20")
    assert res.exit_code == 0, res.output
    models = rb.fitting.results.fit_json.fitted_models(fit_dir)
    for label in ("525nm", "630nm"):
        m = rb.read(tmp_path / f"p_{label}.bsdf")
        want = models[label].brdf(m.theta_i, m.theta_r, m.phi)
        np.testing.assert_allclose(m.values[:, 0], want, rtol=1e-12)
    one = _run("export", "--fit", fit_dir, "--channel", "1", "--to", "zemax", "--out",
               tmp_path / "only.bsdf", "--incidences", "20")
    assert one.exit_code == 0, one.output
    m = rb.read(tmp_path / "only.bsdf")
    np.testing.assert_allclose(m.values[:, 0],
                               models["630nm"].brdf(m.theta_i, m.theta_r, m.phi), rtol=1e-12)


def test_mitsuba_json_and_xml_are_the_library_export(fit_dir, tmp_path):
    m = rb.model("coated", alpha=0.3, rho=0.4, shadow_diffuse=False, interface="rough")
    res = _run("export", "coated", "-p", "alpha=0.3", "-p", "rho=0.4", "-p",
               "shadow_diffuse=false", "-p", "interface=rough", "--to", "mitsuba", "--out",
               tmp_path / "p.json")
    assert res.exit_code == 0, res.output
    assert json.loads((tmp_path / "p.json").read_text()) == to_mitsuba(m)
    assert "exact" in res.output
    xml = _run("export", "lambertian", "-p", "rho=0.25", "--to", "mitsuba-xml", "--out",
               tmp_path / "p.xml")
    assert xml.exit_code == 0, xml.output
    assert '<float name="reflectance" value="0.25" />' in (tmp_path / "p.xml").read_text()


def test_mitsuba_xml_loads_in_mitsuba(tmp_path):
    mi = pytest.importorskip("mitsuba", reason="mitsuba is not installed (test extra)")
    mi.set_variant("scalar_rgb")
    res = _run("export", "lambertian", "-p", "rho=0.5", "--to", "mitsuba-xml", "--out",
               tmp_path / "p.xml")
    assert res.exit_code == 0, res.output
    text = (tmp_path / "p.xml").read_text()
    bsdf = mi.load_string(text)  # the file is a document of its own (version="3.0.0")
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(0, 0, 1)
    ctx = mi.BSDFContext()
    wo = mi.Vector3f(math.sin(0.5), 0, math.cos(0.5))
    value = bsdf.eval(ctx, si, wo)
    # Mitsuba's eval is f cos(theta_o): (0.5/pi) cos(0.5), float32
    assert float(value[0]) == pytest.approx(0.5 / math.pi * math.cos(0.5), rel=1e-6)


def test_unmappable_model_is_refused_naming_the_option(tmp_path):
    res = _run("export", "coated", "--to", "mitsuba", "--out", tmp_path / "p.json")
    assert res.exit_code == 2
    assert "no Mitsuba 3 counterpart" in res.output and "pass --fit-closest" in res.output
    assert not (tmp_path / "p.json").exists()
    fitted = _run("export", "oren-nayar", "-p", "sigma=0.3", "--to", "mitsuba", "--out",
                  tmp_path / "p.json", "--fit-closest")
    assert fitted.exit_code == 0, fitted.output
    assert "fitted" in fitted.output and (tmp_path / "p.json").exists()


def test_existing_files_are_not_replaced_without_force(tmp_path):
    out = tmp_path / "p.json"
    out.write_text("mine\n")
    res = _run("export", "lambertian", "--to", "mitsuba", "--out", out)
    assert res.exit_code == 2 and "--force" in res.output
    assert out.read_text() == "mine\n"
    assert _run("export", "lambertian", "--to", "mitsuba", "--out", out, "--force").exit_code \
        == 0
    assert json.loads(out.read_text())["type"] == "diffuse"


@pytest.mark.parametrize("args, needle", [
    (["--to", "zemax"], "MODEL"),                                        # neither source
    (["lambertian", "--fit", "x", "--to", "zemax"], "not both"),
    (["lambertian", "--to", "gltf"], "--to gltf"),
    (["lambertian", "--to", "zemax", "--rgb"], "apply to the Mitsuba targets"),
    (["lambertian", "--to", "mitsuba", "--incidences", "0:60:30"], "apply to --to zemax"),
    (["lambertian", "--to", "mitsuba", "--theta-max", "95"], "--theta-max"),
    (["--fit", "nowhere", "--to", "zemax"], "fit.json"),
])
def test_bad_options_are_refused_before_writing(tmp_path, args, needle):
    res = _run("export", *args, "--out", tmp_path / "o.bsdf")
    assert res.exit_code == 2, res.output
    assert needle in res.output
    assert not list(tmp_path.iterdir())


def test_channels_that_are_not_one_bsdf_give_one_loadable_file_each(fit_dir, tmp_path):
    # two channels cannot be one RGB BSDF (export.mitsuba, "Channels"): one file per channel,
    # each a Mitsuba document of its own
    res = _run("export", "--fit", fit_dir, "--to", "mitsuba-xml", "--out", tmp_path / "p.xml",
               "--fit-closest")
    assert res.exit_code == 0, res.output
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["p_525nm.xml", "p_630nm.xml"]
    for name in names:
        text = (tmp_path / name).read_text()
        assert text.startswith("<bsdf") and 'version="3.0.0"' in text
        assert text.count("<bsdf ") >= 1 and text.rstrip().endswith("</bsdf>")
