"""``roughbrdf plot``: model plots of every kind, --fit DIR, no overwriting without --force."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

import roughbrdf as rb
from roughbrdf import io as rbio
from roughbrdf.cli import app
from roughbrdf.measurement import Measurement

runner = CliRunner()
PNG = b"\x89PNG\r\n\x1a\n"


def _ok(args):
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    return res


@pytest.mark.parametrize("kind,extra", [
    ("in-plane", ["--theta-i", "0:60:30", "--log"]),
    ("polar", ["--theta-i", "45", "--elevation", "30"]),
    ("hemisphere", ["--theta-i", "30", "--quantity", "bridf"]),
])
def test_plot_model_kinds(tmp_path, kind, extra):
    out = tmp_path / f"{kind}.png"
    res = _ok(["plot", "trowbridge-reitz-1975", "-p", "e=0.3", "-p", "n=1.5", "-p", "k=0",
               "-p", "rho_L=0.1", "--kind", kind, *extra, "--out", str(out)])
    assert str(out) in res.output
    assert out.read_bytes()[:8] == PNG and out.stat().st_size > 1000


def test_plot_ts67_relative_with_none_index(tmp_path):
    out = tmp_path / "ts.png"
    _ok(["plot", "ts67", "-p", "n=None", "--quantity", "relative", "--theta-i", "10:75:15",
         "--out", str(out)])
    assert out.stat().st_size > 0


def test_plot_never_overwrites_without_force(tmp_path):
    out = tmp_path / "a.png"
    out.write_bytes(b"keep")
    res = runner.invoke(app, ["plot", "lambertian", "--out", str(out)])
    assert res.exit_code == 2 and "--force" in res.output
    assert out.read_bytes() == b"keep"
    _ok(["plot", "lambertian", "--out", str(out), "--force"])
    assert out.read_bytes()[:8] == PNG


@pytest.mark.parametrize("args,message", [
    (["plot", "lambertian", "--kind", "contour", "--out", "x.png"], "--kind"),
    (["plot", "lambertian", "--out", "x.pdf"], ".png"),
    (["plot", "lambertian"], "--out"),
    (["plot", "no-such-model", "--out", "x.png"], "unknown model"),
    (["plot", "lambertian", "--kind", "polar", "--theta-i", "0:40:20", "--out", "x.png"],
     "one --theta-i"),
    (["plot", "lambertian", "--quantity", "radiance", "--out", "x.png"], "--quantity"),
    (["plot"], "MODEL"),
])
def test_plot_errors(tmp_path, monkeypatch, args, message):
    monkeypatch.chdir(tmp_path)
    res = runner.invoke(app, args)
    assert res.exit_code == 2
    assert message in res.output
    assert not (tmp_path / "x.png").exists()


# ---------------------------------------------------------------------------------------------
# --fit DIR
# ---------------------------------------------------------------------------------------------
def _fit_dir(tmp_path, *, spec=True, channels=("465nm", "630nm"), quantity="brdf"):
    m = rb.model("trowbridge-reitz-1975", e=0.5, n=1.5, k=0.0, rho_L=0.2)
    ti = np.repeat(np.radians([0.0, 30.0, 60.0]), 30)
    ts = np.tile(np.radians(np.linspace(-80, 80, 30)), 3)
    tr, ph = rb.geometry.from_signed_angle(ts)
    v = m.brdf(ti, tr, ph)
    meas = Measurement(ti, tr, ph, np.column_stack([v, 1.1 * v]), channels=list(channels),
                       quantity=quantity)
    data = tmp_path / "data.csv"
    rbio.write(meas, data)
    fit_dir = tmp_path / "fit"
    fit_dir.mkdir()
    chans = []
    for c in channels:
        entry = {"channel": c, "params": m.params, "stderr": {}, "success": True,
                 "metrics": {"sigma": 0.0}}
        if spec:
            entry["model_spec"] = m.to_dict()
        chans.append(entry)
    fit = {"model": m.name, "file": str(data), "loss": "relative", "quantity": quantity,
           "channels": chans}
    (fit_dir / "fit.json").write_text(json.dumps(fit))
    return fit_dir


def test_plot_fit_writes_one_file_per_channel(tmp_path):
    fit_dir = _fit_dir(tmp_path)
    res = _ok(["plot", "--fit", str(fit_dir)])
    for c in ("465nm", "630nm"):
        p = fit_dir / f"comparison_{c}.png"
        assert p.exists() and p.read_bytes()[:8] == PNG, res.output
    res = runner.invoke(app, ["plot", "--fit", str(fit_dir)])
    assert res.exit_code == 2 and "--force" in res.output
    _ok(["plot", "--fit", str(fit_dir), "--force"])


def test_plot_fit_draws_through_the_fits_aperture(tmp_path, monkeypatch):
    # a fit made with an instrument aperture is drawn the way it was compared with the data
    import math

    from roughbrdf import plot as rbplot

    fit_dir = _fit_dir(tmp_path)
    fit = json.loads((fit_dir / "fit.json").read_text())
    fit["aperture"] = {"half_angle_rad": math.radians(2.0), "half_angle_deg": 2.0, "points": 7}
    (fit_dir / "fit.json").write_text(json.dumps(fit))
    seen = []
    for name in ("plot_comparison", "plot_residual_map"):
        real = getattr(rbplot, name)

        def spy(*args, _real=real, **kw):
            seen.append(kw.get("aperture"))
            return _real(*args, **kw)

        monkeypatch.setattr(rbplot, name, spy)
    _ok(["plot", "--fit", str(fit_dir), "--channel", "465nm"])
    assert len(seen) == 2
    assert all(a.half_angle == pytest.approx(math.radians(2.0)) and a.points == 7 for a in seen)


def test_plot_fit_one_channel_to_out_and_params_only(tmp_path):
    fit_dir = _fit_dir(tmp_path, spec=False)
    out = tmp_path / "cmp.png"
    _ok(["plot", "--fit", str(fit_dir), "--channel", "630nm", "--out", str(out)])
    assert out.read_bytes()[:8] == PNG
    res = runner.invoke(app, ["plot", "--fit", str(fit_dir), "--out", str(tmp_path / "b.png")])
    assert res.exit_code == 2 and "--channel" in res.output
    res = runner.invoke(app, ["plot", "--fit", str(fit_dir), "--channel", "999nm",
                              "--out", str(tmp_path / "c.png")])
    assert res.exit_code == 2 and "999nm" in res.output


def test_plot_fit_errors(tmp_path):
    res = runner.invoke(app, ["plot", "--fit", str(tmp_path)])
    assert res.exit_code == 2 and "fit.json" in res.output
    (tmp_path / "fit.json").write_text("{not json")
    res = runner.invoke(app, ["plot", "--fit", str(tmp_path)])
    assert res.exit_code == 2 and "JSON" in res.output
    (tmp_path / "fit.json").write_text(json.dumps({"model": "lambertian", "channels": []}))
    res = runner.invoke(app, ["plot", "--fit", str(tmp_path)])
    assert res.exit_code == 2 and "'file'" in res.output
    (tmp_path / "fit.json").write_text(json.dumps(
        {"model": "lambertian", "file": str(tmp_path / "gone.csv"), "channels": [{}]}))
    res = runner.invoke(app, ["plot", "--fit", str(tmp_path)])
    assert res.exit_code == 2 and "gone.csv" in res.output
    res = runner.invoke(app, ["plot", "lambertian", "--fit", str(tmp_path)])
    assert res.exit_code == 2 and "not both" in res.output


# ---------------------------------------------------------------------------------------------
# --fit DIR from any folder, a changed input, the fit's set
# ---------------------------------------------------------------------------------------------
def _sha(path) -> str:
    import hashlib

    return hashlib.sha256(path.read_bytes()).hexdigest()


def _record_input(fit_dir, **keys):
    fit = json.loads((fit_dir / "fit.json").read_text())
    fit.update(keys)
    (fit_dir / "fit.json").write_text(json.dumps(fit))


def test_plot_fit_from_any_folder(tmp_path, monkeypatch):
    fit_dir = _fit_dir(tmp_path)
    data = tmp_path / "data.csv"
    # as `roughbrdf fit data.csv` run in tmp_path records it
    _record_input(fit_dir, file="data.csv", file_abspath=str(data), file_sha256=_sha(data))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    res = _ok(["plot", "--fit", str(fit_dir), "--channel", "465nm"])
    assert "warning" not in res.output
    assert (fit_dir / "comparison_465nm.png").read_bytes()[:8] == PNG
    # a different data.csv in the current folder: the recorded one (same SHA-256) wins
    (elsewhere / "data.csv").write_text(data.read_text().replace("465nm", "465nm "))
    res = _ok(["plot", "--fit", str(fit_dir), "--channel", "630nm"])
    assert "warning" not in res.output


def test_plot_fit_warns_when_the_input_changed(tmp_path):
    fit_dir = _fit_dir(tmp_path)
    data = tmp_path / "data.csv"
    _record_input(fit_dir, file_abspath=str(data), file_sha256="0" * 64)
    res = _ok(["plot", "--fit", str(fit_dir), "--channel", "465nm"])
    lines = [ln for ln in res.stderr.splitlines() if ln.startswith("warning")]
    assert len(lines) == 1 and str(data) in lines[0] and "changed since the fit" in lines[0]
    _record_input(fit_dir, file_sha256=_sha(data))
    res = _ok(["plot", "--fit", str(fit_dir), "--channel", "630nm"])
    assert "warning" not in res.output


def test_plot_fit_adds_its_figures_to_the_fits_results(tmp_path):
    from roughbrdf.output import MANIFEST

    fit_dir = _fit_dir(tmp_path)
    (fit_dir / MANIFEST).write_text(json.dumps(["fit.json"]))
    _ok(["plot", "--fit", str(fit_dir)])
    # the manifest maps each name to its SHA-256 (an old-format list is still read)
    assert sorted(json.loads((fit_dir / MANIFEST).read_text())) == [
        "comparison_465nm.png", "comparison_630nm.png", "fit.json"]
    # a figure the user made under that name is never replaced, not even with --force
    (fit_dir / "comparison_465nm.png").unlink()
    (fit_dir / MANIFEST).write_text(json.dumps(["comparison_630nm.png", "fit.json"]))
    (fit_dir / "comparison_465nm.png").write_bytes(b"mine")
    res = runner.invoke(app, ["plot", "--fit", str(fit_dir), "--force"])
    assert res.exit_code == 2 and "not overwriting comparison_465nm.png" in res.output
    assert (fit_dir / "comparison_465nm.png").read_bytes() == b"mine"


@pytest.mark.parametrize("spelling", ["BRDF", "brdf-cos", "brdf*cos", "bridf", "Relative"])
def test_plot_quantity_takes_every_spelling(tmp_path, spelling):
    out = tmp_path / "sub" / "q.png"  # the folder is created
    _ok(["plot", "lambertian", "--quantity", spelling, "--theta-i", "30", "--out", str(out)])
    assert out.read_bytes()[:8] == PNG


def test_plot_errors_name_options_in_degrees(tmp_path):
    res = runner.invoke(app, ["plot", "tr75", "--kind", "hemisphere", "--theta-i", "95",
                              "--out", str(tmp_path / "x.png")])
    assert res.exit_code == 2 and "--theta-i 95 (degrees)" in res.output
    assert not (tmp_path / "x.png").exists()
