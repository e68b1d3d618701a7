"""``roughbrdf fit-batch``: safe names, honest exit statuses and a clean ``--resume``.

Each test names the fault it keeps fixed:

* a file name with Markdown link syntax became a live link in ``summary.md``;
* ``--resume`` counted ``skipped (resume)`` rows as success, kept the old paths of moved
  inputs, and took the catalogue's own files as inputs (``fit-batch IN --out IN``);
* ``--time-limit`` left ``.roughbrdf-lock`` / ``.roughbrdf-tmp-`` files behind;
* a name with a newline split its failure message over two lines;
* ``--seed -1`` said "expected non-negative integer" without naming ``--seed``.

The runs use tiny synthetic files and one real ``dask.distributed`` worker process (a
``LocalCluster`` reached by its address, as ``tests/catalogue/test_catalogue.py`` does).
"""

from __future__ import annotations

import html
import json
import os
import re
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import roughbrdf as rb
from roughbrdf.catalogue import CatalogueResult, fit_catalogue
from roughbrdf.catalogue.rows import one_line, outcome, shown_name
from roughbrdf.catalogue.summary import md_text, write_summary
from roughbrdf.cli import app
from roughbrdf.output import LOCK, TMP_PREFIX

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="catalogues: every row is a whole fit (~40 s or more in plain Python)")

runner = CliRunner()
#: the fastest fit: one start, no plots, the constraint off (a Lambertian fit of Lambertian
#: data is "ok"; TR75 without shadowing gains energy, "gains-energy", as in test_catalogue.py)
FAST = {"starts": 1, "plots": False, "progress": False, "energy_constraint": False}


def _write(path: Path, model: str = "lambertian", **params: float) -> str:
    """A small in-plane measurement of ``model`` (2 incidences x 8 angles x 2 azimuths)."""
    ti, tr, ph = (a.ravel() for a in np.meshgrid(np.radians([20.0, 45.0]),
                                                 np.radians(np.arange(0.0, 80.0, 10.0)),
                                                 [0.0, np.pi], indexing="ij"))
    m = rb.model(model, **params)
    rb.write(rb.Measurement(ti, tr, ph, m.brdf(ti, tr, ph)), path, format="csv")
    return str(path)


@pytest.fixture(scope="module")
def cluster():
    """One single-threaded worker process (with a nanny: --time-limit restarts it)."""
    pytest.importorskip("distributed")
    from distributed import LocalCluster

    from roughbrdf.catalogue.run import close_local

    c = LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None)
    try:
        yield c
    finally:
        close_local(c)


# --------------------------------------------------------------------------------------------
# summary.md: names are text, never markup
# --------------------------------------------------------------------------------------------

EVIL = ["[x](javascript:alert(9)).astm", "*em* _u_ **b**.astm", "`code`.csv",
        "<img src=x onerror=alert(1)>.csv", "![i](javascript:alert(2)).csv",
        "# heading.csv", "- item.csv", "1. one.csv", "&amp;.csv", "a|b.csv", "<http://e.x>.csv"]


def _rendered(folder: Path, names: list[str]) -> str:
    """summary.md of failed rows named ``names``, rendered as CommonMark (tables on)."""
    markdown_it = pytest.importorskip("markdown_it")
    rows = [{"file": f, "channel": f, "model": "lambertian", "status": "failed", "error": f,
             "fit_dir": f"d{k}"} for k, f in enumerate(names)]
    md_path, _ = write_summary(folder, rows, title=names[0])
    md = md_path.read_text(encoding="utf-8")
    return markdown_it.MarkdownIt("commonmark").enable("table").render(md)


def test_summary_markdown_makes_no_markup_of_names(tmp_path):
    # the fault: `[x](javascript:alert(9)).astm` was a live link in summary.md; rendered by a
    # real CommonMark renderer (markdown-it-py, installed with rich), the page has exactly the
    # elements it has with plain names: no name becomes a link, an image, emphasis, code, HTML
    # or a block; and each is shown exactly as it is
    out = _rendered(tmp_path / "evil", EVIL)
    plain = _rendered(tmp_path / "plain", [f"plain{k}.astm" for k in range(len(EVIL))])
    tags = re.compile(r"<(/?[a-z0-9]+)[^>]*>")
    assert tags.findall(out) == tags.findall(plain)
    assert "javascript:" not in "".join(re.findall(r"<[^>]*>", out))  # in no tag or attribute
    assert set(re.findall(r'href="([^"]*)"', out)) == {
        "summary.html", *(f"d{k}" for k in range(len(EVIL)))}
    text = html.unescape(re.sub(r"<[^>]+>", "", out))
    for name in EVIL:  # as given: in the failure list (file, channel, error) and the table
        assert text.count(name) >= 4, name


