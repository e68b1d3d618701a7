"""``roughbrdf fit-batch PATH|GLOB ... --model SPEC --out DIR``: fit many files (a catalogue).

One task per file on ``dask.distributed`` (:func:`roughbrdf.catalogue.fit_catalogue`): a
``LocalCluster`` of ``--workers N`` single-threaded worker processes by default, or an existing
cluster by ``--scheduler tcp://HOST:PORT``. Every option of ``roughbrdf fit`` applies to each
file. DIR receives one fit folder per input (``fit.json``, ``report.txt``, the PNGs), and
``catalogue.csv`` / ``catalogue.json`` with one row per file x channel. A folder holding
results stops the command before any work unless ``--force`` (replace) or ``--resume`` (skip
the inputs whose complete results exist for the same input bytes, model and options; redo the
rest). ``--time-limit S`` fails a task that runs longer than S seconds.

Exit status 1 when a file failed (its error is printed, the others are fitted) or a fit did not
converge; 130 on Ctrl-C (finished fit folders are complete, no catalogue file is written).
"""

from __future__ import annotations

from typing import Annotated, Any

import typer

from .common import handled, parse_params
from .fit import (
    OPTIONS,
    AnglesInOption,
    ApertureOption,
    BoundsOption,
    ChannelOption,
    CvOption,
    FixOption,
    FormatOption,
    FreeScaleOption,
    JointOption,
    KeepExtrapolatedOption,
    LossOption,
    ModelsOption,
    NegativeOption,
    NonfiniteOption,
    ParamOption,
    PlotsOption,
    QuantityOption,
    RelativeToOption,
    SeedOption,
    SharedOption,
    SourceExclusionOption,
    StartsOption,
    ThetaRMaxOption,
)

#: the library's argument names -> this verb's options (errors name the options)
BATCH_OPTIONS = {**OPTIONS, "n_workers": "--workers", "scheduler": "--scheduler",
                 "time_limit": "--time-limit", "inputs": "PATH", "resume": "--resume"}


def read_options(quantity: str | None, angles_in: str | None,
                 file_format: str | None) -> dict[str, Any]:
    """``--quantity``, ``--angles-in``, ``--format`` -> :func:`roughbrdf.read` options.

    Examples
    --------
    >>> read_options("bridf", "deg", None)
    {'quantity': 'bridf', 'angles': 'deg'}
    """
    from ..quantity import Quantity
    from .fit import angle_unit

    opts: dict[str, Any] = {}
    if quantity:
        opts["quantity"] = Quantity.parse(quantity, "--quantity").value
    unit = angle_unit(angles_in)
    if unit is not None:
        opts["angles"] = unit
    if file_format:
        from ..io import FORMATS, format_for

        try:  # every worker would refuse the files otherwise, one failure each
            format_for("input", file_format)
        except ValueError:
            raise ValueError(f"--format: unknown value {file_format!r} (choose from "
                             f"{', '.join(FORMATS)})") from None
        opts["format"] = file_format
    return opts


def check_search(starts: int, loss: str, seed: int, relative_to: str | None = None) -> None:
    """``--starts``, ``--loss``, ``--seed`` and ``--relative-to`` in the terms of the command
    line, before any cluster starts (the library's own check,
    :func:`roughbrdf.catalogue.check_options`, words them for Python and runs next, for every
    other option).

    Examples
    --------
    >>> check_search(0, "relative", 0)
    Traceback (most recent call last):
    ...
    ValueError: --starts must be >= 1 (got 0)
    """
    from ..quantity import LOSSES, Quantity

    if starts < 1:
        raise ValueError(f"--starts must be >= 1 (got {starts})")
    if loss not in LOSSES:
        raise ValueError(f"--loss: unknown value {loss!r} (choose from {', '.join(LOSSES)})")
    if seed < 0:  # numpy's generators take no negative seed
        raise ValueError(f"--seed must be >= 0 (got {seed})")
    if relative_to is not None:
        try:  # what a relative file's values are proportional to (fitting.data.Comparison)
            Quantity.RELATIVE.compared_with(relative_to)
        except ValueError:
            raise ValueError(f"--relative-to: unknown value {relative_to!r} (choose from brdf, "
                             f"bridf)") from None


