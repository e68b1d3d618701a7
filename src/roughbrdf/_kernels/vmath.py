"""Vector math: elementary functions written so that LLVM vectorizes the loops that call them.

Numba's LLVM has no vector math library here (no SVML), so a loop that calls ``math.sin``,
``math.exp`` and the like stays a loop of scalar libm calls. The functions here are written
without libm calls and with selects instead of branches; a model loop built from them
vectorizes. Each states its accuracy and is tested against NumPy/SciPy over the range it is
used on (``tests/kernels/test_vmath.py``).

==============  ======================================  =================  ====================
function        method (source of the coefficients)     measured accuracy  used by
==============  ======================================  =================  ====================
:func:`sincos`  fdlibm k_sin/k_cos, Cody-Waite by pi/2  <= 1.2e-16 abs.    every model
:func:`vexp`    2^k e^r, Taylor degree 13               <= 1 ulp           gaussian-angle,
                                                                           Beckmann, Sirohi,
                                                                           RB08
:func:`vlog`    fdlibm e_log.c                          <= 1 ulp           Beckmann, Sirohi D
:func:`vlog1p`  ``log(u) t/(u - 1)``                    <= 2 ulp           RB08
:func:`vasin`   fdlibm e_asin.c                         <= 2 ulp           RB08
:func:`vacos`   fdlibm e_acos.c, one division           <= 1 ulp           gaussian-angle D
                                                                           (TS67, microfacet)
:func:`vatan2`  fdlibm s_atan.c, one division           <= 1 ulp           geometry parts
:func:`verfc`   fdlibm s_erf.c, coefficients selected   <= 2 ulp           Beckmann Smith
                                                                           Lambda
==============  ======================================  =================  ====================

(ulp: the spacing of doubles at the exact value, ``np.spacing``; measured in
``tests/kernels/test_vmath.py`` against NumPy, against SciPy and a 60-digit ``decimal``
reference for erfc, on the FMA-contracted compiled code and on the plain-Python path, which
agree to 2 ulp.)

Writing rules, followed by every function here:

* no libm calls: ``math.sqrt``, ``abs``, ``math.floor``, ``math.copysign`` and ``min``/``max``
  are LLVM intrinsics or selects; everything else is multiply-adds and one or two divisions;
* branch-free: every candidate value is computed and the result picked with a conditional
  expression (LLVM's vectorizer turns those into vector selects); a piecewise approximation
  selects its *coefficients* and evaluates one polynomial instead of one per piece;
* every denominator is kept non-zero and every ``int()`` argument finite, also on the lanes
  whose value is discarded: the plain-Python path (``NUMBA_DISABLE_JIT=1``) computes those
  lanes too and would raise ``ZeroDivisionError``/``ValueError``, and NumPy would report a 0/0
  in a ufunc as a RuntimeWarning;
* bit manipulations use two bit-cast intrinsics (:func:`f2i`, :func:`i2f`), which are plain
  ``struct`` conversions under ``NUMBA_DISABLE_JIT=1``.
"""

from __future__ import annotations

import math
import struct

import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

from .compile import DISABLE_JIT, jit

__all__ = ["TINY", "SINCOS_MAX_ARG", "sincos", "vexp", "vlog", "vlog1p", "vasin", "vacos",
           "vatan2", "verfc", "f2i", "i2f"]

# --------------------------------------------------------------------------------------------
# bit casts between float64 and int64
# --------------------------------------------------------------------------------------------
if DISABLE_JIT:

    def f2i(x):
        """Bits of a float64 as int64."""
        return struct.unpack("<q", struct.pack("<d", float(x)))[0]

    def i2f(i):
        """int64 bits as a float64."""
        return struct.unpack("<d", struct.pack("<q", int(i)))[0]

else:

    @intrinsic
    def f2i(typingctx, x):  # pragma: no cover - compiled
        """Bits of a float64 as int64 (an LLVM bitcast)."""
        if not isinstance(x, types.Float):
            return None

        def codegen(context, builder, signature, args):
            return builder.bitcast(args[0], ir.IntType(64))

        return types.int64(types.float64), codegen

    @intrinsic
    def i2f(typingctx, i):  # pragma: no cover - compiled
        """int64 bits as a float64 (an LLVM bitcast)."""
        if not isinstance(i, types.Integer):
            return None

        def codegen(context, builder, signature, args):
            return builder.bitcast(args[0], ir.DoubleType())

        return types.float64(types.int64), codegen


