"""The residuals of one channel as a function of the free parameters, and their Jacobians.

``docs/fitting.md`` ("What is minimized"): one residual per sample, ``x`` measured, ``f`` the
model value of the compared quantity (averaged over the instrument aperture if there is one),
``w`` the weight and ``K`` the data scale:

* ``relative``: ``w (K x - f)/f``; its r.m.s. (unweighted) is TR75's sigma, Eq. 34;
* ``log``: ``w (ln(K x) - ln f)``, symmetric in over- and under-estimates;
* ``absolute``: ``w (K x - f)``; with ``weights="uncertainty"`` the usual chi-square;
* ``robust`` (default): ``w r'``, ``r'`` the soft-L1 transform of the log residual
  (quadratic below 0.1 in ln units, linear above: glints and floor noise weigh less).

Each residual, its derivative in ``K`` and the closed-form ``K`` are the loss's
(:class:`roughbrdf.quantity.Loss`); this module weighs them and differentiates the model.

For relative data ``K`` is free and solved in closed form at every evaluation
(:func:`roughbrdf.quantity.relative_scale`, the TR75 Eq. 34 convention ``K x ~ f``;
``docs/models.md`` §3.9 reading (a)); otherwise it is fixed (1, or a known ``scale=``). Model
values are floored at ``1e-12`` times the largest ``|x|`` before dividing or taking logs, and
residuals that are still not finite are replaced by a large finite value so that the optimizer
steps back.

The Jacobian is a finite difference computed through the compiled model kernel: one vectorized
evaluation of all samples per free parameter (:meth:`Objective.jac`, forward, for the optimizer;
:meth:`Objective.jac_central`, central, for the covariance), never a loop over samples.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ...quantity import F_FLOOR, Loss, Quantity, relative_scale

if TYPE_CHECKING:
    from ...models import Model
    from .data import ChannelData

__all__ = ["Objective", "ObjectiveSpec", "BAD_RESIDUAL", "F_FLOOR"]

#: forward-difference step (relative)
EPS_STEP = math.sqrt(np.finfo(float).eps)
#: central-difference step (relative)
CENTRAL_STEP = np.finfo(float).eps ** (1.0 / 3.0)
#: residuals that are still not finite (a model that overflows at some trial parameters) are
#: replaced by this value, so that the optimizer sees a large, finite cost and steps back
BAD_RESIDUAL = 1e6


@dataclass(frozen=True)
class ObjectiveSpec:
    """What is fitted: the model, its free parameters and bounds, the loss and the scale.

    Attributes
    ----------
    model : Model
        The model; its other parameters stay at their values.
    free : tuple of str
        Names of the fitted parameters (the optimizer's variables, in this order).
    lower, upper : numpy.ndarray
        Bounds of the free parameters.
    loss : {"relative", "log", "absolute", "robust"}
        The residual (module notes).
    quantity : Quantity
        Model quantity compared with the data: ``"brdf"`` or ``"bridf"`` (BRDF cos theta_r).
    free_scale : bool
        Solve the data scale ``K`` in closed form (relative data).
    fixed_scale : float
        ``K`` when it is not free.

    Examples
    --------
    >>> import numpy as np, roughbrdf as rb
    >>> spec = ObjectiveSpec(rb.model("lambertian"), ["rho"], [0.0], [1.0], quantity="bridf")
    >>> spec.free, spec.quantity, spec.n_varys
    (('rho',), <Quantity.BRIDF: 'bridf'>, 1)
    """

    model: Model
    free: Sequence[str]
    lower: np.ndarray
    upper: np.ndarray
    loss: str = "relative"
    quantity: Quantity | str = Quantity.BRDF
    free_scale: bool = False
    fixed_scale: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "free", tuple(self.free))
        object.__setattr__(self, "lower", np.asarray(self.lower, dtype=float))
        object.__setattr__(self, "upper", np.asarray(self.upper, dtype=float))
        object.__setattr__(self, "quantity", Quantity.parse(self.quantity))
        Loss.parse(self.loss)  # an ArgumentError (a ValueError) naming the loss
        if not self.lower.shape == self.upper.shape == (len(self.free),):
            raise ValueError("lower and upper need one bound per free parameter")

    @property
    def n_varys(self) -> int:
        """Fitted parameters, the free scale included."""
        return len(self.free) + (1 if self.free_scale else 0)

    def snap_edges(self) -> np.ndarray:
        """``(p, 2)`` booleans: whether each free parameter's lower and upper bound is an
        edge of its physical domain (:attr:`Parameter.domain
        <roughbrdf.models.parameters.Parameter.domain>`, to 1e-9: a lobe's weight 0 or 1,
        ``k = 0``), as :func:`~roughbrdf.fitting.results.statistics.limit_kinds` tells them: where
        :func:`~roughbrdf.fitting.solvers.stationary.snap` tries an end from any distance. None with
        a free scale: a parameter that is one degree of freedom with it (TS67's ``rho_d``) is
        as good on its edge, but that value would be no result.

        Examples
        --------
        >>> import roughbrdf as rb
        >>> ObjectiveSpec(rb.model("coated", lobes=2), ["n", "w2"], [1.05, 0.0],
        ...               [2.5, 1.0]).snap_edges().tolist()
        [[False, False], [True, True]]
        """
        by_name = {p.name: p for p in self.model.parameters}
        out = np.zeros((len(self.free), 2), dtype=bool)
        if self.free_scale:
            return out
        for j, nm in enumerate(self.free):
            par = by_name.get(nm)
            if par is None:  # no parameter of that name (none such today): no edge
                continue
            lo, lo_in, hi, hi_in = par.domain
            # an edge the domain includes (an open one, TS67's c > 0, is no value to try)
            for side, (b, e, inside) in enumerate(((self.lower[j], lo, lo_in),
                                                   (self.upper[j], hi, hi_in))):
                out[j, side] = bool(inside and np.isfinite(e)
                                    and abs(b - e) <= 1e-9 * max(1.0, abs(e)))
        return out

    def snap_points(self) -> np.ndarray:
        """Each free parameter's neutral value (:attr:`Parameter.neutral
        <roughbrdf.models.parameters.Parameter.neutral>`: where its part of the model can
        vanish, TR75's ``n = 1``), NaN for none or outside its bounds: where
        :func:`~roughbrdf.fitting.solvers.stationary.snap` tries an end near it.

        Examples
        --------
        >>> import roughbrdf as rb
        >>> ObjectiveSpec(rb.model("tr75"), ["e", "n"], [0.02, 0.2], [3.0, 5.0]).snap_points()
        array([nan,  1.])
        """
        by_name = {p.name: p for p in self.model.parameters}
        out = np.full(len(self.free), np.nan)
        for j, nm in enumerate(self.free):
            v = getattr(by_name.get(nm), "neutral", None)
            if v is not None and self.lower[j] < v < self.upper[j]:
                out[j] = v
        return out

    def canonical(self, theta: np.ndarray) -> np.ndarray:
        """``theta`` or, for a model with a label symmetry (two lobes that may trade places:
        :meth:`~roughbrdf.models.coated.Coated.lobe_mirror`), its mirror when that puts the
        narrower lobe first. A point and its mirror are the same model at the same cost: the
        search keeps one of them, not both (``docs/fitting.md``, "Global search"; measured,
        C2_Black's two Beckmann lobes explored to one end and its mirror, and both were
        polished). ``theta`` as given unless every name of the symmetry is free and its
        bounds map onto themselves.

        Examples
        --------
        >>> import numpy as np, roughbrdf as rb
        >>> spec = ObjectiveSpec(rb.model("coated", lobes=2), ["alpha", "alpha2", "w2"],
        ...                      [0.01, 0.01, 0.0], [1.0, 1.0, 1.0])
        >>> spec.canonical(np.array([0.3, 0.05, 0.2])).round(3).tolist()
        [0.05, 0.3, 0.8]
        """
        mirror = getattr(self.model, "lobe_mirror", lambda: None)()
        if mirror is None:
            return theta
        swaps, complements = mirror
        pos = {nm: j for j, nm in enumerate(self.free)}
        names = [nm for pair in swaps for nm in pair] + list(complements)
        if not all(nm in pos for nm in names):
            return theta
        lo, hi = self.lower, self.upper
        same = all(lo[pos[a]] == lo[pos[b]] and hi[pos[a]] == hi[pos[b]] for a, b in swaps)
        # w -> 1 - w maps [lo, hi] onto itself only when lo = 1 - hi
        if not same or not all(abs(lo[pos[c]] + hi[pos[c]] - 1.0) <= 1e-12 for c in complements):
            return theta
        first, second = swaps[0]
        if not theta[pos[first]] > theta[pos[second]]:
            return theta
        out = np.array(theta, dtype=float)
        for a, b in swaps:
            out[pos[a]], out[pos[b]] = theta[pos[b]], theta[pos[a]]
        for c in complements:
            out[pos[c]] = 1.0 - theta[pos[c]]
        return out

    def start_values(self) -> dict[str, float]:
        """The model's values of the free parameters (where a fit starts)."""
        params = self.model.params
        return {nm: float(params[nm]) for nm in self.free}  # type: ignore[arg-type]

    def model_at(self, theta: ArrayLike) -> Model:
        """The model with the free parameters set to ``theta``."""
        return self.model.with_values(self.free, [float(t) for t in np.atleast_1d(theta)])


@dataclass(eq=False)
class Objective:
    """Residuals of one channel (or a subsample of it) as a function of the free parameters.

    Built from an :class:`ObjectiveSpec` and the channel's
    :class:`~roughbrdf.fitting.problem.data.ChannelData`; :meth:`fun` and :meth:`jac` are what
    ``scipy.optimize.least_squares`` calls. ``nfev`` counts model evaluations (each one
    vectorized over all samples).

    Examples
    --------
    >>> import numpy as np, roughbrdf as rb
    >>> from roughbrdf.fitting import ChannelData
    >>> data = ChannelData.from_arrays([0.2, 0.4], [0.1, 0.5], [0.0, 1.0], [0.2, 0.2])
    >>> obj = Objective(ObjectiveSpec(rb.model("lambertian"), ["rho"], [0.0], [1.0],
    ...                               loss="absolute"), data)
    >>> obj.fun(np.array([0.2 * np.pi])).round(12).tolist()     # rho/pi = 0.2: exact
    [0.0, 0.0]
    >>> obj.jac(np.array([0.5])).shape, obj.nfev
    ((2, 1), 3)
    """

    spec: ObjectiveSpec
    data: ChannelData
    nfev: int = 0
    _last: tuple[np.ndarray, np.ndarray] | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        x = self.data.values
        self.x = x
        self.w = self.data.weights
        self.loss = Loss.parse(self.spec.loss)
        self.floor = Loss.floor(x)
        self.logx = np.log(x) if self.loss.positive_data else None

    @property
    def n(self) -> int:
        """Number of residuals (samples)."""
        return self.data.n

    def reset(self) -> None:
        """Zero :attr:`nfev` and forget the cached last residual."""
        self.nfev = 0
        self._last = None

    # model ------------------------------------------------------------------------------------
    def model_at(self, theta: ArrayLike) -> Model:
        """The model with the free parameters set to ``theta``."""
        return self.spec.model_at(theta)

    def values(self, theta: ArrayLike) -> np.ndarray:
        """Model values at the samples (one call of the compiled kernel); with an aperture,
        the weighted average over the stencil of each sample."""
        self.nfev += 1
        return self.data.geometry.evaluate(self.model_at(theta), self.spec.quantity)

    # residuals --------------------------------------------------------------------------------
    def scale(self, f: np.ndarray) -> float:
        """Data scale ``K`` (``K x ~ f``) for the model values ``f``: closed form
        (:func:`~roughbrdf.quantity.relative_scale`) when free, else the fixed one."""
        if not self.spec.free_scale:
            return self.spec.fixed_scale
        return relative_scale(self.x, np.maximum(f, self.floor), weights=self.w,
                              loss=self.spec.loss)

    def residual_of(self, f: np.ndarray, k: float | None = None) -> np.ndarray:
        """Weighted residuals for model values ``f`` and scale ``k`` (None: :meth:`scale`)."""
        if k is None:
            k = self.scale(f)
        r = self.loss.residual(self.x, f, k=k, floor=self.floor, logx=self.logx)
        if self.w is not None:
            r = r * self.w
        if not np.isfinite(r).all():
            r = np.where(np.isfinite(r), r, BAD_RESIDUAL)
        return r

    def fun(self, theta: np.ndarray) -> np.ndarray:
        """Residuals at ``theta``, the scale profiled out (what the optimizer minimizes)."""
        r = self.residual_of(self.values(theta))
        self._last = (np.array(theta, dtype=float), r)
        return r

    def cost(self, theta: np.ndarray) -> float:
        """``sum(r^2)`` at ``theta`` (one model evaluation)."""
        return float(np.sum(self.fun(theta) ** 2))

    # Jacobians --------------------------------------------------------------------------------
    def _step(self, theta: np.ndarray, j: int, rel: float) -> float:
        lo, hi = self.spec.lower[j], self.spec.upper[j]
        span = hi - lo
        h = rel * max(abs(theta[j]), 1e-3 * span if math.isfinite(span) else 1e-3, 1e-8)
        if theta[j] + h > hi:
            h = -h
        return h

    def jac(self, theta: np.ndarray, k: float | None = None) -> np.ndarray:
        """Forward-difference Jacobian: one compiled model evaluation per free parameter.

        With ``k=None`` the scale is re-solved at each perturbed point (the Jacobian of the
        profiled residual the optimizer sees); with ``k`` given it is held fixed. The residual
        at ``theta`` is reused from the last :meth:`fun` call when it was at the same point.
        """
        theta = np.asarray(theta, dtype=float)
        if k is None and self._last is not None and np.array_equal(self._last[0], theta):
            r0 = self._last[1]
        else:
            r0 = self.residual_of(self.values(theta), k)
        out = np.empty((self.n, theta.size))
        for j in range(theta.size):
            h = self._step(theta, j, EPS_STEP)
            t = theta.copy()
            t[j] += h
            out[:, j] = (self.residual_of(self.values(t), k) - r0) / h
        return out

    def jac_central(self, theta: np.ndarray, k: float,
                    columns: Sequence[int] | None = None) -> np.ndarray:
        """Central-difference Jacobian at fixed scale ``k`` (for the covariance); one-sided
        next to a bound. ``columns``: only those free parameters (default all), in order."""
        cols = range(theta.size) if columns is None else list(columns)
        out = np.empty((self.n, len(cols)))
        for c, j in enumerate(cols):
            h = abs(self._step(theta, j, CENTRAL_STEP))
            lo_ok = theta[j] - h >= self.spec.lower[j]
            hi_ok = theta[j] + h <= self.spec.upper[j]
            tp, tm = theta.copy(), theta.copy()
            if lo_ok and hi_ok:
                tp[j] += h
                tm[j] -= h
                d = 2 * h
            elif hi_ok:
                tp[j] += h
                d = h
            else:
                tm[j] -= h
                d = h
            out[:, c] = (self.residual_of(self.values(tp), k)
                         - self.residual_of(self.values(tm), k)) / d
        return out

    def curvature_of(self, f: np.ndarray, k: float) -> np.ndarray:
        """Per sample, the factor of the cost's curvature over the Gauss-Newton one at model
        values ``f`` and scale ``k`` (:meth:`~roughbrdf.quantity.Loss.curvature`; the weights
        scale both alike). Non-finite factors (a sample without a residual) are 1."""
        c = self.loss.curvature(self.x, f, k, self.floor, logx=self.logx)
        return np.where(np.isfinite(c), c, 1.0)

    def scale_column(self, f: np.ndarray, k: float) -> np.ndarray:
        """``d r / d K`` at fixed model values (analytic): the scale's Jacobian column."""
        col = self.loss.scale_derivative(self.x, f, k, self.floor)
        return col if self.w is None else col * self.w
