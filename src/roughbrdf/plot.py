"""Matplotlib figures for models and measurements.

Every ``plot_*`` function takes ``ax=`` (an existing :class:`matplotlib.axes.Axes`; a new figure is
made when it is ``None``) and returns ``(fig, ax)``. New figures are built with
:class:`matplotlib.figure.Figure` directly, never through ``pyplot``, so no global figure state
is created or leaked and any backend (Agg included) works; save them with ``fig.savefig(path)``.

Angles are radians in every argument (the library's convention) and degrees on the plot axes.
The in-plane axis is the papers' *signed* reflection angle: ``+theta_r`` on the forward
(specular) side ``phi = 0``, ``-theta_r`` on the source side ``phi = pi``
(:func:`roughbrdf.geometry.signed_angle`).

Relative data are compared with a model through the closed-form scale ``K`` of
:func:`roughbrdf.quantity.relative_scale` (``K x ~ f``, TR75 Eq. 34, the convention of the fit,
``docs/fitting.md``): the data are drawn as measured and the model divided by ``K``. With
``aperture=`` (:mod:`roughbrdf.instrument`; :meth:`FitResult.plot
<roughbrdf.fitting.FitResult.plot>` passes the fit's own) the model is drawn, and the residuals
taken, averaged over the instrument's aperture cone, as the fit compared it with the data.
Matplotlib is imported when a figure is drawn, not with this module.

=========================  ==================================================================
function                   what it draws
=========================  ==================================================================
:func:`plot_in_plane`      model in the plane of incidence, several incidences (TS67 Fig. 8)
:func:`plot_polar`         TR75-style polar plot of the BRIDF against azimuth, ⊥ and ∥ (Fig. 6)
:func:`plot_hemisphere`    heat map on the projected disk ``(sin θ cos φ, sin θ sin φ)``
:func:`plot_comparison`    measurement vs model, in-plane slices, one colour per incidence
:func:`plot_residual_map`  relative residual ``(data - model)/model``, one map per incidence
=========================  ==================================================================

A fit's figure (both, and what the fit left out) is :func:`roughbrdf.plot_fit.plot_fit`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from . import geometry
from .instrument import Aperture, aperture_average
from .mpl_load import load_matplotlib
from .quantity import Quantity, relative_scale

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from .measurement import Measurement
    from .models.base import Model

__all__ = [
    "new_axes",
    "disk_decorations",
    "hemisphere_grid",
    "incidence_colors",
    "model_values",
    "compared_values",
    "best_scale",
    "plot_in_plane",
    "plot_polar",
    "plot_hemisphere",
    "plot_comparison",
    "plot_residual_map",
]

QUANTITY_LABELS = {
    "brdf": r"BRDF $f_r$ [sr$^{-1}$]",
    "bridf": r"BRIDF $f_r\cos\theta_r$ [sr$^{-1}$]",
    "brdf_cos": r"$f_r\cos\theta_r$ [sr$^{-1}$]",
    "relative": r"relative reflectance $f_r/f_r(\mathrm{specular})$",
}
SIGNED_LABEL = r"signed reflection angle $\theta_r$ [deg] (negative = source side)"


# --------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------
def new_axes(ax: Axes | None = None, *, polar: bool = False,
             figsize: tuple[float, float] = (6.4, 4.8)) -> tuple[Figure, Axes]:
    """Return ``(fig, ax)``: ``ax``'s figure, or a new pyplot-free figure with one axes."""
    if ax is not None:
        fig = ax.get_figure()
        if fig is None:  # an axes always belongs to a figure once created
            raise ValueError("ax must belong to a figure")
        return fig, ax  # type: ignore[return-value]  # a SubFigure acts as a Figure here
    # a new Figure, Matplotlib's compiled modules loaded with Ctrl-C held (mpl_load)
    fig = load_matplotlib()(figsize=figsize, layout="constrained")
    ax = fig.add_subplot(projection="polar" if polar else None)
    return fig, ax


