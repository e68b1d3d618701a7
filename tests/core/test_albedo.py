"""Directional-hemispherical reflectance ``rb.albedo``: accurate to 1e-4, also for e=0.05.

Oracles: the exact value 1/(1 + e^2) for the microfacet Trowbridge-Reitz model with F = 1 and
no shadowing at normal incidence (docs/models.md §3.7: the fraction of micro-area with
alpha < 45 deg), Lambert's rho, and independent brute-force quadratures.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from hypothesis_profiles import jit_disabled

import roughbrdf as rb

#: NUMBA_DISABLE_JIT=1 (make test-nojit): the kernels run as plain Python, 100 to 1000 times
#: slower; test_the_cached_rule_is_the_rule integrates a cheaper model on a smaller rule there
NOJIT = jit_disabled(os.environ)


def ggx_white(e):
    """TR/GGX microfacet with F = 1 (n=None) and no shadowing."""
    return rb.model("microfacet", distribution="trowbridge-reitz", alpha=e, n=None, k=None,
                    shadowing="none")


@pytest.mark.parametrize("e", [0.05, 0.1, 0.3, 0.68, 1.0, 2.0, 3.0])
def test_exact_oracle_normal_incidence(e):
    # theta_i = 0: albedo = ∫_{theta_h < 45 deg} D cos(theta_h) dω_h = 1/(1 + e^2)
    assert rb.albedo(ggx_white(e), 0.0) == pytest.approx(1 / (1 + e * e), abs=1e-5)


def test_sharp_lobe_tr75_matches_oracle_to_1e4():
    # the same for TR75 itself: Eq. 30 with R = 1 is the F = 1 microfacet form (§5.2); a lossless
    # mirror-like index is not available, so scale out R(0) at normal incidence for k = 0, n=1.5
    # at e = 0.05 the lobe is 3 deg wide; R(theta_d) varies by < 1e-4 over it
    m = rb.model("tr75", e=0.05, n=1.5, k=0.0, rho_L=0.0)
    r0 = 0.04
    assert rb.albedo(m, 0.0) / r0 == pytest.approx(1 / (1 + 0.05**2), abs=2e-3)


def _brute(model, theta_i):
    """Independent quadrature in the plain (theta_r, phi) grid: tensor Gauss-Legendre on many
    panels (vectorized), with a panel edge at theta_r = theta_i where the lobe peaks."""
    x, w = np.polynomial.legendre.leggauss(12)

    def nodes(edges):
        a, b = edges[:-1, None], edges[1:, None]
        return (0.5 * (b - a) * x + 0.5 * (a + b)).ravel(), (0.5 * (b - a) * w).ravel()

    t_edges = np.unique(np.concatenate([np.linspace(0, theta_i, 60),
                                        np.linspace(theta_i, math.pi / 2, 120)]))
    tr, wt = nodes(t_edges)
    ph, wp = nodes(np.linspace(0, math.pi, 240))
    f = model.bridf(theta_i, tr[:, None], ph[None, :])
    return float(2 * np.sum(f * np.sin(tr)[:, None] * wt[:, None] * wp[None, :]))


@pytest.mark.jit_heavy(reason="default albedo grid vs a brute-force one: minutes in plain Python")
@pytest.mark.parametrize("name, kw, theta_i", [
    ("trowbridge-reitz-1975", {"e": 0.68, "n": 1.0, "k": 0.9, "rho_L": 0.33}, math.radians(45)),
    ("torrance-sparrow-1967", {"g": 2.0, "c": 0.02, "n": 1.5, "rho_d": 0.3}, math.radians(30)),
    ("microfacet", {"alpha": 0.5, "n": 1.5, "k": 0.5}, math.radians(60)),
])
def test_against_brute_force_quadrature(name, kw, theta_i):
    m = rb.model(name, **kw)
    assert rb.albedo(m, theta_i) == pytest.approx(_brute(m, theta_i), abs=2e-5)


def test_sharp_lobe_off_normal_against_half_vector_quadrature():
    # e = 0.05 at theta_i = 40 deg. Oracle: the same integral in half-vector coordinates,
    # ∫ D(h) (w_i.h)/cos(theta_i) [w_r above the horizon] dω_h (F = 1, no G; dω_r = 4 (w_i.h) dω_h),
    # with theta_h on Gauss-Legendre panels graded around the 3-deg lobe; the horizon cut is
    # far out in the tail, where it is resolved by the fine azimuth grid.
    e, ti = 0.05, math.radians(40)
    x, w = np.polynomial.legendre.leggauss(30)
    edges = np.concatenate([[0.0], np.geomspace(1e-4, math.pi / 2, 80)])
    a, b = edges[:-1, None], edges[1:, None]
    th = (0.5 * (b - a) * x + 0.5 * (a + b)).ravel()
    wth = (0.5 * (b - a) * w).ravel()
    nphi = 4096
    ph = (np.arange(nphi) + 0.5) * 2 * math.pi / nphi
    TH, PH = np.meshgrid(th, ph, indexing="ij")
    h = np.stack([np.sin(TH) * np.cos(PH), np.sin(TH) * np.sin(PH), np.cos(TH)], -1)
    wi = np.array([-math.sin(ti), 0, math.cos(ti)])
    wih = h @ wi
    wrz = 2 * wih * h[..., 2] - wi[2]
    d = rb.distributions.trowbridge_reitz(np.cos(TH), e)
    integrand = np.where((wih > 0) & (wrz > 0), d * wih / math.cos(ti), 0.0) * np.sin(TH)
    oracle = float(np.sum(integrand * wth[:, None]) * 2 * math.pi / nphi)
    assert rb.albedo(ggx_white(e), ti) == pytest.approx(oracle, abs=1e-4)


def test_lambertian_exact_everywhere():
    lam = rb.model("lambertian", rho=0.37)
    t = np.radians(np.array([0.0, 10, 45, 80]))
    np.testing.assert_allclose(rb.albedo(lam, t), 0.37, atol=1e-12)
    # at grazing incidence the specular direction, the centre of the quadrature, lies on the
    # horizon; still well inside the required 1e-4
    np.testing.assert_allclose(rb.albedo(lam, np.radians([89.9, 90.0])), 0.37, atol=2e-5)


def test_sum_of_models_and_shapes():
    a = rb.model("tr75", e=0.3, n=1.2, k=0.5, rho_L=0.0)
    b = rb.model("lambertian", rho=0.2)
    t = np.radians(np.array([[0.0, 20], [50, 70]]))
    got = rb.albedo(a + b, t)
    assert got.shape == (2, 2)
    np.testing.assert_allclose(got, rb.albedo(a, t) + 0.2, atol=1e-12)
    assert isinstance(rb.albedo(b, 0.1), float)


def test_polarization():
    m = rb.model("tr75", e=0.4, n=1.5, k=0.2, rho_L=0.0)
    t = math.radians(50)
    un = rb.albedo(m, t)
    s, p = rb.albedo(m, t, polarization="s"), rb.albedo(m, t, polarization="p")
    assert 0.5 * (s + p) == pytest.approx(un, rel=1e-12)
    assert s > p  # R_s > R_p for a dielectric


@pytest.mark.jit_heavy(reason="albedos on the default grid: minutes in plain Python")
def test_energy_conservation_with_smith():
    # F = 1 with Smith height-correlated masking-shadowing: albedo <= 1 (single scattering
    # loses energy, it never creates it); near 1 for a smooth surface at normal incidence
    t = np.radians(np.array([0.0, 30, 60, 80, 89]))
    for a in (0.05, 0.3, 1.0):
        m = rb.model("microfacet", alpha=a, n=None, k=None, shadowing="smith")
        alb = rb.albedo(m, t)
        assert np.all(alb <= 1 + 1e-6)
    # at normal incidence the facets tilted beyond 45 deg reflect below the horizon, so even a
    # smooth surface keeps at most 1/(1 + e^2) (the oracle above); masking takes a little more
    smooth = rb.model("microfacet", alpha=0.05, n=None, k=None, shadowing="smith")
    assert 0.99 < rb.albedo(smooth, 0.0) <= 1 / (1 + 0.05**2)


def test_invalid_incidence_raises():
    with pytest.raises(ValueError, match="theta_i"):
        rb.albedo(rb.model("tr75"), math.pi / 2)  # TR75 divides by cos(theta_i)
    with pytest.raises(ValueError, match=r"theta_i.*-0\.1"):
        rb.albedo(rb.model("lambertian"), -0.1)


def test_the_cached_rule_is_the_rule():
    # integrate._quadrature caches grids up to CACHED_SAMPLES (every fit's plausibility check
    # integrates at the same ten incidences): the cached grid gives the albedo of the grid
    # built afresh to the last bits, a second call the same, and other incidences their own
    # Without the JIT (plain Python: 300 s and more with the coated model) a microfacet model
    # on a 32 x 6 x 6 rule, and for the grid above the cap a Lambertian at 4 incidences x
    # n_psi = 1024 (1.2e6 samples): the same caching code, the same checks.
    from roughbrdf import integrate

    if NOJIT:
        model, rule = rb.model("microfacet", alpha=0.3, n=1.5), dict(n_psi=32, n_panels=6,
                                                                      order=6)
        big_model, big_theta, big_psi = rb.model("lambertian", rho=0.4), [0, 30, 60, 85], 1024
    else:
        model, rule = rb.model("coated", n=1.5, rho=0.4, alpha=0.08), {}
        big_model, big_theta, big_psi = model, np.arange(0.0, 89.0, 5.0), 512
    n_psi, n_panels, order = (rule or dict(n_psi=256, n_panels=24, order=12)).values()
    theta = np.radians([0.0, 40.0, 85.0])
    integrate._quadrature_cached.cache_clear()
    first = rb.albedo(model, theta, **rule)
    assert integrate._quadrature_cached.cache_info().currsize == 1
    again = rb.albedo(model, theta, **rule)
    theta_r, phi, sin_rho, rho_max, w = integrate._build_quadrature(theta.tobytes(), n_psi,
                                                                    n_panels, order)
    fresh = (model.brdf(theta[:, None, None], theta_r, phi) * np.cos(theta_r) * sin_rho
             * rho_max * w).sum(axis=(1, 2)) * (2 * math.pi / n_psi)
    np.testing.assert_array_equal(first, again)
    np.testing.assert_allclose(first, fresh, rtol=1e-12)  # brdf*cos vs brdf_cos: rounding
    other = rb.albedo(model, np.radians([0.0, 41.0, 85.0]), **rule)
    assert other[0] == first[0] and other[2] == first[2] and other[1] != first[1]
    # a grid above the cap is built each time and not kept
    integrate._quadrature_cached.cache_clear()
    assert len(big_theta) * big_psi * 24 * 12 > integrate.CACHED_SAMPLES
    big = rb.albedo(big_model, np.radians(big_theta), n_psi=big_psi)
    assert integrate._quadrature_cached.cache_info().currsize == 0
    assert np.all((big > 0) & (big < 1))
    parts = integrate._quadrature(theta.tobytes(), n_psi, n_panels, order)
    assert not any(a.flags.writeable for a in parts)  # shared by every call: read-only
