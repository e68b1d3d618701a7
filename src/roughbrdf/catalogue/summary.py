"""The summary page of a catalogue fit: ``summary.md`` and a self-contained ``summary.html``.

:func:`write_summary` takes the rows of a catalogue fit (one dict per file x channel, the
schema below) and writes, in the catalogue folder:

* ``summary.md``: the counts by status, the failures with their errors, a table of the first
  rows with links to their fit folders, and a link to the HTML page;
* ``summary.html``: one file with its CSS and JavaScript inline and the rows embedded as JSON
  (column-wise, repeated strings stored once): a sortable (click a header; numbers sort as
  numbers, text as text), filterable, paged table that draws only the current page (100,000
  rows stay responsive), a contact sheet of at most ``max_thumbnails`` evenly sampled fit
  figures each linking to its fit folder, and a histogram (inline SVG) of every fitted
  parameter and of the residual across the catalogue.

The two pages are one set (:class:`roughbrdf.output.ResultFolder`): added to the folder's set,
or, given ``into=`` (the catalogue's own open set), committed with ``catalogue.csv`` and
``catalogue.json``; a kill leaves both old pages or both new ones.

The page's style sheet and script are package data, ``roughbrdf/catalogue/assets/summary.css``
and ``summary.js`` (:data:`ASSETS`), copied into each page.

The thumbnails are the per-fit PNGs referenced by relative path, not embedded: the page lives
in the catalogue folder beside them, and embedding 60 figures as data URIs would add several
megabytes to a page that must stay small at 100,000 rows. The page fetches nothing else.

Row schema: ``file``, ``channel``, ``model``, ``status`` (``"ok"``, ``"not converged"``,
``"at-search-limit"``, ``"gains-energy"``, ``"failed"``, ``"skipped (resume)"``), ``error`` (str
or None), ``params`` and ``stderr`` ({name: value}), ``search_limits`` (str or None),
``max_albedo``, ``peak_ratio``, ``sigma``, ``rms_log``, ``aic``, ``bic``, ``n_points``,
``n_excluded``, ``elapsed_s``, ``sha256``, ``fit_dir`` (relative to the catalogue folder) and
``figure`` (relative path of the fit's PNG, or None). Missing keys count as None.

Examples
--------
>>> import pathlib, tempfile
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> rows = [{"file": "a.astm", "channel": "550nm", "model": "lambertian", "status": "ok",
...          "params": {"rho": 0.4}, "rms_log": 0.05, "fit_dir": "a/550nm"}]
>>> [p.name for p in write_summary(d, rows)]
['summary.md', 'summary.html']
"""

from __future__ import annotations

import functools
import html
import json
import math
import os
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from importlib import resources
from pathlib import Path
from typing import Any
from urllib.parse import quote, urlsplit

import numpy as np

from ..output import ResultFolder, ensure_folder, refuse_existing
from .rows import one_line, shown_name

__all__ = ["write_summary", "md_text", "STATUSES", "SUMMARY_FILES"]

#: the pages :func:`write_summary` writes
SUMMARY_FILES = ("summary.md", "summary.html")

#: the statuses of a row, in the order the counts list them
STATUSES = ("ok", "not converged", "at-search-limit", "gains-energy", "failed",
            "skipped (resume)")
#: the statuses of rows with a fit (their parameters are plotted)
_FITTED = ("ok", "not converged", "at-search-limit", "gains-energy")

#: table columns before the parameters: (key, label, type)
_FIXED = (("file", "file", "text"), ("channel", "channel", "text"), ("model", "model", "text"),
          ("status", "status", "text"), ("n_points", "points", "num"),
          ("n_excluded", "excluded", "num"), ("sigma", "sigma", "num"),
          ("rms_log", "rms log", "num"), ("aic", "AIC", "num"), ("bic", "BIC", "num"),
          ("search_limits", "search limit", "text"), ("max_albedo", "max albedo", "num"),
          ("peak_ratio", "peak ratio", "num"), ("elapsed_s", "time s", "num"))
#: failures listed by name (the rest are counted; the HTML table's filter finds them)
_MAX_FAILURES = 100
#: columns stored once per distinct value (index into a list) in the page's JSON
_CATEGORICAL = ("file", "channel", "model", "status")


