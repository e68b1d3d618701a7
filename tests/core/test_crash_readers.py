"""Readers of a results folder after a write was killed: one whole set, or one line saying why.

``roughbrdf fit --force`` rewrites a fit folder (old set: a Lambertian fit plus the comparison
PNG that ``plot --fit`` added; new set: an Oren-Nayar fit, without the PNG) in a subprocess
killed with ``os._exit(9)`` at its k-th rename or removal inside the folder, for every k (the
kill is injected, not timed, as in ``tests/core/test_output_journal.py``; the checkpoint hook of
:mod:`roughbrdf.interrupts` marks only the command line's tail, after the commit, so it cannot
stop a commit midway). Each reader then reads its own copy of what the kill left:
``rb.load_fit``, ``roughbrdf plot --fit``, ``roughbrdf export --fit`` and explore's loading
(:func:`roughbrdf.explore.app_state.load_session`, no server).

Where the expectations come from:

* the journal's contract (:mod:`roughbrdf.journal`, module docstring): recovery leaves the old
  set or the new one, never a mix; so a reader of a writable folder reads wholly the old set
  or wholly the new one: the folder's files (``fit.json``, ``report.txt``, the PNG, the
  manifest) are byte for byte one reference set, and what the reader returns is what it
  returns for that reference folder;
* :mod:`roughbrdf.result_check` (module docstring): a folder with a journal that cannot be
  written, a live run's lock, a file whose SHA-256 differs from the manifest's, a journal
  roughbrdf did not write: refused with one line naming the folder (the command line: that
  line on stderr and exit status 2, :data:`roughbrdf.cli.EXIT_USAGE`), the folder untouched.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import shutil
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any
from unittest import mock

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.cli import EXIT_USAGE, main
from roughbrdf.explore.app_state import load_session
from roughbrdf.output import JOURNAL, LOCK, MANIFEST
from roughbrdf.result_check import ResultFolderRefused

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

#: run in a subprocess: ``python -c HOOK FOLDER k ARGS...`` runs ``roughbrdf ARGS`` and kills
#: itself at the k-th os.replace or os.unlink of a path inside FOLDER (0: never), then prints
#: how many it saw
HOOK = r"""
import os, sys
folder, kill_at, steps = os.path.realpath(sys.argv[1]), int(sys.argv[2]), [0]
def killing(real):
    def step(path, *rest, **kw):
        if os.path.dirname(os.path.realpath(os.fspath(path))) == folder:
            steps[0] += 1
            if steps[0] == kill_at:
                os._exit(9)
        return real(path, *rest, **kw)
    return step
os.replace, os.unlink = killing(os.replace), killing(os.unlink)
from roughbrdf.cli import main
code = main(sys.argv[3:])
print("STEPS", steps[0], "CODE", code)
"""

GRID = np.radians(np.mgrid[0:61:30, 0:81:20, 0:181:90].reshape(3, -1))


def _run_killed(folder: Path, k: int, args: list[str]) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", HOOK, str(folder), str(k), *args],
                          capture_output=True, text=True, cwd=folder.parent, timeout=300)


def _snapshot(folder: Path) -> dict[str, bytes]:
    """Every file of ``folder``, roughbrdf's records included."""
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def _untimed(value: Any) -> Any:
    """``value`` (fit.json's content) without its ``elapsed_s``: the one thing that differs
    between two runs of the same fit (fitting is seeded)."""
    if isinstance(value, dict):
        return {k: _untimed(v) for k, v in value.items() if k != "elapsed_s"}
    if isinstance(value, list):
        return [_untimed(v) for v in value]
    return value


