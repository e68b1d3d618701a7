"""``roughbrdf convert IN OUT``: formats, --quantity, --force, and clear errors."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

import roughbrdf as rb
from roughbrdf.cli import app
from roughbrdf.io import merl

runner = CliRunner()

CSV = """# roughbrdf-csv 1
# angles: deg
# quantity: brdf
theta_i,theta_r,phi,465nm,525nm
0,10,0,0.5,0.6
30,30,0,2.0,2.1
30,30,180,-0.001,nan
60,70,90,0.3,0.4
"""


def _run(*args):
    return runner.invoke(app, ["convert", *map(str, args)])


def test_csv_to_alta_to_csv(tmp_path):
    src = tmp_path / "in.csv"
    src.write_text(CSV)
    res = _run(src, tmp_path / "out.dat")
    assert res.exit_code == 0, res.output
    assert "1 non-finite and 0 negative" in res.output and "0 non-finite and 1 negative" in \
        res.output
    res = _run(tmp_path / "out.dat", tmp_path / "back.csv")
    assert res.exit_code == 0, res.output
    a, b = rb.read(src), rb.read(tmp_path / "back.csv")
    assert b.channels == a.channels and b.quantity == "brdf"
    assert np.allclose(b.theta_r, a.theta_r) and np.allclose(np.cos(b.phi), np.cos(a.phi))
    assert np.allclose(b.values, a.values, equal_nan=True)


def test_never_overwrites_without_force(tmp_path):
    src = tmp_path / "in.csv"
    src.write_text(CSV)
    out = tmp_path / "out.csv"
    out.write_text("keep me")
    res = _run(src, out)
    assert res.exit_code == 2 and "exists; pass --force" in res.output
    assert out.read_text() == "keep me"
    res = _run(src, out, "--force", "--angles-out", "rad")
    assert res.exit_code == 0 and "# angles: rad" in out.read_text()


def test_alta_without_param_out_needs_quantity(shared_data, tmp_path):
    src = shared_data / "cea_retro" / "retro-gray-tape.dat"
    out = tmp_path / "gray.csv"
    res = _run(src, out)
    assert res.exit_code == 2
    assert "retro-gray-tape.dat" in res.output and "--quantity" in res.output
    assert not out.exists()
    res = _run(src, out, "--quantity", "brdf_cos", "--as", "brdf")
    assert res.exit_code == 0, res.output
    m = rb.read(out)
    assert m.quantity == "brdf" and m.n_samples == 7405


def test_astm_to_csv(shared_data, tmp_path):
    res = _run(shared_data / "minidiff" / "C12_OliveDrab.astm", tmp_path / "o.csv")
    assert res.exit_code == 0, res.output
    m = rb.read(tmp_path / "o.csv")
    assert m.values.shape == (12964, 3) and m.meta["sample"] == "C12_OliveDrab"
    assert m.meta["source_format"] == "astm"


def test_merl_to_csv_small_grid(tmp_path):
    # a MERL-layout file with a small non-standard grid keeps this test fast
    dims = (8, 8, 16)
    mdl = rb.model("lambertian", rho=0.5)
    table = merl.table_from_model(mdl, dims=dims)
    src = tmp_path / "small.binary"
    merl.write_table(src, table)
    res = _run(src, tmp_path / "m.csv", "--stride", "2")
    assert res.exit_code == 0, res.output
    assert "MERL cells left out" in res.output
    m = rb.read(tmp_path / "m.csv")
    assert np.allclose(m.values, 0.5 / np.pi)


@pytest.mark.parametrize("args, match", [
    (["{d}/nope.csv", "{d}/o.csv"], "no such file"),
    (["{d}/in.csv", "{d}/o.xyz"], "unknown format for extension '.xyz'"),
    (["{d}/in.csv", "{d}/o.csv", "--to", "hdf5"], "unknown format 'hdf5'"),
    (["{d}/in.csv", "{d}/o.csv", "--stride", "2"], "--stride applies to MERL"),
    (["{d}/in.csv", "{d}/o.csv", "--quantity", "radiance"], "--quantity must be one of"),
    (["{d}/bad.csv", "{d}/o.csv"], "bad.csv, line 5: non-numeric field 'x'"),
    (["{d}/in.csv", "{d}/o.binary"], "MERL files hold 3 channels"),
])
def test_errors(tmp_path, args, match):
    (tmp_path / "in.csv").write_text(CSV)
    (tmp_path / "bad.csv").write_text(CSV.replace("0,10,0,0.5,0.6", "0,10,0,x,0.6"))
    res = _run(*[a.format(d=tmp_path) for a in args])
    assert res.exit_code == 2
    assert match in res.output.replace("\n", " ") or match in res.output


def test_out_is_a_folder_or_in_itself(tmp_path):
    """Why: a folder given as OUT ended in an OSError traceback after the work was done."""
    src = tmp_path / "in.csv"
    src.write_text(CSV)
    folder = tmp_path / "outdir"
    folder.mkdir()
    res = _run(src, folder)
    assert res.exit_code == 3 and "is a folder" in res.output
    assert "Traceback" not in res.output and list(folder.iterdir()) == []
    res = _run(src, src, "--force")
    assert res.exit_code == 2 and "same file" in res.output
    assert src.read_text() == CSV


def test_options_that_contradict_the_file_are_refused(tmp_path):
    src = tmp_path / "in.csv"
    src.write_text(CSV)
    res = _run(src, tmp_path / "o.dat", "--quantity", "brdf_cos")
    assert res.exit_code == 2
    assert "--quantity brdf_cos" in res.output and "contradicts" in res.output
    res = _run(src, tmp_path / "o.dat", "--angles-in", "rad")
    assert res.exit_code == 2 and "--angles-in rad" in res.output
    assert not (tmp_path / "o.dat").exists()


def test_os_error_is_one_line_with_exit_3(tmp_path, monkeypatch):
    """A full disk (or any OS error while writing): one line naming OUT and the cause, exit 3,
    no traceback, no file."""
    import errno

    import roughbrdf.output

    src = tmp_path / "in.csv"
    src.write_text(CSV)

    def full(fd):
        raise OSError(errno.ENOSPC, "No space left on device", "/somewhere/.roughbrdf-tmp-x")

    monkeypatch.setattr(roughbrdf.output.os, "fsync", full)
    out = tmp_path / "o.csv"
    res = _run(src, out)
    assert res.exit_code == 3
    assert f"cannot write {out}: No space left on device" in res.output
    assert "Traceback" not in res.output and not out.exists()
    assert [p.name for p in tmp_path.iterdir()] == ["in.csv"]
