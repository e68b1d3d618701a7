"""The lmfit-style text report of a fit (``report.txt``, ``roughbrdf fit`` on the terminal).

One header block for the fit (model, data quantity, what it is compared with, loss, aperture),
then per channel: success and message, points (and what was left out, with the reasons of
:data:`roughbrdf.fitting.problem.data.EXCLUSION_REASONS`), variables, starts, model evaluations,
chi2,
reduced chi2, AIC, BIC, TR75's sigma (Eq. 34) and the r.m.s. log residual, the parameters with
their standard errors, initial values and bounds, the scale ``K``, and the correlations above
``min_correl``. ``docs/fitting.md`` shows an example.

Units of angles: a parameter whose unit is an angle (Oren-Nayar ``sigma``) is printed with its
unit named, in radians (the library's unit, ``angles="rad"``, the default) or in degrees
(``angles="deg"``: what ``roughbrdf fit`` prints and writes to ``report.txt``); ``fit.json``
always holds radians.

Honest at bounds: a parameter at a bound (:func:`~roughbrdf.fitting.results.statistics.at_bound`) is
printed ``(at the lower bound: no stderr) [physical limit; <= 0.37 at 95 %, profile]`` (the
one-sided limit of :mod:`~roughbrdf.fitting.results.one_sided`, where the fit has one) or ``(at
the upper bound: no stderr) [search limit: not a result]``
(:func:`~roughbrdf.fitting.results.statistics.limit_kinds`) with a note why (the covariance is
not meaningful at an active bound); the ``[[Plausibility]]`` block
gives the albedo by incidence and the model/data peak ratios
(:mod:`~roughbrdf.fitting.results.plausibility`); a relative error is printed as a percentage only
up
to 1000 % (:func:`percent`); ``# starts`` is the number of local fits run, which is the
number asked.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from ...errors import ArgumentError
from ...quantity import Loss
from ..problem.data import excluded_text
from .physical import limit_hints, report_lines

if TYPE_CHECKING:
    from .result import ChannelFit, FitResult

__all__ = ["report", "fmt", "percent", "MAX_PERCENT_RATIO"]

def fmt(v: float | None, digits: int = 6) -> str:
    """``v`` with ``digits`` significant digits (``"None"``, ``"nan"`` and ``"inf"`` as such).

    Examples
    --------
    >>> fmt(0.123456789), fmt(None), fmt(float("nan")), fmt(2.0, 3)
    ('0.123457', 'None', 'nan', '2')
    """
    if v is None:
        return "None"
    if not math.isfinite(v):
        return str(v)
    return f"{v:.{digits}g}"


#: the units a report can show angle parameters in
ANGLE_UNITS = ("rad", "deg")


def report(result: FitResult, *, min_correl: float = 0.1, angles: str = "rad") -> str:
    """The text report of ``result`` (:meth:`FitResult.report
    <roughbrdf.fitting.FitResult.report>`); parameters whose unit is an angle in ``angles``
    (``"rad"`` or ``"deg"``), with the unit named."""
    if angles not in ANGLE_UNITS:  # a typo would silently print radians
        raise ArgumentError("angles", "must be 'rad' or 'deg'", value=angles)
    lines = _header(result)
    for i, c in enumerate(result.channels):
        lines += ["", *_channel(c), *_variables(c, angles), *_profile_lines(c, angles),
                  *_correlations(c, min_correl),
                  *result.plausibility(i).lines()]
        # a Mueller fit's channel adds its normalized elements (fitting.kinds.polarimetric)
        lines += getattr(c, "report_lines", list)()
    if result.model_choice is not None:
        choice = result.model_choice
        by = "cross-validation score" if choice.criterion == "cv" else "BIC"
        lines += ["", f"[[Model choice]] candidates sorted by {by} (best first; chosen: "
                  f"{choice.best.label})", choice.table()]
    return "\n".join(lines)


def _header(result: FitResult) -> list[str]:
    meta = result.measurement.meta
    src = meta.get("file") or meta.get("sample") or "<measurement in memory>"
    comp = f"model {result.compared}"
    if result.relative_to:
        comp += " (relative data: free scale K, x -> K x, closed form)"
    ap = result.instrument
    return [f"[[Fit]] {result.model_name} to {src}",
            f"    data quantity      = {result.measurement.quantity}",
            f"    compared with      = {comp}",
            f"    loss               = {Loss.parse(result.loss).text}",
            *_mueller_text(result.options),
            "    aperture           = " + (
                "none (model at each measured direction)" if ap is None else ap.describe()),
            f"    fit domain         = {_domain_text(result.options)}",
            *_not_measured(result),
            f"    channels           = {len(result.channels)}" + _joint_text(result.options),
            f"    time               = {result.elapsed:.3g} s"]


def _mueller_text(options: dict) -> list[str]:
    """The line of a Mueller fit (:mod:`~roughbrdf.fitting.kinds.polarimetric`), else nothing."""
    mu = options.get("mueller")
    if not mu:
        return []
    els = mu["elements"]
    which = (f"the {len(els)} other elements" if len(els) == 15
             else ", ".join(els) or "no other element")
    return [f"    polarimetric       = Mueller elements ({mu['kind']}, basis {mu['basis']}): "
            f"m00 by the loss above, {which} as m_ij/m00 by absolute difference "
            f"x {mu['polarimetric_weight']:g}"]


def _not_measured(result: FitResult) -> list[str]:
    """The line about samples the file holds but the instrument did not measure, if any."""
    what = result.measurement.meta.get("extrapolated")
    if not what:
        return []
    done = ("left out (extrapolated='keep' fits them)"
            if result.options.get("extrapolated", "drop") == "drop" else "fitted (asked)")
    return [f"    not measured       = {what}: {done}"]


def _joint_text(options: dict) -> str:
    """`` (joint fit: ... shared)`` for a joint fit, else empty."""
    joint = options.get("joint")
    if not joint:
        return ""
    return (f" (joint fit, shared: {', '.join(joint['shared']) or 'none'}; "
            f"{joint['n_varys']} unknowns in all, BIC {joint['bic']:.6g})")


def _domain_text(options: dict) -> str:
    """The fit-domain options in words (``"all samples"`` when none)."""
    t_max, excl = options.get("theta_r_max"), options.get("source_exclusion")
    parts = ([] if t_max is None else [f"theta_r <= {math.degrees(t_max):.4g} deg"]) + (
        [] if excl is None else [f">= {math.degrees(excl):.4g} deg from the source direction"])
    return ", ".join(parts) or "all samples"


def _starts_text(c: ChannelFit) -> str:
    """The local fits run: the starts (as asked), where they came from, and the polish."""
    explored = [s for s in c.starts if s["stage"] != "full"]
    polished = len(c.starts) - len(explored)
    notes = []
    if any(s.get("origin") == "previous channel" for s in explored):
        notes.append("1 from the previous channel's optimum")
    data = sum(s.get("origin") == "data" for s in explored)
    if data:
        notes.append(f"{data} from the data's peak widths")
    if polished:
        notes.append(f"on a subsample, the {polished} best refined on all samples")
    return f"{len(explored)}" + (f"  ({'; '.join(notes)})" if notes else "")


def _channel(c: ChannelFit) -> list[str]:
    return [
        f"[[Channel {c.channel}]]",
        f"    success            = {c.success}  ({c.message})",
        f"    # data points      = {c.n_points}  (left out / changed: "
        f"{excluded_text(c.excluded)})",
        f"    # variables        = {c.n_varys}"
        + ("  (including the scale K)" if c.free_scale else ""),
        f"    # starts           = {_starts_text(c)}",
        f"    # model evals      = {c.nfev}",
        f"    chi-square         = {fmt(c.chi2)}",
        f"    reduced chi-square = {fmt(c.redchi)}",
        f"    Akaike info crit   = {fmt(c.aic)}",
        f"    Bayesian info crit = {fmt(c.bic)}",
        f"    TR75 sigma         = {fmt(c.sigma, 4)}   (r.m.s. of (Kx - f)/f)",
        f"    r.m.s. log resid.  = {fmt(c.rms_log, 4)}",
    ]


#: relative standard errors above this (1000 %) are not printed as a percentage
MAX_PERCENT_RATIO = 10.0


def percent(se: float | None, val: float | None) -> str:
    """``" (1.23%)"``: the standard error relative to the value, or ``""`` when it is not
    meaningful (no stderr, value 0), or ``" (> 1000%)"`` beyond :data:`MAX_PERCENT_RATIO`.

    Examples
    --------
    >>> percent(0.01, 0.5), percent(5.43e5, 5.6e-13), percent(float("nan"), 1.0), percent(1, 0)
    (' (2.00%)', ' (> 1000%)', '', '')
    """
    if se is None or val is None or not math.isfinite(se) or not val:
        return ""
    ratio = se / abs(val)
    return f" ({100 * ratio:.2f}%)" if ratio <= MAX_PERCENT_RATIO else " (> 1000%)"


def _angle_parameters(c: ChannelFit) -> set[str]:
    """The parameters of the channel's model whose unit is an angle (radians)."""
    model = getattr(c, "model", None)
    return {p.name for p in getattr(model, "parameters", ()) if p.unit == "rad"}