def incidence_colors(n: int, cmap: str = "viridis") -> list[Any]:
    """``n`` distinguishable colours (one per incidence), dark to light."""
    from matplotlib import colormaps

    cm = colormaps[cmap]
    if n <= 1:
        return [cm(0.15)]
    return [cm(x) for x in np.linspace(0.05, 0.85, n)]


def _as_list(theta: ArrayLike) -> list[float]:
    return [float(t) for t in np.atleast_1d(np.asarray(theta, dtype=float))]


def model_values(model: Model, theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike,
                 quantity: str = "brdf", polarization: Any = None) -> np.ndarray:
    """The model's ``brdf``, ``bridf``/``brdf_cos`` or ``relative`` value (specular = 1):
    :meth:`roughbrdf.models.Model.evaluate` as a float array."""
    return np.asarray(model.evaluate(theta_i, theta_r, phi, quantity=Quantity.parse(quantity),
                                     polarization=polarization), dtype=float)


def best_scale(data: ArrayLike, model: ArrayLike) -> float:
    """The model-side factor ``1/K`` that puts a model onto data of unknown scale.

    A thin wrapper of :func:`roughbrdf.quantity.relative_scale`, which gives the data-side
    ``K`` (``K data ~ model``, TR75 Eq. 34, as the fit uses it): ``best_scale`` is ``1/K``, the
    factor with ``data ~ best_scale * model``. It minimizes
    ``sum(((data - s model)/(s model))^2)`` over ``s`` (the same TR75 sigma). Only finite pairs
    with a positive model value are used; returns 1.0 if there are none.

    Examples
    --------
    >>> best_scale([2.0, 4.0], [1.0, 2.0])
    2.0
    """
    return 1.0 / relative_scale(data, model)


def compared_values(model: Model, theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike,
                    quantity: str = "brdf", polarization: Any = None,
                    aperture: Aperture | float | None = None) -> np.ndarray:
    """:func:`model_values`, or with ``aperture`` the model averaged over the instrument's
    cone (:func:`roughbrdf.instrument.aperture_average`; ``brdf`` or ``bridf`` only)."""
    if aperture is None:
        return model_values(model, theta_i, theta_r, phi, quantity, polarization)
    return np.asarray(aperture_average(model, theta_i, theta_r, phi, aperture, quantity=quantity,
                                       polarization=polarization), dtype=float)


def _deg(x: ArrayLike) -> np.ndarray:
    return np.degrees(np.asarray(x, dtype=float))


def _auto_log(values: np.ndarray) -> bool:
    v = values[np.isfinite(values) & (values > 0)]
    return v.size > 1 and v.max() / v.min() > 30.0


def _signed_grid(n: int, limit_deg: float = 89.5) -> np.ndarray:
    return np.radians(np.linspace(-limit_deg, limit_deg, n))


# --------------------------------------------------------------------------------------------
# model plots
# --------------------------------------------------------------------------------------------
def plot_in_plane(model: Model, theta_i: ArrayLike, *, quantity: str = "brdf",
                  log: bool = False, polarization: Any = None, n: int = 721,
                  limit_deg: float = 89.9, label: str | None = None, ax: Axes | None = None,
                  **line_kw: Any) -> tuple[Figure, Axes]:
    """Model in the plane of incidence on the signed reflection-angle axis (degrees).

    Parameters
    ----------
    model : Model
    theta_i : float or sequence of float
        Incidence angle(s), radians; one curve (colour) per incidence.
    quantity : {"brdf", "bridf", "relative"}
        ``relative`` is the model divided by its specular value (TS67 Eq. 23 for TS67).
    log : bool
        Logarithmic value axis.
    polarization : optional
        Passed to the model (``None``, ``"s"``, ``"p"`` or an angle gamma in radians).
    n, limit_deg : int, float
        Samples and the extent of the signed axis, ``[-limit_deg, limit_deg]``.
    label : str, optional
        Legend label prefix (default: the model name).
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    (fig, ax)
    """
    fig, ax = new_axes(ax)
    incs = _as_list(theta_i)
    ts = _signed_grid(n, limit_deg)
    tr, ph = geometry.from_signed_angle(ts)
    prefix = f"{label}, " if label else ""
    for t, col in zip(incs, incidence_colors(len(incs)), strict=True):
        y = model_values(model, t, tr, ph, quantity, polarization)
        ax.plot(_deg(ts), y, color=col, label=prefix + rf"$\theta_i$ = {math.degrees(t):g}°",
                **line_kw)
        ax.axvline(math.degrees(t), color=col, lw=0.6, ls=":", alpha=0.6)
    ax.set_xlabel(SIGNED_LABEL)
    ax.set_ylabel(QUANTITY_LABELS.get(quantity, quantity))
    ax.set_xlim(-90, 90)
    ax.set_xticks(np.arange(-90, 91, 30))
    if log:
        ax.set_yscale("log")
    ax.set_title(label or model.name)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return fig, ax


