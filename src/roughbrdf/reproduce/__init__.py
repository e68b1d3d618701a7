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

from ._common import Reproduction, Table, Unavailable, check_writable

__all__ = ["PAPERS", "Reproduction", "Table", "Unavailable", "reproductions", "run"]

#: paper key -> module name under roughbrdf.reproduce
PAPERS = {"ts67": "ts67", "tr75": "tr75", "rb08": "rb08"}


def _functions(paper: str) -> tuple[Callable[[], Reproduction], ...]:
    key = paper.strip().lower()
    if key not in PAPERS:
        raise ValueError(f"unknown paper {paper!r}; choose from {', '.join(PAPERS)} or 'all'")
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


def run(paper: str, out: str | Path, *, force: bool = False, compact: bool = False,
        data_dir: str | Path | None = None,
        echo: Callable[[str], None] | None = None) -> list[Path]:
    """Write the reproductions of ``paper`` (or ``"all"``) into ``out``; return the paths.

    Existing files are never overwritten unless ``force``; the check is done per reproduction
    before anything of it is written. ``compact`` writes palette PNGs (smaller, for committing);
    ``data_dir`` is passed to :func:`reproductions`.
    """
    out = Path(out)
    written: list[Path] = []
    for rep in reproductions(paper, data_dir=data_dir, echo=echo):
        check_writable(rep.outputs(out), force)
        paths = rep.write(out, force=force, compact=compact)
        if rep.figure is not None:
            rep.figure.clear()
        written.extend(paths)
        if echo is not None:
            echo(f"{rep.name}: {rep.title}")
            for note in rep.notes:
                echo(f"    note: {note}")
            for p in paths:
                echo(f"    wrote {p}")
    return written
