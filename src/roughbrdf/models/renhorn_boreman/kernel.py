"""The compiled RB08 kernel: the packed parameters, the scalar parts and the drivers.

Renhorn & Boreman (2008), Eqs. 5-20 as read in docs/models.md §4 (the formulas are in the
package docstring, :mod:`roughbrdf.models.renhorn_boreman`); :func:`run` evaluates them for
:class:`~roughbrdf.models.renhorn_boreman.model.RenhornBoreman2008` from its packed parameter
tuple (the layout below; the model's ``_pack`` writes it).

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
  angles; 2 cores): 0.27 ms per evaluation, against 1.6 ms for the general kernel.
* **general** (per-sample polarization, and
  :meth:`~roughbrdf.models.renhorn_boreman.RenhornBoreman2008.with_general_kernel`, the
  reference): the incomplete gamma per sample (loops: not vectorized); the
  incidence-only quantities (``sin/cos theta_i``, ``R(alpha0)``, ``V(alpha0)``, ``N``,
  ``E0``) are recomputed only when ``theta_i`` changes within a chunk of 1024 samples.
  ~1e6-4e6 evaluations/s.

All three give the same numbers (tested to 1e-13; the tabulated and general kernels agree
bit for bit on the data measured).

Every compiled function of the model is here except those of the numeric normalization's
quadrature (:mod:`~roughbrdf.models.renhorn_boreman.normalization`, which builds on
:mod:`roughbrdf.shadowing` only): the on-disk cache key of a kernel covers its own file and the
compiled parts outside ``models/`` (:mod:`roughbrdf._kernels.cache`), so no compiled function
here may be built from a part in another file of ``models/``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ... import _kernels, special
from ... import shadowing as shd
from ..._kernels import at, driver, jit, sincos
from ...fresnel import fresnel_sp

__all__ = ["NORM_CODES", "POL_WEIGHT", "RETRO_CODES", "TERM_CODES", "WEIGHT_CODES",
           "ZETA_CODES", "rb08_norm", "rb08_norm_ufunc", "run"]

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


def run(ti: np.ndarray, tr: np.ndarray, phi: np.ndarray, gamma: np.ndarray, p: tuple,
        flag: int, ns: np.ndarray | None = None, nr: np.ndarray | None = None,
        general: bool = False) -> np.ndarray | float:
    """Broadcast the inputs and run the fast, tabulated or general driver.

    ``ns``/``nr``: numeric N per sample (None: the analytic N). The fast (vectorized) drivers
    take integer n, n_r, one polarization for all samples and the analytic N; ``theta_i`` is
    passed as a float when it is one value (LLVM then hoists every incidence quantity out of
    the loop), ``theta_s`` and ``phi`` always as arrays, which keeps the number of compiled
    variants (each ~5 s the first time, then cached on disk) at four. Real n or numeric N with
    one polarization run the tabulated driver (V through a memo, then the vectorized loop: two
    variants); per-sample polarization, or ``general``
    (:meth:`~roughbrdf.models.renhorn_boreman.RenhornBoreman2008.with_general_kernel`), the
    general driver.
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


@_kernels.ufunc(3)
def rb08_norm_ufunc(ci2, a02, rho):
    """:func:`rb08_norm` over arrays (a NumPy ufunc, compiled on its first call)."""
    return rb08_norm(ci2, a02, rho)
