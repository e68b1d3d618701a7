"""The explicit energy constraint: models that cannot guarantee ``albedo <= 1`` are fitted under it.

``docs/fitting.md`` ("Energy constraint"). TR75 with ``rho_L``, TS67, RB08 and sums of models
can reflect more than they receive for some parameter values. After a channel's search
(:func:`roughbrdf.fitting.kinds.channels.fit_channels`), when the fitted model gains energy on the
grid :data:`~roughbrdf.fitting.results.plausibility.EXPORT_INCIDENCES_DEG` (0, 5, ... 85, 89 deg;
the test of :func:`~roughbrdf.fitting.results.plausibility.energy_gain`, the accurate
:func:`roughbrdf.albedo`),
the channel is refitted from that optimum under the constraint ``albedo(theta_i) <= 1`` at every
incidence of the grid (:func:`constrain_channel`):

* the albedo during the refit is :class:`FastAlbedo`: the specular-centred quadrature of
  :func:`roughbrdf.albedo` on a coarser grid, built once (:func:`fast_albedo_grid`), one
  vectorized model call for all 19 incidences; its error against :func:`roughbrdf.albedo`
  (:data:`FAST_ALBEDO_ACCURACY` for smooth lobes, more for lobes a few degrees wide at grazing
  incidence) is taken out by a *defect correction*: at the start of each round the difference
  accurate - fast at the current point is added to the fast albedo;
* the residuals of the fit get one penalty residual per watched incidence,
  ``W max(0, A_k(theta) - target)``, ``target = 1 -`` :data:`MARGIN`
  (:class:`ConstrainedObjective`, forward-difference Jacobian rows), with ``W^2 = lambda *
  cost`` of the start point and ``lambda = 1 / sum(excess^2)`` in the first round; the polish
  of :func:`~roughbrdf.fitting.solvers.search.polish_fit` runs on it unchanged, on
  :data:`ROUND_SAMPLES` samples of the channel, at most :data:`ROUND_NFEV` evaluations;
* after each round the accurate albedo is checked; while it exceeds ``1 +``
  :data:`~roughbrdf.fitting.results.plausibility.ENERGY_TOLERANCE` somewhere, ``lambda`` grows by
  :data:`GROWTH` (at most :data:`MAX_ROUNDS` rounds; then the fit says it could not, and the
  usual :class:`~roughbrdf.fitting.results.plausibility.EnergyWarning` follows);
* the rounds keep the refit in the unconstrained optimum's basin but do not converge on the
  constraint (the hinge makes the cost non-smooth there); the best round's point is finished
  on all samples under the constraint itself,
  :func:`~roughbrdf.fitting.solvers.constrained.constrained_lm` (:func:`_finish`, at most
  :data:`FINISH_PASSES` passes), and kept when the constraint holds.

At a constrained optimum the covariance is the data's, projected on the directions along which
the active constraints stay constant (:func:`conditional_covariance`): the uncertainties are
*conditional on the constraint* (a parameter combination pinned by ``albedo = 1`` has none).
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from ..models.base import PreparedGeometry
from ..polarization import Polarization
from .problem.objective import BAD_RESIDUAL, EPS_STEP, Objective, ObjectiveSpec
from .results.plausibility import ENERGY_TOLERANCE, EXPORT_INCIDENCES_DEG, albedo_by_incidence
from .results.statistics import Covariance
from .solvers.constrained import Limits, constrained_lm, finite_limits
from .solvers.search import POLISH_TOL, SearchOutcome, polish_fit

if TYPE_CHECKING:
    from ..models import Model
    from .problem.data import ChannelData
    from .results.result import ChannelFit

__all__ = ["ConstrainedObjective", "EnergyConstraint", "FastAlbedo", "FAST_ALBEDO_ACCURACY",
           "MAX_ROUNDS", "checked_albedo", "conditional_covariance", "constrain_channel",
           "fast_albedo", "fast_albedo_grid", "refit_constrained"]

#: stated accuracy of :func:`fast_albedo` against :func:`roughbrdf.albedo` (absolute, any
#: incidence of the grid) for every model at its default parameters and TR75/microfacet lobes
#: down to ``e = 0.02`` (tests check it; measured: 7e-3 for RB08, below 1e-3 for the others).
#: Lobes narrower than a degree at grazing incidence can be off by more: the refit corrects
#: the difference (module notes)
FAST_ALBEDO_ACCURACY = 1e-2
#: refits under the constraint at most (``lambda`` x10 and the target lowered each time)
MAX_ROUNDS = 6
#: ``W^2 = lambda * cost``, ``lambda = LAMBDA0 / sum(excess^2)`` in the first round: the
#: penalty at the unconstrained optimum about the data's cost
LAMBDA0 = 1.0
#: ``lambda`` grows by this factor each round that leaves the albedo above ``1 + 1e-3``
GROWTH = 100.0
#: the first round's target: ``1 - MARGIN`` (the penalty leaves a small violation)
MARGIN = 5e-4
#: incidences whose albedo at a round's start is below this are not evaluated in that round
#: (the check at its end sees all: one that rose above 1 is watched in the next round)
WATCH = 0.8
#: the penalty's weight is set against a data cost of at least ``COST_FLOOR^2 N``
COST_FLOOR = 1e-2
#: the accurate albedo is computed only at the incidences where the fast one is above
#: ``1 - SCREEN_MARGIN`` (:func:`checked_albedo`; the fast one's error is below 1e-2 but for
#: lobes narrower than a degree at grazing incidence, and the fit's plausibility check still
#: uses the accurate albedo at every incidence and warns)
SCREEN_MARGIN = 0.05
#: samples of the channel the rounds fit (the best round's point is then finished on all)
ROUND_SAMPLES = 1000
#: residual evaluations of one round at most (each costs a Jacobian too: one fast albedo per
#: free parameter; 10 per parameter made a 14-parameter RB08 refit 20-45 s per C2_Black channel)
ROUND_NFEV = 30
#: constrained refits on all samples at most (the fast albedo's defect correction renewed at
#: each one's start; one suffices but for lobes the fast albedo resolves poorly)
FINISH_PASSES = 3
#: residual evaluations of one of them at most, per free parameter (``least_squares``' own)
PASS_NFEV = 100
#: an incidence is active when its albedo is within this of the target (the solver meets the
#: corrected fast albedo's target to ~1e-7; the accurate albedo differs from it by ~1e-4)
ACTIVE_SLACK = 2e-4
#: (largest incidence in degrees, n_psi) of the fast quadrature: more azimuths near grazing,
#: where the lobe is squeezed against the horizon
N_PSI: tuple[tuple[float, int], ...] = ((60.0, 32), (75.0, 64), (90.0, 192))
#: radial Gauss-Legendre panels (graded toward the specular direction) and their order
N_PANELS, ORDER = 12, 6


def _rho_nodes(n_panels: int, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes/weights on [0, 1] in units of rho_max, graded geometrically toward 0 (as
    :func:`roughbrdf.albedo`)."""
    x, w = np.polynomial.legendre.leggauss(order)
    edges = np.concatenate([[0.0], np.geomspace(1e-4 / math.pi, 1.0, n_panels)])
    a, b = edges[:-1, None], edges[1:, None]
    return (0.5 * (b - a) * x + 0.5 * (a + b)).ravel(), (0.5 * (b - a) * w).ravel()


