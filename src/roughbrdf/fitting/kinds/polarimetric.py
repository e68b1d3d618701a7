"""Fitting Mueller-matrix data (``docs/fitting.md``, "Polarimetric data").

A :class:`~roughbrdf.measurement.Measurement` whose channels are Mueller elements
(``measurement.mueller`` set) is fitted with all its elements at once, as TR75 constrained the
index with polarized data. The residuals of one sample are

* ``m00``: the usual loss of :mod:`~roughbrdf.fitting.problem.objective` (``relative`` by default,
  ``w (K x - f)/f``) on the unpolarized BRDF, with the data scale ``K`` of relative data;
* every other element held: the **absolute** difference of the normalized elements,
  ``w_p w_ij (M_ij/M_00 - m_ij/m00)``, ``M`` the model's Mueller matrix
  (:meth:`roughbrdf.models.Model.mueller`, in the measurement's basis) and ``m`` the data.

Both parts are dimensionless: a 1 % error of ``m00`` costs as much as an error of 0.01 in a
normalized element. ``w_p`` is ``polarimetric_weight`` (default :data:`POLARIMETRIC_WEIGHT` = 1)
and ``w_ij`` the element's weight (1, an array, or ``1/u`` with ``weights="uncertainty"``, ``u``
the uncertainty of ``m_ij/m00``). Normalized elements do not depend on ``K`` nor on the
absolute calibration of the data: with relative data they still fix the index.

:func:`fit_mueller` is what :func:`roughbrdf.fit` runs for such a measurement. It reuses the
whole single-channel machinery: :func:`~roughbrdf.fitting.problem.data.prepare_channel` on ``m00``
(what is left out, and why), the global search
(:class:`~roughbrdf.fitting.solvers.search.MultiStart`
with a :class:`MuellerObjective`), the covariance and the figures of merit
(:mod:`~roughbrdf.fitting.results.statistics`, on all residuals). The result is a
:class:`MuellerFitResult` with one :class:`MuellerChannelFit` labelled ``"mueller"``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ...errors import ArgumentError
from ...instrument import InstrumentGeometry
from ...measurement import MUELLER_ELEMENTS, Measurement
from ...models.factory import as_model, is_auto, model_label
from ...quantity import Quantity
from ..problem.data import DataOptions, prepare_channel, where
from ..problem.objective import BAD_RESIDUAL, Objective, ObjectiveSpec
from ..problem.options import FitOptions, check_polarimetric_weight
from ..problem.plan import FitPlan, check_enough_data
from ..results.result import ChannelFit, FitResult
from ..solvers.search import MultiStart, SearchOptions, SearchOutcome, progress_bar
from ..solvers.threads import single_thread_blas

if TYPE_CHECKING:
    from ...models import Model

__all__ = ["MuellerData", "MuellerObjective", "MuellerChannelFit", "MuellerFitResult",
           "fit_mueller", "prepare_mueller", "check_polarimetric_weight", "POLARIMETRIC_WEIGHT"]

#: default relative weight of the normalized elements against ``m00`` (module notes)
POLARIMETRIC_WEIGHT = 1.0


# --------------------------------------------------------------------------------------------
# the data
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class MuellerData:
    """The samples of a Mueller measurement that enter a fit.

    Attributes
    ----------
    m00 : numpy.ndarray, shape (N,)
        Measured ``m00`` (the measurement's quantity and scale).
    normalized : numpy.ndarray, shape (N, E)
        Measured ``m_ij/m00`` of the ``E`` other elements held.
    elements : tuple of int
        Their flat indices ``4 i + j`` (1 ... 15), the columns of ``normalized``.
    geometry : InstrumentGeometry
        Where the model is evaluated (through the aperture, if any); unpolarized.
    weights, element_weights : numpy.ndarray or None
        Weights of the ``m00`` residuals (N,) and of the normalized ones (N, E), the latter
        without the polarimetric weight.
    basis : str
        Polarization basis of the elements (:meth:`roughbrdf.models.Model.mueller`).
    label, index, excluded
        As :class:`~roughbrdf.fitting.problem.data.ChannelData`.
    """

    m00: np.ndarray
    normalized: np.ndarray
    elements: tuple[int, ...]
    geometry: InstrumentGeometry
    weights: np.ndarray | None = None
    element_weights: np.ndarray | None = None
    basis: str = "psps"
    label: str = "mueller"
    index: np.ndarray = field(default=None, repr=False)  # type: ignore[arg-type]
    excluded: dict[str, int] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.index is None:
            object.__setattr__(self, "index", np.arange(self.m00.size))

    @property
    def values(self) -> np.ndarray:
        """``m00`` (what the single-channel parts of a fit compare)."""
        return self.m00

    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.m00.size)

    @property
    def element_names(self) -> list[str]:
        """``["m01", ...]``: the names of the normalized columns."""
        return [MUELLER_ELEMENTS[e] for e in self.elements]

    def take(self, sub: np.ndarray) -> MuellerData:
        """The samples at positions ``sub`` (the exploration subsample)."""
        return replace(self, m00=self.m00[sub], normalized=self.normalized[sub],
                       geometry=self.geometry.take(sub),
                       weights=None if self.weights is None else self.weights[sub],
                       element_weights=None if self.element_weights is None
                       else self.element_weights[sub], index=self.index[sub])


def _element_weights(weights: Any, meas: Measurement, elements: Sequence[int],
                     norm: np.ndarray) -> np.ndarray | None:
    """Weights of the normalized elements, shape (N, E) (None: unweighted).

    ``"uncertainty"``: ``1/u`` with ``u`` the uncertainty of ``m_ij/m00`` (given as such for
    normalized data; first-order propagation ``sqrt(u_ij^2 + (m_ij/m00)^2 u_00^2)/|m00|`` for
    absolute data), 0 where ``u`` is not positive. An array of shape (N,) weighs every residual
    of a sample alike, one of shape (N, C) each element by its column."""
    if weights is None:
        return None
    cols = [meas.channel_index(MUELLER_ELEMENTS[e]) for e in elements]
    if isinstance(weights, str):  # checked by prepare_channel: "uncertainty", with one
        if meas.uncertainty is None:
            return None  # prepare_channel raises, naming the argument
        u = meas.uncertainty[:, cols]
        if meas.mueller == "absolute":
            j00 = meas.channel_index("m00")
            m00, u00 = meas.values[:, j00:j00 + 1], meas.uncertainty[:, j00:j00 + 1]
            with np.errstate(divide="ignore", invalid="ignore"):
                u = np.sqrt(u * u + (norm * u00) ** 2) / np.abs(m00)
        with np.errstate(divide="ignore", invalid="ignore"):
            w = 1.0 / u
        # u <= 0 or not finite (no uncertainty given; m00 = 0 in the propagation): weight 0,
        # as channel_weights does for an ordinary channel
        return np.where(np.isfinite(w) & (u > 0), w, 0.0)
    w = np.asarray(weights, dtype=float)
    if not np.all(np.isfinite(w)) or np.any(w < 0):  # prepare_channel checked only m00's
        raise ArgumentError("weights", "weights must be finite and >= 0")
    if w.ndim == 2 and w.shape == meas.values.shape:
        return np.ascontiguousarray(w[:, cols])
    return np.repeat(np.broadcast_to(w.reshape(-1), (meas.n_samples,))[:, None], len(cols), 1)


def _unusable_rows(meas: Measurement, norm: np.ndarray, opts: DataOptions, place: str
                   ) -> tuple[np.ndarray, dict[str, int]]:
    """Rows without normalized elements: ``m00 <= 0`` (needs ``negative="drop"``) and
    non-finite elements (needs ``nonfinite="drop"``); else ArgumentError naming the option."""
    m00 = meas.values[:, meas.channel_index("m00")]
    low = np.isfinite(m00) & (m00 <= 0)
    nonfinite = np.isfinite(m00) & ~low & ~np.isfinite(norm).all(axis=1)
    if low.any() and opts.negative != "drop":
        raise ArgumentError("negative", f"{place}: {int(low.sum())} sample(s) have m00 <= 0, "
                            "where the normalized elements m_ij/m00 are not defined; leave "
                            "them out", fix="drop")
    if nonfinite.any() and opts.nonfinite != "drop":
        rows = np.flatnonzero(nonfinite)
        raise ArgumentError("nonfinite", f"{place}: {rows.size} sample(s) have non-finite "
                            f"Mueller elements (first at sample {rows[0]})", fix="drop")
    return low | nonfinite, {"negative": int(low.sum()), "nonfinite": int(nonfinite.sum())}


def prepare_mueller(model: Model, meas: Measurement, opts: DataOptions) -> MuellerData:
    """The samples of a Mueller measurement that enter the fit of ``model``.

    ``m00`` goes through :func:`~roughbrdf.fitting.problem.data.prepare_channel` (every rule of an
    ordinary channel: extrapolated, non-finite and negative values, weights, fit domain, model
    domain); before that, samples with ``m00 <= 0`` or a non-finite element are left out
    (counted as ``negative`` and ``nonfinite``) when ``negative="drop"`` /
    ``nonfinite="drop"`` say so, and raise otherwise.
    """
    elements = tuple(sorted(MUELLER_ELEMENTS.index(c) for c in meas.channels if c != "m00"))
    norm_all = meas.mueller_array("normalized").reshape(-1, 16)[:, list(elements)]
    unusable, counts = _unusable_rows(meas, norm_all, opts, where(meas, "m00"))
    rows = np.flatnonzero(~unusable)
    w = opts.weights
    if w is not None and not isinstance(w, str):
        arr = np.asarray(w, dtype=float)
        w = arr[rows] if arr.ndim and arr.shape[0] == meas.n_samples else arr
    sub = meas.subset(rows)
    d = prepare_channel(model, sub, sub.channel_index("m00"), replace(opts, weights=w))
    idx = rows[d.index]
    norm = norm_all[idx]
    ew = _element_weights(opts.weights, meas, elements, norm_all)
    excluded = dict(d.excluded)
    for key, count in counts.items():
        excluded[key] = excluded.get(key, 0) + count
    return MuellerData(d.values, np.ascontiguousarray(norm), elements, d.geometry, d.weights,
                       None if ew is None else np.ascontiguousarray(ew[idx]),
                       str(meas.mueller_basis), "mueller", idx, excluded)


# --------------------------------------------------------------------------------------------
# the residuals
# --------------------------------------------------------------------------------------------
def mueller_values(model: Model, geometry: InstrumentGeometry, quantity: Quantity,
                   basis: str) -> np.ndarray:
    """The model's Mueller matrices as the instrument reads them, shape (N, 16) (flattened
    row-major): :meth:`~roughbrdf.models.Model.mueller` at every direction of ``geometry``
    (times ``cos theta_r`` for BRDF cos data), averaged over the aperture stencil."""
    g = geometry.geometry
    m = np.asarray(model.mueller(g.theta_i, g.theta_r, g.phi, basis=basis), dtype=float)
    m = m.reshape(-1, 16)
    if quantity.cosine_weighted:
        m = m * np.cos(g.theta_r).reshape(-1, 1)
    if geometry.weights is None:
        return m
    s = geometry.weights.size
    return np.einsum("nsk,s->nk", m.reshape(geometry.n, s, 16), geometry.weights)


@dataclass(eq=False)
class MuellerObjective(Objective):
    """Residuals of a Mueller measurement (module notes): ``N`` for ``m00``, then ``N x E``
    for the normalized elements (sample-major).

    :meth:`values` returns the model's flattened Mueller matrices, shape (N, 16); the
    Jacobians, the scale and the search are those of
    :class:`~roughbrdf.fitting.problem.objective.Objective`.
    """

    data: MuellerData  # type: ignore[assignment]
    weight: float = POLARIMETRIC_WEIGHT

    def __post_init__(self) -> None:
        super().__post_init__()
        ew = self.data.element_weights
        self.ew = self.weight * (np.ones_like(self.data.normalized) if ew is None else ew)
        self.cols = list(self.data.elements)

    @property
    def n(self) -> int:
        """Number of residuals: ``N (1 + E)``."""
        return self.data.n * (1 + len(self.cols))

    def values(self, theta: ArrayLike) -> np.ndarray:
        """The model's flattened Mueller matrices at the samples, shape (N, 16)."""
        self.nfev += 1
        return mueller_values(self.model_at(theta), self.data.geometry,
                              Quantity.parse(self.spec.quantity), self.data.basis)

    def scale(self, f: np.ndarray) -> float:
        """Data scale ``K`` from the model's ``m00`` (``f`` of shape (N, 16) or (N,))."""
        return super().scale(f[:, 0] if f.ndim == 2 else f)

    def normalized_of(self, f: np.ndarray) -> np.ndarray:
        """The model's normalized elements ``M_ij/M_00`` of the held elements, (N, E).

        A ratio is well defined however small ``M_00`` is (far in a lobe's tail it may be
        1e-20 and the ratio still right), so there is no floor; where ``M_00`` is exactly 0
        (no light: an underflowed lobe) the model's elements are taken as 0, a bounded
        residual (the ``m00`` residual already says the model is wrong there)."""
        m00 = f[:, :1]
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(m00 > 0, f[:, self.cols] / np.where(m00 > 0, m00, 1.0), 0.0)

    def residual_of(self, f: np.ndarray, k: float | None = None) -> np.ndarray:
        """``[r_00 (N), r_ij (N x E)]`` for model values ``f`` (N, 16) and scale ``k``."""
        r00 = super().residual_of(f[:, 0], k)
        rn = (self.normalized_of(f) - self.data.normalized) * self.ew
        if not np.isfinite(rn).all():  # a model that overflows: the optimizer steps back
            rn = np.where(np.isfinite(rn), rn, BAD_RESIDUAL)
        return np.concatenate([r00, rn.ravel()])

    def curvature_of(self, f: np.ndarray, k: float) -> np.ndarray:
        """The loss's curvature factors of ``m00``, then 1 for the normalized elements (their
        absolute differences are plain least squares)."""
        return np.concatenate([super().curvature_of(f[:, 0], k), np.ones(self.n - self.data.n)])

    def scale_column(self, f: np.ndarray, k: float) -> np.ndarray:
        """``d r / d K``: that of ``m00``; the normalized elements do not depend on ``K``."""
        return np.concatenate([super().scale_column(f[:, 0], k),
                               np.zeros(self.n - self.data.n)])


