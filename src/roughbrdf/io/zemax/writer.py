"""Writing a Zemax tabular BSDF: a table as text (:func:`write_table`), and a measurement
onto a grid (:func:`plan`, :func:`write`, :class:`ZemaxWriteReport`).

A measurement read from a ``.bsdf`` goes back onto its own grid by node index (exact); one
whose samples form a complete grid is written exactly on it; anything else is binned to the
nearest node, mirrored into 0-180 deg (``PlaneSymmetrical``), averaged and filled, which
:func:`write` refuses unless ``resample=True`` and then reports (the rule of
:mod:`roughbrdf.io.merl`). :func:`header_field` tells other formats' writers what a Zemax header
keyword holds. The format and its conventions are described in :mod:`roughbrdf.io.zemax`.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import ArgumentError
from ...geometry import common_to_specular
from ...measurement import Measurement
from ...output import staged
from ...quantity import Quantity
from .._common import (
    LAYOUT,
    describe_keys,
    header_not_written,
    prepare_target,
    warn_not_written,
)
from .format import (
    COUNTED,
    GRID_TOL,
    HORIZON_EPS,
    SYMMETRIES,
    ZemaxGrid,
    ZemaxTable,
    grid_from_radians,
    normalize_symmetry,
    table_integral,
)
from .reader import kept_nodes

__all__ = ["write", "write_table", "plan", "default_measurement_grid", "header_field",
           "ZemaxWriteReport", "WRITES"]

#: written by :func:`write` and ``to_zemax`` in ``#`` comment lines
WRITES = ("sample", "instrument", "date")


# --------------------------------------------------------------------------------------------
# writing the text
# --------------------------------------------------------------------------------------------
def _num(v: float) -> str:
    """The shortest text that reads back as exactly ``v`` (``10.0`` -> ``10``)."""
    s = repr(float(v))
    return s[:-2] if s.endswith(".0") else s


def _angle_text(values: tuple[float, ...]) -> str:
    return "\t".join(_num(v) for v in values)


def write_table(path: str | os.PathLike, grid: ZemaxGrid, values: Any, tis: Any, *,
                comments: Any = (), source: str = "Measured", overwrite: bool = False) -> Path:
    """Write a tabular BSDF atomically (a temporary file renamed over ``path``).

    Parameters
    ----------
    grid : ZemaxGrid
    values : array_like, shape ``grid.shape``
        BRDF (sr⁻¹), finite.
    tis : array_like, shape ``(rotations, incidences)``
    comments : sequence of str
        Written first, each as a ``#`` line.
    source : str
        The ``Source`` keyword (the format knows ``Measured``).
    overwrite : bool
        Replace an existing file (default: :class:`FileExistsError`).

    Numbers are written in their shortest exact form, tab separated: reading the file back
    gives the same floats.
    """
    v = np.asarray(values, dtype=float)
    t = np.asarray(tis, dtype=float)
    if v.shape != grid.shape or t.shape != grid.shape[:2]:
        raise ValueError(f"values must have shape {grid.shape} and tis {grid.shape[:2]}, got "
                         f"{v.shape} and {t.shape}")
    if not (np.isfinite(v).all() and np.isfinite(t).all()):
        raise ValueError("a .bsdf holds finite numbers only (no NaN or inf in values or tis)")
    head = [f"# {c}".rstrip() for c in comments]
    head += [f"Source\t{source}", f"Symmetry\t{grid.symmetry}", "SpectralContent\tMonochrome",
             "ScatterType\tBRDF"]
    for key, name in COUNTED.items():
        vals = getattr(grid, name)
        head += [f"{key}\t{len(vals)}", _angle_text(vals)]
    head += ["", "Monochrome", "DataBegin"]
    with staged(path, overwrite=overwrite) as fh:
        fh.write("\n".join(head) + "\n")
        for i in range(grid.shape[0]):
            for j in range(grid.shape[1]):
                fh.write(f"TIS\t{_num(t[i, j])}\n")
                fh.write("\n".join("\t".join(map(_num, row)) for row in v[i, j]) + "\n")
        fh.write("DataEnd\n")
    return Path(path)


# --------------------------------------------------------------------------------------------
# write: a Measurement onto a grid
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ZemaxWriteReport:
    """What writing a measurement as a tabular BSDF did to its samples.

    Attributes
    ----------
    path : str
        The file (written, or refused).
    shape : (int, int, int, int)
        The grid: rotations, incidences, azimuths, radials.
    symmetry : str
    n_samples : int
        Samples in the measurement.
    by_index : bool
        Samples were placed by their ``original["zemax_index"]`` (read from a .bsdf): none
        moved.
    n_binned : int
        Samples off the grid's nodes, moved to the nearest node.
    n_folded : int
        Samples with azimuth beyond 180 deg mirrored into 0-180 (``PlaneSymmetrical``).
    n_averaged, n_shared_cells : int
        Samples with different values sharing a node, and those nodes (each holds the mean).
    n_duplicates : int
        Samples repeating another sample's node and value (written once; no change).
    n_filled : int
        Nodes above the horizon without any sample: written as 0 (the format has no "no
        value").
    n_below_horizon_cells : int
        Nodes below the horizon: written as 0, never read back as samples.
    nonfinite, negative : int
        Values that cannot be written (NaN, inf: dropped) and negative values (kept).
    tis_source : str
        Where the TIS lines come from: the source file, or the table's own integral.
    n_read_back : int
        Samples :func:`read` gives back from the file.
    converted : str or None
        The quantity the values were converted from (``brdf_cos``: divided by cos theta_r).
    """

    path: str
    shape: tuple[int, int, int, int]
    symmetry: str
    n_samples: int
    by_index: bool
    n_binned: int = 0
    n_folded: int = 0
    n_averaged: int = 0
    n_shared_cells: int = 0
    n_duplicates: int = 0
    n_filled: int = 0
    n_below_horizon_cells: int = 0
    nonfinite: int = 0
    negative: int = 0
    tis_source: str = ""
    n_read_back: int = 0
    converted: str | None = None

    @property
    def changes_samples(self) -> bool:
        """Whether the file holds other samples than the measurement (moved, mirrored,
        averaged, dropped, or nodes filled with 0)."""
        return bool(self.n_binned or self.n_folded or self.n_averaged or self.n_filled or
                    self.nonfinite)

    def summary(self) -> str:
        """One line: the counts that change the samples."""
        d = "x".join(map(str, self.shape))
        parts = [f"{self.n_binned} off the grid's nodes (binned: moved to the nearest)",
                 f"{self.n_folded} mirrored into azimuth 0-180 deg ({self.symmetry})",
                 f"{self.n_averaged} sharing {self.n_shared_cells} nodes (averaged)",
                 f"{self.nonfinite} non-finite values (dropped)",
                 f"{self.n_filled} nodes above the horizon without a sample (written as 0)"]
        return (f"the Zemax grid {d} (rotations x incidences x azimuths x radials): of "
                f"{self.n_samples} samples, " + ", ".join(parts) +
                f"; reading the file back gives {self.n_read_back} samples")

    def text(self) -> str:
        """Several lines: every count and why (what the CLI prints)."""
        d = "x".join(map(str, self.shape))
        lines = [f"Zemax tabular BSDF {d} ({self.symmetry}): {self.n_samples} samples written, "
                 f"{self.n_read_back} read back"]
        if self.by_index:
            lines.append("  placed by their node index (read from a .bsdf): none moved")
        lines += [f"  binned:   {self.n_binned} samples off the nodes, moved to the nearest node",
                  f"  mirrored: {self.n_folded} samples at azimuth > 180 deg folded into 0-180",
                  f"  averaged: {self.n_averaged} samples with different values share "
                  f"{self.n_shared_cells} nodes; each holds their mean ({self.n_duplicates} "
                  "exact duplicates written once)",
                  f"  dropped:  {self.nonfinite} non-finite values; {self.negative} negative "
                  "values kept as they are",
                  f"  filled:   {self.n_filled} nodes above the horizon had no sample: 0 written",
                  f"  horizon:  {self.n_below_horizon_cells} nodes below the horizon: 0 written",
                  f"  TIS:      {self.tis_source}"]
        if self.converted:
            lines.append(f"  values converted from {self.converted} to BRDF (divided by cos "
                         "theta_r)")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.text()


def _brdf_column(m: Measurement, channel: Any) -> np.ndarray:
    """The one channel to write, as BRDF (sr⁻¹)."""
    if not Quantity.parse(m.quantity).absolute:
        raise ValueError("a tabular BSDF holds absolute BRDF (sr^-1); a 'relative' measurement "
                         "cannot be written as .bsdf")
    if m.polarization is not None and np.isfinite(m.polarization).any():
        raise ValueError("a tabular BSDF holds no polarization; select one polarization "
                         "(Measurement.with_polarization) and drop it")
    if channel is None:
        if m.n_channels != 1:
            raise ArgumentError("channel", f"a .bsdf holds one channel (Monochrome); this "
                                f"measurement has {m.n_channels} ({m.channels}): name one "
                                "(a label or index)", fix=m.channels[0])
        channel = 0
    j = m.channel_index(channel)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray(m.to_brdf()[:, j], dtype=float)


def _by_index(m: Measurement) -> tuple[ZemaxGrid, np.ndarray, np.ndarray] | None:
    """Grid (restricted to the blocks present), node index and TIS of a measurement read from
    a .bsdf whose samples are still where their index says; None otherwise."""
    meta, orig = m.meta, m.original
    if meta.get("format") != "zemax" or "zemax_grid" not in meta or "zemax_index" not in orig:
        return None
    try:
        full = ZemaxGrid.from_meta(meta["zemax_grid"])
        tis = np.asarray(meta["zemax_tis"], dtype=float).reshape(full.shape[:2])
    except (KeyError, TypeError, ValueError):
        return None
    idx = np.asarray(orig["zemax_index"], dtype=np.int64)
    if idx.size == 0 or idx.min() < 0 or idx.max() >= int(np.prod(full.shape)):
        return None
    ir, ia, iz, ik = np.unravel_index(idx, full.shape)
    ti, tr, ph, _ = full.directions()
    at = (ia, iz, ik)
    dphi = np.angle(np.exp(1j * (ph[at] - m.phi)))
    # the samples must still be at their nodes' directions (1e-9 rad: the reader's own values)
    if not (np.allclose(ti[at], m.theta_i, atol=1e-9, rtol=0) and
            np.allclose(np.minimum(tr[at], 0.5 * math.pi), m.theta_r, atol=1e-9, rtol=0) and
            np.all((np.abs(dphi) <= 1e-9) | (m.theta_r <= 1e-9))):
        return None
    rots, aois = np.unique(ir), np.unique(ia)
    grid = ZemaxGrid(tuple(np.asarray(full.aoi_deg)[aois]), full.azimuth_deg, full.radial_deg,
                     tuple(np.asarray(full.rotation_deg)[rots]), full.symmetry)
    new = np.ravel_multi_index((np.searchsorted(rots, ir), np.searchsorted(aois, ia), iz, ik),
                               grid.shape)
    return grid, new, tis[np.ix_(rots, aois)]


def _nearest(nodes: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Index of the node nearest to each ``x`` (nodes sorted)."""
    k = np.clip(np.searchsorted(nodes, x), 1, max(nodes.size - 1, 1))
    if nodes.size == 1:
        return np.zeros(x.shape, dtype=np.int64)
    left = nodes[k - 1]
    return np.where(np.abs(x - left) <= np.abs(nodes[k] - x), k - 1, k).astype(np.int64)


def _specular_coords(m: Measurement, symmetry: str) -> tuple[np.ndarray, ...]:
    """(incidence, azimuth, radial) of every sample in degrees, the azimuth folded into
    0-180 for PlaneSymmetrical, and which samples were folded."""
    rad, az = common_to_specular(m.theta_i, m.theta_r, m.phi)
    aoi, az, rad = np.degrees(m.theta_i), np.degrees(az), np.degrees(rad)
    pole = rad <= GRID_TOL
    az = np.where(pole | (np.abs(az - 360.0) <= GRID_TOL), 0.0, az)
    folded = np.zeros(az.shape, dtype=bool)
    if symmetry == "PlaneSymmetrical":
        folded = az > 180.0 + GRID_TOL
        az = np.where(folded, 360.0 - az, np.minimum(az, 180.0))
    return aoi, az, rad, folded, pole


def _by_geometry(m: Measurement, grid: ZemaxGrid) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Node index of every sample (nearest node), whether it sat on that node, and whether its
    azimuth was mirrored."""
    aoi, az, rad, folded, pole = _specular_coords(m, grid.symmetry)
    nodes = [np.asarray(v) for v in (grid.aoi_deg, grid.azimuth_deg, grid.radial_deg)]
    ia, iz, ik = (_nearest(n, x) for n, x in zip(nodes, (aoi, az, rad), strict=True))
    on = ((np.abs(nodes[0][ia] - aoi) <= GRID_TOL) & (np.abs(nodes[2][ik] - rad) <= GRID_TOL) &
          ((np.abs(nodes[1][iz] - az) <= GRID_TOL) | pole))
    ir = np.zeros(aoi.shape, dtype=np.int64)
    if "sample_rotation" in m.original and grid.shape[0] > 1:
        ir = _nearest(np.asarray(grid.rotation_deg),
                      np.asarray(m.original["sample_rotation"], dtype=float))
    return np.ravel_multi_index((ir, ia, iz, ik), grid.shape), on, folded


def _infer_grid(m: Measurement, symmetry: str) -> ZemaxGrid | None:
    """The grid the samples lie on, if they are on one (their distinct angles)."""
    aoi, az, rad, _, pole = _specular_coords(m, symmetry)
    # angles equal to GRID_TOL (1e-6 deg) are one node: rounding of a file's angles through
    # radians and back (a .bsdf written to CSV/ASTM and read again) is ~1e-13 deg
    axes = [np.unique(np.round(x, 6)) for x in (aoi, az[~pole] if (~pole).any() else
                                                np.zeros(1), rad)]
    try:
        return ZemaxGrid(tuple(axes[0]), tuple(axes[1]), tuple(axes[2]), symmetry=symmetry)
    except ValueError:
        return None


def default_measurement_grid(m: Measurement, symmetry: str = "PlaneSymmetrical") -> ZemaxGrid:
    """The grid ``resample=True`` uses without angles: the measurement's incidences, azimuths
    every 10 deg, radial angles every 2.5 deg up to the horizon of the largest incidence."""
    aoi = np.unique(np.round(np.degrees(m.theta_i), 6))
    top = 180.0 if normalize_symmetry(symmetry) == "PlaneSymmetrical" else 360.0
    rmax = 90.0 + float(aoi.max(initial=0.0))
    return ZemaxGrid(tuple(aoi), tuple(np.arange(0.0, top + 1e-9, 10.0)),
                     tuple(np.append(np.arange(0.0, rmax, 2.5), rmax)), symmetry=symmetry)


def _fill(grid: ZemaxGrid, index: np.ndarray, values: np.ndarray
          ) -> tuple[np.ndarray, dict[str, int]]:
    """The table: the mean of the samples at each node; an empty node repeating the direction
    of a node with samples (radial 0 at every azimuth, azimuth 360) takes that node's value;
    0 at the other empty nodes and below the horizon."""
    n = int(np.prod(grid.shape))
    n_az, n_rad = grid.shape[2:]
    ok = np.isfinite(values)
    sums = np.bincount(index[ok], weights=values[ok], minlength=n)
    cnt = np.bincount(index[ok], minlength=n)
    table = np.where(cnt > 0, sums / np.maximum(cnt, 1), 0.0).reshape(-1, n_az * n_rad)
    cnt = cnt.reshape(-1, n_az * n_rad)
    rep = grid.representatives()
    empty = (cnt == 0) & (cnt[:, rep] > 0)
    table = np.where(empty, table[:, rep], table).reshape(grid.shape)
    # samples sharing a node with different values are averaged; identical copies are
    # duplicates (written once: no change)
    mean = table.ravel()[index]
    shared = ok & (cnt.ravel()[index] > 1)
    changed = np.unique(index[shared & (values != mean)])
    averaged = shared & np.isin(index, changed)
    _, _, _, cz = grid.directions()
    above = np.broadcast_to(cz >= -HORIZON_EPS, grid.shape)
    own = np.broadcast_to((rep == np.arange(rep.size)).reshape(n_az, n_rad), grid.shape)
    covered = (cnt > 0) | (cnt[:, rep] > 0)
    filled = above & own & ~covered.reshape(grid.shape)
    counts = {"n_averaged": int(averaged.sum()), "n_shared_cells": int(changed.size),
              "n_duplicates": int((shared & ~averaged).sum()
                                  - np.unique(index[shared & ~averaged]).size),
              "n_filled": int(filled.sum()), "n_below_horizon_cells": int((~above).sum()),
              "nonfinite": int((~ok).sum()), "negative": int((values[ok] < 0).sum())}
    return np.where(above, table, 0.0), counts


def plan(measurement: Measurement, path: str = "", *, channel: Any = None,
         angles_of_incidence: Any = None, azimuth: Any = None, radial: Any = None,
         symmetry: str | None = None
         ) -> tuple[ZemaxGrid, np.ndarray, np.ndarray, ZemaxWriteReport]:
    """The grid, table, TIS and report of writing ``measurement`` as a .bsdf; writes nothing.

    The grid is, in order: the angles given (radians; the others default as in
    :func:`default_measurement_grid`); the source file's grid for a measurement read from a
    .bsdf (placed by node index: exact); the grid the samples lie on, when every node above
    the horizon holds a sample; else the default grid (which ``resample=True`` needs).
    """
    m = measurement
    values = _brdf_column(m, channel)
    sym = normalize_symmetry(symmetry or "PlaneSymmetrical")
    if sym is None:
        raise ArgumentError("symmetry", f"must be one of {', '.join(SYMMETRIES)}",
                            value=symmetry)
    given = any(v is not None for v in (angles_of_incidence, azimuth, radial))
    placed = None if given or symmetry is not None else _by_index(m)
    if placed is not None:
        grid, index, tis = placed
        on, folded = np.ones(index.size, bool), np.zeros(index.size, bool)
    else:
        grid = _grid_for(m, sym, given, angles_of_incidence, azimuth, radial)
        index, on, folded = _by_geometry(m, grid)
        tis = None
    table, counts = _fill(grid, index, values)
    changed = bool((~on).sum() or folded.sum() or counts["n_averaged"] or counts["n_filled"]
                   or counts["nonfinite"])
    if tis is None or changed:
        tis, source = table_integral(table, grid), ("the table's own integral (trapezoid on "
                                                    "the grid)")
    else:
        source = "the source file's TIS lines"
    keep, _, _ = kept_nodes(ZemaxTable(grid, table, tis), np.arange(grid.shape[0]))
    report = ZemaxWriteReport(
        path=str(path), shape=grid.shape, symmetry=grid.symmetry, n_samples=m.n_samples,
        by_index=placed is not None, n_binned=int((~on).sum()), n_folded=int(folded.sum()),
        tis_source=source, n_read_back=int(keep.size),
        converted=m.quantity.value if m.quantity.cosine_weighted else None, **counts)
    return grid, table, np.asarray(tis, dtype=float), report


def _grid_for(m: Measurement, symmetry: str, given: bool, angles_of_incidence: Any,
              azimuth: Any, radial: Any) -> ZemaxGrid:
    """The grid of a measurement not placed by index: the angles given, else the grid its
    samples lie on (when complete), else the default grid."""
    default = default_measurement_grid(m, symmetry)
    if given:
        return grid_from_radians(
            np.radians(default.aoi_deg) if angles_of_incidence is None else angles_of_incidence,
            np.radians(default.azimuth_deg) if azimuth is None else azimuth,
            np.radians(default.radial_deg) if radial is None else radial, symmetry=symmetry)
    inferred = _infer_grid(m, symmetry)
    if inferred is not None and m.n_samples:
        index, on, folded = _by_geometry(m, inferred)
        _, counts = _fill(inferred, index, np.zeros(m.n_samples))  # coverage only
        if on.all() and not folded.any() and counts["n_filled"] == 0:
            return inferred
    return default


def write(measurement: Measurement, path: str | os.PathLike, *, overwrite: bool = False,
          resample: bool = False, channel: Any = None, angles_of_incidence: Any = None,
          azimuth: Any = None, radial: Any = None, symmetry: str | None = None
          ) -> ZemaxWriteReport:
    """Write a measurement as a Zemax tabular BSDF (one channel, Monochrome).

    A measurement read from a .bsdf goes back onto its own grid by node index (its TIS lines
    and comments too): exact. A measurement whose samples form a complete grid in Zemax's
    specular-centred angles is written exactly on it, with TIS the table's own integral
    (:func:`table_integral`). Anything else would bin, mirror, average or fill samples: it is
    refused unless ``resample=True``, and the report says what was done.

    Parameters
    ----------
    measurement : Measurement
        Absolute BRDF (``brdf``, or ``brdf_cos``/``bridf``, converted), no polarization.
    path : str or path-like
        Never the file the measurement was read from.
    overwrite : bool
        Replace an existing file (default: :class:`FileExistsError`).
    resample : bool
        Write even when the grid changes the samples.
    channel : str or int, optional
        The channel to write (required when there are several).
    angles_of_incidence, azimuth, radial : array_like, optional
        The grid (radians); see :func:`plan` for the defaults.
    symmetry : {"PlaneSymmetrical", "Asymmetrical", "Asymmetrical4D"}, optional

    Returns
    -------
    ZemaxWriteReport

    Examples
    --------
    >>> import roughbrdf as rb, tempfile, pathlib
    >>> from roughbrdf.export.zemax import to_zemax
    >>> from roughbrdf.io.zemax import read_table
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = to_zemax(rb.model("lambertian", rho=0.5), d / "a.bsdf")
    >>> m = rb.read(d / "a.bsdf")
    >>> report = write(m, d / "b.bsdf")          # back onto its own grid: exact
    >>> report.by_index, report.changes_samples
    (True, False)
    >>> bool((read_table(d / "b.bsdf").values == read_table(d / "a.bsdf").values).all())
    True
    >>> write(m.subset(m.theta_r < 1.0), d / "c.bsdf")
    Traceback (most recent call last):
    ...
    roughbrdf.errors.ArgumentError: writing ... would change the samples - ...

    Raises
    ------
    roughbrdf.errors.ArgumentError
        ``path`` is the measurement's own input; the grid would change the samples and
        ``resample`` is false; several channels and no ``channel``.
    FileExistsError
        ``path`` exists and ``overwrite`` is false.
    """
    target = prepare_target(measurement, path, overwrite)
    grid, table, tis, report = plan(measurement, str(target), channel=channel,
                                    angles_of_incidence=angles_of_incidence, azimuth=azimuth,
                                    radial=radial, symmetry=symmetry)
    if report.changes_samples and not resample:
        raise ArgumentError("resample", f"writing {target} would change the samples - "
                            f"{report.summary()}", fix=True)
    m = measurement
    label = m.channels[0 if channel is None else m.channel_index(channel)]
    comments = _comments(m, report, label)
    write_table(target, grid, table, tis, comments=comments,
                source=str(m.meta.get("header", {}).get("Source", "Measured"))
                if m.meta.get("format") == "zemax" else "Measured", overwrite=overwrite)
    items = []
    lost = header_not_written(m.meta, "zemax", WRITES)
    if lost:
        items.append(describe_keys(lost, str(m.meta.get("format"))))
    if m.uncertainty is not None:
        items.append("the uncertainties (sigma)")
    warn_not_written(target, "Zemax tabular BSDF", items)
    return report


def _comments(m: Measurement, report: ZemaxWriteReport, label: str) -> list[str]:
    """The ``#`` lines: the source file's comments, else the provenance the format can hold
    (and the channel written, since the format has one unnamed channel)."""
    if m.meta.get("format") == "zemax" and report.by_index:
        return [str(c) for c in m.meta.get("comments", [])]
    lines = ["written by roughbrdf (roughbrdf.io.zemax)", f"channel: {label}"]
    for key in WRITES:
        if m.meta.get(key):
            lines.append(f"{key}: {m.meta[key]}")
    if m.meta.get("file"):
        lines.append(f"from: {Path(str(m.meta['file'])).name}")
    if report.changes_samples:
        lines.append("resampled onto this grid: " + report.summary())
    return [re.sub(r"[\r\n]+", " ", s) for s in lines]


def header_field(key: str) -> str | None:
    """What a Zemax header keyword holds, for a writer of another format: :data:`LAYOUT` for the
    table's layout (``Symmetry``, ``SpectralContent``, ``ScatterType``: every writer writes its
    own), None for the rest (``Source``), which another format has no place for."""
    return LAYOUT if key in ("Symmetry", "SpectralContent", "ScatterType") else None
