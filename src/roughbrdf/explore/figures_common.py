"""Shared parts of the explorer's Plotly figures (:mod:`roughbrdf.explore.figures`).

Argument checks (each bad input an :class:`~roughbrdf.errors.ArgumentError` naming the
argument), the labels and titles every figure uses (degrees on angle axes, units on every value
axis, the model's :func:`~roughbrdf.models.model_label`, the incidence and the channel), the
projected-disk grid, and the measurement side: one channel's data, the model quantity they are
compared with and, for relative data, the closed-form scale ``K`` (TR75 Eq. 34,
:func:`roughbrdf.quantity.relative_scale`), as :mod:`roughbrdf.plot` compares them.

Every drawn trace that stands for values carries them in ``customdata`` with the names of its
columns in ``meta["fields"]`` (e.g. ``theta_r_deg, phi_deg, value``): the hover text shows them
and :func:`roughbrdf.explore.figures.figure_values` reads them back.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ArgumentError
from ..geometry import check_zenith
from ..measurement import Measurement
from ..models import Model, model_label
from ..quantity import Quantity, relative_scale

__all__ = ["ChannelData", "channel_data", "check_incidence", "check_model", "check_resolution",
           "colors", "custom", "deg", "disk_axis_titles", "disk_grid", "disk_position",
           "disk_rings", "finite_or_nan", "incidence_list", "log_ticks", "measured_incidences",
           "optional_model",
           "quantity_label", "title_text", "SR", "HOVER_ANGLES"]

#: the BRDF's unit as the figures write it
SR = "sr⁻¹"
#: hover lines of the angles every value trace carries first in its customdata
HOVER_ANGLES = "θr = %{customdata[0]:.2f}°<br>φ = %{customdata[1]:.2f}°"

_QUANTITY_LABELS = {
    Quantity.BRDF: f"BRDF f_r [{SR}]",
    Quantity.BRDF_COS: f"BRDF·cos θr [{SR}]",
    Quantity.BRIDF: f"BRIDF f_r·cos θr [{SR}]",
    Quantity.RELATIVE: "relative value [1] (data scale unknown)",
}


def quantity_label(quantity: Quantity | str) -> str:
    """The axis label of a quantity, with its unit (``"BRDF f_r [sr⁻¹]"``)."""
    return _QUANTITY_LABELS[Quantity.parse(quantity)]


def deg(x: ArrayLike) -> np.ndarray:
    """Radians to degrees as a float array."""
    return np.degrees(np.asarray(x, dtype=float))


def optional_model(model: Any, argument: str = "model") -> Model | None:
    """``None``, or :func:`check_model` of ``model``."""
    return None if model is None else check_model(model, argument)


def check_model(model: Any, argument: str = "model") -> Model:
    """``model`` if it is a roughbrdf :class:`~roughbrdf.models.Model`, else an
    :class:`ArgumentError` naming ``argument``."""
    if not isinstance(model, Model):
        raise ArgumentError(argument, "must be a roughbrdf Model (rb.model(...)), got "
                            f"{type(model).__name__}")
    return model


def check_incidence(theta_i: Any, argument: str = "theta_i") -> float:
    """One incidence angle in ``[0, pi/2)`` radians, or an :class:`ArgumentError` naming it.

    Examples
    --------
    >>> check_incidence(0.5)
    0.5
    >>> check_incidence(2.0)
    Traceback (most recent call last):
    ...
    roughbrdf.errors.ArgumentError: theta_i = 2.0 rad: must be in [0, pi/2) rad, i.e. [0, 90) deg
    """
    arr = check_zenith(theta_i, argument, open_upper=True)
    if arr.size != 1:
        raise ArgumentError(argument, "must be one incidence angle (radians)", value=theta_i)
    return float(arr.reshape(-1)[0])


def check_resolution(n: Any, argument: str = "resolution", least: int = 3) -> int:
    """An integer of at least ``least`` (grid points), or an :class:`ArgumentError`."""
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < least:
        raise ArgumentError(argument, f"must be an integer >= {least}", value=n)
    return int(n)


def title_text(what: str, model: Model | None = None, *, label: str | None = None,
               theta_i: float | None = None, channel: str | None = None,
               sample: str | None = None) -> str:
    """A figure title naming the model (its label), the data, the incidence and the channel.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> title_text("lobe", rb.model("lambertian"), theta_i=math.radians(30), channel="465nm")
    'lambertian: lobe, θi = 30° [465nm]'
    """
    who = [label or (model_label(model) if model is not None else "")]
    if sample:
        who.append(f"data {sample}")
    head = " vs ".join(w for w in who if w)
    text = f"{head}: {what}" if head else what
    if theta_i is not None:
        text += f", θi = {math.degrees(theta_i):.4g}°"
    if channel is not None:
        text += f" [{channel}]"
    return text


def colors(n: int) -> list[str]:
    """``n`` distinguishable colours, one per incidence (Viridis, dark to light)."""
    from plotly.colors import sample_colorscale

    return list(sample_colorscale("Viridis", [0.1] if n <= 1 else
                                  list(np.linspace(0.0, 0.85, n))))


def custom(fields: Sequence[str], *columns: ArrayLike) -> tuple[np.ndarray, dict[str, Any]]:
    """``(customdata, meta)`` of a trace: the columns stacked on a last axis and their names."""
    arrays = np.broadcast_arrays(*[np.asarray(c, dtype=float) for c in columns])
    return np.stack(arrays, axis=-1), {"fields": list(fields)}


def log_ticks(lo: float, hi: float) -> dict[str, Any]:
    """Colour-bar ticks for colours that are ``log10`` of a value, written as the values:
    1, 2, 5 times the powers of ten in ``[lo, hi]`` (decades), or only the powers of ten when
    the range spans more than 3 decades.

    Examples
    --------
    >>> log_ticks(-1.2, 0.5)["ticktext"]
    ['0.1', '0.2', '0.5', '1', '2']
    """
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi < lo:
        return {}
    steps = (1.0,) if hi - lo > 3 else (1.0, 2.0, 5.0)
    vals = [10.0 ** k * m for k in range(math.floor(lo), math.ceil(hi) + 1) for m in steps]
    vals = [v for v in vals if lo <= math.log10(v) <= hi]
    return {"tickvals": [math.log10(v) for v in vals], "ticktext": [f"{v:.3g}" for v in vals]}


def disk_grid(n: int, coords: str = "cosines") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The 1-D axis of a projected-disk map and the ``(theta_r, phi)`` grids (radians, NaN
    outside the disk), shape ``(n, n)``, row = y.

    ``coords="cosines"``: ``x = sin θr cos φ``, ``y = sin θr sin φ`` (direction cosines, the
    projected disk); ``"degrees"``: ``x = θr cos φ``, ``y = θr sin φ`` in degrees (polar,
    equidistant in ``θr``). ``φ = 0`` (forward, specular side) to the right.
    """
    if coords not in ("cosines", "degrees"):
        raise ArgumentError("coords", "must be 'cosines' or 'degrees'", value=coords)
    edge = 1.0 if coords == "cosines" else 90.0
    axis = np.linspace(-edge, edge, n)
    X, Y = np.meshgrid(axis, axis)
    r = np.hypot(X, Y) / edge
    inside = r <= 1.0
    radial = np.where(inside, np.minimum(r, 1.0), np.nan)
    tr = np.arcsin(radial) if coords == "cosines" else radial * (math.pi / 2)
    return axis, tr, np.where(inside, np.arctan2(Y, X), np.nan)


