"""Plausibility in every output: the fitted model's albedo by incidence and its model/data peak
ratio per measured incidence (``fit.json``, report, ``compare``); a model that reflects more
than it receives warns (:class:`EnergyWarning`), exits 1 at the CLI and is not exported
without ``allow_energy_gain`` / ``--allow-energy-gain``, which the file then records. Old
``fit.json`` files without these keys still plot and export."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.cli import main
from roughbrdf.errors import ArgumentError
from roughbrdf.fitting.results.plausibility import ALBEDO_INCIDENCES_DEG, EnergyWarning
from roughbrdf.journal import MANIFEST

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

GRID = np.radians(np.mgrid[0:61:30, 0:81:10, 0:181:45].reshape(3, -1))
# ks inside its search range [0, 1]: a fit that ends on its bound 1 is on a search limit
TRUTH = rb.model("microfacet", alpha=0.3, n=1.5, ks=0.8)
#: the new keys of a channel of fit.json
NEW_KEYS = ("limits", "albedo", "max_albedo", "gains_energy", "peak_ratio")


@pytest.fixture(scope="module")
def data_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("energy") / "gloss.csv"
    rb.write(rb.Measurement(*GRID, TRUTH.brdf(*GRID), quantity="brdf"), path)
    return path


@pytest.fixture(scope="module")
def gaining_fit(data_file, tmp_path_factory):
    """``roughbrdf fit`` of the microfacet model with its specular scale fixed at 30: a
    model that reflects more than it receives at grazing incidence (without the energy
    constraint, which would refit it to albedo <= 1: tests/fitting/test_energy_constraint.py)."""
    out = tmp_path_factory.mktemp("fits") / "gain"
    code = main(["fit", str(data_file), "--model", "microfacet", "-p", "ks=30", "--fix", "ks",
                 "--starts", "2", "--no-plots", "--out", str(out), "-q",
                 "--no-energy-constraint"])
    return code, out


def test_energy_gain_warns_in_python(data_file):
    meas = rb.read(data_file)
    with pytest.warns(EnergyWarning, match=r"reflects more than it receives: albedo 1\.\d+ at "
                                           r"theta_i = 85 deg"):
        res = rb.fit(rb.model("microfacet", ks=30.0), meas, fix=["ks"], starts=2,
                     progress=False, energy_constraint=False)
    assert issubclass(EnergyWarning, UserWarning) and res.gains_energy
    with warnings.catch_warnings():  # a plausible fit: no warning
        warnings.simplefilter("error", EnergyWarning)
        ok = rb.fit("microfacet", meas, starts=2, progress=False)
    assert not ok.gains_energy and ok.plausibility().max_albedo < 1


def test_energy_gain_exits_1_with_one_warning_line(gaining_fit, capsys):
    code, out = gaining_fit
    assert code == 1
    (ch,) = json.loads((out / "fit.json").read_text())["channels"]
    albedo = dict(zip(ch["albedo"]["theta_i_deg"], ch["albedo"]["value"], strict=True))
    assert list(albedo) == list(ALBEDO_INCIDENCES_DEG)
    assert albedo[85] > 1 and albedo[0] < 1 and ch["gains_energy"] is True
    assert ch["max_albedo"] == max(albedo.values())
    report = (out / "report.txt").read_text()
    assert "[[Plausibility]]" in report and "GAINS ENERGY" in report


def test_cli_warning_line(data_file, tmp_path, capsys):
    code = main(["fit", str(data_file), "--model", "microfacet", "-p", "ks=30", "--fix", "ks",
                 "--starts", "2", "--no-plots", "--out", str(tmp_path / "o"), "-q",
                 "--no-energy-constraint"])
    err = capsys.readouterr().err
    lines = [x for x in err.splitlines() if x.startswith("warning:")]
    assert code == 1 and len(lines) == 1
    assert "reflects more than it receives" in lines[0] and "85 deg" in lines[0]


def test_albedo_and_peak_ratio_are_what_they_say(data_file):
    """fit.json's albedo is rb.albedo of the fitted model; the peak ratio is max(model) /
    max(K x) over each incidence's fitted samples (here with a free scale K ~ 2)."""
    meas = rb.read(data_file)
    half = rb.Measurement(meas.theta_i, meas.theta_r, meas.phi, 0.5 * meas.values,
                          quantity="brdf")
    res = rb.fit("microfacet", half, starts=2, progress=False, free_scale=True,
                 theta_r_max=np.radians(70.0))
    (ch,) = res.to_dict()["channels"]
    c = res[0]
    expected = rb.albedo(c.model, np.radians(ALBEDO_INCIDENCES_DEG))
    assert ch["albedo"]["value"] == pytest.approx(list(expected), rel=1e-12, abs=0)
    # a lone lobe's ks and K are one degree of freedom (docs/fitting.md): K x = ks f_1
    assert c.scale == pytest.approx(c.params["ks"] / (0.5 * TRUTH.params["ks"]), rel=1e-3)
    ti, tr, ph = half.theta_i[c.index], half.theta_r[c.index], half.phi[c.index]
    model = np.asarray(c.model.brdf(ti, tr, ph))
    data = c.scale * half.values[c.index, 0]
    by_hand = {float(np.degrees(t)): float(model[ti == t].max() / data[ti == t].max())
               for t in np.unique(ti)}
    got = dict(zip(ch["peak_ratio"]["theta_i_deg"], ch["peak_ratio"]["value"], strict=True))
    assert list(got) == pytest.approx(list(by_hand))
    assert list(got.values()) == pytest.approx(list(by_hand.values()), rel=1e-9)


