"""The plan of one fit: what :func:`roughbrdf.fit` does with its model, measurement and
:class:`~roughbrdf.fitting.problem.options.FitOptions`, checked before any work
(``docs/fitting.md``).

:class:`FitPlan` holds the data options, the search, the free parameters and their bounds
(:class:`FreeParameters`), the objective and the data scale ``K`` (free for relative data,
fixed otherwise: :func:`data_scale`); :func:`channel_indices` and :func:`check_enough_data`
check the channels. The options' own checks ran when they were made; the checks that need the
model or the measurement raise here, an :class:`~roughbrdf.errors.ArgumentError` (a
``ValueError`` naming the argument, worded for Python by ``str`` and for the CLI by
``render``), before any fit runs.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ...errors import ArgumentError
from ...instrument import Aperture
from ...measurement import Measurement
from ...models import Model, Parameter
from ...models.factory import as_model, model_label
from ...quantity import Quantity
from .data import ChannelData, Comparison, DataOptions, input_source, negative_rule, where
from .objective import ObjectiveSpec
from .options import check_scale, default_loss
from .search_options import SearchOptions

if TYPE_CHECKING:
    from .options import FitOptions

__all__ = ["BoundsFix", "FitPlan", "FreeParameters", "as_model", "channel_indices",
           "check_enough_data", "data_scale", "model_label"]


@dataclass(frozen=True)
class FreeParameters:
    """The fitted parameters: names, bounds and starting values (the model's values).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> p = FreeParameters.of(rb.model("ts67", n=None, k=None), fix=["c"],
    ...                       bounds={"g": (0.1, 10.0)})
    >>> p.names, p.lower.tolist(), p.upper.tolist()
    (('g', 'rho_d'), [0.1, 0.0], [10.0, 1.0])
    """

    names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    start: np.ndarray

    @classmethod
    def of(cls, model: Model, fix: Iterable[str] | str = (),
           bounds: Mapping[str, Sequence[float]] | None = None) -> FreeParameters:
        """Every parameter of ``model`` that is not in ``fix`` nor switched off (value None),
        with ``bounds`` overriding the model's own."""
        names = model.param_names
        try:
            fixed = [fix] if isinstance(fix, str) else [str(f) for f in fix]
        except TypeError:
            raise ArgumentError("fix", f"fix must be a parameter name or a list of them, got "
                                f"{fix!r}") from None
        if bounds is not None and not isinstance(bounds, Mapping):
            raise ArgumentError("bounds", f"bounds must be a mapping name -> (low, high), got "
                                f"{bounds!r}")
        bounds = dict(bounds or {})
        for arg, nm in [*(("fix", f) for f in fixed), *(("bounds", b) for b in bounds)]:
            if nm not in names:
                try:  # the registry's "unknown parameter" error, with its suggestions
                    model.with_values([nm], [0.0])
                except ValueError as exc:
                    raise ArgumentError(arg, f"{arg}: {exc}") from None
        specs = {p.name: p for p in model.parameters}
        free = [n for n in names if n not in fixed and specs[n].value is not None]
        if not free:
            off = [n for n in names if specs[n].value is None]
            extra = f" ({', '.join(off)} switched off by None)" if off else ""
            raise ValueError(f"every parameter of {model_label(model)} is fixed{extra}: nothing "
                             f"to fit; free at least one of {names}")
        lo, hi, x0 = (np.empty(len(free)) for _ in range(3))
        for j, nm in enumerate(free):
            lo[j], hi[j] = _bounds_of(specs[nm], bounds.get(nm, specs[nm].bounds))
            x0[j] = float(specs[nm].value)  # type: ignore[arg-type]  # not None: free
            if not lo[j] <= x0[j] <= hi[j]:
                raise ArgumentError(
                    "bounds", f"starting value {nm} = {x0[j]:g} is outside its bounds "
                    f"[{lo[j]:g}, {hi[j]:g}] (give another starting value, or bounds that "
                    f"contain it)", fix=BoundsFix(nm))
        return cls(tuple(free), lo, hi, x0)

    def spec(self, model: Model, *, loss: str, quantity: Quantity | str, free_scale: bool,
             fixed_scale: float) -> ObjectiveSpec:
        """The :class:`~roughbrdf.fitting.problem.objective.ObjectiveSpec` of these parameters."""
        return ObjectiveSpec(model, self.names, self.lower, self.upper, loss=loss,
                             quantity=quantity, free_scale=free_scale, fixed_scale=fixed_scale)


