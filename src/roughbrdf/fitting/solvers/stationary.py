"""When a local fit has ended, by properties of the problem: first-order optimality, flat
parameters, and ends on a bound.

``docs/fitting.md`` ("The same answer on every machine"). The kernels round differently on
processors of another vector width (AVX2, AVX-512), and a fit whose end hangs on the last bit
of a model value ends elsewhere on another machine. Three places where that happened, and what
the solvers (:mod:`.bounded`, :mod:`.constrained`) do about each:

* **A stationary point that the Gauss–Newton test does not see.** Where a residual depends on
  a parameter only through its square near a point (TR75's Fresnel factor near ``n = 1``,
  ``k = 0``: a specular lobe switched off), the Jacobian column vanishes there but the
  Gauss–Newton step's predicted decrease ``(J^T f)^2 / (2 J^T J)`` does not: the convergence
  test on the predicted decrease never holds, and the fit ends on its evaluation budget or
  with "no step lowers the cost", depending on the last bits. :func:`optimality` is the
  first-order test: the largest cosine between the (Lagrangian) gradient, projected on the
  box, and a Jacobian column of Marquardt's scaling (the largest column norm seen, as in
  MINPACK's ``gtol`` test); below :data:`GTOL` the point is stationary.
* **A parameter the residuals no longer see** (a lobe's width once its amplitude is nearly
  0): any step moves it freely, and it drifts to a search limit or not by rounding.
  :func:`flat` names those whose whole box changes the linearized residuals by at most
  :data:`FLAT` of their norm and the constraints by at most ``FEASIBLE``: they do not move.
* **An end near a bound.** A parameter whose optimum is its bound but whose residuals are
  quadratic in it there (``k -> 0``) approaches it geometrically and stops 1e-5 or 1e-9 from
  it, so that "at a bound" (:func:`~roughbrdf.fitting.results.statistics.at_bound`) flips.
  :func:`snap` tries each parameter within :data:`SNAP_DIST` of a bound on the bound and keeps
  it there when the cost rises by at most :data:`SNAP_COST` of itself (a change far below any
  statistical meaning) and the point stays feasible. A bound that is an edge of the
  parameter's physical domain (a lobe's weight 0 or 1, ``k = 0``: ``edges``) is tried from
  any distance: two lobes of one width are one lobe, and the second one's weight is then any
  value in its box at one cost (C2_Black's two GGX lobes at 525 nm ended with ``w2 = 0`` in
  one run and ``w2 = 0.03``, ``alpha2 = alpha`` in another); on the edge, the end is one.
* **An end near a neutral value inside the box** (TR75's ``n = 1`` with ``k = 0``: the index
  matched, the specular lobe off; :attr:`Parameter.neutral
  <roughbrdf.models.parameters.Parameter.neutral>`). The residuals are quadratic in ``n - 1``
  there, so the solver stops where its tolerance does, on either side of 1: perturbed copies
  of one constrained TR75 fit ended at ``n - 1`` from ``-9e-6`` to ``+7e-6``, farther apart
  than the standard error the covariance gave. :func:`snap` tries such an end on the value
  with the bound's rule.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["DAMP_FLOOR", "FLAT", "GTOL", "SNAP_COST", "SNAP_DIST", "edges_of", "flat", "optimality",
           "points_of", "scaling", "snap", "snap_spec", "widths"]

#: first-order optimality: the projected gradient's largest cosine with a scaled Jacobian
#: column (forward differences give gradients to ~1e-8 relative: a margin of 100 above them)
GTOL = 1e-6
#: a parameter whose whole box moves the linearized residuals by at most this fraction of
#: their norm is flat (the cost by ~2e-6 of itself: below the polish's tolerance steps' worth)
FLAT = 1e-6
#: Marquardt's squared scale of a parameter is at least this times ``|f|^2 / w^2`` (``w`` its
#: box's width): a step across the whole box costs at least ``lambda`` times the cost in damping
DAMP_FLOOR = 1.0
#: parameters within this fraction of their box of a bound are tried on the bound
SNAP_DIST = 1e-2
#: and kept there when the cost rises by at most this fraction of itself (a 1-sigma change of
#: one parameter raises a normalized chi2 by 1, i.e. by 1/N of itself: 1e-5 for 1e5 samples)
SNAP_COST = 1e-6


def widths(x: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """The width of each parameter's box; ``max(1, |x|)`` where a bound is infinite.

    Examples
    --------
    >>> widths(np.array([3.0, 0.5]), np.array([0.0, 0.0]), np.array([np.inf, 2.0])).tolist()
    [3.0, 2.0]
    """
    w = np.asarray(upper, dtype=float) - np.asarray(lower, dtype=float)
    return np.where(np.isfinite(w), w, np.maximum(1.0, np.abs(x)))


def scaling(d2: np.ndarray, f: np.ndarray, x: np.ndarray, lower: np.ndarray,
            upper: np.ndarray) -> np.ndarray:
    """Marquardt's squared scaling: the largest squared column norms seen, ``d2``, floored at
    ``DAMP_FLOOR |f|^2 / w^2`` (:func:`widths`); 1 where both are 0.

    The floor is for a parameter the residuals barely see *at the current point* (a
    conductor's ``k`` near 0, where the residuals are quadratic in it): with its column's own
    tiny norm for scale, the damping cannot hold it, and the linearized model sends it across
    its whole box, where model and constraints are nothing like their linearization.

    Examples
    --------
    >>> scaling(np.array([4.0, 1e-20]), np.array([3.0, 4.0]), np.zeros(2), np.zeros(2),
    ...         np.array([10.0, 10.0])).tolist()
    [4.0, 0.25]
    """
    floor = DAMP_FLOOR * float(f @ f) / widths(x, lower, upper) ** 2
    out = np.maximum(d2, floor)
    return np.where(out > 0, out, 1.0)


def flat(jac: np.ndarray, f: np.ndarray, x: np.ndarray, lower: np.ndarray,
         upper: np.ndarray, gmat: np.ndarray | None = None, feasible: float = 0.0
         ) -> np.ndarray:
    """Which parameters are flat at ``x`` (module notes): ``|J_j| w_j <= FLAT |f|`` and,
    with constraint Jacobian ``gmat``, ``|G_j| w_j <= feasible`` (``w`` :func:`widths`).

    Examples
    --------
    >>> jac = np.array([[1.0, 1e-12], [0.0, 1e-12]])
    >>> flat(jac, np.array([1.0, 1.0]), np.zeros(2), np.zeros(2), np.ones(2)).tolist()
    [False, True]
    """
    w = widths(x, lower, upper)
    out = np.sqrt(np.sum(jac * jac, axis=0)) * w <= FLAT * float(np.linalg.norm(f))
    if gmat is not None and gmat.size:
        out &= np.max(np.abs(gmat), axis=0) * w <= feasible
    return np.asarray(out)


def optimality(jac: np.ndarray, f: np.ndarray, x: np.ndarray, lower: np.ndarray,
               upper: np.ndarray, d2: np.ndarray, extra: np.ndarray | None = None,
               frozen: np.ndarray | None = None) -> float:
    """The first-order optimality measure at ``x`` (module notes): the largest
    ``|P(J^T f + extra)_j| / (sqrt(d2_j) |f|)``, ``P`` the projection that drops the
    components pushing a parameter on its bound out of the box, ``extra`` the constraints'
    ``G^T mu``, ``d2`` Marquardt's squared column scales; flat (``frozen``) parameters and
    columns of zero scale are left out. 0 when the residuals are 0.

    Examples
    --------
    >>> jac, f = np.array([[1.0], [0.0]]), np.array([0.0, 1.0])  # the residual is orthogonal
    >>> optimality(jac, f, np.zeros(1), np.full(1, -1.0), np.ones(1), np.ones(1))
    0.0
    >>> optimality(jac, np.array([1.0, 0.0]), np.zeros(1), np.zeros(1), np.ones(1),
    ...            np.ones(1))                    # on its lower bound, pushed below it
    0.0
    """
    norm = float(np.linalg.norm(f))
    if not norm > 0:
        return 0.0
    grad = jac.T @ f if extra is None else jac.T @ f + extra
    # a parameter on a bound whose descent direction leaves the box is stationary there
    on_lower, on_upper = x <= lower, x >= upper
    grad = np.where((on_lower & (grad > 0)) | (on_upper & (grad < 0)), 0.0, grad)
    keep = d2 > 0
    if frozen is not None:
        keep &= ~frozen
    if not np.any(keep):
        return 0.0
    return float(np.max(np.abs(grad[keep]) / (np.sqrt(d2[keep]) * norm)))


def points_of(spec: Any) -> np.ndarray | None:
    """``spec.snap_points()`` (the neutral values, TR75's ``n = 1``:
    :meth:`~roughbrdf.fitting.problem.objective.ObjectiveSpec.snap_points`) where the solver's
    objective has it, else None."""
    method = getattr(spec, "snap_points", None)
    return None if method is None else np.asarray(method(), dtype=float)


def edges_of(spec: Any) -> np.ndarray | None:
    """``spec.snap_edges()`` (:meth:`~roughbrdf.fitting.problem.objective.ObjectiveSpec.snap_edges`)
    where the solver's objective has it, else None (a duck-typed objective with bounds only:
    ends near a bound alone are tried)."""
    method = getattr(spec, "snap_edges", None)
    return None if method is None else np.asarray(method(), dtype=bool)


def snap(x: np.ndarray, cost: float, lower: np.ndarray, upper: np.ndarray,
         trial: Callable[[np.ndarray], float | None], edges: np.ndarray | None = None,
         points: np.ndarray | None = None) -> tuple[np.ndarray, float, int]:
    """Each parameter within :data:`SNAP_DIST` of its box of a bound (and of the bound itself,
    but for a bound 0), or at any distance of a bound that ``edges`` (shape ``(p, 2)``: lower,
    upper) marks as a physical edge, in order, tried on the bound: kept when ``trial(x_new)``
    (the cost there, None when the point is refused, e.g. infeasible) is at most
    ``(1 + SNAP_COST) cost``. A parameter on no bound is then tried likewise on its neutral
    value ``points[j]`` (NaN: none) when within :data:`SNAP_DIST` of its box of it (module
    notes: TR75's ``n -> 1``). Returns the point, its cost and the trials made.

    Examples
    --------
    >>> cost = lambda x: float(1.0 + x[0] ** 2 + (x[1] - 0.5) ** 2)
    >>> x, c, n = snap(np.array([1e-5, 0.499]), cost(np.array([1e-5, 0.499])),
    ...                np.zeros(2), np.ones(2), cost)
    >>> x.tolist(), n                              # x0 to its bound 0; x1 is not near one
    ([0.0, 0.499], 1)
    >>> flat = lambda x: float(1.0 + (x[1] - 0.5) ** 2)  # x0 has no effect: its edge 1 as good
    >>> snap(np.array([0.3, 0.499]), 1.000001, np.zeros(2), np.ones(2), flat,
    ...      np.array([[False, True], [False, False]]))[0].tolist()
    [1.0, 0.499]
    >>> quartic = lambda x: float(1.0 + (x[0] - 0.5) ** 4)  # flat at its neutral value 0.5
    >>> snap(np.array([0.5003, 0.2]), quartic(np.array([0.5003])), np.zeros(2), np.ones(2),
    ...      quartic, points=np.array([0.5, np.nan]))[0].tolist()
    [0.5, 0.2]
    """
    x = np.array(x, dtype=float)
    w = widths(x, lower, upper)
    n = 0
    for j in range(x.size):
        if points is not None and _on_point(x, j, points[j], w[j], lower[j], upper[j]):
            x_new = x.copy()
            x_new[j] = points[j]
            c = trial(x_new)
            n += 1
            if c is not None and c <= cost + SNAP_COST * abs(cost):
                x, cost = x_new, c
                continue  # on its neutral value: no bound is near (_on_point)
        for side, b in enumerate((lower[j], upper[j])):
            # near: within SNAP_DIST of the box, and of the bound itself unless it is 0 (a
            # bound far below the box's width, 1e-4 of [1e-4, 1], is a search over decades:
            # 5e-3 is not near it, as for statistics.at_bound); a physical edge: from anywhere
            d = abs(x[j] - b)
            edge = edges is not None and bool(edges[j, side])
            if not np.isfinite(b) or d == 0 or not edge and (d > SNAP_DIST * w[j] or (
                    b != 0 and d > SNAP_DIST * abs(b))):
                continue
            x_new = x.copy()
            x_new[j] = b
            c = trial(x_new)
            n += 1
            # a cost within SNAP_COST of the end's: the bound is as good (module notes)
            if c is not None and c <= cost + SNAP_COST * abs(cost):
                x, cost = x_new, c
                break  # on a bound: the other side is not tried
    return x, cost, n


def snap_spec(x: np.ndarray, cost: float, spec: Any,
              trial: Callable[[np.ndarray], float | None]) -> tuple[np.ndarray, float, int]:
    """:func:`snap` within ``spec``'s bounds, with its physical edges (:func:`edges_of`) and
    neutral values (:func:`points_of`): what every solver's end is settled by."""
    return snap(x, cost, spec.lower, spec.upper, trial, edges_of(spec), points_of(spec))


def _on_point(x: np.ndarray, j: int, point: float, width: float, lo: float, hi: float) -> bool:
    """Whether ``x[j]`` is to be tried on its neutral value ``point``: one is given, ``x[j]``
    is within :data:`SNAP_DIST` of its box of it but not on it, and no bound is nearer (an
    end near a bound is the bound's to settle)."""
    if not np.isfinite(point) or x[j] == point:
        return False
    d = abs(x[j] - point)
    return bool(d <= SNAP_DIST * width and d < abs(x[j] - lo) and d < abs(x[j] - hi))
