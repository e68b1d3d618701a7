"""Coated materials and rough diffuse reflection (docs/models.md §10).

The new terms are tested the way the published models are (tests/models/test_invariants.py,
tests/models/test_ts67.py, tests/models/test_tr75.py, tests/core/test_albedo.py). Where the
expected numbers come from:

* hemispherical Fresnel reflectance ``F_dr`` (§10.1): a composite Gauss-Legendre quadrature of
  ``rb.fresnel.reflectance`` written here (total internal reflection exact: ``R = 1`` below the
  critical cosine, a square-root substitution above it), and the closed form of the
  hemispherical reflectance of a dielectric for isotropic light (Stern 1964), which agrees with
  that quadrature to 1e-14;
* Oren-Nayar (§10.2): a NumPy transcription of Oren & Nayar 1994 Eq. 30 written here, and the
  directional albedo of Eq. 30 integrated in closed form here (derivation at :func:`on_albedo`,
  checked against a quadrature with panel edges on the integrand's kinks);
* coated (§10.3): a NumPy transcription of the formula in ``coated.py``'s module notes built from
  the public ``rb.distributions``, ``rb.shadowing`` and ``rb.fresnel`` functions; identities
  (``rho = 0`` is the microfacet model, each extra lobe adds one microfacet lobe, the energy
  identity of the substrate term); reciprocity and symmetry as for every model.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest
from hypothesis_profiles import jit_disabled

import roughbrdf as rb
from roughbrdf.errors import ArgumentError

HALF_PI = math.pi / 2
#: NUMBA_DISABLE_JIT=1 (make test-nojit): the kernels run as plain Python (100 to 1000 times
#: slower); the identities on thousands of random geometries take a few hundred there (the
#: same identities, the same tolerances)
NOJIT = jit_disabled(os.environ)
TI_MAX = float(np.nextafter(HALF_PI, 0.0))  # the coated and Oren-Nayar models need theta_i < pi/2


def _geometry(n: int, seed: int, top: float = 1.5):
    rng = np.random.default_rng(seed)
    return rng.uniform(0, top, n), rng.uniform(0, top, n), rng.uniform(-math.pi, math.pi, n)


# ------------------------------------------------------------------------------------------
# §10.1 hemispherical (diffuse) Fresnel reflectance
# ------------------------------------------------------------------------------------------
def _gl_panels(a: float, b: float, panels: int, order: int = 20):
    x, w = np.polynomial.legendre.leggauss(order)
    e = np.linspace(a, b, panels + 1)
    lo, hi = e[:-1, None], e[1:, None]
    return (0.5 * (hi - lo) * x + 0.5 * (hi + lo)).ravel(), (0.5 * (hi - lo) * w).ravel()


def fdr_quadrature(n: float, k: float = 0.0) -> float:
    """``F_dr = 2 ∫_0^1 R(mu) mu dmu`` by composite Gauss-Legendre (200 panels x 20 points).

    For a dielectric seen from the dense side (``n < 1``, ``k = 0``) ``R = 1`` exactly below the
    critical cosine ``mu_c = sqrt(1 - n^2)`` (contributing ``mu_c^2``); above it ``R`` has a
    square-root edge at ``mu_c``, removed by ``mu = mu_c + (1 - mu_c) s^2``.
    """
    if n < 1.0 and k == 0.0:
        mu_c = math.sqrt(1.0 - n * n)
        s, w = _gl_panels(0.0, 1.0, 200)
        mu = mu_c + (1.0 - mu_c) * s * s
        jac = 2.0 * (1.0 - mu_c) * s
        r = rb.fresnel.reflectance(mu, n, 0.0)
        return mu_c**2 + 2.0 * float(np.sum(w * jac * r * mu))
    mu, w = _gl_panels(0.0, 1.0, 200)
    return 2.0 * float(np.sum(w * rb.fresnel.reflectance(mu, n, k) * mu))


def fdr_closed_form(n: float) -> float:
    """Hemispherical reflectance of a dielectric (``n > 1``) for isotropic incident light, in
    closed form (F. Stern, Appl. Opt. 3, 111 (1964)); test_fdr_closed_form_is_the_quadrature
    checks it against :func:`fdr_quadrature`."""
    n2, n4 = n * n, n**4
    return (0.5 + (n - 1) * (3 * n + 1) / (6 * (n + 1) ** 2)
            + n2 * (n2 - 1) ** 2 / (n2 + 1) ** 3 * math.log((n - 1) / (n + 1))
            - 2 * n**3 * (n2 + 2 * n - 1) / ((n2 + 1) * (n4 - 1))
            + 8 * n4 * (n4 + 1) / ((n2 + 1) * (n4 - 1) ** 2) * math.log(n))


DIELECTRICS = [1.05, 1.33, 1.5, 1.7, 2.0, 2.5, 4.0]


@pytest.mark.parametrize("n", DIELECTRICS)
def test_fdr_closed_form_is_the_quadrature(n):
    # the two oracles agree with each other before either is used on the library
    assert fdr_closed_form(n) == pytest.approx(fdr_quadrature(n), abs=1e-14)


@pytest.mark.parametrize("n", DIELECTRICS)
def test_fdr_external_dielectric(n):
    got = rb.fresnel.diffuse_reflectance(n)
    assert got == pytest.approx(fdr_quadrature(n), abs=1e-13)
    assert got == pytest.approx(fdr_closed_form(n), abs=1e-13)


@pytest.mark.parametrize("n, k", [(1.5, 0.3), (0.5, 2.0), (0.2, 3.0), (1.0, 0.9), (2.5, 0.01)])
def test_fdr_external_absorbing(n, k):
    assert rb.fresnel.diffuse_reflectance(n, k) == pytest.approx(fdr_quadrature(n, k), abs=1e-12)


@pytest.mark.parametrize("n", DIELECTRICS)
def test_fdr_internal_is_direct_quadrature_at_inverse_index(n):
    # light inside the coating meets the interface with relative index 1/n; the direct
    # quadrature includes total internal reflection beyond the critical angle
    assert rb.fresnel.diffuse_reflectance(n, internal=True) == pytest.approx(
        fdr_quadrature(1.0 / n), abs=1e-12)


def test_fdr_known_values():
    # n = 1.5: 0.0918 external (docs/models.md §10.1; the quadrature and Stern's closed form
    # above give 0.091778), 0.5964 internal (1 - (1 - 0.091778)/2.25 = 0.596346)
    assert rb.fresnel.diffuse_reflectance(1.5) == pytest.approx(0.0918, abs=5e-5)
    assert fdr_quadrature(1.5) == pytest.approx(0.091778, abs=5e-7)
    assert rb.fresnel.diffuse_reflectance(1.5, internal=True) == pytest.approx(0.596346, abs=5e-7)
    # index matched: no interface, nothing reflected
    assert rb.fresnel.diffuse_reflectance(1.0) == pytest.approx(0.0, abs=1e-15)
    assert rb.fresnel.diffuse_reflectance(1.0, internal=True) == pytest.approx(0.0, abs=1e-15)


def test_fdr_stokes_identity_between_the_two_sides():
    # 1 - F_int(n) = (1 - F_ext(n))/n^2 (docs/models.md §10.1), with both sides computed by the
    # direct quadrature (the inside one is the external reflectance at index 1/n)
    for n in DIELECTRICS:
        assert 1 - fdr_quadrature(1 / n) == pytest.approx((1 - fdr_quadrature(n)) / n**2,
                                                          abs=1e-12)


@pytest.mark.parametrize("n", [0.8, 1 / 1.5])
def test_fdr_external_from_the_dense_side(n):
    # n < 1, k = 0: R(mu) has the total-internal-reflection edge at mu_c = sqrt(1 - n^2),
    # which a Gauss-Legendre rule misses (it was 2.8e-3 low at n = 0.8); the code uses
    # F_dr(n) = 1 - n^2 (1 - F_dr(1/n)) there, checked against the direct quadrature
    assert rb.fresnel.diffuse_reflectance(n) == pytest.approx(fdr_quadrature(n), abs=1e-10)


def test_fdr_invalid_arguments():
    with pytest.raises(ValueError, match="k = 0"):
        rb.fresnel.diffuse_reflectance(1.5, 0.1, internal=True)
    for bad in (0.0, -1.5, math.nan, math.inf):
        with pytest.raises(ValueError, match="n must be"):
            rb.fresnel.diffuse_reflectance(bad)
    with pytest.raises(ValueError, match="k must be"):
        rb.fresnel.diffuse_reflectance(1.5, -0.1)


# ------------------------------------------------------------------------------------------
# §10.2 Oren-Nayar (1994) Eq. 30
# ------------------------------------------------------------------------------------------
def on_ab(sigma: float) -> tuple[float, float]:
    s2 = sigma * sigma
    return 1 - 0.5 * s2 / (s2 + 0.33), 0.45 * s2 / (s2 + 0.09)


def on_eq30(ti, tr, phi, rho, sigma):
    """Oren & Nayar 1994 Eq. 30 transcribed: ``rho/pi (A + B max(0, cos(phi_r - phi_i))
    sin(alpha) tan(beta))``, ``alpha = max(theta_i, theta_r)``, ``beta = min(...)``. The source
    lies at ``phi = pi`` (docs/models.md §1.1), so ``phi_r - phi_i = phi - pi`` and
    ``cos(phi_r - phi_i) = -cos(phi)``."""
    a_, b_ = on_ab(sigma)
    alpha, beta = np.maximum(ti, tr), np.minimum(ti, tr)
    c = np.maximum(0.0, -np.cos(phi))
    return rho / np.pi * (a_ + b_ * c * np.sin(alpha) * np.tan(beta))


def on_albedo(ti, sigma):
    """Directional albedo of Eq. 30 per unit rho, integrated by hand.

    ``∫ max(0, -cos phi) dphi = 2``; for ``theta_r < theta_i`` the factor is
    ``sin(theta_i) tan(theta_r)`` and ``∫_0^ti sin^2 = ti/2 - sin(2 ti)/4``; for
    ``theta_r > theta_i`` it is ``sin(theta_r) tan(theta_i)`` and
    ``∫_ti^{pi/2} sin^2 cos = (1 - sin^3 ti)/3``. So
    ``A + (2B/pi) [sin ti (ti/2 - sin(2ti)/4) + tan ti (1 - sin^3 ti)/3]``, which is ``A`` at
    normal incidence and tends to ``A + B/2`` at grazing incidence.
    """
    a_, b_ = on_ab(sigma)
    s = np.sin(ti)
    return a_ + 2 * b_ / np.pi * (s * (ti / 2 - np.sin(2 * ti) / 4) + np.tan(ti) * (1 - s**3) / 3)


def _brute_albedo_kinks(model, theta_i):
    """Albedo by tensor Gauss-Legendre in (theta_r, phi) with panel edges on Eq. 30's kinks
    (theta_r = theta_i, phi = pi/2): exact to rounding for the piecewise-smooth integrand."""
    x, w = np.polynomial.legendre.leggauss(20)

    def nodes(edges):
        a, b = edges[:-1, None], edges[1:, None]
        return (0.5 * (b - a) * x + 0.5 * (a + b)).ravel(), (0.5 * (b - a) * w).ravel()

    tr, wt = nodes(np.unique(np.concatenate([np.linspace(0, theta_i, 12),
                                             np.linspace(theta_i, HALF_PI, 12)])))
    ph, wp = nodes(np.linspace(0, math.pi, 5))
    f = model.bridf(theta_i, tr[:, None], ph[None, :])
    return float(2 * np.sum(f * np.sin(tr)[:, None] * wt[:, None] * wp[None, :]))


SIGMAS = [0.05, 0.2, 0.4, 0.8, 1.2]


def test_oren_nayar_sigma_zero_is_lambertian_exactly():
    ti, tr, ph = _geometry(500, 1)
    tr[:5] = [0.0, HALF_PI, 0.3, 1.0, HALF_PI]
    for rho in (0.0, 0.37, 1.0):
        on = rb.model("oren-nayar", rho=rho, sigma=0.0)
        lam = rb.model("lambertian", rho=rho)
        np.testing.assert_array_equal(on.brdf(ti, tr, ph), lam.brdf(ti, tr, ph))
        np.testing.assert_array_equal(on.brdf(ti, tr, ph), rho / math.pi)
    assert rb.diffuse.oren_nayar(0.3, 0.2, 1.0, 0.0) == 1.0


@pytest.mark.parametrize("sigma", SIGMAS)
def test_oren_nayar_is_eq30(sigma):
    ti, tr, ph = _geometry(2000, 2)
    m = rb.model("oren-nayar", rho=0.7, sigma=sigma)
    expected = on_eq30(ti, tr, ph, 0.7, sigma)
    np.testing.assert_allclose(m.brdf(ti, tr, ph), expected, rtol=1e-13)
    np.testing.assert_allclose(m.bridf(ti, tr, ph), expected * np.cos(tr), rtol=1e-13)
    np.testing.assert_allclose(m.evaluate(ti, tr, ph, quantity="brdf_cos"),
                               expected * np.cos(tr), rtol=1e-13)
    # the NumPy front end of the factor alone
    np.testing.assert_allclose(rb.diffuse.oren_nayar(ti, tr, ph, sigma),
                               expected * np.pi / 0.7, rtol=1e-13)


def test_oren_nayar_phi_mapping():
    # phi = pi is the source side (retro): cos(phi_r - phi_i) = 1, the full B term; phi = 0
    # (forward) and phi = +-pi/2 give A alone (docs/models.md §10.2)
    sigma, ti, tr = 0.5, 0.5, 0.5
    a_, b_ = on_ab(sigma)
    m = rb.model("oren-nayar", rho=1.0, sigma=sigma)

    def factor(ph):
        return math.pi * m.brdf(ti, tr, ph)  # rho = 1: pi brdf is the factor

    assert factor(math.pi) == pytest.approx(a_ + b_ * math.sin(0.5) * math.tan(0.5), rel=1e-14)
    assert factor(math.pi) == pytest.approx(0.87114, abs=5e-6)  # the docstring's value
    for ph in (0.0, HALF_PI, -HALF_PI, 0.3):
        assert factor(ph) == pytest.approx(a_, rel=1e-14)
    # brighter toward the source, and the TR75-frame retro direction is the same point
    assert m.brdf(0.6, 0.6, math.pi) > m.brdf(0.6, 0.6, 0.0)


def test_oren_nayar_reciprocity_symmetry_non_negative():
    ti, tr, ph = _geometry(3000, 3, TI_MAX)
    for sigma in SIGMAS:
        m = rb.model("oren-nayar", rho=0.9, sigma=sigma)
        f = m.brdf(ti, tr, ph)
        np.testing.assert_allclose(m.brdf(tr, ti, ph), f, rtol=1e-13)
        assert np.all(rb.reciprocity_error(m, ti, tr, ph) < 1e-13)
        np.testing.assert_array_equal(m.brdf(ti, tr, -ph), f)
        np.testing.assert_allclose(m.brdf(ti, tr, 2 * math.pi - ph), f, rtol=1e-13)
        assert np.all(f >= 0) and np.all(np.isfinite(f))


def test_oren_nayar_special_geometries():
    m = rb.model("oren-nayar", rho=0.8, sigma=0.6)
    ti = np.array([0.0, 0.0, 0.3, 0.3, 1.2, 1.2, 1.5, TI_MAX])
    tr = np.array([0.0, HALF_PI, 0.3, HALF_PI, 1.2, HALF_PI, HALF_PI, 0.7])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for ph in (0.0, math.pi, -math.pi, HALF_PI):
            f = m.brdf(ti, tr, ph)
            assert np.all(np.isfinite(f)) and np.all(f >= 0)
    # on the horizon the BRIDF is exactly 0 (cos theta_r = 0, docs/models.md §1.1), and the BRDF
    # there is the limit from above
    assert m.bridf(0.3, HALF_PI, math.pi) == 0.0
    assert m.brdf(0.3, HALF_PI, math.pi) == pytest.approx(m.brdf(0.3, HALF_PI - 1e-9, math.pi),
                                                          rel=1e-8)
    with pytest.raises(ValueError, match="theta_i"):
        m.brdf(HALF_PI, 0.3, 0.0)  # tan(beta) diverges with both directions grazing
    with pytest.raises(ValueError, match="sigma"):
        rb.diffuse.oren_nayar(0.3, 0.2, 1.0, -0.1)


@pytest.mark.parametrize("sigma", [0.2, 1.2])
def test_oren_nayar_albedo_closed_form(sigma):
    m = rb.model("oren-nayar", rho=1.0, sigma=sigma)
    t = np.radians([0.0, 30, 60, 85, 89.9])
    exact = on_albedo(t, sigma)
    # the closed form against a quadrature that has panel edges on the kinks ...
    brute = [_brute_albedo_kinks(m, x) for x in t]
    np.testing.assert_allclose(brute, exact, atol=1e-13)
    # ... and rb.albedo, whose specular-centred grid crosses the kinks (theta_r = theta_i,
    # phi = pi/2) obliquely: measured 6e-5 at 60 deg and 5e-4 at 89.9 deg, not its 1e-5
    np.testing.assert_allclose(rb.albedo(m, t), exact, atol=1e-3)
    assert rb.albedo(m, 0.0) == pytest.approx(on_ab(sigma)[0], abs=1e-12)  # A at normal


def test_oren_nayar_albedo_and_rho():
    # albedo <= rho for theta_i up to 60 deg for every sigma (closed form, fine sigma grid);
    # Eq. 30 is not energy conserving beyond: at grazing incidence the albedo tends to
    # rho (A + B/2), at most 1.0152 rho (sigma = 0.199 rad) -- a property of the published
    # qualitative model, not of the code (docs/models.md §10.2)
    s = np.linspace(0.0, 1.2, 2401)[:, None]
    t = np.radians(np.arange(0.0, 60.01, 2.5))[None, :]
    assert np.all(on_albedo(t, s) <= 1.0 + 1e-12)
    a_, b_ = on_ab(s)
    graze = a_ + b_ / 2
    assert graze.max() == pytest.approx(1.01518, abs=1e-5)
    assert s[np.argmax(graze), 0] == pytest.approx(0.1985, abs=1e-3)
    # without the JIT every other sigma (0.05, 0.4, 1.2; 60 s for all five in plain Python)
    for sigma in SIGMAS[::2] if NOJIT else SIGMAS:
        m = rb.model("oren-nayar", rho=0.6, sigma=sigma)
        alb = rb.albedo(m, np.radians([0.0, 20, 40, 60]))
        assert np.all(alb <= 0.6 + 1e-5)
        assert np.all(alb >= 0.6 * 0.5)  # A >= 1/2
    near = rb.albedo(rb.model("oren-nayar", rho=1.0, sigma=0.2), np.radians(89.9))
    assert near > 1.01  # the published model's excess, reproduced


# ------------------------------------------------------------------------------------------
# §10.3 the coated model: the formula, transcribed from coated.py's module notes
# ------------------------------------------------------------------------------------------
def coated_numpy(ti, tr, ph, p, *, distribution="trowbridge-reitz", shadowing="smith-separable",
                 lobes=1, diffuse="lambertian", shadow_diffuse=True, polarization=None):
    """``F(theta_d)/(4 cos i cos r) sum_j w_j D_j G_j + [G_1] base rho/pi (1 - R(theta_i))
    (1 - R(theta_r)) s(theta_i) s(theta_r) / (n^2 (1 - rho F_dr,int))``, from the library's
    public parts: ``w_j`` the lobe weights (``p["ks"...]``: the free scales of
    ``weights="free"``, ``s = 1``), ``s = min(1, (1 - sum_j w_j E_j)/(1 - R))`` the smooth
    interface's limit (``rb.diffuse.lobe_albedo``, ``smooth=True``), linear in ``cos`` between
    its 64 nodes."""
    n, rho = p["n"], p["rho"]
    ci, cr = np.cos(ti), np.cos(tr)
    th = rb.geometry.theta_h(ti, tr, ph)
    td = rb.geometry.theta_d(ti, tr, ph)
    eta = rb.geometry.tr75_eta(ti, tr, ph)
    f = rb.fresnel.reflectance(np.cos(td), n, 0.0, polarization or "unpolarized", eta=eta)
    spec = 0.0
    free = "ks" in p
    weights = ([p["ks" + ("" if j == 1 else str(j))] for j in range(1, lobes + 1)] if free
               else rb.models.coated.lobe_weights(lobes, p.get("w2", 0.0), p.get("w3", 0.0)))
    for j in range(1, lobes + 1):
        sfx = "" if j == 1 else str(j)
        a, ks = p["alpha" + sfx], weights[j - 1]
        d = rb.distributions.evaluate(distribution, np.cos(th), a)
        g = rb.shadowing.smith(ti, tr, a, distribution, shadowing)
        spec = spec + ks * d * g
    spec = f * spec / (4 * ci * cr)
    r_i = rb.fresnel.reflectance(ci, n, 0.0, polarization or "unpolarized")  # eta = 0
    r_r = rb.fresnel.reflectance(cr, n, 0.0)  # unpolarized detector
    fdr_int = rb.fresnel.diffuse_reflectance(n, internal=True)
    diff = rho / np.pi * (1 - r_i) * (1 - r_r) / (n * n * (1 - rho * fdr_int))
    if not free:
        mu = np.linspace(0.0, 1.0, 64)  # the kernel interpolates as if node 0 were at 0
        # (the model's albedo is the rule's, interpolated smoothly in alpha and n)
        e = sum(w * rb.diffuse.lobe_albedo(
            p["alpha" + ("" if j == 1 else str(j))], n, distribution, shadowing, smooth=True)
            for j, w in enumerate(weights, 1) if w > 0)
        t = 1 - rb.fresnel.reflectance(rb.diffuse.TABLE_NODES, n)
        s = np.minimum(1.0, (1 - e) / t)
        s[0] = s[1]
        diff = diff * np.interp(ci, mu, s) * np.interp(cr, mu, s)
    if diffuse == "oren-nayar":
        diff = diff * on_eq30(ti, tr, ph, np.pi, p["sigma"])  # the factor (rho/pi = 1)
        if not free:  # limited to what it receives: Eq. 30's albedo where it exceeds 1
            diff = diff / on_cap(ti, tr, p["sigma"])
    if shadow_diffuse:
        diff = diff * rb.shadowing.smith(ti, tr, p["alpha"], distribution, shadowing)
    return spec + diff


def on_cap(ti, tr, sigma):
    """``max(1, albedo(theta_i), albedo(theta_r))`` of Eq. 30 per unit rho (:func:`on_albedo`):
    what the coated substrate's Oren-Nayar factor is divided by (weights="partition")."""
    ti, tr = np.broadcast_arrays(np.asarray(ti, float), np.asarray(tr, float))
    sig = np.full_like(ti, sigma)
    return np.maximum(1.0, np.maximum(on_albedo(ti, sig), on_albedo(tr, sig)))


