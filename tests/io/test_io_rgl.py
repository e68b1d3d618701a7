"""RGL tensor files read by ``rb.read`` (``roughbrdf.io.rgl``): round trip, dispatch, errors.

A file written by ``roughbrdf.export.rgl.to_rgl`` and read back gives the model's BRDF on the
file's own samples (float32 storage and the warp recomputed from float32 tables are the only
differences); ``.bsdf`` files are told apart by content (the ``tensor_file`` magic) from
Zemax and LightTools; what read gives can be fitted.
"""

from __future__ import annotations

import struct

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.export.rgl import to_rgl
from roughbrdf.io import FormatError, format_for
from roughbrdf.io.rgl_tensor import decode, encode
from roughbrdf.quantity import Quantity

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="RGL exports (the reader's inputs): minutes in plain Python")

SMALL = {"theta_i": 10, "samples": 24, "vndf": 32, "ndf": 128}
COATED = rb.model("coated", alpha=0.2, n=1.5, rho=0.4)


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    path = tmp_path_factory.mktemp("rgl") / "coated.bsdf"
    to_rgl(COATED, path, resolution=SMALL)
    return path


def test_round_trip_gives_the_model_on_the_files_samples(written):
    m = rb.read(written)
    assert m.channels == ["R", "G", "B"] and m.quantity == Quantity.BRDF
    assert m.meta["format"] == "rgl" and "power iteration" in m.meta["description"]
    assert m.n_samples > 0.7 * SMALL["theta_i"] * SMALL["samples"] ** 2
    ref = COATED.brdf(m.theta_i, m.theta_r, m.phi)
    err = np.abs(m.values - ref[:, None]) / ref[:, None]
    assert np.median(err) < 1e-4 and np.percentile(err, 99) < 1e-2, np.percentile(err, 99)
    assert np.unique(m.theta_i).size == SMALL["theta_i"]
    assert m.theta_r.max() <= np.pi / 2 - np.radians(0.5) + 1e-12


def test_read_file_can_be_fitted(written):
    meas = rb.read(written).select_channel("G")
    fit = rb.fit("coated", meas, starts=1, progress=False)
    for name, value in COATED.params.items():
        assert fit.params[name] == pytest.approx(value, rel=0.02), (name, fit.params)


def test_spectral_channels_are_wavelengths(tmp_path):
    fit = {"465nm": rb.model("lambertian", rho=0.2), "630nm": rb.model("lambertian", rho=0.6)}
    path = to_rgl(fit, tmp_path / "s.bsdf", resolution=SMALL).path
    m = rb.read(path)
    assert m.channels == ["465nm", "630nm"]
    np.testing.assert_allclose(m.values.mean(axis=0) * np.pi, [0.2, 0.6], rtol=1e-3)


def test_bsdf_told_apart_by_content(written, tmp_path):
    assert format_for(written) == "zemax"  # by extension: a new .bsdf is Zemax
    assert rb.read(written).meta["format"] == "rgl"  # an existing one: by its contents
    other = tmp_path / "noext"
    other.write_bytes(written.read_bytes())
    assert format_for(other) == "rgl"
    assert rb.read(written, format="rgl").n_samples == rb.read(other).n_samples


def test_errors_name_the_file_and_the_problem(written, tmp_path):
    blob = written.read_bytes()
    cut = tmp_path / "cut.bsdf"
    cut.write_bytes(blob[: len(blob) // 2])
    with pytest.raises(FormatError, match="truncated"):
        rb.read(cut)
    fields = decode(blob)
    missing = tmp_path / "missing.bsdf"
    missing.write_bytes(encode({k: v for k, v in fields.items() if k != "vndf"}))
    with pytest.raises(FormatError, match="no field vndf"):
        rb.read(missing)
    aniso = tmp_path / "aniso.bsdf"
    aniso.write_bytes(encode({**fields, "phi_i": np.zeros(4, np.float32)}))
    with pytest.raises(FormatError, match="anisotropic"):
        rb.read(aniso)
    version = tmp_path / "version.bsdf"
    version.write_bytes(blob[:12] + bytes([1, 3]) + blob[14:])
    with pytest.raises(FormatError, match="version"):
        rb.read(version)
    with pytest.raises(FormatError, match="quantity"):
        rb.read(written, quantity="brdf_cos")


def test_tensor_file_container_layout():
    blob = encode({"a": np.arange(3, dtype=np.float32), "bb": np.ones((2, 2), np.uint8)})
    assert blob[:12] == b"tensor_file\0" and blob[12:14] == bytes([1, 0])
    assert struct.unpack_from("<I", blob, 14) == (2,)
    # field "a": name length 1, ndim 1, type 10 (float32), an 8-byte aligned offset, shape 3
    length, = struct.unpack_from("<H", blob, 18)
    ndim, code, offset = struct.unpack_from("<HBQ", blob, 21)
    assert (length, ndim, code, offset % 8) == (1, 1, 10, 0)
    assert struct.unpack_from("<Q", blob, 32) == (3,)
    assert np.frombuffer(blob, np.float32, 3, offset).tolist() == [0.0, 1.0, 2.0]
    out = decode(blob)
    assert out["bb"].dtype == np.uint8 and out["bb"].shape == (2, 2)
    with pytest.raises(TypeError, match="dtype"):
        encode({"c": np.array(["text"])})
