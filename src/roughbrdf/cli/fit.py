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
candidates of ``roughbrdf.fitting.choice.compare.AUTO_CANDIDATES`` (or those of ``--models``) and
keeps
the best by leave-one-incidence-out prediction, with the comparison in ``fit.json``, the report
and ``compare.png``
(``--no-cv``: without the leave-one-incidence-out score). ``--joint`` fits all channels at
once with the roughness and index shared (``--shared NAME`` chooses), ``--keep-extrapolated``
also fits the values a file holds beyond the instrument's range (``rb.fit(...,
extrapolated="keep")``).

A parameter whose unit is an angle (Oren-Nayar ``sigma``, also in ``coated(diffuse=
oren-nayar)`` and in sums) is in degrees in ``-p`` and ``--bounds`` and in the report printed
and written to ``report.txt``; ``fit.json`` holds radians, as the library does.

Exit status 1 when the fit did not converge for some channel, when a parameter ended on a
search limit (a bound of the search that is no physical limit) or when a fitted model gains
energy (albedo > 1 at some incidence; one ``warning:`` line each): the results are written, not
to be trusted without a look.
"""

from __future__ import annotations

import contextlib
import errno
import inspect
import math
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from .common import FIT_OPTIONS, angle_names, check_channels, cli_model, handled, parse_params
from .options import (
    ModelInput,
    OptionError,
    ReadInput,
    channel_labels,
    check_format,
    command,
    fit_options,
    naming,
    unknown_value,
)

if TYPE_CHECKING:
    from ..fitting.problem.options import FitOptions
    from ..fitting.results.result import FitResult
    from ..measurement import Measurement
    from ..models import Model

#: the library's argument names -> this verb's options (errors name the options)
OPTIONS = FIT_OPTIONS

#: spellings of --angles-in -> the readers' angles= option
ANGLE_UNITS = {"deg": "deg", "degree": "deg", "degrees": "deg", "rad": "rad", "radian": "rad",
               "radians": "rad"}


def build_model(spec: str, params: dict[str, Any] | None = None) -> Model:
    """A model from ``name`` or ``name1+name2`` and ``-p`` settings (:func:`roughbrdf.model`);
    a parameter whose unit is an angle (Oren-Nayar ``sigma``) is given in degrees
    (:func:`~roughbrdf.cli.common.cli_model`); an error names ``--model`` or ``-p/--param``."""
    return cli_model(spec, params, "--model")


def resolve_names(model: Model, names: list[str]) -> list[str]:
    """Map ``--fix`` names to the model's parameter names (plain names allowed in sums)."""
    from .. import models as _models

    return _models.resolve_names(model, names)


def fixed_names(model: Model, names: list[str]) -> list[str]:
    """``--fix NAME`` (repeatable) -> the model's parameter names; an unknown name, or a
    ``NAME=VALUE`` (the value is set with ``-p``), is refused naming ``--fix``.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> fixed_names(rb.model("lambertian"), ["rho=0.2"])
    Traceback (most recent call last):
    ...
    roughbrdf.cli.options.OptionError: --fix rho=0.2: a parameter name is expected ...
    """
    for name in names:
        if "=" in name:
            raise OptionError("--fix", f"--fix {name}: a parameter name is expected (its value "
                                       f"is set with -p {name})")
    with naming("--fix"):
        return resolve_names(model, names)


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
        with naming("--bounds"):
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


def angle_unit(text: str | None, option: str = "--angles-in") -> str | None:
    """``--angles-in`` (or ``--angles-out``: ``option``) -> the readers' ``angles=`` value
    (``"deg"``/``"rad"``), or None.

    Examples
    --------
    >>> angle_unit("Degrees"), angle_unit(None)
    ('deg', None)
    >>> angle_unit("grad")
    Traceback (most recent call last):
    ...
    roughbrdf.cli.options.OptionError: --angles-in: unknown angle unit 'grad' (choose from ...)
    """
    if text is None:
        return None
    unit = ANGLE_UNITS.get(text.strip().lower())
    if unit is None:
        raise unknown_value(option, text, ["deg", "rad"], what="angle unit")
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
    check_format(file_format)  # the option named, not the file
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


