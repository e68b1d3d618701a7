"""Starts read off the data's peaks for models with several lobes
(``roughbrdf.fitting.problem.lobe_starts``; ``docs/fitting.md``, "Multi-scale starts").

What is protected: a two-lobe fit recovers a narrow lobe plus a wide haze from synthetic data
of known parameters; on the glossy black paint, where the Sobol starts alone end in another
basin, the Beckmann pair finds and keeps both lobes; the starts do not hang on the last bits of
the data; models without lobes get none (their search is as before).
"""

from __future__ import annotations

import math
import warnings
from unittest import mock

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.fitting import ChannelData, ObjectiveSpec
from roughbrdf.fitting.problem.lobe_starts import estimate_lobes, lobe_starts
from roughbrdf.fitting.solvers.search import MultiStart

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's energy check alone takes ~40 s in plain Python")

#: a narrow Beckmann lobe with a haze 5 times wider holding 10 % of the weight, over a
#: substrate that stands above the noise floor (1e-3 of the 60 deg peak)
TRUTH = {"n": 1.5, "rho": 0.5, "alpha": 0.03, "alpha2": 0.15, "w2": 0.1}
BECKMANN_PAIR = "coated(lobes=2, distribution=beckmann)"
TRUTH_ONE = {"n": 1.5, "rho": 0.087, "alpha": 0.02}


def minidiff_grid() -> list[np.ndarray]:
    """The Mini-Diff geometry: incidences 0/20/40/60 deg, theta_r 0-75 deg by 1 deg, phi by 10
    deg (the pole once per incidence)."""
    g = np.radians(np.mgrid[0:61:20, 0:76:1, 0:351:10].reshape(3, -1))
    keep = ~((g[1] == 0) & (g[2] > 0))
    return [a[keep] for a in g]


def noisy(truth: rb.Model, seed: int) -> rb.Measurement:
    """``truth`` on the Mini-Diff grid with the noise of docs/fitting.md: 5 % log-normal plus
    a Gaussian floor of 1e-3 of the peak."""
    g = minidiff_grid()
    f = np.asarray(truth.brdf(*g), float)
    rng = np.random.default_rng(seed)
    x = f * np.exp(0.05 * rng.standard_normal(f.shape)) \
        + 1e-3 * f.max() * rng.standard_normal(f.shape)
    return rb.Measurement(*g, x[:, None], channels=["synthetic"])


