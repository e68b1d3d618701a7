"""Writing files without losing anything a user has: atomic writes, no overwrite unless asked.

Every file roughbrdf writes goes through :func:`atomic_write` (one file) or
:class:`ResultFolder` (a set of files):

* an existing file is never replaced unless the caller asks (``overwrite=True``; the CLI's
  ``--force``): :class:`OverwriteRefused` (a :class:`FileExistsError`) names it otherwise;
* the content goes to a temporary file in the same folder, which is then renamed over the
  target (:func:`os.replace`, atomic on POSIX and Windows): a reader, a crash or Ctrl-C sees the
  old file or the new one, never a mix and never a 0-byte file;
* if writing fails or is interrupted, the temporary file is removed and the error propagates;
  an :class:`OSError` names the file or folder it is about, not the temporary file;
* temporary files are named ``.roughbrdf-tmp-<pid>-...`` (:data:`TMP_PREFIX`, then the
  writing process's id): one left by a killed process is recognised and removed by the next
  run (:func:`recover`), one of a live process never.

A :class:`ResultFolder` set survives a kill at any instant: its commit goes through a journal
(:data:`JOURNAL`, :mod:`roughbrdf.journal`) that the next run into the folder rolls forward or
back, and its manifest (:data:`MANIFEST`, ``{name: sha256}``) is trusted only as far as it names
plain files of the folder (:class:`ManifestRefused` otherwise) and only for files whose bytes
still have the recorded hash (a file changed since is the user's and is never replaced).

Examples
--------
>>> import pathlib, tempfile
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> atomic_write(d / "a.txt", "first\\n")
PosixPath('...a.txt')
>>> atomic_write(d / "a.txt", "second\\n")
Traceback (most recent call last):
...
roughbrdf.output.OverwriteRefused: ...a.txt exists; not overwriting it (pass overwrite=True)
>>> _ = atomic_write(d / "a.txt", "second\\n", overwrite=True)
>>> (d / "a.txt").read_text()
'second\\n'
"""

from __future__ import annotations

import contextlib
import errno
import os
import tempfile
from collections.abc import Callable, Iterable, Iterator, Mapping
from pathlib import Path
from typing import IO, Any

from . import journal
from .interrupts import held_interrupts, raise_if_interrupted
from .journal import JOURNAL, LOCK, MANIFEST, TMP_PREFIX, file_sha256, lock_is_stale, tmp_prefix

__all__ = ["atomic_write", "staged", "same_file", "ensure_folder", "file_sha256",
           "lock_is_stale", "refuse_existing", "ResultFolder", "OverwriteRefused",
           "ManifestRefused", "recover", "read_manifest", "MANIFEST", "LOCK", "JOURNAL",
           "TMP_PREFIX"]

Content = str | bytes | Callable[[IO[Any]], None]


