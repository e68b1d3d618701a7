"""Numba plumbing shared by every physics part.

Every physics part of roughbrdf is a small *scalar* function compiled with Numba (:func:`jit`).
Models compose those parts into one scalar ``point`` function per model, and :func:`evaluate`
runs it over NumPy inputs of any broadcastable shape in a parallel ``prange`` loop. Small public
helpers (a Fresnel curve, a distribution, a shadowing factor) become NumPy ufuncs with
:func:`ufunc`.

Fast path (measured, see ``docs/benchmarks.md``)
-----------------------------------------------
A model module may define its own driver with :func:`driver`, a module-level loop that names
its ``point`` function directly::

    @driver
    def _tr75_drive(a, b, c, g, p, flag, out):
        for i in prange(out.size):
            out[i] = _tr75_point(at(a, i), at(b, i), at(c, i), at(g, i), p, flag)

Inputs that are scalars are passed as floats and the others as contiguous 1-D arrays
(:func:`at` is ``x[i]`` or ``x``, resolved at compile time), so every access is unit-stride and
LLVM can vectorize the loop; the driver is compiled once per scalar/array combination and cached
on disk (``cache=True``). Models without a driver use the generic ``_drive``, which receives the
``point`` function as an argument: correct, but not cacheable (it is compiled in every process)
and not vectorized.

Vectorization also needs loop bodies without calls to libm: Numba's LLVM has no vector math
library here (no SVML), so ``math.sin``/``math.cos`` stay scalar calls and block it. That is why
:func:`sincos` exists (hand-written, from fdlibm's kernels): a branch-free sine and cosine that
LLVM vectorizes. With it, the geometry of every model costs a few ns instead of ~60 ns.

With ``NUMBA_DISABLE_JIT=1`` everything still runs as plain Python (slowly): :func:`ufunc` falls
back to :class:`numpy.vectorize`, the drivers to plain ``range`` loops and :func:`at` to
indexing.
"""

from __future__ import annotations

import functools
import hashlib
import math
import os
from collections.abc import Callable
from typing import Any

import numba
import numpy as np
from numba import njit, prange, types
from numba.extending import overload

DISABLE_JIT: bool = bool(numba.config.DISABLE_JIT)

__all__ = ["DISABLE_JIT", "jit", "ufunc", "driver", "at", "sincos", "evaluate", "as_float_array",
           "SINCOS_MAX_ARG", "TINY"]


# --------------------------------------------------------------------------------------------
# on-disk cache that notices edits of the parts
# --------------------------------------------------------------------------------------------
# Numba keys a cached function on its *own* source file only, so a model kernel cached before
# an edit of geometry.py or fresnel.py would keep running the old parts (they are compiled into
# it). For files of this package, the key below also covers every module outside ``models/``
# that defines compiled parts; a model module's cache then follows the parts it uses. Uses
# Numba's cache-locator extension point; if that ever changes, Numba's default applies.
_PKG_DIR = os.path.dirname(os.path.abspath(__file__))
_PART_MARKERS = ("@jit", "@ufunc", "@driver", "@njit", "@vectorize")


@functools.lru_cache(maxsize=1)
def _part_files() -> tuple[str, ...]:
    files = []
    for root, dirs, names in os.walk(_PKG_DIR):
        dirs[:] = [d for d in dirs if d not in ("models", "__pycache__")]
        for nm in sorted(names):
            if nm.endswith(".py"):
                path = os.path.join(root, nm)
                with open(path, encoding="utf-8") as fh:
                    if any(m in fh.read() for m in _PART_MARKERS):
                        files.append(path)
    return tuple(sorted(files))


@functools.lru_cache(maxsize=8)
def _hash_files(stats: tuple) -> str:
    h = hashlib.sha256()
    for path, *_ in stats:
        with open(path, "rb") as fh:
            h.update(path.encode() + b"\0" + fh.read())
    return h.hexdigest()


