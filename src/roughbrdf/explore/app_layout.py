"""The page of ``roughbrdf explore``: its Dash components (no callbacks; :mod:`.app`).

Left: the incidence (degrees), the model's options (drop-downs of the values the model
accepts) and one slider with a typed field per parameter (its search bounds as the slider's
ends, its unit, its domain in the tooltip), the fit and export panels. Right: the views in tabs
(3-D lobe, cuts, hemisphere maps, albedo, Mueller, compare). Element ids are the contract of
the callbacks and of ``tests/explore/test_explore_browser.py``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from dash import dcc, html

from .app_state import Session, option_choices, shown_unit, shown_value, slider_range

if TYPE_CHECKING:
    from ..models import Model

__all__ = ["layout", "parameter_controls", "VIEWS", "THETA_I"]

#: the tabs: (value, label, needs a model); each has a graph ``g-<value>``, a message
#: ``msg-<value>``
VIEWS = (("lobe", "3-D lobe", True), ("cuts", "In/cross-plane cuts", False),
         ("maps", "Hemisphere maps", False), ("albedo", "Albedo (TIS)", True),
         ("mueller", "Mueller / DoLP", True), ("compare", "Compare", True))

#: the name of the incidence control in the pattern ids of the parameter controls
THETA_I = "__theta_i"

_SMALL = {"fontSize": "0.85em", "color": "#555"}
_MSG = {"color": "#a00", "whiteSpace": "pre-wrap"}


def _control(name: str, label: str, value: float | None, lo: float, hi: float,
             hint: str, marks: dict[float, str] | None = None) -> html.Div:
    """A slider with a typed field (ids ``{"role": "slider"|"input", "name": name}``)."""
    step = (hi - lo) / 200 if hi > lo else 0.01
    slider_value = lo if value is None else min(max(value, lo), hi)
    return html.Div([
        html.Label(label, title=hint, style={"fontWeight": "bold"}),
        html.Div([
            html.Div(dcc.Slider(id={"role": "slider", "name": name}, min=lo, max=hi, step=step,
                                value=slider_value, marks=marks, updatemode="mouseup",
                                allow_direct_input=False,  # the typed field is ours
                                tooltip={"placement": "bottom", "always_visible": False}),
                     style={"flex": "1"}),
            dcc.Input(id={"role": "input", "name": name}, type="number", debounce=True,
                      value=value, style={"width": "7em"}),
        ], style={"display": "flex", "alignItems": "center", "gap": "0.5em"}),
        html.Div(hint, style=_SMALL),
    ], className="rb-control", style={"marginBottom": "0.6em"})


def parameter_controls(model: Model | None) -> list[Any]:
    """One control per parameter of ``model`` (angles in degrees)."""
    if model is None:
        return [html.Div("no model: start with --model SPEC or --fit DIR to get controls",
                         style=_SMALL)]
    out: list[Any] = []
    for p in model.parameters:
        lo, hi = slider_range(p)
        unit = shown_unit(p)
        value = shown_value(p, p.value)
        domain = p.domain_text() if p.unit != "rad" else "(angle, degrees)"
        hint = (f"{p.description} - slider {lo:g}..{hi:g} {unit} (search bounds); domain "
                f"{domain}" + ("; empty switches it off" if p.optional else ""))
        out.append(_control(p.name, f"{p.name} [{unit}]", value, lo, hi, hint))
    return out


def _options(model: Model | None) -> list[Any]:
    if model is None:
        return []
    rows: list[Any] = []
    for name, values in option_choices(model).items():
        rows.append(html.Div([
            html.Label(name, style={"fontWeight": "bold"}),
            dcc.Dropdown(id={"role": "option", "name": name}, clearable=False,
                         options=[{"label": str(v), "value": v} for v in values],
                         value=model.options[name]),
        ], style={"marginBottom": "0.5em"}))
    return rows


def _fit_panel(session: Session) -> html.Div:
    ready = session.model is not None and session.measurement is not None
    return html.Div([
        html.H4("Fit from here"),
        html.Button("Fit", id="fit-start", disabled=not ready),
        html.Button("Cancel", id="fit-cancel", disabled=True, style={"marginLeft": "0.5em"}),
        html.Div("" if ready else "needs a measurement (FILE or --fit) and a model",
                 id="fit-status", style=_SMALL),
        html.Progress(id="fit-progress", value="0", max="1", style={"width": "100%"}),
        html.Pre(session.fit_report, id="fit-report",
                 style={"maxHeight": "20em", "overflow": "auto", "fontSize": "0.75em"}),
        dcc.Interval(id="fit-poll", interval=400, disabled=True),
    ])


def _export_panel(session: Session) -> html.Div:
    where = str(session.out) if session.out else "no --out folder: export is off"
    return html.Div([
        html.H4("Export"),
        html.Div(f"into {where}", style=_SMALL),
        dcc.Dropdown(id="export-to", clearable=False, value="zemax",
                     options=[{"label": "Zemax OpticStudio (.bsdf)", "value": "zemax"},
                              {"label": "Mitsuba 3 (JSON dict)", "value": "mitsuba"},
                              {"label": "Mitsuba 3 (XML)", "value": "mitsuba-xml"}]),
        dcc.Input(id="export-name", type="text", value="model", debounce=False,
                  placeholder="file name (no folder)"),
        html.Button("Export", id="export-go", disabled=session.out is None or
                    session.model is None, style={"marginLeft": "0.5em"}),
        html.Pre("", id="export-msg", style={"fontSize": "0.75em", "whiteSpace": "pre-wrap"}),
    ])


def _view_options(session: Session) -> html.Div:
    meas = session.measurement
    channels = list(meas.channels) if meas is not None else list(session.fit_models)
    return html.Div([
        html.Span("quantity "),
        dcc.Dropdown(id="view-quantity", clearable=False, value="brdf",
                     options=[{"label": "BRDF", "value": "brdf"},
                              {"label": "BRDF·cos θr", "value": "brdf_cos"}],
                     style={"width": "10em", "display": "inline-block"}),
        dcc.Checklist(id="view-log", options=[{"label": " log", "value": "log"}], value=[],
                      inline=True, style={"display": "inline-block", "marginLeft": "1em"}),
        html.Span(" channel ", style={"marginLeft": "1em"}),
        dcc.Dropdown(id="view-channel", clearable=False,
                     options=[{"label": c, "value": c} for c in channels],
                     value=channels[0] if channels else None,
                     style={"width": "10em", "display": "inline-block"}),
        dcc.RadioItems(id="view-compare", value="overlay", inline=True,
                       options=[{"label": " overlay", "value": "overlay"},
                                {"label": " side by side", "value": "side"}],
                       style={"display": "inline-block", "marginLeft": "1em"}),
    ], style={"marginBottom": "0.5em"})


def _tabs(session: Session) -> dcc.Tabs:
    has_model = session.model is not None
    tabs = []
    for value, label, needs_model in VIEWS:
        if needs_model and not has_model:
            continue
        tabs.append(dcc.Tab(label=label, value=value, children=[
            html.Div("", id=f"msg-{value}", style=_MSG),
            dcc.Graph(id=f"g-{value}", style={"height": "70vh"},
                      config={"displaylogo": False}),
        ]))
    first = next((v for v, _, needs in VIEWS if has_model or not needs), None)
    return dcc.Tabs(id="view-tabs", value=first, children=tabs)


def _incidences(session: Session) -> tuple[float, dict[float, str] | None]:
    """The incidence the page starts at (the measured one nearest 30 deg, else 30) and the
    slider's marks (the measured incidences, when there are at most 24)."""
    import numpy as np

    meas = session.measurement
    if meas is None or meas.n_samples == 0:
        return 30.0, None
    measured = np.unique(np.round(np.degrees(meas.theta_i), 6))
    measured = measured[measured < 90]
    if measured.size == 0:
        return 30.0, None
    start = float(measured[np.argmin(np.abs(measured - 30.0))])
    marks = {float(d): f"{d:g}" for d in measured} if measured.size <= 24 else None
    return start, marks


