"""The wavelength of each channel, for models that need one (K-correlation / Rayleigh–Rice).

``docs/straylight.md``. A model with a ``wavelength`` option left unset (``None``) cannot be
evaluated; a fit gives each channel's model the wavelength of that channel, from, in order:

1. the fit's ``wavelength=`` option (µm, or a string with a unit such as ``"630nm"``;
   ``--wavelength`` at the command line): every channel;
2. the measurement's ``meta["wavelengths_nm"]`` (set by the readers from the file: the ASTM
   header's ``NNNnm`` channel names, LightTools' wavelength blocks);
3. the channel's label itself when it reads as a wavelength (``"630nm"``, ``"0.63um"``).

Without any of them the fit is refused with an :class:`~roughbrdf.errors.ArgumentError`
naming ``wavelength``. Channels of different wavelengths are fitted one by one, each with its
model (:func:`roughbrdf.fitting.kinds.channels.fit_model`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ...errors import ArgumentError
from ...models.base import SumModel, components
from ...models.kcorr import parse_wavelength

if TYPE_CHECKING:
    from ...measurement import Measurement
    from ...models import Model

__all__ = ["channel_wavelength", "needs_wavelength", "with_wavelength"]


def needs_wavelength(model: Model) -> bool:
    """Whether ``model`` (or a component of a sum) has a ``wavelength`` option left unset."""
    return any("wavelength" in c.options and c.options["wavelength"] is None
               for c in components(model))


def with_wavelength(model: Model, wavelength_um: float) -> Model:
    """``model`` with every unset ``wavelength`` option set to ``wavelength_um`` (µm)."""
    parts = []
    for c in components(model):
        if "wavelength" in c.options and c.options["wavelength"] is None:
            c = type(c)(**{k: v for k, v in c.params.items() if v is not None},
                        **{**dict(c.options), "wavelength": wavelength_um})
        parts.append(c)
    return parts[0] if len(parts) == 1 and not isinstance(model, SumModel) \
        else SumModel(parts)


def channel_wavelength(measurement: Measurement, channel: int, given: Any = None) -> float:
    """The wavelength (µm) of channel ``channel`` (its index) by the rules of the module notes;
    :class:`~roughbrdf.errors.ArgumentError` naming ``wavelength`` when there is none.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> m = rb.Measurement([0.1], [0.2], [0.0], [[0.1, 0.2]], channels=["465nm", "630nm"])
    >>> channel_wavelength(m, 1), channel_wavelength(m, 1, given="1.064um")
    (0.63, 1.064)
    """
    if given is not None:
        lam = parse_wavelength(given)
        assert lam is not None  # given is not None
        return lam
    from_file = (measurement.meta or {}).get("wavelengths_nm")
    if from_file and channel < len(from_file) and from_file[channel]:
        return parse_wavelength(f"{float(from_file[channel])}nm") or 0.0
    label = str(measurement.channels[channel])
    try:
        lam = parse_wavelength(label)
    except ArgumentError:
        lam = None
    if lam is None:
        raise ArgumentError("wavelength", f"the model needs the wavelength of channel "
                            f"{label!r}, which neither the file nor the channel's name gives: "
                            "pass wavelength= (µm, or e.g. '630nm'; command line: "
                            "--wavelength)", value=None)
    return lam
