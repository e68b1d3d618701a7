"""Mueller matrices of the models (``roughbrdf.mueller``, ``Model.mueller``; docs/models.md §11).

Where the expected numbers come from:

* the Stokes definitions of ``roughbrdf.mueller``'s module notes (SCATMECH's conventions),
  written out here in NumPy (:func:`stokes`): the Jones-to-Mueller part is checked against
  them, and the Fresnel amplitudes against NumPy's complex arithmetic (:func:`fresnel_numpy`);
* the library's scalar paths: ``m00`` is ``brdf()``, and the Stokes vectors of ``"s"``, ``"p"``
  and TR75's ``gamma`` give ``brdf(polarization=...)`` (module notes);
* identities: realizability (Cloude's coherency matrix), reciprocity
  ``M(theta_r, theta_i, -phi) = Q M(theta_i, theta_r, phi)^T Q``, ``Q = diag(1, 1, -1, 1)`` in
  psps, and mirror symmetry (docs/models.md §11.4); the smooth-surface limit
  (:func:`roughbrdf.mueller.fresnel_mueller` at the specular direction); ``xyxy`` = the psps
  matrix with the reflected basis rotated by ``phi``;
* NIST SCATMECH 7.23 (pySCATMECH 0.1.10): reference matrices in ``tests/data/scatmech/*.json``
  written by ``scripts/scatmech_reference.py`` (recomputed live where pySCATMECH imports);
* Mitsuba 3's ``roughconductor`` in a polarized variant, where installed.
"""

from __future__ import annotations

import importlib.util
import json
import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from mitsuba_support import mitsuba_variant

import roughbrdf as rb
from roughbrdf._kernels import DISABLE_JIT
from roughbrdf.errors import ArgumentError
from roughbrdf.fresnel import fresnel_amplitudes
from roughbrdf.mueller import coherency, depolarizer, fresnel_mueller, jones_to_mueller

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data" / "scatmech"
SCRIPT = ROOT / "scripts" / "scatmech_reference.py"
# reciprocity and mirror symmetry in psps (docs/models.md §11.4)
Q = np.diag([1.0, 1.0, -1.0, 1.0])
MIRROR = np.diag([1.0, 1.0, -1.0, -1.0])
P = MIRROR @ Q


def stokes(e: np.ndarray) -> np.ndarray:
    """Stokes vectors of Jones vectors ``(..., 2)`` by the module notes' definitions."""
    e1, e2 = e[..., 0], e[..., 1]
    x = np.conj(e1) * e2
    return np.stack([abs(e1) ** 2 + abs(e2) ** 2, abs(e1) ** 2 - abs(e2) ** 2,
                     2 * x.real, 2 * x.imag], axis=-1)


def linear(gamma: np.ndarray) -> np.ndarray:
    """Stokes vector of TR75's linear polarization ``gamma`` (Jones ``(sin, cos)`` in psps)."""
    g = np.asarray(gamma, dtype=float)
    return np.stack([np.ones_like(g), -np.cos(2 * g), np.sin(2 * g), np.zeros_like(g)], -1)


def fresnel_numpy(c, n, k):
    """``r_s``, ``r_p`` in NumPy complex arithmetic (module notes; SCATMECH's sign of r_p)."""
    eps = (n + 1j * k) ** 2
    q = np.sqrt(eps - (1 - c * c) + 0j)  # principal branch: Re q >= 0 (and Im q >= 0)
    return (c - q) / (c + q), (eps * c - q) / (eps * c + q)


def assert_within(got, want, tol):
    """``|got - want| <= tol`` elementwise (``tol`` an array: per-sample tolerances)."""
    err = np.abs(np.asarray(got) - np.asarray(want))
    ok = err <= tol
    assert ok.all(), f"{np.count_nonzero(~ok)} values off, worst err/tol {np.max(err / tol):.3g}"


def geometries(n: int, seed: int, top: float = 1.5):
    rng = np.random.default_rng(seed)
    return rng.uniform(0, top, n), rng.uniform(0, top, n), rng.uniform(-math.pi, math.pi, n)


# every distribution and shadowing of the microfacet model (Smith only where it has a Lambda),
# a metal and a dielectric; TS67, TR75 (both shadowings), the coated variants, the diffuse
# models and sums
MICROFACET = [dict(distribution=d, shadowing=s, alpha=a, n=n, k=k)
              for d, a in (("trowbridge-reitz", 0.3), ("beckmann", 0.2), ("gaussian-angle", 0.05),
                           ("berry", 0.4), ("sirohi", 0.5))
              for s in ("none", "v-groove", "smith-separable", "smith-height-correlated")
              if d in ("trowbridge-reitz", "beckmann") or not s.startswith("smith")
              for n, k in ((1.5, 0.0), (0.2, 3.0))]
