"""Shadowing/masking: TS67 V-groove and Smith (separable and height-correlated).

Registered names (:func:`get`): ``v-groove`` (alias ``torrance-sparrow``, ``ts67``, ``v-cavity``),
``smith-separable`` (alias ``smith-uncorrelated``), ``smith-height-correlated`` (alias ``smith``),
``none``.

Models never use ``G`` alone: they need ``G/(cos theta_i cos theta_r)`` (microfacet form) or
``G/cos theta_r`` (TS67 Eq. 13), which both have finite limits at grazing angles while the
quotient computed naively is 0/0. The scalar parts here return those quotients *per branch*.

TS67 V-groove
-------------
Table I of Torrance & Sparrow (1967) with Eq. 21, in the projected angles (psi_p, theta_p) of
:func:`roughbrdf.geometry.ts67_projected`, is identical (MODELS.md §2.5, verified to 1e-12) to
the 3-D "V-cavity" closed form

.. math::  G = \\min\\{1,\\ 2\\cos\\theta_h\\cos\\theta_r/\\cos\\theta_d,\\
           2\\cos\\theta_h\\cos\\theta_i/\\cos\\theta_d\\}.

The closed form is what the models use; :func:`v_groove_table` keeps the paper's piecewise
Table I as an independent implementation (and test oracle).

Smith
-----
``G1 = 1/(1 + Lambda)``; separable ``G = G1(i) G1(r)``; height-correlated
``G = 1/(1 + Lambda_i + Lambda_r)`` (Heitz 2014, Eqs. 98-99). ``Lambda`` comes from
:mod:`roughbrdf.distributions`.
"""

from __future__ import annotations

import difflib
import math

import numpy as np
from numpy.typing import ArrayLike

from . import distributions as _dist
from ._jit import as_float_array, jit, ufunc
from .geometry import check_angles, half_vector, ts67_projected

__all__ = [
    "NONE",
    "V_GROOVE",
    "SMITH_SEPARABLE",
    "SMITH_HEIGHT_CORRELATED",
    "get",
    "names",
    "v_groove",
    "v_groove_table",
    "g21",
    "smith_g1",
    "smith",
    "g_over_cos_r",
    "g_over_cos_cos",
]

NONE, V_GROOVE, SMITH_SEPARABLE, SMITH_HEIGHT_CORRELATED = 0, 1, 2, 3
_NAMES = {
    "none": NONE, "no": NONE, "off": NONE,
    "v-groove": V_GROOVE, "torrance-sparrow": V_GROOVE, "ts67": V_GROOVE, "v-cavity": V_GROOVE,
    "smith-separable": SMITH_SEPARABLE, "smith-uncorrelated": SMITH_SEPARABLE,
    "smith-height-correlated": SMITH_HEIGHT_CORRELATED, "smith": SMITH_HEIGHT_CORRELATED,
}
_CANONICAL = {NONE: "none", V_GROOVE: "v-groove", SMITH_SEPARABLE: "smith-separable",
              SMITH_HEIGHT_CORRELATED: "smith-height-correlated"}


def names() -> list[str]:
    """Canonical shadowing names."""
    return list(_CANONICAL.values())


def get(name: str | None) -> int:
    """Code of a shadowing function by name or alias (``None`` means ``"none"``)."""
    if name is None:
        return NONE
    key = str(name).strip().lower().replace("_", "-").replace(" ", "-")
    if key in _NAMES:
        return _NAMES[key]
    close = difflib.get_close_matches(key, list(_NAMES), n=3, cutoff=0.5)
    hint = f"; did you mean {', '.join(repr(c) for c in close)}?" if close else ""
    raise ValueError(f"unknown shadowing {name!r}{hint} (known: {', '.join(names())})")


def canonical(code: int) -> str:
    """Canonical name of a shadowing code."""
    return _CANONICAL[code]


# --------------------------------------------------------------------------------------------
# scalar parts
# --------------------------------------------------------------------------------------------
@jit
def _safe_div(a, b):
    # used where the quotient is a candidate of a min(): a zero denominator means "no bound"
    return a / b if b > 0.0 else math.inf


