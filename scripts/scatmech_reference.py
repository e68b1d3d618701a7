"""Reference Mueller matrices from NIST SCATMECH (pySCATMECH) for ``tests/core/test_mueller.py``.

Run with a Python that has pySCATMECH (it is not a dependency of roughbrdf; it builds SCATMECH
from source)::

    /path/to/venv-with-pyscatmech/bin/python scripts/scatmech_reference.py [--out DIR]

It writes ``tests/data/scatmech/*.json``: the random geometries, each case's SCATMECH models
and parameters, the roughbrdf model that defines the same thing, and SCATMECH's Mueller matrix
BRDF at every geometry in the ``psps`` and ``xyxy`` bases, with the pySCATMECH and SCATMECH
versions. The test module imports this file to recompute the values live where pySCATMECH is
importable.

Angle mapping (checked in SCATMECH's ``code/brdf.cpp``, ``code/facet.cpp``,
``code/jmatrix.cpp``, ``docs/BRDF_Model.htm``): ``BRDF_Model::Mueller(thetai, thetas, phis,
rotation, coords)`` takes ``thetai`` = the angle of the direction *toward the source* from
the normal, ``thetas`` that of the viewing direction and ``phis`` its azimuth "measured in a
right-handed fashion about the surface normal from the plane of incidence", specular at
``phis = 0``; the incident light propagates along ``(sin thetai, 0, -cos thetai)``, so the
source lies on ``-x``, and the scattered direction is ``(sin thetas cos phis, sin thetas sin
phis, cos thetas)``. That is the library's frame (``docs/models.md`` §1.1) exactly:
``thetai = theta_i``, ``thetas = theta_r``, ``phis = phi``, ``rotation = 0`` (isotropic
surfaces), ``coords`` = ``basis``. No conversion is applied.

Model correspondences (each derived in ``docs/models.md`` §11.5):

* ``Shadowed_Facet_BRDF_Model`` (``Torrance_Sparrow_Shadow_Function``) with
  ``Gaussian_Slope_Distribution_Function(s)`` = ``microfacet`` Beckmann ``alpha = s``,
  ``shadowing="v-groove"``; ``Facet_BRDF_Model`` = the same with ``shadowing="none"``.
* ``Ellipsoid_Slope_Distribution_Function(rx = ry = 1, rz = e, density = 1/pi)`` is
  Trowbridge-Reitz/GGX with ``alpha = e``: ``microfacet`` GGX, and ``trowbridge-reitz-1975``
  (plus ``Lambertian_BRDF_Model(rho_L)`` for its Lambertian part).
* ``Gaussian_Angle_Distribution_Function(sigma = 1/c deg)`` has TS67's shape
  ``exp(-(c alpha_deg)^2)`` with the normalization ``1/(pi sigma_rad^2 norm)``,
  ``norm = 1 - exp(-(pi/(2 sigma_rad))^2)``; TS67 is ``4 rho_d g sigma_rad^2 norm`` times that
  shadowed facet model plus ``Lambertian_BRDF_Model(rho_d)``.
* ``Lambertian_BRDF_Model(rho)`` = ``lambertian`` (an ideal depolarizer).
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np

#: random geometries per file (theta_i, theta_r up to MAX_DEG, phi in [-180, 180) deg)
N_GEOMETRIES = 200
MAX_DEG = 80.0
SEED = 20261201
BASES = ("psps", "xyxy")
DATA = Path(__file__).resolve().parent.parent / "tests" / "data" / "scatmech"


def _gaussian(s: float) -> dict[str, Any]:
    return {"sdf": "Gaussian_Slope_Distribution_Function", "sdf.s": s}


def _ellipsoid(e: float) -> dict[str, Any]:
    # D = density (rx ry rz/(rz^2 + rx^2 sx^2 + ry^2 sy^2))^2 / cos^4 = GGX(alpha = e)
    return {"sdf": "Ellipsoid_Slope_Distribution_Function", "sdf.rx": 1.0, "sdf.ry": 1.0,
            "sdf.rz": e, "sdf.density": 1.0 / math.pi}


def _facet(shadowed: bool, n: float, k: float, sdf: dict[str, Any]) -> dict[str, Any]:
    model = "Shadowed_Facet_BRDF_Model" if shadowed else "Facet_BRDF_Model"
    params: dict[str, Any] = {"lambda": 0.5, "substrate": [n, k], "stack": "No_StackModel", **sdf}
    if shadowed:
        params["shadow"] = "Torrance_Sparrow_Shadow_Function"
    return {"model": model, "params": params}


def _lambertian(rho: float) -> dict[str, Any]:
    return {"model": "Lambertian_BRDF_Model",
            "params": {"lambda": 0.5, "reflectance": "Table_Reflectance",
                       "reflectance.table": rho}}


def _ts67_case(name: str, g: float, c: float, n: float, k: float, rho_d: float
               ) -> dict[str, Any]:
    sigma_deg = 1.0 / c
    sr = math.radians(sigma_deg)
    norm = 1.0 - math.exp(-((math.pi / sr / 2.0) ** 2))  # SCATMECH facet.cpp, setup()
    sdf = {"sdf": "Gaussian_Angle_Distribution_Function", "sdf.sigma": sigma_deg}
    return {"name": name,
            "terms": [{**_facet(True, n, k, sdf), "weight": 4.0 * rho_d * g * sr * sr * norm},
                      {**_lambertian(rho_d), "weight": 1.0}],
            "roughbrdf": {"model": "torrance-sparrow-1967",
                          "params": {"g": g, "c": c, "n": n, "k": k, "rho_d": rho_d}}}


def cases() -> dict[str, list[dict[str, Any]]]:
    """Every reference case by output file: SCATMECH terms (summed with their weights) and the
    roughbrdf model that defines the same BRDF."""
    def one(name: str, term: dict[str, Any], model: str, params: dict[str, Any],
            **options: Any) -> dict[str, Any]:
        return {"name": name, "terms": [{**term, "weight": 1.0}],
                "roughbrdf": {"model": model, "params": params, "options": options}}

    def beck(shadowed: bool, s: float, n: float, k: float) -> dict[str, Any]:
        tag = "v-groove" if shadowed else "none"
        return one(f"beckmann-{tag}-s{s}-n{n}-k{k}", _facet(shadowed, n, k, _gaussian(s)),
                   "microfacet", {"alpha": s, "n": n, "k": k, "ks": 1.0},
                   distribution="beckmann", shadowing=tag)

    def ggx(shadowed: bool, e: float, n: float, k: float) -> dict[str, Any]:
        tag = "v-groove" if shadowed else "none"
        return one(f"ggx-{tag}-e{e}-n{n}-k{k}", _facet(shadowed, n, k, _ellipsoid(e)),
                   "microfacet", {"alpha": e, "n": n, "k": k, "ks": 1.0},
                   distribution="trowbridge-reitz", shadowing=tag)

    def tr75(shadowed: bool, e: float, n: float, k: float, rho_l: float) -> dict[str, Any]:
        tag = "v-groove" if shadowed else "none"
        return {"name": f"tr75-{tag}-e{e}-n{n}-k{k}-rhoL{rho_l}",
                "terms": [{**_facet(shadowed, n, k, _ellipsoid(e)), "weight": 1.0},
                          {**_lambertian(rho_l), "weight": 1.0}],
                "roughbrdf": {"model": "trowbridge-reitz-1975",
                              "params": {"e": e, "n": n, "k": k, "rho_L": rho_l},
                              "options": {"shadowing": tag}}}

    return {
        # the issue's anchor: Gaussian slopes + Torrance-Sparrow shadowing = Beckmann + V-groove
        "facet_shadowed": [beck(True, 0.3, 0.2, 3.0), beck(True, 0.1, 1.2, 7.0),
                           beck(True, 0.6, 1.5, 0.0), beck(True, 0.2, 4.05, 0.05),
                           ggx(True, 0.5, 0.2, 3.0), tr75(True, 0.3, 1.5, 0.0, 0.1)],
        "facet_unshadowed": [beck(False, 0.3, 1.5, 0.0), ggx(False, 0.4, 1.2, 7.0),
                             tr75(False, 0.68, 1.0, 0.9, 0.33)],
        "ts67": [_ts67_case("ts67-c0.05-n1.5-k0.3", 2.0 / 3.0, 0.05, 1.5, 0.3, 0.3),
                 _ts67_case("ts67-c0.1-n0.2-k3", 5.0, 0.1, 0.2, 3.0, 0.2)],
        "lambertian": [one("lambertian-0.5", _lambertian(0.5), "lambertian", {"rho": 0.5})],
    }


def geometries(seed: int = SEED, n: int = N_GEOMETRIES) -> dict[str, list[float]]:
    """Random geometries (radians): theta_i, theta_r uniform in [0, MAX_DEG] deg, phi uniform in
    [-180, 180) deg."""
    rng = np.random.default_rng(seed)
    top = math.radians(MAX_DEG)
    return {"theta_i": rng.uniform(0.0, top, n).tolist(),
            "theta_r": rng.uniform(0.0, top, n).tolist(),
            "phi": rng.uniform(-math.pi, math.pi, n).tolist()}


def _scatmech_params(params: dict[str, Any]) -> dict[str, Any]:
    out = dict(params)
    if "substrate" in out:  # (n, k) -> SCATMECH's "(n,k)": n + ik, k >= 0 absorbing
        n, k = out["substrate"]
        out["substrate"] = f"({n!r},{k!r})"
    return out


def reference(case: dict[str, Any], geom: dict[str, list[float]], basis: str) -> np.ndarray:
    """SCATMECH's Mueller matrix BRDF of ``case`` (its terms summed with their weights) at the
    geometries, shape ``(n, 4, 4)``: ``MuellerBRDF(thetai=theta_i, thetas=theta_r,
    phis=phi, rotation=0, coords=basis)``."""
    from pySCATMECH.brdf import BRDF_Model

    total = np.zeros((len(geom["theta_i"]), 4, 4))
    for term in case["terms"]:
        model = BRDF_Model(term["model"])
        model.setParameters(_scatmech_params(term["params"]))
        for i, (ti, tr, ph) in enumerate(zip(geom["theta_i"], geom["theta_r"], geom["phi"],
                                              strict=True)):
            total[i] += term["weight"] * np.asarray(model.MuellerBRDF(ti, tr, ph, 0.0, basis))
    return total


def versions() -> dict[str, str]:
    """pySCATMECH's version and that of the SCATMECH library it wraps."""
    import SCATPY  # pySCATMECH's compiled module

    text = Path(SCATPY.__file__).read_bytes()
    found = re.search(rb"SCATMECH (\d+\.\d+)", text)
    return {"pySCATMECH": importlib.metadata.version("pyscatmech"),
            "SCATMECH": found.group(1).decode() if found else "unknown"}


