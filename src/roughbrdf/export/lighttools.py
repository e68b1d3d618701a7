"""Models and measurements as LightTools BSDF files (``.bsdf``; the layout and its angle
convention: :mod:`roughbrdf.io.lighttools`).

:func:`to_lighttools` samples a model's BRDF on a grid of incidences (``AOI``), azimuths about
the normal (``ScatterAzimuth``, source at 90 deg, specular at 270 deg) and polar angles
(``ScatterRadial``) and writes one Monochrome file; each incidence's ``TIS`` is the model's
directional-hemispherical reflectance (:func:`roughbrdf.albedo`). :func:`write_measurement`
writes a measurement whose samples lie on such a grid (e.g. one read from a LightTools file).
Both write atomically and refuse an existing file unless ``overwrite=True``
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
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ArgumentError
from ..io.lighttools import GRID_TOL, LightToolsGrid
from ..measurement import Measurement
from ..output import atomic_write, refuse_existing
from ..quantity import Quantity

__all__ = ["to_lighttools", "write_measurement", "format_table", "model_table",
           "table_integral", "default_grid", "LightToolsFile", "DEFAULT_INCIDENCES_DEG"]

#: AOI of the default grid (degrees)
DEFAULT_INCIDENCES_DEG = tuple(float(a) for a in range(0, 81, 10))
#: default ScatterRadial step (degrees), 0 to 90
RADIAL_STEP_DEG = 2.0
#: default ScatterAzimuth step (degrees), 0 to 360
AZIMUTH_STEP_DEG = 5.0
#: the printed precision of values: ``%.7e``, 8 significant digits
VALUE_FORMAT = "%.7e"


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


def table_integral(grid: LightToolsGrid, values: np.ndarray) -> np.ndarray:
    """``int f cos(theta_r) d omega`` of a table (shape ``grid.shape``) at each incidence, by
    the trapezoid rule on the grid's nodes (``sin theta cos theta d theta d azimuth``; the
    ``PlaneSymmetrical`` half counted twice). The hemisphere is covered only when the radial
    angles reach 0-90 deg and the azimuths the circle (or its half).

    Examples
    --------
    >>> g = default_grid([0.0])
    >>> round(float(table_integral(g, np.full(g.shape, 1 / np.pi))[0]), 4)   # Lambertian, 1
    0.9996
    """
    t = np.radians(np.minimum(grid.radial_deg, 90.0))
    a = np.radians(grid.azimuth_deg)
    if grid.symmetry == "Asymmetric" and a.size > 1 and a[-1] < a[0] + 2 * math.pi - 1e-9:
        # the circle is periodic: close it with the first azimuth's column
        a = np.append(a, a[0] + 2 * math.pi)
        values = np.concatenate([values, values[..., :1, :]], axis=-2)
    w = np.sin(t) * np.cos(t)
    inner = np.trapezoid(values * w, t, axis=-1) if len(t) > 1 else np.zeros(values.shape[:-1])
    total = np.trapezoid(inner, a, axis=-1) if len(a) > 1 else np.zeros(values.shape[:-2])
    return np.asarray(total * (2.0 if grid.symmetry == "PlaneSymmetrical" else 1.0), float)


def format_table(grid: LightToolsGrid, tables: Mapping[str, np.ndarray],
                 tis: Mapping[str, Any], *, spectral: str = "Monochrome",
                 wavelengths: Mapping[str, float | None] | None = None,
                 comments: Sequence[str] = ()) -> str:
    """The text of a LightTools BSDF file: ``tables`` maps each channel to its values
    (shape ``grid.shape``), ``tis`` to its TIS per incidence. ``spectral="XYZ"`` needs the
    channels ``X``, ``Y``, ``Z``; Monochrome channels may carry a ``Wavelength``.

    Comments go first (libbsdf skips comment lines only between keywords, never inside the
    values); one row per azimuth, one value per radial angle, as libbsdf reads them.

    Examples
    --------
    >>> g = LightToolsGrid((0.0,), (0.0, 360.0), (0.0, 90.0))
    >>> print(format_table(g, {"value": np.full(g.shape, 0.1)}, {"value": [0.3]}))
    ... # doctest: +NORMALIZE_WHITESPACE
    Symmetry Asymmetric
    SpectralContent Monochrome
    ScatterAzimuth 2
    0 360
    ScatterRadial 2
    0 90
    DataBegin
    AOI 0
    POI 0
    Side Front
    ScatterType BRDF
    TIS 3.0000000e-01
    1.0000000e-01 1.0000000e-01
    1.0000000e-01 1.0000000e-01
    DataEnd
    """
    if spectral not in ("Monochrome", "XYZ"):
        raise ArgumentError("spectral", "must be 'Monochrome' or 'XYZ'", value=spectral)
    if spectral == "XYZ" and sorted(tables) != ["X", "Y", "Z"]:
        raise ArgumentError("tables", "XYZ needs the channels X, Y and Z", value=list(tables))
    wl = dict(wavelengths or {})
    out = [f"# {c}" for s in comments for c in str(s).splitlines()]
    out += [f"Symmetry {grid.symmetry}", f"SpectralContent {spectral}",
            f"ScatterAzimuth {len(grid.azimuth_deg)}", " ".join(f"{a:.10g}" for a in
                                                                 grid.azimuth_deg),
            f"ScatterRadial {len(grid.radial_deg)}", " ".join(f"{r:.10g}" for r in
                                                               grid.radial_deg), "DataBegin"]
    for ch, table in tables.items():
        vals = np.asarray(table, dtype=float)
        if vals.shape != grid.shape:
            raise ArgumentError("tables", f"channel {ch}: shape {vals.shape}, the grid's is "
                                f"{grid.shape}", value=ch)
        t = np.broadcast_to(np.asarray(tis[ch], dtype=float), (grid.shape[0],))
        for i, aoi in enumerate(grid.aoi_deg):
            out += [f"AOI {aoi:.10g}", "POI 0", "Side Front"]
            w = wl.get(ch)
            if w is not None:
                out.append(f"Wavelength {float(w):.10g}")
            out.append("ScatterType BRDF")
            if spectral == "XYZ":
                out.append(f"TristimulusValue Tris{ch}")
            out.append(f"TIS {VALUE_FORMAT % t[i]}")
            out += [" ".join(VALUE_FORMAT % v for v in row) for row in vals[i]]
    out.append("DataEnd")
    return "\n".join(out) + "\n"


@dataclass(frozen=True)
class LightToolsFile:
    """One written file: its path, grid, TIS per incidence and the table's own integral.

    Attributes
    ----------
    path : pathlib.Path
    model : str
        What was written (the model's ``repr`` or the measurement's file).
    grid : LightToolsGrid
    tis : dict of str -> numpy.ndarray
        TIS written per channel and incidence.
    integral : dict of str -> numpy.ndarray
        :func:`table_integral` of each channel's table.
    """

    path: Path
    model: str
    grid: LightToolsGrid
    tis: dict[str, np.ndarray] = field(repr=False)
    integral: dict[str, np.ndarray] = field(repr=False)

    @property
    def integral_error(self) -> float:
        """Largest ``|integral - TIS|`` over channels and incidences (absolute)."""
        return float(max(np.max(np.abs(self.integral[c] - self.tis[c])) for c in self.tis))

    def text(self) -> str:
        """Two lines: the file and grid, then TIS against the table's integral."""
        n_aoi, n_az, n_rad = self.grid.shape
        tis = {c: np.round(v, 4).tolist() for c, v in self.tis.items()}
        return (f"wrote {self.path}: {n_aoi}x{n_az}x{n_rad} (AOI x ScatterAzimuth x "
                f"ScatterRadial, {self.grid.symmetry})\n  TIS {tis}; table integral within "
                f"{self.integral_error:.2g} of it")

    def __str__(self) -> str:
        return self.text()


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
        (:func:`~roughbrdf.fitting.plausibility.refuse_energy_gain`).

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
    from ..fitting.plausibility import refuse_energy_gain
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


