"""Mitsuba 3 export: a model or a fit as a scene-description dict and an XML ``<bsdf>``.

:func:`to_mitsuba` returns the dict :func:`mitsuba.load_dict` takes, :func:`to_mitsuba_xml` the
``<bsdf>`` element of a scene file, and :func:`export_mitsuba` both with a record of how each
term was mapped (:class:`MitsubaExport`). Targets Mitsuba 3.9's RGB variants (``scalar_rgb``,
``llvm_ad_rgb``, ...); spectral parameters are constant over wavelength. Exports are for
**unpolarized** light: the models are evaluated unpolarized, and Mitsuba's unpolarized
variants never see the polarization of TR75 Eq. 24.

Mappings (Mitsuba's ``eval()`` returns ``f_r cos(theta_o)``; "exact" means the same formula,
checked with Mitsuba itself to 1e-4 relative at random geometries in
``tests/test_export_mitsuba.py``; Mitsuba's float32 arithmetic limits the agreement to a few
1e-6, 3e-5 next to the critical angle of a dielectric with ``n < 1``)

================================  ==========================================================
roughbrdf                         Mitsuba 3
================================  ==========================================================
``lambertian`` ``rho``            ``diffuse``, ``reflectance = rho``
``microfacet`` GGX/Beckmann,      ``roughconductor``, ``distribution`` ``ggx``/``beckmann``,
``smith-separable``, ``n``, ``k``, ``alpha``, ``eta = n``, ``k``, ``specular_reflectance = ks``
``ks`` (``n=None``: F = 1)        (``eta = 0``, ``k = 1``: Mitsuba's ``material="none"``, F = 1)
``coated``, ``smith-separable``,  ``roughplastic`` (``int_ior = n``, ``ext_ior = 1``,
``shadow_diffuse=False``,         ``diffuse_reflectance = rho``, ``nonlinear = true``,
``interface="rough"``             ``specular_reflectance = ks``, ``alpha``); lobes 2 and 3 are
                                  ``roughconductor`` lobes (``eta = n``, ``k = 0``) blended in
``trowbridge-reitz-1975``         ``roughconductor`` GGX with ``alpha = e`` + ``diffuse``
                                  ``rho_L``: *approximate*, see below
sums ``m1 + m2 + ...``            nested ``blendbsdf`` (below)
``oren-nayar`` with ``sigma = 0`` ``diffuse``
================================  ==========================================================

* **Beckmann.** Mitsuba's Smith ``G1`` for Beckmann is a rational approximation (within
  0.35 %, 1 above ``a = 1.6``) of the exact ``G1`` the library uses. The mapping is exact to
  :data:`EXACT` where that makes no difference: ``alpha`` up to about 0.07 for
  ``theta <= 80 deg``. Beyond, the export is *approximate* and reports its deviation (0.16 %
  at ``alpha = 0.08``, about 0.6 % from 0.2 on).
* **TR75** has no shadowing (or TS67's V-groove with ``shadowing="v-groove"``), while
  ``roughconductor`` always applies the separable Smith ``G`` of its distribution. The
  export keeps TR75's distribution (GGX, ``alpha = e``), Fresnel factor and Lambertian part
  and so adds Smith's ``G``; it is *approximate*, with the deviation that ``G`` makes (large
  near grazing: ``G`` is 0.45 at ``theta_i = theta_r = 80 deg`` for ``e = 0.3``). With
  ``fit=True`` the GGX lobe and the diffuse part are fitted instead (*fitted*).
* **Sums.** ``blendbsdf`` gives ``(1 - w) bsdf_0 + w bsdf_1``. A sum of ``N`` parts becomes the
  chain ``blend(w_1, N part_1, blend(w_2, N part_2, ...))`` with ``w_j = (N - j)/(N - j + 1)``:
  every part is scaled by ``N`` through its linear reflectance parameters (``reflectance``,
  ``specular_reflectance``; for ``roughplastic`` with ``nonlinear`` the diffuse reflectance
  ``c rho/(1 + (c - 1) rho F_int)``, which scales its substrate term by exactly ``c``).
  Mitsuba does not clamp these (colours above 1 are written as ``srgb`` with
  ``unbounded=true``).

What does not map -- TS67 (V-groove shadowing, gaussian-in-angle distribution), RB08,
``microfacet`` with another distribution or shadowing (height-correlated Smith, V-groove,
none), ``oren-nayar`` with ``sigma > 0`` and ``coated`` otherwise (smooth interface, diffuse
shadowing, Oren-Nayar substrate, height-correlated Smith) -- raises ``ValueError`` naming the
model, the option and the reason; with ``fit=True`` it is replaced by the closest exactly
mapped model, fitted with :func:`roughbrdf.fit` to the model's values on
:func:`deviation_grid` (least squares of the relative deviation below), and the export
reports the deviation (*fitted*). The stand-ins: a separable-Smith ``microfacet`` lobe with
the model's index (Beckmann for TS67 and other Gaussian-like distributions, GGX otherwise)
plus a ``lambertian`` part for TS67, TR75 and RB08; ``lambertian`` for Oren-Nayar; ``coated``
with the rough interface, no diffuse shadowing and separable Smith for ``coated``.

Every export reports its deviation from the model, ``|f_Mitsuba - f|/f`` (r.m.s. and maximum)
on :func:`deviation_grid` (``theta_i, theta_r <= theta_max``, 80 deg by default), with
``f_Mitsuba`` from :func:`mitsuba_values`, a float64 transcription of Mitsuba 3.9's ``eval`` for
the plugins written here (including its Beckmann ``G1``, its ``roughplastic`` tables and its
``D cos theta_h <= 1e-20 -> 0`` cut-off; values below :data:`FLOOR` or a millionth of the
model's largest count as absolute, :class:`Deviation`).

**Channels** (a :class:`~roughbrdf.fitting.FitResult` with several). ``channel=`` exports one.
Otherwise, when the channels' exports differ only in parameters Mitsuba takes as colours
(``reflectance``, ``diffuse_reflectance``, ``specular_reflectance``, a conductor's ``eta``
and ``k`` -- what a joint fit with the default shared parameters gives: one roughness, one
coating index), there are three channels and their colours are known, the export is **one
BSDF with RGB values**; the channel -> colour assignment is ``rgb=(red, green, blue)`` (channel
labels or positions) or, by default, by wavelength (labels like ``"630nm"``: longest red,
shortest blue) or by ``R``/``G``/``B`` labels. Otherwise it is **one BSDF per channel**:
``{label: bsdf}`` (XML: one ``<bsdf id="label">`` each); ``rgb=False`` forces this.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from .. import distributions as dist
from .. import shadowing as shd
from ..diffuse import ROUGH_TABLE_SIZE, rough_interface
from ..errors import ArgumentError
from ..geometry import theta_d, theta_h
from ..models.base import Model, components
from ..quantity import Quantity

__all__ = ["EXACT", "FLOOR", "Deviation", "MitsubaExport", "TermExport", "deviation_grid",
           "export_mitsuba", "mitsuba_values", "to_mitsuba", "to_mitsuba_xml", "xml_text"]

#: largest deviation from the model (on :func:`deviation_grid`) of a mapping called "exact":
#: half of the 1e-4 the tests check with Mitsuba, the other half for its float32 arithmetic
EXACT = 5e-5
#: BRDF values (sr^-1) below which deviations count as absolute, not relative: Mitsuba sets
#: ``D`` to 0 where ``D cos(theta_h) <= 1e-20``, which removes BRDF values up to ~5e-19 for
#: ``theta <= 80 deg`` (far tails of narrow Beckmann lobes); 1e-12 keeps that below 1e-6
FLOOR = 1e-12
#: ... and values below this fraction of the model's largest value on the grid: where a
#: narrow lobe's tail underflows to 0, any other lobe shape is infinitely far in relative terms
PEAK_FLOOR = 1e-6
#: Mitsuba clamps every microfacet roughness to at least 1e-4 (``MicrofacetDistribution``)
ALPHA_MIN = 1e-4

_MI_DIST = {dist.TR: "ggx", dist.BECKMANN: "beckmann"}
_WAVELENGTH = re.compile(r"^\s*(\d+(?:\.\d+)?)\s*nm\s*$", re.IGNORECASE)
_RANK = {"exact": 0, "approximate": 1, "fitted": 2}


# --------------------------------------------------------------------------------------------
# result types
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Deviation:
    """Relative deviation ``|f_Mitsuba - f|/max(f, floor)`` of an export from its model;
    ``floor = max(FLOOR, PEAK_FLOOR max(f))`` (:data:`FLOOR`, :data:`PEAK_FLOOR`).

    Attributes
    ----------
    rms, max : float
        Root mean square and maximum over the samples (every channel).
    points : int
        Number of geometries (:func:`deviation_grid`).
    """

    rms: float
    max: float
    points: int

    @classmethod
    def of(cls, mitsuba: np.ndarray, model: np.ndarray) -> Deviation:
        """From Mitsuba's values and the model's (same shape)."""
        floor = max(FLOOR, PEAK_FLOOR * float(np.max(np.abs(model))))
        rel = np.abs(mitsuba - model) / np.maximum(np.abs(model), floor)
        return cls(float(np.sqrt(np.mean(rel * rel))), float(rel.max()), int(model.shape[-1]))


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
    """

    bsdf: dict[str, Any]
    rule: str
    terms: dict[str, tuple[TermExport, ...]]
    deviation: dict[str, Deviation]
    rgb: tuple[str, str, str] | None
    theta_max: float
    grid: tuple[np.ndarray, np.ndarray, np.ndarray] = field(repr=False)

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
            return xml_text(self.bsdf, id, version)
        return "\n".join(xml_text(b, f"{id}-{label}" if id else label, version)
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
# Mitsuba plugins as leaves: parameters Mitsuba takes as colours are arrays over channels
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Leaf:
    """One Mitsuba plugin: ``plugin``, its scalar properties and its colour properties (one
    value per channel); ``f_int``: a ``roughplastic``'s internal reflectance (for scaling)."""

    plugin: str
    scalars: tuple[tuple[str, Any], ...]
    colours: tuple[tuple[str, np.ndarray], ...]
    f_int: float = 0.0

    def scaled(self, c: float) -> dict[str, Any]:
        """The plugin's dict with its value multiplied by ``c`` (module notes, "Sums")."""
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
               where: str) -> _Leaf:
    # n = None: F = 1, Mitsuba's material "none" (eta = 0, k = 1)
    eta, kk = (0.0, 1.0) if n is None else (float(n), float(k or 0.0))
    return _Leaf("roughconductor", (("distribution", _MI_DIST[dcode]),
                                    ("alpha", _check_alpha(alpha, where))),
                 (("eta", _arr(eta)), ("k", _arr(kk)), ("specular_reflectance", _arr(ks))))


