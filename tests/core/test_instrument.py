"""roughbrdf.instrument: the aperture value, the cone directions, the geometry seen through it.

The accuracy of the cubature rules (degree by degree against a product rule) and the fits with an
aperture are tested in tests/fitting/test_fitting.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf import geometry, instrument
from roughbrdf.instrument import Aperture, InstrumentGeometry


def test_aperture_parse_and_validation():
    assert Aperture.parse(None) is None and Aperture.parse(0.0) is None
    a = Aperture.parse(np.float64(0.02), 37)
    assert a == Aperture(0.02, 37) and isinstance(a.half_angle, float)
    assert Aperture(1).half_angle == 1.0  # numbers are converted
    for bad in (-0.1, math.pi / 2, math.nan, "wide"):
        with pytest.raises(ValueError, match="aperture"):
            Aperture.parse(bad)
    with pytest.raises(ValueError, match="aperture_points must be one of"):
        Aperture(0.01, 9)
    with pytest.raises(ValueError, match="needs a half-angle > 0"):
        Aperture(0.0)
    d = Aperture(math.radians(1.5), 7).to_dict()
    assert d["half_angle_deg"] == pytest.approx(1.5) and d["points"] == 7
    assert Aperture(math.radians(1.0)).describe().startswith("1 deg half-angle")
    # points are only checked with an aperture, as rb.fit did
    assert instrument.check_aperture(None, 9) is None


def test_gauss_radau_is_exact_to_degree_2m():
    for m in (1, 2, 3):
        u, w = instrument.gauss_radau01(m)
        assert u[0] == 0.0 and np.all(np.diff(u) > 0) and np.all(w > 0)
        for k in range(2 * m + 1):
            assert float(w @ u ** k) == pytest.approx(1.0 / (k + 1), abs=1e-14), (m, k)
        assert abs(float(w @ u ** (2 * m + 1)) - 1.0 / (2 * m + 2)) > 1e-6


def test_directions_keep_the_axis_and_the_cone_angle():
    a = math.radians(3.0)
    tr = np.radians([0.0, 20.0, 60.0])
    ph = np.radians([0.0, -40.0, 170.0])
    tr_s, ph_s, w = instrument.aperture_directions(tr, ph, a, 19)
    assert tr_s.shape == ph_s.shape == (3, 19) and w.shape == (19,)
    np.testing.assert_allclose(tr_s[:, 0], tr, atol=1e-12)
    beta, _, _ = instrument.aperture_stencil(a, 19)
    _, axis = geometry.unit_vectors(0.0, tr, ph)
    _, dirs = geometry.unit_vectors(np.zeros_like(tr_s), tr_s, ph_s)
    ang = np.arccos(np.clip(np.einsum("nsk,nk->ns", dirs, axis), -1, 1))
    np.testing.assert_allclose(ang, np.broadcast_to(beta, ang.shape), atol=1e-7)


def test_instrument_geometry_matches_aperture_average_and_takes_subsets():
    m = rb.model("trowbridge-reitz-1975", e=0.1)
    rng = np.random.default_rng(0)
    n = 40
    ti, tr, ph = rng.uniform(0, 1.2, n), rng.uniform(0, 1.3, n), rng.uniform(-3, 3, n)
    gam = np.where(np.arange(n) % 2 == 0, 0.0, math.pi / 2)
    ap = Aperture(math.radians(2.0), 7)
    inst = InstrumentGeometry.build(ti, tr, ph, gam, ap)
    assert inst.n == n and inst.stencil_size == 7 and inst.geometry.theta_r.shape == (n * 7,)
    want = instrument.aperture_average(m, ti, tr, ph, ap, quantity="bridf", polarization=gam)
    np.testing.assert_array_equal(inst.evaluate(m, "bridf"), want)
    sub = np.array([3, 0, 17])
    np.testing.assert_array_equal(inst.take(sub).evaluate(m, "bridf"), want[sub])
    plain = InstrumentGeometry.build(ti, tr, ph, np.asarray(np.nan), None)
    assert plain.weights is None and plain.stencil_size == 1
    np.testing.assert_array_equal(plain.take(sub).evaluate(m, "brdf"), m.brdf(ti, tr, ph)[sub])


def test_aperture_average_shapes_and_errors():
    m = rb.model("lambertian", rho=0.2)
    assert isinstance(instrument.aperture_average(m, 0.1, 0.2, 0.0, 0.01), float)
    out = instrument.aperture_average(m, np.zeros((2, 3)), 0.2, 0.0, Aperture(0.01))
    assert out.shape == (2, 3)
    np.testing.assert_array_equal(instrument.aperture_average(m, 0.1, [0.2, 0.3], 0.0, None),
                                  m.brdf(0.1, [0.2, 0.3], 0.0))
    with pytest.raises(ValueError, match="quantity must be 'brdf' or 'bridf'"):
        instrument.aperture_average(m, 0.1, 0.2, 0.0, 0.01, quantity="relative")


def test_fitting_reexports_the_instrument():
    from roughbrdf import fitting

    assert fitting.aperture_average is instrument.aperture_average
    assert fitting.aperture_stencil is instrument.aperture_stencil
    assert fitting.APERTURE_POINTS is instrument.APERTURE_POINTS
