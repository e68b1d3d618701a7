"""``roughbrdf fit FILE --model NAME --out DIR``: fit a model to a measurement file.

Writes ``fit.json`` (keys ``model``, ``file``, ``loss``, ``channels``: per channel ``channel``,
``params``, ``stderr``, ``success``, ``metrics`` with ``sigma``, ``rms_log``, ``chi2``, ``aic``,
``bic``, ``n_points``; more keys may follow; ``aperture``: null or the instrument aperture used,
``half_angle_deg``, ``half_angle_rad``, ``points``), ``report.txt`` and one ``fit_<channel>.png``
per channel into DIR, as one set (:class:`roughbrdf.output.ResultFolder`): DIR may exist, but a
folder that holds results already, or a file of a name the run would write, stops the command
before the fit (``--force`` replaces an earlier run's results, never a file roughbrdf did not
write). ``--aperture DEG`` compares each sample with the model averaged over a uniform cone of
that half-angle (degrees) about the measured reflection direction (``rb.fit(...,
aperture=radians)``). ``--free-scale`` fits a closed-form scale ``K`` of the data also for
absolute data (``rb.fit(..., free_scale=True)``), ``--theta-r-max DEG`` and
``--source-exclusion DEG`` leave out (and count) the samples beyond that reflection angle or
within that angle of the direction toward the source (``rb.fit(..., theta_r_max=,
source_exclusion=)`` in radians), ``--no-plots`` skips the figures (and
Matplotlib). ``--bounds NAME=LOW:HIGH`` overrides a parameter's search range; ``--angles-in``
states the angle unit of an ASTM or CSV file that does not. ``--model auto`` fits the
candidates of ``roughbrdf.fitting.compare.AUTO_CANDIDATES`` (or those of ``--models``) and keeps
the lowest BIC, with the comparison in ``fit.json``, the report and ``compare.png``
(``--no-cv``: without the leave-one-incidence-out score). ``--joint`` fits all channels at
once with the roughness and index shared (``--shared NAME`` chooses), ``--keep-extrapolated``
also fits the values a file holds beyond the instrument's range (``rb.fit(...,
extrapolated="keep")``).

A parameter whose unit is an angle (Oren-Nayar ``sigma``, also in ``coated(diffuse=
oren-nayar)`` and in sums) is in degrees in ``-p`` and ``--bounds`` and in the report printed
and written to ``report.txt``; ``fit.json`` holds radians, as the library does.

Exit status 1 when the fit did not converge for some channel (the results are written).
"""

from __future__ import annotations

import errno
import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from .common import FIT_OPTIONS, angle_names, check_channels, cli_model, handled, parse_params

if TYPE_CHECKING:
    from ..measurement import Measurement
    from ..models import Model

#: the library's argument names -> this verb's options (errors name the options)
OPTIONS = FIT_OPTIONS

#: spellings of --angles-in -> the readers' angles= option
ANGLE_UNITS = {"deg": "deg", "degree": "deg", "degrees": "deg", "rad": "rad", "radian": "rad",
               "radians": "rad"}


# the options of model choice, joint fits and the fit domain, shared with `roughbrdf compare`
ModelsOption = Annotated[str | None, typer.Option(
    "--models", metavar="SPEC,SPEC,...",
    help="with --model auto: the candidates (default: trowbridge-reitz-1975, coated, "
         "coated(lobes=2), coated(lobes=2, distribution=beckmann))")]
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
LossOption = Annotated[str, typer.Option(help="relative ((x-f)/f, TR75), log or absolute")]
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
NegativeOption = Annotated[str, typer.Option(help="negative values: keep, drop or clip")]
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


def build_model(spec: str, params: dict[str, Any] | None = None) -> Model:
    """A model from ``name`` or ``name1+name2`` and ``-p`` settings (:func:`roughbrdf.model`);
    a parameter whose unit is an angle (Oren-Nayar ``sigma``) is given in degrees
    (:func:`~roughbrdf.cli.common.cli_model`)."""
    return cli_model(spec, params)