class OverwriteRefused(FileExistsError):
    """roughbrdf refused to replace files (a rule of this module, not an error of the system).

    Attributes
    ----------
    path : pathlib.Path
        The file, or the results folder.
    results : list of str
        Files of an earlier run (the folder's :data:`MANIFEST`) that would be replaced.
    foreign : list of str
        Files of the same names that roughbrdf did not write: never replaced.
    changed : list of str
        Files roughbrdf wrote whose content changed since (their hash in the manifest
        differs): the user's now, never replaced or removed.
    locked : bool
        Another run is writing into the folder (its :data:`LOCK`).

    :meth:`render` words the message for Python (``overwrite=True``) or, given
    ``{"overwrite": "--force"}``, for the command line; ``str(err)`` is the Python wording.
    """

    def __init__(self, path: str | os.PathLike, *, results: Iterable[str] = (),
                 foreign: Iterable[str] = (), overwrite: bool = False, locked: bool = False,
                 single: bool = False, changed: Iterable[str] = ()) -> None:
        self.path = Path(path)
        self.results = sorted(results)
        self.foreign = sorted(foreign)
        self.changed = sorted(changed)
        self.overwrite = overwrite
        self.locked = locked
        self.single = single
        super().__init__(self.render())

    def render(self, options: Mapping[str, str] | None = None) -> str:
        """The message; ``options["overwrite"]`` is how the caller says "replace" (``--force``)."""
        ask = (options or {}).get("overwrite", "overwrite=True")
        if self.locked:
            return (f"another roughbrdf run is writing into {self.path} (lock file "
                    f"{self.path / LOCK}); wait for it to finish, or delete the lock file if no "
                    f"run is active")
        if self.single:
            return f"{self.path} exists; not overwriting it (pass {ask})"
        parts = []
        if self.results:
            parts.append(f"{self.path} holds results already ({', '.join(self.results)}); "
                         f"choose another folder or replace them with {ask}")
        if self.foreign:
            them = "it" if len(self.foreign) == 1 else "them"
            even = f", not even with {ask}" if self.overwrite else ""
            parts.append(f"{self.path}: not overwriting {', '.join(self.foreign)} (not written by "
                         f"roughbrdf{even}); move {them} away or choose another folder")
        if self.changed:
            them = "it" if len(self.changed) == 1 else "them"
            even = f", not even with {ask}" if self.overwrite else ""
            parts.append(f"{self.path}: not replacing or removing {', '.join(self.changed)} "
                         f"(changed since roughbrdf wrote {them}{even}); move {them} away or "
                         f"choose another folder")
        return "; ".join(parts)


class ManifestRefused(OverwriteRefused):
    """A results folder's manifest or commit journal that roughbrdf will not act on.

    Attributes
    ----------
    record : pathlib.Path
        The manifest (:data:`MANIFEST`) or journal (:data:`JOURNAL`).
    reason : str
        What is wrong with it (a name outside the folder, a symbolic link, not JSON ...).
    """

    def __init__(self, record: str | os.PathLike, reason: str) -> None:
        self.record = Path(record)
        self.reason = reason
        super().__init__(self.record.parent)

    def render(self, options: Mapping[str, str] | None = None) -> str:
        """The message (the same for Python and the command line)."""
        return (f"{self.record}: {self.reason}; roughbrdf will not act on this folder's "
                f"records (a folder copied from elsewhere?): check it, and delete {self.record} "
                f"if the files it names are not results of yours")


def same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether ``a`` and ``b`` name the same existing file (links and relative paths resolved)."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def _located(exc: OSError, path: str | os.PathLike) -> OSError:
    """``exc`` (same class and errno) about ``path`` instead of a temporary file."""
    if exc.errno is None:
        return exc
    try:
        new = type(exc)(exc.errno, exc.strerror, str(path))
    except TypeError:  # a subclass with a constructor of its own
        return exc
    new.__cause__ = exc
    return new


#: errors of writing a file's bytes (reported against the file, not the temporary one)
_WRITE_ERRORS = (errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC), errno.EIO, errno.EFBIG)


def _blocking_file(path: Path) -> Path | None:
    """The first of ``path`` and its ancestors that exists and is not a folder, if any."""
    for p in (path, *path.parents):
        if p.exists() or p.is_symlink():
            return None if p.is_dir() else p
    return None


def _is_real_dir(path: Path) -> bool:
    """Whether ``path`` is a folder itself (not a symbolic link to one)."""
    return path.is_dir() and not path.is_symlink()


def ensure_folder(path: str | os.PathLike) -> Path:
    """Create the folder ``path`` (and its parents) if needed; returns it.

    Raises :class:`NotADirectoryError` naming the file in the way when ``path`` or one of its
    parents is a file.
    """
    folder = Path(path)
    block = _blocking_file(folder)
    if block is not None:
        where = "" if block == folder else f" ({block} is a file)"
        raise NotADirectoryError(errno.ENOTDIR, f"not a folder{where}", str(folder))
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def _temporary(folder: Path, target: Path, binary: bool) -> tuple[str, IO[Any]]:
    """A new temporary file in ``folder``, open (errors name ``folder`` or ``target``)."""
    try:
        fd, tmp = tempfile.mkstemp(prefix=tmp_prefix(), suffix=".part", dir=folder)
    except FileNotFoundError as exc:
        raise _located(exc, folder) from None
    except OSError as exc:
        raise _located(exc, target) from None
    fh: IO[Any] = (os.fdopen(fd, "wb") if binary
                   else os.fdopen(fd, "w", encoding="utf-8", newline=""))
    return tmp, fh


