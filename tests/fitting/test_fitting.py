"""rb.fit on synthetic data: parameter recovery, the closed-form scale, options and errors.

The truths here gain energy (TR75 Table 1's cement: albedo 1.46 at 85 deg, 5.9 at 89 deg; TR75
has no shadowing), and these tests check that a fit recovers them: every fit runs with
``energy_constraint=False`` (:func:`fit`). The constraint has its own tests
(``tests/fitting/test_energy_constraint.py``).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf import geometry
from roughbrdf.fitting import ChannelData, Objective, ObjectiveSpec
from roughbrdf.instrument import (
    APERTURE_POINTS,
    Aperture,
    aperture_average,
    aperture_directions,
    aperture_stencil,
)
from roughbrdf.measurement import Measurement

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")


def fit(*args, **kwargs) -> rb.FitResult:
    """``rb.fit`` without the energy constraint (module notes), unless a test sets it."""
    kwargs.setdefault("energy_constraint", False)
    return rb.fit(*args, **kwargs)


TR75_TRUE = {"e": 0.68, "n": 1.00, "k": 0.9, "rho_L": 0.33}  # TR75 Table 1, cement
TR75_START = {"e": 0.3, "n": 1.5, "k": 0.1, "rho_L": 0.5}
TS67_TRUE = {"g": 2.0, "c": 0.08, "rho_d": 0.3}
TS67_START = {"g": 0.7, "c": 0.04, "rho_d": 0.6}


def tr75_design() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """TR75's measurement design (docs/models.md §3.9), 5 azimuths: 6 x (5 x 5 + 1) x 2 = 312."""
    rows = []
    for gam in (90.0, 0.0):
        for b in (0, 15, 30, 45, 60, 70):
            for el in (15, 30, 45, 60, 75, 90):
                for psi in ((0, 45, 90, 135, 180) if el < 90 else (0,)):
                    rows.append((b, el, psi, gam))
    a = np.radians(np.array(rows, dtype=float))
    ti, tr, ph = geometry.from_tr75(a[:, 0], a[:, 1], a[:, 2])
    return ti, np.clip(tr, 0, math.pi / 2), ph, a[:, 3]


def tr75_relative(seed: int, noise: float = 0.1) -> Measurement:
    ti, tr, ph, gam = tr75_design()
    f = rb.model("trowbridge-reitz-1975", **TR75_TRUE).bridf(ti, tr, ph, polarization=gam)
    rng = np.random.default_rng(seed)
    x = f * (1 + noise * rng.standard_normal(f.size))
    return Measurement(ti, tr, ph, x / x[0], quantity="relative", polarization=gam,
                       meta={"relative_to": "bridf", "file": f"synthetic-tr75-{seed}"})


def ts67_grid() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t_i, t_r, p = np.meshgrid(np.radians([10, 30, 50, 70]), np.radians(np.arange(0, 86, 5)),
                              np.radians([0, 45, 90, 135, 180]), indexing="ij")
    return t_i.ravel(), t_r.ravel(), p.ravel()


def ts67_absolute(seed: int, noise: float = 0.1, lognormal: bool = False) -> Measurement:
    ti, tr, ph = ts67_grid()
    f = rb.model("torrance-sparrow-1967", n=None, k=None, **TS67_TRUE).brdf(ti, tr, ph)
    rng = np.random.default_rng(seed)
    eps = noise * rng.standard_normal(f.size)
    return Measurement(ti, tr, ph, f * (np.exp(eps) if lognormal else 1 + eps), quantity="brdf")


def within(res: rb.FitResult, truth: dict[str, float], k: float = 3.0) -> bool:
    c = res.channels[0]
    return all(abs(c.params[n] - v) <= k * c.stderr[n] for n, v in truth.items())


# ---------------------------------------------------------------------------------------------
# recovery: 20 seeds per model, each a fresh noise draw (10 % multiplicative)
# ---------------------------------------------------------------------------------------------
N_SEEDS = 20  # >= 95 % of 20 seeds means at most one miss


def test_tr75_recovery_within_3_stderr_in_95_percent_of_seeds():
    """TR75 (+ its Lambertian rho_L): relative BRIDF, TR75 design (312 samples, both
    polarizations), free scale; runs 20 seeds."""
    hits = 0
    for seed in range(N_SEEDS):
        res = fit(rb.model("trowbridge-reitz-1975", **TR75_START), tr75_relative(seed),
                     starts=3, progress=False)
        assert res.success
        assert 0.07 < res.sigma < 0.13  # the noise level
        hits += within(res, TR75_TRUE)
    assert hits >= math.ceil(0.95 * N_SEEDS), f"{hits}/{N_SEEDS} seeds within 3 stderr"


