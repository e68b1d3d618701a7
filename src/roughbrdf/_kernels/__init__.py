"""The kernel layer: compile decorators, cache locator, broadcasting and vector math.

Every compiled part of roughbrdf is built with these decorators, and every model's kernel runs
through :func:`evaluate`. Submodules: :mod:`.compile` (``jit``, ``ufunc``, ``driver``, ``at``),
:mod:`.cache` (the on-disk cache key that follows the parts), :mod:`.broadcast` (NumPy inputs to
a model's driver), :mod:`.vmath` (``sincos`` and the other vectorizable elementary functions).
"""

from .broadcast import (
                        as_float_array,
                        broadcast_array,
                        broadcast_dense,
                        broadcast_strided,
                        evaluate,
                        run_driver,
)
from .cache import locator_installed
from .compile import DISABLE_JIT, at, driver, jit, tuple_slice, ufunc
from .vmath import SINCOS_MAX_ARG, TINY, sincos

__all__ = ["DISABLE_JIT", "SINCOS_MAX_ARG", "TINY", "as_float_array", "at", "broadcast_array",
           "broadcast_dense", "broadcast_strided", "driver", "evaluate", "jit",
           "locator_installed", "run_driver", "sincos", "tuple_slice", "ufunc"]
