"""Levenberg–Marquardt with the box bounds solved exactly, and the test that says a point is a
minimum within the bounds: the end of the polish
(:func:`roughbrdf.fitting.solvers.search.polish_fit`).

``docs/fitting.md`` ("Polish"). Each iteration minimizes the Gauss–Newton model of the cost,
``m(p) = 1/2 |f + J p|^2``, plus the damping ``1/2 lambda |D p|^2`` (``D`` the column norms
of ``J``, Marquardt's scaling; the largest seen so far, as in MINPACK), **subject to the
bounds** ``lower <= x + p <= upper``: a small bounded linear least-squares problem on the
``k x k`` triangle of ``J``, factored once per Jacobian (:class:`GaussNewtonModel`,
:func:`bounded_step`, SciPy's BVLS). A parameter whose optimum lies on its bound therefore
reaches it in one step, where the interior-point trust region (``least_squares``' ``trf``),
whose iterates stay strictly inside, creeps towards it: on a
14-parameter RB08 fit of a Mini-Diff paint, ``trf`` spent 9,000-19,000 evaluations moving
``n_eff`` from 4.7 to 4.93 of its bound 5 and then stopped by its ``ftol`` test. ``lambda``
follows Nielsen's rule (H. B. Nielsen, *Damping parameter in Marquardt's method*,
IMM-REP-1999-05).

Converged means the model with the bounds predicts no worthwhile decrease: the undamped
bounded step from the point lowers ``m`` by at most ``tol`` times the cost. This holds at a
minimum in the interior (the gradient vanishes) and at one on the bounds (the gradient points
out of the box), and fails at a point that only stopped moving. Or the point is first-order
optimal (:func:`~roughbrdf.fitting.solvers.stationary.optimality` at most
:data:`~roughbrdf.fitting.solvers.stationary.GTOL`: a stationary point where a Jacobian column
vanishes, which the predicted decrease does not see). Flat parameters do not move
(:func:`~roughbrdf.fitting.solvers.stationary.flat`), and the end is settled on the bounds it is as
good on (:func:`~roughbrdf.fitting.solvers.stationary.snap`): ``docs/fitting.md``, "The same answer
on every machine".
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ...interrupts import held_interrupts
from ..problem.objective import Objective
from .stationary import GTOL, flat, optimality, scaling, snap_spec

__all__ = ["BoundedResult", "GaussNewtonModel", "bounded_lm", "bounded_step", "settle"]

#: Nielsen's initial damping, relative to Marquardt's scaling ``D^2``
LAMBDA0 = 1e-3
#: damping beyond which no step can change the cost (the step is below round-off)
LAMBDA_MAX = 1e16


@dataclass
class BoundedResult:
    """The outcome of :func:`bounded_lm` (the fields of ``scipy.optimize.OptimizeResult`` the fit
    reads).

    Attributes
    ----------
    x : numpy.ndarray
        The end point.
    cost : float
        ``1/2 sum(r^2)`` there (``least_squares``' convention).
    status : int
        1 converged (the bounded Gauss–Newton step predicts less than ``tol`` of the cost),
        2 the cost is zero; not converged: 3 no step lowers the cost although the model
        predicts a decrease (the damping reached :data:`LAMBDA_MAX`; e.g. an inaccurate
        finite-difference Jacobian), 0 the evaluation budget ran out.
    message : str
        The status in words.
    nfev, njev : int
        Residual and Jacobian evaluations of the polish.
    """

    x: np.ndarray
    cost: float
    status: int
    message: str
    nfev: int
    njev: int

    @property
    def success(self) -> bool:
        """Whether it converged (``status`` 1 or 2)."""
        return self.status in (1, 2)


@dataclass(frozen=True)
class GaussNewtonModel:
    """The Gauss–Newton model ``1/2 |f + J p|^2`` of the cost at one point, kept as the
    triangle ``R`` of ``J = Q R`` and ``c = Q^T f`` (``|f + J p|^2 = |c + R p|^2`` plus a
    constant): factored once per Jacobian, then solved for any damping."""

    r: np.ndarray
    c: np.ndarray

    @classmethod
    def of(cls, jac: np.ndarray, f: np.ndarray) -> GaussNewtonModel:
        """The model of residuals ``f`` with Jacobian ``jac``."""
        q, r = np.linalg.qr(jac, mode="reduced")
        return cls(r, q.T @ f)

    def step(self, x: np.ndarray, lower: np.ndarray, upper: np.ndarray,
             damping: np.ndarray | None = None) -> tuple[np.ndarray, float]:
        """:func:`bounded_step` on this model."""
        with held_interrupts():  # the first import loads compiled modules (search.sobol_points)
            from scipy.optimize import lsq_linear

        r, c = self.r, self.c
        a, b = r, -c
        if damping is not None:
            a = np.vstack([r, np.diag(np.sqrt(damping))])
            b = np.concatenate([-c, np.zeros(len(x))])
        lo, hi = lower - x, upper - x
        # lsq_linear needs lo < hi: a variable whose bounds coincide (after clipping x into the
        # box, lo <= 0 <= hi always) cannot move
        fixed = hi - lo <= 0
        lo, hi = np.where(fixed, -1.0, lo), np.where(fixed, 1.0, hi)
        p = lsq_linear(a, b, bounds=(lo, hi), method="bvls").x
        p = np.where(fixed, 0.0, np.clip(p, lo, hi))
        # the model decrease, on the triangle: 1/2 |c|^2 - 1/2 |c + R p|^2
        pred = 0.5 * float(c @ c) - 0.5 * float(np.sum((c + r @ p) ** 2))
        return p, pred


def bounded_step(jac: np.ndarray, f: np.ndarray, x: np.ndarray, lower: np.ndarray,
                 upper: np.ndarray, damping: np.ndarray | None = None
                 ) -> tuple[np.ndarray, float]:
    """The step ``p`` minimizing ``1/2 |f + J p|^2 + 1/2 sum(damping p^2)`` subject to
    ``lower <= x + p <= upper``, and the decrease of the Gauss–Newton model it predicts,
    ``1/2 |f|^2 - 1/2 |f + J p|^2``.

    Solved on the triangle ``R`` of ``J = Q R`` (:class:`GaussNewtonModel`) with
    ``scipy.optimize.lsq_linear(method="bvls")``.

    Examples
    --------
    >>> jac = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]])
    >>> f = np.array([-2.0, 1.0, 1.0])             # unbounded optimum p = (2, -1)
    >>> p, pred = bounded_step(jac, f, np.zeros(2), np.array([-5.0, -0.5]), np.full(2, 5.0))
    >>> p.round(12).tolist(), round(pred, 12)    # x2 stops on its bound -0.5
    ([2.0, -0.5], 2.375)
    """
    return GaussNewtonModel.of(jac, f).step(x, lower, upper, damping)


def bounded_lm(obj: Objective, x0: np.ndarray, tol: float, max_nfev: int | None = None
               ) -> BoundedResult:
    """Minimize ``obj`` within its bounds from ``x0`` (module notes); ``max_nfev`` caps the
    residual evaluations (default ``100 k``, ``least_squares``' default for ``k`` unknowns),
    ``tol`` is the convergence test's fraction of the cost.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> from roughbrdf.fitting import ChannelData
    >>> from roughbrdf.fitting.problem.objective import ObjectiveSpec
    >>> spec = ObjectiveSpec(rb.model("lambertian", rho=0.9), ["rho"], [0.0], [0.2],
    ...                      loss="absolute")
    >>> data = ChannelData.from_arrays([0.1, 0.3], [0.2, 0.4], [0.0, 1.0], [0.1, 0.1])
    >>> out = bounded_lm(Objective(spec, data), np.array([0.1]), 1e-10)
    >>> out.status, round(float(out.x[0]), 9)       # the optimum rho = 0.1 pi is above 0.2
    (1, 0.2)
    """
    lo, hi = obj.spec.lower, obj.spec.upper
    budget = max_nfev if max_nfev is not None else 100 * len(x0)
    x = np.clip(np.asarray(x0, dtype=float), lo, hi)
    f = obj.fun(x)
    cost, nfev, njev = 0.5 * float(f @ f), 1, 0
    lam, nu, d2 = LAMBDA0, 2.0, np.zeros(len(x))
    while True:
        if cost == 0.0:
            return BoundedResult(x, cost, 2, "the cost is zero", nfev, njev)
        jac = obj.jac(x)
        njev += 1
        model = GaussNewtonModel.of(jac, f)  # factored once for every trial step below
        d2 = np.maximum(d2, np.sum(jac * jac, axis=0))
        scale2 = scaling(d2, f, x, lo, hi)  # floored (stationary.scaling)
        frozen = flat(jac, f, x, lo, hi)
        # the step's box: a flat parameter keeps its value (module notes)
        slo, shi = np.where(frozen, x, lo), np.where(frozen, x, hi)
        if model.step(x, slo, shi)[1] <= tol * cost:
            return _settled(obj, x, cost, 1, "the bounded Gauss-Newton step predicts a "
                            f"decrease below {tol:g} of the cost", nfev, njev)
        if optimality(jac, f, x, lo, hi, scale2, frozen=frozen) <= GTOL:
            return _settled(obj, x, cost, 1, "first-order optimal (the projected gradient "
                            f"within {GTOL:g} of the scaled columns)", nfev, njev)
        while True:
            if nfev >= budget:
                return _settled(obj, x, cost, 0, "the evaluation budget (max_nfev) is used "
                                "up", nfev, njev)
            if lam > LAMBDA_MAX:
                return _settled(obj, x, cost, 3, "no step lowers the cost", nfev, njev)
            p, pred = model.step(x, slo, shi, lam * scale2)
            x_new = np.clip(x + p, lo, hi)  # round-off of x + p past a bound
            f_new = obj.fun(x_new)
            nfev += 1
            cost_new = 0.5 * float(f_new @ f_new)
            gain = (cost - cost_new) / pred if pred > 0 else -1.0
            if gain > 0:  # accepted: Nielsen's update
                lam *= max(1.0 / 3.0, 1.0 - (2.0 * gain - 1.0) ** 3)
                nu = 2.0
                x, f, cost = x_new, f_new, cost_new
                break
            lam *= nu
            nu *= 2.0


def _settled(obj: Objective, x: np.ndarray, cost: float, status: int, message: str,
             nfev: int, njev: int) -> BoundedResult:
    """The result at ``x``, its parameters near a bound tried on it first
    (:func:`~roughbrdf.fitting.solvers.stationary.snap`)."""
    x, cost, n = snap_spec(x, cost, obj.spec, _cost_of(obj))
    return BoundedResult(x, cost, status, message, nfev + n, njev)


def _cost_of(obj: Objective) -> Callable[[np.ndarray], float]:
    def trial(z: np.ndarray) -> float:
        r = obj.fun(z)
        return 0.5 * float(r @ r) if np.all(np.isfinite(r)) else math.inf
    return trial


def settle(obj: Objective, res: Any) -> Any:
    """A local fit's result (``scipy.optimize.OptimizeResult`` or :class:`BoundedResult`)
    with its end settled on the bounds it is as good on
    (:func:`~roughbrdf.fitting.solvers.stationary.snap`); ``res`` itself when nothing moved.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> from roughbrdf.fitting import ChannelData
    >>> from roughbrdf.fitting.problem.objective import ObjectiveSpec
    >>> spec = ObjectiveSpec(rb.model("lambertian", rho=0.9), ["rho"], [0.0], [1.0],
    ...                      loss="absolute")
    >>> data = ChannelData.from_arrays([0.1, 0.3], [0.2, 0.4], [0.0, 1.0], [0.0, 0.0])
    >>> res = BoundedResult(np.array([1e-9]), 1e-19, 1, "", 1, 1)
    >>> float(settle(Objective(spec, data), res).x[0])        # rho = 0 fits the zeros
    0.0
    """
    x, cost, n = snap_spec(np.asarray(res.x, dtype=float), float(res.cost), obj.spec,
                           _cost_of(obj))
    if n == 0 or np.array_equal(x, res.x):
        return res
    if isinstance(res, BoundedResult):
        return replace(res, x=x, cost=cost, nfev=res.nfev + n)
    out = copy.copy(res)
    out.x, out.cost, out.nfev = x, cost, int(res.nfev) + n
    return out
