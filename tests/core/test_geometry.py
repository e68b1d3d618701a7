"""Geometry: the common frame (docs/models.md §1.1), conversions to each paper's angles (§1.3) as
round trips, and the derived angles (theta_h, theta_d, phi_h, TS67 psi_p/theta_p, TR75 eta).

Oracles: the unit vectors of §1.1 and §3.1 written out with NumPy, the identities quoted in
docs/models.md, and the printed TS67 Eq. 14 / TR75 Eqs. 16-17 where they are valid.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import roughbrdf as rb

G = rb.geometry
HALF_PI = math.pi / 2
ZEN = st.floats(0.0, HALF_PI)
AZ = st.floats(-math.pi, math.pi)


def wrap(phi):
    """Azimuth difference wrapped to (-pi, pi]."""
    return (np.asarray(phi) + np.pi) % (2 * np.pi) - np.pi


def same_direction(t1, p1, t2, p2, atol=1e-9):
    """Directions (zenith, azimuth) agree as unit vectors (azimuth is moot at the pole)."""
    v1 = np.array([np.sin(t1) * np.cos(p1), np.sin(t1) * np.sin(p1), np.cos(t1)])
    v2 = np.array([np.sin(t2) * np.cos(p2), np.sin(t2) * np.sin(p2), np.cos(t2)])
    return np.allclose(v1, v2, atol=atol)


# ------------------------------------------------------------------------------------------
# round trips (Hypothesis)
# ------------------------------------------------------------------------------------------
@settings(max_examples=100, deadline=None)
@given(ti=ZEN, tr=ZEN, ph=AZ)
def test_round_trip_ts67(ti, tr, ph):
    # TS67's (psi, theta, phi) is the common frame (docs/models.md §1.3)
    psi, theta, phi = G.to_ts67(ti, tr, ph)
    assert (psi, theta, phi) == (ti, tr, ph)
    assert tuple(map(float, G.from_ts67(psi, theta, phi))) == (ti, tr, ph)


@settings(max_examples=100, deadline=None)
@given(ti=ZEN, tr=ZEN, ph=AZ)
def test_round_trip_tr75(ti, tr, ph):
    beta, elev, psi = G.to_tr75(ti, tr, ph)
    assert beta == ti and elev == pytest.approx(HALF_PI - tr, abs=1e-15)
    assert 0 <= psi < 2 * math.pi
    ti2, tr2, ph2 = G.from_tr75(beta, elev, psi)
    assert ti2 == ti and tr2 == pytest.approx(tr, abs=1e-15)
    assert abs(wrap(ph2 - ph)) < 1e-12


@settings(max_examples=100, deadline=None)
@given(beta=ZEN, elev=ZEN, psi=st.floats(0, 2 * math.pi))
def test_tr75_vectors(beta, elev, psi):
    # TR75 Eqs. 9 and 11 (j-k plane of incidence, psi = 0 toward the source) map to the common
    # frame's w_i and w_r: (x, y, z)_common = (-j, i, k)_TR75
    l = np.array([0.0, math.sin(beta), math.cos(beta)])
    r = np.array([math.sin(psi) * math.cos(elev), math.cos(psi) * math.cos(elev), math.sin(elev)])
    to_common = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    ti, tr, ph = G.from_tr75(beta, elev, psi)
    wi, wr = G.unit_vectors(ti, tr, ph)
    np.testing.assert_allclose(wi, to_common @ l, atol=1e-12)
    np.testing.assert_allclose(wr, to_common @ r, atol=1e-12)


@settings(max_examples=100, deadline=None)
@given(ti=ZEN, tr=ZEN, ph=AZ)
def test_round_trip_rb08(ti, tr, ph):
    # RB08 direction cosines alpha = sin(theta_s) cos(phi), beta = sin(theta_s) sin(phi),
    # alpha0 = sin(theta_i) (docs/models.md §1.3/§4.3); specular point (alpha0, 0)
    a, b, a0 = G.to_rb08(ti, tr, ph)
    assert a0 == pytest.approx(math.sin(ti), abs=1e-15)
    assert math.hypot(a, b) == pytest.approx(math.sin(tr), abs=1e-15)
    ti2, tr2, ph2 = G.from_rb08(a, b, a0)
    assert ti2 == pytest.approx(ti, abs=2e-8)  # arcsin near pi/2 loses half the digits
    assert same_direction(tr2, ph2, tr, ph, atol=1e-9)


def test_rb08_specular_and_retro_points():
    a, b, a0 = G.to_rb08(0.4, 0.4, 0.0)
    assert (a, b) == pytest.approx((a0, 0.0))
    a, b, a0 = G.to_rb08(0.4, 0.4, math.pi)
    assert (a, b) == pytest.approx((-a0, 0.0), abs=1e-15)
    with pytest.raises(ValueError, match="unit disk"):
        G.from_rb08(0.9, 0.9, 0.1)
    with pytest.raises(ValueError, match="alpha0"):
        G.from_rb08(0.1, 0.1, 1.5)


@settings(max_examples=200, deadline=None)
@given(ti=ZEN, tr=ZEN, ph=AZ)
def test_round_trip_rusinkiewicz(ti, tr, ph):
    wi, wr = G.unit_vectors(ti, tr, ph)
    assume(np.linalg.norm(wi + wr) > 1e-6)  # w_i = -w_r has no half vector
    th, td, pd = G.to_rusinkiewicz(ti, tr, ph)
    # theta_h and theta_d agree with the library's derived angles
    assert th == pytest.approx(float(G.theta_h(ti, tr, ph)), abs=1e-7)
    assert td == pytest.approx(float(G.theta_d(ti, tr, ph)), abs=1e-7)
    ti2, tr2, ph2 = G.from_rusinkiewicz(th, td, pd)
    # an isotropic geometry is fixed by theta_i, theta_r and the angle between w_i and w_r
    # (at theta_i = 0 the azimuth itself is arbitrary)
    assert ti2 == pytest.approx(ti, abs=1e-7)
    assert tr2 == pytest.approx(tr, abs=1e-7)
    wi2, wr2 = G.unit_vectors(ti2, tr2, ph2)
    assert float(np.dot(wi2, wr2)) == pytest.approx(float(np.dot(wi, wr)), abs=1e-7)


def test_rusinkiewicz_below_horizon_is_nan():
    ti, tr, ph = G.from_rusinkiewicz(1.4, 1.0, 0.0)
    assert np.isnan(ti) and np.isnan(tr) and np.isnan(ph)


@settings(max_examples=100, deadline=None)
@given(ti=ZEN, tr=ZEN, ph=AZ, rot=AZ)
def test_round_trip_vectors(ti, tr, ph, rot):
    # unit vectors -> angles, also after rotating the pair about z (isotropy)
    wi, wr = G.unit_vectors(ti, tr, ph)
    np.testing.assert_allclose(np.linalg.norm(wi, axis=-1), 1.0)
    np.testing.assert_allclose(wi, [-math.sin(ti), 0, math.cos(ti)], atol=1e-15)
    c, s = math.cos(rot), math.sin(rot)
    rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    ti2, tr2, ph2 = G.angles_from_vectors(rz @ wi, rz @ wr)
    assert ti2 == pytest.approx(ti, abs=1e-7) and tr2 == pytest.approx(tr, abs=1e-7)
    if 1e-6 < ti < HALF_PI and tr > 1e-6:
        assert abs(wrap(ph2 - ph)) < 1e-7


@settings(max_examples=50, deadline=None)
@given(t=st.floats(-HALF_PI, HALF_PI))
def test_round_trip_signed_angle(t):
    tr, ph = G.from_signed_angle(t)
    assert float(G.signed_angle(tr, ph)) == (t if t != 0 else 0.0) or t == 0
    assert tr == abs(t) and ph in (0.0, math.pi)


# ------------------------------------------------------------------------------------------
# derived angles
# ------------------------------------------------------------------------------------------
def random_geometry(n=20000, seed=0):
    rng = np.random.default_rng(seed)
    return (rng.uniform(0, HALF_PI, n), rng.uniform(0, HALF_PI, n),
            rng.uniform(-np.pi, np.pi, n))


def test_half_and_difference_angles_match_vectors():
    ti, tr, ph = random_geometry()
    wi, wr = G.unit_vectors(ti, tr, ph)
    s = wi + wr
    h = s / np.linalg.norm(s, axis=-1, keepdims=True)
    np.testing.assert_allclose(np.cos(G.theta_h(ti, tr, ph)), h[..., 2], atol=1e-12)
    np.testing.assert_allclose(np.cos(G.theta_d(ti, tr, ph)), np.sum(wi * h, -1), atol=1e-12)
    # docs/models.md §1.1: cos 2 theta_d = w_i.w_r and cos th = (cos ti + cos tr)/(2 cos td)
    td = G.theta_d(ti, tr, ph)
    np.testing.assert_allclose(np.cos(2 * td), np.cos(ti) * np.cos(tr)
                               - np.sin(ti) * np.sin(tr) * np.cos(ph), atol=1e-12)
    np.testing.assert_allclose(np.cos(G.theta_h(ti, tr, ph)),
                               (np.cos(ti) + np.cos(tr)) / (2 * np.cos(td)), rtol=1e-10)
    ph_h = G.phi_h(ti, tr, ph)
    ok = np.hypot(h[..., 0], h[..., 1]) > 1e-9
    np.testing.assert_allclose(wrap(ph_h[ok] - np.arctan2(h[ok, 1], h[ok, 0])), 0, atol=1e-9)


def test_specular_and_retro():
    t = np.radians(np.array([0.0, 1e-6, 10, 45, 80, 89.9999]))
    np.testing.assert_allclose(G.theta_h(t, t, 0.0), 0.0, atol=1e-14)  # specular: h = z
    np.testing.assert_allclose(G.theta_d(t, t, 0.0), t, atol=1e-14)
    np.testing.assert_allclose(G.theta_d(t, t, np.pi), 0.0, atol=1e-14)  # retro: h = w_i
    np.testing.assert_allclose(G.theta_h(t, t, np.pi), t, atol=1e-14)
    # theta_i = theta_r = 90 deg at phi = 0 is w_i = -w_r: no half vector (documented in
    # geometry.half_vector); the functions still return finite angles there
    assert np.isfinite(G.theta_h(HALF_PI, HALF_PI, 0.0))


@settings(max_examples=200, deadline=None)
@given(ti=ZEN, tr=ZEN, ph=AZ)
def test_ts67_projected_angles(ti, tr, ph):
    # docs/models.md §2.4: psi_p >= 0, theta_p = psi_p + 2 alpha_s, |alpha_s| = theta_h, and the
    # projections of w_i and w_r on the plane (z, u) are mirror images about h
    from roughbrdf.geometry import ts67_projected

    # not the forward grazing pair w_i = -w_r (no half vector; cosines < 1e-15 count as 0)
    assume(not (math.cos(ti) < 1e-15 and math.cos(tr) < 1e-15 and math.cos(ph) > 0.5))
    psi_p, theta_p, alpha_s = ts67_projected(ti, tr, ph)
    assert psi_p >= 0
    assert theta_p == pytest.approx(psi_p + 2 * alpha_s, abs=1e-9)
    assert abs(alpha_s) == pytest.approx(float(G.theta_h(ti, tr, ph)), abs=1e-7)
    assert -HALF_PI - 1e-12 <= theta_p <= HALF_PI + 1e-12


def test_ts67_projected_in_plane_eq15():
    # docs/models.md §2.4 Eq. 15: in the plane of incidence psi_p = psi, theta_p = theta (signed)
    psi = np.radians(np.array([10.0, 30, 45, 60, 75]))
    for th in np.radians([-80.0, -30, 0, 20, 60, 85]):
        tr, ph = G.from_signed_angle(th)
        np.testing.assert_allclose(G.ts67_psi_p(psi, tr, ph), psi, atol=1e-12)
        np.testing.assert_allclose(G.ts67_theta_p(psi, tr, ph), th, atol=1e-12)


def test_ts67_printed_eq14_where_valid():
    # docs/models.md §2.4: the printed Eq. 14 (with |psi_p|) agrees with the vector recipe wherever
    # its arcsin branches are valid (beta1 acute: the receiver not beyond the source)
    ti, tr, ph = random_geometry(5000, 3)
    ti, tr, ph = ti[ti > 0.05], tr[ti > 0.05], ph[ti > 0.05]
    psi1 = 0.5 * np.arccos(np.cos(tr) * np.cos(ti) - np.sin(tr) * np.sin(ti) * np.cos(ph))
    beta1 = np.arcsin(np.clip(np.sin(ph) * np.sin(tr) / np.sin(2 * psi1), -1, 1))
    alpha = np.arccos(np.clip(np.cos(ti) * np.cos(psi1)
                              + np.sin(ti) * np.sin(psi1) * np.cos(beta1), -1, 1))
    beta2 = np.pi - np.arcsin(np.clip(np.sin(beta1) * np.sin(psi1) / np.sin(alpha), -1, 1))
    psi_p = np.abs(np.arctan(np.cos(beta2) * np.tan(ti)))
    th = G.theta_h(ti, tr, ph)
    valid = (np.abs(alpha - th) < 1e-9) & (np.sin(alpha) > 1e-3) & (np.abs(np.sin(beta1)) < 0.99)
    assert valid.mean() > 0.5  # most random geometries
    np.testing.assert_allclose(G.ts67_psi_p(ti, tr, ph)[valid], psi_p[valid], atol=1e-7)


def test_tr75_eta_and_eqs_16_17():
    # TR75 Eq. 16 (azimuth z of the micro-normal from the source side), Eq. 17 (cos s) and
    # Eq. 23 (cos eta), in TR75's own angles converted with from_tr75 (docs/models.md §3.1, §3.5)
    rng = np.random.default_rng(4)
    beta = rng.uniform(0.01, 1.5, 3000)
    elev = rng.uniform(0.01, 1.5, 3000)
    psi = rng.uniform(0, 2 * np.pi, 3000)
    ti, tr, ph = G.from_tr75(beta, elev, psi)
    alpha = G.theta_h(ti, tr, ph)
    s = G.theta_d(ti, tr, ph)
    z = np.arctan2(np.sin(psi) * np.cos(elev), np.sin(beta) + np.cos(psi) * np.cos(elev))
    cos_s = np.cos(z) * np.sin(alpha) * np.sin(beta) + np.cos(alpha) * np.cos(beta)  # Eq. 17
    np.testing.assert_allclose(np.cos(s), cos_s, atol=1e-10)
    # phi_h = pi - z (docs/models.md §1.3)
    ok = np.sin(alpha) > 1e-6
    np.testing.assert_allclose(wrap(G.phi_h(ti, tr, ph)[ok] - (np.pi - z[ok])), 0, atol=1e-8)
    eta = G.tr75_eta(ti, tr, ph)
    cos_eta = (np.sin(beta) * np.cos(alpha) - np.cos(beta) * np.cos(z) * np.sin(alpha)) / np.sin(s)
    sin_eta = np.sin(z) * np.sin(alpha) / np.sin(s)
    ok = np.sin(s) > 1e-6
    np.testing.assert_allclose(np.cos(eta[ok]), cos_eta[ok], atol=1e-8)
    np.testing.assert_allclose(np.sin(eta[ok]), sin_eta[ok], atol=1e-8)


def test_tr75_eta_zero_in_plane():
    t = np.radians(np.array([5.0, 30, 70]))
    np.testing.assert_allclose(G.tr75_eta(0.4, t, 0.0), 0.0, atol=1e-12)
    # backward half of the plane: the local plane is the macro plane, eta = 0 or pi (the same
    # polarization, Eq. 24 depends on sin^2(gamma - eta))
    np.testing.assert_allclose(np.sin(G.tr75_eta(0.4, t, np.pi)), 0.0, atol=1e-12)
    assert float(G.tr75_eta(0.4, 0.4, math.pi)) == 0.0  # s = 0 (retro): eta = 0


@pytest.mark.parametrize("fn", [G.theta_h, G.theta_d, G.phi_h, G.ts67_psi_p, G.ts67_theta_p,
                                G.tr75_eta])
def test_derived_angles_validate(fn):
    with pytest.raises(ValueError, match=r"theta_i.*-0\.2"):
        fn(-0.2, 0.3, 0.0)
    with pytest.raises(ValueError, match=r"theta_r.*nan"):
        fn(0.2, math.nan, 0.0)
    with pytest.raises(ValueError, match=r"phi.*inf"):
        fn(0.2, 0.3, math.inf)
    out = fn(np.zeros((2, 1)), np.full((1, 3), 0.3), 0.5)
    assert out.shape == (2, 3)


def test_check_zenith_messages():
    # ArgumentError: "<name> = <value> rad: <what is wrong>" (the CLI words it in degrees)
    with pytest.raises(ValueError, match=r"theta_i = 1\.5707963267948966 rad: must be in "
                                         r"\[0, pi/2\) "):
        G.check_zenith(HALF_PI, "theta_i", open_upper=True)
    assert G.check_zenith([0.0, HALF_PI], "x").tolist() == [0.0, HALF_PI]
    with pytest.raises(ValueError, match="x = 'abc': must be a number or an array of numbers"):
        G.check_zenith("abc", "x")
