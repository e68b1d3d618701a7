"""``--resume``: which inputs already have complete results for the same input, model and options.

Each per-file fit folder of a catalogue holds, besides the fit's own files, :data:`TASK_FILE`
(written in the same all-or-nothing set, :class:`roughbrdf.output.ResultFolder`):
``{"sha256": input hash, "fingerprint": model + options, "files": [...], "rows": [...]}``.
An input is skipped when that file exists, its ``sha256`` and ``fingerprint`` equal the new
run's, and every file it lists (and the task file itself) is in the folder with the SHA-256 the
folder's manifest records for it: a complete set, byte for byte. A commit a killed run left
half done is first rolled forward or back (:func:`roughbrdf.output.recover`); a file altered
or truncated since, a manifest of an older version (no hashes), a manifest roughbrdf will not
trust or a folder another live run is writing into count as not complete.

The rows kept are marked ``"skipped (resume)"``, with the status they had when fitted in
``earlier_status`` (what the exit status counts, :func:`roughbrdf.catalogue.rows.outcome`), and
name the input where it is now: the same bytes (the same SHA-256) found at a new path are the
same input, moved.

A catalogue never takes its own outputs as inputs (:func:`own_outputs`): ``catalogue.csv``,
``catalogue.json``, the summary pages, whatever its folder's manifest lists and every file of
its fit folders, when the inputs are given as the catalogue folder itself (``--out IN`` for
``IN``) or a glob that reaches into it.

Examples
--------
>>> a = fingerprint("tr75", {"starts": 2, "seed": 0})
>>> a == fingerprint("tr75", {"seed": 0, "starts": 2}), a == fingerprint("tr75", {"starts": 3})
(True, False)
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from ..output import file_sha256

__all__ = ["TASK_FILE", "fingerprint", "file_sha256", "completed_rows", "own_outputs",
           "without_own_outputs"]

#: the record of the catalogue task in each per-file folder
TASK_FILE = "catalogue-task.json"


def fingerprint(model: Any, options: dict[str, Any]) -> str:
    """SHA-256 of the model (spec or ``Model.to_dict()``) and the options, key order ignored."""
    spec = model.to_dict() if hasattr(model, "to_dict") else str(model)
    text = json.dumps({"model": spec, "options": options}, sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()


def completed_rows(folder: str | Path, sha256: str | None, fp: str,
                   file: str | None = None) -> list[dict[str, Any]] | None:
    """The rows of the complete earlier result in ``folder`` for this input and fingerprint,
    marked ``"skipped (resume)"`` (``earlier_status``: their status then); None if there is
    none (or it differs, or is incomplete).

    ``file`` is the input as given now: the rows name it (the result is for the same bytes,
    wherever they were when fitted); None keeps the names the rows recorded."""
    from ..output import JOURNAL, read_manifest, recover

    folder = Path(folder)
    if sha256 is None:
        return None
    try:
        recover(folder)  # a killed run's commit is rolled forward or back first
        listed = read_manifest(folder)
        task = json.loads((folder / TASK_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError):  # OverwriteRefused is an OSError: an untrusted record
        return None
    if (folder / JOURNAL).exists():  # a live run is committing there right now
        return None
    if not isinstance(task, dict) or task.get("sha256") != sha256 \
            or task.get("fingerprint") != fp:
        return None
    files = [str(f) for f in task.get("files", [])]
    for f in [*files, TASK_FILE]:
        digest = listed.get(f)
        # the hash the commit recorded, and the bytes now: both known and equal
        if digest is None or not (folder / f).is_file() or file_sha256(folder / f) != digest:
            return None
    rows = task.get("rows")
    if not isinstance(rows, list) or not rows:
        return None
    if not all(isinstance(r, dict) for r in rows):  # a record roughbrdf did not write
        return None
    now = {} if file is None else {"file": file}
    return [{**r, **now, "status": "skipped (resume)", "earlier_status": r.get("status")}
            for r in rows]


def own_outputs(out_dir: str | os.PathLike, reserved: Iterable[str] = ()) -> set[str]:
    """The real paths of the files a catalogue in ``out_dir`` wrote or may write, none of
    which is ever an input: the names ``reserved`` (the catalogue files and summary pages,
    whether they exist yet or not), the files its manifest lists, and every file of its fit
    folders (the sub-folders holding a manifest or a :data:`TASK_FILE`)."""
    from ..output import MANIFEST, read_manifest

    out = Path(out_dir)
    if not out.is_dir():  # a first run: nothing is there yet
        return set()
    names = set(reserved)
    try:
        names.update(read_manifest(out))
    except OSError:  # a manifest roughbrdf will not trust: the run refuses it later
        pass
    found = {os.path.realpath(out / n) for n in names}
    for sub in out.iterdir():
        # only folders a catalogue (or a fit) wrote: a folder of the user's data stays an input
        if sub.is_dir() and not sub.is_symlink() and (
                (sub / MANIFEST).is_file() or (sub / TASK_FILE).is_file()):
            found.update(os.path.realpath(p) for p in sub.rglob("*") if p.is_file())
    return found


def without_own_outputs(files: list[str], out_dir: str | os.PathLike,
                        reserved: Iterable[str] = ()) -> list[str]:
    """``files`` less the outputs of the catalogue in ``out_dir`` (:func:`own_outputs`)."""
    own = own_outputs(out_dir, reserved)
    return [f for f in files if os.path.realpath(f) not in own]
