"""Special functions that must run inside compiled (Numba) kernels.

Why hand-written: RB08's shadowing function (docs/models.md §4.7) is the regularized upper
incomplete gamma function ``Q(a, x) = Γ(a, x)/Γ(a)``, evaluated per sample inside the model
kernel. SciPy's ``scipy.special.gammaincc`` cannot be called from Numba's nopython mode, so
:func:`gammaincc_q` implements it as a Numba scalar. :func:`gammaincc` is its NumPy front end;
the tests check it against ``scipy.special.gammaincc`` (a from 0.5 to 2000, x from 0 to far in
the tail).

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
:func:`gammaincc_int` (integer ``a <= 17``, a fixed-length masked Horner sum) exists so that
the RB08 model loop vectorizes. The branch-free :func:`vexp`, :func:`vlog`, :func:`vlog1p`,
:func:`vasin` it uses are defined in :mod:`roughbrdf._kernels.vmath` and re-exported here.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from ._kernels import as_float_array, jit, ufunc
from ._kernels.vmath import vasin, vexp, vlog, vlog1p  # noqa: F401 - re-exported

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
# integer-a Q that LLVM can vectorize
# --------------------------------------------------------------------------------------------
# The branch-free exp, log, log1p and asin that the RB08 fast path uses live in
# roughbrdf._kernels.vmath with the other vectorizable elementary functions (accuracy and
# method documented there); they are imported above and stay importable from here.

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
