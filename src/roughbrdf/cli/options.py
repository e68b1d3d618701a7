"""The options that ``roughbrdf fit``, ``compare`` and ``fit-batch`` share, declared once.

Each option is one entry of :data:`TABLE` (its typer annotation, with the help text, and its
default). A verb lists the names of its parameters in order (:func:`command` gives the verb
function the :class:`inspect.Signature` typer reads) and receives them as keywords; what it got
becomes a :class:`~roughbrdf.fitting.problem.options.FitOptions` (:func:`fit_options`, degrees
turned
into radians and checked in CLI terms), a :class:`ModelInput` (``--model``, ``-p``, ``--fix``,
``--bounds``, ``--models``; resolved on the model by
:func:`roughbrdf.cli.fit.resolve_model`) and a :class:`ReadInput` (``--quantity``, ``--angles-in``,
``--format``). Nothing heavy is imported at module level (``roughbrdf --help`` stays fast).

Every error about an option's value is an :class:`OptionError`, one line that starts with the
option (``--loss: unknown value 'x' (choose from ...)``): :func:`unknown_value` words a value
not among the choices, :func:`naming` puts the option ahead of a library error raised while a
value is used, and :func:`pick_channel` resolves a ``--channel`` of a saved fit. Every verb uses
these (exit status 2, :data:`roughbrdf.cli.EXIT_USAGE`).
"""

from __future__ import annotations

import contextlib
import inspect
import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated, Any

import typer

if TYPE_CHECKING:
    from ..fitting.problem.options import FitOptions

__all__ = ["TABLE", "ModelInput", "OptionError", "ReadInput", "channel_labels",
           "check_aperture", "check_format", "check_search", "command", "fit_domain",
           "fit_options", "naming", "pick_channel", "unknown_value"]

# the options of model choice, joint fits and the fit domain, shared with `roughbrdf compare`
ModelsOption = Annotated[str | None, typer.Option(
    "--models", metavar="SPEC,SPEC,...",
    help="with --model auto: the candidates (default: trowbridge-reitz-1975, coated, "
         "coated(lobes=2), coated-conductor(coat=false, diffuse=true, flakes=reflectance), "
         "coated-conductor(diffuse=true, flakes=reflectance))")]
CvOption = Annotated[bool, typer.Option(
    "--cv/--no-cv", help="leave-one-incidence-out cross-validation score (model choice)")]
JointOption = Annotated[bool, typer.Option(
    "--joint", help="fit all channels at once, roughness and index shared")]
SharedOption = Annotated[list[str] | None, typer.Option(
    "--shared", help="with --joint: a parameter shared by the channels (repeatable; default: "
                     "all but the reflectances)")]
KeepExtrapolatedOption = Annotated[bool, typer.Option(
    "--keep-extrapolated", help="also fit values the file holds beyond the instrument's "
                                "measured range (default: left out and counted)")]
ParamOption = Annotated[list[str] | None, typer.Option(
    "-p", "--param", help="starting value or option, name=value (repeatable; angles such as "
                         "Oren-Nayar sigma in degrees)")]
FixOption = Annotated[list[str] | None, typer.Option(
    "--fix", help="keep this parameter at its value (repeatable)")]
BoundsOption = Annotated[list[str] | None, typer.Option(
    "--bounds", metavar="NAME=LOW:HIGH",
    help="search range of a parameter, e.g. e=0.1:2 (repeatable; names as for --fix; angles "
         "such as sigma in degrees; a default starting value outside it starts in the middle)")]
ChannelOption = Annotated[list[str] | None, typer.Option(
    "--channel", "-c", help="channel label or index (repeatable; default: all)")]
LossOption = Annotated[str, typer.Option(
    help="auto (robust; relative for TR75: measured best, docs/fitting.md), relative "
         "((x-f)/f, TR75), log, absolute or robust (soft-L1 of ln x - ln f)")]
StartsOption = Annotated[int, typer.Option(help="multistart points per channel")]
QuantityOption = Annotated[str | None, typer.Option(
    help="input: what the file's values are, if the file does not say: brdf, brdf_cos "
         "(= bridf), bridf or relative")]
AnglesInOption = Annotated[str | None, typer.Option(
    "--angles-in", metavar="deg|rad",
    help="input: angle unit of an ASTM or CSV file, overriding the file")]
RelativeToOption = Annotated[str | None, typer.Option(
    "--relative-to",
    help="for relative data: brdf or bridf (default: the file's relative_to, else brdf)")]
FormatOption = Annotated[str | None, typer.Option(
    "--format", help="override the format chosen from the extension")]
