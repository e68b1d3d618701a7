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

Opt-in: with ``intervals="profile"`` (``--intervals profile``) :func:`roughbrdf.fit` computes
them (:func:`one_sided_limits`, through :func:`~roughbrdf.fitting.results.intervals.add_profiles`,
which adds two-sided profile intervals of the other parameters from the same profile) for the
fit it returns: a model's fit, or the one ``--model auto`` keeps, not the candidates nor the
cross-validation folds; for channels fitted on their own and not under an active energy
constraint (the profile would have to hold it too): not for joint or Mueller fits. Each limit
costs 2-4 refits of the other parameters (about 0.1 s on C8_Silver's four-parameter metallic
fit; on C2_Black's 14-parameter RB08 fit at 465 nm, 7 s, the profiles took 165 s: hence not by
default). ``fit.json`` has them as
``one_sided_95``, the report on the parameter's line.

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
from .statistics import Covariance

if TYPE_CHECKING:
    from ...measurement import Measurement
    from ..problem.options import FitOptions
    from .result import ChannelFit

__all__ = ["LEVEL", "Z", "calibration", "dispersion", "held_cost", "objective_of",
           "one_sided_limits", "profile_limit", "rise_above"]

#: the one-sided confidence level of the limits
LEVEL = 0.95
#: its standard-normal quantile (``scipy.stats.norm.ppf(0.95)``)
Z = 1.6448536269514722
#: the profile's refits stop when a step would lower the cost by less than this fraction of
#: it (the polish's test, looser than its 1e-10): ``D`` is needed to 1 % of a threshold that is
#: ``kappa z^2 / 2``, about ``z^2 / (2 N)`` of the cost, so 1e-7 is ~1 % of that 1 % at
#: ``N`` = 10^4 samples (C8_Silver's limits moved by < 1e-6, the refits took 40 % less time)
TOL = 1e-7
#: a limit is where the profile is between its threshold and (1 + RTOL) times it, or the far
#: end of a bracket narrowed to this fraction (``profile_limit``)
RTOL = 0.01
#: at most this many refits per limit
MAX_REFITS = 40