FACET_ONLY = ([("microfacet", kw) for kw in MICROFACET]
              + [("trowbridge-reitz-1975", dict(rho_L=0.0)),
                 ("trowbridge-reitz-1975", dict(rho_L=0.0, shadowing="v-groove", n=4.05, k=0.05)),
                 ("coated", dict(rho=0.0, lobes=2)),
                 ("coated", dict(rho=0.0, lobes=3, distribution="beckmann",
                                 shadowing="smith-height-correlated"))])
WITH_DIFFUSE = [("torrance-sparrow-1967", dict(n=1.5, k=0.3)),
                ("torrance-sparrow-1967", dict(n=0.2, k=3.0, g=5.0, c=0.1)),
                ("trowbridge-reitz-1975", {}),
                ("trowbridge-reitz-1975", dict(shadowing="v-groove")),
                ("coated", dict(lobes=2)), ("coated", dict(diffuse="oren-nayar")),
                ("coated", dict(shadow_diffuse=False, distribution="beckmann", n=1.3)),
                ("coated", dict(interface="rough", alpha=0.3)),
                ("lambertian", {}), ("oren-nayar", dict(sigma=0.4))]
ALL = FACET_ONLY + WITH_DIFFUSE


def build(spec) -> rb.Model:
    name, kw = spec
    return rb.model(name, **kw)


def spec_id(spec) -> str:
    name, kw = spec
    return name + "(" + ",".join(f"{k}={v}" for k, v in kw.items()) + ")"


# ------------------------------------------------------------------------------------------
# the parts: Jones to Mueller, Fresnel amplitudes, the front ends
# ------------------------------------------------------------------------------------------
def test_jones_to_mueller_follows_the_stokes_definitions():
    rng = np.random.default_rng(0)
    j = rng.normal(size=(50, 2, 2)) + 1j * rng.normal(size=(50, 2, 2))
    e = rng.normal(size=(50, 6, 2)) + 1j * rng.normal(size=(50, 6, 2))
    m = jones_to_mueller(j)
    s_out = stokes(np.einsum("nab,nkb->nka", j, e))  # S(J e) = M S(e), for every e
    np.testing.assert_allclose(np.einsum("nab,nkb->nka", m, stokes(e)), s_out,
                               atol=1e-13 * np.abs(s_out).max())
    assert jones_to_mueller(j[0]).shape == (4, 4)
    assert jones_to_mueller(np.zeros((0, 2, 2))).shape == (0, 4, 4)
    with pytest.raises(ArgumentError, match="jones"):
        jones_to_mueller(np.zeros((2, 3)))


def test_circular_handedness():
    # (1, i) on (e1, e2): V = +1 (SCATMECH's LCP: counter-clockwise looking toward the source)
    assert stokes(np.array([1.0, 1j]) / math.sqrt(2)).tolist() == pytest.approx([1, 0, 0, 1])
    # a quarter-wave retarder with e2 delayed by pi/2 (Jones diag(1, i)) turns s + p into V = +1
    m = jones_to_mueller(np.diag([1.0, 1j]))
    assert (m @ [1.0, 0.0, 1.0, 0.0]).tolist() == pytest.approx([1, 0, 0, 1])


@pytest.mark.parametrize("n,k", [(1.5, 0.0), (0.2, 3.0), (1.2, 7.0), (4.05, 0.05), (0.8, 0.0),
                                 (1.0, 0.9), (1.0001, 0.0)])