def _random_params(rng, lobes, diffuse):
    p = {"n": rng.uniform(1.1, 2.4), "rho": rng.uniform(0.0, 1.0)}
    for j in range(1, lobes + 1):
        sfx = "" if j == 1 else str(j)
        p["alpha" + sfx] = float(np.exp(rng.uniform(math.log(0.05), math.log(1.0))))
        if j > 1:
            p["w" + sfx] = float(rng.uniform(0.0, 1.0))
    if diffuse == "oren-nayar":
        p["sigma"] = rng.uniform(0.0, 1.0)
    return p


OPTION_SETS = [
    {},
    {"distribution": "beckmann"},
    {"shadowing": "smith-height-correlated"},
    {"lobes": 2},
    {"lobes": 3, "distribution": "beckmann", "shadowing": "smith-height-correlated"},
    {"diffuse": "oren-nayar"},
    {"shadow_diffuse": False},
    {"lobes": 2, "diffuse": "oren-nayar", "shadow_diffuse": False, "distribution": "beckmann"},
]
OPTION_IDS = ["-".join(f"{k}={v}" for k, v in o.items()) or "defaults" for o in OPTION_SETS]


@pytest.fixture(params=range(len(OPTION_SETS)), ids=OPTION_IDS, scope="module")
def coated_case(request):
    opts = OPTION_SETS[request.param]
    rng = np.random.default_rng(100 + request.param)
    p = _random_params(rng, opts.get("lobes", 1), opts.get("diffuse", "lambertian"))
    return rb.model("coated", **opts, **p), opts, p


