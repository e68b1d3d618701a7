"""One-sided limits of parameters that end on a physical limit
(:mod:`roughbrdf.fitting.results.one_sided`; ``docs/fitting.md``, "One-sided limits at a physical
limit").

Expected values: for a Lambertian fitted with the absolute loss the profile is exactly quadratic
and the limit has a closed form (``rho/pi = m + sqrt(m^2 + kappa z^2 / N)``, ``m`` the data's
mean, ``kappa = sum x^2 / (N - 1)`` the sandwich's dispersion at 0: the Gaussian mean with a bound
at 0); the promise (at most 5 % of fits end on the limit with ``u`` below the truth, 5 % when
the truth is ``z`` standard errors inside) is that Gaussian case's; a fit with free parameters
besides the held one is checked against SciPy's ``least_squares`` refitting them.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize

import roughbrdf as rb
from roughbrdf.fitting import ChannelData
from roughbrdf.fitting.problem.objective import Objective, ObjectiveSpec
from roughbrdf.fitting.results.one_sided import RTOL, Z, dispersion, one_sided_limits, profile_limit


def _flat(x: np.ndarray, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Random directions for ``x.size`` samples of a Lambertian (its BRDF is the same at all)."""
    rng = np.random.default_rng(seed)
    n = x.size
    return rng.uniform(0, 1.2, n), rng.uniform(0, 1.2, n), rng.uniform(0, 2 * np.pi, n)


def _closed(x: np.ndarray) -> float:
    """The Gaussian mean's limit with a bound at 0, in ``rho`` (module notes)."""
    n, m = x.size, float(x.mean())
    kappa = float(x @ x) / (n - 1)
    return math.pi * (m + math.sqrt(m * m + kappa * Z * Z / n))


def _lambertian_objective(x: np.ndarray) -> Objective:
    data = ChannelData.from_arrays(*_flat(x), x)
    return Objective(ObjectiveSpec(rb.model("lambertian"), ["rho"], [0.0], [1.0],
                                   loss="absolute"), data)


@pytest.fixture(scope="module")
def below_zero() -> tuple[rb.FitResult, np.ndarray]:
    """A Lambertian fitted to data whose mean is below 0: ``rho`` on its physical limit."""
    x = -0.002 + 0.01 * np.random.default_rng(3).standard_normal(60)
    meas = rb.Measurement(*_flat(x), x)
    return rb.fit("lambertian", meas, loss="absolute", starts=1, intervals="profile",
                  progress=False), x


def test_the_fit_gives_the_closed_form_limit(below_zero):
    res, x = below_zero
    (c,) = res.channels
    assert c.limits == {"rho": "physical-lower"}
    u = c.one_sided["rho"]
    # the far end of a bracket narrowed to RTOL: at or above the closed form, within RTOL
    assert _closed(x) <= u <= _closed(x) * (1 + RTOL)


def test_the_limit_is_in_the_report_and_fit_json(below_zero, tmp_path):
    res, _ = below_zero
    u = res[0].one_sided["rho"]
    line = next(ln for ln in res.report().splitlines() if ln.strip().startswith("rho"))
    assert f"[physical limit; <= {u:.4g} at 95 %, profile]" in line
    res.save(tmp_path / "out", plots=False)
    back = rb.load_fit(tmp_path / "out" / "fit.json", measurement=res.measurement)
    assert back[0].one_sided == pytest.approx({"rho": u}, rel=1e-12)


def test_dispersion_is_the_residual_variance_for_least_squares():
    """kappa = sum r^2 / (N - 1) for one parameter of a linear model (its sandwich / curvature)."""
    x = np.array([0.1, 0.3, 0.25, 0.15, 0.2])
    obj = _lambertian_objective(x)
    r = x - x.mean()
    assert dispersion(obj, np.array([math.pi * x.mean()]), 0) == pytest.approx(
        float(r @ r) / (x.size - 1), rel=1e-9)


def test_misses_at_most_five_percent_at_the_worst_truth():
    """The truth z standard errors inside the limit (the worst case): a fit ends on the limit
    with u below the truth in 5 % of the seeds (binomial, 400 seeds: 5 +/- 1.1 %)."""
    n, sigma = 30, 0.01
    truth = Z * sigma / math.sqrt(n)  # in x = rho / pi
    rng = np.random.default_rng(12)
    misses = 0
    seeds = 400
    for _ in range(seeds):
        x = truth + sigma * rng.standard_normal(n)
        if x.mean() > 0:
            continue  # an interior optimum: a standard error, no limit
        u = one_sided_limits(_lambertian_objective(x), {"rho": 0.0},
                             {"rho": "physical-lower"})["rho"]
        assert u is not None
        misses += u / math.pi < truth
    assert 0.05 - 3 * 0.011 <= misses / seeds <= 0.05 + 3 * 0.011


def test_a_truth_on_the_limit_is_always_covered():
    rng = np.random.default_rng(5)
    for _ in range(50):
        x = 0.01 * rng.standard_normal(20)
        if x.mean() <= 0:
            u = one_sided_limits(_lambertian_objective(x), {"rho": 0.0},
                                 {"rho": "physical-lower"})["rho"]
            assert u is not None and u > 0


