"""The fit of one named model: Mueller data to :mod:`~roughbrdf.fitting.kinds.polarimetric`, every
other measurement channel by channel (or jointly, :mod:`~roughbrdf.fitting.kinds.joint`).

What :func:`roughbrdf.fit` runs for a model that is not ``"auto"``, and what model choice
(:mod:`~roughbrdf.fitting.choice.compare`) runs for each candidate: :func:`fit_model`. Each channel
is
fitted on its own by default; ``scipy.optimize.least_squares`` (trust-region reflective, box
bounds) minimizes the sum of squared residuals, one per sample: by default the soft-L1
transform of ``ln(K x) - ln f`` (the ``robust`` loss; TR75's sigma, Eq. 34, is reported
whatever the loss). With ``options.energy_constraint`` (the default), a
channel whose fitted model reflects more than it receives on the grid 0, 5, ... 85, 89 deg is
refitted from that optimum under ``albedo <= 1`` (:mod:`~roughbrdf.fitting.energy`); joint fits
and Mueller fits are checked and warned about, not constrained (``docs/fitting.md``, "Energy
constraint").
"""

from __future__ import annotations

import dataclasses
import time
from typing import TYPE_CHECKING, Any

import numpy as np

from ...errors import ArgumentError
from ...models.factory import as_model, spec_text
from ..energy import EnergyConstraint, conditional_covariance, constrain_channel, refit_constrained
from ..problem.data import ChannelData, prepare_channel
from ..problem.objective import ObjectiveSpec
from ..problem.plan import FitPlan, channel_indices, check_enough_data
from ..problem.wavelengths import channel_wavelength, needs_wavelength, with_wavelength
from ..results.plausibility import EXPORT_INCIDENCES_DEG, warn_energy
from ..results.result import ChannelFit, FitResult
from ..solvers.search import MultiStart, SearchOptions, progress_bar
from ..solvers.threads import single_thread_blas
from .joint import fit_joint
from .polarimetric import fit_mueller

if TYPE_CHECKING:
    from ...measurement import Measurement
    from ...models import Model
    from ..problem.options import FitOptions

__all__ = ["fit_model", "fit_channels", "is_mueller", "refuse_polarimetric_weight"]


def is_mueller(measurement: Any) -> bool:
    """Whether ``measurement`` holds Mueller elements (fitted all at once)."""
    return getattr(measurement, "mueller", None) is not None


def refuse_polarimetric_weight(options: FitOptions) -> None:
    """``polarimetric_weight`` weighs normalized Mueller elements: refused for other data."""
    if options.polarimetric_weight is not None:
        raise ArgumentError("polarimetric_weight", "only Mueller data (measurement.mueller "
                            "set) have normalized elements to weigh",
                            value=options.polarimetric_weight)


def fit_model(model: Model | str, measurement: Measurement, options: FitOptions, *,
              check_energy: bool = True, refit: bool = False,
              done: list[ChannelFit] | None = None, statistics: bool = True) -> FitResult:
    """Fit one model (an instance, a name or a spec; not ``"auto"``) with ``options``:
    Mueller data with :func:`~roughbrdf.fitting.kinds.polarimetric.fit_mueller`, others with
    :func:`fit_channels`. With ``check_energy``, an
    :class:`~roughbrdf.fitting.results.plausibility.EnergyWarning` for each channel whose fitted
    model
    reflects more than it receives (the refits of a cross-validation skip the check). With
    ``refit`` (a cross-validation fold: ``model`` holds a fit's optimum), a channel fitted
    under the energy constraint is refitted from that optimum under the constraint directly
    (:func:`~roughbrdf.fitting.energy.refit_constrained`). ``done``: the fits of the first
    channels, made before by this same call with those channels alone
    (:mod:`~roughbrdf.fitting.choice.auto`'s first stage): kept as they are, and the search goes on
    from them as it would have (:func:`fit_channels`); the result is the whole fit's.
    ``statistics=False`` (a cross-validation fold: only its parameters are used): the channels
    carry no covariance (:meth:`~roughbrdf.fitting.results.result.ChannelFit.fields_at_optimum`;
    data that are not Mueller elements)."""
    res: FitResult
    if is_mueller(measurement):  # Mueller elements: all at once
        res = fit_mueller(model, measurement, options=options)
    else:
        refuse_polarimetric_weight(options)
        m = as_model(model)
        res = (_by_wavelength(m, measurement, options, done) if needs_wavelength(m)
               else fit_channels(m, measurement, options, refit=refit, done=done,
                                 statistics=statistics))
    if check_energy:
        warn_energy(res, stacklevel=4)
    return res