def test_ts67_recovery_within_3_stderr_in_95_percent_of_seeds():
    """TS67 absolute form (F = 1): BRDF at 4 incidences x 18 zeniths x 5 azimuths (360
    samples) with 10 % log-normal noise, log loss (its maximum-likelihood match); runs 20 seeds.

    (With ``x = f (1 + 0.1 eps)`` the relative loss is biased by ~sigma^2 = 1 % in a scale
    parameter such as rho_d, about 2 stderr here; see ``test_relative_loss_scale_bias``.)
    """
    hits = 0
    for seed in range(N_SEEDS):
        m0 = rb.model("torrance-sparrow-1967", n=None, k=None, **TS67_START)
        res = fit(m0, ts67_absolute(seed, lognormal=True), loss="log", starts=3,
                     progress=False)
        assert res.success
        assert res.params["n"] is None  # switched-off parts are not fitted
        hits += within(res, TS67_TRUE)
    assert hits >= math.ceil(0.95 * N_SEEDS), f"{hits}/{N_SEEDS} seeds within 3 stderr"


def test_relative_loss_scale_bias():
    """Documented behaviour: with multiplicative noise x = f (1 + s eps), minimizing the relative
    residual (x - f)/f overestimates a scale parameter by about s^2 (here 1 %), averaged over
    seeds; the log loss on log-normal noise does not."""
    rel = [fit(rb.model("torrance-sparrow-1967", n=None, k=None, **TS67_TRUE),
                  ts67_absolute(seed), starts=1, progress=False).params["rho_d"]
           for seed in range(8)]
    log = [fit(rb.model("torrance-sparrow-1967", n=None, k=None, **TS67_TRUE),
                  ts67_absolute(seed, lognormal=True), loss="log", starts=1,
                  progress=False).params["rho_d"] for seed in range(8)]
    assert np.mean(rel) / 0.3 - 1 == pytest.approx(0.01, abs=0.005)
    assert abs(np.mean(log) / 0.3 - 1) < 0.004


def test_noise_free_data_recovered_exactly_for_every_loss():
    ti, tr, ph = ts67_grid()
    truth = rb.model("torrance-sparrow-1967", n=None, k=None, **TS67_TRUE)
    meas = Measurement(ti, tr, ph, truth.brdf(ti, tr, ph), quantity="brdf")
    for loss in ("relative", "log", "absolute"):
        res = fit(rb.model("torrance-sparrow-1967", n=None, k=None, **TS67_START), meas,
                     loss=loss, starts=2, progress=False)
        for name, v in TS67_TRUE.items():
            assert res.params[name] == pytest.approx(v, rel=1e-6), (loss, name)
        assert res.sigma < 1e-7 and res.rms_log < 1e-7


def test_relative_scale_fit_equals_absolute_fit_when_scale_known():
    """A relative copy (x / 3.7) of absolute TR75 data, fitted with the known scale 3.7, gives
    the absolute fit, for each loss."""
    ti, tr, ph, gam = tr75_design()
    f = rb.model("trowbridge-reitz-1975", **TR75_TRUE).bridf(ti, tr, ph, polarization=gam)
    x = f * np.exp(0.1 * np.random.default_rng(5).standard_normal(f.size))
    abs_meas = Measurement(ti, tr, ph, x, quantity="bridf", polarization=gam)
    rel_meas = Measurement(ti, tr, ph, x / 3.7, quantity="relative", polarization=gam,
                           meta={"relative_to": "bridf"})
    for loss in ("relative", "log", "absolute"):
        m0 = rb.model("trowbridge-reitz-1975", **TR75_START)
        a = fit(m0, abs_meas, loss=loss, starts=3, progress=False)
        r = fit(m0, rel_meas, loss=loss, scale=3.7, starts=3, progress=False)
        for name in TR75_TRUE:
            assert r.params[name] == pytest.approx(a.params[name], rel=1e-5), (loss, name)
            assert r.stderr[name] == pytest.approx(a.stderr[name], rel=1e-3), (loss, name)
        assert r.sigma == pytest.approx(a.sigma, rel=1e-6)
        assert r.channels[0].n_varys == a.channels[0].n_varys == 4
        assert "scale K" in r.report() and "(given)" in r.report()


def test_free_scale_recovers_the_scale_when_the_model_scale_is_fixed():
    """TS67's rho_d is an overall scale: with relative data it is fixed, and the closed-form K
    recovers the factor (3.7) while g and c equal the absolute fit's."""
    abs_meas = ts67_absolute(seed=5)
    rel_meas = Measurement(abs_meas.theta_i, abs_meas.theta_r, abs_meas.phi,
                           abs_meas.values / 3.7, quantity="relative",
                           meta={"relative_to": "brdf"})
    m0 = rb.model("torrance-sparrow-1967", n=None, k=None, **TS67_START)
    a = fit(m0, abs_meas, starts=3, progress=False)
    r = fit(m0.with_params(rho_d=a.params["rho_d"]), rel_meas, fix=["rho_d"], starts=3,
               progress=False)
    for name in ("g", "c"):
        assert r.params[name] == pytest.approx(a.params[name], rel=1e-5), name
    assert r.channels[0].scale == pytest.approx(3.7, rel=1e-6)
    assert r.sigma == pytest.approx(a.sigma, rel=1e-6)
    # left free, rho_d and K are one degree of freedom: the covariance says so
    d = fit(m0, rel_meas, starts=2, progress=False)
    assert "covariance not estimated" in d.message and math.isnan(d.stderr["g"])


