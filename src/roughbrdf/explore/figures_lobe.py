"""The lobe in 3-D over the hemisphere, and two lobes compared (Plotly, no Dash).

The lobe is the surface ``r(θr, φ) w_r``: along each reflected direction ``w_r = (sin θr cos φ,
sin θr sin φ, cos θr)`` (the library's frame, ``docs/models.md`` §1.1: normal +z, source on −x,
``φ = 0`` the forward/specular side) at the distance ``r`` = the BRDF ``f_r`` or ``f_r cos θr``
(sr⁻¹), or with ``log`` the number of decades above a floor ``10^-decades`` times the largest
value. The whole ``(n_theta × n_phi)`` grid goes through one model evaluation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import plotly.graph_objects as go
from plotly.subplots import make_subplots

from ..errors import ArgumentError
from ..models import Model, model_label
from ..quantity import Quantity
from .figures_common import (
    HOVER_ANGLES,
    SR,
    check_incidence,
    check_model,
    check_resolution,
    custom,
    finite_or_nan,
    quantity_label,
    title_text,
)

__all__ = ["LobeGrid", "compare_lobes", "lobe_3d", "lobe_grid"]

_QUANTITIES = (Quantity.BRDF, Quantity.BRDF_COS)


@dataclass(frozen=True)
class LobeGrid:
    """A model's values on the ``(θr, φ)`` grid of a lobe.

    Attributes
    ----------
    theta_r, phi : numpy.ndarray
        Grids (radians), shape ``(n_theta, n_phi)``.
    values : numpy.ndarray
        The quantity (sr⁻¹), NaN where not finite.
    specular, retro : float
        The value at the specular (``θr = θi, φ = 0``) and retro (``θr = θi, φ = π``)
        directions.
    """

    theta_r: np.ndarray
    phi: np.ndarray
    values: np.ndarray
    specular: float
    retro: float


def _quantity(quantity: Any) -> Quantity:
    try:
        q = Quantity.parse(quantity)
    except ValueError:
        q = None
    if q not in _QUANTITIES:
        raise ArgumentError("quantity", "must be 'brdf' or 'brdf_cos'", value=quantity)
    return q


def lobe_grid(model: Model, theta_i: float, quantity: Quantity, *, n_theta: int, n_phi: int,
              theta_max_deg: float = 89.5, polarization: Any = None) -> LobeGrid:
    """``model`` on ``θr`` in ``[0, theta_max_deg]`` x ``φ`` in ``[-180°, 180°]``, with the
    specular and retro directions appended to the same single evaluation."""
    if not 0.0 < theta_max_deg <= 90.0:
        raise ArgumentError("theta_max_deg", "must be in (0, 90]", value=theta_max_deg)
    tr = np.radians(np.linspace(0.0, theta_max_deg, n_theta))
    ph = np.linspace(-math.pi, math.pi, n_phi)
    TR, PH = np.meshgrid(tr, ph, indexing="ij")
    # the grid and the two marked directions in one call of the compiled kernel
    all_tr = np.concatenate([TR.ravel(), [theta_i, theta_i]])
    all_ph = np.concatenate([PH.ravel(), [0.0, math.pi]])
    with np.errstate(invalid="ignore", over="ignore"):  # a divergence at the horizon: NaN
        f = finite_or_nan(model.evaluate(theta_i, all_tr, all_ph, quantity=quantity,
                                         polarization=polarization))
    return LobeGrid(TR, PH, f[:-2].reshape(TR.shape), float(f[-2]), float(f[-1]))


def _radius(values: np.ndarray, log: bool, floor: float) -> np.ndarray:
    """The drawn radius: the value (sr⁻¹), or with ``log`` decades above ``floor``."""
    if not log:
        return values
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.maximum(np.log10(np.maximum(values, 0.0) / floor), 0.0)


def _floor(grids: list[LobeGrid], decades: float) -> float:
    top = max((float(np.nanmax(g.values)) if np.isfinite(g.values).any() else 0.0)
              for g in grids)
    # an all-zero (or all-NaN) lobe has no scale: any positive floor draws it at the origin
    return top * 10.0 ** (-decades) if top > 0 else 1.0


def _surface(grid: LobeGrid, name: str, log: bool, floor: float, quantity: Quantity,
             colorscale: str, scene: str, **kw: Any) -> go.Surface:
    r = _radius(grid.values, log, floor)
    st = np.sin(grid.theta_r)
    cd, meta = custom(("theta_r_deg", "phi_deg", "value"), np.degrees(grid.theta_r),
                      np.degrees(grid.phi), grid.values)
    label = quantity_label(quantity)
    colorbar = {"title": {"text": ("decades above floor" if log else label)},
                **kw.pop("colorbar", {})}
    return go.Surface(
        x=r * st * np.cos(grid.phi), y=r * st * np.sin(grid.phi), z=r * np.cos(grid.theta_r),
        surfacecolor=r, customdata=cd, meta=meta, name=name, colorscale=colorscale,
        showlegend=True,
        scene=scene, colorbar=colorbar,
        hovertemplate=f"{name}<br>{HOVER_ANGLES}<br>{label.split(' [')[0]} = "
                      f"%{{customdata[2]:.4g}} {SR}<extra></extra>", **kw)


def _markers(grid: LobeGrid, theta_i: float, log: bool, floor: float, tag: str,
             scene: str, reach: float) -> list[go.Scatter3d]:
    """The specular and retro directions: a line from the origin out to ``reach`` (beyond
    the lobe) with a marker at its end, carrying the model's value there."""
    out = []
    d = math.degrees(theta_i)
    for what, phi, value, color in (("specular", 0.0, grid.specular, "#d62728"),
                                    ("retro", math.pi, grid.retro, "#1f77b4")):
        w = np.array([math.sin(theta_i) * math.cos(phi), math.sin(theta_i) * math.sin(phi),
                      math.cos(theta_i)])
        pts = np.outer([0.0, reach], w)
        cd, meta = custom(("theta_r_deg", "phi_deg", "value"), [d, d], [math.degrees(phi)] * 2,
                          [value, value])
        out.append(go.Scatter3d(
            x=pts[:, 0], y=pts[:, 1], z=pts[:, 2], mode="lines+markers", name=what + tag,
            line={"color": color, "width": 5}, marker={"size": [0, 5], "color": color},
            customdata=cd, meta=meta, scene=scene,
            hovertemplate=f"{what} (θr = θi = {d:.4g}°, φ = {math.degrees(phi):g}°)<br>value ="
                          f" %{{customdata[2]:.4g}} {SR}<extra></extra>"))
    return out