@dataclass(frozen=True)
class FastAlbedo:
    """The quadrature of :func:`fast_albedo` at fixed incidences: geometry and weights.

    Attributes
    ----------
    theta_deg : tuple of float
        The incidences (degrees).
    geometry : PreparedGeometry
        Every node of every incidence, flattened (one model call).
    weights : numpy.ndarray
        Quadrature weight of each node (``sin(rho) rho_max w_u 2 pi / n_psi``).
    which : numpy.ndarray
        The incidence (position in ``theta_deg``) of each node.
    """

    theta_deg: tuple[float, ...]
    geometry: PreparedGeometry
    weights: np.ndarray
    which: np.ndarray

    def __call__(self, model: Model) -> np.ndarray:
        """The albedo of ``model`` at :attr:`theta_deg` (one vectorized model call)."""
        f = np.asarray(model.evaluate_prepared(self.geometry, "brdf_cos"), dtype=float)
        return np.bincount(self.which, weights=f * self.weights, minlength=len(self.theta_deg))


def _incidence_nodes(t: float, n_psi: int, u: np.ndarray, wu: np.ndarray
                     ) -> tuple[np.ndarray, ...]:
    """``(theta_r, phi, weight)`` of the nodes of incidence ``t`` (radians), flattened: the
    specular-centred polar grid of :func:`roughbrdf.albedo`."""
    psi = (np.arange(n_psi) + 0.5) * (2 * math.pi / n_psi)
    cp, sp = np.cos(psi)[:, None], np.sin(psi)[:, None]
    sz, sx = math.cos(t), math.sin(t)
    tx, ty, tz = cp * sz, sp, -cp * sx  # tangent t(psi) = cos psi e1 + sin psi e2
    rho_max = np.arctan2(sz, -tz)  # the horizon along each ray
    rho = u[None, :] * rho_max
    cr, sr = np.cos(rho), np.sin(rho)
    wx, wy = cr * sx + sr * tx, sr * ty
    wz = np.clip(cr * sz + sr * tz, 0.0, 1.0)
    weight = sr * rho_max * wu[None, :] * (2 * math.pi / n_psi)
    return np.arccos(wz).ravel(), np.arctan2(wy, wx).ravel(), weight.ravel()


