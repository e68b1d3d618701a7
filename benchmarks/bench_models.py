"""Evaluations per second of every registered model at 1e6 random geometries (float64).

Inputs are NumPy angle arrays (structure of arrays: ``theta_i``, ``theta_r``, ``phi``), as a
user passes them; the time includes validation and the output allocation. Each model is run at
its default parameters, unpolarized, ``brdf()``; the microfacet model also with the Beckmann
distribution (its other defaults: Smith height-correlated, Fresnel n = 1.5); the coated model
with one lobe (its default) and with two (GGX, Smith separable, diffuse substrate shadowed by
the first lobe, Lambertian), and Oren-Nayar at its defaults (sigma = 0.3). Alongside, a plain
vectorized-NumPy implementation of TR75 (written here, independently of the library, as the
reference) is timed in the same run, and the speed-up of the compiled kernel over it is printed.

The models are timed *interleaved* (one call of each in turn, ``REPEAT`` rounds, the best
round kept per model), so that every model sees the same machine load; the ratio of each
model's rate to TR75's in the same run is printed with it, and so are the CPU time per
evaluation (all threads together; less sensitive to other processes than wall time) and the
load average before and after.

Run with ``make bench`` (all benchmarks) or ``python benchmarks/bench_models.py``.
Figures are recorded in ``docs/benchmarks.md``.
"""

from __future__ import annotations

import math
import os
import time

import numpy as np

import roughbrdf as rb

N = 1_000_000
REPEAT = 15  # interleaved rounds; the best round per model is kept
TR75_PARAMS = {"e": 0.68, "n": 1.0, "k": 0.9, "rho_L": 0.33}  # TR75 Table 1, cement


def tr75_numpy(theta_i, theta_r, phi, e, n, k, rho_L):  # noqa: N803 - paper's symbol
    """TR75 BRDF (Eqs. 30, 32, 33 divided by cos theta_r), unpolarized, in plain NumPy.

    The reference the compiled kernel is compared with: the straightforward vectorized
    transcription of docs/models.md §3.7-3.8 and §1.4 (complex Fresnel with ``np.sqrt``).
    """
    si, ci = np.sin(theta_i), np.cos(theta_i)
    sr, cr = np.sin(theta_r), np.cos(theta_r)
    hx = sr * np.cos(phi) - si
    hy = sr * np.sin(phi)
    hz = ci + cr
    length = np.sqrt(hx * hx + hy * hy + hz * hz)
    cos_h = hz / length  # cos(alpha)
    cos_s = 0.5 * length  # cos(s), local angle of incidence
    m = complex(n, k)
    root = np.sqrt(m * m - (1.0 - cos_s**2) + 0j)
    r_s = np.abs((cos_s - root) / (cos_s + root)) ** 2
    r_p = np.abs((m * m * cos_s - root) / (m * m * cos_s + root)) ** 2
    big_r = 0.5 * (r_s + r_p)
    c2 = cos_h * cos_h
    bridf_s = big_r * e * e / (4.0 * math.pi * ci * (e * e * c2 + (1.0 - c2)) ** 2)
    return bridf_s / cr + rho_L / math.pi