class _MuellerSearch(MultiStart):
    """:class:`~roughbrdf.fitting.solvers.search.MultiStart` on :class:`MuellerObjective`."""

    def __init__(self, spec: ObjectiveSpec, options: SearchOptions, weight: float,
                 on_start: Any = None) -> None:
        super().__init__(spec, options, on_start)
        self.weight = weight

    def objectives(self, data: Any) -> tuple[Objective, Objective]:
        full = MuellerObjective(self.spec, data, weight=self.weight)
        n_sub = self.options.subsample
        if n_sub is None or data.n <= n_sub:
            return full, full
        sub = np.sort(self.rng.choice(data.n, size=int(n_sub), replace=False))
        return full, MuellerObjective(self.spec, data.take(sub), weight=self.weight)


# --------------------------------------------------------------------------------------------
# the result
# --------------------------------------------------------------------------------------------
@dataclass
class MuellerChannelFit(ChannelFit):
    """The fit of a Mueller measurement: a :class:`~roughbrdf.fitting.results.result.ChannelFit`
    (``data``/``fitted``: ``m00``; ``sigma``, ``rms_log``: of ``m00``; ``chi2``, AIC, BIC and
    the covariance: of all residuals) with the normalized elements.

    Attributes
    ----------
    elements : list of str
        The normalized elements fitted (``"m01"``...).
    normalized_data, normalized_fitted : numpy.ndarray, shape (N, E)
        Measured ``m_ij/m00`` and the fitted model's ``M_ij/M_00``.
    polarimetric_weight : float
        ``w_p`` (module notes).
    basis : str
        Polarization basis of the elements.
    chi2_m00, chi2_normalized : float
        The parts of ``chi2`` (weighted sums of squares).
    rms_normalized : dict
        ``element -> r.m.s. of M_ij/M_00 - m_ij/m00`` (unweighted), and ``"all"``.
    """

    elements: list[str] = field(default_factory=list)
    normalized_data: np.ndarray | None = field(default=None, repr=False)
    normalized_fitted: np.ndarray | None = field(default=None, repr=False)
    polarimetric_weight: float = POLARIMETRIC_WEIGHT
    basis: str = "psps"
    chi2_m00: float = math.nan
    chi2_normalized: float = math.nan
    rms_normalized: dict[str, float] = field(default_factory=dict)

    @classmethod
    def from_mueller_search(cls, obj: MuellerObjective, outcome: SearchOutcome,
                            elapsed: float) -> MuellerChannelFit:
        """The result at the search's optimum, statistics on all residuals of ``obj`` (the
        figures of merit, sigma and rms-log, on m00)."""
        data = obj.data
        f = obj.values(outcome.theta)
        fields = ChannelFit.fields_at_optimum(obj, outcome, elapsed, f, data.m00, f[:, 0])
        r = fields["residual"]
        fn = obj.normalized_of(f)
        diff = fn - data.normalized
        rms = {nm: float(np.sqrt(np.mean(diff[:, c] ** 2)))
               for c, nm in enumerate(data.element_names)}
        rms["all"] = float(np.sqrt(np.mean(diff ** 2))) if diff.size else math.nan
        return cls(
            **fields, elements=data.element_names,
            normalized_data=data.normalized, normalized_fitted=fn,
            polarimetric_weight=obj.weight, basis=data.basis,
            chi2_m00=float(r[:data.n] @ r[:data.n]),
            chi2_normalized=float(r[data.n:] @ r[data.n:]), rms_normalized=rms)

    @property
    def metrics(self) -> dict[str, float | int]:
        """The figures of merit of :class:`ChannelFit` and the parts of ``chi2``."""
        return {**super().metrics, "chi2_m00": self.chi2_m00,
                "chi2_normalized": self.chi2_normalized}

    def to_dict(self) -> dict[str, Any]:
        """The channel's ``fit.json`` entry, with ``"mueller"``: the elements, the weight,
        the basis and the r.m.s. of each normalized element."""
        out = super().to_dict()
        out["mueller"] = {"elements": self.elements, "basis": self.basis,
                          "polarimetric_weight": self.polarimetric_weight,
                          "rms_normalized": self.rms_normalized}
        return out

    def report_lines(self) -> list[str]:
        """The report's ``[[Mueller elements]]`` block
        (:mod:`~roughbrdf.fitting.results.report`)."""
        rms = ", ".join(f"{nm} {v:.3g}" for nm, v in self.rms_normalized.items()
                        if nm != "all")
        return ["[[Mueller elements]] (normalized, basis "
                f"{self.basis}; weight {self.polarimetric_weight:g} against m00)",
                f"    chi-square m00     = {self.chi2_m00:.6g}",
                f"    chi-square m_ij/m00= {self.chi2_normalized:.6g}",
                f"    r.m.s. m_ij/m00    = {self.rms_normalized.get('all', math.nan):.4g}",
                f"    r.m.s. by element  : {rms or 'none'}"]


