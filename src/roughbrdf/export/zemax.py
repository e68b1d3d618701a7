"""Models and fits as Zemax OpticStudio tabular BSDF files (``.bsdf``).

:func:`to_zemax` samples a model - or each channel of a fit - on a grid about the specular
direction (the format and its conventions: :mod:`roughbrdf.io.zemax`) and writes one file per
channel, with each incidence's ``TIS`` the model's directional-hemispherical reflectance
(:func:`roughbrdf.albedo`, accurate to about 1e-5).

The default grid:

* ``AngleOfIncidence`` 0, 10, ..., 80 deg;
* ``ScatterRadial`` from 0 to ``90 + max(AngleOfIncidence)`` (so that the whole hemisphere is
  covered on the side toward the normal), graded: steps of ``w/8`` inside the specular lobe
  (``w``, its half width at half maximum, measured on the model out of the plane of incidence
  at every incidence; the narrowest is used), growing by 10 % a node up to 2 deg;
* ``ScatterAzimuth`` every 10 deg (5 deg when the lobe is narrower than 2 deg) over 0-180
  (``PlaneSymmetrical``) or 0-360 (``Asymmetrical``).

That grid is level 0: the table is refined (each level divides every spacing by sqrt 2)
until its own integral (:func:`roughbrdf.io.zemax.table_integral`, the trapezoid rule on the
file's nodes) and a second rule on the same nodes
(:func:`roughbrdf.export.grids.cell_rule`) are within 0.25 % of TIS at every incidence, which
keeps the promised 0.5 % (:data:`roughbrdf.export.grids.INTEGRAL_RTOL`) for other readers'
rules too (:func:`roughbrdf.export.grids.refine`; at most 2e6 values, a warning beyond). What
limits the accuracy is the grid: a lobe narrower than the radial spacing (the radial angles are
shared by all incidences, so the spacing follows the narrowest lobe), the horizon, which cuts
the lobe between nodes at grazing incidence (the largest errors are at 80 deg), and the
azimuth step near the horizon. A ``radial`` or ``azimuth`` given is used as given, with one
:class:`~roughbrdf.export.grids.TableAccuracyWarning` naming the shortfall when it misses
0.5 %.

Directions below the horizon (radial angles past it) hold 0; directions exactly at the horizon
hold the model's value there (0 where the model has no finite value there, counted).
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ArgumentError
from ..integrate import albedo
from ..io.zemax import (
    HORIZON_EPS,
    SYMMETRIES,
    ZemaxGrid,
    grid_from_radians,
    normalize_symmetry,
    table_integral,
    write_table,
)
from ..models.base import Model
from ..output import OverwriteRefused
from .grids import (
    Refined,
    cell_rule,
    grid_note,
    lobe_widths,
    refine,
    relative_errors,
)

__all__ = ["to_zemax", "default_grid", "model_table", "lobe_width", "ZemaxExport",
           "ZemaxFile", "DEFAULT_INCIDENCES_DEG"]

#: AngleOfIncidence of the default grid (degrees)
DEFAULT_INCIDENCES_DEG = tuple(float(a) for a in range(0, 81, 10))
#: the default radial spacing: at most this (degrees) ...
RADIAL_STEP_DEG = 2.0
#: ... growing by this fraction of the radial angle from the lobe's spacing ...
RADIAL_GROWTH = 0.1
#: ... which is the lobe's half width divided by this
NODES_PER_HALF_WIDTH = 8


def lobe_width(model: Model, aoi_deg: Any, *, polarization: Any = None) -> float | None:
    """Half width at half maximum (degrees) of the model's specular lobe: the narrowest, over
    the incidences ``aoi_deg`` (degrees), of
    :func:`roughbrdf.export.grids.lobe_widths` (the radial angle out of the plane of
    incidence at which the BRDF falls half way from its specular value to its lowest value
    within 60 deg). None when no incidence shows a lobe (Lambertian-like).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> lobe_width(rb.model("lambertian", rho=0.5), [0, 40]) is None
    True
    >>> w = lobe_width(rb.model("microfacet", distribution="trowbridge-reitz", alpha=0.05), [0])
    >>> 3.0 < w < 4.5
    True
    """
    widths = [w for w in lobe_widths(model.brdf, aoi_deg, polarization=polarization)
              if w is not None]
    return min(widths) if widths else None


def _graded_radial(width: float | None, rmax: float, scale: float = 1.0) -> np.ndarray:
    """Radial angles (degrees) from 0 to ``rmax``: spacing ``width/8`` in the lobe, growing by
    10 % a node, at most 2 deg (each times ``scale``, the refinement)."""
    hmax = RADIAL_STEP_DEG * scale
    hmin = hmax if width is None else min(hmax, scale * width / NODES_PER_HALF_WIDTH)
    nodes = [0.0]
    r = 0.0
    while r < rmax - 1e-9:
        r = min(r + min(max(RADIAL_GROWTH * scale * r, hmin), hmax), rmax)
        nodes.append(r)
    if len(nodes) > 2 and nodes[-1] - nodes[-2] < 0.25 * hmin:  # no sliver at the end
        nodes.pop(-2)
    return np.round(np.asarray(nodes), 9)


def default_grid(model: Model, *, angles_of_incidence: Any = None,
                 symmetry: str = "PlaneSymmetrical", polarization: Any = None,
                 level: int = 0) -> ZemaxGrid:
    """The grid :func:`to_zemax` uses for ``model`` (module docstring) at refinement
    ``level`` (each divides every spacing by sqrt 2); ``angles_of_incidence`` (radians)
    replaces the default incidences.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> g = default_grid(rb.model("lambertian", rho=0.5))
    >>> g.aoi_deg[-1], g.radial_deg[-1], len(g.azimuth_deg)
    (80.0, 170.0, 19)
    """
    sym = normalize_symmetry(str(symmetry))
    if sym is None:
        raise ArgumentError("symmetry", f"must be one of {', '.join(SYMMETRIES)}",
                            value=symmetry)
    aoi = (np.radians(DEFAULT_INCIDENCES_DEG) if angles_of_incidence is None
           else np.atleast_1d(np.asarray(angles_of_incidence, dtype=float)))
    checked = grid_from_radians(aoi, [0.0], [0.0], symmetry=sym)  # names a bad argument
    width = lobe_width(model, checked.aoi_deg, polarization=polarization)
    scale = 0.5 ** (0.5 * int(level))
    radial = _graded_radial(width, 90.0 + max(checked.aoi_deg), scale)
    step = scale * (5.0 if width is not None and width < 2.0 else 10.0)
    half = math.ceil(180.0 / step - 1e-9)  # steps over a half circle: the whole circle is
    # its mirror image, so that both symmetries give the same table and integral
    top, steps = (180.0, half) if sym == "PlaneSymmetrical" else (360.0, 2 * half)
    azimuth = np.round(np.linspace(0.0, top, steps + 1), 6)
    return ZemaxGrid(checked.aoi_deg, tuple(azimuth), tuple(radial), symmetry=sym)


def model_table(model: Model, grid: ZemaxGrid, *, polarization: Any = None
                ) -> tuple[np.ndarray, dict[str, int]]:
    """The model's BRDF (sr⁻¹) at every node of ``grid`` (shape ``grid.shape``; every
    rotation alike: the models are isotropic), and the counts of nodes below the horizon
    (written 0) and at the horizon without a finite model value (written 0).

    Raises ``ValueError`` naming the node (degrees) where the model has no finite value above
    the horizon.
    """
    ti, tr, ph, cz = grid.directions()
    at_or_above = cz >= -HORIZON_EPS
    values = np.zeros(ti.shape)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        f = np.asarray(model.brdf(ti[at_or_above], np.minimum(tr[at_or_above], 0.5 * math.pi),
                                  ph[at_or_above], polarization=polarization), dtype=float)
    values[at_or_above] = f
    horizon = at_or_above & (cz <= HORIZON_EPS)
    bad = ~np.isfinite(values)
    if (bad & ~horizon).any():
        i, j, k = (int(x[0]) for x in np.nonzero(bad & ~horizon))
        raise ValueError(f"the model has no finite BRDF at AngleOfIncidence "
                         f"{grid.aoi_deg[i]:g} deg, ScatterAzimuth {grid.azimuth_deg[j]:g} deg, "
                         f"ScatterRadial {grid.radial_deg[k]:g} deg (theta_r = "
                         f"{math.degrees(tr[i, j, k]):.6g} deg): {values[i, j, k]!r}")
    values = np.where(bad, 0.0, values)
    counts = {"n_below_horizon": int((~at_or_above).sum()),
              "n_horizon_nonfinite": int((bad & horizon).sum())}
    return np.broadcast_to(values, grid.shape).copy(), counts


@dataclass(frozen=True)
class ZemaxFile:
    """One written file.

    Attributes
    ----------
    path : pathlib.Path
    channel : str or None
        The fit's channel (None for a model).
    model : str
        The model written (its ``repr``).
    grid : ZemaxGrid
    tis : numpy.ndarray
        TIS at each incidence: ``rb.albedo(model, AngleOfIncidence)``.
    integral : numpy.ndarray
        The table's own integral at each incidence (:func:`~roughbrdf.io.zemax.table_integral`).
    n_below_horizon, n_horizon_nonfinite : int
        Nodes per rotation written as 0: below the horizon; at the horizon where the model
        has no finite value.
    """

    path: Path
    channel: str | None
    model: str
    grid: ZemaxGrid
    tis: np.ndarray = field(repr=False)
    integral: np.ndarray = field(repr=False)
    n_below_horizon: int = 0
    n_horizon_nonfinite: int = 0

    @property
    def integral_error(self) -> float:
        """Largest ``|integral - TIS|`` over the incidences (absolute)."""
        return float(np.max(np.abs(self.integral - self.tis)))

    @property
    def relative_error(self) -> float:
        """Largest ``|integral - TIS| / TIS`` over the incidences
        (:func:`roughbrdf.export.grids.relative_errors`)."""
        return float(np.max(relative_errors(self.integral, self.tis)))

    def text(self) -> str:
        """Two lines: the file and grid, then TIS against the table's integral."""
        d = "x".join(map(str, self.grid.shape[1:]))
        ch = f" (channel {self.channel})" if self.channel is not None else ""
        return (f"wrote {self.path}{ch}: {d} (incidences x azimuths x radials, "
                f"{self.grid.symmetry}), {self.n_below_horizon} nodes below the horizon "
                f"(0)\n  TIS = rb.albedo {np.round(self.tis, 4).tolist()}; the table's own "
                f"integral within {100 * self.relative_error:.2g} % of it at every incidence")