#: int64 mask that keeps the high 32 bits of a float64 (``0xFFFFFFFF00000000`` as a signed
#: int64: a uint64 literal would make Numba promote the ``&`` to float)
_HIGH_WORD = -(1 << 32)

# --------------------------------------------------------------------------------------------
# sin and cos
# --------------------------------------------------------------------------------------------
# Cody-Waite reduction by pi/2 in three 33-bit parts (fdlibm e_rem_pio2.c: pio2_1, pio2_2,
# pio2_3): k * pio2_j is exact for |k| < 2**20, so the reduced argument is accurate for
# |x| <= SINCOS_MAX_ARG. Polynomials on [-pi/4, pi/4]: fdlibm k_sin.c / k_cos.c (< 1 ulp).
#: added to a denominator that may be exactly 0 where the quotient is then discarded or 0/TINY
#: = 0; LLVM evaluates both sides of selects, and NumPy reports a 0/0 in a ufunc as a warning
TINY = 1e-300
SINCOS_MAX_ARG = 2.0**19 * 0.5 * math.pi  # 8.2e5 rad; front ends reduce larger azimuths
_INVPIO2 = 6.36619772367581382433e-01
_PIO2_1 = 1.57079632673412561417e00
_PIO2_2 = 6.07710050630396597660e-11
_PIO2_3 = 2.02226624871116645580e-21
_S1 = -1.66666666666666324348e-01
_S2 = 8.33333333332248946124e-03
_S3 = -1.98412698298579493134e-04
_S4 = 2.75573137070700676789e-06
_S5 = -2.50507602534068634195e-08
_S6 = 1.58969099521155010221e-10
_C1 = 4.16666666666666019037e-02
_C2 = -1.38888888888741095749e-03
_C3 = 2.48015872894767294178e-05
_C4 = -2.75573143513906633035e-07
_C5 = 2.08757232129817482790e-09
_C6 = -1.13596475577881948265e-11


@jit(inline=True)
def sincos(x):
    """``(sin x, cos x)`` without libm calls, so that loops using it vectorize.

    Absolute error <= 1.2e-16 (tested against NumPy for |x| <= ``SINCOS_MAX_ARG``); NaN gives
    NaN. Branch-free: the quadrant is selected with comparisons on a float, never an int cast
    (NaN-safe).
    """
    k = np.floor(x * _INVPIO2 + 0.5)  # np.floor: NaN-safe also as plain Python
    r = ((x - k * _PIO2_1) - k * _PIO2_2) - k * _PIO2_3
    z = r * r
    s = r + r * z * (_S1 + z * (_S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))))
    hz = 0.5 * z
    w = 1.0 - hz
    c = w + (((1.0 - w) - hz)
             + z * z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6))))))
    q = k - 4.0 * np.floor(0.25 * k)  # quadrant 0..3, as a float
    odd = q == 1.0 or q == 3.0
    a = c if odd else s
    b = s if odd else c
    sn = -a if q >= 2.0 else a
    cs = -b if (q == 1.0 or q == 2.0) else b
    return sn, cs


# --------------------------------------------------------------------------------------------
# exp
# --------------------------------------------------------------------------------------------
_INVLN2 = 1.44269504088896338700e00
_LN2HI = 6.93147180369123816490e-01  # fdlibm e_exp.c: ln2 in two parts, k * _LN2HI exact
_LN2LO = 1.90821492927058770002e-10
_EXP_TAYLOR = tuple(1.0 / math.factorial(k) for k in range(14))  # e^r, |r| <= ln2/2: 1 ulp
_EXP_MIN = -746.0  # below: e^x < 2^-1075, rounds to 0
_EXP_MAX = 710.0  # above: e^x > DBL_MAX, overflows to inf


