"""Profile intervals of the fitted parameters (``intervals="profile"``, ``--intervals profile``).

A standard error describes the cost as a quadratic bowl; where it is not one (a parameter whose
effect saturates, a width traded against a weight, C8_Silver's flake edge tint ``g_m``, whose
Wald intervals miss the truth two to four times as often as they say: ``docs/fitting.md``,
"One-sided limits at a physical limit") the interval to trust is the profile's: the values of
the parameter where the cost, every other free parameter refitted, has risen by ``kappa z^2 /
2`` (:mod:`~roughbrdf.fitting.results.one_sided`: the profile, the refits and the threshold
``kappa``, the sandwich's dispersion, are the same). Each side is found on its own, so an
interval can be lopsided; where the profile stays below the threshold up to a search bound, that
side is None (the data do not bound it there). Two levels: 68.27 % (``z = 1``, what ``+/-
stderr`` claims) and 95.45 % (``z = 2``). Where the cost is quadratic the 68 % interval is
``value +/- stderr`` (``tests/fitting/test_intervals.py``).

Opt-in, as the one-sided limits (each end costs 2-4 refits, each a local fit of the other
parameters: 1.2 s for C8_Silver's four parameters at 465 nm, against 0.3 s for the fit; 165 s
for a 14-parameter RB08 fit of C2_Black that took 7 s):
with ``intervals="profile"`` :func:`roughbrdf.fit` computes them for the fit it returns, for every
free parameter with a standard error (one on a physical limit gets its one-sided limit instead,
one on a search limit nothing), for channels fitted on their own and not under an active energy
constraint. ``ChannelFit.intervals``, ``fit.json``'s ``profile_intervals``, the report's
``[[Profile intervals]]``.

Examples
--------
>>> LEVELS
{'68': 1.0, '95': 2.0}
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from ..problem.objective import Objective
from .one_sided import (
    calibration,
    held_cost,
    objective_of,
    one_sided_limits,
    profile_limit,
    rise_above,
)

if TYPE_CHECKING:
    from ...measurement import Measurement
    from ..problem.options import FitOptions
    from .result import ChannelFit, FitResult

__all__ = ["INTERVALS", "LEVELS", "NOT_UNDER_CONSTRAINT", "add_profiles", "profile_intervals"]

#: the values of the ``intervals`` option
INTERVALS = ("wald", "profile")
#: level name -> z (two-sided 68.27 % and 95.45 %)
LEVELS = {"68": 1.0, "95": 2.0}

Interval = tuple[float | None, float | None]

#: what a channel's message says when its profiles were asked for and the energy constraint is
#: active there
NOT_UNDER_CONSTRAINT = ("; no profile intervals nor one-sided limits: the energy constraint "
                        "is active (fit with energy_constraint=False for them)")


def profile_intervals(obj: Objective, params: Mapping[str, Any], stderr: Mapping[str, Any],
                      names: list[str]) -> dict[str, dict[str, Interval]]:
    """``{name: {"68": (lo, hi), "95": (lo, hi)}}`` for the free parameters ``names`` of ``obj``
    at the fit ``params`` (module notes); ``stderr`` gives the first steps. A side the data do
    not bound within the search range is None.

    Examples
    --------
    The Lambertian's absolute-loss cost is quadratic in ``rho``: the 68 % interval is
    ``value +/- stderr`` (to the 1 % of the bracket), the 95 % one twice as wide.

    >>> import numpy as np, roughbrdf as rb
    >>> from roughbrdf.fitting import ChannelData
    >>> from roughbrdf.fitting.problem.objective import ObjectiveSpec
    >>> x = np.array([0.1, 0.3, 0.25, 0.15, 0.2])
    >>> data = ChannelData.from_arrays([0.1] * 5, [0.2] * 5, [0.0] * 5, x)
    >>> obj = Objective(ObjectiveSpec(rb.model("lambertian"), ["rho"], [0.0], [1.0],
    ...                               loss="absolute"), data)
    >>> se = np.pi * np.sqrt(np.sum((x - x.mean()) ** 2) / 4 / 5)   # the sandwich's, HC1
    >>> out = profile_intervals(obj, {"rho": np.pi * 0.2}, {"rho": se}, ["rho"])
    >>> [round(float((v - np.pi * 0.2) / se), 2) for v in out["rho"]["68"]]
    [-1.0, 1.0]
    >>> [round(float((v - np.pi * 0.2) / se), 1) for v in out["rho"]["95"]]
    [-2.0, 2.0]
    """
    spec = obj.spec
    theta = np.array([float(params[nm]) for nm in spec.free])
    kappas = calibration(obj, theta)[0] if names else np.empty(0)
    at_fit = 0.5 * obj.cost(theta) if names else math.nan
    out: dict[str, dict[str, Interval]] = {}
    for name in names:
        j = spec.free.index(name)
        kappa = float(kappas[j])
        if not (math.isfinite(kappa) and kappa > 0):
            continue  # no calibration (a singular curvature): no interval claimed
        se = stderr.get(name)
        width = float(spec.upper[j] - spec.lower[j])
        first = float(se) if se is not None and math.isfinite(se) and se > 0 \
            else (width / 20.0 if math.isfinite(width) else 1.0)
        sides = [_side(obj, theta, j, float(bound), kappa, first, at_fit)
                 for bound in (spec.lower[j], spec.upper[j])]
        out[name] = {level: (sides[0][level], sides[1][level]) for level in LEVELS}
    return out


def _side(obj: Objective, theta: np.ndarray, j: int, far: float, kappa: float,
          first: float, at_fit: float) -> dict[str, float | None]:
    """Both levels' ends on the side of ``far`` (a search bound) of free parameter ``j``, the
    profile rising above the cost ``at_fit``; the 95 % search starts from the 68 % end (twice
    its distance: the quadratic guess)."""
    rise = rise_above(held_cost(obj, theta, j), at_fit)
    value = float(theta[j])
    out: dict[str, float | None] = {}
    step = first
    for level, z in LEVELS.items():
        if far == value:
            out[level] = None
            continue
        end = profile_limit(rise, value, far, 0.5 * kappa * z * z, step)
        out[level] = end
        if end is None:  # not bounded at this level: nor at a wider one
            out.update(dict.fromkeys([lv for lv in LEVELS if lv not in out]))
            break
        step = 2.0 * abs(end - value)
    return out


def add_profiles(result: FitResult, measurement: Measurement, options: FitOptions, *,
                 two_sided: bool = True) -> FitResult:
    """``result`` (of ``measurement`` fitted with ``options``, each channel on its own) with,
    when ``options.intervals == "profile"``, the one-sided limits of its parameters on a
    physical limit (:func:`~roughbrdf.fitting.results.one_sided.one_sided_limits`) and, with
    ``two_sided``, the profile intervals of those with a standard error
    (:func:`profile_intervals`; :attr:`ChannelFit.intervals
    <roughbrdf.fitting.results.result.ChannelFit.intervals>`), one objective per channel for
    both; unchanged otherwise."""
    if options.intervals != "profile":  # opt-in: a profile costs many refits (module notes)
        return result
    for c in result.channels:
        if c.energy_constraint is not None and c.energy_constraint.active:
            # the profile would have to hold the constraint (one_sided's notes): said, since
            # they were asked for
            c.message += NOT_UNDER_CONSTRAINT
            continue
        physical = any(k.startswith("physical") for k in c.limits.values())
        names = _with_stderr(c) if two_sided else []
        obj = objective_of(c, measurement, options) if physical or names else None
        if obj is None:
            continue
        if physical:
            c.one_sided = one_sided_limits(obj, c.params, c.limits)
        if names:
            c.intervals = profile_intervals(obj, c.params, c.stderr, names)
    return result


def _with_stderr(c: ChannelFit) -> list[str]:
    """The free parameters of ``c`` with a finite standard error."""
    return [nm for nm in c.free
            if isinstance(c.stderr.get(nm), float) and math.isfinite(c.stderr[nm])  # type: ignore[arg-type]
            and nm not in c.at_bound]
