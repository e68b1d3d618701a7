r"""The rows of a catalogue and the files ``catalogue.csv`` / ``catalogue.json``.

Row schema (one ``dict`` per input file x channel; :func:`roughbrdf.catalogue.summary` and
other tools rely on these keys):

================  ============================================================================
``file``          the input path as given (str)
``channel``       channel label (str), or None when the file failed before its channels were
                  known
``model``         the fitted model's label (str)
``status``        ``"ok"`` | ``"not converged"`` | ``"at-search-limit"`` (a parameter ended on
                  a bound of the search that is no physical limit: not a result) |
                  ``"gains-energy"`` (the fitted model's albedo exceeds 1 at some incidence)
                  | ``"failed"`` | ``"skipped (resume)"`` (first that applies, in this order)
``error``         the error message (str) for ``"failed"``, else None
``params``        ``{name: value}`` of every parameter (empty when failed)
``stderr``        ``{name: standard error or None}``
``sigma``         TR75 sigma (r.m.s. relative residual), float or None
``rms_log``       r.m.s. of the log residuals, float or None
``aic``, ``bic``  float or None
``n_points``      samples fitted (int or None)
``n_excluded``    samples left out, all reasons together (int or None)
``elapsed_s``     seconds of the file's task (read, fit, save) on its worker
``sha256``        SHA-256 of the input file's bytes (None when it could not be read)
``fit_dir``       the file's fit folder, relative to the catalogue folder (str or None)
``figure``        the channel's ``fit_<channel>.png`` relative to the catalogue folder, or None
``limits``        ``{name: "physical-lower" | "search-upper" ...}`` of the parameters at a bound
                  (``catalogue.csv``: ``name=kind`` separated by ``;``)
``search_limits`` the parameters on a search limit, ``", "``-separated (str or None)
``max_albedo``    the largest albedo of the fitted model at 0, 10, ... 80, 85 deg (float or None)
``gains_energy``  whether ``max_albedo`` exceeds ``1 + 1e-3`` (bool or None)
``peak_ratio``    model/data peak ratio farthest from 1 over the measured incidences (float
                  or None)
``albedo``        ``{theta_i_deg: albedo}`` (``catalogue.csv``: ``albedo_<deg>`` columns)
``peak_ratios``   ``{theta_i_deg: ratio}`` per measured incidence (``peak_ratio_<deg>``)
``earlier_status`` for a ``"skipped (resume)"`` row: the status it had when it was fitted
                  (:func:`outcome`), else None
================  ============================================================================

A ``"skipped (resume)"`` row carries the values of the earlier run it kept, and its ``file``
names the input where it is now (the same bytes may have moved since).
``catalogue.csv`` flattens ``params`` and ``stderr`` into ``param_<name>`` and
``stderr_<name>`` columns (the union over all rows, in order of appearance); ``catalogue.json``
is ``{"rows": [...]}`` with the rows as they are (NaN written as null).

Examples
--------
>>> row = failed_row("a.csv", "trowbridge-reitz-1975", "bad header", sha256=None)
>>> row["status"], row["channel"], row["params"]
('failed', None, {})
>>> csv_text([row]).splitlines()[0].split(",")[:4]
['file', 'channel', 'model', 'status']
>>> shown_name("plain name.astm"), shown_name("two\nlines.astm")
('plain name.astm', "'two\\nlines.astm'")
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..fitting.results.result import FitResult

__all__ = ["BY_INCIDENCE", "COLUMNS", "STATUSES", "SKIPPED", "failed_row", "fit_rows",
           "csv_text", "json_text", "status_of", "outcome", "shown_name", "one_line"]

#: the statuses a row can have
STATUSES = ("ok", "not converged", "at-search-limit", "gains-energy", "failed",
            "skipped (resume)")
#: the status of a row kept from an earlier run by ``--resume``
SKIPPED = "skipped (resume)"

#: the scalar columns, in the order of ``catalogue.csv`` (``param_*``/``stderr_*``, then
#: ``albedo_*``/``peak_ratio_*`` follow)
COLUMNS = ("file", "channel", "model", "status", "error", "sigma", "rms_log", "aic", "bic",
           "n_points", "n_excluded", "elapsed_s", "sha256", "fit_dir", "figure", "limits",
           "search_limits", "max_albedo", "gains_energy", "peak_ratio", "earlier_status")
#: the per-incidence columns of ``catalogue.csv``: row key -> column prefix
BY_INCIDENCE = {"albedo": "albedo_", "peak_ratios": "peak_ratio_"}


def _empty(file: str, model: str, sha256: str | None) -> dict[str, Any]:
    row: dict[str, Any] = dict.fromkeys(COLUMNS)
    row.update(file=file, model=model, sha256=sha256, params={}, stderr={}, limits={},
               albedo={}, peak_ratios={})
    return row


def status_of(res: FitResult, i: int) -> str:
    """The status of channel ``i`` of ``res``: ``"not converged"``, ``"at-search-limit"``,
    ``"gains-energy"`` or ``"ok"``, the first that applies."""
    c = res.channels[i]
    if not c.success:
        return "not converged"
    if any(k.startswith("search") for k in c.limits.values()):
        return "at-search-limit"
    return "gains-energy" if res.plausibility(i).gains_energy else "ok"


def _plausibility_fields(res: FitResult, i: int) -> dict[str, Any]:
    """The row's limits and plausibility keys for channel ``i`` of ``res``."""
    c, p = res.channels[i], res.plausibility(i)
    search = [nm for nm, k in c.limits.items() if k.startswith("search")]
    finite = [r for r in p.peak_ratio if math.isfinite(r) and r > 0]
    return dict(limits=dict(c.limits), search_limits=", ".join(search) or None,
                max_albedo=p.max_albedo, gains_energy=p.gains_energy,
                peak_ratio=max(finite, key=lambda r: abs(math.log(r))) if finite else None,
                albedo={f"{t:g}": a for t, a in zip(p.albedo_theta_deg, p.albedo, strict=True)},
                peak_ratios={f"{t:g}": r for t, r in zip(p.peak_theta_deg, p.peak_ratio,
                                                         strict=True)})


