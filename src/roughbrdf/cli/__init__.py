"""Command-line interface (Typer). Angles are in degrees at this edge; verbs mirror the library.

Each verb lives in its own module with a ``register(app)`` function; :data:`VERBS` lists them.
The Typer application :data:`app` is built on first use, so that :func:`main` can catch Ctrl-C
from its very first line (importing Typer alone takes tens of milliseconds).

Exit statuses
-------------
====  ==========================================================================================
0     success
1     a fit did not converge (``success`` false for some channel); its results are written
2     usage error, bad input (arguments, a measurement file that cannot be read), or files that
      roughbrdf refuses to replace (``--force``) or a folder another run is writing into
3     error of the operating system: permission denied, read-only or full disk, a folder where
      a file is expected or a file where a folder is expected
4     internal error (a bug in roughbrdf: ``--debug`` shows the traceback)
130   interrupted (Ctrl-C); nothing half-written is left behind
143   stopped by SIGTERM (``timeout``, SLURM, systemd): the same clean-up as Ctrl-C
129   stopped by SIGHUP (the terminal closed): the same clean-up as Ctrl-C
====  ==========================================================================================

Every error is one line on stderr naming what is wrong (``roughbrdf --debug VERB ...`` adds the
traceback); an interrupt prints ``interrupted`` (``interrupted (SIGTERM)``, ...: the signal
when it is not Ctrl-C), and exits with 128 + the signal's number, as a shell reports a process
that the signal ended (:func:`interrupted_status`).
"""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import typer

    app: typer.Typer

__all__ = ["app", "main", "build_app", "get_app", "VERBS", "EXIT_OK", "EXIT_NOT_CONVERGED",
           "EXIT_USAGE", "EXIT_OS", "EXIT_BUG", "EXIT_INTERRUPTED", "interrupted_status",
           "interrupt_line"]

# the statuses (the table above) and interrupted_status are defined with the one-line wording
# of errors that the explorer shares (roughbrdf.wording, a lower layer); re-exported here
from ..wording import EXIT_BUG as EXIT_BUG
from ..wording import EXIT_INTERRUPTED as EXIT_INTERRUPTED
from ..wording import EXIT_NOT_CONVERGED as EXIT_NOT_CONVERGED
from ..wording import EXIT_OK as EXIT_OK
from ..wording import EXIT_OS as EXIT_OS
from ..wording import EXIT_USAGE as EXIT_USAGE
from ..wording import interrupted_status as interrupted_status


def interrupt_line() -> str:
    """The one line an interrupted run prints: ``interrupted``, naming the signal when it is
    not Ctrl-C (``interrupted (SIGTERM)``)."""
    import signal

    from ..interrupts import interrupt_signal

    signum = interrupt_signal()
    if signum == signal.SIGINT:
        return "interrupted"
    return f"interrupted ({signal.Signals(signum).name})"

#: modules under roughbrdf.cli that register verbs (each defines register(app))
VERBS = ["evaluate", "fit", "fit_batch", "compare", "export", "convert", "plot", "reproduce"]
VERBS += ["explore"]  # roughbrdf explore: the web explorer (docs/explore.md)

_APP: list[Any] = []


class Run:
    """State of the current command line run: set by :func:`main` and the verbs
    (:mod:`roughbrdf.cli.common` records a reported interrupt), read by :func:`main`.

    Attributes
    ----------
    debug : bool
        ``--debug`` was given: errors also show their traceback.
    interrupt_reported : bool
        ``interrupted`` has been printed for this run (printed once).
    """

    debug = False
    interrupt_reported = False


def build_app() -> typer.Typer:
    """A new Typer application with every verb of :data:`VERBS` registered."""
    import importlib

    import typer

    from .usage import OneLineGroup  # the parser's own errors as one line each

    new = typer.Typer(add_completion=False, no_args_is_help=True, cls=OneLineGroup,
                      help="roughbrdf: rough-surface BRDF models - evaluate, fit (a file or "
                           "a catalogue), compare, export, plot, convert, reproduce.")

    @new.callback()
    def _options(debug: bool = typer.Option(
            False, "--debug", help="on an error, also show the traceback")) -> None:
        Run.debug = debug
        Run.interrupt_reported = False

    for name in VERBS:
        try:
            mod = importlib.import_module(f"{__name__}.{name}")
        except ModuleNotFoundError as exc:  # verb not written yet
            if exc.name != f"{__name__}.{name}":
                raise
            continue
        mod.register(new)
    return new


