"""Levenberg–Marquardt under box bounds *and* inequality constraints: the energy-constrained refit.

``docs/fitting.md`` ("Energy constraint"). :func:`constrained_lm` minimizes the cost
``1/2 |f(x)|^2`` of an :class:`~roughbrdf.fitting.problem.objective.Objective` subject to its bounds
and to ``g(x) <= 0`` (:class:`Limits`; for the fits, ``g_k = albedo(theta_k) - target``). It is
the bounded Levenberg–Marquardt of :mod:`roughbrdf.fitting.solvers.bounded` with the constraints
linearized in each step (a Gauss–Newton SQP step, as in the constrained least-squares methods
of Lawson & Hanson, *Solving Least Squares Problems*, 1974, ch. 23):

    minimize   1/2 |c + R p|^2 + 1/2 lambda |D p|^2
    subject to lower <= x + p <= upper,   g(x) + G p <= 0,

``R``, ``c`` the triangle of the Jacobian and the rotated residuals
(:class:`~roughbrdf.fitting.solvers.bounded.GaussNewtonModel`), ``G`` the constraints'
forward-difference
Jacobian, ``D`` Marquardt's scaling. The step is solved exactly (:func:`lsi_step`: the problem
is a *least distance* problem after a change of variables, solved by non-negative least
squares, Lawson & Hanson's LSI → LDP → NNLS, ch. 23, Algorithm LDP). A step is accepted by the
gain of the exact L1 merit function ``cost + rho sum max(0, g_k)`` (``rho`` above the step's
largest multiplier: a feasible point is then never traded for a lower cost), with Nielsen's
damping rule.

Converged means: the point satisfies the constraints (to :data:`FEASIBLE`), and the nearly
undamped step that keeps the linearized constraints predicts a decrease of the cost of at most
``tol`` of it — a
minimum in the interior, on a bound or on a constraint alike. The earlier penalty refit (a
hinge residual ``W max(0, g)``) made the cost non-smooth on the constraint, where trust-region
steps zigzag: it stopped on its evaluation budget on small synthetic TR75 sets.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ...interrupts import held_interrupts
from ..problem.objective import Objective
from .bounded import LAMBDA_MAX, BoundedResult, GaussNewtonModel
from .stationary import GTOL, flat, optimality, scaling, snap_spec

__all__ = ["BAD_LIMIT", "FEASIBLE", "Limits", "constrained_lm", "finite_limits", "lsi_step",
           "violation"]

#: Nielsen's initial damping, relative to Marquardt's scaling ``D^2`` (as bounded.LAMBDA0)
LAMBDA0 = 1e-3
#: a point is feasible when ``sum max(0, g)`` is at most this (albedo units: the fits' target
#: is 5e-4 below 1, their tolerance 1e-3 above it)
FEASIBLE = 1e-5
#: the smallest fraction of a violation a relaxed step must remove (:func:`_relaxed_step`)
MIN_RELAX = 1.0 / 64.0
#: the damping of the convergence test's step, relative to ``D^2``: enough to keep the
#: least-distance problem's triangle invertible (a parameter the residuals barely see)
TEST_DAMPING = 1e-10


@dataclass
class Limits:
    """Inequality constraints ``g(x) <= 0`` as :func:`constrained_lm` sees them.

    Attributes
    ----------
    values : callable
        ``values(x) -> g``, shape ``(m,)``; a non-finite value counts as violated.
    jac : callable
        ``jac(x, g) -> G``, shape ``(m, k)``, the Jacobian at ``x`` (``g`` its values there).
    """

    values: Callable[[np.ndarray], np.ndarray]
    jac: Callable[[np.ndarray, np.ndarray], np.ndarray]


#: stands in for a constraint value that is not finite (a model that overflows at trial
#: parameters): violated, by far more than any finite albedo excess, and finite, so that the
#: merit of two such points can be compared
BAD_LIMIT = 1e6


def finite_limits(g: np.ndarray) -> np.ndarray:
    """``g`` with its non-finite values replaced by :data:`BAD_LIMIT`."""
    g = np.asarray(g, dtype=float)
    return np.where(np.isfinite(g), g, BAD_LIMIT)


def violation(g: np.ndarray) -> float:
    """``sum max(0, g)`` (``g`` finite: :func:`finite_limits`)."""
    return float(np.sum(np.maximum(g, 0.0)))


def lsi_step(model: GaussNewtonModel, damping: np.ndarray, lo: np.ndarray, hi: np.ndarray,
             gmat: np.ndarray, h: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The step ``p`` minimizing ``1/2 |c + R p|^2 + 1/2 sum(damping p^2)`` subject to
    ``lo <= p <= hi`` and ``gmat p <= h``, and the multipliers of the rows of ``gmat``; None
    when no ``p`` satisfies them.

    Lawson & Hanson's LSI problem (ch. 23): with ``A = [R; sqrt(damping)]`` (full rank for
    positive damping) and ``A = Q T``, ``y = T p + Q^T b`` turns it into the least-distance
    problem ``min |y|`` subject to linear inequalities, solved by one non-negative least
    squares (Algorithm LDP); ``damping`` must be positive.

    Examples
    --------
    >>> from roughbrdf.fitting.solvers.bounded import GaussNewtonModel
    >>> m = GaussNewtonModel.of(np.eye(2), np.array([-2.0, -2.0]))  # optimum p = (2, 2)
    >>> p, mu = lsi_step(m, np.full(2, 1e-12), np.full(2, -5.0), np.full(2, 5.0),
    ...                  np.array([[1.0, 1.0]]), np.array([2.0]))   # p1 + p2 <= 2
    >>> p.round(9).tolist(), mu.round(6).tolist()
    ([1.0, 1.0], [1.0])
    """
    with held_interrupts():  # the first import loads compiled modules (search.sobol_points)
        from scipy.optimize import nnls

    k = model.r.shape[1]
    a = np.vstack([model.r, np.diag(np.sqrt(damping))])
    b = np.concatenate([-model.c, np.zeros(k)])
    q, t = np.linalg.qr(a, mode="reduced")
    # the constraints C p <= d: the linearized limits, then the finite bounds
    eye = np.eye(k)
    rows = [gmat, eye[np.isfinite(hi)], -eye[np.isfinite(lo)]]
    cmat = np.vstack(rows)
    d = np.concatenate([h, hi[np.isfinite(hi)], -lo[np.isfinite(lo)]])
    # p = T^-1 (y + Q^T b):  C T^-1 y <= d - C T^-1 Q^T b
    ct = np.linalg.solve(t.T, cmat.T).T  # C T^-1
    e = d - ct @ (q.T @ b)
    # LDP: min |y| subject to (-C T^-1) y >= -e; NNLS on E = [G^T; h^T], f = (0, ..., 0, 1)
    emat = np.vstack([-ct.T, -e[None, :]])
    f = np.zeros(k + 1)
    f[-1] = 1.0
    u, _ = nnls(emat, f, maxiter=50 * emat.shape[1])
    res = emat @ u - f
    if not abs(res[-1]) > 1e-12:  # the residual's last entry is 0: the constraints conflict
        return None
    y = -res[:k] / res[-1]
    p = np.linalg.solve(t, y + q.T @ b)
    mu = u / -res[-1]  # the least-distance problem's multipliers, those of C p <= d
    return np.clip(p, lo, hi), mu[:gmat.shape[0]]


