"""Numba plumbing shared by every physics part.

Every physics part of roughbrdf is a small *scalar* function compiled with Numba (:func:`jit`).
Models compose those parts into one scalar ``point`` function per model, and :func:`evaluate`
runs it over NumPy inputs of any broadcastable shape in a parallel ``prange`` loop. Small public
helpers (a Fresnel curve, a distribution, a shadowing factor) become NumPy ufuncs with
:func:`ufunc`.

With ``NUMBA_DISABLE_JIT=1`` everything still runs as plain Python (slowly): :func:`ufunc` falls
back to :class:`numpy.vectorize` and the driver to a plain ``range`` loop.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numba
import numpy as np
from numba import njit, prange

DISABLE_JIT: bool = bool(numba.config.DISABLE_JIT)

__all__ = ["DISABLE_JIT", "jit", "ufunc", "evaluate", "as_float_array"]


def jit(fn: Callable) -> Callable:
    """Compile a scalar physics part with Numba (``cache=True``, IEEE error model).

    ``error_model="numpy"`` makes a float division by zero give ``inf``/``nan`` as in NumPy
    instead of raising; the parts still guard every such division explicitly, because the
    pure-Python fallback (``NUMBA_DISABLE_JIT=1``) would raise ``ZeroDivisionError``.
    """
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
) -> np.ndarray | float:
    """Run a model's scalar ``point(theta_i, theta_r, phi, gamma, params, flag)`` over arrays.

    The four geometry/polarization inputs are broadcast against each other (NumPy rules); the
    result has the broadcast shape, or is a Python float if every input was a scalar.
    """
    shape = np.broadcast_shapes(theta_i.shape, theta_r.shape, phi.shape, gamma.shape)
    a, sa = _flat(theta_i, shape)
    b, sb = _flat(theta_r, shape)
    c, sc = _flat(phi, shape)
    g, sg = _flat(gamma, shape)
    n = int(np.prod(shape)) if shape else 1
    out = np.empty(n, dtype=np.float64)
    if n:
        # With NUMBA_DISABLE_JIT=1, _drive is plain Python and prange is range.
        _drive(point, a, sa, b, sb, c, sc, g, sg, tuple(float(v) for v in params), flag, out)
    if not shape:
        return float(out[0])
    return out.reshape(shape)
