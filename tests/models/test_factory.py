"""Building models by name (:mod:`roughbrdf.models.factory`): ``rb.model`` by canonical name,
alias or any case, spec strings with settings (``"coated(lobes=2)"``), sums (``"a+b"``), the
dicts of :meth:`Model.to_dict`, and errors that name the bad name and suggest a close one.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.models import available, from_spec, spec_text

deg = np.radians


# ------------------------------------------------------------------------------------------
# names: canonical, aliases, case
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name, canonical", [
    ("trowbridge-reitz-1975", "trowbridge-reitz-1975"), ("TR75", "trowbridge-reitz-1975"),
    ("Trowbridge_Reitz", "trowbridge-reitz-1975"), ("  ts67 ", "torrance-sparrow-1967"),
    ("Torrance Sparrow", "torrance-sparrow-1967"), ("LAMBERT", "lambertian"),
    ("diffuse", "lambertian"), ("cook-torrance", "microfacet"), ("rb08", "renhorn-boreman-2008"),
    ("Paint", "coated"), ("rough_diffuse", "oren-nayar"),
])
def test_model_by_name_alias_or_case(name, canonical):
    m = rb.model(name)
    assert m.name == canonical
    assert type(m) is type(rb.model(canonical))
    assert m.params == rb.model(canonical).params


def test_available_lists_the_canonical_names():
    assert {"coated", "lambertian", "microfacet", "oren-nayar", "renhorn-boreman-2008",
            "torrance-sparrow-1967", "trowbridge-reitz-1975"} <= set(available())
    for name in available():
        assert rb.model(name).name == name


def test_parameters_given_by_keyword_are_set():
    m = rb.model("tr75", e=0.3, rho_L=0.1)
    assert m.params["e"] == 0.3 and m.params["rho_L"] == 0.1
    assert m.params["n"] == rb.model("tr75").params["n"]        # the others keep their defaults


# ------------------------------------------------------------------------------------------
# spec strings: NAME(key=value, ...)
# ------------------------------------------------------------------------------------------
def test_spec_string_with_settings():
    m = rb.model("coated(lobes=2)")
    assert m.name == "coated" and m.options["lobes"] == 2
    assert {"alpha2", "w2"} <= set(m.params)
    both = rb.model("coated(lobes=2, distribution=beckmann)", alpha=0.2)
    assert both.options["distribution"] == "beckmann" and both.params["alpha"] == 0.2
    assert rb.model("Coated( lobes = 2 )").options == m.options


def test_spec_text_round_trips():
    for m in (rb.model("coated", lobes=2, distribution="beckmann"), rb.model("tr75"),
              rb.model("tr75") + rb.model("lambertian")):
        text = spec_text(m)
        again = from_spec(text)
        assert spec_text(again) == text and again.options == m.options
    assert spec_text(rb.model("coated", lobes=2)) == "coated(lobes=2)"


def test_spec_values_are_typed():
    m = from_spec("coated(lobes=2, shadow_diffuse=false)")
    assert m.options["lobes"] == 2 and m.options["shadow_diffuse"] is False


# ------------------------------------------------------------------------------------------
# sums: "a+b"
# ------------------------------------------------------------------------------------------
def test_sum_from_a_string_equals_the_sum_of_models():
    ti, tr, ph = deg([10.0, 40.0]), deg([30.0, 70.0]), deg([0.0, 120.0])
    s = rb.model("tr75+lambertian", e=0.3, rho=0.1)
    by_hand = rb.model("tr75", e=0.3) + rb.model("lambertian", rho=0.1)
    assert s.params == by_hand.params
    assert s.params["tr75_e"] == 0.3 and s.params["lambertian_rho"] == 0.1
    np.testing.assert_array_equal(s.brdf(ti, tr, ph), by_hand.brdf(ti, tr, ph))
    assert rb.model("tr75 + lambertian", tr75_e=0.3, lambertian_rho=0.1).params == s.params


def test_sum_of_a_model_with_itself_numbers_the_prefixes():
    s = rb.model("tr75+TR75", tr751_e=0.2)
    assert s.params["tr751_e"] == 0.2 and s.params["tr752_e"] == rb.model("tr75").params["e"]


def test_sum_with_a_spec_component():
    s = rb.model("tr75+coated(lobes=2)")
    assert [c.name for c in s.components] == ["trowbridge-reitz-1975", "coated"]
    assert s.components[1].options["lobes"] == 2


def test_ambiguous_plain_name_in_a_sum_names_the_prefixed_ones():
    with pytest.raises(ValueError, match=r"'n' is ambiguous .*tr75_n, microfacet_n"):
        rb.model("tr75+microfacet", n=1.2)


@pytest.mark.parametrize("spec", ["tr75+", "+lambertian", "tr75++lambertian"])
def test_empty_component_in_a_sum_is_refused(spec):
    with pytest.raises(ValueError, match=re.escape(f"bad model {spec!r}: expected NAME")):
        rb.model(spec)


# ------------------------------------------------------------------------------------------
# dicts (Model.to_dict)
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("m", [
    rb.model("coated", lobes=2, distribution="beckmann", alpha=0.2),
    rb.model("tr75", e=0.3) + rb.model("lambertian", rho=0.1),
    rb.model("microfacet", distribution="ggx", shadowing="smith", alpha=0.4),
], ids=["coated", "sum", "microfacet"])
def test_dict_spec_rebuilds_the_model(m):
    again = rb.model(m.to_dict())
    assert type(again) is type(m) and again.params == m.params and again.options == m.options
    assert again.brdf(0.3, 0.5, 1.0) == m.brdf(0.3, 0.5, 1.0)


def test_dict_spec_with_an_unknown_model_names_it():
    with pytest.raises(ValueError, match=r"unknown model 'tr76'; did you mean 'tr75'"):
        rb.model({"model": "tr76", "params": {}})


# ------------------------------------------------------------------------------------------
# errors name the bad name and suggest a close one
# ------------------------------------------------------------------------------------------
def test_unknown_component_of_a_sum_is_named_with_a_suggestion():
    with pytest.raises(ValueError, match=r"unknown model 'lambertain'; did you mean "
                                         r"'lambertian'"):
        rb.model("tr75+lambertain")


def test_unknown_alias_like_name_suggests_the_alias_and_its_model():
    with pytest.raises(ValueError, match=r"did you mean 'ts67' \(torrance-sparrow-1967\)"):
        rb.model("ts68")


def test_unknown_parameter_of_a_sum_lists_the_known_ones():
    with pytest.raises(ValueError, match=r"unknown parameter 'rhoo' \(known: tr75_e, .*"
                                         r"lambertian_rho\)"):
        rb.model("tr75+lambertian", rhoo=1.2)


@pytest.mark.parametrize("spec, needle", [
    ("coated(lobes=2", "bad model spec 'coated(lobes=2'"),
    ("coated(lobes)", "bad setting 'lobes' in model spec 'coated(lobes)': expected key=value"),
    ("(lobes=2)", "bad model spec '(lobes=2)'"),
])
def test_bad_spec_strings_are_named(spec, needle):
    with pytest.raises(ValueError) as exc:
        rb.model(spec)
    assert needle in str(exc.value)


def test_unknown_setting_in_a_spec_is_named():
    with pytest.raises(ValueError, match="lobs"):
        rb.model("coated(lobs=2)")
# ------------------------------------------------------------------------------------------
# the public names of DESIGN.md ("Public interface") and their behaviour; errors naming them
# ------------------------------------------------------------------------------------------
def test_design_public_interface():
    m = rb.model("trowbridge-reitz-1975", e=0.68, n=1.0, k=0.9, rho_L=0.33)
    assert rb.model("Trowbridge-Reitz-1975", e=0.68).params == rb.model("TR75", e=0.68).params
    assert m.params == {"e": 0.68, "n": 1.0, "k": 0.9, "rho_L": 0.33}
    p = {q.name: q for q in m.parameters}
    assert set(p) == {"e", "n", "k", "rho_L"}
    assert all(hasattr(q, a) for q in p.values()
               for a in ("name", "value", "bounds", "unit", "description"))
    ti, tr, ph = np.radians([30.0, 50.0]), np.radians([20.0, 60.0]), np.radians([10.0, 170.0])
    f = m.brdf(ti, tr, ph)
    np.testing.assert_allclose(m.bridf(ti, tr, ph), f * np.cos(tr), rtol=1e-13)
    assert np.all(m.brdf(ti, tr, ph, polarization=0.0) > 0)
    assert np.all(m.brdf(ti, tr, ph, polarization="s") > 0)
    ts = rb.model("torrance-sparrow-1967", g=2 / 3, c=0.05, n=None, k=None, rho_d=0.3)
    assert ts.relative(deg(75), deg(75), 0.0) == pytest.approx(1.0)
    assert isinstance(rb.model("lambertian", rho=0.5), rb.Model)
    mf = rb.model("microfacet", distribution="trowbridge-reitz", alpha=0.3, shadowing="smith",
                  n=1.5, k=3.0)
    assert mf.options == {"distribution": "trowbridge-reitz",
                          "shadowing": "smith-height-correlated"}
    total = m + rb.model("lambertian", rho=0.1)
    assert set(total.params) == {"tr75_e", "tr75_n", "tr75_k", "tr75_rho_L", "lambertian_rho"}
    np.testing.assert_allclose(total.brdf(ti, tr, ph), f + 0.1 / np.pi, rtol=1e-13)
    assert set((m + m).params) == {"tr751_e", "tr751_n", "tr751_k", "tr751_rho_L", "tr752_e",
                                   "tr752_n", "tr752_k", "tr752_rho_L"}
    assert total.with_params(lambertian_rho=0.2).params["lambertian_rho"] == 0.2
    assert rb.fresnel.reflectance(1.0, 1.5, k=0.0, polarization="unpolarized") == \
        pytest.approx(0.04)
    assert rb.distributions.trowbridge_reitz(1.0, 0.5) == pytest.approx(1 / (np.pi * 0.25))
    assert rb.distributions.beckmann(1.0, 0.5) == pytest.approx(1 / (np.pi * 0.25))
    assert rb.distributions.gaussian_angle(0.0, 0.05) == pytest.approx(2.8316, abs=5e-5)
    assert rb.shadowing.v_groove(deg(30), deg(30), 0.0) == 1.0
    assert rb.albedo(rb.model("lambertian", rho=0.5), 0.3) == pytest.approx(0.5)


@pytest.mark.parametrize("typo, suggestion", [
    ("trowbridge-reits-1975", "trowbridge-reitz-1975"),
    ("torrance-sparow-1967", "torrance-sparrow-1967"),
    ("lambertain", "lambertian"),
    ("microfacit", "microfacet"),
])
def test_unknown_model_suggests_close_match(typo, suggestion):
    with pytest.raises(ValueError, match=rf"unknown model '{typo}'.*did you mean '{suggestion}'"):
        rb.model(typo)


@pytest.mark.parametrize("name, kw, param", [
    ("tr75", {"e": 0.0}, "e"), ("tr75", {"e": -0.3}, "e"), ("tr75", {"k": -0.1}, "k"),
    ("ts67", {"c": 0.0}, "c"), ("ts67", {"c": -0.05}, "c"), ("ts67", {"n": 1.5, "k": -1.0}, "k"),
    ("microfacet", {"alpha": 0.0}, "alpha"), ("microfacet", {"k": -2.0}, "k"),
    ("tr75", {"e": math.nan}, "e"), ("tr75", {"rho_L": 1.5}, "rho_L"),
])
def test_invalid_parameters_raise_naming_them(name, kw, param):
    with pytest.raises(ValueError) as exc:
        rb.model(name, **kw)
    assert repr(param) in str(exc.value) and repr(kw[param]) in str(exc.value)


def test_unknown_parameter_names_raise():
    with pytest.raises(ValueError, match=r"unknown parameter .*'ee'.*did you mean 'e'"):
        rb.model("tr75", ee=0.5)
    with pytest.raises(ValueError, match="unknown parameter"):
        rb.model("tr75").with_values(["rho_l"], [0.2])
    with pytest.raises(ValueError, match="unknown parameter"):
        (rb.model("tr75") + rb.model("lambertian")).with_params(tr75_x=1.0)
