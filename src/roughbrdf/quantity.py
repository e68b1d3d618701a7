"""What a value means and how a fit compares it: the :class:`Quantity` and :class:`Loss` types.

:class:`Quantity`, one type for measurements, fitting, plotting and model evaluation:

``brdf``
    The standard BRDF ``f_r`` in sr⁻¹ (reflected radiance / incident irradiance).
``brdf_cos``
    ``f_r cos(theta_r)`` (ALTA's ``INV_STERADIAN_COSINE_FACTOR``), finite at the horizon.
``bridf``
    TR75's BRIDF, the same number as ``brdf_cos`` under the paper's own name.
``relative``
    Proportional to ``f_r`` with an unknown scale. A *model* evaluated as ``relative`` is its
    BRDF divided by its BRDF at the specular direction of the same incidence (TS67 Eq. 23,
    ``docs/models.md`` §2.7); *data* marked relative are compared with a model through the
    closed-form scale of :func:`relative_scale`.

The fit :class:`Loss` (``docs/fitting.md``, "What is minimized") owns its names
(:data:`LOSSES`), what data it needs (the log and robust losses: positive values), its
residual and the residual's derivative in the data scale ``K``, the closed-form ``K``
(:func:`relative_scale`) and the line a report shows.

Examples
--------
>>> from roughbrdf.quantity import Loss, Quantity
>>> Quantity.parse("BRIDF").cosine_weighted
True
>>> Quantity.parse("brdf") == "brdf"
True
>>> Loss.parse("log").positive_data
True
"""

from __future__ import annotations

import math
from enum import StrEnum

import numpy as np
from numpy.typing import ArrayLike

from .errors import ArgumentError

__all__ = ["Quantity", "Loss", "relative_scale", "LOSSES", "F_FLOOR", "ROBUST_SCALE"]

#: the fit losses (``docs/fitting.md``): the values of :class:`Loss`
LOSSES = ("relative", "log", "absolute", "robust")
#: the scale ``c`` of the robust loss, in ln units: log residuals below it (a model within about
#: 10 % of the data, the calibration and repeatability of a gonioreflectometer) count as in the
#: log loss, larger ones (glints, a dust speck, a detector at its floor) only linearly
ROBUST_SCALE = 0.1
#: the closed-form scale of the robust loss: at most this many IRLS steps, stopping when
#: ``ln K`` moves by less than :data:`ROBUST_K_TOL`
ROBUST_K_STEPS = 100
ROBUST_K_TOL = 1e-13
#: floor applied to model values before dividing or taking logs, relative to the largest
#: ``|x|``: a model value of exactly 0 (e.g. an underflowed Beckmann lobe) must not give inf
F_FLOOR = 1e-12


class Quantity(StrEnum):
    """The quantity an array of values holds (a ``str``: compares equal to its name)."""

    BRDF = "brdf"
    BRDF_COS = "brdf_cos"
    BRIDF = "bridf"
    RELATIVE = "relative"

    @classmethod
    def parse(cls, value: object, name: str = "quantity") -> Quantity:
        """The quantity named by ``value`` (case-insensitive; ``"brdf*cos"``/``"brdf-cos"``
        accepted); ``ValueError`` naming ``name`` and the value otherwise."""
        if isinstance(value, cls):
            return value
        key = str(value).strip().lower().replace("-", "_").replace("*", "_").replace(" ", "_")
        try:
            return cls(key)
        except ValueError:
            raise ValueError(f"{name} must be one of {', '.join(q.value for q in cls)}; "
                             f"got {value!r}") from None

    @property
    def cosine_weighted(self) -> bool:
        """Whether the values carry the factor ``cos(theta_r)`` (``brdf_cos``, ``bridf``)."""
        return self in (Quantity.BRDF_COS, Quantity.BRIDF)

    @property
    def absolute(self) -> bool:
        """Whether the values have an absolute scale (everything but ``relative``)."""
        return self is not Quantity.RELATIVE

    def compared_with(self, relative_to: object = None) -> Quantity:
        """The model quantity that data of this quantity are compared with: ``brdf`` or
        ``bridf`` (= ``brdf_cos``). Relative data are proportional to ``relative_to``
        (``"brdf"`` when ``None``; ``"brdf_cos"``/``"bridf"`` for TR75's relative BRIDF).

        Examples
        --------
        >>> Quantity.BRDF_COS.compared_with()
        <Quantity.BRIDF: 'bridf'>
        >>> Quantity.RELATIVE.compared_with("brdf_cos")
        <Quantity.BRIDF: 'bridf'>
        """
        if self is not Quantity.RELATIVE:
            return Quantity.BRIDF if self.cosine_weighted else Quantity.BRDF
        rel = Quantity.parse("brdf" if relative_to is None else relative_to, "relative_to")
        if rel is Quantity.RELATIVE:
            raise ValueError("relative_to must be 'brdf' or 'bridf' (what the relative values "
                             f"are proportional to), got {relative_to!r}")
        return rel.compared_with()