@pytest.mark.parametrize("pol", [None, "s", "p", 0.7])
def test_coated_is_the_formula(coated_case, pol):
    m, opts, p = coated_case
    ti, tr, ph = _geometry(1500, 4)
    expected = coated_numpy(ti, tr, ph, p, polarization=pol, **opts)
    np.testing.assert_allclose(m.brdf(ti, tr, ph, polarization=pol), expected, rtol=1e-11)
    np.testing.assert_allclose(m.evaluate(ti, tr, ph, quantity="brdf_cos", polarization=pol),
                               expected * np.cos(tr), rtol=1e-11)


def test_coated_readme_example():
    # the brief's example: two lobes (alpha 0.05/0.3, lobe 2's share w2 = 0.2 by default),
    # rho = 0.6
    m = rb.model("coated", lobes=2, rho=0.6)
    p = {**m.params}
    assert p == {"n": 1.5, "rho": 0.6, "alpha": 0.05, "alpha2": 0.3, "w2": 0.2}
    got = m.brdf(0.3, 0.2, 1.0)
    assert got == pytest.approx(float(coated_numpy(0.3, 0.2, 1.0, p, lobes=2)), rel=1e-12)
    assert isinstance(got, float)


@pytest.mark.parametrize("distribution", ["trowbridge-reitz", "beckmann"])
@pytest.mark.parametrize("shadowing", ["smith-separable", "smith-height-correlated"])
def test_specular_part_is_the_microfacet_model(distribution, shadowing):
    # rho = 0 leaves the lobe: ks F D G/(4 cos i cos r) with F of n + 0i (docs/models.md §8);
    # 300 geometries without the JIT (Beckmann: 36 s a case with 3000 in plain Python)
    ti, tr, ph = _geometry(300 if NOJIT else 3000, 5, TI_MAX)
    ph[:3] = [0.0, math.pi, 0.0]
    tr[:3] = [ti[0], ti[1], HALF_PI]
    for alpha, n, ks in [(0.05, 1.5, 1.0), (0.3, 2.2, 0.7), (1.2, 1.05, 3.0)]:
        kw = {"distribution": distribution, "shadowing": shadowing, "alpha": alpha}
        # one lobe has weight 1 (ks = 1); weights="free" keeps the old free scale
        coat = rb.model("coated", n=n, rho=0.0, **kw) if ks == 1.0 else rb.model(
            "coated", n=n, rho=0.0, weights="free", ks=ks, **kw)
        mf = rb.model("microfacet", n=n, k=0.0, ks=ks, **kw)
        for pol in (None, "s", "p", 1.1):
            np.testing.assert_allclose(coat.brdf(ti, tr, ph, pol), mf.brdf(ti, tr, ph, pol),
                                       rtol=1e-13, atol=1e-300)
            np.testing.assert_allclose(coat.bridf(ti, tr, ph, pol), mf.bridf(ti, tr, ph, pol),
                                       rtol=1e-13, atol=1e-300)


