"""Figures of merit and uncertainties of a fitted channel (``docs/fitting.md``, "Uncertainties
and statistics").

* :class:`GoodnessOfFit` -- ``chi2 = sum(r^2)`` of the loss residuals (weighted), ``redchi =
  chi2/(N - n_varys)``, lmfit's ``aic = N ln(chi2/N) + 2 n_varys`` and ``bic = N ln(chi2/N) +
  ln(N) n_varys``, TR75's ``sigma`` (:func:`tr75_sigma`, Eq. 34) and :func:`rms_log`;
* :class:`Covariance` -- of a channel's fit (:meth:`Covariance.at_optimum`), the
  heteroscedasticity-consistent *sandwich* ``covar = N/(N - n_varys) H^-1 J^T diag(r^2) J H^-1``
  (White 1980, the "HC1" form), ``J`` the central-difference Jacobian of the residuals ``r`` at
  the optimum (free parameters, plus the analytic column of the scale ``K`` when it is free), ``H
  = J^T diag(c) J`` the cost's curvature: ``c`` is 1 for the relative, log and absolute losses
  (``H = J^T J``) and the soft-L1's ``rho''/(2 (dr'/dr)^2)`` per sample for the robust loss
  (:meth:`roughbrdf.quantity.Loss.curvature`; an M-estimator's sandwich, Huber 1981 §6.2: with
  ``J^T J`` the robust fits' standard errors were 1.1-1.4x too small, ``docs/fitting.md``,
  "Coverage on the shared paints"). Why not lmfit's ``(J^T J)^-1 chi2/(N - n_varys)``: that
  assumes every residual has the same variance, and a gonioreflectometer's do not -- its noise is
  multiplicative plus an additive floor, so in a ratio or log loss the dim samples scatter far
  more than the peak that fixes the lobe's width and weight; the classical form then inflates
  those parameters' errors (1-sigma intervals covered the truth in 85-95 % of synthetic two-lobe
  fits instead of 68 %; the sandwich: 60-80 %, ``tests/fitting/test_fit_coverage.py``). Where the
  residuals are homoscedastic the two agree. ``stderr = sqrt(diag(covar))``, ``correl`` is
  ``covar`` normalized. A singular ``J^T J`` gives NaN and a note for the message; joint fits
  (:mod:`~roughbrdf.fitting.kinds.joint`) take the same sandwich over the stacked channels;
* :func:`at_bound` -- the parameters at (or within :data:`AT_BOUND_RTOL` of the width of their
  bounds from) a bound. They get no standard error: the covariance describes the cost as a
  quadratic bowl around an interior optimum, which an active bound is not (the optimum there is
  set by the bound, not by the data, and the bowl may not even curve up along that
  parameter). The covariance of the others is computed with them held at their bounds;
* :func:`limit_kinds` -- whether each bound reached is a *physical* limit (an edge of the
  parameter's domain, :attr:`Parameter.domain <roughbrdf.models.parameters.Parameter.domain>`:
  ``k = 0``, a reflectance at 0 or 1) or only a *search* limit (a bound of the search that is no
  domain edge, such as coated ``n = 2.5``): a value on a search limit is not a result.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from ..problem.objective import Objective, ObjectiveSpec

__all__ = ["AT_BOUND_RTOL", "Covariance", "GoodnessOfFit", "at_bound", "bound_and_undetermined",
           "limit_kinds", "rms_log", "tr75_sigma"]

#: a parameter within this fraction of the width of its bounds from a bound is "at the bound"
AT_BOUND_RTOL = 1e-6
#: a non-zero bound below this fraction of the width marks a search over decades: "at" it
#: means within ``AT_BOUND_RTOL`` of the bound itself
LOG_RANGE = 1e-3


def at_bound(theta: np.ndarray, lower: np.ndarray, upper: np.ndarray, names: Sequence[str],
             rtol: float = AT_BOUND_RTOL) -> dict[str, str]:
    """``{name: "lower" | "upper"}`` for the parameters at a bound.

    A parameter is at a bound when it is within ``rtol`` times the width of its bounds of it
    (``rtol`` times ``max(1, |bound|)`` when the other bound is infinite), or, for a bound
    other than 0 below :data:`LOG_RANGE` times that width, within ``rtol`` times the bound:
    a parameter searched over many decades (an ABC PSD's ``A`` in [1e-14, 1e3]) is not "at"
    its lower bound 1e-14 when it is 2e-5.

    Examples
    --------
    >>> at_bound(np.array([5e-13, 0.5, 4.99999999]), np.zeros(3), np.array([10.0, 1.0, 5.0]),
    ...          ["k", "e", "n"])
    {'k': 'lower', 'n': 'upper'}
    >>> at_bound(np.array([2e-5, 1e-14]), np.full(2, 1e-14), np.full(2, 1e3), ["A", "A2"])
    {'A2': 'lower'}
    """
    out: dict[str, str] = {}
    for nm, t, lo, hi in zip(names, theta, lower, upper, strict=True):
        span = hi - lo
        for side, b, dist in (("lower", lo, t - lo), ("upper", hi, hi - t)):
            if not math.isfinite(b):
                continue
            width = span if math.isfinite(span) else max(1.0, abs(b))
            # a bound far below the width (a search over decades): relative to the bound
            tol = rtol * (abs(b) if 0.0 < abs(b) < LOG_RANGE * width else width)
            if dist <= tol:
                out[nm] = side
                break
    return out


def bound_and_undetermined(obj: Objective, theta: np.ndarray, k: float, r: np.ndarray
                           ) -> tuple[dict[str, str], list[str], np.ndarray]:
    """The parameters :func:`at_bound` and those *undetermined* at the optimum ``theta`` of
    ``obj`` (scale ``k``, residuals ``r``), with the central-difference Jacobian there.

    Undetermined: a parameter without effect at the optimum
    (:func:`~roughbrdf.fitting.solvers.stationary.flat`: a lobe's width at weight 0, TR75's ``e``
    when
    ``n = 1`` turns its lobe off). Where it stopped is any value, so it is not "at a bound"
    even where it stopped on one (two machines' rounding left it on a bound or not), and it
    is held in the covariance as the parameters at a bound are: the others keep their
    standard errors (with it, ``J^T J`` is singular and none would have one).
    """
    from ..solvers.stationary import flat

    spec = obj.spec
    jac = obj.jac_central(theta, k)
    none = [nm for nm, fl in zip(spec.free, flat(jac, r, theta, spec.lower, spec.upper),
                                 strict=True) if fl]
    bound = {nm: side for nm, side in at_bound(theta, spec.lower, spec.upper,
                                               spec.free).items() if nm not in none}
    return bound, none, jac


def limit_kinds(at: Mapping[str, str], bounds: Mapping[str, tuple[float, float]],
                parameters: Sequence[Any],
                physical: Mapping[str, tuple[float, float] | None] | None = None
                ) -> dict[str, str]:
    """``{name: "physical-lower" | "physical-upper" | "search-lower" | "search-upper"}`` for
    the parameters ``at`` a bound (:func:`at_bound`).

    ``bounds`` are the search bounds (``name -> (low, high)``), ``parameters`` the model's
    :class:`~roughbrdf.models.parameters.Parameter` objects. A bound is physical when it is the
    parameter's domain edge on that side (to 1e-9 relative), or the edge of its ``physical``
    range (``name -> (low, high)``: microfacet ``ks = 1``, the most one interface reflects,
    :func:`roughbrdf.fitting.results.physical.physical_range`), else a search limit. A name with no
    parameter of that name (a joint fit's ``name[channel]``) is looked up by its stem.

    Examples
    --------
    >>> from roughbrdf.models.parameters import nonnegative, positive
    >>> ps = [nonnegative("k", 0.0, (0.0, 10.0), "1", ""), positive("n", 1.5, (0.2, 5.0), "1", "")]
    >>> limit_kinds({"k": "lower", "n": "upper"}, {"k": (0.0, 10.0), "n": (0.2, 5.0)}, ps)
    {'k': 'physical-lower', 'n': 'search-upper'}
    """
    by_name = {p.name: p for p in parameters}
    out: dict[str, str] = {}
    for nm, side in at.items():
        par = by_name.get(nm, by_name.get(nm.split("[")[0]))
        lo, hi = bounds.get(nm, (math.nan, math.nan))
        b = lo if side == "lower" else hi
        edge = math.nan if par is None else par.domain[0 if side == "lower" else 2]
        phys = (physical or {}).get(nm) or (physical or {}).get(nm.split("[")[0])
        edges = [edge, math.nan if phys is None else phys[0 if side == "lower" else 1]]
        # an infinite edge is never reached by a finite bound; NaN (unknown) is a search limit
        hit = any(math.isfinite(e) and abs(b - e) <= 1e-9 * max(1.0, abs(e)) for e in edges)
        out[nm] = f"{'physical' if hit else 'search'}-{side}"
    return out


def tr75_sigma(data: np.ndarray, model: np.ndarray, scale: float = 1.0,
               floor: float = 0.0) -> float:
    """TR75's sigma (Eq. 34): the r.m.s. of ``(K x - f)/f`` (``f`` floored at ``floor``).

    Examples
    --------
    >>> import numpy as np
    >>> round(tr75_sigma(np.array([1.0, 2.0]), np.array([1.1, 1.8])), 6)
    0.101514
    """
    rel = (scale * data - model) / np.maximum(model, floor)
    return float(np.sqrt(np.mean(rel * rel))) if rel.size else math.nan


def rms_log(data: np.ndarray, model: np.ndarray, scale: float = 1.0) -> float:
    """r.m.s. of ``ln(K x) - ln f`` over the samples where both are positive (NaN if none).

    Examples
    --------
    >>> import numpy as np
    >>> round(rms_log(np.array([1.0, -1.0]), np.array([np.e, 1.0])), 12)
    1.0
    """
    pos = (data > 0) & (model > 0)
    if not pos.any():
        return math.nan
    return float(np.sqrt(np.mean((np.log(scale * data[pos]) - np.log(model[pos])) ** 2)))


@dataclass(frozen=True)
class GoodnessOfFit:
    """Figures of merit of a fitted channel (the ``metrics`` of ``fit.json``).

    Examples
    --------
    >>> import numpy as np
    >>> g = GoodnessOfFit.of(np.array([0.1, -0.1, 0.2]), np.array([1.0, 2.0, 3.0]),
    ...                      np.array([1.0, 2.0, 3.0]), scale=1.0, n_varys=1)
    >>> round(g.chi2, 12), round(g.redchi, 12), g.sigma
    (0.06, 0.03, 0.0)
    """

    chi2: float
    redchi: float
    aic: float
    bic: float
    sigma: float
    rms_log: float
    n_points: int
    n_varys: int

    @classmethod
    def of(cls, residual: np.ndarray, data: np.ndarray, model: np.ndarray, *, scale: float,
           n_varys: int, floor: float = 0.0) -> GoodnessOfFit:
        """From the loss residuals, the data ``x``, the model values ``f`` and the scale ``K``."""
        n = residual.size
        chi2 = float(residual @ residual)
        dof = n - n_varys
        lchi = math.log(chi2 / n) if chi2 > 0 else -math.inf
        return cls(chi2=chi2, redchi=chi2 / dof if dof > 0 else math.nan,
                   aic=n * lchi + 2 * n_varys, bic=n * lchi + math.log(n) * n_varys,
                   sigma=tr75_sigma(data, model, scale, floor),
                   rms_log=rms_log(data, model, scale), n_points=int(n), n_varys=n_varys)

    @property
    def dof(self) -> int:
        """Degrees of freedom ``N - n_varys``."""
        return self.n_points - self.n_varys

    def as_dict(self) -> dict[str, float | int]:
        """``{"sigma", "rms_log", "chi2", "redchi", "aic", "bic", "n_points", "n_varys"}``."""
        return {"sigma": self.sigma, "rms_log": self.rms_log, "chi2": self.chi2,
                "redchi": self.redchi, "aic": self.aic, "bic": self.bic,
                "n_points": self.n_points, "n_varys": self.n_varys}


@dataclass(frozen=True)
class Covariance:
    """Covariance of the fitted parameters (the free ones, then ``"scale"`` if it is free).

    Examples
    --------
    >>> import numpy as np
    >>> c = Covariance.from_jacobian(np.array([[1.0, 0.0], [0.0, 2.0], [1.0, 2.0]]),
    ...                              ["a", "b"], chi2=1.0, dof=1)
    >>> c.stderr().round(6).tolist(), round(c.correl()["a"]["b"], 6)
    ([0.816497, 0.408248], -0.5)
    """

    matrix: np.ndarray
    names: list[str]
    note: str = ""

    @classmethod
    def from_jacobian(cls, jmat: np.ndarray, names: list[str], *, chi2: float,
                      dof: int, residual: np.ndarray | None = None,
                      curvature: np.ndarray | None = None) -> Covariance:
        """``(J^T J)^-1 chi2/dof`` through the SVD of ``J``, or with the ``residual`` at the
        optimum the sandwich ``N/dof H^-1 J^T diag(r^2) J H^-1`` (module notes), ``H = J^T
        diag(c) J`` with the loss's ``curvature`` factors ``c`` per sample (None: all 1, ``H =
        J^T J``); NaN (and a note) if singular."""
        p = jmat.shape[1]
        if p == 0:
            return cls(np.empty((0, 0)), names)
        try:
            inv = cls.curvature_inverse(jmat, None if residual is None else curvature)
            if residual is None:
                return cls(inv * (chi2 / max(dof, 1)), names)
            meat = (jmat * (residual * residual)[:, None]).T @ jmat
            return cls(inv @ meat @ inv * (jmat.shape[0] / max(dof, 1)), names)
        except np.linalg.LinAlgError:
            return cls(np.full((p, p), np.nan), names,
                       "; covariance not estimated (singular J^T J: a parameter has no effect)")

    @staticmethod
    def curvature_inverse(jmat: np.ndarray, curvature: np.ndarray | None = None) -> np.ndarray:
        """``H^-1``, ``H = J^T diag(c) J`` (``c`` the loss's curvature factors, None: all 1),
        through the SVD of ``sqrt(c) J``; ``numpy.linalg.LinAlgError`` where ``H`` is singular
        (a condition number of ``J`` above 1e12).

        Examples
        --------
        >>> Covariance.curvature_inverse(np.array([[1.0, 0.0], [0.0, 2.0]])).tolist()
        [[1.0, 0.0], [0.0, 0.25]]
        """
        # H = (sqrt(c) J)^T (sqrt(c) J): its inverse through the SVD of the scaled rows
        bread = jmat if curvature is None else jmat * np.sqrt(curvature)[:, None]
        _, s, vt = np.linalg.svd(bread, full_matrices=False)
        if not np.all(np.isfinite(s)) or s[0] == 0 or s[-1] <= s[0] * 1e-12:
            raise np.linalg.LinAlgError("singular")
        return (vt.T / (s * s)) @ vt

    @classmethod
    def at_optimum(cls, obj: Objective, theta: np.ndarray, f: np.ndarray, k: float, *,
                   chi2: float, dof: int, held: Sequence[str] = (),
                   jac: np.ndarray | None = None) -> Covariance:
        """The sandwich (module notes) from the central-difference Jacobian of ``obj`` at
        ``theta`` (scale held at ``k``), when the scale is free its analytic column at the model
        values ``f``, and the residuals there.

        Parameters named in ``held`` (those :func:`at_bound`) are held where they are: they
        get no column, and NaN rows and columns in the result (no standard error, no
        correlation). ``jac``: that Jacobian (every free parameter's column), when the caller
        has it already."""
        names = list(obj.spec.free)
        keep = [j for j, nm in enumerate(names) if nm not in held]
        # C order as jac_central's own (the SVD's last bits follow the memory layout)
        cols = [obj.jac_central(theta, k, columns=keep) if jac is None
                else np.ascontiguousarray(jac[:, keep])]
        if obj.spec.free_scale:
            cols.append(obj.scale_column(f, k)[:, None])
            names.append("scale")
            keep.append(len(names) - 1)
        inner = cls.from_jacobian(np.hstack(cols), [names[j] for j in keep], chi2=chi2,
                                  dof=dof, residual=obj.residual_of(f, k),
                                  curvature=obj.curvature_of(f, k))
        full = np.full((len(names), len(names)), np.nan)
        full[np.ix_(keep, keep)] = inner.matrix
        return cls(full, names, inner.note)

    @classmethod
    def unestimated(cls, spec: ObjectiveSpec, note: str) -> Covariance:
        """A covariance of NaN over ``spec``'s fitted names (its free parameters, then
        ``"scale"`` when free), as :meth:`at_optimum` orders them, with ``note``: none was
        estimated (a cross-validation fold's fit only predicts).

        Examples
        --------
        >>> import roughbrdf as rb
        >>> from roughbrdf.fitting.problem.objective import ObjectiveSpec
        >>> c = Covariance.unestimated(ObjectiveSpec(rb.model("lambertian"), ["rho"], [0.0],
        ...                                          [1.0], free_scale=True), "; none")
        >>> c.names, bool(np.isnan(c.matrix).all())
        (['rho', 'scale'], True)
        """
        names = [*spec.free, *(["scale"] if spec.free_scale else [])]
        return cls(np.full((len(names), len(names)), np.nan), names, note)

    def stderr(self) -> np.ndarray:
        """``sqrt(diag(covar))`` (NaN where not estimable)."""
        d = np.diag(self.matrix)
        return np.sqrt(np.where(d >= 0, d, np.nan))

    def correl(self) -> dict[str, dict[str, float]]:
        """``name -> {other: correlation}``."""
        sd = self.stderr()
        with np.errstate(divide="ignore", invalid="ignore"):
            corr = self.matrix / np.outer(sd, sd)
        return {a: {b: float(corr[i, m]) for m, b in enumerate(self.names) if m != i}
                for i, a in enumerate(self.names)}
