"""A process killed at any instant of a commit.

The kill is injected, not timed: a subprocess replaces ``os.replace`` by a wrapper that calls
``os._exit(9)`` at its k-th call, for every k of a commit (the journal's write is the first
rename, the manifest's one of the last). The next run (:class:`roughbrdf.output.ResultFolder`
entering the folder, :func:`roughbrdf.output.recover`, ``fit --force``, ``--resume``'s check)
then finds the old set or the new one, complete, and no temporary file, journal or lock.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys

import pytest

from roughbrdf.catalogue.resume import TASK_FILE, completed_rows
from roughbrdf.cli import main
from roughbrdf.demo import default_measurement_path
from roughbrdf.output import JOURNAL, LOCK, MANIFEST, TMP_PREFIX, ResultFolder, recover

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

#: run in a subprocess: ``python -c HOOK k`` kills itself at the k-th os.replace (0: never)
#: and prints the number of calls it saw; then runs the code given on stdin
HOOK = r"""
import os, sys
kill_at, calls, real = int(sys.argv[1]), [0], os.replace
def replace(a, b):
    calls[0] += 1
    if calls[0] == kill_at:
        os._exit(9)
    real(a, b)
os.replace = replace
exec(sys.stdin.read())
print("REPLACES", calls[0])
"""


def _run(code: str, k: int, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", HOOK, str(k)], input=code, text=True,
                          capture_output=True, cwd=cwd, timeout=300)


def _count(code: str, cwd) -> int:
    """How many os.replace calls ``code`` makes when nothing kills it."""
    done = _run(code, 0, cwd)
    assert done.returncode == 0, done.stderr
    return int(done.stdout.split("REPLACES")[-1])


def _files(folder) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.name != MANIFEST}


def _settled(folder) -> dict[str, bytes]:
    """Enter the folder as the next run does; its files, checked against their manifest."""
    with ResultFolder(folder, extend=True):
        pass
    names = sorted(os.listdir(folder))
    assert not [n for n in names if n.startswith((TMP_PREFIX, ".roughbrdf-old-"))
                or n in (LOCK, JOURNAL)], names
    files = _files(folder)
    listed = json.loads((folder / MANIFEST).read_text())
    assert sorted(listed) == sorted(files), names
    assert all(listed[n] == hashlib.sha256(b).hexdigest() for n, b in files.items())
    return files


def _kill_everywhere(tmp_path, write_old, code: str, folder_name: str = "out"):
    """For every k: a fresh folder holding the old set, the new one written by ``code`` in a
    subprocess killed at the k-th rename; yields (k, folder, old files, new files)."""
    ref = tmp_path / "reference"
    ref.mkdir()
    write_old(ref / folder_name)
    old = _files(ref / folder_name)
    n = _count(code.replace("FOLDER", repr(str(ref / folder_name))), ref)
    new = _files(ref / folder_name)
    assert new != old and n >= 3
    for k in range(1, n + 1):
        base = tmp_path / f"k{k}"
        base.mkdir()
        write_old(base / folder_name)
        done = _run(code.replace("FOLDER", repr(str(base / folder_name))), k, base)
        assert done.returncode == 9, (k, done.stderr)
        yield k, base / folder_name, old, new


def _staged(folder, new: dict[str, bytes]) -> list:
    """The temporary files holding a file of the new set (not yet renamed into place)."""
    return [p for p in folder.iterdir()
            if p.name.startswith(TMP_PREFIX) and p.read_bytes() in new.values()]


def _three(folder, names, tag):
    with ResultFolder(folder, overwrite=True) as out:
        for name in names:
            out.add(name, f"{name} of the {tag} set\n" * 1000)


SET = """
from roughbrdf.output import ResultFolder
with ResultFolder(FOLDER, overwrite=True) as out:
    for name in ["a.txt", "b.txt", "d.txt"]:
        out.add(name, f"{name} of the new set\\n" * 1000)