def test_relative_scale_is_tr75_reading_a():
    """For the relative loss K = sum(X/f)/sum((X/f)^2) minimizes TR75's sigma
    (docs/models.md §3.9)."""
    meas = tr75_relative(seed=3)
    res = fit(rb.model("trowbridge-reitz-1975", **TR75_START), meas, starts=2,
                 progress=False)
    c = res.channels[0]
    f = res.model.bridf(meas.theta_i, meas.theta_r, meas.phi, polarization=meas.polarization)
    q = meas.values[:, 0] / f
    k = q.sum() / (q * q).sum()
    assert c.scale == pytest.approx(k, rel=1e-10)
    sig = lambda kk: np.sqrt(np.mean((kk * q - 1) ** 2))  # noqa: E731
    assert c.sigma == pytest.approx(sig(k), rel=1e-10)
    assert sig(k) < min(sig(k * 1.01), sig(k * 0.99))


def test_relative_to_selects_the_model_quantity():
    """Relative BRIDF data fitted as if proportional to the BRDF give a worse fit."""
    meas = tr75_relative(seed=1, noise=0.02)
    good = fit("trowbridge-reitz-1975", meas, starts=2, progress=False)
    bad = fit("trowbridge-reitz-1975", meas, relative_to="brdf", starts=2, progress=False)
    assert good.compared == "bridf" and bad.compared == "brdf"
    assert good.sigma < 0.03 < bad.sigma
    meas.meta.pop("relative_to")
    assert fit("trowbridge-reitz-1975", meas, starts=1, progress=False).compared == "brdf"


def test_brdf_cos_data_compared_with_bridf():
    ti, tr, ph = ts67_grid()
    m = rb.model("trowbridge-reitz-1975", e=0.4, n=1.5, k=0.0, rho_L=0.2)
    meas = Measurement(ti, tr, ph, m.bridf(ti, tr, ph), quantity="brdf_cos")
    res = fit(rb.model("trowbridge-reitz-1975"), meas, starts=2, progress=False)
    assert res.compared == "bridf"
    assert res.params["e"] == pytest.approx(0.4, rel=1e-5)


# ---------------------------------------------------------------------------------------------
# Jacobian, covariance, multistart
# ---------------------------------------------------------------------------------------------
def test_jacobian_matches_central_differences():
    meas = tr75_relative(seed=0)
    m = rb.model("trowbridge-reitz-1975")
    free = m.param_names
    lo = np.array([p.bounds[0] for p in m.parameters])
    hi = np.array([p.bounds[1] for p in m.parameters])
    gam = meas.polarization
    obj = Objective(ObjectiveSpec(m, free, lo, hi, loss="relative", quantity="bridf",
                                  free_scale=True),
                    ChannelData.from_arrays(meas.theta_i, meas.theta_r, meas.phi,
                                            meas.values[:, 0], polarization=gam))
    theta = np.array([0.5, 1.3, 0.7, 0.2])
    jac = obj.jac(theta)
    for j in range(theta.size):
        h = 1e-6
        tp, tm = theta.copy(), theta.copy()
        tp[j] += h
        tm[j] -= h
        col = (obj.fun(tp) - obj.fun(tm)) / (2 * h)
        assert np.allclose(jac[:, j], col, rtol=1e-4, atol=1e-6 * np.abs(col).max())
    # one compiled evaluation per column plus one for the residual: never a loop over samples
    obj.reset()
    obj.jac(theta)
    assert obj.nfev == theta.size + 1


def test_stderr_matches_scatter_over_seeds():
    """The covariance (scaled by the residual variance) predicts the seed-to-seed scatter."""
    fits = [fit(rb.model("torrance-sparrow-1967", n=None, k=None, **TS67_START),
                   ts67_absolute(seed), starts=1, progress=False) for seed in range(12)]
    for name in TS67_TRUE:
        vals = np.array([f.params[name] for f in fits])
        se = np.mean([f.stderr[name] for f in fits])
        assert 0.5 < vals.std(ddof=1) / se < 2.0, name


