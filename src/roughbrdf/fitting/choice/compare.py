"""Model choice: fit several candidate models to one measurement and compare them.

:func:`compare` (``rb.compare``, ``roughbrdf compare FILE --models ...``) fits each candidate
with the same options and tabulates, per candidate: the parameters, TR75's sigma and the rms-log
(medians over the channels), AIC and BIC, the rms-log by band of ``theta_r`` and, unless
``cv=False``, a leave-one-incidence-out cross-validation score. ``roughbrdf fit FILE --model
auto`` fits :data:`AUTO_CANDIDATES` and keeps the best by prediction (``docs/fitting.md``,
"Model choice").

**Ranking** (:func:`rank`): by the cross-validation score when it was computed (the default),
by BIC otherwise (``cv=False``, or a single incidence); a candidate whose fitted model gains
energy (albedo above 1 + 1e-3 at some incidence) ranks after every one that does not. BIC is
reported beside the score, and a note says when BIC would choose another candidate.

Information criteria of a candidate over all its channels (channel ``c``: ``n_c`` samples,
``chi2_c`` the sum of its squared loss residuals; ``N = sum n_c``; ``k`` the fitted unknowns of
all channels, free data scales included; for a joint fit the joint count)::

    AIC = sum_c n_c ln(chi2_c/n_c) + 2 k        BIC = sum_c n_c ln(chi2_c/n_c) + ln(N) k

i.e. Gaussian residuals with one variance per channel. A specular lobe whose weight ends below
:data:`LOBE_OFF` (a coated candidate's :meth:`~roughbrdf.models.coated.Coated.specular_lobes`)
is switched off: its width and weight no longer shape the model, so ``k`` does not count them
and the candidate counts as the smaller model (:func:`lobes_off`).

**BIC over thousands of correlated samples exaggerates differences**: it assumes independent
residuals, but neighbouring samples of a goniometer share the model's systematic misfit, so
``N`` overstates the information and a difference of hundreds of BIC units can come from a
detail of the lobe shape. The
cross-validation score asks a different question -- how well does a model fitted without one
incidence predict that incidence -- and is the better guide when the two disagree.

Cross-validation (``cv``): for each channel and each incidence angle of the file (at least two),
the candidate is refitted without that incidence (one local fit started from the full fit's
optimum, same options) and its loss residuals on the left-out samples are collected; the score
is their r.m.s. over every fold and channel (unweighted; the left-out samples are those the
full fit used). Why leave-one-incidence-out: a user relies on the model at incidences the
instrument did not measure (a ray tracer asks for every angle), and the folds follow how a
goniometer's samples are correlated -- along one incidence's scan -- so a fold's samples are
not predicted from their neighbours (``docs/fitting.md``, "Model choice", gives the numbers).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ...errors import ArgumentError
from ...models import Model, from_spec, spec_text
from ...models.factory import split_specs
from ...quantity import Loss
from ..kinds.channels import fit_model
from ..problem.lobe_starts import LOBE_OFF
from ..problem.options import FitOptions, default_loss
from ..results.plausibility import ENERGY_TOLERANCE
from ..solvers.search import progress_bar

if TYPE_CHECKING:
    from ...measurement import Measurement
    from ..results.result import FitResult

__all__ = ["AUTO_CANDIDATES", "THETA_R_BANDS", "Candidate", "ModelComparison", "choice_notes",
           "candidate", "compare", "comparison", "cross_validate", "held_out_residuals",
           "information", "LOBE_OFF", "lobes_off", "rank", "rms", "score_metric",
           "as_candidates"]

#: the candidates of ``--model auto`` for non-retroreflective materials (paints, plastics,
#: coatings, ceramics): TR75 as published, then the coated model with one and two specular
#: lobes (GGX), and the metallic paints: rough metal flakes with pigment between them, bare
#: and under a clear coat (their reflectance and edge tint fitted, ``flakes="reflectance"``:
#: the data fix the flakes' reflectance, rarely their ``n`` and ``k`` apart). Not among them:
#: RB08 (its retro and bulk terms are for retro-reflectors, and it is slow), three lobes (3x
#: the fit time for a small gain on the shared paints) and, since 2026-12-07, the two
#: Beckmann lobes (``coated(lobes=2, distribution=beckmann)``: it won on none of the shared
#: paints, its whole-file score within 1-2 % of the GGX pair's, and it cost half of
#: ``--model auto``'s time, 6.7x one coated fit: ``docs/fitting.md``, "Model choice");
#: ask for them with ``--models``.
AUTO_CANDIDATES: tuple[str, ...] = (
    "trowbridge-reitz-1975",
    "coated",
    "coated(lobes=2)",
    "coated-conductor(coat=false, diffuse=true, flakes=reflectance)",
    "coated-conductor(diffuse=true, flakes=reflectance)",
)


#: bands of theta_r (degrees) of the residual table: [low, high)
THETA_R_BANDS: tuple[tuple[float, float], ...] = (
    (0.0, 30.0), (30.0, 60.0), (60.0, 70.0), (70.0, 80.0), (80.0, 90.01))


@dataclass
class Candidate:
    """One candidate's fit and figures (a row of the comparison table).

    Attributes
    ----------
    label : str
        The candidate's spec (:func:`roughbrdf.models.spec_text`).
    result : FitResult
    k, n_points : int
        Fitted unknowns and samples, all channels.
    aic, bic : float
        Over all channels (module notes).
    sigma, rms_log : float
        Medians over the channels.
    bands : dict
        ``"low-high"`` (deg) -> rms-log of the samples of that theta_r band, all channels
        (NaN where there are none).
    cv : float or None
        Leave-one-incidence-out score (None: not computed).
    """

    label: str
    result: FitResult = field(repr=False)
    k: int
    n_points: int
    aic: float
    bic: float
    sigma: float
    rms_log: float
    bands: dict[str, float]
    cv: float | None = None
    elapsed: float = math.nan
    #: why the candidate was fitted on part of the channels only (``--model auto`` skips a
    #: candidate far behind after the first channel: :mod:`~roughbrdf.fitting.choice.auto`); None
    #: for a whole fit
    partial: str | None = None

    def row(self) -> dict[str, Any]:
        """The table row as plain values (``fit.json``)."""
        res = self.result
        params = {c.channel: dict(c.params) for c in res.channels}
        plaus = {c.channel: res.plausibility(i).to_dict() for i, c in enumerate(res.channels)}
        return {"model": self.label, "k": self.k, "n_points": self.n_points, "aic": self.aic,
                "bic": self.bic, "sigma": self.sigma, "rms_log": self.rms_log,
                "rms_log_by_theta_r": self.bands, "cv": self.cv, "params": params,
                "limits": {c.channel: c.limits for c in res.channels},
                "plausibility": plaus, "elapsed_s": self.elapsed, "partial": self.partial}

    @property
    def max_albedo(self) -> float:
        """The largest albedo of the candidate's fitted models (all channels)."""
        res = self.result
        return max(res.plausibility(i).max_albedo for i in range(len(res.channels)))

    @property
    def worst_peak_ratio(self) -> float:
        """The model/data peak ratio farthest from 1 (as a factor), all channels."""
        res = self.result
        ratios = [r for i in range(len(res.channels)) for r in res.plausibility(i).peak_ratio
                  if math.isfinite(r) and r > 0]
        return max(ratios, key=lambda r: abs(math.log(r))) if ratios else math.nan

    @property
    def search_limits(self) -> list[str]:
        """The parameters (of any channel) that ended on a search limit."""
        return self.result.search_limits


    @property
    def gains_energy(self) -> bool:
        """Whether a fitted model of the candidate reflects more than it receives."""
        return self.max_albedo > 1 + ENERGY_TOLERANCE


