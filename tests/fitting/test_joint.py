"""Joint fits across channels: ``fit(..., joint=True, shared=...)``
(:mod:`roughbrdf.fitting.kinds.joint`).

Where the expected numbers come from:

* synthetic data generated here from the coated model (``docs/models.md`` §10.3) with one
  surface -- ``n = 1.5``, ``alpha = 0.15``, one lobe of weight 1 -- and one reflectance per channel
  (``rho = 0.1, 0.3, 0.6``), times ``1 + 0.02 N(0, 1)`` noise (seed 1): the truth is known;
* identities of least squares: the separate fits minimize the same sum of squares with more
  freedom (each channel its own ``n, alpha``), so the joint chi2 is not below their sum;
  a joint fit that shares nothing *is* the separate fits; a joint fit of one channel is the
  ordinary fit of that channel;
* the information a shared parameter gets from every channel: its joint (unscaled) variance is
  the inverse of a sum of the channels' profiled informations, each positive semi-definite, so
  with equal noise in the channels its standard error is below that of every separate fit;
* the bookkeeping of the module notes: unknowns = shared + per-channel x channels (+ one data
  scale per channel for relative data); ``cost`` is SciPy's ``0.5 sum r^2``.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.errors import ArgumentError
from roughbrdf.fitting.choice.compare import information

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

SHARED_TRUE = {"n": 1.5, "alpha": 0.15}
RHO_TRUE = {"b": 0.1, "g": 0.3, "r": 0.6}
STARTS = 2



def fit(*args, **kwargs) -> rb.FitResult:
    """``rb.fit`` with the relative loss unless a test says otherwise: these data carry
    ``1 + 0.02 N(0, 1)`` noise, which the ratio residual models (a log-type loss, the default
    robust one, shifts rho by about 0.5 %: several of the joint fit's standard errors)."""
    kwargs.setdefault("loss", "relative")
    return rb.fit(*args, **kwargs)

def _grid() -> list[np.ndarray]:
    """theta_i 10, 35, 60 deg; theta_r 0-80 deg by 8; phi 0-180 by 45: 165 directions."""
    return list(np.radians(np.mgrid[10:61:25, 0:81:8, 0:181:45].reshape(3, -1)))


def _values() -> np.ndarray:
    g = _grid()
    clean = np.stack([rb.model("coated", rho=r, **SHARED_TRUE).brdf(*g)
                      for r in RHO_TRUE.values()], axis=1)
    rng = np.random.default_rng(1)
    return clean * (1 + 0.02 * rng.standard_normal(clean.shape))


@pytest.fixture(scope="module")
def meas() -> rb.Measurement:
    return rb.Measurement(*_grid(), _values(), channels=list(RHO_TRUE))


@pytest.fixture(scope="module")
def joint(meas):
    return fit("coated", meas, joint=True, starts=STARTS, progress=False)


@pytest.fixture(scope="module")
def separate(meas):
    return fit("coated", meas, starts=STARTS, progress=False)


def test_joint_recovers_the_shared_parameters_and_each_reflectance(joint):
    assert joint.success
    for c in joint.channels:
        for name, true in SHARED_TRUE.items():
            assert c.params[name] == joint.channels[0].params[name]  # one value for all
            assert abs(c.params[name] - true) <= 4 * c.stderr[name], (c.channel, name)
        assert abs(c.params["rho"] - RHO_TRUE[c.channel]) <= 4 * c.stderr["rho"], c.channel
        assert "joint fit of 3 channels, shared: n, alpha" in c.message


def test_stderr_finite_and_shared_ones_equal_across_channels(joint):
    for c in joint.channels:
        for name in c.free:
            assert math.isfinite(c.stderr[name]) and c.stderr[name] > 0, (c.channel, name)
        for name in SHARED_TRUE:
            assert c.stderr[name] == joint.channels[0].stderr[name]
    rho_sd = [c.stderr["rho"] for c in joint.channels]
    assert len(set(rho_sd)) == 3  # each reflectance its own


def test_shared_parameters_are_better_determined_than_in_separate_fits(joint, separate):
    for name in SHARED_TRUE:
        sd = joint.channels[0].stderr[name]
        assert all(sd < c.stderr[name] for c in separate.channels), name


def test_covar_and_correl_are_the_joint_ones(meas):
    """Each channel's covar is its block of the joint covariance: its diagonal gives the
    reported stderr (the data scale's too, for relative data) and correl is covar
    normalized."""
    rel = rb.Measurement(*_grid(), meas.values / meas.values[0], channels=list(RHO_TRUE),
                         quantity="relative")
    # (the lobe has weight 1: no scale of its own that the free data scale would duplicate)
    res = fit("coated", rel, joint=True, starts=STARTS, progress=False)
    for c in res.channels:
        sd = np.sqrt(np.diag(c.covar))
        np.testing.assert_allclose(sd, [c.stderr[n] for n in c.free] + [c.scale_stderr],
                                   rtol=1e-12)
        names = [*c.free, "scale"]
        for i, a in enumerate(names):
            for j, b in enumerate(names):
                if i != j:
                    assert c.correl[a][b] == pytest.approx(c.covar[i, j] / (sd[i] * sd[j]),
                                                           rel=1e-9, abs=1e-12)


def test_joint_chi2_is_not_below_the_separate_fits(joint, separate):
    j = joint.options["joint"]
    sep = sum(c.chi2 for c in separate.channels)
    assert j["chi2"] == pytest.approx(sum(c.chi2 for c in joint.channels), rel=1e-12)
    assert j["chi2"] >= sep * (1 - 1e-6)
    # SciPy's cost is half the sum of squares
    assert j["cost"] == pytest.approx(0.5 * j["chi2"], rel=1e-9)


def test_sharing_nothing_is_the_separate_fits(meas, separate):
    res = fit("coated", meas, joint=True, shared=[], starts=STARTS, progress=False)
    assert res.options["joint"]["shared"] == [] and res.options["joint"]["n_varys"] == 9
    assert res.options["joint"]["chi2"] == pytest.approx(
        sum(c.chi2 for c in separate.channels), rel=1e-6)
    for a, b in zip(res.channels, separate.channels, strict=True):
        for name in a.free:
            assert a.params[name] == pytest.approx(b.params[name], rel=1e-5), (a.channel, name)


@pytest.mark.parametrize("loss", ["relative", "robust"])
def test_joint_fit_of_one_channel_is_the_ordinary_fit(meas, separate, loss):
    one = fit("coated", meas, joint=True, channel="g", starts=STARTS, loss=loss, progress=False)
    alone = separate["g"] if loss == "relative" else \
        fit("coated", meas, channel="g", starts=STARTS, loss=loss, progress=False)[0]
    assert one.options["joint"]["n_varys"] == alone.n_varys == 3
    assert one.channels[0].chi2 == pytest.approx(alone.chi2, rel=1e-6)
    for name in alone.free:
        assert one.channels[0].params[name] == pytest.approx(alone.params[name], rel=1e-5)
        # the same sandwich (the robust loss's curvature in its bread): the same errors
        assert one.channels[0].stderr[name] == pytest.approx(alone.stderr[name], rel=1e-3)


@pytest.mark.parametrize("shared, fix, n_varys", [
    (None, (), 2 + 3 * 1),            # n, alpha shared; rho per channel
    (["alpha"], (), 1 + 3 * 2),       # n, rho per channel
    (["alpha", "n"], (), 5),          # any order: stored in the model's order
    (None, ("n",), 1 + 3 * 1),
])
def test_n_varys_bookkeeping(meas, shared, fix, n_varys):
    res = fit("coated", meas, joint=True, shared=shared, fix=fix, starts=1, progress=False)
    j = res.options["joint"]
    expected_shared = [n for n in ("n", "alpha") if n not in fix and (
        shared is None or n in shared)]
    assert j["shared"] == expected_shared
    assert j["n_varys"] == n_varys and j["n_points"] == 3 * meas.n_samples
    assert all(c.n_varys == n_varys for c in res.channels)
    k, n, aic, bic = information(res)
    assert (k, n) == (n_varys, 3 * meas.n_samples)
    # the joint summary: one residual variance per channel, the definition of
    # compare.information (so both give the same numbers for the same fit)
    like = sum(c.n_points * math.log(c.chi2 / c.n_points) for c in res.channels)
    assert j["aic"] == pytest.approx(like + 2 * n_varys, rel=1e-12) == aic
    assert j["bic"] == pytest.approx(like + math.log(n) * n_varys, rel=1e-12) == bic
    # each channel's own figures with the joint count of unknowns
    for c in res.channels:
        own = c.n_points * math.log(c.chi2 / c.n_points)
        assert c.aic == pytest.approx(own + 2 * n_varys, rel=1e-12)
        assert c.bic == pytest.approx(own + math.log(n) * n_varys, rel=1e-12)


def test_relative_data_add_one_scale_per_channel(meas):
    rel = rb.Measurement(*_grid(), meas.values / meas.values[0], channels=list(RHO_TRUE),
                         quantity="relative")
    res = fit("coated", rel, joint=True, starts=1, progress=False)
    assert res.options["joint"]["n_varys"] == 2 + 3 + 3
    assert all(c.free_scale and c.scale > 0 for c in res.channels)


def test_starts_are_counted_once_for_all_channels(meas, separate):
    res = fit("coated", meas, joint=True, starts=3, progress=False)
    for c in res.channels:
        origins = [s["origin"] for s in c.starts if s["stage"] != "full"]
        assert origins == ["model", "sobol", "sobol"]
    assert res.options["starts"] == 3
    # separate fits: `starts` per channel, a warm start from the previous channel after the
    # first
    assert [[s["origin"] for s in c.starts if s["stage"] != "full"]
            for c in separate.channels] == [["model", "sobol"],
                                            ["model", "previous channel"],
                                            ["model", "previous channel"]]


def test_subsampled_exploration_reaches_the_full_optimum(meas, joint):
    res = fit("coated", meas, joint=True, starts=3, subsample=60, progress=False)
    stages = [s["stage"] for s in res.channels[0].starts]
    assert stages.count("explore") == 3 and "full" in stages
    assert res.options["joint"]["chi2"] == pytest.approx(joint.options["joint"]["chi2"],
                                                         rel=1e-6)
    for name in SHARED_TRUE:
        assert res.channels[0].params[name] == pytest.approx(joint.channels[0].params[name],
                                                             rel=1e-4)


def test_report_and_json(joint):
    text = joint.report()
    assert "channels           = 3 (joint fit, shared: n, alpha; 5 unknowns in all" in text
    d = json.loads(joint.to_json())
    assert d["options"]["joint"]["shared"] == ["n", "alpha"]
    assert d["options"]["joint"]["n_varys"] == 5
    assert [ch["params"]["alpha"] for ch in d["channels"]] == [
        joint.channels[0].params["alpha"]] * 3
    assert fit("coated", rb.Measurement(*_grid(), _values()[:, 0]), starts=1,
                  progress=False).options["joint"] is None  # a separate fit


def test_shared_without_joint_is_refused(meas):
    with pytest.raises(ArgumentError) as info:
        fit("coated", meas, shared=["alpha"], starts=1, progress=False)
    assert info.value.argument == "shared" and "joint" in str(info.value)


@pytest.mark.parametrize("shared, bad", [(["bogus"], "bogus"), (["alpha", "e"], "e"),
                                         ("bogus", "bogus")])
def test_unknown_shared_name_is_refused(meas, shared, bad):
    with pytest.raises(ArgumentError) as info:
        fit("coated", meas, joint=True, shared=shared, starts=1, progress=False)
    assert info.value.argument == "shared" and info.value.value == bad
    assert "free: n, rho, alpha" in str(info.value)


def test_a_fixed_parameter_cannot_be_shared(meas):
    with pytest.raises(ArgumentError) as info:
        fit("coated", meas, joint=True, shared=["n"], fix=["n"], starts=1, progress=False)
    assert info.value.argument == "shared" and "free: rho, alpha" in str(info.value)


@pytest.mark.parametrize("bad", ["yes", 1, None])
def test_joint_must_be_a_bool(meas, bad):
    with pytest.raises(ArgumentError) as info:
        fit("coated", meas, joint=bad, starts=1, progress=False)
    assert info.value.argument == "joint"
