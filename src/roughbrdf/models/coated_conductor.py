"""Metallic paint: a rough clear dielectric coat over a rough conductor (metal flakes).

Composed from the library's parts (``docs/models.md`` §10.5), nothing re-derived::

    f_r = F(theta_d; n) D(theta_h; alpha) G / (4 cos theta_i cos theta_r)            (coat)
        + s(theta_i) s(theta_r) T(theta_i) T(theta_r) f_base(theta_i', theta_r', phi) / n^2

    f_base = (1 - d) F(theta_d'; m) D(theta_h'; alpha_m) G' / (4 cos theta_i' cos theta_r')
             + d rho/pi,                                   m = (n_m + i k_m)/n

* coat: the ``coated`` model's lobe 1 (weight 1): :mod:`roughbrdf.fresnel` at ``n + 0i`` with
  TR75 Eq. 24 polarization, :mod:`roughbrdf.distributions` (GGX or Beckmann),
  :mod:`roughbrdf.shadowing` (Smith, separable or height-correlated).
* ``T = 1 - R``: the smooth interface's Fresnel transmittance at the macroscopic angles
  (``R(theta_i; gamma)`` for the incident polarization, ``R(theta_r)`` unpolarized), as in
  :func:`roughbrdf.diffuse.coated_diffuse`.
* ``theta'``: the directions refracted into the coat, ``sin theta' = sin theta/n``, same
  azimuth; the flakes' half vector, ``theta_d'`` and ``theta_h'`` are
  :func:`roughbrdf.geometry.half_vector_cs` of the refracted pair (their sines and cosines,
  no ``asin``).
* base: the ``microfacet`` model (unpolarized ``F``, ``ks = 1``) of the conductor at the
  relative index ``(n_m + i k_m)/n`` with its own width ``alpha_m``; with ``diffuse=True`` a
  share ``d`` of pigment of albedo ``rho`` between the flakes.
* ``s(mu) = min(1, (1 - E(mu))/(1 - R(mu)))``: the coated model's smooth-interface limit
  (:func:`roughbrdf.models.coated.smooth_interface_factors`), ``E`` the coat lobe's albedo.

The layering is Weidlich & Wilkie's (2007, "Arbitrarily layered micro-facet surfaces",
GRAPHITE 2007, 171-178): single scattering in the base, smooth-interface refraction, the
``1/n^2`` of radiance across an interface. pbrt-v4's ``CoatedConductorBxDF`` computes the same
layering stochastically (a random walk with all orders of inter-reflection); this closed form
keeps one bounce and drops light that the coat reflects back inside, so it loses a little
energy against a white furnace (measured in ``docs/models.md`` §10.5) and never creates any.
"""

from __future__ import annotations

import dataclasses
import math

from numba import prange

from .. import distributions as dist
from .. import shadowing as shd
from .._kernels import at, driver, jit, sincos, tuple_slice
from ..diffuse import ROUGH_TABLE_SIZE, diffuse_through, interface_transmission, table_lerp
from ..fresnel import (
    check_index,
    diffuse_reflectance,
    fresnel_polarized_xy,
    fresnel_sp,
    index_from_reflectance,
)
from ..geometry import half_vector_cs, tr75_eta_xy
from .base import Model, register
from .coated import lobe, smooth_interface_factors
from .parameters import Parameter, nonnegative, option_flag, positive, reflectance

#: index of the smooth interface's factor table s(mu) in the packed parameters
_TABLE0 = 12
#: the factor table without a coat (``coat=False``: ``n = 1``, ``s = 1``; ``_pack``)
_NO_COAT_TABLE = (1.0,) * ROUGH_TABLE_SIZE