def _plastic(dcode: int, alpha: float, n: float, rho: float, ks: float, where: str) -> _Leaf:
    f_int = rough_interface(alpha, n, dist.get(_MI_DIST[dcode]).name, g1="mitsuba")[1]
    return _Leaf("roughplastic", (("distribution", _MI_DIST[dcode]),
                                  ("alpha", _check_alpha(alpha, where)), ("int_ior", float(n)),
                                  ("ext_ior", 1.0), ("nonlinear", True)),
                 (("diffuse_reflectance", _arr(rho)), ("specular_reflectance", _arr(ks))),
                 f_int)


def _diffuse(rho: float) -> _Leaf:
    return _Leaf("diffuse", (), (("reflectance", _arr(rho)),))


# --------------------------------------------------------------------------------------------
# which models map, and how
# --------------------------------------------------------------------------------------------
def _why_not(m: Model) -> list[str]:
    """Why ``m`` has no exact (or one-to-one approximate) Mitsuba counterpart; [] if it has."""
    name, o, v = m.name, m.options, m.params
    if name in ("lambertian", "trowbridge-reitz-1975"):
        return []
    if name == "oren-nayar":
        return [] if v["sigma"] == 0 else [
            "Mitsuba 3 has no Oren-Nayar BSDF ('diffuse' is Lambertian; sigma = 0 maps)"]
    if name == "microfacet":
        out = []
        if dist.get(o["distribution"]).code not in _MI_DIST:
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


