"""The command line at its edges: Ctrl-C at any moment, two runs at once,
errors of the operating system, and the exit statuses of ``roughbrdf`` (``roughbrdf.cli``).

Times printed by the signal test (``pytest -s``) are figures for the docs, not assertions.
"""

from __future__ import annotations

import errno
import inspect
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time

import pytest
from typer.testing import CliRunner

from roughbrdf.cli import app, main
from roughbrdf.demo import default_measurement_path
from roughbrdf.output import JOURNAL, LOCK, MANIFEST, TMP_PREFIX, file_sha256, read_manifest

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

runner = CliRunner()
DEFAULT = default_measurement_path()
_SCRIPT = os.path.join(os.path.dirname(sys.executable), "roughbrdf")
#: the console script as users run it (``python -m roughbrdf.cli`` where it is not installed)
CLI = [_SCRIPT] if os.access(_SCRIPT, os.X_OK) else [sys.executable, "-m", "roughbrdf.cli"]
#: a fit that exits 0 (a TR75 fit exits 1: its albedo exceeds 1 near grazing incidence)
FIT = ["fit", str(DEFAULT), "-m", "microfacet", "--starts", "2"]
PNG = b"\x89PNG\r\n\x1a\n"
#: a bound on how long one subprocess may take: only against a hung test
HANG = 60


def _snapshot(folder) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def _state(folder, old: dict[str, bytes]) -> str:
    """``"old"`` or ``"new"`` for a complete result set; fails for anything else."""
    files = _snapshot(folder)
    assert not [n for n in files if n.startswith(TMP_PREFIX) or n in (LOCK, JOURNAL)], \
        sorted(files)
    if files == old:
        return "old"
    assert set(files) == set(old), sorted(files)  # the same command writes the same names
    listed = read_manifest(folder)  # {name: sha256} of the files the set holds
    assert sorted(listed) == sorted(n for n in files if n != MANIFEST)
    assert all(digest in (None, file_sha256(folder / n)) for n, digest in listed.items())
    assert json.loads(files["fit.json"])["channels"]
    assert files["report.txt"].startswith(b"[[Fit]]")
    assert all(files[n].startswith(PNG) for n in files if n.endswith(".png"))
    return "new"


def _one_line(text: str) -> str:
    lines = text.replace("\r", "\n").strip().splitlines()
    assert "Traceback" not in text and "Exception ignored" not in text, text
    return lines[-1] if lines else ""


def _finish(p: subprocess.Popen) -> tuple[str, str]:
    try:
        return p.communicate(timeout=HANG)
    except subprocess.TimeoutExpired:
        p.kill()
        p.communicate()
        pytest.fail(f"roughbrdf still running {HANG} s after SIGINT")