def test_md_text_escapes_every_active_character():
    # CommonMark lets any ASCII punctuation be backslash-escaped; the active ones are
    assert md_text("\\`*_{}[]()#+-.!|~") == "".join("\\" + c for c in "\\`*_{}[]()#+-.!|~")
    assert md_text("<a>&") == "&lt;a&gt;&amp;"
    assert md_text("two\nlines\tand\x1b[0m") == "two lines and\\\\x1b\\[0m"


# --------------------------------------------------------------------------------------------
# one-line messages
# --------------------------------------------------------------------------------------------

def test_names_with_control_characters_are_quoted():
    assert shown_name("plain name.csv") == "plain name.csv"
    for name in ("a\nb.csv", "a\tb.csv", "\x1b[31mred.csv", "a\rb.csv", "a\u2028b.csv"):
        shown = shown_name(name)
        assert shown == repr(name) and shown.isprintable(), name
    assert one_line("cannot read /d/a\nb.csv:\n line 3", ["/d/a\nb.csv"]) == \
        "cannot read '/d/a\\nb.csv': line 3"
    assert one_line("bell\x07 here") == "bell\\x07 here"


def test_failure_of_a_name_with_a_newline_is_one_line(cluster, tmp_path):
    # the fault: an input name with a newline split its failure message over two lines
    data = tmp_path / "in"
    data.mkdir()
    _write(data / "good.csv", rho=0.3)
    (data / "bad\nname.csv").write_text("not a measurement\n")
    res = runner.invoke(app, ["fit-batch", str(data), "-m", "lambertian", "-o",
                              str(tmp_path / "cat"), "--scheduler", cluster.scheduler_address,
                              "--starts", "1", "--no-plots", "--no-energy-constraint", "-q"])
    assert res.exit_code == 1, res.output
    failed = [ln for ln in res.output.splitlines() if ln.startswith("failed:")]
    assert len(failed) == 1, res.output
    bad = str(data / "bad\nname.csv")
    assert failed[0].startswith(f"failed: {shown_name(bad)}: "), failed[0]
    rows = json.loads((tmp_path / "cat" / "catalogue.json").read_text())["rows"]
    assert "\n" not in next(r["error"] for r in rows if r["status"] == "failed")


# --------------------------------------------------------------------------------------------
# --resume
# --------------------------------------------------------------------------------------------

def test_kept_rows_count_as_their_earlier_status():
    # the fault: the exit status counted `skipped (resume)` rows as success
    kept = {"status": "skipped (resume)"}
    assert CatalogueResult([{**kept, "earlier_status": "ok"}], Path(".")).success
    for earlier in ("gains-energy", "not converged", "at-search-limit", None):
        row = {**kept, "earlier_status": earlier}
        assert outcome(row) == earlier
        assert not CatalogueResult([row], Path(".")).success, earlier


def test_resume_exit_status_is_the_earlier_one(cluster, tmp_path):
    # a TR75 fit that gains energy exits 1 (docs/catalogue.md); resumed, it still does
    data = tmp_path / "in"
    data.mkdir()
    _write(data / "t.csv", "tr75", e=0.6, rho_L=0.2)
    cmd = ["fit-batch", str(data), "-m", "tr75", "-o", str(tmp_path / "cat"), "--scheduler",
           cluster.scheduler_address, "--starts", "2", "--no-plots", "--no-energy-constraint",
           "-q"]
    first = runner.invoke(app, cmd)
    assert first.exit_code == 1, first.output
    again = runner.invoke(app, [*cmd, "--resume"])
    assert again.exit_code == 1, again.output
    (row,) = json.loads((tmp_path / "cat" / "catalogue.json").read_text())["rows"]
    assert (row["status"], row["earlier_status"]) == ("skipped (resume)", "gains-energy")


