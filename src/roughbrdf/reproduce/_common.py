"""The result of one reproduction (figure + the numbers behind it) and how it is written.

Files are written atomically and never replace a file unless asked (``overwrite=True``; the
CLI's ``--force``), and several files of one reproduction or one run are written as one set
(:class:`roughbrdf.output.ResultFolder`): :mod:`roughbrdf.output`.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import numpy as np
from matplotlib.figure import Figure

__all__ = ["Table", "Reproduction", "Unavailable", "new_figure", "check_writable", "save_png",
           "DPI"]

#: resolution of the written PNGs (small files; the docs commit them)
DPI = 100


class Unavailable(RuntimeError):
    """A reproduction needs a part of the library this version does not have."""


@dataclass
class Table:
    """A table of numbers: column names and rows (each row a sequence of numbers or strings)."""

    columns: list[str]
    rows: Sequence[Sequence[Any]]

    def column(self, name: str) -> np.ndarray:
        """One column as an array (floats where possible)."""
        j = self.columns.index(name)
        vals = [r[j] for r in self.rows]
        try:
            return np.asarray(vals, dtype=float)
        except (TypeError, ValueError):
            return np.asarray(vals, dtype=object)

    def to_csv(self) -> str:
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(self.columns)
        for r in self.rows:
            w.writerow([_fmt(v) for v in r])
        return buf.getvalue()

    def to_markdown(self) -> str:
        lines = ["| " + " | ".join(self.columns) + " |",
                 "|" + "|".join("---" for _ in self.columns) + "|"]
        for r in self.rows:
            lines.append("| " + " | ".join(_fmt(v, md=True) for v in r) + " |")
        return "\n".join(lines) + "\n"


def _fmt(v: Any, md: bool = False) -> str:
    if isinstance(v, float | np.floating):
        if not np.isfinite(v):
            return "" if md else str(v)
        return f"{float(v):.4f}" if md else f"{float(v):.10g}"
    return str(v)


@dataclass
class Reproduction:
    """One reproduced figure or table.

    Attributes
    ----------
    name : str
        File stem, e.g. ``"ts67_fig08"``; files are ``<name>.png``, ``<name>.csv`` (one table) or
        ``<name>_<table>.csv`` (several), and ``<name>.md`` when ``markdown`` is set.
    title : str
        What the paper's figure shows.
    figure : matplotlib.figure.Figure or None
    tables : dict of str -> Table
        The numbers behind the figure (every plotted or printed number).
    markdown : str, optional
        A Markdown rendering (tables).
    notes : list of str
        Where we differ from the paper and why.
    """

    name: str
    title: str
    figure: Figure | None = None
    tables: dict[str, Table] = field(default_factory=dict)
    markdown: str | None = None
    notes: list[str] = field(default_factory=list)

    def outputs(self, out: Path) -> list[Path]:
        """The files :meth:`write` would create in ``out``."""
        paths = []
        if self.figure is not None:
            paths.append(out / f"{self.name}.png")
        for key in self.tables:
            paths.append(out / (f"{self.name}.csv" if len(self.tables) == 1
                                else f"{self.name}_{key}.csv"))
        if self.markdown is not None:
            paths.append(out / f"{self.name}.md")
        return paths

    def files(self, *, dpi: int = DPI, compact: bool = False
              ) -> dict[str, str | Callable[[IO[bytes]], None]]:
        """The files of :meth:`outputs` by name: text, or a writer of the PNG bytes."""
        names = [p.name for p in self.outputs(Path("."))]
        it = iter(names)
        out: dict[str, str | Callable[[IO[bytes]], None]] = {}
        if self.figure is not None:
            fig = self.figure
            out[next(it)] = lambda fh: save_png(fig, fh, dpi=dpi, compact=compact)
        for table in self.tables.values():
            out[next(it)] = table.to_csv()
        if self.markdown is not None:
            out[next(it)] = self.markdown
        return out

    def write(self, out: Path, *, overwrite: bool = False, dpi: int = DPI,
              compact: bool = False) -> list[Path]:
        """Write the PNG, CSV(s) and Markdown into ``out``; refuse to replace a file unless
        ``overwrite``.

        The files are checked first, then written as one set added to the folder's
        (:class:`roughbrdf.output.ResultFolder` with ``extend=True``): an error, Ctrl-C or a
        kill leaves all the old files or all the new ones. The caller named the folder, so
        with ``overwrite`` files of these names that no set lists are replaced (``adopt``).
        ``compact`` stores the PNG with a 256-colour palette (about a third of the size; used
        for the images committed under ``docs/img``).
        """
        from ..output import ResultFolder, ensure_folder

        out = ensure_folder(out)
        paths = self.outputs(out)
        check_writable(paths, overwrite)
        with ResultFolder(out, overwrite=overwrite, extend=True,
                          adopt=[p.name for p in paths]) as folder:
            folder.check([p.name for p in paths])
            for path, content in zip(paths, self.files(dpi=dpi, compact=compact).values(),
                                     strict=True):
                folder.add(path.name, content, binary=callable(content))
        return paths


def save_png(fig: Figure, path: Path | IO[bytes], *, dpi: int = DPI,
             compact: bool = False) -> None:
    """Save ``fig`` as PNG to a path or an open binary file; ``compact`` quantizes to a
    256-colour palette (Pillow)."""
    if not compact:
        fig.savefig(path, dpi=dpi, format="png")
        return
    from PIL import Image  # matplotlib depends on Pillow

    buf = io.BytesIO()
    fig.savefig(buf, dpi=dpi, format="png", facecolor="white")
    buf.seek(0)
    with Image.open(buf) as im:
        im.convert("RGB").quantize(colors=256, method=Image.Quantize.MEDIANCUT).save(
            path, format="PNG", optimize=True)


def check_writable(paths: Sequence[Path], overwrite: bool) -> None:
    """Raise :class:`roughbrdf.output.OverwriteRefused` naming the first existing file unless
    ``overwrite``."""
    from ..output import OverwriteRefused

    if overwrite:
        return
    for p in paths:
        if Path(p).exists():
            raise OverwriteRefused(p, single=True)


def new_figure(nrows: int = 1, ncols: int = 1, *, figsize: tuple[float, float] = (6.4, 4.8),
               polar: bool = False, **kw: Any) -> tuple[Figure, Any]:
    """A pyplot-free figure with a grid of axes (constrained layout)."""
    fig = Figure(figsize=figsize, layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False,
                        subplot_kw={"projection": "polar"} if polar else None, **kw)
    return fig, axes
