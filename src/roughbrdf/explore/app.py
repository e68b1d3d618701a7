"""The Dash application of ``roughbrdf explore``: the page (:mod:`.app_layout`) and its
callbacks.

Data flow (every step a Python callback on the server, all in one process):

* a parameter's slider and typed field mirror each other (:func:`_sync`); the model callback
  (:func:`_model`) rebuilds the model from the options and the typed fields
  (:func:`~roughbrdf.explore.app_state.model_from_controls`), keeps the last good value of a
  parameter whose typed value is outside its domain and says so under the controls, and stores
  the model's ``to_dict()`` in ``model-store``;
* the view callback (:func:`_views`) draws the open tab only, with
  :mod:`roughbrdf.explore.figures`, from ``model-store``, the incidence (degrees on the page,
  radians to the figures) and the view options; an error is one line in the tab;
* "Fit" starts a :class:`~roughbrdf.explore.app_jobs.FitJob`, polled by an interval while it
  runs; "Export" writes into the ``--out`` folder
  (:func:`~roughbrdf.explore.app_jobs.export_model`).

The application serves its scripts and styles itself (``serve_locally=True``: the packages'
own files, nothing from a CDN) and runs without Dash's dev tools.
"""

from __future__ import annotations

import math
import sys
from typing import Any

import dash
from dash import ALL, MATCH, Input, Output, State, ctx, no_update

from .app_jobs import FitJob, evaluation, export_model
from .app_layout import THETA_I, VIEWS, layout, parameter_controls
from .app_state import Session, model_from_controls

__all__ = ["build_app"]


def _say(text: str) -> None:
    """One line on the terminal (the server's stderr)."""
    try:
        print(text, file=sys.stderr, flush=True)
    except (OSError, ValueError):  # stderr closed: the page still shows it
        pass


def _message(exc: BaseException) -> str:
    from ..wording import error_message

    return error_message(exc)


class _OfflineDash(dash.Dash):
    """Dash without the one address of the network its page names: the version check's
    (only the dev tools use it; they are off) is removed from the page's config."""

    def _config(self) -> dict[str, Any]:
        config = super()._config()
        config["dash_version_url"] = ""
        config["disable_version_check"] = True
        return config


def build_app(session: Session) -> dash.Dash:
    """The Dash application for ``session`` (serve its ``.server``, a Flask WSGI app)."""
    app = _OfflineDash("roughbrdf.explore", serve_locally=True, title="roughbrdf explore",
                       update_title=None,  # type: ignore[arg-type]  # None: no "Updating..."
                       suppress_callback_exceptions=True, compress=False)
    app.layout = layout(session)
    if not session.error:
        _controls_callbacks(app, session)
        _view_callbacks(app, session)
        _action_callbacks(app, session)
    return app


def _model_of(data: Any) -> Any:
    import roughbrdf as rb

    return None if not data else rb.model(data)


def _controls_callbacks(app: dash.Dash, session: Session) -> None:
    @app.callback(Output({"role": "slider", "name": MATCH}, "value"),
                  Output({"role": "input", "name": MATCH}, "value"),
                  Input({"role": "slider", "name": MATCH}, "value"),
                  Input({"role": "input", "name": MATCH}, "value"),
                  State({"role": "slider", "name": MATCH}, "min"),
                  State({"role": "slider", "name": MATCH}, "max"),
                  prevent_initial_call=True)
    def _sync(slider: Any, typed: Any, lo: float, hi: float) -> tuple[Any, Any]:
        trigger = ctx.triggered_id or {}
        if trigger.get("role") == "slider":
            return no_update, slider
        if typed is None:  # an empty field (an optional part off): the slider stays
            return no_update, no_update
        return min(max(float(typed), lo), hi), no_update

    @app.callback(Output("param-panel", "children"),
                  Input({"role": "option", "name": ALL}, "value"),
                  State({"role": "option", "name": ALL}, "id"),
                  State("model-store", "data"), prevent_initial_call=True)
    def _options(values: list[Any], ids: list[dict[str, str]], data: Any) -> Any:
        model = _model_of(data) or session.model
        if model is None:  # no model: no options either
            return no_update
        try:
            changed = model.with_params(**{i["name"]: v for i, v in zip(ids, values,
                                                                       strict=True)})
        except (ValueError, TypeError):  # refused combination: the model callback says why
            return no_update
        return parameter_controls(changed)

    @app.callback(Output("model-store", "data"), Output("param-msg", "children"),
                  Input({"role": "input", "name": ALL}, "value"),
                  Input({"role": "option", "name": ALL}, "value"),
                  State({"role": "input", "name": ALL}, "id"),
                  State({"role": "option", "name": ALL}, "id"),
                  State("model-store", "data"), prevent_initial_call=True)
    def _model(values: list[Any], options: list[Any], ids: list[dict[str, str]],
               option_ids: list[dict[str, str]], data: Any) -> tuple[Any, Any]:
        base = _model_of(data) or session.model
        if base is None:
            return no_update, ""
        typed = {i["name"]: v for i, v in zip(ids, values, strict=True)
                 if i["name"] != THETA_I}
        chosen = {i["name"]: v for i, v in zip(option_ids, options, strict=True)}
        try:
            model, bad = model_from_controls(base, typed, chosen)
        except (ValueError, TypeError) as exc:
            return no_update, f"not a model: {_message(exc)}"
        lines = "\n".join(text if repr(name) in text else f"{name}: {text}"
                          for name, text in bad.items())
        spec = model.to_dict()
        return (no_update if spec == data else spec), lines  # unchanged: no redraw


