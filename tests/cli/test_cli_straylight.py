"""The stray-light models (ABg, Harvey-Shack, K-correlation) at the command line: fit, per
incidence, export, list.

Files: the committed Zemax examples (``tests/data/zemax/``: AnoBlack NiTE on Invar, 650 nm, and
Aeroglaze Z307, incidences 10-70 deg). Expected values: TIS <= 1 at every incidence (the energy
constraint, Zemax's TIS check), a written table equal to the fit it came from, a LightTools
file read back equal to the model on its grid.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import roughbrdf as rb
from roughbrdf.cli import app
from roughbrdf.fitting.choice.compare import AUTO_CANDIDATES
from roughbrdf.fitting.results.plausibility import EXPORT_INCIDENCES_DEG

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

DATA = Path(__file__).parents[1] / "data" / "zemax"
ANOBLACK = DATA / "AnoBlackNiTEonINVAR.bsdf"
AEROGLAZE = DATA / "aeroglaze.bsdf"
runner = CliRunner()


def test_models_lists_them_and_auto_leaves_them_out():
    got = runner.invoke(app, ["models"])
    assert got.exit_code == 0
    for name in ("abg", "harvey-shack", "k-correlation"):
        assert name in got.output
        assert not any(c.split("(")[0] == name for c in AUTO_CANDIDATES)


@pytest.mark.parametrize("model", ["abg", "harvey-shack"])
@pytest.mark.parametrize("path", [ANOBLACK, AEROGLAZE], ids=lambda p: p.stem)
def test_fit_of_the_zemax_examples_keeps_tis_below_1(tmp_path, model, path):
    out = tmp_path / "fit"
    got = runner.invoke(app, ["fit", str(path), "--model", model, "--out", str(out),
                              "--no-plots", "--quiet"])
    assert got.exit_code in (0, 1), got.output  # 1: a search limit, said on stderr
    doc = json.loads((out / "fit.json").read_text())
    ch = doc["channels"][0]
    assert ch["success"], ch
    fitted = rb.model(model, **ch["params"])
    tis = rb.albedo(fitted, np.radians(EXPORT_INCIDENCES_DEG))
    assert np.all(tis <= 1 + 1e-3), tis.max()


def test_per_incidence_fit_then_zemax_abg_table(tmp_path):
    out = tmp_path / "rows"
    got = runner.invoke(app, ["fit", str(ANOBLACK), "--model", "abg", "--per-incidence",
                              "--out", str(out), "--quiet"])
    assert got.exit_code == 0, got.output
    doc = json.loads((out / "fit.json").read_text())
    assert doc["per_incidence"] is True and doc["model"] == "abg"
    assert [round(r["theta_i_deg"]) for r in doc["rows"]] == [10, 30, 50, 70]
    assert "4 of 4 rows kept" in (out / "report.txt").read_text()
    table = tmp_path / "anoblack.txt"
    got = runner.invoke(app, ["export", "--fit", str(out), "--to", "zemax-abg", "--out",
                              str(table)])
    assert got.exit_code == 0, got.output
    rows = [ln.split() for ln in table.read_text().splitlines() if ln.startswith("yes ")]
    assert len(rows) == 4
    for cells, r in zip(rows, doc["rows"], strict=True):
        p = r["channels"]["value"]["params"]
        assert float(cells[1]) == pytest.approx(r["theta_i_deg"], abs=1e-3)
        assert float(cells[2]) == pytest.approx(p["A"], rel=1e-6)
        assert float(cells[3]) == pytest.approx(p["B"], rel=1e-6)
        assert float(cells[4]) == pytest.approx(p["g"], rel=1e-5)
        assert float(cells[5]) <= 1.0  # Zemax's TIS check
    # a per-incidence fit goes to the ABg table only
    got = runner.invoke(app, ["export", "--fit", str(out), "--to", "zemax", "--out",
                              str(tmp_path / "x.bsdf")])
    assert got.exit_code == 2 and "zemax-abg" in got.output


def test_export_to_lighttools_reads_back_as_the_model(tmp_path):
    path = tmp_path / "abg.bsdf"
    got = runner.invoke(app, ["export", "abg", "-p", "A=0.002", "-p", "B=0.01", "-p", "g=2",
                              "--to", "lighttools", "--out", str(path)])
    assert got.exit_code == 0, got.output
    m = rb.read(path)
    assert m.meta["format"] == "lighttools"
    model = rb.model("abg", A=0.002, B=0.01, g=2.0)
    np.testing.assert_allclose(m.values[:, 0], model.brdf(m.theta_i, m.theta_r, m.phi),
                               rtol=1e-7)  # the file prints 8 significant digits


def test_k_correlation_needs_a_wavelength_at_the_command_line(tmp_path):
    # the Zemax example's channel is "value": no wavelength in the file's data, so --wavelength
    got = runner.invoke(app, ["fit", str(ANOBLACK), "--model", "k-correlation", "--out",
                              str(tmp_path / "a"), "--no-plots", "--quiet", "--fix", "n",
                              "--fix", "k"])
    assert got.exit_code == 2 and "--wavelength" in got.output
    got = runner.invoke(app, ["fit", str(ANOBLACK), "--model", "k-correlation", "--out",
                              str(tmp_path / "b"), "--no-plots", "--quiet", "--fix", "n",
                              "--fix", "k", "--wavelength", "650nm"])
    assert got.exit_code in (0, 1), got.output
    doc = json.loads((tmp_path / "b" / "fit.json").read_text())
    assert doc["channels"][0]["success"]
    assert math.isfinite(doc["channels"][0]["params"]["A"])


@pytest.mark.parametrize(("model", "truth"), [
    ("abg", {"A": 0.004, "B": 0.002, "g": 1.6}),
    ("harvey-shack", {"b0": 0.5, "L": 0.02, "S": -2.2}),
])
def test_synthetic_recovery_within_standard_errors(model, truth):
    # a full hemisphere at 4 incidences, 3 % multiplicative noise; every parameter within
    # 3 of its reported standard errors of the truth
    rng = np.random.default_rng(7)
    ti, tr, ph = (a.ravel() for a in np.meshgrid(
        np.radians([10.0, 30.0, 50.0, 70.0]), np.radians(np.arange(1.0, 88.0, 3.0)),
        np.radians(np.arange(0.0, 181.0, 15.0)), indexing="ij"))
    f = rb.model(model, **truth).brdf(ti, tr, ph)
    meas = rb.Measurement(ti, tr, ph, f * np.exp(0.03 * rng.standard_normal(ti.size)))
    c = rb.fit(model, meas, progress=False)[0]
    assert c.success, c.message
    for name, value in truth.items():
        assert abs(c.params[name] - value) <= 3 * c.stderr[name], (name, c.params, c.stderr)


@pytest.mark.parametrize("spec", ["abg", "harvey-shack", "k-correlation"])
def test_the_zemax_tabular_writer_takes_every_new_model(tmp_path, spec):
    kw = ["-p", "wavelength=0.633"] if spec == "k-correlation" else []
    path = tmp_path / "m.bsdf"
    got = runner.invoke(app, ["export", spec, *kw, "--to", "zemax", "--out", str(path)])
    assert got.exit_code == 0, got.output
    m = rb.read(path)
    model = rb.model(spec, **({"wavelength": 0.633} if kw else {}))
    ok = m.theta_r < math.radians(89.0)  # the table's own grid, below the horizon
    np.testing.assert_allclose(m.values[ok, 0], model.brdf(m.theta_i[ok], m.theta_r[ok],
                                                           m.phi[ok]), rtol=1e-5)
