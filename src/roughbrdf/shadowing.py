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
:func:`roughbrdf.geometry.ts67_projected`, is identical (docs/models.md §2.5, verified to 1e-12) to
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

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from . import distributions as _dist
from . import special as _special
from ._kernels import TINY, as_float_array, jit, ufunc
from .geometry import check_angles, half_vector, ts67_projected
from .registry import Registry

__all__ = [
    "Shadowing",
    "SHADOWING",
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
    "V",
    "Vm",
    "rb08_v",
    "rb08_vm",
    "rb08_e0",
]

NONE, V_GROOVE, SMITH_SEPARABLE, SMITH_HEIGHT_CORRELATED = 0, 1, 2, 3


@dataclass(frozen=True)
class Shadowing:
    """A registered shadowing function: its canonical name and the code the kernels take."""

    name: str
    code: int
    description: str
    reference: str
    aliases: tuple[str, ...] = ()


_ENTRIES = [
    Shadowing("none", NONE, "no shadowing or masking, G = 1", "", ("no", "off")),
    Shadowing("v-groove", V_GROOVE, "V-groove (V-cavity) geometrical attenuation factor",
              "Torrance & Sparrow 1967, Table I", ("torrance-sparrow", "ts67", "v-cavity")),
    Shadowing("smith-separable", SMITH_SEPARABLE, "Smith G1(i) G1(r), uncorrelated",
              "Smith 1967; Heitz 2014, Eq. 98", ("smith-uncorrelated",)),
    Shadowing("smith-height-correlated", SMITH_HEIGHT_CORRELATED,
              "Smith height-correlated 1/(1 + Lambda(i) + Lambda(r))", "Heitz 2014, Eqs. 98-99",
              ("smith",)),
]

#: every shadowing function by canonical name and alias (:class:`roughbrdf.registry.Registry`)
SHADOWING: Registry[Shadowing] = Registry("shadowing")
for _s in _ENTRIES:
    SHADOWING.add(_s.name, _s, _s.aliases)


def names() -> list[str]:
    """Canonical shadowing names."""
    return SHADOWING.names()


def get(name: str | None) -> Shadowing:
    """A shadowing function by name or alias (``None`` means ``"none"``)."""
    return SHADOWING.get("none" if name is None else name)


def canonical(code: int | Shadowing) -> str:
    """Canonical name of a shadowing entry or code."""
    return _ENTRIES[code.code if isinstance(code, Shadowing) else int(code)].name


# --------------------------------------------------------------------------------------------
# scalar parts
# --------------------------------------------------------------------------------------------
@jit(inline=True)
def v_groove_g(ci, cr, ch, cd):
    """Scalar TS67 V-groove G from cosines (closed form, docs/models.md §2.5)."""
    if cd <= 0.0:
        return 0.0  # w_i = -w_r (grazing, opposite): nothing reflects
    # + TINY: compiled code may evaluate this side also when cd = 0 (roughbrdf._kernels.vmath.TINY)
    return min(1.0, 2.0 * ch * cr / (cd + TINY), 2.0 * ch * ci / (cd + TINY))


@jit(inline=True)
def v_groove_g_over_cos_r(ci, cr, ch, cd):
    """Scalar ``G/cos(theta_r)`` per branch (TS67; finite at theta_r = 90 deg, docs/models.md §2.5).

    With ``m = 2 cos theta_h/cos theta_d``, ``G = min(1, m cos theta_r, m cos theta_i)``, so
    ``G/cos theta_r`` is, per branch: G = 1: ``1/cos theta_r``; masking (``cr <= ci``): ``m``
    (no division by cos theta_r); shadowing: ``m cos theta_i/cos theta_r``. The branch is
    picked by comparing products (G = 1 iff ``cd <= 2 ch min(ci, cr)``) and the chosen
    quotient formed with one division: vectorizable and cheaper than the minimum of the three
    quotients, which it equals to rounding (the candidates meet continuously at the branch
    boundaries).
    """
    g1 = cd <= 2.0 * ch * min(ci, cr)  # G = 1 (the cd <= 0 lanes are replaced by 0 below)
    masking = cr <= ci
    num = 1.0 if g1 else (2.0 * ch if masking else 2.0 * ch * ci)
    den = cr if g1 else (cd if masking else cd * cr)
    # den > 0 on every lane used (g1 needs cr > 0, shadowing cr > ci >= 0); the stand-in 1
    # keeps the cd <= 0 lanes (w_i = -w_r, nothing reflects: 0) free of a division by 0
    q = num / (den if den > 0.0 else 1.0)
    return q if cd > 0.0 else 0.0


