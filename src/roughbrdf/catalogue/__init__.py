"""Catalogues: fit one model to many files on ``dask.distributed`` (``docs/catalogue.md``).

:func:`fit_catalogue` runs one task per input file: a ``LocalCluster`` of worker processes on
this machine by default (one thread each, BLAS single-threaded), or the same code on an existing
cluster given by its scheduler address or a ``distributed.Client``. Each task reads its file,
fits it exactly as :func:`roughbrdf.fit` would, and saves the usual fit folder
(:meth:`roughbrdf.FitResult.save`'s files) as one all-or-nothing set; the rows of every file x
channel (:mod:`~roughbrdf.catalogue.rows`) go into ``catalogue.csv`` and ``catalogue.json``.

One job per module:

=========================================  ===================================================
:mod:`~roughbrdf.catalogue.rows`           the row schema, ``catalogue.csv`` / ``.json``
:mod:`~roughbrdf.catalogue.tasks`          the function a worker runs for one file
:mod:`~roughbrdf.catalogue.worker`         worker set-up: one BLAS thread, kernels warmed once
:mod:`~roughbrdf.catalogue.resume`         input hash + model/options fingerprint, skipping
:mod:`~roughbrdf.catalogue.run`            the cluster, the scheduling loop, progress, limits
=========================================  ===================================================

``dask`` and ``distributed`` are imported only when a catalogue runs.
"""

from __future__ import annotations

import glob
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import ArgumentError
from ..models.factory import as_model, is_auto, model_label
from ..output import LOCK, MANIFEST
from .resume import completed_rows, file_sha256, fingerprint, without_own_outputs
from .rows import outcome
from .tasks import Task

if TYPE_CHECKING:
    from ..fitting.problem.options import FitOptions

__all__ = ["fit_catalogue", "CatalogueResult", "expand_inputs", "folder_names",
           "check_options", "CATALOGUE_FILES", "RESERVED"]

#: the catalogue's own files in its folder
CATALOGUE_FILES = ("catalogue.csv", "catalogue.json")
#: the files of the summary page (:mod:`roughbrdf.catalogue.summary`)
SUMMARY_FILES = ("summary.md", "summary.html")
#: names no fit folder may take: the catalogue's own entries (and its manifest and lock)
RESERVED = (*CATALOGUE_FILES, *SUMMARY_FILES, MANIFEST, LOCK)
#: the longest fit folder stem, in UTF-8 bytes (a "-N" suffix still fits in 255)
MAX_NAME = 200


@dataclass
class CatalogueResult:
    """What :func:`fit_catalogue` returns.

    Attributes
    ----------
    rows : list of dict
        One per file x channel, in the order of the inputs (:mod:`~roughbrdf.catalogue.rows`).
    out_dir : pathlib.Path
        The catalogue folder.
    written : list of pathlib.Path
        ``catalogue.csv``, ``catalogue.json`` (and the summary's files, if any).
    """

    rows: list[dict[str, Any]]
    out_dir: Path
    written: list[Path] = field(default_factory=list)

    @property
    def failed(self) -> list[dict[str, Any]]:
        """The rows whose status is ``"failed"``."""
        return [r for r in self.rows if r["status"] == "failed"]

    @property
    def success(self) -> bool:
        """Every row is ``ok``; a row kept by ``--resume`` counts as the status it had when
        it was fitted (:func:`~roughbrdf.catalogue.rows.outcome`)."""
        return all(outcome(r) == "ok" for r in self.rows)


def expand_inputs(inputs: str | os.PathLike | Iterable[str | os.PathLike]) -> list[str]:
    """Files from paths, folders (their files, sorted) and glob patterns, duplicates removed.

    Examples
    --------
    >>> expand_inputs([])
    Traceback (most recent call last):
    ...
    roughbrdf.errors.ArgumentError: no input files were given
    """
    given = [inputs] if isinstance(inputs, str | os.PathLike) else list(inputs)
    items = [os.fspath(i) for i in given]
    out: list[str] = []
    for item in items:
        if os.path.isdir(item):
            found = sorted(str(p) for p in Path(item).iterdir()
                           if p.is_file() and not p.name.startswith("."))
        elif glob.has_magic(item):
            found = sorted(p for p in glob.glob(item) if os.path.isfile(p))
            if not found:
                raise ArgumentError("inputs", "no file matches the pattern", value=item)
        elif os.path.isfile(item):
            found = [item]
        else:
            raise FileNotFoundError(2, "no such file", item)
        out.extend(found)
    if not out:
        if not items:
            raise ArgumentError("inputs", "no input files were given")
        raise ArgumentError("inputs", "no input files found", value=", ".join(items))
    unique: dict[str, str] = {}
    for f in out:
        unique.setdefault(os.path.abspath(f), f)
    return list(unique.values())


