"""``roughbrdf reproduce``: the papers' figures and tables, written as PNG + CSV (+ Markdown)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from .common import REPRODUCE_OPTIONS, handled
from .options import unknown_value

#: the library's argument names -> this verb's options (errors name the options)
OPTIONS = REPRODUCE_OPTIONS


def register(app: typer.Typer) -> None:
    @app.command("reproduce")
    def reproduce_cmd(
        out: Annotated[Path, typer.Option(
            "--out", "-o", help="output folder (created; refused if it holds results, unless "
                                "--force)")],
        paper: Annotated[str, typer.Option(help="ts67, tr75, rb08 or all")] = "all",
        force: Annotated[bool, typer.Option(
            help="replace the results of an earlier run in --out (files roughbrdf did not "
                 "write are never replaced)")] = False,
        compact: Annotated[bool, typer.Option(
            help="256-colour palette PNGs (smaller files)")] = False,
        data: Annotated[Path | None, typer.Option(
            help="folder of real measurements (../shared/data): overlay the CEA gray tape on "
                 "RB08 Fig. 3")] = None,
    ) -> None:
        """Reproduce the figures and tables of TS67, TR75 and RB08 into OUT.

        Every plotted or printed number comes from the library's public API; each figure is
        written with the CSV of the numbers behind it. See docs/reproduction.md.
        """
        with handled(OPTIONS):
            import matplotlib

            matplotlib.use("Agg")
            from .. import reproduce

            if paper.strip().lower() not in (*reproduce.PAPERS, "all"):
                raise unknown_value("--paper", paper, [*reproduce.PAPERS, "all"], "paper")
            try:
                paths = reproduce.run(paper, out, overwrite=force, compact=compact,
                                      data_dir=data, echo=typer.echo)
            except reproduce.Unavailable as exc:  # the user's to fix (e.g. --data): status 2
                raise ValueError(str(exc)) from exc
        typer.echo(f"{len(paths)} files written to {out}")