@jit(inline=True)
def v_groove_g_over_cos_cos(ci, cr, ch, cd):
    """Scalar TS67 ``G/(cos theta_i cos theta_r)`` per branch (microfacet and absolute forms).

    ``G/(ci cr) = min(1/(ci cr), m/ci, m/cr) = min(1/(ci cr), m/max(ci, cr))`` with
    ``m = 2 cos theta_h/cos theta_d``: the G = 1 branch (``cd <= 2 ch min(ci, cr)``) gives
    ``1/(ci cr)``, the others ``2 ch/(cd max(ci, cr))``, which divides only by the larger
    cosine and stays finite when the smaller one is 0. Symmetric in (i, r); one division.
    Finite unless both directions are exactly grazing, where the limit is ``inf`` (0 if
    nothing reflects, ``cd = 0`` or ``ch = 0``).
    """
    small = min(ci, cr)
    big = max(ci, cr)
    g1 = cd <= 2.0 * ch * small  # G = 1 (the cd <= 0 lanes are replaced by 0 below)
    num = 1.0 if g1 else 2.0 * ch
    den = small * big if g1 else cd * big
    # den = 0: both directions grazing (big = 0), the limit inf of a positive numerator; the
    # stand-in 1 keeps that lane free of a division by 0
    q = num / (den if den > 0.0 else 1.0)
    q = q if den > 0.0 else (math.inf if num > 0.0 else 0.0)
    return q if cd > 0.0 else 0.0  # w_i = -w_r (grazing, opposite): nothing reflects


@jit
def g21(psi_p, theta_p):
    """TS67 Eq. 21 in the cancellation-free form ``G = 1 - A/(1 + sqrt(1 - A^2))``."""
    hd = 0.5 * (theta_p - psi_p)
    ch = math.cos(hd)
    c2 = ch * ch
    st = math.sin(theta_p)
    st2 = st * st
    den = c2 - math.cos(theta_p - psi_p) * st2
    if den == 0.0:
        return 0.0  # A -> infinity only at the boundary theta_p = +-pi/2, where G = 0
    a = (st2 - c2) / den
    # 1 - A^2 without cancellation near |A| = 1 (theta_p -> +-pi/2): with
    # 1 + cos(theta_p - psi_p) = 2 cos^2(hd), one finds 1 - A = 2 cos^2(hd) cos^2(theta_p)/den
    # and 1 + A = 2 sin^2(theta_p) sin^2(hd)/den, so sqrt(1 - A^2) is the product below.
    root = abs(2.0 * ch * math.cos(theta_p) * st * math.sin(hd) / den)
    # G in [0, 1] (the minus root of Eq. 21a); round-off at the boundaries (A = 0, A = 1)
    # can step outside
    return min(1.0, max(0.0, 1.0 - a / (1.0 + min(1.0, root))))


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


@jit(inline=True)
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
    # den <= 0: both directions exactly grazing, fully masked (0); the stand-in 1 keeps that
    # lane free of a division by 0 (compiled code computes both sides of the select)
    q = 1.0 / (den if den > 0.0 else 1.0)
    return q if den > 0.0 else 0.0


