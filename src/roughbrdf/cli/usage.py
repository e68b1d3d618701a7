"""Usage errors of the command-line parser as one line naming the option and the value.

Typer (Click) refuses what it parses itself (``--starts x``, ``--max-rows 1``, an unknown
option, a missing ``--out``) before a verb runs, and shows the refusal as a usage line, a hint
and a framed panel. :class:`OneLineGroup`, the class of the application's group, turns each
into the command line's form of every other error (:func:`roughbrdf.cli.common.handled`): one
line on stderr, ``error: --starts: invalid value 'x': ...``, exit status 2
(:data:`roughbrdf.cli.EXIT_USAGE`). Help (``--help``, no arguments at all) is left as it is.
"""

from __future__ import annotations

from typing import Any

import typer
from typer.core import TyperGroup

__all__ = ["OneLineGroup", "usage_line"]

#: the parser's exceptions (Typer carries its own copy of Click)
_errors: Any = getattr(typer.core, "_click", None)
if _errors is None:  # an older Typer on the real Click
    import click as _errors


def _option_name(param: Any) -> str:
    """How a parameter is named in messages: its long option (``--starts``), or an argument's
    metavar (``FILE``)."""
    opts = list(getattr(param, "opts", None) or [])
    if getattr(param, "param_type_name", "") == "argument" or not opts:
        shown = getattr(param, "metavar", None) or getattr(param, "name", None) or "argument"
        return str(shown).upper()
    return next((o for o in opts if o.startswith("--")), opts[0])


def _given_value(exc: BaseException) -> object:
    """The value Typer could not convert (its validation error records it), or None."""
    cause = exc.__cause__ or exc.__context__
    errors = getattr(cause, "errors", None)
    if not callable(errors):
        return None
    try:
        return errors()[0].get("input")
    except (TypeError, IndexError, KeyError, AttributeError, ValueError):
        return None


def usage_line(exc: Any) -> str:
    """One line for the parser's usage error ``exc``, starting with the option it is about.

    Examples
    --------
    >>> usage_line(_errors.exceptions.NoSuchOption("--nosuch"))
    '--nosuch: no such option'
    >>> usage_line(_errors.exceptions.UsageError("No such command 'fitt'."))
    "no such command 'fitt'"
    """
    text = " ".join(str(exc.message).split()).rstrip(".")
    param = getattr(exc, "param", None)
    if isinstance(exc, _errors.exceptions.NoSuchOption):
        line = f"{exc.option_name}: no such option"
        possible = list(getattr(exc, "possibilities", None) or [])
        return line + (f" (did you mean {', '.join(sorted(possible))}?)" if possible else "")
    if isinstance(exc, _errors.exceptions.MissingParameter) and param is not None:
        kind = "argument" if param.param_type_name == "argument" else "option"
        return f"{_option_name(param)}: missing (a required {kind})"
    if param is not None:  # Typer's validation: "Input should be a valid integer, ..."
        name, value = _option_name(param), _given_value(exc)
        shown = f"invalid value {value!r}: " if value is not None else ""
        return f"{name}: {shown}{text.removeprefix('Input ')}"
    option = getattr(exc, "option_name", None)
    if option and not text.startswith(option):
        return f"{option}: {text[:1].lower()}{text[1:]}"
    return f"{text[:1].lower()}{text[1:]}"


class OneLineGroup(TyperGroup):
    """The application's group: a usage error of a verb is one ``error:`` line and exit 2."""

    def invoke(self, ctx: Any) -> Any:
        """Run the verb; a usage error of its arguments becomes one line on stderr."""
        try:
            return super().invoke(ctx)
        except _errors.exceptions.UsageError as exc:
            if type(exc).__name__ == "NoArgsIsHelpError":  # help, not an error
                raise
            where = getattr(getattr(exc, "ctx", None), "command_path", None) or "roughbrdf"
            typer.echo(f"error: {usage_line(exc)} (see `{where} --help`)", err=True)
            raise typer.Exit(exc.exit_code) from exc
