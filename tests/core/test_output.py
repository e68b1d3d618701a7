"""``roughbrdf.output`` and ``roughbrdf.interrupts``: no overwrite unless asked, all-or-nothing
result sets, one run at a time, and Ctrl-C that is deferred or re-raised, never lost."""

from __future__ import annotations

import errno
import hashlib
import json
import os
import signal
import subprocess
import sys

import pytest

from roughbrdf import interrupts, output
from roughbrdf.output import (
    LOCK,
    MANIFEST,
    TMP_PREFIX,
    OverwriteRefused,
    ResultFolder,
    atomic_write,
    ensure_folder,
)


def _files(folder) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def _leftovers(folder) -> list[str]:
    return [p.name for p in folder.iterdir() if p.name.startswith(TMP_PREFIX) or p.name == LOCK]


def _write_set(folder, files: dict[str, str], **kw) -> list:
    with ResultFolder(folder, **kw) as out:
        for name, text in files.items():
            out.add(name, text)
    return out.previous()


# ---------------------------------------------------------------------------------------------
# atomic_write
# ---------------------------------------------------------------------------------------------
def test_atomic_write_refuses_then_replaces_when_asked(tmp_path):
    p = tmp_path / "a.txt"
    atomic_write(p, "one\n")
    with pytest.raises(OverwriteRefused, match="a.txt exists; not overwriting it") as err:
        atomic_write(p, "two\n")
    assert isinstance(err.value, FileExistsError)
    assert "overwrite=True" in str(err.value)
    assert err.value.render({"overwrite": "--force"}).endswith("(pass --force)")
    assert p.read_text() == "one\n"
    atomic_write(p, b"two\n", overwrite=True)
    assert p.read_bytes() == b"two\n"
    assert _leftovers(tmp_path) == []


@pytest.mark.parametrize("exc", [RuntimeError("boom"), KeyboardInterrupt()])
def test_atomic_write_failure_leaves_the_old_file_and_no_temporary(tmp_path, exc):
    p = tmp_path / "a.txt"
    p.write_text("old")

    def writer(fh):
        fh.write("half of the new content")
        raise exc

    with pytest.raises(type(exc)):
        atomic_write(p, writer, overwrite=True)
    assert p.read_text() == "old" and _leftovers(tmp_path) == []
    with pytest.raises(type(exc)):  # a new file that fails is not created at all (no 0 bytes)
        atomic_write(tmp_path / "new.txt", writer)
    assert not (tmp_path / "new.txt").exists() and _leftovers(tmp_path) == []


def test_atomic_write_never_replaces_a_file_that_appears_meanwhile(tmp_path):
    p = tmp_path / "a.txt"

    def writer(fh):
        fh.write("mine")
        p.write_text("someone else's")  # created while we were writing

    with pytest.raises(OverwriteRefused):
        atomic_write(p, writer)
    assert p.read_text() == "someone else's" and _leftovers(tmp_path) == []


def test_atomic_write_keeps_the_mode_of_the_file_it_replaces(tmp_path):
    p = tmp_path / "a.txt"
    p.write_text("x")
    p.chmod(0o640)
    atomic_write(p, "y", overwrite=True)
    assert p.stat().st_mode & 0o777 == 0o640
    atomic_write(tmp_path / "b.txt", "z")
    umask = os.umask(0)
    os.umask(umask)
    assert (tmp_path / "b.txt").stat().st_mode & 0o777 == 0o666 & ~umask


def test_atomic_write_errors_name_the_path_not_the_temporary_file(tmp_path, monkeypatch):
    with pytest.raises(IsADirectoryError) as err:
        atomic_write(tmp_path, "x", overwrite=True)
    assert err.value.filename == str(tmp_path)
    with pytest.raises(FileNotFoundError) as err:
        atomic_write(tmp_path / "no" / "a.txt", "x")
    assert err.value.filename == str(tmp_path / "no")

    def full(fd):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(output.os, "fsync", full)
    (tmp_path / "a.txt").write_text("old")
    with pytest.raises(OSError) as err:
        atomic_write(tmp_path / "a.txt", "new", overwrite=True)
    assert err.value.errno == errno.ENOSPC and err.value.filename == str(tmp_path / "a.txt")
    assert (tmp_path / "a.txt").read_text() == "old" and _leftovers(tmp_path) == []


