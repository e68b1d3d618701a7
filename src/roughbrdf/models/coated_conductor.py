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
  :func:`roughbrdf.geometry.half_vector` of the refracted pair.
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

import math

from numba import prange

from .. import distributions as dist
from .. import shadowing as shd
from .._kernels import at, driver, jit, sincos, tuple_slice
from ..diffuse import table_lerp
from ..fresnel import check_index, fresnel_polarized_cs, fresnel_polarized_xy, fresnel_sp
from ..geometry import half_vector, tr75_eta_xy
from .base import Model, register
from .coated import lobe, smooth_interface_factors
from .parameters import Parameter, nonnegative, option_flag, positive, reflectance

#: index of the smooth interface's factor table s(mu) in the packed parameters
_TABLE0 = 12


@jit(inline=True)
def _flakes(ti, tr, phi, n, nm, km, am, norm, dcode, scode):
    """The conductor's microfacet BRDF at the directions refracted into the coat.

    ``F((n_m + i k_m)/n) D G/(4 cos theta_i' cos theta_r')`` (unpolarized ``F``: the light
    inside is taken as unpolarized), ``sin theta' = sin theta/n``. ``n > 1``, so
    ``cos theta' >= sqrt(1 - 1/n^2) > 0``: no division by 0 even at grazing outside.
    """
    si, sr = sincos(ti)[0], sincos(tr)[0]
    hx, hy, hz, cd, ci, cr, _ = half_vector(math.asin(si / n), math.asin(sr / n), phi)
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
    hx, hy, hz, cd, ci, cr, si = half_vector(ti, tr, phi)
    ex, ey = tr75_eta_xy(si, ci, hx, hy, hz)
    f = fresnel_polarized_xy(cd, n, 0.0, gamma, ex, ey)
    coat = 0.25 * f * lobe(dcode, scode, a, 1.0, norm, hz, ci, cr)
    # the coat's lobe is 0 where its facets are (0 * inf is excluded by Smith G -> 0 at
    # grazing, as in the coated model)
    t_in = 1.0 - fresnel_polarized_cs(ci, n, 0.0, gamma, 1.0, 0.0)
    rs, rp = fresnel_sp(cr, n, 0.0)
    t_out = 1.0 - 0.5 * (rs + rp)
    base = (1.0 - dd) * _flakes(ti, tr, phi, n, nm, km, am, norm_m, dcode, scode) \
        + dd * rho / math.pi
    layer = table_lerp(ci, tab, 0) * table_lerp(cr, tab, 0) * t_in * t_out * base / (n * n)
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
    ``diffuse`` (``True``: a share ``d`` of pigment of albedo ``rho`` between the flakes,
    ``base = (1 - d) f_flakes + d rho/pi``; default ``False``).

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
               "diffuse": False}
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
        return {"distribution": d.name, "shadowing": shd.canonical(s),
                "diffuse": option_flag(options["diffuse"], "diffuse")}

    def _parameter_specs(self) -> tuple[Parameter, ...]:
        specs = [
            Parameter("n", 1.5, (1.3, 1.8), "1", "refractive index of the clear coat",
                      (1.0, False, math.inf, False)),
            positive("alpha", 0.05, (0.005, 1.5), "1",
                     "width of the coat's specular lobe (distribution parameter)"),
            positive("n_m", 0.2, (0.05, 3.0), "1",
                     "refractive index of the metal flakes (n_m + i k_m, in air)"),
            nonnegative("k_m", 3.3, (0.0, 5.0), "1",
                        "extinction index of the metal flakes (n_m + i k_m, in air)"),
            positive("alpha_m", 0.2, (0.01, 1.5), "1",
                     "width of the flakes' lobe (distribution parameter)"),
        ]
        if self._options["diffuse"]:
            specs += [reflectance("d", 0.2, "share of pigment between the flakes"),
                      reflectance("rho", 0.5, "albedo of the pigment")]
        return tuple(specs)

    def _validate(self) -> None:
        v = self._floats()
        code = dist.get(self._options["distribution"]).code
        dist.check_param(code, v["alpha"], "alpha")
        dist.check_param(code, v["alpha_m"], "alpha_m")
        check_index(v["n_m"], v["k_m"])

    @property
    def conserves_energy(self) -> bool:
        """True: albedo <= 1 by construction (``docs/models.md`` §10.5;
        ``tests/models/test_coated_conductor.py`` checks it over the whole domain)."""
        return True

    def _pack(self) -> tuple:
        v, o = self._floats(), self._options
        d = dist.get(o["distribution"]).code
        n = v["n"]
        table = smooth_interface_factors(((1.0, v["alpha"]),), n, o["distribution"],
                                         o["shadowing"])
        return (n, v["alpha"], dist.normalization(d, v["alpha"]), v["n_m"] / n, v["k_m"] / n,
                v["alpha_m"], dist.normalization(d, v["alpha_m"]), v.get("d", 0.0),
                v.get("rho", 0.0), shd.get(o["shadowing"]).code, d, 0.0, *table)
