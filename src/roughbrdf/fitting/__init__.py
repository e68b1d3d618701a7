"""Fitting models to measurements: :func:`fit` and :class:`FitResult` (``docs/fitting.md``).

Data flows one way: file -> :func:`roughbrdf.read` -> :class:`~roughbrdf.measurement.Measurement`
-> :func:`fit` -> :class:`FitResult` -> report, JSON, plots. Models know nothing about fitting: the
fitter reads ``model.parameters`` (value, bounds) and rebuilds the model with
``model.with_values``. Each channel is fitted on its own; ``scipy.optimize.least_squares``
(trust-region reflective, box bounds) minimizes the sum of squared residuals, one per sample:
``(K x - f)/f`` by default, whose r.m.s. is TR75's sigma (Eq. 34).

One job per module:

=========================================  ===================================================
:mod:`~roughbrdf.fitting.setup`            the options, checked before any work; the free
                                           parameters and bounds; the data scale ``K``
:mod:`~roughbrdf.fitting.data`             one channel's samples: the compared quantity, what
                                           is left out (and counted), the weights
:mod:`~roughbrdf.fitting.objective`        the residuals (losses, closed-form ``K``) and the
                                           compiled finite-difference Jacobians
:mod:`~roughbrdf.fitting.search`           Sobol screening, multistart exploration, polish
:mod:`~roughbrdf.fitting.statistics`       covariance, stderr, correlations, chi2, AIC/BIC,
                                           sigma, rms-log
:mod:`~roughbrdf.fitting.result`           :class:`ChannelFit`, :class:`FitResult`, JSON,
                                           plots, saving
:mod:`~roughbrdf.fitting.report`           the text report
:mod:`~roughbrdf.fitting.threads`          one BLAS thread during a fit (threadpoolctl)
:mod:`roughbrdf.instrument`                the instrument aperture (cone average)
=========================================  ===================================================

Importing this package loads neither SciPy nor Matplotlib: they are imported when a fit runs
or a plot is drawn.
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from ..errors import ArgumentError
from ..instrument import APERTURE_POINTS, aperture_average, aperture_stencil
from ..quantity import LOSSES
from .compare import AUTO_CANDIDATES, ModelComparison, compare, fit_auto
from .data import ChannelData, prepare_channel
from .joint import fit_joint
from .objective import Objective, ObjectiveSpec
from .result import ChannelFit, FitResult
from .search import MultiStart, SearchOptions, progress_bar
from .setup import (
    FitPlan,
    as_model,
    channel_indices,
    check_enough_data,
    model_label,
)
from .threads import single_thread_blas

if TYPE_CHECKING:
    from ..measurement import Measurement
    from ..models import Model

__all__ = ["fit", "compare", "AUTO_CANDIDATES", "ModelComparison", "FitResult", "ChannelFit",
           "LOSSES", "APERTURE_POINTS", "aperture_stencil",
           "aperture_average", "ChannelData", "Objective", "ObjectiveSpec"]


def fit(model: Model | str, measurement: Measurement, *,
        channel: int | str | Sequence | None = None, loss: str = "relative",
        weights: Any = None, fix: Iterable[str] = (),
        bounds: Mapping[str, Sequence[float]] | None = None, starts: int = 8,
        seed: int | None = 0, nonfinite: str = "raise", negative: str = "keep",
        relative_to: str | None = None, free_scale: bool | None = None,
        scale: float | None = None,
        screen: int = 64, subsample: int | None = 1000, polish: int = 2,
        max_nfev: int | None = None, aperture: float | None = None,
        aperture_points: int = 19, theta_r_max: float | None = None,
        source_exclusion: float | None = None, extrapolated: str = "drop",
        joint: bool = False, shared: Iterable[str] | None = None,
        polarimetric_weight: float | None = None,
        progress: bool | None = None) -> FitResult:
    """Fit ``model`` to ``measurement``, each channel on its own.

    Parameters
    ----------
    model : Model or str
        Model with starting values (``rb.model(...)``; sums allowed), a registered name or
        spec (``"coated(lobes=2)"``), or ``"auto"``: fit the candidates of
        :data:`~roughbrdf.fitting.compare.AUTO_CANDIDATES` and keep the lowest BIC, with
        every candidate's figures and a leave-one-incidence-out score in ``model_choice``
        (:func:`~roughbrdf.fitting.compare.fit_auto`; ``fix`` and ``bounds`` do not apply).
    measurement : Measurement
        The data (:func:`roughbrdf.read`).
    channel : int, str, list or None
        Channel(s) to fit (labels or positions); ``None`` fits every channel.
    loss : {"relative", "log", "absolute"}
        Residual: ``(x - f)/f`` (TR75 Eq. 34), ``ln x - ln f`` or ``x - f``
        (:mod:`~roughbrdf.fitting.objective`).
    weights : None, array or "uncertainty"
        Multiplies each residual; shape (N,) or (N, C). ``"uncertainty"`` uses the measurement's
        uncertainty ``u``: ``1/u`` for the absolute loss, ``x/u`` for the relative and log losses.
        Samples of weight 0 are left out (and counted).
    fix : iterable of str
        Parameters kept at the model's value. Parameters whose value is ``None`` (parts switched
        off, e.g. TS67 ``n=None``) are never fitted.
    bounds : dict, optional
        ``name -> (low, high)``, overriding the model's default search ranges.
    starts : int
        Local fits per channel, exactly: one from the model's values, one from the previous
        channel's optimum (channels after the first, ``starts >= 2``), the rest from Sobol
        points in the bounds (``starts=1`` is a plain local fit from the model's values).
    screen : int
        Number of Sobol points in the bounds whose cost is evaluated (one model evaluation
        each) to choose the ``starts - 1`` starting points: the lowest-cost ones, kept at least
        0.15 of the bounds apart.
    seed : int or None
        Seed of the scrambled Sobol sequence and of the subsample (results are reproducible).
    nonfinite : {"raise", "drop"}
        What to do with NaN/inf measured values.
    negative : {"keep", "drop", "clip"}
        What to do with negative measured values (non-positive ones for ``loss="log"``, where
        ``keep`` raises). ``clip`` sets them to 0 (to the smallest positive value for the log
        loss). Counts are reported in ``excluded``.
    relative_to : {"brdf", "bridf"}, optional
        For ``relative`` data: the model quantity the values are proportional to. Default
        ``measurement.meta["relative_to"]`` if the reader found it, else ``"brdf"``.
    free_scale : bool, optional
        Fit a free scale ``K`` of the data in closed form. Default: only for ``relative`` data.
        A model with an overall scale parameter of its own (TS67 ``rho_d``, microfacet ``ks``
        alone) cannot tell it from ``K``: fix that parameter when fitting relative data.
    scale : float, optional
        A known data scale ``K`` (``x -> K x``) instead of a fitted one, e.g. for relative data
        whose absolute calibration is known; the fit is then the absolute fit.
    subsample : int or None
        Above this many samples, the starts are explored on a fixed random subsample and the
        ``polish`` best end points refined on all samples. ``None`` uses all samples throughout.
    polish : int
        Number of explored end points refined on the full data.
    max_nfev : int, optional
        Limit of function evaluations per local fit (``least_squares``).
    aperture : float or None
        Instrument angular response: half-angle (radians) of a uniform cone about the measured
        reflection direction. Each sample is compared with the model averaged over that cone
        (:mod:`roughbrdf.instrument`); ``None`` or 0: the model at the sample's direction. Must
        satisfy ``0 <= aperture < pi/2``.
    aperture_points : {7, 19, 37}
        Size of the cubature rule over the cone (:func:`~roughbrdf.instrument.aperture_stencil`);
        the fit costs about that many times more model evaluations.
    theta_r_max : float or None
        Fit domain: leave out the samples with ``theta_r > theta_r_max`` (radians,
        ``0 <= theta_r_max <= pi/2``; counted in ``excluded``). None: no limit.
    source_exclusion : float or None
        Fit domain: leave out the samples whose reflection direction is less than this angle
        (radians, ``0 <= source_exclusion <= pi``) from the direction toward the source (the
        retro direction ``theta_r = theta_i, phi = pi``), e.g. where the source blocks the
        detector; counted in ``excluded``. None: no exclusion.
    extrapolated : {"drop", "keep"}
        Samples the file holds but the instrument did not measure (``meta["extrapolated_beyond"]``
        set by :func:`roughbrdf.read`, :mod:`roughbrdf.extrapolation`; e.g. the Mini-Diff's
        linear ramp to 0 beyond ``theta_r = 75`` deg): left out (counted in ``excluded``) or
        fitted too.
    joint : bool
        Fit all channels at once (:mod:`~roughbrdf.fitting.joint`): the ``shared`` parameters
        take one value for every channel, the others one per channel. Exactly ``starts``
        local fits in all (not per channel).
    shared : iterable of str, optional
        With ``joint=True``: the free parameters common to all channels. Default: every free
        parameter that is not a reflectance (roughness, index, lobe scales).
    polarimetric_weight : float, optional
        Mueller data only (``measurement.mueller`` set, :mod:`~roughbrdf.fitting.polarimetric`):
        the weight of the absolute residuals of the normalized elements ``m_ij/m00`` against
        the ``loss`` residuals of ``m00`` (default 1).
    progress : bool or None
        Show a tqdm progress bar; ``None`` shows it only on an interactive terminal.

    Returns
    -------
    FitResult
        For Mueller data a :class:`~roughbrdf.fitting.polarimetric.MuellerFitResult`: every
        element is fitted at once (one channel, ``"mueller"``; ``docs/fitting.md``,
        "Polarimetric data").

    Raises
    ------
    ValueError
        Unknown loss or option, every parameter fixed, no data left in a channel, non-finite
        values with ``nonfinite="raise"``, non-positive values for the log loss with
        ``negative="keep"``, an aperture that is negative, not finite or >= pi/2, a
        ``theta_r_max`` or ``source_exclusion`` outside [0, pi/2] or [0, pi], bounds that
        do not contain the starting value or leave a parameter's physical domain. Errors
        about an argument are :class:`~roughbrdf.errors.ArgumentError` (naming the argument,
        the value and, where there is one, the fix; ``err.render(options)`` words them for
        the command line).
    """
    t_start = time.perf_counter()
    if getattr(measurement, "mueller", None) is not None:  # Mueller elements: all at once
        from .polarimetric import POLARIMETRIC_WEIGHT, fit_mueller

        return fit_mueller(
            model, measurement, loss=loss, weights=weights, fix=fix, bounds=bounds,
            polarimetric_weight=POLARIMETRIC_WEIGHT if polarimetric_weight is None
            else polarimetric_weight, starts=starts, seed=seed, nonfinite=nonfinite,
            negative=negative, relative_to=relative_to, free_scale=free_scale, scale=scale,
            screen=screen, subsample=subsample, polish=polish, max_nfev=max_nfev,
            aperture=aperture, aperture_points=aperture_points, theta_r_max=theta_r_max,
            source_exclusion=source_exclusion, extrapolated=extrapolated, channel=channel,
            joint=joint, shared=shared, progress=progress)
    if polarimetric_weight is not None:
        raise ArgumentError("polarimetric_weight", "only Mueller data (measurement.mueller "
                            "set) have normalized elements to weigh", value=polarimetric_weight)
    if isinstance(model, str) and model.strip().lower() == "auto":
        return fit_auto(measurement, channel=channel, loss=loss, weights=weights, fix=fix,
                        bounds=bounds, starts=starts, seed=seed, nonfinite=nonfinite,
                        negative=negative, relative_to=relative_to, free_scale=free_scale,
                        scale=scale, screen=screen, subsample=subsample, polish=polish,
                        max_nfev=max_nfev, aperture=aperture, aperture_points=aperture_points,
                        theta_r_max=theta_r_max, source_exclusion=source_exclusion,
                        extrapolated=extrapolated, joint=joint, shared=shared,
                        progress=progress)
    model = as_model(model)
    chans = channel_indices(measurement, channel)
    plan = FitPlan.of(model, measurement, loss=loss, weights=weights, fix=fix, bounds=bounds,
                      starts=starts, seed=seed, nonfinite=nonfinite, negative=negative,
                      relative_to=relative_to, free_scale=free_scale, scale=scale,
                      screen=screen, subsample=subsample, polish=polish, max_nfev=max_nfev,
                      aperture=aperture, aperture_points=aperture_points,
                      theta_r_max=theta_r_max, source_exclusion=source_exclusion,
                      extrapolated=extrapolated)
    spec, search = plan.spec, plan.search
    # every channel first, so that bad input fails before any work
    data = [prepare_channel(model, measurement, j, plan.opts) for j in chans]
    check_enough_data(measurement, data, spec.n_varys)
    if not isinstance(joint, bool):
        raise ArgumentError("joint", "must be True or False", value=joint)
    if shared is not None and not joint:
        named = shared if isinstance(shared, str) else ", ".join(map(str, shared))
        raise ArgumentError("shared", "only a joint fit shares parameters: ask for one with "
                            "joint=True (command line: --joint)", value=named)
    runs = search.starts * (1 if joint else len(chans))
    with progress_bar(progress, runs, f"fit {model_label(model)}") as bar, \
            single_thread_blas():
        tick = None if bar is None else (lambda: bar.update(1))
        if joint:
            results, summary = fit_joint(spec, data, search, shared, tick)
        else:
            results, summary = _separately(spec, search, data, bar, tick), None
    return FitResult(channels=results, **plan.result_fields(
        measurement, time.perf_counter() - t_start, joint=summary))


def _separately(spec: ObjectiveSpec, search: SearchOptions, data: list[ChannelData],
                bar: Any, tick: Any) -> list[ChannelFit]:
    """Each channel on its own, in order (the previous optimum is a warm start)."""
    results: list[ChannelFit] = []
    runner = MultiStart(spec, search, tick)
    for d in data:
        t0 = time.perf_counter()
        if bar is not None:
            bar.set_postfix_str(d.label)
        obj, outcome = runner.run(d)
        results.append(ChannelFit.from_search(obj, outcome, time.perf_counter() - t0))
    return results