NonfiniteOption = Annotated[str, typer.Option(help="non-finite values: raise or drop")]
NegativeOption = Annotated[str, typer.Option(
    help="negative values: auto (drop for the log and robust losses, else keep), keep, drop "
         "or clip")]
SeedOption = Annotated[int, typer.Option(help="seed of the Sobol starts and the subsample")]
FreeScaleOption = Annotated[bool | None, typer.Option(
    "--free-scale/--no-free-scale",
    help="fit a free scale K of the data in closed form (x -> K x; default: only for "
         "relative data)")]
ApertureOption = Annotated[float | None, typer.Option(
    "--aperture", metavar="DEG",
    help="instrument aperture: half-angle in degrees of a uniform cone about the reflection "
         "direction; the model is averaged over it (default: none)")]
ThetaRMaxOption = Annotated[float | None, typer.Option(
    "--theta-r-max", metavar="DEG",
    help="fit domain: leave out samples with theta_r above DEG (counted; default: none)")]
SourceExclusionOption = Annotated[float | None, typer.Option(
    "--source-exclusion", metavar="DEG",
    help="fit domain: leave out samples within DEG of the direction toward the source "
         "(retro-blocked; counted; default: none)")]
PlotsOption = Annotated[bool, typer.Option("--plots/--no-plots", help="write PNG plots")]
EnergyConstraintOption = Annotated[bool, typer.Option(
    "--energy-constraint/--no-energy-constraint",
    help="refit a model that reflects more than it receives (albedo > 1 at some theta_i of "
         "0, 5, ... 85, 89 deg) under albedo <= 1 there; --no-energy-constraint: the "
         "unconstrained fit")]

IntervalsOption = Annotated[str, typer.Option(
    "--intervals", metavar="KIND",
    help="wald (default): standard errors; profile: also 68 % and 95 % intervals, and "
         "one-sided 95 % limits of parameters on a physical limit, from the profile of the "
         "cost, the other parameters refitted (2-4 refits per limit)")]

WavelengthOption = Annotated[str | None, typer.Option(
    "--wavelength", metavar="WL",
    help="wavelength of every channel for models that need one (k-correlation), in um or "
         "with a unit (630nm); default: from the file or the channel names")]

#: every shared option: parameter name -> (typer annotation, default)
TABLE: dict[str, tuple[Any, Any]] = {
    "models": (ModelsOption, None), "cv": (CvOption, True), "joint": (JointOption, False),
    "shared": (SharedOption, None), "keep_extrapolated": (KeepExtrapolatedOption, False),
    "param": (ParamOption, None), "fix": (FixOption, None), "bounds": (BoundsOption, None),
    "channel": (ChannelOption, None), "loss": (LossOption, "auto"),
    "starts": (StartsOption, 8), "quantity": (QuantityOption, None),
    "angles_in": (AnglesInOption, None), "relative_to": (RelativeToOption, None),
    "file_format": (FormatOption, None), "nonfinite": (NonfiniteOption, "raise"),
    "negative": (NegativeOption, "auto"), "seed": (SeedOption, 0),
    "free_scale": (FreeScaleOption, None), "aperture": (ApertureOption, None),
    "theta_r_max": (ThetaRMaxOption, None), "source_exclusion": (SourceExclusionOption, None),
    "plots": (PlotsOption, True), "energy_constraint": (EnergyConstraintOption, True),
    "wavelength": (WavelengthOption, None), "intervals": (IntervalsOption, "wald"),
}
#: the CLI values that are FitOptions fields as they are
_AS_GIVEN = ("loss", "starts", "seed", "nonfinite", "negative", "relative_to", "free_scale",
             "joint", "energy_constraint", "wavelength", "intervals")
#: options every verb that fits takes (those whose ``order`` has ``starts``), placed after it
_FITTING = ("energy_constraint", "wavelength")


class OptionError(ValueError):
    """A bad value of a command-line option: one line that starts with the option.

    Parameters
    ----------
    option : str
        The option as the command line spells it (``"--loss"``, ``"-p/--param"``, or an
        argument's metavar such as ``"MODEL"``).
    message : str
        What is wrong, naming the offending value; white space is made one line, and the
        option is put ahead unless the message starts with it already.

    Examples
    --------
    >>> str(OptionError("--fix", "unknown parameter 'zz'"))
    "--fix: unknown parameter 'zz'"
    >>> str(OptionError("--starts", "--starts must be >= 1 (got 0)"))
    '--starts must be >= 1 (got 0)'
    """

    def __init__(self, option: str, message: str) -> None:
        self.option = option
        text = " ".join(str(message).split())
        if not (text.startswith(option) and text[len(option):len(option) + 1] in ("", " ", ":")):
            text = f"{option}: {text}"
        super().__init__(text)


