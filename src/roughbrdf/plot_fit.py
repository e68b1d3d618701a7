"""The figure of one channel of a fit: data vs model, the residual maps, what was left out.

:func:`plot_fit` draws :func:`roughbrdf.plot.plot_comparison` (in-plane slices, the full width
above) and :func:`roughbrdf.plot.plot_residual_map` (one map per incidence below) into one
figure, with a note under it saying which samples the fit left out and why (the counts of
:attr:`roughbrdf.fitting.problem.data.ChannelData.excluded` in words,
:func:`roughbrdf.fitting.problem.data.excluded_text`). The measurement given is drawn as it is:
give it
the samples the fit used (:meth:`FitResult.plot_data <roughbrdf.fitting.FitResult.plot_data>`,
or ``roughbrdf plot --fit``'s selection through
:func:`roughbrdf.fitting.problem.data.prepare_channel`),
so that the figure shows the fit and nothing else. Matplotlib is imported when a figure is
drawn, not with this module.
"""

from __future__ import annotations

import textwrap
from typing import TYPE_CHECKING, Any

from . import plot as rbplot

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from .instrument import Aperture
    from .measurement import Measurement
    from .models.base import Model

__all__ = ["plot_fit"]


def plot_fit(model: Model, measurement: Measurement, *, channel: int | str = 0,
             aperture: Aperture | float | None = None, note: str | None = None,
             title: str | None = None, fig: Any = None) -> tuple[Figure, tuple[Axes, Axes]]:
    """Data vs model above, the relative residual per incidence below, ``note`` underneath.

    Parameters
    ----------
    model : Model
        The fitted model.
    measurement : Measurement
        The samples to draw: those the fit used.
    channel : int or str
        The channel of ``measurement`` drawn.
    aperture : float or Aperture, optional
        The fit's instrument aperture (radians): the model is drawn averaged over it.
    note : str, optional
        A line under the figure, e.g. how many samples the fit left out and why.
    title : str, optional
        The figure's title.
    fig : matplotlib.figure.Figure, optional
        Drawn into (a new pyplot-free figure when None).

    Returns
    -------
    (fig, (ax_comparison, ax_residuals))
        ``ax_residuals`` is the first residual panel (:func:`roughbrdf.plot.plot_residual_map`).
    """
    if fig is None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(12.5, 9.5), layout="constrained")
    gs = fig.add_gridspec(2, 1, height_ratios=(1.15, 1.0))
    ax1 = fig.add_subplot(gs[0])
    ax2 = fig.add_subplot(gs[1])
    # through the module's names, so that a caller's replacement of either is used
    rbplot.plot_comparison(model, measurement, channel=channel, ax=ax1, aperture=aperture)
    _, ax2 = rbplot.plot_residual_map(model, measurement, channel=channel, ax=ax2,
                                      aperture=aperture)
    if title:
        fig.suptitle(title, fontsize="medium")
    if note:  # wrapped to the figure's width (about 12 characters an inch at this size)
        fig.supxlabel(textwrap.fill(note, max(40, int(12 * fig.get_figwidth()))),
                      fontsize="small")
    return fig, (ax1, ax2)
