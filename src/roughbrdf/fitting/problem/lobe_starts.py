"""Start points of a multi-lobe search from the data's own peaks (``docs/fitting.md``,
"Multi-scale starts").

A model with two or three specular lobes of one distribution (the ``coated`` model's
``lobes=2, 3``) can describe a narrow peak with a wide haze around it. Sobol points in the box
of ``(alpha, alpha2, w2)`` rarely land in that basin: a narrow lobe of width 0.01-0.02 with a
haze of a few per cent of the weight is a small corner of ``[0.005, 1.5]^2 x [0, 1]``.
This module reads the two scales off the measurement, per incidence, in the space of the
half vector's slope ``t = tan theta_h`` (where GGX and Beckmann are functions of ``t/alpha``):

* the **floor**: the lower quartile of the values far from the mirror direction (the
  substrate's diffuse level);
* the **peak**: the highest value within :data:`PEAK_SLOPE` of the mirror direction, less the
  floor; its **width at half height** ``t_half`` (interpolated between the samples either side
  of half the peak, linearly in ``(t^2, ln excess)``), converted to the distribution's
  ``alpha`` (:data:`HALF_HEIGHT`);
* the **haze**: the median excess over the floor in rings of ``t`` beyond the peak's core
  (:data:`CORE`), its level next to the core (the shoulder) and the ring where it has fallen
  to half of that; the two points fix a lobe of the distribution (its width and its height at
  ``t = 0``), and the heights of both lobes, ``w_j D_j(0)``, ``D(0) = 1/(pi alpha^2)``, give
  the haze's weight.

The estimates of the incidences are combined by their medians and rounded to
:data:`DIGITS` significant digits, so that a start does not hang on the last bits of the data
or of the arithmetic (``docs/fitting.md``, "The same answer on every machine"). The search
(:class:`~roughbrdf.fitting.solvers.search.MultiStart`) runs them in place of Sobol starts;
models without several lobes get none, and their search is unchanged.

A model says where its lobes are with a method ``lobe_layout()`` returning ``(distribution,
widths, shares)`` (:class:`LobeLayout`'s fields; the ``coated`` model has one: models sit below
fitting and do not import it); any other model has no lobes here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from .data import ChannelData
    from .objective import ObjectiveSpec

__all__ = ["LobeEstimate", "LobeLayout", "PeakShape", "estimate_lobes", "lobe_layout",
           "lobe_starts", "peak_shape", "profile", "reopened", "round_sig", "slopes", "CORE",
           "DIGITS", "HALF_HEIGHT", "LOBE_OFF", "MAX_DATA_STARTS", "PEAK_SLOPE"]

#: ``t_half / alpha`` of each distribution at half its height: GGX ``(1 + u)^-2 = 1/2`` at
#: ``u = t^2/alpha^2 = sqrt(2) - 1``; Beckmann ``exp(-u) = 1/2`` at ``u = ln 2``
HALF_HEIGHT = {"trowbridge-reitz": math.sqrt(math.sqrt(2.0) - 1.0),
               "beckmann": math.sqrt(math.log(2.0))}
#: the peak is the highest value within this slope of the mirror direction (theta_h <= 8.5
#: deg): an off-specular peak (the Mini-Diff's at 60 deg, 1-2 deg off) is still found, the
#: diffuse hump of a matte sample far away is not
PEAK_SLOPE = 0.15
#: a specular lobe whose weight is below this is switched off (model choice counts it as the
#: smaller model: ``fitting.choice.compare.lobes_off``; the search reopens it: :func:`reopened`)
LOBE_OFF = 1e-3
#: the haze is read beyond this many half-widths of the peak, where a Beckmann peak has fallen
#: below 0.2 % of its height (and a GGX peak to 4.5 %)
CORE = 3.0
#: significant digits of every estimate: a start may not depend on the last bits of the data
DIGITS = 3
#: at most this many data starts per channel (the rest of ``starts`` stay Sobol points)
MAX_DATA_STARTS = 2
#: ring edges of the haze, as ratios: ``CORE t_half * RING**k``
RING = 1.6
#: a peak must stand this many times above the floor to be read (below: a matte incidence)
MIN_CONTRAST = 3.0


@dataclass(frozen=True)
class LobeLayout:
    """Where a model's specular lobes are: the distribution (``"trowbridge-reitz"`` or
    ``"beckmann"``), each lobe's width parameter and its weight share (None for the first
    lobe, whose weight is what the others leave).

    Examples
    --------
    >>> LobeLayout("beckmann", ("alpha", "alpha2"), (None, "w2")).lobes
    2
    """

    distribution: str
    widths: tuple[str, ...]
    shares: tuple[str | None, ...]

    @property
    def lobes(self) -> int:
        """The number of lobes."""
        return len(self.widths)


@dataclass(frozen=True)
class PeakShape:
    """The peak and haze of one incidence, in the half vector's slope ``t = tan theta_h``.

    Attributes
    ----------
    floor : float
        The values' level far from the mirror direction.
    peak : float
        The highest value near the mirror direction, less the floor.
    half_slope : float
        The peak's half width at half height (slope).
    haze_level : float
        The haze's height at ``t = 0`` over the floor (NaN: no haze read).
    haze_slope : float
        The haze's half width at half height (slope; NaN: none).
    """

    floor: float
    peak: float
    half_slope: float
    haze_level: float = math.nan
    haze_slope: float = math.nan


@dataclass(frozen=True)
class LobeEstimate:
    """The two roughness scales of a channel: the narrow lobe's ``alpha``, the haze's
    ``alpha`` and its weight (of the lobes' total), rounded to :data:`DIGITS` digits."""

    narrow: float
    haze: float
    weight: float


def round_sig(value: float, digits: int = DIGITS) -> float:
    """``value`` rounded to ``digits`` significant digits (NaN and 0 as they are).

    Examples
    --------
    >>> round_sig(0.0123456), round_sig(123456.0), round_sig(0.0)
    (0.0123, 123000.0, 0.0)
    """
    if not math.isfinite(value) or value == 0.0:
        return value
    return float(f"{value:.{digits - 1}e}")


def slopes(theta_i: Any, theta_r: Any, phi: Any) -> np.ndarray:
    """``tan theta_h``, the slope of the half vector of each geometry (``phi = 0`` forward).

    Examples
    --------
    >>> slopes([0.3, 0.3], [0.3, 0.5], [0.0, 0.0]).round(4).tolist()   # mirror, 0.1 rad off
    [0.0, 0.1003]
    """
    ti, tr, ph = (np.asarray(a, dtype=float) for a in (theta_i, theta_r, phi))
    hx = -np.sin(ti) + np.sin(tr) * np.cos(ph)  # the source on -x (docs/models.md 1.1)
    hy = np.sin(tr) * np.sin(ph)
    hz = np.cos(ti) + np.cos(tr)
    # hz = 0 only for two grazing directions opposite each other: no half vector, no slope
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.hypot(hx, hy) / hz
    return np.where(hz > 0.0, t, np.inf)


def profile(u: np.ndarray, dist: str) -> np.ndarray:
    """A lobe's height relative to its top at ``u = t/alpha``: GGX ``(1 + u^2)^-2``, Beckmann
    ``exp(-u^2)`` (the distributions without their ``cos^-4 theta_h``, near 1 for a narrow
    lobe).

    Examples
    --------
    >>> profile(np.array([0.0, 1.0]), "trowbridge-reitz").tolist()
    [1.0, 0.25]
    """
    u2 = np.square(u)
    return np.exp(-u2) if dist == "beckmann" else 1.0 / np.square(1.0 + u2)


def _cross(t: np.ndarray, e: np.ndarray, level: float) -> float:
    """The slope where the excess ``e`` (sorted by ``t``) first falls below ``level``,
    interpolated linearly in ``(t^2, ln e)`` between the last sample at or above it and the
    next one below (exact for a Gaussian in ``t``); NaN when it never does."""
    below = np.flatnonzero(e < level)
    if below.size == 0 or below[0] == 0:
        return math.nan
    k = int(below[0])
    t0, t1, e0, e1 = t[k - 1], t[k], e[k - 1], max(e[k], 1e-300)  # e1 > 0 for the log
    if not t1 > t0 or not e0 > e1:
        return float(t0)
    f = math.log(e0 / level) / math.log(e0 / e1)
    return math.sqrt(t0 * t0 + f * (t1 * t1 - t0 * t0))


def _haze(t: np.ndarray, e: np.ndarray, start: float, floor: float, dist: str
          ) -> tuple[float, float]:
    """``(height at t = 0, half width)`` of the haze from the medians of ``e`` in rings of
    ``t`` from ``start`` (ratio :data:`RING`): its shoulder (the highest ring) and the next
    ring below half of it, read as two points of the distribution; NaNs when the shoulder
    does not stand out of the floor's noise or never halves."""
    edges = start * RING ** np.arange(0, 12)
    rings = []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        sel = (t >= lo) & (t < hi)
        if sel.sum() >= 3:  # a median of fewer is one sample's noise
            rings.append((math.sqrt(lo * hi), float(np.median(e[sel]))))
    # the shoulder: the highest ring (next to the core, what the peak's lobe left may be
    # below 0: the grid misses the top, and the lobe read from it is too wide)
    top = max(range(len(rings)), key=lambda i: rings[i][1]) if rings else 0
    # it must stand out: 5 % of the floor is the Mini-Diff's scatter of one ring
    if len(rings) < 2 or not rings[top][1] > 0.05 * floor:
        return math.nan, math.nan
    (t1, e1) = rings[top]
    nxt = next(((tt, ee) for tt, ee in rings[top + 1:] if ee < 0.5 * e1), None)
    if nxt is None:
        return math.nan, math.nan
    t2, e2 = nxt[0], max(nxt[1], 1e-3 * e1)  # a median at or below 0: a per mille of e1
    if dist == "beckmann":  # e = H exp(-t^2/a^2)
        a2 = (t2 * t2 - t1 * t1) / math.log(e1 / e2)
        height = e1 * math.exp(t1 * t1 / a2)
    else:  # GGX: e^(-1/2) = H^(-1/2) (1 + t^2/a^2)
        q = math.sqrt(e1 / e2)
        a2 = (t2 * t2 - q * t1 * t1) / (q - 1.0)
        if not a2 > 0.0:  # falls faster than any GGX lobe through the first point
            return math.nan, math.nan
        height = e1 * (1.0 + t1 * t1 / a2) ** 2
    return height, math.sqrt(a2) * HALF_HEIGHT[dist]


def peak_shape(t: np.ndarray, x: np.ndarray, dist: str, tilt: np.ndarray | None = None
               ) -> PeakShape | None:
    """The :class:`PeakShape` of one incidence's samples (slopes ``t``, values ``x``), or None
    when no peak stands :data:`MIN_CONTRAST` times above the floor near the mirror direction.
    ``tilt`` (per sample, 1 at the mirror direction) multiplies the excess over the floor
    before the widths are read: ``cos theta_r/cos theta_i`` undoes a BRDF lobe's
    ``1/cos theta_r``, which widens a haze toward grazing.

    Examples
    --------
    >>> t = np.linspace(0.0, 1.0, 401)
    >>> x = 0.01 + 10.0 * np.exp(-t**2 / 0.02**2) + 0.5 * np.exp(-t**2 / 0.1**2)
    >>> s = peak_shape(t, x, "beckmann")
    >>> round(s.half_slope / HALF_HEIGHT["beckmann"], 3), round(s.haze_level, 2)
    (0.02, 0.5)
    >>> round(s.haze_slope / HALF_HEIGHT["beckmann"], 3)
    0.1
    """
    ok = np.isfinite(t) & np.isfinite(x)
    t, x = t[ok], x[ok]
    far = t > np.median(t)
    near = t <= PEAK_SLOPE
    if far.sum() < 4 or not near.any():  # too few samples to tell floor from peak
        return None
    floor = float(np.percentile(x[far], 25))
    top = float(np.max(x[near]))
    # a floor below 0 (noise around a black sample's 0) counts as 0
    if not top > MIN_CONTRAST * max(floor, 0.0) or not top > 0.0:
        return None
    order = np.argsort(t, kind="stable")
    ts, es = t[order], x[order] - floor
    if tilt is not None:
        es = es * np.asarray(tilt, dtype=float)[ok][order]
    peak = top - floor
    half = _cross(ts, np.maximum.accumulate(es[::-1])[::-1], 0.5 * peak)
    if not half > 0.0:  # the peak is one sample wide at the mirror: half the next sample out
        nxt = ts[ts > 0.0]
        half = 0.5 * float(nxt[0]) if nxt.size else math.nan
    if not math.isfinite(half):
        return None
    # the haze is what the peak's own lobe (of the distribution, at the read width) leaves:
    # a GGX peak's tail (t^-4) still holds 4.5 % of its height at CORE half-widths
    height, width = _haze(ts, es - peak * profile(ts / (half / HALF_HEIGHT[dist]), dist),
                          CORE * half, max(floor, 0.0), dist)
    return PeakShape(floor, peak, half, height, width)


def _incidences(theta_i: np.ndarray) -> list[np.ndarray]:
    """Indices of the samples of each incidence (to 0.1 deg, the instruments' grid)."""
    deg = np.round(np.degrees(theta_i), 1)
    return [np.flatnonzero(deg == d) for d in np.unique(deg)]


def estimate_lobes(theta_i: Any, theta_r: Any, phi: Any, values: Any, dist: str,
                   cosine: bool = False) -> LobeEstimate | None:
    """The narrow lobe's and the haze's ``alpha`` and the haze's weight, medians over the
    incidences (:func:`peak_shape`), rounded to :data:`DIGITS` digits; None without a peak.
    ``cosine``: the values are BRDF cos theta_r (no tilt to undo).
    Without a haze read at any incidence, a haze 5 times wider with 5 % of the weight.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> g = np.radians(np.mgrid[20:41:20, 0:76:1, 0:351:10].reshape(3, -1))
    >>> true = rb.model("coated", lobes=2, distribution="beckmann", alpha=0.02,
    ...                 alpha2=0.1, w2=0.1, rho=0.05)
    >>> est = estimate_lobes(*g, true.brdf(*g), "beckmann")
    >>> 0.01 < est.narrow < 0.04 and 0.05 < est.haze < 0.2 and 0.02 < est.weight < 0.3
    True
    """
    ti, tr, ph, x = (np.asarray(a, dtype=float) for a in (theta_i, theta_r, phi, values))
    t = slopes(ti, tr, ph)
    # cos theta_r/cos theta_i: 1 at the mirror; theta_i < 90 deg (a measured incidence)
    tilt = None if cosine else np.cos(tr) / np.cos(ti)
    shapes = [s for idx in _incidences(ti)
              if (s := peak_shape(t[idx], x[idx], dist, None if tilt is None else tilt[idx]))]
    if not shapes:
        return None
    c = HALF_HEIGHT[dist]
    narrow = float(np.median([s.half_slope / c for s in shapes]))
    hazy = [s for s in shapes if math.isfinite(s.haze_slope) and s.haze_slope / c > narrow]
    if not hazy:  # the data show no haze: a start that lets the search find out
        return LobeEstimate(round_sig(narrow), round_sig(5.0 * narrow), 0.05)
    wide = float(np.median([s.haze_slope / c for s in hazy]))
    # lobe heights w_j D_j(0) with D(0) = 1/(pi alpha^2): the haze's share of the weight
    # a haze read as high as the whole peak leaves the narrow lobe nothing: its share -> 1
    ratios = [(s.haze_level / max(s.peak - s.haze_level, 1e-300)) * (s.haze_slope / s.half_slope)
              ** 2 for s in hazy]
    r = float(np.median(ratios))
    return LobeEstimate(round_sig(narrow), round_sig(wide), round_sig(r / (1.0 + r)))


def lobe_layout(model: Any) -> LobeLayout | None:
    """The model's :class:`LobeLayout` (from its ``lobe_layout()`` method), or None: no
    lobes, or a distribution other than GGX and Beckmann (no half-height rule here).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> lobe_layout(rb.model("coated", lobes=2)).widths
    ('alpha', 'alpha2')
    >>> lobe_layout(rb.model("lambertian")) is None
    True
    """
    get = getattr(model, "lobe_layout", None)
    if get is None:
        return None
    dist, widths, shares = get()
    return LobeLayout(dist, tuple(widths), tuple(shares)) if dist in HALF_HEIGHT else None


def _measured(data: ChannelData) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The measured directions of the samples (with an aperture, each stencil's first node,
    its axis: :func:`roughbrdf.instrument.aperture_stencil`)."""
    g, s = data.geometry.geometry, data.geometry.stencil_size

    def axis(a: np.ndarray) -> np.ndarray:
        a = np.broadcast_to(a, (data.n * s,))
        return a.reshape(data.n, s)[:, 0]

    return axis(g.theta_i), axis(g.theta_r), axis(g.phi)


def lobe_starts(spec: ObjectiveSpec, data: ChannelData, k: int = MAX_DATA_STARTS
                ) -> list[np.ndarray]:
    """Up to ``k`` start points (free parameters of ``spec``) with a narrow lobe at the
    data's peak width and a second lobe at its haze (:func:`estimate_lobes`), the other
    parameters at the model's values; the second start puts the narrow lobe at half the read
    width (the instrument's grid and aperture widen a sharp peak). A third lobe starts 4 times
    wider than the haze with the same share. None for a model with fewer than two lobes, or
    whose widths and shares are not all free.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> from roughbrdf.fitting import ChannelData, ObjectiveSpec
    >>> g = np.radians(np.mgrid[20:41:20, 0:76:1, 0:351:10].reshape(3, -1))
    >>> true = rb.model("coated", lobes=2, alpha=0.02, alpha2=0.15, w2=0.1, rho=0.05)
    >>> data = ChannelData.from_arrays(*g, true.brdf(*g))
    >>> m = rb.model("coated", lobes=2)
    >>> spec = ObjectiveSpec(m, ["alpha", "alpha2", "w2"], [0.005, 0.005, 0.0], [1.5, 1.5, 1.0])
    >>> [s.tolist() for s in lobe_starts(spec, data)]   # GGX haze read 1.5x wide: a start
    [[0.0208, 0.229, 0.0971], [0.0104, 0.229, 0.0971]]
    >>> lobe_starts(ObjectiveSpec(rb.model("coated"), ["alpha"], [0.005], [1.5]), data)
    []
    """
    layout = lobe_layout(spec.model)
    names = list(spec.free)
    if k <= 0 or layout is None or layout.lobes < 2:
        return []
    wanted = [*layout.widths, *(s for s in layout.shares if s is not None)]
    if not all(nm in names for nm in wanted) or data.n == 0:
        return []
    est = estimate_lobes(*_measured(data), data.values, layout.distribution,
                         cosine=str(spec.quantity) != "brdf")
    if est is None:
        return []
    base = np.array(list(spec.start_values().values()))
    out = []
    for narrow in (est.narrow, round_sig(0.5 * est.narrow))[:k]:
        x = base.copy()
        widths = (narrow, est.haze, round_sig(4.0 * est.haze))
        for j, nm in enumerate(layout.widths):
            x[names.index(nm)] = widths[j]
        for share in layout.shares[1:]:
            if share is not None:  # weights="free": no share, the scale stays the model's
                x[names.index(share)] = est.weight
        out.append(np.clip(x, spec.lower, spec.upper))
    return out


def reopened(spec: ObjectiveSpec, x: np.ndarray, seeds: Sequence[np.ndarray]
             ) -> list[np.ndarray]:
    """The end ``x`` of a search with its lobes reopened, one point per data start in
    ``seeds`` (:func:`lobe_starts`): every lobe width and share of the seed, the other
    parameters (index, substrate) of ``x``; ``[]`` unless a lobe of ``x`` is switched off
    (its weight below :data:`LOBE_OFF`).

    Why (``docs/fitting.md``, "Multi-scale starts"): a polish that starts on a switched-off
    lobe (weight 0: its width has no effect there) leaves it or steps into a narrow second
    lobe by the last bits of its path. Measured: C8_Silver's two GGX lobes at 525 nm ended
    with the lobe off (chi2 678.70) on the data and with a narrow lobe of 1.3 % (676.60) on
    the data times ``1 + 1e-13 z``. The search polishes these points too and keeps the best.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> from roughbrdf.fitting import ObjectiveSpec
    >>> spec = ObjectiveSpec(rb.model("coated", lobes=2), ["n", "alpha", "alpha2", "w2"],
    ...                      [1.05, 0.005, 0.005, 0.0], [2.5, 1.5, 1.5, 1.0])
    >>> seed = np.array([1.5, 0.02, 0.2, 0.1])
    >>> [y.tolist() for y in reopened(spec, np.array([1.6, 0.1, 1.5, 0.0]), [seed])]
    [[1.6, 0.02, 0.2, 0.1]]
    >>> reopened(spec, np.array([1.6, 0.1, 0.3, 0.2]), [seed])   # both lobes on
    []
    """
    model = getattr(spec, "model", None)  # a joint fit's layout has none (and no data starts)
    layout = None if model is None or not seeds else lobe_layout(model)
    if layout is None or layout.lobes < 2:
        return []
    lobes = getattr(spec.model_at(x), "specular_lobes", None)
    if lobes is None:
        return []
    if all(w >= LOBE_OFF for w, _ in lobes()):
        return []
    names = list(spec.free)
    wanted = [*layout.widths, *(s for s in layout.shares if s is not None)]
    idx = [names.index(nm) for nm in wanted if nm in names]
    out = []
    for seed in seeds:
        y = np.array(x, dtype=float)
        y[idx] = np.asarray(seed, dtype=float)[idx]
        out.append(y)
    return out