@contextlib.contextmanager
def _on_disk(fh: IO[Any], target: Path) -> Iterator[IO[Any]]:
    """Yield ``fh``; then flush it to disk and close it (write errors name ``target``)."""
    try:
        with fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())  # the bytes are on disk before the name points at them
    except OSError as exc:
        if exc.errno in _WRITE_ERRORS:
            raise _located(exc, target) from None
        raise


@contextlib.contextmanager
def staged(path: str | os.PathLike, *, overwrite: bool = False, binary: bool = False
           ) -> Iterator[IO[Any]]:
    """Open a temporary file beside ``path``; on a clean exit it replaces ``path`` atomically.

    Raises :class:`OverwriteRefused` before anything is written if ``path`` exists and
    ``overwrite`` is false (also if the file appears meanwhile: the final rename does not
    replace it), and :class:`IsADirectoryError` if ``path`` is a folder. On any exception
    (``KeyboardInterrupt`` included) the temporary file is removed and ``path`` is left as it
    was.
    """
    target = Path(path)
    if target.is_dir():
        raise IsADirectoryError(errno.EISDIR, "a folder, not a file", str(target))
    if target.exists() and not overwrite:
        raise OverwriteRefused(target, single=True)
    folder = target.parent if str(target.parent) else Path(".")
    tmp: str | None = None
    fh: IO[Any] | None = None
    try:
        with held_interrupts():  # the name is recorded before an interrupt can strike
            tmp, fh = _temporary(folder, target, binary)
        with _on_disk(fh, target) as out:
            yield out
        _keep_mode(target, tmp)
        _put(tmp, target, overwrite)
        tmp = None
    finally:
        if fh is not None and not fh.closed:
            fh.close()
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)


def refuse_existing(path: str | os.PathLike, overwrite: bool) -> None:
    """Raise before any work what :func:`atomic_write` would raise at the end: an existing
    ``path`` without ``overwrite`` (:class:`OverwriteRefused`), a folder where the file goes."""
    target = Path(path)
    if target.is_dir():
        raise IsADirectoryError(f"{target} is a folder, not a file; give a file name")
    if target.exists() and not overwrite:
        raise OverwriteRefused(target, single=True)


def _put(tmp: str, target: Path, overwrite: bool) -> None:
    """Rename ``tmp`` to ``target``; without ``overwrite`` never over an existing file."""
    if overwrite:
        os.replace(tmp, target)
        return
    try:
        os.link(tmp, target)  # atomic and fails if target exists (no race with a new file)
    except FileExistsError:
        raise OverwriteRefused(target, single=True) from None
    except OSError:  # no hard links here (some network or FAT file systems)
        if target.exists():
            raise OverwriteRefused(target, single=True) from None
        os.replace(tmp, target)
        return
    os.unlink(tmp)


def _keep_mode(target: Path, tmp: str) -> None:
    # mkstemp creates the file 0600; give it the mode a plain open() would (umask), or the
    # replaced file's own mode
    try:
        mode = target.stat().st_mode & 0o777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        mode = 0o666 & ~umask
    os.chmod(tmp, mode)


