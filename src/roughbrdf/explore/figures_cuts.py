"""In-plane and cross-plane cuts of a model and a measurement, with residuals (Plotly).

Each cut is drawn against a *signed* reflection angle in degrees:

* in plane (the plane of incidence, ``φ = 0°`` / ``180°``): ``+θr`` on the forward (specular)
  side ``φ = 0``, ``−θr`` on the source side ``φ = 180°`` (the papers' axis,
  :func:`roughbrdf.geometry.signed_angle`);
* cross plane (``φ = ±90°``): ``+θr`` at ``φ = +90°``, ``−θr`` at ``φ = −90°``.

A sample belongs to a cut when its azimuth is within ``atol_deg`` of it (or ``θr <= atol_deg``,
the normal, which lies in both). Data are compared as :func:`roughbrdf.plot.plot_comparison`
compares them: ``brdf`` data with the model BRDF, ``brdf_cos``/``bridf`` with ``f_r cos θr``,
``relative`` data with the model divided by the closed-form scale ``K`` (TR75 Eq. 34).
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
from .figures_common import (
    HOVER_ANGLES,
    ChannelData,
    channel_data,
    check_resolution,
    colors,
    custom,
    deg,
    finite_or_nan,
    incidence_list,
    measured_incidences,
    optional_model,
    quantity_label,
    title_text,
)

__all__ = ["plane_cuts", "polarization_groups", "cut_masks"]

#: the cuts: name, azimuth of the positive side, of the negative side
_CUTS = (("in-plane", 0.0, math.pi), ("cross-plane", math.pi / 2, -math.pi / 2))
#: the default incidences of a model drawn alone, degrees
_MODEL_INCIDENCES_DEG = (0.0, 30.0, 60.0, 75.0)


def polarization_groups(gamma: np.ndarray | None, n: int) -> list[tuple[float | None,
                                                                         np.ndarray, str]]:
    """The samples split by incident polarization: ``[(gamma or None, mask, label)]``."""
    if gamma is None or np.isnan(gamma).all():
        return [(None, np.ones(n, dtype=bool), "")]
    g = np.round(gamma, 9)
    out: list[tuple[float | None, np.ndarray, str]] = []
    if np.isnan(g).any():
        out.append((None, np.isnan(g), ", unpolarized"))
    for v in np.unique(g[~np.isnan(g)]):
        out.append((float(v), g == v, f", γ = {math.degrees(v):.4g}°"))
    return out


def cut_masks(theta_r: np.ndarray, phi: np.ndarray, atol: float
              ) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per cut (module notes): ``(mask, signed angle in radians)`` of the samples."""
    c, s = np.cos(phi), np.sin(phi)
    near_normal = theta_r <= atol
    lim = math.sin(atol)
    return {"in-plane": ((np.abs(s) <= lim) | near_normal, np.where(c < 0, -theta_r, theta_r)),
            "cross-plane": ((np.abs(c) <= lim) | near_normal,
                            np.where(s < 0, -theta_r, theta_r))}