def polar_curves(model: Model, theta_i: float, elevation: float, psi: ArrayLike,
                 polarizations: Sequence[Any] = ("s", "p")) -> dict[Any, np.ndarray]:
    """BRIDF against TR75's azimuth ``psi`` (0 toward the source) at fixed incidence/elevation.

    Angles are radians in TR75's convention, converted with :func:`geometry.from_tr75`.
    Returns ``{polarization: values}``.
    """
    ti, tr, ph = geometry.from_tr75(theta_i, elevation, psi)
    return {p: np.asarray(model.bridf(ti, tr, ph, p), dtype=float) for p in polarizations}


def plot_polar(model: Model, theta_i: float, elevation: float, *, n: int = 361,
               polarizations: Sequence[Any] = ("s", "p"), rmax: float | None = None,
               label: str | None = None, ax: Axes | None = None) -> tuple[Figure, Axes]:
    """TR75-style polar plot (Fig. 6): radius = BRIDF, polar angle = azimuth ψ.

    TR75 measures ψ from the source side (ψ = 0 toward the source, ψ = 180° the forward/specular
    side); the conversion goes through :func:`roughbrdf.geometry.from_tr75`. Incident
    polarization ⊥ (``"s"``, solid) and ∥ (``"p"``, dashed) to the plane of incidence.

    Parameters
    ----------
    model : Model
    theta_i, elevation : float
        TR75 ``beta`` (incidence zenith) and ``theta`` (reflection **elevation**), radians.
    n : int
        Azimuth samples over the full circle.
    polarizations : sequence
        Polarizations to draw (default ⊥ and ∥); ``None`` adds the unpolarized mean.
    """
    from matplotlib.ticker import MaxNLocator

    fig, ax = new_axes(ax, polar=True)
    psi = np.linspace(0.0, 2 * math.pi, n)
    curves = polar_curves(model, theta_i, elevation, psi, polarizations)
    styles = {"s": ("-", "⊥ (s)"), "p": ("--", "∥ (p)"), None: (":", "unpolarized")}
    for p, y in curves.items():
        ls, name = styles.get(p, ("-.", f"γ = {p}"))
        ax.plot(psi, y, ls=ls, color="k" if p in ("s", None) else "C3", label=name)
    pax: Any = ax  # a PolarAxes (new_axes(polar=True)); typed as Axes
    pax.set_theta_zero_location("N")  # psi = 0 (toward the source) at the top
    pax.set_theta_direction(-1)
    pax.set_thetagrids(range(0, 360, 45))
    ax.yaxis.set_major_locator(MaxNLocator(4))
    pax.set_rlabel_position(22.5)
    if rmax is not None:
        pax.set_rlim(0, rmax)
    ax.set_xlabel(r"azimuth $\psi$ (0° toward the source) [deg]", labelpad=4)
    ax.set_ylabel(r"BRIDF [sr$^{-1}$]", labelpad=28)
    head = f"{label}: " if label else ""
    ax.set_title(rf"{head}$\beta$ = {math.degrees(theta_i):g}°, "
                 rf"$\theta$ = {math.degrees(elevation):g}° elev.", fontsize="medium")
    ax.legend(loc="lower left", bbox_to_anchor=(-0.12, -0.12), fontsize="small")
    return fig, ax


