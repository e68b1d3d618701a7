"""Model choice: ``rb.compare``, ``rb.fit("auto", ...)`` and model specs
(:mod:`roughbrdf.fitting.choice.compare`, :mod:`roughbrdf.models.factory`).

Where the expected numbers come from:

* synthetic data generated here from the coated model (``docs/models.md`` §10.3; ``n = 1.5``,
  ``rho = 0.3``, ``alpha = 0.15``; one lobe of weight 1) times ``1 + 0.02 N(0, 1)`` noise: the
  true model is known, and the simpler candidates (Lambertian, Oren-Nayar) cannot make a
  specular lobe;
* the information criteria recomputed here from each channel's residuals with the formula of
  the module notes, ``sum_c n_c ln(chi2_c/n_c) + (2 or ln N) k``;
* the cross-validation score of the Lambertian model with the absolute loss, in closed form:
  its least-squares ``rho/pi`` is the mean of the training values, so each left-out incidence's
  residuals are ``x - mean(x of the other incidences)``;
* the rms-log by theta_r band recomputed from the fitted values.
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.errors import ArgumentError
from roughbrdf.fitting.choice.compare import (
    AUTO_CANDIDATES,
    THETA_R_BANDS,
    band_rms_log,
    cross_validate,
    information,
)
from roughbrdf.models import from_spec, spec_text
from roughbrdf.models.factory import split_specs

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

TRUTH = rb.model("coated", n=1.5, rho=0.3, alpha=0.15)
STARTS = 2


def _grid(top: int = 80, step: int = 8) -> list[np.ndarray]:
    """theta_i 10, 35, 60 deg; theta_r 0-top deg; phi 0-180 by 45."""
    return list(np.radians(np.mgrid[10:61:25, 0:top + 1:step, 0:181:45].reshape(3, -1)))


def _measurement(channels: int = 1, top: int = 80, step: int = 8) -> rb.Measurement:
    g = _grid(top, step)
    rng = np.random.default_rng(1)
    clean = np.stack([TRUTH.with_values(["rho"], [0.3 + 0.2 * j]).brdf(*g)
                      for j in range(channels)], axis=1)
    return rb.Measurement(*g, clean * (1 + 0.02 * rng.standard_normal(clean.shape)),
                          channels=[f"c{j}" for j in range(channels)])


@pytest.fixture(scope="module")
def meas() -> rb.Measurement:
    return _measurement(channels=2)


@pytest.fixture(scope="module")
def comparison(meas):
    return rb.compare(meas, ["lambertian", "oren-nayar", "coated"], starts=STARTS)


def test_compare_picks_the_true_model_by_bic_and_cv(comparison):
    assert comparison.best.label == "coated" and comparison.criterion == "cv"
    assert comparison.best_cv is comparison.best is comparison.best_bic
    # ranked by the score (none gains energy); Oren-Nayar with sigma -> 0 is the Lambertian
    # model, their scores equal to 6 digits: the tie goes to the fewer unknowns
    cvs = [c.cv for c in comparison.candidates]
    assert cvs == pytest.approx(sorted(cvs), rel=1e-5)
    assert [c.label for c in comparison.candidates][1:] == ["lambertian", "oren-nayar"]
    assert not any(c.gains_energy for c in comparison.candidates)
    assert {c.label for c in comparison.candidates} == {"lambertian", "oren-nayar", "coated"}
    for c in comparison.candidates:
        assert c.cv is not None and math.isfinite(c.cv)
    assert all(comparison.best.cv < c.cv for c in comparison.candidates[1:])
    # the true model's CV is its noise level (2 %), the others' an order of magnitude more
    assert comparison.best.cv == pytest.approx(0.02, rel=0.25)


def test_information_recomputed_from_the_channels(comparison, meas):
    for cand in comparison.candidates:
        res = cand.result
        like = sum(c.residual.size * math.log(float(c.residual @ c.residual) / c.residual.size)
                   for c in res.channels)
        k = sum(c.n_varys for c in res.channels)
        n = sum(c.residual.size for c in res.channels)
        assert n == 2 * meas.n_samples
        assert information(res) == pytest.approx((k, n, like + 2 * k, like + math.log(n) * k),
                                                 rel=1e-12)
        assert (cand.k, cand.n_points) == (k, n)
        assert (cand.aic, cand.bic) == pytest.approx((like + 2 * k, like + math.log(n) * k),
                                                     rel=1e-12)
        assert cand.sigma == pytest.approx(np.median([c.sigma for c in res.channels]))
        assert cand.rms_log == pytest.approx(np.median([c.rms_log for c in res.channels]))


def test_information_of_a_joint_fit_counts_the_joint_unknowns(meas):
    res = rb.fit("coated", meas, joint=True, starts=1, progress=False)
    k, n, _, _ = information(res)
    assert k == res.options["joint"]["n_varys"] == 2 + 2  # n, alpha + one rho each
    assert n == 2 * meas.n_samples


def test_band_rms_log_recomputed(comparison, meas):
    res = comparison.best.result
    tr = np.degrees(meas.theta_r)
    logs = np.concatenate([np.log(c.scale * c.data / c.fitted) for c in res.channels])
    where = np.concatenate([tr[c.index] for c in res.channels])
    bands = band_rms_log(res)
    assert list(bands) == ["0-30", "30-60", "60-70", "70-80", "80-90"]
    for (lo, hi), value in zip(THETA_R_BANDS, bands.values(), strict=True):
        sel = (where >= lo) & (where < hi)
        assert value == pytest.approx(math.sqrt(np.mean(logs[sel] ** 2)), rel=1e-12)
    assert bands == comparison.best.bands


def test_cross_validation_in_closed_form():
    """Lambertian, absolute loss: each fold's rho/pi is the mean of the training values."""
    meas = _measurement()
    x, ti = meas.values[:, 0], meas.theta_i
    held = [x[ti == a] - x[ti != a].mean() for a in np.unique(ti)]
    expected = math.sqrt(np.mean(np.concatenate(held) ** 2))
    res = rb.fit("lambertian", meas, loss="absolute", starts=1, progress=False)
    assert cross_validate(res, {"loss": "absolute"}) == pytest.approx(expected, rel=1e-5)
    cmp = rb.compare(meas, ["lambertian"], loss="absolute", starts=1)
    assert cmp.best.cv == pytest.approx(expected, rel=1e-5)
    # weights of one change nothing, also in the folds (a weight per sample is cut with them)
    ones = rb.compare(meas, ["lambertian"], loss="absolute", starts=1,
                      weights=np.ones(meas.n_samples))
    assert ones.best.cv == pytest.approx(expected, rel=1e-5)


