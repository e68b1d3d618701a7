"""One-sided limits for parameters that end on a physical limit: how far the data let them go.

A parameter that ends on an edge of its domain (a lobe's weight or the flakes' edge tint at 0, a
reflectance at 1: ``physical-lower``/``physical-upper`` of
:func:`~roughbrdf.fitting.results.statistics.limit_kinds`) has no standard error: the cost is no
quadratic bowl there (``statistics``). What a user needs instead is the one-sided interval ``[0,
u]``: the values the data do not rule out. ``docs/fitting.md`` ("One-sided limits at a physical
limit") derives it; in short:

* **the profile**: ``D(u) = min C(theta | theta_j = u) - C(theta_hat)``, the cost ``C = 1/2
  sum r^2`` of the loss residuals (scale profiled, as the fit minimizes it) with the parameter
  held at ``u`` and every other free parameter refitted (:func:`~roughbrdf.fitting.solvers.
  bounded.bounded_lm` from the neighbouring point), ``theta_hat`` the fit, on the limit;
* **the threshold**: ``D(u) = kappa z^2 / 2`` with ``z`` = 1.645 (:data:`Z`, one-sided 95 %,
  :data:`LEVEL`) and ``kappa = V_jj / (H^-1)_jj`` (:func:`dispersion`): ``V`` the sandwich
  covariance and ``H = J^T diag(c) J`` the cost's curvature of
  :class:`~roughbrdf.fitting.results.statistics.Covariance`, both with the parameter free, at the
  fit. Where the cost is quadratic this puts ``u`` at ``z`` sandwich standard errors from the
  interior optimum the bound cut off, so the limits and the standard errors of interior fits are
  one calibration (least squares with equal variances: ``kappa = chi2/dof``);
* **what it guarantees** (a Gaussian mean with a bound, ``docs/fitting.md``): the chance that a
  fit ends on the limit *and* its ``u`` lies below the truth is at most 5 % for every truth,
  5 % exactly when the truth is ``z`` standard errors inside; a truth on the limit is always
  covered. Where the data keep ``D`` below the threshold up to the other end of the search
  range, the limit is ``None``: the data do not bound the parameter there.

Computed by :func:`roughbrdf.fit` for the fit it returns (:func:`add_one_sided`: a model's, or
the one ``--model auto`` keeps; not for the candidates nor the cross-validation folds, which
would pay for profiles nobody reads), for channels fitted on their own and not under an active
energy constraint (the profile would have to hold it too): not for joint or Mueller fits.
``fit.json`` has them as ``one_sided_95``, the report on the parameter's line.

Examples
--------
A profile that rises linearly from the limit, ``D(u) = 2 u``, crosses the threshold 1 at 0.5:

>>> round(profile_limit(lambda u: 2.0 * u, 0.0, 1.0, 1.0, 1.0), 2)
0.5
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from ..problem.data import prepare_channel
from ..problem.objective import Objective, ObjectiveSpec
from ..problem.plan import FitPlan
from ..solvers.bounded import bounded_lm

if TYPE_CHECKING:
    from ...measurement import Measurement
    from ..problem.options import FitOptions
    from .result import ChannelFit, FitResult

__all__ = ["LEVEL", "Z", "add_one_sided", "dispersion", "one_sided_limits", "profile_limit"]

#: the one-sided confidence level of the limits
LEVEL = 0.95
#: its standard-normal quantile (``scipy.stats.norm.ppf(0.95)``)
Z = 1.6448536269514722
#: the profile's refits stop at this fraction of the cost (as the fit's polish)
TOL = 1e-10
#: the bracket of ``u`` is narrowed to this fraction of its far end (the limit is its far end)
RTOL = 0.01
#: at most this many refits per limit (doubling to a bracket, then halving it)
MAX_REFITS = 40


def dispersion(obj: Objective, theta: np.ndarray, j: int) -> float:
    """``kappa = V_jj / (H^-1)_jj`` at ``theta`` for free parameter ``j`` (module notes): the
    sandwich variance over the curvature's, the scale's column included when it is free. NaN
    where ``H`` is singular.

    Examples
    --------
    >>> import numpy as np, roughbrdf as rb
    >>> from roughbrdf.fitting import ChannelData
    >>> data = ChannelData.from_arrays([0.1] * 4, [0.2] * 4, [0.0] * 4, [0.1, 0.3, 0.2, 0.2])
    >>> obj = Objective(ObjectiveSpec(rb.model("lambertian"), ["rho"], [0.0], [1.0],
    ...                               loss="absolute"), data)
    >>> round(dispersion(obj, np.array([0.2 * np.pi]), 0), 6)   # sum r^2 / (N - 1)
    0.006667
    """
    f = obj.values(theta)
    k = obj.scale(f)
    r = obj.residual_of(f, k)
    cols = [obj.jac_central(theta, k)]
    if obj.spec.free_scale:
        cols.append(obj.scale_column(f, k)[:, None])
    jac = np.hstack(cols)
    # H = J^T diag(c) J: the M-estimator's curvature (statistics.Covariance)
    curv = jac.T @ (jac * obj.curvature_of(f, k)[:, None])
    meat = jac.T @ (jac * (r * r)[:, None])
    try:
        inv = np.linalg.inv(curv)
    except np.linalg.LinAlgError:
        return math.nan
    dof = max(r.size - jac.shape[1], 1)
    var = float((inv @ meat @ inv)[j, j]) * r.size / dof
    return var / float(inv[j, j]) if inv[j, j] > 0 else math.nan


def profile_limit(rise: Callable[[float], float], bound: float, far: float, threshold: float,
                  first: float) -> float | None:
    """Where ``rise(u)`` (the profile ``D``, 0 at ``bound``) first reaches ``threshold`` going
    from ``bound`` towards ``far``, to :data:`RTOL` (its far end: conservative); None when it
    stays below up to ``far``. ``first`` is the first distance tried.

    Examples
    --------
    >>> round(profile_limit(lambda u: (1.0 - u) ** 2 / 2, 1.0, 0.0, 0.5, 0.01), 2)
    0.0
    >>> profile_limit(lambda u: 1e-3 * u, 0.0, 1.0, 1.0, 0.1) is None
    True
    """
    sign, span = math.copysign(1.0, far - bound), abs(far - bound)
    near, out = 0.0, None
    d = min(max(first, 1e-9 * span), span)
    for _ in range(MAX_REFITS):
        if out is None:  # doubling until D reaches the threshold or the far end is passed
            if rise(bound + sign * d) >= threshold:
                out = d
            elif d >= span:
                return None
            else:
                near, d = d, min(2.0 * d, span)
            continue
        if out - near <= RTOL * out:
            break
        mid = 0.5 * (near + out)
        if rise(bound + sign * mid) >= threshold:
            out = mid
        else:
            near = mid
    return None if out is None else bound + sign * out


def _held(obj: Objective, theta: np.ndarray, j: int) -> Callable[[float], float]:
    """``u -> min C`` with free parameter ``j`` held at ``u``, the others refitted from where
    the last call ended (the profile moves in small steps: a warm start)."""
    spec = obj.spec
    keep = [i for i in range(len(spec.free)) if i != j]
    name = spec.free[j]
    state = {"x": theta[keep].copy()}

    def cost(u: float) -> float:
        held = ObjectiveSpec(spec.model_at(theta).with_values([name], [u]),
                             [spec.free[i] for i in keep], spec.lower[keep], spec.upper[keep],
                             loss=spec.loss, quantity=spec.quantity, free_scale=spec.free_scale,
                             fixed_scale=spec.fixed_scale)
        sub = Objective(held, obj.data)
        if not keep:
            return 0.5 * sub.cost(np.empty(0))
        res = bounded_lm(sub, state["x"], TOL)
        state["x"] = np.asarray(res.x, dtype=float)
        return float(res.cost)

    return cost


def _rise(held: Callable[[float], float], base: float) -> Callable[[float], float]:
    """The profile ``D(u) = held(u) - base``."""
    return lambda u: held(u) - base


def _first_step(obj: Objective, theta: np.ndarray, j: int, threshold: float) -> float:
    """A first distance from the limit: where the local model ``|g| d + h d^2 / 2`` of the
    profile (its slope ``g`` at the limit, the curvature ``h = 1 / (H^-1)_jj``) reaches the
    threshold; a twentieth of the search range where neither is known."""
    spec = obj.spec
    width = float(spec.upper[j] - spec.lower[j])
    f = obj.values(theta)
    k = obj.scale(f)
    col = obj.jac_central(theta, k, columns=[j])[:, 0]
    slope = abs(float(col @ obj.residual_of(f, k)))
    h = float(col @ (col * obj.curvature_of(f, k)))
    if h > 0 and math.isfinite(h):
        return (math.sqrt(slope * slope + 2.0 * h * threshold) - slope) / h
    return width / 20.0 if math.isfinite(width) else 1.0


def one_sided_limits(obj: Objective, params: Mapping[str, Any],
                     limits: Mapping[str, str]) -> dict[str, float | None]:
    """``{name: u}``: the one-sided 95 % limit (module notes) of each free parameter of ``obj``
    that ``limits`` puts on a physical limit (``"physical-lower"``/``"physical-upper"``), the
    fit at ``params``; ``u`` None where the data do not bound it within the search range.

    Examples
    --------
    >>> import numpy as np, roughbrdf as rb
    >>> from roughbrdf.fitting import ChannelData
    >>> x = np.array([-0.01, 0.02, -0.03, 0.0])      # mean -0.005: rho/pi = 0 at its limit
    >>> data = ChannelData.from_arrays([0.1] * 4, [0.2] * 4, [0.0] * 4, x)
    >>> obj = Objective(ObjectiveSpec(rb.model("lambertian"), ["rho"], [0.0], [1.0],
    ...                               loss="absolute"), data)
    >>> u = one_sided_limits(obj, {"rho": 0.0}, {"rho": "physical-lower"})["rho"]
    >>> kappa = float(x @ x) / 3                   # the sandwich's sum r^2 / (N - 1) at 0
    >>> closed = np.pi * (x.mean() + np.sqrt(x.mean() ** 2 + kappa * Z ** 2 / 4))
    >>> bool(closed <= u <= closed * 1.01)
    True
    """
    spec = obj.spec
    theta = np.array([float(params[nm]) for nm in spec.free])
    out: dict[str, float | None] = {}
    for name, kind in limits.items():
        if not kind.startswith("physical") or name not in spec.free:
            continue
        j = spec.free.index(name)
        kappa = dispersion(obj, theta, j)
        if not (math.isfinite(kappa) and kappa > 0):
            continue  # no calibration (a singular curvature): no limit claimed
        threshold = 0.5 * kappa * Z * Z
        lower = kind.endswith("lower")
        bound, far = (spec.lower[j], spec.upper[j]) if lower else (spec.upper[j], spec.lower[j])
        held = _held(obj, theta, j)
        base = min(0.5 * obj.cost(theta), held(float(bound)))
        out[name] = profile_limit(_rise(held, base), float(bound), float(far), threshold,
                                  _first_step(obj, theta, j, threshold))
    return out


def add_one_sided(result: FitResult, measurement: Measurement, options: FitOptions) -> FitResult:
    """``result`` (of ``measurement`` fitted with ``options``, each channel on its own) with the
    one-sided limits of its channels' parameters on a physical limit (:func:`one_sided_limits`,
    :attr:`ChannelFit.one_sided <roughbrdf.fitting.results.result.ChannelFit.one_sided>`); a
    channel fitted under an active energy constraint keeps none."""
    for c in result.channels:
        if not any(k.startswith("physical") for k in c.limits.values()):
            continue
        if c.energy_constraint is not None and c.energy_constraint.active:
            continue  # the profile would have to hold the constraint too (module notes)
        obj = _objective_of(c, measurement, options)
        if obj is not None:
            c.one_sided = one_sided_limits(obj, c.params, c.limits)
    return result


def _objective_of(c: ChannelFit, measurement: Measurement, options: FitOptions
                  ) -> Objective | None:
    """The objective channel ``c`` was fitted with (its data, loss, scale, free parameters and
    bounds); None where the plan gives other free parameters (no limit rather than a wrong
    one)."""
    j = list(measurement.channels).index(c.channel)
    plan = FitPlan.of(c.model, measurement, options.replace(channel=[j]))
    if list(plan.spec.free) != list(c.free):
        return None
    spec = ObjectiveSpec(plan.spec.model, c.free, np.array([c.bounds[nm][0] for nm in c.free]),
                         np.array([c.bounds[nm][1] for nm in c.free]), loss=plan.spec.loss,
                         quantity=plan.spec.quantity, free_scale=plan.spec.free_scale,
                         fixed_scale=plan.spec.fixed_scale)
    return Objective(spec, prepare_channel(c.model, measurement, j, plan.opts))