@dataclass
class ModelComparison:
    """The result of :func:`compare`: the candidates, best first (:func:`rank`).

    Attributes
    ----------
    candidates : list of Candidate
        Best first by ``criterion``.
    criterion : {"cv", "bic"}
        What ranked them: the leave-one-incidence-out score, or BIC without one.
    """

    candidates: list[Candidate]
    measurement: Measurement = field(repr=False)
    notes: list[str] = field(default_factory=list)
    criterion: str = "bic"

    @property
    def best(self) -> Candidate:
        """The first candidate: the best by :attr:`criterion`."""
        return self.candidates[0]

    @property
    def best_bic(self) -> Candidate:
        """The lowest BIC (which may not be :attr:`best`) of the candidates fitted on every
        channel (one fitted on fewer samples has a lower BIC that means nothing)."""
        whole = [c for c in self.candidates if c.partial is None] or self.candidates
        return min(whole, key=lambda c: c.bic)

    @property
    def best_cv(self) -> Candidate | None:
        """The lowest cross-validation score (None without one)."""
        scored = [c for c in self.candidates if c.cv is not None and math.isfinite(c.cv)
                  and c.partial is None]
        return min(scored, key=lambda c: c.cv) if scored else None  # type: ignore[arg-type,return-value]

    def table(self) -> str:
        """The comparison as a Markdown table, with the notes below it."""
        bands = list(self.best.bands)
        head = ["model", "k", "sigma", "rms-log", "dBIC", "dAIC", "CV",
                *[f"rms-log {b}" for b in bands], "max albedo", "peak ratio", "search limit",
                "time (s)"]
        lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        b0, a0 = self.best_bic.bic, min(c.aic for c in self.candidates)
        for c in self.candidates:
            cells = [c.label + (" (first channel only)" if c.partial else ""), str(c.k),
                     f"{c.sigma:.3f}", f"{c.rms_log:.3f}",
                     f"{c.bic - b0:.0f}", f"{c.aic - a0:.0f}",
                     "-" if c.cv is None else f"{c.cv:.4f}",
                     *[_num(c.bands[b]) for b in bands],
                     _num(c.max_albedo) + (" (gains energy)" if c.max_albedo > 1 + ENERGY_TOLERANCE
                                           else ""),
                     _num(c.worst_peak_ratio), ", ".join(c.search_limits) or "-",
                     f"{c.elapsed:.1f}"]
            lines.append("| " + " | ".join(cells) + " |")
        return "\n".join(lines + [""] + [f"- {n}" for n in self.notes])

    def to_dict(self) -> dict[str, Any]:
        """``{"best", "best_cv", "best_bic", "criterion", "candidates": [row...], "notes"}``."""
        cv = self.best_cv
        return {"best": self.best.label, "best_cv": None if cv is None else cv.label,
                "best_bic": self.best_bic.label, "criterion": self.criterion,
                "candidates": [c.row() for c in self.candidates], "notes": list(self.notes)}

    def plot(self, *, fig: Any = None) -> Any:
        """rms-log by theta_r band for each candidate (lines), and BIC differences (bars)."""
        if fig is None:
            from matplotlib.figure import Figure

            fig = Figure(figsize=(10, 4), layout="constrained")
        ax1, ax2 = fig.subplots(1, 2)
        bands = list(self.best.bands)
        for c in self.candidates:
            ax1.plot(range(len(bands)), [c.bands[b] for b in bands], marker="o", label=c.label)
        ax1.set_xticks(range(len(bands)), [f"{b} deg" for b in bands], fontsize=8)
        ax1.set_xlabel("theta_r band")
        ax1.set_ylabel("rms of ln(data/model)")
        ax1.legend(fontsize=7)
        ax1.set_title(self.measurement.meta.get("sample") or "model comparison", fontsize=9)
        dbic = [c.bic - self.best_bic.bic for c in self.candidates]
        ax2.barh(range(len(dbic)), dbic)
        ax2.set_yticks(range(len(dbic)), [c.label for c in self.candidates], fontsize=7)
        ax2.invert_yaxis()
        ax2.set_xlabel("BIC - best BIC")
        return fig


