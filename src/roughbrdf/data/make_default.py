"""Generate ``tr75_cement.csv``, the measurement embedded in the package (run once; seeded).

A synthetic relative BRIDF of the cement surface of Trowbridge & Reitz (1975), Table 1
(docs/models.md §3.10: e = 0.68, n = 1.00, k = 0.9, rho_L = 0.33), taken at TR75's own measurement
design (docs/models.md §3.9):

* incidence beta in {0, 15, 30, 45, 60, 70} deg;
* elevation in {15, 30, 45, 60, 75, 90} deg (theta_r = 90 deg - elevation);
* TR75 azimuth psi (from the source side) in {0, 30, 60, 90, 120, 150, 180} deg, once at
  elevation 90 deg where the azimuth is undefined;
* incident polarization perpendicular (gamma = 90 deg, s) and parallel (gamma = 0, p);

that is 6 x (5 x 7 + 1) x 2 = 432 samples. Each value is the model BRIDF times (1 + 0.1 eps),
eps standard normal (10 % multiplicative noise), divided by the noisy value at normal incidence,
normal view, perpendicular polarization: the file holds *relative* values, proportional to the
BRIDF, declared by ``# quantity: relative`` and ``# relative_to: bridf``.

Usage: ``python src/roughbrdf/data/make_default.py`` (rewrites the CSV next to this script).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

import roughbrdf as rb
from roughbrdf import geometry

TRUE = {"e": 0.68, "n": 1.00, "k": 0.9, "rho_L": 0.33}
SEED = 1975
NOISE = 0.10
BETA = (0, 15, 30, 45, 60, 70)
ELEVATION = (15, 30, 45, 60, 75, 90)
PSI = (0, 30, 60, 90, 120, 150, 180)
POLARIZATION = (90.0, 0.0)  # gamma in degrees: perpendicular (s), parallel (p)
OUT = Path(__file__).with_name("tr75_cement.csv")


def design() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(beta, elevation, psi, gamma) in degrees, one row per sample."""
    rows = []
    for gam in POLARIZATION:
        for b in BETA:
            for el in ELEVATION:
                for psi in (PSI if el < 90 else (0,)):
                    rows.append((b, el, psi, gam))
    a = np.array(rows, dtype=float)
    return a[:, 0], a[:, 1], a[:, 2], a[:, 3]


def make(path: Path = OUT) -> Path:
    beta, elev, psi, gam = design()
    ti, tr, ph = geometry.from_tr75(np.radians(beta), np.radians(elev), np.radians(psi))
    tr = np.clip(tr, 0.0, math.pi / 2)
    model = rb.model("trowbridge-reitz-1975", **TRUE)
    f = np.asarray(model.bridf(ti, tr, ph, polarization=np.radians(gam)))
    rng = np.random.default_rng(SEED)
    x = f * (1.0 + NOISE * rng.standard_normal(f.size))
    x /= x[0]  # first row: beta 0, elevation 90, perpendicular
    head = [
        "# roughbrdf-csv 1",
        "# angles: deg",
        "# quantity: relative",
        "# relative_to: bridf",
        "# sample: TR75 cement (synthetic)",
        "# instrument: synthetic, TR75 measurement design (docs/models.md 3.9)",
        "# truth: trowbridge-reitz-1975 e=0.68 n=1.00 k=0.9 rho_L=0.33 (TR75 Table 1, cement)",
        f"# noise: multiplicative, 1 + {NOISE:g} N(0,1), numpy default_rng seed {SEED}",
        "# normalization: divided by the value at beta 0, elevation 90, perpendicular",
        "# generator: src/roughbrdf/data/make_default.py",
        "theta_i,theta_r,phi,relative,polarization",
    ]
    lines = [f"{a:.10g},{b:.10g},{c:.10g},{v:.6g},{g:g}" for a, b, c, v, g in
             zip(np.degrees(ti), np.degrees(tr), np.degrees(ph), x, gam, strict=True)]
    path.write_text("\n".join(head + lines) + "\n", encoding="utf-8")
    return path


if __name__ == "__main__":
    p = make()
    print(f"wrote {p} ({sum(1 for _ in open(p)) - 11} samples)")
