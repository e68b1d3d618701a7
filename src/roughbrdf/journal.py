"""The records of a results folder: its manifest, the commit journal, and recovery after a kill.

:class:`roughbrdf.output.ResultFolder` uses this module; users call
:func:`roughbrdf.output.recover` and read a folder with :func:`roughbrdf.output.read_manifest`.

* The **manifest** (:data:`MANIFEST`) is a JSON object ``{name: sha256}`` of the files
  roughbrdf wrote into the folder (the older format, a JSON list of names, is read with the
  hashes unknown). It is trusted only if it is a regular file (not a symbolic link) whose names
  are plain file names of the folder: no separator, not ``.``/``..``, not absolute, not one of
  roughbrdf's own records, not a symbolic link leading out of the folder. Anything else raises
  :class:`BadRecord` and nothing is done.
* The **commit journal** (:data:`JOURNAL`) is written (and fsynced, the folder too) before the
  first rename of a commit: the new files (name, staged temporary file, SHA-256, and the
  backup name, :data:`BACKUP_PREFIX`, the old file of that name is renamed to), the stale files
  of the old set (renamed to backup names too), the new manifest and the old one. Then the
  files are renamed, the folder fsynced, the manifest written, the backups and the journal
  removed.
* **Recovery** (:func:`recover_locked`, with the folder's lock held): a journal left by a
  killed process is rolled **forward** when every new file is still there with its journalled
  hash (as the staged temporary file or already under its name), else rolled **back**: the
  backups are renamed back, the new files removed, the old manifest restored. Either way the
  folder holds the old set or the new one, never a mix (the old files stay under their backup
  names until the new manifest is on disk, so rolling back restores them). Backups, unlike
  temporary files, are never removed while their journal exists. Then the temporary files of
  processes
  that no longer exist are removed (their names hold the process id,
  ``.roughbrdf-tmp-<pid>-...``; older names without one are removed too, the caller holding
  the lock).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
import secrets
import stat
import tempfile
from pathlib import Path
from typing import Any

__all__ = ["TMP_PREFIX", "BACKUP_PREFIX", "MANIFEST", "LOCK", "JOURNAL", "BadRecord",
           "file_sha256", "lock_is_stale", "pid_alive", "tmp_prefix", "fsync_folder",
           "name_problem", "parse_manifest", "read_manifest", "manifest_text", "commit_set",
           "recover_locked", "remove_dead_temps"]

#: prefix of the temporary files (a leftover one, after a power cut, is recognizable)
TMP_PREFIX = ".roughbrdf-tmp-"
#: prefix of the old files a commit renamed aside (not :data:`TMP_PREFIX`: a cleaner that removes
#: temporary files, as older versions' did, cannot take them; the journal's recovery then
#: restores the old set)
BACKUP_PREFIX = ".roughbrdf-old-"
#: the record of the files roughbrdf wrote into a results folder (JSON ``{name: sha256}``)
MANIFEST = ".roughbrdf-outputs"
#: present while a run writes into the folder (holds its process id)
LOCK = ".roughbrdf-lock"
#: present while a set is being committed (see the module docstring)
JOURNAL = ".roughbrdf-journal"

_HEX64 = re.compile(r"[0-9a-f]{64}")


class BadRecord(ValueError):
    """A manifest or journal roughbrdf will not act on; ``path`` is the record, ``reason`` why."""

    def __init__(self, path: Path, reason: str) -> None:
        self.path = Path(path)
        self.reason = reason
        super().__init__(f"{self.path}: {reason}")


def file_sha256(path: str | os.PathLike) -> str | None:
    """SHA-256 (hex) of a file's bytes, read in 1 MiB blocks; None if it cannot be read.

    The one fingerprint of a file: ``fit.json``'s ``file_sha256``, the catalogue's
    ``--resume``, ``roughbrdf plot --fit``'s "changed since the fit" and the manifest use it.
    """
    h = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
    except OSError:
        return None
    return h.hexdigest()


def pid_alive(pid: int) -> bool:
    """Whether process ``pid`` exists on this machine (True when that cannot be told)."""
    if pid == os.getpid() or os.name == "nt":
        # this process; on Windows os.kill(pid, 0) would end the process instead of asking
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True  # exists under another user, or not a pid of ours: treat as alive
    return True


def lock_is_stale(lock: Path) -> bool:
    """Whether ``lock`` names a process that no longer exists (on this machine)."""
    try:
        pid = int(Path(lock).read_text().split()[0])
    except FileNotFoundError:
        return True  # gone meanwhile
    except (OSError, ValueError, IndexError):
        return False  # being written right now, or not ours: treat as held
    return not pid_alive(pid)


def tmp_prefix() -> str:
    """The prefix of this process's temporary files: ``.roughbrdf-tmp-<pid>-``."""
    return f"{TMP_PREFIX}{os.getpid()}-"


