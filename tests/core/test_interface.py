"""The one public evaluation interface, the Quantity and Polarization types, the relative
scale, and the one registry behind models, distributions, shadowing and model options."""

from __future__ import annotations

import math

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.models import PreparedGeometry, resolve_names
from roughbrdf.polarization import Polarization
from roughbrdf.quantity import Quantity, relative_scale
from roughbrdf.registry import Registry

TI = np.array([0.1, 0.6, 1.2])
TR = np.array([[0.0], [0.5], [1.4]])
PHI = np.array([0.0, 2.0, math.pi])

MODELS = [rb.model("tr75", e=0.3, n=1.5, k=0.2, rho_L=0.1),
          rb.model("ts67", n=1.5, k=0.0),
          rb.model("microfacet", distribution="beckmann", alpha=0.3, shadowing="smith"),
          rb.model("rb08"),
          rb.model("microfacet+lambertian", alpha=0.2, rho=0.3)]


# -- evaluate: one method, every quantity -------------------------------------------------------
@pytest.mark.parametrize("m", MODELS, ids=lambda m: m.name)
def test_quantities_relate_as_defined(m):
    f = m.evaluate(TI, TR, PHI)
    np.testing.assert_array_equal(f, m.brdf(TI, TR, PHI))
    # brdf_cos and bridf are the same number (docs/models.md §1.2), = f cos(theta_r)
    fc = m.evaluate(TI, TR, PHI, quantity="brdf_cos")
    np.testing.assert_array_equal(fc, m.evaluate(TI, TR, PHI, quantity=Quantity.BRIDF))
    np.testing.assert_allclose(fc, f * np.cos(TR), rtol=1e-12)
    # relative: f over f at the specular direction of the same incidence (TS67 Eq. 23)
    rel = m.evaluate(TI, TR, PHI, quantity="relative")
    spec = m.brdf(TI, TI, 0.0)
    np.testing.assert_allclose(rel, f / spec, rtol=1e-14)
    np.testing.assert_allclose(m.evaluate(TI, TI, 0.0, quantity="relative"), 1.0)


def test_ts67_relative_is_the_relative_quantity():
    ts = rb.model("ts67", g=2 / 3, c=0.05, n=None, k=None)
    a = ts.relative(np.radians(75), np.radians([60, 80, 89]), 0.0)
    b = ts.evaluate(np.radians(75), np.radians([60, 80, 89]), 0.0, quantity="relative")
    np.testing.assert_array_equal(a, b)
    assert round(float(a[1]), 3) == 1.425  # docs/models.md §2.7, TS67 Fig. 8


@pytest.mark.parametrize("m", MODELS, ids=lambda m: m.name)
def test_prepared_equals_direct(m):
    g = m.prepare(TI, TR, PHI, "s")
    assert isinstance(g, PreparedGeometry) and g.shape == (3, 3)
    for q in Quantity:
        np.testing.assert_array_equal(m.evaluate_prepared(g, q),
                                      m.evaluate(TI, TR, PHI, quantity=q, polarization="s"))


def test_polarization_argument_forms_agree():
    m = MODELS[0]
    s = m.brdf(TI, TR, PHI, "s")
    np.testing.assert_array_equal(s, m.evaluate(TI, TR, PHI, polarization=Polarization.parse("s")))
    np.testing.assert_array_equal(s, m.brdf(TI, TR, PHI, math.pi / 2))
    np.testing.assert_array_equal(s, m.brdf(TI, TR, PHI, Polarization.linear(math.pi / 2)))
    per = m.brdf(0.5, 0.4, 0.3, np.array(["s", "p", "unpolarized"]))
    np.testing.assert_array_equal(per, [m.brdf(0.5, 0.4, 0.3, q) for q in ("s", "p", None)])


@pytest.mark.parametrize("bad, match", [("q", "polarization must be"),
                                        (math.inf, "must be finite"),
                                        ([0.1, np.inf], "must be finite")])
def test_bad_polarization_names_the_value(bad, match):
    with pytest.raises(ValueError, match=match):
        MODELS[0].brdf(0.5, 0.5, 0.0, bad)


def test_stokes_and_analyzer_are_used_not_ignored():
    # the Stokes fields are evaluated (tests/core/test_stokes.py); where a path has no
    # Stokes evaluation (prepare: the scalar kernels) they are refused, never dropped
    pol = Polarization(np.asarray(np.nan), stokes=(1.0, 0.0, 0.0, 0.0),
                       analyzer=(0.5, 0.5, 0.0, 0.0))
    assert pol.is_polarimetric
    s_only = MODELS[0].evaluate(0.3, 0.3, 0.0, polarization=pol)
    assert s_only == pytest.approx(0.5 * MODELS[0].evaluate(0.3, 0.3, 0.0, polarization="s"))
    with pytest.raises(ValueError, match="Stokes"):
        MODELS[0].prepare(0.1, 0.2, 0.0, pol)