def _scene(log: bool, floor: float, quantity: Quantity, reach: float | None = None
           ) -> dict[str, Any]:
    """A scene's axes (titles with units); with ``reach`` fixed ranges, the same for every
    scene of a figure so that side-by-side lobes are drawn to one scale."""
    unit = f"decades above {floor:.3g} {SR}" if log else f"{SR}"
    q = "f_r" if quantity is Quantity.BRDF else "f_r cos θr"
    axes: dict[str, Any] = {
        "xaxis": {"title": {"text": f"x = {q} sin θr cos φ [{unit}] (φ = 0°: specular →)"}},
        "yaxis": {"title": {"text": f"y = {q} sin θr sin φ [{unit}]"}},
        "zaxis": {"title": {"text": f"z = {q} cos θr [{unit}] (normal)"}},
        # outside the box whatever the lobe's shape (an "data" aspect box of a narrow spike put
        # this eye inside it: only crossing lines were drawn)
        "aspectmode": "data", "camera": {"eye": {"x": 0.4, "y": -2.2, "z": 1.3}}}
    if reach is not None:
        for k, lo in (("xaxis", -reach), ("yaxis", -reach), ("zaxis", 0.0)):
            axes[k]["range"] = [lo, reach]
        axes.update(aspectmode="manual", aspectratio={"x": 2, "y": 2, "z": 1})
    return axes