def test_fresnel_amplitudes(n, k):
    c = np.concatenate([[0.0, 1e-9, 0.5, 1.0], np.random.default_rng(1).uniform(0, 1, 60)])
    rs, rp = fresnel_numpy(c, n, k)
    got = np.array([fresnel_amplitudes(x, n, k) for x in c])
    np.testing.assert_allclose(got[:, 0] + 1j * got[:, 1], rs, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(got[:, 2] + 1j * got[:, 3], rp, rtol=1e-13, atol=1e-15)
    # |r|^2 equals the library's reflectances (fresnel_sp) to round-off
    r_s = rb.fresnel.reflectance(c, n, k, "s")
    r_p = rb.fresnel.reflectance(c, n, k, "p")
    np.testing.assert_allclose(got[:, 0] ** 2 + got[:, 1] ** 2, r_s, rtol=1e-13, atol=1e-16)
    np.testing.assert_allclose(got[:, 2] ** 2 + got[:, 3] ** 2, r_p, rtol=1e-13, atol=1e-16)


def test_fresnel_sign_convention():
    # normal incidence: r_p = -r_s = (N - 1)/(N + 1); perfect-conductor limit r_s -> -1, r_p -> +1
    rs_re, rs_im, rp_re, rp_im = fresnel_amplitudes(1.0, 0.2, 3.0)
    nn = 0.2 + 3.0j
    assert complex(rp_re, rp_im) == pytest.approx((nn - 1) / (nn + 1), rel=1e-14)
    assert complex(rs_re, rs_im) == pytest.approx(-(nn - 1) / (nn + 1), rel=1e-14)
    rs_re, _, rp_re, _ = fresnel_amplitudes(0.3, 1e6, 0.0)
    assert rs_re == pytest.approx(-1.0, abs=1e-5) and rp_re == pytest.approx(1.0, abs=1e-5)


def test_fresnel_mueller():
    c = np.linspace(0, 1, 11)[:, None]
    n = np.array([1.5, 0.2, 1.2])[None, :]
    k = np.array([0.0, 3.0, 7.0])[None, :]
    m = fresnel_mueller(c, n, k)
    assert m.shape == (11, 3, 4, 4)
    rs, rp = fresnel_numpy(c, n, k)
    x = rs * np.conj(rp)
    want = np.zeros_like(m)
    want[..., 0, 0] = want[..., 1, 1] = (abs(rs) ** 2 + abs(rp) ** 2) / 2
    want[..., 0, 1] = want[..., 1, 0] = (abs(rs) ** 2 - abs(rp) ** 2) / 2
    want[..., 2, 2] = want[..., 3, 3] = x.real
    want[..., 2, 3], want[..., 3, 2] = x.imag, -x.imag
    np.testing.assert_allclose(m, want, atol=1e-14)
    np.testing.assert_allclose(m, jones_to_mueller(np.stack(
        [np.stack([rs, 0 * rs], -1), np.stack([0 * rp, rp], -1)], -2)), atol=1e-15)
    with pytest.raises(ArgumentError, match="cos_theta"):
        fresnel_mueller(1.5, 1.5)
    with pytest.raises(ValueError, match="extinction"):
        fresnel_mueller(0.5, 1.5, -1.0)


def test_depolarizer_and_coherency():
    d = depolarizer(np.array([0.5, 2.0]))
    assert d.shape == (2, 4, 4) and d[1, 0, 0] == 2.0 and np.count_nonzero(d) == 2
    h = coherency(jones_to_mueller(np.array([[0.3 + 0.1j, 0.2j], [-0.1, 0.7]])))
    np.testing.assert_allclose(h, np.conj(np.swapaxes(h, -1, -2)))  # Hermitian
    w = np.linalg.eigvalsh(h)
    assert w[:3] == pytest.approx([0, 0, 0], abs=1e-15) and w[3] > 0  # one Jones matrix: rank 1


# ------------------------------------------------------------------------------------------
# invariants of every model with a Mueller matrix, on random geometries
# ------------------------------------------------------------------------------------------
#: geometries per invariant test; a tenth under NUMBA_DISABLE_JIT=1 (make test-nojit), where
#: a three-lobe coated Mueller matrix takes minutes for 600 of them in plain Python
N_GEOMETRIES = 60 if DISABLE_JIT else 600
TI, TR, PH = geometries(N_GEOMETRIES, 2)
GAMMA = np.random.default_rng(3).uniform(-math.pi, math.pi, TI.size)


@pytest.mark.parametrize("basis", ["psps", "xyxy"])
@pytest.mark.parametrize("spec", ALL, ids=spec_id)
def test_scalar_paths(spec, basis):
    # m00 = the unpolarized BRDF; s, p and gamma through the Stokes vectors of the module notes.
    # Tolerance 5e-13 of the BRDF: m00 and brdf() run the same compiled parts in different
    # loops, whose FMA contraction may differ; Beckmann's exponent tan^2/alpha^2 (up to ~500 on
    # these geometries) amplifies that argument's rounding (measured: <= 2e-13)
    m = build(spec)
    M = m.mueller(TI, TR, PH, basis=basis)
    assert M.shape == (TI.size, 4, 4) and np.isfinite(M).all()
    b = m.brdf(TI, TR, PH)
    tol = 5e-13 * b
    assert_within(M[:, 0, 0], b, tol)
    assert_within(M[:, 0, 0] + M[:, 0, 1], m.brdf(TI, TR, PH, "s"), tol)
    assert_within(M[:, 0, 0] - M[:, 0, 1], m.brdf(TI, TR, PH, "p"), tol)
    i_gamma = np.einsum("nj,nj->n", M[:, 0, :], linear(GAMMA))
    assert_within(i_gamma, m.brdf(TI, TR, PH, GAMMA), tol)


@pytest.mark.parametrize("spec", ALL, ids=spec_id)
def test_realizable(spec):
    # Cloude's coherency matrix has no negative eigenvalue beyond round-off (1e-12 of m00;
    # measured -1.5e-15); a facet term alone is one Jones matrix: rank 1
    m = build(spec)
    M = m.mueller(TI, TR, PH)
    w = np.linalg.eigvalsh(coherency(M))
    m00 = M[:, 0, 0]
    assert (w[:, 0] >= -1e-12 * m00).all()
    if spec in FACET_ONLY:
        np.testing.assert_allclose(w[:, :3], 0.0, atol=1e-12 * m00.max())
        np.testing.assert_allclose(w[:, 3], 2 * m00, rtol=1e-12)  # trace H = 2 m00


@pytest.mark.parametrize("spec", ALL, ids=spec_id)
def test_reciprocity_and_mirror_symmetry(spec):
    # the reversed path (source at w_r, viewer at w_i) is (theta_r, theta_i, -phi) in the
    # library's frame (a rotation about z brings the new source to -x), and the Jones matrix
    # of a reciprocal surface obeys J' = sigma J^T sigma there, sigma = diag(1, -1), so
    # M(theta_r, theta_i, -phi) = Q M^T Q, Q = diag(1, 1, -1, 1) (docs/models.md §11.4).
    # Isotropic surfaces are mirror-symmetric: M(-phi) = D M(phi) D, D = diag(1, 1, -1, -1)
    # (exactly, in both bases); together M(theta_r, theta_i, phi) = P M^T P, P = diag(1, 1, 1,
    # -1). Every model here is reciprocal in its scalar BRDF
    m = build(spec)
    assert m.reciprocal
    ti, tr, ph = geometries(N_GEOMETRIES // 2, 4, top=math.radians(80))
    a = m.mueller(ti, tr, ph)
    tol = 5e-13 * a[:, 0, 0][:, None, None]
    assert_within(m.mueller(tr, ti, -ph), Q @ np.swapaxes(a, -1, -2) @ Q, tol)
    assert_within(m.mueller(tr, ti, ph), P @ np.swapaxes(a, -1, -2) @ P, tol)
    for basis in ("psps", "xyxy"):
        np.testing.assert_array_equal(m.mueller(ti, tr, -ph, basis=basis),
                                      MIRROR @ m.mueller(ti, tr, ph, basis=basis) @ MIRROR)


@pytest.mark.parametrize("spec", [("microfacet", dict(distribution="beckmann", alpha=1e-3,
                                                      shadowing="v-groove", n=0.2, k=3.0)),
                                  ("microfacet", dict(alpha=1e-3, n=1.5)),
                                  ("torrance-sparrow-1967", dict(c=2.0, n=1.2, k=7.0, g=1e7)),
                                  ("trowbridge-reitz-1975", dict(e=1e-3, rho_L=0.2)),
                                  ("coated", dict(alpha=1e-4, n=1.5, rho=0.5))], ids=spec_id)
def test_smooth_specular_limit(spec):
    # at the specular direction M/m00 tends to the Fresnel Mueller matrix normalized as
    # fresnel_mueller(cos theta_i)/A: exactly for the facet term (h = z, no rotation), and to
    # the diffuse part's share for the models that have one (< 1e-5 with these widths: TR75
    # R D/(4 cos^2) ~ 1e4 against rho_L/pi = 0.06; TS67 g = 1e7 facet to diffuse). 1e-5 rad off
    # the peak the local plane turns by ~theta_h/alpha: 1e-4
    m = build(spec)
    n, k = m.params["n"], m.params.get("k") or 0.0
    ti = np.radians([0.0, 20.0, 45.0, 70.0, 80.0])
    f = fresnel_mueller(np.cos(ti), n, k)
    want = f / f[:, :1, :1]
    for dt, tol in ((0.0, 1e-5), (1e-5, 1e-4)):  # at, and 1e-5 rad off, the specular peak
        got = m.mueller(ti, ti + dt, dt)
        np.testing.assert_allclose(got / got[:, :1, :1], want, rtol=0, atol=tol)


def test_specular_facet_term_is_fresnel_exactly():
    mf = rb.model("microfacet", distribution="beckmann", alpha=0.3, n=0.2, k=3.0)
    ti = np.radians([0.0, 20.0, 45.0, 70.0, 80.0])
    got = mf.mueller(ti, ti, 0.0)
    f = fresnel_mueller(np.cos(ti), 0.2, 3.0)
    np.testing.assert_allclose(got / got[:, :1, :1], f / f[:, :1, :1], atol=1e-15)


def test_xyxy_is_psps_rotated_by_phi():
    # (e1, e2) of xyxy = (y_r, x_r) = -R(phi) (s_r, p_r): M_xyxy = R M_psps with the Mueller
    # rotation [[c2, -s2], [s2, c2]] on (Q, U), c2 = cos 2 phi
    m = rb.model("trowbridge-reitz-1975", shadowing="v-groove")
    a, b = m.mueller(TI, TR, PH), m.mueller(TI, TR, PH, basis="xyxy")
    rot = np.zeros((TI.size, 4, 4))
    rot[:, 0, 0] = rot[:, 3, 3] = 1.0
    rot[:, 1, 1] = rot[:, 2, 2] = np.cos(2 * PH)
    rot[:, 1, 2], rot[:, 2, 1] = -np.sin(2 * PH), np.sin(2 * PH)
    np.testing.assert_allclose(b, rot @ a, atol=1e-14 * a[:, 0, 0].max())


def test_xyxy_regular_at_the_normal():
    # at theta_r = 0 the direction does not depend on phi, and neither does the xyxy matrix
    # (the psps basis turns with phi there)
    m = rb.model("microfacet", distribution="beckmann", alpha=0.3, n=0.2, k=3.0)
    phis = np.linspace(-3, 3, 7)
    xy = m.mueller(0.4, 0.0, phis, basis="xyxy")
    np.testing.assert_allclose(xy, np.broadcast_to(xy[0], xy.shape), atol=1e-15)
    sp = m.mueller(0.4, 0.0, phis)
    assert np.ptp(sp[:, 1, 1]) > 1e-3
    near = m.mueller(0.4, 1e-7, phis, basis="xyxy")  # continuous across the normal
    np.testing.assert_allclose(near, xy, atol=1e-7)


def test_retro_direction_is_defined():
    # theta_d = 0: the facet's plane of incidence is undefined, the matrix is not (r_p = -r_s);
    # SCATMECH's Jones matrix there is diag(r_s, r_p) in psps
    m = rb.model("microfacet", alpha=0.3, n=0.2, k=3.0, shadowing="v-groove")
    ti = np.array([0.0, 0.3, 1.0])
    got = m.mueller(ti, ti, math.pi)
    rs, rp = fresnel_numpy(1.0, 0.2, 3.0)
    want = jones_to_mueller(np.diag([rs, rp]))
    np.testing.assert_allclose(got / got[:, :1, :1], np.broadcast_to(want / want[0, 0], got.shape),
                               atol=1e-13)
    near = m.mueller(ti, ti + 1e-9, math.pi)
    np.testing.assert_allclose(near / near[:, :1, :1], got / got[:, :1, :1], atol=1e-9)


def test_sums_add_and_terms_select():
    a = rb.model("trowbridge-reitz-1975", rho_L=0.0)
    b = rb.model("oren-nayar", rho=0.3, sigma=0.4)
    s = a + b
    np.testing.assert_allclose(s.mueller(TI, TR, PH), a.mueller(TI, TR, PH) + b.mueller(TI, TR, PH),
                               rtol=1e-15, atol=0)
    np.testing.assert_array_equal(s.mueller(TI, TR, PH, term="on"), b.mueller(TI, TR, PH))
    np.testing.assert_array_equal(s.mueller(TI, TR, PH, basis="xyxy", term="tr75"),
                                  a.mueller(TI, TR, PH, basis="xyxy"))
    with pytest.raises(ArgumentError, match="term"):
        s.mueller(0.1, 0.2, 0.3, term="nope")
    with pytest.raises(ArgumentError, match="term"):
        a.mueller(0.1, 0.2, 0.3, term="facet")


def test_diffuse_models_are_ideal_depolarizers():
    for m in (rb.model("lambertian", rho=0.4), rb.model("oren-nayar", rho=0.8, sigma=0.4)):
        M = m.mueller(TI, TR, PH, basis="xyxy")
        np.testing.assert_array_equal(M, depolarizer(m.brdf(TI, TR, PH)))


def test_coated_substrate_leaves_partly_p_polarized():
    # the substrate light crosses the interface on the way out: for unpolarized incident light
    # the reflected Q/I is (R_p - R_s)/(2 - R_s - R_p) at theta_r (p-polarized, Q < 0), Fresnel
    # reflectances of the coating's index (module notes of coated.py)
    m = rb.model("coated", rho=0.8, ks=0.0, n=1.5, weights="free")  # the substrate alone
    tr = np.radians([10.0, 40.0, 70.0])
    M = m.mueller(0.3, tr, 2.0)
    r_s = rb.fresnel.reflectance(np.cos(tr), 1.5, 0.0, "s")
    r_p = rb.fresnel.reflectance(np.cos(tr), 1.5, 0.0, "p")
    np.testing.assert_allclose(M[:, 1, 0] / M[:, 0, 0], (r_p - r_s) / (2 - r_s - r_p), rtol=1e-13)
    assert np.all(M[:, 2:, :] == 0) and np.all(M[:, :, 2:] == 0)


# ------------------------------------------------------------------------------------------
# broadcasting, special values and errors
# ------------------------------------------------------------------------------------------
def test_broadcasting():
    m = rb.model("torrance-sparrow-1967", n=1.5, k=0.3)
    ti = np.array([0.1, 0.5, 1.0])[:, None, None]
    tr = np.array([0.0, 0.3, 0.7, 1.2])[None, :, None]
    ph = np.array([0.0, 2.0])
    M = m.mueller(ti, tr, ph, basis="xyxy")
    assert M.shape == (3, 4, 2, 4, 4)
    for idx in np.ndindex(3, 4, 2):
        one = m.mueller(ti[idx[0], 0, 0], tr[0, idx[1], 0], ph[idx[2]], basis="xyxy")
        assert one.shape == (4, 4)
        np.testing.assert_array_equal(M[idx], one)
    assert m.mueller([], [], []).shape == (0, 4, 4)
    np.testing.assert_allclose(m.mueller(0.3, 0.2, 1e7 * 2 * math.pi + 0.5),  # reduced azimuth
                               m.mueller(0.3, 0.2, 0.5), rtol=0, atol=1e-9)


def test_horizon_limits_have_no_nan():
    # TR75 without shadowing diverges at theta_r = 90 deg: inf where the matrix is not 0, never
    # nan; with shadowing and for the other models the matrix is finite there
    M = rb.model("trowbridge-reitz-1975").mueller(0.3, math.pi / 2, [0.0, 1.0])
    assert np.isinf(M[:, 0, 0]).all() and not np.isnan(M).any()
    for m in (rb.model("trowbridge-reitz-1975", shadowing="v-groove"), rb.model("coated"),
              rb.model("microfacet", n=1.5), rb.model("torrance-sparrow-1967", n=1.5)):
        assert np.isfinite(m.mueller(0.3, math.pi / 2, [0.0, 1.0])).all()
    forward_grazing = rb.model("lambertian").mueller(math.pi / 2, math.pi / 2, 0.0)
    assert forward_grazing[0, 0] == pytest.approx(0.5 / math.pi)


@pytest.mark.parametrize("bad", [dict(theta_i=float("nan")), dict(theta_r=-0.1),
                                 dict(theta_r=2.0), dict(phi=float("inf")), dict(theta_i=None),
                                 dict(theta_i=math.pi / 2)])
def test_bad_angles_raise(bad):
    args = dict(theta_i=0.3, theta_r=0.2, phi=0.1) | bad
    with pytest.raises(ArgumentError, match=next(iter(bad))):
        rb.model("microfacet", n=1.5).mueller(**args)


def test_errors():
    m = rb.model("microfacet", n=1.5)
    with pytest.raises(ArgumentError, match="basis"):
        m.mueller(0.1, 0.2, 0.3, basis="plane")
    with pytest.raises(ArgumentError, match="do not broadcast"):
        m.mueller(np.zeros(2), np.zeros(3), 0.0)
    for name, kw in (("torrance-sparrow-1967", {}), ("microfacet", dict(n=None, k=None))):
        with pytest.raises(ArgumentError, match="^n = None") as err:
            rb.model(name, **kw).mueller(0.1, 0.2, 0.3)
        assert err.value.argument == "n"
    with pytest.raises(NotImplementedError, match="renhorn-boreman-2008"):
        rb.model("renhorn-boreman-2008").mueller(0.1, 0.2, 0.3)
    with pytest.raises(NotImplementedError):  # a sum with a component without one
        (rb.model("lambertian") + rb.model("renhorn-boreman-2008")).mueller(0.1, 0.2, 0.3)


def test_pure_python_mode_agrees():
    # NUMBA_DISABLE_JIT=1 (pure Python, for debugging and coverage) gives the same matrices
    code = textwrap.dedent("""
        import json, numpy as np, numba, roughbrdf as rb
        assert numba.config.DISABLE_JIT
        from roughbrdf.mueller import fresnel_mueller
        ti = np.array([0.0, 0.3, 1.2]); tr = np.array([0.0, 0.4, 1.5707963267948966])
        ph = np.array([0.0, 1.0, -2.0])
        out = {}
        for name, kw in [("microfacet", {"distribution": "beckmann", "n": 0.2, "k": 3.0}),
                         ("torrance-sparrow-1967", {"n": 1.5}),
                         ("trowbridge-reitz-1975", {"shadowing": "v-groove"}),
                         ("coated", {"lobes": 2})]:
            m = rb.model(name, **kw)
            out[name] = [m.mueller(ti, tr, ph).tolist(),
                         m.mueller(ti, tr, ph, basis="xyxy").tolist()]
        out["f"] = fresnel_mueller(np.cos(ti), 1.5, 0.3).tolist()
        print(json.dumps(out))
    """)
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=300, check=True)
    pure = json.loads(res.stdout.strip().splitlines()[-1])
    ti, tr = np.array([0.0, 0.3, 1.2]), np.array([0.0, 0.4, math.pi / 2])
    ph = np.array([0.0, 1.0, -2.0])
    for name, kw in [("microfacet", {"distribution": "beckmann", "n": 0.2, "k": 3.0}),
                     ("torrance-sparrow-1967", {"n": 1.5}),
                     ("trowbridge-reitz-1975", {"shadowing": "v-groove"}),
                     ("coated", {"lobes": 2})]:
        m = rb.model(name, **kw)
        for got, basis in zip(pure[name], ("psps", "xyxy"), strict=True):
            want = m.mueller(ti, tr, ph, basis=basis)
            np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-15 * np.abs(want).max())
    np.testing.assert_allclose(pure["f"], fresnel_mueller(np.cos(ti), 1.5, 0.3), atol=1e-15)


