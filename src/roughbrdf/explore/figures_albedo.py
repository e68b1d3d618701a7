"""The albedo (TIS) of a model against incidence, with the energy limit (Plotly)."""

from __future__ import annotations

from typing import Any

import numpy as np
import plotly.graph_objects as go

from ..errors import ArgumentError
from ..geometry import as_angle_array
from ..integrate import albedo
from ..models import Model
from .figures_common import check_model, custom, finite_or_nan, title_text

__all__ = ["albedo_curve", "WARNING_NAME"]

#: the ``name`` of the layout annotation that warns of an albedo above 1
WARNING_NAME = "energy warning"


def _incidences_deg(incidences_deg: Any) -> np.ndarray:
    """The incidences of the curve, degrees in ``[0, 90)`` (the range of every view)."""
    if incidences_deg is None:
        return np.arange(0.0, 90.0, 1.0)
    try:
        d = np.atleast_1d(as_angle_array(incidences_deg, "incidences_deg")).astype(float)
    except ArgumentError:
        raise ArgumentError("incidences_deg", "must be a number or numbers (degrees)",
                            value=incidences_deg) from None
    d = d.ravel()
    if d.size == 0 or not (np.isfinite(d).all() and d.min() >= 0.0 and d.max() < 90.0):
        raise ArgumentError("incidences_deg", "must be finite angles in [0, 90) degrees",
                            value=incidences_deg)
    return np.sort(d)


def albedo_curve(model: Model, *, incidences_deg: Any = None, tolerance: float = 1e-3,
                 polarization: Any = None, label: str | None = None) -> go.Figure:
    """The albedo (directional-hemispherical reflectance, the TIS) against incidence.

    Draws :func:`roughbrdf.albedo` (dimensionless) at each incidence in degrees (default 0,
    1, ..., 89°; every incidence in one evaluation), as the line ``"albedo"``; the energy
    limit ``"albedo = 1"`` (dashed); and, when the albedo exceeds ``1 + tolerance`` anywhere,
    the points above it (``"albedo > 1"``, red) and a visible warning annotation (layout
    annotation named :data:`WARNING_NAME`) giving the largest albedo, where it is reached and
    from which incidence on the limit is crossed. ``customdata``: ``theta_i_deg, value``.

    Parameters
    ----------
    model : Model
    incidences_deg : array_like, optional
        Incidences, degrees in ``[0, 90)``.
    tolerance : float
        How far above 1 counts as gaining energy (the library's ``1e-3``,
        :attr:`Model.conserves_energy <roughbrdf.models.Model.conserves_energy>`).
    polarization : optional
        One incident polarization for all incidences (:func:`roughbrdf.albedo`).
    label : str, optional
        The model's name in the title.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> fig = albedo_curve(rb.model("lambertian", rho=0.5), incidences_deg=[0, 45])
    >>> [round(float(v), 6) for v in fig.data[0].y], len(fig.layout.annotations)
    ([0.5, 0.5], 0)
    """
    model = check_model(model)
    if not (isinstance(tolerance, int | float) and 0.0 <= tolerance < 1.0):
        raise ArgumentError("tolerance", "must be a number in [0, 1)", value=tolerance)
    d = _incidences_deg(incidences_deg)
    a = finite_or_nan(np.atleast_1d(albedo(model, np.radians(d), polarization=polarization)))
    cd, meta = custom(("theta_i_deg", "value"), d, a)
    fig = go.Figure(go.Scatter(
        x=d, y=a, mode="lines+markers", name="albedo", customdata=cd, meta=meta,
        marker={"size": 4}, hovertemplate="θi = %{x:.4g}°<br>albedo = %{y:.5f}<extra></extra>"))
    fig.add_trace(go.Scatter(x=[0.0, 90.0], y=[1.0, 1.0], mode="lines", name="albedo = 1",
                             line={"color": "#666", "dash": "dash"}, hoverinfo="skip"))
    over = a > 1.0 + tolerance
    if over.any():
        c2, m2 = custom(("theta_i_deg", "value"), d[over], a[over])
        fig.add_trace(go.Scatter(x=d[over], y=a[over], mode="markers", name="albedo > 1",
                                 marker={"color": "#d62728", "size": 7}, customdata=c2,
                                 meta=m2, hovertemplate="θi = %{x:.4g}°<br>albedo = %{y:.5f}"
                                 "<extra>gains energy</extra>"))
        top = int(np.nanargmax(a))
        fig.add_annotation(
            name=WARNING_NAME, xref="paper", yref="paper", x=0.02, y=0.98, xanchor="left",
            yanchor="top", showarrow=False, align="left", bgcolor="#fff3cd",
            bordercolor="#d62728", font={"color": "#8a1c1c"},
            text=(f"⚠ albedo above 1: the model reflects more than it receives (largest "
                  f"{a[top]:.4g} at θi = {d[top]:.4g}°; above 1 + {tolerance:g} from θi = "
                  f"{d[over][0]:.4g}° on)"))
    fig.update_layout(
        title={"text": title_text("albedo (TIS) against incidence", model, label=label)},
        xaxis={"title": {"text": "incidence θi [deg]"}, "range": [0, 90], "dtick": 15},
        yaxis={"title": {"text": "albedo (directional-hemispherical reflectance) [1]"},
               "rangemode": "tozero"})
    return fig
