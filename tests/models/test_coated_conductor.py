"""The metallic-paint model: a rough clear coat over rough metal flakes (docs/models.md §10.5).

Expected numbers and where they come from:

* energy: ``rb.albedo <= 1 + 1e-3`` at the fits' incidences (0, 5, ... 85, 89 deg) for every
  parameter value of the search box (§10.5: the base term's albedo is at most
  ``s (1 - R) <= 1 - E_coat``; 1e-3 is the allowance of the coated model's test, the accuracy of
  ``rb.albedo`` and of the tabulated ``E``);
* identities derived from the formula (§10.5): an index-matched, non-absorbing base
  (``n_m = n``, ``k_m = 0``) reflects nothing, leaving the coated model's lobe (``coated`` with
  ``rho = 0``); an all-pigment base (``d = 1``) is the coated model's substrate (the same
  formula, its series of internal reflections included); a coat of index ~1 is invisible,
  leaving the flakes' ``microfacet`` lobe; no coat (``coat=False``) is the ``microfacet``
  conductor lobe plus Lambertian pigment, ``(1 - d) f_microfacet + d rho/pi``;
* ``flakes="reflectance"``: the index of :func:`roughbrdf.fresnel.index_from_reflectance`
  (Gulbrandsen 2014, Eqs. 2-3), whose normal reflectance is ``r`` by construction;
* a gold-like flake (``0.2 + 3.3i``, Johnson & Christy near 600 nm) under a smooth coat:
  ``0.04 + 0.96 * 0.91 * 0.96 ~ 0.84`` at normal incidence (coat ``R(0)``, ``T(0)``, the flakes'
  ``F(0)`` at the relative index ``(0.2 + 3.3i)/1.5``), so the albedo is > 0.5.
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
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import roughbrdf as rb

HALF_PI = math.pi / 2
INCIDENCES = np.radians([*range(0, 90, 5), 89])
TOL = 1e-3
GOLD = {"n_m": 0.2, "k_m": 3.3}


def _geometries(seed: int = 7, size: int = 200) -> tuple[np.ndarray, ...]:
    rng = np.random.default_rng(seed)
    ti, tr = rng.uniform(0.0, 1.55, (2, size))
    return ti, tr, rng.uniform(-math.pi, math.pi, size)


def _end_or(lo: float, hi: float):
    # the whole interval of the search box, with its ends (the corners) drawn often
    return st.one_of(st.sampled_from([lo, hi]), st.floats(lo, hi))


@st.composite
def metallic_models(draw):
    # every option, every parameter over its whole search box (the fits' domain)
    kw = {"distribution": draw(st.sampled_from(["trowbridge-reitz", "beckmann"])),
          "shadowing": draw(st.sampled_from(["smith-separable", "smith-height-correlated"])),
          "alpha_m": draw(_end_or(0.01, 1.5))}
    if draw(st.booleans()):
        kw.update(n=draw(_end_or(1.3, 1.8)), alpha=draw(_end_or(0.005, 1.5)))
    else:
        kw.update(coat=False)
    if draw(st.booleans()):
        kw.update(n_m=draw(_end_or(0.03, 4.0)), k_m=draw(_end_or(0.0, 8.0)))
    else:
        kw.update(flakes="reflectance", r_m=draw(_end_or(0.0, 1.0)),
                  g_m=draw(_end_or(0.0, 1.0)))
    if draw(st.booleans()):
        kw.update(diffuse=True, d=draw(_end_or(0.0, 1.0)), rho=draw(_end_or(0.0, 1.0)))
    return rb.model("metallic", **kw)


@pytest.mark.jit_heavy(reason="albedos at 19 incidences per example: minutes each in plain Python")
@settings(max_examples=40, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(metallic_models())
def test_hypothesis_albedo_at_most_one(m):
    a = np.asarray(rb.albedo(m, INCIDENCES))
    assert a.max() <= 1.0 + TOL, f"{m!r} reflects {a.max():.5f}"


@pytest.mark.jit_heavy(reason="albedos on the default grid: minutes in plain Python")
def test_white_pigment_corner_conserves_energy():
    # the tightest corner: white pigment (albedo 1 inside), the coat lobe whose facet-averaged
    # F exceeds R(theta) (Beckmann alpha ~ 0.22, the coated model's worst corner), no loss
    # but the critical angle
    for dist in ("trowbridge-reitz", "beckmann"):
        m = rb.model("metallic", distribution=dist, n=1.3, alpha=0.22, diffuse=True, d=1.0,
                     rho=1.0)
        assert float(np.max(rb.albedo(m, INCIDENCES))) <= 1.0 + TOL


def test_gold_like_flakes_reflect_like_a_metal():
    m = rb.model("metallic", n=1.5, alpha=0.05, alpha_m=0.05, **GOLD)
    a0 = float(rb.albedo(m, 0.0))
    assert 0.5 < a0 <= 1.0
    # the estimate of the module notes: R(0) + T(0)^2 F_flake(0), less the flakes' lobe tails
    # beyond the critical angle inside the coat (dropped)
    f0 = rb.fresnel.reflectance(1.0, 0.2 / 1.5, 3.3 / 1.5)
    assert a0 == pytest.approx(0.04 + 0.96 ** 2 * float(f0), abs=0.02)


def test_index_matched_base_leaves_the_coat_lobe():
    # n_m = n, k_m = 0: the relative index is 1, the flakes' F is 0: only the coat's lobe,
    # which is the coated model's lobe (rho = 0), for each distribution and shadowing
    ti, tr, ph = _geometries()
    for dist in ("trowbridge-reitz", "beckmann"):
        for sh in ("smith-separable", "smith-height-correlated"):
            kw = {"distribution": dist, "shadowing": sh, "n": 1.45, "alpha": 0.2}
            m = rb.model("metallic", n_m=1.45, k_m=0.0, alpha_m=0.3, **kw)
            coat = rb.model("coated", rho=0.0, **kw)
            for pol in (None, "s", "p"):
                np.testing.assert_allclose(m.brdf(ti, tr, ph, pol), coat.brdf(ti, tr, ph, pol),
                                           rtol=1e-12, atol=1e-300)


def test_all_pigment_base_is_the_coated_substrate():
    # d = 1: the pigment is the coated model's diffuse substrate, the same formula (same s,
    # T, 1/n^2 and the series of internal reflections 1/(1 - rho F_dr,int), §10.3)
    ti, tr, ph = _geometries(3)
    kw = {"n": 1.5, "alpha": 0.15}
    m = rb.model("metallic", diffuse=True, d=1.0, rho=0.7, **kw)
    c = rb.model("coated", rho=0.7, shadow_diffuse=False, **kw)
    for pol in (None, "s"):
        np.testing.assert_allclose(m.brdf(ti, tr, ph, pol), c.brdf(ti, tr, ph, pol),
                                   rtol=1e-10, atol=1e-15)


def test_no_coat_is_a_rough_conductor_plus_pigment():
    # coat=False: n = 1 (no Fresnel, no refraction, T = 1, s = 1): (1 - d) microfacet + d
    # rho/pi, exactly, at every polarization (the flakes' F is unpolarized)
    ti, tr, ph = _geometries(11)
    for sh in ("smith-separable", "smith-height-correlated"):
        m = rb.model("metallic", coat=False, n_m=0.5, k_m=2.0, alpha_m=0.25, shadowing=sh,
                     diffuse=True, d=0.3, rho=0.8)
        assert m.param_names == ["n_m", "k_m", "alpha_m", "d", "rho"]
        flakes = rb.model("microfacet", n=0.5, k=2.0, alpha=0.25, ks=1.0, shadowing=sh)
        want = 0.7 * flakes.brdf(ti, tr, ph) + 0.3 * 0.8 / math.pi
        for pol in (None, "p"):
            np.testing.assert_allclose(m.brdf(ti, tr, ph, pol), want, rtol=1e-12)


def test_reflectance_form_is_the_index_form():
    # flakes="reflectance": the flakes' index relative to the coat is index_from_reflectance
    # (r_m, g_m); the same model as flakes="index" at n times that index (in air)
    ti, tr, ph = _geometries(13)
    for r, g in ((0.9, 0.3), (0.5, 1.0), (0.04, 0.0), (0.999, 0.7)):
        m = rb.model("metallic", flakes="reflectance", r_m=r, g_m=g, n=1.6, alpha=0.1)
        nm, km = rb.fresnel.index_from_reflectance(r, g)
        assert m.flake_index() == (nm, km)
        same = rb.model("metallic", n_m=1.6 * nm, k_m=1.6 * km, n=1.6, alpha=0.1)
        np.testing.assert_allclose(m.brdf(ti, tr, ph), same.brdf(ti, tr, ph), rtol=1e-12)
    assert rb.model("metallic", flakes="reflectance").param_names == \
        ["n", "alpha", "r_m", "g_m", "alpha_m"]


def test_unset_pigment_albedo_and_edge_tint_are_white_and_metal_like():
    # rho = None: white pigment (1), not fitted; g_m = None: 1 (the smallest index of that
    # reflectance); both the same model as the value given
    ti, tr, ph = _geometries(17)
    m = rb.model("metallic", flakes="reflectance", r_m=0.8, g_m=None, diffuse=True, d=0.3)
    assert m.params["rho"] is None and m.params["g_m"] is None
    same = m.with_params(rho=1.0, g_m=1.0)
    np.testing.assert_allclose(m.brdf(ti, tr, ph), same.brdf(ti, tr, ph), rtol=1e-14)
    assert rb.model("metallic", diffuse=True).params["rho"] is None  # the default


def test_index_from_reflectance_is_gulbrandsens_map():
    # Gulbrandsen 2014, Eqs. 2-3: normal reflectance r exactly (Fresnel at cos = 1, §1.4),
    # n > 0, k >= 0; g = 0 the dielectric k = 0; g = 1 the smallest n, (1 - r)/(1 + r)
    for r in (0.0, 0.04, 0.3, 0.7, 0.95, 0.999):
        for g in (0.0, 0.25, 0.5, 1.0):
            n, k = rb.fresnel.index_from_reflectance(r, g)
            assert n > 0 and k >= 0
            rs, rp = rb.fresnel.fresnel_sp(1.0, n, k)
            assert rs == pytest.approx(r, abs=1e-12) and rp == pytest.approx(r, abs=1e-12)
        assert rb.fresnel.index_from_reflectance(r, 1.0)[0] == pytest.approx((1 - r) / (1 + r))
        assert rb.fresnel.index_from_reflectance(r, 0.0)[1] == pytest.approx(0.0, abs=1e-6)
    n, k = rb.fresnel.index_from_reflectance(1.0, 0.5)  # r = 1: finite, reflectance ~1
    assert math.isfinite(n) and math.isfinite(k)
    assert rb.fresnel.fresnel_sp(1.0, n, k)[0] > 1 - 1e-5
    for bad in ((1.2, 0.5), (0.5, -0.1), (math.nan, 0.5)):
        with pytest.raises(ValueError, match="r and edge tint g"):
            rb.fresnel.index_from_reflectance(*bad)


def test_invisible_coat_leaves_the_flakes():
    # n -> 1: the coat reflects nothing, transmits everything and refracts nothing; what is
    # left is the conductor's microfacet lobe (unpolarized F, ks = 1). n = 1 + 1e-6: the
    # refraction moves the angles by ~1e-6 rad, the coat reflects ~1e-13
    ti, tr, ph = _geometries(5)
    ti, tr = ti * 0.8, tr * 0.8  # below 70 deg, where the angles' shift is small
    m = rb.model("metallic", n=1.0 + 1e-6, alpha=0.3, n_m=0.5, k_m=2.0, alpha_m=0.25,
                 shadowing="smith-height-correlated")
    flakes = rb.model("microfacet", n=0.5, k=2.0, alpha=0.25, ks=1.0,
                      shadowing="smith-height-correlated")
    np.testing.assert_allclose(m.brdf(ti, tr, ph), flakes.brdf(ti, tr, ph), rtol=2e-4)


def test_reciprocity_and_phi_symmetry():
    ti, tr, ph = _geometries(11)
    for kw in ({}, {"distribution": "beckmann", "alpha": 0.4, "alpha_m": 0.05},
               {"diffuse": True, "d": 0.4, "rho": 0.8, "shadowing": "smith-height-correlated"}):
        m = rb.model("metallic", **kw)
        f = m.brdf(ti, tr, ph)
        np.testing.assert_allclose(m.brdf(tr, ti, ph), f, rtol=1e-12)
        np.testing.assert_allclose(m.brdf(ti, tr, -ph), f, rtol=1e-12)


def test_special_geometries_finite_and_non_negative():
    m = rb.model("metallic", alpha=0.005, alpha_m=0.01, **GOLD)
    below = np.nextafter(HALF_PI, 0.0)
    t = np.array([0.0, 0.3, 1.0, 1.5, below])
    for ti, tr, ph in ((0.0, 0.0, 0.0), (t, t, 0.0), (t, HALF_PI, 0.0), (t, HALF_PI, math.pi),
                       (t, 0.0, 0.0), (t, t, math.pi)):
        for q in ("brdf", "bridf"):
            v = np.asarray(m.evaluate(ti, tr, ph, quantity=q))
            assert np.isfinite(v).all() and (v >= 0.0).all(), (ti, tr, ph, q, v)
    # exactly at the specular direction the narrow lobes peak: the largest values
    spec = m.brdf(0.5, 0.5, 0.0)
    assert spec > m.brdf(0.5, 0.6, 0.0) > 0.0
    # at the horizon the flakes' term vanishes with T(theta_r) -> 0: the coat's value is left
    coat = rb.model("coated", rho=0.0, alpha=0.005)
    assert m.brdf(0.4, HALF_PI, 0.0) == pytest.approx(coat.brdf(0.4, HALF_PI, 0.0), abs=1e-12)


def test_n_dimensional_inputs():
    m = rb.model("metallic", diffuse=True)
    ti = np.linspace(0.0, 1.4, 6).reshape(2, 3, 1)
    tr = np.linspace(0.1, 1.5, 4).reshape(1, 1, 4)
    ph = np.linspace(-3.0, 3.0, 12).reshape(2, 3, 2)[..., :1]
    got = m.brdf(ti, tr, ph)
    assert got.shape == (2, 3, 4)
    one = [m.brdf(float(a), float(b), float(c))
           for a, b, c in zip(*(x.ravel() for x in np.broadcast_arrays(ti, tr, ph)), strict=True)]
    np.testing.assert_allclose(got.ravel(), one, rtol=1e-14)


def test_invalid_inputs_raise_naming_them():
    m = rb.model("metallic")
    for bad in (-0.1, HALF_PI + 0.01, math.nan, math.inf):
        with pytest.raises(ValueError, match=r"theta_r.*" + repr(bad).replace("+", r"\+")):
            m.brdf(0.3, np.array([0.1, bad]), 0.0)
    with pytest.raises(ValueError, match="theta_i"):
        m.brdf(HALF_PI, 0.3, 0.0)  # grazing incidence: the coat lobe divides by cos theta_i
    with pytest.raises(ValueError, match="phi"):
        m.brdf(0.3, 0.4, math.nan)
    for name, bad in (("n", 1.0), ("n_m", 0.0), ("k_m", -0.1), ("alpha_m", 0.0),
                      ("n", math.nan)):
        with pytest.raises(ValueError, match=repr(name)):
            m.with_params(**{name: bad})
    pigment = m.with_params(diffuse=True)
    for name in ("d", "rho"):  # reflectance-like: [0, 1], as in every model
        assert next(p for p in pigment.parameters if p.name == name).kind == "reflectance"
        for bad in (1.0 + 1e-12, -1e-12, math.nan):
            with pytest.raises(ValueError, match=repr(name)):
                pigment.with_params(**{name: bad})
    with pytest.raises(ValueError, match="diffuse"):
        rb.model("metallic", diffuse="maybe")
    with pytest.raises(ValueError, match="distribution"):
        rb.model("metallic", distribution="berry")
    with pytest.raises(ValueError, match="flakes"):
        rb.model("metallic", flakes="sparkly")
    with pytest.raises(ValueError, match="coat"):
        rb.model("metallic", coat="perhaps")
    tinted = rb.model("metallic", flakes="reflectance")
    for name, bad in (("r_m", 1.0 + 1e-9), ("g_m", -1e-9)):  # reflectance-like: [0, 1]
        with pytest.raises(ValueError, match=repr(name)):
            tinted.with_params(**{name: bad})


def test_registration_parameters_and_options():
    m = rb.model("metallic-paint")
    assert m.name == "coated-conductor" and rb.model("metallic").name == m.name
    assert m.conserves_energy and m.reciprocal and not m.grazing_incidence
    assert m.param_names == ["n", "alpha", "n_m", "k_m", "alpha_m"]
    bounds = {p.name: p.bounds for p in m.parameters}
    # docs/fitting.md, "Bounds": clear coats 1.4-1.7; metals' n from silver's 0.03 to
    # tungsten's ~4, k up to aluminium's ~8 in the visible
    assert bounds["n"] == (1.3, 1.8) and bounds["n_m"] == (0.03, 4.0)
    assert bounds["k_m"] == (0.0, 8.0)
    d = m.with_params(diffuse=True)
    assert d.param_names[-2:] == ["d", "rho"] and d.options["diffuse"] is True
    assert rb.model("metallic", diffuse="true").options["diffuse"] is True
    again = rb.model(d.to_dict())
    assert again.params == d.params and again.options == d.options


def test_pure_python_mode_agrees():
    code = textwrap.dedent("""
        import json, numpy as np, roughbrdf as rb
        import numba
        assert numba.config.DISABLE_JIT
        m = rb.model("metallic", alpha=0.1, alpha_m=0.3, diffuse=True, d=0.3, rho=0.6)
        ti = np.array([0.0, 0.3, 1.2, 1.5]); tr = np.array([0.0, 0.4, 1.2, 1.5707963267948966])
        ph = np.array([0.0, 1.0, 3.141592653589793, -2.0])
        print(json.dumps([m.bridf(ti, tr, ph).tolist(), m.brdf(ti, tr, ph, "s").tolist()]))
    """)
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=300, check=True)
    pure = json.loads(res.stdout.strip().splitlines()[-1])
    m = rb.model("metallic", alpha=0.1, alpha_m=0.3, diffuse=True, d=0.3, rho=0.6)
    ti = np.array([0.0, 0.3, 1.2, 1.5])
    tr = np.array([0.0, 0.4, 1.2, HALF_PI])
    ph = np.array([0.0, 1.0, math.pi, -2.0])
    np.testing.assert_allclose(pure[0], m.bridf(ti, tr, ph), rtol=1e-13)
    np.testing.assert_allclose(pure[1], m.brdf(ti, tr, ph, "s"), rtol=1e-13)


@pytest.mark.parametrize("distribution", ["trowbridge-reitz", "beckmann"])
@pytest.mark.parametrize("shadowing", ["smith-separable", "smith-height-correlated"])
def test_without_a_coat_the_interface_table_is_ones(distribution, shadowing):
    # coat=False packs a constant table of ones (models/coated_conductor.py, _pack): at n = 1
    # the coat's Fresnel factor is exactly 0, so its lobe's albedo E is 0, R is 0 and the
    # smooth-interface factor min(1, (1 - E)/(1 - R)) is 1 at every node, for any width
    from roughbrdf.models.coated import smooth_interface_factors

    for alpha in (0.006, 0.05, 0.3, 1.4):
        table = smooth_interface_factors(((1.0, alpha),), 1.0, distribution, shadowing)
        assert set(table) == {1.0}, (alpha, min(table), max(table))
