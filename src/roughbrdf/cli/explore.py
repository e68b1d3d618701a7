"""``roughbrdf explore [FILE] [--fit DIR] [--model SPEC -p NAME=VALUE ...] [--port N]
[--host H] [--out DIR] [--format F] [--no-browser]``: the web explorer (``docs/explore.md``).

Starts a local web application (Dash; ``pip install roughbrdf[explore]``) showing a
measurement, a model and a fit, prints its address with the run's token and opens a browser
when one is available. It listens on ``127.0.0.1`` only unless ``--host`` is given (then it
says what that exposes); requests without the token, or with a foreign Host or Origin, get 403
(:mod:`roughbrdf.explore.security`). A busy ``--port`` is a usage error (2) naming it; Ctrl-C
stops the server with 130. A file that cannot be read, or a fit whose measurement is gone, is
one line on stderr and the one message of the page.
"""

from __future__ import annotations

from typing import Annotated

import typer

from .common import handled, parse_params

#: the library's argument names -> this verb's options
OPTIONS = {"format": "--format", "out": "--out", "host": "--host", "port": "--port"}


def run_explore(file: str | None, fit_dir: str | None, model: str | None,
                param: list[str] | None, *, port: int | None, host: str | None,
                out: str | None, browser: bool, format: str | None = None) -> None:
    """The work of ``roughbrdf explore``: load, bind, print the address, serve until Ctrl-C."""
    if file is None and fit_dir is None and model is None:
        raise ValueError("nothing to explore: give a measurement FILE, --fit DIR or --model SPEC")
    if param and model is None:
        raise ValueError("-p/--param sets the parameters of --model SPEC; give --model")
    try:
        from ..explore.app import build_app
    except ModuleNotFoundError as exc:
        if exc.name and exc.name.split(".")[0] in ("dash", "plotly", "flask", "werkzeug"):
            raise ValueError("roughbrdf explore needs Dash: pip install 'roughbrdf[explore]'"
                             ) from None
        raise
    from ..explore.app_state import load_session
    from ..explore.server import bind, exposure_note, open_browser
    from ..output import ensure_folder

    if out is not None:
        ensure_folder(out)
    session = load_session(file, fit_dir=fit_dir, model=model, params=parse_params(param),
                           out=out, format=format)
    if session.error:
        typer.echo(f"error: {session.error}", err=True)
    server = bind(build_app(session).server, host=host, port=0 if port is None else port)
    try:
        if host is not None:
            note = exposure_note(server.host)
            if note:
                typer.echo(note, err=True)
        typer.echo(f"roughbrdf explore: serving {session.label}", err=True)
        typer.echo(server.url)  # stdout: the one line a script reads
        if out is None:
            typer.echo("export is off (no --out DIR)", err=True)
        typer.echo("press Ctrl-C to stop", err=True)
        if browser:
            open_browser(server.url)
        server.serve_forever()
    finally:
        server.close()


def register(app: typer.Typer) -> None:
    @app.command("explore")
    def explore_cmd(
        file: Annotated[str | None, typer.Argument(
            help="a measurement file (any format roughbrdf reads)")] = None,
        fit_dir: str = typer.Option(None, "--fit", metavar="DIR",
                                    help="a saved fit (fit.json): its models and its data"),
        model: str = typer.Option(None, "--model", metavar="SPEC",
                                  help="a model to start from, e.g. coated(lobes=2)"),
        param: Annotated[list[str] | None, typer.Option(
            "-p", "--param", help="a --model parameter or option, name=value (repeatable; "
                                  "angles such as sigma in degrees)")] = None,
        port: int = typer.Option(None, "--port", help="port to listen on (default: a free "
                                                      "one)"),
        host: str = typer.Option(None, "--host",
                                 help="address to listen on (default 127.0.0.1, this machine "
                                      "only; anything else is said when starting)"),
        out: str = typer.Option(None, "--out", "-o", metavar="DIR",
                                help="the one folder exports are written into (default: "
                                     "export off)"),
        format: str = typer.Option(None, "--format",
                                   help="the FILE's format, overriding the one chosen from "
                                        "its extension (astm, alta, merl, csv, zemax, ...)"),
        browser: bool = typer.Option(True, "--browser/--no-browser",
                                     help="open the address in a browser when one is "
                                          "available"),
    ) -> None:
        """Explore a measurement, a model and a fit in the browser (local web app)."""
        with handled(OPTIONS):
            run_explore(file, fit_dir, model, param, port=port, host=host, out=out,
                        browser=browser, format=format)
