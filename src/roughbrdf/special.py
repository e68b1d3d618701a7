"""Special functions that must run inside compiled (Numba) kernels.

Why hand-written: RB08's shadowing function (MODELS.md §4.7) is the regularized upper incomplete
gamma function ``Q(a, x) = Γ(a, x)/Γ(a)``, evaluated per sample inside the model kernel. SciPy's
``scipy.special.gammaincc`` cannot be called from Numba's nopython mode, so :func:`gammaincc_q`
implements it as a Numba scalar. :func:`gammaincc` is its NumPy front end; the tests check it
against ``scipy.special.gammaincc`` (a from 0.5 to 2000, x from 0 to far in the tail).

Method
------
Write ``Q(a, x) = 1 - P(a, x)`` and ``x^a e^-x/Γ(a)`` for the common prefactor.

* ``x < a + 1``: the power series of the lower function,
  ``P = [x^a e^-x/Γ(a)] Σ_k x^k / (a (a+1) ... (a+k))``, then ``Q = 1 - P``
  (here ``P`` is at most ~0.6, so the subtraction loses nothing).
* ``x >= a + 1``: the continued fraction of Legendre for ``Q`` itself
  (``Q = [x^a e^-x/Γ(a)] / (x+1-a- 1(1-a)/(x+3-a- 2(2-a)/(x+5-a- ...)))``), evaluated with the
  modified Lentz algorithm; it gives small ``Q`` with full relative accuracy.
* The prefactor is computed as ``sqrt(a/2π) exp(-bd0(a, x) - stirlerr(a))`` with
  ``bd0(a, x) = a log(a/x) + x - a`` (evaluated with a series where ``x ≈ a``) and Stirling's
  remainder ``stirlerr(a) = log Γ(a) - (a - 1/2) log a + a - log(2π)/2`` (Loader's saddle-point
  form). The naive ``exp(a log x - x - log Γ(a))`` subtracts numbers of size ``a log a`` and
  loses ~``a log a`` ulps (3e-13 relative at a = 500); this form keeps the error at the
  conditioning of the problem itself (~1e-14 relative near ``x = a``; in the far tail
  ``|x - a|`` ulps, as in SciPy).
* Integer ``a`` up to :data:`FINITE_SUM_MAX`: the finite sum
  ``Q(a, x) = e^-x Σ_{k<a} x^k/k!`` (all terms positive: no cancellation); ``a = 1`` is
  ``exp(-x)``.

Vectorizable parts
------------------
:func:`gammaincc_int` (integer ``a <= 17``, a fixed-length masked Horner sum) and the
branch-free :func:`vexp`, :func:`vlog`, :func:`vlog1p`, :func:`vasin` exist so that the RB08
model loop vectorizes (see the section comment below).
"""

from __future__ import annotations

import math
import struct

import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic
from numpy.typing import ArrayLike

from ._kernels import DISABLE_JIT, as_float_array, jit, ufunc

__all__ = ["gammaincc", "gammaincc_q", "gammaincc_int", "stirlerr", "bd0", "FINITE_SUM_MAX",
           "INT_HORNER_MAX", "vexp", "vlog", "vlog1p", "vasin"]

#: largest integer ``a`` for which the finite-sum fast path is used (cost ~a multiply-adds)
FINITE_SUM_MAX = 64

_EPS = 1e-16  # relative size of a term/correction below which a series/CF has converged
_FPMIN = 1e-300  # Lentz's guard against a zero denominator (far below any value reached)
_MAXIT = 100000  # iteration cap: the series/CF need O(sqrt(a)) steps near x = a, ~few far off
_HALF_LOG_2PI = 0.5 * math.log(2.0 * math.pi)
_INV_SQRT_2PI = 1.0 / math.sqrt(2.0 * math.pi)