@functools.lru_cache(maxsize=64)
def fast_albedo_grid(theta_deg: tuple[float, ...] = EXPORT_INCIDENCES_DEG) -> FastAlbedo:
    """The :class:`FastAlbedo` of ``theta_deg`` (built once and cached: the fit evaluates it
    hundreds of times)."""
    u, wu = _rho_nodes(N_PANELS, ORDER)
    parts: list[tuple[np.ndarray, ...]] = []
    for j, deg in enumerate(theta_deg):
        n_psi = next(n for top, n in N_PSI if deg <= top)
        tr, ph, w = _incidence_nodes(math.radians(deg), n_psi, u, wu)
        parts.append((np.full(tr.shape, math.radians(deg)), tr, ph, w, np.full(tr.shape, j)))
    ti, tr, ph, w, which = (np.concatenate(p) for p in zip(*parts, strict=True))
    gamma = Polarization.parse(None).kernel_gamma()  # unpolarized, as rb.albedo's default
    return FastAlbedo(tuple(float(t) for t in theta_deg), PreparedGeometry(ti, tr, ph, gamma),
                      w, which.astype(np.intp))


def fast_albedo(model: Model, theta_deg: tuple[float, ...] = EXPORT_INCIDENCES_DEG
                ) -> np.ndarray:
    """The albedo of ``model`` at ``theta_deg`` on the coarse quadrature (module notes; good
    to :data:`FAST_ALBEDO_ACCURACY` for lobes wider than a few degrees).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> a = fast_albedo(rb.model("lambertian", rho=0.5))
    >>> a.shape, bool(abs(a - 0.5).max() < 1e-5)
    ((19,), True)
    """
    return fast_albedo_grid(tuple(float(t) for t in theta_deg))(model)