@jit(inline=True)
def vexp(x):
    """``exp(x)``, branch-free and without libm calls.

    Method: ``x = k ln2 + r`` with ``|r| <= ln2/2`` (Cody-Waite with fdlibm's two-part ln2),
    ``e^r`` by its Taylor polynomial of degree 13 (multiply-adds only, no division; the
    truncation error is 4e-18 relative), and ``2^k`` built from the exponent bits as the
    product of two normal powers of two (so that gradual underflow rounds once).

    Accuracy: <= 1 ulp over the whole float range (measured). Valid for every float: overflow
    to ``inf`` above 709.78, gradual underflow (subnormal results) below -708.4 and 0 below
    -745.2; ``exp(-inf) = 0``, ``exp(inf) = inf``, NaN gives NaN.
    """
    nan = x != x
    # clamped: k then stays in the exponent range and int(k) is finite (NaN -> 0, then NaN out)
    xc = min(max(0.0 if nan else x, _EXP_MIN), _EXP_MAX)
    k = math.floor(xc * _INVLN2 + 0.5)
    r = (xc - k * _LN2HI) - k * _LN2LO
    y = _EXP_TAYLOR[13]
    for j in range(12, -1, -1):
        y = y * r + _EXP_TAYLOR[j]
    ki = int(k)
    k1 = ki >> 1  # 2^k = 2^k1 2^k2, each a normal number for k in [-1076, 1024]
    k2 = ki - k1
    res = y * i2f((k1 + 1023) << 52) * i2f((k2 + 1023) << 52)
    return math.nan if nan else res


@jit(inline=True)
def _vexp2(hi, lo):
    """``exp(hi + lo)`` for a two-part argument (``|lo|`` below ~1, ``hi + lo`` rounded is not
    what is wanted): :func:`vexp` with ``lo`` added to the reduced argument, so that the
    rounding of ``hi + lo`` never enters. <= 1 ulp of the exact ``exp(hi + lo)``."""
    s = hi + lo
    nan = s != s
    inr = s >= _EXP_MIN and s <= _EXP_MAX  # (False for NaN)
    # outside the range the result is 0 or inf: use the clamped one-part argument there
    h = hi if inr else min(max(0.0 if nan else s, _EXP_MIN), _EXP_MAX)
    lw = lo if inr else 0.0
    k = math.floor((h + lw) * _INVLN2 + 0.5)
    r = ((h - k * _LN2HI) + lw) - k * _LN2LO
    y = _EXP_TAYLOR[13]
    for j in range(12, -1, -1):
        y = y * r + _EXP_TAYLOR[j]
    ki = int(k)
    k1 = ki >> 1  # as in vexp
    k2 = ki - k1
    res = y * i2f((k1 + 1023) << 52) * i2f((k2 + 1023) << 52)
    return math.nan if nan else res


# --------------------------------------------------------------------------------------------
# log, log1p
# --------------------------------------------------------------------------------------------
_LG1 = 6.666666666666735130e-01
_LG2 = 3.999999999940941908e-01
_LG3 = 2.857142874366239149e-01
_LG4 = 2.222219843214978396e-01
_LG5 = 1.818357216161805012e-01
_LG6 = 1.531383769920937332e-01
_LG7 = 1.479819860511658591e-01
_SQRT2 = 1.4142135623730951
_TINY_NORMAL = 2.2250738585072014e-308
_MANT_MASK = 0x000FFFFFFFFFFFFF
_ONE_BITS = 0x3FF0000000000000


@jit(inline=True)
def vlog(x):
    """Natural ``log(x)``, branch-free (fdlibm e_log.c: ``x = 2^k m``, ``m`` in
    [sqrt(2)/2, sqrt(2)), ``log(m) = 2 atanh(f/(2 + f))`` by fdlibm's Lg1..Lg7 polynomial).

    Accuracy: <= 1 ulp for all positive floats (measured 1e-300 to 1e300 and subnormals).
    ``log(0) = -inf``, ``log(inf) = inf``, negative or NaN gives NaN; subnormals are scaled by
    2^54 first.
    """
    special_ = not (x > 0.0) or x == math.inf
    xx = 1.0 if special_ else x  # a harmless stand-in on the special lanes (result replaced)
    sub = xx < _TINY_NORMAL
    xx = xx * 18014398509481984.0 if sub else xx  # 2^54: subnormals become normal
    bits = f2i(xx)
    k = (bits >> 52) - 1023
    m = i2f((bits & _MANT_MASK) | _ONE_BITS)  # mantissa in [1, 2)
    big = m > _SQRT2
    m = 0.5 * m if big else m
    kf = float(k) + (1.0 if big else 0.0) - (54.0 if sub else 0.0)
    f = m - 1.0
    s = f / (2.0 + f)
    z = s * s
    w = z * z
    t1 = w * (_LG2 + w * (_LG4 + w * _LG6))
    t2 = z * (_LG1 + w * (_LG3 + w * (_LG5 + w * _LG7)))
    hfsq = 0.5 * f * f
    res = kf * _LN2HI - ((hfsq - (s * (hfsq + t1 + t2) + kf * _LN2LO)) - f)
    if special_:
        res = math.inf if x == math.inf else (-math.inf if x == 0.0 else math.nan)
    return res