@jit
def stirlerr(a):
    """Stirling remainder ``log Γ(a) - [(a - 1/2) log a - a + log(2π)/2]`` for ``a > 0``."""
    if a < 15.0:
        # direct formula: the terms are at most ~40 in size here, so the absolute error of
        # the difference stays ~1e-14 and it is only used inside exp() (relative error ~1e-14)
        return math.lgamma(a) - (a - 0.5) * math.log(a) + a - _HALF_LOG_2PI
    # asymptotic (Bernoulli) series; at a >= 15 the first omitted term is < 1e-19
    r = 1.0 / a
    r2 = r * r
    return r * (1.0 / 12.0 - r2 * (1.0 / 360.0 - r2 * (1.0 / 1260.0 - r2 * (
        1.0 / 1680.0 - r2 * (1.0 / 1188.0 - r2 * (691.0 / 360360.0))))))


@jit
def bd0(a, x):
    """Deviance term ``a log(a/x) + x - a >= 0`` without cancellation near ``x = a`` (x > 0)."""
    d = a - x
    if abs(d) < 0.1 * (a + x):
        # with v = (a - x)/(a + x): a log(a/x) = 2a atanh(v) = 2a (v + v^3/3 + v^5/5 + ...),
        # so bd0 = (a - x) v + 2a (v^3/3 + v^5/5 + ...); |v| < 0.1 makes each step 100x smaller
        v = d / (a + x)
        s = d * v
        ej = 2.0 * a * v
        v2 = v * v
        for j in range(1, 1000):
            ej *= v2
            s1 = s + ej / (2 * j + 1)
            if s1 == s:
                return s1
            s = s1
        return s
    return a * math.log(a / x) + x - a


@jit
def _prefactor(a, x, st):
    """``x^a e^-x / Γ(a)`` given ``st = stirlerr(a)`` (x > 0)."""
    return math.sqrt(a) * _INV_SQRT_2PI * math.exp(-bd0(a, x) - st)


@jit
def _q_finite_sum(m, x):
    """``Q(m, x) = e^-x Σ_{k<m} x^k/k!`` for integer ``m >= 1`` and ``0 < x <= 700``."""
    term = math.exp(-x)
    s = term
    for k in range(1, m):
        term *= x / k
        s += term
    # the true value never exceeds 1; round-off in the sum may reach 1 + a few ulps
    return min(s, 1.0)


@jit
def _q_general(a, x, st):
    """Series (x < a + 1) or continued fraction (x >= a + 1); ``a > 0``, ``x > 0``."""
    if x < a + 1.0:
        ap = a
        term = 1.0 / a
        s = term
        for _ in range(_MAXIT):
            ap += 1.0
            term *= x / ap
            s += term
            if term < s * _EPS:
                break
        p = s * _prefactor(a, x, st)
        return max(0.0, 1.0 - p)  # p <= 1 mathematically; clip a last-ulp overshoot
    # modified Lentz for the even part of Legendre's continued fraction
    b = x + 1.0 - a
    c = 1.0 / _FPMIN
    d = 1.0 / b  # b >= 2 here, never zero
    h = d
    for i in range(1, _MAXIT):
        an = -i * (i - a)
        b += 2.0
        d = an * d + b
        if abs(d) < _FPMIN:  # Lentz's rule: replace an exact zero by a tiny number
            d = _FPMIN
        c = b + an / c
        if abs(c) < _FPMIN:
            c = _FPMIN
        d = 1.0 / d
        delta = d * c
        h *= delta
        if abs(delta - 1.0) < _EPS:
            break
    return h * _prefactor(a, x, st)


@jit
def gammaincc_q(a, x, st):
    """Scalar regularized upper incomplete gamma ``Q(a, x)`` for ``a > 0``, ``x >= 0``.

    ``st`` must be :func:`stirlerr` ``(a)`` (precomputed once per parameter set by callers that
    evaluate many ``x`` for one ``a``). NaN in gives NaN out; ``x = inf`` gives 0.
    """
    if x != x or a != a:
        return math.nan
    if x <= 0.0:
        return 1.0  # Q(a, 0) = 1 (also the limit from above); negative x is outside the domain
    if x == math.inf:
        return 0.0
    if a == 1.0:
        return math.exp(-x)  # Q(1, x) = e^-x: RB08 Eq. 11 (n = 0), exactly
    if a <= FINITE_SUM_MAX and x <= 700.0 and a == math.floor(a):
        # integer a: finite sum. x <= 700 keeps e^-x a normal number (exp underflows at 745)
        return _q_finite_sum(int(a), x)
    return _q_general(a, x, st)


