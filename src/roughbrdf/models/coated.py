"""Coated material (paint, plastic): specular lobes of one dielectric interface over a diffuse base.

Composed from the library's parts (``docs/models.md`` §10.3), nothing re-derived::

    f_r = F(theta_d) / (4 cos theta_i cos theta_r) sum_j ks_j D_j(theta_h) G_j      (lobes)
        + G_1^diffuse(theta_i, theta_r) * base(theta_i, theta_r, phi)
          * rho/pi (1 - R(theta_i)) (1 - R(theta_r)) / (n^2 (1 - rho F_dr,int))    (substrate)

* ``F``, ``R``: :mod:`roughbrdf.fresnel` at index ``n`` (``k = 0``), one interface shared by
  every lobe; ``F`` at the local angle ``theta_d`` with TR75 Eq. 24 polarization.
* ``D_j``, ``G_j``: :mod:`roughbrdf.distributions` and :mod:`roughbrdf.shadowing` (Smith,
  separable or height-correlated) with lobe ``j``'s width ``alpha_j``; the lobes model a
  clear coat and its haze (one interface, several roughness scales).
* substrate: :func:`roughbrdf.diffuse.coated_diffuse` (Weidlich & Wilkie 2007), with
  ``base = 1`` (``diffuse="lambertian"``) or Oren-Nayar's factor (``diffuse="oren-nayar"``,
  parameter ``sigma``), and, with ``shadow_diffuse=True``, masked and shadowed by the first
  lobe's Smith ``G(theta_i, theta_r)`` (without the half vector: the light leaving the
  substrate crosses the same rough interface).
* ``interface="rough"`` (default ``"smooth"``): the smooth factors ``1 - R(theta_i)``,
  ``1 - R(theta_r)`` and ``F_dr,int`` become the first lobe's rough-interface transmittance
  table ``T(theta_i) T(theta_r)`` and internal reflectance ``F_int``
  (:func:`roughbrdf.diffuse.coated_diffuse_rough`, :func:`roughbrdf.diffuse.rough_interface`),
  computed exactly as Mitsuba 3's ``roughplastic`` computes them; the substrate term is then
  unpolarized (the tables are). One lobe, ``shadowing="smith-separable"``,
  ``shadow_diffuse=False`` and ``interface="rough"`` is ``roughplastic`` itself (GGX to float32
  rounding; :mod:`roughbrdf.export.mitsuba`).

Why a named model and not a sum with tied parameters: the lobes and the substrate share ``n``
(the specular ``F`` and the transmission ``1 - R`` are the same interface) and the diffuse
shadowing uses the first lobe's ``alpha``; a named model states those ties once, keeps the
parameter count honest for AIC/BIC, and maps one to one onto Mitsuba's ``roughplastic`` (one
lobe, ``shadowing="smith-separable"``, ``shadow_diffuse=False``, ``interface="rough"``).
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np
from numba import prange

from .. import distributions as dist
from .. import shadowing as shd
from .._kernels import at, driver, jit, sincos, tuple_slice
from ..diffuse import (
    ROUGH_TABLE_SIZE,
    TABLE_NODES,
    coated_diffuse,
    coated_diffuse_rough,
    lobe_albedo,
    oren_nayar_factor,
    rough_interface,
    table_lerp,
)
from ..errors import ArgumentError
from ..fresnel import diffuse_reflectance, fresnel_polarized_xy, fresnel_sp
from ..geometry import half_vector, tr75_eta_xy
from ..mueller import facet_mueller
from .base import Model, PreparedGeometry, register
from .parameters import Parameter, nonnegative, option_flag, positive, reflectance

#: ``diffuse`` option -> code in the packed parameters
DIFFUSE = {"lambertian": 0, "oren-nayar": 1}
#: ``interface`` option -> code in the packed parameters
INTERFACE = {"smooth": 0, "rough": 1}
#: ``weights`` option: the lobes' weights sum to 1 (default), or free scales (legacy)
WEIGHTS = ("partition", "free")
#: most specular lobes (the packed parameters have a slot for each; an unused lobe has ks = 0)
MAX_LOBES = 3
_LOBE0 = 7  # index of the first lobe's (alpha, ks, norm) in the packed parameters
# packed after the distribution code (16): the interface code (17), the rough interface's
# internal reflectance (18) and its transmittance table (19 to 82; for "smooth" the factor
# table of _smooth_factors)
_INTERFACE = 17
_TABLE0 = 19


@jit(inline=True)
def lobe(dcode, scode, a, ks, norm, hz, ci, cr):
    """``ks D G/(cos theta_i cos theta_r)`` of one lobe (0 where ks = 0: the lobe is off)."""
    d = dist.evaluate_d(dcode, hz, a, norm)
    t = ks * d * shd.smith_g_over_cos_cos(scode, dcode, a, ci, cr)
    return t if ks > 0.0 else 0.0


@jit(inline=True)
def _on_albedo(t, c, s, sigma2):
    """``max(1, albedo(theta)/rho)`` of Oren-Nayar's Eq. 30 (``docs/models.md`` §10.2:
    ``A + (2B/pi) [sin t (t/2 - sin 2t/4) + tan t (1 - sin^3 t)/3]``), which exceeds 1 by up to
    1.5 % beyond 60.7 deg: the coated substrate's Eq. 30 factor is divided by it.

    ``t`` is the angle itself (``c``, ``s`` its cosine and sine): no ``atan2``, a libm call
    that would keep the drivers' loops from vectorizing."""
    a = 1.0 - 0.5 * sigma2 / (sigma2 + 0.33)
    b = 0.45 * sigma2 / (sigma2 + 0.09)
    # tan t (1 - sin^3 t) -> 0 at grazing (c = 0): the stand-in 1 keeps the division finite
    tail = s * (1.0 - s * s * s) / (c if c > 0.0 else 1.0) if c > 0.0 else 0.0
    v = a + 2.0 * b / math.pi * (s * (0.5 * t - 0.5 * s * c) + tail / 3.0)
    return v if v > 1.0 else 1.0