def run_batch(paths: list[str], model: str, out: str, *, param: list[str] | None,
              fix: list[str] | None, bounds: list[str] | None, models: str | None, cv: bool,
              workers: int | None, scheduler: str | None, resume: bool, force: bool,
              plots: bool, quiet: bool, time_limit: float | None, aperture: float | None,
              theta_r_max: float | None, source_exclusion: float | None,
              read: dict[str, Any], **fit_options: Any) -> int:
    """The work of ``roughbrdf fit-batch``; the exit status (0, or 1 if a file failed or a fit
    did not converge). Options are checked before any cluster starts."""
    from ..catalogue import fit_catalogue
    from .fit import (
        auto_options,
        build_model,
        check_aperture,
        fit_domain,
        parse_bounds,
        resolve_names,
        start_within,
    )

    if workers is not None and scheduler is not None:
        raise ValueError("--workers sets the size of a local cluster; with --scheduler the "
                         "cluster's own workers run the fits: give one of them")
    if workers is not None and workers < 1:
        raise ValueError(f"--workers must be >= 1 (got {workers})")
    if time_limit is not None and not time_limit > 0:  # also NaN
        raise ValueError(f"--time-limit must be a number of seconds > 0 (got {time_limit:g})")
    check_search(fit_options["starts"], fit_options["loss"], fit_options["seed"],
                 fit_options["relative_to"])
    t_max, excl = fit_domain(theta_r_max, source_exclusion)
    auto = model.strip().lower() == "auto"
    auto_options(models, param, fix, bounds, auto)
    m: Any = "auto"
    if not auto:
        given = parse_params(param)
        m = build_model(model, given)
        fit_options["fix"] = resolve_names(m, list(fix or []))
        ranges = parse_bounds(m, bounds)
        fit_options["bounds"] = ranges or None
        m = start_within(m, ranges, given)
    res = fit_catalogue(paths, m, out, scheduler=scheduler, n_workers=workers, resume=resume,
                        overwrite=force, plots=plots, read_options=read, candidates=models,
                        cv=cv, time_limit=time_limit, progress=None if not quiet else False,
                        aperture=check_aperture(aperture), theta_r_max=t_max,
                        source_exclusion=excl, **fit_options)
    files = {r["file"] for r in res.rows}
    for r in res.failed:
        typer.echo(f"failed: {r['file']}: {r['error']}", err=True)
    bad = {r["file"] for r in res.rows if r["status"] == "not converged"}
    for f in sorted(bad):
        typer.echo(f"not converged: {f}", err=True)
    kept = sum(r["status"] == "skipped (resume)" for r in res.rows)
    typer.echo(f"{len(files)} files, {len(res.rows)} rows ({len(res.failed)} failed, "
               f"{kept} kept from an earlier run); wrote "
               + ", ".join(str(p) for p in res.written))
    return 0 if res.success else 1


def register(app: typer.Typer) -> None:
    @app.command("fit-batch")
    def fit_batch_cmd(
        paths: Annotated[list[str], typer.Argument(
            metavar="PATH...",
            help="measurement files, folders or glob patterns (quoted: 'data/*.astm')")],
        model: str = typer.Option(..., "--model", "-m", help="model name, spec or sum (as for "
                                                             "roughbrdf fit); auto: lowest BIC"),
        out: str = typer.Option(..., "--out", "-o", help="catalogue folder"),
        workers: int = typer.Option(None, "--workers", help="worker processes of the local "
                                                            "cluster (default: the CPUs)"),
        scheduler: str = typer.Option(None, "--scheduler", metavar="tcp://HOST:PORT",
                                      help="run on this dask scheduler's workers instead"),
        resume: bool = typer.Option(False, "--resume", help="skip inputs whose complete results "
                                    "exist for the same input, model and options"),
        time_limit: float = typer.Option(None, "--time-limit", metavar="S",
                                         help="seconds a file's task may run (default: none)"),
        models: ModelsOption = None,
        cv: CvOption = True,
        joint: JointOption = False,
        shared: SharedOption = None,
        keep_extrapolated: KeepExtrapolatedOption = False,
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
        force: bool = typer.Option(False, "--force", help="replace earlier results in --out"),
        quiet: bool = typer.Option(False, "--quiet", "-q", help="no progress bar"),
    ) -> None:
        """Fit a model to many files on dask; one fit folder each, catalogue.csv/.json."""
        with handled(BATCH_OPTIONS):
            code = run_batch(
                paths, model, out, param=param, fix=fix, bounds=bounds, models=models, cv=cv,
                workers=workers, scheduler=scheduler, resume=resume, force=force, plots=plots,
                quiet=quiet, time_limit=time_limit, aperture=aperture, theta_r_max=theta_r_max,
                source_exclusion=source_exclusion,
                read=read_options(quantity, angles_in, file_format), channel=channel,
                loss=loss, starts=starts, seed=seed, free_scale=free_scale,
                nonfinite=nonfinite, negative=negative, relative_to=relative_to, joint=joint,
                shared=shared or None, extrapolated="keep" if keep_extrapolated else "drop")
        if code:
            raise typer.Exit(code)
