"""Helpers shared by the CLI verbs: parsing ``-p name=value`` and degree ranges.

Like every module of :mod:`roughbrdf.cli`, this one imports nothing heavy at module level (NumPy,
the models, SciPy, Matplotlib are imported inside the functions that use them), so that
``roughbrdf --help`` and the argument checks stay fast; ``tests/test_startup.py`` checks it.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import typer

if TYPE_CHECKING:
    import numpy as np


def parse_params(items: list[str] | None) -> dict[str, float | None | str]:
    """``["e=0.5", "n=None", "distribution=ggx"]`` -> dict (numbers where they parse)."""
    out: dict[str, float | None | str] = {}
    for item in items or []:
        if "=" not in item:
            raise typer.BadParameter(f"expected name=value, got {item!r}")
        key, val = item.split("=", 1)
        key, val = key.strip(), val.strip()
        if val.lower() == "none":
            out[key] = None
            continue
        try:
            out[key] = float(val)
        except ValueError:
            out[key] = val
    return out


def degree_range(text: str, name: str) -> np.ndarray:
    """``"30"`` or ``"0:90:5"`` (start:stop:step, stop inclusive) in degrees -> radians."""
    import numpy as np

    try:
        parts = [float(x) for x in text.split(":")]
    except ValueError as exc:
        raise typer.BadParameter(f"{name}: expected DEG or START:STOP:STEP, got {text!r}") from exc
    if len(parts) == 1:
        return np.radians(np.array(parts))
    if len(parts) != 3 or parts[2] == 0:
        raise typer.BadParameter(f"{name}: expected START:STOP:STEP with STEP != 0, got {text!r}")
    start, stop, step = parts
    n = int(math.floor((stop - start) / step + 1e-9)) + 1
    if n <= 0:
        raise typer.BadParameter(f"{name}: empty range {text!r}")
    return np.radians(start + step * np.arange(n))