@jit
def v_groove_g(ci, cr, ch, cd):
    """Scalar TS67 V-groove G from cosines (closed form, MODELS.md §2.5)."""
    if cd <= 0.0:
        return 0.0  # w_i = -w_r (grazing, opposite): nothing reflects
    return min(1.0, 2.0 * ch * cr / cd, 2.0 * ch * ci / cd)


@jit
def v_groove_g_over_cos_r(ci, cr, ch, cd):
    """Scalar ``G/cos(theta_r)`` per branch (TS67; finite at theta_r = 90 deg, MODELS.md §2.5).

    G = 1: ``1/cos theta_r``; masking: ``2 cos theta_h/cos theta_d`` (no division by
    cos theta_r); shadowing: ``2 cos theta_h cos theta_i/(cos theta_d cos theta_r)``.
    """
    if cd <= 0.0:
        return 0.0
    masking = 2.0 * ch / cd
    if cr <= 0.0:
        return masking  # the G=1 and shadowing candidates are +inf at theta_r = 90 deg
    return min(1.0 / cr, masking, masking * ci / cr)


@jit
def g21(psi_p, theta_p):
    """TS67 Eq. 21 in the cancellation-free form ``G = 1 - A/(1 + sqrt(1 - A^2))``."""
    hd = 0.5 * (theta_p - psi_p)
    c2 = math.cos(hd) ** 2
    st2 = math.sin(theta_p) ** 2
    den = c2 - math.cos(theta_p - psi_p) * st2
    if den == 0.0:
        return 0.0  # A -> infinity only at the boundary theta_p = +-pi/2, where G = 0
    a = (st2 - c2) / den
    # clip 1 - A^2 >= 0: round-off can push |A| slightly above 1 at theta_p = +-pi/2
    return 1.0 - a / (1.0 + math.sqrt(max(0.0, 1.0 - a * a)))


@jit
def v_groove_table_g(psi_p, theta_p):
    """TS67 Table I, piecewise, in projected angles (psi_p >= 0, theta_p signed)."""
    upper = (psi_p + math.pi) / 3.0  # Eq. 17
    if psi_p <= 0.25 * math.pi:
        lower = (psi_p - math.pi) / 3.0  # Eq. 18
        if theta_p < lower or theta_p > upper:
            return g21(psi_p, theta_p)
        return 1.0
    if theta_p > upper:
        return g21(psi_p, theta_p)  # masking
    if theta_p < -psi_p:
        return g21(psi_p, theta_p)  # masking-shadowing: masking dominates
    if theta_p < 3.0 * psi_p - math.pi:  # Eq. 19
        return g21(theta_p, psi_p)  # pure shadowing (reverse path)
    return 1.0


@jit
def smith_g_over_cos_cos(code, dcode, a, ci, cr):
    """Scalar Smith ``G/(cos theta_i cos theta_r)`` (finite at grazing).

    Separable: ``1/[(ci + L_i)(cr + L_r)]``; height-correlated:
    ``1/(ci cr + cr L_i + ci L_r)``, with ``L = Lambda cos`` from the distribution.
    """
    li = _dist.lambda_cos(dcode, ci, a)
    lr = _dist.lambda_cos(dcode, cr, a)
    if code == SMITH_SEPARABLE:
        den = (ci + li) * (cr + lr)
    else:
        den = ci * cr + cr * li + ci * lr
    if den <= 0.0:
        return 0.0  # both directions exactly grazing: fully masked
    return 1.0 / den


@jit
def g_over_cos_cos(code, dcode, a, ci, cr, ch, cd):
    """Scalar ``G/(cos theta_i cos theta_r)`` for shadowing ``code`` (NONE gives 1/(ci cr))."""
    if code == NONE:
        den = ci * cr
        return 1.0 / den if den > 0.0 else math.inf  # the no-shadowing form diverges: limit inf
    if code == V_GROOVE:
        if ci <= 0.0:
            # G <= 2 ch ci/cd -> G/ci <= 2 ch/cd: the shadowing candidate stays finite
            return _safe_div(2.0 * ch, cd * cr) if cd > 0.0 else 0.0
        return v_groove_g_over_cos_r(ci, cr, ch, cd) / ci
    return smith_g_over_cos_cos(code, dcode, a, ci, cr)


