"""Command-line interface (Typer). Angles are in degrees at this edge; verbs mirror the library.

Each verb lives in its own module with a ``register(app)`` function; :data:`VERBS` lists them.
"""

from __future__ import annotations

import importlib

import typer

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="roughbrdf: rough-surface BRDF models - evaluate, fit, reproduce, convert.")

#: modules under roughbrdf.cli that register verbs (each defines register(app))
VERBS = ["evaluate", "fit", "convert", "plot", "reproduce"]

for _name in VERBS:
    try:
        _mod = importlib.import_module(f"{__name__}.{_name}")
    except ModuleNotFoundError as exc:  # verb not written yet
        if exc.name != f"{__name__}.{_name}":
            raise
        continue
    _mod.register(app)


def main() -> None:
    """Console-script entry point."""
    app()
