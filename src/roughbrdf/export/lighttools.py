"""Models and measurements as LightTools BSDF files (``.bsdf``; the layout and its angle
convention: :mod:`roughbrdf.io.lighttools`).

:func:`to_lighttools` samples a model's BRDF on a grid of incidences (``AOI``), azimuths about
the normal (``ScatterAzimuth``, source at 90 deg, specular at 270 deg) and polar angles
(``ScatterRadial``) and writes one Monochrome file; each incidence's ``TIS`` is the model's
directional-hemispherical reflectance (:func:`roughbrdf.albedo`). :func:`write_measurement`
writes a measurement whose samples lie on such a grid (e.g. one read from a LightTools file;
it is :func:`roughbrdf.io.lighttools_write.write_measurement`, with the file's text and
integral). Both write atomically and refuse an existing file unless ``overwrite=True``
(:mod:`roughbrdf.output`).

The default grid: ``AOI`` 0, 10, ..., 80 deg; ``ScatterRadial`` 0, 2, ..., 90 deg;
``ScatterAzimuth`` 0, 5, ..., 360 deg (``Asymmetric``, the whole circle, both ends given so
that an interpolating reader - libbsdf's is multilinear - needs no wrap-around). The polar
grid is fixed (it does not follow the specular lobe, unlike the Zemax grid about the specular
direction): a lobe narrower than a few degrees needs finer ``radial``/``azimuth``, which
:func:`table_integral` against TIS shows.

Values are printed with 8 significant digits (``%.7e``); directions beyond the horizon
(``ScatterRadial > 90``) hold 0.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ArgumentError
from ..io.lighttools import LightToolsGrid

# the file's text, its integral and the record of a written file are shared with the
# measurement writer, which lives in io (the layer below) with the reader; write_measurement
# stays importable from here, where it was first documented
from ..io.lighttools_write import (
    VALUE_FORMAT,
    LightToolsFile,
    format_table,
    table_integral,
    write_measurement,
)
from ..output import atomic_write, refuse_existing

__all__ = ["to_lighttools", "write_measurement", "format_table", "model_table",
           "table_integral", "default_grid", "LightToolsFile", "DEFAULT_INCIDENCES_DEG",
           "VALUE_FORMAT"]

#: AOI of the default grid (degrees)
DEFAULT_INCIDENCES_DEG = tuple(float(a) for a in range(0, 81, 10))
#: default ScatterRadial step (degrees), 0 to 90
RADIAL_STEP_DEG = 2.0
#: default ScatterAzimuth step (degrees), 0 to 360
AZIMUTH_STEP_DEG = 5.0


def default_grid(angles_of_incidence: Any = None, *, radial: Any = None, azimuth: Any = None,
                 symmetry: str = "Asymmetric") -> LightToolsGrid:
    """The grid :func:`to_lighttools` uses (module docstring); the arguments (radians)
    replace its parts. ``PlaneSymmetrical`` without ``azimuth`` takes 90-270 deg, the half
    of the circle through the source side (``phi`` in [-pi, 0]).

    Examples
    --------
    >>> g = default_grid()
    >>> g.shape, g.aoi_deg[-1], g.azimuth_deg[-1], g.radial_deg[-1]
    ((9, 73, 46), 80.0, 360.0, 90.0)
    >>> default_grid(symmetry="PlaneSymmetrical").azimuth_deg[::18]
    (90.0, 180.0, 270.0)
    """
    def degrees(value: Any, name: str, default: Any) -> tuple[float, ...]:
        if value is None:
            return tuple(default)
        a = np.atleast_1d(np.asarray(value, dtype=float))
        if a.ndim != 1 or not np.isfinite(a).all():
            raise ArgumentError(name, "must be a 1-d list of finite angles (radians)",
                                value=value, unit="rad")
        return tuple(float(x) for x in np.round(np.degrees(a), 9))

    if symmetry == "PlaneSymmetrical":
        az_default = np.arange(90.0, 270.0 + 1e-9, AZIMUTH_STEP_DEG)
    else:
        az_default = np.arange(0.0, 360.0 + 1e-9, AZIMUTH_STEP_DEG)
    try:
        return LightToolsGrid(
            degrees(angles_of_incidence, "angles_of_incidence", DEFAULT_INCIDENCES_DEG),
            degrees(azimuth, "azimuth", az_default),
            degrees(radial, "radial", np.arange(0.0, 90.0 + 1e-9, RADIAL_STEP_DEG)), symmetry)
    except ArgumentError as exc:  # name the Python argument, in radians
        name = {"aoi_deg": "angles_of_incidence", "azimuth_deg": "azimuth",
                "radial_deg": "radial"}.get(exc.argument, exc.argument)
        raise ArgumentError(name, exc.message + " (given in radians here)",
                            value=exc.value) from None


def _one_model(obj: Any, channel: Any) -> tuple[Any, str | None]:
    """The model to write and its channel label: a Model or callable as given; one channel of
    a fit (``rb.fit(...)``, its ``channels`` of ``ChannelFit``) - the only one, or
    ``channel``. A LightTools file holds one model: libbsdf reads no file with several
    Monochrome wavelengths, so a fit of several channels is written one file per channel."""
    chans = getattr(obj, "channels", None)
    if chans is None or callable(getattr(obj, "brdf", None)):
        if channel is not None:
            raise ArgumentError("channel", "applies to a fit; a model is one file",
                                value=channel)
        return obj, None
    if channel is None:
        if len(chans) != 1:
            raise ArgumentError("channel", f"the fit has {len(chans)} channels "
                                f"({', '.join(str(c.channel) for c in chans)}); a LightTools "
                                "file holds one: give channel= (one file per channel)",
                                value=None)
        return chans[0].model, str(chans[0].channel)
    c = obj[channel]
    return c.model, str(c.channel)


def _brdf_of(model: Any) -> Callable[..., Any]:
    """The BRDF function of a model (``.brdf``) or a plain callable."""
    if hasattr(model, "brdf") and callable(model.brdf):
        return model.brdf
    if callable(model):
        return model
    raise TypeError(f"to_lighttools takes a roughbrdf Model (rb.model(...)) or a callable "
                    f"f(theta_i, theta_r, phi) -> BRDF (sr^-1, radians), got "
                    f"{type(model).__name__}")


def model_table(model: Any, grid: LightToolsGrid, *, polarization: Any = None) -> np.ndarray:
    """The model's BRDF (sr⁻¹) at every node of ``grid`` (shape ``grid.shape``); nodes below
    the horizon hold 0. Raises ``ValueError`` naming the node (degrees) where the model has
    no finite value."""
    brdf = _brdf_of(model)
    ti, tr, ph = grid.directions()
    above = tr <= 0.5 * math.pi + 1e-12
    kw = {} if polarization is None else {"polarization": polarization}
    values = np.zeros(ti.shape)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        f = np.asarray(brdf(ti[above], np.minimum(tr[above], 0.5 * math.pi), ph[above], **kw),
                       dtype=float)
    values[above] = np.broadcast_to(f, values[above].shape)
    bad = ~np.isfinite(values)
    if bad.any():
        i, j, k = (int(x[0]) for x in np.nonzero(bad))
        raise ValueError(f"the model has no finite BRDF at AOI {grid.aoi_deg[i]:g} deg, "
                         f"ScatterAzimuth {grid.azimuth_deg[j]:g} deg, ScatterRadial "
                         f"{grid.radial_deg[k]:g} deg: {values[i, j, k]!r}")
    return values


def _wavelength_nm(wavelength_nm: Any) -> float | None:
    """The ``Wavelength`` to write (nm), checked."""
    if wavelength_nm is None:
        return None
    try:
        w = float(wavelength_nm)
    except (TypeError, ValueError):
        w = math.nan
    if not (math.isfinite(w) and w > 0):
        raise ArgumentError("wavelength_nm", "must be a positive number of nanometres",
                            value=wavelength_nm)
    return w


def to_lighttools(model: Any, out: str | os.PathLike, *, angles_of_incidence: Any = None,
                  radial: Any = None, azimuth: Any = None, symmetry: str = "Asymmetric",
                  polarization: Any = None, wavelength_nm: Any = None, channel: Any = None,
                  overwrite: bool = False, allow_energy_gain: bool = False) -> LightToolsFile:
    """Write a model's BRDF as a LightTools BSDF file.

    Parameters
    ----------
    model : Model, callable or FitResult
        A roughbrdf model (``model.brdf(theta_i, theta_r, phi)``), a function of the same
        three angles (radians, roughbrdf's frame) returning the BRDF in sr⁻¹, or a fit (its
        one channel, or ``channel``).
    out : str or path-like
        The file (``.bsdf`` added when it has no suffix).
    angles_of_incidence, radial, azimuth : array_like, optional
        The grid in radians (written in degrees): incidences (``AOI``), polar angles of the
        scattered direction (``ScatterRadial``) and LightTools azimuths (``ScatterAzimuth``,
        source at pi/2, specular at 3 pi/2); defaults in the module docstring.
    symmetry : {"Asymmetric", "PlaneSymmetrical"}
        ``PlaneSymmetrical`` writes half the circle (default azimuths 90-270 deg).
    polarization : optional
        Incident polarization (:meth:`Model.brdf`); default unpolarized.
    wavelength_nm : float, optional
        Written as each block's ``Wavelength`` (nm); for a fit's channel named ``"550nm"``
        that wavelength by default.
    channel : str or int, optional
        The channel of a fit to write.
    overwrite : bool
        Replace an existing file (default: refuse before any work).
    allow_energy_gain : bool
        Write a roughbrdf model whose albedo exceeds ``1 + 1e-3`` at some incidence (recorded
        in a comment); refused by default
        (:func:`~roughbrdf.fitting.results.plausibility.refuse_energy_gain`).

    Returns
    -------
    LightToolsFile
        TIS is :func:`roughbrdf.albedo` for a Model and the table's own integral
        (:func:`table_integral`) for a plain callable.

    Examples
    --------
    >>> import roughbrdf as rb, tempfile, pathlib
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "paint.bsdf"
    >>> res = to_lighttools(rb.model("lambertian", rho=0.5), out)
    >>> [round(float(t), 6) for t in res.tis["value"][:2]], res.integral_error < 1e-3
    ([0.5, 0.5], True)
    >>> m = rb.io.lighttools.read(out)
    >>> bool(abs(m.values[:, 0] - 0.5 / 3.141592653589793).max() < 1e-8)
    True
    """
    from ..fitting.results.plausibility import refuse_energy_gain
    from ..integrate import albedo
    from ..models.base import Model

    path = Path(out)
    if path.suffix == "":
        path = path.with_suffix(".bsdf")
    refuse_existing(path, overwrite)
    model, label = _one_model(model, channel)
    _brdf_of(model)
    named = re.fullmatch(r"\s*([0-9.]+)\s*nm\s*", label or "")
    wl = _wavelength_nm(wavelength_nm if wavelength_nm is not None or named is None
                        else named.group(1))
    notes = refuse_energy_gain({None: model}, allow_energy_gain) if isinstance(model, Model) \
        else []
    grid = default_grid(angles_of_incidence, radial=radial, azimuth=azimuth, symmetry=symmetry)
    if isinstance(model, Model) and not model.grazing_incidence and max(grid.aoi_deg) >= 90.0:
        raise ArgumentError("angles_of_incidence", f"{model.name} is not defined at grazing "
                            "incidence (theta_i = 90 deg); give angles below pi/2",
                            value=math.radians(max(grid.aoi_deg)), unit="rad")
    values = model_table(model, grid, polarization=polarization)
    integral = table_integral(grid, values)
    if isinstance(model, Model):
        tis = np.atleast_1d(np.asarray(albedo(model, np.radians(grid.aoi_deg),
                                              polarization=polarization), dtype=float))
        how = "the model's directional-hemispherical reflectance (roughbrdf.albedo)"
    else:
        tis, how = integral, "the table's own cosine-weighted integral (trapezoid rule)"
    comments = [f"roughbrdf export of {model!r}"
                + ("" if label is None else f" (channel {label})"),
                "LightTools BSDF as read by libbsdf's "
                "LightToolsBsdfReader: BRDF in sr^-1; AOI = theta_i; ScatterRadial = polar "
                "angle from the normal; ScatterAzimuth about the normal, source at 90 deg, "
                "specular at 270 deg", f"TIS = {how}; the table's own integral is within "
                f"{float(np.max(np.abs(integral - tis))):.2g} of it", *notes]
    text = format_table(grid, {"value": values}, {"value": tis},
                        wavelengths={"value": wl}, comments=comments)
    atomic_write(path, text, overwrite=overwrite)
    return LightToolsFile(path, repr(model), grid, {"value": tis}, {"value": integral})
