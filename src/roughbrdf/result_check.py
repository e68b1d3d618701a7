"""Reading a results folder: one whole set, or a refusal saying why and what to do.

A results folder (:class:`roughbrdf.output.ResultFolder`: ``roughbrdf fit ... --out DIR``,
:meth:`FitResult.save <roughbrdf.fitting.results.result.FitResult.save>`) is written as one set,
through
the commit journal of :mod:`roughbrdf.journal`. A write cut off by a kill leaves the journal
beside a mix of old and new files until the next run into the folder repairs it. Every read
of such a folder (:func:`roughbrdf.load_fit`; ``--fit DIR`` of ``roughbrdf plot``, ``export``
and ``explore``) first calls :func:`check_result_folder`, which

* **refuses** a folder whose lock (:data:`~roughbrdf.output.LOCK`) names a live process:
  another run is writing into it right now, and what is there may change under the read;
* **recovers** a folder holding a commit journal (:data:`~roughbrdf.output.JOURNAL`): it takes
  the folder's lock as the writers do (:meth:`ResultFolder.take_lock
  <roughbrdf.output.ResultFolder.take_lock>`), which rolls the commit forward or back
  (:func:`roughbrdf.journal.recover_locked`: the new set when every new file is there with its
  journalled hash, else the old one), and releases it. A folder that cannot be written (no
  write permission, a read-only disk) cannot be recovered, and is refused;
* **refuses** a folder whose records roughbrdf will not trust (a manifest or journal that is a
  symbolic link, not JSON, or names something other than plain files of the folder:
  :class:`roughbrdf.output.ManifestRefused`), and one where a file its manifest
  (:data:`~roughbrdf.output.MANIFEST`, ``{name: sha256}``) lists no longer has the recorded
  SHA-256 (:func:`roughbrdf.journal.file_sha256`): it was changed after roughbrdf wrote it.

A listed file that is gone is not refused (the user removed it; what is left is as written,
and the read that needs it says so), nor is a file of a manifest of an older version, which
records no hashes. A folder without a manifest (a ``fit.json`` written by hand or by an older
version) is read as it is. The refusal is :class:`ResultFolderRefused`, a :class:`ValueError`:
one line naming the folder and what to run, in Python terms (``str(err)``) or, for the
command line, in its terms (:meth:`ResultFolderRefused.render` given the verb's options); the
command line ends with exit status 2 (:mod:`roughbrdf.cli`).

Examples
--------
>>> import pathlib, tempfile
>>> from roughbrdf.output import ResultFolder
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> with ResultFolder(d) as out:
...     _ = out.add("fit.json", "{}")
>>> check_result_folder(d)
[]
>>> _ = (d / "fit.json").write_text('{"edited": true}')
>>> check_result_folder(d)
Traceback (most recent call last):
...
roughbrdf.result_check.ResultFolderRefused: ...: fit.json was changed after roughbrdf wrote it ...
"""

from __future__ import annotations

import errno
import os
from collections.abc import Mapping
from pathlib import Path

from .journal import JOURNAL, LOCK, MANIFEST, file_sha256, lock_is_stale
from .output import ManifestRefused, OverwriteRefused, ResultFolder, read_manifest

__all__ = ["ResultFolderRefused", "check_result_folder"]

#: errors of creating the lock or renaming in a folder that cannot be written
_NOT_WRITABLE = (errno.EACCES, errno.EPERM, errno.EROFS)


class ResultFolderRefused(ValueError):
    """A results folder roughbrdf will not read: not one whole set it wrote.

    Attributes
    ----------
    folder : pathlib.Path
        The results folder.
    kind : {"locked", "read-only", "changed", "unreadable", "record"}
        Why: a live run holds its lock; a journal is there and the folder cannot be written;
        a listed file's SHA-256 differs from the manifest's; a listed file cannot be read; a
        manifest or journal roughbrdf will not trust.
    file : str or None
        The file concerned (a listed file, or the record's path), None for the folder itself.
    reason : str
        For ``"record"``: what is wrong with the record; else "".
    """

    def __init__(self, folder: str | os.PathLike, kind: str, file: str | None = None,
                 reason: str = "", options: Mapping[str, str] | None = None) -> None:
        self.folder = Path(folder)
        self.kind = kind
        self.file = file
        self.reason = reason
        super().__init__(self.render(options))

    def render(self, options: Mapping[str, str] | None = None) -> str:
        """The one line: in Python terms, or with ``options`` (the verb's ``{argument:
        option}``, :mod:`roughbrdf.cli.common`) in the command line's."""
        cli = options is not None
        d = self.folder
        if self.kind == "locked":
            return (f"another roughbrdf run is writing into {d} (lock file {d / LOCK}): what "
                    f"is there may change under the read; wait for it to finish and read again, "
                    f"or delete the lock file if no run is active")
        if self.kind == "read-only":
            again = "run the command again" if cli else "read it again (rb.load_fit)"
            return (f"{d}: a roughbrdf write into this folder was cut off (its commit journal "
                    f"{d / JOURNAL} is there) and the folder cannot be written, so roughbrdf "
                    f"cannot put it back to one whole set; make it writable (chmod u+w {d}) "
                    f"and {again}: the read then completes or undoes that write")
        if self.kind == "record":
            return (f"{self.file}: {self.reason}; roughbrdf will not read {d} by records it "
                    f"cannot trust (a folder copied from elsewhere?): check it, and delete "
                    f"{self.file} if the files it names are not results of yours")
        refit = "roughbrdf fit FILE --out NEW_DIR" if cli else "FitResult.save(NEW_DIR)"
        what = ("cannot be read, so roughbrdf cannot tell whether it is the file it wrote"
                if self.kind == "unreadable" else
                f"was changed after roughbrdf wrote it (its SHA-256 differs from the one the "
                f"folder's manifest {MANIFEST} records)")
        return (f"{d}: {self.file} {what}: the folder no longer holds the set roughbrdf wrote; "
                f"put the file back as it was, or write the results again into another folder "
                f"({refit})")