def _reach(grids: list[LobeGrid], log: bool, floor: float) -> float:
    tops = [np.nanmax(_radius(g.values, log, floor)) if np.isfinite(g.values).any() else 0.0
            for g in grids]
    top = float(max(tops))
    return 1.15 * top if top > 0 else 1.0


def lobe_3d(model: Model, theta_i: float, *, quantity: str = "brdf", log: bool = False,
            resolution: int = 61, polarization: Any = None, n_phi: int | None = None,
            decades: float = 4.0, theta_max_deg: float = 89.5, label: str | None = None,
            channel: str | None = None) -> go.Figure:
    """The lobe of ``model`` over the reflection hemisphere at incidence ``theta_i``, in 3-D.

    Draws one rotatable surface, radius = the BRDF ``f_r`` (``quantity="brdf"``) or
    ``f_r cos θr`` (``"brdf_cos"``) in sr⁻¹ along each reflected direction (module notes), or
    with ``log`` the decades above ``10^-decades`` times the largest value; colour = radius.
    The specular (``θr = θi, φ = 0°``, red) and retro (``θr = θi, φ = 180°``, toward the
    source, blue) directions are lines from the origin. Hover: ``θr``, ``φ`` in degrees and
    the value in sr⁻¹. The trace ``customdata`` holds ``theta_r_deg, phi_deg, value``.

    Parameters
    ----------
    model : Model
    theta_i : float
        Incidence angle, radians, in ``[0, pi/2)``.
    quantity : {"brdf", "brdf_cos"}
    log : bool
        Radius in decades (the shape of a dim lobe beside a bright one) instead of sr⁻¹.
    resolution : int
        Grid points in ``θr`` (``[0, theta_max_deg]``) and, unless ``n_phi``, in ``φ``
        (``[-180°, 180°]``).
    polarization : optional
        Incident polarization (:meth:`~roughbrdf.models.Model.evaluate`).
    n_phi : int, optional
        Points in azimuth (e.g. 256 for a 64 x 256 grid).
    decades : float
        Depth of the logarithmic radius.
    theta_max_deg : float
        The last zenith row, degrees (the horizon, where unshadowed models diverge, is left out
        by default; values that are not finite are drawn as gaps).
    label, channel : str, optional
        The model's name in the title (default :func:`~roughbrdf.models.model_label`) and a
        channel it belongs to (e.g. the fitted wavelength).

    Returns
    -------
    plotly.graph_objects.Figure

    Examples
    --------
    >>> import math, roughbrdf as rb
    >>> fig = lobe_3d(rb.model("lambertian", rho=0.5), math.radians(30), resolution=5)
    >>> [t.name for t in fig.data]
    ['lambertian', 'specular', 'retro']
    >>> round(float(fig.data[0].customdata[0, 0, 2]), 6)   # rho/pi
    0.159155
    """
    model = check_model(model)
    t = check_incidence(theta_i)
    q = _quantity(quantity)
    n_t = check_resolution(resolution)
    n_p = n_t if n_phi is None else check_resolution(n_phi, "n_phi")
    grid = lobe_grid(model, t, q, n_theta=n_t, n_phi=n_p, theta_max_deg=theta_max_deg,
                     polarization=polarization)
    floor = _floor([grid], decades)
    name = label or model_label(model)
    fig = go.Figure([_surface(grid, name, log, floor, q, "Viridis", "scene"),
                     *_markers(grid, t, log, floor, "", "scene", _reach([grid], log, floor))])
    pol = "" if polarization is None else f", polarization {polarization}"
    fig.update_layout(title={"text": title_text(f"{quantity_label(q).split(' [')[0]} lobe"
                                                + (" (log radius)" if log else "") + pol,
                                                model, label=label, theta_i=t,
                                                channel=channel)},
                      scene=_scene(log, floor, q, _reach([grid], log, floor)),
                      margin={"l": 0, "r": 0, "t": 50, "b": 0},
                      legend={"x": 0.01, "y": 0.99})
    return fig


