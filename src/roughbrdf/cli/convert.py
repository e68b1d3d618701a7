"""``roughbrdf convert IN OUT``: read any supported measurement file and write another format.

What the conversion cannot carry is said, never hidden: writing MERL or Zemax (fixed grids)
refuses a measurement whose samples it would bin, average or drop unless ``--resample``, and
then prints what it did (Zemax: one channel per file, ``--channel``); header keys and
uncertainties the target has no place for are named in a warning line. OUT is never replaced
without ``--force`` and never written onto IN.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Annotated, Any

import typer

from .common import CONVERT_OPTIONS, cli_text, shown_name
from .options import OptionError, check_format

#: the quantities a measurement can hold, for the help text (the same as
#: :data:`roughbrdf.measurement.QUANTITIES`, written out so that ``--help`` imports no NumPy/Numba;
#: the command itself checks against the library's tuple)
HELP_QUANTITIES = ("brdf", "brdf_cos", "bridf", "relative")

#: library argument -> the option of this command that sets it (for ArgumentError messages)
OPTIONS = CONVERT_OPTIONS
#: arguments set by a flag: "pass resample=True" is "pass --resample"
FLAGS = {"overwrite": "--force", "resample": "--resample"}

#: exit statuses: usage or format error, OS error (see the README's table)
EXIT_USAGE = 2
EXIT_OS = 3


def _fail(message: str, status: int = EXIT_USAGE) -> typer.Exit:
    typer.echo(f"error: {message}", err=True)
    return typer.Exit(status)


def _cli_message(exc: BaseException) -> str:
    """An error worded for this command: CLI options instead of Python arguments."""
    from ..errors import ArgumentError

    if isinstance(exc, ArgumentError):
        if exc.argument in FLAGS and exc.fix is True:
            return f"{exc.message}; pass {FLAGS[exc.argument]} to do it anyway"
        return cli_text(exc.render(OPTIONS), OPTIONS)
    return cli_text(str(exc), OPTIONS)  # the readers' Python hints (format=) as options


def _os_message(exc: OSError, src: Path, dst: Path) -> str:
    """One line naming the path and the cause (the temporary file beside OUT is OUT)."""
    if exc.strerror is None:  # raised with a message of its own (a folder given as OUT)
        return str(exc)
    if exc.filename is not None and Path(str(exc.filename)).absolute() == src.absolute():
        return f"cannot read {shown_name(src)}: {exc.strerror}"
    return f"cannot write {shown_name(dst)}: {exc.strerror}"


def _echo_warnings(caught: list[warnings.WarningMessage]) -> None:
    """Each warning of the read or the write as one line on stderr."""
    for w in caught:
        typer.echo("warning: " + " ".join(str(w.message).split()), err=True)


def _options(fin: str, fout: str, args: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """Reader and writer options from the command's options; each applies to some formats."""
    ropts: dict[str, Any] = {}
    wopts: dict[str, Any] = {"overwrite": args["force"]}
    if args["quantity"] is not None:
        if fin == "merl":
            raise ValueError("--quantity does not apply to MERL input (always BRDF)")
        ropts["quantity"] = args["quantity"]
    if args["angles_in"] is not None:
        if fin not in ("astm", "csv"):
            raise ValueError("--angles-in applies to ASTM and CSV input only")
        ropts["angles"] = args["angles_in"]
    if args["stride"] is not None:
        if fin != "merl":
            raise ValueError("--stride applies to MERL input only")
        ropts["stride"] = args["stride"]
    if args["angles_out"] is not None:
        if fout not in ("astm", "csv"):
            raise ValueError("--angles-out applies to ASTM and CSV output only")
        wopts["angles"] = args["angles_out"]
    if args["resample"]:
        if fout not in ("merl", "zemax"):
            raise ValueError("--resample applies to MERL and Zemax output only (the other "
                             "formats keep every sample)")
        wopts["resample"] = True
    if args["channel"] is not None:
        if fout != "zemax":
            raise ValueError("--channel applies to Zemax output only (one channel per .bsdf "
                             "file; the other formats keep every channel)")
        wopts["channel"] = args["channel"]
    return ropts, wopts


def _check_paths(src: Path, dst: Path, force: bool) -> None:
    from ..output import same_file

    if not src.exists():
        raise FileNotFoundError(f"{shown_name(src)}: no such file")
    if src.is_dir():  # not a file of an unknown extension
        raise ValueError(f"IN {src} is a folder; convert reads one measurement file")
    if same_file(src, dst) or src.resolve() == dst.resolve():
        raise ValueError(f"IN and OUT are the same file ({dst}); convert never writes onto "
                         "its input, even with --force")
    if dst.is_dir():
        raise IsADirectoryError(f"OUT {dst} is a folder; give a file name (e.g. {dst}/"
                                f"{src.stem}.csv)")
    if dst.exists() and not force:
        raise ValueError(f"{dst} exists; pass --force to overwrite it")


