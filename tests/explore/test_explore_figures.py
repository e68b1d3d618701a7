"""The explorer's Plotly figures (:mod:`roughbrdf.explore.figures`): the numbers each figure
draws, read back through ``figure_values``, are the model's own values at the drawn angles
(``model.brdf``, ``model.mueller``, ``rb.albedo``) and the measurement's own values; angle
axes are in degrees and value axes carry units; bad input names the argument.

Where an expected number is not the library's own value at the same angles, its source is an
identity stated beside it (rho/pi of a Lambertian surface, ln(1.1) of data made 1.1 times the
model, m00/m00 = 1, the projected-disk coordinates sin(theta_r) cos/sin(phi)).
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.errors import ArgumentError
from roughbrdf.explore import figures as F
from roughbrdf.models.base import NoMuellerMatrix
from roughbrdf.quantity import relative_scale

TR75 = rb.model("tr75")  # defaults: e = 0.68, TR75's cement; albedo > 1 toward grazing
LAMB = rb.model("lambertian", rho=0.5)  # conserves energy: albedo 0.5 at every incidence
RAD = np.radians


def _measurement(model, factor=1.1, quantity="brdf", channels=("465nm", "525nm")):
    """Samples at two incidences: in plane (phi = 0, pi), across (phi = +-90 deg) and off
    both cuts (phi = 45 deg); values ``factor`` times the model (and 2x in channel 2)."""
    tr = RAD([0.0, 10.0, 40.0, 70.0, 20.0, 50.0, 30.0])
    ph = RAD([0.0, 0.0, 180.0, 0.0, 90.0, 270.0, 45.0])
    ti = np.concatenate([np.full(tr.size, RAD(30.0)), np.full(tr.size, RAD(60.0))])
    tr, ph = np.tile(tr, 2), np.tile(ph, 2)
    f = factor * np.asarray(model.brdf(ti, tr, ph))
    values = np.stack([f, 2 * f], axis=1)
    return rb.Measurement(ti, tr, ph, values, channels=list(channels), quantity=quantity,
                          meta={"sample": "synthetic"})


def _angles(entry):
    return RAD(entry["theta_r_deg"]), RAD(entry["phi_deg"])


# ---------------------------------------------------------------------------------------------
# lobe_3d
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("quantity", ["brdf", "brdf_cos"])
def test_lobe_values_are_the_models_at_the_drawn_angles(quantity):
    ti = RAD(30.0)
    fig = F.lobe_3d(TR75, ti, quantity=quantity, resolution=9, n_phi=13)
    v = F.figure_values(fig)["trowbridge-reitz-1975"]
    assert v["value"].shape == (9, 13)  # n_theta x n_phi
    tr, ph = _angles(v)
    want = TR75.evaluate(ti, tr, ph, quantity=quantity)
    np.testing.assert_allclose(v["value"], want, rtol=1e-12)
    # linear radius: the distance of each surface point from the origin is the value
    np.testing.assert_allclose(np.sqrt(v["x"] ** 2 + v["y"] ** 2 + v["z"] ** 2), want,
                               rtol=1e-12)
    # and the point lies along (sin tr cos ph, sin tr sin ph, cos tr) (library frame)
    np.testing.assert_allclose(v["z"], want * np.cos(tr), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(v["x"], want * np.sin(tr) * np.cos(ph), rtol=1e-12, atol=1e-15)


def test_lobe_log_radius_and_marked_directions():
    ti = RAD(45.0)
    fig = F.lobe_3d(TR75, ti, log=True, resolution=11, decades=3.0)
    vals = F.figure_values(fig)
    v = vals["trowbridge-reitz-1975"]
    floor = np.nanmax(v["value"]) * 1e-3
    r = np.sqrt(v["x"] ** 2 + v["y"] ** 2 + v["z"] ** 2)
    np.testing.assert_allclose(r, np.maximum(np.log10(v["value"] / floor), 0.0), atol=1e-12)
    spec, retro = vals["specular"], vals["retro"]
    assert spec["theta_r_deg"][0] == pytest.approx(45.0) and spec["phi_deg"][0] == 0.0
    assert retro["phi_deg"][0] == pytest.approx(180.0)
    assert spec["value"][0] == pytest.approx(TR75.brdf(ti, ti, 0.0), rel=1e-12)
    assert retro["value"][0] == pytest.approx(TR75.brdf(ti, ti, math.pi), rel=1e-12)
    # the specular line points forward (+x, phi = 0), the retro one toward the source (-x)
    assert spec["x"][-1] > 0 > retro["x"][-1]
    assert "trowbridge-reitz-1975" in fig.layout.title.text and "θi = 45°" in fig.layout.title.text
    assert "sr⁻¹" in fig.layout.scene.xaxis.title.text


def test_lobe_polarization_and_label():
    fig = F.lobe_3d(TR75, 0.5, resolution=5, polarization="s", label="fit", channel="465nm")
    v = F.figure_values(fig)["fit"]
    tr, ph = _angles(v)
    np.testing.assert_allclose(v["value"], TR75.brdf(0.5, tr, ph, polarization="s"), rtol=1e-12)
    assert fig.layout.title.text.startswith("fit:") and "[465nm]" in fig.layout.title.text


def test_lobe_divergence_at_the_horizon_is_a_gap_not_inf():
    # TR75 has no shadowing: f_r -> inf at theta_r = 90 deg (docs/models.md §3)
    fig = F.lobe_3d(TR75, 0.3, resolution=7, theta_max_deg=90.0)
    v = F.figure_values(fig)["trowbridge-reitz-1975"]
    assert not np.isinf(v["value"]).any()
    assert np.isnan(v["value"][-1]).any() and np.isfinite(v["value"][:-1]).all()


@pytest.mark.parametrize("bad", [math.pi / 2, -0.1, float("nan"), [0.1, 0.2], None])
def test_lobe_rejects_bad_incidence(bad):
    with pytest.raises(ArgumentError) as err:
        F.lobe_3d(TR75, bad, resolution=5)
    assert err.value.argument == "theta_i"


@pytest.mark.parametrize(("kwargs", "argument"), [
    ({"quantity": "relative"}, "quantity"), ({"resolution": 2}, "resolution"),
    ({"n_phi": 1.5}, "n_phi"), ({"theta_max_deg": 95.0}, "theta_max_deg")])
def test_lobe_rejects_bad_options(kwargs, argument):
    with pytest.raises(ArgumentError) as err:
        F.lobe_3d(TR75, 0.3, **{"resolution": 5, **kwargs})
    assert err.value.argument == argument


def test_lobe_rejects_a_non_model():
    with pytest.raises(ArgumentError) as err:
        F.lobe_3d("tr75", 0.3)
    assert err.value.argument == "model"


# ---------------------------------------------------------------------------------------------
# compare_lobes
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("mode", ["overlay", "side"])
def test_compare_lobes_draws_both_models(mode):
    ti = RAD(20.0)
    fig = F.compare_lobes(TR75, LAMB, ti, mode=mode, resolution=7)
    vals = F.figure_values(fig)
    for name, model in (("A: trowbridge-reitz-1975", TR75), ("B: lambertian", LAMB)):
        tr, ph = _angles(vals[name])
        np.testing.assert_allclose(vals[name]["value"], model.brdf(ti, tr, ph), rtol=1e-12)
    assert {"specular (A)", "retro (B)"} <= set(vals)
    scenes = {t.scene for t in fig.data if t.type == "surface"}
    assert scenes == ({"scene", "scene2"} if mode == "side" else {"scene"})


def test_compare_lobes_rejects_a_bad_mode_and_model():
    with pytest.raises(ArgumentError) as err:
        F.compare_lobes(TR75, LAMB, 0.2, mode="stacked")
    assert err.value.argument == "mode"
    with pytest.raises(ArgumentError) as err:
        F.compare_lobes(TR75, None, 0.2)
    assert err.value.argument == "model_b"


# ---------------------------------------------------------------------------------------------
# plane_cuts
# ---------------------------------------------------------------------------------------------
def test_cuts_of_a_model_alone_follow_the_signed_angle():
    fig = F.plane_cuts(TR75, incidences=[RAD(30.0)], n=41, log=False)
    vals = F.figure_values(fig)
    assert set(vals) == {"model θi = 30° (in-plane)", "model θi = 30° (cross-plane)"}
    for cut, (pos, neg) in {"in-plane": (0.0, 180.0), "cross-plane": (90.0, 270.0)}.items():
        v = vals[f"model θi = 30° ({cut})"]
        tr, ph = _angles(v)
        np.testing.assert_allclose(v["y"], TR75.brdf(RAD(30.0), tr, ph), rtol=1e-12)
        # +theta_r on the positive side (phi = 0 / +90 deg), -theta_r on the other
        np.testing.assert_allclose(np.abs(v["x"]), v["theta_r_deg"], atol=1e-12)
        np.testing.assert_allclose(np.mod(v["phi_deg"][v["x"] < 0], 360), neg, atol=1e-9)
        np.testing.assert_allclose(v["phi_deg"][v["x"] > 0], pos, atol=1e-9)
    assert fig.layout.yaxis.type == "linear" and "sr⁻¹" in fig.layout.yaxis.title.text
    assert "deg" in fig.layout.xaxis.title.text


def test_cuts_default_incidences_of_a_model_alone():
    fig = F.plane_cuts(LAMB, n=5)
    names = {t.name for t in fig.data}
    assert {f"model θi = {d}° (in-plane)" for d in (0, 30, 60, 75)} <= names


def test_cuts_of_model_and_data_hold_data_values_and_log_residuals():
    meas = _measurement(TR75)
    fig = F.plane_cuts(TR75, meas, channel="525nm", n=11)
    vals = F.figure_values(fig)
    d = vals["data θi = 30° (in-plane)"]
    # the data points are the measurement's own values of that channel at those angles
    sel = (np.abs(meas.theta_i - RAD(30.0)) < 1e-9) & np.isin(np.round(np.degrees(meas.phi)),
                                                              [0.0, 180.0])
    np.testing.assert_allclose(np.sort(d["y"]), np.sort(meas.values[sel, 1]), rtol=1e-15)
    tr, ph = _angles(d)
    np.testing.assert_allclose(d["y"], 2.2 * TR75.brdf(RAD(30.0), tr, ph), rtol=1e-12)
    # data = 2.2 x model (the channel 525nm of _measurement): residual ln(2.2) everywhere
    for cut in ("in-plane", "cross-plane"):
        r = vals[f"residual θi = 60° ({cut})"]
        np.testing.assert_allclose(r["y"], math.log(2.2), rtol=1e-12)
    # the off-plane sample (phi = 45 deg) is in neither cut; theta_r = 0 is in both
    drawn = np.concatenate([vals[f"data θi = 30° ({c})"]["phi_deg"] for c in
                            ("in-plane", "cross-plane")])
    assert 45.0 not in np.round(drawn)
    assert fig.layout.yaxis.type == "log" and "[525nm]" in fig.layout.title.text
    assert "synthetic" in fig.layout.title.text
    assert "ln(data / model)" in fig.layout.yaxis3.title.text


def test_cuts_of_data_alone_have_no_model_and_no_residual():
    meas = _measurement(TR75)
    fig = F.plane_cuts(None, meas, log=False)
    names = [t.name for t in fig.data]
    assert names and all(n.startswith("data ") for n in names)
    assert fig.layout.yaxis.type == "linear"


def test_cuts_of_relative_data_scale_the_model_by_k():
    # relative data 3 x the model: the model drawn divided by the data scale K of
    # rb.quantity.relative_scale (K x ~ f, TR75 Eq. 34), which is 1/3 to its solver's tolerance
    meas = _measurement(TR75, factor=3.0, quantity="relative")
    k = relative_scale(meas.values[:, 0], TR75.brdf(meas.theta_i, meas.theta_r, meas.phi))
    assert k == pytest.approx(1 / 3, rel=1e-5)
    fig = F.plane_cuts(TR75, meas, n=7)
    v = F.figure_values(fig)["model θi = 30° (in-plane)"]
    tr, ph = _angles(v)
    np.testing.assert_allclose(v["y"], TR75.brdf(RAD(30.0), tr, ph) / k, rtol=1e-12)
    assert "1/K = 3" in fig.layout.title.text
    r = F.figure_values(fig)["residual θi = 30° (in-plane)"]["y"]
    np.testing.assert_allclose(r, math.log(3.0 * k), rtol=1e-9, atol=1e-12)  # ln(3 K)


def test_cuts_bad_inputs_name_the_argument():
    meas = _measurement(TR75)
    for kwargs, argument in (({"channel": "999nm"}, "channel"), ({"channel": 5}, "channel"),
                             ({"incidences": [0.2, 1.6]}, "incidences")):
        with pytest.raises(ArgumentError) as err:
            F.plane_cuts(TR75, meas, **kwargs)
        assert err.value.argument == argument
    with pytest.raises(ArgumentError) as err:
        F.plane_cuts()
    assert err.value.argument == "model"
    with pytest.raises(ArgumentError) as err:
        F.plane_cuts(TR75, measurement=[1, 2])
    assert err.value.argument == "measurement"


def test_cuts_refuse_a_mueller_element_other_than_m00():
    m = rb.Measurement([0.5], [0.5], [0.0], [[0.8, 0.1]], channels=["m00", "m01"],
                       mueller="normalized")
    with pytest.raises(ArgumentError) as err:
        F.plane_cuts(TR75, m, channel="m01")
    assert err.value.argument == "channel"
    assert F.figure_values(F.plane_cuts(None, m, channel="m00"))[
        "data θi = 28.65° (in-plane)"]["y"].tolist() == [0.8]


# ---------------------------------------------------------------------------------------------
# hemisphere_maps
# ---------------------------------------------------------------------------------------------
def test_maps_model_grid_is_the_model_on_the_projected_disk():
    ti = RAD(40.0)
    fig = F.hemisphere_maps(TR75, theta_i=ti, resolution=21)
    v = F.figure_values(fig)["model"]
    inside = np.isfinite(v["theta_r_deg"])
    tr, ph = _angles(v)
    want = TR75.brdf(ti, tr[inside], ph[inside])
    got = v["value"][inside]
    ok = np.isfinite(want)  # the horizon ring: TR75 diverges there and is drawn as a gap
    np.testing.assert_allclose(got[ok], want[ok], rtol=1e-12)
    assert np.isnan(got[~ok]).all()
    np.testing.assert_allclose(v["z"][inside][ok], np.log10(want[ok]), rtol=1e-12)  # log colours
    # grid column/row positions are the direction cosines sin tr cos ph, sin tr sin ph
    X, Y = np.meshgrid(v["x"], v["y"])
    np.testing.assert_allclose(X[inside], np.sin(tr[inside]) * np.cos(ph[inside]), atol=1e-12)
    np.testing.assert_allclose(Y[inside], np.sin(tr[inside]) * np.sin(ph[inside]), atol=1e-12)
    assert "θi = 40°" in fig.layout.title.text


def test_maps_linear_and_degree_coordinates():
    fig = F.hemisphere_maps(LAMB, theta_i=0.2, resolution=11, log=False, coords="degrees")
    v = F.figure_values(fig)["model"]
    inside = np.isfinite(v["value"])
    np.testing.assert_allclose(v["z"][inside], 0.5 / math.pi, rtol=1e-12)  # rho/pi, linear
    X, Y = np.meshgrid(v["x"], v["y"])
    np.testing.assert_allclose(np.hypot(X, Y)[inside], v["theta_r_deg"][inside], atol=1e-9)
    assert "deg" in fig.layout.xaxis.title.text


def test_maps_of_data_model_and_ratio():
    meas = _measurement(TR75)
    fig = F.hemisphere_maps(TR75, meas, RAD(60.0), channel="465nm", resolution=9)
    vals = F.figure_values(fig)
    assert {"data", "model", "data/model"} <= set(vals)
    d = vals["data"]
    at = np.abs(meas.theta_i - RAD(60.0)) < 1e-9
    np.testing.assert_allclose(d["value"], meas.values[at, 0], rtol=1e-15)
    # the markers sit at the samples' direction cosines
    np.testing.assert_allclose(d["x"], np.sin(meas.theta_r[at]) * np.cos(meas.phi[at]),
                               atol=1e-12)
    np.testing.assert_allclose(vals["data/model"]["value"], 1.1, rtol=1e-12)  # data = 1.1 x
    assert "[465nm]" in fig.layout.title.text
    assert "sr⁻¹" in fig.layout.coloraxis.colorbar.title.text


def test_maps_of_data_alone_default_to_the_first_incidence():
    meas = _measurement(TR75)
    fig = F.hemisphere_maps(measurement=meas)
    assert [n for n in F.figure_values(fig) if not n.startswith(("specular", "retro"))] == \
        ["data"]
    assert "θi = 30°" in fig.layout.title.text


def test_maps_bad_inputs_name_the_argument():
    with pytest.raises(ArgumentError) as err:
        F.hemisphere_maps(TR75)
    assert err.value.argument == "theta_i"
    with pytest.raises(ArgumentError) as err:
        F.hemisphere_maps(TR75, theta_i=math.pi / 2)
    assert err.value.argument == "theta_i"
    with pytest.raises(ArgumentError) as err:
        F.hemisphere_maps(TR75, _measurement(TR75), 0.5, channel="red")
    assert err.value.argument == "channel"
    with pytest.raises(ArgumentError) as err:
        F.hemisphere_maps(TR75, theta_i=0.5, coords="polar")
    assert err.value.argument == "coords"


# ---------------------------------------------------------------------------------------------
# albedo_curve
# ---------------------------------------------------------------------------------------------
def _warnings(fig):
    return [a for a in fig.layout.annotations if a.name == F.WARNING_NAME]


def test_albedo_above_one_gets_the_warning():
    d = [0.0, 30.0, 60.0, 85.0, 89.0]
    fig = F.albedo_curve(TR75, incidences_deg=d)
    v = F.figure_values(fig)
    np.testing.assert_allclose(v["albedo"]["y"], rb.albedo(TR75, RAD(d)), rtol=1e-12)
    assert v["albedo"]["y"][-1] > 1.001  # TR75's defaults gain energy at grazing
    (warn,) = _warnings(fig)
    assert "albedo above 1" in warn.text and "89°" in warn.text
    assert set(v["albedo > 1"]["x"]) <= {85.0, 89.0}
    np.testing.assert_array_equal(v["albedo = 1"]["y"], [1.0, 1.0])
    assert "deg" in fig.layout.xaxis.title.text and "[1]" in fig.layout.yaxis.title.text


def test_albedo_of_an_energy_conserving_model_has_no_warning():
    fig = F.albedo_curve(LAMB, incidences_deg=[0.0, 45.0, 89.0])
    assert LAMB.conserves_energy and not _warnings(fig)
    # rho = 0.5, to the quadrature's stated accuracy (about 1e-5, rb.albedo's docstring)
    np.testing.assert_allclose(F.figure_values(fig)["albedo"]["y"], 0.5, atol=1e-5)


def test_albedo_default_incidences_and_bad_ones():
    v = F.figure_values(F.albedo_curve(LAMB))["albedo"]
    np.testing.assert_array_equal(v["x"], np.arange(90.0))
    for bad in ([0, 90], [-1.0], [np.nan], "x", []):
        with pytest.raises(ArgumentError) as err:
            F.albedo_curve(LAMB, incidences_deg=bad)
        assert err.value.argument == "incidences_deg"


# ---------------------------------------------------------------------------------------------
# mueller_maps
# ---------------------------------------------------------------------------------------------
def test_mueller_maps_are_m00_normalized_elements_and_dolp():
    ti = RAD(50.0)
    fig = F.mueller_maps(TR75, ti, resolution=15)
    vals = F.figure_values(fig)
    assert len([n for n in vals if n.endswith("/m00")]) == 16 and "DoLP" in vals
    v00 = vals["m00/m00"]
    inside = np.isfinite(v00["z"])
    np.testing.assert_array_equal(v00["z"][inside], 1.0)  # m00/m00 = 1
    tr, ph = _angles(v00)
    M = TR75.mueller(ti, tr[inside], ph[inside])
    for ij in ("01", "12", "23", "33"):
        i, j = int(ij[0]), int(ij[1])
        want = M[..., i, j] / M[..., 0, 0]
        np.testing.assert_allclose(vals[f"m{ij}/m00"]["z"][inside], want, rtol=1e-12,
                                   atol=1e-15)
    want = np.hypot(M[..., 1, 0], M[..., 2, 0]) / M[..., 0, 0]  # DoLP of natural light
    np.testing.assert_allclose(vals["DoLP"]["z"][inside], want, rtol=1e-12, atol=1e-15)
    assert ((want >= 0) & (want <= 1 + 1e-12)).all()
    np.testing.assert_allclose(v00["m00"][inside], TR75.brdf(ti, tr[inside], ph[inside]),
                               rtol=1e-12)
    assert "θi = 50°" in fig.layout.title.text


def test_mueller_maps_raise_for_a_model_without_a_matrix():
    with pytest.raises(NoMuellerMatrix):
        F.mueller_maps(rb.model("renhorn-boreman-2008"), 0.3, resolution=5)
    with pytest.raises(ArgumentError) as err:
        F.mueller_maps(TR75, 1.6)
    assert err.value.argument == "theta_i"


# ---------------------------------------------------------------------------------------------
# figure_values and the package's import
# ---------------------------------------------------------------------------------------------
def test_figure_values_read_the_json_form_the_same_way():
    fig = F.plane_cuts(TR75, _measurement(TR75), n=7)
    a, b = F.figure_values(fig), F.figure_values(fig.to_plotly_json())
    assert a.keys() == b.keys()
    for name in a:
        for key in a[name]:
            np.testing.assert_array_equal(a[name][key], b[name][key])


def test_figure_values_number_repeated_names():
    import plotly.graph_objects as go

    fig = go.Figure([go.Scatter(x=[1], y=[2], name="a"), go.Scatter(x=[3], y=[4], name="a")])
    assert list(F.figure_values(fig)) == ["a", "a #2"]


def test_import_roughbrdf_loads_neither_plotly_nor_dash():
    code = ("import sys, roughbrdf as rb; rb.model('tr75').brdf(0.1, 0.2, 0.3); "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('plotly', 'dash')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]"


# ---------------------------------------------------------------------------------------------
# non-finite data, n-dimensional options, a real file
# ---------------------------------------------------------------------------------------------
def test_nan_and_negative_data_are_gaps_not_errors():
    meas = _measurement(TR75)
    meas.values[0, 0] = np.nan  # theta_i 30, theta_r 0 (in both cuts)
    meas.values[1, 0] = -1.0  # theta_i 30, theta_r 10, phi 0: no log ratio
    vals = F.figure_values(F.plane_cuts(TR75, meas, n=5))
    d, r = vals["data θi = 30° (in-plane)"], vals["residual θi = 30° (in-plane)"]
    assert np.isnan(d["y"]).sum() == 1 and np.isnan(r["y"]).sum() == 2
    assert np.isfinite(r["y"]).sum() == d["y"].size - 2
    maps = F.figure_values(F.hemisphere_maps(TR75, meas, RAD(30.0), resolution=5))
    ratio = maps["data/model"]
    assert np.isnan(ratio["value"]).sum() == 1 and ratio["value"][1] < 0  # as measured
    assert np.isnan(ratio["color"]).sum() == 2  # log10 colour: none for NaN and ratio <= 0


def test_cuts_take_incidences_of_any_shape():
    fig = F.plane_cuts(LAMB, incidences=np.array([[0.1], [0.2]]), n=5)
    assert len(fig.data) == 4  # two incidences x two cuts


def test_side_by_side_lobes_share_one_scale():
    fig = F.compare_lobes(TR75, LAMB, 0.4, mode="side", resolution=7)
    assert fig.layout.scene.xaxis.range == fig.layout.scene2.xaxis.range
    surfaces = [t for t in fig.data if t.type == "surface"]
    assert surfaces[0].cmax == surfaces[1].cmax and surfaces[0].cmin == surfaces[1].cmin


def test_a_real_files_points_are_its_values(shared_data):
    meas = rb.read(shared_data / "minidiff" / "C2_Black.astm")
    fig = F.plane_cuts(TR75, meas, channel="630nm", n=11)
    vals = F.figure_values(fig)
    name = next(n for n in vals if n.startswith("data ") and n.endswith("(in-plane)"))
    d = vals[name]
    j = meas.channel_index("630nm")
    for k in (0, d["y"].size // 2, -1):  # each drawn point is one sample of the file
        hit = ((np.abs(np.degrees(meas.theta_i) - d["theta_i_deg"][k]) < 1e-9)
               & (np.abs(np.degrees(meas.theta_r) - d["theta_r_deg"][k]) < 1e-9)
               & (np.abs(np.degrees(meas.phi) - d["phi_deg"][k]) < 1e-9))
        assert hit.sum() >= 1
        assert d["y"][k] in meas.values[hit, j]
    tr, ph = _angles(d)
    np.testing.assert_allclose(d["model"], TR75.brdf(RAD(d["theta_i_deg"]), tr, ph),
                               rtol=1e-12)


def test_cuts_log_axis_ignores_a_few_values_near_zero():
    meas = _measurement(LAMB, channels=("a", "b"))
    meas.values[2, 0] = 1e-18  # one sample at a file's floor (Mini-Diff has such values)
    fig = F.plane_cuts(LAMB, meas, n=5)
    lo, hi = fig.layout.yaxis.range
    # the 0.5th percentile of the drawn positive values / 3, and the largest x 3 (log10 units)
    y = np.concatenate([np.asarray(t.y, dtype=float) for t in fig.data if t.yaxis in ("y", "y2")])
    y = y[y > 0]
    assert lo == pytest.approx(math.log10(np.percentile(y, 0.5) / 3), rel=1e-12)
    assert hi == pytest.approx(math.log10(1.1 * 0.5 / math.pi * 3), rel=1e-12)  # data 1.1 rho/pi
    assert lo > -17  # the 1e-18 sample is below the axis, not stretching it


def test_maps_model_with_a_polarization():
    fig = F.hemisphere_maps(TR75, theta_i=0.6, resolution=9, polarization="p")
    v = F.figure_values(fig)["model"]
    inside = np.isfinite(v["value"])
    tr, ph = _angles(v)
    np.testing.assert_allclose(v["value"][inside],
                               TR75.brdf(0.6, tr[inside], ph[inside], polarization="p"),
                               rtol=1e-12)
    assert not np.allclose(v["value"][inside], TR75.brdf(0.6, tr[inside], ph[inside]))


def test_figure_values_decode_typed_arrays_with_either_shape_form():
    import base64

    a = np.arange(6.0).reshape(2, 3)
    data = base64.b64encode(a.tobytes()).decode()
    for shape in ("2, 3", [2, 3]):
        fig = {"data": [{"name": "t", "z": {"dtype": "f8", "bdata": data, "shape": shape}}]}
        np.testing.assert_array_equal(F.figure_values(fig)["t"]["z"], a)