def compare_lobes(model_a: Model, model_b: Model, theta_i: float, *, mode: str = "overlay",
                  quantity: str = "brdf", log: bool = False, resolution: int = 61,
                  decades: float = 4.0, labels: tuple[str, str] | None = None) -> go.Figure:
    """Two lobes at one incidence (as :func:`lobe_3d`), on one radius scale.

    ``mode="overlay"``: both surfaces in one scene, ``model_a`` opaque (Viridis) and
    ``model_b`` translucent (Reds); ``"side"``: one scene each, side by side, the same radius
    mapping (sr⁻¹, or decades above one common floor with ``log``). Trace names are
    ``"A: <label>"`` and ``"B: <label>"`` (labels default to
    :func:`~roughbrdf.models.model_label`); each has the specular and retro markers
    (``"specular (A)"``, ...). ``customdata`` as in :func:`lobe_3d`.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> fig = compare_lobes(rb.model("lambertian"), rb.model("tr75"), 0.3, resolution=5)
    >>> [t.name for t in fig.data if t.type == "surface"]
    ['A: lambertian', 'B: trowbridge-reitz-1975']
    """
    a = check_model(model_a, "model_a")
    b = check_model(model_b, "model_b")
    if mode not in ("overlay", "side"):
        raise ArgumentError("mode", "must be 'overlay' or 'side'", value=mode)
    t = check_incidence(theta_i)
    q = _quantity(quantity)
    n = check_resolution(resolution)
    names = labels or (model_label(a), model_label(b))
    grids = [lobe_grid(m, t, q, n_theta=n, n_phi=n) for m in (a, b)]
    floor = _floor(grids, decades)
    reach = _reach(grids, log, floor)
    side = mode == "side"
    fig = make_subplots(rows=1, cols=2, specs=[[{"type": "scene"}, {"type": "scene"}]],
                        subplot_titles=[f"A: {names[0]}", f"B: {names[1]}"]) if side \
        else go.Figure()
    scenes = ("scene", "scene2") if side else ("scene", "scene")
    top = reach / 1.15  # the largest radius of both: one colour scale
    for i, (grid, tag, cs) in enumerate(zip(grids, "AB", ("Viridis", "Reds"), strict=True)):
        # side by side: one colour scale and bar; overlaid: B translucent in its own colours
        extra: dict[str, Any] = {"cmin": 0.0, "cmax": top}  # radii are >= 0
        if side:
            extra.update(showscale=i == 0)
            cs = "Viridis"
        else:
            extra["colorbar"] = {"x": 1.0 + 0.12 * i, "len": 0.8,
                                 "title": {"text": tag + (" [decades]" if log else f" [{SR}]")}}
            if i == 1:
                extra["opacity"] = 0.55
        fig.add_trace(_surface(grid, f"{tag}: {names[i]}", log, floor, q, cs, scenes[i],
                               **extra))
        for tr in _markers(grid, t, log, floor, f" ({tag})", scenes[i], reach):
            fig.add_trace(tr)
    what = f"{quantity_label(q).split(' [')[0]} lobes, {mode}" + (" (log radius)" if log else "")
    fig.update_layout(title={"text": title_text(what, label=f"{names[0]} vs {names[1]}",
                                                theta_i=t)},
                      margin={"l": 0, "r": 0, "t": 60, "b": 0}, legend={"x": 0.01, "y": 0.99})
    fig.update_layout(scene=_scene(log, floor, q, reach))  # one fixed box: any lobe shape
    if side:
        fig.update_layout(scene2=_scene(log, floor, q, reach))
    return fig