def test_each_lobe_is_one_microfacet_lobe():
    # the lobes share the interface n: coated(lobes=2, rho=0) = mf(alpha, ks) + mf(alpha2, ks2),
    # and with the substrate, coated(lobes=j) = coated(lobes=1) + the extra microfacet lobes
    # (the substrate is shadowed by the first lobe in both)
    # (weights="free": the free scales add; the partition of unity is tested below);
    # 300 geometries without the JIT (37 s with 2000 in plain Python)
    ti, tr, ph = _geometry(300 if NOJIT else 2000, 6, TI_MAX)
    base = {"n": 1.6, "alpha": 0.08, "ks": 0.6, "weights": "free"}
    extra = [{"alpha": 0.35, "ks": 0.3}, {"alpha": 0.9, "ks": 0.1}]
    for dist_name in ("trowbridge-reitz", "beckmann"):
        o = {"distribution": dist_name, "shadowing": "smith-separable"}
        mfs = [rb.model("microfacet", n=1.6, k=0.0, **o, **e) for e in extra]
        two = rb.model("coated", lobes=2, rho=0.0, alpha2=0.35, ks2=0.3, **o, **base)
        one = rb.model("coated", lobes=1, rho=0.0, **o, **base)
        np.testing.assert_allclose(two.brdf(ti, tr, ph),
                                   one.brdf(ti, tr, ph) + mfs[0].brdf(ti, tr, ph), rtol=1e-13,
                                   atol=1e-300)  # denormal tails
        mf1 = rb.model("microfacet", n=1.6, k=0.0, **o, alpha=0.08, ks=0.6)
        np.testing.assert_allclose(two.brdf(ti, tr, ph),
                                   (mf1 + mfs[0]).brdf(ti, tr, ph), rtol=1e-13, atol=1e-300)
        for diffuse, sd in [("lambertian", True), ("oren-nayar", False)]:
            kw = {**o, **base, "rho": 0.7, "diffuse": diffuse, "shadow_diffuse": sd}
            if diffuse == "oren-nayar":
                kw["sigma"] = 0.4
            three = rb.model("coated", lobes=3, alpha2=0.35, ks2=0.3, alpha3=0.9, ks3=0.1, **kw)
            one = rb.model("coated", lobes=1, **kw)
            np.testing.assert_allclose(
                three.brdf(ti, tr, ph),
                one.brdf(ti, tr, ph) + mfs[0].brdf(ti, tr, ph) + mfs[1].brdf(ti, tr, ph),
                rtol=1e-13, atol=1e-300)
        # the partition of unity: lobe weights 1 - w2 and w2
        part = rb.model("coated", lobes=2, rho=0.0, alpha2=0.35, w2=0.3, n=1.6, alpha=0.08,
                        **o)
        mf1 = rb.model("microfacet", n=1.6, k=0.0, **o, alpha=0.08, ks=0.7)
        np.testing.assert_allclose(part.brdf(ti, tr, ph), (mf1 + mfs[0]).brdf(ti, tr, ph),
                                   rtol=1e-13, atol=1e-300)


def test_lambertian_and_oren_nayar_substrates():
    ti, tr, ph = _geometry(1000, 7, TI_MAX)
    kw = {"n": 1.4, "rho": 0.8, "ks": 0.0, "weights": "free"}  # the substrate alone
    lam = rb.model("coated", **kw)
    # sigma = 0 is the Lambertian substrate exactly
    np.testing.assert_array_equal(rb.model("coated", diffuse="oren-nayar", sigma=0.0, **kw)
                                  .brdf(ti, tr, ph), lam.brdf(ti, tr, ph))
    # otherwise the substrate term is multiplied by Eq. 30's factor
    on = rb.model("coated", diffuse="oren-nayar", sigma=0.5, **kw)
    np.testing.assert_allclose(on.brdf(ti, tr, ph) / lam.brdf(ti, tr, ph),
                               on_eq30(ti, tr, ph, np.pi, 0.5), rtol=1e-13)


# ------------------------------------------------------------------------------------------
# energy
# ------------------------------------------------------------------------------------------
INCIDENCES = np.radians([0.0, 15, 30, 45, 60, 70, 80, 85, 88, 89.5, 89.9])


