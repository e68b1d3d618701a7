"""MERL BRDF database binary files (Matusik, Pfister, Brand & McMillan 2003; ``.binary``).

Layout (little-endian): three ``int32`` dimensions ``n_th, n_td, n_pd = 90, 90, 180``, then
``3 n_th n_td n_pd`` ``float64`` values: all red, then all green, then all blue, each a C-order
array ``[i_th, i_td, i_pd]``. A stored value times the channel scale is the BRDF (sr⁻¹):
``1/1500`` (R), ``1.15/1500`` (G), ``1.66/1500`` (B). Negative values (``-1``) mark cells
without a measurement.

Indexing (Rusinkiewicz half/difference angles, as in MERL's ``BRDFRead.cpp``):

* ``i_th = floor(sqrt(theta_h / (pi/2)) * 90)`` - non-linear, dense near the specular peak;
* ``i_td = floor(theta_d / (pi/2) * 90)`` - linear on [0, pi/2);
* ``i_pd = floor(phi_d / pi * 180)`` with ``phi_d`` folded into [0, pi) by
  ``phi_d -> phi_d + pi`` when negative (reciprocity: that swaps the two directions).

Conventions verified against this library's :func:`roughbrdf.geometry.to_rusinkiewicz` /
:func:`~roughbrdf.geometry.from_rusinkiewicz`: MERL builds ``h = (w_in + w_out)/|...|``, then
``d = R_y(-theta_h) R_z(-phi_h) w_in`` with right-handed (Rodrigues) rotations and
``phi_d = atan2(d_y, d_x)``; ``to_rusinkiewicz`` does the same with ``w_in = w_i`` and the same
rotation matrices (``_rot_z``, ``_rot_y`` are right-handed), so the angles agree, ``phi_d``
included (tests: the index of every cell's geometry, recomputed through ``to_rusinkiewicz``, is
the cell's own index; ``phi_d`` and ``phi_d + pi`` give the same common-frame geometry up to
swapping ``theta_i`` and ``theta_r``).

Each cell is read at its lower corner by default (``cell="corner"``: ``theta_h = (i/90)^2 pi/2``,
``theta_d = j pi/180``, ``phi_d = k pi/180``: the angles that MERL's lookup maps to exactly that
cell), or at its centre (``cell="center"``). Cells whose directions fall below the horizon
(possible for large ``theta_d``) are not BRDF geometries and are always removed, and cells marked
invalid (any channel negative) are removed by default (``invalid="drop"``); both are counted in
``meta["merl_below_horizon"]`` and ``meta["merl_invalid"]`` - never dropped silently.
``stride`` subsamples the grid (e.g. ``stride=4`` or ``(2, 2, 4)``).

Writing a measurement onto the fixed grid (:func:`write`) can change its samples: samples off
the cells' corner angles are moved to them (binned), samples sharing a cell are averaged,
negative and non-finite values cannot be stored (MERL's ``-1`` means "no value"), and a cell
whose corner angles fall below the horizon is never read back. :func:`write` therefore refuses
such a measurement unless ``resample=True``, and then returns a :class:`MerlWriteReport` that
counts each of these, and how many samples ``read`` gives back.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ArgumentError
from ..geometry import from_rusinkiewicz, to_rusinkiewicz
from ..measurement import Measurement
from ..quantity import Quantity
from ._common import (
    FormatError,
    check_fixed_units,
    describe_keys,
    header_not_written,
    prepare_target,
    warn_not_written,
    write_bytes,
)

__all__ = ["read", "write", "write_table", "read_table", "table_from_model", "cell_angles",
           "cell_index", "plan", "MerlWriteReport", "EXTENSIONS", "DIMS", "SCALES",
           "CHANNELS"]

EXTENSIONS = (".binary", ".merl")
DIMS = (90, 90, 180)
SCALES = (1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0)
CHANNELS = ("R", "G", "B")
HALF_PI = 0.5 * math.pi
#: index slack (fraction of a cell): a cell's own corner angles, recomputed in floating point
#: (arccos loses ~1e-8 rad near the pole), map back to that cell
_EPS = 1e-4
#: a sample is on the grid when its Rusinkiewicz angles are within this of a cell's (radians)
GRID_TOL = 1e-6
_WAVELENGTH = re.compile(r"^\s*(\d+(?:\.\d+)?)\s*nm\s*$", re.IGNORECASE)


# --------------------------------------------------------------------------------------------
# index <-> angles
# --------------------------------------------------------------------------------------------
def cell_angles(i_th, i_td, i_pd, dims: tuple[int, int, int] = DIMS, cell: str = "corner"
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rusinkiewicz angles ``(theta_h, theta_d, phi_d)`` of MERL cells (radians)."""
    if cell not in ("corner", "center"):
        raise ValueError(f"cell must be 'corner' or 'center', got {cell!r}")
    off = 0.5 if cell == "center" else 0.0
    n_th, n_td, n_pd = dims
    th = ((np.asarray(i_th, float) + off) / n_th) ** 2 * HALF_PI
    td = (np.asarray(i_td, float) + off) / n_td * HALF_PI
    pd = (np.asarray(i_pd, float) + off) / n_pd * math.pi
    return th, td, pd