def test_multistart_finds_the_global_minimum_from_a_bad_start():
    """A start at the edge of the bounds, one local fit vs the Sobol multistart."""
    ti, tr, ph = ts67_grid()
    truth = rb.model("torrance-sparrow-1967", n=None, k=None, **TS67_TRUE)
    meas = Measurement(ti, tr, ph, truth.brdf(ti, tr, ph), quantity="brdf")
    bad = rb.model("torrance-sparrow-1967", n=None, k=None, g=45.0, c=0.45, rho_d=0.001)
    multi = fit(bad, meas, starts=6, progress=False)
    assert multi.sigma < 1e-6
    assert multi.params["c"] == pytest.approx(0.08, rel=1e-6)
    single = fit(bad, meas, starts=1, progress=False)
    assert single.sigma >= multi.sigma


def test_subsampled_exploration_reaches_the_full_data_optimum():
    meas = tr75_relative(seed=7)
    full = fit("trowbridge-reitz-1975", meas, starts=4, subsample=None, progress=False)
    sub = fit("trowbridge-reitz-1975", meas, starts=4, subsample=100, progress=False)
    assert sub.sigma == pytest.approx(full.sigma, rel=1e-7)
    assert any(s["stage"] == "full" for s in sub.channels[0].starts)


def test_seed_makes_fits_reproducible():
    meas = tr75_relative(seed=2)
    a = fit("trowbridge-reitz-1975", meas, starts=3, subsample=100, seed=11, progress=False)
    b = fit("trowbridge-reitz-1975", meas, starts=3, subsample=100, seed=11, progress=False)
    assert a.params == b.params


# ---------------------------------------------------------------------------------------------
# options
# ---------------------------------------------------------------------------------------------
def test_fix_keeps_parameters_and_reports_them():
    meas = tr75_relative(seed=4)
    res = fit(rb.model("trowbridge-reitz-1975", n=1.0), meas, fix=["n"], starts=2,
                 progress=False)
    assert res.params["n"] == 1.0 and res.stderr["n"] is None
    assert res.channels[0].free == ["e", "k", "rho_L"]
    assert "n    " in res.report() and "(fixed)" in res.report()
    assert res.to_dict()["options"]["fix"] == ["n"]


def test_bounds_override_and_sum_models():
    meas = tr75_relative(seed=4)
    m = rb.model("trowbridge-reitz-1975", rho_L=0.0) + rb.model("lambertian", rho=0.3)
    res = fit(m, meas, fix=["tr75_rho_L"], bounds={"tr75_e": (0.3, 1.2)}, starts=2,
                 progress=False)
    assert res.model_name == "trowbridge-reitz-1975+lambertian"
    assert res.channels[0].bounds["tr75_e"] == (0.3, 1.2)
    assert res.params["lambertian_rho"] == pytest.approx(0.33, abs=0.1)
    assert res.params["tr75_rho_L"] == 0.0


def test_weights_and_zero_weights():
    meas = ts67_absolute(seed=0)
    w = np.ones(meas.n_samples)
    w[:10] = 0.0
    res = fit(rb.model("torrance-sparrow-1967", n=None, k=None), meas, weights=w, starts=1,
                 progress=False)
    c = res.channels[0]
    assert c.n_points == meas.n_samples - 10 and c.excluded["zero_weight"] == 10
    with pytest.raises(ValueError, match="finite and >= 0"):
        fit("ts67", meas, weights=-w, progress=False)
    with pytest.raises(ValueError, match="no uncertainty"):
        fit("ts67", meas, weights="uncertainty", progress=False)


def test_uncertainty_weights():
    meas = ts67_absolute(seed=0)
    meas.uncertainty = 0.1 * np.abs(meas.values)
    res = fit(rb.model("torrance-sparrow-1967", n=None, k=None, **TS67_START), meas,
                 weights="uncertainty", loss="absolute", starts=2, progress=False)
    assert res.channels[0].redchi == pytest.approx(1.0, abs=0.35)  # chi2 per dof ~ 1


def test_nonfinite_and_negative_handling_is_explicit():
    meas = ts67_absolute(seed=0)
    v = meas.values.copy()
    v[3, 0] = np.nan
    v[7, 0] = -0.01
    bad = Measurement(meas.theta_i, meas.theta_r, meas.phi, v, quantity="brdf",
                      meta={"file": "bad.csv"})
    with pytest.raises(ValueError, match=r"bad\.csv.*1 non-finite value.*sample\(s\) 3.*"
                                         r"nonfinite='drop'"):
        fit("ts67", bad, progress=False)
    keep = fit("ts67", bad, nonfinite="drop", starts=1, progress=False).channels[0]
    assert keep.excluded["nonfinite"] == 1 and keep.n_points == meas.n_samples - 1
    drop = fit("ts67", bad, nonfinite="drop", negative="drop", starts=1,
                  progress=False).channels[0]
    assert drop.excluded["negative"] == 1 and drop.n_points == meas.n_samples - 2
    clip = fit("ts67", bad, nonfinite="drop", negative="clip", starts=1,
                  progress=False).channels[0]
    assert clip.excluded["clipped"] == 1 and clip.data.min() == 0.0
    with pytest.raises(ValueError, match="log loss needs positive values.*negative='drop'"):
        fit("ts67", bad, nonfinite="drop", loss="log", negative="keep", progress=False)
    # the default negative="auto" drops them for a log-type loss, and counts them
    auto = fit("ts67", bad, nonfinite="drop", loss="log", starts=1, progress=False).channels[0]
    assert auto.excluded["negative"] == 1 and auto.n_points == meas.n_samples - 2
    logclip = fit("ts67", bad, nonfinite="drop", negative="clip", loss="log", starts=1,
                     progress=False).channels[0]
    assert logclip.data.min() > 0