def _results(folder: Path) -> dict[str, bytes] | None:
    """The results of ``folder`` (its files but roughbrdf's records, the lock and leftover
    temporaries, which a read with nothing to recover leaves for the next write), with the
    time taken left out; None unless they are exactly the set its manifest records (a mix,
    e.g. fit.json new and report.txt old, fails the hashes of either manifest)."""
    files = {n: b for n, b in _snapshot(folder).items() if not n.startswith(".")}
    listed = json.loads((folder / MANIFEST).read_text(encoding="utf-8"))
    if listed != {n: hashlib.sha256(b).hexdigest() for n, b in files.items()}:
        return None
    out = dict(files)
    out["fit.json"] = json.dumps(_untimed(json.loads(files["fit.json"]))).encode()
    out["report.txt"] = b"\n".join(ln for ln in files["report.txt"].splitlines()
                                   if not ln.lstrip().startswith(b"time "))
    return out


# --------------------------------------------------------------------------------------------
# the readers: each returns what it read, or ("refused", the one line it said)
# --------------------------------------------------------------------------------------------
def _refusal(text: str, folder: Path) -> tuple[str, str]:
    """("refused", line); asserts it is one line naming ``folder``."""
    lines = text.strip().splitlines()
    assert len(lines) == 1 and str(folder) in lines[0], text
    return "refused", lines[0]


def _read_python(folder: Path, scratch: Path) -> Any:
    try:
        res = rb.load_fit(folder)
    except ResultFolderRefused as exc:
        return _refusal(str(exc), folder)
    return res.model_name, res.params


def _cli(args: list[str], folder: Path) -> tuple[int, tuple[str, str] | None]:
    """Exit status of ``roughbrdf ARGS`` and its refusal (None when it succeeded)."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = main(args)
    if code == 0:
        return code, None
    assert code == EXIT_USAGE, err.getvalue()
    assert err.getvalue().startswith("error: "), err.getvalue()
    return code, _refusal(err.getvalue(), folder)


def _read_plot(folder: Path, scratch: Path) -> Any:
    from roughbrdf.fitting.results import fit_json

    seen: list[dict[str, Any]] = []
    real = fit_json.read_fit_json

    def spy(*args: Any, **kw: Any) -> Any:  # the fit.json content plot --fit draws from
        content, base = real(*args, **kw)
        seen.append(_untimed(content))
        return content, base

    with mock.patch.object(fit_json, "read_fit_json", spy):
        _code, refused = _cli(["plot", "--fit", str(folder), "--out",
                               str(scratch / "plot.png"), "--force"], folder)
    return refused or seen[0]


def _read_export(folder: Path, scratch: Path) -> Any:
    out = scratch / "export.bsdf"
    _code, refused = _cli(["export", "--fit", str(folder), "--to", "zemax", "--incidences", "0",
                           "--out", str(out), "--force"], folder)
    return refused or (scratch / "export_value.bsdf").read_bytes()


def _read_explore(folder: Path, scratch: Path) -> Any:
    session = load_session(fit_dir=str(folder))
    if session.error:
        return _refusal(session.error, folder)
    return {c: m.params for c, m in session.fit_models.items()}


READERS: dict[str, Callable[[Path, Path], Any]] = {
    "load_fit": _read_python, "plot --fit": _read_plot, "export --fit": _read_export,
    "explore --fit": _read_explore}


# --------------------------------------------------------------------------------------------
# the folders
# --------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def sets(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The reference old and new sets, what each reader reads from them, and the folders a
    ``fit --force`` killed at each step left (never read: copy before reading)."""
    root = tmp_path_factory.mktemp("crash")
    data = root / "lambertian.csv"
    rb.write(rb.Measurement(*GRID, rb.model("lambertian", rho=0.3).brdf(*GRID),
                            quantity="brdf"), data)
    old = root / "old"
    assert main(["fit", str(data), "-m", "lambertian", "--starts", "1", "--no-plots", "-q",
                 "--out", str(old)]) == 0
    assert main(["plot", "--fit", str(old)]) == 0  # a third file, which the new set drops
    rewrite = ["fit", str(data), "-m", "oren-nayar", "--starts", "1", "--no-plots", "-q",
               "--force", "--out"]
    new = root / "new"
    shutil.copytree(old, new)
    done = _run_killed(new, 0, [*rewrite, str(new)])
    assert done.returncode == 0 and "CODE 0" in done.stdout, done.stderr
    steps = int(done.stdout.split("STEPS")[-1].split()[0])
    # journal, 2 backups, 2 renames, the stale PNG aside, the manifest, 3 removed backups,
    # the journal and the lock removed: at least 12 steps inside the folder
    assert steps >= 12, steps
    killed = {}
    for k in range(1, steps + 1):
        folder = root / f"killed-{k}" / "fit"
        shutil.copytree(old, folder)
        done = _run_killed(folder, k, [*rewrite, str(folder)])
        assert done.returncode == 9, (k, done.stdout, done.stderr)
        killed[k] = folder
    scratch = root / "scratch"
    scratch.mkdir()
    expected = {name: {r: read(folder, scratch) for r, read in READERS.items()}
                for name, folder in (("old", old), ("new", new))}
    return {"old": old, "new": new, "killed": killed, "expected": expected,
            "results": {"old": _results(old), "new": _results(new)}}


