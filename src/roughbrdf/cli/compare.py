"""``roughbrdf compare FILE --models SPEC,SPEC,...``: fit candidate models and compare them.

Prints the comparison table (:func:`roughbrdf.compare`: parameters, sigma, rms-log, AIC/BIC,
rms-log by theta_r band, leave-one-incidence-out score); with ``--out DIR`` also writes
``compare.md`` (the table), ``compare.json`` (every candidate's figures and parameters) and
``compare.png`` as one set (:class:`roughbrdf.output.ResultFolder`: no earlier results
replaced without ``--force``). The fit options are those of ``roughbrdf fit``.
"""

from __future__ import annotations

import json
from typing import Any

import typer

from .common import COMPARE_OPTIONS, check_channels, handled
from .fit import (
    AnglesInOption,
    ApertureOption,
    ChannelOption,
    CvOption,
    FormatOption,
    JointOption,
    KeepExtrapolatedOption,
    LossOption,
    NegativeOption,
    QuantityOption,
    SeedOption,
    SourceExclusionOption,
    StartsOption,
    ThetaRMaxOption,
    check_aperture,
    fit_domain,
    read_input,
)

#: the library's argument names -> this verb's options (errors name the options)
OPTIONS = COMPARE_OPTIONS

#: the files of ``--out``
FILES = ("compare.md", "compare.json", "compare.png")


def run_compare(file: str, models: str | None, out: str | None, *, force: bool,
                plots: bool, cv: bool, channel: list[str] | None, angles_in: str | None,
                quantity: str | None, file_format: str | None, aperture: float | None,
                theta_r_max: float | None, source_exclusion: float | None,
                **fit_options: Any) -> int:
    """The work of ``roughbrdf compare``; returns the exit status (0, or 1 if a candidate's fit
    did not converge)."""
    from ..fitting.compare import compare
    from ..fitting.result import clean_json
    from ..output import ResultFolder

    ap = check_aperture(aperture)
    t_max, excl = fit_domain(theta_r_max, source_exclusion)
    meas = read_input(file, file_format, quantity, angles_in)
    check_channels(meas, channel)  # an unknown label listed with the file's channels
    names = [n for n in FILES if plots or not n.endswith(".png")]
    if out is not None:
        ResultFolder(out, overwrite=force).check(names)
    res = compare(meas, models, cv=cv, channel=list(channel) if channel else None,
                  aperture=ap, theta_r_max=t_max, source_exclusion=excl, **fit_options)
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
    return 0 if all(c.result.success for c in res.candidates) else 1


def register(app: typer.Typer) -> None:
    @app.command("compare")
    def compare_cmd(
        file: str = typer.Argument(..., help="measurement file"),
        models: str = typer.Option(None, "--models", metavar="SPEC,SPEC,...",
                                   help="candidates, e.g. 'tr75, coated(lobes=2)' (default: "
                                        "the --model auto set)"),
        out: str = typer.Option(None, "--out", "-o",
                                help="also write compare.md, compare.json, compare.png here"),
        cv: CvOption = True,
        channel: ChannelOption = None,
        loss: LossOption = "relative",
        starts: StartsOption = 8,
        joint: JointOption = False,
        quantity: QuantityOption = None,
        angles_in: AnglesInOption = None,
        file_format: FormatOption = None,
        aperture: ApertureOption = None,
        theta_r_max: ThetaRMaxOption = None,
        source_exclusion: SourceExclusionOption = None,
        keep_extrapolated: KeepExtrapolatedOption = False,
        negative: NegativeOption = "keep",
        seed: SeedOption = 0,
        plots: bool = typer.Option(True, "--plots/--no-plots", help="write compare.png"),
        force: bool = typer.Option(False, "--force", help="replace an earlier run's results"),
    ) -> None:
        """Fit candidate models to a file and compare them (sigma, rms-log, AIC/BIC, CV)."""
        with handled(OPTIONS):
            code = run_compare(file, models, out, force=force, plots=plots, cv=cv,
                               channel=channel, angles_in=angles_in, quantity=quantity,
                               file_format=file_format, aperture=aperture,
                               theta_r_max=theta_r_max, source_exclusion=source_exclusion,
                               loss=loss, starts=starts, joint=joint, negative=negative,
                               seed=seed,
                               extrapolated="keep" if keep_extrapolated else "drop")
        if code:
            raise typer.Exit(code)
