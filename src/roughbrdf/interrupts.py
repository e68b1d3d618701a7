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
           "record_interrupts", "late_interrupts", "checkpoint", "set_checkpoint_hook"]

_depth = 0
_pending: list[Any] = []
_watching = 0
_seen = False
_hooks: list[Any] = []  # the unraisable hook that watch() replaced
_late: list[int] = []  # SIGINTs recorded after record_interrupts()
_checkpoint_hook: list[Callable[[str], None]] = []  # test-only (set_checkpoint_hook)


def _record(signum: int, frame: Any) -> None:
    _pending.append(signum)


def _in_main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


@contextlib.contextmanager
def held_interrupts() -> Iterator[None]:
    """Defer SIGINT during the block; raise ``KeyboardInterrupt`` after it if one came (or,
    inside :func:`watch`, if one was swallowed earlier)."""
    global _depth
    if _depth or not _in_main_thread() or signal.getsignal(signal.SIGINT) is None:
        # nested: the outer block delivers; other threads never receive signals; a handler
        # installed outside Python could not be put back
        yield
        return
    try:
        previous = signal.signal(signal.SIGINT, _record)
    except (ValueError, OSError):  # no signal handling here (e.g. an embedded interpreter)
        yield
        return
    _depth = 1
    try:
        yield
    finally:
        _depth = 0
        signal.signal(signal.SIGINT, previous)
        if _pending:
            _pending.clear()
            _deliver(previous)
        elif _seen:
            raise KeyboardInterrupt


def _deliver(handler: Any) -> None:
    """Act on a SIGINT that arrived while held, as ``handler`` would have."""
    if callable(handler):  # the handler that was in place (Python's raises)
        handler(signal.SIGINT, None)
    elif handler != signal.SIG_IGN:
        raise KeyboardInterrupt


# --------------------------------------------------------------------------------------------
# programs that must end on Ctrl-C
# --------------------------------------------------------------------------------------------
def _on_sigint(signum: int, frame: Any) -> None:
    global _seen
    _seen = True
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


@contextlib.contextmanager
def watch() -> Iterator[None]:
    """Run a program's block so that Ctrl-C always ends it (see the module docstring).

    SIGINT raises ``KeyboardInterrupt`` as usual and is also recorded; an interrupt that some
    library swallowed is raised again by the next :func:`held_interrupts` block,
    :meth:`~roughbrdf.output.ResultFolder.commit` or :func:`raise_if_interrupted`. Only acts in
    the main thread; nests (the outer block is the one that counts).
    """
    global _watching, _seen
    if _watching or not _in_main_thread() or signal.getsignal(signal.SIGINT) is None:
        yield
        return
    try:
        previous = signal.signal(signal.SIGINT, _on_sigint)
    except (ValueError, OSError):
        yield
        return
    _hooks.append(sys.unraisablehook)
    sys.unraisablehook = _unraisable
    _watching, _seen = 1, False
    _late.clear()
    try:
        yield
    finally:
        _watching, _seen = 0, False
        _late.clear()
        sys.unraisablehook = _hooks.pop()
        # put the caller's handler back (last: from here a SIGINT is the caller's), unless the
        # block replaced ours (the command line's SIG_IGN)
        if signal.getsignal(signal.SIGINT) in (_on_sigint, _record_late):
            signal.signal(signal.SIGINT, previous)


def interrupted() -> bool:
    """Whether Ctrl-C was pressed inside the current :func:`watch` block."""
    return _seen


def raise_if_interrupted() -> None:
    """Raise ``KeyboardInterrupt`` if Ctrl-C was pressed inside :func:`watch` (and swallowed)."""
    if _seen:
        raise KeyboardInterrupt


def _record_late(signum: int, frame: Any) -> None:
    _late.append(signum)


def record_interrupts() -> None:
    """From now until the :func:`watch` block ends, record SIGINT instead of raising it.

    For the end of a program whose work is done: a Ctrl-C there changes nothing
    (:func:`late_interrupts` tells whether one came). A SIGINT that was already pending when
    this is called is raised first (``signal.signal`` runs pending handlers before it replaces
    them), so it counts as one that came before. Only acts inside :func:`watch` (outside it,
    Python's own handling is left as it is) and in the main thread.
    """
    # outside watch() the handler is the caller's: not ours to change; other threads cannot
    if _watching and _in_main_thread() and signal.getsignal(signal.SIGINT) is _on_sigint:
        signal.signal(signal.SIGINT, _record_late)


def late_interrupts() -> int:
    """How many SIGINTs came after :func:`record_interrupts` in the current :func:`watch`."""
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
