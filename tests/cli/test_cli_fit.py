"""``roughbrdf fit FILE --model NAME --out DIR``: outputs, model sums, options and errors."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

import roughbrdf as rb
from roughbrdf.cli import app
from roughbrdf.cli.fit import build_model, resolve_names
from roughbrdf.demo import default_measurement_path

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

runner = CliRunner()
DEFAULT = default_measurement_path()


def _fit(*args):
    return runner.invoke(app, ["fit", *map(str, args)])


def test_fit_writes_json_report_and_plots(tmp_path):
    out = tmp_path / "out"
    res = _fit(DEFAULT, "--model", "trowbridge-reitz-1975", "--starts", "2", "--out", out)
    assert res.exit_code == 0, res.output  # TR75 fitted under the energy constraint
    assert "[[Fit]] trowbridge-reitz-1975" in res.output and "TR75 sigma" in res.output
    d = json.loads((out / "fit.json").read_text())
    assert d["model"] == "trowbridge-reitz-1975" and d["loss"] == "relative"
    assert d["file"].endswith("tr75_cement.csv")
    (ch,) = d["channels"]
    assert ch["channel"] == "relative" and ch["success"] is True
    assert set(ch["params"]) == {"e", "n", "k", "rho_L"} == set(ch["stderr"])
    m = ch["metrics"]
    assert {"sigma", "rms_log", "chi2", "aic", "bic", "n_points"} <= set(m)
    # the cement data's unconstrained fit (e = 0.68, sigma 0.10) reflects 5.8 at 89 deg; under
    # the energy constraint e ends near 0.8 and sigma near 0.12
    assert m["n_points"] == 432 and 0.08 < m["sigma"] < 0.13
    assert ch["params"]["e"] == pytest.approx(0.75, abs=0.1)
    assert ch["energy_constraint"]["active"] is True and ch["gains_energy"] is False
    assert (out / "report.txt").read_text().startswith("[[Fit]]")
    assert (out / "fit_relative.png").stat().st_size > 10_000


def test_sum_model_with_parameters_fix_and_loss(tmp_path):
    out = tmp_path / "sum"
    res = _fit(DEFAULT, "-m", "trowbridge-reitz-1975+lambertian", "-p", "tr75_rho_L=0",
               "--fix", "rho_L", "-p", "rho=0.2", "--loss", "log", "--starts", "2", "--out",
               out, "--no-plots", "-q", "--no-energy-constraint")  # TR75 Table 1's own fit
    assert res.exit_code == 1 and "warning:" in res.output, res.output  # TR75: albedo > 1
    assert "[[Fit]]" not in res.output  # --quiet
    d = json.loads((out / "fit.json").read_text())
    assert d["model"] == "trowbridge-reitz-1975+lambertian" and d["loss"] == "log"
    ch = d["channels"][0]
    assert ch["params"]["tr75_rho_L"] == 0.0 and ch["stderr"]["tr75_rho_L"] is None
    assert ch["params"]["lambertian_rho"] == pytest.approx(0.33, abs=0.1)
    assert not list(out.glob("*.png"))


def test_build_model_and_names():
    m = build_model("microfacet+lambertian", {"distribution": "beckmann", "rho": 0.2,
                                               "microfacet_alpha": 0.4})
    assert m.components[0].options["distribution"] == "beckmann"
    assert m.params["lambertian_rho"] == 0.2 and m.params["microfacet_alpha"] == 0.4
    assert resolve_names(m, ["alpha", "lambertian_rho"]) == ["microfacet_alpha",
                                                              "lambertian_rho"]
    with pytest.raises(ValueError, match="ambiguous.*tr75_n, microfacet_n"):
        build_model("trowbridge-reitz-1975+microfacet", {"n": 1.5})
    with pytest.raises(ValueError, match="unknown parameter 'bogus'"):
        build_model("trowbridge-reitz-1975+lambertian", {"bogus": 1.0})
    with pytest.raises(ValueError, match="unknown parameter 'bogus'"):
        resolve_names(m, ["bogus"])
    with pytest.raises(ValueError, match="expected NAME or NAME\\+NAME"):
        build_model("lambertian+", {})


def test_channel_quantity_and_alta_without_param_out(tmp_path):
    """An ALTA file without #PARAM_OUT needs --quantity; --channel picks one channel."""
    t_i, t_r, p = np.meshgrid(np.radians([15, 45]), np.radians(np.arange(0, 80, 5)),
                              np.radians([0, 60, 120, 180]), indexing="ij")
    t_i, t_r, p = t_i.ravel(), t_r.ravel(), p.ravel()
    m = rb.model("trowbridge-reitz-1975", e=0.3, n=1.5, k=0.0, rho_L=0.1)
    f = m.bridf(t_i, t_r, p)
    # ALTA ISOTROPIC_TL_TV_PROJ_DPHI: x1 = theta_v cos(dphi), dphi = 0 on the source side
    dphi = np.pi - p
    rows = [f"{a:.9g} {b * math.cos(c):.9g} {b * math.sin(c):.9g} {v:.9g}"
            for a, b, c, v in zip(t_i, t_r, dphi, f, strict=True)]
    path = tmp_path / "noparam.dat"
    path.write_text("#DIM 3 1\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n" + "\n".join(rows) + "\n")
    res = _fit(path, "-m", "tr75", "--out", tmp_path / "a", "--starts", "2")
    assert res.exit_code == 2 and "--quantity" in res.output
    # the truth (TR75 e = 0.3, rho_L = 0.1) reflects 1.9 at 89 deg: recovered unconstrained
    res = _fit(path, "-m", "tr75", "--quantity", "brdf_cos", "--channel", "0",
               "--out", tmp_path / "a", "--starts", "2", "-q", "--no-energy-constraint")
    assert res.exit_code == 0, res.output
    d = json.loads((tmp_path / "a" / "fit.json").read_text())
    assert d["quantity"] == "brdf_cos" and d["channels"][0]["params"]["e"] == pytest.approx(
        0.3, rel=1e-4)


