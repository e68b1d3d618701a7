"""``roughbrdf fit FILE --model NAME --out DIR``: fit a model to a measurement file.

Writes ``fit.json`` (keys ``model``, ``file``, ``loss``, ``channels``: per channel ``channel``,
``params``, ``stderr``, ``success``, ``metrics`` with ``sigma``, ``rms_log``, ``chi2``, ``aic``,
``bic``, ``n_points``; more keys may follow; ``aperture``: null or the instrument aperture used,
``half_angle_deg``, ``half_angle_rad``, ``points``), ``report.txt`` and one ``fit_<channel>.png``
per channel into DIR. ``--aperture DEG`` compares each sample with the model averaged over a uniform
cone of that half-angle (degrees) about the measured reflection direction (``rb.fit(...,
aperture=radians)``). DIR may exist: files roughbrdf wrote there before are replaced, any other file
of the same name is left alone and the command stops (``--force`` overrides); see
:mod:`roughbrdf._outdir`. ``--free-scale`` fits a closed-form scale ``K`` of the data also for
absolute data (``rb.fit(..., free_scale=True)``), ``--no-plots`` skips the figures (and
Matplotlib).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Annotated, Any

import typer

from .common import parse_params

if TYPE_CHECKING:
    from ..models import Model


def build_model(spec: str, params: dict[str, Any] | None = None) -> Model:
    """A model from ``name`` or ``name1+name2`` and ``-p`` settings (:func:`roughbrdf.model`)."""
    from .. import models as _models

    return _models.model(spec, **(params or {}))


def resolve_names(model: Model, names: list[str]) -> list[str]:
    """Map ``--fix`` names to the model's parameter names (plain names allowed in sums)."""
    from .. import models as _models

    return _models.resolve_names(model, names)


def register(app: typer.Typer) -> None:
    @app.command("fit")
    def fit_cmd(
        file: str = typer.Argument(..., help="measurement file (.astm, .dat/.alta, .csv, "
                                             ".binary)"),
        model: str = typer.Option(..., "--model", "-m",
                                  help="model name or sum, e.g. trowbridge-reitz-1975 or "
                                       "microfacet+lambertian"),
        out: str = typer.Option(..., "--out", "-o", help="output folder"),
        param: Annotated[list[str] | None, typer.Option(
            "-p", "--param", help="starting value or option, name=value (repeatable)")] = None,
        fix: Annotated[list[str] | None, typer.Option(
            "--fix", help="keep this parameter at its value (repeatable)")] = None,
        channel: Annotated[list[str] | None, typer.Option(
            "--channel", "-c", help="channel label or index (repeatable; default: all)")] = None,
        loss: str = typer.Option("relative", help="relative ((x-f)/f, TR75), log or absolute"),
        starts: int = typer.Option(8, help="multistart points per channel"),
        quantity: str = typer.Option(None, help="what the file's values are, if the file does "
                                                "not say: brdf, brdf_cos, bridf or relative"),
        relative_to: str = typer.Option(None, "--relative-to",
                                        help="for relative data: brdf or bridf (default: the "
                                             "file's relative_to, else brdf)"),
        file_format: str = typer.Option(None, "--format", help="override the format chosen "
                                                               "from the extension"),
        nonfinite: str = typer.Option("raise", help="non-finite values: raise or drop"),
        negative: str = typer.Option("keep", help="negative values: keep, drop or clip"),
        seed: int = typer.Option(0, help="seed of the Sobol starts and the subsample"),
        free_scale: bool = typer.Option(None, "--free-scale/--no-free-scale",
                                        help="fit a free scale K of the data in closed form "
                                             "(x -> K x; default: only for relative data)"),
        aperture: float = typer.Option(None, "--aperture", metavar="DEG",
                                       help="instrument aperture: half-angle in degrees of a "
                                            "uniform cone about the reflection direction; the "
                                            "model is averaged over it (default: none)"),
        plots: bool = typer.Option(True, "--plots/--no-plots", help="write PNG plots"),
        force: bool = typer.Option(False, "--force",
                                   help="overwrite files of the same name not written by "
                                        "roughbrdf"),
        quiet: bool = typer.Option(False, "--quiet", "-q", help="no report on the terminal"),
    ) -> None:
        """Fit a model to a measurement file; write fit.json, report.txt and plots into --out."""
        from .. import io as _io
        from ..fitting import fit

        try:
            if aperture is not None and not (math.isfinite(aperture) and 0 <= aperture < 90):
                raise ValueError(f"--aperture must be a half-angle in degrees, 0 <= DEG < 90; "
                                 f"got {aperture!r}")
            m = build_model(model, parse_params(param))
            fixed = resolve_names(m, list(fix or []))
            opts: dict[str, Any] = {}
            if quantity:
                opts["quantity"] = quantity
            meas = _io.read(file, format=file_format, **opts)
            # labels or positions as text; Measurement.channel_index resolves both ("525" also
            # finds "525nm")
            res = fit(m, meas, channel=list(channel) if channel else None, loss=loss, fix=fixed,
                      starts=starts, seed=seed, free_scale=free_scale,
                      nonfinite=nonfinite, negative=negative, relative_to=relative_to,
                      aperture=None if aperture is None else math.radians(aperture),
                      progress=None if not quiet else False)
            written = res.save(out, plots=plots, force=force)
        except (ValueError, FileNotFoundError, FileExistsError, TypeError) as exc:
            typer.echo(f"error: {exc}", err=True)
            raise typer.Exit(2) from exc
        if not quiet:
            typer.echo(res.report())
            typer.echo("")
        typer.echo("wrote " + ", ".join(str(p) for p in written))
        if not res.success:
            raise typer.Exit(1)
