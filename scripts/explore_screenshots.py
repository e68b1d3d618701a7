"""The screenshots of ``docs/explore.md``: one PNG per view of ``roughbrdf explore``.

``.venv/bin/python scripts/explore_screenshots.py [--out docs/img]`` (about a minute). Fits
``coated`` to the Mini-Diff paint ``C2_Black`` (``../shared/data``, or
``ROUGHBRDF_SHARED_DATA``; without it the committed Zemax file
``tests/data/zemax/AnoBlackNiTEonINVAR.bsdf``), saves the fit into ``out/C2_Black`` of a
temporary folder, runs ``roughbrdf explore --fit out/C2_Black --no-browser`` there (the fit's
measurement re-read from the path its ``fit.json`` records) and opens its address in Debian's
headless Chromium (selenium; the pinned flags and SwiftShader WebGL of
``tests/explore/test_explore_browser.py``) at a fixed window size (:data:`WINDOW`). For each view
(3-D lobe, cuts, hemisphere maps, albedo, Mueller, compare) it opens the tab, waits for the
figure and its drawing, checks that the plot is not blank and saves the window as
``explore_<view>.png``. For the compare view, ``alpha`` is first typed as twice its fitted value,
so that the current model (A) and the fit (B) differ, and shown side by side. The lobes'
radius is logarithmic (the "log" box: a glossy fit's spike beside its diffuse floor). Needs
Dash (``pip install roughbrdf[explore]``), selenium, ``chromium`` and ``chromedriver``.
"""

from __future__ import annotations

import argparse
import io
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import roughbrdf as rb

HERE = Path(__file__).resolve().parent
SHARED = Path(os.environ.get("ROUGHBRDF_SHARED_DATA", HERE.parent.parent / "shared" / "data"))
PAINT = SHARED / "minidiff" / "C2_Black.astm"
ZEMAX = HERE.parent / "tests" / "data" / "zemax" / "AnoBlackNiTEonINVAR.bsdf"
MODEL = "coated"
#: the browser window (CSS pixels): every screenshot has this size
WINDOW = (1500, 1250)
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMEDRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"
#: as tests/explore/test_explore_browser.py (WebGL by SwiftShader: software, no GPU)
FLAGS = ("--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
         "--disable-quic", "--no-first-run", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--hide-scrollbars",
         "--force-device-scale-factor=1")
#: (file name part, tab label, WebGL scene) of each view
VIEWS = (("lobe", "3-D lobe", True), ("cuts", "In/cross-plane cuts", False),
         ("maps", "Hemisphere maps", False), ("albedo", "Albedo (TIS)", False),
         ("mueller", "Mueller / DoLP", False), ("compare", "Compare", True))
#: seconds a page state may take before the script gives up (a first draw compiles kernels)
HANG = 240.0
_GD = "var gd = document.querySelector('#' + arguments[0] + ' .js-plotly-plot'); "


@contextmanager
def explorer(args: list[str], cwd: Path) -> Iterator[str]:
    """The running ``roughbrdf explore ARGS --no-browser`` (in ``cwd``): its address; Ctrl-C
    at the end."""
    cmd = [sys.executable, "-m", "roughbrdf.cli", "explore", *args, "--no-browser"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True, cwd=cwd)
    try:
        assert proc.stdout is not None
        url = proc.stdout.readline().strip()  # the one stdout line: the address with the token
        if not url.startswith("http://"):
            raise RuntimeError(f"roughbrdf explore did not print its address ({url!r})")
        yield url
    finally:
        proc.send_signal(signal.SIGINT)  # Ctrl-C: the command's clean stop
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:  # a hung server: ended all the same
            proc.kill()
            proc.wait()


