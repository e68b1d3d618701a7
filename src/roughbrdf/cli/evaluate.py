"""``roughbrdf models`` and ``roughbrdf eval``."""

from __future__ import annotations

import sys

import numpy as np
import typer

from .. import models as _models
from .common import degree_range, parse_params


def register(app: typer.Typer) -> None:
    @app.command("models")
    def models_cmd() -> None:
        """List the registered models with their parameters and units."""
        for name in _models.available():
            m = _models.model(name)
            typer.echo(m.describe())
            typer.echo("")

    @app.command("eval")
    def eval_cmd(
        model: str = typer.Argument(..., help="model name, e.g. trowbridge-reitz-1975"),
        param: list[str] = typer.Option(None, "-p", "--param", help="name=value (repeatable)"),
        theta_i: str = typer.Option("0", "--theta-i", help="incidence zenith, DEG or A:B:STEP"),
        theta_r: str = typer.Option("0:90:10", "--theta-r", help="reflection zenith, DEG or A:B:STEP"),
        phi: str = typer.Option("0", "--phi", help="azimuth (0 = forward), DEG or A:B:STEP"),
        polarization: str = typer.Option("unpolarized", help="unpolarized, s, p or gamma in DEG"),
        quantity: str = typer.Option("brdf", help="brdf or bridf"),
    ) -> None:
        """Evaluate a model on a grid of angles (degrees) and print CSV."""
        try:
            m = _models.model(model, **parse_params(param))
            ti = degree_range(theta_i, "--theta-i")
            tr = degree_range(theta_r, "--theta-r")
            ph = degree_range(phi, "--phi")
            try:
                pol: object = np.radians(float(polarization))
            except ValueError:
                pol = polarization
            if quantity not in ("brdf", "bridf"):
                raise ValueError(f"--quantity must be brdf or bridf, got {quantity!r}")
            TI, TR, PH = (a.reshape(-1) for a in np.meshgrid(ti, tr, ph, indexing="ij"))
            f = getattr(m, quantity)(TI, TR, PH, polarization=pol)
        except ValueError as exc:
            typer.echo(f"error: {exc}", err=True)
            raise typer.Exit(2) from exc
        w = sys.stdout
        w.write(f"theta_i_deg,theta_r_deg,phi_deg,{quantity}\n")
        for a, b, c, v in zip(np.degrees(TI), np.degrees(TR), np.degrees(PH), np.atleast_1d(f),
                              strict=True):
            w.write(f"{a:.6g},{b:.6g},{c:.6g},{v:.10g}\n")
