"""``roughbrdf models`` and ``roughbrdf eval``."""

from __future__ import annotations

import sys
from typing import Annotated

import typer

from .common import degree_range, handled, parse_params

#: the library's argument names -> this verb's options (errors name the options)
OPTIONS = {"theta_i": "--theta-i", "theta_r": "--theta-r", "phi": "--phi",
           "polarization": "--polarization", "gamma": "--polarization", "quantity": "--quantity"}


def describe_with_aliases(name: str) -> str:
    """``Model.describe()`` of model ``name`` with a line listing its aliases."""
    from .. import models as _models

    m = _models.model(name)
    lines = m.describe().splitlines()
    aliases = tuple(getattr(type(m), "aliases", ()))
    if aliases:
        lines.insert(1, f"  aliases: {', '.join(aliases)}")
    return "\n".join(lines)


def register(app: typer.Typer) -> None:
    @app.command("models")
    def models_cmd() -> None:
        """List the registered models with their aliases, parameters and units."""
        from .. import models as _models

        with handled():
            for name in _models.available():
                typer.echo(describe_with_aliases(name))
                typer.echo("")

    @app.command("eval")
    def eval_cmd(
        model: Annotated[str, typer.Argument(help="model name, e.g. trowbridge-reitz-1975")],
        param: Annotated[list[str] | None, typer.Option(
            "-p", "--param", help="name=value (repeatable)")] = None,
        theta_i: Annotated[str, typer.Option(
            "--theta-i", help="incidence zenith, DEG or START:STOP:STEP")] = "0",
        theta_r: Annotated[str, typer.Option(
            "--theta-r", help="reflection zenith, DEG or START:STOP:STEP")] = "0:90:10",
        phi: Annotated[str, typer.Option(
            "--phi", help="azimuth (0 = forward), DEG or START:STOP:STEP")] = "0",
        polarization: Annotated[str, typer.Option(
            help="unpolarized, s, p or gamma in DEG")] = "unpolarized",
        quantity: Annotated[str, typer.Option(
            help="output: the quantity printed, brdf, brdf_cos (= bridf), bridf or relative "
                 "(to the specular value)")] = "brdf",
    ) -> None:
        """Evaluate a model on a grid of angles (degrees) and print CSV."""
        with handled(OPTIONS):
            _evaluate(model, parse_params(param), theta_i, theta_r, phi, polarization, quantity)


def _evaluate(model: str, params: dict, theta_i: str, theta_r: str, phi: str,
              polarization: str, quantity: str) -> None:
    """The work of ``roughbrdf eval``: the CSV table on stdout."""
    import numpy as np

    from .. import models as _models
    from ..quantity import Quantity

    m = _models.model(model, **params)
    ti = degree_range(theta_i, "--theta-i")
    tr = degree_range(theta_r, "--theta-r")
    ph = degree_range(phi, "--phi")
    try:
        pol: object = np.radians(float(polarization))
    except ValueError:
        pol = polarization
    q = Quantity.parse(quantity, "--quantity")
    TI, TR, PH = (a.reshape(-1) for a in np.meshgrid(ti, tr, ph, indexing="ij"))
    f = m.evaluate(TI, TR, PH, quantity=q, polarization=pol)
    w = sys.stdout
    w.write(f"theta_i_deg,theta_r_deg,phi_deg,{quantity}\n")
    for a, b, c, v in zip(np.degrees(TI), np.degrees(TR), np.degrees(PH), np.atleast_1d(f),
                          strict=True):
        w.write(f"{a:.6g},{b:.6g},{c:.6g},{v:.10g}\n")