def _relaxed_step(model: GaussNewtonModel, damping: np.ndarray, lo: np.ndarray,
                  hi: np.ndarray, gmat: np.ndarray, g: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray] | None:
    """:func:`lsi_step` with ``g + G p <= 0``, or, when no step within the bounds meets those
    linearized constraints (far from feasible: the linearization of an albedo of 6 asks for
    more than the box allows), with the violated ones only reduced, to ``(1 - tau) g``,
    ``tau`` = 1/2, 1/4, ... :data:`MIN_RELAX` (the usual relaxation of an SQP step; the merit
    function still decides)."""
    tau = 1.0
    while tau >= MIN_RELAX:
        step = lsi_step(model, damping, lo, hi, gmat, -g + (1.0 - tau) * np.maximum(g, 0.0))
        if step is not None:
            return step
        tau *= 0.5
    return None


def _merit(cost: float, g: np.ndarray, rho: float) -> float:
    return cost + rho * violation(g)


def constrained_lm(obj: Objective, limits: Limits, x0: np.ndarray, tol: float,
                   max_nfev: int | None = None) -> BoundedResult:
    """Minimize ``obj`` within its bounds and ``limits`` from ``x0`` (module notes);
    ``max_nfev`` caps the residual evaluations (default ``100 k``), ``tol`` is the convergence
    test's fraction of the cost. Status as
    :class:`~roughbrdf.fitting.solvers.bounded.BoundedResult`,
    and 4: the linearized constraints cannot be met within the bounds from the end point.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> from roughbrdf.fitting import ChannelData
    >>> from roughbrdf.fitting.problem.objective import ObjectiveSpec
    >>> spec = ObjectiveSpec(rb.model("lambertian", rho=0.9), ["rho"], [0.0], [1.0],
    ...                      loss="absolute")
    >>> data = ChannelData.from_arrays([0.1, 0.3], [0.2, 0.4], [0.0, 1.0], [0.2, 0.2])
    >>> lim = Limits(lambda x: np.array([x[0] - 0.5]), lambda x, g: np.array([[1.0]]))
    >>> out = constrained_lm(Objective(spec, data), lim, np.array([0.9]), 1e-10)
    >>> out.status, round(float(out.x[0]), 9)      # the optimum 0.2 pi = 0.63 is above 0.5
    (1, 0.5)
    """
    lo, hi = obj.spec.lower, obj.spec.upper
    budget = max_nfev if max_nfev is not None else 100 * len(x0)
    x = np.clip(np.asarray(x0, dtype=float), lo, hi)
    f, g = obj.fun(x), finite_limits(limits.values(x))
    cost, nfev, njev = 0.5 * float(f @ f), 1, 0
    lam, nu, d2, rho = LAMBDA0, 2.0, np.zeros(len(x)), 0.0
    while True:
        jac, gmat = obj.jac(x), limits.jac(x, g)
        njev += 1
        model = GaussNewtonModel.of(jac, f)  # factored once for every trial step below
        d2 = np.maximum(d2, np.sum(jac * jac, axis=0))
        scale2 = scaling(d2, f, x, lo, hi)  # floored (stationary.scaling)
        # the step's box: a flat parameter keeps its value (stationary.flat)
        frozen = flat(jac, f, x, lo, hi, gmat, FEASIBLE)
        slo, shi = np.where(frozen, 0.0, lo - x), np.where(frozen, 0.0, hi - x)
        test = lsi_step(model, TEST_DAMPING * scale2, slo, shi, gmat, -g)
        if test is not None:
            rho = max(rho, 2.0 * float(np.max(test[1], initial=0.0)))
            done = _converged(model, test, jac, f, x, g, gmat, scale2, frozen, obj, tol, cost)
            if done is not None:
                return _settled(obj, limits, x, cost, 1, done, nfev, njev)
        while True:
            if nfev >= budget:
                return _settled(obj, limits, x, cost, 0, "the evaluation budget (max_nfev) "
                                "is used up", nfev, njev)
            if lam > LAMBDA_MAX:
                return _settled(obj, limits, x, cost, 3, "no step lowers the cost and the "
                                "constraint violation", nfev, njev)
            step = _relaxed_step(model, lam * scale2, slo, shi, gmat, g)
            if step is None:
                return _settled(obj, limits, x, cost, 4, "the linearized constraints cannot "
                                "be met within the bounds", nfev, njev)
            p, mu = step
            rho = max(rho, 2.0 * float(np.max(mu, initial=0.0)))
            pred = _predicted(model, p, g, gmat, rho)
            trial = _Trial.at(obj, limits, np.clip(x + p, lo, hi))  # round-off past a bound
            nfev += 1
            merit0 = _merit(cost, g, rho)
            if not merit0 - trial.merit(rho) > 0 and violation(trial.g) > violation(g):
                # the constraints' curvature made the step infeasible (the Maratos effect):
                # the second-order correction, the step's linearization moved to its end
                soc = lsi_step(model, lam * scale2, slo, shi, gmat, gmat @ p - trial.g)
                if soc is not None:
                    trial = _Trial.at(obj, limits, np.clip(x + soc[0], lo, hi))
                    nfev += 1
            gain = (merit0 - trial.merit(rho)) / pred if pred > 0 else -1.0
            if gain > 0:  # accepted: Nielsen's update
                lam *= max(1.0 / 3.0, 1.0 - (2.0 * gain - 1.0) ** 3)
                nu = 2.0
                x, f, g, cost = trial.x, trial.f, trial.g, trial.cost
                break
            lam *= nu
            nu *= 2.0


