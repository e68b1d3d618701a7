"""Explorer redraw speed: from a parameter control's change to the redrawn plot data, in the page.

Issue 22's budget: for a Mini-Diff-sized measurement (``C2_Black``: 12,964 geometries x 3
channels) and a 64 x 256 lobe grid, at most 150 ms on an AVX-512 machine and 300 ms on a
2-core AVX2 one, from a control's change event to the redrawn plot data, measured in the
browser with ``performance.now()``.

How: ``roughbrdf explore C2_Black.astm --model coated --no-browser`` runs in a subprocess (the
real command, its Werkzeug server); Debian's headless Chromium (selenium, the pinned flags and
SwiftShader WebGL of ``tests/explore/test_explore_browser.py``) opens the printed address. Each
measurement types a new ``alpha`` into the parameter's field and presses Enter (the field's
change event, ``dcc.Input(debounce=True)``): the page records ``performance.now()`` at that
Enter (a capture listener on the document), at the moment Plotly assigns the graph's new
``data`` (an accessor on the graph div: the new figure has arrived and is being drawn) and at
the ``plotly_afterplot`` event that follows (drawn, WebGL included); the new data must differ
from the previous ones (checked in the page). ``alpha`` alternates between two values; the
first :data:`WARM` changes (kernel compilation, first WebGL set-up) are not counted; median and
range of :data:`REPEAT`. The path measured is the app's: the typed field -> the model callback
(server) -> ``model-store`` -> the view callback (server: model evaluation, figure, JSON) ->
Plotly in the page.

The lobe grid: the app draws ``figures.lobe_3d`` at its default ``resolution=61`` (61 x 61)
and has no option for it; the 64 x 256 rows run the command with ``figures.lobe_3d`` given
``resolution=64, n_phi=256`` (``--lobe-grid 64x256`` of this file's ``--serve`` mode, which
wraps the function before calling the command line); the app's default 61 x 61 is a reference
row, and so are the cuts and hemisphere-map views, which draw the measurement's data.

Printed: a Markdown table with the CPU (``/proc/cpuinfo`` model name), its widest vector unit
(``avx512f``/``avx2``), the cores, the load average before and after (a loaded 2-core machine
doubles every figure), and the date (UTC). Needs ``../shared/data`` (or
``ROUGHBRDF_SHARED_DATA``), Dash (``pip install roughbrdf[explore]``), selenium, ``chromium``
and ``chromedriver``; prints a note and returns without one of them.

``make bench BENCH_ARGS=bench_explore``, or ``.venv/bin/python benchmarks/bench_explore.py
[--repeat N]``.
"""

from __future__ import annotations

import argparse
import datetime
import functools
import os
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))  # run.py loads by path
from machine import cpu_name, load, vector_width  # noqa: E402

HERE = Path(__file__).resolve().parent
DATA = Path(os.environ.get("ROUGHBRDF_SHARED_DATA", HERE.parent.parent / "shared" / "data"))
FILE = "C2_Black"
#: changes timed per row, and changes before them that are not counted
REPEAT = 10
WARM = 2
#: the typed values of ``alpha`` (coated), alternated so that every change redraws
ALPHAS = ("0.08", "0.12")
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMEDRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"
#: as tests/explore/test_explore_browser.py (WebGL by SwiftShader: software, no GPU)
FLAGS = ("--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
         "--disable-quic", "--no-first-run", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--window-size=1400,1000")
#: seconds a page state may take before the run counts as hung (not a speed figure)
HANG = 240.0
TABS = {"lobe": "3-D lobe", "cuts": "In/cross-plane cuts", "maps": "Hemisphere maps"}








# -- the explorer in a subprocess --------------------------------------------------------------
def serve(argv: list[str]) -> int:
    """``--serve [--lobe-grid NxM] -- ARGS``: ``roughbrdf ARGS`` with the lobe view's grid
    ``N x M`` (``figures.lobe_3d(resolution=N, n_phi=M)``; the app has no option for it)."""
    grid = None
    if argv[:1] == ["--lobe-grid"]:
        grid, argv = argv[1], argv[2:]
    if argv[:1] == ["--"]:
        argv = argv[1:]
    if grid is not None:
        from roughbrdf.explore import figures

        n_theta, n_phi = (int(s) for s in grid.lower().split("x"))
        figures.lobe_3d = functools.partial(  # type: ignore[assignment]
            figures.lobe_3d, resolution=n_theta, n_phi=n_phi)
    from roughbrdf.cli import main

    return main(argv)


@contextmanager
def explorer(args: list[str], grid: str | None) -> Iterator[str]:
    """The running ``roughbrdf explore ARGS --no-browser``: its address; Ctrl-C at the end."""
    cmd = [sys.executable, str(Path(__file__).resolve()), "--serve"]
    cmd += ["--lobe-grid", grid] if grid else []
    cmd += ["--", "explore", *args, "--no-browser"]
    log = tempfile.TemporaryFile(mode="w+")  # the server's stderr: shown if it fails
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=log, text=True)
    try:
        assert proc.stdout is not None
        url = proc.stdout.readline().strip()  # the one stdout line: the address with the token
        if not url.startswith("http://"):
            raise RuntimeError(f"roughbrdf explore did not print its address ({url!r})")
        yield url
    except BaseException:
        log.seek(0)
        sys.stderr.write(log.read())
        raise
    finally:
        proc.send_signal(signal.SIGINT)  # Ctrl-C: the command's clean stop (130)
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:  # a hung server: ended, the bench goes on
            proc.kill()
            proc.wait()
        log.close()