# ---------------------------------------------------------------------------------------------
# Ctrl-C
# ---------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_ctrl_c_at_any_moment_of_a_fit_leaves_old_or_new_results(tmp_path):
    """SIGINT from start to finish of ``roughbrdf fit --force`` into a folder holding a complete
    earlier result: exit 130 and ``interrupted`` (0 if it had finished), and the folder holds
    the old set or the new one, complete, never a mix or a leftover. The instants are only a
    spread: what is checked holds at whatever instant the signal lands
    (:func:`_allowed_outcome`); ``tests/cli/test_cli_interrupts.py`` places it deterministically."""
    base = tmp_path / "base"
    t0 = time.monotonic()
    first = subprocess.run([*CLI, *FIT, "--out", str(base)], capture_output=True, text=True,
                           timeout=4 * HANG)
    duration = time.monotonic() - t0
    assert first.returncode == 0, first.stderr
    old = _snapshot(base)
    assert set(old) == {MANIFEST, "fit.json", "report.txt", "fit_relative.png"}
    figures = []
    for i, moment in enumerate([0.05, 0.3, 0.8, 1.5, "saving", "saving+0.15", "end"]):
        out = tmp_path / f"run{i}"
        shutil.copytree(base, out)
        p = subprocess.Popen([*CLI, *FIT, "--out", str(out), "--force"], text=True,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        _wait_for(moment, p, out)
        t_signal = time.monotonic()
        p.send_signal(signal.SIGINT)
        stdout, stderr = _finish(p)
        ended = time.monotonic() - t_signal
        state = _state(out, old)
        figures.append((moment, p.returncode, round(ended, 2), state))
        _allowed_outcome(p.returncode, stdout, stderr, state, figures)
    print(f"\nfit takes {duration:.2f} s; (moment, status, ended s after SIGINT, folder):",
          *figures, sep="\n  ")


#: the line of ``with watch():`` in roughbrdf.cli.main: from there on SIGINT is roughbrdf's
_WATCH_LINE = next(i for i, text in enumerate(inspect.getsourcelines(main)[0],
                                             start=main.__code__.co_firstlineno)
                   if text.strip().startswith("with watch()"))


def _allowed_outcome(code: int, stdout: str, stderr: str, state: str, figures: list) -> None:
    """The outcomes allowed at whatever instant the signal landed (a loaded machine shifts
    every instant, so none is tied to a moment): ``_state`` has already checked that the
    folder holds the old set or the new one, complete.

    * 130 and the one line ``interrupted``: the old set, or the new one if the signal came
      after the commit but before the run's status was settled;
    * 0: the signal came once the run was over (or the run ended before it): the new set;
    * death by the signal (or 1, Python's start-up cut): only before roughbrdf's handler is in
      place (Python starting up, ``import roughbrdf``; about 40 ms on an idle machine, longer
      on a loaded one). Nothing can have been written then: the old set, no output, and a
      traceback, if Python printed one, passes through :func:`main` (if at all) only above
      its ``with watch():`` line, where the handler is installed.
    """
    if code == 130:
        assert stderr.strip() == "interrupted", (stderr, figures)
    elif code == 0:
        assert state == "new" and "Traceback" not in stderr, (stderr, figures)
        assert "interrupted" not in stderr, (stderr, figures)
    elif code in (-signal.SIGINT, 1):
        assert state == "old" and not stdout, (stdout, stderr, figures)
        in_main = re.findall(r'cli[/\\]__init__\.py", line (\d+), in main\b', stderr)
        assert all(int(n) < _WATCH_LINE for n in in_main), (stderr, figures)
    else:
        pytest.fail(f"exit status {code}: {stderr} {figures}")


def _wait_for(moment: float | str, p: subprocess.Popen, out) -> None:
    """Sleep ``moment`` seconds, or until the run starts saving (its lock appears, plus
    ``+S`` seconds), or until it has printed its last line (``"end"``: Python shuts down)."""
    if moment == "end":
        assert p.stdout is not None
        for line in p.stdout:
            if line.startswith("wrote "):
                return
    elif isinstance(moment, str) and moment.startswith("saving"):
        t_end = time.monotonic() + HANG
        while not (out / LOCK).exists() and p.poll() is None and time.monotonic() < t_end:
            time.sleep(0.002)
        time.sleep(float(moment.partition("+")[2] or 0))
    else:
        time.sleep(float(moment))


def _prelude_run(prelude: str, args: list[str]) -> subprocess.CompletedProcess:
    code = prelude + "\nimport sys\nfrom roughbrdf.cli import main\nsys.exit(main())\n"
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True,
                          timeout=4 * HANG)


_IMPORT_HOOK = """
import os, signal, sys
class _CtrlCOnImport:
    def find_spec(self, name, path=None, target=None):
        if name == {module!r}:
            sys.meta_path.remove(self)
            os.kill(os.getpid(), signal.SIGINT)
        return None
sys.meta_path.insert(0, _CtrlCOnImport())
"""


@pytest.fixture
def old_result(tmp_path):
    """A folder holding a complete fit result, and its snapshot."""
    out = tmp_path / "res"
    res = runner.invoke(app, [*FIT[:-1], "1", "--out", str(out), "-q"])
    assert res.exit_code == 0, res.output
    return out, _snapshot(out)


@pytest.mark.parametrize("module", ["numba", "scipy.optimize", "matplotlib.figure"])
def test_ctrl_c_while_a_heavy_module_loads(old_result, module):
    out, old = old_result
    done = _prelude_run(_IMPORT_HOOK.format(module=module), [*FIT, "--out", str(out), "--force"])
    assert done.returncode == 130, done.stderr
    assert done.stderr.strip() == "interrupted"
    assert _state(out, old) == "old"


