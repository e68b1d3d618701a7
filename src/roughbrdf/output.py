"""Writing files without losing anything a user has: atomic writes, no overwrite unless asked.

Every file roughbrdf writes goes through :func:`atomic_write`:

* an existing file is never replaced unless the caller asks (``overwrite=True``; the CLI's
  ``--force``): :class:`FileExistsError` names it otherwise;
* the content goes to a temporary file in the same folder, which is then renamed over the
  target (:func:`os.replace`, atomic on POSIX and Windows): a reader, a crash or Ctrl-C sees the
  old file or the new one, never a mix and never a 0-byte file;
* if writing fails or is interrupted, the temporary file is removed and the error propagates.

Examples
--------
>>> import pathlib, tempfile
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> atomic_write(d / "a.txt", "first\\n")
PosixPath('...a.txt')
>>> atomic_write(d / "a.txt", "second\\n")
Traceback (most recent call last):
...
FileExistsError: ...a.txt exists; not overwriting it (pass overwrite=True)
>>> _ = atomic_write(d / "a.txt", "second\\n", overwrite=True)
>>> (d / "a.txt").read_text()
'second\\n'
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO, Any

__all__ = ["atomic_write", "staged", "same_file", "ResultFolder", "MANIFEST", "LOCK"]

#: prefix of the temporary files (a leftover one, after a power cut, is recognizable)
TMP_PREFIX = ".roughbrdf-tmp-"


def same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether ``a`` and ``b`` name the same existing file (links and relative paths resolved)."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


@contextlib.contextmanager
def staged(path: str | os.PathLike, *, overwrite: bool = False, binary: bool = False
           ) -> Iterator[IO[Any]]:
    """Open a temporary file beside ``path``; on a clean exit it replaces ``path`` atomically.

    Raises :class:`FileExistsError` before anything is written if ``path`` exists and
    ``overwrite`` is false, and :class:`IsADirectoryError` if ``path`` is a folder. On any
    exception (``KeyboardInterrupt`` included) the temporary file is removed and ``path`` is
    left as it was.
    """
    target = Path(path)
    if target.is_dir():
        raise IsADirectoryError(f"{target} is a folder, not a file")
    if target.exists() and not overwrite:
        raise FileExistsError(f"{target} exists; not overwriting it (pass overwrite=True)")
    folder = target.parent if str(target.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix=TMP_PREFIX, suffix=".part", dir=folder)
    try:
        fh_: IO[Any] = (os.fdopen(fd, "wb") if binary
                        else os.fdopen(fd, "w", encoding="utf-8", newline=""))
        with fh_ as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())  # the bytes are on disk before the name points at them
        _keep_mode(target, tmp)
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


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


def atomic_write(path: str | os.PathLike, content: str | bytes | Callable[[IO[Any]], None], *,
                 overwrite: bool = False, binary: bool | None = None) -> Path:
    """Write ``content`` to ``path`` atomically; see the module docstring for the rules.

    Parameters
    ----------
    path : str or path-like
    content : str, bytes or callable
        The text or bytes to write, or a function that writes to the open file it is given
        (text mode unless ``binary=True``).
    overwrite : bool
        Replace an existing file (default: refuse with :class:`FileExistsError`).
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
#: the record of the files roughbrdf wrote into a results folder (JSON list of names)
MANIFEST = ".roughbrdf-outputs"
#: present while a run writes into the folder (holds its process id)
LOCK = ".roughbrdf-lock"


