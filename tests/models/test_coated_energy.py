"""The coated model conserves energy by construction (docs/models.md §10.3).

Its lobes are roughness scales of one interface: their weights sum to 1 (one lobe: weight 1;
``w2``, ``w3`` share it out), and the substrate receives only what the interface transmits
(``interface="rough"``: the lobes' mixed transmittance; ``"smooth"``: ``1 - R(theta)``, limited
to what the lobes do not reflect). So for every option and every parameter value in its
domain, ``rb.albedo <= 1 + 1e-3`` (``rb.albedo`` is good to about 1e-4) at the incidences the
fits check, 0, 5, ... 85, 89 deg. On the code before the change the model had free scales
``ks`` in [0, 20] and ``rb.model("coated", ks=...)`` was accepted; with ``ks = 1`` a Beckmann
lobe over a smooth interface reflected 1.0029 (``test_smooth_interface_corner``).

Also: the clear error for the old ``ks`` and the legacy ``weights="free"`` option, and
microfacet's physical ``ks`` range ([0, 1]: one interface with ``F <= 1``).
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import roughbrdf as rb
from roughbrdf.errors import ArgumentError

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="coated albedos at 19 incidences (~3 min each) and fits, in plain Python")

#: the incidences of the fits' energy check (docs/models.md, "What each model guarantees")
INCIDENCES = np.radians([*range(0, 90, 5), 89])
TOL = 1e-3


def _max_albedo(m: rb.models.Model) -> tuple[float, float]:
    """The largest albedo over :data:`INCIDENCES` and its incidence (degrees)."""
    a = np.asarray(rb.albedo(m, INCIDENCES))
    i = int(np.argmax(a))
    return float(a[i]), float(np.degrees(INCIDENCES[i]))


#: every option value of the coated model (weights: the default, energy-conserving one)
OPTIONS = {"distribution": ["trowbridge-reitz", "beckmann"],
           "shadowing": ["smith-separable", "smith-height-correlated"], "lobes": [1, 2, 3],
           "diffuse": ["lambertian", "oren-nayar"], "shadow_diffuse": [False, True],
           "interface": ["smooth", "rough"]}


def _unit():
    # the whole interval, with its two ends (the corners) drawn often
    return st.one_of(st.sampled_from([0.0, 1.0]), st.floats(0.0, 1.0))


@st.composite
def coated_models(draw):
    opts = {k: draw(st.sampled_from(v)) for k, v in OPTIONS.items()}
    kw = {"n": draw(st.one_of(st.sampled_from([1.01, 1.05, 1.45, 2.5]),
                              st.floats(1.01, 3.0))),
          "rho": draw(_unit()),
          "alpha": draw(st.one_of(st.sampled_from([0.005, 0.22, 1.5]), st.floats(0.005, 2.0)))}
    for j in range(2, opts["lobes"] + 1):
        kw[f"alpha{j}"] = draw(st.one_of(st.sampled_from([0.005, 0.22, 1.5]),
                                         st.floats(0.005, 2.0)))
        kw[f"w{j}"] = draw(_unit())
    if opts["diffuse"] == "oren-nayar":
        kw["sigma"] = draw(st.one_of(st.sampled_from([0.0, 0.2, 1.2]), st.floats(0.0, 1.5)))
    return rb.model("coated", **opts, **kw)


@settings(max_examples=40, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(coated_models())
def test_hypothesis_coated_albedo_at_most_one(m):
    worst, at = _max_albedo(m)
    assert worst <= 1.0 + TOL, f"{m!r} reflects {worst:.5f} at {at:g} deg"


@pytest.mark.parametrize("distribution", ["trowbridge-reitz", "beckmann"])
@pytest.mark.parametrize("shadowing", ["smith-separable", "smith-height-correlated"])
@pytest.mark.parametrize("interface", ["smooth", "rough"])
def test_corners_rho_one(distribution, shadowing, interface):
    # the corners where energy is tightest: a white substrate without diffuse shadowing
    # (which only removes light; the Hypothesis test has it), the rough lobes whose
    # facet-averaged F exceeds the smooth R(theta) (Beckmann alpha ~ 0.2), the widest lobe,
    # the index range's ends; three lobes with all the weight on the last one
    for n, lobes in ((1.45, {"alpha": 0.22}), (1.2, {"alpha": 0.1}), (2.5, {"alpha": 1.5}),
                     (1.05, {"alpha": 0.005}),
                     (1.45, {"lobes": 3, "alpha": 0.005, "alpha2": 1.5, "w2": 0.0,
                             "alpha3": 0.22, "w3": 1.0}),
                     (2.5, {"lobes": 2, "alpha": 0.005, "alpha2": 0.22, "w2": 1.0})):
            m = rb.model("coated", distribution=distribution, shadowing=shadowing,
                         interface=interface, shadow_diffuse=False, rho=1.0, n=n,
                         **lobes)
            worst, at = _max_albedo(m)
            assert worst <= 1.0 + TOL, f"{m!r} reflects {worst:.5f} at {at:g} deg"


@pytest.mark.parametrize("interface", ["smooth", "rough"])
def test_oren_nayar_substrate_corner(interface):
    # Oren-Nayar's Eq. 30 reflects up to 1.5 % more than it receives beyond 60.7 deg (sigma
    # about 0.2 rad; docs/models.md §10.2); under a nearly index-matched, nearly smooth coat
    # that reached 1.0086 at 85 deg. The coated substrate's factor is limited by it
    m = rb.model("coated", diffuse="oren-nayar", sigma=0.199, rho=1.0, n=1.01, alpha=0.005,
                 shadow_diffuse=False, interface=interface)
    worst, at = _max_albedo(m)
    assert worst <= 1.0 + TOL, f"{worst:.5f} at {at:g} deg"


def test_smooth_interface_corner():
    # the worst corner of the old model with the weight 1 it now has: Beckmann, alpha = 0.22,
    # n = 1.45, no diffuse shadowing, white substrate: 1.0029 at 50 deg before the substrate
    # was limited to what the lobe leaves; now at most 1 (to the tables' accuracy)
    m = rb.model("coated", distribution="beckmann", n=1.45, alpha=0.22, rho=1.0,
                 shadow_diffuse=False)
    worst, _ = _max_albedo(m)
    assert worst <= 1.0 + 2e-4
    # where the lobe reflects less than R (a nearly smooth lobe, normal incidence) the
    # substrate term is the smooth interface's formula, unchanged: albedo 1 - R(0) + R(0)
    nearly_smooth = m.with_params(alpha=0.005)
    assert float(rb.albedo(nearly_smooth, 0.0)) == pytest.approx(1.0, abs=2e-4)


def test_rough_interface_mixes_the_lobes_tables():
    # two lobes of one rough interface: the substrate sees the weight-mixture of each lobe's
    # transmittance (before: the first lobe's only, which with a rougher, stronger lobe 2 let
    # the substrate receive light the lobes already reflected)
    kw = {"interface": "rough", "shadow_diffuse": False, "rho": 1.0, "n": 1.5}
    m = rb.model("coated", lobes=2, alpha=0.005, alpha2=1.0, w2=0.9, **kw)
    t1, f1 = rb.diffuse.rough_interface(0.005, 1.5)
    t2, f2 = rb.diffuse.rough_interface(1.0, 1.5)
    t, f_int = 0.1 * t1 + 0.9 * t2, 0.1 * f1 + 0.9 * f2
    ti, tr = np.array([0.0, 0.5, 1.0]), np.array([0.3, 0.9, 0.2])
    lerp = lambda c: np.interp(c, rb.diffuse.TABLE_NODES, t)  # noqa: E731
    diffuse = (1.0 / math.pi * lerp(np.cos(ti)) * lerp(np.cos(tr))
               / (1.5 ** 2 * (1.0 - f_int)))
    lobes_only = m.with_params(rho=0.0)
    got = m.brdf(ti, tr, math.pi / 2) - lobes_only.brdf(ti, tr, math.pi / 2)
    np.testing.assert_allclose(got, diffuse, rtol=1e-9)
    assert _max_albedo(m)[0] <= 1.0 + TOL


def test_weights_are_a_partition_of_unity():
    m = rb.model("coated", lobes=3, alpha=0.05, alpha2=0.2, alpha3=0.6, w2=0.2, w3=0.25)
    assert m.param_names == ["n", "rho", "alpha", "alpha2", "w2", "alpha3", "w3"]
    (w1, _), (w2, _), (w3, _) = m.specular_lobes()
    assert (w1, w2, w3) == pytest.approx((0.6, 0.2, 0.2)) and w1 + w2 + w3 == pytest.approx(1)
    assert rb.model("coated").param_names == ["n", "rho", "alpha"]  # one lobe: weight 1
    for name in ("w2", "w3"):
        p = next(q for q in m.parameters if q.name == name)
        assert p.bounds == (0.0, 1.0) and p.unit == "1"
        with pytest.raises(ArgumentError, match=name):
            m.with_params(**{name: 1.5})
    # lobes=2 with all weight on lobe 2 is the one-lobe model of alpha2
    two = rb.model("coated", lobes=2, alpha=0.05, alpha2=0.3, w2=1.0, rho=0.4,
                   shadow_diffuse=False)  # (diffuse shadowing is the first lobe's)
    one = rb.model("coated", alpha=0.3, rho=0.4, shadow_diffuse=False)
    ti, tr, ph = np.array([0.1, 0.6, 1.2]), np.array([0.2, 0.6, 0.4]), np.array([0.0, 0.1, 2.0])
    np.testing.assert_allclose(two.brdf(ti, tr, ph), one.brdf(ti, tr, ph), rtol=1e-12)


@pytest.mark.parametrize("name", ["ks", "ks2", "ks3"])
def test_old_ks_raises_naming_the_change(name):
    kw = {"lobes": 3, name: 0.5}
    with pytest.raises(ArgumentError) as info:
        rb.model("coated", **kw)
    text = str(info.value)
    assert info.value.argument == name
    assert f"no parameter {name!r}" in text and "sum to 1" in text and "weights='free'" in text
    with pytest.raises(ArgumentError, match="weights='free'"):
        rb.model("coated(ks=0.5)")
    with pytest.raises(ArgumentError, match="weights='free'"):
        rb.model("coated").with_params(ks=0.5)


def test_weights_free_restores_the_old_scales():
    m = rb.model("coated", weights="free", lobes=2, ks=3.0, ks2=0.5, alpha2=0.3)
    assert m.param_names == ["n", "rho", "alpha", "ks", "alpha2", "ks2"]
    assert m.options["weights"] == "free" and "weights" not in rb.model("coated").options
    assert {p.name: p.bounds for p in m.parameters}["ks"] == (0.0, 20.0)
    assert "not energy-conserving" in {p.name: p.description for p in m.parameters}["ks"]
    assert m.specular_lobes() == [(3.0, 0.05), (0.5, 0.3)]
    # the old values exactly: lobe j is ks_j times a microfacet lobe of index n
    mf = rb.model("microfacet", n=1.5, k=0.0, alpha=0.05, ks=3.0, shadowing="smith-separable")
    ti, tr, ph = np.array([0.1, 0.6]), np.array([0.2, 0.6]), np.array([0.0, 0.1])
    lobe1 = m.with_params(rho=0.0, ks2=0.0)
    np.testing.assert_allclose(lobe1.brdf(ti, tr, ph), mf.brdf(ti, tr, ph), rtol=1e-12)
    # not energy-conserving: the old free scale at its search bound reflects far more than 1
    assert float(rb.albedo(m.with_params(ks=20.0), 1.4)) > 2.0
    assert rb.model(m.to_dict()).params == m.params  # round trip keeps the option


def test_microfacet_ks_search_range_is_physical():
    spec = {p.name: p for p in rb.model("microfacet").parameters}["ks"]
    assert spec.bounds == (0.0, 1.0)
    assert rb.model("microfacet", ks=5.0).params["ks"] == 5.0  # the domain is still [0, inf)
    # at ks = 1 one interface reflects at most what it receives (F <= 1; F = 1 with n=None)
    for d, s in [("trowbridge-reitz", "smith-separable"), ("beckmann", "smith-height-correlated"),
                 ("gaussian-angle", "v-groove")]:
        for alpha in (0.01, 0.3, 2.0):
            for n, k in ((None, None), (0.2, 3.0)):
                m = rb.model("microfacet", distribution=d, shadowing=s, alpha=alpha, n=n, k=k,
                             ks=1.0)
                assert _max_albedo(m)[0] <= 1.0 + TOL, m


# ------------------------------------------------------------------------------------------
# fits saved before the change: coated with free lobe scales ks
# ------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def legacy_fit_dir(tmp_path_factory):
    """A fit.json as roughbrdf 0.1.0 wrote it: a real fit of the coated model with the free
    lobe scale ``ks`` in its ``params`` and ``model_spec`` and no ``weights`` option."""
    import json

    from roughbrdf.cli import main

    root = tmp_path_factory.mktemp("legacy")
    grid = np.radians(np.mgrid[0:61:30, 0:81:10, 0:181:45].reshape(3, -1))
    truth = rb.model("coated", n=1.5, rho=0.4, alpha=0.2)
    data = root / "paint.csv"
    rb.write(rb.Measurement(*grid, truth.brdf(*grid), quantity="brdf"), data)
    assert main(["fit", str(data), "--model", "coated", "--starts", "1", "--no-plots", "-q",
                 "--out", str(root / "new")]) in (0, 1)
    fit = json.loads((root / "new" / "fit.json").read_text())
    for chan in fit["channels"]:
        chan["params"]["ks"] = 1.7
        chan["model_spec"]["params"]["ks"] = 1.7
        assert "weights" not in chan["model_spec"]["options"]
    old = root / "old"
    old.mkdir()
    (old / "fit.json").write_text(json.dumps(fit))
    return old


def test_legacy_fit_loads_with_free_weights_and_a_note(legacy_fit_dir):
    from roughbrdf.fitting.results.fit_json import fitted_models
    from roughbrdf.models.coated import LegacyCoatedWarning

    with pytest.warns(LegacyCoatedWarning, match="predates energy-conserving coated lobes"):
        models = fitted_models(legacy_fit_dir)
    (m,) = models.values()
    assert m.options["weights"] == "free" and m.params["ks"] == 1.7


def test_legacy_fit_plots_and_exports(legacy_fit_dir, tmp_path, capsys):
    from roughbrdf.cli import main
    from roughbrdf.models.coated import LegacyCoatedWarning

    with pytest.warns(LegacyCoatedWarning):  # the note, at the command line too
        code = main(["plot", "--fit", str(legacy_fit_dir)])
    assert code == 0, capsys.readouterr().err
    assert list(legacy_fit_dir.glob("*.png"))
    target = tmp_path / "paint.bsdf"
    with pytest.warns(LegacyCoatedWarning):
        code = main(["export", "--fit", str(legacy_fit_dir), "--to", "zemax", "--out",
                     str(target), "--allow-energy-gain"])
    assert code == 0, capsys.readouterr().err
    assert list(tmp_path.glob("paint*.bsdf"))


def test_fit_with_a_non_physical_ks_range_says_so():
    grid = np.radians(np.mgrid[0:61:30, 0:81:10, 0:181:45].reshape(3, -1))
    truth = rb.model("microfacet", alpha=0.3, n=1.5, k=0.0, ks=0.8)
    meas = rb.Measurement(*grid, truth.brdf(*grid), quantity="brdf")
    kw = {"fix": ["n", "k"], "starts": 1, "progress": False}
    wide = rb.fit(truth, meas, bounds={"ks": (0.0, 20.0)}, **kw)
    (chan,) = wide.to_dict()["channels"]
    assert chan["non_physical_range"] == {"ks": [0.0, 20.0]}
    assert "NON-PHYSICAL RANGE: searched ks in [0, 20] (physical: [0, 1])" in wide.report()
    plain = rb.fit(truth, meas, **kw)
    (chan,) = plain.to_dict()["channels"]
    assert chan["non_physical_range"] == {} and "NON-PHYSICAL" not in plain.report()
    assert chan["bounds"]["ks"] == [0.0, 1.0]


def test_legacy_note_is_one_warning_line_at_the_command_line(legacy_fit_dir, tmp_path):
    # the console script prints Python warnings in the command line's form: one line
    # "warning: ...", no source file and line (those come back with --debug)
    import subprocess
    import sys

    out = tmp_path / "legacy.png"
    proc = subprocess.run([sys.executable, "-m", "roughbrdf.cli", "plot", "--fit",
                           str(legacy_fit_dir), "--out", str(out)],
                          capture_output=True, text=True, timeout=300,
                          env={**os.environ, "PYTHONWARNINGS": "default"})
    assert proc.returncode == 0, proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if "predates" in ln]
    assert len(lines) == 1 and lines[0].startswith("warning: "), proc.stderr
    assert "coated.py" not in proc.stderr and "LegacyCoatedWarning" not in proc.stderr