@jit(inline=True)
def _flakes(si, sr, sp, cp, n, nm, km, am, norm, dcode, scode):
    """The conductor's microfacet BRDF at the directions refracted into the coat.

    ``F((n_m + i k_m)/n) D G/(4 cos theta_i' cos theta_r')`` (unpolarized ``F``: the light
    inside is taken as unpolarized), ``sin theta' = sin theta/n`` (``si``, ``sr``, ``sp``,
    ``cp``: the sines of the outside angles and of ``phi``, its cosine). ``n >= 1``, so
    ``cos theta' >= sqrt(1 - 1/n^2)``: positive under a coat; without one (``n = 1``) it is
    the outside cosine, 0 only at grazing, where Smith's ``G`` is 0 too.
    """
    si_, sr_ = si / n, sr / n
    # 1 - s^2 >= 1 - 1/n^2 >= 0 for n >= 1: the max only guards rounding above 1
    ci_ = math.sqrt(max(0.0, 1.0 - si_ * si_))
    cr_ = math.sqrt(max(0.0, 1.0 - sr_ * sr_))
    hx, hy, hz, cd, ci, cr, _ = half_vector_cs(si_, ci_, sr_, cr_, sp, cp)
    rs, rp = fresnel_sp(cd, nm, km)
    t = 0.5 * (rs + rp) * lobe(dcode, scode, am, 1.0, norm, hz, ci, cr)
    # t = 0 (F = 0 at an index-matched base, or D underflowed): 0, never 0 * inf
    return 0.25 * t if t > 0.0 else 0.0


@jit(inline=True)
def _metallic_eval(ti, tr, phi, gamma, p, tab, flag, dcode):
    """``f_r`` (``flag = 0``) or ``f_r cos theta_r`` (``flag = 1``); module notes."""
    n, a, norm, nm, km, am, norm_m, dd, rho = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], \
        p[8]
    scode = int(p[9])
    si, ci0 = sincos(ti)
    sr, cr0 = sincos(tr)
    sp, cp = sincos(phi)
    hx, hy, hz, cd, ci, cr, si = half_vector_cs(si, ci0, sr, cr0, sp, cp)
    ex, ey = tr75_eta_xy(si, ci, hx, hy, hz)
    f = fresnel_polarized_xy(cd, n, 0.0, gamma, ex, ey)
    coat = 0.25 * f * lobe(dcode, scode, a, 1.0, norm, hz, ci, cr)
    # the coat's lobe is 0 where its facets are (0 * inf is excluded by Smith G -> 0 at
    # grazing, as in the coated model)
    t_in, t_out = interface_transmission(ci, cr, n, gamma)  # once: flakes and pigment
    flakes = (1.0 - dd) * t_in * t_out / (n * n) * _flakes(si, sr, sp, cp, n, nm, km, am,
                                                          norm_m, dcode, scode)
    # the pigment: the coated model's diffuse substrate (its light trapped by the coat's
    # internal reflection comes back out, 1/(1 - rho F_dr,int)); dd = 0 without diffuse=True
    pigment = dd * diffuse_through(t_in, t_out, n, rho, p[11]) if dd > 0.0 else 0.0
    layer = table_lerp(ci, tab, 0) * table_lerp(cr, tab, 0) * (flakes + pigment)
    value = coat + layer
    return value * cr if flag else value