def hemisphere_grid(n: int = 201) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Projected-disk grid: ``(x, y, theta_r, phi)`` with NaN angles outside the unit disk."""
    x = np.linspace(-1.0, 1.0, n)
    X, Y = np.meshgrid(x, x)
    r = np.hypot(X, Y)
    inside = r <= 1.0
    tr = np.where(inside, np.arcsin(np.minimum(r, 1.0)), np.nan)
    ph = np.where(inside, np.arctan2(Y, X), np.nan)
    return X, Y, tr, ph


def plot_hemisphere(model: Model, theta_i: float, *, quantity: str = "brdf", log: bool = True,
                    polarization: Any = None, n: int = 201, cmap: str = "magma",
                    vmin: float | None = None, vmax: float | None = None,
                    ax: Axes | None = None) -> tuple[Figure, Axes]:
    """Heat map of the model over the reflection hemisphere, on the projected disk.

    ``x = sin θ_r cos φ`` (forward/specular side to the right), ``y = sin θ_r sin φ``; the source
    sits at ``(-sin θ_i, 0)`` and the specular direction at ``(+sin θ_i, 0)``. With ``log`` the
    colours are logarithmic; a colorbar is added.
    """
    from matplotlib import colors as mcolors

    fig, ax = new_axes(ax, figsize=(5.6, 4.8))
    X, Y, tr, ph = hemisphere_grid(n)
    inside = np.isfinite(tr)
    Z = np.full(X.shape, np.nan)
    Z[inside] = model_values(model, theta_i, tr[inside], ph[inside], quantity, polarization)
    Z[~np.isfinite(Z)] = np.nan
    pos = Z[np.isfinite(Z) & (Z > 0)]
    if log and pos.size:
        lo = vmin if vmin is not None else max(pos.min(), pos.max() * 1e-4)
        norm: Any = mcolors.LogNorm(vmin=lo, vmax=vmax if vmax is not None else pos.max())
        Z = np.where(Z > 0, Z, np.nan)
    else:
        norm = mcolors.Normalize(vmin=vmin, vmax=vmax)
    mesh = ax.pcolormesh(X, Y, np.ma.masked_invalid(Z), shading="auto", cmap=cmap, norm=norm,
                         rasterized=True)
    fig.colorbar(mesh, ax=ax, label=QUANTITY_LABELS.get(quantity, quantity), shrink=0.9)
    disk_decorations(ax)
    s = math.sin(theta_i)
    ax.plot([s], [0], marker="+", ms=10, color="c", ls="none", label="specular")
    ax.plot([-s], [0], marker="x", ms=7, color="c", ls="none", label="source (retro)")
    ax.legend(loc="upper right", fontsize="x-small", framealpha=0.6)
    ax.set_title(rf"{model.name}, $\theta_i$ = {math.degrees(theta_i):g}°", fontsize="medium")
    return fig, ax


def disk_decorations(ax: Axes, *, labels: bool = True) -> None:
    """Circles at theta_r = 30, 60, 90 deg, the plane of incidence, equal aspect and (with
    ``labels``) the axis labels of a projected-disk map (:func:`hemisphere_grid`)."""
    t = np.linspace(0, 2 * math.pi, 361)
    for deg in (30, 60, 90):
        r = math.sin(math.radians(deg))
        ax.plot(r * np.cos(t), r * np.sin(t), color="0.6", lw=0.6 if deg < 90 else 1.0)
    ax.axhline(0, color="0.6", lw=0.5)
    ax.set_aspect("equal")
    ax.set_xlim(-1.05, 1.05)
    ax.set_ylim(-1.05, 1.05)
    if labels:
        ax.set_xlabel(r"$x = \sin\theta_r\cos\phi$ (forward $\rightarrow$)")
        ax.set_ylabel(r"$y = \sin\theta_r\sin\phi$")


# --------------------------------------------------------------------------------------------
# measurement vs model
# --------------------------------------------------------------------------------------------
def _curve_quantity(meas: Measurement) -> Quantity:
    """The model quantity drawn against ``meas``: BRDF, or BRDF·cosθr for cosine-weighted data
    and relative data proportional to it (``meta["relative_to"]``)."""
    return Quantity.parse(meas.quantity).compared_with(meas.meta.get("relative_to"))


def _comparison_setup(model: Model, measurement: Measurement, channel: int | str,
                      aperture: Aperture | float | None = None
                      ) -> tuple[Measurement, np.ndarray, np.ndarray, str, float]:
    """Single channel; model values at the samples, matched to the data's quantity.

    Returns ``(meas, data, model_at_samples, quantity_used, k)``: ``brdf`` is compared with
    the model BRDF, ``brdf_cos``/``bridf`` with BRDF·cosθr, ``relative`` with the model BRDF
    (BRDF·cosθr when ``meta["relative_to"]`` says so) divided by the closed-form data scale
    ``k`` (:func:`roughbrdf.quantity.relative_scale`, ``k data ~ model``; 1 for absolute data).
    With ``aperture`` the model is averaged over the instrument's cone.
    """
    meas = measurement.select_channel(channel)
    data = meas.values[:, 0]
    q = meas.quantity
    curve_q = _curve_quantity(meas)
    mod = compared_values(model, meas.theta_i, meas.theta_r, meas.phi, curve_q,
                          meas.polarization, aperture)
    k = relative_scale(data, mod) if q == "relative" else 1.0
    return meas, data, mod / k, q, k


def _pol_groups(meas: Measurement) -> list[tuple[Any, np.ndarray, str]]:
    """Split samples by incident polarization: ``[(pol, mask, label)]``."""
    if meas.polarization is None or np.all(np.isnan(meas.polarization)):
        return [(None, np.ones(meas.n_samples, bool), "")]
    out: list[tuple[float | None, np.ndarray, str]] = []
    g = np.round(meas.polarization, 9)
    if np.isnan(g).any():
        out.append((None, np.isnan(g), " unpol."))
    for val in np.unique(g[~np.isnan(g)]):
        mask = g == val
        name = {0.0: " ∥", round(math.pi / 2, 9): " ⊥"}.get(float(val),
                                                              f" γ={math.degrees(val):g}°")
        out.append((float(val), mask, name))
    return out


def _pol_mask(meas: Measurement, pol: float | None) -> np.ndarray:
    if meas.polarization is None:
        return np.full(meas.n_samples, pol is None)
    g = np.round(meas.polarization, 9)
    return np.isnan(g) if pol is None else g == pol


def _parity(ax: Axes, data: np.ndarray, mod: np.ndarray, ylabel: str, title: str) -> None:
    """Model against data on log axes (a measurement with no in-plane samples)."""
    ok = np.isfinite(data) & np.isfinite(mod) & (data > 0) & (mod > 0)
    ax.loglog(data[ok], mod[ok], ".", ms=3, alpha=0.6, label="samples")
    if ok.any():
        lo, hi = min(data[ok].min(), mod[ok].min()), max(data[ok].max(), mod[ok].max())
        ax.plot([lo, hi], [lo, hi], "k-", lw=0.8, label="model = data")
    ax.set_xlabel("measured " + ylabel)
    ax.set_ylabel("model " + ylabel)
    ax.set_title(title + " (no in-plane samples: parity plot)", fontsize="medium")
    ax.legend(fontsize="small")


def _comparison_title(model: Model, meas: Measurement, k: float,
                      aperture: Aperture | float | None) -> str:
    title = f"{model.name} vs {meas.meta.get('sample') or meas.meta.get('file') or 'data'}"
    title += f" [{meas.channels[0]}]"
    if meas.quantity == "relative":
        title += f", 1/K = {1 / k:.4g}"  # the model is drawn divided by K
    a = aperture.half_angle if isinstance(aperture, Aperture) else aperture
    if a:
        title += f", aperture {math.degrees(a):.3g}°"
    return title


def _in_plane_slices(ax: Axes, model: Model, inplane: Measurement, k: float, curve_q: str,
                     aperture: Aperture | float | None) -> tuple[np.ndarray, list[float]]:
    """Data markers and model curves per incidence (and polarization); returns the data and,
    per curve, the model's largest finite value over the signed angles the data span."""
    incs = inplane.incidences(4)
    ts_grid = _signed_grid(361, 89.5)
    tr_g, ph_g = geometry.from_signed_angle(ts_grid)
    groups = _pol_groups(inplane)
    markers = ["o", "s", "^", "D"]
    all_vals, peaks = [], []
    for t, col in zip(incs, incidence_colors(len(incs)), strict=True):
        sel = inplane.at_incidence(float(t), atol=1e-4)
        for gi, (pol, _mask, pname) in enumerate(groups):
            sub = sel.subset(_pol_mask(sel, pol)) if len(groups) > 1 else sel
            if sub.n_samples == 0:
                continue
            x = _deg(geometry.signed_angle(sub.theta_r, sub.phi))
            y = sub.values[:, 0]
            all_vals.append(y)
            ax.plot(x, y, ls="none", marker=markers[gi % 4], ms=3.5, mfc="none", color=col,
                    label=rf"data $\theta_i$ = {math.degrees(t):.3g}°{pname}")
            yc = compared_values(model, float(t), tr_g, ph_g, curve_q, pol, aperture) / k
            ax.plot(_deg(ts_grid), yc, color=col, lw=1.2, ls="-" if gi == 0 else "--",
                    label=rf"model $\theta_i$ = {math.degrees(t):.3g}°{pname}")
            # the peak over the data's span and specular (a model may diverge toward grazing, where
            # no sample says anything); at the samples and specular too (a peak between grid points)
            lo_x, hi_x = min(x.min(), math.degrees(t)), max(x.max(), math.degrees(t))
            span = (_deg(ts_grid) >= lo_x) & (_deg(ts_grid) <= hi_x)
            at = compared_values(model, np.append(sub.theta_i, t), np.append(sub.theta_r, t),
                                 np.append(sub.phi, 0.0), curve_q, pol, aperture) / k
            both = np.concatenate([yc[span], np.atleast_1d(at)])
            if np.isfinite(both).any():
                peaks.append(float(np.nanmax(np.where(np.isfinite(both), both, np.nan))))
    return (np.concatenate(all_vals) if all_vals else np.array([])), peaks