def _by_wavelength(model: Model, measurement: Measurement, options: FitOptions,
                   done: list[ChannelFit] | None = None) -> FitResult:
    """A model that needs the wavelength (:mod:`~roughbrdf.fitting.problem.wavelengths`): each
    channel
    fitted with the model at that channel's wavelength, the results in one (those ``done``
    kept: each channel is fitted on its own)."""
    if options.joint:
        raise ArgumentError("joint", "the model depends on the wavelength, which differs from "
                            "channel to channel: fit the channels separately", value=True)
    kept = list(done or [])
    results = [fit_channels(with_wavelength(model, channel_wavelength(
        measurement, j, options.wavelength)), measurement, options.replace(channel=[j]))
        for j in channel_indices(measurement, options.channel)[len(kept):]]
    return dataclasses.replace(results[0], channels=kept + [c for r in results
                                                            for c in r.channels],
                               elapsed=sum(r.elapsed for r in results))


def fit_channels(model: Model, measurement: Measurement, options: FitOptions, *,
                 refit: bool = False, done: list[ChannelFit] | None = None,
                 statistics: bool = True) -> FitResult:
    """Fit ``model`` to the channels of ``measurement`` (not Mueller data), each on its own
    or, with ``options.joint``, all at once; ``refit``, ``done`` and ``statistics`` as
    :func:`fit_model`'s (``done`` and ``statistics`` are for channels fitted on their own)."""
    t_start = time.perf_counter()
    chans = channel_indices(measurement, options.channel)
    plan = FitPlan.of(model, measurement, options)
    spec, search = plan.spec, plan.search
    # every channel first, so that bad input fails before any work
    data = [prepare_channel(model, measurement, j, plan.opts) for j in chans]
    check_enough_data(measurement, data, spec.n_varys)
    joint = options.joint
    runs = search.starts * (1 if joint else len(chans))
    # the spec, options included: three coated candidates of --model auto read apart
    with progress_bar(options.progress, runs, f"fit {spec_text(model)}") as bar, \
            single_thread_blas():
        tick = None if bar is None else (lambda: bar.update(1))
        if joint:
            results, summary = fit_joint(spec, data, search, options.shared, tick)
        else:
            results, summary = _separately(spec, search, data, bar, tick,
                                           options.energy_constraint, refit, done,
                                           statistics), None
    return FitResult(channels=results, **plan.result_fields(
        measurement, time.perf_counter() - t_start, joint=summary,
        energy_constraint=options.energy_constraint and not joint))


def _separately(spec: ObjectiveSpec, search: SearchOptions, data: list[ChannelData],
                bar: Any, tick: Any, energy: bool = True, refit: bool = False,
                done: list[ChannelFit] | None = None, statistics: bool = True
                ) -> list[ChannelFit]:
    """Each channel on its own, in order (the previous optimum is a warm start); with
    ``energy``, a channel whose model gains energy refitted under the constraint; with
    ``refit``, a model that cannot guarantee energy refitted from its values under the
    constraint directly (:func:`~roughbrdf.fitting.energy.refit_constrained`). The fits
    ``done`` of the first channels are kept, and the search state they left is restored: the
    subsample draws they made, their optimum as the next warm start. ``statistics=False``:
    no covariance (:func:`fit_model`)."""
    results: list[ChannelFit] = list(done or [])
    runner = MultiStart(spec, search, tick)
    for d, fit in zip(data, results, strict=False):
        runner.objectives(d)  # the same random subsample draw as when it was fitted
        runner.warm = np.array([fit.params[nm] for nm in spec.free], dtype=float)
        if tick is not None:
            for _ in range(search.starts):
                tick()
    for d in data[len(results):]:
        t0 = time.perf_counter()
        if bar is not None:
            bar.set_postfix_str(d.label)
        direct = None
        if refit and energy and not spec.model.conserves_energy and d.n:
            direct = refit_constrained(spec, d, runner.start, search.max_nfev)
        if direct is not None:
            full = runner.objectives(d)[0]
            fit = ChannelFit.from_search(full, direct[0], time.perf_counter() - t0,
                                         statistics=statistics)
            results.append(_constrained(fit, full, direct[1], statistics))
            continue
        obj, outcome = runner.run(d)
        info = None
        if energy:
            outcome, info = constrain_channel(spec, d, outcome, search.max_nfev)
            runner.warm = outcome.theta.copy()  # the next channel starts from the result
        fit = ChannelFit.from_search(obj, outcome, time.perf_counter() - t0,
                                     statistics=statistics)
        results.append(fit if info is None else _constrained(fit, obj, info, statistics))
    return results


def _constrained(fit: ChannelFit, obj: Any, info: EnergyConstraint,
                 statistics: bool = True) -> ChannelFit:
    """``fit`` at a constrained optimum: its covariance conditional on the active
    constraints (with ``statistics``), the message saying so, and ``info`` kept
    (``fit.json``)."""
    active = [EXPORT_INCIDENCES_DEG.index(t) for t in info.theta_deg]
    out = conditional_covariance(fit, obj, active) if info.satisfied and statistics else fit
    out.message += info.note()
    out.energy_constraint = info
    return out