def unknown_value(option: str, value: object, choices: Sequence[str],
                  what: str = "value") -> OptionError:
    """The error of a value of ``option`` that is none of ``choices`` (to raise).

    Examples
    --------
    >>> str(unknown_value("--paper", "x", ["ts67", "tr75", "rb08", "all"]))
    "--paper: unknown value 'x' (choose from ts67, tr75, rb08, all)"
    >>> str(unknown_value("--to", "hdf5", ["astm", "csv"], what="format"))
    "--to: unknown format 'hdf5' (choose from astm, csv)"
    """
    return OptionError(option, f"unknown {what} {value!r} (choose from {', '.join(choices)})")


@contextlib.contextmanager
def naming(option: str) -> Iterator[None]:
    """A ``ValueError`` raised inside (the library checking a value of ``option``) becomes an
    :class:`OptionError` of ``option``: its message, put after the option. An
    :class:`OptionError` (of any option) passes as it is; other errors (files, bugs) too.

    Examples
    --------
    >>> with naming("--model"):
    ...     raise ValueError("unknown model 'x'")
    Traceback (most recent call last):
    ...
    roughbrdf.cli.options.OptionError: --model: unknown model 'x'
    """
    try:
        yield
    except OptionError:
        raise
    except ValueError as exc:
        raise OptionError(option, str(exc)) from exc


def check_format(file_format: str | None, option: str = "--format", what: str = "value"
                 ) -> None:
    """Refuse a format name (``--format``, ``--from``, ``--to``) the readers do not know,
    before any file is read: the option, the value (``what``: ``"value"``, or ``"format"``
    where the option's name does not say it is one) and the formats there are."""
    if file_format is None:
        return
    from ..io import FORMATS, format_for

    try:
        format_for("input", file_format)
    except ValueError:
        raise unknown_value(option, file_format, list(FORMATS), what) from None


def pick_channel(labels: Sequence[str], channel: str) -> int:
    """The position of ``--channel`` (a label, a label without its ``nm``, or an index, as
    :meth:`roughbrdf.Measurement.channel_index` takes them) among the channels of a saved fit.

    Examples
    --------
    >>> pick_channel(["465nm", "525nm"], "525"), pick_channel(["465nm", "525nm"], "-1")
    (1, 1)
    >>> pick_channel(["relative"], "9")
    Traceback (most recent call last):
    ...
    roughbrdf.cli.options.OptionError: --channel: unknown channel '9' (the fit has 1 channel: ...)
    """
    names = [str(c) for c in labels]
    for form in (names, [n.removesuffix("nm") for n in names]):
        if form.count(channel) == 1:
            return form.index(channel)
    if channel.lstrip("-").isdigit() and -len(names) <= int(channel) < len(names):
        return int(channel) % len(names)
    count = f"{len(names)} channel{'s' if len(names) != 1 else ''}"
    raise OptionError("--channel", f"unknown channel {channel!r} (the fit has {count}: "
                                   f"{', '.join(names)}; a label or an index from 0 to "
                                   f"{len(names) - 1})")


def command(func: Callable[..., Any], order: list[str],
            own: Mapping[str, tuple[Any, Any]]) -> Callable[..., Any]:
    """``func`` (a verb taking ``**values``) with the signature typer reads: the parameters
    ``order`` in that order, each from ``own`` (the verb's own, ``(annotation, default)``;
    default ``inspect.Parameter.empty``: required) or else from :data:`TABLE`. A verb that
    fits (``starts`` in ``order``) also gets the :data:`_FITTING` options after ``starts``."""
    if "starts" in order:  # declared here once, not in each verb's list
        at = order.index("starts") + 1
        order = order[:at] + [n for n in _FITTING if n not in order] + order[at:]
    params = [inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY,
                                annotation=spec[0], default=spec[1])
              for name in order for spec in [own.get(name) or TABLE[name]]]
    func.__signature__ = inspect.Signature(params, return_annotation=None)  # type: ignore[attr-defined]
    return func


def check_aperture(aperture: float | None) -> float | None:
    """``--aperture DEG`` -> radians (None: no aperture); a clear error outside [0, 90)."""
    if aperture is None:
        return None
    if not (math.isfinite(aperture) and 0 <= aperture < 90):
        raise ValueError(f"--aperture must be a half-angle in degrees, 0 <= DEG < 90; got "
                         f"{aperture!r}")
    return math.radians(aperture)