def test_cross_validation_needs_two_incidences():
    one = _measurement()
    one = one.subset(np.isclose(one.theta_i, math.radians(35)))
    res = rb.fit("lambertian", one, starts=1, progress=False)
    assert math.isnan(cross_validate(res, {}))
    cmp = rb.compare(one, ["lambertian"], starts=1)
    assert math.isnan(cmp.best.cv) and cmp.best_cv is None


def test_table_to_dict_and_plot(comparison):
    d = comparison.to_dict()
    assert set(d) == {"best", "best_cv", "best_bic", "criterion", "candidates", "notes"}
    assert d["best"] == d["best_cv"] == d["best_bic"] == "coated" and d["criterion"] == "cv"
    assert [r["model"] for r in d["candidates"]] == [c.label for c in comparison.candidates]
    row = d["candidates"][0]
    assert set(row) == {"model", "k", "n_points", "aic", "bic", "sigma", "rms_log",
                        "rms_log_by_theta_r", "cv", "params", "limits", "plausibility",
                        "elapsed_s", "partial"}
    assert row["partial"] is None  # rb.compare fits every candidate on every channel
    assert set(row["params"]) == {"c0", "c1"} and set(row["params"]["c0"]) == {
        "n", "rho", "alpha"}
    json.dumps(d)  # plain values
    lines = comparison.table().splitlines()
    assert lines[0].startswith("| model | k | sigma | rms-log | dBIC | dAIC | CV |")
    assert lines[2].startswith("| coated | 6 |") and "| 0 | 0 |" in lines[2]
    assert len([ln for ln in lines if ln.startswith("| ")]) == 1 + 3
    assert any(ln.startswith("- BIC and AIC assume independent residuals") for ln in lines)
    fig = comparison.plot()
    assert len(fig.axes) == 2