@jit(inline=True)
def vlog1p(t):
    """``log(1 + t)`` for ``t >= -1`` without cancellation: ``log(u) t/(u - 1)``, ``u = 1 + t``.

    (The classic correction: ``u - 1`` is the exactly representable part of ``t`` that ``u``
    keeps, so the ratio repairs the rounding of ``1 + t``.) Accuracy <= 2 ulp (measured on
    [-0.999, 1e30]); ``t = inf`` gives inf (raising the invalid flag internally), ``t = -1``
    gives -inf, ``t < -1`` or NaN gives NaN.
    """
    u = 1.0 + t
    d = u - 1.0
    # stand-in 1 where d = 0 (|t| < ulp(1)/2, result t below): no 0/0. (t = inf computes
    # inf/inf, invalid flag, on a lane whose result is replaced by inf: guarding that too cost
    # 5 % of RB08's time, measured, and RB08 never passes inf.)
    res = vlog(u) * (t / (d if d != 0.0 else 1.0))
    res = t if d == 0.0 else res
    return math.inf if t == math.inf else res


# --------------------------------------------------------------------------------------------
# asin, acos
# --------------------------------------------------------------------------------------------
# fdlibm e_asin.c / e_acos.c: asin(x) = x + x R(x^2) on |x| < 1/2, R = pS/qS rational; beyond,
# through t = (1 - |x|)/2: asin(x) = pi/2 - 2 asin(sqrt(t)), acos(x) = 2 asin(sqrt(t)).
_PS0 = 1.66666666666666657415e-01
_PS1 = -3.25565818622400915405e-01
_PS2 = 2.01212532134862925881e-01
_PS3 = -4.00555345006794114027e-02
_PS4 = 7.91534994289814532176e-04
_PS5 = 3.47933107596021167570e-05
_QS1 = -2.40339491173441421878e00
_QS2 = 2.02094576023350569471e00
_QS3 = -6.88283971605453293030e-01
_QS4 = 7.70381505559019352791e-02
_PIO2_HI = 1.57079632679489655800e00
_PIO2_LO = 6.12323399573676603587e-17
_PI_HI = 3.14159265358979311600e00
_PI_LO = 1.22464679914735317720e-16


@jit(inline=True)
def _asin_r(t):
    p = t * (_PS0 + t * (_PS1 + t * (_PS2 + t * (_PS3 + t * (_PS4 + t * _PS5)))))
    q = 1.0 + t * (_QS1 + t * (_QS2 + t * (_QS3 + t * _QS4)))  # in [0.6, 1] for t in [0, 1/4]
    return p / q


@jit(inline=True)
def vasin(x):
    """``arcsin(x)`` for ``|x| <= 1``, branch-free (fdlibm e_asin.c's rational approximation).

    ``|x| < 1/2``: ``x + x R(x^2)``; otherwise ``pi/2 - 2 arcsin(sqrt((1 - |x|)/2))``.
    Accuracy <= 2 ulp (measured on [-1, 1]); outside [-1, 1] or NaN: NaN.
    """
    ax = abs(x)
    small = x + x * _asin_r(x * x)
    t = 0.5 * (1.0 - min(ax, 1.0))  # min: keeps sqrt's argument >= 0 (plain Python raises)
    s = math.sqrt(t)
    large = _PIO2_HI - (2.0 * (s + s * _asin_r(t)) - _PIO2_LO)
    res = small if ax < 0.5 else (large if x > 0.0 else -large)
    return res if ax <= 1.0 else math.nan


