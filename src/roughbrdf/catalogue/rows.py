"""The rows of a catalogue and the files ``catalogue.csv`` / ``catalogue.json``.

Row schema (one ``dict`` per input file x channel; :func:`roughbrdf.catalogue.summary` and
other tools rely on these keys):

================  ============================================================================
``file``          the input path as given (str)
``channel``       channel label (str), or None when the file failed before its channels were
                  known
``model``         the fitted model's label (str)
``status``        ``"ok"`` | ``"not converged"`` | ``"failed"`` | ``"skipped (resume)"``
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
================  ============================================================================

A ``"skipped (resume)"`` row carries the values of the earlier run it kept.
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
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..fitting.result import FitResult

__all__ = ["COLUMNS", "STATUSES", "failed_row", "fit_rows", "csv_text", "json_text"]

#: the statuses a row can have
STATUSES = ("ok", "not converged", "failed", "skipped (resume)")

#: the scalar columns, in the order of ``catalogue.csv`` (``param_*``/``stderr_*`` follow)
COLUMNS = ("file", "channel", "model", "status", "error", "sigma", "rms_log", "aic", "bic",
           "n_points", "n_excluded", "elapsed_s", "sha256", "fit_dir", "figure")


def _empty(file: str, model: str, sha256: str | None) -> dict[str, Any]:
    row: dict[str, Any] = dict.fromkeys(COLUMNS)
    row.update(file=file, model=model, sha256=sha256, params={}, stderr={})
    return row


def failed_row(file: str, model: str, error: str, *, sha256: str | None,
               elapsed_s: float | None = None, channel: str | None = None) -> dict[str, Any]:
    """The row of a file (or channel) that failed with ``error``."""
    row = _empty(file, model, sha256)
    row.update(status="failed", error=error, elapsed_s=elapsed_s, channel=channel)
    return row


def fit_rows(res: FitResult, file: str, *, fit_dir: str, figures: Sequence[str | None],
             elapsed_s: float) -> list[dict[str, Any]]:
    """One row per channel of ``res`` (``figures[i]``: the channel's PNG, relative, or None)."""
    from ..jsonsafe import clean_json

    src = res.source or {}
    rows = []
    for c, fig in zip(res.channels, figures, strict=True):
        row = _empty(file, res.model_name, src.get("file_sha256"))
        row.update(
            channel=c.channel, status="ok" if c.success else "not converged",
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
    return [*COLUMNS, *(f"param_{n}" for n in names), *(f"stderr_{n}" for n in names)]


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
        w.writerow({k: ("" if v is None else v) for k, v in flat.items()})
    return buf.getvalue()


def json_text(rows: Sequence[dict[str, Any]], **extra: Any) -> str:
    """``catalogue.json``: ``{"rows": rows, **extra}`` (strict JSON, NaN as null)."""
    from ..jsonsafe import clean_json

    return json.dumps(clean_json({**extra, "rows": list(rows)}), indent=1,
                      allow_nan=False) + "\n"
