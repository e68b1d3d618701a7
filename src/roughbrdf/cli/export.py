"""``roughbrdf export (MODEL -p ... | --fit DIR) --to TARGET --out PATH``.

Targets: zemax, mitsuba, mitsuba-xml, lighttools, zemax-abg, rgl
(:data:`roughbrdf.export.TARGETS`).

Writes a model, or the fitted models of a saved fit (``fit.json``), for another tool
(:func:`roughbrdf.export.export`, ``docs/export.md``): a Zemax OpticStudio tabular BSDF
(``.bsdf``; a fit gives ``<stem>_<channel>.bsdf`` per channel; grid options ``--incidences``,
``--radial``, ``--azimuth`` in degrees, ``--symmetry``; LightTools takes the first three), a
Mitsuba 3 scene-description dict as
JSON, or a Mitsuba 3 XML ``<bsdf>``. What does not map onto Mitsuba is refused with the reason,
or with ``--fit-closest`` exported as the closest Mitsuba model fitted to it, with the deviation
printed. A model that reflects more than it receives (albedo above 1 + 1e-3 at an incidence of
0, 5, ... 85, 89 deg) is refused unless ``--allow-energy-gain``, which the file records.
Nothing is replaced without ``--force``; every file is written atomically. The folder of
``--fit`` is checked first (:func:`roughbrdf.result_check.check_result_folder`): a write cut
off by a kill is completed or undone, a folder being written or changed since is refused.

``--to rgl`` writes an RGL measured-BSDF tensor file (Mitsuba 3's ``measured``; its options
``--color`` and ``--resolution``) and prints its size and the time taken.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import typer

from .common import EXPORT_OPTIONS, cli_model, degree_range, handled, parse_params
from .options import pick_channel

#: the library's argument names -> this verb's options (errors name the options)
OPTIONS = {**EXPORT_OPTIONS, "allow_energy_gain": "--allow-energy-gain", "color": "--color",
           "resolution": "--resolution"}


def _source(model: str | None, param: list[str] | None, fit_dir: str | None,
            target: str = "zemax") -> Any:
    """The model of MODEL and ``-p``, or the fitted models ``{channel: model}`` of ``--fit``
    (for ``--to zemax-abg`` a per-incidence fit's saved rows as they are)."""
    if (model is None) == (fit_dir is None):
        raise ValueError("give a MODEL (with -p settings) or --fit DIR, not both or neither")
    if fit_dir is not None:
        if param:
            raise ValueError("-p sets a MODEL's parameters; a fit's models are as fitted")
        import json

        from ..fitting.results.fit_json import fitted_models
        from ..result_check import check_result_folder

        path = Path(fit_dir) / "fit.json" if Path(fit_dir).is_dir() else Path(fit_dir)
        # one whole set (a cut-off write recovered) or refused, before fit.json is read
        check_result_folder(path.parent, options=OPTIONS)
        doc = None
        if path.is_file():
            try:
                doc = json.loads(path.read_text(encoding="utf-8"))
            except (ValueError, RecursionError, OSError):  # fitted_models names the problem
                doc = None
            if isinstance(doc, dict) and doc.get("per_incidence"):
                if target != "zemax-abg":
                    raise ValueError(f"{path} is a per-incidence fit (--per-incidence): it "
                                     "exports to --to zemax-abg (its rows)")
                return doc
        return fitted_models(fit_dir)
    return cli_model(str(model), parse_params(param), "MODEL")  # -p angles in degrees


def _zemax_options(incidences: str | None, radial: str | None, azimuth: str | None,
                   symmetry: str | None) -> dict[str, Any]:
    opts: dict[str, Any] = {}
    for key, text, name in (("angles_of_incidence", incidences, "--incidences"),
                            ("radial", radial, "--radial"), ("azimuth", azimuth, "--azimuth")):
        if text is not None:
            opts[key] = degree_range(text, name)
    if symmetry is not None:
        opts["symmetry"] = symmetry
    return opts


def _rgl_options(grid: dict[str, Any], rgb: bool | None, fit_closest: bool,
                 theta_max: float | None, color: str | None,
                 resolution: str | None) -> dict[str, Any]:
    """``--to rgl``'s options: ``--color`` and ``--resolution KEY=N,...``; the other targets'
    options refused, naming them."""
    if grid or rgb is not None or fit_closest or theta_max is not None:
        raise ValueError("--incidences, --radial, --azimuth, --symmetry, --rgb/--no-rgb, "
                         "--fit-closest and --theta-max do not apply to --to rgl (its "
                         "options: --color, --resolution)")
    options: dict[str, Any] = {}
    if color is not None:
        options["color"] = color.strip().lower()
    if resolution is not None:
        sizes: dict[str, Any] = {}
        for part in filter(None, (p.strip() for p in resolution.split(","))):
            key, sep, value = part.partition("=")
            key = key.strip().replace("-", "_")
            if not sep or key not in ("theta_i", "samples", "vndf", "ndf", "theta_i_max"):
                raise ValueError(f"--resolution takes KEY=VALUE,... with keys theta_i, "
                                 f"samples, vndf, ndf, theta_i_max (degrees); got {part!r}")
            try:
                sizes[key] = (math.radians(float(value)) if key == "theta_i_max"
                              else int(value))
            except ValueError:
                raise ValueError(f"--resolution {key}: not a number: {value!r}") from None
        options["resolution"] = sizes
    return options


def run_export(model: str | None, param: list[str] | None, fit_dir: str | None, to: str,
               out: str, *, channel: str | None, force: bool, grid: dict[str, Any],
               rgb: bool | None, fit_closest: bool, theta_max: float | None,
               allow_energy_gain: bool = False, color: str | None = None,
               resolution: str | None = None) -> None:
    """The work of ``roughbrdf export``: checked, written, reported."""
    from ..export import export, target_name

    target = target_name(to)
    if target != "rgl" and (color is not None or resolution is not None):
        raise ValueError("--color and --resolution apply to --to rgl")
    if target == "rgl":
        options = _rgl_options(grid, rgb, fit_closest, theta_max, color, resolution)
    elif target in ("lighttools", "zemax-abg"):
        if rgb is not None or fit_closest or theta_max is not None:
            raise ValueError("--rgb/--no-rgb, --fit-closest and --theta-max apply to the "
                             "Mitsuba targets")
        if target == "zemax-abg" and grid:
            raise ValueError("--incidences, --radial, --azimuth and --symmetry do not apply to "
                             "--to zemax-abg (its rows are the fit's incidences)")
        if target == "lighttools" and "symmetry" in grid:
            raise ValueError("--symmetry is Zemax's; --to lighttools writes the whole circle "
                             "(Asymmetric) and takes --incidences, --radial, --azimuth")
        options = grid
    elif target == "zemax":
        if rgb is not None or fit_closest or theta_max is not None:
            raise ValueError("--rgb/--no-rgb, --fit-closest and --theta-max apply to the "
                             "Mitsuba targets")
        options = grid
    else:
        if grid:
            raise ValueError("--incidences, --radial, --azimuth and --symmetry apply to "
                             "--to zemax")
        options = {"fit": fit_closest}
        if rgb is not None:
            options["rgb"] = None if rgb else False
        if theta_max is not None:
            if not (math.isfinite(theta_max) and 0 < theta_max < 90):
                raise ValueError(f"--theta-max must be in (0, 90) degrees, got {theta_max!r}")
            options["theta_max"] = math.radians(theta_max)
    source = _source(model, param, fit_dir, target)
    chan: Any = channel
    if channel is not None and isinstance(source, dict) and not source.get("per_incidence"):
        labels = list(source)  # a fit's {channel: model}: a label or an index, checked here
        chan = labels[pick_channel([str(k) for k in labels], channel)]
    res = export(source, Path(out), to=target, overwrite=force, channel=chan,
                 allow_energy_gain=allow_energy_gain, **options)
    typer.echo(res.report)
    for path in res.paths:  # one "wrote" line per file: those the report has not given
        if not any(line.startswith(f"wrote {path}") for line in res.report.splitlines()):
            typer.echo(f"wrote {path}")


def register(app: typer.Typer) -> None:
    @app.command("export")
    def export_cmd(
        model: Annotated[str | None, typer.Argument(
            help="model name or spec, e.g. coated(lobes=2) or microfacet+lambertian "
                 "(or --fit DIR)")] = None,
        to: str = typer.Option(..., "--to", help="zemax (.bsdf), mitsuba (dict as JSON), "
                                                 "mitsuba-xml (<bsdf>), lighttools (.bsdf) "
                                                 "zemax-abg (ABg catalog values, .txt) or "
                                                 "rgl (RGL measured BSDF, .bsdf)"),
        out: str = typer.Option(..., "--out", "-o", help="the file (Zemax: one per channel "
                                                          "of a fit, <stem>_<channel>.bsdf)"),
        param: Annotated[list[str] | None, typer.Option(
            "-p", "--param", help="a MODEL's parameter or option, name=value (repeatable; "
                                  "angles such as sigma in degrees)")] = None,
        fit_dir: str = typer.Option(None, "--fit", metavar="DIR",
                                    help="export the fitted models of a saved fit (fit.json)"),
        channel: str = typer.Option(None, "--channel", "-c",
                                    help="one channel of the fit (label or index)"),
        incidences: str = typer.Option(None, "--incidences", metavar="DEG|START:STOP:STEP",
                                       help="Zemax, LightTools: angles of incidence "
                                            "(default 0:80:10)"),
        radial: str = typer.Option(None, "--radial", metavar="START:STOP:STEP",
                                   help="Zemax: scatter angles from the specular direction; "
                                        "LightTools: polar angles from the normal (default: "
                                        "graded, dense near specular, refined until the "
                                        "table integrates to TIS within 0.5 %)"),
        azimuth: str = typer.Option(None, "--azimuth", metavar="START:STOP:STEP",
                                    help="Zemax: azimuths about the specular direction; "
                                         "LightTools: about the normal, source at 90"),
        symmetry: str = typer.Option(None, "--symmetry",
                                     help="Zemax: PlaneSymmetrical (default) or Asymmetrical"),
        rgb: bool = typer.Option(None, "--rgb/--no-rgb",
                                 help="Mitsuba: one RGB BSDF where the channels differ only in "
                                      "colours (default where possible), or one per channel"),
        fit_closest: bool = typer.Option(False, "--fit-closest",
                                         help="Mitsuba: export what does not map as the "
                                              "closest Mitsuba model, fitted (deviation shown)"),
        theta_max: float = typer.Option(None, "--theta-max", metavar="DEG",
                                        help="Mitsuba: largest angle of the deviation grid "
                                             "(default 80)"),
        color: str = typer.Option(None, "--color", metavar="rgb|spectral",
                                  help="RGL: RGB file (Mitsuba's RGB variants) or spectral "
                                       "(default when the channels are wavelengths)"),
        resolution: str = typer.Option(None, "--resolution", metavar="KEY=N,...",
                                       help="RGL: grid sizes theta_i (24), samples (48), vndf "
                                            "(64), ndf (256), theta_i_max (88 deg)"),
        force: bool = typer.Option(False, "--force", help="replace existing files"),
        allow_energy_gain: bool = typer.Option(
            False, "--allow-energy-gain",
            help="export a model that reflects more than it receives (albedo > 1 at some "
                 "incidence; refused by default), recorded in the file"),
    ) -> None:
        """Export a model or a fit to Zemax OpticStudio (.bsdf, ABg values), LightTools (.bsdf),
        Mitsuba 3 (dict, XML) or an RGL measured BSDF (.bsdf)."""
        with handled(OPTIONS):
            run_export(model, param, fit_dir, to, out, channel=channel, force=force,
                       grid=_zemax_options(incidences, radial, azimuth, symmetry), rgb=rgb,
                       fit_closest=fit_closest, theta_max=theta_max,
                       allow_energy_gain=allow_energy_gain, color=color,
                       resolution=resolution)