# ------------------------------------------------------------------------------------------
# NIST SCATMECH: committed references, and live where pySCATMECH imports
# ------------------------------------------------------------------------------------------
def _scatmech_cases():
    out = []
    for path in sorted(DATA.glob("*.json")):
        doc = json.loads(path.read_text())
        for case in doc["cases"]:
            out.append(pytest.param(doc, case, id=f"{path.stem}:{case['name']}"))
    return out


def _roughbrdf_model(case) -> rb.Model:
    spec = case["roughbrdf"]
    return rb.model(spec["model"], **spec["params"], **spec.get("options", {}))


def _exponent(case, g):
    """The exponent ``x`` of a gaussian facet distribution, ``exp(-x)``, at the geometries:
    ``tan^2 theta_h/alpha^2`` (Beckmann = SCATMECH's gaussian slopes), ``(c theta_h,deg)^2``
    (TS67 = gaussian angles); 0 for the others."""
    spec = case["roughbrdf"]
    th = rb.geometry.theta_h(g["theta_i"], g["theta_r"], g["phi"])
    if spec.get("options", {}).get("distribution") == "beckmann":
        return np.tan(th) ** 2 / spec["params"]["alpha"] ** 2
    if spec["model"] == "torrance-sparrow-1967":
        return (spec["params"]["c"] * np.degrees(th)) ** 2
    return np.zeros_like(th)