def plot_comparison(model: Model, measurement: Measurement, *, channel: int | str = 0,
                    ax: Axes | None = None, aperture: Aperture | float | None = None
                    ) -> tuple[Figure, Axes]:
    """Measurement vs model: in-plane slices on the signed angle axis, one colour per incidence.

    Markers are the measured in-plane samples (``phi`` within 0.5° of 0 or 180°), lines the model
    at the same incidence (and polarization, if the data have one). The compared quantity follows
    ``measurement.quantity``: ``brdf`` against the model BRDF; ``brdf_cos``/``bridf`` against
    BRDF·cosθr; ``relative`` against the model BRDF (BRDF·cosθr when ``meta["relative_to"]`` is
    ``bridf``) divided by the closed-form data scale ``K``
    (:func:`roughbrdf.quantity.relative_scale`, ``K x ~ f`` as in the fit; ``1/K`` is given in
    the title). With ``aperture``
    (radians, or an :class:`~roughbrdf.instrument.Aperture`) the model is averaged over the
    instrument's cone (:func:`roughbrdf.instrument.aperture_average`), as a fit with that
    aperture compared it with the data. The value axis is logarithmic when the data span
    more than a factor 30. A measurement with no in-plane samples is shown as a parity plot
    (model against data) instead.
    """
    fig, ax = new_axes(ax)
    meas, data, mod, q, k = _comparison_setup(model, measurement, channel, aperture)
    curve_q = _curve_quantity(meas)
    ylabel = QUANTITY_LABELS[curve_q.value]
    if q == "relative":
        ylabel = rf"relative value (model {'BRIDF' if curve_q.cosine_weighted else 'BRDF'} / $K$)"
    inplane = meas.in_plane()
    title = _comparison_title(model, meas, k, aperture)
    if inplane.n_samples == 0:
        _parity(ax, data, mod, ylabel, title)
        return fig, ax
    _value_axis(ax, *_in_plane_slices(ax, model, inplane, k, curve_q, aperture))
    ax.set_xlim(-90, 90)
    ax.set_xticks(np.arange(-90, 91, 30))
    ax.set_xlabel(SIGNED_LABEL)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize="medium")
    ax.grid(True, alpha=0.3)
    n_curves = len(inplane.incidences(4)) * len(_pol_groups(inplane))
    ax.legend(fontsize="x-small", ncol=2 if n_curves > 4 else 1)
    return fig, ax


