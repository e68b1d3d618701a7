"""The papers' figures and tables, built from the library's public API.

Each paper has a module whose functions return a :class:`Reproduction` (a matplotlib figure
plus the tables of numbers behind it); :func:`run` writes them into a directory::

    >>> from roughbrdf import reproduce
    >>> paths = reproduce.run("ts67", "out/reproduce")          # doctest: +SKIP

========  =================================================================================
paper     reproductions
========  =================================================================================
ts67      Figs. 7, 8, 9 (Fresnel for Al and MgO), 10 and 11 (out of plane)
tr75      Fig. 5 (structure functions + HWHMs), Fig. 6-style polar plots, Table 1 DHRs
rb08      Fig. 2 (Vm against scattering angle), Fig. 3 (in-plane BRDF, several incidences)
========  =================================================================================

Where we differ from a paper, the reproduction's ``notes`` say why; ``docs/reproduction.md``
puts each figure next to the paper's claim.
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Callable, Iterable
from pathlib import Path

from ._common import Reproduction, Table, Unavailable

__all__ = ["PAPERS", "Reproduction", "Table", "Unavailable", "reproductions", "run"]

#: paper key -> module name under roughbrdf.reproduce
PAPERS = {"ts67": "ts67", "tr75": "tr75", "rb08": "rb08"}


def _paper_key(paper: str, *, every: bool = False) -> str:
    key = paper.strip().lower()
    if key not in PAPERS and not (every and key == "all"):
        raise ValueError(f"unknown paper {paper!r}; choose from {', '.join(PAPERS)} or 'all'")
    return key


def _functions(paper: str) -> tuple[Callable[[], Reproduction], ...]:
    key = _paper_key(paper)
    mod = importlib.import_module(f"{__name__}.{PAPERS[key]}")
    return tuple(mod.ALL)


def reproductions(paper: str = "all", *, data_dir: str | Path | None = None,
                  skip_unavailable: bool | None = None,
                  echo: Callable[[str], None] | None = None) -> Iterable[Reproduction]:
    """Yield the reproductions of one paper (``"ts67"``, ``"tr75"``, ``"rb08"``) or ``"all"``.

    ``data_dir`` is the folder of real measurements (``../shared/data``); reproductions that can
    overlay measured points (RB08 Fig. 3: the CEA gray tape) use it, the others ignore it.
    A reproduction that needs a missing part of the library raises :class:`Unavailable`; with
    ``skip_unavailable`` (default: only for ``"all"``) it is skipped and reported to ``echo``.
    """
    every = paper.strip().lower() == "all"
    skip = every if skip_unavailable is None else skip_unavailable
    papers = list(PAPERS) if every else [paper]
    for p in papers:
        for fn in _functions(p):
            kwargs = {}
            if data_dir is not None and "data_dir" in inspect.signature(fn).parameters:
                kwargs["data_dir"] = data_dir
            try:
                rep = fn(**kwargs)
            except Unavailable as exc:
                if not skip:
                    raise
                if echo is not None:
                    echo(f"skipped {p}.{fn.__name__}: {exc}")
                continue
            yield rep


def run(paper: str, out: str | Path, *, overwrite: bool = False, compact: bool = False,
        data_dir: str | Path | None = None,
        echo: Callable[[str], None] | None = None) -> list[Path]:
    """Write the reproductions of ``paper`` (or ``"all"``) into ``out``; return the paths.

    ``out`` receives them as one set (:class:`roughbrdf.output.ResultFolder`): a folder that
    holds results already (or any file of the same names) is refused before anything is
    computed, unless ``overwrite`` (the CLI's ``--force``), which replaces exactly the earlier
    run's files; files roughbrdf did not write are never replaced. The files are committed
    together at the end: an error or Ctrl-C leaves the folder as it was. ``compact`` writes
    palette PNGs (smaller, for committing); ``data_dir`` is passed to :func:`reproductions`.
    """
    from ..output import ResultFolder

    _paper_key(paper, every=True)
    folder = ResultFolder(out, overwrite=overwrite)
    folder.check([])
    staged: list[str] = []
    with folder:
        for rep in reproductions(paper, data_dir=data_dir, echo=echo):
            files = rep.files(compact=compact)
            folder.check(list(files))
            for name, content in files.items():
                folder.add(name, content, binary=callable(content))
            if rep.figure is not None:
                rep.figure.clear()
            staged.extend(files)
            if echo is not None:
                echo(f"{rep.name}: {rep.title}")
                for note in rep.notes:
                    echo(f"    note: {note}")
    paths = [folder.path / name for name in staged]
    if echo is not None:
        for p in paths:
            echo(f"    wrote {p}")
    return paths