def folder_names(files: list[str]) -> list[str]:
    """One fit folder name per file: its stem, made unique with ``-2``, ``-3`` ...

    Every name is chosen against every name already used, compared case-insensitively
    (Unicode NFC + casefold: the catalogue may lie on, or be copied to, a file system that folds
    case): the stems of the other inputs, the generated ``-N`` names and the catalogue's own
    entries (:data:`RESERVED`). A stem is kept as it is when it is free (today's names, so that
    existing catalogues resume). Characters other than letters, digits, ``-``, ``_`` and ``.``
    become ``_``; leading and trailing dots are dropped (never ``.``, ``..`` nor a hidden
    name); an empty stem becomes ``input``; a stem is cut to :data:`MAX_NAME` UTF-8 bytes. The
    names depend only on the list of inputs (the same list gives the same names).

    Examples
    --------
    >>> folder_names(["a/x.csv", "b/x.csv", "y.astm"])
    ['x', 'x-2', 'y']
    >>> folder_names(["a.astm", "a.csv", "a-2.astm", "A.astm", "..astm", "catalogue.csv.csv"])
    ['a', 'a-3', 'a-2', 'A-4', 'input', 'catalogue.csv-2']
    """
    stems = [_clean_stem(Path(f).name) for f in files]
    taken = {_fold(n) for n in RESERVED}
    names: list[str | None] = [None] * len(files)
    for k, stem in enumerate(stems):  # first pass: every stem that is free keeps its name
        if _fold(stem) not in taken:
            taken.add(_fold(stem))
            names[k] = stem
    for k, stem in enumerate(stems):  # then the repeats: the first free -N of their stem
        if names[k] is None:
            n = 2
            while _fold(f"{stem}-{n}") in taken:
                n += 1
            taken.add(_fold(f"{stem}-{n}"))
            names[k] = f"{stem}-{n}"
    return [str(n) for n in names]


def _clean_stem(filename: str) -> str:
    """The folder stem of an input file's name (see :func:`folder_names`)."""
    stem = Path(filename).stem if filename not in (".", "..") else ""
    stem = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in stem)
    stem = stem.strip(".")  # ".", "..", hidden names (".roughbrdf-lock"), Windows' "a."
    while len(stem.encode()) > MAX_NAME:  # a folder name has at most 255 bytes
        stem = stem[:-1]
    return stem.rstrip(".") or "input"


def _fold(name: str) -> str:
    """``name`` as a case-folding file system compares it."""
    import unicodedata

    return unicodedata.normalize("NFC", name).casefold()