class Loss(StrEnum):
    """The residual of a fit (a ``str``: compares equal to its name; ``docs/fitting.md``).

    With ``x`` the measured value, ``f`` the model value (floored at :meth:`floor`: ``fs``) and
    ``K`` the data scale, one residual per sample (before the weight):

    * ``relative``: ``(K x - f)/f``, computed ``(K x)/fs - 1``; its r.m.s. is TR75's sigma
      (Eq. 34; the papers' loss, pinned where their sigma is reproduced);
    * ``log``: ``ln(K x) - ln f``, computed ``ln x + ln K - ln fs``;
    * ``absolute``: ``K x - f``; with ``weights="uncertainty"`` the usual chi-square;
    * ``robust`` (the default of :func:`roughbrdf.fit`, chosen by measurement:
      ``docs/fitting.md``, "Choosing the loss"): soft-L1 of the log residual
      ``r = ln(K x) - ln f`` with the scale ``c =`` :data:`ROBUST_SCALE`, as the transformed
      residual
      ``r' = sign(r) sqrt(2 c² (sqrt(1 + r²/c²) - 1))`` (computed
      ``r sqrt(2/(1 + sqrt(1 + r²/c²)))``, exact for small ``r``), so that least squares on
      ``r'`` minimizes ``sum(w² 2c² (sqrt(1 + r²/c²) - 1))``: quadratic (``r'`` ~ ``r``) for
      ``|r| << c``, linear (``r'²`` ~ ``2 c |r|``) for ``|r| >> c``. Like ``log``, it needs
      positive data.

    Examples
    --------
    >>> import numpy as np
    >>> Loss.parse("relative").residual(np.array([2.0]), np.array([1.0]), floor=0.0).tolist()
    [1.0]
    >>> Loss.ABSOLUTE.text
    'absolute, x - f'
    >>> r = Loss.ROBUST.residual(np.array([np.e]), np.array([1.0]), floor=0.0)  # ln x - ln f = 1
    >>> bool(np.isclose(r[0] ** 2, 2 * 0.1**2 * (np.sqrt(1 + 1 / 0.1**2) - 1)))
    True
    """

    RELATIVE = "relative"
    LOG = "log"
    ABSOLUTE = "absolute"
    ROBUST = "robust"

    @classmethod
    def parse(cls, value: object, name: str = "loss") -> Loss:
        """The loss named by ``value`` (exactly its name); an
        :class:`~roughbrdf.errors.ArgumentError` naming ``name`` and the value otherwise."""
        if isinstance(value, cls):
            return value
        if not isinstance(value, str) or value not in LOSSES:  # no case folding: as before
            raise ArgumentError(name, f"unknown loss {value!r}; choose one of "
                                f"{', '.join(LOSSES)}")
        return cls(value)

    @property
    def positive_data(self) -> bool:
        """Whether the data must be positive (``log``, ``robust``: ``ln x``)."""
        return self in (Loss.LOG, Loss.ROBUST)

    @property
    def ratio(self) -> bool:
        """Whether the residual compares ``x`` with ``f`` by ratio (``relative``, ``log``): a
        model value of 0 leaves such a sample without a residual."""
        return self is not Loss.ABSOLUTE

    @property
    def text(self) -> str:
        """The report's ``loss`` line."""
        return _LOSS_TEXT[self]

    @staticmethod
    def floor(x: np.ndarray) -> float:
        """The floor of model values for data ``x``: :data:`F_FLOOR` times the largest ``|x|``."""
        return F_FLOOR * max(float(np.max(np.abs(x))), 1e-300)

    def uncertainty_weight(self, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        """``weights="uncertainty"``: ``1/u`` for the absolute loss, ``|x|/u`` (the inverse
        relative uncertainty) for the relative and log losses."""
        return 1.0 / u if self is Loss.ABSOLUTE else np.abs(x) / u

    def residual(self, x: np.ndarray, f: np.ndarray, *, k: float = 1.0, floor: float,
                 logx: np.ndarray | None = None) -> np.ndarray:
        """The unweighted residuals of data ``x`` (scale ``k``) against model values ``f``
        floored at ``floor``; ``logx``: ``ln x`` computed once (log loss)."""
        fs = np.maximum(f, floor)
        if self is Loss.RELATIVE:
            return (k * x) / fs - 1.0
        if self is Loss.ABSOLUTE:
            return k * x - f
        if logx is None:
            logx = np.log(x)
        r = logx + math.log(k) - np.log(fs)
        if self is Loss.LOG:
            return r
        return r * np.sqrt(2.0 / (1.0 + _soft_l1_s(r)))

    def scale_derivative(self, x: np.ndarray, f: np.ndarray, k: float, floor: float
                         ) -> np.ndarray:
        """``d r / d K`` at fixed model values ``f`` (analytic): the scale's Jacobian column.

        For ``robust``, the chain rule: ``d r'/d r = sqrt((1 + s)/2)/s`` with
        ``s = sqrt(1 + r²/c²)``, times ``d r/d K = 1/K`` of the log residual ``r``."""
        if self is Loss.RELATIVE:
            return x / np.maximum(f, floor)
        if self is Loss.ABSOLUTE:
            return x.copy()
        if self is Loss.LOG:
            return np.full(x.shape[0], 1.0 / k)
        s = _soft_l1_s(Loss.LOG.residual(x, f, k=k, floor=floor))
        return np.sqrt(0.5 * (1.0 + s)) / s / k

    def curvature(self, x: np.ndarray, f: np.ndarray, k: float, floor: float,
                  logx: np.ndarray | None = None) -> np.ndarray:
        """Per sample, the cost's true curvature in the residual over the Gauss-Newton one: the
        factor ``rho''(r)/(2 (dr'/dr)²)`` that turns ``J^T J`` (``J`` the Jacobian of the
        transformed residuals ``r'``, ``rho = r'²``) into the Hessian of ``sum(rho(r))`` (over
        2) in an M-estimator's sandwich covariance (Huber 1981, *Robust Statistics*, §6.2; the
        terms in the residuals' second derivatives, zero in expectation at the optimum, left
        out as in Gauss-Newton).

        1 for the ``relative``, ``log`` and ``absolute`` losses (``r' = r``). For ``robust``,
        with ``s = sqrt(1 + r²/c²)``: ``rho = 2c²(s - 1)``, ``rho'' = 2/s³`` (for the cost
        ``sum(r'²)``) and ``(dr'/dr)² = (1 + s)/(2s²)``, so the factor is ``2/(s (1 + s))``: 1 at
        ``r = 0``, ~``2c²/r²`` far out. Without it the standard errors of a robust fit are too
        small: by 1.12x for 5 % log-normal noise (``docs/fitting.md``, "Uncertainties").
        ``logx``: ``ln x`` computed once, as for :meth:`residual`.

        Examples
        --------
        >>> import numpy as np
        >>> Loss.LOG.curvature(np.array([2.0]), np.array([1.0]), 1.0, 0.0).tolist()
        [1.0]
        >>> c = Loss.ROBUST.curvature(np.array([1.0, np.exp(0.1)]), np.ones(2), 1.0, 0.0)
        >>> c.round(6).tolist()          # r = 0, and r = c: s = sqrt(2)
        [1.0, 0.585786]
        """
        if self is not Loss.ROBUST:
            return np.ones(x.shape[0])
        s = _soft_l1_s(Loss.LOG.residual(x, f, k=k, floor=floor, logx=logx))
        return 2.0 / (s * (1.0 + s))

    def closed_form(self, d: np.ndarray, f: np.ndarray, w2: np.ndarray | None) -> float:
        """The optimum ``K`` of :func:`relative_scale` on usable 1-D pairs (dot products: one
        pass)."""
        if self is Loss.RELATIVE:
            q = d / f
            wq = q if w2 is None else w2 * q
            den = float(np.dot(wq, q))
            return float(wq.sum()) / den if den > 0 else 1.0
        if self is Loss.ABSOLUTE:
            wd = d if w2 is None else w2 * d
            den = float(np.dot(wd, d))
            return float(np.dot(wd, f)) / den if den > 0 else 1.0
        r = np.log(f) - np.log(d)
        if w2 is None:
            t = float(r.mean())
        else:
            wsum = float(w2.sum())
            if not wsum > 0:  # every weight 0: no pair constrains K
                return 1.0
            t = float(np.dot(w2, r)) / wsum
        return math.exp(t if self is Loss.LOG else robust_log_scale(r, w2, t))


def _soft_l1_s(r: np.ndarray) -> np.ndarray:
    """``s = sqrt(1 + r²/c²)`` of log residuals ``r`` (``c`` = :data:`ROBUST_SCALE`): the one
    quantity of the robust loss's residual, its scale derivative and its curvature."""
    return np.sqrt(1.0 + (r / ROBUST_SCALE) ** 2)


#: the report's line of each loss
_LOSS_TEXT = {Loss.RELATIVE: "relative, (x - f)/f  (TR75 Eq. 34)",
              Loss.LOG: "log, ln x - ln f", Loss.ABSOLUTE: "absolute, x - f",
              Loss.ROBUST: f"robust, soft-L1 of ln x - ln f (scale {ROBUST_SCALE:g})"}


def robust_log_scale(y: np.ndarray, w2: np.ndarray | None, t: float) -> float:
    """The ``t = ln K`` minimizing ``sum(w² rho(t - y))``, ``rho`` the soft-L1 of the robust loss.

    ``y = ln model - ln data`` per usable pair, ``w2`` the squared weights (None: all 1), ``t``
    the start (the log loss's optimum, the weighted mean of ``y``). Iteratively reweighted least
    squares: each step is the weighted mean of ``y`` with the weights ``w² / sqrt(1 + u²/c²)``,
    ``u = t - y``, which never increases the (convex) cost. Each step also tries the Newton step
    of the smooth convex cost (curvature ``sum(w² / (1 + u²/c²)^(3/2))``) and takes it when its
    cost is no higher: near the optimum that is the quadratic rate, so the scale is solved to
    round-off (the profiled Jacobian differentiates it). It stops after :data:`ROBUST_K_STEPS`
    steps or when ``t`` moves by less than :data:`ROBUST_K_TOL`.

    Examples
    --------
    >>> y = np.array([0.0, 0.01, -0.01, 5.0])          # one outlier
    >>> round(robust_log_scale(y, None, float(y.mean())), 3)   # the mean is 1.25
    0.036
    """
    c2 = ROBUST_SCALE ** 2
    w = np.ones_like(y) if w2 is None else w2

    def cost(v: float) -> float:
        return float(np.dot(w, np.sqrt(1.0 + (v - y) ** 2 / c2)))

    for _ in range(ROBUST_K_STEPS):
        inv_s = 1.0 / np.sqrt(1.0 + (t - y) ** 2 / c2)
        a = w * inv_s
        den = float(a.sum())
        if not den > 0:  # every weight 0 (the callers pass a positive weight sum)
            return t
        grad = float(np.dot(a, t - y))
        irls = t - grad / den
        newton = t - grad / float(np.dot(a, inv_s * inv_s))
        step = (newton if cost(newton) <= cost(irls) else irls) - t
        t += step
        if abs(step) < ROBUST_K_TOL:
            break
    return t


def relative_scale(data: ArrayLike, model: ArrayLike, *, weights: ArrayLike | None = None,
                   loss: str = "relative") -> float:
    """The closed-form scale ``K`` that puts data of unknown scale onto a model: ``K·data ≈ model``.

    TR75 fits relative measurements by putting the scale on the measured values (Eq. 34,
    ``docs/fitting.md``); for the loss of the fit, with weights ``w`` and ``q = data/model``:

    * ``relative``: minimizes ``sum(w² (K q - 1)²)``: ``K = sum(w² q)/sum(w² q²)``;
    * ``absolute``: minimizes ``sum(w² (K data - model)²)``:
      ``K = sum(w² data model)/sum(w² data²)``;
    * ``log``: minimizes ``sum(w² (ln K + ln data - ln model)²)``: ``ln K`` is the weighted mean of
      ``ln model - ln data``;
    * ``robust``: minimizes the soft-L1 cost of the same log residuals (:class:`Loss`): from the
      log loss's ``ln K``, iteratively reweighted (:func:`robust_log_scale`).

    Only pairs where both values are finite and the model is positive take part (``log`` and
    ``robust`` also need positive data). Returns 1.0 where no pair qualifies or the optimum is
    not a finite positive number.

    Examples
    --------
    >>> relative_scale([2.0, 4.0], [1.0, 2.0])
    0.5
    >>> relative_scale([2.0, 4.0], [1.0, 2.0], loss="log")
    0.5
    """
    if loss not in LOSSES:
        raise ValueError(f"loss must be one of {', '.join(LOSSES)}; got {loss!r}")
    d, f = np.broadcast_arrays(np.asarray(data, dtype=np.float64),
                               np.asarray(model, dtype=np.float64))
    w2 = None if weights is None else np.broadcast_to(
        np.asarray(weights, dtype=np.float64) ** 2, d.shape)
    ok = np.isfinite(d) & np.isfinite(f) & (f > 0)
    if w2 is not None:
        ok &= np.isfinite(w2)
    kind = Loss(loss)
    if kind.positive_data:
        ok &= d > 0
    if not ok.all():  # only usable pairs take part (copies: the common case needs none)
        if not ok.any():
            return 1.0
        d, f = d[ok], f[ok]
        w2 = None if w2 is None else w2[ok]
    d, f = d.ravel(), f.ravel()
    w2 = None if w2 is None else w2.ravel()
    k = kind.closed_form(d, f, w2)
    return k if math.isfinite(k) and k > 0 else 1.0
