"""``roughbrdf models`` and ``roughbrdf eval``."""

from __future__ import annotations

import sys
from typing import Annotated

import typer

from .common import (
    EVAL_OPTIONS,
    MAX_RANGE_POINTS,
    cli_model,
    cli_parameter_lines,
    degree_range,
    handled,
    parse_params,
)

#: the library's argument names -> this verb's options (errors name the options)
OPTIONS = EVAL_OPTIONS

#: the largest grid ``roughbrdf eval`` prints (theta_i x theta_r x phi values): each is a
#: line of CSV
MAX_EVAL_POINTS = 10 * MAX_RANGE_POINTS


def describe_with_aliases(name: str) -> str:
    """``Model.describe()`` of model ``name`` with a line listing its aliases."""
    from .. import models as _models

    m = _models.model(name)
    lines = [m.describe().splitlines()[0]]
    aliases = tuple(getattr(type(m), "aliases", ()))
    if aliases:
        lines.append(f"  aliases: {', '.join(aliases)}")
    lines += [f"  option {k} = {v!r}" for k, v in m.options.items()]
    return "\n".join(lines + cli_parameter_lines(m))  # angles in degrees, as -p takes them


def polarization_value(text: str) -> object:
    """``--polarization`` -> the library's value: a name, or gamma (degrees) in radians.

    Examples
    --------
    >>> polarization_value("S"), round(float(polarization_value("90")), 4)
    ('s', 1.5708)
    """
    import math

    from ..fresnel import polarization_angle

    name = text.strip().lower()
    try:
        gamma = float(name)
    except ValueError:
        pass
    else:
        if not math.isfinite(gamma):  # no direction of the field
            raise ValueError(f"--polarization {text!r}: the angle gamma must be a finite "
                             f"number of degrees")
        return math.radians(gamma)
    try:
        polarization_angle(name)  # the library's names (also natural, perpendicular, te ...)
    except ValueError:
        raise ValueError(f"--polarization {text!r}: expected unpolarized, s, p or an angle "
                         f"gamma in degrees from the plane of incidence") from None
    return name


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
            "-p", "--param",
            help="name=value (repeatable; angles such as sigma in degrees)")] = None,
        theta_i: Annotated[str, typer.Option(
            "--theta-i", help="incidence zenith, DEG or START:STOP:STEP")] = "0",
        theta_r: Annotated[str, typer.Option(
            "--theta-r", help="reflection zenith, DEG or START:STOP:STEP")] = "0:90:10",
        phi: Annotated[str, typer.Option(
            "--phi", help="azimuth (0 = forward), DEG or START:STOP:STEP")] = "0",
        polarization: Annotated[str, typer.Option(
            help="unpolarized, s, p or the angle gamma of the field from the plane of "
                 "incidence in DEG")] = "unpolarized",
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

    from ..quantity import Quantity

    m = cli_model(model, params, "MODEL")  # -p angles (Oren-Nayar sigma) in degrees
    ti = degree_range(theta_i, "--theta-i")
    tr = degree_range(theta_r, "--theta-r")
    ph = degree_range(phi, "--phi")
    if ti.size * tr.size * ph.size > MAX_EVAL_POINTS:  # one CSV line each
        raise ValueError(f"--theta-i x --theta-r x --phi: {ti.size} x {tr.size} x {ph.size} "
                         f"= {ti.size * tr.size * ph.size} points, more than the limit of "
                         f"{MAX_EVAL_POINTS}; use larger steps")
    pol = polarization_value(polarization)
    q = Quantity.parse(quantity, "--quantity")
    TI, TR, PH = (a.reshape(-1) for a in np.meshgrid(ti, tr, ph, indexing="ij"))
    f = m.evaluate(TI, TR, PH, quantity=q, polarization=pol)
    w = sys.stdout
    w.write(f"theta_i_deg,theta_r_deg,phi_deg,{quantity}\n")
    for a, b, c, v in zip(np.degrees(TI), np.degrees(TR), np.degrees(PH), np.atleast_1d(f),
                          strict=True):
        w.write(f"{a:.6g},{b:.6g},{c:.6g},{v:.15g}\n")