def test_compare_shows_albedo_and_peak_ratio(data_file, capsys):
    code = main(["compare", str(data_file), "--models", "microfacet", "--starts", "2",
                 "--no-cv"])
    out = capsys.readouterr().out
    assert code == 0
    header = next(x for x in out.splitlines() if x.startswith("| model"))
    assert "max albedo" in header and "peak ratio" in header


def test_export_refused_then_overridden_and_recorded(gaining_fit, tmp_path, capsys):
    _, fit_dir = gaining_fit
    target = tmp_path / "gain.bsdf"
    code = main(["export", "--fit", str(fit_dir), "--to", "zemax", "--out", str(target)])
    err = capsys.readouterr().err
    assert code != 0 and not target.exists()
    assert "reflects more than it receives: albedo 1.8" in err and "89 deg" in err
    assert "--allow-energy-gain" in err
    code = main(["export", "--fit", str(fit_dir), "--to", "zemax", "--out", str(target),
                 "--allow-energy-gain"])
    assert code == 0, capsys.readouterr().err
    (written,) = tmp_path.glob("gain*.bsdf")
    header = [x for x in written.read_text().splitlines() if x.startswith("#")]
    assert any("allow_energy_gain" in x and "reflects more than it receives" in x
               for x in header)


def test_export_in_python_and_mitsuba_record():
    m = rb.model("microfacet", distribution="ggx", alpha=0.3, n=1.5, k=0.0, ks=30.0,
                 shadowing="smith-separable")
    from roughbrdf.export.mitsuba import export_mitsuba

    with pytest.raises(ArgumentError, match=r"albedo .* at theta_i = 89 deg .*"
                                            r"allow_energy_gain=True"):
        export_mitsuba(m)
    done = export_mitsuba(m, allow_energy_gain=True)
    assert done.note_lines() and "allow_energy_gain" in done.note_lines()[0]
    assert "<!-- allow_energy_gain" in done.xml()


def test_mitsuba_files_record_the_override(tmp_path, capsys):
    args = ["microfacet", "-p", "distribution=ggx", "-p", "alpha=0.3", "-p", "n=1.5", "-p",
            "k=0", "-p", "ks=30", "-p", "shadowing=smith-separable"]
    xml = tmp_path / "gain.xml"
    assert main(["export", *args, "--to", "mitsuba-xml", "--out", str(xml)]) != 0
    assert not xml.exists() and "--allow-energy-gain" in capsys.readouterr().err
    assert main(["export", *args, "--to", "mitsuba-xml", "--out", str(xml),
                 "--allow-energy-gain"]) == 0
    assert xml.read_text().startswith("<!-- allow_energy_gain: exported although")
    js = tmp_path / "gain.json"
    assert main(["export", *args, "--to", "mitsuba", "--out", str(js),
                 "--allow-energy-gain"]) == 0
    doc = json.loads(js.read_text())
    assert "reflects more than it receives" in doc.pop("roughbrdf_allow_energy_gain")[0]
    assert doc["type"] == "roughconductor"


def test_old_fit_json_still_plots_and_exports(data_file, tmp_path, capsys):
    out = tmp_path / "fit"
    assert main(["fit", str(data_file), "--model", "microfacet", "--starts", "2",
                 "--no-plots", "--out", str(out), "-q"]) == 0
    path = out / "fit.json"
    content = json.loads(path.read_text())
    for ch in content["channels"]:  # as an older roughbrdf wrote it
        for key in NEW_KEYS:
            del ch[key]
    path.write_text(json.dumps(content))
    (out / MANIFEST).unlink()  # an older roughbrdf wrote no manifest (a folder of then)
    assert main(["plot", "--fit", str(out), "--out", str(tmp_path / "p.png")]) == 0, \
        capsys.readouterr()
    assert (tmp_path / "p.png").read_bytes().startswith(b"\x89PNG")
    assert main(["export", "--fit", str(out), "--to", "zemax", "--out",
                 str(tmp_path / "old.bsdf")]) == 0, capsys.readouterr()
    assert list(tmp_path.glob("old*.bsdf"))
