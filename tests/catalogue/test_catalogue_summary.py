"""The catalogue summary page: files, contents, escaping, size, and a real browser.

The browser tests open ``summary.html`` in Debian's Chromium, driven by selenium through the
system chromedriver (``/usr/bin/chromedriver``, passed explicitly: selenium's manager never
downloads anything); ``make test`` installs both packages when it runs as root. They skip, with
the reason, only where the two programs are absent.
"""

from __future__ import annotations

import json
import re
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from chromium import chromium

from roughbrdf.catalogue.summary import write_summary
from roughbrdf.output import OverwriteRefused


def make_rows(n: int, folder: Path | None = None, n_figures: int = 0) -> list[dict[str, Any]]:
    """``n`` synthetic rows (2 channels per file); the first ``n_figures`` get a real PNG."""
    rng = np.random.default_rng(1)
    statuses = ["ok"] * 7 + ["not converged", "failed", "skipped (resume)"]
    rows = []
    for i in range(n):
        status = statuses[i % len(statuses)]
        stem, channel = f"sample_{i // 2:06d}", ("red", "nir")[i % 2]
        fit_dir = f"{stem}/{channel}"
        figure = None
        if folder is not None and i < n_figures:
            figure = f"{fit_dir}/fit.png"
            _png(folder / figure, i)
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
            "sha256": f"{i:064x}", "fit_dir": fit_dir, "figure": figure})
    return rows


def _png(path: Path, seed: int) -> None:
    from matplotlib.image import imsave
    path.parent.mkdir(parents=True, exist_ok=True)
    img = np.random.default_rng(seed).uniform(size=(24, 32, 3))
    imsave(path, img)


def _page_data(text: str) -> dict[str, Any]:
    m = re.search(r'<script type="application/json" id="rb-data">(.*?)</script>', text, re.S)
    assert m is not None
    return json.loads(m.group(1))


# --------------------------------------------------------------------------------------------
# files and contents
# --------------------------------------------------------------------------------------------

def test_writes_markdown_and_html(tmp_path: Path) -> None:
    rows = make_rows(20, tmp_path, n_figures=20)
    paths = write_summary(tmp_path, rows, title="My catalogue", max_thumbnails=5)
    assert [p.name for p in paths] == ["summary.md", "summary.html"]
    md, page = (p.read_text(encoding="utf-8") for p in paths)
    assert "# My catalogue" in md and "[summary.html](summary.html)" in md
    assert "| ok | 14 |" in md and "| failed | 2 |" in md and "| not converged | 2 |" in md
    # Markdown punctuation in the data is backslash-escaped (summary.md_text)
    assert "| skipped \\(resume\\) | 2 |" in md
    assert md.count("ValueError: no points") == 2          # every failure, with its error
    assert "[sample\\_000000\\.astm](sample_000000/red)" in md
    assert page.count('class="thumb"') == 5                 # sampled: at most max_thumbnails
    assert 'src="sample_000000/red/fit.png"' in page        # first and last figure included
    assert 'src="sample_000009/nir/fit.png"' in page
    assert page.count("<svg") == 3                          # e, rho_L, rms_log
    data = _page_data(page)
    assert len(data["links"]) == 20 and data["pageSize"] == 100
    assert [c["label"] for c in data["columns"]][-3:] == ["e", "rho_L", "error"]
    assert "http" not in re.sub(r"https?://www\.w3\.org/\S+", "", page)  # fetches nothing