@dataclass(frozen=True)
class ZemaxExport:
    """What :func:`to_zemax` wrote: one :class:`ZemaxFile` per channel."""

    files: list[ZemaxFile]

    def __iter__(self):
        return iter(self.files)

    def __len__(self) -> int:
        return len(self.files)

    def __getitem__(self, k: int) -> ZemaxFile:
        return self.files[k]

    @property
    def paths(self) -> list[Path]:
        """The files written, in order."""
        return [f.path for f in self.files]

    def text(self) -> str:
        """What the CLI prints."""
        return "\n".join(f.text() for f in self.files)

    def __str__(self) -> str:
        return self.text()


def _models(obj: Any, channel: Any) -> list[tuple[str | None, Model]]:
    """(channel label, model) pairs to write: one for a model, one per fitted channel."""
    if isinstance(obj, Model):
        if channel is not None:
            raise ArgumentError("channel", "applies to a fit; a model is one file", value=channel)
        return [(None, obj)]
    if isinstance(obj, Mapping) and obj and all(isinstance(m, Model) for m in obj.values()):
        # {channel: model}, e.g. roughbrdf.fitting.results.fit_json.fitted_models(fit folder)
        if channel is None:
            return [(str(k), m) for k, m in obj.items()]
        key = channel if channel in obj else list(obj)[int(channel)] \
            if str(channel).lstrip("-").isdigit() else None
        if key is None:
            raise ArgumentError("channel", f"not a channel of this fit ({', '.join(obj)})",
                                value=channel)
        return [(str(key), obj[key])]
    chans = getattr(obj, "channels", None)
    if not chans or not all(isinstance(getattr(c, "model", None), Model) for c in chans):
        raise TypeError(f"to_zemax takes a roughbrdf Model (rb.model(...)), a FitResult "
                        f"(rb.fit(...)) or a mapping channel -> Model, got "
                        f"{type(obj).__name__}")
    if channel is not None:
        c = obj[channel]
        return [(str(c.channel), c.model)]
    return [(str(c.channel), c.model) for c in chans]