def _leaves(m: Model, where: str) -> list[_Leaf]:
    """The Mitsuba plugins of a model that maps (:func:`_why_not` is empty; sums too)."""
    parts = components(m)
    if len(parts) > 1:
        return [leaf for part in parts for leaf in _leaves(part, where)]
    v, o = m.params, m.options
    if m.name in ("lambertian", "oren-nayar"):
        return [_diffuse(v["rho"])]
    if m.name == "microfacet":
        return [_conductor(dist.get(o["distribution"]).code, v["alpha"], v["n"], v["k"],
                           v["ks"], where)]
    if m.name == "trowbridge-reitz-1975":  # TR75's distribution is GGX with alpha = e
        return [_conductor(dist.TR, v["e"], v["n"], v["k"], 1.0, where), _diffuse(v["rho_L"])]
    d = dist.get(o["distribution"]).code  # coated: roughplastic + a conductor per extra lobe
    out = [_plastic(d, v["alpha"], v["n"], v["rho"], v["ks"], where)]
    for j in range(2, o["lobes"] + 1):
        out.append(_conductor(d, v[f"alpha{j}"], v["n"], 0.0, v[f"ks{j}"], where))
    return out


def _note(m: Model, status: str) -> str:
    beckmann = m.options.get("distribution") == "beckmann"
    if m.name == "trowbridge-reitz-1975":
        return (f"TR75 has {'V-groove' if m.options['shadowing'] == 'v-groove' else 'no'} "
                f"shadowing; roughconductor (GGX, alpha = e) applies Smith's separable G")
    if beckmann and status == "approximate":
        return "Mitsuba's Beckmann G1 is a rational approximation (within 0.35 %) of Smith's"
    if beckmann:
        return "same formula (Mitsuba's Beckmann G1 approximation within 5e-5 here)"
    return "same formula"


