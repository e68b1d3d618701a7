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

Examples
--------
>>> a = fingerprint("tr75", {"starts": 2, "seed": 0})
>>> a == fingerprint("tr75", {"seed": 0, "starts": 2}), a == fingerprint("tr75", {"starts": 3})
(True, False)
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

from ..output import file_sha256

__all__ = ["TASK_FILE", "fingerprint", "file_sha256", "completed_rows"]

#: the record of the catalogue task in each per-file folder
TASK_FILE = "catalogue-task.json"


def fingerprint(model: Any, options: dict[str, Any]) -> str:
    """SHA-256 of the model (spec or ``Model.to_dict()``) and the options, key order ignored."""
    spec = model.to_dict() if hasattr(model, "to_dict") else str(model)
    text = json.dumps({"model": spec, "options": options}, sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()


def completed_rows(folder: str | Path, sha256: str | None,
                   fp: str) -> list[dict[str, Any]] | None:
    """The rows of the complete earlier result in ``folder`` for this input and fingerprint,
    marked ``"skipped (resume)"``; None if there is none (or it differs, or is incomplete)."""
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
    return [{**r, "status": "skipped (resume)"} for r in rows]
