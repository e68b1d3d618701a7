"""Polarimetric figures (:mod:`roughbrdf.plot_mueller`, ``roughbrdf plot --kind mueller|
mueller-plane|dolp``): what each panel draws is the model's own Mueller matrix
(``Model.mueller``), normalized by m00, and the DoLP of ``stokes.reflected_stokes``; the checks
read the drawn arrays back from the figures."""

from __future__ import annotations

import math

import numpy as np
import pytest
from typer.testing import CliRunner

import roughbrdf as rb
from roughbrdf import plot_mueller as pm
from roughbrdf.cli import app
from roughbrdf.plot import hemisphere_grid
from roughbrdf.stokes import dolp, linear, reflected_stokes

MODEL = rb.model("microfacet", distribution="beckmann", shadowing="smith-separable",
                 alpha=0.3, n=1.5, k=0.0) + rb.model("lambertian", rho=0.1)


def test_normalized_mueller_divides_by_m00_and_keeps_it():
    m = MODEL.mueller(0.4, np.array([0.1, 0.6]), np.array([0.0, 2.0]))
    out = pm.normalized_mueller(m)
    np.testing.assert_array_equal(out[..., 0, 0], m[..., 0, 0])
    np.testing.assert_allclose(out[..., 1, 2], m[..., 1, 2] / m[..., 0, 0], rtol=1e-15)
    # no light, no polarization: NaN, not a division by zero
    assert np.isnan(pm.normalized_mueller(np.zeros((4, 4)))[1, 1])


def test_hemisphere_panels_hold_the_normalized_elements():
    n = 41
    fig, axes = pm.plot_mueller_hemisphere(MODEL, math.radians(45), n=n)
    assert axes.shape == (4, 4)
    assert [ax.get_title() for ax in axes[0]] == ["m00", "m01/m00", "m02/m00", "m03/m00"]
    _, _, tr, ph = hemisphere_grid(n)
    inside = np.isfinite(tr)
    want = pm.normalized_mueller(MODEL.mueller(math.radians(45), tr[inside], ph[inside]))
    drawn = axes[1, 2].collections[0].get_array()  # the pcolormesh of m12/m00
    got = np.ma.filled(drawn.reshape(n, n), np.nan)[inside]
    np.testing.assert_allclose(got, want[:, 1, 2], rtol=1e-12, atol=1e-15)


def test_in_plane_curves_are_the_elements_along_the_plane():
    fig, axes = pm.plot_mueller_in_plane(MODEL, np.radians([20, 60]), n=61)
    line = axes[2, 2].get_lines()[1]  # second incidence: 60 deg
    x, y = line.get_xdata(), line.get_ydata()
    tr, ph = np.radians(np.abs(x)), np.where(x < 0, math.pi, 0.0)
    want = pm.normalized_mueller(MODEL.mueller(math.radians(60), tr, ph))[:, 2, 2]
    np.testing.assert_allclose(y, want, rtol=1e-12)
    assert axes[0, 0].get_yscale() == "log"


def test_dolp_map_is_the_dolp_of_the_reflected_stokes_vector():
    n = 31
    incident = linear(0.3)
    fig, ax = pm.plot_dolp(MODEL, math.radians(60), incident=incident, n=n)
    _, _, tr, ph = hemisphere_grid(n)
    inside = np.isfinite(tr)
    want = dolp(reflected_stokes(MODEL, math.radians(60), tr[inside], ph[inside], incident))
    got = np.ma.filled(ax.collections[0].get_array().reshape(n, n), np.nan)[inside]
    np.testing.assert_allclose(got, want, rtol=1e-12)
    assert np.nanmin(got) >= 0 and np.nanmax(got) <= 1 + 1e-12


@pytest.mark.parametrize("kind, ti", [("mueller", "45"), ("mueller-plane", "20:60:40"),
                                      ("dolp", "60")])
def test_cli_plot_kinds(tmp_path, kind, ti):
    out = tmp_path / f"{kind}.png"
    res = CliRunner().invoke(app, ["plot", "microfacet", "-p", "distribution=beckmann", "-p",
                                   "alpha=0.3", "-p", "n=1.5", "-p", "k=0", "--kind", kind,
                                   "--theta-i", ti, "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cli_model_without_mueller_matrix_is_a_usage_error(tmp_path):
    res = CliRunner().invoke(app, ["plot", "rb08", "--kind", "dolp", "--theta-i", "45",
                                   "--out", str(tmp_path / "x.png")])
    assert res.exit_code == 2, res.output
    assert "no Mueller matrix" in res.output
    assert not (tmp_path / "x.png").exists()
