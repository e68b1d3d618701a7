"""Rich HTML of a model, a measurement and a fit, for Jupyter (``_repr_html_``).

Jupyter shows an object by its ``_repr_html_`` when it has one (IPython's rich display
protocol, "Rich output" in the IPython documentation: a method returning an HTML fragment).
:meth:`Model._repr_html_ <roughbrdf.models.Model._repr_html_>`,
:meth:`Measurement._repr_html_ <roughbrdf.measurement.Measurement._repr_html_>` and
:meth:`FitResult._repr_html_ <roughbrdf.fitting.FitResult._repr_html_>` use the builders here
(the first two through :mod:`roughbrdf.rich_display`, with which this module registers them
when imported: they are lower in the package's layers and do not import this module):

* :func:`model_html`: the model's name and reference, a table of its parameters (value, unit,
  search bounds, physical domain, description) and its options; a sum, one block per component;
* :func:`measurement_html`: samples, channels, quantity, incidences in degrees, provenance;
* :func:`fit_html`: model, input, loss, and per channel its success, message, TR75's sigma,
  the r.m.s. log residual, the largest albedo over incidence and the parameters with their
  standard errors.

Every text is escaped (:func:`html.escape`): a file name, a channel label or a message can hold
``<``, ``&`` or quotes. The fragments are self-contained (no script, no external style).

Examples
--------
>>> import roughbrdf as rb
>>> text = model_html(rb.model("lambertian", rho=0.25))
>>> "<table" in text and "0.25" in text and "rho" in text
True
"""

from __future__ import annotations

import math
from html import escape
from typing import TYPE_CHECKING, Any

import numpy as np

from .rich_display import register_html

if TYPE_CHECKING:
    from .fitting.results.result import ChannelFit, FitResult
    from .measurement import Measurement
    from .models import Model

__all__ = ["fit_html", "measurement_html", "model_html", "number"]

#: the style of the tables (inline: the fragment is shown in notebooks and exported HTML alike)
_TABLE = ('<table style="border-collapse:collapse;margin:0.3em 0;font-size:90%">')
_CELL = ' style="padding:0.1em 0.6em;text-align:left;border-bottom:1px solid #ddd"'


def number(v: Any, digits: int = 6) -> str:
    """``v`` with ``digits`` significant digits; ``None`` as ``"None"`` (a part switched off),
    NaN and infinities by name, anything else as its ``str``.

    Examples
    --------
    >>> number(0.123456789), number(None), number(float("nan")), number(3)
    ('0.123457', 'None', 'nan', '3')
    """
    if v is None:
        return "None"
    if isinstance(v, bool) or not isinstance(v, int | float | np.floating | np.integer):
        return str(v)
    f = float(v)
    return f"{f:.{digits}g}" if math.isfinite(f) else str(f)


def _table(head: list[str], rows: list[list[Any]]) -> str:
    """An HTML table; every cell escaped."""
    th = "".join(f"<th{_CELL}>{escape(str(h))}</th>" for h in head)
    body = "".join("<tr>" + "".join(f"<td{_CELL}>{escape(str(c))}</td>" for c in r) + "</tr>"
                   for r in rows)
    return f"{_TABLE}<thead><tr>{th}</tr></thead><tbody>{body}</tbody></table>"


def _facts(items: list[tuple[str, Any]]) -> str:
    """A two-column table of ``(what, value)`` facts."""
    body = "".join(f"<tr><th{_CELL}>{escape(str(k))}</th><td{_CELL}>{escape(str(v))}</td></tr>"
                   for k, v in items)
    return f"{_TABLE}<tbody>{body}</tbody></table>"


def _block(title: str, *parts: str) -> str:
    return (f'<div class="roughbrdf-repr"><strong>{escape(title)}</strong>'
            + "".join(parts) + "</div>")


def _parameter_rows(model: Model) -> list[list[Any]]:
    return [[p.name, number(p.value), p.unit or "1",
             f"[{number(p.bounds[0])}, {number(p.bounds[1])}]", p.domain_text(), p.description]
            for p in model.parameters]


def _one_model(model: Model) -> str:
    parts = [f"<div>{escape(model.reference)}</div>" if model.reference else "",
             _table(["parameter", "value", "unit", "search bounds", "domain", "description"],
                    _parameter_rows(model))]
    if model.options:
        parts.append(_table(["option", "value"],
                            [[k, repr(v)] for k, v in model.options.items()]))
    return "".join(parts)


def model_html(model: Model) -> str:
    """The HTML of :meth:`Model._repr_html_ <roughbrdf.models.Model._repr_html_>`: name,
    reference, parameters and options (a sum: each component under its prefix).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> "lambertian_rho" in model_html(rb.model("lambertian") + rb.model("tr75"))
    True
    """
    comps = getattr(model, "components", None)
    if not comps:
        return _block(f"{model.name} model", _one_model(model))
    parts = []
    for comp, prefix in zip(comps, model.prefixes, strict=True):  # type: ignore[attr-defined]
        parts.append(f"<div><em>{escape(prefix)}*: {escape(comp.name)}</em></div>"
                     + _one_model(comp))
    names = " + ".join(c.name for c in comps)
    return _block(f"sum of models: {names}", *parts,
                  _table(["parameter of the sum", "value"],
                         [[k, number(v)] for k, v in model.params.items()]))


