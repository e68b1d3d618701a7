"""The K-correlation (ABC PSD) model with Rayleigh–Rice: :class:`KCorrelation`."""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np

from ...errors import ArgumentError
from ..base import Model, PreparedGeometry, register
from ..parameters import Parameter, nonnegative, positive
from . import psd
from .kernel import kcorr_drive, kcorr_mueller_drive

__all__ = ["KCorrelation", "MAX_WAVELENGTH_UM", "parse_wavelength"]

#: the largest wavelength accepted, µm (far infrared): a larger number is almost surely a
#: wavelength in nm given as µm (630 for 0.63), which would make the BRDF 1.6e11 times too small
MAX_WAVELENGTH_UM = 100.0

_UNITS = {"nm": 1e-3, "um": 1.0, "µm": 1.0, "μm": 1.0, "micron": 1.0, "microns": 1.0,
          "mm": 1e3}
_WAVELENGTH_TEXT = re.compile(r"^\s*([0-9.eE+-]+)\s*([a-zA-Zµμ]+)\s*$")


def parse_wavelength(value: Any) -> float | None:
    """The wavelength in µm from a number (µm) or a string with a unit (``"630nm"``,
    ``"0.63 um"``); ``None`` stays ``None`` (not given).

    Raises :class:`~roughbrdf.errors.ArgumentError` naming ``wavelength`` for anything else,
    for a value that is not finite and > 0, and for one above :data:`MAX_WAVELENGTH_UM`.

    Examples
    --------
    >>> from roughbrdf.models.kcorr import parse_wavelength
    >>> parse_wavelength("630nm"), parse_wavelength(0.6328)
    (0.63, 0.6328)
    """
    if value is None:
        return None
    if isinstance(value, bool):
        raise ArgumentError("wavelength", "must be a number in µm or a string such as "
                            "'630nm'", value=value)
    if isinstance(value, str):
        m = _WAVELENGTH_TEXT.match(value)
        unit = m.group(2).lower() if m else ""
        if not m or unit not in _UNITS:
            raise ArgumentError("wavelength", "a string must be a number and a unit (nm, um, "
                                "µm, mm), e.g. '630nm'", value=value)
        try:
            lam = float(m.group(1)) * _UNITS[unit]
        except ValueError:
            raise ArgumentError("wavelength", "not a number with a unit", value=value) from None
    else:
        try:
            lam = float(value)
        except (TypeError, ValueError):
            raise ArgumentError("wavelength", "must be a number in µm or a string such as "
                                "'630nm'", value=value) from None
    if not (math.isfinite(lam) and lam > 0):
        raise ArgumentError("wavelength", "must be finite and > 0 (µm)", value=value)
    if lam > MAX_WAVELENGTH_UM:
        raise ArgumentError("wavelength", f"is in micrometres and must be at most "
                            f"{MAX_WAVELENGTH_UM:g} µm; a value in nm? (630 nm is 0.63, or "
                            f"give '630nm')", value=value)
    # 12 significant digits: "630nm" * 1e-3 gives 0.63 as written, not 0.6300000000000001
    return float(f"{lam:.12g}")