def calibration(obj: Objective, theta: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per free parameter of ``obj`` at ``theta``, from one central-difference Jacobian: the
    dispersion ``kappa = V_jj / (H^-1)_jj`` (module notes: the sandwich variance over the
    curvature's, the scale's column included when it is free; NaN where ``H`` is singular),
    and the profile's local slope ``|J_j . r|`` and curvature ``J_j . c J_j`` (the first
    step's model, :func:`one_sided_limits`)."""
    f = obj.values(theta)
    k = obj.scale(f)
    r = obj.residual_of(f, k)
    curv = obj.curvature_of(f, k)
    params = obj.jac_central(theta, k)
    slope = np.abs(params.T @ r)
    local = np.einsum("ij,ij->j", params, params * curv[:, None])
    jac = params if not obj.spec.free_scale \
        else np.hstack([params, obj.scale_column(f, k)[:, None]])
    p = params.shape[1]
    try:  # H^-1 and the sandwich V of statistics.Covariance, with every parameter free
        inv = np.diag(Covariance.curvature_inverse(jac, curv))[:p]
    except np.linalg.LinAlgError:
        return np.full(p, math.nan), slope, local
    cov = Covariance.from_jacobian(jac, [str(i) for i in range(jac.shape[1])],
                                   chi2=math.nan, dof=r.size - jac.shape[1], residual=r,
                                   curvature=curv)
    var = np.diag(cov.matrix)[:p]
    with np.errstate(invalid="ignore", divide="ignore"):  # a NaN V or H^-1 <= 0: NaN
        kappa = np.where((inv > 0) & np.isfinite(var), var / inv, math.nan)
    return kappa, slope, local


def dispersion(obj: Objective, theta: np.ndarray, j: int) -> float:
    """``kappa`` of free parameter ``j`` (:func:`calibration`).

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
    return float(calibration(obj, theta)[0][j])


def profile_limit(rise: Callable[[float], float], bound: float, far: float, threshold: float,
                  first: float) -> float | None:
    """Where ``rise(u)`` (the profile ``D``, 0 at ``bound``) first reaches ``threshold`` going
    from ``bound`` towards ``far``; None when it stays below up to ``far``. ``first`` is the
    first distance tried.

    Each next distance solves ``a d + b d^2 = threshold`` for the curve through the origin and
    the last two points (one point: ``b`` alone), which is exact for a profile that is linear
    (a limit the data push against) or quadratic (an interior optimum) in ``d``, kept inside the
    bracket once there is one, at most 4x the last distance before. It ends on a point with
    ``threshold <= D <= threshold (1 + RTOL)`` (for a convex profile within :data:`RTOL` beyond
    the crossing: conservative) or a bracket narrowed to ``RTOL``, its far end returned.
    Typically 2-4 refits (a concave profile, rising slower than linearly, takes more).

    Examples
    --------
    >>> calls = []
    >>> def linear(u):
    ...     calls.append(u)
    ...     return 2.0 * u
    >>> round(profile_limit(linear, 0.0, 1.0, 1.0, 0.1), 3), len(calls)
    (0.502, 3)
    >>> round(profile_limit(lambda u: (1.0 - u) ** 2 / 2, 1.0, 0.0, 0.5, 0.01), 2)
    0.0
    >>> profile_limit(lambda u: 1e-3 * u, 0.0, 1.0, 1.0, 0.1) is None
    True
    """
    sign, span = math.copysign(1.0, far - bound), abs(far - bound)
    target = threshold * (1.0 + 0.5 * RTOL)  # aim just past the crossing: an acceptable end
    near, out = 0.0, math.inf  # the bracket: D(near) < threshold <= D(out)
    last: list[tuple[float, float]] = []  # the last two points (d, D)
    # a first step no further than a quarter of the way (a local model that hardly curves
    # guesses far; the refit there is wasted)
    d = min(max(first, 1e-9 * span), 0.25 * span)
    for _ in range(MAX_REFITS):
        val = rise(bound + sign * d)
        # below the reference: rounding, taken as 0; not finite (a model that overflows
        # there): far above any threshold
        val = max(val, 0.0) if math.isfinite(val) else math.inf
        last = [*last[-1:], (d, val)]
        if val >= threshold:
            out = d
            if val <= threshold * (1.0 + RTOL):
                break
        elif d >= span:
            return None  # below the threshold at the far end: not bounded
        else:
            near = d
        if math.isfinite(out) and out - near <= RTOL * out:
            break
        guess = _next_distance(last, target)
        if math.isfinite(out):  # inside the bracket, off its ends
            width = out - near
            d = min(max(guess, near + 0.05 * width), out - 0.05 * width)
        else:
            d = min(max(guess, 1.1 * d), 4.0 * d, span)
    return None if not math.isfinite(out) else bound + sign * out


def _next_distance(points: list[tuple[float, float]], target: float) -> float:
    """``d`` with ``a d + b d^2 = target``, the curve through the origin and ``points``
    (one point: ``a = 0``); a doubling where that curve does not rise."""
    d1, v1 = points[-1]
    a, b = 0.0, v1 / (d1 * d1)
    if len(points) == 2 and points[0][0] != d1:
        d0, v0 = points[0]
        # v = a d + b d^2 through (d0, v0) and (d1, v1): a 2 x 2 linear system
        det = d0 * d1 * (d1 - d0)
        a, b = (v0 * d1 * d1 - v1 * d0 * d0) / det, (v1 * d0 - v0 * d1) / det
    if b > 0.0 and a * a + 4.0 * b * target >= 0.0:
        return (-a + math.sqrt(a * a + 4.0 * b * target)) / (2.0 * b)
    if a > 0.0:
        return target / a
    return 2.0 * d1


def held_cost(obj: Objective, theta: np.ndarray, j: int) -> Callable[[float], float]:
    """``u -> min C`` with free parameter ``j`` held at ``u``, the others refitted from the
    solution at the nearest ``u`` held so far (the fit itself at ``theta[j]`` to begin with).

    Why the nearest and not the last: a refit started where a far point left the others can
    end in another valley. On C2_Black's 14-parameter RB08 fit, ``k_eff`` held at 0.025 after
    10 ended 2.8 above the fit's cost, against 3e-4 started from the fit, and the limit came
    out as 6e-22.
    """
    spec = obj.spec
    keep = [i for i in range(len(spec.free)) if i != j]
    name = spec.free[j]
    solved = {float(theta[j]): theta[keep].copy()}

    def cost(u: float) -> float:
        held = ObjectiveSpec(spec.model_at(theta).with_values([name], [u]),
                             [spec.free[i] for i in keep], spec.lower[keep], spec.upper[keep],
                             loss=spec.loss, quantity=spec.quantity, free_scale=spec.free_scale,
                             fixed_scale=spec.fixed_scale)
        sub = Objective(held, obj.data)
        if not keep:
            return 0.5 * sub.cost(np.empty(0))
        start = solved[min(solved, key=lambda v: abs(v - u))]
        res = bounded_lm(sub, start, TOL)
        solved[float(u)] = np.asarray(res.x, dtype=float)
        return float(res.cost)

    return cost


def rise_above(held: Callable[[float], float], base: float) -> Callable[[float], float]:
    """The profile ``D(u) = held(u) - base`` (``held``: :func:`held_cost`; ``base``: the cost
    at the fit)."""
    return lambda u: held(u) - base


def _first_step(width: float, slope: float, h: float, threshold: float) -> float:
    """A first distance from the limit: where the local model ``|g| d + h d^2 / 2`` of the
    profile (its slope ``g`` at the limit, its curvature ``h``; :func:`calibration`) reaches the
    threshold; a twentieth of the search range ``width`` where neither is known."""
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
    names = [nm for nm, kind in limits.items() if kind.startswith("physical") and nm in spec.free]
    if not names:
        return {}
    kappas, slopes, local = calibration(obj, theta)
    at_fit = 0.5 * obj.cost(theta)
    out: dict[str, float | None] = {}
    for name in names:
        j = spec.free.index(name)
        kappa = float(kappas[j])
        if not (math.isfinite(kappa) and kappa > 0):
            continue  # no calibration (a singular curvature): no limit claimed
        threshold = 0.5 * kappa * Z * Z
        lower = limits[name].endswith("lower")
        bound, far = (spec.lower[j], spec.upper[j]) if lower else (spec.upper[j], spec.lower[j])
        held = held_cost(obj, theta, j)
        base = min(at_fit, held(float(bound)))
        first = _first_step(float(spec.upper[j] - spec.lower[j]), float(slopes[j]),
                            float(local[j]), threshold)
        out[name] = profile_limit(rise_above(held, base), float(bound), float(far), threshold,
                                  first)
    return out


def objective_of(c: ChannelFit, measurement: Measurement, options: FitOptions
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
