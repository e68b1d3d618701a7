"""Fits that conserve energy: models that cannot guarantee ``albedo <= 1`` (TR75 with
``rho_L``, RB08, sums of models) are fitted under the explicit constraint
``albedo(theta_i) <= 1`` at 0, 5, ... 85, 89 deg: the accurate :func:`roughbrdf.albedo` of
the result is at most ``1 + 1e-3`` there. ``energy_constraint=False``
(``--no-energy-constraint``) gives the unconstrained fit."""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest
from typer.testing import CliRunner

import roughbrdf as rb
from roughbrdf.cli import app, main
from roughbrdf.errors import ArgumentError
from roughbrdf.fitting import FitOptions
from roughbrdf.fitting.energy import FAST_ALBEDO_ACCURACY, fast_albedo
from roughbrdf.fitting.results.plausibility import (
    ENERGY_TOLERANCE,
    EXPORT_INCIDENCES_DEG,
    EnergyWarning,
)
from roughbrdf.models import model_label

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="whole fits of the measured paints: many minutes each in plain Python")

GRID = np.radians(np.mgrid[0:61:20, 0:81:5, 0:181:30].reshape(3, -1))
THETA = np.radians(EXPORT_INCIDENCES_DEG)
#: RB08 with its Fresnel factor off (n_eff = 1): the bulk and retro terms reflect 1.38 at 89 deg
RB08_FIXED = ["w_a", "w_b", "gamma", "delta", "n", "n_eff", "k_eff", "retro", "rho_r", "w_r",
              "n_r"]
#: (data from this model, fit from this model, fit keywords): each truth reflects more than it
#: receives at grazing incidence, so the unconstrained fit (which recovers it) does too
CASES = {
    "tr75": (rb.model("tr75", e=0.2, n=1.5, k=0.0, rho_L=0.8), rb.model("tr75"), {}),
    "sum": (rb.model("tr75", e=0.2, n=1.5, k=0.0, rho_L=0.0) + rb.model("lambertian", rho=0.6),
            rb.model("tr75", rho_L=0.0) + rb.model("lambertian"), {"fix": ["tr75_rho_L"]}),
    "rb08": (rb.model("rb08", n_eff=1.0, bulk=1.0, retro=0.1),
             rb.model("rb08", n_eff=1.0, bulk=0.9, retro=0.1), {"fix": RB08_FIXED}),
}


def measurement(truth: rb.Model) -> rb.Measurement:
    return rb.Measurement(*GRID, truth.brdf(*GRID), quantity="brdf")


def fit(case: str, **kw):
    truth, start, opts = CASES[case]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", EnergyWarning)
        return rb.fit(start, measurement(truth), starts=2, progress=False, **opts, **kw)


@pytest.fixture(scope="module", params=list(CASES))
def both(request):
    """``(unconstrained, constrained)`` fits of one case."""
    return fit(request.param, energy_constraint=False), fit(request.param)


def test_unconstrained_fit_gains_energy_constrained_does_not(both):
    off, on = both
    assert rb.albedo(off[0].model, THETA).max() > 1 + ENERGY_TOLERANCE
    albedo = rb.albedo(on[0].model, THETA)
    assert np.all(albedo <= 1 + ENERGY_TOLERANCE), albedo
    info = on[0].energy_constraint
    assert info.satisfied and info.active and 89.0 in info.theta_deg
    assert info.max_albedo == pytest.approx(albedo.max(), abs=1e-12)
    assert not on.gains_energy and off.gains_energy


def test_constrained_fit_does_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error", EnergyWarning)
        res = rb.fit(CASES["tr75"][1], measurement(CASES["tr75"][0]), starts=2, progress=False)
    assert res.options["energy_constraint"] is True
    report = res.report()
    assert "energy constraint active (albedo <= 1) at theta_i = " in report
    assert "89 deg, uncertainties conditional on it" in report