def test_bad_quantity_names_the_value():
    with pytest.raises(ValueError, match="quantity must be one of.*'radiance'"):
        MODELS[0].evaluate(0.1, 0.2, 0.0, quantity="radiance")
    assert Quantity.parse("BRDF*cos") is Quantity.BRDF_COS
    assert Quantity.BRIDF.cosine_weighted and not Quantity.BRDF.cosine_weighted
    assert not Quantity.RELATIVE.absolute


# -- the one relative scale -------------------------------------------------------------------
def test_relative_scale_recovers_a_known_factor_for_every_loss():
    rng = np.random.default_rng(3)
    model = rng.uniform(0.1, 2.0, 200)
    data = model / 7.5  # K data = model exactly with K = 7.5
    w = rng.uniform(0.5, 2.0, 200)
    for loss in ("relative", "log", "absolute"):
        assert relative_scale(data, model, loss=loss) == pytest.approx(7.5, rel=1e-13)
        assert relative_scale(data, model, weights=w, loss=loss) == pytest.approx(7.5,
                                                                                  rel=1e-13)


def test_relative_scale_weighted_is_the_weighted_least_squares_optimum():
    # sum(w^2 (K q - 1)^2) is minimal at the returned K: compare with a dense scan
    rng = np.random.default_rng(4)
    model = rng.uniform(0.1, 2.0, 50)
    data = model * rng.uniform(0.5, 1.5, 50)
    w = rng.uniform(0.1, 3.0, 50)
    k = relative_scale(data, model, weights=w)
    scan = np.linspace(0.5 * k, 1.5 * k, 20001)
    cost = ((w * (scan[:, None] * data / model - 1.0)) ** 2).sum(axis=1)
    assert abs(scan[np.argmin(cost)] - k) <= (scan[1] - scan[0])


def test_relative_scale_ignores_unusable_pairs_and_falls_back_to_one():
    assert relative_scale([1.0, np.nan, 2.0], [2.0, 1.0, 4.0]) == pytest.approx(2.0)
    assert relative_scale([1.0, 1.0], [0.0, -1.0]) == 1.0
    with pytest.raises(ValueError, match="loss must be one of"):
        relative_scale([1.0], [1.0], loss="l1")


# -- one registry ---------------------------------------------------------------------------------
def test_every_name_kind_resolves_the_same_way():
    assert rb.model("Trowbridge_Reitz_1975").name == "trowbridge-reitz-1975"
    assert rb.distributions.get("GGX").name == "trowbridge-reitz"
    assert rb.shadowing.canonical(rb.shadowing.get("Smith")) == "smith-height-correlated"
    m = rb.model("rb08", surface_weight="Q=1")
    assert m.options["surface_weight"] == "product"
    for call, kind in [(lambda: rb.model("trowbridge-reitz-1957"), "model"),
                       (lambda: rb.distributions.get("beckman"), "distribution"),
                       (lambda: rb.shadowing.get("smit"), "shadowing"),
                       (lambda: rb.model("rb08", zeta="angel"), "option 'zeta'")]:
        with pytest.raises(ValueError, match=f"unknown .*{kind}.*did you mean"):
            call()


def test_registry_refuses_a_taken_alias():
    reg: Registry[int] = Registry("thing")
    reg.add("one", 1, aliases=("uno",))
    with pytest.raises(ValueError, match="already taken"):
        reg.add("two", 2, aliases=("UNO",))
    assert reg.aliases("one") == ["uno"] and "Uno" in reg and len(reg) == 1


# -- sums from a string live with the models ---------------------------------------------
def test_sum_from_string_with_plain_and_prefixed_names():
    s = rb.model("microfacet+lambertian", distribution="beckmann", microfacet_alpha=0.4, rho=0.2)
    assert isinstance(s, rb.SumModel)
    assert s.components[0].options["distribution"] == "beckmann"
    assert s.params["microfacet_alpha"] == 0.4 and s.params["lambertian_rho"] == 0.2
    f = s.brdf(0.3, 0.4, 0.5)
    parts = sum(c.brdf(0.3, 0.4, 0.5) for c in s.components)
    assert f == pytest.approx(parts, rel=1e-15)
    assert s.brdf(0.3, 0.4, 0.5, term="lambertian") == pytest.approx(0.2 / math.pi)
    assert resolve_names(s, ["alpha"]) == ["microfacet_alpha"]
    with pytest.raises(ValueError, match="ambiguous"):
        rb.model("tr75+microfacet", n=1.5)
    with pytest.raises(ValueError, match="bad model"):
        rb.model("tr75+")
    assert rb.model(s.to_dict()).params == s.params
