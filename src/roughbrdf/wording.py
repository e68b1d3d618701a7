"""The one-line wording of errors and the degrees of model settings, shared by the command
line (:mod:`roughbrdf.cli`) and the web explorer (:mod:`roughbrdf.explore`).

Both speak to a person at a terminal or a page, not to Python: an error is one line that names
the option (or the file) at fault (:func:`error_message`), and a model parameter whose unit is
an angle is given and shown in degrees (:func:`model_in_degrees`, :func:`cli_unit`). The
explorer is a lower layer than the command line, so what both need lives here, below them;
:mod:`roughbrdf.cli.common` re-exports it under the same names, and the exit statuses
(:data:`EXIT_USAGE`, ...) are :mod:`roughbrdf.cli`'s, documented there.

Like the command line, this module imports nothing heavy at module level (the models and the
catalogue's quoting are imported inside the functions that use them), so that
``roughbrdf --help`` stays fast; ``tests/test_startup.py`` checks it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .errors import ArgumentError
    from .models import Model

__all__ = ["ANGLE_UNIT", "EXIT_BUG", "EXIT_INTERRUPTED", "EXIT_NOT_CONVERGED", "EXIT_OK",
           "EXIT_OS", "EXIT_USAGE", "angle_names", "argument_text", "cli_number", "cli_text",
           "cli_unit", "error_message", "exit_status", "interrupted_status", "model_in_degrees",
           "radian_settings", "shown_name"]

# the exit statuses of the command line (:mod:`roughbrdf.cli` documents them); here because
# :func:`exit_status` words an error with its status
EXIT_OK = 0
EXIT_NOT_CONVERGED = 1
EXIT_USAGE = 2
EXIT_OS = 3
EXIT_BUG = 4
EXIT_INTERRUPTED = 130  # 128 + SIGINT; SIGTERM and SIGHUP give 143 and 129


def interrupted_status() -> int:
    """The exit status of a run that a signal interrupted: 128 + its number (130 for Ctrl-C,
    143 for SIGTERM, 129 for SIGHUP: :func:`roughbrdf.interrupts.interrupt_signal`)."""
    from .interrupts import interrupt_signal

    return 128 + interrupt_signal()


def exit_status(exc: BaseException) -> int:
    """The exit status for ``exc`` (see :mod:`roughbrdf.cli`).

    Examples
    --------
    >>> exit_status(ValueError("bad option")), exit_status(PermissionError(13, "denied"))
    (2, 3)
    """
    from .output import OverwriteRefused

    if isinstance(exc, KeyboardInterrupt):  # 130, or 128 + the SIGTERM/SIGHUP that raised it
        return interrupted_status()
    if isinstance(exc, OverwriteRefused | FileNotFoundError | ValueError | TypeError):
        return EXIT_USAGE
    if isinstance(exc, OSError | MemoryError):
        return EXIT_OS
    return EXIT_BUG


def error_message(exc: BaseException, options: Mapping[str, str] | None = None,
                  code: int | None = None) -> str:
    """One line for ``exc``: library argument errors name CLI options; OS errors name the path
    and the cause; anything unexpected says it is a bug."""
    from .errors import ArgumentError
    from .output import OverwriteRefused

    opts = {"overwrite": "--force", **(options or {})}
    if isinstance(exc, ArgumentError):
        return cli_text(argument_text(exc, opts), opts)
    if isinstance(exc, OverwriteRefused):
        return exc.render(opts)
    if isinstance(exc, OSError) and exc.strerror:
        where = None if exc.filename is None else shown_name(exc.filename)
        if exc.filename2 is not None:
            where = f"{where} -> {shown_name(exc.filename2)}"
        return f"{where}: {exc.strerror}" if where is not None else exc.strerror
    if isinstance(exc, MemoryError):
        return f"out of memory{': ' + str(exc) if str(exc) else ''}"
    text = " ".join(str(exc).split()) or type(exc).__name__
    if not text.isprintable():  # a control character (an escape) left: shown escaped
        from .catalogue.rows import one_line

        text = one_line(text)
    if (exit_status(exc) if code is None else code) == EXIT_BUG:
        return (f"internal error: {type(exc).__name__}: {text} (a bug in roughbrdf; "
                f"`roughbrdf --debug ...` shows the traceback)")
    return cli_text(text, opts)


def shown_name(name: object) -> str:
    r"""A file name as one-line messages show it (:func:`roughbrdf.catalogue.rows.shown_name`:
    as it is, or quoted like a Python string when it holds a newline, a tab or another
    character that is not printable); the catalogue, which imports the models, is loaded
    only for such a name.

    Examples
    --------
    >>> print(shown_name("a b.csv"), shown_name("two\nlines.csv"))
    a b.csv 'two\nlines.csv'
    """
    text = str(name)
    if text.isprintable():  # the common case, without importing the catalogue
        return text
    from .catalogue.rows import shown_name as quoted

    return quoted(text)


def argument_text(exc: ArgumentError, options: Mapping[str, str]) -> str:
    """``exc`` rendered with the verb's ``options``, always naming the option.

    A check worded in Python terms without the value (``"starts must be >= 1"``) names the
    option in place of the argument (``"--starts must be >= 1"``), or ahead of the message.

    Examples
    --------
    >>> from roughbrdf.errors import ArgumentError
    >>> argument_text(ArgumentError("starts", "starts must be >= 1, got 0"), {"starts": "--starts"})
    '--starts must be >= 1, got 0'
    >>> argument_text(ArgumentError("loss", "unknown loss 'x'"), {"loss": "--loss"})
    "--loss: unknown loss 'x'"
    """
    text = " ".join(exc.render(options).split())
    opt = options.get(exc.argument)
    if opt is None or opt in text:  # not an option of this verb, or already named
        return text
    for sep in (" ", ":"):
        if text.startswith(exc.argument + sep):
            return opt + text[len(exc.argument):]
    return f"{opt}: {text}"


#: a value after ``name=`` in a library message: quoted, or a bare word
_HINT_VALUE = r"(?:'[^']*'|\"[^\"]*\"|[\w.+-]+)"


def cli_text(text: str, options: Mapping[str, str] | None) -> str:
    """A library message with its Python argument hints worded as this verb's options.

    The readers and the fit speak Python (``pass format=``, ``angles='deg'``), sometimes with a
    CLI hint for one verb (``(CLI: --from/--to)``); each ``name=`` of an argument in
    ``options`` becomes that option, hint included.

    Examples
    --------
    >>> fit = {"format": "--format", "angles": "--angles-in"}   # as in ``roughbrdf fit``
    >>> cli_text("unknown extension; pass format= (CLI: --from/--to)", fit)
    'unknown extension; pass --format'
    >>> cli_text("the angles look like degrees (angles='deg'; CLI: --angles-in deg)", fit)
    'the angles look like degrees (--angles-in deg)'
    >>> cli_text("exists (pass overwrite=True; CLI: --force)", {"overwrite": "--force"})
    'exists (pass --force)'
    """
    import re

    for arg, opt in (options or {}).items():
        if not arg.isidentifier() or f"{arg}=" not in text:  # fast path: nothing to word
            continue
        pattern = (rf"\b{re.escape(arg)}=({_HINT_VALUE})?"
                   r"(?:;\s*CLI:\s*[^);]*|\s*\((?:CLI:\s*)?--[^)]*\))?")

        def word(m: re.Match[str], opt: str = opt) -> str:
            value = (m.group(1) or "").strip("'\"")
            return opt if value in ("", "True") else f"{opt} {value}"

        text = re.sub(pattern, word, text)
    return text


# --------------------------------------------------------------------------------------------
# model parameters whose unit is an angle: degrees at the CLI, radians in the library
# --------------------------------------------------------------------------------------------
#: the unit of a model parameter (:attr:`roughbrdf.models.Parameter.unit`) that is an angle;
#: the CLI takes and prints such parameters in degrees. Units *per* angle (TS67 ``c`` in
#: ``1/deg``, RB08's ``1/rad`` coefficients) are rates, not angles: they are left as they are.
ANGLE_UNIT = "rad"


def cli_unit(unit: str) -> str:
    """The unit a CLI shows for a parameter of ``unit`` (``"rad"`` -> ``"deg"``)."""
    return "deg" if unit == ANGLE_UNIT else unit


def cli_number(unit: str, value: float | None) -> float | None:
    """``value`` of a parameter of ``unit`` as the CLI shows it (radians -> degrees)."""
    if value is None or unit != ANGLE_UNIT:
        return value
    return math.degrees(value)


def angle_names(model: Model) -> set[str]:
    """The parameters of ``model`` (prefixed in sums) whose unit is an angle."""
    return {p.name for p in model.parameters if p.unit == ANGLE_UNIT}


def radian_settings(model: Model, given: Mapping[str, object]) -> dict[str, object] | None:
    """The settings ``given`` (``-p name=value``, as made into ``model``) with each parameter
    whose unit is an angle (plain or prefixed name) in radians; ``None`` when ``model`` has
    no such parameter (``model`` stands as made).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> radian_settings(rb.model("oren-nayar", sigma=90.0), {"sigma": 90.0})
    {'sigma': 1.5707963267948966}
    >>> radian_settings(rb.model("lambertian"), {"rho": 0.5}) is None
    True
    """
    from . import models as _models

    angles = angle_names(model)
    if not angles:
        return None
    converted = dict(given)
    for key, value in given.items():
        if not isinstance(value, float):
            continue
        try:
            (name,) = _models.resolve_names(model, [key])
        except ValueError:  # an option (diffuse=...), not a parameter
            continue
        if name in angles:
            converted[key] = math.radians(value)
    return converted


def model_in_degrees(spec: str, params: Mapping[str, object] | None = None) -> Model:
    """``roughbrdf.model(spec, **params)`` with settings as the command line and the explorer
    give them: a parameter whose unit is an angle (Oren-Nayar ``sigma``, also in
    ``coated(diffuse="oren-nayar")`` and in sums, by plain or prefixed name) in degrees. The
    library's errors pass as they are (:func:`roughbrdf.cli.common.cli_model` names the
    option at fault).

    Examples
    --------
    >>> round(model_in_degrees("oren-nayar", {"sigma": 20.0}).params["sigma"], 6)
    0.349066
    """
    from . import models as _models

    given = dict(params or {})
    # made first as given, for the names and units (angles in degrees pass the sign checks of
    # their domains just as well), then again with the angles in radians
    first = _models.model(spec, **given)
    converted = radian_settings(first, given)
    return first if converted is None else _models.model(spec, **converted)
