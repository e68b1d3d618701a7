"""Speed figures that the test suite used to assert (``make bench``; finding 8).

A test asserts on what a time stood for (``tests/test_suite_rules.py`` forbids timed
assertions); the times themselves are measured here, as figures:

1. reading the real files: the three Mini-Diff ASTM files (12,964 rows each) and the CEA ALTA
   gray tape (7,405 rows), in this process after one untimed read (``tests/io/test_io_astm.py``
   and ``tests/io/test_io_alta.py`` check that their rows are parsed in one block);
2. ``roughbrdf.catalogue.summary.write_summary`` of 100,000 synthetic rows, and the size of its
   page (``tests/catalogue/test_catalogue_summary.py`` checks that the page is paged);
3. opening that page in headless Chromium and sorting it by one column, where Chromium,
   chromedriver and selenium are installed (``make browser``).

Each figure is the median and the minimum of ``REPEAT`` runs (3 for the summary). Needs
``../shared/data`` (or ``ROUGHBRDF_SHARED_DATA``) for step 1 only. Run alone with
``python benchmarks/run.py bench_suite_figures``.
"""

from __future__ import annotations

import os
import shutil
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

import roughbrdf as rb

ROOT = Path(__file__).resolve().parent.parent
DATA = Path(os.environ.get("ROUGHBRDF_SHARED_DATA", ROOT.parent / "shared" / "data"))
REPEAT = 5
N_ROWS = 100_000
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMEDRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"


def timed(fn: Callable[[], Any], repeat: int = REPEAT) -> list[float]:
    """Seconds of ``repeat`` calls of ``fn``, after one untimed call."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return times


def row(label: str, times: list[float], note: str = "") -> None:
    print(f"  {label:<44} median {statistics.median(times):7.3f} s   "
          f"min {min(times):7.3f} s  {note}", flush=True)


def readers() -> None:
    print("reading the real files (rb.read):")
    files: list[tuple[Path, dict[str, Any]]] = [(DATA / "minidiff" / f"{name}.astm", {})
             for name in ("C2_Black", "C8_Silver", "C12_OliveDrab")]
    files.append((DATA / "cea_retro" / "retro-gray-tape.dat", {"quantity": "brdf_cos"}))
    for path, options in files:
        if not path.is_file():
            print(f"  {path.name}: skipped ({path} not found; set ROUGHBRDF_SHARED_DATA)")
            continue
        m = rb.read(path, **options)
        row(path.name, timed(_reader(path, options)), f"{m.n_samples} samples")


def _reader(path: Path, options: dict[str, Any]) -> Callable[[], Any]:
    return lambda: rb.read(path, **options)


def summary_rows(n: int) -> list[dict[str, Any]]:
    """``n`` synthetic catalogue rows (2 channels per file; 1 in 10 failed), as the tests'."""
    rng = np.random.default_rng(1)
    statuses = ["ok"] * 7 + ["not converged", "failed", "skipped (resume)"]
    rows = []
    for i in range(n):
        status, stem = statuses[i % len(statuses)], f"sample_{i // 2:06d}"
        channel = ("red", "nir")[i % 2]
        failed = status == "failed"
        rows.append({
            "file": f"{stem}.astm", "channel": channel, "model": "trowbridge-reitz-1975",
            "status": status, "error": "ValueError: no points" if failed else None,
            "params": {} if failed else {"e": float(rng.uniform(0.1, 0.9)),
                                         "rho_L": float(rng.uniform(0, 0.5))},
            "stderr": {} if failed else {"e": 0.01, "rho_L": 0.002},
            "sigma": None if failed else float(rng.uniform(0.01, 0.1)),
            "rms_log": None if failed else float(rng.uniform(0.01, 0.3)),
            "aic": None if failed else float(rng.normal(-100, 30)),
            "bic": None if failed else float(rng.normal(-90, 30)),
            "n_points": 100 + i % 37, "n_excluded": i % 3, "elapsed_s": 0.5 + i % 5,
            "sha256": f"{i:064x}", "fit_dir": f"{stem}/{channel}", "figure": None})
    return rows


def summary(folder: Path) -> Path:
    from roughbrdf.catalogue.summary import write_summary

    print(f"\nthe catalogue summary of {N_ROWS:,} rows (write_summary):")
    rows = summary_rows(N_ROWS)
    written: list[Path] = []

    def write() -> None:
        written[:] = write_summary(folder, rows, max_thumbnails=60, overwrite=True)

    times = timed(write, repeat=3)
    page = written[-1]
    row("summary.md + summary.html", times, f"page {page.stat().st_size / 1e6:.1f} MB")
    return page


def browser(page: Path) -> None:
    print(f"\nthe {N_ROWS:,}-row page in headless Chromium:")
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        print("  skipped: selenium not installed (`make browser`)")
        return
    if not (Path(CHROMIUM).exists() and Path(CHROMEDRIVER).exists()):
        print(f"  skipped: {CHROMIUM} or {CHROMEDRIVER} not installed (`make browser`)")
        return
    profile = tempfile.mkdtemp(prefix="rb-chromium-")
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for flag in ("--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                 "--disable-background-networking", "--window-size=1400,1000",
                 f"--user-data-dir={profile}"):
        opts.add_argument(flag)
    driver = webdriver.Chrome(options=opts, service=Service(executable_path=CHROMEDRIVER))
    try:
        def open_page() -> None:
            driver.get(page.resolve().as_uri())
            while driver.execute_script("return document.body.dataset.ready") != "1":
                time.sleep(0.01)

        row("open (until the first page is shown)", timed(open_page))
        headers = [h.text for h in driver.find_elements("css selector", "#rb-table th")]
        col = headers.index("rms log")
        row("sort by rms log (one click)", timed(
            lambda: driver.find_elements("css selector", "#rb-table th")[col].click()))
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)


def main() -> None:
    readers()
    with tempfile.TemporaryDirectory(prefix="rb-bench-summary-") as tmp:
        page = summary(Path(tmp))
        browser(page)


if __name__ == "__main__":
    main()
