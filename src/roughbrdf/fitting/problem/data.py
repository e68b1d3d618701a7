"""The data of a fit, one channel at a time: what is compared, what is left out, the weights.

``docs/fitting.md`` ("What is minimized") describes the rules implemented here:

* :class:`Comparison` -- the model quantity the data are compared with: the BRDF for ``brdf``
  data, BRDF cos(theta_r) (TR75's BRIDF) for ``brdf_cos``/``bridf`` data, and for ``relative``
  data what they are proportional to (``relative_to``);
* :func:`prepare_channel` -- the samples of one channel that enter the fit, as a
  :class:`ChannelData`. Samples are never dropped silently: values the file holds but the
  instrument did not measure (:mod:`roughbrdf.extrapolation`) are left out unless
  ``extrapolated="keep"``; non-finite values raise or are
  dropped (``nonfinite``), negative ones are kept, dropped or clipped (``negative``), samples of
  weight 0, outside the fit domain the user chose (``theta_r_max``, ``source_exclusion``:
  :func:`outside_fit_domain`), where the model is not finite or not defined, and (BRDF cos data
  with the relative or log loss) at ``theta_r = 90`` deg are left out, and every count is kept
  in :attr:`ChannelData.excluded` (:data:`EXCLUSION_REASONS`; a sample is counted under the
  first reason that applies);
* :func:`channel_weights` -- the residual weights (an array, or ``"uncertainty"``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ...errors import ArgumentError
from ...extrapolation import extrapolated_mask
from ...instrument import Aperture, InstrumentGeometry
from ...quantity import Loss, Quantity

if TYPE_CHECKING:
    from ...measurement import Measurement
    from ...models import Model

__all__ = ["Comparison", "ChannelData", "DataOptions", "EXCLUSION_REASONS", "channel_weights",
           "check_fit_domain", "check_relative_to", "check_sample_options", "excluded_text",
           "NEGATIVE_RULES", "negative_rule", "outside_fit_domain", "input_source",
           "prepare_channel", "where"]

#: the reasons a sample is left out or changed, in the order reports list them
EXCLUSION_REASONS: dict[str, str] = {
    "extrapolated": "not measured (the file's extrapolation beyond the instrument's range)",
    "nonfinite": "non-finite",
    "negative": "negative (dropped)",
    "clipped": "negative (clipped)",
    "zero_weight": "of zero weight",
    "theta_r_max": "with theta_r above theta_r_max",
    "source_exclusion": "within the source exclusion (angle to the source direction)",
    "model_domain": "where the model is not finite or not defined",
    "horizon": "at theta_r = 90 deg (BRDF cos theta_r = 0 for every model)",
}


def excluded_text(excluded: dict[str, int]) -> str:
    """The counts of :attr:`ChannelData.excluded` in words (``"none"`` when nothing).

    Examples
    --------
    >>> excluded_text({"nonfinite": 2, "negative": 0})
    '2 non-finite'
    >>> excluded_text({})
    'none'
    """
    return ", ".join(f"{v} {EXCLUSION_REASONS.get(k, k)}" for k, v in excluded.items() if v) \
        or "none"


def where(meas: Measurement, label: str) -> str:
    """``"file, channel 'label'"`` for error messages."""
    f = meas.meta.get("file")
    return f"{f}, channel {label!r}" if f else f"channel {label!r}"


# --------------------------------------------------------------------------------------------
# what is compared
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Comparison:
    """The model quantity a measurement is compared with.

    Attributes
    ----------
    quantity : Quantity
        ``Quantity.BRDF`` or ``Quantity.BRIDF`` (BRDF cos theta_r).
    relative_to : str or None
        For relative data, what they are proportional to (``"brdf"`` or ``"bridf"``); None for
        absolute data.

    Examples
    --------
    >>> from roughbrdf.measurement import Measurement
    >>> m = Measurement([0.1], [0.2], [0.0], [1.0], quantity="relative",
    ...                 meta={"relative_to": "brdf_cos"})
    >>> Comparison.of(m)
    Comparison(quantity=<Quantity.BRIDF: 'bridf'>, relative_to='bridf')
    """

    quantity: Quantity
    relative_to: str | None = None

    @classmethod
    def of(cls, meas: Measurement, relative_to: str | None = None) -> Comparison:
        """For ``meas``; ``relative_to`` overrides ``meas.meta["relative_to"]`` (default
        ``"brdf"``) for relative data."""
        q = Quantity.parse(meas.quantity)
        if relative_to is not None:  # checked also for absolute data, where it is unused: a
            check_relative_to(relative_to)  # typo must not pass silently
        if q.absolute:
            return cls(q.compared_with())
        rel = relative_to or meas.meta.get("relative_to")
        try:
            model_q = q.compared_with(rel)
        except ValueError as exc:  # an unknown name or "relative": say what relative_to means
            raise ArgumentError("relative_to", f"relative_to must be 'brdf' or 'bridf' (what "
                                f"the relative values are proportional to), got {rel!r}"
                                ) from exc
        return cls(model_q, model_q.value)

    @property
    def compared(self) -> str:
        """``"brdf"`` or ``"bridf"``."""
        return self.quantity.value


#: the values ``relative_to`` takes (what relative data are proportional to)
RELATIVE_TO = ("brdf", "bridf", "brdf_cos")


def check_relative_to(relative_to: object) -> None:
    """Refuse a ``relative_to`` that is not one of :data:`RELATIVE_TO` (naming the argument).

    Examples
    --------
    >>> check_relative_to("bridf")
    >>> check_relative_to("brfd")
    Traceback (most recent call last):
    ...
    roughbrdf.errors.ArgumentError: relative_to must be 'brdf' or 'bridf' (or 'brdf_cos', the \
same as 'bridf': what relative values are proportional to), got 'brfd'
    """
    try:  # the spellings Quantity.compared_with accepts for relative data
        ok = Quantity.parse(relative_to, "relative_to").value in RELATIVE_TO
    except ValueError:
        ok = False
    if not ok:
        raise ArgumentError("relative_to", "relative_to must be 'brdf' or 'bridf' (or "
                            "'brdf_cos', the same as 'bridf': what relative values are "
                            f"proportional to), got {relative_to!r}")


@dataclass(frozen=True)
class DataOptions:
    """How :func:`prepare_channel` treats the samples (the options of :func:`roughbrdf.fit`)."""

    comparison: Comparison
    loss: str = "relative"
    weights: Any = None
    nonfinite: str = "raise"
    negative: str = "keep"
    aperture: Aperture | None = None
    theta_r_max: float | None = None
    source_exclusion: float | None = None
    extrapolated: str = "drop"

    def __post_init__(self) -> None:
        t_max, excl = check_fit_domain(self.theta_r_max, self.source_exclusion)
        object.__setattr__(self, "theta_r_max", t_max)
        object.__setattr__(self, "source_exclusion", excl)
        Loss.parse(self.loss)  # ArgumentError naming the loss
        check_sample_options(self.nonfinite, self.negative, self.extrapolated)


#: the values of ``negative`` (``"auto"``: :func:`negative_rule`)
NEGATIVE_RULES = ("auto", "keep", "drop", "clip")


def negative_rule(negative: str, loss: str) -> str:
    """The rule ``negative="auto"`` stands for with ``loss``: ``"drop"`` where the loss takes a
    logarithm (``log``, ``robust``: non-positive values have none), else ``"keep"``; any other
    value as given.

    Examples
    --------
    >>> negative_rule("auto", "robust"), negative_rule("auto", "relative")
    ('drop', 'keep')
    >>> negative_rule("clip", "log")
    'clip'
    """
    if negative != "auto":
        return negative
    return "drop" if Loss.parse(loss).positive_data else "keep"


def check_sample_options(nonfinite: Any, negative: Any, extrapolated: Any) -> None:
    """``nonfinite``, ``negative`` and ``extrapolated`` of :func:`roughbrdf.fit`: one of their
    words each (:class:`~roughbrdf.errors.ArgumentError` naming the option otherwise)."""
    if not isinstance(nonfinite, str) or nonfinite not in ("raise", "drop"):
        raise ArgumentError("nonfinite", "must be 'raise' or 'drop'", value=nonfinite)
    if not isinstance(negative, str) or negative not in NEGATIVE_RULES:
        raise ArgumentError("negative", "must be 'auto', 'keep', 'drop' or 'clip'",
                            value=negative)
    if not isinstance(extrapolated, str) or extrapolated not in ("drop", "keep"):
        raise ArgumentError("extrapolated", "must be 'drop' or 'keep'", value=extrapolated)


def _domain_angle(argument: str, value: Any, high: float, need: str) -> float | None:
    """``value`` as a float in ``[0, high]`` (radians), or None; else an ArgumentError."""
    if value is None:
        return None
    if isinstance(value, str | bytes | bool | complex):
        raise ArgumentError(argument, need, value=value)
    try:
        a = float(value)
    except (TypeError, ValueError, OverflowError):
        raise ArgumentError(argument, need, value=value) from None
    if not (math.isfinite(a) and 0.0 <= a <= high):
        raise ArgumentError(argument, need, value=a, unit="rad")
    return a


def check_fit_domain(theta_r_max: Any, source_exclusion: Any
                     ) -> tuple[float | None, float | None]:
    """The fit-domain options as floats (radians; None: not used).

    Raises :class:`~roughbrdf.errors.ArgumentError` (``unit="rad"``: the CLI shows degrees)
    unless ``0 <= theta_r_max <= pi/2`` and ``0 <= source_exclusion <= pi``.

    Examples
    --------
    >>> check_fit_domain(None, 0.1)
    (None, 0.1)
    >>> try:
    ...     check_fit_domain(2.0, None)
    ... except ValueError as err:
    ...     print(err)
    theta_r_max = 2.0 rad: must be an angle in [0, 90] deg (None: no limit)
    """
    return (_domain_angle("theta_r_max", theta_r_max, 0.5 * math.pi,
                          "must be an angle in [0, 90] deg (None: no limit)"),
            _domain_angle("source_exclusion", source_exclusion, math.pi,
                          "must be an angle in [0, 180] deg (None: no exclusion)"))


def outside_fit_domain(theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike,
                       theta_r_max: float | None = None, source_exclusion: float | None = None
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Masks ``(above, near_source)`` of the samples outside the fit domain.

    ``above``: ``theta_r > theta_r_max``; ``near_source``: the reflection direction ``w_r`` is
    less than ``source_exclusion`` from the direction toward the source ``w_i`` (the retro
    direction ``theta_r = theta_i, phi = pi``), the angle between the unit vectors taken as
    ``2 asin(|w_r - w_i| / 2)`` (accurate near 0). None: no sample. The nominal (measured)
    directions are used, also with an aperture.

    Examples
    --------
    >>> import numpy as np
    >>> above, near = outside_fit_domain([0.5, 0.5], [1.2, 0.52], [0.0, np.pi], 1.0, 0.05)
    >>> above.tolist(), near.tolist()
    ([True, False], [False, True])
    """
    from ...geometry import unit_vectors

    wi, wr = unit_vectors(theta_i, theta_r, phi)
    tr = np.broadcast_to(np.asarray(theta_r, dtype=float), wi.shape[:-1])
    above = (tr > theta_r_max if theta_r_max is not None
             else np.zeros(tr.shape, dtype=bool))
    if source_exclusion is None:
        return above, np.zeros(tr.shape, dtype=bool)
    dist = 2.0 * np.arcsin(np.clip(0.5 * np.linalg.norm(wr - wi, axis=-1), 0.0, 1.0))
    return above, dist < source_exclusion