# --------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------

def _num(value: Any) -> float | int | None:
    """A finite number (6 significant digits for floats), or None."""
    if value is None or isinstance(value, bool):
        return None
    try:
        x = float(value)
    except (TypeError, ValueError):
        return None
    if not math.isfinite(x):
        return None
    if isinstance(value, int | np.integer):
        return int(value)
    return float(f"{x:.6g}")


def _href(path: Any) -> str | None:
    """A relative path as a URL (percent-encoded); None for absolute paths or other schemes."""
    if not path:
        return None
    text = str(path).replace(os.sep, "/")
    if urlsplit(text).scheme or text.startswith("/"):
        return None
    return quote(text, safe="/")


#: the ASCII punctuation a Markdown renderer acts on (CommonMark, and GitHub's tables, ``~``
#: strikethrough): inline (emphasis, code, links, images, escapes, table cells) or at the
#: start of a line (headings, lists, block quotes, thematic breaks). ``<``, ``>`` and ``&``
#: (raw HTML, autolinks, entities) are written as HTML entities instead
_MD_ACTIVE = "\\`*_{}[]()#+-.!|~"
_MD_ESCAPES = str.maketrans({c: "\\" + c for c in _MD_ACTIVE})


def md_text(value: Any) -> str:
    r"""``value`` as literal Markdown text on one line: a renderer shows it as it is and makes
    no link, image, emphasis, code, HTML, heading, list or table cell of it.

    The one escaping of the summary's Markdown (file names, channels, errors, the title):
    line breaks and control characters made one line (:func:`~roughbrdf.catalogue.rows.one_line`),
    ``<``, ``>``, ``&`` as entities, every other active punctuation character
    (:data:`_MD_ACTIVE`) backslash-escaped (CommonMark lets any ASCII punctuation be escaped).

    Examples
    --------
    >>> print(md_text("[x](javascript:alert(9)).astm"))
    \[x\]\(javascript:alert\(9\)\)\.astm
    >>> print(md_text("<b>*a*_b_</b>"))
    &lt;b&gt;\*a\*\_b\_&lt;/b&gt;
    """
    text = one_line("" if value is None else value)
    # the entities first: their own "&" and ";" are not among the characters escaped next
    return html.escape(text, quote=False).translate(_MD_ESCAPES)


def _md_name(value: Any) -> str:
    """A file name for the Markdown page: quoted when it holds control characters
    (:func:`~roughbrdf.catalogue.rows.shown_name`), then :func:`md_text`."""
    return md_text(None if value is None else shown_name(value))


def _fmt(value: Any) -> str:
    x = _num(value)
    if x is None:
        return ""
    return str(x) if isinstance(x, int) else f"{x:.4g}"


def _param_names(rows: Sequence[Mapping[str, Any]]) -> list[str]:
    """Every parameter name, in the order first seen."""
    names: dict[str, None] = {}
    for row in rows:
        for name in row.get("params") or {}:
            names.setdefault(str(name), None)
    return list(names)


def _sample(n: int, k: int) -> list[int]:
    """``min(n, k)`` indices spread evenly over ``range(n)`` (first and last included)."""
    if k <= 0 or n <= 0:
        return []
    if n <= k:
        return list(range(n))
    return sorted({int(round(i)) for i in np.linspace(0, n - 1, k)})


# --------------------------------------------------------------------------------------------
# the data embedded in the page
# --------------------------------------------------------------------------------------------

def _columns(params: list[str]) -> list[dict[str, str]]:
    cols = [{"key": k, "label": lab, "type": t} for k, lab, t in _FIXED]
    cols += [{"key": "p:" + p, "label": p, "type": "num"} for p in params]
    cols.append({"key": "error", "label": "error", "type": "text"})
    return cols


