"""Mitsuba 3 export: a model or a fit as a scene-description dict and an XML ``<bsdf>``.

:func:`to_mitsuba` returns the dict :func:`mitsuba.load_dict` takes, :func:`to_mitsuba_xml` the
``<bsdf>`` element of a scene file, and :func:`export_mitsuba` both with a record of how each
term was mapped (:class:`MitsubaExport`). Targets Mitsuba 3.9's RGB variants (``scalar_rgb``,
``llvm_ad_rgb``, ...); spectral parameters are constant over wavelength. Exports are for
**unpolarized** light: the models are evaluated unpolarized, and Mitsuba's unpolarized
variants never see the polarization of TR75 Eq. 24.

Mappings (Mitsuba's ``eval()`` returns ``f_r cos(theta_o)``; "exact" means the same formula,
checked with Mitsuba itself to 1e-4 relative at random geometries in
``tests/export/test_export_mitsuba.py``; Mitsuba's float32 arithmetic limits the agreement to a few
1e-6, 3e-5 next to the critical angle of a dielectric with ``n < 1``)

================================  ==========================================================
roughbrdf                         Mitsuba 3
================================  ==========================================================
``lambertian`` ``rho``            ``diffuse``, ``reflectance = rho``
``microfacet`` GGX/Beckmann,      ``roughconductor``, ``distribution`` ``ggx``/``beckmann``,
``smith-separable``, ``n``, ``k``, ``alpha``, ``eta = n``, ``k``, ``specular_reflectance = ks``
``ks`` (``n=None``: F = 1)        (``eta = 0``, ``k = 1``: Mitsuba's ``material="none"``, F = 1)
``coated``, ``smith-separable``,  ``roughplastic`` (``int_ior = n``, ``ext_ior = 1``,
``shadow_diffuse=False``,         ``diffuse_reflectance = rho``, ``nonlinear = true``,
``interface="rough"``, one lobe   ``specular_reflectance = 1``, ``alpha``)
``coated`` as above, 2-3 lobes    one ``roughplastic`` per lobe, blended by the lobe weights:
                                  *approximate* (the model's substrate sees the lobes' mixed
                                  interface, each ``roughplastic`` its own lobe's)
``coated`` ``weights="free"``     ``roughplastic`` with ``specular_reflectance = ks``; lobes 2
                                  and 3 ``roughconductor`` lobes (``eta = n``, ``k = 0``,
                                  ``specular_reflectance = ks_j``) blended in
``trowbridge-reitz-1975``         ``roughconductor`` GGX with ``alpha = e`` + ``diffuse``
                                  ``rho_L``: *approximate*, see below
sums ``m1 + m2 + ...``            nested ``blendbsdf`` (below)
``oren-nayar`` with ``sigma = 0`` ``diffuse``
================================  ==========================================================

* **Beckmann.** Mitsuba's Smith ``G1`` for Beckmann is a rational approximation (within
  0.35 %, 1 above ``a = 1.6``) of the exact ``G1`` the library uses. The mapping is exact to
  :data:`EXACT` where that makes no difference: ``alpha`` up to about 0.07 for
  ``theta <= 80 deg``. Beyond, the export is *approximate* and reports its deviation (0.16 %
  at ``alpha = 0.08``, about 0.6 % from 0.2 on).
* **TR75** has no shadowing (or TS67's V-groove with ``shadowing="v-groove"``), while
  ``roughconductor`` always applies the separable Smith ``G`` of its distribution. The
  export keeps TR75's distribution (GGX, ``alpha = e``), Fresnel factor and Lambertian part
  and so adds Smith's ``G``; it is *approximate*, with the deviation that ``G`` makes (large
  near grazing: ``G`` is 0.45 at ``theta_i = theta_r = 80 deg`` for ``e = 0.3``). With
  ``fit=True`` the GGX lobe and the diffuse part are fitted instead (*fitted*).
* **Sums.** ``blendbsdf`` gives ``(1 - w) bsdf_0 + w bsdf_1``. A sum of ``N`` parts becomes the
  chain ``blend(w_1, N part_1, blend(w_2, N part_2, ...))`` with ``w_j = (N - j)/(N - j + 1)``:
  every part is scaled by ``N`` through its linear reflectance parameters (``reflectance``,
  ``specular_reflectance``; for ``roughplastic`` with ``nonlinear`` the diffuse reflectance
  ``c rho/(1 + (c - 1) rho F_int)``, which scales its substrate term by exactly ``c``).
  Mitsuba does not clamp these (colours above 1 are written as ``srgb`` with
  ``unbounded=true``).

What does not map -- TS67 (V-groove shadowing, gaussian-in-angle distribution), RB08,
``microfacet`` with another distribution or shadowing (height-correlated Smith, V-groove,
none), ``oren-nayar`` with ``sigma > 0`` and ``coated`` otherwise (smooth interface, diffuse
shadowing, Oren-Nayar substrate, height-correlated Smith) -- raises ``ValueError`` naming the
model, the option and the reason; with ``fit=True`` it is replaced by the closest exactly
mapped model, fitted with :func:`roughbrdf.fit` to the model's values on
:func:`deviation_grid` (least squares of the relative deviation below), and the export
reports the deviation (*fitted*). The stand-ins: a separable-Smith ``microfacet`` lobe with
the model's index (Beckmann for TS67 and other Gaussian-like distributions, GGX otherwise)
plus a ``lambertian`` part for TS67, TR75 and RB08; ``lambertian`` for Oren-Nayar; ``coated``
with the rough interface, no diffuse shadowing and separable Smith for ``coated``.

Every export reports its deviation from the model, ``|f_Mitsuba - f|/f`` (r.m.s. and maximum)
on :func:`deviation_grid` (``theta_i, theta_r <= theta_max``, 80 deg by default), with
``f_Mitsuba`` from :func:`mitsuba_values`, a float64 transcription of Mitsuba 3.9's ``eval`` for
the plugins written here (including its Beckmann ``G1``, its ``roughplastic`` tables and its
``D cos theta_h <= 1e-20 -> 0`` cut-off; values below :data:`FLOOR` or a millionth of the
model's largest count as absolute, :class:`Deviation`).

**Channels** (a :class:`~roughbrdf.fitting.FitResult` with several). ``channel=`` exports one.
Otherwise, when the channels' exports differ only in parameters Mitsuba takes as colours
(``reflectance``, ``diffuse_reflectance``, ``specular_reflectance``, a conductor's ``eta``
and ``k`` -- what a joint fit with the default shared parameters gives: one roughness, one
coating index), there are three channels and their colours are known, the export is **one
BSDF with RGB values**; the channel -> colour assignment is ``rgb=(red, green, blue)`` (channel
labels or positions) or, by default, by wavelength (labels like ``"630nm"``: longest red,
shortest blue) or by ``R``/``G``/``B`` labels. Otherwise it is **one BSDF per channel**:
``{label: bsdf}`` (XML: one ``<bsdf id="label">`` each); ``rgb=False`` forces this.

Layout (one module per job; everything above is importable from here):

* :mod:`~roughbrdf.export.mitsuba.mapping` -- which model maps to which plugin (the table
  above) and why the others are refused;
* :mod:`~roughbrdf.export.mitsuba.emulation` -- :func:`mitsuba_values`, the float64
  transcription of Mitsuba's ``eval`` that the deviations (and "exact") rest on;
* :mod:`~roughbrdf.export.mitsuba.deviation` -- :func:`deviation_grid`, :class:`Deviation`,
  :data:`EXACT`, :data:`FLOOR`;
* :mod:`~roughbrdf.export.mitsuba.stand_ins` -- the fitted stand-ins (``fit=True``, the CLI's
  ``--fit-closest``);
* :mod:`~roughbrdf.export.mitsuba.xml_writer` -- the XML ``<bsdf>`` text (:func:`xml_text`);
* :mod:`~roughbrdf.export.mitsuba.exporting` -- :func:`export_mitsuba`, :func:`to_mitsuba`,
  :func:`to_mitsuba_xml`, channels and the records (:class:`MitsubaExport`,
  :class:`TermExport`).
"""

from __future__ import annotations

from .deviation import EXACT, FLOOR, Deviation, deviation_grid
from .deviation import PEAK_FLOOR as PEAK_FLOOR  # importable here as before, not in __all__
from .emulation import ALPHA_MIN as ALPHA_MIN  # (idem)
from .emulation import mitsuba_values
from .exporting import MitsubaExport, TermExport, export_mitsuba, to_mitsuba, to_mitsuba_xml
from .xml_writer import xml_text

__all__ = ["EXACT", "FLOOR", "Deviation", "MitsubaExport", "TermExport", "deviation_grid",
           "export_mitsuba", "mitsuba_values", "to_mitsuba", "to_mitsuba_xml", "xml_text"]