def quiet_fit(model, meas, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # bound and energy notes: asserted on where they matter
        return rb.fit(model, meas, negative="drop", progress=False, **kw)


@pytest.mark.parametrize("dist", ["beckmann", "trowbridge-reitz"])
def test_both_scales_are_read_off_noise_free_data(dist):
    g = minidiff_grid()
    truth = rb.model("coated", lobes=2, distribution=dist, n=1.5, rho=0.05, alpha=0.02,
                     alpha2=0.15, w2=0.1)
    est = estimate_lobes(*g, truth.brdf(*g), dist)
    assert est.narrow == pytest.approx(0.02, rel=0.1)
    # Beckmann's haze is read within 5 %; GGX's narrow tail (t^-4) blurs its haze: 50 %
    assert est.haze == pytest.approx(0.15, rel=0.05 if dist == "beckmann" else 0.5)
    assert est.weight == pytest.approx(0.1, rel=0.1 if dist == "beckmann" else 0.5)
    # three significant digits: a start does not depend on the last bits
    for v in (est.narrow, est.haze, est.weight):
        assert float(f"{v:.3g}") == v


def test_no_lobes_no_data_starts():
    g = minidiff_grid()
    data = ChannelData.from_arrays(*g, rb.model("coated", **TRUTH_ONE).brdf(*g))
    for model in (rb.model("coated"), rb.model("lambertian"), rb.model("tr75")):
        spec = ObjectiveSpec(model, model.param_names[:1], [0.01], [1.0])
        assert lobe_starts(spec, data) == []
    # a two-lobe model with a width fixed: the starts would not be the data's
    pair = rb.model("coated", lobes=2)
    assert lobe_starts(ObjectiveSpec(pair, ["alpha", "w2"], [0.005, 0.0], [1.5, 1.0]),
                       data) == []


def test_starts_do_not_hang_on_the_last_bits():
    g = minidiff_grid()
    x = rb.model("coated", lobes=2, distribution="beckmann", **TRUTH).brdf(*g)
    z = np.random.default_rng(0).standard_normal(x.shape)
    pair = rb.model(BECKMANN_PAIR)
    spec = ObjectiveSpec(pair, ["alpha", "alpha2", "w2"], [0.005, 0.005, 0.0], [1.5, 1.5, 1.0])
    a = lobe_starts(spec, ChannelData.from_arrays(*g, x))
    b = lobe_starts(spec, ChannelData.from_arrays(*g, x * (1 + 1e-13 * z)))
    assert len(a) == 2 and all(np.array_equal(p, q) for p, q in zip(a, b, strict=True))


def test_three_lobes_start_a_wider_haze_with_the_same_share():
    g = minidiff_grid()
    truth = {"n": 1.5, "rho": 0.05, "alpha": 0.02, "alpha2": 0.15, "w2": 0.1}
    x = rb.model("coated", lobes=2, distribution="beckmann", **truth).brdf(*g)
    three = rb.model("coated", lobes=3, distribution="beckmann")
    names = ["alpha", "alpha2", "w2", "alpha3", "w3"]
    spec = ObjectiveSpec(three, names, [0.005, 0.005, 0.0, 0.005, 0.0],
                         [1.5, 1.5, 1.0, 1.5, 1.0])
    first, second = lobe_starts(spec, ChannelData.from_arrays(*g, x))
    a, a2, w2, a3, w3 = first.tolist()
    assert a == pytest.approx(truth["alpha"], rel=0.1)
    assert second[0] == pytest.approx(a / 2, rel=0.01)
    assert a2 == pytest.approx(truth["alpha2"], rel=0.1)
    assert w2 == pytest.approx(truth["w2"], rel=0.15)
    assert a3 == pytest.approx(4 * a2, rel=0.01) and w3 == w2


@pytest.fixture(scope="module")
def synthetic_fit():
    """The Beckmann pair fitted to one noisy set (rb.fit defaults)."""
    return quiet_fit(BECKMANN_PAIR, noisy(rb.model(BECKMANN_PAIR, **TRUTH), seed=0))[0]


def test_the_two_lobe_fit_recovers_both_lobes(synthetic_fit):
    fit = synthetic_fit
    assert fit.success and not fit.at_bound
    assert [s["origin"] for s in fit.starts].count("data") == 2
    for name, true in TRUTH.items():
        err = fit.stderr[name]
        assert math.isfinite(err), name
        # measured, seed 0: every parameter within 1.1 standard errors
        assert abs(fit.params[name] - true) <= 3 * err, (name, fit.params[name], err)


# --------------------------------------------------------------------------------------------
# the glossy black paint (issue 28's must-show)
# --------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def black(paints):
    """C2_Black 465 nm (the first channel, where the search before the data starts missed the
    haze with the default seed) fitted on 0/20/40 deg by one lobe and by the Beckmann pair,
    with and without the data starts, and the measured 60 deg samples (theta_r <= 75 deg,
    x > 0)."""
    meas = paints["C2_Black"]
    deg = np.round(np.degrees(meas.theta_i), 1)
    part = meas.subset(deg < 50)
    one = quiet_fit("coated", part, channel="465nm")
    two = quiet_fit(BECKMANN_PAIR, part, channel="465nm")
    with mock.patch.object(MultiStart, "data_starts", lambda self, data, k: []):
        sobol = quiet_fit(BECKMANN_PAIR, part, channel="465nm")  # the search before them
    held = (deg == 60.0) & (np.degrees(meas.theta_r) <= 75.5) & (meas.values[:, 0] > 0)
    return one, two, sobol, (meas.theta_i[held], meas.theta_r[held], meas.phi[held]), \
        meas.values[held, 0]


def _held_out(res, geometry, x) -> tuple[float, float]:
    """rms of ln x - ln f at 60 deg, and the peak ratio there (scripts/compare_losses.py)."""
    f = np.asarray(res.predict(*geometry), float)
    return float(np.sqrt(np.mean((np.log(x) - np.log(f)) ** 2))), float(f.max() / x.max())


def test_the_black_paint_keeps_both_lobes(black):
    one, two, _, geometry, x = black
    c = two[0]
    assert c.success and not c.at_bound
    # a narrow lobe and a haze about 3 times wider with a few per cent of the weight
    assert 0.01 < c.params["alpha"] < 0.03 and 2 * c.params["alpha"] < c.params["alpha2"] < 0.2
    assert 0.01 < c.params["w2"] < 0.1
    # the data need both: 0/20/40 deg fitted better than by one lobe (measured: cost 45.3
    # against 55.0; 39.6 against 49.1 at 525 nm, 48.9 against 62.6 at 630 nm)
    assert c.chi2 < 0.85 * one[0].chi2
    # and the unseen 60 deg peak is put 2-3 times nearer the data (measured 16.7x -> 6.2x)
    assert _held_out(two, geometry, x)[1] < 0.5 * _held_out(one, geometry, x)[1]


def test_sobol_starts_alone_miss_the_black_paints_haze(black):
    _, two, sobol, _, _ = black
    # every Sobol start of the search before the data starts ended in a basin with a second
    # lobe of alpha2 0.78-0.87 (measured): cost 69.9 against 45.3
    assert sobol[0].params["alpha2"] > 0.3
    assert sobol[0].chi2 > 1.3 * two[0].chi2


@pytest.mark.xfail(strict=True, reason=(
    "issue 28's must-show is not reached by starts alone: the Beckmann pair's narrow + haze "
    "predicts 60 deg with rms-log 0.482 against one GGX lobe's 0.480 (465 nm; 0.313/0.287, "
    "0.211/0.186 at 525/630 nm). The 60 deg data hold an in-plane streak out to theta_r = 75 deg "
    "(about 40 % of the peak) and, at 465 nm, values falling to 0 beyond 63 deg that no "
    "isotropic lobe centred on the mirror direction gives; a 2 deg aperture does not change "
    "it. Fitted to all four incidences, 60 deg included, no coated candidate (1-3 lobes, GGX "
    "or Beckmann) has a 60 deg rms-log below 0.471/0.285/0.182, above the mark 0.432/0.258/"
    "0.167 (scripts/sixty_degree_bound.py; docs/fitting.md, 'Multi-scale starts')"))
def test_black_paint_two_lobes_predict_60_deg_10_percent_better(black):
    one, two, _, geometry, x = black
    assert _held_out(two, geometry, x)[0] <= 0.9 * _held_out(one, geometry, x)[0]