def _table_data(rows: Sequence[Mapping[str, Any]], params: list[str]) -> dict[str, Any]:
    """The rows column-wise: categorical columns as indices into ``dicts``."""
    cols = _columns(params)
    dicts: dict[str, dict[str, int]] = {k: {} for k in _CATEGORICAL}
    data: list[list[Any]] = [[] for _ in cols]
    links: list[str | None] = []
    for row in rows:
        values = row.get("params") or {}
        for j, col in enumerate(cols):
            key = col["key"]
            if key in dicts:
                text = "" if row.get(key) is None else str(row.get(key))
                data[j].append(dicts[key].setdefault(text, len(dicts[key])))
            elif key.startswith("p:"):
                data[j].append(_num(values.get(key[2:])))
            elif col["type"] == "num":
                data[j].append(_num(row.get(key)))
            else:
                data[j].append(None if row.get(key) is None else str(row.get(key)))
        links.append(_href(row.get("fit_dir")))
    return {"columns": cols, "data": data, "links": links,
            "dicts": {k: list(v) for k, v in dicts.items()}}


def _json_for_script(obj: Any) -> str:
    """JSON safe inside ``<script type="application/json">`` (no ``<``, ``>`` or ``&``)."""
    text = json.dumps(obj, separators=(",", ":"), ensure_ascii=False, allow_nan=False)
    return (text.replace("&", "\\u0026").replace("<", "\\u003c").replace(">", "\\u003e")
            .replace("\u2028", "\\u2028").replace("\u2029", "\\u2029"))


# --------------------------------------------------------------------------------------------
# plots and thumbnails (static HTML, drawn here)
# --------------------------------------------------------------------------------------------

def _histogram_svg(name: str, values: np.ndarray, bins: int = 30) -> str:
    """An inline SVG histogram of ``values`` (log10 axis when they span over two decades)."""
    w, h, pad = 260, 150, 24
    log = bool(np.all(values > 0) and values.max() / values.min() > 100)
    x = np.log10(values) if log else values
    lo, hi = float(x.min()), float(x.max())
    if hi <= lo:
        lo, hi = lo - 0.5, hi + 0.5
    counts, edges = np.histogram(x, bins=bins, range=(lo, hi))
    top = max(int(counts.max()), 1)
    bar_w = (w - 2 * pad) / bins
    bars = "".join(
        f'<rect x="{pad + i * bar_w:.1f}" y="{h - pad - c / top * (h - 2 * pad):.1f}" '
        f'width="{max(bar_w - 1, 0.5):.1f}" height="{c / top * (h - 2 * pad):.1f}">'
        f'<title>{edges[i]:.4g} to {edges[i + 1]:.4g}: {c}</title></rect>'
        for i, c in enumerate(counts) if c)
    label = html.escape(("log10 " if log else "") + name)
    return (f'<figure class="plot"><svg viewBox="0 0 {w} {h}" width="{w}" height="{h}" '
            f'role="img" aria-label="histogram of {label}">{bars}'
            f'<line x1="{pad}" y1="{h - pad}" x2="{w - pad}" y2="{h - pad}" class="axis"/>'
            f'<text x="{pad}" y="{h - 8}">{lo:.3g}</text>'
            f'<text x="{w - pad}" y="{h - 8}" text-anchor="end">{hi:.3g}</text>'
            f'<text x="{pad}" y="14">max {top}</text></svg>'
            f'<figcaption>{label} (n = {values.size})</figcaption></figure>')


def _plots_html(rows: Sequence[Mapping[str, Any]], params: list[str]) -> str:
    """Histograms of every parameter and of ``rms_log`` over the fitted (ok) rows."""
    fitted = [r for r in rows if r.get("status") in _FITTED]
    series: list[tuple[str, list[Any]]] = [
        (p, [(r.get("params") or {}).get(p) for r in fitted]) for p in params]
    series.append(("rms_log", [r.get("rms_log") for r in fitted]))
    parts = []
    for name, raw in series:
        vals = np.array([v for v in map(_num, raw) if v is not None], dtype=float)
        if vals.size:
            parts.append(_histogram_svg(name, vals))
    if not parts:
        return "<p>No fitted parameters to plot.</p>"
    return '<div class="plots">' + "".join(parts) + "</div>"


