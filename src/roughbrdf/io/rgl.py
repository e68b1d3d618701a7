"""RGL measured-BSDF files (Dupuy & Jakob 2018 tensor files, ``.bsdf``): reader.

The files of the RGL material database (rgl.epfl.ch/materials) and those
:func:`roughbrdf.export.rgl.to_rgl` writes hold a BRDF as samples on a grid warped by the
visible-normal distribution (:mod:`roughbrdf.io.rgl_tensor`). :func:`read` gives a
:class:`~roughbrdf.measurement.Measurement` on the file's own samples: per incidence node
``theta_i`` and sample-space node, the direction that Mitsuba 3's ``measured`` plugin
(``src/bsdfs/measured.cpp``) gives that node - the half vector from the file's ``vndf`` warp,
the outgoing direction its mirror - and the value ``f_r`` that the plugin would return there
divided by ``cos(theta_o)`` (with the ``jacobian`` flag: times ``D(m) / (4 sigma(w_i))`` from
the file's ``ndf`` and ``sigma``). So a file can be fitted, plotted or converted like any
measurement.

It shares the ``.bsdf`` extension with Zemax and LightTools: :func:`roughbrdf.read` tells it
apart by its first bytes (``tensor_file``). Channels: ``R, G, B`` (an RGB file) or one per
wavelength, labelled ``"<nm>nm"`` (a spectral file). Samples whose outgoing direction lies
below the horizon (the warp's corners) or within 0.5 deg of it (``f_r`` is ``f_r cos / cos``
there) are left out. Anisotropic files (more than two incident azimuths) are refused: a
Measurement holds the relative azimuth only.

Examples
--------
>>> import roughbrdf as rb, tempfile, pathlib
>>> path = pathlib.Path(tempfile.mkdtemp()) / "paint.bsdf"
>>> _ = rb.export_to(rb.model("lambertian", rho=0.5), path, to="rgl",
...                  resolution={"theta_i": 4, "samples": 8, "vndf": 16, "ndf": 64})
>>> m = rb.read(path)
>>> m.channels, m.quantity.name
(['R', 'G', 'B'], 'BRDF')
>>> bool(abs(m.values.mean() * 3.141592653589793 - 0.5) < 0.01)
True
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..measurement import Measurement
from ..quantity import Quantity
from ._common import FormatError
from .rgl_tensor import (
    MAGIC,
    bilinear,
    decode,
    is_tensor_file,
    phi_to_v,
    sample_marginal,
    theta_to_u,
    u_to_theta,
    v_to_phi,
)

__all__ = ["EXTENSIONS", "read", "sniff"]

EXTENSIONS = (".bsdf",)
#: samples closer than this to the horizon are left out (dividing f_r cos by cos there
#: magnifies the interpolation's and float32's error without bound)
_HORIZON = math.radians(0.5)
_NEEDED = ("theta_i", "phi_i", "ndf", "sigma", "vndf", "luminance", "description", "jacobian")


def sniff(path: str | os.PathLike) -> bool:
    """Whether ``path`` starts with the tensor-file magic (an RGL file, not Zemax/LightTools)."""
    try:
        with open(path, "rb") as fh:
            return is_tensor_file(fh.read(len(MAGIC)))
    except OSError:
        return False


def _fields(path: Path) -> dict[str, np.ndarray]:
    """The file's fields, checked for what the reader needs; FormatError otherwise."""
    try:
        fields = decode(path.read_bytes())
    except ValueError as exc:
        raise FormatError(str(exc), path) from None
    missing = [k for k in _NEEDED if k not in fields]
    if "rgb" not in fields and not {"spectra", "wavelengths"} <= set(fields):
        missing.append("rgb (or spectra and wavelengths)")
    if missing:
        raise FormatError(f"not an RGL measured BSDF: no field {', '.join(missing)}", path)
    if fields["phi_i"].size > 2:
        raise FormatError(f"an anisotropic RGL file ({fields['phi_i'].size} incident "
                          "azimuths): a Measurement holds the relative azimuth only", path)
    spec = fields.get("rgb", fields.get("spectra"))
    nt = fields["theta_i"].size
    if (fields["vndf"].ndim != 4 or fields["vndf"].shape[1] != nt or spec is None
            or spec.ndim != 5 or spec.shape[1] != nt or fields["ndf"].ndim != 2
            or fields["sigma"].ndim != 2):
        raise FormatError("inconsistent RGL field shapes (vndf, spectra/rgb, ndf, sigma)", path)
    return fields


