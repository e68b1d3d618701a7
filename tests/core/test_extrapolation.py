"""Values a file holds beyond the instrument's range (:mod:`roughbrdf.extrapolation`).

Where the expected numbers come from:

* synthetic rows built here on the Mini-Diff's grid (``theta_r`` 0-90 deg by 1 deg,
  ``../shared/data/README.md``): a row is a ramp when its values from ``theta_c`` on are
  ``x(theta_c) (90 - theta_r)/(90 - theta_c)`` (the module notes), so the start, the rows and
  the samples beyond are known by construction;
* the real Mini-Diff files (``../shared/data/minidiff``): ``theta_c = 75`` deg and the four
  azimuths of the camera's axes exact (the module notes); 4 incidences x 36 azimuths = 144 rows
  reach 90 deg and each has 15 samples beyond 75 deg (76..90), so 144 x 15 = 2160 samples
  (the README's grid); the counts of non-positive values are taken from the files here.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

import roughbrdf as rb
from roughbrdf.cli import app
from roughbrdf.errors import ArgumentError
from roughbrdf.extrapolation import (
    RAMP_RTOL,
    extrapolated_mask,
    find_extrapolated_tail,
    mark_extrapolated,
)

TR_DEG = np.arange(0.0, 91.0)  # the Mini-Diff's theta_r grid (shared/data/README.md)
INCIDENCES = (0.0, 30.0, 60.0)
AZIMUTHS = (0.0, 45.0, 90.0, 135.0, 180.0)
PAINTS = ("C2_Black", "C8_Silver", "C12_OliveDrab")


def _measured(ti: float, ph: float, seed: int, channels: int) -> np.ndarray:
    """A measured-looking row: a smooth lobe with 2 % noise, shape (91, channels)."""
    rng = np.random.default_rng(seed)
    tr = np.radians(TR_DEG)
    lobe = 0.1 + 0.5 * np.exp(-((tr - math.radians(ti)) ** 2) / 0.05) * (1 + math.cos(
        math.radians(ph))) / 2
    scale = np.linspace(1.0, 1.4, channels)
    return lobe[:, None] * scale * (1 + 0.02 * rng.standard_normal((tr.size, channels)))


def _ramp(row: np.ndarray, start_deg: float, wobble: float = 0.0) -> np.ndarray:
    """``row`` with its samples beyond ``start_deg`` replaced by the line to 0 at 90 deg (times
    ``1 + wobble sin(...)``: the interpolated rows of the real files)."""
    out = row.copy()
    c = int(np.flatnonzero(TR_DEG == start_deg)[0])
    frac = (90.0 - TR_DEG[c + 1:]) / (90.0 - start_deg)
    out[c + 1:] = row[c] * frac[:, None] * (1 + wobble * np.sin(TR_DEG[c + 1:]))[:, None]
    return out


def _build(kind, channels: int = 2) -> rb.Measurement:
    """A measurement of every (incidence, azimuth) row; ``kind(ti, phi, row)`` makes the row."""
    ti, tr, ph, vals = [], [], [], []
    for i, t in enumerate(INCIDENCES):
        for j, p in enumerate(AZIMUTHS):
            row = kind(t, p, _measured(t, p, 10 * i + j, channels))
            ti.append(np.full(TR_DEG.size, t))
            tr.append(TR_DEG)
            ph.append(np.full(TR_DEG.size, p))
            vals.append(row)
    g = [np.radians(np.concatenate(a)) for a in (ti, tr, ph)]
    return rb.Measurement(*g, np.concatenate(vals),
                          channels=[f"c{k}" for k in range(channels)])


def _tail(meas: rb.Measurement):
    return find_extrapolated_tail(meas.theta_i, meas.theta_r, meas.phi, meas.values)


def _like_minidiff(t: float, p: float, row: np.ndarray) -> np.ndarray:
    """Exact ramps from 75 deg on the axes' azimuths (0, 90, 180), 1 % off elsewhere."""
    return _ramp(row, 75.0, 0.0 if p % 90 == 0 else 0.01)


# ------------------------------------------------------------------------------------------
# detection on synthetic rows
# ------------------------------------------------------------------------------------------
def test_exact_ramp_in_every_incidence_is_found():
    meas = _build(_like_minidiff)
    tail = _tail(meas)
    assert tail is not None
    assert tail.start == pytest.approx(math.radians(75.0), abs=1e-9)
    # 3 incidences x 3 exact azimuths (0, 90, 180); 3 x 5 rows reach 90 deg
    assert tail.exact_rows == 9 and tail.rows == 15
    assert tail.describe() == ("theta_r > 75 deg is a linear extrapolation to 0 at 90 deg, not a "
                               "measurement (9 of 15 rows exactly)")