def _thumbnails_html(rows: Sequence[Mapping[str, Any]], max_thumbnails: int) -> str:
    """The contact sheet: evenly sampled fit figures, each linking to its fit folder."""
    with_fig = [r for r in rows if _href(r.get("figure"))]
    chosen = [with_fig[i] for i in _sample(len(with_fig), max_thumbnails)]
    if not chosen:
        return "<p>No fit figures.</p>"
    cards = []
    for r in chosen:
        src = html.escape(_href(r.get("figure")) or "")
        link = html.escape(_href(r.get("fit_dir")) or src)
        caption = html.escape(f"{r.get('file', '')} · {r.get('channel', '')}")
        cards.append(f'<a class="thumb" href="{link}"><img src="{src}" alt="{caption}" '
                     f'width="240"><span>{caption}</span></a>')
    note = (f"<p>{len(chosen)} of {len(with_fig)} figures, evenly sampled.</p>"
            if len(chosen) < len(with_fig) else "")
    return note + '<div class="sheet">' + "".join(cards) + "</div>"


# --------------------------------------------------------------------------------------------
# the page
# --------------------------------------------------------------------------------------------

#: the page's style sheet and script, package data beside this module (``assets/``), inlined
#: into every page
ASSETS = ("summary.css", "summary.js")


@functools.cache
def _asset(name: str) -> str:
    """The text of ``assets/<name>`` (one of :data:`ASSETS`), read once per process."""
    path = resources.files("roughbrdf.catalogue").joinpath("assets", name)
    return path.read_text(encoding="utf-8")


def _counts(rows: Sequence[Mapping[str, Any]]) -> list[tuple[str, int]]:
    """(status, count) for the known statuses, then any other status seen."""
    counts = Counter(str(r.get("status")) for r in rows)
    order = [s for s in STATUSES] + sorted(s for s in counts if s not in STATUSES)
    return [(s, counts[s]) for s in order if counts[s] or s in STATUSES]


def _failures(rows: Sequence[Mapping[str, Any]]) -> list[Mapping[str, Any]]:
    return [r for r in rows if r.get("status") == "failed" or r.get("error")]


def _html_page(rows: Sequence[Mapping[str, Any]], title: str, page_size: int,
               max_thumbnails: int) -> str:
    """The whole ``summary.html``."""
    params = _param_names(rows)
    data = _table_data(rows, params)
    data["pageSize"] = max(1, int(page_size))
    counts = "".join(f"<tr><td>{html.escape(s)}</td><td>{c}</td></tr>" for s, c in _counts(rows))
    fails = _failures(rows)
    fail_items = "".join(
        f"<li><b>{html.escape(shown_name(r.get('file')))}</b> · "
        f"{html.escape(str(r.get('channel')))}: "
        f"{html.escape(str(r.get('error') or r.get('status')))}</li>"
        for r in fails[:_MAX_FAILURES])
    more = (f"<li>… and {len(fails) - _MAX_FAILURES} more (filter the table)</li>"
            if len(fails) > _MAX_FAILURES else "")
    fail_html = f"<ul>{fail_items}{more}</ul>" if fails else "<p>None.</p>"
    t = html.escape(title)
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<link rel="icon" href="data:,"><title>{t}</title><style>\n{_asset("summary.css")}</style></head>
<body><h1>{t}</h1>
<p>{len(rows)} fits (file × channel); {len(params)} fitted parameters.</p>
<table class="counts"><tbody>{counts}</tbody></table>
<h2>Failures</h2>{fail_html}
<h2>Fits</h2>
<div id="controls"><input id="rb-filter" type="search" placeholder="filter rows…"
 aria-label="filter rows"><button id="rb-prev" type="button">◀ previous</button>
