"""The settings of a fit's global search (:class:`SearchOptions`): how many starts, how many
Sobol points screened, the subsample of the exploration, how many ends polished, the budget
and the seed; checked once when made. The search itself is
:mod:`~roughbrdf.fitting.solvers.search`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import ArgumentError

__all__ = ["SearchOptions"]


@dataclass(frozen=True)
class SearchOptions:
    """The search settings of :func:`roughbrdf.fit` (see its parameters)."""

    starts: int = 8
    screen: int = 64
    subsample: int | None = 1000
    polish: int = 2
    max_nfev: int | None = None
    seed: int | None = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, "starts", _count("starts", self.starts, 1))
        object.__setattr__(self, "screen", _count("screen", self.screen, 0))
        object.__setattr__(self, "subsample", _count("subsample", self.subsample, 1, True))
        object.__setattr__(self, "polish", max(1, _count("polish", self.polish, 0)))
        object.__setattr__(self, "max_nfev", _count("max_nfev", self.max_nfev, 1, True))
        if self.seed is not None and not isinstance(self.seed, int | np.integer):
            raise ArgumentError("seed", f"seed must be None or an integer, got {self.seed!r}")

    @property
    def n_screen(self) -> int:
        """Sobol candidates evaluated to choose the ``starts - 1`` Sobol starts."""
        return max(self.starts - 1, int(self.screen)) if self.starts > 1 else 0



def _count(name: str, value: Any, minimum: int, none_ok: bool = False) -> Any:
    """``value`` as an int ``>= minimum`` (or None where allowed), else an ArgumentError."""
    if value is None and none_ok:
        return None
    ok = isinstance(value, int | np.integer) and not isinstance(value, bool) or (
        isinstance(value, float) and value.is_integer())
    if not ok or int(value) < minimum:
        raise ArgumentError(name, f"{name} must be >= {minimum} (an integer"
                            f"{', or None' if none_ok else ''}), got {value!r}")
    return int(value)
