"""Start-up and end-to-end fit times, each in a fresh process (``make bench``).

Wall-clock times of whole processes, as a user sees them (``subprocess.run`` from start to exit),
each the median and the minimum of ``REPEAT`` runs after one untimed warm-up run:

1. ``python -c "import roughbrdf"`` and ``roughbrdf --help``;
2. import and one TR75 evaluation, ``rb.model("tr75").brdf(0.5, 0.5, 0.0)``, with a warm Numba
   cache (the cache of the working tree, filled by the warm-up run);
3. the same after ``pip install .`` (not editable) into a fresh venv under the temporary folder,
   with a **cold** cache: ``NUMBA_CACHE_DIR`` pointing to a new empty folder for every run (the
   TR75 kernel is compiled); then warm, with the cache that the last cold run filled. The venv
   gets roughbrdf itself from a wheel built from a copy of ``pyproject.toml``, ``README.md`` and
   ``src/``; its dependencies (NumPy, SciPy, Numba, ...) are the project venv's own, seen through
   a ``.pth`` file, so that no download is needed (the same files, so the same import times);
4. TR75 fitted to every channel of the Mini-Diff file ``C8_Silver.astm`` (relative loss with a
   free data scale K, 3 starts) by the hand-written SciPy script ``benchmarks/fit_by_hand.py``,
   as it is and with one BLAS thread (``OPENBLAS_NUM_THREADS=1``: :data:`THREAD_VARS`), by
   ``roughbrdf fit --free-scale --starts 3 --no-plots`` (writes ``fit.json`` and
   ``report.txt``) and by the same command with its usual figures; the fitted sigma of each
   channel is printed beside the times.

Needs ``../shared/data`` (or ``ROUGHBRDF_SHARED_DATA``) for step 4 only. Run alone with
``python benchmarks/run.py bench_startup``. Figures are recorded in ``docs/benchmarks.md``.
"""

from __future__ import annotations

import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
DATA = Path(os.environ.get("ROUGHBRDF_SHARED_DATA", ROOT.parent / "shared" / "data"))
FIT_FILE = "C8_Silver"
FIT_STARTS = 3
REPEAT = 5
REPEAT_FIT = 3
EVAL = 'import roughbrdf as rb; rb.model("tr75").brdf(0.5, 0.5, 0.0)'
#: set to 1 for the script's second row: OpenBLAS's threads (used by least_squares' SVD) make
#: the script several times slower and erratic when another process holds a core, while
#: rb.fit runs BLAS single-threaded
THREAD_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def _cli() -> list[str]:
    script = Path(sys.executable).parent / "roughbrdf"
    return [str(script)] if script.exists() else [sys.executable, "-m", "roughbrdf.cli"]


def run(cmd: Sequence[str], env: dict[str, str] | None = None) -> float:
    """Wall time (s) of one process; raises if it fails."""
    t = time.perf_counter()
    proc = subprocess.run(list(cmd), env=env, capture_output=True, text=True, check=False)
    dt = time.perf_counter() - t
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    return dt


def timed(cmd: Sequence[str] | Callable[[], Sequence[str]], repeat: int = REPEAT,
          env: dict[str, str] | None = None, warmup: bool = True) -> list[float]:
    """Times of ``repeat`` runs (after one untimed run if ``warmup``); ``cmd`` may be a
    function returning the command, called before every run."""
    make = cmd if callable(cmd) else (lambda: cmd)
    if warmup:
        run(make(), env)
    return [run(make(), env) for _ in range(repeat)]


def row(label: str, times: list[float], note: str = "") -> None:
    print(f"| {label} | {statistics.median(times):.3f} | {min(times):.3f} | {len(times)} "
          f"| {note} |")


def _load() -> str:
    try:
        return ", ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:  # pragma: no cover - not on Linux
        return "?"