def test_resume_names_moved_inputs_where_they_are(cluster, tmp_path):
    # the fault: --resume after the inputs moved (same bytes) kept rows naming the old paths
    old, new = tmp_path / "old", tmp_path / "new"
    old.mkdir()
    for k in range(2):
        _write(old / f"m{k}.csv", rho=0.2 + 0.1 * k)
    out = tmp_path / "cat"
    first = fit_catalogue(old, "lambertian", out, scheduler=cluster.scheduler_address, **FAST)
    assert first.success and {r["status"] for r in first.rows} == {"ok"}
    shutil.move(old, new)
    res = fit_catalogue(new, "lambertian", out, scheduler=cluster.scheduler_address,
                        resume=True, **FAST)
    assert [r["status"] for r in res.rows] == ["skipped (resume)"] * 2
    assert [r["file"] for r in res.rows] == [str(new / "m0.csv"), str(new / "m1.csv")]
    assert res.success
    doc = json.loads((out / "catalogue.json").read_text())
    assert all(r["file"].startswith(str(new)) for r in doc["rows"])


@pytest.mark.parametrize("again", [["--resume"], ["--force"]])
def test_own_outputs_are_never_inputs(cluster, tmp_path, again):
    # the fault: `fit-batch IN --out IN` then --resume fitted catalogue.csv, catalogue.json,
    # summary.html and summary.md as inputs (failed rows); with --force as well
    data = tmp_path / "in"
    data.mkdir()
    inputs = [_write(data / f"o{k}.csv", rho=0.3) for k in range(2)]
    cmd = ["fit-batch", str(data), "-m", "lambertian", "-o", str(data), "--scheduler",
           cluster.scheduler_address, "--starts", "1", "--no-plots",
           "--no-energy-constraint", "-q"]
    first = runner.invoke(app, cmd)
    assert first.exit_code == 0, first.output
    assert {"catalogue.csv", "summary.md"} <= set(os.listdir(data))
    # a glob into the fit folders takes none of their files either
    for args in ([*cmd, *again], [*cmd, str(data / "*" / "*"), *again]):
        res = runner.invoke(app, args)
        assert res.exit_code == 0, res.output
        rows = json.loads((data / "catalogue.json").read_text())["rows"]
        assert sorted(r["file"] for r in rows) == inputs, args


# --------------------------------------------------------------------------------------------
# --time-limit: a restarted worker leaves nothing behind
# --------------------------------------------------------------------------------------------

def _stall_mid_write(task):
    """``run_task``, but it stops half way through writing its fit folder (its lock and a
    temporary file are there) until the worker is restarted."""
    import time

    from roughbrdf.output import ResultFolder

    with ResultFolder(task.folder, overwrite=True) as out:
        out.add("fit.json", "half written")
        time.sleep(120)
    return []


def test_time_limit_restart_leaves_no_lock_or_temporary_file(cluster, tmp_path, monkeypatch):
    # the fault: workers restarted by --time-limit mid-write left 12 `.roughbrdf-lock` /
    # `.roughbrdf-tmp-` files behind; the folder is recovered at the end of the run
    import cloudpickle

    import roughbrdf.catalogue.run as run

    data = tmp_path / "in"
    data.mkdir()
    _write(data / "slow.csv", rho=0.3)
    out = tmp_path / "cat"
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    try:
        monkeypatch.setattr(run, "run_task", _stall_mid_write)
        res = fit_catalogue(data, "lambertian", out, scheduler=cluster.scheduler_address,
                            time_limit=3.0, retries=0, **FAST)
    finally:
        cloudpickle.unregister_pickle_by_value(sys.modules[__name__])
    (row,) = res.rows
    assert row["status"] == "failed" and "time limit of 3 s" in row["error"]
    left = [str(p.relative_to(out)) for p in out.rglob("*")
            if p.name == LOCK or p.name.startswith(TMP_PREFIX)]
    assert left == []


# --------------------------------------------------------------------------------------------
# option errors name the option
# --------------------------------------------------------------------------------------------

@pytest.mark.parametrize("verb", ["fit", "compare", "fit-batch"])
@pytest.mark.parametrize(("option", "value", "expected"), [
    ("--seed", "-1", "--seed must be >= 0 (got -1)"),
    ("--starts", "0", "--starts must be >= 1 (got 0)"),
    ("--loss", "nope", "--loss: unknown value 'nope'"),
])
def test_option_errors_name_the_option(tmp_path, verb, option, value, expected):
    # the fault: `--seed -1` said "expected non-negative integer" naming no option (numpy's
    # words); options.check_search words it for every verb that fits, before any work
    src = _write(tmp_path / "a.csv", rho=0.3)
    model = ["--models", "lambertian,tr75"] if verb == "compare" else ["-m", "lambertian"]
    res = runner.invoke(app, [verb, src, *model, "-o", str(tmp_path / "o"), "--no-plots",
                              option, value])
    assert res.exit_code == 2, res.output
    assert f"error: {expected}" in res.output
    assert not (tmp_path / "o").exists()  # refused before any work
