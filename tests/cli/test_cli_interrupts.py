"""Ctrl-C as the command line ends.

A SIGINT that arrives once ``roughbrdf.cli.main``'s run has returned must not escape ``main`` as
``KeyboardInterrupt`` (a traceback, death by signal): the work is done and committed, so
``main`` returns the run's own status (0 here) and says nothing. One that arrives in the last
statements of the run itself (``_run``'s tail, after the command returned but before its
status is settled) gives 130 and ``interrupted``, with the new file complete.

The signal is injected deterministically, never by timing, in two ways, each in-process
(``main([...])``) and in a subprocess (the console script's ``main()``, which also ignores SIGINT
from its last statement on):

* at **every line** that ``main`` executes after ``_run`` has returned: ``sys.settrace`` on
  ``main``'s frame counts its line events and calls ``signal.raise_signal(SIGINT)`` at the k-th,
  for every k (this also runs against a ``main`` without checkpoints);
* at every named :func:`roughbrdf.interrupts.checkpoint` of ``main`` and ``_run``.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

import roughbrdf.cli as cli
from roughbrdf import interrupts
from roughbrdf.demo import default_measurement_path

#: a cheap command that writes one file (through roughbrdf.output's commit)
SOURCE = default_measurement_path()
#: a bound on one subprocess: only against a hung test
HANG = 120


def _convert(out: Path) -> list[str]:
    return ["convert", str(SOURCE), str(out), "--force"]


def _line_injector(k: int | None, seen: list[int]) -> Callable[..., Any]:
    """A global trace function: after ``cli._run`` has returned, count ``cli.main``'s line
    events (their line numbers go to ``seen``) and send SIGINT at the ``k``-th (from 0)."""
    main_code, run_code = cli.main.__code__, cli._run.__code__
    returned = [False]

    def local(frame: Any, event: str, arg: Any) -> Any:
        if frame.f_code is run_code:
            if event == "return":
                returned[0] = True
            return local
        if event == "line" and returned[0]:
            seen.append(frame.f_lineno)
            if len(seen) - 1 == k:
                signal.raise_signal(signal.SIGINT)  # its handler runs here, at this line
        return local

    def tracer(frame: Any, event: str, arg: Any) -> Any:
        if frame.f_code is main_code or frame.f_code is run_code:
            return local
        return None

    return tracer


def _main_traced(argv: list[str], tracer: Callable[..., Any]) -> int:
    """``main(argv)`` under ``tracer``; fails (instead of ending pytest) if
    ``KeyboardInterrupt`` escapes."""
    previous = sys.gettrace()
    sys.settrace(tracer)
    try:
        return cli.main(argv)
    except KeyboardInterrupt:
        pytest.fail("a SIGINT after _run returned escaped main as KeyboardInterrupt")
    finally:
        sys.settrace(previous)


def _no_traceback(err: str) -> None:
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert "Exception ignored" not in err, err


def _complete_csv(path: Path) -> None:
    text = path.read_text()
    assert text.count("\n") > 400 and text.endswith("\n"), path  # the whole file, committed
    assert not [p.name for p in path.parent.iterdir() if p.name.startswith(".roughbrdf")]


def test_sigint_at_every_line_after_run_returns_in_process(tmp_path, capsys):
    out = tmp_path / "m.csv"
    lines: list[int] = []
    assert _main_traced(_convert(out), _line_injector(None, lines)) == 0
    assert lines, "main ran no line after _run returned"
    capsys.readouterr()
    for k in range(len(lines)):
        code = _main_traced(_convert(out), _line_injector(k, []))
        err = capsys.readouterr().err
        _no_traceback(err)
        assert code == 0, (k, lines[k], err)  # the run's own status: the work is done
        assert "interrupted" not in err, (k, lines[k], err)
        _complete_csv(out)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # the caller's, back


_SUBPROCESS = """
import json, signal, sys
from roughbrdf import interrupts
import roughbrdf.cli as cli
mode, at = sys.argv[1], json.loads(sys.argv[2])
del sys.argv[1:3]
main_code, run_code = cli.main.__code__, cli._run.__code__
seen, returned = [], [False]
def local(frame, event, arg):
    if frame.f_code is run_code:
        if event == "return":
            returned[0] = True
        return local
    if event == "line" and returned[0]:
        seen.append(frame.f_lineno)
        if mode == "line" and len(seen) - 1 == at:
            signal.raise_signal(signal.SIGINT)
    return local
def tracer(frame, event, arg):
    if frame.f_code is main_code or frame.f_code is run_code:
        return local
    return None