@dataclass(eq=False)
class ConstrainedObjective(Objective):
    """An :class:`~roughbrdf.fitting.problem.objective.Objective` with one penalty residual per
    incidence of the grid appended: ``weight * max(0, A_k(theta) + bias_k - target)``.

    ``A`` is :func:`fast_albedo`; ``bias`` its defect correction (accurate - fast at the
    round's start). :meth:`fun` and :meth:`jac` are what ``least_squares`` and the bounded
    Levenberg-Marquardt call; the statistics use the plain data objective.
    """

    weight: float = 1.0
    target: float = 1.0
    bias: np.ndarray = field(default_factory=lambda: np.zeros(len(EXPORT_INCIDENCES_DEG)))
    #: positions (in the grid) of the incidences watched: the others are far below 1
    watch: np.ndarray = field(default_factory=lambda: np.arange(len(EXPORT_INCIDENCES_DEG)))
    albedo_evals: int = 0

    def albedo(self, theta: np.ndarray, where: np.ndarray | None = None) -> np.ndarray:
        """The corrected fast albedo at ``theta``, at the grid positions ``where`` (default
        :attr:`watch`)."""
        self.albedo_evals += 1
        where = self.watch if where is None else where
        degs = tuple(float(EXPORT_INCIDENCES_DEG[k]) for k in where)
        return fast_albedo(self.model_at(theta), degs) + self.bias[where]

    def penalty(self, theta: np.ndarray, where: np.ndarray | None = None) -> np.ndarray:
        """The penalty residuals at ``theta`` (large where the albedo is not finite)."""
        p = self.weight * np.maximum(0.0, self.albedo(theta, where) - self.target)
        # a model that overflows at trial parameters: a large finite value, as for the data
        return np.where(np.isfinite(p), p, BAD_RESIDUAL)

    def fun(self, theta: np.ndarray) -> np.ndarray:
        """Data residuals, then the penalty residuals of the watched incidences."""
        return np.concatenate([super().fun(theta), self.penalty(theta)])

    def jac(self, theta: np.ndarray, k: float | None = None) -> np.ndarray:
        """The data Jacobian, then the penalty's forward differences: one albedo of the
        incidences where the penalty acts per parameter (elsewhere its rows are 0)."""
        theta = np.asarray(theta, dtype=float)
        p0 = self.penalty(theta)
        rows = np.zeros((p0.size, theta.size))
        acting = np.flatnonzero(p0 > 0)
        if acting.size:  # the hinge is flat where the albedo is below the target
            where = self.watch[acting]
            for j in range(theta.size):
                t = theta.copy()
                h = _step(self.spec, theta, j)
                t[j] += h
                rows[acting, j] = (self.penalty(t, where) - p0[acting]) / h
        return np.vstack([super().jac(theta, k), rows])


@dataclass(eq=False)
class AlbedoLimits:
    """The constraint ``A_k(theta) + bias_k - target <= 0`` at the watched incidences of the
    grid, as :class:`~roughbrdf.fitting.solvers.constrained.Limits` for
    :func:`~roughbrdf.fitting.solvers.constrained.constrained_lm`.

    ``A`` is :func:`fast_albedo`; ``bias`` its defect correction (accurate - fast at the
    pass's start point); the Jacobian is forward differences (one fast albedo per parameter).
    """

    spec: ObjectiveSpec
    bias: np.ndarray
    #: positions (in the grid) of the incidences watched: the others are far below 1
    watch: np.ndarray
    target: float = 1.0 - 5e-4
    albedo_evals: int = 0

    def albedo(self, theta: np.ndarray) -> np.ndarray:
        """The corrected fast albedo at ``theta`` at the watched incidences."""
        self.albedo_evals += 1
        degs = tuple(float(EXPORT_INCIDENCES_DEG[k]) for k in self.watch)
        return fast_albedo(self.spec.model_at(theta), degs) + self.bias[self.watch]

    def values(self, theta: np.ndarray) -> np.ndarray:
        """``g(theta)``: the albedo's excess over the target (non-finite for a model that
        overflows; the solver counts it as violated)."""
        return self.albedo(np.asarray(theta, dtype=float)) - self.target

    def jac(self, theta: np.ndarray, g: np.ndarray) -> np.ndarray:
        """Forward differences of :meth:`values` (``g`` its values at ``theta``)."""
        theta = np.asarray(theta, dtype=float)
        rows = np.zeros((self.watch.size, theta.size))
        g0 = finite_limits(g)
        for j in range(theta.size):
            t = theta.copy()
            h = _step(self.spec, theta, j)
            t[j] += h
            rows[:, j] = (finite_limits(self.values(t)) - g0) / h
        return rows

    def limits(self) -> Limits:
        """The solver's view."""
        return Limits(self.values, self.jac)