@jit(inline=True)
def vacos(x):
    """``arccos(x)`` for ``|x| <= 1``, branch-free (fdlibm e_acos.c), one division.

    Method (fdlibm): ``|x| < 1/2``: ``pi/2 - (x + x R(x^2))`` with pi/2 in two parts;
    ``x >= 1/2``: ``2 (df + w)``, ``w = s R(z) + (z - df^2)/(s + df)``, with
    ``z = (1 - x)/2``, ``s = sqrt(z)`` and ``df`` its high 21 bits (``df^2`` exact, so the
    correction term restores the bits of ``s`` that ``df`` drops); ``x <= -1/2``:
    ``pi - 2 (s + s R(z) - pi_lo/2)``. ``R = P/Q`` is fdlibm's rational approximation (the one
    of e_asin.c). Here the three pieces share one quotient: its numerator and denominator are
    selected per lane (``P/Q``; ``[P s (s + df) + (z - df^2) Q]/[Q (s + df)]``, i.e. ``w`` in
    one division; ``P s/Q``), which moves only the rounding of ``w``, itself below 1/20 of
    the result.

    Accuracy: <= 1 ulp on [-1, 1] (measured); ``acos(1) = 0``, ``acos(-1) = pi``, outside
    [-1, 1] or NaN: NaN. Near ``x = 1`` the *function* is ill-conditioned (an ulp of ``x``
    moves acos by ``sqrt(2 ulp)``): callers that start from a vector should prefer
    :func:`vatan2`.
    """
    ax = abs(x)
    lo = ax < 0.5
    pos = x > 0.0
    z = 0.5 * (1.0 - min(ax, 1.0))  # min: keeps sqrt's argument >= 0 (plain Python raises)
    s = math.sqrt(z)
    t = x * x if lo else z
    p = t * (_PS0 + t * (_PS1 + t * (_PS2 + t * (_PS3 + t * (_PS4 + t * _PS5)))))
    q = 1.0 + t * (_QS1 + t * (_QS2 + t * (_QS3 + t * _QS4)))  # in [0.6, 1] for t in [0, 1/4]
    # x >= 1/2: df = s with the low 32 bits cleared, so df * df and z - df * df are exact
    df = i2f(f2i(s) & _HIGH_WORD)
    sdf = s + df
    num = p if lo else (p * s * sdf + (z - df * df) * q if pos else p * s)
    den = q if lo else (q * sdf if pos else q)
    u = num / (den if den > 0.0 else 1.0)  # den = 0 only at x = 1 (s = df = 0; num = 0: u = 0)
    small = _PIO2_HI - (x - (_PIO2_LO - x * u))
    posr = 2.0 * (df + u)
    negr = _PI_HI - 2.0 * (s + (u - _PIO2_LO))
    res = small if lo else (posr if pos else negr)
    return res if ax <= 1.0 else math.nan


# --------------------------------------------------------------------------------------------
# atan2
# --------------------------------------------------------------------------------------------
# fdlibm s_atan.c: atan on [0, 7/16) directly, on [7/16, 11/16) as atan(1/2) + atan of
# (2t - 1)/(2 + t), on [11/16, 1] as atan(1) + atan((t - 1)/(t + 1)); polynomial aT[0..10],
# table values atan(1/2), atan(1) in two parts (hi + lo).
_AT0 = 3.33333333333329318027e-01
_AT1 = -1.99999999998764832476e-01
_AT2 = 1.42857142725034663711e-01
_AT3 = -1.11111104054623557880e-01
_AT4 = 9.09088713343650656196e-02
_AT5 = -7.69187620504482999495e-02
_AT6 = 6.66107313738753120669e-02
_AT7 = -5.83357013379057348645e-02
_AT8 = 4.97687799461593236017e-02
_AT9 = -3.65315727442169155270e-02
_AT10 = 1.62858201153657823623e-02
_ATAN_HALF_HI = 4.63647609000806093515e-01
_ATAN_HALF_LO = 2.26987774529616870924e-17
_ATAN_ONE_HI = 7.85398163397448278999e-01
_ATAN_ONE_LO = 3.06161699786838301793e-17
_TWO_M1000 = 2.0**-1000
_TWO_P1000 = 2.0**1000