def test_without_cv():
    cmp = rb.compare(_measurement(), "lambertian; coated", cv=False, starts=STARTS)
    assert [c.cv for c in cmp.candidates] == [None, None] and cmp.best_cv is None
    assert cmp.to_dict()["best_cv"] is None and cmp.criterion == "bic"
    bics = [c.bic for c in cmp.candidates]  # without a score: ranked by BIC
    assert bics == sorted(bics) and cmp.best is cmp.best_bic
    assert "| - |" in cmp.table().splitlines()[2]


def test_different_sample_counts_are_noted():
    """TR75's BRDF is infinite at theta_r = 90 deg (unshadowed): those samples are left out
    of its fit only, and the AIC/BIC are then not comparable."""
    meas = _measurement(top=90, step=10)
    cmp = rb.compare(meas, ["trowbridge-reitz-1975", "coated"], cv=False, starts=1)
    counts = {c.label: c.n_points for c in cmp.candidates}
    n_horizon = int(np.isclose(meas.theta_r, math.pi / 2).sum())
    assert counts == {"coated": meas.n_samples,
                      "trowbridge-reitz-1975": meas.n_samples - n_horizon}
    assert any("different numbers of samples" in n for n in cmp.notes)


def test_fit_auto_attaches_the_model_choice(tmp_path):
    meas = _measurement()
    res = rb.fit("auto", meas, starts=STARTS, progress=False)
    choice = res.model_choice
    assert res is choice.best.result
    assert {c.label for c in choice.candidates} == {spec_text(from_spec(s))
                                                     for s in AUTO_CANDIDATES}
    assert res.model_name == choice.best.label == "coated"
    # the time of every candidate's fit (Candidate.elapsed: the fit's own time)
    assert res.elapsed == pytest.approx(sum(c.elapsed for c in choice.candidates))
    d = json.loads(res.to_json())
    assert d["model"] == "coated" and d["model_choice"]["best"] == "coated"
    assert len(d["model_choice"]["candidates"]) == len(AUTO_CANDIDATES)
    assert "[[Model choice]] candidates sorted by cross-validation score (best first; chosen: "\
        "coated)" in res.report()
    assert "compare.png" in res.files(plots=True)
    assert "compare.png" not in res.files(plots=False)
    written = res.save(tmp_path / "out", plots=False)
    assert json.loads((tmp_path / "out" / "fit.json").read_text())["model_choice"] == \
        d["model_choice"]
    assert [p.name for p in written] == ["fit.json", "report.txt"]


def test_a_plain_fit_has_no_model_choice():
    res = rb.fit("coated", _measurement(), starts=1, progress=False)
    assert res.model_choice is None and json.loads(res.to_json())["model_choice"] is None
    assert "[[Model choice]]" not in res.report()


@pytest.mark.parametrize("kw", [{"fix": ["rho"]}, {"bounds": {"rho": (0.0, 0.5)}}])
def test_auto_refuses_fix_and_bounds(kw):
    (name,) = kw
    with pytest.raises(ArgumentError) as info:
        rb.fit("auto", _measurement(), starts=1, progress=False, **kw)
    assert info.value.argument == name and "rb.compare" in str(info.value)


@pytest.mark.parametrize("spec", [
    "coated", "coated(lobes=2)", "coated(lobes=2, distribution=beckmann)",
    "trowbridge-reitz-1975+lambertian", "microfacet(distribution=beckmann)+lambertian",
    "trowbridge-reitz-1975(shadowing=v-groove)", "renhorn-boreman-2008(zeta=angle)",
])
def test_spec_round_trip(spec):
    m = from_spec(spec)
    text = spec_text(m)
    again = from_spec(text)
    assert spec_text(again) == text
    assert again.to_dict() == m.to_dict()


def test_spec_values_and_aliases():
    m = from_spec(" coated( lobes = 2 , distribution = beckmann, rho = 0.25 ) ")
    assert m.options["lobes"] == 2 and m.options["distribution"] == "beckmann"
    assert m.params["rho"] == 0.25
    assert spec_text(m) == "coated(distribution=beckmann, lobes=2)"  # parameters are not options
    assert spec_text(from_spec("tr75")) == "trowbridge-reitz-1975"
    assert from_spec("tr75 + lambertian(rho=0.1)").params["lambertian_rho"] == 0.1
    assert split_specs("tr75, coated(lobes=2, distribution=beckmann);lambertian") == [
        "tr75", "coated(lobes=2, distribution=beckmann)", "lambertian"]
    assert split_specs(" ; ,") == []


