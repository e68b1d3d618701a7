"""JSON-safe values: what ``fit.json``, ``compare.json``, the catalogue files and the catalogue's
task records write.

:func:`clean_json` makes a copy that :func:`json.dumps` writes with ``allow_nan=False``:
NaN and infinities become ``null``, NumPy scalars and arrays become Python numbers and lists,
tuples become lists and mapping keys become strings. Importing this module loads no NumPy
(NumPy values are recognized without importing it: a value can only be a NumPy one if NumPy is
loaded already).
"""

from __future__ import annotations

import math
import sys
from typing import Any

__all__ = ["clean_json"]


def clean_json(v: Any) -> Any:
    """JSON-safe copy: NaN/inf -> None, numpy scalars and arrays -> Python.

    Examples
    --------
    >>> import numpy as np
    >>> clean_json({"a": np.float64("nan"), "b": (np.int64(2), 0.5)})
    {'a': None, 'b': [2, 0.5]}
    """
    if isinstance(v, dict):
        return {str(k): clean_json(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [clean_json(x) for x in v]
    np = sys.modules.get("numpy")
    if np is not None:  # NumPy values exist only once NumPy is loaded
        if isinstance(v, np.ndarray):
            return clean_json(v.tolist())
        if isinstance(v, np.integer):
            return int(v)
        if isinstance(v, np.floating):
            v = float(v)
    if isinstance(v, float):
        v = float(v)  # a subclass of float (np.float64 is one) as a plain float
        return v if math.isfinite(v) else None
    return v
