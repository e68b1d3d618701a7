"""Reproduction targets of Trowbridge & Reitz (1975), TR75 (docs/models.md §3.10-3.12), computed
by the library: Table 1's reflectances, the §3.12 sample values, polarization (Eq. 24) and the
half widths of Fig. 5.

Every expected number below comes from docs/models.md (the section is named at each table), which
quotes an independent NumPy/SciPy implementation of the specification, or from an identity
stated next to it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize

import roughbrdf as rb

deg = np.radians


def cement(**kw):
    """TR75 Table 1, cement column (docs/models.md §3.10)."""
    return rb.model("trowbridge-reitz-1975", e=0.68, n=1.0, k=0.9, rho_L=0.33, **kw)


# ------------------------------------------------------------------------------------------
# TR75 Table 1 (docs/models.md §3.10): directional-hemispherical reflectance at normal incidence
# ------------------------------------------------------------------------------------------
TABLE1 = {  # column: (e, n, k, rho_L, total DHR at beta = 0)
    "black velvet, set 1": (0.89, 1.60, 0.00, 0.020, 0.051),
    "black velvet, set 2": (0.88, 1.62, 0.3, 0.022, 0.062),
    "soiled olive drab": (0.24, 1.0, 0.4, 0.06, 0.097),
    "cement": (0.68, 1.00, 0.9, 0.33, 0.450),
    "plywood": (0.51, 0.9, 1.9, 0.40, 0.799),
    "grass": (1.6, 0.7, 1.3, 0.5, 0.612),
}


@pytest.mark.parametrize("surface", sorted(TABLE1))
def test_tr75_table1_dhr_normal_incidence(surface):
    e, n, k, rho_l, dhr = TABLE1[surface]
    m = rb.model("trowbridge-reitz-1975", e=e, n=n, k=k, rho_L=rho_l)
    assert rb.albedo(m, 0.0) == pytest.approx(dhr, abs=0.002)


def test_tr75_table1_interface_parts():
    # docs/models.md §3.10 "interface part" column: the same DHR with rho_L = 0
    for surface, part in [("black velvet, set 1", 0.031), ("cement", 0.120),
                          ("plywood", 0.399), ("grass", 0.112)]:
        e, n, k, _, _ = TABLE1[surface]
        m = rb.model("tr75", e=e, n=n, k=k, rho_L=0.0)
        assert rb.albedo(m, 0.0) == pytest.approx(part, abs=0.002), surface


def test_tr75_dhr_rises_with_beta():
    # docs/models.md §3.10: no shadowing, so the DHR rises with beta; cement 0.450, 0.464, 0.548,
    # 0.919 and Black Velvet 0.051, 0.057, 0.093, 0.275 at beta = 0, 30, 60, 80 deg
    beta = deg(np.array([0.0, 30, 60, 80]))
    np.testing.assert_allclose(rb.albedo(cement(), beta), [0.450, 0.464, 0.548, 0.919],
                               atol=0.002)
    bv = rb.model("tr75", e=0.89, n=1.60, k=0.0, rho_L=0.020)
    np.testing.assert_allclose(rb.albedo(bv, beta), [0.051, 0.057, 0.093, 0.275], atol=0.002)
    dense = rb.albedo(cement(), deg(np.arange(0, 85, 5.0)))
    assert np.all(np.diff(dense) > 0)


# ------------------------------------------------------------------------------------------
# TR75 §3.12 sample values and the normal-incidence closed form
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("elev, expected", [
    (15, [0.0389, 0.0429, 0.0862]),
    (45, [0.0907, 0.0963, 0.1233]),
    (75, [0.1261, 0.1305, 0.1380]),
])
def test_tr75_cement_sample_values(elev, expected):
    # docs/models.md §3.12: cement, unpolarized, beta = 45 deg, TR75 azimuth psi = 0/90/180 deg,
    # converted to the common frame by geometry.from_tr75
    ti, tr, phi = rb.geometry.from_tr75(deg(45), deg(elev), deg(np.array([0.0, 90, 180])))
    np.testing.assert_allclose(cement().bridf(ti, tr, phi), expected, atol=5e-5)


def test_tr75_cement_sample_value_zenith():
    ti, tr, phi = rb.geometry.from_tr75(deg(45), deg(90), 0.0)  # theta_elev = 90: 0.1353
    assert cement().bridf(ti, tr, phi) == pytest.approx(0.1353, abs=5e-5)


def test_tr75_normal_incidence_closed_form():
    # docs/models.md §3.12: f_rI(0; 90 deg, 0) = R(0)/(4 pi e^2), 0.02649 for e = 0.4, n = 1.6
    m = rb.model("tr75", e=0.4, n=1.6, k=0.0, rho_L=0.0)
    assert m.bridf(0.0, 0.0, 0.0) == pytest.approx(0.02649, abs=5e-6)
    r0 = ((1.6 - 1) / (1.6 + 1)) ** 2
    assert m.bridf(0.0, 0.0, 0.0) == pytest.approx(r0 / (4 * np.pi * 0.16), rel=1e-13)


def test_tr75_brdf_is_bridf_over_cos_and_inf_at_horizon():
    m = cement()
    rng = np.random.default_rng(2)
    ti, tr, ph = rng.uniform(0, 1.5, 100), rng.uniform(0, 1.5, 100), rng.uniform(-3, 3, 100)
    np.testing.assert_allclose(m.brdf(ti, tr, ph) * np.cos(tr), m.bridf(ti, tr, ph), rtol=1e-13)
    # the published BRDF (no shadowing) diverges at theta_r = 90 deg: its limit is inf, and the
    # BRIDF stays finite and equals rho_L/pi * 0 + the specular part
    assert m.brdf(0.3, math.pi / 2, 0.0) == math.inf
    assert np.isfinite(m.bridf(0.3, math.pi / 2, 0.0))
    # with the report's footnote option (TS67 G) the BRDF is finite at the horizon
    ms = cement(shadowing="v-groove")
    assert np.isfinite(ms.brdf(0.3, math.pi / 2, 0.0))


def test_tr75_polarization_eq24():
    # docs/models.md §3.5: the mean of gamma = 0 and gamma = 90 deg is the unpolarized value; "p" is
    # gamma = 0 and "s" gamma = 90 deg
    m = cement()
    rng = np.random.default_rng(3)
    ti, tr, ph = rng.uniform(0, 1.5, 300), rng.uniform(0, 1.5, 300), rng.uniform(-3, 3, 300)
    un = m.bridf(ti, tr, ph)
    g0 = m.bridf(ti, tr, ph, polarization=0.0)
    g90 = m.bridf(ti, tr, ph, polarization=np.pi / 2)
    np.testing.assert_allclose(0.5 * (g0 + g90), un, rtol=1e-13)
    np.testing.assert_allclose(m.bridf(ti, tr, ph, polarization="p"), g0, rtol=1e-15)
    np.testing.assert_allclose(m.bridf(ti, tr, ph, polarization="s"), g90, rtol=1e-15)
    # in the plane of incidence eta = 0: gamma = 0 is exactly R_p and gamma = 90 deg R_s
    ti, tr = deg(40.0), deg(np.array([10.0, 30, 60]))
    for phi in (0.0, np.pi):
        td = rb.geometry.theta_d(ti, tr, phi)
        d = rb.distributions.trowbridge_reitz(np.cos(rb.geometry.theta_h(ti, tr, phi)), 0.68)
        for pol, gamma in (("p", 0.0), ("s", np.pi / 2)):
            r = rb.fresnel.reflectance(np.cos(td), 1.0, 0.9, pol)
            expected = r * d / (4 * np.cos(ti)) + np.cos(tr) * 0.33 / np.pi
            np.testing.assert_allclose(m.bridf(ti, tr, phi, polarization=gamma), expected,
                                       rtol=1e-12)
    # an oblique gamma lies between the two
    g45 = m.bridf(0.5, 0.7, 2.0, polarization=np.pi / 4)
    lo, hi = sorted([m.bridf(0.5, 0.7, 2.0, polarization=a) for a in (0.0, np.pi / 2)])
    assert lo - 1e-15 <= g45 <= hi + 1e-15


def test_tr75_per_sample_polarization_array():
    m = cement()
    pol = np.array([0.0, np.pi / 2, np.nan])
    got = m.bridf(0.4, 0.6, 1.0, polarization=pol)
    expected = [m.bridf(0.4, 0.6, 1.0, polarization=p) for p in ("p", "s", None)]
    np.testing.assert_allclose(got, expected, rtol=1e-15)


# ------------------------------------------------------------------------------------------
# TR75 Fig. 5 (docs/models.md §3.11): half widths at half maximum of the peak-normalized forms
# ------------------------------------------------------------------------------------------
def _hwhm_deg(name, param):
    def half(a):
        return rb.distributions.evaluate(name, np.cos(a), param, peak_normalized=True) - 0.5

    return math.degrees(optimize.brentq(half, 1e-9, math.pi / 2 - 1e-12, xtol=1e-13))


@pytest.mark.parametrize("name, param, hwhm", [
    ("trowbridge-reitz", 0.40, 16.31),
    ("berry", 0.25, 14.96),
    ("beckmann", 1 / math.sqrt(7.62), 19.17),  # cos^-4 exp(-A^2 tan^2), m = 1/A
    ("sirohi", 6.93, 18.80),  # p = 2, the recommended reading
    ("gaussian-angle", math.sqrt(0.0021), 18.17),  # Rense exp(-A^2 alpha_deg^2), c = A
])
def test_tr75_fig5_hwhm(name, param, hwhm):
    assert _hwhm_deg(name, param) == pytest.approx(hwhm, abs=0.05)


def test_tr75_fig5_sirohi_p4_is_beckmann():
    # docs/models.md §3.11: the p = 4 Sirohi form cos^-4 exp(-A^2 tan^2) with A^2 = 6.93 has HWHM
    # 20.32 deg; it is Beckmann with m = 1/A (distributions module docstring)
    assert _hwhm_deg("beckmann", 1 / math.sqrt(6.93)) == pytest.approx(20.32, abs=0.05)


def test_tr75_fig5_peak_normalized_is_one_at_zero():
    for name, p in [("tr", 0.4), ("berry", 0.25), ("beckmann", 0.36), ("sirohi", 6.93),
                    ("rense", 0.0458)]:
        assert rb.distributions.evaluate(name, 1.0, p, peak_normalized=True) == 1.0