def test_errors_are_clear(tmp_path):
    res = _fit(DEFAULT, "-m", "tr75", "--loss", "squared", "--out", tmp_path / "x")
    assert res.exit_code == 2, res.output
    (line,) = res.output.splitlines()  # one line: the option, the value and the choices
    assert line.startswith("error: --loss: ") and "'squared'" in line
    assert all(c in line for c in ("auto", "relative", "log", "absolute", "robust")), line
    res = _fit(tmp_path / "missing.astm", "-m", "tr75", "--out", tmp_path / "x")
    assert res.exit_code == 2 and "no such file" in res.output
    res = _fit(DEFAULT, "-m", "no-such-model", "--out", tmp_path / "x")
    assert res.exit_code == 2 and "unknown model 'no-such-model'" in res.output
    res = _fit(DEFAULT, "-m", "tr75", "--fix", "e", "--fix", "n", "--fix", "k", "--fix",
               "rho_L", "--out", tmp_path / "x")
    assert res.exit_code == 2 and "every parameter" in res.output
    res = _fit(DEFAULT, "-m", "tr75", "--channel", "green", "--out", tmp_path / "x")
    assert res.exit_code == 2 and "unknown channel 'green'" in res.output
    assert not (tmp_path / "x").exists()


def test_never_overwrites_foreign_files(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "fit.json").write_text("{}")
    (out / "notes.txt").write_text("keep")
    args = (DEFAULT, "-m", "tr75", "--starts", "1", "--no-plots", "-q", "--out", out)
    res = _fit(*args)
    assert res.exit_code == 2 and "not overwriting fit.json" in res.output
    assert (out / "fit.json").read_text() == "{}"
    # a file roughbrdf did not write is never replaced, not even with --force
    res = _fit(*args, "--force")
    assert res.exit_code == 2 and "not overwriting fit.json" in res.output
    assert "not even with --force" in res.output
    assert (out / "fit.json").read_text() == "{}"
    (out / "fit.json").unlink()  # the user moves it away
    res = _fit(*args)
    assert res.exit_code == 0, res.output  # TR75 fitted under the energy constraint
    res = _fit(*args)  # the folder holds results now: a second run asks for --force
    assert res.exit_code == 2 and "holds results already" in res.output
    assert "--force" in res.output and "overwrite=True" not in res.output
    res = _fit(*args, "--force")  # and replaces them with it
    assert res.exit_code == 0, res.output  # TR75 fitted under the energy constraint
    assert (out / "notes.txt").read_text() == "keep"
    assert json.loads((out / "fit.json").read_text())["model"] == "trowbridge-reitz-1975"


def test_aperture_option_recorded_in_json_and_report(tmp_path):
    out = tmp_path / "ap"
    res = _fit(DEFAULT, "--model", "trowbridge-reitz-1975", "--starts", "1", "--aperture", "2",
               "--out", out, "--no-plots")
    assert res.exit_code == 0, res.output  # TR75 fitted under the energy constraint
    assert "aperture           = 2 deg half-angle, uniform cone about w_r" in res.output
    d = json.loads((out / "fit.json").read_text())
    assert d["aperture"]["half_angle_deg"] == pytest.approx(2.0)
    assert d["aperture"]["half_angle_rad"] == pytest.approx(math.radians(2.0))
    assert d["aperture"]["points"] == 19
    assert d["options"]["aperture"] == pytest.approx(math.radians(2.0))
    plain = _fit(DEFAULT, "--model", "trowbridge-reitz-1975", "--starts", "1", "--out",
                 tmp_path / "plain", "--no-plots", "-q")
    assert plain.exit_code == 0, plain.output  # TR75 fitted under the energy constraint
    assert json.loads((tmp_path / "plain" / "fit.json").read_text())["aperture"] is None


