"""Catalogue throughput (``make bench``; ``python benchmarks/bench_catalogue.py``).

``N_FILES`` distinct synthetic TR75 files on the Mini-Diff geometry (3 channels; incidences
0, 20, 40, 60 deg, reflection 0-89 deg by 1 deg, azimuth 0-350 deg by 10 deg: 12,816 samples
each; random e and rho_L, 2 % noise), fitted with TR75 at ``STARTS`` starts and saved without
plots, four ways (each cluster run ``ROUNDS`` times, the spread printed):

1. a sequential loop of ``rb.fit`` + ``FitResult.save`` in this process (kernels warmed first);
2. ``rb.catalogue.fit_catalogue`` on a ``LocalCluster`` of 1 and of 2 worker processes (the
   cluster's start-up included, as ``roughbrdf fit-batch`` pays it);
3. the same on a cluster of separate processes (``dask scheduler`` + ``dask worker
   --nworkers 2 --nthreads 1``), reached by its address: first run (kernels loaded on the
   workers) and a second run on the warm workers.

Printed: seconds, files per second, and the per-task cost on warm workers, from which
``docs/catalogue.md`` estimates the scaling.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import roughbrdf as rb

N_FILES = 72
STARTS = 8
ROUNDS = 2
ENV = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
       "MKL_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1"}


def make_files(folder: Path, n: int = N_FILES, seed: int = 0) -> list[str]:
    """``n`` distinct synthetic 3-channel TR75 CSV files."""
    rng = np.random.default_rng(seed)
    ti, tr, ph = (a.ravel() for a in np.meshgrid(np.radians([0.0, 20.0, 40.0, 60.0]),
                                                 np.radians(np.arange(0.0, 90.0, 1.0)),
                                                 np.radians(np.arange(0.0, 360.0, 10.0)),
                                                 indexing="ij"))
    paths = []
    for k in range(n):
        cols = []
        for _ in range(3):
            m = rb.model("tr75", e=rng.uniform(0.3, 0.9), rho_L=rng.uniform(0.05, 0.4))
            cols.append(m.brdf(ti, tr, ph) * (1 + 0.02 * rng.standard_normal(ti.size)))
        meas = rb.Measurement(ti, tr, ph, np.stack(cols, axis=1),
                              channels=["465nm", "525nm", "630nm"])
        p = folder / f"sample{k:03d}.csv"
        rb.write(meas, p)
        paths.append(str(p))
    return paths


def sequential(paths: list[str], out: Path) -> float:
    rb.fit("tr75", rb.read(paths[0]), starts=STARTS, progress=False)  # warm the kernels
    t0 = time.perf_counter()
    for p in paths:
        rb.fit("tr75", rb.read(p), starts=STARTS, progress=False).save(
            out / Path(p).stem, plots=False)
    return time.perf_counter() - t0


def catalogue(paths: list[str], out: Path, **where) -> float:
    from roughbrdf.catalogue import fit_catalogue

    t0 = time.perf_counter()
    res = fit_catalogue(paths, "tr75", out, plots=False, progress=False, starts=STARTS,
                        **where)
    assert not res.failed, res.failed
    return time.perf_counter() - t0


def separate_processes(paths: list[str], tmp: Path) -> tuple[float, float]:
    """A scheduler and 2 single-threaded workers as processes of their own."""
    sched_file = tmp / "scheduler.json"
    dask = [sys.executable, "-m", "distributed.cli.dask_scheduler"]
    sched = subprocess.Popen([*dask, "--scheduler-file", str(sched_file), "--host", "127.0.0.1",
                              "--no-dashboard", "--port", "0"], env=ENV,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    worker = None
    try:
        while not sched_file.exists():
            time.sleep(0.1)
        time.sleep(0.2)
        addr = json.loads(sched_file.read_text())["address"]
        worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", addr,
                                   "--nworkers", "2", "--nthreads", "1", "--no-dashboard"],
                                  env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        from distributed import Client

        with Client(addr) as c:
            c.wait_for_workers(2, timeout=60)
        first = catalogue(paths, tmp / "sep1", scheduler=addr)
        warm = catalogue(paths, tmp / "sep2", scheduler=addr)
    finally:
        for p in (worker, sched):
            if p is not None:
                p.terminate()
                p.wait(timeout=30)
    return first, warm


def main() -> None:
    tmp = Path(tempfile.mkdtemp(prefix="bench-catalogue-"))
    try:
        (tmp / "data").mkdir()
        paths = make_files(tmp / "data")
        print(f"{N_FILES} files x 3 channels x 12,816 samples (Mini-Diff geometry), TR75, "
              f"starts={STARTS}, no plots; {os.cpu_count()} cores")
        seq = sequential(paths, tmp / "seq")
        rows = [("sequential rb.fit + save (warm)", [seq])]
        for n in (1, 2):
            rows.append((f"fit_catalogue, LocalCluster {n} worker(s), start-up included",
                         [catalogue(paths, tmp / f"local{n}-{r}", n_workers=n)
                          for r in range(ROUNDS)]))
        first, warm = separate_processes(paths, tmp)
        rows.append(("scheduler + 2 workers (separate processes), first run", [first]))
        rows.append(("scheduler + 2 workers (separate processes), warm workers", [warm]))
        print("| how | s | files/s | / sequential |\n|---|---:|---:|---:|")
        for what, ts in rows:
            span = f"{min(ts):.2f}" if len(ts) == 1 else f"{min(ts):.2f}-{max(ts):.2f}"
            print(f"| {what} | {span} | {N_FILES / min(ts):.1f} | {min(ts) / seq:.2f} |")
        one, two = rows[1][1], rows[2][1]
        print(f"1 -> 2 local workers: {min(one) / max(two):.2f}-{max(one) / min(two):.2f}x "
              f"faster end to end (spread over {ROUNDS} rounds each)")
        print(f"per-task cost on warm workers: {2 * warm / N_FILES:.3f} s per file "
              f"(2 workers)")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
