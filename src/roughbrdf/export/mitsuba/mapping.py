"""Which roughbrdf model maps to which Mitsuba 3 plugin, and why the others are refused.

The mappings table, the notes on Beckmann, TR75 and sums, and the list of what does not map
are in the package notes (:mod:`roughbrdf.export.mitsuba`). Here: :func:`why_not` (the
refusals, with their reasons), :func:`leaves_of` (the plugins of a model that maps, as
:class:`Leaf` objects whose colour properties hold one value per channel), :func:`plugin_tree`
(a sum as a ``blendbsdf`` chain) and :func:`merge_channels` (three channels as one RGB BSDF).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ... import distributions as dist
from ...diffuse import rough_interface
from ...models.base import Model, components
from .emulation import ALPHA_MIN

__all__ = ["MITSUBA_DISTRIBUTIONS", "Leaf", "leaves_of", "merge_channels", "note_for",
           "plugin_tree", "why_not"]

#: the roughbrdf distribution codes Mitsuba's microfacet plugins have, and their names there
MITSUBA_DISTRIBUTIONS = {dist.TR: "ggx", dist.BECKMANN: "beckmann"}


# --------------------------------------------------------------------------------------------
# Mitsuba plugins as leaves: parameters Mitsuba takes as colours are arrays over channels
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Leaf:
    """One Mitsuba plugin: ``plugin``, its scalar properties and its colour properties (one
    value per channel); ``f_int``: a ``roughplastic``'s internal reflectance (for scaling)."""

    plugin: str
    scalars: tuple[tuple[str, Any], ...]
    colours: tuple[tuple[str, np.ndarray], ...]
    f_int: float = 0.0

    def scaled(self, c: float) -> dict[str, Any]:
        """The plugin's dict with its value multiplied by ``c`` (package notes, "Sums")."""
        out: dict[str, Any] = {"type": self.plugin, **dict(self.scalars)}
        for name, v in self.colours:
            if name in ("reflectance", "specular_reflectance"):
                v = v * c
            elif name == "diffuse_reflectance":
                v = c * v / (1.0 + (c - 1.0) * v * self.f_int)
            out[name] = _colour(v)
        return out


def _arr(x: float) -> np.ndarray:
    return np.array([float(x)])


def _colour(v: np.ndarray) -> Any:
    """A float, or an ``srgb`` colour (``unbounded`` where a value exceeds 1)."""
    if np.all(v == v[0]):
        return float(v[0])
    out: dict[str, Any] = {"type": "srgb", "color": [float(x) for x in v]}
    if np.any(v > 1.0):
        out["unbounded"] = True  # Mitsuba refuses RGB reflectances above 1 without it
    return out


def _check_alpha(alpha: float, where: str) -> float:
    if alpha < ALPHA_MIN:
        raise ValueError(f"{where}: alpha = {alpha!r} is below Mitsuba's smallest roughness "
                         f"{ALPHA_MIN} (Mitsuba clamps it there); no Mitsuba model matches")
    return float(alpha)


def _conductor(dcode: int, alpha: float, n: float | None, k: float | None, ks: float,
               where: str) -> Leaf:
    # n = None: F = 1, Mitsuba's material "none" (eta = 0, k = 1)
    eta, kk = (0.0, 1.0) if n is None else (float(n), float(k or 0.0))
    return Leaf("roughconductor", (("distribution", MITSUBA_DISTRIBUTIONS[dcode]),
                                    ("alpha", _check_alpha(alpha, where))),
                 (("eta", _arr(eta)), ("k", _arr(kk)), ("specular_reflectance", _arr(ks))))


def _plastic(dcode: int, alpha: float, n: float, rho: float, ks: float, where: str,
             c: float = 1.0) -> Leaf:
    """A ``roughplastic``; ``c`` scales its substrate term (nonlinear diffuse reflectance
    ``c rho/(1 + (c - 1) rho F_int)``, as :meth:`Leaf.scaled`)."""
    f_int = rough_interface(alpha, n, dist.get(MITSUBA_DISTRIBUTIONS[dcode]).name, g1="mitsuba")[1]
    rho_c = c * rho / (1.0 + (c - 1.0) * rho * f_int)
    return Leaf("roughplastic", (("distribution", MITSUBA_DISTRIBUTIONS[dcode]),
                                  ("alpha", _check_alpha(alpha, where)), ("int_ior", float(n)),
                                  ("ext_ior", 1.0), ("nonlinear", True)),
                 (("diffuse_reflectance", _arr(rho_c)), ("specular_reflectance", _arr(ks))),
                 f_int)


def _diffuse(rho: float) -> Leaf:
    return Leaf("diffuse", (), (("reflectance", _arr(rho)),))



# --------------------------------------------------------------------------------------------
# which models map, and how
# --------------------------------------------------------------------------------------------
def why_not(m: Model) -> list[str]:
    """Why ``m`` has no exact (or one-to-one approximate) Mitsuba counterpart; [] if it has."""
    name, o, v = m.name, m.options, m.params
    if name in ("lambertian", "trowbridge-reitz-1975"):
        return []
    if name == "oren-nayar":
        return [] if v["sigma"] == 0 else [
            "Mitsuba 3 has no Oren-Nayar BSDF ('diffuse' is Lambertian; sigma = 0 maps)"]
    if name == "microfacet":
        out = []
        if dist.get(o["distribution"]).code not in MITSUBA_DISTRIBUTIONS:
            out.append(f"distribution {o['distribution']!r} has no Mitsuba counterpart "
                       f"(roughconductor: 'ggx' = trowbridge-reitz, 'beckmann')")
        if o["shadowing"] != "smith-separable":
            out.append(f"shadowing {o['shadowing']!r}: Mitsuba's roughconductor applies the "
                       f"separable Smith G (shadowing='smith-separable')")
        return out
    if name == "coated":
        return _why_not_coated(o, v)
    if name == "torrance-sparrow-1967":
        return ["TS67's V-groove shadowing and gaussian-in-angle distribution have no "
                "Mitsuba counterpart"]
    if name == "renhorn-boreman-2008":
        return ["RB08's surface, bulk and retro lobes (its V and Vm shadowing, effective "
                "Fresnel) have no Mitsuba counterpart"]
    return [f"no Mitsuba mapping is defined for model {name!r}"]