@jit(inline=True)
def _coated_terms(ti, tr, phi, gamma, p, tab, dcode, rough):
    """``(F, sum_j ks_j D_j G_j/(cos theta_i cos theta_r), substrate term, cos theta_i,
    cos theta_r)``; ``tab`` the interface's table (``p[_TABLE0:]`` as an array)."""
    n, rho, sigma2, scode, dmode, dshadow, fdr_int = p[0], p[1], p[2], p[3], p[4], p[5], p[6]
    scode = int(scode)
    hx, hy, hz, cd, ci, cr, si = half_vector(ti, tr, phi)
    ex, ey = tr75_eta_xy(si, ci, hx, hy, hz)
    f = fresnel_polarized_xy(cd, n, 0.0, gamma, ex, ey)
    spec = lobe(dcode, scode, p[7], p[8], p[9], hz, ci, cr)
    spec += lobe(dcode, scode, p[10], p[11], p[12], hz, ci, cr)
    spec += lobe(dcode, scode, p[13], p[14], p[15], hz, ci, cr)
    if rough:  # a literal in each driver loop: the other interface's code compiles away
        diff = coated_diffuse_rough(ci, cr, n, rho, p[18], tab, 0)
    else:
        # the smooth interface's factor table (1 where the lobes reflect at most R(theta);
        # _smooth_factors): what the lobes do not reflect is all the substrate can receive
        diff = coated_diffuse(ci, cr, n, gamma, rho, fdr_int) * table_lerp(
            ci, tab, 0) * table_lerp(cr, tab, 0)
    if dmode > 0.0:
        sr, cp = sincos(tr)[0], sincos(phi)[1]
        diff *= oren_nayar_factor(ci, cr, si, sr, cp, sigma2)
        if dmode > 1.5:  # Eq. 30 limited to what it receives (weights="partition")
            diff /= max(_on_albedo(ti, ci, si, sigma2), _on_albedo(tr, cr, sr, sigma2))
    if dshadow > 0.0:
        diff *= ci * cr * shd.smith_g_over_cos_cos(scode, dcode, p[7], ci, cr)
    return f, spec, diff, ci, cr


