"""Reproduction targets of TS67 and TR75 (docs/models.md §2.7, §3.10-3.12, §5), computed by the
library.

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


@pytest.fixture(scope="module")
def ts_fig8():
    """TS67 as in Figs. 8, 10, 11: F = 1 (n=None), g = 2/3, c = 0.05 per degree."""
    return rb.model("torrance-sparrow-1967", g=2 / 3, c=0.05, n=None, k=None, rho_d=0.3)


def cement(**kw):
    """TR75 Table 1, cement column (docs/models.md §3.10)."""
    return rb.model("trowbridge-reitz-1975", e=0.68, n=1.0, k=0.9, rho_L=0.33, **kw)


# ------------------------------------------------------------------------------------------
# TS67 Fig. 7: G/cos(theta) in the plane of incidence (docs/models.md §2.7 table)
# ------------------------------------------------------------------------------------------
FIG7_THETA = [-89.9, -80, -60, -45, -30, 0, 30, 45, 60, 75, 80, 85, 89.9]
FIG7 = {  # psi -> G/cos(theta) at FIG7_THETA (negative theta = phi 180 deg)
    0: [2.000, 2.000, 2.000, 1.414, 1.155, 1.000, 1.155, 1.414, 2.000, 2.000, 2.000, 2.000, 2.000],
    30: [1.156, 1.266, 1.464, 1.414, 1.155, 1.000, 1.155, 1.414, 2.000, 3.035, 3.160, 3.302, 3.461],
    45: [0.830, 0.968, 1.228, 1.414, 1.155, 1.000, 1.155, 1.414, 2.000, 3.864, 4.131, 4.447, 4.820],
    60: [0.538, 0.695, 1.000, 0.868, 0.845, 1.000, 1.155, 1.414, 2.000, 3.864, 5.759, 6.493, 7.442],
    75: [0.265, 0.433, 0.400, 0.379, 0.394, 0.518, 0.907, 1.414, 2.000, 3.864, 5.759, 11.474,
         15.093],
}


@pytest.mark.parametrize("psi", sorted(FIG7))
def test_ts67_fig7_g_over_cos_table(psi):
    theta_r, phi = rb.geometry.from_signed_angle(deg(FIG7_THETA))
    got = rb.shadowing.g_over_cos_r(deg(psi), theta_r, phi)
    np.testing.assert_allclose(got, FIG7[psi], atol=1e-3)  # the table has 3 decimals


@pytest.mark.parametrize("psi, limit", [(30, 3.4641), (60, 7.4641), (75, 15.1915)])
def test_ts67_fig7_grazing_forward_limit(psi, limit):
    # docs/models.md §2.7: grazing forward limit 2 cot((90 deg - psi)/2), exactly at theta = 90 deg
    assert rb.shadowing.g_over_cos_r(deg(psi), math.pi / 2, 0.0) == pytest.approx(limit, abs=1e-4)
    assert limit == pytest.approx(2 / math.tan(deg(90 - psi) / 2), abs=1e-4)


@pytest.mark.parametrize("psi, phi, limit", [(75, 0, 15.1915), (75, 45, 1.6330),
                                             (60, 120, 0.6978)])
def test_ts67_eq22_grazing_limit_out_of_plane(psi, phi, limit):
    # docs/models.md §2.5: lim_{theta -> 90 deg} G/cos(theta) = 2 cos(theta_h)/cos(theta_d), checked
    # for these (psi, phi) pairs; the per-branch evaluation reaches it without 0/0 ...
    at_90 = rb.shadowing.g_over_cos_r(deg(psi), math.pi / 2, deg(phi))
    assert at_90 == pytest.approx(limit, abs=1e-4)
    # ... and it is the limit of the values just below the horizon (continuity)
    near = rb.shadowing.g_over_cos_r(deg(psi), math.pi / 2 - 1e-7, deg(phi))
    assert near == pytest.approx(at_90, rel=1e-5)


@pytest.mark.parametrize("psi", [10, 20, 30, 40, 45])
def test_ts67_fig7_back_peak_small_psi(psi):
    # docs/models.md §2.7: backward local maximum at theta = (psi - 180)/3 with value
    # 1/cos((180 - psi)/3) for psi <= 45 deg (e.g. psi = 30 -> -50 deg, 1.5557)
    theta = np.linspace(-89.9, 0, 8991)
    tr, ph = rb.geometry.from_signed_angle(deg(theta))
    g = rb.shadowing.g_over_cos_r(deg(psi), tr, ph)
    i = int(np.argmax(g))
    assert theta[i] == pytest.approx((psi - 180) / 3, abs=0.02)
    # the maximum is a cusp (Eq. 18 boundary): evaluate exactly there
    peak = rb.shadowing.g_over_cos_r(deg(psi), deg((180 - psi) / 3), math.pi)
    assert peak == pytest.approx(1 / math.cos(deg((180 - psi) / 3)), abs=1e-9)
    assert peak >= g.max() - 1e-12
    if psi == 30:
        assert peak == pytest.approx(1.5557, abs=1e-4)  # the example quoted in docs/models.md


@pytest.mark.parametrize("psi", [45, 60, 75])
def test_ts67_fig7_back_peak_at_retro_large_psi(psi):
    # docs/models.md §2.7: for psi >= 45 deg the back maximum is at the retro direction,
    # value 2 cos psi
    theta = np.linspace(-89.9, 0, 8991)
    tr, ph = rb.geometry.from_signed_angle(deg(theta))
    g = rb.shadowing.g_over_cos_r(deg(psi), tr, ph)
    i = int(np.argmax(g))
    assert theta[i] == pytest.approx(-psi, abs=0.02)
    assert g[i] == pytest.approx(2 * math.cos(deg(psi)), abs=1e-4)


# ------------------------------------------------------------------------------------------
# TS67 Fig. 8: Eq. 23 with F = 1, g = 2/3, c = 0.05/deg (docs/models.md §2.7 table and fine rows)
# ------------------------------------------------------------------------------------------
FIG8 = {  # psi: (theta of forward max, ratio at max, at theta 0, at 89.99, at -60)
    10: (13.3, 1.002, 0.970, 0.610, 0.627),
    30: (43.0, 1.031, 0.762, 0.678, 0.533),
    45: (75.0, 1.318, 0.543, 0.979, 0.429),
    60: (80.0, 1.904, 0.311, 1.819, 0.273),
    75: (89.99, 3.19, 0.095, 3.194, 0.091),  # "-> 90 deg (grazing)"
}


@pytest.mark.parametrize("psi", sorted(FIG8))
def test_ts67_fig8_peaks_and_ratios(ts_fig8, psi):
    th_max, r_max, r_0, r_graz, r_back = FIG8[psi]
    theta = np.arange(0.0, 89.99 + 1e-9, 0.01)
    ratio = ts_fig8.relative(deg(psi), deg(theta), 0.0)
    i = int(np.argmax(ratio))
    assert theta[i] == pytest.approx(th_max, abs=0.05)  # peak positions quoted to 0.1 deg
    assert ratio[i] == pytest.approx(r_max, abs=0.5 * 10 ** -(len(str(r_max).split(".")[1])))
    assert ts_fig8.relative(deg(psi), 0.0, 0.0) == pytest.approx(r_0, abs=1e-3)
    assert ts_fig8.relative(deg(psi), deg(89.99), 0.0) == pytest.approx(r_graz, abs=1e-3)
    assert ts_fig8.relative(deg(psi), deg(60), math.pi) == pytest.approx(r_back, abs=1e-3)


def test_ts67_fig8_peaks_grow_with_psi(ts_fig8):
    # docs/models.md §2.7, qualitative target stated by the paper: peaks grow with psi
    theta = deg(np.linspace(0, 89.99, 9000))
    peaks = [np.max(ts_fig8.relative(deg(p), theta, 0.0)) for p in (10, 30, 45, 60, 75)]
    assert np.all(np.diff(peaks) > 0)


def test_ts67_fig8_psi75_peak_at_89_deg(ts_fig8):
    # docs/models.md §2.7: "3.19 (3.06 at 89 deg)"
    assert ts_fig8.relative(deg(75), deg(89), 0.0) == pytest.approx(3.06, abs=5e-3)


@pytest.mark.parametrize("psi, thetas, expected", [
    (75, [30, 45, 60, 70, 75, 80, 85, 89], [0.151, 0.281, 0.500, 0.768, 1.000, 1.425, 2.626,
                                            3.059]),
    (45, [60, 70, 75, 80, 85, 89], [1.131, 1.228, 1.318, 1.205, 1.090, 1.000]),
])
def test_ts67_fig8_fine_rows(ts_fig8, psi, thetas, expected):
    got = ts_fig8.relative(deg(psi), deg(thetas), 0.0)
    np.testing.assert_allclose(got, expected, atol=1e-3)


def test_ts67_relative_is_one_at_specular(ts_fig8):
    # Eq. 23 is normalized by the specular value (docs/models.md §2.3), for any psi and F
    psi = deg(np.array([0.0, 10, 45, 80, 89]))
    assert np.allclose(ts_fig8.relative(psi, psi, 0.0), 1.0, rtol=1e-14)
    al = rb.model("ts67", g=2 / 3, c=0.05, n=0.77, k=6.08, rho_d=0.3)
    assert np.allclose(al.relative(psi, psi, 0.0), 1.0, rtol=1e-14)


# ------------------------------------------------------------------------------------------
# TS67 Figs. 10/11: out of the plane, psi = 75, theta = 80 (docs/models.md §2.7)
# ------------------------------------------------------------------------------------------
FIG10_PHI = [0, 30, 60, 90, 120, 150, 180]


def test_ts67_fig10_g_over_cos_phi_row():
    got = rb.shadowing.g_over_cos_r(deg(75), deg(80), deg(FIG10_PHI))
    np.testing.assert_allclose(got, [5.759, 3.911, 1.519, 0.828, 0.569, 0.463, 0.433], atol=1e-3)


def test_ts67_fig10_ratio_confined_to_plane(ts_fig8):
    got = ts_fig8.relative(deg(75), deg(80), deg(FIG10_PHI))
    assert got[0] == pytest.approx(1.425, abs=1e-3)
    # "then ~0.091-0.093 for phi >= 30 deg": the peak is confined to the plane of incidence
    assert np.all((got[1:] > 0.0905) & (got[1:] < 0.0935))


def test_ts67_absolute_matches_eq12_form():
    # brdf() is (rho_d/pi)[g F G exp(-c^2 a^2)/(cos i cos r) + 1] (docs/models.md §2.3), written out
    # here with the library's independent parts (V-groove G and the complex Fresnel)
    g, c, n, k, rho = 2.0, 0.05, 1.74, 0.3, 0.4
    ts = rb.model("ts67", g=g, c=c, n=n, k=k, rho_d=rho)
    rng = np.random.default_rng(1)
    ti = rng.uniform(0, deg(85), 200)
    tr = rng.uniform(0, deg(85), 200)
    ph = rng.uniform(-np.pi, np.pi, 200)
    th = rb.geometry.theta_h(ti, tr, ph)
    td = rb.geometry.theta_d(ti, tr, ph)
    gg = rb.shadowing.v_groove(ti, tr, ph)
    f = rb.fresnel.reflectance(np.cos(td), n, k)
    expected = rho / np.pi * (g * f * gg * np.exp(-(c * np.degrees(th)) ** 2)
                              / (np.cos(ti) * np.cos(tr)) + 1)
    np.testing.assert_allclose(ts.brdf(ti, tr, ph), expected, rtol=1e-12)
    # bridf = brdf cos(theta_r) (DESIGN.md quantities)
    np.testing.assert_allclose(ts.bridf(ti, tr, ph), expected * np.cos(tr), rtol=1e-12)


def test_ts67_finite_at_horizon_and_matches_limit(ts_fig8):
    # TS67 stays finite at theta_r = 90 deg via the per-branch G/cos (issue: "No NaN")
    ti = deg(np.array([0.0, 30, 60, 75, 85]))
    at = ts_fig8.brdf(ti, math.pi / 2, 0.0)
    near = ts_fig8.brdf(ti, math.pi / 2 - 1e-8, 0.0)
    assert np.all(np.isfinite(at))
    np.testing.assert_allclose(at, near, rtol=1e-6)


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


# ------------------------------------------------------------------------------------------
# the public names of DESIGN.md ("Public interface") and their behaviour
# ------------------------------------------------------------------------------------------
def test_design_public_interface():
    m = rb.model("trowbridge-reitz-1975", e=0.68, n=1.0, k=0.9, rho_L=0.33)
    assert rb.model("Trowbridge-Reitz-1975", e=0.68).params == rb.model("TR75", e=0.68).params
    assert m.params == {"e": 0.68, "n": 1.0, "k": 0.9, "rho_L": 0.33}
    p = {q.name: q for q in m.parameters}
    assert set(p) == {"e", "n", "k", "rho_L"}
    assert all(hasattr(q, a) for q in p.values()
               for a in ("name", "value", "bounds", "unit", "description"))
    ti, tr, ph = np.radians([30.0, 50.0]), np.radians([20.0, 60.0]), np.radians([10.0, 170.0])
    f = m.brdf(ti, tr, ph)
    np.testing.assert_allclose(m.bridf(ti, tr, ph), f * np.cos(tr), rtol=1e-13)
    assert np.all(m.brdf(ti, tr, ph, polarization=0.0) > 0)
    assert np.all(m.brdf(ti, tr, ph, polarization="s") > 0)
    ts = rb.model("torrance-sparrow-1967", g=2 / 3, c=0.05, n=None, k=None, rho_d=0.3)
    assert ts.relative(deg(75), deg(75), 0.0) == pytest.approx(1.0)
    assert isinstance(rb.model("lambertian", rho=0.5), rb.Model)
    mf = rb.model("microfacet", distribution="trowbridge-reitz", alpha=0.3, shadowing="smith",
                  n=1.5, k=3.0)
    assert mf.options == {"distribution": "trowbridge-reitz",
                          "shadowing": "smith-height-correlated"}
    total = m + rb.model("lambertian", rho=0.1)
    assert set(total.params) == {"tr75_e", "tr75_n", "tr75_k", "tr75_rho_L", "lambertian_rho"}
    np.testing.assert_allclose(total.brdf(ti, tr, ph), f + 0.1 / np.pi, rtol=1e-13)
    assert set((m + m).params) == {"tr751_e", "tr751_n", "tr751_k", "tr751_rho_L", "tr752_e",
                                   "tr752_n", "tr752_k", "tr752_rho_L"}
    assert total.with_params(lambertian_rho=0.2).params["lambertian_rho"] == 0.2
    assert rb.fresnel.reflectance(1.0, 1.5, k=0.0, polarization="unpolarized") == \
        pytest.approx(0.04)
    assert rb.distributions.trowbridge_reitz(1.0, 0.5) == pytest.approx(1 / (np.pi * 0.25))
    assert rb.distributions.beckmann(1.0, 0.5) == pytest.approx(1 / (np.pi * 0.25))
    assert rb.distributions.gaussian_angle(0.0, 0.05) == pytest.approx(2.8316, abs=5e-5)
    assert rb.shadowing.v_groove(deg(30), deg(30), 0.0) == 1.0
    assert rb.albedo(rb.model("lambertian", rho=0.5), 0.3) == pytest.approx(0.5)


@pytest.mark.parametrize("typo, suggestion", [
    ("trowbridge-reits-1975", "trowbridge-reitz-1975"),
    ("torrance-sparow-1967", "torrance-sparrow-1967"),
    ("lambertain", "lambertian"),
    ("microfacit", "microfacet"),
])
def test_unknown_model_suggests_close_match(typo, suggestion):
    with pytest.raises(ValueError, match=rf"unknown model '{typo}'.*did you mean '{suggestion}'"):
        rb.model(typo)


@pytest.mark.parametrize("name, kw, param", [
    ("tr75", {"e": 0.0}, "e"), ("tr75", {"e": -0.3}, "e"), ("tr75", {"k": -0.1}, "k"),
    ("ts67", {"c": 0.0}, "c"), ("ts67", {"c": -0.05}, "c"), ("ts67", {"n": 1.5, "k": -1.0}, "k"),
    ("microfacet", {"alpha": 0.0}, "alpha"), ("microfacet", {"k": -2.0}, "k"),
    ("tr75", {"e": math.nan}, "e"), ("tr75", {"rho_L": 1.5}, "rho_L"),
])
def test_invalid_parameters_raise_naming_them(name, kw, param):
    with pytest.raises(ValueError) as exc:
        rb.model(name, **kw)
    assert repr(param) in str(exc.value) and repr(kw[param]) in str(exc.value)


def test_unknown_parameter_names_raise():
    with pytest.raises(ValueError, match=r"unknown parameter .*'ee'.*did you mean 'e'"):
        rb.model("tr75", ee=0.5)
    with pytest.raises(ValueError, match="unknown parameter"):
        rb.model("tr75").with_values(["rho_l"], [0.2])
    with pytest.raises(ValueError, match="unknown parameter"):
        (rb.model("tr75") + rb.model("lambertian")).with_params(tr75_x=1.0)
