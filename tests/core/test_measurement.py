"""Measurement: construction checks, validation counts, explicit drop, selection helpers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from roughbrdf.measurement import QUANTITIES, Measurement


def _m(**kw):
    ti = np.radians([0, 30, 30, 30, 60, 60])
    tr = np.radians([10, 30, 30, 45, 60, 70])
    ph = np.radians([0, 0, 180, 90, 0, 180])
    vals = np.array([[1.0, 2.0], [np.nan, 1.0], [0.5, -1e-4], [0.2, 0.3], [-2e-5, np.inf],
                     [0.1, 0.1]])
    args = dict(theta_i=ti, theta_r=tr, phi=ph, values=vals, channels=["465nm", "525nm"],
                quantity="brdf", original={"theta_s": np.degrees(tr)},
                meta={"file": "x.astm", "sample": "S", "instrument": "I", "date": "D"})
    args.update(kw)
    return Measurement(**args)


def test_validate_counts_and_never_drops():
    m = _m()
    rep = m.validate()
    assert rep == {"465nm": {"n": 6, "nonfinite": 1, "negative": 1},
                   "525nm": {"n": 6, "nonfinite": 1, "negative": 1}}
    assert m.n_samples == 6  # nothing removed by validate
    assert "1 non-finite" in m.validation_text()
    assert "non-finite" in m.summary()


def test_drop_is_explicit_and_reports_what_it_removed():
    m = _m()
    kept, info = m.drop(nonfinite=True, negative=False)
    assert info["n_dropped"] == 2 and info["n_after"] == 4 == kept.n_samples
    assert info["nonfinite"] == {"465nm": 1, "525nm": 1}
    assert info["mask"].tolist() == [False, True, False, False, True, False]
    assert kept.meta["dropped"][0]["n_dropped"] == 2
    assert np.isfinite(kept.values).all()
    kept2, info2 = m.drop(nonfinite=True, negative=True)
    assert info2["n_dropped"] == 3 and info2["negative"]["525nm"] == 1
    # per-channel: a bad value in the other channel does not remove good data
    k3, info3 = m.select_channel("465nm").drop(nonfinite=True, negative=True)
    assert info3["n_dropped"] == 2 and k3.n_samples == 4
    k4, info4 = m.drop(nonfinite=False, negative=False)
    assert info4["n_dropped"] == 0 and k4.n_samples == 6
    # originals follow the samples
    assert kept.original["theta_s"].shape == (4,)


def test_selection_helpers():
    m = _m()
    assert m.channel_index("525nm") == 1 == m.channel_index("525") == m.channel_index(1)
    assert m.channel_index(-1) == 1
    with pytest.raises(ValueError, match="unknown channel"):
        m.channel_index("630nm")
    with pytest.raises(ValueError, match="out of range"):
        m.channel_index(5)
    s = m.select_channel("465")
    assert s.channels == ["465nm"] and s.values.shape == (6, 1)
    assert m.select_channels(["525nm", "465nm"]).channels == ["525nm", "465nm"]
    assert np.allclose(m.incidences(), np.radians([0, 30, 60]))
    assert m.at_incidence(math.radians(30)).n_samples == 3
    ip = m.in_plane()
    assert ip.n_samples == 5  # the phi = 90 deg sample is out of plane
    assert ip.original["theta_s"].shape == (5,)
    assert m.file == "x.astm" and m.sample == "S" and m.instrument == "I" and m.date == "D"


def test_quantity_conversion_and_polarization():
    m = _m(values=np.ones((6, 2)), uncertainty=0.1 * np.ones((6, 2)))
    c = m.as_quantity("brdf_cos")
    assert np.allclose(c.values[:, 0], np.cos(m.theta_r))
    assert np.allclose(c.uncertainty[:, 0], 0.1 * np.cos(m.theta_r))
    assert np.allclose(c.to_brdf(), 1.0)
    assert np.allclose(c.as_quantity("brdf").values, 1.0)
    assert c.as_quantity("bridf").quantity == "bridf"
    r = m.as_quantity("relative")
    with pytest.raises(ValueError, match="relative"):
        r.to_brdf()
    with pytest.raises(ValueError, match="relative"):
        r.as_quantity("brdf")
    p = _m(polarization=np.array([0, 0, np.pi / 2, np.nan, np.nan, 0.0]))
    assert p.with_polarization(0.0).n_samples == 3
    assert p.with_polarization(None).n_samples == 2
    assert _m().with_polarization(None).n_samples == 6


@pytest.mark.parametrize("bad, match", [
    (dict(theta_r=np.zeros(5)), "theta_r has 5 samples"),
    (dict(values=np.zeros((6, 3))), "3 value"),
    (dict(quantity="radiance"), "quantity must be one of"),
    (dict(channels=["a", "a"]), "distinct"),
    # the argument, then the rule (geometry.check_angles words it "theta_i = 2.0 rad: must be
    # in ..." since errors.ArgumentError; before, "theta_i must be in ...")
    (dict(theta_i=np.full(6, 2.0)), r"theta_i\b.*must be in"),
    (dict(phi=np.full(6, np.nan)), r"phi\b.*must be finite"),
    (dict(original={"x": np.zeros(3)}), "original"),
])
def test_construction_errors_name_the_file(bad, match):
    with pytest.raises(ValueError, match=match) as exc:
        _m(**bad)
    assert "x.astm" in str(exc.value)


def test_quantities_listed():
    assert QUANTITIES == ("brdf", "brdf_cos", "bridf", "relative")
    assert "6 samples" in repr(_m())