def _num(v: float) -> str:
    return "-" if not math.isfinite(v) else f"{v:.3f}"


def lobes_off(result: FitResult) -> list[tuple[str, int, float, int]]:
    """``(channel, lobe number from 1, weight, unknowns)`` of each specular lobe whose fitted
    weight is below :data:`LOBE_OFF` (module notes); ``unknowns``: the fitted parameters that
    only that lobe needed (its width; its share ``w<j>``, or the share pinned at 1 that turned
    lobe 1 off; with ``weights="free"`` its ``ks<j>``). ``[]`` for models without several
    lobes. A joint fit's lobes are shared: counted once."""
    out = []
    chans = result.channels[:1] if result.options.get("joint") else result.channels
    for c in chans:
        lobes = c.model.specular_lobes() if hasattr(c.model, "specular_lobes") else []
        if len(lobes) < 2:
            continue
        free = set(c.free)
        for j, (weight, _alpha) in enumerate(lobes, start=1):
            if not weight < LOBE_OFF:
                continue
            sfx = "" if j == 1 else str(j)
            own = {"alpha" + sfx, "ks" + sfx} | ({f"w{j}"} if j > 1 else {
                nm for nm in ("w2", "w3") if (c.params.get(nm) or 0.0) >= 1 - LOBE_OFF})
            out.append((str(c.channel), j, float(weight), len(own & free)))
    return out


