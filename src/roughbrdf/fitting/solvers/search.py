"""The global search of one channel: Sobol screening, local fits from several starts, polish.

``docs/fitting.md`` ("Global search"): exactly ``starts`` local fits
(``scipy.optimize.least_squares``, trust-region reflective, box bounds) per channel: one from the
model's own values, one from the previous channel's optimum when there is one and ``starts >=
2`` (a warm start), for a model with several lobes up to two read off the channel's peaks (a
narrow lobe at the peak's width, a second at its haze:
:mod:`~roughbrdf.fitting.problem.lobe_starts`; at least :data:`MIN_SOBOL` Sobol starts are
kept), and the rest from scrambled Sobol points (:func:`sobol_points`) in the bounds
of the free parameters, chosen by :func:`screen` among ``screen`` candidates (one model
evaluation each: the lowest cost, kept at least :data:`SCREEN_DIST` of the bounds apart).
When a channel has more than ``subsample``
samples, the local fits explore a fixed random subsample (loose tolerance
:data:`EXPLORE_TOL`: they only need to find the basin) and the ``polish`` best distinct end
points are refined on all samples (:func:`polish_fit`, :data:`POLISH_TOL`); when the best has a
lobe switched off, it is polished again with its lobes reopened at each data start's widths
(:func:`~roughbrdf.fitting.problem.lobe_starts.reopened`); the best is the result.

SciPy is imported when a search runs, not with this module.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ...interrupts import held_interrupts
from ..problem.lobe_starts import MAX_DATA_STARTS, lobe_starts, reopened
from ..problem.objective import Objective, ObjectiveSpec
from ..problem.search_options import SearchOptions
from .bounded import bounded_lm, settle

if TYPE_CHECKING:
    from ..problem.data import ChannelData

__all__ = ["MultiStart", "SearchOptions", "SearchOutcome", "local_fit", "polish_fit",
           "progress_bar", "screen", "sobol_points", "CHOICE_TOL", "EXPLORE_TOL", "POLISH_TOL",
           "POLISH_ROUND", "POLISHED_TIE", "SCREEN_DIST", "MIN_SOBOL", "first_best"]

#: tolerance (ftol, xtol, gtol) of the exploring local fits
EXPLORE_TOL = 1e-4
#: tolerance of the polish on all samples
POLISH_TOL = 1e-8
#: residual evaluations of one round of ``least_squares`` in the polish before the bounded
#: Levenberg-Marquardt (:mod:`.bounded`) takes a turn (:func:`polish_fit`); a fit that
#: converges within it ends exactly as a single ``least_squares`` call
POLISH_ROUND = 100
#: screened starts are kept at least this far apart (max-norm, in units of the bounds)
SCREEN_DIST = 0.15
#: end points of the exploration closer than this (in units of the bounds, every parameter)
#: are one point. The exploring fits end at EXPLORE_TOL on a subsample: ends of one basin
#: differ by a few 1e-3 of the box (measured on C2_Black's coated metallic candidate, where
#: with 1e-3 two such ends took both polish slots on one machine and not on another)
DISTINCT_END = 0.05
#: end points whose costs differ by at most this fraction are equally good: the first (in the
#: order of the starts) is kept, so that rounding (1e-13 of a cost between AVX2 and AVX-512
#: kernels) cannot choose between them. Not more: the exploring fits of a small channel end
#: by ``ftol`` (EXPLORE_TOL), 1e-8 apart, and the lowest of them is the nearest the optimum
CHOICE_TOL = 1e-12
#: the same for the polished ends (on all samples, to ``POLISH_TOL``): ends within this fraction
#: of the lowest cost are equally good, the first (in the order of the starts) is kept. Two
#: ends whose normalized costs differ by ``d`` of themselves are ``sqrt(d N)`` standard errors
#: apart at most along any parameter (a 1-sigma change raises the cost by 1/N of itself): 1e-9
#: is at most 0.01 sigma for N = 1e5 samples, and 1e4 times the rounding between machines.
#: Measured: C2_Black's two Beckmann lobes at 465 nm end at two near-mirror points (the lobes
#: swapped, ``w2`` to ``1 - w2``) whose costs differ by 2.8e-13 with AVX2 kernels and 1.1e-12
#: with the host's: with 1e-12 the two machines kept different ones
POLISHED_TIE = 1e-9
X_SCALE = "jac"
#: Sobol starts kept when data starts (:mod:`~roughbrdf.fitting.problem.lobe_starts`) take
#: the others' places: the box is still explored beyond what the data suggest
MIN_SOBOL = 2


@dataclass
class SearchOutcome:
    """The result of one channel's search.

    Attributes
    ----------
    theta : numpy.ndarray
        The best point (free parameters).
    result : scipy.optimize.OptimizeResult or None
        Its local fit.
    tried : list of dict
        Every local fit: ``{"x0", "x", "cost", "stage", "origin"}`` with ``stage``
        ``"single"`` (on all samples, no polish), ``"explore"`` (on the subsample) or ``"full"``
        (polish), and ``origin`` where its start came from: ``"model"`` (the model's values),
        ``"previous channel"`` (its optimum), ``"data"`` (the data's peak widths, models with
        several lobes), ``"sobol"`` or, for a polish, ``"explored"``.
    explore_nfev : int
        Model evaluations of the exploration on the subsample (0 without one).
    """

    theta: np.ndarray
    result: Any
    tried: list[dict[str, Any]] = field(default_factory=list)
    explore_nfev: int = 0


def sobol_points(lower: np.ndarray, upper: np.ndarray, n: int, seed: Any) -> np.ndarray:
    """``n`` scrambled Sobol points (:class:`scipy.stats.qmc.Sobol`) in the box, shape (n, d).

    Examples
    --------
    >>> p = sobol_points(np.array([0.0, 1.0]), np.array([1.0, 3.0]), 5, seed=0)
    >>> p.shape, bool(((p >= [0, 1]) & (p <= [1, 3])).all())
    ((5, 2), True)
    """
    d = len(lower)
    if n <= 0:
        return np.empty((0, d))
    # Ctrl-C held while SciPy's compiled modules load and Sobol's direction numbers are read
    # on first use: an interrupted extension-module initialization made Python abort at exit
    # ("Fatal Python error") instead of ending with status 130 (roughbrdf.interrupts)
    with held_interrupts():
        from scipy.stats import qmc

        sampler = qmc.Sobol(d, scramble=True, seed=seed)
    m = max(0, math.ceil(math.log2(n)))
    return lower + sampler.random_base2(m)[:n] * (upper - lower)


def screen(obj: Objective, candidates: np.ndarray, k: int) -> list[np.ndarray]:
    """The ``k`` best candidates by cost (one model evaluation each), skipping points closer
    than :data:`SCREEN_DIST` (in units of the bounds) to a better one already kept; filled up
    with the next best when too few are far apart."""
    if k <= 0 or candidates.shape[0] == 0:
        return []
    if candidates.shape[0] <= k:
        return list(candidates)
    costs = np.array([obj.cost(c) for c in candidates])
    order = np.argsort(costs, kind="stable")
    lo, hi = obj.spec.lower, obj.spec.upper
    u = (candidates - lo) / (hi - lo)
    kept: list[int] = []
    for i in order:
        if all(np.max(np.abs(u[i] - u[j])) >= SCREEN_DIST for j in kept):
            kept.append(int(i))
        if len(kept) == k:
            break
    for i in order:
        if len(kept) == k:
            break
        if int(i) not in kept:
            kept.append(int(i))
    return [candidates[i] for i in kept]


def local_fit(obj: Objective, x0: np.ndarray, tol: float, max_nfev: int | None) -> Any:
    """One ``least_squares`` (trf, ``x_scale="jac"``) of ``obj`` from ``x0`` with the
    compiled finite-difference Jacobian."""
    with held_interrupts():  # the first import loads compiled modules (see sobol_points)
        from scipy.optimize import least_squares

    return least_squares(obj.fun, x0, jac=obj.jac, bounds=(obj.spec.lower, obj.spec.upper),
                         method="trf", x_scale=X_SCALE, max_nfev=max_nfev,
                         ftol=tol, xtol=tol, gtol=tol)


def polish_fit(obj: Objective, x0: np.ndarray, max_nfev: int | None) -> Any:
    """The polish of one end point on all samples (``docs/fitting.md``, "Polish").

    Rounds of :data:`POLISH_ROUND` residual evaluations of :func:`local_fit` (``trf``) at
    :data:`POLISH_TOL`; after each round that has not converged, one round of the bounded
    Levenberg-Marquardt :func:`roughbrdf.fitting.solvers.bounded.bounded_lm` from its end point.
    ``trf``
    keeps the iterates strictly inside the bounds and so creeps towards an optimum on a bound
    (thousands of evaluations on a 14-parameter RB08 paint fit, stopping short of it); the
    bounded steps land on the bound and prove the point a minimum there. The polish ends when
    either converges or ``max_nfev`` residual evaluations are spent in all (default ``100 k``,
    ``least_squares``' own for ``k`` unknowns). Returns the last result
    (``scipy.optimize.OptimizeResult`` or :class:`roughbrdf.fitting.solvers.bounded.BoundedResult`).
    """
    budget = max_nfev if max_nfev is not None else 100 * len(x0)
    used, x = 0, x0
    while True:
        res = local_fit(obj, x, POLISH_TOL, min(POLISH_ROUND, budget - used))
        used += int(res.nfev)
        if res.status != 0 or used >= budget:  # its end settled on the bounds (as bounded_lm's)
            return settle(obj, res)
        # the bounded steps only accept decreases: their end is never worse than trf's
        res = bounded_lm(obj, res.x, POLISH_TOL, min(POLISH_ROUND, budget - used))
        used += res.nfev
        if res.success or used >= budget:
            return res
        x = res.x


def _distinct(points: list[np.ndarray], k: int, span: np.ndarray) -> list[np.ndarray]:
    """The first ``k`` points (sorted best first) that differ by more than
    :data:`DISTINCT_END` of the bounds from every point kept before."""
    chosen: list[np.ndarray] = []
    for x in points:
        if all(np.max(np.abs(x - c) / span) > DISTINCT_END for c in chosen):
            chosen.append(x)
        if len(chosen) == k:
            break
    return chosen


def search(full: Objective, explore: Objective, starts: list[np.ndarray],
           options: SearchOptions, on_start: Callable[[], Any] | None = None,
           origins: list[str] | None = None) -> SearchOutcome:
    """Local fits of ``explore`` from each start; when ``explore`` is a subsample, the
    ``polish`` best distinct end points refined on ``full``. ``on_start`` is called after each
    exploring fit (progress); ``origins`` names where each start came from (for ``tried``)."""
    lo, hi = full.spec.lower, full.spec.upper
    single = explore is full
    tried: list[dict[str, Any]] = []
    ends: list[tuple[float, np.ndarray, Any]] = []
    origins = origins if origins is not None else ["given"] * len(starts)
    for p0, origin in zip(starts, origins, strict=True):
        p0 = np.clip(p0, lo, hi)
        res = local_fit(explore, p0, EXPLORE_TOL, options.max_nfev)
        if single:  # an end of the search itself: settled on its bounds (bounded.settle)
            res = settle(full, res)
        tried.append({"x0": p0.tolist(), "x": res.x.tolist(), "cost": float(res.cost),
                      "stage": "single" if single else "explore", "origin": origin})
        ends.append((float(res.cost), res.x, res))
        if on_start is not None:
            on_start()
    if single:  # the first end as good as the best (first_best), in the order of the starts
        first = ends[first_best([e[0] for e in ends])]
        return SearchOutcome(first[1], first[2], tried, 0)
    # an end and its mirror (two lobes that traded places) are one end: compared, and
    # polished, in one form (ObjectiveSpec.canonical)
    # (a joint fit's layout has no such symmetry: its ends as they are)
    canonical = getattr(full.spec, "canonical", None)
    if canonical is not None:
        ends = [(c, canonical(x), r) for c, x, r in ends]
    order = sorted(range(len(ends)), key=lambda i: ends[i][0])
    keep = _distinct([ends[i][1] for i in order], options.polish, hi - lo)
    # polished in the order of their starts, so that first_best's choice follows the starts
    chosen = [ends[i][1] for i in sorted(i for i in order if any(ends[i][1] is x for x in keep))]
    polished = []
    for xe in chosen:
        res = polish_fit(full, xe, options.max_nfev)
        tried.append({"x0": xe.tolist(), "x": res.x.tolist(), "cost": float(res.cost),
                      "stage": "full", "origin": "explored"})
        polished.append(res)
    best = polished[first_best([float(r.cost) for r in polished], POLISHED_TIE)]
    # a lobe switched off at the best end: reopened at the data's widths and polished too
    # (problem.lobe_starts.reopened: whether a polish from a lobe of weight 0 steps into a
    # narrow lobe hangs on the last bits of its path); the best of all is kept
    seeds = [s for s, o in zip(starts, origins, strict=True) if o == "data"]
    again = reopened(full.spec, best.x, seeds)
    for xr in again:
        res = polish_fit(full, xr, options.max_nfev)
        tried.append({"x0": xr.tolist(), "x": res.x.tolist(), "cost": float(res.cost),
                      "stage": "full", "origin": "reopened"})
        polished.append(res)
    if again:
        best = polished[first_best([float(r.cost) for r in polished], POLISHED_TIE)]
    return SearchOutcome(best.x, best, tried, explore.nfev)


def first_best(costs: list[float], tol: float = CHOICE_TOL) -> int:
    """The index of the first cost within ``tol`` of the lowest (NaN: worst).

    Examples
    --------
    >>> first_best([3.0, 1.0000000000001, 1.0])   # the second and third are equally good
    1
    >>> first_best([3.0, 1.000001, 1.0], tol=1e-9)
    2
    """
    finite = [c for c in costs if math.isfinite(c)]
    if not finite:
        return 0
    low = min(finite)
    return next(i for i, c in enumerate(costs)
                if math.isfinite(c) and c <= low + tol * abs(low))


class MultiStart:
    """The search over the channels of one fit, in order.

    Holds what the channels share: the Sobol candidates, the random generator of the
    subsamples (both from ``options.seed``) and the previous channel's optimum (the warm start).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> from roughbrdf.fitting import ChannelData
    >>> spec = ObjectiveSpec(rb.model("lambertian", rho=0.9), ["rho"], [0.0], [1.0])
    >>> data = ChannelData.from_arrays([0.1, 0.3, 0.5], [0.2, 0.4, 0.6], [0.0, 1.0, 2.0],
    ...                                [0.1, 0.1, 0.1])
    >>> obj, out = MultiStart(spec, SearchOptions(starts=2)).run(data)
    >>> round(float(out.theta[0]), 6), len(out.tried)             # rho = 0.1 pi
    (0.314159, 2)
    """

    def __init__(self, spec: ObjectiveSpec, options: SearchOptions,
                 on_start: Callable[[], Any] | None = None) -> None:
        self.spec = spec
        self.options = options
        self.on_start = on_start
        self.rng = np.random.default_rng(options.seed)
        self.candidates = sobol_points(spec.lower, spec.upper, options.n_screen, options.seed)
        self.start = np.array(list(spec.start_values().values()))
        self.warm: np.ndarray | None = None

    def objectives(self, data: ChannelData) -> tuple[Objective, Objective]:
        """``(full, explore)``: the objective on all samples, and on the subsample (the same
        object when there is no subsample)."""
        full = Objective(self.spec, data)
        n_sub = self.options.subsample
        if n_sub is None or data.n <= n_sub:
            return full, full
        sub = np.sort(self.rng.choice(data.n, size=int(n_sub), replace=False))
        return full, Objective(self.spec, data.take(sub))

    def run(self, data: ChannelData) -> tuple[Objective, SearchOutcome]:
        """Search one channel; returns the objective on all its samples and the outcome.

        Exactly ``options.starts`` local fits explore: the model's values, the previous
        channel's optimum (when there is one and ``starts >= 2``), the data's peak widths (a
        model with several lobes, :meth:`data_starts`), then Sobol points."""
        full, explore = self.objectives(data)
        n = self.options.starts
        starts, origins = [self.start], ["model"]
        if self.warm is not None and n >= 2:
            starts.append(self.warm)
            origins.append("previous channel")
        # several lobes: a narrow one at the data's peak width and one at its haze, in place
        # of Sobol points (none for other models: their starts are as before)
        peaks = self.data_starts(data, n - len(starts) - MIN_SOBOL)
        starts += peaks
        origins += ["data"] * len(peaks)
        sobol = screen(explore, self.candidates, n - len(starts))
        starts += sobol
        origins += ["sobol"] * len(sobol)
        outcome = search(full, explore, starts, self.options, self.on_start, origins)
        self.warm = outcome.theta.copy()
        return full, outcome

    def data_starts(self, data: ChannelData, k: int) -> list[np.ndarray]:
        """Up to ``k`` starts read off the channel's peaks for a model with several lobes
        (:func:`~roughbrdf.fitting.problem.lobe_starts.lobe_starts`); none for other models
        or data (Mueller elements: their first channel only is a BRDF)."""
        from ..problem.data import ChannelData

        if k <= 0 or not isinstance(data, ChannelData) or data.values.ndim != 1:
            return []
        return lobe_starts(self.spec, data, min(k, MAX_DATA_STARTS))


@contextmanager
def progress_bar(show: bool | None, total: int, desc: str, unit: str = "start"
                 ) -> Iterator[Any]:
    """A tqdm bar counting ``total`` ``unit`` (``show=None``: only on an interactive terminal),
    or None."""
    if show is None:
        show = bool(getattr(sys.stderr, "isatty", lambda: False)())
    if not show:
        yield None
        return
    from tqdm.auto import tqdm

    bar = tqdm(total=total, desc=desc, unit=unit, leave=False)
    try:
        yield bar
    finally:
        bar.close()
