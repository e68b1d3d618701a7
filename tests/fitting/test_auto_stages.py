"""``--model auto`` in two stages (``roughbrdf.fitting.choice.auto``): a candidate far behind on the
first channel is skipped, so is one whose extra parameters do not buy a prediction
``PARSIMONY_MARGIN`` better there, and the candidates fitted further get the fit ``rb.compare``
makes.

What is protected: the choice and every kept candidate's fit are those of the whole comparison
(the skip only saves time), a skipped candidate says so and ranks after every whole one, and
the search resumed after the first channel (``fit_model(..., done=...)``) is the whole fit's.
"""

from __future__ import annotations

import json
import re
import sys

import numpy as np
import pytest

import roughbrdf as rb
import roughbrdf.fitting.choice.auto  # noqa: F401  (the module, not the function of the same name)
from roughbrdf.fitting.kinds.channels import fit_model
from roughbrdf.fitting.problem.options import FitOptions

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

auto = sys.modules["roughbrdf.fitting.choice.auto"]

TRUTH = rb.model("coated", n=1.5, rho=0.3, alpha=0.15)
CANDIDATES = ["lambertian", "coated", "coated(lobes=2)"]
STARTS = 3


def _measurement(channels: int = 3) -> rb.Measurement:
    """The coated model with three diffuse levels, 2 % noise, incidences 10, 35, 60 deg."""
    g = list(np.radians(np.mgrid[10:61:25, 0:81:8, 0:181:45].reshape(3, -1)))
    rng = np.random.default_rng(3)
    clean = np.stack([TRUTH.with_values(["rho"], [0.3 + 0.2 * j]).brdf(*g)
                      for j in range(channels)], axis=1)
    return rb.Measurement(*g, clean * (1 + 0.02 * rng.standard_normal(clean.shape)),
                          channels=[f"c{j}" for j in range(channels)])


@pytest.fixture(scope="module")
def meas() -> rb.Measurement:
    return _measurement()


@pytest.fixture(scope="module")
def both(meas):
    whole = rb.compare(meas, CANDIDATES, starts=STARTS)
    staged = auto.fit_auto(meas, CANDIDATES, starts=STARTS)
    return whole, staged


def test_the_far_candidate_is_skipped_and_says_so(both):
    whole, staged = both
    rows = {c.label: c for c in staged.model_choice.candidates}
    # the Lambertian model cannot make the specular lobe: its first-channel score is many
    # times the coated model's (far beyond the 1 + SKIP_MARGIN factor)
    skipped = rows["lambertian"]
    assert skipped.partial is not None and "fitted to channel c0 only" in skipped.partial
    assert [c.channel for c in skipped.result.channels] == ["c0"]
    assert staged.model_choice.candidates[-1] is skipped  # after every whole candidate
    assert any("lambertian: fitted to channel c0 only" in n for n in staged.model_choice.notes)
    row = json.loads(staged.to_json())["model_choice"]["candidates"]
    # coated(lobes=2) is skipped too (the parsimony rule: next test)
    assert [r["partial"] is not None for r in row] == [False, True, True]
    assert "lambertian (first channel only)" in staged.model_choice.table()
    # a whole candidate's BIC is not compared with one over fewer samples
    assert staged.model_choice.best_bic.partial is None


def test_a_second_lobe_the_data_do_not_need_is_skipped_and_says_so(both):
    whole, staged = both
    rows = {c.label: c for c in staged.model_choice.candidates}
    two, one = rows["coated(lobes=2)"], rows["coated"]
    # one lobe made the data: the second lobe's two parameters cannot predict the first
    # channel 5 % better (an identity of the truth, up to the noise)
    assert one.partial is None and two.partial is not None
    assert "no more than 5% better" in two.partial and "than coated with 3" in two.partial
    assert [c.channel for c in two.result.channels] == ["c0"]
    # the note's two first-channel scores meet the rule's condition; its own is its row's CV
    mine, simpler = map(float, re.findall(r"\(([0-9.e+-]+)\)", two.partial))
    assert mine >= simpler * (1 - auto.PARSIMONY_MARGIN)
    assert mine == pytest.approx(two.cv, rel=1e-3)
    assert staged.model_name == "coated" == whole.best.label


def test_a_second_lobe_the_data_need_goes_on(two_lobes):
    staged, rows = two_lobes
    # a narrow lobe over a wide haze (weights 0.6/0.4, widths 0.05 and 0.4): one GGX lobe
    # cannot make both, the second lobe predicts far more than 5 % better and is fitted whole
    assert rows["coated(lobes=2)"].partial is None
    assert staged.model_name == "coated(lobes=2)"
    assert rows["coated(lobes=2)"].cv < rows["coated"].cv * (1 - auto.PARSIMONY_MARGIN)


@pytest.fixture(scope="module")
def two_lobes():
    truth = rb.model("coated(lobes=2)", n=1.5, rho=0.3, alpha=0.05, alpha2=0.4, w2=0.4)
    g = list(np.radians(np.mgrid[10:61:25, 0:81:4, 0:181:45].reshape(3, -1)))
    rng = np.random.default_rng(5)
    clean = np.stack([truth.with_values(["rho"], [0.3 + 0.2 * j]).brdf(*g)
                      for j in range(2)], axis=1)
    meas = rb.Measurement(*g, clean * (1 + 0.02 * rng.standard_normal(clean.shape)),
                          channels=["c0", "c1"])
    staged = auto.fit_auto(meas, ["coated", "coated(lobes=2)"], starts=STARTS)
    return staged, {c.label: c for c in staged.model_choice.candidates}


def test_the_choice_and_the_kept_fits_are_the_whole_comparisons(both):
    whole, staged = both
    assert staged.model_name == whole.best.label
    rows = {c.label: c for c in staged.model_choice.candidates}
    for c in whole.candidates:
        if rows[c.label].partial:
            continue
        mine = rows[c.label]
        # the same fit to the last bit: the search went on from the first channel's state
        for a, b in zip(c.result.channels, mine.result.channels, strict=True):
            assert a.params == b.params and a.chi2 == b.chi2
        assert mine.cv == pytest.approx(c.cv, rel=1e-12)  # the same folds' residuals


def test_the_resumed_search_is_the_whole_fit(meas):
    opts = FitOptions(starts=STARTS, progress=False)
    whole = fit_model("coated(lobes=2)", meas, opts)
    first = fit_model("coated(lobes=2)", meas, opts.replace(channel=[0]))
    resumed = fit_model("coated(lobes=2)", meas, opts, done=first.channels)
    assert resumed.channels[0] is first.channels[0]
    for a, b in zip(whole.channels, resumed.channels, strict=True):
        assert a.params == b.params


def test_one_channel_or_no_score_compares_every_candidate_whole():
    one = _measurement(channels=1)
    res = auto.fit_auto(one, CANDIDATES, starts=1)
    assert not any(c.partial for c in res.model_choice.candidates)
    res = auto.fit_auto(_measurement(channels=2), CANDIDATES, starts=1, cv=False)
    assert not any(c.partial for c in res.model_choice.candidates)
    assert res.model_choice.criterion == "bic"


def test_the_cli_help_names_the_default_candidates():
    """``--models``' help text lists ``AUTO_CANDIDATES`` as they are (it was left naming the
    Beckmann pair and not the metallic candidates)."""
    from roughbrdf.cli.options import ModelsOption
    from roughbrdf.fitting.choice.compare import AUTO_CANDIDATES

    text = ModelsOption.__metadata__[0].help
    assert text.endswith("(default: " + ", ".join(AUTO_CANDIDATES) + ")")
