"""The TR75 fit of one Mini-Diff file written by hand with NumPy + SciPy (no roughbrdf).

``python benchmarks/fit_by_hand.py FILE.astm OUT.json [--starts N]``

The baseline that ``roughbrdf fit FILE -m tr75 --free-scale --starts N --no-plots`` is timed
against end to end (``benchmarks/bench_startup.py``): what a user would write without the
library, doing the same job:

* read the ASTM E1392 file (``KEY value`` header lines, then comma-separated rows
  ``theta_i, phi_i, theta_s, phi_s, channel...`` in radians; Mini-Diff's ``VARS`` line omits
  ``phi_s``), the source at ``phi_i``, so the azimuth from the forward direction is
  ``phi_s - phi_i + pi``;
* TR75 with its Lambertian part (Trowbridge & Reitz 1975, Eqs. 30-33) as a BRDF, unpolarized,
  in plain vectorized NumPy: ``R(theta_d) D(theta_h) / (4 cos theta_i cos theta_r) + rho_L/pi``
  with ``D = e^2 / (pi (e^2 cos^2 theta_h + sin^2 theta_h)^2)`` and ``R`` the mean of the s and p
  Fresnel reflectances of ``n + ik`` at the angle ``theta_d`` between the incident direction and
  the half vector; samples at ``theta_r = 90 deg`` (where the unshadowed model diverges) are left
  out;
* the relative loss with a free data scale (TR75 Eq. 34): residual ``K x/f - 1`` with ``K`` in
  closed form, ``K = sum(q)/sum(q^2)``, ``q = x/f``;
* ``scipy.optimize.least_squares`` (trust-region reflective, box bounds, 2-point Jacobian) from
  ``N`` starts per channel: the TR75 cement values of Table 1, then uniform random points in the
  bounds; the lowest cost wins; every channel of the file;
* a JSON file of the parameters, ``K``, sigma and the time per channel.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time

import numpy as np
from scipy.optimize import least_squares

NAMES = ("e", "n", "k", "rho_L")
START = np.array([0.68, 1.0, 0.9, 0.33])  # TR75 Table 1, cement
LOW = np.array([0.02, 0.2, 0.0, 0.0])
HIGH = np.array([3.0, 5.0, 10.0, 1.0])


def read_astm(path: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, list[str]]:
    """theta_i, theta_r, phi (radians, phi = 0 forward), values (N, C) and channel names."""
    names: list[str] = []
    rows = []
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            line = line.strip()
            if not line:
                continue
            if line[0].isdigit() or line[0] in "+-.":
                rows.append([float(v) for v in line.split(",")])
            elif line.upper().startswith("VARS"):
                names = [v.strip() for v in line.split(None, 1)[1].split(",")]
    data = np.array(rows)
    channels = names[3:] if len(names) == data.shape[1] - 1 else names[4:]
    ti, pi_, tr, ps = data[:, 0], data[:, 1], data[:, 2], data[:, 3]
    phi = np.angle(np.exp(1j * (ps - pi_ + np.pi)))  # wrapped into (-pi, pi]
    return ti, tr, phi, data[:, 4:], channels


def tr75_brdf(p: np.ndarray, ti: np.ndarray, tr: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """TR75 BRDF (Eqs. 30, 32, 33 divided by cos theta_r), unpolarized."""
    e, n, k, rho_l = p
    ci, cr = np.cos(ti), np.cos(tr)
    # incident direction (source on -x) plus reflected direction, then the half vector
    hx = np.sin(tr) * np.cos(phi) - np.sin(ti)
    hy = np.sin(tr) * np.sin(phi)
    hz = ci + cr
    norm = np.sqrt(hx * hx + hy * hy + hz * hz)
    cos_h = hz / norm  # cos theta_h
    cos_d = 0.5 * norm  # cos theta_d = (w_i . h) = |w_i + w_r|/2
    eps = complex(n, k) ** 2
    root = np.sqrt(eps - (1.0 - cos_d * cos_d) + 0j)
    r_s = np.abs((cos_d - root) / (cos_d + root)) ** 2
    r_p = np.abs((eps * cos_d - root) / (eps * cos_d + root)) ** 2
    e2 = e * e
    d = e2 / (np.pi * (e2 * cos_h * cos_h + (1.0 - cos_h * cos_h)) ** 2)
    return 0.5 * (r_s + r_p) * d / (4.0 * ci * cr) + rho_l / np.pi


def scale_k(x: np.ndarray, f: np.ndarray) -> float:
    """Closed-form K minimizing sum((K x/f - 1)^2)."""
    q = x / f
    den = float(np.dot(q, q))
    return float(q.sum()) / den if den > 0 else 1.0


def fit_channel(x: np.ndarray, geo: tuple, starts: np.ndarray) -> dict:
    def residual(p: np.ndarray) -> np.ndarray:
        f = np.maximum(tr75_brdf(p, *geo), 1e-300)
        q = x / f
        den = float(np.dot(q, q))
        k = float(q.sum()) / den if den > 0 else 1.0
        return k * q - 1.0

    best = None
    nfev = 0
    for p0 in starts:
        r = least_squares(residual, p0, bounds=(LOW, HIGH), method="trf", jac="2-point",
                          x_scale="jac")
        nfev += r.nfev
        if best is None or r.cost < best.cost:
            best = r
    assert best is not None
    f = tr75_brdf(best.x, *geo)
    k = scale_k(x, f)
    sigma = float(np.sqrt(np.mean((k * x / f - 1.0) ** 2)))
    return {"params": dict(zip(NAMES, map(float, best.x), strict=True)), "scale": k,
            "sigma": sigma, "cost": float(best.cost), "nfev": nfev, "success": bool(best.success)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("file")
    ap.add_argument("out")
    ap.add_argument("--starts", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    ti, tr, phi, values, channels = read_astm(args.file)
    keep = tr < 0.5 * math.pi - 1e-9  # the unshadowed TR75 BRDF diverges at theta_r = 90 deg
    geo = (ti[keep], tr[keep], phi[keep])
    rng = np.random.default_rng(args.seed)
    starts = np.vstack([START, LOW + rng.random((args.starts - 1, 4)) * (HIGH - LOW)])
    out = {"model": "trowbridge-reitz-1975", "file": args.file, "loss": "relative",
           "starts": args.starts, "n_points": int(keep.sum()), "channels": []}
    for j, name in enumerate(channels):
        t = time.perf_counter()
        res = fit_channel(values[keep, j], geo, starts)
        res.update(channel=name, seconds=time.perf_counter() - t)
        out["channels"].append(res)
    out["seconds"] = time.perf_counter() - t0
    with open(args.out, "w", encoding="utf-8") as fh:
        json.dump(out, fh, indent=1)
    for c in out["channels"]:
        p = ", ".join(f"{k} {v:.4g}" for k, v in c["params"].items())
        print(f"{c['channel']}: {p}, K {c['scale']:.4g}, sigma {c['sigma']:.4f} "
              f"({c['nfev']} evaluations, {c['seconds']:.2f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