@pytest.mark.jit_heavy(reason="coated albedos on the default grid: over 5 min in plain Python")
@pytest.mark.parametrize("n", [1.05, 1.5, 2.5])
def test_energy_identity_of_the_substrate(n):
    # ks = 0, no diffuse shadowing: all light refracted into the coating comes back out when
    # rho = 1, so the albedo is 1 - R(theta_i) (docs/models.md §10.3); for rho < 1 the series of
    # internal reflections gives (1 - R) rho (1 - F_int)/(1 - rho F_int), since
    # ∫ (1 - R(theta_r)) cos theta_r dω/pi = 1 - F_ext = n^2 (1 - F_int)
    # (weights="free" switches the lobe off: the smooth interface's own formula)
    m = rb.model("coated", n=n, rho=1.0, ks=0.0, shadow_diffuse=False, weights="free")
    r = rb.fresnel.reflectance(np.cos(INCIDENCES), n)
    np.testing.assert_allclose(rb.albedo(m, INCIDENCES), 1 - r, atol=1e-8)
    for pol in ("s", "p"):
        r_pol = rb.fresnel.reflectance(np.cos(INCIDENCES), n, 0.0, pol)
        np.testing.assert_allclose(rb.albedo(m, INCIDENCES, polarization=pol), 1 - r_pol,
                                   atol=1e-8)
    f_int = rb.fresnel.diffuse_reflectance(n, internal=True)
    for rho in (0.2, 0.7):
        m = m.with_params(rho=rho)
        np.testing.assert_allclose(rb.albedo(m, INCIDENCES),
                                   (1 - r) * rho * (1 - f_int) / (1 - rho * f_int), atol=1e-8)
    # the same with the two lobes of lobes=2 switched off
    two = rb.model("coated", lobes=2, n=n, rho=1.0, ks=0.0, ks2=0.0, shadow_diffuse=False,
                   weights="free")
    np.testing.assert_allclose(rb.albedo(two, INCIDENCES), 1 - r, atol=1e-8)


@pytest.mark.jit_heavy(reason="coated albedos on the default grid, 8 option sets x 3 draws and 12 "
                       "lobes: over 5 min in plain Python")
def test_albedo_at_most_one_for_physical_parameters():
    # rho <= 1 and lobe weights that sum to 1 (the lobes share one interface). The substrate
    # term alone never reflects more than 1 - R(theta_i) (the identity above; shadowing only
    # removes light). The lobes reflect the facet-averaged F(theta_d), which can exceed
    # R(theta_i): the smooth interface then passes only what the lobes leave, so the albedo
    # stays <= 1 to the tables' accuracy (docs/models.md §10.3; tests/models/test_coated_energy.py
    # searches the whole domain).
    rng = np.random.default_rng(7)
    for opts in OPTION_SETS:
        lobes, diffuse = opts.get("lobes", 1), opts.get("diffuse", "lambertian")
        for _ in range(3):
            p = _random_params(rng, lobes, diffuse)
            p["rho"] = rng.choice([1.0, rng.uniform(0.5, 1.0)])
            m = rb.model("coated", **opts, **p)
            alb = rb.albedo(m, INCIDENCES)
            assert np.all(alb <= 1 + 1e-3), (opts, p, alb)
            assert np.all(alb >= 0)
            if diffuse == "lambertian":
                diff = alb - rb.albedo(m.with_params(rho=0.0), INCIDENCES)
                r = rb.fresnel.reflectance(np.cos(INCIDENCES), p["n"])
                assert np.all(diff <= 1 - r + 1e-8), (opts, p)
    # one GGX lobe, diffuse shadowing on: <= 1 (to the quadrature's 1e-5)
    for alpha in (0.005, 0.05, 0.3, 1.5):
        for n in (1.05, 1.5, 2.5):
            m = rb.model("coated", n=n, rho=1.0, alpha=alpha)
            assert np.all(rb.albedo(m, INCIDENCES) <= 1 + 1e-5), (alpha, n)
    # the excess of the unlimited smooth-interface factor, reproduced with the legacy free
    # scales: Beckmann without diffuse shadowing; the default model stays <= 1
    kw = {"distribution": "beckmann", "shadow_diffuse": False, "n": 1.45, "rho": 1.0,
          "alpha": 0.22}
    old = rb.model("coated", weights="free", ks=1.0, **kw)
    assert rb.albedo(old, math.radians(47.5)) == pytest.approx(1.00295, abs=5e-5)
    assert rb.albedo(rb.model("coated", **kw), math.radians(47.5)) <= 1 + 2e-4


# ------------------------------------------------------------------------------------------
# invariants (as tests/models/test_invariants.py, on the option variants)
# ------------------------------------------------------------------------------------------
def test_reciprocity_and_phi_symmetry(coated_case):
    m, _, _ = coated_case
    ti, tr, ph = _geometry(3000, 8, TI_MAX)
    f = m.brdf(ti, tr, ph)
    np.testing.assert_allclose(m.brdf(tr, ti, ph), f, rtol=1e-12)
    assert np.all(rb.reciprocity_error(m, ti, tr, ph) < 1e-12)
    np.testing.assert_allclose(m.brdf(ti, tr, -ph), f, rtol=1e-12)
    # phi and 2 pi - phi (= -phi reduced), away from the forward grazing pair where the
    # half vector turns fast and the 1e-16 rounding of the reduction is amplified
    np.testing.assert_allclose(m.brdf(ti, tr, 2 * math.pi - ph), f, rtol=1e-9)
    assert np.all(f >= 0) and np.all(np.isfinite(f))


def test_special_geometries(coated_case):
    m, _, _ = coated_case
    tis = [0.0, 1e-9, 0.3, math.pi / 4, 1.2, HALF_PI - 1e-9, TI_MAX]
    rows = []
    for ti in tis:
        for tr in (0.0, 1e-9, ti, 1.0, HALF_PI - 1e-9, HALF_PI):
            for ph in (0.0, math.pi, -math.pi, HALF_PI, 1e-12, math.pi - 1e-12):
                rows.append((ti, tr, ph))
    ti, tr, ph = np.array(rows).T
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no RuntimeWarning from the kernel either
        f = m.brdf(ti, tr, ph)
        fc = m.bridf(ti, tr, ph)
        fs = m.brdf(ti, tr, ph, "s")
    for v in (f, fc, fs):
        assert np.all(np.isfinite(v)) and np.all(v >= 0)
    # exactly specular at normal incidence: the peak of the lobe (to 1e-3: a broad Beckmann
    # lobe of a dense coating is flat there, its F(theta_d) rising as D falls, and the
    # substrate term, limited to what the lobes leave, can rise by a few 1e-4)
    assert m.brdf(0.0, 0.0, 0.0) >= m.brdf(0.0, 0.05, 0.0) * (1 - 1e-3)
    # on the horizon: the limit of the values just above it, and a BRIDF of exactly 0
    # (the absolute tolerance: near the horizon both terms fall to 0, the substrate as
    # cos theta_r, a Beckmann tail faster)
    for t in (0.0, 0.4, 1.0, 1.4):
        scale = m.brdf(t, t, 0.0)
        for p_ in (0.0, 1.0, math.pi):
            assert m.brdf(t, HALF_PI, p_) == pytest.approx(m.brdf(t, HALF_PI - 1e-10, p_),
                                                           rel=1e-5, abs=1e-9 * scale)
            assert m.bridf(t, HALF_PI, p_) == 0.0


def test_n_dimensional_inputs(coated_case):
    m, _, _ = coated_case
    rng = np.random.default_rng(9)
    ti = rng.uniform(0, 1.5, (2, 1, 3))
    tr = rng.uniform(0, HALF_PI, (1, 4, 1))
    ph = rng.uniform(-np.pi, np.pi, (3,))
    got = m.brdf(ti, tr, ph)
    assert got.shape == (2, 4, 3)
    a, b, c = np.broadcast_arrays(ti, tr, ph)
    loop = np.array([m.brdf(x, y, z) for x, y, z in zip(a.ravel(), b.ravel(), c.ravel(),
                                                        strict=True)]).reshape(2, 4, 3)
    np.testing.assert_allclose(got, loop, rtol=1e-14)
    np.testing.assert_allclose(m.brdf(np.asfortranarray(a), b[:, ::-1, :][:, ::-1, :],
                                      c.tolist()), got, rtol=1e-15)
    # one polarization per sample, broadcast along the last axis
    pol = np.array([0.0, np.pi / 2, np.nan])
    per_sample = m.brdf(ti, tr, ph, polarization=pol)
    for i, q in enumerate(("p", "s", None)):
        np.testing.assert_allclose(per_sample[..., i], m.brdf(ti, tr, ph, q)[..., i],
                                   rtol=1e-15)
    assert isinstance(m.brdf(0.1, 0.2, 0.3), float)
    assert m.brdf(np.zeros((0, 2)), 0.3, 0.0).shape == (0, 2)


