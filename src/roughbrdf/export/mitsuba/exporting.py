"""The exports: :func:`export_mitsuba`, :func:`to_mitsuba`, :func:`to_mitsuba_xml` and their
records (:class:`MitsubaExport`, :class:`TermExport`); a model, a fit or one of its channels,
and several channels as one RGB BSDF or one BSDF each (package notes,
:mod:`roughbrdf.export.mitsuba`, "Channels").
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...errors import ArgumentError
from ...models.base import Model, components
from .deviation import EXACT, Deviation, deviation_grid
from .emulation import mitsuba_values
from .mapping import Leaf, leaves_of, merge_channels, note_for, plugin_tree, why_not
from .stand_ins import describe, fit_closest
from .xml_writer import xml_text

__all__ = ["MitsubaExport", "TermExport", "export_mitsuba", "to_mitsuba", "to_mitsuba_xml",
           "xml_comments"]

#: a channel label naming a wavelength ("630nm"): RGB colours by wavelength
_WAVELENGTH = re.compile(r"^\s*(\d+(?:\.\d+)?)\s*nm\s*$", re.IGNORECASE)
#: statuses from the most to the least exact (MitsubaExport.status)
_RANK = {"exact": 0, "approximate": 1, "fitted": 2}


@dataclass(frozen=True)
class TermExport:
    """How one term of a model was exported.

    Attributes
    ----------
    term : str
        The term (the model's name; in a sum, its parameter prefix).
    plugins : tuple of str
        The Mitsuba plugins written for it.
    status : {"exact", "approximate", "fitted"}
        ``exact``: Mitsuba computes the model's formula (deviation <= :data:`EXACT`);
        ``approximate``: the parameters map one to one but Mitsuba's formula differs (its
        Beckmann ``G1``; TR75's missing shadowing); ``fitted``: the closest exactly mapped
        model was fitted to the term's values.
    note : str
        Why the status is what it is.
    deviation : Deviation
        Of the term's own export from the term.
    fitted : Model or None
        The fitted stand-in (``status == "fitted"``).
    """

    term: str
    plugins: tuple[str, ...]
    status: str
    note: str
    deviation: Deviation
    fitted: Model | None = None


@dataclass(frozen=True)
class MitsubaExport:
    """A Mitsuba 3 export (:func:`export_mitsuba`).

    Attributes
    ----------
    bsdf : dict
        The scene-description dict: one BSDF, or ``{channel: BSDF}`` (``rule="per-channel"``).
    rule : {"model", "channel", "rgb", "per-channel"}
        A model; one channel of a fit; three channels as one RGB BSDF; one BSDF per channel.
    terms : dict
        ``{channel label: (TermExport, ...)}`` (label ``""`` for a model).
    deviation : dict
        ``{channel label: Deviation}`` of the whole BSDF (its colour component, with ``rgb``).
    rgb : tuple of str or None
        The channels written as red, green, blue.
    theta_max : float
        Largest ``theta_i``, ``theta_r`` of the deviation grid (radians).
    grid : tuple of numpy.ndarray
        ``(theta_i, theta_r, phi)`` of the deviation grid (:func:`deviation_grid`), for
        checking the reported deviations with Mitsuba.
    notes : dict
        ``{channel label: [line, ...]}``: the record of ``allow_energy_gain=True`` for each
        model exported although it gains energy (written into the files, :func:`note_lines`).
    """

    bsdf: dict[str, Any]
    rule: str
    terms: dict[str, tuple[TermExport, ...]]
    deviation: dict[str, Deviation]
    rgb: tuple[str, str, str] | None
    theta_max: float
    grid: tuple[np.ndarray, np.ndarray, np.ndarray] = field(repr=False)
    notes: dict[str, list[str]] = field(default_factory=dict)

    def note_lines(self, label: str | None = None) -> list[str]:
        """The notes of channel ``label``, or of every channel (None)."""
        return [n for key, lines in self.notes.items() if label is None or key == label
                for n in lines]

    @property
    def status(self) -> str:
        """The least exact status of any term."""
        return max((t.status for ts in self.terms.values() for t in ts), key=_RANK.__getitem__)

    def xml(self, *, id: str | None = None, version: str | None = None) -> str:  # noqa: A002
        """The ``<bsdf>`` element (one per channel for ``rule="per-channel"``, with the
        channel labels as ids, prefixed ``id-`` when ``id`` is given).

        ``id`` sets the element's id; ``version="3.0.0"`` makes it a document of its own, which
        :func:`mitsuba.load_string` loads as the BSDF.
        """
        if self.rule != "per-channel":
            return xml_comments(self.note_lines()) + xml_text(self.bsdf, id, version)
        return "\n".join(xml_comments(self.note_lines(label))
                         + xml_text(b, f"{id}-{label}" if id else label, version)
                         for label, b in self.bsdf.items())

    def summary(self) -> str:
        """One line per term: status, plugins, deviation (r.m.s., max) and note."""
        lines = [f"Mitsuba 3 export ({self.rule}; deviation over theta_i, theta_r <= "
                 f"{math.degrees(self.theta_max):.0f} deg, unpolarized)"]
        for label, terms in self.terms.items():
            d = self.deviation[label]
            head = f"[{label}] " if label else ""
            lines.append(f"{head}whole BSDF: rms {d.rms:.2e}, max {d.max:.2e}")
            for t in terms:
                lines.append(f"  {t.term:<14} {t.status:<11} {'+'.join(t.plugins):<28} "
                             f"rms {t.deviation.rms:.2e} max {t.deviation.max:.2e}  {t.note}")
        return "\n".join(lines)


# --------------------------------------------------------------------------------------------
# models, fits and channels
# --------------------------------------------------------------------------------------------
def _export_term(m: Model, label: str, fit: bool, grid: tuple[np.ndarray, ...]
                 ) -> tuple[list[Leaf], TermExport]:
    """One term: its plugins (mapped, or fitted with ``fit``) and its record."""
    reasons = why_not(m)
    where = f"model {m.name!r}" + (f" (term {label!r})" if label != m.name else "")
    if reasons and not fit:
        raise ArgumentError("fit", f"{where} has no Mitsuba 3 counterpart: "
                            f"{'; '.join(reasons)}. The closest Mitsuba model fitted to its "
                            f"values can be exported instead (the export then reports the "
                            f"deviation)", fix=True)
    values = np.asarray(m.brdf(*grid), dtype=float)
    stand_in = None
    if reasons or (fit and m.name == "trowbridge-reitz-1975"):
        stand_in = fit_closest(m, grid, values)
        leaves = leaves_of(stand_in, where)
        why = "; ".join(reasons) or note_for(m, "approximate")
        note = f"{why}; fitted: {describe(stand_in)}"
    else:
        leaves = leaves_of(m, where)
    dev = Deviation.of(mitsuba_values(plugin_tree(leaves), *grid), values)
    if stand_in is not None:
        status = "fitted"
    else:
        status = "exact" if dev.max <= EXACT else "approximate"
        note = note_for(m, status)
    return leaves, TermExport(label, tuple(leaf.plugin for leaf in leaves), status, note, dev,
                              stand_in)


def _export_model(m: Model, fit: bool, grid: tuple[np.ndarray, ...]
                  ) -> tuple[list[Leaf], tuple[TermExport, ...]]:
    """Every term of ``m`` (the components of a sum, labelled by their prefixes)."""
    parts = components(m)
    labels = [p[:-1] for p in m.prefixes] if len(parts) > 1 else [m.name]  # type: ignore[attr-defined]
    leaves: list[Leaf] = []
    terms = []
    for part, label in zip(parts, labels, strict=True):
        more, term = _export_term(part, label, fit, grid)
        leaves += more
        terms.append(term)
    return leaves, tuple(terms)


def _models_of(source: Any, channel: Any) -> tuple[dict[str, Model], str]:
    """``{label: model}`` and the rule (``model``, ``channel`` or ``multi``)."""
    if isinstance(source, Model):
        if channel is not None:
            raise ArgumentError("channel", "applies to a fit with channels, not to a model",
                                value=channel)
        return {"": source}, "model"
    if isinstance(source, Mapping) and source and all(isinstance(m, Model)
                                                      for m in source.values()):
        # {channel: model}, e.g. roughbrdf.fitting.results.fit_json.fitted_models(fit folder)
        models = {str(k): m for k, m in source.items()}
        if channel is None:
            return models, ("channel" if len(models) == 1 else "multi")
        labels = list(models)
        key = str(channel) if str(channel) in models else (
            labels[int(channel)] if str(channel).lstrip("-").isdigit()
            and -len(labels) <= int(channel) < len(labels) else None)
        if key is None:
            raise ArgumentError("channel", f"no such channel; the fit has {labels}",
                                value=channel)
        return {key: models[key]}, "channel"
    if isinstance(getattr(source, "model", None), Model) and hasattr(source, "channel"):
        if channel is not None:  # one channel's result (res[label])
            raise ArgumentError("channel", "applies to a whole fit, not to one channel's "
                                "result", value=channel)
        return {source.channel: source.model}, "channel"
    chans = getattr(source, "channels", None)
    if not isinstance(chans, list) or not chans:
        raise TypeError(f"expected a roughbrdf Model or FitResult (or one of its channels), "
                        f"got {type(source).__name__}")
    if channel is not None:
        try:
            c = source[channel]
        except (KeyError, IndexError, TypeError):
            raise ArgumentError("channel", f"no such channel; the fit has "
                                f"{[c.channel for c in chans]}", value=channel) from None
        return {c.channel: c.model}, "channel"
    return {c.channel: c.model for c in chans}, ("channel" if len(chans) == 1 else "multi")


def _rgb_order(labels: list[str], rgb: Any) -> tuple[str, str, str] | None:
    """The channels written as red, green, blue (package notes, "Channels"); None: none."""
    if rgb is False:
        return None
    if rgb is not None and rgb is not True:
        if isinstance(rgb, str) or len(rgb) != 3:
            raise ArgumentError("rgb", "must be three channels (red, green, blue) or False",
                                value=rgb)
        out = []
        for x in rgb:
            if isinstance(x, int) and not isinstance(x, bool) and -len(labels) <= x < len(labels):
                out.append(labels[x])
            elif x in labels:
                out.append(x)
            else:
                raise ArgumentError("rgb", f"no channel {x!r}; the fit has {labels}", value=rgb)
        if len(set(out)) != 3:
            raise ArgumentError("rgb", "names a channel twice", value=rgb)
        return out[0], out[1], out[2]
    if len(labels) != 3:
        return None
    found = [_WAVELENGTH.match(c) for c in labels]
    if all(found):
        waves = [float(f.group(1)) for f in found if f]
        if len(set(waves)) == 3:
            r, g, b = sorted(labels, key=lambda c: -waves[labels.index(c)])
            return r, g, b
    names = {"r": 0, "red": 0, "g": 1, "green": 1, "b": 2, "blue": 2}
    pos = [names.get(c.strip().lower()) for c in labels]
    if sorted(p for p in pos if p is not None) == [0, 1, 2]:
        r, g, b = (labels[pos.index(i)] for i in range(3))
        return r, g, b
    return None


def xml_comments(lines: list[str]) -> str:
    """``<!-- line -->`` per line, each followed by a line break ("--" is not allowed in an
    XML comment: spaced out)."""
    return "".join(f"<!-- {' '.join(n.replace('--', '- -').split())} -->\n" for n in lines)


def export_mitsuba(source: Any, *, channel: int | str | None = None, rgb: Any = None,
                   fit: bool = False, theta_max: float = math.radians(80.0),
                   allow_energy_gain: bool = False) -> MitsubaExport:
    """Export a model or a fit to Mitsuba 3, with a record of how every term was mapped.

    Parameters
    ----------
    source : Model, FitResult or mapping
        A model (sums allowed), a fit (its fitted models), or ``{channel: model}`` (e.g.
        :func:`roughbrdf.fitting.results.fit_json.fitted_models` of a saved fit).
    channel : int or str, optional
        One channel of a fit (label or position).
    rgb : None, False or (red, green, blue)
        Several channels (package notes, "Channels"): ``None`` writes one RGB BSDF where the
        channels allow it (colours by wavelength or R/G/B labels), else one per channel;
        ``(red, green, blue)`` channel labels or positions insist on one RGB BSDF (raises
        ``ValueError`` where the channels differ in more than colours); ``False``: one BSDF
        per channel. (``True`` is ``None``.)
    fit : bool
        Export what does not map as the closest mapped model fitted to its values (and TR75
        as a fitted GGX lobe instead of its one-to-one approximate mapping); without it such
        a model raises ``ValueError`` with the reason.
    theta_max : float
        Largest ``theta_i``, ``theta_r`` (radians) of the deviation grid and the fits.
    allow_energy_gain : bool
        Export a model that reflects more than it receives (albedo above ``1 + 1e-3`` at an
        incidence of 0, 5, ... 85, 89 deg; the roughbrdf model's albedo, not the mapped
        BSDF's), recorded in :attr:`MitsubaExport.notes`; by default refused with an
        :class:`~roughbrdf.errors.ArgumentError` naming the albedo and the incidence
        (:func:`~roughbrdf.fitting.results.plausibility.refuse_energy_gain`).

    Returns
    -------
    MitsubaExport

    Examples
    --------
    >>> import roughbrdf as rb
    >>> from roughbrdf.export.mitsuba import export_mitsuba
    >>> tr75 = rb.model("tr75", e=0.3, n=1.5, k=0.0, rho_L=0.2)  # albedo 1.98 at 89 deg
    >>> e = export_mitsuba(tr75, allow_energy_gain=True)
    >>> e.status, e.terms[""][0].plugins
    ('approximate', ('roughconductor', 'diffuse'))
    >>> e.bsdf["bsdf_1"]["reflectance"]        # rho_L, times 2 in a blend of weight 0.5
    0.4
    """
    if not isinstance(fit, bool):
        raise ArgumentError("fit", "must be True or False", value=fit)
    from ...fitting.results.plausibility import refuse_energy_gain

    grid = deviation_grid(theta_max)
    models, rule = _models_of(source, channel)
    if rule != "multi" and rgb not in (None, True, False):
        raise ArgumentError("rgb", "needs a fit with three channels or more (and no channel=)",
                            value=rgb)
    order = _rgb_order(list(models), rgb) if rule == "multi" else None
    if order is not None and rgb not in (None, True):
        models = {label: models[label] for label in order}  # explicit: those three only
    per = {label: _export_model(m, fit, grid) for label, m in models.items()}
    # after the mapping: a model Mitsuba cannot express is refused for that reason first
    notes = {label: refuse_energy_gain({label: m}, allow_energy_gain)
             for label, m in models.items()}
    merged = merge_channels([per[label][0] for label in order]) if order is not None else None
    if isinstance(merged, str) and rgb not in (None, True):
        raise ValueError(f"rgb={rgb!r}: the channels cannot be one RGB BSDF: {merged}; pass "
                         f"rgb=False for one BSDF per channel")
    if isinstance(merged, list) and order is not None:
        rule, bsdf = "rgb", plugin_tree(merged)
        values = mitsuba_values(bsdf, *grid)
        deviation = {label: Deviation.of(values[i] if values.ndim == 2 else values,
                                         np.asarray(models[label].brdf(*grid)))
                     for i, label in enumerate(order)}
    else:
        if rule == "multi":
            rule, order = "per-channel", None
            bsdf = {label: plugin_tree(per[label][0]) for label in models}
        else:
            bsdf = plugin_tree(next(iter(per.values()))[0])
        deviation = {label: Deviation.of(
            mitsuba_values(bsdf[label] if rule == "per-channel" else bsdf, *grid),
            np.asarray(m.brdf(*grid))) for label, m in models.items()}
    return MitsubaExport(bsdf=bsdf, rule=rule, terms={k: v[1] for k, v in per.items()},
                         deviation=deviation, rgb=order, theta_max=float(theta_max), grid=grid,
                         notes={k: v for k, v in notes.items() if v})


def to_mitsuba(source: Any, *, channel: int | str | None = None, rgb: Any = None,
               fit: bool = False, theta_max: float = math.radians(80.0),
               allow_energy_gain: bool = False) -> dict[str, Any]:
    """A model or fit as a Mitsuba 3 scene-description dict (:func:`mitsuba.load_dict`).

    One BSDF, or ``{channel: BSDF}`` for a fit whose channels are not one RGB BSDF (module
    notes). Arguments as :func:`export_mitsuba`, which also says how each term was mapped and
    how far Mitsuba's values are from the model's.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> from roughbrdf.export.mitsuba import to_mitsuba
    >>> to_mitsuba(rb.model("lambertian", rho=0.25))
    {'type': 'diffuse', 'reflectance': 0.25}
    >>> m = rb.model("microfacet", distribution="ggx", alpha=0.2, n=0.2, k=3.0, ks=1.0,
    ...              shadowing="smith-separable")
    >>> to_mitsuba(m)
    {'type': 'roughconductor', 'distribution': 'ggx', 'alpha': 0.2, 'eta': 0.2, 'k': 3.0,
     'specular_reflectance': 1.0}
    >>> to_mitsuba(rb.model("microfacet", shadowing="smith-height-correlated"))
    Traceback (most recent call last):
    ...
    roughbrdf.errors.ArgumentError: model 'microfacet' has no Mitsuba 3 counterpart: ...fit=True
    """
    return export_mitsuba(source, channel=channel, rgb=rgb, fit=fit, theta_max=theta_max,
                          allow_energy_gain=allow_energy_gain).bsdf


def to_mitsuba_xml(source: Any, *, channel: int | str | None = None, rgb: Any = None,
                   fit: bool = False, theta_max: float = math.radians(80.0),
                   id: str | None = None, version: str | None = None,  # noqa: A002
                   allow_energy_gain: bool = False) -> str:
    """A model or fit as an XML ``<bsdf>`` element of a Mitsuba 3 scene file.

    Arguments as :func:`export_mitsuba`; ``id`` names the element (per-channel exports use
    the channel labels), ``version="3.0.0"`` makes it a document :func:`mitsuba.load_string`
    loads on its own. Text is escaped by :mod:`xml.etree.ElementTree`.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> from roughbrdf.export.mitsuba import to_mitsuba_xml
    >>> print(to_mitsuba_xml(rb.model("lambertian", rho=0.5), id="paint"))
    <bsdf type="diffuse" id="paint">
      <float name="reflectance" value="0.5" />
    </bsdf>
    """
    e = export_mitsuba(source, channel=channel, rgb=rgb, fit=fit, theta_max=theta_max,
                       allow_energy_gain=allow_energy_gain)
    return e.xml(id=id, version=version)
