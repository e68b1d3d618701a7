"""What Mitsuba computes: a float64 NumPy transcription of Mitsuba 3.9's ``eval``.

The evidence behind "exact" (package notes, :mod:`roughbrdf.export.mitsuba`): every export's
deviation is measured against :func:`mitsuba_values`, which reproduces the ``eval`` of the
plugins this package writes -- ``diffuse``, ``roughconductor`` (its Smith ``G1``, the rational
approximation for Beckmann, and its ``D cos theta_h <= 1e-20 -> 0`` cut-off),
``roughplastic`` (its internal-reflection tables, :func:`roughbrdf.diffuse.rough_interface`
with ``g1="mitsuba"``) and ``blendbsdf`` -- and ``tests/export/test_export_mitsuba.py`` checks it
against Mitsuba itself (to 1e-4 relative; Mitsuba's float32 arithmetic accounts for a few
1e-6).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ... import distributions as dist
from ... import shadowing as shd
from ...diffuse import ROUGH_TABLE_SIZE, rough_interface
from ...errors import ArgumentError
from ...geometry import theta_d, theta_h

__all__ = ["ALPHA_MIN", "mitsuba_values"]

#: Mitsuba clamps every microfacet roughness to at least 1e-4 (``MicrofacetDistribution``)
ALPHA_MIN = 1e-4


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
    """Mitsuba 3.9's ``eval()/cos(theta_o)`` (sr⁻¹) of a dict this package writes, in float64.

    A transcription of the ``diffuse``, ``roughconductor``, ``roughplastic`` and
    ``blendbsdf`` plugins' ``eval`` (their Beckmann ``G1``, cut-off and tables included), used
    for the deviations every export reports; ``tests/export/test_export_mitsuba.py`` checks it
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
