"""Generic microfacet BRDF ``F D G / (4 cos theta_i cos theta_r)`` from named parts.

Cook & Torrance (1982) / Walter et al. (2007) form, built from :mod:`roughbrdf.distributions`,
:mod:`roughbrdf.shadowing` and :mod:`roughbrdf.fresnel`::

    f_r = ks F(theta_d) D(theta_h) G / (4 cos theta_i cos theta_r)

``F`` at the local angle ``theta_d`` (polarization per TR75 Eq. 24); ``n=None`` gives ``F = 1``.
``ks`` is an overall scale, 1 for a physical surface. Its domain is ``[0, inf)`` (it is not a
reflectance of a part, ``roughbrdf.models.parameters``), but its search range is the physical
``[0, 1]``: one interface with ``F <= 1`` reflects at most what it receives (the albedo at
``ks = 1`` is at most 1 + 1e-12 for every distribution with Smith or V-groove shadowing,
``alpha`` 0.01-2, ``F = 1`` included; ``tests/models/test_coated_energy.py``). Without shadowing
(``shadowing="none"``) it diverges at grazing incidence whatever ``ks``. A fit may be given a
wider range (``bounds={"ks": (0, 20)}``); its report and ``fit.json`` then say it used a
non-physical range (:mod:`roughbrdf.fitting.results.physical`). With data of unknown scale (a free
data scale ``K``) a lone microfacet lobe's ``ks`` and ``K`` are one degree of freedom: fix
``ks`` (``fix=["ks"]``, ``--fix ks``; ``K`` carries the scale, ``docs/fitting.md``).
The parameter ``alpha`` is the width parameter of the chosen distribution: ``e`` for
Trowbridge-Reitz/GGX and Berry, ``m`` for Beckmann, ``c`` (per degree) for gaussian-angle, ``A2``
for Sirohi.
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from .. import distributions as dist
from .. import shadowing as shd
from .._kernels import at, driver, jit
from ..fresnel import check_index, fresnel_polarized_xy
from ..geometry import half_vector, tr75_eta_xy
from ..mueller import facet_mueller
from .base import Model, PreparedGeometry, register, require_index
from .parameters import Parameter, nonnegative, positive


@jit(inline=True)
def _micro_eval(ti, tr, phi, gamma, p, flag, dcode, scode):
    # Inlined and free of libm calls (vexp/vlog/vacos/verfc in D and Lambda, eta as a vector
    # instead of atan2, selects instead of branches), so that the driver loops vectorize.
    # With literal dcode/scode/flag (the driver's specialized loops) the branches of the other
    # distributions, shadowing functions and quantity compile away.
    alpha, n, k, ks, norm, use_f = p[0], p[1], p[2], p[3], p[6], p[7]
    hx, hy, hz, cd, ci, cr, si = half_vector(ti, tr, phi)
    # F at the local angle; eta (TR75 Eq. 24) from the unnormalized vector sin(s) (cos, sin)
    ex, ey = tr75_eta_xy(si, ci, hx, hy, hz)
    fr = fresnel_polarized_xy(cd, n, k, gamma, ex, ey)
    f = fr if use_f > 0.0 else 1.0
    d = dist.evaluate_d(dcode, hz, alpha, norm)
    if flag:  # BRIDF = f_r cos(theta_r): the 1/cos(theta_r) is never formed
        if scode == shd.NONE:
            # unshadowed: diverges at grazing incidence, limit inf (stand-in 1: no 1/0)
            geo = 1.0 / (ci if ci > 0.0 else 1.0)
            geo = geo if ci > 0.0 else math.inf
        elif scode == shd.V_GROOVE:
            geo = shd.v_groove_g_over_cos_r(cr, ci, hz, cd)  # G/cos(theta_i) (G symmetric)
        else:
            geo = shd.smith_g_over_cos_cos(scode, dcode, alpha, ci, cr) * cr
    else:
        geo = shd.g_over_cos_cos(scode, dcode, alpha, ci, cr, hz, cd)
    t = ks * f * d
    # t = 0 (F = 0, or D underflowed far from its peak) gives 0 there, never 0 * inf; t * geo
    # first: 0.25 * t of a subnormal t rounds to 0, and 0 * inf (unshadowed, grazing) is NaN
    # (scaling by 0.25 is exact otherwise, so the order changes no other value)
    return 0.25 * (t * geo) if t > 0.0 else 0.0


@driver
def _micro_drive(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # module-level loop: cached on disk (roughbrdf._kernels.compile.driver). Specialized
    # loops, each with the distribution and the quantity as literals, for GGX and Beckmann
    # (the shadowing code stays a runtime select: its candidates are cheap); one generic loop
    # for the other distributions.
    dcode = int(p[4])
    scode = int(p[5])
    if dcode == dist.TR:
        if flag:
            for i in prange(out.size):
                out[i] = _micro_eval(at(a, i), at(b, i), at(c, i), at(g, i), p, 1, dist.TR,
                                     scode)
        else:
            for i in prange(out.size):
                out[i] = _micro_eval(at(a, i), at(b, i), at(c, i), at(g, i), p, 0, dist.TR,
                                     scode)
    elif dcode == dist.BECKMANN:
        if flag:
            for i in prange(out.size):
                out[i] = _micro_eval(at(a, i), at(b, i), at(c, i), at(g, i), p, 1,
                                     dist.BECKMANN, scode)
        else:
            for i in prange(out.size):
                out[i] = _micro_eval(at(a, i), at(b, i), at(c, i), at(g, i), p, 0,
                                     dist.BECKMANN, scode)
    else:
        for i in prange(out.size):
            out[i] = _micro_eval(at(a, i), at(b, i), at(c, i), at(g, i), p, flag, dcode, scode)


@driver
def _micro_mueller_drive(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # Mueller matrices (roughbrdf.mueller; flag = basis code): the facet term with the facet
    # factor ks D G/(4 cos cos) of the scalar kernel itself, run with F switched off (p[7] = 0,
    # Microfacet._mueller_pack), and the Fresnel amplitudes of n + ik = p[1] + i p[2]
    nan = math.nan
    for i in prange(out.shape[0]):
        ti, tr, ph = at(a, i), at(b, i), at(c, i)
        f = _micro_eval(ti, tr, ph, nan, p, 0, int(p[4]), int(p[5]))
        facet_mueller(out, i, ti, tr, ph, p[1], p[2], flag, f)


@register
class Microfacet(Model):
    """Microfacet BRDF with distribution, shadowing and Fresnel chosen by name.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> m = rb.model("microfacet", distribution="ggx", alpha=0.3, shadowing="smith", n=1.5, k=0.0)
    >>> m.options["distribution"], m.options["shadowing"]
    ('trowbridge-reitz', 'smith-height-correlated')
    """

    name = "microfacet"
    aliases = ("cook-torrance",)
    short = "microfacet"
    reference = "Cook & Torrance 1982; Walter et al. 2007"
    PARAMETERS = (
        positive("alpha", 0.3, (0.01, 2.0), "1", "width parameter of the distribution"),
        Parameter("n", 1.5, (0.2, 5.0), "1", "refractive index (None: F = 1)",
                  (0.0, False, math.inf, False), optional=True),
        Parameter("k", 0.0, (0.0, 10.0), "1", "extinction index (n + ik)",
                  (0.0, True, math.inf, False), optional=True),
        nonnegative("ks", 1.0, (0.0, 1.0), "1",
                    "scale of the specular term (1: the interface alone; above 1 not physical)"),
    )
    OPTIONS = {"distribution": "trowbridge-reitz", "shadowing": "smith-height-correlated"}
    _drive = _micro_drive

    def _check_options(self, options):
        d = dist.get(options["distribution"])
        s = shd.get(options["shadowing"]).code
        if s in (shd.SMITH_SEPARABLE, shd.SMITH_HEIGHT_CORRELATED) and not d.smith:
            raise ValueError(f"shadowing {options['shadowing']!r} needs a distribution with a "
                             f"Smith Lambda (trowbridge-reitz, beckmann), got {d.name!r}")
        return {"distribution": d.name, "shadowing": shd.canonical(s)}

    def _validate(self) -> None:
        d = dist.get(self._options["distribution"])
        dist.check_param(d.code, self._floats()["alpha"], "alpha")
        n, k = self._values["n"], self._values["k"]
        if n is not None:
            check_index(n, 0.0 if k is None else k)

    def _pack(self) -> tuple:
        v = self._values
        alpha = self._floats()["alpha"]
        d = dist.get(self._options["distribution"])
        use_f = v["n"] is not None
        return (alpha, v["n"] if use_f else 1.0, (v["k"] or 0.0) if use_f else 0.0,
                v["ks"], d.code, shd.get(self._options["shadowing"]).code,
                dist.normalization(d.code, alpha), 1.0 if use_f else 0.0)

    def _mueller(self, g: PreparedGeometry, basis: int, term: str | None) -> np.ndarray:
        require_index(self)
        p = list(self._pack())
        p[7] = 0.0  # the facet factor without F: the Fresnel part is the Mueller matrix's
        return self._mueller_drive(_micro_mueller_drive, g, tuple(p), basis, term)