def _incidence(value: Any) -> float:
    """The incidence (radians) of the page's control (degrees); 30 deg while it is empty."""
    if value is None:
        return math.radians(30.0)
    deg = float(value)
    if not (math.isfinite(deg) and 0 <= deg < 90):
        raise ValueError(f"incidence {deg:g} deg: give an angle in [0, 90) degrees")
    return math.radians(deg)


def _warning(fig: Any) -> str:
    """The albedo figure's warning (an albedo above 1) as one line for the page, or ""."""
    import re

    from .figures_albedo import WARNING_NAME

    for note in fig.layout.annotations or ():
        if note.name == WARNING_NAME:
            return "warning: " + " ".join(re.sub(r"<[^>]+>", " ", str(note.text)).split())
    return ""


#: the 3-D lobe's grid (theta_r x phi): issue 22's benchmark size (benchmarks/bench_explore.py)
LOBE_GRID = (64, 256)


def _figure(view: str, session: Session, model: Any, theta_i: float, quantity: str,
            log: bool, channel: Any, mode: str) -> Any:
    from . import figures

    meas = session.measurement
    if view == "lobe":
        return figures.lobe_3d(model, theta_i, quantity=quantity, log=log,
                               resolution=LOBE_GRID[0], n_phi=LOBE_GRID[1])
    if view == "cuts":
        return figures.plane_cuts(model, meas, channel=channel, log=True)
    if view == "maps":
        return figures.hemisphere_maps(model, meas, theta_i, channel=channel)
    if view == "albedo":
        return figures.albedo_curve(model)
    if view == "mueller":
        return figures.mueller_maps(model, theta_i)
    # B: the fitted model of the channel (--fit, or the last "Fit"), else the starting model
    other = session.fit_models.get(str(channel)) if session.fit_models else None
    other = other if other is not None else session.model
    return figures.compare_lobes(model, other if other is not None else model, theta_i,
                                 mode=mode, quantity=quantity, log=log)


def _view_callbacks(app: dash.Dash, session: Session) -> None:
    views = [v for v, _, needs in VIEWS if session.model is not None or not needs]
    outputs = [Output(f"g-{v}", "figure") for v in views]
    outputs += [Output(f"msg-{v}", "children") for v in views]

    @app.callback(*outputs,
                  Input("view-tabs", "value"), Input("model-store", "data"),
                  Input({"role": "input", "name": THETA_I}, "value"),
                  Input("view-quantity", "value"), Input("view-log", "value"),
                  Input("view-channel", "value"), Input("view-compare", "value"))
    def _views(tab: str, data: Any, incidence: Any, quantity: str, log: list[str],
               channel: Any, mode: str) -> list[Any]:
        figs: list[Any] = [no_update] * len(views)
        msgs: list[Any] = [no_update] * len(views)
        if tab not in views:
            return figs + msgs
        k = views.index(tab)
        try:
            theta_i = _incidence(incidence)
            model = _model_of(data)
            with evaluation():
                figs[k] = _figure(tab, session, model, theta_i, quantity, bool(log), channel,
                                  mode)
            msgs[k] = _warning(figs[k]) if tab == "albedo" else ""
        except Exception as exc:  # noqa: BLE001 - one line in the tab, and in the terminal
            from ..models.base import NoMuellerMatrix

            text = _message(exc) if not isinstance(exc, NoMuellerMatrix) else \
                f"no Mueller matrix: {' '.join(str(exc).split())}"
            msgs[k] = text
            _say(f"explore: {tab}: {text}")
        return figs + msgs


def _action_callbacks(app: dash.Dash, session: Session) -> None:
    jobs: dict[str, FitJob] = {}

    @app.callback(Output("fit-poll", "disabled"), Output("fit-status", "children"),
                  Output("fit-start", "disabled"), Output("fit-cancel", "disabled"),
                  Output("fit-progress", "value"), Output("fit-report", "children"),
                  Input("fit-start", "n_clicks"), Input("fit-cancel", "n_clicks"),
                  Input("fit-poll", "n_intervals"), State("model-store", "data"),
                  prevent_initial_call=True)
    def _fit(start: Any, cancel: Any, poll: Any, data: Any) -> tuple[Any, ...]:
        job = jobs.get("current")
        trigger = ctx.triggered_id
        if trigger == "fit-start" and (job is None or job.state != "running"):
            model = _model_of(data)
            if model is None or session.measurement is None:
                return True, "needs a measurement and a model", False, True, "0", no_update
            job = jobs["current"] = FitJob(model, session.measurement).start()
        elif trigger == "fit-cancel" and job is not None:
            job.cancel()
        if job is None:
            return True, "", False, True, "0", no_update
        running = job.state == "running"
        if job.state == "finished":  # the compare view shows the new fit beside the model
            session.fit_models.update(job.models)
        progress = f"{job.done / job.total if job.total else 1.0:.3f}"
        return (not running, job.status(), running, not running, progress,
                job.report if job.reports else no_update)

    @app.callback(Output("export-msg", "children"), Input("export-go", "n_clicks"),
                  State("export-to", "value"), State("export-name", "value"),
                  State("model-store", "data"), prevent_initial_call=True)
    def _export(clicks: Any, to: str, name: str, data: Any) -> str:
        try:
            text = export_model(_model_of(data), session.out, name, to)
        except Exception as exc:  # noqa: BLE001 - the page says why, nothing is written
            text = f"not exported: {_message(exc)}"
        _say(f"explore: {text.splitlines()[-1]}")
        return text
