"""The Zemax ABg catalog table (``export/abg_catalog.py``): per-incidence ABg rows and TIS.

The expected values are the model's own parameters and its TIS by ``rb.albedo`` (an ABg model
with ``g = 0`` is the constant ``A/(B + 1)``, whose TIS is ``pi A/(B + 1)`` at every incidence).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import roughbrdf as rb
import roughbrdf.models.straylight  # noqa: F401 - registers abg
from roughbrdf.errors import ArgumentError
from roughbrdf.export.abg_catalog import MAX_ROWS, write_abg_catalog
from roughbrdf.fitting.kinds.per_incidence import fit_per_incidence
from roughbrdf.output import OverwriteRefused

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="each export checks the albedo at 19 incidences: ~1 min in plain Python")


def _rows(text):
    """The table's data rows as (angle, A, B, g, TIS)."""
    return [tuple(float(x) for x in ln.split()[1:]) for ln in text.splitlines()
            if ln.startswith("yes ")]


def test_a_model_is_one_row_with_its_values_and_tis(tmp_path):
    m = rb.model("abg", A=0.05, B=0.25, g=0.0)
    path = write_abg_catalog(m, tmp_path / "flat")
    text = path.read_text()
    assert path.name == "flat.txt" and "Name      flat" in text and "Wave (um) 0" in text
    ((angle, a, b, g, tis),) = _rows(text)
    assert (angle, a, b, g) == (0.0, 0.05, 0.25, 0.0)
    assert tis == pytest.approx(math.pi * 0.05 / 1.25, abs=1e-6)  # pi A / (B + 1)
    assert "not publicly documented" in text  # says what it is


def test_per_incidence_rows_are_the_kept_fits(tmp_path):
    # 12 incidences of a synthetic ABg whose A falls with incidence: at most 10 rows kept
    angles = np.radians(np.linspace(0.0, 77.0, 12))
    ti, tr, ph = (a.ravel() for a in np.meshgrid(angles, np.radians(np.arange(0.0, 85.0, 2.5)),
                                                 np.radians([0.0, 45.0, 90.0, 180.0]),
                                                 indexing="ij"))
    a_of = 0.02 * np.cos(ti)
    vals = np.array([rb.model("abg", A=a, B=0.002, g=1.5).brdf(t, r, p)
                     for a, t, r, p in zip(a_of, ti, tr, ph, strict=True)])
    meas = rb.Measurement(ti, tr, ph, vals, channels=["633nm"])
    fit = fit_per_incidence("abg", meas, starts=2, progress=False)
    path = write_abg_catalog(fit, tmp_path / "cat.txt", name="synthetic-abg")
    rows = _rows(path.read_text())
    assert len(rows) == len(fit.chosen) == MAX_ROWS
    assert "Wave (um) 0.633" in path.read_text()  # from the channel's name
    for (angle, a, b, g, tis), k in zip(rows, fit.chosen, strict=True):
        r = fit.rows[k]
        assert angle == pytest.approx(math.degrees(r.theta_i), abs=1e-3)
        p = r.params("633nm")
        assert (a, b, g) == pytest.approx((p["A"], p["B"], p["g"]), rel=1e-6)
        assert tis == pytest.approx(r.tis["633nm"], abs=1e-6)
        assert a == pytest.approx(0.02 * math.cos(r.theta_i), rel=1e-3)  # the truth


def test_refusals_are_named(tmp_path):
    m = rb.model("abg", A=0.05, B=0.25, g=0.0)
    write_abg_catalog(m, tmp_path / "x.txt")
    with pytest.raises(OverwriteRefused):
        write_abg_catalog(m, tmp_path / "x.txt")
    write_abg_catalog(m, tmp_path / "x.txt", overwrite=True)
    with pytest.raises(ArgumentError, match="name"):
        write_abg_catalog(m, tmp_path / "y.txt", name="has space")
    with pytest.raises(ArgumentError, match="ABg models only"):
        write_abg_catalog(rb.model("lambertian"), tmp_path / "z.txt")


def test_a_model_that_scatters_more_than_it_receives_is_refused_unless_allowed(tmp_path):
    hot = rb.model("abg", A=0.5, B=0.25, g=0.0)  # TIS = pi 0.5 / 1.25 = 1.26
    with pytest.raises(ArgumentError, match="allow_energy_gain"):
        write_abg_catalog(hot, tmp_path / "hot.txt")
    assert not (tmp_path / "hot.txt").exists()
    text = write_abg_catalog(hot, tmp_path / "hot.txt", allow_energy_gain=True).read_text()
    assert "allow_energy_gain: exported although" in text
