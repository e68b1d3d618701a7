"""The explorer's views in a notebook: ``rb.explore(model_or_fit, measurement)``.

:func:`explore` returns an :class:`Explorer`, which Jupyter displays through IPython's rich
display protocol (``_repr_mimebundle_``, "Rich output" in the IPython documentation): a
``text/html`` fragment holding the figures of :mod:`roughbrdf.explore.figures` (the lobe in
3-D, the in-plane and cross-plane cuts with the data, the hemisphere maps, the albedo against
incidence and, for a polarized model, the Mueller maps), the model's (or the fit's) table
(:mod:`roughbrdf.html_repr`), and a ``text/plain`` summary for consoles.

The HTML works offline: plotly.js is written inline once, in the first figure
(Plotly's ``Figure.to_html(include_plotlyjs=True)``; the others ``include_plotlyjs=False``), so
neither a CDN nor require.js is needed; no ``<script src=...>`` is written. The same fragment
saved with :meth:`Explorer.to_html` opens in a browser without a network.

Importing this module loads neither Plotly nor Dash (``roughbrdf.explore`` imports it): the
figures are drawn when the explorer is displayed or :meth:`Explorer.figures` is called
(``pip install roughbrdf[explore]``).

Examples
--------
>>> import roughbrdf as rb
>>> ex = rb.explore(rb.model("lambertian", rho=0.4), resolution=21)
>>> len(ex.figures())   # lobe, cuts, hemisphere map, albedo, Mueller maps
5
>>> bundle = ex._repr_mimebundle_()
>>> sorted(bundle), bundle["text/plain"].splitlines()[0]
(['text/html', 'text/plain'], 'Explorer: model lambertian at theta_i = 30 deg')
"""

from __future__ import annotations

import math
import uuid
from dataclasses import dataclass, field
from html import escape
from typing import TYPE_CHECKING, Any

from ..errors import ArgumentError

if TYPE_CHECKING:
    from ..fitting.results.result import FitResult
    from ..measurement import Measurement
    from ..models import Model

__all__ = ["Explorer", "explore", "DEFAULT_INCIDENCE_DEG"]

#: the incidence shown without ``theta_i`` and without data (degrees); with data, the measured
#: incidence nearest to it
DEFAULT_INCIDENCE_DEG = 30.0


def _plotly() -> Any:
    """The explorer's figures module, with a clear message when Plotly is not installed."""
    try:
        from . import figures
    except ImportError as exc:  # the optional extra is missing
        raise ImportError(f"rb.explore needs Plotly: pip install 'roughbrdf[explore]' ({exc})"
                          ) from exc
    return figures