def get_app() -> typer.Typer:
    """The application (:data:`app`), built on the first call."""
    if not _APP:
        _APP.append(build_app())
    return _APP[0]


def __getattr__(name: str) -> Any:
    if name == "app":
        return get_app()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def main(argv: list[str] | None = None) -> int:
    """Run the command line (``argv``, default ``sys.argv[1:]``); returns the exit status.

    Ctrl-C at any moment of the run ends it with :data:`EXIT_INTERRUPTED` and the one line
    ``interrupted``; SIGTERM and SIGHUP likewise, with 143 and 129 (:func:`interrupted_status`;
    also when a library swallowed the ``KeyboardInterrupt``:
    :func:`roughbrdf.interrupts.watch`). Once the run's status is settled (its files are
    committed), a Ctrl-C changes nothing: :func:`main` returns that status and never raises
    ``KeyboardInterrupt`` (:func:`roughbrdf.interrupts.record_interrupts`). As the console
    script (``argv`` None), a Ctrl-C (SIGTERM, SIGHUP) that comes after :func:`main` has returned
    is ignored: only Python's shutdown is left. Called from Python, the caller's handlers are
    back once :func:`main` returns.
    """
    from ..interrupts import checkpoint, ignore_interrupts, record_interrupts, watch

    Run.debug = "--debug" in (sys.argv[1:] if argv is None else argv)  # until parsed
    Run.interrupt_reported = False
    with watch(), _one_line_warnings():
        try:
            code = _run(argv)  # returns with SIGINT recorded, never raised
        except KeyboardInterrupt:  # only where _run did not settle (a second Ctrl-C there)
            code = interrupted_status()
            record_interrupts()
        checkpoint("main: status settled")
        if code == interrupted_status() and not Run.interrupt_reported:
            _say(interrupt_line())
            checkpoint("main: interrupted said")
            Run.interrupt_reported = True
        checkpoint("main: reported")
        if argv is None:
            ignore_interrupts()
            checkpoint("main: SIGINT ignored")
        return code


@contextlib.contextmanager
def _one_line_warnings() -> Iterator[None]:
    """Python warnings printed as one ``warning: ...`` line, the command line's form (not
    Python's two lines with a source file and line); the usual form with ``--debug``. Only the
    text is changed (``warnings.formatwarning``): a caller recording warnings (pytest,
    ``catch_warnings(record=True)``) still gets them."""
    import warnings

    formatted = warnings.formatwarning

    def one_line(message: Any, category: type[Warning], filename: str, lineno: int,
                 line: Any = None) -> str:
        text = " ".join(str(message).split())
        if not category.__module__.startswith("roughbrdf"):  # whose warning it is
            text = f"{category.__name__}: {text}"
        return f"warning: {text}\n"

    if not Run.debug:
        warnings.formatwarning = one_line
    try:
        yield
    finally:
        warnings.formatwarning = formatted


def _run(argv: list[str] | None) -> int:
    """Run the command; its exit status, settled: on return SIGINT is recorded, not raised.

    A Ctrl-C (SIGTERM, SIGHUP) that comes before the status is settled (while the command runs,
    or in the few statements after it, which are still this function's) makes it
    :func:`interrupted_status`.
    """
    from ..interrupts import checkpoint, interrupted, record_interrupts

    try:
        code = _invoke(argv)
        checkpoint("run: command returned")
        if interrupted():  # a Ctrl-C that a library swallowed during the command
            code = interrupted_status()
    except KeyboardInterrupt:
        code = interrupted_status()
    while True:
        try:
            checkpoint("run: settling")
            record_interrupts()
            return code
        except KeyboardInterrupt:  # it came before the handler was replaced: try again
            code = interrupted_status()


def _invoke(argv: list[str] | None) -> int:
    """Build the application and run it in standalone mode; its exit status."""
    try:
        get_app()(args=argv, prog_name="roughbrdf")
    except SystemExit as exc:
        if exc.code is None or isinstance(exc.code, int):
            return int(exc.code or 0)
        _say(str(exc.code))
        return EXIT_USAGE
    except Exception as exc:  # not handled by a verb: a bug
        import traceback

        if Run.debug:
            traceback.print_exception(exc, file=sys.stderr)
        _say(f"error: internal error: {type(exc).__name__}: {exc} (a bug in roughbrdf; "
             f"`roughbrdf --debug ...` shows the traceback)")
        return EXIT_BUG
    return EXIT_OK


def _say(line: str) -> None:
    try:
        print(line, file=sys.stderr, flush=True)
    except (OSError, ValueError):  # stderr closed or a broken pipe: nothing more to do
        pass