def _copies(sets: dict[str, Any], base: Path) -> Iterator[tuple[int, str, Path, Path]]:
    """For every kill point and reader: (k, reader, a fresh copy of the killed folder, a
    scratch folder for the reader's own output)."""
    for k, killed in sets["killed"].items():
        for reader in READERS:
            where = base / f"k{k}" / reader.split()[0]
            shutil.copytree(killed, where / "fit")
            (where / "scratch").mkdir()
            yield k, reader, where / "fit", where / "scratch"


def _which(folder: Path, sets: dict[str, Any]) -> str | None:
    """"old" or "new" when the results of ``folder`` are that set (:func:`_results`), else
    None."""
    now = _results(folder)
    return next((name for name, files in sets["results"].items() if files == now), None)


@pytest.mark.slow
def test_every_reader_after_a_kill_at_each_step_reads_one_whole_set(sets, tmp_path):
    # what a reader that does not check would read: some kill points leave neither set whole
    # (e.g. fit.json new, report.txt and the manifest old)
    mixed = [k for k, f in sets["killed"].items() if _which(f, sets) is None]
    assert mixed, "no kill point left a mix: this test could not fail"
    seen = set()
    for k, reader, folder, scratch in _copies(sets, tmp_path):
        read = READERS[reader](folder, scratch)
        which = _which(folder, sets)
        assert which is not None, (k, reader, sorted(_snapshot(folder)))
        assert not (folder / JOURNAL).exists(), (k, reader)  # recovered, not left for later
        assert read == sets["expected"][which][reader], (k, reader, which)
        seen.add(which)
    assert seen == {"old", "new"}  # killed before the journal: old; after it: rolled forward


def _read_only(monkeypatch: pytest.MonkeyPatch, folder: Path) -> None:
    """Make ``folder`` read-only. Its owner's root bypasses the permission bits, so there the
    folder is also reported not writable by ``os.access`` (what a reader asks first)."""
    folder.chmod(0o555)
    if os.access(folder, os.W_OK):
        real = os.access

        def access(path: Any, mode: int, *args: Any, **kw: Any) -> bool:
            if mode & os.W_OK and Path(path) == folder:
                return False
            return real(path, mode, *args, **kw)

        monkeypatch.setattr(os, "access", access)


@pytest.mark.slow
def test_a_read_only_folder_left_mid_write_is_refused_untouched(sets, tmp_path, monkeypatch):
    refused = 0
    for k, reader, folder, scratch in _copies(sets, tmp_path):
        journal = (folder / JOURNAL).exists()
        before = _snapshot(folder)
        with monkeypatch.context() as m:
            _read_only(m, folder)
            try:
                read = READERS[reader](folder, scratch)
            finally:
                folder.chmod(0o755)
        if journal:  # cannot be recovered: refused, naming the folder and what to do
            assert read[0] == "refused" and "chmod u+w" in read[1], (k, reader, read)
            assert _snapshot(folder) == before, (k, reader)
            refused += 1
        else:  # nothing to recover: the whole set the kill left
            which = _which(folder, sets)
            assert which is not None and read == sets["expected"][which][reader], (k, reader)
    assert refused  # some kill points leave a journal