@jit(inline=True)
def vatan2(y, x):
    """``atan2(y, x)`` in [-pi, pi], branch-free (fdlibm s_atan.c polynomial and table).

    Method: with ``n = min(|x|, |y|)``, ``d = max(|x|, |y|)`` the angle is ``K + sigma
    atan(n/d)`` (``K`` in {0, pi/2, pi}, ``sigma = +-1`` by octant), and ``atan`` on [0, 1] is
    fdlibm's: the reduced argument of each of its three intervals is formed directly from
    ``n`` and ``d`` (``n/d``, ``(2n - d)/(2d + n)``, ``(n - d)/(n + d)``, numerators exact),
    so the whole function costs one division. ``K + sigma atan(1/2 or 1)`` is added in two
    parts (Fast2Sum), so the octant offset adds no rounding of its own. ``n, d`` are scaled
    by a power of two when ``d`` is huge or tiny (no overflow in ``2d + n``, no loss in a
    subnormal ``d``).

    Accuracy: <= 1 ulp for all finite ``(y, x)`` (measured, including subnormal and huge
    arguments). Special values as C99/NumPy: ``atan2(+-0, +0) = +-0``,
    ``atan2(+-0, -0) = +-pi``, ``atan2(+-inf, +-inf) = +-pi/4`` or ``+-3pi/4``,
    ``atan2(y, -inf) = +-pi``, ``atan2(+-inf, x) = +-pi/2``; the sign of ``y`` (also of a
    zero) gives the sign of the result; NaN in either gives NaN.
    """
    ay = abs(y)
    ax = abs(x)
    swap = ay > ax
    n = ax if swap else ay
    d = ay if swap else ax
    both_inf = n == math.inf  # (then d is inf too) the angle is a multiple of pi/4
    n = 1.0 if both_inf else n
    d = 1.0 if both_inf else d
    # scale by a power of two (exact): 2d + n must not overflow and 2n - d must not lose bits
    # in subnormals. (Downscaling by 2^-8 can only make n subnormal when n/d < 2^-1000, whose
    # atan underflows to 0 anyway.)
    sc = 0.00390625 if d > _TWO_P1000 else (1152921504606846976.0 if d < _TWO_M1000 else 1.0)
    n = n * sc
    d = d * sc
    # interval of fdlibm's atan: t = n/d in [0, 7/16], (7/16, 11/16], (11/16, 1]
    i0 = n <= 0.4375 * d  # (n = d = 0 lands here: atan(0) = 0)
    i1 = n <= 0.6875 * d
    # reduced argument, one division; the numerators are exact (Sterbenz: 2n and d, n and d
    # are within a factor 2 of each other on their intervals). Selected, not blended with 0/1
    # weights: 0 * d would be NaN for d = inf.
    num = n if i0 else (2.0 * n - d if i1 else n - d)
    den = d if i0 else (2.0 * d + n if i1 else n + d)
    t = num / (den if den > 0.0 else 1.0)  # den = 0 only for n = d = 0 (num = 0: t = 0)
    tab_hi = 0.0 if i0 else (_ATAN_HALF_HI if i1 else _ATAN_ONE_HI)
    tab_lo = 0.0 if i0 else (_ATAN_HALF_LO if i1 else _ATAN_ONE_LO)
    z = t * t
    w = z * z
    s1 = z * (_AT0 + w * (_AT2 + w * (_AT4 + w * (_AT6 + w * (_AT8 + w * _AT10)))))
    s2 = w * (_AT1 + w * (_AT3 + w * (_AT5 + w * (_AT7 + w * _AT9))))
    err = (t * (s1 + s2) - tab_lo) - t  # atan(n/d) = tab_hi - err
    # octant: K + sigma atan(n/d)
    xneg = math.copysign(1.0, x) < 0.0  # also -0
    k_hi = (_PIO2_HI if swap else (_PI_HI if xneg else 0.0))
    k_lo = (_PIO2_LO if swap else (_PI_LO if xneg else 0.0))
    sigma = 1.0 if (swap and xneg) or not (swap or xneg) else -1.0
    h = k_hi + sigma * tab_hi  # |k_hi| >= |tab_hi| or k_hi = 0: Fast2Sum is exact
    h_err = (k_hi - h) + sigma * tab_hi
    res = h + ((h_err + k_lo) - sigma * err)
    res = math.copysign(res, y)
    return math.nan if (x != x or y != y) else res