def _scatmech_tolerance(case, g, m00):
    # relative to m00 (docs/models.md §11.5): 1e-13; the exponent x of a gaussian D amplifies
    # its argument's rounding to ~x eps (2e-15 x: up to 1e-12 at x = 530 far in the tail);
    # SCATMECH's own loss near the retro direction, where it takes the local angle as
    # acos(cos iota) and divides by sin^2(2 iota): ~eps/theta_d^2 (7e-13 at theta_d = 1.2 deg)
    td = rb.geometry.theta_d(g["theta_i"], g["theta_r"], g["phi"])
    rel = 1e-13 + 2e-15 * _exponent(case, g) + 4e-16 / td**2
    return (rel * np.maximum(m00, 1e-300))[:, None, None]


@pytest.mark.parametrize("doc,case", _scatmech_cases())
def test_scatmech_reference(doc, case):
    g = doc["geometries"]
    m = _roughbrdf_model(case)
    for basis in ("psps", "xyxy"):
        ref = np.array(case[basis]).reshape(-1, 4, 4)
        got = m.mueller(g["theta_i"], g["theta_r"], g["phi"], basis=basis)
        assert_within(got, ref, _scatmech_tolerance(case, g, ref[:, 0, 0]))


def test_scatmech_reference_files_are_complete():
    stems = {p.stem for p in DATA.glob("*.json")}
    assert {"facet_shadowed", "facet_unshadowed", "ts67", "lambertian"} <= stems
    doc = json.loads((DATA / "facet_shadowed.json").read_text())
    assert doc["versions"]["SCATMECH"] and len(doc["geometries"]["phi"]) == 200
    assert max(max(doc["geometries"][k]) for k in ("theta_i", "theta_r")) <= math.radians(80)
    assert any(c["roughbrdf"]["options"].get("distribution") == "beckmann"
               and c["roughbrdf"]["params"]["k"] > 1 for c in doc["cases"])  # a metal
    assert any(c["roughbrdf"]["params"]["k"] == 0.0 for c in doc["cases"])  # a dielectric