def test_model_nonfinite_samples_are_left_out_and_counted():
    """The unshadowed TR75 BRDF is +inf at theta_r = 90 deg: such samples cannot be fitted."""
    ti, tr, ph = ts67_grid()
    tr = tr.copy()
    tr[:4] = math.pi / 2
    m = rb.model("trowbridge-reitz-1975", e=0.4)
    vals = np.where(tr < math.pi / 2, m.brdf(ti, np.minimum(tr, 1.5), ph), 1.0)
    res = fit("trowbridge-reitz-1975", Measurement(ti, tr, ph, vals), starts=1,
                 progress=False)
    assert res.channels[0].excluded["model_domain"] == 4
    assert res.params["e"] == pytest.approx(0.4, rel=1e-5)


# ---------------------------------------------------------------------------------------------
# results: several channels, JSON, report, plot, save
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def two_channel_fit() -> rb.FitResult:
    ti, tr, ph = ts67_grid()
    a = rb.model("torrance-sparrow-1967", n=None, k=None, **TS67_TRUE)
    b = a.with_params(c=0.05, rho_d=0.5)
    vals = np.column_stack([a.brdf(ti, tr, ph), b.brdf(ti, tr, ph)])
    meas = Measurement(ti, tr, ph, vals, channels=["blue", "red"], quantity="brdf",
                       meta={"file": "two.csv", "sample": "two"})
    return fit(rb.model("torrance-sparrow-1967", n=None, k=None), meas, starts=2,
                  progress=False)


def test_per_channel_results(two_channel_fit):
    res = two_channel_fit
    assert len(res) == 2 and [c.channel for c in res] == ["blue", "red"]
    assert res["blue"].params["c"] == pytest.approx(0.08, rel=1e-6)
    assert res["red"].params["c"] == pytest.approx(0.05, rel=1e-6)
    assert res[1] is res["red"] and res.success
    with pytest.raises(AttributeError, match=r"2 channels.*res\[channel\]\.params"):
        _ = res.params
    with pytest.raises(KeyError):
        res["green"]


def test_json_schema_and_report(two_channel_fit):
    d = json.loads(two_channel_fit.to_json())
    assert {"model", "file", "loss", "channels"} <= set(d)
    assert d["model"] == "torrance-sparrow-1967" and d["file"] == "two.csv"
    for ch in d["channels"]:
        assert {"channel", "params", "stderr", "success", "metrics"} <= set(ch)
        assert {"sigma", "rms_log", "chi2", "aic", "bic", "n_points"} <= set(ch["metrics"])
        assert ch["params"]["n"] is None and ch["stderr"]["n"] is None
    text = two_channel_fit.report()
    for key in ("[[Channel blue]]", "[[Channel red]]", "TR75 sigma", "Akaike", "[[Variables]]",
                "+/-"):
        assert key in text


def test_channel_selection(two_channel_fit):
    meas = two_channel_fit.measurement
    res = fit(rb.model("torrance-sparrow-1967", n=None, k=None), meas, channel="red",
                 starts=1, progress=False)
    assert [c.channel for c in res] == ["red"]
    assert res.params["rho_d"] == pytest.approx(0.5, rel=1e-6)


def test_plot_and_save(two_channel_fit, tmp_path):
    import matplotlib.pyplot as plt

    fig, (a1, a2) = two_channel_fit.plot("red")
    assert a1.get_title() and a2.get_title()
    plt.close(fig)
    written = two_channel_fit.save(tmp_path / "out")
    names = sorted(p.name for p in written)
    assert names == ["fit.json", "fit_blue.png", "fit_red.png", "report.txt"]
    # an earlier run's results are replaced only when asked; the new set
    # replaces the old one exactly (the stale PNGs go)
    two_channel_fit.save(tmp_path / "out", plots=False, overwrite=True)
    assert sorted(p.name for p in (tmp_path / "out").iterdir()
                  if not p.name.startswith(".")) == ["fit.json", "report.txt"]
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "report.txt").write_text("my notes")
    with pytest.raises(FileExistsError, match="report.txt"):
        two_channel_fit.save(tmp_path / "mine", plots=False)
    assert (tmp_path / "mine" / "report.txt").read_text() == "my notes"
    assert not (tmp_path / "mine" / "fit.json").exists()  # nothing written before the check
    # a file roughbrdf did not write is never replaced, not even with overwrite=True
    with pytest.raises(FileExistsError, match=r"report\.txt.*not written by roughbrdf"):
        two_channel_fit.save(tmp_path / "mine", plots=False, overwrite=True)
    assert (tmp_path / "mine" / "report.txt").read_text() == "my notes"


