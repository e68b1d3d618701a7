"""A lone microfacet lobe's ``ks`` against the data scale and its physical range.

Expected values: the model (``docs/models.md``, microfacet: ``ks D G F/(4 cos cos)``) is linear
in ``ks``, so relative data (``K x ~ f``, a free ``K``) cannot tell ``ks`` from ``K``: ``ks`` is
held at 1 and ``K`` comes out as ``1/ks_true`` times the data's own scale; ``ks = 1`` is the most
one interface with ``F <= 1`` reflects, so a fit ending there ends on a physical limit.
"""

from __future__ import annotations

import numpy as np
import pytest

import roughbrdf as rb

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

TRUTH = rb.model("microfacet", alpha=0.25, n=1.5, k=0.0, ks=0.6)


def _grid():
    return [a.ravel() for a in np.meshgrid(np.radians([10, 30, 50]),
                                            np.radians(np.arange(0, 81, 5)),
                                            np.radians([0, 45, 90, 135, 180]), indexing="ij")]


def test_relative_data_hold_ks_at_1_and_k_carries_the_scale():
    g = _grid()
    meas = rb.Measurement(*g, 3.0 * TRUTH.brdf(*g), quantity="relative")
    res = rb.fit("microfacet", meas, starts=2, progress=False)
    (c,) = res.channels
    assert "ks" not in c.free and c.params["ks"] == 1.0
    assert res.options["fix"] == ["ks"]
    # K x = f with ks = 1: K = ks_true-free model / (3 ks_true model) = 1/(3 x 0.6)
    assert c.scale == pytest.approx(1 / 1.8, rel=2e-3)  # to the fit's tolerance
    assert c.params["alpha"] == pytest.approx(0.25, rel=2e-3)
    assert np.isfinite(c.stderr["alpha"]) and not c.at_bound


def test_held_only_without_the_users_own_choice():
    g = _grid()
    meas = rb.Measurement(*g, 3.0 * TRUTH.brdf(*g), quantity="relative")
    # the user's bounds on ks: searched (and the degeneracy is theirs)
    res = rb.fit("microfacet", meas, starts=1, progress=False, bounds={"ks": (0.1, 1.0)})
    assert "ks" in res.channels[0].free
    # absolute data: ks is fitted
    absolute = rb.fit("microfacet", rb.Measurement(*g, TRUTH.brdf(*g)), starts=2,
                      progress=False)
    (c,) = absolute.channels
    assert "ks" in c.free and c.params["ks"] == pytest.approx(0.6, rel=1e-4)


def test_ks_at_1_is_a_physical_limit_not_a_search_limit():
    # data brighter than one interface can reflect: ks ends on 1, its physical edge
    g = _grid()
    bright = rb.Measurement(*g, 1.5 * TRUTH.with_params(ks=1.0).brdf(*g))
    res = rb.fit("microfacet", bright, starts=2, progress=False)
    (c,) = res.channels
    assert c.params["ks"] == pytest.approx(1.0)
    assert c.limits == {"ks": "physical-upper"}
    # the same value reached with a wider, non-physical search range is not a limit at all
    wide = rb.fit("microfacet", bright, starts=2, progress=False, bounds={"ks": (0.0, 20.0)})
    # ks is on no limit; k may end on its physical lower bound 0 (the truth's k = 0: where it
    # ends, 0 or 1e-9 above, is the optimizer's path, not the physics)
    assert "ks" not in wide.channels[0].limits
    assert set(wide.channels[0].limits.items()) <= {("k", "physical-lower")}
    assert wide.channels[0].params["ks"] > 1.0