def measurement_html(meas: Measurement) -> str:
    """The HTML of :meth:`Measurement._repr_html_
    <roughbrdf.measurement.Measurement._repr_html_>`: samples, channels, quantity, incidences
    (degrees) and provenance.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> text = measurement_html(rb.Measurement([0.5, 0.5], [0.1, 0.2], [0.0, 0.0], [1.0, 2.0]))
    >>> "28.6479" in text   # 0.5 rad in degrees
    True
    """
    inc = np.degrees(meas.incidences()) if meas.n_samples else np.array([])
    shown = ", ".join(number(t, 6) for t in inc[:24]) + (" ..." if inc.size > 24 else "")
    meta = meas.meta
    facts: list[tuple[str, Any]] = [
        ("samples", meas.n_samples), ("channels", ", ".join(meas.channels)),
        ("quantity", str(getattr(meas.quantity, "value", meas.quantity))),
        (f"incidences ({inc.size}), deg", shown or "none")]
    if meas.mueller is not None:
        facts.append(("Mueller elements", f"{meas.mueller}, basis {meas.mueller_basis}"))
    if meas.polarization is not None:
        facts.append(("polarization", "per sample (gamma, radians)"))
    facts.append(("uncertainty", "given" if meas.uncertainty is not None else "none"))
    facts += [(k, meta[k]) for k in ("file", "format", "sample", "instrument", "date")
              if meta.get(k) is not None]
    return _block("Measurement", _facts(facts))


def _channel_rows(c: ChannelFit) -> list[list[Any]]:
    units = {p.name: p.unit for p in c.model.parameters}
    rows = []
    for name, val in c.params.items():
        se = c.stderr.get(name)
        state = ("fitted" if name in c.free else "fixed" if val is not None else "off")
        if name in c.at_bound:
            state = f"at the {c.at_bound[name]} bound ({c.limits.get(name, '')})"
        lo, hi = c.bounds.get(name, (None, None))
        rows.append([name, number(val), "" if se is None else number(se, 4),
                     units.get(name, "") or "1", state,
                     "" if lo is None else f"[{number(lo)}, {number(hi)}]"])
    if c.free_scale:
        rows.append(["scale K", number(c.scale), number(c.scale_stderr, 4), "1", "fitted", ""])
    return rows


def _channel_html(res: FitResult, i: int) -> str:
    c = res.channels[i]
    try:
        albedo = number(res.plausibility(i).max_albedo, 4)
    except (ValueError, ArithmeticError):  # a model that cannot be integrated: said, not raised
        albedo = "not computed"
    facts = [("success", c.success), ("message", c.message),
             ("TR75 sigma (r.m.s. of (Kx - f)/f)", number(c.sigma, 4)),
             ("r.m.s. log residual", number(c.rms_log, 4)),
             ("data points / variables", f"{c.n_points} / {c.n_varys}"),
             ("largest albedo (TIS) over incidence", albedo)]
    rows = _channel_rows(c)
    return (f"<div><em>channel {escape(str(c.channel))}</em></div>" + _facts(facts)
            + _table(["parameter", "value", "stderr", "unit", "state", "bounds"], rows))


def fit_html(res: FitResult) -> str:
    """The HTML of :meth:`FitResult._repr_html_ <roughbrdf.fitting.FitResult._repr_html_>`:
    the fit (model, input, loss, compared quantity) and each channel.

    Examples
    --------
    >>> import numpy as np, roughbrdf as rb
    >>> g = np.radians(np.mgrid[0:61:30, 0:81:20, 0:181:90].reshape(3, -1))
    >>> meas = rb.Measurement(*g, rb.model("lambertian", rho=0.3).brdf(*g))
    >>> res = rb.fit("lambertian", meas, starts=1, progress=False)
    >>> "0.3" in fit_html(res) and "stderr" in fit_html(res)
    True
    """
    facts = [("model", res.model_name), ("input", res.measurement.meta.get("file") or
                                         "a measurement made in Python"),
             ("loss", res.loss), ("compared with", f"model {res.compared}"),
             ("channels", len(res.channels)), ("success", res.success)]
    if res.aperture is not None:
        facts.append(("aperture half-angle, deg", number(math.degrees(res.aperture), 4)))
    return _block("Fit", _facts(facts),
                  *(_channel_html(res, i) for i in range(len(res.channels))))


# the low objects display through the registry (see the module docstring)
register_html("model", model_html)
register_html("measurement", measurement_html)