# --------------------------------------------------------------------------------------------
# erfc
# --------------------------------------------------------------------------------------------
# fdlibm s_erf.c, four intervals of |x|, each a rational approximation P(v)/Q(v):
#   [0, 0.84375)      v = x^2,     erfc = 1 - (x + x P/Q)       (erf's series form)
#   [0.84375, 1.25)   v = |x| - 1, erfc = (1 - erx) -+ P/Q      (expansion about x = 1)
#   [1.25, 1/0.35)    v = 1/x^2,   erfc = exp(-x^2 - 0.5625 + P/Q)/|x|   (ra/sa)
#   [1/0.35, 28)      v = 1/x^2,   same form                             (rb/sb)
# erfc(-x) = 2 - erfc(x). The coefficients of the lane's interval are selected first and one
# numerator (degree 7) and one denominator (degree 8) are evaluated; unused high coefficients
# are 0 (exact: they add nothing). Tables: index 0..3 = interval, numerator c0..c7, denominator
# 1 + d1 v + ... + d8 v^8.
_ERX = 8.45062911510467529297e-01
_ERFC_NUM = (
    (1.28379167095512558561e-01, -3.25042107247001499370e-01, -2.84817495755985104766e-02,
     -5.77027029648944159157e-03, -2.37630166566501626084e-05, 0.0, 0.0, 0.0),
    (-2.36211856075265944077e-03, 4.14856118683748331666e-01, -3.72207876035701323847e-01,
     3.18346619901161753674e-01, -1.10894694282396677476e-01, 3.54783043256182359371e-02,
     -2.16637559486879084300e-03, 0.0),
    (-9.86494403484714822705e-03, -6.93858572707181764372e-01, -1.05586262253232909814e01,
     -6.23753324503260060396e01, -1.62396669462573470355e02, -1.84605092906711035994e02,
     -8.12874355063065934246e01, -9.81432934416914548592e00),
    (-9.86494292470009928597e-03, -7.99283237680523006574e-01, -1.77579549177547519889e01,
     -1.60636384855821916062e02, -6.37566443368389627722e02, -1.02509513161107724954e03,
     -4.83519191608651397019e02, 0.0),
)
_ERFC_DEN = (
    (3.97917223959155352819e-01, 6.50222499887672944485e-02, 5.08130628187576562776e-03,
     1.32494738004321644526e-04, -3.96022827877536812320e-06, 0.0, 0.0, 0.0),
    (1.06420880400844228286e-01, 5.40397917702171048937e-01, 7.18286544141962662868e-02,
     1.26171219808761642112e-01, 1.36370839120290507362e-02, 1.19844998467991074170e-02,
     0.0, 0.0),
    (1.96512716674392571292e01, 1.37657754143519042600e02, 4.34565877475229228821e02,
     6.45387271733267880336e02, 4.29008140027567833386e02, 1.08635005541779435134e02,
     6.57024977031928170135e00, -6.04244152148580987438e-02),
    (3.03380607434824582924e01, 3.25792512996573918826e02, 1.53672958608443695994e03,
     3.19985821950859553908e03, 2.55305040643316442583e03, 4.74528541206955367215e02,
     -2.24409524465858183362e01, 0.0),
)
_ERFC_X1 = 0.84375
_ERFC_X2 = 1.25
_ERFC_X3 = 1.0 / 0.35
_ERFC_XMAX = 28.0  # erfc(28) = 6e-343: below the smallest subnormal


@jit(inline=True)
def _sel4(i1, i2, i3, v0, v1, v2, v3):
    """``v0`` below interval 1, ``v1`` in 1, ``v2`` in 2, ``v3`` from 3 on (``i_j``: x is at
    least the lower end of interval ``j``)."""
    return v3 if i3 else (v2 if i2 else (v1 if i1 else v0))