"""


def test_a_kill_at_any_rename_leaves_the_old_set_or_the_new_one(tmp_path):
    seen = set()
    for k, folder, old, new in _kill_everywhere(
            tmp_path, lambda f: _three(f, ["a.txt", "b.txt", "c.txt"], "old"), SET):
        state = _settled(folder)
        assert state in (old, new), (k, sorted(state))
        seen.add("old" if state == old else "new")
    assert seen == {"old", "new"}  # killed before the journal: old; after it: rolled forward


@pytest.mark.parametrize("loss", ["truncated", "every temporary file deleted"])
def test_recover_rolls_back_when_a_staged_file_was_lost(tmp_path, loss):
    for k, folder, old, new in _kill_everywhere(
            tmp_path, lambda f: _three(f, ["a.txt", "b.txt", "c.txt"], "old"), SET):
        staged = _staged(folder, new)
        journal = (folder / JOURNAL).exists()
        if loss == "truncated":
            for p in staged:  # the disk lost what was staged (a power cut on a lying disk)
                p.write_bytes(b"")
        else:  # a cleaner of temporary files ran first (older versions' catalogue tidy())
            for p in folder.glob(f"{TMP_PREFIX}*"):
                p.unlink()
        recover(folder)
        state = _settled(folder)
        if journal and staged:
            assert state == old, k  # cannot finish: rolled back, the old files restored
        else:
            assert state in (old, new), k


def test_recover_removes_only_dead_processes_temporary_files_and_locks(tmp_path):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    pid = int(dead.stdout)
    live = subprocess.Popen([sys.executable, "-c", "import sys; sys.stdin.read()"],
                            stdin=subprocess.PIPE)
    try:
        (tmp_path / f"{TMP_PREFIX}{pid}-abc.part").write_text("left by a killed worker")
        (tmp_path / f"{TMP_PREFIX}{live.pid}-def.part").write_text("being written")
        (tmp_path / f"{TMP_PREFIX}oldname.part").write_text("older version's leftover")
        (tmp_path / LOCK).write_text(f"{pid}\n")
        (tmp_path / "mine.txt").write_text("user's")
        removed = {p.name for p in recover(tmp_path)}
        assert removed == {f"{TMP_PREFIX}{pid}-abc.part", f"{TMP_PREFIX}oldname.part", LOCK}
        assert sorted(os.listdir(tmp_path)) == [f"{TMP_PREFIX}{live.pid}-def.part", "mine.txt"]
        # a live run's lock: its files stay, only a dead process's temporary file goes
        (tmp_path / LOCK).write_text(f"{live.pid}\n")
        (tmp_path / f"{TMP_PREFIX}{pid}-ghi.part").write_text("x")
        (tmp_path / f"{TMP_PREFIX}old2.part").write_text("x")
        assert [p.name for p in recover(tmp_path)] == [f"{TMP_PREFIX}{pid}-ghi.part"]
        assert (tmp_path / LOCK).exists() and (tmp_path / f"{TMP_PREFIX}old2.part").exists()
    finally:
        live.communicate("")


ZEMAX = """
import roughbrdf as rb
from roughbrdf.export.zemax import to_zemax
to_zemax({c: rb.model("lambertian", rho=r) for c, r in [("red", .6), ("green", .5),
                                                     ("blue", .4)]},
         FOLDER + "/olive.bsdf", overwrite=True, angles_of_incidence=[0.0, 0.5])
"""


def _old_zemax(folder):
    import roughbrdf as rb
    from roughbrdf.export.zemax import to_zemax

    folder.mkdir(parents=True)
    to_zemax({c: rb.model("lambertian", rho=0.2) for c in ("red", "green", "blue")},
             folder / "olive.bsdf", angles_of_incidence=[0.0, 0.5])


def test_a_multichannel_zemax_export_killed_midway_is_all_old_or_all_new(tmp_path):
    for k, folder, old, new in _kill_everywhere(tmp_path, _old_zemax, ZEMAX):
        assert sorted(old) == ["olive_blue.bsdf", "olive_green.bsdf", "olive_red.bsdf"]
        assert _settled(folder) in (old, new), k


SUMMARY = """
from roughbrdf.catalogue.summary import write_summary
write_summary(FOLDER, [{"file": "new.astm", "status": "ok", "params": {"rho": 0.4}}],
              overwrite=True)
