"""RGL measured-BSDF files (Dupuy & Jakob 2018) from any model: Mitsuba 3's ``measured``.

Dupuy & Jakob 2018, "An adaptive parameterization for efficient material acquisition and
rendering" (ACM TOG 37(6), SIGGRAPH Asia) store a BRDF as samples on a grid warped by the
material's visible-normal distribution, in a *tensor file* (``.bsdf``). Mitsuba 3's
``measured`` plugin (``src/bsdfs/measured.cpp``) and pbrt-v4's ``MeasuredBxDF``
(``src/pbrt/bxdfs.cpp``) render them. :func:`to_rgl` writes one from a model or a fit: the
NDF (exact for the ``microfacet`` model, else by the power iteration of Dupuy et al. 2015,
:mod:`~roughbrdf.export.rgl.ndf`), the projected area, the visible-normal and luminance
warps and the samples (:mod:`~roughbrdf.export.rgl.build`); ``docs/export.md`` says what the
file holds and its limits. :func:`roughbrdf.read` reads such a file back
(:mod:`roughbrdf.io.rgl`).

Channels: a spectral file (``spectra`` and ``wavelengths``, Mitsuba's spectral variants) holds
a fit's channels at their wavelengths (labels such as ``"525nm"``); an RGB file (``rgb``,
Mitsuba's RGB variants) holds R, G, B, each the channels' values linearly interpolated in
wavelength at the sRGB primaries' dominant wavelengths (:data:`RGB_NM`, held constant beyond
the first and last channel). A model or a single channel is grey: R = G = B (spectral: flat
from 360 to 830 nm). Channels without wavelengths are written to an RGB file only when there
are three of them (taken as R, G, B in their order) or one.
"""

from __future__ import annotations

import os
import re
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import ArgumentError
from .build import Resolution, build_fields

__all__ = ["RGB_NM", "Resolution", "RglExport", "to_rgl"]

#: the wavelengths (nm) at which R, G and B take the channels' values: the dominant
#: wavelengths of the sRGB / Rec. 709 primaries (red 612, green 549, blue 465 nm)
RGB_NM = (612.0, 549.0, 465.0)
#: a grey spectral file: one value from 360 to 830 nm (Mitsuba holds it beyond)
_FLAT_NM = (360.0, 830.0)


@dataclass
class RglExport:
    """What :func:`to_rgl` wrote.

    Attributes
    ----------
    path : pathlib.Path
    color : {"rgb", "spectral"}
    channels : list of str
        The file's channels (``R, G, B`` or the wavelengths).
    ndf_source : str
        Where the NDF came from (exact, or power iteration).
    resolution : Resolution
    size : int
        Bytes written.
    seconds : float
        Time to compute and write.
    """

    path: Path
    color: str
    channels: list[str]
    ndf_source: str
    resolution: Resolution
    size: int
    seconds: float

    def text(self) -> str:
        """One paragraph for people: grid, channels, NDF, size and time."""
        r = self.resolution
        return (f"RGL measured BSDF (Dupuy & Jakob 2018; Mitsuba 3 'measured'): "
                f"{r.theta_i} incidences x {r.samples}x{r.samples} samples x "
                f"{len(self.channels)} {self.color} channel(s) ({', '.join(self.channels)}); "
                f"NDF: {self.ndf_source}; {self.size / 1e6:.2f} MB in {self.seconds:.1f} s")


def _wavelength(label: str) -> float | None:
    found = re.fullmatch(r"\s*(\d+(?:\.\d+)?)\s*nm\s*", str(label), re.IGNORECASE)
    return float(found.group(1)) if found else None


def _channels(source: Any, channel: Any) -> list[tuple[str, Any]]:
    """``[(label, model)]`` of a model (label ``""``), a fit or ``{channel: model}``
    (``channel``: one of them, by label or index)."""
    from ...models.base import Model

    if isinstance(source, Model):
        if channel is not None:
            raise ArgumentError("channel", "applies to a fit; a model is one BRDF",
                                value=channel)
        return [("", source)]
    if isinstance(source, Mapping) and source and all(isinstance(m, Model)
                                                      for m in source.values()):
        pairs = [(str(k), m) for k, m in source.items()]
    elif getattr(source, "channels", None) and all(
            isinstance(getattr(c, "model", None), Model) for c in source.channels):
        pairs = [(str(c.channel), c.model) for c in source.channels]
    else:
        raise ArgumentError("source", "to_rgl takes a roughbrdf Model (rb.model(...)), a "
                            "FitResult (rb.fit(...)) or a mapping channel -> Model",
                            value=type(source).__name__)
    if channel is None:
        return pairs
    labels = [lab for lab, _ in pairs]
    if str(channel) in labels:
        return [pairs[labels.index(str(channel))]]
    if isinstance(channel, int | np.integer) and -len(pairs) <= channel < len(pairs):
        return [pairs[int(channel)]]
    raise ArgumentError("channel", f"not a channel of the fit ({', '.join(labels)})",
                        value=channel)