def fsync_folder(folder: Path) -> None:
    """Flush ``folder``'s entries (the renames) to disk, where the system allows it."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:  # Windows cannot open a folder; its renames are durable on return
        return
    try:
        with contextlib.suppress(OSError):  # some file systems refuse fsync on a folder
            os.fsync(fd)
    finally:
        os.close(fd)


def _write_durable(path: Path, text: str) -> None:
    """``text`` into ``path``: a fsynced temporary file renamed over it, then the folder fsynced."""
    fd, tmp = tempfile.mkstemp(prefix=tmp_prefix(), suffix=".part", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes it 0600; a plain open() would not
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    fsync_folder(path.parent)


def name_problem(folder: Path, name: Any) -> str | None:
    """Why ``name`` is not a plain file name of ``folder`` (None if it is one)."""
    if not isinstance(name, str) or not name:
        return "not a file name"
    if any(s and s in name for s in ("/", "\\", os.sep, os.altsep, "\0")):
        return "a path, not a file name of the folder"
    if name in (".", "..") or os.path.isabs(name):
        return "outside the folder"
    if name in (MANIFEST, LOCK, JOURNAL) or name.startswith((TMP_PREFIX, BACKUP_PREFIX)):
        return "one of roughbrdf's own records"
    p = folder / name
    if p.is_symlink():
        real, base = os.path.realpath(p), os.path.realpath(folder)
        if os.path.dirname(real) != base:
            return "a symbolic link leading outside the folder"
    return None


def _regular_text(path: Path) -> str | None:
    """The text of ``path`` (None if absent); :class:`BadRecord` if not a regular file."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return None
    if stat.S_ISLNK(st.st_mode):
        raise BadRecord(path, "a symbolic link, not a file roughbrdf wrote")
    if not stat.S_ISREG(st.st_mode):
        raise BadRecord(path, "not a regular file")
    try:
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise BadRecord(path, f"cannot be read ({exc})") from None


def parse_manifest(folder: Path, text: str, where: Path) -> dict[str, str | None]:
    """The ``{name: sha256 or None}`` a manifest's ``text`` holds; :class:`BadRecord` if bad."""
    try:
        data = json.loads(text)
    except ValueError:
        raise BadRecord(where, "not JSON") from None
    if isinstance(data, list):  # the older format: names only
        files: dict[str, Any] = {n: None for n in data} if all(
            isinstance(n, str) for n in data) else {"": None}
    elif isinstance(data, dict):
        files = data
    else:
        raise BadRecord(where, "holds no list of file names")
    for name, digest in files.items():
        problem = name_problem(folder, name)
        if problem is not None:
            raise BadRecord(where, f"lists {name!r}: {problem}")
        if digest is not None and not (isinstance(digest, str) and _HEX64.fullmatch(digest)):
            raise BadRecord(where, f"gives {name!r} the hash {digest!r}, not a SHA-256")
    return dict(files)


def read_manifest(folder: str | os.PathLike) -> tuple[dict[str, str | None], str | None]:
    """The folder's manifest ``{name: sha256 or None}`` and its raw text (``{}, None`` if none)."""
    folder = Path(folder)
    text = _regular_text(folder / MANIFEST)
    if text is None:
        return {}, None
    return parse_manifest(folder, text, folder / MANIFEST), text


def manifest_text(files: dict[str, str | None]) -> str:
    """The manifest holding ``files`` (sorted by name)."""
    return json.dumps(dict(sorted(files.items())), indent=1) + "\n"


def _backup_name(name: str) -> str:
    return f"{BACKUP_PREFIX}{os.getpid()}-{secrets.token_hex(4)}-{name}"


def commit_set(folder: Path, new: dict[str, tuple[str, str]], stale: list[str],
               manifest: dict[str, str | None], old_manifest: str | None) -> None:
    """Commit ``new`` (``{name: (staged temporary file name, sha256)}``) into ``folder``,
    removing ``stale`` and writing ``manifest``, through the journal (module docstring)."""
    entries = [{"name": n, "tmp": tmp, "sha256": sha,
                "backup": _backup_name(n) if os.path.lexists(folder / n) else None}
               for n, (tmp, sha) in sorted(new.items())]
    record = {"journal": 1, "pid": os.getpid(), "new": entries,
              "stale": [{"name": n, "backup": _backup_name(n)} for n in sorted(stale)],
              "manifest": manifest, "old_manifest": old_manifest}
    _write_durable(folder / JOURNAL, json.dumps(record, indent=1) + "\n")
    _roll_forward(folder, record)


def _roll_forward(folder: Path, record: dict[str, Any]) -> None:
    """Finish the commit ``record`` describes (each step skipped when already done)."""
    for e in record["new"]:
        target, tmp = folder / e["name"], folder / e["tmp"]
        if os.path.lexists(tmp):
            if e["backup"] and os.path.lexists(target) \
                    and not os.path.lexists(folder / e["backup"]):
                os.replace(target, folder / e["backup"])  # the old file kept until the end
            os.replace(tmp, target)
    for e in record["stale"]:
        if os.path.lexists(folder / e["name"]) and not os.path.lexists(folder / e["backup"]):
            os.replace(folder / e["name"], folder / e["backup"])
    fsync_folder(folder)
    text = manifest_text(record["manifest"])
    if _regular_text(folder / MANIFEST) != text:
        _write_durable(folder / MANIFEST, text)
    _finish(folder, record)


