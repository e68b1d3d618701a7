"""Nonsense that must not succeed: a fit of data
with no positive value is refused, naming the channel, in Python and at the CLI."""

from __future__ import annotations

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.cli import main
from roughbrdf.measurement import Measurement

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")


def _measurement(values: np.ndarray, channels: list[str]) -> Measurement:
    ti, tr = np.meshgrid(np.radians([10.0, 30.0, 50.0]), np.radians(np.arange(0.0, 80.0, 10.0)))
    ti, tr = ti.ravel(), tr.ravel()
    return Measurement(ti, tr, np.zeros_like(ti), values.reshape(ti.size, -1),
                       channels=channels, quantity="brdf")


@pytest.mark.parametrize("fill", [0.0, -0.1])
def test_all_zero_data_refused_naming_the_channel(fill):
    meas = _measurement(np.full((24, 1), fill), ["525nm"])
    with pytest.raises(ValueError, match=r"525nm.*no positive value"):
        rb.fit("tr75", meas, starts=1, negative="keep")
    # the same samples with positive values fit (the refusal is about the values only)
    res = rb.fit("lambertian", _measurement(np.full((24, 1), 0.1), ["525nm"]), starts=1)
    assert res.success and res.params["rho"] == pytest.approx(0.1 * np.pi, rel=1e-6)


def test_one_zero_channel_among_good_ones_is_named():
    values = np.column_stack([np.full(24, 0.1), np.zeros(24)])
    meas = _measurement(values, ["465nm", "630nm"])
    with pytest.raises(ValueError, match="630nm") as exc:
        rb.fit("tr75", meas, starts=1)
    assert "465nm" not in str(exc.value)


def test_all_zero_file_at_the_cli_is_one_line(tmp_path, capsys):
    path = tmp_path / "zeros.csv"
    rb.io.write(_measurement(np.zeros((24, 1)), ["525nm"]), path)
    code = main(["fit", str(path), "-m", "tr75", "--starts", "1", "--no-plots", "-q",
                 "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1 and err.startswith("error: ")
    assert "525nm" in err and "no positive value" in err
    assert not (tmp_path / "o").exists()