@pytest.mark.parametrize("spec, needle", [
    ("coated(lobes=2", "bad model spec"),
    ("(lobes=2)", "bad model spec"),
    ("", "bad model spec"),
    ("coated(lobes)", "bad setting 'lobes'"),
    ("coated(bogus=1)", "'bogus'"),
    ("nosuch", "unknown model 'nosuch'"),
    ("coated(lobes=7)", "lobes must be 1, 2 or 3"),
])
def test_spec_errors(spec, needle):
    with pytest.raises(ValueError) as info:
        from_spec(spec)
    assert needle in str(info.value)
    with pytest.raises(ArgumentError) as info:
        rb.compare(_measurement(), [spec], cv=False, starts=1)
    assert info.value.argument == "candidates" and needle in str(info.value)


@pytest.mark.parametrize("cands", [[], "", [3]])
def test_compare_bad_candidates(cands):
    with pytest.raises(ArgumentError) as info:
        rb.compare(_measurement(), cands, cv=False, starts=1)
    assert info.value.argument == "candidates"


def _candidate(label: str, cv: float | None, bic: float, albedo: float = 0.5,
               limited: bool = False):
    """A Candidate of a stand-in result (one channel of the given maximum albedo, a parameter
    on a search limit or not): the ranking reads only the score, the BIC, the albedo and the
    search limit."""
    from types import SimpleNamespace

    from roughbrdf.fitting.choice.compare import Candidate

    plaus = SimpleNamespace(max_albedo=albedo)
    chan = SimpleNamespace(channel="c", model=rb.model("lambertian"), free=["rho"], params={})
    res = SimpleNamespace(channels=[chan], options={}, plausibility=lambda i: plaus,
                          at_search_limit=limited)
    return Candidate(label, res, 3, 100, bic, bic, 0.1, 0.1, {}, cv)


def test_rank_by_score_bic_beside_energy_gain_last():
    from roughbrdf.fitting.choice.compare import ModelComparison, rank

    # the case that made the score rank: the lowest BIC predicts the left-out incidences worst
    rows = [_candidate("a", 1.36, -900.0), _candidate("b", 0.52, -500.0),
            _candidate("c", 0.40, -950.0, albedo=4.0), _candidate("d", 0.77, -600.0)]
    ranked, criterion = rank(rows)
    assert criterion == "cv"
    assert [c.label for c in ranked] == ["b", "d", "a", "c"]  # c gains energy: last
    cmp = ModelComparison(ranked, None, criterion=criterion)  # type: ignore[arg-type]
    assert cmp.best.label == "b" and cmp.best_bic.label == "c" and cmp.best_cv.label == "c"
    from roughbrdf.fitting.choice.compare import choice_notes

    notes = choice_notes(cmp)
    assert any("ranked by cross-validation: b" in n and "BIC prefers c" in n for n in notes)
    assert any("gains energy rank last" in n for n in notes)
    # one candidate without a score: all by BIC (a score for some only is not comparable)
    ranked, criterion = rank([_candidate("a", 0.3, -10.0), _candidate("b", None, -20.0)])
    assert criterion == "bic" and [c.label for c in ranked] == ["b", "a"]
    # NaN (a single incidence) is no score either
    ranked, criterion = rank([_candidate("a", math.nan, -10.0), _candidate("b", 0.1, -5.0)])
    assert criterion == "bic" and [c.label for c in ranked] == ["a", "b"]
    # a candidate stopped unscored on the first channel (auto, a search limit: partial) does
    # not take the score away from the whole ones; it ranks after a partial one with a score
    stopped = dataclasses.replace(_candidate("s", None, -99.0, limited=True), partial="stopped")
    skipped = dataclasses.replace(_candidate("k", 0.9, -1.0), partial="skipped")
    ranked, criterion = rank([stopped, _candidate("a", 0.3, -10.0), skipped,
                              _candidate("b", 0.2, -5.0)])
    assert criterion == "cv" and [c.label for c in ranked] == ["b", "a", "k", "s"]