class ResultFolder:
    """A folder of results written as one all-or-nothing set, one run at a time.

    Use it as a context manager, :meth:`add` every file, and the set is committed when the
    block ends without an error::

        with ResultFolder("fit-silver", overwrite=False) as out:
            out.add("fit.json", text)
            out.add("fit_525nm.png", lambda fh: fig.savefig(fh, format="png"), binary=True)

    Rules (the CLI's ``--force`` is ``overwrite=True``):

    * **refuse** (:class:`FileExistsError`, naming the files) if the folder holds the results of
      an earlier run (its :data:`MANIFEST`) or any file this set would write, unless
      ``overwrite``; even then a file of the same name that roughbrdf did not write is refused
      (move it away): files the user made are never replaced;
    * with ``overwrite``, the new set replaces exactly the old one: files of the old set that
      the new one does not write are removed, every other file stays;
    * **all or nothing**: each file is written to a temporary file in the folder first; only
      when all are written are they renamed into place, with Ctrl-C held
      (:func:`roughbrdf.interrupts.held_interrupts`), then the manifest, then the stale files
      go. An error or interrupt before that removes the temporary files and leaves the old set
      as it was;
    * **one run at a time**: :data:`LOCK` is created exclusively; a second run is refused with a
      message naming the lock (a lock left by a process that no longer exists is taken over).
    """

    def __init__(self, path: str | os.PathLike, *, overwrite: bool = False) -> None:
        self.path = Path(path)
        self.overwrite = overwrite
        self._staged: dict[str, str] = {}  # name -> temporary file
        self._locked = False

    # -- context ---------------------------------------------------------------------------
    def __enter__(self) -> ResultFolder:
        if self.path.exists() and not self.path.is_dir():
            raise NotADirectoryError(f"{self.path} exists and is not a folder")
        self.path.mkdir(parents=True, exist_ok=True)
        self._lock()
        return self

    def __exit__(self, exc_type: Any, exc: Any, tb: Any) -> None:
        try:
            if exc_type is None:
                self.commit()
        finally:
            self._discard()
            self._unlock()

    # -- content ---------------------------------------------------------------------------
    def previous(self) -> list[str]:
        """Names the folder's manifest lists (the last committed set), empty if none."""
        import json

        m = self.path / MANIFEST
        try:
            data = json.loads(m.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return []
        return [str(x) for x in data] if isinstance(data, list) else []

    def check(self, names: list[str]) -> None:
        """Raise :class:`FileExistsError` if writing ``names`` here would replace anything the
        rules do not allow (call it before expensive work)."""
        old = set(self.previous())
        if not self.overwrite:
            clash = sorted(old | {n for n in names if (self.path / n).exists()})
            if clash:
                raise FileExistsError(
                    f"{self.path} holds results already ({', '.join(clash)}); choose another "
                    f"folder or replace them with --force (overwrite=True)")
            return
        foreign = sorted(n for n in names if (self.path / n).exists() and n not in old)
        if foreign:
            raise FileExistsError(
                f"{self.path}: {', '.join(foreign)} not written by roughbrdf; not replacing "
                f"it even with --force (move it away or choose another folder)")

    def add(self, name: str, content: str | bytes | Callable[[IO[Any]], None], *,
            binary: bool | None = None) -> Path:
        """Stage ``name`` (text, bytes, or a function writing to the open file); returns the
        path it will have once committed."""
        if os.sep in name or name in (MANIFEST, LOCK) or name.startswith("."):
            raise ValueError(f"not a result file name: {name!r}")
        is_binary = isinstance(content, bytes) if binary is None else binary
        fd, tmp = tempfile.mkstemp(prefix=TMP_PREFIX, suffix=".part", dir=self.path)
        self._staged[name] = tmp
        fh_: IO[Any] = (os.fdopen(fd, "wb") if is_binary
                        else os.fdopen(fd, "w", encoding="utf-8", newline=""))
        with fh_ as fh:
            if callable(content):
                content(fh)
            else:
                fh.write(content)
            fh.flush()
            os.fsync(fh.fileno())
        return self.path / name

    def commit(self) -> list[Path]:
        """Put the staged set in place (see the class docstring); returns the paths."""
        from .interrupts import held_interrupts

        names = sorted(self._staged)
        self.check(names)
        stale = [n for n in self.previous() if n not in self._staged]
        with held_interrupts():
            for name in names:
                _keep_mode(self.path / name, self._staged[name])
                os.replace(self._staged.pop(name), self.path / name)
            _write_manifest(self.path, names)
            for n in stale:
                with contextlib.suppress(FileNotFoundError):
                    (self.path / n).unlink()
        return [self.path / n for n in names]

    # -- lock and clean-up -----------------------------------------------------------------
    def _lock(self) -> None:
        lock = self.path / LOCK
        for _ in range(2):
            try:
                fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                if _lock_is_stale(lock):
                    with contextlib.suppress(FileNotFoundError):
                        lock.unlink()
                    continue
                raise FileExistsError(
                    f"another roughbrdf run is writing into {self.path} (lock file {lock}); "
                    f"wait for it to finish, or delete the lock file if no run is active"
                ) from None
            with os.fdopen(fd, "w") as fh:
                fh.write(f"{os.getpid()}\n")
            self._locked = True
            return

    def _unlock(self) -> None:
        if self._locked:
            with contextlib.suppress(FileNotFoundError):
                (self.path / LOCK).unlink()
            self._locked = False

    def _discard(self) -> None:
        for tmp in self._staged.values():
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        self._staged.clear()


def _write_manifest(folder: Path, names: list[str]) -> None:
    import json

    atomic_write(folder / MANIFEST, json.dumps(names, indent=1) + "\n", overwrite=True)


def _lock_is_stale(lock: Path) -> bool:
    """Whether ``lock`` names a process that no longer exists (on this machine)."""
    try:
        pid = int(lock.read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return False  # being written right now, or not ours: treat as held
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except PermissionError:
        return False
    return False