@dataclass(frozen=True)
class _Trial:
    """A trial point: its residuals, constraint values and cost."""

    x: np.ndarray
    f: np.ndarray
    g: np.ndarray
    cost: float

    @classmethod
    def at(cls, obj: Objective, limits: Limits, x: np.ndarray) -> _Trial:
        f = obj.fun(x)
        return cls(x, f, finite_limits(limits.values(x)), 0.5 * float(f @ f))

    def merit(self, rho: float) -> float:
        return _merit(self.cost, self.g, rho)


def _converged(model: GaussNewtonModel, test: tuple[np.ndarray, np.ndarray], jac: np.ndarray,
               f: np.ndarray, x: np.ndarray, g: np.ndarray, gmat: np.ndarray, d2: np.ndarray,
               frozen: np.ndarray, obj: Objective, tol: float, cost: float) -> str | None:
    """Why ``x`` is a constrained minimum (module notes), or None: feasible, and the nearly
    undamped step that keeps the linearized constraints predicts no worthwhile decrease, or the
    Lagrangian's projected gradient is first-order optimal
    (:func:`~roughbrdf.fitting.solvers.stationary.optimality`, the test step's multipliers)."""
    if violation(g) > FEASIBLE:
        return None
    # the merit's violation part is within FEASIBLE (nearly dependent active constraints can
    # make rho, and so it, large): the data part alone decides
    if _predicted(model, test[0], g, gmat, 0.0) <= tol * max(cost, 1e-300):
        return f"the constrained Gauss-Newton step predicts a decrease below {tol:g} of the cost"
    extra = gmat.T @ test[1] if gmat.size else None
    if optimality(jac, f, x, obj.spec.lower, obj.spec.upper, d2, extra, frozen) <= GTOL:
        return f"first-order optimal (the projected gradient within {GTOL:g} of the scaled " \
               "columns)"
    return None


def _settled(obj: Objective, limits: Limits, x: np.ndarray, cost: float, status: int,
             message: str, nfev: int, njev: int) -> BoundedResult:
    """The result at ``x``, its parameters near a bound tried on it first where the point
    stays as feasible (:func:`~roughbrdf.fitting.solvers.stationary.snap`)."""
    allowed = max(FEASIBLE, violation(finite_limits(limits.values(x))))

    def trial(z: np.ndarray) -> float | None:
        t = _Trial.at(obj, limits, z)
        return t.cost if violation(t.g) <= allowed and math.isfinite(t.cost) else None

    x, cost, n = snap_spec(x, cost, obj.spec, trial)
    return BoundedResult(x, cost, status, message, nfev + n, njev)


def _predicted(model: GaussNewtonModel, p: np.ndarray, g: np.ndarray, gmat: np.ndarray,
               rho: float) -> float:
    """The merit decrease the linearized model predicts for the step ``p``."""
    c, r = model.c, model.r
    data = 0.5 * float(c @ c) - 0.5 * float(np.sum((c + r @ p) ** 2))
    return data + rho * (violation(g) - violation(g + gmat @ p))
