"""K-correlation (ABC PSD) surface scatter with Rayleigh–Rice: model, PSD metrology, TIS.

The stray-light codes' "K-correlation" model (FRED; Dittman, *Proc. SPIE* 6291 (2006)) is the
first-order vector perturbation (Rayleigh–Rice) BRDF of a smooth rough interface with the
ABC power spectral density of Church & Takacs, exactly NIST SCATMECH's
``Microroughness_BRDF_Model`` with its ``ABC_PSD_Function`` (``docs/straylight.md``,
"K-correlation"):

* :mod:`.kernel`: the compiled Rayleigh–Rice Jones elements, the scalar kernel and drivers;
* :mod:`.model`: :class:`KCorrelation` (registered as ``"k-correlation"``, aliases ``"kcorr"``,
  ``"abc"``), the wavelength option (µm);
* :mod:`.psd`: the PSD, its normalization, rms roughness over a band of spatial frequencies,
  rms slope, correlation length, 1-D/2-D conversions and the Bragg frequency of a geometry;
* :mod:`.tis`: the total integrated scatter by quadrature and its small-roughness closed form.
"""

from .model import MAX_WAVELENGTH_UM, KCorrelation, parse_wavelength
from .psd import (
    abc_1d_from_2d,
    abc_2d_from_1d,
    abc_from_metrology,
    abc_psd,
    correlation_length,
    rms_slope,
    sigma_rms,
    spatial_frequency,
)
from .tis import tis, tis_smooth_limit

__all__ = ["KCorrelation", "MAX_WAVELENGTH_UM", "abc_1d_from_2d", "abc_2d_from_1d",
           "abc_from_metrology", "abc_psd", "correlation_length", "parse_wavelength",
           "rms_slope", "sigma_rms", "spatial_frequency", "tis", "tis_smooth_limit"]
