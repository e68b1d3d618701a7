"""``roughbrdf reproduce``: the papers' figures and tables, written as PNG + CSV (+ Markdown)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer


def register(app: typer.Typer) -> None:
    @app.command("reproduce")
    def reproduce_cmd(
        out: Annotated[Path, typer.Option("--out", "-o", help="output directory (created)")],
        paper: Annotated[str, typer.Option(help="ts67, tr75, rb08 or all")] = "all",
        force: Annotated[bool, typer.Option(help="overwrite existing files")] = False,
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
        import matplotlib

        matplotlib.use("Agg")
        from .. import reproduce

        try:
            paths = reproduce.run(paper, out, force=force, compact=compact, data_dir=data,
                                   echo=typer.echo)
        except (ValueError, FileExistsError, FileNotFoundError, reproduce.Unavailable) as exc:
            typer.echo(f"error: {exc}", err=True)
            raise typer.Exit(2) from exc
        typer.echo(f"{len(paths)} files written to {out}")
