"""Mitsuba 3 export (``roughbrdf.export.mitsuba``), checked with Mitsuba 3 itself.

Every exact mapping is loaded with ``mi.load_dict`` (the dict) and ``mi.load_string`` (the XML)
in Mitsuba's ``scalar_rgb`` variant and evaluated with ``bsdf.eval(ctx, si, wo)`` at 1000
random geometries with ``theta_i, theta_r <= 80 deg``; ``value / cos(theta_o)`` must equal
roughbrdf's ``brdf`` to :data:`RTOL` = 1e-4 relative. The angles are drawn in float32; Mitsuba
gets directions built from them in float32 arithmetic, roughbrdf the same float32 angles
(exactly, as float64). What limits the agreement is float32: Mitsuba computes in single
precision (a few 1e-6 relative; 3e-5 next to the critical angle of a dielectric with
``n < 1``, where its Fresnel takes the square root of a small difference), and the directions
carry float32 rounding. Values below :data:`roughbrdf.export.mitsuba.FLOOR` (1e-12 sr^-1) are
compared absolutely against it: Mitsuba sets a microfacet ``D`` to 0 where
``D cos(theta_h) <= 1e-20`` (the far tail of a narrow Beckmann lobe).

Approximate and fitted exports report their deviation from the model on the export's grid;
the tests evaluate Mitsuba on that grid and check the reported numbers against Mitsuba's.
The tests skip only where the ``mitsuba`` package cannot be imported (it is in the ``test``
extra that ``make test`` installs).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.export.mitsuba import (
    EXACT,
    FLOOR,
    Deviation,
    deviation_grid,
    export_mitsuba,
    mitsuba_values,
    to_mitsuba,
    to_mitsuba_xml,
)

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="each export checks the albedo at 19 incidences: ~1 min in plain Python")

# ImportError too: an installed package whose native library cannot load on this platform
mi = pytest.importorskip("mitsuba", reason="the mitsuba package (test extra) is not installed "
                         "or cannot be imported on this platform", exc_type=ImportError)
mi.set_variant("scalar_rgb")

RTOL = 1e-4
N = 1000
SEP = {"shadowing": "smith-separable"}


# ------------------------------------------------------------------------------------------
# Mitsuba evaluation
# ------------------------------------------------------------------------------------------
def geometry(seed: int, n: int = N):
    """Float32 angles (theta <= 80 deg) as float64 for roughbrdf, float32 directions for Mitsuba
    (the library's frame: source on -x, phi = 0 forward)."""
    rng = np.random.default_rng(seed)
    top = np.float32(math.radians(80.0))
    ti = rng.uniform(0.0, top, n).astype(np.float32)
    tr = rng.uniform(0.0, top, n).astype(np.float32)
    ph = rng.uniform(-math.pi, math.pi, n).astype(np.float32)
    wi = np.stack([-np.sin(ti), np.zeros_like(ti), np.cos(ti)], 1)
    wo = np.stack([np.sin(tr) * np.cos(ph), np.sin(tr) * np.sin(ph), np.cos(tr)], 1)
    assert wi.dtype == wo.dtype == np.float32
    return (ti.astype(float), tr.astype(float), ph.astype(float)), wi, wo


def mitsuba_eval(bsdf, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """``bsdf.eval(ctx, si, wo) / cos(theta_o)``, shape (N, 3)."""
    ctx = mi.BSDFContext()
    si = mi.SurfaceInteraction3f()
    out = np.empty((len(wi), 3))
    for j in range(len(wi)):
        si.wi = mi.Vector3f(*(float(x) for x in wi[j]))
        v = bsdf.eval(ctx, si, mi.Vector3f(*(float(x) for x in wo[j])))
        out[j] = (v[0], v[1], v[2])
    return out / wo[:, 2:3].astype(float)


def grid_directions(grid):
    ti, tr, ph = grid
    wi = np.stack([-np.sin(ti), np.zeros_like(ti), np.cos(ti)], 1).astype(np.float32)
    wo = np.stack([np.sin(tr) * np.cos(ph), np.sin(tr) * np.sin(ph), np.cos(tr)],
                  1).astype(np.float32)
    return wi, wo


def rel_error(value, reference) -> np.ndarray:
    return np.abs(value - reference) / np.maximum(np.abs(reference), FLOOR)


def loaded(e):
    """The export loaded from the dict and from the XML."""
    return mi.load_dict(e.bsdf), mi.load_string(e.xml(version="3.0.0"))


def check_exact(model, seed: int, reference=None, rtol: float = RTOL, status: str = "exact"):
    """Mitsuba (dict and XML) against ``reference`` (default: the model) at N geometries."""
    e = export_mitsuba(model, allow_energy_gain=True)  # the mapping is tested, not the albedo
    assert e.status == status, e.summary()
    angles, wi, wo = geometry(seed)
    ref = (reference or model).brdf(*angles)
    assert np.all(np.isfinite(ref))
    for bsdf in loaded(e):
        got = mitsuba_eval(bsdf, wi, wo)
        for c in range(3):
            err = rel_error(got[:, c], ref)
            assert err.max() <= rtol, f"{model!r}: max rel. error {err.max():.2e}"
    return e


# ------------------------------------------------------------------------------------------
# exact mappings
# ------------------------------------------------------------------------------------------
def test_lambertian_is_diffuse():
    e = check_exact(rb.model("lambertian", rho=0.37), 1)
    assert e.bsdf == {"type": "diffuse", "reflectance": 0.37}


@pytest.mark.parametrize("alpha", [0.01, 0.2, 1.0])
def test_ggx_conductor(alpha):
    m = rb.model("microfacet", distribution="ggx", alpha=alpha, n=0.2, k=3.0, ks=0.8, **SEP)
    e = check_exact(m, 2)
    assert e.bsdf == {"type": "roughconductor", "distribution": "ggx", "alpha": alpha,
                      "eta": 0.2, "k": 3.0, "specular_reflectance": 0.8}


@pytest.mark.parametrize("n, k", [(None, None), (1.5, 0.0), (0.7, 0.0)])
def test_ggx_unit_fresnel_dielectric_and_total_internal_reflection(n, k):
    # n=None (F = 1) is Mitsuba's material "none" (eta = 0, k = 1); n = 0.7 reflects totally
    # beyond 44.4 deg: float32 near the critical angle gives up to ~3e-5 there
    m = rb.model("microfacet", distribution="ggx", alpha=0.3, n=n, k=k, **SEP)
    e = check_exact(m, 3)
    if n is None:
        assert (e.bsdf["eta"], e.bsdf["k"]) == (0.0, 1.0)


def test_beckmann_conductor_where_mitsubas_g1_agrees():
    # Mitsuba's rational G1 for Beckmann equals Smith's to < 5e-5 for alpha up to ~0.07
    # (theta <= 80 deg): the mapping is exact there
    m = rb.model("microfacet", distribution="beckmann", alpha=0.05, n=1.1, k=2.0, ks=1.2, **SEP)
    e = check_exact(m, 4)
    assert e.bsdf["distribution"] == "beckmann" and e.deviation[""].max <= EXACT


def test_sum_is_a_blend_of_scaled_parts():
    m = (rb.model("microfacet", distribution="ggx", alpha=0.1, n=1.5, k=0.5, **SEP)
         + rb.model("lambertian", rho=0.7))
    e = check_exact(m, 5)
    assert e.bsdf["type"] == "blendbsdf" and e.bsdf["weight"] == 0.5
    assert e.bsdf["bsdf_0"]["specular_reflectance"] == 2.0
    assert e.bsdf["bsdf_1"]["reflectance"] == 1.4  # 2 rho, above 1: Mitsuba does not clamp


def test_three_term_sum_nests_blends():
    m = (rb.model("microfacet", distribution="ggx", alpha=0.25, n=0.3, k=2.5, ks=0.5, **SEP)
         + rb.model("microfacet", distribution="beckmann", alpha=0.04, n=1.5, k=0.0, **SEP)
         + rb.model("lambertian", rho=0.4))
    e = check_exact(m, 6)
    assert e.bsdf["weight"] == pytest.approx(2 / 3)
    assert e.bsdf["bsdf_1"]["weight"] == 0.5
    assert [t.term for t in e.terms[""]] == ["microfacet1", "microfacet2", "lambertian"]
    assert e.bsdf["bsdf_1"]["bsdf_1"]["reflectance"] == pytest.approx(1.2)


@pytest.mark.parametrize("dist_, alpha, rho", [("ggx", 0.1, 0.5), ("ggx", 0.5, 1.0),
                                              ("ggx", 1.2, 0.8), ("beckmann", 0.05, 0.9)])
def test_coated_rough_interface_is_roughplastic(dist_, alpha, rho):
    # one lobe has weight 1: specular_reflectance 1; weights="free" maps its free scale ks
    m = rb.model("coated", distribution=dist_, alpha=alpha, n=1.5, rho=rho,
                 shadow_diffuse=False, interface="rough")
    e = check_exact(m, 7)
    b = e.bsdf
    assert (b["type"], b["int_ior"], b["ext_ior"], b["nonlinear"]) == (
        "roughplastic", 1.5, 1.0, True)
    assert (b["diffuse_reflectance"], b["specular_reflectance"]) == (rho, 1.0)
    free = rb.model("coated", distribution=dist_, alpha=alpha, n=1.5, rho=rho, ks=0.9,
                    shadow_diffuse=False, interface="rough", weights="free")
    b = check_exact(free, 7).bsdf
    assert (b["diffuse_reflectance"], b["specular_reflectance"]) == (rho, 0.9)


def test_coated_lobes_in_a_sum():
    # weights="free": lobes 2 and 3 are roughconductor lobes of the coating's index (the
    # substrate sees lobe 1's interface); in a blend the substrate term is scaled through
    # roughplastic's nonlinear diffuse reflectance
    m = rb.model("coated", alpha=0.08, n=1.45, rho=0.85, ks=0.7, lobes=3, alpha2=0.3, ks2=0.2,
                 alpha3=0.9, ks3=0.1, shadow_diffuse=False, interface="rough",
                 weights="free") + rb.model("lambertian", rho=0.1)
    e = check_exact(m, 8)
    assert e.terms[""][0].plugins == ("roughplastic", "roughconductor", "roughconductor")


def test_coated_lobe_weights_are_blended_roughplastics():
    # lobe weights that sum to 1: one roughplastic per lobe, each scaled by its weight (the
    # model's substrate sees the lobes' mixed interface: approximate, a small deviation);
    # with one width for both lobes the mixture is the one lobe, and the export exact
    m = rb.model("coated", alpha=0.08, n=1.45, rho=0.85, lobes=2, alpha2=0.3, w2=0.3,
                 shadow_diffuse=False, interface="rough")
    e = export_mitsuba(m)
    assert e.terms[""][0].plugins == ("roughplastic", "roughplastic")
    assert e.status == "approximate" and e.deviation[""].max < 0.05
    assert "mixed rough interface" in e.terms[""][0].note
    reported_matches_mitsuba(e, m)
    same = m.with_params(alpha2=0.08)
    assert export_mitsuba(same).status == "exact"


def test_oren_nayar_with_sigma_zero_is_diffuse():
    e = check_exact(rb.model("oren-nayar", rho=0.6, sigma=0.0), 9)
    assert e.bsdf == {"type": "diffuse", "reflectance": 0.6}


def test_xml_in_a_scene_file():
    # the <bsdf> element used by id in a scene: the shape's BSDF is the export
    m = rb.model("microfacet", distribution="ggx", alpha=0.2, n=1.5, k=0.0, **SEP) + rb.model(
        "lambertian", rho=0.3)
    text = to_mitsuba_xml(m, id="paint")
    scene = mi.load_string(f'<scene version="3.0.0">{text}<shape type="rectangle">'
                           f'<ref id="paint"/></shape></scene>')
    angles, wi, wo = geometry(10, 200)
    got = mitsuba_eval(scene.shapes()[0].bsdf(), wi, wo)[:, 0]
    assert rel_error(got, m.brdf(*angles)).max() <= RTOL


def test_xml_escapes_text():
    text = to_mitsuba_xml(rb.model("lambertian"), id='a"<b>&c')
    assert ET.fromstring(text).get("id") == 'a"<b>&c'


# ------------------------------------------------------------------------------------------
# approximate mappings: parameters one to one, Mitsuba's formula differs; deviation reported
# ------------------------------------------------------------------------------------------
def reported_matches_mitsuba(e, model, channel: str = ""):
    """The reported deviation equals Mitsuba's own on the export's grid."""
    wi, wo = grid_directions(e.grid)
    got = mitsuba_eval(mi.load_dict(e.bsdf if e.rule != "per-channel" else e.bsdf[channel]),
                       wi, wo)[:, 0]
    actual = Deviation.of(got, np.asarray(model.brdf(*e.grid)))
    rep = e.deviation[channel]
    assert rep.max == pytest.approx(actual.max, rel=1e-3, abs=2e-5)
    assert rep.rms == pytest.approx(actual.rms, rel=1e-3, abs=2e-5)
    return actual


def test_tr75_maps_its_distribution_and_adds_smiths_shadowing():
    # TR75 = R D/(4 cos cos) + rho_L/pi with D GGX (alpha = e) and no shadowing;
    # roughconductor always multiplies by Smith's separable G: exactly the microfacet model
    m = rb.model("tr75", e=0.3, n=1.2, k=1.5, rho_L=0.2)
    same = rb.model("microfacet", distribution="ggx", alpha=0.3, n=1.2, k=1.5, **SEP) + rb.model(
        "lambertian", rho=0.2)
    e = check_exact(m, 11, reference=same, status="approximate")
    assert "shadowing" in e.terms[""][0].note
    actual = reported_matches_mitsuba(e, m)
    assert 0.2 < actual.max < 1.0  # G at theta = 80 deg


def test_beckmann_beyond_the_g1_approximation_is_approximate():
    m = rb.model("microfacet", distribution="beckmann", alpha=0.4, n=1.5, k=0.0, **SEP)
    e = export_mitsuba(m)
    assert e.status == "approximate" and "rational" in e.terms[""][0].note
    actual = reported_matches_mitsuba(e, m)
    assert 1e-3 < actual.max < 1e-2  # Mitsuba's G1 is within 0.35 % per direction
    # mitsuba_values (the transcription behind the reports) is Mitsuba's to float32
    angles, wi, wo = geometry(12)
    got = mitsuba_eval(mi.load_dict(e.bsdf), wi, wo)[:, 0]
    assert rel_error(got, mitsuba_values(e.bsdf, *angles)).max() <= RTOL


def test_coated_beckmann_rough_interface_beyond_the_g1_approximation():
    m = rb.model("coated", distribution="beckmann", alpha=0.3, n=1.5, rho=0.8,
                 shadow_diffuse=False, interface="rough")
    e = export_mitsuba(m)
    assert e.status == "approximate"
    reported_matches_mitsuba(e, m)


# ------------------------------------------------------------------------------------------
# what does not map: refused with a reason, or fitted with the deviation reported
# ------------------------------------------------------------------------------------------
REFUSED = [
    (rb.model("torrance-sparrow-1967"), "V-groove"),
    (rb.model("renhorn-boreman-2008"), "RB08"),
    (rb.model("microfacet", shadowing="smith-height-correlated"), "smith-height-correlated"),
    (rb.model("microfacet", distribution="gaussian-angle", alpha=0.05, shadowing="v-groove"),
     "gaussian-angle"),
    (rb.model("microfacet", shadowing="none"), "shadowing 'none'"),
    (rb.model("oren-nayar", sigma=0.3), "Oren-Nayar"),
    (rb.model("coated"), "interface='smooth'"),
    (rb.model("coated", interface="rough"), "shadow_diffuse=True"),
    (rb.model("coated", interface="rough", shadow_diffuse=False, diffuse="oren-nayar"),
     "oren-nayar"),
    (rb.model("lambertian") + rb.model("coated", interface="rough", shadow_diffuse=False,
                                       shadowing="smith-height-correlated"), "term 'coat'"),
]


@pytest.mark.parametrize("model, reason", REFUSED, ids=[r for _, r in REFUSED])
def test_refused_with_a_reason(model, reason):
    with pytest.raises(ValueError, match="no Mitsuba 3 counterpart") as info:
        to_mitsuba(model)
    assert reason in str(info.value) and "fit=True" in str(info.value)


def test_roughness_below_mitsubas_minimum_is_refused():
    m = rb.model("microfacet", distribution="ggx", alpha=5e-5, **SEP)
    with pytest.raises(ValueError, match="smallest roughness"):
        to_mitsuba(m)


FITTED = [
    rb.model("oren-nayar", rho=0.6, sigma=0.4),
    rb.model("microfacet", distribution="ggx", alpha=0.2, n=1.5, k=0.0),
    rb.model("torrance-sparrow-1967", g=2 / 3, c=0.05, n=1.5, k=0.0, rho_d=0.3),
    rb.model("coated", alpha=0.1, rho=0.6, n=1.5),
    rb.model("renhorn-boreman-2008"),
]


@pytest.mark.parametrize("model", FITTED, ids=[m.name for m in FITTED])
def test_fitted_export_reports_mitsubas_deviation(model):
    e = export_mitsuba(model, fit=True, allow_energy_gain=True)  # RB08's albedo exceeds 1
    assert e.status == "fitted" and e.terms[""][0].fitted is not None
    actual = reported_matches_mitsuba(e, model)
    assert actual.rms < 0.25
    # the XML is the same BSDF
    got = mitsuba_eval(mi.load_string(e.xml(version="3.0.0")), *grid_directions(e.grid))[:, 0]
    assert Deviation.of(got, np.asarray(model.brdf(*e.grid))).max == pytest.approx(
        actual.max, rel=1e-4, abs=1e-6)


def test_tr75_fitted_on_request():
    m = rb.model("tr75", e=0.3, n=1.5, k=0.0, rho_L=0.2)
    # TR75 has no shadowing: its albedo exceeds 1 at grazing incidence
    mapped = export_mitsuba(m, allow_energy_gain=True)
    fitted = export_mitsuba(m, fit=True, allow_energy_gain=True)
    assert fitted.status == "fitted"
    actual = reported_matches_mitsuba(fitted, m)
    assert actual.rms < mapped.deviation[""].rms


def test_sum_fits_only_the_part_that_does_not_map():
    m = rb.model("lambertian", rho=0.2) + rb.model("oren-nayar", rho=0.5, sigma=0.5)
    e = export_mitsuba(m, fit=True)
    assert [t.status for t in e.terms[""]] == ["exact", "fitted"]
    reported_matches_mitsuba(e, m)


# ------------------------------------------------------------------------------------------
# channels: one RGB BSDF where only colours differ, else one BSDF per channel
# ------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def three_channels():
    rng = np.random.default_rng(0)
    ti, tr, ph = rng.uniform(0, 1.3, 300), rng.uniform(0, 1.3, 300), rng.uniform(0, np.pi, 300)
    # weights="free" (ks + ks2 = 1): roughplastic + roughconductor, an exact export
    base = rb.model("coated", alpha=0.2, n=1.5, rho=0.5, shadow_diffuse=False,
                    interface="rough", lobes=2, alpha2=0.5, ks=0.7, ks2=0.3, weights="free")
    alphas, rhos = (0.2, 0.21, 0.23), (0.1, 0.5, 0.9)  # 630, 525, 465 nm
    vals = np.stack([base.with_params(alpha=a, rho=r).brdf(ti, tr, ph)
                     for a, r in zip(alphas, rhos, strict=True)], 1)
    meas = rb.Measurement(ti, tr, ph, vals, channels=["630nm", "525nm", "465nm"])
    joint = rb.fit(base, meas, joint=True, fix=["n"], starts=1, progress=False)
    apart = rb.fit(base, meas, fix=["n"], starts=1, progress=False)
    return joint, apart


def test_joint_fit_is_one_rgb_bsdf(three_channels):
    joint, _ = three_channels
    e = export_mitsuba(joint)
    assert e.rule == "rgb" and e.rgb == ("630nm", "525nm", "465nm")  # longest wavelength red
    colour = e.bsdf["bsdf_0"]["diffuse_reflectance"]
    assert colour["type"] == "srgb" and len(colour["color"]) == 3
    angles, wi, wo = geometry(13)
    for bsdf in loaded(e):
        got = mitsuba_eval(bsdf, wi, wo)
        for c, label in enumerate(e.rgb):
            assert rel_error(got[:, c], joint[label].model.brdf(*angles)).max() <= RTOL
    # explicit assignment: blue, green, red in another order
    e2 = export_mitsuba(joint, rgb=("465nm", 1, "630nm"))
    assert e2.rgb == ("465nm", "525nm", "630nm")


def test_separate_fits_are_one_bsdf_per_channel(three_channels):
    _, apart = three_channels
    e = export_mitsuba(apart)
    assert e.rule == "per-channel" and set(e.bsdf) == {"630nm", "525nm", "465nm"}
    angles, wi, wo = geometry(14, 300)
    xml = {el.get("id"): ET.tostring(el, encoding="unicode")
           for el in ET.fromstring(f"<root>{e.xml()}</root>")}
    for label, bsdf in e.bsdf.items():
        ref = apart[label].model.brdf(*angles)
        for b in (mi.load_dict(bsdf), mi.load_string(xml[label].replace(
                "<bsdf ", '<bsdf version="3.0.0" ', 1))):
            assert rel_error(mitsuba_eval(b, wi, wo)[:, 0], ref).max() <= RTOL
    with pytest.raises(ValueError, match="alpha"):
        export_mitsuba(apart, rgb=("630nm", "525nm", "465nm"))
    one = export_mitsuba(apart, channel="525nm")
    assert one.rule == "channel" and one.bsdf["type"] == "blendbsdf"
    assert export_mitsuba(apart["525nm"]).bsdf == one.bsdf  # one channel's result
    with pytest.raises(ValueError, match="rgb"):
        export_mitsuba(apart, channel="525nm", rgb=("630nm", "525nm", "465nm"))
    with pytest.raises(ValueError, match="channel"):
        export_mitsuba(apart, channel="700nm")
    ids = [el.get("id") for el in ET.fromstring(f"<root>{e.xml(id='paint')}</root>")]
    assert ids == ["paint-630nm", "paint-525nm", "paint-465nm"]
    assert export_mitsuba(three_channels[0], rgb=False).rule == "per-channel"


def test_arguments_are_named():
    m = rb.model("lambertian")
    with pytest.raises(ValueError, match="channel"):
        to_mitsuba(m, channel=0)
    with pytest.raises(ValueError, match="theta_max"):
        to_mitsuba(m, theta_max=2.0)
    with pytest.raises(ValueError, match="fit"):
        to_mitsuba(m, fit="yes")
    with pytest.raises(TypeError, match="Model or FitResult"):
        to_mitsuba({"type": "diffuse"})
    ti, _, _ = deviation_grid(math.radians(60.0))
    assert ti.max() <= math.radians(60.0) + 1e-12
