"""The work of one catalogue task, run on a worker: read a file, fit it, save its folder.

:func:`run_task` never raises for a bad file or a failed fit: it returns a ``"failed"`` row
naming the error (:mod:`~roughbrdf.catalogue.rows`), so that one file cannot stop the others.
The per-file folder is written as one all-or-nothing set
(:class:`roughbrdf.output.ResultFolder`): ``fit.json``, ``report.txt``, the PNGs and
:data:`~roughbrdf.catalogue.resume.TASK_FILE`; an interrupted task leaves no partial set.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ..jsonsafe import clean_json
from ..models.factory import is_auto
from .resume import TASK_FILE, file_sha256
from .rows import failed_row, fit_rows, one_line

if TYPE_CHECKING:
    from ..fitting.problem.options import FitOptions

__all__ = ["Task", "run_task"]


@dataclass(frozen=True)
class Task:
    """One input file of a catalogue.

    Attributes
    ----------
    file : str
        The input path as given (rows name it so).
    path : str
        Its absolute path (what the worker reads).
    folder : str
        Absolute path of its fit folder.
    fit_dir : str
        That folder relative to the catalogue folder.
    model : Model or str
        What ``rb.fit`` gets (a model, a spec, or ``"auto"``).
    fingerprint : str
        Model and options (:func:`~roughbrdf.catalogue.resume.fingerprint`).
    label : str
        The model's label, for the rows of a file that failed.
    options : FitOptions or None
        The options of the fit (None: the defaults); fitted without a progress bar.
    """

    file: str
    path: str
    folder: str
    fit_dir: str
    model: Any
    fingerprint: str
    label: str
    options: FitOptions | None = None
    read_options: dict[str, Any] = field(default_factory=dict)
    candidates: Any = None
    cv: bool = True
    plots: bool = True
    overwrite: bool = False


def run_task(task: Task) -> list[dict[str, Any]]:
    """Read, fit and save one file; its rows (one per channel, or one ``"failed"`` row)."""
    t0 = time.perf_counter()
    sha = file_sha256(task.path)
    try:
        return _fit_and_save(task, sha, t0)
    except Exception as exc:  # a bad file or a failed fit: reported, the others go on
        # one line whatever the error says; the file's name (as given, or the absolute path
        # the reader saw) quoted when it holds a newline, a tab, an escape ...
        text = one_line(exc, names=(task.path, task.file)) or type(exc).__name__
        return [failed_row(task.file, task.label, f"{type(exc).__name__}: {text}", sha256=sha,
                           elapsed_s=time.perf_counter() - t0)]


def _fit_and_save(task: Task, sha: str | None, t0: float) -> list[dict[str, Any]]:
    import json

    from .. import io as _io
    from ..fitting import FitOptions, fit
    from ..fitting.choice.auto import fit_auto
    from ..output import ResultFolder

    meas = _io.read(task.path, **task.read_options)
    options = (task.options or FitOptions()).replace(progress=False)
    if is_auto(task.model):
        res = fit_auto(meas, task.candidates, cv=task.cv, options=options)
    else:
        res = fit(task.model, meas, options=options)
    files = res.files(plots=task.plots)
    pngs = res.plot_names() if task.plots else [None] * len(res.channels)
    figures = [None if p is None else f"{task.fit_dir}/{p}" for p in pngs]
    with ResultFolder(task.folder, overwrite=task.overwrite) as out:
        out.check([*files, TASK_FILE])  # refuse before the (slow) drawing
        for name, content in files.items():
            out.add(name, content, binary=callable(content))
        rows = fit_rows(res, task.file, fit_dir=task.fit_dir, figures=figures,
                        elapsed_s=time.perf_counter() - t0)
        record = {"sha256": sha, "fingerprint": task.fingerprint, "files": sorted(files),
                  "rows": rows}
        out.add(TASK_FILE, json.dumps(clean_json(record), indent=1) + "\n")
    return rows