def _value_axis(ax: Axes, vals: np.ndarray, peaks: Sequence[float] = ()) -> None:
    """The value range: the data and each model curve's peak (``peaks``, over the angles the
    data span), padded by a factor 3 on log axes and 5 % on linear ones; logarithmic when the
    data span more than a factor 30."""
    top = np.concatenate([vals, np.asarray(peaks, dtype=float)])
    if _auto_log(vals):
        ax.set_yscale("log")
        pos = vals[np.isfinite(vals) & (vals > 0)]
        hi = float(np.max(top[np.isfinite(top) & (top > 0)]))
        # the 0.5th percentile keeps a few noise values near zero from stretching the axis
        ax.set_ylim(max(pos.min(), float(np.percentile(pos, 0.5))) / 3, hi * 3)
    elif np.isfinite(vals).any():
        fin = top[np.isfinite(top)]
        lo, hi = min(0.0, float(fin.min())), float(fin.max())
        pad = 0.05 * (hi - lo) if hi > lo else 1.0  # all equal (e.g. zeros): a unit range
        ax.set_ylim(lo - pad, hi + pad)


def relative_residuals(model: Model, measurement: Measurement, *, channel: int | str = 0,
                       aperture: Aperture | float | None = None
                       ) -> tuple[Measurement, np.ndarray]:
    """``(meas, (data - model)/model)`` for one channel, with the quantity and aperture
    handling of :func:`plot_comparison` (NaN where the model is not positive and finite); for
    relative data ``(K x - f)/f``, TR75's residual (Eq. 34)."""
    meas, data, mod, _q, _k = _comparison_setup(model, measurement, channel, aperture)
    with np.errstate(divide="ignore", invalid="ignore"):
        res = np.where(np.isfinite(mod) & (mod > 0), (data - mod) / mod, np.nan)
    return meas, res


