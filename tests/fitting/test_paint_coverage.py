"""Honest intervals on a real paint's geometry: a parametric bootstrap of C8_Silver (reduced).

The reduced form of ``scripts/coverage_paints.py`` (``docs/fitting.md``, "Coverage on the shared
paints"; issue 28): the model ``rb.fit("auto")`` keeps on the metallic-flake silver,
``coated-conductor(coat=false, diffuse=true, flakes=reflectance)``, fitted to its 525 nm channel
with the defaults, is the truth; synthetic sets from it on 2000 of the paint's measured geometries
(a uniform random subset, ``theta_r <= 75`` deg) with the instrument noise of ``docs/fitting.md``
(multiplicative log-normal 5 %, additive Gaussian floor 1e-3 of the peak), 20 seeds, fitted with
``rb.fit`` defaults. The criterion of ``test_fit_coverage.py`` (1-sigma 68 +/- 15 %, 2-sigma at
least 85 %) is asserted for the pigment share ``d``, the one parameter of this paint for which the
full run (every measured geometry) meets it. The others do not, and the test records how:

* ``g_m`` (the flakes' edge tint): the truth is on its physical limit 0, where a fit either ends
  on the bound (no standard error: counted as not covered) or inside it;
* ``r_m``, ``alpha_m``: 2-sigma 75-80 % on the full geometry (met on this subset): the additive
  floor, which the robust (log-type) loss does not model, biases them by about half a standard
  error, and with 10,800 samples the standard errors are small enough for that to show.

About 30 s on the 2-core development machine under load (1-1.5 s per fit). Skipped without
``../shared/data``.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import roughbrdf as rb

SPEC = "coated-conductor(coat=false, diffuse=true, flakes=reflectance)"
SEEDS = range(20)
SAMPLES = 2000


def _geometry(meas: rb.Measurement) -> list[np.ndarray]:
    keep = np.flatnonzero(meas.theta_r <= math.radians(75.0) + 1e-9)
    keep = np.sort(np.random.default_rng(0).choice(keep, SAMPLES, replace=False))
    return [meas.theta_i[keep], meas.theta_r[keep], meas.phi[keep]]


def _noisy(truth: rb.models.Model, geo: list[np.ndarray], seed: int) -> rb.Measurement:
    f = truth.brdf(*geo)
    rng = np.random.default_rng(seed)
    x = f * np.exp(0.05 * rng.standard_normal(f.size)) \
        + 1e-3 * f.max() * rng.standard_normal(f.size)
    return rb.Measurement(*geo, x)


@pytest.mark.slow
def test_silver_pigment_share_intervals_cover_the_truth(shared_data: Path):
    meas = rb.read(shared_data / "minidiff" / "C8_Silver.astm")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", rb.fitting.EnergyWarning)
        (c0,) = rb.fit(SPEC, meas, channel="525nm", progress=False).channels
    assert c0.free == ["r_m", "g_m", "alpha_m", "d"]
    assert c0.at_bound == {"g_m": "lower"}  # the edge tint on its physical limit 0
    truth, geo = c0.model, _geometry(meas)
    one = two = bound = 0
    for seed in SEEDS:
        with warnings.catch_warnings():
            warnings.simplefilter("error", rb.fitting.EnergyWarning)  # none may gain energy
            (c,) = rb.fit(SPEC, _noisy(truth, geo, seed), progress=False).channels
        assert c.success, (seed, c.message)
        bound += "g_m" in c.at_bound
        assert set(c.at_bound) <= {"g_m"}, (seed, c.at_bound)
        err = abs(c.params["d"] - c0.params["d"])
        one += err <= c.stderr["d"]
        two += err <= 2 * c.stderr["d"]
    n = len(SEEDS)
    assert 0.53 <= one / n <= 0.83, (one, two)
    assert two / n >= 0.85, (one, two)
    assert 0 < bound < n  # g_m: on its limit in some seeds, inside it in others
