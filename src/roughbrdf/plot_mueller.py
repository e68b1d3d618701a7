"""Polarimetric figures: the 16 Mueller elements and the degree of linear polarization.

* :func:`plot_mueller_hemisphere` -- a 4×4 grid of maps over the reflection hemisphere on the
  projected disk (as :func:`roughbrdf.plot.plot_hemisphere`): ``m00`` (the unpolarized BRDF,
  logarithmic colours) and the 15 normalized elements ``m_ij/m00`` in [-1, 1];
* :func:`plot_mueller_in_plane` -- the same 16 elements along the plane of incidence against
  the signed reflection angle (negative: the source side), one curve per incidence;
* :func:`plot_dolp` -- the degree of linear polarization of the reflected light for an incident
  Stokes vector (natural light by default) over the hemisphere.

The matrices come from :meth:`Model.mueller <roughbrdf.models.Model.mueller>` in the basis asked
for (``"psps"``: each direction's s/p basis; ``"xyxy"``: a basis regular at the normal; the
conventions are in :mod:`roughbrdf.mueller`). Figures are built without pyplot (like
:mod:`roughbrdf.plot`); each function returns the figure (and its axes).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from .plot import disk_decorations, hemisphere_grid, incidence_colors, new_axes

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from numpy.typing import ArrayLike

    from .models import Model

__all__ = ["plot_dolp", "plot_mueller_hemisphere", "plot_mueller_in_plane",
           "normalized_mueller"]


def normalized_mueller(matrices: np.ndarray) -> np.ndarray:
    """``m_ij/m00`` for ``i, j != 0`` and ``m00`` itself, shape unchanged (NaN where
    ``m00 <= 0``: no light, no polarization).

    Examples
    --------
    >>> m = np.diag([2.0, 1.0, -1.0, 0.5])
    >>> normalized_mueller(m).diagonal().tolist()
    [2.0, 0.5, -0.5, 0.25]
    """
    m = np.asarray(matrices, dtype=float)
    m00 = m[..., 0, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where((m00 > 0)[..., None, None], m / m00[..., None, None], np.nan)
    out[..., 0, 0] = m00
    return out


def _new_figure(fig: Figure | None, size: tuple[float, float]) -> Figure:
    if fig is not None:
        return fig
    from matplotlib.figure import Figure

    return Figure(figsize=size, layout="constrained")


def plot_mueller_hemisphere(model: Model, theta_i: float, *, basis: str = "psps",
                            n: int = 101, fig: Figure | None = None) -> tuple[Figure, Any]:
    """The 16 elements over the hemisphere for one incidence (module notes).

    Returns ``(fig, axes)`` with ``axes`` of shape (4, 4), ``axes[i, j]`` showing ``m_ij``.
    """
    from matplotlib import colors as mcolors

    fig = _new_figure(fig, (11.5, 10.5))
    axes = np.asarray(fig.subplots(4, 4, sharex=True, sharey=True))
    X, Y, tr, ph = hemisphere_grid(n)
    inside = np.isfinite(tr)
    M = np.full((*X.shape, 4, 4), np.nan)
    M[inside] = normalized_mueller(model.mueller(theta_i, tr[inside], ph[inside], basis=basis))
    for i in range(4):
        for j in range(4):
            ax = axes[i, j]
            Z = np.ma.masked_invalid(M[..., i, j])
            if i == j == 0:
                pos = Z.compressed()[Z.compressed() > 0]
                norm: Any = mcolors.LogNorm(max(pos.min(), pos.max() * 1e-4), pos.max()) \
                    if pos.size else mcolors.Normalize()
                mesh = ax.pcolormesh(X, Y, np.ma.masked_less_equal(Z, 0), shading="auto",
                                     cmap="magma", norm=norm, rasterized=True)
                fig.colorbar(mesh, ax=ax, shrink=0.8, label="m00 = BRDF [sr⁻¹]")
            else:
                mesh = ax.pcolormesh(X, Y, Z, shading="auto", cmap="RdBu_r", vmin=-1, vmax=1,
                                     rasterized=True)
            disk_decorations(ax, labels=False)
            ax.set_title(f"m{i}{j}" + ("" if i == j == 0 else "/m00"), fontsize="small")
    fig.colorbar(mesh, ax=axes[:, -1].tolist(), shrink=0.5, label="m_ij/m00")
    fig.suptitle(rf"{model.name}: Mueller matrix ({basis}), $\theta_i$ = "
                 f"{math.degrees(theta_i):g}°; x = sinθr cosφ (forward →)", fontsize="medium")
    return fig, axes


def plot_mueller_in_plane(model: Model, theta_i: ArrayLike, *, basis: str = "psps",
                          n: int = 361, limit_deg: float = 89.0,
                          fig: Figure | None = None) -> tuple[Figure, Any]:
    """The 16 elements along the plane of incidence, one curve per incidence (module notes).

    The abscissa is the signed reflection angle: ``theta_r`` on the forward side (``phi =
    0``), ``-theta_r`` on the source side (``phi = pi``). ``m00`` is drawn on a log axis.
    """
    fig = _new_figure(fig, (12.0, 9.5))
    axes = np.asarray(fig.subplots(4, 4, sharex=True))
    signed = np.radians(np.linspace(-limit_deg, limit_deg, n))
    tr, ph = np.abs(signed), np.where(signed < 0, math.pi, 0.0)
    incidences = np.atleast_1d(np.asarray(theta_i, dtype=float))
    for t, color in zip(incidences, incidence_colors(incidences.size), strict=True):
        M = normalized_mueller(model.mueller(t, tr, ph, basis=basis))
        for i in range(4):
            for j in range(4):
                axes[i, j].plot(np.degrees(signed), M[:, i, j], color=color, lw=1.2,
                                label=rf"$\theta_i$ = {math.degrees(t):g}°")
    for i in range(4):
        for j in range(4):
            ax = axes[i, j]
            ax.set_title(f"m{i}{j}" + ("" if i == j == 0 else "/m00"), fontsize="small")
            if i == j == 0:
                ax.set_yscale("log")
            else:
                ax.set_ylim(-1.05, 1.05)
            ax.axvline(0, color="0.7", lw=0.5)
    axes[0, 0].legend(fontsize="xx-small")
    for ax in axes[-1]:
        ax.set_xlabel("signed θr [deg] (− = source side)")
    fig.suptitle(f"{model.name}: Mueller matrix in the plane of incidence ({basis})",
                 fontsize="medium")
    return fig, axes


def plot_dolp(model: Model, theta_i: float, *, incident: ArrayLike | None = None,
              basis: str = "psps", n: int = 201, ax: Axes | None = None
              ) -> tuple[Figure, Axes]:
    """Degree of linear polarization of the reflected light over the hemisphere.

    ``incident`` is the incident Stokes vector (:mod:`roughbrdf.stokes`; default natural
    light, ``[1, 0, 0, 0]``); the DoLP ``sqrt(Q² + U²)/I`` does not depend on the basis.
    """
    from .stokes import dolp, reflected_stokes, unpolarized

    fig, ax = new_axes(ax, figsize=(5.6, 4.8))
    s_in = unpolarized() if incident is None else np.asarray(incident, dtype=float)
    X, Y, tr, ph = hemisphere_grid(n)
    inside = np.isfinite(tr)
    Z = np.full(X.shape, np.nan)
    # a model that diverges at the horizon (TR75 has no shadowing: +-inf at theta_r = 90 deg)
    # has no DoLP there: NaN, drawn blank, without NumPy's warning
    with np.errstate(invalid="ignore"):
        Z[inside] = dolp(reflected_stokes(model, theta_i, tr[inside], ph[inside], s_in,
                                          basis=basis))
    mesh = ax.pcolormesh(X, Y, np.ma.masked_invalid(Z), shading="auto", cmap="viridis",
                         vmin=0.0, vmax=1.0, rasterized=True)
    fig.colorbar(mesh, ax=ax, label="degree of linear polarization", shrink=0.9)
    disk_decorations(ax)
    s = math.sin(theta_i)
    ax.plot([s], [0], marker="+", ms=10, color="w", ls="none", label="specular")
    ax.legend(loc="upper right", fontsize="x-small", framealpha=0.6)
    ax.set_title(rf"{model.name}: DoLP, $\theta_i$ = {math.degrees(theta_i):g}°",
                 fontsize="medium")
    return fig, ax
