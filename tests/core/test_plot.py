"""roughbrdf.plot: every function takes ax=, returns (fig, ax), labels its axes, leaks no pyplot
state, and draws the right numbers (conventions: signed in-plane angle, TR75 azimuth)."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.figure import Figure

import roughbrdf as rb
from roughbrdf import plot
from roughbrdf.measurement import Measurement

TR = dict(e=0.68, n=1.0, k=0.9, rho_L=0.33)  # TR75 cement (Table 1)


@pytest.fixture(scope="module")
def tr():
    return rb.model("trowbridge-reitz-1975", **TR)


@pytest.fixture(scope="module")
def ts():
    return rb.model("torrance-sparrow-1967", g=2 / 3, c=0.05, n=None, k=None, rho_d=0.3)


def _in_plane_measurement(model, quantity="brdf", scale=1.0, noise=0.0, pol=None, seed=0):
    ti = np.repeat(np.radians([0.0, 30.0, 60.0]), 35)
    ts_ = np.tile(np.radians(np.linspace(-80, 80, 35)), 3)
    tr_, ph = rb.geometry.from_signed_angle(ts_)
    q = "bridf" if quantity in ("bridf", "brdf_cos") else "brdf"
    v = plot.model_values(model, ti, tr_, ph, q, pol) * scale
    if noise:
        v = v * (1 + noise * np.random.default_rng(seed).standard_normal(v.size))
    return Measurement(ti, tr_, ph, v, quantity=quantity, polarization=pol,
                       meta={"sample": "synthetic"})


def _labelled(ax):
    assert ax.get_xlabel() and ax.get_ylabel()
    assert ax.get_legend() is not None
    assert ax.get_legend().get_texts()


def test_no_pyplot_figures_are_created(tr):
    before = plt.get_fignums()
    fig, ax = plot.plot_in_plane(tr, [0.0, 0.5])
    plot.plot_hemisphere(tr, 0.5, n=41)
    plot.plot_polar(tr, 0.5, 0.7, n=91)
    assert plt.get_fignums() == before
    assert isinstance(fig, Figure)


def test_in_plane_signed_axis_and_values(ts):
    fig, ax = plot.plot_in_plane(ts, np.radians([30.0, 60.0]), quantity="relative", n=361,
                                 limit_deg=90.0)
    _labelled(ax)
    assert len(ax.get_lines()) >= 2
    line = ax.get_lines()[0]  # psi = 30
    x, y = line.get_xdata(), line.get_ydata()
    assert x.min() == pytest.approx(-90) and x.max() == pytest.approx(90)
    # relative = 1 at the specular direction (+30 deg), Eq. 23
    j = int(np.argmin(np.abs(x - 30.0)))
    assert y[j] == pytest.approx(1.0, abs=1e-12)
    # negative abscissa = source side: phi = pi
    k = int(np.argmin(np.abs(x + 45.0)))
    expected = ts.relative(math.radians(30), math.radians(45), math.pi)
    assert y[k] == pytest.approx(float(expected), rel=1e-12)
    fig2, ax2 = plot.plot_in_plane(ts, 0.5, log=True, quantity="brdf")
    assert ax2.get_yscale() == "log"


def test_in_plane_uses_given_axes(tr):
    fig = Figure()
    ax = fig.add_subplot()
    f2, a2 = plot.plot_in_plane(tr, 0.3, quantity="bridf", ax=ax)
    assert f2 is fig and a2 is ax


def test_polar_tr75_convention(tr):
    beta, elev = math.radians(60.0), math.radians(30.0)
    fig, ax = plot.plot_polar(tr, beta, elev, n=361)
    assert ax.name == "polar"
    assert ax.get_xlabel() and ax.get_ylabel() and ax.get_legend() is not None
    s_line, p_line = ax.get_lines()[:2]
    psi, ys = s_line.get_xdata(), s_line.get_ydata()
    # psi = 180 deg is the forward side: there the ray is the specular one (theta_r = beta)
    j = int(np.argmin(np.abs(psi - math.pi)))
    assert ys[j] == pytest.approx(float(tr.bridf(beta, math.pi / 2 - elev, 0.0, "s")))
    # psi = 0 points at the source
    assert ys[0] == pytest.approx(float(tr.bridf(beta, math.pi / 2 - elev, math.pi, "s")))
    yp = p_line.get_ydata()
    assert yp[j] == pytest.approx(float(tr.bridf(beta, math.pi / 2 - elev, 0.0, "p")))
    assert ys[j] > yp[j]  # near Brewster-like angles s reflects more than p
    assert ax.get_theta_offset() == pytest.approx(math.pi / 2)  # psi = 0 at the top


def test_hemisphere_disk(tr):
    fig, ax = plot.plot_hemisphere(tr, math.radians(40.0), n=81, log=True)
    assert ax.get_xlabel() and ax.get_ylabel() and ax.get_legend() is not None
    assert len(fig.axes) == 2  # the colorbar
    assert fig.axes[1].get_ylabel()  # colorbar label
    mesh = ax.collections[0]
    z = np.ma.masked_invalid(mesh.get_array())
    assert z.count() > 0 and z.min() > 0
    X, Y, tr_, ph = plot.hemisphere_grid(81)
    assert np.isnan(tr_[0, 0]) and tr_[40, 40] == pytest.approx(0.0)
    # the maximum sits on the forward side, near the specular point (+sin 40, 0)
    zz = np.asarray(z.filled(np.nan)).reshape(X.shape)
    i, j = np.unravel_index(np.nanargmax(zz), zz.shape)
    assert X[i, j] > 0.3


@pytest.mark.parametrize("quantity", ["brdf", "bridf", "relative"])
def test_comparison_quantities(tr, quantity):
    meas = _in_plane_measurement(tr, quantity, scale=7.3 if quantity == "relative" else 1.0)
    fig, ax = plot.plot_comparison(tr, meas)
    _labelled(ax)
    assert ax.get_title()
    # data markers and model lines: one colour per incidence, 3 incidences
    data_lines = [ln for ln in ax.get_lines() if ln.get_linestyle() == "None"]
    model_lines = [ln for ln in ax.get_lines() if ln.get_linestyle() != "None"]
    assert len(data_lines) == 3 and len(model_lines) == 3
    assert len({tuple(ln.get_color()) for ln in data_lines}) == 3
    # exact data: the model residual is zero (relative: after the closed-form scale)
    m, res = plot.relative_residuals(tr, meas)
    assert np.nanmax(np.abs(res)) < 1e-9
    if quantity == "relative":
        assert "K = 7.3" in ax.get_title()


def test_comparison_with_polarization_groups(tr):
    n = 105
    pol = np.where(np.arange(n) % 2 == 0, 0.0, math.pi / 2)
    meas = _in_plane_measurement(tr, "bridf", pol=pol)
    fig, ax = plot.plot_comparison(tr, meas)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("⊥" in s for s in labels) and any("∥" in s for s in labels)
    _, res = plot.relative_residuals(tr, meas)
    assert np.nanmax(np.abs(res)) < 1e-9


def test_comparison_parity_fallback_and_residual_map(tr):
    rng = np.random.default_rng(1)
    ti = np.full(150, 0.5)
    tr_ = rng.uniform(0.05, 1.4, 150)
    ph = rng.uniform(0.3, 2.8, 150)
    v = tr.brdf(ti, tr_, ph) * (1 + 0.05 * rng.standard_normal(150))
    meas = Measurement(ti, tr_, ph, v, quantity="brdf")
    fig, ax = plot.plot_comparison(tr, meas)
    assert "parity" in ax.get_title()
    assert ax.get_xscale() == "log" and ax.get_legend() is not None
    fig, ax = plot.plot_residual_map(tr, meas)
    assert ax.get_xlabel() and ax.get_ylabel() and ax.get_legend() is not None
    assert len(fig.axes) == 2 and "model" in fig.axes[1].get_ylabel()
    assert "r.m.s." in ax.get_title()
    offsets = ax.collections[0].get_offsets()
    # the residual panels' axes are theta_r cos(phi), theta_r sin(phi) in degrees
    np.testing.assert_allclose(offsets[:, 0], np.degrees(tr_) * np.cos(ph))


def test_residual_map_on_noisy_data_and_channels(tr):
    meas = _in_plane_measurement(tr, "brdf", noise=0.1)
    two = Measurement(meas.theta_i, meas.theta_r, meas.phi,
                      np.column_stack([meas.values[:, 0], 2 * meas.values[:, 0]]),
                      channels=["red", "blue"], quantity="brdf")
    _, r0 = plot.relative_residuals(tr, two, channel="red")
    _, r1 = plot.relative_residuals(tr, two, channel=1)
    np.testing.assert_allclose(r1, 2 * r0 + 1)
    fig, ax = plot.plot_residual_map(tr, two, channel="blue")
    assert "[blue]" in ax.get_title()
    rms = float(np.sqrt(np.mean(r0 ** 2)))
    assert 0.05 < rms < 0.2


def test_best_scale():
    f = np.array([1.0, 2.0, 4.0])
    assert plot.best_scale(3.0 * f, f) == pytest.approx(3.0)
    assert plot.best_scale([1.0, np.nan], [0.0, 1.0]) == 1.0
    # minimizes sum((d - K f)/(K f))^2
    rng = np.random.default_rng(0)
    d = f * (2 + 0.3 * rng.standard_normal(3))
    k = plot.best_scale(d, f)

    def cost(kk):
        return float(np.sum(((d - kk * f) / (kk * f)) ** 2))

    assert cost(k) <= min(cost(k * 1.01), cost(k * 0.99))


def test_model_values_rejects_unknown_quantity(tr):
    with pytest.raises(ValueError, match="quantity"):
        plot.model_values(tr, 0.1, 0.2, 0.0, "radiance")


def test_best_scale_is_the_inverse_of_the_relative_scale():
    """plot uses the fit's convention (K x ~ f, roughbrdf.quantity.relative_scale); best_scale is
    the model-side factor 1/K."""
    from roughbrdf.quantity import relative_scale

    rng = np.random.default_rng(3)
    f = rng.uniform(0.5, 2.0, 20)
    d = 4.0 * f * (1 + 0.1 * rng.standard_normal(20))
    assert plot.best_scale(d, f) == pytest.approx(1.0 / relative_scale(d, f), rel=1e-14)


def test_comparison_through_an_aperture(tr):
    """With aperture= the curves and the residuals are the model averaged over the cone."""
    from roughbrdf.instrument import Aperture, aperture_average

    sharp = rb.model("trowbridge-reitz-1975", e=0.05, n=1.5, k=0.0, rho_L=0.01)
    ap = Aperture(math.radians(2.0), 7)
    meas = _in_plane_measurement(sharp, "bridf")
    fig, ax = plot.plot_comparison(sharp, meas, aperture=ap)
    assert "aperture 2°" in ax.get_title()
    line = [ln for ln in ax.get_lines() if ln.get_linestyle() != "None"][1]  # 30 deg
    x = np.radians(line.get_xdata())
    tr_, ph = rb.geometry.from_signed_angle(x)
    t = round(math.radians(30.0), 4)  # the plot's incidences are rounded (Measurement.incidences)
    want = aperture_average(sharp, t, tr_, ph, ap, quantity="bridf")
    np.testing.assert_allclose(line.get_ydata(), want, rtol=1e-8)  # x went through degrees
    plain = plot.model_values(sharp, t, tr_, ph, "bridf")
    assert np.max(want) < 0.9 * np.max(plain)  # the peak is read lower through the cone
    _, res = plot.relative_residuals(sharp, meas, aperture=ap)
    at = aperture_average(sharp, meas.theta_i, meas.theta_r, meas.phi, ap, quantity="bridf")
    np.testing.assert_allclose(res, meas.values[:, 0] / at - 1, rtol=1e-9, atol=1e-12)
    fig, ax = plot.plot_residual_map(sharp, meas, aperture=math.radians(2.0))
    assert "r.m.s." in ax.get_title()