def test_ensure_folder_names_the_file_in_the_way(tmp_path):
    (tmp_path / "f").write_text("a file")
    with pytest.raises(NotADirectoryError, match=r"f is a file") as err:
        ensure_folder(tmp_path / "f" / "sub")
    assert err.value.filename == str(tmp_path / "f" / "sub")
    with pytest.raises(NotADirectoryError):
        ensure_folder(tmp_path / "f")
    assert ensure_folder(tmp_path / "a" / "b").is_dir()


# ---------------------------------------------------------------------------------------------
# ResultFolder
# ---------------------------------------------------------------------------------------------
def test_result_folder_writes_the_set_and_its_manifest(tmp_path):
    out = tmp_path / "new" / "res"
    assert _write_set(out, {"b.txt": "B", "a.txt": "A"}) == ["a.txt", "b.txt"]
    files = _files(out)
    assert json.loads(files.pop(MANIFEST)) == {
        "a.txt": hashlib.sha256(b"A").hexdigest(), "b.txt": hashlib.sha256(b"B").hexdigest()}
    assert files == {"a.txt": b"A", "b.txt": b"B"}


def test_second_run_is_refused_unless_overwrite_which_replaces_exactly_the_old_set(tmp_path):
    _write_set(tmp_path, {"fit.json": "1", "fit_a.png": "old plot"})
    (tmp_path / "notes.txt").write_text("the user's")
    before = _files(tmp_path)
    with pytest.raises(OverwriteRefused, match=r"holds results already \(fit.json, fit_a.png\)"):
        _write_set(tmp_path, {"other.txt": "x"})  # any earlier result, not only same names
    assert _files(tmp_path) == before
    assert _write_set(tmp_path, {"fit.json": "2", "fit_b.png": "new"}, overwrite=True) == [
        "fit.json", "fit_b.png"]
    files = _files(tmp_path)
    assert files["fit.json"] == b"2" and "fit_a.png" not in files  # the stale file went
    assert files["notes.txt"] == b"the user's"  # files roughbrdf did not write stay


def test_foreign_files_are_never_replaced(tmp_path):
    (tmp_path / "report.txt").write_text("hand edits")
    for overwrite in (False, True):
        with pytest.raises(OverwriteRefused, match="not overwriting report.txt") as err:
            _write_set(tmp_path, {"report.txt": "r", "fit.json": "f"}, overwrite=overwrite)
        assert err.value.foreign == ["report.txt"]
        assert ("not even with --force" in err.value.render({"overwrite": "--force"})) \
            == overwrite
    assert _files(tmp_path) == {"report.txt": b"hand edits"}


@pytest.mark.parametrize("exc", [OSError(errno.ENOSPC, "No space left on device"),
                                 KeyboardInterrupt()])
def test_a_failure_midway_leaves_exactly_the_old_set(tmp_path, exc):
    _write_set(tmp_path, {"fit.json": "old", "fit_a.png": "old plot"})
    before = _files(tmp_path)

    def figure(fh):
        fh.write(b"\x89PNG half a figure")
        raise exc

    with pytest.raises(type(exc)), ResultFolder(tmp_path, overwrite=True) as out:
        out.add("fit.json", "new")
        out.add("fit_a.png", figure, binary=True)
    assert _files(tmp_path) == before and _leftovers(tmp_path) == []


def test_a_file_that_failed_is_not_committed(tmp_path):
    def bad(fh):
        fh.write("partial")
        raise RuntimeError("boom")

    with ResultFolder(tmp_path) as out:
        out.add("good.txt", "g")
        with pytest.raises(RuntimeError):
            out.add("bad.txt", bad)
    files = _files(tmp_path)
    assert sorted(json.loads(files.pop(MANIFEST))) == ["good.txt"]
    assert files == {"good.txt": b"g"}


def test_manifest_lists_only_files_that_exist(tmp_path):
    _write_set(tmp_path, {"a.txt": "A", "b.txt": "B"})
    (tmp_path / "a.txt").unlink()
    (tmp_path / "b.txt").unlink()
    # an old manifest whose files are gone is no earlier result
    assert _write_set(tmp_path, {"c.txt": "C"}) == ["c.txt"]
    _write_set(tmp_path, {"d.txt": "D"}, extend=True)
    (tmp_path / "c.txt").unlink()
    assert _write_set(tmp_path, {"e.txt": "E"}, extend=True) == ["d.txt", "e.txt"]


