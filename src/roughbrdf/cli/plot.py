"""``roughbrdf plot``: plot a model (in-plane, polar or hemisphere) or a fit's comparison."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Annotated, Any

import typer

from .common import degree_range, parse_params

KINDS = ("in-plane", "polar", "hemisphere")


def _fail(msg: str) -> typer.Exit:
    typer.echo(f"error: {msg}", err=True)
    return typer.Exit(2)


def _check_out(path: Path, force: bool) -> None:
    if path.suffix.lower() != ".png":
        raise ValueError(f"--out must be a .png file, got {str(path)!r}")
    if path.exists() and not force:
        raise FileExistsError(f"{path} exists; use --force to overwrite")


def _model_figure(model_name: str, params: dict[str, Any], kind: str, theta_i: str,
                  elevation: float, quantity: str, log: bool | None):
    import numpy as np

    from .. import models as _models
    from .. import plot as rbplot

    m = _models.model(model_name, **params)
    ti = degree_range(theta_i, "--theta-i")
    if kind == "in-plane":
        if np.any(ti >= 0.5 * math.pi):
            raise ValueError("--theta-i must be below 90 degrees")
        return rbplot.plot_in_plane(m, ti, quantity=quantity, log=bool(log))
    if ti.size != 1:
        raise ValueError(f"--kind {kind} takes one --theta-i, got {ti.size}")
    if kind == "polar":
        return rbplot.plot_polar(m, float(ti[0]), math.radians(elevation), label=m.name)
    return rbplot.plot_hemisphere(m, float(ti[0]), quantity=quantity,
                                  log=True if log is None else log)


def _read_fit(fit_dir: Path) -> tuple[dict[str, Any], Path]:
    path = fit_dir / "fit.json" if fit_dir.is_dir() else fit_dir
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no fit.json (run `roughbrdf fit FILE --out DIR` first)")
    try:
        fit = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not valid JSON ({exc})") from exc
    for key in ("model", "file", "channels"):
        if key not in fit:
            raise ValueError(f"{path}: missing key {key!r}")
    return fit, path.parent


def _fit_model(fit: dict[str, Any], chan: dict[str, Any]):
    from .. import models as _models

    spec = chan.get("model_spec")
    if isinstance(spec, dict):
        return _models.model(spec)
    name = fit["model"]
    if isinstance(name, dict):
        return _models.model(name, **(chan.get("params") or {}))
    return _models.model(str(name), **(chan.get("params") or {}))


def _fit_aperture(fit: dict[str, Any]):
    """The instrument aperture the fit used (``fit.json`` ``aperture``), or None."""
    from ..instrument import Aperture

    ap = fit.get("aperture")
    if not isinstance(ap, dict):
        return None
    return Aperture.parse(ap["half_angle_rad"], ap.get("points", 19))


def _fit_measurement(fit: dict[str, Any], base: Path):
    from dataclasses import replace

    from .. import io as rbio

    file = Path(fit["file"])
    candidates = [file] if file.is_absolute() else [file, base / file]
    path = next((c for c in candidates if c.exists()), None)
    if path is None:
        raise FileNotFoundError(f"measurement file {fit['file']!r} of the fit not found "
                                f"(looked in {', '.join(str(c) for c in candidates)})")
    try:
        meas = rbio.read(path)
    except ValueError:
        q = fit.get("quantity")
        if not q:
            raise
        meas = rbio.read(path, quantity=q)  # e.g. ALTA files without #PARAM_OUT
    if meas.quantity == "relative" and fit.get("relative_to"):
        meas = replace(meas, meta={**meas.meta, "relative_to": fit["relative_to"]})
    return meas


def _safe(label: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "_", str(label)) or "channel"


def _fit_figures(fit_dir: Path, out: Path | None, channel: str | None, force: bool
                 ) -> list[Path]:
    from matplotlib.figure import Figure

    from .. import plot as rbplot

    fit, base = _read_fit(fit_dir)
    meas = _fit_measurement(fit, base)
    chans = fit["channels"]
    if channel is not None:
        chans = [c for i, c in enumerate(chans) if str(c.get("channel")) == channel
                 or str(i) == channel]
        if not chans:
            labels = [str(c.get("channel")) for c in fit["channels"]]
            raise ValueError(f"no channel {channel!r} in the fit; channels: {labels}")
    if out is not None and len(chans) > 1:
        raise ValueError("--out names one file but the fit has several channels; pick one with "
                         "--channel or omit --out (files go into the fit directory)")
    targets = []
    for c in chans:
        target = out if out is not None else base / f"comparison_{_safe(c.get('channel'))}.png"
        _check_out(target, force)
        targets.append(target)
    aperture = _fit_aperture(fit)
    written = []
    for c, target in zip(chans, targets, strict=True):
        model = _fit_model(fit, c)
        label = c.get("channel")
        ch = meas.channel_index(label) if str(label) in meas.channels else 0
        fig = Figure(figsize=(13, 5.2), layout="constrained")
        ax1 = fig.add_subplot(1, 2, 1)
        ax2 = fig.add_subplot(1, 2, 2)
        rbplot.plot_comparison(model, meas, channel=ch, ax=ax1, aperture=aperture)
        rbplot.plot_residual_map(model, meas, channel=ch, ax=ax2, aperture=aperture)
        fig.suptitle(f"fit {fit_dir}: {fit['model']} to {Path(str(fit['file'])).name} "
                     f"[{label}], loss {fit.get('loss', '?')}", fontsize="medium")
        fig.savefig(target, dpi=100)
        written.append(target)
    return written


def register(app: typer.Typer) -> None:
    @app.command("plot")
    def plot_cmd(
        model: Annotated[str | None, typer.Argument(
            help="model name, e.g. trowbridge-reitz-1975")] = None,
        param: Annotated[list[str] | None, typer.Option(
            "-p", "--param", help="name=value (repeatable)")] = None,
        kind: Annotated[str, typer.Option(help="in-plane, polar or hemisphere")] = "in-plane",
        theta_i: Annotated[str, typer.Option(
            "--theta-i", help="incidence, DEG or START:STOP:STEP (one value for "
                              "polar/hemisphere)")] = "0:60:20",
        elevation: Annotated[float, typer.Option(
            help="polar: reflection elevation (TR75 theta), DEG")] = 45.0,
        quantity: Annotated[str, typer.Option(help="brdf, bridf or relative")] = "brdf",
        log: Annotated[bool | None, typer.Option(
            "--log/--linear", help="logarithmic value axis/colours")] = None,
        fit: Annotated[Path | None, typer.Option(
            help="a fit directory (with fit.json): plot data vs model and the residual "
                 "map")] = None,
        channel: Annotated[str | None, typer.Option(help="with --fit: one channel")] = None,
        out: Annotated[Path | None, typer.Option("--out", "-o", help="output PNG file")] = None,
        force: Annotated[bool, typer.Option(help="overwrite an existing output file")] = False,
    ) -> None:
        """Plot a model (MODEL -p name=value ...) or a fit (--fit DIR) to a PNG file.

        Angles are in degrees. Examples:

          roughbrdf plot trowbridge-reitz-1975 -p e=0.3 -p n=1.5 -p k=0 -p rho_L=0.1
          --theta-i 0:60:30 --log --out tr.png

          roughbrdf plot --fit fitdir          (writes fitdir/comparison_<channel>.png)
        """
        import matplotlib

        matplotlib.use("Agg")
        try:
            if fit is not None:
                if model is not None:
                    raise ValueError("give either MODEL or --fit DIR, not both")
                for p in _fit_figures(fit, out, channel, force):
                    typer.echo(f"wrote {p}")
                return
            if model is None:
                raise ValueError("give a MODEL name (see `roughbrdf models`) or --fit DIR")
            if out is None:
                raise ValueError("--out FILE.png is required")
            if kind not in KINDS:
                raise ValueError(f"--kind must be one of {', '.join(KINDS)}, got {kind!r}")
            if quantity not in ("brdf", "bridf", "relative"):
                raise ValueError(f"--quantity must be brdf, bridf or relative, got {quantity!r}")
            _check_out(out, force)
            fig, _ax = _model_figure(model, parse_params(param), kind, theta_i, elevation,
                                     quantity, log)
            fig.savefig(out, dpi=100)
            typer.echo(f"wrote {out}")
        except (ValueError, FileExistsError, FileNotFoundError) as exc:
            raise _fail(str(exc)) from exc
