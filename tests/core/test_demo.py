"""``make demo`` = ``python -m roughbrdf.demo --out out``: tables, then the fit of the embedded
default measurement, with its files in the output folder."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

import roughbrdf as rb
from roughbrdf import demo


def test_embedded_default_measurement_is_tr75_design():
    meas = rb.read(demo.default_measurement_path())
    assert meas.quantity == "relative" and meas.meta["relative_to"] == "bridf"
    assert meas.n_samples == 432  # 6 beta x (5 elevations x 7 azimuths + 1) x 2 polarizations
    assert sorted(round(float(x)) for x in set(meas.polarization.round(6) * 180 / 3.14159265)) \
        == [0, 90]
    assert len(meas.incidences(3)) == 6


@pytest.mark.jit_heavy(reason="the demo fits the cement data: minutes in plain Python")
def test_demo_prints_tables_and_recovers_cement(tmp_path, capsys):
    assert demo.main(["--out", str(tmp_path / "out")]) == 0
    text = capsys.readouterr().out
    # first the paper checks, then the fit
    assert text.index("TS67 Fig. 8") < text.index("TR75 Table 1") < text.index("[[Fit]]")
    assert "Recovered vs true" in text and "TR75 sigma" in text
    out = tmp_path / "out"
    for name in ("fit.json", "report.txt", "fit_relative.png", "ts67_fig8.txt",
                 "tr75_table1_dhr.txt", "recovered.txt"):
        assert (out / name).is_file(), name
    ch = json.loads((out / "fit.json").read_text())["channels"][0]
    for name, truth in demo.TRUE.items():
        assert abs(ch["params"][name] - truth) <= 3 * ch["stderr"][name], name
    assert ch["metrics"]["sigma"] == pytest.approx(0.10, abs=0.02)  # the 10 % noise
    # a second run into the same folder replaces its own files
    assert demo.main(["--out", str(out), "--force"]) == 0


@pytest.mark.jit_heavy(reason="the demo's tables (TR75 albedos): minutes in plain Python")
def test_demo_tables_match_models_md():
    t = demo.ts67_fig8_table()
    for psi, ref in demo.TS67_FIG8.items():
        row = next(r for r in t.splitlines() if r.split()[:1] == [str(psi)])
        left, right = row.split("|")
        vals = [float(v) for v in left.split()[-4:]]
        assert vals[0] == pytest.approx(ref[1], abs=0.005)  # docs/models.md gives 3.19 for psi 75
        assert vals[1:] == pytest.approx(list(ref[2:]), abs=0.0011)
    t = demo.tr75_table1_dhr()
    for name, ref in demo.TR75_TABLE1.items():
        row = next(r for r in t.splitlines() if r.strip().startswith(name))
        interface, total = (float(v) for v in row.split("|")[1].split())
        assert interface == pytest.approx(ref[4], abs=0.0015) and total == pytest.approx(
            ref[5], abs=0.0015)


def test_demo_refuses_foreign_files(tmp_path):
    (tmp_path / "report.txt").write_text("mine")
    with pytest.raises(FileExistsError, match="not overwriting report.txt"):
        demo.main(["--out", str(tmp_path)])
    assert (tmp_path / "report.txt").read_text() == "mine"


def test_demo_refuses_earlier_results_before_any_work(tmp_path, monkeypatch, capsys):
    """`make demo` passes --force for its own out/; without it an earlier result stops
    the run before it computes anything, with one line and exit status 2."""
    from roughbrdf.output import ResultFolder

    with ResultFolder(tmp_path) as out:
        out.add("fit.json", "{}")

    def must_not_run():
        raise AssertionError("computed")

    monkeypatch.setattr(demo, "ts67_fig8_table", must_not_run)
    monkeypatch.setattr(sys, "argv", ["python -m roughbrdf.demo", "--out", str(tmp_path)])
    assert demo._console() == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {tmp_path} holds results already (fit.json)")
    assert "--force" in err and len(err.strip().splitlines()) == 1


def test_make_demo_passes_force():
    makefile = (Path(__file__).parents[2] / "Makefile").read_text()
    assert "$(PY) -m roughbrdf.demo --out out --force" in makefile