def test_ctrl_c_in_the_progress_bar(old_result):
    prelude = """
import os, signal, sys
class _Terminal:  # stderr as a terminal: the fit shows its tqdm bar
    def __init__(self, stream):
        self._stream = stream
    def isatty(self):
        return True
    def __getattr__(self, name):
        return getattr(self._stream, name)
sys.stderr = _Terminal(sys.stderr)
import tqdm.std
_update = tqdm.std.tqdm.update
def update(self, n=1):
    os.kill(os.getpid(), signal.SIGINT)
    return _update(self, n)
tqdm.std.tqdm.update = update
"""
    out, old = old_result
    done = _prelude_run(prelude, [*FIT, "--out", str(out), "--force"])
    assert done.returncode == 130, done.stderr
    assert "fit microfacet" in done.stderr  # the bar was there
    assert _one_line(done.stderr) == "interrupted"
    assert _state(out, old) == "old"


def test_ctrl_c_swallowed_by_a_library_still_ends_the_run(old_result):
    """Numba's case: a KeyboardInterrupt raised where Python can only print
    "Exception ignored" (a C callback, a finalizer) must still stop the run, before it writes."""
    prelude = """
import os, signal
import roughbrdf.fitting as _fitting
_fit = _fitting.fit
class _Swallows:
    def __del__(self):
        os.kill(os.getpid(), signal.SIGINT)
        sum(range(1000))  # the handler runs in here: its KeyboardInterrupt is "ignored"
def fit(*args, **kwargs):
    _Swallows()
    return _fit(*args, **kwargs)
_fitting.fit = fit
"""
    out, old = old_result
    done = _prelude_run(prelude, [*FIT, "--out", str(out), "--force"])
    assert done.returncode == 130, done.stderr
    assert done.stderr.strip() == "interrupted"
    assert _state(out, old) == "old"


# ---------------------------------------------------------------------------------------------
# one run at a time, all or nothing
# ---------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_two_runs_into_one_folder_at_once(tmp_path):
    out = tmp_path / "out"
    procs = [subprocess.Popen([*CLI, *FIT, "--no-plots", "-q", "--out", str(out)], text=True,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE) for _ in range(2)]
    done = [(p, *_finish(p)) for p in procs]
    assert sorted(p.returncode for p, _, _ in done) == [0, 2], [e for _, _, e in done]
    (err,) = [e for p, _, e in done if p.returncode == 2]
    line = _one_line(err)
    assert line == err.strip()
    assert "another roughbrdf run is writing into" in line or "holds results already" in line
    assert sorted(os.listdir(out)) == [MANIFEST, "fit.json", "report.txt"]


def test_a_lock_held_by_a_live_run_is_one_clear_line(tmp_path, monkeypatch):
    import roughbrdf.fitting

    monkeypatch.setattr(roughbrdf.fitting, "fit", _must_not_fit)
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        (tmp_path / LOCK).write_text(f"{sleeper.pid}\n")
        res = runner.invoke(app, [*FIT, "--out", str(tmp_path)])
    finally:
        sleeper.kill()
        sleeper.wait()
    assert res.exit_code == 2
    assert res.output.startswith(f"error: another roughbrdf run is writing into {tmp_path} ")
    assert len(res.output.strip().splitlines()) == 1


@pytest.mark.parametrize("exc, code", [(OSError(errno.ENOSPC, "No space left on device"), 3),
                                       (KeyboardInterrupt(), 130)])
def test_a_figure_that_fails_midway_leaves_the_old_set(old_result, monkeypatch, exc, code):
    from matplotlib.figure import Figure

    out, old = old_result

    def fails(self, *args, **kwargs):
        raise exc

    monkeypatch.setattr(Figure, "savefig", fails)
    res = runner.invoke(app, [*FIT, "--out", str(out), "--force", "-q"])
    assert res.exit_code == code, res.output
    assert _snapshot(out) == old


def _must_not_fit(*args, **kwargs):
    raise AssertionError("the run should have stopped before fitting")


# ---------------------------------------------------------------------------------------------
# errors of the operating system and exit statuses
# ---------------------------------------------------------------------------------------------
def _cli(*args):
    return runner.invoke(app, [str(a) for a in args])


def _error(res, code: int) -> str:
    assert res.exit_code == code, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), res.output
    return lines[0]


def test_a_file_where_a_folder_is_expected(tmp_path, monkeypatch):
    import roughbrdf.fitting

    monkeypatch.setattr(roughbrdf.fitting, "fit", _must_not_fit)  # refused before fitting
    f = tmp_path / "somefile"
    f.write_text("a file")
    for out in (f, f / "sub"):
        line = _error(_cli(*FIT, "--out", out), 3)
        assert str(out) in line and "not a folder" in line
    line = _error(_cli("plot", "lambertian", "--out", f / "x.png"), 3)
    assert str(f) in line and "not a folder" in line
    line = _error(_cli("reproduce", "--paper", "tr75", "--out", f), 3)
    assert str(f) in line
    assert f.read_text() == "a file"


