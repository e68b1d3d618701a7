"""Named model parameters: value, search bounds, unit, description and physical domain."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

__all__ = ["Parameter", "positive", "nonnegative", "unit_interval"]


@dataclass(frozen=True)
class Parameter:
    """A named model parameter.

    Attributes
    ----------
    name : str
    value : float or None
        ``None`` switches an optional part off (e.g. TS67 ``n=None`` gives F = 1).
    bounds : (float, float)
        Default search range for fits (finite, inside the physical domain).
    unit : str
    description : str
    domain : (float, bool, float, bool)
        Physical domain ``(low, low_inclusive, high, high_inclusive)``; values outside raise.
    optional : bool
        Whether ``None`` is accepted.
    """

    name: str
    value: float | None
    bounds: tuple[float, float]
    unit: str = ""
    description: str = ""
    domain: tuple[float, bool, float, bool] = (-math.inf, False, math.inf, False)
    optional: bool = False

    def check(self, value: Any) -> float | None:
        """Validate ``value`` against the domain; return it as float (or None)."""
        if value is None:
            if self.optional:
                return None
            raise ValueError(f"parameter {self.name!r} cannot be None")
        try:
            v = float(value)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"parameter {self.name!r} must be a number, got {value!r}") from exc
        lo, lo_inc, hi, hi_inc = self.domain
        ok = (math.isfinite(v) and (v >= lo if lo_inc else v > lo)
              and (v <= hi if hi_inc else v < hi))
        if not ok:
            lo_s = ("[" if lo_inc else "(") + f"{lo:g}"
            hi_s = f"{hi:g}" + ("]" if hi_inc else ")")
            raise ValueError(
                f"parameter {self.name!r} = {value!r} is outside its physical domain "
                f"{lo_s}, {hi_s}" + (f" ({self.description})" if self.description else "")
            )
        return v


def positive(name: str, default: float, bounds: tuple[float, float], unit: str, desc: str,
             **kw: Any) -> Parameter:
    """A parameter that must be > 0."""
    return Parameter(name, default, bounds, unit, desc, (0.0, False, math.inf, False), **kw)


def nonnegative(name: str, default: float, bounds: tuple[float, float], unit: str, desc: str,
                **kw: Any) -> Parameter:
    """A parameter that must be >= 0."""
    return Parameter(name, default, bounds, unit, desc, (0.0, True, math.inf, False), **kw)


def unit_interval(name: str, default: float, desc: str) -> Parameter:
    """A reflectance-like parameter in [0, 1]."""
    return Parameter(name, default, (0.0, 1.0), "1", desc, (0.0, True, 1.0, True))