# --------------------------------------------------------------------------------------------
# NumPy front ends
# --------------------------------------------------------------------------------------------
@ufunc(3)
def _v_groove(ti, tr, phi):
    hx, hy, hz, cd, ci, cr, si = half_vector(ti, tr, phi)
    return v_groove_g(ci, cr, hz, cd)


@ufunc(3)
def _v_groove_table(ti, tr, phi):
    psi_p, theta_p, _ = ts67_projected(ti, tr, phi)
    return v_groove_table_g(psi_p, theta_p)


@ufunc(3)
def _v_groove_over_cos_r(ti, tr, phi):
    hx, hy, hz, cd, ci, cr, si = half_vector(ti, tr, phi)
    return v_groove_g_over_cos_r(ci, cr, hz, cd)


def v_groove(theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike) -> np.ndarray:
    """TS67 geometrical attenuation factor G (V-groove), anywhere on the hemisphere.

    Examples
    --------
    >>> import numpy as np, roughbrdf as rb
    >>> float(rb.shadowing.v_groove(np.radians(30), np.radians(30), 0.0))  # specular: G = 1
    1.0
    """
    return _v_groove(*check_angles(theta_i, theta_r, phi))


def v_groove_table(theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike) -> np.ndarray:
    """TS67 G from the paper's Table I and Eq. 21 (projected angles; independent of v_groove)."""
    return _v_groove_table(*check_angles(theta_i, theta_r, phi))


def g_over_cos_r(theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike) -> np.ndarray:
    """TS67 ``G/cos(theta_r)`` evaluated per branch (the factor plotted in TS67 Fig. 7)."""
    return _v_groove_over_cos_r(*check_angles(theta_i, theta_r, phi))


@ufunc(4)
def _g1(dcode, a, c, _unused):
    lc = _dist.lambda_cos(int(dcode), c, a)
    den = c + lc
    return c / den if den > 0.0 else 0.0


def smith_g1(cos_theta: ArrayLike, alpha: float, distribution: str = "trowbridge-reitz"
             ) -> np.ndarray:
    """Smith monostatic masking ``G1 = 1/(1 + Lambda)`` (= ``cos/(cos + Lambda cos)``)."""
    d = _dist.get(distribution)
    if not d.smith:
        raise ValueError(f"the {d.name} distribution has no Smith Lambda")
    _dist.check_param(d.code, float(alpha), "alpha")
    c = as_float_array(cos_theta, "cos_theta")
    if np.any(~np.isfinite(c) | (c < 0) | (c > 1)):
        raise ValueError(f"cos_theta must be in [0, 1], got {c[~((c >= 0) & (c <= 1))].flat[0]!r}")
    return _g1(d.code, float(alpha), c, 0.0)


@ufunc(5)
def _smith_g(code, dcode, a, ci, cr):
    return smith_g_over_cos_cos(int(code), int(dcode), a, ci, cr) * ci * cr


def smith(theta_i: ArrayLike, theta_r: ArrayLike, alpha: float,
          distribution: str = "trowbridge-reitz", kind: str = "smith-height-correlated"
          ) -> np.ndarray:
    """Smith bidirectional G, separable or height-correlated (``kind``)."""
    code = get(kind)
    if code not in (SMITH_SEPARABLE, SMITH_HEIGHT_CORRELATED):
        raise ValueError(f"kind must be a Smith variant, got {kind!r}")
    d = _dist.get(distribution)
    if not d.smith:
        raise ValueError(f"the {d.name} distribution has no Smith Lambda")
    _dist.check_param(d.code, float(alpha), "alpha")
    ti, tr, _ = check_angles(theta_i, theta_r, 0.0)
    return _smith_g(code, d.code, float(alpha), np.cos(ti), np.cos(tr))
