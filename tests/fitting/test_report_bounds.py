"""An honest report at bounds, the counts of starts, and how a fit is saved.

Reproduced from a report once written: ``k : 5.6e-13 +/- 5.43e+05 (96289224998234226688.00%)`` (a
parameter at a bound given a standard error and an absurd percentage), a parameter 4.9e-8 from
a bound not flagged, and ``# starts = 9`` when 8 were asked (the previous channel's optimum
came on top of ``starts``). Also :meth:`FitResult.save` (``overwrite=``, all-or-nothing through
:class:`roughbrdf.output.ResultFolder`) and the input's ``file_abspath``/``file_sha256`` in
``fit.json``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.fitting.results.report import MAX_PERCENT_RATIO, percent
from roughbrdf.fitting.results.statistics import AT_BOUND_RTOL, at_bound
from roughbrdf.measurement import Measurement

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

TS67_TRUE = {"g": 2.0, "c": 0.08, "rho_d": 0.3}


def ts67_measurement(channels: int = 1, noise: float = 0.05, **meta) -> Measurement:
    t_i, t_r, p = np.meshgrid(np.radians([10, 40, 70]), np.radians(np.arange(0, 86, 10)),
                              np.radians([0, 90, 180]), indexing="ij")
    ti, tr, ph = t_i.ravel(), t_r.ravel(), p.ravel()
    f = rb.model("torrance-sparrow-1967", n=None, k=None, **TS67_TRUE).brdf(ti, tr, ph)
    rng = np.random.default_rng(3)
    vals = np.column_stack([f * (1 + noise * rng.standard_normal(f.size))
                            for _ in range(channels)])
    return Measurement(ti, tr, ph, vals, channels=[f"c{j}" for j in range(channels)],
                       quantity="brdf", meta=meta)


@pytest.fixture(scope="module")
def bound_fit():
    """g's bounds stop it below its true value 2: the optimum sits on the upper bound 0.5."""
    return rb.fit(rb.model("ts67", n=None, k=None, g=0.3), ts67_measurement(),
                  bounds={"g": (0.0, 0.5)}, starts=2, progress=False)


# ---------------------------------------------------------------------------------------------
# at a bound: marked, no standard error, no percentage; why is said
# ---------------------------------------------------------------------------------------------
def test_at_bound_rule():
    lo, hi = np.array([0.0, 0.2]), np.array([10.0, 5.0])
    assert at_bound(np.array([5.6e-13, 5.0]), lo, hi, ["k", "n"]) == {"k": "lower",
                                                                       "n": "upper"}
    # the miss once reported: 4.9e-8 from a bound (bounds [0, 1]), within a relative 1e-6 of it
    assert at_bound(np.array([4.9e-8]), np.zeros(1), np.ones(1), ["x"]) == {"x": "lower"}
    assert at_bound(np.array([1 - 4.9e-8]), np.zeros(1), np.ones(1), ["x"]) == {"x": "upper"}
    assert AT_BOUND_RTOL == 1e-6
    assert at_bound(np.array([2e-6, 0.5]), np.zeros(2), np.ones(2), ["x", "y"]) == {}
    # an infinite bound is never reached; the other bound's tolerance is relative to it
    assert at_bound(np.array([1.0 + 5e-7]), np.ones(1), np.array([np.inf]), ["x"]) == {
        "x": "lower"}


def test_parameter_at_bound_has_no_stderr(bound_fit):
    c = bound_fit.channels[0]
    assert c.params["g"] == pytest.approx(0.5, abs=1e-6)
    assert c.at_bound == {"g": "upper"}
    assert math.isnan(c.stderr["g"])
    assert all(math.isnan(v) for v in c.correl["g"].values())
    for other in ("c", "rho_d"):  # the others keep theirs, computed with g held at its bound
        assert math.isfinite(c.stderr[other]) and c.stderr[other] > 0
    assert "at a bound: g" in c.message


def test_report_marks_the_bound_and_says_why(bound_fit):
    text = bound_fit.report()
    g_line = next(line for line in text.splitlines() if line.strip().startswith("g "))
    assert "(at the upper bound: no stderr)" in g_line
    assert "+/-" not in g_line and "%" not in g_line
    assert "covariance is not meaningful" in text and "at an active bound" in text
    c_line = next(line for line in text.splitlines() if line.strip().startswith("c "))
    assert "+/-" in c_line and "%" in c_line


def test_fit_json_marks_the_bound(bound_fit):
    ch = json.loads(bound_fit.to_json())["channels"][0]
    assert ch["at_bound"] == {"g": "upper"}
    assert ch["stderr"]["g"] is None and ch["stderr"]["c"] > 0


def test_a_parameter_at_a_bound_has_no_stderr_in_the_report(bound_fit):
    # k : 5.6e-13 +/- 5.43e+05 (96289224998234226688.00%) -- rebuilt on a real result
    c = bound_fit.channels[0]
    fake = dataclasses.replace(
        c, params={**c.params, "c": 5.6e-13}, stderr={**c.stderr, "c": 5.43e5},
        bounds={**c.bounds, "c": (0.0, 0.5)}, at_bound={**c.at_bound, "c": "lower"})
    res = dataclasses.replace(bound_fit, channels=[fake])
    line = next(ln for ln in res.report().splitlines() if ln.strip().startswith("c "))
    assert "+/-" not in line and "%" not in line and "lower bound" in line
    # the same value not at a bound: a standard error, but no absurd percentage
    fake = dataclasses.replace(fake, at_bound={"g": "upper"}, bounds={**c.bounds})
    text = dataclasses.replace(bound_fit, channels=[fake]).report()
    line = next(ln for ln in text.splitlines() if ln.strip().startswith("c "))
    assert "+/- 5.43e+05 1/deg (> 1000%)" in line  # TS67's c is per degree