def test_off_is_the_unconstrained_optimum(both):
    """``energy_constraint=False`` ends at the search's own optimum: the best of the local
    fits the constrained fit ran before its refit, to the last digit."""
    off, on = both
    before = [s for s in on[0].starts if s["stage"] != "energy"]
    assert [s["x"] for s in off[0].starts] == [s["x"] for s in before]
    best = min((s for s in before if s["stage"] in ("single", "full")), key=lambda s: s["cost"])
    assert [off[0].params[n] for n in off[0].free] == best["x"]
    assert off[0].energy_constraint is None and off.options["energy_constraint"] is False


def test_a_model_that_conserves_energy_is_not_refitted():
    truth = rb.model("microfacet", alpha=0.3, n=1.5, ks=1.0)
    meas = measurement(truth)
    on = rb.fit("microfacet", meas, starts=2, progress=False)
    off = rb.fit("microfacet", meas, starts=2, progress=False, energy_constraint=False)
    assert on[0].energy_constraint is None and on.params == off.params


@pytest.mark.parametrize("model", [
    rb.model("lambertian", rho=0.7), rb.model("oren-nayar"), rb.model("ts67"),
    rb.model("tr75"), rb.model("tr75", e=0.02, n=1.5, k=0.0, rho_L=0.1), rb.model("coated"),
    rb.model("microfacet", alpha=0.05), rb.model("rb08"),
    rb.model("tr75") + rb.model("lambertian")], ids=model_label)
def test_fast_albedo_agrees_with_albedo(model):
    assert np.abs(fast_albedo(model) - rb.albedo(model, THETA)).max() <= FAST_ALBEDO_ACCURACY


@pytest.mark.parametrize("bad", ["no", 1, None])
def test_bad_option_is_named(bad):
    with pytest.raises(ArgumentError, match="energy_constraint"):
        FitOptions(energy_constraint=bad)
    with pytest.raises(ArgumentError, match="energy_constraint"):
        rb.fit("lambertian", measurement(rb.model("lambertian")), energy_constraint=bad)


@pytest.mark.parametrize("verb", ["fit", "compare", "fit-batch"])
def test_cli_help_lists_the_option(verb):
    res = CliRunner().invoke(app, [verb, "--help"], env={"COLUMNS": "250"})
    assert res.exit_code == 0 and "--no-energy-constraint" in res.output, res.output


@pytest.fixture(scope="module")
def data_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("energy") / "gain.csv"
    rb.write(measurement(CASES["tr75"][0]), path)
    return path


def test_cli_constrained_exits_0_and_records_it(data_file, tmp_path, capsys):
    out = tmp_path / "on"
    code = main(["fit", str(data_file), "--model", "tr75", "--starts", "2", "--no-plots",
                 "--out", str(out), "-q"])
    assert code == 0, capsys.readouterr().err
    content = json.loads((out / "fit.json").read_text())
    (ch,) = content["channels"]
    assert content["options"]["energy_constraint"] is True
    assert ch["energy_constraint"]["active"] is True and ch["gains_energy"] is False
    assert 89.0 in ch["energy_constraint"]["theta_deg"]
    assert ch["energy_constraint"]["max_albedo"] <= 1 + ENERGY_TOLERANCE
    assert "energy constraint active" in (out / "report.txt").read_text()


def test_cli_off_gains_energy_and_exits_1(data_file, tmp_path, capsys):
    out = tmp_path / "off"
    code = main(["fit", str(data_file), "--model", "tr75", "--starts", "2", "--no-plots",
                 "--out", str(out), "-q", "--no-energy-constraint"])
    assert code == 1 and "reflects more than it receives" in capsys.readouterr().err
    content = json.loads((out / "fit.json").read_text())
    (ch,) = content["channels"]
    assert content["options"]["energy_constraint"] is False
    assert ch["energy_constraint"] is None and ch["gains_energy"] is True


