"""Headless Debian Chromium for the browser tests, started one way (the flags pinned here).

The flags are those the machine's probe found to work as root on this closed network
(``--no-sandbox``, and no background networking, component updates or sync, whose connection
attempts are refused); WebGL pages (the explorer's 3-D views) add SwiftShader, software WebGL.
A test that cannot have a browser skips with the reason (``make test`` as root installs
Debian's ``chromium`` and ``chromium-driver``).
"""

from __future__ import annotations

import contextlib
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMEDRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"
#: every start: headless, no sandbox (root), nothing that reaches for the network
FLAGS = ("--headless", "--no-sandbox", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--window-size=1400,1000")
#: pages without WebGL
NO_GPU = ("--disable-gpu",)
#: WebGL in software (headless Chromium has no GPU here)
WEBGL = ("--use-angle=swiftshader", "--enable-unsafe-swiftshader")


@contextlib.contextmanager
def chromium(extra: tuple[str, ...] = NO_GPU) -> Iterator[Any]:
    """A selenium driver of headless Chromium with :data:`FLAGS` and ``extra``, its browser
    console log kept; a fresh profile, removed afterwards. Skips the test when Chromium,
    chromedriver or selenium is missing, or Chromium cannot start."""
    if not (Path(CHROMIUM).exists() and Path(CHROMEDRIVER).exists()):
        pytest.skip(f"Chromium and chromedriver not installed ({CHROMIUM}, {CHROMEDRIVER}); "
                    "`make test` as root installs Debian's chromium and chromium-driver")
    webdriver = pytest.importorskip("selenium.webdriver")
    from selenium.common.exceptions import WebDriverException
    from selenium.webdriver.chrome.service import Service

    profile = tempfile.mkdtemp(prefix="rb-chromium-")
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for flag in (*FLAGS, *extra, f"--user-data-dir={profile}"):
        opts.add_argument(flag)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    try:
        driver = webdriver.Chrome(options=opts, service=Service(executable_path=CHROMEDRIVER))
    except WebDriverException as exc:
        shutil.rmtree(profile, ignore_errors=True)
        pytest.skip(f"Chromium cannot start here: {' '.join(str(exc).split())[:300]}")
    try:
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)
