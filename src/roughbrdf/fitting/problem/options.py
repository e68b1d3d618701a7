"""The options of a fit: one typed, frozen :class:`FitOptions`, checked once on construction.

:func:`roughbrdf.fit` takes them as keywords (``rb.fit(model, meas, loss="log")``: the
keywords build a :class:`FitOptions`) or typed (``rb.fit(model, meas, options=opts)``);
:func:`~roughbrdf.fitting.choice.compare.compare`, :func:`~roughbrdf.fitting.choice.auto.fit_auto`,
:func:`~roughbrdf.fitting.kinds.polarimetric.fit_mueller`,
:class:`~roughbrdf.fitting.problem.plan.FitPlan`,
:func:`roughbrdf.catalogue.fit_catalogue` and the command line pass one along. Every check that
needs no measurement nor model runs when the options are made (an
:class:`~roughbrdf.errors.ArgumentError` naming the option); those that need them (``fix`` and
``bounds`` against the model's parameters, ``weights`` against the samples, ``relative_to``
against the data, ``channel`` against its labels) run in
:meth:`FitPlan.of <roughbrdf.fitting.problem.plan.FitPlan.of>`, before any fit.

Examples
--------
>>> opts = FitOptions(loss="log", starts=2)
>>> opts.replace(starts=4).starts, opts.changed()
(4, {'loss': 'log', 'starts': 2})
>>> FitOptions(negative="nope")
Traceback (most recent call last):
...
roughbrdf.errors.ArgumentError: negative = 'nope': must be 'auto', 'keep', 'drop' or 'clip'
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from ...errors import ArgumentError
from ...instrument import Aperture
from ...models.kcorr import parse_wavelength
from ...quantity import LOSSES, Loss
from .data import check_fit_domain, check_sample_options
from .search_options import SearchOptions

__all__ = ["AUTO_LOSS", "FitOptions", "MODEL_LOSSES", "check_loss", "check_polarimetric_weight",
           "check_scale", "default_loss"]


#: the loss of ``loss="auto"`` by model name where the comparison measured another than
#: :data:`AUTO_LOSS` (``docs/fitting.md``, "Choosing the loss"): the models that cannot follow
#: the shared paints' peaks, for which the robust loss gives the peak up where ``relative``
#: keeps it -- TR75 (held-out peak ratio 0.07 against 3.2, held-out r.m.s. ln 0.61 against
#: 0.50; C2_Black's ``e`` on its search limit), microfacet (held-out peak ratio 0.36, down to
#: 0.001 on the glossy black, against 0.63), TS67 (C2_Black 465 nm: TR75's sigma 15 against
#: 0.4, the peak dropped; ``tests/fitting/test_fitting_real.py``); a sum with one of them as well
MODEL_LOSSES: dict[str, str] = {"trowbridge-reitz-1975": "relative",
                                "torrance-sparrow-1967": "relative", "microfacet": "relative"}
#: the loss of ``loss="auto"`` for every other model (and sums)
AUTO_LOSS = "robust"


def check_loss(loss: Any) -> None:
    """``loss`` is ``"auto"`` or a loss name (:class:`~roughbrdf.quantity.Loss`); an
    :class:`~roughbrdf.errors.ArgumentError` naming ``loss`` otherwise."""
    if loss == "auto":
        return
    try:
        Loss.parse(loss)
    except ArgumentError:
        raise ArgumentError("loss", f"unknown loss {loss!r}; choose one of auto, "
                            f"{', '.join(LOSSES)}") from None


def default_loss(model: Any, loss: str) -> str:
    """The loss a fit of ``model`` uses: ``loss`` itself unless ``"auto"``, then the model's
    entry of :data:`MODEL_LOSSES` (by name; a sum: its first component's that has one), else
    :data:`AUTO_LOSS`.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> default_loss(rb.model("coated"), "auto"), default_loss(rb.model("tr75"), "auto")
    ('robust', 'relative')
    >>> default_loss(rb.model("tr75"), "log")
    'log'
    """
    if loss != "auto":
        return loss
    parts = getattr(model, "components", None) or [model]
    own = [MODEL_LOSSES[p.name] for p in parts if p.name in MODEL_LOSSES]
    return own[0] if own else AUTO_LOSS


@dataclass(frozen=True)
class FitOptions:
    """Every option of :func:`roughbrdf.fit` but the model and the measurement.

    Parameters
    ----------
    channel : int, str, list or None
        Channel(s) to fit (labels or positions); ``None`` fits every channel.
    loss : {"auto", "robust", "relative", "log", "absolute"}
        Residual: ``robust`` (soft-L1 of ``ln x - ln f``, scale 0.1), ``(x - f)/f`` (TR75
        Eq. 34, the papers' loss), ``ln x - ln f`` or ``x - f``
        (:class:`roughbrdf.quantity.Loss`, :mod:`~roughbrdf.fitting.problem.objective`). ``auto``
        (default): the loss measured best for the model (:func:`default_loss`: ``robust``;
        ``relative`` for TR75, TS67, microfacet and sums with them; ``docs/fitting.md``,
        "Choosing the loss"); ``fit.json`` records the loss used.
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
    seed : int or None
        Seed of the scrambled Sobol sequence and of the subsample (results are reproducible).
    nonfinite : {"raise", "drop"}
        What to do with NaN/inf measured values.
    negative : {"auto", "keep", "drop", "clip"}
        What to do with negative measured values (non-positive ones for the ``log`` and
        ``robust`` losses, where ``keep`` raises). ``clip`` sets them to 0 (to the smallest
        positive value for those losses). ``auto`` (default): ``drop`` for the ``log`` and
        ``robust`` losses (a logarithm needs a positive value: the noise floor's zeros and
        negatives carry no ratio), ``keep`` for the others. Counts are reported in
        ``excluded``; ``fit.json`` records the rule applied.
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
    screen : int
        Number of Sobol points in the bounds whose cost is evaluated (one model evaluation
        each) to choose the ``starts - 1`` starting points: the lowest-cost ones, kept at least
        0.15 of the bounds apart.
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
        Fit all channels at once (:mod:`~roughbrdf.fitting.kinds.joint`): the ``shared`` parameters
        take one value for every channel, the others one per channel. Exactly ``starts``
        local fits in all (not per channel).
    shared : iterable of str, optional
        With ``joint=True``: the free parameters common to all channels. Default: every free
        parameter that is not a reflectance (roughness, index, lobe scales).
    polarimetric_weight : float, optional
        Mueller data only (``measurement.mueller`` set,
        :mod:`~roughbrdf.fitting.kinds.polarimetric`):
        the weight of the absolute residuals of the normalized elements ``m_ij/m00`` against
        the ``loss`` residuals of ``m00`` (default 1).
    progress : bool or None
        Show a tqdm progress bar; ``None`` shows it only on an interactive terminal.
    energy_constraint : bool
        Refit a channel whose fitted model reflects more than it receives (albedo above
        ``1 + 1e-3`` at some incidence of 0, 5, ... 85, 89 deg) under the constraint
        ``albedo <= 1`` there (:mod:`~roughbrdf.fitting.energy`); models that conserve energy
        by construction never need it. ``False``: the unconstrained fit (as the papers').
        Joint and Mueller fits are checked, not constrained.
    wavelength : float, str or None
        For models with a ``wavelength`` option left unset (K-correlation / Rayleigh–Rice): the
        wavelength of every channel, in µm or as a string with a unit (``"630nm"``). None
        (default): each channel's from the file or its name (:mod:`~roughbrdf.fitting.
        wavelengths`); a model that needs one and finds none is refused.
    intervals : {"wald", "profile"}
        ``"wald"`` (default): the standard errors alone. ``"profile"``: also, from the profile
        of the cost, the 68 % and 95 % intervals of every fitted parameter with a standard
        error (:mod:`~roughbrdf.fitting.results.intervals`) and the one-sided 95 % limit of
        each on a physical limit (:mod:`~roughbrdf.fitting.results.one_sided`); 2-4 refits
        of the other parameters per limit and side.

    Raises
    ------
    ArgumentError
        On construction (and by :meth:`replace`), for every option that is bad whatever the
        model and the data: the aperture and its rule, the fit domain, the loss, ``nonfinite``,
        ``negative``, ``extrapolated``, the search counts and seed, ``scale``, ``joint``,
        ``shared`` without a joint fit, ``polarimetric_weight``, ``energy_constraint``,
        ``wavelength``, ``intervals``.
    """

    channel: int | str | Sequence[int | str] | None = None
    loss: str = "auto"
    weights: Any = None
    fix: Iterable[str] | str = ()
    bounds: Mapping[str, Sequence[float]] | None = None
    starts: int = 8
    seed: int | None = 0
    nonfinite: str = "raise"
    negative: str = "auto"
    relative_to: str | None = None
    free_scale: bool | None = None
    scale: float | None = None
    screen: int = 64
    subsample: int | None = 1000
    polish: int = 2
    max_nfev: int | None = None
    aperture: float | None = None
    aperture_points: int = 19
    theta_r_max: float | None = None
    source_exclusion: float | None = None
    extrapolated: str = "drop"
    joint: bool = False
    shared: Iterable[str] | None = None
    polarimetric_weight: float | None = None
    progress: bool | None = None
    energy_constraint: bool = True
    wavelength: float | str | None = None
    intervals: str = "wald"

    def __post_init__(self) -> None:
        # in the order the fit met them before the options were one object
        Aperture.parse(self.aperture, self.aperture_points)
        check_fit_domain(self.theta_r_max, self.source_exclusion)
        check_loss(self.loss)
        check_sample_options(self.nonfinite, self.negative, self.extrapolated)
        self.search()
        check_scale(self.scale, self.free_scale)
        if not isinstance(self.joint, bool):  # `if joint:` would take any truthy value
            raise ArgumentError("joint", "must be True or False", value=self.joint)
        if self.shared is not None and not self.joint:
            shared = self.shared
            named = shared if isinstance(shared, str) else ", ".join(map(str, shared))
            raise ArgumentError("shared", "only a joint fit shares parameters: ask for one with "
                                "joint=True (command line: --joint)", value=named)
        if self.polarimetric_weight is not None:
            check_polarimetric_weight(self.polarimetric_weight)
        if not isinstance(self.energy_constraint, bool):  # a string "no" would be truthy
            raise ArgumentError("energy_constraint", "must be True or False",
                                value=self.energy_constraint)
        parse_wavelength(self.wavelength)  # ArgumentError naming wavelength
        if self.intervals not in ("wald", "profile"):  # results.intervals.INTERVALS
            raise ArgumentError("intervals", "must be 'wald' or 'profile'", value=self.intervals)
        if self.intervals == "profile" and self.joint:  # the profile is of one channel's cost
            raise ArgumentError("intervals", "profile intervals are for channels fitted on "
                                "their own, not a joint fit", value=self.intervals)

    @classmethod
    def of(cls, options: FitOptions | None = None, keywords: Mapping[str, Any] | None = None,
           *, caller: str = "fit") -> FitOptions:
        """``options`` (default: the defaults) with ``keywords`` replacing fields; a keyword
        that is no option raises the ``TypeError`` Python raises for a function ``caller``."""
        known = {f.name for f in dataclasses.fields(cls)}
        for name in keywords or {}:
            if name not in known:  # as Python words it for a function without that parameter
                raise TypeError(f"{caller}() got an unexpected keyword argument {name!r}")
        if options is None:
            return cls(**dict(keywords or {}))
        if not isinstance(options, FitOptions):
            raise ArgumentError("options", "must be a roughbrdf.fitting.FitOptions (or give "
                                "the options as keywords)", value=options)
        return options.replace(**keywords) if keywords else options

    def replace(self, **changes: Any) -> FitOptions:
        """A copy with ``changes`` (checked again), as :func:`dataclasses.replace`."""
        return dataclasses.replace(self, **changes)

    def search(self) -> SearchOptions:
        """The search settings (:class:`~roughbrdf.fitting.solvers.search.SearchOptions`)."""
        return SearchOptions(self.starts, self.screen, self.subsample, self.polish,
                             self.max_nfev, self.seed)

    def as_dict(self) -> dict[str, Any]:
        """Every option by name (the values as given)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    def changed(self) -> dict[str, Any]:
        """The options that differ from the defaults (compared as their JSON text, so that
        ``fix=[]`` is the default ``()``)."""
        out = {}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if _text(value) != _text(f.default):
                out[f.name] = value
        return out


def _text(value: Any) -> str:
    """What :func:`changed` compares: the JSON text (``repr`` for what JSON has no form of)."""
    return json.dumps(value, sort_keys=True, default=repr)


def check_scale(scale: Any, free_scale: Any) -> float | None:
    """A known data ``scale`` as a float (finite, > 0; None: not given), and not together
    with ``free_scale=True``; ArgumentError naming ``scale`` otherwise."""
    if scale is None:
        return None
    try:  # a number, not text that reads as one ("1") nor a bool
        fixed = math.nan if isinstance(scale, str | bytes | bool) else float(scale)
    except (TypeError, ValueError, OverflowError):
        fixed = math.nan
    if not (math.isfinite(fixed) and fixed > 0):
        raise ArgumentError("scale", f"scale must be finite and > 0, got {scale!r}")
    if free_scale:
        raise ArgumentError("scale", "give either scale= (a known data scale) or "
                            "free_scale=True")
    return fixed


def check_polarimetric_weight(value: Any) -> float:
    """``polarimetric_weight`` as a float, finite and >= 0 (ArgumentError otherwise).

    Examples
    --------
    >>> check_polarimetric_weight(2)
    2.0
    """
    bad = isinstance(value, str | bytes | bool | complex)
    try:
        w = math.nan if bad else float(value)
    except (TypeError, ValueError, OverflowError):
        w = math.nan
    if not (math.isfinite(w) and w >= 0.0):
        raise ArgumentError("polarimetric_weight", "must be a finite number >= 0 (the weight "
                            "of the normalized Mueller elements against m00)", value=value)
    return w