<button id="rb-next" type="button">next ▶</button><span id="rb-info"></span></div>
<table id="rb-table"><thead><tr></tr></thead><tbody></tbody></table>
<h2>Parameters across the catalogue</h2>{_plots_html(rows, params)}
<h2>Contact sheet</h2>{_thumbnails_html(rows, max_thumbnails)}
<script type="application/json" id="rb-data">{_json_for_script(data)}</script>
<script>\n{_asset("summary.js")}</script>
</body></html>
"""


def _markdown(rows: Sequence[Mapping[str, Any]], title: str, page_size: int) -> str:
    """The whole ``summary.md``."""
    params = _param_names(rows)
    lines = [f"# {md_text(title)}", "",
             f"{len(rows)} fits (file × channel). Sortable, filterable table, parameter plots and "
             "contact sheet: [summary.html](summary.html).", "",
             "| status | fits |", "|---|---:|"]
    lines += [f"| {md_text(s)} | {c} |" for s, c in _counts(rows)]
    lines += ["", "## Failures", ""]
    fails = _failures(rows)
    lines += [f"- **{_md_name(r.get('file'))}** · {md_text(r.get('channel'))}: "
              f"{md_text(r.get('error') or r.get('status'))}"
              for r in fails[:_MAX_FAILURES]] or ["None."]
    if len(fails) > _MAX_FAILURES:
        lines.append(f"- … and {len(fails) - _MAX_FAILURES} more (filter the HTML table)")
    shown = rows[:max(1, int(page_size))]
    lines += ["", f"## Fits (first {len(shown)} of {len(rows)})", ""]
    head = ["file", "channel", "model", "status", "rms log", "BIC", "max albedo", *params]
    lines += ["| " + " | ".join(md_text(h) for h in head) + " |",
              "|" + "---|" * 4 + "---:|" * (len(head) - 4)]
    for r in shown:
        name, link = _md_name(r.get("file")), _href(r.get("fit_dir"))
        cells = [f"[{name}]({link})" if link else name, md_text(r.get("channel")),
                 md_text(r.get("model")), md_text(r.get("status")), _fmt(r.get("rms_log")),
                 _fmt(r.get("bic")), _fmt(r.get("max_albedo")),
                 *(_fmt((r.get("params") or {}).get(p)) for p in params)]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def write_summary(out_dir: str | os.PathLike, rows: Iterable[Mapping[str, Any]], *,
                  title: str | None = None, page_size: int = 100, max_thumbnails: int = 60,
                  overwrite: bool = False, into: ResultFolder | None = None) -> list[Path]:
    """Write ``summary.md`` and ``summary.html`` of a catalogue fit into ``out_dir``.

    Parameters
    ----------
    out_dir : str or path-like
        The catalogue folder (``fit_dir`` and ``figure`` of the rows are relative to it).
    rows : iterable of mapping
        One per file x channel, with the keys listed in the module docstring.
    title : str, optional
        The page's title (default: "Catalogue summary: <folder name>").
    page_size : int
        Rows per page of the HTML table, and rows in the Markdown table.
    max_thumbnails : int
        At most this many fit figures, evenly sampled, in the contact sheet.
    overwrite : bool
        Replace existing summary files (default: refuse with
        :class:`roughbrdf.output.OverwriteRefused` before writing anything).
    into : roughbrdf.output.ResultFolder, optional
        An open set on ``out_dir`` (the catalogue's, holding ``catalogue.csv`` and
        ``catalogue.json``): the two pages are staged into it and committed with it, so the
        catalogue files and their summary are one set. Without it the pages are written as a
        set of their own, added to the folder's (``extend=True``): both old or both new.

    Returns
    -------
    list of pathlib.Path
        ``[summary.md, summary.html]``.
    """
    folder = ensure_folder(out_dir)
    md_path, html_path = folder / SUMMARY_FILES[0], folder / SUMMARY_FILES[1]
    if into is not None and Path(into.path).resolve() != folder.resolve():
        raise ValueError(f"into is a set on {into.path}, not on out_dir {folder}")
    refuse_existing(md_path, overwrite)
    refuse_existing(html_path, overwrite)
    rows = list(rows)
    title = title or f"Catalogue summary: {folder.resolve().name}"
    page = _html_page(rows, title, page_size, max_thumbnails)
    pages = {md_path.name: _markdown(rows, title, page_size), html_path.name: page}
    if into is not None:
        for name, text in pages.items():
            into.add(name, text)
        return [md_path, html_path]
    # earlier versions wrote the pages outside any set: with overwrite they are replaced
    with ResultFolder(folder, overwrite=overwrite, extend=True, adopt=SUMMARY_FILES) as out:
        out.check(pages)
        for name, text in pages.items():
            out.add(name, text)
    return [md_path, html_path]
