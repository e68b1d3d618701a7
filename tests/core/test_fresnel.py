"""Fresnel reflectance (docs/models.md §1.4, TR75 Eqs. 20-24).

Oracles: TR75's real-arithmetic Eqs. 20-21, written out below independently of the library;
the normal-incidence formula Eq. 22; Brewster's angle; Snell's law and total internal reflection
for n < 1; textbook values.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import roughbrdf as rb

R = rb.fresnel.reflectance


def tr75_eq20_21(s: float, n: float, k: float) -> tuple[float, float]:
    """TR75 Eqs. 20-21 in real arithmetic (docs/models.md §1.4), for local incidence angle s (rad).

    With m2 = n^2 + k^2, a = n sin s/m2, b = k sin s/m2, c = 1 - sin^2 s/m2:
    sinh^2 x = (sqrt(c^2 + 4 b^2) - c)/2, sin s1 = a/cosh x,
    R_perp = [sin^2(s - s1) + sinh^2 x]/[sin^2(s + s1) + sinh^2 x],
    R_par  = R_perp [cos^2(s + s1) + sinh^2 x]/[cos^2(s - s1) + sinh^2 x].
    At s = 0 (0/0) Eq. 22 is used. For n < 1 and k = 0 beyond the critical angle, sin s1 > 1:
    the refracted wave is evanescent and R = 1 (docs/models.md §1.4 "R -> 1 beyond the critical
    angle").
    """
    if s == 0.0:
        r0 = ((n - 1) ** 2 + k**2) / ((n + 1) ** 2 + k**2)
        return r0, r0
    m2 = n * n + k * k
    sin_s = math.sin(s)
    a = n * sin_s / m2
    b = k * sin_s / m2
    c = 1 - sin_s**2 / m2
    if c <= 0 and 2 * b <= 1e-12 * -c:  # beyond the critical angle with no (or negligible,
        # e.g. k = 1e-187) absorption: sin s1 = 1 to rounding, and Eq. 20-21 give 1 to 1e-12
        # (evaluating asin at a rounded 1 - 1e-16 would lose 8 digits)
        return 1.0, 1.0
    root = math.sqrt(c * c + 4 * b * b)
    # (root - c)/2, written without cancellation when c > 0 (small s, where root ~ c)
    sinh2 = 2 * b * b / (root + c) if c > 0 else (root - c) / 2
    sin_s1 = a / math.sqrt(1 + sinh2)
    if sin_s1 >= 1.0:  # total internal reflection (k = 0, n < 1)
        return 1.0, 1.0
    s1 = math.asin(sin_s1)
    r_perp = (math.sin(s - s1) ** 2 + sinh2) / (math.sin(s + s1) ** 2 + sinh2)
    r_par = r_perp * (math.cos(s + s1) ** 2 + sinh2) / (math.cos(s - s1) ** 2 + sinh2)
    return r_perp, r_par


INDICES = [(1.5, 0.0), (1.0, 0.9), (0.9, 1.9), (0.7, 1.3), (1.6, 0.3), (0.77, 6.08),
           (2.5, 0.01), (4.0, 3.0), (1.74, 0.0), (0.2, 3.0)]


@pytest.mark.parametrize("n, k", INDICES)
def test_tr75_eqs_20_21_oracle(n, k):
    s = np.radians(np.linspace(0.0, 89.9, 300))
    oracle = np.array([tr75_eq20_21(x, n, k) for x in s])
    np.testing.assert_allclose(R(np.cos(s), n, k, "s"), oracle[:, 0], rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(R(np.cos(s), n, k, "p"), oracle[:, 1], rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(R(np.cos(s), n, k), oracle.mean(axis=1), rtol=1e-10, atol=1e-14)


@settings(max_examples=60, deadline=None)
@given(s=st.floats(1e-6, math.radians(89.99)), n=st.floats(0.05, 10.0), k=st.floats(0.0, 10.0))
def test_tr75_oracle_property(s, n, k):
    # (the oracle is 0/0 as s -> 0, where docs/models.md §1.4 says to use Eq. 22, tested below)
    rs, rp = tr75_eq20_21(s, n, k)
    assert R(math.cos(s), n, k, "s") == pytest.approx(rs, rel=1e-8, abs=1e-12)
    assert R(math.cos(s), n, k, "p") == pytest.approx(rp, rel=1e-8, abs=1e-12)


@pytest.mark.parametrize("n, k", INDICES)
def test_normal_incidence_eq22(n, k):
    # TR75 Eq. 22: R(0) = ((n - 1)^2 + k^2)/((n + 1)^2 + k^2), for s, p and unpolarized
    r0 = ((n - 1) ** 2 + k**2) / ((n + 1) ** 2 + k**2)
    for pol in ("s", "p", "unpolarized", 0.3):
        assert R(1.0, n, k, pol) == pytest.approx(r0, rel=1e-13)


def test_textbook_values():
    assert R(1.0, 1.5) == pytest.approx(0.04, rel=1e-14)  # glass at normal incidence
    assert R(1.0, 1.0, 0.0) == 0.0  # index matched
    assert R(math.cos(math.radians(45)), 1.5, 0.0, "s") == pytest.approx(0.0920, abs=1e-4)
    assert R(math.cos(math.radians(45)), 1.5, 0.0, "p") == pytest.approx(0.0085, abs=1e-4)


@pytest.mark.parametrize("n, k", INDICES)
def test_grazing_incidence_is_one(n, k):
    # R -> 1 at grazing incidence, for every index and polarization
    for pol in ("s", "p", "unpolarized"):
        assert R(0.0, n, k, pol) == pytest.approx(1.0, abs=1e-14)
        assert R(1e-9, n, k, pol) == pytest.approx(1.0, abs=1e-7)


@pytest.mark.parametrize("n", [1.33, 1.5, 1.74, 2.4, 4.0, 0.75, 0.5])
def test_brewster_angle(n):
    # R_p = 0 at tan(theta_B) = n for k = 0 (also for n < 1, internal incidence)
    theta_b = math.atan(n)
    assert R(math.cos(theta_b), n, 0.0, "p") == pytest.approx(0.0, abs=1e-15)
    assert R(math.cos(theta_b), n, 0.0, "s") > 1e-3
    # and it is the minimum of R_p
    t = np.linspace(0, math.pi / 2, 2001)
    rp = R(np.cos(t), n, 0.0, "p")
    assert abs(t[np.argmin(rp)] - theta_b) < 1e-3


@pytest.mark.parametrize("n", [0.5, 0.67, 0.9])
def test_total_internal_reflection(n):
    # a dielectric with n < 1 (light inside the denser medium): R = 1 beyond the critical angle
    crit = math.asin(n)
    beyond = np.linspace(crit + 1e-9, math.pi / 2, 50)
    for pol in ("s", "p", "unpolarized"):
        np.testing.assert_allclose(R(np.cos(beyond), n, 0.0, pol), 1.0, atol=1e-12)
    below = np.linspace(0, crit - 1e-3, 50)
    assert np.all(R(np.cos(below), n, 0.0) < 1.0)
    # below the critical angle, Snell's law gives the textbook amplitudes
    t = below[1:]
    tt = np.arcsin(np.sin(t) / n)
    rs = (np.sin(t - tt) / np.sin(t + tt)) ** 2
    rp = (np.tan(t - tt) / np.tan(t + tt)) ** 2
    ok = t > 1e-6
    np.testing.assert_allclose(R(np.cos(t[ok]), n, 0.0, "s"), rs[ok], rtol=1e-9)
    np.testing.assert_allclose(R(np.cos(t[ok]), n, 0.0, "p"), rp[ok], rtol=1e-9, atol=1e-15)


@pytest.mark.parametrize("n", [1.2, 1.5, 2.0, 0.8])
def test_snell_dielectric(n):
    # k = 0, n > 1: R_s and R_p from the Fresnel amplitudes with Snell's law
    t = np.linspace(0.01, 1.55, 100)
    valid = np.sin(t) / n < 1
    t = t[valid]
    valid = valid[valid]
    tt = np.arcsin(np.sin(t) / n)
    rs = (np.sin(t - tt) / np.sin(t + tt)) ** 2
    rp = (np.tan(t - tt) / np.tan(t + tt)) ** 2
    np.testing.assert_allclose(R(np.cos(t), n, 0.0, "s")[valid], rs[valid], rtol=1e-9)
    np.testing.assert_allclose(R(np.cos(t), n, 0.0, "p")[valid], rp[valid], rtol=1e-9,
                               atol=1e-15)


def test_conjugate_index_convention():
    # docs/models.md §1.4: n + ik and n - ik give identical reflectances; with the library's k >= 0
    # this is a check against NumPy complex arithmetic with the conjugate index n - ik
    c = np.linspace(0, 1, 101)
    for n, k in INDICES:
        m = complex(n, -k)
        root = np.sqrt(m * m - (1 - c * c) + 0j)
        root = np.where(root.real < 0, -root, root)
        rs = np.abs((c - root) / (c + root)) ** 2
        rp = np.abs((m * m * c - root) / (m * m * c + root)) ** 2
        np.testing.assert_allclose(R(c, n, k, "s"), rs, rtol=1e-10, atol=1e-14)
        np.testing.assert_allclose(R(c, n, k, "p"), rp, rtol=1e-10, atol=1e-14)


def test_polarization_angle_eq24():
    # TR75 Eq. 24: R(gamma) = R_perp sin^2(gamma - eta) + R_par cos^2(gamma - eta)
    c, n, k = 0.6, 1.3, 0.7
    rs, rp = R(c, n, k, "s"), R(c, n, k, "p")
    for gamma in np.linspace(-3, 3, 13):
        for eta in (0.0, 0.4, -1.1):
            expected = rs * math.sin(gamma - eta) ** 2 + rp * math.cos(gamma - eta) ** 2
            assert R(c, n, k, gamma, eta=eta) == pytest.approx(expected, rel=1e-13)
    assert R(c, n, k, 0.0) == pytest.approx(rp, rel=1e-14)  # gamma = 0: p
    assert R(c, n, k, math.pi / 2) == pytest.approx(rs, rel=1e-14)  # gamma = 90 deg: s
    assert R(c, n, k) == pytest.approx(0.5 * (rs + rp), rel=1e-14)
    for name in ("natural", "circular", None):
        assert R(c, n, k, name) == pytest.approx(0.5 * (rs + rp), rel=1e-14)
    assert R(c, n, k, "perpendicular") == R(c, n, k, "s")
    assert R(c, n, k, "parallel") == R(c, n, k, "p")


def test_reflectance_in_unit_interval_and_broadcasts():
    c = np.linspace(0, 1, 7)[:, None, None]
    n = np.array([0.5, 1.0, 1.5, 3.0])[None, :, None]
    k = np.array([0.0, 0.5, 5.0])[None, None, :]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no RuntimeWarning from the compiled ufunc
        out = R(c, n, k)
    assert out.shape == (7, 4, 3)
    assert np.all((out >= 0) & (out <= 1 + 1e-15))


@pytest.mark.parametrize("kw, name", [
    ({"cos_theta": 1.2}, "cos_theta"), ({"cos_theta": -0.1}, "cos_theta"),
    ({"cos_theta": math.nan}, "cos_theta"), ({"n": 0.0}, "n"), ({"n": -1.0}, "n"),
    ({"n": math.inf}, "n"), ({"k": -0.1}, "k"), ({"k": math.nan}, "k"),
])
def test_invalid_inputs_raise(kw, name):
    args = {"cos_theta": 0.5, "n": 1.5, "k": 0.1, **kw}
    bad = next(iter(kw.values()))
    with pytest.raises(ValueError, match=rf"\b{name}\b.*{bad!r}"):
        R(**args)


def test_invalid_polarization_raises():
    with pytest.raises(ValueError, match="polarization"):
        R(0.5, 1.5, 0.0, "circularly")
    with pytest.raises(ValueError, match="gamma"):
        R(0.5, 1.5, 0.0, math.inf)


def test_sincos_kernel_accuracy():
    # the vectorizable sin/cos used by every kernel (the kernel layer's vmath.sincos, fdlibm
    # polynomials)
    from roughbrdf._kernels.vmath import SINCOS_MAX_ARG, sincos

    rng = np.random.default_rng(0)
    for lo, hi in [(0, math.pi / 2), (-math.pi, math.pi), (-SINCOS_MAX_ARG, SINCOS_MAX_ARG)]:
        x = np.concatenate([rng.uniform(lo, hi, 3000), [0.0, math.pi / 2, math.pi, 1e-300]])
        got = np.array([sincos(v) for v in x])
        np.testing.assert_allclose(got[:, 0], np.sin(x), rtol=0, atol=2.3e-16)
        np.testing.assert_allclose(got[:, 1], np.cos(x), rtol=0, atol=2.3e-16)
    assert all(math.isnan(v) for v in sincos(math.nan))