"""


def test_summary_pages_killed_midway_are_both_old_or_both_new(tmp_path):
    from roughbrdf.catalogue.summary import write_summary

    def old_pages(folder):
        write_summary(folder, [{"file": "old.astm", "status": "failed", "error": "bad"}])

    for k, folder, old, new in _kill_everywhere(tmp_path, old_pages, SUMMARY):
        assert sorted(old) == ["summary.html", "summary.md"]
        assert _settled(folder) in (old, new), k


TASK = """
import json
from roughbrdf.output import ResultFolder
with ResultFolder(FOLDER, overwrite=True) as out:
    out.add("fit.json", '{"fit": "B"}' * 500)
    out.add("catalogue-task.json", json.dumps({"sha256": "s", "fingerprint": "B",
                                               "files": ["fit.json"], "rows": [{"r": "B"}]}))
"""


def _task_set(folder, fp="A"):
    with ResultFolder(folder, overwrite=True) as out:
        out.add("fit.json", f'{{"fit": "{fp}"}}' * 500)
        out.add(TASK_FILE, json.dumps({"sha256": "s", "fingerprint": fp,
                                       "files": ["fit.json"], "rows": [{"r": fp}]}))


def test_resume_never_takes_a_half_committed_set_for_a_complete_one(tmp_path):
    for k, folder, _old, new in _kill_everywhere(tmp_path, _task_set, TASK):
        staged = _staged(folder, new)
        journal = (folder / JOURNAL).exists()
        for p in staged:  # half committed, and what was staged is lost
            p.write_bytes(b"")
        b, a = completed_rows(folder, "s", "B"), completed_rows(folder, "s", "A")
        if journal and staged:  # rolled back: the old, complete set A
            assert b is None and a == [{"r": "A", "status": "skipped (resume)",
                                        "earlier_status": None}], k
        else:
            assert (a is None) != (b is None), k
            if b is not None:
                assert _files(folder)["fit.json"] == new["fit.json"], k


def test_resume_does_not_take_a_truncated_fit_json_for_a_result(tmp_path):
    _task_set(tmp_path)
    assert completed_rows(tmp_path, "s", "A") == [{"r": "A", "status": "skipped (resume)",
                                                   "earlier_status": None}]
    (tmp_path / "fit.json").write_bytes(b"")
    assert completed_rows(tmp_path, "s", "A") is None
    _task_set(tmp_path / "edited")
    (tmp_path / "edited" / "fit.json").write_text('{"fit": "A", "edited": true}')
    assert completed_rows(tmp_path / "edited", "s", "A") is None


FIT = ["fit", str(default_measurement_path()), "--no-plots"]
FIT_NEW = f"""
from roughbrdf.cli import main
main({[*FIT, "-m", "tr75", "--starts", "2", "--force", "--out"]!r} + [FOLDER])
"""


@pytest.mark.parametrize("k", [2, 4])
def test_fit_force_killed_midway_then_the_next_run_finds_one_set(tmp_path, k, capsys):
    out = tmp_path / "fit"
    assert main([*FIT, "-m", "lambertian", "--out", str(out)]) == 0
    done = _run(FIT_NEW.replace("FOLDER", repr(str(out))), k, tmp_path)
    assert done.returncode == 9, done.stderr
    files = _settled(out)
    assert sorted(files) == ["fit.json", "report.txt"]
    model = json.loads(files["fit.json"])["model"]
    assert files["report.txt"].startswith(f"[[Fit]] {model} to".encode()), k  # never a mix
    # TR75 fitted under the energy constraint (its albedo would exceed 1): written, exit 0
    assert main([*FIT, "-m", "tr75", "--starts", "2", "--force", "--out", str(out)]) == 0
    files = _settled(out)
    model = json.loads(files["fit.json"])["model"]
    assert model != "lambertian" and files["report.txt"].startswith(f"[[Fit]] {model} to".encode())