def test_fit_batch_passes_the_option_on(data_file, tmp_path):
    out = tmp_path / "cat"
    assert main(["fit-batch", str(data_file), "--model", "tr75", "--out", str(out), "--starts",
                 "2", "--no-plots", "--workers", "1", "-q", "--no-energy-constraint"]) == 1
    (row,) = json.loads((out / "catalogue.json").read_text())["rows"]
    assert row["status"] == "gains-energy"
    (fit_json,) = out.glob("*/fit.json")
    assert json.loads(fit_json.read_text())["options"]["energy_constraint"] is False


def test_uncertainties_are_conditional_on_the_active_constraint(both):
    """At the constrained optimum the covariance gives the active albedo (89 deg, pinned at 1
    by the constraint) no uncertainty: ``sqrt(g^T C g)`` below 1e-3, ``g`` its gradient."""
    _, on = both
    c = on[0]
    assert "uncertainties conditional on it" in c.message
    names = list(c.free)
    free = [i for i in range(len(names)) if np.isfinite(c.covar[i, i])]
    if not free:  # RB08 here: rho and w have no effect at n_eff = 1, J^T J is singular
        assert "covariance not estimated" in c.message
        return
    k = list(EXPORT_INCIDENCES_DEG).index(89)
    theta = np.array([c.params[n] for n in names])
    g = np.zeros(len(names))
    for i in free:
        h = 1e-5 * max(abs(theta[i]), 1e-3)
        up, down = (c.model.with_values(names, list(theta + s * h * np.eye(len(names))[i]))
                    for s in (1, -1))
        g[i] = (fast_albedo(up)[k] - fast_albedo(down)[k]) / (2 * h)
    cov = np.nan_to_num(c.covar[:len(names), :len(names)])
    # without the projection sqrt(g^T C g) is 28 (sum) to 870 (tr75)
    assert np.abs(g).max() > 0.01 and math.sqrt(abs(g @ cov @ g)) < 1e-3, (g, cov)


def test_tr75_on_the_shared_paints_keeps_albedo_below_1(paints):
    """TR75 with TR75's loss (``relative``) on the three Mini-Diff paints: C2_Black's
    unconstrained fit reflects 1.26 at 89 deg; under the constraint no channel exceeds
    1 + 1e-3 on the grid."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", EnergyWarning)
        off = rb.fit("tr75", paints["C2_Black"], progress=False, energy_constraint=False,
                     loss="relative")
    assert max(rb.albedo(c.model, THETA).max() for c in off) > 1 + ENERGY_TOLERANCE
    for name, meas in paints.items():
        res = rb.fit("tr75", meas, progress=False, loss="relative")
        for c in res:
            albedo = rb.albedo(c.model, THETA)
            assert np.all(albedo <= 1 + ENERGY_TOLERANCE), (name, c.channel, albedo.max())


@pytest.mark.parametrize(("spec", "expected"), [
    ("coated", True), ("coated(lobes=3, diffuse=oren-nayar)", True),
    ("coated(weights=free)", False), ("lambertian", True), ("tr75", False),
    ("coated-conductor", True), ("metallic(diffuse=true)", True),
    ("microfacet", False), ("rb08", False)])
def test_conserves_energy_says_what_the_construction_guarantees(spec, expected):
    # True only where docs/models.md §10.4 proves it (coated: tests/models/test_coated_energy.py's
    # Hypothesis test over the whole domain; Lambertian: albedo = rho <= 1); a sum never
    assert rb.model(spec).conserves_energy is expected
    assert (rb.model(spec) + rb.model("lambertian")).conserves_energy is False


def test_a_model_that_conserves_energy_by_construction_skips_the_check(monkeypatch):
    import roughbrdf.fitting.energy as energy

    def fail(model):
        raise AssertionError("checked_albedo called for an energy-conserving model")

    monkeypatch.setattr(energy, "checked_albedo", fail)
    truth = rb.model("coated", alpha=0.2, rho=0.3)
    res = rb.fit("coated", measurement(truth), starts=1, progress=False)
    assert res[0].energy_constraint is None and not res.gains_energy
