"""A fit gives a wavelength-dependent model each channel's wavelength
(``fitting/problem/wavelengths.py``).

The K-correlation (Rayleigh–Rice) BRDF scales as ``lambda^-4`` times the PSD at
``|beta - beta0|/lambda`` (``docs/straylight.md``): data of two channels at 465 and 630 nm from
one surface are fitted with one parameter set per channel, each at its wavelength, and recover
that surface (synthetic, 2 % noise, within 3 standard errors).
"""

from __future__ import annotations

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.errors import ArgumentError
from roughbrdf.fitting.problem.wavelengths import (
    channel_wavelength,
    needs_wavelength,
    with_wavelength,
)

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

TRUTH = {"A": 2e-5, "B": 8.0, "C": 3.0}


def _grid():
    return (a.ravel() for a in np.meshgrid(np.radians([10.0, 30.0, 50.0]),
                                           np.radians(np.arange(0.0, 80.0, 4.0)),
                                           np.radians(np.arange(0.0, 181.0, 30.0)),
                                           indexing="ij"))


def _measurement(channels=("465nm", "630nm"), noise=0.02, seed=3, **kw):
    ti, tr, ph = _grid()
    rng = np.random.default_rng(seed)
    cols = []
    for lam in (0.465, 0.630):
        m = rb.model("k-correlation", **TRUTH, n=1.5, k=0.0, wavelength=lam)
        cols.append(m.brdf(ti, tr, ph) * np.exp(noise * rng.standard_normal(ti.size)))
    return rb.Measurement(ti, tr, ph, np.column_stack(cols), channels=list(channels), **kw)


def test_each_channel_is_fitted_at_its_wavelength_and_recovers_the_surface():
    start = rb.model("k-correlation", A=1e-5, B=4.0, C=2.5, n=1.5, k=0.0)
    res = rb.fit(start, _measurement(), fix=["n", "k"], progress=False)
    assert [c.model.options["wavelength"] for c in res] == [0.465, 0.63]
    for c in res:
        assert c.success, c.message
        for name, true in TRUTH.items():
            assert abs(c.params[name] - true) <= 3 * c.stderr[name], (c.channel, name)


def test_wavelength_from_the_file_then_the_option():
    # channel names that are no wavelength, the file's wavelengths in meta (as the readers set)
    meas = _measurement(channels=("blue", "red"), meta={"wavelengths_nm": [465.0, 630.0]})
    assert channel_wavelength(meas, 0) == 0.465 and channel_wavelength(meas, 1) == 0.63
    assert channel_wavelength(meas, 1, given="1064nm") == 1.064  # the option wins


def test_a_fit_without_a_wavelength_is_refused_naming_it():
    meas = _measurement(channels=("blue", "red"))
    with pytest.raises(ArgumentError, match="wavelength") as err:
        rb.fit("k-correlation", meas, fix=["n", "k"], progress=False)
    assert "'blue'" in str(err.value) and "--wavelength" in str(err.value)
    res = rb.fit("k-correlation", meas, fix=["n", "k"], wavelength=0.5, channel="blue",
                 starts=1, progress=False)
    assert res[0].model.options["wavelength"] == 0.5


@pytest.mark.parametrize("bad", [-1.0, "630", "5 parsecs", 630.0])
def test_a_bad_wavelength_option_is_named(bad):
    with pytest.raises(ArgumentError, match="wavelength"):
        rb.fit("k-correlation", _measurement(), wavelength=bad, progress=False)


def test_joint_fit_across_wavelengths_is_refused():
    with pytest.raises(ArgumentError, match="joint"):
        rb.fit("k-correlation", _measurement(), joint=True, progress=False)


def test_needs_and_with_wavelength_on_sums():
    s = rb.model("k-correlation") + rb.model("lambertian")
    assert needs_wavelength(s) and not needs_wavelength(rb.model("tr75"))
    t = with_wavelength(s, 0.55)
    assert not needs_wavelength(t) and t.params == s.params
    assert t.components[0].options["wavelength"] == 0.55
