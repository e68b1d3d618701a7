"""Figures that show a fit honestly: a user can trust what they see.

* the residual map has one panel per measured incidence, one colour scale and one colour bar;
* the comparison's value axis holds the model's peak as well as the data;
* ``roughbrdf plot --fit DIR`` draws the samples the fit used (a Mini-Diff file's extrapolated
  ramp beyond theta_r = 75 deg left out, as the fit left it out), with finite r.m.s. values, no
  numerical warning, and a note of what was left out.
"""

from __future__ import annotations

import json
import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from matplotlib.collections import PathCollection

import roughbrdf as rb
from roughbrdf import plot
from roughbrdf.cli import main
from roughbrdf.measurement import Measurement

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

ROUGH = dict(e=0.4, n=1.5, k=0.0, rho_L=0.1)
SHARP = dict(e=0.05, n=1.5, k=0.0, rho_L=0.1)


def _hemisphere_measurement(model, incidences_deg=(0.0, 30.0, 60.0)):
    """Samples of ``model`` on a grid of the hemisphere, at each incidence."""
    tr_, ph = np.meshgrid(np.radians(np.arange(2.0, 80.0, 6.0)),
                          np.radians(np.arange(0.0, 360.0, 30.0)))
    ti = np.repeat(np.radians(incidences_deg), tr_.size)
    tr_ = np.tile(tr_.ravel(), len(incidences_deg))
    ph = np.tile(ph.ravel(), len(incidences_deg))
    return Measurement(ti, tr_, ph, model.brdf(ti, tr_, ph), quantity="brdf",
                       meta={"sample": "synthetic"})


def _scatter_axes(fig):
    """The axes that hold the samples (a scatter collection)."""
    return [ax for ax in fig.axes if any(isinstance(c, PathCollection) for c in ax.collections)]


def test_residual_map_has_one_panel_per_incidence():
    data_model = rb.model("trowbridge-reitz-1975", **ROUGH)
    drawn = rb.model("trowbridge-reitz-1975", **{**ROUGH, "e": 0.5})
    meas = _hemisphere_measurement(data_model)
    fig, ax = plot.plot_residual_map(drawn, meas)
    panels = _scatter_axes(fig)
    assert len(panels) == 3 and panels[0] is ax
    for p, deg in zip(panels, (0, 30, 60), strict=True):
        assert rf"$\theta_i$ = {deg}°" in p.get_title()
        n = sum(len(c.get_offsets()) for c in p.collections if isinstance(c, PathCollection))
        assert n == meas.n_samples // 3  # each panel holds the samples of its incidence
    assert "[deg]" in panels[0].get_xlabel() and "[deg]" in panels[0].get_ylabel()
    # one colour scale for every panel, one colour bar
    norms = {(c.norm.vmin, c.norm.vmax) for p in panels for c in p.collections
             if isinstance(c, PathCollection)}
    assert len(norms) == 1
    assert len(fig.axes) == len(panels) + 1
    assert "model" in fig.axes[-1].get_ylabel()


def test_comparison_y_range_holds_the_model_peak():
    # a model much sharper than the data: its specular peaks are far above the data's
    ts_ = np.radians(np.linspace(-80, 80, 81))
    tr_, ph = rb.geometry.from_signed_angle(ts_)
    ti = np.repeat(np.radians([0.0, 30.0, 60.0]), ts_.size)
    meas = Measurement(ti, np.tile(tr_, 3), np.tile(ph, 3),
                       rb.model("trowbridge-reitz-1975", **ROUGH).brdf(
                           ti, np.tile(tr_, 3), np.tile(ph, 3)) * 0.1, quantity="brdf")
    sharp = rb.model("trowbridge-reitz-1975", **SHARP)
    fig, ax = plot.plot_comparison(sharp, meas)
    lo, hi = ax.get_ylim()
    models = [ln for ln in ax.get_lines() if ln.get_label().startswith("model")]
    assert len(models) == 3
    for ln in models:
        x, y = np.asarray(ln.get_xdata()), np.asarray(ln.get_ydata())
        peak = np.max(y[(x >= -80) & (x <= 80)])
        assert peak > 3 * np.max(meas.values)  # a model peak the old axis (data only) cut off
        assert lo < peak < hi, ln.get_label()
    assert hi > np.max(meas.values)


@pytest.fixture(scope="module")
def minidiff_fit(shared_data: Path, tmp_path_factory) -> Path:
    """A fit folder of the coated model to one channel of C2_Black (a Mini-Diff file whose
    values beyond theta_r = 75 deg are the reader's extrapolation)."""
    out = tmp_path_factory.mktemp("fit") / "c2"
    code = main(["fit", str(shared_data / "minidiff" / "C2_Black.astm"), "-m", "coated",
                 "--channel", "465nm", "--out", str(out)])
    # the coated fit to this paint may be flagged implausible (exit status 1): its figure is
    # what is tested here, and it is drawn for any fit that wrote fit.json
    assert code in (0, 1) and (out / "fit.json").is_file()
    return out


def test_plot_fit_draws_the_fits_own_samples(minidiff_fit, tmp_path, monkeypatch, capsys):
    drawn = {}
    for name in ("plot_comparison", "plot_residual_map"):
        real = getattr(plot, name)

        def spy(*args, _real=real, _name=name, **kw):
            drawn[_name] = _real(*args, **kw)
            return drawn[_name]

        monkeypatch.setattr(plot, name, spy)
    capsys.readouterr()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code = main(["plot", "--fit", str(minidiff_fit), "--out", str(tmp_path / "c.png")])
    err = capsys.readouterr().err
    assert code == 0, err
    assert not caught, [str(w.message) for w in caught]
    assert "warning" not in err.lower()
    fit = json.loads((minidiff_fit / "fit.json").read_text())
    n_points = fit["channels"][0]["metrics"]["n_points"]
    assert fit["channels"][0]["excluded"]["extrapolated"] > 0  # the Mini-Diff ramp left out

    fig, _ax = drawn["plot_residual_map"]
    panels = _scatter_axes(fig)
    residual_panels = [p for p in panels if p is not drawn["plot_comparison"][1]]
    assert len(residual_panels) == 4  # C2_Black: 0, 20, 40, 60 deg
    n = sum(len(c.get_offsets()) for p in residual_panels for c in p.collections
            if isinstance(c, PathCollection))
    assert n == n_points
    for p in residual_panels:
        m = re.search(r"r\.m\.s\. (\S+)", p.get_title())
        assert m and math.isfinite(float(m.group(1))), p.get_title()
    # no sample beyond the instrument's range (75 deg) is drawn
    r = np.concatenate([np.hypot(*c.get_offsets().T) for p in residual_panels
                        for c in p.collections if isinstance(c, PathCollection)])
    assert r.max() <= 75.0 + 1e-9
    # the note says how many were left out and why
    texts = [t.get_text() for t in fig.texts]
    assert any(f"{n_points} of" in t and "not measured" in t for t in texts), texts

    _fig, cax = drawn["plot_comparison"]
    lo, hi = cax.get_ylim()
    data_lines = [ln for ln in cax.get_lines() if ln.get_label().startswith("data")]
    models = [ln for ln in cax.get_lines() if ln.get_label().startswith("model")]
    assert len(models) == 4
    for d, ln in zip(data_lines, models, strict=True):
        xd = np.asarray(d.get_xdata())
        assert np.max(np.abs(xd)) <= 75.0 + 1e-9
        x, y = np.asarray(ln.get_xdata()), np.asarray(ln.get_ydata())
        peak = np.max(y[(x >= xd.min()) & (x <= xd.max())])
        assert lo < peak < hi, ln.get_label()