def _step(spec: ObjectiveSpec, theta: np.ndarray, j: int, rel: float = EPS_STEP) -> float:
    """A finite-difference step of parameter ``j`` that stays inside its bounds."""
    span = spec.upper[j] - spec.lower[j]
    h = rel * max(abs(theta[j]), 1e-3 * span if math.isfinite(span) else 1e-3, 1e-8)
    return -h if theta[j] + h > spec.upper[j] else h


@dataclass
class EnergyConstraint:
    """What the constraint did to one channel (``fit.json``'s ``energy_constraint``).

    Attributes
    ----------
    active : bool
        The refit ran and the constraint holds some incidence at ``albedo = 1``.
    theta_deg : list of float
        The incidences (degrees) where it is active.
    max_albedo : float
        The accurate albedo's maximum over the grid at the result.
    satisfied : bool
        That maximum is at most ``1 + ENERGY_TOLERANCE``.
    unconstrained_max_albedo : float
        The maximum before the refit.
    rounds : int
        Refits run.
    elapsed : float
        Seconds the refits took.
    """

    active: bool
    theta_deg: list[float]
    max_albedo: float
    satisfied: bool
    unconstrained_max_albedo: float
    rounds: int
    elapsed: float

    def to_dict(self) -> dict[str, Any]:
        """The ``energy_constraint`` entry of a channel in ``fit.json``."""
        return {"active": self.active, "theta_deg": self.theta_deg,
                "max_albedo": self.max_albedo, "satisfied": self.satisfied,
                "unconstrained_max_albedo": self.unconstrained_max_albedo,
                "rounds": self.rounds, "elapsed_s": self.elapsed,
                "grid_deg": list(EXPORT_INCIDENCES_DEG)}

    def note(self) -> str:
        """The words added to the channel's message (and so to the report)."""
        where = ", ".join(f"{t:g}" for t in self.theta_deg)
        if not self.satisfied:
            return (f"; energy constraint could not bring the albedo to 1 in {self.rounds} "
                    f"refits (max {self.max_albedo:.4g})")
        if not self.theta_deg:  # the refit ended inside the constraint, not on it
            return (f"; refitted under the energy constraint (albedo {self.max_albedo:.4g} "
                    f"<= 1, the constraint not active at the result)")
        return (f"; energy constraint active (albedo <= 1) at theta_i = {where} deg, "
                f"uncertainties conditional on it")


def conditional_covariance(fit: ChannelFit, obj: Objective, active: list[int]) -> ChannelFit:
    """``fit`` with its covariance projected on the directions that keep the albedo at the
    ``active`` incidences (positions in the grid) constant: ``C - C G (G^T C G)^-1 G^T C``,
    ``G`` the albedo's gradients (central differences of :func:`fast_albedo`; 0 for the
    scale; the parameters at a bound, NaN in ``C``, left out). The uncertainties conditional
    on the constraint."""
    names = list(fit.free) + (["scale"] if fit.free_scale else [])
    cov = np.array(fit.covar, dtype=float)
    keep = [i for i, nm in enumerate(names) if np.isfinite(cov[i, i])]
    if not active or not keep:  # nothing pinned, or no covariance to project
        return fit
    theta = np.array([fit.params[nm] for nm in fit.free], dtype=float)
    grad = np.zeros((len(names), len(active)))
    for j in (i for i in keep if i < len(fit.free)):
        h = abs(_step(obj.spec, theta, j, rel=1e-5))
        tp, tm = theta.copy(), theta.copy()
        tp[j] = min(theta[j] + h, obj.spec.upper[j])
        tm[j] = max(theta[j] - h, obj.spec.lower[j])
        diff = fast_albedo(obj.model_at(tp)) - fast_albedo(obj.model_at(tm))
        grad[j] = diff[active] / (tp[j] - tm[j])
    out = np.full_like(cov, np.nan)
    out[np.ix_(keep, keep)] = _project(cov[np.ix_(keep, keep)], grad[keep])
    conditional = Covariance(out, names)
    sd = conditional.stderr()
    stderr = dict(fit.stderr)
    stderr.update({nm: float(s) for nm, s in zip(names, sd, strict=True) if nm != "scale"})
    return replace(fit, covar=out, stderr=stderr, correl=conditional.correl(),
                   scale_stderr=float(sd[-1]) if fit.free_scale else fit.scale_stderr)


