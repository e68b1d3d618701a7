"""Accuracy of the vectorizable elementary functions (``roughbrdf._kernels.vmath``).

Each function is compared with NumPy (``exp``, ``log``, ``log1p``, ``arcsin``, ``arccos``,
``arctan2``; glibc's, correctly rounded or within 1 ulp) or SciPy (``scipy.special.erfc``) over
the whole range it is used on, plus the edge cases: 0, tiny, huge, +-inf, NaN and both sides
of the ends of every reduction interval.

Tolerances are in ulp of the reference value, measured as ``|got - want| / np.spacing(want)``;
each is the largest error measured on the compiled code (FMA-contracted) and on the plain-Python
path, and the bound stated in the function's docstring. SciPy's ``erfc`` (Cephes' algorithm) is
itself accurate only to 5.7e-14 relative on [0, 26.6] (Cephes' documented peak error; up to
~500 ulp measured here), so ``verfc`` is checked against it with that tolerance and, to the
ulp, against a 60-digit ``decimal`` evaluation (:func:`_erfc_decimal`).
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
import textwrap
from decimal import Decimal, localcontext

import numpy as np
import pytest
from scipy import special

from roughbrdf._kernels import DISABLE_JIT
from roughbrdf._kernels import vmath as V

TINY_SUB = 5e-324  # smallest subnormal
LN2 = math.log(2.0)


def _ufunc1(fn):
    """A NumPy-callable vectorized version of a scalar vmath function (compiled unless
    NUMBA_DISABLE_JIT=1)."""
    if DISABLE_JIT:
        return np.vectorize(fn, otypes=[np.float64])
    import numba

    @numba.vectorize(["f8(f8)"])
    def u(x):  # pragma: no cover - compiled
        return fn(x)

    return u


def _ufunc2(fn):
    if DISABLE_JIT:
        return np.vectorize(fn, otypes=[np.float64])
    import numba

    @numba.vectorize(["f8(f8, f8)"])
    def u(y, x):  # pragma: no cover - compiled
        return fn(y, x)

    return u


EXP, LOG, LOG1P = _ufunc1(V.vexp), _ufunc1(V.vlog), _ufunc1(V.vlog1p)
ASIN, ACOS, ERFC = _ufunc1(V.vasin), _ufunc1(V.vacos), _ufunc1(V.verfc)
ATAN2 = _ufunc2(V.vatan2)


def ulp_error(got, want):
    """Largest ``|got - want|`` in units of ``np.spacing(want)`` over finite ``want``; values
    that must be 0, inf or NaN have to match exactly."""
    got = np.asarray(got, dtype=float)
    want = np.asarray(want, dtype=float)
    fin = np.isfinite(want)
    np.testing.assert_array_equal(got[~fin], want[~fin])
    assert np.all(np.isfinite(got[fin]))
    zero = fin & (want == 0.0)
    np.testing.assert_array_equal(got[zero], 0.0)
    nz = fin & ~zero
    if not nz.any():
        return 0.0
    return float(np.max(np.abs(got[nz] - want[nz]) / np.spacing(np.abs(want[nz]))))


def around(points, k=3):
    """Each point and its ``k`` neighbouring doubles on either side (reduction-interval ends)."""
    out = []
    for p in np.atleast_1d(np.asarray(points, dtype=float)):
        lo = hi = p
        out.append(p)
        for _ in range(k):
            lo, hi = np.nextafter(lo, -np.inf), np.nextafter(hi, np.inf)
            out += [lo, hi]
    return np.array(out)


# ------------------------------------------------------------------------------------------
# exp, log, log1p
# ------------------------------------------------------------------------------------------
def exp_points():
    rng = np.random.default_rng(1)
    k = np.arange(-1075, 1024)
    return np.concatenate([
        rng.uniform(-745.2, 709.78, 200_000),  # the whole finite range, incl. subnormal results
        rng.uniform(-1.0, 1.0, 20_000),
        around((k + 0.5) * LN2, 1),  # ends of the reduction intervals |r| <= ln2/2
        around([0.0, -708.3964185322641, -745.1332191019411, 709.782712893384]),  # e^x normal
        [TINY_SUB, -TINY_SUB, 1e-300, -1e-300],  # ... limit, smallest subnormal, overflow
    ])


def test_vexp_accuracy():
    # 1 ulp: measured maximum (normal and subnormal results, compiled and plain Python)
    x = exp_points()
    with np.errstate(over="ignore"):
        assert ulp_error(EXP(x), np.exp(x)) <= 1.0
    assert EXP(0.0) == 1.0


def log_points():
    rng = np.random.default_rng(2)
    k = np.arange(-1074, 1024, dtype=float)
    with np.errstate(over="ignore"):  # the neighbours of the largest double include inf
        x = np.concatenate([
            np.exp(rng.uniform(math.log(TINY_SUB), math.log(1.7e308), 200_000)),  # positives
            rng.uniform(0.0, 2.0, 20_000),
            around(2.0**k, 1), around(math.sqrt(2.0) * 2.0**k[50:-50], 1),  # mantissa split
            around([1.0, 2.2250738585072014e-308, 1.7976931348623157e308]),  # subnormal ends
        ])
    return x[(x > 0.0) & (x < math.inf)]  # log(0), log(inf): test_special_values


def test_vlog_accuracy():
    # 1 ulp: measured maximum (over all positive doubles, subnormals included)
    x = log_points()
    assert ulp_error(LOG(x), np.log(x)) <= 1.0
    assert LOG(1.0) == 0.0


def test_vlog1p_accuracy():
    # 2 ulp: measured maximum; RB08 uses it on t > 0 (1 + t = 1/cos^2 or similar ratios)
    rng = np.random.default_rng(3)
    t = np.concatenate([np.exp(rng.uniform(math.log(1e-300), math.log(1e30), 100_000)),
                        rng.uniform(-0.999, 1.0, 50_000), around([0.0, 1.0, 2.0**-53]),
                        [-1.0 + 2.0**-52, 1e300, TINY_SUB]])
    with np.errstate(divide="ignore"):
        assert ulp_error(LOG1P(t), np.log1p(t)) <= 2.0


# ------------------------------------------------------------------------------------------
# asin, acos
# ------------------------------------------------------------------------------------------
def unit_points():
    rng = np.random.default_rng(4)
    near_one = 1.0 - np.exp(rng.uniform(math.log(1.1e-16), 0.0, 20_000))
    return np.concatenate([
        rng.uniform(-1.0, 1.0, 200_000), near_one, -near_one,
        around([-1.0, -0.5, 0.0, 0.5, 1.0]), [TINY_SUB, -TINY_SUB, 1e-300, -1e-300],
    ])


def test_vacos_accuracy():
    # 1 ulp: measured maximum over [-1, 1] (TS67's gaussian-angle distribution: acos(cos h))
    x = unit_points()
    x = x[np.abs(x) <= 1.0]
    assert ulp_error(ACOS(x), np.arccos(x)) <= 1.0
    assert ACOS(1.0) == 0.0 and ACOS(-1.0) == math.pi and ACOS(0.0) == 0.5 * math.pi


def test_vasin_accuracy():
    # 2 ulp: measured maximum over [-1, 1] (RB08)
    x = unit_points()
    x = x[np.abs(x) <= 1.0]
    assert ulp_error(ASIN(x), np.arcsin(x)) <= 2.0


# ------------------------------------------------------------------------------------------
# atan2
# ------------------------------------------------------------------------------------------
def test_vatan2_accuracy():
    # 1 ulp: measured maximum over all finite (y, x), both signs, magnitudes 1e-320 to 1e308
    rng = np.random.default_rng(5)
    n = 200_000
    sign = rng.choice([-1.0, 1.0], (2, n))
    y = sign[0] * np.exp(rng.uniform(-736.0, 709.0, n))
    x = sign[1] * np.exp(rng.uniform(-736.0, 709.0, n))
    assert ulp_error(ATAN2(y, x), np.arctan2(y, x)) <= 1.0
    # O(1) magnitudes, every octant (the geometry parts' use), and the unit circle
    y, x = rng.standard_normal((2, n))
    assert ulp_error(ATAN2(y, x), np.arctan2(y, x)) <= 1.0
    ang = rng.uniform(-math.pi, math.pi, n)
    assert ulp_error(ATAN2(np.sin(ang), np.cos(ang)), np.arctan2(np.sin(ang), np.cos(ang))) <= 1
    # ends of the reduction intervals: |y/x| = 7/16, 11/16, 1 (and the swap at 1), each octant
    r = around([7.0 / 16.0, 11.0 / 16.0, 1.0, 16.0 / 11.0, 16.0 / 7.0], 3)
    for sy in (1.0, -1.0):
        for sx in (1.0, -1.0):
            assert ulp_error(ATAN2(sy * r, sx * 1.0), np.arctan2(sy * r, sx * 1.0)) <= 1.0
    # the power-of-two scaling thresholds |y|, |x| ~ 2^+-1000, and subnormal arguments
    big = around([2.0**1000, 2.0**-1000, 1.7e308, 2.2250738585072014e-308, TINY_SUB], 2)
    yy, xx = np.meshgrid(np.concatenate([big, -big, [1.0, 0.3]]), np.concatenate([big, -big]))
    assert ulp_error(ATAN2(yy, xx), np.arctan2(yy, xx)) <= 1.0


def test_vatan2_special_values_like_numpy():
    v = np.array([0.0, -0.0, np.inf, -np.inf, np.nan, TINY_SUB, -TINY_SUB, 1e308, -1e308, 1.0,
                  -1.0])
    y, x = np.meshgrid(v, v)
    with np.errstate(invalid="ignore"):  # comparisons on NaN may set the invalid flag
        got = ATAN2(y, x)
    want = np.arctan2(y, x)
    np.testing.assert_array_equal(got, want)  # NaN where NumPy has NaN, +-pi/4 at infinities
    np.testing.assert_array_equal(np.signbit(got), np.signbit(want))  # signs of zeros, +-pi


# ------------------------------------------------------------------------------------------
# erfc
# ------------------------------------------------------------------------------------------
_PI = Decimal("3.14159265358979323846264338327950288419716939937510582097494459230781640629")


def _erfc_decimal(x: float) -> float:
    """erfc(x) from a 60-digit evaluation: the Maclaurin series of erf below 3, the continued
    fraction ``erfc x = e^-x^2/sqrt(pi) / (x + (1/2)/(x + 1/(x + (3/2)/(x + ...))))`` above
    (400 terms: converged to far below 1e-40 relative for x >= 3)."""
    if x < 0.0:
        return float(2 - Decimal(_erfc_decimal(-x)))  # erfc(x) ~ 2 here: one rounding
    with localcontext() as ctx:
        ctx.prec = 60
        d = Decimal(x)  # the exact binary value
        if x < 3.0:
            # terms grow to ~e^9 before they shrink: 60 digits leave > 45 after cancellation
            x2, term, s, n = d * d, d, d, 0
            while True:
                n += 1
                term = -term * x2 / n
                t = term / (2 * n + 1)
                s += t
                if abs(t) < Decimal(10) ** -58:
                    break
            return float(1 - 2 * s / _PI.sqrt())
        f = d
        for k in range(400, 0, -1):
            f = d + (Decimal(k) / 2) / f
        return float((-(d * d)).exp() / _PI.sqrt() / f)


ERFC_ENDS = [0.0, 0.25, 0.84375, 1.25, 1.0 / 0.35, 6.0, 26.5, 27.0]


def test_verfc_accuracy_against_decimal_reference():
    # 2 ulp: measured maximum against the 60-digit reference (2 ulp at one point of [1.25,
    # 2.86), 1 ulp elsewhere), every interval of the approximation, over the range Beckmann's
    # Smith Lambda uses (u = c/(m sin) >= 0) and the negative side; normal results (x < 26.5)
    rng = np.random.default_rng(6)
    x = np.concatenate([rng.uniform(lo, hi, 250) for lo, hi in
                        [(-6.0, 0.0), (0.0, 0.84375), (0.84375, 1.25), (1.25, 1.0 / 0.35),
                         (1.0 / 0.35, 6.0), (6.0, 26.5)]]
                       + [around(ERFC_ENDS[:-1], 1), -around(ERFC_ENDS[1:5], 1),
                          [1e-300, -1e-300, TINY_SUB, 2.0**-28]])
    want = np.array([_erfc_decimal(float(v)) for v in x])
    assert ulp_error(ERFC(x), want) <= 2.0
    # subnormal results (26.55 < x < 27.3) and the underflow to 0: within one spacing of the
    # subnormals (absolute), the precision a subnormal result has (2 ulp where still normal)
    x = np.concatenate([rng.uniform(26.5, 27.4, 200), around([26.55, 27.2, 27.3], 2)])
    want = np.array([_erfc_decimal(float(v)) for v in x])
    tol = np.where(want >= 2.2250738585072014e-308, 2.0 * np.spacing(want), TINY_SUB)
    assert np.all(np.abs(ERFC(x) - want) <= tol)


def test_verfc_against_scipy():
    # SciPy's erfc is the reference the models were written against; its own error is up to
    # 5.7e-14 relative on [0, 26.6] (Cephes ndtr.c documents a 5.7e-14 peak; 5.72e-14 measured
    # here against _erfc_decimal, at x = 26.34), so the tolerance is 6e-14: SciPy's error plus
    # our 2 ulp (4.4e-16), rounded up. Normal results only: SciPy flushes part of the
    # subnormal range (x > 26.55) to 0 (the decimal test covers that range); below -6 both
    # are 2.
    rng = np.random.default_rng(7)
    x = np.concatenate([rng.uniform(-8.0, 26.5, 200_000), np.linspace(0.0, 3.0, 30_001),
                        around(ERFC_ENDS[:-1], 2), -around(ERFC_ENDS, 2)])
    got, want = ERFC(x), special.erfc(x)
    assert np.all(want >= 2.2250738585072014e-308)
    np.testing.assert_allclose(got, want, rtol=6e-14, atol=0)
    assert ERFC(27.3) == special.erfc(27.3) == 0.0


def test_verfc_special_values():
    x = np.array([0.0, -0.0, np.inf, -np.inf, 28.0, 1e300, -1e300, -30.0, 1e-300, TINY_SUB])
    with np.errstate(all="raise", under="ignore"):  # no overflow/invalid/divide flags
        got = ERFC(x)
    np.testing.assert_array_equal(got, [1, 1, 0, 2, 0, 0, 2, 2, 1, 1])
    with np.errstate(invalid="ignore"):  # ordered comparisons on a NaN set the invalid flag
        assert math.isnan(ERFC(np.nan))


# ------------------------------------------------------------------------------------------
# special values and floating-point flags of the others
# ------------------------------------------------------------------------------------------
def test_special_values():
    inf, nan = math.inf, math.nan
    with np.errstate(all="raise", under="ignore", over="ignore"):
        assert list(EXP(np.array([-inf, inf, -1000.0, 1000.0, 0.0]))) == [0, inf, 0, inf, 1]
        assert list(LOG(np.array([0.0, inf, 1.0]))) == [-inf, inf, 0.0]
        assert LOG(TINY_SUB) == np.log(TINY_SUB)
        assert list(LOG1P(np.array([0.0, 1e-300]))) == [0.0, 1e-300]
        with np.errstate(invalid="ignore"):  # vlog1p(inf) computes inf/inf on a discarded lane
            assert LOG1P(inf) == inf
        assert ASIN(1.0) == 0.5 * math.pi and ASIN(-1.0) == -0.5 * math.pi
        # in-domain arguments leave no invalid/divide flag (NumPy would warn in a ufunc)
        ACOS(np.array([-1.0, -0.5, 0.0, 0.5, 1.0, TINY_SUB]))
        ATAN2(np.array([0.0, 1.0, inf, -inf]), np.array([0.0, inf, inf, 1.0]))
    with np.errstate(invalid="ignore"):  # out of the domain: NaN, as NumPy
        for fn, x in [(EXP, nan), (LOG, -1.0), (LOG, nan), (LOG1P, -2.0), (ASIN, 1.5),
                      (ACOS, 1.5), (ACOS, -inf), (ACOS, nan)]:
            assert math.isnan(fn(x)), (fn, x)


# ------------------------------------------------------------------------------------------
# the plain-Python path (NUMBA_DISABLE_JIT=1) gives the same numbers
# ------------------------------------------------------------------------------------------
def _sample_points():
    rng = np.random.default_rng(8)
    edge = [0.0, -0.0, math.inf, -math.inf, math.nan, TINY_SUB, 1e-300, 1.0, -1.0, 0.5, -0.5]
    return {
        "vexp": np.concatenate([rng.uniform(-745.2, 709.78, 400), edge, [-745.1, 709.7]]),
        "vlog": np.concatenate([np.exp(rng.uniform(-744.0, 709.0, 400)), edge]),
        "vlog1p": np.concatenate([np.exp(rng.uniform(-690.0, 69.0, 400)), edge, [-0.3]]),
        "vasin": np.concatenate([rng.uniform(-1.0, 1.0, 400), edge]),
        "vacos": np.concatenate([rng.uniform(-1.0, 1.0, 400), edge]),
        "verfc": np.concatenate([rng.uniform(-7.0, 28.0, 400), edge, ERFC_ENDS, [28.0]]),
        "sincos": np.concatenate([rng.uniform(-8e5, 8e5, 200), rng.uniform(-7, 7, 200), edge]),
        "vatan2": np.concatenate([rng.standard_normal((2, 400)),
                                  np.array(np.meshgrid(edge, edge)).reshape(2, -1)], axis=1),
    }


_PURE_PYTHON = textwrap.dedent("""
    import json, sys, numba
    assert numba.config.DISABLE_JIT
    from roughbrdf._kernels import vmath as V
    pts = json.loads(sys.stdin.read())
    out = {}
    for name, xs in pts.items():
        fn = getattr(V, name)
        if name == "vatan2":
            out[name] = [float(fn(y, x)) for y, x in zip(*xs)]
        elif name == "sincos":
            out[name] = [[float(v) for v in fn(x)] for x in xs]
        else:
            out[name] = [float(fn(x)) for x in xs]
    print(json.dumps(out))