def _parts_stamp() -> str:
    stats = []
    for path in _part_files():
        st = os.stat(path)
        stats.append((path, st.st_mtime_ns, st.st_size))
    return _hash_files(tuple(stats))


def _install_cache_locators() -> None:
    try:
        from numba.core import caching

        bases = [caching.UserProvidedCacheLocator, caching.InTreeCacheLocator,
                 caching.UserWideCacheLocator]
        registry = caching.CacheImpl._locator_classes
    except (ImportError, AttributeError):  # pragma: no cover - other Numba versions
        return

    def make(base: type) -> type:
        class Locator(base):  # type: ignore[misc, valid-type]
            def get_source_stamp(self):
                return (super().get_source_stamp(), _parts_stamp())

            @classmethod
            def from_function(cls, py_func, py_file):
                if not os.path.abspath(py_file).startswith(_PKG_DIR + os.sep):
                    return None
                return super().from_function(py_func, py_file)

        Locator.__name__ = Locator.__qualname__ = "Roughbrdf" + base.__name__
        return Locator

    if not any(getattr(c, "__name__", "").startswith("Roughbrdf") for c in registry):
        registry[0:0] = [make(b) for b in bases]


_install_cache_locators()


#: The only fast-math flag used (hot-path parts and drivers): "contract" lets LLVM fuse a*b + c
#: into one FMA, which rounds once instead of twice (measured: 17 % less CPU time for TR75).
#: No "nnan"/"ninf"/"reassoc": the kernels rely on NaN tests (unpolarized = NaN), on inf as a
#: returned limit, and on the order of operations in the cancellation-free formulas.
_FASTMATH = {"contract"}


def jit(fn: Callable | None = None, *, inline: bool = False, contract: bool = True) -> Callable:
    """Compile a scalar physics part with Numba (``cache=True``, IEEE error model).

    ``error_model="numpy"`` makes a float division by zero give ``inf``/``nan`` as in NumPy
    instead of raising; the parts still guard every such division explicitly, because the
    pure-Python fallback (``NUMBA_DISABLE_JIT=1``) would raise ``ZeroDivisionError``.

    ``@jit(inline=True)`` inlines the part into its callers at Numba's IR level. Only the small
    parts on the hot path of a model with a :func:`driver` use it: LLVM does not inline them by
    itself (they are compiled as separate libraries and exceed its inlining threshold), and a
    loop that still calls a function is not vectorized. It costs compile time in every caller,
    so the other parts do not use it. Inlined parts also get FMA contraction (``_FASTMATH``)
    unless ``contract=False``: :func:`roughbrdf.fresnel.fresnel_sp` keeps plain rounding,
    because the RB08 kernel's tests compare its ``1 - R`` near grazing, where ``R`` is 1 to
    the last bit, with a NumPy reference.
    """
    if fn is None:
        return lambda f: jit(f, inline=inline, contract=contract)
    if inline:
        fm = _FASTMATH if contract else False
        return njit(cache=True, error_model="numpy", forceinline=True, fastmath=fm)(fn)
    return njit(cache=True, error_model="numpy")(fn)


def ufunc(nargs: int) -> Callable[[Callable], Callable]:
    """Turn a scalar float function of ``nargs`` float arguments into a NumPy ufunc."""

    def wrap(fn: Callable) -> Callable:
        if DISABLE_JIT:
            vec = np.vectorize(fn, otypes=[np.float64])

            def call(*args: Any) -> Any:
                out = vec(*args)
                return out[()] if isinstance(out, np.ndarray) and out.ndim == 0 else out

            call.__doc__ = fn.__doc__
            call.__name__ = fn.__name__
            return call
        sig = "f8(" + ",".join(["f8"] * nargs) + ")"
        return numba.vectorize([sig], cache=True)(fn)

    return wrap


def driver(fn: Callable) -> Callable:
    """Compile a model's module-level driver loop (parallel, cached, IEEE error model).

    See the module docstring for the pattern; :func:`evaluate` calls it as
    ``drive(a, b, c, g, params, flag, out)`` with ``a, b, c, g`` floats or contiguous 1-D arrays.
    """
    return njit(parallel=True, cache=True, error_model="numpy", fastmath=_FASTMATH)(fn)