def resolve_names(model: Model, names: list[str]) -> list[str]:
    """Map ``--fix`` names to the model's parameter names (plain names allowed in sums)."""
    from .. import models as _models

    return _models.resolve_names(model, names)


def parse_bounds(model: Model, items: list[str] | None) -> dict[str, tuple[float, float]]:
    """``--bounds NAME=LOW:HIGH`` (repeatable) -> ``{parameter: (low, high)}`` for ``rb.fit``.

    Names are resolved like ``--fix`` (plain names allowed in sums); the range of a parameter
    whose unit is an angle (Oren-Nayar ``sigma``) is in degrees, like its ``-p`` value.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> parse_bounds(rb.model("tr75+lambertian"), ["e=0.1:2", "lambertian_rho=0:0.5"])
    {'tr75_e': (0.1, 2.0), 'lambertian_rho': (0.0, 0.5)}
    """
    out: dict[str, tuple[float, float]] = {}
    for item in items or []:
        name, sep, rng = item.partition("=")
        parts = rng.split(":")
        try:
            if not sep or len(parts) != 2:
                raise ValueError
            low, high = float(parts[0]), float(parts[1])
        except ValueError:
            raise ValueError(f"--bounds expects NAME=LOW:HIGH (e.g. --bounds e=0.1:2), got "
                             f"{item!r}") from None
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise ValueError(f"--bounds {item}: need finite LOW < HIGH")
        (key,) = resolve_names(model, [name.strip()])
        out[key] = (low, high)
        if key in angle_names(model):
            out[key] = (math.radians(low), math.radians(high))
            _check_angle_domain(model, key, item, *out[key])
    return out


def _check_angle_domain(model: Model, key: str, item: str, low: float, high: float) -> None:
    """Refuse ``--bounds`` of an angle parameter outside its physical domain, in degrees (the
    library's own check would word it in radians)."""
    spec = next(p for p in model.parameters if p.name == key)
    dlo, lo_inc, dhi, hi_inc = spec.domain
    if (low >= dlo if lo_inc else low > dlo) and (high <= dhi if hi_inc else high < dhi):
        return
    domain = (("[" if lo_inc else "(") + f"{math.degrees(dlo):g}, {math.degrees(dhi):g}"
              + ("]" if hi_inc else ")"))
    raise ValueError(f"--bounds {item}: the range leaves the physical domain of {key!r}, "
                     f"{domain} degrees")


def start_within(model: Model, ranges: dict[str, tuple[float, float]],
                 given: dict[str, Any]) -> Model:
    """``model`` with each default starting value that ``--bounds`` excludes moved to the middle
    of its range; a value the user gave (``-p``) is left for the fit to reject.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> start_within(rb.model("tr75"), {"e": (1.0, 2.0)}, {}).params["e"]
    1.5
    """
    mine = set()
    for key in given:
        try:
            mine.update(resolve_names(model, [key]))
        except ValueError:  # an option (distribution=...), not a parameter
            continue
    move = {name: 0.5 * (low + high) for name, (low, high) in ranges.items()
            if name not in mine and model.params.get(name) is not None
            and not low <= float(model.params[name]) <= high}
    return model.with_values(list(move), list(move.values())) if move else model


def angle_unit(text: str | None) -> str | None:
    """``--angles-in`` -> the readers' ``angles=`` value (``"deg"``/``"rad"``), or None."""
    if text is None:
        return None
    unit = ANGLE_UNITS.get(text.strip().lower())
    if unit is None:
        raise ValueError(f"--angles-in must be deg or rad, got {text!r}")
    return unit


