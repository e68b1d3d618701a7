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

The default grid: ``AOI`` 0, 10, ..., 80 deg; ``ScatterRadial`` (polar angle) 0-90 deg and
``ScatterAzimuth`` 0-360 deg (``Asymmetric``, the whole circle, both ends given so that an
interpolating reader - libbsdf's is multilinear - needs no wrap-around), non-uniform: dense
around each incidence's specular direction (``ScatterRadial`` = AOI, ``ScatterAzimuth`` = 270),
spaced there by an eighth of the lobe's half width (:func:`~roughbrdf.export.grids.lobe_widths`;
in azimuth divided by ``sin AOI``, the circle's radius there), the spacing growing by 10 % of
the distance from it up to 2 deg radial and 5 deg azimuth (a model without a lobe: 0, 2, ...,
90 and 0, 5, ..., 360). It is refined level by level (every spacing near the lobe halved)
until the table's own integral (:func:`table_integral`, the trapezoid rule on the file's
nodes) is within 0.25 % of TIS at every incidence, so that it stays within 0.5 %
(:data:`~roughbrdf.export.grids.INTEGRAL_RTOL`) for another reader's quadrature too
(:func:`~roughbrdf.export.grids.refine`: at most
:data:`~roughbrdf.export.grids.MAX_TABLE_VALUES` values; a warning if even that misses). A
``radial`` or ``azimuth`` given is used as given (the other part the first level's), with one
:class:`~roughbrdf.export.grids.TableAccuracyWarning` saying by how much its integral misses
TIS when that is more than 0.5 %.

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
from .grids import (
    cell_rule,
    graded_axis,
    grid_note,
    lobe_widths,
    refine,
)

__all__ = ["to_lighttools", "write_measurement", "format_table", "model_table",
           "table_integral", "default_grid", "LightToolsFile", "DEFAULT_INCIDENCES_DEG",
           "VALUE_FORMAT"]

#: AOI of the default grid (degrees)
DEFAULT_INCIDENCES_DEG = tuple(float(a) for a in range(0, 81, 10))
#: the largest ScatterRadial step (degrees), 0 to 90: the spacing away from any lobe
RADIAL_STEP_DEG = 2.0
#: the largest ScatterAzimuth step (degrees), 0 to 360
AZIMUTH_STEP_DEG = 5.0
#: nodes per half width of the specular lobe at the first level (each level doubles it)
NODES_PER_HALF_WIDTH = 8
#: the spacing grows by this fraction of the distance from the specular direction (first
#: level; each level halves it)
GROWTH = 0.1
#: the width (degrees) of the azimuth cells either side of 90 deg in a non-uniform list
#: (:func:`_lobe_axes`: the cell libbsdf's reader loses)
LIBBSDF_WEDGE_DEG = 1e-3


def default_grid(angles_of_incidence: Any = None, *, radial: Any = None, azimuth: Any = None,
                 symmetry: str = "Asymmetric", model: Any = None, level: int = 0,
                 polarization: Any = None) -> LightToolsGrid:
    """The grid :func:`to_lighttools` uses (module docstring): for ``model`` (a Model or a
    function of the angles) dense around each incidence's specular direction, finer with each
    ``level``; without a model (or for one without a lobe) uniform, 2 deg radial and 5 deg
    azimuth. ``angles_of_incidence``, ``radial`` and ``azimuth`` (radians) replace its parts.
    ``PlaneSymmetrical`` takes 90-270 deg of azimuth, the half of the circle through the
    source side (``phi`` in [-pi, 0]).

    Examples
    --------
    >>> g = default_grid()
    >>> g.shape, g.aoi_deg[-1], g.azimuth_deg[-1], g.radial_deg[-1]
    ((9, 73, 46), 80.0, 360.0, 90.0)
    >>> default_grid(symmetry="PlaneSymmetrical").azimuth_deg[::18]
    (90.0, 180.0, 270.0)
    >>> import roughbrdf as rb
    >>> g = default_grid(model=rb.model("microfacet", alpha=0.05))
    >>> 30.0 in g.radial_deg and 270.0 in g.azimuth_deg    # specular nodes at AOI 30
    True
    >>> float(min(np.diff(g.radial_deg))) < 0.5           # dense there
    True
    """
    def degrees(value: Any, name: str) -> tuple[float, ...]:
        a = np.atleast_1d(np.asarray(value, dtype=float))
        if a.ndim != 1 or not np.isfinite(a).all():
            raise ArgumentError(name, "must be a 1-d list of finite angles (radians)",
                                value=value, unit="rad")
        return tuple(float(x) for x in np.round(np.degrees(a), 9))

    try:
        aoi = (DEFAULT_INCIDENCES_DEG if angles_of_incidence is None
               else degrees(angles_of_incidence, "angles_of_incidence"))
        rad_given = None if radial is None else degrees(radial, "radial")
        az_given = None if azimuth is None else degrees(azimuth, "azimuth")
        LightToolsGrid(aoi, (0.0,), (0.0,), symmetry)  # names a bad incidence or symmetry
        rad, az = _lobe_axes(model, aoi, symmetry, level, polarization)
        return LightToolsGrid(aoi, az if az_given is None else az_given,
                              rad if rad_given is None else rad_given, symmetry)
    except ArgumentError as exc:  # name the Python argument; the angle in radians
        name = {"aoi_deg": "angles_of_incidence", "azimuth_deg": "azimuth",
                "radial_deg": "radial"}.get(exc.argument, exc.argument)
        message = re.sub(r"\[(\S+), (\S+)\] deg", lambda m: f"{m[0]} ("
                         f"{math.radians(float(m[1])):.4g} to {math.radians(float(m[2])):.4g} "
                         "rad)", exc.message)
        if isinstance(exc.value, float):  # one angle (degrees here): shown in each unit
            raise ArgumentError(name, message, value=math.radians(exc.value),
                                unit="rad") from None
        raise ArgumentError(name, message + " (the file's degrees)", value=exc.value) from None


def _lobe_axes(model: Any, aoi: tuple[float, ...], symmetry: str, level: int,
               polarization: Any) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """ScatterRadial and ScatterAzimuth (degrees) at refinement ``level``: dense at each
    incidence's specular direction (polar angle AOI, azimuth 270) where the model has a lobe.
    Near the specular direction an azimuth step ``da`` is an angle ``sin(AOI) da``, so the
    azimuth spacing there is the radial one over ``sin AOI`` (normal incidence, where every
    azimuth meets the lobe alike - the models are isotropic -, sets none)."""
    scale = 0.5 ** (0.5 * int(level))  # each level divides the spacings by sqrt(2)
    widths = [None] * len(aoi) if model is None else \
        lobe_widths(_brdf_of(model), aoi, polarization=polarization)
    lobes = [(a, w) for a, w in zip(aoi, widths, strict=True) if w is not None]
    radial = graded_axis(0.0, 90.0, [a for a, _ in lobes],
                         [scale * w / NODES_PER_HALF_WIDTH for _, w in lobes], GROWTH * scale,
                         RADIAL_STEP_DEG)
    fine = [scale * w / NODES_PER_HALF_WIDTH / math.sin(math.radians(a)) for a, w in lobes
            if a > 0]
    lo = 90.0 if symmetry == "PlaneSymmetrical" else 0.0
    hi = 270.0 if symmetry == "PlaneSymmetrical" else 360.0
    # libbsdf turns a non-uniform azimuth list by -90 deg node by node and so loses the cell
    # that begins at azimuth 90 (90 lands on 0 or 360, not both): nodes LIBBSDF_WEDGE_DEG
    # either side of 90 make that cell negligible (a uniform list it turns exactly)
    azimuth = graded_axis(lo, hi, [270.0] if fine else [], [min(fine)] if fine else [],
                          GROWTH * scale, AZIMUTH_STEP_DEG, pins=(90.0, 180.0))
    if fine:
        wedge = [90.0 - LIBBSDF_WEDGE_DEG, 90.0 + LIBBSDF_WEDGE_DEG]
        azimuth = np.unique(np.concatenate([azimuth, [a for a in wedge if lo <= a <= hi]]))
    return tuple(radial.tolist()), tuple(azimuth.tolist())


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
    given = radial is not None or azimuth is not None

    def build(level: int) -> LightToolsGrid:
        return default_grid(angles_of_incidence, radial=radial, azimuth=azimuth,
                            symmetry=symmetry, model=model, level=level,
                            polarization=polarization)

    first = build(0)
    if isinstance(model, Model) and not model.grazing_incidence and max(first.aoi_deg) >= 90.0:
        raise ArgumentError("angles_of_incidence", f"{model.name} is not defined at grazing "
                            "incidence (theta_i = 90 deg); give angles below pi/2",
                            value=math.radians(max(first.aoi_deg)), unit="rad")
    if isinstance(model, Model):
        tis_known = np.atleast_1d(np.asarray(albedo(model, np.radians(first.aoi_deg),
                                                    polarization=polarization), dtype=float))
        how = "the model's directional-hemispherical reflectance (roughbrdf.albedo)"
    else:
        tis_known, how = None, "the table's own cosine-weighted integral (trapezoid rule)"

    def evaluate(grid: LightToolsGrid) -> tuple[np.ndarray, np.ndarray, np.ndarray, None]:
        values = model_table(model, grid, polarization=polarization)
        t = np.radians(np.minimum(grid.radial_deg, 90.0))
        cells = cell_rule(values, t, np.radians(grid.azimuth_deg), np.cos(t)[None, :],
                          factor=2.0 if grid.symmetry == "PlaneSymmetrical" else 1.0)
        return values, table_integral(grid, values), cells, None

    chosen = refine(lambda lv: first if lv == 0 else build(lv), evaluate, tis_known,
                    size=lambda g: int(np.prod(g.shape)), user_grid=first if given else None,
                    what=str(path))
    grid, values, integral = chosen.grid, chosen.values, chosen.integral
    tis = integral if tis_known is None else tis_known
    comments = [f"roughbrdf export of {model!r}"
                + ("" if label is None else f" (channel {label})"),
                "LightTools BSDF as read by libbsdf's "
                "LightToolsBsdfReader: BRDF in sr^-1; AOI = theta_i; ScatterRadial = polar "
                "angle from the normal; ScatterAzimuth about the normal, source at 90 deg, "
                "specular at 270 deg", f"TIS = {how}; the table's own integral (trapezoid "
                f"rule on this file's nodes) is within {100 * float(np.max(chosen.errors)):.2g}"
                " % of it at every AOI",
                grid_note(chosen.level, "dense around each AOI's specular direction"), *notes]
    if chosen.warning is not None:
        comments.append("warning: " + chosen.warning)
    text = format_table(grid, {"value": values}, {"value": tis},
                        wavelengths={"value": wl}, comments=comments)
    atomic_write(path, text, overwrite=overwrite)
    return LightToolsFile(path, repr(model), grid, {"value": tis}, {"value": integral})
