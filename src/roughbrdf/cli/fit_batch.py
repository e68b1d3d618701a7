"""``roughbrdf fit-batch PATH|GLOB ... --model SPEC --out DIR``: fit many files (a catalogue).

One task per file on ``dask.distributed`` (:func:`roughbrdf.catalogue.fit_catalogue`): a
``LocalCluster`` of ``--workers N`` single-threaded worker processes by default, or an existing
cluster by ``--scheduler tcp://HOST:PORT``. Every option of ``roughbrdf fit`` applies to each
file. DIR receives one fit folder per input (``fit.json``, ``report.txt``, the PNGs), and
``catalogue.csv`` / ``catalogue.json`` with one row per file x channel. A folder holding
results stops the command before any work unless ``--force`` (replace) or ``--resume`` (skip
the inputs whose complete results exist for the same input bytes, model and options; redo the
rest). ``--time-limit S`` fails a task that runs longer than S seconds.

Exit status 0 when every row is ``ok``; 1 when a file failed (its error is printed, the others
are fitted) or a fit is not to be trusted without a look: it did not converge, a parameter
ended on a search limit or the model gains energy (row statuses ``not converged``,
``at-search-limit``, ``gains-energy``). A row ``--resume`` kept (``skipped (resume)``) counts as
the status it had when it was fitted (``earlier_status``). 130 on Ctrl-C (finished fit folders
are complete, no catalogue file is written).
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Annotated, Any

import typer

from .common import handled
from .fit import OPTIONS, resolve_model
from .options import ModelInput, check_format, check_search, command, fit_options

if TYPE_CHECKING:
    from ..fitting.problem.options import FitOptions

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
        check_format(file_format)  # every worker would refuse the files, one failure each
        opts["format"] = file_format
    return opts


@dataclass(frozen=True)
class BatchRun:
    """How ``fit-batch`` runs: the cluster (``--workers``, ``--scheduler``), ``--resume``,
    ``--force``, ``--plots``, ``--quiet``, ``--time-limit``, ``--cv`` and the reading options."""

    workers: int | None = None
    scheduler: str | None = None
    resume: bool = False
    force: bool = False
    plots: bool = True
    quiet: bool = False
    time_limit: float | None = None
    cv: bool = True
    read: dict[str, Any] = field(default_factory=dict)

    def check(self) -> None:
        """The cluster and the limit, in CLI terms, before any cluster starts."""
        if self.workers is not None and self.scheduler is not None:
            raise ValueError("--workers sets the size of a local cluster; with --scheduler the "
                             "cluster's own workers run the fits: give one of them")
        if self.workers is not None and self.workers < 1:
            raise ValueError(f"--workers must be >= 1 (got {self.workers})")
        if self.time_limit is not None and not self.time_limit > 0:  # also NaN
            raise ValueError(f"--time-limit must be a number of seconds > 0 (got "
                             f"{self.time_limit:g})")


def run_batch(paths: list[str], out: str, given: ModelInput, options: FitOptions,
              run: BatchRun) -> int:
    """The work of ``roughbrdf fit-batch``; the exit status (0, or 1 if a file failed or a row's
    status is not ``ok``: module notes). Options are checked before any cluster starts."""
    from ..catalogue import fit_catalogue

    m, options = resolve_model(given, options)
    res = fit_catalogue(paths, m, out, scheduler=run.scheduler, n_workers=run.workers,
                        resume=run.resume, overwrite=run.force, plots=run.plots,
                        read_options=run.read, candidates=given.models, cv=run.cv,
                        time_limit=run.time_limit, progress=None if not run.quiet else False,
                        options=options)
    from ..catalogue.rows import outcome, shown_name

    files = {r["file"] for r in res.rows}
    for r in res.failed:  # one line each, whatever the name holds (a newline, an escape)
        typer.echo(f"failed: {shown_name(r['file'])}: {r['error']}", err=True)
    bad = {r["file"] for r in res.rows if outcome(r) == "not converged"}
    for f in sorted(bad):
        typer.echo(f"not converged: {shown_name(f)}", err=True)
    kept = sum(r["status"] == "skipped (resume)" for r in res.rows)
    typer.echo(f"{len(files)} files, {len(res.rows)} rows ({len(res.failed)} failed, "
               f"{kept} kept from an earlier run); wrote "
               + ", ".join(str(p) for p in res.written))
    return 0 if res.success else 1


#: the parameters of ``roughbrdf fit-batch``, in the order of its help
BATCH_ORDER = ["paths", "model", "out", "workers", "scheduler", "resume", "time_limit",
               "models", "cv", "joint", "shared", "keep_extrapolated", "param", "fix",
               "bounds", "channel", "loss", "starts", "quantity", "angles_in", "relative_to",
               "file_format", "nonfinite", "negative", "seed", "free_scale", "aperture",
               "theta_r_max", "source_exclusion", "intervals", "plots", "force", "quiet"]
#: the verb's own parameters (the shared ones: :data:`roughbrdf.cli.options.TABLE`)
BATCH_OWN: dict[str, tuple[Any, Any]] = {
    "paths": (Annotated[list[str], typer.Argument(
        metavar="PATH...",
        help="measurement files, folders or glob patterns (quoted: 'data/*.astm')")],
        inspect.Parameter.empty),
    "model": (Annotated[str, typer.Option(
        "--model", "-m", help="model name, spec or sum (as for roughbrdf fit); auto: lowest "
                              "BIC")], inspect.Parameter.empty),
    "out": (Annotated[str, typer.Option("--out", "-o", help="catalogue folder")],
            inspect.Parameter.empty),
    "workers": (Annotated[int, typer.Option(
        "--workers", help="worker processes of the local cluster (default: the CPUs)")], None),
    "scheduler": (Annotated[str, typer.Option(
        "--scheduler", metavar="tcp://HOST:PORT",
        help="run on this dask scheduler's workers instead")], None),
    "resume": (Annotated[bool, typer.Option(
        "--resume", help="skip inputs whose complete results exist for the same input, model "
                         "and options")], False),
    "time_limit": (Annotated[float, typer.Option(
        "--time-limit", metavar="S", help="seconds a file's task may run (default: none)")],
        None),
    "force": (Annotated[bool, typer.Option("--force", help="replace earlier results in --out")],
              False),
    "quiet": (Annotated[bool, typer.Option("--quiet", "-q", help="no progress bar")], False),
}


def register(app: typer.Typer) -> None:
    def fit_batch_cmd(**values: Any) -> None:
        """Fit a model to many files on dask; one fit folder each, catalogue.csv/.json."""
        with handled(BATCH_OPTIONS):
            run = BatchRun(values["workers"], values["scheduler"], values["resume"],
                           values["force"], values["plots"], values["quiet"],
                           values["time_limit"], values["cv"],
                           read_options(values["quantity"], values["angles_in"],
                                        values["file_format"]))
            run.check()
            check_search(values["starts"], values["loss"], values["seed"],
                         values["relative_to"])  # before the model is built
            code = run_batch(values["paths"], values["out"], ModelInput.of(values),
                             fit_options(values), run)
        if code:
            raise typer.Exit(code)

    app.command("fit-batch")(command(fit_batch_cmd, BATCH_ORDER, BATCH_OWN))