def _line_geometry(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Signed angle (degrees, both cuts concatenated), ``theta_r`` and ``phi`` of the model
    lines; the horizon is left out (unshadowed models diverge there)."""
    s = np.radians(np.linspace(-89.5, 89.5, n))
    tr = np.abs(s)
    phs = [np.where(s < 0, neg, pos) for _, pos, neg in _CUTS]
    return np.degrees(np.concatenate([s, s])), np.concatenate([tr, tr]), np.concatenate(phs)


def _model_lines(fig: go.Figure, model: Model, incs: list[float], quantity: Quantity,
                 k: float, groups: list[tuple[float | None, Any, str]], n: int) -> None:
    """Model lines: every incidence (and polarization) and both cuts in one evaluation each."""
    x, tr, ph = _line_geometry(n)
    cols = colors(len(incs))
    for gamma, _mask, suffix in groups:
        with np.errstate(invalid="ignore", over="ignore"):
            f = finite_or_nan(model.evaluate(np.asarray(incs)[:, None], tr[None, :],
                                             ph[None, :], quantity=quantity,
                                             polarization=gamma)) / k
        for row, t in enumerate(incs):
            d = math.degrees(t)
            for c, (cut, _, _) in enumerate(_CUTS):
                sl = slice(c * n, (c + 1) * n)
                cd, meta = custom(("theta_r_deg", "phi_deg", "value"), np.degrees(tr[sl]),
                                  np.degrees(ph[sl]), f[row, sl])
                fig.add_trace(go.Scatter(
                    x=x[sl], y=f[row, sl], mode="lines", name=f"model θi = {d:.4g}°{suffix} "
                    f"({cut})", line={"color": cols[row], "dash": "solid" if c == 0 else "dot"},
                    legendgroup=f"{d:.4g}{suffix}", showlegend=c == 0, customdata=cd, meta=meta,
                    hovertemplate=f"model θi = {d:.4g}°{suffix}<br>{HOVER_ANGLES}<br>"
                                  "%{customdata[2]:.4g}<extra></extra>"), row=1, col=c + 1)


def _data_points(fig: go.Figure, cd: ChannelData, model: Model | None, incs: list[float],
                 atol: float) -> bool:
    """Data markers per incidence, polarization and cut, and (with a model) the residual
    ``ln(data/model)`` below; returns whether any sample fell in a cut."""
    m = cd.meas
    data = cd.values
    mod = cd.model_at(model) if model is not None else None
    cuts = cut_masks(m.theta_r, m.phi, atol)
    groups = polarization_groups(m.polarization, m.n_samples)
    cols = colors(len(incs))
    tol = math.radians(0.05)  # the incidence tolerance of Measurement.at_incidence
    drawn = False
    for row, t in enumerate(incs):
        d = math.degrees(t)
        at = np.abs(m.theta_i - t) <= tol
        for _gamma, gmask, suffix in groups:
            for c, (cut, _, _) in enumerate(_CUTS):
                sel = at & gmask & cuts[cut][0]
                if not sel.any():
                    continue
                drawn = True
                x = deg(cuts[cut][1][sel])
                extra = () if mod is None else (mod[sel],)
                fields = ("theta_r_deg", "phi_deg", "value", "theta_i_deg") + (
                    ("model",) if mod is not None else ())
                cdata, meta = custom(fields, deg(m.theta_r[sel]), deg(m.phi[sel]), data[sel],
                                     deg(m.theta_i[sel]), *extra)
                name = f"θi = {d:.4g}°{suffix} ({cut})"
                fig.add_trace(go.Scatter(
                    x=x, y=data[sel], mode="markers", name="data " + name,
                    marker={"color": cols[row], "size": 6, "symbol": "circle-open"},
                    legendgroup=f"{d:.4g}{suffix}", showlegend=c == 0, customdata=cdata,
                    meta=meta, hovertemplate=f"data {name}<br>{HOVER_ANGLES}<br>"
                    "%{customdata[2]:.4g}<extra></extra>"), row=1, col=c + 1)
                if mod is None:
                    continue
                with np.errstate(divide="ignore", invalid="ignore"):  # <= 0: no log ratio
                    res = finite_or_nan(np.log(data[sel] / mod[sel]))
                rd, rmeta = custom(("theta_r_deg", "phi_deg", "value"), deg(m.theta_r[sel]),
                                   deg(m.phi[sel]), res)
                fig.add_trace(go.Scatter(
                    x=x, y=res, mode="markers", name="residual " + name,
                    marker={"color": cols[row], "size": 5}, legendgroup=f"{d:.4g}{suffix}",
                    showlegend=False, customdata=rd, meta=rmeta,
                    hovertemplate=f"ln(data/model) {name}<br>{HOVER_ANGLES}<br>"
                    "%{customdata[2]:.3f}<extra></extra>"), row=2, col=c + 1)
    return drawn


def _incidences(cd: ChannelData | None, incidences: Any) -> list[float]:
    if incidences is not None:
        return incidence_list(incidences, "incidences")
    if cd is not None:
        return measured_incidences(cd.meas)
    return list(np.radians(_MODEL_INCIDENCES_DEG))


def _value_range(fig: go.Figure, log: bool) -> list[float] | None:
    """The value axes' range (both cuts): on a log axis from the 0.5th percentile of the
    positive values / 3 to the largest x 3 (log10 units, Plotly's), so that a few values near
    zero (noise, a file's floor) do not stretch it over many decades; None otherwise."""
    ys = [np.asarray(t.y, dtype=float) for t in fig.data if t.yaxis in ("y", "y2")]
    v = np.concatenate(ys) if ys else np.array([])
    v = v[np.isfinite(v) & (v > 0)]
    if not log or v.size == 0:
        return None
    lo = max(float(v.min()), float(np.percentile(v, 0.5))) / 3.0
    return [math.log10(lo), math.log10(float(v.max()) * 3.0)]


def _axes(fig: go.Figure, rows: int, log: bool, ylabel: str) -> None:
    span = _value_range(fig, log)
    for c in (1, 2):
        fig.update_xaxes(range=[-90, 90], dtick=30, row=rows, col=c,
                         title_text=("signed θr [deg] (− source side φ = 180°)" if c == 1
                                     else "signed θr [deg] (− at φ = −90°)"))
        fig.update_yaxes(type="log" if log else "linear", row=1, col=c, range=span,
                         exponentformat="power", title_text=ylabel if c == 1 else None)
        if rows == 2:
            fig.update_xaxes(range=[-90, 90], dtick=30, row=1, col=c)
            fig.update_yaxes(row=2, col=c, zeroline=True,
                             title_text="ln(data / model) [1]" if c == 1 else None)


def plane_cuts(model: Model | None = None, measurement: Any = None, *,
               channel: int | str | None = None, incidences: Any = None, log: bool = True,
               quantity: str = "brdf", n: int = 361, atol_deg: float = 0.5,
               label: str | None = None) -> go.Figure:
    """In-plane and cross-plane cuts: data points and model lines per incidence, residuals.

    Left panel: the plane of incidence (``φ = 0°/180°``); right: the cross plane
    (``φ = ±90°``); abscissa the signed reflection angle in degrees (module notes). Data are
    open markers (``"data θi = 30° (in-plane)"``), the model a line per incidence (solid in
    plane, dotted across; ``"model θi = 30° (in-plane)"``), one colour per incidence. With both
    a model and a measurement a second row shows ``ln(data/model)`` at each sample
    (``"residual ..."``, dimensionless). Values are in the data's quantity (sr⁻¹; relative data:
    the model divided by ``K``, given in the title) or, for a model alone, ``quantity``.
    ``customdata``: ``theta_r_deg, phi_deg, value`` (data also ``theta_i_deg`` and, with a
    model, ``model``, the compared model value at the sample).

    Parameters
    ----------
    model : Model, optional
    measurement : Measurement, optional
        At least one of the two.
    channel : int or str, optional
        The measurement's channel (default the first); ignored without a measurement.
    incidences : float or sequence, optional
        Incidence angles, radians in ``[0, pi/2)``; default the measured ones (a model
        alone: 0, 30, 60, 75°). Data are drawn at the measured ones among them.
    log : bool
        Logarithmic value axis.
    quantity : {"brdf", "brdf_cos", "bridf"}
        The model's quantity when drawn alone (with data: the data's).
    n : int
        Points per model line and cut.
    atol_deg : float
        Azimuth tolerance of a cut, degrees.
    label : str, optional
        The model's name in the title.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> fig = plane_cuts(rb.model("lambertian", rho=0.5), incidences=[0.0], n=5)
    >>> [t.name for t in fig.data]
    ['model θi = 0° (in-plane)', 'model θi = 0° (cross-plane)']
    >>> [round(float(v), 6) for v in fig.data[0].y]      # rho/pi on both sides
    [0.159155, 0.159155, 0.159155, 0.159155, 0.159155]
    """
    model = optional_model(model)
    if model is None and measurement is None:
        raise ArgumentError("model", "give a model, a measurement or both")
    n = check_resolution(n, "n")
    if not 0.0 < atol_deg < 45.0:
        raise ArgumentError("atol_deg", "must be in (0, 45) degrees", value=atol_deg)
    cd = channel_data(measurement, channel, model) if measurement is not None else None
    incs = _incidences(cd, incidences)
    rows = 2 if (cd is not None and model is not None) else 1
    fig = make_subplots(rows=rows, cols=2, shared_xaxes=True, vertical_spacing=0.08,
                        row_heights=[0.7, 0.3] if rows == 2 else None,
                        subplot_titles=["in plane (φ = 0° / 180°)", "cross plane (φ = ±90°)"])
    q = cd.model_quantity if cd is not None else Quantity.parse(quantity)
    if model is not None:
        groups: list[tuple[float | None, Any, str]] = [(None, None, "")]
        if cd is not None:
            groups = list(polarization_groups(cd.meas.polarization, cd.meas.n_samples))
        _model_lines(fig, model, incs, q, cd.k if cd is not None else 1.0, groups, n)
    if cd is not None and not _data_points(fig, cd, model, incs, math.radians(atol_deg)):
        fig.add_annotation(text="no sample of these incidences lies in either cut",
                           xref="paper", yref="paper", x=0.5, y=0.5, showarrow=False)
    ylabel = quantity_label(q)
    if cd is not None and not cd.quantity.absolute:
        ylabel = "relative value [1]" + (" (model / K)" if model is not None else "")
    _axes(fig, rows, log, ylabel)
    what = "in-plane and cross-plane cuts"
    if cd is not None and model is not None and not cd.quantity.absolute:
        what += f", model / K with 1/K = {1 / cd.k:.4g}"
    sample = None
    if cd is not None:
        sample = str(cd.meas.meta.get("sample") or cd.meas.meta.get("file") or "measurement")
    fig.update_layout(title={"text": title_text(what, model, label=label,
                                                channel=cd.channel if cd else None,
                                                sample=sample)},
                      legend={"font": {"size": 10}})
    return fig