@ufunc(2)
def _gammaincc(a, x):
    if not (a > 0.0) or x < 0.0:
        return math.nan  # outside the domain (the front end raises before getting here)
    return gammaincc_q(a, x, stirlerr(a))


def gammaincc(a: ArrayLike, x: ArrayLike) -> np.ndarray:
    """Regularized upper incomplete gamma ``Q(a, x) = Γ(a, x)/Γ(a)`` (compiled; see module doc).

    Same values as ``scipy.special.gammaincc`` (to ~1e-13 relative over ``a`` in [0.5, 2000]);
    exists because the RB08 kernel needs it inside Numba.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> round(float(rb.special.gammaincc(5.0, 5.0)), 12)
    0.440493285065
    """
    aa = as_float_array(a, "a")
    xa = as_float_array(x, "x")
    bad = ~((aa > 0) & np.isfinite(aa))
    if bad.any():
        raise ValueError(f"a must be finite and > 0, got {aa[bad].flat[0]!r}")
    if np.any(np.isnan(xa) | (xa < 0)):
        raise ValueError(f"x must be >= 0, got {xa[~(xa >= 0)].flat[0]!r}")
    return _gammaincc(aa, xa)


# --------------------------------------------------------------------------------------------
# branch-free exp, log, log1p, asin and integer-a Q that LLVM can vectorize
# --------------------------------------------------------------------------------------------
# Why hand-written: Numba's LLVM has no vector math library here (no SVML), so a loop calling
# math.exp/log/asin stays scalar (see roughbrdf._kernels.vmath). These are written with selects instead
# of branches and without libm calls, so a model loop that uses them vectorizes (the RB08 fast
# path). Argument reductions and the log/asin coefficients are fdlibm's (e_log.c, e_asin.c);
# exp uses a degree-13 Taylor polynomial (no division). Accuracy is tested against NumPy
# (1-2 ulp). The bit manipulations use two bit-cast intrinsics (struct-based pure Python under
# NUMBA_DISABLE_JIT=1).

if DISABLE_JIT:

    def _f2i(x):
        """Bits of a float64 as int64."""
        return struct.unpack("<q", struct.pack("<d", float(x)))[0]

    def _i2f(i):
        """int64 bits as a float64."""
        return struct.unpack("<d", struct.pack("<q", int(i)))[0]

else:

    @intrinsic
    def _f2i(typingctx, x):  # pragma: no cover - compiled
        if not isinstance(x, types.Float):
            return None

        def codegen(context, builder, signature, args):
            return builder.bitcast(args[0], ir.IntType(64))

        return types.int64(types.float64), codegen

    @intrinsic
    def _i2f(typingctx, i):  # pragma: no cover - compiled
        if not isinstance(i, types.Integer):
            return None

        def codegen(context, builder, signature, args):
            return builder.bitcast(args[0], ir.DoubleType())

        return types.float64(types.int64), codegen


_INVLN2 = 1.44269504088896338700e00
_LN2HI = 6.93147180369123816490e-01
_LN2LO = 1.90821492927058770002e-10
_EXP_TAYLOR = tuple(1.0 / math.factorial(k) for k in range(14))  # e^r, |r| <= ln2/2: 1 ulp


