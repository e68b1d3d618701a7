"""Fitted stand-ins (``fit=True``, the CLI's ``--fit-closest``) for what does not map.

A model without a Mitsuba counterpart (:func:`roughbrdf.export.mitsuba.mapping.why_not`) is
replaced by the closest exactly mapped model (package notes, :mod:`roughbrdf.export.mitsuba`),
fitted with :func:`roughbrdf.fit` to the model's values on the deviation grid by least squares
of the relative deviation :class:`~roughbrdf.export.mitsuba.deviation.Deviation` reports.
"""

from __future__ import annotations

import numpy as np

from ... import distributions as dist
from ...models.base import Model, components
from ...quantity import Quantity
from .deviation import FLOOR, PEAK_FLOOR
from .mapping import MITSUBA_DISTRIBUTIONS

__all__ = ["describe", "fit_closest"]


# --------------------------------------------------------------------------------------------
# fitted stand-ins for what does not map
# --------------------------------------------------------------------------------------------
def _candidate(m: Model) -> tuple[Model, list[str], dict[str, tuple[float, float]]]:
    """The closest exactly mapped model family for ``m``, started at ``m``'s values: the
    model, the parameters kept fixed and search bounds."""
    from ...models import model as make

    v, o = m.params, m.options
    if m.name == "oren-nayar":
        return make("lambertian", rho=v["rho"]), [], {}
    if m.name == "coated":
        keep = {k: v[k] for k in m.param_names if k != "sigma"}
        return make("coated", distribution=o["distribution"], shadowing="smith-separable",
                    lobes=o["lobes"], shadow_diffuse=False, interface="rough",
                    weights=o.get("weights", "partition"), **keep), ["n"], {}
    if m.name == "microfacet":
        d = dist.get(o["distribution"])
        # Gaussian-like shapes (gaussian-angle, Sirohi) are closest to Beckmann, the others
        # (Berry) to GGX; their widths are other parameters, so the search starts at 0.2
        name, alpha = (d.name, v["alpha"]) if d.code in MITSUBA_DISTRIBUTIONS else (
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


def fit_closest(m: Model, grid: tuple[np.ndarray, ...], values: np.ndarray) -> Model:
    """:func:`_candidate` fitted to ``m``'s values on the grid: least squares of the relative
    deviation that :class:`Deviation` reports."""
    from ...fitting import fit
    from ...measurement import Measurement

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


def describe(m: Model) -> str:
    """A fitted stand-in in one line, ``name(param=value, ...) + ...`` (the export's note)."""
    parts = []
    for c in components(m):
        vals = ", ".join(f"{k}={v:.6g}" for k, v in c.params.items() if v is not None)
        parts.append(f"{c.name}({vals})")
    return " + ".join(parts)