@dataclass
class MuellerFitResult(FitResult):
    """:class:`~roughbrdf.fitting.results.result.FitResult` of a Mueller fit: one
    :class:`MuellerChannelFit` labelled ``"mueller"``; plots show ``m00``
    (:meth:`plot_data`)."""

    def plot_data(self, channel: int | str = 0) -> tuple[Model, Measurement]:
        """The fitted model and the fitted ``m00`` on the model's absolute scale, as an
        ordinary one-channel measurement (``"m00"``)."""
        c = self[channel]
        meas = self.measurement.subset(c.index)
        meas = replace(meas, values=(c.scale * c.data)[:, None], channels=["m00"],
                       quantity=Quantity.parse(self.compared).compared_with(),
                       uncertainty=None, mueller=None, mueller_basis=None,
                       meta=dict(meas.meta))
        return c.model, meas


# --------------------------------------------------------------------------------------------
# the fit
# --------------------------------------------------------------------------------------------
def _refuse(model: Model | str, measurement: Measurement, channel: Any, joint: Any,
            shared: Any) -> None:
    """What a Mueller fit does not do, refused by argument before any work."""
    if is_auto(model):
        raise ArgumentError("model", "model='auto' compares models on BRDF data; fit Mueller "
                            "data with a named model (a facet model with an index)",
                            value=model)
    if channel is not None:
        raise ArgumentError("channel", "a Mueller fit uses every element at once; choose the "
                            "elements with measurement.select_channels(['m00', ...])",
                            value=channel)
    if joint is not False or shared is not None:
        raise ArgumentError("joint", "Mueller data are one fit of all their elements; there "
                            "are no channels to fit jointly", value=joint)
    if not hasattr(as_model(model), "mueller"):
        raise ArgumentError("model", "this model has no Mueller matrix (Model.mueller)",
                            value=model_label(as_model(model)))


