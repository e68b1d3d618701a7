"""Facet distributions: normalization ∫ D cos(theta_h) dω = 1 (docs/models.md §3.7), closed forms,
peak-normalized shapes (TR75 Fig. 5), registry with aliases, Smith Lambda.

The normalization integrals are computed here with composite Gauss-Legendre quadrature on
panels graded toward the lobe, independently of the library's own normalization constants
(closed forms for TR/Beckmann/Berry, SciPy ``quad`` for gaussian-angle and Sirohi).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import roughbrdf as rb

D = rb.distributions


def hemisphere_integral(fn, width: float) -> float:
    """2 pi ∫_0^{pi/2} fn(theta) sin(theta) dtheta, Gauss-Legendre on geometric panels."""
    x, w = np.polynomial.legendre.leggauss(40)
    edges = np.unique(np.concatenate([[0.0], np.geomspace(min(width, 1.0) * 1e-4, math.pi / 2,
                                                          60)]))
    a, b = edges[:-1, None], edges[1:, None]
    t = 0.5 * (b - a) * x + 0.5 * (a + b)
    wt = 0.5 * (b - a) * w
    return float(2 * math.pi * np.sum(wt * fn(t.ravel()).reshape(t.shape) * np.sin(t)))


def norm_of(name, param, width):
    return hemisphere_integral(lambda t: D.evaluate(name, np.cos(t), param) * np.cos(t), width)


@pytest.mark.parametrize("e", [0.05, 0.07, 0.1, 0.2, 0.3, 0.5, 0.68, 1.0, 1.6, 2.0, 3.0])
def test_trowbridge_reitz_normalized_1e9(e):
    # docs/models.md §3.7 / §6: ∫ D_std cos(alpha) dΩ = 1 for e = 0.05 ... 3, to 1e-9
    assert norm_of("trowbridge-reitz", e, e) == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("name, params, width", [
    ("beckmann", [0.05, 0.1, 0.3, 0.5, 1.0, 2.0], None),
    ("gaussian-angle", [0.01, 0.02, 0.035, 0.046, 0.05, 0.1, 0.2, 0.5], None),
    ("berry", [0.05, 0.1, 0.25, 0.5, 0.999999, 1.0, 1.5, 3.0], None),
    ("sirohi", [0.5, 1.0, 6.93, 20.0, 100.0, 400.0], None),
])
def test_every_distribution_normalized(name, params, width):
    for p in params:
        w = {"gaussian-angle": 1 / (p * 57.3), "sirohi": 1 / math.sqrt(p)}.get(name, p)
        assert norm_of(name, p, w) == pytest.approx(1.0, abs=1e-9), (name, p)


def test_registry_is_complete():
    assert set(D.names()) == {"trowbridge-reitz", "beckmann", "gaussian-angle", "berry",
                              "sirohi"}


@pytest.mark.parametrize("alias, canonical", [
    ("ggx", "trowbridge-reitz"), ("GGX", "trowbridge-reitz"), ("tr75", "trowbridge-reitz"),
    ("Trowbridge_Reitz", "trowbridge-reitz"), ("ts67", "gaussian-angle"),
    ("rense", "gaussian-angle"), ("Beckmann", "beckmann"),
])
def test_aliases(alias, canonical):
    assert D.get(alias).name == canonical
    c = np.linspace(0.1, 1, 5)
    p = {"gaussian-angle": 0.05}.get(canonical, 0.4)
    np.testing.assert_array_equal(D.evaluate(alias, c, p), D.evaluate(canonical, c, p))


@pytest.mark.parametrize("typo, suggestion", [("bekmann", "beckmann"), ("gxx", "ggx"),
                                              ("trowbridge-reits", "trowbridge-reitz"),
                                              ("sirohy", "sirohi")])
def test_unknown_name_suggests(typo, suggestion):
    with pytest.raises(ValueError, match=rf"unknown distribution '{typo}'.*did you mean.*"
                                         rf"'{suggestion}'"):
        D.get(typo)
    with pytest.raises(ValueError, match="did you mean"):
        D.evaluate(typo, 0.5, 0.3)
    with pytest.raises(ValueError, match="did you mean"):
        rb.model("microfacet", distribution=typo)


def test_ggx_closed_form_and_alpha_equals_e():
    # D = e^2/(pi (e^2 cos^2 + sin^2)^2) (docs/models.md §3.7), = GGX with alpha = e
    c = np.linspace(0.0, 1.0, 101)
    for e in (0.05, 0.3, 1.0, 2.5):
        expected = e**2 / (np.pi * (e**2 * c**2 + 1 - c**2) ** 2)
        np.testing.assert_allclose(D.trowbridge_reitz(c, e), expected, rtol=1e-13)
        np.testing.assert_allclose(D.ggx(c, e), expected, rtol=1e-13)
        # Walter et al. 2007 GGX form: alpha^2 / (pi cos^4 (alpha^2 + tan^2)^2)
        cc = c[c > 0]
        walter = e**2 / (np.pi * cc**4 * (e**2 + (1 - cc**2) / cc**2) ** 2)
        np.testing.assert_allclose(D.trowbridge_reitz(cc, e), walter, rtol=1e-10)
    assert float(D.trowbridge_reitz(1.0, 0.5)) == pytest.approx(1 / (np.pi * 0.25), rel=1e-15)


def test_tr_peak_shape_eq31():
    # TR75 Eq. 31: D(alpha) = e^4/(e^2 cos^2 + sin^2)^2, normalized to D(0) = 1
    a = np.linspace(0, np.pi / 2, 50)
    e = 0.4
    np.testing.assert_allclose(D.evaluate("tr", np.cos(a), e, peak_normalized=True),
                               e**4 / (e**2 * np.cos(a) ** 2 + np.sin(a) ** 2) ** 2, rtol=1e-13)


@pytest.mark.parametrize("e", [0.1, 0.68, 1.0, 2.0])
def test_tr_fraction_below_45_deg(e):
    # docs/models.md §3.7: the fraction of micro-area (projected) with alpha < 45 deg is 1/(1 + e^2)
    x, w = np.polynomial.legendre.leggauss(200)
    t = (x + 1) * math.pi / 8
    frac = 2 * math.pi * np.sum(w * math.pi / 8 * D.trowbridge_reitz(np.cos(t), e) * np.cos(t)
                                * np.sin(t))
    assert frac == pytest.approx(1 / (1 + e**2), abs=1e-10)


def test_beckmann_closed_form():
    # exp(-tan^2/m^2)/(pi m^2 cos^4) (DESIGN.md public interface)
    c = np.linspace(0.05, 1.0, 50)
    for m in (0.1, 0.36, 1.0):
        expected = np.exp(-(1 - c**2) / c**2 / m**2) / (np.pi * m**2 * c**4)
        np.testing.assert_allclose(D.beckmann(c, m), expected, rtol=1e-12)
    assert float(D.beckmann(0.0, 0.3)) == 0.0  # the limit at grazing


def test_gaussian_angle_b0():
    # docs/models.md §2.3: b0 = 2.8316 sr^-1 for c = 0.05/deg (1.5067 for 0.035, 2.4316 for 0.046),
    # with theta_h in radians at the API and c per degree
    for c, b0 in [(0.05, 2.8316), (0.035, 1.5067), (0.046, 2.4316)]:
        peak = float(D.gaussian_angle(0.0, c))
        assert peak == pytest.approx(b0, abs=5e-5)
        th = np.radians(np.array([5.0, 20.0, 40.0]))
        np.testing.assert_allclose(D.gaussian_angle(th, c),
                                   peak * np.exp(-(c * np.degrees(th)) ** 2), rtol=1e-14)


def test_berry_and_sirohi_shapes():
    # TR75 Fig. 5 forms (docs/models.md §3.11): Berry e^2/(e^2 cos^2 + sin^2); Sirohi (p = 2)
    # cos^-2 exp(-A2 tan^2)
    a = np.linspace(0, 1.5, 40)
    c = np.cos(a)
    np.testing.assert_allclose(D.evaluate("berry", c, 0.25, peak_normalized=True),
                               0.0625 / (0.0625 * c**2 + np.sin(a) ** 2), rtol=1e-13)
    np.testing.assert_allclose(D.evaluate("sirohi", c, 6.93, peak_normalized=True),
                               np.exp(-6.93 * np.tan(a) ** 2) / c**2, rtol=1e-12)
    # Berry's closed-form normalization (e^2 - 1)/(pi e^2 ln e^2), -> 1/pi at e = 1
    for e in (0.25, 2.0):
        assert float(D.berry(1.0, e)) == pytest.approx((e * e - 1) / (np.pi * e * e *
                                                                      math.log(e * e)))
    assert float(D.berry(1.0, 1.0)) == pytest.approx(1 / np.pi, rel=1e-12)


@settings(max_examples=40, deadline=None)
@given(c=st.floats(0.0, 1.0), e=st.floats(0.01, 5.0))
def test_distributions_positive_and_one_at_normal(c, e):
    for name in ("trowbridge-reitz", "beckmann", "berry", "sirohi"):
        p = D.evaluate(name, c, e, peak_normalized=True)
        assert p >= 0.0 and np.isfinite(p)
        assert D.evaluate(name, 1.0, e, peak_normalized=True) == 1.0
        # oblate ellipsoids (e <= 1) have their maximum at the normal; prolate ones (e > 1,
        # "vertical grass blades", docs/models.md §3.7) at grazing
        if name in ("trowbridge-reitz", "berry"):
            assert (p <= 1.0 + 1e-12) if e <= 1 else (p >= 1.0 - 1e-12)


def test_smith_lambda():
    # GGX: Lambda = (-1 + sqrt(1 + a^2 tan^2))/2 (Walter et al. 2007, Eq. 72)
    c = np.linspace(0.01, 1.0, 50)
    t2 = (1 - c**2) / c**2
    for a in (0.1, 0.5, 1.2):
        np.testing.assert_allclose(D.lambda_smith("ggx", c, a),
                                   0.5 * (-1 + np.sqrt(1 + a * a * t2)), rtol=1e-10, atol=1e-15)
    # Beckmann: (erf(u) - 1)/2 + exp(-u^2)/(2 u sqrt(pi)), u = 1/(m tan) (Walter Eq. 27)
    from scipy.special import erfc

    cc = c[:-1]
    u = cc / (0.3 * np.sqrt(1 - cc**2))
    expected = -0.5 * erfc(u) + np.exp(-u * u) / (2 * u * np.sqrt(np.pi))
    np.testing.assert_allclose(D.lambda_smith("beckmann", cc, 0.3), expected, rtol=1e-9,
                               atol=1e-300)
    assert float(D.lambda_smith("ggx", 1.0, 0.5)) == 0.0
    with pytest.raises(ValueError, match="Smith"):
        D.lambda_smith("berry", 0.5, 0.3)


@pytest.mark.parametrize("fn, arg", [(D.trowbridge_reitz, "e"), (D.beckmann, "m"),
                                     (D.gaussian_angle, "c"), (D.berry, "e"), (D.sirohi, "A2")])
@pytest.mark.parametrize("bad", [0.0, -0.5, math.nan, math.inf])
def test_invalid_parameter_raises(fn, arg, bad):
    with pytest.raises(ValueError, match=rf"\b{arg}\b.*{bad!r}"):
        fn(0.5, bad)


@pytest.mark.parametrize("bad", [-0.1, 1.1, math.nan])
def test_invalid_cos_raises(bad):
    with pytest.raises(ValueError, match=rf"cos_theta_h.*{bad!r}"):
        D.trowbridge_reitz(np.array([0.5, bad]), 0.3)
    with pytest.raises(ValueError, match=r"theta_h"):
        D.gaussian_angle(np.array([0.1, 2.0]), 0.05)
