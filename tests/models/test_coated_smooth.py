"""The coated model is smooth in its parameters where the smooth interface's energy limit is
active (``docs/models.md`` §10.3): a fit's forward differences (steps ~1e-8 relative) see its
derivative, and exact data of such a model is recovered by ``rb.fit``."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import roughbrdf as rb

#: a coarse in-plane and out-of-plane grid (degrees -> radians), as in test_fit_limits
GRID = np.radians(np.mgrid[0:61:20, 0:81:5, 0:181:30].reshape(3, -1))
#: Beckmann lobe at alpha 0.25, n = 1.45: the lobe reflects more than R(theta) from 0 to
#: ~55 deg, so the substrate's factor is limited to (1 - E)/(1 - R) < 1 there
TRUTH = {"distribution": "beckmann", "n": 1.45, "rho": 0.5, "alpha": 0.25}


def test_the_energy_limit_is_active_at_the_truth():
    """The premise of the tests below: the limited substrate is below the smooth formula."""
    free = rb.model("coated", weights="free", ks=1.0, **TRUTH)  # the smooth formula
    limited = rb.model("coated", **TRUTH)
    ratio = limited.brdf(*GRID) / free.brdf(*GRID)
    assert ratio.min() < 1.0 - 1e-4


@pytest.mark.parametrize("name", ["n", "alpha"])
def test_forward_difference_matches_the_derivative(name):
    """A relative step of 1.5e-8 (the fit's) changes the model in proportion: its forward
    difference matches a central difference of step 1e-4 to 1e-4 of the largest derivative
    (a model piecewise constant at the 1e-7 level gives 0 or a jump instead: 1e-2 in n)."""
    model = rb.model("coated", **TRUTH)
    x = TRUTH[name]

    def f(v: float) -> np.ndarray:
        return model.with_params(**{name: v}).brdf(*GRID)

    h, big = 1.5e-8 * x, 1e-4 * x
    forward = (f(x + h) - f(x)) / h
    central = (f(x + big) - f(x - big)) / (2 * big)
    assert np.abs(forward - central).max() < 1e-4 * np.abs(central).max()


@pytest.mark.jit_heavy(reason="a whole coated fit (2 starts) and its albedos: over 5 min in "
                       "plain Python")
def test_exact_data_recovered():
    """Exact data of the limited model: ``rb.fit`` returns its parameters to 1e-7."""
    truth = rb.model("coated", **TRUTH)
    meas = rb.Measurement(*GRID, truth.brdf(*GRID))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the fit's notes on a synthetic data set
        result = rb.fit(rb.model("coated", distribution="beckmann"), meas, starts=2,
                        progress=False)
    params = result.channels[0].params
    for name in ("n", "rho", "alpha"):
        assert params[name] == pytest.approx(TRUTH[name], rel=1e-7), name