def resolve_model(given: ModelInput, options: FitOptions) -> tuple[Model | str, FitOptions]:
    """The model (``"auto"`` as such) and ``options`` with ``--fix`` and ``--bounds`` resolved
    on it (a default starting value outside ``--bounds`` moved inside); what ``--model auto``
    cannot take (and ``--models`` without it) is refused."""
    auto_options(given.models, given.param, given.fix, given.bounds, given.auto)
    if given.auto:
        return "auto", options
    params = parse_params(given.param)
    m = build_model(given.spec, params)
    fixed = fixed_names(m, list(given.fix or []))
    ranges = parse_bounds(m, given.bounds)
    return start_within(m, ranges, params), options.replace(fix=fixed, bounds=ranges or None)


def run_per_incidence(file: str, out: str, given: ModelInput, options: FitOptions,
                      read: ReadInput, *, max_rows: int, force: bool, quiet: bool) -> int:
    """``roughbrdf fit --per-incidence``: one parameter set per measured incidence, at most
    ``--max-rows`` rows kept as an optical code's catalog holds them
    (:func:`roughbrdf.fitting.kinds.per_incidence.fit_per_incidence`); writes ``fit.json`` and
    ``report.txt``. Exit status 1 as for a fit, if any row's fit is not to be trusted."""
    from ..fitting.kinds.per_incidence import fit_per_incidence
    from ..output import ResultFolder

    if given.auto:
        raise ValueError("--per-incidence fits one model: name it with --model")
    if options.joint:
        raise ValueError("--per-incidence fits each incidence on its own; drop --joint")
    m, options = resolve_model(given, options)
    meas = read_input(file, read.file_format, read.quantity, read.angles_in)
    ResultFolder(out, overwrite=force).check(["fit.json", "report.txt"])
    with energy_warnings():
        res = fit_per_incidence(m, meas, max_rows=max_rows, options=options)
    written = res.save(out, overwrite=force)
    if not quiet:
        typer.echo(res.report())
    typer.echo("wrote " + ", ".join(str(p) for p in written))
    trusted = all([echo_untrusted(r.result) for r in res.rows])
    return 0 if res.success and trusted else 1


def run_fit(file: str, out: str, given: ModelInput, options: FitOptions, read: ReadInput, *,
            cv: bool, plots: bool, force: bool, quiet: bool) -> int:
    """The work of ``roughbrdf fit``; returns the exit status (0, or 1 if not converged, on a
    search limit or gaining energy: :func:`echo_untrusted`).

    Everything that can be checked is checked before the fit: the options (``options`` were
    checked when made), the input file, and that ``out`` may receive the results
    (:meth:`roughbrdf.output.ResultFolder.check`).
    """
    from ..fitting import fit
    from ..fitting.choice.auto import fit_auto
    from ..output import ResultFolder

    m, options = resolve_model(given, options)
    meas = read_input(file, read.file_format, read.quantity, read.angles_in)
    chans = channel_labels(options)
    ResultFolder(out, overwrite=force).check(result_names(meas, chans, plots, given.auto))
    with energy_warnings():
        if given.auto:
            res = fit_auto(meas, given.models, cv=cv, options=options)
        else:
            res = fit(m, meas, options=options)
    # the report in degrees with the unit named, on the terminal and in report.txt (fit.json
    # keeps the library's radians)
    written = res.save(out, plots=plots, overwrite=force, report_angles="deg")
    if not quiet:
        typer.echo(res.report(angles="deg"))
        typer.echo("")
    typer.echo("wrote " + ", ".join(str(p) for p in written))
    trusted = echo_untrusted(res)
    return 0 if res.success and trusted else 1


@contextlib.contextmanager
def energy_warnings() -> Iterator[None]:
    """Silence the :class:`~roughbrdf.fitting.results.plausibility.EnergyWarning` of a fit: the CLI
    words them itself (:func:`echo_untrusted`), one ``warning:`` line each."""
    from ..fitting.results.plausibility import EnergyWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", EnergyWarning)
        yield