def read_input(file: str, file_format: str | None, quantity: str | None,
               angles: str | None) -> Measurement:
    """The measurement FILE with the verb's reading options (``--format``, ``--quantity``,
    ``--angles-in``), each checked in CLI terms first."""
    from .. import io as _io
    from ..quantity import Quantity

    if not Path(file).exists():
        raise FileNotFoundError(errno.ENOENT, "no such file", file)
    if Path(file).is_dir():  # not a file of an unknown extension: a verb for one file
        raise ValueError(f"{file} is a folder: this command reads one measurement file "
                         f"(fit-batch fits the files of a folder)")
    opts: dict[str, Any] = {}
    if quantity:
        opts["quantity"] = Quantity.parse(quantity, "--quantity").value
    unit = angle_unit(angles)
    if unit is not None:
        fmt = _io.format_for(file, file_format)
        if fmt not in ("astm", "csv"):
            raise ValueError(f"--angles-in applies to ASTM and CSV files; {fmt.upper()} files "
                             f"are always in radians")
        opts["angles"] = unit
    if quantity and _io.format_for(file, file_format) == "merl":
        raise ValueError("--quantity does not apply to MERL files (always BRDF)")
    return _io.read(file, format=file_format, **opts)


def result_names(meas: Measurement, channel: list[str] | None, plots: bool,
                 auto: bool = False) -> list[str]:
    """The files the run will write (``FitResult.save``: ``fit.json``, ``report.txt``,
    ``fit_<channel>.png`` as :meth:`roughbrdf.FitResult.plot_names` names them, and
    ``compare.png`` for ``--model auto``)."""
    labels = ([meas.channels[i] for i in check_channels(meas, channel)] if channel
              else list(meas.channels))
    if getattr(meas, "mueller", None):  # Mueller elements are fitted as one "channel"
        labels = ["mueller"]
    names = ["fit.json", "report.txt"]
    if plots:
        for label in labels:
            safe = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in label)
            names.append(f"fit_{safe or 'channel'}.png")
        if auto:
            names.append("compare.png")
    return names


def fit_domain(theta_r_max: float | None, source_exclusion: float | None
               ) -> tuple[float | None, float | None]:
    """``--theta-r-max``, ``--source-exclusion`` (degrees) -> radians, checked by the library
    (errors name the options, in degrees)."""
    from ..fitting.data import check_fit_domain

    return check_fit_domain(*(None if v is None else math.radians(v)
                              for v in (theta_r_max, source_exclusion)))


def auto_options(models: str | None, param: list[str] | None, fix: list[str] | None,
                 bounds: list[str] | None, auto: bool) -> None:
    """Refuse what ``--model auto`` cannot take (and ``--models`` without it)."""
    if not auto:
        if models:
            raise ValueError("--models lists the candidates of --model auto (or use "
                             "roughbrdf compare)")
        return
    for name, given in (("-p/--param", param), ("--fix", fix), ("--bounds", bounds)):
        if given:
            raise ValueError(f"{name} names settings of one model; with --model auto the "
                             f"candidates differ: choose the model, or compare candidates "
                             f"with roughbrdf compare")


def check_aperture(aperture: float | None) -> float | None:
    """``--aperture DEG`` -> radians (None: no aperture); a clear error outside [0, 90)."""
    if aperture is None:
        return None
    if not (math.isfinite(aperture) and 0 <= aperture < 90):
        raise ValueError(f"--aperture must be a half-angle in degrees, 0 <= DEG < 90; got "
                         f"{aperture!r}")
    return math.radians(aperture)