@jit(inline=True)
def verfc(x):
    """Complementary error function ``erfc(x) = 1 - erf(x)``, branch-free (fdlibm s_erf.c).

    Method: fdlibm's four rational approximations (see the table above this function); the
    interval's coefficients are selected per lane and one numerator/denominator pair is
    evaluated. On ``|x| >= 1.25`` the factor ``exp(-x^2 - 0.5625 + P/Q)`` is evaluated as
    ``exp(hi + lo)`` (:func:`_vexp2`): ``x^2`` is formed exactly from ``x`` split into its
    high 21 bits ``z`` (``-x^2 = -z^2 + (z - x)(z + x)``) and ``-z^2 - 0.5625`` by Fast2Sum,
    so the large exponent adds no rounding (a naive ``exp(-x*x)`` loses up to ``x^2`` ulp).

    Accuracy: <= 2 ulp where the result is a normal number (x < 26.55; measured against a
    60-digit reference: 1 ulp but at one point of [1.25, 2.86)); SciPy's own ``erfc`` is
    within 5.7e-14 relative of it. On (26.55, 27.3) the result is subnormal, within one
    subnormal spacing (5e-324). ``erfc(x) = 0`` for ``x >= 28`` (also ``inf``; it underflows
    from 27.3 on), ``2`` for ``x <= -6`` as far as a double can tell (also ``-inf``); NaN
    gives NaN. No floating-point exception flag for any non-NaN argument.
    """
    ax = abs(x)
    i1 = ax >= _ERFC_X1
    i2 = ax >= _ERFC_X2
    i3 = ax >= _ERFC_X3
    # |x| >= 28 gives 0 or 2 (selected at the end): compute with |x| clamped to 28 there, so
    # that no lane forms x^2 = inf (overflow flag) or inf - inf (invalid flag), which NumPy
    # would report as warnings of a ufunc built on this function
    ax = min(ax, _ERFC_XMAX)
    xs = math.copysign(ax, x)
    # 1/x^2 only where it is the variable (x^2 >= 1.5625 there: no division by 0)
    inv2 = 1.0 / (xs * xs if i2 else 1.0)
    v = inv2 if i2 else (ax - 1.0 if i1 else xs * xs)
    p = _sel4(i1, i2, i3, _ERFC_NUM[0][7], _ERFC_NUM[1][7], _ERFC_NUM[2][7], _ERFC_NUM[3][7])
    for j in range(6, -1, -1):
        p = p * v + _sel4(i1, i2, i3, _ERFC_NUM[0][j], _ERFC_NUM[1][j], _ERFC_NUM[2][j],
                          _ERFC_NUM[3][j])
    q = _sel4(i1, i2, i3, _ERFC_DEN[0][7], _ERFC_DEN[1][7], _ERFC_DEN[2][7], _ERFC_DEN[3][7])
    for j in range(6, -1, -1):
        q = q * v + _sel4(i1, i2, i3, _ERFC_DEN[0][j], _ERFC_DEN[1][j], _ERFC_DEN[2][j],
                          _ERFC_DEN[3][j])
    q = 1.0 + v * q  # > 0.5 on every interval (fdlibm's S, Q polynomials)
    y = p / q
    # [0, 0.84375): fdlibm keeps 1 - erf accurate by two forms split at x = 1/4
    r0 = 1.0 - (xs + xs * y) if xs < 0.25 else 0.5 - (xs * y + (xs - 0.5))
    # [0.84375, 1.25)
    r1 = (1.0 - _ERX) - y if xs >= 0.0 else 1.0 + (_ERX + y)
    # [1.25, 28): exp(-x^2 - 0.5625 + y)/|x|, -x^2 = -z^2 + (z - ax)(z + ax) exactly
    z = i2f(f2i(ax) & _HIGH_WORD)  # z^2 exact (21-bit mantissa)
    hi = -z * z - 0.5625
    lo = ((-z * z - hi) - 0.5625) + ((z - ax) * (z + ax) + y)  # Fast2Sum error, |z^2| > 0.5625
    tail = _vexp2(hi, lo) / (ax if i2 else 1.0)  # (ax >= 1.25 where it is used)
    r2 = tail if xs > 0.0 else 2.0 - tail
    res = r2 if i2 else (r1 if i1 else r0)
    # |x| >= 28: erfc underflows to 0 (x > 0) or is 2 (x < 0)
    res = (0.0 if xs > 0.0 else 2.0) if ax >= _ERFC_XMAX else res
    return math.nan if x != x else res