names = []
def hook(name):
    names.append(name)
    if mode == "checkpoint" and name == at and names.count(name) == 1:
        signal.raise_signal(signal.SIGINT)
if mode == "checkpoint":
    interrupts.set_checkpoint_hook(hook)
if mode == "line":
    sys.settrace(tracer)
try:
    code = cli.main()
finally:
    sys.settrace(None)
    print(json.dumps({"lines": seen, "checkpoints": names}))
sys.exit(code)
"""


def _subprocess(mode: str, at: Any, out: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", _SUBPROCESS, mode, json.dumps(at),
                           *_convert(out)], capture_output=True, text=True, timeout=HANG)


@pytest.mark.slow
def test_sigint_at_every_line_after_run_returns_in_a_subprocess(tmp_path):
    """The console script's ``main()`` (``argv`` None): it also puts SIG_IGN in place."""
    out = tmp_path / "m.csv"
    first = _subprocess("line", None, out)
    assert first.returncode == 0, first.stderr
    lines = json.loads(first.stdout.splitlines()[-1])["lines"]
    assert lines
    for k in range(len(lines)):
        done = _subprocess("line", k, out)
        _no_traceback(done.stderr)
        assert done.returncode == 0, (k, lines[k], done.returncode, done.stderr)
        assert "interrupted" not in done.stderr
        _complete_csv(out)


def _expected(name: str) -> tuple[int, bool]:
    """Exit status and whether ``interrupted`` is said, for SIGINT at checkpoint ``name``:
    in ``_run``'s tail (``run: ...``) the status is not settled yet: 130; once ``_run`` has
    returned (``main: ...``) the run's own status."""
    return (130, True) if name.startswith("run: ") else (0, False)


def _said_interrupted(err: str) -> bool:
    lines = err.strip().splitlines()
    return bool(lines) and lines[-1] == "interrupted"


def _with_checkpoint_signal(at: str | None, names: list[str]) -> Callable[[str], None] | None:
    def hook(name: str) -> None:
        names.append(name)
        if name == at and names.count(name) == 1:  # once: a retry passes it again
            signal.raise_signal(signal.SIGINT)

    return interrupts.set_checkpoint_hook(hook)


def test_sigint_at_every_checkpoint_in_process(tmp_path, capsys):
    out = tmp_path / "m.csv"
    names: list[str] = []
    previous = _with_checkpoint_signal(None, names)
    try:
        assert cli.main(_convert(out)) == 0
    finally:
        interrupts.set_checkpoint_hook(previous)
    assert names == ["run: command returned", "run: settling", "main: status settled",
                     "main: reported"]
    capsys.readouterr()
    for name in names:
        previous = _with_checkpoint_signal(name, [])
        try:
            code = cli.main(_convert(out))
        except KeyboardInterrupt:
            pytest.fail(f"SIGINT at {name!r} escaped main as KeyboardInterrupt")
        finally:
            interrupts.set_checkpoint_hook(previous)
        err = capsys.readouterr().err
        _no_traceback(err)
        status, said = _expected(name)
        assert code == status, (name, err)
        assert _said_interrupted(err) is said, (name, err)
        _complete_csv(out)


@pytest.mark.slow
def test_sigint_at_every_checkpoint_in_a_subprocess(tmp_path):
    out = tmp_path / "m.csv"
    first = _subprocess("checkpoint", None, out)
    assert first.returncode == 0, first.stderr
    names = json.loads(first.stdout.splitlines()[-1])["checkpoints"]
    assert names == ["run: command returned", "run: settling", "main: status settled",
                     "main: reported", "main: SIGINT ignored"]
    for name in names:
        done = _subprocess("checkpoint", name, out)
        _no_traceback(done.stderr)
        status, said = _expected(name)
        assert done.returncode == status, (name, done.returncode, done.stderr)
        assert _said_interrupted(done.stderr) is said, (name, done.stderr)
        _complete_csv(out)


def test_checkpoint_is_a_no_op_without_a_hook():
    previous = interrupts.set_checkpoint_hook(None)
    try:
        interrupts.checkpoint("anything")  # nothing installed: nothing happens
    finally:
        interrupts.set_checkpoint_hook(previous)


def test_record_interrupts_outside_watch_leaves_the_handler():
    handler = signal.getsignal(signal.SIGINT)
    interrupts.record_interrupts()
    assert signal.getsignal(signal.SIGINT) is handler
    with interrupts.watch():
        interrupts.record_interrupts()
        signal.raise_signal(signal.SIGINT)  # recorded, not raised
        assert interrupts.late_interrupts() == 1 and not interrupts.interrupted()
    assert signal.getsignal(signal.SIGINT) is handler