def atomic_write(path: str | os.PathLike, content: Content, *, overwrite: bool = False,
                 binary: bool | None = None) -> Path:
    """Write ``content`` to ``path`` atomically; see the module docstring for the rules.

    Parameters
    ----------
    path : str or path-like
    content : str, bytes or callable
        The text or bytes to write, or a function that writes to the open file it is given
        (text mode unless ``binary=True``).
    overwrite : bool
        Replace an existing file (default: refuse with :class:`OverwriteRefused`).
    binary : bool, optional
        Open the file in binary mode (default: for ``bytes`` content).

    Returns
    -------
    pathlib.Path
        The path written.
    """
    is_binary = isinstance(content, bytes) if binary is None else binary
    with staged(path, overwrite=overwrite, binary=is_binary) as fh:
        if callable(content):
            content(fh)
        else:
            fh.write(content)
    return Path(path)


# --------------------------------------------------------------------------------------------
# a folder of results, written as one set
# --------------------------------------------------------------------------------------------
def read_manifest(folder: str | os.PathLike) -> dict[str, str | None]:
    """The files roughbrdf wrote into ``folder``, ``{name: sha256}`` (None: hash unknown, a
    manifest of an older version); empty if the folder has no manifest.

    Raises :class:`ManifestRefused` naming the manifest if it is not one roughbrdf can trust
    (a symbolic link, not JSON, a name that is a path or leads outside the folder ...).
    """
    try:
        return journal.read_manifest(folder)[0]
    except journal.BadRecord as exc:
        raise ManifestRefused(exc.path, exc.reason) from None


def recover(folder: str | os.PathLike) -> list[Path]:
    """Repair what killed processes left in ``folder``; returns the paths acted upon.

    A commit journal (:data:`JOURNAL`) is rolled forward when every new file of the set is
    still there with its recorded SHA-256, else back (the old set and manifest come back):
    the folder then holds one complete set. The temporary files (:data:`TMP_PREFIX`) of
    processes that no longer exist, and a lock (:data:`LOCK`) whose process no longer exists,
    are removed. A live process's files are never touched: while another live run holds the
    lock, only temporary files whose process id names a dead process are removed.
    :class:`ResultFolder` calls this on entering a folder. Raises :class:`ManifestRefused` for
    a journal roughbrdf did not write.
    """
    path = Path(folder)
    if not path.is_dir():  # nothing to repair where nothing was written
        return []
    lock = path / LOCK
    had_lock = lock.exists()
    rf = ResultFolder(path)
    try:
        rf.take_lock()
    except OverwriteRefused:  # a live run writes there: its own files are not ours to touch
        return journal.remove_dead_temps(path, old_names=False)
    try:
        return rf.recovered + ([lock] if had_lock else [])
    finally:
        rf.release_lock()


