"""Output folders that never overwrite a user's file silently.

``roughbrdf fit --out DIR`` and ``python -m roughbrdf.demo --out DIR`` write into a folder that
may already exist. The rule:

* the folder is created if needed; files already in it that roughbrdf did not write are never
  touched;
* every file roughbrdf writes there is recorded in ``DIR/.roughbrdf-outputs`` (a JSON list of
  file names); a later run may replace exactly those files;
* a file of the same name that is *not* in that record (the user's own ``report.txt``, say)
  stops the run with an error before anything is written, unless ``force=True``
  (CLI ``--force``).
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from pathlib import Path

MANIFEST = ".roughbrdf-outputs"

__all__ = ["OutputDir", "MANIFEST"]


class OutputDir:
    """A folder we write results into; see the module docstring for the overwrite rule."""

    def __init__(self, path: str | Path, *, force: bool = False) -> None:
        self.path = Path(path)
        self.force = force
        if self.path.exists() and not self.path.is_dir():
            raise FileExistsError(f"{self.path} exists and is not a folder")
        self.owned = set(self._read_manifest())

    def _read_manifest(self) -> list[str]:
        m = self.path / MANIFEST
        if not m.is_file():
            return []
        try:
            data = json.loads(m.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return []
        return [str(x) for x in data] if isinstance(data, list) else []

    def check(self, names: Iterable[str]) -> None:
        """Raise ``FileExistsError`` if any of ``names`` exists and is not ours (unless forced)."""
        if self.force:
            return
        clash = [n for n in names if (self.path / n).exists() and n not in self.owned]
        if clash:
            raise FileExistsError(
                f"{self.path}: not overwriting {', '.join(sorted(clash))} (not written by "
                f"roughbrdf, or written before {MANIFEST} existed); choose another folder or "
                f"pass --force (force=True)")

    def file(self, name: str) -> Path:
        """Path for ``name`` inside the folder; checks it and records it as ours."""
        self.check([name])
        self.path.mkdir(parents=True, exist_ok=True)
        # merge with the record on disk: another OutputDir on the same folder may have added to it
        known = set(self._read_manifest())
        if name not in known:
            self.owned |= known | {name}
            (self.path / MANIFEST).write_text(json.dumps(sorted(self.owned), indent=1) + "\n",
                                              encoding="utf-8")
        self.owned |= known
        return self.path / name

    def write_text(self, name: str, text: str) -> Path:
        p = self.file(name)
        p.write_text(text if text.endswith("\n") else text + "\n", encoding="utf-8")
        return p
