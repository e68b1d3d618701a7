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

Examples
--------
>>> with held_interrupts():
...     pass
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from typing import Any

__all__ = ["held_interrupts"]

_depth = 0
_pending: list[Any] = []


def _record(signum: int, frame: Any) -> None:
    _pending.append(signum)


@contextlib.contextmanager
def held_interrupts() -> Iterator[None]:
    """Defer SIGINT during the block; raise ``KeyboardInterrupt`` after it if one came."""
    global _depth
    if _depth or threading.current_thread() is not threading.main_thread():
        yield  # nested: the outer block delivers; other threads never receive signals
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
            if callable(previous):  # the handler that was in place (Python's raises)
                previous(signal.SIGINT, None)
            elif previous != signal.SIG_IGN:
                raise KeyboardInterrupt
