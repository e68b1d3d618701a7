"""``roughbrdf explore`` in a real headless browser (Debian's Chromium through selenium).

The page loads without a console error for a measurement alone, a model alone and a fit; every
view draws (its plot element's pixels are not blank: WebGL canvases for the 3-D views, SVG for
the others); a typed or slid parameter redraws the lobe with the values ``model.brdf`` gives at
the drawn angles (read back from the page's figure); a data point on the page is the file's
value; a value outside a parameter's domain is a message; a bad file is one message; "Fit"
runs in the background and shows its report; "Export" writes into ``--out``.

Chromium runs with pinned flags (as ``tests/catalogue/test_catalogue_summary.py``); WebGL is
SwiftShader's (``--use-angle=swiftshader --enable-unsafe-swiftshader``: software rendering, no
GPU needed). One browser serves the module; each server runs in a thread on a free port.
"""

from __future__ import annotations

import base64
import io
import json
import math
import shutil
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("dash", reason="the explore extra (pip install roughbrdf[explore])")

from chromium import WEBGL, chromium  # noqa: E402

import roughbrdf as rb  # noqa: E402
from roughbrdf.explore.app import build_app  # noqa: E402
from roughbrdf.explore.app_state import load_session  # noqa: E402
from roughbrdf.explore.figures import figure_values  # noqa: E402
from roughbrdf.explore.server import bind  # noqa: E402

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="browser tests that fit: ~40 s per fit in plain Python")

DATA = Path(__file__).parents[1] / "data"
ZEMAX = DATA / "zemax" / "AnoBlackNiTEonINVAR.bsdf"
#: seconds the page may take to reach a state before the test counts it as hung (a first
#: evaluation may compile kernels; not a speed figure)
HANG = 240
@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    """Headless Debian Chromium with software WebGL (tests/chromium.py)."""
    with chromium(WEBGL) as driver:
        yield driver


@pytest.fixture
def serve() -> Iterator[Callable[..., Any]]:
    """``serve(**load_session arguments)`` -> a server in a thread; shut down afterwards."""
    servers: list[Any] = []

    def start(*args: Any, **kwargs: Any) -> Any:
        server = bind(build_app(load_session(*args, **kwargs)).server, port=0)
        server.start_thread()
        servers.append(server)
        return server

    yield start
    for server in servers:
        server.shutdown()


def _wait(driver: Any, script: str, *args: Any, what: str = "the page") -> Any:
    give_up = time.monotonic() + HANG
    while time.monotonic() < give_up:
        value = driver.execute_script(script, *args)
        if value:
            return value
        time.sleep(0.1)
    raise AssertionError(f"{what}: not reached in {HANG} s ({script[:80]})")


def _open(driver: Any, server: Any) -> None:
    driver.get_log("browser")  # drop earlier entries
    driver.get(server.url)
    _wait(driver, "return document.querySelector('h2') !== null && "
                  "document.querySelector('._dash-loading') === null", what="the layout")


def _severe(driver: Any) -> list[dict[str, Any]]:
    return [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]


_GRAPH = "var g = document.querySelector('#' + arguments[0] + ' .js-plotly-plot'); "


def _drawn(driver: Any, graph: str) -> bool:
    return bool(driver.execute_script(_GRAPH + "return g !== null && g.data !== undefined && "
                                      "g.data.length > 0 && g._fullLayout !== undefined",
                                      graph))