# --------------------------------------------------------------------------------------------
# a measurement on a LightTools grid
# --------------------------------------------------------------------------------------------
def _node_angles(m: Measurement) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each sample's (AOI, ScatterAzimuth, ScatterRadial), degrees: the file's own angles
    when read from a LightTools file, else from the geometry (azimuth = phi - 90 deg)."""
    o = m.original
    if m.meta.get("format") == "lighttools" and {"aoi", "scatter_azimuth",
                                                 "scatter_radial"} <= set(o):
        return (np.asarray(o["aoi"], float), np.asarray(o["scatter_azimuth"], float),
                np.asarray(o["scatter_radial"], float))
    az = np.mod(np.degrees(m.phi) - 90.0, 360.0)
    az = np.where(az > 360.0 - GRID_TOL, 0.0, az)
    return np.degrees(m.theta_i), az, np.degrees(m.theta_r)


def _grid_of(m: Measurement) -> tuple[LightToolsGrid, tuple[np.ndarray, ...]]:
    """The grid the samples lie on (the file's, when read from one) and each sample's index."""
    aoi, az, rad = _node_angles(m)
    g = m.meta.get("lighttools_grid") if m.meta.get("format") == "lighttools" else None
    axes = []
    for name, vals in (("aoi_deg", aoi), ("azimuth_deg", az), ("radial_deg", rad)):
        axis = np.asarray(g[name], float) if g else np.unique(np.round(vals, 6))
        if not g and name == "azimuth_deg" and axis[0] == 0.0 and axis[-1] < 360 - GRID_TOL:
            axis = np.append(axis, 360.0)  # close the circle: no wrap-around for interpolators
        axes.append(axis)
    grid = LightToolsGrid(tuple(axes[0]), tuple(axes[1]), tuple(axes[2]),
                          symmetry=g["symmetry"] if g else "Asymmetric")
    idx = []
    for axis, vals, name in zip(axes, (aoi, az, rad), ("AOI", "ScatterAzimuth",
                                                       "ScatterRadial"), strict=True):
        k = np.clip(np.searchsorted(axis, vals - GRID_TOL), 0, axis.size - 1)
        if not (np.abs(axis[k] - vals) <= 1e-5).all():
            bad = int(np.flatnonzero(np.abs(axis[k] - vals) > 1e-5)[0])
            raise ArgumentError("measurement", f"sample {bad} is off the grid ({name} "
                                f"{vals[bad]:g} deg)", value=float(vals[bad]))
        idx.append(k)
    return grid, tuple(idx)


def _fill(grid: LightToolsGrid, idx: tuple[np.ndarray, ...], values: np.ndarray
          ) -> np.ndarray:
    """The table ``(channels, *grid.shape)``: each sample at its node; the normal and azimuth
    360 completed from the node they repeat; below the horizon 0; any other gap refused."""
    n_ch = values.shape[1]
    table = np.full((n_ch, *grid.shape), np.nan)
    table[:, idx[0], idx[1], idx[2]] = values.T
    rad, az = np.asarray(grid.radial_deg), np.asarray(grid.azimuth_deg)
    for r0 in np.flatnonzero(np.abs(rad) <= GRID_TOL):  # the normal: one value per incidence
        col = table[:, :, :, r0]
        first = np.nanmax(np.where(np.isnan(col), -np.inf, col), axis=2, keepdims=True)
        table[:, :, :, r0] = np.where(np.isnan(col), first, col)
    if az.size > 1 and abs(az[-1] - az[0] - 360.0) <= GRID_TOL:
        table[:, :, -1] = np.where(np.isnan(table[:, :, -1]), table[:, :, 0], table[:, :, -1])
        table[:, :, 0] = np.where(np.isnan(table[:, :, 0]), table[:, :, -1], table[:, :, 0])
    table[:, :, :, rad > 90.0 + GRID_TOL] = 0.0
    gap = ~np.isfinite(table)
    if gap.any():
        _, i, j, k = (int(x[0]) for x in np.nonzero(gap))
        raise ArgumentError("measurement", f"not on a full LightTools grid: {int(gap.sum())} "
                            f"nodes have no sample, e.g. AOI {grid.aoi_deg[i]:g}, "
                            f"ScatterAzimuth {grid.azimuth_deg[j]:g}, ScatterRadial "
                            f"{grid.radial_deg[k]:g} deg (every AOI x azimuth x radial node "
                            "needs one)", value=int(gap.sum()))
    return table


def _spectral(channels: list[str]) -> tuple[str, dict[str, float | None]]:
    """SpectralContent and each channel's wavelength (nm) from the channel labels."""
    if sorted(channels) == ["X", "Y", "Z"]:
        return "XYZ", dict.fromkeys(channels)
    wl: dict[str, float | None] = {}
    for c in channels:
        mt = re.fullmatch(r"\s*([0-9.]+(?:[eE][-+]?\d+)?)\s*nm\s*", c)
        wl[c] = float(mt.group(1)) if mt else None
    if len(channels) > 1 and any(w is None for w in wl.values()):
        raise ArgumentError("measurement", "several channels can be written only as "
                            "wavelengths ('550nm', ...) or as X, Y, Z", value=channels)
    return "Monochrome", wl


def write_measurement(measurement: Measurement, path: str | os.PathLike, *,
                      overwrite: bool = False) -> LightToolsFile:
    """Write a measurement whose samples fill a LightTools grid (every AOI x ScatterAzimuth x
    ScatterRadial node, the normal and azimuth 360 completed from the nodes they repeat):
    one read from a LightTools file is written back on its own grid, with its TIS.

    Channels ``"550nm"``... become Wavelength blocks, ``X, Y, Z`` an XYZ file. TIS: the
    file's (``meta["lighttools_tis"]``) if it was read from one, else the table's own
    integral (:func:`table_integral`). Refuses (``ArgumentError`` of ``measurement``)
    samples off a full grid, quantities other than BRDF, Mueller data, and the file the
    measurement was read from.
    """
    from ..output import same_file

    p = Path(path)
    if measurement.mueller:
        raise ArgumentError("measurement", "holds Mueller elements; LightTools files hold the "
                            "BRDF only", value=measurement.mueller)
    if measurement.quantity != Quantity.BRDF:
        raise ArgumentError("measurement", "LightTools files hold the BRDF (sr^-1); convert "
                            "the values first", value=str(measurement.quantity))
    src = measurement.meta.get("file_abs")
    if src and p.exists() and same_file(src, p):
        raise ArgumentError("path", "is the file the measurement was read from", value=str(p))
    refuse_existing(p, overwrite)
    grid, idx = _grid_of(measurement)
    table = _fill(grid, idx, measurement.values)
    spectral, wl = _spectral(measurement.channels)
    tables = {c: table[i] for i, c in enumerate(measurement.channels)}
    integral = {c: table_integral(grid, t) for c, t in tables.items()}
    known = measurement.meta.get("lighttools_tis") or {}
    tis = {c: np.asarray(known[c], float) if c in known else integral[c] for c in tables}
    comments = [f"roughbrdf: {measurement.meta.get('file') or 'a measurement'} as a "
                "LightTools BSDF (BRDF in sr^-1)"]
    atomic_write(p, format_table(grid, tables, tis, spectral=spectral, wavelengths=wl,
                                 comments=comments), overwrite=overwrite)
    return LightToolsFile(p, str(measurement.meta.get("file")), grid, tis, integral)
