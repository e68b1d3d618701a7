"""Search limits are not results: a parameter that ends on a bound of the search that is no
physical limit is told apart from one on its physical edge, in ``fit.json`` (``limits``), the
report, ``compare``, the catalogue, and the exit status of ``roughbrdf fit``/``fit-batch``."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.cli import main

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

#: a coarse in-plane and out-of-plane grid (degrees -> radians)
GRID = np.radians(np.mgrid[0:61:20, 0:81:5, 0:181:30].reshape(3, -1))


def _write(tmp_path, truth: rb.Model, name: str):
    path = tmp_path / f"{name}.csv"
    rb.write(rb.Measurement(*GRID, truth.brdf(*GRID), quantity="brdf"), path)
    return path


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A coated paint whose index (4) is beyond the search range of n (up to 2.5), and one
    without a diffuse part (rho = 0: the physical edge of a reflectance)."""
    d = tmp_path_factory.mktemp("limits")
    return {"search": _write(d, rb.model("coated", n=4.0, rho=0.3, alpha=0.2), "high_index"),
            "physical": _write(d, rb.model("coated", n=1.5, rho=0.0, alpha=0.2), "no_diffuse")}


#: the relative loss: with rho = 0 exactly, the robust (default) fit of these noise-free data
#: stops at rho ~ 1e-5 short of its edge (a known convergence limit of that loss); what is
#: tested here is how an edge and a search limit are told apart
LOSS = ["--loss", "relative"]


def _fit(path, out, *extra) -> int:
    return main(["fit", str(path), "--model", "coated", "--starts", "2", "--no-plots", *LOSS,
                 "--out", str(out), "-q", *extra])


def test_search_limit_in_fit_json_report_and_exit_status(files, tmp_path, capsys):
    code = _fit(files["search"], tmp_path / "out")
    err = capsys.readouterr().err
    assert code == 1  # written, but not to be trusted without a look
    (ch,) = json.loads((tmp_path / "out" / "fit.json").read_text())["channels"]
    assert ch["at_bound"] == {"n": "upper"}  # kept as it was, for old readers
    assert ch["limits"] == {"n": "search-upper"}
    assert ch["success"] is True  # the optimizer did converge: the search limit is the problem
    report = (tmp_path / "out" / "report.txt").read_text()
    n_line = next(x for x in report.splitlines() if x.strip().startswith("n "))
    assert "search limit" in n_line and "not a result" in n_line
    assert "SEARCH LIMIT: n" in report
    assert "warning:" in err and "n ended on a search limit" in err


def test_physical_edge_is_a_result(files, tmp_path, capsys):
    code = _fit(files["physical"], tmp_path / "out")
    assert code == 0, capsys.readouterr().err
    (ch,) = json.loads((tmp_path / "out" / "fit.json").read_text())["channels"]
    assert ch["limits"] == {"rho": "physical-lower"}
    report = (tmp_path / "out" / "report.txt").read_text()
    rho_line = next(x for x in report.splitlines() if x.strip().startswith("rho "))
    assert "physical limit" in rho_line and "search limit" not in rho_line


def test_python_api_tells_them_apart(files):
    meas = rb.read(files["search"])
    res = rb.fit("coated", meas, starts=2, progress=False)
    assert res[0].limits == {"n": "search-upper"} and res.at_search_limit
    # a bound the user gave that is not the domain edge is a search limit too
    low = rb.fit("coated", rb.read(files["physical"]), starts=2, progress=False,
                 bounds={"rho": (0.0, 1.0)}, loss="relative")
    assert low[0].limits == {"rho": "physical-lower"} and not low.at_search_limit


def test_compare_names_the_search_limit(files, tmp_path, capsys):
    code = main(["compare", str(files["search"]), "--models", "coated", "--starts", "2",
                 "--no-cv", "--out", str(tmp_path / "cmp"), "--no-plots"])
    out = capsys.readouterr()
    assert code == 1  # the best candidate (the only one) ends on a search limit
    header = next(x for x in out.out.splitlines() if x.startswith("| model"))
    assert "search limit" in header
    row = next(x for x in out.out.splitlines() if x.startswith("| coated"))
    assert row.split("|")[-3].strip() == "n"
    data = json.loads((tmp_path / "cmp" / "compare.json").read_text())
    (cand,) = data["candidates"]
    assert list(cand["limits"].values()) == [{"n": "search-upper"}]


def test_catalogue_status_and_columns(files, tmp_path, capsys):
    pytest.importorskip("distributed")
    out = tmp_path / "cat"
    code = main(["fit-batch", str(files["search"]), str(files["physical"]), "-m", "coated",
                 "--starts", "2", "--no-plots", "-o", str(out), "--workers", "1", *LOSS])
    assert code == 1, capsys.readouterr()
    rows = {r["file"]: r for r in json.loads((out / "catalogue.json").read_text())["rows"]}
    high, none = rows[str(files["search"])], rows[str(files["physical"])]
    assert high["status"] == "at-search-limit" and high["limits"] == {"n": "search-upper"}
    assert high["search_limits"] == "n"
    assert none["status"] == "ok" and none["limits"] == {"rho": "physical-lower"}
    with open(out / "catalogue.csv", newline="") as fh:
        table = {r["file"]: r for r in csv.DictReader(fh)}
    assert table[str(files["search"])]["status"] == "at-search-limit"
    assert table[str(files["search"])]["limits"] == "n=search-upper"
    assert table[str(files["physical"])]["limits"] == "rho=physical-lower"
    page = (out / "summary.html").read_text()
    assert "at-search-limit" in page and "search limit" in page


def test_rows_of_an_older_catalogue_still_write():
    """Rows an older roughbrdf wrote (no limits nor plausibility keys; what ``--resume`` keeps
    from an earlier run) are written to the new CSV with those cells empty."""
    from roughbrdf.catalogue.rows import csv_text

    old = {"file": "a.csv", "channel": "value", "model": "coated", "status": "skipped (resume)",
           "params": {"n": 1.5}, "stderr": {"n": 0.01}, "sigma": 0.1}
    (cells,) = list(csv.DictReader(csv_text([old]).splitlines()))
    assert cells["status"] == "skipped (resume)" and cells["param_n"] == "1.5"
    assert cells["limits"] == "" and cells["max_albedo"] == "" and cells["search_limits"] == ""