def _decode(obj: Any) -> Any:
    """Plotly's typed arrays (``{"dtype", "bdata", "shape"}``) as NumPy arrays."""
    if isinstance(obj, dict):
        if "bdata" in obj and "dtype" in obj:
            arr = np.frombuffer(base64.b64decode(obj["bdata"]), dtype=obj["dtype"])
            shape = obj.get("shape")
            if shape is not None:
                dims = [int(s) for s in str(shape).split(",")] if isinstance(shape, str) \
                    else list(shape)
                arr = arr.reshape(dims)
            return arr
        return {k: _decode(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_decode(v) for v in obj]
    return obj


def _values(driver: Any, graph: str) -> dict[str, dict[str, np.ndarray]]:
    """The numbers the page's figure ``graph`` holds (its traces' data, as drawn)."""
    text = driver.execute_script(_GRAPH + "return JSON.stringify({data: g.data});", graph)
    return figure_values(_decode(json.loads(text)))


def _not_blank(driver: Any, graph: str) -> int:
    """How many distinct colours the drawn plot area of ``graph`` shows (a blank one: 1)."""
    from PIL import Image

    element = driver.find_element("css selector", f"#{graph} .js-plotly-plot")
    image = Image.open(io.BytesIO(element.screenshot_as_png)).convert("RGB")
    return len(image.getcolors(maxcolors=1 << 24) or [])


def _tab(driver: Any, label: str) -> None:
    driver.find_element("xpath", f"//*[contains(@class, 'tab') and normalize-space()="
                                 f"'{label}']").click()


def _draws(driver: Any, view: str, label: str) -> None:
    _tab(driver, label)
    _wait(driver, _GRAPH + "return g !== null && g.data !== undefined && g.data.length > 0",
          f"g-{view}", what=f"the {label} view")
    if view in ("lobe", "compare"):  # WebGL scenes
        _wait(driver, _GRAPH + "return g.querySelectorAll('canvas').length > 0", f"g-{view}",
              what=f"the {label} canvas")
    else:
        assert driver.execute_script(_GRAPH + "return g.querySelectorAll('svg path').length",
                                     f"g-{view}") > 0
    time.sleep(0.3)  # the drawing of the frame the figure data is already in
    assert _not_blank(driver, f"g-{view}") > 20, f"{label}: blank"
    message = driver.execute_script("return document.getElementById(arguments[0])"
                                    ".textContent", f"msg-{view}")
    assert message == "", f"{label}: {message}"


def _type(driver: Any, name: str, value: str) -> None:
    from selenium.webdriver.common.keys import Keys

    field = driver.find_element("css selector", f"input[id*='\"name\":\"{name}\"']"
                                                f"[id*='\"role\":\"input\"']")
    field.send_keys(Keys.CONTROL, "a")
    field.send_keys(value, Keys.ENTER)


# --------------------------------------------------------------------------------------------
def test_a_measurement_alone_loads_draws_and_shows_the_files_values(
        browser: Any, serve: Callable[..., Any]) -> None:
    _open(browser, serve(str(ZEMAX)))
    for view, label in (("cuts", "In/cross-plane cuts"), ("maps", "Hemisphere maps")):
        _draws(browser, view, label)
    assert _severe(browser) == []
    meas = rb.read(ZEMAX)
    _tab(browser, "In/cross-plane cuts")
    _wait(browser, _GRAPH + "return g !== null && g.data !== undefined", "g-cuts")
    traces = {k: v for k, v in _values(browser, "g-cuts").items() if k.startswith("data ")}
    assert traces, "no data trace"
    checked = 0
    for name, trace in traces.items():
        inc = float(name.split("θi = ")[1].split("°")[0])
        for tr, ph, value in zip(trace["theta_r_deg"], trace["phi_deg"], trace["value"],
                                 strict=True):
            # the file's sample at this geometry (angles as the page shows them, degrees)
            hit = (np.abs(np.degrees(meas.theta_i) - inc) < 1e-6) \
                & (np.abs(np.degrees(meas.theta_r) - tr) < 1e-6) \
                & (np.abs(np.degrees(meas.phi) - ph) < 1e-6)
            assert hit.sum() == 1, (name, tr, ph)
            assert value == meas.values[hit, 0][0]  # the file's number, exactly
            checked += 1
    assert checked > 50


def test_a_model_alone_draws_every_view_and_follows_its_parameters(
        browser: Any, serve: Callable[..., Any]) -> None:
    _open(browser, serve(model="microfacet", params={"alpha": 0.2, "n": 1.5}))
    views = (("lobe", "3-D lobe"), ("cuts", "In/cross-plane cuts"),
             ("maps", "Hemisphere maps"), ("albedo", "Albedo (TIS)"),
             ("mueller", "Mueller / DoLP"), ("compare", "Compare"))
    for view, label in views:
        _draws(browser, view, label)
    assert _severe(browser) == []
    _tab(browser, "3-D lobe")
    _wait(browser, _GRAPH + "return g !== null && g.data !== undefined", "g-lobe")
    before = _values(browser, "g-lobe")["microfacet"]["value"]
    _type(browser, "alpha", "0.35")
    _wait(browser, _GRAPH + "return g !== null && g.data !== undefined && "
                            "JSON.stringify(g.data[0].customdata) !== arguments[1]",
          "g-lobe", json.dumps(None), what="the redraw")
    give_up = time.monotonic() + HANG
    while time.monotonic() < give_up:  # until the page holds the new lobe
        lobe = _values(browser, "g-lobe")["microfacet"]
        if lobe["value"].shape != before.shape or not np.array_equal(
                np.nan_to_num(lobe["value"]), np.nan_to_num(before)):
            break
        time.sleep(0.1)
    model = rb.model("microfacet", alpha=0.35, n=1.5)
    expected = model.brdf(math.radians(30.0), np.radians(lobe["theta_r_deg"]),
                          np.radians(lobe["phi_deg"]))
    ok = np.isfinite(expected)
    assert ok.sum() > 100
    np.testing.assert_allclose(lobe["value"][ok], expected[ok], rtol=1e-12)
    assert not np.allclose(before[ok], expected[ok])  # it did change
    # the incidence control: typed degrees become the drawn lobe's incidence
    _type(browser, "__theta_i", "50")
    _wait(browser, "return document.querySelector('#g-lobe .gtitle') !== null && "
                   "document.querySelector('#g-lobe .gtitle').textContent.includes('50')",
          what="the incidence redraw")
    lobe = _values(browser, "g-lobe")["microfacet"]
    expected = model.brdf(math.radians(50.0), np.radians(lobe["theta_r_deg"]),
                          np.radians(lobe["phi_deg"]))
    ok = np.isfinite(expected)
    np.testing.assert_allclose(lobe["value"][ok], expected[ok], rtol=1e-12)
    # the slider: its top end (the key End) is alpha's upper search bound, mirrored in the
    # typed field and drawn
    from selenium.webdriver.common.keys import Keys

    top = {p.name: p for p in model.parameters}["alpha"].bounds[1]
    browser.find_element("css selector", "[id='{\"name\":\"alpha\",\"role\":\"slider\"}'] "
                                         "[role=slider]").send_keys(Keys.END)
    _wait(browser, "return document.getElementById('{\"name\":\"alpha\",\"role\":\"input\"}')"
                   ".value === arguments[0]", f"{top:g}", what="the typed field following")
    steep = rb.model("microfacet", alpha=top, n=1.5)
    give_up = time.monotonic() + HANG
    while time.monotonic() < give_up:
        lobe = _values(browser, "g-lobe")["microfacet"]
        expected = steep.brdf(math.radians(50.0), np.radians(lobe["theta_r_deg"]),
                              np.radians(lobe["phi_deg"]))
        ok = np.isfinite(expected)
        if np.allclose(lobe["value"][ok], expected[ok], rtol=1e-12):
            break
        time.sleep(0.1)
    np.testing.assert_allclose(lobe["value"][ok], expected[ok], rtol=1e-12)
    # a typed value outside the parameter's domain: a message, the model kept
    _type(browser, "alpha", "-1")
    text = _wait(browser, "return document.getElementById('param-msg').textContent",
                 what="the domain message")
    assert "alpha" in text and "domain" in text
    assert _severe(browser) == []


def test_a_fit_loads_fits_from_here_and_exports(browser: Any, serve: Callable[..., Any],
                                                tmp_path: Path) -> None:
    data = tmp_path / "ano.bsdf"
    shutil.copy(ZEMAX, data)
    res = rb.fit(rb.model("lambertian"), rb.read(data), starts=1, progress=False)
    res.save(tmp_path / "fit", plots=False)
    out = tmp_path / "out"
    out.mkdir()
    _open(browser, serve(fit_dir=str(tmp_path / "fit"), out=str(out)))
    _draws(browser, "lobe", "3-D lobe")
    _draws(browser, "cuts", "In/cross-plane cuts")
    report = browser.find_element("id", "fit-report").text
    assert "rho" in report
    assert _severe(browser) == []
    browser.find_element("id", "fit-start").click()
    status = _wait(browser, "var t = document.getElementById('fit-status').textContent; "
                            "return t.startsWith('fit finished') ? t : '';", what="the fit")
    assert "1 of 1" in status
    assert "rho" in browser.find_element("id", "fit-report").text
    browser.find_element("id", "export-go").click()
    text = _wait(browser, "return document.getElementById('export-msg').textContent",
                 what="the export")
    assert "wrote" in text and [p.name for p in out.iterdir()] == ["model.bsdf"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ano.bsdf", "fit", "out"]
    browser.find_element("id", "export-go").click()  # the same name again: refused
    _wait(browser, "return document.getElementById('export-msg').textContent"
                   ".startsWith('not exported')", what="the refusal")
    assert [p.name for p in out.iterdir()] == ["model.bsdf"]
    assert _severe(browser) == []


@pytest.mark.parametrize("case", ["bad file", "fit input gone"])
def test_a_bad_input_is_one_message_on_the_page(browser: Any, serve: Callable[..., Any],
                                                tmp_path: Path, case: str) -> None:
    if case == "bad file":
        culprit = tmp_path / "broken.astm"
        culprit.write_text("not an ASTM file\n")
        server = serve(str(culprit))
    else:
        culprit = tmp_path / "ano.bsdf"
        shutil.copy(ZEMAX, culprit)
        rb.fit(rb.model("lambertian"), rb.read(culprit), starts=1, progress=False).save(
            tmp_path / "fit", plots=False)
        culprit.unlink()
        server = serve(fit_dir=str(tmp_path / "fit"))
    _open(browser, server)
    messages = browser.execute_script("return Array.from(document.querySelectorAll("
                                      "'.rb-error')).map(e => e.textContent)")
    assert len(messages) == 1 and culprit.name in messages[0]
    body = browser.execute_script("return document.body.innerText")
    assert "Traceback" not in body and body.count("error:") == 1
    assert _severe(browser) == []
