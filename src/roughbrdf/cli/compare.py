"""``roughbrdf compare FILE --models SPEC,SPEC,...``: fit candidate models and compare them.

Prints the comparison table (:func:`roughbrdf.compare`: parameters, sigma, rms-log, AIC/BIC,
rms-log by theta_r band, leave-one-incidence-out score); with ``--out DIR`` also writes
``compare.md`` (the table), ``compare.json`` (every candidate's figures and parameters) and
``compare.png`` as one set (:class:`roughbrdf.output.ResultFolder`: no earlier results
replaced without ``--force``). The fit options are those of ``roughbrdf fit``.
"""

from __future__ import annotations

import inspect
import json
from typing import TYPE_CHECKING, Annotated, Any

import typer

from .common import COMPARE_OPTIONS, check_channels, handled
from .fit import echo_untrusted, energy_warnings, read_input
from .options import ReadInput, channel_labels, command, fit_options

if TYPE_CHECKING:
    from ..fitting.problem.options import FitOptions

#: the library's argument names -> this verb's options (errors name the options)
OPTIONS = COMPARE_OPTIONS

#: the files of ``--out``
FILES = ("compare.md", "compare.json", "compare.png")


def run_compare(file: str, models: str | None, out: str | None, options: FitOptions,
                read: ReadInput, *, force: bool, plots: bool, cv: bool) -> int:
    """The work of ``roughbrdf compare``; returns the exit status (0, or 1 if a candidate's fit
    did not converge, or the best candidate (by the cross-validation score; BIC with
    ``--no-cv``) has a parameter on a search limit or
    gains energy: one ``warning:`` line each)."""
    from ..fitting.choice.compare import compare
    from ..jsonsafe import clean_json
    from ..output import ResultFolder

    meas = read_input(file, read.file_format, read.quantity, read.angles_in)
    # an unknown label listed with the file's channels
    check_channels(meas, channel_labels(options))
    names = [n for n in FILES if plots or not n.endswith(".png")]
    if out is not None:
        ResultFolder(out, overwrite=force).check(names)
    with energy_warnings():
        res = compare(meas, models, cv=cv, options=options)
    typer.echo(res.table())
    if out is not None:
        files: dict[str, Any] = {
            "compare.md": f"# Model comparison: {meas.meta.get('file')}\n\n{res.table()}\n",
            "compare.json": json.dumps(clean_json(res.to_dict()), indent=2,
                                       allow_nan=False) + "\n"}
        if plots:
            def draw(fh: Any) -> None:
                res.plot().savefig(fh, format="png", dpi=110, metadata={"Software": "roughbrdf"})
            files["compare.png"] = draw
        with ResultFolder(out, overwrite=force) as folder:
            for name, content in files.items():
                folder.add(name, content, binary=callable(content))
        typer.echo("wrote " + ", ".join(str(folder.path / n) for n in files))
    # the best candidate's trust decides (the others' problems are in the table)
    best = res.best.result
    trusted = echo_untrusted(best)
    return 0 if all(c.result.success for c in res.candidates) and trusted else 1


#: the parameters of ``roughbrdf compare``, in the order of its help
COMPARE_ORDER = ["file", "models", "out", "cv", "channel", "loss", "starts", "joint", "quantity",
                 "angles_in", "file_format", "aperture", "theta_r_max", "source_exclusion",
                 "keep_extrapolated", "negative", "seed", "plots", "force"]
#: the verb's own parameters (the shared ones: :data:`roughbrdf.cli.options.TABLE`)
COMPARE_OWN: dict[str, tuple[Any, Any]] = {
    "file": (Annotated[str, typer.Argument(help="measurement file")], inspect.Parameter.empty),
    "models": (Annotated[str, typer.Option(
        "--models", metavar="SPEC,SPEC,...",
        help="candidates, e.g. 'tr75, coated(lobes=2)' (default: the --model auto set)")], None),
    "out": (Annotated[str, typer.Option(
        "--out", "-o", help="also write compare.md, compare.json, compare.png here")], None),
    "plots": (Annotated[bool, typer.Option("--plots/--no-plots", help="write compare.png")],
              True),
    "force": (Annotated[bool, typer.Option("--force", help="replace an earlier run's results")],
              False),
}


def register(app: typer.Typer) -> None:
    def compare_cmd(**values: Any) -> None:
        """Fit candidate models to a file and compare them (sigma, rms-log, AIC/BIC, CV)."""
        with handled(OPTIONS):
            # candidates' fits without a bar unless asked (as rb.compare's keywords)
            options = fit_options(values, progress=False)
            code = run_compare(values["file"], values["models"], values["out"], options,
                               ReadInput.of(values), force=values["force"],
                               plots=values["plots"], cv=values["cv"])
        if code:
            raise typer.Exit(code)

    app.command("compare")(command(compare_cmd, COMPARE_ORDER, COMPARE_OWN))