@pytest.mark.parametrize("bad", ["-1", "90", "nan"])
def test_bad_aperture_is_a_clean_error(tmp_path, bad):
    res = _fit(DEFAULT, "--model", "ts67", "--aperture", bad, "--out", tmp_path / "x")
    assert res.exit_code == 2
    assert "--aperture must be a half-angle in degrees" in res.output


def test_free_scale_option_fits_a_data_scale_on_absolute_data(tmp_path):
    """--free-scale: absolute data off by a calibration factor give the model's parameters and
    K = 1/factor (rb.fit(..., free_scale=True)); without it the scale stays 1."""
    t_i, t_r, p = np.meshgrid(np.radians([0, 20, 40, 60]), np.radians(np.arange(0, 86, 5)),
                              np.radians(np.arange(0, 181, 30)), indexing="ij")
    truth = {"e": 0.3, "n": 1.5, "k": 0.0, "rho_L": 0.1}
    f = rb.model("trowbridge-reitz-1975", **truth).brdf(t_i, t_r, p)
    rows = [f"{a:.9g},{b:.9g},{c:.9g},{2.0 * v:.12g}"
            for a, b, c, v in zip(t_i.ravel(), t_r.ravel(), p.ravel(), f.ravel(), strict=True)]
    path = tmp_path / "scaled.csv"
    path.write_text("# angles: rad\n# quantity: brdf\ntheta_i,theta_r,phi,value\n"
                    + "\n".join(rows) + "\n")
    # n and k fixed: the Fresnel factor then sets the absolute scale, so K is identifiable
    # the truth reflects more than it receives at 89 deg: recovered without the constraint
    args = (path, "-m", "tr75", "-p", "n=1.5", "-p", "k=0", "--fix", "n", "--fix", "k",
            "--starts", "2", "--no-plots", "-q", "--no-energy-constraint")
    res = _fit(*args, "--free-scale", "--out", tmp_path / "free")
    assert res.exit_code == 0, res.output
    ch = json.loads((tmp_path / "free" / "fit.json").read_text())["channels"][0]
    assert ch["scale"] == pytest.approx(0.5, rel=1e-4)
    for name in ("e", "rho_L"):
        assert ch["params"][name] == pytest.approx(truth[name], rel=1e-4)
    res = _fit(*args, "--out", tmp_path / "fixed")
    assert res.exit_code == 0, res.output
    ch = json.loads((tmp_path / "fixed" / "fit.json").read_text())["channels"][0]
    assert ch["scale"] == 1.0
    assert not list(tmp_path.glob("*/*.png"))


# ---------------------------------------------------------------------------------------------
# CLI options for what the library takes, refusing before the fit
# ---------------------------------------------------------------------------------------------
def test_bounds_option(tmp_path):
    out = tmp_path / "b"
    # unconstrained: the bound, not the energy constraint, is what this test looks at
    res = _fit(DEFAULT, "-m", "tr75", "--bounds", "e=0.1:0.5", "--bounds", "rho_L=0.2:0.6",
               "--starts", "2", "--no-plots", "-q", "--out", out, "--no-energy-constraint")
    assert res.exit_code == 1 and "warning:" in res.output, res.output  # TR75: albedo > 1
    params = json.loads((out / "fit.json").read_text())["channels"][0]["params"]
    assert 0.1 <= params["e"] <= 0.5 and params["e"] == pytest.approx(0.5, abs=1e-6)  # true 0.68
    m = build_model("trowbridge-reitz-1975+lambertian")
    from roughbrdf.cli.fit import parse_bounds

    assert parse_bounds(m, ["e=0:1", "rho=0.1:0.2"]) == {"tr75_e": (0.0, 1.0),
                                                          "lambertian_rho": (0.1, 0.2)}


@pytest.mark.parametrize("bounds, needle", [
    ("e=0.1", "--bounds expects NAME=LOW:HIGH"),
    ("e:0.1:2", "--bounds expects NAME=LOW:HIGH"),
    ("e=a:b", "--bounds expects NAME=LOW:HIGH"),
    ("e=2:1", "need finite LOW < HIGH"),
    ("bogus=0:1", "unknown parameter 'bogus'"),
    ("e=1:2", "--bounds"),  # the starting value -p e=0.68 is outside: the fix names the option
])
def test_bounds_errors_name_the_option(tmp_path, bounds, needle):
    res = _fit(DEFAULT, "-m", "tr75", "-p", "e=0.68", "--bounds", bounds, "--out",
               tmp_path / "x", "--no-plots")
    assert res.exit_code == 2, res.output
    assert needle in res.output and "bounds={" not in res.output
    assert not (tmp_path / "x").exists()


