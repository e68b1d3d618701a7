"""Measurements written as LightTools BSDF files (``.bsdf``; the layout and its angle
convention: :mod:`roughbrdf.io.lighttools`, the reader).

:func:`write_measurement` writes a measurement whose samples lie on a LightTools grid (e.g. one
read from a LightTools file) - the writer of :func:`roughbrdf.io.write` for
``format="lighttools"``. The text of a file (:func:`format_table`), the table's own integral
(:func:`table_integral`) and the record of a written file (:class:`LightToolsFile`) are shared
with the model writer, :func:`roughbrdf.export.lighttools.to_lighttools`, which re-exports them:
they live here, with the reading and writing of measurements, so that :mod:`roughbrdf.io`
imports nothing of the layer above it (``export``). Files are written atomically and an
existing one is refused unless ``overwrite=True`` (:mod:`roughbrdf.output`).

Values are printed with 8 significant digits (``%.7e``); directions beyond the horizon
(``ScatterRadial > 90``) hold 0.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ArgumentError
from ..measurement import Measurement
from ..output import atomic_write, refuse_existing
from ..quantity import Quantity
from .lighttools import GRID_TOL, LightToolsGrid

__all__ = ["write_measurement", "format_table", "table_integral", "LightToolsFile",
           "VALUE_FORMAT"]

#: the printed precision of values: ``%.7e``, 8 significant digits
VALUE_FORMAT = "%.7e"


def table_integral(grid: LightToolsGrid, values: np.ndarray) -> np.ndarray:
    """``int f cos(theta_r) d omega`` of a table (shape ``grid.shape``) at each incidence, by
    the trapezoid rule on the grid's nodes (``sin theta cos theta d theta d azimuth``; the
    ``PlaneSymmetrical`` half counted twice). The hemisphere is covered only when the radial
    angles reach 0-90 deg and the azimuths the circle (or its half).

    Examples
    --------
    >>> g = LightToolsGrid((0.0,), tuple(np.arange(0.0, 360.1, 5.0)),
    ...                    tuple(np.arange(0.0, 90.1, 2.0)))   # the export's default grid
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
            row_format = " ".join([VALUE_FORMAT] * grid.shape[2])  # one % per row: fast
            out += [row_format % tuple(row) for row in vals[i].tolist()]
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

    @property
    def relative_error(self) -> float:
        """Largest ``|integral - TIS| / TIS`` over channels and incidences (a TIS of 0
        compared absolutely: a table of nothing)."""
        worst = 0.0
        for c, t in self.tis.items():
            t = np.asarray(t, dtype=float)
            scale = np.where(np.abs(t) > 1e-12, np.abs(t), 1.0)  # no division by a zero TIS
            worst = max(worst, float(np.max(np.abs(self.integral[c] - t) / scale)))
        return worst

    def text(self) -> str:
        """Two lines: the file and grid, then TIS against the table's integral."""
        n_aoi, n_az, n_rad = self.grid.shape
        tis = {c: np.round(v, 4).tolist() for c, v in self.tis.items()}
        return (f"wrote {self.path}: {n_aoi}x{n_az}x{n_rad} (AOI x ScatterAzimuth x "
                f"ScatterRadial, {self.grid.symmetry})\n  TIS {tis}; the table's own integral "
                f"within {100 * self.relative_error:.2g} % of it at every AOI")

    def __str__(self) -> str:
        return self.text()


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
