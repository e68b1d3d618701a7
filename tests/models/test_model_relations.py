"""The cross-model relations of docs/models.md §5, computed by the library: TS67's G is the
V-cavity G, TR75 is a GGX microfacet model without G (plus a Lambertian term), TR75's TS-style
ratio is TS67's specular term, and Rense's Gaussian is TS67's.
"""

from __future__ import annotations

import math

import numpy as np

import roughbrdf as rb

deg = np.radians


def cement(**kw):
    """TR75 Table 1, cement column (docs/models.md §3.10)."""
    return rb.model("trowbridge-reitz-1975", e=0.68, n=1.0, k=0.9, rho_L=0.33, **kw)


# ------------------------------------------------------------------------------------------
# §5 cross-model relations
# ------------------------------------------------------------------------------------------
def _random_geometry(n, seed, max_deg=89.0):
    rng = np.random.default_rng(seed)
    return (rng.uniform(0, deg(max_deg), n), rng.uniform(0, deg(max_deg), n),
            rng.uniform(-np.pi, np.pi, n))


def test_relation1_ts67_g_is_v_cavity_g():
    # docs/models.md §5.1: TS67 G (Table I in projected angles) == V-cavity
    # min(1, 2 cos th cos tr / cos td, 2 cos th cos ti / cos td), here written with NumPy
    ti, tr, ph = _random_geometry(20000, 4, 90.0)
    th = rb.geometry.theta_h(ti, tr, ph)
    td = rb.geometry.theta_d(ti, tr, ph)
    ch, cd = np.cos(th), np.cos(td)
    v_cavity = np.minimum(1, np.minimum(2 * ch * np.cos(tr) / cd, 2 * ch * np.cos(ti) / cd))
    np.testing.assert_allclose(rb.shadowing.v_groove_table(ti, tr, ph), v_cavity, atol=1e-10)
    np.testing.assert_allclose(rb.shadowing.v_groove(ti, tr, ph), v_cavity, atol=1e-12)


def test_relation2_tr75_is_ggx_microfacet_times_cos():
    # docs/models.md §5.2: TR75 Eq. 30 == (microfacet BRDF, GGX D with alpha = e, Fresnel at
    # theta_d, no G) x cos(theta_r)
    ti, tr, ph = _random_geometry(5000, 5)
    for e, n, k in [(0.68, 1.0, 0.9), (0.24, 1.0, 0.4), (1.6, 0.7, 1.3), (0.05, 1.5, 0.0)]:
        tr75 = rb.model("tr75", e=e, n=n, k=k, rho_L=0.0)
        mf = rb.model("microfacet", distribution="ggx", alpha=e, shadowing="none", n=n, k=k)
        np.testing.assert_allclose(tr75.bridf(ti, tr, ph), mf.brdf(ti, tr, ph) * np.cos(tr),
                                   rtol=1e-12)
        np.testing.assert_allclose(tr75.bridf(ti, tr, ph), mf.bridf(ti, tr, ph), rtol=1e-12)


def test_relation2_with_lambertian_sum():
    # Eq. 33: TR75 = specular part + Lambertian (Eq. 32); as a sum of library models
    ti, tr, ph = _random_geometry(2000, 6)
    mf = rb.model("microfacet", distribution="ggx", alpha=0.68, shadowing="none", n=1.0, k=0.9)
    total = mf + rb.model("lambertian", rho=0.33)
    np.testing.assert_allclose(total.brdf(ti, tr, ph), cement().brdf(ti, tr, ph), rtol=1e-12)


def test_relation3_ts_style_ratio():
    # docs/models.md §5.3 (TR75 footnote): with D set to 1 and no G, Eq. 30 converted to a TS-style
    # ratio of BRRDFs equals TS67's specular term. Both are F D/(4 cos i cos r) forms: TR75 with
    # the peak shape divided out (D -> 1), and TS67 with g -> infinity (no diffuse part), c -> 0
    # (Gaussian -> 1) and G removed, relative to the specular direction.
    ti, tr, ph = _random_geometry(3000, 7, 85.0)
    n, k, e = 1.5, 0.2, 0.5
    tr75 = rb.model("tr75", e=e, n=n, k=k, rho_L=0.0)
    th = rb.geometry.theta_h(ti, tr, ph)
    shape = rb.distributions.evaluate("tr", np.cos(th), e, peak_normalized=True)
    tr_ratio = (tr75.brdf(ti, tr, ph) / shape) / tr75.brdf(ti, ti, 0.0)
    td = rb.geometry.theta_d(ti, tr, ph)
    f = rb.fresnel.reflectance(np.cos(td), n, k)
    f0 = rb.fresnel.reflectance(np.cos(ti), n, k)
    ts_specular = (f / (np.cos(ti) * np.cos(tr))) / (f0 / np.cos(ti) ** 2)
    np.testing.assert_allclose(tr_ratio, ts_specular, rtol=1e-12)
    # and the library's TS67 approaches it when g is large, c small and G ~ 1 (near specular)
    ts = rb.model("ts67", g=1e9, c=1e-6, n=n, k=k, rho_d=1.0)
    near = np.abs(th) < deg(5)
    ts_rel = ts.relative(ti[near], tr[near], ph[near]) / rb.shadowing.v_groove(
        ti[near], tr[near], ph[near])
    np.testing.assert_allclose(ts_rel, ts_specular[near], rtol=1e-6)


def test_relation4_rense_equals_ts67_gaussian():
    # docs/models.md §5.4: exp(-c^2 alpha^2) with c = 0.046/deg is Rense's exp(-0.0021 alpha_deg^2)
    a = deg(np.linspace(0, 60, 61))
    rense = np.exp(-0.0021 * np.degrees(a) ** 2)
    ts = rb.distributions.evaluate("gaussian-angle", np.cos(a), math.sqrt(0.0021),
                                   peak_normalized=True)
    np.testing.assert_allclose(ts, rense, rtol=1e-12)
    # 0.046 is sqrt(0.0021) = 0.0458 rounded: the exponents agree to 1 %
    ts046 = rb.distributions.evaluate("gaussian-angle", np.cos(a), 0.046, peak_normalized=True)
    np.testing.assert_allclose(np.log(ts046[1:]), np.log(rense[1:]), rtol=0.01)
