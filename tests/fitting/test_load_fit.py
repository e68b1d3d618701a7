"""``rb.load_fit``: a saved fit folder read back as a FitResult (``roughbrdf.fitting.load``).

Every expected value is the fit's own, before saving: the loaded result must give the same
parameters, standard errors, figures of merit, report, ``fit.json`` and predictions (an
identity: the same model rebuilt from its recorded spec, the same samples selected again with
the recorded options). The input is a copy of ``tests/data/zemax/AnoBlackNiTEonINVAR.bsdf`` in
a temporary folder, so that it can be changed and deleted.
"""

from __future__ import annotations

import json
import math
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.errors import ArgumentError
from roughbrdf.fitting.load import InputChangedWarning
from roughbrdf.journal import MANIFEST

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

DATA = Path(__file__).parents[1] / "data" / "zemax" / "AnoBlackNiTEonINVAR.bsdf"


@pytest.fixture(scope="module")
def saved(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[rb.FitResult, Path]]:
    """``{name: (fit, folder)}`` of a Lambertian and a TR75 fit of a copy of the Zemax file,
    saved without plots."""
    root = tmp_path_factory.mktemp("fits")
    src = root / "input.bsdf"
    shutil.copyfile(DATA, src)
    meas = rb.read(src)
    out = {}
    for name, kw in (("lambertian", {}), ("tr75", {"loss": "relative"})):
        res = rb.fit(name, meas, starts=2, progress=False, **kw)
        res.save(root / name, plots=False)
        out[name] = (res, root / name)
    return out


def _hand_edit(folder: Path, doc: dict) -> None:
    """Write ``doc`` as ``folder``'s fit.json as a folder written before manifests were: a
    hand-edited fit.json beside the manifest is refused (its hash differs), which
    tests/core/test_crash_readers.py covers; these tests are about what load_fit reads."""
    (folder / "fit.json").write_text(json.dumps(doc))
    (folder / MANIFEST).unlink()


def _same(a: dict, b: dict) -> None:
    """Equal dicts of numbers, NaN equal to NaN and None to None."""
    assert a.keys() == b.keys()
    for k in a:
        if a[k] is None or b[k] is None:
            assert a[k] is b[k], k
        else:
            assert a[k] == pytest.approx(b[k], rel=1e-12, nan_ok=True), k


def _report_lines(res: rb.FitResult) -> list[str]:
    # "# starts" counts the local fits run, which fit.json does not list (module notes)
    return [ln for ln in res.report().splitlines() if "# starts" not in ln]


@pytest.mark.parametrize("name", ["lambertian", "tr75"])
def test_round_trip_gives_the_fit_back(saved, name):
    res, folder = saved[name]
    back = rb.load_fit(folder)
    assert [c.channel for c in back] == [c.channel for c in res]
    for c0, c1 in zip(res, back, strict=True):
        _same(c0.params, c1.params)
        _same(c0.stderr, c1.stderr)
        _same(c0.metrics, c1.metrics)
        assert (c1.success, c1.message, c1.free, c1.at_bound) == \
            (c0.success, c0.message, c0.free, c0.at_bound)
        assert c1.scale == c0.scale and c1.excluded == c0.excluded
        # the samples the fit used, selected again, and the model and residuals there
        np.testing.assert_array_equal(c1.index, c0.index)
        np.testing.assert_allclose(c1.data, c0.data, rtol=0)
        np.testing.assert_allclose(c1.fitted, c0.fitted, rtol=1e-12)
        np.testing.assert_allclose(c1.residual, c0.residual, rtol=1e-10, atol=1e-14)
        # the covariance rebuilt from stderr and correlations (NaN where the fit had NaN)
        np.testing.assert_allclose(c1.covar, c0.covar, rtol=1e-9, equal_nan=True)
    assert _report_lines(back) == _report_lines(res)
    assert json.loads(back.to_json()) == json.loads(res.to_json())
    assert (back.loss, back.compared, back.options) == (res.loss, res.compared, res.options)


def test_predict_and_plot_work_on_the_loaded_fit(saved):
    res, folder = saved["tr75"]
    back = rb.load_fit(folder / "fit.json")  # the file itself, not only its folder
    t = np.radians([[10.0, 30.0], [50.0, 70.0]])
    np.testing.assert_allclose(back.predict(t, 0.4, [[0.0], [2.0]]),
                               res.predict(t, 0.4, [[0.0], [2.0]]), rtol=1e-12)
    fig, (ax_cmp, ax_res) = back.plot()
    assert ax_cmp.lines and fig.axes
    assert back.measurement.n_samples == res.measurement.n_samples