def test_quantities(coated_case):
    m, _, _ = coated_case
    ti, tr, ph = _geometry(500, 10)
    f = m.brdf(ti, tr, ph)
    np.testing.assert_allclose(m.evaluate(ti, tr, ph, quantity="brdf_cos"), f * np.cos(tr),
                               rtol=1e-13)
    np.testing.assert_allclose(m.bridf(ti, tr, ph), f * np.cos(tr), rtol=1e-13)
    # relative: divided by the value at the specular direction of the same incidence
    np.testing.assert_allclose(m.evaluate(ti, tr, ph, quantity="relative"),
                               f / m.brdf(ti, ti, 0.0), rtol=1e-13)


def test_polarization(coated_case):
    m, _, _ = coated_case
    ti, tr, ph = _geometry(1000, 11)
    un = m.brdf(ti, tr, ph)
    s, p = m.brdf(ti, tr, ph, "s"), m.brdf(ti, tr, ph, "p")
    np.testing.assert_allclose(0.5 * (s + p), un, rtol=1e-13)  # TR75 Eq. 24 averaged
    np.testing.assert_allclose(m.brdf(ti, tr, ph, np.pi / 2), s, rtol=1e-15)
    np.testing.assert_allclose(m.brdf(ti, tr, ph, 0.0), p, rtol=1e-15)
    # R(gamma) + R(gamma + pi/2) = R_s + R_p for every eta (TR75 Eq. 24), in both terms
    for gamma in (np.pi / 4, 0.3, -1.2):
        np.testing.assert_allclose(m.brdf(ti, tr, ph, gamma) + m.brdf(ti, tr, ph, gamma + HALF_PI),
                                   s + p, rtol=1e-13)
    # in the plane of incidence (eta = 0) an oblique gamma lies between s and p
    for phi in (0.0, math.pi):
        g = m.brdf(ti, tr, phi, np.pi / 4)
        lo = np.minimum(m.brdf(ti, tr, phi, "s"), m.brdf(ti, tr, phi, "p"))
        hi = np.maximum(m.brdf(ti, tr, phi, "s"), m.brdf(ti, tr, phi, "p"))
        assert np.all((g >= lo * (1 - 1e-13)) & (g <= hi * (1 + 1e-13)))


def test_polarization_wiring():
    # p-polarized light exactly at Brewster's angle, specular direction: theta_d = theta_i and
    # R_p = 0, so the lobe vanishes; the substrate gets 1 - R_p(theta_i) = 1 (all of it)
    n = 1.5
    tb = math.atan(n)
    lobe = rb.model("coated", n=n, rho=0.0, alpha=0.1)
    assert lobe.brdf(tb, tb, 0.0, "p") == pytest.approx(0.0, abs=1e-12 * lobe.brdf(tb, tb, 0.0))
    assert lobe.brdf(tb, tb, 0.0, "s") > 0
    sub = rb.model("coated", n=n, rho=0.5, ks=0.0, weights="free")  # the substrate alone
    ti, tr, ph = _geometry(300, 12)
    ratio = sub.brdf(ti, tr, ph, "s") / sub.brdf(ti, tr, ph, "p")
    rs = rb.fresnel.reflectance(np.cos(ti), n, 0.0, "s")
    rp = rb.fresnel.reflectance(np.cos(ti), n, 0.0, "p")
    np.testing.assert_allclose(ratio, (1 - rs) / (1 - rp), rtol=1e-13)


# ------------------------------------------------------------------------------------------
# arguments, parameters and options
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name, kw", [("coated", {"lobes": 2, "diffuse": "oren-nayar"}),
                                      ("oren-nayar", {})])
def test_invalid_angles_raise_argument_error(name, kw):
    m = rb.model(name, **kw)
    for which in ("theta_i", "theta_r"):
        for bad in (-0.1, HALF_PI + 0.01, math.nan, math.inf, -math.inf):
            args = {"theta_i": 0.3, "theta_r": 0.4, "phi": 0.0}
            args[which] = np.array([0.1, bad, 0.2])
            for method in (m.brdf, m.bridf):
                with pytest.raises(ArgumentError) as exc:
                    method(**args)
                assert exc.value.argument == which
                assert which in str(exc.value) and repr(float(bad)) in str(exc.value)
    for bad in (math.nan, math.inf):
        with pytest.raises(ArgumentError, match=r"phi.*" + repr(bad)):
            m.brdf(0.3, 0.4, bad)
    with pytest.raises(ArgumentError, match="theta_i"):
        m.brdf(HALF_PI, 0.3, 0.0)
    with pytest.raises(ArgumentError, match="polarization"):
        m.brdf(0.3, 0.4, 0.0, polarization="q")
    with pytest.raises(ArgumentError, match="polarization"):
        m.brdf(0.3, 0.4, 0.0, polarization=math.inf)


@pytest.mark.parametrize("kw, param", [
    ({"n": 1.0}, "n"), ({"n": 0.8}, "n"), ({"n": math.nan}, "n"), ({"rho": 1.5}, "rho"),
    ({"rho": -0.1}, "rho"), ({"alpha": 0.0}, "alpha"), ({"weights": "free", "ks": -1.0}, "ks"),
    ({"lobes": 2, "alpha2": -0.3}, "alpha2"), ({"lobes": 3, "w3": math.inf}, "w3"),
    ({"lobes": 2, "w2": 1.5}, "w2"), ({"lobes": 3, "weights": "free", "ks3": math.inf}, "ks3"),
    ({"diffuse": "oren-nayar", "sigma": -0.1}, "sigma"),
])
def test_invalid_parameters_name_them(kw, param):
    with pytest.raises(ValueError) as exc:
        rb.model("coated", **kw)
    assert repr(param) in str(exc.value) and repr(kw[param]) in str(exc.value)


@pytest.mark.parametrize("kw, match", [
    ({"lobes": 0}, "lobes"), ({"lobes": 4}, "lobes"), ({"lobes": True}, "lobes"),
    ({"lobes": "two"}, "lobes"), ({"lobes": 1.5}, "lobes"),
    ({"diffuse": "phong"}, "diffuse"),
    ({"shadowing": "v-groove"}, "smith-separable or smith-height-correlated"),
    ({"shadowing": "none"}, "smith-separable or smith-height-correlated"),
    ({"distribution": "gaussian-angle"}, "Smith Lambda"),
    ({"distribution": "berry"}, "Smith Lambda"),
    ({"distribution": "no-such"}, "no-such"),
    ({"shadow_diffuse": "maybe"}, "shadow_diffuse"),
    ({"shadow_diffuse": 1.0}, "shadow_diffuse"),
])
def test_option_validation(kw, match):
    with pytest.raises(ValueError, match=match):
        rb.model("coated", **kw)


def test_options_as_text_and_aliases():
    m = rb.model("plastic", lobes="2", shadow_diffuse="false", diffuse="Oren_Nayar",
                 distribution="ggx", shadowing="smith")
    assert m.name == "coated" and rb.model("paint").name == "coated"
    assert m.options == {"distribution": "trowbridge-reitz",
                         "shadowing": "smith-height-correlated", "lobes": 2,
                         "diffuse": "oren-nayar", "shadow_diffuse": False}
    assert m.param_names == ["n", "rho", "alpha", "alpha2", "w2", "sigma"]
    assert rb.model("rough-diffuse").name == "oren-nayar"
    with pytest.raises(ValueError, match="unknown parameter.*'alpha2'"):
        rb.model("coated", alpha2=0.3)  # lobes=1 has no second lobe
    with pytest.raises(ValueError, match="unknown parameter.*'sigma'"):
        rb.model("coated", sigma=0.3)  # the Lambertian substrate has no sigma


