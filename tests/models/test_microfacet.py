"""The microfacet model at its edges (docs/models.md, microfacet: F D G / (4 cos cos))."""

from __future__ import annotations

import numpy as np

import roughbrdf as rb


def test_unshadowed_beckmann_at_the_horizon_is_its_limit_not_nan():
    # Found by tests/models/test_invariants.py (Hypothesis): theta_r = 90 deg on the source side,
    # where Beckmann's D is a subnormal number. Without shadowing 1/(cos cos) diverges there,
    # so the BRDF's limit is inf (as TR75's, README), never NaN; BRIDF stays finite (>= 0).
    m = rb.model("microfacet", distribution="beckmann", shadowing="none", alpha=0.3)
    ti, tr, phi = 1.37348722, np.full(3, np.pi / 2), np.array([1.90039062, 0.0, np.pi])
    f = m.brdf(ti, tr, phi)
    assert not np.isnan(f).any() and (f >= 0).all()
    # D > 0 (subnormal) at the first two: the limit inf; at phi = 180 deg D underflows to 0
    assert np.isinf(f[:2]).all()
    b = m.bridf(ti, tr, phi)
    assert np.isfinite(b).all() and (b >= 0).all()


def test_the_reordered_product_changes_no_ordinary_value():
    # 0.25 * (t * geo) equals (0.25 * t) * geo bit for bit away from under/overflow (a power
    # of two scales exactly): the model's values at ordinary angles are those of the formula
    m = rb.model("microfacet", distribution="beckmann", shadowing="none", alpha=0.3,
                 n=1.5, k=0.0)
    ti, tr, phi = np.radians(30.0), np.radians(30.0), 0.0
    d = rb.distributions.beckmann(1.0, 0.3)  # at the specular direction theta_h = 0
    f = rb.fresnel.reflectance(np.cos(ti), 1.5)
    expected = f * d / (4 * np.cos(ti) * np.cos(tr))
    assert np.isclose(m.brdf(ti, tr, phi), expected, rtol=1e-12, atol=0)