def test_relative_plot_data_on_model_scale():
    res = fit("trowbridge-reitz-1975", tr75_relative(seed=0), starts=1, progress=False)
    model, meas = res.plot_data(0)
    assert meas.quantity == "bridf"
    f = model.bridf(meas.theta_i, meas.theta_r, meas.phi, polarization=meas.polarization)
    assert np.sqrt(np.mean((meas.values[:, 0] / f - 1) ** 2)) == pytest.approx(res.sigma)


def test_progress_bar_can_be_switched_on(capsys):
    fit("ts67", ts67_absolute(seed=0), starts=2, progress=True)
    assert "fit torrance-sparrow-1967" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------
# instrument aperture
# ---------------------------------------------------------------------------------------------
def _cap_average_reference(fun, theta_r: float, phi: float, a: float) -> float:
    """Average of ``fun(w)`` over the uniform cap of half-angle ``a`` about w(theta_r, phi), by a
    product Gauss-Legendre (40 nodes in u = (1 - cos beta)/(1 - cos a)) x 64-azimuth rule:
    exact for polynomials of direction of degree < 40."""
    u, wu = np.polynomial.legendre.leggauss(40)
    u, wu = 0.5 * (u + 1.0), 0.5 * wu
    beta = np.arccos(1.0 - u * (1.0 - math.cos(a)))
    psi = 2 * math.pi * np.arange(64) / 64
    _, n = geometry.unit_vectors(0.0, theta_r, phi)
    e1 = np.array([math.cos(theta_r) * math.cos(phi), math.cos(theta_r) * math.sin(phi),
                   -math.sin(theta_r)])
    e2 = np.array([-math.sin(phi), math.cos(phi), 0.0])
    b, p = np.meshgrid(beta, psi, indexing="ij")
    w = (np.cos(b)[..., None] * n + np.sin(b)[..., None]
         * (np.cos(p)[..., None] * e1 + np.sin(p)[..., None] * e2))
    return float(np.sum(wu[:, None] * fun(w)) / 64)


def _poly(degree: int, seed: int):
    """A random polynomial of the direction components x, y, z of exactly this degree."""
    c = np.random.default_rng(seed).standard_normal((degree + 1,) * 3)

    def fun(w):
        x, y, z = w[..., 0], w[..., 1], w[..., 2]
        return sum(c[i, j, k] * x ** i * y ** j * z ** k
                   for i in range(degree + 1) for j in range(degree + 1 - i)
                   for k in range(degree + 1 - i - j))
    return fun


@pytest.mark.parametrize("points", sorted(APERTURE_POINTS))
def test_aperture_stencil_accuracy(points):
    """Weights sum to 1, nodes in the cone; a constant and polynomials of the direction vector
    up to the stated degree (7: 2, 19: 4, 37: 6) are averaged exactly, one degree more is not;
    at the pole too. A wide cone (40 deg), since the error of a small one is tiny anyway."""
    exact_to = {7: 2, 19: 4, 37: 6}[points]
    a = math.radians(40.0)
    beta, psi, wt = aperture_stencil(a, points)
    assert beta.size == psi.size == wt.size == points
    assert wt.sum() == pytest.approx(1.0, abs=1e-14) and np.all(wt > 0)
    assert beta[0] == 0.0 and np.all(beta <= a + 1e-15)
    for tr, ph in ((0.0, 0.0), (0.4, 1.0), (0.8, -2.5)):  # the cone stays above the horizon
        tr_s, ph_s, w = aperture_directions(np.array([tr]), np.array([ph]), a, points)
        _, dirs = geometry.unit_vectors(np.zeros_like(tr_s), tr_s, ph_s)
        _, axis = geometry.unit_vectors(0.0, tr, ph)
        assert np.degrees(np.arccos(np.clip(dirs @ axis, -1, 1))).max() <= 40.0 + 1e-9
        for degree in range(exact_to + 2):
            f = _poly(degree, seed=degree)
            ref = _cap_average_reference(f, tr, ph, a)
            err = abs(float(f(dirs)[0] @ w) - ref)
            if degree <= exact_to:
                assert err < 1e-12 * max(1.0, abs(ref)), (points, tr, degree, err)
            else:
                assert err > 1e-10, (points, tr, degree, err)
    # a constant model gives the constant (the Lambertian BRDF), any geometry
    lam = rb.model("lambertian", rho=0.4)
    got = aperture_average(lam, [0.1, 0.5, 0.7], [0.0, 0.3, 1.5], [0.0, 2.0, -1.0],
                           math.radians(3.0), points=points)
    assert np.allclose(got, 0.4 / math.pi, rtol=1e-14)