def checked_albedo(model: Model) -> np.ndarray:
    """The albedo of ``model`` on the grid as the constraint checks it: the accurate
    :func:`roughbrdf.albedo` at the incidences where :func:`fast_albedo` is within
    :data:`SCREEN_MARGIN` of 1 or above (or not finite), the fast one elsewhere (far below 1:
    its error cannot reach the tolerance there, and the accurate one costs 5 ms per incidence
    against 0.1 ms)."""
    out = fast_albedo(model)
    near = np.flatnonzero(~(out < 1.0 - SCREEN_MARGIN))
    if near.size:  # the accurate albedo only where it can matter
        out[near] = albedo_by_incidence(model, [EXPORT_INCIDENCES_DEG[k] for k in near])
    return out


def _project(c: np.ndarray, g: np.ndarray) -> np.ndarray:
    """``C - C G (G^T C G)^-1 G^T C`` computed stably: in units of the standard errors, on the
    independent directions of the gradients ``G`` (the active albedos' gradients are often
    nearly parallel), symmetric."""
    d = np.sqrt(np.diag(c))
    d = np.where(d > 0, d, 1.0)  # a parameter without variance keeps its unit
    cn = c / np.outer(d, d)
    u, sv, _ = np.linalg.svd(g * d[:, None], full_matrices=False)
    if sv.size == 0 or not sv[0] > 0:  # no gradient: nothing is pinned
        return c
    q = u[:, sv > 1e-8 * sv[0]]
    cq = cn @ q
    pn = cn - cq @ np.linalg.solve(q.T @ cq, cq.T)
    pn = 0.5 * (pn + pn.T)
    return pn * np.outer(d, d)


def _round(obj: ConstrainedObjective, theta: np.ndarray, accurate: np.ndarray,
           max_nfev: int | None) -> tuple[Any, np.ndarray]:
    """One refit of ``obj`` from ``theta`` (at most :data:`ROUND_NFEV` evaluations) with
    the fast albedo corrected to ``accurate`` there; returns the local fit and the accurate
    albedo at its end."""
    obj.bias = accurate - fast_albedo(obj.model_at(theta))
    obj.watch = np.flatnonzero(~(accurate < WATCH))  # NaN watched too
    res = polish_fit(obj, theta, ROUND_NFEV if max_nfev is None else min(max_nfev, ROUND_NFEV))
    return res, checked_albedo(obj.model_at(res.x))


def _subsample(data: ChannelData) -> ChannelData:
    """The rounds' samples: :data:`ROUND_SAMPLES` evenly spread over the channel (all when
    there are not many more)."""
    if data.n <= 2 * ROUND_SAMPLES:  # a small channel: the rounds see all of it
        return data
    return data.take(np.unique(np.linspace(0, data.n - 1, ROUND_SAMPLES).astype(np.intp)))


@dataclass
class _Rounds:
    """The state of the rounds: the best point so far and what it came with."""

    ok: bool = False
    rank: float = math.inf
    theta: np.ndarray | None = None
    result: Any = None
    accurate: np.ndarray | None = None
    lam: float = 0.0
    count: int = 0

    def offer(self, ok: bool, rank: float, theta: np.ndarray, result: Any,
              accurate: np.ndarray, lam: float) -> None:
        """Keep this round if it satisfies the constraint at a lower cost, or if nothing
        satisfies it yet and its albedo is lower."""
        if self.theta is None or (not ok, rank) < (not self.ok, self.rank):
            self.ok, self.rank, self.theta, self.result = ok, rank, theta, result
            self.accurate, self.lam = accurate, lam