def _physical_units(c: ChannelFit) -> dict[str, str]:
    """The units of the channel's parameters that have one other than an angle or ``1`` (the
    stray-light codes' ``A`` in sr⁻¹, the PSD's ``A`` in µm⁴, TS67's ``c`` per degree)."""
    model = getattr(c, "model", None)
    return {p.name: p.unit for p in getattr(model, "parameters", ())
            if p.unit not in ("", "1", "rad")}


def _shown(v: float | None, angle: str | None, digits: int = 6) -> str:
    """``v`` (radians where ``angle`` names the unit of an angle parameter) in that unit,
    :func:`fmt`-ed."""
    if v is None or angle is None:
        return fmt(v, digits)
    return fmt(math.degrees(v) if angle == "deg" else v, digits)


def _variable(c: ChannelFit, name: str, val: float | None, angle: str | None,
              physical: str | None = None) -> str:
    """One parameter's line; ``angle`` is the unit of an angle parameter (else None),
    ``physical`` another unit to print beside the values (else None)."""
    def shown(v: float | None, digits: int = 6) -> str:
        return _shown(v, angle, digits)

    unit = f" {angle}" if angle else (f" {physical}" if physical else "")
    if name not in c.free:
        return "None (switched off)" if val is None else f"{shown(val, 7)}{unit} (fixed)"
    lo, hi = c.bounds[name]
    tail = f"(init = {shown(c.init[name])}{unit}, bounds [{shown(lo)}, {shown(hi)}]{unit})"
    side = c.at_bound.get(name)
    if side is not None:
        kind = c.limits.get(name, "search").split("-")[0]
        what = "search limit: not a result" if kind == "search" else "physical limit"
        if name in c.one_sided:  # its one-sided limit from the profile (results.one_sided)
            u = c.one_sided[name]
            what += (f"; {'<=' if side == 'lower' else '>='} {shown(u, 4)}{unit} at 95 %, "
                     f"profile" if u is not None else "; not bounded by the data within the "
                     "search range, profile")
        return f"{shown(val, 7)}{unit} (at the {side} bound: no stderr) [{what}] {tail}"
    se = c.stderr.get(name)
    return f"{shown(val, 7)}{unit} +/- {shown(se, 4)}{unit}{percent(se, val)} {tail}"


