"""The fit domain: ``rb.fit(..., theta_r_max=, source_exclusion=)`` and ``roughbrdf fit
--theta-r-max DEG --source-exclusion DEG`` leave samples out, counted, never silently."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

import roughbrdf as rb
from roughbrdf.cli import app
from roughbrdf.demo import default_measurement_path
from roughbrdf.errors import ArgumentError
from roughbrdf.fitting.problem.data import outside_fit_domain
from roughbrdf.measurement import Measurement

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

MODEL = rb.model("trowbridge-reitz-1975", e=0.4, rho_L=0.05)
T_MAX, EXCL = math.radians(70.0), math.radians(12.0)


def _measurement(n: int = 600, seed: int = 3) -> Measurement:
    """TR75 BRDF with 5 % noise at random directions, a sixth of them near the retro
    direction."""
    rng = np.random.default_rng(seed)
    ti = rng.uniform(0.0, 1.3, n)
    tr = rng.uniform(0.0, 1.5, n)
    ph = rng.uniform(-math.pi, math.pi, n)
    near = slice(0, n // 6)  # around the source direction (theta_r = theta_i, phi = pi)
    tr[near] = np.clip(ti[near] + rng.normal(0.0, 0.15, n // 6), 0.0, 1.5)
    ph[near] = math.pi - rng.normal(0.0, 0.3, n // 6)
    vals = MODEL.brdf(ti, tr, ph) * (1.0 + 0.05 * rng.standard_normal(n))
    return Measurement(ti, tr, ph, vals, quantity="brdf")


def _numpy_counts(ti, tr, ph, t_max, excl) -> tuple[int, int, np.ndarray]:
    """Independent count: spherical law of cosines for the angle to the source direction;
    a sample beyond theta_r_max is counted there only."""
    above = tr > t_max
    cos_d = np.cos(ti) * np.cos(tr) - np.sin(ti) * np.sin(tr) * np.cos(ph)
    near = (np.arccos(np.clip(cos_d, -1.0, 1.0)) < excl) & ~above
    return int(above.sum()), int(near.sum()), ~(above | near)


def _fit(meas, **kw):
    return rb.fit("trowbridge-reitz-1975", meas, starts=1, progress=False, **kw)


def test_default_is_all_samples_as_before():
    meas = _measurement()
    base = _fit(meas)
    same = _fit(meas, theta_r_max=None, source_exclusion=None)
    wide = _fit(meas, theta_r_max=math.pi / 2, source_exclusion=0.0)  # excludes nothing
    for res in (same, wide):
        c = res.channels[0]
        assert c.n_points == base.channels[0].n_points == meas.n_samples
        assert c.params == base.channels[0].params
        assert c.excluded["theta_r_max"] == c.excluded["source_exclusion"] == 0
    assert base.options["theta_r_max"] is None and base.options["source_exclusion"] is None
    assert "fit domain         = all samples" in base.report()


def test_counts_match_numpy_and_the_fit_uses_exactly_the_rest():
    meas = _measurement()
    n_above, n_near, keep = _numpy_counts(meas.theta_i, meas.theta_r, meas.phi, T_MAX, EXCL)
    assert n_above > 50 and n_near > 20  # the test means something
    res = _fit(meas, theta_r_max=T_MAX, source_exclusion=EXCL)
    c = res.channels[0]
    assert c.excluded["theta_r_max"] == n_above and c.excluded["source_exclusion"] == n_near
    assert c.n_points == meas.n_samples - n_above - n_near == int(keep.sum())
    # the same fit as on the remaining samples alone, without the options
    sub = Measurement(meas.theta_i[keep], meas.theta_r[keep], meas.phi[keep],
                      meas.values[keep], quantity="brdf")
    alone = _fit(sub).channels[0]
    assert c.n_points == alone.n_points
    for name, value in alone.params.items():
        assert c.params[name] == pytest.approx(value, rel=1e-9, abs=1e-12)
    assert c.sigma == pytest.approx(alone.sigma, rel=1e-9)
    # each option alone
    only = _fit(meas, source_exclusion=EXCL).channels[0]
    cos_d = (np.cos(meas.theta_i) * np.cos(meas.theta_r)
             - np.sin(meas.theta_i) * np.sin(meas.theta_r) * np.cos(meas.phi))
    assert only.excluded["source_exclusion"] == int(
        (np.arccos(np.clip(cos_d, -1, 1)) < EXCL).sum())
    assert _fit(meas, theta_r_max=T_MAX).channels[0].excluded["theta_r_max"] == n_above


def test_source_distance_at_the_retro_direction():
    ti = np.array([0.0, 0.6, 0.6, 1.2, 0.6])
    tr = np.array([0.0, 0.6, 0.6 + 0.05, 1.2, 0.6])
    ph = np.array([0.0, math.pi, math.pi, -math.pi, 0.0])  # the last one: specular
    above, near = outside_fit_domain(ti, tr, ph, None, 0.04)
    assert not above.any() and near.tolist() == [True, True, False, True, False]


def test_report_and_fit_json_show_the_domain(tmp_path):
    meas = _measurement()
    res = _fit(meas, theta_r_max=T_MAX, source_exclusion=EXCL)
    c = res.channels[0]
    text = res.report()
    assert "fit domain         = theta_r <= 70 deg, >= 12 deg from the source direction" in text
    assert (f"{c.excluded['theta_r_max']} with theta_r above theta_r_max" in text
            and f"{c.excluded['source_exclusion']} within the source exclusion" in text)
    d = json.loads(res.to_json())
    assert d["options"]["theta_r_max"] == pytest.approx(T_MAX)
    assert d["options"]["source_exclusion"] == pytest.approx(EXCL)
    assert d["channels"][0]["excluded"]["theta_r_max"] == c.excluded["theta_r_max"]
    assert d["channels"][0]["excluded"]["source_exclusion"] == c.excluded["source_exclusion"]


@pytest.mark.parametrize("arg, value", [
    ("theta_r_max", -0.1), ("theta_r_max", math.nan), ("theta_r_max", math.pi / 2 + 1e-9),
    ("theta_r_max", "1"), ("theta_r_max", True), ("source_exclusion", math.inf),
    ("source_exclusion", -1e-3), ("source_exclusion", math.pi + 0.01),
    ("source_exclusion", [0.1]),
])
def test_bad_values_raise_argument_error(arg, value):
    with pytest.raises(ArgumentError) as info:
        _fit(_measurement(n=60), **{arg: value})
    assert info.value.argument == arg and arg in str(info.value)


def test_cli_options_and_errors(tmp_path):
    runner = CliRunner()
    path = default_measurement_path()
    meas = rb.read(path)
    n_above, n_near, keep = _numpy_counts(meas.theta_i, meas.theta_r, meas.phi,
                                          math.radians(60), math.radians(10))
    assert n_above > 0
    out = tmp_path / "out"
    res = runner.invoke(app, ["fit", str(path), "-m", "tr75", "--starts", "1", "--no-plots",
                              "--theta-r-max", "60", "--source-exclusion", "10",
                              "--out", str(out)])
    assert res.exit_code == 0, res.output  # TR75 fitted under the energy constraint
    d = json.loads((out / "fit.json").read_text())
    assert d["options"]["theta_r_max"] == pytest.approx(math.radians(60))
    assert d["options"]["source_exclusion"] == pytest.approx(math.radians(10))
    ch = d["channels"][0]
    assert ch["excluded"]["theta_r_max"] == n_above
    assert ch["excluded"]["source_exclusion"] == n_near
    assert ch["metrics"]["n_points"] == int(keep.sum())
    report = (out / "report.txt").read_text()
    assert f"{n_above} with theta_r above theta_r_max" in report
    assert "theta_r <= 60 deg, >= 10 deg from the source direction" in report
    for opt, value, shown in [("--theta-r-max", "100", "--theta-r-max 100 (degrees)"),
                              ("--source-exclusion", "-5", "--source-exclusion -5 (degrees)"),
                              ("--theta-r-max", "nan", "--theta-r-max nan (degrees)")]:
        bad = runner.invoke(app, ["fit", str(path), "-m", "tr75", "--out",
                                  str(tmp_path / "bad"), opt, value])
        assert bad.exit_code == 2, bad.output
        assert shown in bad.output and "theta_r_max =" not in bad.output
    assert not (tmp_path / "bad").exists()