@dataclass(eq=False)
class Explorer:
    """The views of a model, a measurement or a fit, for a notebook (:func:`explore`).

    Attributes
    ----------
    model : Model or None
        The model drawn (a fit's: the channel's fitted model); None for a measurement alone.
    measurement : Measurement or None
        The data drawn beside it.
    theta_i : float
        The incidence of the lobe, the hemisphere maps and the Mueller maps, radians.
    channel : str or None
        The measurement's channel compared (a fit's: the fitted channel).
    fit : FitResult or None
        The fit, when one was given (its table is shown).
    resolution : int
        Grid points per axis of the lobe, the hemisphere maps and the Mueller maps (the
        HTML grows with its square: 61 keeps a notebook's output to a few MB).
    """

    model: Model | None
    measurement: Measurement | None
    theta_i: float
    channel: str | None = None
    fit: FitResult | None = field(default=None, repr=False)
    resolution: int = 61

    def figures(self) -> list[Any]:
        """The figures, in the order shown: with a model the lobe (3-D), the cuts, the
        hemisphere maps, the albedo against incidence and (a model with a Mueller matrix)
        the Mueller maps; a measurement alone, its cuts and hemisphere map.

        Returns
        -------
        list of plotly.graph_objects.Figure
        """
        fg = _plotly()
        m, meas, t, ch = self.model, self.measurement, self.theta_i, self.channel
        n = self.resolution
        if m is None:
            return [fg.plane_cuts(measurement=meas, channel=ch),
                    fg.hemisphere_maps(measurement=meas, theta_i=t, channel=ch, resolution=n)]
        out = [fg.lobe_3d(m, t, resolution=n), fg.plane_cuts(m, meas, channel=ch),
               fg.hemisphere_maps(m, meas, theta_i=t, channel=ch, resolution=n),
               fg.albedo_curve(m)]
        if _has_mueller(m):
            out.append(fg.mueller_maps(m, t, resolution=n))
        return out

    def _title(self) -> str:
        from ..models import model_label

        what = (f"model {model_label(self.model)}" if self.model is not None
                else "measurement")
        return f"Explorer: {what} at theta_i = {math.degrees(self.theta_i):.4g} deg"

    def _data_line(self) -> str:
        meas = self.measurement
        if meas is None:
            return "no measurement"
        where = meas.meta.get("file") or "a measurement made in Python"
        ch = f", channel {self.channel}" if self.channel is not None else ""
        return f"data: {where} ({meas.n_samples} samples{ch})"

    def __repr__(self) -> str:
        return f"{self._title()}\n{self._data_line()}"

    def _table(self) -> str:
        if self.fit is not None:
            return self.fit._repr_html_()
        if self.model is not None:
            return self.model._repr_html_()
        assert self.measurement is not None  # an explorer shows a model or data
        return self.measurement._repr_html_()

    def to_html(self, *, include_plotlyjs: bool | str = True) -> str:
        """The HTML fragment of the explorer: a title, the table, every figure.

        ``include_plotlyjs``: as Plotly's ``Figure.to_html``, for the first figure only (the
        others never include it): ``True`` writes plotly.js inline (offline, the default),
        ``False`` leaves it out (a page that has loaded it already).
        """
        prefix = f"roughbrdf-explore-{uuid.uuid4().hex[:10]}"
        parts = [f'<div class="roughbrdf-explorer" id="{prefix}">',
                 f"<h3>{escape(self._title())}</h3>", f"<p>{escape(self._data_line())}</p>",
                 self._table()]
        for i, fig in enumerate(self.figures()):
            parts.append(fig.to_html(full_html=False, include_plotlyjs=include_plotlyjs
                                     if i == 0 else False, div_id=f"{prefix}-{i}",
                                     config={"displaylogo": False, "responsive": True}))
        parts.append("</div>")
        return "\n".join(parts)

    def _repr_mimebundle_(self, include: Any = None, exclude: Any = None
                          ) -> dict[str, str]:
        """IPython's rich display: ``{"text/html": to_html(), "text/plain": repr}``
        (``include`` and ``exclude``, IPython's filters, are honoured by IPython itself)."""
        return {"text/html": self.to_html(), "text/plain": repr(self)}


def _has_mueller(model: Model) -> bool:
    """Whether ``model`` has a Mueller matrix (one evaluation at a regular direction)."""
    try:
        model.mueller(0.3, 0.3, 0.0)
    except (NotImplementedError, ValueError):  # NoMuellerMatrix; n=None (ArgumentError)
        return False
    return True


def _default_incidence(meas: Measurement | None) -> float:
    """The measured incidence nearest :data:`DEFAULT_INCIDENCE_DEG` (that incidence itself
    without data, or with grazing data only)."""
    target = math.radians(DEFAULT_INCIDENCE_DEG)
    if meas is None or meas.n_samples == 0:
        return target
    inc = [float(t) for t in meas.incidences() if t < 0.5 * math.pi]
    return min(inc, key=lambda t: abs(t - target)) if inc else target