def _targets(out: str | os.PathLike, labels: list[str | None], single: bool) -> list[Path]:
    """The file of each channel: ``out`` (``.bsdf`` added without a suffix) for one model or
    a chosen channel, else ``<stem>_<channel>.bsdf`` beside it."""
    base = Path(out)
    if base.suffix == "":
        base = base.with_suffix(".bsdf")
    if single:
        return [base]
    paths = []
    for i, label in enumerate(labels):
        safe = re.sub(r"[^A-Za-z0-9.+-]+", "_", str(label)).strip("._") or f"channel{i}"
        paths.append(base.with_name(f"{base.stem}_{safe}{base.suffix}"))
    if len(set(paths)) != len(paths):
        raise ValueError(f"the channel labels {labels} give the same file names; export the "
                         "channels one by one (channel=)")
    return paths


def _check_targets(paths: list[Path], overwrite: bool) -> None:
    """Before writing anything: no folder in the way, no existing file unless ``overwrite``."""
    for p in paths:
        if p.is_dir():
            raise IsADirectoryError(f"{p} is a folder, not a file; give a file name")
    existing = [p for p in paths if p.exists()]
    if existing and not overwrite:
        if len(existing) == 1:
            raise OverwriteRefused(existing[0], single=True)
        raise OverwriteRefused(existing[0].parent, foreign=[p.name for p in existing],
                               overwrite=False)