def _run_rounds(obj: ConstrainedObjective, theta: np.ndarray, accurate: np.ndarray,
                max_nfev: int | None, tried: list[dict[str, Any]]) -> _Rounds:
    """The rounds on ``obj`` (the subsample) from ``theta``, ``lambda`` growing until the
    accurate albedo is at most ``1 + ENERGY_TOLERANCE`` or :data:`MAX_ROUNDS` ran."""
    cost0 = max(obj.cost(theta), COST_FLOOR ** 2 * obj.n)
    excess = np.maximum(0.0, accurate - 1.0)
    # the first weight makes the penalty at the start about the data's cost: a stronger one
    # throws the refit far from the optimum, into a worse basin (measured on C2_Black)
    lam = LAMBDA0 / max(float(np.sum(excess ** 2)), 1e-12)
    obj.target = 1.0 - MARGIN
    state = _Rounds()
    for state.count in range(1, MAX_ROUNDS + 1):
        obj.weight = math.sqrt(lam * cost0)
        res, accurate = _round(obj, theta, accurate, max_nfev)
        theta = np.asarray(res.x, dtype=float)
        top = float(np.nanmax(accurate))
        ok = top <= 1 + ENERGY_TOLERANCE
        data_cost = 0.5 * float(np.sum(Objective.fun(obj, theta) ** 2))
        tried.append({"x0": tried[-1]["x"] if tried else theta.tolist(), "x": theta.tolist(),
                      "cost": data_cost, "stage": "energy",
                      "origin": f"energy round {state.count}"})
        state.offer(ok, data_cost if ok else top, theta, res, accurate, lam)
        if ok:
            break
        lam *= GROWTH  # the violation the penalty leaves falls as 1/lambda
    return state


def _finish(spec: ObjectiveSpec, data: ChannelData, state: _Rounds, max_nfev: int | None,
            tried: list[dict[str, Any]]) -> int:
    """The refit of the best round's point on all samples of ``data`` under the constraint
    itself (:func:`~roughbrdf.fitting.solvers.constrained.constrained_lm`, the fast albedo corrected
    at each pass's start), to convergence; a pass that ends with the accurate albedo above the
    tolerance is followed by another from its end (at most :data:`FINISH_PASSES`). Kept when
    it satisfies the constraint, or lowers the albedo of rounds that did not (``state``
    updated); else the round's point stands. Returns the residual evaluations it made."""
    assert state.theta is not None and state.accurate is not None  # one round ran
    if data.n == 0:
        return 0
    nfev = 0
    obj = Objective(spec, data)
    budget = PASS_NFEV * state.theta.size if max_nfev is None else max_nfev
    theta, accurate = state.theta, state.accurate
    for k in range(1, FINISH_PASSES + 1):
        limits = AlbedoLimits(spec, accurate - fast_albedo(spec.model_at(theta)),
                              np.flatnonzero(~(accurate < WATCH)), 1.0 - MARGIN)
        res = constrained_lm(obj, limits.limits(), theta, POLISH_TOL, budget)
        nfev += res.nfev
        theta = np.asarray(res.x, dtype=float)
        accurate = checked_albedo(spec.model_at(theta))
        tried.append({"x0": tried[-1]["x"], "x": theta.tolist(), "stage": "energy",
                      "cost": float(res.cost), "origin": f"energy finish {k}"})
        state.count += 1
        ok = not np.nanmax(accurate) > 1 + ENERGY_TOLERANCE
        if ok or (not state.ok and np.nanmax(accurate) < np.nanmax(state.accurate)):
            state.theta, state.result, state.accurate = theta, res, accurate
            state.ok = ok
        if ok:
            break
    return nfev


