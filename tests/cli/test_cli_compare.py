"""``roughbrdf compare FILE --models ...`` and ``roughbrdf fit --model auto / --models /
--joint / --shared`` (:mod:`roughbrdf.cli.compare`, :mod:`roughbrdf.cli.fit`).

The input is an ASTM file written here from the coated model (``docs/models.md`` §10.3;
``n = 1.5``, ``alpha = 0.15``, one lobe of weight 1, one reflectance per channel: 0.1, 0.3,
0.6) with 2 % noise, so the true model is known: the comparison must rank it first. The numbers
checked are those the library's own ``rb.compare`` / ``rb.fit`` give on the same file
(tests/fitting/test_compare.py and tests/fitting/test_joint.py test those against independent
computations).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

import roughbrdf as rb
from roughbrdf.cli import app

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

runner = CliRunner()
RHOS = {"b": 0.1, "g": 0.3, "r": 0.6}
MODELS = "lambertian, coated"


def _run(*args):
    return runner.invoke(app, [*map(str, args)])


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """``one.astm`` (channel g alone) and ``three.astm`` (b, g, r)."""
    d = tmp_path_factory.mktemp("input")
    g = list(np.radians(np.mgrid[10:61:25, 0:81:8, 0:181:45].reshape(3, -1)))
    clean = np.stack([rb.model("coated", n=1.5, rho=r, alpha=0.15).brdf(*g)
                      for r in RHOS.values()], axis=1)
    vals = clean * (1 + 0.02 * np.random.default_rng(1).standard_normal(clean.shape))
    rb.write(rb.Measurement(*g, vals, channels=list(RHOS)), d / "three.astm")
    rb.write(rb.Measurement(*g, vals[:, 1:2], channels=["g"]), d / "one.astm")
    return {"one": d / "one.astm", "three": d / "three.astm"}


# ------------------------------------------------------------------------------------------
# roughbrdf compare
# ------------------------------------------------------------------------------------------
def test_compare_writes_the_three_files(files, tmp_path):
    out = tmp_path / "cmp"
    res = _run("compare", files["one"], "--models", MODELS, "--starts", 2, "--out", out)
    assert res.exit_code == 0, res.output
    assert res.output.startswith("| model | k | sigma | rms-log | dBIC | dAIC | CV |")
    assert "wrote " in res.output
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == [
        "compare.json", "compare.md", "compare.png"]
    d = json.loads((out / "compare.json").read_text())
    assert d["best"] == d["best_cv"] == "coated" and d["criterion"] == "cv"
    assert [r["model"] for r in d["candidates"]] == ["coated", "lambertian"]
    assert all(r["cv"] is not None for r in d["candidates"])
    # the same figures as the library's comparison of the same file
    lib = rb.compare(rb.read(files["one"]), MODELS, starts=2)
    for row, cand in zip(d["candidates"], lib.candidates, strict=True):
        assert row["bic"] == pytest.approx(cand.bic, rel=1e-9)
        assert row["cv"] == pytest.approx(cand.cv, rel=1e-9)
    md = (out / "compare.md").read_text()
    assert md.startswith("# Model comparison: ") and "| coated | 3 |" in md
    assert (out / "compare.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_compare_without_out_writes_nothing(files, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    res = _run("compare", files["one"], "--models", MODELS, "--starts", 1, "--no-cv")
    assert res.exit_code == 0, res.output
    assert "| coated | 3 |" in res.output and "wrote" not in res.output
    assert list(tmp_path.iterdir()) == []


def test_compare_refuses_an_existing_result_set_without_force(files, tmp_path):
    out = tmp_path / "cmp"
    args = ("compare", files["one"], "--models", MODELS, "--starts", 1, "--no-cv", "--out", out)
    assert _run(*args).exit_code == 0
    before = (out / "compare.json").read_text()
    res = _run(*args)
    assert res.exit_code == 2 and "--force" in res.output
    assert (out / "compare.json").read_text() == before
    # --force replaces the whole set: without plots, the old compare.png goes too
    res = _run(*args, "--force", "--no-plots")
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == [
        "compare.json", "compare.md"]


@pytest.mark.parametrize("spec, needle", [
    ("coated(lobes=2", "bad model spec"),
    ("lambertian, nosuch", "unknown model 'nosuch'"),
    ("coated(bogus=1)", "'bogus'"),
])
def test_compare_bad_models_spec(files, tmp_path, spec, needle):
    out = tmp_path / "bad"
    res = _run("compare", files["one"], "--models", spec, "--out", out)
    assert res.exit_code == 2, res.output
    assert "--models" in res.output and needle in res.output
    assert "Traceback" not in res.output
    assert not out.exists()


def test_compare_joint(files, tmp_path):
    out = tmp_path / "joint"
    res = _run("compare", files["three"], "--models", MODELS, "--joint", "--no-cv", "--starts",
               1, "--no-plots", "--out", out)
    assert res.exit_code == 0, res.output
    d = json.loads((out / "compare.json").read_text())
    k = {r["model"]: r["k"] for r in d["candidates"]}
    # joint: coated shares n, alpha and has one rho per channel; Lambertian shares nothing
    assert k == {"coated": 2 + 3, "lambertian": 3}


# ------------------------------------------------------------------------------------------
# roughbrdf fit --model auto / --models / --joint / --shared
# ------------------------------------------------------------------------------------------
def test_fit_auto_writes_the_model_choice(files, tmp_path):
    out = tmp_path / "auto"
    res = _run("fit", files["one"], "--model", "auto", "--models", MODELS, "--starts", 2,
               "--no-plots", "-q", "--out", out)
    assert res.exit_code == 0, res.output
    d = json.loads((out / "fit.json").read_text())
    assert d["model"] == "coated" and d["model_choice"]["best"] == "coated"
    assert [r["model"] for r in d["model_choice"]["candidates"]] == ["coated", "lambertian"]
    assert set(d["channels"][0]["params"]) == {"n", "rho", "alpha"}
    assert "[[Model choice]]" in (out / "report.txt").read_text()
    assert not list(out.glob("*.png"))


def test_fit_auto_with_plots_writes_compare_png(files, tmp_path):
    out = tmp_path / "auto"
    res = _run("fit", files["one"], "--model", "auto", "--models", MODELS, "--starts", 1,
               "--no-cv", "-q", "--out", out)
    assert res.exit_code == 0, res.output
    assert (out / "compare.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "fit_g.png").exists()
    d = json.loads((out / "fit.json").read_text())
    assert all(r["cv"] is None for r in d["model_choice"]["candidates"])  # --no-cv


@pytest.mark.parametrize("extra, needle", [
    (["--model", "coated", "--models", "lambertian"], "--models"),
    (["--model", "auto", "-p", "rho=0.2"], "-p/--param"),
    (["--model", "auto", "--fix", "rho"], "--fix"),
    (["--model", "auto", "--bounds", "rho=0:0.5"], "--bounds"),
    (["--model", "auto", "--models", "coated(lobes=2"], "--models"),
])
def test_fit_refuses_what_auto_cannot_take(files, tmp_path, extra, needle):
    out = tmp_path / "refused"
    res = _run("fit", files["one"], *extra, "--starts", 1, "--out", out)
    assert res.exit_code == 2, res.output
    assert needle in res.output and "Traceback" not in res.output
    assert not out.exists()


def test_fit_joint(files, tmp_path):
    out = tmp_path / "joint"
    res = _run("fit", files["three"], "--model", "coated", "--joint", "--starts", 2,
               "--no-plots", "-q", "--out", out)
    assert res.exit_code == 0, res.output
    d = json.loads((out / "fit.json").read_text())
    j = d["options"]["joint"]
    assert j["shared"] == ["n", "alpha"] and j["n_varys"] == 5
    params = [ch["params"] for ch in d["channels"]]
    assert [p["channel"] for p in d["channels"]] == list(RHOS)
    for name in j["shared"]:
        assert len({p[name] for p in params}) == 1
    assert len({p["rho"] for p in params}) == 3
    # the same fit as the library's
    lib = rb.fit("coated", rb.read(files["three"]), joint=True, starts=2, progress=False)
    assert j["chi2"] == pytest.approx(lib.options["joint"]["chi2"], rel=1e-9)
    assert "joint fit, shared: n, alpha" in (out / "report.txt").read_text()


def test_fit_joint_shared_option(files, tmp_path):
    out = tmp_path / "shared"
    res = _run("fit", files["three"], "--model", "coated", "--joint", "--shared", "alpha",
               "--shared", "n", "--starts", 1, "--no-plots", "-q", "--out", out)
    assert res.exit_code == 0, res.output
    j = json.loads((out / "fit.json").read_text())["options"]["joint"]
    assert j["shared"] == ["n", "alpha"] and j["n_varys"] == 2 + 3 * 1


@pytest.mark.parametrize("extra, needles", [
    (["--joint", "--shared", "bogus"], ["--shared bogus", "free: n, rho, alpha"]),
    (["--shared", "alpha"], ["--shared", "only a joint fit shares parameters", "--joint"]),
])
def test_fit_shared_errors(files, tmp_path, extra, needles):
    out = tmp_path / "bad"
    res = _run("fit", files["three"], "--model", "coated", *extra, "--starts", 1, "--out", out)
    assert res.exit_code == 2, res.output
    assert all(n in res.output for n in needles), res.output
    assert not out.exists()


def test_shared_without_joint_points_to_the_joint_option(files, tmp_path):
    res = _run("fit", files["three"], "--model", "coated", "--shared", "alpha", "--starts", 1,
               "--out", tmp_path / "bad")
    assert res.exit_code == 2
    assert "--joint" in res.output and "--shared joint=True" not in res.output
