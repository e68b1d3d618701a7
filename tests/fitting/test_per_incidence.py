"""Fits per incidence and the rows a catalog keeps (``fitting/kinds/per_incidence.py``).

Expected values: a Lambertian truth whose ``rho`` is linear in ``cos theta_i`` (then Zemax's
interpolation rule, linear in cosine, is exact between any two rows) or piecewise constant (then
it is not, by an amount computed here by hand); the TIS of a Lambertian model is ``rho``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf._kernels import DISABLE_JIT
from roughbrdf.errors import ArgumentError
from roughbrdf.fitting.kinds.per_incidence import MAX_ROWS, fit_per_incidence, interpolate_params


def _measurement(rho_of_theta, incidences_deg):
    """Noise-free Lambertian data whose rho depends on the incidence."""
    ti, tr, ph = (a.ravel() for a in np.meshgrid(
        np.radians(incidences_deg), np.radians(np.arange(0.0, 80.0, 10.0)), [0.0, np.pi],
        indexing="ij"))
    values = np.array([rho_of_theta(t) / math.pi for t in ti])
    return rb.Measurement(ti, tr, ph, values)


#: the greedy choice of rows: 12 incidences, more than Zemax's 10 rows (the default max_rows).
#: Under NUMBA_DISABLE_JIT=1 (make test-nojit) 4 incidences, 3 kept: each trial of the choice
#: takes one albedo per row (seconds each in plain Python; 12 rows took over 5 min), and 4 rows
#: of 3 still take the greedy loop's steps (a row added to the two ends by its score)
GREEDY_ROWS, GREEDY_KEPT = (4, {"max_rows": 3}) if DISABLE_JIT else (12, {})


def test_rows_recover_each_incidence_and_interpolation_is_exact_when_linear_in_cos():
    def rho(t):
        return 0.2 + 0.4 * math.cos(t)

    angles = np.linspace(0.0, 77.0, GREEDY_ROWS)
    res = fit_per_incidence("lambertian", _measurement(rho, angles), starts=1, progress=False,
                            **GREEDY_KEPT)
    assert len(res.rows) == GREEDY_ROWS
    assert len(res.chosen) == GREEDY_KEPT.get("max_rows", MAX_ROWS) < GREEDY_ROWS
    assert res.chosen[0] == 0 and res.chosen[-1] == GREEDY_ROWS - 1  # the end rows always
    for r in res.rows:
        # to the search's own tolerance (1e-4 of the cost: a fit this small is not polished)
        assert r.params("value")["rho"] == pytest.approx(rho(r.theta_i), rel=1e-4)
        assert r.tis["value"] == pytest.approx(rho(r.theta_i), rel=1e-4)  # TIS = rho
    # rho linear in cos: the interpolated rows reproduce every left-out incidence
    assert res.tis_error["value"] < 2e-4 and res.rms_log["value"] < 1e-4
    assert res.success


def test_two_rows_of_three_give_the_error_of_the_middle_incidence():
    # rho 0.3 at 0 and 60 deg, 0.6 at 30 deg: with the rows at 0 and 60 deg kept, the
    # interpolation gives 0.3 at 30 deg: TIS error |0.3 - 0.6| / 0.6 = 0.5, and the data there
    # are 2x the model: rms-log over the three incidences' samples sqrt(ln(2)^2 / 3)
    res = fit_per_incidence("lambertian",
                            _measurement(lambda t: 0.6 if abs(t - math.radians(30)) < 1e-6
                                         else 0.3, [0.0, 30.0, 60.0]),
                            max_rows=2, starts=1, progress=False)
    assert res.chosen == [0, 2]
    assert res.tis_error["value"] == pytest.approx(0.5, rel=1e-3)
    assert res.rms_log["value"] == pytest.approx(math.log(2.0) / math.sqrt(3.0), rel=1e-3)
    model = res.model_at(math.radians(30.0))
    assert model.params["rho"] == pytest.approx(0.3, rel=1e-4)


def test_interpolation_is_linear_in_cosine_and_held_outside():
    rows = [{"A": 1.0, "g": 2.0}, {"A": 3.0, "g": 2.0}]
    t = [math.radians(20.0), math.radians(60.0)]
    mid = math.acos(0.5 * (math.cos(t[0]) + math.cos(t[1])))
    assert interpolate_params(t, rows, mid)["A"] == pytest.approx(2.0)
    assert interpolate_params(t, rows, 0.0) == {"A": 1.0, "g": 2.0}  # below the first row
    assert interpolate_params(t, rows, math.radians(85.0))["A"] == 3.0  # above the last


def test_report_and_dict_say_which_rows_are_kept_in_degrees():
    res = fit_per_incidence("lambertian", _measurement(lambda t: 0.5, [10.0, 40.0]),
                            starts=1, progress=False)
    d = res.to_dict()
    assert [r["theta_i_deg"] for r in d["rows"]] == pytest.approx([10.0, 40.0])
    assert all(r["kept"] for r in d["rows"]) and d["per_incidence"] is True
    text = res.report()
    assert "2 of 2 rows kept" in text and "40.000" in text and "TIS" in text


@pytest.mark.parametrize(("kw", "name"), [({"max_rows": 1}, "max_rows"),
                                          ({"max_rows": 2.5}, "max_rows")])
def test_bad_arguments_are_named(kw, name):
    meas = _measurement(lambda t: 0.5, [10.0, 40.0])
    with pytest.raises(ArgumentError, match=name):
        fit_per_incidence("lambertian", meas, progress=False, **kw)


def test_auto_is_refused():
    with pytest.raises(ArgumentError, match="model"):
        fit_per_incidence("auto", _measurement(lambda t: 0.5, [10.0]), progress=False)