def echo_untrusted(res: FitResult) -> bool:
    """Print a ``warning:`` line (stderr) for each channel of ``res`` whose model gains energy
    and each with a parameter on a search limit; whether there was none (a fit to trust)."""
    for i, c in enumerate(res.channels):
        p = res.plausibility(i)
        if p.gains_energy:
            typer.echo(f"warning: {res.model_name}, channel {c.channel}: the fitted model "
                       f"reflects more than it receives (albedo {p.max_albedo:.4g} at "
                       f"theta_i = {p.worst_incidence:g} deg): not physical", err=True)
        names = [nm for nm, k in c.limits.items() if k.startswith("search")]
        if names:
            typer.echo(f"warning: {res.model_name}, channel {c.channel}: {', '.join(names)} "
                       "ended on a search limit (a bound of the search, not a physical "
                       "limit): not a result", err=True)
    return not (res.at_search_limit or res.gains_energy)


#: the parameters of ``roughbrdf fit``, in the order of its help
FIT_ORDER = ["file", "model", "models", "cv", "joint", "shared", "per_incidence", "max_rows",
             "keep_extrapolated", "out",
             "param", "fix", "bounds", "channel", "loss", "starts", "quantity", "angles_in",
             "relative_to", "file_format", "nonfinite", "negative", "seed", "free_scale",
             "aperture", "theta_r_max", "source_exclusion", "intervals", "plots", "force", "quiet"]
#: the verb's own parameters (the shared ones: :data:`roughbrdf.cli.options.TABLE`)
FIT_OWN: dict[str, tuple[Any, Any]] = {
    "file": (Annotated[str, typer.Argument(help="measurement file (.astm, .dat/.alta, .csv, "
                                                ".binary)")], inspect.Parameter.empty),
    "model": (Annotated[str, typer.Option(
        "--model", "-m", help="model name, spec or sum, e.g. trowbridge-reitz-1975, "
                              "coated(lobes=2) or microfacet+lambertian (aliases: roughbrdf "
                              "models); auto: the candidate that predicts left-out incidences "
                              "best (--models)")],
              inspect.Parameter.empty),
    "out": (Annotated[str, typer.Option("--out", "-o", help="output folder (refused if it "
                                                             "holds results, unless --force)")],
            inspect.Parameter.empty),
    "force": (Annotated[bool, typer.Option(
        "--force", help="replace the results of an earlier run in --out (files roughbrdf did "
                        "not write are never replaced)")], False),
    "quiet": (Annotated[bool, typer.Option("--quiet", "-q", help="no report on the terminal")],
              False),
    "per_incidence": (Annotated[bool, typer.Option(
        "--per-incidence", help="one parameter set per measured incidence, the rows an optical "
                                "code's catalog keeps (Zemax ABg: up to 10, interpolated in "
                                "cos theta_i); writes fit.json and report.txt")], False),
    "max_rows": (Annotated[int, typer.Option(
        "--max-rows", min=2, help="with --per-incidence: rows kept at most")], 10),
}


def register(app: typer.Typer) -> None:
    def fit_cmd(**values: Any) -> None:
        """Fit a model to a measurement file; write fit.json, report.txt and plots into --out."""
        with handled(OPTIONS):
            options = fit_options(values, progress=None if not values["quiet"] else False)
            if values["per_incidence"]:
                code = run_per_incidence(values["file"], values["out"], ModelInput.of(values),
                                         options, ReadInput.of(values),
                                         max_rows=values["max_rows"], force=values["force"],
                                         quiet=values["quiet"])
            else:
                code = run_fit(values["file"], values["out"], ModelInput.of(values), options,
                               ReadInput.of(values), cv=values["cv"], plots=values["plots"],
                               force=values["force"], quiet=values["quiet"])
        if code:
            raise typer.Exit(code)

    app.command("fit")(command(fit_cmd, FIT_ORDER, FIT_OWN))
