"""The Zemax tabular BSDF's data model: its grid, its table, its integral (no file I/O).

:class:`ZemaxGrid` holds the four counted axes of a ``.bsdf`` (SampleRotation,
AngleOfIncidence, ScatterAzimuth, ScatterRadial, in degrees) and its Symmetry, and gives every
node's direction in the library's frame (through :func:`roughbrdf.geometry.specular_to_common`:
the specular frame, defined in :mod:`roughbrdf.geometry_frames`); :class:`ZemaxTable` is a
whole file (grid, values, TIS, header, comments); :func:`table_integral` is a table's own
directional-hemispherical reflectance (what TIS holds); :func:`grid_from_radians` builds a grid
from the Python API's radians; :func:`normalize_symmetry` reads a Symmetry keyword. The format
and its conventions are described in :mod:`roughbrdf.io.zemax`, which re-exports these names.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...errors import ArgumentError
from ...geometry import specular_to_common

__all__ = ["ZemaxGrid", "ZemaxTable", "table_integral", "grid_from_radians",
           "normalize_symmetry", "EXTENSIONS", "SYMMETRIES", "COUNTED", "HORIZON_EPS",
           "GRID_TOL"]

EXTENSIONS = (".bsdf",)
#: the Symmetry keyword's values (read case-insensitively; ``ASymmetrical4D`` also occurs)
SYMMETRIES = ("PlaneSymmetrical", "Asymmetrical", "Asymmetrical4D")
#: the counted header keywords, in the file's order, and their ZemaxGrid field
COUNTED = {"SampleRotation": "rotation_deg", "AngleOfIncidence": "aoi_deg",
           "ScatterAzimuth": "azimuth_deg", "ScatterRadial": "radial_deg"}
#: a direction is above the horizon when cos(theta_r) exceeds this; nodes within it of 0 are
#: at the horizon (theta_r = 90 deg exactly: rounding of the node's angles, not a direction
#: below the surface)
HORIZON_EPS = 1e-12
#: two angles of a grid (degrees) closer than this are the same node
GRID_TOL = 1e-6


# --------------------------------------------------------------------------------------------
# the grid
# --------------------------------------------------------------------------------------------
def normalize_symmetry(text: str) -> str | None:
    """The canonical Symmetry keyword, ``PlaneSymmetrical``, ``Asymmetrical`` or
    ``Asymmetrical4D``, of ``text`` in any capitalization (and surrounding blanks); None when
    ``text`` is none of them.

    Examples
    --------
    >>> normalize_symmetry("ASymmetrical4D"), normalize_symmetry("round")
    ('Asymmetrical4D', None)
    """
    for name in SYMMETRIES:
        if text.strip().lower() == name.lower():
            return name
    return None


def _check_axis(name: str, values: np.ndarray, low: float, high: float) -> str | None:
    """What is wrong with one axis of a grid (degrees), or None."""
    if values.size == 0:
        return f"{name} lists no angles"
    if not np.isfinite(values).all():
        return f"{name} has a non-finite angle"
    if values.min() < low - GRID_TOL or values.max() > high + GRID_TOL:
        return (f"{name} angles must lie in [{low:g}, {high:g}] deg, got "
                f"[{values.min():g}, {values.max():g}]")
    if values.size > 1 and not (np.diff(values) > 0).all():
        return f"{name} angles must increase strictly (each once), got {values.tolist()}"
    return None


@dataclass(frozen=True)
class ZemaxGrid:
    """The angles of a tabular BSDF, in **degrees** (the file's unit).

    Attributes
    ----------
    aoi_deg, azimuth_deg, radial_deg, rotation_deg : tuple of float
        AngleOfIncidence (= theta_i), ScatterAzimuth, ScatterRadial and SampleRotation.
    symmetry : str
        ``PlaneSymmetrical`` (azimuths in [0, 180]) or ``Asymmetrical``/``Asymmetrical4D``
        (azimuths in [0, 360]).

    Examples
    --------
    >>> g = ZemaxGrid((0, 30), (0, 90, 180), (0, 10, 20))
    >>> g.shape
    (1, 2, 3, 3)
    """

    aoi_deg: tuple[float, ...]
    azimuth_deg: tuple[float, ...]
    radial_deg: tuple[float, ...]
    rotation_deg: tuple[float, ...] = (0.0,)
    symmetry: str = "PlaneSymmetrical"

    def __post_init__(self) -> None:
        for name in ("aoi_deg", "azimuth_deg", "radial_deg", "rotation_deg"):
            object.__setattr__(self, name, tuple(float(v) for v in np.ravel(getattr(self,
                                                                                 name))))
        sym = normalize_symmetry(str(self.symmetry))
        if sym is None:
            raise ArgumentError("symmetry", f"must be one of {', '.join(SYMMETRIES)}",
                                value=self.symmetry)
        object.__setattr__(self, "symmetry", sym)
        problem = self.problem()
        if problem:
            raise ValueError(f"not a Zemax grid: {problem}")

    def problem(self) -> str | None:
        """What makes these angles unusable as a grid (None when they are fine)."""
        top = 180.0 if self.symmetry == "PlaneSymmetrical" else 360.0
        for name, vals, low, high in (
                ("AngleOfIncidence", self.aoi_deg, 0.0, 90.0),
                ("ScatterAzimuth", self.azimuth_deg, 0.0, top),
                ("ScatterRadial", self.radial_deg, 0.0, 180.0),
                ("SampleRotation", self.rotation_deg, -360.0, 360.0)):
            p = _check_axis(name, np.asarray(vals, float), low, high)
            if p:
                return p + (f" ({self.symmetry})" if name == "ScatterAzimuth" else "")
        return None

    @property
    def shape(self) -> tuple[int, int, int, int]:
        """``(rotations, incidences, azimuths, radials)``: the shape of the table."""
        return (len(self.rotation_deg), len(self.aoi_deg), len(self.azimuth_deg),
                len(self.radial_deg))

    def directions(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(theta_i, theta_r, phi, cos_theta_r)`` of every node of one rotation, each of
        shape ``(incidences, azimuths, radials)`` (radians; theta_r > pi/2 below the horizon)."""
        t = np.radians(np.asarray(self.aoi_deg))[:, None, None]
        a = np.radians(np.asarray(self.azimuth_deg))[None, :, None]
        r = np.radians(np.asarray(self.radial_deg))[None, None, :]
        theta_r, phi, cz = specular_to_common(t, r, a)
        shape = np.broadcast_shapes(t.shape, a.shape, r.shape)
        return (np.broadcast_to(t, shape).copy(), np.broadcast_to(theta_r, shape).copy(),
                np.broadcast_to(phi, shape).copy(), np.broadcast_to(cz, shape).copy())

    def representatives(self) -> np.ndarray:
        """For each ``(azimuth, radial)`` node of a block, the flat index of the first node
        with the same direction: radial 0 is the specular direction at every azimuth, and
        azimuth 360 is azimuth 0 (when both are listed)."""
        n_az, n_rad = len(self.azimuth_deg), len(self.radial_deg)
        rep = np.arange(n_az * n_rad).reshape(n_az, n_rad)
        az = np.asarray(self.azimuth_deg)
        zero = np.flatnonzero(np.abs(az) <= GRID_TOL)
        full = np.flatnonzero(np.abs(az - 360.0) <= GRID_TOL)
        if zero.size and full.size:
            rep[full[0], :] = rep[zero[0], :]
        pole = np.flatnonzero(np.abs(np.asarray(self.radial_deg)) <= GRID_TOL)
        if pole.size:
            rep[:, pole[0]] = rep[0, pole[0]]
        return rep.ravel()

    def as_meta(self) -> dict[str, Any]:
        """The grid as plain lists (``meta["zemax_grid"]``)."""
        return {"symmetry": self.symmetry, "sample_rotation": list(self.rotation_deg),
                "angle_of_incidence": list(self.aoi_deg),
                "scatter_azimuth": list(self.azimuth_deg),
                "scatter_radial": list(self.radial_deg)}

    @classmethod
    def from_meta(cls, meta: dict[str, Any]) -> ZemaxGrid:
        """The grid recorded by :func:`read` in ``meta["zemax_grid"]``."""
        return cls(tuple(meta["angle_of_incidence"]), tuple(meta["scatter_azimuth"]),
                   tuple(meta["scatter_radial"]), tuple(meta["sample_rotation"]),
                   str(meta["symmetry"]))


def table_integral(values: Any, grid: ZemaxGrid) -> np.ndarray:
    """The table's own directional-hemispherical reflectance, ``int f cos(theta_r) d omega``
    at each (rotation, incidence): shape ``(rotations, incidences)``.

    The integrand ``f cos(theta_r) sin(r)`` is integrated with the trapezoid rule over the
    grid's (radial, azimuth) nodes (``d omega = sin r dr da`` about the specular direction);
    ``cos theta_r`` is 0 at and below the horizon. ``PlaneSymmetrical`` tables count twice
    (the mirror half); an ``Asymmetrical`` table is closed periodically from its last azimuth
    to its first + 360 deg. Directions beyond the grid's last radial angle (or outside its
    azimuths) count as 0. The accuracy is the grid's: a lobe narrower than the radial spacing,
    or a horizon cut between nodes, is what limits it (``docs``: ``export.zemax``).

    Examples
    --------
    >>> import numpy as np
    >>> g = ZemaxGrid((0,), np.arange(0, 181, 10), np.arange(0, 91, 1))
    >>> lambertian = np.full(g.shape, 0.5 / np.pi)
    >>> round(float(table_integral(lambertian, g)[0, 0]), 3)
    0.5
    """
    v = np.asarray(values, dtype=float).reshape(grid.shape)
    _, _, _, cz = grid.directions()
    r = np.radians(np.asarray(grid.radial_deg))
    a = np.radians(np.asarray(grid.azimuth_deg))
    g = v * np.clip(cz, 0.0, None)[None] * np.sin(r)
    inner = np.trapezoid(g, r, axis=-1) if r.size > 1 else np.zeros(g.shape[:-1])
    if grid.symmetry == "PlaneSymmetrical":
        return 2.0 * (np.trapezoid(inner, a, axis=-1) if a.size > 1 else 0.0 * inner[..., 0])
    closed = np.concatenate([inner, inner[..., :1]], axis=-1)
    return np.trapezoid(closed, np.concatenate([a, a[:1] + 2 * math.pi]), axis=-1)


# --------------------------------------------------------------------------------------------
# the table of a file
# --------------------------------------------------------------------------------------------
@dataclass
class ZemaxTable:
    """A tabular BSDF as it is in the file.

    Attributes
    ----------
    grid : ZemaxGrid
    values : numpy.ndarray, shape ``grid.shape``
        BRDF (sr⁻¹) at ``[rotation, incidence, azimuth, radial]``.
    tis : numpy.ndarray, shape ``(rotations, incidences)``
        The TIS line of each block.
    header : dict of str -> str
        ``Source``, ``Symmetry``, ``SpectralContent``, ``ScatterType`` as written.
    comments : list of str
        The ``#`` lines (without ``#``), in order.
    """

    grid: ZemaxGrid
    values: np.ndarray
    tis: np.ndarray
    header: dict[str, str] = field(default_factory=dict)
    comments: list[str] = field(default_factory=list)



# --------------------------------------------------------------------------------------------
# a grid from radians (the Python API's unit)
# --------------------------------------------------------------------------------------------
def grid_from_radians(angles_of_incidence: Any, azimuth: Any, radial: Any, *,
                      symmetry: str = "PlaneSymmetrical", sample_rotation: Any = (0.0,)
                      ) -> ZemaxGrid:
    """A :class:`ZemaxGrid` from angles in radians (the Python API's unit), converted to
    degrees rounded to 1e-9 deg so that ``radians(10)`` is written as ``10``.

    Raises :class:`~roughbrdf.errors.ArgumentError` naming the argument that is not a valid
    axis (range, order, finiteness).

    Examples
    --------
    >>> import numpy as np
    >>> grid_from_radians(np.radians([0, 45]), np.radians([0, 180]), np.radians([0, 5])).aoi_deg
    (0.0, 45.0)
    """
    axes = {"angles_of_incidence": angles_of_incidence, "azimuth": azimuth, "radial": radial,
            "sample_rotation": sample_rotation}
    deg = {}
    for name, val in axes.items():
        try:
            arr = np.atleast_1d(np.asarray(val, dtype=float))
        except (TypeError, ValueError):
            raise ArgumentError(name, "must be angles in radians (a number or a sequence)",
                                value=val) from None
        # 9 decimals of a degree: removes the rounding of radians(d) -> d, keeps 1e-11 rad
        deg[name] = tuple(np.round(np.degrees(arr.ravel()), 9))
    top = 180.0 if normalize_symmetry(str(symmetry)) == "PlaneSymmetrical" else 360.0
    for name, key, low, high in (("angles_of_incidence", "AngleOfIncidence", 0, 90),
                                 ("azimuth", "ScatterAzimuth", 0, top),
                                 ("radial", "ScatterRadial", 0, 180)):
        p = _check_axis(key, np.asarray(deg[name]), low, high)
        if p:
            raise ArgumentError(name, p + " (radians here: "
                                f"{np.radians(low):.4g} to {np.radians(high):.4g})")
    return ZemaxGrid(deg["angles_of_incidence"], deg["azimuth"], deg["radial"],
                     deg["sample_rotation"], symmetry)