def to_zemax(model_or_fit: Any, out: str | os.PathLike, *, angles_of_incidence: Any = None,
             radial: Any = None, azimuth: Any = None, symmetry: str = "PlaneSymmetrical",
             channel: Any = None, polarization: Any = None, overwrite: bool = False,
             allow_energy_gain: bool = False) -> ZemaxExport:
    """Write a model, or each channel of a fit, as a Zemax tabular BSDF.

    Parameters
    ----------
    model_or_fit : Model, FitResult or mapping
        A fit (or ``{channel: model}``, e.g.
        :func:`roughbrdf.fitting.results.fit_json.fitted_models` of a saved fit) writes one
        file per channel, ``<stem>_<channel>.bsdf`` beside ``out``.
    out : str or path-like
        The file (``.bsdf`` added when it has no suffix).
    angles_of_incidence, radial, azimuth : array_like, optional
        The grid, in radians (written in degrees); defaults in the module docstring.
    symmetry : {"PlaneSymmetrical", "Asymmetrical", "Asymmetrical4D"}
        ``PlaneSymmetrical`` (azimuths 0-180) suits the isotropic models.
    channel : str or int, optional
        One channel of a fit, written to ``out`` itself.
    polarization : optional
        Incident polarization (:meth:`Model.brdf`); default unpolarized.
    overwrite : bool
        Replace existing files (default: refuse, before writing any).
    allow_energy_gain : bool
        Write a model that reflects more than it receives (albedo above ``1 + 1e-3`` at an
        incidence of 0, 5, ... 85, 89 deg), recorded in a header comment; by default refused
        with an :class:`~roughbrdf.errors.ArgumentError` naming the albedo and the incidence
        (:func:`~roughbrdf.fitting.results.plausibility.refuse_energy_gain`).

    Returns
    -------
    ZemaxExport
        The files, their TIS and their tables' own integrals.

    Examples
    --------
    >>> import roughbrdf as rb, tempfile, pathlib
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "paint.bsdf"
    >>> res = to_zemax(rb.model("lambertian", rho=0.5), out)
    >>> res[0].path.name, [round(float(t), 6) for t in res[0].tis[:2]]
    ('paint.bsdf', [0.5, 0.5])
    >>> res[0].integral_error < 1e-3
    True
    >>> m = rb.read(out)          # read back: the model on the grid
    >>> bool(abs(m.values[:, 0] - 0.5 / 3.141592653589793).max() < 1e-12)
    True
    """
    from ..fitting.results.plausibility import refuse_energy_gain

    pairs = _models(model_or_fit, channel)
    targets = _targets(out, [c for c, _ in pairs], single=len(pairs) == 1 and (
        isinstance(model_or_fit, Model) or channel is not None))
    _check_targets(targets, overwrite)
    notes = [refuse_energy_gain({label: mdl}, allow_energy_gain) for label, mdl in pairs]
    chosen = [_choose(mdl, angles_of_incidence, radial, azimuth, symmetry, polarization,
                      str(path)) for (_, mdl), path in zip(pairs, targets, strict=True)]
    if len(targets) == 1:  # one file: written atomically on its own
        return ZemaxExport([_write_one(pairs[0][1], pairs[0][0], chosen[0], targets[0],
                                       overwrite, notes[0])])
    return ZemaxExport(_write_set(pairs, chosen, targets, overwrite, notes))