def _tree(leaves: Sequence[_Leaf]) -> dict[str, Any]:
    """One plugin, or the ``blendbsdf`` chain of the module notes ("Sums")."""
    n = len(leaves)
    node = leaves[-1].scaled(float(n))
    for j in range(n - 2, -1, -1):
        w = (n - j - 1) / (n - j)
        node = {"type": "blendbsdf", "weight": w, "bsdf_0": leaves[j].scaled(float(n)),
                "bsdf_1": node}
    return node


def _merge(per: Sequence[Sequence[_Leaf]]) -> list[_Leaf] | str:
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
        out.append(_Leaf(leaf.plugin, leaf.scalars, colours, leaf.f_int))
    return out


# --------------------------------------------------------------------------------------------
# fitted stand-ins for what does not map
# --------------------------------------------------------------------------------------------
def _candidate(m: Model) -> tuple[Model, list[str], dict[str, tuple[float, float]]]:
    """The closest exactly mapped model family for ``m``, started at ``m``'s values: the
    model, the parameters kept fixed and search bounds."""
    from ..models import model as make

    v, o = m.params, m.options
    if m.name == "oren-nayar":
        return make("lambertian", rho=v["rho"]), [], {}
    if m.name == "coated":
        keep = {k: v[k] for k in m.param_names if k != "sigma"}
        return make("coated", distribution=o["distribution"], shadowing="smith-separable",
                    lobes=o["lobes"], shadow_diffuse=False, interface="rough", **keep), ["n"], {}
    if m.name == "microfacet":
        d = dist.get(o["distribution"])
        # Gaussian-like shapes (gaussian-angle, Sirohi) are closest to Beckmann, the others
        # (Berry) to GGX; their widths are other parameters, so the search starts at 0.2
        name, alpha = (d.name, v["alpha"]) if d.code in _MI_DIST else (
            "beckmann" if d.code in (dist.GAUSS_ANGLE, dist.SIROHI) else "trowbridge-reitz", 0.2)
        lobe = make("microfacet", distribution=name, shadowing="smith-separable",
                    alpha=min(max(alpha, 0.002), 2.0), n=v["n"], k=v["k"], ks=v["ks"])
        return lobe, [p for p in ("n", "k") if v[p] is not None], {"alpha": (0.002, 2.0)}
    # specular lobe + Lambertian part: TS67 (its gaussian-in-angle lobe is closest to
    # Beckmann), TR75 (fit=True), RB08, anything else (GGX)
    n, k, alpha, rho = {
        "torrance-sparrow-1967": lambda: (v["n"], v["k"], 0.2, v["rho_d"]),
        "trowbridge-reitz-1975": lambda: (v["n"], v["k"], v["e"], v["rho_L"]),
        "renhorn-boreman-2008": lambda: (v["n_eff"], v["k_eff"], 0.2, v["bulk"]),
    }.get(m.name, lambda: (None, None, 0.2, 0.5))()
    k = k if k is not None or n is None else 0.0  # k = None with an index: a dielectric
    lobe = make("microfacet", shadowing="smith-separable",
                distribution="beckmann" if m.name == "torrance-sparrow-1967" else "ggx",
                alpha=min(max(alpha, 0.002), 2.0), n=n, k=k, ks=1.0)
    fix = [f"microfacet_{p}" for p, val in (("n", n), ("k", k)) if val is not None]
    return lobe + make("lambertian", rho=rho), fix, {"microfacet_alpha": (0.002, 2.0)}


