"""Grids of the exported tables, chosen so that each table is as accurate as the model.

A LightTools or Zemax ``.bsdf`` states a TIS per incidence (the model's directional-hemispherical
reflectance, :func:`roughbrdf.albedo`), and a reader integrates the table itself: the trapezoid
rule over the file's own nodes (:func:`roughbrdf.io.lighttools_write.table_integral`,
:func:`roughbrdf.io.zemax.table_integral`; libbsdf's node quadrature is of the same order).
The writers refine their default grids near the specular direction, level by level, until the
table's own integral - and a second rule on the same nodes, :func:`cell_rule` (each cell's
corner mean times its solid angle, the form of libbsdf's node quadrature) - is within
:data:`REFINE_TARGET` of TIS at every incidence (:func:`refine`). That keeps it within
:data:`INTEGRAL_RTOL`, the accuracy promised, for other readers' rules too (libbsdf's
interpolated 360 x 360 quadrature, measured). A grid given by the user is written as given,
with one :class:`TableAccuracyWarning` when it misses :data:`INTEGRAL_RTOL`; so is the finest
grid allowed (:data:`MAX_TABLE_VALUES`) when even it misses.

The parts: :func:`lobe_widths` (the specular lobe's half width at each incidence, which sets
the finest spacing), :func:`graded_axis` (nodes dense at given centres, spacing growing with
the distance from them) and :func:`relative_errors`.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["INTEGRAL_RTOL", "REFINE_TARGET", "grid_note", "MAX_LEVEL", "MAX_TABLE_VALUES",
           "TableAccuracyWarning", "Refined", "lobe_widths", "graded_axis", "cell_rule",
           "relative_errors", "refine"]

#: the accuracy promised (issue 29): each table's own integral within 0.5 % (relative) of the
#: TIS it states, at every incidence
INTEGRAL_RTOL = 5e-3
#: what the refinement aims at, with two rules (the trapezoid and :func:`cell_rule`): half the
#: promise, because other readers integrate the same nodes with yet other rules of the same
#: order, not exactly ours (libbsdf's bilinear interpolant on 360 x 360 cells read 0.64 %
#: above TIS a Zemax table whose trapezoid integral was 0.13 % above: the coated C2_Black fit
#: at AOI 80 on the former default grid)
REFINE_TARGET = 0.5 * INTEGRAL_RTOL
#: refinement levels tried after the first (each halves the spacings near the lobe)
MAX_LEVEL = 5
#: the most values a file's table may hold (incidences x azimuths x radials): about 30 MB of
#: text at 15 bytes a value, beyond which writing and reading a file take tens of seconds
MAX_TABLE_VALUES = 2_000_000
#: a TIS below this is a model that reflects nothing: its error is taken absolutely (no
#: division by a zero TIS)
TINY_TIS = 1e-12
#: nodes are rounded to this many decimals of a degree (written exactly by both formats)
NODE_DECIMALS = 6


class TableAccuracyWarning(UserWarning):
    """An exported table's own integral misses the TIS it states by more than
    :data:`INTEGRAL_RTOL` (a user's grid too coarse, or the finest grid allowed reached)."""


@dataclass(frozen=True)
class Refined:
    """The grid chosen, its table and how close its integral is to TIS.

    Attributes
    ----------
    grid : object
        The format's grid (``LightToolsGrid`` or ``ZemaxGrid``).
    values : numpy.ndarray
        The table on it.
    integral : numpy.ndarray
        The table's own integral per incidence.
    errors : numpy.ndarray
        ``|integral - TIS| / TIS`` per incidence (:func:`relative_errors`).
    level : int or None
        The refinement level used; None for a user's grid.
    warning : str or None
        The warning given (a table missing :data:`INTEGRAL_RTOL`), None when it does not.
    extra : object
        What the evaluation returned besides values and integral (the Zemax node counts).
    """

    grid: Any
    values: np.ndarray
    integral: np.ndarray
    errors: np.ndarray
    level: int | None
    warning: str | None = None
    extra: Any = None


def grid_note(level: int | None, layout: str) -> str:
    """The header comment of an exported table saying how its grid was chosen: ``layout``
    describes the grid (e.g. ``"dense around each AOI's specular direction"``); ``level`` is
    the refinement level (None: the user's grid, as given).

    Examples
    --------
    >>> grid_note(None, "graded")
    'grid: as given'
    >>> grid_note(2, "graded").split(",")[0]
    'grid: graded'
    """
    if level is None:
        return "grid: as given"
    return (f"grid: {layout}, refinement level {level}, chosen so that the table's own "
            f"integral is within {100 * REFINE_TARGET:g} % of TIS (promised: "
            f"{100 * INTEGRAL_RTOL:g} %)")


def relative_errors(integral: Any, tis: Any) -> np.ndarray:
    """``|integral - TIS| / TIS`` per incidence (absolute where TIS is 0).

    Examples
    --------
    >>> relative_errors([0.101, 0.0], [0.1, 0.0]).round(6).tolist()
    [0.01, 0.0]
    """
    i = np.asarray(integral, dtype=float)
    t = np.asarray(tis, dtype=float)
    scale = np.where(np.abs(t) > TINY_TIS, np.abs(t), 1.0)  # TIS 0: compared absolutely
    return np.abs(i - t) / scale


def lobe_widths(brdf: Callable[..., Any], aoi_deg: Sequence[float], *,
                polarization: Any = None) -> list[float | None]:
    """Half width at half maximum (degrees) of the specular lobe at each incidence: the angle
    from the specular direction, out of the plane of incidence, at which the BRDF falls half
    way from its specular value to its lowest value within 60 deg. None where there is no lobe
    (the specular value within 10 % of the lowest: Lambertian-like), at 89 deg and beyond (the
    lobe lies on the horizon) and where the model has no finite value.

    ``brdf(theta_i, theta_r, phi)`` takes radians (a model's ``brdf``, or a function).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> lobe_widths(rb.model("lambertian", rho=0.5).brdf, [0, 40])
    [None, None]
    >>> w = lobe_widths(rb.model("microfacet", alpha=0.05).brdf, [0])[0]
    >>> 3.0 < w < 4.5
    True
    """
    from ..geometry import specular_to_common

    r = np.radians(np.geomspace(1e-3, 60.0, 400))
    kw = {} if polarization is None else {"polarization": polarization}
    widths: list[float | None] = []
    for t in np.radians(np.atleast_1d(np.asarray(aoi_deg, dtype=float))):
        if t > math.radians(89.0):  # out of the plane the lobe then lies on the horizon
            widths.append(None)
            continue
        theta_r, phi, _ = specular_to_common(t, r, 0.5 * math.pi)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            f = np.broadcast_to(np.asarray(brdf(np.full(r.shape, t), theta_r, phi, **kw),
                                           dtype=float), r.shape)
        peak, low = (f[0], f.min()) if np.isfinite(f).all() else (0.0, 0.0)
        if peak - low <= 0.1 * abs(peak):  # no lobe worth resolving (or no finite values)
            widths.append(None)
            continue
        below = np.flatnonzero(f < low + 0.5 * (peak - low))
        widths.append(math.degrees(r[below[0]]))
    return widths


def graded_axis(lo: float, hi: float, centers: Sequence[float], finest: Sequence[float],
                growth: float, coarsest: float, pins: Sequence[float] = ()) -> np.ndarray:
    """Nodes (degrees) from ``lo`` to ``hi``: spacing ``finest[j]`` at ``centers[j]``,
    growing by ``growth`` times the distance from it, never above ``coarsest``; every centre
    and pin inside the range is a node, and no step is more than the spacing there.

    Examples
    --------
    >>> graded_axis(0, 10, [], [], 0.1, 2.5).tolist()
    [0.0, 2.5, 5.0, 7.5, 10.0]
    >>> graded_axis(0, 8, [4], [0.5], 0.5, 2.0).tolist()   # dense at 4
    [0.0, 1.0, 1.75, 2.3125, 2.8125, 3.3125, 3.65625, 4.0, 4.5, 5.0, 5.5, 6.25, 7.375, 8.0]
    """
    c = np.asarray(centers, dtype=float)
    f = np.maximum(np.asarray(finest, dtype=float), 1e-6)  # at least a node's rounding

    def spacing(x: float) -> float:
        if c.size == 0:
            return coarsest
        return float(min(coarsest, np.min(np.maximum(f, growth * np.abs(x - c)))))

    stops = sorted({float(p) for p in (*c.tolist(), *pins) if lo < p < hi}) + [float(hi)]
    nodes = [float(lo)]
    x, k = float(lo), 0
    while k < len(stops):
        s = spacing(x)
        s = min(s, spacing(min(x + s, hi)))  # the spacing shrinks toward a centre: look ahead
        gap = stops[k] - x
        if gap <= s * (1 + 1e-9):
            x = stops[k]
            k += 1
        else:  # two halves rather than a sliver before the stop
            x = x + (0.5 * gap if gap < 1.5 * s else s)
        nodes.append(x)
    out = np.unique(np.round(np.asarray(nodes), NODE_DECIMALS))
    return out


def cell_rule(values: np.ndarray, radial: np.ndarray, azimuth: np.ndarray,
              cosine: np.ndarray, *, factor: float = 1.0) -> np.ndarray:
    """``int f cos(theta_r) d omega`` by cells: the sum over the cells between nodes of the
    mean of the four corners' ``f cos(theta_r)`` times the cell's solid angle
    ``(cos r0 - cos r1) (a1 - a0)`` (``radial``, ``azimuth`` in radians, the last two axes of
    ``values``; ``cosine`` broadcast to them, 0 below the horizon). The form of libbsdf's
    quadrature on a file's nodes (``lb::computeReflectance`` of a table): a second rule of the
    trapezoid's order whose difference from it shows how much a reader's choice of rule moves
    the integral. ``factor`` 2 counts a mirrored half.

    Examples
    --------
    >>> t = np.radians(np.arange(0, 90.1, 1.0)); a = np.radians(np.arange(0, 360.1, 5.0))
    >>> f = np.full((a.size, t.size), 1 / np.pi)                    # Lambertian, albedo 1
    >>> round(float(cell_rule(f, t, a, np.cos(t)[None, :])), 4)
    1.0
    """
    g = np.asarray(values, dtype=float) * np.clip(cosine, 0.0, None)
    if g.shape[-1] < 2 or g.shape[-2] < 2:
        return np.zeros(g.shape[:-2])
    corners = 0.25 * (g[..., :-1, :-1] + g[..., 1:, :-1] + g[..., :-1, 1:] + g[..., 1:, 1:])
    omega = np.diff(azimuth)[:, None] * -np.diff(np.cos(radial))[None, :]
    return factor * np.sum(corners * omega, axis=(-2, -1))


def refine(build: Callable[[int], Any], evaluate: Callable[[Any], tuple[Any, ...]],
           tis: Any, *, size: Callable[[Any], int],
           user_grid: Any = None, what: str = "the table") -> Refined:
    """Choose the grid: ``build(level)`` for level 0, 1, ... until the table's own integral
    is within :data:`REFINE_TARGET` of TIS at every incidence (or ``user_grid`` as given).

    ``evaluate(grid)`` returns ``(values, integral, check, extra)``: the table, its own
    integral, a second rule's (:func:`cell_rule`; None for none) - both must meet the target,
    the warnings concern the first - and anything else to keep; ``tis`` is the TIS per
    incidence (None: the table's own integral, which then needs no refinement);
    ``size(grid)`` is the number of table values. Stops at :data:`MAX_LEVEL` or
    before a grid of more than :data:`MAX_TABLE_VALUES` values; a table then missing
    :data:`INTEGRAL_RTOL` - or a user's grid missing it - gives one
    :class:`TableAccuracyWarning` naming the shortfall (``what`` names the file).
    """
    best = None
    grids = [user_grid] if user_grid is not None else (build(lv) for lv in
                                                       range(MAX_LEVEL + 1))
    for level, grid in enumerate(grids):
        if best is not None and size(grid) > MAX_TABLE_VALUES:
            break
        values, integral, check, extra = evaluate(grid)
        target = integral if tis is None else tis
        err = relative_errors(integral, target)
        both = err if check is None else np.maximum(err, relative_errors(check, target))
        best = Refined(grid, values, np.asarray(integral, float), err,
                       None if user_grid is not None else level, extra=extra)
        if float(np.max(both)) <= REFINE_TARGET:
            break
    assert best is not None  # the first grid is always evaluated
    worst = int(np.argmax(best.errors))
    miss = float(best.errors[worst])
    if miss <= INTEGRAL_RTOL:
        return best
    aoi = best.grid.aoi_deg[worst]
    if user_grid is not None:
        text = (f"{what}: the grid given is too coarse: the table's own integral misses the "
                f"TIS it states by {100 * miss:.2g} % at AOI {aoi:g} deg (more than "
                f"{100 * INTEGRAL_RTOL:g} %); give finer radial/azimuth angles (--radial, "
                "--azimuth), or none for a grid refined until it meets that")
    else:
        text = (f"{what}: the finest grid allowed ({best.grid.shape} nodes, at most "
                f"{MAX_TABLE_VALUES:,} values) still misses the TIS it states by "
                f"{100 * miss:.2g} % at AOI {aoi:g} deg (more than {100 * INTEGRAL_RTOL:g} %)")
    warnings.warn(TableAccuracyWarning(text), stacklevel=3)
    return Refined(best.grid, best.values, best.integral, best.errors, best.level, text,
                   best.extra)