def _dip() -> tuple[rb.Measurement, ChannelData]:
    """A Lambertian with a dip around the mirror direction: a specular lobe can only add, so
    the microfacet ``ks`` of ``lambertian+microfacet`` (its width held at the dip's) ends on its
    physical limit 0."""
    rng = np.random.default_rng(7)
    n = 300
    ti, tr, ph = rng.uniform(0, 1.2, n), rng.uniform(0, 1.2, n), rng.uniform(0, 2 * np.pi, n)
    glint = rb.model("microfacet", ks=1.0, alpha=0.3).brdf(ti, tr, ph)
    x = (0.4 / np.pi) * (1 - 0.3 * glint / glint.max()) \
        * np.exp(0.03 * rng.standard_normal(n))
    return rb.Measurement(ti, tr, ph, x), ChannelData.from_arrays(ti, tr, ph, x)


def test_refitted_profile_agrees_with_scipy():
    """At ``u`` the profile, refitted by SciPy's least_squares, is at the threshold: just below
    it a bracket's width (RTOL) inside."""
    meas, _ = _dip()
    model = rb.model("lambertian+microfacet", microfacet_alpha=0.3)
    res = rb.fit(model, meas, loss="log", progress=False, intervals="profile",
                 fix=["microfacet_alpha", "microfacet_n", "microfacet_k"])
    c = res[0]
    name = next(nm for nm in c.free if nm.endswith("ks"))
    assert c.limits.get(name) == "physical-lower"
    u = c.one_sided[name]
    assert u is not None and 0 < u < 1
    # the profile and its threshold rebuilt with SciPy refitting the other parameters
    spec = ObjectiveSpec(c.model, c.free, [c.bounds[nm][0] for nm in c.free],
                         [c.bounds[nm][1] for nm in c.free], loss="log")
    j = c.free.index(name)
    others = [i for i in range(len(c.free)) if i != j]
    theta = np.array([c.params[nm] for nm in c.free])
    obj = Objective(spec, _dip()[1])
    threshold = 0.5 * dispersion(obj, theta, j) * Z * Z
    base = 0.5 * obj.cost(theta)

    def profile(v: float) -> float:
        def fun(t):
            full = theta.copy()
            full[others] = t
            full[j] = v
            return obj.fun(full)
        lo, hi = spec.lower[others], spec.upper[others]
        out = optimize.least_squares(fun, np.clip(theta[others], lo, hi), bounds=(lo, hi),
                                     xtol=1e-12, ftol=1e-12, gtol=1e-12)
        return float(out.cost) - base

    assert profile(u) >= threshold * (1 - 1e-3)
    assert profile(u * (1 - 2 * RTOL)) < threshold


def test_only_when_asked():
    """Opt-in (a profile costs many refits): the default fit reports the physical limit alone,
    in the report as before; a joint fit (whose channels share parameters) has none."""
    x = -0.002 + 0.01 * np.random.default_rng(4).standard_normal(40)
    meas = rb.Measurement(*_flat(x), x)
    res = rb.fit("lambertian", meas, loss="absolute", starts=1, progress=False)
    assert res[0].limits == {"rho": "physical-lower"} and res[0].one_sided == {}
    assert "[physical limit] (init" in res.report()
    two = rb.Measurement(*_flat(x), np.stack([x, x + 0.001], axis=1), channels=["a", "b"])
    res = rb.fit("lambertian", two, loss="absolute", joint=True, starts=1, progress=False)
    assert all(c.one_sided == {} for c in res.channels)


def test_threshold_is_the_sandwich_calibration_of_the_standard_errors():
    """At an interior optimum of a robust fit (heteroscedastic in its residuals: the sandwich
    differs from chi2/dof), the profile reaches the threshold z sandwich standard errors away:
    the limits and the standard errors are one calibration."""
    rng = np.random.default_rng(9)
    x = 0.1 * np.exp(0.05 * rng.standard_normal(200)) + 0.004 * rng.standard_normal(200)
    meas = rb.Measurement(*_flat(x), x)
    (c,) = rb.fit("lambertian", meas, starts=1, progress=False).channels  # robust default
    assert not c.at_bound
    obj = Objective(ObjectiveSpec(rb.model("lambertian"), ["rho"], [0.0], [1.0],
                                  loss="robust"), ChannelData.from_arrays(
                                      *_flat(x), x))
    rho = c.params["rho"]
    kappa = dispersion(obj, np.array([rho]), 0)
    chi2_dof = c.chi2 / (c.n_points - 1)
    assert abs(kappa / chi2_dof - 1) > 0.05  # a case where the calibration matters
    base = 0.5 * obj.cost(np.array([rho]))
    u = profile_limit(lambda v: 0.5 * obj.cost(np.array([v])) - base, rho, 1.0,
                      0.5 * kappa * Z * Z, 1e-3)
    assert u is not None
    assert (u - rho) / (Z * c.stderr["rho"]) == pytest.approx(1.0, abs=0.03)


def test_a_limit_at_the_upper_edge_mirrors_the_lower():
    """rho on its upper physical limit 1 (data above 1/pi): the limit lies below it, at the
    mirrored closed form (the distances below the edge, y = 1/pi - x, as x above)."""
    x = 1 / np.pi + 0.002 + 0.01 * np.random.default_rng(6).standard_normal(50)
    obj = _lambertian_objective(x)
    u = one_sided_limits(obj, {"rho": 1.0}, {"rho": "physical-upper"})["rho"]
    mirrored = 1.0 - _closed(1 / np.pi - x)
    assert u is not None
    # the far end of the bracket: at or below the closed form, within RTOL of its distance
    assert mirrored - RTOL * (1 - mirrored) <= u <= mirrored
