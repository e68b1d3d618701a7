"""The parts of roughbrdf.fitting on their own: data, objective, search, statistics, threads.

End-to-end fits are in tests/fitting/test_fitting.py; these check each module's public pieces.
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.fitting import ChannelData, Objective, ObjectiveSpec
from roughbrdf.fitting.problem.data import Comparison, excluded_text
from roughbrdf.fitting.problem.plan import FreeParameters
from roughbrdf.fitting.results.statistics import Covariance, GoodnessOfFit
from roughbrdf.fitting.solvers.search import MultiStart, SearchOptions, screen, sobol_points
from roughbrdf.fitting.solvers.threads import single_thread_blas
from roughbrdf.measurement import Measurement
from roughbrdf.quantity import relative_scale

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")


@pytest.fixture(scope="module")
def ts67_data():
    t_i, t_r, p = np.meshgrid(np.radians([10, 40, 70]), np.radians(np.arange(0, 86, 10)),
                              np.radians([0, 90, 180]), indexing="ij")
    ti, tr, ph = t_i.ravel(), t_r.ravel(), p.ravel()
    truth = rb.model("torrance-sparrow-1967", n=None, k=None, g=2.0, c=0.08, rho_d=0.3)
    return ti, tr, ph, truth.brdf(ti, tr, ph)


def _spec(**kw):
    m = rb.model("torrance-sparrow-1967", n=None, k=None, g=1.0, c=0.1, rho_d=0.5)
    p = FreeParameters.of(m, fix=["rho_d"])
    kw.setdefault("loss", "relative")
    kw.setdefault("quantity", "brdf")
    kw.setdefault("free_scale", False)
    kw.setdefault("fixed_scale", 1.0)
    return p.spec(m, **kw)


def test_comparison_of_each_quantity():
    m = Measurement([0.1], [0.2], [0.0], [1.0], quantity="brdf_cos")
    assert Comparison.of(m).compared == "bridf" and Comparison.of(m).relative_to is None
    m.quantity = "relative"
    assert Comparison.of(m) == Comparison(rb.quantity.Quantity.BRDF, "brdf")
    assert Comparison.of(m, "BRIDF").compared == "bridf"
    with pytest.raises(ValueError, match="relative_to must be"):
        Comparison.of(m, "radiance")
    assert excluded_text({"clipped": 1, "zero_weight": 0, "horizon": 3}) == (
        "1 negative (clipped), 3 at theta_r = 90 deg (BRDF cos theta_r = 0 for every model)")


def test_objective_spec_checks():
    with pytest.raises(ValueError, match="unknown loss"):
        _spec(loss="squared")
    m = rb.model("lambertian")
    with pytest.raises(ValueError, match="one bound per free parameter"):
        ObjectiveSpec(m, ["rho"], [0.0, 0.0], [1.0, 1.0])
    spec = _spec(free_scale=True)
    assert spec.free == ("g", "c") and spec.n_varys == 3
    assert spec.model_at([2.0, 0.08]).params["g"] == 2.0


@pytest.mark.parametrize("loss", ["relative", "log", "absolute"])
def test_free_scale_is_the_relative_scale_convention(ts67_data, loss):
    """K x ~ f: data 3.7 times too small give K = 3.7 at the true parameters, for each loss,
    and K is roughbrdf.quantity.relative_scale of the data and the model values."""
    ti, tr, ph, f = ts67_data
    obj = Objective(_spec(loss=loss, free_scale=True),
                    ChannelData.from_arrays(ti, tr, ph, f / 3.7))
    fv = obj.values([2.0, 0.08]) * 0.3 / 0.5  # rho_d fixed at 0.5 in the spec: rescale
    k = obj.scale(fv)
    assert k == pytest.approx(3.7, rel=1e-12)
    assert k == relative_scale(f / 3.7, fv, loss=loss)
    assert np.abs(obj.residual_of(fv)).max() < 1e-12


def test_subsample_objective_is_the_subset_of_the_full_one(ts67_data):
    ti, tr, ph, f = ts67_data
    w = np.linspace(0.5, 2.0, f.size)
    data = ChannelData.from_arrays(ti, tr, ph, f * 1.1, weights=w)
    full = Objective(_spec(), data)
    sub = np.array([5, 1, 30, 77])
    part = Objective(_spec(), data.take(sub))
    theta = np.array([1.5, 0.1])
    np.testing.assert_array_equal(part.fun(theta), full.fun(theta)[sub])
    np.testing.assert_array_equal(part.data.index, sub)
    assert part.nfev == full.nfev == 1
    part.reset()
    assert part.nfev == 0


def test_search_options_and_sobol_screen(ts67_data):
    with pytest.raises(ValueError, match="starts must be >= 1"):
        SearchOptions(starts=0)
    assert SearchOptions(starts=1).n_screen == 0 and SearchOptions(starts=8).n_screen == 64
    assert SearchOptions(polish=0).polish == 1
    lo, hi = np.array([0.0, 0.001]), np.array([50.0, 0.5])
    a, b = sobol_points(lo, hi, 16, seed=3), sobol_points(lo, hi, 16, seed=3)
    np.testing.assert_array_equal(a, b)
    assert a.shape == (16, 2) and np.all((a >= lo) & (a <= hi))
    ti, tr, ph, f = ts67_data
    obj = Objective(_spec(), ChannelData.from_arrays(ti, tr, ph, f * 0.5 / 0.3))
    kept = screen(obj, a, 3)
    costs = sorted(obj.cost(c) for c in a)
    assert obj.cost(kept[0]) == costs[0]  # the best candidate first
    for i in range(3):
        for j in range(i):
            assert np.max(np.abs(kept[i] - kept[j]) / (hi - lo)) >= 0.15


def test_multistart_warm_start_and_subsample(ts67_data):
    ti, tr, ph, f = ts67_data
    runner = MultiStart(_spec(), SearchOptions(starts=2, subsample=50, seed=1))
    data = ChannelData.from_arrays(ti, tr, ph, f * 0.5 / 0.3)
    obj, first = runner.run(data)
    assert obj.data.n == data.n
    stages = [s["stage"] for s in first.tried]
    assert stages[:2] == ["explore", "explore"] and set(stages[2:]) == {"full"}
    assert first.explore_nfev > 0
    np.testing.assert_allclose(first.theta, [2.0, 0.08], rtol=1e-7)
    _, second = runner.run(data)
    np.testing.assert_array_equal(second.tried[1]["x0"], first.theta)  # the warm start


def test_statistics_match_the_channel_fit(ts67_data):
    ti, tr, ph, f = ts67_data
    noisy = f * (1 + 0.05 * np.random.default_rng(0).standard_normal(f.size))
    meas = Measurement(ti, tr, ph, noisy, quantity="brdf")
    res = rb.fit(rb.model("ts67", n=None, k=None), meas, starts=2, progress=False)
    c = res.channels[0]
    gof = GoodnessOfFit.of(c.residual, c.data, c.fitted, scale=c.scale, n_varys=c.n_varys)
    assert gof.as_dict() == c.metrics
    spec = FreeParameters.of(rb.model("ts67", n=None, k=None)).spec(
        c.model, loss="relative", quantity="brdf", free_scale=False, fixed_scale=1.0)
    obj = Objective(spec, ChannelData.from_arrays(ti, tr, ph, noisy))
    theta = np.array([c.params[n] for n in c.free])
    cov = Covariance.at_optimum(obj, theta, c.fitted, 1.0, chi2=gof.chi2, dof=gof.dof)
    np.testing.assert_allclose(cov.stderr(), [c.stderr[n] for n in c.free], rtol=1e-12)
    assert cov.correl() == c.correl


def test_single_thread_blas_limits_and_restores():
    from threadpoolctl import threadpool_info

    before = [(i["filepath"], i["num_threads"]) for i in threadpool_info()
              if i["user_api"] == "blas"]
    with single_thread_blas():
        inside = [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]
        assert all(n == 1 for n in inside)
    after = [(i["filepath"], i["num_threads"]) for i in threadpool_info()
             if i["user_api"] == "blas"]
    assert after == before


def test_importing_fitting_and_plot_loads_no_heavy_modules():
    code = ("import sys, roughbrdf.fitting, roughbrdf.plot, roughbrdf.instrument; "
            "heavy = ['scipy.optimize', 'scipy.stats', 'matplotlib', 'tqdm', 'threadpoolctl']; "
            "print([m for m in heavy if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]"


def test_report_lists_the_aperture_and_the_exclusions():
    ti = np.full(40, 0.3)
    tr = np.linspace(0.0, math.pi / 2, 40)
    m = rb.model("trowbridge-reitz-1975", e=0.3)
    x = np.asarray(m.bridf(ti, tr, 0.0))
    meas = Measurement(ti, tr, np.zeros(40), x, quantity="bridf")
    res = rb.fit(m, meas, fix=["n", "k"], starts=1, aperture=math.radians(1.0),
                 aperture_points=7, progress=False)
    text = res.report()
    assert "aperture           = 1 deg half-angle, uniform cone about w_r (7-point" in text
    assert "1 at theta_r = 90 deg" in text
    assert res.instrument == rb.instrument.Aperture(math.radians(1.0), 7)


def test_two_lobe_ends_and_their_mirrors_are_polished_once():
    # lobe 1 and lobe 2 trading places (alpha <-> alpha2, w2 -> 1 - w2) is the same model at
    # the same cost: the search compares and polishes the ends in one form (narrower lobe
    # first, ObjectiveSpec.canonical), so no two polished ends are one another's mirror
    truth = rb.model("coated", lobes=2, n=1.5, rho=0.3, alpha=0.06, alpha2=0.3, w2=0.35)
    g = np.radians(np.mgrid[10:61:25, 0:81:2, 0:181:15].reshape(3, -1))
    rng = np.random.default_rng(5)
    meas = rb.Measurement(*g, truth.brdf(*g) * (1 + 0.02 * rng.standard_normal(g.shape[1])))
    res = rb.fit(truth.with_params(alpha=0.3, alpha2=0.06, w2=0.65), meas, starts=6,
                 subsample=500, progress=False)
    full = [t for t in res.channels[0].starts if t["stage"] == "full"]
    assert full, "no polish ran: the data were not subsampled"
    free = list(res.channels[0].free)
    a, a2 = free.index("alpha"), free.index("alpha2")
    for t in full:
        assert t["x0"][a] <= t["x0"][a2]  # started from the canonical form
    p = res.channels[0].params
    # the truth recovered, in either form
    lobes = sorted(res.channels[0].model.specular_lobes(), key=lambda wl: wl[1])
    assert lobes[0][1] == pytest.approx(0.06, rel=0.1) and lobes[1][1] == \
        pytest.approx(0.3, rel=0.1)
    assert p["n"] == pytest.approx(1.5, rel=0.05)


def test_canonical_leaves_a_point_whose_bounds_are_not_symmetric():
    spec = ObjectiveSpec(rb.model("coated", lobes=2), ["alpha", "alpha2", "w2"],
                         [0.01, 0.02, 0.0], [1.0, 1.0, 1.0])
    theta = np.array([0.3, 0.05, 0.2])
    assert spec.canonical(theta) is theta  # the mirror would leave the box of alpha2
    spec = ObjectiveSpec(rb.model("coated", lobes=2), ["alpha", "alpha2"], [0.01, 0.01],
                         [1.0, 1.0])
    assert spec.canonical(np.array([0.3, 0.05])).tolist() == [0.3, 0.05]  # w2 is not free
    spec = ObjectiveSpec(rb.model("coated", lobes=3), ["alpha", "alpha2", "w2"],
                         [0.01, 0.01, 0.0], [1.0, 1.0, 1.0])
    assert spec.canonical(np.array([0.3, 0.05, 0.2])).tolist() == [0.3, 0.05, 0.2]