def _fit_closest(m: Model, grid: tuple[np.ndarray, ...], values: np.ndarray) -> Model:
    """:func:`_candidate` fitted to ``m``'s values on the grid: least squares of the relative
    deviation that :class:`Deviation` reports."""
    from ..fitting import fit
    from ..measurement import Measurement

    cand, fix, bounds = _candidate(m)
    meas = Measurement(theta_i=grid[0], theta_r=grid[1], phi=grid[2], values=values,
                       quantity=Quantity.BRDF, meta={"sample": f"{m.name} values"})
    # the residual that the reported r.m.s. deviation is made of (Deviation.of):
    # (x - f)/max(x, floor), as the absolute loss weighted by 1/max(x, floor)
    floor = max(FLOOR, PEAK_FLOOR * float(np.max(np.abs(values))))
    # a coated stand-in shares the model's physics: one local fit from its values suffices
    # (each new alpha builds the rough-interface tables, ~30 ms); the others search 4 starts
    res = fit(cand, meas, loss="absolute", weights=1.0 / np.maximum(np.abs(values), floor),
              fix=fix, bounds=bounds, free_scale=False, starts=1 if m.name == "coated" else 4,
              seed=0, progress=False)
    return res.model


# --------------------------------------------------------------------------------------------
# what Mitsuba computes (float64), for the deviations
# --------------------------------------------------------------------------------------------
def _mi_g1(dname: str, a: float, c: np.ndarray) -> np.ndarray:
    """Mitsuba's ``smith_g1``: Smith's for GGX, the rational approximation for Beckmann."""
    c = np.clip(c, 0.0, 1.0)
    if dname == "ggx":
        return shd.smith_g1(c, a, "trowbridge-reitz")
    s = np.sqrt(1.0 - c * c)
    # s = 0 (the normal direction): no masking, G1 = 1 (selected below; the stand-in 1 keeps
    # that lane free of a division by 0)
    x = c / (a * np.where(s > 0.0, s, 1.0))
    g = np.where(x >= 1.6, 1.0, (3.535 * x + 2.181 * x * x) / (1.0 + 2.276 * x + 2.577 * x * x))
    return np.where(s == 0.0, 1.0, g)


