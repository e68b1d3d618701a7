"""Compile decorators: scalar parts, lazily built ufuncs, and the models' parallel drivers.

Every physics part of roughbrdf is a small *scalar* function compiled with Numba (:func:`jit`).
Models compose those parts into one scalar ``point`` function per model; a model's
:func:`driver` is a module-level ``prange`` loop over it, and
:func:`roughbrdf._kernels.broadcast.evaluate` feeds it NumPy inputs of any broadcastable shape.
Small public helpers (a Fresnel curve, a distribution, a shadowing factor) become NumPy ufuncs
with :func:`ufunc`; they are compiled (or loaded from the disk cache) on their first call, not
at import, so that importing a module costs no compilation.

Fast path (measured, see ``docs/benchmarks.md``)
-----------------------------------------------
A model module defines its own driver, a module-level loop that names its ``point`` function::

    @driver
    def _tr75_drive(a, b, c, g, p, flag, out):
        for i in prange(out.size):
            out[i] = _tr75_point(at(a, i), at(b, i), at(c, i), at(g, i), p, flag)

Inputs that are scalars are passed as floats and the others as contiguous 1-D arrays
(:func:`at` is ``x[i]`` or ``x``, resolved at compile time), so every access is unit-stride and
LLVM can vectorize the loop; the driver is compiled once per scalar/array combination and cached
on disk (``cache=True``). Vectorization also needs loop bodies without libm calls: see
:mod:`roughbrdf._kernels.vmath`.

With ``NUMBA_DISABLE_JIT=1`` everything still runs as plain Python (slowly): :func:`ufunc` falls
back to :class:`numpy.vectorize`, the drivers to plain ``range`` loops and :func:`at` to
indexing.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import numba
import numpy as np
from numba import njit, types
from numba.extending import overload

from ..interrupts import held_interrupts
from .cache import install_cache_locators

__all__ = ["DISABLE_JIT", "LazyUfunc", "jit", "ufunc", "driver", "at", "tuple_slice"]

DISABLE_JIT: bool = bool(numba.config.DISABLE_JIT)  # type: ignore[attr-defined]

install_cache_locators()


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



class LazyUfunc:
    """A NumPy ufunc built from a scalar function on its first call (compiled or loaded from the
    disk cache then), so that importing the module that defines it compiles nothing."""

    def __init__(self, fn: Callable, nargs: int) -> None:
        self._fn, self._nargs = fn, nargs
        self._ufunc: Any = None
        functools.update_wrapper(self, fn)

    def _build(self) -> Any:
        if self._ufunc is None:
            sig = "f8(" + ",".join(["f8"] * self._nargs) + ")"
            with held_interrupts():  # Ctrl-C while it loads would be lost (interrupts.py)
                self._ufunc = numba.vectorize([sig], cache=True)(self._fn)
        return self._ufunc

    @property
    def built(self) -> bool:
        """Whether the ufunc has been compiled (or loaded from the cache) yet."""
        return self._ufunc is not None

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return self._build()(*args, **kwargs)

    def __getattr__(self, name: str) -> Any:  # ufunc methods and attributes (reduce, nin, ...)
        if name.startswith("_"):
            raise AttributeError(name)
        return getattr(self._build(), name)


def ufunc(nargs: int) -> Callable[[Callable], Callable]:
    """Turn a scalar float function of ``nargs`` float arguments into a NumPy ufunc (built on
    first call; :class:`numpy.vectorize` under ``NUMBA_DISABLE_JIT=1``)."""

    def wrap(fn: Callable) -> Callable:
        if DISABLE_JIT:
            vec = np.vectorize(fn, otypes=[np.float64])

            def call(*args: Any) -> Any:
                out = vec(*args)
                return out[()] if isinstance(out, np.ndarray) and out.ndim == 0 else out

            call.__doc__ = fn.__doc__
            call.__name__ = fn.__name__
            return call
        return LazyUfunc(fn, nargs)

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



@njit(cache=True)
def tuple_slice(p, start, stop):  # pragma: no cover - compiled
    """``np.array(p[start:stop])`` of a tuple of floats, for a driver's table look-ups.

    A driver receives its packed parameters as a tuple; indexing a tuple with an index known
    only at run time (a table look-up) compiles to a copy of the tuple per access, ten times
    slower than an array (measured on the coated model's factor table). Copy the table once
    per call.
    """
    out = np.empty(stop - start)
    for j in range(stop - start):
        out[j] = p[start + j]
    return out
