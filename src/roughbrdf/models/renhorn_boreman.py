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

Kernels (all compiled with Numba, parallel over samples):

* **fast** (integer ``n, n_r <= 16``, e.g. the defaults; one polarization for all samples;
  analytic N): a branch-free loop that LLVM vectorizes (AVX2/AVX-512): V by a fixed-length
  finite sum, ``exp/log/asin`` from :mod:`roughbrdf.special`, ``sin/cos`` from
  :func:`roughbrdf._kernels.vmath.sincos`. A *lean* variant drops Vm (``w_a = 0``) and the second
  shadowing pair (``w_r, n_r = w, n``). With a scalar ``theta_i`` every incidence quantity is
  hoisted out of the loop. Measured (1e6 random geometries, 2 cores, defaults): ~6e7
  evaluations/s (3.7e7 on one core).
* **tabulated** (any real n, or numeric N; one polarization): V by the general incomplete
  gamma (series/continued fraction, loops), but once per distinct angle: a first loop fills
  ``V(sin theta_i)``, ``V(sin theta_s)`` per sample through a small memo keyed on the angle
  (a fit's data repeat a few dozen angles), then the vectorized loop of the fast kernel reads
  them. Measured on a Mini-Diff channel (10,804 geometries, 4 incidences, 76 reflection
  angles; 2 cores): 0.27 ms per evaluation, against 1.6 ms for the general kernel (which,
  until 2026-12, ran every fit with non-integer n: over 80 % of a 14-parameter fit's time).
* **general** (per-sample polarization, and :meth:`RenhornBoreman2008.with_general_kernel`,
  the reference): the incomplete gamma per sample (loops: not vectorized); the
  incidence-only quantities (``sin/cos theta_i``, ``R(alpha0)``, ``V(alpha0)``, ``N``,
  ``E0``) are recomputed only when ``theta_i`` changes within a chunk of 1024 samples.
  ~1e6-4e6 evaluations/s.

All three give the same numbers (tested to 1e-13; the tabulated and general kernels agree
bit for bit on the data measured).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numba import prange

from .. import _kernels, special
from .. import shadowing as shd
from .._kernels import at, driver, jit, sincos
from ..fresnel import check_index, fresnel_sp
from ..registry import Registry
from .base import Model, PreparedGeometry, register
from .parameters import Parameter, nonnegative, positive, reflectance

__all__ = ["RenhornBoreman2008", "rb08_norm", "lobe_integral"]

# ---- layout of the packed parameter tuple -------------------------------------------------
(_RHO, _W, _N, _WA, _WB, _GAM, _DEL, _NEFF, _KEFF, _BULK, _RETRO, _RHOR, _WR, _NR,
 _ZETA, _WEIGHT, _NORM, _POL, _TERM,
 _A_S, _SC_S, _ST_S, _A_R, _SC_R, _ST_R, _SAME_V, _FAST, _RAMP) = range(28)

# option codes (stored as floats in the packed tuple)
ZETA_CODES = {"angle": 0, "cosine": 1, "zenith-difference": 2}
WEIGHT_CODES = {"geometric-mean": 0, "product": 1, "transmission": 2}
NORM_CODES = {"literal": 0, "specular-width": 1, "numeric": 2}
POL_WEIGHT = {"unpolarized": 0.5, "s": 1.0, "p": 0.0}  # weight of R_s in R
TERM_CODES = {None: 0, "surface": 1, "bulk": 2, "retro": 3}
RETRO_CODES = {"width": 0, "amplitude": 1}  # where the retro V pair acts (_RAMP)

def _option(name: str, values: dict[str, tuple[str, ...]]) -> Registry[str]:
    reg: Registry[str] = Registry(f"value {{name}} for option {name!r} of model "
                                  "'renhorn-boreman-2008'")
    for canonical, aliases in values.items():
        reg.add(canonical, canonical, aliases)
    return reg


#: the readings (options) of the reconstructed model and their aliases (docs/models.md §4)
OPTION_VALUES: dict[str, Registry[str]] = {
    "zeta": _option("zeta", {"angle": ("z-a",), "cosine": ("z-b",),
                             "zenith-difference": ("z-c",)}),
    "surface_weight": _option("surface_weight", {"geometric-mean": ("sqrt", "q=1/2"),
                                                 "product": ("q=1",), "transmission": ()}),
    "normalization": _option("normalization", {"literal": (), "specular-width": (),
                                               "numeric": ()}),
    "retro_shadowing": _option("retro_shadowing", {"width": (), "amplitude": ("acceptance",)}),
    "polarization": _option("polarization", {"unpolarized": ("natural", "none"),
                                             "s": ("te", "perpendicular"),
                                             "p": ("tm", "parallel")}),
}


# --------------------------------------------------------------------------------------------
# scalar parts
# --------------------------------------------------------------------------------------------
# Every part on the hot path is branch-free (selects) and free of libm calls (sincos, vexp,
# vlog1p and vasin from roughbrdf._kernels.vmath), so that the fast driver's loop vectorizes.
# ``fast`` (a compile-time constant at each call site) selects the shadowing function: the
# vectorizable finite sum for integer n <= special.INT_HORNER_MAX, or the general incomplete
# gamma (series / continued fraction, loops) for any real n.
@jit(inline=True)
def rb08_norm(ci2, a02, rho):
    """Scalar Eq. 6/8 normalization ``N(alpha0, rho)`` from ``ci2 = 1 - alpha0^2``, ``a02``.

    ``N = 1/(pi ln(arg))``, ``arg = [A + S]/(2 rho^2)``, ``A = ci2 + rho^2``,
    ``S = sqrt(A^2 + 4 a02 rho^2)``; evaluated as ``ln(arg) = log1p((ci2 + S - rho^2)/(2 rho^2))``
    with ``S - rho^2 = (ci2^2 + 2 ci2 rho^2 + 4 a02 rho^2)/(S + rho^2)`` (no cancellation for any
    rho). ``N -> 0`` as ``rho -> 0`` (the lobe's disk integral diverges logarithmically).
    """
    r2 = rho * rho
    ok = r2 > 0.0  # rho = 0 (or underflow of rho^2): ln(arg) = inf, N = 0
    r2s = r2 if ok else 1.0
    s = math.sqrt((ci2 + r2s) * (ci2 + r2s) + 4.0 * a02 * r2s)
    t = (ci2 + (ci2 * ci2 + 2.0 * ci2 * r2s + 4.0 * a02 * r2s) / (s + r2s)) / (2.0 * r2s)
    lg = special.vlog1p(t)  # t > 0 for every direction (ci2 + a02 = 1)
    return 1.0 / (math.pi * lg) if ok else 0.0


@jit(inline=True)
def _v(chi, scale, a, st, fast):
    # RB08 V (Eq. 10): finite sum (integer n, vectorizable) or the general Q
    if fast:
        return special.gammaincc_int(a, scale * chi * chi)
    return shd.rb08_v(chi, scale, a, st)


@jit(inline=True)
def _lobe(num, den):
    # num/den for a lobe; den = 0 only at the lobe's own peak when its width vanishes (V
    # underflow for extremely sharp shadowing): the limit there is +inf (0 if num = 0).
    q = num / (den if den > 0.0 else 1.0)
    return q if den > 0.0 else (math.inf if num > 0.0 else 0.0)


@jit(inline=True)
def _incidence(ti, p, fast, lean):
    """Quantities that depend on theta_i only: (si, ci, Rs0, Rp0, V0, V0r, E0, N_s, N_r).

    ``lean`` (compile-time constant, only when ``w_a = 0`` and the retro lobe shares ``w, n``):
    skip E0 (Vm = 1) and the retro V, which the other variant computes and then selects.
    """
    si, ci = sincos(ti)
    v0 = _v(si, p[_SC_S], p[_A_S], p[_ST_S], fast)
    if lean:
        v0r = v0
    else:
        v0r = v0 if p[_SAME_V] == 1.0 else _v(si, p[_SC_R], p[_A_R], p[_ST_R], fast)
    return _incidence_v(ti, si, ci, v0, v0r, p, lean)


@jit(inline=True)
def _incidence_v(ti, si, ci, v0, v0r, p, lean):
    """:func:`_incidence` given ``sincos(theta_i)`` and ``V(sin theta_i)`` of both pairs."""
    rs0, rp0 = fresnel_sp(ci, p[_NEFF], p[_KEFF])
    if lean:
        e0 = 1.0
    else:
        zeta0 = si if p[_ZETA] == 1.0 else ti  # "cosine" reading: alpha0; otherwise theta_i
        e0 = shd.rb08_e0(zeta0, p[_GAM], p[_DEL])
    ci2 = ci * ci
    a02 = si * si
    sw = p[_NORM] == 1.0  # specular-width: rho_eff = rho ci V(alpha0), the width at the peak
    ns = rb08_norm(ci2, a02, p[_RHO] * ci * v0 if sw else p[_RHO])
    # retro_shadowing="amplitude": the retro V pair is not in the width (rho_eff = rho_r ci)
    v0r_w = 1.0 if p[_RAMP] == 1.0 else v0r
    nr = rb08_norm(ci2, a02, p[_RHOR] * ci * v0r_w if sw else p[_RHOR])
    # (numeric normalization: the caller replaces ns, nr by its per-incidence values)
    return si, ci, rs0, rp0, v0, v0r, e0, ns, nr


@jit(inline=True)
def _scatter(si, ci, rs0, rp0, v0, v0r, e0, ns, nr, ti, tr, phi, gamma, p, flag, fast, lean):
    """The BRDF (flag 0) or BRDF cos(theta_s) (flag 1) given the incidence quantities."""
    ss, cs = sincos(tr)
    vs = _v(ss, p[_SC_S], p[_A_S], p[_ST_S], fast)
    if lean:
        vsr = vs
    else:
        vsr = vs if p[_SAME_V] == 1.0 else _v(ss, p[_SC_R], p[_A_R], p[_ST_R], fast)
    return _scatter_v(si, ci, rs0, rp0, v0, v0r, e0, ns, nr, ti, tr, ss, cs, vs, vsr, phi,
                      gamma, p, flag, lean)


@jit(inline=True)
def _scatter_v(si, ci, rs0, rp0, v0, v0r, e0, ns, nr, ti, tr, ss, cs, vs, vsr, phi, gamma, p,
               flag, lean):
    """:func:`_scatter` given ``sincos(theta_s)`` and ``V(sin theta_s)`` of both pairs."""
    cs = 0.0 if cs < 1e-15 else cs  # cos(pi/2) = 6e-17: exact grazing gives exactly 0
    sph, cph = sincos(phi)
    a = ss * cph  # direction cosines alpha, beta (docs/models.md §4.3)
    b = ss * sph
    # Fresnel at the macroscopic angles (Eqs. 16-17 = fresnel_sp, docs/models.md §4.9); a per-call
    # polarization angle g gives R = R_s sin^2 g + R_p cos^2 g, NaN the option's weight
    unpol = gamma != gamma
    sg, cg = sincos(0.0 if unpol else gamma)
    ws = p[_POL] if unpol else sg * sg
    rss, rps = fresnel_sp(cs, p[_NEFF], p[_KEFF])
    r0 = ws * rs0 + (1.0 - ws) * rp0
    rsc = ws * rss + (1.0 - ws) * rps
    # sigma_surface and 1 - sigma_surface (Eqs. 19-20), per surface_weight
    wcode = p[_WEIGHT]
    prod = r0 * rsc
    trans = (1.0 - r0) * (1.0 - rsc)  # "transmission": 1 - sigma_s, computed directly
    sig = math.sqrt(prod) if wcode == 0.0 else (prod if wcode == 1.0 else 1.0 - trans)
    rest = max(0.0, trans if wcode == 2.0 else 1.0 - sig)  # R <= 1; guard a last-ulp overshoot
    half_sum2 = 0.25 * (ci + cs) * (ci + cs)
    # surface lobe, Eq. 15
    den = (a - si) * (a - si) + b * b + half_sum2 * v0 * vs * p[_RHO] * p[_RHO]
    if lean:
        vm = 1.0  # w_a = 0: B = 1 and Vm = 1 exactly
    else:
        zc = p[_ZETA]
        # zeta: "angle" arcsin(alpha) (signed in-plane scattering angle), "cosine" alpha,
        # "zenith-difference" theta_s - theta_i (sin^2 theta_s in B: azimuthally symmetric)
        zeta = special.vasin(min(1.0, max(-1.0, a))) if zc == 0.0 else (
            a if zc == 1.0 else tr - ti)
        al2 = ss * ss if zc == 2.0 else a * a
        vm = shd.rb08_vm(zeta, e0, al2, p[_WA], p[_WB])
    term = p[_TERM]
    surf = _lobe(sig * ns * vm, den) if (term == 0.0 or term == 1.0) else 0.0
    # bulk, Eq. 19 (Lambertian)
    bulk = rest * p[_BULK] * (1.0 / math.pi) if (term == 0.0 or term == 2.0) else 0.0
    # retro lobe, Eq. 20: the surface lobe mirrored to (-alpha0, 0), own width and shadowing
    # retro_shadowing: "width" (docs/models.md §4.10) V(sin theta_i) V(sin theta_s) narrows the
    # width term; "amplitude" it multiplies the strength (the acceptance-angle cut-off)
    amp = p[_RAMP] == 1.0
    vr = v0r * vsr
    den_r = (a + si) * (a + si) + b * b + half_sum2 * (1.0 if amp else vr) * p[_RHOR] * p[_RHOR]
    num_r = rest * p[_RETRO] * nr * (vr if amp else 1.0)
    retro = _lobe(num_r, den_r) if (term == 0.0 or term == 3.0) else 0.0
    total = surf + bulk + retro
    # BRIDF = BRDF cos(theta_s); total = inf only at a peak, where cos theta_s = cos theta_i > 0
    return total * cs if (flag != 0 and total < math.inf) else total


@jit(inline=True)
def _or_nan(x, default):
    # x, or default where x is NaN (the numeric normalization arrays use NaN for "analytic")
    return default if x != x else x


@jit
def _rb08_point(ti, tr, phi, gamma, p, flag):
    """Scalar RB08 kernel ``point(theta_i, theta_s, phi, gamma, p, flag)`` (analytic N)."""
    si, ci, rs0, rp0, v0, v0r, e0, ns, nr = _incidence(ti, p, False, False)
    return _scatter(si, ci, rs0, rp0, v0, v0r, e0, ns, nr, ti, tr, phi, gamma, p, flag, False,
                    False)


@driver
def _rb08_fast(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # Vectorized loop (integer n, n_r <= INT_HORNER_MAX, analytic N): everything per sample;
    # with a scalar theta_i, LLVM hoists the incidence quantities out of the loop.
    for k in prange(out.size):
        ti = at(a, k)
        si, ci, rs0, rp0, v0, v0r, e0, ns0, nr0 = _incidence(ti, p, True, False)
        out[k] = _scatter(si, ci, rs0, rp0, v0, v0r, e0, ns0, nr0, ti, at(b, k), at(c, k),
                          at(g, k), p, flag, True, False)


@driver
def _rb08_fast_lean(a, b, c, g, p, flag, out):  # pragma: no cover - compiled
    # _rb08_fast for w_a = 0 and (w_r, n_r) = (w, n) (the defaults): no Vm, one shadowing pair
    for k in prange(out.size):
        ti = at(a, k)
        si, ci, rs0, rp0, v0, v0r, e0, ns0, nr0 = _incidence(ti, p, True, True)
        out[k] = _scatter(si, ci, rs0, rp0, v0, v0r, e0, ns0, nr0, ti, at(b, k), at(c, k),
                          at(g, k), p, flag, True, True)


_CHUNK = 1024  # samples per task of the general loop (its incidence cache lives per task)


@driver
def _rb08_general(a, sa, b, sb, c, sc, g, sg, ns, sns, nr, snr, p, flag, out):  # pragma: no cover
    # Any real n: the incomplete gamma has loops, so this loop is not vectorized; instead the
    # incidence quantities (two or four Q evaluations) are recomputed only when theta_i changes
    # within a chunk (a fit's data, a grid with theta_i outermost, a scalar theta_i). Inputs
    # of size 1 are broadcast with a zero stride (sa = 0). ns/nr: numeric N per sample (NaN:
    # the analytic N).
    n = out.size
    nchunks = (n + _CHUNK - 1) // _CHUNK
    for k in prange(nchunks):
        start = k * _CHUNK
        stop = min(n, start + _CHUNK)
        last = a[start * sa]
        si, ci, rs0, rp0, v0, v0r, e0, ns0, nr0 = _incidence(last, p, False, False)
        for j in range(start, stop):
            ti = a[j * sa]
            if ti != last:
                si, ci, rs0, rp0, v0, v0r, e0, ns0, nr0 = _incidence(ti, p, False, False)
                last = ti
            out[j] = _scatter(si, ci, rs0, rp0, v0, v0r, e0, _or_nan(ns[j * sns], ns0),
                              _or_nan(nr[j * snr], nr0), ti, b[j * sb], c[j * sc], g[j * sg],
                              p, flag, False, False)


#: slots of the per-chunk memo of V (a power of 2) and slots per radian: angles on a grid finer
#: than 0.09 deg share slots, which only costs recomputations (a slot holds its exact key)
_MEMO_SIZE = 1024
_MEMO_SCALE = _MEMO_SIZE / (0.5 * math.pi)
_MEMO_CHUNK = 4096  # samples per task of the memo loop (each task has its own memo)


@jit
def _v_memo(t, start, stop, scale, a, st, out):
    """``out[j] = V(sin t[j])`` for ``start <= j < stop``, each distinct angle computed once.

    ``V`` by the general incomplete gamma (:func:`roughbrdf.shadowing.rb08_v`, any real n) of
    ``sin`` from :func:`~roughbrdf._kernels.vmath.sincos`: the same numbers as the kernels'
    own ``_v(sin theta, ...)``. A fit's geometries repeat a few dozen angles (a goniometer
    grid), so almost every sample reads its V from the direct-mapped memo.
    """
    keys = np.full(_MEMO_SIZE, np.nan)  # NaN equals no angle: every slot starts empty
    vals = np.zeros(_MEMO_SIZE)
    for j in range(start, stop):
        x = t[j]
        # the slot from the angle; the guard keeps int() finite for any input (angles are
        # validated to [0, pi/2] before any kernel runs)
        xc = x if (x >= 0.0 and x <= 4.0) else 0.0
        slot = int(xc * _MEMO_SCALE) & (_MEMO_SIZE - 1)
        if keys[slot] == x:
            out[j] = vals[slot]
        else:
            sx, _ = sincos(x)
            v = shd.rb08_v(sx, scale, a, st)
            keys[slot] = x
            vals[slot] = v
            out[j] = v


@driver
def _rb08_tab(a, b, c, g, ns, nr, p, flag, out):  # pragma: no cover - compiled
    # Any real n, one polarization: first V(sin theta_i) and V(sin theta_s) of both shadowing
    # pairs per sample through the memo (a loop with branches), then the vectorized loop of
    # the fast kernels reading them. a, b, c: arrays; g: float; ns/nr: numeric N per sample
    # (arrays) or NaN (floats) for the analytic N.
    n = out.size
    same = p[_SAME_V] == 1.0
    v0 = np.empty(n)
    vs = np.empty(n)
    v0r = v0 if same else np.empty(n)
    vsr = vs if same else np.empty(n)
    for k in prange((n + _MEMO_CHUNK - 1) // _MEMO_CHUNK):
        lo = k * _MEMO_CHUNK
        hi = min(n, lo + _MEMO_CHUNK)
        _v_memo(a, lo, hi, p[_SC_S], p[_A_S], p[_ST_S], v0)
        _v_memo(b, lo, hi, p[_SC_S], p[_A_S], p[_ST_S], vs)
        if not same:
            _v_memo(a, lo, hi, p[_SC_R], p[_A_R], p[_ST_R], v0r)
            _v_memo(b, lo, hi, p[_SC_R], p[_A_R], p[_ST_R], vsr)
    for k in prange(n):
        ti = a[k]
        tr = b[k]
        si, ci = sincos(ti)
        si, ci, rs0, rp0, v0k, v0rk, e0, ns0, nr0 = _incidence_v(ti, si, ci, v0[k], v0r[k], p,
                                                                 False)
        ss, cs = sincos(tr)
        out[k] = _scatter_v(si, ci, rs0, rp0, v0k, v0rk, e0, _or_nan(at(ns, k), ns0),
                            _or_nan(at(nr, k), nr0), ti, tr, ss, cs, vs[k], vsr[k], c[k], g, p,
                            flag, False)


def _run(ti: np.ndarray, tr: np.ndarray, phi: np.ndarray, gamma: np.ndarray, p: tuple,
         flag: int, ns: np.ndarray | None = None, nr: np.ndarray | None = None,
         general: bool = False) -> np.ndarray | float:
    """Broadcast the inputs and run the fast, tabulated or general driver.

    ``ns``/``nr``: numeric N per sample (None: the analytic N). The fast (vectorized) drivers
    take integer n, n_r, one polarization for all samples and the analytic N; ``theta_i`` is
    passed as a float when it is one value (LLVM then hoists every incidence quantity out of
    the loop), ``theta_s`` and ``phi`` always as arrays, which keeps the number of compiled
    variants (each ~5 s the first time, then cached on disk) at four. Real n or numeric N with
    one polarization run the tabulated driver (V through a memo, then the vectorized loop: two
    variants); per-sample polarization, or ``general`` (:meth:`~RenhornBoreman2008.
    with_general_kernel`), the general driver.
    """
    shape = np.broadcast_shapes(ti.shape, tr.shape, phi.shape, gamma.shape)
    n = math.prod(shape)
    out = np.empty(n, dtype=np.float64)
    if n:
        pt = tuple(float(v) for v in p)
        arr = _kernels.broadcast_array
        if general or gamma.size != 1:
            flat = _kernels.broadcast_strided
            nan = np.full(1, math.nan)
            args = (*flat(ti, shape), *flat(tr, shape), *flat(phi, shape), *flat(gamma, shape),
                    *((nan, 0) if ns is None else flat(ns, shape)),
                    *((nan, 0) if nr is None else flat(nr, shape)), pt, int(flag), out)
            _kernels.run_driver(_rb08_general, *args)
        elif p[_FAST] == 1.0 and ns is None and nr is None:
            lean = p[_WA] == 0.0 and p[_SAME_V] == 1.0
            drive = _rb08_fast_lean if lean else _rb08_fast
            a = float(ti.reshape(-1)[0]) if ti.size == 1 else arr(ti, shape)
            _kernels.run_driver(drive, a, arr(tr, shape), arr(phi, shape),
                                float(gamma.reshape(-1)[0]), pt, int(flag), out)
        else:
            norms = _norm_args(ns, nr, shape)
            _kernels.run_driver(_rb08_tab, arr(ti, shape), arr(tr, shape), arr(phi, shape),
                                float(gamma.reshape(-1)[0]), *norms, pt, int(flag), out)
    if not shape:
        return float(out[0])
    return out.reshape(shape)


def _norm_args(ns: np.ndarray | None, nr: np.ndarray | None, shape: tuple[int, ...]) -> tuple:
    """``(ns, nr)`` for the tabulated driver: two NaN floats (analytic N), or two arrays of the
    broadcast shape (numeric N; NaN where a term keeps the analytic N)."""
    if ns is None and nr is None:
        return math.nan, math.nan
    nan = np.full(1, math.nan)
    return tuple(_kernels.broadcast_array(nan if x is None else x, shape) for x in (ns, nr))


# --------------------------------------------------------------------------------------------
# numeric normalization: exact quadrature of the lobe over the unit disk, per incidence
# --------------------------------------------------------------------------------------------
#: Gauss-Legendre nodes and weights on [-1, 1] of one panel of :func:`lobe_integral`
_GL_X, _GL_W = np.polynomial.legendre.leggauss(12)
#: where V = Q(a, x) turns over: x = a + z sqrt(a) (Q falls from 1 to 0 around x = a, over a
#: width sqrt(a)); panel edges are placed at the s = sin(theta) of these x
_V_TURN_Z = np.array([-4.0, -2.0, -1.0, 0.0, 1.0, 2.0, 4.0, 8.0, 16.0])
_MIN_PANELS = 8  # uniform panels on each side of the peak
_U_PER_PANEL = 3.0  # and at most this much of u per panel (u_max ~ ln(2/eps) for a sharp peak)
_U_LARGE = 700.0  # beyond it sinh, cosh are taken as exp(u)/2 (they overflow at 710)


@jit
def _lobe_radial(u, side, a0, ci, v0, eps, rho2, scale, a, st):
    """Integrand of :func:`lobe_integral` per unit ``u``, at ``s = a0 + side eps sinh(u)``.

    ``2 pi s ds / sqrt(((s - a0)^2 + c)((s + a0)^2 + c))`` with ``ds = eps cosh(u) du``,
    divided by ``2 pi``, written with ``(s - a0)^2 + c = (eps cosh u)^2 (tanh^2 u + q)``:
    ``eps^2`` itself underflows when V(sin theta_i) is below ~1e-150, ``q`` does not.
    """
    if u > _U_LARGE:  # eps below ~1e-300: the exponential asymptote, eps in the exponent
        dx = side * 0.5 * math.exp(u + math.log(eps))
        sech = 2.0 * math.exp(-u)
    else:
        dx = side * eps * math.sinh(u)
        sech = 1.0 / math.cosh(u)
    s = min(1.0, a0 + dx)
    cs = math.sqrt(max(0.0, (1.0 - s) * (1.0 + s)))  # max: s = 1 may round (1 - s)(1 + s) < 0
    vs = shd.rb08_v(s, scale, a, st)
    h = (ci + cs) * sech / (2.0 * ci)
    # q = c(s)/(eps cosh u)^2 = h^2 V(s)/V(a0), which overflows where V(a0) is subnormal and
    # the width term dwarfs the distance to the peak
    num = h * h * vs
    if num >= 1e300 * v0:
        return 0.0  # q = num/v0 would overflow: the integrand is below 1e-150 of the total
    q = num / v0
    th = math.tanh(u)
    c = 0.25 * (ci + cs) * (ci + cs) * v0 * vs * rho2
    return s / math.sqrt((th * th + q) * ((s + a0) * (s + a0) + c))


@jit(inline=True)
def _asinh_ratio(x, eps):
    # asinh(x/eps) for x, eps > 0 without forming x/eps, which overflows for a subnormal eps:
    # asinh(r) = ln(2r) to double precision for r > 1e300 (ln r > 690.8)
    lr = math.log(x) - math.log(eps)
    return lr + math.log(2.0) if lr > 690.8 else math.asinh(x / eps)


@jit
def _lobe_edges(a0, eps, span, umax, side, scale, a):
    """Sorted panel edges in ``x`` on [0, 1] for one side of the peak (see lobe_integral)."""
    npan = max(_MIN_PANELS, int(math.ceil(umax / _U_PER_PANEL)))
    edges = np.empty(npan + 1 + _V_TURN_Z.size + 64)
    m = 0
    for k in range(npan + 1):
        edges[m] = k / npan
        m += 1
    pts = np.empty(_V_TURN_Z.size + 64)
    npts = 0
    if scale > 0.0:  # scale = 0: w = inf, V = 1, no turn-over
        for z in _V_TURN_Z:
            xq = a + z * math.sqrt(a)
            if xq > 0.0:
                pts[npts] = math.sqrt(xq / scale)
                npts += 1
    if side < 0.0:
        # near grazing, cos(theta_s) ~ sqrt(1 - s) varies on the scale 1 - a0 next to the
        # peak: edges at distances (1 - a0) 4^k from it (the max keeps the loop finite when
        # sin(theta_i) rounds to 1)
        d = max(1.0 - a0, 1e-17)
        while d < a0 and npts < pts.size:
            pts[npts] = a0 - d
            npts += 1
            d *= 4.0
    for k in range(npts):
        dist = (pts[k] - a0) * side
        if 0.0 < dist < span:
            r = _asinh_ratio(dist, eps) / umax
            edges[m] = 1.0 - math.sqrt(max(0.0, 1.0 - r)) if side > 0.0 else r
            m += 1
    return np.sort(edges[:m])


@jit
def _lobe_side(a0, ci, v0, rho, scale, a, st, side):
    """``∫ s ds / sqrt(((s - a0)^2 + c)((s + a0)^2 + c))`` from ``a0`` to 1 (side 1) or to 0
    (side -1), in ``s = a0 + side eps sinh(u)``, ``eps = cos(theta_i) V(a0) rho`` (the width
    at the peak); on the rim side ``u = u_max (1 - (1 - x)^2)``, which makes the square root
    of ``cos theta_s`` at ``s = 1`` smooth in ``x``; on the other ``u = u_max x``."""
    span = 1.0 - a0 if side > 0.0 else a0
    if not span > 0.0:
        return 0.0  # normal incidence: nothing below the peak
    eps = ci * v0 * rho
    umax = _asinh_ratio(span, eps)
    edges = _lobe_edges(a0, eps, span, umax, side, scale, a)
    total = 0.0
    for k in range(edges.size - 1):
        half = 0.5 * (edges[k + 1] - edges[k])
        mid = 0.5 * (edges[k + 1] + edges[k])
        for j in range(_GL_X.size):
            x = mid + half * _GL_X[j]
            if side > 0.0:
                u = umax * (1.0 - (1.0 - x) * (1.0 - x))
                du = 2.0 * umax * (1.0 - x)
            else:
                u = umax * x
                du = umax
            total += half * _GL_W[j] * du * _lobe_radial(u, side, a0, ci, v0, eps, rho * rho,
                                                         scale, a, st)
    return total


@_kernels.ufunc(5)
def _lobe_integral_ufunc(ti, rho, scale, a, st):
    a0, ci = math.sin(ti), math.cos(ti)
    v0 = shd.rb08_v(a0, scale, a, st)
    if not ci * v0 * rho > 0.0:
        return math.inf  # zero width at the peak: the disk integral diverges
    return 2.0 * math.pi * (_lobe_side(a0, ci, v0, rho, scale, a, st, 1.0)
                            + _lobe_side(a0, ci, v0, rho, scale, a, st, -1.0))


def lobe_integral(theta_i, rho: float, w: float, n: float) -> np.ndarray:
    """``I = ∫∫_{alpha²+beta²<=1} dalpha dbeta / D(alpha - alpha0; rho, w, n)`` per incidence.

    The unit-disk integral of the cosine-width, V-shadowed lobe of Eqs. 12/15 (without sigma,
    N and Vm), so that ``N = 1/I`` normalizes it exactly (``normalization="numeric"``). The
    same ``I`` serves the retro lobe (its mirror image, with rho_r, w_r, n_r); ``w = inf``
    drops V (the amplitude retro lobe).

    Method: ``D = (alpha - alpha0)^2 + beta^2 + c(s)``, where the width term
    ``c(s) = (cos theta_i + cos theta_s)^2 V(alpha0) V(s) rho^2/4`` depends on
    ``s = sqrt(alpha^2 + beta^2) = sin theta_s`` only. In polar coordinates about the origin
    the azimuthal integral is elementary, ``∫_0^{2pi} dphi/(A - B cos phi) = 2pi/sqrt(A^2 -
    B^2)``, which leaves one radial integral, exactly::

        I = 2 pi ∫_0^1 s ds / sqrt(((s - alpha0)^2 + c(s)) ((s + alpha0)^2 + c(s)))

    It is taken on each side of the peak ``s = alpha0`` in ``s - alpha0 = ±eps sinh(u)``
    (``eps = cos theta_i V(alpha0) rho``, the width at the peak: smooth in ``u`` whatever the
    width) by composite 12-point Gauss-Legendre panels: 8 uniform ones (more for a peak
    narrower than ~1e-3), plus edges where V turns over (sharp for large n or small w) and,
    below the peak, at distances ``(1 - alpha0) 4^k`` from it (near grazing incidence).
    ~300-6000 integrand evaluations, ~0.02 ms per incidence. Relative accuracy against a
    16x finer quadrature: <= 2e-11 up to 89.99 deg (rho 0.005-2, w 0.05-2, n 0-50, tested),
    ~1e-7 within 1e-4 deg of grazing (where ``1 - sin theta`` itself loses the digits).

    (Until 2026-12 this was a 2-D quadrature about the peak, ~3 ms per incidence, which made
    a numeric-N fit of one Mini-Diff channel take over a minute; it erred by up to 6e-3 where
    V turns over within a few of its nodes (w ~0.05, n ~50) and returned NaN or inf where
    ``V(sin theta_i)`` is below ~1e-150; the kernel then fell back to the literal N.)
    """
    ti = np.asarray(theta_i, dtype=np.float64)
    a = 1.0 + n
    scale = a / (w * w)  # w = inf: scale = 0 and V = Q(a, 0) = 1
    return np.atleast_1d(_lobe_integral_ufunc(ti, float(rho), scale, a, special.stirlerr(a)))


_NUMERIC_CACHE: dict[tuple, float] = {}
_NUMERIC_CACHE_MAX = 200_000
_NUMERIC_EXACT_MAX = 256  # more distinct incidences than this: interpolate a cached table
_TABLE_CACHE: dict[tuple, Any] = {}


def _numeric_n(ti: np.ndarray, lobes: list[tuple[float, float, float] | None]
               ) -> list[np.ndarray | None]:
    """Per-sample numeric normalization ``1/I(theta_i)`` (shape of ``ti``) of each lobe
    ``(rho, w, n)`` (None: not wanted), the distinct incidences found once for all of them."""
    index = _incidence_index(ti)
    out: list[np.ndarray | None] = []
    for lobe in lobes:
        if lobe is None:
            out.append(None)
        elif index is None:
            out.append(_numeric_table(*lobe)(ti.reshape(-1)).reshape(ti.shape))
        else:
            out.append(_numeric_exact(index[0], *lobe)[index[1]])
    return out


#: the last few ``theta_i`` arrays seen by :func:`_incidence_index`: id -> (the array, a copy
#: of its values, its index); a fit evaluates the same array thousands of times
_INDEX_MEMO: dict[int, tuple[np.ndarray, np.ndarray, Any]] = {}


def _incidence_index(ti: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """``(distinct incidences, index of each sample into them)``, or None when there are more
    than :data:`_NUMERIC_EXACT_MAX` (then the table is interpolated). Remembered for the last
    few arrays, checked against a copy of their values (~10 us instead of a sort, ~70 us for
    a Mini-Diff channel)."""
    got = _INDEX_MEMO.get(id(ti))
    if got is not None and got[0] is ti and np.array_equal(got[1], ti):
        return got[2]
    flat = ti.reshape(-1)
    index = None
    # many distinct incidences (e.g. random geometries) show up in a subsample already:
    # skip the full sort then and interpolate every sample directly
    sub = flat[:: max(1, flat.size // 4096)]
    if sub.size == flat.size or np.unique(sub).size <= _NUMERIC_EXACT_MAX:
        uniq, inv = np.unique(flat, return_inverse=True)
        if uniq.size <= _NUMERIC_EXACT_MAX:
            index = (uniq, inv.reshape(ti.shape))
    if len(_INDEX_MEMO) >= 4:
        _INDEX_MEMO.clear()
    _INDEX_MEMO[id(ti)] = (ti, ti.copy(), index)
    return index


def _numeric_exact(uniq: np.ndarray, rho: float, w: float, n: float) -> np.ndarray:
    """``1/I`` for each distinct incidence, from the cache or by quadrature."""
    vals = np.empty(uniq.size)
    missing = []
    for j, t in enumerate(uniq):
        got = _NUMERIC_CACHE.get((rho, w, n, float(t)))
        if got is None:
            missing.append(j)
        else:
            vals[j] = got
    if missing:
        ints = lobe_integral(uniq[missing], rho, w, n)
        if len(_NUMERIC_CACHE) + len(missing) > _NUMERIC_CACHE_MAX:
            _NUMERIC_CACHE.clear()
        for j, i_val in zip(missing, ints, strict=True):
            vals[j] = 1.0 / i_val
            _NUMERIC_CACHE[(rho, w, n, float(uniq[j]))] = vals[j]
    return vals


# nodes in z = log(cos theta_i): every 0.5 deg up to 89 deg, then cos theta_i geometric to 1e-5
_Z_NODES = np.unique(np.log(np.concatenate([
    np.geomspace(1e-5, math.cos(math.radians(89.0)), 80),
    np.cos(np.radians(np.linspace(0.0, 89.0, 179)))])))


def _numeric_table(rho: float, w: float, n: float) -> Callable[[np.ndarray], np.ndarray]:
    """Interpolant of the numeric N over theta_i in [0, pi/2), for many distinct incidences.

    Interpolated: the ratio ``N_numeric / N(alpha0, rho_eff)`` to the specular-width analytic
    N (smooth, close to 1), by a cubic spline in ``z = log(cos theta_i)`` (an even, smooth
    function of theta_i near 0 and logarithmic near grazing), on 258 nodes computed exactly
    (every 0.5 deg to 89 deg, then geometric in ``cos theta_i`` down to 1e-5); relative error
    ~1e-7 at most (tested). Incidences with ``cos theta_i < 1e-5`` (within 0.0006 deg of
    grazing), and those where the analytic N is 0, are computed exactly.
    """
    key = (rho, w, n)
    interp = _TABLE_CACHE.get(key)
    if interp is None:
        interp = _build_table(rho, w, n)
        if len(_TABLE_CACHE) > 64:
            _TABLE_CACHE.clear()
        _TABLE_CACHE[key] = interp
    return interp


def _build_table(rho: float, w: float, n: float) -> Callable[[np.ndarray], np.ndarray]:
    """The interpolant of :func:`_numeric_table` (258 exact values, ~5 ms)."""
    from scipy.interpolate import CubicSpline

    th = np.arccos(np.exp(_Z_NODES))
    exact = 1.0 / lobe_integral(th, rho, w, n)
    analytic = _analytic_specular_width(th, rho, w, n)
    # where rho_eff = rho cos(theta_i) V(sin theta_i) underflows (V below ~1e-160: large n,
    # sin theta_i beyond w) the analytic N is 0 and the ratio undefined: those incidences are
    # computed exactly, and the ratio at their nodes is continued from the others (it then
    # only shapes the spline). Node 0 (theta_i = 0, V = 1) is always valid.
    ok = analytic > 0.0
    ratio = np.empty_like(exact)
    ratio[ok] = exact[ok] / analytic[ok]
    ratio[~ok] = np.interp(_Z_NODES[~ok], _Z_NODES[ok], ratio[ok])
    spline = CubicSpline(_Z_NODES, ratio)

    def interp(theta: np.ndarray) -> np.ndarray:
        ci = np.cos(theta)
        scale = _analytic_specular_width(theta, rho, w, n)
        out = spline(np.log(np.maximum(ci, 1e-5))) * scale
        edge = (ci < 1e-5) | ~(scale > 0.0)
        if edge.any():
            out[edge] = _numeric_exact(theta[edge], rho, w, n)
        return out

    return interp


def _analytic_specular_width(theta, rho, w, n):
    theta = np.asarray(theta, dtype=np.float64)
    a0 = np.sin(theta)
    ci = np.cos(theta)
    v0 = 1.0 if w == math.inf else shd.V(a0, w, n)  # w = inf: no shadowing (V = 1)
    # a subnormal rho_eff (V underflowing) overflows ln(arg) to inf: N = 0, its limit
    with np.errstate(over="ignore"):
        return _norm_ufunc(ci * ci, a0 * a0, rho * ci * v0)


@_kernels.ufunc(3)
def _norm_ufunc(ci2, a02, rho):
    return rb08_norm(ci2, a02, rho)


# --------------------------------------------------------------------------------------------
# the model
# --------------------------------------------------------------------------------------------
def _horner_ok(n: float) -> bool:
    # V by the vectorizable finite sum: integer n up to special.INT_HORNER_MAX
    return float(n).is_integer() and n <= special.INT_HORNER_MAX


def _real(name: str, default: float, bounds: tuple[float, float], unit: str, desc: str
          ) -> Parameter:
    return Parameter(name, default, bounds, unit, desc)


@register
class RenhornBoreman2008(Model):
    """Renhorn & Boreman (2008) analytical rough-surface BRDF: surface, bulk and retro terms.

    I. G. E. Renhorn and G. D. Boreman, "Analytical fitting model for rough-surface BRDF",
    Opt. Express 16(17), 12892 (2008), Eqs. 5-20, as reconstructed in docs/models.md §4. Only the
    flattened equations of the paper survive, so some parts are *our reading*; every alternative
    reading is an option.

    Parameters (the fourteen of the abstract, docs/models.md §4.11)
    ----------------------------------------------------------
    rho : float > 0
        Surface-lobe width: half width at half maximum of the Lorentzian in direction-cosine
        space (an inverse correlation length). *Certain* (Eqs. 5-15).
    w : float > 0
        Shadowing cut-off of ``V`` in ``sin theta`` units (Eq. 10). *Certain.*
    n : float >= 0
        Shadowing sharpness of ``V`` (0: ``exp(-chi^2/w^2)``, Eq. 11; large: a step at ``w``).
        *Certain.*
    w_a, w_b : float (any sign)
        Amplitude and angular decay of the masking multiplier ``Vm``,
        ``B = exp(-w_a zeta exp(-w_b alpha^2))`` (Eq. 13). *Certain* as symbols; the signs are our
        convention (any lost sign is absorbed by the sign of the parameter).
    gamma : float >= 0
        Amplitude of Vm's incidence weight ``E0 = exp(-gamma zeta0 exp(-delta zeta0^2))``.
        *Certain* as a symbol; ``gamma >= 0`` keeps ``E0 <= 1`` and hence ``Vm > 0``.
    delta : float (any sign)
        Decay of Vm's incidence weight. *Certain* as a symbol.
    n_eff, k_eff : float
        Effective complex index ``n_eff + i k_eff`` of the Fresnel factor (Eqs. 16-17). *Certain.*
    bulk, retro : float in [0, 1]
        Strengths of the bulk (Lambertian) and retro terms, ``sigma_bulk = (1 - sigma_s) bulk``,
        ``sigma_retro = (1 - sigma_s) retro`` (Eqs. 19-20). *Certain* as strengths; the bulk
        term's Lambertian shape is *our reading* (the shapes were defined in the lost prose).
        Both are reflectances of a part (before the Fresnel weight ``1 - sigma_s``), so their
        domain is ``[0, 1]`` like every reflectance-like parameter
        (:data:`~roughbrdf.models.parameters.REFLECTANCE_DOMAIN`).
    rho_r, w_r, n_r : float
        Retro lobe width and its own shadowing pair. *Our reading:* ``rho_r`` is probable (a
        retro lobe needs a width), ``w_r``, ``n_r`` speculative (docs/models.md §4.11).

    Options (the alternative readings; defaults are docs/models.md's recommendations)
    ----------------------------------------------------------------------------
    zeta : {"angle", "cosine", "zenith-difference"}
        What Vm's ``zeta``, ``zeta0`` are (§4.8): ``"angle"`` ``zeta = arcsin(sin theta_s cos
        phi)``, ``zeta0 = theta_i`` (radians); ``"cosine"`` ``zeta = alpha``, ``zeta0 =
        alpha0``; ``"zenith-difference"`` ``zeta = theta_s - theta_i``, ``zeta0 = theta_i`` and
        ``sin^2 theta_s`` in B's exponent (our choice: the reading is then azimuthally symmetric).
    surface_weight : {"geometric-mean", "product", "transmission"}
        The bracket of Eqs. 19-20, ``1 - sigma_s``: ``sigma_s = sqrt(R(alpha0) R(alpha, beta))``
        (q = 1/2), ``R(alpha0) R(alpha, beta)`` (q = 1), or the two-bracket transmission
        ``1 - sigma_s = [1 - R(alpha0)][1 - R(alpha, beta)]``. The printed identity
        ``sigma_bulk/bulk = sigma_retro/retro = 1 - sigma_s`` holds for all three.
    normalization : {"literal", "specular-width", "numeric"}
        The ``N`` of Eqs. 9-15 (§4.12): ``"literal"`` ``N(alpha0, rho)`` as printed (then sigma
        is not the lobe's hemispherical reflectance: 1.0-3.3x at rho = 0.1-0.3, theta_i <= 75
        deg); ``"specular-width"`` ``N(alpha0, rho cos theta_i V(sin theta_i))``, the width at the
        peak (within ~5 %); ``"numeric"`` ``N = 1/∫∫_disk dalpha dbeta/D`` by quadrature
        (:func:`lobe_integral`), so that with constant sigma and Vm = 1 the lobe's hemispherical
        integral is exactly sigma. Numeric N is computed per distinct ``theta_i`` (a 1-D
        radial quadrature, ~0.02 ms each, cached) when there are at most 256 of them, else
        interpolated from a table of 258 exact values (cubic spline in ``log cos theta_i``,
        relative error ~1e-7; built once per (rho, w, n) in ~5 ms and cached).
    polarization : {"unpolarized", "s", "p"}
        Which Fresnel reflectance of Eqs. 16-17 is R: ``(R_s + R_p)/2``, ``R_s`` or ``R_p``. A
        per-call ``brdf(..., polarization=...)`` overrides it: ``"s"`` (gamma = pi/2), ``"p"``
        (gamma = 0) or an angle gamma of the incident field from the plane of incidence gives
        ``R = R_s sin^2 gamma + R_p cos^2 gamma`` (TR75 Eq. 24 with eta = 0, the Fresnel factor
        being taken at macroscopic angles), used for both ``R(alpha0)`` and ``R(alpha, beta)``;
        ``None``/NaN uses the option.
    retro_shadowing : {"width", "amplitude"}
        Where the retro lobe's own shadowing pair ``V(sin theta_i, w_r, n_r) V(sin theta_s,
        w_r, n_r)`` acts. Parameters 13-14 (``w_r``, ``n_r``) are *speculative* (docs/models.md
        §4.10-4.11: the retro shape was in the lost prose), so both are *our reading*.
        ``"width"`` (default, docs/models.md §4.10): the surface lobe mirrored to the retro point,
        the pair multiplying ``rho_r^2`` in the width term as V does in Eq. 12. Its retro peak
        ``BRDF cos theta_s = (1 - R(theta_i)) retro N(alpha0, rho_r)/(cos theta_i V(sin
        theta_i)^2 rho_r^2)`` can only *grow* with incidence (V <= 1 decreasing; for
        ``n_eff >= 1`` the peak at 15 deg is at most ~0.5x the one at 60 deg over the bounds),
        unless the effective index is below ``sin theta_i`` (a total-internal-reflection
        artefact of the Fresnel factor). ``"amplitude"``: the pair multiplies the retro
        *strength* and the width term is ``(cos theta_i + cos theta_s)^2 rho_r^2/4``: the
        acceptance-angle cut-off of bead and prism retro-reflectors, whose retro peak falls
        steeply beyond the acceptance angle ``~w_r`` (in ``sin theta``). Measured
        retro-reflectors need it: the CEA gray tape's retro peak BRDF cos falls 72.5 -> 42.5 ->
        1.1 at 15, 30, 60 deg. The ``normalization`` options then use the amplitude lobe's own
        width: ``"specular-width"`` ``N(alpha0, rho_r cos theta_i)``, ``"numeric"`` the disk
        integral of the lobe without V (the retro term's hemispherical integral is then
        ``~(1 - sigma_s) retro V(sin theta_i)^2``: V cuts off the strength).

    Notes
    -----
    * The Fresnel factor is evaluated at the macroscopic angles ``theta_i`` and ``theta_s``
      (Eqs. 16-17 written in the direction cosine are exactly the standard Fresnel equations,
      docs/models.md §4.9), with :func:`roughbrdf.fresnel.fresnel_sp`.
    * **Not reciprocal** (docs/models.md §4.13): the denominators and ``sigma_s`` (q = 1/2) are
      symmetric in ``(theta_i, theta_s)``, but ``N(alpha0, rho)`` depends on the incidence only
      and Vm distinguishes incidence from scattering, so ``f(i, s) != f(s, i)`` in general. Energy
      conservation is not guaranteed either (the model is a fitting function).
    * Evaluated over the full hemisphere (out of the plane of incidence too). Finite everywhere
      for ``theta_i < pi/2``, including normal incidence, ``theta_s = pi/2``, the specular and the
      retro points. ``theta_i = pi/2`` is rejected: there ``cos theta_i + cos theta_s`` and hence
      the width term vanish at the specular and retro points on the rim, the lobes become
      ``1/distance^2`` singularities with an infinite hemispherical integral, and the BRDF is not
      defined (it is finite for any ``theta_i`` below pi/2). If ``V(sin theta_i)`` underflows
      to 0 (extremely sharp shadowing, ``n`` in the hundreds with ``sin theta_i > w``) the same
      happens at the peak, which then returns ``inf`` (never NaN).
    * ``term="surface" | "bulk" | "retro"`` evaluates one term alone.
    * The sigma of Eqs. 5-15 is ``sigma_surface`` itself (no separate free scale, docs/models.md
      §4.10): the 14 parameters of the abstract are then exactly the list above.
    * Defaults: a matte-paint-like surface, no published values being available: index 1.5
      (R = 4 % at normal incidence), a broad weak gloss lobe (rho = 0.3, w = 0.9, n = 4), a
      strong bulk term (bulk = 0.85), a faint retro lobe (retro = 0.02, rho_r = 0.2) and Vm
      switched off (w_a = 0). Directional-hemispherical reflectance 0.87 at normal incidence,
      0.89 at 60 deg with ``normalization="specular-width"``; with the literal N it exceeds 1
      beyond ~60 deg (1.75 at 80 deg: the lobe's integral grows as in docs/models.md §4.12).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> m = rb.model("rb08")
    >>> f = m.brdf(0.5, 0.5, 0.0)             # specular point
    >>> parts = [m.brdf(0.5, 0.5, 0.0, term=t) for t in ("surface", "bulk", "retro")]
    >>> abs(sum(parts) - f) < 1e-12
    True
    """

    name = "renhorn-boreman-2008"
    aliases = ("rb08", "renhorn-boreman")
    short = "rb08"
    reference = "Renhorn & Boreman, Opt. Express 16(17), 12892 (2008)"
    PARAMETERS = (
        positive("rho", 0.3, (0.005, 2.0), "1",
                 "surface lobe width (HWHM in direction-cosine space), Eqs. 5-15"),
        positive("w", 0.9, (0.05, 2.0), "1", "shadowing cut-off of V, in sin(theta), Eq. 10"),
        nonnegative("n", 4.0, (0.0, 50.0), "1", "shadowing sharpness of V, Eq. 10"),
        _real("w_a", 0.0, (-5.0, 5.0), "1/rad", "Vm amplitude, B = exp(-w_a zeta exp(-w_b a^2))"),
        _real("w_b", 1.0, (-5.0, 5.0), "1", "Vm angular decay (exponent of alpha^2), Eq. 13"),
        nonnegative("gamma", 1.0, (0.0, 10.0), "1/rad",
                    "Vm incidence weight amplitude, E0 = exp(-gamma z0 exp(-delta z0^2))"),
        _real("delta", 0.0, (-5.0, 5.0), "1/rad^2", "Vm incidence weight decay, Eq. 13"),
        positive("n_eff", 1.5, (0.2, 5.0), "1", "effective refractive index, Eqs. 16-17"),
        nonnegative("k_eff", 0.0, (0.0, 10.0), "1", "effective extinction index, Eqs. 16-17"),
        reflectance("bulk", 0.85,
                    "bulk (Lambertian) strength, sigma_bulk = (1 - sigma_s) bulk, Eq. 19"),
        reflectance("retro", 0.02,
                    "retro-reflection strength, sigma_retro = (1 - sigma_s) retro, Eq. 20"),
        positive("rho_r", 0.2, (0.005, 2.0), "1", "retro lobe width (our reading)"),
        positive("w_r", 0.9, (0.05, 2.0), "1", "retro shadowing cut-off (our reading)"),
        nonnegative("n_r", 4.0, (0.0, 50.0), "1", "retro shadowing sharpness (our reading)"),
    )
    OPTIONS = {"zeta": "angle", "surface_weight": "geometric-mean", "normalization": "literal",
               "polarization": "unpolarized", "retro_shadowing": "width"}
    #: set by :meth:`with_general_kernel`
    _force_general: bool = False
    TERMS = ("surface", "bulk", "retro")
    grazing_incidence = False
    reciprocal = False

    def _check_options(self, options: dict[str, Any]) -> dict[str, Any]:
        return {key: OPTION_VALUES[key].canonical("unpolarized" if val is None else val)
                for key, val in options.items()}

    def _validate(self) -> None:
        v = self._floats()
        check_index(v["n_eff"], v["k_eff"])

    def _pack(self, term: int = 0) -> tuple:
        v = self._floats()
        o = self._options
        a_s = 1.0 + v["n"]
        a_r = 1.0 + v["n_r"]
        return (v["rho"], v["w"], v["n"], v["w_a"], v["w_b"], v["gamma"], v["delta"],
                v["n_eff"], v["k_eff"], v["bulk"], v["retro"], v["rho_r"], v["w_r"], v["n_r"],
                float(ZETA_CODES[o["zeta"]]), float(WEIGHT_CODES[o["surface_weight"]]),
                float(NORM_CODES[o["normalization"]]), POL_WEIGHT[o["polarization"]],
                float(term),
                a_s, a_s / (v["w"] * v["w"]), special.stirlerr(a_s),
                a_r, a_r / (v["w_r"] * v["w_r"]), special.stirlerr(a_r),
                1.0 if (v["w_r"], v["n_r"]) == (v["w"], v["n"]) else 0.0,
                1.0 if self.uses_fast_kernel else 0.0,
                float(RETRO_CODES[o["retro_shadowing"]]))

    @property
    def uses_fast_kernel(self) -> bool:
        """Whether evaluation takes the vectorized kernel: integer ``n`` and ``n_r`` up to
        ``special.INT_HORNER_MAX``, unless made with :meth:`with_general_kernel`."""
        v = self._floats()
        return not self._force_general and _horner_ok(v["n"]) and _horner_ok(v["n_r"])

    def with_general_kernel(self) -> RenhornBoreman2008:
        """A copy that always runs the general kernel (series / continued fraction for V, any
        real ``n``): the reference the vectorized kernel is checked against (to ~1e-13)."""
        new = copy.copy(self)
        new._force_general = True
        return new

    def _numeric_lobes(self, term: str | None) -> list[tuple[float, float, float] | None]:
        """``(rho, w, n)`` of the surface and retro lobes whose numeric N ``term`` needs (None:
        not needed; the amplitude retro lobe has no V in its width: ``w = inf``)."""
        v = self._floats()
        surface = (v["rho"], v["w"], v["n"]) if term in (None, "surface") else None
        retro = None
        if term in (None, "retro") and v["retro"] != 0.0:
            amp = self._options["retro_shadowing"] == "amplitude"
            retro = (v["rho_r"], math.inf, 0.0) if amp else (v["rho_r"], v["w_r"], v["n_r"])
        return [surface, retro]

    def _kernel(self, g: PreparedGeometry, flag: int, term: str | None
                ) -> np.ndarray | float:
        ti, tr, phi, gamma = g.theta_i, g.theta_r, g.phi, g.gamma
        if term not in TERM_CODES:
            raise ValueError(f"model {self.name!r} has terms {self.TERMS}; got term={term!r}")
        p = self._pack(TERM_CODES[term])
        ns = nr = None
        if self._options["normalization"] == "numeric":
            ns, nr = _numeric_n(np.asarray(ti, dtype=np.float64), self._numeric_lobes(term))
        return _run(np.asarray(ti, dtype=np.float64), np.asarray(tr, dtype=np.float64),
                    np.asarray(phi, dtype=np.float64), np.asarray(gamma, dtype=np.float64),
                    p, flag, ns, nr, general=self._force_general)