def run_fit(file: str, model: str, out: str, *, param: list[str] | None,
            fix: list[str] | None, bounds: list[str] | None, channel: list[str] | None,
            angles_in: str | None, quantity: str | None, file_format: str | None,
            aperture: float | None, plots: bool, force: bool, quiet: bool,
            theta_r_max: float | None = None, source_exclusion: float | None = None,
            models: str | None = None, cv: bool = True, **fit_options: Any) -> int:
    """The work of ``roughbrdf fit``; returns the exit status (0, or 1 if not converged).

    Everything that can be checked is checked before the fit: the options, the input file,
    and that ``out`` may receive the results (:meth:`roughbrdf.output.ResultFolder.check`).
    """
    from ..fitting import fit
    from ..fitting.compare import fit_auto
    from ..output import ResultFolder

    ap = check_aperture(aperture)
    t_max, excl = fit_domain(theta_r_max, source_exclusion)
    auto = model.strip().lower() == "auto"
    auto_options(models, param, fix, bounds, auto)
    if not auto:
        given = parse_params(param)
        m = build_model(model, given)
        fixed = resolve_names(m, list(fix or []))
        ranges = parse_bounds(m, bounds)
        m = start_within(m, ranges, given)
    meas = read_input(file, file_format, quantity, angles_in)
    chans = list(channel) if channel else None
    ResultFolder(out, overwrite=force).check(result_names(meas, chans, plots, auto))
    # labels or positions as text; Measurement.channel_index resolves both ("525" also finds
    # "525nm")
    common = {"channel": chans, "aperture": ap, "theta_r_max": t_max, "source_exclusion": excl,
              "progress": None if not quiet else False, **fit_options}
    if auto:
        res = fit_auto(meas, models, cv=cv, **common)
    else:
        res = fit(m, meas, fix=fixed, bounds=ranges or None, **common)
    # the report in degrees with the unit named, on the terminal and in report.txt (fit.json
    # keeps the library's radians)
    written = res.save(out, plots=plots, overwrite=force, report_angles="deg")
    if not quiet:
        typer.echo(res.report(angles="deg"))
        typer.echo("")
    typer.echo("wrote " + ", ".join(str(p) for p in written))
    return 0 if res.success else 1


def register(app: typer.Typer) -> None:
    @app.command("fit")
    def fit_cmd(
        file: str = typer.Argument(..., help="measurement file (.astm, .dat/.alta, .csv, "
                                             ".binary)"),
        model: str = typer.Option(..., "--model", "-m",
                                  help="model name, spec or sum, e.g. trowbridge-reitz-1975, "
                                       "coated(lobes=2) or microfacet+lambertian (aliases: "
                                       "roughbrdf models); auto: the lowest BIC of the "
                                       "candidates (--models)"),
        models: ModelsOption = None,
        cv: CvOption = True,
        joint: JointOption = False,
        shared: SharedOption = None,
        keep_extrapolated: KeepExtrapolatedOption = False,
        out: str = typer.Option(..., "--out", "-o", help="output folder (refused if it holds "
                                                          "results, unless --force)"),
        param: ParamOption = None,
        fix: FixOption = None,
        bounds: BoundsOption = None,
        channel: ChannelOption = None,
        loss: LossOption = "relative",
        starts: StartsOption = 8,
        quantity: QuantityOption = None,
        angles_in: AnglesInOption = None,
        relative_to: RelativeToOption = None,
        file_format: FormatOption = None,
        nonfinite: NonfiniteOption = "raise",
        negative: NegativeOption = "keep",
        seed: SeedOption = 0,
        free_scale: FreeScaleOption = None,
        aperture: ApertureOption = None,
        theta_r_max: ThetaRMaxOption = None,
        source_exclusion: SourceExclusionOption = None,
        plots: PlotsOption = True,
        force: bool = typer.Option(False, "--force",
                                   help="replace the results of an earlier run in --out (files "
                                        "roughbrdf did not write are never replaced)"),
        quiet: bool = typer.Option(False, "--quiet", "-q", help="no report on the terminal"),
    ) -> None:
        """Fit a model to a measurement file; write fit.json, report.txt and plots into --out."""
        with handled(OPTIONS):
            code = run_fit(file, model, out, param=param, fix=fix, bounds=bounds,
                           channel=channel, angles_in=angles_in, quantity=quantity,
                           file_format=file_format, aperture=aperture,
                           theta_r_max=theta_r_max, source_exclusion=source_exclusion,
                           plots=plots,
                           force=force, quiet=quiet, loss=loss, starts=starts, seed=seed,
                           free_scale=free_scale, nonfinite=nonfinite, negative=negative,
                           relative_to=relative_to, models=models, cv=cv, joint=joint,
                           shared=shared or None,
                           extrapolated="keep" if keep_extrapolated else "drop")
        if code:
            raise typer.Exit(code)