def fresh_venv(base: Path) -> Path | None:
    """A new venv with roughbrdf installed from a wheel (not editable); its python or None."""
    src = base / "src-copy"
    src.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(ROOT / name, src / name)
    shutil.copytree(ROOT / "src", src / "src", ignore=shutil.ignore_patterns(
        "__pycache__", "*.egg-info", "*.nbi", "*.nbc"))
    venv = base / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    py = venv / "bin" / "python"
    site = subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()"
                           "['purelib'])"], check=True, capture_output=True, text=True)
    deps = subprocess.run([sys.executable, "-c", "import numpy, os; print(os.path.dirname("
                           "os.path.dirname(numpy.__file__)))"], check=True,
                          capture_output=True, text=True)
    Path(site.stdout.strip(), "_roughbrdf_bench_deps.pth").write_text(deps.stdout.strip() + "\n")
    pip = [sys.executable, "-m", "pip", "--python", str(py), "install", "-q", "--no-deps"]
    for extra in ([], ["--no-build-isolation"]):  # the second needs no download
        proc = subprocess.run([*pip, *extra, str(src)], capture_output=True, text=True)
        if proc.returncode == 0:
            return py
    print(f"(fresh venv skipped: pip install failed: {proc.stderr.strip()[-500:]})")
    return None


def startup() -> None:
    py, cli = sys.executable, _cli()
    print("| what | median (s) | min (s) | runs | note |")
    print("|---|---|---|---|---|")
    row("`python -c pass` (the interpreter alone)", timed([py, "-c", "pass"]))
    row("`python -c \"import roughbrdf\"`", timed([py, "-c", "import roughbrdf"]),
        "target <= 0.5")
    row("`roughbrdf --help`", timed([*cli, "--help"]), "target <= 0.3")
    row("`roughbrdf fit --help`", timed([*cli, "fit", "--help"]))
    row("import + TR75 evaluation, warm cache", timed([py, "-c", EVAL]), "target <= 0.8")
    with tempfile.TemporaryDirectory(prefix="roughbrdf-startup-") as tmp:
        base = Path(tmp)
        t = time.perf_counter()
        vpy = fresh_venv(base)
        if vpy is None:
            return
        setup = time.perf_counter() - t
        caches = iter(range(1000))
        env = dict(os.environ)

        def cold() -> list[str]:
            cache = base / f"numba-cache-{next(caches)}"
            cache.mkdir()
            env["NUMBA_CACHE_DIR"] = str(cache)
            return [str(vpy), "-c", EVAL]

        row("fresh venv (`pip install .`), cold Numba cache: import + TR75 evaluation",
            timed(cold, repeat=3, env=env), f"venv set up in {setup:.1f} s")
        row("fresh venv, warm cache: import + TR75 evaluation",
            timed([str(vpy), "-c", EVAL], env=env, warmup=False))


def _sigmas(path: Path) -> str:
    d = json.loads(path.read_text())
    return ", ".join(f"{c.get('sigma', c.get('metrics', {}).get('sigma')):.4f}"
                     for c in d["channels"])


def fits() -> None:
    data = DATA / "minidiff" / f"{FIT_FILE}.astm"
    if not data.is_file():
        print(f"\n(fit comparison skipped: {data} not found; set ROUGHBRDF_SHARED_DATA)")
        return
    print(f"\nEnd to end: TR75 fitted to the 3 channels of {FIT_FILE}.astm, relative loss with "
          f"a free scale K, {FIT_STARTS} starts\n")
    print("| what | median (s) | min (s) | runs | sigma per channel |")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory(prefix="roughbrdf-fit-") as tmp:
        out = Path(tmp)
        script = [sys.executable, str(HERE / "fit_by_hand.py"), str(data),
                  str(out / "hand.json"), "--starts", str(FIT_STARTS)]
        row("SciPy script by hand (`benchmarks/fit_by_hand.py`)",
            timed(script, repeat=REPEAT_FIT), _sigmas(out / "hand.json"))
        one = {**os.environ, **{v: "1" for v in THREAD_VARS}}
        row("SciPy script by hand, one BLAS thread", timed(script, repeat=REPEAT_FIT, env=one),
            _sigmas(out / "hand.json"))
        # --keep-extrapolated: every sample, as the script by hand fits them
        fit = [*_cli(), "fit", str(data), "-m", "trowbridge-reitz-1975", "--free-scale",
               "--starts", str(FIT_STARTS), "--force", "--keep-extrapolated"]
        row("`roughbrdf fit --no-plots` (fit.json, report.txt)",
            timed([*fit, "--no-plots", "-o", str(out / "np")], repeat=REPEAT_FIT),
            _sigmas(out / "np" / "fit.json"))
        row("`roughbrdf fit` (with its 3 figures)",
            timed([*fit, "-o", str(out / "p")], repeat=REPEAT_FIT),
            _sigmas(out / "p" / "fit.json"))


def main() -> None:
    print(f"load average before: {_load()}\n")
    startup()
    fits()
    print(f"\nload average after: {_load()}")


if __name__ == "__main__":
    main()