def _report(m: Any, dst: Path, fout: str, result: Any) -> None:
    """What was written: sizes, then what happened to bad values (or the MERL report)."""
    typer.echo(f"wrote {dst} ({fout}): {m.n_samples} samples x {m.n_channels} channels "
               f"{m.channels}, quantity {m.quantity}")
    if result is not None and hasattr(result, "text"):
        typer.echo(result.text())
    else:
        for ch, r in m.validate().items():
            if r["nonfinite"] or r["negative"]:
                typer.echo(f"  channel {ch}: {r['nonfinite']} non-finite and {r['negative']} "
                           "negative values kept as they are")
    if m.meta.get("merl_below_horizon") or m.meta.get("merl_invalid"):
        typer.echo(f"  MERL cells left out on reading: {m.meta.get('merl_below_horizon', 0)} "
                   f"below the horizon, {m.meta.get('merl_invalid', 0)} marked invalid (-1)")


def _checked(args: dict[str, Any]) -> dict[str, Any]:
    """The options' values checked, before any file is looked at (each error names its option
    and the value), in the spellings the readers and writers take."""
    from ..quantity import Quantity
    from .fit import angle_unit

    check_format(args["from_"], "--from", "format")
    check_format(args["to"], "--to", "format")
    out = dict(args)
    for key, option in (("quantity", "--quantity"), ("as_quantity", "--as")):
        if args[key] is not None:  # the same spellings as every other verb's --quantity
            out[key] = Quantity.parse(args[key], option).value
    for key, option in (("angles_in", "--angles-in"), ("angles_out", "--angles-out")):
        out[key] = angle_unit(args[key], option)
    if args["stride"] is not None and args["stride"] < 1:
        raise OptionError("--stride", f"must be >= 1 (got {args['stride']})")
    return out


def _convert(src: Path, dst: Path, args: dict[str, Any]) -> None:
    from .. import io as _io

    args = _checked(args)
    _check_paths(src, dst, args["force"])
    fin = _io.format_for(src, args["from_"])
    fout = _io.format_for(dst, args["to"])
    ropts, wopts = _options(fin, fout, args)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            m = _io.read(src, format=fin, **ropts)
            if args["as_quantity"] is not None:
                m = m.as_quantity(args["as_quantity"])
            result = _io.write(m, dst, format=fout, **wopts)
        finally:
            _echo_warnings(caught)
    _report(m, dst, fout, result)


def register(app: typer.Typer) -> None:
    @app.command("convert")
    def convert_cmd(
        src: Annotated[Path, typer.Argument(metavar="IN", help="input measurement file")],
        dst: Annotated[Path, typer.Argument(metavar="OUT", help="output file (not overwritten "
                                            "unless --force; never IN)")],
        from_: str = typer.Option(None, "--from", help="input format (astm, alta, merl, csv, "
                                  "zemax); default from the extension"),
        to: str = typer.Option(None, "--to", help="output format; default from the extension"),
        quantity: str = typer.Option(None, "--quantity", help="what the input values hold, "
                                     "where the file does not say (it must agree where it "
                                     f"does): {', '.join(HELP_QUANTITIES)}"),
        as_quantity: str = typer.Option(None, "--as", help="convert the values to this quantity "
                                        "before writing (brdf <-> brdf_cos)"),
        angles_in: str = typer.Option(None, "--angles-in", help="angle unit of the input "
                                      "(deg or rad; ASTM and CSV), where the file does not say "
                                      "(it must agree where it does)"),
        angles_out: str = typer.Option(None, "--angles-out", help="angle unit written (deg or "
                                       "rad; CSV default deg, ASTM default rad)"),
        stride: int = typer.Option(None, "--stride", help="MERL input: keep every N-th cell "
                                   "along each axis"),
        resample: bool = typer.Option(False, "--resample", help="MERL and Zemax output: write "
                                      "even though the fixed grid bins, averages or drops "
                                      "samples (the counts are printed); without it such "
                                      "input is refused"),
        channel: str = typer.Option(None, "--channel", help="Zemax output: the channel to "
                                    "write (label or index; one per .bsdf file)"),
        force: bool = typer.Option(False, "--force", help="overwrite OUT if it exists"),
    ) -> None:
        """Convert a measurement between formats (astm, alta, merl, csv, zemax).

        Non-finite and negative values are carried over and reported, never dropped silently:
        MERL output, a fixed grid, needs --resample when it would change the samples and then
        reports what was binned, averaged and dropped.
        """
        from ..errors import ArgumentError
        from ..io import FormatError

        args = {"from_": from_, "to": to, "quantity": quantity, "as_quantity": as_quantity,
                "angles_in": angles_in, "angles_out": angles_out, "stride": stride,
                "resample": resample, "force": force, "channel": channel}
        try:
            _convert(src, dst, args)
        except (ArgumentError, FormatError, ValueError, FileNotFoundError,
                FileExistsError) as exc:
            raise _fail(_cli_message(exc)) from exc
        except OSError as exc:  # permission denied, a folder, a full disk...
            raise _fail(_os_message(exc, src, dst), EXIT_OS) from exc