def test_with_params_follows_the_options():
    m = rb.model("coated", lobes=2, alpha2=0.4, w2=0.3, rho=0.2)
    one = m.with_params(lobes=1)
    assert one.param_names == ["n", "rho", "alpha"]
    assert one.params["rho"] == 0.2  # the others are kept
    three = m.with_params(lobes=3)
    assert three.params["alpha2"] == 0.4 and three.params["w2"] == 0.3  # kept
    assert (three.params["alpha3"], three.params["w3"]) == (0.6, 0.2)  # defaults
    on = m.with_params(diffuse="oren-nayar", sigma=0.25)
    assert on.params["sigma"] == 0.25
    assert "sigma" not in on.with_params(diffuse="lambertian").params
    # lobes=1 evaluates as the lobes=2 model with w2 = 0
    ti, tr, ph = _geometry(300, 13)
    np.testing.assert_allclose(one.brdf(ti, tr, ph), m.with_params(w2=0.0).brdf(ti, tr, ph),
                               rtol=1e-15)
    for x in (m, one, three, on):
        again = rb.model(x.to_dict())
        assert again.params == x.params and again.options == x.options
        np.testing.assert_array_equal(again.brdf(ti, tr, ph), x.brdf(ti, tr, ph))


# ------------------------------------------------------------------------------------------
# NUMBA_DISABLE_JIT=1 gives the same numbers (pure Python, for debugging and coverage)
# ------------------------------------------------------------------------------------------
# the lobes' widths on the lobe-albedo grid's nodes (alpha = 10^(i/128), diffuse._albedo_smooth)
# but one: in plain Python each node table takes seconds to build (diffuse._albedo_node), a
# width on a node needs its own only, one between nodes the four around it. The spline between
# the nodes is NumPy code, the same with the JIT on or off; the kernels' paths are those of
# any widths
_NODE = [10.0 ** (i / 128) for i in (-128, -127, -126)]  # 0.1, 0.1018, 0.1037
_PURE_CASES = [
    ("coated", {"lobes": 2, "diffuse": "oren-nayar", "sigma": 0.4, "rho": 0.7,
                "alpha": _NODE[0], "alpha2": 0.1009, "w2": 0.3}),
    ("coated", {"distribution": "beckmann", "shadowing": "smith-height-correlated",
                "shadow_diffuse": False, "lobes": 3, "alpha": _NODE[0], "alpha2": _NODE[1],
                "alpha3": _NODE[2], "w2": 0.3, "w3": 0.2}),
    ("oren-nayar", {"sigma": 0.5}),
]


def test_pure_python_mode_agrees():
    code = textwrap.dedent("""
        import json, numpy as np, numba, roughbrdf as rb
        assert numba.config.DISABLE_JIT
        cases = json.loads(%r)
        ti = np.array([0.0, 0.3, 1.2, 1.5]); tr = np.array([0.0, 0.4, 1.2, 1.5707963267948966])
        ph = np.array([0.0, 1.0, 3.141592653589793, -2.0])
        # each model built once: in plain Python its lobe-albedo tables take most of the time
        models = [rb.model(n, **kw) for n, kw in cases]
        out = [[m.bridf(ti, tr, ph).tolist(), m.brdf(ti, tr, ph, "s").tolist()]
               for m in models]
        out.append([rb.diffuse.oren_nayar(ti, tr, ph, 0.3).tolist(),
                    rb.fresnel.diffuse_reflectance(1.5, internal=True)])
        print(json.dumps(out))
    """) % json.dumps(_PURE_CASES)
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=300, check=True)
    pure = json.loads(res.stdout.strip().splitlines()[-1])
    ti = np.array([0.0, 0.3, 1.2, 1.5])
    tr = np.array([0.0, 0.4, 1.2, HALF_PI])
    ph = np.array([0.0, 1.0, math.pi, -2.0])
    for (name, kw), (bridf, brdf_s) in zip(_PURE_CASES, pure, strict=False):
        m = rb.model(name, **kw)
        np.testing.assert_allclose(bridf, m.bridf(ti, tr, ph), rtol=1e-13)
        np.testing.assert_allclose(brdf_s, m.brdf(ti, tr, ph, "s"), rtol=1e-13)
    np.testing.assert_allclose(pure[-1][0], rb.diffuse.oren_nayar(ti, tr, ph, 0.3), rtol=1e-13)
    assert pure[-1][1] == pytest.approx(rb.fresnel.diffuse_reflectance(1.5, internal=True),
                                        rel=1e-14)


# ------------------------------------------------------------------------------------------
# interface="rough": the substrate under the rough interface (Mitsuba 3's roughplastic);
# checked against Mitsuba itself in tests/export/test_export_mitsuba.py
# ------------------------------------------------------------------------------------------
def rough_substrate_numpy(ti, tr, p, distribution):
    """``rho/pi T(cos theta_i) T(cos theta_r) / (n^2 (1 - rho F_int))`` with the tables of
    ``rb.diffuse.rough_interface`` interpolated by ``np.interp`` on the cell positions k/63
    (Mitsuba's ``lerp_gather`` works on ``63 cos theta``, not on the clamped first node).
    Several lobes: the weight-mixture of each lobe's tables (one interface)."""
    lobes = 1 + sum(f"alpha{j}" in p for j in (2, 3))
    weights = rb.models.coated.lobe_weights(lobes, p.get("w2", 0.0), p.get("w3", 0.0))
    t, f_int = np.zeros(64), 0.0
    for j, w in enumerate(weights, 1):
        tj, fj = rb.diffuse.rough_interface(p["alpha" if j == 1 else f"alpha{j}"], p["n"],
                                            distribution)
        t, f_int = t + w * tj, f_int + w * fj
    nodes = np.arange(64) / 63.0
    t_i, t_r = np.interp(np.cos(ti), nodes, t), np.interp(np.cos(tr), nodes, t)
    return p["rho"] / np.pi * t_i * t_r / (p["n"] ** 2 * (1 - p["rho"] * f_int))


@pytest.mark.parametrize("distribution, lobes, diffuse, shadow_diffuse", [
    ("trowbridge-reitz", 1, "lambertian", False), ("beckmann", 2, "lambertian", False),
    ("trowbridge-reitz", 3, "oren-nayar", True)])
def test_rough_interface_is_the_formula(distribution, lobes, diffuse, shadow_diffuse):
    rng = np.random.default_rng(31)
    p = _random_params(rng, lobes, diffuse)
    m = rb.model("coated", distribution=distribution, lobes=lobes, diffuse=diffuse,
                 shadow_diffuse=shadow_diffuse, interface="rough", **p)
    # 400 geometries without the JIT (Beckmann, 2 lobes: 112 s with 4000 in plain Python)
    ti, tr, ph = _geometry(400 if NOJIT else 4000, 32)
    for pol in (None, "s"):
        lobes_only = coated_numpy(ti, tr, ph, {**p, "rho": 0.0}, distribution=distribution,
                                  lobes=lobes, polarization=pol)
        sub = rough_substrate_numpy(ti, tr, p, distribution)  # unpolarized
        if diffuse == "oren-nayar":
            sub = sub * on_eq30(ti, tr, ph, np.pi, p["sigma"]) / on_cap(ti, tr, p["sigma"])
        if shadow_diffuse:
            sub = sub * rb.shadowing.smith(ti, tr, p["alpha"], distribution, "smith-separable")
        np.testing.assert_allclose(m.brdf(ti, tr, ph, pol), lobes_only + sub, rtol=1e-11,
                                   atol=1e-300)


def test_rough_interface_option():
    m = rb.model("coated", interface="rough", shadow_diffuse=False)
    assert m.options["interface"] == "rough"
    smooth = m.with_params(interface="smooth")
    assert "interface" not in smooth.options  # the default is not listed (older files read)
    default = rb.model("coated", shadow_diffuse=False)
    ti, tr, ph = _geometry(500, 33)
    np.testing.assert_array_equal(smooth.brdf(ti, tr, ph), default.brdf(ti, tr, ph))
    assert not np.allclose(m.brdf(ti, tr, ph), default.brdf(ti, tr, ph))
    # rho = 0: no substrate, the interface does not matter
    np.testing.assert_array_equal(m.with_params(rho=0.0).brdf(ti, tr, ph),
                                  default.with_params(rho=0.0).brdf(ti, tr, ph))
    with pytest.raises(ValueError, match="interface must be 'smooth' or 'rough'"):
        rb.model("coated", interface="bumpy")
    assert rb.model("coated", interface="ROUGH").options["interface"] == "rough"