@jit(inline=True)
def g_over_cos_cos(code, dcode, a, ci, cr, ch, cd):
    """Scalar ``G/(cos theta_i cos theta_r)`` for shadowing ``code`` (NONE gives 1/(ci cr))."""
    if code == NONE:
        den = ci * cr
        # the no-shadowing form diverges at grazing: limit inf (stand-in 1: no division by 0)
        q = 1.0 / (den if den > 0.0 else 1.0)
        return q if den > 0.0 else math.inf
    if code == V_GROOVE:
        return v_groove_g_over_cos_cos(ci, cr, ch, cd)
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
    return min(1.0, smith_g_over_cos_cos(int(code), int(dcode), a, ci, cr) * ci * cr)


def smith(theta_i: ArrayLike, theta_r: ArrayLike, alpha: float,
          distribution: str = "trowbridge-reitz", kind: str = "smith-height-correlated"
          ) -> np.ndarray:
    """Smith bidirectional G, separable or height-correlated (``kind``)."""
    code = get(kind).code
    if code not in (SMITH_SEPARABLE, SMITH_HEIGHT_CORRELATED):
        raise ValueError(f"kind must be a Smith variant, got {kind!r}")
    d = _dist.get(distribution)
    if not d.smith:
        raise ValueError(f"the {d.name} distribution has no Smith Lambda")
    _dist.check_param(d.code, float(alpha), "alpha")
    ti, tr, _ = check_angles(theta_i, theta_r, 0.0)
    return _smith_g(code, d.code, float(alpha), np.cos(ti), np.cos(tr))


# --------------------------------------------------------------------------------------------
# RB08: Renhorn & Boreman (2008) shadowing V (Eqs. 10-12) and masking multiplier Vm (Eqs. 13-15)
# --------------------------------------------------------------------------------------------
# docs/models.md §4.7-4.8. The scalar parts are used inside the RB08 model kernel
# (roughbrdf.models.renhorn_boreman); V and Vm below are their NumPy front ends.


@jit
def rb08_v(chi, scale, a, st):
    """Scalar RB08 shadowing ``V = Q(a, scale chi^2)`` (Eq. 10), fast arguments.

    ``a = 1 + n``, ``scale = (1 + n)/w^2`` and ``st = stirlerr(a)`` are precomputed once per
    parameter set; ``Q`` is :func:`roughbrdf.special.gammaincc_q` (exp for n = 0, a finite sum
    for integer n, series/continued fraction otherwise).
    """
    return _special.gammaincc_q(a, scale * chi * chi, st)


@jit(inline=True)
def rb08_e0(zeta0, gamma, delta):
    """Scalar ``E0 = exp(-gamma zeta0 exp(-delta zeta0^2))``, the incidence weight of Eq. 13."""
    return _special.vexp(-gamma * zeta0 * _special.vexp(-delta * zeta0 * zeta0))


@jit(inline=True)
def rb08_vm(zeta, e0, alpha2, w_a, w_b):
    """Scalar RB08 masking/shadowing multiplier Vm (Eq. 13) given ``E0`` (:func:`rb08_e0`).

    ``B = exp(-w_a zeta exp(-w_b alpha^2))``; Eq. 13 with ``Sgn`` is, piecewise,
    ``zeta < 0: B``; ``zeta > 0: 1 - E0 (1 - B)``; ``zeta = 0 (Sgn 0 = 0): (1 - E0 + B + B E0)/2``
    (= 1, since B = 1 there: Vm is continuous). Branch-free (selects, vectorizable exp).
    """
    b = _special.vexp(-w_a * zeta * _special.vexp(-w_b * alpha2))
    pos = 1.0 + e0 * (b - 1.0)  # 1 - E0 (1 - B); within an ulp of Vm even when B ~ 1
    # zeta = 0: B = exp(0) = 1, and the literal Sgn(0) = 0 value (1 - E0 + B + B E0)/2 is 1
    vm = b if zeta < 0.0 else (pos if zeta > 0.0 else 1.0)
    return 1.0 if w_a == 0.0 else vm  # w_a = 0: B = 1 exactly and every branch of Eq. 13 is 1