def _incidence(theta_i: Any) -> float:
    """``theta_i`` as a float in ``[0, pi/2)`` (radians); ArgumentError naming it otherwise."""
    if isinstance(theta_i, bool | str | bytes | complex):
        raise ArgumentError("theta_i", "must be an angle in radians in [0, pi/2)",
                            value=theta_i)
    try:
        t = float(theta_i)
    except (TypeError, ValueError, OverflowError):
        raise ArgumentError("theta_i", "must be an angle in radians in [0, pi/2)",
                            value=theta_i) from None
    if not (math.isfinite(t) and 0.0 <= t < 0.5 * math.pi):
        raise ArgumentError("theta_i", "must be an angle in radians in [0, pi/2)", value=t,
                            unit="rad")
    return t


def explore(model_or_fit: Model | FitResult | Measurement | str,
            measurement: Measurement | None = None, *, theta_i: float | None = None,
            channel: int | str | None = None, resolution: int = 61) -> Explorer:
    """The explorer's views of a model, a fit or a measurement, for a notebook.

    Parameters
    ----------
    model_or_fit : Model, FitResult, Measurement or str
        A model (or a model name or spec, ``"tr75"``), a fit (:func:`roughbrdf.fit`,
        :func:`roughbrdf.load_fit`: its channel's fitted model, and its measurement unless
        ``measurement`` is given) or a measurement alone.
    measurement : Measurement, optional
        Data to draw beside the model.
    theta_i : float, optional
        Incidence of the lobe and the maps, radians in ``[0, pi/2)``; default the measured
        incidence nearest 30 deg (30 deg without data).
    channel : int or str, optional
        The measurement's channel (a fit's: the fitted channel, default its first).
    resolution : int
        Grid points per axis of the lobe and the maps (:class:`Explorer`), at least 3.

    Returns
    -------
    Explorer
        Displayed by Jupyter (``_repr_mimebundle_``); :meth:`Explorer.figures` gives the
        Plotly figures, :meth:`Explorer.to_html` the offline HTML.

    Raises
    ------
    roughbrdf.errors.ArgumentError
        ``model_or_fit`` or ``measurement`` of another type, a bad ``theta_i``, an unknown
        channel.

    Examples
    --------
    >>> import numpy as np, roughbrdf as rb
    >>> g = np.radians(np.mgrid[10:61:25, 0:81:10, 0:181:45].reshape(3, -1))
    >>> meas = rb.Measurement(*g, rb.model("lambertian", rho=0.3).brdf(*g))
    >>> res = rb.fit("lambertian", meas, starts=1, progress=False)
    >>> ex = rb.explore(res, resolution=11)
    >>> round(ex.model.params["rho"], 6), round(float(np.degrees(ex.theta_i)), 3)
    (0.3, 35.0)
    """
    from ..fitting.results.result import FitResult
    from ..measurement import Measurement
    from ..models import Model
    from ..models.factory import as_model

    if measurement is not None and not isinstance(measurement, Measurement):
        raise ArgumentError("measurement", "must be a roughbrdf Measurement (rb.read(path)) "
                            f"or None, got a {type(measurement).__name__}")
    fit = model_or_fit if isinstance(model_or_fit, FitResult) else None
    model: Model | None
    label: str | None = None
    if fit is not None:
        c = fit[0 if channel is None else channel]
        model, label = c.model, c.channel
        measurement = fit.measurement if measurement is None else measurement
    elif isinstance(model_or_fit, Measurement):
        if measurement is not None:
            raise ArgumentError("measurement", "give the model first: rb.explore(model, "
                                "measurement), or a measurement alone")
        model, measurement = None, model_or_fit
    elif isinstance(model_or_fit, Model | str):
        model = as_model(model_or_fit)
    else:
        raise ArgumentError("model_or_fit", "must be a Model, a model name, a FitResult or a "
                            f"Measurement, got a {type(model_or_fit).__name__}")
    if measurement is not None and label is None and channel is not None:
        label = measurement.channels[measurement.channel_index(channel)]
    t = _default_incidence(measurement) if theta_i is None else _incidence(theta_i)
    if isinstance(resolution, bool) or not isinstance(resolution, int) or resolution < 3:
        raise ArgumentError("resolution", "must be an integer >= 3 (grid points per axis)",
                            value=resolution)
    return Explorer(model, measurement, t, label, fit, resolution)