class BoundsFix:
    """The ``fix`` of an :class:`~roughbrdf.errors.ArgumentError` about ``bounds``: shown as
    ``bounds={'e': (low, high)}`` in Python (``repr``) and ``--bounds e=LOW:HIGH`` on the
    command line (``str``).

    Examples
    --------
    >>> from roughbrdf.errors import ArgumentError
    >>> err = ArgumentError("bounds", "e = 5 is outside [0.02, 3]", fix=BoundsFix("e"))
    >>> str(err)
    "e = 5 is outside [0.02, 3]; pass bounds={'e': (low, high)}"
    >>> err.render({"bounds": "--bounds"})
    'e = 5 is outside [0.02, 3]; pass --bounds e=LOW:HIGH'
    """

    def __init__(self, name: str) -> None:
        self.name = name

    def __repr__(self) -> str:
        return f"{{{self.name!r}: (low, high)}}"

    def __str__(self) -> str:
        return f"{self.name}=LOW:HIGH"


def _bounds_of(spec: Parameter, b: Any) -> tuple[float, float]:
    """``(low, high)`` of one free parameter: two numbers, ``low < high``, inside the
    parameter's physical domain (a fit must not try values the model refuses)."""
    nm = spec.name
    try:
        lo, hi = (float(v) for v in b)
    except (TypeError, ValueError, OverflowError):
        raise ArgumentError("bounds", f"bounds of {nm!r} must be two numbers (low, high), got "
                            f"{b!r}") from None
    if not lo < hi:
        raise ArgumentError("bounds", f"bounds of {nm!r} must satisfy low < high, got "
                            f"{tuple(b)}")
    dlo, lo_inc, dhi, hi_inc = spec.domain
    inside = ((lo >= dlo if lo_inc else lo > dlo) and (hi <= dhi if hi_inc else hi < dhi))
    if not inside:
        raise ArgumentError("bounds", f"bounds of {nm!r} [{lo:g}, {hi:g}] leave its physical "
                            f"domain {spec.domain_text()}" + (
                                f" ({spec.description})" if spec.description else ""))
    return lo, hi


#: ``model name -> parameter`` that only scales the whole model (no other term beside it):
#: with a free data scale ``K`` the two are one degree of freedom
SCALE_PARAMETERS = {"microfacet": "ks"}


def hold_scale_parameter(model: Model, fix: Any, bounds: Any, free_scale: bool
                         ) -> tuple[Model, Any]:
    """With a free data scale ``K`` (relative data), a model's pure scale parameter
    (:data:`SCALE_PARAMETERS`: a lone microfacet lobe's ``ks``) is held at 1 -- ``K`` carries
    the scale, and the two would be one degree of freedom (a singular covariance, ``ks`` on a
    bound). Not when the user fixes it or gives it bounds, nor in a sum (there ``ks`` weighs
    the lobe against the other terms). Returns the model and the ``fix`` list."""
    name = SCALE_PARAMETERS.get(model.name)
    try:
        given = [fix] if isinstance(fix, str) else list(fix or ())
    except TypeError:  # not a list of names: FreeParameters.of names the error
        return model, fix
    if not free_scale or name is None or name in given or name in (bounds or {}):
        return model, fix
    return model.with_params(**{name: 1.0}), [*given, name]


def data_scale(meas: Measurement, free_scale: bool | None, scale: float | None
               ) -> tuple[bool, float]:
    """``(free_scale, fixed_scale)``: a known ``scale`` is fixed; otherwise ``K`` is free for
    relative data unless ``free_scale`` says otherwise."""
    fixed = check_scale(scale, free_scale)
    if fixed is not None:
        return False, fixed
    if free_scale is None:
        free_scale = meas.quantity == "relative"
    return bool(free_scale), 1.0