def _dumps(doc: dict[str, Any]) -> str:
    """JSON with one line per case field and per matrix (compact, diff-friendly)."""
    def line(x: Any) -> str:
        return json.dumps(x, separators=(",", ":"))

    head = {k: v for k, v in doc.items() if k not in ("geometries", "cases")}
    parts = ["{"] + [f" {line(k)}: {line(v)}," for k, v in head.items()]
    parts.append(' "geometries": {')
    parts.append(",\n".join(f"  {line(k)}: {line(v)}" for k, v in doc["geometries"].items()))
    parts.append(" },")
    parts.append(' "cases": [')
    blocks = []
    for case in doc["cases"]:
        fields = []
        for k, v in case.items():
            if k in BASES:
                rows = ",\n".join(f"    {line(r)}" for r in v)
                fields.append(f"   {line(k)}: [\n{rows}\n   ]")
            else:
                fields.append(f"   {line(k)}: {line(v)}")
        blocks.append("  {\n" + ",\n".join(fields) + "\n  }")
    parts.append(",\n".join(blocks))
    parts.append(" ]")
    parts.append("}")
    return "\n".join(parts) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, default=DATA, help="output directory")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    geom = geometries()
    for stem, group in cases().items():
        for case in group:
            for basis in BASES:
                case[basis] = reference(case, geom, basis).reshape(-1, 16).tolist()
        doc = {"generator": "scripts/scatmech_reference.py", "versions": versions(),
               "call": "pySCATMECH.brdf.BRDF_Model(model).MuellerBRDF(thetai, thetas, phis, "
                       "rotation, coords), summed over terms with weights",
               "mapping": "thetai = theta_i, thetas = theta_r, phis = phi (the library's frame; "
                          "no conversion), rotation = 0, coords = basis",
               "matrix_layout": "row-major 4x4 per geometry, [I, Q, U, V] column vectors",
               "geometries": geom, "cases": group}
        path = args.out / f"{stem}.json"
        path.write_text(_dumps(doc))
        print(f"wrote {path} ({len(group)} cases x {len(geom['phi'])} geometries)")


if __name__ == "__main__":
    main()