def _mi_fresnel(c: np.ndarray, eta: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Mitsuba's ``fresnel_conductor`` (unpolarized; ``k = 0``: a dielectric)."""
    c2 = c * c
    s2 = 1.0 - c2
    t1 = eta * eta - k * k - s2
    a2b2 = np.sqrt(t1 * t1 + 4.0 * k * k * eta * eta)
    a = np.sqrt(np.maximum(0.0, 0.5 * (a2b2 + t1)))
    t2 = 2.0 * c * a
    rs = (a2b2 + c2 - t2) / (a2b2 + c2 + t2)
    t3 = a2b2 * c2 + s2 * s2
    t4 = t2 * s2
    return 0.5 * (rs + rs * (t3 - t4) / (t3 + t4))


def _value(x: Any) -> np.ndarray:
    """A property's value over channels, shape (C, 1)."""
    if isinstance(x, dict):
        x = x["color"] if "color" in x else x["value"]
    return np.asarray(x, dtype=float).reshape(-1, 1)


def _mi_specular(node: dict[str, Any], g: dict[str, np.ndarray], eta: np.ndarray,
                 k: np.ndarray) -> np.ndarray:
    a = max(float(node.get("alpha", 0.1)), ALPHA_MIN)
    dname = node.get("distribution", "beckmann")
    d = dist.evaluate("trowbridge-reitz" if dname == "ggx" else "beckmann", g["ch"], a)
    d = np.where(d * g["ch"] > 1e-20, d, 0.0)  # Mitsuba's cut-off (MicrofacetDistribution)
    geo = _mi_g1(dname, a, g["ci"]) * _mi_g1(dname, a, g["cr"])
    f = _mi_fresnel(g["cd"], eta, k)
    ks = _value(node.get("specular_reflectance", 1.0))
    return ks * f * d * geo / (4.0 * g["ci"] * g["cr"])


def _lerp_table(table: np.ndarray, c: np.ndarray) -> np.ndarray:
    x = c * (ROUGH_TABLE_SIZE - 1)
    i = np.minimum(x.astype(int), ROUGH_TABLE_SIZE - 2)
    return table[i] + (table[i + 1] - table[i]) * (x - i)


def _mi_eval(node: dict[str, Any], g: dict[str, np.ndarray]) -> np.ndarray:
    """``eval()/cos(theta_o)`` of one plugin dict, shape (C, N)."""
    kind = node["type"]
    if kind == "diffuse":
        return _value(node.get("reflectance", 0.5)) / math.pi * np.ones_like(g["ci"])
    if kind == "roughconductor":
        return _mi_specular(node, g, _value(node.get("eta", 0.0)), _value(node.get("k", 1.0)))
    if kind == "roughplastic":
        eta = float(node.get("int_ior", 1.49)) / float(node.get("ext_ior", 1.000277))
        a = max(float(node.get("alpha", 0.1)), ALPHA_MIN)
        dname = node.get("distribution", "beckmann")
        spec = _mi_specular(node, g, np.array([[eta]]), np.zeros((1, 1)))
        table, f_int = rough_interface(a, eta, "trowbridge-reitz" if dname == "ggx" else
                                       "beckmann", g1="mitsuba")
        dr = _value(node.get("diffuse_reflectance", 0.5))
        dr = dr / (1.0 - (dr * f_int if node.get("nonlinear", False) else f_int))
        return spec + dr / (math.pi * eta * eta) * _lerp_table(table, g["ci"]) * _lerp_table(
            table, g["cr"])
    if kind == "blendbsdf":
        w = min(max(float(node["weight"]), 0.0), 1.0)  # Mitsuba clips the weight
        kids = [x for x in node.values() if isinstance(x, dict) and
                x.get("type") not in ("rgb", "srgb")]
        return (1.0 - w) * _mi_eval(kids[0], g) + w * _mi_eval(kids[1], g)
    raise ValueError(f"mitsuba_values: plugin {kind!r} is not one this module writes")


def mitsuba_values(bsdf: dict[str, Any], theta_i: Any, theta_r: Any, phi: Any) -> np.ndarray:
    """Mitsuba 3.9's ``eval()/cos(theta_o)`` (sr⁻¹) of a dict this module writes, in float64.

    A transcription of the ``diffuse``, ``roughconductor``, ``roughplastic`` and
    ``blendbsdf`` plugins' ``eval`` (their Beckmann ``G1``, cut-off and tables included), used
    for the deviations every export reports; ``tests/test_export_mitsuba.py`` checks it
    against Mitsuba. Angles in radians (the library's frame); ``theta_i, theta_r < pi/2``.

    Returns
    -------
    numpy.ndarray
        Broadcast shape of the angles; with RGB values, ``(3, *shape)``.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> from roughbrdf.export.mitsuba import mitsuba_values, to_mitsuba
    >>> m = rb.model("microfacet", distribution="ggx", alpha=0.3, n=1.5, k=0.0,
    ...              shadowing="smith-separable")
    >>> bool(abs(mitsuba_values(to_mitsuba(m), 0.4, 0.3, 0.5) / m.brdf(0.4, 0.3, 0.5) - 1)
    ...      < 1e-12)
    True
    """
    ti, tr, ph = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (theta_i, theta_r,
                                                                           phi)))
    shape = ti.shape
    ti, tr, ph = ti.ravel(), tr.ravel(), ph.ravel()
    if np.any(ti >= 0.5 * math.pi) or np.any(tr >= 0.5 * math.pi):
        raise ArgumentError("theta_i", "mitsuba_values needs theta_i, theta_r < pi/2 "
                            "(Mitsuba's eval is 0 at and below the horizon)")
    g = {"ci": np.cos(ti), "cr": np.cos(tr), "ch": np.cos(theta_h(ti, tr, ph)),
         "cd": np.cos(theta_d(ti, tr, ph))}
    out = _mi_eval(bsdf, g)
    return out.reshape(shape) if out.shape[0] == 1 else out.reshape(out.shape[0], *shape)