def fit_catalogue(inputs: str | os.PathLike | Iterable[str | os.PathLike], model: Any,
                  out_dir: str | os.PathLike, *, client: Any = None,
                  scheduler: str | None = None, n_workers: int | None = None,
                  resume: bool = False, overwrite: bool = False, plots: bool = True,
                  read_options: Mapping[str, Any] | None = None,
                  candidates: Any = None, cv: bool = True, time_limit: float | None = None,
                  retries: int = 1, progress: bool | None = None,
                  options: FitOptions | None = None, **fit_options: Any) -> CatalogueResult:
    """Fit ``model`` to every input file, one task per file, on ``dask.distributed``.

    Parameters
    ----------
    inputs : path, folder, glob pattern, or a list of them
        The measurement files (:func:`expand_inputs`).
    model : Model or str
        As for :func:`roughbrdf.fit` (``"auto"``: the best of ``candidates`` by cross-validation).
    out_dir : path
        The catalogue folder: one fit folder per input (named by :func:`folder_names`),
        ``catalogue.csv`` and ``catalogue.json``.
    client : distributed.Client, optional
        Run on this client's cluster (it is left open).
    scheduler : str, optional
        Address of a running scheduler (``tcp://HOST:PORT``); not with ``client``.
    n_workers : int, optional
        Worker processes of the ``LocalCluster`` started when neither ``client`` nor
        ``scheduler`` is given (default: the CPUs, at most one per file).
    resume : bool
        Skip the inputs whose fit folder holds complete results for the same input bytes,
        model and options (:mod:`~roughbrdf.catalogue.resume`); redo the others, replacing
        their earlier results, and replace the catalogue files.
    overwrite : bool
        Replace earlier results (the CLI's ``--force``); without it (or ``resume``) a folder
        holding results stops the run before any work. Files roughbrdf did not write are never
        replaced.
    plots : bool
        Write ``fit_<channel>.png`` in each fit folder.
    read_options : mapping, optional
        Passed to :func:`roughbrdf.read` (``format``, ``quantity``, ``angles``).
    candidates, cv
        With ``model="auto"``: as for :func:`roughbrdf.fitting.choice.auto.fit_auto`.
    time_limit : float, optional
        Seconds one task may run; a task over it is reported failed and its worker restarted.
    retries : int
        How often a task is run again when its worker died under it.
    progress : bool or None
        Progress bar (files, channels, failures, ETA); None: on an interactive terminal.
    options : FitOptions, optional
        The options of every file's fit (:class:`roughbrdf.fitting.FitOptions`; its
        ``progress`` is not used: each fit runs without a bar).
    **fit_options
        Options of :func:`roughbrdf.fit` by name (``fix``, ``bounds``, ``loss``, ``starts``,
        ...), replacing those of ``options``.

    Returns
    -------
    CatalogueResult

    Notes
    -----
    Ctrl-C cancels the tasks and closes a cluster this call started; every fit folder that was
    finished is complete and no catalogue file is written.
    """
    from ..output import ResultFolder
    from . import summary  # the summary page (imports NumPy: loaded when a catalogue runs)
    from .run import run_tasks

    if client is not None and scheduler is not None:
        raise ArgumentError("scheduler", "give either a client or a scheduler address",
                            value=scheduler)
    fit_opts = check_options(model, fit_options, read_options=read_options,
                             time_limit=time_limit, retries=retries, n_workers=n_workers,
                             options=options)
    out = Path(out_dir)
    # the catalogue's own files are never inputs (`fit-batch IN --out IN`, with or without
    # --resume): they would be "fitted" and fail
    files = without_own_outputs(expand_inputs(inputs), out, RESERVED)
    if not files:
        raise ArgumentError("inputs", "no input files found (besides the catalogue's own)",
                            value=os.fspath(out))
    # the fingerprint of --resume: the options of `options` that differ from the defaults and
    # the keywords as given (a keyword call fingerprints as it did before FitOptions existed)
    given = {**({} if options is None else options.changed()), **fit_options}
    opts = {"fit": {k: v for k, v in given.items() if k != "progress"},
            "read": dict(read_options or {}), "plots": plots, "candidates": candidates,
            "cv": cv}
    fp = fingerprint(model, opts)
    label = _label(model)
    tasks, kept = [], {}
    own = (*CATALOGUE_FILES, *SUMMARY_FILES)
    # the catalogue files and the summary pages are one set (adopt: pages an older version
    # wrote outside the set may be replaced with --force/--resume)
    with ResultFolder(out, overwrite=overwrite or resume, adopt=SUMMARY_FILES) as cat:
        cat.check(own)
        for i, (f, name) in enumerate(zip(files, folder_names(files), strict=True)):
            folder = out / name
            rows = completed_rows(folder, file_sha256(f), fp, file=f) if resume else None
            if rows is not None:
                kept[i] = rows
                continue
            if not (overwrite or resume):
                ResultFolder(folder).check([])
            tasks.append((i, Task(file=f, path=os.path.abspath(f), folder=str(folder.resolve()),
                                  fit_dir=name, model=model, fingerprint=fp, label=label,
                                  options=fit_opts, read_options=opts["read"],
                                  candidates=candidates, cv=cv, plots=plots,
                                  overwrite=overwrite or resume)))
        done = run_tasks(tasks, model, client=client, scheduler=scheduler, n_workers=n_workers,
                         time_limit=time_limit, retries=retries, progress=progress,
                         skipped=sum(len(r) for r in kept.values()))
        rows = [r for i in range(len(files)) for r in (kept.get(i) or done.get(i) or [])]
        from .rows import csv_text, json_text

        cat.add("catalogue.csv", csv_text(rows))
        cat.add("catalogue.json", json_text(rows, model=label))
        summary.write_summary(out, rows, overwrite=overwrite or resume, into=cat)
    return CatalogueResult(rows=rows, out_dir=out, written=[out / n for n in own])