@driver
def _metallic_drive(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # module-level loop: cached on disk (roughbrdf._kernels.compile.driver); the distribution
    # (GGX or Beckmann: the two with a Smith Lambda) a literal in each loop
    tab = tuple_slice(p, _TABLE0, len(p))
    if int(p[10]) == dist.TR:
        for i in prange(out.size):
            out[i] = _metallic_eval(at(a, i), at(b, i), at(c, i), at(g, i), p, tab, flag,
                                    dist.TR)
    else:
        for i in prange(out.size):
            out[i] = _metallic_eval(at(a, i), at(b, i), at(c, i), at(g, i), p, tab, flag,
                                    dist.BECKMANN)


@register
class CoatedConductor(Model):
    """Metallic paint: a rough clear coat of index ``n`` over rough metal flakes ``n_m + i k_m``.

    The coat's lobe (the ``coated`` model's lobe 1) plus the flakes' microfacet lobe seen
    through the coat's smooth interface: Fresnel transmission in and out, refraction of both
    directions, ``1/n^2``, the conductor at the relative index ``(n_m + i k_m)/n``, and the
    coated model's limit ``s`` so that the flakes receive at most what the coat's lobe leaves.
    Single scattering (Weidlich & Wilkie 2007; the renderer anchor is pbrt-v4's
    ``CoatedConductorBxDF``, which adds the higher orders stochastically): energy-conserving
    by construction, reciprocal. ``docs/models.md`` §10.5; the module notes give the formula.

    Options: ``distribution`` (``"trowbridge-reitz"``/GGX or ``"beckmann"``, for the coat and
    the flakes), ``shadowing`` (``"smith-separable"`` or ``"smith-height-correlated"``),
    ``diffuse`` (``True``: a share ``d`` of pigment of albedo ``rho`` between the flakes, the
    coated model's diffuse substrate; default ``False``), ``flakes`` (``"index"``: the flakes'
    complex index ``n_m + i k_m`` in air, default; ``"reflectance"``: their normal reflectance
    ``r_m`` inside the coat and edge tint ``g_m``, :func:`roughbrdf.fresnel.index_from_reflectance`
    - the form a fit can determine: the data fix the flakes' reflectance, rarely ``n_m`` and
    ``k_m`` apart), ``coat`` (``False``: no clear coat, ``n = 1``: a rough conductor, plus the
    pigment, in air; default ``True``).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> m = rb.model("metallic", n=1.5, alpha=0.05, n_m=0.2, k_m=3.3, alpha_m=0.05)
    >>> m.param_names
    ['n', 'alpha', 'n_m', 'k_m', 'alpha_m']
    >>> round(float(rb.albedo(m, 0.0)), 2)        # gold-like flakes: a metal's reflectance
    0.87
    >>> rb.model("metallic-paint", diffuse=True).param_names[-2:]
    ['d', 'rho']
    """

    name = "coated-conductor"
    aliases = ("metallic", "metallic-paint")
    short = "metal"
    reference = "Weidlich & Wilkie 2007; Walter et al. 2007; pbrt-v4 CoatedConductorBxDF"
    OPTIONS = {"distribution": "trowbridge-reitz", "shadowing": "smith-separable",
               "diffuse": False, "flakes": "index", "coat": True}
    _drive = _metallic_drive

    def _check_options(self, options):
        d = dist.get(options["distribution"])
        if d.code not in (dist.TR, dist.BECKMANN):
            raise ValueError(f"the coated-conductor model needs a distribution with a Smith "
                             f"Lambda (trowbridge-reitz, beckmann), got "
                             f"{options['distribution']!r}")
        s = shd.get(options["shadowing"]).code
        if s not in (shd.SMITH_SEPARABLE, shd.SMITH_HEIGHT_CORRELATED):
            raise ValueError(f"the coated-conductor model's shadowing must be smith-separable "
                             f"or smith-height-correlated, got {options['shadowing']!r}")
        flakes = str(options["flakes"]).strip().lower()
        if flakes not in ("index", "reflectance"):
            raise ValueError(f"flakes must be 'index' (n_m, k_m) or 'reflectance' (r_m, g_m), "
                             f"got {options['flakes']!r}")
        return {"distribution": d.name, "shadowing": shd.canonical(s),
                "diffuse": option_flag(options["diffuse"], "diffuse"), "flakes": flakes,
                "coat": option_flag(options["coat"], "coat")}

    def _parameter_specs(self) -> tuple[Parameter, ...]:
        o = self._options
        specs = []
        if o["coat"]:
            specs += [Parameter("n", 1.5, (1.3, 1.8), "1", "refractive index of the clear coat",
                                (1.0, False, math.inf, False)),
                      positive("alpha", 0.05, (0.005, 1.5), "1",
                               "width of the coat's specular lobe (distribution parameter)")]
        if o["flakes"] == "reflectance":
            tint = reflectance("g_m", 0.5, "edge tint of the flakes (Gulbrandsen 2014: 0 the "
                               "largest index of that r_m, 1 the smallest; None: 1, a metal's, "
                               "not fitted)")
            # search from 0.25: the metals of paints reflect 0.3-0.95 at normal incidence in
            # a binder over the visible (docs/fitting.md, "Bounds"); below, the fit would be a
            # dielectric's, which the coated model describes
            specs += [reflectance("r_m", 0.9, "normal reflectance of the metal flakes (in the "
                                  "coat)", bounds=(0.25, 1.0)),
                      dataclasses.replace(tint, optional=True)]
        else:
            specs += [positive("n_m", 0.2, (0.03, 4.0), "1",
                               "refractive index of the metal flakes (n_m + i k_m, in air)"),
                      nonnegative("k_m", 3.3, (0.0, 8.0), "1",
                                  "extinction index of the metal flakes (n_m + i k_m, in air)")]
        specs.append(positive("alpha_m", 0.2, (0.01, 1.5), "1",
                              "width of the flakes' lobe (distribution parameter)"))
        if o["diffuse"]:
            rho = reflectance("rho", 0.5, "albedo of the pigment (None: white, 1, not fitted: "
                              "the data rarely tell it from the share d)")
            specs += [reflectance("d", 0.2, "share of pigment between the flakes"),
                      dataclasses.replace(rho, value=None, optional=True)]
        return tuple(specs)

    def _validate(self) -> None:
        v = self._floats()
        code = dist.get(self._options["distribution"]).code
        if self._options["coat"]:
            dist.check_param(code, v["alpha"], "alpha")
        dist.check_param(code, v["alpha_m"], "alpha_m")
        if self._options["flakes"] == "index":
            check_index(v["n_m"], v["k_m"])

    def flake_index(self) -> tuple[float, float]:
        """The flakes' complex index relative to the coat, ``(n_m + i k_m)/n`` (``flakes=
        "index"``) or :func:`~roughbrdf.fresnel.index_from_reflectance` of ``r_m, g_m``.

        Examples
        --------
        >>> import roughbrdf as rb
        >>> m = rb.model("metallic", flakes="reflectance", r_m=0.04, g_m=0.0)
        >>> [round(v, 6) for v in m.flake_index()]        # a dielectric of index 1.5 n
        [1.5, 0.0]
        """
        v = self._floats()
        if self._options["flakes"] == "reflectance":
            # g_m = None: 1, the smallest index of that reflectance (metals: 0.97-1 by the map)
            return index_from_reflectance(v["r_m"], v.get("g_m", 1.0))
        n = v.get("n", 1.0)
        return v["n_m"] / n, v["k_m"] / n

    @property
    def conserves_energy(self) -> bool:
        """True: albedo <= 1 by construction (``docs/models.md`` §10.5;
        ``tests/models/test_coated_conductor.py`` checks it over the whole domain)."""
        return True

    def _pack(self) -> tuple:
        v, o = self._floats(), self._options
        d = dist.get(o["distribution"]).code
        # no coat: n = 1, where the coat's Fresnel is 0 (its lobe vanishes), T = 1, s = 1
        n, alpha = (v["n"], v["alpha"]) if o["coat"] else (1.0, v["alpha_m"])
        # no coat: F = 0 at n = 1 exactly, so the lobe's albedo E = 0, R = 0 and s = 1 at every
        # node: the table is ones (not recomputed for each alpha_m a fit tries)
        table = smooth_interface_factors(((1.0, alpha),), n, o["distribution"],
                                         o["shadowing"]) if o["coat"] else _NO_COAT_TABLE
        nm, km = self.flake_index()
        # no pigment: d = 0 (its term vanishes); rho = None: white pigment
        return (n, alpha, dist.normalization(d, alpha), nm, km, v["alpha_m"],
                dist.normalization(d, v["alpha_m"]), v.get("d", 0.0), v.get("rho", 1.0),
                shd.get(o["shadowing"]).code, d, diffuse_reflectance(n, internal=True), *table)
