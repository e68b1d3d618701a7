"""Broadcasting NumPy inputs onto a model's compiled scalar kernel.

:func:`evaluate` broadcasts the geometry and polarization arrays (NumPy rules), hands the
model's :func:`~roughbrdf._kernels.compile.driver` scalars as floats and arrays as contiguous
1-D arrays, and reshapes the result. A kernel may return several numbers per sample
(``out_shape``): the result then has the broadcast shape followed by ``out_shape``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numba
import numpy as np

from ..interrupts import held_interrupts
from .compile import DISABLE_JIT

__all__ = ["as_float_array", "broadcast_array", "broadcast_dense", "broadcast_strided", "evaluate",
           "run_driver", "SERIAL_BELOW"]


def as_float_array(x: Any, name: str) -> np.ndarray:
    """Convert ``x`` to a float64 array, raising ``ValueError`` that names ``name`` if it cannot."""
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric, got {x!r}") from exc
    return arr


def broadcast_dense(arr: np.ndarray, shape: tuple[int, ...]) -> np.ndarray | float:
    """A float if ``arr`` has one element, else a contiguous 1-D array of the broadcast shape."""
    if arr.size == 1:
        return float(arr.reshape(-1)[0])
    if arr.shape == shape and arr.flags.c_contiguous:
        return arr.reshape(-1)
    return np.ascontiguousarray(np.broadcast_to(arr, shape)).reshape(-1)


def broadcast_array(arr: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """A contiguous 1-D array of ``arr`` broadcast to ``shape`` (a view when it already is one)."""
    if arr.shape == shape and arr.flags.c_contiguous:
        return arr.reshape(-1)
    return np.ascontiguousarray(np.broadcast_to(arr, shape)).reshape(-1)


def broadcast_strided(arr: np.ndarray, shape: tuple[int, ...]) -> tuple[np.ndarray, int]:
    """A contiguous 1-D array for ``arr`` broadcast to ``shape`` and its stride: ``(arr, 0)`` for
    a single value (read as ``arr[i * 0]``, never copied), ``(flat array, 1)`` otherwise."""
    if arr.size == 1:
        return np.ascontiguousarray(arr.reshape(1)), 0
    if arr.shape == shape and arr.flags.c_contiguous:
        return arr.reshape(-1), 1
    return np.ascontiguousarray(np.broadcast_to(arr, shape)).reshape(-1), 1


#: (driver, which arguments are floats) of the calls that have loaded their compiled variant
_LOADED: set[tuple[Any, tuple[bool, ...]]] = set()


#: below this many samples a driver runs on one thread: starting the parallel region costs
#: about 50 us a call (measured: TR75 on 1,000 samples 73 us on two threads, 28 us on one; on
#: 3,000 samples 83 us and 38 us), more than the work of a few thousand samples; a fit's
#: searches evaluate 1,000-sample subsamples thousands of times
SERIAL_BELOW = 2048


def _call(drive: Callable, args: tuple) -> None:
    """``drive(*args)``, on one thread when the output (the last argument) is small."""
    out = args[-1]
    if DISABLE_JIT or out.shape[0] >= SERIAL_BELOW:
        drive(*args)
        return
    threads = numba.get_num_threads()
    numba.set_num_threads(1)  # this thread's setting only (~1 us); restored below
    try:
        drive(*args)
    finally:
        numba.set_num_threads(threads)


def run_driver(drive: Callable, *args: Any) -> None:
    """Call a compiled driver; the first call of each variant (the float/array layout of its
    arguments) runs with Ctrl-C held, since loading or compiling it would swallow the interrupt
    (:mod:`roughbrdf.interrupts`). Later calls skip the hold (it costs ~7 us a call). Fewer
    than :data:`SERIAL_BELOW` samples run on one thread."""
    key = (drive, tuple(type(a) is float for a in args))
    if key in _LOADED:
        _call(drive, args)
        return
    with held_interrupts():
        _call(drive, args)
    _LOADED.add(key)


def evaluate(
    drive: Callable,
    theta_i: np.ndarray,
    theta_r: np.ndarray,
    phi: np.ndarray,
    gamma: np.ndarray,
    params: tuple,
    flag: int = 0,
    out_shape: tuple[int, ...] = (),
) -> np.ndarray | float:
    """Run a model's driver ``drive(a, b, c, g, params, flag, out)`` over broadcast arrays.

    The four geometry/polarization inputs are broadcast against each other (NumPy rules). The
    driver fills ``out`` of shape ``(size, *out_shape)``; the result has the broadcast shape
    followed by ``out_shape``, or is a Python float if every input was a scalar and
    ``out_shape`` is ``()``. ``|phi|`` must not exceed
    :data:`~roughbrdf._kernels.vmath.SINCOS_MAX_ARG` (the model front ends reduce it).
    """
    shape = np.broadcast_shapes(theta_i.shape, theta_r.shape, phi.shape, gamma.shape)
    n = math.prod(shape)
    out = np.empty((n, *out_shape), dtype=np.float64)
    if n:
        p = tuple(float(v) for v in params)
        # the angles always as arrays, gamma as a float when it is one value: two compiled
        # variants per driver (a float angle would add up to eight more, some of which take
        # LLVM minutes to optimize, and buys nothing where it matters: large arrays)
        args = (broadcast_array(theta_i, shape), broadcast_array(theta_r, shape),
                broadcast_array(phi, shape), broadcast_dense(gamma, shape), p, int(flag),
                out if out_shape else out.reshape(n))
        run_driver(drive, *args)
    if not shape and not out_shape:
        return float(out[0])
    return out.reshape(*shape, *out_shape)