def _panel_grid(fig: Figure, ax: Axes, n: int) -> list[Axes]:
    """``n`` panels in ``ax``'s place (``ax`` the first), in the grid of largest panels."""
    spec = ax.get_subplotspec()
    if spec is None:  # an axes placed by hand (add_axes) has no grid cell to divide
        raise ValueError("ax must be a subplot (fig.add_subplot) to hold the residual panels")
    pos = ax.get_position()
    w, h = pos.width * fig.get_figwidth(), pos.height * fig.get_figheight()
    ncols = max(range(1, n + 1), key=lambda c: (min(w / c, h / math.ceil(n / c)), -c))
    gs = spec.subgridspec(math.ceil(n / ncols), ncols)
    ax.set_subplotspec(gs[0])
    return [ax] + [fig.add_subplot(gs[j]) for j in range(1, n)]


def _degree_disk(ax: Axes) -> None:
    """Circles at theta_r = 30, 60, 90 deg on a panel of axes theta_r cos/sin(phi) [deg]."""
    t = np.linspace(0, 2 * math.pi, 361)
    for deg in (30, 60, 90):
        ax.plot(deg * np.cos(t), deg * np.sin(t), color="0.6", lw=0.6 if deg < 90 else 1.0)
    ax.axhline(0, color="0.6", lw=0.5)
    ax.set_aspect("equal")
    ax.set(xlim=(-95, 95), ylim=(-95, 95))
    ax.set_xticks(np.arange(-90, 91, 30))
    ax.set_yticks(np.arange(-90, 91, 30))
    ax.tick_params(labelsize="x-small")


