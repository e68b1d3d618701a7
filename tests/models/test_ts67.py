"""Reproduction targets of Torrance & Sparrow (1967), TS67 (docs/models.md §2.7), computed by the
library: Figs. 7, 8, 10 and 11, the Eq. 12 form and the horizon.

Every expected number below comes from docs/models.md (the section is named at each table), which
quotes an independent NumPy/SciPy implementation of the specification, or from an identity
stated next to it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import roughbrdf as rb

deg = np.radians


@pytest.fixture(scope="module")
def ts_fig8():
    """TS67 as in Figs. 8, 10, 11: F = 1 (n=None), g = 2/3, c = 0.05 per degree."""
    return rb.model("torrance-sparrow-1967", g=2 / 3, c=0.05, n=None, k=None, rho_d=0.3)


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
    # TS67 stays finite at theta_r = 90 deg via the per-branch G/cos: no NaN at the horizon
    ti = deg(np.array([0.0, 30, 60, 75, 85]))
    at = ts_fig8.brdf(ti, math.pi / 2, 0.0)
    near = ts_fig8.brdf(ti, math.pi / 2 - 1e-8, 0.0)
    assert np.all(np.isfinite(at))
    np.testing.assert_allclose(at, near, rtol=1e-6)