def geometries(n: int = N, seed: int = 20250101) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Random geometries on the hemisphere (theta_i < 89.9 deg so every model is defined)."""
    rng = np.random.default_rng(seed)
    theta_i = rng.uniform(0.0, math.radians(89.9), n)
    theta_r = rng.uniform(0.0, math.radians(89.9), n)
    phi = rng.uniform(-math.pi, math.pi, n)
    return theta_i, theta_r, phi


def _rows() -> list[tuple[str, object]]:
    """(label, model) per benchmark row: every registered model, plus Beckmann microfacet and
    the two-lobe coated model."""
    rows = []
    for name in rb.available():
        m = rb.model(name, **(TR75_PARAMS if name == "trowbridge-reitz-1975" else {}))
        label = name
        if name == "coated":  # one lobe (the default) and two lobes sharing the interface
            for mm in (m, rb.model("coated", lobes=2)):
                k = mm.options["lobes"]
                rows.append((f"coated ({k} lobe{'s' if k > 1 else ''}, ggx, smith-sep)", mm))
            continue
        if name == "microfacet":  # GGX and Beckmann, each with its default Smith and Fresnel
            for mm in (m, rb.model("microfacet", distribution="beckmann")):
                short = {"trowbridge-reitz": "ggx", "smith-height-correlated": "smith-hc",
                         "smith-separable": "smith-sep"}
                o = mm.options
                d, sh = short.get(o["distribution"], o["distribution"]), o["shadowing"]
                rows.append((f"microfacet ({d}, {short.get(sh, sh)}, fresnel)", mm))
            continue
        rows.append((label, m))
    return rows


def _load() -> str:
    try:
        return "/".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:  # pragma: no cover - not on every platform
        return "?"


def main() -> dict[str, float]:
    """Print and return evaluations/s per model, the ratios to TR75, the NumPy reference and
    the TR75 speed-up (all from one interleaved run)."""
    import numba

    ti, tr, phi = geometries()
    rows = _rows()
    tr75 = next(m for label, m in rows if label == "trowbridge-reitz-1975")
    calls = [(label, (lambda m=m: m.brdf(ti, tr, phi))) for label, m in rows]
    calls.append(("tr75 (plain NumPy reference)",
                  lambda: tr75_numpy(ti, tr, phi, **TR75_PARAMS)))
    load_before = _load()
    print(f"{N:.0e} random geometries, float64, unpolarized brdf(); {REPEAT} interleaved rounds, "
          f"best per model; {numba.get_num_threads()} Numba threads; load average (1/5/15 min) "
          f"before: {load_before}")
    for _, fn in calls:  # warm-up: compile or load from the disk cache
        fn()
    wall: dict[str, list[float]] = {label: [] for label, _ in calls}
    cpu: dict[str, list[float]] = {label: [] for label, _ in calls}
    for _ in range(REPEAT):
        for label, fn in calls:
            w0, c0 = time.perf_counter(), time.process_time()
            fn()
            cpu[label].append(time.process_time() - c0)
            wall[label].append(time.perf_counter() - w0)
    rates = {label: N / min(t) for label, t in wall.items()}
    ref_label = "trowbridge-reitz-1975"
    cpu_ns = {label: min(t) / N * 1e9 for label, t in cpu.items()}
    print(f"{'model':<46} {'evaluations/s':>13} {'/ TR75':>7} {'CPU ns/eval':>11} "
          f"{'TR75 CPU / CPU':>14}")
    for label, _ in calls:
        print(f"{label:<46} {rates[label]:>13.3e} {rates[label] / rates[ref_label]:>7.2f} "
              f"{cpu_ns[label]:>11.1f} {cpu_ns[ref_label] / cpu_ns[label]:>14.2f}")
    # the two TR75 implementations must agree, or the comparison means nothing
    fast = tr75.brdf(ti, tr, phi)
    slow = tr75_numpy(ti, tr, phi, **TR75_PARAMS)
    err = float(np.max(np.abs(fast - slow) / np.abs(slow)))
    ref = rates["tr75 (plain NumPy reference)"]
    speedup = rates[ref_label] / ref
    print(f"TR75 compiled: {rates[ref_label]:.3e} evaluations/s, {speedup:.1f}x the NumPy "
          f"reference (max relative difference {err:.1e}); CPU time "
          f"{min(cpu['tr75 (plain NumPy reference)']) / min(cpu[ref_label]):.1f}x less")
    print(f"load average after: {_load()} on {os.cpu_count()} cores (other processes slow the "
          "2-thread kernels more than single-threaded NumPy)")
    out = {label: rates[label] for label, _ in calls}
    out["tr75-numpy-reference"] = ref
    out["tr75-speedup"] = speedup
    for label, _ in calls:
        out[f"{label} / tr75"] = rates[label] / rates[ref_label]
    out.update(mueller_rates(ti, tr, phi, rates[ref_label]))
    return out


def mueller_rates(ti: np.ndarray, tr: np.ndarray, phi: np.ndarray,
                  tr75_rate: float) -> dict[str, float]:
    """Mueller matrices per second (``model.mueller``, psps) on the same geometries,
    interleaved; the ratio to TR75's scalar ``brdf()`` rate of the table above."""
    models = {"trowbridge-reitz-1975": rb.model("trowbridge-reitz-1975", **TR75_PARAMS),
              "microfacet (ggx, smith-hc, fresnel)": rb.model("microfacet"),
              "coated (1 lobe)": rb.model("coated"), "lambertian": rb.model("lambertian")}
    for m in models.values():  # warm-up: compile or load from the disk cache
        m.mueller(ti[:10], tr[:10], phi[:10])
    best = dict.fromkeys(models, math.inf)
    for _ in range(5):
        for label, m in models.items():
            t0 = time.perf_counter()
            m.mueller(ti, tr, phi)
            best[label] = min(best[label], time.perf_counter() - t0)
    print(f"\nMueller matrices (model.mueller, psps, {N:.0e} geometries, 4x4 float64 each; "
          f"best of 5 interleaved rounds):")
    out = {}
    for label, t in best.items():
        rate = N / t
        out[f"mueller {label}"] = rate
        print(f"  {label:<44} {rate:>10.3e} matrices/s  ({rate / tr75_rate:.3f} x TR75 brdf)")
    return out


if __name__ == "__main__":
    main()
