"""RGL measured-BSDF export: file size, time to write, and Mitsuba's error, by resolution.

For a coated model (alpha = 0.15) and ABg (its default 1-degree lobe), at three resolutions
(``samples`` 32, 48 - the default - and 96), ``roughbrdf.export.rgl.to_rgl`` is timed (median
of ``REPEAT`` runs after one warm-up) and the file loaded by Mitsuba 3's ``measured`` plugin
(``scalar_rgb``) and evaluated at 1,000 random directions (theta <= 80 deg): the median and
95th-percentile relative error of ``eval`` against ``f_r cos(theta_o)``. Without ``mitsuba``
only sizes and times are printed. Run alone with ``python benchmarks/run.py bench_rgl``.
"""

from __future__ import annotations

import math
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

import roughbrdf as rb
from roughbrdf.export.rgl import to_rgl

try:  # the machine's description beside the figures (benchmarks/machine.py)
    from machine import cpu_name, load, vector_width
except ImportError:  # run from elsewhere
    def cpu_name() -> str:
        return "unknown"

    def vector_width() -> str:
        return "unknown"

    def load() -> str:
        return "unknown"

REPEAT = 3
N = 1000
SAMPLES = (32, 48, 96)
MODELS = {"coated alpha=0.15": rb.model("coated", alpha=0.15, n=1.5, rho=0.4),
          "abg (1 deg lobe)": rb.model("abg")}


def _errors(model, path: Path) -> tuple[float, float] | None:
    """Median and p95 relative error of Mitsuba's eval, or None without mitsuba."""
    try:
        import mitsuba as mi
    except ImportError:
        return None
    mi.set_variant("scalar_rgb")
    bsdf = mi.load_dict({"type": "measured", "filename": str(path)})
    rng = np.random.default_rng(1)
    top = math.cos(math.radians(80.0))
    ti, tr = (np.arccos(rng.uniform(top, 1.0, N)) for _ in range(2))
    ph = rng.uniform(-math.pi, math.pi, N)
    ctx, si = mi.BSDFContext(), mi.SurfaceInteraction3f()
    got = np.empty(N)
    for j in range(N):  # the scalar variant: one direction a call
        si.wi = mi.Vector3f(-math.sin(ti[j]), 0.0, math.cos(ti[j]))
        wo = mi.Vector3f(math.sin(tr[j]) * math.cos(ph[j]), math.sin(tr[j]) * math.sin(ph[j]),
                         math.cos(tr[j]))
        got[j] = bsdf.eval(ctx, si, wo)[0]
    ref = model.brdf(ti, tr, ph) * np.cos(tr)
    err = np.abs(got - ref) / ref
    return float(np.median(err)), float(np.percentile(err, 95))


def main() -> None:
    print(f"RGL export ({cpu_name()}, {vector_width()}, load {load()})")
    print(f"{'model':20s} {'samples':>7s} {'MB':>6s} {'write s':>8s} {'median':>8s} {'p95':>7s}")
    with tempfile.TemporaryDirectory() as tmp:
        for name, model in MODELS.items():
            for n in SAMPLES:
                path = Path(tmp) / f"{n}.bsdf"
                res = {"samples": n}
                to_rgl(model, path, resolution=res, overwrite=True)  # warm-up
                times = []
                for _ in range(REPEAT):
                    t = time.perf_counter()
                    done = to_rgl(model, path, resolution=res, overwrite=True)
                    times.append(time.perf_counter() - t)
                err = _errors(model, path)
                tail = "   (no mitsuba)" if err is None else \
                    f" {err[0] * 100:7.2f}% {err[1] * 100:6.2f}%"
                print(f"{name:20s} {n:7d} {done.size / 1e6:6.2f} "
                      f"{statistics.median(times):8.2f}{tail}")


if __name__ == "__main__":
    main()