def test_rough_interface_reciprocal_and_symmetric():
    m = rb.model("coated", interface="rough", shadow_diffuse=False, alpha=0.4, rho=0.9, n=1.7)
    ti, tr, ph = _geometry(2000, 34)
    np.testing.assert_allclose(m.brdf(ti, tr, ph), m.brdf(tr, ti, ph), rtol=1e-12)
    np.testing.assert_array_equal(m.brdf(ti, tr, ph), m.brdf(ti, tr, -ph))


def test_rough_tables_approach_the_smooth_interface():
    # a nearly smooth interface transmits 1 - R(theta) (away from grazing), and its internal
    # reflectance is Mitsuba's 64-node mean of the smooth internal Fresnel reflectance
    t, f_int = rb.diffuse.rough_interface(0.005, 1.5)
    mu = np.maximum(1e-6, np.linspace(0, 1, 64))
    ok = mu > 0.2
    np.testing.assert_allclose(t[ok], 1 - rb.fresnel.reflectance(mu[ok], 1.5), rtol=2e-3)
    smooth = 2 * np.mean(rb.fresnel.reflectance(mu, 1 / 1.5) * mu)
    assert f_int == pytest.approx(smooth, rel=2e-3)


@pytest.mark.parametrize("mu, alpha", [(0.5, 0.3), (0.9, 0.6)])
def test_rough_transmittance_is_the_lobe_integral(mu, alpha):
    """``T(mu) = ∫ (1 - F(wi.m)) G1(wi) G1(wt) D(m) (wi.m)/cos(theta_i) dω_m`` (GGX) by an
    adaptive quadrature written here; Mitsuba's 32 x 32 rule, which the table reproduces,
    is ~2e-4 above it (the reason the table is not computed more accurately)."""
    from scipy import integrate

    n = 1.5
    wi = np.array([math.sqrt(1 - mu * mu), 0.0, mu])

    def g1(c):
        return 2 / (1 + math.sqrt(1 + alpha ** 2 * (1 - c * c) / (c * c)))

    def integrand(phm, thm):
        m = np.array([math.sin(thm) * math.cos(phm), math.sin(thm) * math.sin(phm),
                      math.cos(thm)])
        c = float(wi @ m)
        if c <= 0:
            return 0.0
        ct = math.sqrt(1 - (1 - c * c) / n ** 2)
        wt = -wi / n + (c / n - ct) * m
        d = float(rb.distributions.trowbridge_reitz(m[2], alpha))
        f = float(rb.fresnel.reflectance(c, n))
        return (1 - f) * g1(mu) * g1(abs(wt[2])) * d * c / mu * math.sin(thm)

    exact, _ = integrate.dblquad(integrand, 0, HALF_PI, 0, 2 * math.pi, epsabs=1e-10,
                                 epsrel=1e-9)
    t, _ = rb.diffuse.rough_interface(alpha, n)
    k = int(round(mu * 63))
    assert mu == pytest.approx(k / 63, abs=0.01)
    t_mu = np.interp(mu, np.arange(64) / 63, t)
    assert t_mu == pytest.approx(exact, rel=6e-4)


def test_erfinv_of_the_beckmann_sampling():
    from scipy.special import erfinv

    from roughbrdf.diffuse import _erfinv

    y = np.concatenate([np.linspace(-0.999999999, 0.999999999, 4001),
                        [1e-12, -0.5, 0.5, 1 - 1e-15, -1 + 1e-14, 1 - 2 ** -53]])
    got = np.array([_erfinv(v) for v in y])
    np.testing.assert_allclose(got, erfinv(y), rtol=1e-14)
    assert _erfinv(1.0) == math.inf and _erfinv(-1.0) == -math.inf


@pytest.fixture
def small_rough_rules(monkeypatch):
    """Without the JIT, the rough interface's rules of :data:`_PURE_RULE` (Mitsuba's 32 and 128
    nodes a table take 30 s for Beckmann in plain Python), its cache emptied before and after
    (no table of these rules is left for another test); with the JIT nothing changes."""
    if NOJIT:
        for name, nodes in _PURE_RULE.items():
            monkeypatch.setattr(rb.diffuse, name, nodes)
        rb.diffuse._rough_cached.cache_clear()
        yield
        rb.diffuse._rough_cached.cache_clear()
    else:
        yield


def test_rough_interface_arguments(small_rough_rules):
    with pytest.raises(ValueError, match="distribution"):
        rb.diffuse.rough_interface(0.3, 1.5, "gaussian-angle")
    with pytest.raises(ValueError, match="alpha"):
        rb.diffuse.rough_interface(0.0, 1.5)
    with pytest.raises(ValueError, match="n must be"):
        rb.diffuse.rough_interface(0.3, 1.0)
    with pytest.raises(ValueError, match="g1"):
        rb.diffuse.rough_interface(0.3, 1.5, g1="approximate")
    t, f_int = rb.diffuse.rough_interface(0.3, 1.5, "beckmann", g1="mitsuba")
    t2, f_int2 = rb.diffuse.rough_interface(0.3, 1.5, "beckmann")
    assert t.shape == (64,) and 0 < f_int < 1 and f_int != f_int2  # the G1 differs


#: Gauss-Legendre nodes per axis of the rough interface's rules in the plain-Python check
#: (Mitsuba's 32 and 128 take 20 s in plain Python; the check compares the two paths, which
#: compute the same rule whatever its size)
_PURE_RULE = {"_NODES_EXTERNAL": 8, "_NODES_INTERNAL": 16}


def test_rough_interface_pure_python_mode_agrees(monkeypatch):
    code = textwrap.dedent("""
        import json, numpy as np, numba, roughbrdf as rb
        assert numba.config.DISABLE_JIT
        for name, nodes in json.loads(%r).items():
            setattr(rb.diffuse, name, nodes)
        m = rb.model("coated", alpha=0.3, rho=0.7, shadow_diffuse=False, interface="rough")
        ti = np.array([0.0, 0.3, 1.2, 1.5]); tr = np.array([0.0, 0.4, 1.2, 1.5707963267948966])
        ph = np.array([0.0, 1.0, 3.141592653589793, -2.0])
        print(json.dumps([m.brdf(ti, tr, ph).tolist(), m.bridf(ti, tr, ph, "p").tolist()]))
    """) % json.dumps(_PURE_RULE)
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=300, check=True)
    brdf, bridf = json.loads(res.stdout.strip().splitlines()[-1])
    for name, nodes in _PURE_RULE.items():
        monkeypatch.setattr(rb.diffuse, name, nodes)
    # the tables are cached per (alpha, n): none of the full rule before, none of this after
    rb.diffuse._rough_cached.cache_clear()
    try:
        m = rb.model("coated", alpha=0.3, rho=0.7, shadow_diffuse=False, interface="rough")
        ti = np.array([0.0, 0.3, 1.2, 1.5])
        tr = np.array([0.0, 0.4, 1.2, HALF_PI])
        ph = np.array([0.0, 1.0, math.pi, -2.0])
        got = m.brdf(ti, tr, ph), m.bridf(ti, tr, ph, "p")
        small = rb.diffuse.rough_interface(0.3, 1.5)[0]
    finally:
        monkeypatch.undo()
        rb.diffuse._rough_cached.cache_clear()
    np.testing.assert_allclose(brdf, got[0], rtol=1e-13)
    np.testing.assert_allclose(bridf, got[1], rtol=1e-13)
    # the smaller rule is a different table (so the check did use it), near Mitsuba's
    full = rb.diffuse.rough_interface(0.3, 1.5)[0]
    assert not np.array_equal(full, small)
    np.testing.assert_allclose(small, full, atol=0.05)


def test_a_sum_takes_an_option_left_at_its_default_out_of_options():
    # coated lists "interface" in .options only when it is "rough"; rb.model("a+b", ...) must
    # still route it to the coated component (models.factory)
    m = rb.model("coated+lambertian", interface="rough", shadow_diffuse=False)
    assert m.components[0].options["interface"] == "rough"
    assert "interface" not in rb.model("coated").options