def cell_index(theta_h, theta_d, phi_d, dims: tuple[int, int, int] = DIMS
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """MERL cell indices of Rusinkiewicz angles (the lookup of ``BRDFRead.cpp``, with a slack of
    1e-4 cell so that angles recomputed in floating point land in the cell they came from).

    ``phi_d`` is folded into [0, pi) (``phi_d + pi`` is the same geometry with the directions
    swapped) and is periodic: ``phi_d`` just below pi is cell 0, as ``-0.0`` is.
    """
    n_th, n_td, n_pd = dims
    th = np.clip(np.asarray(theta_h, float), 0.0, None)
    i = np.floor(np.sqrt(th / HALF_PI) * n_th + _EPS)
    j = np.floor(np.asarray(theta_d, float) / HALF_PI * n_td + _EPS)
    k = np.floor(np.mod(np.asarray(phi_d, float), math.pi) / math.pi * n_pd + _EPS)
    return (np.clip(i, 0, n_th - 1).astype(np.int64), np.clip(j, 0, n_td - 1).astype(np.int64),
            np.mod(k, n_pd).astype(np.int64))


@lru_cache(maxsize=8)
def _grid(dims: tuple[int, int, int], stride: tuple[int, int, int], cell: str):
    """Flat cell indices of the (sub)grid and their common-frame angles (cached, read-only)."""
    ii, jj, kk = np.meshgrid(np.arange(0, dims[0], stride[0]), np.arange(0, dims[1], stride[1]),
                             np.arange(0, dims[2], stride[2]), indexing="ij")
    flat = np.ravel_multi_index((ii.ravel(), jj.ravel(), kk.ravel()), dims)
    th, td, pd = cell_angles(ii.ravel(), jj.ravel(), kk.ravel(), dims, cell)
    ti, tr, ph = from_rusinkiewicz(th, td, pd)
    for a in (flat, th, td, pd, ti, tr, ph):
        a.setflags(write=False)
    return flat, th, td, pd, ti, tr, ph


# --------------------------------------------------------------------------------------------
# raw table
# --------------------------------------------------------------------------------------------
def read_table(path: str | os.PathLike, *, scaled: bool = True) -> np.ndarray:
    """The whole table, shape ``(3, n_th, n_td, n_pd)``: BRDF (``scaled``) or the stored numbers.

    Raises :class:`FormatError` for a file shorter or longer than its dimensions say.
    """
    path = Path(path)
    size = path.stat().st_size
    if size < 12:
        raise FormatError(f"truncated MERL file: {size} bytes, fewer than the 12-byte header "
                          "(three int32 dimensions)", path)
    with open(path, "rb") as fh:
        dims = tuple(int(d) for d in np.frombuffer(fh.read(12), dtype="<i4"))
        if any(d <= 0 or d > 100000 for d in dims):
            raise FormatError(f"not a MERL binary: header dimensions {dims} (expected "
                              f"{DIMS})", path)
        n = dims[0] * dims[1] * dims[2]
        expected = 12 + 3 * n * 8
        if size != expected:
            kind = "truncated" if size < expected else "over-long"
            raise FormatError(f"{kind} MERL file: dimensions {dims} need {expected} bytes "
                              f"(12 + 3 x {n} float64), the file has {size} "
                              f"({(size - 12) / 8:.0f} values of {3 * n})", path)
        raw = np.fromfile(fh, dtype="<f8", count=3 * n)
    table = raw.reshape(3, *dims)
    if scaled:
        table = table * np.asarray(SCALES)[:, None, None, None]
    return table


def write_table(path: str | os.PathLike, table: np.ndarray, *, overwrite: bool = False) -> None:
    """Write a BRDF table ``(3, n_th, n_td, n_pd)`` (sr⁻¹; NaN or negative = invalid -> -1).

    Atomic (a temporary file renamed over ``path``); an existing ``path`` is refused
    (:class:`FileExistsError`) unless ``overwrite``.
    """
    t = np.asarray(table, dtype=float)
    if t.ndim != 4 or t.shape[0] != 3:
        raise ValueError(f"table must have shape (3, n_th, n_td, n_pd), got {t.shape}")
    target = Path(path)
    if target.exists() and not overwrite:
        raise FileExistsError(f"{target} exists; not overwriting it (pass overwrite=True)")
    raw = t / np.asarray(SCALES)[:, None, None, None]
    raw = np.where(np.isfinite(raw) & (raw >= 0), raw, -1.0)
    write_bytes(target, (np.asarray(t.shape[1:], dtype="<i4").tobytes(),
                         np.ascontiguousarray(raw, dtype="<f8").tobytes()), overwrite=overwrite)


def table_from_model(model, dims: tuple[int, int, int] = DIMS, cell: str = "corner"
                     ) -> np.ndarray:
    """BRDF table ``(3, *dims)`` of a model (or three models, R, G, B) at the cell angles.

    Cells below the horizon or at exactly grazing incidence/reflection (where models that
    divide by a cosine are undefined) are NaN (written as -1).
    """
    models = list(model) if isinstance(model, list | tuple) else [model] * 3
    if len(models) != 3:
        raise ValueError("give one model or three (R, G, B)")
    flat, th, td, pd, ti, tr, ph = _grid(tuple(dims), (1, 1, 1), cell)
    ok = np.isfinite(ti) & (ti < HALF_PI) & (tr < HALF_PI)
    out = np.full((3, int(np.prod(dims))), np.nan)
    for c, mdl in enumerate(models):
        out[c, flat[ok]] = np.asarray(mdl.brdf(ti[ok], tr[ok], ph[ok]), dtype=float)
    return out.reshape(3, *dims)


# --------------------------------------------------------------------------------------------
# Measurement
# --------------------------------------------------------------------------------------------
def _stride(stride: int | tuple[int, int, int]) -> tuple[int, int, int]:
    s = (stride,) * 3 if isinstance(stride, int | np.integer) else tuple(int(x) for x in stride)
    if len(s) != 3 or any(x < 1 for x in s):
        raise ValueError(f"stride must be a positive int or three of them, got {stride!r}")
    return s  # type: ignore[return-value]


def read(path: str | os.PathLike, *, stride: int | tuple[int, int, int] = 1,
         invalid: str = "drop", cell: str = "corner", quantity: str | None = None,
         angles: str | None = None, **options: Any) -> Measurement:
    """Read a MERL binary into a :class:`~roughbrdf.measurement.Measurement` (channels R, G, B).

    Parameters
    ----------
    quantity, angles : str, optional
        Accepted for symmetry with the text readers: MERL holds BRDF at angles in radians, so
        only ``"brdf"`` and ``"rad"`` agree with the file (anything else: :class:`FormatError`).
    stride : int or (int, int, int)
        Keep every ``stride``-th cell along (theta_h, theta_d, phi_d).
    invalid : {"drop", "nan", "keep"}
        Cells with a negative (``-1``) value in any channel: removed (default), kept with NaN
        in the negative channels, or kept as stored. The count is ``meta["merl_invalid"]``.
    cell : {"corner", "center"}
        Angles given to each cell (module docstring).
    """
    if options:
        raise TypeError(f"merl.read got unknown options {sorted(options)}")
    if invalid not in ("drop", "nan", "keep"):
        raise ValueError(f"invalid must be 'drop', 'nan' or 'keep', got {invalid!r}")
    path = Path(path)
    check_fixed_units("MERL", angles, quantity, path)
    table = read_table(path, scaled=True)
    dims = tuple(table.shape[1:])
    st = _stride(stride)
    flat, th, td, pd, ti, tr, ph = _grid(dims, st, cell)
    vals = table.reshape(3, -1)[:, flat].T
    above = np.isfinite(ti)
    bad = (vals < 0).any(axis=1)
    n_grid = int(flat.size)
    below_with_data = int((~above & ~bad).sum())
    keep = above.copy()
    n_invalid = int((bad & above).sum())
    if invalid == "drop":
        keep &= ~bad
    vals = vals[keep]
    if invalid == "nan":
        vals = np.where(vals < 0, np.nan, vals)
    meta: dict[str, Any] = {
        "file": str(path),
        "file_abs": str(path.resolve()),
        "format": "merl",
        "sample": path.stem,
        "instrument": "MERL BRDF database (Matusik et al. 2003) layout",
        "date": None,
        "merl_dims": dims,
        "merl_stride": st,
        "merl_cell": cell,
        "merl_cells_read": n_grid,
        "merl_below_horizon": int((~above).sum()),
        "merl_below_horizon_with_data": below_with_data,
        "merl_invalid": n_invalid,
        "merl_invalid_policy": invalid,
        "channel_scales": SCALES,
        "original_units": "rad (Rusinkiewicz theta_h, theta_d, phi_d); merl_index flat cell",
    }
    if dims != DIMS:
        meta["merl_nonstandard_dims"] = True
    original = {"theta_h": np.array(th[keep]), "theta_d": np.array(td[keep]),
                "phi_d": np.array(pd[keep]), "merl_index": np.array(flat[keep])}
    return Measurement(theta_i=np.clip(ti[keep], 0.0, HALF_PI),
                       theta_r=np.clip(tr[keep], 0.0, HALF_PI), phi=np.array(ph[keep]),
                       values=vals, channels=list(CHANNELS), quantity=Quantity.BRDF,
                       original=original, meta=meta)


@dataclass(frozen=True)
class MerlWriteReport:
    """What writing a measurement onto MERL's fixed grid did to its samples.

    Attributes
    ----------
    path : str
        The file (written, or to be written).
    dims : (int, int, int)
        The grid.
    n_samples : int
        Samples in the measurement.
    by_index : bool
        Samples were placed by their MERL cell index (a measurement read from a MERL file of
        the same grid), so none was moved.
    n_binned : int
        Samples off the grid: moved to the corner angles of the cell they fall in.
    n_averaged, n_shared_cells : int
        Samples that share a cell with others, and the cells they share: each cell holds the
        mean of its samples' valid values.
    negative, nonfinite : dict of str -> int
        Per channel of the measurement: values that cannot be stored (MERL's ``-1`` means "no
        value") and are dropped.
    n_invalid_markers : int
        Samples of a MERL source marked invalid there, written as invalid (-1) again (no
        change).
    n_off_grid : int
        Samples in cells whose corner angles fall below the horizon: a MERL reader skips them.
    n_lost_invalid : int
        Other samples not read back: their cell lacks a valid value in some channel (a cell is
        read only when R, G and B all hold one).
    n_read_back : int
        Samples (cells) that :func:`read` with its defaults gives back.
    channel_map : dict of str -> str
        ``{"R": label, "G": label, "B": label}``: which channel became which.
    converted : str or None
        The quantity the values were converted from (``brdf_cos``: divided by cos theta_r).
    """

    path: str
    dims: tuple[int, int, int]
    n_samples: int
    by_index: bool
    n_binned: int
    n_averaged: int
    n_shared_cells: int
    negative: dict[str, int] = field(default_factory=dict)
    nonfinite: dict[str, int] = field(default_factory=dict)
    n_invalid_markers: int = 0
    n_off_grid: int = 0
    n_lost_invalid: int = 0
    n_read_back: int = 0
    channel_map: dict[str, str] = field(default_factory=dict)
    converted: str | None = None

    @property
    def n_dropped_values(self) -> int:
        """Values (channel by channel) that could not be stored."""
        return sum(self.negative.values()) + sum(self.nonfinite.values())

    @property
    def changes_samples(self) -> bool:
        """Whether the file holds other samples than the measurement (binned, averaged, values
        dropped, or samples that are not read back)."""
        return bool(self.n_binned or self.n_averaged or self.n_dropped_values or
                    self.n_off_grid or (self.n_lost_invalid and not self.by_index))

    def summary(self) -> str:
        """One line: the counts that change the samples."""
        d = "x".join(map(str, self.dims))
        parts = [f"{self.n_binned} off the grid's cell angles (binned: moved to them)",
                 f"{self.n_averaged} sharing {self.n_shared_cells} cells (averaged)",
                 f"{sum(self.negative.values())} negative and {sum(self.nonfinite.values())} "
                 "non-finite values (dropped: MERL's -1 means no value)",
                 f"{self.n_off_grid} in cells below the horizon (never read back)"]
        return (f"MERL's fixed {d} grid: of {self.n_samples} samples, " + ", ".join(parts) +
                f"; reading the file back gives {self.n_read_back} samples")

    def text(self) -> str:
        """Several lines: every count, why, and the channel mapping (what the CLI prints)."""
        d = "x".join(map(str, self.dims))
        lines = [f"MERL grid {d}: {self.n_samples} samples written, {self.n_read_back} read "
                 "back (rb.read with its defaults)"]
        if self.by_index:
            lines.append("  placed by their MERL cell index (read from a MERL file of this "
                         "grid): none moved")
        lines.append(f"  binned:   {self.n_binned} samples off the cells' corner angles, moved "
                     "to the corner angles of the cell they fall in")
        lines.append(f"  averaged: {self.n_averaged} samples share {self.n_shared_cells} cells; "
                     "each cell holds the mean of their valid values")
        per = ", ".join(f"{c} {self.negative.get(c, 0)} negative / {self.nonfinite.get(c, 0)} "
                        "non-finite" for c in dict.fromkeys([*self.negative, *self.nonfinite]))
        lines.append(f"  dropped:  {self.n_dropped_values} values that MERL cannot store "
                     f"(-1 means no value){': ' + per if per else ''}")
        lines.append(f"  not read back: {self.n_off_grid} samples in cells whose corner angles "
                     f"are below the horizon; {self.n_lost_invalid} in cells without a value "
                     "in every channel (a cell is read only when R, G and B hold one)")
        if self.n_invalid_markers:
            lines.append(f"  {self.n_invalid_markers} samples marked invalid in the source MERL "
                         "file are written as invalid (-1) again")
        chans = ", ".join(f"{k}={v}" for k, v in self.channel_map.items())
        conv = (f"; values converted from {self.converted} to BRDF (divided by cos theta_r)"
                if self.converted else "")
        lines.append(f"  channels: {chans}{conv}")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.text()


def _channel_order(m: Measurement) -> list[int]:
    """Columns of ``m`` written as R, G, B: one channel thrice; R/G/B labels by name;
    wavelength labels (``630nm``) longest first; otherwise in order."""
    if m.n_channels == 1:
        return [0, 0, 0]
    if m.n_channels != 3:
        raise ValueError(f"MERL files hold 3 channels (R, G, B); this measurement has "
                         f"{m.n_channels} ({m.channels}); select one or three")
    upper = [c.upper() for c in m.channels]
    if sorted(upper) == ["B", "G", "R"]:
        return [upper.index(c) for c in "RGB"]
    found = [_WAVELENGTH.match(c) for c in m.channels]
    waves = [float(f.group(1)) for f in found if f]
    if len(waves) == 3 and len(set(waves)) == 3:
        return sorted(range(3), key=lambda j: -waves[j])
    return [0, 1, 2]


def _placement(m: Measurement, dims: tuple[int, int, int]
               ) -> tuple[np.ndarray, np.ndarray, bool]:
    """Flat cell index of every sample, whether it sits at its cell's corner angles, and
    whether the cell index came from the source MERL file."""
    n = int(np.prod(dims))
    if "merl_index" in m.original and tuple(m.meta.get("merl_dims", ())) == dims:
        flat = np.asarray(m.original["merl_index"], dtype=np.int64)
        if flat.size and (flat.min() < 0 or flat.max() >= n):
            raise ValueError(f"original['merl_index'] holds cells outside the {dims} grid")
        return flat, np.ones(flat.size, dtype=bool), True
    th, td, pd = to_rusinkiewicz(m.theta_i, m.theta_r, m.phi)
    idx = cell_index(th, td, pd, dims)
    cth, ctd, cpd = cell_angles(*idx, dims)
    dpd = np.abs(np.mod(pd, math.pi) - cpd)
    dpd = np.minimum(dpd, math.pi - dpd)
    on_grid = (np.abs(th - cth) <= GRID_TOL) & (np.abs(td - ctd) <= GRID_TOL) & (
        (dpd <= GRID_TOL) | (cth <= GRID_TOL) | (ctd <= GRID_TOL))  # phi_d moot at a pole
    return np.ravel_multi_index(idx, dims), on_grid, False


def plan(measurement: Measurement, dims: tuple[int, int, int] = DIMS, path: str = ""
         ) -> tuple[np.ndarray, MerlWriteReport]:
    """The BRDF table ``(3, *dims)`` a measurement becomes on the MERL grid, and the report of
    what that does to its samples (see :class:`MerlWriteReport`); writes nothing."""
    m = measurement
    if not Quantity.parse(m.quantity).absolute:
        raise ValueError("MERL files hold absolute BRDF; a 'relative' measurement cannot be "
                         "written as MERL")
    if m.polarization is not None and np.isfinite(m.polarization).any():
        raise ValueError("MERL files cannot hold per-sample polarization; select one "
                         "polarization (Measurement.with_polarization) and drop it")
    order = _channel_order(m)
    d0, d1, d2 = (int(d) for d in dims)
    dims = (d0, d1, d2)
    n = d0 * d1 * d2
    flat, on_grid, by_index = _placement(m, dims)
    with np.errstate(invalid="ignore", divide="ignore"):
        vals = m.to_brdf()[:, order]
    valid = np.isfinite(vals) & (vals >= 0)
    table = np.full((3, n), np.nan)
    for c in range(3):
        ok = valid[:, c]
        s = np.bincount(flat[ok], weights=vals[ok, c], minlength=n)
        k = np.bincount(flat[ok], minlength=n)
        with np.errstate(invalid="ignore", divide="ignore"):
            table[c] = np.where(k > 0, s / np.maximum(k, 1), np.nan)
    counts = np.bincount(flat, minlength=n)
    ci, cj, ck = np.unravel_index(flat, dims)
    ti_cell, _, _ = from_rusinkiewicz(*cell_angles(ci, cj, ck, dims))
    above = np.isfinite(ti_cell)
    cell_ok = np.isfinite(table).all(axis=0)
    read_back = np.zeros(n, dtype=bool)
    read_back[flat[above]] = True
    read_back &= cell_ok
    col = {m.channels[j]: vals[:, order.index(j)] for j in sorted(set(order))}
    bad_neg = {c: int((np.isfinite(v) & (v < 0)).sum()) for c, v in col.items()}
    bad_nan = {c: int((~np.isfinite(v)).sum()) for c, v in col.items()}
    lost_invalid = int((above & ~cell_ok[flat]).sum())
    report = MerlWriteReport(
        path=str(path), dims=dims, n_samples=m.n_samples, by_index=by_index,
        n_binned=int((~on_grid).sum()), n_averaged=int(counts[counts > 1].sum()),
        n_shared_cells=int((counts > 1).sum()),
        negative={} if by_index else bad_neg, nonfinite={} if by_index else bad_nan,
        n_invalid_markers=int((~valid).any(axis=1).sum()) if by_index else 0,
        n_off_grid=int((~above).sum()), n_lost_invalid=lost_invalid,
        n_read_back=int(read_back.sum()),
        channel_map={c: m.channels[j] for c, j in zip("RGB", order, strict=True)},
        converted=m.quantity.value if m.quantity.cosine_weighted else None)
    return table.reshape(3, *dims), report


def write(measurement: Measurement, path: str | os.PathLike, *,
          dims: tuple[int, int, int] = DIMS, resample: bool = False,
          overwrite: bool = False) -> MerlWriteReport:
    """Write a measurement as a MERL binary.

    Samples are placed in the cell of their Rusinkiewicz angles (``original["merl_index"]`` is
    used as is when the measurement came from a MERL file of the same dimensions); samples that
    share a cell are averaged; cells without a sample get ``-1`` (invalid). Three channels are
    written as R, G, B (wavelength labels longest first: ``630nm`` is R); a single channel is
    written to all three. The values must be absolute BRDF (``brdf``, or ``brdf_cos``/``bridf``,
    converted).

    Parameters
    ----------
    measurement : Measurement
    path : str or path-like
        Never the file the measurement was read from.
    dims : (int, int, int)
        The grid (MERL's is 90 x 90 x 180).
    resample : bool
        Write even when the grid changes the samples (binning, averaging, values that cannot
        be stored, cells below the horizon); without it such a measurement is refused with an
        :class:`~roughbrdf.errors.ArgumentError` that says what would change.
    overwrite : bool
        Replace an existing file (default: :class:`FileExistsError`).

    Returns
    -------
    MerlWriteReport
        What the grid did to the samples (``print(report)`` lists every count and why).
    """
    target = prepare_target(measurement, path, overwrite)
    table, report = plan(measurement, dims, str(target))
    if report.changes_samples and not resample:
        raise ArgumentError("resample", f"writing {target} would change the samples - "
                            f"{report.summary()}", fix=True)
    m = measurement
    items = []
    lost = header_not_written(m.meta, "merl", ())
    if lost:
        items.append(describe_keys(lost, str(m.meta.get("format"))))
    if m.uncertainty is not None:
        items.append("the uncertainties (sigma)")
    if m.n_channels == 3 and [c.upper() for c in m.channels] != list(CHANNELS) and \
            sorted(c.upper() for c in m.channels) != ["B", "G", "R"]:
        items.append("the channel labels (written as " +
                     ", ".join(f"{k}={v}" for k, v in report.channel_map.items()) + ")")
    write_table(target, table, overwrite=overwrite)
    warn_not_written(target, "MERL", items)
    return report