def test_a_folder_where_a_file_is_expected(tmp_path):
    for out in (tmp_path, tmp_path / "looks.png"):
        out.mkdir(exist_ok=True)
        line = _error(_cli("plot", "lambertian", "--out", out, "--force"), 3)
        assert str(out) in line and "folder" in line


@pytest.mark.skipif(os.geteuid() == 0, reason="root ignores file modes: permission denied "
                                              "cannot be provoked (simulated below)")
def test_permission_denied_for_real(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        line = _error(_cli("plot", "lambertian", "--out", ro / "x.png"), 3)
        assert str(ro) in line and "ermission denied" in line
        line = _error(_cli(*FIT, "--out", ro / "sub"), 3)
        assert str(ro) in line
    finally:
        ro.chmod(0o700)
    assert list(ro.iterdir()) == []


@pytest.mark.parametrize("err", [errno.EACCES, errno.EROFS])
def test_permission_denied_or_read_only_simulated(tmp_path, monkeypatch, err):
    """What the system says when the folder cannot be written (as root, simulated)."""
    from roughbrdf import output

    def refuse(*args, **kwargs):
        raise OSError(err, os.strerror(err), os.path.join(kwargs.get("dir", "."), "tmpXYZ"))

    monkeypatch.setattr(output.tempfile, "mkstemp", refuse)
    out = tmp_path / "fig.png"
    line = _error(_cli("plot", "lambertian", "--out", out), 3)
    assert line == f"error: {out}: {os.strerror(err)}"
    assert not out.exists()


def test_disk_full_leaves_no_partial_file(tmp_path, monkeypatch):
    from roughbrdf import output

    out = tmp_path / "fig.png"
    out.write_bytes(b"old figure")

    def full(fd):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(output.os, "fsync", full)
    line = _error(_cli("plot", "lambertian", "--out", out, "--force"), 3)
    assert line == f"error: {out}: No space left on device"
    assert out.read_bytes() == b"old figure"
    assert sorted(os.listdir(tmp_path)) == ["fig.png"]


def test_debug_shows_the_traceback(tmp_path):
    res = _cli("--debug", "plot", "lambertian", "--out", tmp_path, "--force")
    assert res.exit_code == 3
    assert "Traceback" in res.output and "IsADirectoryError" in res.output
    assert res.output.strip().splitlines()[-1].startswith("error: ")


def test_exit_status_1_when_a_fit_does_not_converge(tmp_path, monkeypatch):
    from roughbrdf.fitting.results.result import FitResult

    monkeypatch.setattr(FitResult, "success", property(lambda self: False))
    res = _cli(*FIT[:-1], "1", "--no-plots", "-q", "--out", tmp_path / "o")
    assert res.exit_code == 1, res.output
    assert (tmp_path / "o" / "fit.json").is_file()  # the results are written all the same


def test_exit_status_4_for_a_bug(tmp_path, monkeypatch):
    from roughbrdf import plot

    def bug(*args, **kwargs):
        raise RuntimeError("something roughbrdf got wrong")

    monkeypatch.setattr(plot, "plot_in_plane", bug)
    line = _error(_cli("plot", "lambertian", "--out", tmp_path / "x.png"), 4)
    assert "internal error: RuntimeError: something roughbrdf got wrong" in line
    assert "--debug" in line


def test_main_returns_the_exit_status(tmp_path, capsys):
    assert main(["plot", "lambertian", "--out", str(tmp_path)]) == 3
    assert main(["plot", "lambertian", "--out", str(tmp_path / "a.png")]) == 0
    assert main(["plot", "lambertian", "--out", str(tmp_path / "a.png")]) == 2
    assert main(["fit"]) == 2  # usage: missing FILE and options
    assert main(["--help"]) == 0
    err = capsys.readouterr().err
    assert "a.png exists; not overwriting it (pass --force)" in err
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # put back


def test_main_turns_ctrl_c_into_130(monkeypatch, capsys):
    import roughbrdf.cli as cli

    def interrupted(argv):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "_run", interrupted)
    assert main(["models"]) == 130
    assert capsys.readouterr().err == "interrupted\n"
