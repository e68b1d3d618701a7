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
"""

from __future__ import annotations

import math
import os
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from ..geometry import from_rusinkiewicz, to_rusinkiewicz
from ..measurement import Measurement
from ..quantity import Quantity
from ._common import FormatError

__all__ = ["read", "write", "write_table", "read_table", "table_from_model", "cell_angles",
           "cell_index", "EXTENSIONS", "DIMS", "SCALES", "CHANNELS"]

EXTENSIONS = (".binary", ".merl")
DIMS = (90, 90, 180)
SCALES = (1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0)
CHANNELS = ("R", "G", "B")
HALF_PI = 0.5 * math.pi
#: index slack (fraction of a cell): a cell's own corner angles, recomputed in floating point
#: (arccos loses ~1e-8 rad near the pole), map back to that cell
_EPS = 1e-4


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
    1e-4 cell so that angles recomputed in floating point land in the cell they came from)."""
    n_th, n_td, n_pd = dims
    th = np.clip(np.asarray(theta_h, float), 0.0, None)
    i = np.floor(np.sqrt(th / HALF_PI) * n_th + _EPS)
    j = np.floor(np.asarray(theta_d, float) / HALF_PI * n_td + _EPS)
    pd = np.asarray(phi_d, float)
    pd = np.where(pd < 0.0, pd + math.pi, pd)
    k = np.floor(pd / math.pi * n_pd + _EPS)
    return (np.clip(i, 0, n_th - 1).astype(np.int64), np.clip(j, 0, n_td - 1).astype(np.int64),
            np.clip(k, 0, n_pd - 1).astype(np.int64))


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


def write_table(path: str | os.PathLike, table: np.ndarray) -> None:
    """Write a BRDF table ``(3, n_th, n_td, n_pd)`` (sr⁻¹; NaN or negative = invalid -> -1)."""
    t = np.asarray(table, dtype=float)
    if t.ndim != 4 or t.shape[0] != 3:
        raise ValueError(f"table must have shape (3, n_th, n_td, n_pd), got {t.shape}")
    raw = t / np.asarray(SCALES)[:, None, None, None]
    raw = np.where(np.isfinite(raw) & (raw >= 0), raw, -1.0)
    with open(path, "wb") as fh:
        fh.write(np.asarray(t.shape[1:], dtype="<i4").tobytes())
        fh.write(np.ascontiguousarray(raw, dtype="<f8").tobytes())


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
         invalid: str = "drop", cell: str = "corner", **options: Any) -> Measurement:
    """Read a MERL binary into a :class:`~roughbrdf.measurement.Measurement` (channels R, G, B).

    Parameters
    ----------
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


def write(measurement: Measurement, path: str | os.PathLike, *,
          dims: tuple[int, int, int] = DIMS) -> None:
    """Write a measurement as a MERL binary.

    Samples are placed in the cell of their Rusinkiewicz angles (``original["merl_index"]`` is
    used as is when the measurement came from a MERL file of the same dimensions); samples that
    share a cell are averaged; cells without a sample get ``-1`` (invalid). Three channels are
    written as R, G, B; a single channel is written to all three. The values must be absolute
    BRDF (``brdf``, or ``brdf_cos``/``bridf``, converted).
    """
    m = measurement
    if not Quantity.parse(m.quantity).absolute:
        raise ValueError("MERL files hold absolute BRDF; a 'relative' measurement cannot be "
                         "written as MERL")
    if m.n_channels not in (1, 3):
        raise ValueError(f"MERL files hold 3 channels (R, G, B); this measurement has "
                         f"{m.n_channels} ({m.channels}); select one or three")
    vals = m.to_brdf()
    if vals.shape[1] == 1:
        vals = np.repeat(vals, 3, axis=1)
    d0, d1, d2 = (int(d) for d in dims)
    dims = (d0, d1, d2)
    n = int(np.prod(dims))
    if "merl_index" in m.original and tuple(m.meta.get("merl_dims", ())) == dims:
        flat = np.asarray(m.original["merl_index"], dtype=np.int64)
    else:
        th, td, pd = to_rusinkiewicz(m.theta_i, m.theta_r, m.phi)
        flat = np.ravel_multi_index(cell_index(th, td, pd, dims), dims)
    table = np.full((3, n), np.nan)
    counts = np.bincount(flat, minlength=n)
    has = counts > 0
    for c in range(3):
        ok = np.isfinite(vals[:, c]) & (vals[:, c] >= 0)
        s = np.bincount(flat[ok], weights=vals[ok, c], minlength=n)
        k = np.bincount(flat[ok], minlength=n)
        with np.errstate(invalid="ignore", divide="ignore"):
            table[c] = np.where(has & (k > 0), s / np.maximum(k, 1), np.nan)
    write_table(path, table.reshape(3, *dims))