""")


def test_pure_python_path_agrees():
    pts = _sample_points()
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    res = subprocess.run([sys.executable, "-c", _PURE_PYTHON], env=env, capture_output=True,
                         text=True, timeout=600, check=True,
                         input=json.dumps({k: v.tolist() for k, v in pts.items()}))
    pure = {k: np.array(v, dtype=float) for k, v in
            json.loads(res.stdout.strip().splitlines()[-1]).items()}
    compiled = {}
    with np.errstate(all="ignore"):
        for name in ("vexp", "vlog", "vlog1p", "vasin", "vacos", "verfc"):
            compiled[name] = _ufunc1(getattr(V, name))(pts[name])
        compiled["vatan2"] = ATAN2(*pts["vatan2"])
        compiled["sincos"] = np.array([V.sincos(float(x)) for x in pts["sincos"]])
    for name, got in pure.items():
        want = compiled[name]
        # special values identical (NaN, inf, 0 and the sign of zeros) ...
        np.testing.assert_array_equal(np.isnan(got), np.isnan(want), err_msg=name)
        fin = np.isfinite(want)
        np.testing.assert_array_equal(got[~fin], want[~fin], err_msg=name)
        np.testing.assert_array_equal(np.signbit(got[fin & (want == 0)]),
                                      np.signbit(want[fin & (want == 0)]), err_msg=name)
        # ... and finite values within 2 ulp: the compiled code lets LLVM fuse a*b + c into
        # one FMA ("contract"), which rounds once where plain Python rounds twice (measured:
        # 2 ulp at most, in verfc; most values are identical)
        f = fin & (want != 0)
        diff = np.abs(got[f] - want[f]) / np.spacing(np.abs(want[f]))
        assert diff.max() <= 2.0, (name, diff.max())
    # and the plain-Python values meet the accuracy bounds themselves
    with np.errstate(all="ignore"):
        assert ulp_error(pure["vexp"], np.exp(pts["vexp"])) <= 1.0
        assert ulp_error(pure["vacos"], np.arccos(pts["vacos"])) <= 1.0
        assert ulp_error(pure["vatan2"], np.arctan2(*pts["vatan2"])) <= 1.0


# ------------------------------------------------------------------------------------------
# the model loops that use them contain no libm call and are vectorized
# ------------------------------------------------------------------------------------------
_LIBM = ("exp", "log", "log1p", "expm1", "pow", "sin", "cos", "tan", "asin", "acos", "atan",
         "atan2", "erf", "erfc", "sinh", "cosh", "tanh", "lgamma", "tgamma")


@pytest.mark.slow
@pytest.mark.skipif(DISABLE_JIT, reason="inspects compiled code")
@pytest.mark.parametrize("model, kwargs", [
    ("trowbridge-reitz-1975", {}),
    ("torrance-sparrow-1967", {}),
    ("microfacet", {}),  # the driver holds the GGX, Beckmann and generic loops
    ("lambertian", {}),
])
def test_model_driver_loop_has_no_libm_calls(model, kwargs):
    # A serial copy of the model's driver (prange is range without parallel=True), compiled
    # with the drivers' options, inspected for calls to libm and for vector instructions.
    import numba

    import roughbrdf as rb

    m = rb.model(model, **kwargs)
    drive = type(m)._drive
    serial = numba.njit(error_model="numpy", fastmath={"contract"})(drive.py_func)
    n = 64
    x = np.linspace(0.0, 1.4, n)
    serial(x, x, x, math.nan, tuple(float(v) for v in m._pack()), 0, np.empty(n))
    ir = serial.inspect_llvm(serial.signatures[0])
    called = set(re.findall(r"call [^@\n]*@\"?([A-Za-z_][\w.]*)", ir))
    libm = {c for c in called if c in _LIBM or re.fullmatch(
        r"llvm\.(" + "|".join(_LIBM) + r")\.\w+", c)}
    assert not libm, f"{model}: the driver loop calls {sorted(libm)}"
    assert re.search(r"<\d+ x double>", ir), f"{model}: the driver loop is not vectorized"
