"""Helpers shared by the CLI verbs: errors and exit statuses, ``-p name=value``, degree ranges.

Like every module of :mod:`roughbrdf.cli`, this one imports nothing heavy at module level (NumPy,
the models, SciPy, Matplotlib are imported inside the functions that use them), so that
``roughbrdf --help`` and the argument checks stay fast; ``tests/test_startup.py`` checks it.

Every verb runs its work inside :func:`handled`, which turns an exception into one line on
stderr and the exit status of :mod:`roughbrdf.cli` (2 usage or input, 3 operating system, 4 a
bug, 130 interrupted), names CLI options in library errors about arguments
(:class:`roughbrdf.errors.ArgumentError`, :class:`roughbrdf.output.OverwriteRefused`) and shows
the traceback only with ``roughbrdf --debug``.
"""

from __future__ import annotations

import contextlib
import math
import sys
from collections.abc import Iterator, Mapping
from typing import TYPE_CHECKING

import typer

from . import EXIT_BUG, EXIT_INTERRUPTED, EXIT_OS, EXIT_USAGE, _Run

if TYPE_CHECKING:
    import numpy as np

#: exceptions Typer shows by itself (usage errors, exits)
_TYPER_OWN: tuple[type[BaseException], ...] = (
    typer.Exit, typer.Abort,
    *(c for c in typer.BadParameter.__mro__ if c.__name__ == "ClickException"))


@contextlib.contextmanager
def handled(options: Mapping[str, str] | None = None) -> Iterator[None]:
    """Run a verb's work: every error becomes one line on stderr and an exit status.

    Parameters
    ----------
    options : mapping of str to str
        The verb's ``{Python argument name: CLI option}`` (``{"theta_i": "--theta-i"}``), used
        to word :class:`~roughbrdf.errors.ArgumentError` (and ``"overwrite"``: ``"--force"``
        for :class:`~roughbrdf.output.OverwriteRefused`).

    Ctrl-C ends the run with status 130 and ``interrupted``, also when a library swallowed it
    (:func:`roughbrdf.interrupts.watch`).
    """
    from ..interrupts import raise_if_interrupted, watch

    with watch():
        try:
            yield
            raise_if_interrupted()  # a Ctrl-C swallowed after the last safe point
        except _TYPER_OWN:
            raise
        except KeyboardInterrupt as exc:
            _Run.interrupt_reported = True
            typer.echo("interrupted", err=True)
            raise typer.Exit(EXIT_INTERRUPTED) from exc
        except BrokenPipeError as exc:  # stdout's reader went away (`| head`): nothing to say
            _silence_stdout()
            raise typer.Exit(EXIT_OS) from exc
        except Exception as exc:
            code = exit_status(exc)
            if _Run.debug:
                import traceback

                traceback.print_exception(exc, file=sys.stderr)
            typer.echo(f"error: {error_message(exc, options, code)}", err=True)
            raise typer.Exit(code) from exc


def _silence_stdout() -> None:
    """Point stdout at the null device, so that the final flush cannot fail again."""
    import os

    try:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, sys.stdout.fileno())
    except (OSError, ValueError):  # no file descriptor (captured output)
        pass


def exit_status(exc: BaseException) -> int:
    """The exit status for ``exc`` (see :mod:`roughbrdf.cli`).

    Examples
    --------
    >>> exit_status(ValueError("bad option")), exit_status(PermissionError(13, "denied"))
    (2, 3)
    """
    from ..output import OverwriteRefused

    if isinstance(exc, KeyboardInterrupt):
        return EXIT_INTERRUPTED
    if isinstance(exc, OverwriteRefused | FileNotFoundError | ValueError | TypeError):
        return EXIT_USAGE
    if isinstance(exc, OSError | MemoryError):
        return EXIT_OS
    return EXIT_BUG


def error_message(exc: BaseException, options: Mapping[str, str] | None = None,
                  code: int | None = None) -> str:
    """One line for ``exc``: library argument errors name CLI options; OS errors name the path
    and the cause; anything unexpected says it is a bug."""
    from ..errors import ArgumentError
    from ..output import OverwriteRefused

    if isinstance(exc, ArgumentError | OverwriteRefused):
        return exc.render({"overwrite": "--force", **(options or {})})
    if isinstance(exc, OSError) and exc.strerror:
        where = exc.filename
        if exc.filename2 is not None:
            where = f"{exc.filename} -> {exc.filename2}"
        return f"{where}: {exc.strerror}" if where is not None else exc.strerror
    if isinstance(exc, MemoryError):
        return f"out of memory{': ' + str(exc) if str(exc) else ''}"
    text = " ".join(str(exc).split()) or type(exc).__name__
    if (exit_status(exc) if code is None else code) == EXIT_BUG:
        return (f"internal error: {type(exc).__name__}: {text} (a bug in roughbrdf; "
                f"`roughbrdf --debug ...` shows the traceback)")
    return text


def parse_params(items: list[str] | None) -> dict[str, float | None | str]:
    """``["e=0.5", "n=None", "distribution=ggx"]`` -> dict (numbers where they parse)."""
    out: dict[str, float | None | str] = {}
    for item in items or []:
        if "=" not in item:
            raise typer.BadParameter(f"expected name=value, got {item!r}")
        key, val = item.split("=", 1)
        key, val = key.strip(), val.strip()
        if val.lower() == "none":
            out[key] = None
            continue
        try:
            out[key] = float(val)
        except ValueError:
            out[key] = val
    return out


def degree_range(text: str, name: str) -> np.ndarray:
    """``"30"`` or ``"0:90:5"`` (start:stop:step, stop inclusive) in degrees -> radians."""
    import numpy as np

    try:
        parts = [float(x) for x in text.split(":")]
    except ValueError as exc:
        raise typer.BadParameter(f"{name}: expected DEG or START:STOP:STEP, got {text!r}") from exc
    if len(parts) == 1:
        return np.radians(np.array(parts))
    if len(parts) != 3 or parts[2] == 0:
        raise typer.BadParameter(f"{name}: expected START:STOP:STEP with STEP != 0, got {text!r}")
    start, stop, step = parts
    n = int(math.floor((stop - start) / step + 1e-9)) + 1
    if n <= 0:
        raise typer.BadParameter(f"{name}: empty range {text!r}")
    return np.radians(start + step * np.arange(n))