def test_single_channel_values_and_one_dimensional_values():
    meas = _build(_like_minidiff, channels=1)
    one_d = find_extrapolated_tail(meas.theta_i, meas.theta_r, meas.phi, meas.values[:, 0])
    assert one_d == _tail(meas) and one_d is not None and one_d.exact_rows == 9


def test_the_smallest_start_of_a_row_is_reported():
    """A row that is a ramp from 75 deg is one from 80 deg too: the start is the smallest."""
    tail = _tail(_build(lambda t, p, row: _ramp(row, 75.0)))
    assert tail is not None and tail.start == pytest.approx(math.radians(75.0), abs=1e-9)
    assert tail.exact_rows == tail.rows == 15


def test_a_row_with_a_non_finite_value_is_not_considered():
    def kind(t, p, row):
        row = _like_minidiff(t, p, row)
        if t == 30.0 and p == 45.0:
            row[10, 0] = np.nan
        return row

    tail = _tail(_build(kind))
    assert tail is not None and tail.rows == 14 and tail.exact_rows == 9


def test_rows_in_any_sample_order_and_only_long_rows_walked(monkeypatch):
    # the rows are found by one sort (extrapolation._rows), not one array per row: the same
    # tail whatever the order of the samples, and the per-row walk (_ramp_start) only for the
    # rows that can hold a ramp -- none of 20000 one-sample rows (a MERL file: a million)
    from roughbrdf import extrapolation

    meas = _build(_like_minidiff)
    perm = np.random.default_rng(5).permutation(meas.n_samples)
    shuffled = find_extrapolated_tail(meas.theta_i[perm], meas.theta_r[perm], meas.phi[perm],
                                      meas.values[perm])
    assert shuffled == _tail(meas) and shuffled is not None and shuffled.exact_rows == 9
    walked = []
    real = extrapolation._ramp_start
    monkeypatch.setattr(extrapolation, "_ramp_start",
                        lambda tr, x: walked.append(tr.size) or real(tr, x))
    rng = np.random.default_rng(6)
    ti, ph = rng.uniform(0, 1.5, 20000), rng.uniform(-3, 3, 20000)
    tr = np.full(20000, 0.5 * math.pi)  # each row a single sample at 90 deg: counted, no ramp
    tail = find_extrapolated_tail(ti, tr, ph, np.zeros((20000, 1)))
    assert tail is None and walked == []
    assert find_extrapolated_tail(ti[:0], tr[:0], ph[:0], np.zeros((0, 1))) is None
    assert _tail(meas) is not None and walked == [TR_DEG.size] * 15  # the 15 rows, whole


@pytest.mark.parametrize("case", ["measured", "model_brdf_cos", "zeros", "all_zeros",
                                  "some_incidences", "two_starts", "near_ramp", "too_short"])
def test_not_detected(case):
    """Rows that are not the software's ramp, or ramps that are not in every incidence from one
    start, are no extrapolated tail."""
    if case == "measured":
        meas = _build(lambda t, p, row: row)
    elif case == "model_brdf_cos":
        # noise-free BRDF cos(theta_r) of a Lambertian surface: it goes to 0 at 90 deg and is
        # nearly a straight line there (cos 88/cos 87 = 0.66682 against 2/3), but not exactly
        g = np.radians(np.stack(np.meshgrid(INCIDENCES, TR_DEG, AZIMUTHS, indexing="ij"))
                       .reshape(3, -1))
        meas = rb.Measurement(*g, rb.model("lambertian", rho=0.4).brdf(*g) * np.cos(g[1]),
                              quantity="brdf_cos")
    elif case == "zeros":  # the 60 deg incidence has rows of zeros instead of ramps
        meas = _build(lambda t, p, row: np.zeros_like(row) if t == 60.0 and p % 90 == 0
                      else _ramp(row, 75.0, 0.0 if p % 90 == 0 else 0.01))
    elif case == "all_zeros":
        meas = _build(lambda t, p, row: np.zeros_like(row))
    elif case == "some_incidences":  # no ramp at 60 deg incidence
        meas = _build(lambda t, p, row: row if t == 60.0 else _like_minidiff(t, p, row))
    elif case == "two_starts":  # 60 deg incidence ramps from 70 deg, the others from 75
        meas = _build(lambda t, p, row: _ramp(row, 70.0 if t == 60.0 else 75.0))
    elif case == "near_ramp":  # a ramp to 1000 x the tolerance
        meas = _build(lambda t, p, row: _ramp(row, 75.0, 1e3 * RAMP_RTOL))
    else:  # 88 deg: 2 samples beyond the start, fewer than MIN_RAMP_SAMPLES (4)
        meas = _build(lambda t, p, row: _ramp(row, 88.0))
    assert _tail(meas) is None
    assert mark_extrapolated(meas) is None
    assert "extrapolated_beyond" not in meas.meta and "extrapolated" not in meas.meta