def information(result: FitResult) -> tuple[int, int, float, float]:
    """``(k, N, AIC, BIC)`` of a fit over all its channels (module notes; a lobe switched
    off, :func:`lobes_off`, does not count its width and weight)."""
    joint = result.options.get("joint")
    n = sum(c.n_points for c in result.channels)
    k = joint["n_varys"] if joint else sum(c.n_varys for c in result.channels)
    k -= sum(off[3] for off in lobes_off(result))
    like = sum(c.n_points * math.log(c.chi2 / c.n_points) if c.chi2 > 0 else -math.inf
               for c in result.channels)
    return k, n, like + 2 * k, like + math.log(n) * k


def band_rms_log(result: FitResult) -> dict[str, float]:
    """rms-log of the fitted samples by theta_r band (:data:`THETA_R_BANDS`), all channels."""
    tr = np.degrees(result.measurement.theta_r)
    logs, where = [], []
    for c in result.channels:
        x = c.scale * c.data
        ok = (x > 0) & (c.fitted > 0)
        logs.append(np.log(x[ok] / c.fitted[ok]))
        where.append(tr[c.index][ok])
    lr, t = np.concatenate(logs), np.concatenate(where)
    out = {}
    for lo, hi in THETA_R_BANDS:
        sel = (t >= lo) & (t < hi)
        out[f"{lo:g}-{min(hi, 90.0):g}"] = float(np.sqrt(np.mean(lr[sel] ** 2))) \
            if sel.any() else math.nan
    return out


def cross_validate(result: FitResult, options: FitOptions | Mapping[str, Any], *,
                   label: str | None = None, metric: str | None = None) -> float:
    """Leave-one-incidence-out score of a fit made with ``options`` (a
    :class:`~roughbrdf.fitting.problem.options.FitOptions` or its fields by name; module notes); NaN
    with a single incidence. The held-out residuals are the fit's loss's, or with
    ``metric="log"`` ``ln(K x) - ln f`` (one yardstick for candidates fitted with different
    losses, :func:`compare`). A progress bar (``options.progress``) names the candidate
    (``label``, default the fit's model), the fold's incidence and the channel."""
    if result.measurement.incidences().size < 2:
        return math.nan
    return rms(held_out_residuals(result, options, label=label, metric=metric))


def rms(residuals: np.ndarray) -> float:
    """The r.m.s. of the finite ``residuals`` (NaN without one): a cross-validation score."""
    r = residuals[np.isfinite(residuals)]
    return float(np.sqrt(np.mean(r * r))) if r.size else math.nan