def check_result_folder(folder: str | os.PathLike, *,
                        options: Mapping[str, str] | None = None) -> list[Path]:
    """Check the results folder ``folder`` before reading it; recover it if a write was cut off.

    Parameters
    ----------
    folder : str or path-like
        The results folder (a fit's folder; for a ``fit.json`` path, pass its folder).
    options : mapping of str to str, optional
        The command line verb's ``{argument: option}`` (:mod:`roughbrdf.cli.common`): the
        refusal is then worded for the command line. Default: Python terms.

    Returns
    -------
    list of pathlib.Path
        What recovery acted upon (the journal, temporary files of dead processes); empty when
        the folder was whole, has no records, or does not exist (the reader's own error then
        names what is missing).

    Raises
    ------
    ResultFolderRefused
        A live run's lock; a journal in a folder that cannot be written; a record roughbrdf
        will not trust; a listed file changed since roughbrdf wrote it, or unreadable (module
        docstring).
    """
    path = Path(folder)
    if not path.is_dir():  # nothing written there: the reader's own error names what is gone
        return []
    lock = path / LOCK
    # a live writer: its commit may rename files while this read runs (a stale lock, of a
    # process that no longer exists, is taken over below if recovery needs it)
    if os.path.lexists(lock) and not lock_is_stale(lock):
        raise ResultFolderRefused(path, "locked", options=options)
    # a journal: a write was cut off, and the files may be a mix until it is rolled forward
    # or back (without one, nothing is taken: a reader's lock could fail a writer's commit)
    recovered = _recover(path, options) if os.path.lexists(path / JOURNAL) else []
    try:
        listed = read_manifest(path)
    except ManifestRefused as exc:  # never judged by a record that may point anywhere
        raise ResultFolderRefused(path, "record", str(exc.record), exc.reason,
                                  options) from None
    for name, digest in sorted(listed.items()):
        # an older manifest records no hash (nothing to compare); a removed file is no mix
        if digest is None or not os.path.lexists(path / name):
            continue
        actual = file_sha256(path / name)
        if actual != digest:  # not the bytes roughbrdf committed (or not readable at all)
            kind = "unreadable" if actual is None else "changed"
            raise ResultFolderRefused(path, kind, name, options=options)
    return recovered


def _recover(path: Path, options: Mapping[str, str] | None) -> list[Path]:
    """Roll the journal of ``path`` forward or back, holding the folder's lock as the writers
    do; :class:`ResultFolderRefused` where that cannot be done."""
    # a folder this process cannot write: taking the lock or renaming would fail half-way
    if not os.access(path, os.W_OK | os.X_OK):
        raise ResultFolderRefused(path, "read-only", options=options)
    rf = ResultFolder(path)
    try:
        rf.take_lock()  # recovers the journal (journal.recover_locked) with the lock held
    except ManifestRefused as exc:  # a journal roughbrdf did not write: never acted upon
        raise ResultFolderRefused(path, "record", str(exc.record), exc.reason,
                                  options) from None
    except OverwriteRefused:  # a live run took the lock since the check above
        raise ResultFolderRefused(path, "locked", options=options) from None
    except OSError as exc:
        # not writable after all (a read-only disk that access() did not tell, ACLs)
        if exc.errno in _NOT_WRITABLE:
            raise ResultFolderRefused(path, "read-only", options=options) from None
        raise
    try:
        return list(rf.recovered)
    finally:
        rf.release_lock()