def plot_residual_map(model: Model, measurement: Measurement, *, channel: int | str = 0,
                      ax: Axes | None = None, aperture: Aperture | float | None = None
                      ) -> tuple[Figure, Axes]:
    """Relative residual ``(data - model)/model`` of every sample, one panel per incidence.

    Each measured incidence has its own map of the reflection hemisphere: a sample sits at
    ``(theta_r cos(phi), theta_r sin(phi))`` in degrees (forward side ``phi = 0`` to the right,
    circles at ``theta_r`` = 30, 60, 90 deg, ``+`` the specular direction), coloured by its
    residual on one diverging scale for all panels, symmetric about 0 (clipped at the 98th
    percentile of ``|residual|``, and at ±1 at most: a factor 2 off is saturated), with one
    colour bar. Each panel's title gives its incidence, the r.m.s. relative residual (TR75's
    σ, Eq. 34) of its samples and their number; a new figure's title the r.m.s. of all.
    ``aperture``: as for :func:`plot_comparison`. With ``ax`` (a subplot), its place in the
    figure is divided into the panels, ``ax`` the first.

    Returns
    -------
    (fig, ax)
        ``ax`` is the first panel; every panel holds one scatter collection of its samples.
    """
    from matplotlib import colors as mcolors

    meas, res = relative_residuals(model, measurement, channel=channel, aperture=aperture)
    ok = np.isfinite(res)
    incs = [t for t in meas.incidences(4) if (ok & (np.abs(meas.theta_i - t) <= 1e-4)).any()]
    n, own = max(len(incs), 1), ax is None
    fig, ax = new_axes(ax, figsize=(min(n, 4) * 2.9 + 1.3, 3.3 * math.ceil(n / 4) + 0.4))
    panels = _panel_grid(fig, ax, n)
    x, y = _deg(meas.theta_r) * np.cos(meas.phi), _deg(meas.theta_r) * np.sin(meas.phi)
    p98 = float(np.percentile(np.abs(res[ok]), 98)) if ok.any() else 1.0
    lim = min(p98, 1.0) if p98 > 0 else 1.0
    norm = mcolors.TwoSlopeNorm(vcenter=0.0, vmin=-lim, vmax=lim)
    ch = meas.channels[0]
    sc = None
    for pax, t in zip(panels, incs, strict=False):
        m = (np.abs(meas.theta_i - t) <= 1e-4) & ok
        sc = pax.scatter(x[m], y[m], c=np.clip(res[m], -lim, lim), cmap="RdBu_r", norm=norm,
                         s=9, edgecolors="0.3", linewidths=0.15, rasterized=True)
        pax.plot([math.degrees(t)], [0.0], marker="+", color="k", ms=8, ls="none",
                 label="specular")
        rms_t = float(np.sqrt(np.mean(res[m] ** 2)))
        pax.set_title(rf"$\theta_i$ = {math.degrees(t):.3g}° [{ch}]" + "\n"
                      + f"r.m.s. {rms_t:.3g} ({int(m.sum())} samples)", fontsize="small")
    for pax in panels:
        _degree_disk(pax)
    panels[0].set_xlabel(r"$\theta_r\cos\phi$ [deg] (forward $\rightarrow$)", fontsize="small")
    panels[0].set_ylabel(r"$\theta_r\sin\phi$ [deg]", fontsize="small")
    panels[0].legend(fontsize="x-small", loc="upper left", framealpha=0.6)
    if sc is not None:
        clipped = bool(np.abs(res[ok]).max() > lim)
        fig.colorbar(sc, ax=panels, label="(data − model) / model", shrink=0.9,
                     extend="both" if clipped else "neither")
    rms = float(np.sqrt(np.mean(res[ok] ** 2))) if ok.any() else float("nan")
    if not incs:  # nothing finite to draw: say so where the samples would be
        panels[0].set_title(f"[{ch}] no finite residual", fontsize="small")
    if own:  # a figure of the caller's keeps the caller's title
        fig.suptitle(f"{model.name}: relative residual [{ch}], r.m.s. {rms:.3g} over "
                     f"{int(ok.sum())} samples", fontsize="medium")
    return fig, panels[0]