@ufunc(3)
def _rb08_v_ufunc(chi, w, n):
    a = 1.0 + n
    return rb08_v(chi, a / (w * w), a, _special.stirlerr(a))


@ufunc(7)
def _rb08_vm_ufunc(zeta, zeta0, alpha, w_a, w_b, gamma, delta):
    return rb08_vm(zeta, rb08_e0(zeta0, gamma, delta), alpha * alpha, w_a, w_b)


def _finite(x: ArrayLike, name: str) -> np.ndarray:
    arr = as_float_array(x, name)
    bad = ~np.isfinite(arr)
    if bad.any():
        raise ValueError(f"{name} must be finite, got {arr[bad].flat[0]!r}")
    return arr


def V(chi: ArrayLike, w: ArrayLike, n: ArrayLike) -> np.ndarray:
    """RB08 shadowing function ``V(chi, w, n) = Γ(1+n, (1+n) chi²/w²)/Γ(1+n)`` (Eq. 10).

    The regularized upper incomplete gamma ``Q(1+n, (1+n) chi²/w²)`` for real ``n >= 0``
    (``n!`` of the paper read as ``Γ(1+n)``). ``chi`` is a sine of a zenith angle (RB08 uses
    ``sin theta_i`` and ``sin theta_s``), ``w > 0`` the cut-off and ``n`` the sharpness:
    ``V(0) = 1``, ``V(chi, w, 0) = exp(-chi²/w²)`` (Eq. 11), ``V(w) -> 1/2`` and
    ``V -> [chi < w]`` as ``n -> inf``. Arrays broadcast.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> round(float(rb.shadowing.V(0.5, 0.8, 0.0)), 12)      # exp(-0.25/0.64), Eq. 11
    0.676633846161
    """
    c = _finite(chi, "chi")
    wa = _finite(w, "w")
    na = _finite(n, "n")
    if np.any(wa <= 0):
        raise ValueError(f"w must be > 0, got {wa[wa <= 0].flat[0]!r}")
    if np.any(na < 0):
        raise ValueError(f"n must be >= 0, got {na[na < 0].flat[0]!r}")
    return _rb08_v_ufunc(c, wa, na)


def Vm(zeta: ArrayLike, zeta0: ArrayLike, w_a: ArrayLike, w_b: ArrayLike, gamma: ArrayLike,
       delta: ArrayLike, alpha: ArrayLike | None = None) -> np.ndarray:
    """RB08 masking/shadowing multiplier ``Vm(zeta, zeta0, w_a, w_b, gamma, delta)`` (Eq. 13).

    With the recommended signs (docs/models.md §4.8) ``E0 = exp(-gamma zeta0 exp(-delta zeta0²))``
    and ``B = exp(-w_a zeta exp(-w_b alpha²))``::

        Vm = 1/2 (1 - E0) [Sgn(zeta) + 1] + B {1/2 [1 - Sgn(zeta)] + 1/2 E0 [Sgn(zeta) + 1]}

    i.e. ``B`` for ``zeta < 0``, ``1 - E0 (1 - B)`` for ``zeta > 0`` and 1 at ``zeta = 0``.
    ``alpha`` is the direction cosine in B's exponent; by default ``sin(zeta)``, its in-plane
    value under the recommended reading (zeta = signed in-plane scattering angle, radians).
    ``E0 <= 1`` (hence ``Vm > 0``) needs ``gamma zeta0 >= 0``. Arrays broadcast.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> float(rb.shadowing.Vm(0.0, 0.5, 1.0, 1.0, 1.0, 1.0))   # continuous, Vm(0) = 1
    1.0
    """
    z = _finite(zeta, "zeta")
    al = np.sin(z) if alpha is None else _finite(alpha, "alpha")
    return _rb08_vm_ufunc(z, _finite(zeta0, "zeta0"), al, _finite(w_a, "w_a"),
                          _finite(w_b, "w_b"), _finite(gamma, "gamma"), _finite(delta, "delta"))
