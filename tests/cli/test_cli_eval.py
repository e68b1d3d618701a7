"""CLI: ``roughbrdf models`` and ``roughbrdf eval`` (degrees at this edge, CSV out)."""

from __future__ import annotations

import csv
import io
import math

import numpy as np
import pytest
from typer.testing import CliRunner

import roughbrdf as rb
from roughbrdf.cli import app

runner = CliRunner()


def run(*args):
    return runner.invoke(app, list(args))


def rows(output: str) -> list[dict[str, str]]:
    return list(csv.DictReader(io.StringIO(output)))


def test_models_lists_every_model_with_units():
    res = run("models")
    assert res.exit_code == 0, res.output
    for name in rb.available():
        assert name in res.output
        for p in rb.model(name).parameters:
            assert p.name in res.output
    assert "[1/deg]" in res.output  # TS67 c is per degree (docs/models.md §2.3)


def test_eval_tr75_matches_library():
    res = run("eval", "trowbridge-reitz-1975", "-p", "e=0.68", "-p", "n=1.0", "-p", "k=0.9",
              "-p", "rho_L=0.33", "--theta-i", "45", "--theta-r", "0:90:15", "--phi", "0:180:90",
              "--quantity", "bridf")
    assert res.exit_code == 0, res.output
    table = rows(res.stdout)
    assert list(table[0]) == ["theta_i_deg", "theta_r_deg", "phi_deg", "bridf"]
    assert len(table) == 7 * 3  # theta_r 0..90 step 15 (stop inclusive) x phi 0, 90, 180
    m = rb.model("tr75", e=0.68, n=1.0, k=0.9, rho_L=0.33)
    for r in table:
        expected = m.bridf(math.radians(float(r["theta_i_deg"])),
                           math.radians(float(r["theta_r_deg"])),
                           math.radians(float(r["phi_deg"])))
        assert float(r["bridf"]) == pytest.approx(expected, rel=1e-9)
    # docs/models.md §3.12 cement sample: beta = 45, elevation 45, TR75 psi = 180 (phi = 0): 0.1233
    one = [r for r in table if r["theta_r_deg"] == "45" and r["phi_deg"] == "0"][0]
    assert float(one["bridf"]) == pytest.approx(0.1233, abs=5e-5)


def test_eval_ts67_f_equal_one_and_default_quantity():
    # TS67 Fig. 8 setting (F = 1 via n=None); brdf is the default quantity
    res = run("eval", "ts67", "-p", "g=0.6667", "-p", "c=0.05", "-p", "n=None",
              "--theta-i", "75", "--theta-r", "80")
    assert res.exit_code == 0, res.output
    (r,) = rows(res.stdout)
    ts = rb.model("ts67", g=0.6667, c=0.05, n=None)
    assert float(r["brdf"]) == pytest.approx(ts.brdf(math.radians(75), math.radians(80), 0.0),
                                             rel=1e-9)


def test_eval_options_and_polarization():
    res = run("eval", "microfacet", "-p", "distribution=ggx", "-p", "shadowing=v-groove",
              "-p", "alpha=0.2", "--theta-i", "30", "--theta-r", "10:50:20",
              "--polarization", "s")
    assert res.exit_code == 0, res.output
    m = rb.model("microfacet", distribution="ggx", shadowing="v-groove", alpha=0.2)
    got = [float(r["brdf"]) for r in rows(res.stdout)]
    expected = m.brdf(math.radians(30), np.radians([10, 30, 50]), 0.0, polarization="s")
    np.testing.assert_allclose(got, expected, rtol=1e-9)
    # a number is the polarization angle gamma in degrees
    res = run("eval", "tr75", "--theta-i", "40", "--theta-r", "30", "--phi", "60",
              "--polarization", "90")
    (r,) = rows(res.stdout)
    assert float(r["brdf"]) == pytest.approx(
        rb.model("tr75").brdf(math.radians(40), math.radians(30), math.radians(60), "s"),
        rel=1e-9)


def test_eval_horizon_gives_inf_for_unshadowed_tr75():
    res = run("eval", "tr75", "--theta-i", "30", "--theta-r", "90")
    assert res.exit_code == 0
    assert rows(res.stdout)[0]["brdf"] == "inf"


@pytest.mark.parametrize("args, needles", [
    (["eval", "trowbridge-reits"], ["did you mean 'trowbridge-reitz-1975'"]),
    (["eval", "tr75", "-p", "bogus=1"], ["unknown parameter"]),
    (["eval", "tr75", "-p", "e=-1"], ["'e'", "-1.0"]),
    (["eval", "tr75", "-p", "k=-0.5"], ["'k'", "-0.5"]),
    (["eval", "ts67", "-p", "c=0"], ["'c'", "0.0"]),
    # angles are named as the options and shown in degrees
    (["eval", "tr75", "--theta-i", "90"], ["--theta-i 90 (degrees)"]),
    (["eval", "tr75", "--theta-r", "95"], ["--theta-r 95 (degrees)"]),
    (["eval", "microfacet", "-p", "distribution=bekmann"], ["did you mean 'beckmann'"]),
    (["eval", "tr75", "--quantity", "radiance"], ["--quantity"]),
    (["eval", "tr75", "--polarization", "q"], ["polarization"]),
])
def test_eval_errors(args, needles):
    res = run(*args)
    assert res.exit_code == 2
    for needle in needles:
        assert needle in res.output
    assert len(res.output.strip().splitlines()) == 1  # one line, no traceback


@pytest.mark.parametrize("bad", ["a:b", "0:90", "0:90:0", "50:10:5"])
def test_eval_bad_ranges(bad):
    res = run("eval", "tr75", "--theta-r", bad)
    assert res.exit_code == 2
    assert "--theta-r" in res.output


def test_models_lists_aliases():
    res = run("models")
    assert res.exit_code == 0, res.output
    assert "  aliases: tr75, trowbridge-reitz" in res.output
    assert "  aliases: ts67, torrance-sparrow" in res.output
    for name in rb.available():
        block = res.output.split(name + "  (", 1)[1].split("\n\n", 1)[0]
        for alias in type(rb.model(name)).aliases:
            assert alias in block


@pytest.mark.parametrize("spelling", ["BRDF_COS", "brdf-cos", "brdf*cos", "bridf"])
def test_eval_quantity_spellings(spelling):
    res = run("eval", "tr75", "--theta-i", "30", "--theta-r", "40", "--quantity", spelling)
    assert res.exit_code == 0, res.output
    (r,) = rows(res.stdout)
    assert float(r[spelling]) == pytest.approx(
        rb.model("tr75").bridf(math.radians(30), math.radians(40), 0.0), rel=1e-9)