def _slice(fields: dict[str, np.ndarray], k: int, spec: np.ndarray,
           jacobian: bool) -> tuple[np.ndarray, ...]:
    """Incidence node ``k``: ``(theta_r, phi, values (n, channels))`` of its samples."""
    theta_i = float(fields["theta_i"][k])
    vndf = fields["vndf"][0, k].astype(float)
    ny, nx = spec.shape[-2:]
    sx, sy = np.meshgrid(np.linspace(0, 1, nx), np.linspace(0, 1, ny))
    x, y = sample_marginal(vndf, sx.ravel(), sy.ravel())
    tm, pm = u_to_theta(x), v_to_phi(y)
    m = np.stack([np.sin(tm) * np.cos(pm), np.sin(tm) * np.sin(pm), np.cos(tm)])
    wi = np.array([math.sin(theta_i), 0.0, math.cos(theta_i)])[:, None]
    wo = 2.0 * (wi * m).sum(axis=0) * m - wi
    values = spec[0, k].reshape(spec.shape[2], -1).T.astype(float)
    if jacobian:  # measured.cpp: spec *= ndf(u_m) / (4 sigma(u_wi))
        sigma = bilinear(fields["sigma"].astype(float), theta_to_u(theta_i), phi_to_v(0.0))
        values = values * (bilinear(fields["ndf"].astype(float), x, y) / (4 * sigma))[:, None]
    keep = wo[2] > math.sin(_HORIZON)
    cos_o = wo[2][keep]
    # clip: a unit vector's z may round beyond 1, where arccos is NaN
    return (np.arccos(np.clip(cos_o, -1.0, 1.0)), np.angle(-(wo[0] + 1j * wo[1]))[keep],
            values[keep] / cos_o[:, None])


def read(path: str | os.PathLike, *, quantity: Any = None, angles: Any = None) -> Measurement:
    """Read an RGL tensor file into a Measurement of ``f_r`` on its samples.

    Parameters
    ----------
    path : str or path-like
    quantity, angles : optional
        As for every reader; an RGL file holds BRDF values in radians: anything else is a
        :class:`FormatError`.

    Raises
    ------
    FormatError
        Not a tensor file, a field missing or of the wrong shape, an anisotropic file.
    """
    p = Path(path)
    if quantity is not None and Quantity.parse(quantity, "quantity") != Quantity.BRDF:
        raise FormatError(f"quantity={quantity!r}: an RGL file holds the BRDF", p)
    if angles is not None and str(angles).lower() not in ("rad", "radians"):
        raise FormatError(f"angles={angles!r}: an RGL file's angles are radians", p)
    fields = _fields(p)
    spec = fields.get("rgb", fields.get("spectra"))
    assert spec is not None  # _fields checked it
    if "rgb" in fields:
        channels = ["R", "G", "B"]
    else:
        channels = [f"{w:g}nm" for w in fields["wavelengths"].astype(float).tolist()]
    jacobian = bool(fields["jacobian"].reshape(-1)[0])
    parts = [_slice(fields, k, spec, jacobian) for k in range(fields["theta_i"].size)]
    ti = np.concatenate([np.full(part[0].shape, float(t))
                         for part, t in zip(parts, fields["theta_i"], strict=True)])
    description = bytes(fields["description"].astype(np.uint8)).decode("utf-8", "replace")
    meta = {"file": str(p), "format": "rgl", "description": description,
            "jacobian": jacobian}
    # the float32 theta_i nodes are in [0, pi/2] up to rounding, which the Measurement refuses
    return Measurement(theta_i=np.clip(ti, 0.0, math.pi / 2),
                       theta_r=np.concatenate([part[0] for part in parts]),
                       phi=np.concatenate([part[1] for part in parts]),
                       values=np.concatenate([part[2] for part in parts]),
                       channels=channels, quantity=Quantity.BRDF, meta=meta)