def held_out_residuals(result: FitResult, options: FitOptions | Mapping[str, Any], *,
                       label: str | None = None, metric: str | None = None) -> np.ndarray:
    """The left-out residuals of every fold and channel of :func:`cross_validate` (whose
    score is their r.m.s., :func:`rms`); empty with a single incidence."""
    if not isinstance(options, FitOptions):
        options = FitOptions.of(None, options, caller="cross_validate")
    meas = result.measurement
    angles = meas.incidences()
    if angles.size < 2:
        return np.array([])
    joint = bool(result.options.get("joint"))
    # one local fit on all training samples from the full optimum (no exploration stage: the
    # start is already in the basin)
    held: list[np.ndarray] = []
    groups = [result.channels] if joint else [[c] for c in result.channels]
    with progress_bar(options.progress, angles.size * len(groups),
                      f"cv {label or result.model_name}", unit="fold") as bar:
        for g in angles:
            out = np.abs(meas.theta_i - g) < 1e-6
            held += _fold(result, options, meas.subset(~out), out, groups, bar,
                          f"theta_i {math.degrees(g):g} deg", metric)
    return np.concatenate(held) if held else np.array([])


def _fold(result: FitResult, options: FitOptions, train: Measurement, out: np.ndarray,
          groups: list[list[Any]], bar: Any, where: str, metric: str | None = None
          ) -> list[np.ndarray]:
    """The left-out residuals of one incidence's fold (``out``: its samples), each channel
    group refitted on ``train`` from the full fit's optimum."""
    meas = result.measurement
    loss = Loss.LOG if metric == "log" else Loss.parse(result.loss)
    joint = bool(result.options.get("joint"))
    # an array of weights, one per sample: the training samples'
    weights = _subset_weights(options.weights, meas.n_samples, ~out)
    held: list[np.ndarray] = []
    for group in groups:
        if bar is not None:
            bar.set_postfix_str(f"{where}, channel {'+'.join(str(c.channel) for c in group)}")
        fold_options = options.replace(
            channel=[c.channel for c in group], starts=1, progress=False, subsample=None,
            joint=joint, shared=result.options["joint"]["shared"] if joint else None,
            weights=weights)
        # only the fold's parameters are used (its prediction): no covariance
        fold = fit_model(group[0].model, train, fold_options, check_energy=False, refit=True,
                         statistics=False)
        for c, fc in zip(group, fold.channels, strict=True):
            idx = c.index[out[c.index]]
            if idx.size == 0:
                continue
            f = fold.predict(meas.theta_i[idx], meas.theta_r[idx], meas.phi[idx],
                             channel=c.channel,
                             polarization=None if meas.polarization is None
                             else meas.polarization[idx])
            x = fc.scale * meas.values[idx, meas.channel_index(c.channel)]
            with np.errstate(divide="ignore", invalid="ignore"):  # x <= 0: log loss
                # left-out samples of no log residual are not finite: filtered below
                held.append(loss.residual(x, np.asarray(f), floor=Loss.floor(x)))
        if bar is not None:
            bar.update(1)
    return held


def _subset_weights(weights: Any, n: int, keep: np.ndarray) -> Any:
    """The weights of the samples ``keep`` of a fold: an array with one row per sample is
    cut like the measurement; None, ``"uncertainty"`` and a broadcast scalar pass as given."""
    if weights is None or isinstance(weights, str):
        return weights
    w = np.asarray(weights)
    return w[keep] if w.ndim >= 1 and w.shape[0] == n else weights


def as_candidates(candidates: Sequence[Model | str] | str | None) -> list[Model]:
    """The candidate models (ArgumentError naming ``candidates`` for a bad one)."""
    if candidates is None:
        candidates = AUTO_CANDIDATES
    if isinstance(candidates, str):
        candidates = split_specs(candidates)
    models = []
    for c in candidates:
        if isinstance(c, Model):
            models.append(c)
        elif isinstance(c, str):
            try:
                models.append(from_spec(c))
            except ValueError as exc:
                raise ArgumentError("candidates", str(exc), value=c) from None
        else:
            raise ArgumentError("candidates", "each candidate must be a model or a model spec "
                                "such as 'coated(lobes=2)'", value=c)
    if not models:
        raise ArgumentError("candidates", "no candidate to compare", value=candidates)
    return models


