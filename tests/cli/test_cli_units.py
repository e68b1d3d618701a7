"""Degrees everywhere at the CLI: model parameters
whose unit is an angle (Oren-Nayar ``sigma``, alone, in ``coated(diffuse="oren-nayar")`` and in
sums) and the polarization angle are taken and printed in degrees; ``fit.json`` and the Python
API keep radians."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.cli import main
from roughbrdf.measurement import Measurement

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

THETA_R = "0:80:20"
PHI = "0:180:90"


def _eval(capsys, *args) -> np.ndarray:
    """The value column of ``roughbrdf eval ARGS`` (theta_i 30, THETA_R, PHI)."""
    code = main(["eval", *args, "--theta-i", "30", "--theta-r", THETA_R, "--phi", PHI])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    rows = [line.split(",") for line in captured.out.splitlines()[1:]]
    return np.array([float(r[3]) for r in rows])


def _library(m: rb.Model) -> np.ndarray:
    """``m.brdf`` on the grid of :func:`_eval` (the same order: theta_r, then phi)."""
    tr, ph = np.meshgrid(np.radians(np.arange(0.0, 81.0, 20.0)), np.radians([0.0, 90.0, 180.0]),
                         indexing="ij")
    return np.asarray(m.brdf(math.radians(30.0), tr.ravel(), ph.ravel()))


def test_eval_oren_nayar_sigma_in_degrees(capsys):
    got = _eval(capsys, "oren-nayar", "-p", "rho=0.5", "-p", "sigma=20")
    want = _library(rb.model("oren-nayar", rho=0.5, sigma=np.radians(20)))
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=0)


def test_eval_coated_oren_nayar_sigma_in_degrees(capsys):
    got = _eval(capsys, "coated", "-p", "diffuse=oren-nayar", "-p", "sigma=25")
    want = _library(rb.model("coated", diffuse="oren-nayar", sigma=np.radians(25)))
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=0)


@pytest.mark.parametrize("name", ["sigma", "on_sigma"])
def test_eval_sum_sigma_in_degrees_plain_or_prefixed(capsys, name):
    got = _eval(capsys, "oren-nayar+tr75", "-p", f"{name}=30", "-p", "tr75_rho_L=0.1")
    want = _library(rb.model("oren-nayar+tr75", on_sigma=np.radians(30), tr75_rho_L=0.1))
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=0)


def test_eval_per_degree_parameter_left_alone(capsys):
    # TS67's c is per degree (unit 1/deg), not an angle: taken as given
    got = _eval(capsys, "ts67", "-p", "c=0.1")
    np.testing.assert_allclose(got, _library(rb.model("ts67", c=0.1)), rtol=1e-12)


def test_models_listing_shows_sigma_in_degrees(capsys):
    assert main(["models"]) == 0
    out = capsys.readouterr().out
    sigma = [line for line in out.splitlines() if line.strip().startswith("sigma ")]
    assert sigma, out
    for line in sigma:
        assert "[deg]" in line and "17.1887" in line, line
    assert "[rad]" not in out


def test_polarization_message_says_degrees(capsys):
    code = main(["eval", "tr75", "--polarization", "sideways"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert "--polarization" in err and "'sideways'" in err
    assert "degrees" in err and "radian" not in err


def test_polarization_angle_in_degrees(capsys):
    got = _eval(capsys, "tr75", "--polarization", "30")
    m = rb.model("tr75")
    tr, ph = np.meshgrid(np.radians(np.arange(0.0, 81.0, 20.0)), np.radians([0.0, 90.0, 180.0]),
                         indexing="ij")
    want = m.brdf(math.radians(30.0), tr.ravel(), ph.ravel(), polarization=math.radians(30))
    np.testing.assert_allclose(got, want, rtol=1e-12)


def _oren_nayar_file(tmp_path) -> tuple[object, float]:
    sigma = math.radians(20.0)
    ti, tr, ph = np.meshgrid(np.radians([0.0, 30.0, 60.0]), np.radians(np.arange(0.0, 81.0, 10.0)),
                             np.radians([0.0, 90.0, 180.0]))
    ti, tr, ph = ti.ravel(), tr.ravel(), ph.ravel()
    v = np.asarray(rb.model("oren-nayar", rho=0.6, sigma=sigma).brdf(ti, tr, ph))
    path = tmp_path / "on.csv"
    rb.io.write(Measurement(ti, tr, ph, v[:, None], channels=["550nm"], quantity="brdf"), path)
    return path, sigma


def _sigma_line(report: str) -> str:
    (line,) = [ln for ln in report.splitlines() if re.match(r"\s+sigma\s*:", ln)]
    return line


def test_fit_takes_and_prints_sigma_in_degrees(capsys, tmp_path):
    path, sigma = _oren_nayar_file(tmp_path)
    out = tmp_path / "fit"
    code = main(["fit", str(path), "-m", "oren-nayar", "-p", "sigma=10", "--bounds",
                 "sigma=0:60", "--starts", "2", "--no-plots", "--out", str(out)])
    printed = capsys.readouterr().out
    assert code == 0
    # fit.json: radians, as in Python
    (ch,) = json.loads((out / "fit.json").read_text())["channels"]
    assert ch["params"]["sigma"] == pytest.approx(sigma, rel=1e-4)
    assert ch["init"]["sigma"] == pytest.approx(math.radians(10), rel=1e-12)
    assert ch["bounds"]["sigma"] == pytest.approx([0.0, math.radians(60)], rel=1e-12)
    # the report on the terminal and in report.txt: degrees, with the unit named
    for report in (printed, (out / "report.txt").read_text()):
        line = _sigma_line(report)
        value = float(line.split(":")[1].split()[0])
        assert value == pytest.approx(20.0, rel=1e-4), line
        assert "deg" in line and "(init = 10 deg, bounds [0, 60] deg)" in line, line


def test_python_report_keeps_radians_with_unit(tmp_path):
    path, sigma = _oren_nayar_file(tmp_path)
    res = rb.fit("oren-nayar", rb.io.read(path), starts=1)
    line = _sigma_line(res.report())
    assert float(line.split(":")[1].split()[0]) == pytest.approx(sigma, rel=1e-4)
    assert " rad" in line and "deg" not in line
    assert "deg" in _sigma_line(res.report(angles="deg"))


def test_fit_bounds_of_sigma_refused_in_degrees(capsys, tmp_path):
    path, _ = _oren_nayar_file(tmp_path)
    code = main(["fit", str(path), "-m", "oren-nayar", "--bounds", "sigma=-10:20", "--out",
                 str(tmp_path / "o")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1, err
    assert "--bounds sigma=-10:20" in err and "[0, inf) degrees" in err
    assert not (tmp_path / "o").exists()