def _load_script():
    spec = importlib.util.spec_from_file_location("scatmech_reference", SCRIPT)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_scatmech_live():
    pytest.importorskip("pySCATMECH", reason="pySCATMECH (NIST SCATMECH) is not installed: it "
                        "builds from source and is not a dependency; the committed reference "
                        "values are compared instead")
    script = _load_script()
    geom = {k: v[:40] for k, v in script.geometries().items()}
    for stem, group in script.cases().items():
        committed = json.loads((DATA / f"{stem}.json").read_text())
        for case, saved in zip(group, committed["cases"], strict=True):
            m = _roughbrdf_model(case)
            for basis in ("psps", "xyxy"):
                live = script.reference(case, geom, basis)
                tol = _scatmech_tolerance(case, geom, live[:, 0, 0])
                saved_m = np.array(saved[basis])[:40].reshape(-1, 4, 4)
                assert_within(live, saved_m, tol)  # the committed values still hold
                got = m.mueller(geom["theta_i"], geom["theta_r"], geom["phi"], basis=basis)
                assert_within(got, live, tol)


# ------------------------------------------------------------------------------------------
# Mitsuba 3 roughconductor in a polarized variant
# ------------------------------------------------------------------------------------------
def _mitsuba_polarized():
    mi = pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed")
    for variant in ("scalar_spectral_polarized", "scalar_rgb_polarized"):
        if variant in mi.variants():
            return mi, variant
    pytest.skip(f"no scalar polarized Mitsuba variant in {mi.variants()}")