def test_changed_input_warns(saved, tmp_path):
    res, folder = saved["lambertian"]
    src = tmp_path / "input.bsdf"
    shutil.copyfile(DATA, src)
    fit = tmp_path / "fit"
    res.save(fit, plots=False)
    doc = json.loads((fit / "fit.json").read_text())
    doc["file"] = doc["file_abspath"] = str(src)
    _hand_edit(fit, doc)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the same bytes: no warning
        rb.load_fit(fit)
    with src.open("a") as fh:
        fh.write("\n")  # one more byte: another SHA-256, the same samples
    with pytest.warns(InputChangedWarning, match="SHA-256 differs") as record:
        back = rb.load_fit(fit)
    assert str(src) in str(record[0].message)
    _same(back.params, res.params)


def test_gone_input_is_an_error_naming_it(saved, tmp_path):
    res, _ = saved["lambertian"]
    src = tmp_path / "gone.bsdf"
    shutil.copyfile(DATA, src)
    res2 = rb.fit("lambertian", rb.read(src), starts=1, progress=False)
    res2.save(tmp_path / "fit", plots=False)
    src.unlink()
    with pytest.raises(FileNotFoundError, match="is gone: it recorded") as err:
        rb.load_fit(tmp_path / "fit")
    assert str(src) in str(err.value) and "measurement=" in str(err.value)
    # the documented way out: the file where it is now, or the measurement itself
    back = rb.load_fit(tmp_path / "fit", measurement=DATA)
    _same(back.params, res2.params)
    back = rb.load_fit(tmp_path / "fit", measurement=rb.read(DATA))
    assert back.report().splitlines()[-1] == res2.report().splitlines()[-1]
    with pytest.raises(FileNotFoundError, match="nowhere.bsdf"):
        rb.load_fit(tmp_path / "fit", measurement=tmp_path / "nowhere.bsdf")


def test_relative_file_name_is_found_beside_the_fit(saved, tmp_path):
    res, folder = saved["lambertian"]
    shutil.copytree(folder, tmp_path / "fit")
    shutil.copyfile(DATA, tmp_path / "fit" / "moved.bsdf")
    doc = json.loads((tmp_path / "fit" / "fit.json").read_text())
    doc["file"], doc["file_abspath"] = "moved.bsdf", None  # a relative name only
    _hand_edit(tmp_path / "fit", doc)
    back = rb.load_fit(tmp_path / "fit")
    _same(back.params, res.params)


def test_fit_of_a_measurement_made_in_python(tmp_path):
    g = np.radians(np.mgrid[0:61:30, 0:81:20, 0:181:90].reshape(3, -1))
    meas = rb.Measurement(*g, rb.model("lambertian", rho=0.3).brdf(*g))
    res = rb.fit("lambertian", meas, starts=1, progress=False)
    res.save(tmp_path, plots=False)
    with pytest.raises(FileNotFoundError, match="records no input file"):
        rb.load_fit(tmp_path)
    back = rb.load_fit(tmp_path, measurement=meas)
    assert back.params["rho"] == pytest.approx(0.3, rel=1e-9)  # the synthetic truth
    assert _report_lines(back) == _report_lines(res)


def test_relative_data_keep_their_free_scale(tmp_path):
    # relative data: K free, solved in closed form (TR75 Eq. 34); the loaded K and the
    # residuals are the fit's
    g = np.radians(np.mgrid[10:61:25, 0:81:10, 0:181:45].reshape(3, -1))
    truth = rb.model("tr75", e=0.3, rho_L=0.1)
    meas = rb.Measurement(*g, 7.0 * truth.brdf(*g), quantity="relative")
    res = rb.fit(truth.with_params(e=0.5), meas, starts=1, progress=False)
    res.save(tmp_path, plots=False)
    back = rb.load_fit(tmp_path, measurement=meas)
    assert back[0].free_scale and back[0].scale == res[0].scale
    np.testing.assert_allclose(back[0].residual, res[0].residual, rtol=1e-10, atol=1e-14)
    assert _report_lines(back) == _report_lines(res)