def _why_not_coated(o: Any, v: Any) -> list[str]:
    out = []
    if o["shadowing"] != "smith-separable":
        out.append(f"shadowing {o['shadowing']!r}: roughplastic applies the separable Smith G")
    if o.get("interface", "smooth") != "rough":
        out.append("interface='smooth': the substrate term crosses a smooth interface, "
                   "roughplastic's the rough one (the coated model's interface='rough' is "
                   "roughplastic's)")
    if o["shadow_diffuse"]:
        out.append("shadow_diffuse=True: roughplastic does not mask or shadow its substrate "
                   "term (shadow_diffuse=False)")
    if o["diffuse"] == "oren-nayar" and v["sigma"] != 0:
        out.append("diffuse='oren-nayar': roughplastic's substrate is Lambertian")
    return out


def leaves_of(m: Model, where: str) -> list[Leaf]:
    """The Mitsuba plugins of a model that maps (:func:`why_not` is empty; sums too)."""
    parts = components(m)
    if len(parts) > 1:
        return [leaf for part in parts for leaf in leaves_of(part, where)]
    v, o = m.params, m.options
    if m.name in ("lambertian", "oren-nayar"):
        return [_diffuse(v["rho"])]
    if m.name == "microfacet":
        return [_conductor(dist.get(o["distribution"]).code, v["alpha"], v["n"], v["k"],
                           v["ks"], where)]
    if m.name == "trowbridge-reitz-1975":  # TR75's distribution is GGX with alpha = e
        return [_conductor(dist.TR, v["e"], v["n"], v["k"], 1.0, where), _diffuse(v["rho_L"])]
    d = dist.get(o["distribution"]).code
    lobes = m.specular_lobes()  # type: ignore[attr-defined]
    if o.get("weights") == "free" or len(lobes) == 1:
        # the substrate sees lobe 1's interface: roughplastic (specular_reflectance = its
        # weight, 1 for one lobe) + a conductor of the coating's index per extra lobe
        out = [_plastic(d, v["alpha"], v["n"], v["rho"], lobes[0][0], where)]
        out += [_conductor(d, a, v["n"], 0.0, w, where) for w, a in lobes[1:]]
        return out
    # several lobes of one interface (weights sum to 1): one roughplastic per lobe, its
    # specular part and its substrate term scaled by the lobe's weight; the model's substrate
    # sees the lobes' mixed tables instead (approximate, note_for)
    return [_plastic(d, a, v["n"], v["rho"], w, where, c=w) for w, a in lobes]


def note_for(m: Model, status: str) -> str:
    beckmann = m.options.get("distribution") == "beckmann"
    if m.name == "coated" and m.options["lobes"] > 1 and m.options.get("weights") != "free" \
            and status == "approximate":
        return ("one roughplastic per lobe, blended by weight: the model's substrate sees the "
                "lobes' mixed rough interface, each roughplastic's its own lobe's")
    if m.name == "trowbridge-reitz-1975":
        return (f"TR75 has {'V-groove' if m.options['shadowing'] == 'v-groove' else 'no'} "
                f"shadowing; roughconductor (GGX, alpha = e) applies Smith's separable G")
    if beckmann and status == "approximate":
        return "Mitsuba's Beckmann G1 is a rational approximation (within 0.35 %) of Smith's"
    if beckmann:
        return "same formula (Mitsuba's Beckmann G1 approximation within 5e-5 here)"
    return "same formula"


def plugin_tree(leaves: Sequence[Leaf]) -> dict[str, Any]:
    """One plugin, or the ``blendbsdf`` chain of the package notes ("Sums")."""
    n = len(leaves)
    node = leaves[-1].scaled(float(n))
    for j in range(n - 2, -1, -1):
        w = (n - j - 1) / (n - j)
        node = {"type": "blendbsdf", "weight": w, "bsdf_0": leaves[j].scaled(float(n)),
                "bsdf_1": node}
    return node


def merge_channels(per: Sequence[Sequence[Leaf]]) -> list[Leaf] | str:
    """The channels' plugins with their colours stacked, or why they cannot be one BSDF."""
    first = per[0]
    if any(len(p) != len(first) for p in per):
        return "the channels' exports have different parts"
    out = []
    for i, leaf in enumerate(first):
        same = [p[i] for p in per]
        for other in same:
            if other.plugin != leaf.plugin:
                return f"the channels export different plugins ({leaf.plugin}, {other.plugin})"
            for (name, a), (_, b) in zip(leaf.scalars, other.scalars, strict=True):
                if a != b:
                    return (f"{leaf.plugin} {name!r} differs between channels ({a!r}, {b!r}); "
                            f"Mitsuba takes it as one number")
        colours = tuple((name, np.concatenate([dict(o.colours)[name] for o in same]))
                        for name, _ in leaf.colours)
        out.append(Leaf(leaf.plugin, leaf.scalars, colours, leaf.f_int))
    return out