def _mixing(labels: list[str], color: str) -> tuple[np.ndarray, list[str], list[float] | None]:
    """The matrix from the channels' values to the file's, its channel names, and the
    wavelengths of a spectral file."""
    nm = [_wavelength(lab) for lab in labels]
    if len(labels) == 1:  # grey
        names = ["R", "G", "B"] if color == "rgb" else [f"{w:g}nm" for w in _FLAT_NM]
        return np.ones((len(names), 1)), names, None if color == "rgb" else list(_FLAT_NM)
    if any(w is None for w in nm):
        if color == "rgb" and len(labels) == 3:
            return np.eye(3), ["R", "G", "B"], None
        raise ArgumentError("color", f"channels {', '.join(labels)} have no wavelengths "
                            "(labels like '525nm'): an RGB file takes three of them or one; "
                            "pick one with channel=", value=color)
    waves = np.array(nm, float)
    order = np.argsort(waves)
    if color == "spectral":
        return np.eye(len(labels))[order], [labels[i] for i in order], waves[order].tolist()
    mix = np.zeros((3, len(labels)))
    for row, target in enumerate(RGB_NM):  # linear interpolation in wavelength, held at ends
        k = np.interp(target, waves[order], np.arange(len(labels), dtype=float))
        lo = int(np.floor(k))
        hi = min(lo + 1, len(labels) - 1)
        mix[row, order[lo]] += 1 - (k - lo)
        mix[row, order[hi]] += k - lo
    return mix, ["R", "G", "B"], None


def to_rgl(source: Any, out: str | os.PathLike, *, channel: int | str | None = None,
           overwrite: bool = False, color: str | None = None,
           resolution: Resolution | Mapping[str, Any] | None = None,
           description: str | None = None, allow_energy_gain: bool = False) -> RglExport:
    """Write an RGL measured-BSDF tensor file (``.bsdf``) of a model or a fit.

    Parameters
    ----------
    source : Model, FitResult or mapping
        An isotropic model (``rb.model``), a fit (``rb.fit``) or ``{channel: model}``.
    out : str or path-like
        The file (``.bsdf`` added without a suffix).
    channel : int or str, optional
        One channel of a fit.
    overwrite : bool
        Replace an existing file (default: refuse before any work).
    color : {"rgb", "spectral"}, optional
        Default: spectral when a fit's channels are wavelengths (``"525nm"``), else RGB.
    resolution : Resolution or mapping, optional
        Grid sizes (:class:`~roughbrdf.export.rgl.build.Resolution`; a mapping of its fields).
    description : str, optional
        Text for the file's ``description`` (default: the model); the NDF's source is added.
    allow_energy_gain : bool
        Write a model whose albedo exceeds ``1 + 1e-3`` at an incidence of 0, 5, ... 85,
        89 deg (refused by default, an :class:`~roughbrdf.errors.ArgumentError` naming it, as
        by every export), recorded in the ``description``.

    Returns
    -------
    RglExport

    Examples
    --------
    >>> import roughbrdf as rb, tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "paint.bsdf"
    >>> done = to_rgl(rb.model("coated", alpha=0.2), path,
    ...               resolution={"theta_i": 6, "samples": 16, "vndf": 16, "ndf": 64})
    >>> done.color, done.channels, path.read_bytes()[:11]
    ('rgb', ['R', 'G', 'B'], b'tensor_file')
    >>> "power iteration" in done.ndf_source
    True
    """
    from ...fitting.results.plausibility import refuse_energy_gain
    from ...io.rgl_tensor import encode
    from ...output import atomic_write, refuse_existing

    start = time.perf_counter()
    path = Path(out) if Path(out).suffix else Path(out).with_suffix(".bsdf")
    refuse_existing(path, overwrite)
    res = _resolution(resolution)
    pairs = _channels(source, channel)
    labels = [lab for lab, _ in pairs]
    if color is None:
        color = "spectral" if len(pairs) > 1 and all(_wavelength(x) for x in labels) else "rgb"
    if color not in ("rgb", "spectral"):
        raise ArgumentError("color", "must be 'rgb' or 'spectral'", value=color)
    mix, names, waves = _mixing(labels, color)
    models = [m for _, m in pairs]
    notes = refuse_energy_gain(dict(pairs), allow_energy_gain)
    if description is not None:
        text = description
    elif len(models) == 1:
        text = f"roughbrdf export of {models[0]!r}" + (f" ({labels[0]})" if labels[0] else "")
    else:  # the channels' parameters differ: name the model, not one channel's values
        text = (f"roughbrdf export of a {getattr(models[0], 'name', 'model')} fit, channels "
                f"{', '.join(labels)}")
    text = "; ".join([text, *notes])
    fields, source_ndf = build_fields(models, res, rgb=color == "rgb", mix=mix,
                                      wavelengths=waves, description=text)
    blob = encode(fields)
    atomic_write(path, blob, overwrite=overwrite, binary=True)
    return RglExport(path, color, names, source_ndf, res, len(blob),
                     time.perf_counter() - start)


def _resolution(value: Any) -> Resolution:
    if value is None:
        return Resolution()
    try:
        res = value if isinstance(value, Resolution) else Resolution(**dict(value))
        res.check()
    except (TypeError, ValueError) as exc:
        raise ArgumentError("resolution", str(exc), value=value) from None
    return res