def constrain_channel(spec: ObjectiveSpec, data: ChannelData, outcome: SearchOutcome,
                      max_nfev: int | None = None
                      ) -> tuple[SearchOutcome, EnergyConstraint | None]:
    """Refit one channel under ``albedo <= 1`` on the grid when its search's optimum gains
    energy (module notes); ``(outcome, None)`` when it does not.

    The rounds run on :data:`ROUND_SAMPLES` samples of the channel; the best round's point is
    then refitted on all of them under the constraint (:func:`_finish`). Returns the outcome
    at the constrained optimum (the refits added to ``tried`` with stage ``"energy"``) and
    what the constraint did. The round with the lowest cost among those that satisfy the
    constraint is kept; when none does, the one with the lowest albedo.
    """
    if spec.model.conserves_energy:  # by construction: nothing to check or constrain (the
        return outcome, None         # fit's plausibility check still computes its albedo)
    t0 = time.perf_counter()
    theta = np.asarray(outcome.theta, dtype=float)
    # plausibility.energy_gain's test (every channel of every candidate and cross-validation
    # fold passes here), on the albedo the rounds start from
    accurate = checked_albedo(spec.model_at(theta))
    if not np.any(accurate > 1 + ENERGY_TOLERANCE):  # conserves energy: nothing to constrain
        return outcome, None
    tried = list(outcome.tried)
    sub = ConstrainedObjective(spec, _subsample(data))
    state = _run_rounds(sub, theta, accurate, max_nfev, tried)
    finish_nfev = _finish(spec, data, state, max_nfev, tried)
    assert state.theta is not None and state.accurate is not None  # one round ran
    # active: where the constraint holds the albedo at the target (to the accurate albedo's
    # agreement with the corrected fast one)
    active = [k for k, a in enumerate(state.accurate) if a >= 1.0 - MARGIN - ACTIVE_SLACK]
    info = EnergyConstraint(
        active=bool(active), theta_deg=[float(EXPORT_INCIDENCES_DEG[k]) for k in active],
        max_albedo=float(np.nanmax(state.accurate)), satisfied=state.ok,
        unconstrained_max_albedo=float(np.nanmax(accurate)), rounds=state.count,
        elapsed=time.perf_counter() - t0)
    nfev = outcome.explore_nfev + sub.nfev + finish_nfev
    return SearchOutcome(state.theta, state.result, tried, nfev), info


def refit_constrained(spec: ObjectiveSpec, data: ChannelData, theta: np.ndarray,
                      max_nfev: int | None = None
                      ) -> tuple[SearchOutcome, EnergyConstraint] | None:
    """The refit of a constrained optimum ``theta`` on other samples of its channel (a
    cross-validation fold): :func:`_finish` from ``theta`` directly, under the constraint
    itself, without the unconstrained search and the penalty rounds (which start from the
    unconstrained optimum). ``theta`` must satisfy the constraint; None when it does not, or
    when the refit does not end satisfying it (the caller then fits as usual).

    A fold's constrained optimum is near the full fit's: the finish reaches it in a few
    steps, where the usual path first leaves the feasible set (a local fit without the
    constraint) and comes back (``docs/fitting.md``, "Model choice": measured on C2_Black,
    TR75's CV score in 0.68 s instead of 1.5-2.0 s).
    """
    t0 = time.perf_counter()
    accurate = checked_albedo(spec.model_at(theta))
    if np.any(~(accurate <= 1 + ENERGY_TOLERANCE)):  # infeasible (or NaN): the usual path
        return None
    if not np.any(accurate >= WATCH):  # the constraint is far at every incidence: the fold's
        return None                    # optimum is the unconstrained one (the usual path)
    tried: list[dict[str, Any]] = [{"x0": theta.tolist(), "x": theta.tolist(), "cost": math.nan,
                                    "stage": "energy", "origin": "refit from the optimum"}]
    state = _Rounds(ok=True, theta=theta, accurate=accurate)
    nfev = _finish(spec, data, state, max_nfev, tried)
    if not state.ok or state.result is None:
        return None
    assert state.theta is not None and state.accurate is not None  # set by _finish
    active = [k for k, a in enumerate(state.accurate) if a >= 1.0 - MARGIN - ACTIVE_SLACK]
    info = EnergyConstraint(
        active=bool(active), theta_deg=[float(EXPORT_INCIDENCES_DEG[k]) for k in active],
        max_albedo=float(np.nanmax(state.accurate)), satisfied=True,
        unconstrained_max_albedo=math.nan, rounds=state.count,
        elapsed=time.perf_counter() - t0)
    return SearchOutcome(state.theta, state.result, tried, nfev), info