def layout(session: Session) -> html.Div:
    """The whole page for ``session``; only the message when loading failed."""
    header = html.H2(f"roughbrdf explore - {session.label}", style={"margin": "0.3em 0"})
    if session.error:
        return html.Div([header, html.Div(f"error: {session.error}", id="banner",
                                          className="rb-error", style=_MSG)])
    model = session.model
    start, marks = _incidences(session)
    incidence = _control(THETA_I, "incidence θi [deg]", start, 0.0, 89.0,
                         "angle of incidence, degrees from the normal"
                         + (" (marks: the measured ones)" if marks else ""), marks)
    left = html.Div([
        incidence, html.Div(_options(model), id="option-panel"),
        html.Div(parameter_controls(model), id="param-panel"),
        html.Div("", id="param-msg", className="rb-param-msg", style=_MSG),
        _fit_panel(session), _export_panel(session),
    ], style={"width": "24em", "flexShrink": "0", "overflowY": "auto", "maxHeight": "95vh"})
    right = html.Div([_view_options(session), _tabs(session)], style={"flex": "1"})
    stores = [dcc.Store(id="model-store", data=model.to_dict() if model else None),
              dcc.Store(id="fit-store", data=None)]
    return html.Div([header, html.Div("", id="banner"),
                     html.Div([left, right], style={"display": "flex", "gap": "1em"}),
                     *stores], style={"fontFamily": "sans-serif", "margin": "0.5em"})