class ResultFolder:
    """A folder of results written as one all-or-nothing set, one run at a time.

    Use it as a context manager, :meth:`add` every file, and the set is committed when the
    block ends without an error::

        with ResultFolder("fit-silver", overwrite=False) as out:
            out.add("fit.json", text)
            out.add("fit_525nm.png", lambda fh: fig.savefig(fh, format="png"), binary=True)

    Rules (the CLI's ``--force`` is ``overwrite=True``):

    * **refuse** (:class:`OverwriteRefused`, naming the files) if the folder holds the results
      of an earlier run (files its :data:`MANIFEST` lists) or any file this set would write,
      unless ``overwrite``; even then a file of the same name that roughbrdf did not write, or
      a listed file whose content changed since roughbrdf wrote it (its SHA-256 differs from
      the manifest's), is refused: files the user made or edited are never replaced or
      removed. ``adopt`` names files an older version wrote outside any set (or that the
      caller names explicitly): with ``overwrite`` they may be replaced though unlisted;
    * a manifest that is a symbolic link, not JSON, or lists a name that is a path, leads
      outside the folder or is a symbolic link out of it, is refused
      (:class:`ManifestRefused`, naming it) and never acted upon;
    * with ``overwrite``, the new set replaces exactly the old one: files of the old set that
      the new one does not write are removed, every other file stays;
    * ``extend=True`` adds files to the folder's set instead (``roughbrdf plot --fit DIR``
      adds its figures to the fit's results): the old set stays, and only files of the same
      names are replaced (with ``overwrite``);
    * **all or nothing, even if the process is killed**: each file is written to a temporary
      file in the folder and fsynced; only when all are written is the commit journal
      (:data:`JOURNAL`: names, SHA-256, backup names) written and fsynced; then, with Ctrl-C
      held, each old file is renamed aside, each new one into place, the folder fsynced, the
      manifest written, the backups and the journal removed. An error or interrupt before the
      journal leaves the old set as it was; a kill after it is repaired by the next
      :class:`ResultFolder` on the folder (:func:`recover`): old set or new, never a mix;
    * **one run at a time**: :data:`LOCK` is created exclusively; a second run is refused with a
      message naming the lock (a lock left by a process that no longer exists is taken over).
    """

    def __init__(self, path: str | os.PathLike, *, overwrite: bool = False,
                 extend: bool = False, adopt: Iterable[str] = ()) -> None:
        self.path = Path(path)
        self.overwrite = overwrite
        self.extend = extend
        self.adopt = frozenset(adopt)
        self._staged: dict[str, str] = {}  # name -> temporary file
        self._hashes: dict[str, str] = {}  # name -> SHA-256 of the staged bytes
        self._locked = False
        #: what :func:`recover` repaired on entering the folder
        self.recovered: list[Path] = []

    # -- context ---------------------------------------------------------------------------
    def __enter__(self) -> ResultFolder:
        ensure_folder(self.path)
        self.take_lock()
        return self

    def __exit__(self, exc_type: Any, exc: Any, tb: Any) -> None:
        try:
            if exc_type is None:
                self.commit()
        finally:
            with held_interrupts():  # a second Ctrl-C must not leave temporary files behind
                self._discard()
                self.release_lock()

    # -- content ---------------------------------------------------------------------------
    def previous(self) -> list[str]:
        """Names the folder's manifest lists (the last committed set), empty if none.

        Raises :class:`ManifestRefused` for a manifest roughbrdf will not trust."""
        return sorted(read_manifest(self.path))

    def check(self, names: Iterable[str]) -> None:
        """Raise if writing ``names`` here would break a rule (call it before expensive work).

        :class:`OverwriteRefused` for files the rules do not let this set replace or a folder
        another run is writing into (:class:`ManifestRefused` for a manifest it will not
        trust); :class:`NotADirectoryError` if the folder or one of its parents is a file;
        :class:`PermissionError` if the folder (or the nearest existing parent, where it
        would be created) cannot be written.
        """
        names = set(names)
        self._check_location()
        if not self._locked and self.path.is_dir() and (
                os.path.lexists(self.path / JOURNAL) or any(self.path.glob(f"{TMP_PREFIX}*"))):
            recover(self.path)  # a killed run's commit: judge the set it leaves
        if not self._locked and (self.path / LOCK).exists() \
                and not lock_is_stale(self.path / LOCK):
            raise OverwriteRefused(self.path, locked=True)
        old = read_manifest(self.path)
        here = {n for n in names | set(old) | self.adopt if os.path.lexists(self.path / n)}
        listed = {n for n in old if n in here}
        adopted = (self.adopt & here) - listed
        # a folder now where roughbrdf wrote a file (an old manifest has no hash to tell)
        changed = {n for n in listed if (old[n] is not None and file_sha256(self.path / n)
                                         != old[n]) or _is_real_dir(self.path / n)}
        touched = (names & here) if self.extend else (names & here) | listed
        foreign = (names & here) - listed - adopted
        results = ((touched & listed) | (adopted & names)) - changed if self.extend \
            else (listed | (adopted & names)) - changed
        changed &= touched
        if foreign or changed or (results and not self.overwrite):
            raise OverwriteRefused(self.path, results=() if self.overwrite else results,
                                   foreign=foreign, overwrite=self.overwrite, changed=changed)

    def _check_location(self) -> None:
        block = _blocking_file(self.path)
        if block is not None:
            where = "" if block == self.path else f" ({block} is a file)"
            raise NotADirectoryError(errno.ENOTDIR, f"not a folder{where}", str(self.path))
        existing = next(p for p in (self.path, *self.path.parents, Path(".")) if p.exists())
        if not os.access(existing, os.W_OK | os.X_OK):
            raise PermissionError(errno.EACCES, "permission denied (cannot write there)",
                                  str(self.path if existing == self.path else existing))

    def add(self, name: str, content: Content, *, binary: bool | None = None) -> Path:
        """Stage ``name`` (text, bytes, or a function writing to the open file); returns the
        path it will have once committed."""
        if os.sep in name or "/" in name or name in (MANIFEST, LOCK) or name.startswith("."):
            raise ValueError(f"not a result file name: {name!r}")
        is_binary = isinstance(content, bytes) if binary is None else binary
        fh: IO[Any] | None = None
        try:
            with held_interrupts():  # the temporary file is recorded before an interrupt
                if name in self._staged:  # staged twice: the later content wins
                    with contextlib.suppress(OSError):
                        os.unlink(self._staged.pop(name))
                tmp, fh = _temporary(self.path, self.path / name, is_binary)
                self._staged[name] = tmp
            with _on_disk(fh, self.path / name) as out:  # fsynced before any rename
                if callable(content):
                    content(out)
                else:
                    out.write(content)
            self._hashes[name] = file_sha256(tmp) or ""
        except BaseException:  # a file that failed is not part of the set
            if name in self._staged:
                with contextlib.suppress(OSError):
                    os.unlink(self._staged.pop(name))
            raise
        finally:
            if fh is not None and not fh.closed:
                fh.close()
        return self.path / name

    def commit(self) -> list[Path]:
        """Put the staged set in place (see the class docstring); returns the paths."""
        raise_if_interrupted()  # a Ctrl-C that a library swallowed still stops the commit
        names = sorted(self._staged)
        self.check(names)
        try:
            old, old_text = journal.read_manifest(self.path)
        except journal.BadRecord as exc:  # changed since check(): refused all the same
            raise ManifestRefused(exc.path, exc.reason) from None
        kept = {n: h for n, h in old.items() if os.path.lexists(self.path / n)}
        stale = [] if self.extend else [n for n in kept if n not in self._staged]
        new = {n: (os.path.basename(self._staged[n]), self._hashes[n]) for n in names}
        listed: dict[str, str | None] = {**kept, **self._hashes} if self.extend \
            else dict(self._hashes)
        with held_interrupts():
            for name in names:
                _keep_mode(self.path / name, self._staged[name])
            journal.commit_set(self.path, new, stale, listed, old_text)
            self._staged.clear()
        return [self.path / n for n in names]

    # -- lock and clean-up -----------------------------------------------------------------
    def take_lock(self) -> None:
        """Take the folder's :data:`LOCK` (a stale one is taken over), then repair what a
        killed run left (:func:`recover`); :class:`OverwriteRefused` if a live run holds it."""
        try:
            self._lock()
            try:
                self.recovered = journal.recover_locked(self.path)
            except journal.BadRecord as exc:
                raise ManifestRefused(exc.path, exc.reason) from None
        except BaseException:
            self.release_lock()
            raise

    def _lock(self) -> None:
        lock = self.path / LOCK
        for _ in range(2):
            with held_interrupts():  # never leave an empty lock file behind
                try:
                    fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
                except FileExistsError:
                    fd = -1
                else:
                    self._locked = True
                    with os.fdopen(fd, "w") as fh:
                        fh.write(f"{os.getpid()}\n")
            if self._locked:
                return
            if not lock_is_stale(lock):
                raise OverwriteRefused(self.path, locked=True)
            with contextlib.suppress(FileNotFoundError):
                lock.unlink()
        raise OverwriteRefused(self.path, locked=True)

    def release_lock(self) -> None:
        """Remove the folder's lock if this object holds it."""
        if self._locked:
            with contextlib.suppress(FileNotFoundError):
                (self.path / LOCK).unlink()
            self._locked = False

    def _discard(self) -> None:
        for tmp in self._staged.values():
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        self._staged.clear()
