"""Worker memory over a plotted catalogue, profiler off vs on (``python
benchmarks/bench_worker_memory.py``; issue "Safe edges, second pass", finding 6).

``N_FILES`` small synthetic TR75 files (one channel, 2 incidences x 8 reflection angles x 2
azimuths, 2 % noise) are fitted with TR75 (``starts=STARTS``) and **plotted** (``fit_<channel>.png``
in each fit folder) by ``rb.catalogue.fit_catalogue`` on a real ``LocalCluster`` of one
single-threaded worker process, twice in one run: with dask's statistical profiler off (what
``fit-batch`` runs: ``distributed.worker.profile.enabled: False``) and on (dask's default).
Printed for each: the worker's resident memory (RSS) after ``WARM`` warm-up files, after the
``N_FILES`` files, and the growth per file.
"""

from __future__ import annotations

import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

import roughbrdf as rb

N_FILES = 60
WARM = 5
STARTS = 2


def _files(folder: Path, n: int) -> list[str]:
    rng = np.random.default_rng(7)
    ti, tr, ph = (a.ravel() for a in np.meshgrid(np.radians([20.0, 45.0]),
                                                 np.radians(np.arange(0.0, 80.0, 10.0)),
                                                 [0.0, np.pi], indexing="ij"))
    paths = []
    for k in range(n):
        m = rb.model("tr75", e=rng.uniform(0.4, 0.9), rho_L=rng.uniform(0.1, 0.4))
        v = m.brdf(ti, tr, ph) * (1 + 0.02 * rng.standard_normal(ti.size))
        p = folder / f"s{k:03d}.csv"
        rb.write(rb.Measurement(ti, tr, ph, v), p)
        paths.append(str(p))
    return paths


def _rss() -> int:
    import psutil

    return int(psutil.Process().memory_info().rss)


def measure(files: list[str], out: Path, profile: bool) -> tuple[float, float]:
    """Worker RSS (MB) after the warm-up files and after every file, with the profiler
    ``profile``."""
    import dask
    from distributed import Client, LocalCluster

    env = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1",
           "DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED": str(profile)}
    with dask.config.set({"distributed.worker.profile.enabled": profile,
                          "logging.distributed": "error"}), \
            LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                         dashboard_address=None, env=env) as cluster, Client(cluster) as client:
        (on,) = client.run(lambda: dask.config.get("distributed.worker.profile.enabled")
                           ).values()
        assert on is profile, on
        rb.fit_catalogue(files[:WARM], "tr75", out / "warm", client=client, plots=True,
                         starts=STARTS, progress=False)
        (before,) = client.run(_rss).values()
        rb.fit_catalogue(files, "tr75", out / "run", client=client, plots=True,
                         starts=STARTS, progress=False)
        (after,) = client.run(_rss).values()
    return before / 1e6, after / 1e6


def main() -> None:
    print(f"# {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
          f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, load average "
          f"{' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(f"# {N_FILES} plotted TR75 fits (starts={STARTS}) on a LocalCluster of 1 worker")
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        (root / "in").mkdir()
        files = _files(root / "in", N_FILES)
        print(f"{'profiler':>9} {'RSS before MB':>14} {'RSS after MB':>13} {'per file MB':>12}")
        for profile in (False, True):
            before, after = measure(files, root / f"out-{profile}", profile)
            print(f"{'on' if profile else 'off':>9} {before:14.1f} {after:13.1f} "
                  f"{(after - before) / N_FILES:12.3f}")
    print(f"# load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
