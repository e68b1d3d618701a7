"""Ctrl-C that is never lost: hold SIGINT where an interrupt would be swallowed or half-done.

Two places must not be interrupted in the middle:

* **loading or compiling a kernel.** Numba and llvmlite call back into Python from C while they
  load a cached kernel; a ``KeyboardInterrupt`` raised there is printed as "Exception ignored"
  and lost, and the program runs on as if nothing had happened. A compiled loop cannot be
  interrupted either (it does not return to Python until it ends);
* **committing a set of output files** (:class:`roughbrdf.output.ResultFolder`): the renames
  must all happen or none.

:func:`held_interrupts` defers SIGINT for the duration of its block and raises
``KeyboardInterrupt`` right after it if one arrived, so the interrupt takes effect at the next
safe point instead of disappearing. It only acts in the main thread (where Python delivers
signals) and nests.

Other code can swallow an interrupt too: any C or Cython callback, finalizer (``__del__``) or
weak-reference callback turns the ``KeyboardInterrupt`` raised in it into an "Exception
ignored" message (seen in SciPy's Sobol initialization and in Numba's cache loader). A program
that must end on Ctrl-C (the command line) runs inside :func:`watch`: it records every SIGINT,
silences those messages for ``KeyboardInterrupt`` only, and every :func:`held_interrupts`
block, :meth:`~roughbrdf.output.ResultFolder.commit` and :func:`raise_if_interrupted` raises
``KeyboardInterrupt`` again if one was swallowed. Outside :func:`watch` nothing changes.

Once a program's work is done (the command line: its status is known and every file committed),
:func:`record_interrupts` makes the rest of the :func:`watch` block record SIGINT instead of
raising it, so that a late Ctrl-C cannot turn a finished run into a traceback.
:func:`checkpoint` marks the statements of that tail: a no-op unless a test installed a hook
(:func:`set_checkpoint_hook`) that sends the signal there.

The requests to stop that a program receives from outside the terminal end it the same way:
inside :func:`watch`, SIGTERM (``timeout``, a batch system such as SLURM, systemd) and SIGHUP
(the terminal closed) are handled as SIGINT is (:data:`SIGNALS`): they raise
``KeyboardInterrupt``, are held by :func:`held_interrupts` and recorded by
:func:`record_interrupts`, so that every clean-up of Ctrl-C (locks released, temporary files
removed, a cluster's workers stopped) runs for them too. :func:`interrupt_signal` tells which
one came first (the command line exits with 128 + its number). Outside :func:`watch` only SIGINT
is handled, as Python does.

The clean-up that follows an interrupt (a cluster's workers stopped, the folders of cancelled
tasks tidied) runs in :func:`cleaning_up`: signals are held there as in :func:`held_interrupts`,
but the interrupt already on its way is not raised again by the blocks inside it (each one
would otherwise end the clean-up at its first step).

Examples
--------
>>> with held_interrupts():
...     pass
>>> with watch():
...     interrupted()
False
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from typing import Any

__all__ = ["held_interrupts", "watch", "interrupted", "raise_if_interrupted",
           "record_interrupts", "late_interrupts", "checkpoint", "set_checkpoint_hook",
           "interrupt_signal", "ignore_interrupts", "cleaning_up", "SIGNALS"]

#: the signals that end a program run inside :func:`watch`: Ctrl-C, and the requests to stop
#: of ``timeout``, a batch system or a service manager (SIGTERM) and of a closed terminal
#: (SIGHUP, which Windows does not have)
SIGNALS: tuple[int, ...] = tuple(
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))

_depth = 0
_pending: list[int] = []  # the signals held by held_interrupts(), in order
_watching = 0
_seen = False
_received: list[int] = []  # the first signal that interrupted the current watch() block
_hooks: list[Any] = []  # the unraisable hook that watch() replaced
_late: list[int] = []  # signals recorded after record_interrupts()
_checkpoint_hook: list[Callable[[str], None]] = []  # test-only (set_checkpoint_hook)
_cleaning = False  # inside cleaning_up(): an interrupt seen earlier is not raised again


def _record(signum: int, frame: Any) -> None:
    _pending.append(signum)


def _in_main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def _held_signals() -> list[int]:
    """The signals :func:`held_interrupts` defers: SIGINT (whatever Python handler it has), and
    the other :data:`SIGNALS` while :func:`watch` handles them (outside it their handler is not
    ours: SIGTERM's default ends the process, and files are recovered by the next run)."""
    held: list[int] = [signal.SIGINT]
    held += [s for s in SIGNALS[1:] if signal.getsignal(s) is _on_signal]
    return held


@contextlib.contextmanager
def held_interrupts() -> Iterator[None]:
    """Defer SIGINT during the block (and, inside :func:`watch`, SIGTERM and SIGHUP); raise
    ``KeyboardInterrupt`` after it if one came (or, inside :func:`watch`, if one was swallowed
    earlier)."""
    global _depth
    if _depth or not _in_main_thread() or signal.getsignal(signal.SIGINT) is None:
        # nested: the outer block delivers; other threads never receive signals; a handler
        # installed outside Python could not be put back
        yield
        return
    previous: dict[int, Any] = {}
    try:
        for signum in _held_signals():
            previous[signum] = signal.signal(signum, _record)
    except (ValueError, OSError):  # no signal handling here (e.g. an embedded interpreter)
        _put_back(previous)
        yield
        return
    _depth = 1
    try:
        yield
    finally:
        _depth = 0
        _put_back(previous)
        if _pending:
            first = _pending[0]
            _pending.clear()
            _deliver(previous[first], first)
        elif _seen and not _cleaning:  # a clean-up goes on: its interrupt is on its way
            raise KeyboardInterrupt


def _put_back(handlers: dict[int, Any]) -> None:
    """Install ``handlers`` (``{signal: handler}``) again."""
    for signum, handler in handlers.items():
        signal.signal(signum, handler)


def _deliver(handler: Any, signum: int = signal.SIGINT) -> None:
    """Act on a signal that arrived while held, as ``handler`` would have."""
    if callable(handler):  # the handler that was in place (Python's raises)
        handler(signum, None)
    elif handler != signal.SIG_IGN:
        raise KeyboardInterrupt


# --------------------------------------------------------------------------------------------
# programs that must end on Ctrl-C
# --------------------------------------------------------------------------------------------
def _on_signal(signum: int, frame: Any) -> None:
    global _seen
    _seen = True
    if not _received:  # the first one is the cause; a second only repeats the request
        _received.append(signum)
    raise KeyboardInterrupt


def _unraisable(info: Any) -> None:
    """``sys.unraisablehook`` inside :func:`watch`: a swallowed ``KeyboardInterrupt`` is
    recorded (and raised again at the next safe point) instead of printed."""
    global _seen
    if isinstance(info.exc_value, KeyboardInterrupt):
        _seen = True
        return
    hook = _hooks[-1] if _hooks else sys.__unraisablehook__
    hook(info)


def _install(handler: Any) -> dict[int, Any]:
    """Install ``handler`` for the :data:`SIGNALS` :func:`watch` handles; ``{signal: the
    handler it replaced}``. SIGINT always (as Python does; also when a shell started the
    program with it ignored, a background job); SIGTERM and SIGHUP only where they have their
    default action: an ignored one (``nohup``) or a caller's Python handler stays as it is."""
    previous: dict[int, Any] = {signal.SIGINT: signal.signal(signal.SIGINT, handler)}
    for signum in SIGNALS[1:]:
        if signal.getsignal(signum) is signal.SIG_DFL:
            previous[signum] = signal.signal(signum, handler)
    return previous


@contextlib.contextmanager
def watch() -> Iterator[None]:
    """Run a program's block so that Ctrl-C, SIGTERM and SIGHUP always end it (see the module
    docstring).

    Each of :data:`SIGNALS` raises ``KeyboardInterrupt`` (as SIGINT does in Python) and is
    recorded (:func:`interrupt_signal`); an interrupt that some library swallowed is raised
    again by the next :func:`held_interrupts` block,
    :meth:`~roughbrdf.output.ResultFolder.commit` or :func:`raise_if_interrupted`. Only acts in
    the main thread; nests (the outer block is the one that counts). On exit the caller's
    handlers are back.
    """
    global _watching, _seen
    if _watching or not _in_main_thread() or signal.getsignal(signal.SIGINT) is None:
        yield
        return
    try:
        previous = _install(_on_signal)
    except (ValueError, OSError):  # no signal handling here (e.g. an embedded interpreter)
        yield
        return
    _hooks.append(sys.unraisablehook)
    sys.unraisablehook = _unraisable
    _watching, _seen = 1, False
    _late.clear()
    _received.clear()
    try:
        yield
    finally:
        _watching, _seen = 0, False
        _late.clear()
        _received.clear()
        sys.unraisablehook = _hooks.pop()
        # put the caller's handlers back (last: from here a signal is the caller's), unless
        # the block replaced ours (the command line's SIG_IGN, ignore_interrupts)
        for signum, handler in previous.items():
            if signal.getsignal(signum) in (_on_signal, _record_late):
                signal.signal(signum, handler)


def interrupted() -> bool:
    """Whether Ctrl-C (or SIGTERM, SIGHUP) came inside the current :func:`watch` block."""
    return _seen


def interrupt_signal() -> int:
    """The number of the first of :data:`SIGNALS` that interrupted the current :func:`watch`
    block; ``signal.SIGINT`` when none did (a ``KeyboardInterrupt`` raised otherwise, or a
    Ctrl-C outside :func:`watch`).

    Examples
    --------
    >>> import signal
    >>> with watch():
    ...     interrupt_signal() == signal.SIGINT
    True
    """
    return _received[0] if _received else int(signal.SIGINT)


def raise_if_interrupted() -> None:
    """Raise ``KeyboardInterrupt`` if Ctrl-C was pressed inside :func:`watch` (and swallowed),
    unless inside :func:`cleaning_up`."""
    if _seen and not _cleaning:  # a clean-up goes on: its interrupt is on its way
        raise KeyboardInterrupt


@contextlib.contextmanager
def cleaning_up() -> Iterator[None]:
    """Run the clean-up after an interrupt (or an error) to its end.

    Signals are held during the block as by :func:`held_interrupts` (one that comes during it
    is raised right after it: a second Ctrl-C cannot cut the clean-up short), but an interrupt
    that came before the block is not raised again inside it, nor at its end: neither by the
    :func:`held_interrupts` blocks it runs nor by :func:`raise_if_interrupted`. Without that,
    the first of them re-raises the interrupt recorded by :func:`watch` and the steps after it
    (the next folder to tidy) never run. The exception the caller is handling goes on as it
    was.

    Examples
    --------
    >>> with watch(), cleaning_up():
    ...     with held_interrupts():
    ...         pass
    """
    global _cleaning
    outer = _cleaning
    _cleaning = True
    try:
        with held_interrupts():
            yield
    finally:
        _cleaning = outer


def _record_late(signum: int, frame: Any) -> None:
    _late.append(signum)


def record_interrupts() -> None:
    """From now until the :func:`watch` block ends, record SIGINT (SIGTERM, SIGHUP) instead of
    raising it.

    For the end of a program whose work is done: a Ctrl-C there changes nothing
    (:func:`late_interrupts` tells whether one came). A signal that was already pending when
    this is called is raised first (``signal.signal`` runs pending handlers before it replaces
    them), so it counts as one that came before. Only acts inside :func:`watch` (outside it,
    Python's own handling is left as it is) and in the main thread.
    """
    # outside watch() the handlers are the caller's: not ours to change; other threads cannot
    if _watching and _in_main_thread():
        for signum in SIGNALS:
            if signal.getsignal(signum) is _on_signal:
                signal.signal(signum, _record_late)


def ignore_interrupts() -> None:
    """Ignore SIGINT from now on, and SIGTERM and SIGHUP where :func:`watch` handles them.

    For the very end of a program (the console script, once its status is known): only
    Python's shutdown is left, which a signal could only turn into a death by that signal. The
    :func:`watch` block leaves them ignored when it ends. Only acts in the main thread.
    """
    if not _in_main_thread():  # signal.signal works in the main thread only
        return
    for signum in SIGNALS:
        # SIGINT as the command line always did; the others only where watch() installed ours
        # (an ignored SIGHUP or a caller's SIGTERM handler is not ours to change)
        if signum == signal.SIGINT or signal.getsignal(signum) in (_on_signal, _record_late):
            with contextlib.suppress(ValueError, OSError):  # no signal handling here
                signal.signal(signum, signal.SIG_IGN)


def late_interrupts() -> int:
    """How many of :data:`SIGNALS` came after :func:`record_interrupts` in the current
    :func:`watch`."""
    return len(_late)


def checkpoint(name: str) -> None:
    """A named point of a program's tail where a test may send SIGINT; a no-op otherwise.

    :func:`roughbrdf.cli.main` calls it between its last statements, so that a test can inject
    Ctrl-C at each of them deterministically instead of by timing.

    Parameters
    ----------
    name : str
        The point, as the hook receives it (``"main: status settled"``).
    """
    if _checkpoint_hook:  # no hook outside tests: nothing to do
        _checkpoint_hook[0](name)


def set_checkpoint_hook(hook: Callable[[str], None] | None) -> Callable[[str], None] | None:
    """Install ``hook`` (called with each :func:`checkpoint`'s name), or remove it. For tests.

    Parameters
    ----------
    hook : callable or None
        Called as ``hook(name)`` at every :func:`checkpoint`; None removes the hook.

    Returns
    -------
    callable or None
        The hook installed before (to put back when the test ends).
    """
    previous = _checkpoint_hook[0] if _checkpoint_hook else None
    _checkpoint_hook.clear()
    if hook is not None:
        _checkpoint_hook.append(hook)
    return previous
