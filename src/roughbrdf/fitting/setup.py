"""What :func:`roughbrdf.fit` is asked to do, checked before any work (``docs/fitting.md``).

The model (an instance or a registered name), the measurement, the channels, the free parameters
and their bounds (:class:`FreeParameters`), and the data scale ``K`` (free for relative data,
fixed otherwise: :func:`data_scale`). Every bad option raises ``ValueError`` here, before any
fit runs.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..measurement import Measurement
from ..models import Model
from ..quantity import Quantity
from .data import ChannelData, where
from .objective import ObjectiveSpec

__all__ = ["FreeParameters", "as_model", "channel_indices", "check_enough_data", "data_scale",
           "model_label"]


def as_model(model: Model | str) -> Model:
    """``model`` itself, or the registered model of that name (sums ``"a+b"`` allowed)."""
    if isinstance(model, str):
        from ..models import model as make_model

        model = make_model(model)
    if not isinstance(model, Model):
        raise TypeError(f"model must be a roughbrdf Model or a model name, got {type(model)}")
    return model


def model_label(m: Model) -> str:
    """``"a+b"`` for a sum, else the model's name.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> model_label(rb.model("trowbridge-reitz-1975") + rb.model("lambertian"))
    'trowbridge-reitz-1975+lambertian'
    """
    comps = getattr(m, "components", None)
    return "+".join(c.name for c in comps) if comps else m.name


@dataclass(frozen=True)
class FreeParameters:
    """The fitted parameters: names, bounds and starting values (the model's values).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> p = FreeParameters.of(rb.model("ts67", n=None, k=None), fix=["c"],
    ...                       bounds={"g": (0.1, 10.0)})
    >>> p.names, p.lower.tolist(), p.upper.tolist()
    (('g', 'rho_d'), [0.1, 0.0], [10.0, 1.0])
    """

    names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    start: np.ndarray

    @classmethod
    def of(cls, model: Model, fix: Iterable[str] | str = (),
           bounds: Mapping[str, Sequence[float]] | None = None) -> FreeParameters:
        """Every parameter of ``model`` that is not in ``fix`` nor switched off (value None),
        with ``bounds`` overriding the model's own."""
        names = model.param_names
        fixed = [fix] if isinstance(fix, str) else list(fix)
        bounds = dict(bounds or {})
        for nm in [*fixed, *bounds]:
            if nm not in names:
                model.with_values([nm], [0.0])  # raises the registry's "unknown parameter" error
        specs = {p.name: p for p in model.parameters}
        free = [n for n in names if n not in fixed and specs[n].value is not None]
        if not free:
            off = [n for n in names if specs[n].value is None]
            extra = f" ({', '.join(off)} switched off by None)" if off else ""
            raise ValueError(f"every parameter of {model_label(model)} is fixed{extra}: nothing "
                             f"to fit; free at least one of {names}")
        lo, hi, x0 = (np.empty(len(free)) for _ in range(3))
        for j, nm in enumerate(free):
            b = bounds.get(nm, specs[nm].bounds)
            lo[j], hi[j] = float(b[0]), float(b[1])
            if not lo[j] < hi[j]:
                raise ValueError(f"bounds of {nm!r} must satisfy low < high, got {tuple(b)}")
            x0[j] = float(specs[nm].value)  # type: ignore[arg-type]  # not None: free
            if not lo[j] <= x0[j] <= hi[j]:
                raise ValueError(f"starting value {nm} = {x0[j]:g} is outside its bounds "
                                 f"[{lo[j]:g}, {hi[j]:g}]; pass bounds={{{nm!r}: (low, high)}} or "
                                 f"another starting value")
        return cls(tuple(free), lo, hi, x0)

    def spec(self, model: Model, *, loss: str, quantity: Quantity | str, free_scale: bool,
             fixed_scale: float) -> ObjectiveSpec:
        """The :class:`~roughbrdf.fitting.objective.ObjectiveSpec` of these parameters."""
        return ObjectiveSpec(model, self.names, self.lower, self.upper, loss=loss,
                             quantity=quantity, free_scale=free_scale, fixed_scale=fixed_scale)


def data_scale(meas: Measurement, free_scale: bool | None, scale: float | None
               ) -> tuple[bool, float]:
    """``(free_scale, fixed_scale)``: a known ``scale`` is fixed; otherwise ``K`` is free for
    relative data unless ``free_scale`` says otherwise."""
    if scale is not None:
        fixed = float(scale)
        if not (math.isfinite(fixed) and fixed > 0):
            raise ValueError(f"scale must be finite and > 0, got {scale!r}")
        if free_scale:
            raise ValueError("give either scale= (a known data scale) or free_scale=True")
        return False, fixed
    if free_scale is None:
        free_scale = meas.quantity == "relative"
    return bool(free_scale), 1.0


def channel_indices(meas: Measurement, channel: Any) -> list[int]:
    """Positions of the channels to fit: all (None), one, or a list of labels/positions."""
    if not isinstance(meas, Measurement):
        raise TypeError(f"measurement must be a roughbrdf Measurement, got {type(meas)}")
    if channel is None:
        chans = list(range(len(meas.channels)))
    elif isinstance(channel, list | tuple):
        chans = [meas.channel_index(c) for c in channel]
    else:
        chans = [meas.channel_index(channel)]
    if not chans:
        raise ValueError("no channel to fit")
    return chans


def check_enough_data(meas: Measurement, data: Sequence[ChannelData], n_varys: int) -> None:
    """Raise unless every channel has more samples than fitted parameters."""
    for d in data:
        if d.n <= n_varys:
            raise ValueError(f"{where(meas, d.label)}: {d.n} samples for {n_varys} fitted "
                             f"parameters; need more data than parameters")