def test_fewest_ramp_samples():
    """MIN_RAMP_SAMPLES = 4 samples beyond the start, the 90 deg one included (module notes):
    a ramp from 86 deg (87, 88, 89, 90) is found, one from 87 deg (3 samples) is not."""
    found = _tail(_build(lambda t, p, row: _ramp(row, 86.0)))
    assert found is not None and found.start == pytest.approx(math.radians(86.0), abs=1e-9)
    assert _tail(_build(lambda t, p, row: _ramp(row, 87.0))) is None


def test_the_start_sample_itself_is_not_flagged():
    meas = _build(_like_minidiff)
    start = _tail(meas).start
    mask = extrapolated_mask(meas.theta_r, start)
    deg = np.degrees(meas.theta_r)
    assert not mask[np.isclose(deg, 75.0)].any()
    assert mask[np.isclose(deg, 76.0)].all()
    assert mask.sum() == 15 * 15  # 15 rows x 15 samples (76..90 deg)
    np.testing.assert_array_equal(mask, deg > 75.0 + 1e-6)
    assert not extrapolated_mask(meas.theta_r, None).any()


def test_mark_extrapolated_records_and_leaves_the_values():
    meas = _build(_like_minidiff)
    before = meas.values.copy()
    tail = mark_extrapolated(meas)
    assert meas.meta["extrapolated_beyond"] == tail.start
    assert meas.meta["extrapolated"] == tail.describe()
    np.testing.assert_array_equal(meas.values, before)


# ------------------------------------------------------------------------------------------
# fits of a synthetic measurement
# ------------------------------------------------------------------------------------------
def _fit(meas, model="lambertian", **kw):
    # the relative loss unless a test says otherwise: with the default (robust for the
    # Lambertian model) negative="auto" would also drop the ramp's zeros, and these tests
    # count exactly what the extrapolation rule leaves out
    kw.setdefault("loss", "relative")
    return rb.fit(model, meas, starts=1, progress=False, **kw)


def test_fit_drops_by_default_and_keeps_when_asked():
    meas = _build(_like_minidiff, channels=1)
    mark_extrapolated(meas)
    n_beyond = 15 * 15
    drop = _fit(meas)
    c = drop.channels[0]
    assert c.excluded["extrapolated"] == n_beyond
    assert c.n_points == meas.n_samples - n_beyond
    assert drop.options["extrapolated"] == "drop"
    assert "not measured       = theta_r > 75 deg" in drop.report()
    assert "left out (extrapolated='keep' fits them)" in drop.report()
    keep = _fit(meas, extrapolated="keep")
    assert keep.channels[0].excluded["extrapolated"] == 0
    assert keep.channels[0].n_points == meas.n_samples
    assert "fitted (asked)" in keep.report()
    assert json.loads(keep.to_json())["options"]["extrapolated"] == "keep"
    # dropping is fitting the measured samples alone
    alone = _fit(meas.subset(~extrapolated_mask(meas.theta_r, meas.meta["extrapolated_beyond"])))
    assert alone.channels[0].n_points == c.n_points
    assert alone.channels[0].params["rho"] == pytest.approx(c.params["rho"], rel=1e-9)


def test_without_a_tail_nothing_is_left_out_and_the_report_is_silent():
    meas = _build(lambda t, p, row: row, channels=1)
    assert mark_extrapolated(meas) is None
    res = _fit(meas)
    assert res.channels[0].excluded["extrapolated"] == 0
    assert res.channels[0].n_points == meas.n_samples
    assert "not measured" not in res.report()


@pytest.mark.parametrize("bad", ["maybe", None, True, 0])
def test_bad_extrapolated_option_names_the_argument(bad):
    meas = _build(_like_minidiff, channels=1)
    with pytest.raises(ArgumentError) as info:
        _fit(meas, extrapolated=bad)
    assert info.value.argument == "extrapolated" and "'drop' or 'keep'" in str(info.value)


# ------------------------------------------------------------------------------------------
# the real Mini-Diff files
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", PAINTS)
def test_minidiff_tail(paints, name):
    meas = paints[name]
    tail = _tail(meas)
    assert math.degrees(tail.start) == pytest.approx(75.0, abs=1e-6)
    assert tail.exact_rows == 16 and tail.rows == 144
    assert extrapolated_mask(meas.theta_r, tail.start).sum() == 2160
    # read() recorded it
    assert meas.meta["extrapolated_beyond"] == tail.start
    assert meas.meta["extrapolated"] == tail.describe()
    assert "(16 of 144 rows exactly)" in meas.meta["extrapolated"]