def channel_indices(meas: Measurement, channel: Any) -> list[int]:
    """Positions of the channels to fit: all (None), one, or a list of labels/positions."""
    if not isinstance(meas, Measurement):
        raise TypeError(f"measurement must be a roughbrdf Measurement, got {type(meas)}")
    if channel is None:
        chans = list(range(len(meas.channels)))
    elif isinstance(channel, list | tuple):
        chans = [meas.channel_index(c) for c in channel]
    else:
        chans = [meas.channel_index(channel)]
    if not chans:
        raise ValueError("no channel to fit")
    return chans


def check_enough_data(meas: Measurement, data: Sequence[ChannelData], n_varys: int) -> None:
    """Raise unless every channel has more samples than fitted parameters."""
    for d in data:
        if d.n <= n_varys:
            raise ValueError(f"{where(meas, d.label)}: {d.n} samples for {n_varys} fitted "
                             f"parameters; need more data than parameters")


@dataclass(frozen=True)
class FitPlan:
    """What one call of :func:`roughbrdf.fit` (or its Mueller form) does, checked before any
    work: the data options, the search, the free parameters and their
    :class:`~roughbrdf.fitting.problem.objective.ObjectiveSpec`, and the ``options`` of
    ``fit.json``."""

    model: Model
    opts: DataOptions
    search: SearchOptions
    params: FreeParameters
    spec: ObjectiveSpec
    recorded: dict[str, Any]

    @classmethod
    def of(cls, model: Model, measurement: Measurement, options: FitOptions) -> FitPlan:
        """Check what needs the model or the measurement (ArgumentError naming the option)
        and build the plan."""
        o = options
        ap = Aperture.parse(o.aperture, o.aperture_points)
        loss = default_loss(model, o.loss)
        negative = negative_rule(o.negative, loss)
        opts = DataOptions(Comparison.of(measurement, o.relative_to), loss, o.weights,
                           o.nonfinite, negative, ap, o.theta_r_max, o.source_exclusion,
                           o.extrapolated)
        search = o.search()
        k_free, k_fixed = data_scale(measurement, o.free_scale, o.scale)
        model, fix = hold_scale_parameter(model, o.fix, o.bounds, k_free)
        params = FreeParameters.of(model, fix, o.bounds)
        spec = params.spec(model, loss=loss, quantity=opts.comparison.quantity,
                           free_scale=k_free, fixed_scale=k_fixed)
        recorded = {
            "starts": search.starts, "seed": o.seed, "subsample": o.subsample,
            "polish": search.polish, "nonfinite": o.nonfinite, "negative": negative,
            "free_scale": k_free, "scale": o.scale,
            "aperture": None if ap is None else ap.half_angle,
            "aperture_points": None if ap is None else ap.points,
            "theta_r_max": opts.theta_r_max, "source_exclusion": opts.source_exclusion,
            "extrapolated": o.extrapolated,
            "fix": sorted(set(model.param_names) - set(params.names)),
            "weights": None if o.weights is None else
            (o.weights if isinstance(o.weights, str) else "array")}
        return cls(model, opts, search, params, spec, recorded)

    def result_fields(self, measurement: Measurement, elapsed: float,
                      **options: Any) -> dict[str, Any]:
        """The fields of a :class:`~roughbrdf.fitting.results.result.FitResult` of this plan besides
        its channels; ``options`` adds to (or sets) the recorded ``options``."""
        ap = self.opts.aperture
        return {"measurement": measurement, "model_name": model_label(self.model),
                "loss": self.spec.loss, "compared": self.opts.comparison.compared,
                "relative_to": self.opts.comparison.relative_to,
                "options": {**self.recorded, **options}, "elapsed": elapsed,
                "aperture": None if ap is None else ap.half_angle,
                "aperture_points": 19 if ap is None else ap.points,
                "source": input_source(measurement)}
