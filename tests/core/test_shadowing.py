"""Shadowing/masking: TS67 V-groove (Table I vs closed form, docs/models.md §2.5), per-branch
G/cos, Smith separable and height-correlated, the registry of names.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import roughbrdf as rb

S = rb.shadowing
HALF_PI = math.pi / 2


def random_geometry(n, seed):
    """Uniform on the closed hemisphere, out of the plane of incidence."""
    rng = np.random.default_rng(seed)
    return (rng.uniform(0, HALF_PI, n), rng.uniform(0, HALF_PI, n),
            rng.uniform(-np.pi, np.pi, n))


def test_table_i_equals_closed_form_random_out_of_plane():
    # docs/models.md §2.5/§6: Table I + Eq. 21 in projected angles == 3-D closed form, to 1e-10
    ti, tr, ph = random_geometry(200_000, 1)
    np.testing.assert_allclose(S.v_groove_table(ti, tr, ph), S.v_groove(ti, tr, ph), atol=1e-10,
                               rtol=0)


def test_table_i_equals_closed_form_in_plane_and_edges():
    # in the plane (phi = 0, pi), at normal incidence, at the Eq. 17-19 boundaries and grazing
    th = np.linspace(0, HALF_PI, 181)
    ti, tr = np.meshgrid(th, th, indexing="ij")
    # except theta_i = theta_r = 90 deg at phi = 0 (w_i = -w_r): no half vector, and the limits
    # differ by path (1 along the specular direction, 0 at grazing incidence); both forms
    # return a value in [0, 1] there
    forward_pair = (ti == HALF_PI) & (tr == HALF_PI)
    for ph in (0.0, np.pi, HALF_PI, 1e-9, np.pi - 1e-9):
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # no 0/0 in the compiled ufuncs
            table, closed = S.v_groove_table(ti, tr, ph), S.v_groove(ti, tr, ph)
        keep = ~forward_pair if ph == 0.0 else np.ones_like(forward_pair)
        np.testing.assert_allclose(table[keep], closed[keep], atol=1e-10, rtol=0)
        assert np.all((table >= 0) & (table <= 1) & (closed >= 0) & (closed <= 1))


@settings(max_examples=200, deadline=None)
@given(ti=st.floats(0, HALF_PI), tr=st.floats(0, HALF_PI), ph=st.floats(-np.pi, np.pi))
def test_table_i_equals_closed_form_property(ti, tr, ph):
    # (w_i = -w_r, theta_i = theta_r = 90 deg at phi = 0, has no half vector: see above)
    # (cosines below 1e-15 count as exactly grazing in the kernels)
    assume(not (math.cos(ti) < 1e-15 and math.cos(tr) < 1e-15 and math.cos(ph) > 0.5))
    assert S.v_groove_table(ti, tr, ph) == pytest.approx(S.v_groove(ti, tr, ph), abs=1e-10)


def test_v_groove_is_v_cavity_formula():
    # docs/models.md §2.5: G = min(1, 2 (z.h)(z.w_r)/(w_r.h), 2 (z.h)(z.w_i)/(w_r.h)) in vectors
    ti, tr, ph = random_geometry(20_000, 2)
    wi, wr = rb.geometry.unit_vectors(ti, tr, ph)
    h = wi + wr
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    zh, zi, zr = h[..., 2], wi[..., 2], wr[..., 2]
    rh = np.sum(wr * h, axis=-1)
    g = np.minimum(1, np.minimum(2 * zh * zr / rh, 2 * zh * zi / rh))
    np.testing.assert_allclose(S.v_groove(ti, tr, ph), g, atol=1e-12)


def test_v_groove_bounds_symmetry_and_specular():
    ti, tr, ph = random_geometry(50_000, 3)
    g = S.v_groove(ti, tr, ph)
    assert np.all((g >= 0) & (g <= 1))
    np.testing.assert_allclose(S.v_groove(tr, ti, ph), g, atol=1e-14)  # reciprocity of G
    np.testing.assert_array_equal(S.v_groove(ti, tr, -ph), g)
    # specular direction: facet normal = macro normal, G = 1 (DESIGN docstring example)
    np.testing.assert_array_equal(S.v_groove(ti, ti, 0.0), 1.0)
    # normal incidence and normal view: G = 1 ... and the horizon: G = 0 for grazing incidence
    assert float(S.v_groove(0.0, 0.0, 0.0)) == 1.0
    assert float(S.v_groove(HALF_PI, 0.3, 0.0)) == 0.0


def test_g21_limits():
    # docs/models.md §2.5: A = 0 at theta_p* = (psi_p + pi)/3 gives G = 1 (L'Hopital);
    # theta_p = pi/2 gives A = 1, G = 0; at theta_p = -psi_p masking and shadowing forms agree
    for psi in np.radians([0.0, 10, 30, 45, 60, 80]):
        assert S.g21(psi, (psi + math.pi) / 3) == pytest.approx(1.0, abs=1e-12)
        assert S.g21(psi, HALF_PI) == pytest.approx(0.0, abs=1e-7)
        assert S.g21(psi, -psi) == pytest.approx(S.g21(-psi, psi), abs=1e-12)


def test_g_over_cos_r_per_branch():
    # G/cos(theta_r) equals G / cos(theta_r) wherever that quotient is defined, and has the
    # masking-branch value 2 cos(theta_h)/cos(theta_d) at theta_r = 90 deg (docs/models.md §2.5)
    ti, tr, ph = random_geometry(50_000, 4)
    tr = np.minimum(tr, 1.5)
    np.testing.assert_allclose(S.g_over_cos_r(ti, tr, ph), S.v_groove(ti, tr, ph) / np.cos(tr),
                               rtol=1e-12)
    ti = np.radians(np.array([0.0, 20, 45, 70, 89]))
    ph = np.radians(np.array([0.0, 45, 90, 135, 180]))
    th = rb.geometry.theta_h(ti, HALF_PI, ph)
    td = rb.geometry.theta_d(ti, HALF_PI, ph)
    np.testing.assert_allclose(S.g_over_cos_r(ti, HALF_PI, ph), 2 * np.cos(th) / np.cos(td),
                               rtol=1e-12)


def test_g_over_cos_cos_symmetric_and_finite():
    from roughbrdf.geometry import half_vector

    rng = np.random.default_rng(5)
    for _ in range(2000):
        ti, tr, ph = rng.uniform(0, HALF_PI), rng.uniform(0, HALF_PI), rng.uniform(-3, 3)
        hx, hy, hz, cd, ci, cr, si = half_vector(ti, tr, ph)
        a = S.v_groove_g_over_cos_cos(ci, cr, hz, cd)
        b = S.v_groove_g_over_cos_cos(cr, ci, hz, cd)
        assert a == pytest.approx(b, rel=1e-13)
        if ci > 0 and cr > 0:
            assert a == pytest.approx(S.v_groove_g(ci, cr, hz, cd) / (ci * cr), rel=1e-12)
    # one direction grazing: finite (the shadowing/masking branch has no 1/cos of it)
    hx, hy, hz, cd, ci, cr, si = half_vector(HALF_PI, 0.4, 0.3)
    assert np.isfinite(S.v_groove_g_over_cos_cos(ci, cr, hz, cd))


def test_smith_g1_ggx_closed_form():
    # GGX: G1 = 2/(1 + sqrt(1 + a^2 tan^2)) (Walter et al. 2007, Eq. 34)
    c = np.linspace(0.0, 1.0, 101)
    for a in (0.05, 0.3, 1.0):
        with np.errstate(divide="ignore"):
            t2 = (1 - c**2) / c**2
        expected = np.where(c > 0, 2 / (1 + np.sqrt(1 + a * a * t2)), 0.0)
        np.testing.assert_allclose(S.smith_g1(c, a, "ggx"), expected, rtol=1e-12, atol=1e-15)
    assert float(S.smith_g1(1.0, 0.5)) == 1.0


@pytest.mark.parametrize("dist", ["trowbridge-reitz", "beckmann"])
def test_smith_bidirectional(dist):
    rng = np.random.default_rng(6)
    ti, tr = rng.uniform(0, HALF_PI, 5000), rng.uniform(0, HALF_PI, 5000)
    a = 0.4
    g1i = S.smith_g1(np.cos(ti), a, dist)
    g1r = S.smith_g1(np.cos(tr), a, dist)
    sep = S.smith(ti, tr, a, dist, "smith-separable")
    hc = S.smith(ti, tr, a, dist, "smith")
    np.testing.assert_allclose(sep, g1i * g1r, rtol=1e-12, atol=1e-300)
    # height-correlated 1/(1 + L_i + L_r) (Heitz 2014, Eq. 99) >= separable G1 G1
    li = S.smith_g1(np.cos(ti), a, dist)
    lam_i = np.where(li > 0, 1 / np.maximum(li, 1e-300) - 1, np.inf)
    lam_r = np.where(g1r > 0, 1 / np.maximum(g1r, 1e-300) - 1, np.inf)
    ok = np.isfinite(lam_i) & np.isfinite(lam_r) & (np.cos(ti) > 1e-3) & (np.cos(tr) > 1e-3)
    np.testing.assert_allclose(hc[ok], 1 / (1 + lam_i[ok] + lam_r[ok]), rtol=1e-9)
    assert np.all(hc >= sep - 1e-15)
    assert np.all((hc >= 0) & (hc <= 1))
    np.testing.assert_allclose(S.smith(0.0, 0.0, a, dist), 1.0)


@pytest.mark.parametrize("alias, canonical", [
    ("v-groove", "v-groove"), ("torrance-sparrow", "v-groove"), ("v_cavity", "v-groove"),
    ("smith", "smith-height-correlated"), ("smith-separable", "smith-separable"),
    ("none", "none"), (None, "none"), ("Smith_Height_Correlated", "smith-height-correlated"),
])
def test_shadowing_names(alias, canonical):
    assert S.canonical(S.get(alias)) == canonical


def test_shadowing_unknown_name_suggests():
    with pytest.raises(ValueError, match="unknown shadowing 'smyth'.*did you mean.*'smith'"):
        S.get("smyth")
    with pytest.raises(ValueError, match="did you mean"):
        rb.model("microfacet", shadowing="v-grove")


def test_smith_needs_a_smith_distribution():
    with pytest.raises(ValueError, match="Smith"):
        rb.model("microfacet", distribution="berry", shadowing="smith")
    with pytest.raises(ValueError, match="Smith"):
        S.smith_g1(0.5, 0.3, "gaussian-angle")


def test_invalid_angles_raise():
    with pytest.raises(ValueError, match=r"theta_r.*1\.7"):
        S.v_groove(0.2, 1.7, 0.0)
    with pytest.raises(ValueError, match=r"theta_i.*nan"):
        S.g_over_cos_r(math.nan, 0.2, 0.0)
    with pytest.raises(ValueError, match=r"alpha.*-0\.1"):
        S.smith_g1(0.5, -0.1)
