"""Profile intervals (``intervals="profile"``, :mod:`roughbrdf.fitting.results.intervals`).

Expected values: where the cost is quadratic in the parameter (a Lambertian, absolute loss) the
profile's 68 % interval is ``value +/- stderr`` and its 95 % one ``value +/- 2 stderr`` (the
threshold is calibrated on the sandwich standard errors: ``docs/fitting.md``); where it is not,
the ends are checked against the profile rebuilt with SciPy's ``least_squares`` refitting the
other parameters.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import optimize
from typer.testing import CliRunner

import roughbrdf as rb
from roughbrdf.cli import app
from roughbrdf.demo import default_measurement_path
from roughbrdf.errors import ArgumentError
from roughbrdf.fitting import ChannelData
from roughbrdf.fitting.kinds.per_incidence import fit_per_incidence
from roughbrdf.fitting.problem.objective import Objective, ObjectiveSpec
from roughbrdf.fitting.results.intervals import LEVELS, NOT_UNDER_CONSTRAINT
from roughbrdf.fitting.results.one_sided import RTOL, dispersion

#: fits and a CLI run: too slow without the JIT (make test-nojit deselects them)
pytestmark = pytest.mark.jit_heavy(reason="whole fits with profiles: minutes in plain Python")


def _directions(n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.uniform(0, 1.2, n), rng.uniform(0, 1.2, n), rng.uniform(0, 2 * np.pi, n)


def test_quadratic_cost_gives_the_standard_errors():
    x = 0.2 + 0.02 * np.random.default_rng(1).standard_normal(80)
    meas = rb.Measurement(*_directions(80, 1), x)
    (c,) = rb.fit("lambertian", meas, loss="absolute", starts=1, intervals="profile",
                  progress=False).channels
    rho, se = c.params["rho"], c.stderr["rho"]
    for level, z in LEVELS.items():
        lo, hi = c.intervals["rho"][level]
        # each end the far end of a bracket narrowed to RTOL of its distance
        assert (rho - lo) / (z * se) == pytest.approx(1.0, abs=RTOL)
        assert (hi - rho) / (z * se) == pytest.approx(1.0, abs=RTOL)


def test_default_has_no_intervals():
    x = 0.2 + 0.02 * np.random.default_rng(1).standard_normal(30)
    res = rb.fit("lambertian", rb.Measurement(*_directions(30, 1), x), loss="absolute",
                 starts=1, progress=False)
    assert res[0].intervals == {}
    assert json.loads(res.to_json())["channels"][0]["profile_intervals"] == {}


@pytest.fixture(scope="module")
def glossy() -> tuple[rb.FitResult, ChannelData]:
    """A microfacet lobe over a Lambertian, 5 % log-normal noise; n and k held (the width,
    the lobe's and the diffuse reflectance free): a non-quadratic cost in alpha and ks."""
    ti, tr, ph = _directions(400, 2)
    truth = rb.model("lambertian+microfacet", lambertian_rho=0.3, microfacet_alpha=0.25,
                     microfacet_ks=0.6)
    x = truth.brdf(ti, tr, ph) * np.exp(0.05 * np.random.default_rng(3).standard_normal(400))
    res = rb.fit(rb.model("lambertian+microfacet"), rb.Measurement(ti, tr, ph, x), loss="log",
                 fix=["microfacet_n", "microfacet_k"], intervals="profile", progress=False)
    return res, ChannelData.from_arrays(ti, tr, ph, x)


def test_every_free_parameter_gets_both_levels(glossy):
    res, _ = glossy
    c = res[0]
    assert not c.at_bound and set(c.intervals) == set(c.free)
    for name, by in c.intervals.items():
        (lo68, hi68), (lo95, hi95) = by["68"], by["95"]
        assert lo95 < lo68 < c.params[name] < hi68 < hi95, name


def test_ends_are_where_scipy_refitted_profile_crosses(glossy):
    res, data = glossy
    c = res[0]
    spec = ObjectiveSpec(c.model, c.free, np.array([c.bounds[nm][0] for nm in c.free]),
                         np.array([c.bounds[nm][1] for nm in c.free]), loss="log")
    obj = Objective(spec, data)
    theta = np.array([c.params[nm] for nm in c.free])
    base = 0.5 * obj.cost(theta)
    name = "microfacet_alpha"
    j = c.free.index(name)
    others = [i for i in range(len(c.free)) if i != j]
    threshold = 0.5 * dispersion(obj, theta, j) * LEVELS["68"] ** 2

    def profile(v: float) -> float:
        def fun(t):
            full = theta.copy()
            full[others], full[j] = t, v
            return obj.fun(full)
        lo, hi = spec.lower[others], spec.upper[others]
        out = optimize.least_squares(fun, np.clip(theta[others], lo, hi), bounds=(lo, hi),
                                     xtol=1e-12, ftol=1e-12, gtol=1e-12)
        return float(out.cost) - base

    lo, hi = c.intervals[name]["68"]
    for end in (lo, hi):
        d = end - theta[j]
        assert profile(end) >= threshold * (1 - 1e-3)
        assert profile(theta[j] + d * (1 - 2 * RTOL)) < threshold


def test_report_and_fit_json_round_trip(glossy, tmp_path):
    res, _ = glossy
    c = res[0]
    text = res.report()
    assert "[[Profile intervals]]" in text
    lo, hi = c.intervals["microfacet_alpha"]["68"]
    assert f"68 % [{lo:.5g}, {hi:.5g}]" in text
    res.save(tmp_path / "out", plots=False)
    back = rb.load_fit(tmp_path / "out" / "fit.json", measurement=res.measurement)
    assert set(back[0].intervals) == set(c.intervals)
    for nm, by in c.intervals.items():
        for lv, pair in by.items():
            assert back[0].intervals[nm][lv] == pytest.approx(pair, rel=1e-12)


def test_refused_where_there_is_no_profile():
    x = 0.2 + 0.02 * np.random.default_rng(1).standard_normal(30)
    meas = rb.Measurement(*_directions(30, 1), np.stack([x, x], axis=1), channels=["a", "b"])
    with pytest.raises(ArgumentError, match="intervals.*joint"):
        rb.fit("lambertian", meas, joint=True, intervals="profile")
    with pytest.raises(ArgumentError, match="intervals = 'sandwich': must be 'wald' or"):
        rb.fit("lambertian", meas, intervals="sandwich")
    with pytest.raises(ArgumentError, match="per-incidence fit has no profile"):
        fit_per_incidence("lambertian", meas, intervals="profile")


def test_command_line_writes_them(tmp_path):
    x = 0.2 + 0.02 * np.random.default_rng(1).standard_normal(60)
    path = tmp_path / "flat.csv"
    rb.write(rb.Measurement(*_directions(60, 1), x), path)
    out = tmp_path / "out"
    run = CliRunner().invoke(app, ["fit", str(path), "-m", "lambertian", "--loss", "absolute",
                                   "--intervals", "profile", "--no-plots", "--out", str(out)])
    assert run.exit_code == 0, run.output
    assert "[[Profile intervals]]" in (out / "report.txt").read_text()
    chan = json.loads((out / "fit.json").read_text())["channels"][0]
    assert set(chan["profile_intervals"]["rho"]) == {"68", "95"}
    bad = CliRunner().invoke(app, ["fit", str(path), "-m", "lambertian", "--intervals", "x",
                                   "--out", str(tmp_path / "bad")])
    assert bad.exit_code != 0 and "--intervals x: must be 'wald' or 'profile'" in bad.output


def test_an_active_energy_constraint_says_why_there_are_none():
    """TR75 on the embedded cement data is refitted under the energy constraint (active at
    grazing incidence): no profile of the unconstrained cost is offered, and the message (so the
    report) says why."""
    meas = rb.read(default_measurement_path())
    res = rb.fit("trowbridge-reitz-1975", meas, starts=2, intervals="profile", progress=False)
    c = res[0]
    assert c.energy_constraint.active
    assert c.intervals == {} and c.one_sided == {}
    assert NOT_UNDER_CONSTRAINT in c.message and "energy_constraint=False" in res.report()
