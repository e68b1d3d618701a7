"""Vector math: elementary functions written so that LLVM vectorizes the loops that call them.

Numba's LLVM has no vector math library here (no SVML), so a loop that calls ``math.sin``,
``math.exp`` and the like stays a loop of scalar libm calls. The functions here are written
without libm calls and with selects instead of branches; a model loop built from them
vectorizes. Each states its accuracy and is tested against NumPy/SciPy over the range it is
used on (``tests/test_vmath.py``).
"""

from __future__ import annotations

import math

import numpy as np

from .compile import jit

__all__ = ["TINY", "SINCOS_MAX_ARG", "sincos"]

# --------------------------------------------------------------------------------------------
# sin and cos that LLVM can vectorize
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