def compare(measurement: Measurement, candidates: Sequence[Model | str] | str | None = None,
            *, cv: bool = True, options: FitOptions | None = None,
            **keywords: Any) -> ModelComparison:
    """Fit each candidate to ``measurement`` and compare them (module notes).

    Parameters
    ----------
    measurement : Measurement
    candidates : list of Model or str, or str, optional
        Models, or specs such as ``"coated(lobes=2, distribution=beckmann)"`` (a string:
        separated by ``;`` or by ``,`` outside parentheses). Default :data:`AUTO_CANDIDATES`.
    cv : bool
        Compute the leave-one-incidence-out score (one local refit per candidate, channel
        group and incidence).
    options : FitOptions, optional
        The options of every candidate's fit
        (:class:`~roughbrdf.fitting.problem.options.FitOptions`).
    **keywords
        Options as keywords (``loss``, ``channel``, ``joint``, ``aperture``, ``theta_r_max``,
        ...), replacing those of ``options``; given as keywords, ``progress`` is False unless
        set.

    Returns
    -------
    ModelComparison
        Candidates best first (:func:`rank`: by the cross-validation score, or BIC without
        one).

    Examples
    --------
    >>> import numpy as np, roughbrdf as rb
    >>> g = np.radians(np.mgrid[0:61:30, 0:81:10, 0:181:45].reshape(3, -1))
    >>> truth = rb.model("coated", n=1.5, rho=0.4, alpha=0.2)
    >>> meas = rb.Measurement(*g, truth.brdf(*g))
    >>> res = rb.compare(meas, ["lambertian", "coated"], starts=2)
    >>> res.best.label, round(res.best.sigma, 6)
    ('coated', 0.0)
    """
    if options is None:  # a progress bar per candidate only when asked for
        keywords = {"progress": False, **keywords}
    options = FitOptions.of(options, keywords, caller="compare")
    models = as_candidates(candidates)
    # candidates fitted with different losses (loss="auto": robust, relative for TR75 ...)
    # have scores in different units: they are scored on one yardstick, the log residual
    metric, losses = score_metric(models, options)
    rows: list[Candidate] = []
    for m in models:
        res = fit_model(m, measurement, options)
        score = cross_validate(res, options, label=spec_text(m), metric=metric) if cv else None
        rows.append(candidate(spec_text(m), res, score))
    return comparison(rows, measurement, losses)


def score_metric(models: Sequence[Model], options: FitOptions) -> tuple[str | None, set[str]]:
    """The held-out metric of :func:`compare` (``"log"`` when the candidates are fitted with
    different losses: one yardstick for all; None: each one's loss) and the losses."""
    losses = {default_loss(m, options.loss) for m in models}
    return ("log" if len(losses) > 1 else None), losses


def candidate(label: str, res: FitResult, cv: float | None, partial: str | None = None
              ) -> Candidate:
    """The table row of a fitted candidate (information criteria, medians, bands)."""
    k, n, aic, bic = information(res)
    return Candidate(label, res, k, n, aic, bic,
                     float(np.median([c.sigma for c in res.channels])),
                     float(np.median([c.rms_log for c in res.channels])), band_rms_log(res),
                     cv, res.elapsed, partial)