@jit(inline=True)
def _coated_eval(ti, tr, phi, gamma, p, tab, flag, dcode, rough):
    f, spec, diff, ci, cr = _coated_terms(ti, tr, phi, gamma, p, tab, dcode, rough)
    value = 0.25 * f * spec + diff
    return value * cr if flag else value


@jit(inline=True)
def _substrate_mueller(out, i, diff, ci, cr, n):
    """Add the smooth-interface substrate term: ``diff u_r u_i^T`` with
    ``u = (1, (R_p - R_s)/(2 - R_s - R_p), 0, 0)`` at ``theta_i`` and ``theta_r``.

    The light crosses the interface (Mueller transmission ``[[T, dT], [dT, T]]``, ``T = 1 -
    (R_s + R_p)/2``, ``dT = (R_p - R_s)/2``), is depolarized by the substrate, and crosses it
    again: row 0 gives the scalar path's ``1 - R(theta_i; gamma)``, column 0 the partial p
    polarization of the light that leaves (``docs/models.md`` §11).
    """
    rsi, rpi = fresnel_sp(ci, n, 0.0)
    rsr, rpr = fresnel_sp(cr, n, 0.0)
    ti_, tr_ = 2.0 - rsi - rpi, 2.0 - rsr - rpr  # 2 T; 0 only at grazing, where diff = 0
    ui = (rpi - rsi) / ti_ if ti_ > 0.0 else 0.0
    ur = (rpr - rsr) / tr_ if tr_ > 0.0 else 0.0
    out[i, 0, 0] += diff
    out[i, 0, 1] += diff * ui
    out[i, 1, 0] += diff * ur
    out[i, 1, 1] += diff * ur * ui