def test_aperture_horizon_guard_and_pole():
    """Near grazing the part of the cone below the surface is clipped to theta_r = 90 deg."""
    tr_s, ph_s, _ = aperture_directions(np.radians([89.5, 0.0]), np.array([0.3, 0.0]),
                                         math.radians(2.0), 19)
    assert tr_s.max() == 0.5 * math.pi and np.sum(tr_s[0] == 0.5 * math.pi) >= 6
    assert np.all(tr_s[1] <= math.radians(2.0) + 1e-12) and tr_s[1, 0] == 0.0
    m = rb.model("trowbridge-reitz-1975")
    assert np.isfinite(aperture_average(m, 0.3, math.radians(89.5), 0.3, math.radians(2.0),
                                        quantity="bridf"))


def test_aperture_none_or_zero_is_the_plain_fit():
    meas = ts67_absolute(seed=1)
    plain = fit("ts67", meas, starts=2, progress=False)
    for a in (None, 0.0):
        res = fit("ts67", meas, starts=2, progress=False, aperture=a)
        assert res.params == plain.params and res.sigma == plain.sigma
        assert res.aperture is None and res.options["aperture"] is None
        assert "aperture           = none" in res.report()
        assert res.to_dict()["aperture"] is None


def _sharp_model(alpha: float = 0.02, ks: float = 0.8, rho: float = 0.05) -> rb.models.Model:
    return (rb.model("microfacet", distribution="trowbridge-reitz", shadowing="smith", n=1.5,
                     k=0.0, alpha=alpha, ks=ks) + rb.model("lambertian", rho=rho))