def check_options(model: Any, fit_options: Mapping[str, Any] | None = None, *,
                  read_options: Mapping[str, Any] | None = None, time_limit: float | None = None,
                  retries: int = 1, n_workers: int | None = None,
                  options: FitOptions | None = None) -> FitOptions:
    """Check the options of :func:`fit_catalogue` once, before any cluster starts; the fit
    options of every task (``options`` with ``fit_options`` by name replacing fields).

    Every option that a worker would reject for *any* file raises here
    (:class:`~roughbrdf.errors.ArgumentError` naming the argument), instead of failing each
    file on the workers: unknown keywords of :func:`roughbrdf.fit`, the checks of
    :class:`roughbrdf.fitting.FitOptions` (loss, starts, seed, subsample, aperture, fit
    domain ...) and those of :class:`roughbrdf.fitting.problem.plan.FitPlan` (fix, bounds) on a
    small
    stand-in measurement, without fitting. Options whose validity depends on the file (a
    channel label, ``quantity=`` against what the file says) are left to the task.

    Examples
    --------
    >>> check_options("tr75", {"starts": 0})
    Traceback (most recent call last):
    ...
    roughbrdf.errors.ArgumentError: starts must be >= 1 (an integer), got 0
    """
    import dataclasses

    from ..fitting.problem.options import FitOptions

    _check_run_options(time_limit, retries, n_workers)
    if read_options:
        _check_read_options(read_options)
    known = {f.name for f in dataclasses.fields(FitOptions)}
    for name in fit_options or {}:  # a misspelt keyword: TypeError on every worker otherwise
        if name not in known or name == "progress":  # the catalogue has its own bar
            raise ArgumentError(name, f"{name}= is not an option of roughbrdf.fit (known: "
                                f"{', '.join(sorted(known))})")
    opts = FitOptions.of(options, fit_options, caller="fit_catalogue").replace(progress=False)
    seed = opts.seed
    # numpy's generators refuse a negative seed ("expected non-negative integer") on the worker
    if seed is not None and not isinstance(seed, bool) and isinstance(seed, int) and seed < 0:
        raise ArgumentError("seed", "must be None or an integer >= 0", value=seed)
    _check_channel(opts.channel)
    _check_plan(model, opts)
    return opts


def _check_plan(model: Any, opts: FitOptions) -> None:
    """:class:`~roughbrdf.fitting.problem.plan.FitPlan`'s checks of ``opts`` on a stand-in
    measurement (a few directions; relative data when ``relative_to`` is given)."""
    import numpy as np

    from ..fitting.problem.plan import FitPlan
    from ..measurement import Measurement
    from ..quantity import Quantity

    auto = is_auto(model)
    if auto:
        for name in ("fix", "bounds"):  # as fit_auto: the candidates' parameters differ
            if getattr(opts, name):
                raise ArgumentError(name, "names parameters of one model; with model 'auto' "
                                    "the candidates have different parameters: choose the "
                                    "model", value=getattr(opts, name))
        # the other options do not depend on the model: a stand-in candidate checks them
        opts = opts.replace(fix=(), bounds=None)
    m = as_model("lambertian" if auto else model)
    t = np.radians(np.array([10.0, 20.0, 30.0, 40.0]))
    probe = Measurement(t, t, np.zeros(4), np.ones(4), quantity=Quantity.parse(
        "relative" if opts.relative_to else "brdf"))
    FitPlan.of(m, probe, opts)


def _check_run_options(time_limit: float | None, retries: Any, n_workers: Any) -> None:
    """``time_limit``, ``retries`` and ``n_workers`` of :func:`fit_catalogue`."""
    if time_limit is not None and (isinstance(time_limit, bool)
                                   or not isinstance(time_limit, int | float)
                                   or not time_limit > 0):
        raise ArgumentError("time_limit", "must be a number of seconds > 0", value=time_limit)
    if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
        raise ArgumentError("retries", "must be a whole number >= 0", value=retries)
    if n_workers is not None and (isinstance(n_workers, bool) or not isinstance(n_workers, int)
                                  or n_workers < 1):
        raise ArgumentError("n_workers", "must be a whole number >= 1", value=n_workers)


def _check_read_options(read_options: Mapping[str, Any]) -> None:
    """``format`` and ``quantity`` of :func:`roughbrdf.read` (their form; whether a file
    agrees with them is the file's business)."""
    from ..io import format_for
    from ..quantity import Quantity

    if read_options.get("format") is not None:
        format_for("input", read_options["format"])
    if read_options.get("quantity") is not None:
        Quantity.parse(read_options["quantity"], "quantity")


def _check_channel(channel: Any) -> None:
    """``channel``: None, a label or position, or a list of them (which ones exist depends on
    the file)."""
    items = channel if isinstance(channel, list | tuple) else [channel]
    if channel is not None and (not items or not all(
            isinstance(c, str | int) and not isinstance(c, bool) for c in items)):
        raise ArgumentError("channel", "must be a channel label or position, or a list of "
                            "them", value=channel)


def _label(model: Any) -> str:
    """The model's label for the rows; an unknown model name fails here, before any work."""
    if is_auto(model):
        return "auto"
    return model_label(as_model(model))
