"""Facet (micro-normal) distributions, each normalized so that  ∫ D cos(theta_h) dω = 1.

Every distribution is stored as its *peak-normalized* shape ``P`` (``P(theta_h = 0) = 1``, the
form TR75 Fig. 5 compares) times a normalization constant ``K(param)`` (sr⁻¹), so that
``D = K P`` is the standard per-solid-angle facet-normal density of microfacet theory.

==================  =======  ================================================  ====================
name (aliases)      param    peak shape P(alpha)                               reference
==================  =======  ================================================  ====================
trowbridge-reitz    e        e^4 / (e^2 cos^2 a + sin^2 a)^2                    TR75 Eq. 31; GGX a=e
(ggx, tr, tr75)
beckmann            m        cos^-4 a exp(-tan^2 a / m^2)                       Beckmann 1963
gaussian-angle      c        exp(-(c a_deg)^2), ``c`` per degree                TS67 Eq. 5
(ts67, rense)
berry               e        e^2 / (e^2 cos^2 a + sin^2 a)                      TR75 Fig. 5 (Berry)
sirohi              A2       cos^-2 a exp(-A2 tan^2 a)                          TR75 Fig. 5 (Sirohi)
==================  =======  ================================================  ====================

Normalizations: Trowbridge-Reitz ``1/(pi e^2)``; Beckmann ``1/(pi m^2)``; Berry
``(e^2 - 1)/(pi e^2 ln e^2)`` (``1/pi`` at e = 1); gaussian-angle and Sirohi by adaptive
quadrature (SciPy ``quad``, cached per parameter value), because their integrals over the
hemisphere have no elementary closed form. The Sirohi exponent is ``p = 2`` (docs/models.md §3.11,
recommended reading); the ``p = 4`` variant is exactly Beckmann with ``m = 1/sqrt(A2)``.

Smith's ``Lambda`` (needed by :mod:`roughbrdf.shadowing`) depends on D, so it lives here too,
as ``Lambda(theta) cos(theta)``, which stays finite at grazing angles.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ._kernels import as_float_array, jit, ufunc
from ._kernels.vmath import vacos, verfc, vexp, vlog
from .registry import Registry

__all__ = [
    "Distribution",
    "DISTRIBUTIONS",
    "get",
    "names",
    "trowbridge_reitz",
    "ggx",
    "beckmann",
    "gaussian_angle",
    "berry",
    "sirohi",
    "peak",
    "normalization",
    "evaluate",
    "lambda_smith",
]

TR, BECKMANN, GAUSS_ANGLE, BERRY, SIROHI = 0, 1, 2, 3, 4
_DEG = 180.0 / math.pi
_SQRT_PI = math.sqrt(math.pi)


@dataclass(frozen=True)
class Distribution:
    """A registered facet distribution (see the module table)."""

    name: str
    code: int
    param: str
    unit: str
    description: str
    reference: str
    aliases: tuple[str, ...] = ()
    smith: bool = False  # has an analytic Smith Lambda


_ENTRIES = [
    Distribution("trowbridge-reitz", TR, "e", "1",
                 "ellipsoid 'average irregularity' (e = axis ratio); GGX with alpha = e",
                 "Trowbridge & Reitz 1975, Eqs. 30-31; Walter et al. 2007",
                 ("ggx", "tr", "tr75", "trowbridge-reitz-1975"), True),
    Distribution("beckmann", BECKMANN, "m", "1", "gaussian slopes, r.m.s. slope m",
                 "Beckmann & Spizzichino 1963", ("beckmann-spizzichino",), True),
    Distribution("gaussian-angle", GAUSS_ANGLE, "c", "1/deg",
                 "gaussian in the facet tilt angle, exp(-(c alpha_deg)^2)",
                 "Torrance & Sparrow 1967, Eq. 5", ("ts67", "torrance-sparrow", "rense")),
    Distribution("berry", BERRY, "e", "1", "Berry's curvature-based distribution",
                 "Trowbridge & Reitz 1975, Fig. 5"),
    Distribution("sirohi", SIROHI, "A2", "1", "Sirohi (after Berry), cos^-2 exp(-A2 tan^2)",
                 "Trowbridge & Reitz 1975, Fig. 5 (exponent p = 2)"),
]

#: every distribution by canonical name and alias (:class:`roughbrdf.registry.Registry`)
DISTRIBUTIONS: Registry[Distribution] = Registry("distribution")
for _d in _ENTRIES:
    DISTRIBUTIONS.add(_d.name, _d, _d.aliases)


def names() -> list[str]:
    """Canonical names of the registered distributions."""
    return DISTRIBUTIONS.names()


def get(name: str) -> Distribution:
    """Look up a distribution by name or alias (case and ``_``/``-`` insensitive)."""
    return DISTRIBUTIONS.get(name)


def check_param(code: int, value: float, name: str = "") -> None:
    """Raise ``ValueError`` unless the width parameter is finite and > 0."""
    label = name or _ENTRIES[code].param
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{label} must be finite and > 0 for the {_ENTRIES[code].name} "
                         f"distribution, got {value!r}")


# --------------------------------------------------------------------------------------------
# scalar parts
# --------------------------------------------------------------------------------------------
# Inlined (``@jit(inline=True)``) and free of libm calls (exp, log and acos from
# roughbrdf._kernels.vmath), so that the model loops that call them vectorize; with a literal
# ``code`` (the model drivers) the other distributions' branches compile away.
@jit(inline=True)
def peak(code, c, a):
    """Peak-normalized shape ``P`` at ``cos theta_h = c`` for distribution ``code``, width ``a``."""
    c = min(1.0, max(0.0, c))
    s2 = 1.0 - c * c
    if code == TR:
        r = a * a / (a * a * c * c + s2)  # e^4/q^2 as (e^2/q)^2: exactly 1 at c = 1
        return r * r
    if code == BERRY:
        return a * a / (a * a * c * c + s2)
    if code == GAUSS_ANGLE:
        x = a * vacos(c) * _DEG
        return vexp(-x * x)
    # Beckmann/Sirohi: exp(-A tan^2) beats any power of 1/cos at grazing, the limit is 0; below
    # c = 1e-150, tan^2 > 1e300 and the value underflows for every width parameter in range.
    # (cc: a stand-in on those lanes, so that nothing below divides by 0 or takes log(0).)
    grazing = c < 1e-150
    cc = 1.0 if grazing else c
    t2 = s2 / (cc * cc)
    # exp(-x tan^2) / cos^p as one exponential: for tiny c, cos^p underflows to 0 (0/0 in the
    # quotient) while the exponent goes to -inf first, so the log form gives the limit 0.
    lc = vlog(cc)
    if code == BECKMANN:
        v = vexp(-t2 / (a * a) - 4.0 * lc)
    else:  # SIROHI
        v = vexp(-a * t2 - 2.0 * lc)
    return 0.0 if grazing else v


@jit(inline=True)
def lambda_cos(code, c, a):
    """Smith ``Lambda(theta) * cos(theta)`` at ``cos theta = c`` (finite at grazing).

    Trowbridge-Reitz/GGX: ``Lambda = (-1 + sqrt(1 + a^2 tan^2))/2`` (Walter et al. 2007, Eq. 72);
    Beckmann: ``Lambda = (erf(u) - 1)/2 + exp(-u^2)/(2 u sqrt(pi))``, ``u = 1/(m tan)`` (Eq. 27).
    Multiplying by ``cos theta`` removes the ``1/u`` pole at grazing.
    """
    c = min(1.0, max(0.0, c))
    s = math.sqrt(1.0 - c * c)
    if code == TR:
        return 0.5 * (math.sqrt(c * c + a * a * s * s) - c)
    # BECKMANN, u = c/(a s). a s = 0 (s = 0, the normal direction, or a s underflowing):
    # u = inf, no masking, Lambda = 0 (returned below). The stand-in denominator keeps that
    # lane free of a division by 0, whose flag the ufunc front ends would report as a warning.
    den = a * s
    u = c / (den if den > 0.0 else 1.0)
    # erfc instead of erf - 1 (no cancellation); Lambda >= 0, so clip the round-off below 0
    lam = max(0.0, 0.5 * den * vexp(-u * u) / _SQRT_PI - 0.5 * c * verfc(u))
    return lam if den > 0.0 else 0.0


@ufunc(3)
def _peak(code, c, a):
    return peak(int(code), c, a)


# --------------------------------------------------------------------------------------------
# normalization (Python level, once per parameter value)
# --------------------------------------------------------------------------------------------
@functools.lru_cache(maxsize=4096)
def _numeric_norm(code: int, a: float) -> float:
    from scipy import integrate  # imported here: SciPy costs start-up time most users never need

    def integrand(alpha: float) -> float:
        c = math.cos(alpha)
        return 2 * math.pi * float(_peak(code, c, a)) * c * math.sin(alpha)

    width = 1.0 / (a * _DEG) if code == GAUSS_ANGLE else math.atan(1.0 / math.sqrt(a))
    pts = [p for p in (0.5 * width, width, 3 * width) if p < 0.5 * math.pi]
    val, _ = integrate.quad(integrand, 0.0, 0.5 * math.pi, points=pts or None, limit=200,
                            epsabs=0.0, epsrel=1e-12)
    return 1.0 / val


def normalization(code: int, a: float) -> float:
    """Constant ``K`` with ``D = K P`` and ``∫ D cos(theta_h) dω = 1`` (sr⁻¹)."""
    if code == TR or code == BECKMANN:
        return 1.0 / (math.pi * a * a)
    if code == BERRY:
        x = a * a - 1.0
        # x / ln(1 + x) -> 1 as e -> 1; log1p keeps it accurate near e = 1.
        ratio = 1.0 if abs(x) < 1e-12 else x / math.log1p(x)
        return ratio / (math.pi * a * a)
    return _numeric_norm(int(code), float(a))


@jit(inline=True)
def trowbridge_reitz_d(c, e):
    """Scalar part: normalized Trowbridge-Reitz/GGX ``e^2/(pi (e^2 c^2 + 1 - c^2)^2)``.

    The same value as ``evaluate_d(TR, c, e, 1/(pi e^2))``, as a small inlined part for the TR75
    kernel (docs/models.md §3.7).
    """
    c = min(1.0, max(0.0, c))
    q = e * e * c * c + (1.0 - c * c)
    return e * e / (math.pi * q * q)


@jit(inline=True)
def evaluate_d(code, c, a, norm):
    """Scalar part: normalized ``D = norm * P(c)`` (``norm`` from :func:`normalization`)."""
    return norm * peak(code, c, a)


# --------------------------------------------------------------------------------------------
# NumPy front ends
# --------------------------------------------------------------------------------------------
def _check_cos(c: ArrayLike) -> np.ndarray:
    arr = as_float_array(c, "cos_theta_h")
    bad = ~np.isfinite(arr) | (arr < 0) | (arr > 1)
    if bad.any():
        raise ValueError(f"cos_theta_h must be in [0, 1], got {arr[bad].flat[0]!r}")
    return arr


def evaluate(name: str, cos_theta_h: ArrayLike, param: float, *, peak_normalized: bool = False
             ) -> np.ndarray:
    """Evaluate a registered distribution by name at ``cos(theta_h)``.

    With ``peak_normalized=True`` return the shape ``P`` with ``P(0) = 1`` (TR75 Fig. 5);
    otherwise the normalized density ``D`` (sr⁻¹).
    """
    d = get(name)
    param = float(param)
    check_param(d.code, param)
    c = _check_cos(cos_theta_h)
    p = _peak(d.code, c, param)
    return p if peak_normalized else p * normalization(d.code, param)


def trowbridge_reitz(cos_theta_h: ArrayLike, e: float) -> np.ndarray:
    """TR75 ellipsoid distribution = GGX with ``alpha = e``, normalized (TR75 Eqs. 30-31).

    ``D = e^2 / (pi (e^2 cos^2 theta_h + sin^2 theta_h)^2)`` sr⁻¹.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> round(float(rb.distributions.trowbridge_reitz(1.0, 0.5)), 6)  # 1/(pi e^2)
    1.27324
    """
    return evaluate("trowbridge-reitz", cos_theta_h, e)


ggx = trowbridge_reitz


def beckmann(cos_theta_h: ArrayLike, m: float) -> np.ndarray:
    """Beckmann distribution ``exp(-tan^2/m^2) / (pi m^2 cos^4)`` sr⁻¹."""
    return evaluate("beckmann", cos_theta_h, m)


def gaussian_angle(theta_h: ArrayLike, c: float) -> np.ndarray:
    """TS67 Eq. 5 ``b0 exp(-(c alpha)^2)`` with ``alpha = theta_h`` in degrees, ``c`` per degree.

    ``theta_h`` is in radians; ``b0`` is computed so that ``∫ D cos dω = 1`` (2.8316 sr⁻¹ for
    c = 0.05/deg, docs/models.md §2.3).
    """
    th = as_float_array(theta_h, "theta_h")
    bad = ~np.isfinite(th) | (th < 0) | (th > 0.5 * math.pi)
    if bad.any():
        raise ValueError(f"theta_h must be in [0, pi/2], got {th[bad].flat[0]!r}")
    return evaluate("gaussian-angle", np.cos(th), c)


def berry(cos_theta_h: ArrayLike, e: float) -> np.ndarray:
    """Berry's distribution (TR75 Fig. 5), normalized."""
    return evaluate("berry", cos_theta_h, e)


def sirohi(cos_theta_h: ArrayLike, A2: float) -> np.ndarray:  # noqa: N803 - paper's symbol
    """Sirohi's distribution ``cos^-2 exp(-A2 tan^2)`` (TR75 Fig. 5, p = 2), normalized."""
    return evaluate("sirohi", cos_theta_h, A2)


@ufunc(3)
def _lambda(code, c, a):
    code = int(code)
    if c <= 0.0:
        return math.inf  # Lambda itself diverges at grazing; Lambda*cos stays finite
    return lambda_cos(code, c, a) / c


def lambda_smith(name: str, cos_theta: ArrayLike, param: float) -> np.ndarray:
    """Smith's ``Lambda(theta)`` for a distribution that has one (Trowbridge-Reitz, Beckmann)."""
    d = get(name)
    if not d.smith:
        raise ValueError(f"the {d.name} distribution has no analytic Smith Lambda; use "
                         "'trowbridge-reitz' or 'beckmann', or shadowing='v-groove'")
    check_param(d.code, float(param))
    return _lambda(d.code, _check_cos(cos_theta), float(param))