def at(x: Any, i: int) -> Any:
    """``x[i]`` for an array, ``x`` for a scalar (resolved at compile time inside drivers)."""
    return x[i] if isinstance(x, np.ndarray) else x


@overload(at, inline="always")
def _at_overload(x, i):  # pragma: no cover - compiled
    if isinstance(x, types.Array):
        return lambda x, i: x[i]
    return lambda x, i: x


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


@njit(parallel=True, error_model="numpy")
def _drive(point, a, sa, b, sb, c, sc, g, sg, p, flag, out):  # pragma: no cover - compiled
    # One generic parallel loop for every model: the model's scalar ``point`` function is passed
    # in as a first-class function. Inputs of size 1 are broadcast with a zero stride (sa = 0)
    # instead of being copied.
    for i in prange(out.size):
        out[i] = point(a[i * sa], b[i * sb], c[i * sc], g[i * sg], p, flag)


def as_float_array(x: Any, name: str) -> np.ndarray:
    """Convert ``x`` to a float64 array, raising ``ValueError`` that names ``name`` if it cannot."""
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric, got {x!r}") from exc
    return arr


def _dense(arr: np.ndarray, shape: tuple[int, ...]) -> np.ndarray | float:
    """A float if ``arr`` has one element, else a contiguous 1-D array of the broadcast shape."""
    if arr.size == 1:
        return float(arr.reshape(-1)[0])
    if arr.shape == shape and arr.flags.c_contiguous:
        return arr.reshape(-1)
    return np.ascontiguousarray(np.broadcast_to(arr, shape)).reshape(-1)


def _flat(arr: np.ndarray, shape: tuple[int, ...]) -> tuple[np.ndarray, int]:
    """Return a 1-D contiguous view/copy of ``arr`` broadcast to ``shape`` and its stride (0/1)."""
    if arr.size == 1:
        return np.ascontiguousarray(arr.reshape(1)), 0
    if arr.shape == shape and arr.flags.c_contiguous:
        return arr.reshape(-1), 1
    return np.ascontiguousarray(np.broadcast_to(arr, shape)).reshape(-1), 1


def evaluate(
    point: Callable,
    theta_i: np.ndarray,
    theta_r: np.ndarray,
    phi: np.ndarray,
    gamma: np.ndarray,
    params: tuple,
    flag: int = 0,
    drive: Callable | None = None,
) -> np.ndarray | float:
    """Run a model's scalar ``point(theta_i, theta_r, phi, gamma, params, flag)`` over arrays.

    The four geometry/polarization inputs are broadcast against each other (NumPy rules); the
    result has the broadcast shape, or is a Python float if every input was a scalar. ``drive``
    is the model's own :func:`driver` (fast path); without it the generic loop is used.
    ``|phi|`` must not exceed ``SINCOS_MAX_ARG`` (the model front ends reduce it).
    """
    shape = np.broadcast_shapes(theta_i.shape, theta_r.shape, phi.shape, gamma.shape)
    n = math.prod(shape)
    if drive is not None:
        out = np.empty(n, dtype=np.float64)
        if n:
            p = tuple(float(v) for v in params)
            drive(_dense(theta_i, shape), _dense(theta_r, shape), _dense(phi, shape),
                  _dense(gamma, shape), p, int(flag), out)
        return float(out[0]) if not shape else out.reshape(shape)
    a, sa = _flat(theta_i, shape)
    b, sb = _flat(theta_r, shape)
    c, sc = _flat(phi, shape)
    g, sg = _flat(gamma, shape)
    out = np.empty(n, dtype=np.float64)
    if n:
        # With NUMBA_DISABLE_JIT=1, _drive is plain Python and prange is range.
        _drive(point, a, sa, b, sb, c, sc, g, sg, tuple(float(v) for v in params), flag, out)
    if not shape:
        return float(out[0])
    return out.reshape(shape)
