"""Joint fits of several channels: shared parameters once, the others per channel.

``rb.fit(..., joint=True)`` (``docs/fitting.md``, "Joint fits across channels"). A
multi-wavelength file of one surface has one geometry: the roughness and the index of a coating
do not change from 465 to 630 nm, the reflectances do. Fitting the channels one by one gives
each its own roughness; the joint fit has one vector of unknowns

    ``[shared parameters..., per-channel parameters of channel 1..., of channel 2..., ...]``

and stacks the channels' residuals (each channel keeps its own data scale ``K`` when the data
are relative). By default the per-channel parameters are the reflectances (parameters of kind
``"reflectance"``, :mod:`roughbrdf.models.parameters`) and every other free parameter is
shared; ``shared=`` names them explicitly.

:class:`JointObjective` has the interface of :class:`~roughbrdf.fitting.problem.objective.Objective`
that the search uses (``fun``, ``jac``, ``cost``, ``spec.lower``/``upper``), so the same
screening, multistart and polish (:mod:`~roughbrdf.fitting.solvers.search`) run on it. The standard
errors come from the joint Jacobian (the shared parameters are constrained by every channel).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from ...errors import ArgumentError
from ..problem.objective import Objective, ObjectiveSpec
from ..results.result import ChannelFit
from ..results.statistics import Covariance, at_bound
from ..solvers.search import SearchOptions, SearchOutcome, screen, search, sobol_points

if TYPE_CHECKING:
    from ...models import Model
    from ..problem.data import ChannelData

__all__ = ["JointLayout", "JointObjective", "default_shared", "fit_joint"]


def default_shared(model: Model, free: Sequence[str]) -> tuple[str, ...]:
    """The free parameters a joint fit shares by default: all but the reflectances.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> m = rb.model("coated", lobes=2)
    >>> default_shared(m, m.param_names)
    ('n', 'alpha', 'alpha2', 'w2')
    """
    kinds = {p.name: p.kind for p in model.parameters}
    return tuple(nm for nm in free if kinds.get(nm) != "reflectance")


@dataclass(frozen=True)
class JointLayout:
    """Where each channel's free parameters sit in the joint vector of unknowns.

    Attributes
    ----------
    spec : ObjectiveSpec
        The per-channel spec (its ``free`` order is each channel's parameter order).
    shared : tuple of str
        Free parameters common to every channel.
    labels : tuple of str
        The channels.
    """

    spec: ObjectiveSpec
    shared: tuple[str, ...]
    labels: tuple[str, ...]

    @property
    def own(self) -> tuple[str, ...]:
        """The per-channel free parameters."""
        return tuple(nm for nm in self.spec.free if nm not in self.shared)

    @property
    def free(self) -> tuple[str, ...]:
        """Names of the joint unknowns: shared ones, then ``name[channel]``."""
        return self.shared + tuple(f"{nm}[{lb}]" for lb in self.labels for nm in self.own)

    def index(self, c: int) -> np.ndarray:
        """Positions in the joint vector of channel ``c``'s parameters (``spec.free`` order)."""
        ns, no = len(self.shared), len(self.own)
        pos = {nm: i for i, nm in enumerate(self.shared)}
        pos.update({nm: ns + c * no + i for i, nm in enumerate(self.own)})
        return np.array([pos[nm] for nm in self.spec.free], dtype=int)

    def _expand(self, per_channel: np.ndarray) -> np.ndarray:
        """A joint vector from one value per ``spec.free`` parameter (same for each channel)."""
        out = np.empty(len(self.free))
        for c in range(len(self.labels)):
            out[self.index(c)] = per_channel
        return out

    @property
    def lower(self) -> np.ndarray:
        return self._expand(self.spec.lower)

    @property
    def upper(self) -> np.ndarray:
        return self._expand(self.spec.upper)

    def snap_edges(self) -> np.ndarray:
        """:meth:`ObjectiveSpec.snap_edges` of each joint unknown."""
        per = self.spec.snap_edges()
        out = np.zeros((len(self.free), 2), dtype=bool)
        for c in range(len(self.labels)):
            out[self.index(c)] = per
        return out

    @property
    def n_varys(self) -> int:
        """Joint unknowns, the free data scales (one per channel) included."""
        return len(self.free) + (len(self.labels) if self.spec.free_scale else 0)


class JointObjective:
    """The stacked residuals of several channels as a function of the joint unknowns."""

    def __init__(self, layout: JointLayout, objectives: Sequence[Objective]) -> None:
        self.spec = layout
        self.objectives = list(objectives)
        self.rows = np.cumsum([0] + [o.n for o in self.objectives])

    @property
    def n(self) -> int:
        return int(self.rows[-1])

    @property
    def nfev(self) -> int:
        """Model evaluations, all channels (one per channel per joint evaluation)."""
        return sum(o.nfev for o in self.objectives)

    def fun(self, theta: np.ndarray) -> np.ndarray:
        return np.concatenate([o.fun(theta[self.spec.index(c)])
                               for c, o in enumerate(self.objectives)])

    def cost(self, theta: np.ndarray) -> float:
        return float(np.sum(self.fun(theta) ** 2))

    def jac(self, theta: np.ndarray) -> np.ndarray:
        """Block Jacobian: each channel's rows against its own and the shared unknowns."""
        out = np.zeros((self.n, theta.size))
        for c, o in enumerate(self.objectives):
            idx = self.spec.index(c)
            out[self.rows[c]:self.rows[c + 1], idx] = o.jac(theta[idx])
        return out

    def covariance(self, theta: np.ndarray, held: Sequence[str]) -> Covariance:
        """The sandwich of a single channel's fit
        (:meth:`~roughbrdf.fitting.results.statistics.Covariance.at_optimum`: the loss's
        curvature in the bread, each sample's own squared residual in the meat) from the
        central-difference joint Jacobian at ``theta``, the channels' residuals stacked (scales
        at their optimum; parameters in ``held``, at a bound, get NaN)."""
        names = list(self.spec.free)
        keep = [j for j, nm in enumerate(names) if nm not in held]
        blocks, chi2, res, curv = [], 0.0, [], []
        n_scale = len(self.objectives) if self.spec.spec.free_scale else 0
        for c, o in enumerate(self.objectives):
            idx = self.spec.index(c)
            f = o.values(theta[idx])
            k = o.scale(f)
            r = o.residual_of(f, k)
            chi2 += float(r @ r)
            res.append(r)
            curv.append(o.curvature_of(f, k))
            block = np.zeros((o.n, len(names) + n_scale))
            block[:, idx] = o.jac_central(theta[idx], k)
            if n_scale:
                block[:, len(names) + c] = o.scale_column(f, k)
            blocks.append(block)
        cols = keep + list(range(len(names), len(names) + n_scale))
        all_names = names + [f"scale[{lb}]" for lb in self.spec.labels][:n_scale]
        inner = Covariance.from_jacobian(np.vstack(blocks)[:, cols],
                                         [all_names[j] for j in cols], chi2=chi2,
                                         dof=self.n - self.spec.n_varys,
                                         residual=np.concatenate(res),
                                         curvature=np.concatenate(curv))
        full = np.full((len(all_names), len(all_names)), np.nan)
        full[np.ix_(cols, cols)] = inner.matrix
        return Covariance(full, all_names, inner.note)


def check_shared(shared: Iterable[str] | None, spec: ObjectiveSpec) -> tuple[str, ...]:
    """The shared parameters: ``shared`` checked against the free ones, or the default."""
    if shared is None:
        return default_shared(spec.model, spec.free)
    names = (shared,) if isinstance(shared, str) else tuple(str(s) for s in shared)
    bad = [nm for nm in names if nm not in spec.free]
    if bad:
        raise ArgumentError("shared", f"not a free parameter of the model (free: "
                            f"{', '.join(spec.free)})", value=bad[0])
    return tuple(nm for nm in spec.free if nm in names)


def _subsampled(layout: JointLayout, full: JointObjective, data: Sequence[ChannelData],
                options: SearchOptions, rng: np.random.Generator) -> JointObjective:
    """The exploring objective: each channel on its own fixed random subsample."""
    n_sub = options.subsample
    if n_sub is None or all(d.n <= n_sub for d in data):
        return full
    objs = []
    for d in data:
        part = d if d.n <= n_sub else d.take(np.sort(rng.choice(d.n, int(n_sub), replace=False)))
        objs.append(Objective(layout.spec, part))
    return JointObjective(layout, objs)


def fit_joint(spec: ObjectiveSpec, data: Sequence[ChannelData], options: SearchOptions,
              shared: Iterable[str] | None = None,
              on_start: Callable[[], Any] | None = None
              ) -> tuple[list[ChannelFit], dict[str, Any]]:
    """Fit every channel of ``data`` at once (module notes); one :class:`ChannelFit` each,
    and the joint figures (``fit.json``'s ``options.joint``): ``shared``, ``n_varys``,
    ``n_points``, ``chi2``, ``aic``, ``bic`` of all channels together (one residual variance
    per channel: the definition of :func:`roughbrdf.fitting.choice.compare.information`).

    The search is the one of a single channel (:func:`~roughbrdf.fitting.solvers.search.search`):
    exactly ``options.starts`` local fits, from the model's values and from screened Sobol
    points of the joint box. Each channel's entry reports its own figures of merit; ``free``,
    ``stderr`` and ``correl`` are of the joint unknowns it depends on (shared ones under their
    own name), and its message names the shared parameters.
    """
    import time

    t0 = time.perf_counter()
    layout = JointLayout(spec, check_shared(shared, spec), tuple(d.label for d in data))
    full = JointObjective(layout, [Objective(spec, d) for d in data])
    explore = _subsampled(layout, full, data, options, np.random.default_rng(options.seed))
    start = layout._expand(np.array(list(spec.start_values().values())))
    n_sobol = max(options.starts - 1, int(options.screen)) if options.starts > 1 else 0
    cands = sobol_points(layout.lower, layout.upper, n_sobol, options.seed)
    starts = [start, *screen(explore, cands, options.starts - 1)]  # type: ignore[arg-type]
    origins = ["model"] + ["sobol"] * (len(starts) - 1)
    outcome = search(full, explore, starts, options, on_start, origins)  # type: ignore[arg-type]
    bound = at_bound(outcome.theta, layout.lower, layout.upper, layout.free)
    cov = full.covariance(outcome.theta, list(bound))
    elapsed = time.perf_counter() - t0
    fits = [_channel_fit(full, c, outcome, cov, bound, elapsed) for c in range(len(data))]
    chi2 = sum(f.chi2 for f in fits)
    k, n = layout.n_varys, full.n
    # one residual variance per channel, as roughbrdf.fitting.choice.compare.information counts it
    like = sum(f.n_points * math.log(f.chi2 / f.n_points) if f.chi2 > 0 else -math.inf
               for f in fits)
    summary = {"shared": list(layout.shared), "n_varys": k, "n_points": n, "chi2": chi2,
               "aic": like + 2 * k, "bic": like + math.log(n) * k,
               "cost": float(outcome.result.cost) if outcome.result is not None else None}
    return fits, summary


def _channel_fit(full: JointObjective, c: int, outcome: SearchOutcome, cov: Covariance,
                 bound: dict[str, str], elapsed: float) -> ChannelFit:
    """Channel ``c``'s entry of a joint fit (figures of merit of its own samples)."""
    layout, obj = full.spec, full.objectives[c]
    idx = layout.index(c)
    theta = outcome.theta[idx]
    part = SearchOutcome(theta, outcome.result, outcome.tried, 0)
    fit = ChannelFit.from_search(obj, part, elapsed / len(full.objectives))
    names = [layout.free[j] for j in idx]  # joint names of this channel's parameters
    sd = dict(zip(cov.names, cov.stderr(), strict=True))
    stderr = dict(fit.stderr)
    for nm, jn in zip(layout.spec.free, names, strict=True):
        stderr[nm] = float(sd[jn])
    label = layout.labels[c]
    corr = cov.correl()
    rows = list(zip(layout.spec.free, names, strict=True))  # + the scale, as in a separate fit
    rows += [("scale", f"scale[{label}]")] if layout.spec.free_scale else []
    correl = {nm: {(o if o in layout.shared else o.split("[")[0]): v
                   for o, v in corr[jn].items() if o in layout.shared or o.endswith(f"[{label}]")}
              for nm, jn in rows}
    own_bound = {nm: bound[jn] for nm, jn in zip(layout.spec.free, names, strict=True)
                 if jn in bound}
    message = (outcome.result.message.rstrip(".") if outcome.result is not None
               else "no local fit finished")
    message += cov.note + f"; joint fit of {len(full.objectives)} channels, shared: " \
        + (", ".join(layout.shared) or "none")
    if own_bound:
        message += f"; at a bound: {', '.join(own_bound)}"
    # covar and the scale's stderr from the joint covariance too (this channel's block)
    sel = list(idx) + ([len(layout.free) + c] if layout.spec.free_scale else [])
    scale_sd = float(sd[f"scale[{label}]"]) if layout.spec.free_scale else 0.0
    return replace(fit, stderr=stderr, correl=correl, at_bound=own_bound, message=message,
                   covar=cov.matrix[np.ix_(sel, sel)], scale_stderr=scale_sd,
                   nfev=full.nfev, n_varys=layout.n_varys,
                   aic=_ic(fit, layout.n_varys, 2.0),
                   bic=_ic(fit, layout.n_varys, math.log(full.n)))


def _ic(fit: ChannelFit, k: int, per_parameter: float) -> float:
    """AIC/BIC of one channel's samples with the joint fit's ``k`` unknowns."""
    lchi = math.log(fit.chi2 / fit.n_points) if fit.chi2 > 0 else -math.inf
    return fit.n_points * lchi + per_parameter * k