# --------------------------------------------------------------------------------------------
# one channel's samples
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ChannelData:
    """The samples of one channel that enter a fit.

    Attributes
    ----------
    values : numpy.ndarray, shape (N,)
        The measured values ``x`` (after ``negative="clip"``), in the measurement's own scale.
    geometry : InstrumentGeometry
        Where the model is evaluated for each sample (through the aperture, if any).
    weights : numpy.ndarray or None
        Residual weights, shape (N,).
    label : str
        Channel label.
    index : numpy.ndarray
        Indices of the samples in the measurement.
    excluded : dict
        Samples left out or changed, by reason (:data:`EXCLUSION_REASONS`).
    """

    values: np.ndarray
    geometry: InstrumentGeometry
    weights: np.ndarray | None = None
    label: str = ""
    index: np.ndarray = field(default=None, repr=False)  # type: ignore[arg-type]
    excluded: dict[str, int] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.index is None:
            object.__setattr__(self, "index", np.arange(self.values.size))

    @classmethod
    def from_arrays(cls, theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike,
                    values: ArrayLike, *, polarization: ArrayLike | None = None,
                    weights: ArrayLike | None = None, aperture: Aperture | None = None,
                    label: str = "") -> ChannelData:
        """Samples given as 1-d arrays inside the hemisphere (nothing is left out).

        Examples
        --------
        >>> d = ChannelData.from_arrays([0.1, 0.2], [0.3, 0.4], [0.0, 3.0], [1.0, 2.0])
        >>> d.n, d.geometry.stencil_size
        (2, 1)
        """
        x = np.ascontiguousarray(values, dtype=float)
        gam = (np.asarray(np.nan) if polarization is None
               else np.broadcast_to(np.asarray(polarization, dtype=float), x.shape).copy())
        geo = InstrumentGeometry.build(np.asarray(theta_i, dtype=float),
                                       np.asarray(theta_r, dtype=float),
                                       np.asarray(phi, dtype=float), gam, aperture)
        w = None if weights is None else np.ascontiguousarray(weights, dtype=float)
        return cls(x, geo, w, label)

    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.values.size)

    def take(self, sub: np.ndarray) -> ChannelData:
        """The samples at positions ``sub`` (e.g. the exploration subsample)."""
        return replace(self, values=self.values[sub], geometry=self.geometry.take(sub),
                       weights=None if self.weights is None else self.weights[sub],
                       index=self.index[sub])