def test_escapes_html_from_the_data(tmp_path: Path) -> None:
    evil = '<img src=x onerror="alert(1)">|&'
    rows = make_rows(4)
    rows[0].update(file=evil + ".astm", status="failed", error="</script><b>boom</b>",
                   fit_dir='x"><script>', figure="javascript:alert(1)")
    rows[1].update(channel=evil, fit_dir="/etc", figure="../a b.png")
    md_path, html_path = write_summary(tmp_path, rows, title="<T&>")
    page, md = html_path.read_text(encoding="utf-8"), md_path.read_text(encoding="utf-8")
    for text in (page, md):
        assert "<img src=x" not in text and "<b>boom" not in text and "<T&>" not in text
    assert page.count("</script>") == 2                     # the page's own two scripts only
    assert "javascript:" not in page and 'href="/etc"' not in page
    assert 'src="../a%20b.png"' in page
    assert '&lt;img src=x onerror="alert\\(1\\)"&gt;\\|&amp;' in md
    data = _page_data(page)                                 # round-trips exactly
    assert data["dicts"]["file"][0] == evil + ".astm"
    assert data["links"][:2] == ['x%22%3E%3Cscript%3E', None]


def test_refuses_to_overwrite(tmp_path: Path) -> None:
    rows = make_rows(3)
    (tmp_path / "summary.html").write_text("mine")
    with pytest.raises(OverwriteRefused):
        write_summary(tmp_path, rows)
    assert not (tmp_path / "summary.md").exists()           # refused before writing anything
    assert (tmp_path / "summary.html").read_text() == "mine"
    write_summary(tmp_path, rows, overwrite=True)
    assert "rb-data" in (tmp_path / "summary.html").read_text()


def test_empty_and_odd_rows(tmp_path: Path) -> None:
    rows = [{"file": "a", "status": "failed", "error": None},
            {"file": "b", "status": "weird", "params": {"x": float("nan"), "y": "abc"}}]
    write_summary(tmp_path / "new", [])
    write_summary(tmp_path, rows)
    md = (tmp_path / "summary.md").read_text()
    assert "| weird | 1 |" in md and "**a**" in md
    assert "No fitted parameters" in (tmp_path / "summary.html").read_text()


def test_hundred_thousand_rows_stay_small(tmp_path: Path) -> None:
    rows = make_rows(100_000)
    _, html_path = write_summary(tmp_path, rows, max_thumbnails=60)
    size = html_path.stat().st_size
    assert size < 200 * len(rows), size                     # measured: 11.2 MB (112 B a row)
    # paged: the rows are data, once (columns, strings through dictionaries); the browser
    # renders one page of them, so the page's markup does not grow with the rows (its time to
    # write and to open: benchmarks/bench_suite_figures.py)
    page = html_path.read_text(encoding="utf-8")
    _, small = write_summary(tmp_path / "small", make_rows(10), max_thumbnails=60)
    markup = small.read_text(encoding="utf-8")
    for tag in ("<tr", "<td", "<a ", "<img"):
        assert page.count(tag) == markup.count(tag), tag
    data = _page_data(page)
    assert data["pageSize"] == 100
    assert all(len(col) == len(rows) for col in data["data"]) and len(data["links"]) == len(rows)
    assert len(data["dicts"]["file"]) == 50_000             # each file name once
    md = (tmp_path / "summary.md").read_text()
    assert "## Fits (first 100 of 100000)" in md and len(md) < 500_000
    assert "| failed | 10000 |" in md and "- … and 9900 more" in md


# --------------------------------------------------------------------------------------------
# a real headless browser
# --------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    """Headless Debian Chromium (tests/chromium.py)."""
    with chromium() as driver:
        yield driver


#: seconds the page's script may take before the test counts it as hung (not a speed figure:
#: benchmarks/bench_suite_figures.py measures that)
HANG = 300


def _open(driver: Any, path: Path) -> None:
    driver.get(path.resolve().as_uri())
    give_up = time.monotonic() + HANG
    while (ready := driver.execute_script("return document.body.dataset.ready")) != "1":
        if time.monotonic() > give_up:  # hung: stop waiting
            break
        time.sleep(0.05)
    assert ready == "1", "the page's script did not finish"


def _column(driver: Any, index: int) -> list[str]:
    return driver.execute_script(
        "var j = arguments[0]; return Array.from(document.querySelectorAll('#rb-table tbody tr'))"
        ".map(function (r) { return r.children[j].textContent; });", index)


def _severe(driver: Any) -> list[dict[str, Any]]:
    return [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]