@contextmanager
def chromium() -> Iterator[Any]:
    """Headless Debian Chromium at :data:`WINDOW` (the viewport, not the outer window)."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    profile = tempfile.mkdtemp(prefix="rb-shots-chromium-")
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for flag in (*FLAGS, f"--window-size={WINDOW[0]},{WINDOW[1]}",
                 f"--user-data-dir={profile}"):
        opts.add_argument(flag)
    driver = webdriver.Chrome(options=opts, service=Service(executable_path=CHROMEDRIVER))
    try:
        # the viewport at exactly WINDOW, whatever the browser's frame takes
        driver.execute_cdp_cmd("Emulation.setDeviceMetricsOverride", {
            "width": WINDOW[0], "height": WINDOW[1], "deviceScaleFactor": 1, "mobile": False})
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)


def wait(driver: Any, script: str, *args: Any, what: str = "the page") -> Any:
    """The first truthy value of ``script`` in the page, polled every 100 ms."""
    give_up = time.monotonic() + HANG
    while time.monotonic() < give_up:
        value = driver.execute_script(script, *args)
        if value:
            return value
        time.sleep(0.1)
    raise RuntimeError(f"{what}: not reached in {HANG:g} s")


def fit_folder(folder: Path) -> None:
    """``coated`` fitted to the paint (else the Zemax file), saved into ``folder`` (its
    ``fit.json`` names the measurement, which the explorer re-reads)."""
    data = PAINT if PAINT.is_file() else ZEMAX
    if data is ZEMAX:
        print(f"note: {PAINT} not found (set ROUGHBRDF_SHARED_DATA): fitting {ZEMAX.name}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the plausibility notes are the fit report's
        res = rb.fit(MODEL, rb.read(data), progress=False)
    res.save(folder, plots=False)


def _colours(driver: Any, view: str) -> int:
    """How many colours the plot element of ``view`` shows (a blank plot: a handful)."""
    from PIL import Image

    element = driver.find_element("css selector", f"#g-{view} .js-plotly-plot")
    image = Image.open(io.BytesIO(element.screenshot_as_png)).convert("RGB")
    return len(image.getcolors(maxcolors=1 << 24) or [])


def _fitted_alpha(driver: Any) -> float:
    return float(driver.find_element("css selector", "input[id*='\"name\":\"alpha\"']"
                                                     "[id*='\"role\":\"input\"']")
                 .get_attribute("value"))


def _type(driver: Any, name: str, value: str) -> None:
    from selenium.webdriver.common.keys import Keys

    field = driver.find_element("css selector", f"input[id*='\"name\":\"{name}\"']"
                                                f"[id*='\"role\":\"input\"']")
    field.send_keys(Keys.CONTROL, "a")
    field.send_keys(value, Keys.ENTER)


def shoot(driver: Any, url: str, out: Path) -> list[Path]:
    """One PNG per view into ``out``."""
    driver.get(url)
    wait(driver, "return document.querySelector('h2') !== null && "
                 "document.querySelector('._dash-loading') === null", what="the layout")
    # the lobes' radius in decades: a glossy fit's specular spike beside its diffuse floor
    driver.find_element("css selector", "#view-log input[type=checkbox]").click()
    written = []
    for view, label, webgl in VIEWS:
        if view == "compare":  # the current model away from the fit, then compared with it
            _type(driver, "alpha", f"{2 * _fitted_alpha(driver):.4g}")
            # side by side: two scenes on one fixed scale (the overlay's scene takes the data's
            # aspect, in which a narrow linear spike puts the camera inside the box)
            driver.find_element("css selector", "#view-compare input[value=side]").click()
        driver.find_element("xpath", f"//*[contains(@class, 'tab') and normalize-space()="
                                     f"'{label}']").click()
        wait(driver, _GD + "return gd !== null && gd.data !== undefined && gd.data.length > 0 "
                           "&& gd._fullLayout !== undefined", f"g-{view}", what=label)
        if webgl:
            wait(driver, _GD + "return gd.querySelectorAll('canvas').length > 0", f"g-{view}",
                 what=f"{label}: its WebGL canvas")
        time.sleep(2.0)  # the last redraw (the compare view's new alpha) and its frame
        message = driver.execute_script("return document.getElementById(arguments[0])"
                                        ".textContent", f"msg-{view}")
        if message and not message.startswith("warning"):
            raise RuntimeError(f"{label}: the page says {message!r}")
        if _colours(driver, view) <= 20:
            raise RuntimeError(f"{label}: the plot is blank")
        path = out / f"explore_{view}.png"
        driver.save_screenshot(str(path))
        written.append(path)
        print(f"wrote {path}", flush=True)
    return written


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--out", type=Path, default=HERE.parent / "docs" / "img",
                        help="folder of the PNGs (default docs/img)")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="rb-shots-") as tmp:
        name = "C2_Black" if PAINT.is_file() else ZEMAX.stem
        fit_folder(Path(tmp) / "out" / name)  # the page's title: "fit out/NAME"
        with explorer(["--fit", f"out/{name}"], Path(tmp)) as url, chromium() as driver:
            shoot(driver, url, args.out)


if __name__ == "__main__":
    main()
