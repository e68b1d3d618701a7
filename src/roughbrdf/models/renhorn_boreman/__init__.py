"""Renhorn & Boreman (2008): analytical 14-parameter rough-surface BRDF (surface, bulk, retro).

I. G. E. Renhorn and G. D. Boreman, "Analytical fitting model for rough-surface BRDF",
Opt. Express 16(17), 12892-12898 (2008), doi:10.1364/OE.16.012892. docs/models.md §4 (reconstructed
from the 20 flattened equations of seed ``004_...``; the readings are listed there).

Recommended reading, in the common frame (``alpha = sin theta_s cos phi``,
``beta = sin theta_s sin phi``, ``alpha0 = sin theta_i``, ``cs = cos theta_s``,
``ci = cos theta_i``)::

    BRDF  = BRDF_surface + BRDF_bulk + BRDF_retro                                    (Eq. 18)
    BRDF_surface = sigma_s N(alpha0, rho) Vm / D(alpha - alpha0; rho, w, n)           (Eq. 15)
    D(x; rho, w, n) = x^2 + beta^2 + (ci + cs)^2/4 V(alpha0, w, n) V(sin theta_s, w, n) rho^2
    N(alpha0, rho) = 1 / (pi ln{[1 - alpha0^2 + rho^2 + sqrt((1 - alpha0^2 + rho^2)^2
                                   + 4 alpha0^2 rho^2)] / (2 rho^2)})               (Eqs. 6, 8)
    V(chi, w, n) = Q(1 + n, (1 + n) chi^2/w^2)                            (Eq. 10, shadowing.V)
    Vm = Eq. 13 with zeta = arcsin(alpha), zeta0 = theta_i                  (shadowing.Vm)
    sigma_s = sqrt(R(alpha0) R(sin theta_s)),  R = Fresnel of n_eff + i k_eff (Eqs. 16-17, 19)
    BRDF_bulk  = (1 - sigma_s) bulk / pi                                              (Eq. 19)
    BRDF_retro = (1 - sigma_s) retro N(alpha0, rho_r) / D(alpha + alpha0; rho_r, w_r, n_r)  (20)

With ``retro_shadowing="amplitude"`` (an alternative reading of the speculative w_r, n_r) the
retro pair multiplies the strength instead of the width::

    BRDF_retro = (1 - sigma_s) retro N(alpha0, rho_r) V(alpha0, w_r, n_r) V(sin theta_s, w_r, n_r)
                 / [(alpha + alpha0)^2 + beta^2 + (ci + cs)^2/4 rho_r^2]

Layout (the kernels, their speeds and how they agree are described in ``kernel``):

* :mod:`~roughbrdf.models.renhorn_boreman.kernel` -- the compiled kernel: packed parameters,
  scalar parts (Eqs. 6/8 N, 15, 19, 20), the fast, tabulated and general drivers;
* :mod:`~roughbrdf.models.renhorn_boreman.normalization` -- ``normalization="numeric"``: the
  1-D quadrature of the lobe (:func:`lobe_integral`) and
  :class:`~roughbrdf.models.renhorn_boreman.normalization.NumericNormalization`, which owns
  its caches;
* :mod:`~roughbrdf.models.renhorn_boreman.model` -- :class:`RenhornBoreman2008`, its
  parameters and options (the readings).
"""

from __future__ import annotations

from .kernel import NORM_CODES as NORM_CODES  # importable here as before, not in __all__
from .kernel import POL_WEIGHT as POL_WEIGHT
from .kernel import RETRO_CODES as RETRO_CODES
from .kernel import TERM_CODES as TERM_CODES
from .kernel import WEIGHT_CODES as WEIGHT_CODES
from .kernel import ZETA_CODES as ZETA_CODES
from .kernel import rb08_norm
from .model import OPTION_VALUES as OPTION_VALUES
from .model import RenhornBoreman2008
from .normalization import lobe_integral

__all__ = ["RenhornBoreman2008", "rb08_norm", "lobe_integral"]