def test_fewer_samples_than_recorded_warn(saved, tmp_path):
    res, folder = saved["lambertian"]
    meas = rb.read(DATA)
    fewer = meas.subset(np.arange(meas.n_samples) % 2 == 0)
    with pytest.warns(InputChangedWarning, match=f"used {res[0].n_points} samples"):
        rb.load_fit(folder, measurement=fewer)


def test_per_incidence_fit_is_refused_with_what_to_do(tmp_path):
    from roughbrdf.fitting.kinds.per_incidence import fit_per_incidence

    meas = rb.read(DATA)
    fit_per_incidence("lambertian", meas, starts=1, progress=False).save(tmp_path)
    assert json.loads((tmp_path / "fit.json").read_text())["per_incidence"] is True
    with pytest.raises(ValueError, match="per-incidence fit .* json.load"):
        rb.load_fit(tmp_path)


@pytest.mark.parametrize("content, match", [
    ("[1, 2]", "not a fit's JSON"),
    ("{not json", "not valid JSON"),
    ('{"model": "lambertian", "file": null, "channels": [{"channel": "a", "params": '
     '{"rho": "x"}}]}', "not a finite number"),
])
def test_not_a_fit_json(tmp_path, content, match):
    (tmp_path / "fit.json").write_text(content)
    with pytest.raises(ValueError, match=match):
        rb.load_fit(tmp_path)


def test_no_fit_json_and_wrong_channel(saved, tmp_path):
    with pytest.raises(FileNotFoundError, match="no fit.json"):
        rb.load_fit(tmp_path)
    _, folder = saved["lambertian"]
    other = rb.Measurement([0.2], [0.3], [0.0], [[0.1]], channels=["550nm"])
    with pytest.raises(ArgumentError, match="no channel 'value'"):
        rb.load_fit(folder, measurement=other)


def test_mueller_fit_is_refused(tmp_path):
    doc = {"model": "microfacet", "file": None, "options": {"mueller": "normalized"},
           "channels": [{"channel": "mueller", "params": {}}]}
    (tmp_path / "fit.json").write_text(json.dumps(doc))
    with pytest.raises(ValueError, match="Mueller-matrix fit"):
        rb.load_fit(tmp_path)


def test_nan_stderr_stays_nan(saved, tmp_path):
    # fit.json writes NaN as null: a free parameter's null is NaN (not estimable), a fixed
    # one's None
    res, folder = saved["tr75"]
    shutil.copytree(folder, tmp_path / "fit")
    doc = json.loads((tmp_path / "fit" / "fit.json").read_text())
    free = doc["channels"][0]["free"][0]
    doc["channels"][0]["stderr"][free] = None
    _hand_edit(tmp_path / "fit", doc)
    back = rb.load_fit(tmp_path / "fit", measurement=res.measurement)
    assert math.isnan(back[0].stderr[free])
    fixed = [k for k in back[0].params if k not in back[0].free]
    assert all(back[0].stderr[k] is None for k in fixed)


@pytest.mark.parametrize("options", [{"aperture": 0.02}, {"joint": True, "shared": ["e"]}])
def test_two_channels_with_an_aperture_or_joint(tmp_path, options):
    # two channels of a CSV file (synthetic TR75, one e, two rho_L): the fit's aperture and
    # joint summary come back with it, and its predictions per channel
    g = np.radians(np.mgrid[10:61:25, 0:81:10, 0:181:45].reshape(3, -1))
    truth = rb.model("tr75", e=0.3, rho_L=0.1)
    v = np.stack([truth.brdf(*g), truth.with_params(rho_L=0.05).brdf(*g)], axis=1)
    rb.write(rb.Measurement(*g, v, channels=["465nm", "550nm"]), tmp_path / "syn.csv")
    res = rb.fit(truth, rb.read(tmp_path / "syn.csv"), starts=1, progress=False, **options)
    res.save(tmp_path / "fit", plots=False)
    back = rb.load_fit(tmp_path / "fit")
    assert json.loads(back.to_json()) == json.loads(res.to_json())
    assert back.aperture == res.aperture and back.options == res.options
    for ch in ("465nm", "550nm"):
        np.testing.assert_allclose(back.predict(0.3, [0.2, 0.5], 0.0, channel=ch),
                                   res.predict(0.3, [0.2, 0.5], 0.0, channel=ch), rtol=1e-12)
        np.testing.assert_allclose(back[ch].residual, res[ch].residual, rtol=1e-10,
                                   atol=1e-14)