def check_search(starts: int | None, loss: str | None, seed: int | None,
                 relative_to: str | None = None) -> None:
    """``--starts``, ``--loss``, ``--seed`` and ``--relative-to`` in the terms of the command
    line, for every verb that fits (:func:`fit_options` calls it), before any work: each
    error names its option and the value (numpy would say "expected non-negative integer" of
    a negative seed, naming nothing). None: the verb has no such option.

    Examples
    --------
    >>> check_search(0, "relative", 0)
    Traceback (most recent call last):
    ...
    ValueError: --starts must be >= 1 (got 0)
    >>> check_search(8, "auto", -1)
    Traceback (most recent call last):
    ...
    ValueError: --seed must be >= 0 (got -1)
    """
    from ..quantity import LOSSES, Loss, Quantity

    if starts is not None and starts < 1:  # no start point, no fit
        raise ValueError(f"--starts must be >= 1 (got {starts})")
    try:  # the loss's own check, worded for the command line
        if loss is not None and loss != "auto":
            Loss.parse(loss)
    except ValueError:
        raise unknown_value("--loss", loss, ["auto", *LOSSES]) from None
    if seed is not None and seed < 0:  # numpy's generators take no negative seed
        raise ValueError(f"--seed must be >= 0 (got {seed})")
    if relative_to is not None:
        try:  # what a relative file's values are proportional to (fitting.problem.data.Comparison)
            Quantity.RELATIVE.compared_with(relative_to)
        except ValueError:
            raise unknown_value("--relative-to", relative_to, ["brdf", "bridf"]) from None


def fit_domain(theta_r_max: float | None, source_exclusion: float | None
               ) -> tuple[float | None, float | None]:
    """``--theta-r-max``, ``--source-exclusion`` (degrees) -> radians, checked by the library
    (errors name the options, in degrees)."""
    from ..fitting.problem.data import check_fit_domain

    return check_fit_domain(*(None if v is None else math.radians(v)
                              for v in (theta_r_max, source_exclusion)))


def fit_options(values: Mapping[str, Any], *, progress: bool | None = None) -> FitOptions:
    """The :class:`~roughbrdf.fitting.problem.options.FitOptions` of a verb's values, without
    ``--fix`` and ``--bounds`` (they need the model: :func:`roughbrdf.cli.fit.resolve_model`):
    angles in degrees checked and turned into radians, ``--keep-extrapolated`` as
    ``extrapolated``; the search options checked in CLI terms (:func:`check_search`)."""
    from ..fitting.problem.options import FitOptions

    # --relative-to is left to the library here: fit and compare name it (with the value and
    # the choices); fit-batch checks it too, before any cluster starts
    check_search(values.get("starts"), values.get("loss"), values.get("seed"))
    aperture = check_aperture(values.get("aperture"))
    t_max, excl = fit_domain(values.get("theta_r_max"), values.get("source_exclusion"))
    given = {k: values[k] for k in _AS_GIVEN if k in values}
    channel = values.get("channel")
    # labels or positions as text; Measurement.channel_index resolves both ("525" also finds
    # "525nm")
    return FitOptions(**given, channel=list(channel) if channel else None,
                      shared=values.get("shared") or None, aperture=aperture,
                      theta_r_max=t_max, source_exclusion=excl,
                      extrapolated="keep" if values.get("keep_extrapolated") else "drop",
                      progress=progress)


def channel_labels(options: FitOptions) -> list[str] | None:
    """The ``--channel`` values of ``options`` as the command line gave them (text), or None."""
    chosen = options.channel
    if chosen is None:
        return None
    return [str(c) for c in (chosen if isinstance(chosen, list | tuple) else [chosen])]


@dataclass(frozen=True)
class ReadInput:
    """How to read the input: ``--format``, ``--quantity``, ``--angles-in`` as typed."""

    file_format: str | None = None
    quantity: str | None = None
    angles_in: str | None = None

    @classmethod
    def of(cls, values: Mapping[str, Any]) -> ReadInput:
        """The reading options among a verb's values."""
        return cls(values.get("file_format"), values.get("quantity"), values.get("angles_in"))


@dataclass(frozen=True)
class ModelInput:
    """The model as typed: ``--model``, ``-p``, ``--fix``, ``--bounds`` and ``--models``."""

    spec: str
    param: list[str] | None = None
    fix: list[str] | None = None
    bounds: list[str] | None = None
    models: str | None = None

    @classmethod
    def of(cls, values: Mapping[str, Any]) -> ModelInput:
        """The model's options among a verb's values."""
        return cls(values["model"], values.get("param"), values.get("fix"),
                   values.get("bounds"), values.get("models"))

    @property
    def auto(self) -> bool:
        """``--model auto`` (model choice)."""
        from ..models.factory import is_auto

        return is_auto(self.spec)