def disk_position(theta_r: ArrayLike, phi: ArrayLike, coords: str) -> tuple[np.ndarray, ...]:
    """``(x, y)`` of directions on a :func:`disk_grid` map."""
    tr, ph = np.asarray(theta_r, dtype=float), np.asarray(phi, dtype=float)
    r = np.sin(tr) if coords == "cosines" else np.degrees(tr)
    return r * np.cos(ph), r * np.sin(ph)


def disk_rings(coords: str, xref: str, yref: str) -> list[dict[str, Any]]:
    """Layout shapes: circles at ``θr`` = 30, 60, 90° and the plane of incidence."""
    shapes = []
    for d in (30, 60, 90):
        r = math.sin(math.radians(d)) if coords == "cosines" else float(d)
        shapes.append({"type": "circle", "xref": xref, "yref": yref, "x0": -r, "x1": r,
                       "y0": -r, "y1": r, "line": {"color": "#999", "width": 1 if d < 90 else 2}})
    edge = 1.0 if coords == "cosines" else 90.0
    shapes.append({"type": "line", "xref": xref, "yref": yref, "x0": -edge, "x1": edge,
                   "y0": 0, "y1": 0, "line": {"color": "#999", "width": 0.5}})
    return shapes


def disk_axis_titles(coords: str) -> tuple[str, str]:
    """The axis titles of a projected-disk map (angles in degrees where they are angles)."""
    if coords == "cosines":
        return ("α = sin θr cos φ [1] (forward, φ = 0° →)", "β = sin θr sin φ [1]")
    return ("θr cos φ [deg] (forward, φ = 0° →)", "θr sin φ [deg]")