def _near_specular_design() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Two incidences: 0.5 deg steps within 6 deg of the mirror direction (3 azimuths), plus a
    coarse 10 deg grid: 204 samples."""
    rows = []
    for ti in (20.0, 45.0):
        rows += [(ti, abs(ti + off), ph) for off in np.arange(-6, 6.01, 0.5)
                 for ph in (0.0, 2.0, 4.0)]
        rows += [(ti, tr, ph) for tr in range(0, 86, 10) for ph in (0, 90, 180)]
    ti, tr, ph = np.radians(np.array(rows, dtype=float)).T
    return ti, tr, ph


def test_aperture_fit_recovers_a_sharp_lobe_the_plain_fit_biases():
    """Data: a specular lobe about as wide as the instrument (GGX alpha 0.02, 1.5 deg aperture),
    averaged over the aperture by the 37-point rule. The 19-point aperture fit recovers the
    parameters; the plain fit widens the lobe (alpha +12 %) and cannot fit the data."""
    ti, tr, ph = _near_specular_design()
    ap = math.radians(1.5)
    x = aperture_average(_sharp_model(), ti, tr, ph, ap, points=37)
    meas = Measurement(ti, tr, ph, x, quantity="brdf")
    start = _sharp_model(alpha=0.1, ks=1.0, rho=0.1)
    fix = ["microfacet_n", "microfacet_k"]
    res = fit(start, meas, fix=fix, starts=3, aperture=ap, progress=False, subsample=100)
    assert res.success and res.aperture == ap
    assert res.params["microfacet_alpha"] == pytest.approx(0.02, rel=2e-3)
    assert res.params["microfacet_ks"] == pytest.approx(0.8, rel=2e-3)
    assert res.params["lambertian_rho"] == pytest.approx(0.05, rel=2e-3)
    assert res.sigma < 2e-3
    assert np.allclose(res.predict(ti, tr, ph), res.channels[0].fitted, rtol=1e-12)
    plain = fit(start, meas, fix=fix, starts=3, progress=False)
    assert plain.params["microfacet_alpha"] > 1.08 * 0.02
    assert plain.sigma > 20 * res.sigma
    # recorded for plots and reports
    d = res.to_dict()
    assert d["aperture"]["half_angle_deg"] == pytest.approx(1.5)
    assert d["aperture"]["points"] == 19 and d["options"]["aperture"] == ap
    assert "aperture           = 1.5 deg half-angle" in res.report()


def test_aperture_jacobian_is_one_vectorized_evaluation_per_parameter():
    ti, tr, ph = _near_specular_design()
    m = _sharp_model()
    free = ["microfacet_alpha", "microfacet_ks", "lambertian_rho"]
    lo, hi = np.array([0.001, 0.0, 0.0]), np.array([1.0, 10.0, 1.0])
    x = aperture_average(m, ti, tr, ph, math.radians(1.0))
    obj = Objective(ObjectiveSpec(m, free, lo, hi, loss="relative", quantity="brdf",
                                  free_scale=False, fixed_scale=1.0),
                    ChannelData.from_arrays(ti, tr, ph, x,
                                            aperture=Aperture(math.radians(1.0), 19)))
    theta = np.array([0.03, 0.7, 0.06])
    assert np.allclose(obj.values(np.array([0.02, 0.8, 0.05])), x, rtol=1e-13)
    jac = obj.jac(theta)
    for j in range(theta.size):
        h = 1e-6 * theta[j]
        tp, tm = theta.copy(), theta.copy()
        tp[j] += h
        tm[j] -= h
        col = (obj.fun(tp) - obj.fun(tm)) / (2 * h)
        assert np.allclose(jac[:, j], col, rtol=1e-4, atol=1e-6 * np.abs(col).max())
    obj.reset()
    obj.jac(theta)
    assert obj.nfev == theta.size + 1


@pytest.mark.parametrize("bad", [-0.01, math.nan, math.inf, 0.5 * math.pi, 2.0, "wide"])
def test_error_bad_aperture(bad):
    meas = ts67_absolute(seed=0)
    with pytest.raises(ValueError, match="aperture"):
        fit("ts67", meas, aperture=bad, progress=False)
    with pytest.raises(ValueError, match="aperture"):
        aperture_average(rb.model("ts67"), 0.1, 0.2, 0.0, bad)


def test_error_bad_aperture_points():
    with pytest.raises(ValueError, match="aperture_points must be one of"):
        fit("ts67", ts67_absolute(seed=0), aperture=0.01, aperture_points=9, progress=False)


# ---------------------------------------------------------------------------------------------
# errors
# ---------------------------------------------------------------------------------------------
def test_error_every_parameter_fixed():
    meas = ts67_absolute(seed=0)
    with pytest.raises(ValueError, match="every parameter .* is fixed"):
        fit(rb.model("torrance-sparrow-1967", n=None, k=None), meas,
               fix=["g", "c", "rho_d"], progress=False)


def test_error_no_data_in_channel():
    ti, tr, ph = ts67_grid()
    vals = np.column_stack([np.full(ti.size, np.nan), np.ones(ti.size)])
    meas = Measurement(ti, tr, ph, vals, channels=["465nm", "525nm"], meta={"file": "x.astm"})
    with pytest.raises(ValueError, match=r"x\.astm, channel '465nm': no data to fit \(360 "
                                         r"samples; left out: 360 non-finite\)"):
        fit("ts67", meas, nonfinite="drop", progress=False)
    with pytest.raises(ValueError, match="no data to fit"):
        fit("ts67", meas.subset(np.zeros(ti.size, bool)), progress=False)
    few = meas.subset(np.arange(3))
    with pytest.raises(ValueError, match="3 samples for 3 fitted parameters"):
        fit(rb.model("torrance-sparrow-1967", n=None, k=None), few, channel=1,
               progress=False)


def test_error_bad_options():
    meas = ts67_absolute(seed=0)
    with pytest.raises(ValueError,
                       match="unknown loss 'squared'; choose one of auto, relative, log"):
        fit("ts67", meas, loss="squared")
    # worded as argument errors (roughbrdf.errors): the CLI shows them as --nonfinite/--negative
    with pytest.raises(ValueError, match="nonfinite = 'ignore': must be 'raise' or 'drop'"):
        fit("ts67", meas, nonfinite="ignore")
    with pytest.raises(ValueError,
                       match="negative = 'abs': must be 'auto', 'keep', 'drop' or 'clip'"):
        fit("ts67", meas, negative="abs")
    with pytest.raises(ValueError, match="unknown parameter .*'gg'"):
        fit("ts67", meas, fix=["gg"])
    with pytest.raises(ValueError, match="low < high"):
        fit("ts67", meas, bounds={"g": (2.0, 1.0)})
    with pytest.raises(ValueError, match=r"starting value g = 60 is outside its bounds"):
        fit(rb.model("ts67", g=60.0), meas)
    with pytest.raises(ValueError, match="scale must be finite and > 0"):
        fit("ts67", meas, scale=0.0)
    with pytest.raises(ValueError, match="either scale"):
        fit("ts67", meas, scale=2.0, free_scale=True)
    with pytest.raises(ValueError, match="relative_to must be"):
        fit("ts67", Measurement(meas.theta_i, meas.theta_r, meas.phi, meas.values,
                                   quantity="relative"), relative_to="radiance")
    with pytest.raises(ValueError, match="unknown channel"):
        fit("ts67", meas, channel="green")
    with pytest.raises(TypeError, match="Measurement"):
        fit("ts67", meas.values)
