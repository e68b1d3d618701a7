"""Maps over the reflection hemisphere at one incidence (Plotly): data, model, data/model; the
normalized Mueller elements and the degree of linear polarization.

The maps use the projected disk: ``α = sin θr cos φ`` to the right (``φ = 0``, the forward,
specular side), ``β = sin θr sin φ`` up (``docs/models.md`` §1.1, the direction cosines of
``DESIGN.md``); ``coords="degrees"`` draws ``θr cos φ``, ``θr sin φ`` in degrees instead.
Circles mark ``θr`` = 30, 60, 90°; ``+`` the specular direction ``(sin θi, 0)``, ``x`` the
source (retro) direction ``(−sin θi, 0)``. A model is drawn as a heat map on a grid (one
evaluation of the whole grid), data as coloured markers at the samples.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import plotly.graph_objects as go
from plotly.subplots import make_subplots

from ..errors import ArgumentError
from ..models import Model
from ..quantity import Quantity
from ..stokes import dolp
from .figures_common import (
    HOVER_ANGLES,
    SR,
    channel_data,
    check_incidence,
    check_model,
    check_resolution,
    custom,
    deg,
    disk_axis_titles,
    disk_grid,
    disk_position,
    disk_rings,
    finite_or_nan,
    log_ticks,
    measured_incidences,
    optional_model,
    quantity_label,
    title_text,
)

__all__ = ["hemisphere_maps", "mueller_maps"]


def _colour(values: np.ndarray, log: bool) -> np.ndarray:
    """The colour of a value: ``log10`` of it with ``log`` (NaN where not positive)."""
    if not log:
        return values
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(values > 0, np.log10(np.where(values > 0, values, 1.0)), np.nan)


def _grid_values(model: Model, theta_i: float, tr: np.ndarray, ph: np.ndarray,
                 quantity: Quantity, k: float, polarization: Any = None) -> np.ndarray:
    inside = np.isfinite(tr)
    out = np.full(tr.shape, np.nan)
    with np.errstate(invalid="ignore", over="ignore"):  # a divergence at the horizon: NaN
        out[inside] = finite_or_nan(model.evaluate(theta_i, tr[inside], ph[inside],
                                                   quantity=quantity,
                                                   polarization=polarization)) / k
    return out


def _marks(fig: go.Figure, theta_i: float, coords: str, col: int, first: bool) -> None:
    """The specular and retro directions on one panel."""
    for what, phi, symbol in (("specular", 0.0, "cross-thin"), ("retro", math.pi, "x-thin")):
        x, y = disk_position(theta_i, phi, coords)
        fig.add_trace(go.Scatter(
            x=[float(x)], y=[float(y)], mode="markers", name=what,
            legendgroup=what, showlegend=first, marker={"symbol": symbol, "size": 12,
                                                        "color": "cyan",
                                                        "line": {"width": 2, "color": "cyan"}},
            hovertemplate=f"{what}: θr = {math.degrees(theta_i):.4g}°, φ = "
                          f"{math.degrees(phi):g}°<extra></extra>"), row=1, col=col)


def _disk_axes(fig: go.Figure, n_cols: int, coords: str, rows: int = 1) -> None:
    """Equal-aspect disks (the panel shrinks, the range stays) with the rings."""
    xt, yt = disk_axis_titles(coords)
    edge = 1.05 if coords == "cosines" else 95.0
    shapes: list[dict[str, Any]] = []
    for i in range(rows * n_cols):
        sfx = "" if i == 0 else str(i + 1)
        shapes += disk_rings(coords, f"x{sfx}", f"y{sfx}")
        fig.layout[f"yaxis{sfx}"].update(scaleanchor=f"x{sfx}", scaleratio=1,
                                         range=[-edge, edge], constrain="domain")
        fig.layout[f"xaxis{sfx}"].update(range=[-edge, edge], constrain="domain")
    fig.update_layout(shapes=shapes)
    fig.update_xaxes(title_text=xt, row=rows, col=1)
    fig.update_yaxes(title_text=yt, row=rows, col=1)


def _heatmap(axis: np.ndarray, tr: np.ndarray, ph: np.ndarray, z: np.ndarray,
             values: np.ndarray, name: str, coloraxis: str, unit: str,
             field: str = "value") -> go.Heatmap:
    cd, meta = custom(("theta_r_deg", "phi_deg", field), deg(tr), deg(ph), values)
    return go.Heatmap(x=axis, y=axis, z=z, customdata=cd, meta=meta, name=name,
                      coloraxis=coloraxis, hoverongaps=False,
                      hovertemplate=f"{name}<br>{HOVER_ANGLES}<br>%{{customdata[2]:.4g}} "
                                    f"{unit}<extra></extra>")


def _scatter(theta_r: np.ndarray, phi: np.ndarray, z: np.ndarray, values: np.ndarray,
             name: str, coloraxis: str, coords: str, unit: str,
             extra: dict[str, np.ndarray]) -> go.Scatter:
    x, y = disk_position(theta_r, phi, coords)
    sparse = np.size(x) <= 500  # few samples: large outlined markers; many: small plain ones
    cd, meta = custom(("theta_r_deg", "phi_deg", "value", *extra), deg(theta_r), deg(phi),
                      values, *extra.values())
    # no legend item: the panel's title names it, and Plotly cannot draw a legend symbol for
    # markers coloured through a colour axis (a console warning per item)
    return go.Scatter(x=x, y=y, mode="markers", name=name, customdata=cd, meta=meta,
                      showlegend=False,
                      marker={"color": z, "coloraxis": coloraxis, "size": 7 if sparse else 4,
                              "line": {"width": 0.3 if sparse else 0, "color": "#444"}},
                      hovertemplate=f"{name}<br>{HOVER_ANGLES}<br>%{{customdata[2]:.4g}} "
                                    f"{unit}<extra></extra>")


def hemisphere_maps(model: Model | None = None, measurement: Any = None,
                    theta_i: float | None = None, *, channel: int | str | None = None,
                    log: bool = True, quantity: str = "brdf", resolution: int = 101,
                    coords: str = "cosines", label: str | None = None,
                    polarization: Any = None) -> go.Figure:
    """Maps of the reflection hemisphere at one incidence: data, model and data/model.

    The panels that exist for what is given, left to right: ``"data"`` (the samples at
    ``theta_i``, within 0.05°, coloured by value), ``"model"`` (a ``resolution²`` heat map)
    and ``"data/model"`` (the ratio at each sample, log10 colours centred on 1). Data and
    model share one colour scale: ``log10`` of the value in sr⁻¹ with ``log`` (ticks at the
    powers of ten, written as values), else linear; values are in the data's quantity
    (relative data: the model divided by ``K``, TR75 Eq. 34) or, for a model alone,
    ``quantity``. Projected disk and markers as in the module notes. Trace
    ``customdata``: ``theta_r_deg, phi_deg, value`` (the ratio trace also ``data`` and
    ``model``); ``z`` (heat map) and ``marker.color`` are the drawn colours.

    Parameters
    ----------
    model : Model, optional
    measurement : Measurement, optional
        At least one of the two.
    theta_i : float, optional
        Incidence, radians in ``[0, pi/2)``; default the measurement's first incidence
        (required for a model alone).
    channel : int or str, optional
        The measurement's channel (default the first).
    log, quantity, resolution, coords, label
        Colour scale, the model's quantity when alone, grid points per side, ``"cosines"``
        or ``"degrees"``, the model's name in the title.
    polarization : optional
        The incident polarization of the model map (:meth:`~roughbrdf.models.Model.evaluate`;
        default unpolarized). The ratio panel always uses each sample's own polarization.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> fig = hemisphere_maps(rb.model("lambertian", rho=0.5), theta_i=0.2, resolution=5)
    >>> [t.name for t in fig.data]
    ['model', 'specular', 'retro']
    >>> round(float(fig.data[0].customdata[2, 2, 2]), 6)       # the centre: rho/pi
    0.159155
    """
    model = optional_model(model)
    if model is None and measurement is None:
        raise ArgumentError("model", "give a model, a measurement or both")
    cd = channel_data(measurement, channel, model) if measurement is not None else None
    if theta_i is None:
        if cd is None:
            raise ArgumentError("theta_i", "a model alone needs an incidence (radians)")
        theta_i = measured_incidences(cd.meas)[0]
    t = check_incidence(theta_i)
    n = check_resolution(resolution)
    axis, tr, ph = disk_grid(n, coords)
    q = cd.model_quantity if cd is not None else Quantity.parse(quantity)
    unit = SR if (cd is None or cd.quantity.absolute) else "(relative)"
    traces: list[tuple[str, Any]] = []
    at = None
    if cd is not None:
        at = np.abs(cd.meas.theta_i - t) <= math.radians(0.05)  # Measurement.at_incidence's
        sub = cd.meas.subset(at)
        v = cd.values[at]
        traces.append(("data", _scatter(sub.theta_r, sub.phi, _colour(v, log), v, "data",
                                        "coloraxis", coords, unit, {})))
    if model is not None:
        grid = _grid_values(model, t, tr, ph, q, cd.k if cd is not None else 1.0,
                            polarization)
        traces.append(("model", _heatmap(axis, tr, ph, _colour(grid, log), grid, "model",
                                         "coloraxis", unit)))
    if cd is not None and model is not None and at is not None:
        v, mod = cd.values[at], cd.model_at(model, at)
        with np.errstate(divide="ignore", invalid="ignore"):  # <= 0 has no ratio to draw
            ratio = finite_or_nan(v / mod)
        traces.append(("data/model", _scatter(
            sub.theta_r, sub.phi, _colour(ratio, True), ratio, "data/model", "coloraxis2",
            coords, "", {"data": v, "model": mod})))
    names = [n_ for n_, _ in traces]
    fig = make_subplots(rows=1, cols=len(traces), subplot_titles=names,
                        horizontal_spacing=0.08)
    for col, (_, tr_) in enumerate(traces, start=1):
        fig.add_trace(tr_, row=1, col=col)
        _marks(fig, t, coords, col, col == 1)
    _disk_axes(fig, len(traces), coords)
    _colour_axes(fig, traces, log, q, cd is not None and not cd.quantity.absolute)
    sample = None
    if cd is not None:
        sample = str(cd.meas.meta.get("sample") or cd.meas.meta.get("file") or "measurement")
        if at is not None and not at.any():
            fig.add_annotation(text=f"no sample at θi = {math.degrees(t):.4g}°",
                               xref="x domain", yref="y domain", x=0.5, y=0.5,
                               showarrow=False)
    fig.update_layout(title={"text": title_text("hemisphere maps", model, label=label,
                                                theta_i=t, channel=cd.channel if cd else None,
                                                sample=sample)},
                      showlegend=True, legend={"orientation": "h", "y": -0.15})
    return fig


def _colour_axes(fig: go.Figure, traces: list[tuple[str, Any]], log: bool, q: Quantity,
                 relative: bool) -> None:
    """One colour scale for data and model, a diverging one (log10, centred on 1) for the
    ratio; colour bars with units."""
    parts = []
    for name, tr in traces:
        if name != "data/model":
            c = np.asarray(tr.z if name == "model" else tr.marker.color, dtype=float).ravel()
            parts.append(c[np.isfinite(c)])
    c = np.concatenate(parts) if parts else np.array([])
    lo, hi = (math.inf, -math.inf) if c.size == 0 else (float(c.min()), float(c.max()))
    if c.size > 20:
        # the 99.5th percentile: a model diverging at the horizon (TR75) must not set the
        # scale for the whole disk; the few values above it saturate
        hi = float(np.percentile(c, 99.5))
    if log and math.isfinite(hi):  # at most 4 decades: a few tiny values must not wash it out
        lo = max(lo, hi - 4.0)
    label = "relative value [1]" if relative else quantity_label(q)
    bar: dict[str, Any] = {"title": {"text": label, "side": "right"}, "x": 1.02, "len": 0.9}
    if log:
        bar.update(log_ticks(lo, hi))
    axis: dict[str, Any] = {"colorscale": "Magma", "colorbar": bar}
    if math.isfinite(lo) and math.isfinite(hi) and hi > lo:
        axis.update(cmin=lo, cmax=hi)
    fig.update_layout(coloraxis=axis)
    if any(name == "data/model" for name, _ in traces):
        ratio_bar = {"title": {"text": "data / model [1]", "side": "right"}, "x": 1.12,
                     "len": 0.9,
                     "tickvals": [-1, -0.5, -0.3, 0, 0.3, 0.5, 1],
                     "ticktext": ["0.1", "0.32", "0.5", "1", "2", "3.2", "10"]}
        fig.update_layout(coloraxis2={"colorscale": "RdBu_r", "cmin": -1.0, "cmax": 1.0,
                                      "cmid": 0.0, "colorbar": ratio_bar})


def mueller_maps(model: Model, theta_i: float, *, basis: str = "psps", resolution: int = 61,
                 coords: str = "cosines", label: str | None = None) -> go.Figure:
    """The normalized Mueller matrix ``m_ij/m00`` and the DoLP over the hemisphere.

    Sixteen heat maps in a 4 x 4 grid (row ``i`` = output, column ``j`` = input Stokes
    component ``I, Q, U, V``), each ``m_ij/m00`` of :meth:`Model.mueller
    <roughbrdf.models.Model.mueller>` (dimensionless, in [-1, 1], one diverging scale; the
    ``m00/m00`` panel is 1 wherever the model reflects), and a fifth column with the degree
    of linear polarization of the light reflected from natural incident light,
    ``sqrt(m10² + m20²)/m00`` (:func:`roughbrdf.stokes.dolp`, 0 to 1). Projected disk as in
    the module notes; ``basis`` as for :meth:`~roughbrdf.models.Model.mueller`. Trace names
    ``"m01/m00"`` ... and ``"DoLP"``; ``z`` the drawn values, ``customdata``
    ``theta_r_deg, phi_deg, m00`` (sr⁻¹).

    Raises
    ------
    roughbrdf.models.base.NoMuellerMatrix
        For a model without a Mueller matrix (e.g. RB08).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> fig = mueller_maps(rb.model("tr75"), 0.5, resolution=5)
    >>> fig.data[0].name, float(np.nanmax(np.abs(np.asarray(fig.data[0].z) - 1.0)))
    ('m00/m00', 0.0)
    """
    model = check_model(model)
    t = check_incidence(theta_i)
    n = check_resolution(resolution)
    axis, tr, ph = disk_grid(n, coords)
    inside = np.isfinite(tr)
    M = np.full((*tr.shape, 4, 4), np.nan)
    # one call for the whole grid; it raises NoMuellerMatrix for a model without one
    with np.errstate(invalid="ignore", over="ignore"):
        M[inside] = model.mueller(t, tr[inside], ph[inside], basis=basis)
    m00 = finite_or_nan(M[..., 0, 0])
    m00[~(m00 > 0)] = np.nan  # no reflected light: no normalized matrix, no polarization
    with np.errstate(invalid="ignore", divide="ignore"):
        N = finite_or_nan(M / m00[..., None, None])
        dl = finite_or_nan(dolp(np.where(np.isfinite(m00)[..., None], M[..., :, 0], 0.0)))
    fig = make_subplots(rows=4, cols=5, horizontal_spacing=0.03, vertical_spacing=0.05,
                        specs=[[{}] * 4 + [{"rowspan": 2}], [{}] * 4 + [None],
                               [{}] * 4 + [None], [{}] * 4 + [None]],
                        subplot_titles=[*(f"m{i}{j}/m00" for j in range(4) for i in (0,)),
                                        "DoLP (natural light)",
                                        *(f"m{i}{j}/m00" for i in (1, 2, 3) for j in range(4))])
    for i in range(4):
        for j in range(4):
            fig.add_trace(_heatmap(axis, tr, ph, N[..., i, j], m00, f"m{i}{j}/m00",
                                   "coloraxis", SR, "m00"), row=i + 1, col=j + 1)
    fig.add_trace(_heatmap(axis, tr, ph, dl, m00, "DoLP", "coloraxis2", SR, "m00"),
                  row=1, col=5)
    _marks(fig, t, coords, 5, True)
    _mueller_axes(fig, coords)
    fig.update_layout(
        coloraxis={"colorscale": "RdBu_r", "cmin": -1, "cmax": 1,
                   "colorbar": {"title": {"text": "m_ij / m00 [1]"}, "x": 1.02, "len": 0.5,
                                "y": 0.25}},
        coloraxis2={"colorscale": "Viridis", "cmin": 0, "cmax": 1,
                    "colorbar": {"title": {"text": "DoLP [1]"}, "x": 1.02, "len": 0.45,
                                 "y": 0.77}},
        title={"text": title_text(f"normalized Mueller matrix ({basis}) and DoLP", model,
                                  label=label, theta_i=t)},
        height=900, showlegend=False)
    return fig


def _mueller_axes(fig: go.Figure, coords: str) -> None:
    """Equal-aspect disks with rings on all 17 panels; titles on the lower left one."""
    edge = 1.05 if coords == "cosines" else 95.0
    shapes: list[dict[str, Any]] = []
    for key in [k for k in fig.layout if k.startswith("xaxis")]:
        sfx = key[len("xaxis"):]
        shapes += disk_rings(coords, f"x{sfx}", f"y{sfx}")
        fig.layout[f"yaxis{sfx}"].update(scaleanchor=f"x{sfx}", scaleratio=1,
                                         range=[-edge, edge], showticklabels=False,
                                         constrain="domain")
        fig.layout[key].update(range=[-edge, edge], showticklabels=False, constrain="domain")
    fig.update_layout(shapes=shapes)
    xt, yt = disk_axis_titles(coords)
    fig.update_xaxes(title_text=xt, showticklabels=True, row=4, col=1)
    fig.update_yaxes(title_text=yt, showticklabels=True, row=4, col=1)