@dataclass(frozen=True)
class ChannelData:
    """One channel of a measurement, ready to draw against a model.

    Attributes
    ----------
    meas : Measurement
        The samples (all channels; ``values[:, index]`` is the channel).
    index : int
        The channel's column.
    channel : str
        Its label.
    quantity : Quantity
        What the data hold (the measurement's quantity).
    model_quantity : Quantity
        What the model is compared as (``brdf`` or ``bridf``; ``Quantity.compared_with``).
    k : float
        Data scale: the model is drawn divided by ``k`` (1 for absolute data; the closed-form
        ``K`` with ``K data ~ model`` for relative data, TR75 Eq. 34).
    """

    meas: Measurement
    index: int
    channel: str
    quantity: Quantity
    model_quantity: Quantity
    k: float

    @property
    def values(self) -> np.ndarray:
        """The channel's values (unit of :attr:`quantity`)."""
        return self.meas.values[:, self.index]

    def model_at(self, model: Model, mask: np.ndarray | None = None) -> np.ndarray:
        """The model at the samples (all, or ``mask``), as compared: divided by ``k``."""
        m = self.meas if mask is None else self.meas.subset(mask)
        with np.errstate(invalid="ignore", over="ignore"):
            out = np.asarray(model.evaluate(m.theta_i, m.theta_r, m.phi,
                                            quantity=self.model_quantity,
                                            polarization=m.polarization), dtype=float)
        return out / self.k


def channel_data(measurement: Any, channel: int | str | None, model: Model | None
                 ) -> ChannelData:
    """One channel of ``measurement`` (the first when ``channel`` is None) with the quantity
    and scale its comparison with ``model`` uses.

    Raises :class:`ArgumentError` naming ``measurement`` (not a Measurement) or ``channel``
    (unknown, or for Mueller data an element other than ``m00``, the only BRDF among them).
    """
    if not isinstance(measurement, Measurement):
        raise ArgumentError("measurement", "must be a roughbrdf Measurement (rb.read(...)), "
                            f"got {type(measurement).__name__}")
    try:
        j = measurement.channel_index(0 if channel is None else channel)
    except (ValueError, TypeError) as exc:
        raise ArgumentError("channel", f"{exc}", value=channel) from None
    label = measurement.channels[j]
    if measurement.is_mueller and label != "m00":
        raise ArgumentError("channel", "of Mueller data only 'm00' is a BRDF to draw here "
                            "(the elements are in mueller_maps)", value=channel)
    q = Quantity.parse(measurement.quantity)
    mq = q.compared_with(measurement.meta.get("relative_to"))
    k = 1.0
    if model is not None and not q.absolute:
        data = measurement.values[:, j]
        with np.errstate(invalid="ignore", over="ignore"):
            mod = np.asarray(model.evaluate(measurement.theta_i, measurement.theta_r,
                                            measurement.phi, quantity=mq,
                                            polarization=measurement.polarization))
        k = float(relative_scale(data, mod))
    return ChannelData(measurement, j, label, q, mq, k)


def finite_or_nan(values: ArrayLike) -> np.ndarray:
    """Float array with every non-finite value NaN (drawn as a gap: a model that diverges
    at the horizon, TR75 without shadowing, has no value to draw there)."""
    v = np.array(values, dtype=float)
    v[~np.isfinite(v)] = np.nan
    return v


def measured_incidences(meas: Measurement) -> list[float]:
    """The distinct incidences of ``meas`` (:meth:`Measurement.incidences`), each as the
    exact angle of a sample (``incidences()`` rounds to 1e-6 rad; a model drawn at the rounded
    angle would differ from the model at the samples)."""
    ti = meas.theta_i
    return [float(ti[np.argmin(np.abs(ti - t))]) for t in meas.incidences()]


def incidence_list(values: Any, argument: str) -> list[float]:
    """Incidence angles (radians), each checked to lie in ``[0, pi/2)``."""
    arr = check_zenith(values, argument, open_upper=True)
    return [float(t) for t in np.atleast_1d(arr).reshape(-1)]