@register
class KCorrelation(Model):
    """K-correlation (ABC PSD) surface with Rayleigh–Rice scatter (smooth-surface limit).

    ``f_r = (16 pi^2/lambda^4) cos theta_i cos theta_r Q S_2(f)``, ``f = |beta - beta_0|/lambda``,
    ``S_2(f) = A / (1 + (B f)^2)^(C/2)`` the 2-D PSD (SCATMECH's ``ABC_PSD_Function``) and ``Q``
    the Rayleigh–Rice polarization factor of the complex index ``n + i k``
    (:mod:`roughbrdf.models.kcorr.kernel`; NIST SCATMECH ``Microroughness_BRDF_Model``; Stover,
    *Optical Scattering*; Church & Takacs). Valid where the surface is
    smooth, ``4 pi sigma cos theta_i / lambda << 1``; no specular peak is included (the model
    is the diffuse part only, as every stray-light scatter model).

    Units: ``A`` in µm⁴, ``B`` in µm, ``C`` dimensionless; the option ``wavelength`` in µm (or
    a string such as ``"630nm"``), which evaluation needs: without it every evaluation raises
    :class:`~roughbrdf.errors.ArgumentError` naming ``wavelength``. Metrology terms:
    :meth:`sigma_rms`, :meth:`rms_slope`, :attr:`correlation_length`, :meth:`metrology`.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> from roughbrdf.models import kcorr
    >>> m = rb.model("k-correlation", A=1e-5, B=5.0, C=3.0, n=1.5, k=0.0, wavelength="633nm")
    >>> f = m.brdf(0.0, 0.2, 0.0, polarization="s")
    >>> bool(0.0 < f < 1.0)
    True
    >>> round(m.sigma_rms() * 1e3, 3), round(m.correlation_length, 4)   # nm, µm
    (1.585, 0.7958)
    """

    name = "k-correlation"
    aliases = ("kcorr", "abc", "k-correlation-rayleigh-rice")
    short = "kcorr"
    reference = ("Rayleigh-Rice (Rice 1951; Church & Zavada 1975; Stover, Optical Scattering) "
                 "with the ABC/K-correlation PSD (Church & Takacs); NIST SCATMECH "
                 "Microroughness_BRDF_Model + ABC_PSD_Function")
    PARAMETERS = (
        positive("A", 1e-5, (1e-14, 1e3), "um^4", "ABC PSD amplitude S_2(0) (2-D PSD)"),
        positive("B", 5.0, (1e-3, 1e5), "um", "ABC PSD knee: 2 pi x correlation length"),
        Parameter("C", 3.0, (0.5, 8.0), "1", "ABC PSD exponent (total sigma finite for C > 2)",
                  (0.0, True, 50.0, True)),
        positive("n", 1.5, (0.2, 10.0), "1", "substrate refractive index (n + ik)"),
        nonnegative("k", 0.0, (0.0, 15.0), "1", "substrate extinction index (n + ik)"),
    )
    OPTIONS = {"wavelength": None}
    grazing_incidence = True
    _drive = kcorr_drive

    def _check_options(self, options: dict[str, Any]) -> dict[str, Any]:
        return {"wavelength": parse_wavelength(options["wavelength"])}

    @property
    def wavelength(self) -> float:
        """The wavelength in µm; raises :class:`~roughbrdf.errors.ArgumentError` naming
        ``wavelength`` when the model was built without one."""
        lam = self._options["wavelength"]
        if lam is None:
            raise ArgumentError(
                "wavelength", "the k-correlation (Rayleigh-Rice) model needs the wavelength: "
                "build it with wavelength=0.6328 (µm) or wavelength='632.8nm' (a fit takes it "
                "from the measurement's channel names, e.g. '630nm', or --wavelength)",
                value=None)
        return float(lam)

    def _pack(self) -> tuple:
        v = self._values
        return (v["A"], v["B"], v["C"], v["n"], v["k"], self.wavelength)

    def _mueller(self, g: PreparedGeometry, basis: int, term: str | None) -> np.ndarray:
        return self._mueller_drive(kcorr_mueller_drive, g, self._pack(), basis, term)

    # -- metrology ------------------------------------------------------------------------------
    def sigma_rms(self, f_min: float = 0.0, f_max: float = math.inf) -> float:
        """RMS roughness in µm over ``[f_min, f_max]`` (cycles/µm; the total by default, which
        needs ``C > 2``): :func:`roughbrdf.models.kcorr.sigma_rms`."""
        v = self._floats()
        return psd.sigma_rms(v["A"], v["B"], v["C"], f_min, f_max)

    def rms_slope(self, f_min: float = 0.0, f_max: float = math.inf) -> float:
        """RMS slope over ``[f_min, f_max]`` (the total needs ``C > 4``)."""
        v = self._floats()
        return psd.rms_slope(v["A"], v["B"], v["C"], f_min, f_max)

    @property
    def correlation_length(self) -> float:
        """``B / (2 pi)`` in µm."""
        return psd.correlation_length(self._floats()["B"])

    def band(self, theta_i: Any, theta_r: Any, phi: Any) -> tuple[float, float]:
        """``(f_min, f_max)`` (cycles/µm) the given geometries (radians) sample at this
        model's wavelength: the band of a measurement, for :meth:`sigma_rms`."""
        f = psd.spatial_frequency(theta_i, theta_r, phi, self.wavelength)
        return float(np.min(f)), float(np.max(f))

    def metrology(self, f_min: float = 0.0, f_max: float = math.inf) -> dict[str, float | None]:
        """The parameters in metrology terms: ``sigma_rms`` (µm, over the band; ``None`` where
        it diverges), ``correlation_length`` (µm), ``rms_slope`` (``None`` where it diverges),
        ``C`` and the profile (1-D) PSD's ``A_1d`` (µm³, ``None`` for ``C <= 1``)."""
        v = self._floats()
        out: dict[str, float | None] = {"correlation_length": self.correlation_length,
                                        "C": v["C"]}
        for key, fn in (("sigma_rms", self.sigma_rms), ("rms_slope", self.rms_slope)):
            try:
                out[key] = fn(f_min, f_max)
            except ArgumentError:
                out[key] = None
        out["A_1d"] = psd.abc_1d_from_2d(v["A"], v["B"], v["C"])[0] if v["C"] > 1 else None
        return out

    def describe(self) -> str:
        """The base description plus the parameters in metrology terms (total band)."""
        met = self.metrology()

        def show(key: str, unit: str, why: str) -> str:
            v = met[key]
            return f"{v:.6g} {unit} (total)" if v is not None else f"diverges ({why})"

        return "\n".join([
            super().describe(),
            f"  metrology: sigma_rms = {show('sigma_rms', 'um', 'C <= 2')}, "
            f"correlation length = {met['correlation_length']:.6g} um (B/2pi), "
            f"rms slope = {show('rms_slope', 'rad', 'C <= 4')}"])
