"""A spy shared by the readers' tests: how many Python calls parsing a file's rows makes.

A speed figure belongs in ``benchmarks/`` (a loaded machine makes timed tests flaky); what the
tests check instead is that a reader parses its rows as one block: the number of Python
function calls inside ``parse_rows`` does not grow with the rows.
"""

from __future__ import annotations

import inspect
import sys

#: code flags of a generator or coroutine (a resumption is a 'call' to the profiler)
GENERATOR = inspect.CO_GENERATOR | inspect.CO_COROUTINE | inspect.CO_ASYNC_GENERATOR


def python_calls_parsing_rows(monkeypatch, module) -> list[tuple[int, int]]:
    """Spy on ``module.parse_rows``: for each call, (rows given, Python function calls made
    inside it, generators' resumptions aside). The rows of a file are parsed as one block when
    that count does not grow with the rows (the row-by-row parse makes several per row)."""
    real = module.parse_rows
    seen: list[tuple[int, int]] = []

    def spy(texts, *args, **kwargs):
        calls = [0]

        def profile(frame, event, arg):
            if event == "call" and not frame.f_code.co_flags & GENERATOR:
                calls[0] += 1

        previous = sys.getprofile()
        sys.setprofile(profile)
        try:
            return real(texts, *args, **kwargs)
        finally:
            sys.setprofile(previous)
            seen.append((len(texts), calls[0]))

    monkeypatch.setattr(module, "parse_rows", spy)
    return seen