def test_extend_adds_to_the_set(tmp_path):
    _write_set(tmp_path, {"fit.json": "f"})
    _write_set(tmp_path, {"comparison_a.png": "c"}, extend=True)
    assert ResultFolder(tmp_path).previous() == ["comparison_a.png", "fit.json"]
    with pytest.raises(OverwriteRefused, match=r"holds results already \(comparison_a.png\)"):
        _write_set(tmp_path, {"comparison_a.png": "c2"}, extend=True)
    _write_set(tmp_path, {"comparison_a.png": "c2"}, extend=True, overwrite=True)
    assert _files(tmp_path)["comparison_a.png"] == b"c2"
    # a new run of the verb that made the set replaces it all, the added files included
    _write_set(tmp_path, {"fit.json": "f2"}, overwrite=True)
    assert set(_files(tmp_path)) == {MANIFEST, "fit.json"}


def test_check_refuses_before_any_work_and_creates_nothing(tmp_path):
    (tmp_path / "f").write_text("a file")
    for bad in (tmp_path / "f", tmp_path / "f" / "sub"):
        with pytest.raises(NotADirectoryError):
            ResultFolder(bad).check(["fit.json"])
    ResultFolder(tmp_path / "new").check(["fit.json"])
    assert not (tmp_path / "new").exists()
    with pytest.raises(ValueError, match="not a result file name"):
        with ResultFolder(tmp_path / "new") as out:
            out.add("../escape.txt", "x")


def test_one_run_at_a_time(tmp_path):
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        (tmp_path / LOCK).write_text(f"{sleeper.pid}\n")
        with pytest.raises(OverwriteRefused, match="another roughbrdf run is writing into"):
            ResultFolder(tmp_path).check(["a.txt"])
        with pytest.raises(OverwriteRefused, match="lock file"), ResultFolder(tmp_path):
            pass
        assert (tmp_path / LOCK).read_text() == f"{sleeper.pid}\n"  # not ours to remove
    finally:
        sleeper.kill()
        sleeper.wait()
    # the process is gone: its lock is stale and taken over
    assert _write_set(tmp_path, {"a.txt": "A"}) == ["a.txt"]
    assert not (tmp_path / LOCK).exists()


# ---------------------------------------------------------------------------------------------
# interrupts
# ---------------------------------------------------------------------------------------------
def test_held_interrupts_defers_ctrl_c_to_the_end_of_the_block():
    done = []
    with pytest.raises(KeyboardInterrupt):
        with interrupts.held_interrupts():
            signal.raise_signal(signal.SIGINT)
            with interrupts.held_interrupts():  # nested: the outer block delivers
                done.append("inner")
            done.append("outer")
    assert done == ["inner", "outer"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_watch_records_an_interrupt_that_a_finalizer_swallowed(capfd):
    class Swallows:
        def __del__(self):
            signal.raise_signal(signal.SIGINT)  # raised in __del__: Python can only ignore it

    hook = sys.unraisablehook
    with interrupts.watch():
        Swallows()  # created and finalized at once
        assert interrupts.interrupted()
        assert "Exception ignored" not in capfd.readouterr().err
        with pytest.raises(KeyboardInterrupt):  # the next safe point raises it again
            with interrupts.held_interrupts():
                pass
        with pytest.raises(KeyboardInterrupt):
            interrupts.raise_if_interrupted()
    assert not interrupts.interrupted()
    assert sys.unraisablehook is hook
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_commit_refuses_after_a_swallowed_interrupt(tmp_path):
    _write_set(tmp_path, {"a.txt": "old"})
    before = _files(tmp_path)
    with interrupts.watch():
        with pytest.raises(KeyboardInterrupt), ResultFolder(tmp_path, overwrite=True) as out:
            out.add("a.txt", "new")
            try:
                signal.raise_signal(signal.SIGINT)
            except KeyboardInterrupt:
                pass  # a library that catches it and goes on
    assert _files(tmp_path) == before and _leftovers(tmp_path) == []


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_outside_watch_nothing_changes():
    class Swallows:
        def __del__(self):
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        signal.raise_signal(signal.SIGINT)
    Swallows()
    assert not interrupts.interrupted()
    with interrupts.held_interrupts():
        pass


def test_json_manifest_maps_names_to_their_sha256(tmp_path):
    text = json.dumps({"a": 1})
    _write_set(tmp_path, {"x.json": text})
    assert json.loads((tmp_path / MANIFEST).read_text()) == {
        "x.json": hashlib.sha256(text.encode()).hexdigest()}