@contextmanager
def chromium(width: int = 1400, height: int = 1000) -> Iterator[Any]:
    """Headless Debian Chromium through the system chromedriver (nothing downloaded)."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    profile = tempfile.mkdtemp(prefix="rb-bench-chromium-")
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for flag in (*FLAGS[:-1], f"--window-size={width},{height}", f"--user-data-dir={profile}"):
        opts.add_argument(flag)
    driver = webdriver.Chrome(options=opts, service=Service(executable_path=CHROMEDRIVER))
    try:
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)


def wait(driver: Any, script: str, *args: Any, what: str = "the page") -> Any:
    """The first truthy value of ``script`` in the page, polled every 20 ms."""
    give_up = time.monotonic() + HANG
    while time.monotonic() < give_up:
        value = driver.execute_script(script, *args)
        if value:
            return value
        time.sleep(0.02)
    raise RuntimeError(f"{what}: not reached in {HANG:g} s")


# -- the measurement in the page ---------------------------------------------------------------
_GD = "var gd = document.querySelector('#' + arguments[0] + ' .js-plotly-plot'); "
#: arms one measurement: the Enter that fires the change, the assignment of the graph's new
#: data, the afterplot that follows; the previous data kept to check that they changed
_ARM = _GD + """
var r = window.__rb = {t0: null, tData: null, tPlot: null, changed: null, server: null,
                       before: JSON.stringify(gd.data)};
performance.clearResourceTimings();
if (!window.__rbKey) {
  document.addEventListener('keydown', function (e) {
    var r = window.__rb;
    if (e.key === 'Enter' && r && r.t0 === null) { r.t0 = performance.now(); }
  }, true);
  window.__rbKey = true;
}
function inFlight(t0, t1) {  // ms in [t0, t1] with a callback request open (their union)
  var spans = performance.getEntriesByType('resource').filter(function (e) {
    return e.name.indexOf('_dash-update-component') >= 0 && e.startTime >= t0
      && e.responseEnd <= t1; }).map(function (e) { return [e.startTime, e.responseEnd]; });
  spans.sort(function (a, b) { return a[0] - b[0]; });
  var total = 0, end = -Infinity;
  spans.forEach(function (s) {
    if (s[1] > end) { total += s[1] - Math.max(s[0], end); end = s[1]; } });
  return total;
}
if (!gd.__rbHooked) {
  var current = gd.data;
  Object.defineProperty(gd, 'data', {configurable: true, enumerable: true,
    get: function () { return current; },
    set: function (v) {
      current = v; var r = window.__rb;
      if (r && r.t0 !== null && r.tData === null) { r.tData = performance.now(); }
    }});
  gd.on('plotly_afterplot', function () {
    var r = window.__rb;
    if (r && r.tData !== null && r.tPlot === null) {
      r.tPlot = performance.now(); r.changed = JSON.stringify(gd.data) !== r.before;
      r.server = inFlight(r.t0, r.tData);
    }
  });
  gd.__rbHooked = true;
}
return true;
"""
_DONE = "var r = window.__rb; return r && r.tPlot !== null ? " \
        "[r.tData - r.t0, r.tPlot - r.t0, r.server, r.changed] : null;"


def _type(driver: Any, name: str, value: str) -> None:
    from selenium.webdriver.common.keys import Keys

    field = driver.find_element("css selector", f"input[id*='\"name\":\"{name}\"']"
                                                f"[id*='\"role\":\"input\"']")
    field.send_keys(Keys.CONTROL, "a")
    field.send_keys(value, Keys.ENTER)


def _open_view(driver: Any, url: str, view: str) -> None:
    driver.get(url)
    wait(driver, "return document.querySelector('h2') !== null && "
                 "document.querySelector('._dash-loading') === null", what="the layout")
    driver.find_element("xpath", f"//*[contains(@class, 'tab') and normalize-space()="
                                 f"'{TABS[view]}']").click()
    wait(driver, _GD + "return gd !== null && gd.data !== undefined && gd.data.length > 0",
         f"g-{view}", what=f"the {view} view")


def _grid_shape(driver: Any) -> str:
    """The lobe surface's grid as drawn (rows x columns of its ``z``)."""
    shape = driver.execute_script(_GD + "var z = gd._fullData[0].z; "
                                  "return [z.length, z[0].length];", "g-lobe")
    return f"{shape[0]}x{shape[1]}"


