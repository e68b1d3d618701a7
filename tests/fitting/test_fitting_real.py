"""rb.fit on real measurements (../shared/data; skipped without it).

Mini-Diff paints (12,964 geometries x 3 channels each), per channel: TR75 (with its Lambertian
part rho_L, Eq. 33), TS67 absolute form (F = 1, g allowed up to 2000 for the glossy black), and
the microfacet model (Trowbridge-Reitz + Smith + Fresnel) + Lambertian. The tests use 4 starts
instead of the default 8 to stay fast; ``benchmarks/bench_fit.py`` shows the defaults reach the
same sigma and compares with a careful hand-written global search.

CEA retro-reflectors (ALTA, BRDF cos): RB08 fitted to the gray tape and the 3M sheeting, with the
instrument aperture (``rb.fit(..., aperture=...)``): 1.0 deg half-angle, the value the gray tape's
flat-topped retro peak prefers (``benchmarks/bench_fit.py`` scans it).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import roughbrdf as rb

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="whole fits of the measured paints: many minutes each in plain Python")

PAINTS = ("C2_Black", "C8_Silver", "C12_OliveDrab")

MODELS = {
    "tr75": (lambda: rb.model("trowbridge-reitz-1975"), {}),
    "ts67": (lambda: rb.model("torrance-sparrow-1967", n=None, k=None), {"g": (0.0, 2000.0)}),
    "microfacet+lambertian": (
        lambda: rb.model("microfacet", distribution="trowbridge-reitz", shadowing="smith",
                         n=1.5, k=0.0) + rb.model("lambertian", rho=0.1), {}),
}

# sigma (TR75 Eq. 34) of these fits on the measured samples (theta_r <= 75 deg) lies in
# 0.09-0.40, like TR75's own 0.19-0.35 on their surfaces; these bounds catch a fit that went
# astray (sigma -> 1 is the "model far above the data" corner of the relative loss) without
# pinning the numbers.
SIGMA_MAX = {"tr75": 0.45, "ts67": 0.55, "microfacet+lambertian": 0.40}


@pytest.fixture(scope="module")
def paints(shared_data):
    return {name: rb.read(shared_data / "minidiff" / f"{name}.astm") for name in PAINTS}


@pytest.mark.parametrize("model_name", list(MODELS))
def test_paint_fits_converge_with_sensible_sigma(paints, model_name):
    make, bounds = MODELS[model_name]
    for name, meas in paints.items():
        # energy_constraint=False: these bounds are the unconstrained fits' (TR75 gains energy
        # near grazing; its constrained refit is tests/fitting/test_energy_constraint.py's).
        # Under the constraint TR75 cannot follow C8_Silver: the refit converges with e and n on
        # their search limits and sigma 2.7-3.3 (TR75 has no shadowing, and its lobe's grazing
        # albedo is what the constraint holds down), so these bounds are not its
        res = rb.fit(make(), meas, bounds=bounds, starts=4, progress=False,
                     energy_constraint=False)
        assert [c.channel for c in res] == ["465nm", "525nm", "630nm"]
        assert res.success, (name, [c.message for c in res])
        for c in res:
            assert 0.03 < c.sigma < SIGMA_MAX[model_name], (name, c.channel, c.sigma)
            assert 0.05 < c.rms_log < 2.0, (name, c.channel, c.rms_log)
            # theta_r > 75 deg is the Mini-Diff's extrapolation (roughbrdf.extrapolation):
            # 15 rows (76..90 deg) x 36 azimuths x 4 incidences = 2160 samples left out
            assert c.excluded["extrapolated"] == 2160
            assert c.n_points >= meas.n_samples - 2160 - 144  # and theta_r = 90 deg at most
            free = [p for p in c.free if math.isfinite(c.stderr[p])]
            assert free, (name, c.channel, c.message)


def test_tr75_paint_parameters_are_physical(paints):
    """Glossy black: narrow lobe; matte olive drab: broad lobe; Lambertian part small for both."""
    black = rb.fit("trowbridge-reitz-1975", paints["C2_Black"], channel="525nm", starts=4,
                   progress=False)
    olive = rb.fit("trowbridge-reitz-1975", paints["C12_OliveDrab"], channel="525nm", starts=4,
                   progress=False)
    assert black.params["e"] < 0.1 < 0.15 < olive.params["e"] < 0.5
    assert black.params["rho_L"] < 0.1 and olive.params["rho_L"] < 0.15


# ---------------------------------------------------------------------------------------------
# RB08 on the CEA retro-reflectors
# ---------------------------------------------------------------------------------------------
def _retro_distance_deg(meas) -> np.ndarray:
    """Angle (deg) between each sample's reflected direction and the source direction."""
    ti, tr, ph = meas.theta_i, meas.theta_r, meas.phi
    dot = (-np.sin(ti) * np.sin(tr) * np.cos(ph) + np.cos(ti) * np.cos(tr))
    return np.degrees(np.arccos(np.clip(dot, -1.0, 1.0)))


def retro_peaks(meas) -> dict[float, float]:
    """Measured value at the retro direction (the sample within 0.5 deg of it), per incidence."""
    d = _retro_distance_deg(meas)
    out = {}
    for t in meas.incidences(4):
        sel = (np.abs(meas.theta_i - t) < 1e-3) & (d <= 0.5)
        out[float(t)] = float(meas.values[sel, 0].max())
    return out


#: instrument aperture of the CEA gonio-reflectometer (half-angle): the minimum of the gray
#: tape's fit cost over 0.5-2 deg (bench_fit.py); the same instrument measured both files
APERTURE = math.radians(1.0)


