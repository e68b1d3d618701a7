"""The specular frame in ``rb.geometry``: (radial, azimuth) about the specular direction <->
the common frame's (theta_r, phi), the frame of Zemax's tabular BSDF files.

Oracle: the definition in docs/export.md (and ``roughbrdf.geometry_frames``), written out
with NumPy vectors: ``w = cos r s + sin r (cos a u0 + sin a v)``, ``s = (sin t, 0, cos t)``,
``u0 = (-cos t, 0, sin t)`` (toward the normal), ``v = s x u0 = (0, -1, 0)``.
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
INCIDENCE = st.floats(0.0, 1.5)
RADIAL = st.floats(0.0, math.pi)
AZIMUTH = st.floats(0.0, 2 * math.pi)


def direction(theta, phi):
    """The common frame's unit vector of (zenith, azimuth)."""
    theta, phi = np.asarray(theta, float), np.asarray(phi, float)
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)],
                    axis=-1)


def by_definition(t, r, a):
    """The scattered direction at radial ``r``, azimuth ``a`` about the specular direction of
    incidence ``t``, from docs/export.md."""
    s = np.array([math.sin(t), 0.0, math.cos(t)])
    u0 = np.array([-math.cos(t), 0.0, math.sin(t)])
    v = np.cross(s, u0)
    return math.cos(r) * s + math.sin(r) * (math.cos(a) * u0 + math.sin(a) * v)


def test_the_conversions_live_in_geometry_and_the_format_uses_them():
    from roughbrdf.io import zemax

    assert "specular_to_common" in G.__all__ and "common_to_specular" in G.__all__
    assert zemax.specular_to_common is G.specular_to_common
    assert zemax.common_to_specular is G.common_to_specular


@settings(max_examples=200, deadline=None)
@given(t=INCIDENCE, r=RADIAL, a=AZIMUTH)
def test_specular_to_common_is_the_definition(t, r, a):
    theta_r, phi, cos_theta_r = G.specular_to_common(t, r, a)
    w = by_definition(t, r, a)
    assert float(cos_theta_r) == pytest.approx(w[2], abs=1e-12)   # below the horizon too
    assert np.allclose(direction(theta_r, phi), w, atol=1e-12)
    assert 0.0 <= float(theta_r) <= math.pi and -math.pi <= float(phi) <= math.pi


@pytest.mark.parametrize("t", [0.0, 0.2, 0.7, 1.4])
def test_the_specular_direction_is_radial_zero(t):
    # radial 0 is the specular direction (theta_r = theta_i, phi = 0) at every azimuth
    for a in (0.0, 1.0, math.pi, 5.0):
        theta_r, phi, cz = G.specular_to_common(t, 0.0, a)
        assert float(theta_r) == pytest.approx(t, abs=1e-15)
        assert float(phi) == pytest.approx(0.0, abs=1e-15)
        assert float(cz) == pytest.approx(math.cos(t), abs=1e-15)
    radial, _ = G.common_to_specular(t, t, 0.0)   # and back: radial 0 (azimuth moot there)
    assert float(radial) == pytest.approx(0.0, abs=1e-15)


def test_azimuth_zero_points_toward_the_normal_and_90_to_negative_phi():
    t = math.radians(35)
    theta_r, _, _ = G.specular_to_common(t, t, 0.0)           # radial t toward the normal
    assert float(theta_r) == pytest.approx(0.0, abs=1e-12)
    theta_r, phi, _ = G.specular_to_common(t, 0.1, HALF_PI)   # azimuth 90: v = (0, -1, 0)
    assert float(phi) < 0
    theta_r, phi, _ = G.specular_to_common(0.0, 0.3, 0.0)     # normal incidence: source side
    assert float(theta_r) == pytest.approx(0.3) and abs(float(phi)) == pytest.approx(math.pi)
    radial, azimuth = G.common_to_specular(t, 0.0, 0.0)       # the normal: radial t, azimuth 0
    assert float(radial) == pytest.approx(t, abs=1e-12)
    assert float(azimuth) == pytest.approx(0.0, abs=1e-12)


@settings(max_examples=200, deadline=None)
@given(t=INCIDENCE, r=RADIAL, a=AZIMUTH)
def test_radial_is_the_angle_from_the_specular_direction(t, r, a):
    theta_r, phi, _ = G.specular_to_common(t, r, a)
    cosang = float(np.dot(direction(theta_r, phi), direction(t, 0.0)))
    assert math.acos(min(1.0, max(-1.0, cosang))) == pytest.approx(r, abs=1e-7)


@settings(max_examples=200, deadline=None)
@given(t=INCIDENCE, r=st.floats(1e-6, math.pi - 1e-6), a=AZIMUTH)
def test_round_trip_specular_common_specular(t, r, a):
    theta_r, phi, _ = G.specular_to_common(t, r, a)
    radial, azimuth = G.common_to_specular(t, theta_r, phi)
    assert float(radial) == pytest.approx(r, abs=1e-9)
    # [0, 2 pi]: numpy.mod of an azimuth a hair below 0 rounds to 2 pi itself (the same
    # direction as 0; the Zemax code this conversion came from does the same)
    assert 0.0 <= float(azimuth) <= 2 * math.pi
    if math.sin(r) > 1e-6:  # the azimuth is moot at radial 0 and pi
        assert abs(np.angle(np.exp(1j * (float(azimuth) - a)))) < 1e-6


@settings(max_examples=200, deadline=None)
@given(ti=st.floats(0.0, HALF_PI), tr=st.floats(0.0, HALF_PI), ph=st.floats(-math.pi, math.pi))
def test_round_trip_common_specular_common(ti, tr, ph):
    radial, azimuth = G.common_to_specular(ti, tr, ph)
    assume(float(radial) > 1e-9)
    theta_r, phi, cz = G.specular_to_common(ti, radial, azimuth)
    assert np.allclose(direction(theta_r, phi), direction(tr, ph), atol=1e-12)
    assert float(cz) >= -1e-12   # a direction above the horizon stays above it


def test_arrays_broadcast_like_numpy():
    t = np.radians([0.0, 30.0])[:, None, None]
    a = np.radians([0.0, 90.0, 180.0])[None, :, None]
    r = np.radians([0.0, 10.0, 20.0, 30.0])[None, None, :]
    theta_r, phi, cz = G.specular_to_common(t, r, a)
    assert theta_r.shape == phi.shape == cz.shape == (2, 3, 4)
    for i, j, k in np.ndindex(2, 3, 4):
        one = G.specular_to_common(float(t[i, 0, 0]), float(r[0, 0, k]), float(a[0, j, 0]))
        assert (float(one[0]), float(one[1]), float(one[2])) == (
            theta_r[i, j, k], phi[i, j, k], cz[i, j, k])