def fit_mueller(model: Model | str, measurement: Measurement, *,
                options: FitOptions | None = None, **keywords: Any) -> MuellerFitResult:
    """Fit ``model`` to the Mueller elements of ``measurement`` (module notes).

    The options are those of :func:`roughbrdf.fit` (which calls this for a measurement with
    Mueller data): a :class:`~roughbrdf.fitting.problem.options.FitOptions` or its fields as
    keywords;
    ``polarimetric_weight`` is ``w_p`` (finite and >= 0; None: :data:`POLARIMETRIC_WEIGHT`).
    ``loss`` applies to ``m00``; the normalized elements always take the absolute difference.
    Samples with ``m00 <= 0`` are left out with ``negative="drop"`` and raise otherwise;
    ``channel``, ``joint``, ``shared`` and ``model="auto"`` are refused (ArgumentError).

    Returns
    -------
    MuellerFitResult
        One channel, ``"mueller"``; ``options["mueller"]`` (in ``fit.json``) says what was
        fitted.
    """
    options = FitOptions.of(options, keywords, caller="fit_mueller")
    t_start = time.perf_counter()
    _refuse(model, measurement, options.channel, options.joint, options.shared)
    model = as_model(model)
    w_p = check_polarimetric_weight(POLARIMETRIC_WEIGHT if options.polarimetric_weight is None
                                    else options.polarimetric_weight)
    plan = FitPlan.of(model, measurement, options)
    spec, search, opts = plan.spec, plan.search, plan.opts
    data = prepare_mueller(model, measurement, opts)
    check_enough_data(measurement, [data], spec.n_varys)  # type: ignore[list-item]
    label = f"fit {model_label(model)} (Mueller)"
    with progress_bar(options.progress, search.starts, label) as bar, single_thread_blas():
        tick = None if bar is None else (lambda: bar.update(1))
        t0 = time.perf_counter()
        obj, outcome = _MuellerSearch(spec, search, w_p, tick).run(data)  # type: ignore[arg-type]
        result = MuellerChannelFit.from_mueller_search(obj, outcome,  # type: ignore[arg-type]
                                                       time.perf_counter() - t0)
    mueller = {"kind": measurement.mueller, "basis": measurement.mueller_basis,
               "elements": data.element_names, "polarimetric_weight": w_p,
               "residuals": "m00: the loss; m_ij/m00: absolute difference x "
                            "polarimetric_weight"}
    return MuellerFitResult(channels=[result], **plan.result_fields(
        measurement, time.perf_counter() - t_start, joint=None, mueller=mueller))