@jit(inline=True)
def vexp(x):
    """``exp(x)``, branch-free: ``x = k ln2 + r`` (fdlibm's two-part ln2), ``e^r`` by its Taylor
    polynomial of degree 13 (FMAs only, no division; <= 1 ulp on ``|r| <= ln2/2``).

    Correct over the whole float range: overflow to inf above 709.78, gradual underflow to 0
    below -708, NaN in gives NaN.
    """
    nan = x != x
    xc = min(max(0.0 if nan else x, -746.0), 710.0)  # clamped: k stays in the exponent range
    k = math.floor(xc * _INVLN2 + 0.5)
    r = (xc - k * _LN2HI) - k * _LN2LO
    y = _EXP_TAYLOR[13]
    for j in range(12, -1, -1):
        y = y * r + _EXP_TAYLOR[j]
    ki = int(k)
    k1 = ki >> 1  # 2^k = 2^k1 2^k2, each a normal number for k in [-1076, 1024]
    k2 = ki - k1
    res = y * _i2f((k1 + 1023) << 52) * _i2f((k2 + 1023) << 52)
    return math.nan if nan else res


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
    """Natural ``log(x)``, branch-free (fdlibm: ``x = 2^k m``, ``m`` in [sqrt(2)/2, sqrt(2))).

    ``log(0) = -inf``, ``log(inf) = inf``, negative or NaN gives NaN; subnormals are handled.
    """
    special_ = not (x > 0.0) or x == math.inf
    xx = 1.0 if special_ else x
    sub = xx < _TINY_NORMAL
    xx = xx * 18014398509481984.0 if sub else xx  # 2^54: subnormals become normal
    bits = _f2i(xx)
    k = (bits >> 52) - 1023
    m = _i2f((bits & _MANT_MASK) | _ONE_BITS)  # mantissa in [1, 2)
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
    keeps, so the ratio repairs the rounding of ``1 + t``; a few ulp.)
    """
    u = 1.0 + t
    d = u - 1.0
    res = vlog(u) * (t / (d if d != 0.0 else 1.0))
    res = t if d == 0.0 else res
    return math.inf if t == math.inf else res


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


@jit(inline=True)
def _asin_r(t):
    p = t * (_PS0 + t * (_PS1 + t * (_PS2 + t * (_PS3 + t * (_PS4 + t * _PS5)))))
    q = 1.0 + t * (_QS1 + t * (_QS2 + t * (_QS3 + t * _QS4)))
    return p / q


@jit(inline=True)
def vasin(x):
    """``arcsin(x)`` for ``|x| <= 1``, branch-free (fdlibm's rational approximation).

    ``|x| < 1/2``: ``x + x R(x^2)``; otherwise ``pi/2 - 2 arcsin(sqrt((1 - |x|)/2))``.
    Outside [-1, 1] or NaN: NaN.
    """
    ax = abs(x)
    small = x + x * _asin_r(x * x)
    t = 0.5 * (1.0 - min(ax, 1.0))
    s = math.sqrt(t)
    large = _PIO2_HI - (2.0 * (s + s * _asin_r(t)) - _PIO2_LO)
    res = small if ax < 0.5 else (large if x > 0.0 else -large)
    return res if ax <= 1.0 else math.nan


#: largest integer ``n`` (``a = n + 1``) of the vectorizable :func:`gammaincc_int`
INT_HORNER_MAX = 16
_INV_FACT = tuple(1.0 / math.factorial(k) for k in range(INT_HORNER_MAX + 1))


@jit(inline=True)
def gammaincc_int(a, x):
    """``Q(a, x) = e^-x Σ_{k<a} x^k/k!`` for integer-valued ``a`` in [1, INT_HORNER_MAX + 1].

    Branch-free: a fixed-length Horner loop whose coefficients ``1/k!`` are masked to 0 for
    ``k >= a`` (LLVM unrolls it; all terms positive, no cancellation): ~1e-14 relative. In
    the far tail ``x > 708``, ``e^-x`` is subnormal and values below ~1e-290 lose digits;
    ``x > 745`` gives 0. (RB08 only multiplies a width by V: such values act as 0 anyway.)
    """
    s = 0.0
    for j in range(INT_HORNER_MAX + 1):
        k = INT_HORNER_MAX - j
        s = s * x + (_INV_FACT[k] if k < a else 0.0)
    q = vexp(-x) * s
    q = 0.0 if x > 745.0 else q
    return min(q, 1.0)
