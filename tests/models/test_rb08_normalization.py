"""RB08's numeric normalization and its caches (``normalization="numeric"``, docs/models.md §4.12).

:class:`~roughbrdf.models.renhorn_boreman.normalization.NumericNormalization` owns the caches
(exact values per incidence, interpolation tables, the distinct incidences of recent arrays):
what they return must be what a fresh computation gives, keyed so that lobes never mix, and
they must stay within their bounds.
"""

from __future__ import annotations

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.models.renhorn_boreman import lobe_integral
from roughbrdf.models.renhorn_boreman import normalization as nrm

deg = np.radians
LOBE_A = (0.21, 0.7, 3.3)
LOBE_B = (0.05, 1.2, 0.4)


def test_cached_values_equal_a_fresh_computation(monkeypatch):
    ti = deg(np.repeat([0.0, 20.0, 45.0, 70.0], 5))
    cache = nrm.NumericNormalization()
    first, second = cache(ti, [LOBE_A, LOBE_B])
    uniq = np.unique(ti)
    fresh_a = 1.0 / lobe_integral(uniq, *LOBE_A)
    fresh_b = 1.0 / lobe_integral(uniq, *LOBE_B)
    assert np.array_equal(first, fresh_a[np.searchsorted(uniq, ti)])
    assert np.array_equal(second, fresh_b[np.searchsorted(uniq, ti)])

    # the second time everything comes from the caches: no quadrature runs
    def no_quadrature(*args):
        raise AssertionError("the cache recomputed a value it holds")

    monkeypatch.setattr(nrm, "lobe_integral", no_quadrature)
    again = cache(ti.copy(), [LOBE_B, LOBE_A])  # another array, the lobes the other way round
    assert np.array_equal(again[0], second) and np.array_equal(again[1], first)
    assert cache(ti, [None, LOBE_A])[0] is None


def test_interpolation_tables_are_cached_per_lobe():
    # more distinct incidences than max_exact: the values come from a table per lobe
    ti = deg(np.linspace(0.0, 85.0, 40))
    cache = nrm.NumericNormalization(max_exact=8)
    a1, b1 = cache(ti, [LOBE_A, LOBE_B])
    assert cache.sizes()["tables"] == 2
    a2, b2 = cache(ti.copy(), [LOBE_A, LOBE_B])
    fresh_a, fresh_b = nrm.NumericNormalization(max_exact=8)(ti, [LOBE_A, LOBE_B])
    assert np.array_equal(a1, a2) and np.array_equal(a1, fresh_a)
    assert np.array_equal(b1, b2) and np.array_equal(b1, fresh_b)
    np.testing.assert_allclose(a1, 1.0 / lobe_integral(ti, *LOBE_A), rtol=1e-6)
    assert not np.array_equal(a1, b1)


def test_caches_stay_within_their_bounds():
    cache = nrm.NumericNormalization(max_values=10, max_exact=4, max_tables=2, max_index=3)
    ti = deg([0.0, 30.0, 50.0, 70.0])
    for k in range(8):  # 8 lobes of 4 incidences each: 32 values through a cache of 10
        lobe = (0.1 + 0.05 * k, 0.8, 2.0)
        got = cache(ti + 0.0, [lobe])[0]
        assert np.array_equal(got, 1.0 / lobe_integral(ti, *lobe))
        sizes = cache.sizes()
        assert sizes["values"] <= 10 and sizes["index"] <= 3
    many = deg(np.linspace(0.0, 80.0, 12))  # above max_exact: tables
    for k in range(6):
        cache(many, [(0.1 + 0.05 * k, 0.8, 2.0)])
        # emptied when a new table comes on top of more than max_tables
        assert cache.sizes()["tables"] <= 3
    cache.clear()
    assert cache.sizes() == {"values": 0, "tables": 0, "index": 0}


@pytest.mark.parametrize("n_incidences", [4, 300])  # exact values; interpolation tables
def test_the_model_reads_the_shared_caches(n_incidences):
    # from the user's side: a numeric-N model gives the same numbers from the caches as after
    # emptying them, and its evaluations fill the one shared instance
    m = rb.model("rb08", normalization="numeric", n=3.3, n_r=2.7, w_a=0.3)
    ti = deg(np.repeat(np.linspace(0.0, 80.0, n_incidences), 3))
    tr = deg(np.tile([10.0, 40.0, 70.0], n_incidences))
    nrm.NUMERIC_N.clear()
    first = m.brdf(ti, tr, 0.2)
    assert nrm.NUMERIC_N.sizes()["values" if n_incidences == 4 else "tables"] > 0
    cached = m.brdf(ti, tr, 0.2)
    nrm.NUMERIC_N.clear()
    fresh = m.brdf(ti, tr, 0.2)
    assert np.array_equal(first, cached) and np.array_equal(first, fresh)