def test_browser_renders_sorts_pages_and_loads_thumbnails(browser: Any, tmp_path: Path) -> None:
    rows = make_rows(250, tmp_path, n_figures=250)
    _, page = write_summary(tmp_path, rows, page_size=100, max_thumbnails=30)
    browser.get_log("browser")                              # drop earlier entries
    _open(browser, page)
    headers = [h.text for h in browser.find_elements("css selector", "#rb-table th")]
    assert headers[:4] == ["file", "channel", "model", "status"]
    assert len(browser.find_elements("css selector", "#rb-table tbody tr")) == 100
    info = browser.find_element("id", "rb-info")
    assert info.text == "rows 1–100 of 250 (page 1 of 3)"

    col = headers.index("points")
    th = browser.find_elements("css selector", "#rb-table th")[col]
    th.click()
    up = [int(v) for v in _column(browser, col)]
    assert up == sorted(up) and up[0] == 100 and th.get_attribute("aria-sort") == "ascending"
    th.click()
    down = [int(v) for v in _column(browser, col)]
    assert down == sorted(down, reverse=True) and down[0] == 136

    browser.find_element("id", "rb-next").click()
    browser.find_element("id", "rb-next").click()
    assert info.text == "rows 201–250 of 250 (page 3 of 3)"
    assert len(browser.find_elements("css selector", "#rb-table tbody tr")) == 50
    browser.find_element("id", "rb-filter").send_keys("sample_000003")
    assert info.text == "rows 1–2 of 2 (page 1 of 1)"

    thumbs = browser.execute_script(
        "return Array.from(document.images).map(function (i) {"
        " return [i.complete, i.naturalWidth]; });")
    assert len(thumbs) == 30 and all(ok and w > 0 for ok, w in thumbs), thumbs
    assert _severe(browser) == []


def test_browser_hundred_thousand_rows(browser: Any, tmp_path: Path) -> None:
    rows = make_rows(100_000)
    _, page = write_summary(tmp_path, rows)
    browser.get_log("browser")
    _open(browser, page)
    # paged: the DOM holds one page of rows, not 100000 (the times: benchmarks/)
    assert len(browser.find_elements("css selector", "#rb-table tbody tr")) == 100
    elements = browser.execute_script("return document.getElementsByTagName('*').length")
    assert elements < 10_000, elements                     # 100000 rows: over a million
    assert browser.find_element("id", "rb-info").text.endswith("of 100000 (page 1 of 1000)")
    headers = [h.text for h in browser.find_elements("css selector", "#rb-table th")]
    browser.find_elements("css selector", "#rb-table th")[headers.index("rms log")].click()
    vals = [float(v) for v in _column(browser, headers.index("rms log"))]
    assert vals == sorted(vals) and len(vals) == 100
    # all 100000 rows were sorted, not the page shown: the first is the smallest of them all
    smallest = min(r["rms_log"] for r in rows if r["rms_log"] is not None)
    assert vals[0] == pytest.approx(smallest, rel=1e-3), (vals[0], smallest)
    assert len(browser.find_elements("css selector", "#rb-table tbody tr")) == 100
    assert _severe(browser) == []


# --------------------------------------------------------------------------------------------
# the page's style sheet and script are the package's asset files, inlined as they are
# --------------------------------------------------------------------------------------------

def test_page_inlines_the_asset_files(tmp_path: Path) -> None:
    from importlib import resources

    assets = resources.files("roughbrdf.catalogue").joinpath("assets")
    css = assets.joinpath("summary.css").read_text(encoding="utf-8")
    js = assets.joinpath("summary.js").read_text(encoding="utf-8")
    page = write_summary(tmp_path, make_rows(6))[1].read_text(encoding="utf-8")
    style = re.findall(r"<style>\n(.*?)</style>", page, re.S)
    scripts = re.findall(r"<script>\n(.*?)</script>", page, re.S)
    assert style == [css] and scripts == [js]
    assert "aria-sort" in css and 'document.body.dataset.ready = "1"' in js
