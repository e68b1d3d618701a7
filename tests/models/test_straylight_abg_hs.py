"""ABg and Harvey–Shack (the optical codes' stray-light models) and their TIS.

Sources of the expected numbers:

* the definitions: Zemax OpticStudio help, "Available Scatter Models" (ABg: ``A/(B + |β-β0|^g)``,
  ``A >= 0``, ``B > 1e-12`` unless ``g = 0``, constant BSDF at ``g = 0``), and FRED's help,
  "Scatter Types > Harvey-Shack" (``b0`` the BSDF at ``β = β0``, ``L`` the knee, ``S`` the
  slope, ``S < 0``) — ``docs/straylight.md``;
* identities: ``|β - β0|`` is symmetric in the two zenith angles (reciprocity) and in
  ``phi -> -phi``; ``cos(theta_r) dΩ = d²β`` (TIS = area integral over the unit disk);
* closed forms derived in ``roughbrdf.models.straylight.tis``: Harvey–Shack
  ``G(r) = b0 L²((1 + r²/L²)^((S+2)/2) - 1)/(S + 2)``; ABg at normal incidence
  ``2π G(1) = plane · I_x(2/g, 1 - 2/g)``, ``x = 1/(1 + B)`` (regularized incomplete beta
  function, SciPy), plane ``2π² A B^(2/g-1)/(g sin(2π/g))``;
* an independent integrator, :func:`roughbrdf.albedo` (quadrature centred on the specular
  direction in angle space, not in ``β``).
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from hypothesis_profiles import jit_disabled
from scipy.integrate import quad
from scipy.special import betainc

import roughbrdf as rb
import roughbrdf.models.straylight as sl
from roughbrdf.errors import ArgumentError

HALF_PI = math.pi / 2
RNG = np.random.default_rng(21)
#: NUMBA_DISABLE_JIT=1 (make test-nojit): the kernels run as plain Python (100 to 1000 times
#: slower); the TIS-against-albedo tests take fewer cases and incidences there (_tis_cases)
NOJIT = jit_disabled(os.environ)


def _beta_geometry(beta0x: np.ndarray, dx: np.ndarray, dy: np.ndarray):
    """Angles (theta_i, theta_r, phi) with β0 = (beta0x, 0) and β = β0 + (dx, dy)."""
    bx, by = beta0x + dx, dy
    return np.arcsin(beta0x), np.arcsin(np.hypot(bx, by)), np.arctan2(by, bx)


MODELS = [("abg", {"A": 0.0025, "B": 0.001, "g": 1.8}),
          ("abg", {"A": 0.2, "B": 0.05, "g": -0.7}),
          ("harvey-shack", {"b0": 0.1, "L": 0.01, "S": -1.5}),
          ("hs", {"b0": 3.0, "L": 0.2, "S": -3.0})]


@pytest.fixture(params=range(len(MODELS)), ids=[f"{n}-{kw}" for n, kw in MODELS])
def model(request):
    name, kw = MODELS[request.param]
    return rb.model(name, **kw)


# ------------------------------------------------------------------------------------------
# registration
# ------------------------------------------------------------------------------------------
def test_registered_under_names_and_aliases():
    assert {"abg", "harvey-shack"} <= set(rb.available())
    assert type(rb.model("ABg")) is sl.ABg and type(rb.model("zemax-abg")) is sl.ABg
    for alias in ("hs", "Harvey-Shack", "harvey_shack"):
        assert type(rb.model(alias)) is sl.HarveyShack
    assert rb.model("abg").grazing_incidence and rb.model("hs").grazing_incidence


# ------------------------------------------------------------------------------------------
# identities of the definitions
# ------------------------------------------------------------------------------------------
def test_shift_invariance_in_beta(model):
    # the same displacement β - β0 from two different specular points: the BSDF depends on
    # |β - β0| only (Zemax "Scatter Models"; FRED "linear shift-invariant")
    n = 50
    ang = RNG.uniform(-math.pi, math.pi, n)
    rho = RNG.uniform(0.0, 0.3, n)
    dx, dy = rho * np.cos(ang), rho * np.sin(ang)
    f1 = model.brdf(*_beta_geometry(np.full(n, 0.1), dx, dy))
    f2 = model.brdf(*_beta_geometry(np.full(n, 0.6), dx, dy))
    # a third: the same |β - β0| along another direction at a third incidence
    f3 = model.brdf(*_beta_geometry(np.full(n, 0.3), -rho, np.zeros(n)))
    np.testing.assert_allclose(f1, f2, rtol=1e-11)
    np.testing.assert_allclose(f1, f3, rtol=1e-11)
    # and at normal incidence the BSDF is a function of sin(theta_r) alone, any azimuth
    tr = np.arcsin(rho)
    np.testing.assert_allclose(model.brdf(0.0, tr, ang), f1, rtol=1e-11)


def test_abg_with_g_zero_is_constant():
    # Zemax: "If g is 0.0 ... the BSDF is constant" = A/(B + 1), and B = 0 is then allowed
    ti = RNG.uniform(0.0, HALF_PI, 200)
    tr = RNG.uniform(0.0, HALF_PI, 200)
    ph = RNG.uniform(-math.pi, math.pi, 200)
    for a, b in ((0.5, 0.25), (0.3, 0.0)):
        m = rb.model("abg", A=a, B=b, g=0.0)
        np.testing.assert_allclose(m.brdf(ti, tr, ph), a / (b + 1.0), rtol=1e-15)
        assert m.brdf(0.4, 0.4, 0.0) == a / (b + 1.0)          # at the specular too
        assert m.brdf(HALF_PI, HALF_PI, math.pi) == a / (b + 1.0)


def test_reciprocity(model):
    # |β - β0|² = sin²θr + sin²θi - 2 sinθr sinθi cos φ is symmetric in θi <-> θr
    ti = RNG.uniform(0.0, HALF_PI, 100)
    tr = RNG.uniform(0.0, HALF_PI, 100)
    ph = RNG.uniform(-math.pi, math.pi, 100)
    np.testing.assert_allclose(model.brdf(ti, tr, ph), model.brdf(tr, ti, ph), rtol=1e-12)
    assert model.reciprocal
    assert float(np.max(rb.reciprocity_error(model, ti, tr, ph))) < 1e-12


def test_phi_symmetry(model):
    ti = RNG.uniform(0.0, HALF_PI, 100)
    tr = RNG.uniform(0.0, HALF_PI, 100)
    ph = RNG.uniform(0.0, math.pi, 100)
    np.testing.assert_array_equal(model.brdf(ti, tr, ph), model.brdf(ti, tr, -ph))


def test_bridf_is_bsdf_times_cos(model):
    ti, tr, ph = 0.3, np.linspace(0.0, HALF_PI, 7), 0.8
    want = model.brdf(ti, tr, ph) * np.cos(tr)
    want[-1] = 0.0  # the horizon: exactly 0 (cos(pi/2) rounds to 6e-17)
    np.testing.assert_allclose(model.bridf(ti, tr, ph), want, rtol=1e-14, atol=0.0)


def test_beta_distance_matches_the_vector_difference():
    ti = RNG.uniform(0.0, HALF_PI, 100)
    tr = RNG.uniform(0.0, HALF_PI, 100)
    ph = RNG.uniform(-math.pi, math.pi, 100)
    d = np.hypot(np.sin(tr) * np.cos(ph) - np.sin(ti), np.sin(tr) * np.sin(ph))
    got = np.array([sl.beta_distance(a, b, c) for a, b, c in zip(ti, tr, ph, strict=True)])
    np.testing.assert_allclose(got, d, rtol=1e-12, atol=1e-15)


# ------------------------------------------------------------------------------------------
# values at the specular, normal incidence, grazing (hand-computed from the definitions)
# ------------------------------------------------------------------------------------------
def test_values_at_special_geometries():
    m = rb.model("abg", A=0.5, B=0.25, g=2.0)
    assert m.brdf(0.7, 0.7, 0.0) == pytest.approx(2.0, rel=1e-15)          # A/B at specular
    # normal incidence, theta_r = 30 deg: |β - β0| = 1/2, A/(B + 1/4) = 1
    assert m.brdf(0.0, math.pi / 6, 2.0) == pytest.approx(1.0, rel=1e-14)
    # grazing incidence, grazing retro direction: |β - β0| = 2, A/(B + 4)
    assert m.brdf(HALF_PI, HALF_PI, math.pi) == pytest.approx(0.5 / 4.25, rel=1e-14)
    assert m.brdf(HALF_PI, HALF_PI, 0.0) == pytest.approx(2.0, rel=1e-15)  # grazing specular
    assert m.bridf(HALF_PI, HALF_PI, 0.0) == 0.0
    # g < 0: |β - β0|^g -> inf at the specular, the BSDF -> 0 (finite, not NaN)
    assert rb.model("abg", A=1.0, B=0.1, g=-1.0).brdf(0.3, 0.3, 0.0) == 0.0
    h = rb.model("hs", b0=0.4, L=2.0, S=-2.0)
    assert h.brdf(1.1, 1.1, 0.0) == pytest.approx(0.4, rel=1e-15)          # b0 at specular
    # grazing retro: |β - β0| = 2 = L, b0 (1 + 1)^(-1) = b0/2
    assert h.brdf(HALF_PI, HALF_PI, math.pi) == pytest.approx(0.2, rel=1e-14)
    # normal incidence, theta_r = 30 deg: b0 (1 + (0.5/2)²)^-1 = 0.4/1.0625
    assert h.brdf(0.0, math.pi / 6, 0.0) == pytest.approx(0.4 / 1.0625, rel=1e-14)


def test_no_nan_on_the_closed_hemisphere(model):
    edges = np.array([0.0, 1e-9, 0.5, HALF_PI - 1e-9, HALF_PI])
    ti, tr, ph = np.meshgrid(edges, edges, np.array([0.0, 1e-9, HALF_PI, math.pi]))
    for f in (model.brdf(ti, tr, ph), model.bridf(ti, tr, ph)):
        assert np.all(np.isfinite(f)) and np.all(f >= 0.0)


# ------------------------------------------------------------------------------------------
# inputs: n-dimensional, NaN/inf, bad parameters
# ------------------------------------------------------------------------------------------
def test_n_dimensional_inputs(model):
    ti = RNG.uniform(0.0, HALF_PI, (2, 1, 4))
    tr = RNG.uniform(0.0, HALF_PI, (1, 3, 4))
    ph = RNG.uniform(-math.pi, math.pi, (3, 1))
    f = model.brdf(ti, tr, ph)
    assert f.shape == (2, 3, 4)
    flat = [model.brdf(float(a), float(b), float(c))
            for a, b, c in zip(*(np.broadcast_arrays(ti, tr, ph)[k].ravel() for k in range(3)),
                               strict=True)]
    np.testing.assert_array_equal(f.ravel(), flat)
    t = model.tis(np.array([[0.0, 0.5], [1.0, HALF_PI]]))
    assert t.shape == (2, 2)
    assert t[1, 0] == model.tis(1.0) and isinstance(model.tis(1.0), float)
    assert model.tis(np.array([])).shape == (0,)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_nan_and_inf_angles_are_refused(model, bad):
    for pos, name in enumerate(("theta_i", "theta_r", "phi")):
        args = [0.3, 0.3, 0.3]
        args[pos] = np.array([0.1, bad])
        with pytest.raises(ArgumentError, match=name):
            model.brdf(*args)
    with pytest.raises(ArgumentError, match="theta_i"):
        model.tis([0.2, bad])


def test_out_of_range_incidence_is_refused(model):
    with pytest.raises(ArgumentError, match="theta_i"):
        model.tis(HALF_PI + 1e-9)
    with pytest.raises(ArgumentError, match="theta_i"):
        model.brdf(-0.1, 0.2, 0.0)


@pytest.mark.parametrize(("kw", "name"), [
    ({"A": -1e-3}, "A"), ({"A": math.nan}, "A"), ({"B": -1.0}, "B"),
    ({"B": 0.0}, "B"),                       # g = 1.8 (default): B > 1e-12 needed
    ({"B": 1e-12, "g": 2.0}, "B"),           # Zemax: "greater than 1E-12"
    ({"B": 0.0, "g": -1.0}, "B"), ({"g": math.inf}, "g"),
])
def test_bad_abg_parameters_name_the_parameter(kw, name):
    with pytest.raises(ArgumentError, match=repr(name)) as exc:
        rb.model("abg", **kw)
    assert exc.value.argument == name
    with pytest.raises(ArgumentError, match=name):
        sl.abg_tis(0.1, **{"A": 0.1, "B": 0.1, "g": 1.8, **kw})


def test_abg_b_zero_is_allowed_with_g_zero_and_with_params_checks_the_rule():
    m = rb.model("abg", A=0.2, B=0.0, g=0.0)
    assert m.brdf(0.1, 0.5, 0.2) == 0.2
    with pytest.raises(ArgumentError, match="B") as exc:
        m.with_params(g=1.0)                  # B = 0 no longer allowed
    assert exc.value.argument == "B"
    with pytest.raises(ArgumentError, match="B"):
        m.with_values(["g"], [2.0])
    assert rb.model("abg", B=2e-12).params["B"] == 2e-12


@pytest.mark.parametrize(("kw", "name"), [
    ({"b0": 0.0}, "b0"), ({"b0": -1.0}, "b0"), ({"L": 0.0}, "L"), ({"L": math.nan}, "L"),
    ({"S": 0.0}, "S"), ({"S": 1.0}, "S"),
])
def test_bad_harvey_shack_parameters_name_the_parameter(kw, name):
    with pytest.raises(ArgumentError, match=repr(name)) as exc:
        rb.model("harvey-shack", **kw)
    assert exc.value.argument == name
    with pytest.raises(ArgumentError, match=name):
        sl.harvey_shack_tis(0.1, **{"b0": 0.1, "L": 0.01, "S": -1.5, **kw})


def test_plane_forms_refuse_divergent_parameters():
    with pytest.raises(ArgumentError, match="g") as exc:
        sl.abg_tis_plane(1.0, 0.1, 2.0)
    assert exc.value.argument == "g"
    with pytest.raises(ArgumentError, match="S") as exc:
        sl.harvey_shack_tis_plane(1.0, 0.1, -2.0)
    assert exc.value.argument == "S"


# ------------------------------------------------------------------------------------------
# TIS: closed forms
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("A", "B", "g"), [(3e-12, 2e-12, 2.5), (1e-9, 2e-12, 3.0),
                                           (1e-6, 1e-8, 4.0), (0.01, 0.01, 2.5),
                                           (1.0, 1.0, 6.0), (1e-3, 1e-6, 2.01)])
def test_abg_tis_at_normal_incidence_is_the_incomplete_beta_form(A, B, g):
    # 2π G(1) = plane · I_x(2/g, 1 - 2/g), x = (1/B)/(1 + 1/B): u = ρ^g/B, v = u/(1+u)
    exact = sl.abg_tis_plane(A, B, g) * betainc(2 / g, 1 - 2 / g, 1 / (1 + B))
    assert sl.abg_tis(0.0, A, B, g) == pytest.approx(exact, rel=1e-7)


@pytest.mark.parametrize("ti", [0.0, 0.5, 1.2, HALF_PI])
def test_abg_tis_with_g_zero_is_the_disk_area_times_the_constant(ti):
    # constant BSDF over the unit disk (projected solid angle π): π A/(B + 1)
    assert sl.abg_tis(ti, 0.3, 0.5, 0.0) == pytest.approx(math.pi * 0.3 / 1.5, rel=1e-13)
    assert sl.abg_tis(ti, 0.3, 0.0, 0.0) == pytest.approx(math.pi * 0.3, rel=1e-13)


@pytest.mark.parametrize(("b0", "L", "S"), [(0.1, 0.01, -1.5), (1.0, 1e-5, -3.0),
                                            (1.0, 0.3, -2.0), (2.0, 0.05, -0.3)])
def test_harvey_shack_tis_at_normal_incidence_is_closed_form(b0, L, S):
    # R(ψ) = 1: 2π b0 L² ((1 + 1/L²)^((S+2)/2) - 1)/(S + 2)  (log form at S = -2)
    x = 1.0 / L**2
    if S == -2.0:
        exact = math.pi * b0 * L * L * math.log1p(x)
    else:
        exact = 2 * math.pi * b0 * L * L * ((1 + x) ** ((S + 2) / 2) - 1) / (S + 2)
    assert sl.harvey_shack_tis(0.0, b0, L, S) == pytest.approx(exact, rel=1e-12)


def test_harvey_shack_radial_is_continuous_through_s_minus_two():
    g0 = sl.harvey_shack_radial(1.0, 1.0, 0.01, -2.0)
    assert g0 == pytest.approx(0.5 * 1e-4 * math.log1p(1e4), rel=1e-14)
    for eps in (1e-9, -1e-9):
        assert sl.harvey_shack_radial(1.0, 1.0, 0.01, -2.0 + eps) == pytest.approx(g0, rel=1e-7)


@pytest.mark.parametrize(("A", "B", "g"), [(1e-9, 2e-12, 3.0), (1e-6, 1e-8, 4.0),
                                           (3e-12, 2e-12, 2.5)])
def test_sharp_abg_tis_is_bracketed_by_the_plane_form(A, B, g):
    # TIS <= plane; the part of the plane outside the disk lies at |β - β0| >= 1 - s, where
    # F < A ρ^-g, so TIS >= plane - 2π A (1 - s)^(2-g)/(g - 2)
    plane = sl.abg_tis_plane(A, B, g)
    for ti in (0.0, 0.05, 0.2, 0.5):
        s = math.sin(ti)
        tail = 2 * math.pi * A * (1 - s) ** (2 - g) / (g - 2)
        t = sl.abg_tis(ti, A, B, g)
        # the lower bound is tight to O(B) at normal incidence: allow the quadrature's 1e-9
        assert plane - tail <= t * (1 + 1e-9) and t <= plane
        assert t == pytest.approx(plane, rel=1.001 * tail / plane)


@pytest.mark.parametrize(("b0", "L", "S"), [(1e3, 1e-5, -3.0), (10.0, 1e-4, -2.5),
                                            (1e4, 1e-6, -2.2)])
def test_sharp_harvey_shack_tis_is_bracketed_by_the_plane_form(b0, L, S):
    # as for ABg with F <= b0 (ρ/L)^S
    plane = sl.harvey_shack_tis_plane(b0, L, S)
    for ti in (0.0, 0.05, 0.2, 0.5):
        tail = 2 * math.pi * b0 * L ** (-S) * (1 - math.sin(ti)) ** (2 + S) / (-S - 2)
        t = sl.harvey_shack_tis(ti, b0, L, S)
        assert plane - tail <= t * (1 + 1e-9) and t <= plane


def test_grazing_tis_of_a_sharp_lobe_is_half_the_plane():
    # β0 on the rim: the disk cuts a sharp lobe in half (to O(lobe width))
    assert sl.abg_tis(HALF_PI, 1e-9, 2e-12, 3.0) / sl.abg_tis_plane(1e-9, 2e-12, 3.0) \
        == pytest.approx(0.5, abs=2e-3)
    assert sl.harvey_shack_tis(HALF_PI, 1e3, 1e-5, -3.0) \
        / sl.harvey_shack_tis_plane(1e3, 1e-5, -3.0) == pytest.approx(0.5, abs=2e-3)


def _radius(ti: float, psi: float) -> float:
    """Distance from β0 = (sin ti, 0) to the unit circle along ψ (the chord of the disk)."""
    s, c, cp = math.sin(ti), math.cos(ti), math.cos(psi)
    q = math.sqrt(c * c + s * s * cp * cp)
    return c * c / (q + s * cp) if cp > 0 else q - s * cp


def _adaptive_tis(radial, ti: float) -> float:
    # SciPy's adaptive quad on 2 ∫_0^π G(R(ψ)) dψ, breakpoints where R changes fastest
    pts = [math.pi / 2 + x for x in (-1e-2, -1e-4, -1e-6, 0.0, 1e-6, 1e-4, 1e-2)]
    return 2 * quad(lambda p: radial(_radius(ti, p)), 0.0, math.pi, points=pts, limit=2000,
                    epsabs=0.0, epsrel=1e-12)[0]


@pytest.mark.parametrize("deg", [60.0, 89.9, 89.999, 89.9999])
def test_harvey_shack_tis_equals_adaptive_quadrature_near_grazing(deg):
    # independent rule on the same exact reduction; a lobe 1e-5 wide, beta0 1e-8 from the rim
    b0, L, S = 1.0, 1e-5, -3.0
    ti = math.radians(deg)
    exact = _adaptive_tis(lambda r: sl.harvey_shack_radial(r, b0, L, S), ti)
    assert sl.harvey_shack_tis(ti, b0, L, S) == pytest.approx(exact, rel=1e-8)


@pytest.mark.parametrize("deg", [60.0, 89.0])
def test_sharp_abg_tis_equals_adaptive_quadrature_at_oblique_incidence(deg):
    # B = 2e-12: a lobe 1.3e-4 wide in |β - β0|, which rb.albedo's angle grid cannot resolve;
    # G(r) by adaptive quad with breakpoints around the knee B^(1/g)
    A, B, g = 1e-9, 2e-12, 3.0
    w = B ** (1 / g)

    def radial(r: float) -> float:
        pts = [p for p in (0.1 * w, w, 10 * w, 100 * w) if p < r] or None
        return quad(lambda x: A * x / (B + x**g), 0.0, r, points=pts, limit=500,
                    epsabs=0.0, epsrel=1e-12)[0]

    ti = math.radians(deg)
    assert sl.abg_tis(ti, A, B, g) == pytest.approx(_adaptive_tis(radial, ti), rel=1e-9)


# ------------------------------------------------------------------------------------------
# TIS against rb.albedo (independent quadrature in angle space)
# ------------------------------------------------------------------------------------------
#: the incidences of the TIS-against-albedo tests; without the JIT (plain Python: 15 s a case
#: on all seven) normal, 60 deg and the most grazing one
TI_GRID = np.radians([0.0, 20.0, 45.0, 60.0, 75.0, 85.0, 89.0])[[0, 3, 6] if NOJIT else
                                                                  slice(None)]


def _tis_cases(shapes, scales):
    """``pytest.param(shape, scale)`` of every pair (ids ``"shape-scale"``, shape outermost);
    without the JIT one pair a shape, the scales taken in turn (every shape and every scale
    kept: 9 of the 36 ABg cases, 7 of the 28 Harvey-Shack ones)."""
    return [pytest.param(s, x, id=f"{s}-{x}") for i, s in enumerate(shapes)
            for j, x in enumerate(scales) if not NOJIT or j == i % len(scales)]


@pytest.mark.parametrize(("g", "B"), _tis_cases([-1.0, 0.0, 0.5, 1.0, 1.8, 2.0, 2.5, 3.0, 4.0],
                                                [1e-6, 1e-4, 1e-2, 1.0]))
def test_abg_tis_equals_albedo(B, g):
    # range: A = 1e-3, B in [1e-6, 1], g in [-1, 4], theta_i in [0, 89] deg
    m = rb.model("abg", A=1e-3, B=B, g=g)
    np.testing.assert_allclose(m.tis(TI_GRID), rb.albedo(m, TI_GRID), rtol=1e-4)


@pytest.mark.parametrize(("S", "L"), _tis_cases([-0.3, -1.0, -1.5, -2.0, -2.5, -3.0, -4.0],
                                                [1e-3, 1e-2, 0.1, 1.0]))
def test_harvey_shack_tis_equals_albedo(L, S):
    # range: b0 = 1, L in [1e-3, 1], S in [-4, -0.3], theta_i in [0, 89] deg
    m = rb.model("harvey-shack", b0=1.0, L=L, S=S)
    np.testing.assert_allclose(m.tis(TI_GRID), rb.albedo(m, TI_GRID), rtol=1e-4)


@pytest.mark.parametrize("m", [rb.model("abg", A=1e-3, B=1e-6, g=1.8),
                               rb.model("hs", b0=1.0, L=1e-3, S=-4.0),
                               rb.model("hs", b0=1.0, L=0.05, S=-0.5)], ids=repr)
def test_grazing_tis_equals_a_finer_albedo(m):
    # at theta_i = 90 deg a sharp lobe is 1e-3 wide across the plane of incidence: the
    # albedo's azimuthal rule needs 2048 nodes there (its 256 default is off by 2e-3)
    fine = rb.albedo(m, HALF_PI, n_psi=2048, n_panels=48)
    assert m.tis(HALF_PI) == pytest.approx(fine, rel=1e-6)


# ------------------------------------------------------------------------------------------
# Mueller matrix and the pure-Python mode
# ------------------------------------------------------------------------------------------
def test_mueller_is_an_ideal_depolarizer(model):
    ti, tr, ph = np.array([0.1, 0.9]), 0.4, np.array([[0.0], [2.0]])
    M = model.mueller(ti, tr, ph)
    assert M.shape == (2, 2, 4, 4)
    np.testing.assert_array_equal(M[..., 0, 0], model.brdf(ti, tr, ph))
    rest = M.copy()
    rest[..., 0, 0] = 0.0
    assert not rest.any()
    np.testing.assert_array_equal(model.brdf(ti, tr, ph, "s"), model.brdf(ti, tr, ph))


def test_pure_python_mode_agrees():
    code = textwrap.dedent("""
        import json, numpy as np, numba, roughbrdf as rb, roughbrdf.models.straylight
        assert numba.config.DISABLE_JIT
        ti = np.array([0.0, 0.3, 1.2, 1.5707963267948966])
        tr = np.array([0.0, 0.3, 1.2, 1.5707963267948966]); ph = np.array([0.0, 0.0, 3.0, -2.0])
        out = {}
        for name, kw in [("abg", {}), ("abg", {"g": 0.0, "B": 0.0}), ("abg", {"g": -1.0}),
                         ("hs", {})]:
            m = rb.model(name, **kw)
            out[repr(m)] = [m.brdf(ti, tr, ph).tolist(), m.bridf(ti, tr, ph).tolist(),
                            m.tis(ti).tolist()]
        print(json.dumps(out))
    """)
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=300, check=True)
    pure = json.loads(res.stdout.strip().splitlines()[-1])
    ti = np.array([0.0, 0.3, 1.2, HALF_PI])
    ph = np.array([0.0, 0.0, 3.0, -2.0])
    assert len(pure) == 4
    for key, (f, fc, t) in pure.items():
        m = eval(key, {"rb": rb})  # the repr is rb.model(...): rebuild the same model
        np.testing.assert_allclose(f, m.brdf(ti, ti, ph), rtol=1e-13)
        np.testing.assert_allclose(fc, m.bridf(ti, ti, ph), rtol=1e-13)
        np.testing.assert_allclose(t, m.tis(ti), rtol=1e-12)