# --------------------------------------------------------------------------------------------
# the deviation grid
# --------------------------------------------------------------------------------------------
@lru_cache(maxsize=8)
def _grid(theta_max: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    from ..geometry import from_rusinkiewicz

    # a regular grid in the library's angles ...
    a, b, c = np.meshgrid(np.linspace(0.0, theta_max, 9), np.linspace(0.0, theta_max, 17),
                          np.linspace(0.0, math.pi, 13), indexing="ij")
    # ... and one in Rusinkiewicz's half/difference angles, dense near the specular peak
    # (theta_h quadratic in the index), where the narrow lobes are; phi_d in [0, pi/2] covers
    # an isotropic, reciprocal BRDF
    h, d, p = np.meshgrid(0.5 * math.pi * (np.arange(24) / 24.0) ** 2,
                          np.linspace(0.0, math.radians(85.0), 18),
                          np.linspace(0.0, 0.5 * math.pi, 7), indexing="ij")
    ti, tr, ph = from_rusinkiewicz(h.ravel(), d.ravel(), p.ravel())
    keep = np.isfinite(ti) & np.isfinite(tr) & (ti <= theta_max) & (tr <= theta_max)
    out = (np.concatenate([a.ravel(), ti[keep]]), np.concatenate([b.ravel(), tr[keep]]),
           np.concatenate([c.ravel(), np.abs(ph[keep])]))
    for x in out:
        x.setflags(write=False)
    return out


def deviation_grid(theta_max: float = math.radians(80.0)
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The geometries ``(theta_i, theta_r, phi)`` (radians) of the reported deviations and of
    the fits: a 9 x 17 x 13 grid of ``theta_i, theta_r <= theta_max``, ``phi`` in [0, pi],
    and a half/difference-angle grid dense near the specular direction (about 4700 in all).

    Examples
    --------
    >>> from roughbrdf.export.mitsuba import deviation_grid
    >>> ti, tr, phi = deviation_grid()
    >>> ti.size > 4000, round(float(max(ti.max(), tr.max())), 4)   # 80 deg
    (True, 1.3963)
    """
    t = float(theta_max)
    if not (0.0 < t < 0.5 * math.pi):
        raise ArgumentError("theta_max", "must be in (0, pi/2) radians", value=theta_max,
                            unit="rad")
    return _grid(t)


# --------------------------------------------------------------------------------------------
# models, fits and channels
# --------------------------------------------------------------------------------------------
def _export_term(m: Model, label: str, fit: bool, grid: tuple[np.ndarray, ...]
                 ) -> tuple[list[_Leaf], TermExport]:
    """One term: its plugins (mapped, or fitted with ``fit``) and its record."""
    reasons = _why_not(m)
    where = f"model {m.name!r}" + (f" (term {label!r})" if label != m.name else "")
    if reasons and not fit:
        raise ArgumentError("fit", f"{where} has no Mitsuba 3 counterpart: "
                            f"{'; '.join(reasons)}. The closest Mitsuba model fitted to its "
                            f"values can be exported instead (the export then reports the "
                            f"deviation)", fix=True)
    values = np.asarray(m.brdf(*grid), dtype=float)
    stand_in = None
    if reasons or (fit and m.name == "trowbridge-reitz-1975"):
        stand_in = _fit_closest(m, grid, values)
        leaves = _leaves(stand_in, where)
        why = "; ".join(reasons) or _note(m, "approximate")
        note = f"{why}; fitted: {_describe(stand_in)}"
    else:
        leaves = _leaves(m, where)
    dev = Deviation.of(mitsuba_values(_tree(leaves), *grid), values)
    if stand_in is not None:
        status = "fitted"
    else:
        status = "exact" if dev.max <= EXACT else "approximate"
        note = _note(m, status)
    return leaves, TermExport(label, tuple(leaf.plugin for leaf in leaves), status, note, dev,
                              stand_in)


def _describe(m: Model) -> str:
    parts = []
    for c in components(m):
        vals = ", ".join(f"{k}={v:.6g}" for k, v in c.params.items() if v is not None)
        parts.append(f"{c.name}({vals})")
    return " + ".join(parts)


def _export_model(m: Model, fit: bool, grid: tuple[np.ndarray, ...]
                  ) -> tuple[list[_Leaf], tuple[TermExport, ...]]:
    """Every term of ``m`` (the components of a sum, labelled by their prefixes)."""
    parts = components(m)
    labels = [p[:-1] for p in m.prefixes] if len(parts) > 1 else [m.name]  # type: ignore[attr-defined]
    leaves: list[_Leaf] = []
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
        # {channel: model}, e.g. roughbrdf.fitting.result.fitted_models(fit folder)
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
    """The channels written as red, green, blue (module notes, "Channels"); None: none."""
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


def export_mitsuba(source: Any, *, channel: int | str | None = None, rgb: Any = None,
                   fit: bool = False, theta_max: float = math.radians(80.0)) -> MitsubaExport:
    """Export a model or a fit to Mitsuba 3, with a record of how every term was mapped.

    Parameters
    ----------
    source : Model, FitResult or mapping
        A model (sums allowed), a fit (its fitted models), or ``{channel: model}`` (e.g.
        :func:`roughbrdf.fitting.result.fitted_models` of a saved fit).
    channel : int or str, optional
        One channel of a fit (label or position).
    rgb : None, False or (red, green, blue)
        Several channels (module notes, "Channels"): ``None`` writes one RGB BSDF where the
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

    Returns
    -------
    MitsubaExport

    Examples
    --------
    >>> import roughbrdf as rb
    >>> from roughbrdf.export.mitsuba import export_mitsuba
    >>> e = export_mitsuba(rb.model("tr75", e=0.3, n=1.5, k=0.0, rho_L=0.2))
    >>> e.status, e.terms[""][0].plugins
    ('approximate', ('roughconductor', 'diffuse'))
    >>> e.bsdf["bsdf_1"]["reflectance"]        # rho_L, times 2 in a blend of weight 0.5
    0.4
    """
    if not isinstance(fit, bool):
        raise ArgumentError("fit", "must be True or False", value=fit)
    grid = deviation_grid(theta_max)
    models, rule = _models_of(source, channel)
    if rule != "multi" and rgb not in (None, True, False):
        raise ArgumentError("rgb", "needs a fit with three channels or more (and no channel=)",
                            value=rgb)
    order = _rgb_order(list(models), rgb) if rule == "multi" else None
    if order is not None and rgb not in (None, True):
        models = {label: models[label] for label in order}  # explicit: those three only
    per = {label: _export_model(m, fit, grid) for label, m in models.items()}
    merged = _merge([per[label][0] for label in order]) if order is not None else None
    if isinstance(merged, str) and rgb not in (None, True):
        raise ValueError(f"rgb={rgb!r}: the channels cannot be one RGB BSDF: {merged}; pass "
                         f"rgb=False for one BSDF per channel")
    if isinstance(merged, list) and order is not None:
        rule, bsdf = "rgb", _tree(merged)
        values = mitsuba_values(bsdf, *grid)
        deviation = {label: Deviation.of(values[i] if values.ndim == 2 else values,
                                         np.asarray(models[label].brdf(*grid)))
                     for i, label in enumerate(order)}
    else:
        if rule == "multi":
            rule, order = "per-channel", None
            bsdf = {label: _tree(per[label][0]) for label in models}
        else:
            bsdf = _tree(next(iter(per.values()))[0])
        deviation = {label: Deviation.of(
            mitsuba_values(bsdf[label] if rule == "per-channel" else bsdf, *grid),
            np.asarray(m.brdf(*grid))) for label, m in models.items()}
    return MitsubaExport(bsdf=bsdf, rule=rule, terms={k: v[1] for k, v in per.items()},
                         deviation=deviation, rgb=order, theta_max=float(theta_max), grid=grid)


def to_mitsuba(source: Any, *, channel: int | str | None = None, rgb: Any = None,
               fit: bool = False, theta_max: float = math.radians(80.0)) -> dict[str, Any]:
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
    return export_mitsuba(source, channel=channel, rgb=rgb, fit=fit, theta_max=theta_max).bsdf


def to_mitsuba_xml(source: Any, *, channel: int | str | None = None, rgb: Any = None,
                   fit: bool = False, theta_max: float = math.radians(80.0),
                   id: str | None = None, version: str | None = None) -> str:  # noqa: A002
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
    e = export_mitsuba(source, channel=channel, rgb=rgb, fit=fit, theta_max=theta_max)
    return e.xml(id=id, version=version)


# --------------------------------------------------------------------------------------------
# XML
# --------------------------------------------------------------------------------------------
def _xml_property(parent: ET.Element, name: str, value: Any) -> None:
    if isinstance(value, dict) and value.get("type") in ("rgb", "srgb"):
        rgb = ", ".join(repr(float(x)) for x in (value["color"] if "color" in value
                                                 else value["value"]))
        if not value.get("unbounded"):
            ET.SubElement(parent, "rgb", name=name, value=rgb)
            return
        tex = ET.SubElement(parent, "texture", type="srgb", name=name)
        ET.SubElement(tex, "rgb", name="color", value=rgb)
        ET.SubElement(tex, "boolean", name="unbounded", value="true")
    elif isinstance(value, dict):
        parent.append(_xml_element(value, name))
    elif isinstance(value, bool):
        ET.SubElement(parent, "boolean", name=name, value="true" if value else "false")
    elif isinstance(value, int | float):
        ET.SubElement(parent, "float", name=name, value=repr(float(value)))
    else:
        ET.SubElement(parent, "string", name=name, value=str(value))


def _xml_element(bsdf: dict[str, Any], name: str | None = None) -> ET.Element:
    el = ET.Element("bsdf", type=str(bsdf["type"]))
    if name is not None:
        el.set("name", name)
    for key, value in bsdf.items():
        if key != "type":
            _xml_property(el, key, value)
    return el


def xml_text(bsdf: dict[str, Any], id: str | None = None,  # noqa: A002
             version: str | None = None) -> str:
    """One BSDF dict as an XML ``<bsdf>`` element; ``version="3.0.0"`` makes it a document
    Mitsuba loads on its own (``mitsuba.load_string``)."""
    el = _xml_element(bsdf)
    if version is not None:
        el.set("version", str(version))
    if id:
        el.set("id", str(id))
    ET.indent(el)
    return ET.tostring(el, encoding="unicode")
