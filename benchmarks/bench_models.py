"""Evaluations per second of every registered model at 1e6 random geometries (float64).

Inputs are NumPy angle arrays (structure of arrays: ``theta_i``, ``theta_r``, ``phi``), as a
user passes them; the time includes validation and the output allocation. Each model is run at
its default parameters, unpolarized, ``brdf()``. Alongside, a plain vectorized-NumPy
implementation of TR75 (written here, independently of the library, as the reference) is timed
in the same run, and the speed-up of the compiled kernel over it is printed.

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
REPEAT = 7
TR75_PARAMS = {"e": 0.68, "n": 1.0, "k": 0.9, "rho_L": 0.33}  # TR75 Table 1, cement


def tr75_numpy(theta_i, theta_r, phi, e, n, k, rho_L):  # noqa: N803 - paper's symbol
    """TR75 BRDF (Eqs. 30, 32, 33 divided by cos theta_r), unpolarized, in plain NumPy.

    The reference the compiled kernel is compared with: the straightforward vectorized
    transcription of MODELS.md §3.7-3.8 and §1.4 (complex Fresnel with ``np.sqrt``).
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


def _best(fn, repeat: int = REPEAT) -> float:
    """Smallest wall time of ``repeat`` calls (after one warm-up call), seconds."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def geometries(n: int = N, seed: int = 20250101) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Random geometries on the hemisphere (theta_i < 89.9 deg so every model is defined)."""
    rng = np.random.default_rng(seed)
    theta_i = rng.uniform(0.0, math.radians(89.9), n)
    theta_r = rng.uniform(0.0, math.radians(89.9), n)
    phi = rng.uniform(-math.pi, math.pi, n)
    return theta_i, theta_r, phi


def main() -> dict[str, float]:
    """Print and return evaluations/s per model, the NumPy reference, and the TR75 speed-up."""
    import numba

    ti, tr, phi = geometries()
    print(f"{N:.0e} random geometries, float64, unpolarized brdf(); best of {REPEAT}; "
          f"{numba.get_num_threads()} Numba threads")
    print(f"{'model':<28} {'evaluations/s':>14}")
    rates: dict[str, float] = {}
    for name in rb.available():
        m = rb.model(name, **(TR75_PARAMS if name == "trowbridge-reitz-1975" else {}))
        rates[name] = N / _best(lambda m=m: m.brdf(ti, tr, phi))
        print(f"{name:<28} {rates[name]:>14.3e}")
    # TR75 compiled vs NumPy, interleaved so that both see the same machine load
    tr75 = rb.model("trowbridge-reitz-1975", **TR75_PARAMS)
    t_fast, t_ref, c_fast, c_ref = [], [], [], []
    for _ in range(REPEAT):
        for fn, wall, cpu in ((lambda: tr75.brdf(ti, tr, phi), t_fast, c_fast),
                              (lambda: tr75_numpy(ti, tr, phi, **TR75_PARAMS), t_ref, c_ref)):
            fn()
            w0, c0 = time.perf_counter(), time.process_time()
            fn()
            cpu.append(time.process_time() - c0)
            wall.append(time.perf_counter() - w0)
    rates["trowbridge-reitz-1975"] = max(rates["trowbridge-reitz-1975"], N / min(t_fast))
    ref = N / min(t_ref)
    rates["tr75-numpy-reference"] = ref
    print(f"{'tr75 (plain NumPy reference)':<28} {ref:>14.3e}")
    # the two implementations must agree, or the comparison means nothing
    fast = tr75.brdf(ti, tr, phi)
    slow = tr75_numpy(ti, tr, phi, **TR75_PARAMS)
    err = float(np.max(np.abs(fast - slow) / np.abs(slow)))
    speedup = rates["trowbridge-reitz-1975"] / ref
    rates["tr75-speedup"] = speedup
    print(f"TR75 compiled: {rates['trowbridge-reitz-1975']:.3e} evaluations/s, "
          f"{speedup:.1f}x the NumPy reference (max relative difference {err:.1e})")
    # CPU time (all threads) is less sensitive to other processes than wall time
    print(f"CPU time per evaluation: TR75 compiled {min(c_fast) / N * 1e9:.1f} ns, NumPy "
          f"{min(c_ref) / N * 1e9:.1f} ns ({min(c_ref) / min(c_fast):.1f}x less work)")
    try:
        load = os.getloadavg()[0]
        print(f"load average during the run: {load:.2f} on {os.cpu_count()} cores "
              "(other processes slow the 2-thread kernel more than single-threaded NumPy)")
    except OSError:  # pragma: no cover - not on every platform
        pass
    return rates


if __name__ == "__main__":
    main()