def _roll_back(folder: Path, record: dict[str, Any]) -> None:
    """Undo the commit ``record`` describes: the old set and the old manifest come back."""
    for e in record["new"]:
        target, tmp = folder / e["name"], folder / e["tmp"]
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        ours = not os.path.lexists(target) or file_sha256(target) == e["sha256"]
        backup = folder / e["backup"] if e["backup"] else None
        if backup is not None and os.path.lexists(backup):
            # the old file goes back; a file someone put there since the crash stays, and
            # the old one is kept beside it under a visible name
            os.replace(backup, target if ours else folder / f"{e['name']}.roughbrdf-old")
        elif backup is None and ours and os.path.lexists(target):
            os.unlink(target)  # a new name of the set: it was not there before
    for e in record["stale"]:
        if os.path.lexists(folder / e["backup"]) and not os.path.lexists(folder / e["name"]):
            os.replace(folder / e["backup"], folder / e["name"])
    fsync_folder(folder)
    if record["old_manifest"] is None:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(folder / MANIFEST)
    elif _regular_text(folder / MANIFEST) != record["old_manifest"]:
        _write_durable(folder / MANIFEST, record["old_manifest"])
    _finish(folder, record)


def _finish(folder: Path, record: dict[str, Any]) -> None:
    """Remove the backups, then the journal (the set is complete without them)."""
    for e in [*record["new"], *record["stale"]]:
        if e["backup"]:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(folder / e["backup"])
    fsync_folder(folder)
    os.unlink(folder / JOURNAL)
    fsync_folder(folder)


def _load_journal(folder: Path, text: str) -> dict[str, Any]:
    """The journal's record, checked: every name in it is a plain name of ``folder``."""
    where = folder / JOURNAL
    try:
        rec = json.loads(text)
        new, stale = rec["new"], rec["stale"]
        parse_manifest(folder, json.dumps(rec["manifest"]), where)
        ok = isinstance(rec["old_manifest"], str | None) and isinstance(new, list) \
            and isinstance(stale, list)
        if rec["old_manifest"] is not None:
            parse_manifest(folder, rec["old_manifest"], where)
        for e in [*new, *stale]:
            names = [e["name"], e.get("tmp"), e["backup"]]
            ok = ok and name_problem(folder, e["name"]) is None and all(
                n is None or (isinstance(n, str) and n.startswith((TMP_PREFIX, BACKUP_PREFIX))
                              and name_problem(folder, "x" + n) is None)
                for n in names[1:])
            ok = ok and (e in stale or (isinstance(e["tmp"], str) and isinstance(
                e["sha256"], str)))
    except (ValueError, KeyError, TypeError, AttributeError):
        ok = False
    if not ok:
        raise BadRecord(where, "not a commit journal roughbrdf wrote")
    return dict(rec)


def _complete(folder: Path, record: dict[str, Any]) -> bool:
    """Whether every new file of ``record`` is there with its hash (staged or in place)."""
    for e in record["new"]:
        tmp = folder / e["tmp"]
        where = tmp if os.path.lexists(tmp) else folder / e["name"]
        if file_sha256(where) != e["sha256"]:
            return False
    return True


def recover_locked(folder: str | os.PathLike) -> list[Path]:
    """Roll a journal forward or back and remove dead processes' temporary files (the
    caller holds the folder's lock); the paths acted upon."""
    folder = Path(folder)
    done: list[Path] = []
    text = _regular_text(folder / JOURNAL)
    if text is not None:
        record = _load_journal(folder, text)
        (_roll_forward if _complete(folder, record) else _roll_back)(folder, record)
        done.append(folder / JOURNAL)
    # no journal is left: a backup of a dead process is an orphan (its journal was deleted)
    return done + remove_dead_temps(folder, old_names=True, prefix=BACKUP_PREFIX) \
        + remove_dead_temps(folder, old_names=True)


def remove_dead_temps(folder: Path, *, old_names: bool, prefix: str = TMP_PREFIX
                      ) -> list[Path]:
    """Remove the temporary files (names starting with ``prefix``) of processes that no
    longer exist (``old_names``: also those named without a process id, by older versions);
    the paths removed."""
    removed = []
    for p in sorted(folder.glob(f"{prefix}*")):
        owner = p.name[len(prefix):].split("-")[0]
        if owner.isdigit() and pid_alive(int(owner)):
            continue  # a live process's file (this process's too)
        if not owner.isdigit() and not old_names:
            continue
        if p.is_symlink() or p.is_file():
            with contextlib.suppress(FileNotFoundError):
                p.unlink()
                removed.append(p)
    return removed