def _write_set(pairs: list[tuple[str | None, Model]],
               chosen: list[tuple[Refined, np.ndarray]], targets: list[Path], overwrite: bool,
               notes: list[list[str]]) -> list[ZemaxFile]:
    """The channels' files as one set (:class:`roughbrdf.output.ResultFolder`, added to the
    folder's set): a kill or an error leaves all the old files or all the new ones.

    Each table is written to a scratch folder first (``write_table`` writes to a path), then
    staged into the set; the user named the files, so with ``overwrite`` an existing file of
    those names that no set lists is replaced (``adopt``) unless the manifest says it changed.
    """
    import tempfile

    from ..output import ResultFolder

    files = []
    with tempfile.TemporaryDirectory(prefix="roughbrdf-zemax-") as scratch, \
            ResultFolder(targets[0].parent, overwrite=overwrite, extend=True,
                         adopt=[p.name for p in targets]) as out:
        out.check([p.name for p in targets])  # before the (slow) tables
        for (label, mdl), table, path, note in zip(pairs, chosen, targets, notes, strict=True):
            tmp = Path(scratch) / path.name
            done = _write_one(mdl, label, table, tmp, True, note)
            out.add(path.name, tmp.read_bytes())
            tmp.unlink()
            files.append(replace(done, path=path))
    return files


def _choose(model: Model, angles_of_incidence: Any, radial: Any, azimuth: Any, symmetry: str,
            polarization: Any, what: str) -> tuple[Refined, np.ndarray]:
    """The table of one model and its TIS: on the default grid refined until its own integral
    meets TIS (:func:`roughbrdf.export.grids.refine`), or on the angles given (``radial`` or
    ``azimuth``: the grid as given, the other part the default's first level; a warning when
    it misses). ``what`` names the file in a warning."""
    def build(level: int) -> ZemaxGrid:
        return default_grid(model, angles_of_incidence=angles_of_incidence, symmetry=symmetry,
                            polarization=polarization, level=level)

    base = build(0)
    user = None
    if radial is not None or azimuth is not None:
        user = grid_from_radians(np.radians(base.aoi_deg),
                                 np.radians(base.azimuth_deg) if azimuth is None else azimuth,
                                 np.radians(base.radial_deg) if radial is None else radial,
                                 symmetry=base.symmetry)
    if not model.grazing_incidence and max(base.aoi_deg) >= 90.0:
        raise ArgumentError("angles_of_incidence", f"{model.name} is not defined at grazing "
                            "incidence (theta_i = 90 deg); give angles below pi/2",
                            value=math.radians(max(base.aoi_deg)), unit="rad")
    tis = np.atleast_1d(np.asarray(albedo(model, np.radians(base.aoi_deg),
                                          polarization=polarization), dtype=float))

    def evaluate(grid: ZemaxGrid) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                          dict[str, int]]:
        values, counts = model_table(model, grid, polarization=polarization)
        a = np.radians(grid.azimuth_deg)
        v, cz = values[0], grid.directions()[3]
        if grid.symmetry != "PlaneSymmetrical" and a[-1] < a[0] + 2 * math.pi - 1e-9:
            # the circle is closed by the first azimuth's column (as table_integral does)
            a = np.append(a, a[0] + 2 * math.pi)
            v, cz = (np.concatenate([x, x[:, :1]], axis=1) for x in (v, cz))
        cells = cell_rule(v, np.radians(grid.radial_deg), a, cz,
                          factor=2.0 if grid.symmetry == "PlaneSymmetrical" else 1.0)
        return values, table_integral(values, grid)[0], cells, counts

    chosen = refine(lambda lv: base if lv == 0 else build(lv), evaluate, tis,
                    size=lambda g: int(np.prod(g.shape)), user_grid=user, what=what)
    return chosen, tis


def _write_one(model: Model, label: str | None, chosen: tuple[Refined, np.ndarray],
               path: Path, overwrite: bool, notes: list[str]) -> ZemaxFile:
    """Write one file (``notes``: more header comments)."""
    table, tis = chosen
    grid, values, integral = table.grid, table.values, table.integral
    comments = [f"roughbrdf export of {model!r}"]
    if label is not None:
        comments.append(f"channel: {label}")
    comments += [
        "BRDF in sr^-1 on a grid about the specular direction: ScatterRadial = angle from the "
        "specular direction, ScatterAzimuth = 0 toward the surface normal, counter-clockwise "
        "seen from above; AngleOfIncidence = theta_i = the specular angle",
        "TIS = the model's directional-hemispherical reflectance (roughbrdf.albedo); the "
        "table's own integral (trapezoid rule on this file's nodes) is within "
        f"{100 * float(np.max(table.errors)):.2g} % of it at every AngleOfIncidence",
        grid_note(table.level, "graded from the specular direction"),
        "directions below the horizon hold 0", *notes]
    if table.warning is not None:
        comments.append("warning: " + table.warning)
    tis_all = np.broadcast_to(tis, grid.shape[:2])
    write_table(path, grid, values, tis_all, comments=comments, overwrite=overwrite)
    return ZemaxFile(Path(path), label, repr(model), grid, tis, integral, **table.extra)
