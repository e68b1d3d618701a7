"""Samples a file holds that the instrument did not measure: a linear extrapolation to 0 at 90 deg.

Some instruments cover only part of the hemisphere and their software fills the rest. The
Light Tec Mini-Diff V2 files (``../shared/data/minidiff``, ``docs/fitting.md`` "Data quirks")
measure up to ``theta_r = 75`` deg; beyond it every row of constant ``(theta_i, phi)`` goes on
as a straight line in ``theta_r`` from its value at 75 deg to exactly 0 at 90 deg (on the four
azimuths of the camera's axes to 1e-9; on the others, interpolated from the camera's grid,
to a few per cent). No physical BRDF does that, and fitting it is fitting the software's
guess: a fit leaves those samples out by default (counted; ``rb.fit(extrapolated="keep")``
or ``roughbrdf fit --keep-extrapolated`` fits them too).

:func:`find_extrapolated_tail` finds such a tail: the smallest ``theta_c`` from which the
rows that are exactly such a ramp start, when every incidence of the file has one.
:func:`roughbrdf.read` stores it as ``meta["extrapolated_beyond"]`` (radians).
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .measurement import Measurement

__all__ = ["ExtrapolatedTail", "RAMP_RTOL", "extrapolated_mask", "find_extrapolated_tail",
           "mark_extrapolated"]

#: a row is a ramp when every sample beyond the start is on the line to within this fraction of
#: the row's largest value there (the exact rows of the Mini-Diff files agree to 1e-12; a
#: measured row is never that smooth)
RAMP_RTOL = 1e-9
#: the fewest samples beyond the start (the 90 deg one included) that make a row a ramp: two
#: points are always on a line
MIN_RAMP_SAMPLES = 4
_ROW_DECIMALS = 9  # rows grouped by (theta_i, phi) rounded to 1e-9 rad


@dataclass(frozen=True)
class ExtrapolatedTail:
    """Where a measurement's values stop being measured.

    Attributes
    ----------
    start : float
        ``theta_c`` in radians: the samples with ``theta_r > theta_c`` are extrapolated.
    exact_rows : int
        Rows of constant ``(theta_i, phi)`` that are exactly the ramp from ``theta_c``.
    rows : int
        Rows that reach ``theta_r = 90`` deg.
    """

    start: float
    exact_rows: int
    rows: int

    def describe(self) -> str:
        """One sentence for reports."""
        return (f"theta_r > {math.degrees(self.start):.4g} deg is a linear extrapolation to 0 "
                f"at 90 deg, not a measurement ({self.exact_rows} of {self.rows} rows exactly)")


def _rows(theta_i: np.ndarray, theta_r: np.ndarray, phi: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray]:
    """``(order, bounds)``: the sample indices sorted by row of constant ``(theta_i, phi)``
    (rounded to :data:`_ROW_DECIMALS`), within a row by ``theta_r`` (stable); row ``k`` is
    ``order[bounds[k]:bounds[k + 1]]``. One sort for all rows: a MERL file has a million rows
    of one or two samples, which a list of per-row arrays took 30 s to build and walk."""
    ti = np.round(theta_i, _ROW_DECIMALS)
    ph = np.round(np.mod(phi, 2 * math.pi), _ROW_DECIMALS)
    order = np.lexsort((theta_r, ph, ti))
    new_row = (np.diff(ti[order]) != 0) | (np.diff(ph[order]) != 0)
    bounds = np.concatenate([[0], np.flatnonzero(new_row) + 1, [order.size]])
    return order, bounds


def _ramp_start(theta_r: np.ndarray, values: np.ndarray) -> float | None:
    """The smallest ``theta_c`` of one row (sorted by ``theta_r``) from which it is a ramp."""
    top = theta_r.size - 1
    if abs(theta_r[top] - 0.5 * math.pi) > 1e-9:
        return None
    start = None
    for c in range(top - MIN_RAMP_SAMPLES, -1, -1):  # c + 1 .. top: MIN_RAMP_SAMPLES
        x_c = values[c]
        tail = values[c + 1:]
        if not np.any(x_c != 0.0):
            break  # a row of zeros is no evidence of anything
        line = x_c[None, :] * ((0.5 * math.pi - theta_r[c + 1:]) /
                               (0.5 * math.pi - theta_r[c]))[:, None]
        scale = np.max(np.abs(values[c:]), axis=0)
        if np.all(np.abs(tail - line) <= RAMP_RTOL * scale):
            start = float(theta_r[c])
        else:
            break
    return start


def find_extrapolated_tail(theta_i: np.ndarray, theta_r: np.ndarray, phi: np.ndarray,
                           values: np.ndarray) -> ExtrapolatedTail | None:
    """The extrapolated tail of a measurement, or None (see the module notes).

    Found when at least one row of every incidence is exactly a ramp, all of them from the
    same ``theta_c``; rows with a non-finite value are not considered.

    Examples
    --------
    >>> import numpy as np
    >>> tr = np.radians(np.arange(0.0, 91.0))
    >>> x = np.where(tr <= np.radians(75), 0.1 + 0.01 * np.sin(7 * tr),
    ...              (0.1 + 0.01 * np.sin(7 * np.radians(75))) * (90 - np.degrees(tr)) / 15)
    >>> tail = find_extrapolated_tail(np.zeros(91), tr, np.zeros(91), x[:, None])
    >>> round(float(np.degrees(tail.start)), 6), tail.exact_rows
    (75.0, 1)
    """
    if theta_r.size == 0:  # no samples, no rows
        return None
    values = np.asarray(values, dtype=float).reshape(theta_r.size, -1)
    order, bounds = _rows(theta_i, theta_r, phi)
    # per row, at once: all values finite, the last (largest) theta_r at 90 deg, its length
    finite = np.logical_and.reduceat(np.isfinite(values).all(axis=1)[order], bounds[:-1])
    reaches = np.abs(theta_r[order[bounds[1:] - 1]] - 0.5 * math.pi) <= 1e-9
    rows = int(np.count_nonzero(finite & reaches))
    # only rows long enough to hold a ramp are walked (_ramp_start needs more than
    # MIN_RAMP_SAMPLES samples): a few hundred in a Mini-Diff file, none in a MERL one
    walk = np.flatnonzero(finite & reaches & (np.diff(bounds) > MIN_RAMP_SAMPLES))
    starts: Counter[float] = Counter()
    incidences_with_ramp: set[float] = set()
    for k in walk:
        idx = order[bounds[k]:bounds[k + 1]]
        start = _ramp_start(theta_r[idx], values[idx])
        if start is not None:
            starts[round(start, _ROW_DECIMALS)] += 1
            incidences_with_ramp.add(round(float(theta_i[idx[0]]), _ROW_DECIMALS))
    incidences = set(np.round(theta_i, _ROW_DECIMALS).tolist())
    if len(starts) != 1 or incidences_with_ramp != incidences:
        return None
    (start, exact), = starts.items()
    return ExtrapolatedTail(start, exact, rows)


def extrapolated_mask(theta_r: np.ndarray, start: float | None) -> np.ndarray:
    """``theta_r > start`` (all False when ``start`` is None)."""
    if start is None:
        return np.zeros(theta_r.shape, dtype=bool)
    return theta_r > start + 1e-9  # 1e-9: the start sample itself is measured


def mark_extrapolated(measurement: Measurement) -> ExtrapolatedTail | None:
    """Find the tail of ``measurement`` and record it in its ``meta`` (what a reader calls).

    Sets ``meta["extrapolated_beyond"]`` (``theta_c`` in radians) and ``meta["extrapolated"]``
    (the sentence for reports) when there is one; the values are not changed.
    """
    tail = find_extrapolated_tail(measurement.theta_i, measurement.theta_r, measurement.phi,
                                  measurement.values)
    if tail is not None:
        measurement.meta["extrapolated_beyond"] = tail.start
        measurement.meta["extrapolated"] = tail.describe()
    return tail
