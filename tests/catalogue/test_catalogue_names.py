"""Catalogue fit folder names: every input's fit
folder lies inside ``--out``, is distinct from the others (also case-insensitively) and is
never one of the catalogue's own files, whatever the inputs' names; ordinary names are kept.
Run on a real ``dask.distributed`` LocalCluster of worker processes.
"""

from __future__ import annotations

import os

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.catalogue import fit_catalogue, folder_names
from roughbrdf.cli import main

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="catalogues: every row is a whole fit (~40 s or more in plain Python)")

pytest.importorskip("distributed")

#: inputs whose stems are dot-only, collide with each other or with the generated -N names,
#: or equal the catalogue's own entries
AWKWARD = ["..astm", "...csv", "a.astm", "a.csv", "a-2.astm", "A.astm", "catalogue.csv",
           "summary.astm", "catalogue.csv.astm", "catalogue.json.csv", "summary.html.astm",
           "summary.md.csv", ".roughbrdf-lock.csv", ".roughbrdf-outputs.astm", "plain.csv"]
OWN = {"catalogue.csv", "catalogue.json", "summary.md", "summary.html", ".roughbrdf-outputs",
       ".roughbrdf-lock"}


def _measurement() -> rb.Measurement:
    ti, tr, ph = (a.ravel() for a in np.meshgrid(np.radians([20.0, 45.0]),
                                                 np.radians(np.arange(0.0, 80.0, 10.0)),
                                                 [0.0, np.pi], indexing="ij"))
    return rb.Measurement(ti, tr, ph, rb.model("tr75", e=0.6, rho_L=0.2).brdf(ti, tr, ph))


def _inputs(folder, names) -> list[str]:
    folder.mkdir()
    meas = _measurement()
    paths = []
    for name in names:
        p = folder / name
        rb.write(meas, p, format="astm" if name.endswith(".astm") else "csv")
        paths.append(str(p))
    return paths


def _check_folders(out, rows) -> list[str]:
    dirs = [r["fit_dir"] for r in rows]
    assert len(set(d.casefold() for d in dirs)) == len(dirs), dirs
    root = os.path.realpath(out)
    for d in dirs:
        assert d and not set(d) <= {"."} and "/" not in d and os.sep not in d, d
        assert d.casefold() not in {n.casefold() for n in OWN}, d
        assert os.path.dirname(os.path.realpath(out / d)) == root, d
        assert (out / d / "fit.json").is_file(), d
    for own in ("catalogue.csv", "catalogue.json"):
        assert (out / own).is_file()
    return dirs


def test_awkward_stems_get_their_own_folder_inside_out(tmp_path):
    paths = _inputs(tmp_path / "in", AWKWARD)
    out = tmp_path / "cat"
    # energy_constraint=False: the names are tested, not the fits
    # (tests/catalogue/test_catalogue.py)
    res = fit_catalogue(paths, "tr75", out, n_workers=1, plots=False, starts=1,
                        progress=False, energy_constraint=False)
    # TR75 unconstrained: its albedo exceeds 1 near grazing incidence, a written row
    assert not res.failed, [r["error"] for r in res.failed]
    assert all(r["status"] == "gains-energy" for r in res.rows)
    dirs = _check_folders(out, res.rows)
    by_file = dict(zip([r["file"] for r in res.rows], dirs, strict=True))
    # names of ordinary inputs are today's: their stem
    for name, want in [("a.astm", "a"), ("a-2.astm", "a-2"), ("plain.csv", "plain"),
                       ("catalogue.csv", "catalogue"), ("summary.astm", "summary")]:
        assert by_file[str(tmp_path / "in" / name)] == want
    # nothing was written beside the catalogue folder
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cat", "in"]


def test_cli_awkward_stems(tmp_path):
    paths = _inputs(tmp_path / "in", ["..astm", "a.csv", "a.astm", "a-2.csv", "A.csv"])
    out = tmp_path / "cat"
    assert main(["fit-batch", *paths, "--model", "tr75", "--out", str(out), "--starts", "1",
                 "--no-plots", "--workers", "1", "-q",
                 "--no-energy-constraint"]) == 1  # TR75 gains energy: written, exit 1
    import json

    rows = json.loads((out / "catalogue.json").read_text())["rows"]
    _check_folders(out, rows)


def test_names_are_stable_and_keep_ordinary_stems():
    files = ["d/x.csv", "e/x.csv", "y.astm", "z.alta"]
    assert folder_names(files) == ["x", "x-2", "y", "z"]  # today's names
    assert folder_names(files) == folder_names(list(files))
    names = folder_names(["a.astm", "a.csv", "a-2.astm", "A.astm", "..astm", "...csv"])
    assert len({n.casefold() for n in names}) == 6
    assert names[0] == "a" and names[2] == "a-2"
    assert all(n.strip(".") == n and n for n in names)
