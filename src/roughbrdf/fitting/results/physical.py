"""Search ranges beyond a parameter's physical range: which a fit used, and what to say.

A free scale that is not a reflectance keeps a domain of ``[0, inf)`` (data of unknown scale
may need it), but only part of it is physical: microfacet ``ks`` (one interface with
``F <= 1`` reflects at most what it receives at ``ks = 1``) and the legacy free lobe scales of
``coated(weights="free")``. Their default search range is the physical one
(microfacet ``[0, 1]``); a fit given a wider one (``bounds={"ks": (0, 20)}``) used a
*non-physical range*: :func:`non_physical` lists it for ``fit.json``
(``non_physical_range``) and :func:`report_lines` for the report (``docs/fitting.md``).

Examples
--------
>>> import roughbrdf as rb
>>> m = rb.model("microfacet")
>>> non_physical_ranges(m, {"alpha": (0.01, 2.0), "ks": (0.0, 20.0)})
{'ks': [0.0, 20.0]}
>>> non_physical_ranges(m, {"ks": (0.0, 1.0)})
{}
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ...models.base import Model, SumModel

__all__ = ["PHYSICAL_RANGES", "LIMIT_HINTS", "limit_hints", "non_physical",
           "non_physical_ranges", "physical_range", "report_lines"]

#: ``(model name, parameter) -> (low, high)``: the physical range of a free scale
PHYSICAL_RANGES: dict[tuple[str, str], tuple[float, float]] = {
    ("microfacet", "ks"): (0.0, 1.0),
    ("coated", "ks"): (0.0, 1.0), ("coated", "ks2"): (0.0, 1.0), ("coated", "ks3"): (0.0, 1.0),
}


#: ``(model name, parameter, side) -> what it says about the model`` when a fit ends there on
#: a search limit (``docs/fitting.md``, "Bounds"): clear coats and binders have n = 1.4-1.7; a
#: coated fit that needs the coat's n at its upper limit asks for more reflection than a
#: dielectric interface gives, the sign of metal flakes
LIMIT_HINTS: dict[tuple[str, str, str], str] = {
    ("coated", "n", "upper"): "a coat index this high is a sign of a wrong model (clear coats "
    "have n = 1.4-1.7): metal flakes? try the metallic-paint model coated-conductor "
    "(model auto compares it)",
    ("coated-conductor", "n", "upper"): "a coat index this high (clear coats have n = "
    "1.4-1.7) asks for more specular reflection than a coat gives: try "
    "coated-conductor(coat=false), flakes without a clear coat",
    ("trowbridge-reitz-1975", "n", "upper"): "an index this high is a sign of a wrong model for "
    "a paint: try model auto (it compares the metallic-paint model)",
}


def limit_hints(channel: Any) -> list[str]:
    """The report's hints for parameters that ended on a search limit (:data:`LIMIT_HINTS`).

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> import roughbrdf as rb
    >>> c = SimpleNamespace(model=rb.model("coated"), at_bound={"n": "upper"},
    ...                     limits={"n": "search-upper"})
    >>> limit_hints(c)[0].split(":")[0]
    '    HINT (n at its upper search limit)'
    """
    lines = []
    for name, side in getattr(channel, "at_bound", {}).items():
        if not str(channel.limits.get(name, "search")).startswith("search"):
            continue
        hint = LIMIT_HINTS.get((channel.model.name, name.split("[")[0], side))
        if hint:
            lines.append(f"    HINT ({name} at its {side} search limit): {hint}")
    return lines


def physical_range(model: Model, name: str) -> tuple[float, float] | None:
    """The physical range of ``model``'s parameter ``name`` (a sum: its prefixed name; a
    joint fit's ``name[channel]``: its stem), or None where the domain is all physical."""
    stem = name.split("[")[0]
    if isinstance(model, SumModel):
        for prefix, part in zip(model.prefixes, model.components, strict=True):
            if stem.startswith(prefix) and stem[len(prefix):] in part.param_names:
                return physical_range(part, stem[len(prefix):])
        return None
    return PHYSICAL_RANGES.get((model.name, stem))


def non_physical_ranges(model: Model, bounds: Mapping[str, tuple[float, float]]
                        ) -> dict[str, list[float]]:
    """``{name: [low, high]}`` of the search bounds that reach beyond the physical range."""
    out: dict[str, list[float]] = {}
    for name, (lo, hi) in bounds.items():
        phys = physical_range(model, name)
        # a bound outside the physical range by more than rounding
        if phys is not None and (hi > phys[1] * (1 + 1e-12) or lo < phys[0] - 1e-12):
            out[name] = [float(lo), float(hi)]
    return out


def non_physical(channel: Any) -> dict[str, list[float]]:
    """:func:`non_physical_ranges` of a :class:`~roughbrdf.fitting.results.result.ChannelFit` (its
    fitted model and search bounds): the ``non_physical_range`` entry of ``fit.json``."""
    return non_physical_ranges(channel.model, channel.bounds)


def report_lines(channel: Any) -> list[str]:
    """The report's note on a non-physical search range (none: [])."""
    ranges = non_physical(channel)
    if not ranges:
        return []
    names = ", ".join(f"{nm} in [{lo:g}, {hi:g}] (physical: "
                      f"[{physical_range(channel.model, nm)[0]:g}, "  # type: ignore[index]
                      f"{physical_range(channel.model, nm)[1]:g}])"  # type: ignore[index]
                      for nm, (lo, hi) in ranges.items())
    return [f"    NON-PHYSICAL RANGE: searched {names}:",
            "     the fitted model may reflect more light than it receives"]