def _mitsuba_mueller(mi, bsdf, ti, tr, ph):
    """Mitsuba's Mueller BSDF·cos at one geometry, converted to psps.

    Mitsuba's ``eval(ctx, si, wo)`` (radiance mode): light arrives along ``-wo`` (our ``w_i``)
    and leaves along ``si.wi`` (our ``w_r``); the matrix maps the Stokes basis
    ``stokes_basis(-wo)`` to ``stokes_basis(si.wi)``, with ``s3 > 0`` right circular seen by
    the receiver (SPIE) = our ``-V``. Rotating both bases onto ``s_i``, ``s_r`` and flipping
    ``V`` (``P M P``) gives our psps matrix times ``cos theta_i``.
    """
    w_i = mi.Vector3f(-math.sin(ti), 0.0, math.cos(ti))
    w_r = mi.Vector3f(math.sin(tr) * math.cos(ph), math.sin(tr) * math.sin(ph), math.cos(tr))
    si = mi.SurfaceInteraction3f()
    si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
    si.wi = w_r
    si.wavelengths = mi.UnpolarizedSpectrum(550.0)
    value = np.asarray(bsdf.eval(mi.BSDFContext(), si, w_i))
    m4 = value if value.ndim == 2 else value[:, :, 0]  # spectral: 4 equal wavelengths
    k_i = -w_i
    rot = mi.mueller.rotate_mueller_basis(
        mi.Matrix4f(m4), k_i, mi.mueller.stokes_basis(k_i), mi.Vector3f(0.0, 1.0, 0.0),
        w_r, mi.mueller.stokes_basis(w_r), mi.Vector3f(-math.sin(ph), math.cos(ph), 0.0))
    return P @ np.asarray(rot) @ P