@driver
def _coated_drive(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # module-level loop: cached on disk (roughbrdf._kernels.compile.driver); the distribution
    # (Trowbridge-Reitz/GGX or Beckmann: the two with a Smith Lambda) and the interface
    # literals in each loop, so that the smooth loops stay free of the table look-up
    rough = p[_INTERFACE] > 0.0
    tab = tuple_slice(p, _TABLE0, len(p))
    if int(p[16]) == dist.TR:
        if rough:
            for i in prange(out.size):
                out[i] = _coated_eval(at(a, i), at(b, i), at(c, i), at(g, i), p, tab, flag,
                                      dist.TR, True)
        else:
            for i in prange(out.size):
                out[i] = _coated_eval(at(a, i), at(b, i), at(c, i), at(g, i), p, tab, flag,
                                      dist.TR, False)
    elif rough:
        for i in prange(out.size):
            out[i] = _coated_eval(at(a, i), at(b, i), at(c, i), at(g, i), p, tab, flag,
                                  dist.BECKMANN, True)
    else:
        for i in prange(out.size):
            out[i] = _coated_eval(at(a, i), at(b, i), at(c, i), at(g, i), p, tab, flag,
                                  dist.BECKMANN, False)


@driver
def _coated_mueller_drive(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # Mueller matrices (roughbrdf.mueller; flag = basis code): the lobes as one facet term of
    # index n (they share F), the substrate term of the scalar kernel (unpolarized) through
    # the smooth interface's transmission (_substrate_mueller), or for interface="rough"
    # (unpolarized tables) as an ideal depolarizer
    nan = math.nan
    dcode = int(p[16])
    rough = p[_INTERFACE] > 0.0
    tab = tuple_slice(p, _TABLE0, len(p))
    for i in prange(out.shape[0]):
        ti, tr, ph = at(a, i), at(b, i), at(c, i)
        f, spec, diff, ci, cr = _coated_terms(ti, tr, ph, nan, p, tab, dcode, rough)
        facet_mueller(out, i, ti, tr, ph, p[0], 0.0, flag, 0.25 * spec)
        if rough:
            out[i, 0, 0] += diff
        else:
            _substrate_mueller(out, i, diff, ci, cr, p[0])


def _lobe_parameters(j: int, free: bool) -> tuple[Parameter, ...]:
    """Lobe ``j``'s width and, with ``free``, its free scale ``ks_j`` (legacy), else (``j >= 2``)
    its share ``w_j`` of the weight (:func:`lobe_weights`)."""
    suffix = "" if j == 1 else str(j)
    alpha = positive("alpha" + suffix, (0.05, 0.3, 0.6)[j - 1], (0.005, 1.5), "1",
                     f"width of specular lobe {j} (distribution parameter)")
    if free:
        return (alpha, nonnegative("ks" + suffix, 1.0 if j == 1 else 0.2, (0.0, 20.0), "1",
                                   f"free scale of specular lobe {j} (weights='free'; 1: the "
                                   f"interface alone; not energy-conserving)"))
    if j == 1:
        return (alpha,)  # its weight is what the other lobes leave
    share = ("lobe 2's share of the lobes' weight" if j == 2 else
             "lobe 3's share of the weight lobe 2 leaves")
    return (alpha, Parameter(f"w{j}", 0.2, (0.0, 1.0), "1", share + " (weights sum to 1)",
                             (0.0, True, 1.0, True)))


def lobe_weights(lobes: int, w2: float = 0.0, w3: float = 0.0) -> tuple[float, ...]:
    """The lobes' weights from the stick-breaking shares: they sum to 1 for every ``w2``,
    ``w3`` in [0, 1].

    One lobe: ``(1,)``; two: ``(1 - w2, w2)``; three: ``((1 - w2)(1 - w3), w2, (1 - w2) w3)``.

    Examples
    --------
    >>> lobe_weights(3, 0.2, 0.25)
    (0.6000000000000001, 0.2, 0.2)
    """
    if lobes == 1:
        return (1.0,)
    if lobes == 2:
        return (1.0 - w2, w2)
    return ((1.0 - w2) * (1.0 - w3), w2, (1.0 - w2) * w3)


def _smooth_factors(lobes: list[tuple[float, float]], n: float, distribution: str,
                    shadowing: str) -> np.ndarray:
    """The smooth interface's transmission factor ``s(mu) = min(1, (1 - E(mu))/(1 - R(mu)))``
    at :data:`~roughbrdf.diffuse.TABLE_NODES`, ``E = sum_j w_j E_j`` the lobes' albedo
    (:func:`~roughbrdf.diffuse.lobe_albedo` with ``smooth=True``), ``R`` the
    smooth interface's reflectance.

    A rough lobe reflects the facet-averaged ``F(theta_d)``, which can exceed ``R(theta)``
    (by up to 0.3 %: Beckmann, ``alpha`` about 0.2); the substrate then receives at most what
    the lobes leave, ``1 - E``. 1 wherever ``E <= R``: those values are the smooth formula's.
    """
    mu = TABLE_NODES
    e = np.zeros(ROUGH_TABLE_SIZE)
    # E interpolated smoothly between tables on a fixed (alpha, n) grid: a fit's finite
    # differences (~1e-8 relative steps) see its derivative and reuse the cached node tables
    for w, a in lobes:
        if w > 0.0:  # a lobe of weight 0 reflects nothing (and costs no table)
            e += w * lobe_albedo(a, n, distribution, shadowing, smooth=True)
    c = mu
    g = np.sqrt(n * n - 1.0 + c * c)
    rs = ((g - c) / (g + c)) ** 2
    rp = rs * ((c * (g + c) - 1.0) / (c * (g - c) + 1.0)) ** 2
    t = 1.0 - 0.5 * (rs + rp)
    s = np.minimum(1.0, (1.0 - e) / t)
    # the first node (cos = 1e-6) has t ~ 1e-6: its ratio is rounding; the substrate is 0
    # there anyway, so it takes the next node's factor
    s[0] = s[1]
    return np.maximum(s, 0.0)


@functools.lru_cache(maxsize=256)
def _smooth_packed(lobes: tuple[tuple[float, float], ...], n: float, distribution: str,
                   shadowing: str) -> tuple[float, ...]:
    """The smooth interface's packed code and :func:`_smooth_factors`, cached: a fit's
    Jacobian perturbs ``rho`` or ``sigma`` as often as the lobes (measured: 0.47 s of a 5 s
    ``rb.fit("auto")`` went to recomputing the same factors)."""
    return (0.0, 0.0, *_smooth_factors(list(lobes), n, distribution, shadowing))


def smooth_interface_factors(lobes: tuple[tuple[float, float], ...], n: float,
                             distribution: str, shadowing: str) -> tuple[float, ...]:
    """The smooth interface's factor ``s(mu) = min(1, (1 - E(mu))/(1 - R(mu)))`` at
    :data:`~roughbrdf.diffuse.TABLE_NODES` for lobes ``((weight, alpha), ...)`` (cached): what
    the coated model packs, shared with the layered models that sit under the same coat
    (:mod:`roughbrdf.models.coated_conductor`).

    Examples
    --------
    >>> s = smooth_interface_factors(((1.0, 0.005),), 1.5, "trowbridge-reitz", "smith-separable")
    >>> len(s), round(float(s[-1]), 3)    # a nearly smooth lobe reflects R(0): the factor is 1
    (64, 1.0)
    """
    return _smooth_packed(lobes, n, distribution, shadowing)[2:]


@register
class Coated(Model):
    """Coated material: rough dielectric interface (one or more lobes) over a diffuse substrate.

    Options: ``distribution`` (``"trowbridge-reitz"``/GGX or ``"beckmann"``), ``shadowing``
    (``"smith-separable"`` or ``"smith-height-correlated"``), ``lobes`` (1 to 3 specular lobes
    of one interface, sharing ``n``), ``diffuse`` (``"lambertian"`` or ``"oren-nayar"``),
    ``shadow_diffuse`` (mask and shadow the substrate term by the first lobe's Smith G),
    ``interface`` (``"smooth"``: Fresnel transmission of a smooth interface into and out of
    the coating, limited to what the lobes leave; ``"rough"``: the lobes' rough-interface
    transmittance, Mitsuba 3's ``roughplastic``; listed in :attr:`options` only when
    ``"rough"``), ``weights`` (``"partition"``, default: the lobes' weights sum to 1 --
    one lobe has weight 1, ``w2`` and ``w3`` share it out (:func:`lobe_weights`) -- so no
    parameter value reflects more than it receives; ``"free"``: the free scales ``ks``,
    ``ks2``, ``ks3`` in [0, 20] of roughbrdf 0.1.0, *not energy-conserving*, for fits
    saved by it; listed only when ``"free"``). Reciprocal. ``docs/models.md`` §10.3; the
    module notes give the formula.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> m = rb.model("coated", n=1.5, alpha=0.1, rho=0.6, lobes=2)
    >>> m.param_names
    ['n', 'rho', 'alpha', 'alpha2', 'w2']
    >>> m0 = m.with_params(rho=1.0, lobes=1, alpha=0.005, shadow_diffuse=False)
    >>> round(float(rb.albedo(m0, 0.0)), 3)      # rho = 1: all light comes back out
    1.0
    >>> rough = rb.model("coated", alpha=0.3, rho=0.5, shadow_diffuse=False, interface="rough")
    >>> round(rough.brdf(0.0, 0.0, 0.0), 5)     # roughplastic's value (Mitsuba 3)
    0.11645
    >>> rb.model("coated", ks=0.5)
    Traceback (most recent call last):
    ...
    roughbrdf.errors.ArgumentError: ks = 0.5: the coated model has no parameter 'ks' ...
    """

    name = "coated"
    aliases = ("paint", "plastic", "coated-diffuse")
    short = "coat"
    reference = "Weidlich & Wilkie 2007; Walter et al. 2007; Oren & Nayar 1994"
    OPTIONS = {"distribution": "trowbridge-reitz", "shadowing": "smith-separable", "lobes": 1,
               "diffuse": "lambertian", "shadow_diffuse": True, "interface": "smooth",
               "weights": "partition"}
    _drive = _coated_drive

    def __init__(self, **kwargs: Any) -> None:
        # the free lobe scales are gone unless asked for: a clear error, not "unknown name"
        if str(kwargs.get("weights", "partition")).strip().lower() != "free":
            old = [k for k in ("ks", "ks2", "ks3") if k in kwargs]
            if old:
                raise ArgumentError(
                    old[0], f"the coated model has no parameter {old[0]!r} any more: its "
                    f"lobes are one interface and their weights sum to 1 (one lobe: weight 1; "
                    f"lobes=2, 3: shares w2, w3 in [0, 1]), so that it cannot reflect more than "
                    f"it receives; weights='free' restores the old free scales ks, ks2, ks3 "
                    f"(not energy-conserving)", value=kwargs[old[0]])
        super().__init__(**kwargs)

    def _check_options(self, options):
        d = dist.get(options["distribution"])
        if d.code not in (dist.TR, dist.BECKMANN):
            raise ValueError(f"the coated model needs a distribution with a Smith Lambda "
                             f"(trowbridge-reitz, beckmann), got {options['distribution']!r}")
        s = shd.get(options["shadowing"]).code
        if s not in (shd.SMITH_SEPARABLE, shd.SMITH_HEIGHT_CORRELATED):
            raise ValueError(f"the coated model's shadowing must be smith-separable or "
                             f"smith-height-correlated, got {options['shadowing']!r}")
        lobes = options["lobes"]
        if isinstance(lobes, str) and lobes.strip().isdigit():
            lobes = int(lobes)
        if isinstance(lobes, bool) or lobes not in range(1, MAX_LOBES + 1):
            raise ValueError(f"lobes must be 1, 2 or 3, got {options['lobes']!r}")
        diffuse = str(options["diffuse"]).strip().lower().replace("_", "-")
        if diffuse not in DIFFUSE:
            raise ValueError(f"diffuse must be 'lambertian' or 'oren-nayar', "
                             f"got {options['diffuse']!r}")
        sd = option_flag(options["shadow_diffuse"], "shadow_diffuse")
        interface = str(options["interface"]).strip().lower()
        if interface not in INTERFACE:
            raise ValueError(f"interface must be 'smooth' or 'rough', "
                             f"got {options['interface']!r}")
        weights = str(options["weights"]).strip().lower()
        if weights not in WEIGHTS:
            raise ValueError(f"weights must be 'partition' or 'free', got {options['weights']!r}")
        out = {"distribution": d.name, "shadowing": shd.canonical(s), "lobes": int(lobes),
               "diffuse": diffuse, "shadow_diffuse": sd}
        # interface and weights are listed only when not the default: models, reprs and fit
        # files of the default coating read as they did before the options existed
        if interface == "rough":
            out["interface"] = interface
        if weights == "free":
            out["weights"] = weights
        return out

    def _parameter_specs(self) -> tuple[Parameter, ...]:
        specs = [Parameter("n", 1.5, (1.05, 2.5), "1", "refractive index of the coating",
                           (1.0, False, math.inf, False)),
                 reflectance("rho", 0.5, "albedo of the diffuse substrate")]
        free = self._options.get("weights") == "free"
        for j in range(1, self._options["lobes"] + 1):
            specs.extend(_lobe_parameters(j, free))
        if self._options["diffuse"] == "oren-nayar":
            specs.append(nonnegative("sigma", 0.3, (0.0, 1.2), "rad",
                                     "Oren-Nayar slope-angle deviation of the substrate"))
        return tuple(specs)

    def _validate(self) -> None:
        code = dist.get(self._options["distribution"]).code
        for j in range(1, self._options["lobes"] + 1):
            name = "alpha" if j == 1 else f"alpha{j}"
            dist.check_param(code, self._floats()[name], name)

    @property
    def conserves_energy(self) -> bool:
        """True with the default ``weights="partition"`` (``docs/models.md`` §10.4;
        ``tests/models/test_coated_energy.py`` checks albedo <= 1 + 1e-3 over the whole domain)."""
        return self._options.get("weights") != "free"

    def lobe_mirror(self) -> tuple[tuple[tuple[str, str], ...], tuple[str, ...]] | None:
        """The two-lobe model's label symmetry: ``(swaps, complements)`` such that
        exchanging the values of each pair in ``swaps`` and replacing each ``w`` in
        ``complements`` by ``1 - w`` gives the same model (lobe 1 and lobe 2 trade places); None
        for one or three lobes (three lobes' weights, :func:`lobe_weights`, are not symmetric
        under a pairwise exchange). The search uses it to treat a point and its mirror as one
        end (:meth:`~roughbrdf.fitting.problem.objective.ObjectiveSpec.canonical`).

        Examples
        --------
        >>> import roughbrdf as rb
        >>> rb.model("coated", lobes=2).lobe_mirror()
        ((('alpha', 'alpha2'),), ('w2',))
        >>> rb.model("coated").lobe_mirror() is None
        True
        """
        if self._options["lobes"] != 2:
            return None
        if self._options.get("weights") == "free":
            return (("alpha", "alpha2"), ("ks", "ks2")), ()
        return (("alpha", "alpha2"),), ("w2",)

    def lobe_layout(self) -> tuple[str, tuple[str, ...], tuple[str | None, ...]]:
        """Where the specular lobes are, for the search's starts from the data's peak widths
        (``roughbrdf.fitting.problem.lobe_starts``): the distribution, each lobe's width
        parameter and its weight share (``w2``, ``w3``; None for the first lobe, and for every
        lobe with ``weights="free"``, whose scales are no shares).

        Examples
        --------
        >>> import roughbrdf as rb
        >>> rb.model("coated", lobes=2, distribution="beckmann").lobe_layout()
        ('beckmann', ('alpha', 'alpha2'), (None, 'w2'))
        """
        o = self._options
        widths = tuple("alpha" if j == 1 else f"alpha{j}" for j in range(1, o["lobes"] + 1))
        free = o.get("weights") == "free"
        shares = tuple(None if j == 1 or free else f"w{j}" for j in range(1, o["lobes"] + 1))
        return o["distribution"], widths, shares

    def specular_lobes(self) -> list[tuple[float, float]]:
        """``[(weight, alpha), ...]`` of the specular lobes: the weights of
        :func:`lobe_weights` (they sum to 1), or the free scales ``ks_j`` with
        ``weights="free"``.

        Examples
        --------
        >>> import roughbrdf as rb
        >>> rb.model("coated", lobes=2, alpha=0.05, alpha2=0.3, w2=0.25).specular_lobes()
        [(0.75, 0.05), (0.25, 0.3)]
        """
        v, o = self._floats(), self._options
        alphas = [v["alpha" if j == 1 else f"alpha{j}"] for j in range(1, o["lobes"] + 1)]
        if o.get("weights") == "free":
            ws: tuple[float, ...] = tuple(v["ks" if j == 1 else f"ks{j}"]
                                          for j in range(1, o["lobes"] + 1))
        else:
            ws = lobe_weights(o["lobes"], v.get("w2", 0.0), v.get("w3", 0.0))
        return list(zip(ws, alphas, strict=True))

    def _interface(self, lobes: list[tuple[float, float]]) -> tuple[float, ...]:
        """The packed interface code, internal reflectance and table (module notes)."""
        v, o = self._floats(), self._options
        if o.get("interface") == "rough":
            if o.get("weights") == "free":  # legacy: the first lobe's interface
                table, f_int = rough_interface(v["alpha"], v["n"], o["distribution"])
                return (1.0, f_int, *table)
            # the interface is the lobes' mixture: its transmittance and internal
            # reflectance are the weight-mixtures of each lobe's (linear in the distribution)
            mix, f_mix = np.zeros(ROUGH_TABLE_SIZE), 0.0
            for w, a in lobes:
                if w > 0.0:  # a lobe of weight 0 is no part of the interface (no table)
                    table, f_int = rough_interface(a, v["n"], o["distribution"])
                    mix += w * table
                    f_mix += w * f_int
            return (1.0, f_mix, *mix)
        if o.get("weights") == "free":  # legacy: the smooth factors unlimited
            return (0.0, 0.0) + (1.0,) * ROUGH_TABLE_SIZE
        return _smooth_packed(tuple(lobes), v["n"], o["distribution"], o["shadowing"])

    def _pack(self) -> tuple:
        v, o = self._floats(), self._options
        d = dist.get(o["distribution"]).code
        used = self.specular_lobes()
        packed: list[float] = []
        for j in range(MAX_LOBES):
            # unused slot: a valid width, switched off by weight 0
            w, a = used[j] if j < len(used) else (0.0, 1.0)
            packed += [a, w, dist.normalization(d, a)]
        return (v["n"], v["rho"], v.get("sigma", 0.0) ** 2,
                # Oren-Nayar: 1 as published (weights="free"), 2 limited to albedo <= 1
                shd.get(o["shadowing"]).code,
                DIFFUSE[o["diffuse"]] * (1 if o.get("weights") == "free" else 2),
                1.0 if o["shadow_diffuse"] else 0.0,
                diffuse_reflectance(v["n"], internal=True), *packed, d, *self._interface(used))

    def _mueller(self, g: PreparedGeometry, basis: int, term: str | None) -> np.ndarray:
        return self._mueller_drive(_coated_mueller_drive, g, self._pack(), basis, term)


class LegacyCoatedWarning(UserWarning):
    """A saved fit of the coated model with free lobe scales (``ks``), from before the lobes'
    weights summed to 1: rebuilt with ``weights="free"`` (:func:`legacy_spec`)."""


def _legacy_entry(spec: dict[str, Any]) -> tuple[dict[str, Any], bool]:
    if spec.get("model") == "sum":
        parts = [_legacy_entry(c) for c in spec.get("components", [])]
        return {**spec, "components": [p for p, _ in parts]}, any(old for _, old in parts)
    name = str(spec.get("model", "")).split("(")[0].strip().lower()
    options, params = dict(spec.get("options") or {}), spec.get("params") or {}
    is_coated = name in (Coated.name, *Coated.aliases)
    # a coated model with a free scale and no weights option: written before the option
    if is_coated and "ks" in params and "weights" not in options:
        return {**spec, "options": {**options, "weights": "free"}}, True
    return spec, False


def legacy_spec(spec: dict[str, Any]) -> dict[str, Any]:
    """A stored model spec (``Model.to_dict()``, or ``{"model": name, "params": ...}``) as the
    current coated model reads it: a coated entry with ``ks`` and no ``weights`` option (a
    fit.json or catalogue of roughbrdf 0.1.0) gets ``weights="free"``, its old free lobe
    scales, with a :class:`LegacyCoatedWarning` (one line). Other specs are returned as they
    are.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     legacy_spec({"model": "coated", "params": {"ks": 20.0}})["options"]
    ...     print(w[0].message)
    {'weights': 'free'}
    the fit predates energy-conserving coated lobes (free lobe scales ks): rebuilt with ...
    """
    import warnings

    out, old = _legacy_entry(spec)
    if old:  # stacklevel 1: one place, so Python shows the note once per run (not per caller)
        warnings.warn("the fit predates energy-conserving coated lobes (free lobe scales ks): "
                      "rebuilt with weights='free', which is not energy-conserving; refit for "
                      "lobe weights that sum to 1", LegacyCoatedWarning, stacklevel=1)
    return out