def channel_weights(weights: Any, meas: Measurement, j: int, x: np.ndarray, loss: str
                    ) -> np.ndarray | None:
    """Weights of channel ``j`` (None: unweighted).

    ``weights`` is None, an array of shape (N,) or (N, C), or ``"uncertainty"``: the
    measurement's uncertainty ``u`` gives ``1/u`` for the absolute loss and ``x/u`` (the inverse
    relative uncertainty) for the relative and log losses, 0 where ``u`` is not positive.
    """
    if weights is None:
        return None
    if isinstance(weights, str):
        if weights != "uncertainty":
            raise ArgumentError("weights", f"weights must be None, an array or 'uncertainty', "
                                f"got {weights!r}")
        if meas.uncertainty is None:
            raise ArgumentError("weights", "weights='uncertainty' but the measurement has no "
                                "uncertainty")
        u = meas.uncertainty[:, j]
        with np.errstate(divide="ignore", invalid="ignore"):
            w = Loss.parse(loss).uncertainty_weight(x, u)
        return np.where(np.isfinite(w) & (u > 0), w, 0.0)
    try:
        w = np.asarray(weights, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ArgumentError("weights", "weights must be None, an array of numbers or "
                            "'uncertainty'") from None
    if w.ndim == 2:
        if w.shape != meas.values.shape:
            raise ArgumentError("weights", f"weights of shape {w.shape} do not match the values "
                                f"{meas.values.shape}")
        w = w[:, j]
    try:
        w = np.broadcast_to(w, (meas.n_samples,)).astype(float)
    except ValueError:
        raise ArgumentError("weights", f"weights of shape {w.shape} do not match the "
                            f"{meas.n_samples} samples") from None
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ArgumentError("weights", "weights must be finite and >= 0")
    return w


def _bad_values(x: np.ndarray, keep: np.ndarray, excluded: dict[str, int],
                opts: DataOptions, place: str) -> None:
    """Non-finite and negative values (non-positive for the log loss): raise, drop or clip.

    Only the samples still kept count. Updates ``x`` (clipping), ``keep`` and ``excluded`` in
    place."""
    bad = keep & ~np.isfinite(x)
    if bad.any():
        if opts.nonfinite == "raise":
            rows = np.flatnonzero(bad)
            show = ", ".join(str(r) for r in rows[:8]) + (" ..." if rows.size > 8 else "")
            raise ArgumentError("nonfinite", f"{place}: {rows.size} non-finite value(s) at "
                                f"sample(s) {show}, which cannot be fitted", fix="drop")
        keep &= ~bad
        excluded["nonfinite"] = int(bad.sum())
    log = Loss.parse(opts.loss).positive_data
    neg = keep & np.isfinite(x) & ((x <= 0) if log else (x < 0))
    if not neg.any():
        return
    rule = negative_rule(opts.negative, opts.loss)
    if rule == "keep":
        if log:
            raise ArgumentError("negative", f"{place}: the {opts.loss} loss needs positive "
                                f"values but "
                                f"{int(neg.sum())} are <= 0 (drop them, or clip them to the "
                                f"smallest positive value with 'clip')", fix="drop")
    elif rule == "drop":
        keep &= ~neg
        excluded["negative"] = int(neg.sum())
    else:  # clip
        pos = x[np.isfinite(x) & (x > 0)]
        x[neg] = (pos.min() if pos.size else 1.0) if log else 0.0
        excluded["clipped"] = int(neg.sum())


def _not_measured(meas: Measurement, keep: np.ndarray, excluded: dict[str, int],
                  opts: DataOptions) -> None:
    """Leave out the samples the reader found extrapolated (:mod:`roughbrdf.extrapolation`)."""
    if opts.extrapolated == "keep":
        return
    out = extrapolated_mask(meas.theta_r, meas.meta.get("extrapolated_beyond"))
    excluded["extrapolated"] = int(out.sum())
    keep &= ~out


def _fit_domain(meas: Measurement, keep: np.ndarray, excluded: dict[str, int],
                opts: DataOptions) -> None:
    """Leave out (in ``keep``) the samples outside the fit domain the user chose."""
    if opts.theta_r_max is None and opts.source_exclusion is None:
        return
    above, near = outside_fit_domain(meas.theta_i, meas.theta_r, meas.phi, opts.theta_r_max,
                                     opts.source_exclusion)
    for key, mask in (("theta_r_max", above), ("source_exclusion", near)):
        out = keep & mask
        excluded[key] = int(out.sum())
        keep &= ~out


def _outside_domain(model: Model, meas: Measurement, keep: np.ndarray,
                    excluded: dict[str, int], opts: DataOptions) -> None:
    """Leave out (in ``keep``) the samples the model cannot be compared with."""
    if not model.grazing_incidence:
        graze = keep & (meas.theta_i >= 0.5 * math.pi)
        excluded["model_domain"] += int(graze.sum())
        keep &= ~graze
    if opts.comparison.quantity.cosine_weighted and Loss.parse(opts.loss).ratio:
        # BRDF cos(theta_r) of every model is 0 at theta_r = 90 deg: a measured value there (a
        # noise floor) has no relative or logarithmic residual
        horizon = keep & (np.cos(meas.theta_r) <= 1e-12)
        excluded["horizon"] = int(horizon.sum())
        keep &= ~horizon
    # samples where the model itself is not finite at the starting values (e.g. the BRDF of the
    # unshadowed TR75 model at theta_r = 90 deg, which is +inf): these cannot be fitted. With
    # an aperture, the model averaged over the cone (as the fit compares it) is checked.
    idx = np.flatnonzero(keep)
    if idx.size:
        f0 = _instrument_geometry(meas, idx, opts.aperture).evaluate(
            model, opts.comparison.quantity)
        ok = np.isfinite(f0)
        if not ok.all():
            excluded["model_domain"] += int((~ok).sum())
            keep[idx[~ok]] = False


def _instrument_geometry(meas: Measurement, idx: np.ndarray, aperture: Aperture | None
                         ) -> InstrumentGeometry:
    gam = (np.asarray(np.nan) if meas.polarization is None
           else np.ascontiguousarray(meas.polarization[idx]))
    return InstrumentGeometry.build(meas.theta_i[idx], meas.theta_r[idx], meas.phi[idx], gam,
                                    aperture)


def prepare_channel(model: Model, meas: Measurement, j: int, opts: DataOptions) -> ChannelData:
    """The samples of channel ``j`` that enter the fit of ``model``; every one left out counted.

    Raises ``ValueError`` (naming the file and channel) for non-finite values with
    ``nonfinite="raise"``, non-positive values for the log loss with ``negative="keep"``, and
    a channel with no sample left.
    """
    label = meas.channels[j]
    place = where(meas, label)
    x = meas.values[:, j].astype(float).copy()
    keep = np.ones(x.size, dtype=bool)
    excluded = dict.fromkeys(EXCLUSION_REASONS, 0)
    _not_measured(meas, keep, excluded, opts)
    _bad_values(x, keep, excluded, opts, place)
    w = channel_weights(opts.weights, meas, j, x, opts.loss)
    if w is not None:
        excluded["zero_weight"] = int((keep & (w == 0)).sum())
        keep &= w > 0
    _fit_domain(meas, keep, excluded, opts)
    _outside_domain(model, meas, keep, excluded, opts)
    idx = np.flatnonzero(keep)
    if idx.size == 0:
        total = int(x.size)
        raise ValueError(f"{place}: no data to fit ({total} samples; left out: "
                         + excluded_text(excluded) + ")"
                         if total else f"{place}: no data to fit (0 samples)")
    if not np.any(x[idx] > 0):  # all zero (or below): any model with a zero scale "fits",
        # and the fit would report success at its starting values
        raise ValueError(f"{place}: no positive value among the {idx.size} samples to fit "
                         f"(all are 0 or below): nothing to fit a BRDF to")
    return ChannelData(x[idx], _instrument_geometry(meas, idx, opts.aperture),
                       None if w is None else w[idx], label, idx, excluded)


def input_source(meas: Measurement) -> dict[str, str | None]:
    """``{"file", "file_abspath", "file_sha256"}`` of the file ``meas`` was read from.

    ``file`` is ``meta["file"]`` as recorded; ``file_abspath`` and ``file_sha256`` come from
    the reader's ``meta`` when it recorded them, else from the file itself (read now), and are
    None when the measurement did not come from a file or the file cannot be read.

    Examples
    --------
    >>> from roughbrdf.measurement import Measurement
    >>> input_source(Measurement([0.1], [0.2], [0.0], [1.0]))
    {'file': None, 'file_abspath': None, 'file_sha256': None}
    """
    meta = meas.meta
    f = meta.get("file")
    out: dict[str, str | None] = {"file": None if f is None else str(f),
                                  "file_abspath": meta.get("file_abspath"),
                                  "file_sha256": meta.get("file_sha256")}
    if f is None or (out["file_abspath"] and out["file_sha256"]):
        return out
    path = Path(str(out["file_abspath"] or f))
    if not path.is_file():
        return out
    out["file_abspath"] = out["file_abspath"] or str(path.resolve())
    if not out["file_sha256"]:
        from ...output import file_sha256

        out["file_sha256"] = file_sha256(path)
    return out