def _variables(c: ChannelFit, angles: str = "rad") -> list[str]:
    width = max(len(n) for n in [*c.params, "scale K"])
    lines = ["[[Variables]]"]
    angular, units = _angle_parameters(c), _physical_units(c)
    lines += [f"    {name:<{width}}: "
              f"{_variable(c, name, val, angles if name in angular else None, units.get(name))}"
              for name, val in c.params.items()]
    if c.at_bound:
        names = ", ".join(c.at_bound)
        lines += [f"    ({names} at a bound: no standard error, since the covariance is not "
                  f"meaningful",
                  f"     at an active bound; the others' are computed with {names} held there)"]
        search = [nm for nm, k in c.limits.items() if k.startswith("search")]
        if search:
            lines += [f"    SEARCH LIMIT: {', '.join(search)} ended on a bound of the search that "
                      f"is no physical limit:",
                      "     the value is where the search stopped, not a result (widen the "
                      "bounds or change the model)"]
            lines += limit_hints(c)  # what such a limit says about the model (physical.py)
    lines += report_lines(c)  # a search range beyond the physical one (fitting.results.physical)
    if c.free_scale:
        lines.append(f"    {'scale K':<{width}}: {fmt(c.scale, 7)} +/- "
                     f"{fmt(c.scale_stderr, 4)}{percent(c.scale_stderr, c.scale)} (closed form)")
    elif c.scale != 1.0:
        lines.append(f"    {'scale K':<{width}}: {fmt(c.scale, 7)} (given)")
    return lines


def _profile_lines(c: ChannelFit, angles: str) -> list[str]:
    """The ``[[Profile intervals]]`` block (``intervals="profile"``; none: [])
    (:mod:`~roughbrdf.fitting.results.intervals`)."""
    if not c.intervals:
        return []
    angular = _angle_parameters(c)
    width = max(len(n) for n in c.intervals)
    lines = ["[[Profile intervals]] (where the cost, the others refitted, rises as the standard "
             "errors calibrate it)"]
    for name, by in c.intervals.items():
        angle = angles if name in angular else None
        unit = f" {angle}" if angle else ""
        lines.append(f"    {name:<{width}}: " + "  ".join(
            f"{lv} % [{_end(lo, angle)}, {_end(hi, angle)}]{unit}" for lv, (lo, hi) in by.items()))
    if any(v is None for by in c.intervals.values() for pair in by.values() for v in pair):
        lines.append("    (none: the data do not bound that side within the search range)")
    return lines


def _end(v: float | None, angle: str | None) -> str:
    """One end of a profile interval: ``none`` where the data do not bound that side."""
    return "none" if v is None else _shown(v, angle, 5)


def _correlations(c: ChannelFit, min_correl: float) -> list[str]:
    pairs = []
    names = list(c.correl)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            v = c.correl[a].get(b)
            if v is not None and math.isfinite(v) and abs(v) >= min_correl:
                pairs.append((abs(v), a, b, v))
    if not pairs:
        return []
    return [f"[[Correlations]] (unreported correlations are < {min_correl:.3f})",
            *(f"    C({a}, {b}) = {v:+.4f}" for _, a, b, v in sorted(pairs, reverse=True))]