@pytest.fixture
def old_copy(sets: dict[str, Any], tmp_path: Path) -> tuple[Path, Path]:
    """A copy of the old, complete set, and a scratch folder."""
    shutil.copytree(sets["old"], tmp_path / "fit")
    (tmp_path / "scratch").mkdir()
    return tmp_path / "fit", tmp_path / "scratch"


@pytest.mark.parametrize("name", ["report.txt", "fit.json", "comparison_value.png"])
def test_a_file_changed_after_roughbrdf_wrote_it_is_refused_by_every_reader(old_copy, name):
    folder, scratch = old_copy
    with open(folder / name, "ab") as fh:  # an edit: its SHA-256 no longer the manifest's
        fh.write(b"\n" if name != "fit.json" else b" ")
    before = _snapshot(folder)
    for reader, read in READERS.items():
        got = read(folder, scratch)
        assert got[0] == "refused", (reader, got)
        assert f"{name} was changed after roughbrdf wrote it" in got[1], (reader, got)
        assert _snapshot(folder) == before, reader
    with pytest.raises(ResultFolderRefused) as err:  # also given fit.json itself
        rb.load_fit(folder / "fit.json")
    assert err.value.kind == "changed" and err.value.file == name
    assert "FitResult.save" in str(err.value)  # Python terms; the CLI's name `roughbrdf fit`
    assert "roughbrdf fit FILE" in _read_export(folder, scratch)[1]


def test_a_live_runs_lock_is_refused_and_its_journal_left_alone(sets, tmp_path):
    # a kill point that left a journal, now with a live process's lock: a commit under way
    k, killed = next((k, f) for k, f in sets["killed"].items() if (f / JOURNAL).exists())
    live = subprocess.Popen([sys.executable, "-c", "import sys; sys.stdin.read()"],
                            stdin=subprocess.PIPE)
    try:
        for reader, read in READERS.items():
            folder = tmp_path / reader.split()[0] / "fit"
            shutil.copytree(killed, folder)
            (folder / LOCK).write_text(f"{live.pid}\n")
            before = _snapshot(folder)
            got = read(folder, folder.parent)
            assert got[0] == "refused" and str(folder / LOCK) in got[1], (k, reader, got)
            assert _snapshot(folder) == before, reader  # a live writer's files are its own
    finally:
        live.communicate("")


def test_a_dead_runs_lock_alone_does_not_stop_a_read(old_copy, sets):
    folder, scratch = old_copy
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    (folder / LOCK).write_text(dead.stdout)
    for reader, read in READERS.items():
        assert read(folder, scratch) == sets["expected"]["old"][reader], reader


def test_a_journal_roughbrdf_did_not_write_is_refused_untouched(old_copy):
    folder, scratch = old_copy
    (folder / JOURNAL).write_text(json.dumps({"journal": 1, "new": [{"name": "../x"}]}))
    before = _snapshot(folder)
    for reader, read in READERS.items():
        got = read(folder, scratch)
        assert got[0] == "refused" and "not a commit journal roughbrdf wrote" in got[1], reader
        assert _snapshot(folder) == before, reader


def test_a_folder_without_hashes_is_read_as_it_is(old_copy, sets):
    # an older version's manifest (names only) and no manifest: nothing to compare
    folder, scratch = old_copy
    (folder / MANIFEST).write_text(json.dumps(["fit.json", "report.txt"]))
    (folder / "report.txt").write_text("edited")
    assert _read_python(folder, scratch) == sets["expected"]["old"]["load_fit"]
    (folder / MANIFEST).unlink()
    assert _read_export(folder, scratch) == sets["expected"]["old"]["export --fit"]