def test_angles_in_option(tmp_path):
    text = DEFAULT.read_text().replace("# angles: deg\n", "")
    path = tmp_path / "noangles.csv"
    path.write_text(text)
    res = _fit(path, "-m", "tr75", "--starts", "1", "--no-plots", "-q", "--out", tmp_path / "a")
    assert res.exit_code == 2 and "angle" in res.output  # the reader's message (roughbrdf.io)
    res = _fit(path, "-m", "tr75", "--angles-in", "deg", "--starts", "1", "--no-plots", "-q",
               "--out", tmp_path / "a", "--no-energy-constraint")  # TR75 Table 1's own fit
    assert res.exit_code == 1 and "warning:" in res.output, res.output  # TR75: albedo > 1
    d = json.loads((tmp_path / "a" / "fit.json").read_text())
    assert d["channels"][0]["params"]["e"] == pytest.approx(0.68, abs=0.05)
    res = _fit(path, "-m", "tr75", "--angles-in", "grad", "--out", tmp_path / "b")
    assert res.exit_code == 2
    assert "--angles-in: unknown angle unit 'grad' (choose from deg, rad)" in res.output
    alta = tmp_path / "x.dat"
    alta.write_text("#DIM 3 1\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT INV_STERADIAN\n"
                    "0.1 0.2 0 1\n")
    res = _fit(alta, "-m", "tr75", "--angles-in", "deg", "--out", tmp_path / "b")
    assert res.exit_code == 2 and "--angles-in applies to ASTM and CSV files" in res.output


def test_quantity_takes_every_spelling(tmp_path, monkeypatch):
    from roughbrdf import io as rbio

    seen = []
    real = rbio.read

    def spy(path, format=None, **options):
        seen.append(options.get("quantity"))
        return real(path, format=format, **options)

    monkeypatch.setattr(rbio, "read", spy)
    for spelling in ("RELATIVE", "relative"):
        res = _fit(DEFAULT, "-m", "tr75", "--quantity", spelling, "--starts", "1", "-q",
                   "--no-plots", "--out", tmp_path / spelling)
        assert res.exit_code == 0, res.output  # TR75 fitted under the energy constraint
    assert seen == ["relative", "relative"]
    res = _fit(DEFAULT, "-m", "tr75", "--quantity", "radiance", "--out", tmp_path / "x")
    assert res.exit_code == 2
    assert "--quantity must be one of brdf, brdf_cos, bridf, relative" in res.output


def test_refuses_before_fitting(tmp_path, monkeypatch):
    import roughbrdf.fitting

    def must_not_fit(*args, **kwargs):
        raise AssertionError("fitted")

    out = tmp_path / "o"
    out.mkdir()
    (out / "fit_relative.png").write_bytes(b"the user's figure")
    monkeypatch.setattr(roughbrdf.fitting, "fit", must_not_fit)
    res = _fit(DEFAULT, "-m", "tr75", "--out", out)
    assert res.exit_code == 2 and "not overwriting fit_relative.png" in res.output
    assert (out / "fit_relative.png").read_bytes() == b"the user's figure"


def test_result_names_are_the_names_save_writes(tmp_path):
    from roughbrdf.cli.fit import result_names

    meas = rb.read(DEFAULT)
    res = rb.fit(rb.model("tr75"), meas, starts=1)
    assert result_names(meas, None, True) == ["fit.json", "report.txt", *res.plot_names()]
    assert result_names(meas, ["0"], False) == ["fit.json", "report.txt"]


def test_force_replaces_the_whole_earlier_set(tmp_path):
    """A second fit (another model, no plots) once replaced fit.json and report.txt without a
    word and left the old PNG beside them; now it asks for --force, which replaces the set."""
    out = tmp_path / "o"
    res = _fit(DEFAULT, "-m", "tr75", "--starts", "1", "-q", "--out", out)
    assert res.exit_code == 0, res.output  # TR75 fitted under the energy constraint
    assert (out / "fit_relative.png").is_file()
    again = (DEFAULT, "-m", "ts67", "-p", "n=None", "--fix", "rho_d", "--starts", "1", "-q",
             "--no-plots", "--out", out)
    res = _fit(*again)
    assert res.exit_code == 2 and "holds results already" in res.output
    assert json.loads((out / "fit.json").read_text())["model"] == "trowbridge-reitz-1975"
    res = _fit(*again, "--force")
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in out.iterdir()) == [".roughbrdf-outputs", "fit.json",
                                                     "report.txt"]
    assert json.loads((out / "fit.json").read_text())["model"] == "torrance-sparrow-1967"