def measure(driver: Any, url: str, view: str, repeat: int) -> dict[str, list[float]]:
    """``repeat`` changes of ``alpha`` on ``view``: ms to the new plot data, to afterplot,
    and in callback requests (HTTP + server) before the new data."""
    _open_view(driver, url, view)
    out: dict[str, list[float]] = {"data": [], "plot": [], "server": []}
    for k in range(WARM + repeat):
        driver.execute_script(_ARM, f"g-{view}")
        _type(driver, "alpha", ALPHAS[k % 2])
        t_data, t_plot, server, changed = wait(driver, _DONE, what=f"the {view} redraw")
        if not changed:
            raise RuntimeError(f"the {view} view redrew the same data (alpha {ALPHAS[k % 2]})")
        if k >= WARM:
            for key, value in (("data", t_data), ("plot", t_plot), ("server", server)):
                out[key].append(value)
    return out


def _cell(ms: list[float]) -> str:
    return f"{statistics.median(ms):.0f} ({min(ms):.0f}-{max(ms):.0f})"


def _missing(path: Path) -> str:
    if not path.is_file():
        return f"{path} not found (set ROUGHBRDF_SHARED_DATA)"
    for module in ("dash", "selenium"):
        try:
            __import__(module)
        except ImportError:
            return f"{module} is not installed (pip install 'roughbrdf[explore]' selenium)"
    if not (Path(CHROMIUM).exists() and Path(CHROMEDRIVER).exists()):
        return f"Chromium and chromedriver not found ({CHROMIUM}, {CHROMEDRIVER})"
    return ""


def main(repeat: int = REPEAT) -> None:
    path = DATA / "minidiff" / f"{FILE}.astm"
    print("\n## Explorer redraw speed (bench_explore)")
    why = _missing(path)
    if why:
        print(f"skipped: {why}")
        return
    import roughbrdf as rb

    meas = rb.read(path)
    before = load()
    rows: list[tuple[str, str, dict[str, list[float]]]] = []
    args = [str(path), "--model", "coated"]
    with chromium() as driver:
        for grid, views in (("64x256", ("lobe", "cuts", "maps")), (None, ("lobe",))):
            with explorer(args, grid) as url:
                for view in views:
                    times = measure(driver, url, view, repeat)
                    shape = _grid_shape(driver) if view == "lobe" else "-"
                    label = f"{TABS[view]}" + (" (the target)" if grid and view == "lobe"
                                               else " (app default grid)" if view == "lobe"
                                               else " (reference: draws the data)")
                    rows.append((label, shape, times))
    after = load()
    print(f"\n`roughbrdf explore {FILE}.astm --model coated` ({meas.n_samples} geometries x "
          f"{len(meas.channels)} channels), headless Chromium (SwiftShader WebGL); a typed "
          f"`alpha` ({' <-> '.join(ALPHAS)}) + Enter, to the graph's new data and to "
          f"`plotly_afterplot`, `performance.now()` in the page; median (range) of {repeat} "
          f"after {WARM} not counted, ms (callback requests open: the time "
          "in which at least one `_dash-update-component` request was under way, Resource "
          "Timing)\n")
    print(f"CPU: {cpu_name()} ({vector_width()}, {os.cpu_count()} cores); load average "
          f"before {before}, after {after}; "
          f"{datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC; "
          "target (64x256 lobe): <= 150 ms AVX-512, <= 300 ms 2-core AVX2\n")
    print("| view | lobe grid (θr x φ) | change -> new plot data | of which callback requests "
          "open | change -> afterplot (drawn) |\n|---|---|---|---|---|")
    for label, shape, t in rows:
        print(f"| {label} | {shape} | {_cell(t['data'])} | {_cell(t['server'])} | "
              f"{_cell(t['plot'])} |", flush=True)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--serve"]:
        sys.exit(serve(sys.argv[2:]))
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--repeat", type=int, default=REPEAT, help="changes timed per row")
    main(parser.parse_args().repeat)