def test_minidiff_exact_rows_are_the_camera_axes(paints):
    """Row by row: the exact ramps are the azimuths 0, 90, 180, 270 deg of every incidence."""
    meas = paints["C8_Silver"]
    exact = []
    keys = np.stack([np.round(np.degrees(meas.theta_i)), np.round(np.degrees(meas.phi)) % 360])
    for ti, ph in np.unique(keys.T, axis=0):
        row = (keys[0] == ti) & (keys[1] == ph)
        if meas.theta_r[row].max() < math.radians(89.9):
            continue
        tail = find_extrapolated_tail(meas.theta_i[row], meas.theta_r[row], meas.phi[row],
                                      meas.values[row])
        if tail is not None:
            assert math.degrees(tail.start) == pytest.approx(75.0, abs=1e-6)
            exact.append((ti, ph))
    assert sorted(exact) == [(ti, ph) for ti in (0, 20, 40, 60) for ph in (0, 90, 180, 270)]


def test_minidiff_fit_drops_the_tail_by_default(paints):
    meas = paints["C12_OliveDrab"]
    drop = _fit(meas, channel=0)
    c = drop.channels[0]
    assert c.excluded["extrapolated"] == 2160 and c.n_points == 12964 - 2160
    assert "not measured       = theta_r > 75 deg" in drop.report()
    keep = _fit(meas, channel=0, extrapolated="keep")
    assert keep.channels[0].excluded["extrapolated"] == 0
    assert keep.channels[0].n_points == 12964


def test_minidiff_log_loss_needs_negative_drop_only_for_measured_non_positive(paints):
    """The ramp ends at 0 at 90 deg and the files' small negative values are mostly there: with
    the tail left out, the log loss needs ``negative='drop'`` only when the measured samples
    (theta_r <= 75 deg) hold a non-positive value; the count in the error is theirs."""
    branches = set()
    for meas in paints.values():
        mask = extrapolated_mask(meas.theta_r, meas.meta["extrapolated_beyond"])
        n_bad = int((meas.values[~mask, 0] <= 0).sum())
        n_all = int((meas.values[:, 0] <= 0).sum())
        assert n_all > n_bad  # the ramp itself holds non-positive values (0 at 90 deg)
        with pytest.raises(ArgumentError, match=f"but {n_all} are <= 0") as info:
            _fit(meas, channel=0, loss="log", extrapolated="keep", negative="keep")
        assert info.value.argument == "negative"
        if n_bad:
            with pytest.raises(ArgumentError, match=f"but {n_bad} are <= 0") as info:
                _fit(meas, channel=0, loss="log", negative="keep")
            assert info.value.argument == "negative"
            res = _fit(meas, channel=0, loss="log", negative="drop")
            assert res.channels[0].excluded["negative"] == n_bad
        else:
            res = _fit(meas, channel=0, loss="log")
            assert res.channels[0].excluded["negative"] == 0
            assert res.channels[0].n_points == 12964 - 2160
        branches.add(bool(n_bad))
    assert branches == {True, False}  # both cases occur among the three files


def test_astm_round_trip_keeps_values_and_tail(paints, tmp_path):
    meas = paints["C2_Black"]
    path = tmp_path / "copy.astm"
    rb.write(meas, path)
    back = rb.read(path)
    np.testing.assert_array_equal(back.values, meas.values)
    assert back.meta["extrapolated_beyond"] == meas.meta["extrapolated_beyond"]
    assert back.meta["extrapolated"] == meas.meta["extrapolated"]


def test_cli_keep_extrapolated(shared_data, tmp_path):
    runner = CliRunner()
    path = shared_data / "minidiff" / "C12_OliveDrab.astm"
    base = ["fit", str(path), "-m", "lambertian", "--loss", "relative", "--channel", "0",
            "--starts", "1",
            "--no-plots", "-q"]
    for flag, n_out in (([], 2160), (["--keep-extrapolated"], 0)):
        out = tmp_path / ("keep" if flag else "drop")
        res = runner.invoke(app, [*base, *flag, "--out", str(out)])
        assert res.exit_code == 0, res.output
        d = json.loads((out / "fit.json").read_text())
        assert d["options"]["extrapolated"] == ("keep" if flag else "drop")
        ch = d["channels"][0]
        assert ch["excluded"]["extrapolated"] == n_out
        assert ch["metrics"]["n_points"] == 12964 - n_out
        assert "not measured" in (out / "report.txt").read_text()