def fit_rb08_retro(meas, *, weight: float = 20.0, cone: float = 2.0, starts: int = 8,
                   aperture: float | None = None):
    """RB08 (14 parameters) with the log loss; the samples within ``cone`` deg of the retro
    direction weigh ``weight`` times more, since the retro peak is a few dozen of ~7400
    samples and an unweighted fit of any loss ignores it. For speed: every 6th sample plus all
    within 3 deg of the retro direction (about 1460 samples).

    The plain fit uses 8 starts: with 2, which of the 14-parameter basins it ends in changed
    with the round-off of the kernels (the gray tape fell into one with no retro lobe,
    weighted chi2 125437 instead of 8698). With ``aperture``, the plain optimum, which already
    matches everything but the peak's top, is the first of 2 starts of the aperture fit
    (the result is the same from seeds 0 and 1, with 1 or 2 starts). Returns
    ``(aperture fit or plain fit, plain fit)``."""
    d = _retro_distance_deg(meas)
    keep = (np.arange(meas.n_samples) % 6 == 0) | (d <= 3.0)
    w = np.where(d[keep] <= cone, weight, 1.0)
    sub = meas.subset(keep)
    plain = rb.fit(rb.model("renhorn-boreman-2008"), sub, loss="log", weights=w, starts=starts,
                   progress=False)
    if aperture is None:
        return plain, plain
    res = rb.fit(plain.model, sub, loss="log", weights=w, starts=2, aperture=aperture,
                 progress=False)
    return res, plain


def _rb08_case(shared_data, name, aperture):
    if "renhorn-boreman-2008" not in rb.available():
        pytest.skip("RB08 model not available")
    meas = rb.read(shared_data / "cea_retro" / name, quantity="brdf_cos")
    res, plain = fit_rb08_retro(meas, aperture=aperture)
    assert res.success and res.aperture == aperture
    for t, measured in retro_peaks(meas).items():
        # what the instrument would read: the fitted model averaged over the aperture
        model = float(res.predict(t, t, math.pi))
        assert model == pytest.approx(measured, rel=0.3), (name, math.degrees(t), model)
    if aperture is not None:
        # the aperture explains the data better than the plain model does
        assert res.channels[0].chi2 < plain.channels[0].chi2


def test_rb08_reproduces_3m_retro_peak_heights(shared_data):
    """3M yellow sheeting: retro peak BRDF cos 11.9, 11.5, 7.5 at 15, 30, 60 deg; the fitted
    RB08 is within 30 % at each incidence, without an aperture (a broad retro lobe) and with
    the instrument's."""
    _rb08_case(shared_data, "retro-3M-jaune.dat", None)
    _rb08_case(shared_data, "retro-3M-jaune.dat", APERTURE)


def test_rb08_reproduces_gray_tape_retro_peak_heights_with_the_aperture(shared_data):
    """Gray tape: the measured retro peak is flat-topped (BRDF cos at 0/1/2/3 deg from retro,
    15 deg incidence: 72.5/60.5/16.9/3.7), blurred by the instrument's aperture, while the RB08
    retro lobe is a cusp; without an aperture the fit overshoots the retro point 2.1-2.6x.
    Fitted with the 1 deg aperture, the model averaged over it is within 30 % of the measured
    peak (72.5, 42.5, 1.13) at each incidence (here +23 / +26 / +21 %). The 60 deg peak is the
    weakly held one: fitted to all ~7400 samples (bench_fit.py) it is +42 % (+30 % with a
    1.25 deg aperture), while 15 and 30 deg stay within 25 %."""
    _rb08_case(shared_data, "retro-gray-tape.dat", APERTURE)


@pytest.mark.parametrize("name", ["retro-gray-tape.dat", "retro-3M-jaune.dat"])
def test_rb08_amplitude_reading_reproduces_retro_peaks_on_all_samples(shared_data, name):
    """The recipe that holds on ALL samples of both CEA files (docs/models.md §4.11: parameters
    13-14 are speculative). With the default "width" reading the retro peak can only grow with
    incidence (peak(15)/peak(60) <= 0.52 over 20,000 random parameter sets) while the gray tape's
    falls 64x (72.5, 42.5, 1.13); ``retro_shadowing="amplitude"`` lets the pair V(sin ti) V(sin ts)
    cut the retro strength (a retroreflector's acceptance angle). ``n_eff >= 1`` keeps the
    Fresnel factor physical (below 1 its total internal reflection fakes the cut-off). The
    single apex sample per incidence weighs about a whole 1-deg ring (x200; x50 overshoots it
    ~40 %, as a Lorentzian through the rings). Measured on all samples: gray tape +1/+6/+10 %,
    3M -2/+1/+6 % (sigma 0.417 / 0.892, 15 s / 2 s)."""
    if "renhorn-boreman-2008" not in rb.available():
        pytest.skip("RB08 model not available")
    meas = rb.read(shared_data / "cea_retro" / name, quantity="brdf_cos")
    d = _retro_distance_deg(meas)
    w = np.where(d <= 0.5, 200.0, np.where(d <= 2.0, 20.0, 1.0))
    # energy_constraint=False: the recipe's figures were measured unconstrained; under the
    # constraint (RB08's albedo <= 1 at every incidence) the gray tape's 60 deg retro peak
    # came out 1.7x the measured one with the penalty refit (not re-measured since the
    # constrained finish, fitting/solvers/constrained.py)
    res = rb.fit(rb.model("renhorn-boreman-2008", retro_shadowing="amplitude"), meas,
                 loss="log", weights=w, bounds={"n_eff": (1.0, 5.0)}, starts=8, seed=0,
                 progress=False, energy_constraint=False)
    assert res.channels[0].success
    for t, measured in retro_peaks(meas).items():
        model = float(res.model.bridf(t, t, math.pi))
        assert model == pytest.approx(measured, rel=0.3), (name, math.degrees(t), model)