def test_a_candidate_on_a_search_limit_ranks_after_those_without():
    # a search limit is where the search stopped, not a result (docs/fitting.md, "Model
    # choice"): the best score on a search limit ranks after every candidate without one, and
    # before one that gains energy; a note says so
    from roughbrdf.fitting.choice.compare import ModelComparison, choice_notes, rank

    rows = [_candidate("a", 0.30, -900.0), _candidate("b", 0.20, -950.0, limited=True),
            _candidate("c", 0.10, -990.0, albedo=4.0), _candidate("d", 0.25, -600.0)]
    ranked, criterion = rank(rows)
    assert criterion == "cv" and [c.label for c in ranked] == ["d", "a", "b", "c"]
    notes = choice_notes(ModelComparison(ranked, None, criterion=criterion))  # type: ignore
    assert any(n.startswith("b: a parameter on a search limit") for n in notes), notes
    # all on a search limit: by the score, no note
    rows = [_candidate("a", 0.3, -1.0, limited=True), _candidate("b", 0.2, -1.0, limited=True)]
    ranked, _ = rank(rows)
    assert [c.label for c in ranked] == ["b", "a"]
    notes = choice_notes(ModelComparison(ranked, None, criterion="cv"))  # type: ignore
    assert not any("search limit" in n for n in notes)


@pytest.mark.parametrize(("w2", "off"), [(0.0, 2), (1.0, 1)])
def test_a_lobe_below_1e_3_is_switched_off_and_not_counted(w2, off):
    # a second lobe of weight 0 (w2 = 0) or a first lobe of weight 0 (w2 = 1), w2 held there:
    # the idle lobe's width is fitted but shapes nothing -- k counts one unknown less
    from roughbrdf.fitting.choice.compare import lobes_off

    meas = _measurement()
    res = rb.fit(rb.model("coated", lobes=2, w2=w2), meas, fix=["w2"], starts=1,
                 progress=False)
    (chan,) = res.channels
    assert lobes_off(res) == [(chan.channel, off, 0.0, 1)]
    k, _, _, _ = information(res)
    assert k == chan.n_varys - 1
    cmp = rb.compare(meas, [rb.model("coated", lobes=2, w2=w2)], fix=["w2"], cv=False, starts=1)
    assert cmp.best.k == chan.n_varys - 1
    assert any(f"lobe {off} in {chan.channel} (weight 0) below 0.001: switched off" in n
               for n in cmp.notes)
    # a lobe of weight above the limit stays counted
    used = rb.fit(rb.model("coated", lobes=2, w2=0.3), meas, fix=["w2"], starts=1,
                  progress=False)
    assert lobes_off(used) == [] and information(used)[0] == used.channels[0].n_varys


def test_candidates_of_different_losses_are_scored_on_one_yardstick():
    # loss="auto": coated is fitted with robust, TR75 with relative; their loss residuals are in
    # different units, so the score is the r.m.s. of ln(data/model) of the left-out samples
    meas = _measurement()
    cmp = rb.compare(meas, ["trowbridge-reitz-1975", "coated"], starts=1)
    losses = {c.label: c.result.loss for c in cmp.candidates}
    assert losses == {"trowbridge-reitz-1975": "relative", "coated": "robust"}
    assert any("fitted with different losses (relative, robust)" in n for n in cmp.notes)
    for c in cmp.candidates:
        assert c.cv == pytest.approx(cross_validate(c.result, {"starts": 1}, metric="log"),
                                     rel=1e-9)
    # one loss for all: each candidate's own loss residual, as before
    same = rb.compare(meas, ["lambertian", "coated"], starts=1, cv=True)
    assert not any("different losses" in n for n in same.notes)
    assert same.best.cv == pytest.approx(cross_validate(same.best.result, {"starts": 1}),
                                         rel=1e-9)


def test_a_fold_without_statistics_is_the_same_fit():
    # a cross-validation fold only predicts (compare._fold: statistics=False): the same
    # parameters and figures of merit to the last bit, no covariance (NaN errors, a note)
    from roughbrdf.fitting.kinds.channels import fit_model
    from roughbrdf.fitting.problem.options import FitOptions

    meas = _measurement()
    opts = FitOptions(starts=2, progress=False)
    full = fit_model("coated", meas, opts)
    lean = fit_model("coated", meas, opts, statistics=False)
    a, b = full.channels[0], lean.channels[0]
    assert a.params == b.params and a.chi2 == b.chi2 and a.scale == b.scale
    assert all(math.isfinite(v) for v in a.stderr.values() if v is not None)
    assert all(math.isnan(v) for v in b.stderr.values() if v is not None)
    assert "no covariance (a cross-validation fold)" in b.message
