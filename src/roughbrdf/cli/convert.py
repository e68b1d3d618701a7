"""``roughbrdf convert IN OUT``: read any supported measurement file and write another format."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

#: the quantities a measurement can hold, for the help text (the same as
#: :data:`roughbrdf.measurement.QUANTITIES`, written out so that ``--help`` imports no NumPy/Numba;
#: the command itself checks against the library's tuple)
HELP_QUANTITIES = ("brdf", "brdf_cos", "bridf", "relative")


def register(app: typer.Typer) -> None:
    @app.command("convert")
    def convert_cmd(
        src: Annotated[Path, typer.Argument(metavar="IN", help="input measurement file")],
        dst: Annotated[Path, typer.Argument(metavar="OUT", help="output file (not overwritten "
                                            "unless --force)")],
        from_: str = typer.Option(None, "--from", help="input format (astm, alta, merl, csv); "
                                  "default from the extension"),
        to: str = typer.Option(None, "--to", help="output format; default from the extension"),
        quantity: str = typer.Option(None, "--quantity", help="what the input values hold when "
                                     f"the file does not say: {', '.join(HELP_QUANTITIES)}"),
        as_quantity: str = typer.Option(None, "--as", help="convert the values to this quantity "
                                        "before writing (brdf <-> brdf_cos)"),
        angles_in: str = typer.Option(None, "--angles-in", help="angle unit of the input "
                                      "(deg or rad; ASTM and CSV), overriding the file"),
        angles_out: str = typer.Option(None, "--angles-out", help="angle unit written (deg or "
                                       "rad; CSV default deg, ASTM default rad)"),
        stride: int = typer.Option(None, "--stride", help="MERL input: keep every N-th cell "
                                   "along each axis"),
        force: bool = typer.Option(False, "--force", help="overwrite OUT if it exists"),
    ) -> None:
        """Convert a measurement between formats (astm, alta, merl, csv).

        Non-finite and negative values are carried over and reported, never dropped.
        """
        from .. import io as _io
        from ..measurement import QUANTITIES

        try:
            if quantity is not None and quantity not in QUANTITIES:
                raise ValueError(f"--quantity must be one of {', '.join(QUANTITIES)}, "
                                 f"got {quantity!r}")
            if not src.exists():
                raise ValueError(f"{src}: no such file")
            if dst.exists() and not force:
                raise ValueError(f"{dst} exists; pass --force to overwrite it")
            if dst.resolve() == src.resolve():
                raise ValueError("IN and OUT are the same file")
            fin = _io.format_for(src, from_)
            fout = _io.format_for(dst, to)
            ropts: dict = {}
            if quantity is not None:
                if fin == "merl":
                    raise ValueError("--quantity does not apply to MERL input (always BRDF)")
                ropts["quantity"] = quantity
            if angles_in is not None:
                if fin not in ("astm", "csv"):
                    raise ValueError("--angles-in applies to ASTM and CSV input only")
                ropts["angles"] = angles_in
            if stride is not None:
                if fin != "merl":
                    raise ValueError("--stride applies to MERL input only")
                ropts["stride"] = stride
            wopts: dict = {}
            if angles_out is not None:
                if fout not in ("astm", "csv"):
                    raise ValueError("--angles-out applies to ASTM and CSV output only")
                wopts["angles"] = angles_out
            m = _io.read(src, format=fin, **ropts)
            if as_quantity is not None:
                m = m.as_quantity(as_quantity)
            _io.write(m, dst, format=fout, **wopts)
        except (ValueError, FileNotFoundError) as exc:
            typer.echo(f"error: {exc}", err=True)
            raise typer.Exit(2) from exc
        typer.echo(f"wrote {dst} ({fout}): {m.n_samples} samples x {m.n_channels} channels "
                   f"{m.channels}, quantity {m.quantity}")
        for ch, r in m.validate().items():
            if r["nonfinite"] or r["negative"]:
                typer.echo(f"  channel {ch}: {r['nonfinite']} non-finite and {r['negative']} "
                           "negative values kept as they are")
        if m.meta.get("merl_below_horizon") or m.meta.get("merl_invalid"):
            typer.echo(f"  MERL cells left out on reading: {m.meta.get('merl_below_horizon', 0)} "
                       f"below the horizon, {m.meta.get('merl_invalid', 0)} marked invalid (-1)")