def failed_row(file: str, model: str, error: str, *, sha256: str | None,
               elapsed_s: float | None = None, channel: str | None = None) -> dict[str, Any]:
    """The row of a file (or channel) that failed with ``error`` (made one line:
    :func:`one_line`, so that ``failed: FILE: error`` is one line whatever the error says)."""
    row = _empty(file, model, sha256)
    row.update(status="failed", error=one_line(error), elapsed_s=elapsed_s, channel=channel)
    return row


def outcome(row: dict[str, Any]) -> str | None:
    """The status ``row`` counts as for the exit status: its own, or for a row kept by
    ``--resume`` (:data:`SKIPPED`) the status it had when it was fitted (None: not recorded,
    a row of an older catalogue)."""
    if row.get("status") == SKIPPED:
        return row.get("earlier_status")
    return row.get("status")


def shown_name(name: Any) -> str:
    r"""A file name as one-line messages show it: as it is, or quoted like a Python string
    literal (``'a\nb.csv'``) when it holds a character that is not printable (a newline, a
    tab, an escape ...), so that the message stays one line and the name can be told exactly.

    Examples
    --------
    >>> print(shown_name("a\tb.csv"), shown_name("\x1b[31mred.csv"))
    'a\tb.csv' '\x1b[31mred.csv'
    """
    text = str(name)
    # str.isprintable is False for every control, format and line/paragraph separator
    # character (and for spaces other than " "): all of them are shown escaped
    return text if text.isprintable() else repr(text)


def one_line(text: Any, names: Sequence[Any] = ()) -> str:
    r"""``text`` as one line: each of ``names`` (file names it may contain) shown by
    :func:`shown_name`, runs of white space made one space, any other control character
    escaped (``\x1b``).

    Examples
    --------
    >>> one_line("cannot read /d/a\nb.csv:\n  line 3", names=["/d/a\nb.csv"])
    "cannot read '/d/a\\nb.csv': line 3"
    """
    out = str(text)
    for name in sorted({str(n) for n in names if n}, key=len, reverse=True):
        out = out.replace(name, shown_name(name))  # longest first: a path before its tail
    out = " ".join(out.split())
    if out.isprintable():  # the common case: nothing left to escape
        return out
    return "".join(ch if ch.isprintable() else repr(ch)[1:-1] for ch in out)


def fit_rows(res: FitResult, file: str, *, fit_dir: str, figures: Sequence[str | None],
             elapsed_s: float) -> list[dict[str, Any]]:
    """One row per channel of ``res`` (``figures[i]``: the channel's PNG, relative, or None)."""
    from ..jsonsafe import clean_json

    src = res.source or {}
    rows = []
    for i, (c, fig) in enumerate(zip(res.channels, figures, strict=True)):
        row = _empty(file, res.model_name, src.get("file_sha256"))
        row.update(_plausibility_fields(res, i))
        row.update(
            channel=c.channel, status=status_of(res, i),
            params=dict(c.params), stderr=dict(c.stderr), sigma=c.sigma, rms_log=c.rms_log,
            aic=c.aic, bic=c.bic, n_points=c.n_points,
            n_excluded=int(sum(c.excluded.values())), elapsed_s=elapsed_s, fit_dir=fit_dir,
            figure=fig)
        rows.append(clean_json(row))
    return rows


def _columns(rows: Sequence[dict[str, Any]]) -> list[str]:
    params: dict[str, None] = {}
    for r in rows:
        params.update(dict.fromkeys(r.get("params") or {}))
    names = list(params)
    per: dict[str, dict[str, None]] = {key: {} for key in BY_INCIDENCE}
    for r in rows:
        for key in BY_INCIDENCE:
            per[key].update(dict.fromkeys(r.get(key) or {}))
    return [*COLUMNS, *(f"param_{n}" for n in names), *(f"stderr_{n}" for n in names),
            *(f"{pre}{t}" for key, pre in BY_INCIDENCE.items() for t in per[key])]


def csv_text(rows: Sequence[dict[str, Any]]) -> str:
    """``catalogue.csv``: the scalar columns, then ``param_<name>``, ``stderr_<name>``."""
    cols = _columns(rows)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=cols, lineterminator="\n")
    w.writeheader()
    for r in rows:
        flat = {k: r.get(k) for k in COLUMNS}
        flat.update({f"param_{k}": v for k, v in (r.get("params") or {}).items()})
        flat.update({f"stderr_{k}": v for k, v in (r.get("stderr") or {}).items()})
        # a row of an older catalogue (resume) may lack these: empty cells
        flat["limits"] = ";".join(f"{k}={v}" for k, v in (r.get("limits") or {}).items())
        for key, pre in BY_INCIDENCE.items():
            flat.update({f"{pre}{t}": v for t, v in (r.get(key) or {}).items()})
        w.writerow({k: ("" if v is None else v) for k, v in flat.items()})
    return buf.getvalue()


def json_text(rows: Sequence[dict[str, Any]], **extra: Any) -> str:
    """``catalogue.json``: ``{"rows": rows, **extra}`` (strict JSON, NaN as null)."""
    from ..jsonsafe import clean_json

    return json.dumps(clean_json({**extra, "rows": list(rows)}), indent=1,
                      allow_nan=False) + "\n"