def test_mitsuba_polarized_roughconductor():
    mi, variant = _mitsuba_polarized()
    with mitsuba_variant(mi, variant):
        ti, tr, ph = geometries(40, 6, top=math.radians(80))
        for dist, mdist in (("trowbridge-reitz", "ggx"), ("beckmann", "beckmann")):
            bsdf = mi.load_dict({"type": "roughconductor", "distribution": mdist, "alpha": 0.3,
                                 "eta": 0.2, "k": 3.0, "sample_visible": False})
            m = rb.model("microfacet", distribution=dist, shadowing="smith-separable",
                         alpha=0.3, n=0.2, k=3.0)
            ref = np.array([_mitsuba_mueller(mi, bsdf, *g) for g in zip(ti, tr, ph, strict=True)])
            got = m.mueller(ti, tr, ph) * np.cos(ti)[:, None, None]
            if dist == "trowbridge-reitz":  # the same BSDF: float32 rounding (measured 2e-6)
                assert_within(got, ref, 2e-5 * got[:, :1, :1])
            # Mitsuba's Beckmann G1 is a rational approximation (docs/models.md §10.3): compare
            # the polarization, M/m00, which does not depend on D and G, where Mitsuba's float32
            # D has not underflowed (m00 above 1e-6 of the largest)
            keep = ref[:, 0, 0] > 1e-6 * ref[:, 0, 0].max()
            assert keep.sum() >= 20
            np.testing.assert_allclose(got[keep] / got[keep, :1, :1],
                                       ref[keep] / ref[keep, :1, :1], rtol=0, atol=2e-5)