def comparison(rows: list[Candidate], measurement: Measurement, losses: set[str]
               ) -> ModelComparison:
    """The :class:`ModelComparison` of fitted candidates: ranked (:func:`rank`), with the
    notes that say how to read it."""
    metric = "log" if len(losses) > 1 else None
    rows, criterion = rank(rows)
    if metric == "log":
        notes_metric = ["the candidates were fitted with different losses "
                        f"({', '.join(sorted(losses))}): CV is the r.m.s. of ln(data/model) of "
                        "the left-out samples for all"]
    else:
        notes_metric = []
    notes = ["BIC and AIC assume independent residuals; neighbouring samples share the "
             "models' systematic misfit, so differences of this size overstate the evidence. "
             "CV: r.m.s. loss residual of each incidence predicted by a fit without it "
             "(lower is better)."]
    if len({c.n_points for c in rows if c.partial is None}) > 1:
        notes.append("the candidates were fitted on different numbers of samples (the "
                     "model's own domain differs): their AIC/BIC are not comparable")
    notes += choice_notes(ModelComparison(rows, measurement, criterion=criterion))
    notes.append("max albedo: the fitted model's largest directional-hemispherical reflectance "
                 "(0-85 deg; > 1 gains energy); peak ratio: model/data maximum of the "
                 "incidence where it is farthest from 1; search limit: parameters that ended "
                 "on a search bound that is no physical limit (not a result)")
    return ModelComparison(rows, measurement, notes + notes_metric, criterion)


def rank(rows: Sequence[Candidate]) -> tuple[list[Candidate], str]:
    """The candidates best first and the criterion (module notes): ``"cv"`` when every
    candidate fitted on all channels has a finite cross-validation score, else ``"bic"``
    (a candidate stopped unscored ranks after the scored ones); those that gain energy
    last, before them those with a parameter on a search limit (where the search stopped, not
    a result of the model: ``docs/fitting.md``, "Parameters at a bound"); one fitted on part of
    the channels (:attr:`Candidate.partial`) after every whole one. Ties keep the given
    order."""
    whole = [c for c in rows if c.partial is None] or list(rows)
    cv = all(_scored(c) for c in whole)
    criterion = "cv" if cv else "bic"

    def key(c: Candidate) -> tuple[bool, bool, bool, float, int]:
        # equal scores (a lobe switched off: the smaller model's fit): the fewer unknowns;
        # a candidate fitted on the first channel only (skipped) after every whole one, and
        # one stopped unscored (a search limit, auto's first stage) after the scored ones
        if cv:
            score = float(f"{c.cv:.6g}") if _scored(c) else math.inf  # type: ignore[arg-type]
        else:
            score = c.bic
        return (c.partial is not None, c.gains_energy, bool(c.result.at_search_limit), score,
                c.k)

    return sorted(rows, key=key), criterion


def _scored(c: Candidate) -> bool:
    """Whether ``c`` has a finite cross-validation score."""
    return c.cv is not None and math.isfinite(c.cv)


def choice_notes(cmp: ModelComparison) -> list[str]:
    """What the ranking chose against what BIC or the score alone would have."""
    notes = []
    best, by_bic = cmp.best, cmp.best_bic
    if cmp.criterion == "cv":
        if by_bic is not best:
            notes.append(f"ranked by cross-validation: {best.label} predicts the left-out "
                         f"incidences best; BIC prefers {by_bic.label} (they disagree)")
    else:
        by_cv = cmp.best_cv
        if by_cv is not None and by_cv is not best:
            notes.append(f"cross-validation prefers {by_cv.label} (ranked by BIC: {best.label})")
    for c in cmp.candidates:
        off = lobes_off(c.result)
        if off:
            what = ", ".join(f"lobe {j} in {ch} (weight {w:.1g})" for ch, j, w, _ in off)
            notes.append(f"{c.label}: {what} below {LOBE_OFF:g}: switched off, counted as the "
                         f"smaller model (k = {c.k})")
    for c in cmp.candidates:
        if c.partial:
            notes.append(f"{c.label}: {c.partial}")
    if any(c.gains_energy for c in cmp.candidates):
        notes.append("candidates whose fitted model gains energy rank last, whatever their "
                     "score")
    limited = [c.label for c in cmp.candidates if c.result.at_search_limit]
    if limited and len(limited) < len(cmp.candidates):
        notes.append(f"{', '.join(limited)}: a parameter on a search limit (where the search "
                     f"stopped, not a result): ranked after the candidates without one, "
                     f"whatever the score")
    return notes