def test_percentages_are_never_absurd():
    assert percent(0.01, 0.5) == " (2.00%)"
    assert percent(5.43e5, 5.6e-13) == " (> 1000%)"
    assert percent(10.0, 1.0) == " (1000.00%)" and MAX_PERCENT_RATIO == 10.0
    assert percent(math.nan, 1.0) == percent(None, 1.0) == percent(1.0, 0.0) == ""


def test_every_percentage_in_a_report_is_at_most_1000(bound_fit):
    c = bound_fit.channels[0]
    wild = dataclasses.replace(c, stderr={**c.stderr, "rho_d": 1e30}, scale_stderr=1e30)
    text = dataclasses.replace(bound_fit, channels=[wild]).report()
    for pct in re.findall(r"\(([0-9.eE+]+)%\)", text):
        assert float(pct) <= 1000.0, text


# ---------------------------------------------------------------------------------------------
# the counts printed are the counts run
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("starts", [1, 2, 8])
def test_starts_counted_as_asked_on_every_channel(starts):
    # before: the previous channel's optimum came on top, "# starts = 9" when 8 were asked
    res = rb.fit(rb.model("ts67", n=None, k=None), ts67_measurement(channels=3),
                 starts=starts, progress=False)
    for c in res:
        explored = [s for s in c.starts if s["stage"] != "full"]
        assert len(explored) == starts, c.channel
        assert explored[0]["origin"] == "model"
    # the warm start takes the place of a Sobol start (not there with starts=1)
    origins = [s["origin"] for s in res.channels[1].starts]
    assert ("previous channel" in origins) == (starts >= 2)
    counts = re.findall(r"# starts\s+= (\d+)", res.report())
    assert counts == [str(starts)] * 3
    assert json.loads(res.to_json())["options"]["starts"] == starts


def test_progress_bar_total_matches_the_local_fits(monkeypatch):
    import roughbrdf.fitting.kinds.channels as fitting

    seen = {}

    class Bar:
        def __init__(self, total):
            seen["total"], seen["n"] = total, 0

        def update(self, k):
            seen["n"] += k

        def set_postfix_str(self, s):
            pass

    from contextlib import contextmanager

    @contextmanager
    def fake(show, total, desc):
        yield Bar(total)

    monkeypatch.setattr(fitting, "progress_bar", fake)
    rb.fit(rb.model("ts67", n=None, k=None), ts67_measurement(channels=2), starts=3,
           progress=True)
    assert seen["n"] == seen["total"] == 6


# ---------------------------------------------------------------------------------------------
# saving: overwrite=, all or nothing; fit.json names the input file and its SHA-256
# ---------------------------------------------------------------------------------------------
def _listing(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def test_save_refuses_an_earlier_run_unless_overwrite(bound_fit, tmp_path):
    out = tmp_path / "out"
    written = bound_fit.save(out, plots=False)
    assert [p.name for p in written] == ["fit.json", "report.txt"]
    before = _listing(out)
    with pytest.raises(FileExistsError, match="--force|overwrite"):
        bound_fit.save(out, plots=False)
    assert _listing(out) == before
    bound_fit.save(out, plots=True, overwrite=True)
    assert (out / "fit_c0.png").read_bytes().startswith(b"\x89PNG")
    with pytest.raises(TypeError):
        bound_fit.save(out, force=True)  # one name for "asked": overwrite=


@pytest.mark.parametrize("exc", [RuntimeError("drawing failed"), KeyboardInterrupt()])
def test_save_is_all_or_nothing(bound_fit, tmp_path, monkeypatch, exc):
    out = tmp_path / "out"
    bound_fit.save(out, plots=False)
    before = _listing(out)

    def broken(self, channel=0, *, fig=None):
        raise exc

    monkeypatch.setattr(rb.FitResult, "plot", broken)
    with pytest.raises(type(exc)):
        bound_fit.save(out, plots=True, overwrite=True)
    assert _listing(out) == before  # the previous complete set, no temporary file, no lock


def test_to_json_path_refuses_an_existing_file(bound_fit, tmp_path):
    path = tmp_path / "fit.json"
    bound_fit.to_json(path)
    with pytest.raises(FileExistsError):
        bound_fit.to_json(path)
    bound_fit.to_json(path, overwrite=True)
    assert json.loads(path.read_text())["model"] == "torrance-sparrow-1967"


def test_fit_json_records_the_input_file_and_its_sha256(tmp_path, monkeypatch):
    src = Path(rb.__file__).parent / "data" / "tr75_cement.csv"
    path = tmp_path / "cement.csv"
    path.write_bytes(src.read_bytes())
    monkeypatch.chdir(tmp_path)
    meas = rb.read("cement.csv")
    res = rb.fit("trowbridge-reitz-1975", meas, starts=1, progress=False)
    d = res.to_dict()
    assert d["file"] == "cement.csv"
    assert d["file_abspath"] == str(path.resolve())
    assert d["file_sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
    # recorded when the fit ran: a later change of the file does not change the record
    path.write_text("changed")
    assert res.to_dict()["file_sha256"] == d["file_sha256"]


def test_fit_json_without_a_file_has_null_provenance(bound_fit):
    d = json.loads(bound_fit.to_json())
    assert d["file"] is None and d["file_abspath"] is None and d["file_sha256"] is None
